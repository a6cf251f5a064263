"""Mean-field annealing: the analog Hopfield network on the same energy (thesis future work 1).

Each neuron holds a probability ``v_a`` in ``[0, 1]`` set asynchronously to its mean-field
value at temperature ``T``::

    v_a = 1 / (1 + exp(-u_a / T)),    u_a = sum_b W_ab v_b + I_a

with the exact weights of :func:`~ismb_lab.network.hopfield.hopfield_form`.  Cooling slowly
lets the ``v`` commit one after another, usually into a deeper minimum than a greedy descent
from "all on".  At the end ``v`` is rounded at 1/2 and polished by the discrete network, so
the answer is an exact fixed point.

>>> from ismb_lab.network.hopfield import Network
>>> net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1],
...                           similarity=[0.5, -0.5, -0.5, 0.5],
...                           pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.9])
>>> result = anneal(net, rng=0)
>>> result.state.tolist(), round(result.energy, 2)
([1, 0, 0, 1], -2.8)
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Iterator

import numba
import numpy as np

from .._core.validation import ParameterError, check_number, check_rng, message
from .hopfield import Network, Topology, check_net, energy, hopfield_form
from .dynamics import run

__all__ = ["MAX_SWEEPS", "anneal", "AnnealResult", "AnnealStep", "iter_annealing"]

#: Most sweeps a schedule may run in all (its temperatures times `sweeps`); the default runs 88.
MAX_SWEEPS = 100_000


@dataclass(frozen=True)
class AnnealStep:
    """One temperature of the schedule, after its sweeps.

    ``change`` is the largest ``|dv|`` of the last sweep, ``energy`` is
    ``const - 1/2 v'Wv - I'v`` of the analog state, and ``committed`` the share of neurons
    with ``v`` below 0.05 or above 0.95.
    """

    index: int
    temperature: float
    change: float
    energy: float
    committed: float


@dataclass(frozen=True, eq=False)
class AnnealResult:
    """Outcome of :func:`anneal`: the discrete fixed point ``state`` and its ``energy``, the
    ``rounded`` analog state ``v > 1/2`` before the polish, the final ``analog`` ``v``, and
    the temperatures visited (``steps``)."""

    state: np.ndarray
    energy: float
    rounded: np.ndarray
    analog: np.ndarray
    steps: int


@numba.njit(cache=True)
def _logistic(x):
    """``1 / (1 + exp(-x))`` without overflow: ``exp`` of a negative number only."""
    if x >= 0:
        return 1.0 / (1.0 + np.exp(-x))
    z = np.exp(x)
    return z / (1.0 + z)


@numba.njit(cache=True)
def _sweeps(W, u, v, orders, T):
    """Asynchronous mean-field updates at temperature `T`, one sweep per row of `orders`;
    `v` and `u` change in place.  Returns the largest ``|dv|``.  ``exp`` is the C library's,
    as :func:`math.exp` is."""
    change = 0.0
    for s in range(orders.shape[0]):
        for a in orders[s]:
            new = _logistic(u[a] / T)
            d = new - v[a]
            if d != 0.0:
                v[a] = new
                for b in range(u.shape[0]):   # W is symmetric: row a is column a
                    u[b] += W[a, b] * d
                change = max(change, abs(d))
    return change


def iter_annealing(net: Network, *, rng=0, t_start: float = 2.0, t_end: float = 0.02,
                   cooling: float = 0.9, sweeps: int = 2, settle: float = 0.0,
                   state: list | None = None) -> Iterator[AnnealStep]:
    """Cool the analog network, yielding an :class:`AnnealStep` per temperature.

    Parameters
    ----------
    net : Network
        The network to anneal.
    rng : int or numpy.random.Generator, default 0
        Seeds the start (``v = 1/2`` plus noise of 0.01) and the visiting orders.
    t_start, t_end : float, default 2.0, 0.02
        First and last temperature, ``t_start > t_end > 0``, in units of the weights (2 is "hot").
    cooling : float, default 0.9
        Factor in (0, 1) between consecutive temperatures.
    sweeps : int, default 2
        Sweeps per temperature; at most :data:`MAX_SWEEPS` sweeps in all.
    settle : float, default 0.0
        In [0, 1/2): stop after the first temperature that moved no ``v`` across 1/2 and
        left every ``v`` within `settle` of 0 or 1; 0 runs the whole schedule.
    state : list, optional
        A one-element list that receives the analog state array (updated in place).

    Yields
    ------
    step : AnnealStep
        One per temperature, after its sweeps.

    Raises
    ------
    ParameterError
        A schedule out of range or longer than :data:`MAX_SWEEPS` sweeps.

    Examples
    --------
    >>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.8, -0.8],
    ...                           pair_a=[], pair_b=[], pair_c=[], match_bias=0.0)
    >>> steps = list(iter_annealing(net, rng=0))
    >>> steps[0].temperature, round(steps[-1].temperature, 3), steps[-1].committed
    (2.0, 0.021, 1.0)
    """
    t_start, t_end, cooling, sweeps = check_schedule(net, "iter_annealing", t_start, t_end, cooling, sweeps)
    settle = check_settle(settle, "iter_annealing")
    rng = check_rng(rng, "rng", "iter_annealing")
    return _anneal(net, rng, t_start, t_end, cooling, sweeps, settle, state)


def check_settle(settle, owner) -> float:
    """`settle`, a number in [0, 1/2), checked as `owner`'s."""
    settle = check_number(settle, "settle", owner, low=0)
    if settle >= 0.5:
        raise ParameterError(message("settle", owner, "a number in [0, 0.5)", settle))
    return settle


def check_schedule(net, owner, t_start, t_end, cooling, sweeps):
    """The schedule's arguments, checked as `owner`'s."""
    check_net(net, owner)
    return check_schedule_options(owner, t_start, t_end, cooling, sweeps)


def check_schedule_options(owner, t_start, t_end, cooling, sweeps):
    """The schedule's options, checked as `owner`'s (a solver's, before any network exists)."""
    t_end = check_number(t_end, "t_end", owner, low=0, low_open=True)
    t_start = check_number(t_start, "t_start", owner, low=t_end)
    cooling = check_number(cooling, "cooling", owner, low=0, low_open=True)
    if cooling >= 1:
        raise ParameterError(message("cooling", owner, "a number in (0, 1)", cooling))
    sweeps = check_number(sweeps, "sweeps", owner, low=1, high=MAX_SWEEPS, integer=True)
    if _temperatures(t_start, t_end, cooling, MAX_SWEEPS // sweeps) is None:
        raise ParameterError(message("cooling", owner, f"a factor that cools from t_start {t_start:g} to t_end "
                                     f"{t_end:g} in at most {MAX_SWEEPS // sweeps} temperatures of {sweeps} sweeps "
                                     f"({MAX_SWEEPS} sweeps in all)", cooling))
    return t_start, t_end, cooling, sweeps


def _temperatures(t_start: float, t_end: float, cooling: float, most: int) -> list | None:
    """The schedule's temperatures, or None as soon as there are more than `most`."""
    temperatures = []
    T = t_start
    while T >= t_end * (1 - 1e-12):
        if len(temperatures) == most:
            return None
        temperatures.append(T)
        T *= cooling
    return temperatures


def _anneal(net, rng, t_start, t_end, cooling, sweeps, settle, holder):
    W, I = hopfield_form(net)
    n = net.n_neurons
    v = 0.5 + 0.01 * rng.uniform(-1, 1, n)
    if holder is not None:
        holder[:] = [v]
    u = W @ v + I
    for index, T in enumerate(_temperatures(t_start, t_end, cooling, MAX_SWEEPS // sweeps)):
        orders = np.array([rng.permutation(n) for _ in range(sweeps)], dtype=np.int64).reshape(sweeps, n)
        before = v > 0.5
        change = _sweeps(W, u, v, orders, T)
        e = net.constant - 0.5 * v @ W @ v - I @ v
        committed = float(np.mean((v < 0.05) | (v > 0.95))) if n else 1.0
        yield AnnealStep(index, float(T), float(change), float(e), committed)
        if settle > 0 and np.array_equal(before, v > 0.5) and np.all((v < settle) | (v > 1 - settle)):
            return


def anneal(net: Network, *, rng=0, t_start: float = 2.0, t_end: float = 0.02, cooling: float = 0.9,
           sweeps: int = 2, settle: float = 0.0) -> AnnealResult:
    """Run the schedule of :func:`iter_annealing` to the end, round ``v`` at 1/2 and settle with
    the discrete network; an :class:`AnnealResult`.

    The schedule runs in one compiled call on neighbour lists instead of the dense rows of
    ``W``: the same updates in the same order from the same generator, so the same ``v``.

    Parameters
    ----------
    net : Network
        The network to anneal.
    rng : int or numpy.random.Generator, default 0
        Seeds the start (``v = 1/2`` plus noise of 0.01), the visiting orders and the polish.
    t_start, t_end : float, default 2.0, 0.02
        First and last temperature, ``t_start > t_end > 0``.
    cooling : float, default 0.9
        Factor in (0, 1) between consecutive temperatures.
    sweeps : int, default 2
        Sweeps per temperature; at most :data:`MAX_SWEEPS` sweeps in all.
    settle : float, default 0.0
        In [0, 1/2): stop early once every ``v`` is within it of 0 or 1 (see :func:`iter_annealing`).

    Returns
    -------
    result : AnnealResult
        The polished state, its energy, the rounded and analog states.

    Raises
    ------
    ParameterError
        A schedule out of range or longer than :data:`MAX_SWEEPS` sweeps.

    Examples
    --------
    >>> net = Network.from_arrays(2, 1, rows=[0, 1], cols=[0, 0], similarity=[0.9, 0.2],
    ...                           pair_a=[], pair_b=[], pair_c=[], match_bias=0.0)
    >>> anneal(net, rng=3).state.tolist()     # the better of two rivals for one column
    [1, 0]
    """
    rng = check_rng(rng, "rng", "anneal")
    t_start, t_end, cooling, sweeps = check_schedule(net, "anneal", t_start, t_end, cooling, sweeps)
    settle = check_settle(settle, "anneal")
    temperatures = _temperatures(t_start, t_end, cooling, MAX_SWEEPS // sweeps)
    v = 0.5 + 0.01 * rng.uniform(-1, 1, net.n_neurons)
    ptr, idx, pair = _neighbours(net.topology)
    W, w = _dense_and_listed(ptr, idx, pair, net.pair_c, 2.0 * net.uniqueness)
    u = W @ v + (net.match_bias + net.similarity)   # hopfield_form's W and I: the same sum
    steps = _schedule(rng, ptr, idx, w, u, v, np.array(temperatures, dtype=float), sweeps, settle)
    rounded = (v > 0.5).astype(np.uint8)
    polish = run(net, rng=rng, state=rounded)
    return AnnealResult(polish.state, energy(net, polish.state), rounded, v, steps)


#: Each topology's neighbour lists, kept while the topology lives (a GA anneals many
#: networks of one topology).
_NEIGHBOURS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _neighbours(top: Topology) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where :func:`~ismb_lab.network.hopfield.hopfield_form`'s ``W`` may be non-zero off its
    diagonal: neuron ``a``'s neighbours ``idx[ptr[a]:ptr[a + 1]]`` and, for each, its pair
    (whose ``C`` the entry holds; the last of a repeated pair), or -1 on a shared row or column.
    """
    found = _NEIGHBOURS.get(top)
    if found is None:
        lay = top.layout
        found = _neighbour_lists(top.rows, top.cols, lay.nb_ptr, lay.nb_idx, lay.nb_pair, lay.row_ptr,
                                 lay.row_idx, lay.col_ptr, lay.col_idx)
        _NEIGHBOURS[top] = found
    return found


@numba.njit(cache=True)
def _neighbour_lists(rows, cols, nb_ptr, nb_idx, nb_pair, row_ptr, row_idx, col_ptr, col_idx):
    """The lists of :func:`_neighbours`, from a topology's layout."""
    n = rows.shape[0]
    ptr = np.zeros(n + 1, dtype=np.int64)
    for a in range(n):
        count = row_ptr[rows[a] + 1] - row_ptr[rows[a]] + col_ptr[cols[a] + 1] - col_ptr[cols[a]] - 2
        for e in range(nb_ptr[a], nb_ptr[a + 1]):
            count += e + 1 == nb_ptr[a + 1] or nb_idx[e + 1] != nb_idx[e]   # a repeated pair once
        ptr[a + 1] = ptr[a] + count
    idx = np.empty(ptr[n], dtype=np.int64)
    pair = np.empty(ptr[n], dtype=np.int64)
    for a in range(n):
        j = ptr[a]
        for e in range(row_ptr[rows[a]], row_ptr[rows[a] + 1]):
            if row_idx[e] != a:
                idx[j], pair[j] = row_idx[e], -1
                j += 1
        for e in range(col_ptr[cols[a]], col_ptr[cols[a] + 1]):
            if col_idx[e] != a:
                idx[j], pair[j] = col_idx[e], -1
                j += 1
        for e in range(nb_ptr[a], nb_ptr[a + 1]):
            if e + 1 == nb_ptr[a + 1] or nb_idx[e + 1] != nb_idx[e]:   # the last of a repeated pair
                idx[j], pair[j] = nb_idx[e], nb_pair[e]
                j += 1
    return ptr, idx, pair


@numba.njit(cache=True)
def _dense_and_listed(ptr, idx, pair, pair_c, two_kappa):
    """``W`` of :func:`ismb_lab.network.hopfield.hopfield_form` (rule "exact"), value for value, and
    its entries in the order of `idx`."""
    n = ptr.shape[0] - 1
    W = np.zeros((n, n))
    w = np.empty(idx.shape[0])
    for a in range(n):
        for e in range(ptr[a], ptr[a + 1]):
            # hopfield_form's arithmetic: (C + C') doubled, less 2 kappa on a shared row or column
            x = 2.0 * (pair_c[pair[e]] + 0.0) - 0.0 if pair[e] >= 0 else 2.0 * 0.0 - two_kappa
            W[a, idx[e]] = x
            w[e] = x
    return W, w


@numba.njit(cache=True)
def _schedule(rng, ptr, idx, w, u, v, temperatures, sweeps, settle):
    """:func:`_sweeps` at every temperature on neighbour lists, each order drawn from `rng` as
    :func:`_anneal` draws it; `v` and `u` change in place.  Returns the temperatures run.

    A zero weight the dense row would add is skipped: it could only change the sign of a
    zero ``u``, which gives the same ``v``."""
    n = v.shape[0]
    before = np.empty(n, dtype=np.bool_)
    for t in range(temperatures.shape[0]):
        T = temperatures[t]
        if settle > 0:
            before[:] = v > 0.5
        for _ in range(sweeps):
            for a in rng.permutation(n):
                new = _logistic(u[a] / T)
                d = new - v[a]
                if d != 0.0:
                    v[a] = new
                    for e in range(ptr[a], ptr[a + 1]):
                        u[idx[e]] += w[e] * d
        if settle > 0 and _settled(before, v, settle):
            return t + 1
    return temperatures.shape[0]


@numba.njit(cache=True)
def _settled(before, v, settle):
    """No ``v`` crossed 1/2 since `before` and every ``v`` lies within `settle` of 0 or 1."""
    for a in range(v.shape[0]):
        if before[a] != (v[a] > 0.5) or settle <= v[a] <= 1 - settle:
            return False
    return True
