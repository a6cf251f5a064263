"""Time one Hopfield network run: the textbook kernel against the numba kernel.

Problems are real Harris corners: Middlebury Motorcycle's centre ROI and the synthetic
scene's with 20 corners per image, and a full 320 x 240 rendered indoor pair
(images/realistic/01) with 200.  Each figure is the median over runs with different
update-order seeds, with the 10th and 90th percentiles.

    python benchmarks/bench_hnn.py [--smoke]
"""

from __future__ import annotations

import argparse
import statistics
import time

from pathlib import Path

from ismb_lab.images.datasets import motorcycle
from ismb_lab.network.dynamics import run
from ismb_lab.matching.pipeline import MatchConfig, prepare
from ismb_lab.network.methods import THESIS_PARAMS, get_method
from ismb_lab.scenes import synthetic_scene

REALISTIC = Path(__file__).resolve().parents[1] / "images" / "realistic" / "01"


def seconds(fn, repeats: int) -> list:
    times = []
    for seed in range(repeats):
        start = time.perf_counter()
        fn(seed)
        times.append(time.perf_counter() - start)
    return times


def spread(times) -> str:
    q = statistics.quantiles(times, n=10) if len(times) > 2 else [min(times)] * 9
    return f"{statistics.median(times) * 1e6:8.1f}us ({q[0] * 1e6:.1f}-{q[-1] * 1e6:.1f})"


def problems(smoke: bool):
    """(name, Problem) of the figures in issue #18: a 20-corner ROI of Middlebury Motorcycle,
    the synthetic scene's centre ROI, and 200 corners of a full 320 x 240 pair."""
    bike = motorcycle()
    yield "Motorcycle centre ROI", prepare(bike.left, bike.right,
                                           MatchConfig(n_min=20, n_max=20)).problem
    if smoke:
        return
    scene = synthetic_scene(seed=0)
    yield "synthetic centre ROI", prepare(scene.left, scene.right, MatchConfig(n_min=20, n_max=20)).problem
    yield "realistic 01, full", prepare(REALISTIC / "left.png", REALISTIC / "right.png",
                                        MatchConfig(roi="full", n_min=200, n_max=200)).problem


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="the 20-corner problem, a few runs each")
    smoke = parser.parse_args(argv).smoke
    scale = 0.02 if smoke else 1.0
    method, params = get_method("III"), THESIS_PARAMS["III"]
    print(f"{'problem':>22} {'corners':>7} {'neurons':>7} {'pairs':>7} {'attempts':>8} {'textbook':>10} "
          f"{'numba, median (p10-p90)':>27} {'per attempt':>11} {'ratio':>6} {'+energy':>9} {'build+numba':>11}")
    for name, problem in problems(smoke):
        net = method.network(problem, params)
        run(net)  # compile outside the timing
        attempts = statistics.median(run(net, rng=s).attempts for s in range(20))
        many = max(3, int(2001 * scale))
        slow = statistics.median(seconds(lambda s: run(net, rng=s, kernel="textbook"),
                                         max(3, int((7 if problem.n_neurons > 300 else 31) * scale))))
        fast = seconds(lambda s: run(net, rng=10_000 + s), many)      # a new seed every run
        with_energy = statistics.median(seconds(lambda s: run(net, rng=20_000 + s).energy, many))
        full = statistics.median(seconds(lambda s: run(method.network(problem, params), rng=s), many))
        size = f"{len(problem.left_xy)}x{len(problem.right_xy)}"
        median = statistics.median(fast)
        print(f"{name:>22} {size:>7} {problem.n_neurons:>7} {2 * len(problem.pairs):>7} {attempts:>8.0f} "
              f"{slow * 1e3:>8.2f}ms {spread(fast):>27} {median / attempts * 1e9:>9.1f}ns "
              f"{slow / median:>5.0f}x {with_energy * 1e6:>7.1f}us {full * 1e6:>9.1f}us")
    print("pairs: non-zero compatibility weights (both directions); attempts: median per run; "
          "numba: a new update-order seed every run; +energy: the same with the final energy read "
          "(RunResult.energy is computed when first read); build+numba: the network built from the "
          "problem and parameters, then run")


if __name__ == "__main__":
    main()
