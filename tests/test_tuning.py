"""The GA joined to matching: genes <-> parameters, fitness (4-1), and learning from targets."""

import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab.matching.pipeline import match, prepare
from ismb_lab.network.methods import Params
from ismb_lab.tuning.cases import Case, format_protocol, protocol
from ismb_lab.scenes import synthetic_scene, true_matches
from ismb_lab.tuning.fitness import Fitness, evaluate, gene_bounds, to_chromosome, to_params, tune


def case(scene, seed):
    prepared = prepare(scene.left, scene.right)
    truth = true_matches(scene, prepared.problem.left_xy, prepared.problem.right_xy)
    left = np.flatnonzero(truth >= 0)
    return Case(prepared, np.stack([left, truth[left]], axis=1), name=f"scene {seed}")


@pytest.fixture(scope="module")
def cases(rendered):
    return [case(rendered(synthetic_scene, seed=s), s) for s in (100, 101, 0, 1)]


def test_genes_round_trip_and_bounds():
    p = Params(theta_c=3.0, theta_s=20.0, lambda_c=0.7, lambda_s=1.5)
    assert to_params("III", to_chromosome("III", p)) == p
    assert to_params("I", [5.0, 2.0], base=p) == Params(5.0, 20.0, 2.0, 1.5)
    assert gene_bounds("II").names == ("theta_c", "theta_s", "lambda_c", "lambda_s")
    assert np.all(gene_bounds("III").low < gene_bounds("III").high)
    with pytest.raises(ParameterError, match="'chromosome'"):
        to_params("III", [1.0, 2.0])


def test_fitness_is_n_correct_minus_n_errors(cases):
    params = Params(theta_c=2.0, lambda_c=0.5)
    fitness = Fitness(cases[:2], "III")
    value = fitness(to_chromosome("III", params)[None, :])[0]
    expected = 0
    for c in cases[:2]:
        result = match(prepared=c.prepared, params=params, seed=0)
        wanted = {tuple(t) for t in c.targets.tolist()}
        hits = sum(tuple(p) in wanted for p in result.pairs.tolist())
        expected += hits - (len(result.pairs) - hits)
    assert value == expected
    assert fitness.target == sum(len(c.targets) for c in cases[:2])


def test_ga_learns_parameters_that_transfer_to_held_out_scenes(cases):
    records = list(tune(cases[:1], "III", rng=0, generations=60))
    best = to_params("III", records[-1].best_chromosome)
    assert records[-1].best >= records[0].best
    held_out = evaluate(cases[2:], "III", best)
    assert held_out.recall >= 0.9 and held_out.precision >= 0.9


def test_same_seed_same_tuning(cases):
    a = [r.best_chromosome for r in tune(cases[:1], "I", rng=4, generations=5)]
    b = [r.best_chromosome for r in tune(cases[:1], "I", rng=4, generations=5)]
    assert all(np.array_equal(x, y) for x, y in zip(a, b))


def test_empty_targets_and_bad_arguments_are_rejected(cases):
    empty = Case(cases[0].prepared, np.zeros((0, 2), dtype=np.int64))
    with pytest.raises(ParameterError, match="empty target set"):
        tune([empty], "III")
    with pytest.raises(ParameterError, match="'population'"):
        tune(cases[:1], "III", population=1)
    with pytest.raises(ParameterError, match="'cases'"):
        Fitness([], "III")


def test_protocol_reports_training_testing_and_peers(cases):
    report = protocol(cases[:3], "III", train=0, seeds=2, generations=20, peers=True)
    text = format_protocol(report)
    assert "Testing:" in text and "Training:" in text and "over 2 update-order seeds" in text
    assert len(report.held_out) == 2 and set(report.peers) == {"mutual-nn", "hungarian", "rrwm", "spectral"}
    pooled = report.held_out[0]
    assert pooled.targets == sum(len(c.targets) for c in cases[1:3])
    with pytest.raises(ParameterError, match="'train'"):
        protocol(cases[:2], train=5)


def test_method_nm_has_a_fifth_gene_with_documented_bounds():
    bounds = gene_bounds("NM")
    assert bounds.names[-1] == "match_bias" and (bounds.low[-1], bounds.high[-1]) == (-2.0, 2.0)
    p = to_params("NM", [3.0, 20.0, 0.7, 1.5, 0.25])
    assert p.match_bias == 0.25 and to_chromosome("NM", p).tolist() == [3.0, 20.0, 0.7, 1.5, 0.25]
    assert to_params("III", to_chromosome("III", p), base=Params()).match_bias is None


def test_fitness_over_seeds_is_the_mean_of_single_seed_fitnesses(cases):
    chromosome = to_chromosome("NM", Params(theta_c=2.0, lambda_c=0.5, match_bias=0.5))[None, :]
    single = [Fitness(cases[:1], "NM", seed=s)(chromosome)[0] for s in range(3)]
    assert Fitness(cases[:1], "NM", seed=0, seeds=3)(chromosome)[0] == pytest.approx(np.mean(single))
    exact = Fitness(cases[:1], "NM", solver="exact")(chromosome)[0]
    assert exact == Fitness(cases[:1], "NM", solver="exact", seed=5)(chromosome)[0]
    with pytest.raises(ParameterError, match="'solver' parameter of Fitness"):
        Fitness(cases[:1], "NM", solver="greedy")
    with pytest.raises(ParameterError, match="'solver' parameter of evaluate"):
        evaluate(cases[:1], "NM", Params(match_bias=0.0), solver="greedy")


def _one_at_a_time(fitness, population):
    """The mean over seeds of evaluate()'s fitness: one Params, one network and one run per
    chromosome and seed."""
    return np.array([sum(evaluate(fitness.cases, fitness.method, fitness.params(c), seed=fitness.seed + s,
                                  solver=fitness.solver).fitness for s in range(fitness.seeds))
                     / fitness.seeds for c in population])


@pytest.mark.parametrize("method", ["I", "II", "III", "NM", "NM4", "NM3"])
def test_a_batch_of_chromosomes_scores_as_each_one_alone(cases, method):
    """The compiled batch (every built-in method, both rules, both stop rules, several seeds,
    Method-I's post-processing) gives each chromosome the fitness of its own network run."""
    from ismb_lab.tuning.genetic import initial_population
    from ismb_lab.network.solvers import get_solver

    population = initial_population(len(method), gene_bounds(method), 25)
    population[0] = gene_bounds(method).low   # the edges of the box too
    population[1] = gene_bounds(method).high
    for solver in (get_solver("network"), get_solver("network", rule="thesis"),
                   get_solver("network", stop_rule="stall")):
        for seeds in (1, 3):
            fitness = Fitness(cases[:2], method, solver=solver, seeds=seeds, seed=5)
            assert fitness._batch(population) is not None
            batched, alone = fitness(population), _one_at_a_time(fitness, population)
            assert batched.dtype == alone.dtype and np.array_equal(batched, alone)
            assert len(set(batched.tolist())) > 1   # the chromosomes differ in what they score


def test_the_batch_leaves_other_methods_solvers_and_bad_genes_to_the_general_path(cases):
    from ismb_lab.network.methods import MethodIII

    class Flat(MethodIII):
        name = "FLAT-TEST"

        def similarity(self, problem, params):
            return np.zeros(problem.n_neurons)

    population = np.array([[10.0, 20.0, 3.0, 2.0], [30.0, 10.0, 1.0, 5.0]])
    flat = Fitness(cases[:1], Flat())
    assert flat._batch(population) is None
    assert np.array_equal(flat(population), _one_at_a_time(flat, population))
    from ismb_lab.network.solvers import get_solver
    textbook = Fitness(cases[:1], "III", solver=get_solver("network", kernel="textbook"))
    assert textbook._batch(population) is None
    assigned = Fitness(cases[:1], "III", solver="assign")
    assert assigned._batch(population) is None
    bad = np.array([[10.0, 20.0, -3.0, 2.0]])   # lambda_c must be > 0
    plain = Fitness(cases[:1], "III")
    assert plain._batch(bad) is None
    with pytest.raises(ParameterError, match="'lambda_c'"):
        plain(bad)


def test_the_general_path_scores_each_chromosome_over_its_seeds_as_evaluate_does(cases):
    """The annealing path (no compiled batch) builds each network once for all the fit seeds;
    the fitness is still evaluate()'s mean over the seeds."""
    from ismb_lab.tuning.genetic import initial_population
    from ismb_lab.network.solvers import AnnealSolver

    population = initial_population(3, gene_bounds("NM3"), 4)
    for solver in ("anneal", AnnealSolver(settle=0.2)):
        fitness = Fitness(cases[:2], "NM3", solver=solver, seeds=3, seed=2)
        assert fitness._batch(population) is None
        assert np.array_equal(fitness(population), _one_at_a_time(fitness, population))


def test_a_persons_few_labels_are_scored_only_at_the_corners_they_label(tmp_path):
    """Five true pairs saved, as a student saves them in notebook 04: read as the thesis' full
    target list, every other match is an extra and the fitness is far below 5; read as partial
    labels, only the five corners count, as notebook 04 scores them."""
    import cv2

    from ismb_lab.matching.pipeline import match, prepare
    from ismb_lab.tuning.cases import Case
    from ismb_lab.scenes import synthetic_scene, true_matches
    from ismb_lab.labels.targets import save_targets, targets_from_matches
    from ismb_lab.widgets.explorer import ParameterExplorer

    scene = synthetic_scene(seed=3)
    files = [tmp_path / "left.png", tmp_path / "right.png"]
    for path, image in zip(files, (scene.left, scene.right)):
        cv2.imwrite(str(path), np.clip(np.rint(image), 0, 255).astype(np.uint8))
    prepared = prepare(*files)
    truth = true_matches(scene, prepared.problem.left_xy, prepared.problem.right_xy)
    found = match(prepared=prepared, method="III", seed=0).pairs
    five = [(i, k) for i, k in found.tolist() if truth[i] == k][:5]
    assert len(five) == 5 and len(found) >= 10
    path = save_targets(tmp_path / "mine.json", targets_from_matches(
        five, prepared.problem.left_xy, prepared.problem.right_xy,
        left_sha256=prepared.pair.left_sha256, right_sha256=prepared.pair.right_sha256))

    whole, partial = Case.from_files(*files, path), Case.from_files(*files, path, partial=True)
    assert whole.unknown.size == 0 and sorted(set(partial.unknown.tolist()) | {i for i, _ in five}) \
        == list(range(len(prepared.problem.left_xy)))
    from ismb_lab.network.methods import THESIS_PARAMS

    as_whole, as_partial = (evaluate([c], "III", THESIS_PARAMS["III"]) for c in (whole, partial))
    assert as_whole.extra == len(found) - 5 and as_whole.fitness < 0
    assert str(as_partial) == "5/0+0/5" and as_partial.fitness == 5

    explorer = ParameterExplorer(*files, targets=path, partial=True)
    assert explorer.model.score == as_partial
    with pytest.raises(TypeError, match="'partial' parameter of ParameterExplorer.*True or False.*'yes'"):
        ParameterExplorer(*files, targets=path, partial="yes")
    with pytest.raises(TypeError, match="'partial' parameter of Case.from_files"):
        Case.from_files(*files, path, partial=1)
