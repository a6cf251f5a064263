import json
import threading
import time

import numpy as np
import pytest

from ismb_lab.network.methods import Params
from ismb_lab.tuning.cases import Case
from ismb_lab.tuning.fitness import to_params, tune
from ismb_lab.widgets.ga_runner import GAModel, GARunner


@pytest.fixture(scope="module")
def case(prepared, truth):
    return Case(prepared, truth, name="synthetic")


@pytest.fixture(scope="module")
def endless(prepared, truth):
    """A case with one target no network can produce (not a candidate), so the GA never
    reaches its target mean and runs until stopped."""
    rows, cols = prepared.problem.rows, prepared.problem.cols
    k = next(k for k in range(len(prepared.problem.right_xy)) if k not in cols[rows == 0])
    return Case(prepared, np.vstack([truth, [[0, k]]]), name="endless")


def slow(runner, seconds=0.02):
    runner.model.listeners.append(lambda record: time.sleep(seconds))


def test_model_records_equal_tune(case):
    model = GAModel([case], population=6, generations=4, seed=3)
    assert model.start()
    assert model.wait(60) and model.status in ("finished",)
    expected = list(tune([case], "III", rng=3, population=6, generations=4, seed=3))
    assert [g.best for g in model.history] == [g.best for g in expected]
    assert [g.mean for g in model.history] == [g.mean for g in expected]
    assert model.best_params == to_params("III", expected[-1].best_chromosome)


def test_the_status_says_how_long_the_ga_computed_without_its_pauses(endless):
    """The runner reports the seconds of GA work; time spent in listeners (here a held
    generation) and in pauses is not counted."""
    model = GAModel([endless], population=6, generations=6, seed=0)
    model.listeners.append(lambda record: time.sleep(0.3))
    began = time.monotonic()
    assert model.start() and model.wait(60) and model.status == "finished"
    wall = time.monotonic() - began
    assert 0 < model.elapsed < wall - 6 * 0.3 + 0.05, (model.elapsed, wall)
    assert f"network evaluations in {model.elapsed:.1f} s" in model.describe()


def test_stop_mid_run_ends_the_thread(endless):
    runner = GARunner(endless, population=6, generations=500, redraw_every=0.05)
    slow(runner)
    runner.start_button.click()
    assert runner.model.running and runner.start_button.disabled and not runner.stop_button.disabled
    deadline = time.monotonic() + 20
    while len(runner.model.history) < 4 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert len(runner.model.history) >= 4
    runner.stop_button.click()
    assert runner.wait(10)
    count = len(runner.model.history)
    assert 4 <= count < 50 and runner.model.status == "stopped"
    time.sleep(0.1)
    assert len(runner.model.history) == count
    assert not any(t.name.startswith("ismb-ga") for t in threading.enumerate())
    assert runner.progress.value == runner.model.history[-1].index
    assert "stopped, generation" in runner.status.value
    assert len(runner.artists["best"].get_xdata()) == count  # the final redraw happened
    assert not runner.start_button.disabled and runner.stop_button.disabled


def test_stop_after_the_run_ended_keeps_its_final_status(case):
    # Stop pressed as the run ends: the run's last word stays (it used to be replaced by
    # "stopping after the current generation", for good)
    runner = GARunner(case, population=6, generations=3)
    runner.start()
    assert runner.wait(60) and runner.model.status == "finished"
    final = runner.status.value
    runner.stop_button.click()   # a click the browser sent before the button was disabled
    assert runner.status.value == final and "finished, generation" in final


def test_a_failing_final_redraw_lands_in_the_log(case, monkeypatch):
    # only the watcher thread redraws here (no redraw during the run); its error must show
    runner = GARunner(case, population=6, generations=2, redraw_every=1e9)
    monkeypatch.setattr(runner.pane, "draw", lambda: (_ for _ in ()).throw(RuntimeError("no canvas")))
    runner.start()
    assert runner.wait(60) and runner.model.error is None
    assert "Error: no canvas" in runner.status.value
    assert any("RuntimeError: no canvas" in o.get("text", "") for o in runner.log.outputs)


def test_pause_holds_the_run_and_resume_continues(endless):
    runner = GARunner(endless, population=6, generations=500)
    slow(runner, 0.01)
    runner.start()
    while len(runner.model.history) < 2:
        time.sleep(0.01)
    runner.pause_button.click()
    assert runner.model.status == "paused" and runner.pause_button.description == "Resume"
    time.sleep(0.1)
    held = len(runner.model.history)
    time.sleep(0.2)
    assert len(runner.model.history) == held
    runner.pause_button.click()
    while len(runner.model.history) < held + 2:
        time.sleep(0.01)
    runner.stop()
    assert runner.wait(10) and runner.model.status == "stopped"


def test_finished_run_apply_calls_back(case):
    runner = GARunner(case, population=8, generations=6, seed=1)
    received = []
    runner.on_apply(received.append)
    runner.apply_button.click()
    assert received == [] and "Start the GA first" in runner.status.value
    runner.start()
    assert runner.wait(60)
    assert runner.model.status == "finished"
    runner.apply_button.click()
    assert len(received) == 1 and isinstance(received[0], Params)
    assert received[0] == runner.model.best_params
    assert "best chromosome" in runner.chromosome.value
    x, best = runner.artists["best"].get_data()
    assert list(best) == [g.best for g in runner.model.history]


def test_a_failing_fitness_lands_in_the_log(case, monkeypatch):
    runner = GARunner(case, population=4, generations=5)
    runner.model.listeners.insert(0, lambda record: 1 / 0)
    runner.start()
    assert runner.wait(30)
    assert runner.model.status == "failed"
    assert any("ZeroDivisionError" in o["text"] for o in runner.log.outputs)


def test_from_folder_and_bad_input(pair_folder, tmp_path):
    runner = GARunner.from_folder(pair_folder, method="I", population=4, generations=2)
    assert runner.model.method.name == "I" and runner.model.target > 0
    assert "ismb-ga" in runner.widget._dom_classes and "ismb-progress" in runner.progress._dom_classes
    with pytest.raises(TypeError, match="'cases_or_folder' parameter"):
        GARunner(42)
    (pair_folder / "answer_key.json").unlink()
    with pytest.raises(ValueError, match="answer_key.json"):
        GARunner.from_folder(pair_folder)
    with pytest.raises(TypeError, match="'callback' parameter"):
        runner.on_apply("not callable")


def test_the_best_parameters_so_far_are_on_disk_during_the_run(case, tmp_path):
    path = tmp_path / "params.json"
    model = GAModel([case], population=6, generations=5, seed=3, save_to=path)
    model.start()
    assert model.wait(120)
    saved = json.loads(path.read_text())
    assert saved["params"] == model.best_params.to_dict() and saved["fitness"] == model.best.best
    with pytest.raises(ValueError, match="'save_to' parameter of GAModel"):
        GAModel([case], save_to=tmp_path / "no" / "p.json")


KILLED = """
import sys, time
from ismb_lab.tuning.cases import Case
from ismb_lab.scenes import synthetic_scene
from ismb_lab.widgets.ga_runner import GAModel

case = Case.from_scene(synthetic_scene(seed=0))
model = GAModel([case], population=8, generations=100000, seed=1, save_to=sys.argv[1])
model.start()
while len(model.history) < 3:
    time.sleep(0.05)
print("running", flush=True)
model.wait()
"""


@pytest.mark.slow
def test_a_kernel_killed_mid_run_leaves_the_best_so_far(tmp_path):
    import signal
    import subprocess
    import sys

    path = tmp_path / "params.json"
    proc = subprocess.Popen([sys.executable, "-c", KILLED, str(path)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "running"
        proc.send_signal(signal.SIGTERM)       # what a hub's culler or a kernel shutdown sends
        proc.wait(60)
    finally:
        proc.kill()
    saved = json.loads(path.read_text())
    assert saved["method"] == "III" and saved["generations"] >= 0 and set(saved["params"]) >= {"theta_c"}


def test_solver_menu_tunes_with_that_solver_and_records_it(case, tmp_path):
    runner = GARunner(case, population=6, generations=3, seed=2, save_to=tmp_path / "p.json")
    runner.solver_menu.value = "anneal"
    assert runner.model.solver == "anneal" and "(anneal)" in runner.status.value
    runner.start_button.click()
    assert runner.wait(120) and runner.model.status == "finished"
    expected = list(tune([case], "III", rng=2, population=6, generations=3, seed=2, solver="anneal"))
    assert [g.best for g in runner.model.history] == [g.best for g in expected]
    assert json.loads((tmp_path / "p.json").read_text())["solver"] == "anneal"
    from ismb_lab.matching.recipe import load_recipe

    saved = load_recipe(tmp_path / "p.json").recipe       # the recipe match --params-file uses as it is
    assert saved.solver.name == "anneal" and saved.params == runner.model.best_params


def test_solver_cannot_change_mid_run(endless):
    runner = GARunner(endless, population=6, generations=500, redraw_every=0.05)
    slow(runner)
    runner.start_button.click()
    assert runner.solver_menu.disabled
    with pytest.raises(ValueError, match="'solver' parameter of GARunner.set_solver"):
        runner.set_solver("exact")
    assert runner.model.solver == "network" and runner.solver_menu.value == "network"
    runner.stop_button.click()
    assert runner.wait(10) and not runner.solver_menu.disabled


def test_the_generations_field_sets_the_length_of_the_next_run(endless):
    """A class can stop the GA after a few generations: the field sets the next run's limit,
    which the run keeps (the endless case never reaches its target), and the status and the
    progress bar count to it."""
    runner = GARunner(endless, population=6, generations=500, redraw_every=0.05)
    runner.generations_field.value = 4
    assert runner.model.generations == 4 and runner.progress.max == 4 and "(6 chromosomes" in runner.status.value
    runner.start_button.click()
    assert runner.wait(60) and runner.model.status == "finished"
    assert [g.index for g in runner.model.history] == [0, 1, 2, 3, 4]
    assert "generation 4/4" in runner.status.value and runner.progress.value == 4
    expected = list(tune([endless], "III", rng=0, population=6, generations=4, seed=0))
    assert [g.best for g in runner.model.history] == [g.best for g in expected]


def test_generations_cannot_change_mid_run_or_below_one(endless):
    runner = GARunner(endless, population=6, generations=500, redraw_every=0.05)
    slow(runner)
    runner.start_button.click()
    assert runner.generations_field.disabled
    with pytest.raises(ValueError, match="'generations' parameter of GAModel.set_generations"):
        runner.set_generations(50)
    assert runner.model.generations == 500 and runner.generations_field.value == 500
    runner.stop_button.click()
    assert runner.wait(10) and not runner.generations_field.disabled
    with pytest.raises(ValueError, match="'generations' parameter of GAModel.set_generations must be"):
        runner.model.set_generations(0)
