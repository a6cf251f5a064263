"""Chessboard calibration of a fixed two-camera rig: intrinsics, baseline and rectification maps.

Corners by ``cv2.findChessboardCorners`` (refined with ``cv2.cornerSubPix``), each camera by
``cv2.calibrateCamera``, then the pair by ``cv2.stereoCalibrate`` with those intrinsics fixed.
The board's square size sets the scale of everything metric.  The rig keeps each pair's corners,
so a pair can be dropped without finding the boards again (:func:`recalibrate`).
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path
from typing import NamedTuple

import cv2
import numpy as np

from .._core.validation import ParameterError, message
from .camera import BOARD, FORMAT, MAX_ZOOM, SQUARE_M, BoardPair, StereoCamera, check_board
from ..images.io import grey_uint8
from ..images.rectify import load_photo

__all__ = ["BOARD", "MAX_ZOOM", "SQUARE_M", "HeldOut", "board_depth", "board_points", "calibrate_rig",
           "find_board", "leave_one_out", "outliers", "recalibrate"]

#: Fewest pairs in which the board is found in both views for a calibration.
MIN_PAIRS = 3
_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-6)
#: A pair is an outlier above both this many times the pairs' median error and `OUTLIER_PX`: on
#: OpenCV's sample, pair 02 (4.5 times the median) is; the worst pair once it is dropped (2.1) is
#: not; the floor keeps a rig of good pairs from marking any.
OUTLIER_RATIO = 3.0
OUTLIER_PX = 0.5


def find_board(image, board=BOARD) -> np.ndarray | None:
    """The board's inner corners ``(x, y)``, refined to sub-pixel, or None when not found."""
    grey = grey_uint8(image)
    found, corners = cv2.findChessboardCorners(grey, tuple(board), cv2.CALIB_CB_ADAPTIVE_THRESH
                                               + cv2.CALIB_CB_NORMALIZE_IMAGE)
    if not found:
        return None
    corners = cv2.cornerSubPix(grey, corners, (11, 11), (-1, -1), _CRITERIA)
    return corners.reshape(-1, 2).astype(float)


def board_points(board, square_m: float) -> np.ndarray:
    """The board's inner corners in its own frame, metres, in ``cv2.findChessboardCorners``' order.

    >>> board_points((3, 2), 0.5)[[0, 1, 3]].tolist()
    [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0]]
    """
    cols, rows = board
    grid = np.zeros((rows * cols, 3), np.float32)
    grid[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_m
    return grid


def outliers(pairs) -> tuple:
    """Indices of the pairs whose error is above both three times the median and 0.5 px.

    Parameters
    ----------
    pairs : sequence of BoardPair
        The rig's pairs, with their ``rms_px``.

    Returns
    -------
    indices : tuple of int
        The outliers' positions in `pairs`.

    Examples
    --------
    >>> outliers([BoardPair("a", "b", [[0, 0]], [[0, 0]], e) for e in (0.2, 0.3, 0.25, 1.2, 0.4)])
    (3,)
    """
    errors = np.array([p.rms_px for p in pairs], dtype=float)
    if not len(errors):
        return ()
    limit = max(OUTLIER_RATIO * float(np.median(errors)), OUTLIER_PX)
    return tuple(int(i) for i in np.flatnonzero(errors > limit))


def calibrate_rig(pairs, board=BOARD, square_m: float = SQUARE_M, progress=None) -> StereoCamera:
    """Calibrate a rig from ``(name, left, right)`` chessboard pairs (paths, bytes or grey arrays,
    all of one size); `progress` is called once per pair.  Pairs where the board is not found in
    both views are named in ``skipped``; fewer than 3 usable pairs raise a ParameterError.

    Parameters
    ----------
    pairs : iterable of tuple
        ``(name, left, right)``, the photos as paths, bytes or grey arrays.
    board : tuple of int, default BOARD
        Inner corners ``(columns, rows)`` of the chessboard.
    square_m : float, default SQUARE_M
        Side of a square, metres: the scale of everything metric.
    progress : callable, optional
        Called with each pair's name once it is searched.

    Returns
    -------
    rig : StereoCamera
        The calibrated rig, with its pairs' corners and errors.

    Raises
    ------
    ParameterError
        Photos of different sizes, fewer than 3 usable pairs, or corners OpenCV refuses.
    """
    owner = "calibrate_rig"
    board, square_m = check_board(board, square_m, owner)
    found_pairs, used, skipped, size = [], [], [], None
    for name, left, right in pairs:
        names = _photo_name(left, f"{name} left"), _photo_name(right, f"{name} right")
        left, right = load_photo(left, f"left {name}", owner), load_photo(right, f"right {name}", owner)
        here = (left.shape[1], left.shape[0])
        if size is None:
            size = here
        if here != size or right.shape != left.shape:
            raise ParameterError(message("pairs", owner, f"images all of one size ({size[0]}x{size[1]})",
                                         f"pair {name}: {here[0]}x{here[1]} and {right.shape[1]}x{right.shape[0]}"))
        found = find_board(left, board), find_board(right, board)
        if progress is not None:
            progress(name)
        if found[0] is None or found[1] is None:
            skipped.append(str(name))
            continue
        found_pairs.append(BoardPair(*names, *found))
        used.append(str(name))
    return _calibrate(found_pairs, tuple(used), tuple(skipped), size, tuple(board), square_m, owner)


def _photo_name(photo, default: str) -> str:
    return Path(photo).name if isinstance(photo, (str, Path)) else default


@contextmanager
def _one_thread():
    """OpenCV on one thread for the duration: with more, its calibration's sums depend on scheduling."""
    before = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        yield
    finally:
        cv2.setNumThreads(before)


def _calibrate(pairs, used, skipped, size, board, square_m, owner) -> StereoCamera:
    """The rig from the corners already found: each camera, then the pair with them fixed."""
    if len(pairs) < MIN_PAIRS:
        raise ParameterError(message("pairs", owner, f"at least {MIN_PAIRS} pairs with the {board[0]}x{board[1]} "
                                     "board found in both views", f"{len(pairs)} (skipped: {', '.join(skipped)})"))
    corners = board[0] * board[1]
    for p in pairs:
        if len(p.left_corners) != corners:
            raise ParameterError(message("pairs", owner, f"the {corners} corners of the {board[0]}x{board[1]} board "
                                         "in each view", f"{len(p.left_corners)} corners in pair {p.left}"))
    objects = [board_points(board, square_m)] * len(pairs)
    left_points = [p.left_corners.astype(np.float32) for p in pairs]
    right_points = [p.right_corners.astype(np.float32) for p in pairs]
    try:
        with _one_thread():          # the same corners give the same rig, bit for bit
            _, k_l, d_l, _, _ = cv2.calibrateCamera(objects, left_points, size, None, None)
            _, k_r, d_r, _, _ = cv2.calibrateCamera(objects, right_points, size, None, None)
            rms, k_l, d_l, k_r, d_r, rotation, translation, _, _, rvecs, tvecs, per_view = \
                cv2.stereoCalibrateExtended(objects, left_points, right_points, k_l, d_l, k_r, d_r, size, None, None,
                                            criteria=_CRITERIA, flags=cv2.CALIB_FIX_INTRINSIC)
    except cv2.error as exc:   # corners that no camera could have seen (edited by hand, for one)
        said = next((line for line in str(exc).splitlines() if "error:" in line), str(exc)).strip()
        raise ParameterError(message("pairs", owner, "corners from which OpenCV can calibrate the cameras",
                                     f"{len(pairs)} pairs that OpenCV refuses: {said}")) from None
    # per_view holds each view's RMS; both views have as many corners, so the pair's is their quadratic mean.
    errors = np.sqrt(np.mean(np.square(per_view), axis=1))
    pairs = tuple(BoardPair(p.left, p.right, p.left_corners, p.right_corners, float(e), r, t)
                  for p, e, r, t in zip(pairs, errors, rvecs, tvecs))
    return StereoCamera(tuple(size), k_l, d_l, k_r, d_r, rotation, translation, float(rms), tuple(board), square_m,
               tuple(used), tuple(skipped), pairs)


def recalibrate(rig: StereoCamera, drop=()) -> StereoCamera:
    """`rig` calibrated again from its own corners without the pairs in `drop`, each named by its
    left or right photo (a path names it by its file name) or by its name in ``rig.used``.

    Parameters
    ----------
    rig : StereoCamera
        A calibrated rig.
    drop : str, Path or iterable of them, optional
        The pairs to leave out.

    Returns
    -------
    rig : StereoCamera
        The rig calibrated from the other pairs.

    Raises
    ------
    ParameterError
        A rig without its pairs' corners, an unknown pair, or fewer than 3 left.
    """
    owner = "recalibrate"
    if not rig.pairs:
        raise ParameterError(message("rig", owner, "a rig that keeps its pairs' corners (format "
                                     f"{FORMAT}); calibrate it again from the photos", "a rig without them"))
    drop = (drop,) if isinstance(drop, (str, Path)) else tuple(drop)
    known = lambda name: any(name in (*p.names, u) for p, u in zip(rig.pairs, rig.used))
    # a path as typed (boards/left02.jpg) names its photo: the rig keeps the photos' names only
    typed = tuple(str(name) for name in drop)
    drop = tuple(name if known(name) else Path(name).name for name in typed)
    unknown = [name for name, own in zip(typed, drop) if not known(own)]
    if unknown:
        raise ParameterError(message("drop", owner, "photos of the rig's pairs ("
                                     + ", ".join(p.left for p in rig.pairs) + ")", ", ".join(unknown)))
    return _refit(rig, [(p, u) for p, u in zip(rig.pairs, rig.used) if not set(drop) & {*p.names, u}], owner)


def _refit(rig: StereoCamera, kept, owner: str) -> StereoCamera:
    """`rig` calibrated again from the ``(pair, name)`` items of `kept`."""
    return _calibrate([p for p, _ in kept], tuple(u for _, u in kept), rig.skipped, tuple(rig.size),
                      tuple(rig.board), rig.square_m, owner)


class HeldOut(NamedTuple):
    """One pair's figures under the rig calibrated without it (:func:`leave_one_out`)."""

    reprojection_px: float
    depth_error: float


def _held_out(rig: StereoCamera, pair: BoardPair) -> HeldOut:
    """`pair`'s board under `rig`, which was calibrated without it."""
    grid = board_points(rig.board, rig.square_m).astype(np.float64)
    ok, rvec, tvec = cv2.solvePnP(grid, pair.left_corners, rig.k_left, rig.d_left)
    if not ok:
        return HeldOut(float("nan"), float("nan"))
    pose, _ = cv2.Rodrigues(rvec)
    left, _ = cv2.projectPoints(grid, rvec, tvec, rig.k_left, rig.d_left)
    right_pose, _ = cv2.Rodrigues(rig.rotation @ pose)
    right, _ = cv2.projectPoints(grid, right_pose, rig.rotation @ tvec.reshape(3, 1) + rig.translation,
                                 rig.k_right, rig.d_right)
    residuals = np.concatenate([left.reshape(-1, 2) - pair.left_corners, right.reshape(-1, 2) - pair.right_corners])
    reprojection = float(np.sqrt(np.mean(np.sum(residuals ** 2, axis=1))))
    disparity = rig.rectify_points(pair.left_corners, "left")[:, 0] - rig.rectify_points(pair.right_corners,
                                                                                         "right")[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        stereo = rig.focal_px * rig.baseline_m / disparity
    seen = ((grid @ pose.T + tvec.reshape(1, 3)) @ rig.left_to_rectified.T)[:, 2]
    return HeldOut(reprojection, float(np.median(np.abs(stereo - seen) / seen)))


def leave_one_out(rig: StereoCamera, progress=None) -> tuple:
    """Each pair of `rig` held out in turn: its board under the rig calibrated from the others.

    The fit's RMS falls with every pair dropped, bad or not; a held-out board's error does not,
    so it tells when dropping stops helping.  ``reprojection_px``: the board's pose from its left
    view (``cv2.solvePnP``) carried to the right camera by ``R``, ``T``; the RMS error of its
    corners over both views.  ``depth_error``: the median over the corners of
    ``|Z_stereo - Z_pose| / Z_pose`` in the rectified frame.  NaN where the others do not
    calibrate.  `rig` keeps the corners of at least 4 pairs.

    Parameters
    ----------
    rig : StereoCamera
        A calibrated rig.
    progress : callable, optional
        Called with each pair's index once it is done.

    Returns
    -------
    held_out : tuple of HeldOut
        One per pair of `rig`, in order.

    Raises
    ------
    ParameterError
        A rig that keeps the corners of 3 pairs or fewer.
    """
    owner = "leave_one_out"
    if len(rig.pairs) <= MIN_PAIRS:
        raise ParameterError(message("rig", owner, f"a rig that keeps the corners of more than {MIN_PAIRS} pairs "
                                     f"(format {FORMAT})", f"{len(rig.pairs)} pairs"))
    found = []
    for n, pair in enumerate(rig.pairs):
        others = [(p, u) for m, (p, u) in enumerate(zip(rig.pairs, rig.used)) if m != n]
        try:
            found.append(_held_out(_refit(rig, others, owner), pair))
        except (ParameterError, cv2.error):
            found.append(HeldOut(float("nan"), float("nan")))
        if progress is not None:
            progress(n)
    return tuple(found)


def board_depth(rig: StereoCamera, left, right) -> dict:
    """The board's median depth in a pair of `rig`, in the rectified left frame, two ways whose
    agreement checks the calibration: ``"stereo"`` (``Z = f B / d`` of the rectified corners)
    and ``"pnp"`` (the pose from the left view and the board's known size).

    Parameters
    ----------
    rig : StereoCamera
        A calibrated rig.
    left, right : str, Path, bytes or array
        A pair of photos taken by the rig, showing the whole board.

    Returns
    -------
    depths : dict
        ``"stereo"`` and ``"pnp"`` in metres, and ``"disparity_px"``, the corners' [min, max].

    Raises
    ------
    ParameterError
        The board is not found in both views.
    """
    owner = "board_depth"
    rectified = rig.rectify(left, right)
    corners = find_board(rectified.left, rig.board), find_board(rectified.right, rig.board)
    if corners[0] is None or corners[1] is None:
        raise ParameterError(message("left", owner, "a pair showing the whole board in both views",
                                     "a pair where it was not found"))
    disparity = corners[0][:, 0] - corners[1][:, 0]
    stereo = rig.focal_px * rig.baseline_m / disparity
    raw = find_board(load_photo(left, "left", owner), rig.board)
    if raw is None:
        raise ParameterError(message("left", owner, "a photo showing the whole board", "one where it was not found"))
    grid = board_points(rig.board, rig.square_m)
    ok, rvec, tvec = cv2.solvePnP(grid, raw.astype(np.float32), rig.k_left, rig.d_left)
    pose, _ = cv2.Rodrigues(rvec)
    in_camera = grid @ pose.T + tvec.reshape(1, 3)
    in_rectified = in_camera @ rig.left_to_rectified.T
    return {"stereo": float(np.median(stereo)), "pnp": float(np.median(in_rectified[:, 2])),
            "disparity_px": [float(disparity.min()), float(disparity.max())]}
