"""Harris response and corner detection (thesis chapter 2)."""

import math

import cv2
import numpy as np
import pytest
from scipy import ndimage as ndi

from ismb_lab.images.features import (Corners, detect_corners, harris_from_tensor, harris_response,
                               image_gradients, resolve_roi, structure_tensor)


def rectangles():
    """Four bright rectangles on black: 16 corners at known pixels."""
    img = np.zeros((120, 160))
    for x, y, w, h, v in [(15, 20, 40, 30, 200), (80, 15, 50, 35, 150),
                          (30, 70, 30, 35, 120), (95, 65, 45, 40, 230)]:
        img[y:y + h, x:x + w] = v
    return img


def blocks(seed=3):
    """A 240x320 patchwork of random grey 20x20 blocks: many corners of many strengths."""
    levels = np.random.default_rng(seed).uniform(0, 255, (12, 16))
    return np.kron(levels, np.ones((20, 20)))


def cv2_box_harris(img, k=0.04):
    """cv2.cornerHarris(blockSize=3, ksize=3) rebuilt from this module's pieces.

    For float32 input OpenCV scales its Sobel derivatives by 1 / (2**(ksize-1) * blockSize)
    = 1/12 instead of our 1/8, and sums the products over the 3x3 block (unnormalised box).
    """
    Ix, Iy = image_gradients(img)
    scale = (8 / 12) ** 2 * 9
    tensor = [ndi.uniform_filter(p, 3, mode="mirror") * scale for p in (Ix * Ix, Ix * Iy, Iy * Iy)]
    return harris_from_tensor(*tensor, k)


def cv2_peaks(img):
    R = cv2.cornerHarris(img.astype(np.float32), blockSize=3, ksize=3, k=0.04)
    rows, cols = np.nonzero((R == ndi.maximum_filter(R, 7)) & (R > 0.01 * R.max()))
    return np.stack([cols, rows], axis=1)


def test_box_window_tensor_equals_cv2_corner_harris_everywhere():
    smooth = ndi.gaussian_filter(np.random.default_rng(0).uniform(0, 255, (60, 80)), 1.5)
    for img in (smooth, rectangles()):
        ours = cv2_box_harris(img)
        theirs = cv2.cornerHarris(img.astype(np.float32), blockSize=3, ksize=3, k=0.04)
        err = np.abs(ours - theirs) / np.abs(theirs).max()
        # both use reflect-101 borders, so the border agrees as well as the interior
        assert err[2:-2, 2:-2].max() < 1e-4 and err.max() < 1e-4
        assert np.abs(theirs).max() > 0


def test_gaussian_window_corners_coincide_with_cv2_peaks():
    img = rectangles()
    ours = detect_corners(img, roi="full", n_min=16, n_max=16).xy
    theirs = cv2_peaks(img)
    assert len(ours) == len(theirs) == 16
    dist = np.abs(ours[:, None, :] - theirs[None, :, :]).max(axis=2)
    assert dist.min(axis=1).max() <= 2 and dist.min(axis=0).max() <= 2


def test_gradients_have_unit_scale_and_x_right_y_down():
    ramp = np.add.outer(3.0 * np.arange(6), np.arange(7))        # I = x + 3 y
    Ix, Iy = image_gradients(ramp)
    assert np.allclose(Ix[1:-1, 1:-1], 1) and np.allclose(Iy[1:-1, 1:-1], 3)
    assert np.all(Ix[:, [0, -1]] == 0) and np.all(Iy[[0, -1], :] == 0)   # mirrored borders


def test_structure_tensor_of_a_ramp_is_its_squared_slope():
    ramp = np.add.outer(3.0 * np.arange(20), np.arange(20))
    Axx, Axy, Ayy = (a[8:12, 8:12] for a in structure_tensor(ramp, sigma=1.5))
    assert np.allclose(Axx, 1) and np.allclose(Axy, 3) and np.allclose(Ayy, 9)
    assert np.allclose(harris_response(ramp)[8:12, 8:12], -0.04 * 100)   # an edge: det = 0


def test_response_is_positive_at_a_corner_negative_on_an_edge_zero_when_flat():
    img = np.zeros((40, 40))
    img[10:30, 10:30] = 200.0
    R = harris_response(img)
    assert R[10, 10] > 0 and R[29, 29] > 0
    assert R[20, 10] < 0 and R[10, 20] < 0
    assert R[20, 20] == 0 and R[2, 35] == 0
    assert R[10, 10] > 0.1 * R.max()


def test_rotated_square_gives_its_four_vertices():
    img = np.zeros((100, 100), np.uint8)
    angles = np.deg2rad(30) + np.arange(4) * np.pi / 2
    vertices = 50 + 25 * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    cv2.fillPoly(img, [np.round(vertices * 16).astype(np.int32)], 200, cv2.LINE_AA, shift=4)
    xy = detect_corners(img, roi="full", n_min=4, n_max=10).xy
    assert len(xy) == 4
    dist = np.hypot(*(xy[:, None, :] - vertices[None, :, :]).transpose(2, 0, 1))
    assert sorted(dist.argmin(axis=1)) == [0, 1, 2, 3] and dist.min(axis=1).max() < 2.5


def test_high_threshold_relaxes_until_n_min_and_no_further():
    img, start = blocks(), 1e9
    c = detect_corners(img, threshold=start, n_min=20, n_max=40)
    assert c.iterations > 0 and 20 <= len(c) <= 40 and c.message == ""
    assert c.threshold == pytest.approx(start * 0.8 ** c.iterations)
    assert c.response.min() >= c.threshold
    one_less = detect_corners(img, threshold=c.threshold / 0.8, n_min=1, n_max=1000)
    assert one_less.iterations == 0 and len(one_less) < 20


def test_default_threshold_starts_at_the_strongest_candidate():
    c = detect_corners(blocks(), n_min=1)
    assert len(c) == 1 and c.iterations == 0 and c.threshold == c.response[0]


def test_n_max_keeps_the_strongest():
    img = blocks()
    everything = detect_corners(img, roi="full", n_min=1000, n_max=1000)
    capped = detect_corners(img, roi="full", n_min=5, n_max=5, threshold=1.0)
    assert len(everything) > 5 and len(capped) == 5
    strongest = np.sort(everything.response)[-5:]
    assert np.array_equal(np.sort(capped.response), strongest)
    assert {tuple(p) for p in capped.xy} <= {tuple(p) for p in everything.xy}


def test_flat_image_gives_no_corners_and_says_why():
    for threshold in (None, 5.0):
        c = detect_corners(np.full((60, 80), 7.0), threshold=threshold)
        assert len(c) == 0 and c.xy.shape == (0, 2) and c.response.shape == (0,)
        assert "flat" in c.message and c.iterations == 0
    assert math.isnan(detect_corners(np.zeros((60, 80))).threshold)
    edge = np.zeros((60, 80))
    edge[:, 40:] = 100
    straight = detect_corners(edge)
    assert len(straight) == 0 and "no positive local maximum" in straight.message


def test_a_single_tiny_corner_ends_the_relaxation():
    img = np.zeros((60, 80))
    img[30:, 40:] = 1e-6
    c = detect_corners(img, threshold=1.0)
    assert len(c) == 1 and 0 < c.response[0] < 1e-20
    assert c.threshold <= c.response[0] < c.threshold / 0.8     # stopped at the first T below it
    assert "only 1 corner found" in c.message and "n_min=20" in c.message
    slow = detect_corners(img, threshold=1e300, relax=1 - 1e-9)   # ~8e11 relaxations, not a loop
    assert len(slow) == 1 and slow.iterations > 1e11


def test_corners_closer_than_the_window_to_the_image_edge_are_left_out():
    img = np.zeros((40, 40))
    img[3:20, 3:20] = 200.0            # corners at 3 and 19 in x and y
    narrow = detect_corners(img, roi="full", n_min=4, sigma=0.5)    # border 3
    assert narrow.xy.tolist() == [[3, 3], [19, 3], [3, 19], [19, 19]] and narrow.message == ""
    wide = detect_corners(img, roi="full", n_min=4, sigma=1.0)      # border 4
    assert wide.xy.tolist() == [[19, 19]]
    assert "at least 4 pixels from the image edge" in wide.message


def test_plateau_ties_keep_one_point_the_first_in_row_major_order():
    img = np.zeros((20, 20))
    img[9:11, 9:11] = 100.0             # R is an exact 2x2 plateau around the block
    R = harris_response(img)
    assert R[9, 9] == R[9, 10] == R[10, 9] == R[10, 10] == R.max()
    c = detect_corners(img, roi="full", n_min=1)
    assert c.xy.tolist() == [[9.0, 9.0]]


def test_corners_lie_in_the_roi_are_sorted_row_major_and_spaced():
    img = blocks()
    for roi, min_distance in [("center", 3), ((200, 10, 90, 70), 5), ("full", 8)]:
        c = detect_corners(img, roi=roi, n_min=10, n_max=60, min_distance=min_distance)
        x, y, w, h = c.roi
        assert len(c) >= 10
        assert np.all((c.xy[:, 0] >= x) & (c.xy[:, 0] < x + w))
        assert np.all((c.xy[:, 1] >= y) & (c.xy[:, 1] < y + h))
        border = 4                                   # ceil(3 * sigma) + 1
        assert np.all((c.xy >= border) & (c.xy <= np.array([319, 239]) - border))
        order = np.lexsort((c.xy[:, 0], c.xy[:, 1]))
        assert np.array_equal(order, np.arange(len(c)))
        gaps = np.abs(c.xy[:, None] - c.xy[None]).max(axis=2) + np.eye(len(c)) * 1e9
        assert gaps.min() > min_distance
        assert np.allclose(c.response, harris_response(img)[c.xy[:, 1].astype(int),
                                                            c.xy[:, 0].astype(int)])


def test_detection_is_deterministic_and_leaves_the_input_alone():
    img = blocks()
    before = img.copy()
    a, b = detect_corners(img), detect_corners(np.asfortranarray(img))
    assert np.array_equal(img, before)
    assert isinstance(a, Corners) and np.array_equal(a.xy, b.xy)
    assert np.array_equal(a.response, b.response)
    assert a.threshold == b.threshold and a.iterations == b.iterations
    assert np.array_equal(detect_corners(img.astype(np.uint8)).xy,
                          detect_corners(img.astype(np.uint8).astype(float)).xy)


@pytest.mark.parametrize("roi, box", [
    ("center", (80, 60, 160, 120)),
    ("CENTER", (80, 60, 160, 120)),
    ("full", (0, 0, 320, 240)),
    ((10, 20, 30, 40), (10, 20, 30, 40)),
    ([0, 0, 320, 240], (0, 0, 320, 240)),
    (np.array([1, 2, 3, 4]), (1, 2, 3, 4)),
    ("10,20,30,40", (10, 20, 30, 40)),
    (" 10 , 20, 30 ,40 ", (10, 20, 30, 40)),
])
def test_roi_accepted_forms(roi, box):
    got = resolve_roi(roi, (240, 320))
    assert got == box and all(type(v) is int for v in got)


@pytest.mark.parametrize("roi", [
    "middle", "10,20,30", "10,20,30,40,50", "10,20,3.5,40", "a,b,c,d",
    (10, 20, 30), (10, 20, 30.0, 40), (10, 20, True, 40),
    (10, 20, 0, 40), (10, 20, 30, -1),
    (-1, 0, 10, 10), (0, -1, 10, 10), (300, 0, 21, 10), (0, 230, 10, 11), "0,0,321,240",
])
def test_roi_errors_name_roi_the_value_and_the_image_size(roi):
    with pytest.raises(ValueError) as info:
        resolve_roi(roi, (240, 320))
    text = str(info.value)
    assert "'roi'" in text and "320x240" in text and repr(roi) in text


def test_roi_of_a_wrong_type_is_a_type_error():
    with pytest.raises(TypeError, match="'roi'"):
        resolve_roi(None, (240, 320))


@pytest.mark.parametrize("kwargs, exc, name", [
    (dict(n_min=0), ValueError, "n_min"),
    (dict(n_min=2.5), TypeError, "n_min"),
    (dict(n_min=10, n_max=9), ValueError, "n_max"),
    (dict(sigma=0), ValueError, "sigma"),
    (dict(k=0), ValueError, "k"),
    (dict(k=0.25), ValueError, "k"),
    (dict(threshold=0), ValueError, "threshold"),
    (dict(threshold=float("nan")), ValueError, "threshold"),
    (dict(threshold="1"), TypeError, "threshold"),
    (dict(min_distance=0), ValueError, "min_distance"),
    (dict(relax=1), ValueError, "relax"),
    (dict(relax=0), ValueError, "relax"),
    (dict(roi="nowhere"), ValueError, "roi"),
])
def test_bad_parameters_are_refused(kwargs, exc, name):
    with pytest.raises(exc, match=f"'{name}' parameter of"):
        detect_corners(np.zeros((40, 40)), **kwargs)


@pytest.mark.parametrize("image, exc, shown", [
    (np.zeros((4, 4, 3)), ValueError, "(4, 4, 3)"),
    (np.zeros((0, 4)), ValueError, "(0, 4)"),
    (np.zeros((4, 4), dtype=np.int64), TypeError, "int64"),
    (np.zeros((4, 4), dtype=bool), TypeError, "bool"),
    (np.array([[0.0, np.inf]]), ValueError, "NaN or infinite"),
])
def test_bad_images_are_refused(image, exc, shown):
    for func in (detect_corners, harris_response, image_gradients):
        with pytest.raises(exc) as info:
            func(image)
        assert "'image'" in str(info.value) and shown in str(info.value)
