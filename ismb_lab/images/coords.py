"""The one coordinate convention of ismb_lab.

Everything in the package, its files and its command line follows these rules.

* **Images** are 2-D arrays indexed ``image[row, column]``, i.e. ``image[y, x]``.
* **Points** are ``(x, y)`` pairs: ``x`` is the 0-based column and ``y`` the
  0-based row of the pixel *in the full input image* (never relative to an ROI).
  A set of points is an ``(N, 2)`` float array with columns ``x, y``.
* **Features** are numbered from 0 in the order :func:`ismb_lab.images.features.detect_corners`
  returns them (row-major: by ``y``, then ``x``).  Printed tables number them from 1,
  as the thesis does.
* **Neurons** are candidate pairs ``(i, k)``: left feature ``i``, right feature ``k``.
* **Disparity** of a left point ``p = (x_l, y_l)`` and a right point ``q = (x_r, y_r)``:

  - horizontal disparity ``x_l - x_r`` (positive for points in front of a parallel rig),
  - vertical disparity ``y_r - y_l`` (zero for a rectified rig),
  - Euclidean disparity ``||p - q||``, the "disparity" column of the thesis' tables.

* **ROIs** are ``(x, y, w, h)`` boxes: columns ``x .. x + w - 1`` and rows ``y .. y + h - 1``.

Glossary
--------
"Pair" alone is ambiguous here, so each meaning has its own word:

image pair
    A left and a right image of one view (:class:`ismb_lab.images.io.StereoPair`).
feature
    A Harris corner in one image, numbered as above (``i`` on the left, ``k`` on the right).
candidate
    A neuron ``(i, k)`` whose right feature lies in left feature ``i``'s candidate
    window (§3.3); only candidates ever change state.
neighbours
    Two neurons ``(i, k)`` and ``(j, l)`` whose left features lie close enough to
    interact through ``C_ikjl`` (3-12).
match
    A candidate that is on in a solved state, after the method's post-processing
    (:func:`ismb_lab.network.solvers.to_matches`); ``MatchResult.pairs`` lists them as ``(i, k)``.
target
    A match a person (or a ground truth) says is right, stored by coordinates with
    the images' hashes (:mod:`ismb_lab.labels.targets`) and snapped to features for scoring.
case
    An image pair with its targets, the unit the GA trains on (:class:`ismb_lab.tuning.cases.Case`).
solver
    A way to find the network's final state (:data:`ismb_lab.network.solvers.SOLVERS`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["euclidean_disparity", "horizontal_disparity", "vertical_disparity"]


def horizontal_disparity(left_xy, right_xy) -> np.ndarray:
    """Horizontal disparity ``x_left - x_right`` of matched points.

    >>> horizontal_disparity([[99, 99]], [[88, 100]])
    array([11.])
    """
    return np.asarray(left_xy, float)[..., 0] - np.asarray(right_xy, float)[..., 0]


def vertical_disparity(left_xy, right_xy) -> np.ndarray:
    """Vertical disparity ``y_right - y_left`` of matched points.

    >>> vertical_disparity([[99, 99]], [[88, 100]])
    array([1.])
    """
    return np.asarray(right_xy, float)[..., 1] - np.asarray(left_xy, float)[..., 1]


def euclidean_disparity(left_xy, right_xy) -> np.ndarray:
    """Euclidean disparity ``||p - q||``, as in the thesis' tables.

    Parameters
    ----------
    left_xy, right_xy : (n, 2) float array
        Matched points ``(x, y)``, row ``n`` with row ``n``.

    Returns
    -------
    disparity : (n,) float array
        ``||p - q||`` of each match.

    Examples
    --------

    >>> euclidean_disparity([[99, 99]], [[88, 100]]).round(2)   # Table 5.1, pair 1
    array([11.05])
    """
    diff = np.asarray(left_xy, float) - np.asarray(right_xy, float)
    return np.hypot(diff[..., 0], diff[..., 1])
