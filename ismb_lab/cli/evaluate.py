"""``ismb-lab evaluate``: the train/test protocol of Fig. 5.10 over a manifest's pairs."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from .._core.files import atomic_write_text
from ..tuning.cases import format_protocol, load_manifest, protocol
from ..tuning.genetic import GAConfig
from ..network.solvers import DEFAULT_SOLVER, SOLVERS
from ._common import (DEFAULT_METHOD, BestSoFar, UsageError, add_ga_options, add_method_option, given, seed,
                      add_one_to_one_option, add_solver_option, default_of, ga_config, progress_bar, said_changes)
from ._guard import (LIMITS, Files, add_force_option, deferred_signals, interrupted, interrupted_line,
                     is_interruption, json_text, limit, output_path)

__all__ = ["add_parser", "run"]

#: The protocol's own defaults, which the options fall back to.
DEFAULTS = {name: default_of(protocol, name) for name in ("train", "seeds", "fit_seeds", "rng")}


def add_parser(sub) -> None:
    """Add the ``evaluate`` command: the train/test protocol of Fig. 5.10 over a manifest's pairs."""
    e = sub.add_parser("evaluate", help="train on one pair, test on the others (Fig. 5.10)",
                       description="Run the thesis' train/test protocol over the pairs of a "
                       "manifest, with every network figure over several update-order seeds.")
    e.add_argument("manifest", type=Path, help='JSON: {"pairs": [{"left", "right", "targets", '
                   '"roi", "shift"} or {"source": "middlebury-motorcycle", "roi"}, ...]}')
    add_method_option(e, DEFAULT_METHOD)
    e.add_argument("--train", type=int, default=None, metavar="INDEX",
                   help="the pair whose GA parameters are tested on the others "
                   f"(default: {DEFAULTS['train']})")
    e.add_argument("--seeds", type=int, default=None,
                   help=f"update-order seeds per figure (default: {DEFAULTS['seeds']})")
    add_ga_options(e)
    e.add_argument("--peers", action="store_true", help="also score the peer matchers")
    e.add_argument("--recipe", type=Path, default=None, metavar="P.json",
                   help="take the method, the solver with its options, the fit seeds and one-to-one from a "
                   "params file of 'ismb-lab tune' (its parameters are fitted again under the protocol); "
                   "the options given here replace single fields")
    add_one_to_one_option(e, "score the network's matches after keeping at most one per corner (the most similar)")
    add_solver_option(e, f"the recipe's, else {DEFAULT_SOLVER}")
    e.add_argument("--solvers", nargs="*", choices=tuple(SOLVERS), default=(),
                   help="also solve the tested energies these other ways")
    e.add_argument("--fit-solver", choices=tuple(SOLVERS), default=None,
                   help=f"how the GA solves each network while fitting (default: the recipe's solver, else "
                   f"{DEFAULT_SOLVER})")
    e.add_argument("--fit-seeds", type=int, default=None, metavar="N",
                   help=f"update-order seeds averaged in each GA fitness (default: {DEFAULTS['fit_seeds']})")
    e.add_argument("--ga-seed", type=seed, default=None, metavar="N",
                   help=f"seed of the GA (default: {DEFAULTS['rng']}); a small training pair can "
                   "leave the GA on a plateau, so compare a few")
    e.add_argument("--held-out-only", action="store_true",
                   help="fit only the training pair (the held-out figures are the same; the other "
                   "rows' 'Training' column is skipped)")
    e.add_argument("--jobs", type=int, default=None, metavar="N",
                   help=f"worker processes for the GA fits and the scores; the report is the same for "
                   f"every N (default: all cores, {available_cores()} here); the workers end with "
                   "the command, however it ends")
    e.add_argument("--json", type=output_path, default=None, metavar="OUT",
                   help="write the report as JSON; when a signal stops the run, OUT gets the best "
                   "parameters so far, marked \"interrupted\": true (with --jobs above 1, of the last "
                   "fit that finished), or nothing, as the one line on stderr says")
    add_force_option(e)
    e.set_defaults(run=run, declare_files=files, limit_defaults=limit_defaults, compiles=True)


def limit_defaults() -> dict:
    """The defaults of evaluate's limited options: the protocol's, which evaluate falls back to."""
    ga = GAConfig()
    return {"population": ga.population, "generations": ga.generations, "seeds": DEFAULTS["seeds"],
            "fit_seeds": DEFAULTS["fit_seeds"], "jobs": available_cores()}


def files(args) -> Files:
    """The manifest and the recipe read, with every file the manifest names; the report written."""
    from ..tuning.cases import manifest_files

    return Files(inputs=(("manifest", args.manifest),) + given(("--recipe", args.recipe)),
                 reads=tuple(manifest_files(args.manifest)), outputs=given(("--json", args.json)))


def available_cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def run(args) -> int:
    """Run :func:`~ismb_lab.tuning.cases.protocol` on the manifest and print its report;
    returns the exit code."""
    jobs = available_cores() if args.jobs is None else args.jobs
    if jobs < 1:
        raise UsageError(f"--jobs must be an integer >= 1, got {jobs}")
    recipe = given_recipe(args)
    best, reported = BestSoFar(recipe), []
    try:
        return _run(args, jobs, best, reported, recipe)
    except BaseException as exc:
        if not is_interruption(exc):
            raise
        with deferred_signals():   # a second signal cannot cut the write or the line short
            return _stopped(best, args.json, "fit" if jobs > 1 else "generation", reported)


def _stopped(best, path, unit: str, reported) -> int:
    """After a signal: say that the report is out, or write the best parameters so far, or say
    that nothing was written."""
    where = f" to {path}" if path is not None else ""
    if reported:
        print(interrupted_line(f"the report is complete{' and written' + where if where else ''}"),
              file=sys.stderr)
    elif best.record is None:
        print(interrupted_line(f"nothing was written{where}: no GA {unit} had finished"), file=sys.stderr)
    else:
        return best.save(path)
    return 130


def given_recipe(args):
    """The method, solver, fit seeds and one-to-one of --recipe (if any), replaced by the options given."""
    from dataclasses import replace

    from .._core.files import check_input
    from ..matching.recipe import Recipe, load_recipe
    from ..network.solvers import get_solver

    if args.recipe is None:
        base = Recipe(args.method or DEFAULT_METHOD, fit_seeds=DEFAULTS["fit_seeds"])
    else:
        base = load_recipe(check_input(args.recipe, what="--recipe"), method=args.method).recipe
        if args.method and base.method.name != args.method:
            raise UsageError(f"--method {args.method} conflicts with --recipe, which holds Method-{base.method.name}")
    solver = base.solver if args.solver is None or args.solver == base.solver.name else get_solver(args.solver)
    recipe = replace(base, solver=solver, fit_seeds=base.fit_seeds if args.fit_seeds is None else args.fit_seeds,
                     one_to_one=base.one_to_one if args.one_to_one is None else args.one_to_one)
    if args.recipe is not None:
        most = limit("fit_seeds")   # a file is held to the limit an option is held to
        if args.fit_seeds is None and base.fit_seeds > most:
            variable = LIMITS["fit_seeds"][0]
            raise UsageError(f"--recipe {str(args.recipe)!r}: fit_seeds {base.fit_seeds} is above the limit of {most} "
                             f"seeds; set {variable}={base.fit_seeds} to allow it, or give --fit-seeds")
        said_changes(args.recipe, base, recipe)
    return recipe


def _run(args, jobs: int, best, reported: list, recipe) -> int:
    ga = ga_config(args)
    cases = load_manifest(args.manifest)
    bars = {}

    def progress(name, record):
        best(name, record)
        if jobs > 1:   # one update per finished fit
            if not bars:
                fits = len(cases) if not args.held_out_only else 1
                bars["fits"] = progress_bar(fits, f"GA fits on {jobs} processes", unit="fit")
            bars["fits"].update(1)
            bars["fits"].set_postfix(last=name, best=f"{record.best:g}")
            return
        if name not in bars:
            for bar in bars.values():
                bar.close()
            bars[name] = progress_bar(ga.generations + 1, f"GA on {name}")
        bars[name].update(1)
        bars[name].set_postfix(best=f"{record.best:g}", mean=f"{record.mean:.2f}")

    given = {k: v for k, v in (("train", args.train), ("seeds", args.seeds), ("rng", args.ga_seed))
             if v is not None}
    fit_solver = recipe.solver if args.fit_solver is None else args.fit_solver
    try:
        report = protocol(cases, recipe.method, ga=ga, peers=args.peers, progress=progress,
                          solvers=tuple(args.solvers), fit_all=not args.held_out_only, jobs=jobs,
                          solver=recipe.solver, fit_solver=fit_solver, fit_seeds=recipe.fit_seeds,
                          one_to_one=recipe.one_to_one, **given)
    finally:
        for bar in bars.values():
            bar.close()
    with deferred_signals():   # the work is done: a signal now waits for its report
        print(format_protocol(report))
        if args.json is not None:
            data = {**report.to_dict(), "ga_seed": given.get("rng", DEFAULTS["rng"])}
            atomic_write_text(args.json, json_text(data))
        reported.append(True)
    if interrupted():
        raise KeyboardInterrupt
    return 0
