"""One camera model: points from disparities by the pinhole geometry, and its defaults declared once."""

import re
from pathlib import Path

import cv2
import numpy as np
import pytest

import ismb_lab
from ismb_lab import ParameterError
from ismb_lab.cameras.camera import BASELINE_M, FOCAL_PX, StereoCamera
from ismb_lab.depth.objects import DepthConfig, depth_from_matches
from ismb_lab.images.io import load_pair
from ismb_lab.matching.pipeline import MatchConfig, match, prepare
from ismb_lab.matching.metric import match_points, mutual_best, prepare_for_camera, row_tolerance, subpixel
from ismb_lab.scenes import lab_scene, synthetic_scene, toy_car_scene


def test_the_default_camera_is_the_rendered_scenes_rig(rendered):
    cam = StereoCamera()
    assert (cam.focal_px, cam.baseline_m, cam.size) == (FOCAL_PX, BASELINE_M, (320, 240))
    rig = rendered(synthetic_scene, 0).rig
    assert rig.focal_px == FOCAL_PX and rig.baseline_m == BASELINE_M
    assert cam.right_origin.tolist() == [BASELINE_M, 0.0, 0.0]


def test_points_from_disparity_inverts_the_projection_of_the_rendered_rig():
    rng = np.random.default_rng(5)
    points = np.column_stack([rng.uniform(-0.5, 0.5, 50), rng.uniform(-0.4, 0.4, 50), rng.uniform(0.5, 3, 50)])
    cam = StereoCamera.pinhole(vertical_offset_px=3.0)       # rows differ, disparities do not change
    left, right = cam.project_left(points), cam.project_right(points)
    assert np.allclose(cam.points_from_disparity(left, left[:, 0] - right[:, 0]), points, atol=1e-12)


def test_points_from_disparity_inverts_the_rectified_projection_of_a_distorted_rotated_pair():
    k = np.array([[520.0, 0, 318], [0, 522.0, 242], [0, 0, 1]])
    rotation, _ = cv2.Rodrigues(np.array([0.01, -0.02, 0.005]))
    cam = StereoCamera((640, 480), k, [-0.2, 0.1, 0.001, -0.001, 0.0], k * [[1.01], [1.0], [1.0]],
                       [-0.25, 0.12, 0.0, 0.001, 0.0], rotation, [-0.08, 0.001, 0.002], rms=0.3)
    assert cam.distorted and cam.focal_px != k[0, 0]          # cropped by stereoRectify's alpha=0
    p1, p2 = cam._rectification()["p1"], cam._rectification()["p2"]
    rng = np.random.default_rng(6)
    points = np.column_stack([rng.uniform(-0.2, 0.2, 30), rng.uniform(-0.1, 0.1, 30), rng.uniform(0.3, 2, 30)])
    h = np.hstack([points, np.ones((30, 1))])
    left, right = (h @ p1.T), (h @ p2.T)
    left, right = left[:, :2] / left[:, 2:], right[:, :2] / right[:, 2:]
    assert np.allclose(left[:, 1], right[:, 1])               # rectified: one row
    assert np.allclose(cam.points_from_disparity(left, left[:, 0] - right[:, 0]), points, atol=1e-9)
    # and the raw corners' rectified positions agree with the maps' geometry: a raw point of
    # the left camera lands where P1 puts its 3-D point, rotated into the rectified frame
    raw, _ = cv2.projectPoints(points, np.zeros(3), np.zeros(3), cam.k_left, cam.d_left)
    in_rect = points @ cam.left_to_rectified.T
    expected = in_rect[:, :2] / in_rect[:, 2:] * cam.focal_px + cam.rectified_centre
    assert np.allclose(cam.rectify_points(raw.reshape(-1, 2)), expected, atol=1e-3)


def test_no_positive_disparity_no_point_and_bad_input_is_named():
    cam = StereoCamera()
    out = cam.points_from_disparity([[1.0, 2.0], [3.0, 4.0]], [0.0, -2.0])
    assert np.isnan(out).all()
    with pytest.raises(ParameterError, match="'disparity' parameter of StereoCamera.points_from_disparity"):
        cam.points_from_disparity([[1.0, 2.0]], [1.0, 2.0])
    with pytest.raises(ParameterError, match="'size' parameter of StereoCamera"):
        StereoCamera((0, 240))


def test_the_camera_defaults_are_declared_once():
    package = Path(ismb_lab.__file__).parent
    found = [f"{p.name}:{n}" for p in package.rglob("*.py") if p.name != "camera.py"
             for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
             if re.search(r"(?<![\d.])(300\.0|0\.10)(?![\d])", line) and "ipympl" not in line
             and not line.lstrip().startswith(">>>")]          # a doctest's input is an example, not a default
    assert found == []


@pytest.mark.slow
def test_a_depth_results_points_are_its_kept_matches_in_metres(rendered):
    config = MatchConfig(roi=(40, 40, 240, 160), shift=22.0)
    lab, cars = rendered(lab_scene, 3), rendered(toy_car_scene, 3)
    background, scene = (match(s.left, s.right, config=config) for s in (lab, cars))
    result = depth_from_matches(background, scene, DepthConfig())
    h, w = lab.left.shape
    points = result.points(StereoCamera.pinhole(width=w, height=h, focal_px=FOCAL_PX, baseline_m=BASELINE_M))
    assert len(points) == len(result.kept_xy) > 0
    assert np.allclose(points[:, 2], FOCAL_PX * BASELINE_M / result.kept_disparity)
    assert np.allclose(points[:, 0], (result.kept_xy[:, 0] - (w - 1) / 2) * points[:, 2] / FOCAL_PX)
    with pytest.raises(TypeError, match="camera"):
        result.points(None)


def test_match_points_are_the_scene_points_on_a_rendered_pair(rendered):
    scene = rendered(synthetic_scene, 0)
    result = match(scene.left, scene.right)
    xyz = match_points(result, scene.rig)
    front = np.isfinite(xyz[:, 2])
    assert front.sum() >= len(xyz) - 1 and len(xyz) > 10
    right = scene.rig.project_right(xyz[front])              # the left point and the disparity, exactly
    assert np.allclose(right[:, 0], result.right_match_xy[front, 0], atol=1e-9)
    assert np.allclose(scene.rig.project_left(xyz[front]), result.left_match_xy[front], atol=1e-9)


def test_mutual_best_keeps_only_pairs_that_are_each_others_most_similar(rendered):
    scene = rendered(synthetic_scene, 1)
    prepared = prepare(scene.left, scene.right)
    result = match(prepared=prepared)
    kept = mutual_best(prepared, result)
    problem = prepared.problem
    m = problem.dissimilarity
    for i, k in kept.pairs:
        assert m[i, k] == min(m[i, c] for r, c in zip(problem.rows, problem.cols) if r == i)
        assert m[i, k] == min(m[r, k] for r, c in zip(problem.rows, problem.cols) if c == k)
    assert int(kept.state.sum()) == len(kept.pairs)
    assert row_tolerance(StereoCamera(rms=0.25)) == 1.5
    assert row_tolerance(StereoCamera(rms=0.25), subpixel=True) == 0.5


def test_subpixel_finds_a_saddle_between_the_pixels():
    x0, y0, s = 20.3, 17.7, 16          # the corner, and 16 x 16 samples per pixel (centres on integers)
    yy, xx = np.mgrid[0:40 * s, 0:40 * s]
    xs, ys = (xx + 0.5) / s - 0.5, (yy + 0.5) / s - 0.5
    image = 20 + 200 * ((xs - x0) * (ys - y0) > 0).reshape(40, s, 40, s).mean(axis=(1, 3))
    found = subpixel(image, np.array([[21.0, 18.0], [19.0, 17.0]]), 5)
    assert np.abs(found - [x0, y0]).max() < 0.1
    assert subpixel(image, np.zeros((0, 2)), 5).shape == (0, 2)


def test_prepare_for_camera_refines_the_geometry_and_keeps_the_whole_pixel_similarity(rendered):
    scene = rendered(synthetic_scene, 2)
    camera = StereoCamera(rms=0.3)
    prepared = prepare_for_camera(load_pair(scene.left, scene.right), MatchConfig(), camera)
    plain = prepare(prepared.pair, None, MatchConfig(window_height=prepared.config.window_height))
    assert prepared.config.window_height == pytest.approx(4 * 0.3)
    assert np.array_equal(prepared.problem.dissimilarity, plain.problem.dissimilarity)
    half = MatchConfig().patch_size // 2
    assert np.array_equal(prepared.problem.left_xy, subpixel(prepared.pair.left, plain.left_corners.xy, half))
    assert np.array_equal(prepared.problem.right_xy, subpixel(prepared.pair.right, plain.right_corners.xy, half))
    problem = prepared.problem
    dy = np.abs(problem.left_xy[problem.rows, 1] - problem.right_xy[problem.cols, 1])
    assert dy.max() <= 2 * 0.3
    with pytest.raises(TypeError, match="camera"):
        prepare_for_camera(prepared.pair, MatchConfig(), "rig.json")
