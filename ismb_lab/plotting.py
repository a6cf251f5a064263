"""Matplotlib drawings of the pipeline's results: each draws into a given ``Axes`` (never
``pyplot``) and returns its artists."""

from __future__ import annotations

import numpy as np

__all__ = ["GAP", "LEFT_COLOUR", "OKABE_ITO", "RIGHT_COLOUR", "VERDICT_COLOURS", "outlines", "plot_depth",
           "plot_matches", "side_by_side", "verdicts"]

GAP = 8  # pixels between the left and right image in side-by-side views

#: Okabe and Ito's palette (*Color Universal Design*, 2008): told apart with every colour-vision deficiency.
OKABE_ITO = {"black": "#000000", "orange": "#E69F00", "sky blue": "#56B4E9", "bluish green": "#009E73",
             "yellow": "#F0E442", "blue": "#0072B2", "vermillion": "#D55E00", "reddish purple": "#CC79A7"}

#: A match's verdict against the targets (:func:`verdicts`): never red against green.
VERDICT_COLOURS = {"correct": OKABE_ITO["blue"], "wrong partner": OKABE_ITO["vermillion"],
                   "extra": OKABE_ITO["reddish purple"]}

#: Left and right features in every side-by-side view.
LEFT_COLOUR, RIGHT_COLOUR = OKABE_ITO["yellow"], OKABE_ITO["bluish green"]


def verdicts(pairs, targets, unknown=()) -> list:
    """Each matched pair's verdict as :func:`ismb_lab.tuning.evaluation.score` counts it
    (None: its left feature's truth is unknown).

    >>> verdicts([[0, 0], [1, 2], [3, 3], [4, 4]], [[0, 0], [1, 1]], unknown=[4])
    ['correct', 'wrong partner', 'extra', None]
    """
    from .tuning.evaluation import Scorer

    pairs = np.asarray(pairs, int).reshape(-1, 2)
    names = (None, "correct", "wrong partner", "extra")     # Scorer.neuron_codes' codes 0-3
    return [names[code] for code in Scorer(targets, unknown).neuron_codes(pairs[:, 0], pairs[:, 1])]


def side_by_side(left: np.ndarray, right: np.ndarray, gap: int = GAP) -> np.ndarray:
    """The two images next to each other, separated by a white gap.

    >>> side_by_side(np.zeros((2, 3)), np.ones((2, 3)), gap=1).shape
    (2, 7)
    """
    return np.hstack([left, np.full((left.shape[0], gap), 255.0), right])


def plot_matches(ax, left, right, left_xy, right_xy, pairs, *, numbers: bool = True,
                 cmap: str = "viridis", targets=None, unknown=()) -> dict:
    """Draw a pair side by side with its features (``(N, 2)`` points, the right ones offset by
    ``W + GAP``) and lines for the matched ``(i, k)`` `pairs`, coloured by Euclidean disparity or
    by their :func:`verdicts` against `targets` (grey where `unknown`); `numbers` labels features
    1, 2, ... as in the thesis' figures.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where to draw.
    left, right : (H, W) float ndarray
        The grey images.
    left_xy, right_xy : (N, 2) float array_like
        Left and right features ``(x, y)``.
    pairs : (m, 2) int array_like
        Matched ``(i, k)`` feature pairs.
    numbers : bool, default True
        Label the features 1, 2, ...
    cmap : str, default "viridis"
        Colour map of the disparity, without `targets`.
    targets : (n, 2) int array_like, optional
        Target pairs: lines are then coloured by verdict.
    unknown : int array_like, optional
        Left features whose truth is unknown (grey lines).

    Returns
    -------
    artists : dict
        ``image``, ``left_points``, ``right_points``, ``lines`` and ``labels``.
    """
    from matplotlib.collections import LineCollection

    from .images.coords import euclidean_disparity

    left_xy = np.asarray(left_xy, float).reshape(-1, 2)
    right_xy = np.asarray(right_xy, float).reshape(-1, 2)
    pairs = np.asarray(pairs, int).reshape(-1, 2)
    shifted = right_xy + [left.shape[1] + GAP, 0.0]
    image = ax.imshow(side_by_side(left, right), cmap="gray", vmin=0, vmax=255)
    lp, = ax.plot(*left_xy.T, "+", color=LEFT_COLOUR, ms=8, mew=1.5)
    rp, = ax.plot(*shifted.T, "+", color=RIGHT_COLOUR, ms=8, mew=1.5)
    segments = np.stack([left_xy[pairs[:, 0]], shifted[pairs[:, 1]]], axis=1)
    if targets is not None:
        kinds = verdicts(pairs, targets, unknown)
        # the correct lines first: an error (often a corner's second match) is drawn on top
        order = sorted(range(len(kinds)), key=lambda n: kinds[n] != "correct")
        lines = LineCollection(segments[order], linewidths=1.5,
                               colors=[VERDICT_COLOURS.get(kinds[n], "0.6") for n in order])
    else:
        lines = LineCollection(segments, cmap=cmap, linewidths=1.2)
        if len(pairs):
            lines.set_array(euclidean_disparity(left_xy[pairs[:, 0]], right_xy[pairs[:, 1]]))
    ax.add_collection(lines)
    labels = []
    if numbers:
        for xy, colour in ((left_xy, LEFT_COLOUR), (shifted, RIGHT_COLOUR)):
            labels += [ax.text(x + 2, y - 2, str(n), color=colour, fontsize=7)
                       for n, (x, y) in enumerate(xy, 1)]
    ax.set_axis_off()
    return {"image": image, "left_points": lp, "right_points": rp, "lines": lines, "labels": labels}


def outlines(labels: np.ndarray) -> list:
    """The outer outline of every blob of `labels` (> 0) as a closed polygon of pixel centres.

    Parameters
    ----------
    labels : (H, W) int ndarray
        Blob labels, 0 for none.

    Returns
    -------
    polygons : list of (n, 2) float ndarray
        One closed ``(x, y)`` polygon per outline.

    Examples
    --------
    >>> labels = np.zeros((6, 6), dtype=int)
    >>> labels[1:4, 2:5] = 1
    >>> [p.tolist() for p in outlines(labels)]
    [[[2.0, 1.0], [2.0, 3.0], [4.0, 3.0], [4.0, 1.0], [2.0, 1.0]]]
    """
    import cv2

    labels = np.asarray(labels)
    polygons = []
    for k in np.unique(labels[labels > 0]):
        found, _ = cv2.findContours((labels == k).astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        polygons += [np.vstack([c[:, 0, :], c[:1, 0, :]]).astype(float) for c in found]
    return polygons


def plot_depth(ax, left, result, *, cmap: str = "plasma") -> dict:
    """Draw Fig. 5.14: the scene's left image (`left`), the new features of `result` (a
    :class:`~ismb_lab.depth.objects.DepthResult`) by disparity, the removed ones as grey crosses,
    each object's rank and depth, the dashed box where corners were sought and the cyan blobs.

    Returns the artists: ``image``, ``features``, ``removed``, ``labels``, ``box`` (None without
    ``result.scene_roi``) and ``outlines`` (None without ``result.silhouettes``).
    """
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Rectangle

    image = ax.imshow(left, cmap="gray", vmin=0, vmax=255)

    drawn = None
    if getattr(result, "silhouettes", None) is not None:
        drawn = ax.add_collection(LineCollection(outlines(result.silhouettes.labels), colors=OKABE_ITO["sky blue"],
                                                 linewidths=0.8))
    removed, = ax.plot(*np.asarray(result.removed_xy).reshape(-1, 2).T, "x", color="0.6", ms=5)
    xy = np.asarray(result.kept_xy).reshape(-1, 2)
    features = ax.scatter(xy[:, 0], xy[:, 1], c=result.kept_disparity, cmap=cmap, s=28,
                          edgecolors="white", linewidths=0.5)
    labels = []
    for obj in result.objects:
        depth = f"{obj.depth_m:.2f} m" if obj.depth_m is not None else obj.depth.status
        x, y = obj.centroid_xy
        labels.append(ax.text(x, y - 8, f"#{obj.rank} {depth}\nd={obj.mean_disparity:.1f}",
                              color=OKABE_ITO["yellow"], fontsize=7, ha="center", va="bottom"))
    box = None
    if result.scene_roi is not None:
        x, y, w, h = result.scene_roi
        box = ax.add_patch(Rectangle((x - 0.5, y - 0.5), w, h, fill=False, ec=OKABE_ITO["yellow"], lw=0.8, ls="--"))
    ax.set_axis_off()
    return {"image": image, "features": features, "removed": removed, "labels": labels, "box": box,
            "outlines": drawn}

