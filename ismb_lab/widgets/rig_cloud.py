"""Any rig's pair in 3-D: the network's matches in metres, as ``ismb-lab match --rig --roi full``
gives them, with OpenCV's SGBM dense disparity of the same rectified pair beside them."""

from __future__ import annotations

import html
from dataclasses import replace
from pathlib import Path

import ipywidgets
import numpy as np

from .._core.validation import ParameterError, message
from ..cameras.camera import StereoCamera, load_camera
from ..matching.dense import MAX_DENSE, agreement, dense_points, sgbm_disparity, window_range
from ..network.methods import DEFAULT_METHOD
from ._common import Base, button, check_type, row, with_class
from .cloud import Cloud, PointCloudView, _cloud, match_cloud

__all__ = ["RigCloud", "RigCloudModel"]


def _camera(rig, owner: str) -> tuple[StereoCamera, str]:
    """The rig and how to name it: a StereoCamera as it is, else a rig file (path or JSON text)."""
    if isinstance(rig, StereoCamera):
        return rig, "the rig given"
    check_type(rig, (str, Path), "rig", owner, "a StereoCamera or a rig file (path or JSON text)")
    camera = load_camera(rig)
    return camera, ("the rig file given" if str(rig).lstrip().startswith("{") else Path(rig).name)


class RigCloudModel:
    """A rig's pair matched as ``ismb-lab match --rig`` matches it, in metres, with SGBM beside it.

    `rig` is a StereoCamera or its file (path or JSON text); `method` runs with
    :class:`~ismb_lab.matching.recipe.Recipe`'s parameters and solver; with `board` (the pair shows
    the calibration board) a note gives its corners' median depth; at most `most` SGBM points.

    Attributes
    ----------
    cloud : Cloud or None
        The network's matches in metres (None before a pair, or when the pair was refused).
    dense : (H, W) ndarray or None
        SGBM's disparity of the rectified pair (NaN: none); `dense_xyz` its subsample in metres.
    refused : str
        The one-line refusal of a pair the rig does not fit ("" when it fits).

    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> model = RigCloudModel(s.rig)
    >>> said = model.load(s.right, s.left)          # swapped: refused in one line, no cloud
    >>> model.cloud is None, "swap the two files" in model.refused, "\\n" in said
    (True, True, False)
    """

    def __init__(self, rig, *, method: str = DEFAULT_METHOD, seed: int = 0, board: bool = False, most: int = MAX_DENSE):
        from ..matching.recipe import Recipe

        self.settings = Recipe(method=method).match_settings()
        self.seed, self.board, self.most = seed, bool(board), most
        self.set_rig(rig)

    def set_rig(self, rig) -> str:
        """Use `rig` from now on (a pair matched before is forgotten)."""
        from ..matching.metric import photo_config

        self.camera, self.rig_name = _camera(rig, "RigCloudModel")
        # the corners in proportion to the photo, the whole photo, the window measured on the pair:
        # the defaults of `ismb-lab match --rig` with `--roi full`
        self.config = replace(photo_config(self.camera), roi="full", shift="auto")
        self._clear()
        w, h = self.camera.size
        self.message = (f"rig {self.rig_name}: {w} x {h} px, f = {self.camera.focal_px:.1f} px, "
                        f"B = {self.camera.baseline_m * 100:.2f} cm; give it a pair (the left camera's photo first)")
        return self.message

    def _clear(self) -> None:
        self.cloud = self.dense = self.agreement = self.prepared = self.found = self.result = None
        self.dense_xyz = np.zeros((0, 3))
        self.refused = self.how = ""

    def empty_cloud(self) -> Cloud:
        """The cameras alone (what the view shows before a pair, or after a refusal)."""
        return _cloud(self.camera, np.zeros((0, 3)), [], "")

    def load(self, left, right, name: str = "pair") -> str:
        """Match `left` and `right` (paths, file bytes or arrays) with the rig; returns the status line.
        A pair the rig does not fit (:func:`ismb_lab.matching.metric.for_camera`) leaves no cloud."""
        from ..images.io import load_pair
        from ..matching.metric import for_camera, match_with_camera

        self._clear()
        try:
            left, right, self.how = for_camera(left, right, self.camera)
        except ParameterError as exc:
            self.refused = " ".join(str(exc).split())
            self.message = f"{name} refused: {self.refused}"
            return self.message
        pair = load_pair(left, right, min_shape=self.config.min_shape)
        self.prepared, self.found, self.result = match_with_camera(pair, self.config, self.camera, **self.settings,
                                                                   seed=self.seed)
        self.cloud = match_cloud(self.result, self.camera, board=pair if self.board else None)
        self.dense = sgbm_disparity(pair.left, pair.right, *window_range(self.prepared.config))
        kept = self.result
        self.agreement = agreement(self.dense, kept.left_match_xy, kept.left_match_xy[:, 0] - kept.right_match_xy[:, 0])
        self.dense_xyz, _ = dense_points(self.camera, self.dense, self.most)
        measured = int(np.isfinite(self.dense).sum())
        c = self.prepared.config
        self.message = (f"{name}: {self.how.split(' (')[0]}; {c.n_min} to {c.n_max} corners per photo, window "
                        f"{c.shift - c.window_width / 2:.0f} to {c.shift + c.window_width / 2:.0f} px; "
                        f"{len(kept.pairs)} of {len(self.found.pairs)} matches kept; {self.agreement}; "
                        f"SGBM: {len(self.dense_xyz):,} of its {measured:,} pixels drawn")
        return self.message


class RigCloud(Base):
    """Your rig and your pair in 3-D: the network's matches coloured by depth, the cameras, and
    SGBM's dense points at the press of a toggle.

    Without `rig`, its path is typed in the widget; without `left` and `right`, two photos are
    uploaded or a folder opened.  The other parameters are :class:`RigCloudModel`'s.

    The upload is :class:`~ismb_lab.widgets.photos.PhotoLoader`'s, without *Rectify* and *Use
    this pair* (the rig rectifies); each pair reaches :meth:`load` as given, not scaled.

    Parameters
    ----------
    rig : StereoCamera, str or os.PathLike, optional
        The rig or its file; else its path is typed in the widget.
    left, right : path, bytes or ndarray, optional
        A pair to show at once.
    name : str, default "pair"
        What the status line calls the pair given.
    method : str, default ``DEFAULT_METHOD``
        The energy.
    seed : int, default 0
        The network's update order.
    board : bool, default False
        The pair shows the calibration board.
    height : int, default 360
        The 3-D view's height, px.
    folder, user
        The photo loader's (:class:`~ismb_lab.widgets.photos.PhotoLoader`).

    Notes
    -----
    CSS classes: root ``ismb-rig-cloud``; rig path ``ismb-rig-file``, button ``ismb-load-rig``;
    the toggle ``ismb-dense``; ``ismb-status``; ``ismb-log``; the loader's (``ismb-upload``,
    ``ismb-photo-folder``, ``ismb-open-folder``, ``ismb-photo-pair``) and the view's
    (``ismb-cloud`` ...).
    """

    def __init__(self, rig=None, left=None, right=None, *, name: str = "pair", method: str = DEFAULT_METHOD, seed: int = 0,
                 board: bool = False, height: int = 360, folder=".", user: str | None = None):
        from .photos import PhotoLoader

        super().__init__()
        self._options = dict(method=method, seed=seed, board=board)
        self.model = None if rig is None else RigCloudModel(rig, **self._options)
        self.loader = PhotoLoader(folder=folder, user=user)
        for hidden in (self.loader.rectify_button, self.loader.use_button):
            hidden.layout.display = "none"
        shown = self.loader.load

        def take(left, right, name="photos"):     # the loader draws the pair, then it is matched here
            said = shown(left, right, name)
            self.guard(self.load)(left, right, name)
            return said

        self.loader.load = take
        self.panes = self.loader.panes
        self.rig_field = with_class(ipywidgets.Text(value=str(rig) if isinstance(rig, (str, Path)) and
                                                    not str(rig).lstrip().startswith("{") else "",
                                                    placeholder="rig file, e.g. rig.json",
                                                    layout=ipywidgets.Layout(width="18em")), "ismb-rig-file")
        self.rig_button = button("Load rig", "ismb-load-rig", "Read the rig file (ismb-lab calibrate or rig)",
                                 icon="camera")
        self.dense_toggle = with_class(ipywidgets.ToggleButton(value=False, description="SGBM points",
                                                               tooltip="OpenCV's dense disparity of the same "
                                                               "rectified pair, in metres through the same rig",
                                                               layout=ipywidgets.Layout(width="auto")), "ismb-dense")
        self.rig_button.on_click(self.guard(lambda _: self.set_rig(self.rig_field.value.strip())))
        self.dense_toggle.observe(self.guard(lambda change: self.view.show_dense(change["new"])), names="value")
        self._pair = None
        if self.model is not None and left is not None:
            self.loader.load(left, right, name)
        empty = self.model.empty_cloud() if self.model is not None else _cloud(StereoCamera(), np.zeros((0, 3)), [], "")
        matched = self.model is not None and self.model.cloud is not None
        self.view = PointCloudView(self.model.cloud if matched else empty, height=height,
                                   dense=self.model.dense_xyz if matched else None)
        self.widget = with_class(ipywidgets.VBox([
            row([self.rig_field, self.rig_button]),
            row([self.loader.upload, self.loader.folder_field, self.loader.open_button]),
            self.loader.pane.widget, row([self.dense_toggle]), self.status, self.view.widget,
            self.loader.log, self.log], layout=ipywidgets.Layout(width="100%")), "ismb-rig-cloud")
        self.refresh()

    def set_rig(self, rig) -> str:
        """Use `rig` (a StereoCamera, or a rig file's path); the pair shown, if any, is matched again."""
        if isinstance(rig, str) and not rig:
            raise ParameterError(message("rig", "RigCloud", "a rig file's path", rig))
        if self.model is None:
            self.model = RigCloudModel(rig, **self._options)
        else:
            self.model.set_rig(rig)
        if self._pair is not None:
            return self.load(*self._pair)
        self.refresh()
        return self.model.message

    def load(self, left, right, name: str = "pair") -> str:
        """Match a pair (paths, file bytes or arrays) with the rig and show it."""
        if self.model is None:
            raise ParameterError(message("rig", "RigCloud", "loaded before a pair (type its path, press "
                                         "'Load rig')", None))
        self._pair = (left, right, name)
        try:
            return self.model.load(left, right, name)
        finally:
            if hasattr(self, "view"):
                self.refresh()

    def refresh(self) -> None:
        model = self.model
        if model is None:
            self.say("type the rig file's path (from 'ismb-lab calibrate' or 'ismb-lab rig') and press 'Load rig'")
            return
        cloud = model.cloud if model.cloud is not None else model.empty_cloud()
        self.view.update(cloud, model.dense_xyz if len(model.dense_xyz) else None)
        self.view.show_dense(self.dense_toggle.value)
        self.dense_toggle.disabled = not len(model.dense_xyz)
        self.say(model.message)
        self.status.value = (f"<span style='color:#b00'>{html.escape(model.message, quote=False)}</span>"
                             if model.refused else self.status.value)
