"""The compiled network run of :func:`ismb_lab.network.dynamics.run`, and a GA's batch of them.

It draws the visiting order from the SplitMix64 stream of
:func:`ismb_lab.network.dynamics.visiting_order` and makes the same exact integer decisions
as the textbook kernel there; the tests hold the two to bit-identical agreement.
"""

from __future__ import annotations

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils, types

from .hopfield import NB_SHIFT, PACKED, _quantised

__all__ = ["fitness_runs", "run_network"]

_GOLDEN, _MIX1, _MIX2 = 0x9E3779B97F4A7C15, 0xBF58476D1CE4E5B9, 0x94D049BB133111EB

_U64 = numba.types.uint64
# numba freezes module globals as constants; as plain ints these would not fit an int64
_GOLDEN_U, _MIX1_U, _MIX2_U = np.uint64(_GOLDEN), np.uint64(_MIX1), np.uint64(_MIX2)


@numba.njit(cache=True)
def _next(state):
    """One SplitMix64 step: ``(new state, number)``, all arithmetic modulo 2**64."""
    state = _U64(state + _GOLDEN_U)
    z = state
    z = _U64((z ^ (z >> _U64(30))) * _MIX1_U)
    z = _U64((z ^ (z >> _U64(27))) * _MIX2_U)
    return state, _U64(z ^ (z >> _U64(31)))


@numba.njit(cache=True)
def _ones_below(x):
    """`x` with every bit under its highest set bit set: the mask of a draw below ``x + 1``."""
    mask = _U64(x)
    mask |= mask >> _U64(1)
    mask |= mask >> _U64(2)
    mask |= mask >> _U64(4)
    mask |= mask >> _U64(8)
    mask |= mask >> _U64(16)
    mask |= mask >> _U64(32)
    return mask


@numba.njit(cache=True)
def _below(state, bound):
    """:meth:`_Stream.below`: ``(new state, a number in range(bound))``."""
    mask = _ones_below(bound - 1)
    while True:
        state, x = _next(state)
        x = _U64(x & mask)
        if x < _U64(bound):
            return state, np.int64(x)


@numba.njit(cache=True)
def _draw(drawn, state):
    """Fill `drawn` with the stream's next ``len(drawn)`` numbers after `state`.  Each number
    depends on its place only, so the loop vectorises."""
    for k in range(drawn.shape[0]):
        z = _U64(state + _U64(k + 1) * _GOLDEN_U)
        z = _U64((z ^ (z >> _U64(30))) * _MIX1_U)
        z = _U64((z ^ (z >> _U64(27))) * _MIX2_U)
        drawn[k] = z ^ (z >> _U64(31))


@numba.njit(cache=True)
def _shuffle(order, state, drawn):
    """Shuffle `order` in place as :func:`visiting_order`'s sweep does, and return the new state.

    The same draws as ``_below(state, t + 1)`` for ``t = n - 1, ..., 1``, without a branch on
    the draw: a rejected number swaps ``t`` with itself and leaves it where it is.  The
    numbers come ``len(drawn)`` at a time (:func:`_draw`); the state returned is that after
    the last number used.
    """
    state, one = _U64(state), _U64(1)
    t = _U64(max(order.shape[0] - 1, 0))   # unsigned: no test for a negative index
    m = _U64(drawn.shape[0])
    k = m
    while t > _U64(0):
        mask = _ones_below(t)
        low = mask >> one   # the mask holds while t is above its lower half
        while t > low:
            if k == m:
                _draw(drawn, state)
                state = _U64(state + m * _GOLDEN_U)
                k = _U64(0)
            x = drawn[k] & mask
            k += one
            # accepted when x <= t: swapped with x, and t moves down; else swapped with itself
            j = min(x, t)
            order[t], order[j] = order[j], order[t]
            t = t - one + _U64(x > t)   # a compare and an add with carry: the loop's chain
    return _U64(state - (m - k) * _GOLDEN_U)


@numba.extending.intrinsic
def _prefetch(typingctx, array, index):
    """Ask the processor to fetch ``array[index]`` into its caches (LLVM's ``prefetch``);
    nothing is read or changed."""
    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        byte = ir.IntType(8).as_pointer()
        fn = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(ir.VoidType(), [byte] + [ir.IntType(32)] * 3), "llvm.prefetch.p0")
        i32 = ir.IntType(32)
        builder.call(fn, [builder.bitcast(builder.gep(data, [args[1]]), byte), i32(0), i32(3), i32(1)])
        return context.get_dummy_value()
    return types.void(array, index), codegen


# The run takes the topology's integers in one buffer (Topology.packed) and the network's in
# another (_Weights.values): a compiled call unboxes each array argument, about 0.1 us apiece.
_NB_PTR, _ROW_PTR, _COL_PTR, _NEURONS, _COL_IDX = range(len(PACKED))
_INDEX = (1 << NB_SHIFT) - 1   # an entry's low bits: the neighbour's index
_AHEAD = 4
_FEW = 2   # a sweep with at most this many flips is often the last to flip: test for the end
_DRAWN = 128   # numbers drawn at a time for a shuffle


@numba.njit(cache=True)
def _segment(packed, j):
    return packed[packed[j]:packed[j + 1]]


@numba.njit(cache=True)
def _split(packed, values):
    """``(entries, self_w, bias, pos_end)``: the views of a :class:`_Weights` ``values`` buffer."""
    m, n = packed[packed[_NB_PTR + 1] - 1], packed[_NEURONS + 1] - packed[_NEURONS]
    return values[:m], values[m:m + n], values[m + n:m + 2 * n], values[m + 2 * n:m + 3 * n]


@numba.njit(cache=True)
def _inputs_of(y, u, nb_ptr, entries, self_w, bias, neurons, on_in_row, on_in_col, row_w, col_w):
    """Fill ``u`` with every net input: ``bias_a + self_w_a y_a + sum_b W_ab y_b`` and the
    uniqueness terms, pushing the weights of the neurons on."""
    for a in range(y.shape[0]):
        ya = np.int64(y[a])
        u[a] = (bias[a] + self_w[a] * ya + row_w * (on_in_row[neurons[2 * a]] - ya)
                + col_w * (on_in_col[neurons[2 * a + 1]] - ya))
    for a in range(y.shape[0]):
        if y[a]:
            for p in range(nb_ptr[a], nb_ptr[a + 1]):
                x = entries[p]
                u[x & _INDEX] += x >> NB_SHIFT


@numba.njit(cache=True)
def _settled(y, u):
    """Whether no neuron would flip: every ``u_a`` is zero or has the sign of ``y_a``."""
    for a in range(y.shape[0]):
        ua = u[a]
        if (ua != 0) & ((ua > 0) ^ (y[a] == 1)):
            return False
    return True


@numba.njit(cache=True)
def _unstable_from(order, t, lim, u, y):
    """The first place in ``order[t:lim]`` of a neuron that would flip, or `lim`."""
    p, end = _U64(t), _U64(lim)
    while p < end:
        a = order[p]
        ya = np.int64(y[a])
        if (u[a] ^ -ya) + ya > 0:   # u_a, or -u_a when y_a is 1, is positive
            return np.int64(p)
        p += _U64(1)
    return lim


@numba.njit(cache=True)
def _pull_sweep(order, y, on_in_row, on_in_col, nb_ptr, entries, pos_end, neurons, self_w, bias, row_w, col_w,
                sweep_rule, patience, max_attempts, attempts, unchanged, from_on):
    """One sweep of :func:`run_network` that sums each attempt's input afresh; with `from_on`
    every neuron is on when attempted.  Returns ``(flips, attempts, unchanged, stop code or 0)``."""
    n = order.shape[0]
    changed = code = 0
    for t in range(n):
        a = order[t]
        attempts += 1
        ya = np.int64(1) if from_on else np.int64(y[a])
        if t + _AHEAD < n:
            _prefetch(entries, nb_ptr[order[t + _AHEAD]])
        i, k = neurons[a + a], neurons[a + a + _U64(1)]
        ua = bias[a] + self_w[a] * ya + row_w * (on_in_row[i] - ya) + col_w * (on_in_col[k] - ya)
        # the weights after pos_end[a] can only lower ua: once they are being read and ua is
        # negative, its sign is known.  Blocks of eight, whatever their signs, avoid a
        # mispredicted loop exit per attempt.
        p, mid, end = nb_ptr[a], pos_end[a], nb_ptr[a + _U64(1)]
        while p + _U64(8) <= end and (p < mid or ua >= 0):
            for q in range(p, p + _U64(8)):
                x = entries[q]
                ua += (x >> NB_SHIFT) * y[x & _INDEX]
            p += _U64(8)
        if p < mid or ua >= 0:
            for q in range(p, end):
                x = entries[q]
                ua += (x >> NB_SHIFT) * y[x & _INDEX]
        # flip when on with u < 0 or off with u > 0, without a branch on y: on a random
        # visiting order that branch is mispredicted about half the time
        if not ((ua != 0) & ((ua > 0) ^ (ya == 1))):
            unchanged += 1
            if not sweep_rule:
                if unchanged >= patience:
                    code = 2
                elif attempts >= max_attempts:
                    code = 3
                if code:
                    break
            continue
        y[a] = 1 - ya
        on_in_row[i] += 1 - 2 * ya
        on_in_col[k] += 1 - 2 * ya
        changed += 1
        unchanged = 0
        if not sweep_rule and attempts >= max_attempts:
            code = 3
            break
    return changed, attempts, unchanged, code


@numba.njit(cache=True)
def _push_sweep(order, y, u, nb_ptr, entries, neurons, row_ptr, col_ptr, col_idx, self_w, row_w, col_w,
                sweep_rule, patience, max_attempts, attempts, unchanged):
    """One sweep of :func:`run_network` that keeps every ``u`` current, each flip adding its
    weights to its neighbours' inputs; the attempts between two flips only look for the
    next neuron to flip.  Returns ``(flips, attempts, unchanged, stop code or 0)``."""
    n = order.shape[0]
    changed = code = 0
    t = 0
    while True:
        lim = n
        if not sweep_rule:
            lim = min(n, t + min(patience - unchanged, max_attempts - attempts))
        s = _unstable_from(order, t, lim, u, y)
        attempts += s - t
        unchanged += s - t
        if s == lim:
            if not sweep_rule:
                if unchanged >= patience:
                    code = 2
                elif attempts >= max_attempts:
                    code = 3
            break
        a = order[s]
        attempts += 1
        # a flip of y_a by d adds W_ab d to every u_b of a neighbour, and row_w d or col_w d
        # to every other neuron of its row and column (consecutive in a row); its own u_a
        # changes only by its self term.
        i, k = neurons[a + a], neurons[a + a + _U64(1)]
        if y[a]:
            y[a] = 0
            for p in range(nb_ptr[a], nb_ptr[a + _U64(1)]):
                x = entries[p]
                u[x & _INDEX] -= x >> NB_SHIFT
            for b in range(row_ptr[i], row_ptr[i + _U64(1)]):
                u[b] -= row_w
            for q in range(col_ptr[k], col_ptr[k + _U64(1)]):
                u[col_idx[q]] -= col_w
            u[a] += row_w + col_w - self_w[a]
        else:
            y[a] = 1
            for p in range(nb_ptr[a], nb_ptr[a + _U64(1)]):
                x = entries[p]
                u[x & _INDEX] += x >> NB_SHIFT
            for b in range(row_ptr[i], row_ptr[i + _U64(1)]):
                u[b] += row_w
            for q in range(col_ptr[k], col_ptr[k + _U64(1)]):
                u[col_idx[q]] += col_w
            u[a] += self_w[a] - row_w - col_w
        changed += 1
        unchanged = 0
        if not sweep_rule and attempts >= max_attempts:
            code = 3
            break
        t = s + 1
    return changed, attempts, unchanged, code


@numba.njit(cache=True)
def run_network(seed, sweep_rule, patience, max_attempts, y0, all_on, packed, values):
    """The whole run in one call, from `seed` (:func:`visiting_order`'s stream), every net
    input exact.  `packed` is :attr:`Topology.packed`, `values` the :class:`_Weights` buffer;
    with `all_on` the run starts from every neuron on (`y0` unread).  Returns ``(state, stop
    code of _STOP_NAMES, attempts, flips)``.

    ``u_a = c_a + row_w (R_i - y_a) + col_w (K_k - y_a)``, with ``R_i`` and ``K_k`` the
    neurons on in the row and column of ``a``: the same integers as (3-20) term by term.
    The first sweep pulls (most neurons flip in it, and pushing each flip cost more than
    the sums); later sweeps flip few neurons, so they push.  The stop tests are those of
    :func:`_updates`, in its order; after a sweep of few flips, a run that has settled
    counts the last sweep's attempts without drawing its order."""
    # indices read as unsigned: numba then skips the test for a negative (from-the-end) index

    nb_ptr = _segment(packed, _NB_PTR).view(np.uint64)
    row_ptr, col_ptr = _segment(packed, _ROW_PTR).view(np.uint64), _segment(packed, _COL_PTR).view(np.uint64)
    col_idx = _segment(packed, _COL_IDX).view(np.uint64)
    neurons = _segment(packed, _NEURONS).view(np.uint32)   # i, k of each neuron, side by side
    entries, self_w, bias, pos_end = _split(packed, values)
    pos_end = pos_end.view(np.uint64)
    row_w, col_w = values[-2], values[-1]
    n, n_left, n_right = self_w.shape[0], row_ptr.shape[0] - 1, col_ptr.shape[0] - 1
    # one allocation for the visiting order, the net inputs, the counts and the draws
    work = np.empty(2 * n + n_left + n_right + _DRAWN, dtype=np.int64)
    order, u = work[:n].view(np.uint64), work[n:2 * n]
    on_in_row, on_in_col = work[2 * n:2 * n + n_left], work[2 * n + n_left:2 * n + n_left + n_right]
    drawn = work[2 * n + n_left + n_right:].view(np.uint64)
    if all_on:
        y = np.ones(n, dtype=np.uint8)
        for i in range(n_left):
            on_in_row[i] = row_ptr[i + 1] - row_ptr[i]
        for k in range(n_right):
            on_in_col[k] = col_ptr[k + 1] - col_ptr[k]
    else:
        y = y0.copy()
        on_in_row[:] = 0
        on_in_col[:] = 0
        for a in range(n):
            on_in_row[neurons[2 * a]] += y[a]
            on_in_col[neurons[2 * a + 1]] += y[a]
    for t in range(n):
        order[t] = t
    state = _U64(seed)
    attempts = flips = unchanged = 0
    code = 0
    pull = True
    while code == 0:
        if sweep_rule:
            state = _shuffle(order, state, drawn)
        else:
            for t in range(n):
                state, order[t] = _below(state, n)
        if pull:
            changed, attempts, unchanged, code = _pull_sweep(
                order, y, on_in_row, on_in_col, nb_ptr, entries, pos_end, neurons, self_w, bias, row_w, col_w,
                sweep_rule, patience, max_attempts, attempts, unchanged, all_on and sweep_rule)
        else:
            changed, attempts, unchanged, code = _push_sweep(
                order, y, u, nb_ptr, entries, neurons, row_ptr, col_ptr, col_idx, self_w, row_w, col_w,
                sweep_rule, patience, max_attempts, attempts, unchanged)
        flips += changed
        if sweep_rule:
            if changed == 0:
                code = 1
            elif attempts >= max_attempts:
                code = 3
        if pull and code == 0:
            _inputs_of(y, u, nb_ptr, entries, self_w, bias, neurons, on_in_row, on_in_col, row_w, col_w)
            pull = False
        elif code == 0 and sweep_rule and changed <= _FEW and _settled(y, u):
            # no neuron would flip in the next sweep, whatever its order: it ends the run
            # with n attempts and no flip, so its order need not be drawn
            attempts += n
            code = 1
    return y, code, attempts, flips


@numba.njit(cache=True)
def _least_dy(on, owner, n_owner, dy):
    """Of the neurons `on` (ascending), the one of least ``dy`` of each owner (ties: the
    lower index), ascending: Method-I's post-processing step."""
    best = np.full(n_owner, -1, dtype=np.int64)
    for a in on:
        o = owner[a]
        b = best[o]
        if b < 0 or dy[a] < dy[b]:
            best[o] = a
    kept = best[best >= 0]
    kept.sort()
    return kept


@numba.njit(cache=True)
def fitness_runs(packed, nb_ptr, nb_pair, nb_idx, pair_c, similarity, self_c, match_bias, exact, scale,
                  self_penalty, unique, seeds, sweep_rule, patience, max_attempts, codes, least_dy, rows, cols,
                  n_left, n_right, dy):
    """``sum over seeds of (correct - wrong - extra)`` for each row of `pair_c`, `similarity`,
    `self_c` and `match_bias`: each network run from every neuron on, its matches (after
    Method-I's step with `least_dy`) tallied by `codes` as
    :func:`ismb_lab.tuning.evaluation._tally` does."""
    m = pair_c.shape[0]
    totals = np.zeros(m, dtype=np.int64)
    no_state = np.zeros(0, dtype=np.uint8)
    for j in range(m):
        values = _quantised(pair_c[j], nb_ptr, nb_pair, nb_idx, similarity[j], self_c[j], exact, scale,
                            match_bias[j], self_penalty, unique)
        for seed in seeds:
            y = run_network(seed, sweep_rule, patience, max_attempts, no_state, True, packed, values)[0]
            on = np.flatnonzero(y)
            if least_dy:
                on = _least_dy(_least_dy(on, rows, n_left, dy), cols, n_right, dy)
            for a in on:
                code = codes[a]
                totals[j] += np.int64(code == 1) - np.int64(code == 2) - np.int64(code == 3)
    return totals
