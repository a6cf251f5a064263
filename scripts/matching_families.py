"""Matching on the new scene families: the network's methods beside the peers, train on one pair.

For each family of :func:`ismb_lab.scenes.families` (contrast, repetitive, border, cameras) a set
of layouts is rendered (two or three objects each); the targets are every corner whose true
partner is a detected corner; layouts with fewer than 3 targets are left out. The GA is fitted
on one pair of each set (the first with at least 8 targets, a rule fixed before any result)
and tested on the others, every network figure over 3 update-order seeds and 3 GA seeds (0, 1, 2);
mutual nearest neighbour and Hungarian assignment with a no-match cost see the same corners.

    python scripts/matching_families.py                  # development split (seeds 2000-)
    python scripts/matching_families.py --held-out       # held-out split (seeds 930000-), run once

The variants are Method-III (the thesis, network), Method-NM4 (annealed) and Method-NM
(network); ``--variants III:network NM4:anneal`` picks others, and ``METHOD:SOLVER:FIT_SOLVER``
also has the GA fit with that solver (by default the GA fits with the network).  A solver
may carry options: ``anneal(cooling=0.8,sweeps=1)``.
``--fit-seeds N`` has the GA score each chromosome over N update-order seeds, ``--ga-seeds N``
sets the number of GA seeds and ``--seeds-from`` the first layout seed. It prints the
figures per family, pooled, and their spread over GA seeds and over update-order seeds, and
the elapsed time.

The records of every run, with the variants tried and chosen and their development and held-out
figures, are in ``docs/experiments/2026-11-24-matching-families.md``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ismb_lab.tuning.evaluation import score
from ismb_lab.images.io import save_image
from ismb_lab.tuning.cases import family_cases, protocol
from ismb_lab.scenes import families
from ismb_lab.network.solvers import DEFAULT_SOLVER, get_solver
from ismb_lab.labels.targets import save_targets, targets_from_matches

DEV_START, HELD_OUT_START = 2000, 930_000
VARIANTS = ("III:network", "NM4:anneal", "NM:network")


def solver_of(text: str):
    """A solver name, or a configured solver from ``NAME(OPTION=VALUE,...)``.

    >>> solver_of("anneal(cooling=0.8,sweeps=1)")
    AnnealSolver(t_start=2.0, t_end=0.02, cooling=0.8, sweeps=1, settle=0.0)
    >>> solver_of("network")
    'network'
    """
    if not text.endswith(")"):
        return text
    name, _, options = text[:-1].partition("(")
    values = dict(item.split("=", 1) for item in options.split(",") if item)
    return get_solver(name, "--variants", **{k: json.loads(v) for k, v in values.items()})


def family_sets(start: int, count: int) -> dict:
    """Every registered family's cases, the `n`-th family of :func:`~ismb_lab.scenes.families`
    drawn from seed ``start + 100 n`` on (:func:`~ismb_lab.tuning.cases.family_cases`)."""
    return {f: family_cases(f, start + 100 * n, count) for n, f in enumerate(families())}


def figures(scores) -> tuple[int, int, int]:
    return (sum(s.correct for s in scores), sum(s.errors for s in scores), sum(s.targets for s in scores))


def _cli(*words) -> None:
    proc = subprocess.run([sys.executable, "-m", "ismb_lab.cli", *map(str, words)], capture_output=True, text=True)
    if proc.returncode:
        raise SystemExit(f"ismb-lab {words[0]} failed: {proc.stderr.strip()}")


def _window(case) -> list:
    config = case.prepared.config
    return ["--roi", ",".join(map(str, config.roi)), "--shift", f"{config.shift:g}"]


def _images(case, folder: Path) -> list:
    folder.mkdir(parents=True, exist_ok=True)
    return [save_image(folder / f"{side}.png", getattr(case.prepared.pair, side)) for side in ("left", "right")]


def cli_held_out(cases, method: str, solver: str, fit_solver: str, ga_seed: int, fit_seeds: int,
                 generations: int, folder: Path, one_to_one: bool = False) -> list:
    """The protocol through the command line alone: ``ismb-lab tune`` on the training pair's
    images and targets, then ``ismb-lab match --params-file`` on each other pair for update
    seeds 0-2.  Returns the held-out figures ``[(C, E, T)]``, one per update seed."""
    train, problem = cases[0], cases[0].prepared.problem
    left, right = _images(train, folder / "train")
    targets = folder / "train" / "targets.json"
    save_targets(targets, targets_from_matches(train.targets, problem.left_xy, problem.right_xy))
    params = folder / f"params-{ga_seed}.json"
    _cli("tune", left, right, targets, "--method", method, "--solver", fit_solver, "--fit-seeds", fit_seeds,
         "--generations", generations, "--seed", ga_seed, *_window(train), "--out", params, "--force")
    runs = []
    for seed in range(3):
        scores = []
        for n, case in enumerate(cases[1:], 1):
            out = folder / f"match-{n}.json"
            _cli("match", *_images(case, folder / f"test-{n}"), "--params-file", params, "--solver", solver,
                 "--seed", seed, *_window(case), "--json", out, "--force", *(["--one-to-one"] if one_to_one else []))
            p = case.prepared.problem
            index = ({tuple(xy): i for i, xy in enumerate(p.left_xy.tolist())},
                     {tuple(xy): k for k, xy in enumerate(p.right_xy.tolist())})
            pairs = np.array([(index[0][tuple(m["left_xy"])], index[1][tuple(m["right_xy"])])
                              for m in json.loads(out.read_text())["matches"]], dtype=np.int64).reshape(-1, 2)
            scores.append(score(pairs, case.targets, case.unknown))
        runs.append(figures(scores))
    return runs


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--held-out", action="store_true", help="the held-out split (run it once)")
    parser.add_argument("--seeds-from", type=int, default=None, metavar="SEED",
                        help=f"first layout seed (default {DEV_START}, or {HELD_OUT_START} with --held-out)")
    parser.add_argument("--count", type=int, default=12, help="layouts per family (default 12)")
    parser.add_argument("--generations", type=int, default=200, help="GA generations (default 200)")
    parser.add_argument("--ga-seeds", type=int, default=3, help="GA seeds 0, 1, ... per fit (default 3)")
    parser.add_argument("--fit-seeds", type=int, default=1,
                        help="update-order seeds the GA scores each chromosome over (default 1)")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes of each protocol (default 1)")
    parser.add_argument("--variants", nargs="+", default=VARIANTS, metavar="METHOD:SOLVER[:FIT_SOLVER]")
    parser.add_argument("--one-to-one", action="store_true",
                        help="score the network's matches after one match per corner (match --one-to-one)")
    parser.add_argument("--cli", action="store_true",
                        help="one variant through 'ismb-lab tune' and 'ismb-lab match' themselves, on PNG files")
    args = parser.parse_args(argv)
    if args.cli and len(args.variants) != 1:
        parser.error("--cli runs one variant")
    start = args.seeds_from if args.seeds_from is not None else HELD_OUT_START if args.held_out else DEV_START
    began = time.perf_counter()
    sets = family_sets(start, args.count)
    print(f"{'held-out' if args.held_out else 'development'} split, seeds from {start}, "
          f"{args.ga_seeds} GA seed(s), 3 update-order seeds: "
          + ", ".join(f"{f} {len(c)} pairs / {sum(len(x.targets) for x in c)} targets" for f, c in sets.items()))
    if args.cli:
        method, solver, *fit = args.variants[0].split(":")
        total = [0, 0, 0]
        with tempfile.TemporaryDirectory(prefix="matching_families-") as folder:
            for family, cases in sets.items():
                rows = [0, 0, 0]
                for ga_seed in range(args.ga_seeds):
                    for cet in cli_held_out(cases, method, solver, fit[0] if fit else DEFAULT_SOLVER, ga_seed,
                                            args.fit_seeds, args.generations, Path(folder) / family,
                                            args.one_to_one):
                        rows = [a + b for a, b in zip(rows, cet)]
                total = [a + b for a, b in zip(total, rows)]
                print(f"{family:>10} {args.variants[0]} through the CLI: {rate(*rows)}", flush=True)
        print(f"pooled over the families, {args.ga_seeds} GA seed(s) x 3 update-order seeds, through the CLI: "
              f"{rate(*total)}")
        print(f"elapsed {time.perf_counter() - began:.0f} s")
        return
    pooled = {}        # name -> [C, E, T] over families, GA seeds and update-order seeds
    per_seed = {}      # (variant, "GA"|"update", seed) -> [C, E, T] over families and the other seeds
    for variant in args.variants:
        method, solver, *fit = variant.split(":")     # METHOD:SOLVER[:FIT_SOLVER]; the GA fits with the network
        for family, cases in sets.items():
            rows = {}
            for ga_seed in range(args.ga_seeds):
                # only the training pair's fit is tested on the others: fit_all=False fits it alone
                report = protocol(cases, method, peers=ga_seed == 0, generations=args.generations, seeds=3,
                                  solver=solver_of(solver), fit_solver=solver_of(fit[0]) if fit else DEFAULT_SOLVER,
                                  rng=ga_seed,
                                  fit_seeds=args.fit_seeds, fit_all=False, jobs=args.jobs,
                                  one_to_one=args.one_to_one)
                add(rows, variant, figures(report.held_out))
                add(per_seed, (variant, "GA", ga_seed), figures(report.held_out))
                for run, s in enumerate(report.held_out):
                    add(per_seed, (variant, "update", run), figures([s]))
                if ga_seed == 0:   # the peers are deterministic and use no fitted parameter
                    for peer in ("mutual-nn", "hungarian"):
                        rows[peer] = figures([report.peers[peer].held_out])
            for name, cet in rows.items():
                if name == variant or variant == args.variants[0]:
                    add(pooled, name, cet)
            print(f"{family:>10} " + "   ".join(f"{name}: {rate(c, e, t)}" for name, (c, e, t) in rows.items()),
                  flush=True)
    print(f"pooled over the families (network figures over {args.ga_seeds} GA seed(s) x 3 update-order seeds):")
    for name, (c, e, t) in pooled.items():
        print(f"  {name:>12}: {rate(c, e, t)}")
        for kind in ("GA", "update"):
            spread = [cet for (v, k, _), cet in per_seed.items() if v == name and k == kind]
            if len(spread) > 1:
                recall = [100 * c / t for c, e, t in spread]
                precision = [100 * c / max(c + e, 1) for c, e, t in spread]
                print(f"  {'':>12}  over {kind} seeds: C/T {min(recall):.1f}-{max(recall):.1f}%, "
                      f"precision {min(precision):.1f}-{max(precision):.1f}%")
    print(f"elapsed {time.perf_counter() - began:.0f} s")


def add(totals: dict, key, cet) -> None:
    total = totals.setdefault(key, [0, 0, 0])
    for n, value in enumerate(cet):
        total[n] += value


def rate(c: int, e: int, t: int) -> str:
    return f"C/T {100 * c / t:5.1f}% precision {100 * c / max(c + e, 1):5.1f}%"


if __name__ == "__main__":
    main()
