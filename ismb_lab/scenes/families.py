"""Families of depth-demo scenes: textured objects in front of a textured wall, with exact truth.

Each family draws two or three objects (boxes and upright cylinders) standing at
distinct depths in front of a wall, renders the *scene* pair and the *background*
pair (the same wall without the objects, a second photograph: fresh camera noise),
and records which object is nearest.  They exercise the §5.2.3 depth demo
(:func:`ismb_lab.depth_demo.relative_depth`) where it is weak:

``"contrast"``
    Objects of varied size, some with low-contrast textures in front of a
    high-contrast wall, or the reverse (a high-contrast object, a quiet wall).
``"repetitive"``
    Stripes and tiles with a period of 7 to 13 px, on the objects and often on
    the wall, so that several candidates in the 40 px window look alike.
``"border"``
    One box straddles the left image border (its left edge 8 px beyond it to 4 px
    inside), so that its left part is out
    of the right view; objects stand 2 to 6 px apart, so that a nearer object on
    the right hides part of its neighbour in the right view; and in half the
    layouts another object leaves the left image on the right.
``"cameras"``
    Camera noise of 2 to 4 grey levels, and a right camera with gain 0.75 to 1.3
    and offset -20 to +20 (the left camera has gain 1, offset 0).

Geometry of every layout (the default :class:`~ismb_lab.scenes.Rig`: 320 x 240
images, ``f B = 30`` px m, so ``d = 30 / Z``):

* the wall has disparity 5 to 9 px (3.3 to 6 m);
* every object has a disparity in 10 to 26 px, at least :data:`MIN_GAP_PX` = 3 px
  from every other object's and from the wall's: ranking is meaningful, since
  3 px is six times the half-pixel quantisation of integer corners;
* objects are 32 to 64 px wide and 36 to 68 px tall (cylinders a little
  narrower), side by side in the ROI :data:`LAYOUT_ROI` = ``(40, 40, 240, 160)``;
* the candidate window's shift is the middle of the layout's disparity range
  (wall to nearest object), so every true match lies inside the 40 px window;
  :attr:`Layout.shift` records it.

A family function returns the scene (or, with ``empty=True``, the background) as a
:class:`~ismb_lab.scenes.Scene`; its ``primitives`` are the wall, then the objects,
each named (``"object 1"`` ... from left to right), so that :func:`object_ids` tells
which object every pixel sees.  :func:`object_layout` returns both pairs with the
truth (:class:`Layout`).  Randomness comes only from the seed or Generator passed in.

>>> lay = object_layout(0, 3, family="contrast")
>>> [o.rank for o in lay.objects], lay.family, lay.roi
([1, 2, 3], 'contrast', (40, 40, 240, 160))
>>> bool(np.all(np.diff([o.disparity for o in lay.objects]) <= -MIN_GAP_PX))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validation import ParameterTypeError, check_choice, check_number, check_rng, message
from .geometry import Rig
from .primitives import Box, Cylinder, Group, Plane, cast
from .render import Scene, render
from .textures import Texture, random_texture

__all__ = ["FAMILIES", "LAYOUT_ROI", "MIN_GAP_PX", "Layout", "ObjectTruth", "border_scene",
           "camera_scene", "contrast_scene", "object_ids", "object_layout", "repetitive_scene"]

FAMILIES = ("contrast", "repetitive", "border", "cameras")
"""The scene families, in the order the protocol cycles through them."""

LAYOUT_ROI = (40, 40, 240, 160)
"""The ROI ``(x, y, w, h)`` in which the families place their objects (columns 40..279)."""

MIN_GAP_PX = 3.0
"""Smallest disparity difference between two objects, or an object and the wall, pixels."""

WALL_DISPARITY = (5.0, 9.0)
OBJECT_DISPARITY = (10.0, 26.0)
HIGH, LOW = (0.28, 0.4), (0.07, 0.13)     # texture contrasts (albedo steps)


@dataclass(frozen=True)
class ObjectTruth:
    """What was put into the scene, for scoring a ranking.

    Attributes
    ----------
    name : str
        The primitive's name in ``Scene.primitives`` (``"object 1"`` is the leftmost).
    index : int
        Its index in ``Scene.primitives``.
    rank : int
        1 = nearest.
    kind : {"box", "cylinder"}
    disparity : float
        Designed disparity of the face (or the line of the cylinder) nearest the cameras, pixels.
    depth_m : float
        Its depth ``z``, metres.
    box_xy : (x0, y0, x1, y1)
        The object's extent in the left image, pixels (may reach past the image).
    centre_xy : (float, float)
        A left-image point on that face, inside the image (the middle of its visible part).
    contrast : {"low", "high"}
    texture : {"posters", "stripes", "tiles"}
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


@dataclass(frozen=True, eq=False)
class Layout:
    """One random layout: the background and scene pairs and the truth.

    Attributes
    ----------
    family : str
    seed : int or None
        The seed it was drawn from (None when drawn from a Generator).
    background, scene : Scene
        The empty view and the view with the objects (same wall, same cameras, fresh noise).
    objects : tuple of ObjectTruth
        Nearest first.
    wall_disparity : float
    shift : float
        Candidate-window shift for this layout (``MatchConfig.shift``), pixels.
    roi : (x, y, w, h)
        :data:`LAYOUT_ROI`.
    """

    family: str
    seed: int | None
    background: Scene
    scene: Scene
    objects: tuple
    wall_disparity: float
    shift: float
    roi: tuple = LAYOUT_ROI

    @property
    def order(self) -> tuple:
        """Object names nearest first."""
        return tuple(o.name for o in self.objects)


# ------------------------------------------------------------------ design

@dataclass(frozen=True)
class _Design:
    """A drawn layout before rendering: primitives, truth and cameras."""

    wall: Plane
    objects: tuple           # primitives, left to right
    truth: tuple             # ObjectTruth, nearest first
    wall_disparity: float
    camera: dict             # render() keywords: gain, offset, noise_std
    noise: tuple             # two seeds: background, scene


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


def _design(rng: np.random.Generator, family: str, n: int, rig: Rig) -> _Design:
    f, fb, (cx, cy) = rig.focal_px, rig.focal_px * rig.baseline_m, rig.centre
    rx, ry, rw, rh = LAYOUT_ROI
    wall_d = float(rng.uniform(*WALL_DISPARITY))
    wall_z = fb / wall_d
    disp = _disparities(rng, n, wall_d)
    order = rng.permutation(n)                  # which column gets which depth
    objects_d = disp[::-1][order]               # left to right; [::-1] makes order[k] == 0 the nearest
    contrast_mode = rng.choice(["low-on-high", "high-on-low", "mixed"])
    if family == "contrast":
        wall_contrast = LOW if contrast_mode == "high-on-low" else HIGH
    else:
        wall_contrast = HIGH
    wall_base = float(rng.uniform(0.4, 0.6))
    wall_kind = rng.choice(["stripes", "tiles", "posters"]) if family == "repetitive" else "posters"
    half = (cx + 40) * wall_z / f, (cy + 40) * wall_z / f
    wall_tex = _texture(rng, wall_kind, (-half[0], -half[1], half[0], half[1]), wall_z / f, wall_base,
                        wall_contrast)
    wall = Plane((0, 0, wall_z), (1, 0, 0), (0, 1, 0), 3 * half[0], 3 * half[1], wall_tex)

    widths = rng.uniform(32, 64, n)
    heights = rng.uniform(36, 68, n)
    lo, hi, gap = rx + 2, rx + rw - 2, (8.0, 20.0)
    right_border = False
    if family == "border":
        gap = (2.0, 6.0)
        lo = float(rng.uniform(-8, 4))                  # a box across the image's left edge
        widths[0] = rx - lo + rng.uniform(22, 36)       # 22-36 px inside the ROI
        right_border = bool(rng.random() < 0.5) and n > 1
        if right_border:
            hi = float(rng.uniform(300, 318))
            widths[-1] = hi - (rx + rw) + rng.uniform(22, 36)
    x0, widths = _columns(rng, widths, lo, hi, gap)
    if family == "border":                          # pin the border objects to the border
        x0[0] = lo
        if right_border:
            x0[-1] = hi - widths[-1]
    prims, truth = [], []
    for k in range(n):
        d = float(objects_d[k])
        z = fb / d
        pm = z / f                                   # metres per pixel at the object
        kind = "cylinder" if rng.random() < 0.35 else "box"
        if family == "border" and k == 0:
            kind = "box"
        contrast = {"low-on-high": "low", "high-on-low": "high"}.get(
            contrast_mode, rng.choice(["low", "high"])) if family == "contrast" else "high"
        tone = float(np.clip(wall_base + rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 0.3), 0.1, 0.9))
        tex_kind = rng.choice(["stripes", "tiles"]) if family == "repetitive" else "posters"
        levels = LOW if contrast == "low" else HIGH
        h = heights[k]
        y0 = float(rng.uniform(ry + 4, ry + rh - 4 - h))
        top, bottom = (y0 - cy) * pm, (y0 + h - cy) * pm
        name = f"object {k + 1}"
        if kind == "box":
            xa, xb = (x0[k] - cx) * pm, (x0[k] + widths[k] - cx) * pm
            deep = rng.uniform(0.05, 0.12)
            tex = _texture(rng, tex_kind, (0, 0, xb - xa, bottom - top), pm, tone, levels)
            side = Texture(base=tone)
            prim = Group((Box((xa, top, z), (xb, bottom, z + deep), (side, side, side, side, tex, side)),),
                         name)
            span = (x0[k], x0[k] + widths[k])
        else:
            r = widths[k] / 2 * pm
            xc = (x0[k] + widths[k] / 2 - cx) * pm
            tex = _texture(rng, tex_kind, (-np.pi * r, 0, np.pi * r, bottom - top), pm, tone, levels)
            prim = Cylinder((xc, z + r), r, (top, bottom), tex, name=name)
            span = (x0[k] + widths[k] / 2 - 0.3 * widths[k], x0[k] + widths[k] / 2 + 0.3 * widths[k])
        prims.append(prim)
        vis = (max(span[0], 1.0), min(span[1], rig.width - 2.0))
        truth.append(ObjectTruth(name, k + 1, int(order[k]) + 1, kind, d, float(z),
                                 (float(x0[k]), float(y0), float(x0[k] + widths[k]), float(y0 + h)),
                                 (float(np.mean(vis)), float(y0 + h / 2)), str(contrast), str(tex_kind)))
    if family == "cameras":
        camera = {"gain": float(rng.uniform(0.75, 1.3)), "offset": float(rng.uniform(-20, 20)),
                  "noise_std": float(rng.uniform(2.0, 4.0))}
    else:
        camera = {"gain": 0.92, "offset": 6.0, "noise_std": 1.0}
    noise = tuple(int(s) for s in rng.integers(2 ** 63, size=2))
    return _Design(wall, tuple(prims), tuple(sorted(truth, key=lambda t: t.rank)), wall_d, camera, noise)


def _check(seed, family, n_objects, supersample, owner):
    rng = check_rng(seed, "seed", owner)
    family = check_choice(family, "family", owner, FAMILIES)
    n = check_number(n_objects, "n_objects", owner, low=2, high=3, integer=True)
    s = check_number(supersample, "supersample", owner, low=1, high=8, integer=True)
    return rng, family, n, s


def _render(design: _Design, rig: Rig, empty: bool, supersample: int) -> Scene:
    prims = [design.wall] + ([] if empty else list(design.objects))
    return render(prims, rig, seed=design.noise[0 if empty else 1], supersample=supersample,
                  **design.camera)


def _family_scene(family: str, owner: str, seed, n_objects, empty, supersample) -> Scene:
    rng, family, n, s = _check(seed, family, n_objects, supersample, owner)
    if not isinstance(empty, bool):
        raise ParameterTypeError(message("empty", owner, "True or False", empty))
    rig = Rig()
    return _render(_design(rng, family, n, rig), rig, empty, s)


_DOC = """{what}

    Parameters
    ----------
    seed : int or numpy.random.Generator
        Draws the layout, the textures and then the cameras' noise.
    n_objects : {{2, 3}}
    empty : bool
        Render the background instead: the same wall and cameras without the
        objects, with fresh noise (a second photograph).
    supersample : int
        Rays per pixel side (see :func:`~ismb_lab.scenes.render`).

    Returns
    -------
    Scene
        ``primitives`` are the wall and then the objects, left to right; use
        :func:`object_layout` for the truth.

    Examples
    --------
    >>> scene = {name}(0)
    >>> [getattr(p, "name", "wall") for p in scene.primitives]
    ['wall', 'object 1', 'object 2']
    >>> len({name}(0, empty=True).primitives)
    1
    """


def contrast_scene(seed=0, *, n_objects: int = 2, empty: bool = False, supersample: int = 1) -> Scene:
    return _family_scene("contrast", "contrast_scene", seed, n_objects, empty, supersample)


def repetitive_scene(seed=0, *, n_objects: int = 2, empty: bool = False, supersample: int = 1) -> Scene:
    return _family_scene("repetitive", "repetitive_scene", seed, n_objects, empty, supersample)


def border_scene(seed=0, *, n_objects: int = 2, empty: bool = False, supersample: int = 1) -> Scene:
    return _family_scene("border", "border_scene", seed, n_objects, empty, supersample)


def camera_scene(seed=0, *, n_objects: int = 2, empty: bool = False, supersample: int = 1) -> Scene:
    return _family_scene("cameras", "camera_scene", seed, n_objects, empty, supersample)


contrast_scene.__doc__ = _DOC.format(
    name="contrast_scene", what="Boxes and cylinders of varied size and contrast in front of a wall "
    "(the ``\"contrast\"`` family).")
repetitive_scene.__doc__ = _DOC.format(
    name="repetitive_scene", what="Striped and tiled objects, often before a striped or tiled wall "
    "(``\"repetitive\"``).")
border_scene.__doc__ = _DOC.format(
    name="border_scene", what="An object across the left image border, partly out of the right view, "
    "and neighbours close enough to hide each other in one view (``\"border\"``).")
camera_scene.__doc__ = _DOC.format(
    name="camera_scene", what="Noisy cameras with different gain and offset (``\"cameras\"``).")


def object_layout(seed, n_objects: int = 2, *, family: str = "contrast", supersample: int = 1) -> Layout:
    """A random layout of two or three objects at distinct depths, both pairs rendered, with its truth.

    Parameters
    ----------
    seed : int or numpy.random.Generator
        Everything random is drawn from it: the same seed gives bit-identical images.
    n_objects : {2, 3}
    family : {"contrast", "repetitive", "border", "cameras"}
        See the module's docstring.
    supersample : int
        Rays per pixel side.

    Returns
    -------
    Layout
        ``scene`` is what the family function returns for `seed`, ``background``
        what it returns with ``empty=True``.

    Examples
    --------
    >>> lay = object_layout(7, 2, family="border")
    >>> lay.objects[0].disparity - lay.objects[1].disparity >= MIN_GAP_PX
    True
    >>> o = min(lay.objects, key=lambda o: o.box_xy[0])      # the one across the left border
    >>> x, y = int(o.box_xy[0]) + 1, int(o.centre_xy[1])
    >>> bool(lay.scene.occluded[y, x]), float(lay.scene.disparity[y, x])   # out of the right view
    (True, nan)
    >>> object_layout(7, 4)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'n_objects' parameter of object_layout must be an integer >= 2 and <= 3. Got 4 instead.
    """
    own = "object_layout"
    rng, family, n, s = _check(seed, family, n_objects, supersample, own)
    rig = Rig()
    design = _design(rng, family, n, rig)
    top = max(o.disparity for o in design.truth)
    shift = float(round((design.wall_disparity + top) / 2))
    return Layout(family, seed if isinstance(seed, (int, np.integer)) else None,
                  _render(design, rig, True, s), _render(design, rig, False, s), design.truth,
                  design.wall_disparity, shift)


def object_ids(scene: Scene) -> np.ndarray:
    """Which primitive each left pixel centre sees: an ``(H, W)`` index into ``scene.primitives``.

    -1 where no surface.  For the families, 0 is the wall and ``k`` is ``"object k"``.

    Examples
    --------
    >>> lay = object_layout(0, 2)
    >>> ids = object_ids(lay.scene)
    >>> o = lay.objects[0]
    >>> int(ids[int(o.centre_xy[1]), int(o.centre_xy[0])]) == o.index, int(ids[5, 5])
    (True, 0)
    """
    if not isinstance(scene, Scene):
        raise ParameterTypeError(message("scene", "object_ids", "a Scene", scene))
    rig = scene.rig
    gy, gx = np.mgrid[0:rig.height, 0:rig.width]
    o, d = rig.rays_left(np.stack([gx.ravel(), gy.ravel()], axis=1).astype(float))
    return cast(scene.primitives, o, d)[1].reshape(rig.height, rig.width)

