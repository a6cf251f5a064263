"""Objects by their outlines: the blobs where a scene pair differs from its background pair.

The depth demo (:mod:`ismb_lab.depth_demo`) has a background pair and a scene pair of the
same view.  Where the scene differs from the background is where the objects are, in the
left image and in the right one.  :func:`silhouettes` gives each left blob of change the
shift that lays it best on the right image's change (its *silhouette disparity*), and
:func:`ismb_lab.depth.depth_from_matches` makes each well-fitting blob one object, at the
disparity its agreeing features give.  The outline does not depend on texture, so it
holds where the features are ambiguous (stripes, tiles) or missing (a plain object).
This goes beyond the thesis, which groups the features alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter

from ._outline_fit import _ascend, _best_shift, _cut, _join, _placed_dice
from ._validation import ParameterError, ParameterTypeError, check_number, message, readonly
from .features import resolve_roi
from .io import StereoPair

__all__ = ["Silhouettes", "changed_in_roi", "silhouettes"]


@dataclass(frozen=True, eq=False)
class Silhouettes:
    """Blobs of change of a scene's left image, each with the shift that lays it on the right image's.

    Made by :func:`silhouettes`; read by :func:`ismb_lab.depth.depth_from_matches`.

    Attributes
    ----------
    labels : (H, W) int ndarray
        0 where the left image did not change, ``k`` on blob ``k`` (1..n) (read-only).
    disparity : (n,) ndarray
        Blob ``k``'s silhouette disparity at index ``k - 1``: the whole-pixel shift
        ``x_left - x_right`` with the largest Dice overlap.
    score : (n,) ndarray
        That overlap, 0-1; 0 for a blob that covers more than half of the ROI, which is a
        change of the light or of the view rather than an object.
    centroid_xy : (n, 2) ndarray
        Mean left-image ``(x, y)`` of each blob's pixels.
    right : (H, W) bool ndarray or None
        The right image's changed pixels (read-only), which :meth:`cut_dice` lays the blobs on;
        None when not known.
    pad_px : int
        Columns on each side that an overlap counts as well (:func:`silhouettes`' `pad_px`).
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
        """How well blob `k` (1..n), cut at left-image `column` into a left and a right part moved
        at once by ``shifts = (left, right)``, lies on the right image's change: one Dice over the
        parts' rows and the columns they cover (padded by :attr:`pad_px`), the moved parts and the
        right image's change each with holes narrower than ``pad_px + 1`` columns closed; nan
        without :attr:`right`.

        Equal shifts give the whole blob at that shift.  Where an object's texture looks like the
        wall behind it, its blob has holes, and the wall behind differs between the two views:
        closed, the holes do not tell shifts apart.

        Examples
        --------
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
        """The shifts ``(left, right)`` that lay the two parts of :meth:`cut_dice` best, both moved at
        once: coordinate ascent over :attr:`shifts` from `start`, each part in turn, until neither
        moves (at most three rounds).

        Examples
        --------
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
        """Blob `k` cut at `column` (left part, right part), the right image's change with holes
        narrower than ``pad_px + 1`` columns closed, and the line that closes them."""
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

    The one test of "changed" behind :func:`silhouettes` and
    :func:`ismb_lab.depth_demo.changed_roi` / :func:`~ismb_lab.depth_demo.changed_regions`:
    the absolute difference of two grey images, Gaussian-smoothed with `sigma`, above
    `threshold` grey levels.  With `low` (a hysteresis threshold, named `threshold_low` to the
    caller), pixels above `low` that connect to one above `threshold` count as well; `low` is
    raised to twice the image's median smoothed difference (the noise floor, since most of the
    image is unchanged), and at most to `threshold`.  Bad values are named as parameters of
    `own`; `name` is the parameter that holds `scene`.

    Examples
    --------
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


def silhouettes(background, scene, roi="center", *, shifts=range(0, 41), threshold: float = 8.0,
                sigma: float = 1.0, min_pixels: int = 20, pad_px: int = 8, merge_gap_px: int = 10,
                merge_disparity_px: float = 1.0, max_fraction: float = 0.5, join: bool = True,
                split: bool = True, split_score: float = 0.9, split_step_px: float = 3.0,
                keep_apart: bool = True, split_far_px: float | None = 5.0,
                split_far_score: float = 0.94, split_placed: bool = True,
                join_weak: bool = True, link_score: float | None = 0.9,
                split_far_poor_px: float | None = 8.0, threshold_low: float | None = 5.0,
                by_region: bool = True) -> Silhouettes:
    """Blobs of change of the scene's left image, each with the shift that lays it on the right's.

    Where the scene pair differs from the background pair is where the objects are, in
    both images: the same changed pixels as :func:`ismb_lab.depth_demo.changed_regions`
    (whole image, the blobs that reach into `roi`), and the right image's changed pixels; by
    default, fainter ones that connect to them as well, region by region (`threshold_low`,
    `by_region`).  A blob's
    silhouette disparity is the shift ``d`` in `shifts` with the largest Dice overlap
    between the blob and the right image's changed pixels ``d`` pixels left, counted over
    the columns both images have (an object across the image border is seen in part).
    The outline does not depend on texture, so a striped object whose stripes match
    one period off still has its true shift; the features then give it to a fraction
    of a pixel (:func:`ismb_lab.depth.depth_from_matches`).

    Blobs with shifts within `merge_disparity_px` and boxes within `merge_gap_px` of
    each other are one object cut in two where it looks like the wall behind it (with
    `link_score`, only when one of them fits poorly).  With
    `join`, so are neighbours (boxes within `merge_gap_px`) whose union one shift lays on
    the right image's change at least as well as their own shifts lay them (Dice weighted by
    size): the pieces of a striped object, each of which fits some shift poorly.  With
    `split`, a blob that two shifts `split_step_px` or more apart lay better than one, cut at a
    column into a left and a right part that each fit with a Dice of `split_score` or more,
    is two objects side by side that touch in the image (cut again while that holds).  With
    `keep_apart` as well, two neighbours are joined only when one shift lays their union at least
    as well as their own two shifts, applied at once, lay both together (one Dice over the same
    padded columns): two objects side by side at different depths stay apart.

    Parameters
    ----------
    background, scene : StereoPair
        The two pairs of one view (images of one size).
    roi : str or (x, y, w, h)
        Where the objects may be, as :attr:`ismb_lab.matching.MatchConfig.roi`.
    shifts : iterable of int
        Disparities to try (:func:`ismb_lab.depth_demo.relative_depth`: the candidate window's).
    threshold, sigma : float
        As :func:`ismb_lab.depth_demo.changed_roi`.
    threshold_low : float or None
        With a number (at most `threshold`), a pixel whose smoothed difference exceeds it, and twice
        the image's median smoothed difference (noisy cameras), is changed too when it connects to
        one above `threshold` (hysteresis, in both images): the outline of an object that looks
        nearly like the wall behind it then breaks into fewer pieces, but neighbours are bridged
        more often.  None: `threshold` alone (docs/experiments/2026-11-26-depth-unseen-11.md).
    by_region : bool
        With `threshold_low`, make the blobs both without and with it and keep, in each region (the
        blobs of the two that overlap), those that fit better on average (mean Dice; a tie keeps
        those without).  Hysteresis then mends the outlines it mends, and where it bridges two
        neighbours into a blob that fits worse, the threshold's blobs stay.  The defaults
        (docs/experiments/2026-11-26-depth-unseen-12.md); False: hysteresis everywhere.
    min_pixels : int
        Smaller blobs are camera noise.
    pad_px : int
        Columns on each side of a blob's box that the overlap counts as well.
    merge_gap_px, merge_disparity_px : float
        See above.
    max_fraction : float
        A blob that covers more of the ROI than this is no object's outline but a change
        of the light or of the view: its score is 0, so its features are grouped alone.
    join, split : bool
        Join the pieces of one object, cut two touching objects apart (see above).
    keep_apart : bool
        With `join`, compare the union with both parts moved at once by their own shifts (a part
        narrower than ``2 * pad_px`` by its neighbour's) rather than with the parts' own fits.
    split_score : float
        Least Dice (0-1) of each part of a cut blob (measured as every blob is, padded by
        `pad_px`); each part is at least ``2 * pad_px`` columns wide.
    split_step_px : float
        Least difference of the two parts' shifts, pixels.
    split_far_px : float or None
        With a number (None: no such cut), a blob that the cut's test of each part (padded) does not cut is still cut
        when two shifts this far apart or more, one per part, lay both parts at once on the right
        image's change (one Dice over the same padded columns) better, by 0.01 or more, than the
        best single shift lays the blob, while that single shift lays it with a Dice of
        `split_far_score` or more.  Each part's padding holds its neighbour's change, which counts
        against it when two objects at different depths touch in the image; both moved at once
        do not.  Asked once per blob, not of its parts; a shift at either end of `shifts`, or a
        part moved off the right image, does not count.
    split_far_score : float
        See `split_far_px`.
    split_far_poor_px : float or None
        With a number, the test of `split_far_px` also cuts a blob that the best single shift lays
        with a Dice from `split_score` up to `split_far_score`, when two shifts this far apart or
        more lay both parts at once with `split_far_score` or more (and better, by 0.01 or more,
        than the single shift): two objects far apart in depth that touch in the image are what
        makes one shift fit them poorly (docs/experiments/2026-11-26-depth-unseen-9.md).
    split_placed : bool
        Take a cut only when its two parts, each moved by its own (padded) shift, both at once, lay
        on the right image's change at least as well (one Dice over the same padded columns) as the
        best single shift lays the blob: the halves of one object fit slightly different shifts
        each, but not better together than the whole at one.
    join_weak : bool
        With `join` and `keep_apart`, two neighbours neither of which fits with a Dice of
        `split_score` or more are joined when their union fits at least as well as the better of
        them (such pieces are no well-seen objects; a cut would not make them either).
    link_score : float or None
        With a number, blobs whose shifts differ (by `merge_disparity_px` or less) are linked only
        when one of them fits with a Dice below it: two pieces that both fit well, at shifts a pixel
        apart, are two objects (a cylinder's outline lies 1-3 px behind its front, so a cylinder
        and a box 3 px behind it can fit shifts a pixel apart).

    Returns
    -------
    Silhouettes
        Blobs numbered left to right by centroid.

    Examples
    --------
    >>> import numpy as np
    >>> from ismb_lab.io import load_pair
    >>> rng = np.random.default_rng(0)
    >>> wall = rng.uniform(0, 120, (240, 320))
    >>> left, right = wall.copy(), wall.copy()
    >>> left[100:140, 150:190] = right[100:140, 128:168] = 255.0     # an object 22 px nearer
    >>> s = silhouettes(load_pair(wall, wall), load_pair(left, right))
    >>> s.disparity.tolist(), s.score.round(2).tolist(), s.centroid_xy.round().tolist()
    ([22.0], [1.0], [[170.0, 120.0]])
    """
    options = dict(locals())        # first, so that it holds the arguments only
    from scipy.ndimage import find_objects, label
    from scipy.sparse.csgraph import connected_components

    own = "silhouettes"
    for name, value in (("background", background), ("scene", scene)):
        if not isinstance(value, StereoPair):
            raise ParameterTypeError(message(name, own, "a StereoPair", value))
    if background.shape != scene.shape:
        raise ParameterError(message("scene", own, "images of the background's size",
                                     f"images of shape {scene.shape}"))
    min_pixels = check_number(min_pixels, "min_pixels", own, low=1, integer=True)
    merge_gap_px = check_number(merge_gap_px, "merge_gap_px", own, low=0, integer=True)
    pad_px = check_number(pad_px, "pad_px", own, low=0, integer=True)
    merge_disparity_px = check_number(merge_disparity_px, "merge_disparity_px", own, low=0)
    max_fraction = check_number(max_fraction, "max_fraction", own, low=0, high=1, low_open=True)
    split_score = check_number(split_score, "split_score", own, low=0, high=1)
    split_step_px = check_number(split_step_px, "split_step_px", own, low=0)
    if split_far_px is not None:
        split_far_px = check_number(split_far_px, "split_far_px", own, low=0)
    split_far_score = check_number(split_far_score, "split_far_score", own, low=0, high=1)
    if split_far_poor_px is not None:
        split_far_poor_px = check_number(split_far_poor_px, "split_far_poor_px", own, low=0)
    if link_score is not None:
        link_score = check_number(link_score, "link_score", own, low=0, high=1)
    for name, value in (("join", join), ("split", split), ("keep_apart", keep_apart),
                        ("split_placed", split_placed), ("join_weak", join_weak), ("by_region", by_region)):
        if not isinstance(value, bool):
            raise ParameterTypeError(message(name, own, "True or False", value))
    if by_region and threshold_low is not None:
        options["by_region"] = False
        return _by_region(silhouettes(**{**options, "threshold_low": None}), silhouettes(**options))
    try:
        shifts = [int(d) for d in shifts]
    except (TypeError, ValueError):
        raise ParameterTypeError(message("shifts", own, "an iterable of whole pixels", shifts)) from None
    if not shifts:
        raise ParameterError(message("shifts", own, "at least one shift", shifts))
    shape = scene.shape
    changed = [changed_in_roi(b, c, (0, 0, shape[1], shape[0]), threshold, sigma, 0, own, "scene",
                              threshold_low)[0]
               for b, c in ((background.left, scene.left), (background.right, scene.right))]
    x, y, w, h = resolve_roi(roi, shape)
    blobs, n = label(changed[0], structure=np.ones((3, 3)))
    sizes = np.bincount(blobs.ravel(), minlength=n + 1)
    inside = np.zeros(n + 1, dtype=bool)
    inside[np.unique(blobs[y:y + h, x:x + w])] = True
    keep = (sizes >= min_pixels) & inside
    keep[0] = False
    blobs = np.where(keep[blobs], blobs, 0)

    def measure(mask):
        rows, cols = find_objects(mask.astype(int))[0]
        return (*_best_shift(mask, rows, cols, changed[1], shifts, pad_px), (rows, cols))

    ks = np.flatnonzero(keep)
    found = [measure(blobs == k) for k in ks]
    link = np.eye(len(ks), dtype=bool)
    for a, (_, da, (ra, ca)) in enumerate(found):
        for b, (_, db, (rb, cb)) in enumerate(found):
            gap = max(ra.start - rb.stop, rb.start - ra.stop, ca.start - cb.stop, cb.start - ca.stop, 0)
            near = abs(da - db) <= merge_disparity_px and gap <= merge_gap_px
            if near and da != db and link_score is not None:
                near = min(found[a][0], found[b][0]) < link_score
            link[a, b] |= near
    group = connected_components(link, directed=False)[1] if len(ks) else np.zeros(0, dtype=int)
    masks = [np.isin(blobs, ks[group == g]) for g in np.unique(group)]
    if join:
        masks = _join(masks, measure, merge_gap_px, changed[1], pad_px, keep_apart,
                      split_score if join_weak and keep_apart else None)
    if split:
        todo, masks = [(m, split_far_px) for m in masks], []
        while todo:
            part, far = todo.pop()
            whole_view = np.count_nonzero(part[y:y + h, x:x + w]) > max_fraction * w * h
            two = None if whole_view else _cut(part, changed[1], shifts, min_pixels, split_step_px,
                                               split_score, pad_px, far, split_far_score, split_placed,
                                               split_far_poor_px)
            if two is None:
                masks.append(part)
            else:
                todo += [(p, None) for p in two]      # the test of two shifts far apart: once per blob
    centroids = [np.argwhere(m).mean(axis=0)[::-1] for m in masks]
    labels = np.zeros(shape, dtype=np.int32)
    disparity, score = [], []
    order = np.argsort([c[0] for c in centroids], kind="stable")
    for k, j in enumerate(order, 1):
        labels[masks[j]] = k
        dice, d, _ = measure(masks[j])
        if np.count_nonzero(masks[j][y:y + h, x:x + w]) > max_fraction * w * h:
            dice = 0.0          # the whole view changed (another light, a moved camera): no outline
        disparity.append(d)
        score.append(dice)
    centroid = [centroids[j] for j in order]
    return Silhouettes(labels, disparity, score, np.array(centroid).reshape(-1, 2), changed[1], pad_px, shifts)


def _by_region(plain: Silhouettes, grown: Silhouettes) -> Silhouettes:
    """The blobs of `plain` or of `grown` (the same call with hysteresis), region by region.

    A region is a set of blobs of the two that overlap, directly or through others.  Each region
    keeps the blobs of the one whose blobs fit better on average (mean Dice; a tie keeps `plain`'s);
    a region that only `grown` has (an object too faint for the threshold alone) keeps `grown`'s.
    Each blob keeps its own Dice and shift.  The right image's change is `plain`'s, which the depth
    stage's cuts of a blob (:meth:`Silhouettes.cut_dice`) lay blobs on.
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
    kept.sort(key=lambda blob: blob[0].centroid_xy[blob[1], 0])      # numbered left to right, as ever
    labels = np.zeros(plain.labels.shape, dtype=np.int32)
    for number, (source, k) in enumerate(kept, 1):
        labels[source.labels == k + 1] = number
    return Silhouettes(labels, [source.disparity[k] for source, k in kept], [source.score[k] for source, k in kept],
                       np.array([source.centroid_xy[k] for source, k in kept]).reshape(-1, 2), plain.right,
                       plain.pad_px, plain.shifts)
