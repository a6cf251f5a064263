"""Mean-field annealing: schedule, determinism, fixed points and exact minima."""

import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab.network.annealing import anneal, iter_annealing
from ismb_lab.network.exact import exhaustive_minimum
from ismb_lab.network.hopfield import Network, energy, hopfield_form
from ismb_lab.network.dynamics import run


def net_of(seed, no_match=True):
    rng = np.random.default_rng(seed)
    rows, cols = np.nonzero(rng.random((5, 5)) < 0.5)
    a, b = np.triu_indices(len(rows), k=1)
    keep = (rows[a] != rows[b]) & (cols[a] != cols[b]) & (rng.random(len(a)) < 0.6)
    return Network.from_arrays(5, 5, rows, cols, rng.uniform(-1, 1, len(rows)), a[keep], b[keep],
                               rng.uniform(-1, 1, int(keep.sum())), match_bias=0.5 if no_match else 2.0)


def test_schedule_is_geometric_and_records_are_frozen():
    steps = list(iter_annealing(net_of(0), rng=1, t_start=1.0, t_end=0.1, cooling=0.5))
    assert [s.temperature for s in steps] == [1.0, 0.5, 0.25, 0.125]
    assert [s.index for s in steps] == [0, 1, 2, 3]
    with pytest.raises(AttributeError):
        steps[0].energy = 0.0
    assert steps[-1].committed >= steps[0].committed


def test_same_seed_same_run_and_seeds_matter():
    net = net_of(2)
    a, b = anneal(net, rng=4), anneal(net, rng=np.random.default_rng(4))
    assert np.array_equal(a.analog, b.analog) and np.array_equal(a.state, b.state)
    first = {next(iter_annealing(net, rng=s)).energy for s in range(4)}
    assert len(first) == 4


@pytest.mark.parametrize("seed", range(10))
def test_result_is_a_discrete_fixed_point_never_above_the_rounded_state(seed):
    net = net_of(seed, no_match=seed % 2 == 0)
    result = anneal(net, rng=seed)
    W, I = hopfield_form(net)
    u = W @ result.state + I
    assert np.all(result.state[u > 1e-9] == 1) and np.all(result.state[u < -1e-9] == 0)
    assert result.energy <= energy(net, result.rounded) + 1e-9
    assert result.energy == energy(net, result.state)


def test_annealing_reaches_the_exact_minimum_more_often_than_greedy_descent():
    hits_anneal = hits_greedy = 0
    for seed in range(30):
        net = net_of(100 + seed)
        if net.n_neurons > 20:
            continue
        best = exhaustive_minimum(net).energy
        hits_anneal += anneal(net, rng=seed).energy <= best + 1e-9
        hits_greedy += run(net, rng=seed).energy <= best + 1e-9
    assert hits_anneal > hits_greedy


def test_analog_energy_at_a_committed_state_is_the_discrete_energy():
    net = net_of(5)
    holder = []
    last = list(iter_annealing(net, rng=0, t_end=0.005, state=holder))[-1]
    v = holder[0]
    assert last.committed == 1.0
    assert last.energy == pytest.approx(energy(net, (v > 0.5).astype(np.uint8)), abs=1e-2)


@pytest.mark.parametrize("kwargs, error, words", [
    (dict(t_end=0.0), ParameterError, "'t_end'"),
    (dict(t_start=0.01, t_end=0.1), ParameterError, "'t_start'"),
    (dict(cooling=1.0), ParameterError, "'cooling'"),
    (dict(sweeps=0), ParameterError, "'sweeps'"),
    (dict(settle=-0.1), ParameterError, "'settle'"),
    (dict(settle=0.5), ParameterError, "'settle' parameter of .* a number in \\[0, 0.5\\). Got 0.5"),
    (dict(settle="0.1"), TypeError, "'settle'"),
    (dict(rng="x"), TypeError, "'rng'"),
])
def test_bad_arguments(kwargs, error, words):
    with pytest.raises(error, match=words):
        list(iter_annealing(net_of(0), **kwargs))
    if "rng" not in kwargs:
        with pytest.raises(error, match=words):
            anneal(net_of(0), **kwargs)
    with pytest.raises(TypeError, match="'net'"):
        iter_annealing("net")


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("settle", [0.05, 0.2])
def test_a_settled_schedule_stops_at_the_first_temperature_that_moved_no_v_across_a_half(seed, settle):
    """The full schedule's records show where the settled one must stop: the first temperature
    after which every v lies within `settle` of 0 or 1 and no v changed side of 1/2; up to
    there both runs are the same numbers (the same generator, the same updates)."""
    net = net_of(seed)
    full_v, sides, near = [], [], []
    rng = np.random.default_rng(seed)
    holder = []
    before = None
    for step in iter_annealing(net, rng=rng, state=holder):
        v = holder[0]
        sides.append(before is not None and np.array_equal(before, v > 0.5))
        near.append(bool(np.all((v < settle) | (v > 1 - settle))))
        full_v.append(v.copy())
        before = v > 0.5
    # the first temperature's "before" is the start: v = 1/2 + noise, rounded
    start = 0.5 + 0.01 * np.random.default_rng(seed).uniform(-1, 1, net.n_neurons) > 0.5
    v0 = full_v[0]
    sides[0] = bool(np.array_equal(start, v0 > 0.5))
    stop = next((t for t in range(len(full_v)) if sides[t] and near[t]), len(full_v) - 1)
    holder = []
    steps = list(iter_annealing(net, rng=seed, settle=settle, state=holder))
    assert len(steps) == stop + 1
    assert np.array_equal(holder[0], full_v[stop])
    short = anneal(net, rng=seed, settle=settle)
    assert short.steps == stop + 1 and np.array_equal(short.analog, full_v[stop])
    assert np.array_equal(run(net, rng=0, state=short.state).state, short.state)   # a fixed point still


def test_settle_zero_runs_every_temperature_and_a_settle_stops_earlier():
    assert anneal(net_of(3), rng=2, settle=0).steps == anneal(net_of(3), rng=2).steps == 44
    assert all(anneal(net_of(s), rng=2, settle=0.2).steps < 44 for s in range(8))
    assert np.array_equal(anneal(net_of(3), rng=2, settle=0.0).analog, anneal(net_of(3), rng=2).analog)
