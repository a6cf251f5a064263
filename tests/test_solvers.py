"""The solvers: the registry's fourth member (the network started from the similarity assignment),
each solver's own options, and a solver added by one definition."""

import itertools

import numpy as np
import pytest

from ismb_lab import ParameterTypeError
from ismb_lab.cli import main
from ismb_lab.network.dynamics import iter_updates, run
from ismb_lab.network.hopfield import Network, energy
from ismb_lab.network.solvers import ASSIGN, SOLVERS, similarity_assignment, solve


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


def test_one_match_per_corner_keeps_the_most_similar_of_each_corner():
    from ismb_lab.network.methods import build_problem
    from ismb_lab.network.solvers import one_match_per_corner

    rng = np.random.default_rng(5)
    for _ in range(30):
        lxy = rng.uniform(0, 60, (8, 2))
        rxy = lxy - [10.0, 0.0] + rng.normal(0, 3, (8, 2))
        p = build_problem(lxy, rxy, rng.integers(0, 8, (8, 8)).astype(float), window_width=80, window_height=60)
        on = np.flatnonzero(rng.random(p.n_neurons) < 0.5)
        kept = one_match_per_corner(p, on)
        assert set(kept.tolist()) <= set(on.tolist()) and np.all(np.diff(kept) > 0)
        assert len(set(p.rows[kept].tolist())) == len(kept) == len(set(p.cols[kept].tolist()))
        m = p.neuron_dissimilarity
        for a in set(on.tolist()) - set(kept.tolist()):
            # dropped only for a kept neuron on the same corner that comes first: smaller M, or equal M and index
            rivals = kept[(p.rows[kept] == p.rows[a]) | (p.cols[kept] == p.cols[a])]
            assert any((m[b], b) < (m[a], a) for b in rivals)
        untouched = on[[np.sum(p.rows[on] == p.rows[a]) == 1 and np.sum(p.cols[on] == p.cols[a]) == 1 for a in on]]
        assert set(untouched.tolist()) <= set(kept.tolist())


def test_one_match_per_corner_takes_any_order_and_checks_it():
    from ismb_lab.network.methods import build_problem
    from ismb_lab.network.solvers import one_match_per_corner

    # left corner 0 has two matches: neuron 0 (M 2) and neuron 1 (M 40)
    p = build_problem([[100, 50], [110, 50]], [[80, 51], [90, 51]], [[2.0, 40.0], [30.0, 3.0]])
    assert one_match_per_corner(p, [0, 1, 3]).tolist() == [0, 3]
    assert one_match_per_corner(p, [0, 1, 3], key=[5.0, 0.0, 1.0]).tolist() == [1]   # 1 first: 3 and 0 share its corners
    assert one_match_per_corner(p, [0, 1, 3], key=[1.0, 1.0, 0.0]).tolist() == [0, 3]  # a tie: index 0
    with pytest.raises(ValueError, match=r"'key' parameter of one_match_per_corner must be of length 3, "
                                         r"one value per matched neuron. Got 'length 2'"):
        one_match_per_corner(p, [0, 1, 3], key=[1.0, 2.0])


def test_one_to_one_in_match_the_cli_and_evaluate(rendered):

    from ismb_lab.matching.pipeline import match, prepare
    from ismb_lab.network.params import Params
    from ismb_lab.tuning.cases import Case
    from ismb_lab.scenes import synthetic_scene
    from ismb_lab.network.solvers import matched_neurons, one_match_per_corner, to_matches
    from ismb_lab.tuning.fitness import evaluate
    from ismb_lab.tuning.evaluation import score

    scene = rendered(synthetic_scene, seed=3)
    prepared = prepare(scene.left, scene.right)
    params = Params(theta_c=60.0, theta_s=24.0, lambda_c=2.0, lambda_s=2.0)   # strong support: corners matched twice
    plain = match(method="III", params=params, prepared=prepared, seed=0)
    single = match(method="III", params=params, prepared=prepared, seed=0, one_to_one=True)
    assert len(plain.pairs) > len(set(plain.pairs[:, 0].tolist()))
    assert len(single.pairs) == len(set(single.pairs[:, 0].tolist())) == len(set(single.pairs[:, 1].tolist()))
    assert {tuple(x) for x in single.pairs.tolist()} < {tuple(x) for x in plain.pairs.tolist()}
    assert single.to_dict()["one_to_one"] is True and plain.to_dict()["one_to_one"] is False
    with pytest.raises(TypeError, match="'one_to_one' parameter of match"):
        match(method="III", prepared=prepared, one_to_one="yes")
    # evaluate scores what match returns, the GA's fitness is not changed
    case = Case.from_scene(scene)
    p = case.prepared.problem
    state = solve(get_method_network(p, params), "network", seed=0).state
    kept = one_match_per_corner(p, matched_neurons(p, state))
    by_hand = score(np.stack([p.rows[kept], p.cols[kept]], axis=1), case.targets, case.unknown)
    assert evaluate([case], "III", params, 0, "network", one_to_one=True) == by_hand
    assert evaluate([case], "III", params, 0, "network") == score(to_matches(p, state).pairs, case.targets,
                                                                  case.unknown)


def get_method_network(problem, params):
    from ismb_lab.network.methods import get_method

    return get_method("III").network(problem, params)


def test_match_one_to_one_on_the_command_line(pair, tmp_path):
    import json

    out = tmp_path / "m.json"
    assert main(["match", *map(str, pair), "--theta-c", "60", "--one-to-one", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    lefts = [m["left"] for m in data["matches"]]
    rights = [m["right"] for m in data["matches"]]
    assert data["one_to_one"] is True and len(lefts) == len(set(lefts)) == len(set(rights)) > 0


# --- solvers are configured objects, registered by one definition ---------------------------

from dataclasses import dataclass  # noqa: E402

from ismb_lab import ParameterError  # noqa: E402
from ismb_lab.network.annealing import anneal  # noqa: E402
from ismb_lab.network.solvers import (AnnealSolver, ExactSolver, NetworkSolver, Solution, Solver,  # noqa: E402
                              get_solver, register_solver, unregister_solver)


def test_each_solver_takes_its_own_options_and_only_those():
    assert get_solver("anneal", cooling=0.8) == AnnealSolver(cooling=0.8)
    assert get_solver("exact", time_limit=5) == ExactSolver(time_limit=5)
    assert get_solver("network", stop_rule="stall", rule=None) == NetworkSolver(stop_rule="stall")
    for name in ("anneal", "exact"):
        with pytest.raises(ParameterError, match=rf"'stop_rule' parameter of match must be an option of the '{name}'"):
            get_solver(name, "match", stop_rule="stall")
    with pytest.raises(ParameterError, match="'cooling' parameter of AnnealSolver"):
        AnnealSolver(cooling=1.0)
    with pytest.raises(ParameterError, match="'time_limit' parameter of ExactSolver"):
        ExactSolver(time_limit=0)
    with pytest.raises(ParameterError, match="'kernel' parameter of NetworkSolver"):
        NetworkSolver(kernel="fortran")


@pytest.mark.parametrize("seed", range(4))
def test_the_anneal_schedule_reaches_the_annealer_and_the_name_stays_apart_from_the_stop_rule(seed):
    net = grid_network(500 + seed, 5, 6)
    quick = AnnealSolver(t_start=1.0, cooling=0.5, sweeps=1)
    got = solve(net, quick, seed=seed)
    assert np.array_equal(got.state, anneal(net, rng=seed, t_start=1.0, cooling=0.5, sweeps=1).state)
    assert np.array_equal(solve(net, "anneal", seed=seed).state, anneal(net, rng=seed).state)
    assert (got.solver, got.stop_rule) == ("anneal", "sweep")
    exact = solve(grid_network(500 + seed, 3, 4), "exact")   # a small one: a MILP of 30 neurons takes 1 s
    assert (exact.solver, exact.stop_rule) == ("exact", "minimum")
    assert solve(net, "network", seed=seed).solver == "network"


@dataclass(frozen=True)
class AllOff(Solver):
    """Every candidate off: a solver defined in one place, with one option of its own."""

    name, description, seeded = "all-off", "every candidate off (a test solver)", False
    level: int = 0

    def solve(self, net, seed):
        return Solution(np.full(net.n_neurons, self.level, np.uint8), "minimum", 0, net, solver=self.name)


@pytest.fixture
def all_off():
    solver = register_solver(AllOff())
    yield solver
    unregister_solver(solver.name)


def test_a_solver_defined_once_shows_up_in_the_cli_and_in_the_protocol(all_off, capsys):
    from ismb_lab.tuning.cases import format_protocol, protocol

    for command in ("match", "tune", "evaluate", "depth"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        assert "all-off: every candidate off" in capsys.readouterr().out, command
    cases = _hand_cases()
    report = protocol(cases, "III", seeds=2, generations=2, solvers=("all-off",))
    assert [str(s) for s in report.solvers["all-off"].held_out] == ["0/0+0/4"]
    assert "solver   all-off: held-out 0/0+0/4" in format_protocol(report)
    on = protocol(cases, "III", seeds=2, generations=2, solver=AllOff(level=1), fit_all=False)
    assert on.solver == "all-off" and len(on.held_out) == 1 and on.held_out[0].extra > 0
    with pytest.raises(ParameterError, match="'solver' parameter of register_solver"):
        register_solver(AllOff())      # the name is taken


def _hand_cases():
    from ismb_lab.matching.pipeline import Prepared
    from ismb_lab.network.methods import build_problem
    from ismb_lab.tuning.cases import Case

    cases = []
    for offset in (0, 30, 60):
        lxy = np.array([[100.0, 50.0], [112.0, 56.0], [140.0, 90.0]]) + [offset, 0]
        rxy = np.array([[80.0, 50.0], [92.0, 56.0], [126.0, 92.0]]) + [offset, 0]
        M = np.array([[2.0, 60.0, 60.0], [60.0, 3.0, 60.0], [60.0, 60.0, 45.0]])
        prepared = Prepared.__new__(Prepared)
        object.__setattr__(prepared, "problem", build_problem(lxy, rxy, M))
        cases.append(Case(prepared, np.array([[0, 0], [1, 1]]), name=str(offset)))
    return cases
