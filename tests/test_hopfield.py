"""The network against its theory: energy identities, descent, determinism, kernels."""

import numpy as np
import pytest

from ismb_lab.network.hopfield import MAX_NEURONS, SCALE, Network, Topology, _weights, energy, hopfield_form
from ismb_lab.network.dynamics import iter_updates, run


def random_network(seed, n_left=None, n_right=None, p_candidate=0.4, p_pair=0.5):
    """A random energy (3-15) with random candidates, S in [-1, 1] and C in [-1, 1]."""
    rng = np.random.default_rng(seed)
    n_left = n_left or int(rng.integers(2, 9))
    n_right = n_right or int(rng.integers(2, 9))
    mask = rng.random((n_left, n_right)) < p_candidate
    rows, cols = np.nonzero(mask)
    n = len(rows)
    a, b = np.triu_indices(n, k=1)
    ok = (rows[a] != rows[b]) & (cols[a] != cols[b]) & (rng.random(len(a)) < p_pair)
    a, b = a[ok], b[ok]
    return Network.from_arrays(n_left, n_right, rows, cols, similarity=rng.uniform(-1, 1, n),
                   pair_a=a, pair_b=b, pair_c=rng.uniform(-1, 1, len(a)),
                   self_c=rng.uniform(0, 1, n))


def dense(net, state):
    """The state, a dense 4-D C and S over the full N_l x N_r grid."""
    y = net.to_matrix(state).astype(float)
    C = np.zeros((net.n_left, net.n_right, net.n_left, net.n_right))
    ra, ca = net.rows[net.pair_a], net.cols[net.pair_a]
    rb, cb = net.rows[net.pair_b], net.cols[net.pair_b]
    C[ra, ca, rb, cb] = net.pair_c
    C[rb, cb, ra, ca] = net.pair_c
    S = np.zeros((net.n_left, net.n_right))
    S[net.rows, net.cols] = net.similarity
    return y, C, S


def thesis_energy(net, state):
    """(3-15) evaluated over the full N_l x N_r grid with a dense 4-D C."""
    y, C, S = dense(net, state)
    return (-np.einsum("ikjl,ik,jl->", C, y, y)
            + np.sum((1 - y.sum(axis=1)) ** 2) + np.sum((1 - y.sum(axis=0)) ** 2)
            - np.sum(S * y))


NETS = [random_network(s) for s in range(60)]
NETS = [net for net in NETS if net.n_neurons > 0]


@pytest.mark.parametrize("seed", range(20))
def test_energy_is_the_thesis_energy_and_the_hopfield_form(seed):
    net = NETS[seed]
    W, I = hopfield_form(net)
    rng = np.random.default_rng(seed)
    for _ in range(10):
        y = (rng.random(net.n_neurons) < 0.5).astype(np.uint8)
        e = energy(net, y)
        assert e == pytest.approx(thesis_energy(net, y), abs=1e-9)
        constant = net.n_left + net.n_right
        assert e == pytest.approx(constant - 0.5 * y @ W @ y - I @ y, abs=1e-9)


def test_exact_weights_have_the_derived_structure():
    net = NETS[3]
    W, I = hopfield_form(net)
    assert np.array_equal(W, W.T)
    assert np.all(np.diag(W) == 0)
    same_row = net.rows[:, None] == net.rows[None, :]
    same_col = net.cols[:, None] == net.cols[None, :]
    off = ~np.eye(net.n_neurons, dtype=bool)
    assert np.all(W[(same_row | same_col) & off] == -2)
    assert np.allclose(W[net.pair_a, net.pair_b], 2 * net.pair_c)
    assert np.allclose(I, 2 + net.similarity)


@pytest.mark.parametrize("stop_rule", ["sweep", "stall"])
@pytest.mark.parametrize("seed", range(12))
def test_every_flip_lowers_energy_by_u_times_dy(seed, stop_rule):
    net = NETS[seed]
    y = net.initial_state().astype(np.uint8)
    previous = energy(net, y)
    flips = 0
    for step in iter_updates(net, rng=seed, stop_rule=stop_rule):
        y[step.neuron] = step.new
        e = energy(net, y)
        assert e - previous == pytest.approx(-step.u * (step.new - step.old), abs=1e-9)
        assert e <= previous + 1e-9
        assert step.energy == pytest.approx(e, abs=1e-9)
        flips += step.changed
        previous = e
    assert flips > 0


@pytest.mark.parametrize("seed", range(15))
def test_sweep_rule_stops_at_an_exact_fixed_point(seed):
    net = NETS[seed]
    result = run(net, rng=seed)
    assert result.stop_rule == "sweep" and result.converged
    W, I = hopfield_form(net)
    u = W @ result.state + I
    assert np.all(result.state[u > 1e-9] == 1)
    assert np.all(result.state[u < -1e-9] == 0)


def test_stall_rule_counts_unchanged_attempts():
    net = NETS[0]
    steps = list(iter_updates(net, rng=0, stop_rule="stall", patience=7))
    tail = steps[-7:]
    assert steps[-1].stop == "stall"
    assert not any(s.changed for s in tail)
    assert steps[-8].changed
    assert all(s.stop is None for s in steps[:-1])


@pytest.mark.parametrize("rule", ["exact", "thesis"])
@pytest.mark.parametrize("stop_rule", ["sweep", "stall"])
@pytest.mark.parametrize("seed", range(25))
def test_kernels_agree_bit_for_bit(seed, stop_rule, rule):
    net = NETS[seed]
    fast = run(net, rng=seed, stop_rule=stop_rule, rule=rule, max_sweeps=40)
    slow = run(net, rng=seed, stop_rule=stop_rule, rule=rule, max_sweeps=40, kernel="textbook")
    assert np.array_equal(fast.state, slow.state)
    assert fast.energy == slow.energy
    assert (fast.stop_rule, fast.attempts, fast.flips) == (slow.stop_rule, slow.attempts, slow.flips)


@pytest.mark.parametrize("seed", range(10))
def test_kernels_agree_from_a_given_state(seed):
    """The compiled run starts from cached all-on inputs by default; a given state is summed anew."""
    net = NETS[seed]
    start = np.random.default_rng(seed).integers(0, 2, net.n_neurons).astype(np.uint8)
    fast = run(net, rng=seed, state=start)
    slow = run(net, rng=seed, state=start, kernel="textbook")
    assert np.array_equal(fast.state, slow.state) and fast.energy == slow.energy == energy(net, slow.state)
    assert (fast.attempts, fast.flips) == (slow.attempts, slow.flips)
    ones = np.ones(net.n_neurons, dtype=np.uint8)
    default, given = run(net, rng=seed), run(net, rng=seed, state=ones)
    assert np.array_equal(default.state, given.state) and default.energy == given.energy


def test_kernels_agree_on_large_networks():
    for seed in range(3):
        net = random_network(100 + seed, 60, 60, p_candidate=0.15, p_pair=0.3)
        fast = run(net, rng=seed)
        slow = run(net, rng=seed, kernel="textbook")
        assert net.n_neurons > 400
        assert np.array_equal(fast.state, slow.state) and fast.energy == slow.energy
        assert fast.attempts == slow.attempts


def test_ties_are_exact_in_fixed_point():
    # u = 2 + S + 2C - 2 = 0 exactly when S = 0 and C = 0: the neuron must stay as it is,
    # in both kernels, even after neighbours switch back and forth.
    net = Network.from_arrays(2, 3, rows=[0, 0, 1], cols=[0, 1, 2], similarity=[0.0, -0.3, 0.1],
                  pair_a=[0], pair_b=[2], pair_c=[0.1])
    for seed in range(10):
        fast = run(net, rng=seed)
        slow = run(net, rng=seed, kernel="textbook")
        assert np.array_equal(fast.state, slow.state)


def test_seeded_runs_are_bit_identical_and_seeds_matter():
    net = random_network(7, 40, 40, p_candidate=0.2, p_pair=0.4)
    a, b = run(net, rng=5), run(net, rng=5)
    assert np.array_equal(a.state, b.state) and a.energy == b.energy and a.attempts == b.attempts
    attempts = {run(net, rng=s).attempts for s in range(8)}
    assert len(attempts) > 1
    # a Generator gives one seed per run, drawn from it
    seed = int(np.random.default_rng(11).integers(0, 2**63, dtype=np.int64))
    c, d = run(net, rng=np.random.default_rng(11)), run(net, rng=seed)
    assert np.array_equal(c.state, d.state) and c.attempts == d.attempts


def test_compiled_stream_draws_what_the_python_stream_draws():
    from ismb_lab.network.dynamics import _below, _next, _Stream

    for seed in (0, 1, 2**63 - 1, 123456789):
        py, state = _Stream(seed), np.uint64(seed)
        for _ in range(200):
            state, x = _next(np.uint64(state))
            assert int(x) == py.next()
        for bound in (1, 2, 3, 7, 8, 9, 1000, 2**31 + 1, 2**40 - 3):
            state, x = _below(np.uint64(state), bound)
            assert int(x) == py.below(bound) and 0 <= int(x) < bound


@pytest.mark.parametrize("n", [0, 1, 2, 3, 4, 5, 8, 9, 16, 17, 58, 1024, 1025])
def test_compiled_shuffle_makes_the_sweeps_of_visiting_order(n):
    # the branch-free shuffle against the plain Fisher-Yates of the textbook stream, sizes
    # at and just past powers of two (where the mask changes), several sweeps in a row;
    # numbers drawn one, three and 128 at a time (refilled mid-sweep or not at all)
    from ismb_lab.network.dynamics import _Stream, _shuffle, visiting_order

    for seed in (0, 7, 2**63 - 1):
        for m in (1, 3, 128):
            sweeps = visiting_order(seed, n, "sweep")
            order, state, drawn = np.arange(n), np.uint64(seed), np.empty(m, dtype=np.uint64)
            for _ in range(4):
                state = _shuffle(order, np.uint64(state), drawn)
                np.testing.assert_array_equal(order, next(sweeps))
            py = _Stream(seed)
            for _ in range(4):
                for t in range(n - 1, 0, -1):
                    py.below(t + 1)
            assert int(state) == py.state


def test_visiting_orders_are_uniform_permutations():
    """Each sweep is a permutation; over many seeds every neuron comes first about equally
    often (chi-squared below the 0.1% critical value for 4 degrees of freedom, 18.47)."""
    from ismb_lab.network.dynamics import visiting_order

    first = np.zeros(5)
    for seed in range(5000):
        sweeps = visiting_order(seed, 5, "sweep")
        order = next(sweeps)
        assert sorted(order.tolist()) == [0, 1, 2, 3, 4] and sorted(next(sweeps).tolist()) == [0, 1, 2, 3, 4]
        first[order[0]] += 1
    assert ((first - 1000) ** 2 / 1000).sum() < 18.47
    stall = next(visiting_order(3, 1000, "stall"))
    assert stall.min() >= 0 and stall.max() < 1000 and len(set(stall.tolist())) < 1000


def test_literal_thesis_rule_raises_energy_and_fails_to_settle():
    raised = not_settled = runs = 0
    for seed, net in enumerate(NETS[:30]):
        runs += 1
        e = [s.energy for s in iter_updates(net, rng=seed, rule="thesis", max_sweeps=50)]
        raised += any(b > a + 1e-9 for a, b in zip(e, e[1:]))
        not_settled += not run(net, rng=seed, rule="thesis", max_sweeps=50).converged
    assert raised >= runs // 2
    assert not_settled >= runs // 2
    for seed, net in enumerate(NETS[:30]):
        assert run(net, rng=seed, rule="exact").converged


def test_literal_rule_uses_halved_weights_and_a_self_weight():
    net = NETS[2]
    W, I = hopfield_form(net, rule="thesis")
    We, _ = hopfield_form(net)
    off = ~np.eye(net.n_neurons, dtype=bool)
    assert np.allclose(W[off], We[off] / 2)
    assert np.allclose(np.diag(W), net.self_c - 2)


def test_empty_network_runs():
    net = Network.from_arrays(3, 0, rows=[], cols=[], similarity=[], pair_a=[], pair_b=[], pair_c=[])
    result = run(net)
    assert result.state.shape == (0,) and result.energy == 3.0 and result.attempts == 0
    assert list(iter_updates(net)) == []


@pytest.mark.parametrize("kwargs, error, words", [
    (dict(stop_rule="never"), ValueError, "'stop_rule'"),
    (dict(rule="mine"), ValueError, "'rule'"),
    (dict(kernel="cuda"), ValueError, "'kernel'"),
    (dict(patience=0), ValueError, "'patience'"),
    (dict(max_sweeps=1.5), TypeError, "'max_sweeps'"),
    (dict(rng=-1), ValueError, "'rng'"),
    (dict(rng="seed"), TypeError, "'rng'"),
    (dict(state=[2, 0]), ValueError, "'state'"),
])
def test_run_rejects_bad_arguments(kwargs, error, words):
    with pytest.raises(error, match=words):
        run(NETS[0], **kwargs)


@pytest.mark.parametrize("kwargs, words", [
    (dict(cols=[0, 5]), "'cols'"),
    (dict(rows=[1, 0]), "'rows'"),
    (dict(similarity=[np.nan, 0]), "'similarity'"),
    (dict(pair_a=[0], pair_b=[1], pair_c=[0.5]), "shared row"),
    (dict(similarity=[0.0]), "'similarity'"),
    (dict(similarity=[0.5, -1.5]), r"'similarity'.*in \[-1, 1\]. Got \[-1.5\]"),
    (dict(self_c=[1.01, 0.0]), r"'self_c'.*in \[-1, 1\]"),
])
def test_network_rejects_inconsistent_arrays(kwargs, words):
    base = dict(rows=[0, 0], cols=[0, 1], similarity=[0.0, 0.0], pair_a=[], pair_b=[], pair_c=[])
    base.update(kwargs)
    with pytest.raises(ValueError, match=words):
        Network.from_arrays(2, 2, **base)


def test_network_rejects_a_compatibility_outside_its_range():
    with pytest.raises(ValueError, match=r"'pair_c'.*in \[-1, 1\]. Got \[2.5\]"):
        Network.from_arrays(2, 2, rows=[0, 1], cols=[0, 1], similarity=[0.0, 0.0],
                            pair_a=[0], pair_b=[1], pair_c=[2.5])


def test_topology_refuses_more_neurons_than_an_entry_can_index():
    n = MAX_NEURONS + 1
    with pytest.raises(ValueError, match="'rows'.*at most 2,097,152 candidate neurons. Got 2097153"):
        Topology(1, n, np.zeros(n, dtype=np.int64), np.arange(n), [], [])


@pytest.mark.slow
def test_packed_entries_hold_the_extreme_weights_and_indices():
    """C = +-1 gives the largest weights, +-2**41 under the exact rule; the entries give them
    back with every neighbour's index, and both kernels then agree."""
    net = random_network(7, 40, 40, p_candidate=0.3, p_pair=0.4)
    extreme = np.where(np.arange(net.n_pairs) % 2, 1.0, -1.0)
    net = Network(net.topology, net.similarity, extreme, net.self_c)
    for rule, size in (("exact", 2.0 * SCALE), ("thesis", SCALE)):
        w = _weights(net, rule)
        assert np.array_equal(np.abs(w.nb_w), np.full(2 * net.n_pairs, size, dtype=np.int64))
        assert np.array_equal(w.values[:2 * net.n_pairs] & (MAX_NEURONS - 1), w.nb_idx)
        assert sorted(w.nb_idx.tolist()) == sorted(net.topology.layout.nb_idx.tolist())
        fast, slow = run(net, rng=3, rule=rule), run(net, rng=3, rule=rule, kernel="textbook")
        assert np.array_equal(fast.state, slow.state) and fast.attempts == slow.attempts


# --- Beyond the thesis: a uniqueness strength kappa and a match bias beta --------------------

def no_match_network(seed, **kwargs):
    """A random network with its own kappa in (0.3, 3) and beta in (-2, 2)."""
    net = random_network(seed, **kwargs)
    rng = np.random.default_rng(1000 + seed)
    return Network(net.topology, net.similarity, net.pair_c, net.self_c,
                   uniqueness=float(rng.uniform(0.3, 3.0)), match_bias=float(rng.uniform(-2.0, 2.0)))


def dense_energy(net, state):
    """-sum C y y + kappa sum (h - r)^2 + kappa sum (h - c)^2 - sum S y on the full grid."""
    y, C, S = dense(net, state)
    h = 0.5 + net.match_bias / (4 * net.uniqueness)
    return (-np.einsum("ikjl,ik,jl->", C, y, y)
            + net.uniqueness * (np.sum((h - y.sum(axis=1)) ** 2) + np.sum((h - y.sum(axis=0)) ** 2))
            - np.sum(S * y))


NM_NETS = [net for net in (no_match_network(s) for s in range(60)) if net.n_neurons > 0]


@pytest.mark.parametrize("seed", range(20))
def test_no_match_energy_equals_its_definition_and_hopfield_form(seed):
    net = NM_NETS[seed]
    W, I = hopfield_form(net)
    assert np.allclose(I, net.match_bias + net.similarity)
    rng = np.random.default_rng(seed)
    for _ in range(10):
        y = (rng.random(net.n_neurons) < 0.5).astype(np.uint8)
        e = energy(net, y)
        assert e == pytest.approx(dense_energy(net, y), abs=1e-9)
        assert e == pytest.approx(net.constant - 0.5 * y @ W @ y - I @ y, abs=1e-9)


@pytest.mark.parametrize("seed", range(20))
def test_no_match_net_input_is_the_energy_difference_of_one_flip(seed):
    # u_a = E(y_a = 0) - E(y_a = 1) with all other outputs fixed, for any state and neuron
    net = NM_NETS[seed]
    W, I = hopfield_form(net)
    rng = np.random.default_rng(seed)
    for _ in range(10):
        y = (rng.random(net.n_neurons) < 0.5).astype(np.uint8)
        a = int(rng.integers(net.n_neurons))
        on, off = y.copy(), y.copy()
        on[a], off[a] = 1, 0
        u = W[a] @ y + I[a]
        assert energy(net, off) - energy(net, on) == pytest.approx(u, abs=1e-9)


@pytest.mark.parametrize("stop_rule", ["sweep", "stall"])
@pytest.mark.parametrize("seed", range(12))
def test_no_match_flips_lower_energy_by_u_times_dy(seed, stop_rule):
    net = NM_NETS[seed]
    y = net.initial_state().astype(np.uint8)
    previous = energy(net, y)
    for step in iter_updates(net, rng=seed, stop_rule=stop_rule):
        y[step.neuron] = step.new
        e = energy(net, y)
        assert e - previous == pytest.approx(-step.u * (step.new - step.old), abs=1e-9)
        assert e <= previous + 1e-9 and step.energy == pytest.approx(e, abs=1e-9)
        previous = e
    W, I = hopfield_form(net)
    u = W @ y + I
    assert np.all(y[u > 1e-9] == 1) and np.all(y[u < -1e-9] == 0)


@pytest.mark.parametrize("rule", ["exact", "thesis"])
@pytest.mark.parametrize("seed", range(20))
def test_no_match_kernels_agree_bit_for_bit(seed, rule):
    net = NM_NETS[seed]
    fast = run(net, rng=seed, rule=rule, max_sweeps=40)
    slow = run(net, rng=seed, rule=rule, max_sweeps=40, kernel="textbook")
    assert np.array_equal(fast.state, slow.state) and fast.energy == slow.energy
    assert (fast.stop_rule, fast.attempts, fast.flips) == (slow.stop_rule, slow.attempts, slow.flips)


def test_thesis_values_of_kappa_and_beta_reproduce_the_thesis_network_exactly():
    for seed, net in enumerate(NETS[:10]):
        same = Network(net.topology, net.similarity, net.pair_c, net.self_c, uniqueness=1.0, match_bias=2.0)
        assert same.target_count == 1.0 and same.constant == net.n_left + net.n_right
        for rule in ("exact", "thesis"):
            W0, I0 = hopfield_form(net, rule)
            W1, I1 = hopfield_form(same, rule)
            assert np.array_equal(W0, W1) and np.array_equal(I0, I1)
        a, b = run(net, rng=seed), run(same, rng=seed)
        assert np.array_equal(a.state, b.state) and a.energy == b.energy
        assert b.energy == pytest.approx(thesis_energy(net, b.state), abs=1e-9)


def test_zero_bias_lets_an_unsupported_feature_stay_unmatched():
    # one left feature, one right candidate with S = -0.3 and nothing else: the thesis' energy
    # (beta = 2) matches it anyway, "at most one" (beta = 0) leaves it unmatched
    net = Network.from_arrays(1, 1, [0], [0], [-0.3], [], [], [])
    assert run(net).state.tolist() == [1]
    free = Network(net.topology, net.similarity, net.pair_c, match_bias=0.0)
    assert run(free).state.tolist() == [0]
    assert energy(free, [0]) - energy(free, [1]) == pytest.approx(-0.3)   # u = S + beta


@pytest.mark.parametrize("kwargs, error, words", [
    (dict(uniqueness=0.0), ValueError, "'uniqueness'"),
    (dict(uniqueness=-1.0), ValueError, "'uniqueness'"),
    (dict(match_bias=np.nan), ValueError, "'match_bias'"),
    (dict(match_bias="1"), TypeError, "'match_bias'"),
])
def test_network_rejects_bad_uniqueness_and_bias(kwargs, error, words):
    net = NETS[0]
    with pytest.raises(error, match=words):
        Network(net.topology, net.similarity, net.pair_c, **kwargs)


def test_a_match_bias_too_large_for_the_fixed_point_is_refused():
    """With beta = -1e7 the 2**-40 fixed point overflowed int64 and every neuron switched on."""
    from ismb_lab.network.hopfield import MAX_INPUT

    net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1], similarity=[0.5, -0.2, -0.3, 0.4],
                              pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.5], match_bias=-1e7)
    with pytest.raises(ValueError, match=r"'match_bias' parameter of Network must be small enough .* Got -10000000.0"):
        run(net)
    ok = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1], similarity=[0.5, -0.2, -0.3, 0.4],
                             pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.5], match_bias=-1e3)
    assert run(ok).state.tolist() == [0, 0, 0, 0] and MAX_INPUT > 1e6


@pytest.mark.parametrize("rule", ["exact", "thesis"])
def test_each_neurons_entries_hold_its_neighbours_positive_weights_first(rule):
    """The first sweep reads a neuron's positive weights, then the others until the input is
    negative: each segment must hold exactly the neighbours' weights, the positive ones
    before pos_end.  A C of exactly zero gives a zero weight, among the others."""
    net = NETS[5]
    pair_c = net.pair_c.copy()
    pair_c[::7] = 0.0
    net = Network(net.topology, net.similarity, pair_c, net.self_c)
    w, lay = _weights(net, rule), net.topology.layout
    W, _ = hopfield_form(net, rule)
    for a in range(net.n_neurons):
        lo, mid, hi = lay.nb_ptr[a], w.pos_end[a], lay.nb_ptr[a + 1]
        assert lo <= mid <= hi
        assert np.all(w.nb_w[lo:mid] > 0) and np.all(w.nb_w[mid:hi] <= 0)
        got = sorted(zip(w.nb_idx[lo:hi].tolist(), w.nb_w[lo:hi].tolist()))
        assert [b for b, _ in got] == sorted(lay.nb_idx[lo:hi].tolist())
        # neighbours share no row or column: the fixed-point weight is W's entry, rounded
        assert [v for _, v in got] == [int(np.rint(W[a, b] * SCALE)) for b, _ in got]
    fast, slow = run(net, rng=4, rule=rule), run(net, rng=4, rule=rule, kernel="textbook")
    assert np.array_equal(fast.state, slow.state) and (fast.attempts, fast.flips) == (slow.attempts, slow.flips)
