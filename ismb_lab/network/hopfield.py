"""The 2-D discrete Hopfield network of the thesis (§3.2, §3.3): its neurons, weights and energy.

Neuron ``a = (i, k)`` says "left feature i matches right feature k"; only candidate neurons
exist.  The energy (3-15), with a uniqueness strength ``kappa`` and a match bias ``beta``
(the thesis: 1 and 2), is::

    E = - sum_{ik} sum_{jl} C_ikjl y_ik y_jl
        + kappa sum_i (h - sum_k y_ik)^2 + kappa sum_k (h - sum_i y_ik)^2 - sum_ik S_ik y_ik,
    h = 1/2 + beta / (4 kappa)

``h`` is the preferred number of matches per feature: 1 in the thesis, 1/2 ("at most one")
for ``beta = 0``.  With ``y^2 = y`` its exact Hopfield form is ``E = kappa h^2 (N_l + N_r)
- 1/2 y'Wy - I'y`` with ``W_ab = 2 C_ab`` between neighbours, ``-2 kappa`` on a shared row
or column, ``W_aa = 0`` and ``I_a = S_a + beta``; every asynchronous flip then changes the
energy by exactly ``-u_a dy_a`` (``rule="exact"``).  ``rule="thesis"`` takes (3-16)/(3-17)
and (3-20) literally, ``W = C - kappa (delta_ij + delta_kl)`` with a self-weight
``C_ikik - 2 kappa``: flips can raise ``E`` and the network can oscillate.

Weights and biases are rounded once to multiples of ``2**-40`` and held as int64, so every
net input is an exact sum in any order and both kernels make bit-identical decisions.
"""

from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass
from functools import cached_property

import numba
import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_choice, check_number, message

__all__ = ["MAX_INPUT", "MAX_NEURONS", "RULES", "SCALE", "energy", "hopfield_form", "Network", "Topology"]

SCALE = 2.0 ** 40
RULES = ("exact", "thesis")
#: Bits of a neighbour's index in a packed weight entry (:class:`_Weights`).
NB_SHIFT = 21
#: The most candidate neurons a network holds: one more needs a 22-bit index.
MAX_NEURONS = 1 << NB_SHIFT
_ONE_WEIGHT = 1 << NB_SHIFT   # a packed entry is at least this when its weight is positive


def _csr(n: int, src: np.ndarray, dst: np.ndarray):
    """Compressed rows: for each source, its destinations; plus the sort order used."""
    order = np.lexsort((dst, src))
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n), out=indptr[1:])
    return indptr, dst[order].astype(np.int64), order


# A topology's adjacency in compressed rows, read by both kernels: the neighbours of neuron a
# are nb_idx[nb_ptr[a]:nb_ptr[a + 1]] (nb_pair: their pairs), the neurons of left feature i
# row_idx[row_ptr[i]:row_ptr[i + 1]], and those of right feature k likewise in col_idx.
_Layout = namedtuple("_Layout", "nb_ptr nb_idx nb_pair row_ptr row_idx col_ptr col_idx")


@dataclass(frozen=True, eq=False)
class Topology:
    """Which neurons exist and which pairs of them interact (shared by all networks of a pair).

    Parameters
    ----------
    rows, cols : (n,) int array_like
        Left and right feature of each candidate neuron, sorted by ``(i, k)``.
    pair_a, pair_b : (P,) int array_like
        Interacting neuron pairs, ``pair_a < pair_b``, on different rows and columns.

    Examples
    --------
    >>> top = Topology(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1], pair_a=[0, 1], pair_b=[3, 2])
    >>> top.n_neurons, top.n_pairs
    (4, 2)
    """

    n_left: int
    n_right: int
    rows: np.ndarray
    cols: np.ndarray
    pair_a: np.ndarray
    pair_b: np.ndarray

    def __post_init__(self):
        owner = "Topology"
        check_number(self.n_left, "n_left", owner, low=0, integer=True)
        check_number(self.n_right, "n_right", owner, low=0, integer=True)
        for name in ("rows", "cols", "pair_a", "pair_b"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=np.int64).ravel())
        n, rows, cols, a, b = self.n_neurons, self.rows, self.cols, self.pair_a, self.pair_b
        if n > MAX_NEURONS:
            raise ParameterError(message("rows", owner, f"at most {MAX_NEURONS:,} candidate neurons", n))
        if len(cols) != n:
            raise ParameterError(message("cols", owner, f"of length {n} like 'rows'", f"length {len(cols)}"))
        if len(b) != len(a):
            raise ParameterError(message("pair_b", owner, "as long as 'pair_a'", f"length {len(b)}"))
        if n and (rows.min() < 0 or rows.max() >= self.n_left):
            raise ParameterError(message("rows", owner, f"indices in [0, {self.n_left})", rows))
        if n and (cols.min() < 0 or cols.max() >= self.n_right):
            raise ParameterError(message("cols", owner, f"indices in [0, {self.n_right})", cols))
        if np.any(np.diff(rows * max(self.n_right, 1) + cols) <= 0):
            raise ParameterError(message("rows", owner, "sorted by (row, col) without repeats",
                                         "unsorted or repeated neurons"))
        if len(a):
            if a.min() < 0 or b.max() >= n or np.any(a >= b):
                raise ParameterError(message("pair_a", owner, f"indices with 0 <= pair_a < pair_b < {n}",
                                             "other indices"))
            if np.any(rows[a] == rows[b]) or np.any(cols[a] == cols[b]):
                raise ParameterError(message("pair_a", owner, "pairs of neurons on different rows and "
                                             "columns (C is zero when i == j or k == l)",
                                             "a shared row or column"))

    @property
    def n_neurons(self) -> int:
        """int: candidate neurons."""
        return len(self.rows)

    @property
    def n_pairs(self) -> int:
        """int: interacting neuron pairs."""
        return len(self.pair_a)

    @cached_property
    def layout(self) -> _Layout:
        n, p = self.n_neurons, self.n_pairs
        src = np.concatenate([self.pair_a, self.pair_b])
        dst = np.concatenate([self.pair_b, self.pair_a])
        nb_ptr, nb_idx, order = _csr(n, src, dst)
        nb_pair = np.concatenate([np.arange(p), np.arange(p)])[order].astype(np.int64)
        idx = np.arange(n, dtype=np.int64)
        row_ptr, row_idx, _ = _csr(self.n_left, self.rows, idx)
        col_ptr, col_idx, _ = _csr(self.n_right, self.cols, idx)
        return _Layout(nb_ptr, nb_idx, nb_pair, row_ptr, row_idx, col_ptr, col_idx)

    @cached_property
    def packed(self) -> np.ndarray:
        """The layout the compiled run reads, in one int64 buffer (one array crosses into
        compiled code faster than five): segment j is ``packed[packed[j]:packed[j + 1]]``,
        in the order of :data:`PACKED`."""
        lay = self.layout
        neurons = np.stack([self.rows, self.cols], axis=1).astype(np.uint32).reshape(-1)
        parts = (lay.nb_ptr, lay.row_ptr, lay.col_ptr, neurons.view(np.int64), lay.col_idx)
        starts = len(parts) + 1 + np.cumsum([0] + [len(x) for x in parts])
        return np.concatenate([starts, *parts]).astype(np.int64)

    @cached_property
    def crowding(self) -> tuple[int, int]:
        """The most neurons sharing a neuron's row or column (itself included), and the most
        neighbours of one neuron: what bounds a net input."""
        lay = self.layout
        if self.n_neurons == 0:
            return 0, 0
        crowd = (np.diff(lay.row_ptr)[self.rows] + np.diff(lay.col_ptr)[self.cols]).max()
        return int(crowd), int(np.diff(lay.nb_ptr).max())


@dataclass(frozen=True, eq=False)
class Network:
    """An energy (3-15) over the candidate neurons of one image pair.

    Attributes
    ----------
    topology : Topology
        The candidate neurons and their interacting pairs.
    similarity : (n,) float array_like
        ``S_ik`` of each neuron, in ``[-1, 1]``.
    pair_c : (P,) float array_like
        Compatibility ``C_ab`` in ``[-1, 1]`` of each interacting pair.
    self_c : (n,) float array_like, optional
        ``C_ikik``; only the thesis' literal rule uses it.
    uniqueness : float, default 1.0
        ``kappa > 0`` (1 in (3-15)).
    match_bias : float, default 2.0
        ``beta`` (2 in (3-15): exactly one match per feature).

    Raises
    ------
    ParameterError
        Arrays of the wrong length, values outside ``[-1, 1]``, or ``kappa <= 0``.

    Examples
    --------
    >>> net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1],
    ...                           similarity=[0.5, -0.5, -0.5, 0.5],
    ...                           pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.9])
    >>> net.n_neurons, net.n_pairs
    (4, 2)
    """

    topology: Topology
    similarity: np.ndarray
    pair_c: np.ndarray
    self_c: np.ndarray | None = None
    uniqueness: float = 1.0
    match_bias: float = 2.0

    def __post_init__(self):
        owner = "Network"
        object.__setattr__(self, "uniqueness",
                           check_number(self.uniqueness, "uniqueness", owner, low=0, low_open=True))
        object.__setattr__(self, "match_bias", check_number(self.match_bias, "match_bias", owner))
        if not isinstance(self.topology, Topology):
            raise ParameterTypeError(message("topology", owner, "a Topology", type(self.topology).__name__))
        n, p = self.topology.n_neurons, self.topology.n_pairs
        if self.self_c is None:
            object.__setattr__(self, "self_c", np.zeros(n))
        for name, length in (("similarity", n), ("pair_c", p), ("self_c", n)):
            values = np.asarray(getattr(self, name), dtype=float).ravel()
            if len(values) != length:
                raise ParameterError(message(name, owner, f"of length {length}", f"length {len(values)}"))
            if not np.all(np.isfinite(values)):
                raise ParameterError(message(name, owner, "finite", "NaN or infinite values"))
            # the fixed-point weights and the overflow bound of _check_fits rely on it
            if len(values) and np.abs(values).max() > 1:
                raise ParameterError(message(name, owner, "values in [-1, 1]", values[np.abs(values) > 1][:3].tolist()))
            object.__setattr__(self, name, values)
        object.__setattr__(self, "_weights", {})

    @classmethod
    def _trusted(cls, topology: Topology, similarity, pair_c, self_c, uniqueness: float = 1.0,
                 match_bias: float = 2.0) -> "Network":
        """Skip validation: for arrays finite by construction and validated scalars."""
        net = object.__new__(cls)
        for name, value in (("topology", topology), ("similarity", similarity),
                            ("pair_c", pair_c), ("self_c", self_c), ("uniqueness", float(uniqueness)),
                            ("match_bias", float(match_bias)), ("_weights", {})):
            object.__setattr__(net, name, value)
        return net

    @classmethod
    def from_arrays(cls, n_left, n_right, rows, cols, similarity, pair_a, pair_b, pair_c,
                    self_c=None, uniqueness: float = 1.0, match_bias: float = 2.0) -> "Network":
        """Build the topology and the network in one call.

        Parameters
        ----------
        n_left, n_right : int
            Features in the left and the right image.
        rows, cols : (n,) int array_like
            Left and right feature of each candidate neuron, sorted by ``(i, k)``.
        similarity : (n,) float array_like
            ``S_ik`` of each neuron, in ``[-1, 1]``.
        pair_a, pair_b : (P,) int array_like
            Interacting neuron pairs.
        pair_c : (P,) float array_like
            ``C_ab`` of each pair, in ``[-1, 1]``.
        self_c : (n,) float array_like, optional
            ``C_ikik``, for the thesis' literal rule.
        uniqueness : float, default 1.0
            ``kappa``.
        match_bias : float, default 2.0
            ``beta``.

        Returns
        -------
        net : Network
            The network.
        """
        return cls(Topology(n_left, n_right, rows, cols, pair_a, pair_b), similarity, pair_c, self_c,
                   uniqueness, match_bias)

    n_left = property(lambda self: self.topology.n_left)
    n_right = property(lambda self: self.topology.n_right)
    rows = property(lambda self: self.topology.rows)
    cols = property(lambda self: self.topology.cols)
    pair_a = property(lambda self: self.topology.pair_a)
    pair_b = property(lambda self: self.topology.pair_b)
    n_neurons = property(lambda self: self.topology.n_neurons)
    n_pairs = property(lambda self: self.topology.n_pairs)

    @property
    def target_count(self) -> float:
        """``h = 1/2 + beta / (4 kappa)``, the preferred number of matches per feature.

        >>> net = Network.from_arrays(1, 1, [0], [0], [0.0], [], [], [])
        >>> net.target_count, Network(net.topology, [0.0], [], match_bias=0.0).target_count
        (1.0, 0.5)
        """
        return 0.5 + self.match_bias / (4.0 * self.uniqueness)

    @property
    def constant(self) -> float:
        """The constant of the Hopfield form, ``kappa h^2 (N_l + N_r)``."""
        return self.uniqueness * self.target_count ** 2 * (self.n_left + self.n_right)

    def initial_state(self) -> np.ndarray:
        """Every candidate neuron on, as in §3.3."""
        return np.ones(self.n_neurons, dtype=np.uint8)

    def to_matrix(self, state) -> np.ndarray:
        """The full ``N_l x N_r`` 0/1 grid of a state over the candidate neurons."""
        grid = np.zeros((self.n_left, self.n_right), dtype=np.uint8)
        grid[self.rows, self.cols] = np.asarray(state, dtype=np.uint8)
        return grid


#: The segments of :attr:`Topology.packed`, in order.
PACKED = ("nb_ptr", "row_ptr", "col_ptr", "neurons", "col_idx")


class _Weights(namedtuple("_Weights", "nb_ptr row_ptr row_idx col_ptr col_idx rows cols row_w col_w "
                                      "self_w bias values run_args")):
    """Fixed-point weights of one rule, in the layout the kernels read.

    ``values`` is one buffer, ``entries | self_w | bias | pos_end | row_w | col_w``.  An entry
    holds a neighbour weight shifted left by :data:`NB_SHIFT` bits and the neighbour's index
    in those bits (one word read per neighbour); a weight is at most ``2**41``, so it fits
    the 43 bits left.  Neuron ``a``'s entries are ``entries[nb_ptr[a]:nb_ptr[a + 1]]``, its
    positive weights first (up to ``pos_end[a]``), so the compiled run can stop summing once
    the input is negative.  ``run_args`` are the compiled run's last arguments,
    ``(Topology.packed, values)``.
    """

    __slots__ = ()

    @property
    def nb_idx(self) -> np.ndarray:
        """Each entry's neighbour, unpacked from ``values``."""
        return self.values[:self.nb_ptr[-1]] & (MAX_NEURONS - 1)

    @property
    def nb_w(self) -> np.ndarray:
        """Each entry's weight, unpacked from ``values``."""
        return self.values[:self.nb_ptr[-1]] >> NB_SHIFT

    @property
    def pos_end(self) -> np.ndarray:
        """Where each neuron's positive weights end in ``entries``."""
        m, n = int(self.nb_ptr[-1]), len(self.bias)
        return self.values[m + 2 * n:m + 3 * n]


#: Largest net input the 64-bit fixed point holds with room to spare: 2**62 / SCALE, about 4.2e6.
MAX_INPUT = 2.0 ** 62 / SCALE


def _check_fits(net: Network, lay) -> None:
    """Refuse a network whose net inputs could overflow the int64 sums.

    ``|u| <= |beta| + 1 + 2 kappa (row + column size) + 2 (neighbours) + 2 kappa``.
    """
    n = net.n_neurons
    if n == 0:
        return
    crowd, neighbours = net.topology.crowding
    bound = abs(net.match_bias) + 1 + 2 * net.uniqueness * (crowd + 1) + 2 * neighbours
    if bound < MAX_INPUT:
        return
    rest = bound - abs(net.match_bias)
    name, value, room = (("match_bias", net.match_bias, MAX_INPUT - rest)
                         if abs(net.match_bias) >= 2 * net.uniqueness * (crowd + 1) else
                         ("uniqueness", net.uniqueness, (MAX_INPUT - 1 - abs(net.match_bias)) / (2 * (crowd + 1))))
    raise ParameterError(message(name, "Network", f"small enough for exact 64-bit net inputs (|{name}| below "
                                 f"about {max(room, 0):.3g} for this network)", value))


def _weights(net: Network, rule: str) -> _Weights:
    if rule in net._weights:
        return net._weights[rule]
    lay = net.topology.layout
    exact = rule == "exact"
    # exact: W = 2C, -2 kappa on a shared row or column, no self-weight;
    # thesis: (3-17) taken literally, W = C - kappa - kappa, with the neuron's own term of (3-20)
    kappa = net.uniqueness
    _check_fits(net, lay)
    # round() of a float rounds half to even, as np.rint does, to the same integer
    unique = np.int64(round((-2.0 * kappa if exact else -kappa) * SCALE))
    values = _quantised(net.pair_c, lay.nb_ptr, lay.nb_pair, lay.nb_idx, net.similarity, net.self_c, exact,
                        SCALE, net.match_bias, 2.0 * kappa, unique)
    m, n = len(lay.nb_pair), net.n_neurons
    w = _Weights(lay.nb_ptr, lay.row_ptr, lay.row_idx, lay.col_ptr, lay.col_idx,
                 net.rows, net.cols, unique, unique, values[m:m + n], values[m + n:m + 2 * n], values,
                 (net.topology.packed, values))
    net._weights[rule] = w
    return w


@numba.njit(cache=True)
def _quantised(pair_c, nb_ptr, nb_pair, nb_idx, similarity, self_c, exact, scale, match_bias, self_penalty,
               unique):
    """The ``values`` buffer of :class:`_Weights`: each neuron's positive weights from the
    front of its segment, the others from the back."""
    m, n = nb_pair.shape[0], similarity.shape[0]
    values = np.zeros(m + 3 * n + 2, dtype=np.int64)
    values[-2] = values[-1] = unique
    entries, self_w, bias, pos_end = values[:m], values[m:m + n], values[m + n:m + 2 * n], values[m + 2 * n:m + 3 * n]
    ptr = nb_ptr.view(np.uint64)   # unsigned: no test for a negative (from-the-end) index
    one = np.uint64(1)
    for a in range(n):
        # positive weights from the front, the others from the back: each entry is stored at
        # both ends of the part not yet filled, and the end that keeps it moves on, so no
        # branch depends on a weight's sign (the other copy is overwritten later)
        front, back = ptr[a], ptr[a + 1]
        for p in range(ptr[a], ptr[a + 1]):
            c = pair_c[nb_pair[p]]
            e = (np.int64(np.rint((2.0 * c if exact else c) * scale)) << NB_SHIFT) | nb_idx[p]
            entries[front] = e
            entries[back - one] = e
            positive = np.uint64(e >= _ONE_WEIGHT)
            front += positive
            back -= one - positive
        pos_end[a] = front
        bias[a] = np.int64(np.rint((match_bias + similarity[a]) * scale))
        if not exact:
            self_w[a] = np.int64(np.rint((self_c[a] - self_penalty) * scale))
    return values


def hopfield_form(net: Network, rule: str = "exact") -> tuple[np.ndarray, np.ndarray]:
    """Dense weights ``W`` and biases ``I`` with ``E = const - 1/2 y'Wy - I'y``, for small networks.

    ``rule="exact"``: ``W = 2C``, ``-2 kappa`` on a shared row or column, zero diagonal;
    ``"thesis"``: (3-17) literally, with the diagonal ``C_ikik - 2 kappa``.  Both have
    ``I = beta + S``; the constant is :attr:`Network.constant`.

    Parameters
    ----------
    net : Network
        The network.
    rule : {"exact", "thesis"}, default "exact"
        Which weights.

    Returns
    -------
    W : (n, n) float array
        The weights.
    I : (n,) float array
        The biases.

    Examples
    --------
    >>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, 0.0],
    ...               pair_a=[], pair_b=[], pair_c=[])
    >>> W, I = hopfield_form(net)
    >>> W
    array([[ 0., -2.],
           [-2.,  0.]])
    >>> I
    array([2.5, 2. ])
    """
    check_choice(rule, "rule", "hopfield_form", RULES)
    n, kappa = net.n_neurons, net.uniqueness
    same = (net.rows[:, None] == net.rows[None, :]).astype(float) + (net.cols[:, None] == net.cols[None, :])
    W = np.zeros((n, n))
    W[net.pair_a, net.pair_b] = net.pair_c
    W += W.T
    if rule == "exact":
        W = 2.0 * W - (2.0 * kappa) * same
        np.fill_diagonal(W, 0.0)
    else:
        W = W - kappa * same
        W[np.diag_indices(n)] = net.self_c - 2.0 * kappa
    return W, net.match_bias + net.similarity


def energy(net: Network, state) -> float:
    """The energy (3-15) of a 0/1 `state`, from ``C`` and ``S`` directly (never the weights).

    Parameters
    ----------
    net : Network
        The network.
    state : (n,) 0/1 array
        Output of each candidate neuron.

    Returns
    -------
    E : float
        The energy.

    Raises
    ------
    ParameterError
        `state` not a 0/1 array of length ``n``.

    Examples
    --------
    >>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, 0.0],
    ...               pair_a=[], pair_b=[], pair_c=[])
    >>> energy(net, [1, 0])   # row and column 0 satisfied, column 1 empty
    0.5
    >>> energy(net, [1, 1])   # (1 - 2)^2 + 0 + 0 - 0.5
    0.5
    """
    return _energy_of(net, _check_state(net, state, "energy"))


def _energy_of(net: Network, y: np.ndarray) -> float:
    """:func:`energy` of a state known to be a 0/1 uint8 array of the right length."""
    top = net.topology
    return _energy(top.n_left, top.n_right, top.rows, top.cols, net.similarity, top.pair_a,
                   top.pair_b, net.pair_c, y, net.uniqueness, net.target_count)


@numba.njit(cache=True)
def _energy(n_left, n_right, rows, cols, similarity, pair_a, pair_b, pair_c, y, kappa, h):
    # - sum_ik sum_jl C_ikjl y_ik y_jl: each stored pair stands for (a, b) and (b, a)
    compatibility = 0.0
    for p in range(pair_a.shape[0]):
        # a pair with a neuron off adds a signed zero, which changes no sum: skip it
        if y[pair_a[p]] and y[pair_b[p]]:
            compatibility -= 2.0 * pair_c[p]
    row_sum = np.zeros(n_left)
    col_sum = np.zeros(n_right)
    similar = 0.0
    for a in range(rows.shape[0]):
        row_sum[rows[a]] += y[a]
        col_sum[cols[a]] += y[a]
        similar += similarity[a] * y[a]
    uniqueness = 0.0
    for i in range(n_left):
        uniqueness += kappa * (h - row_sum[i]) ** 2
    for k in range(n_right):
        uniqueness += kappa * (h - col_sum[k]) ** 2
    return compatibility + uniqueness - similar


def check_net(net, owner: str) -> Network:
    if not isinstance(net, Network):
        raise ParameterTypeError(message("net", owner, "a Network", type(net).__name__))
    return net


def _check_state(net: Network, state, owner: str) -> np.ndarray:

    y = np.asarray(state)
    if y.shape != (net.n_neurons,) or not np.all((y == 0) | (y == 1)):
        raise ParameterError(message("state", owner, f"a 0/1 array of shape ({net.n_neurons},)",
                                 f"an array of shape {y.shape}" if y.shape != (net.n_neurons,) else y))
    return y.astype(np.uint8)
