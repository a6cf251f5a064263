"""Random designs of two or three textured objects standing before a textured wall, with their truth.

A family changes a design through a :class:`Look`, hooks that draw from the same Generator in a
fixed order (wall, disparities, wall texture, sizes, places, object by object, cameras, noise).

>>> design = draw_objects(np.random.default_rng(0), 2, StereoCamera.pinhole(), Look())
>>> [t.rank for t in design.truth], design.camera["noise_std"]
([1, 2], 1.0)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np

from .._core.validation import ParameterTypeError, message
from ..cameras.camera import StereoCamera
from .primitives import Box, Cylinder, Group, Plane
from .textures import Texture, random_texture

__all__ = ["HIGH", "LAYOUT_ROI", "LOW", "MIN_GAP_PX", "Design", "Look", "ObjectTruth", "Placement",
           "draw_objects"]

LAYOUT_ROI = (40, 40, 240, 160)
"""The ROI ``(x, y, w, h)`` in which the families place their objects."""

MIN_GAP_PX = 3.0
"""Smallest disparity difference between two objects, or an object and the wall, pixels."""

WALL_DISPARITY = (5.0, 9.0)
OBJECT_DISPARITY = (10.0, 26.0)
HIGH, LOW = (0.28, 0.4), (0.07, 0.13)
"""Texture contrasts (ranges of albedo steps) of high- and low-contrast surfaces."""


@dataclass(frozen=True)
class ObjectTruth:
    """What was put into the scene, for scoring a ranking.

    ``name`` and ``index`` are the primitive's in ``Scene.primitives`` (``"object 1"`` is the
    leftmost), ``rank`` 1 the nearest; ``disparity`` (px) and ``depth_m`` are of the face (or
    cylinder line) nearest the cameras; ``box_xy`` is the left-image extent ``(x0, y0, x1, y1)``
    and ``centre_xy`` a point of that face inside the image.
    """

    name: str
    index: int
    rank: int
    kind: str
    disparity: float
    depth_m: float
    box_xy: tuple
    centre_xy: tuple
    contrast: str
    texture: str


@dataclass(frozen=True)
class Design:
    """A drawn layout before rendering: primitives (objects left to right), truth (nearest first),
    the right camera's ``gain``, ``offset`` and ``noise_std``, and the noise seeds of the
    background and of the scene."""

    wall: Plane
    objects: tuple
    truth: tuple
    wall_disparity: float
    camera: dict
    noise: tuple


@dataclass(frozen=True)
class Placement:
    """Where the objects of `widths` stand: left edges between `lo` and `hi`, gaps in `gap`; with
    `pin_left` the first starts at `lo` (a box), with `pin_right` the last ends at `hi`."""

    lo: float
    hi: float
    gap: tuple
    widths: np.ndarray
    pin_left: bool = False
    pin_right: bool = False


def plain_wall(rng, mode: str) -> tuple:
    """Posters of high contrast (no draw)."""
    return "posters", HIGH


def side_by_side(rng, widths: np.ndarray) -> Placement:
    """Anywhere in the layout ROI, 8 to 20 px apart (no draw)."""
    rx, _, rw, _ = LAYOUT_ROI
    return Placement(rx + 2, rx + rw - 2, (8.0, 20.0), widths)


def high_contrast(rng, mode: str) -> str:
    """Every object of high contrast (no draw)."""
    return "high"


def posters(rng) -> str:
    """Every object papered with posters (no draw)."""
    return "posters"


def common_sizes(rng, n: int) -> tuple:
    """Widths 32 to 64 px and heights 36 to 68 px."""
    return rng.uniform(32, 64, n), rng.uniform(36, 68, n)


def box_or_cylinder(rng, box_only: bool) -> str:
    """A cylinder one time in three (0.35), a box otherwise or when `box_only` (one draw either way)."""
    return "cylinder" if rng.random() < 0.35 and not box_only else "box"


def quiet_cameras(rng) -> dict:
    """Noise of 1 grey level, the right camera with gain 0.92 and offset 6 (no draw)."""
    return {"gain": 0.92, "offset": 6.0, "noise_std": 1.0}


@dataclass(frozen=True)
class Look:
    """What a family changes in :func:`draw_objects`: hooks that may draw from the layout's Generator.

    ``wall(rng, mode) -> (kind, contrast)``: the wall's texture (``"posters"``, ``"stripes"``,
    ``"tiles"``) and contrast (:data:`HIGH`, :data:`LOW`), `mode` being ``"low-on-high"``,
    ``"high-on-low"`` or ``"mixed"``; ``sizes(rng, n) -> (widths, heights)``;
    ``placement(rng, widths) -> Placement``; then per object, left to right,
    ``shape(rng, box_only) -> "box" | "cylinder"``, ``contrast(rng, mode) -> "low" | "high"``
    and ``texture(rng) -> kind``; last ``camera(rng) -> dict`` of ``gain``, ``offset``, ``noise_std``.

    Attributes
    ----------
    wall, placement, contrast, texture, camera, sizes, shape : callable
        The hooks above; defaults :func:`plain_wall`, :func:`side_by_side`, :func:`high_contrast`,
        :func:`posters`, :func:`quiet_cameras`, :func:`common_sizes`, :func:`box_or_cylinder`.

    Examples
    --------
    >>> Look(camera=lambda rng: {"gain": 1.0, "offset": 0.0, "noise_std": 3.0}).camera(None)["noise_std"]
    3.0
    """

    wall: Callable = plain_wall
    placement: Callable = side_by_side
    contrast: Callable = high_contrast
    texture: Callable = posters
    camera: Callable = quiet_cameras
    sizes: Callable = common_sizes
    shape: Callable = box_or_cylinder

    def __post_init__(self):
        for f in fields(self):
            if not callable(getattr(self, f.name)):
                raise ParameterTypeError(message(f.name, "Look", "a callable", getattr(self, f.name)))


def _disparities(rng, n: int, wall: float) -> np.ndarray:
    """`n` disparities in OBJECT_DISPARITY, MIN_GAP_PX apart and from `wall` (rejection sampling)."""
    lo = max(OBJECT_DISPARITY[0], wall + MIN_GAP_PX)
    while True:
        d = np.sort(rng.uniform(lo, OBJECT_DISPARITY[1], n))
        if np.all(np.diff(d) >= MIN_GAP_PX):
            return d


def _columns(rng, widths, lo: float, hi: float, gap: tuple) -> np.ndarray:
    """Left edges of objects of `widths` placed left to right in ``[lo, hi]``, gaps in `gap`."""
    widths = np.asarray(widths, float)
    gaps = rng.uniform(*gap, len(widths) - 1)
    slack = hi - lo - widths.sum() - gaps.sum()
    if slack < 0:                              # shrink the objects to fit
        widths = widths * (hi - lo - gaps.sum()) / widths.sum()
        slack = 0.0
    cuts = np.sort(rng.uniform(0, slack, len(widths) + 1))
    spare = np.diff(cuts)                      # split the slack at random, ends included
    x0 = lo + cuts[0] + np.concatenate([[0], np.cumsum(widths[:-1] + gaps + spare[:-1])])
    return x0, widths


def _texture(rng, kind: str, extent, pixel_m: float, base: float, contrast) -> Texture:
    """Posters, stripes or tiles on `extent` (metres), sized in pixels via `pixel_m` (m per px)."""
    if kind == "posters":
        return random_texture(rng, extent, cell=rng.uniform(16, 24) * pixel_m, fill=0.55, base=base,
                              contrast=contrast, ripple=0.05)
    step = float(rng.uniform(*contrast)) * rng.choice([-1.0, 1.0])
    period = rng.uniform(7, 13) * pixel_m
    if base + step < 0.04 or base + step > 0.96:
        step = -step
    if kind == "tiles":
        return Texture(base=base, checker=period / 2, checker_contrast=min(abs(step) * 2, 1.0))
    u0, _, u1, v1 = extent
    cols = max(1, int(np.ceil((u1 - u0) / period)))
    rects = np.tile([0.0, -1e3, 0.5, 1e3], (1, cols, 1))
    return Texture(base=base, cell=(period, 2e3), origin=(u0, -1e3), rects=rects,
                   levels=np.full((1, cols), base + step))


def _wall(rng, look: Look, mode: str, wall_z: float, rig: StereoCamera) -> tuple:
    """The wall plane at `wall_z` (three times the field of view) and its tone."""
    f, (cx, cy) = rig.focal_px, rig.centre
    base = float(rng.uniform(0.4, 0.6))
    kind, contrast = look.wall(rng, mode)
    half = (cx + 40) * wall_z / f, (cy + 40) * wall_z / f
    tex = _texture(rng, kind, (-half[0], -half[1], half[0], half[1]), wall_z / f, base, contrast)
    return Plane((0, 0, wall_z), (1, 0, 0), (0, 1, 0), 3 * half[0], 3 * half[1], tex), base


def _object(rng, look: Look, mode: str, k: int, left: float, width: float, height: float, d: float,
            order: int, wall_base: float, box_only: bool, rig: StereoCamera) -> tuple:
    """Object ``k`` (from 0, left to right) at disparity `d`: its primitive and its truth."""
    f, fb, (cx, cy) = rig.focal_px, rig.focal_px * rig.baseline_m, rig.centre
    _, ry, _, rh = LAYOUT_ROI
    z = fb / d
    pm = z / f                                   # metres per pixel at the object
    kind = look.shape(rng, box_only)
    contrast = look.contrast(rng, mode)
    tone = float(np.clip(wall_base + rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 0.3), 0.1, 0.9))
    tex_kind = look.texture(rng)
    levels = LOW if contrast == "low" else HIGH
    y0 = float(rng.uniform(ry + 4, ry + rh - 4 - height))
    top, bottom = (y0 - cy) * pm, (y0 + height - cy) * pm
    name = f"object {k + 1}"
    if kind == "box":
        xa, xb = (left - cx) * pm, (left + width - cx) * pm
        deep = rng.uniform(0.05, 0.12)
        tex = _texture(rng, tex_kind, (0, 0, xb - xa, bottom - top), pm, tone, levels)
        side = Texture(base=tone)
        prim = Group((Box((xa, top, z), (xb, bottom, z + deep), (side, side, side, side, tex, side)),), name)
        span = (left, left + width)
    else:
        r = width / 2 * pm
        xc = (left + width / 2 - cx) * pm
        tex = _texture(rng, tex_kind, (-np.pi * r, 0, np.pi * r, bottom - top), pm, tone, levels)
        prim = Cylinder((xc, z + r), r, (top, bottom), tex, name=name)
        span = (left + width / 2 - 0.3 * width, left + width / 2 + 0.3 * width)
    vis = (max(span[0], 1.0), min(span[1], rig.width - 2.0))
    truth = ObjectTruth(name, k + 1, order + 1, kind, d, float(z),
                        (float(left), float(y0), float(left + width), float(y0 + height)),
                        (float(np.mean(vis)), float(y0 + height / 2)), str(contrast), str(tex_kind))
    return prim, truth


def draw_objects(rng: np.random.Generator, n: int, rig: StereoCamera, look: Look) -> Design:
    """Draw `n` objects (2 or 3) at distinct depths before a wall, as `look` says, from `rng`.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source.
    n : int
        2 or 3 objects.
    rig : StereoCamera
        The cameras.
    look : Look
        The family's hooks.

    Returns
    -------
    design : Design
        The wall, objects, truth and camera settings.

    Examples
    --------
    >>> d = draw_objects(np.random.default_rng(1), 3, StereoCamera.pinhole(), Look())
    >>> bool(np.all(np.diff([t.disparity for t in d.truth]) <= -MIN_GAP_PX)), len(d.objects)
    (True, 3)
    """
    fb = rig.focal_px * rig.baseline_m
    wall_d = float(rng.uniform(*WALL_DISPARITY))
    disp = _disparities(rng, n, wall_d)
    order = rng.permutation(n)                  # which column gets which depth
    objects_d = disp[::-1][order]               # left to right; [::-1] makes order[k] == 0 the nearest
    mode = str(rng.choice(["low-on-high", "high-on-low", "mixed"]))
    wall, wall_base = _wall(rng, look, mode, fb / wall_d, rig)
    widths, heights = look.sizes(rng, n)
    place = look.placement(rng, widths)
    x0, widths = _columns(rng, place.widths, place.lo, place.hi, place.gap)
    if place.pin_left:
        x0[0] = place.lo
    if place.pin_right:
        x0[-1] = place.hi - widths[-1]
    prims, truth = [], []
    for k in range(n):
        prim, t = _object(rng, look, mode, k, x0[k], widths[k], heights[k], float(objects_d[k]),
                          int(order[k]), wall_base, place.pin_left and k == 0, rig)
        prims.append(prim)
        truth.append(t)
    camera = look.camera(rng)
    noise = tuple(int(s) for s in rng.integers(2 ** 63, size=2))
    return Design(wall, tuple(prims), tuple(sorted(truth, key=lambda t: t.rank)), wall_d, camera, noise)
