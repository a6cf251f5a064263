"""Disparity to depth, and the toy-car demo's objects ranked near to far (thesis §5.2.3).
"""

from .objects import GROUPINGS, Depth, DepthConfig, DepthObject, DepthResult, depth_from_matches, metric_depth
from .outlines import CHANGE_SIGMA, CHANGE_THRESHOLD, OutlineConfig, Silhouettes, changed_in_roi, silhouettes
from .pipeline import (DEPTH_MATCH_CONFIG, DEPTH_PARAMS, DEPTH_SOLVER, REGION_CORNERS, changed_regions, changed_roi,
    depth_match, depth_pairs, layout_match_config, load_stereo, relative_depth, scene_match_config,
    pair_silhouettes, scene_prepared)

__all__ = ["CHANGE_SIGMA", "CHANGE_THRESHOLD", "DEPTH_MATCH_CONFIG", "DEPTH_PARAMS", "DEPTH_SOLVER", "Depth",
           "DepthConfig", "DepthObject", "DepthResult", "GROUPINGS", "OutlineConfig", "REGION_CORNERS",
           "Silhouettes", "changed_in_roi", "changed_regions", "changed_roi", "depth_from_matches",
           "depth_match", "depth_pairs", "layout_match_config", "load_stereo", "metric_depth",
           "pair_silhouettes", "relative_depth", "scene_match_config", "scene_prepared", "silhouettes"]
