"""Reproduce the Method-NM evaluation: Fig. 5.10's protocol on the Middlebury ROIs and on a
second data set, for Method-III, Method-NM and Method-NM4, with the network and annealed
solvers (and the exact one with --exact) and the peer matchers.

    python scripts/evaluate_no_match.py [--generations 50] [--seeds 5] [--quick] [--exact]

The GA (seed 0) fits on pair 0 of each data set only; every other pair is held out.
The second data set is images/realistic/manifest.json when it exists, else eight synthetic
scenes (ismb_lab.scenes, seeds 100-107) with exact ground truth as a stand-in.
"""

import argparse
import time
from pathlib import Path

from ismb_lab.tuning.evaluation import Score
from ismb_lab.tuning.cases import Case, Spread, format_protocol, load_manifest, protocol
from ismb_lab.scenes import synthetic_scene

ROOT = Path(__file__).resolve().parents[1]


def synthetic_cases(seeds=range(100, 108)):
    cases = []
    for s in seeds:
        cases.append(Case.from_scene(synthetic_scene(seed=s), name=f"synthetic {s}"))
    return cases


def pooled(scores):
    return (f"{scores[0]}  C/T {Spread.of([s.recall for s in scores])}  "
            f"precision {Spread.of([s.precision for s in scores])}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--generations", type=int, default=50)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="Middlebury only")
    parser.add_argument("--exact", action="store_true", help="also the exact MILP minimum (slow)")
    args = parser.parse_args()
    realistic = ROOT / "images" / "realistic" / "manifest.json"
    sets = [("middlebury", load_manifest(ROOT / "manifests" / "middlebury.json"))]
    if not args.quick:
        sets.append(("realistic", load_manifest(realistic)) if realistic.is_file()
                    else ("synthetic stand-in", synthetic_cases()))
    runs = [("III", "network"), ("NM", "network"), ("NM", "anneal"), ("NM4", "network"), ("NM4", "anneal")]
    solvers = ("anneal", "exact") if args.exact else ("anneal",)
    totals = {}
    for name, cases in sets:
        for method, fit_solver in runs:
            t = time.perf_counter()
            report = protocol(cases, method, train=0, seeds=args.seeds, generations=args.generations,
                              peers=(method, fit_solver) == ("III", "network"), solvers=solvers,
                              fit_solver=fit_solver, fit_all=False)
            print(f"\n=== {name}: Method-{method}, GA fitness solved by '{fit_solver}' "
                  f"({time.perf_counter() - t:.0f} s)")
            print(format_protocol(report))
            key = f"Method-{method} (fit: {fit_solver})"
            totals.setdefault(key + " / network", []).append(report.held_out)
            for solver, variant in report.solvers.items():
                totals.setdefault(f"{key} / {solver}", []).append(variant.held_out)
            for peer, result in report.peers.items():
                totals.setdefault(f"peer {peer}", []).append([result.held_out])
    print(f"\n=== pooled over {len(sets)} data set(s) (held-out pairs only)")
    for key, parts in totals.items():
        n = min(len(p) for p in parts)
        print(f"{key:45s} " + pooled([sum((p[s] for p in parts), Score(0, 0, 0, 0)) for s in range(n)]))


if __name__ == "__main__":
    main()
