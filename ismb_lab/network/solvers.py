"""How a network's final state is found, and how a final state becomes matches.

Four solvers minimise the same energy (3-15), each a frozen dataclass of its own options:
``"network"``, the thesis' discrete network from "all on"; ``"anneal"``, mean-field
annealing polished by the discrete network; ``"exact"``, the global minimum as a
mixed-integer programme (it ignores the seed); and ``"assign"`` (beyond the thesis), the
discrete network started from the assignment of largest total similarity.
:data:`SOLVERS` is their registry; :func:`to_matches` is the one way from a final state to
matched ``(i, k)`` feature pairs.

>>> from ismb_lab.network.hopfield import Network
>>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, -0.7],
...                           pair_a=[], pair_b=[], pair_c=[])
>>> [solve(net, name).state.tolist() for name in SOLVERS]
[[1, 0], [1, 0], [1, 0], [1, 0]]
>>> get_solver("anneal", cooling=0.95)
AnnealSolver(t_start=2.0, t_end=0.02, cooling=0.95, sweeps=2, settle=0.0)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields, replace
from functools import cached_property
from typing import ClassVar, NamedTuple

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_choice, check_number, message
from .annealing import anneal, check_schedule_options, check_settle
from .exact import MAX_TIME_LIMIT, milp_minimum
from .hopfield import RULES, Network, _energy_of
from .dynamics import KERNELS, STOP_RULES, run

__all__ = ["ANNEAL", "ASSIGN", "DEFAULT_SOLVER", "EXACT", "NETWORK", "SOLVERS", "AnnealSolver", "AssignSolver",
           "ExactSolver", "Matches", "NetworkSolver", "Solution", "Solver", "get_solver", "matched_neurons",
           "one_match_per_corner", "register_solver", "similarity_assignment", "solve", "solver_names",
           "to_matches", "unregister_solver"]

#: The solvers' names, for code that means one of them.
NETWORK, ANNEAL, EXACT, ASSIGN = "network", "anneal", "exact", "assign"


@dataclass(frozen=True, eq=False)
class Solution:
    """A solver's final state, before any post-processing.

    ``stop_rule`` is what stopped the discrete network (``"sweep"``, ``"stall"`` or
    ``"max_attempts"``), or ``"minimum"`` for a proven global minimum; ``attempts`` are the
    discrete network's (0 for annealing and exact); ``energy`` (3-15) is computed when first read.

    Attributes
    ----------
    state : (n,) uint8 array
        Final output of each candidate neuron.
    stop_rule : str
        ``"sweep"``, ``"stall"``, ``"max_attempts"`` or ``"minimum"``.
    attempts : int
        The discrete network's update attempts.
    net : Network
        The network solved.
    converged : bool, default True
        Whether a stop rule fired, rather than the attempt limit.
    solver : str, default "network"
        Name of the solver.
    """

    state: np.ndarray
    stop_rule: str
    attempts: int
    net: Network = field(repr=False)
    converged: bool = True
    solver: str = NETWORK

    @cached_property
    def energy(self) -> float:
        """float: energy (3-15) of the final state."""
        return _energy_of(self.net, self.state)

    @classmethod
    def _of(cls, state, stop_rule, attempts, net, converged, solver) -> "Solution":
        """The same record without the frozen ``__init__``'s ``object.__setattr__`` calls."""
        s = object.__new__(cls)
        d = s.__dict__
        d["state"], d["stop_rule"], d["attempts"], d["net"] = state, stop_rule, attempts, net
        d["converged"], d["solver"] = converged, solver
        return s


@dataclass(frozen=True)
class Solver:
    """One way to minimise the energy, configured: the base of every solver.

    A subclass sets `name`, `description` and `seeded` (whether the seed matters), declares
    its options as dataclass fields with defaults, checks them in ``__post_init__`` and
    implements :meth:`solve`.

    Attributes
    ----------
    name : str
        Registry name (class variable).
    description : str
        One line for help texts (class variable).
    seeded : bool
        Whether the seed matters (class variable).
    """

    name: ClassVar[str] = ""
    description: ClassVar[str] = ""
    seeded: ClassVar[bool] = True

    def solve(self, net: Network, seed: int) -> Solution:
        """Minimise `net`'s energy from update-order (or annealing) seed `seed`.

        Parameters
        ----------
        net : Network
            The network whose energy is minimised.
        seed : int
            Update-order (or annealing) seed.

        Returns
        -------
        solution : Solution
            The final state and what stopped it.
        """
        raise NotImplementedError

    def options(self) -> dict:
        """The solver's options, by name (JSON-ready).

        >>> ExactSolver().options()
        {'time_limit': 60.0}
        """
        return asdict(self)

    def configured(self, owner: str = "Solver.configured", **options) -> "Solver":
        """A copy with some options changed; an option this solver does not have is an error.

        >>> SOLVERS["network"].configured(stop_rule="stall").stop_rule
        'stall'
        >>> SOLVERS["anneal"].configured(stop_rule="stall")
        Traceback (most recent call last):
        ...
        ismb_lab.ParameterError: The 'stop_rule' parameter of Solver.configured must be an option of the 'anneal' solver (t_start, t_end, cooling, sweeps, settle). Got 'stall' instead.
        """
        own = [f.name for f in fields(self)]
        for key, value in options.items():
            if key not in own:
                raise ParameterError(message(key, owner, f"an option of the {self.name!r} solver "
                                             f"({', '.join(own) or 'none'})", value))
        return replace(self, **options) if options else self


@dataclass(frozen=True)
class NetworkSolver(Solver):
    """The thesis' discrete network (:func:`ismb_lab.network.dynamics.run`) from "all on"."""

    name: ClassVar[str] = NETWORK
    description: ClassVar[str] = "the thesis' discrete network: asynchronous flips to a fixed point"
    stop_rule: str = "sweep"
    rule: str = "exact"
    kernel: str = "numba"

    def __post_init__(self):
        own = type(self).__name__
        check_choice(self.stop_rule, "stop_rule", own, STOP_RULES)
        check_choice(self.rule, "rule", own, RULES)
        check_choice(self.kernel, "kernel", own, KERNELS)

    def solve(self, net, seed) -> Solution:
        r = run(net, rng=seed, stop_rule=self.stop_rule, rule=self.rule, kernel=self.kernel)
        return Solution._of(r.state, r.stop_rule, r.attempts, net, r.converged, self.name)


@dataclass(frozen=True)
class AnnealSolver(Solver):
    """Mean-field annealing (:func:`ismb_lab.network.annealing.anneal`, whose arguments the fields are)."""

    name: ClassVar[str] = ANNEAL
    description: ClassVar[str] = "mean-field annealing, then the discrete network from the rounded state"
    t_start: float = 2.0
    t_end: float = 0.02
    cooling: float = 0.9
    sweeps: int = 2
    settle: float = 0.0

    def __post_init__(self):
        own = "AnnealSolver"
        check_schedule_options(own, self.t_start, self.t_end, self.cooling, self.sweeps)
        check_settle(self.settle, own)

    def solve(self, net, seed) -> Solution:
        r = anneal(net, rng=seed, t_start=self.t_start, t_end=self.t_end, cooling=self.cooling, sweeps=self.sweeps,
                   settle=self.settle)
        return Solution(r.state, "sweep", 0, net, solver=self.name)


@dataclass(frozen=True)
class ExactSolver(Solver):
    """The global minimum as a mixed-integer programme (:func:`ismb_lab.network.exact.milp_minimum`)."""

    name: ClassVar[str] = EXACT
    description: ClassVar[str] = "the global minimum energy as a mixed-integer programme (small problems)"
    seeded: ClassVar[bool] = False
    time_limit: float = 60.0

    def __post_init__(self):
        check_number(self.time_limit, "time_limit", "ExactSolver", low=0, low_open=True, high=MAX_TIME_LIMIT)

    def solve(self, net, seed) -> Solution:
        r = milp_minimum(net, time_limit=self.time_limit)
        return Solution(r.state, "minimum", 0, net, solver=self.name)


def similarity_assignment(net: Network) -> np.ndarray:
    """The state of the one-to-one assignment of largest total ``S``, among neurons with ``S > 0``.

    Examples
    --------
    >>> from ismb_lab.network.hopfield import Network
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


@dataclass(frozen=True)
class AssignSolver(NetworkSolver):
    """The discrete network started from :func:`similarity_assignment` (beyond the thesis)."""

    name: ClassVar[str] = ASSIGN
    description: ClassVar[str] = ("the discrete network started from the assignment of largest total similarity "
                                  "(beyond the thesis)")

    def solve(self, net, seed) -> Solution:
        r = run(net, rng=seed, state=similarity_assignment(net), stop_rule=self.stop_rule, rule=self.rule,
                kernel=self.kernel)
        return Solution(r.state, r.stop_rule, r.attempts, net, r.converged, self.name)


#: The registered solvers by name, each with its default options, in the order help texts list them.
SOLVERS: dict[str, Solver] = {}

#: The thesis' solver, the default everywhere except the depth demo.
DEFAULT_SOLVER = NETWORK


def register_solver(solver: Solver) -> Solver:
    """Add a solver to the registry that the command line, the GA and the widgets read.

    Parameters
    ----------
    solver : Solver
        An instance with a new, non-empty name that implements ``solve``.

    Returns
    -------
    solver : Solver
        `solver` itself.

    Raises
    ------
    ParameterTypeError
        Not a Solver.
    ParameterError
        A name already taken or empty, or no ``solve``.

    Examples
    --------
    >>> @dataclass(frozen=True)
    ... class AllOff(Solver):
    ...     name, description, seeded = "off", "every candidate off", False
    ...     def solve(self, net, seed):
    ...         return Solution(np.zeros(net.n_neurons, np.uint8), "minimum", 0, net, solver=self.name)
    >>> register_solver(AllOff()); "off" in solver_names()
    AllOff()
    True
    >>> unregister_solver("off"); "off" in solver_names()
    False
    """
    own = "register_solver"
    if not isinstance(solver, Solver):
        raise ParameterTypeError(message("solver", own, "a Solver instance", solver))
    if not isinstance(solver.name, str) or not solver.name or solver.name in SOLVERS:
        raise ParameterError(message("solver", own, "a solver with a new, non-empty name", f"name {solver.name!r}"))
    if type(solver).solve is Solver.solve:
        raise ParameterError(message("solver", own, "a solver that implements solve(net, seed)", solver))
    SOLVERS[solver.name] = solver
    return solver


def unregister_solver(name: str) -> None:
    """Remove a solver added by :func:`register_solver`."""
    check_choice(name, "name", "unregister_solver", tuple(SOLVERS))
    del SOLVERS[name]


for _solver in (NetworkSolver(), AnnealSolver(), ExactSolver(), AssignSolver()):
    register_solver(_solver)


def solver_names() -> tuple[str, ...]:
    """The registered solvers' names.

    >>> solver_names()
    ('network', 'anneal', 'exact', 'assign')
    """
    return tuple(SOLVERS)


def get_solver(solver, owner: str = "get_solver", parameter: str = "solver", **options) -> Solver:
    """Resolve a solver once: a name or a :class:`Solver`, with some `options` changed (None
    keeps the solver's own), checked as `owner`'s argument `parameter`.

    >>> get_solver("annealing")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'solver' parameter of get_solver must be one of 'network', 'anneal', 'exact', 'assign'. Got 'annealing' instead.
    >>> get_solver("network", stop_rule="stall")
    NetworkSolver(stop_rule='stall', rule='exact', kernel='numba')
    """
    if not isinstance(solver, Solver):
        if not isinstance(solver, str):
            raise ParameterTypeError(message(parameter, owner, "a solver name or a Solver", solver))
        solver = SOLVERS[check_choice(solver, parameter, owner, solver_names())]
    return solver.configured(owner, **{k: v for k, v in options.items() if v is not None})


def solve(net: Network, solver=DEFAULT_SOLVER, *, seed: int = 0, owner: str = "solve", **options) -> Solution:
    """Minimise `net`'s energy with a solver of :data:`SOLVERS` (a name or a configured
    :class:`Solver`) and its `options`; `seed` is the update-order (and annealing) seed, and
    `owner` the function named in error messages.

    Parameters
    ----------
    net : Network
        The network whose energy is minimised.
    solver : str or Solver, default "network"
        The solver.
    seed : int, default 0
        Update-order (and annealing) seed, >= 0.
    owner : str, default "solve"
        Function named in error messages.
    **options
        Solver options to change.

    Returns
    -------
    solution : Solution
        The final state, before any post-processing.

    Raises
    ------
    ParameterTypeError
        `net` not a Network.
    ParameterError
        An unknown solver or option, or a bad seed.
    """
    chosen = solver if isinstance(solver, Solver) and not options else get_solver(solver, owner, **options)
    if not isinstance(net, Network):
        raise ParameterTypeError(message("net", owner, "a Network", net))
    # a GA solves thousands of networks: a plain seed passes without a call
    if not (type(seed) is int and seed >= 0):
        check_number(seed, "seed", owner, low=0, integer=True)
    return chosen.solve(net, seed)


class Matches(NamedTuple):
    """Matched feature pairs and the post-processed state they come from."""

    pairs: np.ndarray
    state: np.ndarray


def matched_neurons(neurons, state, method=None) -> np.ndarray:
    """Indices of the neurons that are matches in a final state, sorted: those on, less any
    that `method`'s :meth:`~ismb_lab.network.methods.Method.postprocess` drops.

    Parameters
    ----------
    neurons : Problem, Network or Topology
        Anything with ``rows`` and ``cols``.
    state : (n,) 0/1 array
        A final state.
    method : Method, optional
        Whose post-processing applies; None keeps every neuron on.

    Returns
    -------
    on : (m,) int64 array
        Indices of the matched neurons, sorted.

    Examples
    --------
    >>> from ismb_lab.network.methods import build_problem
    >>> p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], np.zeros((2, 2)))
    >>> matched_neurons(p, [1, 0, 0, 1]).tolist()
    [0, 3]
    """
    on = np.flatnonzero(np.asarray(state, dtype=np.uint8))
    kept = on if method is None else method.postprocess(neurons, on)
    return on if kept is on else np.sort(kept)   # a method that keeps every match returns `on` itself


def one_match_per_corner(problem, on, key=None) -> np.ndarray:
    """Of the matched neurons `on`, at most one per left and per right corner: the most similar.

    Neurons are taken by increasing ``M`` (or `key`; ties by index), and kept when neither
    corner has a kept match yet: where two wrong matches support each other a solver can
    leave both on.  A decoding option (``match(..., one_to_one=True)``); the GA's fitness
    does not apply it.  `problem` is anything with ``rows``, ``cols`` and
    ``neuron_dissimilarity``.

    Parameters
    ----------
    problem : Problem
        Anything with ``rows``, ``cols`` and ``neuron_dissimilarity``.
    on : (m,) int array
        Indices of the matched neurons.
    key : (m,) float array, optional
        Order of preference, lowest first; default ``M`` of each neuron.

    Returns
    -------
    kept : (m',) int64 array
        The neurons kept, sorted.

    Raises
    ------
    ParameterError
        `key` not as long as `on`.

    Examples
    --------
    >>> from ismb_lab.network.methods import build_problem
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
    """The matched ``(i, k)`` feature pairs of a final state, sorted by neuron, and the
    post-processed state: the one place this is done.

    `neurons` is anything with ``rows`` and ``cols`` (a Problem, Network or Topology);
    `method`'s :meth:`~ismb_lab.network.methods.Method.postprocess` decides which neurons stay.

    Parameters
    ----------
    neurons : Problem, Network or Topology
        Anything with ``rows`` and ``cols``.
    state : (n,) 0/1 array
        A final state.
    method : Method, optional
        Whose post-processing applies; None keeps every neuron on.

    Returns
    -------
    matches : Matches
        ``pairs`` (``(m, 2)`` int64) and the post-processed ``state``.

    Examples
    --------
    >>> from ismb_lab.network.methods import build_problem
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
