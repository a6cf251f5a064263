"""The one coordinate convention of ismb_lab.

Everything in the package, its files and its command line follows these rules.

* **Images** are 2-D arrays indexed ``image[row, column]``, i.e. ``image[y, x]``.
* **Points** are ``(x, y)`` pairs: ``x`` is the 0-based column and ``y`` the
  0-based row of the pixel *in the full input image* (never relative to an ROI).
  A set of points is an ``(N, 2)`` float array with columns ``x, y``.
* **Features** are numbered from 0 in the order :func:`ismb_lab.features.detect_corners`
  returns them (row-major: by ``y``, then ``x``).  Printed tables number them from 1,
  as the thesis does.
* **Neurons** are candidate pairs ``(i, k)``: left feature ``i``, right feature ``k``.
* **Disparity** of a left point ``p = (x_l, y_l)`` and a right point ``q = (x_r, y_r)``:

  - horizontal disparity ``x_l - x_r`` (positive for points in front of a parallel rig),
  - vertical disparity ``y_r - y_l`` (zero for a rectified rig),
  - Euclidean disparity ``||p - q||``, the "disparity" column of the thesis' tables.

* **ROIs** are ``(x, y, w, h)`` boxes: columns ``x .. x + w - 1`` and rows ``y .. y + h - 1``.
"""

from __future__ import annotations

import numpy as np


def horizontal_disparity(left_xy, right_xy) -> np.ndarray:
    """Horizontal disparity ``x_left - x_right`` of matched points.

    Examples
    --------
    >>> horizontal_disparity([[99, 99]], [[88, 100]])
    array([11.])
    """
    return np.asarray(left_xy, float)[..., 0] - np.asarray(right_xy, float)[..., 0]


def vertical_disparity(left_xy, right_xy) -> np.ndarray:
    """Vertical disparity ``y_right - y_left`` of matched points.

    Examples
    --------
    >>> vertical_disparity([[99, 99]], [[88, 100]])
    array([1.])
    """
    return np.asarray(right_xy, float)[..., 1] - np.asarray(left_xy, float)[..., 1]


def euclidean_disparity(left_xy, right_xy) -> np.ndarray:
    """Euclidean disparity ``||p - q||``, as in the thesis' tables.

    Examples
    --------
    >>> euclidean_disparity([[99, 99]], [[88, 100]]).round(2)   # Table 5.1, pair 1
    array([11.05])
    """
    diff = np.asarray(left_xy, float) - np.asarray(right_xy, float)
    return np.hypot(diff[..., 0], diff[..., 1])
