"""Harris corners (thesis chapter 2).

``M`` is the structure tensor of the image gradients averaged over a Gaussian window; its
response ``R = det(M) - k tr(M)^2`` is positive at corners, negative on straight edges and zero
in flat regions.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
from scipy import ndimage as ndi

from .._core.validation import ParameterError, ParameterTypeError, check_number, message

__all__ = ["MAX_SIGMA", "Corners", "check_roi", "detect_corners", "harris_from_tensor", "harris_response", "image_gradients",
           "resolve_roi", "structure_tensor"]


#: Largest Gaussian window (sigma, pixels) of the structure tensor: a wider one blurs every corner away.
MAX_SIGMA = 50.0


def _check_sigma(sigma, owner: str) -> float:
    return check_number(sigma, "sigma", owner, low=0, low_open=True, high=MAX_SIGMA)


def _check_image(image, owner: str) -> np.ndarray:
    rule = "a non-empty 2-D array of finite float or unsigned integer values"
    image = np.asarray(image)
    if not (np.issubdtype(image.dtype, np.floating)
            or np.issubdtype(image.dtype, np.unsignedinteger)):
        raise ParameterTypeError(message("image", owner, rule, f"an array of dtype {image.dtype}"))
    if image.ndim != 2 or image.size == 0:
        raise ParameterError(message("image", owner, rule, f"an array of shape {image.shape}"))
    image = image.astype(np.float64)
    if not np.all(np.isfinite(image)):
        raise ParameterError(message("image", owner, rule, "an array with NaN or infinite values"))
    return image


def _check_k(k, owner: str) -> float:
    k = check_number(k, "k", owner, low=0, low_open=True, high=0.25)
    if k == 0.25:   # then R = -(l1 - l2)^2 / 4 <= 0 everywhere: no corner can exist
        raise ParameterError(message("k", owner, "a finite number > 0 and < 0.25", k))
    return k


def image_gradients(image) -> tuple[np.ndarray, np.ndarray]:
    """Image derivatives ``(dI/dx, dI/dy)`` by the 3x3 Sobel operator, divided by 8.

    ``x`` grows along columns, ``y`` down the rows.  Dividing by 8 makes a ramp rising by 1 per
    pixel give exactly 1.  Borders are mirrored without repeating the edge pixel (``'mirror'``).

    >>> Ix, Iy = image_gradients(np.tile(np.arange(4.0), (3, 1)))   # I = x
    >>> Ix[1]
    array([0., 1., 1., 0.])
    >>> bool(np.all(Iy == 0))
    True
    """
    image = _check_image(image, "image_gradients")
    Ix = ndi.sobel(image, axis=1, mode="mirror") / 8.0
    Iy = ndi.sobel(image, axis=0, mode="mirror") / 8.0
    return Ix, Iy


def structure_tensor(image, sigma: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Harris matrix ``M = [[Axx, Axy], [Axy, Ayy]]`` at every pixel: the products of the
    gradients averaged over a Gaussian window of `sigma` pixels (``'mirror'`` borders).

    Parameters
    ----------
    image : (H, W) float or unsigned integer array
        Grey image, finite values.
    sigma : float, default 1.0
        Standard deviation of the Gaussian window, pixels (> 0, at most :data:`MAX_SIGMA`).

    Returns
    -------
    Axx, Axy, Ayy : (H, W) float64 array
        The tensor's entries at every pixel.

    Examples
    --------
    >>> Axx, Axy, Ayy = structure_tensor(np.tile(np.arange(9.0), (9, 1)))
    >>> float(Axx[4, 4]), float(Axy[4, 4]), float(Ayy[4, 4])
    (1.0, 0.0, 0.0)
    """
    sigma = _check_sigma(sigma, "structure_tensor")
    Ix, Iy = image_gradients(image)
    return tuple(ndi.gaussian_filter(p, sigma, mode="mirror") for p in (Ix * Ix, Ix * Iy, Iy * Iy))


def harris_from_tensor(Axx, Axy, Ayy, k: float = 0.04) -> np.ndarray:
    """Harris response ``det(M) - k tr(M)^2`` of a structure tensor (the thesis: k from 0.04 to 0.06).

    Parameters
    ----------
    Axx, Axy, Ayy : float or array
        The tensor's entries (:func:`structure_tensor`).
    k : float, default 0.04
        Harris ``k``, in (0, 0.25).

    Returns
    -------
    R : float64 array
        The response, shaped as the entries.

    Examples
    --------
    >>> float(harris_from_tensor(1.0, 0.0, 1.0))    # corner: two strong directions
    0.84
    >>> float(harris_from_tensor(1.0, 0.0, 0.0))    # edge: one direction
    -0.04
    """
    k = _check_k(k, "harris_from_tensor")
    Axx, Axy, Ayy = (np.asarray(a, dtype=np.float64) for a in (Axx, Axy, Ayy))
    return Axx * Ayy - Axy ** 2 - k * (Axx + Ayy) ** 2


def harris_response(image, sigma: float = 1.0, k: float = 0.04) -> np.ndarray:
    """Harris response ``R`` of every pixel (see :func:`structure_tensor`, :func:`harris_from_tensor`).

    Parameters
    ----------
    image : (H, W) float or unsigned integer array
        Grey image, finite values.
    sigma : float, default 1.0
        Gaussian window of the structure tensor, pixels.
    k : float, default 0.04
        Harris ``k``, in (0, 0.25).

    Returns
    -------
    R : (H, W) float64 array
        Positive at corners, negative on edges, zero in flat regions.

    Examples
    --------
    >>> img = np.zeros((20, 20)); img[10:, 10:] = 100.0     # one bright quadrant
    >>> R = harris_response(img)
    >>> bool(R[10, 10] > 0), bool(R[15, 10] < 0), bool(R[2, 2] == 0)
    (True, True, True)
    """
    k = _check_k(k, "harris_response")
    sigma = _check_sigma(sigma, "harris_response")
    return harris_from_tensor(*structure_tensor(image, sigma), k)


def resolve_roi(roi, shape) -> tuple[int, int, int, int]:
    """The region of interest as an ``(x, y, w, h)`` box inside an image of `shape` ``(H, W)``.

    `roi` is ``"center"`` (the centre quarter, a ``W//2 x H//2`` box at ``(W//4, H//4)``, as in
    the thesis' tables), ``"full"``, ``(x, y, w, h)`` or ``"X,Y,W,H"``.

    >>> resolve_roi("center", (240, 320))
    (80, 60, 160, 120)
    >>> resolve_roi("10, 20, 30, 40", (240, 320))
    (10, 20, 30, 40)
    >>> resolve_roi((300, 0, 30, 10), (240, 320))
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'roi' parameter of resolve_roi must be ... inside the 320x240 (width x height)
    image. Got (300, 0, 30, 10) instead.
    """
    height, width = (int(n) for n in shape)
    rule = ("'center', 'full', (x, y, w, h) or 'X,Y,W,H' with integers w, h >= 1 and the box "
            f"inside the {width}x{height} (width x height) image")
    box = _roi_box(roi, rule)
    if box in ("center", "full"):
        return (width // 4, height // 4, max(1, width // 2), max(1, height // 2)) if box == "center" else \
            (0, 0, width, height)
    x, y, w, h = box
    if w < 1 or h < 1 or x < 0 or y < 0 or x + w > width or y + h > height:
        raise ParameterError(message("roi", "resolve_roi", rule, roi))
    return box


def check_roi(roi, owner: str):
    """`roi`, its form checked before any image is read (see :func:`resolve_roi`).

    >>> check_roi("10,20,30,40", "MatchConfig")
    '10,20,30,40'
    >>> check_roi("1,2,3", "MatchConfig")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'roi' parameter of MatchConfig must be 'center', 'full', (x, y, w, h) or 'X,Y,W,H' with integers x, y >= 0 and w, h >= 1. Got '1,2,3' instead.
    """
    rule = "'center', 'full', (x, y, w, h) or 'X,Y,W,H' with integers x, y >= 0 and w, h >= 1"
    box = _roi_box(roi, rule, owner)
    if box not in ("center", "full") and (box[0] < 0 or box[1] < 0 or box[2] < 1 or box[3] < 1):
        raise ParameterError(message("roi", owner, rule, roi))
    return roi


def _roi_box(roi, rule: str, owner: str = "resolve_roi"):
    """``"center"``, ``"full"`` or the ``(x, y, w, h)`` that `roi` spells, whatever the image."""
    if isinstance(roi, str):
        name = roi.strip().lower()
        if name in ("center", "full"):
            return name
        parts = [p.strip() for p in name.split(",")]
        if len(parts) != 4 or not all(p.lstrip("+-").isdigit() and len(p) <= 19 for p in parts):
            raise ParameterError(message("roi", owner, rule, roi))
        return tuple(int(p) for p in parts)
    if isinstance(roi, (tuple, list, np.ndarray)):
        if len(roi) != 4 or not all(isinstance(v, numbers.Integral) and not isinstance(v, bool)
                                    for v in roi):
            raise ParameterError(message("roi", owner, rule, roi))
        return tuple(int(v) for v in roi)
    raise ParameterTypeError(message("roi", owner, rule, roi))


@dataclass(frozen=True, eq=False)
class Corners:
    """Harris corners of one image: ``xy`` in full-image coordinates, sorted row-major, with
    their ``response``; the final ``threshold`` T (NaN when there was no candidate and none was
    given), how many ``iterations`` relaxed it, the ``roi`` box searched, and a ``message``
    saying why fewer than ``n_min`` were found (empty otherwise).

    Attributes
    ----------
    xy : (n, 2) float64 array
        Corners ``(x, y)`` in the full image, row-major.
    response : (n,) float64 array
        Their Harris response ``R``.
    threshold : float
        The final threshold ``T``.
    iterations : int
        How many times ``T`` was relaxed.
    roi : tuple of int
        The ``(x, y, w, h)`` box searched.
    message : str
        Why fewer than ``n_min`` were found, or "".
    """

    xy: np.ndarray
    response: np.ndarray
    threshold: float
    iterations: int
    roi: tuple[int, int, int, int]
    message: str = ""

    def __len__(self) -> int:
        return len(self.xy)


def _local_maxima(R, box, border: int, min_distance: int):
    """Rows, columns and values of the positive local maxima of ``R`` in `box`, by ``(-R, y, x)``;
    of tied maxima within `min_distance` (Chebyshev) the first in row-major order survives."""
    size = 2 * min_distance + 1
    peak = (R == ndi.maximum_filter(R, size=size, mode="nearest")) & (R > 0)
    x, y, w, h = box
    inside = np.zeros_like(peak)
    H, W = R.shape
    inside[max(y, border):min(y + h, H - border), max(x, border):min(x + w, W - border)] = True
    rows, cols = np.nonzero(peak & inside)
    values = R[rows, cols]
    order = np.lexsort((cols, rows, -values))
    taken = np.zeros(R.shape, dtype=bool)
    keep = []
    for i in order:
        r, c = rows[i], cols[i]
        if not taken[r, c]:
            keep.append(i)
            taken[max(r - min_distance, 0):r + size - min_distance,
                  max(c - min_distance, 0):c + size - min_distance] = True
    keep = np.asarray(keep, dtype=int)
    return rows[keep], cols[keep], values[keep]


def _relaxations(start: float, target: float, relax: float) -> int:
    """Fewest ``m >= 0`` with ``start * relax**m <= target`` (by logarithms: a loop could take billions)."""
    if start <= target:
        return 0
    m = max(1, math.ceil((math.log(target) - math.log(start)) / math.log(relax)))
    # one step either way corrects the rounding of the logarithms
    if start * relax ** m > target:
        m += 1
    elif m > 1 and start * relax ** (m - 1) <= target:
        m -= 1
    return m


def detect_corners(image, *, roi="center", n_min: int = 20, n_max: int = 30,
                   threshold: float | None = None, sigma: float = 1.0, k: float = 0.04,
                   min_distance: int = 3, relax: float = 0.8) -> Corners:
    """Harris corners inside a region of interest (thesis chapter 2, steps 1-3).

    1. Candidates are the positive local maxima of ``R`` (over a ``2 min_distance + 1`` square)
       inside `roi` and at least ``ceil(3 sigma) + 1`` pixels from the image edge.
    2. Keep those with ``R >= T``; while fewer than `n_min` are kept and some candidate is
       still below ``T``, relax ``T <- relax * T``.
    3. Keep the strongest `n_max` (ties: row-major order first).

    Parameters
    ----------
    image : (H, W) float or unsigned integer array
        Grey image, finite values.
    roi : str or tuple of int, default "center"
        Region searched (:func:`resolve_roi`).
    n_min, n_max : int, default 20, 30
        Fewest corners wanted and most corners kept (the thesis uses 20 and 30).
    threshold : float or None, default None
        Initial ``T``.  ``R`` scales with the fourth power of the contrast, so no fixed value
        suits every image; None starts at the strongest candidate.
    sigma : float, default 1.0
        Gaussian window of the structure tensor (:func:`structure_tensor`).
    k : float, default 0.04
        Harris ``k`` (:func:`harris_from_tensor`).
    min_distance : int, default 3
        Radius of the local-maximum square, pixels.
    relax : float, default 0.8
        Factor that lowers ``T``, in (0, 1).

    Returns
    -------
    Corners
        Sorted row-major; fewer than `n_min` (never an error) come with ``message`` saying why.

    Raises
    ------
    ParameterError, ParameterTypeError
        A bad image or a setting out of its range.

    Examples
    --------
    >>> img = np.zeros((40, 40)); img[10:30, 10:30] = 200.0     # one bright square
    >>> c = detect_corners(img, roi="full", n_min=4)
    >>> c.xy
    array([[10., 10.],
           [29., 10.],
           [10., 29.],
           [29., 29.]])
    >>> c.iterations, c.message
    (0, '')
    >>> detect_corners(np.zeros((40, 40))).message
    'no corners: the image is flat inside the ROI'
    """
    owner = "detect_corners"
    image = _check_image(image, owner)
    n_min = check_number(n_min, "n_min", owner, low=1, integer=True)
    n_max = check_number(n_max, "n_max", owner, low=n_min, integer=True)
    if threshold is not None:
        threshold = check_number(threshold, "threshold", owner, low=0, low_open=True)
    sigma = _check_sigma(sigma, owner)
    k = _check_k(k, owner)
    H, W = image.shape
    min_distance = check_number(min_distance, "min_distance", owner, low=1, integer=True)
    relax = check_number(relax, "relax", owner, low=0, low_open=True, high=1)
    if relax == 1:
        raise ParameterError(message("relax", owner, "a finite number > 0 and < 1", relax))
    box = resolve_roi(roi, image.shape)

    border = math.ceil(3 * sigma) + 1
    x, y, w, h = box
    searched = max(y, border) < min(y + h, H - border) and max(x, border) < min(x + w, W - border)
    if searched and image.min() < image.max():
        R = harris_response(image, sigma, k)
        # a radius beyond the image covers all of it, as the image's own size does
        rows, cols, values = _local_maxima(R, box, border, min(min_distance, max(H, W)))
    else:   # no pixel to search, or R = 0 everywhere: the same answer without computing R
        values = ()

    if len(values) == 0:
        inner = image[y:y + h, x:x + w]
        why = ("the image is flat inside the ROI" if inner.min() == inner.max() else
               f"R has no positive local maximum inside the ROI, at least {border} pixels "
               "from the image edge")
        start = math.nan if threshold is None else threshold
        return Corners(np.empty((0, 2)), np.empty(0), start, 0, box, f"no corners: {why}")

    start = float(values[0]) if threshold is None else threshold
    # values is sorted strongest first: reaching values[n_min - 1] yields n_min corners
    iterations = _relaxations(start, float(values[min(n_min, len(values)) - 1]), relax)
    T = start * relax ** iterations
    n = min(int(np.count_nonzero(values >= T)), n_max)
    rows, cols, values = rows[:n], cols[:n], values[:n]

    note = ""
    if n < n_min:
        note = (f"only {n} corner{'s' if n != 1 else ''} found, fewer than n_min={n_min}, "
                f"with T relaxed {iterations} times to {T:.3g}: R has no more positive local "
                f"maxima inside the ROI, at least {border} pixels from the image edge")
    order = np.lexsort((cols, rows))
    xy = np.stack([cols[order], rows[order]], axis=1).astype(np.float64)
    return Corners(xy, values[order].astype(np.float64), float(T), iterations, box, note)
