"""The bundled Middlebury Motorcycle pair and targets generated from its ground truth."""

import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab.images.datasets import MOTORCYCLE_ROIS, ground_truth_pairs, motorcycle
from ismb_lab.matching.pipeline import MatchConfig, prepare
from ismb_lab.tuning.cases import load_manifest

MANIFEST = __import__("pathlib").Path(__file__).parents[1] / "manifests" / "middlebury.json"


@pytest.fixture(scope="module")
def moto():
    return motorcycle()


def test_motorcycle_is_a_grey_320_px_pair_with_unknown_disparity_marked(moto):
    assert moto.left.shape == moto.right.shape == moto.disparity.shape == (216, 320)
    for image in (moto.left, moto.right):
        assert image.dtype == float and 0 <= image.min() and image.max() <= 255
    known = np.isfinite(moto.disparity)
    assert 0.5 < known.mean() < 1.0               # occlusions and holes stay unknown
    assert np.all(moto.disparity[known] > 0)


def test_ground_truth_disparity_carries_the_left_view_onto_the_right(moto):
    # The left view warped by its ground-truth disparity must look like the right view,
    # far better than the unwarped left view does.
    ys, xs = np.nonzero(np.isfinite(moto.disparity))
    xr = np.rint(xs - moto.disparity[ys, xs]).astype(int)
    keep = (xr >= 0)
    warped = np.abs(moto.left[ys[keep], xs[keep]] - moto.right[ys[keep], xr[keep]]).mean()
    unwarped = np.abs(moto.left[ys[keep], xs[keep]] - moto.right[ys[keep], xs[keep]]).mean()
    assert warped < 0.5 * unwarped


def test_ground_truth_pairs_follow_the_rule_on_real_corners(moto):
    prepared = prepare(moto.left, moto.right, MatchConfig(roi=MOTORCYCLE_ROIS[1]))
    lxy, rxy = prepared.problem.left_xy, prepared.problem.right_xy
    pairs, unknown = ground_truth_pairs(moto.disparity, lxy, rxy)
    assert len(pairs) >= 8
    assert not set(pairs[:, 0]) & set(unknown)
    for i, k in pairs:
        x, y = lxy[i]
        d = moto.disparity[int(round(y)), int(round(x))]
        assert np.hypot(rxy[k, 0] - (x - d), rxy[k, 1] - y) <= 1.5
    for i in unknown:
        x, y = lxy[i]
        assert np.isnan(moto.disparity[int(round(y)), int(round(x))])


def test_ground_truth_pairs_tolerance_edge_and_errors():
    d = np.full((10, 20), 4.0)
    pairs, _ = ground_truth_pairs(d, [[10, 5]], [[7.5, 5]], tol=1.5)   # 1.5 px away: in
    assert pairs.tolist() == [[0, 0]]
    pairs, _ = ground_truth_pairs(d, [[10, 5]], [[7.6, 5]], tol=1.5)   # 1.6 px away: out
    assert pairs.tolist() == []
    with pytest.raises(ParameterError, match="'left_xy'"):
        ground_truth_pairs(d, [[25, 5]], [[7, 5]])
    with pytest.raises(ParameterError, match="'tol'"):
        ground_truth_pairs(d, [[10, 5]], [[7, 5]], tol=-1)


def test_motorcycle_width_is_checked():
    with pytest.raises(ParameterError, match="'width'"):
        motorcycle(width=5000)


def test_the_middlebury_manifest_gives_four_labelled_rois():
    cases = load_manifest(MANIFEST)
    assert [c.name for c in cases] == ["motorcycle top-left", "motorcycle top-right",
                                       "motorcycle bottom-left", "motorcycle bottom-right"]
    for case in cases:
        n_left = len(case.prepared.problem.left_xy)
        assert 20 <= n_left <= 30
        assert 5 <= len(case.targets) <= n_left


# --- OpenCV's sample photos (Debian's opencv-doc, which CI installs) -------------------------
import os  # noqa: E402

from ismb_lab.images.datasets import (OPENCV_DATA_VARIABLE, SampleDataMissing, aloe, books,  # noqa: E402
                               chessboard_pairs, opencv_samples)


def _need_samples():
    try:
        return opencv_samples()
    except SampleDataMissing:
        if os.environ.get("CI") == "true":
            raise       # CI installs opencv-doc: a missing install step must not hide as a skip
        pytest.skip("opencv-doc is not installed")


def test_aloe_ground_truth_carries_the_left_view_onto_the_right():
    _need_samples()
    for pair in (aloe(), aloe(320)):
        ys, xs = np.nonzero(np.isfinite(pair.disparity))
        xr = np.rint(xs - pair.disparity[ys, xs]).astype(int)
        keep = xr >= 0
        warped = np.abs(pair.left[ys[keep], xs[keep]] - pair.right[ys[keep], xr[keep]]).mean()
        unwarped = np.abs(pair.left[ys[keep], xs[keep]] - pair.right[ys[keep], xs[keep]]).mean()
        assert warped < 0.5 * unwarped, pair.name
        assert 0 <= pair.left.min() and pair.left.max() <= 255
    assert aloe().left.shape == (1110, 1282) and aloe(320).left.shape == (277, 320)


def test_books_and_the_chessboard_rig():
    _need_samples()
    left, right = books()
    assert left.shape == right.shape == (459, 612) and left.dtype == float
    pairs = chessboard_pairs()
    assert [n for n, _, _ in pairs] == ["01", "02", "03", "04", "05", "06", "07", "08", "09", "11", "12",
                                          "13", "14"]
    assert all(lf.shape == rt.shape == (480, 640) for _, lf, rt in pairs)


def test_missing_samples_say_how_to_install_them(tmp_path, monkeypatch):
    monkeypatch.setenv(OPENCV_DATA_VARIABLE, str(tmp_path))
    with pytest.raises(SampleDataMissing, match="apt-get install opencv-doc.*ISMB_LAB_OPENCV_DATA"):
        books()
    with pytest.raises(FileNotFoundError, match=str(tmp_path / "nowhere")):
        aloe(folder=tmp_path / "nowhere")
    monkeypatch.delenv(OPENCV_DATA_VARIABLE)
    _need_samples()
    with pytest.raises(ParameterError, match="'width' parameter of aloe"):
        aloe(5)
