"""``ismb-lab calibrate``: calibrate a fixed two-camera rig from chessboard pairs."""

from __future__ import annotations

from pathlib import Path

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    from ..rig import BOARD, SQUARE_M

    c = sub.add_parser("calibrate", help="calibrate a fixed rig from chessboard pairs",
                       description="Find the chessboard in each pair, calibrate both cameras and the "
                       "pair (cv2.stereoCalibrate) and write the rig as JSON: the RMS reprojection "
                       "error, the rectified focal length in px and the baseline in m. Pairs where the "
                       "board is not found in both views are skipped and named.")
    c.add_argument("pairs", type=Path, nargs="+", metavar="LEFT RIGHT",
                   help="photos in pairs: left1 right1 left2 right2 ... (at least 3 pairs)")
    c.add_argument("--board", default=f"{BOARD[0]}x{BOARD[1]}", metavar="COLSxROWS",
                   help=f"inner corners per row and per column (default: {BOARD[0]}x{BOARD[1]})")
    c.add_argument("--square-m", type=float, default=SQUARE_M, metavar="S",
                   help=f"side of one square in metres (default: {SQUARE_M}); B and Z scale with it")
    c.add_argument("--out", type=Path, required=True, metavar="RIG.json", help="where the rig is written")
    c.set_defaults(run=run)


def run(args) -> int:
    import math

    from .._files import atomic_write_text, check_input, check_output
    from ..rig import calibrate_rig
    from ._common import UsageError, progress_bar

    if len(args.pairs) % 2:
        raise UsageError(f"calibrate takes photos in pairs (left right ...): got {len(args.pairs)} files")
    try:
        board = tuple(int(v) for v in args.board.lower().split("x"))
        assert len(board) == 2 and min(board) >= 2
    except (ValueError, AssertionError):
        raise UsageError(f"--board must be COLSxROWS of inner corners, e.g. 9x6; got {args.board!r}") from None
    if not args.square_m > 0 or math.isinf(args.square_m):
        raise UsageError(f"--square-m must be a finite number > 0, got {args.square_m:g}")
    for path in args.pairs:
        check_input(path, what="a photo")
    check_output(args.out, inputs=args.pairs, force=getattr(args, "force", False), what="--out")
    pairs = [(f"{args.pairs[n].name}+{args.pairs[n + 1].name}", args.pairs[n], args.pairs[n + 1])
             for n in range(0, len(args.pairs), 2)]
    with progress_bar(len(pairs), "chessboards", unit="pair") as bar:
        rig = calibrate_rig(pairs, board, args.square_m, progress=lambda _: bar.update(1))
    atomic_write_text(args.out, rig.to_json())
    if rig.skipped:
        print(f"board not found in both views, skipped: {', '.join(rig.skipped)}")
    print(f"{len(rig.used)} pairs: RMS reprojection error {rig.rms:.3f} px, focal length {rig.focal_px:.1f} px, "
          f"baseline {rig.baseline_m:.4f} m (squares of {rig.square_m:g} m) -> {args.out}")
    return 0
