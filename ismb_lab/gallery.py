"""The project's own stereo pairs in ``images/``, rendered from :mod:`ismb_lab.scenes`.

``ismb-lab render`` writes them; a test renders them again and compares bytes, so the
committed files are exactly what this code produces.

Each pair folder holds ``left.png`` and ``right.png`` (8-bit grey), ``disparity.png``
(16-bit, horizontal disparity of the left view times 256, 0 where the left pixel is
occluded or leaves the right view: the KITTI convention) and ``scene.json`` (the rig and
how the pair was made).
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from ._files import atomic_write_bytes, atomic_write_text
from .scenes import Scene, synthetic_scene

DISPARITY_SCALE = 256.0


def _png(image: np.ndarray) -> bytes:
    ok, data = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if not ok:  # pragma: no cover - OpenCV only fails here on an empty image
        raise RuntimeError("PNG encoding failed")
    return data.tobytes()


def encode_disparity(disparity: np.ndarray) -> np.ndarray:
    """Disparity map to the 16-bit KITTI encoding (``round(256 d)``, 0 = unknown).

    Examples
    --------
    >>> encode_disparity(np.array([[16.5, np.nan]]))
    array([[4224,    0]], dtype=uint16)
    """
    valid = np.isfinite(disparity) & (disparity > 0)
    out = np.zeros(disparity.shape, dtype=np.uint16)
    out[valid] = np.rint(disparity[valid] * DISPARITY_SCALE).astype(np.uint16)
    return out


def decode_disparity(encoded: np.ndarray) -> np.ndarray:
    """Inverse of :func:`encode_disparity`; unknown pixels become NaN.

    Examples
    --------
    >>> decode_disparity(np.array([[4224, 0]], dtype=np.uint16))
    array([[16.5,  nan]])
    """
    out = encoded.astype(float) / DISPARITY_SCALE
    out[encoded == 0] = np.nan
    return out


def write_scene(scene: Scene, folder, **about) -> list[Path]:
    """Write a rendered scene as a pair folder; returns the files written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rig = scene.rig
    info = {"rig": {"width": rig.width, "height": rig.height, "focal_px": rig.focal_px,
                    "baseline_m": rig.baseline_m, "vertical_offset_px": rig.vertical_offset_px,
                    "roll_deg": rig.roll_deg},
            "disparity_encoding": "uint16 PNG: horizontal disparity of the left view * 256; 0 = unknown",
            **about}
    files = {
        "left.png": _png(np.clip(np.rint(scene.left), 0, 255).astype(np.uint8)),
        "right.png": _png(np.clip(np.rint(scene.right), 0, 255).astype(np.uint8)),
        "disparity.png": _png(encode_disparity(scene.disparity)),
    }
    written = [atomic_write_bytes(folder / name, data) for name, data in files.items()]
    written.append(atomic_write_text(folder / "scene.json", json.dumps(info, indent=2, sort_keys=True) + "\n"))
    return written


def render_gallery(out="images") -> list[Path]:
    """Render every committed pair into `out`; returns the files written."""
    out = Path(out)
    return write_scene(synthetic_scene(seed=0), out / "synthetic",
                       made_by="ismb_lab.scenes.synthetic_scene(seed=0)")
