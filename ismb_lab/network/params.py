"""The energy's parameters and the genes a GA searches (thesis (3-10), (3-13), ch. 4).

Gene bounds: ``theta_c`` in [0, 60] px (correct neighbour pairs have ``X`` of a few pixels,
wrong ones tens; the thesis found 7.45 to 41.57); ``theta_s`` in [0, 60] grey levels (on the
synthetic scenes ``M`` is about 5 for true matches, 45 for false ones); ``lambda_c`` and
``lambda_s`` in [0.05, 10] (almost flat to a step one pixel wide); ``match_bias`` in [-2, 2]
(``h = 1/2 + beta / 4`` from 0 through "at most one" to "exactly one").

Outside a GA, :class:`Params` takes thetas in [0, :data:`MAX_THETA`], lambdas in
(0, :data:`MAX_LAMBDA`] and ``|match_bias|`` up to :data:`MAX_BIAS`: beyond them the
arithmetic overflows and the matches are garbage.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

from .._core.validation import ParameterError, ParameterTypeError, check_choice, check_number, message

__all__ = ["LAMBDA_C", "LAMBDA_S", "MATCH_BIAS", "MAX_BIAS", "MAX_LAMBDA", "MAX_THETA", "THETA_C", "THETA_S", "Gene",
           "Params"]

#: Largest tolerance ``theta_c`` or ``theta_s``.
MAX_THETA = 1000.0
#: Largest steepness ``lambda_c`` or ``lambda_s``.
MAX_LAMBDA = 1000.0
#: Largest ``|match_bias|``.
MAX_BIAS = 100.0


@dataclass(frozen=True, repr=False)
class Params:
    """The parameters of the energy: tolerances ``theta``, steepnesses ``lambda`` and, for
    Method-NM only, a match bias.

    The defaults are the thesis' Method-III values (§5.2.2).  ``match_bias`` is None unless
    set, and then left out of ``repr`` and :meth:`to_dict`.

    Attributes
    ----------
    theta_c : float, default 17.97
        Tolerance of ``X`` in ``C`` (3-13), pixels, in [0, :data:`MAX_THETA`].
    theta_s : float, default 24.02
        Tolerance of ``M`` in ``S`` (3-10), grey levels, in [0, :data:`MAX_THETA`].
    lambda_c : float, default 6.37
        Steepness of ``C``, in (0, :data:`MAX_LAMBDA`].
    lambda_s : float, default 2.2
        Steepness of ``S``, in (0, :data:`MAX_LAMBDA`].
    match_bias : float or None, default None
        ``beta`` of Method-NM, ``|beta|`` at most :data:`MAX_BIAS`.

    Raises
    ------
    ParameterError
        A value out of its range.

    Examples
    --------
    >>> Params()
    Params(theta_c=17.97, theta_s=24.02, lambda_c=6.37, lambda_s=2.2)
    >>> Params(match_bias=0.5).to_dict()["match_bias"]
    0.5
    >>> Params(lambda_c=-1)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'lambda_c' parameter of Params must be a finite number > 0 and <= 1000.0. Got -1.0 instead.
    """

    theta_c: float = 17.97
    theta_s: float = 24.02
    lambda_c: float = 6.37
    lambda_s: float = 2.2
    match_bias: float | None = None

    def __post_init__(self):
        # A GA builds one Params per chromosome: plain floats in range pass without a call.
        t_c, t_s, l_c, l_s, beta = self.theta_c, self.theta_s, self.lambda_c, self.lambda_s, self.match_bias
        if (type(t_c) is type(t_s) is type(l_c) is type(l_s) is float and 0.0 <= t_c <= MAX_THETA
                and 0.0 <= t_s <= MAX_THETA and 0.0 < l_c <= MAX_LAMBDA and 0.0 < l_s <= MAX_LAMBDA
                and (beta is None or type(beta) is float and -MAX_BIAS <= beta <= MAX_BIAS)):
            return
        for f in fields(self):
            if f.name == "match_bias":
                if self.match_bias is not None:
                    value = check_number(self.match_bias, f.name, "Params", low=-MAX_BIAS, high=MAX_BIAS)
                    object.__setattr__(self, f.name, value)
                continue
            strict = f.name.startswith("lambda")
            value = check_number(getattr(self, f.name), f.name, "Params", low=0, low_open=strict,
                                 high=MAX_LAMBDA if strict else MAX_THETA)
            object.__setattr__(self, f.name, value)

    def __repr__(self) -> str:
        return "Params(" + ", ".join(f"{k}={v!r}" for k, v in self.to_dict().items()) + ")"

    def to_dict(self) -> dict:
        """The fields by name, without ``match_bias`` when it is None.

        Returns
        -------
        values : dict
            Field name to value.
        """
        return {k: v for k, v in asdict(self).items() if v is not None}

    @classmethod
    def from_dict(cls, values, owner: str = "Params.from_dict") -> "Params":
        """Build from a mapping; unknown keys are an error, missing keys take the defaults."""
        if not isinstance(values, dict):
            raise ParameterTypeError(message("params", owner, "a JSON object of parameter values", values))
        unknown = sorted(set(values) - {f.name for f in fields(cls)})
        if unknown:
            raise ParameterError(message("params", owner, "an object with keys among theta_c, theta_s, "
                                     "lambda_c, lambda_s, match_bias", f"unknown keys {unknown}"))
        return cls(**values)


@dataclass(frozen=True)
class Gene:
    """One parameter a method's GA searches: a :class:`Params` field, its search bounds, what
    it means (for help texts) and its thesis symbol (for slider labels).

    Attributes
    ----------
    name : str
        A field of :class:`Params`.
    low, high : float
        Search bounds, ``low < high``.
    meaning : str, default ""
        What it means, for help texts.
    symbol : str, default ""
        Its thesis symbol, for slider labels.

    Examples
    --------
    >>> THETA_C
    Gene(name='theta_c', low=0.0, high=60.0, meaning='tolerance of X in C (3-13)', symbol='θc')
    >>> Gene("theta_x", 0.0, 1.0)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'name' parameter of Gene must be a field of Params (theta_c, theta_s, lambda_c, lambda_s, match_bias). Got 'theta_x' instead.
    """

    name: str
    low: float
    high: float
    meaning: str = ""
    symbol: str = ""

    def __post_init__(self):
        names = tuple(f.name for f in fields(Params))
        check_choice(self.name, "name", "Gene", names,
                     rule=f"a field of Params ({', '.join(names)})")
        low = check_number(self.low, "low", "Gene")
        check_number(self.high, "high", "Gene", low=low, low_open=True)


THETA_C = Gene("theta_c", 0.0, 60.0, "tolerance of X in C (3-13)", "θc")
THETA_S = Gene("theta_s", 0.0, 60.0, "tolerance of M in S (3-10)", "θs")
LAMBDA_C = Gene("lambda_c", 0.05, 10.0, "steepness of C (3-13)", "λc")
LAMBDA_S = Gene("lambda_s", 0.05, 10.0, "steepness of S (3-10)", "λs")
MATCH_BIAS = Gene("match_bias", -2.0, 2.0, "beta: preferred matches per feature h = 1/2 + beta/4", "β")
