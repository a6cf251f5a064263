"""Objects by their outlines: the blobs where a scene pair differs from its background pair.

:func:`silhouettes` gives each left blob of change the shift that lays it best on the right
image's change; the outline does not depend on texture (beyond the thesis; ``docs/depth.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter

from ._outline_fit import _ascend, _best_shift, _cut, _join, _placed_dice
from .._core.validation import ParameterError, ParameterTypeError, check_number, message, readonly
from ..images.features import resolve_roi
from ..images.io import StereoPair

__all__ = ["CHANGE_SIGMA", "CHANGE_THRESHOLD", "OutlineConfig", "Silhouettes", "changed_in_roi", "silhouettes"]

#: Grey levels (0-255) that the smoothed difference from the background must exceed to count as
#: a change: the one threshold of the corners' boxes and of the outlines.
CHANGE_THRESHOLD = 8.0

#: Standard deviation (px) of the Gaussian that smooths that difference first.
CHANGE_SIGMA = 1.0


@dataclass(frozen=True)
class OutlineConfig:
    """How :func:`silhouettes` finds the blobs of change and their shifts (``DepthConfig.outline``).

    ``docs/depth.md`` describes every field beside its default (section 4).  `threshold_low`
    (grey levels) is the hysteresis threshold, from 0 to :data:`CHANGE_THRESHOLD`; distances are
    in pixels and scores are Dice overlaps in [0, 1].

    Attributes
    ----------
    threshold_low : float, default 5.0
        Hysteresis threshold: weaker change that connects to a stronger one counts too.
    min_pixels : int, default 20
        Smaller blobs are camera noise.
    pad_px : int, default 8
        Columns on each side of a blob's box that its overlap counts as well.
    merge_gap_px : int, default 10
        Largest gap between the boxes of two blobs that may be one object.
    merge_disparity_px : float, default 1.0
        Blobs this close in shift (and `merge_gap_px` apart) are one object ...
    link_score : float, default 0.9
        ... unless their shifts differ and both fit with a Dice of this or more.
    max_fraction : float, default 0.5
        A blob covering more of the ROI than this is a change of light or view: its score is 0.
    split_score : float, default 0.9
        Least Dice of each part of a blob cut in two.
    split_step_px : float, default 3.0
        Least difference of the two parts' shifts.
    split_far_px, split_far_score : float, default 5.0 and 0.94
        A blob one shift lays this well is cut when two shifts this far apart lay it better.
    split_far_poor_px : float, default 8.0
        ... and one laid less well, when two shifts this far apart lay both parts well.

    Examples
    --------
    >>> OutlineConfig(pad_px=6).pad_px
    6
    >>> OutlineConfig(threshold_low=9)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'threshold_low' parameter of OutlineConfig must be a finite number >= 0 and <= 8.0. Got 9.0 instead.
    """

    threshold_low: float = 5.0
    min_pixels: int = 20
    pad_px: int = 8
    merge_gap_px: int = 10
    merge_disparity_px: float = 1.0
    link_score: float = 0.9
    max_fraction: float = 0.5
    split_score: float = 0.9
    split_step_px: float = 3.0
    split_far_px: float = 5.0
    split_far_score: float = 0.94
    split_far_poor_px: float = 8.0

    def __post_init__(self):
        own = "OutlineConfig"
        checks = {"threshold_low": dict(low=0, high=CHANGE_THRESHOLD), "min_pixels": dict(low=1, integer=True),
                  "pad_px": dict(low=0, integer=True), "merge_gap_px": dict(low=0, integer=True),
                  "merge_disparity_px": dict(low=0), "link_score": dict(low=0, high=1),
                  "max_fraction": dict(low=0, high=1, low_open=True), "split_score": dict(low=0, high=1),
                  "split_step_px": dict(low=0), "split_far_px": dict(low=0), "split_far_score": dict(low=0, high=1),
                  "split_far_poor_px": dict(low=0)}
        for name, rule in checks.items():
            object.__setattr__(self, name, check_number(getattr(self, name), name, own, **rule))


@dataclass(frozen=True, eq=False)
class Silhouettes:
    """Blobs of change of a scene's left image, each with the shift that lays it on the right image's.

    Attributes
    ----------
    labels : (H, W) int ndarray
        0 where the left image did not change, ``k`` on blob ``k`` (1..n) (read-only).
    disparity, score : (n,) ndarray
        Blob ``k``'s shift ``x_left - x_right`` with the largest Dice overlap, and that Dice, at
        index ``k - 1``.
    centroid_xy : (n, 2) ndarray
        Mean left-image ``(x, y)`` of each blob's pixels.
    right : (H, W) bool ndarray or None
        The right image's changed pixels (read-only), which :meth:`cut_dice` lays the blobs on.
    pad_px : int
        :attr:`OutlineConfig.pad_px`.
    shifts : tuple of int
        The shifts tried.
    """

    labels: np.ndarray
    disparity: np.ndarray
    score: np.ndarray
    centroid_xy: np.ndarray
    right: np.ndarray | None = None
    pad_px: int = 0
    shifts: tuple = ()

    def __post_init__(self):
        labels = np.array(self.labels)
        if labels.ndim != 2 or not np.issubdtype(labels.dtype, np.integer):
            raise ParameterError(message("labels", "Silhouettes", "a 2-D integer array",
                                         f"{labels.dtype} array of shape {labels.shape}"))
        n = int(labels.max(initial=0))
        for name, shape in (("disparity", (n,)), ("score", (n,)), ("centroid_xy", (n, 2))):
            value = np.array(getattr(self, name), dtype=float).reshape(-1, *shape[1:]) if n else \
                np.zeros(shape)
            if value.shape != shape:
                raise ParameterError(message(name, "Silhouettes", f"shape {shape}, one per blob of labels",
                                             f"shape {value.shape}"))
            object.__setattr__(self, name, readonly(value))
        labels.flags.writeable = False
        object.__setattr__(self, "labels", labels)
        if self.right is not None:
            right = np.array(self.right, dtype=bool)
            if right.shape != labels.shape:
                raise ParameterError(message("right", "Silhouettes", f"a mask of the labels' shape {labels.shape}",
                                             f"shape {right.shape}"))
            right.flags.writeable = False
            object.__setattr__(self, "right", right)
        object.__setattr__(self, "shifts", tuple(int(d) for d in self.shifts))

    def __len__(self) -> int:
        return len(self.disparity)

    def cut_dice(self, k: int, column: int, shifts) -> float:
        """How well blob `k` (1..n), cut at left-image `column` into two parts moved at once by
        ``shifts = (left, right)``, lies on the right image's change (one Dice; nan without
        :attr:`right`).  Holes narrower than ``pad_px + 1`` columns are closed on both sides,
        since where an object looks like the wall its blob has holes that do not tell shifts apart.

        >>> import numpy as np
        >>> labels = np.zeros((20, 60), dtype=np.int32); labels[5:15, 30:50] = 1
        >>> right = np.zeros((20, 60), dtype=bool)
        >>> right[5:15, 20:30] = right[5:15, 36:46] = True      # left half 10 px, right half 4 px
        >>> s = Silhouettes(labels, [4.0], [0.5], [[39.5, 9.5]], right, 2, range(0, 15))
        >>> s.cut_dice(1, 40, (10, 4)), round(s.cut_dice(1, 40, (10, 10)), 3)
        (1.0, 0.7)
        """
        if self.right is None:
            return float("nan")
        parts, right, line = self._cut_parts(k, column)
        return float(_placed_dice(parts, shifts, right, self.pad_px, line))

    def cut_shifts(self, k: int, column: int, start) -> tuple:
        """The shifts ``(left, right)`` that lay the two parts of :meth:`cut_dice` best, by coordinate
        ascent over :attr:`shifts` from `start`.

        >>> import numpy as np
        >>> labels = np.zeros((20, 60), dtype=np.int32); labels[5:15, 30:50] = 1
        >>> right = np.zeros((20, 60), dtype=bool)
        >>> right[5:15, 20:30] = right[5:15, 36:46] = True
        >>> Silhouettes(labels, [4.0], [0.5], [[39.5, 9.5]], right, 2, range(0, 15)).cut_shifts(1, 40, (7, 7))
        (10, 4)
        """
        if self.right is None:
            raise ParameterError(message("right", "Silhouettes.cut_shifts", "the right image's changed pixels",
                                         None))
        parts, right, line = self._cut_parts(k, column)
        return tuple(int(v) for v in _ascend(parts, start, right, self.shifts, self.pad_px, line)[1])

    def _cut_parts(self, k: int, column: int):
        """Blob `k` cut at `column` (left, right part), the right image's change closed, and the line."""
        from scipy.ndimage import binary_closing

        line = np.ones((1, self.pad_px + 1), dtype=bool)
        if "_closed" not in self.__dict__:      # the same for every cut: closed once
            object.__setattr__(self, "_closed", self.right | binary_closing(self.right, line))
        mask = self.labels == k
        left = mask.copy()
        left[:, column:] = False
        return [left, mask & ~left], self._closed, line


def changed_in_roi(background, scene, roi, threshold, sigma, margin, own: str, name: str, low=None):
    """The pixels of `roi` whose smoothed difference exceeds `threshold`, the ROI and the margin.

    The one test of "changed": the absolute difference of two grey images, Gaussian-smoothed with
    `sigma`, above `threshold` grey levels.  With `low` (``threshold_low`` to the caller), pixels
    above it that connect to one above `threshold` count as well; `low` is raised to twice the
    median difference (the noise floor), at most to `threshold`.  Bad values are named as
    parameters of `own`; `name` holds `scene`.

    >>> import numpy as np
    >>> background = np.zeros((6, 8))
    >>> scene = background.copy(); scene[2:4, 3:5] = 50.0
    >>> changed, roi, margin = changed_in_roi(background, scene, "full", 8.0, 0.0, 0, "demo", "scene")
    >>> int(changed.sum()), roi
    (4, (0, 0, 8, 6))
    """
    bg = np.asarray(background, dtype=float)
    sc = np.asarray(scene, dtype=float)
    if bg.ndim != 2 or bg.shape != sc.shape:
        raise ParameterError(message(name, own, "a grey image of the background's shape "
                                     f"{bg.shape}", f"shape {sc.shape}"))
    threshold = check_number(threshold, "threshold", own, low=0)
    sigma = check_number(sigma, "sigma", own, low=0)
    margin = check_number(margin, "margin", own, low=0, integer=True)
    x, y, w, h = resolve_roi(roi, bg.shape)
    diff = np.abs(sc - bg)
    if sigma:
        diff = gaussian_filter(diff, sigma)
    if low is None:
        return diff[y:y + h, x:x + w] > threshold, (x, y, w, h), margin
    from skimage.filters import apply_hysteresis_threshold

    low = check_number(low, "threshold_low", own, low=0, high=threshold)
    low = min(max(low, 2 * float(np.median(diff))), threshold)
    return apply_hysteresis_threshold(diff, low, threshold)[y:y + h, x:x + w], (x, y, w, h), margin


def silhouettes(background, scene, roi="center", *, shifts=range(0, 41),
                config: OutlineConfig | None = None) -> Silhouettes:
    """Blobs of change of the scene's left image, each with the shift that lays it on the right's.

    `background` and `scene` are StereoPairs of one view; the blobs of the left image that reach
    into `roi` each get the shift of `shifts` with the largest Dice overlap (``docs/depth.md``,
    section 4), and are numbered left to right by centroid.

    >>> import numpy as np
    >>> from ismb_lab.images.io import load_pair
    >>> rng = np.random.default_rng(0)
    >>> wall = rng.uniform(0, 120, (240, 320))
    >>> left, right = wall.copy(), wall.copy()
    >>> left[100:140, 150:190] = right[100:140, 128:168] = 255.0     # an object 22 px nearer
    >>> s = silhouettes(load_pair(wall, wall), load_pair(left, right))
    >>> s.disparity.tolist(), s.score.round(2).tolist(), s.centroid_xy.round().tolist()
    ([22.0], [1.0], [[170.0, 120.0]])
    """
    own = "silhouettes"
    for name, value in (("background", background), ("scene", scene)):
        if not isinstance(value, StereoPair):
            raise ParameterTypeError(message(name, own, "a StereoPair", value))
    if background.shape != scene.shape:
        raise ParameterError(message("scene", own, "images of the background's size",
                                     f"images of shape {scene.shape}"))
    config = OutlineConfig() if config is None else config
    if not isinstance(config, OutlineConfig):
        raise ParameterTypeError(message("config", own, "None or an OutlineConfig", config))
    try:
        shifts = [int(d) for d in shifts]
    except (TypeError, ValueError):
        raise ParameterTypeError(message("shifts", own, "an iterable of whole pixels", shifts)) from None
    if not shifts:
        raise ParameterError(message("shifts", own, "at least one shift", shifts))
    h, w = scene.shape
    box = resolve_roi(roi, scene.shape)
    partitions = []
    for low in (None, config.threshold_low):
        changed = [changed_in_roi(b, c, (0, 0, w, h), CHANGE_THRESHOLD, CHANGE_SIGMA, 0, own, "scene", low)[0]
                   for b, c in ((background.left, scene.left), (background.right, scene.right))]
        partitions.append(_partition(*changed, box, shifts, config))
    return _by_region(*partitions)


def _partition(left, right, box, shifts, config: OutlineConfig) -> Silhouettes:
    """:func:`silhouettes` of the changed pixels `left` and `right` (full-image masks)."""
    from scipy.ndimage import find_objects, label
    from scipy.sparse.csgraph import connected_components

    x, y, w, h = box
    pad = config.pad_px
    blobs, n = label(left, structure=np.ones((3, 3)))
    sizes = np.bincount(blobs.ravel(), minlength=n + 1)
    inside = np.zeros(n + 1, dtype=bool)
    inside[np.unique(blobs[y:y + h, x:x + w])] = True
    keep = (sizes >= config.min_pixels) & inside
    keep[0] = False
    blobs = np.where(keep[blobs], blobs, 0)

    def measure(mask):
        rows, cols = find_objects(mask.astype(int))[0]
        return (*_best_shift(mask, rows, cols, right, shifts, pad), (rows, cols))

    def whole_view(mask):
        return np.count_nonzero(mask[y:y + h, x:x + w]) > config.max_fraction * w * h

    ks = np.flatnonzero(keep)
    found = [measure(blobs == k) for k in ks]
    link = np.eye(len(ks), dtype=bool)
    for a, (fa, da, (ra, ca)) in enumerate(found):
        for b, (fb, db, (rb, cb)) in enumerate(found):
            gap = max(ra.start - rb.stop, rb.start - ra.stop, ca.start - cb.stop, cb.start - ca.stop, 0)
            near = abs(da - db) <= config.merge_disparity_px and gap <= config.merge_gap_px
            if near and da != db:
                near = min(fa, fb) < config.link_score     # two pieces that both fit well are two objects
            link[a, b] |= near
    group = connected_components(link, directed=False)[1] if len(ks) else np.zeros(0, dtype=int)
    masks = [np.isin(blobs, ks[group == g]) for g in np.unique(group)]
    masks = _join(masks, measure, config.merge_gap_px, right, pad, config.split_score)
    todo, masks = [(m, True) for m in masks], []
    while todo:
        part, far = todo.pop()
        two = None if whole_view(part) else _cut(part, right, shifts, config, far)
        if two is None:
            masks.append(part)
        else:
            todo += [(p, False) for p in two]      # the test of two shifts far apart: once per blob
    fits = [measure(m) for m in masks]
    return _numbered(masks, [0.0 if whole_view(m) else f[0] for m, f in zip(masks, fits)],
                     [f[1] for f in fits], [np.argwhere(m).mean(axis=0)[::-1] for m in masks], right, pad, shifts)


def _numbered(masks, score, disparity, centroids, right, pad, shifts) -> Silhouettes:
    """Blobs `masks` with their fits and centroids, numbered left to right by centroid."""
    labels = np.zeros(right.shape, dtype=np.int32)
    order = np.argsort([c[0] for c in centroids], kind="stable")
    for k, j in enumerate(order, 1):
        labels[masks[j]] = k
    return Silhouettes(labels, [disparity[j] for j in order], [score[j] for j in order],
                       np.array([centroids[j] for j in order]).reshape(-1, 2), right, pad, shifts)


def _by_region(plain: Silhouettes, grown: Silhouettes) -> Silhouettes:
    """The blobs of `plain` or of `grown` (with hysteresis), region by region.

    A region is a set of overlapping blobs of the two; it keeps the blobs of the one that fit
    better on average (a tie keeps `plain`'s).  The right image's change is `plain`'s.
    """
    from scipy.sparse.csgraph import connected_components

    n = len(plain)
    link = np.eye(n + len(grown), dtype=bool)
    both = (plain.labels > 0) & (grown.labels > 0)
    for a, b in set(zip(plain.labels[both].tolist(), grown.labels[both].tolist())):
        link[a - 1, n + b - 1] = link[n + b - 1, a - 1] = True
    group = connected_components(link, directed=False)[1]
    kept = []
    for g in np.unique(group):
        mine = np.flatnonzero(group[:n] == g)
        theirs = np.flatnonzero(group[n:] == g)
        grow = len(theirs) and (not len(mine) or grown.score[theirs].mean() > plain.score[mine].mean())
        kept += [(grown, k) for k in theirs] if grow else [(plain, k) for k in mine]
    return _numbered([s.labels == k + 1 for s, k in kept], [s.score[k] for s, k in kept],
                     [s.disparity[k] for s, k in kept], [s.centroid_xy[k] for s, k in kept], plain.right,
                     plain.pad_px, plain.shifts)
