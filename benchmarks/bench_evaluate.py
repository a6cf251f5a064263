"""The train/test protocol on one process and on several: wall time and speed-up.

    python benchmarks/bench_evaluate.py [--generations 60] [--seeds 3] [--repeats 3] [--jobs 1 2]
    python benchmarks/bench_evaluate.py --smoke

Runs ``ismb_lab.tuning.cases.protocol`` over ``images/realistic/manifest.json`` (Method-III,
every pair fitted, as ``ismb-lab evaluate`` does) with each ``--jobs`` value, checks
that every run gives the same report, and prints the median wall time, its spread and
the speed-up over the first ``--jobs`` value.  The corners are found once, outside the
timing.  ``--smoke`` runs two pairs and two generations, to check that the script works.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

from ismb_lab.tuning.cases import load_manifest, protocol

MANIFEST = Path(__file__).resolve().parents[1] / "images" / "realistic" / "manifest.json"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--generations", type=int, default=60)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--jobs", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--smoke", action="store_true", help="two pairs, two generations, one repeat")
    args = parser.parse_args(argv)
    cases = load_manifest(MANIFEST)
    if args.smoke:
        cases, args.generations, args.seeds, args.repeats = cases[:2], 2, 1, 1
    print(f"{len(cases)} pairs, {args.generations} generations, {args.seeds} update-order seeds; "
          f"{len(os.sched_getaffinity(0))} cores; load average {os.getloadavg()[0]:.2f}")
    reports, medians = {}, {}
    for jobs in args.jobs:
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            reports[jobs] = protocol(cases, "III", generations=args.generations, seeds=args.seeds, jobs=jobs)
            times.append(time.perf_counter() - start)
        medians[jobs] = statistics.median(times)
        print(f"jobs {jobs}: median {medians[jobs]:.2f} s (min {min(times):.2f}, max {max(times):.2f}, "
              f"{len(times)} runs)  speed-up {medians[args.jobs[0]] / medians[jobs]:.2f}x")
    first = reports[args.jobs[0]]
    same = all(r == first for r in reports.values())
    print(f"identical reports for every jobs value: {same}")
    if not same:
        raise SystemExit("the reports differ between jobs values")


if __name__ == "__main__":
    main()
