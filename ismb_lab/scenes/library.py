"""The named scenes: the synthetic test scene, the lab and toy cars of §5.2.3, the realistic pairs."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .._core.validation import ParameterTypeError, check_number, check_rng, message
from ..cameras.camera import StereoCamera
from .geometry import ROI
from .primitives import _FACE_UV, Box, Group, Plane
from .render import Scene, render
from .textures import Texture, random_texture

__all__ = ["CAR_DEPTH", "REALISTIC_COUNT", "TABLE_Y", "WALL_Z", "lab_scene", "realistic_scene",
           "synthetic_scene", "toy_car", "toy_car_layout", "toy_car_scene"]

WALL_Z = 1.8
TABLE_Y = 0.15


def _wall_shadow(box: Box, rig: StereoCamera, margin: float) -> np.ndarray:
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


def _scene_primitives(rng: np.random.Generator, rig: StereoCamera) -> list:
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


def _room(rng: np.random.Generator, rig: StereoCamera, wall_base: float, boxes, poster_bottom: float) -> list:
    """The wall at 1.8 m with posters down to ``y = poster_bottom`` and the table: ``[wall, table]``."""
    # No poster that a box's silhouette cuts in either view: no occlusion junction moves between them.
    wall_tex = random_texture(rng, (-1.2, -0.9, 1.2, poster_bottom), cell=0.17, fill=0.5,
                              base=wall_base, contrast=(0.32, 0.4))
    wall_tex = _clear(wall_tex, [_wall_shadow(box, rig, margin=0.04) for box in boxes])
    wall = Plane((0, 0, WALL_Z), (1, 0, 0), (0, 1, 0), 20, 20, wall_tex)
    # The table reaches the wall and is lit a little less than it, so that the crease makes no
    # strong corners; its sheets of paper lie near the cameras only (below the ROI).
    near, depth = 0.15, WALL_Z - 0.15
    table_tex = random_texture(rng, (-0.6, -depth / 2, 0.6, -depth / 2 + 0.5), cell=0.3, fill=0.5,
                               base=wall_base * rng.uniform(0.95, 1.0), contrast=(0.3, 0.4))
    table = Plane((0, TABLE_Y, near + depth / 2), (1, 0, 0), (0, 0, 1), 3, depth / 2, table_tex)
    return [wall, table]


def synthetic_scene(seed=0, *, vertical_offset_px: float = 0.0, roll_deg: float = 0.0,
                    noise_std: float = 1.0) -> Scene:
    """A ready-made indoor test scene: posters on a wall, a table, one or two boxes.

    A wall at 1.8 m, a table top 15 cm below the cameras, and one or two labelled boxes 1.0 to
    1.4 m away in the centre-quarter ROI; the right camera has gain 0.9 and offset +8.  No poster
    is cut by a box's silhouette, so nearly every corner is a real 3-D point.

    `seed` draws the layout and textures, then the noise; `vertical_offset_px` and `roll_deg` go
    to :meth:`~ismb_lab.cameras.camera.StereoCamera.pinhole` and do not move the layout.

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
    rig = _demo_rig(own, vertical_offset_px, roll_deg)
    noise_std = check_number(noise_std, "noise_std", own, low=0)
    return render(_scene_primitives(rng, rig), rig, seed=rng, noise_std=noise_std, gain=0.9, offset=8.0)


CAR_DEPTH = 0.06
"""Depth (along ``z``) of a toy car's body, metres."""


def toy_car(rng, x_centre: float, z_front: float, *, length: float = 0.13, name: str = "toy car") -> Group:
    """A toy car standing on the table, its side towards the cameras: a :class:`Group` of
    ``(body, cabin, wheel, wheel, wheel, wheel)``, its side striped in a paint drawn from `rng`.

    `x_centre` is the car's middle, `z_front` the depth of its side (> 0) and `length` its body's
    (0.05 to 0.5), metres.

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


def _lab_primitives(rng: np.random.Generator, rig: StereoCamera) -> list:
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
    # The posters end 9 cm above the table: the toy cars never cut a poster.
    return _room(rng, rig, wall_base, [box], poster_bottom=0.06) + [box]


def _demo_rig(owner: str, vertical_offset_px, roll_deg) -> StereoCamera:
    return StereoCamera.pinhole(vertical_offset_px=check_number(vertical_offset_px, "vertical_offset_px", owner),
                                roll_deg=check_number(roll_deg, "roll_deg", owner, low=-180, high=180))


def lab_scene(seed=0, *, noise_std: float = 1.0, vertical_offset_px: float = 0.0,
              roll_deg: float = 0.0, supersample: int = 2) -> Scene:
    """The background of the depth demo (thesis Fig. 5.11): a box in front of a wall.

    A wall with posters at 1.8 m, stopping 9 cm above the table so that the cars of
    :func:`toy_car_scene` stand before plain wall, and one labelled box 1.3 to 1.45 m away,
    36 to 42 px wide, just right of the middle; the right camera has gain 0.92 and offset +6.
    `supersample` is rays per pixel side (1 renders 4 times faster).  The layout does not
    depend on the camera's roll or offset.

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


def toy_car_layout(cars=0, rig: StereoCamera = StereoCamera.pinhole()) -> tuple[tuple[float, float, float], ...]:
    """Positions of the two toy cars of :func:`toy_car_scene`: ``((x, z, length), ...)``, left first.

    The left car stands 0.88 to 1.0 m away, the right one 10 cm or more farther, up to 1.2 m,
    both in front of :func:`lab_scene`'s box, one on each side of it.

    >>> (xl, zl, ll), (xr, zr, lr) = toy_car_layout(0)
    >>> bool(0.88 <= zl <= 1.0 and zl + 0.1 <= zr <= 1.2), bool(xl < 0 < xr)
    (True, True)
    """
    own = "toy_car_layout"
    rng = check_rng(cars, "cars", own)
    if not isinstance(rig, StereoCamera):
        raise ParameterTypeError(message("rig", own, "a StereoCamera", rig))
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

    The background is exactly ``lab_scene(seed)``'s; `cars` (default `seed`) draws the cars'
    places and paint (:func:`toy_car_layout`), then fresh camera noise.  The cars are the last two
    primitives, :class:`Group` objects named ``"left car"`` and ``"right car"``.

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
    """Varied indoor pairs like the thesis' Fig. 5.10, some not rectified; `index` >= 1.

    Boxes as in :func:`synthetic_scene`, up to two toy cars in front that may hide part of a box,
    another light and right camera.  Two indices in three shift the right image down by 2.5 to
    5 px, and every fourth one also rolls the right camera by up to 1 degree.

    >>> scene = realistic_scene(2)
    >>> scene.rig.vertical_offset_px > 0, realistic_scene(3).rig.vertical_offset_px
    (True, 0.0)
    """
    own = "realistic_scene"
    index = check_number(index, "index", own, low=1, integer=True)
    rng = np.random.default_rng([index, 20090701])
    offset_px = round(float(rng.uniform(2.5, 5.0)) * 2) / 2 if index % 3 else 0.0
    roll = round(float(rng.uniform(-1.0, 1.0)), 2) if index % 4 == 0 else 0.0
    rig = StereoCamera.pinhole(vertical_offset_px=offset_px, roll_deg=roll)
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
