"""The toy-car depth demo of the thesis' §5.2.3, from four images to objects near -> far.

``relative_depth(background, scene)`` matches a background pair and a scene pair of the
same view (:func:`depth_match`) and hands both to
:func:`ismb_lab.depth.objects.depth_from_matches`, which removes the background and ranks the
objects left.

*Corners where something changed.*  The corner detector keeps the strongest corners
of its ROI, and textured posters have stronger corners than a small toy car, so with
the thesis' ROI a far car can end with one corner or none.  The demo knows the
background, so it looks for the scene pair's corners only in the bounding box of the
ROI's pixels whose smoothed left-image difference from the background exceeds
:data:`~ismb_lab.depth.outlines.CHANGE_THRESHOLD` grey levels, plus a margin (:func:`changed_roi`).  The box still holds some background, so
the background removal has work to do; where nothing changed, or everything did
(another day's lighting), it is the whole ROI.  The background pair keeps the ROI.
The figures behind this choice are in ``benchmarks/README.md``.

*Objects by their outlines* (beyond the thesis).  The same differences, in the left and
in the right image, are the objects' outlines: :func:`ismb_lab.depth.outlines.silhouettes`
gives each left blob of change the shift that lays it on the right image's blobs, and
:func:`ismb_lab.depth.objects.depth_from_matches` makes each well-fitting blob one object at the
disparity its agreeing features give (``DepthConfig.grouping``; ``"features"`` is the
thesis' grouping).  ``docs/depth.md`` describes the method as it runs;
``scripts/depth_layouts.py`` scores it on random object layouts.

The demo's defaults, :data:`DEPTH_PARAMS`, :data:`DEPTH_MATCH_CONFIG` and
:data:`DEPTH_SOLVER`, are declared here once; the command line and the widget read them.

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

#: Corners of the depth demo: the thesis' centre quarter, but 40 to 60 corners instead of
#: 20 to 30, so that the small toy cars get some next to the posters' many.
DEPTH_MATCH_CONFIG = MatchConfig(n_min=40, n_max=60)


#: Method-III parameters of the depth demo, fitted by the GA on the background pair
#: images/lab and its answer key only, with :data:`DEPTH_MATCH_CONFIG`'s corners
#: (``python scripts/fit_depth_params.py``: GA seed 0, 500 generations, each chromosome
#: scored over update orders 0-4).  The thesis' values were fitted to its webcams and
#: give many extra matches on rendered scenes.
DEPTH_PARAMS = Params(theta_c=1.945540697133651, theta_s=13.577571706866182,
                      lambda_c=7.143116184828514, lambda_s=6.966076587109354)

#: The method :data:`DEPTH_PARAMS` were fitted for.
DEPTH_METHOD = "III"

#: Corners per blob of change in the scene pair (:func:`scene_prepared`): at least, at most.
REGION_CORNERS = (20, 40)

#: How the demo solves the energy, a name in :data:`ismb_lab.network.solvers.SOLVERS`: mean-field
#: annealing ranked the cars right on more development layouts than the discrete network
#: (the figures are in ``benchmarks/README.md``).
DEPTH_SOLVER = ANNEAL


def layout_match_config(layout, match_config=None) -> MatchConfig:
    """The demo's corner settings with a layout's ROI and candidate-window shift.

    Parameters
    ----------
    layout : object with ``.roi`` and ``.shift``
        E.g. a :class:`ismb_lab.scenes.Layout`, which knows its disparity range.
    match_config : MatchConfig, optional
        Default :data:`DEPTH_MATCH_CONFIG`.

    Returns
    -------
    MatchConfig
        As ``ismb-lab depth --roi X,Y,W,H --shift S`` would use.

    Examples
    --------
    >>> from ismb_lab.scenes import object_layout
    >>> c = layout_match_config(object_layout(0))
    >>> c.roi, c.shift, c.n_min
    ((40, 40, 240, 160), 11.0, 40)
    """
    own = "layout_match_config"
    match_config = DEPTH_MATCH_CONFIG if match_config is None else match_config
    if not isinstance(match_config, MatchConfig):
        raise ParameterTypeError(message("match_config", own, "a MatchConfig", match_config))
    if not (hasattr(layout, "roi") and hasattr(layout, "shift")):
        raise ParameterTypeError(message("layout", own, "an object with .roi and .shift", layout))
    return replace(match_config, roi=tuple(int(v) for v in layout.roi),
                   shift=check_number(layout.shift, "layout.shift", own))


def changed_roi(background_left, scene_left, roi="center", *, threshold: float = CHANGE_THRESHOLD,
                sigma: float = CHANGE_SIGMA, margin: int = 4):
    """The box of `roi` where the scene's left image differs from the background's.

    Parameters
    ----------
    background_left, scene_left : (H, W) array_like
        Grey left images of the background and of the scene, one size.
    roi : str or (x, y, w, h)
        Where to look, as :attr:`ismb_lab.matching.pipeline.MatchConfig.roi`.
    threshold : float
        Grey levels (0-255) by which the Gaussian-smoothed absolute difference must
        exceed to count as a change; camera noise alone stays below it.
    sigma : float
        Standard deviation of the Gaussian smoothing, pixels.
    margin : int
        Pixels added on every side of the changed pixels' bounding box (clipped
        to `roi`), so that corners on an object's outline are inside.

    Returns
    -------
    box : (x, y, w, h) or None
        None when no pixel of `roi` changed.

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
    """The demo's corner settings for a scene pair: `match_config` with its ROI cut
    down to :func:`changed_roi`.

    Parameters
    ----------
    background, scene : StereoPair
        The two pairs of the same view (:func:`ismb_lab.images.io.load_pair`).
    match_config : MatchConfig, optional
        Default :data:`DEPTH_MATCH_CONFIG`.

    Returns
    -------
    MatchConfig
        `match_config` itself when nothing in its ROI changed.

    Examples
    --------
    >>> from ismb_lab.images.io import load_pair
    >>> from ismb_lab.scenes import lab_scene, toy_car_scene
    >>> bg, sc = (load_pair(s.left, s.right) for s in (lab_scene(0), toy_car_scene(0)))
    >>> scene_match_config(bg, sc).roi
    (97, 127, 134, 49)
    """
    own = "scene_match_config"
    match_config = DEPTH_MATCH_CONFIG if match_config is None else match_config
    if not isinstance(match_config, MatchConfig):
        raise ParameterTypeError(message("match_config", own, "a MatchConfig", match_config))
    if match_config.shift == "auto" and background is not None:
        match_config = auto_window(load_stereo(background, "background", own), match_config)
    for name, value in (("background", background), ("scene", scene)):
        if not isinstance(value, StereoPair):
            raise ParameterTypeError(message(name, own, "a StereoPair", value))
    _check_same_size(background, scene, own)
    box = changed_roi(background.left, scene.left, match_config.roi)
    return match_config if box is None else replace(match_config, roi=box)


def changed_regions(background_image, scene_image, roi="center", *, threshold: float = CHANGE_THRESHOLD,
                    sigma: float = CHANGE_SIGMA, margin: int = 4, min_pixels: int = 20) -> list:
    """Boxes of the separate blobs of `roi` where `scene_image` differs from `background_image`.

    The pixels that :func:`changed_roi` counts as changed, split into connected
    blobs (8-neighbours); each blob's bounding box grows by `margin` (clipped to
    `roi`).  Blobs of fewer than `min_pixels` pixels are camera noise and skipped.

    Returns
    -------
    list of (x, y, w, h)
        Left to right (by ``x``); empty when nothing changed.

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
    """Corners of every box (the first with ``config``'s numbers, each other its own
    `n_min`..`n_max`), merged row-major, duplicates once."""
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

    The changed box (:func:`scene_match_config`) keeps its corners, and each blob of
    change (:func:`changed_regions`) of the left images gets corners of its own, as
    does each blob of the right images (in the right ROI, ``shift``
    pixels left): a textured poster beside a plain object no longer takes the
    object's share of the corner budget, and a striped object does not take its
    neighbour's.  Each blob keeps :data:`REGION_CORNERS` corners.  Where nothing
    changed this is :func:`ismb_lab.matching.pipeline.prepare` with ``match_config``.

    Parameters
    ----------
    background, scene : StereoPair
    match_config : MatchConfig, optional
        Default :data:`DEPTH_MATCH_CONFIG`.

    Returns
    -------
    Prepared
        Its ``config.roi`` is :func:`scene_match_config`'s box.

    Examples
    --------
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
    # The changed box's own corners, as before (the background removal needs some
    # background), plus each blob's.
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
    """Match one stereo pair as the depth demo does.

    Parameters
    ----------
    pair : StereoPair, (left, right) or object with ``.left`` and ``.right``
        Images (arrays or paths); a :class:`~ismb_lab.scenes.Scene` works too.
    background : same kinds as `pair`, optional
        The background pair of the same view.  When given, `pair` is a scene and its
        corners are sought only in :func:`changed_roi` of the ROI (the whole ROI
        where nothing changed).
    method, params, match_config, seed
        As in :func:`relative_depth` (``params`` default: :data:`DEPTH_PARAMS` for
        Method-III).
    solver : str or Solver
        A name in :data:`ismb_lab.network.solvers.SOLVERS` or a configured solver (default :data:`DEPTH_SOLVER`).
    one_to_one : bool
        Keep at most one match per corner (:func:`ismb_lab.matching.pipeline.match`).
    **network
        Options of the solver (e.g. ``stop_rule``, ``rule`` or ``kernel`` of the discrete network)
        (:func:`ismb_lab.matching.pipeline.match`).

    Returns
    -------
    MatchResult

    Examples
    --------
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


def _prepared(pair, background, match_config, own: str) -> Prepared:
    """:func:`depth_match`'s corners and energy ingredients of `pair`."""
    match_config = DEPTH_MATCH_CONFIG if match_config is None else match_config
    if not isinstance(match_config, MatchConfig):
        raise ParameterTypeError(message("match_config", own, "a MatchConfig", match_config))
    if match_config.shift == "auto" and background is not None:
        match_config = auto_window(load_stereo(background, "background", own), match_config)
    pair = load_stereo(pair, "pair", own)
    if background is not None:
        return scene_prepared(load_stereo(background, "background", own), pair, match_config)
    return prepare(pair, None, match_config)


def _match(prepared: Prepared, method, params, seed, solver, one_to_one=False) -> MatchResult:
    if params is None and get_method(method).name == DEPTH_METHOD:
        params = DEPTH_PARAMS
    return match(method=method, params=params, seed=seed, solver=solver, prepared=prepared, one_to_one=one_to_one)


def depth_pairs(background, scene, match_config=None) -> tuple[Prepared, Prepared]:
    """The background and scene pairs prepared as :func:`relative_depth` prepares them.

    Corners, ``M`` and the geometry do not depend on the method, the parameters, the
    seed or the tolerances: pass the result as ``relative_depth(..., prepared=...)``
    to change those without preparing the pairs again.

    Parameters
    ----------
    background, scene, match_config
        As in :func:`relative_depth`.

    Returns
    -------
    (Prepared, Prepared)
        The background pair's and the scene pair's.
    """
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
    background, scene : pair folder, (left, right) or object with ``.left`` and ``.right``
        The two stereo pairs of the same view (:func:`load_stereo`; a
        :class:`~ismb_lab.scenes.Scene` works too).  All four images must have one size.
    method : str
        Energy recipe, see :mod:`ismb_lab.network.methods` (the thesis uses Method-III).
    params : Params, optional
        Energy parameters (default: :data:`DEPTH_PARAMS` for Method-III, fitted on the
        background pair images/lab; the method's own defaults for the others).
    match_config : MatchConfig, optional
        Corners, ROI and candidate window (default: :data:`DEPTH_MATCH_CONFIG`, the
        thesis' settings with 40 to 60 corners).  The scene pair's corners are
        sought in the part of the ROI that changed (:func:`changed_roi`).
    config : DepthConfig, optional
        Tolerances and calibration.
    seed : int
        Update-order seed of both runs.
    solver : str or Solver
        How the energy is solved (see :func:`depth_match`).
    prepared : (Prepared, Prepared), optional
        Both pairs already prepared by :func:`depth_pairs` with these images and
        `match_config` (which are then not read again): a change of method, parameters,
        seed or tolerances need not find the corners again.
    silhouettes : Silhouettes, optional
        :func:`pair_silhouettes` of these `prepared` pairs, found once as well (with
        ``config.grouping`` ``"silhouettes"`` only).
    one_to_one : bool
        Keep at most one match per corner in both pairs (:func:`ismb_lab.matching.pipeline.match`).
    **network
        The solver's options, as in :func:`depth_match`.

    Returns
    -------
    DepthResult

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
    """:func:`~ismb_lab.depth.outlines.silhouettes` of two pairs prepared by :func:`depth_pairs`.

    The blobs are sought in the background's ROI, at the whole-pixel shifts of the scene's
    candidate window (the disparities the matcher may find), as ``config.outline`` says.

    Examples
    --------
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
