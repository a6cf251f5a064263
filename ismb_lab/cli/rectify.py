"""``ismb-lab rectify``: make a hand-held (or a calibrated rig's) stereo pair rectified."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from .._core.files import atomic_write_bytes, atomic_write_text
from ._common import given
from ._guard import Files, UsageError, add_force_option, json_text

__all__ = ["add_parser", "run"]

FILES = ("left.png", "right.png", "rectify.json")


def add_parser(sub) -> None:
    """Add the ``rectify`` command: rectify a hand-held pair, or a calibrated rig's."""
    from ..images.rectify import WORKING_SIDE

    r = sub.add_parser("rectify", help="rectify a stereo pair (hand-held photos, or a calibrated rig's)",
                       description="Find robust matches (SIFT, ratio test, mutual), estimate the "
                       "fundamental matrix with RANSAC and rectify without calibration; with --rig, "
                       "rectify exactly with a rig from 'ismb-lab calibrate'. Writes DIR/left.png, "
                       "DIR/right.png and DIR/rectify.json (the row differences of the inliers after "
                       f"rectification, the disparity range, the size). Photos are scaled to at most "
                       f"{WORKING_SIDE} px on their longer side; EXIF orientation is honoured.")
    r.add_argument("left", type=Path, help="left photo")
    r.add_argument("right", type=Path, help="right photo")
    r.add_argument("--out", dest="out_dir", type=Path, required=True, metavar="DIR",
                   help="folder for left.png, right.png and rectify.json (made if missing)")
    r.add_argument("--rig", type=Path, default=None, metavar="RIG.json",
                   help="rectify with this calibrated rig instead of from matches (a pair the rig does not fit, "
                   "swapped, turned or already rectified, is refused)")
    add_force_option(r)
    r.set_defaults(run=run, declare_files=files)


def files(args) -> Files:
    """The photos and the rig read; the files written into --out, if it exists (a new one is made
    after the work, so a refused pair leaves nothing behind)."""
    folder = Path(args.out_dir)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"--out {str(folder)!r} is not a folder")
    if not folder.is_dir():
        parent = folder.absolute().parent
        if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
            raise UsageError(f"--out {str(folder)!r}: cannot make a folder in {str(parent)!r}")
    outputs = tuple((f"--out {name}", folder / name) for name in FILES) if folder.is_dir() else ()
    return Files(inputs=(("left", args.left), ("right", args.right)) + given(("--rig", args.rig)),
                 outputs=outputs)


def run(args) -> int:
    """Rectify the pair of `args` and write DIR/left.png and DIR/right.png; returns the exit code."""
    from ..images.io import png_bytes
    from ..images.rectify import rectify_pair

    folder = Path(args.out_dir)
    targets = [folder / name for name in FILES]
    if args.rig is not None:
        from ..cameras.camera import load_camera
        from ..matching.metric import rectify_for_camera

        result = rectify_for_camera(args.left, args.right, load_camera(args.rig), "ismb-lab rectify --rig")
    else:
        result = rectify_pair(args.left, args.right)
    folder.mkdir(parents=True, exist_ok=True)
    # the images first and the record last: a rectify.json always describes images beside it
    atomic_write_bytes(targets[0], png_bytes(result.left))
    atomic_write_bytes(targets[1], png_bytes(result.right))
    atomic_write_text(targets[2], json_text(result.to_dict()))
    lo, hi = result.disparity_range_px
    for warning in result.warnings:
        print(warning, file=sys.stderr)
    print(f"{result.method}: {result.inliers} {result.measured_on}, |dy| median {result.median_abs_dy_px:.2f} px, "
          f"90th percentile {result.p90_abs_dy_px:.2f} px; disparities {lo:.1f} to {hi:.1f} px; "
          f"{result.size[0]}x{result.size[1]} -> {folder}")
    return 0
