"""Synthetic stereo scenes with exact ground truth, by ray casting.

The left camera sits at the origin looking along ``+z``, ``x`` right and ``y`` *down*; the right
one at ``(baseline_m, 0, 0)``, possibly rolled and shifted down.  Points follow
:mod:`ismb_lab.images.coords`.  Anything with ``intersect``, ``normals`` and ``albedo`` can be
rendered (:class:`Primitive`); shading is Lambertian, identical in both views.  The modules:
``geometry``, ``textures``, ``primitives``, ``render``, ``library`` (the named scenes),
``design`` and ``layouts`` (the families of random layouts of the depth demo).
"""

from .design import Look, Placement
from .geometry import ROI
from .layouts import (FAMILIES, LAYOUT_ROI, MIN_GAP_PX, UNSEEN, Family, Layout, ObjectTruth, border_scene,
                      camera_scene, contrast_scene, families, get_family, object_ids, object_layout,
                      register_family, repetitive_scene, unregister_family)
from .library import (CAR_DEPTH, REALISTIC_COUNT, lab_scene, realistic_scene, synthetic_scene, toy_car,
                      toy_car_layout, toy_car_scene)
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
