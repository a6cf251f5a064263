"""The 2-D discrete Hopfield network of the thesis (§3.2, §3.3).

Neuron ``a = (i, k)`` says "left feature i matches right feature k".  Only
*candidate* neurons (see :func:`ismb_lab.similarity.candidate_mask`) exist here;
all other neurons of the ``N_l x N_r`` grid are fixed at 0 and drop out.  The
energy is (3-15)::

    E = - sum_{ik} sum_{jl} C_ikjl y_ik y_jl
        + sum_i (1 - sum_k y_ik)^2 + sum_k (1 - sum_i y_ik)^2 - sum_ik S_ik y_ik

Exact Hopfield form
-------------------
Expanding with ``y^2 = y`` gives ``E = N_l + N_r - 1/2 y'Wy - I'y`` with

* ``W_ab = 2 C_ab`` for neighbouring pairs (the double sum counts each pair twice),
* ``W_ab = -2`` when ``a`` and ``b`` share a left or a right feature,
* ``W_aa = 0`` (no self-connection), and ``I_a = 2 + S_a``.

With ``u_a = sum_b W_ab y_b + I_a`` an asynchronous flip changes the energy by
exactly ``dE = -u_a dy_a <= 0``.  This is ``rule="exact"``, the default.

The thesis' literal rule
------------------------
(3-16)/(3-17) use ``W = C - delta_ij - delta_kl``: the quadratic part halved, and
(3-20) sums over *all* ``(j, l)``, the neuron itself included, which adds a
self-weight ``C_ikik - 2`` (about -1).  Then ``u`` is not the energy gradient,
flips can raise ``E`` and the network can oscillate forever.  It is kept as
``rule="thesis"`` so a class can watch it fail.

Exact arithmetic
----------------
Weights and biases are rounded once to multiples of ``2**-40`` (about 1e-12) and
held as 64-bit integers.  Every net input is then an exact integer sum, whatever
the order of summation, so the readable kernel (which re-sums (3-20) at every
attempt) and the fast kernel (which updates ``u`` incrementally after each flip)
make bit-identical decisions.

Update order
------------
Attempts visit neurons in a random order drawn from a numpy Generator in fixed
blocks (:func:`visiting_order`), shared by both kernels.  Two stop rules:

* ``"sweep"`` (default): a full random-order sweep over all neurons changes
  nothing.  That is an exact fixed point.
* ``"stall"``: ``patience`` (200 in the thesis) consecutive attempts, drawn with
  replacement, change nothing.  With many neurons it can stop short of a fixed point.

Both give up after ``max_sweeps * n`` attempts (stop rule ``"max_attempts"``).

Beyond the thesis: a feature may stay unmatched
-----------------------------------------------
``(1 - r)^2`` with ``r = sum_k y_ik`` is smallest at *exactly one* match, so every
corner without a partner (occluded, or simply not detected in the other image)
is pushed to take a wrong one.  A network carries two more numbers, a
uniqueness strength ``kappa`` and a match bias ``beta`` (the thesis: 1 and 2),
and its energy is::

    E = - sum C y y + kappa sum_i (h - r_i)^2 + kappa sum_k (h - c_k)^2 - sum S y,
    h = 1/2 + beta / (4 kappa)

``h`` is the preferred number of matches per feature.  For binary ``y``,
``r^2 = r + 2 * (pairs of matches in the row)``, so
``kappa (h - r)^2 = kappa h^2 + kappa (1 - 2h) r + 2 kappa * pairs``.  Adding the
row and column terms gives the exact Hopfield form

* ``W_ab = 2 C_ab`` for neighbouring pairs, ``W_ab = -2 kappa`` on a shared
  row or column, ``W_aa = 0``;
* ``I_a = S_a + 2 kappa (2h - 1) = S_a + beta``;
* ``E = kappa h^2 (N_l + N_r) - 1/2 y'Wy - I'y``,

and still ``dE = -u dy`` for every asynchronous flip: ``u_a`` is exactly
``E(y_a = 0) - E(y_a = 1)`` with all other outputs fixed, because ``W`` is
symmetric with a zero diagonal.  With ``h = 1/2`` (``beta = 0``) no match and one
match cost the same, ``kappa / 4``, two matches ``9 kappa / 4``: the term only
says *at most one*, and ``S`` and ``C`` decide whether a match is worth it.
The thesis' energy is ``kappa = 1, beta = 2`` (``h = 1``), bit for bit.
"""

from __future__ import annotations

import itertools
import numbers
from dataclasses import dataclass
from functools import cached_property
from typing import Iterator, NamedTuple

import numba
import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_choice, check_number, check_rng, message

SCALE = 2.0 ** 40
RULES = ("exact", "thesis")
STOP_RULES = ("sweep", "stall")
KERNELS = ("numba", "textbook")
_BLOCK_SWEEPS = 4


def _quantise(x) -> np.ndarray:
    return np.rint(np.asarray(x, dtype=float) * SCALE).astype(np.int64)


def _csr(n: int, src: np.ndarray, dst: np.ndarray):
    """Compressed rows: for each source, its destinations; plus the sort order used."""
    order = np.lexsort((dst, src))
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n), out=indptr[1:])
    return indptr, dst[order].astype(np.int64), order


class _Layout(NamedTuple):
    """Adjacency of a topology in compressed-row form, read by both kernels."""

    nb_ptr: np.ndarray   # neighbours of neuron a: nb_idx[nb_ptr[a]:nb_ptr[a + 1]]
    nb_idx: np.ndarray
    nb_pair: np.ndarray  # the pair index of each neighbour entry
    row_ptr: np.ndarray  # neurons of left feature i: row_idx[row_ptr[i]:row_ptr[i + 1]]
    row_idx: np.ndarray
    col_ptr: np.ndarray  # neurons of right feature k
    col_idx: np.ndarray


@dataclass(frozen=True, eq=False)
class Topology:
    """Which neurons exist and which pairs of them interact.

    A topology depends on the features and the candidate window only, not on
    the energy parameters, so all networks a GA builds for one image pair share
    one topology: it is validated and laid out once.

    Parameters
    ----------
    n_left, n_right : int
        Number of left and right features ``N_l`` and ``N_r``.
    rows, cols : (n,) int array_like
        Left feature ``i`` and right feature ``k`` of each candidate neuron,
        sorted by ``(i, k)``.
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
        object.__setattr__(self, "_orders", {})

    def __getstate__(self):
        # The remembered visiting orders hold generators, which cannot be pickled (worker
        # processes of the protocol); a copy draws them again, the same for the same seed.
        return {**self.__dict__, "_orders": {}}

    @property
    def n_neurons(self) -> int:
        return len(self.rows)

    @property
    def n_pairs(self) -> int:
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

    def orders(self, seed: int, stop_rule: str) -> Iterator[np.ndarray]:
        """:func:`visiting_order` of ``default_rng(seed)``, remembered for reuse.

        The visiting order does not depend on the energy, so networks that
        share this topology and a seed (a GA's population) draw it only once.
        """
        key = (seed, stop_rule)
        if key not in self._orders:
            self._orders[key] = ([], visiting_order(np.random.default_rng(seed), self.n_neurons, stop_rule))
        blocks, source = self._orders[key]
        for t in itertools.count():
            if t == len(blocks):
                blocks.append(next(source))
            yield blocks[t]


@dataclass(frozen=True, eq=False)
class Network:
    """An energy (3-15) over the candidate neurons of one image pair.

    Parameters
    ----------
    topology : Topology
        The candidate neurons and their interacting pairs.
    similarity : (n,) float array_like
        ``S_ik`` of each neuron, in ``[-1, 1]`` (zero for Method-I).
    pair_c : (P,) float array_like
        Compatibility ``C_ab`` in ``[-1, 1]`` of each interacting pair.
    self_c : (n,) float array_like, optional
        ``C_ikik`` (a neuron's compatibility with itself, ``X = 0`` for the
        geometric terms).  Only the thesis' literal rule uses it.
    uniqueness : float
        ``kappa > 0``, the weight of the uniqueness terms (1 in (3-15)).
    match_bias : float
        ``beta``, the bias every neuron gets on top of ``S`` (2 in (3-15), which
        asks for exactly one match per feature; see the module docstring).

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
            object.__setattr__(self, name, values)
        object.__setattr__(self, "_weights", {})

    @classmethod
    def _trusted(cls, topology: Topology, similarity, pair_c, self_c, uniqueness: float = 1.0,
                 match_bias: float = 2.0) -> "Network":
        """Skip validation: for float arrays of the right lengths that are finite by
        construction (transfer functions of validated parameters), and validated scalars."""
        net = object.__new__(cls)
        for name, value in (("topology", topology), ("similarity", similarity),
                            ("pair_c", pair_c), ("self_c", self_c), ("uniqueness", float(uniqueness)),
                            ("match_bias", float(match_bias)), ("_weights", {})):
            object.__setattr__(net, name, value)
        return net

    @classmethod
    def from_arrays(cls, n_left, n_right, rows, cols, similarity, pair_a, pair_b, pair_c,
                    self_c=None, uniqueness: float = 1.0, match_bias: float = 2.0) -> "Network":
        """Build the topology and the network in one call."""
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


class _Weights(NamedTuple):
    """Fixed-point weights of one rule, in the layout the kernels read."""

    nb_ptr: np.ndarray
    nb_idx: np.ndarray
    nb_w: np.ndarray
    row_ptr: np.ndarray
    row_idx: np.ndarray
    col_ptr: np.ndarray
    col_idx: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    row_w: np.int64
    col_w: np.int64
    self_w: np.ndarray
    bias: np.ndarray


def _weights(net: Network, rule: str) -> _Weights:
    if rule in net._weights:
        return net._weights[rule]
    lay = net.topology.layout
    exact = rule == "exact"
    # exact: W = 2C, -2 kappa on a shared row or column, no self-weight;
    # thesis: (3-17) taken literally, W = C - kappa - kappa, with the neuron's own term of (3-20)
    kappa = net.uniqueness
    nb_w, self_w, bias = _quantised(net.pair_c, lay.nb_pair, net.similarity, net.self_c, exact, SCALE,
                                    net.match_bias, 2.0 * kappa)
    unique = np.int64(_quantise(-2.0 * kappa if exact else -kappa))
    w = _Weights(lay.nb_ptr, lay.nb_idx, nb_w, lay.row_ptr, lay.row_idx, lay.col_ptr, lay.col_idx,
                 net.rows, net.cols, unique, unique, self_w, bias)
    net._weights[rule] = w
    return w


@numba.njit(cache=True)
def _quantised(pair_c, nb_pair, similarity, self_c, exact, scale, match_bias, self_penalty):
    nb_w = np.empty(nb_pair.shape[0], dtype=np.int64)
    for p in range(nb_pair.shape[0]):
        c = pair_c[nb_pair[p]]
        nb_w[p] = np.int64(np.rint((2.0 * c if exact else c) * scale))
    n = similarity.shape[0]
    self_w = np.zeros(n, dtype=np.int64)
    bias = np.empty(n, dtype=np.int64)
    for a in range(n):
        bias[a] = np.int64(np.rint((match_bias + similarity[a]) * scale))
        if not exact:
            self_w[a] = np.int64(np.rint((self_c[a] - self_penalty) * scale))
    return nb_w, self_w, bias


def hopfield_form(net: Network, rule: str = "exact") -> tuple[np.ndarray, np.ndarray]:
    """Dense weights ``W`` and biases ``I`` with ``E = const - 1/2 y'Wy - I'y``.

    For teaching and checking on small networks; the kernels use a sparse layout.

    Parameters
    ----------
    net : Network
    rule : {"exact", "thesis"}
        ``"exact"``: ``W = 2C``, ``-2 kappa`` on a shared row or column, zero diagonal.
        ``"thesis"``: (3-17) literally, ``W = C - kappa (delta_ij + delta_kl)``
        including the diagonal ``C_ikik - 2 kappa``.  Both have ``I = beta + S``
        (``kappa = 1`` and ``beta = 2`` in the thesis); the constant is
        :attr:`Network.constant`.

    Returns
    -------
    W : (n, n) ndarray
    I : (n,) ndarray

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
    """The thesis energy (3-15), computed from its definition.

    It reads ``C`` and ``S`` directly and never the Hopfield weights, so it can
    check them.  A network with its own ``uniqueness`` and ``match_bias`` has
    the uniqueness terms ``kappa (h - r)^2`` of the module docstring instead of
    ``(1 - r)^2``.

    Parameters
    ----------
    net : Network
    state : (n,) array_like of {0, 1}
        Outputs of the candidate neurons; all other neurons are 0.

    Returns
    -------
    E : float

    Examples
    --------
    >>> net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, 0.0],
    ...               pair_a=[], pair_b=[], pair_c=[])
    >>> energy(net, [1, 0])   # row and column 0 satisfied, column 1 empty
    0.5
    >>> energy(net, [1, 1])   # (1 - 2)^2 + 0 + 0 - 0.5
    0.5
    """
    y = _check_state(net, state, "energy")
    return _energy(net.n_left, net.n_right, net.rows, net.cols, net.similarity, net.pair_a,
                   net.pair_b, net.pair_c, y, net.uniqueness, net.target_count)


@numba.njit(cache=True)
def _energy(n_left, n_right, rows, cols, similarity, pair_a, pair_b, pair_c, y, kappa, h):
    # - sum_ik sum_jl C_ikjl y_ik y_jl: each stored pair stands for (a, b) and (b, a)
    compatibility = 0.0
    for p in range(pair_a.shape[0]):
        compatibility -= 2.0 * pair_c[p] * y[pair_a[p]] * y[pair_b[p]]
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


def _check_state(net: Network, state, owner: str) -> np.ndarray:
    y = np.asarray(state)
    if y.shape != (net.n_neurons,) or not np.all((y == 0) | (y == 1)):
        raise ParameterError(message("state", owner, f"a 0/1 array of shape ({net.n_neurons},)",
                                 f"an array of shape {y.shape}" if y.shape != (net.n_neurons,) else y))
    return y.astype(np.uint8)


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
        return net.topology.orders(int(rng), stop_rule), y0
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
