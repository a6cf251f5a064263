"""The stereo rig and rays: two pinhole cameras, pixel <-> ray, and small vector helpers.

The geometry of the whole package is in its docstring (:mod:`ismb_lab.scenes`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._validation import ParameterError, ParameterTypeError, check_number, check_points, message

__all__ = ["EPS", "ROI", "Rig"]

ROI = (80, 60, 160, 120)
"""The thesis' region of interest, the centre quarter of a 320 x 240 image, as ``(x, y, w, h)``."""

EPS = 1e-9
"""Smallest ray parameter counted as a hit (metres along a unit ray)."""


def _vector(value, name: str, owner: str, n: int = 3) -> np.ndarray:
    rule = f"a finite vector of {n} numbers"
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterTypeError(message(name, owner, rule, value)) from None
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ParameterError(message(name, owner, rule, value))
    return arr


def _points3d(points, name: str, owner: str) -> np.ndarray:
    rule = "an (N, 3) array of finite (X, Y, Z) points"
    try:
        arr = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise ParameterTypeError(message(name, owner, rule, points)) from None
    if arr.size == 0:
        return arr.reshape(0, 3)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ParameterError(message(name, owner, rule, f"an array of shape {arr.shape}"))
    if not np.all(np.isfinite(arr)):
        raise ParameterError(message(name, owner, rule, "an array with NaN or infinite values"))
    return arr


def _rotate(vectors: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """``vectors @ matrix.T`` for ``(N, 3)`` vectors (much faster than matmul for this shape)."""
    return np.stack([vectors @ row for row in matrix], axis=1)


def _unit(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.sqrt(np.einsum("ij,ij->i", vectors, vectors))[:, None]


def _rays(origins, dirs, owner: str) -> tuple[np.ndarray, np.ndarray]:
    origins = _points3d(origins, "origins", owner)
    dirs = _points3d(dirs, "dirs", owner)
    if origins.shape != dirs.shape:
        raise ParameterError(message("dirs", owner, f"an array of the shape of origins {origins.shape}",
                                     f"an array of shape {dirs.shape}"))
    return origins, dirs


# --------------------------------------------------------------------------- rig


@dataclass(frozen=True)
class Rig:
    """Two pinhole cameras side by side.

    The defaults mimic the thesis' webcams: 320 x 240 images, 10 cm apart.
    ``focal_px = 300`` gives a horizontal field of view of about 56 degrees
    (``2 atan(160 / 300)``), like a webcam; a point at 1.8 m (the deepest
    background) then has a disparity of 16.7 px and one at 1 m of 30 px,
    bracketing the thesis' expected shift of 20 px.

    Parameters
    ----------
    width, height : int
        Image size in pixels.  The principal point is the image centre
        ``((width - 1) / 2, (height - 1) / 2)``.
    focal_px : float
        Focal length in pixels (> 0), the same for both cameras.
    baseline_m : float
        Distance between the optical centres in metres (> 0).
    vertical_offset_px : float
        The right image is shifted *down* by this many pixels (a point's right
        ``y`` grows by this amount).
    roll_deg : float
        Rotation of the right camera about its optical axis, in degrees.  A
        positive roll turns the camera's ``x`` axis towards its ``y`` axis, so
        the scene appears rotated counter-clockwise on screen in the right image.

    Examples
    --------
    >>> rig = Rig()
    >>> float(rig.disparity_at(1.8)), float(rig.disparity_at(1.0))
    (16.666666666666668, 30.0)
    >>> rig.project_left([[0.0, 0.0, 2.0]]), rig.project_right([[0.0, 0.0, 2.0]])
    (array([[159.5, 119.5]]), array([[144.5, 119.5]]))
    >>> Rig(baseline_m=-0.1)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'baseline_m' parameter of Rig must be a finite number > 0. Got -0.1 instead.
    """

    width: int = 320
    height: int = 240
    focal_px: float = 300.0
    baseline_m: float = 0.10
    vertical_offset_px: float = 0.0
    roll_deg: float = 0.0

    def __post_init__(self):
        for name in ("width", "height"):
            object.__setattr__(self, name, check_number(getattr(self, name), name, "Rig",
                                                        low=2, high=100_000, integer=True))
        for name in ("focal_px", "baseline_m"):
            object.__setattr__(self, name, check_number(getattr(self, name), name, "Rig",
                                                        low=0, low_open=True))
        object.__setattr__(self, "vertical_offset_px",
                           check_number(self.vertical_offset_px, "vertical_offset_px", "Rig"))
        object.__setattr__(self, "roll_deg",
                           check_number(self.roll_deg, "roll_deg", "Rig", low=-180, high=180))

    @property
    def centre(self) -> np.ndarray:
        """Principal point ``(cx, cy)`` of both cameras."""
        return np.array([(self.width - 1) / 2, (self.height - 1) / 2])

    @property
    def right_origin(self) -> np.ndarray:
        """Optical centre of the right camera, ``(baseline_m, 0, 0)``."""
        return np.array([self.baseline_m, 0.0, 0.0])

    @property
    def right_rotation(self) -> np.ndarray:
        """Rotation matrix from right-camera to world coordinates (roll about ``z``)."""
        a = math.radians(self.roll_deg)
        c, s = math.cos(a), math.sin(a)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def disparity_at(self, depth) -> np.ndarray:
        """Disparity ``focal_px * baseline_m / depth`` of the parallel rig, in pixels.

        Examples
        --------
        >>> Rig().disparity_at([1.0, 1.5])
        array([30., 20.])
        """
        return self.focal_px * self.baseline_m / np.asarray(depth, dtype=float)

    def _pixels(self, cam: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = self.centre + self.focal_px * cam[:, :2] / cam[:, 2:3]
        xy[cam[:, 2] <= 0] = np.nan
        return xy

    def project_left(self, points3d) -> np.ndarray:
        """Left-image ``(x, y)`` of 3-D points; NaN rows for points not in front of the camera.

        Examples
        --------
        >>> Rig().project_left([[0.1, -0.05, 1.0]])
        array([[189.5, 104.5]])
        """
        return self._pixels(_points3d(points3d, "points3d", "Rig.project_left"))

    def project_right(self, points3d) -> np.ndarray:
        """Right-image ``(x, y)`` of 3-D points; NaN rows for points not in front of the camera.

        Examples
        --------
        >>> Rig(vertical_offset_px=2).project_right([[0.1, -0.05, 1.0]])
        array([[159.5, 106.5]])
        """
        points = _points3d(points3d, "points3d", "Rig.project_right")
        xy = self._pixels(_rotate(points - self.right_origin, self.right_rotation.T))
        xy[:, 1] += self.vertical_offset_px
        return xy

    def _dirs(self, xy: np.ndarray) -> np.ndarray:
        d = np.empty((len(xy), 3))
        d[:, :2] = (xy - self.centre) / self.focal_px
        d[:, 2] = 1.0
        return d

    def rays_left(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """Rays through left-image points: ``(origins, unit directions)``, both ``(N, 3)``.

        Examples
        --------
        >>> o, d = Rig().rays_left([[159.5, 119.5]])
        >>> o, d
        (array([[0., 0., 0.]]), array([[0., 0., 1.]]))
        """
        xy = check_points(xy, "xy", "Rig.rays_left")
        d = self._dirs(xy)
        return np.zeros_like(d), _unit(d)

    def rays_right(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """Rays through right-image points: ``(origins, unit directions)``, both ``(N, 3)``.

        Examples
        --------
        >>> o, d = Rig().rays_right([[159.5, 119.5]])
        >>> o, d
        (array([[0.1, 0. , 0. ]]), array([[0., 0., 1.]]))
        """
        xy = check_points(xy, "xy", "Rig.rays_right").copy()
        xy[:, 1] -= self.vertical_offset_px
        d = self._dirs(xy)
        if self.roll_deg:
            d = _rotate(d, self.right_rotation)
        return np.broadcast_to(self.right_origin, d.shape).copy(), _unit(d)
