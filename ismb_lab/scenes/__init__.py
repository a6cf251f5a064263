"""Synthetic stereo scenes with exact ground truth, by ray casting.

A tiny deterministic renderer for testing the matcher: a stereo :class:`~ismb_lab.cameras.camera.StereoCamera`, a
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
:mod:`ismb_lab.images.coords`: ``(x, y)`` = (column, row), pixel centres at integers,
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
The package follows the data: :mod:`~ismb_lab.scenes.geometry` (rays; the rig is :class:`~ismb_lab.cameras.camera.StereoCamera`),
:mod:`~ismb_lab.scenes.textures`, :mod:`~ismb_lab.scenes.primitives`,
:mod:`~ismb_lab.scenes.render` (the two views and their ground truth) and
:mod:`~ismb_lab.scenes.library` (the named scenes) and
:mod:`~ismb_lab.scenes.layouts` (the registered families of random layouts for the depth demo,
with their truth, drawn by :mod:`~ismb_lab.scenes.design`).
"""

from .design import Look, Placement
from .layouts import (
                       FAMILIES,
                       LAYOUT_ROI,
                       MIN_GAP_PX,
                       UNSEEN,
                       Family,
                       Layout,
                       ObjectTruth,
                       border_scene,
                       camera_scene,
                       contrast_scene,
                       families,
                       get_family,
                       object_ids,
                       object_layout,
                       register_family,
                       repetitive_scene,
                       unregister_family,
)
from .geometry import ROI
from .library import (
                      CAR_DEPTH,
                      REALISTIC_COUNT,
                      lab_scene,
                      realistic_scene,
                      synthetic_scene,
                      toy_car,
                      toy_car_layout,
                      toy_car_scene,
)
from .primitives import Box, Cylinder, Group, Plane, Primitive, cast
from .render import Scene, render, true_matches
from .textures import Texture, random_texture

__all__ = [
    "Texture", "random_texture", "Primitive", "Plane", "Box", "Group", "cast",
    "Scene", "render", "synthetic_scene", "true_matches", "ROI",
    "toy_car", "toy_car_layout", "lab_scene", "toy_car_scene", "realistic_scene",
    "REALISTIC_COUNT", "CAR_DEPTH", "Cylinder",
    "FAMILIES", "LAYOUT_ROI", "MIN_GAP_PX", "UNSEEN", "Layout", "ObjectTruth", "object_layout", "object_ids",
    "contrast_scene", "repetitive_scene", "border_scene", "camera_scene",
    "Family", "Look", "Placement", "families", "get_family", "register_family", "unregister_family",
]
