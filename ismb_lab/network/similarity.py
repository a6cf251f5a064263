"""Similarity of feature points and the candidate window (thesis 3-8 ... 3-10, §3.3).

``M[i, k]`` is the mean absolute difference of zero-mean grey windows (3-8, 3-9); the
transfer function (3-10) maps it to ``S`` in ``[-1, 1]``, and the compatibility ``X`` to ``C`` (3-13).
"""

from __future__ import annotations

import numbers

import numba
import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, check_points, message

__all__ = ["MAX_CANDIDATE_PAIRS", "MAX_WINDOW_VALUES", "candidate_mask", "mean_abs_difference", "no_match_cut",
           "patches", "transfer"]

_INF = float("inf")
#: Most values :func:`patches` returns (``N x size x size``), 800 MB of float64: 10**8.
MAX_WINDOW_VALUES = 10**8
#: Most (left, right) pairs :func:`candidate_mask` compares, one byte each in its mask: 10**8.
MAX_CANDIDATE_PAIRS = 10**8


def transfer(x, theta: float, lam: float) -> np.ndarray:
    """The thesis' transfer function ``2 / (1 + exp(lam * (x - theta))) - 1`` (3-10, 3-13).

    Evaluated as the identical ``-tanh(lam * (x - theta) / 2)``, which never overflows.
    `theta` is the value of `x` where the output crosses zero, `lam` the steepness (Fig. 3.3).

    Parameters
    ----------
    x : float or array
        The measure (``M`` or ``X``).
    theta : float or array
        Where the output crosses zero.
    lam : float or array
        Steepness.

    Returns
    -------
    y : float array
        In ``[-1, 1]``, broadcast from the inputs.

    Raises
    ------
    ParameterError
        A non-finite `theta` or `lam`.

    Examples
    --------
    >>> transfer([0.0, 10.0, 1e6], theta=10.0, lam=2.0).round(4)
    array([ 1.,  0., -1.])
    >>> transfer([1.0], theta=float("nan"), lam=2.0)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'theta' parameter of transfer must be a finite number. Got nan instead.
    """
    if not (type(theta) is float and type(lam) is float and abs(theta) < _INF and abs(lam) < _INF):
        theta, lam = _finite(theta, "theta"), _finite(lam, "lam")
    with np.errstate(over="ignore"):   # lam (x - theta) beyond a float is +-inf, and tanh of it +-1
        return -np.tanh(0.5 * lam * (np.asarray(x, dtype=float) - theta))


def _finite(value, name: str):
    """`value`, a finite number or an array of them (a GA's column of parameters), for transfer."""
    if isinstance(value, numbers.Real):
        return check_number(value, name, "transfer")
    try:
        finite = np.all(np.isfinite(np.asarray(value, dtype=float)))
    except (TypeError, ValueError):
        raise ParameterTypeError(message(name, "transfer", "a finite number or an array of them", value)) from None
    if not finite:
        raise ParameterError(message(name, "transfer", "a finite number or an array of them",
                                     "an array with NaN or infinite values"))
    return value


def patches(image: np.ndarray, xy, size: int) -> np.ndarray:
    """Zero-mean square grey windows ``V = I - mean(I)`` centred on points (3-9).

    Points ``(x, y)`` are rounded to the nearest pixel.  The odd `size` is at most
    ``2 min(H, W) - 1``, as windows that cross the border are completed by mirroring
    (``BORDER_REFLECT_101``); the ``(N, size, size)`` result holds at most
    :data:`MAX_WINDOW_VALUES` values.

    Examples
    --------
    >>> patches(np.arange(25.0).reshape(5, 5), [[2, 2]], 3)[0]
    array([[-6., -5., -4.],
           [-1.,  0.,  1.],
           [ 4.,  5.,  6.]])
    """
    own = "patches"
    image = np.asarray(image, dtype=float)
    if image.ndim != 2 or image.size == 0:
        raise ParameterError(message("image", own, "a non-empty 2-D grey image", f"an array of shape {image.shape}"))
    # the mirror completes a window only while it reaches back no further than the image
    most = 2 * min(image.shape) - 1
    size = check_number(size, "size", own, low=1, high=most, integer=True)
    if size % 2 == 0:
        raise ParameterError(f"The 'size' parameter of patches must be an odd integer. Got {size} instead.")
    xy = check_points(xy, "xy", own)
    if len(xy) * size * size > MAX_WINDOW_VALUES:
        raise ParameterError(message("size", own, f"a window of which the {len(xy)} points' windows hold at most "
                                     f"{MAX_WINDOW_VALUES} values (N x size x size)", size))
    half = size // 2
    padded = np.pad(image, half, mode="reflect")
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
    """The dissimilarity ``M[i, k]`` of every left/right feature pair (3-8), in grey levels.

    `size` is the odd window side (the thesis does not state it).  ``M`` equals, bit for
    bit, ``np.abs(lp[:, None] - rp[None]).mean(axis=2)`` of the flattened windows, without
    that ``N_l x N_r x size²`` array: the compiled loop repeats NumPy's pairwise summation.

    Examples
    --------
    >>> img = np.random.default_rng(0).uniform(0, 255, (40, 40))
    >>> M = mean_abs_difference(img, img + 30, [[10, 10], [20, 25]], [[10, 10], [20, 25]], 7)
    >>> np.diag(M)            # a constant brightness offset does not matter
    array([0., 0.])
    """
    lp = patches(left, left_xy, size).reshape(-1, size * size)
    rp = patches(right, right_xy, size).reshape(-1, size * size)
    return _mean_abs_difference(np.ascontiguousarray(lp, dtype=float), np.ascontiguousarray(rp, dtype=float))


@numba.njit(cache=True)
def _block_sum(a, lo, n):
    """NumPy's summation of at most 128 terms: eight partial sums, then the rest."""
    if n < 8:
        s = 0.0
        for t in range(lo, lo + n):
            s += a[t]
        return s
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    stop = lo + n - n % 8
    for t in range(lo + 8, stop, 8):
        r0 += a[t]
        r1 += a[t + 1]
        r2 += a[t + 2]
        r3 += a[t + 3]
        r4 += a[t + 4]
        r5 += a[t + 5]
        r6 += a[t + 6]
        r7 += a[t + 7]
    s = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    for t in range(stop, lo + n):
        s += a[t]
    return s


@numba.njit(cache=True)
def _pairwise_sum(a, n):
    """NumPy's pairwise summation of ``a[:n]``: blocks of at most 128 terms, above that the
    sum of two halves (the first a multiple of 8 long).  On an explicit stack, as numba's
    cache does not keep recursive functions."""
    if n <= 128:
        return _block_sum(a, 0, n)
    lo = np.empty(64, dtype=np.int64)
    size = np.empty(64, dtype=np.int64)
    stage = np.empty(64, dtype=np.int64)
    values = np.empty(64)
    top, depth = 0, 0
    lo[0], size[0], stage[0] = 0, n, 0
    while top >= 0:
        m = size[top]
        if m <= 128:
            values[depth] = _block_sum(a, lo[top], m)
            depth += 1
            top -= 1
            continue
        half = m // 2
        half -= half % 8
        if stage[top] == 0:
            stage[top] = 1
            top += 1
            lo[top], size[top], stage[top] = lo[top - 1], half, 0
        elif stage[top] == 1:
            stage[top] = 2
            top += 1
            lo[top], size[top], stage[top] = lo[top - 1] + half, m - half, 0
        else:
            depth -= 1
            values[depth - 1] = values[depth - 1] + values[depth]
            top -= 1
    return values[0]


@numba.njit(cache=True)
def _mean_abs_difference(lp, rp):
    n_left, d = lp.shape
    if d > 128:
        out = np.empty((n_left, rp.shape[0]))
        row = np.empty(d)
        for i in range(n_left):
            for k in range(rp.shape[0]):
                for t in range(d):
                    row[t] = abs(lp[i, t] - rp[k, t])
                out[i, k] = _pairwise_sum(row, d) / d
        return out
    return _mean_abs_difference_small(lp, rp)


@numba.njit(cache=True)
def _mean_abs_difference_small(lp, rp):
    """``M`` for windows of at most 128 pixels, with :func:`_block_sum`'s additions per pair.

    Right windows are stored pixel-major, so the innermost loop runs over right windows in
    a row of memory and vectorises.
    """
    n_left, d = lp.shape
    n_right = rp.shape[0]
    by_pixel = np.ascontiguousarray(rp.T)
    out = np.empty((n_left, n_right))
    partial = np.empty((8, n_right))
    stop = d - d % 8 if d >= 8 else 0
    for i in range(n_left):
        x, o = lp[i], out[i]
        partial[:] = 0.0
        for t in range(stop):
            xt, r, acc = x[t], by_pixel[t], partial[t % 8]
            for k in range(n_right):
                acc[k] += abs(xt - r[k])
        if stop:
            for k in range(n_right):
                o[k] = (((partial[0, k] + partial[1, k]) + (partial[2, k] + partial[3, k]))
                        + ((partial[4, k] + partial[5, k]) + (partial[6, k] + partial[7, k])))
        else:
            o[:] = 0.0
        for t in range(stop, d):
            xt, r = x[t], by_pixel[t]
            for k in range(n_right):
                o[k] += abs(xt - r[k])
        for k in range(n_right):
            o[k] /= d
    return out


def no_match_cut(dissimilarity) -> float:
    """Half the median of ``M`` over all feature pairs: the dissimilarity a match must beat.

    Nearly all pairs are unrelated, so the median is a typical wrong match in this pair's
    own contrast.  The peer matchers' no-match cost, and Method-NM3's ``theta_s``; 1.0
    when there are no pairs.

    Parameters
    ----------
    dissimilarity : (N_l, N_r) float array
        ``M``.

    Returns
    -------
    cut : float
        Half the median, at least machine epsilon.

    Examples
    --------
    >>> no_match_cut([[2.0, 40.0], [40.0, 3.0]])
    10.75
    """
    M = np.asarray(dissimilarity, dtype=float)
    return max(float(np.median(M)) / 2, np.finfo(float).eps) if M.size else 1.0


def candidate_mask(left_xy, right_xy, *, shift: float = 20.0, height: float = 30.0,
                   width: float = 40.0) -> np.ndarray:
    """Which right features are candidates for each left feature (§3.3).

    Right feature ``k`` is a candidate of left feature ``i`` when it lies in the
    ``height x width`` window centred at ``(x_i - shift, y_i)``, borders included (the
    thesis: 30 x 40 px, ``shift = 20``).  At most :data:`MAX_CANDIDATE_PAIRS` pairs.

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
    if len(lxy) * len(rxy) > MAX_CANDIDATE_PAIRS:
        raise ParameterError(message("right_xy", "candidate_mask", f"points whose pairs with the {len(lxy)} left "
                                     f"points number at most {MAX_CANDIDATE_PAIRS}", f"{len(rxy)} points"))
    mask = np.empty((len(lxy), len(rxy)), dtype=bool)
    rows = max(1, (1 << 22) // max(len(rxy), 1))   # the float differences a few rows at a time
    for start in range(0, len(lxy), rows):
        part = lxy[start:start + rows]
        dx = rxy[None, :, 0] - (part[:, None, 0] - shift)
        dy = rxy[None, :, 1] - part[:, None, 1]
        mask[start:start + rows] = (np.abs(dx) <= width / 2) & (np.abs(dy) <= height / 2)
    return mask
