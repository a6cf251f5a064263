"""``ismb-lab tune``: the best recipe's against Method-III's, on one training pair.

    python benchmarks/bench_tune.py [--pair images/realistic/01] [--repeats 3]
    python benchmarks/bench_tune.py --smoke

Runs the command line itself, as a user does (a fresh interpreter per run: import, corners,
GA, the final scoring and the write), on a committed pair with its answer key as the targets:
first one run of each, untimed, so that numba's cache is warm, then ``--repeats`` rounds
that alternate Method-III's tune (its defaults) and the best recipe's (:data:`RECIPE`, README's
command; ``--earlier`` adds the same recipe over three fit seeds, and each
``--also "OPTIONS"`` one more tune with those options).  It prints every time, the medians
and their ratio.

Then, in this process, one annealing of the pair's NM3 network (the GA's work unit): the
readable schedule (:func:`ismb_lab.network.annealing.iter_annealing`, dense rows of ``W``, one
compiled call per temperature, then the discrete polish: what ``anneal()`` ran before it was
compiled whole) against :func:`~ismb_lab.network.annealing.anneal`, in alternating blocks, with a
check that both give the same state.  ``--smoke`` runs each command once with 2 generations
and a few annealings, to check that the script works.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ismb_lab.network.annealing import anneal, iter_annealing
from ismb_lab.network.dynamics import run
from ismb_lab.matching.pipeline import prepare
from ismb_lab.network.methods import get_method
from ismb_lab.network.params import Params

ROOT = Path(__file__).resolve().parents[1]

#: README's best recipe, as ``ismb-lab tune`` options (one fit seed, the whole schedule).
RECIPE = ("--method", "NM3", "--solver", "anneal", "--one-to-one", "--generations", "200")
#: The recipe before 2026-11-26 (``--earlier``): the same over three fit seeds.
EARLIER = ("--method", "NM3", "--solver", "anneal", "--fit-seeds", "3", "--one-to-one", "--generations", "200")
#: Method-III's tune: every option at its default.
THESIS = ()


def tune(pair: Path, options, out: Path) -> float:
    """Seconds of one ``ismb-lab tune`` run, in a fresh interpreter."""
    command = [sys.executable, "-m", "ismb_lab.cli", "tune", pair / "left.png", pair / "right.png",
               pair / "answer_key.json", *options, "--out", out, "--force"]
    start = time.perf_counter()
    proc = subprocess.run([str(c) for c in command], capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if proc.returncode:
        raise SystemExit(f"ismb-lab tune failed: {proc.stderr.strip()[-2000:]}")
    return elapsed


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pair", type=Path, default=ROOT / "images" / "realistic" / "01",
                        help="a folder with left.png, right.png and answer_key.json (default: %(default)s)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--earlier", action="store_true", help="also the recipe over three fit seeds (the recipe before 2026-11-26)")
    parser.add_argument("--also", action="append", default=[], metavar="OPTIONS",
                        help="one more tune with these options, e.g. \"--method NM3 --fit-seeds 2\" (repeatable)")
    parser.add_argument("--smoke", action="store_true", help="each command once, 2 generations")
    args = parser.parse_args(argv)
    runs = {"Method-III": THESIS, "best recipe": RECIPE, **({"earlier recipe": EARLIER} if args.earlier else {}),
            **{f"also {n + 1}": tuple(options.split()) for n, options in enumerate(args.also)}}
    if args.smoke:
        args.repeats = 1
        runs = {name: (*options[:-2], "--generations", "2") if "--generations" in options
                else (*options, "--generations", "2") for name, options in runs.items()}
    print(f"pair {args.pair}; {len(os.sched_getaffinity(0))} cores; load average {os.getloadavg()[0]:.2f}")
    for name, options in runs.items():
        print(f"  {name}: ismb-lab tune LEFT RIGHT answer_key.json {' '.join(options)}".rstrip())
    times = {name: [] for name in runs}
    with tempfile.TemporaryDirectory(prefix="bench_tune-") as folder:
        out = Path(folder) / "params.json"
        if not args.smoke:
            for options in runs.values():     # numba's cache warm, the files in the page cache
                tune(args.pair, options, out)
        for _ in range(args.repeats):
            for name, options in runs.items():
                times[name].append(tune(args.pair, options, out))
    medians = {name: statistics.median(t) for name, t in times.items()}
    for name, t in times.items():
        print(f"{name:>12}: median {medians[name]:.2f} s  (runs {', '.join(f'{x:.2f}' for x in t)})")
    for name in medians:
        if name != "Method-III":
            print(f"ratio {name} / Method-III: {medians[name] / medians['Method-III']:.2f}x")
    print(f"load average {os.getloadavg()[0]:.2f}")
    annealing(args.pair, 3 if args.smoke else 200)


def readable(net, seed: int):
    """The annealing as the readable schedule runs it, then the discrete polish."""
    rng, holder = np.random.default_rng(seed), []
    for _ in iter_annealing(net, rng=rng, state=holder):
        pass
    return run(net, rng=rng, state=(holder[0] > 0.5).astype(np.uint8)).state


def annealing(pair: Path, count: int) -> None:
    """Median time of one annealing of `pair`'s NM3 network, both ways, alternating blocks."""
    problem = prepare(pair / "left.png", pair / "right.png").problem
    net = get_method("NM3").network(problem, Params(theta_c=5.0, lambda_c=8.3, lambda_s=7.9))
    ways = {"readable schedule": readable, "anneal()": lambda net, seed: anneal(net, rng=seed).state}
    same = all(np.array_equal(readable(net, s), ways["anneal()"](net, s)) for s in range(3))
    times = {name: [] for name in ways}
    for block in range(4):
        for name, way in ways.items():
            start = time.perf_counter()
            for seed in range(block * count, (block + 1) * count):
                way(net, seed)
            times[name].append((time.perf_counter() - start) / count)
    medians = {name: statistics.median(t) * 1e3 for name, t in times.items()}
    print(f"one annealing of the NM3 network ({net.n_neurons} neurons), median of 4 blocks of {count}: "
          + ", ".join(f"{name} {m:.3f} ms" for name, m in medians.items())
          + f"; {medians['readable schedule'] / medians['anneal()']:.2f}x; same states: {same}")


if __name__ == "__main__":
    main()
