"""``ismb-lab calibrate``: a fixed two-camera rig from chessboard pairs, or from a rig's own corners
without some of its pairs (``--from RIG.json --drop left02.jpg``)."""

from __future__ import annotations

import sys
from pathlib import Path

from ._guard import Files, UsageError, _short, add_force_option, output_path

__all__ = ["add_parser", "files", "report", "run"]


def add_parser(sub) -> None:
    """Add the ``calibrate`` command: calibrate a fixed rig from chessboard pairs and write it as JSON."""
    from ..cameras.rig import BOARD, MAX_ZOOM, OUTLIER_PX, OUTLIER_RATIO, SQUARE_M

    c = sub.add_parser("calibrate", help="calibrate a fixed rig from chessboard pairs",
                       description="Find the chessboard in each pair, calibrate both cameras and the "
                       "pair (cv2.stereoCalibrate) and write the rig as JSON: the RMS reprojection "
                       "error, each pair's own error, the rectified focal length in px, the baseline in m "
                       "and each pair's corners. Pairs where the board is not found in both views are "
                       "skipped and named. The table of pairs marks with '<-- outlier' a pair whose error "
                       f"is above both {OUTLIER_RATIO:g}x the median and {OUTLIER_PX:g} px; drop it with "
                       "--from RIG.json --drop LEFT.jpg; each pair's error when it is held out (the rig calibrated from "
                       "the others) tells when dropping stops helping. A rectified zoom above "
                       f"{MAX_ZOOM:g}x, or a board leaving the rectified view, is warned about.")
    c.add_argument("pairs", type=Path, nargs="*", metavar="LEFT RIGHT",
                   help="photos in pairs: left1 right1 left2 right2 ... (at least 3 pairs)")
    c.add_argument("--from", dest="source", type=Path, default=None, metavar="RIG.json",
                   help="calibrate again from this rig's corners instead of photos (no photos then)")
    c.add_argument("--drop", action="append", default=[], metavar="PHOTO",
                   help="with --from: leave out the pair of this left or right photo, named as typed "
                   "(boards/left02.jpg) or by its file name (left02.jpg) (repeatable)")
    c.add_argument("--board", default=None, metavar="COLSxROWS",
                   help=f"inner corners per row and per column (default: {BOARD[0]}x{BOARD[1]})")
    c.add_argument("--square-m", type=float, default=None, metavar="S",
                   help=f"side of one square in metres (default: {SQUARE_M}); B and Z scale with it")
    c.add_argument("--out", type=output_path, required=True, metavar="RIG.json", help="where the rig is written")
    add_force_option(c)
    c.set_defaults(run=run, declare_files=files)


def files(args) -> Files:
    """The photos or the rig read; the rig written."""
    inputs = tuple(("a photo", path) for path in args.pairs)
    if args.source is not None:
        inputs += (("--from", args.source),)
    return Files(inputs=inputs, outputs=(("--out", args.out),))


def report(rig, held=()) -> str:
    """The table of the rig's pairs, their errors and outliers; with `held` (``leave_one_out``), each
    pair's errors when held out, and their summary."""
    import math

    import numpy as np

    from ..cameras.rig import OUTLIER_PX, OUTLIER_RATIO, outliers

    marked = set(outliers(rig.pairs))
    width = max([len("left")] + [len(p.left) for p in rig.pairs])
    extra = "  held_out_px  depth_error" if held else ""
    lines = [f"{'left':<{width}}  {'right':<{width}}  rms_px{extra}"]
    for n, p in enumerate(rig.pairs):
        row = f"{p.left:<{width}}  {p.right:<{width}}  {p.rms_px:6.3f}"
        if held:
            h = held[n]
            row += f"  {h.reprojection_px:11.3f}  " + (f"{100 * h.depth_error:10.2f}%" if math.isfinite(h.depth_error)
                                                       else f"{'-':>11}")
        lines.append(row + ("  <-- outlier" if n in marked else ""))
    if marked:
        lines.append(f"outlier: above both {OUTLIER_RATIO:g}x the median and {OUTLIER_PX:g} px; to leave one "
                     "out: ismb-lab calibrate --from RIG.json --drop LEFT --out NEW.json")
    if held:
        px = np.array([h.reprojection_px for h in held])
        depth = np.array([h.depth_error for h in held])
        ok = np.isfinite(px) & np.isfinite(depth)
        if ok.any():
            lines.append(f"leave-one-out: each pair held out, the rig calibrated from the others: RMS reprojection "
                         f"error {np.sqrt(np.mean(px[ok] ** 2)):.3f} px over the held-out boards (the fit's: "
                         f"{rig.rms:.3f} px), median depth error {100 * np.median(depth[ok]):.2f}%. Dropping a pair "
                         "always lowers the fit's error; drop while the held-out figures fall too")
    return "\n".join(lines)


def _board(text: str):
    from ..cameras.camera import MAX_BOARD_SIDE

    parts = [p.strip() for p in text.lower().split("x")]
    if len(parts) != 2 or not all(p.isascii() and p.isdigit() and len(p) <= 4 and 2 <= int(p) <= MAX_BOARD_SIDE
                                  for p in parts):
        raise UsageError(f"--board must be COLSxROWS of inner corners, each from 2 to {MAX_BOARD_SIDE}, e.g. 9x6; "
                         f"got {_short(text)!r}")
    return tuple(int(p) for p in parts)


def _from_rig(args):
    from ..cameras.camera import load_camera
    from ..cameras.rig import recalibrate

    if args.pairs:
        raise UsageError("calibrate takes either photos or --from RIG.json, not both")
    if args.board is not None or args.square_m is not None:
        raise UsageError("--board and --square-m are the rig's own with --from; leave them out")
    return recalibrate(load_camera(args.source), args.drop)


def run(args) -> int:
    """Calibrate the rig from the chessboard pairs of `args` and write the rig file; returns the exit code."""
    from .._core.files import atomic_write_text
    from ..cameras.camera import MAX_SQUARE_M, MIN_SQUARE_M
    from ..cameras.rig import BOARD, MIN_PAIRS, SQUARE_M, calibrate_rig, leave_one_out
    from ._common import progress_bar

    if args.drop and args.source is None:
        raise UsageError("--drop leaves a pair out of a rig: give the rig with --from RIG.json")
    if args.source is not None:
        rig = _from_rig(args)
    else:
        if len(args.pairs) % 2 or not args.pairs:
            raise UsageError(f"calibrate takes photos in pairs (left right ...) or --from RIG.json: got "
                             f"{len(args.pairs)} files")
        board = _board(args.board) if args.board is not None else BOARD
        square_m = SQUARE_M if args.square_m is None else args.square_m
        if not MIN_SQUARE_M <= square_m <= MAX_SQUARE_M:
            raise UsageError(f"--square-m must be a side from {MIN_SQUARE_M:g} to {MAX_SQUARE_M:g} m, got {square_m:g}")
        pairs = [(f"{args.pairs[n].name}+{args.pairs[n + 1].name}", args.pairs[n], args.pairs[n + 1])
                 for n in range(0, len(args.pairs), 2)]
        with progress_bar(len(pairs), "chessboards", unit="pair") as bar:
            rig = calibrate_rig(pairs, board, square_m, progress=lambda _: bar.update(1))
    held = leave_one_out(rig) if len(rig.pairs) > MIN_PAIRS else ()
    atomic_write_text(args.out, rig.to_json())
    if rig.skipped:
        print(f"board not found in both views, skipped: {', '.join(rig.skipped)}")
    print(report(rig, held))
    if not held:
        print(f"leave-one-out: needs more than {MIN_PAIRS} pairs")
    print(f"{len(rig.used)} pairs: RMS reprojection error {rig.rms:.3f} px, focal length {rig.focal_px:.1f} px, "
          f"baseline {rig.baseline_m:.4f} m (squares of {rig.square_m:g} m), rectified zoom {rig.zoom:.2f}x "
          f"-> {args.out}")
    for text in rig.warnings():
        print(f"ismb-lab: warning: {text}", file=sys.stderr)
    return 0
