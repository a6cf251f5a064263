"""Relative and metric depth (§5.2.3) on the committed toy-car scene and rendered variants."""

import json
import math

import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.depth.objects import DepthConfig, depth_from_matches, metric_depth
from ismb_lab.depth.pipeline import (
    DEPTH_MATCH_CONFIG,
    DEPTH_PARAMS,
    changed_roi,
    depth_match,
    depth_pairs,
    load_stereo,
    pair_silhouettes,
    relative_depth,
    scene_match_config,
)
from ismb_lab.images.features import resolve_roi
from ismb_lab.images.io import load_pair
from ismb_lab.matching.pipeline import match, prepare
from ismb_lab.scenes import lab_scene, toy_car_scene
from ismb_lab.depth.outlines import Silhouettes

IMAGES = __import__("pathlib").Path(__file__).resolve().parent.parent / "images"


def on_car(scene, car, obj):
    """Does the object's centroid lie on the car's image (its bounding box, 3 px margin)?"""
    lo = scene.rig.project_left([[car.lo[0], car.lo[1], car.lo[2]]])[0]
    hi = scene.rig.project_left([[car.hi[0], car.hi[1], car.lo[2]]])[0]
    x, y = obj.centroid_xy
    return lo[0] - 3 <= x <= hi[0] + 3 and lo[1] - 3 <= y <= hi[1] + 3


def car_objects(scene, result):
    return [[o for o in result.objects if on_car(scene, car, o)] for car in scene.primitives[3:]]


@pytest.fixture(scope="module")
def committed():
    scene = toy_car_scene(0)
    paths = [IMAGES / "lab" / n for n in ("left.png", "right.png")], \
        [IMAGES / "toy_cars" / n for n in ("left.png", "right.png")]
    return scene, relative_depth(tuple(paths[0]), tuple(paths[1]))


def test_committed_scene_left_car_nearer_both_in_front_of_the_box(committed):
    scene, result = committed
    left, right = car_objects(scene, result)
    assert left and right
    assert min(o.rank for o in left) < min(o.rank for o in right)
    box_z = scene.primitives[2].lo[2]
    # The object that ranks each car (its nearest) stands in front of the box.
    assert all(min(objs, key=lambda o: o.rank).depth_m < box_z for objs in (left, right))
    ranks = [o.rank for o in result.objects]
    assert ranks == list(range(1, len(ranks) + 1))
    assert [o.mean_disparity for o in result.objects] == sorted(
        (o.mean_disparity for o in result.objects), reverse=True)
    assert result.background_removed >= 5


def test_committed_scene_has_no_spurious_objects(committed):
    """Exactly one object per car: nothing at wall disparity, no second object on a car."""
    scene, result = committed
    assert [len(objs) for objs in car_objects(scene, result)] == [1, 1]
    assert len(result.objects) == 2


def test_committed_scene_metric_depth_of_each_car_within_ten_percent(committed):
    scene, result = committed
    for car, objs in zip(scene.primitives[3:], car_objects(scene, result)):
        truth = car.parts[0].lo[2]
        best = min(abs(o.depth_m - truth) / truth for o in objs)
        assert best <= 0.10, (car.name, [o.depth_m for o in objs], truth)
        good = [o for o in objs if abs(o.depth_m - truth) / truth <= 0.10]
        # The quantisation error bar is honest: it holds the truth within one more pixel.
        assert any(metric_depth(o.mean_disparity + 1).z <= truth <= metric_depth(o.mean_disparity - 1).z
                   for o in good)


# Car layouts of the variants: drawn from their own seeds, never used to fit anything
# (DEPTH_PARAMS come from images/lab alone; the layouts 100-139 served for development).
# The first 20 were checked once with the thesis' ROI for the scene (19 right; in 48274
# the far car had a single correct match) and again after the change box of
# ismb_lab.depth.pipeline.changed_roi was chosen on the development layouts; the second 20 were
# drawn after that choice and checked once.  Measured with the demo's defaults: 40 of 40
# right here (supersample 1); rendered at the committed images' supersample 2, 39 of 40
# (in 35318 the near car, 1.00 m against 1.15 m, kept no object).
VARIANTS = (np.random.default_rng(5213).integers(1000, 10 ** 6, size=20).tolist()
            + np.random.default_rng(20261123).integers(1000, 10 ** 6, size=20).tolist())


@pytest.mark.slow
def test_ranking_on_rendered_variants():
    """Measured, not tuned: the demo's defaults on 40 random car layouts, left car nearer."""
    background = lab_scene(0, supersample=1)
    bg = depth_match(background)
    wrong = []
    for cars in VARIANTS:
        scene = toy_car_scene(0, cars=cars, supersample=1)
        result = depth_from_matches(bg, depth_match(scene, background=background))
        left, right = car_objects(scene, result)
        if not (left and right and min(o.rank for o in left) < min(o.rank for o in right)):
            wrong.append(cars)
    assert wrong == []


def test_changed_roi_boxes_what_changed_inside_the_roi():
    bg = np.full((240, 320), 100.0)
    scene = bg.copy()
    scene[100:120, 150:190] = 150.0
    x, y, w, h = changed_roi(bg, scene)
    assert x <= 150 and y <= 100 and x + w >= 190 and y + h >= 120
    assert w < 60 and h < 40
    assert changed_roi(bg, bg + 3.0) is None          # below the threshold: camera noise
    assert changed_roi(bg, bg + 30.0) == resolve_roi("center", bg.shape)   # new lighting
    outside = bg.copy()
    outside[:20, :20] = 250.0
    assert changed_roi(bg, outside) is None and changed_roi(bg, outside, "full") is not None


@pytest.mark.slow
def test_scene_corners_are_sought_where_the_cars_are(committed):
    background, scene = (load_pair(s.left, s.right) for s in (lab_scene(0), toy_car_scene(0)))
    assert scene_match_config(background, background) is DEPTH_MATCH_CONFIG
    box = scene_match_config(background, scene).roi
    assert committed[1].scene_roi == box
    corners = committed[1].scene.left_xy
    assert np.all((corners >= box[:2]) & (corners < np.add(box[:2], box[2:])))
    x, y, w, h = box
    cx, cy, cw, ch = resolve_roi(DEPTH_MATCH_CONFIG.roi, scene.shape)
    assert cx <= x and cy <= y and x + w <= cx + cw and y + h <= cy + ch and w * h < cw * ch / 2
    for car in toy_car_scene(0).primitives[3:]:
        (x0, y0), (x1, y1) = toy_car_scene(0).rig.project_left([car.lo, car.hi])
        assert x <= min(x0, x1) and max(x0, x1) <= x + w


def test_network_solver_is_the_plain_match_and_annealing_ends_at_a_fixed_point():
    scene = lab_scene(0, supersample=1)
    plain = match(scene.left, scene.right, params=DEPTH_PARAMS, config=DEPTH_MATCH_CONFIG, seed=1)
    network = depth_match(scene, solver="network", seed=1)
    annealed = depth_match(scene, seed=1)
    assert np.array_equal(network.pairs, plain.pairs) and network.stop_rule == plain.stop_rule
    assert annealed.solver == "anneal" and annealed.stop_rule == "sweep" and len(annealed.pairs)
    assert np.array_equal(annealed.left_xy, plain.left_xy)
    problem = prepare(scene.left, scene.right, DEPTH_MATCH_CONFIG).problem
    candidates = set(zip(problem.rows.tolist(), problem.cols.tolist()))
    assert all(tuple(p) in candidates for p in annealed.pairs.tolist())
    assert annealed.pairs[:, 0].tolist() == sorted(annealed.pairs[:, 0].tolist())


def test_metric_depth_never_divides_by_zero():
    assert metric_depth(0.0).status == "at infinity" and metric_depth(0.0).z is None
    assert metric_depth(-3.0).status == "invalid"
    d = metric_depth(15.0, focal_px=600, baseline_m=0.05, error_px=0.5)
    assert d.z == pytest.approx(2.0) and d.near < 2.0 < d.far
    assert math.isinf(metric_depth(0.5).far)


def test_identical_scene_and_background_give_no_objects():
    scene = lab_scene(0, supersample=1)
    m = match(scene.left, scene.right)
    result = depth_from_matches(m, m)
    assert result.objects == () and "no objects" in result.message
    assert result.background_removed == len(np.unique(m.pairs[:, 0]))


def test_to_dict_is_the_json_contract(committed):
    _, result = committed
    data = json.loads(json.dumps(result.to_dict()))
    assert data["background_removed"] == result.background_removed
    for obj, o in zip(data["objects"], result.objects):
        assert obj["centroid_xy"] == list(o.centroid_xy) and obj["depth_m"] == o.depth_m
        assert obj["mean_disparity"] == o.mean_disparity and len(obj["features"]) == len(o.features)


@pytest.mark.parametrize("make, name, error", [
    (lambda: DepthConfig(focal_px=-1), "focal_px", ValueError),
    (lambda: DepthConfig(baseline_m=0), "baseline_m", ValueError),
    (lambda: DepthConfig(min_features=0), "min_features", ValueError),
    (lambda: DepthConfig(outline={"pad_px": 4}), "outline", TypeError),
    (lambda: pair_silhouettes(None), "prepared", TypeError),
    (lambda: pair_silhouettes(("a", "b")), "prepared", TypeError),
    (lambda: relative_depth((np.zeros((60, 80)),) * 2, (np.zeros((60, 80)),) * 2, config=DepthConfig(grouping="features"),
                            silhouettes=Silhouettes(np.zeros((60, 80), dtype=int), [], [], np.zeros((0, 2)))),
     "silhouettes", ValueError),
    (lambda: relative_depth(IMAGES, IMAGES / "toy_cars"), "background", ValueError),
    (lambda: metric_depth(1.0, focal_px=0), "focal_px", ValueError),
    (lambda: depth_from_matches(None, None), "background", TypeError),
    (lambda: relative_depth(5, (np.zeros((60, 80)),) * 2), "background", TypeError),
    (lambda: depth_match((np.zeros((60, 80)),) * 2, solver="magic"), "solver", ValueError),
    (lambda: depth_match(7), "pair", TypeError),
    (lambda: relative_depth((np.zeros((60, 80)),) * 2, (np.zeros((50, 80)),) * 2), "scene", ValueError),
    (lambda: changed_roi(np.zeros((60, 80)), np.zeros((50, 80))), "scene_left", ValueError),
    (lambda: changed_roi(np.zeros((60, 80)), np.zeros((60, 80)), threshold=-1), "threshold", ValueError),
    (lambda: scene_match_config(np.zeros((60, 80)), None), "background", TypeError),
    (lambda: depth_match((np.zeros((60, 80)),) * 2, background=(np.zeros((50, 80)),) * 2), "scene",
     ValueError),
    (lambda: depth_match((np.zeros((60, 80)),) * 2, match_config="center"), "match_config", TypeError),
])
def test_bad_input_names_the_parameter(make, name, error):
    error = {ValueError: ParameterError, TypeError: ParameterTypeError}[error]
    with pytest.raises(error, match=rf"^The '{name}' parameter of \w[\w.]* must be .* Got .* instead\.$"):
        make()


def test_pairs_prepared_once_give_what_preparing_them_each_time_gives(committed):
    _, fresh = committed
    lab = tuple(IMAGES / "lab" / n for n in ("left.png", "right.png"))
    cars = tuple(IMAGES / "toy_cars" / n for n in ("left.png", "right.png"))
    prepared = depth_pairs(lab, cars)
    assert relative_depth(lab, cars, prepared=prepared).to_dict() == fresh.to_dict()
    for seed, method in ((3, "III"), (1, "II")):
        assert (relative_depth(lab, cars, seed=seed, method=method, prepared=prepared).to_dict()
                == relative_depth(lab, cars, seed=seed, method=method).to_dict())
    with pytest.raises(ParameterTypeError, match="'prepared' parameter of relative_depth"):
        relative_depth(lab, cars, prepared=prepared[:1])


def test_one_loader_takes_a_folder_a_pair_of_files_and_a_scene():
    files = load_pair(IMAGES / "lab" / "left.png", IMAGES / "lab" / "right.png")
    for value in (IMAGES / "lab", str(IMAGES / "lab"), (IMAGES / "lab" / "left.png", IMAGES / "lab" / "right.png"),
                  files):
        pair = load_stereo(value, "background", "test")
        assert np.array_equal(pair.left, files.left) and np.array_equal(pair.right, files.right)
    scene = lab_scene(0, supersample=1)
    assert np.array_equal(load_stereo(scene, "background", "test").left, load_pair(scene.left, scene.right).left)
