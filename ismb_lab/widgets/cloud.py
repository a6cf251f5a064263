"""The matched points in 3-D: a rotatable point cloud coloured by depth, with both cameras drawn.

:class:`Cloud` is the model (plain numbers: points in the rectified left camera's frame,
the two camera centres, the depth each point is coloured by, short notes);
:func:`depth_cloud` makes one from a depth demo, :func:`match_cloud` from the network's
matches of a pair rectified with a calibrated :class:`~ismb_lab.camera.StereoCamera`, and
:func:`board_cloud` from a chessboard's corners in such a pair.  Every point comes from
:meth:`~ismb_lab.camera.StereoCamera.points_from_disparity`.  :class:`PointCloudView` is the view: k3d objects (WebGL in the browser, the
JavaScript shipped inside the k3d wheel and sent by the kernel, nothing fetched from a
CDN) created once and updated in place by :meth:`PointCloudView.update`.

Frame: metres, X right, Y down, Z forward from the left camera.  The plot shows
``(X, Z, -Y)`` so that up is up on screen.
"""

from __future__ import annotations

import html
from dataclasses import dataclass, field

import numpy as np

from .._validation import ParameterError, ParameterTypeError, message, readonly
from ..camera import StereoCamera

__all__ = ["Cloud", "MAX_NOTES", "PointCloudView", "board_cloud", "depth_cloud", "frustum_edges", "match_cloud"]

#: How many notes (e.g. ``#1 0.89 m`` beside an object) a view can show at once.
MAX_NOTES = 6


def frustum_edges(centres, corners_xyz) -> tuple[np.ndarray, np.ndarray]:
    """A pyramid per camera: apex at its centre, base the image's 4 corners seen at some depth.

    Parameters
    ----------
    centres : (K, 3) array
        Camera centres.
    corners_xyz : (4, 3) array
        The image corners, in order around the image, relative to a camera's centre.

    Returns
    -------
    vertices : (5 K, 3) float32 ndarray
    segments : (8 K, 2) uint32 ndarray
        Vertex indices of each edge: 4 from the apex, 4 around the base.

    Examples
    --------
    >>> v, s = frustum_edges([[0, 0, 0], [0.1, 0, 0]], [[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]])
    >>> v.shape, s.shape, s[:5].tolist()
    ((10, 3), (16, 2), [[0, 1], [0, 2], [0, 3], [0, 4], [1, 2]])
    """
    centres = np.asarray(centres, dtype=float).reshape(-1, 3)
    corners = np.asarray(corners_xyz, dtype=float).reshape(4, 3)
    one = np.array([[0, 1], [0, 2], [0, 3], [0, 4], [1, 2], [2, 3], [3, 4], [4, 1]])
    vertices = np.concatenate([np.vstack([c, c + corners]) for c in centres]) if len(centres) else np.zeros((0, 3))
    segments = np.concatenate([one + 5 * k for k in range(len(centres))]) if len(centres) else np.zeros((0, 2))
    return vertices.astype(np.float32), segments.astype(np.uint32)


@dataclass(frozen=True)
class Cloud:
    """What a point-cloud view shows.

    Parameters
    ----------
    points : (N, 3) array
        Finite 3-D points, metres, in the rectified left camera's frame.
    centres : (2, 3) array
        The left and the right camera centre.
    frustum : (4, 3) array
        The image's corners relative to a camera centre, at the depth the cameras are drawn.
    colour : (N,) array, optional
        What each point is coloured by; None: its depth Z.
    notes : tuple of (str, (x, y, z))
        Short texts placed in 3-D (at most :data:`MAX_NOTES`).
    caption : str
        One line saying what is shown and in which units.

    Examples
    --------
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
        if not isinstance(self.caption, str):
            raise ParameterTypeError(message("caption", owner, "a str", self.caption))
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
    """The depth demo's matched points in 3-D: the background pair's matches (the box, the wall)
    and the scene's matches kept after background removal, with each object's rank and depth.

    Metres come from the demo's calibration: a :meth:`~ismb_lab.camera.StereoCamera.pinhole`
    camera of the scene's size with ``model.config.focal_px`` and ``baseline_m`` (its principal
    point is the image centre, as the rendered rig's), so for photos of one's own they are only
    as right as those defaults.
    """
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
    """The board's corners in both rectified views (cv2), their disparities and a note at their
    centre with their median depth."""
    from ..rig import find_board

    left, right = find_board(rectified.left, camera.board), find_board(rectified.right, camera.board)
    if left is None or right is None:
        raise ParameterError(message("rectified", owner, "a pair showing the whole board in both views",
                                     "a pair where it was not found"))
    d = left[:, 0] - right[:, 0]
    median = float(np.median(d))
    z = float(camera.disparity_at(median))
    return left, d, (f"board's corners (cv2), median Z {z:.3f} m", left.mean(axis=0), median)


def board_cloud(camera: StereoCamera, rectified) -> Cloud:
    """A chessboard's corners, found in both views of a pair rectified with `camera`, in metres
    (:meth:`~ismb_lab.camera.StereoCamera.points_from_disparity`)."""
    if not isinstance(camera, StereoCamera):
        raise ParameterTypeError(message("camera", "board_cloud", "a StereoCamera", camera))
    left, d, note = _board(camera, rectified, "board_cloud")
    caption = (f"the board's {len(left)} corners matched between the rectified views, in metres "
               f"(f = {camera.focal_px:.1f} px, B = {camera.baseline_m * 100:.2f} cm); left camera at 0, "
               "Z forward, colour = Z")
    return _cloud(camera, camera.points_from_disparity(left, d), [note], caption)


def match_cloud(result, camera: StereoCamera, board=None) -> Cloud:
    """The network's matches of a pair rectified with `camera`, in metres
    (:func:`ismb_lab.metric.match_points`), as ``ismb-lab match --rig`` gives them.

    Parameters
    ----------
    result : ismb_lab.matching.MatchResult
        The matches (e.g. after :func:`ismb_lab.metric.mutual_best`).
    camera : StereoCamera
        The camera that rectified the pair.
    board : ismb_lab.rectify.Rectified, optional
        The rectified pair, when it shows the calibration board: a note at the board's centre
        gives its corners' median depth (found by cv2, not by the network), for comparison.

    Examples
    --------
    >>> from ismb_lab.matching import match
    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> cloud = match_cloud(match(s.left, s.right), StereoCamera())
    >>> len(cloud.points) > 0, bool((cloud.points[:, 2] > 0).all()), cloud.centres[1].tolist()
    (True, True, [0.1, 0.0, 0.0])
    """
    from ..metric import match_points

    if not isinstance(camera, StereoCamera):
        raise ParameterTypeError(message("camera", "match_cloud", "a StereoCamera", camera))
    notes = [] if board is None else [_board(camera, board, "match_cloud")[2]]
    caption = (f"the network's {len(result.pairs)} matches (Method-{result.method}) in metres "
               f"(f = {camera.focal_px:.1f} px, B = {camera.baseline_m * 100:.2f} cm); left camera at 0, "
               "Z forward, colour = Z")
    return _cloud(camera, match_points(result, camera), notes, caption)


def _shown(xyz) -> np.ndarray:
    """Camera frame (X right, Y down, Z forward) to the plot's (X, Z, -Y): up is up on screen."""
    xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
    return np.column_stack([xyz[:, 0], xyz[:, 2], -xyz[:, 1]]).astype(np.float32)


def _colour_map() -> np.ndarray:
    """matplotlib's plasma, reversed (near = yellow, as in the depth demo's disparity colours),
    as k3d's flat ``[t, r, g, b, ...]``."""
    from matplotlib import colormaps

    t = np.linspace(0, 1, 32)
    return np.column_stack([t, colormaps["plasma_r"](t)[:, :3]]).ravel().astype(np.float32)


class PointCloudView:
    """A rotatable 3-D view of a :class:`Cloud` (k3d, WebGL): drag to turn, wheel to zoom.

    Built once; :meth:`update` replaces the data of the same k3d objects.  ``.widget`` is
    a box as wide as the output area, `height` px tall, with a caption line above.

    Notes
    -----
    CSS classes: root ``ismb-cloud``; caption ``ismb-cloud-caption``; the k3d plot ``ismb-cloud-plot``.
    """

    def __init__(self, cloud: Cloud, height: int = 360):
        import ipywidgets
        import k3d

        if not isinstance(cloud, Cloud):
            raise ParameterTypeError(message("cloud", "PointCloudView", "a Cloud", cloud))
        self.plot = k3d.plot(height=int(height), menu_visibility=False, axes_helper=0, grid_visible=True,
                             camera_auto_fit=False, axes=[r"X\ \mathrm{(m)}", r"Z\ \mathrm{(m)}", r"-Y\ \mathrm{(m)}"])
        # made with the first cloud's data: a k3d points object created empty never shows its
        # colour map in the browser, whatever data it gets later (k3d 3.2, Chromium)
        self.points = k3d.points(_shown(cloud.points if len(cloud.points) else [[0, 0, 0]]),
                                 attribute=cloud.colour.astype(np.float32) if len(cloud.points) else [0.0],
                                 color_map=_colour_map(), color_range=[0.0, 1.0], shader="flat", name="matches")
        vertices, segments = frustum_edges(cloud.centres, cloud.frustum)
        self.cameras = k3d.lines(vertices, segments, indices_type="segment", shader="simple", color=0x303030,
                                 name="cameras")
        self.notes = [k3d.text("", (0.0, 0.0, 0.0), color=0x202020, size=0.7, label_box=False, is_html=True,
                               visible=False)
                      for _ in range(MAX_NOTES)]
        for obj in (self.points, self.cameras, *self.notes):
            self.plot += obj
        self.plot.colorbar_object_id = self.points.id
        self.plot.add_class("ismb-cloud-plot")
        self.caption = ipywidgets.HTML("")
        self.caption.add_class("ismb-cloud-caption")
        self.widget = ipywidgets.VBox([self.caption, self.plot], layout=ipywidgets.Layout(width="100%"))
        self.widget.add_class("ismb-cloud")
        self.update(cloud)
        self.plot.camera = self._camera(cloud)

    def update(self, cloud: Cloud) -> None:
        """Show `cloud` in the same objects (the camera stays where the student turned it)."""
        if not isinstance(cloud, Cloud):
            raise ParameterTypeError(message("cloud", "PointCloudView.update", "a Cloud", cloud))
        lo, hi = cloud.depth_range
        with self.points.hold_sync():   # positions and colours of the same count arrive together
            if len(cloud.points):        # none: hide the last ones rather than send an empty object
                self.points.positions = _shown(cloud.points)
                self.points.attribute = cloud.colour.astype(np.float32)
                self.points.color_range = [lo, hi if hi > lo else lo + 1e-3]
                self.points.point_size = 0.02 * self._span(cloud)
            self.points.visible = bool(len(cloud.points))
        vertices, _ = frustum_edges(cloud.centres, cloud.frustum)
        self.cameras.vertices = _shown(vertices)
        for k, text in enumerate(self.notes):
            if k < len(cloud.notes):
                words, xyz = cloud.notes[k]
                text.text, text.position, text.visible = html.escape(words, quote=False), _shown(xyz)[0], True
            else:
                text.visible = False
        self.caption.value = f"<small>{html.escape(cloud.caption, quote=False)}</small>"

    @staticmethod
    def _span(cloud: Cloud) -> float:
        both = np.vstack([cloud.points, cloud.centres])
        return float(max(np.ptp(both, axis=0).max(), 1e-3))

    @staticmethod
    def _camera(cloud: Cloud) -> list:
        """Behind and above the cameras, looking at the cloud's middle: eye, target, up (plot axes)."""
        both = np.vstack([cloud.points, cloud.centres])
        target = _shown((both.min(axis=0) + both.max(axis=0)) / 2)[0]
        eye = target + PointCloudView._span(cloud) * np.array([-0.25, -0.75, 0.4])
        return [*map(float, eye), *map(float, target), 0.0, 0.0, 1.0]

    def _repr_mimebundle_(self, **kwargs):
        return self.widget._repr_mimebundle_(**kwargs)
