"""Exact minima: Gray-code search against a plain enumeration, MILP against both."""

import itertools

import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab.network.exact import MAX_EXHAUSTIVE, exhaustive_minimum, milp_minimum
from ismb_lab.network.hopfield import Network, energy
from ismb_lab.network.dynamics import run


def random_net(rng, n_left, n_right, p_candidate, no_match):
    """Random candidates, S, C in [-1, 1]; the thesis' kappa and beta or random ones."""
    rows, cols = np.nonzero(rng.random((n_left, n_right)) < p_candidate)
    a, b = np.triu_indices(len(rows), k=1)
    keep = (rows[a] != rows[b]) & (cols[a] != cols[b]) & (rng.random(len(a)) < 0.6)
    extra = dict(uniqueness=rng.uniform(0.3, 3), match_bias=rng.uniform(-2, 2)) if no_match else {}
    return Network.from_arrays(n_left, n_right, rows, cols, rng.uniform(-1, 1, len(rows)), a[keep], b[keep],
                               rng.uniform(-1, 1, int(keep.sum())), **extra)


def small(seed, no_match):
    rng = np.random.default_rng(seed)
    while True:
        net = random_net(rng, int(rng.integers(2, 6)), int(rng.integers(2, 6)), 0.5, no_match)
        if 1 <= net.n_neurons <= 12:
            return net


@pytest.mark.parametrize("no_match", [False, True])
@pytest.mark.parametrize("seed", range(8))
def test_gray_code_search_finds_the_minimum_of_a_plain_enumeration(seed, no_match):
    net = small(seed, no_match)
    energies = np.array([energy(net, np.array(y, np.uint8))
                         for y in itertools.product((0, 1), repeat=net.n_neurons)])
    best = exhaustive_minimum(net)
    assert best.energy == pytest.approx(energies.min(), abs=1e-9)
    assert best.n_minima == np.sum(energies <= energies.min() + 1e-9)
    assert energy(net, best.state) == best.energy


@pytest.mark.parametrize("no_match", [False, True])
@pytest.mark.parametrize("seed", range(8))
def test_milp_agrees_with_the_exhaustive_search_and_bounds_every_fixed_point(seed, no_match):
    net = small(seed + 20, no_match)
    exact, milp = exhaustive_minimum(net), milp_minimum(net)
    assert milp.energy == pytest.approx(exact.energy, abs=1e-6)
    for s in range(5):
        assert run(net, rng=s).energy >= exact.energy - 1e-9


def test_a_trap_the_network_falls_into_and_the_exact_search_does_not():
    # "at most one" (beta = 0): two rows compete for one column; starting all on, whichever
    # is visited first turns off, but the global minimum keeps the better one (S = 0.9)
    net = Network.from_arrays(2, 1, rows=[0, 1], cols=[0, 0], similarity=[0.9, 0.2],
                              pair_a=[], pair_b=[], pair_c=[], match_bias=0.0)
    assert exhaustive_minimum(net).state.tolist() == [1, 0]
    finals = {tuple(run(net, rng=s).state.tolist()) for s in range(20)}
    assert finals == {(1, 0), (0, 1)}


def test_limits_and_types():
    big = random_net(np.random.default_rng(3), 12, 12, 0.5, True)
    assert big.n_neurons > MAX_EXHAUSTIVE
    with pytest.raises(ParameterError, match="'net' parameter of exhaustive_minimum.*milp_minimum"):
        exhaustive_minimum(big)
    with pytest.raises(TypeError, match="'net' parameter of milp_minimum"):
        milp_minimum("net")
    with pytest.raises(ParameterError, match="'time_limit'"):
        milp_minimum(big, time_limit=0)
    empty = Network.from_arrays(2, 0, [], [], [], [], [], [])
    assert exhaustive_minimum(empty).energy == 2.0 and milp_minimum(empty).state.shape == (0,)
