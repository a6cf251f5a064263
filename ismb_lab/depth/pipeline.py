"""The toy-car depth demo of the thesis' §5.2.3, from four images to objects near -> far.

:func:`relative_depth` matches a background pair and a scene pair of the same view, the scene's
corners sought where it changed, and hands both to :func:`~ismb_lab.depth.objects.depth_from_matches`;
``docs/depth.md`` describes the method.  The demo's defaults are declared here once.

>>> from ismb_lab.scenes import lab_scene, toy_car_scene
>>> result = relative_depth(lab_scene(0), toy_car_scene(0))
>>> [round(o.depth_m, 2) for o in result.objects]    # the cars are at 0.885 and 1.183 m
[0.88, 1.16]
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, message
from .objects import DepthConfig, DepthResult, depth_from_matches
from ..images.features import Corners, detect_corners, resolve_roi
from ..images.io import StereoPair, load_pair
from ..matching.pipeline import MatchConfig, MatchResult, Prepared, auto_window, corner_problem, match, prepare, shift_roi
from ..network.methods import DEFAULT_METHOD, get_method
from ..network.params import Params
from .outlines import CHANGE_SIGMA, CHANGE_THRESHOLD, Silhouettes, changed_in_roi, silhouettes
from ..network.solvers import ANNEAL, get_solver

__all__ = ["DEPTH_MATCH_CONFIG", "DEPTH_PARAMS", "DEPTH_SOLVER", "REGION_CORNERS",
           "changed_regions", "changed_roi", "depth_match", "depth_pairs",
           "layout_match_config", "load_stereo", "relative_depth", "scene_match_config",
           "pair_silhouettes", "scene_prepared"]

#: The thesis' centre quarter with 40 to 60 corners, so that small toy cars get some.
DEPTH_MATCH_CONFIG = MatchConfig(n_min=40, n_max=60)


#: Method-III parameters fitted by the GA on the background pair images/lab and its answer key
#: alone (``scripts/fit_depth_params.py``).
DEPTH_PARAMS = Params(theta_c=1.945540697133651, theta_s=13.577571706866182,
                      lambda_c=7.143116184828514, lambda_s=6.966076587109354)

#: The method :data:`DEPTH_PARAMS` were fitted for.
DEPTH_METHOD = "III"

#: Corners per blob of change in the scene pair (:func:`scene_prepared`): at least, at most.
REGION_CORNERS = (20, 40)

#: How the demo solves the energy, a name in :data:`ismb_lab.network.solvers.SOLVERS`.
DEPTH_SOLVER = ANNEAL


def layout_match_config(layout, match_config=None) -> MatchConfig:
    """The demo's corner settings (default :data:`DEPTH_MATCH_CONFIG`) with the ROI and
    candidate-window shift of `layout` (an object with ``.roi`` and ``.shift``).

    >>> from ismb_lab.scenes import object_layout
    >>> c = layout_match_config(object_layout(0))
    >>> c.roi, c.shift, c.n_min
    ((40, 40, 240, 160), 11.0, 40)
    """
    own = "layout_match_config"
    match_config = _match_config(match_config, own)
    if not (hasattr(layout, "roi") and hasattr(layout, "shift")):
        raise ParameterTypeError(message("layout", own, "an object with .roi and .shift", layout))
    return replace(match_config, roi=tuple(int(v) for v in layout.roi),
                   shift=check_number(layout.shift, "layout.shift", own))


def changed_roi(background_left, scene_left, roi="center", *, threshold: float = CHANGE_THRESHOLD,
                sigma: float = CHANGE_SIGMA, margin: int = 4):
    """The box of `roi` where the scene's left image differs from the background's, or None.

    Changed: the difference, smoothed by a Gaussian of `sigma` px, exceeds `threshold` grey levels.
    The box grows by `margin` px (within `roi`) so that corners on an object's outline are inside.

    Parameters
    ----------
    background_left, scene_left : (h, w) array
        The left images of the background and of the scene, of one size.
    roi : str or (x, y, w, h) tuple, default "center"
        Where to look, as :func:`resolve_roi` takes it.
    threshold : float, default :data:`CHANGE_THRESHOLD`
        Grey levels of smoothed difference that count as a change.
    sigma : float, default :data:`CHANGE_SIGMA`
        Standard deviation (px) of the Gaussian smoothing the difference.
    margin : int, default 4
        Pixels the box grows by on every side, clipped to `roi`.

    Returns
    -------
    box : (x, y, w, h) tuple of int or None
        The changed box in image coordinates; None when nothing changed.

    Examples
    --------
    >>> import numpy as np
    >>> background = np.zeros((240, 320))
    >>> scene = background.copy()
    >>> scene[100:120, 150:190] = 200.0
    >>> changed_roi(background, scene)
    (144, 94, 52, 32)
    >>> changed_roi(background, background) is None
    True
    """
    changed, (x, y, w, h), margin = changed_in_roi(background_left, scene_left, roi, threshold, sigma, margin,
                                                   "changed_roi", "scene_left")
    rows, cols = np.nonzero(changed)
    if not len(rows):
        return None
    return _grown_box(x, y, w, h, cols.min(), rows.min(), cols.max(), rows.max(), margin)


def _grown_box(x, y, w, h, c0, r0, c1, r1, margin) -> tuple[int, int, int, int]:
    """The box of ROI columns c0..c1 and rows r0..r1, grown by `margin` and clipped to the ROI."""
    x0, y0 = max(c0 - margin, 0), max(r0 - margin, 0)
    x1, y1 = min(c1 + margin, w - 1), min(r1 + margin, h - 1)
    return int(x + x0), int(y + y0), int(x1 - x0 + 1), int(y1 - y0 + 1)


def scene_match_config(background, scene, match_config=None):
    """`match_config` (default :data:`DEPTH_MATCH_CONFIG`) with its ROI cut down to
    :func:`changed_roi` of two StereoPairs; `match_config` itself when nothing changed.

    >>> from ismb_lab.images.io import load_pair
    >>> from ismb_lab.scenes import lab_scene, toy_car_scene
    >>> bg, sc = (load_pair(s.left, s.right) for s in (lab_scene(0), toy_car_scene(0)))
    >>> scene_match_config(bg, sc).roi
    (97, 127, 134, 49)
    """
    own = "scene_match_config"
    match_config = _match_config(match_config, own, background)
    for name, value in (("background", background), ("scene", scene)):
        if not isinstance(value, StereoPair):
            raise ParameterTypeError(message(name, own, "a StereoPair", value))
    _check_same_size(background, scene, own)
    box = changed_roi(background.left, scene.left, match_config.roi)
    return match_config if box is None else replace(match_config, roi=box)


def changed_regions(background_image, scene_image, roi="center", *, threshold: float = CHANGE_THRESHOLD,
                    sigma: float = CHANGE_SIGMA, margin: int = 4, min_pixels: int = 20) -> list:
    """Boxes ``(x, y, w, h)``, left to right, of the blobs (8-neighbours, `min_pixels` or more) of
    the pixels :func:`changed_roi` counts as changed, each grown by `margin` within `roi`.

    Parameters
    ----------
    background_image, scene_image : (h, w) array
        The two images to compare, of one size.
    roi, threshold, sigma, margin
        As in :func:`changed_roi`.
    min_pixels : int, default 20
        Smallest blob (changed pixels) that counts.

    Returns
    -------
    boxes : list of (x, y, w, h) tuple
        One box per blob, sorted left to right.

    Examples
    --------
    >>> import numpy as np
    >>> background = np.zeros((240, 320))
    >>> scene = background.copy()
    >>> scene[100:120, 100:130] = scene[90:140, 180:200] = 200.0
    >>> changed_regions(background, scene)
    [(94, 94, 42, 32), (174, 84, 32, 62)]
    """
    from scipy.ndimage import find_objects, label

    own = "changed_regions"
    min_pixels = check_number(min_pixels, "min_pixels", own, low=1, integer=True)
    changed, (x, y, w, h), margin = changed_in_roi(background_image, scene_image, roi, threshold, sigma, margin,
                                                   own, "scene_image")
    blobs, n = label(changed, structure=np.ones((3, 3)))
    sizes = np.bincount(blobs.ravel(), minlength=n + 1)
    return sorted(_grown_box(x, y, w, h, cols.start, rows.start, cols.stop - 1, rows.stop - 1, margin)
                  for k, (rows, cols) in enumerate(find_objects(blobs), 1) if sizes[k] >= min_pixels)


def _region_corners(image, boxes, config: MatchConfig, n_min: int, n_max: int) -> Corners:
    """Corners of every box (the first with `config`'s numbers, the others `n_min`..`n_max`),
    merged row-major, duplicates once."""
    kw = dict(threshold=config.threshold, sigma=config.harris_sigma, k=config.harris_k,
              min_distance=config.min_distance)
    found = [detect_corners(image, roi=box, n_min=config.n_min if not n else n_min,
                            n_max=config.n_max if not n else n_max, **kw) for n, box in enumerate(boxes)]
    xy = np.vstack([c.xy for c in found]).reshape(-1, 2)
    response = np.concatenate([c.response for c in found])
    xy, first = np.unique(xy, axis=0, return_index=True)
    order = np.lexsort((xy[:, 0], xy[:, 1]))
    xs = [b[0] for b in boxes] + [b[0] + b[2] for b in boxes]
    ys = [b[1] for b in boxes] + [b[1] + b[3] for b in boxes]
    union = (min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys))
    notes = "; ".join(f"box {b}: {c.message}" for b, c in zip(boxes, found) if c.message)
    return Corners(xy[order], response[first][order], float(min(c.threshold for c in found)),
                   max(c.iterations for c in found), union, notes)


def scene_prepared(background, scene, match_config=None) -> Prepared:
    """Corners and energy ingredients of a scene pair, sought where it differs from the background.

    The changed box (:func:`scene_match_config`, the returned ``config.roi``) keeps its corners,
    and each blob of change (:func:`changed_regions`) of either image gets :data:`REGION_CORNERS`
    of its own, so that a textured poster cannot take a plain object's share.

    >>> from ismb_lab.images.io import load_pair
    >>> from ismb_lab.scenes import lab_scene, toy_car_scene
    >>> bg, sc = (load_pair(s.left, s.right) for s in (lab_scene(0), toy_car_scene(0)))
    >>> p = scene_prepared(bg, sc)
    >>> p.config.roi, len(p.left_corners) > 20
    ((97, 127, 134, 49), True)
    """
    base = DEPTH_MATCH_CONFIG if match_config is None else match_config
    if isinstance(base, MatchConfig) and base.shift == "auto":
        base = auto_window(background, base)
    config = scene_match_config(background, scene, base)
    if config is base:
        return prepare(scene, None, config)
    roi = resolve_roi(base.roi, scene.shape)
    left = changed_regions(background.left, scene.left, roi)
    right = changed_regions(background.right, scene.right, shift_roi(roi, base.shift, scene.shape))
    if not right:
        right = [shift_roi(box, base.shift, scene.shape) for box in left]
    # The changed box's own corners (the background removal needs some background), plus each blob's.
    left, right = [config.roi] + left, [shift_roi(config.roi, base.shift, scene.shape)] + right
    lo, hi = REGION_CORNERS
    lc = _region_corners(scene.left, left, config, lo, hi)
    rc = _region_corners(scene.right, right, config, lo, hi)
    return Prepared(scene, config, lc, rc, corner_problem(scene, lc.xy, rc.xy, config))


def _check_same_size(background, scene, owner: str):
    if background.shape != scene.shape:
        (h, w), (h2, w2) = background.shape, scene.shape
        raise ParameterError(message("scene", owner, f"images of the background's size {w}x{h} "
                                     "(width x height)", f"images of size {w2}x{h2}"))


def load_stereo(value, name: str, owner: str) -> StereoPair:
    """A pair as the demo takes it: a StereoPair, a pair folder (``left.png`` and ``right.png``),
    a ``(left, right)`` pair of images or paths, or an object with ``.left`` and ``.right``.

    Parameters
    ----------
    value : StereoPair, str, Path, (left, right) tuple or object with .left and .right
        The pair to load.
    name : str
        The parameter's name, for error messages.
    owner : str
        The calling function's name, for error messages.

    Returns
    -------
    pair : StereoPair
        The two images as grey float arrays of one size.

    Raises
    ------
    ParameterError
        A folder without ``left.png`` or ``right.png``.
    ParameterTypeError
        Any other kind of value.

    Examples
    --------
    >>> import numpy as np
    >>> load_stereo((np.zeros((40, 60)), np.zeros((40, 60))), "background", "demo").shape
    (40, 60)
    >>> load_stereo(42, "background", "demo")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterTypeError: The 'background' parameter of demo must be a pair folder, a (left, right) pair of images or paths, or an object with .left and .right. Got 42 instead.
    """
    if isinstance(value, StereoPair):
        return value
    if isinstance(value, (str, Path)):
        folder = Path(value)
        missing = [f for f in ("left.png", "right.png") if not (folder / f).is_file()]
        if missing:
            raise ParameterError(message(name, owner, "a pair folder holding left.png and right.png "
                                         f"(this one has no {missing[0]})", str(folder)))
        return load_pair(folder / "left.png", folder / "right.png")
    if hasattr(value, "left") and hasattr(value, "right"):
        return load_pair(value.left, value.right)
    if isinstance(value, (tuple, list)) and len(value) == 2:
        return load_pair(value[0], value[1])
    raise ParameterTypeError(message(name, owner, "a pair folder, a (left, right) pair of images or "
                                     "paths, or an object with .left and .right", value))


def depth_match(pair, *, background=None, method=DEFAULT_METHOD, params=None, match_config=None,
                seed: int = 0, solver=DEPTH_SOLVER, one_to_one: bool = False, **network) -> MatchResult:
    """Match one pair (any kind :func:`load_stereo` takes) as the depth demo does.

    With `background`, `pair` is a scene whose corners are sought where it changed
    (:func:`scene_prepared`).  The other arguments are :func:`relative_depth`'s.

    >>> from ismb_lab.scenes import lab_scene
    >>> m = depth_match(lab_scene(0, supersample=1))
    >>> m.solver, m.stop_rule, len(m.pairs) > 10
    ('anneal', 'sweep', True)
    >>> depth_match(lab_scene(0, supersample=1), solver="annealing")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'solver' parameter of depth_match must be one of 'network', 'anneal', 'exact', 'assign'. Got 'annealing' instead.
    """
    own = "depth_match"
    solver = get_solver(solver, own, **network)
    return _match(_prepared(pair, background, match_config, own), method, params, seed, solver, one_to_one)


def _match_config(match_config, own: str, background=None) -> MatchConfig:
    """`match_config` (default :data:`DEPTH_MATCH_CONFIG`), its ``shift="auto"`` measured on `background`."""
    match_config = DEPTH_MATCH_CONFIG if match_config is None else match_config
    if not isinstance(match_config, MatchConfig):
        raise ParameterTypeError(message("match_config", own, "a MatchConfig", match_config))
    if match_config.shift == "auto" and background is not None:
        match_config = auto_window(load_stereo(background, "background", own), match_config)
    return match_config


def _prepared(pair, background, match_config, own: str) -> Prepared:
    match_config = _match_config(match_config, own, background)
    pair = load_stereo(pair, "pair", own)
    if background is not None:
        return scene_prepared(load_stereo(background, "background", own), pair, match_config)
    return prepare(pair, None, match_config)


def _match(prepared: Prepared, method, params, seed, solver, one_to_one=False) -> MatchResult:
    if params is None and get_method(method).name == DEPTH_METHOD:
        params = DEPTH_PARAMS
    return match(method=method, params=params, seed=seed, solver=solver, prepared=prepared, one_to_one=one_to_one)


def depth_pairs(background, scene, match_config=None) -> tuple[Prepared, Prepared]:
    """The (background, scene) Prepared pairs of :func:`relative_depth`, to pass back as its
    `prepared` when only the method, parameters, seed or tolerances change."""
    return _depth_pairs(background, scene, match_config, "depth_pairs")


def _depth_pairs(background, scene, match_config, own: str) -> tuple[Prepared, Prepared]:
    bg, sc = load_stereo(background, "background", own), load_stereo(scene, "scene", own)
    if isinstance(match_config, MatchConfig) and match_config.shift == "auto":
        match_config = auto_window(bg, match_config)   # one window for both pairs, from the background
    _check_same_size(bg, sc, own)
    return _prepared(bg, None, match_config, own), _prepared(sc, bg, match_config, own)


def relative_depth(background, scene, *, method=DEFAULT_METHOD, params=None, match_config=None,
                   config: DepthConfig | None = None, seed: int = 0,
                   solver=DEPTH_SOLVER, prepared=None, silhouettes: Silhouettes | None = None,
                   one_to_one: bool = False, **network) -> DepthResult:
    """Match a background pair and a scene pair, and rank the scene's new objects by depth.

    Parameters
    ----------
    background, scene : StereoPair, folder or (left, right) pair
        Two pairs of the same view, of one size, as :func:`load_stereo` takes them.
    method : str, default ``DEFAULT_METHOD``
        The matching method, a registered method name.
    params : Params, optional
        Default :data:`DEPTH_PARAMS` for Method-III, the method's own for the others.
    match_config : MatchConfig, optional
        Corner and window settings; default :data:`DEPTH_MATCH_CONFIG`.
    config : DepthConfig, optional
        Depth settings (tolerances, grouping); default ``DepthConfig()``.
    seed : int, default 0
        Update-order seed of both runs.
    solver : str or Solver, default :data:`DEPTH_SOLVER`
        A name in :data:`ismb_lab.network.solvers.SOLVERS` or a configured solver.
    prepared : (Prepared, Prepared), optional
        :func:`depth_pairs` of these images and `match_config`, which are then not read again.
    silhouettes : Silhouettes, optional
        :func:`pair_silhouettes` of `prepared`, found once as well (``grouping="silhouettes"`` only).
    one_to_one : bool
        Keep at most one match per corner (:func:`ismb_lab.matching.pipeline.match`).
    **network
        The solver's options (e.g. ``stop_rule`` of the discrete network).

    Returns
    -------
    result : DepthResult
        The scene's objects ranked near to far, with ``scene_roi`` set to the scene's searched box.

    Raises
    ------
    ParameterError, ParameterTypeError
        Pairs of different sizes, or a bad `config`, `prepared` or `silhouettes`.

    Examples
    --------
    >>> import numpy as np
    >>> flat = np.zeros((60, 80))
    >>> relative_depth((flat, flat), (np.zeros((50, 80)), np.zeros((50, 80))))
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'scene' parameter of relative_depth must be images of the background's size 80x60 (width x height). Got 'images of size 80x50' instead.
    """
    own = "relative_depth"
    solver = get_solver(solver, own, **network)
    if prepared is None:
        prepared = _depth_pairs(background, scene, match_config, own)
    _check_prepared(prepared, own)
    config = DepthConfig() if config is None else config
    if not isinstance(config, DepthConfig):
        raise ParameterTypeError(message("config", own, "a DepthConfig", config))
    if silhouettes is not None:
        if not isinstance(silhouettes, Silhouettes):
            raise ParameterTypeError(message("silhouettes", own, "None or the Silhouettes that pair_silhouettes "
                                             "returns", silhouettes))
        if config.grouping != "silhouettes":
            raise ParameterError(message("silhouettes", own, "None when config.grouping is "
                                         f"{config.grouping!r} (the features alone group the objects)",
                                         "a Silhouettes"))
    results = [_match(p, method, params, seed, solver, one_to_one) for p in prepared]
    scene_roi = resolve_roi(prepared[1].config.roi, prepared[1].pair.shape)
    blobs = None
    if config.grouping == "silhouettes":
        blobs = pair_silhouettes(prepared, config) if silhouettes is None else silhouettes
    return replace(depth_from_matches(*results, config, blobs), scene_roi=scene_roi)


def _check_prepared(prepared, own: str) -> None:
    if not (isinstance(prepared, tuple) and len(prepared) == 2 and all(isinstance(p, Prepared) for p in prepared)):
        raise ParameterTypeError(message("prepared", own, "the (background, scene) pair of Prepared "
                                         "that depth_pairs returns", prepared))


def pair_silhouettes(prepared, config: DepthConfig | None = None) -> Silhouettes:
    """:func:`~ismb_lab.depth.outlines.silhouettes` of :func:`depth_pairs`, in the background's ROI
    at the whole-pixel shifts of the scene's candidate window.

    >>> from ismb_lab.scenes import lab_scene, toy_car_scene
    >>> blobs = pair_silhouettes(depth_pairs(lab_scene(0), toy_car_scene(0)))
    >>> blobs.disparity.tolist()        # the two cars, near one first (left to right)
    [33.0, 25.0]
    >>> pair_silhouettes(None)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterTypeError: The 'prepared' parameter of pair_silhouettes must be the (background, scene) pair of Prepared that depth_pairs returns. Got None instead.
    """
    own = "pair_silhouettes"
    _check_prepared(prepared, own)
    config = DepthConfig() if config is None else config
    if not isinstance(config, DepthConfig):
        raise ParameterTypeError(message("config", own, "None or a DepthConfig", config))
    (background, scene), window = (p.pair for p in prepared), prepared[1].config
    half = float(window.window_width) / 2
    shifts = range(int(np.floor(window.shift - half)), int(np.ceil(window.shift + half)) + 1)
    return silhouettes(background, scene, prepared[0].config.roi, shifts=shifts, config=config.outline)
