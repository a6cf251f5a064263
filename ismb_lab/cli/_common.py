"""Pieces every ``ismb-lab`` command shares: the one-line error, option groups, parameters."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from .._files import check_input
from .._validation import ParameterError, ParameterTypeError  # noqa: F401  (re-exported for main)
from ._guard import interrupted

if TYPE_CHECKING:
    from ..methods import Params

# The method names, here so that building the parser does not import numba.
METHOD_NAMES = ("I", "II", "III", "NM", "NM4")

PARAM_OPTIONS = ("theta_c", "theta_s", "lambda_c", "lambda_s", "match_bias")


class UsageError(Exception):
    """A mistake in the command line or its files, reported in one line."""


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line instead of argparse's usage dump
        raise UsageError(f"{message} (see '{self.prog} --help')")


def add_matching_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--method", choices=METHOD_NAMES, default=None,
                   help="energy recipe (default: the params file's, else III)")
    for name in PARAM_OPTIONS:
        p.add_argument("--" + name.replace("_", "-"), type=float, default=None, metavar="X",
                       help=f"override {name} (thesis default for the method)")
    p.add_argument("--params-file", type=Path, default=None, metavar="P.json",
                   help='parameters as {"method": ..., "params": {...}}, e.g. from ismb-lab tune')
    add_feature_options(p)
    p.add_argument("--seed", type=int, default=0, help="seed of the update order (default: 0)")
    p.add_argument("--stop-rule", choices=("sweep", "stall"), default="sweep",
                   help="sweep: a full sweep without change (default); stall: 200 idle attempts")
    p.add_argument("--rule", choices=("exact", "thesis"), default="exact",
                   help="exact Hopfield weights (default) or the thesis' literal (3-17)/(3-20)")


def add_feature_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--roi", default="center", help="center | full | X,Y,W,H (default: center)")
    p.add_argument("--shift", type=float, default=20.0, metavar="PX",
                   help="expected disparity: centre of the candidate window (default: 20)")
    p.add_argument("--n-min", type=int, default=20, help="fewest corners per image (default: %(default)s)")
    p.add_argument("--n-max", type=int, default=30, help="most corners per image (default: %(default)s)")


def read_params_file(path: Path) -> tuple[str | None, dict]:
    """Read ``{"method": ..., "params": {...}}``; extra keys are allowed."""
    try:
        data = json.loads(check_input(path, what="--params-file").read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"--params-file {path}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UsageError(f"--params-file {path}: not a readable JSON file ({exc})") from None
    except RecursionError:
        raise UsageError(f"--params-file {path}: its JSON is nested too deeply to read") from None
    if not isinstance(data, dict) or not isinstance(data.get("params"), dict):
        raise UsageError(f"--params-file {path}: expected an object with a 'params' object")
    method = data.get("method")
    if method is not None and method not in METHOD_NAMES:
        raise UsageError(f"--params-file {path}: unknown method {method!r} "
                         f"(expected one of {', '.join(METHOD_NAMES)})")
    return method, data["params"]


def resolve_params(args) -> tuple[str, Params]:
    """The method and parameters from --method, --params-file and the single overrides.

    A ``match_bias`` is refused for a method that does not run it: only Method-NM
    uses it, and Method-NM4 runs with 0 (so 0 is accepted there), so what a result
    records is always what was run.
    """
    from ..methods import THESIS_PARAMS, Params

    file_method, values = (None, {})
    if args.params_file is not None:
        file_method, values = read_params_file(args.params_file)
    if args.method and file_method and args.method != file_method:
        raise UsageError(f"--method {args.method} conflicts with --params-file, "
                         f"which holds parameters for Method-{file_method}")
    method = args.method or file_method or "III"
    merged = THESIS_PARAMS[method].to_dict()
    merged.update(values)
    merged.update({k: getattr(args, k) for k in PARAM_OPTIONS if getattr(args, k) is not None})
    params = Params.from_dict(merged, owner="ismb-lab")
    check_match_bias(method, params)
    return method, params


def check_match_bias(method: str, params) -> None:
    """Refuse a ``match_bias`` that `method` would not run (recorded as one value, run as another)."""
    bias = params.match_bias
    if bias is None or method == "NM" or (method == "NM4" and bias == 0):
        return
    runs = "runs with match_bias 0" if method == "NM4" else "has no match bias"
    raise UsageError(f"match_bias {bias:g} is not used by Method-{method}, which {runs}; "
                     "only Method-NM takes a match_bias (use --method NM, or drop match_bias)")


def progress_bar(total: int, desc: str):
    """A tqdm bar whose ``update`` raises KeyboardInterrupt once SIGINT, SIGTERM or SIGHUP came.

    The signal handler raises KeyboardInterrupt itself, but one raised inside a C
    extension (numba's dispatcher, an import) can be swallowed there; checking at
    every generation makes sure the work still stops at the next one.
    """
    from tqdm import tqdm

    class _Bar(tqdm):
        def update(self, n=1):
            if interrupted():
                raise KeyboardInterrupt
            return super().update(n)

    return _Bar(total=total, desc=desc, unit="gen", file=sys.stderr, dynamic_ncols=True,
                disable=None)


class BestSoFar:
    """A GA progress callback's companion: keeps the latest record, to save it when interrupted."""

    def __init__(self, method: str):
        self.method, self.name, self.record = method, None, None

    def __call__(self, name, record) -> None:
        self.name, self.record = name, record

    def save(self, path) -> int:
        """Write the best parameters so far to `path` (if given and a generation finished); 130."""
        from .._files import atomic_write_text
        from ..tuning import to_params
        from ._guard import json_text

        if self.record is None:
            raise KeyboardInterrupt
        params = to_params(self.method, self.record.best_chromosome)
        if path is not None:
            atomic_write_text(path, json_text({
                "method": self.method, "params": params.to_dict(), "fitness": self.record.best,
                "generations": self.record.index, "fitted_on": self.name, "interrupted": True}))
        print(f"ismb-lab: interrupted while fitting {self.name}; best parameters so far "
              f"{params.to_dict()}" + (f", written to {path}" if path is not None else ""),
              file=sys.stderr)
        return 130


def match_config(args):
    from ..matching import MatchConfig
    return MatchConfig(roi=args.roi, shift=args.shift, n_min=args.n_min, n_max=args.n_max)


