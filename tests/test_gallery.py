"""images/ is exactly what the code renders, and its ground truth decodes back."""

from pathlib import Path

import cv2
import numpy as np

from ismb_lab.cli import main
from ismb_lab.gallery import decode_disparity
from ismb_lab.scenes import synthetic_scene

IMAGES = Path(__file__).resolve().parent.parent / "images"


def test_render_reproduces_the_committed_images_byte_for_byte(tmp_path):
    assert main(["render", "--out", str(tmp_path)]) == 0
    rendered = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    committed = sorted(p.relative_to(IMAGES) for p in IMAGES.rglob("*") if p.is_file()
                       and p.name != "README.md")
    assert rendered == committed and rendered
    for name in rendered:
        assert (tmp_path / name).read_bytes() == (IMAGES / name).read_bytes(), name


def test_committed_ground_truth_is_the_scene_disparity():
    scene = synthetic_scene(seed=0)
    encoded = cv2.imread(str(IMAGES / "synthetic" / "disparity.png"), cv2.IMREAD_UNCHANGED)
    assert encoded.dtype == np.uint16
    disparity = decode_disparity(encoded)
    known = np.isfinite(scene.disparity)
    assert np.array_equal(np.isfinite(disparity), known)
    assert np.max(np.abs(disparity[known] - scene.disparity[known])) <= 0.5 / 256 + 1e-12
    left = cv2.imread(str(IMAGES / "synthetic" / "left.png"), cv2.IMREAD_UNCHANGED)
    assert np.array_equal(left, scene.left.astype(np.uint8))
