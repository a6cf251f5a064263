"""A dense disparity beside the network's sparse matches: OpenCV's semi-global matching (SGBM),
shown as a comparison in the window's disparity range, compared at the matched points and
turned into metres through the same camera."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, message
from ..cameras.camera import StereoCamera
from ..images.io import grey_uint8

__all__ = ["AGREE_PX", "AGREE_SHARE", "Agreement", "MAX_DENSE", "SGBM_BLOCK", "agreement", "dense_points",
           "sgbm_disparity", "sgbm_range", "window_range"]

#: SGBM's matched block, pixels (odd): it follows a board's edge, and a 640 x 480 photo's noise.
SGBM_BLOCK = 5
#: Two disparities agree when they are within this share of the network's ...
AGREE_SHARE = 0.05
#: ... or within this many pixels of it (a near point's 5% is several pixels, a far one's a fraction).
AGREE_PX = 1.0
#: At most this many SGBM points are sent to the 3-D view (WebGL draws them smoothly in a browser).
MAX_DENSE = 20_000


def window_range(config) -> tuple[float, float]:
    """The disparities a candidate window searches: ``shift -/+ window_width / 2`` pixels.

    >>> from ismb_lab.matching.pipeline import MatchConfig
    >>> window_range(MatchConfig())
    (0.0, 40.0)
    """
    shift = config.shift
    if isinstance(shift, str):
        raise ParameterError(message("config", "window_range", "a window with a measured shift (prepare the pair "
                                     "first)", shift))
    half = float(config.window_width) / 2
    return float(shift) - half, float(shift) + half


def sgbm_range(low: float, high: float) -> tuple[int, int]:
    """SGBM's ``(minDisparity, numDisparities)`` for disparities `low` to `high` px: from the whole
    pixel at or below `low`, a count that is a positive multiple of 16 (OpenCV's rule).

    >>> sgbm_range(19.96, 163.92)
    (19, 160)
    >>> sgbm_range(-3.5, 4.0)
    (-4, 16)
    """
    own = "sgbm_range"
    low = check_number(low, "low", own)
    high = check_number(high, "high", own, low=low, low_open=True)
    start = math.floor(low)
    return start, max(16, 16 * math.ceil((high - start) / 16))


def _grey8(image, name: str, owner: str) -> np.ndarray:
    arr = np.asarray(image, dtype=float)
    if arr.ndim != 2 or min(arr.shape) < 8 or not np.isfinite(arr).all():
        raise ParameterError(message(name, owner, "a grey image (2-D, finite, at least 8 x 8)",
                                     f"an array of shape {arr.shape}"))
    return grey_uint8(arr)


def sgbm_disparity(left, right, low: float, high: float, *, block: int = SGBM_BLOCK) -> np.ndarray:
    """OpenCV's semi-global matching of a rectified pair (grey, rounded to 8 bits), searching
    disparities `low` to `high` pixels with an odd `block`; returns ``x_left - x_right`` per left
    pixel (in sixteenths), NaN where SGBM gives none.

    The range is the network's window's (:func:`window_range`), not OpenCV's usual 0 to 64: SGBM
    then cannot find a repeated texture's period outside it, and both matchers search alike.
    ``P1 = 8 block²``, ``P2 = 32 block²``, uniqueness 10%, left-right check 1 px, speckles under
    100 px (range 2) removed, ``MODE_SGBM_3WAY``.

    >>> rng = np.random.default_rng(0)
    >>> texture = cv2.GaussianBlur(rng.uniform(0, 255, (60, 160)), (0, 0), 1.5) * 4 % 255
    >>> d = sgbm_disparity(texture[:, :-12], texture[:, 12:], 4, 20)
    >>> float(np.nanmedian(d))
    12.0
    """
    own = "sgbm_disparity"
    a, b = _grey8(left, "left", own), _grey8(right, "right", own)
    if a.shape != b.shape:
        raise ParameterError(message("right", own, f"an image of the left one's shape {a.shape}",
                                     f"shape {b.shape}"))
    block = check_number(block, "block", own, low=1, high=31, integer=True)
    if block % 2 == 0:
        raise ParameterError(message("block", own, "an odd number of pixels", block))
    start, count = sgbm_range(low, high)
    sgbm = cv2.StereoSGBM_create(minDisparity=start, numDisparities=count, blockSize=block,
                                 P1=8 * block * block, P2=32 * block * block, disp12MaxDiff=1,
                                 uniquenessRatio=10, speckleWindowSize=100, speckleRange=2,
                                 mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY)
    d = sgbm.compute(a, b).astype(float) / 16.0
    d[d < start] = np.nan          # OpenCV marks "none" as (minDisparity - 1) * 16
    return d


@dataclass(frozen=True)
class Agreement:
    """How a dense disparity map agrees with the network's `matches`: `measured` of them have an
    SGBM disparity, `agree` of those within `share` or `px` of the network's."""

    matches: int
    measured: int
    agree: int
    share: float = AGREE_SHARE
    px: float = AGREE_PX

    @property
    def fraction(self) -> float:
        """``agree / measured`` (NaN when nothing was measured)."""
        return self.agree / self.measured if self.measured else math.nan

    def __str__(self) -> str:
        if not self.matches:
            return "no network match to compare with SGBM"
        text = (f"SGBM agrees with the network at {self.agree} of {self.measured} matched points "
                f"({self.fraction:.0%}) within {self.share:.0%} or {self.px:g} px")
        missing = self.matches - self.measured
        return text + (f"; {missing} of the {self.matches} have no SGBM disparity" if missing else "")


def agreement(dense, xy, disparity, *, share: float = AGREE_SHARE, px: float = AGREE_PX) -> Agreement:
    """Compare a dense disparity map with the network's matches at their left pixels.

    A match agrees when ``|d_dense - d| <= max(px, share * d)`` at the pixel nearest its left
    point; a pixel without a dense disparity (NaN) is not ``measured``.

    >>> dense = np.full((10, 10), 20.0); dense[0, 0] = np.nan
    >>> str(agreement(dense, [[5, 5], [6, 5], [0, 0]], [20.5, 25.0, 20.0]))
    'SGBM agrees with the network at 1 of 2 matched points (50%) within 5% or 1 px; 1 of the 3 have no SGBM disparity'
    """
    own = "agreement"
    dense = np.asarray(dense, dtype=float)
    if dense.ndim != 2:
        raise ParameterError(message("dense", own, "a 2-D disparity map", f"shape {dense.shape}"))
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    d = np.asarray(disparity, dtype=float).reshape(-1)
    if len(d) != len(xy) or not np.isfinite(d).all() or not np.isfinite(xy).all():
        raise ParameterError(message("disparity", own, f"{len(xy)} finite numbers, one per point of xy",
                                     f"{len(d)} values"))
    share = check_number(share, "share", own, low=0)
    px = check_number(px, "px", own, low=0)
    h, w = dense.shape
    col = np.clip(np.rint(xy[:, 0]).astype(int), 0, w - 1)
    row = np.clip(np.rint(xy[:, 1]).astype(int), 0, h - 1)
    found = dense[row, col]
    measured = np.isfinite(found)
    close = np.abs(found[measured] - d[measured]) <= np.maximum(px, share * np.abs(d[measured]))
    return Agreement(len(d), int(measured.sum()), int(close.sum()), share, px)


def dense_points(camera: StereoCamera, dense, most: int = MAX_DENSE) -> tuple[np.ndarray, np.ndarray]:
    """At most `most` pixels of a dense disparity map of `camera`'s rectified pair, in metres.

    The pixels lie on a regular grid (every ``s``-th row and column, ``s`` as small as `most`
    allows).  Returns ``(xyz, xy)``: metres in the rectified left camera's frame, and the pixels.

    >>> xyz, xy = dense_points(StereoCamera(), np.full((240, 320), 30.0), most=1000)
    >>> len(xyz) <= 1000, float(xyz[0, 2])
    (True, 1.0)
    """
    own = "dense_points"
    if not isinstance(camera, StereoCamera):
        raise ParameterTypeError(message("camera", own, "a StereoCamera", camera))
    dense = np.asarray(dense, dtype=float)
    if dense.ndim != 2:
        raise ParameterError(message("dense", own, "a 2-D disparity map", f"shape {dense.shape}"))
    most = check_number(most, "most", own, low=1, integer=True)
    valid = np.isfinite(dense) & (dense > 0)
    step = max(1, math.ceil(math.sqrt(valid.sum() / most)))
    while True:
        rows, cols = np.nonzero(valid[::step, ::step])
        if len(rows) <= most:
            break
        step += 1
    rows, cols = rows * step, cols * step
    xy = np.column_stack([cols, rows]).astype(float)
    return camera.points_from_disparity(xy, dense[rows, cols]), xy
