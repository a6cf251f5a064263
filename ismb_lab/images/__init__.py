"""The pixels: loading a pair, Harris corners (thesis ch. 2), rectification and the photo datasets.
"""

from .coords import euclidean_disparity, horizontal_disparity, vertical_disparity
from .io import (MAX_PIXELS, MOST_PIXELS, PIXELS_VARIABLE, decode, exif_orientation, grey_uint8,
    image_sha256, load_image, load_pair, max_pixels, orient, png_bytes, save_image, save_pair, StereoPair)
from .features import (MAX_SIGMA, Corners, check_roi, detect_corners, harris_from_tensor, harris_response, image_gradients,
    resolve_roi, structure_tensor)
from .rectify import (ROW_SPREAD, WORKING_SIDE, Correspondences, Rectified, apply_rectification, check_for_matching,
    check_rectified, epipole_warning, load_photo, measured, negative_share, photo_orientation,
    row_spread_px, sideways_step, rectify_pair, robust_matches, working_size)
from .datasets import (CHESSBOARD_PAIRS, MOTORCYCLE_ROIS, OPENCV_DATA, OPENCV_DATA_VARIABLE, SampleDataMissing, aloe,
    aloe_files, books, chessboard_pairs, ground_truth_pairs, GroundTruthPair, motorcycle,
    motorcycle_files, opencv_samples)

__all__ = ["CHESSBOARD_PAIRS", "Corners", "Correspondences", "GroundTruthPair", "MAX_PIXELS",
           "MAX_SIGMA", "MOST_PIXELS", "MOTORCYCLE_ROIS", "OPENCV_DATA", "OPENCV_DATA_VARIABLE",
           "PIXELS_VARIABLE", "ROW_SPREAD", "Rectified", "SampleDataMissing", "StereoPair", "WORKING_SIDE",
           "aloe", "aloe_files", "apply_rectification", "books", "check_for_matching", "check_rectified",
           "check_roi", "chessboard_pairs", "decode", "detect_corners", "epipole_warning",
           "euclidean_disparity", "exif_orientation", "grey_uint8", "ground_truth_pairs",
           "harris_from_tensor", "harris_response", "horizontal_disparity", "image_gradients", "image_sha256",
           "load_image", "load_pair", "load_photo", "max_pixels", "measured", "motorcycle",
           "motorcycle_files", "negative_share", "opencv_samples", "orient", "photo_orientation", "png_bytes",
           "rectify_pair", "resolve_roi", "robust_matches", "row_spread_px", "save_image", "save_pair",
           "sideways_step", "structure_tensor", "vertical_disparity", "working_size"]
