"""The grouping steps of :func:`ismb_lab.depth.objects.depth_from_matches` (``docs/depth.md``, 3-5)."""

from __future__ import annotations

import numpy as np

from .outlines import Silhouettes


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


def _peel(feature: np.ndarray, d: np.ndarray, config) -> list:
    """Consensus match masks of one group, largest first, each band's features removed before the
    next is sought, until a band has too few features."""
    left = np.ones(len(d), dtype=bool)
    bands = []
    while left.sum():
        inlier = np.zeros(len(d), dtype=bool)
        inlier[left] = _consensus(d[left], config.consensus_px)
        members = np.unique(feature[inlier])
        if len(members) < config.min_features:
            break
        bands.append(inlier)
        left &= ~np.isin(feature, members)
    return bands


def _merge(parts: list, config) -> list:
    """Union of parts (match rows, median disparity, left xy) that are one object: medians within
    ``merge_disparity_px`` and features within ``merge_px``."""
    n = len(parts)
    root = list(range(n))

    def find(a):
        while root[a] != a:
            a = root[a]
        return a

    for a in range(n):
        for b in range(a + 1, n):
            if abs(parts[a][1] - parts[b][1]) > config.merge_disparity_px:
                continue
            gap = np.linalg.norm(parts[a][2][:, None, :] - parts[b][2][None, :, :], axis=2).min()
            if gap <= config.merge_px:
                root[find(b)] = find(a)
    groups = {}
    for a in range(n):
        groups.setdefault(find(a), []).append(a)
    return [np.concatenate([parts[a][0] for a in members]) for members in groups.values()]


def _on_blobs(xy, silhouettes: Silhouettes, grow: int) -> np.ndarray:
    """Blob label of each left position: the blob within `grow` pixels (0: none)."""
    from scipy.ndimage import grey_dilation

    labels = silhouettes.labels
    if grow:
        # Where two grown blobs meet, a pixel goes to the one it lies on, then the larger label.
        labels = np.where(labels > 0, labels, grey_dilation(labels, size=2 * grow + 1))
    h, w = labels.shape
    ix = np.clip(np.round(xy).astype(int).reshape(-1, 2), 0, [w - 1, h - 1])
    return labels[ix[:, 1], ix[:, 0]]


def _band_cut(idx, feature, first, d, config, silhouettes: Silhouettes, k: int):
    """Blob `k` as two objects ``[(rows, centroid, shift)] * 2``, left first, by two of the three
    largest bands of its features, or None."""
    from itertools import combinations

    bands = [b for b in _peel(feature[idx], d[idx], config)
             if len(np.unique(feature[idx][b])) >= config.band_features][:3]
    for a, b in combinations(bands, 2):
        cut = _cut_between(idx[a], idx[b], feature, first, d, config, silhouettes, k)
        if cut is not None:
            return cut
    return None


def _cut_between(one, two, feature, first, d, config, silhouettes: Silhouettes, k: int):
    """:func:`_band_cut` for the bands of match rows `one` and `two`."""
    rows = [one, two]
    shift = [float(np.mean(d[r])) for r in rows]
    if abs(shift[0] - shift[1]) < config.band_step_px:
        return None
    x = [np.array([first[f][0] for f in np.unique(feature[r])]) for r in rows]
    if np.median(x[0]) > np.median(x[1]):
        rows, shift, x = rows[::-1], shift[::-1], x[::-1]
    cuts = np.unique(np.concatenate(x))
    wrong = [np.count_nonzero(x[0] >= c) + np.count_nonzero(x[1] < c) for c in cuts]
    best = int(np.argmin(wrong))
    if wrong[best] > max(1, 0.1 * (len(x[0]) + len(x[1]))):
        return None             # the bands interleave: no column between them
    below = x[0][x[0] < cuts[best]]
    hi = int(np.ceil(cuts[best]))
    lo = int(np.floor(below.max())) + 1 if len(below) else hi
    mask = silhouettes.labels == k
    own = [int(round(v)) for v in shift]
    empty = [c for c in range(lo, hi) if not mask[:, c].any()]
    cols = np.flatnonzero(mask.any(axis=0))
    wide = [c for c in range(lo, hi + 1) if min(c - cols.min(), cols.max() + 1 - c) >= 2 * silhouettes.pad_px]
    if empty:
        column = empty[len(empty) // 2]
        single = own
    elif not wide:
        return None             # one piece too narrow to cut
    else:
        # One piece: two objects that touch in the image.  The cut goes where the two shifts lay the
        # parts best, and the two must lay them firmly and better than any one shift lays the blob.
        column = max(wide, key=lambda c: silhouettes.cut_dice(k, c, own))
        if silhouettes.cut_dice(k, column, own) < config.band_one_piece:
            return None
        single = silhouettes.shifts
    # Each piece must lie better at its own band's shift than at the other's (both moved at once):
    # a piece of a striped object whose features match one period off does not.
    fit = silhouettes.cut_dice(k, column, own)
    if not fit > max(silhouettes.cut_dice(k, column, [v, v]) for v in single):
        return None
    # And each band must agree with the shift its piece's outline takes (both pieces moved at once,
    # each to its best shift), as a trusted blob's features must (``silhouette_tol_px``, either way:
    # a cylinder's outline lies behind its front).
    outline = silhouettes.cut_shifts(k, column, own)
    if max(abs(a - b) for a, b in zip(shift, outline)) > config.silhouette_tol_px:
        return None
    if not empty and abs(outline[0] - outline[1]) < config.band_step_px:
        return None             # one piece whose outline sees one shift: a cylinder's bands
    xs = np.arange(mask.shape[1])
    sides = (xs < column, xs >= column)
    centroids = [np.argwhere(mask & side[None, :]).mean(axis=0)[::-1] for side in sides]
    return [(rows[n], centroids[n], shift[n]) for n in (0, 1)]
