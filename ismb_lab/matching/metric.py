"""Matches in metres: match a pair rectified by a calibrated camera with what the camera knows.

A match's corners are refined to sub-pixel and lie on one row to within :func:`row_tolerance`;
the disparity range is measured on robust matches along their rows (:func:`auto_window` with
``rows_px``); only mutual-best matches are kept (:func:`mutual_best`); :func:`match_points`
gives them in metres in the rectified left camera's frame.
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, message
from ..cameras.camera import StereoCamera
from .pipeline import MatchConfig, MatchResult, Prepared, auto_window, corner_problem, match, prepare

__all__ = ["IMPROVES", "THESIS_SIZE", "photo_config", "fit_rows_px", "for_camera", "match_points",
           "rectify_for_camera", "match_with_camera", "mutual_best", "prepare_for_camera", "rig_config",
           "row_tolerance", "subpixel"]

#: cv2.cornerSubPix stops when a step is under 0.001 px or after 40 steps.
_SUBPIXEL_STOP = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 40, 0.001)


def row_tolerance(camera: StereoCamera, subpixel: bool = False) -> float:
    """Largest row difference, px, of a true match in `camera`'s rectified pair: ``2 rms`` for
    sub-pixel corners, ``1 + 2 rms`` for whole-pixel ones, ``1`` for an uncalibrated camera.

    Parameters
    ----------
    camera : StereoCamera
        The calibrated camera that rectified the pair.
    subpixel : bool, default False
        Whether the corners are sub-pixel.

    Returns
    -------
    rows_px : float
        The tolerance, pixels.

    Examples
    --------
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
    """`config` with the window `camera` gives: :func:`row_tolerance` rows up and down, and, with
    ``shift="auto"``, the disparity range measured on `pair` along those rows.

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


#: The thesis' image, width x height, which ``MatchConfig``'s 20-30 corners are for.
THESIS_SIZE = (320, 240)


def photo_config(camera: StereoCamera, config: MatchConfig | None = None, *, scale: float = 1.0,
                 most: int | None = None) -> MatchConfig:
    """`config` with ``n_min`` and ``n_max`` scaled by `camera`'s image area over
    :data:`THESIS_SIZE`'s, times `scale`; with `most`, ``n_max`` is at most that and ``n_min``
    keeps its share of it.

    Parameters
    ----------
    camera : StereoCamera
        The camera whose image size counts.
    config : MatchConfig, optional
        The settings to scale; default ``MatchConfig()``.
    scale : float, default 1.0
        Extra factor (> 0).
    most : int, optional
        Largest ``n_max``.

    Returns
    -------
    config : MatchConfig
        `config` with the scaled corner counts.

    Raises
    ------
    ParameterTypeError
        `config` or `camera` of the wrong type.

    Examples
    --------
    >>> c = photo_config(StereoCamera(size=(640, 480)))
    >>> c.n_min, c.n_max
    (80, 120)
    >>> c = photo_config(StereoCamera(size=(4000, 3000)), most=500)
    >>> c.n_min, c.n_max
    (333, 500)
    """
    config = MatchConfig() if config is None else config
    if not isinstance(config, MatchConfig):
        raise ParameterTypeError(message("config", "photo_config", "a MatchConfig", config))
    if not isinstance(camera, StereoCamera):
        raise ParameterTypeError(message("camera", "photo_config", "a StereoCamera", camera))
    scale = check_number(scale, "scale", "photo_config", low=0, low_open=True)
    area = camera.size[0] * camera.size[1] / (THESIS_SIZE[0] * THESIS_SIZE[1]) * scale
    n_min, n_max = config.n_min * area, config.n_max * area
    if most is not None:
        most = check_number(most, "most", "photo_config", low=1, integer=True)
        if n_max > most:
            n_min, n_max = n_min * most / n_max, most
    return replace(config, n_min=max(1, round(n_min)), n_max=max(1, round(n_max)))


def subpixel(image, xy, half: int) -> np.ndarray:
    """Corners `xy` of `image` refined to sub-pixel (``cv2.cornerSubPix``, a ``2 half + 1``
    window), kept inside the image.

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
    """`pair` (rectified by `camera`) prepared in `camera`'s window: ``M`` compares whole-pixel
    patches, the geometry uses the corners' sub-pixel positions.

    >>> from ismb_lab.images.io import load_pair
    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> p = prepare_for_camera(load_pair(s.left, s.right), MatchConfig(), StereoCamera())
    >>> p.config.window_height, p.problem.n_neurons > 0
    (2.0, True)
    """
    if not isinstance(camera, StereoCamera):
        raise ParameterTypeError(message("camera", "prepare_for_camera", "a StereoCamera", camera))
    prepared = prepare(pair, None, rig_config(camera, config, pair, subpixel=True))
    pair, half = prepared.pair, prepared.config.patch_size // 2
    lxy = subpixel(pair.left, prepared.left_corners.xy, half)
    rxy = subpixel(pair.right, prepared.right_corners.xy, half)
    problem = corner_problem(pair, lxy, rxy, prepared.config, prepared.problem.dissimilarity)
    return replace(prepared, problem=problem)


def match_with_camera(pair, config: MatchConfig, camera: StereoCamera, **options) -> tuple:
    """``ismb-lab match --rig``: :func:`prepare_for_camera`, :func:`match` with `options`, then
    :func:`mutual_best`.  Returns ``(prepared, found, kept)``.

    >>> from ismb_lab.images.io import load_pair
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
    """`result` with only the matches whose corners are each other's most similar candidate.

    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> p = prepare(s.left, s.right)
    >>> r = match(prepared=p)
    >>> 0 < len(mutual_best(p, r).pairs) <= len(r.pairs)
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
    """The ``(m, 3)`` points, metres, of `result`'s matches in the rectified left frame of
    `camera`, which rectified the pair (NaN rows where the disparity is not > 0).

    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> xyz = match_points(match(s.left, s.right), StereoCamera())
    >>> xyz.shape[1], bool(np.all(xyz[:, 2] > 0))
    (3, True)
    """
    if not isinstance(camera, StereoCamera):
        raise ParameterTypeError(message("camera", "match_points", "a StereoCamera", camera))
    return camera.points_from_disparity(result.left_match_xy, result.horizontal_disparity)


#: The rig's rectification improves a pair's rows when it lowers their median difference by
#: more than this share; otherwise a pair whose rows agree is matched as it is given.
IMPROVES = 0.25
#: What each EXIF orientation does to the stored pixels.
_TURNS = {2: "mirrors it", 3: "turns it 180°", 4: "flips it upside down", 5: "transposes it",
          6: "turns it 90° clockwise", 7: "transposes it the other way", 8: "turns it 90° anticlockwise"}


#: The least share of a pair's robust matches on their rows (within :func:`fit_rows_px`) for a rig to fit it.
FIT_SHARE = 0.25


def fit_rows_px(camera: StereoCamera) -> float:
    """Largest median row difference, px, of the robust matches of a pair `camera` fits:
    :func:`~ismb_lab.images.rectify.row_spread_px`, or the sub-pixel :func:`row_tolerance` if larger.

    >>> fit_rows_px(StereoCamera(size=(640, 480))), fit_rows_px(StereoCamera(size=(640, 480), rms=0.8))
    (1.0, 1.6)
    """
    from ..images.rectify import row_spread_px

    return max(row_spread_px(camera.size[::-1]), row_tolerance(camera, subpixel=True))


def _misfit(matches, limit: float) -> str:
    """Why a pair with robust `matches` does not fit a rig (a few words), or "" (also for < 8)."""
    from ..images.rectify import negative_share

    if len(matches) < 8:
        return ""
    dy = matches.abs_dy
    # a share, not the median: on a chessboard half the robust matches may pair neighbouring squares
    within = float(np.mean(dy <= limit))
    if within < FIT_SHARE:
        return f"rows {float(np.median(dy)):.1f} px apart at the median, {within:.0%} within {limit:g} px"
    share, n = negative_share(matches, 2 * limit)
    if n >= 8 and share > 0.5:
        return f"{share:.0%} of {n} matches on their rows at a negative disparity"
    return ""


def _fits(left, right, camera: StereoCamera, limit: float) -> bool:
    """Whether a pair fits `camera`, as given or rectified with it."""
    from ..images.rectify import robust_matches

    if not _misfit(robust_matches(left, right), limit):
        return True
    rectified = camera.rectify(left, right)
    return not _misfit(robust_matches(rectified.left, rectified.right), limit)


def _photos(left, right, camera: StereoCamera, owner: str) -> tuple:
    """``camera.photos``, refusing a photo its EXIF tag turned to another size than the rig's."""
    from ..images.rectify import load_photo, photo_orientation

    for name, source in (("left", left), ("right", right)):
        turn = photo_orientation(source)
        if turn in (5, 6, 7, 8):
            image = load_photo(source, name, owner)
            if (image.shape[0], image.shape[1]) == tuple(camera.size) != (image.shape[1], image.shape[0]):
                raise ParameterError(message(
                    name, owner, f"a {camera.size[0]}x{camera.size[1]} photo, the size the rig was calibrated at: "
                    "remove its EXIF orientation tag (save it again without EXIF), or calibrate with photos tagged "
                    "the same way", _Shown(f"{image.shape[1]}x{image.shape[0]}: the EXIF orientation tag ({turn}) "
                                           f"{_TURNS[turn]}, stored {camera.size[0]}x{camera.size[1]}")))
    return camera.photos(left, right, owner)


class _Shown(str):
    """A value shown in a message as it is, without quotes."""

    def __repr__(self) -> str:
        return str(self)


def _refusal(sources, camera: StereoCamera, problem: str, limit: float, owner: str) -> ParameterError:
    """The refusal of a pair `camera` does not fit, naming the likely cause: the files swapped,
    an EXIF tag that does not match the pixels, or a rig that is not this pair's."""
    from ..images.rectify import load_photo, photo_orientation

    names = ("left", "right")
    turns = dict(zip(names, (photo_orientation(source) for source in sources)))
    tagged = [name for name in names if turns[name] != 1]
    fits_stored = False
    if tagged:     # a tag first: a pair turned by 180 degrees also looks like a swapped one
        stored = [load_photo(source, name, owner, upright=False) for name, source in zip(names, sources)]
        fits_stored = stored[0].shape == stored[1].shape == tuple(camera.size[::-1]) and any(
            _fits(a, b, camera, limit) for a, b in ((stored[0], stored[1]), (stored[1], stored[0])))

    def exif(fits: bool) -> ParameterError:
        name = tagged[0]
        return ParameterError(message(
            name, owner, "a photo whose EXIF orientation tag matches its pixels"
            + (" (with the tag ignored, the rig fits the pair)" if fits else "")
            + ": remove the tag (save the photo again without EXIF)",
            _Shown(f"a tag ({turns[name]}) that {_TURNS[turns[name]]}, and {problem}")))

    if fits_stored:
        return exif(True)
    upright = [load_photo(source, name, owner) for name, source in zip(names, sources)]
    if _fits(upright[1], upright[0], camera, limit):
        return ParameterError(message("left", owner, "the left camera's photo, given first: swap the two files "
                                      "(swapped, the rig fits them)", _Shown(f"the right camera's ({problem})")))
    if tagged:
        return exif(False)
    return ParameterError(message(
        "right", owner, f"a photo the rig fits (rows within {limit:.1f} px of the left one's once rectified): photos "
        "neither turned nor cropped, the cameras not moved since calibrating; else calibrate again with boards "
        "taken in this setup", _Shown(f"a pair with {problem}, as given and rectified")))


def rectify_for_camera(left, right, camera: StereoCamera, owner: str = "rectify_for_camera"):
    """`left` and `right` rectified with `camera`.

    Raises
    ------
    ParameterError
        As :func:`for_camera`, and for a pair that is rectified already.
    """
    from ..images.rectify import Correspondences, robust_matches

    sources = (left, right)
    left, right = _photos(left, right, camera, owner)
    limit = fit_rows_px(camera)
    rectified = camera.rectify(left, right)
    problem = _misfit(Correspondences(rectified.left_xy, rectified.right_xy), limit)
    if problem and not _misfit(robust_matches(left, right), limit):
        raise ParameterError(message("left", owner, "a raw photo of the rig: this pair is already rectified, "
                                     "use it as it is", _Shown(f"a rectified pair (rectified again: {problem})")))
    if problem:
        raise _refusal(sources, camera, problem, limit, owner)
    return rectified


def for_camera(left, right, camera: StereoCamera) -> tuple:
    """The pair to match with `camera`, ``(left, right, how)``: as given when its robust matches'
    rows agree (:func:`fit_rows_px`) and rectifying would not lower their median difference by
    more than :data:`IMPROVES`, else rectified; either way its rows must agree and most
    disparities be positive.

    Raises
    ------
    ParameterError
        Naming the likely cause and its fix (photos of another size, files swapped, an EXIF tag
        that does not match the pixels, photos the rig was not calibrated for).
    """
    from ..images.rectify import Correspondences, robust_matches

    owner = "for_camera"
    sources = (left, right)
    left, right = _photos(left, right, camera, owner)
    limit = fit_rows_px(camera)
    given = robust_matches(left, right)
    rectified = camera.rectify(left, right)
    median = lambda m: float(np.median(m.abs_dy)) if len(m) >= 8 else math.inf
    again = Correspondences(rectified.left_xy, rectified.right_xy)
    before, after = median(given), median(again)
    as_given = before <= limit and not after < (1 - IMPROVES) * before
    problem = _misfit(given if as_given else again, limit)
    if not as_given and len(again) < 8 <= len(given):
        problem = f"only {len(again)} of its {len(given)} robust matches remain once rectified with the rig"
    if problem:
        raise _refusal(sources, camera, problem, limit, owner)
    figures = lambda v: f"{v:.2f} px" if math.isfinite(v) else "too few robust matches to tell"
    if as_given:
        return left, right, (f"already rectified: matched as given (median row difference of robust matches "
                             f"{figures(before)} as given, {figures(after)} after the rig's rectification)")
    return rectified.left, rectified.right, (f"raw photos, rectified with the rig (median row difference of "
                                             f"robust matches {figures(before)} before, {figures(after)} after)")
