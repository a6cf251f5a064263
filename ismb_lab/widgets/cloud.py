"""The matched points in 3-D: a :class:`Cloud` (the model, plain numbers) and its rotatable k3d
view :class:`PointCloudView`, both cameras drawn.

Frame: metres, X right, Y down, Z forward from the left camera; the plot shows ``(X, Z, -Y)``.
"""

from __future__ import annotations

import html
from dataclasses import dataclass, field

import ipywidgets
import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, message, readonly
from ..cameras.camera import StereoCamera
from ._common import check_type, with_class

__all__ = ["AXIS_TITLES", "Cloud", "MAX_NOTES", "MAX_TICKS", "PointCloudView", "axes_frame", "axis_ticks", "board_cloud",
           "colour_bar_html", "depth_cloud", "frustum_edges", "match_cloud"]

#: How many notes (e.g. ``#1 0.89 m`` beside an object) a view can show at once.
MAX_NOTES = 6


def frustum_edges(centres, corners_xyz) -> tuple[np.ndarray, np.ndarray]:
    """A pyramid per camera centre (``(K, 3)``): apex at it, base the image's 4 corners
    `corners_xyz` (``(4, 3)``, in order around the image, relative to a centre).

    Returns ``(5 K, 3)`` float32 vertices and ``(8 K, 2)`` uint32 edges (4 from the apex, 4 around).

    >>> v, s = frustum_edges([[0, 0, 0], [0.1, 0, 0]], [[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]])
    >>> v.shape, s.shape, s[:5].tolist()
    ((10, 3), (16, 2), [[0, 1], [0, 2], [0, 3], [0, 4], [1, 2]])
    """
    centres = np.asarray(centres, dtype=float).reshape(-1, 3)
    corners = np.asarray(corners_xyz, dtype=float).reshape(4, 3)
    if not len(centres):
        return np.zeros((0, 3), np.float32), np.zeros((0, 2), np.uint32)
    one = np.array([[0, 1], [0, 2], [0, 3], [0, 4], [1, 2], [2, 3], [3, 4], [4, 1]])
    vertices = np.concatenate([np.vstack([c, c + corners]) for c in centres])
    segments = np.concatenate([one + 5 * k for k in range(len(centres))])
    return vertices.astype(np.float32), segments.astype(np.uint32)


@dataclass(frozen=True)
class Cloud:
    """What a point-cloud view shows.

    Parameters
    ----------
    points : (N, 3) array
        Finite points, metres, in the rectified left camera's frame.
    centres : (2, 3) array
        The left and the right camera centre.
    frustum : (4, 3) array
        The image's corners relative to a camera centre, at the depth the cameras are drawn.
    colour : (N,) array, optional
        What each point is coloured by; None: its depth Z.
    notes : tuple of (str, (x, y, z))
        Short texts placed in 3-D (at most :data:`MAX_NOTES`).

    >>> c = Cloud([[0, 0, 1.0]], [[0, 0, 0], [0.1, 0, 0]], np.ones((4, 3)))
    >>> c.colour.tolist(), c.depth_range
    ([1.0], (1.0, 1.0))
    """

    points: np.ndarray
    centres: np.ndarray
    frustum: np.ndarray
    colour: np.ndarray | None = None
    notes: tuple = ()
    caption: str = ""
    depth_range: tuple = field(init=False)

    def __post_init__(self):
        owner = "Cloud"
        for name, shape in (("points", (-1, 3)), ("centres", (2, 3)), ("frustum", (4, 3))):
            value = getattr(self, name)
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                raise ParameterTypeError(message(name, owner, f"an array of shape {shape}", value)) from None
            if name == "points" and arr.size == 0:
                arr = arr.reshape(0, 3)
            if arr.ndim != 2 or arr.shape[1] != 3 or (shape[0] > 0 and arr.shape[0] != shape[0]):
                raise ParameterError(message(name, owner, f"an array of shape {shape}", f"shape {arr.shape}"))
            if not np.isfinite(arr).all():
                raise ParameterError(message(name, owner, "finite numbers", "NaN or infinite values"))
            object.__setattr__(self, name, readonly(arr))
        colour = self.points[:, 2] if self.colour is None else np.asarray(self.colour, dtype=float).ravel()
        if colour.shape != (len(self.points),) or not np.isfinite(colour).all():
            raise ParameterError(message("colour", owner, f"None or {len(self.points)} finite numbers",
                                         f"shape {colour.shape}"))
        object.__setattr__(self, "colour", readonly(colour))
        if not isinstance(self.notes, tuple) or len(self.notes) > MAX_NOTES:
            raise ParameterError(message("notes", owner, f"a tuple of at most {MAX_NOTES} (text, xyz)", self.notes))
        check_type(self.caption, str, "caption", owner, "a str")
        lo, hi = (float(colour.min()), float(colour.max())) if len(colour) else (0.0, 1.0)
        object.__setattr__(self, "depth_range", (lo, hi))


def _cloud(camera: StereoCamera, points, notes, caption: str) -> Cloud:
    """`points` of `camera`'s rectified left frame that have a place (a NaN row: a disparity
    <= 0), the cameras drawn 0.6 baselines deep, each note ``(text, xy, disparity)`` placed."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    ok = np.isfinite(points).all(axis=1)
    w, h = camera.size
    corners = np.array([[0, 0], [w - 1, 0], [w - 1, h - 1], [0, h - 1]], dtype=float)
    frustum = camera.points_from_disparity(corners, np.full(4, camera.focal_px / 0.6))   # Z = 0.6 B
    placed = tuple((text, tuple(float(v) for v in camera.points_from_disparity([at_xy], [d])[0]))
                   for text, at_xy, d in notes if d > 0)
    if not ok.all():
        caption += f"; {int((~ok).sum())} match(es) with disparity <= 0 left out"
    return Cloud(points[ok], [[0, 0, 0], [camera.baseline_m, 0, 0]], frustum, notes=placed[:MAX_NOTES],
                 caption=caption)


def depth_cloud(model) -> Cloud:
    """The depth demo's background matches and kept scene matches in 3-D, with each object's rank
    and depth, in metres of a pinhole camera of ``model.config``'s ``focal_px`` and ``baseline_m``."""
    r, cfg = model.result, model.config
    h, w = model.scene.left.shape
    camera = StereoCamera.pinhole(width=w, height=h, focal_px=cfg.focal_px, baseline_m=cfg.baseline_m)
    xy = np.vstack([np.asarray(r.background.left_match_xy, dtype=float).reshape(-1, 2),
                    np.asarray(r.kept_xy, dtype=float).reshape(-1, 2)])
    d = np.concatenate([np.asarray(r.background.horizontal_disparity, dtype=float).ravel(),
                        np.asarray(r.kept_disparity, dtype=float).ravel()])
    notes = [(f"#{o.rank} {o.depth_m:.2f} m" if o.depth_m is not None else f"#{o.rank}", o.centroid_xy,
              o.mean_disparity) for o in r.objects]
    caption = (f"{len(r.background.pairs)} background matches and {len(r.kept_xy)} scene matches kept, in "
               f"metres for f = {cfg.focal_px:g} px and B = {cfg.baseline_m:g} m (the demo's calibration); "
               "left camera at 0, Z forward, colour = Z")
    return _cloud(camera, camera.points_from_disparity(xy, d), notes, caption)


def _board(camera: StereoCamera, rectified, owner: str) -> tuple:
    """The board's corners in both rectified views (cv2), their disparities and a note of their depth."""
    from ..cameras.rig import find_board

    left, right = find_board(rectified.left, camera.board), find_board(rectified.right, camera.board)
    if left is None or right is None:
        raise ParameterError(message("rectified", owner, "a pair showing the whole board in both views",
                                     "a pair where it was not found"))
    d = left[:, 0] - right[:, 0]
    median = float(np.median(d))
    note = f"board's corners (cv2), median Z {float(camera.disparity_at(median)):.3f} m"
    return left, d, (note, left.mean(axis=0), median)


def board_cloud(camera: StereoCamera, rectified) -> Cloud:
    """A chessboard's corners, found in both views of a pair rectified with `camera`, in metres."""
    check_type(camera, StereoCamera, "camera", "board_cloud", "a StereoCamera")
    left, d, note = _board(camera, rectified, "board_cloud")
    caption = f"the board's {len(left)} corners matched between the rectified views, " + _in_metres(camera)
    return _cloud(camera, camera.points_from_disparity(left, d), [note], caption)


def _in_metres(camera: StereoCamera) -> str:
    return (f"in metres (f = {camera.focal_px:.1f} px, B = {camera.baseline_m * 100:.2f} cm); "
            "left camera at 0, Z forward, colour = Z")


def match_cloud(result, camera: StereoCamera, board=None) -> Cloud:
    """The network's matches (`result`) of a pair rectified with `camera`, in metres
    (:func:`ismb_lab.matching.metric.match_points`).

    `board`, the rectified pair when it shows the calibration board, adds a note with its
    corners' median depth (found by cv2, not by the network).

    >>> from ismb_lab.matching.pipeline import match
    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> cloud = match_cloud(match(s.left, s.right), StereoCamera())
    >>> len(cloud.points) > 0, bool((cloud.points[:, 2] > 0).all()), cloud.centres[1].tolist()
    (True, True, [0.1, 0.0, 0.0])
    """
    from ..matching.metric import match_points

    check_type(camera, StereoCamera, "camera", "match_cloud", "a StereoCamera")
    notes = [] if board is None else [_board(camera, board, "match_cloud")[2]]
    caption = f"the network's {len(result.pairs)} matches (Method-{result.method}) " + _in_metres(camera)
    return _cloud(camera, match_points(result, camera), notes, caption)


def _shown(xyz) -> np.ndarray:
    """Camera frame (X right, Y down, Z forward) to the plot's (X, Z, -Y): up is up on screen."""
    xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
    return np.column_stack([xyz[:, 0], xyz[:, 2], -xyz[:, 1]]).astype(np.float32)


def _colours(n: int = 32) -> np.ndarray:
    """Reversed plasma (near = yellow, as the depth demo's disparities): ``(n, 4)`` rows ``t, r, g, b``."""
    from matplotlib import colormaps

    t = np.linspace(0, 1, n)
    return np.column_stack([t, colormaps["plasma_r"](t)[:, :3]])


#: The axes' titles, in the plot's order (X right, Z forward, up).
AXIS_TITLES = ("X (m)", "Z (m)", "-Y (m)")
#: At most this many numbered ticks per axis.
MAX_TICKS = 6


def axis_ticks(lo: float, hi: float) -> np.ndarray:
    """Round values from `lo` to `hi` to number an axis with (at most :data:`MAX_TICKS`).

    >>> axis_ticks(0.0, 1.62).tolist()
    [0.0, 0.5, 1.0, 1.5]
    """
    from matplotlib.ticker import MaxNLocator

    values = MaxNLocator(nbins=4, steps=[1, 2, 2.5, 5, 10]).tick_values(lo, hi)
    span = max(hi - lo, 1e-9)
    values = values[(values >= lo - 1e-9 * span) & (values <= hi + 1e-9 * span)]
    return np.round(values, 10)[:MAX_TICKS]


def axes_frame(lo, hi) -> tuple[np.ndarray, np.ndarray, list]:
    """Three axes along the edges of the box `lo` - `hi` (plot coordinates) that meet at its
    near, left, bottom corner, each numbered and titled once.

    Returns ``(V, 3)`` float32 vertices, ``(S, 2)`` uint32 segments and the texts as
    ``(str, (x, y, z), reference_point)``.

    >>> v, s, texts = axes_frame([0, 0, 0], [1, 2, 1])
    >>> [t for t, _, _ in texts if t.endswith("(m)")]
    ['X (m)', 'Z (m)', '-Y (m)']
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    span = float(max((hi - lo).max(), 1e-3))
    tick = 0.02 * span
    # where each axis' numbers sit, off the axis: X's and Z's below the floor, up's to the left
    outward = {0: np.array([0.0, 0.0, -1.0]), 1: np.array([0.0, 0.0, -1.0]), 2: np.array([-1.0, 0.0, 0.0])}
    vertices, segments, texts = [], [], []

    def segment(a, b):
        vertices.extend([a, b])
        segments.append([len(vertices) - 2, len(vertices) - 1])

    for axis in range(3):
        end = lo.copy()
        end[axis] = hi[axis]
        segment(lo.copy(), end)
        out = outward[axis]
        for value in axis_ticks(lo[axis], hi[axis]):
            at = lo.copy()
            at[axis] = value
            segment(at, at + tick * out)
            texts.append((f"{value:g}", tuple(at + 3 * tick * out), "ct" if axis < 2 else "rc"))
        title = end + 3 * tick * out + (tick * 3 * np.eye(3)[axis])
        texts.append((AXIS_TITLES[axis], tuple(title), "lc" if axis != 2 else "cb"))
    return (np.asarray(vertices, dtype=np.float32).reshape(-1, 3), np.asarray(segments, dtype=np.uint32).reshape(-1, 2),
            texts)


def colour_bar_html(lo: float, hi: float) -> str:
    """The colour scale, depth `lo` m (yellow) to `hi` m, as HTML outside the canvas (never over the axes)."""
    stops = ", ".join(f"rgb({int(255 * r)},{int(255 * g)},{int(255 * b)}) {100 * t:.0f}%"
                      for t, r, g, b in _colours(9))
    return ("<div style='display:flex;align-items:center;gap:0.5em;font-size:small'>"
            f"<span>colour = Z: {lo:.2f} m</span>"
            f"<div style='flex:0 1 20em;height:0.8em;min-width:4em;background:linear-gradient(to right, {stops})'></div>"
            f"<span>{hi:.2f} m</span></div>")


def _fill(points, xyz, colour, size: float, colour_range, wanted: bool) -> None:
    """Set a k3d points object; positions and colours of the same count arrive together, and
    no points hide the last ones rather than send an empty object."""
    with points.hold_sync():
        if len(xyz):
            points.positions = _shown(xyz)
            points.attribute = colour.astype(np.float32)
            points.point_size = size
        points.color_range = colour_range
        points.visible = bool(wanted and len(xyz))


class PointCloudView:
    """A rotatable 3-D view of a :class:`Cloud` (k3d, WebGL), `height` px tall; `dense` points
    (metres) are drawn in the same colours, hidden until :meth:`show_dense`.

    The view draws its own axes: k3d's grid titles each axis twice, and its colour bar
    covered the numbers.

    Parameters
    ----------
    cloud : Cloud
        The points, cameras and notes to show.
    height : int, default 360
        The view's height, px.
    dense : (M, 3) float array_like, optional
        Dense points (metres), hidden until :meth:`show_dense`.

    Notes
    -----
    CSS classes: root ``ismb-cloud``; caption ``ismb-cloud-caption``; colour scale
    ``ismb-cloud-colours``; the k3d plot ``ismb-cloud-plot``.
    """

    def __init__(self, cloud: Cloud, height: int = 360, dense=None):
        import k3d

        check_type(cloud, Cloud, "cloud", "PointCloudView", "a Cloud")
        self.plot = k3d.plot(height=int(height), menu_visibility=False, axes_helper=0, grid_visible=False,
                             camera_auto_fit=False)
        # made with the first cloud's data: a k3d points object created empty never shows its
        # colour map in the browser, whatever data it gets later (k3d 3.2, Chromium)
        seed = _shown(cloud.points if len(cloud.points) else [[0, 0, 0]])
        colour = cloud.colour.astype(np.float32) if len(cloud.points) else np.zeros(1, np.float32)
        cmap = _colours().ravel().astype(np.float32)

        def points(name, **kw):
            return k3d.points(seed, attribute=colour, color_map=cmap, color_range=[0.0, 1.0], shader="flat",
                              name=name, **kw)

        def texts(n, rgb, size):
            return [k3d.text("", (0.0, 0.0, 0.0), color=rgb, size=size, label_box=False, is_html=True,
                             visible=False) for _ in range(n)]

        self.points, self.dense = points("matches"), points("dense", visible=False)
        vertices, segments = frustum_edges(cloud.centres, cloud.frustum)
        self.cameras = k3d.lines(vertices, segments, indices_type="segment", shader="simple", color=0x303030,
                                 name="cameras")
        self.axes = k3d.lines(np.zeros((2, 3), np.float32), np.array([[0, 1]], np.uint32), indices_type="segment",
                              shader="simple", color=0x808080, name="axes")
        self.axis_texts = texts(3 * (MAX_TICKS + 1), 0x404040, 0.8)
        self.notes = texts(MAX_NOTES, 0x202020, 0.7)
        for obj in (self.points, self.dense, self.cameras, self.axes, *self.axis_texts, *self.notes):
            self.plot += obj
        # k3d draws a colour bar inside the canvas for the first object with a colour range unless
        # told which object's to draw: the cameras' lines have none, so none is drawn
        self.plot.colorbar_object_id = self.cameras.id
        self.plot.add_class("ismb-cloud-plot")
        self.caption = with_class(ipywidgets.HTML(""), "ismb-cloud-caption")
        self.colours = with_class(ipywidgets.HTML("", layout=ipywidgets.Layout(width="100%")),
                                  "ismb-cloud-colours")
        self.widget = with_class(ipywidgets.VBox([self.caption, self.colours, self.plot],
                                                 layout=ipywidgets.Layout(width="100%")), "ismb-cloud")
        self._dense_points = np.zeros((0, 3))
        self._dense_wanted = False
        self.update(cloud, dense)
        self.plot.camera = self._camera(*self._box)

    def update(self, cloud: Cloud, dense=None) -> None:
        """Show `cloud` and `dense` (``(M, 3)`` metres, or None) in the same objects, with one
        colour scale from the nearest to the farthest point of either; the camera stays."""
        check_type(cloud, Cloud, "cloud", "PointCloudView.update", "a Cloud")
        dense = np.zeros((0, 3)) if dense is None else np.asarray(dense, dtype=float).reshape(-1, 3)
        dense = dense[np.isfinite(dense).all(axis=1)]
        lo, hi = cloud.depth_range
        if len(dense):
            z = dense[:, 2]
            lo, hi = (min(lo, float(z.min())), max(hi, float(z.max()))) if len(cloud.points) else \
                (float(z.min()), float(z.max()))
        colour_range = [lo, hi if hi > lo else lo + 1e-3]
        both = np.vstack([cloud.points, cloud.centres])
        size = 0.02 * float(max(np.ptp(both, axis=0).max(), 1e-3))
        _fill(self.points, cloud.points, cloud.colour, size, colour_range, True)
        self._dense_points = dense
        _fill(self.dense, dense, dense[:, 2], 0.4 * size, colour_range, self._dense_wanted)
        vertices, _ = frustum_edges(cloud.centres, cloud.frustum)
        self.cameras.vertices = _shown(vertices)
        self._draw_axes(cloud, dense, vertices)
        for k, text in enumerate(self.notes):
            if k < len(cloud.notes):
                words, xyz = cloud.notes[k]
                text.text, text.position, text.visible = html.escape(words, quote=False), _shown(xyz)[0], True
            else:
                text.visible = False
        self.caption.value = f"<small>{html.escape(cloud.caption, quote=False)}</small>"
        self.colours.value = colour_bar_html(*colour_range) if len(cloud.points) or len(dense) else ""

    def show_dense(self, shown: bool) -> None:
        """Show or hide the dense points (shown only when there are some)."""
        self._dense_wanted = bool(shown)
        self.dense.visible = bool(shown and len(self._dense_points))

    def _draw_axes(self, cloud: Cloud, dense, vertices) -> None:
        every = _shown(np.vstack([cloud.points, dense, vertices]))
        self._box = (every.min(axis=0), every.max(axis=0))
        lines, segments, texts = axes_frame(*self._box)
        with self.axes.hold_sync():
            self.axes.vertices, self.axes.indices = lines, segments
        drawn = bool(len(cloud.points) or len(dense))    # no axes around the cameras alone
        self.axes.visible = drawn
        for k, label in enumerate(self.axis_texts):
            if drawn and k < len(texts):
                words, at, anchor = texts[k]
                label.text, label.position, label.reference_point, label.visible = words, list(map(float, at)), anchor, True
            else:
                label.visible = False

    @staticmethod
    def _camera(lo, hi) -> list:
        """Behind, left of and above the cameras, looking at the middle of the box `lo` - `hi` (plot
        coordinates) from far enough to see all of it (k3d's field of view is 60°): eye, target, up."""
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        target = lo + (hi - lo) * [0.5, 0.5, 0.4]      # a little low: the near, bottom corner is nearest the eye
        eye = target + 1.5 * float(max((hi - lo).max(), 1e-3)) * np.array([-0.65, -0.7, 0.3])
        return [*map(float, eye), *map(float, target), 0.0, 0.0, 1.0]

    def _repr_mimebundle_(self, **kwargs):
        return self.widget._repr_mimebundle_(**kwargs)
