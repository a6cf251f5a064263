"""How well blobs of change lie on the right image's change: the fits, cuts and joins of
:func:`ismb_lab.depth.outlines.silhouettes`."""

from __future__ import annotations

import numpy as np

def _best_shift(mask: np.ndarray, rows: slice, cols: slice, right: np.ndarray, shifts,
                pad: int) -> tuple[float, float]:
    """The Dice overlap and the shift ``d`` that lays blob `mask` (box `rows` x `cols`) best on
    `right` shifted by ``d`` (ties: the first in `shifts`).

    Counted over the box widened by `pad` columns, where both images have columns: without the
    padding a blob at the image's left edge fits every shift from its true one up equally well."""
    width = right.shape[1]
    c = np.arange(max(cols.start - pad, 0), min(cols.stop + pad, width))
    mine = mask[rows, c.min():c.max() + 1]
    best = (0.0, float("nan"))
    for d in shifts:
        valid = (c - d >= 0) & (c - d < width)
        m = mine[:, valid]
        patch = right[rows, c[valid] - d]
        total = np.count_nonzero(m) + np.count_nonzero(patch)
        dice = 2 * np.count_nonzero(m & patch) / total if total else 0.0
        if dice > best[0]:
            best = (dice, float(d))
    return best


def _two_shifts(parts, start, one: float, right: np.ndarray, shifts, config) -> bool:
    """Whether two shifts ``split_far_px`` or more apart, one per part (by :func:`_ascend` from
    `start`), lay `parts` better than `one`, the whole's best Dice at one shift, by 0.01.

    `one` must be ``split_far_score`` or more, or else ``split_score`` or more with the shifts
    ``split_far_poor_px`` apart laying both parts with ``split_far_score``; each part must lie
    wholly on the right image (a part across the border fits any shift)."""
    least, fair = config.split_far_score, config.split_score
    best, d = _ascend(parts, start, right, shifts, config.pad_px)
    if abs(d[0] - d[1]) < config.split_far_px:
        return False
    if any(np.nonzero(part)[1].min() - s < 0 for part, s in zip(parts, d)):
        return False
    if one >= least:
        return best >= one + 0.01
    return one >= fair and abs(d[0] - d[1]) >= config.split_far_poor_px and best >= least and best >= one + 0.01


def _cut(mask: np.ndarray, right: np.ndarray, shifts, config, far: bool):
    """The two parts of `mask`, cut at the column where two shifts lay them on `right` better than
    one shift lays the whole, or None.

    The shifts must differ by ``split_step_px`` or more, each part fit (:func:`_best_shift`) with
    ``split_score`` or more, and both parts at once lay no worse than the whole at one shift; with
    `far`, :func:`_two_shifts` may cut it otherwise.  Per-column counts summed cumulatively give
    every cut's Dice at once."""
    from scipy.ndimage import find_objects

    min_pixels, step, least, pad = config.min_pixels, config.split_step_px, config.split_score, config.pad_px

    rows, cols = find_objects(mask.astype(int))[0]
    width = right.shape[1]
    c = np.arange(cols.start, cols.stop)
    m = mask[rows, cols]
    shifts = np.asarray(shifts)
    a = np.zeros((len(shifts), len(c)))
    b = np.zeros_like(a)
    inter = np.zeros_like(a)
    for k, d in enumerate(shifts):
        valid = (c - d >= 0) & (c - d < width)
        patch = right[rows, np.clip(c - d, 0, width - 1)]
        a[k] = np.where(valid, m.sum(axis=0), 0)
        b[k] = np.where(valid, patch.sum(axis=0), 0)
        inter[k] = np.where(valid, (m & patch).sum(axis=0), 0)
    count = np.concatenate([[0], np.cumsum(m.sum(axis=0))])
    cum = [np.concatenate([np.zeros((len(shifts), 1)), np.cumsum(v, axis=1)], axis=1) for v in (a, b, inter)]

    def best(lo, hi):
        """Best shift index, overlap and (blob + right) counts of columns lo..hi-1."""
        ai, bi, ii = (v[:, hi] - v[:, lo] for v in cum)
        ok = 2 * ai >= count[hi] - count[lo]        # most of the part on the right image
        dice = np.where(ok & (ai + bi > 0), 2 * ii / np.maximum(ai + bi, 1), 0.0)
        k = int(np.argmax(dice))
        return k, ii[k], ai[k] + bi[k], dice[k]

    n = len(c)
    whole = best(0, n)[3]
    top = None
    for x in range(1, n):
        if min(count[x], count[n] - count[x]) < min_pixels or min(x, n - x) < 2 * pad:
            continue            # a sliver narrower than both paddings can fit almost any shift
        kl, il, tl, dl = best(0, x)
        kr, ir, tr, dr = best(x, n)
        score = 2 * (il + ir) / max(tl + tr, 1)
        if (abs(shifts[kl] - shifts[kr]) >= step and min(dl, dr) >= least
                and (top is None or score > top[0])):
            top = (score, x)
    if top is None or top[0] < whole:
        return None
    left = mask.copy()
    left[:, cols.start + top[1]:] = False
    parts = left, mask & ~left
    # Then the test every blob passes (padded), since a thin sliver, or a piece of stripes, can
    # fit its own columns at almost any shift.
    fits = [_best_shift(part, *find_objects(part.astype(int))[0], right, shifts, pad) for part in parts]
    own = [f[1] for f in fits]
    if any(np.isnan(d) for d in own):
        return None             # a part that fits no shift: no cut, by any test below
    one = max(_placed_dice([mask], [s], right, pad) for s in shifts)   # the whole at one shift
    if _placed_dice(parts, own, right, pad) < one:
        return None             # each part at its own shift, both at once, lay worse than one shift
    if min(f[0] for f in fits) >= least and abs(fits[0][1] - fits[1][1]) >= step:
        return parts
    # Each part's padding holds its neighbour's change, which counts against it when two objects
    # touch: then ask whether two shifts far apart lay both parts at once better than one shift.
    if not far:
        return None
    return parts if _two_shifts(parts, own, one, right, shifts, config) else None


def _ascend(parts, start, right: np.ndarray, shifts, pad: int, line=None) -> tuple[float, list]:
    """The best :func:`_placed_dice` of two `parts` and their shifts: coordinate ascent over
    `shifts` from `start`, each part in turn, for at most three rounds."""
    d = list(start)
    best = _placed_dice(parts, d, right, pad, line)
    for _ in range(3):
        moved = False
        for k in (0, 1):
            for s in shifts:
                trial = list(d)
                trial[k] = s
                score = _placed_dice(parts, trial, right, pad, line)
                if score > best + 1e-12:
                    best, d, moved = score, trial, True
        if not moved:
            break
    return best, d


def _placed_dice(parts, shifts, right: np.ndarray, pad: int, line=None) -> float:
    """Dice overlap of `parts`, each moved left by its shift, with `right`, over their rows and
    padded columns; with `line`, the moved parts are closed by it first."""
    width = right.shape[1]
    placed = np.zeros_like(right)
    for part, d in zip(parts, shifts):
        rows, cols = np.nonzero(part)
        keep = (cols - int(d) >= 0) & (cols - int(d) < width)
        placed[rows[keep], cols[keep] - int(d)] = True
    if line is not None and placed.any():
        from scipy.ndimage import binary_closing

        # Closed within the placed pixels' columns and a margin wider than the line, which gives
        # what closing the whole image gives at a fraction of the cost.
        cols = np.flatnonzero(placed.any(axis=0))
        margin = 2 * line.shape[1]
        c = slice(max(cols[0] - margin, 0), min(cols[-1] + 1 + margin, width))
        placed[:, c] |= binary_closing(placed[:, c], line)
    rows, cols = np.nonzero(placed)
    if not len(rows):
        return 0.0
    r = slice(rows.min(), rows.max() + 1)
    c = slice(max(cols.min() - pad, 0), min(cols.max() + 1 + pad, width))
    mine, theirs = placed[r, c], right[r, c]
    total = np.count_nonzero(mine) + np.count_nonzero(theirs)
    return 2 * np.count_nonzero(mine & theirs) / total if total else 0.0


def _join(masks: list, measure, gap_px: int, right: np.ndarray, pad: int, weak: float) -> list:
    """Join neighbouring blobs (boxes `gap_px` or less apart), best pair first, while one shift
    lays their union at least as well as their own shifts, both at once, lay them.

    A part narrower than ``2 * pad`` fits almost any shift, so it takes its neighbour's.  Two
    neighbours that both fit below `weak` are joined when the union fits as well as the better."""
    fits = [measure(m) for m in masks]
    keys = [frozenset([k]) for k in range(len(masks))]
    unions = {}
    while len(masks) > 1:
        best = None
        for a in range(len(masks)):
            for b in range(a + 1, len(masks)):
                (ra, ca), (rb, cb) = fits[a][2], fits[b][2]
                gap = max(ra.start - rb.stop, rb.start - ra.stop, ca.start - cb.stop, cb.start - ca.stop, 0)
                if gap > gap_px:
                    continue
                key = keys[a] | keys[b]
                if key not in unions:
                    unions[key] = measure(masks[a] | masks[b])
                union = unions[key]
                if np.isnan(union[1]):
                    continue            # the union has no shift: nothing to compare
                own = [fits[a][1], fits[b][1]]
                loose = [bool(ca.stop - ca.start < 2 * pad or np.isnan(own[0])),
                         bool(cb.stop - cb.start < 2 * pad or np.isnan(own[1]))]
                if all(loose):
                    own = [union[1], union[1]]
                elif any(loose):
                    own = [own[loose[0]]] * 2       # the firm part's shift for both
                margin = (_placed_dice([masks[a] | masks[b]], [union[1]], right, pad)
                          - _placed_dice([masks[a], masks[b]], own, right, pad))
                if max(fits[a][0], fits[b][0]) < weak:
                    margin = max(margin, union[0] - max(fits[a][0], fits[b][0]))
                if margin >= 0 and (best is None or margin > best[0]):
                    best = (margin, a, b, union)
        if best is None:
            return masks
        _, a, b, union = best
        masks[a] = masks[a] | masks[b]
        fits[a], keys[a] = union, keys[a] | keys[b]
        del masks[b], fits[b], keys[b]
    return masks
