"""The 3-D point cloud: its points from theory, its model and its view's callbacks (no browser)."""

from pathlib import Path

import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.cameras.camera import StereoCamera
from ismb_lab.widgets import DepthDemo, DepthModel
from ismb_lab.widgets.cloud import (MAX_NOTES, Cloud, PointCloudView, _cloud, board_cloud, depth_cloud,
                                    frustum_edges, match_cloud)

IMAGES = Path(__file__).resolve().parents[2] / "images"


def test_matches_in_3d_project_back_onto_their_pixels(rendered):
    """The cloud's points, seen again by the camera that placed them, fall on the matched pixels:
    on the left one exactly, and on the right one's column (the pinhole pair shares rows)."""
    from ismb_lab.matching.pipeline import match
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
    from ismb_lab.images.datasets import chessboard_pairs
    from ismb_lab.cameras.rig import board_depth, calibrate_rig

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


@pytest.mark.slow
def test_the_networks_matches_of_a_held_out_pair_are_placed_by_the_rig(opencv_data):
    """The path of ``ismb-lab match --rig`` (as notebook 09 takes it) on held-out pair 14: the
    cloud holds the matches' points in metres, most of them at the board's depths (the board
    fills part of the photo; the room behind it is farther), and the note gives the board's own
    depth from its corners."""
    from ismb_lab.images.datasets import chessboard_pairs
    from ismb_lab.images.io import load_pair
    from ismb_lab.matching.pipeline import MatchConfig
    from ismb_lab.matching.metric import for_camera, match_points, match_with_camera
    from ismb_lab.cameras.rig import board_depth, calibrate_rig

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


# --- any rig's pair: RigCloud, its model, and SGBM beside the network ----------------------------

def _upload(loader, named):
    """Files given to the loader's upload control as a browser gives them: ``[(name, bytes), ...]``."""
    import datetime

    loader.upload.value = tuple({"name": name, "type": "image/png", "size": len(data), "content": memoryview(data),
                                 "last_modified": datetime.datetime.now(datetime.timezone.utc)}
                                for name, data in named)


def _png(image) -> bytes:
    import cv2

    ok, data = cv2.imencode(".png", np.clip(np.rint(image), 0, 255).astype(np.uint8))
    assert ok
    return data.tobytes()


def test_sgbm_agrees_with_the_truth_and_its_agreement_with_the_network_is_counted_right(rendered):
    """On a rendered pair whose true disparity is known: SGBM, run in the window the network's
    pair measured, is right at the network's matched points; and a match where both are within
    0.5 px of the truth counts as agreeing, one where only one of them is right as not."""
    from ismb_lab.matching.dense import agreement, window_range
    from ismb_lab.scenes import synthetic_scene
    from ismb_lab.widgets.rig_cloud import RigCloudModel

    scene = rendered(synthetic_scene, 0)
    model = RigCloudModel(scene.rig)
    model.load(scene.left, scene.right, "scene 0")
    assert model.refused == "" and "already rectified" in model.how
    kept = model.result
    xy, d = kept.left_match_xy, kept.left_match_xy[:, 0] - kept.right_match_xy[:, 0]
    assert len(d) >= 10
    at = lambda image: image[np.rint(xy[:, 1]).astype(int), np.rint(xy[:, 0]).astype(int)]  # noqa: E731
    truth, dense = at(scene.disparity), at(model.dense)
    # the window holds the true disparities of the matched points, and SGBM searched it
    lo, hi = window_range(model.prepared.config)
    known = np.isfinite(truth)
    assert known.sum() >= 0.9 * len(d) and ((truth[known] >= lo) & (truth[known] <= hi)).all()
    both = known & np.isfinite(dense)
    assert both.sum() >= 0.8 * len(d)
    assert np.mean(np.abs(dense[both] - truth[both]) <= np.maximum(1.0, 0.05 * truth[both])) >= 0.9
    # the agreement, as counted: each match on its own, against the truth
    a = model.agreement
    assert (a.matches, a.measured) == (len(d), int(np.isfinite(dense).sum()))
    right = lambda values: np.isfinite(values) & known & (np.abs(values - truth) <= 0.5)  # noqa: E731
    assert a.agree >= int((right(dense) & right(np.asarray(d))).sum()) > 0
    far = np.isfinite(dense) & (np.abs(dense - d) > np.maximum(1.0, 0.05 * d))
    assert a.agree == int(np.isfinite(dense).sum() - far.sum())
    # the truth itself, as the "dense" map, agrees with every network match the truth says is right
    truth_agrees = agreement(scene.disparity, xy, d)
    assert truth_agrees.agree == int((known & (np.abs(truth - d) <= np.maximum(1.0, 0.05 * d))).sum())
    assert str(a) in model.message and f"{a.agree} of {a.measured}" in model.message
    # SGBM's points in metres through the same rig: back on their pixels, at Z = f B / d
    from ismb_lab.matching.dense import dense_points

    xyz, pixels = dense_points(scene.rig, model.dense)
    np.testing.assert_allclose(scene.rig.project_left(xyz), pixels, atol=1e-6)
    np.testing.assert_allclose(xyz, model.dense_xyz)
    assert 0 < len(xyz) <= 20_000


def test_sgbm_finds_a_known_shift_within_its_range():
    import cv2

    from ismb_lab.matching.dense import sgbm_disparity, sgbm_range

    rng = np.random.default_rng(1)
    texture = cv2.GaussianBlur(rng.uniform(0, 255, (120, 400)), (0, 0), 1.2) * 3 % 255
    d = sgbm_disparity(texture[:, :-37], texture[:, 37:], 30, 45)
    found = d[np.isfinite(d)]
    assert len(found) > 0.5 * d.size and np.mean(np.abs(found - 37) <= 0.25) > 0.95
    # searched outside the range, the shift is not found: the range is what SGBM looks at
    assert not np.any(np.abs(sgbm_disparity(texture[:, :-37], texture[:, 37:], 0, 15) - 37) < 1)
    assert sgbm_range(30, 45) == (30, 16) and sgbm_range(19.96, 163.92) == (19, 160)
    with pytest.raises(ParameterError, match="'block' parameter of sgbm_disparity"):
        sgbm_disparity(texture, texture, 0, 16, block=4)


def test_a_pair_the_rig_does_not_fit_shows_one_line_and_no_cloud(rendered):
    from ismb_lab.scenes import synthetic_scene
    from ismb_lab.widgets.rig_cloud import RigCloud

    scene = rendered(synthetic_scene, 0)
    widget = RigCloud(scene.rig, scene.left, scene.right, name="scene 0")
    view = widget.view
    objects = [id(o) for o in view.plot.objects]
    assert widget.errors == [] and view.points.visible and widget.model.cloud is not None
    widget.dense_toggle.value = True
    assert view.dense.visible
    widget.load(scene.right, scene.left, "swapped")           # the two files swapped
    assert widget.errors == [] and widget.model.cloud is None and widget.model.refused
    status = widget.status.value
    assert "swapped refused: The 'left' parameter of for_camera" in status and "swap the two files" in status
    assert "\n" not in status and "<br" not in status
    assert not view.points.visible and not view.dense.visible and widget.dense_toggle.disabled
    assert view.caption.value == "<small></small>"
    assert not view.axes.visible and not any(t.visible for t in view.axis_texts)
    assert [id(o) for o in view.plot.objects] == objects       # the same objects, nothing new
    widget.load(scene.left, scene.right, "again")             # the right order shows it again
    assert view.points.visible and view.dense.visible and not widget.dense_toggle.disabled and view.axes.visible
    assert len(view.points.positions) == len(widget.model.cloud.points)


def test_the_toggle_shows_sgbm_points_in_the_same_colours(rendered):
    from ismb_lab.scenes import synthetic_scene
    from ismb_lab.widgets.rig_cloud import RigCloud

    scene = rendered(synthetic_scene, 0)
    widget = RigCloud(scene.rig, scene.left, scene.right)
    view, model = widget.view, widget.model
    assert not view.dense.visible                              # the network first
    widget.dense_toggle.value = True
    assert view.dense.visible and widget.errors == []
    shown = view.dense.positions
    np.testing.assert_allclose(shown, np.column_stack([model.dense_xyz[:, 0], model.dense_xyz[:, 2],
                                                       -model.dense_xyz[:, 1]]), rtol=1e-6)
    np.testing.assert_allclose(view.dense.attribute, model.dense_xyz[:, 2], rtol=1e-6)
    # one colour scale: from the nearest to the farthest point of either set, in both objects
    z = np.concatenate([model.cloud.points[:, 2], model.dense_xyz[:, 2]])
    assert list(view.points.color_range) == list(view.dense.color_range) == pytest.approx([z.min(), z.max()])
    assert f"{z.min():.2f} m" in view.colours.value and f"{z.max():.2f} m" in view.colours.value
    widget.dense_toggle.value = False
    assert not view.dense.visible


def test_each_axis_is_titled_once_and_no_colour_bar_sits_in_the_canvas(rendered):
    from ismb_lab.scenes import synthetic_scene
    from ismb_lab.widgets.cloud import AXIS_TITLES
    from ismb_lab.widgets.rig_cloud import RigCloud

    scene = rendered(synthetic_scene, 0)
    view = RigCloud(scene.rig, scene.left, scene.right).view
    # k3d's grid (each title on two edges) is off, and its colour bar, drawn for the object
    # colorbar_object_id names, is given one without colours: none is drawn in the canvas
    assert not view.plot.grid_visible and view.plot.colorbar_object_id == view.cameras.id
    assert view.cameras.attribute.size == 0 and len(view.cameras.color_range) == 0   # k3d draws a bar for [lo, hi]
    shown = [t.text for t in view.axis_texts if t.visible]
    assert [shown.count(title) for title in AXIS_TITLES] == [1, 1, 1]
    # the axes span what is drawn: the numbers of each axis lie within its points' range
    every = np.vstack([view.points.positions, view.dense.positions, view.cameras.vertices])
    numbers, axis = {0: [], 1: [], 2: []}, 0
    for text in shown:
        if text in AXIS_TITLES:
            axis += 1
        else:
            numbers[axis].append(float(text))
    for k in range(3):
        assert len(numbers[k]) >= 2
        assert every[:, k].min() - 1e-6 <= min(numbers[k]) and max(numbers[k]) <= every[:, k].max() + 1e-6
    assert view.widget.children.index(view.colours) < view.widget.children.index(view.plot)


def test_an_upload_and_a_rig_file_reach_the_model(rendered, tmp_path):
    """Photos uploaded through the loader (named, in either order) are matched with the rig as
    given; a rig file typed in the field replaces the rig and the pair is matched again."""
    from ismb_lab.scenes import synthetic_scene
    from ismb_lab.widgets.rig_cloud import RigCloud

    scene = rendered(synthetic_scene, 0)
    widget = RigCloud()
    assert widget.model is None and "Load rig" in widget.status.value
    rig = tmp_path / "rig.json"
    rig.write_text(scene.rig.to_json())
    widget.rig_field.value = str(rig)
    widget.rig_button.click()
    assert widget.errors == [] and widget.model.camera.focal_px == scene.rig.focal_px
    assert "rig rig.json" in widget.status.value
    _upload(widget.loader, [("right.png", _png(scene.right)), ("left.png", _png(scene.left))])
    assert widget.errors == [] and widget.loader.errors == []
    assert widget.model.cloud is not None and "right.png" not in widget.status.value
    assert widget.status.value.startswith("left: already rectified")
    assert widget.view.points.visible and len(widget.view.points.positions) == len(widget.model.cloud.points)
    before = widget.model.cloud.points
    other = tmp_path / "wide.json"
    other.write_text(StereoCamera.pinhole(width=320, height=240, focal_px=300.0, baseline_m=0.2).to_json())
    widget.rig_field.value = str(other)
    widget.rig_button.click()                                  # the same pair, twice the baseline
    assert widget.errors == [] and widget.model.cloud is not None
    np.testing.assert_allclose(np.median(widget.model.cloud.points[:, 2]), 2 * np.median(before[:, 2]), rtol=1e-9)
    widget.rig_field.value = str(tmp_path / "missing.json")
    widget.rig_button.click()
    assert len(widget.errors) == 1 and "'source' parameter of load_camera" in widget.status.value
