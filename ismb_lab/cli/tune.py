"""``ismb-lab tune``: fit a method's parameters to labelled target pairs with the GA (ch. 4)."""

from __future__ import annotations

import sys
from pathlib import Path

from ..matching import MatchConfig
from ..methods import save_params
from ..protocol import Case
from ..solvers import DEFAULT_SOLVER
from .. import tuning
from ._common import (DEFAULT_METHOD, UsageError, add_feature_options, add_ga_options, add_method_option,
                      add_solver_option, default_of, ga_config, match_config, progress_bar)

__all__ = ["add_parser", "run"]

#: The GA seed and the fitness's update-order seeds that :func:`ismb_lab.tuning.tune` uses by default.
GA_SEED, FIT_SEEDS = default_of(tuning.tune, "rng"), default_of(tuning.tune, "seeds")


def add_parser(sub) -> None:
    t = sub.add_parser("tune", help="fit the parameters to target pairs with the GA (ch. 4)",
                       description="Fit a method's parameters to the target pairs of one image pair "
                       "with the real-coded GA, and write them for 'ismb-lab match --params-file'. "
                       "Ctrl-C stops early and still writes the best parameters so far.")
    t.add_argument("left", type=Path, help="left image file")
    t.add_argument("right", type=Path, help="right image file")
    t.add_argument("targets", type=Path, help="target pairs (JSON, as saved by the labeller)")
    add_method_option(t, DEFAULT_METHOD)
    add_ga_options(t)
    t.add_argument("--seed", type=int, default=None, help=f"seed of the GA (default: {GA_SEED})")
    add_solver_option(t, DEFAULT_SOLVER)
    t.add_argument("--fit-seeds", type=int, default=None, metavar="N",
                   help=f"update-order seeds averaged in each GA fitness (default: {FIT_SEEDS}); more "
                   "seeds favour parameters that do not work for one visiting order only")
    add_feature_options(t, MatchConfig())
    t.add_argument("--out", type=Path, default=Path("params.json"), metavar="PARAMS.json",
                   help="where to write the parameters (default: %(default)s)")
    t.set_defaults(run=run)


def run(args) -> int:
    method, solver, ga = args.method or DEFAULT_METHOD, args.solver or DEFAULT_SOLVER, ga_config(args)
    seed = GA_SEED if args.seed is None else args.seed
    fit_seeds = FIT_SEEDS if args.fit_seeds is None else args.fit_seeds
    case = Case.from_files(args.left, args.right, args.targets, match_config(args),
                           check_hash=not args.no_hash_check)
    if len(case.left_out):
        print(f"ismb-lab: note: {len(case.left_out)} targets have no corner within 1.5 px and are "
              f"left out: {', '.join(f'#{n + 1}' for n in case.left_out)}", file=sys.stderr)
    if len(case.targets) == 0:
        raise UsageError(f"{args.targets}: no target pair lies on the corners found "
                         f"({len(case.left_out)} targets, {len(case.prepared.problem.left_xy)} left corners)")
    records = tuning.tune([case], method, rng=seed, ga=ga, solver=solver, seeds=fit_seeds)
    best, interrupted = None, False
    with progress_bar(ga.generations + 1, f"Method-{method} GA") as bar:
        try:
            for best in records:
                bar.update(1)
                bar.set_postfix(best=f"{best.best:g}", mean=f"{best.mean:.2f}", target=len(case.targets))
        except KeyboardInterrupt:
            interrupted = True
    if best is None:
        raise KeyboardInterrupt
    params = tuning.to_params(method, best.best_chromosome)
    save_params(args.out, method, params, solver=solver, fitness=best.best, generations=best.index,
                seed=seed, fit_seeds=fit_seeds, targets=len(case.targets), interrupted=interrupted)
    result = tuning.evaluate([case], method, params, solver=solver)
    print(f"Method-{method} ({solver}): best fitness {best.best:g} of {len(case.targets)} after "
          f"{best.index} generations; C/E/T {result}; parameters {params.to_dict()}")
    print(f"written to {args.out}")
    if interrupted:
        print("ismb-lab: interrupted; the best parameters so far were written", file=sys.stderr)
        return 130
    return 0
