"""Similarity of feature points and the candidate window (thesis 3-8 ... 3-10, §3.3).

``M[i, k]`` is the mean absolute difference of the zero-mean grey windows around
left feature ``i`` and right feature ``k`` (3-8, 3-9); the transfer function
(3-10) maps it to ``S[i, k]`` in ``[-1, 1]``.  The same transfer function maps the
compatibility measure ``X`` to ``C`` (3-13).
"""

from __future__ import annotations

import numpy as np

from ._validation import ParameterError, check_number, check_points

__all__ = ["candidate_mask", "mean_abs_difference", "patches", "transfer"]


def transfer(x, theta: float, lam: float) -> np.ndarray:
    """The thesis' transfer function ``2 / (1 + exp(lam * (x - theta))) - 1``.

    Used for similarity (3-10) and compatibility (3-13).  It is evaluated as the
    identical ``-tanh(lam * (x - theta) / 2)``, which never overflows.

    Parameters
    ----------
    x : array_like
        Dissimilarity values (``M`` or ``X``); small means good.
    theta : float
        Tolerance: the value of `x` where the output crosses zero.
    lam : float
        Steepness: above 1 the output switches abruptly around `theta` (Fig. 3.3).

    Returns
    -------
    out : ndarray
        Values in ``[-1, 1]``: near 1 for ``x << theta``, near -1 for ``x >> theta``.

    Examples
    --------
    >>> transfer([0.0, 10.0, 1e6], theta=10.0, lam=2.0).round(4)
    array([ 1.,  0., -1.])
    """
    return -np.tanh(0.5 * lam * (np.asarray(x, dtype=float) - theta))


def patches(image: np.ndarray, xy, size: int) -> np.ndarray:
    """Zero-mean square grey windows centred on points (3-9).

    Parameters
    ----------
    image : (H, W) ndarray
        Grey image.
    xy : (N, 2) array_like
        Points ``(x, y)``; they are rounded to the nearest pixel.
    size : int
        Odd window side length.  Windows that cross the border are completed by
        mirroring the image (OpenCV's ``BORDER_REFLECT_101``).

    Returns
    -------
    windows : (N, size, size) ndarray
        ``V = I - mean(I)`` over each window.

    Examples
    --------
    >>> img = np.arange(25.0).reshape(5, 5)
    >>> patches(img, [[2, 2]], 3)[0]
    array([[-6., -5., -4.],
           [-1.,  0.,  1.],
           [ 4.,  5.,  6.]])
    """
    size = check_number(size, "size", "patches", low=1, integer=True)
    if size % 2 == 0:
        raise ParameterError(f"The 'size' parameter of patches must be an odd integer. Got {size} instead.")
    xy = check_points(xy, "xy", "patches")
    half = size // 2
    padded = np.pad(np.asarray(image, dtype=float), half, mode="reflect")
    cols = np.rint(xy[:, 0]).astype(int)
    rows = np.rint(xy[:, 1]).astype(int)
    offsets = np.arange(size)
    if len(xy) == 0:
        return np.zeros((0, size, size))
    windows = padded[rows[:, None, None] + offsets[None, :, None],
                     cols[:, None, None] + offsets[None, None, :]]
    return windows - windows.mean(axis=(1, 2), keepdims=True)


def mean_abs_difference(left: np.ndarray, right: np.ndarray, left_xy, right_xy,
                        size: int = 11) -> np.ndarray:
    """The dissimilarity ``M[i, k]`` of every left/right feature pair (3-8).

    Parameters
    ----------
    left, right : (H, W) ndarray
        The grey image pair.
    left_xy : (N_l, 2) array_like
    right_xy : (N_r, 2) array_like
        Feature points ``(x, y)``.
    size : int
        Odd side of the square window (the thesis does not state it).

    Returns
    -------
    M : (N_l, N_r) ndarray
        Mean absolute difference of the zero-mean windows, in grey levels.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> img = rng.uniform(0, 255, (40, 40))
    >>> M = mean_abs_difference(img, img + 30, [[10, 10], [20, 25]], [[10, 10], [20, 25]], 7)
    >>> np.diag(M)            # a constant brightness offset does not matter
    array([0., 0.])
    """
    lp = patches(left, left_xy, size).reshape(-1, size * size)
    rp = patches(right, right_xy, size).reshape(-1, size * size)
    return np.abs(lp[:, None, :] - rp[None, :, :]).mean(axis=2)


def candidate_mask(left_xy, right_xy, *, shift: float = 20.0, height: float = 30.0,
                   width: float = 40.0) -> np.ndarray:
    """Which right features are candidates for each left feature (§3.3).

    Right feature ``k`` is a candidate of left feature ``i`` when it lies in the
    ``height x width`` window centred at ``(x_i - shift, y_i)``, borders included:
    ``|x_k - (x_i - shift)| <= width / 2`` and ``|y_k - y_i| <= height / 2``.
    The thesis uses a 30 x 40 window and ``shift = 20`` px for its webcams.

    Parameters
    ----------
    left_xy : (N_l, 2) array_like
    right_xy : (N_r, 2) array_like
    shift : float
        Expected horizontal disparity, in pixels.
    height, width : float
        Window size in pixels.

    Returns
    -------
    mask : (N_l, N_r) bool ndarray
        ``True`` where the neuron ``y_ik`` is a candidate (it starts at 1).

    Examples
    --------
    >>> candidate_mask([[120, 100]], [[100, 100], [75, 100], [130, 100], [100, 116]])
    array([[ True, False, False, False]])
    """
    shift = check_number(shift, "shift", "candidate_mask")
    height = check_number(height, "height", "candidate_mask", low=0, low_open=True)
    width = check_number(width, "width", "candidate_mask", low=0, low_open=True)
    lxy = check_points(left_xy, "left_xy", "candidate_mask")
    rxy = check_points(right_xy, "right_xy", "candidate_mask")
    dx = rxy[None, :, 0] - (lxy[:, None, 0] - shift)
    dy = rxy[None, :, 1] - lxy[:, None, 1]
    return (np.abs(dx) <= width / 2) & (np.abs(dy) <= height / 2)
