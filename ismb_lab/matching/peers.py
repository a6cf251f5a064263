"""Peer matchers on the network's own features and candidate window.

To judge the Hopfield network honestly, these matchers see exactly what it
sees: the corners, ``M`` and candidate neurons ``(i, k)`` of a
:class:`~ismb_lab.network.methods.Problem`.  Each returns one-to-one matches among
candidate neurons as an ``(m, 2)`` int array of ``(i, k)`` sorted by ``i``.

* :func:`mutual_nearest`: mutual nearest neighbours on ``M`` (appearance only);
* :func:`hungarian`: the optimal one-to-one assignment on ``M`` with a no-match cost;
* :func:`graph_matching`: RRWM or spectral matching (pygmtools) of the method's
  own ``S`` and ``C``, i.e. a standard solver of the thesis' quadratic objective.

:data:`PEERS` maps short names to callables ``f(problem, method=DEFAULT_METHOD, params=None)`` (the default method is :data:`ismb_lab.network.methods.DEFAULT_METHOD`).

>>> from ismb_lab.network.methods import build_problem
>>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [40.0, 3.0]])
>>> [PEERS[name](p).tolist() for name in PEERS]
[[[0, 0], [1, 1]], [[0, 0], [1, 1]], [[0, 0], [1, 1]], [[0, 0], [1, 1]]]
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from .._core.validation import ParameterError, ParameterTypeError, check_choice, check_number, message
from ..network.methods import DEFAULT_METHOD, Problem, get_method
from ..network.params import Params

__all__ = ["MAX_ASSIGNMENTS", "PEERS", "affinity_matrix", "default_no_match_cost", "graph_matching",
           "hungarian", "mutual_nearest"]

#: Largest ``N_l * N_r`` for :func:`graph_matching`: its dense affinity has this size squared.
MAX_ASSIGNMENTS = 5000


def _check_problem(problem, owner: str) -> Problem:
    if not isinstance(problem, Problem):
        raise ParameterTypeError(message("problem", owner, "a Problem", type(problem).__name__))
    return problem


def _pairs(rows, cols) -> np.ndarray:
    rows, cols = np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)
    order = np.argsort(rows, kind="stable")
    return np.stack([rows[order], cols[order]], axis=1).reshape(-1, 2)


def _candidate_costs(problem: Problem) -> np.ndarray:
    """``M`` on candidate neurons, ``inf`` elsewhere."""
    cost = np.full(problem.dissimilarity.shape, np.inf)
    cost[problem.rows, problem.cols] = problem.neuron_dissimilarity
    return cost


def mutual_nearest(problem, max_dissimilarity=None) -> np.ndarray:
    """Mutual nearest neighbours on ``M``, among candidate neurons only.

    ``(i, k)`` is kept when ``k`` is the candidate of ``i`` with the smallest ``M``
    and ``i`` that of ``k`` (ties go to the lower index).

    Parameters
    ----------
    problem : Problem
    max_dissimilarity : float, optional
        Also drop matches with ``M_ik`` above this value.

    Returns
    -------
    pairs : (m, 2) int ndarray
        Matched ``(i, k)``, sorted by ``i``.

    Examples
    --------
    >>> from ismb_lab.network.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[1.0, 4.0], [2.0, 3.0]])
    >>> mutual_nearest(p)      # left 1 prefers right 0, which prefers left 0
    array([[0, 0]])
    """
    problem = _check_problem(problem, "mutual_nearest")
    cost = _candidate_costs(problem)
    if max_dissimilarity is not None:
        limit = check_number(max_dissimilarity, "max_dissimilarity", "mutual_nearest")
        cost[cost > limit] = np.inf
    if not np.isfinite(cost).any():
        return np.zeros((0, 2), dtype=np.int64)
    best_k = np.argmin(cost, axis=1)
    best_i = np.argmin(cost, axis=0)
    rows = np.flatnonzero(np.isfinite(cost.min(axis=1)))
    rows = rows[best_i[best_k[rows]] == rows]
    return _pairs(rows, best_k[rows])


def hungarian(problem, no_match_cost) -> np.ndarray:
    """The one-to-one assignment of least total ``M``, where a feature may stay unmatched.

    The cost matrix is ``M`` on candidate neurons (``inf`` elsewhere) augmented
    with one dummy column per left feature and one dummy row per right feature:
    leaving a feature unmatched costs ``no_match_cost / 2``, so the solver
    minimises ``sum(M_ik - no_match_cost)`` over the matches and never keeps a
    match with ``M_ik > no_match_cost``; non-candidates are never returned.

    Parameters
    ----------
    problem : Problem
    no_match_cost : float
        The largest ``M`` worth a match, > 0, in the units of ``M`` (grey levels).

    Returns
    -------
    pairs : (m, 2) int ndarray
        Matched ``(i, k)``, sorted by ``i``.

    Examples
    --------
    >>> from ismb_lab.network.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[1.0, 4.0], [2.0, 30.0]])
    >>> hungarian(p, no_match_cost=10).tolist()     # 4 + 2 beats 1 alone
    [[0, 1], [1, 0]]
    >>> hungarian(p, no_match_cost=3).tolist()
    [[0, 0]]
    """
    problem = _check_problem(problem, "hungarian")
    half = check_number(no_match_cost, "no_match_cost", "hungarian", low=0, low_open=True) / 2
    n_l, n_r = problem.dissimilarity.shape
    cost = np.zeros((n_l + n_r, n_r + n_l))
    cost[:n_l, :n_r] = _candidate_costs(problem)
    cost[:n_l, n_r:] = np.where(np.eye(n_l, dtype=bool), half, np.inf)   # left i unmatched
    cost[n_l:, :n_r] = np.where(np.eye(n_r, dtype=bool), half, np.inf)   # right k unmatched
    rows, cols = linear_sum_assignment(cost)
    real = (rows < n_l) & (cols < n_r)
    return _pairs(rows[real], cols[real])


def affinity_matrix(problem, method=DEFAULT_METHOD, params=None) -> np.ndarray:
    """The non-negative affinity ``K`` of the method's energy, in pygmtools' layout.

    ``K`` spans the full ``N_l x N_r`` assignment space in pygmtools' column-major
    ``vec`` order: neuron ``(i, k)`` has index ``k * N_l + i``.  Its diagonal is
    ``(S + 1) / 2`` of the candidate neurons, its off-diagonal ``(C + 1) / 2`` of
    the interacting pairs; all else is 0.  Mapping ``[-1, 1]`` to ``[0, 1]``
    keeps ``K`` non-negative, as SM and RRWM need; ``C = -1`` then counts like no
    interaction.

    Parameters
    ----------
    problem : Problem
    method : {"I", "II", "III"}
        Which energy's ``S`` and ``C`` (see :mod:`ismb_lab.network.methods`).
    params : Params, optional
        By default the thesis' GA values for the method.

    Returns
    -------
    K : (N_l * N_r, N_l * N_r) ndarray
        Symmetric, entries in ``[0, 1]``.

    Examples
    --------
    >>> from ismb_lab.network.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], np.full((2, 2), 24.02))
    >>> affinity_matrix(p).round(2)     # S = 0 on the diagonal; vec order (0,0) (1,0) (0,1) (1,1)
    array([[0.5, 0. , 0. , 1. ],
           [0. , 0.5, 0. , 0. ],
           [0. , 0. , 0.5, 0. ],
           [1. , 0. , 0. , 0.5]])
    """
    problem = _check_problem(problem, "affinity_matrix")
    m = get_method(method)
    params = m.defaults if params is None else params
    if not isinstance(params, Params):
        raise ParameterTypeError(message("params", "affinity_matrix", "a Params instance", params))
    n_l, n_r = problem.dissimilarity.shape
    if n_l * n_r > MAX_ASSIGNMENTS:
        raise ParameterError(message("problem", "affinity_matrix", f"at most {MAX_ASSIGNMENTS} "
                                     "left x right feature pairs (K is dense)", f"{n_l} x {n_r}"))
    net = m.network(problem, params)
    idx = problem.cols * n_l + problem.rows
    a, b = idx[problem.pairs.a], idx[problem.pairs.b]
    K = np.zeros((n_l * n_r, n_l * n_r))
    K[idx, idx] = (net.similarity + 1) / 2
    K[a, b] = K[b, a] = (net.pair_c + 1) / 2
    return K


def graph_matching(problem, method=DEFAULT_METHOD, params=None, *, solver="rrwm",
                   max_dissimilarity=None) -> np.ndarray:
    """Match by graph matching (pygmtools) on the method's own similarity and compatibility.

    Solves ``max vec(X)' K vec(X)`` with ``K`` from :func:`affinity_matrix`,
    by RRWM (Cho et al. 2010) or spectral matching (Leordeanu & Hebert 2005)
    on pygmtools' numpy backend (passed per call: the global
    ``pygmtools.BACKEND`` is left alone), then discretises with the Hungarian
    algorithm and keeps candidate neurons only.

    Parameters
    ----------
    problem : Problem
    method, params
        As in :func:`affinity_matrix`.
    solver : {"rrwm", "sm"}
        The continuous solver.
    max_dissimilarity : float, optional
        The no-match rule: drop matches with ``M_ik`` above it (the Hungarian
        step matches all it can, occluded features too).  The soft score is no
        use for this (measured on the synthetic scenes): RRWM's Sinkhorn jumps
        give every row similar mass, so wrong matches score 0.2-0.9 of the top
        score like true ones (0.6-1); SM's leading eigenvector gathers on one
        cluster of neighbouring features and scores true matches elsewhere ~0.

    Returns
    -------
    pairs : (m, 2) int ndarray
        Matched ``(i, k)``, sorted by ``i``.

    Examples
    --------
    >>> from ismb_lab.network.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [40.0, 3.0]])
    >>> graph_matching(p, solver="sm").tolist()
    [[0, 0], [1, 1]]
    """
    import pygmtools

    owner = "graph_matching"
    check_choice(solver, "solver", owner, ("rrwm", "sm"))
    if max_dissimilarity is not None:
        max_dissimilarity = check_number(max_dissimilarity, "max_dissimilarity", owner)
    K = affinity_matrix(_check_problem(problem, owner), method, params)
    n_l, n_r = problem.dissimilarity.shape
    if problem.n_neurons == 0:
        return np.zeros((0, 2), dtype=np.int64)
    solve = pygmtools.rrwm if solver == "rrwm" else pygmtools.sm
    soft = solve(K, n_l, n_r, backend="numpy")
    hard = pygmtools.hungarian(soft, backend="numpy")
    keep = np.zeros((n_l, n_r), dtype=bool)
    keep[problem.rows, problem.cols] = True
    keep &= hard > 0.5
    if max_dissimilarity is not None:
        keep &= problem.dissimilarity <= max_dissimilarity
    return _pairs(*np.nonzero(keep))


def default_no_match_cost(problem) -> float:
    """The no-match cut of :data:`PEERS`: half the median of ``M`` over all feature pairs
    (:func:`ismb_lab.network.similarity.no_match_cut`).

    Examples
    --------
    >>> from ismb_lab.network.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [40.0, 3.0]])
    >>> default_no_match_cost(p)
    10.75
    """
    return _check_problem(problem, "default_no_match_cost").no_match_cut


def _mnn(problem, method=DEFAULT_METHOD, params=None):
    return mutual_nearest(problem, default_no_match_cost(problem))


def _hungarian(problem, method=DEFAULT_METHOD, params=None):
    return hungarian(problem, default_no_match_cost(problem))


def _rrwm(problem, method=DEFAULT_METHOD, params=None):
    return graph_matching(problem, method, params, max_dissimilarity=default_no_match_cost(problem))


def _spectral(problem, method=DEFAULT_METHOD, params=None):
    return graph_matching(problem, method, params, solver="sm",
                          max_dissimilarity=default_no_match_cost(problem))


#: Peer matchers by name, each ``f(problem, method=DEFAULT_METHOD, params=None) -> pairs``.
#: All four refuse matches with ``M_ik`` above :func:`default_no_match_cost`;
#: ``mutual-nn`` and ``hungarian`` use ``M`` only (they ignore `method` and
#: `params`), ``rrwm`` and ``spectral`` the method's ``S`` and ``C`` (thesis GA
#: parameters by default).  The network has no such cut: for a like-for-like
#: look, call the functions without it.
PEERS = {"mutual-nn": _mnn, "hungarian": _hungarian, "rrwm": _rrwm, "spectral": _spectral}
