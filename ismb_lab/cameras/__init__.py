"""One stereo camera model, and a rig's calibration from chessboard pairs.
"""

from .camera import (BASELINE_M, BOARD, FOCAL_PX, MAX_BASELINE_M, MAX_BOARD_SIDE, MAX_SQUARE_M, MAX_ZOOM, MIN_SQUARE_M,
    SQUARE_M, FORMAT, HEIGHT, OPENCV_NAMES, UNITS, WIDTH, BoardPair, StereoCamera, check_board,
    load_camera)
from .rig import (HeldOut, board_depth, board_points, calibrate_rig, find_board, leave_one_out, outliers, recalibrate)

__all__ = ["BASELINE_M", "BOARD", "BoardPair", "FOCAL_PX", "FORMAT", "HEIGHT", "HeldOut", "MAX_BASELINE_M",
           "MAX_BOARD_SIDE", "MAX_SQUARE_M", "MAX_ZOOM", "MIN_SQUARE_M", "OPENCV_NAMES", "SQUARE_M",
           "StereoCamera", "UNITS", "WIDTH", "board_depth", "board_points", "calibrate_rig", "check_board",
           "find_board", "leave_one_out", "load_camera", "outliers", "recalibrate"]
