"""How the network runs: asynchronous updates in a random order, to a fixed point (§3.3, (3-20)).

Update order
------------
Attempts visit neurons in a random order drawn from a numpy Generator in fixed
blocks (:func:`visiting_order`), shared by both kernels.  Two stop rules:

* ``"sweep"`` (default): a full random-order sweep over all neurons changes
  nothing.  That is an exact fixed point.
* ``"stall"``: ``patience`` (200 in the thesis) consecutive attempts, drawn with
  replacement, change nothing.  With many neurons it can stop short of a fixed point.

Both give up after ``max_sweeps * n`` attempts (stop rule ``"max_attempts"``).

Two kernels make the same decisions: the readable "textbook" one of
:func:`iter_updates`, which re-sums (3-20) at every attempt and yields an
:class:`Update` record each time, and the compiled one of :func:`run`, which
keeps every net input current after each flip.  Their weights are the integers of
:mod:`ismb_lab.hopfield`, so they agree bit for bit.
"""

from __future__ import annotations

import itertools
import numbers
from dataclasses import dataclass
from typing import Iterator

import numba
import numpy as np

from ._validation import ParameterTypeError, check_choice, check_number, check_rng, message
from .hopfield import RULES, SCALE, Network, Topology, _check_state, _energy, _Weights, _weights, energy

__all__ = ["KERNELS", "STOP_RULES", "iter_updates", "run", "RunResult", "Update", "visiting_order"]

STOP_RULES = ("sweep", "stall")
KERNELS = ("numba", "textbook")
_BLOCK_SWEEPS = 4

def visiting_order(rng: np.random.Generator, n: int, stop_rule: str) -> Iterator[np.ndarray]:
    """Endless blocks of neuron indices to attempt, shared by both kernels.

    ``"sweep"``: each block holds 4 independent random permutations of ``range(n)``.
    ``"stall"``: each block holds ``4 n`` indices drawn uniformly with replacement.

    Examples
    --------
    >>> blocks = visiting_order(np.random.default_rng(0), 3, "sweep")
    >>> sorted(next(blocks)[:3].tolist())
    [0, 1, 2]
    """
    base = np.tile(np.arange(n, dtype=np.int64), (_BLOCK_SWEEPS, 1))
    while True:
        if stop_rule == "sweep":
            yield rng.permuted(base, axis=1).ravel()
        else:
            yield rng.integers(0, n, size=_BLOCK_SWEEPS * n, dtype=np.int64)


def _remembered_orders(topology: Topology, seed: int, stop_rule: str) -> Iterator[np.ndarray]:
    """:func:`visiting_order` of ``default_rng(seed)``, remembered on `topology` for reuse.

    The visiting order does not depend on the energy, so networks that share a
    topology and a seed (a GA's population) draw it only once.
    """
    key = (seed, stop_rule)
    if key not in topology._orders:
        topology._orders[key] = ([], visiting_order(np.random.default_rng(seed), topology.n_neurons,
                                                     stop_rule))
    blocks, source = topology._orders[key]
    for t in itertools.count():
        if t == len(blocks):
            blocks.append(next(source))
        yield blocks[t]


@dataclass(frozen=True)
class Update:
    """One asynchronous update attempt (one step of (3-19)).

    Attributes
    ----------
    attempt : int
        0-based attempt number.
    neuron : int
        Index of the attempted candidate neuron; ``i`` and ``k`` are its left
        and right features.
    u : float
        Its net input under the rule in use ((3-20) for ``"thesis"``).
    old, new : int
        Output before and after the attempt.
    energy : float
        Energy (3-15) after the attempt.
    stop : str or None
        Set on the last attempt of a run: ``"sweep"``, ``"stall"`` or ``"max_attempts"``.
    """

    attempt: int
    neuron: int
    i: int
    k: int
    u: float
    old: int
    new: int
    energy: float
    stop: str | None = None

    @property
    def changed(self) -> bool:
        return self.old != self.new


def _as_lists(w: _Weights) -> _Weights:
    return _Weights(*(x.tolist() if isinstance(x, np.ndarray) else int(x) for x in w))


def _net_input_textbook(a: int, y: list, w: _Weights) -> int:
    """(3-19)/(3-20): u_ik = sum_j sum_l W_ikjl y_jl + I_ik, term by term (fixed point)."""
    u = w.bias[a]
    for p in range(w.nb_ptr[a], w.nb_ptr[a + 1]):  # neighbours j of i, and their l != k
        u += w.nb_w[p] * y[w.nb_idx[p]]
    i, k = w.rows[a], w.cols[a]
    for p in range(w.row_ptr[i], w.row_ptr[i + 1]):  # j == i: uniqueness of the left point
        b = w.row_idx[p]
        if b != a:
            u += w.row_w * y[b]
    for p in range(w.col_ptr[k], w.col_ptr[k + 1]):  # l == k: uniqueness of the right point
        b = w.col_idx[p]
        if b != a:
            u += w.col_w * y[b]
    return u + w.self_w[a] * y[a]


def _check_run_args(net, rng, state, stop_rule, rule, patience, max_sweeps, owner):
    if not isinstance(net, Network):
        raise ParameterTypeError(message("net", owner, "a Network", type(net).__name__))
    check_choice(stop_rule, "stop_rule", owner, STOP_RULES)
    check_choice(rule, "rule", owner, RULES)
    check_number(patience, "patience", owner, low=1, integer=True)
    check_number(max_sweeps, "max_sweeps", owner, low=1, integer=True)
    y0 = net.initial_state() if state is None else _check_state(net, state, owner)
    if isinstance(rng, np.random.Generator):
        return visiting_order(rng, net.n_neurons, stop_rule), y0
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool) and rng >= 0:
        return _remembered_orders(net.topology, int(rng), stop_rule), y0
    check_rng(rng, "rng", owner)  # raises the standard error


def iter_updates(net: Network, *, rng=0, state=None, stop_rule: str = "sweep",
                 rule: str = "exact", patience: int = 200,
                 max_sweeps: int = 500) -> Iterator[Update]:
    """Run the network one attempt at a time, yielding an :class:`Update` per attempt.

    This is the readable "textbook" kernel: it re-evaluates (3-20) term by term
    at each attempt and applies (3-19).  Widgets, notebooks and tests consume it;
    :func:`run` with ``kernel="numba"`` gives the same result much faster.

    Parameters
    ----------
    net : Network
    rng : int or numpy.random.Generator
        Seed or generator for the random visiting order.
    state : (n,) array_like of {0, 1}, optional
        Initial outputs; all candidates on by default (§3.3).
    stop_rule : {"sweep", "stall"}
        See the module docstring.
    rule : {"exact", "thesis"}
        ``"exact"`` is the sound Hopfield form; ``"thesis"`` is (3-17)/(3-20) literally.
    patience : int
        Unchanged attempts in a row that stop the ``"stall"`` rule (200 in the thesis).
    max_sweeps : int
        Give up after ``max_sweeps * n`` attempts.

    Yields
    ------
    update : Update
        The last one has ``stop`` set.  Nothing is yielded for an empty network.

    Examples
    --------
    >>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, -0.5],
    ...               pair_a=[], pair_b=[], pair_c=[])
    >>> steps = list(iter_updates(net, rng=0))
    >>> [(s.neuron, s.u, s.old, s.new) for s in steps if s.changed]
    [(1, -0.5, 1, 0)]
    >>> steps[-1].stop, steps[-1].energy
    ('sweep', 0.5)
    """
    blocks, y0 = _check_run_args(net, rng, state, stop_rule, rule, patience, max_sweeps, "iter_updates")
    return _updates(net, blocks, y0, stop_rule, rule, patience, max_sweeps)


def _updates(net, blocks, y0, stop_rule, rule, patience, max_sweeps):
    n = net.n_neurons
    if n == 0:
        return
    w = _as_lists(_weights(net, rule))
    exact = w if rule == "exact" else _as_lists(_weights(net, "exact"))
    y = [int(v) for v in y0]
    e0 = energy(net, y0)
    drop = 0  # exact sum of u * dy so far, in units of 2**-40
    attempt = changed_in_sweep = unchanged = 0
    for block in blocks:
        for a in block.tolist():
            u = _net_input_textbook(a, y, w)
            old = y[a]
            new = 1 if u > 0 else 0 if u < 0 else old
            if new != old:
                drop += (u if w is exact else _net_input_textbook(a, y, exact)) * (new - old)
                y[a] = new
                changed_in_sweep += 1
                unchanged = 0
            else:
                unchanged += 1
            attempt += 1
            stop = None
            if stop_rule == "sweep" and attempt % n == 0:
                if changed_in_sweep == 0:
                    stop = "sweep"
                changed_in_sweep = 0
            elif stop_rule == "stall" and unchanged >= patience:
                stop = "stall"
            if stop is None and attempt >= max_sweeps * n:
                stop = "max_attempts"
            yield Update(attempt - 1, a, int(net.rows[a]), int(net.cols[a]), u / SCALE,
                         old, new, e0 - drop / SCALE, stop)
            if stop is not None:
                return


@dataclass(frozen=True, eq=False)
class RunResult:
    """Outcome of one network run.

    Attributes
    ----------
    state : (n,) uint8 ndarray
        Final outputs of the candidate neurons.
    energy : float
        Energy (3-15) of the final state, from :func:`energy`.
    stop_rule : str
        What stopped the run: ``"sweep"``, ``"stall"`` or ``"max_attempts"``.
    attempts, flips : int
        Update attempts made and outputs changed.
    """

    state: np.ndarray
    energy: float
    stop_rule: str
    attempts: int
    flips: int

    @property
    def converged(self) -> bool:
        """Whether a stop rule fired (rather than the attempt limit)."""
        return self.stop_rule != "max_attempts"


_STOP_NAMES = {1: "sweep", 2: "stall", 3: "max_attempts"}


@numba.njit(cache=True)
def _initial_input(y, nb_ptr, nb_idx, nb_w, rows, cols, n_left, n_right, row_w, col_w,
                   self_w, bias):
    n = y.shape[0]
    row_sum = np.zeros(n_left, dtype=np.int64)
    col_sum = np.zeros(n_right, dtype=np.int64)
    for a in range(n):
        row_sum[rows[a]] += y[a]
        col_sum[cols[a]] += y[a]
    u = np.empty(n, dtype=np.int64)
    for a in range(n):
        s = bias[a]
        for p in range(nb_ptr[a], nb_ptr[a + 1]):
            s += nb_w[p] * y[nb_idx[p]]
        s += row_w * (row_sum[rows[a]] - y[a]) + col_w * (col_sum[cols[a]] - y[a])
        u[a] = s + self_w[a] * y[a]
    return u


@numba.njit(cache=True)
def _run_block(order, y, u, counters, nb_ptr, nb_idx, nb_w, row_ptr, row_idx, col_ptr,
               col_idx, rows, cols, row_w, col_w, self_w, sweep_rule, patience, max_attempts):
    """Attempt the neurons in `order`, keeping every net input current after each flip.

    counters = [attempts, changed in this sweep, unchanged in a row, flips].
    Returns 0 when the block is used up, else the stop code of _STOP_NAMES.
    """
    n = y.shape[0]
    for t in range(order.shape[0]):
        a = order[t]
        ua = u[a]
        old = y[a]
        new = old
        if ua > 0:
            new = 1
        elif ua < 0:
            new = 0
        counters[0] += 1
        if new != old:
            d = np.int64(new) - np.int64(old)
            y[a] = new
            for p in range(nb_ptr[a], nb_ptr[a + 1]):
                u[nb_idx[p]] += nb_w[p] * d
            i = rows[a]
            for p in range(row_ptr[i], row_ptr[i + 1]):
                if row_idx[p] != a:
                    u[row_idx[p]] += row_w * d
            k = cols[a]
            for p in range(col_ptr[k], col_ptr[k + 1]):
                if col_idx[p] != a:
                    u[col_idx[p]] += col_w * d
            u[a] += self_w[a] * d
            counters[1] += 1
            counters[2] = 0
            counters[3] += 1
        else:
            counters[2] += 1
        if sweep_rule:
            if counters[0] % n == 0:
                if counters[1] == 0:
                    return 1
                counters[1] = 0
        elif counters[2] >= patience:
            return 2
        if counters[0] >= max_attempts:
            return 3
    return 0


def run(net: Network, *, rng=0, state=None, stop_rule: str = "sweep", rule: str = "exact",
        patience: int = 200, max_sweeps: int = 500, kernel: str = "numba") -> RunResult:
    """Run the network to a stop and return the final state.

    Parameters are those of :func:`iter_updates`, plus:

    kernel : {"numba", "textbook"}
        ``"numba"`` keeps every net input current incrementally in compiled
        code; ``"textbook"`` consumes :func:`iter_updates`.  For the same
        arguments both return bit-identical results.

    Returns
    -------
    result : RunResult

    Examples
    --------
    >>> net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1],
    ...                           similarity=[0.5, -0.5, -0.5, 0.5],
    ...                           pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.9])
    >>> r = run(net, rng=1)
    >>> r.state, r.stop_rule, round(r.energy, 2)
    (array([1, 0, 0, 1], dtype=uint8), 'sweep', -2.8)
    >>> np.array_equal(run(net, rng=1, kernel="textbook").state, r.state)
    True
    """
    check_choice(kernel, "kernel", "run", KERNELS)
    blocks, y0 = _check_run_args(net, rng, state, stop_rule, rule, patience, max_sweeps, "run")
    n = net.n_neurons
    if n == 0:
        return RunResult(y0, energy(net, y0), stop_rule, 0, 0)
    if kernel == "textbook":
        y, flips, last = y0.copy(), 0, None
        for last in _updates(net, blocks, y0, stop_rule, rule, patience, max_sweeps):
            y[last.neuron] = last.new
            flips += last.changed
        return RunResult(y, energy(net, y), last.stop, last.attempt + 1, flips)
    w = _weights(net, rule)
    y = y0.astype(np.int64)
    u = _initial_input(y, w.nb_ptr, w.nb_idx, w.nb_w, w.rows, w.cols, net.n_left, net.n_right,
                       w.row_w, w.col_w, w.self_w, w.bias)
    counters = np.zeros(4, dtype=np.int64)
    for block in blocks:
        code = _run_block(block, y, u, counters, w.nb_ptr, w.nb_idx, w.nb_w, w.row_ptr,
                          w.row_idx, w.col_ptr, w.col_idx, w.rows, w.cols, w.row_w, w.col_w,
                          w.self_w, stop_rule == "sweep", patience, max_sweeps * n)
        if code:
            state = y.astype(np.uint8)
            e = _energy(net.n_left, net.n_right, net.rows, net.cols, net.similarity, net.pair_a,
                        net.pair_b, net.pair_c, state, net.uniqueness, net.target_count)
            return RunResult(state, e, _STOP_NAMES[code], int(counters[0]), int(counters[3]))
