"""Time one Hopfield network run: the textbook kernel against the numba kernel.

Problems are real Harris corners of the synthetic scene (seed 0): the centre-quarter
ROI with 20 and 30 corners per image, and the full image with 200.  Each figure is
the median over runs with different update-order seeds.

    python benchmarks/bench_hnn.py [--smoke]
"""

from __future__ import annotations

import argparse
import statistics
import time

from ismb_lab.dynamics import run
from ismb_lab.matching import MatchConfig, prepare
from ismb_lab.methods import THESIS_PARAMS, get_method
from ismb_lab.scenes import synthetic_scene


def median_seconds(fn, repeats: int) -> float:
    times = []
    for seed in range(repeats):
        start = time.perf_counter()
        fn(seed)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="the 20-corner problem, a few runs each")
    smoke = parser.parse_args(argv).smoke
    scale = 0.02 if smoke else 1.0
    scene = synthetic_scene(seed=0)
    method, params = get_method("III"), THESIS_PARAMS["III"]
    print(f"{'problem':>9} {'neurons':>7} {'pairs':>7} {'attempts':>8} {'textbook':>10} "
          f"{'numba':>10} {'ratio':>6} {'order kept':>10} {'build+numba':>11}")
    for n, roi in ((20, "center"),) if smoke else ((20, "center"), (30, "center"), (200, "full")):
        prepared = prepare(scene.left, scene.right, MatchConfig(roi=roi, n_min=n, n_max=n))
        problem = prepared.problem
        net = method.network(problem, params)
        run(net)  # compile outside the timing
        attempts = statistics.median(run(net, rng=s).attempts for s in range(20))
        many = max(3, int(501 * scale))
        slow = median_seconds(lambda s: run(net, rng=s, kernel="textbook"), max(3, int((7 if n > 30 else 31) * scale)))
        fast = median_seconds(lambda s: run(net, rng=s), many)        # each seed's order drawn anew
        kept = median_seconds(lambda s: run(net, rng=s), many)        # orders remembered by the topology
        full = median_seconds(lambda s: run(method.network(problem, params), rng=s), many)
        size = f"{len(problem.left_xy)}x{len(problem.right_xy)}"
        print(f"{size:>9} {problem.n_neurons:>7} {2 * len(problem.pairs):>7} {attempts:>8.0f} "
              f"{slow * 1e3:>8.2f}ms {fast * 1e6:>8.1f}us {slow / fast:>5.0f}x {kept * 1e6:>8.1f}us "
              f"{full * 1e6:>9.1f}us")
    print("pairs: non-zero compatibility weights (both directions); attempts: median per run")
    print("numba: a new seed per run, so its visiting order is drawn first; order kept: the same seeds "
          "again, their orders remembered (as in the GA, where every chromosome uses one seed); "
          "build+numba: the network built from the problem and parameters, then run with a kept order")


if __name__ == "__main__":
    main()
