import numpy as np
import pytest

from ismb_lab.tuning.evaluation import score
from ismb_lab.matching.pipeline import match
from ismb_lab.network.methods import THESIS_PARAMS, Params
from ismb_lab.network.similarity import transfer
from ismb_lab.widgets.explorer import ExplorerModel, ParameterExplorer


@pytest.fixture
def explorer(prepared, truth):
    return ParameterExplorer(prepared, targets=truth)


def test_slider_rematches_and_redraws(explorer, prepared, truth):
    explorer.sliders["theta_c"].value = 4.5
    assert explorer.params.theta_c == 4.5
    expected = match(prepared=prepared, method="III", params=Params(4.5, 24.02, 6.37, 2.2), seed=0)
    np.testing.assert_array_equal(explorer.model.pairs, expected.pairs)
    assert len(explorer.pair_artists["lines"].get_segments()) == len(expected.pairs)
    assert str(score(expected.pairs, truth)) in explorer.score_label.value
    np.testing.assert_allclose(explorer.transfer_artists["c"].get_ydata(),
                               transfer(explorer.transfer_artists["x"], 4.5, 6.37))
    assert explorer.transfer_artists["c_dot"].get_xdata()[0] == 4.5


def test_each_slider_reaches_its_gene(explorer):
    for gene, value in (("theta_s", 10.0), ("lambda_c", 1.5), ("lambda_s", 0.5)):
        explorer.sliders[gene].value = value
        assert getattr(explorer.params, gene) == value
    np.testing.assert_allclose(explorer.transfer_artists["s"].get_ydata(),
                               transfer(explorer.transfer_artists["x"], 10.0, 0.5))


def test_method_and_seed_controls(explorer, prepared):
    explorer.method_menu.value = "I"
    assert explorer.model.method == "I" and explorer.sliders["theta_s"].disabled
    explorer.seed_field.value = 7
    expected = match(prepared=prepared, method="I", params=THESIS_PARAMS["III"], seed=7)
    np.testing.assert_array_equal(explorer.model.pairs, expected.pairs)
    assert "Method-I (network), seed 7" in explorer.status.value


def test_solver_menu_rematches_with_that_solver(explorer, prepared):
    explorer.solver_menu.value = "anneal"
    expected = match(prepared=prepared, method="III", params=THESIS_PARAMS["III"], seed=0, solver="anneal")
    assert explorer.model.solver == "anneal"
    np.testing.assert_array_equal(explorer.model.pairs, expected.pairs)
    assert "Method-III (anneal)" in explorer.status.value


def test_a_refused_solver_keeps_the_last_state(explorer, monkeypatch):
    import ismb_lab.widgets.explorer as module
    from ismb_lab import ParameterError

    before = explorer.model.pairs.copy()
    real = module.match

    def refuse_exact(**kw):
        if kw["solver"] == "exact":
            raise ParameterError("The 'net' parameter of exhaustive_minimum must be small. Got 900 instead.")
        return real(**kw)

    monkeypatch.setattr(module, "match", refuse_exact)
    explorer.solver_menu.value = "exact"
    assert "exhaustive_minimum" in str(explorer.log.outputs)
    assert explorer.model.solver == "network" and explorer.solver_menu.value == "network"
    np.testing.assert_array_equal(explorer.model.pairs, before)
    explorer.sliders["theta_c"].value = 4.5      # still responds, with the solver in use
    assert explorer.model.solver == "network" and explorer.params.theta_c == 4.5


def test_set_params_rematches_once(explorer, monkeypatch):
    calls = []
    original = explorer.model.rematch
    monkeypatch.setattr(explorer.model, "rematch", lambda: calls.append(1) or original())
    params = Params(theta_c=9.0, theta_s=30.0, lambda_c=2.0, lambda_s=1.0)
    explorer.set_params(params)
    assert calls == [1] and explorer.params == params
    assert [s.value for s in explorer.sliders.values()] == [9.0, 30.0, 2.0, 1.0, 0.0]
    with pytest.raises(TypeError, match="'params' parameter"):
        explorer.set_params({"theta_c": 1})


def test_ga_apply_reaches_the_explorer(explorer, prepared, truth):
    from ismb_lab.tuning.cases import Case
    from ismb_lab.widgets.ga_runner import GARunner

    runner = GARunner(Case(prepared, truth), population=4, generations=2)
    runner.on_apply(explorer.set_params)
    runner.start()
    assert runner.wait(60)
    runner.apply_button.click()
    assert explorer.params == runner.model.best_params


def test_bad_slider_value_is_logged_not_lost(explorer, monkeypatch):
    monkeypatch.setattr(explorer.model, "set", lambda **kw: (_ for _ in ()).throw(ValueError("bad")))
    explorer.sliders["lambda_c"].value = 3.0
    assert any("ValueError: bad" in o["text"] for o in explorer.log.outputs)


def test_without_targets_says_so(prepared):
    model = ExplorerModel(prepared)
    assert model.score is None and "no targets" in model.score_text()


def test_from_folder_reads_the_answer_key(pair_folder, truth):
    explorer = ParameterExplorer.from_folder(pair_folder)
    np.testing.assert_array_equal(np.sort(explorer.model.targets, axis=0), np.sort(truth, axis=0))
    assert "ismb-explorer" in explorer.widget._dom_classes
    assert "ismb-theta-c" in explorer.sliders["theta_c"]._dom_classes
    fig = explorer.static_figure()
    assert len(fig.axes) == 3



@pytest.mark.parametrize("lambda_s", [0.3, 1.16, 4.0])
def test_nm3_draws_s_at_the_theta_s_it_sets_from_the_pair(prepared, lambda_s):
    from matplotlib.figure import Figure

    from ismb_lab.network.methods import get_method
    from ismb_lab.widgets.explorer import draw_transfer, update_transfer

    params = Params(theta_c=17.97, theta_s=24.02, lambda_c=6.37, lambda_s=lambda_s)
    model = ExplorerModel(prepared, "NM3", params)
    cut = prepared.problem.no_match_cut
    assert abs(cut - params.theta_s) > 1      # the pair's theta_s is not the one in params
    art = draw_transfer(Figure().subplots(1, 2), model)
    update_transfer(art, model)
    theta = art["s_theta"].get_xdata()[0]
    assert theta == pytest.approx(cut, abs=1e-9) and art["s_dot"].get_xdata()[0] == theta
    # the curve drawn is the S the method's network is built with, neuron by neuron
    network = get_method("NM3").network(prepared.problem, model.params)
    np.testing.assert_allclose(transfer(prepared.problem.neuron_dissimilarity, theta, lambda_s),
                               network.similarity, atol=1e-9)
    assert art["s"].get_alpha() == 1.0


def test_s_is_faded_only_for_a_method_without_it(prepared):
    from matplotlib.figure import Figure

    from ismb_lab.widgets.explorer import draw_transfer, update_transfer

    for method, alpha in (("I", 0.25), ("III", 1.0), ("NM4", 1.0), ("NM3", 1.0)):
        model = ExplorerModel(prepared, method)
        art = draw_transfer(Figure().subplots(1, 2), model)
        update_transfer(art, model)
        assert art["s"].get_alpha() == alpha, method
        if method in ("III", "NM4"):
            assert art["s_theta"].get_xdata()[0] == model.params.theta_s
