"""A recipe: everything about a match but the images and the corners, saved and loaded whole.

The params file (``{"method": ..., "params": {...}}``) is written and read here only.  A recipe
adds keys (``"version": 2``, ``"solver_options"``, ``"fit_seeds"``, ``"one_to_one"``); a file
without ``"version"`` predates recipes.

>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "p.json"
>>> _ = save_recipe(path, Recipe("NM3", solver="anneal", one_to_one=True), fitness=12)
>>> loaded = load_recipe(path).recipe
>>> loaded.method.name, loaded.solver.name, loaded.one_to_one
('NM3', 'anneal', True)
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from .._core.files import atomic_write_text
from .._core.validation import ParameterError, ParameterTypeError, check_number, message
from ..network.methods import DEFAULT_METHOD, Method, get_method, method_names
from ..network.params import Params
from ..network.solvers import DEFAULT_SOLVER, Solver, get_solver

__all__ = ["RECIPE_VERSION", "Loaded", "Recipe", "load_recipe", "recipe_of", "save_recipe"]

#: The version :func:`save_recipe` writes; files without a version key are version 1.
RECIPE_VERSION = 2

#: The keys a recipe writes; :func:`save_recipe`'s extras may not reuse them.
_KEYS = ("version", "method", "params", "solver", "solver_options", "fit_seeds", "one_to_one")


@dataclass(frozen=True)
class Recipe:
    """Method, parameters (default: the method's), solver with its options, fit seeds and
    match-time settings; `method` and `solver` are resolved once.

    `fit_seeds` records how many update-order seeds each GA fitness averaged over; `one_to_one`
    keeps at most one match per corner after solving.

    Attributes
    ----------
    method : Method or str, default "III"
        The energy recipe; a name is resolved to its Method.
    params : Params, optional
        Energy parameters; None gives the method's defaults.
    solver : Solver or str, default "network"
        How the energy is minimised; a name is resolved to its Solver.
    fit_seeds : int, default 1
        Update-order seeds each GA fitness averaged over.
    one_to_one : bool, default False
        Keep at most one match per corner after solving.

    Raises
    ------
    ParameterTypeError
        `params` not a Params, or `one_to_one` not a bool.

    Examples
    --------
    >>> Recipe("NM3", solver="anneal").to_dict()["solver"]
    'anneal'
    >>> Recipe(one_to_one="yes")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterTypeError: The 'one_to_one' parameter of Recipe must be True or False. Got 'yes' instead.
    """

    method: Method | str = DEFAULT_METHOD
    params: Params | None = None
    solver: Solver | str = DEFAULT_SOLVER
    fit_seeds: int = 1
    one_to_one: bool = False

    def __post_init__(self):
        own = "Recipe"
        method = get_method(self.method)
        object.__setattr__(self, "method", method)
        if self.params is None:
            object.__setattr__(self, "params", method.defaults)
        elif not isinstance(self.params, Params):
            raise ParameterTypeError(message("params", own, "a Params instance", self.params))
        object.__setattr__(self, "solver", get_solver(self.solver, own))
        check_number(self.fit_seeds, "fit_seeds", own, low=1, integer=True)
        if not isinstance(self.one_to_one, bool):
            raise ParameterTypeError(message("one_to_one", own, "True or False", self.one_to_one))

    def to_dict(self) -> dict:
        """The recipe's keys of the params file.

        Returns
        -------
        data : dict
            ``version``, ``method``, ``params``, ``solver``, ``solver_options``, ``fit_seeds``,
            ``one_to_one``.
        """
        return {"version": RECIPE_VERSION, "method": self.method.name, "params": self.params.to_dict(),
                "solver": self.solver.name, "solver_options": self.solver.options(),
                "fit_seeds": int(self.fit_seeds), "one_to_one": self.one_to_one}

    def match_settings(self) -> dict:
        """The keyword arguments of :func:`ismb_lab.matching.pipeline.match` that the recipe sets."""
        return {"method": self.method, "params": self.params, "solver": self.solver,
                "one_to_one": self.one_to_one}

    def changes(self, other: "Recipe") -> list[str]:
        """What differs from `other`, as ``"field old -> new"`` (for a command's note).

        >>> Recipe(solver="anneal").changes(Recipe(solver="network", one_to_one=True))
        ['solver anneal -> network', 'one_to_one False -> True']
        """
        out = []
        for name in ("method", "params", "solver", "fit_seeds", "one_to_one"):
            old, new = getattr(self, name), getattr(other, name)
            if old == new:
                continue
            if name == "solver" and old.name == new.name:
                out.append(f"solver options {old.options()} -> {new.options()}")
            elif name == "params":
                was, now = old.to_dict(), new.to_dict()
                out += [f"{k} {was.get(k)} -> {now.get(k)}" for k in {**was, **now} if was.get(k) != now.get(k)]
            else:
                out.append(f"{name} {_shown(old)} -> {_shown(new)}")
        return out


def _shown(value):
    """A recipe field as a note shows it."""
    return value.name if isinstance(value, (Method, Solver)) else value


class Loaded(NamedTuple):
    """A recipe read from a file, and what the reader should be told once (or "")."""

    recipe: Recipe
    note: str


def save_recipe(path, recipe: Recipe, **extra) -> Path:
    """Write `recipe` and `extra` keys (e.g. the GA's fitness) atomically as JSON."""
    if not isinstance(recipe, Recipe):
        raise ParameterTypeError(message("recipe", "save_recipe", "a Recipe", recipe))
    clash = sorted(set(extra) & set(_KEYS))
    if clash:
        raise ParameterError(message("extra", "save_recipe", "keys other than the recipe's own", clash))
    return atomic_write_text(path, json.dumps({**recipe.to_dict(), **extra}, indent=2) + "\n")


def _read_params_file(path, owner: str) -> dict:
    """The JSON object of a params file (within ``MAX_JSON_BYTES``) holding a ``"params"`` object."""
    from .._core.files import read_json

    try:
        data = read_json(path)
    except FileNotFoundError:
        raise ParameterError(message("path", owner, "an existing params file", str(path))) from None
    except (OSError, ValueError) as exc:   # a ValueError has no strerror
        why = getattr(exc, "strerror", None) or exc
        raise ParameterError(message("path", owner, f"a readable JSON file ({why})", str(path))) from None
    if not isinstance(data, dict) or not isinstance(data.get("params"), dict):
        raise ParameterError(message("path", owner, "a JSON object with a 'params' object", str(path)))
    return data


def load_recipe(path, *, method=None, solver=DEFAULT_SOLVER, before: str | None = None) -> Loaded:
    """Read the recipe of a params file.

    `method` and `solver` are used when the file names none.  `before` is the solver the reading
    command used with a version-1 file; when the file's own differs, the note says so.
    """
    own = f"load_recipe('{path}')"
    data = _read_params_file(path, "load_recipe")
    version = data.get("version", 1)
    if type(version) is not int or not 1 <= version <= RECIPE_VERSION:
        raise ParameterError(message("version", own, f"an integer from 1 to {RECIPE_VERSION}", version))
    named = data.get("method")
    if named is not None and not (isinstance(named, str) and named in method_names()):
        raise ParameterError(message("method", own, "one of " + ", ".join(repr(n) for n in method_names()),
                                     named))
    # missing values take the defaults of the file's method, else of `method`, else DEFAULT_METHOD's
    base = get_method(named or method or DEFAULT_METHOD).defaults
    values = Params.from_dict({**base.to_dict(), **data["params"]}, owner=own)
    saved = data.get("solver")
    options = data.get("solver_options", {})
    if not isinstance(options, dict):
        raise ParameterError(message("solver_options", own, "an object of the solver's options", options))
    for key in ("fit_seeds", "one_to_one"):
        if key in data and (type(data[key]) is not (bool if key == "one_to_one" else int)):
            rule = "true or false" if key == "one_to_one" else "an integer >= 1"
            raise ParameterError(message(key, own, rule, data[key]))
    recipe = Recipe(named or method or DEFAULT_METHOD, values,
                    get_solver(solver if saved is None else saved, own, **options),
                    data.get("fit_seeds", 1), data.get("one_to_one", False))
    note = ""
    if version == 1 and saved is not None and before is not None and saved != get_solver(before).name:
        note = (f"{path} was written before recipes were saved whole: its solver '{saved}' is used, "
                f"where this command used '{get_solver(before).name}' with it before")
    return Loaded(recipe, note)


def recipe_of(recipe, owner: str = "recipe_of", solver=DEFAULT_SOLVER) -> Recipe:
    """A :class:`Recipe` as it is, or the recipe of a params file (`solver`: when it names none).

    >>> recipe_of(Recipe("NM3")).method.name
    'NM3'
    >>> recipe_of(3)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterTypeError: The 'recipe' parameter of recipe_of must be a Recipe or the path of a params file. Got 3 instead.
    """
    if isinstance(recipe, Recipe):
        return recipe
    if not isinstance(recipe, (str, Path)):
        raise ParameterTypeError(message("recipe", owner, "a Recipe or the path of a params file", recipe))
    return load_recipe(recipe, solver=solver).recipe
