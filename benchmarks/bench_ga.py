"""Time a full 30 x 500 GA (the thesis' settings) on one centre-ROI pair.

Two pairs: the synthetic scene's centre ROI (labelled targets), and Middlebury
Motorcycle's centre ROI with 20 corners per image (targets from its ground-truth
disparity), the pair of issue #18's GA figure.  The target stop is disabled so all 500
generations run.  Prints the wall time, the time per generation, the number of
fitness evaluations (network runs) and the time per evaluation.

    python benchmarks/bench_ga.py
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from ismb_lab.images.datasets import ground_truth_pairs, motorcycle
from ismb_lab.tuning.genetic import evolve
from ismb_lab.matching.pipeline import MatchConfig, prepare
from ismb_lab.tuning.cases import Case
from ismb_lab.scenes import synthetic_scene
from ismb_lab.tuning.fitness import Fitness, gene_bounds


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--generations", type=int, default=500)
    parser.add_argument("--smoke", action="store_true", help="one repeat of 3 generations")
    args = parser.parse_args(argv)
    repeats, generations = (1, 3) if args.smoke else (args.repeats, args.generations)
    for name, case in cases():
        problem = case.prepared.problem
        print(f"{name}: {len(problem.left_xy)}x{len(problem.right_xy)} corners, "
              f"{problem.n_neurons} candidate neurons, {len(case.targets)} targets")
        for method in ("I", "III"):
            fitness = Fitness([case], method)
            fitness(np.array([gene_bounds(method).low]))  # compile outside the timing
            times, evaluations = [], 0
            for seed in range(repeats):
                start = time.perf_counter()
                for record in evolve(fitness, gene_bounds(method), rng=seed, population=30,
                                     generations=generations):
                    evaluations = record.evaluations
                times.append(time.perf_counter() - start)
            wall = statistics.median(times)
            print(f"  Method-{method}: 30 x {generations} GA median {wall:.2f} s over {repeats} seeds "
                  f"({min(times):.2f}-{max(times):.2f}), {wall / generations * 1e3:.2f} ms per generation, "
                  f"{evaluations} network runs, {wall / evaluations * 1e6:.1f} us per run")


def cases():
    yield "synthetic centre ROI", Case.from_scene(synthetic_scene(seed=100))
    bike = motorcycle()
    prepared = prepare(bike.left, bike.right, MatchConfig(n_min=20, n_max=20))
    targets, unknown = ground_truth_pairs(bike.disparity, prepared.problem.left_xy, prepared.problem.right_xy)
    yield "Motorcycle centre ROI", Case(prepared, targets, unknown, "motorcycle")


if __name__ == "__main__":
    main()
