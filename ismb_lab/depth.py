"""Which object is nearer: depth from a background pair and a scene pair (thesis §5.2.3).

The thesis first matches a background pair (a box in front of a wall, Fig. 5.11/5.12),
then a pair of the same view with two toy cars added (Fig. 5.13), deletes the scene's
feature points that belong to the background, and compares disparities: the larger
the disparity, the nearer the object (Fig. 5.14).  This module does exactly that, and
with the rig's calibration also gives metric depth ``Z = f B / d``.

Public API
----------
``relative_depth(background, scene, *, method="III", params=None, match_config=None,
config=None, seed=0, solver=DEPTH_SOLVER) -> DepthResult``
    Match both pairs (:func:`depth_match`) and find the objects.
``depth_match(pair, *, background=None, method="III", params=None, match_config=None,
seed=0, solver=DEPTH_SOLVER) -> MatchResult``
    One pair matched as the demo matches it; with `background`, the scene pair's
    corners are sought where the scene differs from the background.
``changed_roi(background_left, scene_left, roi="center", ...) -> (x, y, w, h) or None``
    The box of the ROI where the scene's left image differs from the background's.
``scene_match_config(background, scene, match_config=None) -> MatchConfig``
    The corner settings :func:`depth_match` uses for a scene pair.
``depth_from_matches(background, scene, config=None) -> DepthResult``
    The same from two :class:`~ismb_lab.matching.MatchResult` objects already made.
``metric_depth(disparity, focal_px, baseline_m, error_px=0.5) -> Depth``
    ``Z = f B / d`` with the depth range of ``d +- error_px``.
``DEPTH_PARAMS``, ``DEPTH_MATCH_CONFIG``, ``DEPTH_SOLVER``
    The demo's defaults: Method-III parameters fitted by the GA on the background
    pair images/lab and its answer key alone (``scripts/fit_depth_params.py``), and
    the thesis' corner settings with 40 to 60 corners so that the small cars get
    some.  The thesis' parameters, fitted to its webcams, give many extra matches on
    rendered scenes (a spurious object on each car of the committed pair).  The
    energy is solved by mean-field annealing (:mod:`ismb_lab.annealing`): the
    discrete network's greedy descent from "all on" settles, on a few layouts, with
    the far car's corners matched to the wrong window of its repeated texture or not
    at all; annealing reaches a deeper minimum with the same parameters.
``DepthConfig``
    The tolerances and the calibration (frozen, validated).
``DepthResult``, ``DepthObject``, ``Depth``
    Frozen result records; ``DepthResult.objects`` is ranked near -> far and
    ``DepthResult.to_dict()`` is the JSON of ``ismb-lab depth --json``.

How it works
------------
0. *Corners where something changed.*  The corner detector keeps the strongest
   corners of its ROI, and textured posters have stronger corners than a small toy
   car, so with the thesis' ROI a far car can end with one corner or none.  The demo
   knows the background, so it looks for the scene pair's corners only in the
   bounding box of the ROI's pixels whose smoothed left-image difference from the
   background exceeds 8 grey levels, plus a margin (:func:`changed_roi`).  The box
   still holds some background, so step 1 has work to do; where nothing changed, or
   everything did (another day's lighting), it is the whole ROI.  The background
   pair keeps the ROI.  With the thesis' ROI the left car
   failed to rank first on 1 of the 40 development layouts (``cars=100..139``), and
   on 6 of them rendered at the committed images' supersampling; with the box, on
   none of either.
1. *Background removal.*  A scene feature belongs to the background when one of its
   matches lies within ``position_tol_px`` of a background match (left image) with a
   horizontal disparity within ``disparity_tol_px`` of it.  Its matches are dropped.
2. *In front of the background.*  An object put into the scene stands in front of
   what was there, so (with ``in_front``) a scene match is dropped unless its
   disparity exceeds the local background disparity (the smallest disparity of the
   background matches within ``local_px``, i.e. the farthest surface there; the
   smallest of all where none is that close) by more than ``disparity_tol_px``.
   This drops wrong matches and background corners that the background pair did not
   match right.  The smallest, not the median, because whole groups of background
   corners can be matched wrongly, at too large a disparity.
3. *Objects.*  The remaining features are grouped by single linkage: two features
   are linked when they lie within ``link_px`` of each other (left image) and have
   matches whose disparities differ by at most ``link_disparity_px``; an object is a
   connected component of these links (:func:`scipy.sparse.csgraph.connected_components`),
   so a car next to a box in the image but nearer stays apart from it.
4. *An object's disparity.*  The network may give a feature several matches.  The
   object's disparity is the disparity with the most matches of the object within
   ``consensus_px`` (a fronto-parallel object has one disparity; ties go to the
   band with the smallest spread); its
   ``mean_disparity`` is the mean of those consensus matches.  Objects with fewer than
   ``min_features`` features among them are dropped as noise.
5. *Depth.*  Objects are ranked by mean disparity, largest (nearest) first.  Metric
   depth is ``f B / d``; quantised disparities are off by up to ``quantisation_px``,
   so the depth lies in ``[f B / (d + q), f B / (d - q)]`` (infinite far end when
   ``d <= q``).  Zero disparity is "at infinity", negative disparity "invalid":
   no depth, never a division by zero.

Disparities are horizontal, ``x_left - x_right`` (:mod:`ismb_lab.coords`), the
quantity that ``f B / Z`` predicts for a parallel rig even when the right image is
shifted vertically.

>>> from ismb_lab.scenes import lab_scene, toy_car_scene
>>> result = relative_depth(lab_scene(0), toy_car_scene(0))
>>> [round(o.depth_m, 2) for o in result.objects]    # the cars are at 0.885 and 1.183 m
[0.88, 1.16]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_choice, check_number, message

__all__ = ["DEPTH_MATCH_CONFIG", "DEPTH_PARAMS", "DEPTH_SOLVER", "DepthConfig", "Depth",
           "DepthObject", "DepthResult", "changed_roi", "metric_depth", "depth_from_matches",
           "depth_match", "relative_depth", "scene_match_config"]


def _match_config():
    from .matching import MatchConfig
    return MatchConfig(n_min=40, n_max=60)


#: Corners of the depth demo: the thesis' centre quarter, but 40 to 60 corners instead of
#: 20 to 30, so that the small toy cars get some next to the posters' many.
DEPTH_MATCH_CONFIG = _match_config()


def _params():
    from .methods import Params
    return Params(theta_c=1.945540697133651, theta_s=13.577571706866182,
                  lambda_c=7.143116184828514, lambda_s=6.966076587109354)


#: Method-III parameters of the depth demo, fitted by the GA on the background pair
#: images/lab and its answer key only, with :data:`DEPTH_MATCH_CONFIG`'s corners
#: (``python scripts/fit_depth_params.py``: GA seed 0, 500 generations, each chromosome
#: scored over update orders 0-4).  The thesis' values were fitted to its webcams and
#: give many extra matches on rendered scenes.
DEPTH_PARAMS = _params()

#: How the demo solves the energy: ``"anneal"`` (mean-field annealing, then the discrete
#: network from the rounded state) or ``"network"`` (the thesis' discrete network alone).
#: Measured with :data:`DEPTH_PARAMS` on the development layouts ``cars=100..139``, the
#: scene's corners sought in :func:`changed_roi`: the left car ranks first on 40 of 40 with
#: annealing, 36 of 40 with the network (update-order seed 0).
DEPTH_SOLVER = "anneal"
SOLVERS = ("network", "anneal")


@dataclass(frozen=True)
class DepthConfig:
    """Tolerances of :func:`depth_from_matches` and the rig's calibration.

    Attributes
    ----------
    position_tol_px : float
        Largest distance (left image) between a scene match and a background match
        counted as the same place.
    disparity_tol_px : float
        Largest disparity difference counted as the same disparity.
    link_px : float
        Single-linkage distance: features closer than this may be in one object.
    link_disparity_px : float
        ... if they have matches whose disparities differ by at most this.
    consensus_px : float
        Half width of the disparity band around an object's consensus disparity.
    min_features : int
        Fewest consensus features an object needs; smaller groups are dropped.
    in_front : bool
        Drop scene matches not in front of the local background disparity.
    local_px : float
        Radius of the local background around a scene match.
    focal_px, baseline_m : float
        Focal length in pixels and baseline in metres (> 0); the defaults are
        :class:`ismb_lab.scenes.Rig`'s (the thesis' 10 cm rig).
    quantisation_px : float
        Disparity error bar for the depth range (integer corners: 0.5 px).

    Examples
    --------
    >>> DepthConfig(link_px=25).link_px
    25.0
    >>> DepthConfig(focal_px=0)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'focal_px' parameter of DepthConfig must be a finite number > 0. Got 0.0 instead.
    """

    position_tol_px: float = 2.0
    disparity_tol_px: float = 1.5
    link_px: float = 30.0
    link_disparity_px: float = 2.0
    consensus_px: float = 1.0
    min_features: int = 2
    in_front: bool = True
    local_px: float = 40.0
    focal_px: float = 300.0
    baseline_m: float = 0.10
    quantisation_px: float = 0.5

    def __post_init__(self):
        own = "DepthConfig"
        for name in ("position_tol_px", "disparity_tol_px", "consensus_px", "quantisation_px",
                     "link_disparity_px"):
            object.__setattr__(self, name, check_number(getattr(self, name), name, own, low=0))
        for name in ("link_px", "local_px", "focal_px", "baseline_m"):
            object.__setattr__(self, name, check_number(getattr(self, name), name, own,
                                                        low=0, low_open=True))
        object.__setattr__(self, "min_features",
                           check_number(self.min_features, "min_features", own, low=1, integer=True))
        if not isinstance(self.in_front, bool):
            raise ParameterTypeError(message("in_front", own, "True or False", self.in_front))


@dataclass(frozen=True)
class Depth:
    """Metric depth of one disparity: ``z`` (None unless ``status == "finite"``) and its range."""

    z: float | None
    near: float | None
    far: float | None
    status: str


def metric_depth(disparity, focal_px: float = 300.0, baseline_m: float = 0.10,
                 error_px: float = 0.5) -> Depth:
    """``Z = f B / d`` and the depth range of ``d +- error_px``.

    Parameters
    ----------
    disparity : float
        Horizontal disparity in pixels.
    focal_px, baseline_m : float
        Calibration, both > 0.
    error_px : float
        Disparity error bar (>= 0).

    Returns
    -------
    Depth
        ``status`` is ``"finite"``, ``"at infinity"`` (``d == 0``) or ``"invalid"``
        (``d < 0``: a point behind the cameras, i.e. a wrong match); the range's far
        end is ``inf`` when ``d <= error_px``.

    Examples
    --------
    >>> metric_depth(30.0)
    Depth(z=1.0, near=0.9836065573770492, far=1.0169491525423728, status='finite')
    >>> metric_depth(0.0), metric_depth(-2.0).status
    (Depth(z=None, near=None, far=None, status='at infinity'), 'invalid')
    >>> metric_depth(0.25).far
    inf
    """
    own = "metric_depth"
    d = check_number(disparity, "disparity", own)
    fb = (check_number(focal_px, "focal_px", own, low=0, low_open=True)
          * check_number(baseline_m, "baseline_m", own, low=0, low_open=True))
    e = check_number(error_px, "error_px", own, low=0)
    if d == 0:
        return Depth(None, None, None, "at infinity")
    if d < 0:
        return Depth(None, None, None, "invalid")
    return Depth(fb / d, fb / (d + e), fb / (d - e) if d > e else math.inf, "finite")


@dataclass(frozen=True, eq=False)
class DepthObject:
    """One object found in the scene (or in the background).

    Attributes
    ----------
    rank : int
        1 = nearest.
    centroid_xy : (float, float)
        Mean left-image position ``(x, y)`` of its features.
    mean_disparity : float
        Mean horizontal disparity of its consensus matches, pixels.
    disparity_std : float
        Their standard deviation.
    depth : Depth
        Metric depth of `mean_disparity` with its range.
    features : (n, 2) ndarray
        Left-image positions of its consensus features (read-only).
    n_matches : int
        Consensus matches (a feature may have several).
    outliers : int
        The object's matches off the consensus, not counted.
    """

    rank: int
    centroid_xy: tuple
    mean_disparity: float
    disparity_std: float
    depth: Depth
    features: np.ndarray
    n_matches: int
    outliers: int = 0

    @property
    def depth_m(self) -> float | None:
        """Metric depth in metres, None unless finite."""
        return self.depth.z

    def to_dict(self) -> dict:
        """The object's part of ``ismb-lab depth --json``."""
        d = self.depth
        return {"rank": self.rank, "centroid_xy": [float(v) for v in self.centroid_xy],
                "mean_disparity": self.mean_disparity, "disparity_std": self.disparity_std,
                "depth_m": d.z, "depth_range_m": None if d.z is None else
                [d.near, None if math.isinf(d.far) else d.far],
                "depth_status": d.status, "n_matches": self.n_matches, "outliers": self.outliers,
                "features": [[float(x), float(y)] for x, y in self.features]}


@dataclass(frozen=True, eq=False)
class DepthResult:
    """What :func:`depth_from_matches` found.

    Attributes
    ----------
    objects : tuple of DepthObject
        The scene's objects, nearest first.
    background_objects : tuple of DepthObject
        The background pair's own objects (e.g. the box and the wall), nearest first,
        for comparisons like "both cars are in front of the box".
    background_removed : int
        Scene features removed as background.
    behind_background : int
        Scene matches dropped because they are not in front of the local background.
    dropped : int
        Scene features in groups smaller than ``min_features``.
    kept_xy, kept_disparity : ndarray
        Scene matches left after steps 1 and 2 (left ``(x, y)``, disparity), for plots.
    removed_xy : ndarray
        Left positions of the features removed as background.
    background, scene : MatchResult
    config : DepthConfig
    message : str
        Empty, or why there are no objects.
    scene_roi : (x, y, w, h) or None
        The box in which the scene pair's corners were sought (:func:`changed_roi`),
        when :func:`relative_depth` made the result.
    """

    objects: tuple
    background_objects: tuple
    background_removed: int
    behind_background: int
    dropped: int
    kept_xy: np.ndarray
    kept_disparity: np.ndarray
    removed_xy: np.ndarray
    background: object
    scene: object
    config: DepthConfig
    message: str = ""
    scene_roi: tuple | None = None

    def to_dict(self) -> dict:
        """The JSON of ``ismb-lab depth --json``: objects near -> far and the counts."""
        return {"objects": [o.to_dict() for o in self.objects],
                "background_removed": self.background_removed,
                "behind_background": self.behind_background, "dropped": self.dropped,
                "background_objects": [o.to_dict() for o in self.background_objects],
                "focal_px": self.config.focal_px, "baseline_m": self.config.baseline_m,
                "scene_roi": None if self.scene_roi is None else list(self.scene_roi),
                "message": self.message}


def _readonly(arr) -> np.ndarray:
    arr = np.array(arr, dtype=float)
    arr.flags.writeable = False
    return arr


def _matches(result) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Left feature index, left ``(x, y)`` and horizontal disparity of every match."""
    return result.pairs[:, 0], result.left_match_xy, result.horizontal_disparity


def _clusters(xy: np.ndarray, disparities: list, link_px: float, link_disparity_px: float) -> np.ndarray:
    """Single-linkage labels (0, 1, ...): features linked when near and of a like disparity."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    near = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=2) <= link_px
    for a, b in zip(*np.nonzero(np.triu(near, 1))):
        gap = np.min(np.abs(disparities[a][:, None] - disparities[b][None, :]))
        near[a, b] = near[b, a] = gap <= link_disparity_px
    return connected_components(csr_matrix(near), directed=False)[1]


def _consensus(d: np.ndarray, band: float) -> np.ndarray:
    """Mask of the matches within `band` of the disparity that most matches agree with."""
    near = np.abs(d[:, None] - d[None, :]) <= band
    support = near.sum(axis=1)
    spread = np.array([d[row].std() for row in near])
    # Ties go to the tightest band: exact agreement is the stronger evidence.
    centre = d[np.lexsort((spread, -support))[0]]
    return np.abs(d - centre) <= band


def _local_background(xy, bxy, bd, radius: float) -> np.ndarray:
    """Smallest background disparity within `radius` of each point (overall where none is)."""
    dist = np.linalg.norm(xy[:, None, :] - bxy[None, :, :], axis=2)
    out = np.full(len(xy), float(np.min(bd)))
    for n, row in enumerate(dist <= radius):
        if row.any():
            out[n] = np.min(bd[row])
    return out


def _objects(feature, xy, d, config: DepthConfig) -> tuple[list, int]:
    """Group matches into objects; returns (objects near -> far, features dropped)."""
    features = np.unique(feature)
    if not len(features):
        return [], 0
    first = {f: xy[feature == f][0] for f in features}
    labels = _clusters(np.array([first[f] for f in features]), [d[feature == f] for f in features],
                       config.link_px, config.link_disparity_px)
    label_of = dict(zip(features.tolist(), labels.tolist()))
    found, dropped = [], 0
    for label in np.unique(labels):
        sel = np.array([label_of[f] == label for f in feature.tolist()])
        inlier = _consensus(d[sel], config.consensus_px)
        members = np.unique(feature[sel][inlier])
        if len(members) < config.min_features:
            dropped += int(np.sum(labels == label))
            continue
        pts = np.array([first[f] for f in members])
        dd = d[sel][inlier]
        mean = float(dd.mean())
        found.append(DepthObject(0, tuple(float(v) for v in pts.mean(axis=0)), mean, float(dd.std()),
                                 metric_depth(mean, config.focal_px, config.baseline_m,
                                              config.quantisation_px),
                                 _readonly(pts), int(inlier.sum()), int((~inlier).sum())))
    found.sort(key=lambda o: -o.mean_disparity)
    ranked = [DepthObject(n, o.centroid_xy, o.mean_disparity, o.disparity_std, o.depth, o.features,
                          o.n_matches, o.outliers) for n, o in enumerate(found, 1)]
    return ranked, dropped


def depth_from_matches(background, scene, config: DepthConfig | None = None) -> DepthResult:
    """Objects of `scene` that are not in `background`, ranked near -> far.

    Parameters
    ----------
    background, scene : MatchResult
        Matches of the background pair and of the scene pair (same view, same size).
    config : DepthConfig, optional

    Returns
    -------
    DepthResult

    Examples
    --------
    >>> from ismb_lab.matching import match
    >>> from ismb_lab.scenes import lab_scene
    >>> bg = match(*(lambda s: (s.left, s.right))(lab_scene(0)))
    >>> r = depth_from_matches(bg, bg)
    >>> r.objects, r.message
    ((), 'no objects: every scene feature matches the background')
    """
    from .matching import MatchResult

    own = "depth_from_matches"
    config = DepthConfig() if config is None else config
    if not isinstance(config, DepthConfig):
        raise ParameterTypeError(message("config", own, "a DepthConfig", config))
    for name, value in (("background", background), ("scene", scene)):
        if not isinstance(value, MatchResult):
            raise ParameterTypeError(message(name, own, "a MatchResult", value))
    bf, bxy, bd = _matches(background)
    sf, sxy, sd = _matches(scene)
    background_objects, _ = _objects(bf, bxy, bd, config)

    same = np.zeros(len(sf), dtype=bool)
    if len(bf) and len(sf):
        near = np.linalg.norm(sxy[:, None, :] - bxy[None, :, :], axis=2) <= config.position_tol_px
        same = (near & (np.abs(sd[:, None] - bd[None, :]) <= config.disparity_tol_px)).any(axis=1)
    removed = np.unique(sf[same])
    keep = ~np.isin(sf, removed)
    behind = np.zeros(len(sf), dtype=bool)
    if config.in_front and len(bd):
        behind = keep & (sd <= _local_background(sxy, bxy, bd, config.local_px)
                         + config.disparity_tol_px)
    keep &= ~behind
    objects, dropped = _objects(sf[keep], sxy[keep], sd[keep], config)

    note = ""
    if not len(sf):
        note = "no matches in the scene pair" + (f" ({scene.message})" if scene.message else "")
    elif not len(bf):
        note = ("no matches in the background pair"
                + (f" ({background.message})" if background.message else ""))
    elif not objects:
        note = ("no objects: every scene feature matches the background" if not keep.any() else
                f"no objects: no group of {config.min_features} or more new features agrees "
                "on a disparity")
    first = {f: xy for f, xy in zip(sf.tolist(), sxy)}
    return DepthResult(tuple(objects), tuple(background_objects), int(len(removed)),
                       int(behind.sum()), dropped, _readonly(sxy[keep].reshape(-1, 2)),
                       _readonly(sd[keep]), _readonly(np.array([first[f] for f in removed.tolist()]
                                                               ).reshape(-1, 2)),
                       background, scene, config, note)


def changed_roi(background_left, scene_left, roi="center", *, threshold: float = 8.0,
                sigma: float = 1.0, margin: int = 4):
    """The box of `roi` where the scene's left image differs from the background's.

    Parameters
    ----------
    background_left, scene_left : (H, W) array_like
        Grey left images of the background and of the scene, one size.
    roi : str or (x, y, w, h)
        Where to look, as :attr:`ismb_lab.matching.MatchConfig.roi`.
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
    from scipy.ndimage import gaussian_filter

    from .features import resolve_roi

    own = "changed_roi"
    bg = np.asarray(background_left, dtype=float)
    sc = np.asarray(scene_left, dtype=float)
    if bg.ndim != 2 or bg.shape != sc.shape:
        raise ParameterError(message("scene_left", own, "a grey image of the background's shape "
                                     f"{bg.shape}", f"shape {sc.shape}"))
    threshold = check_number(threshold, "threshold", own, low=0)
    sigma = check_number(sigma, "sigma", own, low=0)
    margin = check_number(margin, "margin", own, low=0, integer=True)
    x, y, w, h = resolve_roi(roi, bg.shape)
    diff = np.abs(sc - bg)
    if sigma:
        diff = gaussian_filter(diff, sigma)
    rows, cols = np.nonzero(diff[y:y + h, x:x + w] > threshold)
    if not len(rows):
        return None
    x0, y0 = max(cols.min() - margin, 0), max(rows.min() - margin, 0)
    x1, y1 = min(cols.max() + margin, w - 1), min(rows.max() + margin, h - 1)
    return int(x + x0), int(y + y0), int(x1 - x0 + 1), int(y1 - y0 + 1)


def scene_match_config(background, scene, match_config=None):
    """The demo's corner settings for a scene pair: `match_config` with its ROI cut
    down to :func:`changed_roi`.

    Parameters
    ----------
    background, scene : StereoPair
        The two pairs of the same view (:func:`ismb_lab.io.load_pair`).
    match_config : MatchConfig, optional
        Default :data:`DEPTH_MATCH_CONFIG`.

    Returns
    -------
    MatchConfig
        `match_config` itself when nothing in its ROI changed.

    Examples
    --------
    >>> from ismb_lab.io import load_pair
    >>> from ismb_lab.scenes import lab_scene, toy_car_scene
    >>> bg, sc = (load_pair(s.left, s.right) for s in (lab_scene(0), toy_car_scene(0)))
    >>> scene_match_config(bg, sc).roi
    (97, 127, 134, 49)
    """
    from dataclasses import replace

    from .io import StereoPair
    from .matching import MatchConfig

    own = "scene_match_config"
    match_config = DEPTH_MATCH_CONFIG if match_config is None else match_config
    if not isinstance(match_config, MatchConfig):
        raise ParameterTypeError(message("match_config", own, "a MatchConfig", match_config))
    for name, value in (("background", background), ("scene", scene)):
        if not isinstance(value, StereoPair):
            raise ParameterTypeError(message(name, own, "a StereoPair", value))
    _check_same_size(background, scene, own)
    box = changed_roi(background.left, scene.left, match_config.roi)
    return match_config if box is None else replace(match_config, roi=box)


def _check_same_size(background, scene, owner: str):
    if background.shape != scene.shape:
        (h, w), (h2, w2) = background.shape, scene.shape
        raise ParameterError(message("scene", owner, f"images of the background's size {h}x{w}",
                                     f"images of size {h2}x{w2}"))


def _load(value, name: str, owner: str):
    """A StereoPair from a StereoPair, a (left, right) pair or an object with .left and .right."""
    from .io import StereoPair, load_pair

    if isinstance(value, StereoPair):
        return value
    if hasattr(value, "left") and hasattr(value, "right"):
        return load_pair(value.left, value.right)
    if isinstance(value, (tuple, list)) and len(value) == 2:
        return load_pair(value[0], value[1])
    raise ParameterTypeError(message(name, owner, "a (left, right) pair of images or "
                                     "paths, or an object with .left and .right", value))


def depth_match(pair, *, background=None, method: str = "III", params=None, match_config=None,
                seed: int = 0, solver: str = DEPTH_SOLVER):
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
    solver : {"anneal", "network"}
        Mean-field annealing (:func:`ismb_lab.annealing.anneal`, seeded by `seed`) or
        the discrete network alone (:func:`ismb_lab.matching.match`).

    Returns
    -------
    MatchResult
        With ``stop_rule == "anneal"`` when annealed.

    Examples
    --------
    >>> from ismb_lab.scenes import lab_scene
    >>> m = depth_match(lab_scene(0, supersample=1))
    >>> m.stop_rule, len(m.pairs) > 10
    ('anneal', True)
    >>> depth_match(lab_scene(0, supersample=1), solver="exact")
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'solver' parameter of depth_match must be one of 'network', 'anneal'. Got 'exact' instead.
    """
    from dataclasses import replace

    from .annealing import anneal
    from .matching import MatchConfig, match, prepare
    from .methods import get_method

    own = "depth_match"
    check_choice(solver, "solver", own, SOLVERS)
    if params is None and method == "III":
        params = DEPTH_PARAMS
    match_config = DEPTH_MATCH_CONFIG if match_config is None else match_config
    if not isinstance(match_config, MatchConfig):
        raise ParameterTypeError(message("match_config", own, "a MatchConfig", match_config))
    pair = _load(pair, "pair", own)
    if background is not None:
        match_config = scene_match_config(_load(background, "background", own), pair, match_config)
    prepared = prepare(pair, None, match_config)
    result = match(method=method, params=params, seed=seed, prepared=prepared)
    if solver == "network" or not result.n_candidates:
        return result
    m, problem = get_method(method), prepared.problem
    annealed = anneal(m.network(problem, result.params), rng=seed)
    state = m.postprocess(problem, annealed.state)
    on = np.flatnonzero(state)
    pairs = np.stack([problem.rows[on], problem.cols[on]], axis=1).reshape(-1, 2)
    return replace(result, stop_rule="anneal", energy=float(annealed.energy), pairs=pairs,
                   state=state)


def relative_depth(background, scene, *, method: str = "III", params=None, match_config=None,
                   config: DepthConfig | None = None, seed: int = 0,
                   solver: str = DEPTH_SOLVER) -> DepthResult:
    """Match a background pair and a scene pair, and rank the scene's new objects by depth.

    Parameters
    ----------
    background, scene : (left, right) or object with ``.left`` and ``.right``
        The two stereo pairs of the same view, as image arrays or paths (a
        :class:`~ismb_lab.scenes.Scene` works too).  All four images must have one size.
    method : str
        Energy recipe, see :mod:`ismb_lab.methods` (the thesis uses Method-III).
    params : Params, optional
        Energy parameters (default: :data:`DEPTH_PARAMS` for Method-III, fitted on the
        background pair images/lab; the thesis' for the other methods).
    match_config : MatchConfig, optional
        Corners, ROI and candidate window (default: :data:`DEPTH_MATCH_CONFIG`, the
        thesis' settings with 40 to 60 corners).  The scene pair's corners are
        sought in the part of the ROI that changed (:func:`changed_roi`).
    config : DepthConfig, optional
        Tolerances and calibration.
    seed : int
        Update-order seed of both network runs.
    solver : {"anneal", "network"}
        How the energy is solved (see :func:`depth_match`).

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
    ismb_lab.ParameterError: The 'scene' parameter of relative_depth must be images of the background's size 60x80. Got 'images of size 50x80' instead.
    """
    from dataclasses import replace

    from .features import resolve_roi

    own = "relative_depth"
    bg, sc = _load(background, "background", own), _load(scene, "scene", own)
    _check_same_size(bg, sc, own)
    scene_config = scene_match_config(bg, sc, match_config)
    results = [depth_match(p, method=method, params=params, match_config=c, seed=seed, solver=solver)
               for p, c in ((bg, match_config), (sc, scene_config))]
    return replace(depth_from_matches(*results, config),
                   scene_roi=resolve_roi(scene_config.roi, sc.shape))
