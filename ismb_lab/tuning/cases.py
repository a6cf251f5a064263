"""The train/test protocol of the thesis' Fig. 5.10, its report, and the training pair (Case):
fit the GA on one pair and apply the parameters to every other, printing ``C/E/T`` for each."""

from __future__ import annotations

import ctypes
import multiprocessing
import numbers
import os
import signal
import sys
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from .._core.validation import MAX_SEED, ParameterError, ParameterTypeError, check_number, message
from ..images.datasets import aloe, ground_truth_pairs, motorcycle
from .evaluation import Score, Scorer, score, unlabelled
from .genetic import GAConfig
from ..matching.pipeline import MatchConfig, Prepared, prepare
from ..network.methods import DEFAULT_METHOD, get_method
from ..network.params import Params
from ..matching.peers import PEERS
from ..scenes import true_matches
from ..network.solvers import DEFAULT_SOLVER, Solver, get_solver
from ..labels.targets import check_one_to_one, load_targets, snap
from .fitness import evaluate, to_params, tune

__all__ = ["SOURCES", "Case", "PairReport", "PeerReport", "ProtocolReport", "SolverReport", "Spread",
           "family_cases", "format_protocol", "load_manifest", "protocol"]

_NONE = Score(0, 0, 0, 0)


@dataclass(frozen=True, eq=False)
class Case:
    """One stereo pair with its targets ``(i, k)``: the unit the GA trains on and the protocol scores.

    Matches of the left features in `unknown` are not scored; `left_out` lists the source file's
    targets that no corner is close enough to.

    Attributes
    ----------
    prepared : Prepared
        The pair's corners, config and candidate neurons.
    targets : (n, 2) int ndarray
        Target ``(i, k)`` pairs of left and right corner indices.
    unknown : int ndarray
        Left corners whose matches are not scored.
    name : str
        Shown in reports.
    left_out : int ndarray
        Source targets no corner is close enough to.
    """

    prepared: Prepared
    targets: np.ndarray
    unknown: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    name: str = ""
    left_out: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @cached_property
    def scorer(self) -> Scorer:
        """:func:`~ismb_lab.tuning.evaluation.score` against this case's targets, built once."""
        return Scorer(self.targets, self.unknown)

    @cached_property
    def neuron_codes(self) -> np.ndarray:
        """The scorer's codes of this case's candidate neurons."""
        problem = self.prepared.problem
        return self.scorer.neuron_codes(problem.rows, problem.cols)

    @classmethod
    def from_files(cls, left, right, targets, config: MatchConfig | None = None,
                   name: str | None = None, check_hash: bool = True, partial: bool = False) -> "Case":
        """A case from two image files and a targets file (as the labeller saves it).

        The targets are checked against the images' hashes (unless not `check_hash`), refused if a
        corner has two partners, and snapped to the corners `config` finds.  With `partial` the file
        labels only some corners (a person's labels): matches of the others are not scored; without
        it, as in the thesis, any other match is an error.

        Parameters
        ----------
        left, right : str or Path
            The image files.
        targets : str or Path
            The targets JSON file (:func:`~ismb_lab.labels.targets.save_targets`).
        config : MatchConfig, optional
            Corner settings; default ``MatchConfig()``.
        name : str, optional
            The case's name; default the left file's path.
        check_hash : bool, default True
            Refuse targets saved for other images.
        partial : bool, default False
            The file labels only some corners.

        Returns
        -------
        case : Case
            The prepared pair with its snapped targets.
        """
        if not isinstance(partial, bool):
            raise ParameterTypeError(message("partial", "Case.from_files", "True or False", partial))
        prepared = prepare(left, right, config)
        target_set = check_one_to_one(load_targets(targets, pair=prepared.pair, check_hash=check_hash),
                                      str(targets), "Case.from_files")
        snapped = snap(target_set, prepared.problem.left_xy, prepared.problem.right_xy)
        left_out = np.union1d(snapped.missing_left, snapped.missing_right).astype(np.int64)
        pairs = snapped.pairs.astype(np.int64)
        unknown = unlabelled(pairs, len(prepared.problem.left_xy)) if partial else np.zeros(0, np.int64)
        return cls(prepared, pairs, unknown, name=str(left) if name is None else name, left_out=left_out)

    @classmethod
    def from_scene(cls, scene, config: MatchConfig | None = None, name: str = "") -> "Case":
        """A case from a rendered Scene: every corner whose true partner is a detected corner is a target.

        Parameters
        ----------
        scene : Scene
            A rendered scene with its ground truth (e.g. :func:`~ismb_lab.scenes.synthetic_scene`).
        config : MatchConfig, optional
            Corner settings; default ``MatchConfig()``.
        name : str, default ""
            The case's name.

        Returns
        -------
        case : Case
            The prepared pair with its true targets.

        Examples
        --------
        >>> from ismb_lab.scenes import synthetic_scene
        >>> case = Case.from_scene(synthetic_scene(seed=0), name="synthetic 0")
        >>> case.name, len(case.targets) > 15
        ('synthetic 0', True)
        """
        prepared = prepare(scene.left, scene.right, config)
        truth = true_matches(scene, prepared.problem.left_xy, prepared.problem.right_xy)
        left = np.flatnonzero(truth >= 0)
        return cls(prepared, np.stack([left, truth[left]], axis=1).astype(np.int64), name=name)


def family_cases(family: str, start: int, count: int) -> list:
    """The cases of one scene family's layouts ``start .. start + count - 1`` (``2 + seed % 2``
    objects each, in their ROI and window shift), without those of fewer than 3 targets; the
    first case is the training pair, the first with at least 8 targets.

    Parameters
    ----------
    family : str
        A scene family's name (:func:`~ismb_lab.scenes.get_family`).
    start : int
        First layout seed.
    count : int
        Number of layouts, >= 1.

    Returns
    -------
    cases : list of Case
        The kept cases, the training pair first.

    Raises
    ------
    ParameterError
        No layout has 3 targets.

    Examples
    --------
    >>> cases = family_cases("cameras", 2300, 3)
    >>> len(cases[0].targets) >= 8, cases[0].name.startswith("cameras ")
    (True, True)
    """
    from ..scenes import get_family, object_layout

    family = get_family(family, "family_cases").name
    start = check_number(start, "start", "family_cases", low=0, high=MAX_SEED, integer=True)
    count = check_number(count, "count", "family_cases", low=1, high=MAX_SEED - start + 1, integer=True)
    cases = []
    for seed in range(start, start + count):
        layout = object_layout(seed, 2 + seed % 2, family=family)
        case = Case.from_scene(layout.scene, MatchConfig(roi=layout.roi, shift=layout.shift),
                               name=f"{family} {seed}")
        if len(case.targets) >= 3:
            cases.append(case)
    if not cases:
        raise ParameterError(message("count", "family_cases", "a split with a layout of at least 3 targets",
                                     f"{count} layout(s) from seed {start}, none with 3 targets"))
    first = next((i for i, c in enumerate(cases) if len(c.targets) >= 8), 0)
    return [cases[first]] + cases[:first] + cases[first + 1:]


#: Built-in ground-truth pairs a manifest can name as ``"source"``, at the thesis' width of 320 px.
SOURCES = {"middlebury-motorcycle": lambda: motorcycle(), "middlebury-aloe": lambda: aloe(320)}


def _read_manifest(path: Path):
    """The JSON of a manifest, read within ``MAX_JSON_BYTES``."""
    from .._core.files import read_json

    try:
        return read_json(path)
    except FileNotFoundError:
        raise ParameterError(message("path", "load_manifest", "an existing file", str(path))) from None
    except OSError as exc:
        raise ParameterError(message("path", "load_manifest", f"a readable JSON manifest ({exc.strerror or exc})",
                                     str(path))) from None
    except ValueError as exc:
        raise ParameterError(message("path", "load_manifest", f"a JSON manifest ({exc})", str(path))) from None


def source_files(name: str) -> tuple:
    """The files a built-in source of :data:`SOURCES` reads (those that exist).

    >>> [p.name for p in source_files("middlebury-motorcycle")][:2]
    ['motorcycle_left.png', 'motorcycle_right.png']
    """
    from ..images.datasets import SampleDataMissing, aloe_files, motorcycle_files

    try:
        found = {"middlebury-motorcycle": motorcycle_files, "middlebury-aloe": aloe_files}[name]()
    except (KeyError, SampleDataMissing, ImportError):
        return ()
    return tuple(p for p in found if p.is_file())


def manifest_files(path) -> list:
    """Every file a manifest makes a run read (its pairs' and its sources'), or none if it cannot
    be read: best effort, for the check that no output is one of them."""
    try:
        data = _read_manifest(Path(path))
        entries = data["pairs"]
        named = [Path(path).parent / e[k] for e in entries for k in ("left", "right", "targets")
                 if isinstance(e, dict) and isinstance(e.get(k), str)]
        sources = {e["source"] for e in entries if isinstance(e, dict) and isinstance(e.get("source"), str)}
    except (ParameterError, TypeError, KeyError):
        return []
    return named + [f for name in sorted(sources) for f in source_files(name)]


def load_manifest(path, config: MatchConfig | None = None) -> list[Case]:
    """Read an evaluation manifest, ``{"pairs": [entry, ...]}``, into :class:`Case` objects.

    An entry is a file pair, ``{"name", "left", "right", "targets", "roi", "shift"}`` (paths
    relative to the manifest; ``roi`` and ``shift`` optional), or a built-in ground-truth pair,
    ``{"name", "source", "roi"}`` with a source of :data:`SOURCES`.

    Parameters
    ----------
    path : str or Path
        The manifest JSON file.
    config : MatchConfig, optional
        Corner settings each entry's ``roi`` and ``shift`` override; default ``MatchConfig()``.

    Returns
    -------
    cases : list of Case
        One per entry, in order.

    Raises
    ------
    ParameterError
        An unreadable manifest, or an entry with a missing file or unknown source.
    """
    path = Path(path)
    owner = f"the manifest '{path}'"
    data = _read_manifest(path)
    entries = data.get("pairs") if isinstance(data, dict) else None
    if not isinstance(entries, list) or not entries:
        raise ParameterError(message("pairs", owner, "a non-empty list of pair entries", entries))
    base = config or MatchConfig()
    cases, loaded = [], {}
    for n, entry in enumerate(entries):
        if not isinstance(entry, dict):
            raise ParameterError(message(f"pairs[{n}]", owner, "an object", entry))
        cfg = replace(base, **{k: entry[k] for k in ("roi", "shift") if k in entry})
        name = str(entry.get("name", f"pair {n}"))
        if "source" in entry:
            source = entry["source"]
            if source not in SOURCES:
                raise ParameterError(message(f"pairs[{n}].source", owner, "one of " + ", ".join(map(repr, SOURCES)),
                                             source))
            loaded[source] = loaded.get(source) or SOURCES[source]()
            truth = loaded[source]
            prepared = prepare(truth.left, truth.right, cfg)
            targets, unknown = ground_truth_pairs(truth.disparity, prepared.problem.left_xy,
                                                  prepared.problem.right_xy)
            cases.append(Case(prepared, targets, unknown, name))
            continue
        files = {}
        for key in ("left", "right", "targets"):
            if not isinstance(entry.get(key), str):
                raise ParameterError(message(f"pairs[{n}].{key}", owner, "a file path (a string)",
                                             entry.get(key)))
            files[key] = path.parent / entry[key]
            if not files[key].is_file():
                raise ParameterError(message(f"pairs[{n}].{key}", owner, "an existing file",
                                             str(files[key])))
        cases.append(Case.from_files(files["left"], files["right"], files["targets"], cfg, name))
    return cases


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
        """The Spread of `values`, one per seed."""
        v = np.asarray(values, dtype=float)
        return cls(float(v.mean()), float(v.std()), float(v.min()), float(v.max()), len(v))

    def __str__(self) -> str:
        if self.n == 1 or self.high == self.low:
            return f"{100 * self.mean:.1f}%"
        return f"{100 * self.mean:.1f}% ({100 * self.low:.1f}-{100 * self.high:.1f})"


@dataclass(frozen=True)
class PairReport:
    """One pair's row: a Score per update-order seed with the tested parameters and with its own
    fit (`training` and `params` None when it was not fitted)."""

    name: str
    testing: tuple
    training: tuple | None
    params: Params | None


@dataclass(frozen=True)
class SolverReport:
    """The tested parameters solved another way: per pair and per seed, and pooled."""

    rows: tuple
    held_out: tuple
    seeded: bool = True


@dataclass(frozen=True)
class PeerReport:
    """A deterministic peer matcher: per pair, and pooled over the held-out pairs."""

    rows: tuple
    held_out: Score


@dataclass(frozen=True)
class ProtocolReport:
    """What :func:`protocol` measured: `params` fitted on pair `train` and tested on all, and
    `held_out`, the held-out pairs' pooled Score per update-order seed.

    Attributes
    ----------
    method : str
        The method's name.
    params : Params
        Fitted on the training pair.
    train : int
        Index of the training pair.
    rows : tuple of PairReport
        One per pair.
    held_out : tuple of Score
        The held-out pairs pooled, per seed.
    solver : str
        The solver of the tested energies.
    peers : dict of str to PeerReport
        Peer matchers' scores, when asked for.
    solvers : dict of str to SolverReport
        Other solvers' scores, when asked for.
    one_to_one : bool
        Whether matches were cut to one per corner.
    """

    method: str
    params: Params
    train: int
    rows: tuple
    held_out: tuple
    solver: str = DEFAULT_SOLVER
    peers: dict = field(default_factory=dict)
    solvers: dict = field(default_factory=dict)
    one_to_one: bool = False

    def to_dict(self) -> dict:
        """The JSON of ``ismb-lab evaluate --json``."""
        def figures(s: Score) -> dict:
            return {"cet": str(s), "recall": s.recall, "precision": s.precision}

        return {"method": self.method, "solver": self.solver, "one_to_one": self.one_to_one, "train": self.train,
                "params": self.params.to_dict(),
                "seeds": len(self.held_out),
                "pairs": [{"name": r.name, "testing": [str(s) for s in r.testing],
                           "training": None if r.training is None else [str(s) for s in r.training]}
                          for r in self.rows],
                "held_out": [figures(s) for s in self.held_out],
                "peers": {name: {"held_out": str(p.held_out), "recall": p.held_out.recall,
                                 "precision": p.held_out.precision} for name, p in self.peers.items()},
                "solvers": {name: [figures(s) for s in v.held_out] for name, v in self.solvers.items()}}


def protocol(cases, method=DEFAULT_METHOD, *, train: int = 0, seeds: int = 5, ga: GAConfig | None = None,
             rng=0, peers: bool = False, progress=None, solver=DEFAULT_SOLVER, solvers=(),
             fit_solver=DEFAULT_SOLVER, fit_seeds: int = 1, fit_all: bool = True, jobs: int = 1,
             one_to_one: bool = False, **settings) -> ProtocolReport:
    """Fig. 5.10's protocol: GA-fit on each pair ("training", only pair `train` without `fit_all`)
    and on pair `train` applied to all the others ("testing"), every network figure over `seeds`
    update-order seeds.

    `ga` (overridden by `settings`) and `rng` run the GA, which scores a chromosome with
    `fit_solver` over `fit_seeds` seeds; `progress(case_name, generation)` follows it (once per
    fit with ``jobs > 1``).  `solver` solves the tested energies (once if it ignores the seed),
    `solvers` are others reported beside; `peers` also scores :mod:`ismb_lab.matching.peers`;
    `one_to_one` scores the network's matches after one match per corner.  The report is the same
    for every number of worker processes `jobs`.

    Parameters
    ----------
    cases : sequence of Case
        At least two pairs.
    method : str or Method, default ``DEFAULT_METHOD``
        The method to fit.
    train : int, default 0
        Index of the training pair.
    seeds : int, default 5
        Update-order seeds of every network figure.
    ga : GAConfig, optional
        The GA's settings.
    rng : int or numpy.random.Generator, default 0
        The GA's random source.
    peers : bool, default False
        Also score the peer matchers.
    progress : callable, optional
        ``progress(case_name, generation)``, called as the GA runs.
    solver : str or Solver, default ``DEFAULT_SOLVER``
        Solves the tested energies.
    solvers : sequence of str or Solver, optional
        Other solvers reported beside.
    fit_solver : str or Solver, default ``DEFAULT_SOLVER``
        Solves the energies while fitting.
    fit_seeds : int, default 1
        Update-order seeds per chromosome while fitting.
    fit_all : bool, default True
        Fit every pair on its own ("training"), not only pair `train`.
    jobs : int, default 1
        Worker processes.
    one_to_one : bool, default False
        Score the network's matches after one match per corner.
    **settings
        :class:`GAConfig` fields overriding `ga`'s.

    Returns
    -------
    report : ProtocolReport
        The fitted parameters and every score (:func:`format_protocol` prints it).
    """
    own = "protocol"
    if not hasattr(cases, "__len__") or not all(isinstance(c, Case) for c in cases):
        raise ParameterTypeError(message("cases", own, "a sequence of Case", cases))
    if len(cases) < 2:   # the held-out figures would be 0/0
        raise ParameterError(message("cases", own, "at least two pairs: one to fit the parameters on, one or more "
                                     "to test them on", f"{len(cases)} pair{'s' if len(cases) != 1 else ''}"))
    method = get_method(method)
    train = check_number(train, "train", own, low=0, high=len(cases) - 1, integer=True)
    seeds = check_number(seeds, "seeds", own, low=1, integer=True)
    main = get_solver(solver, own)
    fit_solver = get_solver(fit_solver, own, "fit_solver")
    fit_seeds = check_number(fit_seeds, "fit_seeds", own, low=1, integer=True)
    if not isinstance(one_to_one, bool):
        raise ParameterTypeError(message("one_to_one", own, "True or False", one_to_one))
    solvers = (solvers,) if isinstance(solvers, (str, Solver)) else tuple(solvers)
    chosen = [get_solver(name, own, "solvers") for name in solvers]
    if any(s.name == main.name for s in chosen):
        raise ParameterError(message("solvers", own, f"solvers other than solver={main.name!r}, "
                                     "whose rows the report has already", solvers))
    runs = range(seeds) if main.seeded else range(1)
    ga = (ga or GAConfig()).updated(own, **settings)
    jobs = check_number(jobs, "jobs", own, low=1, integer=True)
    if jobs > 1 and not (isinstance(rng, numbers.Integral) and not isinstance(rng, bool)):
        raise ParameterTypeError(message("rng", own, "an integer seed when jobs > 1", rng))
    fitted = [train] + [n for n in range(len(cases)) if n != train and fit_all]
    fit = (method, rng, ga, fit_solver, fit_seeds)
    with _workers(min(jobs, len(cases))) as pool:   # a worker more than the tasks would idle
        if pool is None:
            fits = {n: _fit(cases[n], *fit, progress) for n in fitted}
        else:
            with _starting_workers():
                futures = {n: pool.submit(_fit, cases[n], *fit) for n in fitted}
            fits = {}
            for n, future in futures.items():
                fits[n] = future.result()
                if progress:
                    progress(cases[n].name, fits[n][1])
        tested = fits[train][0]
        task = (method, tested, runs, main, chosen, seeds, peers, one_to_one)
        owns = [fits[n][0] if n in fits else None for n in range(len(cases))]
        if pool is None:
            scored = [_score_pair(c, p, *task) for c, p in zip(cases, owns)]
        else:
            with _starting_workers():   # map submits every task at once, and returns
                results = pool.map(_score_pair, cases, owns, *([t] * len(cases) for t in task))
            scored = list(results)

    rows = tuple(PairReport(c.name, s["testing"], s["training"], p) for c, s, p in zip(cases, scored, owns))

    def pooled(per_pair, runs):
        return tuple(sum((p[s] for n, p in enumerate(per_pair) if n != train), _NONE) for s in runs)

    held_out = pooled([r.testing for r in rows], runs)
    solver_reports = {}
    for other in chosen:
        per_pair = tuple(s["solvers"][other.name] for s in scored)
        solver_reports[other.name] = SolverReport(per_pair, pooled(per_pair, range(len(per_pair[0]))),
                                                   other.seeded)
    peer_reports = {}
    for name in PEERS if peers else ():
        per_pair = tuple(s["peers"][name] for s in scored)
        peer_reports[name] = PeerReport(per_pair, sum((p for n, p in enumerate(per_pair) if n != train), _NONE))
    return ProtocolReport(method.name, tested, train, rows, held_out, main.name, peer_reports, solver_reports,
                          one_to_one)


def _fit(case, method, rng, ga, fit_solver, fit_seeds, progress=None):
    """One GA fit: the best parameters and the last generation's record."""
    last = None
    for last in tune([case], method, rng=rng, ga=ga, solver=fit_solver, seeds=fit_seeds):
        if progress:
            progress(case.name, last)
    return to_params(method, last.best_chromosome), last


def _score_pair(case, own_params, method, tested, runs, solver, others, seeds, peers, one_to_one) -> dict:
    """One pair's scores: tested and own parameters, other solvers and peers."""
    out = {"testing": tuple(evaluate([case], method, tested, s, solver, one_to_one) for s in runs),
           "training": None if own_params is None else tuple(
               evaluate([case], method, own_params, s, solver, one_to_one) for s in runs),
           "solvers": {other.name: tuple(evaluate([case], method, tested, s, other, one_to_one)
                                         for s in (range(seeds) if other.seeded else range(1)))
                       for other in others},
           "peers": {}}
    if peers:
        out["peers"] = {name: score(peer(case.prepared.problem, method, tested), case.targets, case.unknown)
                        for name, peer in PEERS.items()}
    return out


_PR_SET_PDEATHSIG = 1   # from <linux/prctl.h>


def _start_worker(parent: int) -> None:
    """A worker's first step: die with its parent, then leave Ctrl-C to the parent (which stops
    the pool and reports once)."""
    _die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def _starting_workers():
    """Within: SIGINT blocked in this thread, so that a worker started here is born with it
    blocked (else a Ctrl-C while it imports prints a traceback); a Ctrl-C waits for the end."""
    block = getattr(signal, "pthread_sigmask", None)
    if block is None:   # pragma: no cover - not POSIX
        yield
        return
    old = block(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        block(signal.SIG_SETMASK, old)


def _die_with_parent(parent: int) -> None:
    """On Linux, ask the kernel for SIGKILL when the parent dies, however it dies."""
    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        failed = libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0
    except (OSError, AttributeError):
        return
    if not failed and os.getppid() != parent:   # it died before the request: no signal will come
        os._exit(1)


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """Terminate the pool's workers now: a task they run is not waited for."""
    stop = getattr(pool, "terminate_workers", None)   # Python 3.14
    if stop is not None:
        stop()
        return
    for process in list((pool._processes or {}).values()):
        if process.is_alive():
            process.terminate()


class _workers:
    """A spawned process pool for ``jobs > 1`` whose workers die with the process that made them:
    an exception leaving the block terminates them, and on Linux so does that process's death.
    They die if the thread that enters the block ends: enter it from one that outlives the pool."""

    def __init__(self, jobs: int):
        self.jobs, self.pool = jobs, None

    def __enter__(self):
        if self.jobs > 1:
            self.pool = ProcessPoolExecutor(self.jobs, mp_context=multiprocessing.get_context("spawn"),
                                            initializer=_start_worker, initargs=(os.getpid(),))
        return self.pool

    def __exit__(self, kind, *_):
        if self.pool is not None:
            if kind is not None:
                _stop_workers(self.pool)
            self.pool.shutdown(wait=True, cancel_futures=kind is not None)
        return False


def _percent(ratio: float, none: str) -> str:
    """A ratio as a percentage; `none` says why there is none (a ratio of 0/0)."""
    return f"{100 * ratio:.1f}%" if np.isfinite(ratio) else f"- ({none})"


def _figures(s: Score) -> str:
    return (f"{s}   C/T {_percent(s.recall, 'no targets')}   "
            f"precision {_percent(s.precision, 'no matches')}")


def _over_seeds(scores, what: str) -> list[str]:
    if len(scores) < 2:
        return []
    recall = Spread.of([s.recall for s in scores])
    precision = Spread.of([s.precision for s in scores])
    return [f"  {what} over {len(scores)} update-order seeds: C/T mean {recall}   "
            f"precision mean {precision}"]


def format_protocol(report: ProtocolReport) -> str:
    """The protocol as the thesis prints it: "Testing: 14/2+0/16  Training: 16/0+1/16", with the
    mean and range over the update-order seeds on lines of their own.

    Each score reads ``C/wrong+extra/T`` (see :class:`~ismb_lab.tuning.evaluation.Score`).

    Parameters
    ----------
    report : ProtocolReport
        What :func:`protocol` returned.

    Returns
    -------
    text : str
        The report, one line per pair, solver and peer.
    """
    lines = [f"Method-{report.method} ({report.solver}{', one match per corner' if report.one_to_one else ''}), "
             f"parameters fitted on pair {report.train}: {report.params}",
             "Per pair, update-order seed 0 (C/wrong+extra/T):"]
    for n, row in enumerate(report.rows):
        mark = " (training pair)" if n == report.train else ""
        trained = "not fitted" if row.training is None else row.training[0]
        lines.append(f"{row.name}{mark}: Testing: {row.testing[0]}  Training: {trained}")
    if report.held_out:
        lines.append(f"Held-out total, seed 0: {_figures(report.held_out[0])}")
        lines += _over_seeds(report.held_out, "held-out total")
    for name, variant in report.solvers.items():
        seed = " (seed 0)" if variant.seeded else ""
        lines.append(f"solver {name:>9}: held-out{seed} {_figures(variant.held_out[0])}   per pair: "
                     + "  ".join(str(p[0]) for p in variant.rows))
        lines += _over_seeds(variant.held_out, f"solver {name}")
    for name, peer in report.peers.items():
        lines.append(f"peer {name:>10}: held-out {_figures(peer.held_out)}   per pair: "
                     + "  ".join(str(s) for s in peer.rows))
    return "\n".join(lines)
