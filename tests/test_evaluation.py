"""C/E/T arithmetic on hand-made cases."""

import math
import re

import numpy as np
import pytest

from ismb_lab.tuning.evaluation import Score, Scorer, score
from ismb_lab.matching.pipeline import Prepared
from ismb_lab.network.methods import Params, build_problem
from ismb_lab.tuning.cases import Case, format_protocol, protocol
from ismb_lab import ParameterError
from ismb_lab.scenes import synthetic_scene
from ismb_lab.tuning.fitness import Fitness, evaluate, to_chromosome


@pytest.mark.parametrize("pairs, targets, unknown, expected", [
    ([], [[0, 0]], (), "0/0+0/1"),
    ([[0, 0], [1, 1]], [[0, 0], [1, 1]], (), "2/0+0/2"),
    ([[0, 1]], [[0, 0]], (), "0/1+0/1"),                    # wrong partner
    ([[5, 5]], [[0, 0]], (), "0/0+1/1"),                    # extra: left 5 has no target
    ([[5, 5]], [[0, 0]], [5], "0/0+0/1"),                   # unknown truth: not counted
    ([[0, 0], [0, 1]], [[0, 0]], (), "1/1+0/1"),            # a second match of a labelled feature
    ([[0, 0], [0, 0]], [[0, 0], [0, 0]], (), "2/0+0/1"),    # duplicate targets count once in T
])
def test_cet_counts(pairs, targets, unknown, expected):
    assert str(score(pairs, targets, unknown)) == expected
    scorer = Scorer(targets, unknown)   # built once, then used on several match sets
    assert str(scorer(pairs)) == expected and str(scorer(pairs)) == expected
    assert str(scorer(np.zeros((0, 2), dtype=int))) == f"0/0+0/{expected.rsplit('/', 1)[1]}"


def test_rates_and_fitness():
    s = score([[0, 0], [1, 1], [2, 0], [7, 3]], [[0, 0], [1, 1], [2, 2], [3, 3]])
    assert (s.correct, s.wrong_partner, s.extra, s.targets) == (2, 1, 1, 4)
    assert s.recall == 0.5 and s.precision == 0.5 and s.fitness == 0
    assert math.isnan(Score(0, 0, 0, 0).recall) and math.isnan(Score(0, 0, 0, 3).precision)


def test_the_thesis_fig_5_10_rows_do_not_add_up_to_its_printed_total():
    # Fig. 5.10 prints "Total: C/E/T = 125/14/137"; its eleven testing rows add up to
    # 139/13/150 (92.7%, not 91.24%).  A lesson in checking totals.
    rows = ["12/0+0/12", "15/0+0/15", "14/2+0/16", "16/1+1/17", "11/0+1/12", "5/0+2/5",
            "14/0+1/16", "16/0+1/20", "11/0+1/12", "13/0+1/13", "12/0+2/12"]
    total = Score(0, 0, 0, 0)
    for row in rows:
        c, e, t = row.split("/")
        w, x = e.split("+")
        total = total + Score(int(c), int(w), int(x), int(t))
    assert (total.correct, total.errors, total.targets) == (139, 13, 150)


# --- solvers in the protocol, on hand-made pairs -----------------------------------------------


def hand_case(offset, name):
    # three left corners; 0 and 1 have partners 20 px left, 2 (no neighbours) has none:
    # its only candidate looks unlike it
    lxy = np.array([[100.0, 50.0], [112.0, 56.0], [140.0, 90.0]]) + [offset, 0]
    rxy = np.array([[80.0, 50.0], [92.0, 56.0], [126.0, 92.0]]) + [offset, 0]
    M = np.array([[2.0, 60.0, 60.0], [60.0, 3.0, 60.0], [60.0, 60.0, 45.0]])
    problem = build_problem(lxy, rxy, M)
    prepared = Prepared.__new__(Prepared)
    object.__setattr__(prepared, "problem", problem)
    return Case(prepared, np.array([[0, 0], [1, 1]]), name=name)


def test_no_match_energy_leaves_the_partnerless_corner_unmatched_under_every_solver():
    case = hand_case(0, "a")
    params = Params(theta_c=3.0, theta_s=20.0, lambda_c=1.0, lambda_s=0.5)
    for solver in ("network", "anneal", "exact"):
        three = evaluate([case], "III", params, solver=solver)
        nm = evaluate([case], "NM", Params(**params.to_dict(), match_bias=0.0), solver=solver)
        assert str(nm) == "2/0+0/2", solver
        assert three.extra >= 1, solver          # exactly one match per row: corner 2 takes one


def test_evaluate_scores_any_object_with_a_pair_and_targets_as_it_scores_a_case():
    from types import SimpleNamespace

    case = hand_case(0, "a")
    plain = SimpleNamespace(prepared=case.prepared, targets=case.targets, unknown=case.unknown)
    params = Params(theta_c=3.0, theta_s=20.0, lambda_c=1.0, lambda_s=0.5)
    assert str(evaluate([plain], "III", params)) == str(evaluate([case], "III", params))
    assert case.scorer is case.scorer
    twice = SimpleNamespace(prepared=case.prepared, targets=np.repeat(case.targets, 2, axis=0), unknown=())
    assert str(evaluate([twice], "III", params)) == str(evaluate([case], "III", params))  # T counts a target once


def test_protocol_reports_annealed_and_exact_rows():
    cases = [hand_case(0, "a"), hand_case(30, "b"), hand_case(60, "c")]
    report = protocol(cases, "NM", train=0, seeds=2, generations=3, solvers=("anneal", "exact"),
                      fit_solver="anneal")
    assert set(report.solvers) == {"anneal", "exact"}
    assert len(report.solvers["anneal"].held_out) == 2 and len(report.solvers["exact"].held_out) == 1
    assert all(s.targets == 4 for s in report.solvers["exact"].held_out)
    text = format_protocol(report)
    assert "solver    anneal" in text and "solver     exact" in text
    with pytest.raises(ValueError, match="'solvers' parameter of protocol"):
        protocol(cases, "NM", solvers=("network",))
    with pytest.raises(ValueError, match="'fit_solver' parameter of protocol"):
        protocol(cases, "NM", fit_solver="magic")


def test_protocol_can_fit_the_training_pair_only():
    cases = [hand_case(0, "a"), hand_case(30, "b"), hand_case(60, "c")]
    full = protocol(cases, "NM4", train=0, seeds=2, generations=3)
    lean = protocol(cases, "NM4", train=0, seeds=2, generations=3, fit_all=False)
    assert lean.params == full.params and lean.held_out == full.held_out
    assert lean.rows[0].training == full.rows[0].training
    assert lean.rows[1].training is None and lean.rows[2].params is None
    assert "Training: not fitted" in format_protocol(lean)


# --- format_protocol: every printed count beside its own percentages -------------------------

COUNT = re.compile(r"(\d+)/(\d+)\+(\d+)/(\d+)\s+C/T ([\d.]+)%\s+precision ([\d.]+)%")


def check_printed_figures(text: str) -> int:
    """Each 'C/W+E/T   C/T x%   precision y%' on a line: x and y are that count's own."""
    checked = 0
    for line in text.splitlines():
        for c, w, e, t, recall, precision in COUNT.findall(line):
            c, w, e, t = map(int, (c, w, e, t))
            assert float(recall) == pytest.approx(100 * c / t, abs=0.05), line
            assert float(precision) == pytest.approx(100 * c / (c + w + e), abs=0.05), line
            checked += 1
        if "%" in line and not COUNT.search(line):
            assert "over" in line and "mean" in line and not re.search(r"\d+/\d+\+\d+/\d+", line), line
    return checked


def test_every_printed_percentage_is_its_printed_counts():
    cases = [hand_case(0, "a"), hand_case(30, "b"), hand_case(60, "c")]
    report = protocol(cases, "III", train=0, seeds=3, generations=3, solvers=("anneal", "exact"), peers=True)
    text = format_protocol(report)
    assert check_printed_figures(text) == 1 + 2 + 4     # held-out, two solvers, four peers
    assert "over 3 update-order seeds" in text


def test_the_figure_check_catches_a_mean_beside_a_count():
    with pytest.raises(AssertionError):
        check_printed_figures("Held-out total: 146/5+17/159   C/T 89.3%   precision 86.9%")


@pytest.mark.slow
def test_protocol_on_two_processes_reports_exactly_what_one_process_does():
    cases = [hand_case(0, "a"), hand_case(30, "b"), hand_case(60, "c")]
    kwargs = dict(train=1, seeds=2, generations=4, solvers=("anneal",), peers=True, rng=3)
    one, two = protocol(cases, "NM4", jobs=1, **kwargs), protocol(cases, "NM4", jobs=2, **kwargs)
    assert two == one and two.to_dict() == one.to_dict()
    with pytest.raises(TypeError, match="'rng' parameter of protocol must be an integer seed"):
        protocol(cases, "NM4", jobs=2, rng=np.random.default_rng(0))


def test_counting_coded_neurons_scores_every_state_as_their_pairs_do():
    rng = np.random.default_rng(5)
    rows, cols = np.nonzero(rng.random((12, 14)) < 0.4)
    targets = np.stack([np.arange(0, 12, 2), rng.integers(0, 14, 6)], axis=1)
    scorer = Scorer(targets, unknown=[1, 4, 5])
    codes = scorer.neuron_codes(rows, cols)
    assert set(codes.tolist()) == {0, 1, 2, 3}
    for _ in range(200):
        on = np.flatnonzero(rng.random(len(rows)) < rng.random())
        assert scorer.count(codes, on) == scorer(np.stack([rows[on], cols[on]], axis=1))
    assert str(scorer.count(codes, [])) == f"0/0+0/{len(targets)}"


@pytest.mark.parametrize("matched", [[-1], [0, 10**6]])
def test_counting_refuses_an_index_outside_the_neurons(matched):
    scorer = Scorer([[0, 0]])
    with pytest.raises(ParameterError, match=r"'matched'.*\[0, 3\)"):
        scorer.count(scorer.neuron_codes([0, 0, 1], [0, 1, 1]), matched)


@pytest.fixture(scope="module")
def case7(rendered):
    return Case.from_scene(rendered(synthetic_scene, 7))


@pytest.mark.parametrize("method", ["I", "II", "III", "NM", "NM4"])
def test_evaluate_is_the_score_of_to_matches_pairs_for_every_method(case7, method):
    from ismb_lab.network.methods import get_method
    from ismb_lab.network.solvers import solve, to_matches

    case = case7
    problem, m = case.prepared.problem, get_method(method)
    for theta_c in (2.0, 20.0, 60.0):
        params = Params(theta_c=theta_c, lambda_c=0.5, match_bias=0.0)
        for seed in (0, 1):
            state = solve(m.network(problem, params), seed=seed).state
            expected = score(to_matches(problem, state, m).pairs, case.targets, case.unknown)
            assert evaluate([case], method, params, seed=seed) == expected
            fitness = Fitness([case], method, seed=seed, base=params)
            assert fitness(to_chromosome(method, params)[None, :])[0] == expected.fitness


def test_a_postprocess_that_invents_neurons_is_named():
    from ismb_lab.network.methods import MethodIII, register_method, unregister_method

    class Stray(MethodIII):
        name, description = "STRAY", "keeps a neuron that does not exist"

        def postprocess(self, problem, on):
            return np.append(on, problem.n_neurons)

    register_method(Stray())
    try:
        with pytest.raises(ParameterError, match="'method'.*postprocess"):
            evaluate([hand_case(0, "a")], "STRAY", Params())
    finally:
        unregister_method("STRAY")
