"""How preparing and running the network grows with the number of corners per image.

The pair is Middlebury Motorcycle (scikit-image's copy) at 640 px wide, the full image as the
ROI, with 200, 500 and 1,000 corners per image and the candidate window centred at its own
median disparity (40 px at this size).  For each size it prints the median over repeats of:
preparing (Harris in both images, ``M``, candidates and neighbour pairs), building the
Method-III network and one run to a fixed point (a new update-order seed each time), the peak
of memory allocated during one prepare-build-run (``tracemalloc``: NumPy's buffers included)
and the process's resident size.  The last lines fit the growth exponent ``b`` of
``time = a * corners^b`` over the sizes.

    python benchmarks/bench_scale.py [--smoke]
"""

from __future__ import annotations

import argparse
import resource
import statistics
import time
import tracemalloc

import numpy as np

from ismb_lab.images.datasets import motorcycle
from ismb_lab.network.dynamics import run
from ismb_lab.matching.pipeline import MatchConfig, prepare
from ismb_lab.network.methods import THESIS_PARAMS, get_method


def timed(fn, repeats: int):
    times, out = [], None
    for r in range(repeats):
        start = time.perf_counter()
        out = fn(r)
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), max(times), out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="200 corners, one repeat")
    smoke = parser.parse_args(argv).smoke
    sizes, repeats = ((200,), 1) if smoke else ((200, 500, 1000), 7)
    data = motorcycle(width=640)
    pair = type("Pair", (), {"left": np.clip(data.left, 0, 255), "right": np.clip(data.right, 0, 255)})
    method, params = get_method("III"), THESIS_PARAMS["III"]
    prepare(pair.left, pair.right, MatchConfig(roi="full", n_min=50, n_max=50, shift=40.0))  # compile
    rows = []
    print(f"{'corners':>7} {'neurons':>7} {'pairs':>7} {'prepare ms':>17} {'build ms':>8} "
          f"{'run ms':>17} {'attempts':>8} {'peak MB':>7} {'RSS MB':>6}")
    for n in sizes:
        config = MatchConfig(roi="full", n_min=n, n_max=n, shift=40.0)
        prep_t, prep_lo, prep_hi, prepared = timed(lambda _: prepare(pair.left, pair.right, config), repeats)
        build_t, _, _, net = timed(lambda _: method.network(prepared.problem, params), repeats)
        run(net, rng=0)
        run_t, run_lo, run_hi, result = timed(lambda r: run(net, rng=1000 + r), repeats)
        tracemalloc.start()
        run(method.network(prepare(pair.left, pair.right, config).problem, params), rng=1)
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        problem = prepared.problem
        rows.append((len(problem.left_xy), prep_t, run_t))
        print(f"{len(problem.left_xy):>7} {problem.n_neurons:>7} {len(problem.pairs):>7} "
              f"{prep_t * 1e3:>6.1f} ({prep_lo * 1e3:.0f}-{prep_hi * 1e3:.0f}) {build_t * 1e3:>8.2f} "
              f"{run_t * 1e3:>6.2f} ({run_lo * 1e3:.2f}-{run_hi * 1e3:.2f}) {result.attempts:>8} "
              f"{peak:>7.1f} {rss:>6.0f}")
    if len(rows) > 1:
        corners = np.log([r[0] for r in rows])
        for name, column in (("prepare", 1), ("run", 2)):
            slope = np.polyfit(corners, np.log([r[column] for r in rows]), 1)[0]
            print(f"growth exponent of {name}: {slope:.2f}")
    print("peak MB: memory allocated during one prepare + build + run (tracemalloc); RSS MB: the "
          "process's largest resident size so far, imports included")


if __name__ == "__main__":
    main()
