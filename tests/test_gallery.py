"""images/ is exactly what the code renders, and its ground truth decodes back."""

from pathlib import Path

import cv2
import numpy as np
import pytest

from ismb_lab.cli import main
from ismb_lab.scenes.gallery import decode_disparity
from ismb_lab.images.io import load_pair
from ismb_lab.matching.pipeline import prepare
from ismb_lab.tuning.cases import load_manifest
from ismb_lab.scenes import REALISTIC_COUNT, synthetic_scene, toy_car_scene, true_matches
from ismb_lab.labels.targets import load_targets, snap

IMAGES = Path(__file__).resolve().parent.parent / "images"


@pytest.mark.slow
def test_render_reproduces_the_committed_images_byte_for_byte(tmp_path):
    assert main(["render", "--out", str(tmp_path)]) == 0
    rendered = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    committed = sorted(p.relative_to(IMAGES) for p in IMAGES.rglob("*") if p.is_file()
                       and p != IMAGES / "README.md")
    assert rendered == committed and rendered
    for name in rendered:
        assert (tmp_path / name).read_bytes() == (IMAGES / name).read_bytes(), name


def test_committed_ground_truth_is_the_scene_disparity(rendered):
    scene = rendered(synthetic_scene, seed=0)
    encoded = cv2.imread(str(IMAGES / "synthetic" / "disparity.png"), cv2.IMREAD_UNCHANGED)
    assert encoded.dtype == np.uint16
    disparity = decode_disparity(encoded)
    known = np.isfinite(scene.disparity)
    assert np.array_equal(np.isfinite(disparity), known)
    assert np.max(np.abs(disparity[known] - scene.disparity[known])) <= 0.5 / 256 + 1e-12
    left = cv2.imread(str(IMAGES / "synthetic" / "left.png"), cv2.IMREAD_UNCHANGED)
    assert np.array_equal(left, scene.left.astype(np.uint8))


PAIRS = ["lab", "toy_cars"] + [f"realistic/{n:02d}" for n in range(1, REALISTIC_COUNT + 1)]


@pytest.mark.parametrize("folder", PAIRS)
def test_every_pair_folder_has_the_files_widgets_load(folder):
    for name in ("left.png", "right.png", "disparity.png", "scene.json", "answer_key.json"):
        assert (IMAGES / folder / name).is_file(), name
    pair = load_pair(IMAGES / folder / "left.png", IMAGES / folder / "right.png")
    key = load_targets(IMAGES / folder / "answer_key.json", pair=pair)   # hashes checked
    assert key.meta["kind"] == "answer key generated from ground truth"
    assert len(key) >= 8
    # Every target sits on a corner of the default matcher, on both sides.
    prepared = prepare(pair, None)
    snapped = snap(key, prepared.problem.left_xy, prepared.problem.right_xy, tol=0)
    assert len(snapped.pairs) == len(key)
    assert len(set(snapped.pairs[:, 1].tolist())) == len(key)


def test_the_answer_key_is_the_ground_truth(rendered):
    scene = rendered(toy_car_scene, seed=0)
    key = load_targets(IMAGES / "toy_cars" / "answer_key.json")
    truth = scene.correspond(key.left_xy)
    assert np.max(np.linalg.norm(truth - key.right_xy, axis=1)) <= 1.5
    prepared = prepare(IMAGES / "toy_cars" / "left.png", IMAGES / "toy_cars" / "right.png")
    partner = true_matches(scene, prepared.problem.left_xy, prepared.problem.right_xy)
    # Only left corners sharing a right partner with a nearer one are left out.
    assert len(key) >= len(set(partner[partner >= 0].tolist()))


@pytest.mark.parametrize("folder, count", [("lab", 1), ("toy_cars", 1), ("realistic", REALISTIC_COUNT)])
def test_manifests_load_for_evaluate(folder, count):
    cases = load_manifest(IMAGES / folder / "manifest.json")
    assert len(cases) == count
    assert all(len(case.targets) >= 8 for case in cases)
    assert (IMAGES / folder / "README.md").is_file()
