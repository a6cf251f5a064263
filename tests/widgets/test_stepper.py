import numpy as np
import pytest

from ismb_lab.network.dynamics import iter_updates, run
from ismb_lab.matching.pipeline import match
from ismb_lab.network.methods import THESIS_PARAMS, get_method
from ismb_lab.widgets.stepper import HopfieldStepper, StepperModel


@pytest.fixture
def stepper(prepared):
    return HopfieldStepper(prepared, seed=3)


def test_steps_follow_the_core_generator(prepared):
    model = StepperModel(prepared, seed=5)
    made = model.step(37)
    core = list(iter_updates(model.network, rng=5))[:37]
    assert made == core
    state = model.network.initial_state().copy()
    for u in core:
        state[u.neuron] = u.new
    np.testing.assert_array_equal(model.state, state)
    assert model.energies[1:] == [u.energy for u in core]


@pytest.mark.parametrize("method,seed", [("III", 0), ("II", 4), ("I", 2)])
def test_run_to_convergence_equals_the_core_run(prepared, method, seed):
    model = StepperModel(prepared, method, seed=seed)
    model.run()
    assert model.stop == "sweep"
    net = get_method(method).network(prepared.problem, THESIS_PARAMS[method])
    core = run(net, rng=seed)
    np.testing.assert_array_equal(model.state, core.state)
    assert model.attempts == core.attempts and model.flips == core.flips
    assert model.energies[-1] == pytest.approx(core.energy, abs=1e-9)
    if method != "I":  # Method-I post-processes the final state
        expected = match(prepared=prepared, method=method, seed=seed).pairs
        np.testing.assert_array_equal(model.pairs, expected)


def test_exact_rule_never_raises_the_energy_and_the_thesis_rule_does(prepared):
    exact = StepperModel(prepared, seed=1)
    exact.run()
    assert len(exact.rises()) == 0 and np.all(np.diff(exact.energies) <= 1e-9)
    thesis = StepperModel(prepared, seed=1, rule="thesis")
    thesis.run(5000)
    assert len(thesis.rises()) > 0


def test_buttons_step_and_redraw(stepper):
    stepper.step_button.click()
    assert stepper.model.attempts == 1
    u = stepper.model.last
    assert f"neuron (i={u.i + 1}, k={u.k + 1})" in stepper.status.value
    assert f"u = {u.u:+.3f}" in stepper.status.value and "Δy" in stepper.status.value
    assert stepper.grid_artists["cursor"].get_xy() == (u.k - 0.5, u.i - 0.5)
    stepper.step10_button.click()
    assert stepper.model.attempts == 11
    x, e = stepper.energy_artists["line"].get_data()
    assert len(x) == 12 and list(e) == stepper.model.energies
    np.testing.assert_array_equal(stepper.grid_artists["grid"].get_array(), stepper.model.grid() + 1)


def test_run_button_converges_draws_once_and_disables_stepping(stepper, monkeypatch):
    draws = []
    monkeypatch.setattr(stepper.energy_pane, "draw", lambda: draws.append(1))
    stepper.run_button.click()
    assert stepper.model.stop == "sweep" and "converged (sweep rule)" in stepper.status.value
    assert draws == [1]
    assert stepper.step_button.disabled and stepper.run_button.disabled
    assert len(stepper.pair_artists["lines"].get_segments()) == len(stepper.model.pairs)


def test_run_is_capped(prepared):
    stepper = HopfieldStepper(prepared, seed=0, run_limit=25)
    stepper.rule_box.value = True
    stepper.run_button.click()
    assert stepper.model.attempts == 25 and "press Run again" in stepper.status.value
    stepper.run_button.click()
    assert stepper.model.attempts == 50


def test_thesis_toggle_and_seed_reset(stepper):
    stepper.step(30)
    stepper.rule_box.value = True
    assert stepper.model.rule == "thesis" and stepper.model.attempts == 0
    stepper.step(3000)
    assert len(stepper.energy_artists["rises"].get_offsets()) == len(stepper.model.rises()) > 0
    stepper.seed_field.value = 9
    assert stepper.model.seed == 9 and stepper.model.attempts == 0
    stepper.rule_box.value = False
    stepper.step(20)
    stepper.reset_button.click()
    assert stepper.model.attempts == 0 and stepper.model.rule == "exact"
    assert not stepper.grid_artists["cursor"].get_visible()


def test_callback_errors_are_logged(stepper, monkeypatch):
    monkeypatch.setattr(stepper.model, "step", lambda n: 1 / 0)
    stepper.step_button.click()
    assert any("ZeroDivisionError" in o["text"] for o in stepper.log.outputs)


def test_from_folder_static_figure_and_classes(pair_folder):
    stepper = HopfieldStepper.from_folder(pair_folder, method="II", seed=2)
    assert stepper.model.method.name == "II" and stepper.model.seed == 2
    assert "ismb-stepper" in stepper.widget._dom_classes
    assert "ismb-energy" in stepper.energy_pane.widget._dom_classes
    stepper.step(5)
    fig = stepper.static_figure()
    assert [ax.get_label() for ax in fig.axes] == ["grid", "pair", "energy", "<colorbar>"]
    key = fig.axes[-1]
    assert [t.get_text() for t in key.get_yticklabels()] == ["no neuron", "off", "on"]
    with pytest.raises(ValueError, match="'folder' parameter"):
        HopfieldStepper.from_folder(pair_folder / "nowhere")


def _lab(colour) -> np.ndarray:
    """CIE L*a*b* (D65) of a matplotlib colour."""
    from matplotlib.colors import to_rgb

    rgb = np.array(to_rgb(colour))
    lin = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ lin
    f = lambda t: np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)  # noqa: E731
    fx, fy, fz = f(xyz / np.array([0.9505, 1.0, 1.089]))
    return np.array([116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)])


@pytest.mark.slow
def test_the_cursor_tells_a_flip_from_a_kept_state_by_far_apart_colours(prepared):
    """Orange beside vermillion differ mostly in lightness (ΔE about 37); the cursor's two
    colours are far apart (ΔE above 50) and neither is vermillion."""
    from ismb_lab.plotting import OKABE_ITO

    stepper = HopfieldStepper(prepared, seed=0)
    seen = {}
    for _ in range(60):
        stepper.step_button.click()
        seen[bool(stepper.model.last.changed)] = stepper.grid_artists["cursor"].get_edgecolor()
    assert set(seen) == {True, False}
    assert np.linalg.norm(_lab(seen[True][:3]) - _lab(seen[False][:3])) > 50
    assert np.linalg.norm(_lab(OKABE_ITO["orange"]) - _lab(OKABE_ITO["vermillion"])) < 50   # the rule can fail
    assert OKABE_ITO["vermillion"] not in {mcolour(c) for c in seen.values()}


def mcolour(rgba) -> str:
    from matplotlib.colors import to_hex

    return to_hex(rgba).upper()
