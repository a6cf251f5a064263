"""anneal() and iter_annealing() against the mean-field schedule written out in plain Python.

:func:`textbook` runs the schedule of :mod:`ismb_lab.network.annealing` one neuron at a time on the
dense ``W`` and ``I`` of :func:`ismb_lab.network.hopfield.hopfield_form`, with :func:`math.exp`,
drawing the start and every visiting order from the same generator, then rounds ``v`` at
1/2 and polishes it with the discrete network's textbook kernel.  The compiled schedule of
:func:`~ismb_lab.network.annealing.anneal` (neighbour lists, one call) and the per-temperature one of
:func:`~ismb_lab.network.annealing.iter_annealing` must give the same numbers bit for bit, on random
networks, on edge cases and on the networks of two committed pairs, for several seeds and
schedules.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from ismb_lab.network.annealing import anneal, iter_annealing
from ismb_lab.network.dynamics import run
from ismb_lab.network.hopfield import Network, energy, hopfield_form

ROOT = Path(__file__).resolve().parents[1]
SCHEDULES = {"default": {}, "short": dict(t_start=1.0, t_end=0.05, cooling=0.8, sweeps=3),
             "settled": dict(settle=0.2),
             "settled short": dict(t_start=1.0, t_end=0.05, cooling=0.8, sweeps=3, settle=0.05)}
SEEDS = (0, 1, 7)


def random_net(seed: int, size: int) -> Network:
    """A random network on a `size` x `size` grid, with a random match bias and uniqueness."""
    rng = np.random.default_rng(seed)
    rows, cols = np.nonzero(rng.random((size, size)) < 0.5)
    a, b = np.triu_indices(len(rows), k=1)
    keep = (rows[a] != rows[b]) & (cols[a] != cols[b]) & (rng.random(len(a)) < 0.6)
    return Network.from_arrays(size, size, rows, cols, rng.uniform(-1, 1, len(rows)), a[keep], b[keep],
                               rng.uniform(-1, 1, int(keep.sum())), match_bias=float(rng.uniform(-1, 2)),
                               uniqueness=float(rng.uniform(0.5, 2)))


def small_nets() -> dict:
    nets = {f"random {s} size {size}": (random_net, (s, size)) for s in range(4) for size in (4, 7, 12)}
    nets["empty"] = (Network.from_arrays, (0, 0, [], [], [], [], [], []))
    nets["one neuron"] = (Network.from_arrays, (1, 1, [0], [0], [0.3], [], [], []))
    # pair (0, 3) listed twice: the dense W holds its last C, as the neighbour lists must
    nets["repeated pair"] = (Network.from_arrays, (2, 2, [0, 0, 1, 1], [0, 1, 0, 1], [0.1, -0.2, 0.3, 0.4],
                                                   [0, 0, 1], [3, 3, 2], [0.5, -0.7, 0.2]))
    return nets


IMAGE_NETS = ("realistic01 III", "realistic01 NM3", "synthetic NM4", "synthetic NM3")


@pytest.fixture(scope="module")
def image_nets() -> dict:
    """Networks of two committed pairs, as the GA builds them."""
    from ismb_lab.matching.pipeline import prepare
    from ismb_lab.network.methods import get_method
    from ismb_lab.network.params import Params

    realistic = prepare(ROOT / "images/realistic/01/left.png", ROOT / "images/realistic/01/right.png").problem
    synthetic = prepare(ROOT / "images/synthetic/left.png", ROOT / "images/synthetic/right.png").problem
    nm3 = Params(theta_c=5.04092061494309, lambda_c=8.334809269151307, lambda_s=7.881628159512399)
    nets = {"realistic01 III": get_method("III").network(realistic, Params()),
            "realistic01 NM3": get_method("NM3").network(realistic, nm3),
            "synthetic NM4": get_method("NM4").network(synthetic, Params()),
            "synthetic NM3": get_method("NM3").network(synthetic, nm3)}
    assert tuple(nets) == IMAGE_NETS
    return nets


def textbook(net, seed, t_start=2.0, t_end=0.02, cooling=0.9, sweeps=2, settle=0.0):
    """The schedule in plain Python: ``[(temperature, change, v)]`` after each temperature,
    the rounded state and the discrete network's result from it."""
    W, I = hopfield_form(net)
    rng = np.random.default_rng(seed)
    n = net.n_neurons
    v = 0.5 + 0.01 * rng.uniform(-1, 1, n)
    u = W @ v + I
    T, records = t_start, []
    while T >= t_end * (1 - 1e-12):
        before = v > 0.5
        change = 0.0
        for _ in range(sweeps):
            for a in rng.permutation(n).tolist():
                x = u[a] / T
                new = 1.0 / (1.0 + math.exp(-x)) if x >= 0 else math.exp(x) / (1.0 + math.exp(x))
                d = new - v[a]
                if d != 0.0:
                    v[a] = new
                    u = u + W[a] * d           # W is symmetric: row a is column a
                    change = max(change, abs(d))
        records.append((T, change, v.copy()))
        if settle > 0 and np.array_equal(before, v > 0.5) and np.all((v < settle) | (v > 1 - settle)):
            break
        T *= cooling
    rounded = (v > 0.5).astype(np.uint8)
    return records, rounded, run(net, rng=rng, state=rounded, kernel="textbook")


def assert_textbook(net, seed, schedule):
    records, rounded, polish = textbook(net, seed, **schedule)
    fast = anneal(net, rng=seed, **schedule)
    v = records[-1][2]
    assert fast.steps == len(records)
    assert fast.analog.tobytes() == v.tobytes()
    assert np.array_equal(fast.rounded, rounded) and np.array_equal(fast.state, polish.state)
    assert fast.energy == energy(net, polish.state)
    holder = []
    for step, (T, change, v) in zip(iter_annealing(net, rng=seed, state=holder, **schedule), records, strict=True):
        assert (step.temperature, step.change) == (T, change)
        assert holder[0].tobytes() == v.tobytes()


@pytest.mark.parametrize("schedule", SCHEDULES)
@pytest.mark.parametrize("name", small_nets())
def test_anneal_is_the_textbook_schedule_then_the_discrete_network(name, schedule):
    make, args = small_nets()[name]
    net = make(*args)
    for seed in SEEDS:
        assert_textbook(net, seed, SCHEDULES[schedule])


@pytest.mark.parametrize("schedule", SCHEDULES)
@pytest.mark.parametrize("name", IMAGE_NETS)
def test_anneal_is_the_textbook_schedule_on_the_networks_of_committed_pairs(image_nets, name, schedule):
    assert_textbook(image_nets[name], 1, SCHEDULES[schedule])


def test_the_schedules_differ_in_what_they_run():
    """The schedules above are not one schedule under four names: on one network they visit
    different numbers of temperatures and end in different analog states."""
    net = random_net(2, 12)
    runs = {name: anneal(net, rng=1, **s) for name, s in SCHEDULES.items()}
    assert len({r.steps for r in runs.values()}) == 4
    assert len({r.analog.tobytes() for r in runs.values()}) == 4
