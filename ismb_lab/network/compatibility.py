"""Pairwise compatibility of two candidate matches (thesis 3-12, 3-13).

Neurons ``a = (i, k)`` and ``b = (j, l)`` interact only when ``i`` and ``j`` are neighbours
and ``k != l``.  For such a pair:

* ``dd = |d_ik - d_jl|``: smoothness, the difference of the two (Euclidean) disparities;
* ``dD = | ||p_i - p_j|| - ||q_k - q_l|| |``: geometry, the change of the point distance;
* ``dY = |(y_k - y_i) - (y_l - y_j)|``: the difference of the vertical disparities.

Method-II uses ``X = dd + dD``, Method-III ``X = dd + dD + dY``; ``C = transfer(X)`` is
symmetric, so only pairs ``a < b`` are stored.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from scipy.spatial import cKDTree

from .._core.validation import ParameterError, check_choice, check_number, check_points
from ..images.coords import euclidean_disparity

__all__ = ["left_neighbours", "neuron_pairs", "NeuronPairs"]


def left_neighbours(left_xy, *, radius: float = 20.0, shape: str = "box") -> np.ndarray:
    """Unordered pairs ``(i, j)``, ``i < j``, of neighbouring left features, in lexicographic order.

    The thesis gives "distance < 20 px" (3-12, ``shape="disc"``) and "a 40 x 40 region
    centred on feature i" (§3.3, the procedure it runs; ``"box"``, the default).

    Parameters
    ----------
    left_xy : (N, 2) float array
        Left features ``(x, y)``.
    radius : float, default 20.0
        Features closer than this interact (> 0).
    shape : {"box", "disc"}, default "box"
        Chebyshev or Euclidean distance.

    Returns
    -------
    pairs : (P, 2) int64 array
        The pairs ``(i, j)``.

    Examples
    --------
    >>> left_neighbours([[0, 0], [15, 15], [40, 0]])
    array([[0, 1]])
    >>> left_neighbours([[0, 0], [15, 15], [40, 0]], shape="disc")
    array([], shape=(0, 2), dtype=int64)
    """
    radius = check_number(radius, "radius", "left_neighbours", low=0, low_open=True)
    check_choice(shape, "shape", "left_neighbours", ("box", "disc"))
    xy = check_points(left_xy, "left_xy", "left_neighbours")
    # A k-d tree offers every pair within a slightly larger reach (memory and time grow with
    # the pairs, not with N²); the exact rule then decides, as a dense comparison would.
    reach = radius * (1 + 1e-9) + 1e-9
    pairs = cKDTree(xy).query_pairs(reach, p=np.inf if shape == "box" else 2, output_type="ndarray")
    pairs = np.sort(pairs.astype(np.int64).reshape(-1, 2), axis=1)
    diff = xy[pairs[:, 0]] - xy[pairs[:, 1]]
    if shape == "box":
        near = np.all(np.abs(diff) < radius, axis=1)
    else:
        near = np.hypot(diff[:, 0], diff[:, 1]) < radius
    pairs = pairs[near]
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


@dataclass(frozen=True)
class NeuronPairs:
    """Interacting neuron pairs ``a < b`` and their differences ``dd``, ``dD``, ``dY`` (pixels)."""

    a: np.ndarray
    b: np.ndarray
    dd: np.ndarray
    dD: np.ndarray
    dY: np.ndarray

    def __len__(self) -> int:
        return len(self.a)


def neuron_pairs(left_xy, right_xy, rows, cols, neighbours) -> NeuronPairs:
    """All pairs of candidate neurons (`rows` sorted, `cols`) whose left points are `neighbours`.

    Every ``(a, b)`` with ``(rows[a], rows[b])`` a neighbour pair and ``cols[a] != cols[b]``.

    Examples
    --------
    >>> p = neuron_pairs([[100, 50], [110, 50]], [[80, 51], [90, 51]], [0, 0, 1, 1], [0, 1, 0, 1], [[0, 1]])
    >>> p.a, p.b
    (array([0, 1]), array([3, 2]))
    >>> p.dd.round(2)   # the crossed pair (1, 2) breaks smoothness
    array([ 0.  , 19.97])
    """
    lxy = check_points(left_xy, "left_xy", "neuron_pairs")
    rxy = check_points(right_xy, "right_xy", "neuron_pairs")
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    nb = np.asarray(neighbours, dtype=np.int64).reshape(-1, 2)
    if np.any(np.diff(rows) < 0):
        raise ParameterError("The 'rows' parameter of neuron_pairs must be sorted ascending. "
                         f"Got {rows.tolist()[:10]} instead.")
    counts = np.bincount(rows, minlength=len(lxy))
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    p, q = lxy[rows], rxy[cols]
    a, b, dd, dD, dY = _pairs(nb, starts, cols, p, q, euclidean_disparity(p, q))
    return NeuronPairs(a=a, b=b, dd=dd, dD=dD, dY=dY)


@numba.njit(cache=True)
def _pairs(nb, starts, cols, p, q, disparity):
    """The pairs and their differences in one pass, with the order and arithmetic of the NumPy
    expressions they replace (``math.hypot`` compiles to the C library's, as ``np.hypot`` is)."""
    size = 0
    for t in range(nb.shape[0]):
        for u in range(starts[nb[t, 0]], starts[nb[t, 0] + 1]):
            for v in range(starts[nb[t, 1]], starts[nb[t, 1] + 1]):
                size += cols[u] != cols[v]
    a = np.empty(size, dtype=np.int64)
    b = np.empty(size, dtype=np.int64)
    dd, dD, dY = np.empty(size), np.empty(size), np.empty(size)
    m = 0
    for t in range(nb.shape[0]):
        i, j = nb[t, 0], nb[t, 1]
        for u in range(starts[i], starts[i + 1]):
            for v in range(starts[j], starts[j + 1]):
                if cols[u] == cols[v]:
                    continue
                a[m], b[m] = u, v
                dd[m] = abs(disparity[u] - disparity[v])
                dD[m] = abs(math.hypot(p[u, 0] - p[v, 0], p[u, 1] - p[v, 1])
                            - math.hypot(q[u, 0] - q[v, 0], q[u, 1] - q[v, 1]))
                dY[m] = abs((q[u, 1] - p[u, 1]) - (q[v, 1] - p[v, 1]))
                m += 1
    return a, b, dd, dD, dY
