"""Check and fix a hand-held stereo pair: robust matches, F with RANSAC, uncalibrated rectification.

The network's candidate window (thesis 3.3) assumes a point and its partner on one row.
:func:`rectify_pair` finds mutual SIFT matches (Lowe's ratio test), F by RANSAC (MAGSAC, 1 px),
warps both photos by Hartley's homographies (``cv2.stereoRectifyUncalibrated``), and shifts
them so that the left content starts at the top left and 98% of the disparities are positive.
Photos are first scaled to at most :data:`WORKING_SIDE` pixels, EXIF orientation applied.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from .._core.files import JsonRecord
from .._core.validation import ParameterError, ParameterTypeError, check_number, message
from .io import _is_path, _read, _to_grey, decode, grey_uint8

__all__ = ["ROW_SPREAD", "WORKING_SIDE", "Correspondences", "Rectified", "apply_rectification", "check_for_matching",
           "check_rectified", "epipole_warning", "load_photo", "measured", "negative_share", "photo_orientation",
           "row_spread_px", "sideways_step", "rectify_pair", "robust_matches", "working_size"]

#: Longest side, in pixels, that photos are scaled down to (Middlebury's Aloe stays whole).
WORKING_SIDE = 1600
#: Longest side of the copy that SIFT looks at (see :func:`robust_matches`).
DETECT_SIDE = 1024
#: Median row difference of the robust matches above which a pair is not rectified, as a share
#: of the image's longer side (SIFT's positions are only as fine as the image).
ROW_SPREAD = 1 / 640
#: Fewest RANSAC inliers that make a pair worth rectifying.
MIN_INLIERS = 20
_RATIO = 0.75


def row_spread_px(shape) -> float:
    """The largest median row difference (px) of a rectified pair of `shape`'s robust matches.

    >>> row_spread_px((480, 640)), row_spread_px((3000, 4000))
    (1.0, 6.25)
    """
    return ROW_SPREAD * max(shape[:2])


def negative_share(matches: "Correspondences", rows_px: float) -> tuple[float, int]:
    """The share of `matches` on their rows (``|dy| <= rows_px``) with a negative disparity (most
    negative: the photos were given right first), and how many are on their rows.

    >>> m = Correspondences(np.array([[10.0, 5], [20, 5], [30, 9]]), np.array([[12.0, 5], [25, 5], [20, 1]]))
    >>> negative_share(m, 1.0)
    (1.0, 2)
    """
    if not len(matches):
        return 0.0, 0
    on_rows = matches.abs_dy <= rows_px
    d = (matches.left_xy[:, 0] - matches.right_xy[:, 0])[on_rows]
    return (float(np.mean(d < 0)) if len(d) else 0.0), int(len(d))


def photo_orientation(source) -> int:
    """The EXIF orientation tag (1-8) of a photo's path or file bytes; 1 for an array or no tag.

    >>> photo_orientation(np.zeros((4, 4)))
    1
    """
    from .io import exif_orientation

    if isinstance(source, (bytes, bytearray, memoryview)):
        return exif_orientation(bytes(source))
    if _is_path(source):
        try:
            with open(source, "rb") as handle:
                return exif_orientation(handle.read(1 << 17))   # the APP1 segment is at most 64 kB
        except OSError:
            return 1
    return 1


#: The EXIF orientation that undoes each one (turning 90 degrees one way undoes the other).
_UNDO = {1: 1, 2: 2, 3: 3, 4: 4, 5: 5, 6: 8, 7: 7, 8: 6}


def load_photo(source, name: str = "photo", owner: str = "load_photo", *, upright: bool = True) -> np.ndarray:
    """A photo (path, file bytes or grey/RGB/RGBA array) as a grey float image in ``[0, 255]``,
    EXIF orientation applied unless `upright` is False.

    Parameters
    ----------
    source : str, Path, bytes or array
        A photo's path, its file's bytes, or a grey, RGB or RGBA array.
    name : str, default "photo"
        Name of `source` in error messages.
    owner : str, default "load_photo"
        Function named in error messages.
    upright : bool, default True
        Apply the EXIF orientation; False gives the pixels as stored.

    Returns
    -------
    image : (H, W) float64 array
        Grey values in ``[0, 255]``.

    Raises
    ------
    ParameterError
        An unreadable or undecodable photo, or one too large.
    ParameterTypeError
        `source` of another type.
    """
    from .io import orient

    image = _photo(source, name, owner, None)[0]
    return image if upright else orient(image, _UNDO[photo_orientation(source)])


def _photo(source, name: str, owner: str, max_side: int | None) -> tuple[np.ndarray, float]:
    """:func:`load_photo` scaled down to `max_side` before it becomes float64, and the factor."""
    if isinstance(source, np.ndarray):
        grey = _to_grey(source, name, owner, bgr=False)
        factor = 1.0 if max_side is None else working_size(grey.shape, max_side)
        return _scale(grey, factor), factor
    if isinstance(source, (bytes, bytearray, memoryview)):
        rule = "the bytes of an image file OpenCV can decode"
        error = lambda why: ParameterError(message(name, owner, rule, f"{len(source)} bytes: {why}"))  # noqa: E731
        image = decode(bytes(source), cv2.IMREAD_COLOR, error)   # the size limit, from the header
    elif _is_path(source):
        image = _read(str(source), name, owner)   # size limits, readable regular file, decodable
        if image.dtype == np.uint8:               # again with IMREAD_COLOR, which applies EXIF
            image = _read(str(source), name, owner, cv2.IMREAD_COLOR)
    else:
        raise ParameterTypeError(message(name, owner, "a path, the bytes of an image file or an array", source))
    if image.dtype == np.uint8 and image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
    factor = 1.0 if max_side is None else working_size(image.shape, max_side)
    if image.dtype == np.uint8 and factor < 1.0:
        return np.clip(_scale(image, factor), 0.0, 255.0), factor
    grey = _to_grey(image, name, owner, bgr=True)
    return _scale(grey, factor), factor


def working_size(shape, max_side: int = WORKING_SIDE) -> float:
    """The factor (at most 1) that brings an image of `shape` within `max_side` pixels."""
    return min(1.0, max_side / max(shape[:2]))


def _scale(image: np.ndarray, factor: float) -> np.ndarray:
    if factor >= 1.0:
        return image
    size = (max(1, round(image.shape[1] * factor)), max(1, round(image.shape[0] * factor)))
    return cv2.resize(image.astype(np.float32), size, interpolation=cv2.INTER_AREA).astype(float)


@dataclass(frozen=True, eq=False)
class Correspondences:
    """Matched points ``(x, y)`` of a left and a right image, row ``n`` with row ``n``."""

    left_xy: np.ndarray
    right_xy: np.ndarray

    def __len__(self) -> int:
        return len(self.left_xy)

    @property
    def abs_dy(self) -> np.ndarray:
        """(n,) float array: the row difference ``|y_left - y_right|`` of each match."""
        return np.abs(self.left_xy[:, 1] - self.right_xy[:, 1])


def robust_matches(left, right, *, max_features: int = 4000, rows_px: float | None = None) -> Correspondences:
    """SIFT keypoints matched both ways, kept when they pass the ratio test and are mutual.

    With `rows_px` (a pair rectified by a calibrated rig), a keypoint's candidates are only the
    keypoints within `rows_px` of its row at a positive disparity: on a repetitive texture the
    ratio test then compares against the keypoint's own row, not the whole pattern.

    >>> rng = np.random.default_rng(0)
    >>> img = cv2.GaussianBlur(rng.uniform(0, 255, (200, 240)), (0, 0), 2) * 3 % 255
    >>> m = robust_matches(img[:, 10:], img[:, :-10])
    >>> len(m) > 20, bool(np.allclose(m.left_xy[:, 0] - m.right_xy[:, 0], -10, atol=1))
    (True, True)
    """
    max_features = check_number(max_features, "max_features", "robust_matches", low=8, integer=True)
    if rows_px is not None:
        rows_px = check_number(rows_px, "rows_px", "robust_matches", low=0, low_open=True)
    sift = cv2.SIFT_create(nfeatures=max_features)
    # SIFT doubles its input first: a larger image would hold several hundred MB of pyramid
    factor = working_size(np.shape(left), DETECT_SIDE)
    as_u8 = lambda g: grey_uint8(_scale(np.asarray(g, dtype=float), factor))
    kl, dl = sift.detectAndCompute(as_u8(left), None)
    kr, dr = sift.detectAndCompute(as_u8(right), None)
    empty = Correspondences(np.zeros((0, 2)), np.zeros((0, 2)))
    if dl is None or dr is None or len(kl) < 2 or len(kr) < 2:
        return empty
    matcher = cv2.BFMatcher(cv2.NORM_L2)

    def passing(query, train):
        return {m[0].queryIdx: m[0].trainIdx for m in matcher.knnMatch(query, train, k=2)
                if len(m) == 2 and m[0].distance < _RATIO * m[1].distance}

    if rows_px is None:
        forward, backward = passing(dl, dr), passing(dr, dl)
    else:
        forward, backward = _row_passing(kl, dl, kr, dr, rows_px * factor)
    kept = sorted((q, t) for q, t in forward.items() if backward.get(t) == q)
    if not kept:
        return empty
    back = lambda points: (np.array(points, dtype=float) + 0.5) / factor - 0.5   # pixel centres
    lxy, rxy = back([kl[q].pt for q, _ in kept]), back([kr[t].pt for _, t in kept])
    # SIFT gives one point a keypoint per dominant orientation: keep each matched pair once
    _, first = np.unique(np.round(np.hstack([lxy, rxy]), 3), axis=0, return_index=True)
    first = np.sort(first)
    return Correspondences(lxy[first], rxy[first])


def _row_passing(kl, dl, kr, dr, rows_px: float) -> tuple:
    """The ratio test both ways among the keypoints of one row band at positive disparities."""
    pl, pr = np.array([k.pt for k in kl]), np.array([k.pt for k in kr])
    dl, dr = np.asarray(dl, np.float32), np.asarray(dr, np.float32)
    dist = np.sqrt(np.maximum((dl ** 2).sum(1)[:, None] + (dr ** 2).sum(1)[None, :] - 2 * dl @ dr.T, 0))
    band = (np.abs(pl[:, None, 1] - pr[None, :, 1]) <= rows_px) & (pl[:, None, 0] > pr[None, :, 0])
    dist = np.where(band, dist, np.inf)

    def passing(table):
        if table.shape[1] < 2:
            return {}
        two = np.partition(table, 1, axis=1)[:, :2]
        best = np.argmin(table, axis=1)
        ok = np.isfinite(two[:, 0]) & (two[:, 0] < _RATIO * two[:, 1])
        return {int(q): int(best[q]) for q in np.flatnonzero(ok)}

    return passing(dist), passing(dist.T)


def _dy_figures(left_xy, right_xy) -> dict:
    """Row differences, and the 2nd to 98th percentile of the disparities within 2 px of their row."""
    dy = np.abs(left_xy[:, 1] - right_xy[:, 1])
    d = (left_xy[:, 0] - right_xy[:, 0])[dy <= 2.0]
    span = [float(np.percentile(d, 2)), float(np.percentile(d, 98))] if len(d) else [0.0, 0.0]
    return {"median_abs_dy_px": float(np.median(dy)), "p90_abs_dy_px": float(np.percentile(dy, 90)),
            "disparity_range_px": span}


@dataclass(frozen=True, eq=False)
class Rectified(JsonRecord):
    """A rectified pair at the working size, and how it was made.

    ``left_h``, ``right_h`` are the homographies from the scaled inputs (the identity for a rig);
    ``inliers`` counts the correspondences (``left_xy``, ``right_xy``, after rectification) that
    the row differences and the 2nd to 98th percentile of ``x_left - x_right`` were measured on,
    and ``measured_on`` says which; ``scale`` is the factor the inputs were scaled by first.
    """

    left: np.ndarray
    right: np.ndarray
    left_h: np.ndarray
    right_h: np.ndarray
    method: str
    inliers: int
    median_abs_dy_px: float
    p90_abs_dy_px: float
    disparity_range_px: list
    scale: float
    left_xy: np.ndarray = field(repr=False, default=None)
    right_xy: np.ndarray = field(repr=False, default=None)
    measured_on: str = "RANSAC inliers"
    warnings: tuple = ()

    @property
    def size(self) -> list:
        """``[width, height]`` of the rectified images."""
        return [int(self.left.shape[1]), int(self.left.shape[0])]

    def to_dict(self) -> dict:
        """What ``ismb-lab rectify`` writes to ``rectify.json``.

        Returns
        -------
        data : dict
            Method, figures, size, scale and both homographies.
        """
        return {"method": self.method, "inliers": self.inliers, "measured_on": self.measured_on,
                "warnings": list(self.warnings), "median_abs_dy_px": self.median_abs_dy_px,
                "p90_abs_dy_px": self.p90_abs_dy_px, "disparity_range_px": list(self.disparity_range_px),
                "size": self.size, "scale": self.scale, "working_side": WORKING_SIDE,
                "left_homography": self.left_h.tolist(), "right_homography": self.right_h.tolist()}


def pair_inputs(left, right, owner: str, max_side: int):
    """Both photos grey, of one size, scaled by one factor so the longer side is <= `max_side`."""
    (left, factor), (right, other) = (_photo(left, "left", owner, max_side),
                                      _photo(right, "right", owner, max_side))
    if left.shape != right.shape or factor != other:
        raise ParameterError(message("right", owner, "a photo of the left one's size (take both with one "
                                     "camera and the same settings)",
                                     f"{right.shape[1]}x{right.shape[0]} beside {left.shape[1]}x{left.shape[0]}"
                                     + (" after scaling" if factor < 1 else "")))
    return left, right, factor


def _refuse_same(matches: Correspondences, owner: str) -> None:
    if len(matches) and np.percentile(np.hypot(*(matches.left_xy - matches.right_xy).T), 90) < 0.5:
        raise ParameterError(message("right", owner, "a photo taken after moving the camera a few centimetres "
                                     "sideways", f"the left photo again (90% of {len(matches)} matches moved < 0.5 px)"))


def _fundamental(matches: Correspondences, owner: str):
    n = len(matches)
    if n < MIN_INLIERS:
        raise ParameterError(message("right", owner, "a second, sharp view of the left photo's textured scene "
                                     f"(at least {MIN_INLIERS} robust matches)", f"{n} robust matches"))
    method = getattr(cv2, "USAC_MAGSAC", cv2.FM_RANSAC)
    F, mask = cv2.findFundamentalMat(matches.left_xy, matches.right_xy, method, 1.0, 0.999, 10000)
    inliers = np.zeros(n, bool) if mask is None else mask.ravel().astype(bool)
    if F is None or F.shape != (3, 3) or inliers.sum() < MIN_INLIERS:
        raise ParameterError(message("right", owner, f"a view of the left photo's scene (at least {MIN_INLIERS} "
                                     "matches agreeing on one epipolar geometry)",
                                     f"{int(inliers.sum())} of {n} matches agreeing"))
    # with a baseline, points at different depths move differently: no one homography fits them
    homography, fits = cv2.findHomography(matches.left_xy[inliers], matches.right_xy[inliers], cv2.RANSAC, 1.0)
    if homography is not None and fits.mean() >= 0.9:
        raise ParameterError(message("right", owner, "a view from a camera moved sideways, with parallax",
                                     f"no parallax: one homography fits {fits.mean():.0%} of the matches (the "
                                     "camera only turned, or the scene is flat)"))
    return F, inliers


def sideways_step(left_xy, right_xy, F, shape) -> float | None:
    """The x component of the camera's unit translation from the left photo to the right one
    (negative: taken to the right), or None when the pair does not say.

    A hand-held pair's turn and step forward shift every disparity alike, so the motion is
    found from `F` (``cv2.recoverPose``, an assumed focal length of one image width).  A motion
    that under 80% of the matches put in front of both cameras, or mostly forward
    (``|x| < 0.2``), decides nothing.

    >>> xy = np.random.default_rng(0).uniform(0, 400, (40, 2))
    >>> depth = np.random.default_rng(1).uniform(1, 2, 40)
    >>> shifted = xy - np.c_[40 / depth, np.zeros(40)]     # a right view: near points move more
    >>> F = np.array([[0, 0, 0], [0, 0, -1], [0, 1, 0]], float)
    >>> round(sideways_step(xy, shifted, F, (400, 400)), 3), round(sideways_step(shifted, xy, F, (400, 400)), 3)
    (-1.0, 1.0)
    """
    h, w = shape
    K = np.array([[w, 0, w / 2], [0, w, h / 2], [0, 0, 1]], float)
    left_xy, right_xy = np.asarray(left_xy, float), np.asarray(right_xy, float)
    if len(left_xy) < 5:
        return None
    good, _, t, _ = cv2.recoverPose(K.T @ F @ K, left_xy, right_xy, K)
    step = float(t.ravel()[0])
    return step if good >= 0.8 * len(left_xy) and abs(step) >= 0.2 else None


def _refuse_swapped(left_xy, right_xy, F, shape, owner: str) -> None:
    """Refuse a pair given right first: by its disparities' sign if its rows already agree (a
    pure sideways F leaves ``cv2.recoverPose`` guessing), else by :func:`sideways_step`."""
    limit = row_spread_px(shape)
    matches = Correspondences(np.asarray(left_xy, float), np.asarray(right_xy, float))
    if len(matches) and np.median(matches.abs_dy) <= limit:
        if _refuse_by_sign(matches, limit, owner) >= 8:
            return
    step = sideways_step(left_xy, right_xy, F, shape)
    if step is not None and step > 0:
        raise ParameterError(message("left", owner, "the left camera's photo, given first: swap the two files",
                                     f"the right camera's (its {len(left_xy)} robust matches put it to the "
                                     "right)"))


def _refuse_by_sign(matches: Correspondences, limit: float, owner: str) -> int:
    """Refuse a pair most of whose matches on their rows have a negative disparity; how many are."""
    share, n = negative_share(matches, 2 * limit)
    if n >= 8 and share > 0.5:
        raise ParameterError(message("left", owner, "the left camera's photo, given first: swap the two "
                                     "files", f"the right camera's ({share:.0%} of {n} robust matches have a "
                                     "negative disparity)"))
    return n


def check_for_matching(left, right, owner: str = "check_for_matching") -> str:
    """Refuse a swapped pair, and return a one-line warning for an unrectified one ("" if none).

    Measured on the robust matches of the grey pair as given; fewer than 8 say nothing.
    """
    matches = robust_matches(left, right)
    if len(matches) < 8:
        return ""
    limit = row_spread_px(np.shape(left))
    spread = float(np.median(matches.abs_dy))
    if spread > limit:
        return (f"warning: the pair is not rectified (the rows of its {len(matches)} robust matches differ by "
                f"{spread:.1f} px at the median): make it so with 'ismb-lab rectify LEFT RIGHT --out DIR'")
    _refuse_by_sign(matches, limit, owner)
    return ""


def epipole_warning(F, shape) -> str:
    """A one-line warning when an epipole lies within one image diagonal of its image, else "".

    Rectification sends the epipoles to infinity: the nearer one is, the more the framing changes
    with every small error in `F`.

    >>> F = np.array([[0, 0, 0], [0, 0, -1], [0, 1, 0]], float)   # sideways: epipoles at infinity
    >>> epipole_warning(F, (480, 640))
    ''
    """
    h, w = shape
    diagonal = float(np.hypot(w, h))
    for side, matrix in (("left", F), ("right", F.T)):
        e = np.linalg.svd(matrix)[2][-1]                      # matrix @ e = 0
        if abs(e[2]) < 1e-12 * np.abs(e[:2]).max():
            continue
        x, y = e[:2] / e[2]
        away = float(np.hypot(max(0.0, -x, x - w), max(0.0, -y, y - h)))
        if away < diagonal:
            return (f"warning: the {side} epipole lies {away:.0f} px from the image (within its {diagonal:.0f} px "
                    "diagonal): the camera moved forward more than sideways, so the rectified framing is "
                    "unstable; take the right photo after a sideways step")
    return ""


def _transform(h, xy) -> np.ndarray:
    return cv2.perspectiveTransform(np.asarray(xy, float).reshape(-1, 1, 2), h).reshape(-1, 2)


def _place(h_left, h_right, left_xy, right_xy, shape):
    """Move both homographies so the left content starts at (0, 0) and 98% of disparities are > 0."""
    h, w = shape
    corners = np.array([[0, 0], [w, 0], [w, h], [0, h]], float)
    box = _transform(h_left, corners)
    start = box.min(axis=0)
    shift = np.array([[1, 0, -start[0]], [0, 1, -start[1]], [0, 0, 1]], float)
    h_left, h_right = shift @ h_left, shift @ h_right
    d = _transform(h_left, left_xy)[:, 0] - _transform(h_right, right_xy)[:, 0]
    dx = 1.0 - np.percentile(d, 2)        # the 2nd percentile of the disparities at 1 px
    h_right = np.array([[1, 0, -dx], [0, 1, 0], [0, 0, 1]], float) @ h_right
    size = np.ceil(_transform(h_left, corners).max(axis=0)).astype(int)
    return h_left, h_right, (int(min(size[0], 2 * w)), int(min(size[1], 2 * h)))


def rectify_pair(left, right, *, max_side: int = WORKING_SIDE) -> Rectified:
    """Rectify a hand-held stereo pair (left camera's first, one size; see the module).

    Both are scaled so the longer side, also of the warped output, is at most `max_side`.  A pair
    whose inliers already agree (median ``|dy|`` <= 0.5 px, 90th percentile <= 1.5 px) is left
    as it is.  A ParameterError says in one sentence why a pair cannot be rectified.

    Parameters
    ----------
    left, right : str, Path, bytes or array
        The photos, the left camera's first, of one size.
    max_side : int, default WORKING_SIDE
        Longest side of the inputs and of the output, pixels (at least 64).

    Returns
    -------
    rectified : Rectified
        The rectified pair and how it was made.

    Raises
    ------
    ParameterError
        Photos of different sizes, too few matches, the same photo twice, no common epipolar
        geometry, no parallax, or the two photos swapped.
    """
    owner = "rectify_pair"
    max_side = check_number(max_side, "max_side", owner, low=64, integer=True)
    left, right, factor = pair_inputs(left, right, owner, max_side)
    F, n, lxy, rxy = _inliers(robust_matches(left, right), left.shape, owner)
    figures = _dy_figures(lxy, rxy)
    if _aligned(figures):
        eye = np.eye(3)
        return Rectified(left, right, eye, eye, "already rectified", n, **figures, scale=factor, left_xy=lxy,
                         right_xy=rxy)
    h, w = left.shape
    ok, h_left, h_right = cv2.stereoRectifyUncalibrated(lxy, rxy, F, (w, h))
    if not ok:
        raise ParameterError(message("right", owner, "a view OpenCV's uncalibrated rectification accepts",
                                     f"a pair it refused ({len(lxy)} inliers)"))
    h_left, h_right, size = _place(h_left, h_right, lxy, rxy, (h, w))
    shrink = working_size(size[::-1], max_side)
    if shrink < 1.0:       # the warp can enlarge the image: the output, too, stays within max_side
        scale = np.diag([shrink, shrink, 1.0])
        h_left, h_right, size = _place(scale @ h_left, scale @ h_right, lxy, rxy, (h, w))
        size = (min(size[0], max_side), min(size[1], max_side))
    lxy, rxy = _transform(h_left, lxy), _transform(h_right, rxy)
    warning = epipole_warning(F, (h, w))
    return Rectified(_warp(left, h_left, size), _warp(right, h_right, size), h_left,
                     h_right, "uncalibrated", n, **_dy_figures(lxy, rxy), scale=factor, left_xy=lxy,
                     right_xy=rxy, warnings=(warning,) if warning else ())


def _inliers(matches: Correspondences, shape, owner: str) -> tuple:
    """F, the number of RANSAC inliers and their points; the same photo twice or a swapped pair refused."""
    _refuse_same(matches, owner)
    F, inliers = _fundamental(matches, owner)
    lxy, rxy = matches.left_xy[inliers], matches.right_xy[inliers]
    _refuse_swapped(lxy, rxy, F, shape, owner)
    return F, int(inliers.sum()), lxy, rxy


def _aligned(figures: dict) -> bool:
    """Whether the rows already agree: the test that leaves a pair as it is."""
    return figures["median_abs_dy_px"] <= 0.5 and figures["p90_abs_dy_px"] <= 1.5


def apply_rectification(left, right, left_h, right_h, size) -> Rectified:
    """Warp a pair to `size` ``(width, height)`` by homographies found on another pair of the same
    camera positions (the depth demo's background), measured on new robust matches."""
    size = (int(size[0]), int(size[1]))
    return measured(_warp(left, left_h, size), _warp(right, right_h, size), left_h, right_h,
                    "the background's")


def _warp(image, h, size) -> np.ndarray:
    """`image` warped by the homography `h` to `size` (bilinear, 0 outside), clipped to ``[0, 255]``."""
    warped = cv2.warpPerspective(np.asarray(image, np.float32), np.asarray(h, float), size)
    return np.clip(warped.astype(float), 0, 255)


def measured(left, right, left_h, right_h, method: str) -> Rectified:
    """A pair rectified some other way, with its figures measured on new robust matches."""
    matches = robust_matches(left, right)
    figures = (_dy_figures(matches.left_xy, matches.right_xy) if len(matches) else
               {"median_abs_dy_px": float("nan"), "p90_abs_dy_px": float("nan"), "disparity_range_px": [0.0, 0.0]})
    return Rectified(left, right, np.asarray(left_h, float), np.asarray(right_h, float), method, len(matches),
                     **figures, scale=1.0, left_xy=matches.left_xy, right_xy=matches.right_xy,
                     measured_on="robust matches (no RANSAC)")


def check_rectified(left, right, *, max_side: int = WORKING_SIDE) -> dict:
    """How far a pair is from rectified, without warping it: :class:`Rectified`'s figures for the
    inliers as they are, with ``matches``, ``inliers``, ``rectified`` (:func:`rectify_pair`'s test),
    ``problem`` (why it cannot be rectified, or "") and the inliers ``left_xy``, ``right_xy``.

    Parameters
    ----------
    left, right : str, Path, bytes or array
        The photos, the left camera's first, of one size.
    max_side : int, default WORKING_SIDE
        Longest side the photos are scaled to, pixels.

    Returns
    -------
    figures : dict
        ``matches``, ``inliers``, ``rectified``, ``problem``, ``median_abs_dy_px``,
        ``p90_abs_dy_px``, ``disparity_range_px``, ``left_xy``, ``right_xy``.
    """
    owner = "check_rectified"
    left, right, _ = pair_inputs(left, right, owner, max_side)
    matches = robust_matches(left, right)
    out = {"matches": len(matches), "inliers": 0, "rectified": False, "problem": "",
           "median_abs_dy_px": None, "p90_abs_dy_px": None, "disparity_range_px": None,
           "left_xy": np.zeros((0, 2)), "right_xy": np.zeros((0, 2))}
    try:
        _, n, lxy, rxy = _inliers(matches, left.shape, owner)
    except ParameterError as exc:
        return {**out, "problem": str(exc)}
    figures = _dy_figures(lxy, rxy)
    return {**out, **figures, "inliers": n, "rectified": _aligned(figures), "left_xy": lxy, "right_xy": rxy}
