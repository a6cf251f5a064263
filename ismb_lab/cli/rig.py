"""``ismb-lab rig``: a rig file from a factory calibration (``StereoCamera.from_factory``) or from
one OpenCV wrote (``StereoCamera.from_opencv``), for a camera that needs no chessboard."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from ._guard import Files, UsageError, _short, add_force_option, output_path

__all__ = ["add_parser", "files", "run"]


def _size(text: str) -> tuple:
    parts = text.lower().split("x")
    if len(parts) != 2 or not all(p.strip().isascii() and p.strip().isdigit() and len(p.strip()) <= 5
                                  and 1 <= int(p) <= 1 << 16 for p in parts):
        raise argparse.ArgumentTypeError(f"WxH in pixels, each from 1 to {1 << 16}, e.g. 640x480; "
                                         f"not {_short(text)!r}")
    return tuple(int(p) for p in parts)


def _centre(text: str) -> tuple:
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"CX,CY in pixels, e.g. 319.5,239.5; not {_short(text)!r}")
    return values


def add_parser(sub) -> None:
    """Add the ``rig`` command: write a rig file from a factory calibration, without a chessboard."""
    from ..cameras.camera import MAX_BASELINE_M, UNITS

    r = sub.add_parser("rig", help="write a rig file from a factory calibration (no chessboard)",
                       description="Write the rig file that 'calibrate' writes, for a camera calibrated at the "
                       "factory. A rectified stereo camera (OAK-D, RealSense, ZED): give its rectified focal "
                       "length, baseline, image size and principal point (default: the image centre). A "
                       "calibration OpenCV wrote (cv2.FileStorage YAML, XML or JSON with the two cameras' "
                       "K1, D1, K2, D2, R and T): give the file(s) with --from-opencv. The rig has no measured "
                       "RMS error (rms_px null): 'match --rig' then keeps candidates within the search band "
                       "of a rig without one, which it prints.")
    r.add_argument("--focal-px", type=float, default=None, metavar="F", help="rectified focal length in pixels")
    r.add_argument("--baseline-m", type=float, default=None, metavar="B",
                   help=f"distance between the cameras' centres in metres (at most {MAX_BASELINE_M:g})")
    r.add_argument("--size", type=_size, default=None, metavar="WxH",
                   help="image width and height in pixels (with --from-opencv: default the file's "
                   "image_width and image_height)")
    r.add_argument("--centre", type=_centre, default=None, metavar="CX,CY",
                   help="principal point of the rectified views in pixels (default: the image centre)")
    r.add_argument("--from-opencv", dest="opencv", type=Path, action="append", default=None, metavar="FILE.yml",
                   help="read K1, D1, K2, D2, R and T from an OpenCV FileStorage file (repeat it for a "
                   "calibration split over files, such as intrinsics.yml and extrinsics.yml)")
    r.add_argument("--units", choices=tuple(UNITS), default=None,
                   help="with --from-opencv: the unit of T, the calibration board's (default: m)")
    r.add_argument("--out", type=output_path, required=True, metavar="RIG.json", help="where the rig is written")
    add_force_option(r)
    r.set_defaults(run=run, declare_files=files)


def files(args) -> Files:
    """The OpenCV files read; the rig written."""
    return Files(inputs=tuple(("--from-opencv", path) for path in args.opencv or ()), outputs=(("--out", args.out),))


def _factory(args):
    from ..cameras.camera import MAX_BASELINE_M, StereoCamera

    missing = [f"--{name}" for name, value in (("focal-px", args.focal_px), ("baseline-m", args.baseline_m),
                                               ("size", args.size)) if value is None]
    if missing:
        raise UsageError(f"a rig from factory values needs --focal-px, --baseline-m and --size (missing: "
                         f"{', '.join(missing)}), or give --from-opencv FILE.yml")
    if args.units is not None:
        raise UsageError("--units is the unit of an OpenCV file's T: --baseline-m is in metres already")
    if not (math.isfinite(args.focal_px) and args.focal_px > 0):
        raise UsageError(f"--focal-px must be a finite number > 0, got {args.focal_px:g}")
    if not (math.isfinite(args.baseline_m) and 0 < args.baseline_m <= MAX_BASELINE_M):
        raise UsageError(f"--baseline-m must be a finite number > 0 and at most {MAX_BASELINE_M:g} (metres), "
                         f"got {args.baseline_m:g}")
    width, height = args.size
    if args.centre is not None:
        cx, cy = args.centre
        if not (0 <= cx <= width - 1 and 0 <= cy <= height - 1):
            raise UsageError(f"--centre must lie inside the {width}x{height} image (0 to {width - 1}, 0 to "
                             f"{height - 1}), got {cx:g},{cy:g}")
    return StereoCamera.from_factory(args.focal_px, args.baseline_m, args.size, args.centre)


def _opencv(args):
    from ..cameras.camera import StereoCamera

    given = [f"--{name}" for name, value in (("focal-px", args.focal_px), ("baseline-m", args.baseline_m),
                                             ("centre", args.centre)) if value is not None]
    if given:
        raise UsageError(f"--from-opencv gives the cameras: leave out {' and '.join(given)}")
    return StereoCamera.from_opencv(*args.opencv, size=args.size, units=args.units or "m")


def run(args) -> int:
    """Build the rig from the given numbers or OpenCV file and write it; returns the exit code."""
    from .._core.files import atomic_write_text
    from ..matching.metric import row_tolerance

    rig = _opencv(args) if args.opencv else _factory(args)
    warnings = rig.warnings()
    atomic_write_text(args.out, rig.to_json())
    (cx, cy), (w, h) = rig.rectified_centre, rig.size
    how = ("a rectified camera: pairs are matched as they are" if rig.is_rectified
           else f"raw photos are rectified with it (rectified zoom {rig.zoom:.2f}x)")
    print(f"{w}x{h}, focal length {rig.focal_px:.1f} px, principal point ({cx:.1f}, {cy:.1f}), baseline "
          f"{rig.baseline_m:.4f} m; {how}; no measured RMS error, so 'match --rig' keeps candidates within "
          f"{row_tolerance(rig, subpixel=True):g} px of their row -> {args.out}")
    for text in warnings:
        print(f"ismb-lab: warning: {text}", file=sys.stderr)
    return 0
