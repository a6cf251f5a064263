"""The compiled annealing run against the outputs the earlier code (commit 967f640) recorded.

``tests/data/anneal_reference.json`` holds, for every case of :func:`reference_cases`, a
SHA-256 digest of the final discrete state, the rounded state, the analog state and the
energy that :func:`ismb_lab.annealing.anneal` returned before its sweeps ran on a
neighbour list in one compiled call.  ``python tests/test_annealing_kernel.py --record``
writes the file again (only to be run on the code the digests are meant to pin).
"""

import hashlib
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from ismb_lab.annealing import anneal, iter_annealing
from ismb_lab.dynamics import run
from ismb_lab.hopfield import Network, energy
from ismb_lab.matching import prepare
from ismb_lab.methods import get_method
from ismb_lab.params import Params

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "tests" / "data" / "anneal_reference.json"
SCHEDULES = {"default": {}, "short": dict(t_start=1.0, t_end=0.05, cooling=0.8, sweeps=3)}


def random_net(seed: int, size: int) -> Network:
    rng = np.random.default_rng(seed)
    rows, cols = np.nonzero(rng.random((size, size)) < 0.5)
    a, b = np.triu_indices(len(rows), k=1)
    keep = (rows[a] != rows[b]) & (cols[a] != cols[b]) & (rng.random(len(a)) < 0.6)
    return Network.from_arrays(size, size, rows, cols, rng.uniform(-1, 1, len(rows)), a[keep], b[keep],
                               rng.uniform(-1, 1, int(keep.sum())), match_bias=float(rng.uniform(-1, 2)),
                               uniqueness=float(rng.uniform(0.5, 2)))


def image_nets() -> dict:
    """Networks of the committed pairs, as the GA builds them."""
    nets = {}
    realistic = prepare(ROOT / "images/realistic/01/left.png", ROOT / "images/realistic/01/right.png").problem
    synthetic = prepare(ROOT / "images/synthetic/left.png", ROOT / "images/synthetic/right.png").problem
    nm3 = Params(theta_c=5.04092061494309, lambda_c=8.334809269151307, lambda_s=7.881628159512399)
    nets["realistic01 III"] = get_method("III").network(realistic, Params())
    nets["realistic01 NM3"] = get_method("NM3").network(realistic, nm3)
    nets["synthetic NM4"] = get_method("NM4").network(synthetic, Params())
    nets["synthetic NM3"] = get_method("NM3").network(synthetic, nm3)
    return nets


def reference_cases():
    """(name, network, seed, schedule) of every recorded run."""
    nets = {f"random {s} size {size}": random_net(s, size) for s in range(8) for size in (4, 7, 12)}
    nets["empty"] = Network.from_arrays(0, 0, [], [], [], [], [], [])
    nets["one neuron"] = Network.from_arrays(1, 1, [0], [0], [0.3], [], [], [])
    nets["repeated pair"] = Network.from_arrays(2, 2, [0, 0, 1, 1], [0, 1, 0, 1], [0.1, -0.2, 0.3, 0.4],
                                                [0, 0, 1], [3, 3, 2], [0.5, -0.7, 0.2])
    nets.update(image_nets())
    for name, net in nets.items():
        for seed in (0, 1, 7):
            for schedule in SCHEDULES:
                yield name, net, seed, schedule


def digest(result) -> str:
    h = hashlib.sha256()
    for arr in (result.state, result.rounded, result.analog):
        h.update(np.ascontiguousarray(arr).tobytes())
    h.update(repr((float(result.energy), int(result.steps))).encode())
    return h.hexdigest()


def key(name, seed, schedule) -> str:
    return f"{name} | seed {seed} | {schedule}"


def record() -> None:
    runs = {key(name, seed, schedule): digest(anneal(net, rng=seed, **SCHEDULES[schedule]))
            for name, net, seed, schedule in reference_cases()}
    REFERENCE.write_text(json.dumps(runs, indent=1, sort_keys=True) + "\n")


@pytest.fixture(scope="module")
def recorded():
    return json.loads(REFERENCE.read_text())


def test_every_case_is_recorded(recorded):
    assert sorted(recorded) == sorted(key(n, s, c) for n, _, s, c in reference_cases())


@pytest.mark.parametrize("case", list(reference_cases()), ids=lambda c: key(c[0], c[2], c[3]))
def test_anneal_reproduces_the_earlier_code_bit_for_bit(case, recorded):
    name, net, seed, schedule = case
    assert digest(anneal(net, rng=seed, **SCHEDULES[schedule])) == recorded[key(name, seed, schedule)]


@pytest.mark.parametrize("case", [c for c in reference_cases() if c[2] == 1], ids=lambda c: key(c[0], c[2], c[3]))
def test_anneal_is_the_readable_schedule_then_the_discrete_network(case):
    """anneal() equals iter_annealing() run to its end (dense weights, one temperature at a
    time), rounded at 1/2 and polished by the discrete network from the same generator."""
    name, net, seed, schedule = case
    assert_readable_then_discrete(net, seed, SCHEDULES[schedule])


def assert_readable_then_discrete(net, seed, schedule: dict):
    """anneal() with `schedule` gives iter_annealing()'s values bit for bit, and the discrete
    network's polish of them from the same generator."""
    rng, holder = np.random.default_rng(seed), []
    steps = len(list(iter_annealing(net, rng=rng, state=holder, **schedule)))
    v = holder[0] if holder else np.zeros(0)
    polish = run(net, rng=rng, state=(v > 0.5).astype(np.uint8))
    fast = anneal(net, rng=seed, **schedule)
    assert fast.steps == steps
    assert np.array_equal(fast.analog, v) and fast.analog.tobytes() == v.tobytes()
    assert np.array_equal(fast.state, polish.state) and fast.energy == energy(net, polish.state)


#: Schedules that stop once the state has settled (not in the recorded digests: the earlier
#: code had no such option).
SETTLED = {"settled": dict(settle=0.2), "settled short": dict(t_start=1.0, t_end=0.05, cooling=0.8, sweeps=3,
                                                              settle=0.05)}


@pytest.mark.parametrize("schedule", SETTLED)
@pytest.mark.parametrize("case", [c for c in reference_cases() if c[2] == 7 and c[3] == "default"],
                         ids=lambda c: c[0])
def test_a_settled_anneal_is_the_readable_settled_schedule_then_the_discrete_network(case, schedule):
    name, net, seed, _ = case
    assert_readable_then_discrete(net, seed, SETTLED[schedule])


if __name__ == "__main__" and "--record" in sys.argv:
    record()
