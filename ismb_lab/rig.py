"""Chessboard calibration of a fixed two-camera rig: intrinsics, baseline and rectification maps.

A rig whose cameras do not move relative to each other is calibrated once from a few pairs
of a printed chessboard: OpenCV finds the inner corners (``cv2.findChessboardCorners``,
refined with ``cv2.cornerSubPix``), calibrates each camera (``cv2.calibrateCamera``), then
the pair (``cv2.stereoCalibrate`` with those intrinsics fixed), and ``cv2.stereoRectify``
turns the result into the two rectifying maps, the rectified focal length ``f`` (pixels)
and the baseline ``B`` (metres).  Then depth is ``Z = f B / d`` for a disparity ``d``
(:func:`ismb_lab.depth.metric_depth`).

The board's square size sets the scale of everything metric: ``B`` and ``Z`` are
proportional to it, and nothing else depends on it.

The rig keeps each pair's detected corners, its reprojection error and the board's pose
(format ``ismb_lab-rig-v2``; v1 files, without them, still load), so a pair can be dropped
and the rig recalibrated without finding the boards again (:func:`recalibrate`).  A pair is
marked as an outlier when its error exceeds both three times the median of the pairs and
0.5 px (:func:`outliers`).  On OpenCV's sample, pair 02 is at 1.22 px, 4.5 times the median
(0.27 px), and is marked; once it is dropped, the worst pair is 2.1 times the median
(0.515 against 0.246 px): twice the median would mark it, three times does not.  The 0.5 px
floor keeps a rig whose pairs are all good from marking any.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_number, message
from .rectify import Rectified, load_photo, measured

__all__ = ["BOARD", "SQUARE_M", "BoardPair", "Rig", "board_depth", "calibrate_rig", "find_board", "load_rig",
           "outliers", "recalibrate"]

#: Inner corners of OpenCV's sample board (columns, rows).
BOARD = (9, 6)
#: Square size assumed for OpenCV's sample board, in metres.  The sample does not state it
#: (its calibration program takes the size as an argument and defaults to 1 unit); 25 mm is
#: a common printed board and gives a baseline of a few centimetres, as the rig's two small
#: cameras suggest.  Every metric result scales with it.
SQUARE_M = 0.025
#: Fewest pairs in which the board is found in both views for a calibration.
MIN_PAIRS = 3
_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-6)
FORMAT = "ismb_lab-rig-v2"
_FORMATS = ("ismb_lab-rig-v1", FORMAT)
#: A pair is an outlier above both this many times the pairs' median error and `OUTLIER_PX`.
OUTLIER_RATIO = 3.0
OUTLIER_PX = 0.5
#: Above this rectified zoom (rectified focal length over the cameras' own), the rig warns.
MAX_ZOOM = 1.3


def _u8(image) -> np.ndarray:
    return np.clip(np.rint(np.asarray(image, dtype=float)), 0, 255).astype(np.uint8)


def find_board(image, board=BOARD) -> np.ndarray | None:
    """The board's inner corners ``(x, y)``, refined to sub-pixel, or None when not found."""
    grey = _u8(image)
    found, corners = cv2.findChessboardCorners(grey, tuple(board), cv2.CALIB_CB_ADAPTIVE_THRESH
                                               + cv2.CALIB_CB_NORMALIZE_IMAGE)
    if not found:
        return None
    corners = cv2.cornerSubPix(grey, corners, (11, 11), (-1, -1), _CRITERIA)
    return corners.reshape(-1, 2).astype(float)


def _board_points(board, square_m: float) -> np.ndarray:
    cols, rows = board
    grid = np.zeros((rows * cols, 3), np.float32)
    grid[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_m
    return grid


@dataclass(frozen=True, eq=False)
class BoardPair:
    """One calibration pair: its photos' names, the board's corners found in each, the
    board's pose in the left camera (``rvec``, ``tvec`` as ``cv2.Rodrigues`` vectors, metres)
    and the pair's RMS reprojection error over both views, in pixels."""

    left: str
    right: str
    left_corners: np.ndarray
    right_corners: np.ndarray
    rms_px: float = float("nan")
    rvec: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    tvec: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))

    def __post_init__(self):
        for name in ("left_corners", "right_corners"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.ndim != 2 or value.shape[1] != 2 or not len(value) or not np.isfinite(value).all():
                raise ParameterError(message(name, "BoardPair", "finite (x, y) corners, one row each",
                                             f"shape {value.shape}"))
            object.__setattr__(self, name, value)
        if self.left_corners.shape != self.right_corners.shape:
            raise ParameterError(message("right_corners", "BoardPair", "as many corners as left_corners",
                                         f"{len(self.right_corners)} against {len(self.left_corners)}"))
        for name in ("rvec", "tvec"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float).reshape(3))

    @property
    def names(self) -> tuple:
        return (self.left, self.right)

    def to_dict(self) -> dict:
        return {"left": self.left, "right": self.right, "rms_px": self.rms_px, "rvec": self.rvec.tolist(),
                "tvec": self.tvec.tolist(), "left_corners": self.left_corners.tolist(),
                "right_corners": self.right_corners.tolist()}


def outliers(pairs) -> tuple:
    """Indices of the pairs whose error is above both three times the median and 0.5 px.

    >>> outliers([BoardPair("a", "b", [[0, 0]], [[0, 0]], e) for e in (0.2, 0.3, 0.25, 1.2, 0.4)])
    (3,)
    """
    errors = np.array([p.rms_px for p in pairs], dtype=float)
    if not len(errors):
        return ()
    limit = max(OUTLIER_RATIO * float(np.median(errors)), OUTLIER_PX)
    return tuple(int(i) for i in np.flatnonzero(errors > limit))


@dataclass(frozen=True, eq=False)
class Rig:
    """A calibrated rig (see the module's description).

    Attributes
    ----------
    size : (int, int)
        Image width and height the rig was calibrated at.
    k_left, d_left, k_right, d_right : ndarray
        Camera matrices and distortion coefficients.
    rotation, translation : ndarray
        The right camera's pose relative to the left one (metres).
    rms : float
        Reprojection error of the stereo calibration, in pixels.
    board, square_m
        The board used.
    used, skipped : tuple of str
        Names of the pairs used, and of those where the board was not found in both views.
    pairs : tuple of BoardPair
        The used pairs' corners, poses and errors (empty for a rig read from a v1 file).
    """

    size: tuple
    k_left: np.ndarray
    d_left: np.ndarray
    k_right: np.ndarray
    d_right: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    rms: float
    board: tuple = BOARD
    square_m: float = SQUARE_M
    used: tuple = ()
    skipped: tuple = ()
    pairs: tuple = ()
    _rect: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        _check_rig(self, "Rig")

    def _rectification(self) -> dict:
        if not self._rect:
            r1, r2, p1, p2, q, _, _ = cv2.stereoRectify(self.k_left, self.d_left, self.k_right, self.d_right,
                                                          tuple(self.size), self.rotation, self.translation,
                                                          flags=cv2.CALIB_ZERO_DISPARITY, alpha=0)
            self._rect.update(r1=r1, r2=r2, p1=p1, p2=p2, q=q)
        return self._rect

    @property
    def focal_px(self) -> float:
        """Focal length of the rectified views, in pixels."""
        return float(self._rectification()["p1"][0, 0])

    @property
    def baseline_m(self) -> float:
        """Distance between the two rectified camera centres, in metres."""
        p2 = self._rectification()["p2"]
        return float(abs(p2[0, 3] / p2[0, 0]))

    @property
    def zoom(self) -> float:
        """How much the rectified views are enlarged: their focal length over the smaller of the
        cameras' own.  Near 1 for a good rig (0.97 on OpenCV's sample); a poorly constrained
        distortion makes the crop to valid pixels zoom in (1.9 with its pairs 03, 05, 14 alone)."""
        return self.focal_px / min(float(self.k_left[0, 0]), float(self.k_right[0, 0]))

    def cropped(self) -> tuple:
        """Names of the pairs whose board has a corner outside a rectified view."""
        rect, (w, h) = self._rectification(), self.size
        out = []
        for pair in self.pairs:
            for corners, k, d, r, p in ((pair.left_corners, self.k_left, self.d_left, rect["r1"], rect["p1"]),
                                        (pair.right_corners, self.k_right, self.d_right, rect["r2"], rect["p2"])):
                xy = cv2.undistortPoints(corners.reshape(-1, 1, 2), k, d, R=r, P=p).reshape(-1, 2)
                if not ((xy >= 0).all() and (xy[:, 0] <= w - 1).all() and (xy[:, 1] <= h - 1).all()):
                    out.append(pair.left)
                    break
        return tuple(out)

    def warnings(self) -> tuple:
        """What makes this rig's rectified views doubtful, each naming the fix."""
        found = []
        if self.zoom > MAX_ZOOM:
            found.append(f"the rectified views are zoomed {self.zoom:.2f}x (above {MAX_ZOOM}x): the lens "
                         "distortion is poorly constrained; calibrate with more pairs, or with poses that put "
                         "the board near the corners and tilted")
        cropped = self.cropped()
        if cropped:
            found.append(f"the board leaves the rectified view in {len(cropped)} pair(s) ({', '.join(cropped)}); "
                         "calibrate with more pairs, or with different poses")
        return tuple(found)

    def maps(self):
        """The ``cv2.remap`` maps of the left and the right view."""
        rect = self._rectification()
        make = lambda k, d, r, p: cv2.initUndistortRectifyMap(k, d, r, p, tuple(self.size), cv2.CV_32FC1)
        return (make(self.k_left, self.d_left, rect["r1"], rect["p1"]),
                make(self.k_right, self.d_right, rect["r2"], rect["p2"]))

    def rectify(self, left, right) -> Rectified:
        """Rectify a pair of this rig exactly (no matching needed; the figures are measured
        on robust matches afterwards).  A pair of another size is refused."""
        owner = "Rig.rectify"
        left, right = load_photo(left, "left", owner), load_photo(right, "right", owner)
        for name, image in (("left", left), ("right", right)):
            if (image.shape[1], image.shape[0]) != tuple(self.size):
                raise ParameterError(message(name, owner, f"a {self.size[0]}x{self.size[1]} photo, the size the "
                                             "rig was calibrated at", f"{image.shape[1]}x{image.shape[0]}"))
        (lx, ly), (rx, ry) = self.maps()
        warp = lambda image, mx, my: cv2.remap(image.astype(np.float32), mx, my, cv2.INTER_LINEAR).astype(float)
        return measured(warp(left, lx, ly), warp(right, rx, ry), np.eye(3), np.eye(3), "rig")

    def to_dict(self) -> dict:
        return {"format": FORMAT, "size": list(self.size), "rms_px": self.rms,
                "focal_px": self.focal_px, "baseline_m": self.baseline_m, "zoom": self.zoom,
                "cropped": list(self.cropped()), "board": list(self.board),
                "square_m": self.square_m, "used": list(self.used), "skipped": list(self.skipped),
                "k_left": self.k_left.tolist(), "d_left": self.d_left.ravel().tolist(),
                "k_right": self.k_right.tolist(), "d_right": self.d_right.ravel().tolist(),
                "rotation": self.rotation.tolist(), "translation": self.translation.ravel().tolist(),
                "pairs": [pair.to_dict() for pair in self.pairs]}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)


def _check_camera(k, d, name: str, owner: str) -> None:
    rule = "a camera matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with finite fx, fy > 0 and cx, cy"
    k = np.asarray(k, dtype=float)
    if (k.shape != (3, 3) or not np.isfinite(k).all() or not (k[0, 0] > 0 and k[1, 1] > 0)
            or not np.allclose(k[2], (0, 0, 1)) or k[1, 0] != 0):
        raise ParameterError(message(f"k_{name}", owner, rule, k.tolist()))
    d = np.asarray(d, dtype=float)
    if d.size not in (4, 5, 8, 12, 14) or not np.isfinite(d).all():
        raise ParameterError(message(f"d_{name}", owner, "4, 5, 8, 12 or 14 finite distortion "
                                     "coefficients", d.ravel().tolist()))


def _check_rig(rig: Rig, owner: str) -> None:
    """Refuse a rig that cannot rectify: it would give black images or a crash, not an error."""
    size = rig.size
    if (len(size) != 2 or not all(isinstance(v, (int, np.integer)) and 1 <= v <= 1 << 16 for v in size)):
        raise ParameterError(message("size", owner, f"(width, height), whole numbers from 1 to {1 << 16}",
                                     tuple(size)))
    for name, k, d in (("left", rig.k_left, rig.d_left), ("right", rig.k_right, rig.d_right)):
        _check_camera(k, d, name, owner)
    r = np.asarray(rig.rotation, dtype=float)
    if r.shape != (3, 3) or not np.isfinite(r).all() or not np.allclose(r @ r.T, np.eye(3), atol=1e-6) \
            or not np.linalg.det(r) > 0:
        raise ParameterError(message("rotation", owner, "a 3x3 rotation matrix", r.tolist()))
    t = np.asarray(rig.translation, dtype=float)
    if t.size != 3 or not np.isfinite(t).all() or not np.linalg.norm(t) > 0:
        raise ParameterError(message("translation", owner, "a finite (x, y, z) offset of the right camera, "
                                     "not zero (a baseline > 0)", t.ravel().tolist()))
    if not (np.isfinite(rig.focal_px) and rig.focal_px > 0 and np.isfinite(rig.baseline_m)
            and rig.baseline_m > 0):
        raise ParameterError(message("k_left", owner, "cameras that rectify to a finite focal length > 0",
                                     f"focal length {rig.focal_px} px, baseline {rig.baseline_m} m"))


def load_rig(source) -> Rig:
    """A rig from ``ismb-lab calibrate``'s JSON (a path or the text), validated."""
    owner = "load_rig"
    try:
        text = Path(source).read_text() if not str(source).lstrip().startswith("{") else str(source)
        data = json.loads(text)
    except (OSError, ValueError) as exc:
        raise ParameterError(message("source", owner, "a readable rig JSON file", f"{source} ({exc})")) from None
    if not isinstance(data, dict) or data.get("format") not in _FORMATS:
        raise ParameterError(message("source", owner, "a rig file written by 'ismb-lab calibrate' "
                                     f"(format {' or '.join(_FORMATS)})", str(source)))
    try:
        arr = lambda key, shape: np.asarray(data[key], dtype=float).reshape(shape)
        rig = Rig(tuple(int(v) for v in data["size"]), arr("k_left", (3, 3)), arr("d_left", (1, -1)),
                  arr("k_right", (3, 3)), arr("d_right", (1, -1)), arr("rotation", (3, 3)),
                  arr("translation", (3, 1)), float(data["rms_px"]), tuple(data["board"]),
                  float(data["square_m"]), tuple(data.get("used", ())), tuple(data.get("skipped", ())),
                  tuple(BoardPair(str(p["left"]), str(p["right"]), p["left_corners"], p["right_corners"],
                                  float(p["rms_px"]), p["rvec"], p["tvec"]) for p in data.get("pairs", ())))
    except ParameterError as exc:   # a degenerate rig: name the file
        raise ParameterError(str(exc).replace("of Rig", f"of the rig file {str(source)!r}")) from None
    except (KeyError, TypeError, ValueError, OverflowError) as exc:
        raise ParameterError(message("source", owner, "a complete rig file", f"{source} ({exc})")) from None
    return rig


def calibrate_rig(pairs, board=BOARD, square_m: float = SQUARE_M, progress=None) -> Rig:
    """Calibrate a rig from chessboard pairs.

    Parameters
    ----------
    pairs : sequence of (name, left, right)
        Images as paths, bytes or grey arrays, all of one size.
    board : (int, int)
        Inner corners per row and per column.
    square_m : float
        Side of one square, in metres.
    progress : callable, optional
        Called once per pair (for a progress bar).

    Returns
    -------
    Rig
        Pairs where the board is not found in both views are skipped and named in
        ``Rig.skipped``.

    Raises
    ------
    ParameterError
        Fewer than 3 usable pairs, or images of different sizes.
    """
    owner = "calibrate_rig"
    square_m = check_number(square_m, "square_m", owner, low=0, low_open=True)
    if (not isinstance(board, (tuple, list)) or len(board) != 2
            or not all(isinstance(v, (int, np.integer)) and v >= 2 for v in board)):
        raise ParameterTypeError(message("board", owner, "two integers >= 2 (inner corners per row, per column)",
                                         board))
    found_pairs, used, skipped, size = [], [], [], None
    for name, left, right in pairs:
        names = _photo_name(left, f"{name} left"), _photo_name(right, f"{name} right")
        left, right = load_photo(left, f"left {name}", owner), load_photo(right, f"right {name}", owner)
        here = (left.shape[1], left.shape[0])
        if size is None:
            size = here
        if here != size or right.shape != left.shape:
            raise ParameterError(message("pairs", owner, f"images all of one size ({size[0]}x{size[1]})",
                                         f"pair {name}: {here[0]}x{here[1]} and {right.shape[1]}x{right.shape[0]}"))
        found = find_board(left, board), find_board(right, board)
        if progress is not None:
            progress(name)
        if found[0] is None or found[1] is None:
            skipped.append(str(name))
            continue
        found_pairs.append(BoardPair(*names, *found))
        used.append(str(name))
    return _calibrate(found_pairs, tuple(used), tuple(skipped), size, tuple(board), square_m, owner)


def _photo_name(photo, default: str) -> str:
    return Path(photo).name if isinstance(photo, (str, Path)) else default


def _calibrate(pairs, used, skipped, size, board, square_m, owner) -> Rig:
    """The rig from the corners already found: each camera, then the pair with them fixed."""
    if len(pairs) < MIN_PAIRS:
        raise ParameterError(message("pairs", owner, f"at least {MIN_PAIRS} pairs with the {board[0]}x{board[1]} "
                                     "board found in both views", f"{len(pairs)} (skipped: {', '.join(skipped)})"))
    objects = [_board_points(board, square_m)] * len(pairs)
    left_points = [p.left_corners.astype(np.float32) for p in pairs]
    right_points = [p.right_corners.astype(np.float32) for p in pairs]
    _, k_l, d_l, _, _ = cv2.calibrateCamera(objects, left_points, size, None, None)
    _, k_r, d_r, _, _ = cv2.calibrateCamera(objects, right_points, size, None, None)
    rms, k_l, d_l, k_r, d_r, rotation, translation, _, _, rvecs, tvecs, per_view = cv2.stereoCalibrateExtended(
        objects, left_points, right_points, k_l, d_l, k_r, d_r, size, None, None, criteria=_CRITERIA,
        flags=cv2.CALIB_FIX_INTRINSIC)
    # per_view holds each view's RMS; both views have as many corners, so the pair's is their quadratic mean.
    errors = np.sqrt(np.mean(np.square(per_view), axis=1))
    pairs = tuple(BoardPair(p.left, p.right, p.left_corners, p.right_corners, float(e), r, t)
                  for p, e, r, t in zip(pairs, errors, rvecs, tvecs))
    return Rig(tuple(size), k_l, d_l, k_r, d_r, rotation, translation, float(rms), tuple(board), square_m,
               tuple(used), tuple(skipped), pairs)


def recalibrate(rig: Rig, drop=()) -> Rig:
    """`rig` calibrated again from its own corners without the pairs named in `drop` (a
    pair is named by its left or its right photo, or by its name in ``rig.used``).

    Raises
    ------
    ParameterError
        A rig without corners (read from a v1 file), a name that is no pair of the rig, or
        fewer than 3 pairs left.
    """
    owner = "recalibrate"
    if not rig.pairs:
        raise ParameterError(message("rig", owner, "a rig that keeps its pairs' corners (format "
                                     f"{FORMAT}); calibrate it again from the photos", "a rig without them"))
    drop = (drop,) if isinstance(drop, str) else tuple(str(name) for name in drop)
    known = lambda name: any(name in (*p.names, u) for p, u in zip(rig.pairs, rig.used))
    unknown = [name for name in drop if not known(name)]
    if unknown:
        raise ParameterError(message("drop", owner, "photos of the rig's pairs ("
                                     + ", ".join(p.left for p in rig.pairs) + ")", ", ".join(unknown)))
    kept = [(p, u) for p, u in zip(rig.pairs, rig.used) if not set(drop) & {*p.names, u}]
    return _calibrate([p for p, _ in kept], tuple(u for _, u in kept), rig.skipped, tuple(rig.size),
                      tuple(rig.board), rig.square_m, owner)


def board_depth(rig: Rig, left, right) -> dict:
    """The board's depth in a pair of `rig`, two ways, in the left rectified camera's frame.

    ``"stereo"``: the board's corners found in both rectified views, ``Z = f B / d`` of each,
    the median.  ``"pnp"``: the board's pose from ``cv2.solvePnP`` on the left view alone,
    its corners' depths rotated into the rectified frame, the median.  The two use the rig
    differently (disparity and baseline against the board's known size), so their
    agreement checks the calibration.
    """
    owner = "board_depth"
    rectified = rig.rectify(left, right)
    corners = find_board(rectified.left, rig.board), find_board(rectified.right, rig.board)
    if corners[0] is None or corners[1] is None:
        raise ParameterError(message("left", owner, "a pair showing the whole board in both views",
                                     "a pair where it was not found"))
    disparity = corners[0][:, 0] - corners[1][:, 0]
    stereo = rig.focal_px * rig.baseline_m / disparity
    raw = find_board(load_photo(left, "left", owner), rig.board)
    if raw is None:
        raise ParameterError(message("left", owner, "a photo showing the whole board", "one where it was not found"))
    grid = _board_points(rig.board, rig.square_m)
    ok, rvec, tvec = cv2.solvePnP(grid, raw.astype(np.float32), rig.k_left, rig.d_left)
    pose, _ = cv2.Rodrigues(rvec)
    in_camera = grid @ pose.T + tvec.reshape(1, 3)
    in_rectified = in_camera @ rig._rectification()["r1"].T
    return {"stereo": float(np.median(stereo)), "pnp": float(np.median(in_rectified[:, 2])),
            "disparity_px": [float(disparity.min()), float(disparity.max())]}
