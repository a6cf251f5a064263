"""The project's own stereo pairs in ``images/``, rendered from :mod:`ismb_lab.scenes`.

Each pair folder holds ``left.png`` and ``right.png`` (8-bit grey), ``disparity.png`` (16-bit,
disparity times 256, 0 = unknown: the KITTI convention) and ``scene.json`` (the rig and its making).
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from .._core.files import atomic_write_bytes, atomic_write_text
from ..cameras.camera import BASELINE_M, FOCAL_PX
from ..images.io import grey_uint8, image_sha256
from . import REALISTIC_COUNT, Scene, lab_scene, realistic_scene, synthetic_scene, toy_car_scene, true_matches
from ..labels.targets import save_targets, targets_from_matches

__all__ = ["ANSWER_KEY", "DISPARITY_SCALE", "SNAP_PX", "answer_key", "decode_disparity",
           "encode_disparity", "gallery_files", "render_gallery", "write_manifest", "write_pair", "write_scene"]

DISPARITY_SCALE = 256.0


def _png(image: np.ndarray) -> bytes:
    ok, data = cv2.imencode(".png", image, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if not ok:  # pragma: no cover - OpenCV only fails here on an empty image
        raise RuntimeError("PNG encoding failed")
    return data.tobytes()


def encode_disparity(disparity: np.ndarray) -> np.ndarray:
    """Disparity map to the 16-bit KITTI encoding (``round(256 d)``, 0 = unknown).

    >>> encode_disparity(np.array([[16.5, np.nan]]))
    array([[4224,    0]], dtype=uint16)
    """
    valid = np.isfinite(disparity) & (disparity > 0)
    out = np.zeros(disparity.shape, dtype=np.uint16)
    out[valid] = np.rint(disparity[valid] * DISPARITY_SCALE).astype(np.uint16)
    return out


def decode_disparity(encoded: np.ndarray) -> np.ndarray:
    """Inverse of :func:`encode_disparity`; unknown pixels become NaN.

    Parameters
    ----------
    encoded : (H, W) uint16 ndarray
        The encoded map.

    Returns
    -------
    disparity : (H, W) float ndarray
        Disparity, px; NaN where unknown.

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
        "left.png": _png(grey_uint8(scene.left)),
        "right.png": _png(grey_uint8(scene.right)),
        "disparity.png": _png(encode_disparity(scene.disparity)),
    }
    written = [atomic_write_bytes(folder / name, data) for name, data in files.items()]
    written.append(atomic_write_text(folder / "scene.json", json.dumps(info, indent=2, sort_keys=True) + "\n"))
    return written


ANSWER_KEY = "answer_key.json"
SNAP_PX = 1.5


def answer_key(scene: Scene, left_path, right_path):
    """Target pairs (a TargetSet) of a rendered pair from its ground truth, on the default
    matcher's corners: a left corner's partner is the right corner within :data:`SNAP_PX` of its
    exact correspondence; of two left corners sharing one, the nearer keeps it.

    Parameters
    ----------
    scene : Scene
        The rendered scene.
    left_path, right_path : str or Path
        Its written images.

    Returns
    -------
    targets : TargetSet
        The answer key, with the images' hashes.
    """
    from ..matching.pipeline import prepare

    prepared = prepare(left_path, right_path)
    left_xy, right_xy = prepared.problem.left_xy, prepared.problem.right_xy
    partner = true_matches(scene, left_xy, right_xy, tol=SNAP_PX)
    truth = scene.correspond(left_xy)
    keep = {}
    for i in np.flatnonzero(partner >= 0):
        k = int(partner[i])
        dist = float(np.hypot(*(truth[i] - right_xy[k])))
        if k not in keep or dist < keep[k][1]:
            keep[k] = (int(i), dist)
    pairs = sorted((i, k) for k, (i, _) in keep.items())
    return targets_from_matches(
        np.array(pairs, dtype=np.intp).reshape(-1, 2), left_xy, right_xy,
        left_sha256=image_sha256(left_path), right_sha256=image_sha256(right_path),
        kind="answer key generated from ground truth",
        how=(f"corners of ismb_lab.matching.prepare with the default MatchConfig; a left corner's "
             f"target is the right corner within {SNAP_PX} px of its exact correspondence "
             f"(ismb_lab.scenes.true_matches), one left corner per right corner"),
        left_corners=len(left_xy), right_corners=len(right_xy))


def write_pair(scene: Scene, folder, **about) -> list[Path]:
    """:func:`write_scene` plus the pair's ``answer_key.json``; returns the files written."""
    folder = Path(folder)
    written = write_scene(scene, folder, **about)
    written.append(save_targets(folder / ANSWER_KEY, answer_key(scene, folder / "left.png",
                                                              folder / "right.png")))
    return written


def write_manifest(folder, pairs, about: str) -> Path:
    """An ``ismb-lab evaluate`` manifest of pair folders ``pairs`` (relative to `folder`)."""
    entries = [{"name": name, "left": f"{rel}left.png", "right": f"{rel}right.png",
                "targets": f"{rel}{ANSWER_KEY}"} for name, rel in pairs]
    return atomic_write_text(Path(folder) / "manifest.json",
                             json.dumps({"about": about, "pairs": entries}, indent=2) + "\n")


_READMES = {
    "lab": f"""# lab/: the background of the depth demo (thesis Fig. 5.11)

`ismb_lab.scenes.lab_scene(seed=0)`, written by `ismb-lab render`: a wall with posters
at 1.8 m (the deepest background), a table 15 cm below the cameras and one cardboard box
just right of the middle of the view, its front 1.3 to 1.45 m away. The right camera has gain 0.92
and offset +6; both images have camera noise (sigma 1 grey level).

* `left.png`, `right.png`: 240x320 8-bit grey; `disparity.png`: exact disparity x256
  (16-bit, 0 = unknown); `scene.json`: the rig (f = {FOCAL_PX:g} px, B = {BASELINE_M:.2f} m).
* `answer_key.json`: ground-truth target pairs on the default matcher's corners.
* `manifest.json`: this pair for `ismb-lab evaluate`.
""",
    "toy_cars": """# toy_cars/: two toy cars in front of the box (thesis Fig. 5.13)

`ismb_lab.scenes.toy_car_scene(seed=0)`, written by `ismb-lab render`: the background of
`../lab/` (the same wall, table and box) plus two toy cars on the table, the left one
nearer. The cars' depths are in `scene.json`. The camera noise is drawn afresh, as in a
second photograph.

    ismb-lab depth images/lab/left.png images/lab/right.png \
                   images/toy_cars/left.png images/toy_cars/right.png

Files as in `../lab/`; `answer_key.json` holds ground-truth target pairs and
`manifest.json` lists this pair for `ismb-lab evaluate`.
""",
    "realistic": f"""# realistic/: {REALISTIC_COUNT} varied indoor pairs (like the thesis' Fig. 5.10)

`NN/` is `ismb_lab.scenes.realistic_scene(NN)`, written by `ismb-lab render`: one or two
boxes in front of a wall with posters, up to two toy cars, other light and another right
camera each time. Two pairs in three have the right image shifted down by 2.5 to 5 px
(the thesis' webcams were off by 3 to 5 px) and every fourth one also has the right
camera rolled by up to 1 degree: see each `scene.json`.

Every folder has `left.png`, `right.png`, `disparity.png` (exact, x256, 16-bit),
`scene.json` and `answer_key.json` (ground-truth target pairs on the corners the default
matcher finds; occluded corners and occlusion junctions get none).

    ismb-lab evaluate images/realistic/manifest.json
""",
}


def _car_info(scene: Scene) -> list:
    return [{"name": p.name, "x_centre_m": round(float((p.lo[0] + p.hi[0]) / 2), 6),
             "z_front_m": round(float(p.parts[0].lo[2]), 6)}
            for p in scene.primitives if hasattr(p, "parts")]


PAIR_FILES = ("left.png", "right.png", "disparity.png", "scene.json", ANSWER_KEY)


def gallery_files(out="images") -> list[Path]:
    """Every file :func:`render_gallery` writes into `out`, known before anything is rendered.

    >>> [p.as_posix() for p in gallery_files("images")][:2]
    ['images/synthetic/left.png', 'images/synthetic/right.png']
    """
    out = Path(out)
    pairs = ["synthetic", "lab", "toy_cars"] + [f"realistic/{n:02d}" for n in range(1, REALISTIC_COUNT + 1)]
    files = [out / pair / name for pair in pairs for name in PAIR_FILES]
    files += [out / name / "manifest.json" for name in ("lab", "toy_cars", "realistic")]
    return files + [out / name / "README.md" for name in _READMES]


def render_gallery(out="images") -> list[Path]:
    """Render every committed pair into `out`; returns the files written."""
    out = Path(out)
    written = write_pair(synthetic_scene(seed=0), out / "synthetic",
                         made_by="ismb_lab.scenes.synthetic_scene(seed=0)")
    lab = lab_scene(seed=0)
    box = lab.primitives[2]
    written += write_pair(lab, out / "lab", made_by="ismb_lab.scenes.lab_scene(seed=0)",
                          box_front_m=round(float(box.lo[2]), 6))
    written.append(write_manifest(out / "lab", [("lab", "")], "The depth demo's background pair."))
    cars = toy_car_scene(seed=0)
    written += write_pair(cars, out / "toy_cars", made_by="ismb_lab.scenes.toy_car_scene(seed=0)",
                          box_front_m=round(float(cars.primitives[2].lo[2]), 6), cars=_car_info(cars))
    written.append(write_manifest(out / "toy_cars", [("toy cars", "")],
                                  "The depth demo's scene pair: two toy cars in front of the box."))
    names = [f"{n:02d}" for n in range(1, REALISTIC_COUNT + 1)]
    for n, name in enumerate(names, 1):
        scene = realistic_scene(n)
        written += write_pair(scene, out / "realistic" / name,
                              made_by=f"ismb_lab.scenes.realistic_scene({n})", cars=_car_info(scene))
    written.append(write_manifest(out / "realistic", [(name, f"{name}/") for name in names],
                                  f"{REALISTIC_COUNT} rendered indoor pairs, some with a vertical "
                                  "offset or roll; targets from the ground truth."))
    for name, text in _READMES.items():
        written.append(atomic_write_text(out / name / "README.md", text))
    return written
