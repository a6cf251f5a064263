"""Pieces the ``ismb-lab`` commands share: the one-line error, option groups, the recipe.

An option left out means the library's default: options default to None, and their help shows it.
"""

from __future__ import annotations

import argparse
import inspect
import sys
from dataclasses import replace
from pathlib import Path

from .._core.files import check_input
from .._core.validation import ParameterError, ParameterTypeError
from ..tuning.genetic import GAConfig
from ..network.hopfield import RULES
from ..network.dynamics import STOP_RULES
from ..matching.pipeline import MatchConfig, match
from ..network.methods import DEFAULT_METHOD, all_genes, get_method, method_names
from ..network.solvers import SOLVERS, NetworkSolver
from ._guard import Files, UsageError, _short, interrupted

__all__ = ["ParameterError", "ParameterTypeError", "Parser", "UsageError", "add_ga_options", "given",
           "add_matching_options", "add_feature_options", "window_record", "add_solver_option",
           "add_solver_settings", "ga_config", "solver_settings", "with_settings",
           "match_config", "progress_bar", "resolve_recipe"]

FEATURE_OPTIONS = ("roi", "shift", "n_min", "n_max")


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line instead of argparse's usage dump
        raise UsageError(f"{message} (see '{self.prog} --help')")


def default_of(function, name: str):
    """The default of one of `function`'s keyword arguments: the one place it is declared."""
    return inspect.signature(function).parameters[name].default


def add_method_option(p: argparse.ArgumentParser, default_text: str) -> None:
    p.add_argument("--method", choices=method_names(), default=None,
                   help=f"energy recipe (default: {default_text})")


def add_matching_options(p: argparse.ArgumentParser, base: MatchConfig) -> None:
    add_method_option(p, f"the params file's, else {DEFAULT_METHOD}")
    for gene in all_genes():
        p.add_argument("--" + gene.name.replace("_", "-"), type=float, default=None, metavar="X",
                       help=f"{gene.meaning} (default: the method's)")
    p.add_argument("--params-file", type=Path, default=None, metavar="P.json",
                   help="the recipe that 'ismb-lab tune' writes: method, parameters, solver with its options "
                   "and one-to-one, used as it is; the options given here replace single fields")
    add_feature_options(p, base)
    p.add_argument("--seed", type=seed, default=None,
                   help=f"seed of the update order, 0 to 2**63 - 1 (default: {default_of(match, 'seed')})")
    p.add_argument("--stop-rule", choices=STOP_RULES, default=None,
                   help="sweep: a full sweep without change; stall: 200 idle attempts "
                   f"(default: {NetworkSolver().stop_rule})")
    p.add_argument("--rule", choices=RULES, default=None,
                   help="exact Hopfield weights, or the thesis' literal (3-17)/(3-20) "
                   f"(default: {NetworkSolver().rule})")
    add_one_to_one_option(p, "keep at most one match per corner after solving, the most similar (smallest M)")


def add_one_to_one_option(p: argparse.ArgumentParser, text: str) -> None:
    p.add_argument("--one-to-one", action=argparse.BooleanOptionalAction, default=None,
                   help=f"{text} (default: the params file's, else off)")


def add_solver_option(p: argparse.ArgumentParser, default: str) -> None:
    text = "; ".join(f"{s.name}: {s.description}" for s in SOLVERS.values())
    p.add_argument("--solver", choices=tuple(SOLVERS), default=None,
                   help=f"how the energy is minimised ({text}) (default: {default})")


def add_solver_settings(p: argparse.ArgumentParser) -> None:
    """``--solver-option NAME=VALUE``: one of the solver's own options (repeatable)."""
    own = "; ".join(f"{s.name}: {', '.join(s.options()) or 'none'}" for s in SOLVERS.values())
    p.add_argument("--solver-option", action="append", default=None, metavar="NAME=VALUE",
                   help=f"an option of the solver, e.g. cooling=0.8 for anneal; repeat it for more ({own}) "
                   "(default: the params file's, else the solver's own)")


def solver_settings(args) -> dict:
    """The ``--solver-option`` values by name, numbers read as numbers.

    >>> solver_settings(argparse.Namespace(solver_option=["cooling=0.8", "sweeps=1", "rule=thesis"]))
    {'cooling': 0.8, 'sweeps': 1, 'rule': 'thesis'}
    """
    settings = {}
    for text in getattr(args, "solver_option", None) or ():
        name, equals, value = text.partition("=")
        if not equals or not name.strip():
            raise UsageError(f"--solver-option takes NAME=VALUE (e.g. cooling=0.8), not {text!r}")
        value = value.strip()
        for kind in (int, float):
            try:
                value = kind(value)
                break
            except ValueError:
                pass
        settings[name.strip()] = value
    return settings


def window_record(config: MatchConfig, auto: bool) -> dict:
    """The candidate window a command used, for its JSON (``auto``: measured with ``--shift auto``)."""
    return {"shift": float(config.shift), "width": float(config.window_width),
            "height": float(config.window_height), "auto": bool(auto)}


def seed(text: str) -> int:
    """An argparse type: a seed from 0 to 2**63 - 1.

    >>> seed("7")
    7
    """
    from .._core.validation import MAX_SEED

    text = text.strip()
    value = int(text) if text.isascii() and text.isdigit() and len(text) <= len(str(MAX_SEED)) else -1
    if not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"a seed is a whole number from 0 to {MAX_SEED} (2**63 - 1), "
                                         f"not {_short(text)!r}")
    return value


def _shift(text: str):
    if text == "auto":
        return text
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a number of pixels or 'auto', not {text!r}") from None


def add_feature_options(p: argparse.ArgumentParser, base: MatchConfig) -> None:
    roi = base.roi if isinstance(base.roi, str) else ",".join(map(str, base.roi))
    p.add_argument("--roi", default=None, help=f"center | full | X,Y,W,H (default: {roi})")
    p.add_argument("--shift", type=_shift, default=None, metavar="PX|auto",
                   help="expected disparity: centre of the candidate window; 'auto' measures it on the "
                   "pair (robust matches) and widens the window to hold their range "
                   f"(default: {base.shift:g})")
    p.add_argument("--n-min", type=int, default=None, help=f"fewest corners per image (default: {base.n_min})")
    p.add_argument("--n-max", type=int, default=None, help=f"most corners per image (default: {base.n_max})")


def add_ga_options(p: argparse.ArgumentParser) -> None:
    ga = GAConfig()
    p.add_argument("--generations", type=int, default=None,
                   help=f"most GA generations (default: {ga.generations})")
    p.add_argument("--population", type=int, default=None,
                   help=f"chromosomes per generation (default: {ga.population})")


def ga_config(args) -> GAConfig:
    return GAConfig().updated("ismb-lab", generations=args.generations,
                              population=getattr(args, "population", None))


def match_config(args, base: MatchConfig | None = None) -> MatchConfig:
    """`base` (default: :class:`MatchConfig`'s defaults) with the feature options given."""
    base = MatchConfig() if base is None else base
    return replace(base, **{k: getattr(args, k) for k in FEATURE_OPTIONS if getattr(args, k) is not None})


def resolve_recipe(args, solver: str, defaults=None):
    """The recipe from --params-file, replaced field by field by the options given.

    `solver` is the command's solver when the file names none (or there is no file); `defaults`
    (method name -> Params) replaces a method's own defaults when no file is given.  What the
    options change in the file's recipe is said on stderr.
    """
    from ..matching.recipe import Recipe, load_recipe

    loaded = None
    if args.params_file is not None:
        loaded = load_recipe(check_input(args.params_file, what="--params-file"), method=args.method,
                             solver=solver, before=solver)
        if args.method and loaded.recipe.method.name != args.method:
            raise UsageError(f"--method {args.method} conflicts with --params-file, "
                             f"which holds parameters for Method-{loaded.recipe.method.name}")
        if loaded.note:
            note(loaded.note)
        base = loaded.recipe
    else:
        method = args.method or DEFAULT_METHOD
        base = Recipe(method, (defaults or {}).get(method), solver)
    method = base.method
    given = {g.name: getattr(args, g.name) for g in all_genes() if getattr(args, g.name) is not None}
    for name in method.derived:
        if name in given:
            raise UsageError(f"--{name.replace('_', '-')} is not used by Method-{method.name}, which sets {name} "
                             f"from each image pair (half the median of M); drop it")
    try:
        params = replace(base.params, **given)
    except (ParameterError, ParameterTypeError) as exc:
        raise UsageError(str(exc).replace("of Params", "of ismb-lab")) from None
    check_unused_genes(method.name, params)
    one_to_one = base.one_to_one if args.one_to_one is None else args.one_to_one
    recipe = replace(base, params=params, solver=configured_solver(args, base.solver), one_to_one=one_to_one)
    if loaded is not None:
        said_changes(args.params_file, loaded.recipe, recipe)
    return recipe


def configured_solver(args, base):
    """`base`, or the solver --solver names, with --stop-rule, --rule and --solver-option."""
    from ..network.solvers import get_solver

    chosen = base if args.solver is None or args.solver == base.name else args.solver
    settings = {"stop_rule": getattr(args, "stop_rule", None), "rule": getattr(args, "rule", None)}
    try:
        chosen = get_solver(chosen, "ismb-lab", **settings)
    except ParameterError:
        name = get_solver(chosen).name
        used = [f"--{k.replace('_', '-')}" for k, v in settings.items() if v is not None]
        raise UsageError(f"{' and '.join(used)} set the discrete network, which the {name} solver does "
                         f"not run (drop {'them' if len(used) > 1 else 'it'}, or use --solver network)") from None
    return with_settings(chosen, args)


def with_settings(solver, args):
    """`solver` (a name or a Solver) with the ``--solver-option`` values given; a bad one is a usage error."""
    from ..network.solvers import get_solver

    try:
        return get_solver(solver, "ismb-lab", "--solver-option", **solver_settings(args))
    except (ParameterError, ParameterTypeError) as exc:
        raise UsageError(str(exc).replace("parameter of ismb-lab", "option of ismb-lab's --solver-option")) from None


def said_changes(path, before, after) -> None:
    """One note on stderr naming what the options changed in the recipe read from `path`."""
    changes = before.changes(after)
    if changes:
        note(f"options override {path}: " + "; ".join(changes))


def note(text: str) -> None:
    print(f"ismb-lab: note: {text}", file=sys.stderr)


def check_unused_genes(method: str, params) -> None:
    """Refuse a ``match_bias`` that `method` would not run (one that fixes it accepts that value
    alone), so that a result records what ran."""
    m, bias = get_method(method), params.match_bias
    if bias is None or "match_bias" in m.gene_names or m.fixed.get("match_bias") == bias:
        return
    runs = f"runs with match_bias {m.fixed['match_bias']:g}" if "match_bias" in m.fixed else "has no match bias"
    users = [n for n in method_names() if "match_bias" in get_method(n).gene_names]
    raise UsageError(f"match_bias {bias:g} is not used by Method-{method}, which {runs}; only "
                     f"{', '.join('Method-' + n for n in users)} take a match_bias (drop it, or use "
                     f"--method {users[0]})")


def given(*named) -> tuple:
    """The ``(option, path)`` pairs of `named` whose path was given (not None).

    >>> given(("--rig", None), ("--json", "out.json"))
    (('--json', 'out.json'),)
    """
    return tuple((what, path) for what, path in named if path is not None)


def matched_files(args, images) -> Files:
    """`images` ((name, path) pairs), --params-file and --rig read; --json, --plot and --ply written."""
    return Files(inputs=tuple(images) + given(("--params-file", args.params_file), ("--rig", args.rig)),
                 outputs=given(("--json", args.json), ("--plot", args.plot), ("--ply", args.ply)))


def write_ply(path, xyz, xy, image, camera, what: str) -> None:
    """Write the PLY cloud of the points `xyz` in front of the cameras, each grey as `image` at its `xy`."""
    import numpy as np

    from .._core.files import atomic_write_bytes
    from ..matching.ply import ply_bytes

    keep = np.all(np.isfinite(xyz), axis=1)
    xy = np.rint(np.asarray(xy, dtype=float).reshape(-1, 2)[keep]).astype(int)
    h, w = image.shape
    grey = image[np.clip(xy[:, 1], 0, h - 1), np.clip(xy[:, 0], 0, w - 1)]
    atomic_write_bytes(path, ply_bytes(xyz[keep], np.clip(grey, 0, 255), comments=(
        f"{what}metres in the rectified left camera's frame (X right, Y down, Z forward)",
        f"focal length {camera.focal_px:.6g} px, baseline {camera.baseline_m:.6g} m")))


def seed_setting(args) -> dict:
    """--seed, if given, as a keyword argument."""
    return {} if args.seed is None else {"seed": args.seed}


def progress_bar(total: int, desc: str, unit: str = "gen"):
    """A tqdm bar on stderr whose ``update`` raises KeyboardInterrupt once a signal came (the
    handler's own can be swallowed inside a C extension)."""
    from tqdm import tqdm

    class _Bar(tqdm):
        def update(self, n=1):
            if interrupted():
                raise KeyboardInterrupt
            return super().update(n)

    return _Bar(total=total, desc=desc, unit=unit, file=sys.stderr, dynamic_ncols=True, disable=None)


class BestSoFar:
    """A GA progress callback that keeps the latest record, to save `recipe` with the best
    parameters so far when interrupted."""

    def __init__(self, recipe):
        self.recipe, self.name, self.record = recipe, None, None

    def __call__(self, name, record) -> None:
        self.name, self.record = name, record

    def save(self, path) -> int:
        """Write the recipe with the best parameters so far to `path` (if given); 130."""
        from ..matching.recipe import save_recipe
        from ..tuning.fitness import to_params

        if self.record is None:
            raise KeyboardInterrupt
        recipe = replace(self.recipe, params=to_params(self.recipe.method, self.record.best_chromosome))
        if path is not None:
            save_recipe(path, recipe, fitness=self.record.best, generations=self.record.index,
                        fitted_on=self.name, interrupted=True)
        print(f"ismb-lab: interrupted while fitting {self.name}; best parameters so far "
              f"{recipe.params.to_dict()}" + (f", written to {path}" if path is not None else ""),
              file=sys.stderr)
        return 130
