"""Methods I, II and III as energy recipes (thesis §3.3, §5.2).

A method turns the ingredients of one image pair (a :class:`Problem`) and its
parameters into a :class:`~ismb_lab.hopfield.Network`, and may post-process the
network's final state.

* **Method-II**: a separate similarity ``S = transfer(M, theta_s, lambda_s)`` and
  ``X = dd + dD``.
* **Method-III** (ISMB, the thesis' method): Method-II plus the vertical-disparity
  term, ``X = dd + dD + dY``.
* **Method-I** (Achour & Mahiddine 2002) is a *reconstruction*: their paper is not
  at hand, and the thesis says only that the similarity ``M`` is folded into the
  pairwise term, that there is no separate ``S``, that vertical disparity is used
  only afterwards to remove multiple matches, and that it has two parameters
  ``(theta_c, lambda_c)``.  Here ``X = dd + dD + (M_ik + M_jl) / 2``, ``S = 0``, and
  the post-processing keeps, for every feature matched more than once, the match
  with the smallest vertical disparity.
* **Method-NM** (beyond the thesis): Method-III's ``S`` and ``C`` with a
  uniqueness term that lets a feature stay unmatched.  The thesis'
  ``(1 - sum y)^2`` asks for *exactly one* match per feature, so corners without
  a partner take wrong ones; Method-NM's fifth gene, the match bias ``beta``,
  moves the preferred count to ``h = 1/2 + beta / 4`` (``beta = 2`` is
  Method-III, ``beta = 0`` says "at most one").  The derivation is in
  :mod:`ismb_lab.hopfield`.
* **Method-NM4**: Method-NM with the match bias fixed at 0 ("at most one match
  per feature") and Method-III's four genes.  Trained on one small pair, the
  fifth gene mostly fits that pair's own count of unmatched corners; without
  it the GA has one thing less to overfit.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace

import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_choice, check_number, message
from .compatibility import NeuronPairs, left_neighbours, neuron_pairs
from .hopfield import Network, Topology
from .similarity import candidate_mask, transfer

METHOD_NAMES = ("I", "II", "III", "NM", "NM4")


@dataclass(frozen=True, repr=False)
class Params:
    """The parameters of the energy: tolerances ``theta``, steepnesses ``lambda``
    and, for Method-NM only, a match bias.

    The defaults are the thesis' Method-III values ``[17.97, 24.02, 6.37, 2.2]``
    (§5.2.2), found by its GA on its own images.  Method-I reads only
    ``theta_c`` and ``lambda_c``.  ``match_bias`` (``beta``, any finite number)
    is optional: it is None unless set, and then left out of ``repr`` and
    :meth:`to_dict`, so the four-parameter methods see exactly the thesis' record.

    Examples
    --------
    >>> Params()
    Params(theta_c=17.97, theta_s=24.02, lambda_c=6.37, lambda_s=2.2)
    >>> Params(match_bias=0.5).to_dict()["match_bias"]
    0.5
    >>> Params(lambda_c=-1)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'lambda_c' parameter of Params must be a finite number > 0. Got -1.0 instead.
    """

    theta_c: float = 17.97
    theta_s: float = 24.02
    lambda_c: float = 6.37
    lambda_s: float = 2.2
    match_bias: float | None = None

    def __post_init__(self):
        for f in fields(self):
            if f.name == "match_bias":
                if self.match_bias is not None:
                    object.__setattr__(self, f.name, check_number(self.match_bias, f.name, "Params"))
                continue
            strict = f.name.startswith("lambda")
            value = check_number(getattr(self, f.name), f.name, "Params", low=0, low_open=strict)
            object.__setattr__(self, f.name, value)

    def __repr__(self) -> str:
        return "Params(" + ", ".join(f"{k}={v!r}" for k, v in self.to_dict().items()) + ")"

    def to_dict(self) -> dict:
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


#: The parameters the thesis' GA found (§5.2.1 for Method-I, §5.2.2 for II and III).
#: Method-I's theta_s and lambda_s are unused placeholders.  Method-NM is not in
#: the thesis: its entry is Method-III's values with ``match_bias = 0`` ("at most
#: one match"), a neutral start for its GA rather than a fitted result.
THESIS_PARAMS = {
    "I": Params(theta_c=41.57, lambda_c=4.40),
    "II": Params(theta_c=11.51, theta_s=26.24, lambda_c=8.89, lambda_s=1.16),
    "III": Params(theta_c=17.97, theta_s=24.02, lambda_c=6.37, lambda_s=2.2),
    "NM": Params(theta_c=17.97, theta_s=24.02, lambda_c=6.37, lambda_s=2.2, match_bias=0.0),
    "NM4": Params(theta_c=17.97, theta_s=24.02, lambda_c=6.37, lambda_s=2.2),
}


@dataclass(frozen=True, eq=False)
class Problem:
    """The parameter-free ingredients of one image pair's energy.

    Everything that does not depend on ``theta``/``lambda`` is computed once
    here, so a GA can build thousands of networks cheaply.

    Attributes
    ----------
    left_xy : (N_l, 2) ndarray
    right_xy : (N_r, 2) ndarray
        Feature points ``(x, y)``.
    dissimilarity : (N_l, N_r) ndarray
        ``M_ik`` (3-8).
    rows, cols : (n,) int ndarray
        Candidate neurons ``(i, k)``, sorted.
    pairs : NeuronPairs
        Interacting neuron pairs with their ``dd``, ``dD``, ``dY``.
    topology : Topology
        The same neurons and pairs, laid out for the network.
    """

    left_xy: np.ndarray
    right_xy: np.ndarray
    dissimilarity: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    pairs: NeuronPairs
    topology: Topology

    @property
    def n_neurons(self) -> int:
        return len(self.rows)


def build_problem(left_xy, right_xy, dissimilarity, *, shift: float = 20.0,
                  window_height: float = 30.0, window_width: float = 40.0,
                  radius: float = 20.0, neighbourhood: str = "box") -> Problem:
    """Candidate neurons and their interacting pairs for one image pair.

    Parameters
    ----------
    left_xy, right_xy : (N, 2) array_like
        Feature points.
    dissimilarity : (N_l, N_r) array_like
        ``M_ik`` from :func:`ismb_lab.similarity.mean_abs_difference`.
    shift, window_height, window_width : float
        The candidate window (§3.3), see :func:`ismb_lab.similarity.candidate_mask`.
    radius, neighbourhood
        Which left features are neighbours, see :func:`ismb_lab.compatibility.left_neighbours`.

    Returns
    -------
    problem : Problem

    Examples
    --------
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], np.zeros((2, 2)))
    >>> p.rows, p.cols, len(p.pairs)
    (array([0, 0, 1, 1]), array([0, 1, 0, 1]), 2)
    """
    lxy = np.asarray(left_xy, dtype=float).reshape(-1, 2)
    rxy = np.asarray(right_xy, dtype=float).reshape(-1, 2)
    M = np.asarray(dissimilarity, dtype=float)
    if M.shape != (len(lxy), len(rxy)):
        raise ParameterError(message("dissimilarity", "build_problem", f"of shape ({len(lxy)}, {len(rxy)})",
                                 f"shape {M.shape}"))
    mask = candidate_mask(lxy, rxy, shift=shift, height=window_height, width=window_width)
    rows, cols = np.nonzero(mask)
    neighbours = left_neighbours(lxy, radius=radius, shape=neighbourhood)
    pairs = neuron_pairs(lxy, rxy, rows, cols, neighbours)
    rows, cols = rows.astype(np.int64), cols.astype(np.int64)
    topology = Topology(len(lxy), len(rxy), rows, cols, pairs.a, pairs.b)
    return Problem(lxy, rxy, M, rows, cols, pairs, topology)


class Method:
    """An energy recipe: how ``S`` and ``X`` are formed, and any post-processing.

    Use :func:`get_method` to obtain one by name.
    """

    name: str = ""
    genes: tuple[str, ...] = ()
    description: str = ""

    def similarity(self, problem: Problem, params: Params) -> np.ndarray:
        return transfer(problem.dissimilarity[problem.rows, problem.cols], params.theta_s, params.lambda_s)

    def pair_measure(self, problem: Problem) -> np.ndarray:
        """``X`` for every interacting pair, and ``X`` of a neuron with itself."""
        raise NotImplementedError

    def self_measure(self, problem: Problem) -> np.ndarray:
        return np.zeros(problem.n_neurons)

    def network(self, problem: Problem, params: Params) -> Network:
        """The network whose energy (3-15) this method minimises."""
        if not isinstance(params, Params):
            raise ParameterTypeError(message("params", f"Method-{self.name}", "a Params instance", params))
        c = transfer(self.pair_measure(problem), params.theta_c, params.lambda_c)
        self_c = transfer(self.self_measure(problem), params.theta_c, params.lambda_c)
        # Params are validated finite and transfer() maps finite input into [-1, 1].
        return Network._trusted(problem.topology, self.similarity(problem, params), c, self_c)

    def postprocess(self, problem: Problem, state: np.ndarray) -> np.ndarray:
        return state

    def __repr__(self) -> str:
        return f"Method-{self.name}"


class MethodI(Method):
    """Method-I, reconstructed from the thesis' description of Achour & Mahiddine (2002).

    ``X = dd + dD + (M_ik + M_jl) / 2``: the similarity acts only through
    neighbouring pairs; ``S = 0``; two parameters ``(theta_c, lambda_c)``.
    Afterwards, a feature matched more than once keeps only its match with the
    smallest absolute vertical disparity ``|y_k - y_i|`` (left features first,
    then right features; ties go to the lower index).
    """

    name, genes = "I", ("theta_c", "lambda_c")
    description = "X = dd + dD + mean(M); no S; vertical disparity only as post-processing"

    def similarity(self, problem, params):
        return np.zeros(problem.n_neurons)

    def pair_measure(self, problem):
        p = problem.pairs
        m = problem.dissimilarity[problem.rows, problem.cols]
        return p.dd + p.dD + 0.5 * (m[p.a] + m[p.b])

    def self_measure(self, problem):
        return problem.dissimilarity[problem.rows, problem.cols]

    def postprocess(self, problem, state):
        state = np.array(state, dtype=np.uint8)
        dy = np.abs(problem.right_xy[problem.cols, 1] - problem.left_xy[problem.rows, 1])
        for owner in (problem.rows, problem.cols):
            on = np.flatnonzero(state)
            order = np.lexsort((on, dy[on], owner[on]))  # by feature, then |dy|, then index
            ranked = on[order]
            first = np.ones(len(ranked), dtype=bool)
            first[1:] = owner[ranked][1:] != owner[ranked][:-1]
            state[ranked[~first]] = 0
        return state


class MethodII(Method):
    """Method-II: separate similarity ``S``, ``X = dd + dD``."""

    name, genes = "II", ("theta_c", "theta_s", "lambda_c", "lambda_s")
    description = "S from M; X = dd + dD"

    def pair_measure(self, problem):
        return problem.pairs.dd + problem.pairs.dD


class MethodIII(Method):
    """Method-III (ISMB): separate similarity ``S``, ``X = dd + dD + dY``."""

    name, genes = "III", ("theta_c", "theta_s", "lambda_c", "lambda_s")
    description = "S from M; X = dd + dD + dY (vertical disparity)"

    def pair_measure(self, problem):
        return problem.pairs.dd + problem.pairs.dD + problem.pairs.dY


class MethodNM(MethodIII):
    """Method-NM: Method-III's ``S`` and ``C`` with a no-match-aware uniqueness term.

    The energy is (3-15) with ``(1 - r)^2`` replaced by ``(h - r)^2``, where
    ``h = 1/2 + beta / 4`` and ``beta`` is the fifth gene ``params.match_bias``.
    Its exact Hopfield form has ``W = 2C`` between neighbours, ``W = -2`` on a
    shared row or column, no self-weight, and ``I = S + beta`` (Method-III:
    ``I = S + 2``), so every asynchronous flip changes the energy by exactly
    ``-u dy`` (:mod:`ismb_lab.hopfield`).  With ``beta = 2`` it is Method-III;
    with ``beta`` near 0 an isolated neuron turns on only when ``S + beta > 0``,
    i.e. when its windows look alike, and a neuron with support from compatible
    neighbours when ``S + beta + 2 sum C y > 0``: no match is an answer.

    Examples
    --------
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [40.0, 60.0]])
    >>> net = get_method("NM").network(p, Params(match_bias=0.0))
    >>> float(net.match_bias), float(net.target_count)
    (0.0, 0.5)
    """

    name = "NM"
    genes = MethodIII.genes + ("match_bias",)
    description = "Method-III with 'at most one' uniqueness and a match bias (fifth gene)"

    def network(self, problem: Problem, params: Params) -> Network:
        if not isinstance(params, Params):
            raise ParameterTypeError(message("params", "Method-NM", "a Params instance", params))
        if params.match_bias is None:
            raise ParameterError(message("params", "Method-NM", "Params with a match_bias (its fifth "
                                         "gene)", params))
        base = super().network(problem, params)
        return Network._trusted(problem.topology, base.similarity, base.pair_c, base.self_c,
                                1.0, params.match_bias)


class MethodNM4(MethodNM):
    """Method-NM with ``beta = 0`` fixed: "at most one match" and four genes.

    ``h = 1/2``: no match and one match cost the same, two cost more, so a
    neuron stays on only when ``S`` and the compatible neighbours pay for it.
    The genes are Method-III's; a ``match_bias`` in `params` is ignored.

    Examples
    --------
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [40.0, 60.0]])
    >>> net = get_method("NM4").network(p, Params())
    >>> float(net.match_bias), get_method("NM4").genes
    (0.0, ('theta_c', 'theta_s', 'lambda_c', 'lambda_s'))
    """

    name = "NM4"
    genes = MethodIII.genes
    description = "Method-III with 'at most one' uniqueness (match bias 0), four genes"

    def network(self, problem: Problem, params: Params) -> Network:
        if not isinstance(params, Params):
            raise ParameterTypeError(message("params", "Method-NM4", "a Params instance", params))
        return super().network(problem, replace(params, match_bias=0.0))


_METHODS = {m.name: m for m in (MethodI(), MethodII(), MethodIII(), MethodNM(), MethodNM4())}


def get_method(name) -> Method:
    """Look a method up by name: ``"I"``, ``"II"``, ``"III"``, ``"NM"`` or ``"NM4"`` (a ``Method`` passes through).

    Examples
    --------
    >>> get_method("NM")
    Method-NM
    >>> get_method("V")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'method' parameter of get_method must be one of 'I', 'II', 'III', 'NM', 'NM4'. Got 'V' instead.
    """
    if isinstance(name, Method):
        return name
    check_choice(name, "method", "get_method", tuple(_METHODS))
    return _METHODS[name]
