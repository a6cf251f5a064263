"""``ismb-lab tune``: fit a method's parameters to labelled target pairs with the GA (ch. 4)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from .._files import atomic_write_text
from ..methods import METHOD_NAMES
from ._common import UsageError, add_feature_options, match_config, progress_bar


def add_parser(sub) -> None:
    t = sub.add_parser("tune", help="fit the parameters to target pairs with the GA (ch. 4)",
                       description="Fit a method's parameters to the target pairs of one image pair "
                       "with the real-coded GA, and write them for 'ismb-lab match --params-file'. "
                       "Ctrl-C stops early and still writes the best parameters so far.")
    t.add_argument("left", type=Path, help="left image file")
    t.add_argument("right", type=Path, help="right image file")
    t.add_argument("targets", type=Path, help="target pairs (JSON, as saved by the labeller)")
    t.add_argument("--method", choices=METHOD_NAMES, default="III", help="energy recipe (default: III)")
    t.add_argument("--generations", type=int, default=500, help="most generations (default: 500)")
    t.add_argument("--population", type=int, default=30, help="chromosomes (default: 30)")
    t.add_argument("--seed", type=int, default=0, help="seed of the GA (default: 0)")
    add_feature_options(t)
    t.add_argument("--out", type=Path, default=Path("params.json"), metavar="PARAMS.json",
                   help="where to write the parameters (default: params.json)")
    t.set_defaults(run=run)


def run(args) -> int:
    from ..matching import prepare
    from ..targets import load_targets, snap
    from ..tuning import Case, evaluate, to_params, tune

    prepared = prepare(args.left, args.right, match_config(args))
    targets = load_targets(args.targets, pair=prepared.pair, check_hash=not args.no_hash_check)
    snapped = snap(targets, prepared.problem.left_xy, prepared.problem.right_xy)
    missing = sorted(set(snapped.missing_left.tolist()) | set(snapped.missing_right.tolist()))
    if missing:
        print(f"ismb-lab: note: {len(missing)} of {len(targets)} targets have no corner within "
              f"1.5 px and are left out: {', '.join(f'#{n + 1}' for n in missing)}", file=sys.stderr)
    if len(snapped.pairs) == 0:
        raise UsageError(f"{args.targets}: no target pair lies on the corners found "
                         f"({len(targets)} targets, {len(prepared.problem.left_xy)} left corners)")
    case = Case(prepared, snapped.pairs, name=str(args.left))
    records = tune([case], args.method, rng=args.seed, population=args.population,
                   generations=args.generations)
    best, interrupted = None, False
    with progress_bar(args.generations + 1, f"Method-{args.method} GA") as bar:
        try:
            for best in records:
                bar.update(1)
                bar.set_postfix(best=f"{best.best:g}", mean=f"{best.mean:.2f}", target=len(case.targets))
        except KeyboardInterrupt:
            interrupted = True
    if best is None:
        raise KeyboardInterrupt
    params = to_params(args.method, best.best_chromosome)
    out = {"method": args.method, "params": params.to_dict(), "fitness": best.best,
           "generations": best.index, "seed": args.seed, "targets": len(case.targets),
           "interrupted": interrupted}
    atomic_write_text(args.out, json.dumps(out, indent=2) + "\n")
    result = evaluate([case], args.method, params)
    print(f"Method-{args.method}: best fitness {best.best:g} of {len(case.targets)} after "
          f"{best.index} generations; C/E/T {result}; parameters {params.to_dict()}")
    print(f"written to {args.out}")
    if interrupted:
        print("ismb-lab: interrupted; the best parameters so far were written", file=sys.stderr)
        return 130
    return 0
