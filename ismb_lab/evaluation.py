"""Scoring matches against target pairs: C/E/T as in the thesis' Fig. 5.10.

* **C**: matched pairs identical to a target;
* **E**: matched pairs that are not targets, split into *wrong partner* (the
  left feature has a target, but with another right feature) and *extra* (the
  left feature has no target at all);
* **T**: the number of targets.

The thesis prints ``C/E/T``; with E split it reads ``14/2+0/16`` (C / wrong +
extra / T).  Matches of left features whose truth is unknown (no ground truth
there) are not counted either way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Score:
    """C/E/T counts of one or more pairs (scores add with ``+``).

    Examples
    --------
    >>> s = Score(correct=14, wrong_partner=2, extra=0, targets=16)
    >>> str(s), round(s.precision, 3), s.recall
    ('14/2+0/16', 0.875, 0.875)
    >>> str(s + Score(16, 0, 1, 16))
    '30/2+1/32'
    """

    correct: int
    wrong_partner: int
    extra: int
    targets: int

    @property
    def errors(self) -> int:
        return self.wrong_partner + self.extra

    @property
    def recall(self) -> float:
        """C / T (the thesis' "accurate rate")."""
        return self.correct / self.targets if self.targets else float("nan")

    @property
    def precision(self) -> float:
        """C / (C + E)."""
        matched = self.correct + self.errors
        return self.correct / matched if matched else float("nan")

    @property
    def fitness(self) -> int:
        """The GA's fitness (4-1): n_c - n_e."""
        return self.correct - self.errors

    def __add__(self, other: "Score") -> "Score":
        return Score(self.correct + other.correct, self.wrong_partner + other.wrong_partner,
                     self.extra + other.extra, self.targets + other.targets)

    def __str__(self) -> str:
        return f"{self.correct}/{self.wrong_partner}+{self.extra}/{self.targets}"


def score(pairs, targets, unknown=()) -> Score:
    """Compare matched feature pairs with target feature pairs.

    Parameters
    ----------
    pairs : (m, 2) int array_like
        Matched ``(i, k)`` feature indices.
    targets : (t, 2) int array_like
        Target ``(i, k)`` feature indices (snapped from coordinates).
    unknown : int array_like
        Left features whose truth is unknown; their matches are not counted.

    Returns
    -------
    score : Score

    Examples
    --------
    >>> str(score([[0, 0], [1, 2], [3, 3], [4, 4]], [[0, 0], [1, 1], [2, 2]], unknown=[4]))
    '1/1+1/3'
    """
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    targets = np.asarray(targets, dtype=np.int64).reshape(-1, 2)
    wanted = {tuple(t) for t in targets.tolist()}
    has_target = set(targets[:, 0].tolist())
    skip = set(np.asarray(unknown, dtype=np.int64).ravel().tolist())
    correct = wrong = extra = 0
    for i, k in pairs.tolist():
        if (i, k) in wanted:
            correct += 1
        elif i in has_target:
            wrong += 1
        elif i not in skip:
            extra += 1
    return Score(correct, wrong, extra, len(wanted))


# --- The train/test protocol of Fig. 5.10 -------------------------------------------------

@dataclass(frozen=True)
class Spread:
    """A figure measured over several update-order seeds."""

    mean: float
    std: float
    low: float
    high: float
    n: int

    @classmethod
    def of(cls, values) -> "Spread":
        v = np.asarray(values, dtype=float)
        return cls(float(v.mean()), float(v.std()), float(v.min()), float(v.max()), len(v))

    def __str__(self) -> str:
        if self.n == 1 or self.high == self.low:
            return f"{100 * self.mean:.1f}%"
        return f"{100 * self.mean:.1f}% ({100 * self.low:.1f}-{100 * self.high:.1f})"


def load_manifest(path, config=None) -> list:
    """Read an evaluation manifest into :class:`~ismb_lab.tuning.Case` objects.

    The manifest is JSON: ``{"pairs": [entry, ...]}``.  An entry is either a file pair,
    ``{"name", "left", "right", "targets", "roi", "shift"}`` (paths relative to the
    manifest; ``roi`` and ``shift`` optional), or a built-in ground-truth pair,
    ``{"name", "source": "middlebury-motorcycle", "roi": [x, y, w, h]}``, whose targets
    come from the ground-truth disparity (:func:`ismb_lab.datasets.ground_truth_pairs`).
    """
    import json
    from dataclasses import replace
    from pathlib import Path

    from ._validation import ParameterError, message
    from .datasets import ground_truth_pairs, motorcycle
    from .matching import MatchConfig, prepare
    from .targets import load_targets, snap
    from .tuning import Case

    path = Path(path)
    owner = f"the manifest '{path}'"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ParameterError(message("path", "load_manifest", "an existing file", str(path))) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ParameterError(message("path", "load_manifest", f"a JSON manifest ({exc})", str(path))) from None
    except RecursionError:
        raise ParameterError(message("path", "load_manifest", "a JSON manifest (not nested too deeply)", str(path))) from None
    entries = data.get("pairs") if isinstance(data, dict) else None
    if not isinstance(entries, list) or not entries:
        raise ParameterError(message("pairs", owner, "a non-empty list of pair entries", entries))
    base = config or MatchConfig()
    cases, moto = [], None
    for n, entry in enumerate(entries):
        if not isinstance(entry, dict):
            raise ParameterError(message(f"pairs[{n}]", owner, "an object", entry))
        settings = {k: entry[k] for k in ("roi", "shift") if k in entry}
        cfg = replace(base, **settings)
        name = str(entry.get("name", f"pair {n}"))
        if entry.get("source") == "middlebury-motorcycle":
            moto = moto or motorcycle()
            prepared = prepare(moto.left, moto.right, cfg)
            targets, unknown = ground_truth_pairs(moto.disparity, prepared.problem.left_xy,
                                                  prepared.problem.right_xy)
        else:
            files = {}
            for key in ("left", "right", "targets"):
                if not isinstance(entry.get(key), str):
                    raise ParameterError(message(f"pairs[{n}].{key}", owner, "a file path (a string)", entry.get(key)))
                files[key] = path.parent / entry[key]
                if not files[key].is_file():
                    raise ParameterError(message(f"pairs[{n}].{key}", owner, "an existing file",
                                                 str(files[key])))
            prepared = prepare(files["left"], files["right"], cfg)
            target_set = load_targets(files["targets"], pair=prepared.pair)
            snapped = snap(target_set, prepared.problem.left_xy, prepared.problem.right_xy)
            targets, unknown = snapped.pairs, np.zeros(0, dtype=np.int64)
        cases.append(Case(prepared, targets, unknown, name))
    return cases


def protocol(cases, method="III", *, train: int = 0, seeds: int = 5, generations: int = 500,
             rng=0, peers: bool = False, progress=None, solvers=(), fit_solver: str = "network",
             fit_seeds: int = 1, fit_all: bool = True) -> dict:
    """Fig. 5.10's protocol: GA-fit on each pair ("training") and on one pair applied to all
    the others ("testing"), every network figure over `seeds` update-order seeds.

    With `peers`, the peer matchers of :mod:`ismb_lab.peers` (deterministic) are scored
    on the same pairs, with the tested parameters where they use S and C.

    `solvers` adds rows that solve the same energies, with the same tested parameters,
    another way: ``"anneal"`` (mean-field annealing, over the same seeds) and ``"exact"``
    (the MILP global minimum, seed-independent: one value).  `fit_solver` and `fit_seeds`
    choose how the GA scores a chromosome (:class:`~ismb_lab.tuning.Fitness`).  Without
    `fit_all` only the training pair is fitted: the other rows' ``"training"`` and
    ``"params"`` are None (the held-out figures do not use them).

    Returns a dict with the tested parameters, per-pair :class:`Score` lists and pooled
    scores; ``report["solvers"][name]`` has ``"rows"`` (per pair, per seed) and ``"held_out"``.
    """
    from ._validation import ParameterError, check_choice, check_number, message
    from .tuning import SOLVERS

    if not cases:
        raise ParameterError(message("cases", "protocol", "at least one pair", cases))
    train = check_number(train, "train", "protocol", low=0, high=len(cases) - 1, integer=True)
    seeds = check_number(seeds, "seeds", "protocol", low=1, integer=True)
    fit_solver = check_choice(fit_solver, "fit_solver", "protocol", SOLVERS)
    fit_seeds = check_number(fit_seeds, "fit_seeds", "protocol", low=1, integer=True)
    solvers = (solvers,) if isinstance(solvers, str) else tuple(solvers)
    for name in solvers:
        check_choice(name, "solvers", "protocol", SOLVERS[1:])
    from .tuning import to_params, tune

    def fit(case):
        last = None
        for last in tune([case], method, rng=rng, generations=generations, solver=fit_solver,
                         seeds=fit_seeds):
            if progress:
                progress(case.name, last)
        return to_params(method, last.best_chromosome)

    from .tuning import evaluate
    tested = fit(cases[train])
    rows = []
    for n, case in enumerate(cases):
        own = tested if n == train else fit(case) if fit_all else None
        testing = tuple(evaluate([case], method, tested, seed) for seed in range(seeds))
        training = None if own is None else tuple(evaluate([case], method, own, seed)
                                                  for seed in range(seeds))
        rows.append({"name": case.name, "testing": testing, "training": training, "params": own})
    held_out = [r for n, r in enumerate(rows) if n != train]
    pooled = [sum((r["testing"][s] for r in held_out), Score(0, 0, 0, 0)) for s in range(seeds)]
    report = {"method": method, "params": tested, "train": train, "rows": rows, "held_out": pooled,
              "peers": {}, "solvers": {}}
    for name in solvers:
        runs = range(1) if name == "exact" else range(seeds)
        per_pair = [tuple(evaluate([c], method, tested, s, name) for s in runs) for c in cases]
        report["solvers"][name] = {"rows": per_pair, "held_out": [
            sum((p[s] for n, p in enumerate(per_pair) if n != train), Score(0, 0, 0, 0)) for s in runs]}
    if peers:
        from .peers import PEERS
        for name, peer in PEERS.items():
            per_pair = [score(peer(c.prepared.problem, method, tested), c.targets, c.unknown) for c in cases]
            report["peers"][name] = {"rows": per_pair, "held_out": sum(
                (p for n, p in enumerate(per_pair) if n != train), Score(0, 0, 0, 0))}
    return report


def format_protocol(report: dict) -> str:
    """Print the protocol like the thesis: "Testing: 14/2+0/16  Training: 16/0+1/16"."""
    lines = [f"Method-{report['method']}, parameters fitted on pair {report['train']}: "
             f"{report['params']}"]
    for n, row in enumerate(report["rows"]):
        mark = " (training pair)" if n == report["train"] else ""
        trained = "not fitted" if row["training"] is None else row["training"][0]
        lines.append(f"{row['name']}{mark}: Testing: {row['testing'][0]}  Training: {trained}")
    pooled = report["held_out"]
    if pooled:
        recall = Spread.of([s.recall for s in pooled])
        precision = Spread.of([s.precision for s in pooled])
        lines.append(f"Held-out total (seed 0): {pooled[0]}   C/T {recall}   precision {precision}"
                     f"   over {len(pooled)} update-order seeds")
    for name, variant in report.get("solvers", {}).items():
        held = variant["held_out"]
        recall = Spread.of([s.recall for s in held])
        precision = Spread.of([s.precision for s in held])
        lines.append(f"solver {name:>9}: held-out {held[0]}   C/T {recall}   precision {precision}   "
                     f"per pair: " + "  ".join(str(p[0]) for p in variant["rows"]))
    for name, peer in report.get("peers", {}).items():
        total = peer["held_out"]
        lines.append(f"peer {name:>10}: held-out {total}   C/T {100 * total.recall:.1f}%   "
                     f"precision {100 * total.precision:.1f}%   per pair: "
                     + "  ".join(str(s) for s in peer["rows"]))
    return "\n".join(lines)
