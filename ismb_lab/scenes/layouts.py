"""Families of depth-demo scenes: textured objects in front of a textured wall, with exact truth.

Each layout holds two or three boxes or upright cylinders at distinct depths before a wall: the
*scene* pair, the *background* pair (the wall alone, fresh camera noise) and the truth.  A family
(:class:`Family`) is a name, a description and a :class:`~ismb_lab.scenes.design.Look`; the library
registers four (:data:`FAMILIES`), where the depth demo is weak: ``"contrast"``, ``"repetitive"``,
``"border"`` and ``"cameras"``.

A new family's stream is ``SeedSequence(seed, spawn_key=(k,))``, ``k`` from the SHA-256 of its
name, so it moves no other family's draws; the four keep ``default_rng(seed)`` itself, so their
recorded layouts stay bit for bit.  On the default rig (``f B = 30`` px m) walls lie at 5 to 9 px
of disparity, objects at 10 to 26 px, :data:`MIN_GAP_PX` apart, and the candidate window's shift
is the middle of that range (:attr:`Layout.shift`).

>>> lay = object_layout(0, 3, family="contrast")
>>> [o.rank for o in lay.objects], lay.family, lay.roi
([1, 2, 3], 'contrast', (40, 40, 240, 160))
>>> bool(np.all(np.diff([o.disparity for o in lay.objects]) <= -MIN_GAP_PX))
True

:data:`UNSEEN` is a fifth family, defined but not registered:

>>> register_family(UNSEEN).name, object_layout(0, 3, family="unseen").family
('unseen', 'unseen')
>>> unregister_family("unseen")
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_choice, check_number, check_rng, message
from .design import HIGH, LAYOUT_ROI, LOW, MIN_GAP_PX, Design, Look, ObjectTruth, Placement, draw_objects
from ..cameras.camera import StereoCamera
from .primitives import cast
from .render import Scene, render

__all__ = ["FAMILIES", "LAYOUT_ROI", "MIN_GAP_PX", "UNSEEN", "Family", "Layout", "ObjectTruth", "border_scene",
           "camera_scene", "contrast_scene", "families", "get_family", "object_ids", "object_layout",
           "register_family", "repetitive_scene", "unregister_family"]

FAMILIES = ("contrast", "repetitive", "border", "cameras")
"""The four families the library registers, in order; their stream is the seed itself."""


def _name_key(name: str) -> int:
    """A 64-bit number from `name`, the same in every process (``hash`` is salted per process)."""
    return int.from_bytes(hashlib.sha256(name.encode("utf-8")).digest()[:8], "little")


@dataclass(frozen=True)
class Family:
    """A scene family: its name, a one-line description, and the hooks of
    :func:`~ismb_lab.scenes.design.draw_objects` it changes.

    Attributes
    ----------
    name : str
        Non-empty; the name :func:`get_family` looks up.
    description : str
        One line on what the family varies.
    look : Look, default ``Look()``
        The design hooks it replaces.

    Examples
    --------
    >>> from ismb_lab.scenes.design import Look
    >>> dim = Family("dim", "A darker right camera", Look(camera=lambda rng: {
    ...     "gain": float(rng.uniform(0.5, 0.6)), "offset": 0.0, "noise_std": 1.0}))
    >>> dim.name, dim.draw(dim.stream(0), 2, StereoCamera.pinhole()).camera["gain"] < 0.6
    ('dim', True)
    """

    name: str
    description: str
    look: Look = Look()

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.strip():
            raise ParameterTypeError(message("name", "Family", "a non-empty string", self.name))
        if not isinstance(self.description, str):
            raise ParameterTypeError(message("description", "Family", "a string", self.description))
        if not isinstance(self.look, Look):
            raise ParameterTypeError(message("look", "Family", "a Look", self.look))

    def stream(self, seed, owner: str = "Family.stream") -> np.random.Generator:
        """The family's random stream for `seed` (a Generator is returned as it is).

        Parameters
        ----------
        seed : int or numpy.random.Generator
            The layout's seed.
        owner : str, default "Family.stream"
            The caller's name, for error messages.

        Returns
        -------
        rng : numpy.random.Generator
            The built-in families' stream is ``default_rng(seed)``; others' are keyed by name.

        Examples
        --------
        >>> mine = Family("mine", "").stream(0).integers(1000, size=3)
        >>> bool(np.array_equal(mine, np.random.default_rng(0).integers(1000, size=3)))
        False
        >>> contrast = get_family("contrast").stream(0).integers(1000, size=3)
        >>> bool(np.array_equal(contrast, np.random.default_rng(0).integers(1000, size=3)))
        True
        """
        rng = check_rng(seed, "seed", owner)
        if isinstance(seed, np.random.Generator) or self.name in FAMILIES:
            return rng
        return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(_name_key(self.name),)))

    def draw(self, rng: np.random.Generator, n_objects: int, rig: StereoCamera) -> Design:
        """One layout's design, drawn from `rng` (see :func:`~ismb_lab.scenes.design.draw_objects`).

        Parameters
        ----------
        rng : numpy.random.Generator
            Random source (:meth:`stream`).
        n_objects : int
            2 or 3.
        rig : StereoCamera
            The cameras.

        Returns
        -------
        design : Design
            The wall, the objects, their truth and the camera settings.
        """
        return draw_objects(rng, n_objects, rig, self.look)


_FAMILIES: dict[str, Family] = {}


def register_family(family: Family) -> Family:
    """Add a family, of a new name, to the registry that :func:`object_layout` and the scripts read.

    Parameters
    ----------
    family : Family
        A family whose name is not registered yet.

    Returns
    -------
    family : Family
        `family` itself.

    Examples
    --------
    >>> register_family(Family("plain", "The common design, nothing changed")).name
    'plain'
    >>> families()[-1], object_layout(0, 2, family="plain").family
    ('plain', 'plain')
    >>> unregister_family("plain"); "plain" in families()
    False
    """
    own = "register_family"
    if not isinstance(family, Family):
        raise ParameterTypeError(message("family", own, "a Family", family))
    if family.name in _FAMILIES:
        raise ParameterError(message("family", own, "a family with a new name", f"name {family.name!r}"))
    _FAMILIES[family.name] = family
    return family


def unregister_family(name: str) -> None:
    """Remove a family added by :func:`register_family`."""
    check_choice(name, "name", "unregister_family", families())
    del _FAMILIES[name]


def families() -> tuple[str, ...]:
    """The registered families' names, in registration order (the order the scripts cycle through).

    >>> families()
    ('contrast', 'repetitive', 'border', 'cameras')
    """
    return tuple(_FAMILIES)


def get_family(name, owner: str = "get_family", parameter: str = "family") -> Family:
    """Look a registered family up by name.

    >>> get_family("border").description.split(",")[0]
    'One box across the left image border'
    >>> get_family("stripes")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'family' parameter of get_family must be one of 'contrast', 'repetitive', 'border', 'cameras'. Got 'stripes' instead.
    """
    return _FAMILIES[check_choice(name, parameter, owner, families())]


def _contrast_wall(rng, mode: str) -> tuple:
    return "posters", LOW if mode == "high-on-low" else HIGH


def _contrast_object(rng, mode: str) -> str:
    drawn = rng.choice(["low", "high"])     # even when the mode decides: the recorded layouts have this draw
    return {"low-on-high": "low", "high-on-low": "high"}.get(mode, drawn)


def _repetitive_wall(rng, mode: str) -> tuple:
    return rng.choice(["stripes", "tiles", "posters"]), HIGH


def _stripes_or_tiles(rng) -> str:
    return rng.choice(["stripes", "tiles"])


def _across_the_borders(rng, widths) -> Placement:
    rx, _, rw, _ = LAYOUT_ROI
    widths = np.array(widths, float)
    lo = float(rng.uniform(-8, 4))                     # a box across the image's left edge,
    widths[0] = rx - lo + rng.uniform(22, 36)          # 22-36 px inside the ROI
    right = bool(rng.random() < 0.5) and len(widths) > 1
    hi = rx + rw - 2
    if right:                                          # and one across the right edge
        hi = float(rng.uniform(300, 318))
        widths[-1] = hi - (rx + rw) + rng.uniform(22, 36)
    return Placement(lo, hi, (2.0, 6.0), widths, pin_left=True, pin_right=right)


def _unsteady_cameras(rng) -> dict:
    return {"gain": float(rng.uniform(0.75, 1.3)), "offset": float(rng.uniform(-20, 20)),
            "noise_std": float(rng.uniform(2.0, 4.0))}


for _family in (
        Family("contrast", "Objects of varied size, of low contrast before a busy wall or the reverse",
               Look(wall=_contrast_wall, contrast=_contrast_object)),
        Family("repetitive", "Striped and tiled objects, often before a striped or tiled wall",
               Look(wall=_repetitive_wall, texture=_stripes_or_tiles)),
        Family("border", "One box across the left image border, neighbours 2 to 6 px apart, "
               "in half the layouts one across the right border", Look(placement=_across_the_borders)),
        Family("cameras", "Camera noise of 2 to 4 grey levels, the right camera's gain and offset off",
               Look(camera=_unsteady_cameras))):
    register_family(_family)


# A family the depth code never saw.
def _any_wall(rng, mode: str) -> tuple:
    return rng.choice(["posters", "stripes", "tiles"]), (HIGH, LOW)[int(rng.integers(2))]


def _any_sizes(rng, n: int) -> tuple:
    return rng.uniform(18, 96, n), rng.uniform(24, 120, n)


def _anywhere(rng, widths) -> Placement:
    rx, _, rw, _ = LAYOUT_ROI
    return Placement(rx + 2, rx + rw - 2, (3.0, 30.0), widths)


def _any_shape(rng, box_only: bool) -> str:
    return "cylinder" if rng.random() < 0.5 and not box_only else "box"


def _any_contrast(rng, mode: str) -> str:
    return str(rng.choice(["low", "high"]))


def _any_texture(rng) -> str:
    return str(rng.choice(["posters", "stripes", "tiles"]))


def _any_cameras(rng) -> dict:
    return {"gain": float(rng.uniform(0.8, 1.25)), "offset": float(rng.uniform(-15, 15)),
            "noise_std": float(rng.uniform(0.5, 3.0))}


UNSEEN = Family("unseen", "Objects 18 to 96 px wide and 24 to 120 px tall, half of them cylinders, 3 to 30 px "
                "apart, any texture and contrast on objects and wall, cameras a little off",
                Look(wall=_any_wall, placement=_anywhere, contrast=_any_contrast, texture=_any_texture,
                     camera=_any_cameras, sizes=_any_sizes, shape=_any_shape))
"""A family of wider ranges than the four, for held-out tests of the depth demo; left out of
:func:`families` so that the scripts' recorded splits stay as they were."""


@dataclass(frozen=True, eq=False)
class Layout:
    """One random layout: the background and scene pairs (Scene), the objects' truth nearest
    first, the wall's disparity, the candidate-window shift and the ROI; `seed` is None when it
    was drawn from a Generator."""

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


def _check(seed, family, n_objects, supersample, owner):
    check_rng(seed, "seed", owner)
    fam = get_family(family, owner)
    n = check_number(n_objects, "n_objects", owner, low=2, high=3, integer=True)
    s = check_number(supersample, "supersample", owner, low=1, high=8, integer=True)
    return fam.stream(seed, owner), fam, n, s


def _render(design: Design, rig: StereoCamera, empty: bool, supersample: int) -> Scene:
    prims = [design.wall] + ([] if empty else list(design.objects))
    return render(prims, rig, seed=design.noise[0 if empty else 1], supersample=supersample,
                  **design.camera)


def _family_scene(family: str, owner: str, seed, n_objects, empty, supersample) -> Scene:
    rng, fam, n, s = _check(seed, family, n_objects, supersample, owner)
    if not isinstance(empty, bool):
        raise ParameterTypeError(message("empty", owner, "True or False", empty))
    rig = StereoCamera.pinhole()
    return _render(fam.draw(rng, n, rig), rig, empty, s)


_DOC = """{what}

    With `empty`, the background: the same wall and cameras without the objects, fresh noise.
    ``primitives`` are the wall, then the objects left to right; :func:`object_layout` has the truth.

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

    `seed` (int or Generator) draws everything from the family's stream (:meth:`Family.stream`);
    ``scene`` is what the family function returns for it, ``background`` with ``empty=True``.

    Parameters
    ----------
    seed : int or numpy.random.Generator
        Draws the layout, textures and noise.
    n_objects : int, default 2
        2 or 3.
    family : str, default "contrast"
        A family's name (:func:`families`, or ``"unseen"``).
    supersample : int, default 1
        Rays per pixel side, 1 to 8.

    Returns
    -------
    layout : Layout
        Both rendered pairs, the objects' truth, the window shift and the ROI.

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
    rng, fam, n, s = _check(seed, family, n_objects, supersample, own)
    rig = StereoCamera.pinhole()
    design = fam.draw(rng, n, rig)
    top = max(o.disparity for o in design.truth)
    shift = float(round((design.wall_disparity + top) / 2))
    return Layout(fam.name, seed if isinstance(seed, (int, np.integer)) else None,
                  _render(design, rig, True, s), _render(design, rig, False, s), design.truth,
                  design.wall_disparity, shift)


def object_ids(scene: Scene) -> np.ndarray:
    """Which primitive each left pixel centre sees: an ``(H, W)`` index into ``scene.primitives``
    (-1 where none; for the families 0 is the wall and ``k`` is ``"object k"``).

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

