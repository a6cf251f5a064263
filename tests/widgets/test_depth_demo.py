import re
from pathlib import Path

import numpy as np
import pytest

from ismb_lab.depth.objects import DepthConfig, DepthObject, metric_depth
from ismb_lab.depth.pipeline import relative_depth
from ismb_lab.network.methods import Params
from ismb_lab.widgets import DepthDemo, DepthModel

IMAGES = Path(__file__).resolve().parents[2] / "images"
LAB = (IMAGES / "lab" / "left.png", IMAGES / "lab" / "right.png")
CARS = (IMAGES / "toy_cars" / "left.png", IMAGES / "toy_cars" / "right.png")


@pytest.fixture
def demo():
    return DepthDemo.from_folders(IMAGES / "lab", IMAGES / "toy_cars", background_name="the box")


def expected(**kw):
    return relative_depth(LAB, CARS, **kw).to_dict()


def test_model_computes_what_relative_depth_computes():
    model = DepthModel(IMAGES / "lab", IMAGES / "toy_cars")
    assert model.result.to_dict() == expected()
    config = DepthConfig(position_tol_px=3.0)
    model.set(method="II", seed=4, config=config)
    assert model.result.to_dict() == expected(method="II", seed=4, config=config)
    model.set(disparity_tol_px=2.5)
    assert model.config == DepthConfig(position_tol_px=3.0, disparity_tol_px=2.5)
    assert model.result.to_dict() == expected(method="II", seed=4, config=model.config)


def test_a_seed_change_does_not_find_the_corners_again(monkeypatch):
    import ismb_lab.depth.pipeline as depth_demo

    model = DepthModel(IMAGES / "lab", IMAGES / "toy_cars")
    prepared = model.prepared

    def refuse(*args, **kwargs):
        raise AssertionError("the pairs were prepared again")

    import ismb_lab.widgets.depth_demo as widget

    blobs = model.silhouettes
    monkeypatch.setattr(depth_demo, "prepare", refuse)
    monkeypatch.setattr(depth_demo, "scene_prepared", refuse)
    for owner in (depth_demo, widget):
        monkeypatch.setattr(owner, "pair_silhouettes", refuse)
    model.set(seed=5, method="II", position_tol_px=4.0)
    monkeypatch.undo()
    assert model.prepared is prepared and model.silhouettes is blobs
    assert model.result.to_dict() == expected(method="II", seed=5, config=model.config)


def test_an_outline_setting_finds_the_blobs_again():
    from dataclasses import replace

    from ismb_lab.depth.outlines import OutlineConfig

    model = DepthModel(IMAGES / "lab", IMAGES / "toy_cars")
    blobs = model.silhouettes
    config = replace(model.config, outline=OutlineConfig(pad_px=6))
    model.set(config=config)
    assert model.silhouettes is not blobs and model.silhouettes.pad_px == 6
    assert model.result.to_dict() == expected(config=config)


def test_ranking_lists_objects_near_to_far(demo):
    objects = demo.model.objects
    assert demo.objects is objects
    lines = demo.model.ranking()
    assert len(objects) >= 2 and len(lines) == len(objects)
    shown = [float(re.search(r"d = ([\d.]+) px", line).group(1)) for line in lines]
    assert shown == sorted(shown, reverse=True)
    for n, (line, obj) in enumerate(zip(lines, objects), 1):
        assert line.startswith(f"{n}. object at ({obj.centroid_xy[0]:.0f}, {obj.centroid_xy[1]:.0f}): ")
        assert f"d = {obj.mean_disparity:.1f} px, Z = {obj.depth_m:.2f} m ± " in line
        assert line.endswith(f" ({obj.n_features} features, spread {obj.disparity_spread:.1f} px; "
                             f"outline {obj.silhouette_disparity:.0f} px)")
        assert len(obj.features) >= 2 and obj.disparity_spread >= 0
    assert demo.ranking.value == demo.model.ranking_html()
    assert lines[0] in demo.ranking.value and "the box" in demo.ranking.value
    assert f"{len(objects)} objects" in demo.status.value


def _object(rank, x, d, n=2, spread=0.0):
    return DepthObject(rank, (x, 100.0), d, 0.0, metric_depth(d), np.zeros((n, 2)), n,
                       disparity_spread=spread)


def test_ranking_shows_how_many_features_each_object_rests_on_and_their_spread(demo):
    from dataclasses import replace

    model = demo.model
    model.result = replace(model.result, objects=(_object(1, 80, 34.0, n=1), _object(2, 200, 25.0, 12, 0.5)))
    first, second = model.ranking()
    assert first.endswith("(1 feature, spread 0.0 px)")
    assert second.endswith("(12 features, spread 0.5 px)")
    assert model.objects[1].median_disparity == 25.0          # defaults to the mean
    outline = replace(_object(3, 140, 20.0, n=0), silhouette_disparity=20.0, silhouette_score=0.97)
    shifted = replace(_object(1, 80, 34.4, n=3), silhouette_disparity=34.0, silhouette_score=0.99)
    model.result = replace(model.result, objects=(shifted, outline))
    assert model.ranking()[0].endswith("(3 features, spread 0.0 px; outline 34 px)")
    assert model.ranking()[1].endswith("(outline only: 20 px, overlap 0.97)")
    demo.ranking.value = model.ranking_html()
    assert "outline only: 20 px, overlap 0.97" in demo.ranking.value


def test_sentence_says_which_is_nearer_and_what_they_are_in_front_of(demo):
    from dataclasses import replace

    model = demo.model
    base = model.result
    model.result = replace(base, objects=(_object(1, 80, 34.0), _object(2, 200, 25.0)),
                           background_objects=(_object(1, 150, 21.5),))
    text = model.sentence()
    assert text.startswith("The left object is nearer to the cameras than the right one")
    assert "(34.0 px > 25.0 px)" in text and "both are in front of the box (d = 21.5 px" in text
    model.result = replace(base, objects=(_object(1, 200, 30.0), _object(2, 80, 20.0)),
                           background_objects=(_object(1, 150, 21.5),))
    assert model.sentence().startswith("The right object is nearer")
    assert "only object 1 is in front of the box" in model.sentence()
    model.result = replace(base, objects=(), message="no matches in the scene pair")
    assert model.sentence() == "no matches in the scene pair" and model.ranking() == []


@pytest.mark.slow
def test_controls_recompute_and_redraw(demo):
    demo.seed_field.value = 3
    assert demo.model.result.to_dict() == expected(seed=3)
    demo.method_menu.value = "II"
    assert demo.model.result.to_dict() == expected(seed=3, method="II")
    demo.sliders["position_tol_px"].value = 4.0
    config = DepthConfig(position_tol_px=4.0)
    assert demo.model.result.to_dict() == expected(seed=3, method="II", config=config)
    r = demo.model.result
    np.testing.assert_array_equal(demo.scene_artists["features"].get_offsets(), r.kept_xy.reshape(-1, 2))
    np.testing.assert_array_equal(demo.scene_artists["removed"].get_xdata(), r.removed_xy[:, 0])
    np.testing.assert_array_equal(demo.background_artists["features"].get_offsets(),
                                  r.background.left_match_xy)
    assert len(demo.scene_artists["labels"].get_paths()) == len(r.objects)
    box, (x, y, w, h) = demo.scene_artists["box"], r.scene_roi
    assert box.get_visible() and (box.get_x(), box.get_y(), box.get_width(), box.get_height()) == (
        x - 0.5, y - 0.5, w, h)
    assert "Method-II, seed 3" in demo.status.value and demo.errors == []
    before = demo.model.result
    demo.recompute_button.click()
    assert demo.model.result is not before and demo.model.result.to_dict() == before.to_dict()
    assert demo.model.result.silhouettes is demo.model.silhouettes      # found once, at the start
    outlines = demo.scene_artists["outlines"]
    labels = demo.model.result.silhouettes.labels
    assert outlines.get_visible() and len(outlines.get_segments()) == labels.max() == len(r.objects)
    for polygon in outlines.get_segments():       # each runs along one blob's edge
        x, y = np.rint(polygon).astype(int).T
        assert len(set(labels[y, x].tolist())) == 1 and labels[y[0], x[0]] > 0
    demo.grouping_menu.value = "features"
    assert not outlines.get_visible()
    config = DepthConfig(position_tol_px=4.0, grouping="features")
    assert demo.model.result.to_dict() == expected(seed=3, method="II", config=config)
    assert all(o.silhouette_disparity is None for o in demo.model.objects)


def test_bad_input_is_logged_and_state_kept():
    demo = DepthDemo(LAB, CARS, params=Params())  # four genes: Method-NM needs a fifth
    before = demo.model.result
    demo.method_menu.value = "NM"
    assert any("match_bias" in o["text"] for o in demo.log.outputs)
    assert demo.model.method == "III" and demo.model.result is before
    assert demo.method_menu.value == "III" and "Error" in demo.status.value


def test_bad_arguments_name_the_parameter(tmp_path):
    with pytest.raises(ValueError, match="'folder' parameter of DepthDemo.from_folders"):
        DepthDemo.from_folders(tmp_path, IMAGES / "toy_cars")
    with pytest.raises(TypeError, match="'background' parameter of DepthModel"):
        DepthModel(42, CARS)
    model = DepthModel(LAB, CARS)
    with pytest.raises(ValueError, match="'local_px' parameter of DepthConfig"):
        model.set(local_px=0)
    assert model.config == DepthConfig()


def test_static_figure_and_css(demo):
    fig = demo.static_figure()
    assert len(fig.axes) == 3  # background, scene, colour bar
    assert fig._suptitle.get_text() == demo.model.sentence()
    assert "ismb-depth" in demo.widget._dom_classes
    for w, css in ((demo.ranking, "ismb-ranking"), (demo.seed_field, "ismb-seed"),
                   (demo.method_menu, "ismb-method"), (demo.recompute_button, "ismb-recompute"),
                   (demo.grouping_menu, "ismb-grouping"),
                   (demo.sliders["disparity_tol_px"], "ismb-disparity-tol-px"),
                   (demo.status, "ismb-status"), (demo.log, "ismb-log")):
        assert css in w._dom_classes


def test_the_model_uses_a_recipe_as_it_is(tmp_path):
    from ismb_lab.matching.recipe import Recipe, save_recipe

    recipe = Recipe("NM3", Params(theta_c=9.0, lambda_c=5.0, lambda_s=4.0), "network", one_to_one=True)
    path = save_recipe(tmp_path / "recipe.json", recipe)
    model = DepthModel(IMAGES / "lab", IMAGES / "toy_cars", recipe=path)
    assert (model.method, model.params, model.solver, model.one_to_one) == ("NM3", recipe.params,
                                                                           recipe.solver, True)
    assert model.result.scene.solver == "network" and model.result.scene.one_to_one
    assert model.result.to_dict() == expected(method="NM3", params=recipe.params, solver="network",
                                              one_to_one=True)
    with pytest.raises(TypeError, match="'recipe' parameter of DepthModel"):
        DepthModel(LAB, CARS, recipe=3)
