"""Rays and small vector helpers of the renderer; its rig is :class:`ismb_lab.cameras.camera.StereoCamera`.

The geometry of the whole package is in its docstring (:mod:`ismb_lab.scenes`).
"""

from __future__ import annotations

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_points, message

__all__ = ["EPS", "ROI"]

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


def _rays(origins, dirs, owner: str) -> tuple[np.ndarray, np.ndarray]:
    origins = check_points(origins, "origins", owner, dims=3)
    dirs = check_points(dirs, "dirs", owner, dims=3)
    if origins.shape != dirs.shape:
        raise ParameterError(message("dirs", owner, f"an array of the shape of origins {origins.shape}",
                                     f"an array of shape {dirs.shape}"))
    return origins, dirs
