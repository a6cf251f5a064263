"""Synthetic stereo scenes with exact ground truth, by ray casting.

A tiny deterministic renderer for testing the matcher: a stereo :class:`Rig`, a
list of textured primitives (:class:`Plane`, :class:`Box`), and :func:`render`,
which ray-casts both views and returns a :class:`Scene` holding the grey
images, the depth and disparity maps of the left view, the occlusion mask and
an exact correspondence function, :meth:`Scene.correspond`.
:func:`synthetic_scene` builds a ready-made test scene and :func:`true_matches`
tells which detected right points are the true partners of left points.

Geometry
--------
The left camera sits at the origin looking along ``+z``; ``x`` points right and
``y`` *down*, as in images.  The right camera sits at ``(baseline_m, 0, 0)``,
parallel to the left one, possibly rolled about its optical axis and with its
image shifted down (an unrectified webcam pair).  Points follow
:mod:`ismb_lab.coords`: ``(x, y)`` = (column, row), pixel centres at integers,
horizontal disparity ``x_left - x_right``.  For the parallel rig a point at depth
``Z`` has disparity ``focal_px * baseline_m / Z`` exactly.

Primitives
----------
Anything with these three methods can be rendered (see :class:`Primitive`)::

    intersect(origins, dirs) -> (t, info)   # ray parameter (inf = miss), (N, 3) surface u, v, face
    normals(info) -> (N, 3)                 # unit surface normals
    albedo(info) -> (N,)                    # reflectance in [0, 1], from a Texture

Shading is Lambertian with one distant light plus ambient light, identical in
both views, so a surface point has the same radiance in both cameras.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Protocol, runtime_checkable

import numpy as np

from ._validation import (ParameterError, ParameterTypeError, check_number, check_points,
                          check_rng, message)

__all__ = [
    "Rig", "Texture", "random_texture", "Primitive", "Plane", "Box", "Group", "cast",
    "Scene", "render", "synthetic_scene", "true_matches", "ROI",
    "toy_car", "toy_car_layout", "lab_scene", "toy_car_scene", "realistic_scene",
    "REALISTIC_COUNT", "CAR_DEPTH",
]

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


# ----------------------------------------------------------------------- texture


@dataclass(frozen=True, eq=False)
class Texture:
    """A procedural grey texture on a surface's 2-D coordinates ``(u, v)`` in metres.

    Three layers, evaluated in this order:

    1. a ``base`` albedo, optionally a checker of period ``checker`` metres whose
       squares are ``base +- checker_contrast / 2``;
    2. "posters": a grid of cells of size ``cell = (cu, cv)`` metres (a single
       number for square cells) starting at ``origin``; cell ``(row, col)``,
       that is ``u`` in ``origin[0] + [col, col + 1) * cu``, may hold one axis-aligned rectangle
       ``rects[row, col] = (u0, v0, u1, v1)`` in fractions of the cell (NaN = empty)
       painted with albedo ``levels[row, col]``.  One rectangle per cell keeps the
       corners well separated; evaluation is a table look-up, O(N);
    3. a mild low-frequency variation: the albedo is multiplied by
       ``1 + ripple * mean(sin(k_u u + k_v v + phase))`` over the rows of ``waves``.

    The result is clipped to ``[0, 1]``.  Build random ones with :func:`random_texture`.

    Examples
    --------
    >>> tex = Texture(base=0.5, cell=1.0, origin=(0, 0),
    ...               rects=[[[0.25, 0.25, 0.75, 0.75]]], levels=[[0.9]])
    >>> tex([[0.5, 0.5], [0.1, 0.5], [1.5, 0.5]])
    array([0.9, 0.5, 0.5])
    >>> Texture(checker=0.1, checker_contrast=0.4)([[0.05, 0.05], [0.15, 0.05]])
    array([0.3, 0.7])
    """

    base: float = 0.5
    cell: tuple = (1.0, 1.0)
    origin: tuple = (0.0, 0.0)
    rects: np.ndarray = field(default_factory=lambda: np.full((0, 0, 4), np.nan))
    levels: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    checker: float = 0.0
    checker_contrast: float = 0.0
    waves: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    ripple: float = 0.0

    def __post_init__(self):
        own = "Texture"
        object.__setattr__(self, "base", check_number(self.base, "base", own, low=0, high=1))
        cell = (self.cell,) * 2 if np.ndim(self.cell) == 0 else self.cell
        cell = _vector(cell, "cell", own, 2)
        if not np.all(cell > 0):
            raise ParameterError(message("cell", own, "a positive size or (cu, cv) pair of sizes",
                                         self.cell))
        object.__setattr__(self, "cell", tuple(float(c) for c in cell))
        object.__setattr__(self, "origin", tuple(_vector(self.origin, "origin", own, 2)))
        object.__setattr__(self, "checker", check_number(self.checker, "checker", own, low=0))
        object.__setattr__(self, "checker_contrast",
                           check_number(self.checker_contrast, "checker_contrast", own, low=0, high=1))
        object.__setattr__(self, "ripple", check_number(self.ripple, "ripple", own, low=0, high=1))
        rects = np.array(self.rects, dtype=float)
        levels = np.array(self.levels, dtype=float)
        if rects.ndim != 3 or rects.shape[2] != 4:
            raise ParameterError(message("rects", own, "an array of shape (rows, cols, 4)",
                                         f"an array of shape {rects.shape}"))
        if levels.shape != rects.shape[:2]:
            raise ParameterError(message("levels", own, f"an array of shape {rects.shape[:2]}",
                                         f"an array of shape {levels.shape}"))
        if not np.all((levels >= 0) & (levels <= 1)):
            raise ParameterError(message("levels", own, "an array of albedos in [0, 1]", levels))
        waves = np.array(self.waves, dtype=float).reshape(-1, 3) if np.size(self.waves) else \
            np.zeros((0, 3))
        if not np.all(np.isfinite(waves)):
            raise ParameterError(message("waves", own, "an (M, 3) array of finite (k_u, k_v, phase)",
                                         waves))
        for name, arr in (("rects", rects), ("levels", levels), ("waves", waves)):
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    def __call__(self, uv) -> np.ndarray:
        uv = check_points(uv, "uv", "Texture")
        u, v = uv[:, 0], uv[:, 1]
        value = np.full(len(u), self.base)
        if self.checker > 0 and self.checker_contrast > 0:
            parity = (np.floor(u / self.checker) + np.floor(v / self.checker)) % 2
            value = value + self.checker_contrast * (parity - 0.5)
        if self.levels.size:
            rows, cols = self.levels.shape
            fu = (u - self.origin[0]) / self.cell[0]
            fv = (v - self.origin[1]) / self.cell[1]
            iu, iv = np.floor(fu).astype(np.int64), np.floor(fv).astype(np.int64)
            inside = (iu >= 0) & (iu < cols) & (iv >= 0) & (iv < rows)
            iu, iv = np.clip(iu, 0, cols - 1), np.clip(iv, 0, rows - 1)
            r = self.rects[iv, iu]
            su, sv = fu - iu, fv - iv
            with np.errstate(invalid="ignore"):
                hit = inside & (su >= r[:, 0]) & (su < r[:, 2]) & (sv >= r[:, 1]) & (sv < r[:, 3])
            value = np.where(hit, self.levels[iv, iu], value)
        if self.ripple > 0 and len(self.waves):
            k = self.waves
            value = value * (1 + self.ripple * np.sin(np.outer(u, k[:, 0]) + np.outer(v, k[:, 1])
                                                      + k[:, 2]).mean(axis=1))
        return np.clip(value, 0.0, 1.0)


def random_texture(rng, extent, *, cell: float, fill: float = 0.6, base: float = 0.55,
                   contrast=(0.25, 0.45), sizes=(0.4, 0.76), margin: float = 0.12,
                   checker: float = 0.0, checker_contrast: float = 0.0,
                   ripple: float = 0.08, wavelengths=(0.4, 1.5)) -> Texture:
    """A random corner-rich :class:`Texture`: posters on a grid, plus mild ripple.

    Parameters
    ----------
    rng : numpy.random.Generator or int
        Source of randomness (an integer is a seed).
    extent : (4,) array_like
        ``(u_min, v_min, u_max, v_max)`` of the surface area to cover, metres.
        Outside it only the base (and checker, ripple) remain.
    cell : float
        Approximate grid cell side in metres; each cell holds at most one
        rectangle.  The cells are stretched a little so that a whole number of
        them tiles `extent` exactly: no rectangle crosses its border.
    fill : float
        Fraction of the cells that hold a rectangle (rounded; at least one).
    base : float
        Background albedo.
    contrast : (2,) floats
        Range of ``|level - base|`` of the rectangles; the sign is random.
    sizes : (2,) floats
        Range of a rectangle's side, as a fraction of ``cell``.
    margin : float
        Smallest gap between a rectangle and its cell's border, as a fraction of
        ``cell``, so corners of neighbouring rectangles stay apart.
    checker, checker_contrast : float
        Optional checker background, see :class:`Texture`.
    ripple : float
        Relative amplitude of the low-frequency variation (3 random plane waves).
    wavelengths : (2,) floats
        Range of the waves' wavelengths in metres.

    Examples
    --------
    >>> tex = random_texture(0, (0, 0, 1, 1), cell=0.25)
    >>> tex.levels.shape
    (4, 4)
    >>> bool(np.array_equal(tex([[0.3, 0.6]]), random_texture(0, (0, 0, 1, 1), cell=0.25)([[0.3, 0.6]])))
    True
    """
    own = "random_texture"
    rng = check_rng(rng, "rng", own)
    ext = _vector(extent, "extent", own, 4)
    if not (ext[2] > ext[0] and ext[3] > ext[1]):
        raise ParameterError(message("extent", own, "(u_min, v_min, u_max, v_max) with "
                                     "u_max > u_min and v_max > v_min", tuple(ext)))
    cell = check_number(cell, "cell", own, low=0, low_open=True)
    fill = check_number(fill, "fill", own, low=0, high=1)
    base = check_number(base, "base", own, low=0, high=1)
    margin = check_number(margin, "margin", own, low=0, high=0.25)
    lo_c, hi_c = (check_number(c, "contrast", own, low=0, high=1) for c in contrast)
    lo_s, hi_s = (check_number(s, "sizes", own, low=0, low_open=True, high=1 - 2 * margin)
                  for s in sizes)
    lo_w, hi_w = (check_number(w, "wavelengths", own, low=0, low_open=True) for w in wavelengths)
    cols = max(1, round((ext[2] - ext[0]) / cell))
    rows = max(1, round((ext[3] - ext[1]) / cell))
    shape = (rows, cols)
    cells = rows * cols
    w = rng.uniform(lo_s, hi_s, shape)
    h = rng.uniform(lo_s, hi_s, shape)
    u0 = margin + rng.uniform(0, 1, shape) * (1 - 2 * margin - w)
    v0 = margin + rng.uniform(0, 1, shape) * (1 - 2 * margin - h)
    rects = np.stack([u0, v0, u0 + w, v0 + h], axis=-1)
    rects[(rng.permutation(cells) >= max(1, round(fill * cells))).reshape(shape)] = np.nan
    step = rng.uniform(lo_c, hi_c, shape) * rng.choice([-1.0, 1.0], shape)
    levels = base + step
    levels = np.where((levels < 0.04) | (levels > 0.96), base - step, levels)
    angle = rng.uniform(0, 2 * np.pi, 3)
    k = 2 * np.pi / rng.uniform(lo_w, hi_w, 3)
    waves = np.stack([k * np.cos(angle), k * np.sin(angle), rng.uniform(0, 2 * np.pi, 3)], axis=1)
    cell = ((ext[2] - ext[0]) / cols, (ext[3] - ext[1]) / rows)
    return Texture(base=base, cell=cell, origin=(ext[0], ext[1]), rects=rects,
                   levels=np.clip(levels, 0, 1), checker=checker,
                   checker_contrast=checker_contrast, waves=waves, ripple=ripple)


# -------------------------------------------------------------------- primitives


@runtime_checkable
class Primitive(Protocol):
    """What :func:`render` needs from a surface.

    ``intersect(origins, dirs)`` takes ``(N, 3)`` ray origins and unit
    directions and returns ``(t, info)``: the ray parameter of the first hit
    (``np.inf`` for a miss; only ``t > EPS`` counts) and an ``(N, 3)`` array of
    surface coordinates ``(u, v, face)`` in metres.  ``normals(info)`` returns
    unit normals ``(N, 3)`` and ``albedo(info)`` reflectances in ``[0, 1]``.
    """

    def intersect(self, origins, dirs) -> tuple[np.ndarray, np.ndarray]: ...

    def normals(self, info) -> np.ndarray: ...

    def albedo(self, info) -> np.ndarray: ...


def _check_texture(texture, name: str, owner: str) -> Texture:
    if not isinstance(texture, Texture):
        raise ParameterTypeError(message(name, owner, "a Texture", texture))
    return texture


@dataclass(frozen=True, eq=False)
class Plane:
    """A textured rectangle (two-sided).

    Parameters
    ----------
    centre : (3,) array_like
        Centre in metres.
    u_axis, v_axis : (3,) array_like
        Orthogonal in-plane directions (normalised here); the texture's
        ``(u, v)`` are metres along them from the centre.
    half_u, half_v : float
        Half sizes along the axes in metres.  Make them large for a wall or a
        floor that fills the view.
    texture : Texture

    Examples
    --------
    >>> wall = Plane((0, 0, 1.8), (1, 0, 0), (0, 1, 0), 10, 10, Texture())
    >>> t, info = wall.intersect([[0, 0, 0], [0, 0, 0]], [[0, 0, 1], [0, 0, -1]])
    >>> t, info[0]
    (array([1.8, inf]), array([0., 0., 0.]))
    """

    centre: np.ndarray
    u_axis: np.ndarray
    v_axis: np.ndarray
    half_u: float
    half_v: float
    texture: Texture

    def __post_init__(self):
        own = "Plane"
        object.__setattr__(self, "centre", _vector(self.centre, "centre", own))
        for name in ("u_axis", "v_axis"):
            axis = _vector(getattr(self, name), name, own)
            norm = np.linalg.norm(axis)
            if norm == 0:
                raise ParameterError(message(name, own, "a non-zero vector", tuple(axis)))
            object.__setattr__(self, name, axis / norm)
        if abs(float(self.u_axis @ self.v_axis)) > 1e-9:
            raise ParameterError(message("v_axis", own, "orthogonal to u_axis", tuple(self.v_axis)))
        for name in ("half_u", "half_v"):
            object.__setattr__(self, name, check_number(getattr(self, name), name, own,
                                                        low=0, low_open=True))
        _check_texture(self.texture, "texture", own)

    @property
    def normal(self) -> np.ndarray:
        """Unit normal ``u_axis x v_axis``."""
        return np.cross(self.u_axis, self.v_axis)

    def intersect(self, origins, dirs) -> tuple[np.ndarray, np.ndarray]:
        """First hits of rays: ``(t, info)`` with ``info = (u, v, 0)``."""
        origins, dirs = _rays(origins, dirs, "Plane.intersect")
        n, c = self.normal, self.centre
        denom = dirs @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (c @ n - origins @ n) / denom
        t = np.where(np.abs(denom) > 1e-15, t, np.inf)
        tf = np.where(np.isfinite(t), t, 0.0)
        u = origins @ self.u_axis - c @ self.u_axis + tf * (dirs @ self.u_axis)
        v = origins @ self.v_axis - c @ self.v_axis + tf * (dirs @ self.v_axis)
        hit = (t > EPS) & (np.abs(u) <= self.half_u) & (np.abs(v) <= self.half_v)
        return np.where(hit, t, np.inf), np.stack([u, v, np.zeros_like(u)], axis=1)

    def normals(self, info) -> np.ndarray:
        """The plane's normal for every hit."""
        return np.broadcast_to(self.normal, (len(info), 3)).copy()

    def albedo(self, info) -> np.ndarray:
        """Texture values at ``(u, v)``."""
        info = np.asarray(info, dtype=float)
        return self.texture(info[:, :2])


_FACE_NORMALS = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], float)
# Texture coordinates of the faces of each axis: (u, v) = (p[a], p[b]) - lo[[a, b]].
_FACE_UV = {0: (2, 1), 1: (0, 2), 2: (0, 1)}


@dataclass(frozen=True, eq=False)
class Box:
    """A solid axis-aligned box, seen from outside.

    Parameters
    ----------
    lo, hi : (3,) array_like
        Opposite corners, ``lo < hi`` component-wise, in metres.
    textures : Texture or sequence of 6 Textures
        One texture for every face, or one per face in the order
        ``-x, +x, -y (top, y is down), +y (bottom), -z (front), +z (back)``.
        A face's ``(u, v)`` are metres from its ``lo`` corner: ``(z, y)`` on the
        ``x`` faces, ``(x, z)`` on the ``y`` faces and ``(x, y)`` on the ``z`` faces.
        The faces also differ in brightness through shading.

    Examples
    --------
    >>> box = Box((-0.1, -0.1, 1.0), (0.1, 0.1, 1.2), Texture())
    >>> t, info = box.intersect([[0, 0, 0]], [[0, 0, 1]])
    >>> t, info   # the front face, -z, is face 4
    (array([1.]), array([[0.1, 0.1, 4. ]]))
    """

    lo: np.ndarray
    hi: np.ndarray
    textures: tuple

    def __post_init__(self):
        own = "Box"
        object.__setattr__(self, "lo", _vector(self.lo, "lo", own))
        object.__setattr__(self, "hi", _vector(self.hi, "hi", own))
        if not np.all(self.hi > self.lo):
            raise ParameterError(message("hi", own, "greater than lo in every component",
                                         tuple(self.hi)))
        textures = self.textures
        if isinstance(textures, Texture):
            textures = (textures,) * 6
        textures = tuple(textures) if isinstance(textures, (list, tuple)) else (textures,)
        if len(textures) != 6:
            raise ParameterError(message("textures", own, "a Texture or a sequence of 6 Textures",
                                         self.textures))
        for tex in textures:
            _check_texture(tex, "textures", own)
        object.__setattr__(self, "textures", textures)

    def intersect(self, origins, dirs) -> tuple[np.ndarray, np.ndarray]:
        """First hits of rays from outside: ``(t, info)`` with ``info = (u, v, face)``."""
        origins, dirs, t, info, near_rays = _misses(origins, dirs, self.lo, self.hi, "Box.intersect")
        if not len(near_rays):
            return t, info
        o, d = origins[near_rays], dirs[near_rays]
        safe = np.where(d == 0, 1e-300, d)
        t1 = (self.lo - o) / safe
        t2 = (self.hi - o) / safe
        near = np.minimum(t1, t2)
        axis = np.argmax(near, axis=1)
        t_near = near.max(axis=1)
        t_far = np.maximum(t1, t2).min(axis=1)
        hit = (t_near <= t_far) & (t_near > EPS)
        o, d, axis, t_near, idx = o[hit], d[hit], axis[hit], t_near[hit], near_rays[hit]
        rows = np.arange(len(idx))
        p = o + t_near[:, None] * d - self.lo
        uv_cols = np.array([_FACE_UV[i] for i in range(3)])[axis]
        t[idx] = t_near
        info[idx, 0] = p[rows, uv_cols[:, 0]]
        info[idx, 1] = p[rows, uv_cols[:, 1]]
        info[idx, 2] = 2 * axis + (d[rows, axis] < 0)
        return t, info

    def normals(self, info) -> np.ndarray:
        """Outward unit normals of the faces hit."""
        return _FACE_NORMALS[np.asarray(info)[:, 2].astype(int)]

    def albedo(self, info) -> np.ndarray:
        """Each face's texture at its ``(u, v)``."""
        info = np.asarray(info, dtype=float)
        face = info[:, 2].astype(int)
        out = np.zeros(len(info))
        for f in np.unique(face):
            sel = face == f
            out[sel] = self.textures[f](info[sel, :2])
        return out


def _near_rays(origins: np.ndarray, dirs: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Indices of the rays that pass the bounding sphere of the box ``lo..hi``.

    Culling with the sphere first is cheap, and most rays miss a small object.
    """
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    to_c = centre - origins
    along = np.einsum("ij,ij->i", to_c, dirs)       # dirs are unit vectors
    miss2 = np.einsum("ij,ij->i", to_c, to_c) - along ** 2
    return np.flatnonzero((miss2 <= radius ** 2 * (1 + 1e-9)) & (along > -radius))


@dataclass(frozen=True, eq=False)
class Group:
    """Several boxes rendered as one primitive, e.g. a toy car.

    A hit's ``info`` is ``(u, v, 6 * part + face)``: the part's own surface
    coordinates, with the part's index folded into the face number.

    Parameters
    ----------
    parts : sequence of Box
        The boxes; they may overlap (the first hit wins).
    name : str
        A label, e.g. ``"left car"``.

    Examples
    --------
    >>> g = Group([Box((-0.1, -0.1, 1.0), (0.1, 0.1, 1.2), Texture(base=0.2)),
    ...            Box((0.1, -0.1, 1.5), (0.3, 0.1, 1.7), Texture(base=0.8))], "pair")
    >>> t, info = g.intersect([[0, 0, 0], [0.2, 0, 0]], [[0, 0, 1], [0, 0, 1]])
    >>> t, info[:, 2], g.albedo(info), g.lo, g.hi
    (array([1. , 1.5]), array([ 4., 10.]), array([0.2, 0.8]), array([-0.1, -0.1,  1. ]), array([0.3, 0.1, 1.7]))
    """

    parts: tuple
    name: str = ""

    def __post_init__(self):
        own = "Group"
        rule = "a non-empty sequence of Box"
        parts = self.parts
        try:
            parts = tuple(parts)
        except TypeError:
            raise ParameterTypeError(message("parts", own, rule, self.parts)) from None
        if not parts or not all(isinstance(p, Box) for p in parts):
            raise ParameterTypeError(message("parts", own, rule, self.parts))
        if not isinstance(self.name, str):
            raise ParameterTypeError(message("name", own, "a str", self.name))
        object.__setattr__(self, "parts", parts)

    @property
    def lo(self) -> np.ndarray:
        """Lower corner of the bounding box of all parts."""
        return np.min([p.lo for p in self.parts], axis=0)

    @property
    def hi(self) -> np.ndarray:
        """Upper corner of the bounding box of all parts."""
        return np.max([p.hi for p in self.parts], axis=0)

    def intersect(self, origins, dirs) -> tuple[np.ndarray, np.ndarray]:
        """First hits of rays: ``(t, info)`` with ``info = (u, v, 6 * part + face)``."""
        origins, dirs, t, info, near = _misses(origins, dirs, self.lo, self.hi, "Group.intersect")
        if not len(near):
            return t, info
        t_near, which, info_near = cast(self.parts, origins[near], dirs[near])
        hit = which >= 0
        info_near[hit, 2] += 6 * which[hit]
        t[near], info[near] = t_near, info_near
        return t, info

    def _split(self, info) -> tuple[np.ndarray, np.ndarray]:
        info = np.asarray(info, dtype=float).copy()
        part = (info[:, 2] // 6).astype(int)
        info[:, 2] -= 6 * part
        return part, info

    def normals(self, info) -> np.ndarray:
        """Outward unit normals of the faces hit."""
        return _FACE_NORMALS[self._split(info)[1][:, 2].astype(int)]

    def albedo(self, info) -> np.ndarray:
        """Each part's texture at its ``(u, v)``."""
        part, local = self._split(info)
        out = np.zeros(len(local))
        for n in np.unique(part):
            sel = part == n
            out[sel] = self.parts[n].albedo(local[sel])
        return out


def _misses(origins, dirs, lo, hi, owner: str):
    """Checked rays, an all-miss ``(t, info)`` and the rays near the box ``lo..hi``."""
    origins, dirs = _rays(origins, dirs, owner)
    t = np.full(len(origins), np.inf)
    info = np.full((len(origins), 3), np.nan)
    return origins, dirs, t, info, _near_rays(origins, dirs, lo, hi)


def _check_primitives(primitives, owner: str) -> tuple:
    rule = "a non-empty sequence of primitives (objects with intersect, normals and albedo)"
    if isinstance(primitives, Primitive):
        primitives = (primitives,)
    try:
        primitives = tuple(primitives)
    except TypeError:
        raise ParameterTypeError(message("primitives", owner, rule, primitives)) from None
    if not primitives or not all(isinstance(p, Primitive) for p in primitives):
        raise ParameterTypeError(message("primitives", owner, rule, primitives))
    return primitives


def cast(primitives, origins, dirs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First hit of each ray among several primitives.

    Parameters
    ----------
    primitives : sequence of Primitive
    origins, dirs : (N, 3) array_like
        Ray origins and unit directions.

    Returns
    -------
    t : (N,) ndarray
        Ray parameter of the nearest hit, ``np.inf`` for none.
    which : (N,) ndarray of int
        Index of the primitive hit, -1 for none.
    info : (N, 3) ndarray
        That primitive's surface coordinates ``(u, v, face)`` (NaN for none).

    Examples
    --------
    >>> wall = Plane((0, 0, 1.8), (1, 0, 0), (0, 1, 0), 10, 10, Texture())
    >>> box = Box((-0.1, -0.1, 1.0), (0.1, 0.1, 1.2), Texture())
    >>> t, which, _ = cast([wall, box], [[0, 0, 0], [0.5, 0, 0]], [[0, 0, 1], [0, 0, 1]])
    >>> t, which
    (array([1. , 1.8]), array([1, 0]))
    """
    primitives = _check_primitives(primitives, "cast")
    origins, dirs = _rays(origins, dirs, "cast")
    ts, infos = zip(*(prim.intersect(origins, dirs) for prim in primitives))
    ts = np.stack(ts)
    which = np.argmin(ts, axis=0)
    best = ts[which, np.arange(len(origins))]
    which[~np.isfinite(best)] = -1
    info = np.full((len(origins), 3), np.nan)
    for i, inf in enumerate(infos):
        sel = which == i
        info[sel] = inf[sel]
    return best, which, info


# -------------------------------------------------------------------------- scene


def _correspond(primitives, rig: Rig, left_xy: np.ndarray):
    """3-D points, depths and right-image positions of left points (NaN when not visible)."""
    o, d = rig.rays_left(left_xy)
    t, _, _ = cast(primitives, o, d)
    found = np.isfinite(t)
    points = np.where(found[:, None], o + np.where(found, t, 0.0)[:, None] * d, np.nan)
    depth = np.where(found, points[:, 2], np.inf)
    right = np.full((len(left_xy), 2), np.nan)
    if found.any():
        p = points[found]
        xy = rig.project_right(p)
        inside = ((xy[:, 0] >= -0.5) & (xy[:, 0] <= rig.width - 0.5)
                  & (xy[:, 1] >= -0.5) & (xy[:, 1] <= rig.height - 0.5))
        to_p = p - rig.right_origin
        dist = np.sqrt(np.einsum("ij,ij->i", to_p, to_p))
        t_r, _, _ = cast(primitives, np.broadcast_to(rig.right_origin, p.shape), to_p / dist[:, None])
        visible = inside & (t_r >= dist - (1e-7 * dist + 1e-9))
        right[np.flatnonzero(found)[visible]] = xy[visible]
    return points, depth, right


@dataclass(frozen=True, eq=False)
class Scene:
    """A rendered stereo pair with exact ground truth.

    Attributes
    ----------
    left, right : (H, W) ndarray of float64
        Grey images in ``[0, 255]`` (integer-valued: quantised like 8-bit cameras).
    depth : (H, W) ndarray
        ``z`` in metres of the surface seen at each left pixel centre, ``np.inf``
        where no surface.
    disparity : (H, W) ndarray
        ``x_left - x_right`` of each left pixel's true correspondence; NaN where
        occluded, out of the right view or where there is no surface.
    occluded : (H, W) ndarray of bool
        Left pixels whose surface point is hidden from the right camera or falls
        outside the right image (False where there is no surface at all).
    rig : Rig
    primitives : tuple of Primitive
    gain, offset, noise_std : float
        The right image is ``gain * radiance + offset + noise``; the left image
        is ``radiance + noise``; ``noise`` has standard deviation ``noise_std``.

    Examples
    --------
    >>> scene = synthetic_scene(0)
    >>> scene.left.shape, scene.left.dtype, bool(np.isnan(scene.disparity).any())
    ((240, 320), dtype('float64'), True)
    """

    left: np.ndarray
    right: np.ndarray
    depth: np.ndarray
    disparity: np.ndarray
    occluded: np.ndarray
    rig: Rig
    primitives: tuple
    gain: float = 1.0
    offset: float = 0.0
    noise_std: float = 0.0

    def __post_init__(self):
        own = "Scene"
        if not isinstance(self.rig, Rig):
            raise ParameterTypeError(message("rig", own, "a Rig", self.rig))
        object.__setattr__(self, "primitives", _check_primitives(self.primitives, own))
        shape = (self.rig.height, self.rig.width)
        for name in ("left", "right", "depth", "disparity", "occluded"):
            arr = np.asarray(getattr(self, name), dtype=bool if name == "occluded" else float)
            if arr.shape != shape:
                raise ParameterError(message(name, own, f"an array of shape {shape} (the rig's)",
                                             f"an array of shape {arr.shape}"))
            arr = arr.copy()
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "gain", check_number(self.gain, "gain", own, low=0, low_open=True))
        object.__setattr__(self, "offset", check_number(self.offset, "offset", own))
        object.__setattr__(self, "noise_std", check_number(self.noise_std, "noise_std", own, low=0))

    def surface_points(self, left_xy) -> np.ndarray:
        """3-D points seen at left-image points (exact ray cast); NaN rows where no surface.

        Examples
        --------
        >>> synthetic_scene(0).surface_points([[20.0, 20.0]]).round(6)   # the back wall
        array([[-0.837, -0.597,  1.8  ]])
        """
        xy = check_points(left_xy, "left_xy", "Scene.surface_points")
        return _correspond(self.primitives, self.rig, xy)[0]

    def correspond(self, left_xy) -> np.ndarray:
        """True right-image positions of arbitrary left-image points.

        Casts the left ray analytically, takes its first hit, projects that
        3-D point into the right camera and checks, by casting the right ray
        towards it, that nothing lies in front of it and that it is inside the
        right image.  Exact geometry, not a look-up in the rendered maps.

        Parameters
        ----------
        left_xy : (N, 2) array_like
            Left points ``(x, y)``, any real values.

        Returns
        -------
        right_xy : (N, 2) ndarray
            Their right-image ``(x, y)``; NaN rows for occluded, out-of-view or
            surface-less points.

        Examples
        --------
        >>> scene = synthetic_scene(0)
        >>> scene.correspond([[20.0, 20.0], [0.0, 100.0]]).round(3)  # wall; out of the right view
        array([[  3.333,  20.   ],
               [    nan,    nan]])
        """
        xy = check_points(left_xy, "left_xy", "Scene.correspond")
        return _correspond(self.primitives, self.rig, xy)[2]


def _sample_grid(rig: Rig, s: int) -> np.ndarray:
    """``(H*s*W*s, 2)`` sub-pixel sample points, row-major, ``s x s`` per pixel."""
    off = (np.arange(s) + 0.5) / s - 0.5
    xs = (np.arange(rig.width)[:, None] + off).ravel()
    ys = (np.arange(rig.height)[:, None] + off).ravel()
    gx, gy = np.meshgrid(xs, ys)
    return np.stack([gx.ravel(), gy.ravel()], axis=1)


def _radiance(primitives, origins, dirs, light, ambient, background) -> np.ndarray:
    _, which, info = cast(primitives, origins, dirs)
    out = np.full(len(origins), float(background))
    for i, prim in enumerate(primitives):
        sel = which == i
        if not sel.any():
            continue
        n = prim.normals(info[sel])
        facing = np.where(np.einsum("ij,ij->i", n, dirs[sel]) > 0, -1.0, 1.0)
        lambert = np.clip(facing * (n @ light), 0.0, None)
        out[sel] = 255.0 * prim.albedo(info[sel]) * (ambient + (1 - ambient) * lambert)
    return out


def render(primitives, rig: Rig = Rig(), *, seed, noise_std: float = 1.0, gain: float = 1.0,
           offset: float = 0.0, supersample: int = 2, light=(0.3, -0.8, -1.0),
           ambient: float = 0.35, background: float = 0.0, quantise: bool = True) -> Scene:
    """Ray-cast both views of a scene and compute its ground truth.

    Parameters
    ----------
    primitives : sequence of Primitive
        The surfaces, e.g. :class:`Plane` and :class:`Box`.
    rig : Rig
        The cameras.
    seed : int or numpy.random.Generator
        Source of the camera noise (keyword-only, required).
    noise_std : float
        Standard deviation of the Gaussian camera noise in grey levels, drawn
        independently for every pixel of both images.
    gain, offset : float
        The right camera's response ``gain * radiance + offset``, mimicking two
        different webcams (the left camera has gain 1, offset 0).
    supersample : int
        Rays per pixel side: ``supersample**2`` rays at regular sub-pixel
        positions are averaged, which anti-aliases edges.
    light : (3,) array_like
        Direction *towards* the distant light (normalised here); the default
        comes from above, slightly right, behind the cameras.
    ambient : float
        Fraction of the light that is ambient; radiance is
        ``255 * albedo * (ambient + (1 - ambient) * max(0, n . light))``.
    background : float
        Grey level of rays that hit nothing.
    quantise : bool
        Round to integers (after noise, gain and offset), like 8-bit cameras.
        Images are clipped to ``[0, 255]`` and returned as float64 in any case.

    Returns
    -------
    Scene
        Images and the exact depth, disparity and occlusion maps of the left
        view, computed at pixel centres with :meth:`Scene.correspond`'s geometry.

    Examples
    --------
    >>> rig = Rig(width=32, height=24, focal_px=30)
    >>> wall = Plane((0, 0, 1.8), (1, 0, 0), (0, 1, 0), 10, 10, Texture(base=0.6))
    >>> scene = render([wall], rig, seed=0, noise_std=0)
    >>> round(float(scene.disparity[12, 20]), 12), bool(scene.occluded[12, 0])
    (1.666666666667, True)
    """
    own = "render"
    primitives = _check_primitives(primitives, own)
    if not isinstance(rig, Rig):
        raise ParameterTypeError(message("rig", own, "a Rig", rig))
    rng = check_rng(seed, "seed", own)
    noise_std = check_number(noise_std, "noise_std", own, low=0)
    gain = check_number(gain, "gain", own, low=0, low_open=True)
    offset = check_number(offset, "offset", own)
    s = check_number(supersample, "supersample", own, low=1, high=8, integer=True)
    light = _vector(light, "light", own)
    if not np.linalg.norm(light) > 0:
        raise ParameterError(message("light", own, "a non-zero vector", tuple(light)))
    light = light / np.linalg.norm(light)
    ambient = check_number(ambient, "ambient", own, low=0, high=1)
    background = check_number(background, "background", own, low=0, high=255)

    shape = (rig.height, rig.width)
    samples = _sample_grid(rig, s)
    images = []
    for rays in (rig.rays_left, rig.rays_right):
        o, d = rays(samples)
        rad = _radiance(primitives, o, d, light, ambient, background)
        images.append(rad.reshape(rig.height, s, rig.width, s).mean(axis=(1, 3)))
    left = images[0] + rng.normal(0.0, noise_std, shape)
    right = gain * images[1] + offset + rng.normal(0.0, noise_std, shape)
    if quantise:
        left, right = np.rint(left), np.rint(right)
    left, right = np.clip(left, 0, 255), np.clip(right, 0, 255)

    gy, gx = np.mgrid[0:rig.height, 0:rig.width]
    centres = np.stack([gx.ravel(), gy.ravel()], axis=1).astype(float)
    _, depth, right_xy = _correspond(primitives, rig, centres)
    disparity = (centres[:, 0] - right_xy[:, 0]).reshape(shape)
    occluded = (np.isfinite(depth) & np.isnan(right_xy[:, 0])).reshape(shape)
    return Scene(left=left, right=right, depth=depth.reshape(shape), disparity=disparity,
                 occluded=occluded, rig=rig, primitives=primitives, gain=gain, offset=offset,
                 noise_std=noise_std)


# ------------------------------------------------------------ ready-made scene

WALL_Z = 1.8
TABLE_Y = 0.15


def _wall_shadow(box: Box, rig: Rig, margin: float) -> np.ndarray:
    """``(x0, y0, x1, y1)`` on the wall hidden by `box` from either camera, plus `margin`."""
    corners = np.array(np.meshgrid(*zip(box.lo, box.hi))).reshape(3, -1).T
    hits = []
    for centre in (np.zeros(3), rig.right_origin):
        scale = (WALL_Z - centre[2]) / (corners[:, 2] - centre[2])
        hits.append(centre[:2] + scale[:, None] * (corners[:, :2] - centre[:2]))
    hits = np.vstack(hits)
    return np.concatenate([hits.min(axis=0) - margin, hits.max(axis=0) + margin])


def _clear(texture: Texture, zones) -> Texture:
    """`texture` without the rectangles that overlap any of the ``(u0, v0, u1, v1)`` zones."""
    rows, cols = texture.levels.shape
    r = texture.rects
    col, row = np.meshgrid(np.arange(cols), np.arange(rows))
    (cu, cv), (ou, ov) = texture.cell, texture.origin
    u0, u1 = ou + (col + r[..., 0]) * cu, ou + (col + r[..., 2]) * cu
    v0, v1 = ov + (row + r[..., 1]) * cv, ov + (row + r[..., 3]) * cv
    rects = r.copy()
    for zu0, zv0, zu1, zv1 in zones:
        rects[(u0 < zu1) & (u1 > zu0) & (v0 < zv1) & (v1 > zv0)] = np.nan
    return replace(texture, rects=rects)


def _scene_primitives(rng: np.random.Generator, rig: Rig) -> list:
    """Wall, table and boxes of :func:`synthetic_scene`; the layout ignores roll and offset."""
    x0, _, w, _ = ROI
    cx, f = rig.centre[0], rig.focal_px
    n_boxes = int(rng.integers(1, 3))
    # Split the ROI's columns into one slot per box; each box's front face fits in its slot.
    edges = np.linspace(x0 + 4, x0 + w - 4, n_boxes + 1)
    boxes = []
    for k in range(n_boxes):
        z = rng.uniform(1.0, 1.25)                # front face; the back stays within 1.4 m
        deep = rng.uniform(0.1, min(0.2, 1.4 - z))
        width_px = rng.uniform(0.55, 0.8) * min(edges[k + 1] - edges[k], 90)
        left_px = rng.uniform(edges[k], edges[k + 1] - width_px)
        xa = (left_px - cx) * z / f
        xb = xa + width_px * z / f
        height = rng.uniform(0.16, 0.24)         # the top stays above eye level: unseen
        boxes.append(((xa, TABLE_Y - height, z), (xb, TABLE_Y, z + deep)))
    # Similar contrasts everywhere give corners of similar Harris strength.
    wall_base = rng.uniform(0.45, 0.55)
    prims = [_cardboard(rng, lo, hi, wall_base) for lo, hi in boxes]
    return _room(rng, rig, wall_base, prims, poster_bottom=0.3) + prims


def _cardboard(rng: np.random.Generator, lo, hi, wall_base: float) -> Box:
    """A cardboard box darker or lighter than the wall, with labels on every face."""
    tone = wall_base + rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 0.36)
    size = np.subtract(hi, lo)
    faces = tuple(random_texture(rng, (0, 0, size[a], size[b]), cell=0.1, fill=0.4, base=tone,
                                 contrast=(0.32, 0.4), sizes=(0.5, 0.75))
                  for a, b in (_FACE_UV[axis] for axis in (0, 0, 1, 1, 2, 2)))
    return Box(lo, hi, faces)


def _room(rng: np.random.Generator, rig: Rig, wall_base: float, boxes, poster_bottom: float) -> list:
    """The wall at 1.8 m with posters down to ``y = poster_bottom`` and the table: ``[wall, table]``."""
    # Posters: none that a box's silhouette would cut in either view, so that no
    # corner of the scene is an occlusion junction that moves between the views.
    wall_tex = random_texture(rng, (-1.2, -0.9, 1.2, poster_bottom), cell=0.17, fill=0.5,
                              base=wall_base, contrast=(0.32, 0.4))
    wall_tex = _clear(wall_tex, [_wall_shadow(box, rig, margin=0.04) for box in boxes])
    wall = Plane((0, 0, WALL_Z), (1, 0, 0), (0, 1, 0), 20, 20, wall_tex)
    # The table top reaches from 15 cm in front of the cameras to the wall, so
    # the wall/table crease has no parallax; it is lit only a little less than
    # the wall, so the boxes' edges crossing the crease make no strong corners.
    # Its sheets of paper lie near the cameras only (below the ROI).
    near, depth = 0.15, WALL_Z - 0.15
    table_tex = random_texture(rng, (-0.6, -depth / 2, 0.6, -depth / 2 + 0.5), cell=0.3, fill=0.5,
                               base=wall_base * rng.uniform(0.95, 1.0), contrast=(0.3, 0.4))
    table = Plane((0, TABLE_Y, near + depth / 2), (1, 0, 0), (0, 0, 1), 3, depth / 2, table_tex)
    return [wall, table]


def synthetic_scene(seed=0, *, vertical_offset_px: float = 0.0, roll_deg: float = 0.0,
                    noise_std: float = 1.0) -> Scene:
    """A ready-made indoor test scene: posters on a wall, a table, one or two boxes.

    A back wall at 1.8 m with posters, a table top 15 cm below the cameras
    reaching the wall, and one or two cardboard boxes with labels standing on it
    (front faces 1.0 to 1.25 m away, backs within 1.4 m), inside the
    centre-quarter ROI (columns 80..239, rows 60..179).  The right camera has
    gain 0.9 and offset +8 (a different webcam); both have camera noise.

    The scene is made for corner matching: posters, labels and box corners give
    about 25-40 strong, well-separated Harris corners in the ROI, spread over
    the wall and the boxes.  No poster is cut by a box's silhouette in either
    view and the table/wall crease has little contrast, so nearly every corner
    is a real 3-D point seen the same way by both cameras (occluded ones aside).

    Parameters
    ----------
    seed : int or numpy.random.Generator
        Draws the layout and the textures, then the noise.  The layout does not
        depend on the other arguments, so the same seed with another roll,
        offset or noise level shows the same scene.
    vertical_offset_px, roll_deg : float
        Passed to :class:`Rig` (an unrectified pair).
    noise_std : float
        Camera noise in grey levels, see :func:`render`.

    Returns
    -------
    Scene
        Its ``primitives`` are ``(wall, table, box[, box])``.

    Examples
    --------
    >>> scene = synthetic_scene(3)
    >>> [type(p).__name__ for p in scene.primitives]
    ['Plane', 'Plane', 'Box', 'Box']
    >>> x, y, w, h = ROI
    >>> d = scene.disparity[y:y + h, x:x + w]
    >>> round(float(np.nanmin(d)), 3), bool(np.nanmax(d) > 24)    # wall, boxes
    (16.667, True)
    """
    own = "synthetic_scene"
    rng = check_rng(seed, "seed", own)
    vertical_offset_px = check_number(vertical_offset_px, "vertical_offset_px", own)
    roll_deg = check_number(roll_deg, "roll_deg", own, low=-180, high=180)
    noise_std = check_number(noise_std, "noise_std", own, low=0)
    rig = Rig(vertical_offset_px=vertical_offset_px, roll_deg=roll_deg)
    prims = _scene_primitives(rng, rig)
    return render(prims, rig, seed=rng, noise_std=noise_std, gain=0.9, offset=8.0)


def true_matches(scene: Scene, left_xy, right_xy, tol: float = 1.5) -> np.ndarray:
    """Index of the true partner of each left point among right points.

    Parameters
    ----------
    scene : Scene
    left_xy : (N_l, 2) array_like
        Left points, e.g. detected corners.
    right_xy : (N_r, 2) array_like
        Right points.
    tol : float
        Largest distance in pixels between a right point and the true
        correspondence :meth:`Scene.correspond` of a left point.

    Returns
    -------
    index : (N_l,) ndarray of int
        Index of the nearest right point within `tol` of the true
        correspondence, or -1 when the left point is occluded or out of the right
        view, or no right point is that close.  Two left points may share a partner.

    Examples
    --------
    >>> scene = synthetic_scene(0)
    >>> left = [[120.0, 30.0], [0.0, 100.0]]
    >>> right = scene.correspond(left)[:1] + [[0.5, -0.5]]
    >>> true_matches(scene, left, np.vstack([[[5.0, 5.0]], right]))
    array([ 1, -1])
    """
    own = "true_matches"
    if not isinstance(scene, Scene):
        raise ParameterTypeError(message("scene", own, "a Scene", scene))
    left_xy = check_points(left_xy, "left_xy", own)
    right_xy = check_points(right_xy, "right_xy", own)
    tol = check_number(tol, "tol", own, low=0, low_open=True)
    index = np.full(len(left_xy), -1)
    if not len(left_xy) or not len(right_xy):
        return index
    truth = scene.correspond(left_xy)
    dist = np.linalg.norm(truth[:, None, :] - right_xy[None, :, :], axis=2)
    dist = np.where(np.isnan(dist), np.inf, dist)
    nearest = np.argmin(dist, axis=1)
    close = dist[np.arange(len(left_xy)), nearest] <= tol
    index[close] = nearest[close]
    return index


# ------------------------------------------------------- the depth demo (§5.2.3)

CAR_DEPTH = 0.06
"""Depth (along ``z``) of a toy car's body, metres."""


def toy_car(rng, x_centre: float, z_front: float, *, length: float = 0.13, name: str = "toy car") -> Group:
    """A toy car standing on the table, its side towards the cameras.

    Parts (all :class:`Box`): a body ``length`` long, 5 cm tall and 6 cm deep,
    1.6 cm above the table; a cabin on top with windows; four dark 3.2 cm wheels
    with light hubs, the front pair sticking 6 mm out of the body's side.  The
    body's side carries stripes (:func:`random_texture`) in a light or dark
    paint drawn from `rng`, so the car has corners of its own.

    Parameters
    ----------
    rng : numpy.random.Generator or int
        Draws the paint and the side's pattern.
    x_centre : float
        ``x`` of the car's middle, metres.
    z_front : float
        Depth of the body's side facing the cameras, metres (> 0).
    length : float
        Body length in metres, 0.05 to 0.5.
    name : str
        The group's label.

    Returns
    -------
    Group
        Parts ``(body, cabin, wheel, wheel, wheel, wheel)``.

    Examples
    --------
    >>> car = toy_car(0, 0.0, 0.8)
    >>> len(car.parts), car.lo.round(3).tolist(), car.hi.round(3).tolist()
    (6, [-0.065, 0.049, 0.794], [0.065, 0.15, 0.866])
    """
    own = "toy_car"
    rng = check_rng(rng, "rng", own)
    x_centre = check_number(x_centre, "x_centre", own)
    z_front = check_number(z_front, "z_front", own, low=0, low_open=True)
    length = check_number(length, "length", own, low=0.05, high=0.5)
    wheel, clearance, body_h, cabin_h = 0.032, 0.016, 0.05, 0.035
    bottom = TABLE_Y - clearance
    light = rng.uniform(0.7, 0.8)
    dark = rng.uniform(0.2, 0.3)
    tone = light if rng.random() < 0.5 else dark
    plain = Texture(base=tone)
    side = random_texture(rng, (0, 0, length, body_h), cell=0.03, fill=0.6, base=tone,
                          contrast=(0.26, 0.34), sizes=(0.45, 0.7))
    body = Box((x_centre - length / 2, bottom - body_h, z_front),
               (x_centre + length / 2, bottom, z_front + CAR_DEPTH),
               (plain, plain, plain, plain, side, plain))
    cabin_len = 0.55 * length
    windows = random_texture(rng, (0, 0, cabin_len, cabin_h), cell=cabin_h, fill=1.0, base=tone,
                             contrast=(0.28, 0.36), sizes=(0.5, 0.7))
    x0 = x_centre - 0.3 * length
    cabin = Box((x0, bottom - body_h - cabin_h, z_front + 0.008),
                (x0 + cabin_len, bottom - body_h, z_front + CAR_DEPTH - 0.008),
                (plain, plain, plain, plain, windows, plain))
    hub = Texture(base=0.12, cell=wheel, rects=[[[0.3, 0.3, 0.7, 0.7]]], levels=[[0.45]])
    wheels = [Box((x - wheel / 2, TABLE_Y - wheel, z0), (x + wheel / 2, TABLE_Y, z0 + 0.02), hub)
              for z0 in (z_front - 0.006, z_front + CAR_DEPTH - 0.014)
              for x in (x_centre - 0.3 * length, x_centre + 0.3 * length)]
    return Group((body, cabin, *wheels), name)


def _lab_primitives(rng: np.random.Generator, rig: Rig) -> list:
    """Wall, table and one cardboard box in the middle of the view (Fig. 5.11)."""
    cx, f = rig.centre[0], rig.focal_px
    z = rng.uniform(1.3, 1.45)
    deep = rng.uniform(0.12, 0.2)
    width_px = rng.uniform(36, 42)
    left_px = cx + 5 - width_px / 2 + rng.uniform(-2, 2)
    xa = (left_px - cx) * z / f
    height = rng.uniform(0.18, 0.24)             # the top stays above eye level: unseen
    wall_base = rng.uniform(0.45, 0.55)
    box = _cardboard(rng, (xa, TABLE_Y - height, z), (xa + width_px * z / f, TABLE_Y, z + deep),
                     wall_base)
    # The posters end 9 cm above the table: toy cars on the table, seen against
    # the plain bottom of the wall, never cut a poster.
    return _room(rng, rig, wall_base, [box], poster_bottom=0.06) + [box]


def _demo_rig(owner: str, vertical_offset_px, roll_deg) -> Rig:
    return Rig(vertical_offset_px=check_number(vertical_offset_px, "vertical_offset_px", owner),
               roll_deg=check_number(roll_deg, "roll_deg", owner, low=-180, high=180))


def lab_scene(seed=0, *, noise_std: float = 1.0, vertical_offset_px: float = 0.0,
              roll_deg: float = 0.0, supersample: int = 2) -> Scene:
    """The background of the depth demo (thesis Fig. 5.11): a box in front of a wall.

    A wall with posters at 1.8 m (the thesis' deepest background), a table top
    15 cm below the cameras reaching the wall, and one cardboard box with
    labels just right of the middle of the view, its front 1.3 to 1.45 m away
    and 36 to 42 px wide.  The posters stop 9 cm above the table, leaving the wall behind
    :func:`toy_car_scene`'s cars plain.  The right camera has gain 0.92 and
    offset +6.

    Parameters
    ----------
    seed : int or numpy.random.Generator
        Draws the layout and the textures, then the camera noise.
    noise_std : float
        Camera noise in grey levels.
    vertical_offset_px, roll_deg : float
        Passed to :class:`Rig`; the layout does not depend on them.
    supersample : int
        Rays per pixel side, see :func:`render` (1 renders 4 times faster).

    Returns
    -------
    Scene
        Its ``primitives`` are ``(wall, table, box)``.

    Examples
    --------
    >>> scene = lab_scene(0)
    >>> [type(p).__name__ for p in scene.primitives]
    ['Plane', 'Plane', 'Box']
    >>> box = scene.primitives[2]
    >>> bool(1.3 <= box.lo[2] <= 1.45), round(float(scene.disparity[60, 20]), 3)   # the wall
    (True, 16.667)
    """
    own = "lab_scene"
    rng = check_rng(seed, "seed", own)
    rig = _demo_rig(own, vertical_offset_px, roll_deg)
    prims = _lab_primitives(rng, rig)
    return render(prims, rig, seed=rng, noise_std=check_number(noise_std, "noise_std", own, low=0),
                  gain=0.92, offset=6.0, supersample=supersample)


def toy_car_layout(cars=0, rig: Rig = Rig()) -> tuple[tuple[float, float, float], ...]:
    """Positions of the two toy cars of :func:`toy_car_scene`: ``((x, z, length), ...)``, left first.

    ``x`` is the car's middle and ``z`` the depth of its side, metres; cars are
    9 to 11 cm long.  The left car stands 0.88 to 1.0 m away (disparity 30 to
    34 px), the right one 10 cm or more farther, up to 1.2 m (25 px or more);
    both stand in front of :func:`lab_scene`'s box (1.3 m or farther), the left
    one left of it and the right one right of it in the view, with their inner
    ends 132 to 138 px and 194 to 200 px from the image's left side.

    Examples
    --------
    >>> (xl, zl, ll), (xr, zr, lr) = toy_car_layout(0)
    >>> bool(0.88 <= zl <= 1.0 and zl + 0.1 <= zr <= 1.2), bool(xl < 0 < xr)
    (True, True)
    """
    own = "toy_car_layout"
    rng = check_rng(cars, "cars", own)
    if not isinstance(rig, Rig):
        raise ParameterTypeError(message("rig", own, "a Rig", rig))
    cx, f = rig.centre[0], rig.focal_px
    z_left = rng.uniform(0.88, 1.0)
    z_right = rng.uniform(z_left + 0.1, 1.2)
    out = []
    for z, inner_px, sign in ((z_left, rng.uniform(132, 138), -1), (z_right, rng.uniform(194, 200), 1)):
        length = rng.uniform(0.09, 0.11)
        inner = (inner_px - cx) * z / f
        out.append((float(inner + sign * length / 2), float(z), float(length)))
    return tuple(out)


def toy_car_scene(seed=0, *, cars=None, noise_std: float = 1.0, vertical_offset_px: float = 0.0,
                  roll_deg: float = 0.0, supersample: int = 2) -> Scene:
    """:func:`lab_scene` with two toy cars on the table, the left one nearer (Fig. 5.13).

    The background (wall, table, box) is exactly ``lab_scene(seed)``'s; the
    cars, drawn by :func:`toy_car_layout` and :func:`toy_car`, stand in front of
    the box, one left and one right of it.  The camera noise is drawn afresh, as
    in a second photograph.

    Parameters
    ----------
    seed : int
        The background's seed (as for :func:`lab_scene`).
    cars : int, optional
        Seed of the cars' positions, depths and paint, then of the camera noise;
        None uses `seed`.  Varying it gives variants of the same background.
    noise_std, vertical_offset_px, roll_deg, supersample
        As for :func:`lab_scene`.

    Returns
    -------
    Scene
        Its ``primitives`` are ``(wall, table, box, left car, right car)``; the
        cars are :class:`Group` objects named ``"left car"`` and ``"right car"``.

    Examples
    --------
    >>> scene = toy_car_scene(0)
    >>> [p.name for p in scene.primitives[3:]]
    ['left car', 'right car']
    >>> left, right = scene.primitives[3:]
    >>> bool(left.lo[2] < right.lo[2] < scene.primitives[2].lo[2])
    True
    """
    own = "toy_car_scene"
    base = check_rng(seed, "seed", own)
    cars = seed if cars is None else cars
    rng = np.random.default_rng(check_rng(cars, "cars", own).integers(2 ** 63))
    rig = _demo_rig(own, vertical_offset_px, roll_deg)
    prims = _lab_primitives(base, rig)
    layout = toy_car_layout(rng, rig)
    prims += [toy_car(rng, x, z, length=length, name=name)
              for (x, z, length), name in zip(layout, ("left car", "right car"))]
    return render(prims, rig, seed=rng, noise_std=check_number(noise_std, "noise_std", own, low=0),
                  gain=0.92, offset=6.0, supersample=supersample)


REALISTIC_COUNT = 11
"""How many realistic pairs ``images/realistic/`` holds (the thesis' Fig. 5.10 has 11)."""


def realistic_scene(index: int, *, noise_std: float = 1.5, supersample: int = 2) -> Scene:
    """Varied indoor pairs like the thesis' Fig. 5.10, some not rectified.

    Each index gives another room: one or two boxes (as in :func:`synthetic_scene`),
    up to two toy cars in front that may hide part of a box or cut a poster (so
    some corners are occlusion junctions without a true partner), another light
    direction, and another right camera (gain 0.85 to 1, offset -4 to +10).
    Two indices in three shift the right image down by 2.5 to 5 px, like the
    thesis' webcams (Table 5.4: 3 to 5 px), and every fourth one also rolls the
    right camera by up to 1 degree.

    Parameters
    ----------
    index : int
        Which pair, >= 1; the layout is a fixed function of it.
    noise_std : float
        Camera noise in grey levels.
    supersample : int
        Rays per pixel side, see :func:`render`.

    Returns
    -------
    Scene

    Examples
    --------
    >>> scene = realistic_scene(2)
    >>> scene.rig.vertical_offset_px > 0, realistic_scene(3).rig.vertical_offset_px
    (True, 0.0)
    """
    own = "realistic_scene"
    index = check_number(index, "index", own, low=1, integer=True)
    rng = np.random.default_rng([index, 20090701])
    offset_px = round(float(rng.uniform(2.5, 5.0)) * 2) / 2 if index % 3 else 0.0
    roll = round(float(rng.uniform(-1.0, 1.0)), 2) if index % 4 == 0 else 0.0
    rig = Rig(vertical_offset_px=offset_px, roll_deg=roll)
    prims = _scene_primitives(rng, rig)
    cx, f = rig.centre[0], rig.focal_px
    n_cars = int(rng.integers(0, 3))
    for k in range(n_cars):
        z = rng.uniform(0.75, 1.0)
        lo_px, hi_px = (85, 150) if k == 0 else (170, 235)
        x = (rng.uniform(lo_px, hi_px) - cx) * z / f
        prims.append(toy_car(rng, x, z, length=rng.uniform(0.1, 0.14), name=f"car {k + 1}"))
    light = (rng.uniform(-0.6, 0.6), -rng.uniform(0.5, 1.0), -1.0)
    return render(prims, rig, seed=rng, noise_std=check_number(noise_std, "noise_std", own, low=0),
                  gain=rng.uniform(0.85, 1.0), offset=rng.uniform(-4.0, 10.0), light=light,
                  ambient=rng.uniform(0.3, 0.45), supersample=supersample)
