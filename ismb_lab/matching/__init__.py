"""From a pair to matches: corners, the network's problem, a solver, and the matches in pixels or metres;
the peer matchers and SGBM beside it."""

from .pipeline import (AUTO_MARGIN, MatchConfig, MatchResult, Prepared, auto_window, check_window, corner_problem, match,
    prepare, shift_roi, warm_up)
from .recipe import RECIPE_VERSION, Loaded, Recipe, load_recipe, recipe_of, save_recipe
from .peers import (MAX_ASSIGNMENTS, PEERS, affinity_matrix, default_no_match_cost, graph_matching, hungarian,
    mutual_nearest)
from .metric import (IMPROVES, THESIS_SIZE, photo_config, fit_rows_px, for_camera, match_points, rectify_for_camera,
    match_with_camera, mutual_best, prepare_for_camera, rig_config, row_tolerance, subpixel)
from .dense import (AGREE_PX, AGREE_SHARE, Agreement, MAX_DENSE, SGBM_BLOCK, agreement, dense_points, sgbm_disparity,
    sgbm_range, window_range)
from .ply import ply_bytes

__all__ = ["AGREE_PX", "AGREE_SHARE", "AUTO_MARGIN", "Agreement", "IMPROVES", "Loaded", "MAX_ASSIGNMENTS",
           "MAX_DENSE", "MatchConfig", "MatchResult", "PEERS", "Prepared", "RECIPE_VERSION", "Recipe",
           "SGBM_BLOCK", "THESIS_SIZE", "affinity_matrix", "agreement", "auto_window", "check_window",
           "corner_problem", "default_no_match_cost", "dense_points", "fit_rows_px", "for_camera",
           "graph_matching", "hungarian", "load_recipe", "match", "match_points", "match_with_camera",
           "mutual_best", "mutual_nearest", "photo_config", "ply_bytes", "prepare", "prepare_for_camera",
           "recipe_of", "rectify_for_camera", "rig_config", "row_tolerance", "save_recipe", "sgbm_disparity",
           "sgbm_range", "shift_roi", "subpixel", "warm_up", "window_range"]
