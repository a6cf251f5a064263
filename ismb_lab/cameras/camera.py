"""A stereo camera model: two cameras, their rectification, and metres from disparities.

The right camera's pose follows OpenCV: a point ``X`` of the left camera's frame is ``R X + T``
in the right one's.  A match at rectified left ``(x, y)`` with disparity ``d`` is the point
``Z = f B / d``, ``X = (x - cx) Z / f``, ``Y = (y - cy) Z / f`` (metres; X right, Y down, Z forward).
"""

from __future__ import annotations

import json
import math
import numbers
import re
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from .._core.files import JsonRecord
from .._core.validation import ParameterError, ParameterTypeError, check_number, check_points, message

__all__ = ["BASELINE_M", "BOARD", "FOCAL_PX", "MAX_BASELINE_M", "MAX_BOARD_SIDE", "MAX_SQUARE_M", "MAX_ZOOM",
           "MIN_SQUARE_M", "SQUARE_M", "FORMAT", "HEIGHT", "OPENCV_NAMES", "UNITS", "WIDTH", "BoardPair",
           "StereoCamera", "check_board", "load_camera"]

#: The rendered scenes' camera, like the thesis' webcams: 320 x 240 images, 10 cm apart; 300 px
#: gives a field of view of about 56 degrees, and 16.7 to 30 px of disparity from 1.8 m to 1 m.
WIDTH, HEIGHT = 320, 240
FOCAL_PX = 300.0
BASELINE_M = 0.10
#: Inner corners of OpenCV's sample board (columns, rows).
BOARD = (9, 6)
#: Square size assumed for OpenCV's sample board, in metres (the sample does not state it).
SQUARE_M = 0.025
#: The range of a board's square side (metres) and of its inner corners per row or column.
MIN_SQUARE_M, MAX_SQUARE_M = 1e-5, 10.0
MAX_BOARD_SIDE = 100
#: Format of the rig files (v1 files, without the pairs, still load).
FORMAT = "ismb_lab-rig-v2"
_FORMATS = ("ismb_lab-rig-v1", FORMAT)
#: Above this rectified zoom (rectified focal length over the cameras' own), the rig warns.
MAX_ZOOM = 1.3
#: The longest baseline a factory calibration may give, in metres (a longer one was typed in mm).
MAX_BASELINE_M = 10.0
#: The units a factory file's translation may be in, as metres per unit.
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}
#: The names an OpenCV ``FileStorage`` file may give each matrix (the first is the usual one).
OPENCV_NAMES = {"k_left": ("K1", "M1", "cameraMatrix1"), "d_left": ("D1", "distCoeffs1"),
                "k_right": ("K2", "M2", "cameraMatrix2"), "d_right": ("D2", "distCoeffs2"),
                "rotation": ("R",), "translation": ("T",)}


def _rotate(vectors: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """``vectors @ matrix.T`` for ``(N, 3)`` vectors (much faster than matmul for this shape)."""
    return np.stack([vectors @ row for row in matrix], axis=1)


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.sqrt(np.einsum("ij,ij->i", vectors, vectors))[:, None]


@dataclass(frozen=True, eq=False)
class BoardPair:
    """One calibration pair: photo names, board corners in each, the board's pose in the left
    camera (Rodrigues ``rvec``, ``tvec`` in metres) and the pair's RMS reprojection error (px)."""

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
        """tuple of str: ``(left, right)``."""
        return (self.left, self.right)

    def to_dict(self) -> dict:
        """The pair's record in a rig file (JSON-ready).

        Returns
        -------
        record : dict
            Names, error, pose and corners of the pair.
        """
        return {"left": self.left, "right": self.right, "rms_px": self.rms_px, "rvec": self.rvec.tolist(),
                "tvec": self.tvec.tolist(), "left_corners": self.left_corners.tolist(),
                "right_corners": self.right_corners.tolist()}


def _intrinsics(focal_px: float, cx: float, cy: float) -> np.ndarray:
    return np.array([[focal_px, 0.0, cx], [0.0, focal_px, cy], [0.0, 0.0, 1.0]])


@dataclass(frozen=True, eq=False)
class StereoCamera(JsonRecord):
    """Two cameras, their rectification and the calibration they came from.

    ``k_*`` and ``d_*`` are the camera matrices and distortions (None: :data:`FOCAL_PX` at the
    image centre, none); ``rotation`` and ``translation`` the right camera's pose (None:
    :data:`BASELINE_M` to the right); ``rms`` the calibration's reprojection error in pixels
    (NaN: none measured); ``used``, ``skipped`` and ``pairs`` the calibration's pairs.

    Attributes
    ----------
    size : tuple of int, default (320, 240)
        ``(width, height)`` of the images.
    k_left, k_right : (3, 3) float array, optional
        Camera matrices.
    d_left, d_right : (1, k) float array, optional
        Distortion coefficients.
    rotation : (3, 3) float array, optional
        Rotation from the left camera's frame to the right one's.
    translation : (3, 1) float array, optional
        Translation of the same transform, metres.
    rms : float, default NaN
        The calibration's RMS reprojection error, pixels.
    board : tuple of int, default BOARD
        Inner corners ``(columns, rows)`` of the calibration board.
    square_m : float, default SQUARE_M
        Side of its squares, metres.
    used, skipped : tuple of str
        Names of the pairs used and of those where the board was not found.
    pairs : tuple of BoardPair
        The corners of the pairs used.

    Raises
    ------
    ParameterError
        A bad size, matrix or distortion.

    Examples
    --------
    >>> camera = StereoCamera()
    >>> camera.focal_px, camera.baseline_m, camera.size
    (300.0, 0.1, (320, 240))
    >>> camera.points_from_disparity([[159.5, 119.5], [189.5, 89.5]], [30.0, 15.0])
    array([[ 0. ,  0. ,  1. ],
           [ 0.2, -0.2,  2. ]])
    """

    size: tuple = (WIDTH, HEIGHT)
    k_left: np.ndarray = None
    d_left: np.ndarray = None
    k_right: np.ndarray = None
    d_right: np.ndarray = None
    rotation: np.ndarray = None
    translation: np.ndarray = None
    rms: float = float("nan")
    board: tuple = BOARD
    square_m: float = SQUARE_M
    used: tuple = ()
    skipped: tuple = ()
    pairs: tuple = ()
    # The right camera's centre as `pinhole` was given it: the rendered scenes' rays are pinned bit for bit.
    _origin: np.ndarray = field(default=None, repr=False)
    _rect: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        size = tuple(self.size) if isinstance(self.size, (tuple, list)) else self.size
        if (not isinstance(size, tuple) or len(size) != 2
                or not all(isinstance(v, (int, np.integer)) and 1 <= v <= 1 << 16 for v in size)):
            raise ParameterError(message("size", "StereoCamera",
                                         f"(width, height), whole numbers from 1 to {1 << 16}", self.size))
        object.__setattr__(self, "size", tuple(int(v) for v in size))
        defaults = {"k_left": lambda: _intrinsics(FOCAL_PX, (size[0] - 1) / 2, (size[1] - 1) / 2),
                    "d_left": lambda: np.zeros((1, 5)), "rotation": lambda: np.eye(3),
                    "translation": lambda: np.array([[-BASELINE_M], [0.0], [0.0]])}
        for name in ("k_left", "d_left", "rotation", "translation"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, defaults[name]())
        for name, default in (("k_right", self.k_left), ("d_right", self.d_left)):
            if getattr(self, name) is None:
                object.__setattr__(self, name, default)
        _check(self, "StereoCamera")

    @classmethod
    def pinhole(cls, width: int = WIDTH, height: int = HEIGHT, focal_px: float = FOCAL_PX,
                baseline_m: float = BASELINE_M, vertical_offset_px: float = 0.0,
                roll_deg: float = 0.0) -> StereoCamera:
        """Two distortion-free cameras side by side, as the rendered scenes use.

        The principal point is the image centre.  The right image is shifted *down* by
        `vertical_offset_px`; a positive `roll_deg` turns the right camera's ``x`` axis towards
        its ``y`` axis (the scene turns counter-clockwise on screen).

        >>> cam = StereoCamera.pinhole()
        >>> float(cam.disparity_at(1.8)), float(cam.disparity_at(1.0))
        (16.666666666666668, 30.0)
        >>> cam.project_left([[0.0, 0.0, 2.0]]), cam.project_right([[0.0, 0.0, 2.0]])
        (array([[159.5, 119.5]]), array([[144.5, 119.5]]))
        >>> StereoCamera.pinhole(baseline_m=-0.1)
        Traceback (most recent call last):
        ...
        ismb_lab.ParameterError: The 'baseline_m' parameter of StereoCamera.pinhole must be a finite number > 0. Got -0.1 instead.
        """
        own = "StereoCamera.pinhole"
        width, height = (check_number(v, name, own, low=2, high=100_000, integer=True)
                         for v, name in ((width, "width"), (height, "height")))
        focal_px, baseline_m = (check_number(v, name, own, low=0, low_open=True)
                                for v, name in ((focal_px, "focal_px"), (baseline_m, "baseline_m")))
        offset = check_number(vertical_offset_px, "vertical_offset_px", own)
        roll = check_number(roll_deg, "roll_deg", own, low=-180, high=180)
        cx, cy = (width - 1) / 2, (height - 1) / 2
        a = math.radians(roll)
        c, s = math.cos(a), math.sin(a)
        to_left = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])   # right camera -> left frame
        origin = np.array([baseline_m, 0.0, 0.0])
        rotation = to_left.T
        return cls((width, height), _intrinsics(focal_px, cx, cy), np.zeros((1, 5)),
                   _intrinsics(focal_px, cx, cy + offset), np.zeros((1, 5)), rotation,
                   (-(rotation @ origin)).reshape(3, 1), _origin=origin)

    @classmethod
    def from_factory(cls, focal_px: float, baseline_m: float, size, centre=None) -> StereoCamera:
        """A rectified stereo camera from its factory calibration (OAK-D, RealSense, ZED, ...).

        Two distortion-free cameras with the rectified matrix, side by side: rectifying changes
        no pixel.  `centre` is the principal point (default: the image centre).  ``rms`` is NaN,
        so the search band is 1 px up and down (:func:`ismb_lab.matching.metric.row_tolerance`):
        a guessed smaller RMS would narrow the band and widen the auto disparity window.

        Parameters
        ----------
        focal_px : float
            Rectified focal length, pixels (> 0).
        baseline_m : float
            Baseline, metres (> 0, at most :data:`MAX_BASELINE_M`).
        size : tuple of int
            ``(width, height)`` of the images.
        centre : tuple of float, optional
            Principal point ``(cx, cy)``; default the image centre.

        Returns
        -------
        camera : StereoCamera
            A rectified camera.

        Raises
        ------
        ParameterError
            A value out of range, or a centre outside the image.

        Examples
        --------
        >>> cam = StereoCamera.from_factory(520.8, 0.0836, (640, 480), centre=(350.6, 243.1))
        >>> cam.focal_px, cam.baseline_m, cam.rectified_centre.tolist(), cam.is_rectified
        (520.8, 0.0836, [350.6, 243.1], True)
        >>> import math; math.isnan(cam.rms)
        True
        >>> StereoCamera.from_factory(520.8, 0.0, (640, 480))
        Traceback (most recent call last):
        ...
        ismb_lab.ParameterError: The 'baseline_m' parameter of StereoCamera.from_factory must be a finite number > 0 and <= 10.0. Got 0.0 instead.
        """
        own = "StereoCamera.from_factory"
        size = _check_size(size, own)
        focal_px = check_number(focal_px, "focal_px", own, low=0, low_open=True)
        baseline_m = check_number(baseline_m, "baseline_m", own, low=0, low_open=True, high=MAX_BASELINE_M)
        width, height = size
        if centre is None:
            centre = ((width - 1) / 2, (height - 1) / 2)
        rule = f"a principal point (cx, cy) inside the {width}x{height} image"
        if not isinstance(centre, (tuple, list, np.ndarray)) or len(centre) != 2:
            raise ParameterTypeError(message("centre", own, rule, centre))
        cx, cy = (check_number(v, "centre", own) for v in centre)
        if not (0 <= cx <= width - 1 and 0 <= cy <= height - 1):
            raise ParameterError(message("centre", own, rule, (cx, cy)))
        k = _intrinsics(focal_px, cx, cy)
        return cls(size, k, np.zeros((1, 5)), k.copy(), np.zeros((1, 5)), np.eye(3),
                   np.array([[-baseline_m], [0.0], [0.0]]))

    @classmethod
    def from_opencv(cls, *paths, size=None, units: str = "m") -> StereoCamera:
        """A rig from OpenCV ``FileStorage`` files (YAML, XML or JSON) of a stereo calibration.

        The matrices (:data:`OPENCV_NAMES`; ``R`` a matrix or a Rodrigues vector) may be split
        over several files, each given once.  `size` defaults to the files' ``image_width`` and
        ``image_height`` (or ``imageSize``); `units` is the unit of ``T`` (:data:`UNITS`).
        The rig has no measured RMS, so its search band is 1 px (see :meth:`from_factory`).

        Parameters
        ----------
        *paths : str or Path
            The ``FileStorage`` files.
        size : tuple of int, optional
            ``(width, height)``; default the files' own.
        units : {"m", "cm", "mm"}, default "m"
            Unit of ``T``.

        Returns
        -------
        camera : StereoCamera
            The rig.

        Raises
        ------
        ParameterError
            No file, a matrix missing or given twice, no size, or an implausible baseline.
        """
        own = "StereoCamera.from_opencv"
        if not paths:
            raise ParameterError(message("paths", own, "at least one FileStorage file", "none"))
        if not isinstance(units, str) or units not in UNITS:
            raise ParameterError(message("units", own, f"one of {', '.join(UNITS)}", units))
        found, given_size = {}, None
        for path in paths:
            read, file_size = _read_opencv(path, own)
            for name, value in read.items():
                if name in found:
                    raise ParameterError(message("paths", own, f"files that give {OPENCV_NAMES[name][0]} "
                                                 "once", f"it again in {str(path)!r}"))
                found[name] = value
            if file_size is not None:
                if given_size is not None and file_size != given_size:
                    raise ParameterError(message("paths", own, "files of one image size",
                                                 f"{given_size} and {file_size}"))
                given_size = file_size
        missing = [OPENCV_NAMES[name][0] for name in OPENCV_NAMES if name not in found]
        if missing:
            raise ParameterError(message("paths", own, "files that give K1, D1, K2, D2, R and T",
                                         f"no {', '.join(missing)} in {', '.join(map(str, paths))}"))
        if size is None:
            if given_size is None:
                raise ParameterError(message("size", own, "the image size (width, height), as the files do not "
                                             "give image_width and image_height", None))
            size = given_size
        size = _check_size(size, own)
        if given_size is not None and tuple(given_size) != size:
            raise ParameterError(message("size", own, f"the files' own image size {given_size[0]}x{given_size[1]}",
                                         f"{size[0]}x{size[1]}"))
        rotation = found["rotation"]
        if rotation.size == 3:
            rotation, _ = cv2.Rodrigues(rotation.reshape(3, 1))
        translation = found["translation"] * UNITS[units]
        if translation.size == 3 and np.linalg.norm(translation) > MAX_BASELINE_M:
            raise ParameterError(message("units", own, f"the unit of T that gives a baseline of at most "
                                         f"{MAX_BASELINE_M:g} m (millimetres: units='mm')",
                                         f"{units!r}, a baseline of {np.linalg.norm(translation):g} m"))
        try:
            return cls(size, found["k_left"], found["d_left"].reshape(1, -1), found["k_right"],
                       found["d_right"].reshape(1, -1), rotation, translation)
        except ParameterError as exc:   # name the file's own matrix
            text = str(exc)
            for name in OPENCV_NAMES:
                text = text.replace(f"'{name}' parameter of StereoCamera",
                                    f"'{OPENCV_NAMES[name][0]}' matrix of {', '.join(map(str, paths))}")
            raise ParameterError(text) from None

    @property
    def width(self) -> int:
        """int: image width, pixels."""
        return self.size[0]

    @property
    def height(self) -> int:
        """int: image height, pixels."""
        return self.size[1]

    @property
    def centre(self) -> np.ndarray:
        """Principal point ``(cx, cy)`` of the left camera."""
        return self.k_left[:2, 2].copy()

    @property
    def vertical_offset_px(self) -> float:
        """How far the right camera's principal point is below the left one's, in pixels."""
        return float(self.k_right[1, 2] - self.k_left[1, 2])

    @property
    def roll_deg(self) -> float:
        """The right camera's roll about its optical axis, in degrees (to 1e-9 degree)."""
        return round(math.degrees(math.atan2(self.rotation[0, 1], self.rotation[0, 0])), 9) + 0.0

    @property
    def right_origin(self) -> np.ndarray:
        """Optical centre of the right camera in the left camera's frame."""
        if self._origin is not None:
            return self._origin
        return -(self.rotation.T @ self.translation.reshape(3)) + 0.0   # + 0.0: no -0.0

    @property
    def distorted(self) -> bool:
        """Whether either camera has lens distortion."""
        return bool(np.any(self.d_left) or np.any(self.d_right))

    @property
    def is_rectified(self) -> bool:
        """Whether the cameras already are a rectified pair: one matrix, no distortion, no
        rotation, the right camera straight to the right.

        >>> StereoCamera().is_rectified, StereoCamera.pinhole(roll_deg=1).is_rectified
        (True, False)
        """
        t = self.translation.reshape(3)
        return bool(not self.distorted and np.array_equal(self.k_left, self.k_right)
                    and np.array_equal(self.rotation, np.eye(3)) and t[0] < 0 and t[1] == 0 and t[2] == 0)

    def _pixels(self, cam: np.ndarray, k: np.ndarray) -> np.ndarray:
        # this order of additions is the one the rendered scenes are pinned bit for bit with
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = self.centre + k[0, 0] * cam[:, :2] / cam[:, 2:3]
        xy += k[:2, 2] - self.k_left[:2, 2]
        xy[cam[:, 2] <= 0] = np.nan
        return xy

    def project_left(self, points3d) -> np.ndarray:
        """Left-image ``(x, y)`` of 3-D points (no distortion); NaN rows behind the camera.

        >>> StereoCamera().project_left([[0.1, -0.05, 1.0]])
        array([[189.5, 104.5]])
        """
        return self._pixels(check_points(points3d, "points3d", "StereoCamera.project_left", dims=3), self.k_left)

    def project_right(self, points3d) -> np.ndarray:
        """Right-image ``(x, y)`` of left-frame 3-D points (no distortion); NaN rows behind it.

        >>> StereoCamera.pinhole(vertical_offset_px=2).project_right([[0.1, -0.05, 1.0]])
        array([[159.5, 106.5]])
        """
        points = check_points(points3d, "points3d", "StereoCamera.project_right", dims=3)
        return self._pixels(_rotate(points - self.right_origin, self.rotation), self.k_right)

    def _dirs(self, xy: np.ndarray, k: np.ndarray) -> np.ndarray:
        d = np.empty((len(xy), 3))
        d[:, :2] = (xy - self.centre) / k[0, 0]
        d[:, 2] = 1.0
        return d

    def rays_left(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """Rays through left-image points: ``(origins, unit directions)``, both ``(N, 3)``.

        >>> StereoCamera().rays_left([[159.5, 119.5]])
        (array([[0., 0., 0.]]), array([[0., 0., 1.]]))
        """
        xy = check_points(xy, "xy", "StereoCamera.rays_left")
        d = self._dirs(xy, self.k_left)
        return np.zeros_like(d), _unit(d)

    def rays_right(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """Rays through right-image points, in the left camera's frame.

        >>> StereoCamera().rays_right([[159.5, 119.5]])
        (array([[0.1, 0. , 0. ]]), array([[0., 0., 1.]]))
        """
        xy = check_points(xy, "xy", "StereoCamera.rays_right") - (self.k_right[:2, 2] - self.k_left[:2, 2])
        d = self._dirs(xy, self.k_right)
        if not np.array_equal(self.rotation, np.eye(3)):
            d = _rotate(d, self.rotation.T)
        return np.broadcast_to(self.right_origin, d.shape).copy(), _unit(d)

    def _rectification(self) -> dict:
        if not self._rect:
            r1, r2, p1, p2, q, _, _ = cv2.stereoRectify(self.k_left, self.d_left, self.k_right, self.d_right,
                                                          tuple(self.size), self.rotation, self.translation,
                                                          flags=cv2.CALIB_ZERO_DISPARITY, alpha=0)
            focal, baseline = float(p1[0, 0]), float(abs(p2[0, 3] / p2[0, 0]))
            if not self.distorted:   # nothing to crop: keep the left camera's matrix
                origin = self.right_origin
                focal, baseline = float(self.k_left[0, 0]), float(np.sqrt(origin @ origin))
                p1 = np.hstack([self.k_left, np.zeros((3, 1))])
                p2 = p1.copy()
                p2[0, 3] = -focal * baseline
            self._rect.update(r1=r1, r2=r2, p1=p1, p2=p2, q=q, focal=focal, baseline=baseline)
        return self._rect

    @property
    def focal_px(self) -> float:
        """Focal length of the rectified views, in pixels."""
        return self._rectification()["focal"]

    @property
    def baseline_m(self) -> float:
        """Distance between the two rectified camera centres, in metres."""
        return self._rectification()["baseline"]

    @property
    def rectified_centre(self) -> np.ndarray:
        """Principal point ``(cx, cy)`` of the rectified left view."""
        return self._rectification()["p1"][:2, 2].copy()

    @property
    def left_to_rectified(self) -> np.ndarray:
        """Rotation from the left camera's frame to the rectified left camera's."""
        return self._rectification()["r1"].copy()

    def disparity_at(self, depth) -> np.ndarray:
        """Disparity ``focal_px * baseline_m / depth`` of the rectified pair, in pixels.

        >>> StereoCamera().disparity_at([1.0, 1.5])
        array([30., 20.])
        """
        return self.focal_px * self.baseline_m / np.asarray(depth, dtype=float)

    def points_from_disparity(self, xy_left, disparity) -> np.ndarray:
        """3-D points ``(X, Y, Z)`` in metres of rectified-left pixels and their disparities
        (``x_left - x_right``); NaN rows where the disparity is not > 0.

        Parameters
        ----------
        xy_left : (n, 2) float array
            Rectified-left pixels ``(x, y)``.
        disparity : (n,) float array
            Their disparities, pixels.

        Returns
        -------
        points : (n, 3) float array
            ``(X, Y, Z)`` in the rectified left frame, metres.

        Raises
        ------
        ParameterError
            Not one finite disparity per point.

        Examples
        --------
        >>> StereoCamera().points_from_disparity([[10.0, 20.0]], [0.0])
        array([[nan, nan, nan]])
        """
        own = "StereoCamera.points_from_disparity"
        xy = check_points(xy_left, "xy_left", own)
        d = np.asarray(disparity, dtype=float).reshape(-1)
        if len(d) != len(xy) or not np.all(np.isfinite(d)):
            raise ParameterError(message("disparity", own, f"{len(xy)} finite numbers, one per point of xy_left",
                                         f"{len(d)} values" if len(d) != len(xy) else "NaN or infinite values"))
        f, (cx, cy) = self.focal_px, self.rectified_centre
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(d > 0, f * self.baseline_m / d, np.nan)
        return np.stack([(xy[:, 0] - cx) * z / f, (xy[:, 1] - cy) * z / f, z], axis=1)

    @property
    def zoom(self) -> float:
        """The rectified focal length over the smaller of the cameras' own (near 1 for a good rig;
        a poorly constrained distortion makes the crop to valid pixels zoom in)."""
        return self.focal_px / min(float(self.k_left[0, 0]), float(self.k_right[0, 0]))

    def rectify_points(self, xy, side: str = "left") -> np.ndarray:
        """Raw-image points ``(x, y)`` of one camera in its rectified view."""
        rect = self._rectification()
        k, d, r, p = ((self.k_left, self.d_left, rect["r1"], rect["p1"]) if side == "left"
                      else (self.k_right, self.d_right, rect["r2"], rect["p2"]))
        xy = np.asarray(xy, dtype=float).reshape(-1, 1, 2)
        return cv2.undistortPoints(xy, k, d, R=r, P=p).reshape(-1, 2)

    def cropped(self) -> tuple:
        """Names of the pairs whose board has a corner outside a rectified view."""
        (w, h), out = self.size, []
        for pair in self.pairs:
            for corners, side in ((pair.left_corners, "left"), (pair.right_corners, "right")):
                xy = self.rectify_points(corners, side)
                if not ((xy >= 0).all() and (xy[:, 0] <= w - 1).all() and (xy[:, 1] <= h - 1).all()):
                    out.append(pair.left)
                    break
        return tuple(out)

    def warnings(self) -> tuple:
        """What makes this rig's rectified views doubtful, each naming the fix.

        Returns
        -------
        warnings : tuple of str
            One sentence each; empty for a sound rig.
        """
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

    def photos(self, left, right, owner: str = "StereoCamera.photos") -> tuple:
        """A pair of this camera's size loaded grey (:func:`ismb_lab.images.rectify.load_photo`).

        Parameters
        ----------
        left, right : str, Path, bytes or array
            The photos.
        owner : str, default "StereoCamera.photos"
            Function named in error messages.

        Returns
        -------
        left, right : (H, W) float array
            Grey images in ``[0, 255]``.

        Raises
        ------
        ParameterError
            A photo of another size than the rig's.
        """
        from ..images.rectify import load_photo

        left, right = load_photo(left, "left", owner), load_photo(right, "right", owner)
        for name, image in (("left", left), ("right", right)):
            if (image.shape[1], image.shape[0]) != tuple(self.size):
                raise ParameterError(message(name, owner, f"a {self.size[0]}x{self.size[1]} photo, the size the "
                                             "rig was calibrated at", f"{image.shape[1]}x{image.shape[0]}"))
        return left, right

    def rectify(self, left, right):
        """The pair rectified exactly, as a :class:`ismb_lab.images.rectify.Rectified`.

        Parameters
        ----------
        left, right : str, Path, bytes or array
            Photos of the rig's size.

        Returns
        -------
        rectified : Rectified
            The rectified pair, measured on new robust matches.
        """
        from ..images.rectify import measured

        left, right = self.photos(left, right, "StereoCamera.rectify")
        (lx, ly), (rx, ry) = self.maps()
        warp = lambda image, mx, my: cv2.remap(image.astype(np.float32), mx, my, cv2.INTER_LINEAR).astype(float)
        return measured(warp(left, lx, ly), warp(right, rx, ry), np.eye(3), np.eye(3), "rig")

    def to_dict(self) -> dict:
        """The rig file's record (:data:`FORMAT`); None for an unmeasured RMS or an unused board.

        Returns
        -------
        record : dict
            JSON-ready fields of the rig file.
        """
        boarded = bool(self.used)
        return {"format": FORMAT, "size": list(self.size), "rms_px": self.rms if math.isfinite(self.rms) else None,
                "focal_px": self.focal_px, "baseline_m": self.baseline_m, "zoom": self.zoom,
                "cropped": list(self.cropped()), "board": list(self.board) if boarded else None,
                "square_m": self.square_m if boarded else None, "used": list(self.used),
                "skipped": list(self.skipped),
                "k_left": self.k_left.tolist(), "d_left": self.d_left.ravel().tolist(),
                "k_right": self.k_right.tolist(), "d_right": self.d_right.ravel().tolist(),
                "rotation": self.rotation.tolist(), "translation": self.translation.ravel().tolist(),
                "pairs": [pair.to_dict() for pair in self.pairs]}


_RMS_RULE = ("a finite number > 0 (the calibration's RMS reprojection error in pixels, which sets the search "
             "band), or NaN when none was measured")


def _two_ints(value, name: str, owner: str, rule: str, low: int, high: int) -> tuple:
    """`value` as a tuple of two whole numbers from `low` to `high`."""
    if (not isinstance(value, (tuple, list)) or len(value) != 2
            or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in value)):
        raise ParameterTypeError(message(name, owner, rule, value))
    if not all(low <= v <= high for v in value):
        raise ParameterError(message(name, owner, rule, tuple(value)))
    return tuple(int(v) for v in value)


def _check_size(size, owner: str) -> tuple:
    return _two_ints(size, "size", owner, f"(width, height), whole numbers from 1 to {1 << 16}", 1, 1 << 16)


def _opencv_values(node) -> np.ndarray | None:
    """A FileStorage node's numbers (a matrix or a sequence), or None."""
    if node.isSeq():
        items = [node.at(i) for i in range(node.size())]
        if not all(item.isReal() or item.isInt() for item in items):
            return None
        return np.array([item.real() for item in items], dtype=float)
    if node.isReal() or node.isInt():
        return np.array([node.real()], dtype=float)
    value = node.mat()
    return None if value is None else np.asarray(value, dtype=float)


def _read_opencv(path, owner: str) -> tuple:
    """The matrices of one FileStorage file by :data:`OPENCV_NAMES`' keys, and its image size."""
    from .._core.files import MAX_JSON_BYTES

    shown = str(path)
    try:
        most = Path(path).stat().st_size
    except OSError as exc:
        raise ParameterError(message("paths", owner, f"a readable OpenCV FileStorage file ({exc.strerror})",
                                     shown)) from None
    if most > MAX_JSON_BYTES:
        raise ParameterError(message("paths", owner, f"a FileStorage file of at most {MAX_JSON_BYTES} bytes",
                                     f"{shown} ({most} bytes)"))
    try:
        storage = cv2.FileStorage(shown, cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError) as exc:   # a parse error can reach Python as a SystemError
        exc = exc.__cause__ if isinstance(exc, SystemError) and exc.__cause__ is not None else exc
        said = next((line for line in str(exc).splitlines() if "error:" in line), str(exc)).strip()
        said = re.sub(r"^.*?error: \([^)]*\)\s*", "", said)
        raise ParameterError(message("paths", owner, f"an OpenCV FileStorage file (YAML, XML or JSON) that "
                                     f"OpenCV can parse (it says: {said})", shown)) from None
    if not storage.isOpened():
        raise ParameterError(message("paths", owner, "an OpenCV FileStorage file (YAML, XML or JSON)", shown))
    try:
        found = {}
        for name, aliases in OPENCV_NAMES.items():
            for alias in aliases:
                node = storage.getNode(alias)
                if node.empty():
                    continue
                if name in found:
                    raise ParameterError(message("paths", owner, f"a file that gives {aliases[0]} once "
                                                 f"(as one of {', '.join(aliases)})", f"two of them in {shown}"))
                values = _opencv_values(node)
                if values is None or not values.size or not np.isfinite(values).all():
                    raise ParameterError(message("paths", owner, f"a matrix of finite numbers as {alias}",
                                                 f"something else in {shown}"))
                found[name] = values
        size = None
        width, height = storage.getNode("image_width"), storage.getNode("image_height")
        both = storage.getNode("imageSize")
        if not width.empty() and not height.empty():
            size = (width.real(), height.real())
        elif not both.empty():
            values = _opencv_values(both)
            size = tuple(values.ravel()) if values is not None else None
        if size is not None:
            if len(size) != 2 or not all(float(v).is_integer() and 1 <= v <= 1 << 16 for v in size):
                raise ParameterError(message("paths", owner, "an image size of two whole numbers from 1 to "
                                             f"{1 << 16}", f"{size} in {shown}"))
            size = tuple(int(v) for v in size)
    finally:
        storage.release()
    return found, size


def _check_intrinsics(k, d, name: str, owner: str) -> None:
    rule = "a camera matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with finite fx, fy > 0 and cx, cy"
    k = np.asarray(k, dtype=float)
    if (k.shape != (3, 3) or not np.isfinite(k).all() or not (k[0, 0] > 0 and k[1, 1] > 0)
            or not np.allclose(k[2], (0, 0, 1)) or k[1, 0] != 0):
        raise ParameterError(message(f"k_{name}", owner, rule, k.tolist()))
    d = np.asarray(d, dtype=float)
    if d.size not in (4, 5, 8, 12, 14) or not np.isfinite(d).all():
        raise ParameterError(message(f"d_{name}", owner, "4, 5, 8, 12 or 14 finite distortion "
                                     "coefficients", d.ravel().tolist()))


def check_board(board, square_m, owner: str) -> tuple:
    """`board` (inner corners per row, per column) and `square_m` (metres), checked as `owner`'s.

    >>> check_board([9, 6], 0.025, "calibrate_rig")
    ((9, 6), 0.025)
    >>> check_board((9, 6), -1, "the rig file")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'square_m' parameter of the rig file must be a finite number >= 1e-05 and <= 10.0. Got -1.0 instead.
    """
    rule = f"two whole numbers from 2 to {MAX_BOARD_SIDE} (inner corners per row, per column)"
    board = _two_ints(board, "board", owner, rule, 2, MAX_BOARD_SIDE)
    return board, check_number(square_m, "square_m", owner, low=MIN_SQUARE_M, high=MAX_SQUARE_M)


def _check(camera: StereoCamera, owner: str) -> None:
    """Refuse a camera that cannot rectify (black images or a crash), or an RMS that sets no band."""
    rms = camera.rms
    if isinstance(rms, bool) or not isinstance(rms, numbers.Real):
        raise ParameterTypeError(message("rms", owner, _RMS_RULE, rms))
    if not (math.isnan(rms) or (math.isfinite(rms) and rms > 0)):
        raise ParameterError(message("rms", owner, _RMS_RULE, rms))
    object.__setattr__(camera, "rms", float(rms))
    board, square_m = check_board(camera.board, camera.square_m, owner)
    object.__setattr__(camera, "board", board)
    object.__setattr__(camera, "square_m", square_m)
    for name in ("k_left", "d_left", "k_right", "d_right", "rotation", "translation"):
        object.__setattr__(camera, name, np.asarray(getattr(camera, name), dtype=float))
    for name in ("left", "right"):
        _check_intrinsics(getattr(camera, f"k_{name}"), getattr(camera, f"d_{name}"), name, owner)
    r = camera.rotation
    if r.shape != (3, 3) or not np.isfinite(r).all() or not np.allclose(r @ r.T, np.eye(3), atol=1e-6) \
            or not np.linalg.det(r) > 0:
        raise ParameterError(message("rotation", owner, "a 3x3 rotation matrix", r.tolist()))
    t = camera.translation
    if t.size != 3 or not np.isfinite(t).all() or not np.linalg.norm(t) > 0:
        raise ParameterError(message("translation", owner, "a finite (x, y, z) offset of the right camera, "
                                     "not zero (a baseline > 0)", t.ravel().tolist()))
    object.__setattr__(camera, "translation", t.reshape(3, 1))
    if not (np.isfinite(camera.focal_px) and camera.focal_px > 0 and np.isfinite(camera.baseline_m)
            and camera.baseline_m > 0):
        raise ParameterError(message("k_left", owner, "cameras that rectify to a finite focal length > 0",
                                     f"focal length {camera.focal_px} px, baseline {camera.baseline_m} m"))


#: The fields every rig file has (the derived ``focal_px``, ``baseline_m``, ``zoom``, ``cropped`` are
#: checked if given).
REQUIRED = ("format", "size", "rms_px", "board", "square_m", "k_left", "d_left", "k_right", "d_right",
            "rotation", "translation")


class _Fields:
    """The checks of one rig file's fields."""

    def __init__(self, data: dict, owner: str):
        self.data, self.owner = data, owner

    def fail(self, name: str, rule: str, value, kind=ParameterError):
        return kind(message(name, self.owner, rule, value))

    def get(self, name: str, rule: str):
        if name not in self.data:
            raise self.fail(name, f"given: a complete rig file has {', '.join(REQUIRED)}; here it must be {rule}",
                            _Missing())
        return self.data[name]

    def numbers(self, name: str, value, shape: tuple, rule: str) -> np.ndarray:
        """`value` (nested lists of JSON numbers) as a float array of `shape` (-1: any length)."""
        def plain(v):
            if isinstance(v, list):
                return all(plain(x) for x in v)
            return isinstance(v, (int, float)) and not isinstance(v, bool)

        if not plain(value):
            raise self.fail(name, rule, value, ParameterTypeError)
        try:
            array = np.asarray(value, dtype=float).reshape(shape)
        except (OverflowError, ValueError):   # an integer of hundreds of digits, ragged lists
            raise self.fail(name, rule, value) from None
        if array.ndim != len(shape) or any(s != -1 and a != s for a, s in zip(array.shape, shape)) \
                or not np.isfinite(array).all():
            raise self.fail(name, rule, value)
        return array

    def names(self, name: str) -> tuple:
        value = self.data.get(name, [])
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.fail(name, "a list of names (strings)", value, ParameterTypeError)
        return tuple(value)


class _Missing:
    def __repr__(self) -> str:
        return "nothing"


def _number(fields: _Fields, name: str, value, **bounds) -> float:
    try:
        return check_number(value, name, fields.owner, **bounds)
    except ParameterTypeError as exc:
        raise ParameterTypeError(str(exc)) from None


def _from_record(data, owner: str) -> StereoCamera:
    """The camera of a rig file's parsed JSON."""
    fields = _Fields(data, owner)
    size = fields.get("size", "(width, height)")
    size = _check_size(size, owner)
    rule = ("null (no error measured: a 1 px search band) or a finite number > 0 (the calibration's RMS "
            "reprojection error in pixels, which sets the search band)")
    rms = fields.get("rms_px", rule)
    if rms is not None:
        if not isinstance(rms, (int, float)) or isinstance(rms, bool):
            raise fields.fail("rms_px", rule, rms, ParameterTypeError)
        try:
            value = float(rms)
        except OverflowError:   # an integer of hundreds of digits
            value = math.inf
        if not (math.isfinite(value) and value > 0):
            raise fields.fail("rms_px", rule, rms)
    rms = math.nan if rms is None else value
    used, skipped = fields.names("used"), fields.names("skipped")
    board, square_m = fields.get("board", "[columns, rows]"), fields.get("square_m", "a side in metres")
    if board is None and square_m is None and not used:   # a rig calibrated from no board
        board, square_m = BOARD, SQUARE_M
    elif board is None or square_m is None:
        name = "board" if board is None else "square_m"
        raise fields.fail(name, "given (null only in a rig calibrated from no board: no 'used' pairs)", None)
    board, square_m = check_board(board, square_m, owner)
    matrix = "a 3x3 camera matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] of finite numbers"
    arrays = {"k_left": (matrix, (3, 3)), "k_right": (matrix, (3, 3)),
              "d_left": ("4, 5, 8, 12 or 14 finite distortion coefficients", (1, -1)),
              "d_right": ("4, 5, 8, 12 or 14 finite distortion coefficients", (1, -1)),
              "rotation": ("a 3x3 rotation matrix of finite numbers", (3, 3)),
              "translation": ("a finite (x, y, z) offset of the right camera, in metres", (3, 1))}
    values = {name: fields.numbers(name, fields.get(name, rule), shape, rule)
              for name, (rule, shape) in arrays.items()}
    pairs = data.get("pairs", [])
    if not isinstance(pairs, list):
        raise fields.fail("pairs", "a list of the calibration's pairs", pairs, ParameterTypeError)
    pairs = tuple(_pair(fields, n, p) for n, p in enumerate(pairs))
    try:
        camera = StereoCamera(size, values["k_left"], values["d_left"], values["k_right"], values["d_right"],
                              values["rotation"], values["translation"], rms, board, square_m, used, skipped, pairs)
    except ParameterError as exc:   # a degenerate rig: name the file
        raise ParameterError(str(exc).replace("of StereoCamera", f"of {owner}")) from None
    for name, have in (("focal_px", camera.focal_px), ("baseline_m", camera.baseline_m)):
        if name in data:   # derived: a value edited by hand would not be used, so it must agree
            given = _number(fields, name, data[name])
            if not math.isclose(given, have, rel_tol=1e-6):
                raise fields.fail(name, f"the value the cameras give, {have:.10g} (it is derived: change k_left, "
                                  "k_right and translation, or write the rig with 'ismb-lab rig')", given)
    if "zoom" in data:
        _number(fields, "zoom", data["zoom"], low=0, low_open=True)
    fields.names("cropped")
    return camera


def _pair(fields: _Fields, n: int, record) -> BoardPair:
    """Calibration pair `n` of a rig file, each field named ``pairs[n].field``."""
    at = f"pairs[{n}]"
    if not isinstance(record, dict):
        raise fields.fail(at, "a pair's record {left, right, left_corners, right_corners, rms_px, rvec, tvec}",
                          record, ParameterTypeError)
    for name in ("left", "right", "left_corners", "right_corners", "rms_px", "rvec", "tvec"):
        if name not in record:
            raise fields.fail(f"{at}.{name}", "given in every pair", _Missing())
    for name in ("left", "right"):
        if not isinstance(record[name], str):
            raise fields.fail(f"{at}.{name}", "a photo's name", record[name], ParameterTypeError)
    corners = "finite (x, y) corners, one [x, y] per corner"
    left = fields.numbers(f"{at}.left_corners", record["left_corners"], (-1, 2), corners)
    right = fields.numbers(f"{at}.right_corners", record["right_corners"], (-1, 2), corners)
    if left.shape != right.shape or not len(left):
        raise fields.fail(f"{at}.right_corners", "as many corners as left_corners (at least one)",
                          f"{len(right)} against {len(left)}")
    rms = _number(fields, f"{at}.rms_px", record["rms_px"], low=0)
    vectors = [fields.numbers(f"{at}.{name}", record[name], (3,), "three finite numbers (a Rodrigues vector "
                              "or a translation in metres)") for name in ("rvec", "tvec")]
    return BoardPair(record["left"], record["right"], left, right, rms, *vectors)


def load_camera(source) -> StereoCamera:
    """A rig from its file (``ismb-lab calibrate``'s or ``ismb-lab rig``'s JSON; a path or the text).

    Each field is checked by name.  ``rms_px`` is null when none was measured; ``board`` and
    ``square_m`` are null only for a rig that no board calibrated; the derived ``focal_px`` and
    ``baseline_m`` must agree with the cameras'.

    Parameters
    ----------
    source : str or Path
        The rig file, or its JSON text.

    Returns
    -------
    camera : StereoCamera
        The rig.

    Raises
    ------
    ParameterError
        An unreadable file, another format, or a field that fails its check.

    Examples
    --------
    >>> cam = load_camera(StereoCamera.from_factory(500.0, 0.06, (640, 480)).to_json())
    >>> cam.focal_px, cam.baseline_m, cam.is_rectified
    (500.0, 0.06, True)
    >>> load_camera('{"format": "ismb_lab-rig-v2", "size": [640, 480], "rms_px": 0}')
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'rms_px' parameter of the rig file must be null (no error measured: a 1 px search band) or a finite number > 0 (the calibration's RMS reprojection error in pixels, which sets the search band). Got 0 instead.
    """
    from .._core.files import MAX_JSON_BYTES, read_json

    owner = "load_camera"
    inline = str(source).lstrip().startswith("{")
    try:
        if inline:
            if len(str(source)) > MAX_JSON_BYTES:
                raise ValueError(f"it is larger than {MAX_JSON_BYTES} bytes")
            data = json.loads(str(source))
        else:
            data = read_json(source)
    except RecursionError:
        raise ParameterError(message("source", owner, "a readable rig JSON file (its JSON is nested too deeply)",
                                     str(source))) from None
    except (OSError, ValueError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise ParameterError(message("source", owner, f"a readable rig JSON file ({why})", str(source))) from None
    if not isinstance(data, dict) or data.get("format") not in _FORMATS:
        raise ParameterError(message("source", owner, "a rig file written by 'ismb-lab calibrate' "
                                     f"(format {' or '.join(_FORMATS)})", str(source)))
    shown = "the rig file" if inline else f"the rig file {str(source)!r}"
    return _from_record(data, shown)
