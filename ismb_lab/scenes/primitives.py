"""Surfaces that rays can hit (:class:`Plane`, :class:`Box`, :class:`Cylinder`, :class:`Group`),
and :func:`cast`; a new kind needs only ``intersect``, ``normals`` and ``albedo``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, message
from .geometry import EPS, _rays, _vector
from .textures import Texture

__all__ = ["Box", "cast", "Cylinder", "Group", "Plane", "Primitive"]


@runtime_checkable
class Primitive(Protocol):
    """What :func:`render` needs from a surface.

    ``intersect(origins, dirs)`` of ``(N, 3)`` origins and unit directions returns ``(t, info)``:
    the first hit's ray parameter (``inf`` for a miss; only ``t > EPS`` counts) and ``(N, 3)``
    surface coordinates ``(u, v, face)``; ``normals(info)`` gives unit normals, ``albedo(info)``
    reflectances in ``[0, 1]``.
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
    """A textured two-sided rectangle: `centre`, orthogonal in-plane axes (normalised here; the
    texture's ``(u, v)`` are metres along them from the centre) and half sizes, metres.

    Attributes
    ----------
    centre : (3,) float ndarray
        The rectangle's centre, m.
    u_axis, v_axis : (3,) float ndarray
        Orthogonal in-plane axes, normalised.
    half_u, half_v : float
        Half sizes along them, m.
    texture : Texture
        The surface's texture.

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
    """A solid axis-aligned box from `lo` to `hi` (metres), seen from outside.

    `textures` is one Texture or one per face, ``-x, +x, -y (top), +y, -z (front), +z``; a face's
    ``(u, v)`` are metres from its ``lo`` corner: ``(z, y)``, ``(x, z)`` or ``(x, y)``.

    Attributes
    ----------
    lo, hi : (3,) float ndarray
        Opposite corners, m.
    textures : tuple of Texture
        One per face.

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
        return _piecewise(info[:, 2].astype(int), info[:, :2], self.textures)


@dataclass(frozen=True, eq=False)
class Cylinder:
    """A solid upright cylinder (axis along ``y``, ``y_range = (y_top, y_bottom)``) with flat caps.

    The side's ``(u, v)`` are the arc length from the point facing ``-z``, positive towards
    ``+x``, and ``y - y_top``; `cap` (default plain ``texture.base``) lies on
    ``(x - x_axis, z - z_axis)``.

    Attributes
    ----------
    centre_xz : (2,) float ndarray
        The axis' ``(x, z)``, m.
    radius : float
        Radius, m.
    y_range : (y_top, y_bottom) tuple
        Vertical extent, m (``y`` down).
    texture : Texture
        The side's texture.
    cap : Texture, optional
        The caps' texture.
    name : str, default ""
        The object's name.

    Examples
    --------
    >>> can = Cylinder((0.0, 1.2), 0.1, (-0.1, 0.1), Texture(base=0.3))
    >>> t, info = can.intersect([[0, 0, 0], [0, -1, 0]], [[0, 0, 1], [0, 1, 0]])
    >>> t.round(3), info[:, 2], can.normals(info[:1]).round(3)   # the side; a cap, face 1
    (array([1.1, inf]), array([ 0., nan]), array([[ 0.,  0., -1.]]))
    """

    centre_xz: np.ndarray
    radius: float
    y_range: tuple
    texture: Texture
    cap: Texture | None = None
    name: str = ""

    def __post_init__(self):
        own = "Cylinder"
        object.__setattr__(self, "centre_xz", _vector(self.centre_xz, "centre_xz", own, 2))
        object.__setattr__(self, "radius", check_number(self.radius, "radius", own, low=0, low_open=True))
        y = _vector(self.y_range, "y_range", own, 2)
        if not y[1] > y[0]:
            raise ParameterError(message("y_range", own, "(y_top, y_bottom) with y_top < y_bottom",
                                         tuple(y)))
        object.__setattr__(self, "y_range", (float(y[0]), float(y[1])))
        _check_texture(self.texture, "texture", own)
        cap = Texture(base=self.texture.base) if self.cap is None else self.cap
        object.__setattr__(self, "cap", _check_texture(cap, "cap", own))
        if not isinstance(self.name, str):
            raise ParameterTypeError(message("name", own, "a str", self.name))

    @property
    def lo(self) -> np.ndarray:
        """Lower corner of the bounding box."""
        (x, z), r = self.centre_xz, self.radius
        return np.array([x - r, self.y_range[0], z - r])

    @property
    def hi(self) -> np.ndarray:
        """Upper corner of the bounding box."""
        (x, z), r = self.centre_xz, self.radius
        return np.array([x + r, self.y_range[1], z + r])

    def intersect(self, origins, dirs) -> tuple[np.ndarray, np.ndarray]:
        """First hits of rays from outside: ``(t, info)``, face 0 the side, 1 the top, 2 the bottom."""
        origins, dirs, t, info, near = _misses(origins, dirs, self.lo, self.hi, "Cylinder.intersect")
        if not len(near):
            return t, info
        o, d = origins[near], dirs[near]
        (xc, zc), r = self.centre_xz, self.radius
        ox, oz = o[:, 0] - xc, o[:, 2] - zc
        a = d[:, 0] ** 2 + d[:, 2] ** 2
        b = 2 * (d[:, 0] * ox + d[:, 2] * oz)
        disc = b ** 2 - 4 * a * (ox ** 2 + oz ** 2 - r ** 2)
        with np.errstate(divide="ignore", invalid="ignore"):
            ts = (-b - np.sqrt(disc)) / (2 * a)
        ys = o[:, 1] + ts * d[:, 1]
        side = (disc >= 0) & (a > 0) & (ts > EPS) & (ys >= self.y_range[0]) & (ys <= self.y_range[1])
        best = np.where(side, ts, np.inf)
        face = np.zeros(len(o))
        for f, y in ((1.0, self.y_range[0]), (2.0, self.y_range[1])):
            with np.errstate(divide="ignore", invalid="ignore"):
                tc = (y - o[:, 1]) / d[:, 1]
                px, pz = ox + tc * d[:, 0], oz + tc * d[:, 2]
            cap = (np.abs(d[:, 1]) > 1e-15) & (tc > EPS) & (px ** 2 + pz ** 2 <= r ** 2) & (tc < best)
            best = np.where(cap, tc, best)
            face = np.where(cap, f, face)
        hit = np.isfinite(best)
        tf = np.where(hit, best, 0.0)
        px, py, pz = ox + tf * d[:, 0], o[:, 1] + tf * d[:, 1], oz + tf * d[:, 2]
        on_side = face == 0
        u = np.where(on_side, r * np.arctan2(px, -pz), px)
        v = np.where(on_side, py - self.y_range[0], pz)
        t[near[hit]] = best[hit]
        info[near[hit]] = np.stack([u, v, face], axis=1)[hit]
        return t, info

    def normals(self, info) -> np.ndarray:
        """Outward unit normals: radial on the side, ``-y`` on the top, ``+y`` on the bottom."""
        info = np.asarray(info, dtype=float)
        angle = info[:, 0] / self.radius
        out = np.stack([np.sin(angle), np.zeros(len(info)), -np.cos(angle)], axis=1)
        out[info[:, 2] == 1] = (0.0, -1.0, 0.0)
        out[info[:, 2] == 2] = (0.0, 1.0, 0.0)
        return out

    def albedo(self, info) -> np.ndarray:
        """The side's texture at its ``(u, v)``, the cap's on the caps."""
        info = np.asarray(info, dtype=float)
        side = info[:, 2] == 0
        out = np.empty(len(info))
        if side.any():
            out[side] = self.texture(info[side, :2])
        if (~side).any():
            out[~side] = self.cap(info[~side, :2])
        return out


def _near_rays(origins: np.ndarray, dirs: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Indices of the rays that pass the bounding sphere of the box ``lo..hi`` (a cheap cull)."""
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    to_c = centre - origins
    along = np.einsum("ij,ij->i", to_c, dirs)       # dirs are unit vectors
    miss2 = np.einsum("ij,ij->i", to_c, to_c) - along ** 2
    return np.flatnonzero((miss2 <= radius ** 2 * (1 + 1e-9)) & (along > -radius))


@dataclass(frozen=True, eq=False)
class Group:
    """Several boxes (they may overlap: the first hit wins) rendered as one primitive, e.g. a toy
    car; a hit's ``info`` is ``(u, v, 6 * part + face)``.

    Attributes
    ----------
    parts : tuple of Box
        The boxes.
    name : str, default ""
        The object's name.

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
        return _piecewise(part, local, [p.albedo for p in self.parts])


def _piecewise(index, info, functions) -> np.ndarray:
    """``functions[k](info)`` on the rows where `index` is ``k``."""
    out = np.zeros(len(info))
    for k in np.unique(index):
        sel = index == k
        out[sel] = functions[k](info[sel])
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
    """First hit of each ray among several primitives: the ray parameter (``inf`` for none), the
    index of the primitive hit (-1) and its surface coordinates ``(u, v, face)`` (NaN).

    Parameters
    ----------
    primitives : sequence of Primitive
        The surfaces.
    origins, dirs : (N, 3) float array_like
        Ray origins and unit directions.

    Returns
    -------
    t : (N,) float ndarray
        Ray parameter of the first hit, ``inf`` for none.
    which : (N,) int ndarray
        Index of the primitive hit, -1 for none.
    info : (N, 3) float ndarray
        Surface coordinates ``(u, v, face)`` of the hit, NaN for none.

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
