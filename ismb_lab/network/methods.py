"""Methods I, II, III and beyond as energy recipes (thesis §3.3, §5.2).

A method turns a :class:`Problem` and its :class:`Params` into a
:class:`~ismb_lab.network.hopfield.Network`, and may post-process the final state.

* **Method-I** (Achour & Mahiddine 2002) is a reconstruction from the thesis' description:
  ``X = dd + dD + (M_ik + M_jl) / 2``, ``S = 0``, two parameters, and vertical disparity
  only afterwards, to remove multiple matches.
* **Method-II**: ``S = transfer(M, theta_s, lambda_s)`` and ``X = dd + dD``.
* **Method-III** (ISMB): Method-II plus the vertical-disparity term, ``X = dd + dD + dY``.
* **Method-NM**, **NM4**, **NM3** (beyond the thesis): Method-III with a uniqueness term
  that lets a feature stay unmatched (:mod:`ismb_lab.network.hopfield`).

:func:`register_method` adds a method; the command line, the GA and the widgets list
whatever is registered.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from functools import cached_property

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_choice, message
from .compatibility import NeuronPairs, left_neighbours, neuron_pairs
from .hopfield import Network, Topology
from .params import LAMBDA_C, LAMBDA_S, MATCH_BIAS, THETA_C, THETA_S, Gene, Params
from .similarity import candidate_mask, no_match_cut, transfer

__all__ = ["BATCHED", "all_genes", "Method", "MethodI", "MethodII", "MethodIII", "MethodNM", "MethodNM3", "MethodNM4",
           "DEFAULT_METHOD", "Problem", "THESIS_PARAMS", "build_problem", "get_method", "method_names",
           "register_method", "unregister_method"]


@dataclass(frozen=True, eq=False)
class Problem:
    """The parameter-free ingredients of one image pair's energy, computed once for a GA.

    Attributes
    ----------
    left_xy, right_xy : (N_l, 2), (N_r, 2) float ndarray
        The features ``(x, y)`` of each image.
    dissimilarity : (N_l, N_r) ndarray
        ``M_ik`` (3-8).
    rows, cols : (n,) int ndarray
        Candidate neurons ``(i, k)``, sorted.
    pairs : NeuronPairs
        Interacting neuron pairs with their ``dd``, ``dD``, ``dY``.
    topology : Topology
        The neurons and pairs, shared by every network of the pair.
    """

    left_xy: np.ndarray
    right_xy: np.ndarray
    dissimilarity: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    pairs: NeuronPairs
    topology: Topology
    # each method's X and self-X (Method._measures), kept: a GA asks for them on every chromosome
    _measures: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def n_neurons(self) -> int:
        """int: candidate neurons."""
        return len(self.rows)

    def __getstate__(self) -> dict:
        # a process pool gets the ingredients, not what this process derived from them
        state = dict(self.__dict__)
        state["_measures"] = {}
        state.pop("neuron_dissimilarity", None)
        state.pop("no_match_cut", None)
        return state

    @cached_property
    def neuron_dissimilarity(self) -> np.ndarray:
        """``M_ik`` of every candidate neuron, in neuron order (read-only)."""
        m = self.dissimilarity[self.rows, self.cols]
        m.setflags(write=False)
        return m

    @cached_property
    def no_match_cut(self) -> float:
        """Half the median of ``M`` (:func:`ismb_lab.network.similarity.no_match_cut`)."""
        return no_match_cut(self.dissimilarity)


def build_problem(left_xy, right_xy, dissimilarity, *, shift: float = 20.0,
                  window_height: float = 30.0, window_width: float = 40.0,
                  radius: float = 20.0, neighbourhood: str = "box") -> Problem:
    """Candidate neurons and their interacting pairs for one image pair.

    `dissimilarity` is ``M_ik`` (:func:`~ismb_lab.network.similarity.mean_abs_difference`);
    the window options are :func:`~ismb_lab.network.similarity.candidate_mask`'s, and
    `radius` and `neighbourhood` those of :func:`~ismb_lab.network.compatibility.left_neighbours`.

    Parameters
    ----------
    left_xy, right_xy : (N_l, 2), (N_r, 2) float array
        Features ``(x, y)`` of each image.
    dissimilarity : (N_l, N_r) float array
        ``M_ik`` (3-8).
    shift : float, default 20.0
        Pixels left of each left feature at which the candidate window is centred.
    window_height, window_width : float, default 30.0, 40.0
        Size of the candidate window.
    radius : float, default 20.0
        Radius within which left features interact.
    neighbourhood : {"box", "disc"}, default "box"
        Shape of that neighbourhood.

    Returns
    -------
    problem : Problem
        The candidates, their interacting pairs and ``M``.

    Raises
    ------
    ParameterError
        `dissimilarity` not of shape ``(N_l, N_r)``, or a bad window.

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
    """An energy recipe: how ``S`` and ``X`` are formed, and any post-processing (see :func:`get_method`).

    Attributes
    ----------
    name : str
        Registry name (``"III"``).
    section : str
        Where the thesis describes it.
    genes : tuple of Gene
        The parameters a GA searches.
    defaults : Params
        Default parameters (the thesis' GA values where it has them).
    fixed : dict
        Parameters the method runs with whatever ``params`` says.
    derived : tuple of str
        Parameters the method sets from each image pair.
    description : str
        One line for help texts.
    """

    name: str = ""
    section: str = ""
    genes: tuple[Gene, ...] = ()
    defaults: Params = Params()
    #: Parameters the method runs with whatever ``params`` says (Method-NM4: a match bias of 0).
    fixed: dict = {}
    #: Parameters the method sets from each image pair, whatever ``params`` says (Method-NM3: theta_s).
    derived: tuple = ()
    description: str = ""

    @property
    def gene_names(self) -> tuple[str, ...]:
        """tuple of str: the names of :attr:`genes`."""
        return tuple(g.name for g in self.genes)

    def similarity(self, problem: Problem, params: Params) -> np.ndarray:
        """``S`` of every candidate neuron (3-10).

        Parameters
        ----------
        problem : Problem
            The pair's energy ingredients.
        params : Params
            The energy parameters.

        Returns
        -------
        S : (n,) float array
            In ``[-1, 1]``.
        """
        return transfer(problem.neuron_dissimilarity, params.theta_s, params.lambda_s)

    def pair_measure(self, problem: Problem) -> np.ndarray:
        """``X`` for every interacting pair, and ``X`` of a neuron with itself.

        Parameters
        ----------
        problem : Problem
            The pair's energy ingredients.

        Returns
        -------
        X : (P,) float array
            ``X`` of each interacting pair.
        """
        raise NotImplementedError

    def self_measure(self, problem: Problem) -> np.ndarray:
        """``X`` of each neuron with itself (zeros unless the method says otherwise).

        Parameters
        ----------
        problem : Problem
            The pair's energy ingredients.

        Returns
        -------
        X : (n,) float array
            One value per neuron.
        """
        return np.zeros(problem.n_neurons)

    def network(self, problem: Problem, params: Params) -> Network:
        """The network whose energy (3-15) this method minimises.

        Parameters
        ----------
        problem : Problem
            The pair's energy ingredients.
        params : Params
            The energy parameters.

        Returns
        -------
        net : Network
            The network of `problem` with these parameters.

        Raises
        ------
        ParameterTypeError
            `params` not a Params.
        """
        if not isinstance(params, Params):
            raise ParameterTypeError(message("params", f"Method-{self.name}", "a Params instance", params))
        pair_x, self_x = self._measures(problem)
        c = transfer(pair_x, params.theta_c, params.lambda_c)
        self_c = transfer(self_x, params.theta_c, params.lambda_c)
        # Params are validated finite and transfer() maps finite input into [-1, 1].
        return Network._trusted(problem.topology, self.similarity(problem, params), c, self_c)

    def _measures(self, problem: Problem) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`pair_measure` and :meth:`self_measure`, computed once per problem (read-only)."""
        kept = problem._measures.get(self)
        if kept is None:
            kept = tuple(np.array(x, dtype=float) for x in (self.pair_measure(problem), self.self_measure(problem)))
            for x in kept:
                x.setflags(write=False)
            problem._measures[self] = kept
        return kept

    def batch_columns(self, problem: Problem, table: dict, thesis: bool):
        """``(S, C, self_C, match_bias)`` of the networks :meth:`network` builds from each row
        of `table` (an ``(m,)`` array per :class:`Params` field), for a GA's batch; ``self_C``
        only for the thesis rule.  The same operations on the same numbers, element by
        element.  Only the built-in methods (:data:`BATCHED`) use it."""
        pair_x, self_x = self._measures(problem)
        theta_c, lambda_c = table["theta_c"][:, None], table["lambda_c"][:, None]
        c = transfer(pair_x, theta_c, lambda_c)
        self_c = transfer(self_x, theta_c, lambda_c) if thesis else None
        return self._similarities(problem, table), c, self_c, self._match_biases(table)

    def _similarities(self, problem: Problem, table: dict) -> np.ndarray:
        return transfer(problem.neuron_dissimilarity, table["theta_s"][:, None], table["lambda_s"][:, None])

    def _match_biases(self, table: dict) -> np.ndarray:
        return np.full(len(table["theta_c"]), 2.0)   # Network's default, which network() keeps

    def postprocess(self, problem: Problem, on: np.ndarray) -> np.ndarray:
        """Which of the neurons that are on (indices `on`) stay matches; `on` itself by default.

        Parameters
        ----------
        problem : Problem
            The pair's energy ingredients.
        on : (m,) int array
            Indices of the neurons on.

        Returns
        -------
        kept : (m',) int array
            The neurons that stay matches.
        """
        return on

    def __repr__(self) -> str:
        return f"Method-{self.name}"


class MethodI(Method):
    """Method-I: ``X = dd + dD + (M_ik + M_jl) / 2``, ``S = 0``, two parameters.

    Afterwards a feature matched more than once keeps only its match of least ``|y_k - y_i|``
    (left features first, then right; ties go to the lower index).
    """

    name, section, genes = "I", "§3.3, §5.2.1 (Achour & Mahiddine 2002)", (THETA_C, LAMBDA_C)
    #: The thesis' GA result; theta_s and lambda_s are unused placeholders.
    defaults = Params(theta_c=41.57, lambda_c=4.40)
    description = "X = dd + dD + mean(M); no S; vertical disparity only as post-processing"

    def similarity(self, problem, params):
        return np.zeros(problem.n_neurons)

    def pair_measure(self, problem):
        p = problem.pairs
        m = problem.neuron_dissimilarity
        return p.dd + p.dD + 0.5 * (m[p.a] + m[p.b])

    def self_measure(self, problem):
        return problem.neuron_dissimilarity

    def _similarities(self, problem, table):
        return np.zeros((len(table["theta_c"]), problem.n_neurons))

    def postprocess(self, problem, on):
        on = np.asarray(on, dtype=np.int64)
        dy = np.abs(problem.right_xy[problem.cols, 1] - problem.left_xy[problem.rows, 1])
        for owner in (problem.rows, problem.cols):
            ranked = on[np.lexsort((on, dy[on], owner[on]))]  # by feature, then |dy|, then index
            first = np.ones(len(ranked), dtype=bool)
            first[1:] = owner[ranked][1:] != owner[ranked][:-1]
            on = np.sort(ranked[first])
        return on


class MethodII(Method):
    """Method-II: separate similarity ``S``, ``X = dd + dD``."""

    name, section, genes = "II", "§3.3, §5.2.1", (THETA_C, THETA_S, LAMBDA_C, LAMBDA_S)
    defaults = Params(theta_c=11.51, theta_s=26.24, lambda_c=8.89, lambda_s=1.16)
    description = "S from M; X = dd + dD"

    def pair_measure(self, problem):
        return problem.pairs.dd + problem.pairs.dD


class MethodIII(Method):
    """Method-III (ISMB): separate similarity ``S``, ``X = dd + dD + dY``."""

    name, section, genes = "III", "§3.2, §5.2.2 (ISMB)", (THETA_C, THETA_S, LAMBDA_C, LAMBDA_S)
    defaults = Params(theta_c=17.97, theta_s=24.02, lambda_c=6.37, lambda_s=2.2)
    description = "S from M; X = dd + dD + dY (vertical disparity)"

    def pair_measure(self, problem):
        return problem.pairs.dd + problem.pairs.dD + problem.pairs.dY


class MethodNM(MethodIII):
    """Method-NM: Method-III's ``S`` and ``C`` with ``(h - r)^2``, ``h = 1/2 + beta / 4``, for ``(1 - r)^2``.

    ``beta`` is the fifth gene ``params.match_bias``: 2 is Method-III, near 0 no match is an
    answer (:mod:`ismb_lab.network.hopfield`).

    Examples
    --------
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [40.0, 60.0]])
    >>> net = get_method("NM").network(p, Params(match_bias=0.0))
    >>> float(net.match_bias), float(net.target_count)
    (0.0, 0.5)
    """

    name, section = "NM", "beyond the thesis (README)"
    genes = MethodIII.genes + (MATCH_BIAS,)
    #: Not fitted: Method-III's values with "at most one match", a neutral start for the GA.
    defaults = replace(MethodIII.defaults, match_bias=0.0)
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

    def _match_biases(self, table):
        return table["match_bias"]


class MethodNM4(MethodNM):
    """Method-NM with ``beta = 0`` fixed ("at most one match") and Method-III's four genes.

    One gene less for the GA to overfit a pair's count of unmatched corners with.

    Examples
    --------
    >>> net = get_method("NM4").network(build_problem([[100, 50]], [[80, 51]], [[2.0]]), Params())
    >>> float(net.match_bias), get_method("NM4").gene_names
    (0.0, ('theta_c', 'theta_s', 'lambda_c', 'lambda_s'))
    """

    name, section = "NM4", "beyond the thesis (README)"
    genes = MethodIII.genes
    defaults = MethodIII.defaults
    fixed = {"match_bias": 0.0}
    description = "Method-III with 'at most one' uniqueness (match bias 0), four genes"

    def network(self, problem: Problem, params: Params) -> Network:
        if not isinstance(params, Params):
            raise ParameterTypeError(message("params", "Method-NM4", "a Params instance", params))
        return super().network(problem, replace(params, **self.fixed))

    def _match_biases(self, table):
        return np.full(len(table["theta_c"]), float(self.fixed["match_bias"]))


class MethodNM3(MethodNM4):
    """Method-NM4 with ``theta_s`` the pair's :attr:`Problem.no_match_cut`: three genes.

    The cut moves with a camera's gain or a scene's texture; a ``theta_s`` in `params` is unused.

    Examples
    --------
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [40.0, 3.0]])
    >>> m = get_method("NM3")
    >>> p.no_match_cut, m.gene_names
    (10.75, ('theta_c', 'lambda_c', 'lambda_s'))
    >>> bool(np.array_equal(m.network(p, Params(theta_s=1.0)).similarity,
    ...                     m.network(p, Params(theta_s=50.0)).similarity))
    True
    """

    name, section = "NM3", "beyond the thesis (README)"
    genes = (THETA_C, LAMBDA_C, LAMBDA_S)
    derived = ("theta_s",)
    description = "Method-NM4 with theta_s from the pair (half the median of M), three genes"

    def similarity(self, problem: Problem, params: Params) -> np.ndarray:
        return transfer(problem.neuron_dissimilarity, problem.no_match_cut, params.lambda_s)

    def _similarities(self, problem, table):
        return transfer(problem.neuron_dissimilarity, problem.no_match_cut, table["lambda_s"][:, None])


_METHODS: dict[str, Method] = {}


def register_method(method: Method) -> Method:
    """Add a method to the registry (a new name, distinct genes, Params defaults).

    Returns `method`.

    Parameters
    ----------
    method : Method
        An instance with a new name, distinct genes and Params defaults.

    Returns
    -------
    method : Method
        `method` itself.

    Raises
    ------
    ParameterError, ParameterTypeError
        A name already taken, no or repeated genes, or defaults that are not Params.

    Examples
    --------
    >>> class Flat(MethodIII):
    ...     name, description = "FLAT", "Method-III without the similarity term"
    ...     def similarity(self, problem, params):
    ...         return np.zeros(problem.n_neurons)
    >>> register_method(Flat()); "FLAT" in method_names()
    Method-FLAT
    True
    >>> unregister_method("FLAT"); "FLAT" in method_names()
    False
    """
    own = "register_method"
    if not isinstance(method, Method):
        raise ParameterTypeError(message("method", own, "a Method instance", method))
    if not isinstance(method.name, str) or not method.name or method.name in _METHODS:
        raise ParameterError(message("method", own, "a method with a new, non-empty name",
                                     f"name {method.name!r}"))
    names = [g.name for g in method.genes]
    if not names or not all(isinstance(g, Gene) for g in method.genes) or len(set(names)) != len(names):
        raise ParameterError(message("method", own, "a method with one or more distinct Gene objects",
                                     method.genes))
    if not isinstance(method.defaults, Params):
        raise ParameterTypeError(message("method", own, "a method whose defaults are Params",
                                         method.defaults))
    _METHODS[method.name] = method
    return method


def unregister_method(name: str) -> None:
    """Remove a method added by :func:`register_method`."""
    check_choice(name, "name", "unregister_method", tuple(_METHODS))
    del _METHODS[name]


def all_genes() -> tuple[Gene, ...]:
    """Every registered method's genes, each once, in the order of :class:`Params`' fields.

    Examples
    --------
    >>> [g.name for g in all_genes()]
    ['theta_c', 'theta_s', 'lambda_c', 'lambda_s', 'match_bias']
    """
    seen = {}
    for method in _METHODS.values():
        for gene in method.genes:
            seen.setdefault(gene.name, gene)
    return tuple(seen[f.name] for f in fields(Params) if f.name in seen)


def method_names() -> tuple[str, ...]:
    """The registered methods' names, in registration order.

    Examples
    --------
    >>> method_names()
    ('I', 'II', 'III', 'NM', 'NM4', 'NM3')
    """
    return tuple(_METHODS)


class _Defaults(Mapping):
    """Each registered method's default parameters, by name (a live view of the registry)."""

    def __getitem__(self, name):
        return get_method(name).defaults

    def __iter__(self):
        return iter(_METHODS)

    def __len__(self):
        return len(_METHODS)

    def __repr__(self):
        return "THESIS_PARAMS(" + ", ".join(f"{k}={v!r}" for k, v in self.items()) + ")"


#: Each method's ``defaults``: the thesis' GA results (§5.2.1, §5.2.2) for I, II and III.
THESIS_PARAMS = _Defaults()

for _method in (MethodI(), MethodII(), MethodIII(), MethodNM(), MethodNM4(), MethodNM3()):
    register_method(_method)

#: The methods whose networks :meth:`Method.batch_columns` builds for a batch of parameter sets.
BATCHED = (MethodI, MethodII, MethodIII, MethodNM, MethodNM4, MethodNM3)

#: The method used wherever none is named: the thesis' own.
DEFAULT_METHOD = MethodIII.name


def get_method(name) -> Method:
    """Look a method up by name (a ``Method`` passes through).

    Parameters
    ----------
    name : str or Method
        A name of :func:`method_names`, or a Method.

    Returns
    -------
    method : Method
        The registered method.

    Raises
    ------
    ParameterError
        An unknown name.

    Examples
    --------
    >>> get_method("NM")
    Method-NM
    >>> get_method("V")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'method' parameter of get_method must be one of 'I', 'II', 'III', 'NM', 'NM4', 'NM3'. Got 'V' instead.
    """
    if isinstance(name, Method):
        return name
    check_choice(name, "method", "get_method", method_names())
    return _METHODS[name]

