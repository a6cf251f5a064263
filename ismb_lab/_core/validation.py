"""Input checks shared by the whole package, each raising with one message format::

    The 'theta_c' parameter of Params must be a finite number >= 0. Got -1.0 instead.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = ["ParameterError", "ParameterTypeError", "check_choice", "check_number", "check_points", "check_rng",
           "message", "readonly", "shown_int"]


class _ShownAs(str):
    """Text shown as it is in a message (not quoted)."""

    def __repr__(self) -> str:
        return str(self)


class ParameterError(ValueError):
    """A parameter value breaks its rule.  The command line reports it in one line."""

    __module__ = "ismb_lab"


class ParameterTypeError(TypeError):
    """A parameter has the wrong type.  The command line reports it in one line."""

    __module__ = "ismb_lab"


#: The largest seed: seeds are non-negative int64 (an update-order stream's state is 64-bit).
MAX_SEED = 2**63 - 1


def shown_int(value: int) -> str:
    # repr() of an int over 4300 digits raises ValueError; the size is what matters then.
    size = abs(value)
    digits = int((max(size.bit_length(), 1) - 1) * math.log10(2)) + 1
    digits += size >= 10**digits
    return repr(value) if digits <= 40 else f"an integer of {digits} digits"


def message(name: str, owner: str, rule: str, value) -> str:
    """Return the package's one error message format (on one line).

    >>> message("seed", "match", "an integer", 10**5000)
    "The 'seed' parameter of match must be an integer. Got an integer of 5001 digits instead."
    """
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        value = _ShownAs(shown_int(int(value)))
    if isinstance(value, np.ndarray) and value.ndim > 1:
        shown = f"an array of shape {value.shape} and dtype {value.dtype}"
    else:
        shown = value if isinstance(value, str) and len(value) > 60 else repr(value)
        if "\n" in shown:
            shown = " ".join(shown.split())
    if isinstance(shown, str) and len(shown) > 80:
        shown = shown[:77] + "..."
    return f"The {name!r} parameter of {owner} must be {rule}. Got {shown} instead."


def check_number(value, name: str, owner: str, *, low=None, high=None,
                 low_open: bool = False, integer: bool = False) -> float | int:
    """`value` as a finite ``float`` (or ``int`` when `integer`; never ``bool``) within the
    inclusive bounds `low` and `high` (`low_open`: strict), else raise naming `name` of `owner`.

    >>> check_number(3, "n_min", "detect_corners", low=1, integer=True)
    3
    >>> check_number(float("nan"), "theta_c", "Params")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'theta_c' parameter of Params must be a finite number. Got nan instead.
    """
    rule = "an integer" if integer else "a finite number"
    bound = lambda b: shown_int(b) if isinstance(b, int) else b   # noqa: E731
    if low is not None:
        rule += f" {'>' if low_open else '>='} {bound(low)}"
    if high is not None:
        rule += f"{' and' if low is not None else ''} <= {bound(high)}"
    if type(value) not in (float, int) and (isinstance(value, bool) or not isinstance(value, numbers.Real)):
        raise ParameterTypeError(message(name, owner, rule, value))
    if integer:
        if not isinstance(value, numbers.Integral) and not float(value).is_integer():
            raise ParameterTypeError(message(name, owner, rule, value))
        value = int(value)
    else:
        try:
            value = float(value)
        except OverflowError:   # an int of hundreds of digits
            raise ParameterError(message(name, owner, rule, value)) from None
        if not math.isfinite(value):
            raise ParameterError(message(name, owner, rule, value))
    if low is not None and (value <= low if low_open else value < low):
        raise ParameterError(message(name, owner, rule, value))
    if high is not None and value > high:
        raise ParameterError(message(name, owner, rule, value))
    return value


def check_choice(value, name: str, owner: str, choices, rule: str | None = None) -> str:
    """Check that `value` is one of the strings in `choices` (`rule` words the message).

    >>> check_choice("sweep", "stop_rule", "run", ("sweep", "stall"))
    'sweep'
    >>> check_choice("fast", "stop_rule", "run", ("sweep", "stall"))
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'stop_rule' parameter of run must be one of 'sweep', 'stall'. Got 'fast' instead.
    """
    if isinstance(value, str) and value in choices:
        return value
    rule = rule or "one of " + ", ".join(repr(c) for c in choices)
    kind = ParameterError if isinstance(value, str) else ParameterTypeError
    raise kind(message(name, owner, rule, value))


def check_points(points, name: str, owner: str, dims: int = 2) -> np.ndarray:
    """Check an ``(N, 2)`` array of finite ``(x, y)`` points (``dims=3``: ``(X, Y, Z)``) and
    return it as float.

    >>> check_points([[1, 2], [3, 4]], "left_xy", "match").shape
    (2, 2)
    >>> check_points([], "points3d", "project", dims=3).shape
    (0, 3)
    """
    rule = ("an (N, 2) array of finite (x, y) coordinates" if dims == 2
            else "an (N, 3) array of finite (X, Y, Z) points")
    try:
        arr = np.asarray(points, dtype=float)
    except OverflowError:   # an int of hundreds of digits
        raise ParameterError(message(name, owner, rule, "an array with a number too large for a float")) from None
    except (TypeError, ValueError):
        raise ParameterTypeError(message(name, owner, rule, points)) from None
    if arr.size == 0:
        return arr.reshape(0, dims)
    if arr.ndim != 2 or arr.shape[1] != dims:
        raise ParameterError(message(name, owner, rule, f"an array of shape {arr.shape}"))
    if not np.all(np.isfinite(arr)):
        raise ParameterError(message(name, owner, rule, "an array with NaN or infinite values"))
    return arr


def check_rng(rng, name: str = "rng", owner: str = "function") -> np.random.Generator:
    """A numpy Generator from a Generator or an integer seed (the package's only way to randomness).

    >>> int(check_rng(0).integers(10)) == int(check_rng(0).integers(10))
    True
    """
    if isinstance(rng, np.random.Generator):
        return rng
    rule = f"an integer seed from 0 to {MAX_SEED} (2**63 - 1) or a numpy Generator"
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool):
        if not 0 <= rng <= MAX_SEED:
            raise ParameterError(message(name, owner, rule, rng))
        return np.random.default_rng(int(rng))
    raise ParameterTypeError(message(name, owner, rule, rng))


def readonly(values) -> np.ndarray:
    """A float copy of `values` that cannot be written to (for frozen records).

    >>> readonly([1, 2]).flags.writeable
    False
    """
    arr = np.array(values, dtype=float)
    arr.flags.writeable = False
    return arr
