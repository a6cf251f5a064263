"""Real stereo data with ground truth: the Middlebury 2014 Motorcycle pair.

scikit-image ships a 4x down-sampled copy (``skimage.data.stereo_motorcycle``), so
nothing is downloaded.  It is scaled once more to the thesis' width (about 320 px)
and cut into thesis-sized ROIs, each an evaluation pair that no one labelled by hand:
its targets come from the ground-truth disparity (:func:`ground_truth_pairs`).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ._validation import ParameterError, check_number, message

__all__ = ["MOTORCYCLE_ROIS", "ground_truth_pairs", "GroundTruthPair", "motorcycle"]

#: Four non-overlapping 160 x 108 ROIs (x, y, w, h) of the 320 x 216 pair.
MOTORCYCLE_ROIS = ((0, 0, 160, 108), (160, 0, 160, 108), (0, 108, 160, 108), (160, 108, 160, 108))


@dataclass(frozen=True, eq=False)
class GroundTruthPair:
    """A rectified grey pair and the horizontal disparity of its left view.

    Attributes
    ----------
    left, right : (H, W) float ndarray
        Grey images in ``[0, 255]``.
    disparity : (H, W) float ndarray
        ``x_left - x_right`` for each left pixel; NaN where it is unknown.
    name : str
    """

    left: np.ndarray
    right: np.ndarray
    disparity: np.ndarray
    name: str


def motorcycle(width: int = 320) -> GroundTruthPair:
    """The Middlebury 2014 Motorcycle pair, grey, scaled to `width` pixels.

    Images are scaled with area averaging.  The disparity is scaled the same way,
    averaging only known pixels; a low-resolution pixel is unknown when less than
    half of its footprint was known.  (Requiring the whole footprint leaves half
    of all Harris corners unknown, since corners sit on depth edges.)

    Parameters
    ----------
    width : int
        Output width in pixels, at most the bundled 741.

    Returns
    -------
    pair : GroundTruthPair

    Examples
    --------
    >>> pair = motorcycle()
    >>> pair.left.shape, bool(np.nanmax(pair.disparity) < 30)
    ((216, 320), True)
    """
    width = check_number(width, "width", "motorcycle", low=16, high=741, integer=True)
    try:
        from skimage.data import stereo_motorcycle
    except ImportError:  # pragma: no cover - scikit-image is in the test extra
        raise ImportError("motorcycle() needs scikit-image: pip install scikit-image") from None
    left, right, disparity = stereo_motorcycle()
    scale = width / left.shape[1]
    size = (width, int(round(left.shape[0] * scale)))
    grey = lambda rgb: cv2.resize(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32), size,
                                  interpolation=cv2.INTER_AREA).astype(float)
    known = np.isfinite(disparity)
    total = cv2.resize(np.where(known, disparity, 0).astype(np.float32), size, interpolation=cv2.INTER_AREA)
    share = cv2.resize(known.astype(np.float32), size, interpolation=cv2.INTER_AREA)
    small = np.full(share.shape, np.nan)
    known_enough = share >= 0.5
    small[known_enough] = total[known_enough] / share[known_enough] * scale
    return GroundTruthPair(grey(left), grey(right), small, f"motorcycle@{width}")


def ground_truth_pairs(disparity: np.ndarray, left_xy, right_xy, tol: float = 1.5):
    """Target pairs from a ground-truth disparity map.

    A left corner's partner is the right corner within `tol` pixels of
    ``(x - d(x, y), y)``.  Corners where ``d`` is unknown are *unknown*: neither
    a target nor an error when matched.

    Parameters
    ----------
    disparity : (H, W) ndarray
        Left-view horizontal disparity, NaN where unknown.
    left_xy, right_xy : (N, 2) array_like
        Corner points ``(x, y)``.
    tol : float
        Snap distance in pixels.

    Returns
    -------
    pairs : (m, 2) int ndarray
        ``(i, k)`` feature indices of the targets.
    unknown : (u,) int ndarray
        Left corners whose ground truth is unknown.

    Examples
    --------
    >>> d = np.full((10, 20), 5.0); d[:, :3] = np.nan
    >>> pairs, unknown = ground_truth_pairs(d, [[10, 4], [2, 4], [15, 4]], [[5, 4], [10.5, 4]])
    >>> pairs.tolist(), unknown.tolist()
    ([[0, 0], [2, 1]], [1])
    """
    tol = check_number(tol, "tol", "ground_truth_pairs", low=0)
    lxy = np.asarray(left_xy, float).reshape(-1, 2)
    rxy = np.asarray(right_xy, float).reshape(-1, 2)
    if lxy.size and (np.any(lxy < 0) or np.any(lxy[:, 0] > disparity.shape[1] - 1)
                     or np.any(lxy[:, 1] > disparity.shape[0] - 1)):
        raise ParameterError(message("left_xy", "ground_truth_pairs",
                                     f"points inside the {disparity.shape[1]}x{disparity.shape[0]} map",
                                     "points outside it"))
    d = disparity[np.rint(lxy[:, 1]).astype(int), np.rint(lxy[:, 0]).astype(int)]
    unknown = np.flatnonzero(~np.isfinite(d))
    pairs = []
    if len(rxy):
        expected = np.stack([lxy[:, 0] - d, lxy[:, 1]], axis=1)
        dist = np.hypot(*(expected[:, None, :] - rxy[None, :, :]).transpose(2, 0, 1))
        for i in np.flatnonzero(np.isfinite(d)):
            k = int(np.argmin(dist[i]))
            if dist[i, k] <= tol:
                pairs.append((i, k))
    return np.array(pairs, dtype=np.int64).reshape(-1, 2), unknown
