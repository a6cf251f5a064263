"""How a network's final state is found, and how a final state becomes matches.

Four solvers minimise the same energy (3-15):

* ``"network"``: the thesis' discrete Hopfield network (:func:`ismb_lab.dynamics.run`),
  asynchronous flips from "all candidates on" to a fixed point; it honours the
  update rule, the stop rule and the kernel.
* ``"anneal"``: mean-field annealing (:func:`ismb_lab.annealing.anneal`), the analog
  network of the thesis' future work, polished by the discrete network.
* ``"exact"``: the global minimum as a mixed-integer programme
  (:func:`ismb_lab.exact.milp_minimum`).  It ignores the seed, and refuses a
  problem it cannot solve within its time limit.
* ``"assign"`` (beyond the thesis): the discrete network started not from "all on" but
  from the one-to-one assignment of largest total similarity ``S`` (only pairs with
  ``S > 0``, :func:`similarity_assignment`); the compatibility and uniqueness terms then
  add and remove matches by exact descent.  The peers' Hungarian assignment
  (:func:`ismb_lab.peers.hungarian`) is the same idea on ``M`` with a no-match cost.

:data:`SOLVERS` is the one registry of them, which the command line, the library
and the widgets read.  :func:`to_matches` is the one way from a final state to
matched ``(i, k)`` feature pairs, including a method's post-processing.

>>> from ismb_lab.hopfield import Network
>>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, -0.7],
...                           pair_a=[], pair_b=[], pair_c=[])
>>> [solve(net, name).state.tolist() for name in SOLVERS]
[[1, 0], [1, 0], [1, 0], [1, 0]]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, NamedTuple

import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_choice, check_number, message
from .annealing import anneal
from .exact import milp_minimum
from .hopfield import RULES, Network, _energy_of
from .dynamics import STOP_RULES, run

__all__ = ["ANNEAL", "ASSIGN", "DEFAULT_SOLVER", "EXACT", "NETWORK", "SOLVERS", "Matches", "Solution", "Solver",
           "get_solver", "matched_neurons", "one_match_per_corner", "similarity_assignment", "solve",
           "solver_names", "to_matches"]


@dataclass(frozen=True, eq=False)
class Solution:
    """A solver's final state.

    Attributes
    ----------
    state : (n,) uint8 ndarray
        Outputs of the candidate neurons, before any post-processing.
    stop_rule : str
        What stopped it: the network's ``"sweep"``, ``"stall"`` or ``"max_attempts"``,
        else the solver's name.
    attempts : int
        Update attempts of the discrete network (annealing: of its polishing run;
        exact: 0).
    net : Network
        The network solved.
    converged : bool
        False only when the network hit its attempt limit.
    energy : float
        Energy (3-15) of `state` (:func:`ismb_lab.hopfield.energy`), computed when first
        read: a GA solves thousands of networks and reads none.
    """

    state: np.ndarray
    stop_rule: str
    attempts: int
    net: Network = field(repr=False)
    converged: bool = True

    @cached_property
    def energy(self) -> float:
        return _energy_of(self.net, self.state)

    @classmethod
    def _of(cls, state, stop_rule, attempts, net, converged) -> "Solution":
        """The same record without the frozen ``__init__``'s ``object.__setattr__`` calls."""
        s = object.__new__(cls)
        d = s.__dict__
        d["state"], d["stop_rule"], d["attempts"], d["net"], d["converged"] = state, stop_rule, attempts, net, converged
        return s


@dataclass(frozen=True)
class Solver:
    """One way to minimise the energy: its name, what it is, and the function.

    ``solve(net, seed, stop_rule, rule, kernel) -> Solution``; `seeded` says whether
    the seed matters.
    """

    name: str
    description: str
    seeded: bool
    solve: Callable


def _network(net, seed, stop_rule, rule, kernel) -> Solution:
    r = run(net, rng=seed, stop_rule=stop_rule, rule=rule, kernel=kernel)
    return Solution._of(r.state, r.stop_rule, r.attempts, net, r.converged)


def _anneal(net, seed, stop_rule, rule, kernel) -> Solution:
    r = anneal(net, rng=seed)
    return Solution(r.state, ANNEAL, 0, net)


def _exact(net, seed, stop_rule, rule, kernel) -> Solution:
    r = milp_minimum(net)
    return Solution(r.state, EXACT, 0, net)


def similarity_assignment(net: Network) -> np.ndarray:
    """The state of the one-to-one assignment of largest total similarity.

    Among candidate neurons with ``S > 0``, at most one per left and per right
    feature, chosen to maximise the sum of ``S`` (:func:`scipy.optimize.linear_sum_assignment`);
    the others are off.  It ignores the compatibility terms.

    Examples
    --------
    >>> from ismb_lab.hopfield import Network
    >>> net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1],
    ...                           similarity=[0.9, 0.8, 0.7, -0.2], pair_a=[], pair_b=[], pair_c=[])
    >>> similarity_assignment(net).tolist()     # 0.8 + 0.7 beats 0.9 alone
    [0, 1, 1, 0]
    """
    from scipy.optimize import linear_sum_assignment

    if not isinstance(net, Network):
        raise ParameterTypeError(message("net", "similarity_assignment", "a Network", net))
    gain = np.zeros((net.n_left, net.n_right))
    good = net.similarity > 0
    gain[net.rows[good], net.cols[good]] = net.similarity[good]
    chosen = np.zeros((net.n_left, net.n_right), dtype=bool)
    left, right = linear_sum_assignment(gain, maximize=True)
    chosen[left, right] = gain[left, right] > 0
    return chosen[net.rows, net.cols].astype(np.uint8)


def _assign(net, seed, stop_rule, rule, kernel) -> Solution:
    r = run(net, rng=seed, state=similarity_assignment(net), stop_rule=stop_rule, rule=rule, kernel=kernel)
    return Solution(r.state, r.stop_rule, r.attempts, net, r.converged)


#: The solvers' names, for code that means one of them.
NETWORK, ANNEAL, EXACT, ASSIGN = "network", "anneal", "exact", "assign"

#: The solvers by name, in the order help texts list them.
SOLVERS = {s.name: s for s in (
    Solver(NETWORK, "the thesis' discrete network: asynchronous flips to a fixed point", True, _network),
    Solver(ANNEAL, "mean-field annealing, then the discrete network from the rounded state", True, _anneal),
    Solver(EXACT, "the global minimum energy as a mixed-integer programme (small problems)", False, _exact),
    Solver(ASSIGN, "the discrete network started from the assignment of largest total similarity "
                   "(beyond the thesis)", True, _assign),
)}

#: The thesis' solver, the default everywhere except the depth demo.
DEFAULT_SOLVER = NETWORK


def solver_names() -> tuple[str, ...]:
    """The registered solvers' names.

    >>> solver_names()
    ('network', 'anneal', 'exact', 'assign')
    """
    return tuple(SOLVERS)


def get_solver(name, owner: str = "get_solver", parameter: str = "solver") -> Solver:
    """Look a solver up by name, checked as `owner`'s argument `parameter`.

    >>> get_solver("annealing")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'solver' parameter of get_solver must be one of 'network', 'anneal', 'exact', 'assign'. Got 'annealing' instead.
    """
    return SOLVERS[check_choice(name, parameter, owner, solver_names())]


def solve(net: Network, solver: str = DEFAULT_SOLVER, *, seed: int = 0, stop_rule: str = "sweep",
          rule: str = "exact", kernel: str = "numba", owner: str = "solve") -> Solution:
    """Minimise `net`'s energy with one of :data:`SOLVERS`.

    Parameters
    ----------
    net : Network
    solver : str
        A name in :data:`SOLVERS`.
    seed : int
        Update-order (and annealing) seed; the exact solver ignores it.
    stop_rule, rule, kernel
        The discrete network's settings (:func:`ismb_lab.dynamics.run`); the
        ``"network"`` and ``"assign"`` solvers read them.
    owner : str
        The function named in error messages.

    Returns
    -------
    Solution
    """
    chosen = get_solver(solver, owner)
    if not isinstance(net, Network):
        raise ParameterTypeError(message("net", owner, "a Network", net))
    # a GA solves thousands of networks: the common arguments pass without a call
    if not (type(seed) is int and seed >= 0 and stop_rule in STOP_RULES and rule in RULES):
        check_number(seed, "seed", owner, low=0, integer=True)
        check_choice(stop_rule, "stop_rule", owner, STOP_RULES)
        check_choice(rule, "rule", owner, RULES)
    return chosen.solve(net, seed, stop_rule, rule, kernel)


class Matches(NamedTuple):
    """Matched feature pairs and the post-processed state they come from."""

    pairs: np.ndarray
    state: np.ndarray


def matched_neurons(neurons, state, method=None) -> np.ndarray:
    """Indices of the neurons that are matches in a final state, sorted: those that are on,
    less any that `method`'s :meth:`~ismb_lab.methods.Method.postprocess` drops.

    :func:`to_matches` turns them into feature pairs; a GA that only counts them stops here.
    The arguments are :func:`to_matches`'.

    Examples
    --------
    >>> from ismb_lab.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], np.zeros((2, 2)))
    >>> matched_neurons(p, [1, 0, 0, 1]).tolist()
    [0, 3]
    """
    on = np.flatnonzero(np.asarray(state, dtype=np.uint8))
    kept = on if method is None else method.postprocess(neurons, on)
    return on if kept is on else np.sort(kept)   # a method that keeps every match returns `on` itself


def one_match_per_corner(problem, on, key=None) -> np.ndarray:
    """Of the matched neurons `on`, at most one per left and per right corner: the most similar.

    The neurons are taken by increasing ``M`` (or `key`; ties by index), and one is kept
    when neither of its corners has a kept match yet.  The "at most one" term of Methods NM,
    NM4 and NM3 makes a second match costly, but where two wrong matches support each
    other a solver can leave both on; this step removes them after solving.  It is a
    decoding option for testing (``match(..., one_to_one=True)``,
    ``ismb-lab match --one-to-one``); the GA's fitness does not apply it.

    Parameters
    ----------
    problem : Problem
        Anything with ``rows``, ``cols`` and ``neuron_dissimilarity``.
    on : (m,) int array_like
        Indices of the matched neurons (:func:`matched_neurons`).
    key : (m,) float array_like, optional
        The order in which they are taken, smallest first (default: their ``M``).

    Returns
    -------
    kept : (m',) int ndarray
        Sorted.

    Examples
    --------
    >>> from ismb_lab.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [30.0, 3.0]])
    >>> one_match_per_corner(p, [0, 1, 3]).tolist()   # left corner 0 twice: M 2 beats M 40
    [0, 3]
    """
    on = np.asarray(on, dtype=np.int64)
    if key is None:
        key = problem.neuron_dissimilarity[on]
    else:
        key = np.asarray(key, dtype=float).ravel()
        if len(key) != len(on):
            raise ParameterError(message("key", "one_match_per_corner",
                                         f"of length {len(on)}, one value per matched neuron", f"length {len(key)}"))
    if len(on) < 2:
        return on
    rows, cols = problem.rows, problem.cols
    left_used, right_used, kept = set(), set(), []
    for a in on[np.lexsort((on, key))].tolist():
        i, k = int(rows[a]), int(cols[a])
        if i not in left_used and k not in right_used:
            left_used.add(i)
            right_used.add(k)
            kept.append(a)
    return np.sort(np.array(kept, dtype=np.int64))


def to_matches(neurons, state, method=None) -> Matches:
    """The matched ``(i, k)`` feature pairs of a final state: the one place this is done.

    Parameters
    ----------
    neurons : Problem, Network or Topology
        Anything with the candidate neurons' ``rows`` and ``cols``.
    state : (n,) array_like of 0/1
        Outputs of the candidate neurons.
    method : Method, optional
        Its :meth:`~ismb_lab.methods.Method.postprocess` decides which of the
        neurons that are on stay matches (Method-I drops multiple matches).

    Returns
    -------
    Matches
        ``pairs`` (m, 2) int ndarray sorted by neuron, and the post-processed
        ``state`` (uint8).

    Examples
    --------
    >>> from ismb_lab.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], np.zeros((2, 2)))
    >>> to_matches(p, [1, 0, 0, 1]).pairs.tolist()
    [[0, 0], [1, 1]]
    """
    state = np.asarray(state, dtype=np.uint8)
    on = matched_neurons(neurons, state, method)
    if method is not None:
        state = np.zeros_like(state)
        state[on] = 1
    pairs = np.empty((len(on), 2), dtype=np.int64)
    pairs[:, 0] = neurons.rows[on]
    pairs[:, 1] = neurons.cols[on]
    return Matches(pairs, state)
