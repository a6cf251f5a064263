"""Matches in metres: match a calibrated camera's pair using what the camera knows.

A pair rectified with a calibrated :class:`~ismb_lab.camera.StereoCamera` has its
epipolar lines on the image rows, to within the calibration's error.  Matching it
(``ismb-lab match --rig``, :func:`prepare_for_camera`) uses that three ways, none of them
special to any scene:

1. **rows**: the corners' positions are refined to sub-pixel (:func:`subpixel`; the
   similarity ``M`` still compares the whole-pixel patches), and a match's two corners are
   on one row to within :func:`row_tolerance` pixels, ``2 rms``: each of the two points is
   rectified with about the calibration's RMS reprojection error.  The candidate window is
   that tall.  (Whole-pixel corners, as ``depth --rig`` uses, need ``1 + 2 rms``: each is up
   to half a pixel from its point);
2. **the disparity range**: the window's range is measured on robust SIFT matches that
   search only their own rows and positive disparities (a point in front of both cameras)
   (:func:`ismb_lab.matching.auto_window` with ``rows_px``), so a repetitive texture's
   ratio test compares a keypoint with the others of its row only;
3. **mutual best**: of the network's matches, only those whose two corners are each
   other's most similar candidate in that window are kept (:func:`mutual_best`).

Then each match is a point ``(X, Y, Z)`` in metres in the rectified left camera's frame
(:func:`match_points`, :meth:`~ismb_lab.camera.StereoCamera.points_from_disparity`), from
the sub-pixel positions' disparity.
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np

from ._validation import ParameterError, ParameterTypeError, message
from .camera import StereoCamera
from .matching import MatchConfig, MatchResult, Prepared, auto_window, match, prepare
from .methods import build_problem

__all__ = ["for_camera", "match_points", "match_with_camera", "mutual_best", "prepare_for_camera", "rig_config", "row_tolerance",
           "subpixel"]

#: cv2.cornerSubPix stops when a step is under 0.001 px or after 40 steps.
_SUBPIXEL_STOP = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 40, 0.001)


def row_tolerance(camera: StereoCamera, subpixel: bool = False) -> float:
    """Largest row difference, in pixels, of a true corner match in `camera`'s rectified pair:
    ``2 rms`` for sub-pixel corners, ``1 + 2 rms`` for whole-pixel ones (``1`` for an
    uncalibrated, ideal camera, which has no error to go by).

    >>> row_tolerance(StereoCamera())
    1.0
    >>> row_tolerance(StereoCamera(rms=0.25)), row_tolerance(StereoCamera(rms=0.25), subpixel=True)
    (1.5, 0.5)
    """
    rms = float(camera.rms)
    if not math.isfinite(rms):
        return 1.0
    return 2.0 * rms + (0.0 if subpixel else 1.0)


def rig_config(camera: StereoCamera, config: MatchConfig, pair=None, subpixel: bool = False) -> MatchConfig:
    """`config` with the candidate window `camera` gives: :func:`row_tolerance` rows up and
    down (for sub-pixel corners when `subpixel`), and, with ``shift="auto"``, the disparity
    range measured on `pair` along those rows.

    >>> rig_config(StereoCamera(), MatchConfig()).window_height
    2.0
    """
    if not isinstance(config, MatchConfig):
        raise ParameterTypeError(message("config", "rig_config", "a MatchConfig", config))
    rows = row_tolerance(camera, subpixel)
    config = replace(config, window_height=2 * rows)
    if config.shift == "auto":
        if pair is None:
            raise ParameterError(message("pair", "rig_config", "the pair whose disparities set shift='auto'",
                                         None))
        config = auto_window(pair, config, rows_px=rows)
    return config


def subpixel(image, xy, half: int) -> np.ndarray:
    """Corner points `xy` ``(x, y)`` of `image` refined to sub-pixel (``cv2.cornerSubPix``
    in a ``(2 half + 1)`` square window), kept inside the image.

    >>> import numpy as np
    >>> img = np.zeros((40, 40)); img[:20, :20] = img[20:, 20:] = 255.0
    >>> subpixel(img, np.array([[21.0, 18.0]]), 5).round(1).tolist()
    [[19.5, 19.5]]
    """
    grey = np.asarray(image, dtype=np.float32)
    points = np.asarray(xy, dtype=np.float32).reshape(-1, 1, 2).copy()
    if not len(points):
        return np.zeros((0, 2))
    refined = cv2.cornerSubPix(grey, points, (int(half), int(half)), (-1, -1), _SUBPIXEL_STOP)
    refined = refined.reshape(-1, 2).astype(float)
    height, width = grey.shape
    return np.clip(refined, 0, [width - 1, height - 1])


def prepare_for_camera(pair, config: MatchConfig, camera: StereoCamera) -> Prepared:
    """`pair` (rectified by `camera`) prepared in the window `camera` gives: the corners are
    detected as :func:`~ismb_lab.matching.prepare` does and ``M`` compares their whole-pixel
    patches, then the geometry (the candidate window, the neighbours, the disparities) uses
    their sub-pixel positions (:func:`subpixel`, half the patch size) and rows within
    ``row_tolerance(camera, subpixel=True)``.

    >>> from ismb_lab.io import load_pair
    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> p = prepare_for_camera(load_pair(s.left, s.right), MatchConfig(), StereoCamera())
    >>> p.config.window_height, p.problem.n_neurons > 0
    (2.0, True)
    """
    if not isinstance(camera, StereoCamera):
        raise ParameterTypeError(message("camera", "prepare_for_camera", "a StereoCamera", camera))
    prepared = prepare(pair, None, rig_config(camera, config, pair, subpixel=True))
    c, half = prepared.config, prepared.config.patch_size // 2
    lxy = subpixel(prepared.pair.left, prepared.left_corners.xy, half)
    rxy = subpixel(prepared.pair.right, prepared.right_corners.xy, half)
    problem = build_problem(lxy, rxy, prepared.problem.dissimilarity, shift=c.shift,
                            window_height=c.window_height, window_width=c.window_width,
                            radius=c.neighbour_radius, neighbourhood=c.neighbourhood)
    return replace(prepared, problem=problem)


def match_with_camera(pair, config: MatchConfig, camera: StereoCamera, **options) -> tuple:
    """``ismb-lab match --rig`` on a pair rectified by `camera`: :func:`prepare_for_camera`,
    :func:`~ismb_lab.matching.match` with `options` (method, params, solver, seed, ...), then
    :func:`mutual_best`.  Returns ``(prepared, found, kept)``: the network's matches and those
    kept; ``match_points(kept, camera)`` gives them in metres.

    >>> from ismb_lab.io import load_pair
    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> prepared, found, kept = match_with_camera(load_pair(s.left, s.right), MatchConfig(), s.rig)
    >>> 0 < len(kept.pairs) <= len(found.pairs)
    True
    """
    prepared = prepare_for_camera(pair, config, camera)
    found = match(prepared=prepared, **options)
    return prepared, found, mutual_best(prepared, found)


def mutual_best(prepared: Prepared, result: MatchResult) -> MatchResult:
    """`result` with only the matches whose two corners are each other's most similar
    candidate (smallest ``M``) among the candidate pairs of `prepared`.

    >>> import numpy as np
    >>> from ismb_lab.matching import match, prepare
    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> p = prepare(s.left, s.right)
    >>> r = match(prepared=p)
    >>> kept = mutual_best(p, r)
    >>> 0 < len(kept.pairs) <= len(r.pairs)
    True
    """
    if not isinstance(prepared, Prepared) or not isinstance(result, MatchResult):
        raise ParameterTypeError(message("prepared", "mutual_best", "a Prepared and its MatchResult",
                                         type(prepared).__name__))
    problem = prepared.problem
    rows, cols = problem.rows, problem.cols
    if not len(result.pairs):
        return result
    m = problem.dissimilarity[rows, cols]
    best_right = np.full(len(problem.left_xy), -1)
    best_left = np.full(len(problem.right_xy), -1)
    for r, c, value in zip(rows, cols, m):
        if best_right[r] < 0 or value < problem.dissimilarity[r, best_right[r]]:
            best_right[r] = c
        if best_left[c] < 0 or value < problem.dissimilarity[best_left[c], c]:
            best_left[c] = r
    i, k = result.pairs[:, 0], result.pairs[:, 1]
    keep = (best_right[i] == k) & (best_left[k] == i)
    state = result.state
    if state is not None:
        neuron = {(int(r), int(c)): n for n, (r, c) in enumerate(zip(rows, cols))}
        state = state.copy()
        for a, b in result.pairs[~keep]:
            state[neuron[(int(a), int(b))]] = 0
    return replace(result, pairs=result.pairs[keep], state=state)


def match_points(result: MatchResult, camera: StereoCamera) -> np.ndarray:
    """The ``(m, 3)`` points, metres, of `result`'s matches in `camera`'s rectified left
    frame (NaN rows for a disparity that is not > 0); the pair must be rectified by `camera`.

    >>> import numpy as np
    >>> from ismb_lab.matching import match
    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> xyz = match_points(match(s.left, s.right), StereoCamera())
    >>> xyz.shape[1], bool(np.all(xyz[:, 2] > 0))
    (3, True)
    """
    if not isinstance(camera, StereoCamera):
        raise ParameterTypeError(message("camera", "match_points", "a StereoCamera", camera))
    left, right = result.left_match_xy, result.right_match_xy
    return camera.points_from_disparity(left, left[:, 0] - right[:, 0])


def for_camera(left, right, camera: StereoCamera) -> tuple:
    """The pair to match with `camera`: ``(left, right, how)``.

    Raw photos of `camera` are rectified with it; a pair that is already rectified (its
    robust matches' median row difference is not larger than after rectifying it again) is
    kept as it is.  ``how`` says which, with both figures.  Photos of another size than the
    camera's are refused.
    """
    from .rectify import _dy_figures, robust_matches

    left, right = camera.photos(left, right, "for_camera")
    rectified = camera.rectify(left, right)
    given = robust_matches(left, right)
    before = _dy_figures(given.left_xy, given.right_xy)["median_abs_dy_px"] if len(given) else math.inf
    after = rectified.median_abs_dy_px if rectified.inliers else math.inf
    if before < after:
        return left, right, (f"already rectified (median row difference of robust matches {before:.2f} px; "
                             f"{after:.2f} px if rectified again): matched as they are")
    return rectified.left, rectified.right, (f"raw photos, rectified with the rig (median row difference of "
                                             f"robust matches {before:.2f} px before, {after:.2f} px after)")
