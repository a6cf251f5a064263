"""Render both views of a list of primitives, with exact ground truth (:class:`Scene`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, check_points, check_rng, message
from ..cameras.camera import StereoCamera
from .geometry import _vector
from .primitives import _check_primitives, cast

__all__ = ["render", "Scene", "true_matches"]


def _correspond(primitives, rig: StereoCamera, left_xy: np.ndarray):
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

    `left` and `right` are grey float images in ``[0, 255]``; at each left pixel centre, `depth` is
    the ``z`` (m) of the surface seen (``inf`` where none), `disparity` the true ``x_left - x_right``
    (NaN where occluded, out of the right view or surfaceless) and `occluded` whether the right
    camera misses that point.  The right image is ``gain * radiance + offset + noise``, the left
    ``radiance + noise``.

    Attributes
    ----------
    left, right : (H, W) float ndarray
        The grey images, read-only.
    depth : (H, W) float ndarray
        ``z`` (m) of the surface seen at each left pixel, ``inf`` where none.
    disparity : (H, W) float ndarray
        True ``x_left - x_right``, px; NaN where unknown.
    occluded : (H, W) bool ndarray
        Whether the right camera misses the point.
    rig : StereoCamera
        The cameras.
    primitives : tuple of Primitive
        What was rendered.
    gain, offset, noise_std : float
        The right camera's response and the noise, grey levels.

    Examples
    --------
    >>> from ismb_lab.scenes import synthetic_scene
    >>> scene = synthetic_scene(0)
    >>> scene.left.shape, scene.left.dtype, bool(np.isnan(scene.disparity).any())
    ((240, 320), dtype('float64'), True)
    """

    left: np.ndarray
    right: np.ndarray
    depth: np.ndarray
    disparity: np.ndarray
    occluded: np.ndarray
    rig: StereoCamera
    primitives: tuple
    gain: float = 1.0
    offset: float = 0.0
    noise_std: float = 0.0

    def __post_init__(self):
        own = "Scene"
        if not isinstance(self.rig, StereoCamera):
            raise ParameterTypeError(message("rig", own, "a StereoCamera", self.rig))
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

        >>> from ismb_lab.scenes import synthetic_scene
        >>> synthetic_scene(0).surface_points([[20.0, 20.0]]).round(6)   # the back wall
        array([[-0.837, -0.597,  1.8  ]])
        """
        xy = check_points(left_xy, "left_xy", "Scene.surface_points")
        return _correspond(self.primitives, self.rig, xy)[0]

    def correspond(self, left_xy) -> np.ndarray:
        """True right-image positions of left-image points, by exact ray casting both ways; NaN
        rows for occluded, out-of-view or surface-less points.

        >>> from ismb_lab.scenes import synthetic_scene
        >>> scene = synthetic_scene(0)
        >>> scene.correspond([[20.0, 20.0], [0.0, 100.0]]).round(3)  # wall; out of the right view
        array([[  3.333,  20.   ],
               [    nan,    nan]])
        """
        xy = check_points(left_xy, "left_xy", "Scene.correspond")
        return _correspond(self.primitives, self.rig, xy)[2]


def _sample_grid(rig: StereoCamera, s: int) -> np.ndarray:
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


def render(primitives, rig: StereoCamera = StereoCamera.pinhole(), *, seed, noise_std: float = 1.0, gain: float = 1.0,
           offset: float = 0.0, supersample: int = 2, light=(0.3, -0.8, -1.0),
           ambient: float = 0.35, background: float = 0.0, quantise: bool = True) -> Scene:
    """Ray-cast both views of a scene and compute its ground truth at the left pixel centres.

    `seed` (required) draws the Gaussian camera noise of `noise_std` grey levels; the right camera
    responds ``gain * radiance + offset``; `supersample` rays per pixel side are averaged; radiance
    is ``255 * albedo * (ambient + (1 - ambient) * max(0, n . light))`` with `light` the direction
    *towards* the light, and `background` for rays that hit nothing.  `quantise` rounds like 8-bit
    cameras; images are clipped to ``[0, 255]`` either way.

    Parameters
    ----------
    primitives : sequence of Primitive
        The objects to render.
    rig : StereoCamera, default ``StereoCamera.pinhole()``
        The cameras.
    seed : int or numpy.random.Generator
        Draws the camera noise (required).
    noise_std : float, default 1.0
        Standard deviation of the noise, grey levels.
    gain : float, default 1.0
        The right camera's gain, > 0.
    offset : float, default 0.0
        The right camera's offset, grey levels.
    supersample : int, default 2
        Rays per pixel side, 1 to 8.
    light : (3,) float tuple, default (0.3, -0.8, -1.0)
        Direction towards the light.
    ambient : float, default 0.35
        Share of light that does not depend on the normal, 0 to 1.
    background : float, default 0.0
        Radiance of rays that hit nothing, 0 to 255.
    quantise : bool, default True
        Round the images to whole grey levels.

    Returns
    -------
    scene : Scene
        Both images with their exact ground truth.

    Examples
    --------
    >>> rig = StereoCamera.pinhole(width=32, height=24, focal_px=30)
    >>> from ismb_lab.scenes import Plane, Texture
    >>> wall = Plane((0, 0, 1.8), (1, 0, 0), (0, 1, 0), 10, 10, Texture(base=0.6))
    >>> scene = render([wall], rig, seed=0, noise_std=0)
    >>> round(float(scene.disparity[12, 20]), 12), bool(scene.occluded[12, 0])
    (1.666666666667, True)
    """
    own = "render"
    primitives = _check_primitives(primitives, own)
    if not isinstance(rig, StereoCamera):
        raise ParameterTypeError(message("rig", own, "a StereoCamera", rig))
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


def true_matches(scene: Scene, left_xy, right_xy, tol: float = 1.5) -> np.ndarray:
    """Index of the true partner of each left point among right points: the nearest within `tol`
    px of its exact correspondence (:meth:`Scene.correspond`), or -1.  Two may share a partner.

    >>> from ismb_lab.scenes import synthetic_scene
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
