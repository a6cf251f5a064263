"""Disparity to depth, and objects ranked near -> far (thesis §5.2.3, the steps after matching).

:func:`depth_from_matches` removes the background's features and groups the rest into objects
(``docs/depth.md``); disparities are horizontal, ``x_left - x_right``, and ``Z = f B / d``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_choice, check_number, message, readonly
from ..cameras.camera import BASELINE_M, FOCAL_PX, StereoCamera
from ..matching.pipeline import MatchResult
from .outlines import OutlineConfig, Silhouettes
from ._grouping import _band_cut, _clusters, _consensus, _local_background, _merge, _on_blobs, _peel

__all__ = ["GROUPINGS", "Depth", "DepthConfig", "DepthObject", "DepthResult", "depth_from_matches", "metric_depth"]

#: How objects are found: by the blobs of change of both images, or by the features alone.
GROUPINGS = ("silhouettes", "features")


@dataclass(frozen=True)
class DepthConfig:
    """Tolerances of :func:`depth_from_matches` and the rig's calibration.

    ``docs/depth.md`` describes every field beside its default; distances and disparities are in
    pixels, scores are Dice overlaps in [0, 1].

    Attributes
    ----------
    position_tol_px : float, default 2.0
        Largest distance (left image) between a scene and a background match at the same place.
    disparity_tol_px : float, default 1.5
        Largest disparity difference counted as the same disparity.
    link_px : float, default 30.0
        Single-linkage distance: features closer than this may be in one object.
    link_disparity_px : float, default 2.0
        ... if they have matches whose disparities differ by at most this.
    consensus_px : float, default 1.0
        Half width of the disparity band around an object's consensus disparity.
    min_features : int, default 2
        Fewest consensus features an object needs; smaller groups are dropped.
    merge_px, merge_disparity_px : float, default 45.0 and 1.5
        Objects whose features come this close and whose median disparities differ this little are one.
    local_px : float, default 40.0
        Radius of the local background around a scene match.
    grouping : {"silhouettes", "features"}, default "silhouettes"
        Objects by the blobs of change (:class:`~ismb_lab.depth.outlines.Silhouettes`) or by the
        features alone (the thesis').
    silhouette_tol_px : float, default 3.0
        A match counts for its blob when its disparity lies from the blob's shift to this much above.
    silhouette_score : float, default 0.8
        Least Dice overlap of a blob in front of the background for it to be trusted as one object.
    silhouette_grow_px : int, default 3
        A feature within this many pixels of a blob lies on it.
    band_features, band_step_px : int, float, default 3 and 3.0
        Two bands of this many features this far apart in disparity may cut a blob in two.
    band_one_piece : float, default 0.97
        Least Dice of both parts for a blob of one piece to be cut.
    firm_outline : float, default 0.95
        A blob whose outline fits this well stands in front of the background.
    outline : OutlineConfig
        How the blobs of change and their shifts are found.
    focal_px, baseline_m : float
        The rig's focal length (px) and baseline (m), > 0; defaults ``FOCAL_PX`` and ``BASELINE_M``.
    quantisation_px : float, default 0.5
        Disparity error bar of the depth range.

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
    merge_px: float = 45.0
    merge_disparity_px: float = 1.5
    local_px: float = 40.0
    grouping: str = "silhouettes"
    silhouette_tol_px: float = 3.0
    silhouette_score: float = 0.8
    silhouette_grow_px: int = 3
    band_features: int = 3
    band_step_px: float = 3.0
    band_one_piece: float = 0.97
    firm_outline: float = 0.95
    outline: OutlineConfig = field(default_factory=OutlineConfig)
    focal_px: float = FOCAL_PX
    baseline_m: float = BASELINE_M
    quantisation_px: float = 0.5

    def __post_init__(self):
        own = "DepthConfig"
        rules = {("position_tol_px", "disparity_tol_px", "consensus_px", "quantisation_px", "link_disparity_px",
                  "merge_px", "merge_disparity_px", "silhouette_tol_px", "band_step_px"): dict(low=0),
                 ("link_px", "local_px", "focal_px", "baseline_m"): dict(low=0, low_open=True),
                 ("min_features", "band_features"): dict(low=1, integer=True),
                 ("silhouette_grow_px",): dict(low=0, integer=True),
                 ("silhouette_score", "band_one_piece", "firm_outline"): dict(low=0, high=1)}
        for names, rule in rules.items():
            for name in names:
                object.__setattr__(self, name, check_number(getattr(self, name), name, own, **rule))
        check_choice(self.grouping, "grouping", own, GROUPINGS)
        if not isinstance(self.outline, OutlineConfig):
            raise ParameterTypeError(message("outline", own, "an OutlineConfig", self.outline))


@dataclass(frozen=True)
class Depth:
    """Metric depth of one disparity: ``z`` (None unless ``status == "finite"``) and its range."""

    z: float | None
    near: float | None
    far: float | None
    status: str


def metric_depth(disparity, focal_px: float = FOCAL_PX, baseline_m: float = BASELINE_M,
                 error_px: float = 0.5) -> Depth:
    """``Z = f B / d`` and the depth range of ``d +- error_px``.

    ``status`` is ``"finite"``, ``"at infinity"`` (``d == 0``) or ``"invalid"`` (``d < 0``, a
    wrong match); the range's far end is ``inf`` when ``d <= error_px``.

    Parameters
    ----------
    disparity : float
        Horizontal disparity ``d`` in pixels.
    focal_px : float, default ``FOCAL_PX``
        Focal length in pixels, > 0.
    baseline_m : float, default ``BASELINE_M``
        Baseline in metres, > 0.
    error_px : float, default 0.5
        Disparity error bar (px), >= 0.

    Returns
    -------
    depth : Depth
        Depth ``z``, its ``near``/``far`` range and ``status``.

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
    mean_disparity, disparity_std : float
        Of its consensus matches, pixels.
    features : (n, 2) ndarray
        Left-image positions of its consensus features (read-only).
    n_matches, outliers : int
        Its matches in the consensus (a feature may have several) and off it.
    median_disparity, disparity_spread : float
        Median of its features' disparities (default `mean_disparity`), and their median
        absolute deviation from it.
    silhouette_disparity, silhouette_score : float or None
        The shift and Dice of its blob of change, None when found by its features alone;
        with no features (``n_features == 0``) the shift is its disparity.
    """

    rank: int
    centroid_xy: tuple
    mean_disparity: float
    disparity_std: float
    depth: Depth
    features: np.ndarray
    n_matches: int
    outliers: int = 0
    median_disparity: float | None = None
    disparity_spread: float = 0.0
    silhouette_disparity: float | None = None
    silhouette_score: float | None = None

    def __post_init__(self):
        if self.median_disparity is None:
            object.__setattr__(self, "median_disparity", self.mean_disparity)

    @property
    def n_features(self) -> int:
        """How many features the object rests on."""
        return len(self.features)

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
                "n_features": self.n_features, "median_disparity": self.median_disparity,
                "disparity_spread": self.disparity_spread,
                "silhouette_disparity": self.silhouette_disparity, "silhouette_score": self.silhouette_score,
                "features": [[float(x), float(y)] for x, y in self.features]}


@dataclass(frozen=True, eq=False)
class DepthResult:
    """What :func:`depth_from_matches` found.

    Attributes
    ----------
    objects, background_objects : tuple of DepthObject
        The scene's new objects and the background pair's own, nearest first.
    background_removed, behind_background, dropped : int
        Scene features removed as background, matches not in front of the local background,
        features in no object.
    kept_xy, kept_disparity : ndarray
        Scene matches left after the background removal.
    removed_xy : ndarray
        Left positions of the features removed as background.
    background, scene : MatchResult
        The two matchings the result comes from.
    config : DepthConfig
        The settings used.
    message : str
        Empty, or why there are no objects.
    scene_roi : (x, y, w, h) or None
        Where :func:`~ismb_lab.depth.pipeline.relative_depth` sought the scene's corners.
    silhouettes : Silhouettes or None
        The blobs of change that grouped the objects, None when the features alone did.
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
    silhouettes: Silhouettes | None = None

    def points(self, camera: StereoCamera) -> np.ndarray:
        """The kept scene matches as ``(N, 3)`` points in metres, in `camera`'s rectified left
        frame (the principal point depends on the image's size, which a result does not hold).

        Parameters
        ----------
        camera : StereoCamera
            The rig, set up for the images' size.

        Returns
        -------
        points : (N, 3) float array
            One point per kept scene match, metres.
        """
        if not isinstance(camera, StereoCamera):
            raise ParameterTypeError(message("camera", "DepthResult.points", "a StereoCamera", camera))
        return camera.points_from_disparity(self.kept_xy, self.kept_disparity)

    def to_dict(self) -> dict:
        """The JSON of ``ismb-lab depth --json``: objects near -> far and the counts."""
        return {"objects": [o.to_dict() for o in self.objects],
                "background_removed": self.background_removed,
                "behind_background": self.behind_background, "dropped": self.dropped,
                "background_objects": [o.to_dict() for o in self.background_objects],
                "focal_px": self.config.focal_px, "baseline_m": self.config.baseline_m,
                "grouping": self.config.grouping if self.silhouettes is not None else "features",
                "scene_roi": None if self.scene_roi is None else list(self.scene_roi),
                "message": self.message}


def _matches(result) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Left feature index, left ``(x, y)`` and horizontal disparity of every match."""
    return result.pairs[:, 0], result.left_match_xy, result.horizontal_disparity


def _object(rows, feature, first, d, config: DepthConfig, centroid=None, silhouette=(None, None)) -> DepthObject:
    """One object from its consensus matches `rows` (positions of `feature` and `d`)."""
    members = np.unique(feature[rows])
    per_feature = np.array([np.median(d[rows][feature[rows] == f]) for f in members])
    pts = np.array([first[f] for f in members]).reshape(-1, 2)
    dd = d[rows]
    mean = float(dd.mean()) if len(dd) else float(silhouette[0])
    median = float(np.median(per_feature)) if len(per_feature) else mean
    if centroid is None:
        centroid = pts.mean(axis=0)
    return DepthObject(0, tuple(float(v) for v in centroid), mean, float(dd.std()) if len(dd) else 0.0,
                       metric_depth(mean, config.focal_px, config.baseline_m, config.quantisation_px),
                       readonly(pts), int(len(rows)), int(np.isin(feature, members).sum() - len(rows)),
                       median, float(np.median(np.abs(per_feature - median))) if len(per_feature) else 0.0,
                       *silhouette)


def _objects(feature, xy, d, config: DepthConfig, silhouettes: Silhouettes | None = None,
             trusted=None, infront=None) -> tuple[list, int]:
    """Group matches into objects; returns (objects near -> far, features dropped)."""
    features = np.unique(feature)
    if not len(features) and silhouettes is None:
        return [], 0
    first = {f: xy[feature == f][0] for f in features}
    found, parts, used = [], [], set()
    groups, outlined = [], []
    if silhouettes is None:
        labels = _clusters(np.array([first[f] for f in features]).reshape(-1, 2),
                           [d[feature == f] for f in features], config.link_px, config.link_disparity_px)
        label_of = dict(zip(features.tolist(), labels.tolist()))
        group = np.array([label_of[f] for f in feature.tolist()], dtype=int)
        groups = [np.flatnonzero(group == label) for label in np.unique(labels)]
    else:
        blob = _on_blobs(xy, silhouettes, config.silhouette_grow_px)
        for k in range(1, len(silhouettes) + 1):
            idx = np.flatnonzero(blob == k)
            dk, score = float(silhouettes.disparity[k - 1]), float(silhouettes.score[k - 1])
            if infront[k - 1] and score > 0 and len(idx):
                two = _band_cut(idx, feature, first, d, config, silhouettes, k)
                if two is not None:
                    for rows, centroid, shift in two:
                        used.update(np.unique(feature[rows]).tolist())
                        outlined.append((rows, centroid, (shift, score)))
                    continue
            if trusted[k - 1]:
                gap = d[idx] - dk
                near = idx[(gap >= 0) & (gap <= config.silhouette_tol_px)]
                rows = near[_consensus(d[near], config.consensus_px)] if len(near) else near
            elif infront[k - 1] and score > 0 and not _peel(feature[idx], d[idx], config):
                rows = idx[:0]        # a poor outline in front that no features agree on: nothing else places it
            else:
                groups.append(idx)    # the features decide
                continue
            used.update(np.unique(feature[rows]).tolist())
            outlined.append((rows, silhouettes.centroid_xy[k - 1], (dk, score)))
        found += [_object(rows, feature, first, d, config, centroid, outline) for rows, centroid, outline in outlined]
    for idx in groups:
        for band in _peel(feature[idx], d[idx], config):
            rows = idx[band]
            members = np.unique(feature[rows])
            used.update(members.tolist())
            per_feature = [np.median(d[rows][feature[rows] == f]) for f in members]
            parts.append((rows, float(np.median(per_feature)), np.array([first[f] for f in members])))
    found += [_object(rows, feature, first, d, config) for rows in _merge(parts, config)]
    found.sort(key=lambda o: -o.mean_disparity)
    ranked = [replace(o, rank=n) for n, o in enumerate(found, 1)]
    return ranked, len(features) - len(used)


def depth_from_matches(background, scene, config: DepthConfig | None = None,
                       silhouettes: Silhouettes | None = None) -> DepthResult:
    """Objects of `scene` that are not in `background`, ranked near -> far.

    Parameters
    ----------
    background, scene : MatchResult
        Matches of the background pair and of the scene pair (same view, same size).
    config : DepthConfig, optional
        Tolerances and the rig's calibration; default ``DepthConfig()``.
    silhouettes : Silhouettes, optional
        The scene's blobs of change; without them the features alone are grouped, whatever
        ``config.grouping`` says.

    Returns
    -------
    result : DepthResult
        The new objects nearest first, the background's own, and the counts of removed features.

    Raises
    ------
    ParameterTypeError
        `background` or `scene` not a MatchResult, or a bad `config` or `silhouettes`.
    ParameterError
        `silhouettes` smaller than the scene's images.

    Examples
    --------
    >>> from ismb_lab.matching.pipeline import match
    >>> from ismb_lab.scenes import lab_scene
    >>> bg = match(*(lambda s: (s.left, s.right))(lab_scene(0)))
    >>> r = depth_from_matches(bg, bg)
    >>> r.objects, r.message
    ((), 'no objects: every scene feature matches the background')
    """
    own = "depth_from_matches"
    config = DepthConfig() if config is None else config
    if not isinstance(config, DepthConfig):
        raise ParameterTypeError(message("config", own, "a DepthConfig", config))
    for name, value in (("background", background), ("scene", scene)):
        if not isinstance(value, MatchResult):
            raise ParameterTypeError(message(name, own, "a MatchResult", value))
    if silhouettes is not None:
        if not isinstance(silhouettes, Silhouettes):
            raise ParameterTypeError(message("silhouettes", own, "None or a Silhouettes", silhouettes))
        h, w = silhouettes.labels.shape
        if len(scene.left_xy) and not (np.all(scene.left_xy >= 0) and scene.left_xy[:, 0].max() < w
                                       and scene.left_xy[:, 1].max() < h):
            raise ParameterError(message("silhouettes", own, "labels as large as the scene's images "
                                         "(every scene feature on them)", f"labels of {w}x{h} (width x height)"))
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
    if len(bd):
        behind = keep & (sd <= _local_background(sxy, bxy, bd, config.local_px)
                         + config.disparity_tol_px)
    keep &= ~behind
    trusted = infront = None
    if silhouettes is not None:
        # An outline at the background's disparity or behind it is a sliver that looks like the
        # wall, unless it fits firmly.  Only a background object, not a lone wrong match, sets that floor.
        infront = np.ones(len(silhouettes), dtype=bool)
        if len(bd) and background_objects:
            infront = ((silhouettes.disparity > bd.min() + config.disparity_tol_px)
                       | (silhouettes.score >= config.firm_outline))
        trusted = (silhouettes.score >= config.silhouette_score) & infront
    objects, dropped = _objects(sf[keep], sxy[keep], sd[keep], config, silhouettes, trusted, infront)

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
                       int(behind.sum()), dropped, readonly(sxy[keep].reshape(-1, 2)),
                       readonly(sd[keep]), readonly(np.array([first[f] for f in removed.tolist()]
                                                               ).reshape(-1, 2)),
                       background, scene, config, note, silhouettes=silhouettes)
