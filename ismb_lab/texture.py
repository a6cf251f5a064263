"""The texture inside a blob of change: census costs per column, and the shifts they give.

A blob's outline (:func:`ismb_lab.silhouettes.silhouettes`) does not depend on texture, which
makes it robust to stripes, but it is blunt.  Two objects 3-4 px apart that touch in the image fit
shifts 1-2 px apart, and a narrow or poorly seen object can fit a wrong shift outright.  The
texture inside the blob measures its surface column by column.  A census transform (each pixel's
order against its 5 x 5 neighbours, robust to the cameras' gain and offset) is compared at each
shift, and the Hamming distance is averaged down each column of the blob.  Stripes repeat, so the
texture alone can pick a shift one period off.  :func:`textured` therefore lets
it decide only with the outline:

* **a cut** where the texture steps by ``step_px`` or more, near the shift the outline fits.  Each
  part then takes the shift that its texture and its outline agree on best.  That shift must
  confirm the step, and both parts at those shifts must lie on the right image's change nearly as
  well as the best single shift lays the whole;
* **a poorly fitting outline** (Dice below ``poor``) takes the shift that its texture and its
  outline agree on best.

:func:`ismb_lab.depth_demo.pair_silhouettes` applies it only when asked (``texture_gain=0.09,
texture_poor=0.9`` were tried): on the development layouts it fixed four that the defaults rank
wrong, but on a held-out draw it fixed none and cut a cylinder in two, whose front is nearer than
its sides.

Reference: R. Zabih and J. Woodfill, "Non-parametric local transforms for computing visual
correspondence", ECCV 1994 (the census transform).  The rules and their figures are in
docs/experiments/2026-11-26-depth-unseen-7.md.
"""

from __future__ import annotations

import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_number, message

__all__ = ["census", "column_costs", "two_shifts", "textured"]

_BITS = np.array([bin(v).count("1") for v in range(256)], dtype=np.uint8)


def census(image, radius: int = 2) -> np.ndarray:
    """The census transform: for each pixel, which of its ``(2r+1)**2 - 1`` neighbours are brighter.

    Parameters
    ----------
    image : (H, W) array_like
        Grey values.
    radius : int
        Half the window's side; the border is extended by its edge values.

    Returns
    -------
    (H, W, B) uint8 ndarray
        The bits, packed (``B = ceil(((2r+1)**2 - 1) / 8)``); compare two with :func:`column_costs`.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.zeros((5, 5)); image[2, 3] = 9.0
    >>> bits = np.unpackbits(census(image, 1)[2, 2])[:8]
    >>> bits.tolist()              # neighbours row by row; only the one to the right is brighter
    [0, 0, 0, 0, 1, 0, 0, 0]
    """
    image = np.asarray(image, dtype=float)
    if image.ndim != 2:
        raise ParameterError(message("image", "census", "a 2-D grey image", f"shape {image.shape}"))
    h, w = image.shape
    padded = np.pad(image, radius, mode="edge")
    bits = [padded[radius + dy:radius + dy + h, radius + dx:radius + dx + w] > image
            for dy in range(-radius, radius + 1) for dx in range(-radius, radius + 1) if dy or dx]
    return np.packbits(np.stack(bits, axis=-1), axis=-1)


def column_costs(left, right, mask, shifts, erode: int = 2, least: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """Mean Hamming distance down each column of `mask` between `left`'s census and `right`'s, moved.

    Parameters
    ----------
    left, right : (H, W, B) uint8 ndarray
        :func:`census` of the left and the right image.
    mask : (H, W) bool ndarray
        The blob, in the left image.  It is first eroded by `erode` pixels sideways (its edges
        see the wall behind, which moves differently).
    shifts : sequence of int
        Disparities: the left pixel ``(y, x)`` is compared with the right pixel ``(y, x - d)``.
    least : int
        Columns with fewer pixels of the eroded blob are left out.

    Returns
    -------
    cols : (n,) int ndarray
        The columns kept.
    costs : (n, len(shifts)) ndarray
        The mean distance, nan where the moved column leaves the right image.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(1)
    >>> wall = rng.uniform(0, 255, (30, 80))
    >>> mask = np.zeros((30, 80), dtype=bool); mask[5:25, 40:60] = True
    >>> cols, costs = column_costs(census(wall[:, :-4]), census(wall[:, 4:]), mask[:, 4:], range(8))
    >>> int(np.argmin(costs.mean(axis=0)))             # the right image is the left moved 4 px
    4
    """
    from scipy.ndimage import binary_erosion

    own = "column_costs"
    for name, value in (("left", left), ("right", right)):
        if not (isinstance(value, np.ndarray) and value.ndim == 3 and value.dtype == np.uint8):
            raise ParameterTypeError(message(name, own, "a census (an (H, W, B) uint8 array)", value))
    if left.shape != right.shape:
        raise ParameterError(message("right", own, f"a census of the left one's shape {left.shape}",
                                     f"shape {right.shape}"))
    mask = np.asarray(mask, dtype=bool)
    if mask.shape != left.shape[:2]:
        raise ParameterError(message("mask", own, f"a mask of the images' shape {left.shape[:2]}",
                                     f"shape {mask.shape}"))
    erode = check_number(erode, "erode", own, low=0, integer=True)
    least = check_number(least, "least", own, low=1, integer=True)
    shifts = [int(check_number(d, "shifts", own, integer=True)) for d in shifts]
    if erode:
        mask = binary_erosion(mask, np.ones((1, 2 * erode + 1), dtype=bool))
    counts = mask.sum(axis=0)
    cols = np.flatnonzero(counts >= least)
    width = left.shape[1]
    rows, xs = np.nonzero(mask[:, cols])
    costs = np.full((len(cols), len(shifts)), np.nan)
    for j, d in enumerate(shifts):
        inside = (cols - d >= 0) & (cols - d < width)
        keep = inside[xs]
        x = cols[xs[keep]]
        far = _BITS[left[rows[keep], x] ^ right[rows[keep], x - d]].sum(axis=-1)
        sums = np.bincount(xs[keep], weights=far, minlength=len(cols))
        costs[inside, j] = sums[inside] / counts[cols[inside]]
    return cols, costs


def two_shifts(costs, wide: int = 16):
    """One shift for all columns against two with a cut between them: the columns' best cut.

    Parameters
    ----------
    costs : (n, m) ndarray
        :func:`column_costs`, columns left to right, without nan.
    wide : int
        Least columns on each side of the cut.

    Returns
    -------
    tuple or None
        ``(gain, cut, a, b)``: the share of the one shift's summed cost that the cut removes, the
        index of the cut's first right column, and the shift indices left and right of it; None
        for fewer than ``2 * wide`` columns.

    Examples
    --------
    >>> import numpy as np
    >>> costs = np.ones((40, 3)); costs[:25, 0] = costs[25:, 2] = 0.0
    >>> two_shifts(costs, wide=10)
    (1.0, 25, 0, 2)
    """
    costs = np.asarray(costs, dtype=float)
    if costs.ndim != 2 or np.isnan(costs).any():
        raise ParameterError(message("costs", "two_shifts", "a 2-D array of costs without nan",
                                     f"shape {costs.shape}"))
    wide = check_number(wide, "wide", "two_shifts", low=1, integer=True)
    n = len(costs)
    if n < 2 * wide:
        return None
    one = costs.sum(axis=0).min()
    prefix = np.vstack([np.zeros(costs.shape[1]), np.cumsum(costs, axis=0)])
    best = None
    for j in range(wide, n - wide + 1):
        a, b = prefix[j], prefix[n] - prefix[j]
        ia, ib = int(np.argmin(a)), int(np.argmin(b))
        if best is None or a[ia] + b[ib] < best[0]:
            best = (a[ia] + b[ib], j, ia, ib)
    total, j, ia, ib = best
    return float((one - total) / one) if one else 0.0, j, ia, ib


def _agreed(left, right, part, silhouettes):
    """The shift (over :attr:`~ismb_lab.silhouettes.Silhouettes.shifts`) that minimises a part's
    census cost, relative to its best, plus one minus its outline's Dice; and that Dice.  None when
    no column of the part is measured at every shift."""
    from ._outline_fit import _placed_dice

    shifts = list(silhouettes.shifts)
    _, costs = column_costs(left, right, part, shifts)
    costs = costs[~np.isnan(costs).any(axis=1)]
    if not len(costs):
        return None
    total = costs.sum(axis=0)
    low = total.min()
    excess = total / low - 1 if low > 0 else np.where(total > 0, np.inf, 0.0)
    dice = np.array([_placed_dice([part], [d], silhouettes.right, silhouettes.pad_px) for d in shifts])
    j = int(np.argmin(excess + (1 - dice)))
    return shifts[j], float(dice[j])


def _cut(s, k, mask, codes, near, gain, step_px, wide, slack):
    """Blob `k`'s two parts and their agreed ``(shift, Dice)`` where its texture steps (see
    :func:`textured`), or None."""
    cols, costs = column_costs(*codes, mask, near)
    fine = ~np.isnan(costs).any(axis=1)
    step = two_shifts(costs[fine], wide)
    if step is None or step[0] < gain or abs(near[step[2]] - near[step[3]]) < step_px:
        return None
    cut = int(cols[fine][step[1]])
    left = mask.copy()
    left[:, cut:] = False
    parts = [left, mask & ~left]
    agreed = [_agreed(*codes, p, s) for p in parts]
    if None in agreed or abs(agreed[0][0] - agreed[1][0]) < step_px:
        return None
    if abs(agreed[0][0] - near[step[2]]) > 1 or abs(agreed[1][0] - near[step[3]]) > 1:
        return None             # the texture's step and the parts' own shifts disagree
    single = max(s.cut_dice(k, cut, (d, d)) for d in s.shifts)
    if s.cut_dice(k, cut, (agreed[0][0], agreed[1][0])) < single - slack:
        return None
    return parts, agreed


def textured(silhouettes, scene, *, gain: float | None = 0.09, step_px: float = 3.0,
             poor: float | None = 0.9, window=(-4, 6), wide: int = 16, slack: float = 0.01):
    """`silhouettes` with blobs cut, and poorly fitting outlines moved, where the texture says so.

    Parameters
    ----------
    silhouettes : Silhouettes
        Of `scene`, with its right image's change.
    scene : StereoPair
        The pair whose texture is compared.
    gain, step_px, window, wide : float or None, float, (int, int), int
        With a `gain` (None: no cut), a blob with an outline is cut where its columns' census
        costs, over the shifts from its outline's plus ``window[0]`` to plus ``window[1]``, fall
        by a share `gain` or more with two shifts `step_px` or more apart (:func:`two_shifts`,
        each side `wide` columns or more).
        Each part's shift must then be, by its texture and its outline together, within 1 px of
        the cut's and `step_px` or more from the other part's, and both parts moved at once by those
        shifts must lie within `slack` (Dice) of the best single shift's fit.
    poor : float or None
        A blob that is not cut and whose outline fits with a Dice below this takes the shift of its
        texture and its outline together; None: no such move.

    Returns
    -------
    Silhouettes
        The same when nothing changed; else blobs numbered again left to right, a part's or a moved
        blob's disparity and score being the shift its texture and outline agree on and the Dice
        there.
    """
    from .io import StereoPair
    from .silhouettes import Silhouettes

    own = "textured"
    if not isinstance(silhouettes, Silhouettes) or silhouettes.right is None:
        raise ParameterTypeError(message("silhouettes", own, "Silhouettes with the right image's change",
                                         silhouettes))
    if not isinstance(scene, StereoPair) or scene.shape != silhouettes.labels.shape:
        raise ParameterTypeError(message("scene", own, f"a StereoPair of shape {silhouettes.labels.shape}",
                                         scene))
    gain = None if gain is None else check_number(gain, "gain", own, low=0, high=1)
    poor = None if poor is None else check_number(poor, "poor", own, low=0, high=1)
    step_px = check_number(step_px, "step_px", own, low=0)
    slack = check_number(slack, "slack", own, low=0, high=1)
    wide = check_number(wide, "wide", own, low=1, integer=True)
    try:
        low, high = (int(check_number(v, "window", own, integer=True)) for v in window)
    except (TypeError, ValueError):
        raise ParameterTypeError(message("window", own, "two whole pixels (low, high)", window)) from None
    if low > high:
        raise ParameterError(message("window", own, "low <= high", window))
    s = silhouettes
    codes = []          # both images' census, made when first needed
    masks, given, changed = [], [], False
    for k in range(1, len(s) + 1):
        mask = s.labels == k
        dk, score = float(s.disparity[k - 1]), float(s.score[k - 1])
        kept = None
        if score > 0 and not np.isnan(dk) and (gain is not None or (poor is not None and score < poor)):
            codes = codes or [census(scene.left), census(scene.right)]
            if gain is not None:
                near = [d for d in s.shifts if int(dk) + low <= d <= int(dk) + high]
                kept = _cut(s, k, mask, codes, near, gain, step_px, wide, slack)
            if kept is None and poor is not None and score < poor:
                moved = _agreed(*codes, mask, s)
                if moved is not None and moved[0] != dk:
                    kept = ([mask], [moved])
        if kept is None:
            masks.append(mask)
            given.append((dk, score))
        else:
            masks += kept[0]
            given += kept[1]
            changed = True
    if not changed:
        return s
    centroids = [np.argwhere(m).mean(axis=0)[::-1] for m in masks]
    labels = np.zeros(s.labels.shape, dtype=np.int32)
    disparity, scores, order = [], [], np.argsort([c[0] for c in centroids], kind="stable")
    for k, j in enumerate(order, 1):
        labels[masks[j]] = k
        disparity.append(given[j][0])
        scores.append(given[j][1])
    return Silhouettes(labels, disparity, scores, np.array([centroids[j] for j in order]).reshape(-1, 2),
                       s.right, s.pad_px, s.shifts)
