"""The solver registry's fourth member: the network started from the similarity assignment."""

import itertools

import numpy as np
import pytest

from ismb_lab import ParameterTypeError
from ismb_lab.cli import main
from ismb_lab.dynamics import iter_updates, run
from ismb_lab.hopfield import Network, energy
from ismb_lab.solvers import ASSIGN, SOLVERS, similarity_assignment, solve


def grid_network(seed, n_left, n_right):
    """Every left-right pair a candidate, S and C uniform in [-1, 1], a third of the allowed pairs."""
    rng = np.random.default_rng(seed)
    rows, cols = np.divmod(np.arange(n_left * n_right), n_right)
    a, b = np.triu_indices(len(rows), k=1)
    keep = (rows[a] != rows[b]) & (cols[a] != cols[b]) & (rng.random(len(a)) < 1 / 3)
    return Network.from_arrays(n_left, n_right, rows, cols, similarity=rng.uniform(-1, 1, len(rows)),
                               pair_a=a[keep], pair_b=b[keep], pair_c=rng.uniform(-1, 1, keep.sum()))


def best_total_similarity(net) -> float:
    """The largest sum of S > 0 over one-to-one sets of candidates, by trying every set."""
    S = {(i, k): s for i, k, s in zip(net.rows.tolist(), net.cols.tolist(), net.similarity.tolist()) if s > 0}
    best = 0.0
    lefts = sorted({i for i, _ in S})
    for size in range(1, len(lefts) + 1):
        for chosen in itertools.combinations(lefts, size):
            for rights in itertools.permutations(range(net.n_right), size):
                if all((i, k) in S for i, k in zip(chosen, rights)):
                    best = max(best, sum(S[i, k] for i, k in zip(chosen, rights)))
    return best


@pytest.mark.parametrize("seed", range(12))
def test_the_start_is_the_one_to_one_assignment_of_largest_similarity(seed):
    net = grid_network(300 + seed, 4, 5)
    start = similarity_assignment(net)
    on = start.astype(bool)
    assert len(set(net.rows[on])) == on.sum() and len(set(net.cols[on])) == on.sum()   # one to one
    assert np.all(net.similarity[on] > 0)
    assert net.similarity[on].sum() == pytest.approx(best_total_similarity(net), abs=1e-12)


@pytest.mark.parametrize("seed", range(12))
def test_assign_runs_the_network_from_that_start_and_only_descends(seed):
    net = grid_network(400 + seed, 6, 7)
    start = similarity_assignment(net)
    got = solve(net, ASSIGN, seed=seed)
    plain = run(net, rng=seed, state=start)
    assert np.array_equal(got.state, plain.state) and got.energy == plain.energy
    assert got.energy <= energy(net, start) + 1e-12
    previous = energy(net, start)
    for step in iter_updates(net, rng=seed, state=start):
        assert step.energy <= previous + 1e-9 and step.energy == pytest.approx(
            previous - step.u * (step.new - step.old), abs=1e-9)
        previous = step.energy
    assert previous == pytest.approx(got.energy, abs=1e-9)


def test_assign_is_everywhere_a_solver_is_offered(capsys):
    assert SOLVERS[ASSIGN].seeded
    with pytest.raises(SystemExit):
        main(["match", "--help"])
    assert ASSIGN in capsys.readouterr().out


def test_similarity_assignment_names_its_argument():
    with pytest.raises(ParameterTypeError, match="'net' parameter of similarity_assignment"):
        similarity_assignment("not a network")
