"""Photos of one's own in the widgets: upload, check, rectify, ROI, use; without a browser."""

import datetime
import json

import numpy as np
import pytest
from matplotlib.backend_bases import MouseEvent

from ismb_lab.images.io import image_sha256
from ismb_lab.widgets import ParameterExplorer, PhotoLoader, TargetLabeler


@pytest.fixture(scope="session")
def data(opencv_data):
    return opencv_data


def upload(loader, *files):
    loader.upload.value = tuple({"name": f.name, "type": "image/jpeg", "size": f.stat().st_size,
                                 "content": memoryview(f.read_bytes()),
                                 "last_modified": datetime.datetime.now(datetime.timezone.utc)} for f in files)


def drag(loader, start, stop):
    """A left-button drag on the left image, in data coordinates, through the canvas' events."""
    canvas = loader.pane.fig.canvas
    to_px = loader.ax.transData.transform
    for name, point in (("button_press_event", start), ("motion_notify_event", stop),
                        ("button_release_event", stop)):
        x, y = to_px(point)
        MouseEvent(name, canvas, x, y, button=1)._process()


@pytest.mark.slow
def test_upload_check_rectify_roi_use_and_label(data, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)         # the labeller's own targets file goes to the working folder
    loader = TargetLabeler.from_photos(folder=tmp_path)
    assert isinstance(loader, PhotoLoader) and loader.use_button.disabled
    upload(loader, data / "right.jpg", data / "left.jpg")        # named: the order is fixed by the names
    assert "not rectified" in loader.status.value and not loader.rectify_button.disabled
    assert loader.use_button.disabled and loader.model.name == "left"
    before = loader.model.check["median_abs_dy_px"]
    loader.rectify_button.click()
    assert "rectified (uncalibrated)" in loader.status.value and loader.model.rectified.median_abs_dy_px <= 1.0
    assert before > 5 and not loader.use_button.disabled and loader.rectify_button.disabled
    assert len(loader.artists["lines"].get_segments()) == loader.model.rectified.inliers
    drag(loader, (300, 200), (700, 500))
    assert loader.model.roi == (300, 200, 400, 300) and loader.artists["roi"].get_visible()
    loader.use_button.click()
    assert loader.errors == []
    folder = tmp_path / f"photos-{loader.model.user}-left"
    assert sorted(p.name for p in folder.iterdir()) == ["left.png", "rectify.json", "right.png"]
    assert json.loads((folder / "rectify.json").read_text())["roi"] == [300, 200, 400, 300]
    labeler = loader.opened
    assert isinstance(labeler, TargetLabeler) and loader.area.children == (labeler.widget,)
    assert labeler.model.prepared.config.roi == (300, 200, 400, 300)
    assert labeler.model.prepared.config.shift != "auto"       # measured on the pair
    x, y = labeler.model.left_xy[0]
    labeler.click(x, y, side="left")
    k = int(np.argmin(np.abs(labeler.model.right_xy[:, 1] - y) + np.abs(labeler.model.right_xy[:, 0] - x) * 0.01))
    labeler.click(*labeler.model.right_xy[k], side="right")
    path = labeler.save()
    saved = json.loads(path.read_text())
    assert len(saved["pairs"]) == 1 and saved["left_image_sha256"] == image_sha256(folder / "left.png")


@pytest.mark.slow
def test_an_already_rectified_pair_needs_no_rectify_and_explorer_opens(data, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    loader = ParameterExplorer.from_photos(folder=tmp_path)
    loader.load(data / "aloeL.jpg", data / "aloeR.jpg", "aloe")
    assert "already rectified" in loader.status.value and loader.rectify_button.disabled
    assert not loader.use_button.disabled
    loader.use()
    assert isinstance(loader.opened, ParameterExplorer) and loader.errors == []


def test_bad_photos_are_refused_and_lose_nothing(data, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    loader = TargetLabeler.from_photos(folder=tmp_path)
    upload(loader, data / "left.jpg", data / "right.jpg")
    kept = loader.model.left
    upload(loader, data / "left.jpg")                                # one file
    assert "two photos at once" in str(loader.log.outputs) and loader.model.left is kept
    loader.load(data / "left.jpg", data / "left.jpg", "twice")       # the same photo twice
    assert "cannot be used" in loader.status.value
    assert loader.rectify_button.disabled and loader.use_button.disabled
    loader.guard(loader.open_folder)(tmp_path / "nowhere")
    assert "left.* and right.*" in str(loader.log.outputs)
    with pytest.raises(ValueError, match="a rectified pair"):
        loader.model.save()
    assert not any(p.name.startswith("photos-") for p in tmp_path.iterdir())


@pytest.mark.slow
def test_depth_demo_from_photos_background_then_scene(tmp_path, monkeypatch):
    """The rendered lab (empty) and toy-car pairs stand in for two pairs of photos taken from
    one fixed pair of camera positions: both are rectified, so no rectification is needed."""
    from pathlib import Path

    from ismb_lab.widgets import DepthDemo

    monkeypatch.chdir(tmp_path)
    images = Path(__file__).resolve().parents[2] / "images"
    first = DepthDemo.from_photos(folder=tmp_path)
    first.load(images / "lab" / "left.png", images / "lab" / "right.png", "desk")
    assert "already rectified" in first.status.value and not first.use_button.disabled
    second = first.use()
    assert isinstance(second, PhotoLoader) and first.model.saved.name.endswith("desk-background")
    second.load(images / "toy_cars" / "left.png", images / "toy_cars" / "right.png", "desk")
    demo = second.use()
    assert isinstance(demo, DepthDemo) and demo.errors == [] and second.model.saved.name.endswith("desk-scene")
    assert len(demo.model.result.objects) >= 1 and "features" in demo.ranking.value


def test_the_scene_pair_takes_the_background_rectification(data, tmp_path):
    from ismb_lab.widgets.photos import PhotoModel

    background = PhotoModel(tmp_path, role="background")
    background.set_photos(data / "left.jpg", data / "right.jpg", "books")
    background.rectify()
    r = background.rectified
    scene = PhotoModel(tmp_path, role="scene", homographies=(r.left_h, r.right_h, r.left.shape[::-1]))
    scene.set_photos(data / "left.jpg", data / "right.jpg", "books")
    assert scene.ready and scene.rectified.method == "the background's"
    # the figures of a pair placed by another pair's homographies went through no RANSAC
    assert "robust matches (no RANSAC)" in scene.rectify() and "inliers" not in scene.message
    np.testing.assert_array_equal(scene.rectified.left, r.left)
    np.testing.assert_array_equal(scene.rectified.right, r.right)


@pytest.mark.slow
def test_another_pair_under_a_used_name_gets_its_own_folder_and_the_first_is_kept(tmp_path):
    from ismb_lab.scenes import synthetic_scene
    from ismb_lab.widgets.photos import PhotoModel

    first, second = synthetic_scene(seed=0), synthetic_scene(seed=1)
    model = PhotoModel(folder=tmp_path, user="ann")
    model.set_photos(first.left, first.right, "desk")
    kept = model.save()
    assert kept == tmp_path / "photos-ann-desk"
    files = {p.name: p.read_bytes() for p in kept.iterdir()}

    model.set_roi(10, 10, 100, 90)                     # the same pair again: its own folder, new ROI
    assert model.save() == kept
    assert json.loads((kept / "rectify.json").read_text())["roi"] == [10, 10, 90, 80]
    assert (kept / "left.png").read_bytes() == files["left.png"]

    model.set_photos(second.left, second.right, "desk")   # another pair, the same name
    assert model.save() == tmp_path / "photos-ann-desk-2"
    assert (kept / "left.png").read_bytes() == files["left.png"]
    assert (kept / "right.png").read_bytes() == files["right.png"]
    assert (tmp_path / "photos-ann-desk-2" / "left.png").read_bytes() != files["left.png"]

    (tmp_path / "photos-ann-note").write_text("mine")     # a file, and a link to a folder, are not used
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (tmp_path / "photos-ann-link").symlink_to(elsewhere, target_is_directory=True)
    for name in ("note", "link"):
        model.set_photos(first.left, first.right, name)
        assert model.save() == tmp_path / f"photos-ann-{name}-2"
    assert (tmp_path / "photos-ann-note").read_text() == "mine" and not any(elsewhere.iterdir())
