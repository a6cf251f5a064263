"""``ismb-lab tune``: fit a method's parameters to labelled target pairs with the GA (ch. 4)."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

from ..tuning.genetic import GAConfig
from ..matching.pipeline import MatchConfig
from ..tuning.cases import Case
from ..matching.recipe import Recipe, save_recipe
from ..network.solvers import DEFAULT_SOLVER
from ..tuning import fitness
from ._common import (DEFAULT_METHOD, UsageError, add_feature_options, seed, add_ga_options, add_method_option,
                      add_solver_option, add_solver_settings, default_of, ga_config, match_config, progress_bar,
                      with_settings)
from ._guard import (Files, add_force_option, deferred_signals, interrupted, interrupted_line, is_interruption,
                     output_path)

__all__ = ["add_parser", "run", "why_negative"]

#: The defaults of :func:`ismb_lab.tuning.fitness.tune`.
GA_SEED, FIT_SEEDS = default_of(fitness.tune, "rng"), default_of(fitness.tune, "seeds")


def add_parser(sub) -> None:
    """Add the ``tune`` command: fit a method's parameters to a pair's targets with the GA (ch. 4)."""
    t = sub.add_parser("tune", help="fit the parameters to target pairs with the GA (ch. 4)",
                       description="Fit a method's parameters to the target pairs of one image pair "
                       "with the real-coded GA, and write them for 'ismb-lab match --params-file'. "
                       "Ctrl-C (or SIGTERM, SIGHUP) stops early and still writes the best parameters "
                       "so far; if no generation had finished, its one line says nothing was saved.")
    t.add_argument("left", type=Path, help="left image file")
    t.add_argument("right", type=Path, help="right image file")
    t.add_argument("targets", type=Path, help="target pairs (JSON, as saved by the labeller)")
    add_method_option(t, DEFAULT_METHOD)
    add_ga_options(t)
    t.add_argument("--seed", type=seed, default=None, help=f"seed of the GA (default: {GA_SEED})")
    add_solver_option(t, DEFAULT_SOLVER)
    add_solver_settings(t)
    t.add_argument("--fit-seeds", type=int, default=None, metavar="N",
                   help=f"update-order seeds averaged in each GA fitness (default: {FIT_SEEDS}); more "
                   "seeds favour parameters that do not work for one visiting order only")
    t.add_argument("--one-to-one", action="store_true",
                   help="record in the params file that matching keeps at most one match per corner, the "
                   "most similar (the GA's fitness does not apply it)")
    add_feature_options(t, MatchConfig())
    t.add_argument("--out", type=output_path, default=Path("params.json"), metavar="PARAMS.json",
                   help="where to write the parameters (default: %(default)s)")
    add_force_option(t)
    t.add_argument("--no-hash-check", action="store_true",
                   help="accept targets labelled on images with other bytes (e.g. re-encoded)")
    t.set_defaults(run=run, declare_files=files, limit_defaults=limit_defaults, compiles=True)


def limit_defaults() -> dict:
    """The defaults of tune's limited options: the library's, which tune falls back to."""
    ga = GAConfig()
    return {"n_max": MatchConfig().n_max, "population": ga.population, "generations": ga.generations,
            "fit_seeds": FIT_SEEDS}


def files(args) -> Files:
    """The pair and its targets read; the parameters written."""
    return Files(inputs=(("left", args.left), ("right", args.right), ("targets", args.targets)),
                 outputs=(("--out", args.out),))


class _Fit:
    """What a run of the GA has to keep: its last generation, and whether the file is written."""

    def __init__(self, args):
        self.out, self.seed = args.out, GA_SEED if args.seed is None else args.seed
        self.recipe = Recipe(args.method or DEFAULT_METHOD, solver=with_settings(args.solver or DEFAULT_SOLVER, args),
                             fit_seeds=FIT_SEEDS if args.fit_seeds is None else args.fit_seeds,
                             one_to_one=args.one_to_one)
        self.targets, self.last, self.written = 0, None, False

    def write(self, interrupted: bool) -> Recipe:
        """Write and return the recipe with the last generation's best parameters."""
        recipe = replace(self.recipe, params=fitness.to_params(self.recipe.method, self.last.best_chromosome))
        with deferred_signals():
            save_recipe(self.out, recipe, fitness=self.last.best, generations=self.last.index, seed=self.seed,
                        targets=self.targets, interrupted=interrupted)
            self.written = True
        return recipe


def run(args) -> int:
    """Run the GA on the pair and write the best parameters; returns the exit code."""
    fit = _Fit(args)
    try:
        return _run(args, fit)
    except BaseException as exc:
        if not is_interruption(exc):
            raise
        with deferred_signals():   # a second signal cannot cut the write or the line short
            print(interrupted_line(_keep(fit)), file=sys.stderr)
        return 130


def _keep(fit: _Fit) -> str:
    """After a signal: write the best parameters so far unless written; say what was saved."""
    if fit.written:
        return f"the parameters were written to {fit.out}"
    if fit.last is None:
        return "nothing was saved: no GA generation had finished"
    try:
        fit.write(interrupted=True)
    except OSError as exc:
        return f"nothing was saved: cannot write {fit.out}: {exc.strerror or exc}"
    return (f"the best parameters so far were written to {fit.out} (fitness {fit.last.best:g} "
            f"after {fit.last.index} generations)")


def why_negative(best, score, corners: int, labelled: int) -> str | None:
    """The line that explains a negative `best` (the GA's best fitness) or `score` (the C/E/T of one
    run), with `labelled` of the `corners` left corners in a target pair; None when neither is negative."""
    if best >= 0 and score.fitness >= 0:
        return None
    c, w, e = score.correct, score.wrong_partner, score.extra
    head = f"negative fitness: fitness = correct - wrong - extra ({c} - {w} - {e} = {c - w - e} in the C/E/T above); "
    if not e:
        return head + "more labelled corners got a wrong partner than the right one"
    return (head + f"the {e} extra are matches on left corners nobody labelled ({corners - labelled} of the "
            f"{corners} left corners have no target pair): label more corners, or judge by C/T")


def _run(args, fit: _Fit) -> int:
    ga, recipe = ga_config(args), fit.recipe
    method, solver = recipe.method.name, recipe.solver.name
    case = Case.from_files(args.left, args.right, args.targets, match_config(args),
                           check_hash=not args.no_hash_check)
    if len(case.left_out):
        print(f"ismb-lab: note: {len(case.left_out)} targets have no corner within 1.5 px and are "
              f"left out: {', '.join(f'#{n + 1}' for n in case.left_out)}", file=sys.stderr)
    if len(case.targets) == 0:
        raise UsageError(f"{args.targets}: no target pair lies on the corners found "
                         f"({len(case.left_out)} targets, {len(case.prepared.problem.left_xy)} left corners)")
    fit.targets = len(case.targets)
    records = fitness.tune([case], recipe.method, rng=fit.seed, ga=ga, solver=recipe.solver, seeds=recipe.fit_seeds)
    with progress_bar(ga.generations + 1, f"Method-{method} GA") as bar:
        for fit.last in records:
            bar.update(1)
            bar.set_postfix(best=f"{fit.last.best:g}", mean=f"{fit.last.mean:.2f}", target=fit.targets)
    recipe, best = fit.write(interrupted=False), fit.last
    params = recipe.params
    if interrupted():   # a signal came during the write, which finished first
        raise KeyboardInterrupt
    result = fitness.evaluate([case], recipe.method, params, solver=recipe.solver, one_to_one=recipe.one_to_one)
    after = ", one match per corner" if recipe.one_to_one else ""
    print(f"Method-{method} ({solver}{after}): best fitness {best.best:g} of {fit.targets} after "
          f"{best.index} generations; C/E/T {result}; parameters {params.to_dict()}")
    why = why_negative(best.best, result, len(case.prepared.problem.left_xy),
                       len(set(case.targets[:, 0].tolist())))
    if why:
        print(why)
    print(f"written to {args.out}")
    return 0
