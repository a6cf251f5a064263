"""Peer matchers that see what the network sees: the corners, ``M`` and candidate neurons of a
:class:`~ismb_lab.network.methods.Problem`.  Each returns one-to-one ``(i, k)`` candidate
pairs, an ``(m, 2)`` int array sorted by ``i``.

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
    """Mutual nearest neighbours on ``M`` among candidate neurons (ties to the lower index),
    without matches whose ``M_ik`` is above `max_dissimilarity`.

    Parameters
    ----------
    problem : Problem
        Corners, ``M`` and candidate neurons (:func:`ismb_lab.network.methods.build_problem`).
    max_dissimilarity : float, optional
        Largest ``M_ik`` kept; None keeps all.

    Returns
    -------
    pairs : (m, 2) int array
        One-to-one ``(i, k)`` candidate pairs, sorted by ``i``.

    Raises
    ------
    ParameterTypeError
        `problem` is not a Problem.

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

    Dummy rows and columns make leaving a feature unmatched cost ``no_match_cost / 2``, so no
    match with ``M_ik > no_match_cost`` (grey levels, > 0) is kept; non-candidates never are.

    Parameters
    ----------
    problem : Problem
        Corners, ``M`` and candidate neurons (:func:`ismb_lab.network.methods.build_problem`).
    no_match_cost : float
        Cost of leaving a left and a right feature unmatched, in grey levels (> 0).

    Returns
    -------
    pairs : (m, 2) int array
        One-to-one ``(i, k)`` candidate pairs, sorted by ``i``.

    Raises
    ------
    ParameterTypeError
        `problem` is not a Problem.
    ParameterError
        `no_match_cost` not > 0.

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
    """The affinity ``K`` of the method's energy in pygmtools' layout: neuron ``(i, k)`` at
    ``k * N_l + i``, ``(S + 1) / 2`` on the diagonal, ``(C + 1) / 2`` for interacting pairs, 0
    elsewhere (non-negative, as SM and RRWM need).  `params` default to the method's.

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
    """Match by RRWM (Cho et al. 2010) or spectral matching (Leordeanu & Hebert 2005) on
    :func:`affinity_matrix` (pygmtools, numpy backend per call), discretised by the Hungarian
    algorithm, candidates only.

    `max_dissimilarity` drops matches with ``M_ik`` above it: the Hungarian step matches
    occluded features too, and the soft scores do not tell them apart.

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
    """The no-match cut of :data:`PEERS`: half the median of ``M`` over all feature pairs.

    Parameters
    ----------
    problem : Problem
        Corners, ``M`` and candidate neurons (:func:`ismb_lab.network.methods.build_problem`).

    Returns
    -------
    cut : float
        The cut, in grey levels.

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


#: Peer matchers by name, ``f(problem, method=DEFAULT_METHOD, params=None) -> pairs``, each with the
#: cut of :func:`default_no_match_cost`; ``mutual-nn`` and ``hungarian`` use ``M`` only.
PEERS = {"mutual-nn": _mnn, "hungarian": _hungarian, "rrwm": _rrwm, "spectral": _spectral}
