"""The exact global minimum of a network's energy ``const - 1/2 y'Wy - I'y``, for small problems.

:func:`exhaustive_minimum` visits all ``2**n`` states in Gray-code order (one flip, one
update of the net inputs per state) on the kernels' fixed-point integers, so ties are exact.
:func:`milp_minimum` solves a mixed-integer programme with ``z_ab = y_a y_b`` linearised
(``z <= y_a, z <= y_b`` where ``W_ab > 0``, ``z >= y_a + y_b - 1`` where it costs): it
scales further, to the solver's tolerance.

>>> from ismb_lab.network.hopfield import Network
>>> net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1],
...                           similarity=[0.5, -0.5, -0.5, 0.5],
...                           pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.9])
>>> best = exhaustive_minimum(net)
>>> best.state.tolist(), round(best.energy, 2), best.n_minima
([1, 0, 0, 1], -2.8, 1)
>>> milp_minimum(net).state.tolist()
[1, 0, 0, 1]
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from .._core.validation import ParameterError, check_number, message
from .hopfield import SCALE, Network, check_net, energy, hopfield_form

__all__ = ["MAX_EXHAUSTIVE", "MAX_TIME_LIMIT", "exhaustive_minimum", "milp_minimum", "Minimum"]

#: Largest network :func:`exhaustive_minimum` accepts (``2**26`` states).
MAX_EXHAUSTIVE = 26
#: Longest time limit of :func:`milp_minimum`, in seconds: one hour.
MAX_TIME_LIMIT = 3600.0


@dataclass(frozen=True, eq=False)
class Minimum:
    """A global minimum of the energy: a minimising ``state`` (the first met, exhaustively),
    its ``energy``, how many states tie exactly (``n_minima``; 1 for the MILP, which reports
    one) and the ``method``, ``"exhaustive"`` or ``"milp"``."""

    state: np.ndarray
    energy: float
    n_minima: int
    method: str


def _integer_form(net: Network) -> tuple[np.ndarray, np.ndarray]:
    W, I = hopfield_form(net)
    return np.rint(W * SCALE).astype(np.int64), np.rint(I * SCALE).astype(np.int64)


@numba.njit(cache=True)
def _gray_search(W, I):
    n = I.shape[0]
    y = np.zeros(n, dtype=np.int64)
    u = I.copy()                  # net inputs of the all-off state
    e = np.int64(0)               # energy minus the constant, in units of 2**-40
    best = np.int64(0)
    best_code = np.int64(0)
    count = np.int64(1)
    code = np.int64(0)
    for step in range(1, np.int64(1) << n):
        a = 0                     # Gray code: flip the lowest set bit of the step
        while not (step >> a) & 1:
            a += 1
        d = 1 - 2 * y[a]
        e -= u[a] * d
        y[a] += d
        code ^= np.int64(1) << a
        for b in range(n):
            u[b] += W[b, a] * d
        if e < best:
            best, best_code, count = e, code, np.int64(1)
        elif e == best:
            count += 1
    return best_code, count


def exhaustive_minimum(net: Network) -> Minimum:
    """Search all ``2**n`` states (``n`` at most :data:`MAX_EXHAUSTIVE`) for the lowest energy.

    Examples
    --------
    >>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, 0.0],
    ...                           pair_a=[], pair_b=[], pair_c=[])
    >>> m = exhaustive_minimum(net)        # [1, 0] and [1, 1] both have E = 0.5
    >>> m.state.tolist(), m.energy, m.n_minima
    ([1, 0], 0.5, 2)
    """
    net = check_net(net, "exhaustive_minimum")
    n = net.n_neurons
    if n > MAX_EXHAUSTIVE:
        raise ParameterError(message("net", "exhaustive_minimum", f"at most {MAX_EXHAUSTIVE} candidate "
                                     "neurons (2**n states); use milp_minimum", f"{n} neurons"))
    W, I = _integer_form(net)
    code, count = _gray_search(W, I)
    state = ((int(code) >> np.arange(n)) & 1).astype(np.uint8)
    return Minimum(state, energy(net, state), int(count), "exhaustive")


def milp_minimum(net: Network, *, time_limit: float = 60.0) -> Minimum:
    """The minimum energy as a mixed-integer linear programme (``scipy.optimize.milp``).

    A ``ParameterError`` says when the solver gave up within `time_limit` seconds (at most
    :data:`MAX_TIME_LIMIT`) without proving optimality.

    Parameters
    ----------
    net : Network
        The network.
    time_limit : float, default 60.0
        Seconds the solver may take, > 0 and at most :data:`MAX_TIME_LIMIT`.

    Returns
    -------
    minimum : Minimum
        A minimising state (``n_minima`` 1, ``method`` ``"milp"``).

    Raises
    ------
    ParameterError
        A bad `time_limit`, or no proven optimum within it.

    Examples
    --------
    >>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, -0.7],
    ...                           pair_a=[], pair_b=[], pair_c=[])
    >>> milp_minimum(net).state.tolist()
    [1, 0]
    """
    from scipy.optimize import Bounds, LinearConstraint, milp
    from scipy.sparse import coo_matrix

    net = check_net(net, "milp_minimum")
    limit = check_number(time_limit, "time_limit", "milp_minimum", low=0, low_open=True, high=MAX_TIME_LIMIT)
    n = net.n_neurons
    if n == 0:
        empty = np.zeros(0, dtype=np.uint8)
        return Minimum(empty, energy(net, empty), 1, "milp")
    W, I = hopfield_form(net)
    a, b = np.nonzero(np.triu(W, k=1))
    w = W[a, b]
    m = len(a)
    cost = np.concatenate([-I, -w])           # E - const = -sum I y - sum_{a<b} W_ab z_ab
    rows, cols, vals, upper = [], [], [], []
    reward = np.flatnonzero(w > 0)
    for r, p in enumerate(reward):            # z - y_a <= 0 and z - y_b <= 0
        rows += [2 * r, 2 * r, 2 * r + 1, 2 * r + 1]
        cols += [n + p, a[p], n + p, b[p]]
        vals += [1.0, -1.0, 1.0, -1.0]
    upper += [0.0] * (2 * len(reward))
    first = 2 * len(reward)
    for r, p in enumerate(np.flatnonzero(w < 0)):   # y_a + y_b - z <= 1
        rows += [first + r] * 3
        cols += [a[p], b[p], n + p]
        vals += [1.0, 1.0, -1.0]
        upper.append(1.0)
    constraints = []
    if upper:
        A = coo_matrix((vals, (rows, cols)), shape=(len(upper), n + m)).tocsr()
        constraints.append(LinearConstraint(A, -np.inf, np.array(upper)))
    result = milp(cost, constraints=constraints, integrality=np.concatenate([np.ones(n), np.zeros(m)]),
                  bounds=Bounds(0, 1), options={"time_limit": limit})
    if result.status != 0:
        raise ParameterError(message("net", "milp_minimum", f"a problem the solver can close within "
                                     f"{limit:g} s", f"status {result.status}: {result.message}"))
    state = (result.x[:n] > 0.5).astype(np.uint8)
    return Minimum(state, energy(net, state), 1, "milp")
