"""How the network runs: asynchronous updates in a random order, to a fixed point (§3.3, (3-20)).

Attempts visit neurons in an order drawn from a seed (:func:`visiting_order`, a SplitMix64
stream).  Stop rules: ``"sweep"`` (default), a full random-order sweep changes nothing, an
exact fixed point; ``"stall"``, ``patience`` (200 in the thesis) consecutive attempts drawn
with replacement change nothing.  Both give up after ``max_sweeps * n`` attempts
(``"max_attempts"``).

Two kernels make the same decisions on the integer weights of :mod:`ismb_lab.network.hopfield`:
the readable "textbook" one of :func:`iter_updates`, which re-sums (3-20) at every attempt,
and the compiled one of :func:`run` (:mod:`ismb_lab.network.kernel`).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from functools import cached_property
from collections import namedtuple
from typing import Iterator

import numpy as np

from .kernel import _GOLDEN, _MIX1, _MIX2, _below, _next, _shuffle, run_network  # noqa: F401 (tested here)
from .._core.validation import MAX_SEED, check_choice, check_number, check_rng
from .hopfield import RULES, SCALE, Network, check_net, _check_state, _Weights, _weights, _energy_of, energy

__all__ = ["KERNELS", "STOP_RULES", "iter_updates", "run", "RunResult", "Update", "visiting_order"]

STOP_RULES = ("sweep", "stall")
KERNELS = ("numba", "textbook")

_MASK64 = (1 << 64) - 1


class _Stream:
    """SplitMix64 (Steele, Lea and Flood, 2014) with bounded draws, in plain Python.

    The compiled :func:`_next` and :func:`_below` agree with it on every draw.
    """

    def __init__(self, seed: int):
        self.state = seed & _MASK64

    def next(self) -> int:
        self.state = (self.state + _GOLDEN) & _MASK64
        z = self.state
        z = ((z ^ (z >> 30)) * _MIX1) & _MASK64
        z = ((z ^ (z >> 27)) * _MIX2) & _MASK64
        return z ^ (z >> 31)

    def below(self, bound: int) -> int:
        """Uniform in ``range(bound)``: the low bits of a draw, rejected when too large."""
        mask = (1 << (bound - 1).bit_length()) - 1
        while True:
            x = self.next() & mask
            if x < bound:
                return x


def visiting_order(seed: int, n: int, stop_rule: str) -> Iterator[np.ndarray]:
    """Endless sweeps of neuron indices to attempt, one array of `n` per sweep.

    ``"sweep"``: the previous order shuffled again (Fisher-Yates, from the last position
    down), starting from ``0, 1, ..., n - 1``; ``"stall"``: `n` indices drawn with replacement.

    Examples
    --------
    >>> sorted(next(visiting_order(0, 5, "sweep")).tolist())
    [0, 1, 2, 3, 4]
    """
    stream = _Stream(seed)
    order = list(range(n))
    while True:
        if stop_rule == "sweep":
            for t in range(n - 1, 0, -1):
                j = stream.below(t + 1)
                order[t], order[j] = order[j], order[t]
            yield np.array(order, dtype=np.int64)
        else:
            yield np.array([stream.below(n) for _ in range(n)], dtype=np.int64)


def _seed_of(rng, owner: str) -> int:
    """The stream's seed: the integer itself, or one draw from a Generator."""
    if type(rng) is int and 0 <= rng <= MAX_SEED:   # the common case, before the slower general test
        return rng
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool) and 0 <= rng <= MAX_SEED:
        return int(rng)
    if isinstance(rng, np.random.Generator):
        return int(rng.integers(0, 2**63, dtype=np.int64))
    check_rng(rng, "rng", owner)  # raises the standard error
    raise AssertionError("unreachable")


@dataclass(frozen=True)
class Update:
    """One asynchronous update attempt (one step of (3-19)).

    ``attempt`` counts from 0; ``neuron`` is the attempted candidate, ``i`` and ``k`` its
    features, ``u`` its net input under the rule in use, ``old`` and ``new`` its output before
    and after, ``energy`` (3-15) that after the attempt; ``stop`` is set on a run's last attempt.
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
        """bool: whether the output changed."""
        return self.old != self.new


_Lists = namedtuple("_Lists", "nb_ptr nb_idx nb_w row_ptr row_idx col_ptr col_idx rows cols row_w col_w "
                    "self_w bias")   # what the textbook kernel reads of _Weights, as Python lists and ints


def _as_lists(w: _Weights) -> _Lists:
    return _Lists(*(x.tolist() if isinstance(x, np.ndarray) else int(x)
                    for x in (getattr(w, name) for name in _Lists._fields)))


def _net_input_textbook(a: int, y: list, w: _Lists) -> int:
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


def _check_run_args(net, rng, state, stop_rule, rule, patience, max_sweeps, owner, all_on=False):
    """``(seed, initial state)``; with `all_on` the state is None when it is every neuron on."""
    check_net(net, owner)
    # the common case (a GA makes thousands of runs) is checked in a few hundred nanoseconds
    if not (stop_rule in STOP_RULES and rule in RULES and type(patience) is int and patience >= 1
            and type(max_sweeps) is int and max_sweeps >= 1):
        check_choice(stop_rule, "stop_rule", owner, STOP_RULES)
        check_choice(rule, "rule", owner, RULES)
        check_number(patience, "patience", owner, low=1, integer=True)
        check_number(max_sweeps, "max_sweeps", owner, low=1, integer=True)
    if state is None:
        y0 = None if all_on else net.initial_state()
    else:
        y0 = _check_state(net, state, owner)
    return _seed_of(rng, owner), y0


def iter_updates(net: Network, *, rng=0, state=None, stop_rule: str = "sweep",
                 rule: str = "exact", patience: int = 200,
                 max_sweeps: int = 500) -> Iterator[Update]:
    """Run the network one attempt at a time (the textbook kernel), yielding an :class:`Update` each.

    Parameters
    ----------
    net : Network
        The network to run.
    rng : int or numpy.random.Generator, default 0
        Seed of the visiting order (:func:`visiting_order`); a Generator gives one seed per run.
    state : (n,) array_like of {0, 1}, optional
        Initial outputs; all candidates on by default (§3.3).
    stop_rule : {"sweep", "stall"}, default "sweep"
        What stops the run (see the module).
    rule : {"exact", "thesis"}, default "exact"
        The sound Hopfield form, or (3-17)/(3-20) literally.
    patience : int, default 200
        Unchanged attempts in a row that stop the ``"stall"`` rule.
    max_sweeps : int, default 500
        Give up after ``max_sweeps * n`` attempts.

    Yields
    ------
    update : Update
        The last one has ``stop`` set; nothing for an empty network.

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
    seed, y0 = _check_run_args(net, rng, state, stop_rule, rule, patience, max_sweeps, "iter_updates")
    return _updates(net, visiting_order(seed, net.n_neurons, stop_rule), y0, stop_rule, rule, patience,
                    max_sweeps)


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

    ``stop_rule`` is what stopped it (``"sweep"``, ``"stall"`` or ``"max_attempts"``);
    ``energy`` (3-15) of the final state is computed when first read, as a GA never reads it.
    """

    state: np.ndarray
    stop_rule: str
    attempts: int
    flips: int
    net: Network = field(repr=False)

    @cached_property
    def energy(self) -> float:
        """float: energy (3-15) of the final state."""
        return _energy_of(self.net, self.state)

    @classmethod
    def _of(cls, state, stop_rule, attempts, flips, net) -> "RunResult":
        """The same record without the frozen ``__init__``'s ``object.__setattr__`` calls."""
        r = object.__new__(cls)
        d = r.__dict__
        d["state"], d["stop_rule"], d["attempts"], d["flips"], d["net"] = state, stop_rule, attempts, flips, net
        return r

    @property
    def converged(self) -> bool:
        """Whether a stop rule fired (rather than the attempt limit)."""
        return self.stop_rule != "max_attempts"


_STOP_NAMES = {1: "sweep", 2: "stall", 3: "max_attempts"}
_NO_STATE = np.zeros(0, dtype=np.uint8)


def run(net: Network, *, rng=0, state=None, stop_rule: str = "sweep", rule: str = "exact",
        patience: int = 200, max_sweeps: int = 500, kernel: str = "numba") -> RunResult:
    """Run the network to a stop and return a :class:`RunResult`.

    Parameters are those of :func:`iter_updates`, and `kernel`: ``"numba"`` (compiled) or
    ``"textbook"`` (:func:`iter_updates`), bit-identical for the same arguments.

    Parameters
    ----------
    net : Network
        The network to run.
    rng : int or numpy.random.Generator, default 0
        Seed of the visiting order.
    state : (n,) array_like of {0, 1}, optional
        Initial outputs; all candidates on by default.
    stop_rule : {"sweep", "stall"}, default "sweep"
        What stops the run.
    rule : {"exact", "thesis"}, default "exact"
        Which weights.
    patience : int, default 200
        Unchanged attempts in a row that stop the ``"stall"`` rule.
    max_sweeps : int, default 500
        Give up after ``max_sweeps * n`` attempts.
    kernel : {"numba", "textbook"}, default "numba"
        Compiled or readable kernel.

    Returns
    -------
    result : RunResult
        Final state, stop rule, attempts and flips.

    Raises
    ------
    ParameterError
        An unknown choice, a bad state or seed.

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
    # the common call of a GA's thousands of runs, checked and run in about a microsecond
    if (kernel == "numba" and state is None and type(net) is Network and type(rng) is int
            and 0 <= rng <= MAX_SEED and stop_rule in STOP_RULES and rule in RULES
            and type(patience) is int and patience >= 1 and type(max_sweeps) is int and max_sweeps >= 1):
        w = net._weights.get(rule) or _weights(net, rule)
        n = w.self_w.shape[0]
        if n:
            y, code, attempts, flips = run_network(rng, stop_rule == "sweep", patience, max_sweeps * n,
                                              _NO_STATE, True, *w.run_args)
            return RunResult._of(y, _STOP_NAMES[code], attempts, flips, net)
    if kernel not in KERNELS:
        check_choice(kernel, "kernel", "run", KERNELS)
    check_net(net, "run")
    n = net.n_neurons
    seed, y0 = _check_run_args(net, rng, state, stop_rule, rule, patience, max_sweeps, "run",
                               all_on=kernel == "numba" and n > 0)
    if n == 0:
        return RunResult(y0, stop_rule, 0, 0, net)
    if kernel == "textbook":
        y, flips, last = y0.copy(), 0, None
        for last in _updates(net, visiting_order(seed, n, stop_rule), y0, stop_rule, rule, patience,
                             max_sweeps):
            y[last.neuron] = last.new
            flips += last.changed
        return RunResult(y, last.stop, last.attempt + 1, flips, net)
    state, code, attempts, flips = run_network(seed, stop_rule == "sweep", patience, max_sweeps * n,
                                          _NO_STATE if y0 is None else y0, y0 is None,
                                          *_weights(net, rule).run_args)
    return RunResult._of(state, _STOP_NAMES[code], attempts, flips, net)
