"""A recipe is one saved object: what tune fits with is what match, depth and evaluate use."""

import json

import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.cli import main
from ismb_lab.network.params import Params
from ismb_lab.matching.recipe import RECIPE_VERSION, Recipe, load_recipe, save_recipe
from ismb_lab.scenes import synthetic_scene
from ismb_lab.network.solvers import AnnealSolver, NetworkSolver


@pytest.fixture(scope="module")
def targets(pair, tmp_path_factory, rendered):
    from ismb_lab.matching.pipeline import prepare
    from ismb_lab.scenes import true_matches
    from ismb_lab.labels.targets import save_targets, targets_from_matches

    prepared = prepare(*pair)
    truth = true_matches(rendered(synthetic_scene, seed=3), prepared.problem.left_xy, prepared.problem.right_xy)
    found = [(i, k) for i, k in enumerate(truth) if k >= 0]
    return save_targets(tmp_path_factory.mktemp("targets") / "targets.json", targets_from_matches(
        found, prepared.problem.left_xy, prepared.problem.right_xy,
        left_sha256=prepared.pair.left_sha256, right_sha256=prepared.pair.right_sha256))


@pytest.fixture(scope="module")
def tuned(pair, targets, tmp_path_factory):
    """The params file of tune with the README's best recipe: NM3, annealed, 2 fit seeds, one-to-one."""
    out = tmp_path_factory.mktemp("tuned") / "recipe.json"
    assert main(["tune", *map(str, pair), str(targets), "--method", "NM3", "--solver", "anneal", "--fit-seeds", "2",
                 "--one-to-one", "--generations", "2", "--population", "6", "--out", str(out)]) == 0
    return out


def match_json(pair, tmp_path, capsys, *options, name="m.json"):
    out = tmp_path / name
    assert main(["match", *map(str, pair), *map(str, options), "--json", str(out)]) == 0
    return json.loads(out.read_text()), capsys.readouterr().err


def test_tune_saves_the_whole_recipe(tuned):
    data = json.loads(tuned.read_text())
    assert data["version"] == RECIPE_VERSION and data["method"] == "NM3" and data["solver"] == "anneal"
    assert data["solver_options"] == AnnealSolver().options()
    assert data["fit_seeds"] == 2 and data["one_to_one"] is True
    recipe = load_recipe(tuned).recipe
    assert recipe == Recipe("NM3", Params(**data["params"]), "anneal", 2, True)


def test_match_with_the_params_file_alone_gives_the_figures_of_the_options_retyped(pair, tuned, tmp_path, capsys):
    alone, said = match_json(pair, tmp_path, capsys, "--params-file", tuned, name="alone.json")
    retyped, _ = match_json(pair, tmp_path, capsys, "--params-file", tuned, "--solver", "anneal", "--one-to-one",
                            name="retyped.json")
    assert (alone["solver"], alone["one_to_one"]) == ("anneal", True)
    assert alone == retyped
    assert said == ""     # nothing overridden, nothing to say


def test_an_option_overrides_one_field_and_says_so_in_one_line(pair, tuned, tmp_path, capsys):
    plain, said = match_json(pair, tmp_path, capsys, "--params-file", tuned, "--solver", "network",
                             "--no-one-to-one", "--theta-c", "3")
    assert (plain["solver"], plain["one_to_one"], plain["params"]["theta_c"]) == ("network", False, 3.0)
    notes = [line for line in said.splitlines() if "override" in line]
    assert len(notes) == 1 and said.count("\n") == 1
    assert "solver anneal -> network" in notes[0] and "one_to_one True -> False" in notes[0]
    assert "theta_c" in notes[0] and str(tuned) in notes[0]


def test_the_network_options_refuse_a_solver_without_a_network(pair, tuned, tmp_path, capsys):
    out = tmp_path / "m.json"
    code = main(["match", *map(str, pair), "--params-file", str(tuned), "--stop-rule", "stall", "--json", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--stop-rule" in err and "anneal" in err
    assert not out.exists()
    stalled, _ = match_json(pair, tmp_path, capsys, "--params-file", tuned, "--solver", "network",
                            "--stop-rule", "stall")
    assert stalled["stop_rule"] in ("stall", "sweep", "max_attempts") and stalled["solver"] == "network"


def test_method_with_another_params_file_stays_an_error(pair, tuned, capsys):
    assert main(["match", *map(str, pair), "--params-file", str(tuned), "--method", "III"]) == 2
    assert "conflicts with --params-file" in capsys.readouterr().err


def old_file(tmp_path, **extra):
    path = tmp_path / "old.json"
    path.write_text(json.dumps({"method": "NM3", "params": {"theta_c": 9.0, "lambda_c": 5.0, "lambda_s": 4.0},
                                **extra}))
    return path


def test_an_old_file_loads_and_its_saved_solver_is_used_with_a_note_once(pair, tmp_path, capsys):
    annealed, said = match_json(pair, tmp_path, capsys, "--params-file", old_file(tmp_path, solver="anneal"))
    assert annealed["solver"] == "anneal" and annealed["params"]["theta_c"] == 9.0
    assert said.count("written before recipes") == 1 and "'anneal'" in said and "'network'" in said
    plain, said = match_json(pair, tmp_path, capsys, "--params-file", old_file(tmp_path))
    assert plain["solver"] == "network" and said == ""
    same, said = match_json(pair, tmp_path, capsys, "--params-file", old_file(tmp_path, solver="network"))
    assert same["solver"] == "network" and said == ""


def test_depth_reads_an_old_file_against_its_own_former_solver(tmp_path):
    path = old_file(tmp_path, solver="network")
    loaded = load_recipe(path, solver="anneal", before="anneal")     # what ismb-lab depth passes
    assert loaded.recipe.solver == NetworkSolver() and "used 'anneal' with it before" in loaded.note
    assert load_recipe(old_file(tmp_path), solver="anneal", before="anneal") == (
        Recipe("NM3", Params(theta_c=9.0, lambda_c=5.0, lambda_s=4.0), "anneal"), "")


def test_a_recipe_round_trips_with_its_solver_options(tmp_path):
    recipe = Recipe("NM", Params(match_bias=0.5), AnnealSolver(cooling=0.8), fit_seeds=3, one_to_one=True)
    path = save_recipe(tmp_path / "r.json", recipe, fitness=4)
    assert load_recipe(path) == (recipe, "")
    assert json.loads(path.read_text())["fitness"] == 4
    with pytest.raises(ParameterError, match="'extra' parameter of save_recipe"):
        save_recipe(tmp_path / "x.json", recipe, solver="network")


@pytest.mark.parametrize("change, words", [
    ({"version": 3}, "'version' parameter"),
    ({"version": "2"}, "'version' parameter"),
    ({"solver": "annealing"}, "'solver' parameter"),
    ({"solver": "anneal", "solver_options": {"stop_rule": "stall"}}, "'stop_rule' parameter"),
    ({"solver_options": [1]}, "'solver_options' parameter"),
    ({"fit_seeds": 0}, "'fit_seeds' parameter"),
    ({"one_to_one": "yes"}, "'one_to_one' parameter"),
])
def test_a_bad_recipe_file_is_named(tmp_path, change, words):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"method": "III", "params": {}, **change}))
    with pytest.raises((ParameterError, ParameterTypeError), match=words):
        load_recipe(path)


def test_evaluate_takes_the_recipes_solver_fit_seeds_and_one_to_one(tuned, tmp_path, monkeypatch, capsys):
    import ismb_lab.cli.evaluate as command

    seen = {}

    def fake_protocol(cases, method, **kwargs):
        seen.update(method=method, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(command, "protocol", fake_protocol)
    monkeypatch.setattr(command, "load_manifest", lambda path: [])
    main(["evaluate", str(tmp_path / "m.json"), "--recipe", str(tuned)])
    assert seen["method"].name == "NM3" and seen["solver"] == seen["fit_solver"] == AnnealSolver()
    assert seen["fit_seeds"] == 2 and seen["one_to_one"] is True
    assert "override" not in capsys.readouterr().err
    main(["evaluate", str(tmp_path / "m.json"), "--recipe", str(tuned), "--fit-seeds", "1", "--no-one-to-one"])
    assert seen["fit_seeds"] == 1 and seen["one_to_one"] is False
    notes = [line for line in capsys.readouterr().err.splitlines() if "override" in line]
    assert len(notes) == 1 and "fit_seeds 2 -> 1" in notes[0] and "one_to_one True -> False" in notes[0]


def test_depth_uses_the_params_file_as_it_is(tuned, tmp_path, capsys):
    from pathlib import Path

    images = Path(__file__).resolve().parents[1] / "images"
    scenes = [images / folder / side for folder in ("lab", "toy_cars") for side in ("left.png", "right.png")]
    out = tmp_path / "depth.json"
    assert main(["depth", *map(str, scenes), "--params-file", str(tuned), "--json", str(out)]) == 0
    said = capsys.readouterr()
    assert "Method-NM3 (anneal, one match per corner)" in said.out and "override" not in said.err
    assert json.loads(out.read_text())["objects"]


def test_evaluate_interrupted_writes_the_recipe_with_the_best_so_far(tuned, tmp_path, monkeypatch, capsys):
    from types import SimpleNamespace

    import ismb_lab.cli.evaluate as command

    def interrupted_protocol(cases, method, progress=None, **kwargs):
        progress("a", SimpleNamespace(best_chromosome=[9.0, 5.0, 4.0], best=3.0, index=2, mean=1.0))
        raise KeyboardInterrupt

    monkeypatch.setattr(command, "protocol", interrupted_protocol)
    monkeypatch.setattr(command, "load_manifest", lambda path: [])
    out = tmp_path / "report.json"
    assert main(["evaluate", str(tmp_path / "m.json"), "--recipe", str(tuned), "--jobs", "1",
                 "--json", str(out)]) == 130
    saved = load_recipe(out).recipe
    assert saved == Recipe("NM3", Params(theta_c=9.0, lambda_c=5.0, lambda_s=4.0), "anneal", 2, True)
    assert json.loads(out.read_text())["interrupted"] is True and "interrupted" in capsys.readouterr().err


@pytest.fixture(scope="module")
def scheduled(pair, targets, tmp_path_factory):
    """A tune whose annealing schedule is set with --solver-option."""
    out = tmp_path_factory.mktemp("scheduled") / "recipe.json"
    assert main(["tune", *map(str, pair), str(targets), "--method", "NM3", "--solver", "anneal", "--solver-option",
                 "cooling=0.8", "--solver-option", "sweeps=1", "--solver-option", "settle=0.2", "--fit-seeds", "3",
                 "--one-to-one", "--generations", "2", "--population", "6", "--out", str(out)]) == 0
    return out


def test_tune_records_the_solver_options_given_and_match_uses_them_alone(pair, scheduled, tmp_path, capsys):
    data = json.loads(scheduled.read_text())
    assert data["solver_options"] == AnnealSolver(cooling=0.8, sweeps=1, settle=0.2).options()
    assert load_recipe(scheduled).recipe.solver == AnnealSolver(cooling=0.8, sweeps=1, settle=0.2)
    assert data["fit_seeds"] == 3
    alone, said = match_json(pair, tmp_path, capsys, "--params-file", scheduled, name="alone.json")
    retyped, _ = match_json(pair, tmp_path, capsys, "--params-file", scheduled, "--solver", "anneal",
                            "--solver-option", "cooling=0.8", "--solver-option", "sweeps=1", "--solver-option",
                            "settle=0.2", "--one-to-one", name="retyped.json")
    assert alone == retyped and said == ""
    default, said = match_json(pair, tmp_path, capsys, "--params-file", scheduled, "--solver-option", "cooling=0.9",
                               "--solver-option", "sweeps=2", "--solver-option", "settle=0", name="default.json")
    assert "solver options" in said and said.count("\n") == 1
    assert default["params"] == alone["params"]


@pytest.mark.parametrize("options, words", [
    (["--solver-option", "cool=0.8"], "'cool' option of ismb-lab's --solver-option"),
    (["--solver-option", "cooling=2"], "'cooling' parameter of AnnealSolver"),
    (["--solver-option", "cooling"], "NAME=VALUE"),
    (["--solver", "network", "--solver-option", "cooling=0.8"], "the 'network' solver"),
])
def test_a_bad_solver_option_is_one_line(pair, targets, tmp_path, capsys, options, words):
    out = tmp_path / "p.json"
    code = main(["tune", *map(str, pair), str(targets), "--solver", "anneal", *options, "--generations", "2",
                 "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err
    assert not out.exists()
    code = main(["match", *map(str, pair), "--solver", "anneal", *options, "--json", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err
