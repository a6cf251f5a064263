"""Mean-field annealing: the analog Hopfield network on the same energy (thesis future work 1).

The discrete network flips one neuron at a time and stops at the first state no
single flip improves.  The analog network keeps a *probability* ``v_a`` in
``[0, 1]`` per neuron and sets it to the mean-field value at temperature ``T``::

    v_a = 1 / (1 + exp(-u_a / T)),    u_a = sum_b W_ab v_b + I_a

with the exact weights of :func:`ismb_lab.hopfield.hopfield_form`.  At high ``T``
every ``v`` sits near 1/2 and the energy landscape is smooth; cooling slowly
lets the ``v`` commit one after another, usually into a deeper minimum than a
greedy descent from "all on".  At each temperature the neurons are updated
asynchronously in a random order, for `sweeps` sweeps.  The energy reported on
the way is ``const - 1/2 v'Wv - I'v``, which equals :func:`ismb_lab.hopfield.energy`
for 0/1 states.

At the end ``v`` is rounded at 1/2 and handed to the discrete network
(:func:`ismb_lab.dynamics.run` from that state), so the answer is an exact fixed
point like the discrete network's.

>>> from ismb_lab.hopfield import Network
>>> net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1],
...                           similarity=[0.5, -0.5, -0.5, 0.5],
...                           pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.9])
>>> result = anneal(net, rng=0)
>>> result.state.tolist(), round(result.energy, 2)
([1, 0, 0, 1], -2.8)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import numba
import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_number, check_rng, message
from .hopfield import Network, energy, hopfield_form
from .dynamics import run

__all__ = ["anneal", "AnnealResult", "AnnealStep", "iter_annealing"]


@dataclass(frozen=True)
class AnnealStep:
    """One temperature of the schedule, after its sweeps.

    Attributes
    ----------
    index : int
    temperature : float
    change : float
        Largest ``|dv|`` of the last sweep.
    energy : float
        ``const - 1/2 v'Wv - I'v`` of the analog state.
    committed : float
        Share of neurons with ``v`` below 0.05 or above 0.95.
    """

    index: int
    temperature: float
    change: float
    energy: float
    committed: float


@dataclass(frozen=True, eq=False)
class AnnealResult:
    """Outcome of :func:`anneal`.

    Attributes
    ----------
    state : (n,) uint8 ndarray
        The discrete fixed point reached from the rounded analog state.
    energy : float
        Its energy (:func:`ismb_lab.hopfield.energy`).
    rounded : (n,) uint8 ndarray
        ``v > 1/2`` at the end of the schedule, before the discrete polish.
    analog : (n,) float ndarray
        The final ``v``.
    steps : int
        Temperatures visited.
    """

    state: np.ndarray
    energy: float
    rounded: np.ndarray
    analog: np.ndarray
    steps: int


@numba.njit(cache=True)
def _sweeps(W, u, v, orders, T):
    """Asynchronous mean-field updates at temperature `T`, one sweep per row of `orders`;
    `v` and the net inputs `u` are updated in place.  Returns the largest ``|dv|``.

    ``exp`` is the C library's, as :func:`math.exp` is: a plain Python loop with
    ``math.exp`` gives the same numbers bit for bit (tested)."""
    change = 0.0
    for s in range(orders.shape[0]):
        for a in orders[s]:
            x = u[a] / T
            if x >= 0:
                new = 1.0 / (1.0 + np.exp(-x))
            else:
                z = np.exp(x)
                new = z / (1.0 + z)
            d = new - v[a]
            if d != 0.0:
                v[a] = new
                for b in range(u.shape[0]):   # W is symmetric: row a is column a
                    u[b] += W[a, b] * d
                change = max(change, abs(d))
    return change


def iter_annealing(net: Network, *, rng=0, t_start: float = 2.0, t_end: float = 0.02,
                   cooling: float = 0.9, sweeps: int = 2, state: list | None = None) -> Iterator[AnnealStep]:
    """Cool the analog network, yielding an :class:`AnnealStep` per temperature.

    Parameters
    ----------
    net : Network
    rng : int or numpy.random.Generator
        Seeds the start (``v = 1/2`` plus noise of 0.01) and the visiting orders.
    t_start, t_end : float
        First and last temperature, ``t_start > t_end > 0``; in units of the
        weights (``S`` and ``C`` lie in [-1, 1], so 2 is "hot").
    cooling : float
        Factor in (0, 1) between consecutive temperatures.
    sweeps : int
        Asynchronous sweeps per temperature.
    state : list, optional
        If given, a one-element list that receives the analog state array
        (updated in place as the schedule runs), for callers that want ``v``.

    Yields
    ------
    step : AnnealStep

    Examples
    --------
    >>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.8, -0.8],
    ...                           pair_a=[], pair_b=[], pair_c=[], match_bias=0.0)
    >>> steps = list(iter_annealing(net, rng=0))
    >>> steps[0].temperature, round(steps[-1].temperature, 3), steps[-1].committed
    (2.0, 0.021, 1.0)
    """
    owner = "iter_annealing"
    if not isinstance(net, Network):
        raise ParameterTypeError(message("net", owner, "a Network", type(net).__name__))
    t_end = check_number(t_end, "t_end", owner, low=0, low_open=True)
    t_start = check_number(t_start, "t_start", owner, low=t_end)
    cooling = check_number(cooling, "cooling", owner, low=0, low_open=True)
    if cooling >= 1:
        raise ParameterError(message("cooling", owner, "a number in (0, 1)", cooling))
    sweeps = check_number(sweeps, "sweeps", owner, low=1, integer=True)
    rng = check_rng(rng, "rng", owner)
    return _anneal(net, rng, t_start, t_end, cooling, sweeps, state)


def _anneal(net, rng, t_start, t_end, cooling, sweeps, holder):
    W, I = hopfield_form(net)
    n = net.n_neurons
    v = 0.5 + 0.01 * rng.uniform(-1, 1, n)
    if holder is not None:
        holder[:] = [v]
    u = W @ v + I
    T, index = t_start, 0
    while T >= t_end * (1 - 1e-12):
        orders = np.array([rng.permutation(n) for _ in range(sweeps)], dtype=np.int64).reshape(sweeps, n)
        change = _sweeps(W, u, v, orders, T)
        e = net.constant - 0.5 * v @ W @ v - I @ v
        committed = float(np.mean((v < 0.05) | (v > 0.95))) if n else 1.0
        yield AnnealStep(index, float(T), float(change), float(e), committed)
        index += 1
        T *= cooling


def anneal(net: Network, *, rng=0, t_start: float = 2.0, t_end: float = 0.02, cooling: float = 0.9,
           sweeps: int = 2) -> AnnealResult:
    """Run :func:`iter_annealing` to the end, round ``v`` at 1/2 and settle with the discrete network.

    Parameters are those of :func:`iter_annealing`.

    Returns
    -------
    result : AnnealResult

    Examples
    --------
    >>> net = Network.from_arrays(2, 1, rows=[0, 1], cols=[0, 0], similarity=[0.9, 0.2],
    ...                           pair_a=[], pair_b=[], pair_c=[], match_bias=0.0)
    >>> anneal(net, rng=3).state.tolist()     # the better of two rivals for one column
    [1, 0]
    """
    rng = check_rng(rng, "rng", "anneal")
    holder: list = []
    steps = 0
    for steps, _ in enumerate(iter_annealing(net, rng=rng, t_start=t_start, t_end=t_end,
                                             cooling=cooling, sweeps=sweeps, state=holder), 1):
        pass
    v = holder[0] if holder else np.zeros(0)
    rounded = (v > 0.5).astype(np.uint8)
    polish = run(net, rng=rng, state=rounded)
    return AnnealResult(polish.state, energy(net, polish.state), rounded, v.copy(), steps)
