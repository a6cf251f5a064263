"""The 3-D point cloud: its points from theory, its model and its view's callbacks (no browser)."""

from pathlib import Path

import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.camera import StereoCamera
from ismb_lab.widgets import DepthDemo, DepthModel
from ismb_lab.widgets.cloud import (MAX_NOTES, Cloud, PointCloudView, _cloud, board_cloud, depth_cloud,
                                    frustum_edges, match_cloud)

IMAGES = Path(__file__).resolve().parents[2] / "images"


def test_matches_in_3d_project_back_onto_their_pixels(rendered):
    """The cloud's points, seen again by the camera that placed them, fall on the matched pixels:
    on the left one exactly, and on the right one's column (the pinhole pair shares rows)."""
    from ismb_lab.matching import match
    from ismb_lab.scenes import synthetic_scene

    scene = rendered(synthetic_scene, 0)
    result = match(scene.left, scene.right)
    h, w = scene.left.shape
    camera = StereoCamera.pinhole(width=w, height=h, focal_px=250.0, baseline_m=0.12)
    cloud = match_cloud(result, camera)
    d = result.left_match_xy[:, 0] - result.right_match_xy[:, 0]
    assert (d > 0).all() and len(cloud.points) == len(result.pairs) > 10
    np.testing.assert_allclose(cloud.points[:, 2], 250.0 * 0.12 / d, rtol=1e-12)
    np.testing.assert_allclose(camera.project_left(cloud.points), result.left_match_xy, atol=1e-9)
    np.testing.assert_allclose(camera.project_right(cloud.points)[:, 0], result.right_match_xy[:, 0], atol=1e-9)
    np.testing.assert_allclose(cloud.centres, [[0, 0, 0], [0.12, 0, 0]])
    assert "the network's" in cloud.caption and "f = 250.0 px, B = 12.00 cm" in cloud.caption


def test_the_drawn_cameras_see_the_image_corners_at_0_6_baselines():
    camera = StereoCamera.pinhole(width=320, height=240, focal_px=300.0, baseline_m=0.1)
    cloud = _cloud(camera, np.zeros((0, 3)), [], "")
    np.testing.assert_allclose(cloud.frustum[:, 2], 0.06, rtol=1e-12)
    np.testing.assert_allclose(camera.project_left(cloud.frustum), [[0, 0], [319, 0], [319, 239], [0, 239]],
                               atol=1e-9)


def test_a_point_without_a_positive_disparity_has_no_place():
    camera = StereoCamera.pinhole(width=61, height=61, focal_px=300.0, baseline_m=0.1)   # centre (30, 30)
    points = camera.points_from_disparity([[10, 10], [20, 20], [60, 60]], [0.0, -2.0, 6.0])
    cloud = _cloud(camera, points, [("behind", (5, 5), -1.0), ("front", (60, 60), 6.0)], "c")
    # Z = 300 * 0.1 / 6 = 5, X = Y = (60 - 30) Z / 300
    np.testing.assert_allclose(cloud.points, [[0.5, 0.5, 5.0]], rtol=1e-12)
    assert cloud.caption == "c; 2 match(es) with disparity <= 0 left out"
    assert [text for text, _ in cloud.notes] == ["front"] and cloud.notes[0][1] == pytest.approx((0.5, 0.5, 5.0))


def test_frustums_have_their_apex_at_each_centre():
    corners = [[-1, -1, 2], [1, -1, 2], [1, 1, 2], [-1, 1, 2]]
    vertices, segments = frustum_edges([[0, 0, 0], [0.1, 0, 0]], corners)
    assert vertices.dtype == np.float32 and segments.dtype == np.uint32
    np.testing.assert_allclose(vertices[[0, 5]], [[0, 0, 0], [0.1, 0, 0]], atol=1e-7)
    np.testing.assert_allclose(vertices[6:10] - vertices[5], corners, atol=1e-6)
    # each camera: 4 edges from the apex, 4 around the base, each base vertex on 3 edges
    for k in range(2):
        own = segments[8 * k: 8 * k + 8] - 5 * k
        assert (own >= 0).all() and (own < 5).all()
        assert np.bincount(own.ravel(), minlength=5).tolist() == [4, 3, 3, 3, 3]


def test_a_bad_cloud_is_refused_naming_the_parameter():
    ok = dict(points=[[0, 0, 1.0]], centres=[[0, 0, 0], [0.1, 0, 0]], frustum=np.ones((4, 3)))
    with pytest.raises(ParameterError, match="'points' parameter of Cloud"):
        Cloud(**{**ok, "points": [[0, 0]]})
    with pytest.raises(ParameterError, match="'points' parameter of Cloud must be finite numbers"):
        Cloud(**{**ok, "points": [[0, 0, np.nan]]})
    with pytest.raises(ParameterError, match="'centres' parameter of Cloud"):
        Cloud(**{**ok, "centres": [[0, 0, 0]]})
    with pytest.raises(ParameterError, match="'colour' parameter of Cloud"):
        Cloud(**ok, colour=[1.0, 2.0])
    with pytest.raises(ParameterError, match="'notes' parameter of Cloud"):
        Cloud(**ok, notes=(("a", (0, 0, 1)),) * (MAX_NOTES + 1))
    with pytest.raises(ParameterTypeError, match="'cloud' parameter of PointCloudView"):
        PointCloudView([[0, 0, 1.0]])


@pytest.fixture(scope="module")
def model():
    return DepthModel(IMAGES / "lab", IMAGES / "toy_cars")


def test_the_demo_cloud_holds_its_matches_at_f_b_over_d(model):
    cloud, r, cfg = depth_cloud(model), model.result, model.config
    d = np.concatenate([r.background.horizontal_disparity, r.kept_disparity])
    assert len(cloud.points) == int((d > 0).sum()) > 20
    np.testing.assert_allclose(cloud.points[:, 2], cfg.focal_px * cfg.baseline_m / d[d > 0], rtol=1e-12)
    # the principal point is the image centre, as the rendered rig's
    h, w = model.scene.left.shape
    xy = np.vstack([r.background.left_match_xy, r.kept_xy])[d > 0]
    np.testing.assert_allclose(cloud.points[:, :2], (xy - [(w - 1) / 2, (h - 1) / 2]) * cloud.points[:, 2:] / cfg.focal_px,
                               rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(cloud.colour, cloud.points[:, 2])
    np.testing.assert_allclose(cloud.centres, [[0, 0, 0], [cfg.baseline_m, 0, 0]])
    assert [text for text, _ in cloud.notes] == [f"#{o.rank} {o.depth_m:.2f} m" for o in r.objects]
    for (_, xyz), o in zip(cloud.notes, r.objects):
        assert xyz[2] == pytest.approx(o.depth_m)
    assert "f = 300 px and B = 0.1 m" in cloud.caption


def test_the_view_shows_the_cloud_it_was_given(model):
    cloud = depth_cloud(model)
    view = PointCloudView(cloud)
    shown = view.points.positions
    np.testing.assert_allclose(shown, np.column_stack([cloud.points[:, 0], cloud.points[:, 2], -cloud.points[:, 1]]),
                               rtol=1e-6)
    np.testing.assert_allclose(view.points.attribute, cloud.colour, rtol=1e-6)
    assert list(view.points.color_range) == pytest.approx(cloud.depth_range, rel=1e-6)
    assert [t.text for t in view.notes if t.visible] == [text for text, _ in cloud.notes]
    assert "width" in view.widget.layout.keys and view.widget.layout.width == "100%"
    assert "ismb-cloud" in view.widget._dom_classes


def test_a_seed_change_updates_the_same_objects():
    demo = DepthDemo.from_folders(IMAGES / "lab", IMAGES / "toy_cars", background_name="the box")
    view = demo.cloud
    objects = [id(o) for o in view.plot.objects]
    points, cameras = view.points, view.cameras
    before = np.array(view.points.positions)
    demo.seed_field.value = 7                  # fires the observer: recompute and refresh
    assert demo.errors == [] and demo.model.seed == 7
    assert [id(o) for o in view.plot.objects] == objects
    assert view.points is points and view.cameras is cameras
    expected = depth_cloud(demo.model)
    np.testing.assert_allclose(view.points.positions,
                               np.column_stack([expected.points[:, 0], expected.points[:, 2], -expected.points[:, 1]]),
                               rtol=1e-6)
    # the annealed demo gives the same matches for seeds 0 and 7; Method-I gives others (62 points, not 51)
    np.testing.assert_array_equal(view.points.positions, before)
    demo.method_menu.value = "I"
    assert demo.errors == [] and [id(o) for o in view.plot.objects] == objects and view.points is points
    expected = depth_cloud(demo.model)
    assert len(view.points.positions) == len(expected.points) != len(before)
    np.testing.assert_allclose(view.points.attribute, expected.colour, rtol=1e-6)
    assert view.caption.value == f"<small>{expected.caption}</small>"


def test_an_empty_cloud_hides_the_points_without_a_new_object(model):
    view = PointCloudView(depth_cloud(model))
    points = view.points
    cloud = depth_cloud(model)
    view.update(Cloud(np.zeros((0, 3)), cloud.centres, cloud.frustum))
    assert view.points is points and not view.points.visible
    view.update(cloud)
    assert view.points.visible and len(view.points.positions) == len(cloud.points)


def test_the_board_cloud_lies_at_the_board_depth(opencv_data):
    from ismb_lab.datasets import chessboard_pairs
    from ismb_lab.rig import board_depth, calibrate_rig

    pairs = chessboard_pairs()
    rig = calibrate_rig([p for p in pairs if p[0] != "14"])
    _, left, right = [p for p in pairs if p[0] == "14"][0]
    cloud = board_cloud(rig, rig.rectify(left, right))
    assert len(cloud.points) == rig.board[0] * rig.board[1]
    assert np.median(cloud.points[:, 2]) == pytest.approx(board_depth(rig, left, right)["stereo"], rel=1e-12)
    # the board is flat: its corners lie within 2 mm of their best plane
    centred = cloud.points - cloud.points.mean(axis=0)
    assert np.linalg.svd(centred, compute_uv=False)[-1] / np.sqrt(len(centred)) < 0.002
    # neighbouring corners one square apart (25 mm, rig.square_m), to within 5%
    step = np.linalg.norm(np.diff(cloud.points.reshape(rig.board[1], rig.board[0], 3), axis=1), axis=2)
    assert np.median(step) == pytest.approx(rig.square_m, rel=0.05)


def test_the_networks_matches_of_a_held_out_pair_are_placed_by_the_rig(opencv_data):
    """The path of ``ismb-lab match --rig`` (as notebook 09 takes it) on held-out pair 14: the
    cloud holds the matches' points in metres, most of them at the board's depths (the board
    fills part of the photo; the room behind it is farther), and the note gives the board's own
    depth from its corners."""
    from ismb_lab.datasets import chessboard_pairs
    from ismb_lab.io import load_pair
    from ismb_lab.matching import MatchConfig
    from ismb_lab.metric import for_camera, match_points, match_with_camera
    from ismb_lab.rig import board_depth, calibrate_rig

    pairs = chessboard_pairs()
    rig = calibrate_rig([p for p in pairs if p[0] != "14"])
    _, raw_left, raw_right = [p for p in pairs if p[0] == "14"][0]
    left, right, how = for_camera(raw_left, raw_right, rig)
    assert "rectified with the rig" in how
    config = MatchConfig(roi="full", shift="auto", n_min=150, n_max=200)
    pair = load_pair(left, right, min_shape=config.min_shape)
    _, _, result = match_with_camera(pair, config, rig)
    rectified = rig.rectify(raw_left, raw_right)
    cloud = match_cloud(result, rig, board=rectified)
    xyz = match_points(result, rig)
    np.testing.assert_array_equal(cloud.points, xyz[np.isfinite(xyz).all(axis=1)])
    assert len(cloud.points) >= 20
    corners = board_cloud(rig, rectified).points[:, 2]
    z = cloud.points[:, 2]
    assert np.mean((z >= 0.95 * corners.min()) & (z <= 1.05 * corners.max())) > 0.5
    (text, at), = cloud.notes
    assert text.startswith("board's corners (cv2)")
    assert at[2] == pytest.approx(board_depth(rig, raw_left, raw_right)["stereo"], rel=1e-3)
