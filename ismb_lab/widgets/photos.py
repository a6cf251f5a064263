"""A class's own stereo photos: upload, check, rectify, pick a ROI, then label, explore or match.

:meth:`PhotoModel.save` writes the pair to the student's own ``photos-<user>-<name>/`` (with
``rectify.json``), so that labels saved against its images stay valid.
"""

from __future__ import annotations

import html
import json
import re
from pathlib import Path
from typing import Callable

import ipywidgets
import numpy as np

from .._core.files import atomic_write_text
from .._core.validation import ParameterError, ParameterTypeError, message
from ..labels.classroom import user_name
from ..plotting import GAP, OKABE_ITO, side_by_side
from ..images.io import save_pair
from ..images.rectify import Rectified, apply_rectification, check_rectified, pair_inputs, rectify_pair
from ._common import Base, Pane, button, grey_rgb, row, with_class

__all__ = ["PhotoLoader", "PhotoModel"]

_IMAGE = re.compile(r"\.(jpe?g|png|bmp|tiff?|webp)$", re.IGNORECASE)


class PhotoModel:
    """Two photos on their way to a rectified pair in the student's own folder.

    :meth:`save` makes the pair's folder in `folder`, named after `user` (default
    :func:`ismb_lab.labels.classroom.user_name`) and `role`; `homographies`, ``(H_left, H_right,
    (width, height))`` found on another pair of the same cameras, are applied as they are.

    >>> import cv2
    >>> rng = np.random.default_rng(0)
    >>> scene = cv2.GaussianBlur(rng.uniform(0, 255, (200, 260)), (0, 0), 2) * 3 % 255
    >>> model = PhotoModel()
    >>> model.set_photos(scene[:, 10:], scene[:, :-10], name="desk")   # a flat scene moved sideways
    "these photos cannot be used: ... no parallax..."
    """

    def __init__(self, folder=".", user: str | None = None, role: str = "", homographies=None):
        self.folder = Path(folder)
        self.user = user_name() if user is None else str(user)
        self.role = re.sub(r"[^A-Za-z0-9._-]+", "-", str(role)).strip("-.")
        self.homographies = homographies
        self.name = ""
        self.left = self.right = None
        self.check: dict | None = None
        self.rectified: Rectified | None = None
        self.roi: tuple | None = None
        self.saved: Path | None = None
        self.message = "upload two photos: the left camera's first"

    @property
    def ready(self) -> bool:
        """Whether the pair (as shown) is rectified and can be used."""
        return self.rectified is not None or bool(self.check and self.check["rectified"])

    def set_photos(self, left, right, name: str = "photos") -> str:
        """Load two photos (paths, file bytes or arrays) and check them; nothing is kept on failure."""
        left, right, _ = pair_inputs(left, right, "PhotoModel.set_photos", 1600)
        check = check_rectified(left, right)
        self.left, self.right, self.check, self.rectified, self.roi, self.saved = left, right, check, None, None, None
        self.name = re.sub(r"[^A-Za-z0-9._-]+", "-", str(name)).strip("-.") or "photos"
        if self.role:
            self.name = f"{self.name}-{self.role}"
        if self.homographies is not None:
            return self.rectify()
        if check["problem"]:
            self.message = f"these photos cannot be used: {check['problem']}"
        elif check["rectified"]:
            self.message = (f"already rectified: {check['inliers']} matches, |dy| median "
                            f"{check['median_abs_dy_px']:.2f} px: choose a ROI (drag on the left image) "
                            "and press 'Use this pair'")
        else:
            self.message = (f"not rectified: {check['inliers']} matches, |dy| median {check['median_abs_dy_px']:.1f} px "
                            f"(90% below {check['p90_abs_dy_px']:.1f} px): press 'Rectify'")
        return self.message

    def rectify(self) -> str:
        if self.left is None:
            raise ParameterError(message("photos", "PhotoModel.rectify", "loaded first (set_photos)", None))
        if self.homographies is not None:
            self.rectified = apply_rectification(self.left, self.right, *self.homographies)
        else:
            self.rectified = rectify_pair(self.left, self.right)
        self.roi, self.saved = None, None
        r = self.rectified
        self.message = (f"rectified ({r.method}): {r.inliers} {r.measured_on}, |dy| median {r.median_abs_dy_px:.2f} px, "
                        f"90% below {r.p90_abs_dy_px:.2f} px; disparities {r.disparity_range_px[0]:.0f} to "
                        f"{r.disparity_range_px[1]:.0f} px: choose a ROI and press 'Use this pair'")
        return self.message

    def current(self):
        """The pair as it will be used: ``(left, right, left_xy, right_xy)`` of its matches."""
        if self.rectified is not None:
            r = self.rectified
            return r.left, r.right, r.left_xy, r.right_xy
        if self.left is None:
            return None
        return self.left, self.right, self.check["left_xy"], self.check["right_xy"]

    def set_roi(self, x0, y0, x1, y1) -> tuple:
        """The ROI from two corners of a dragged rectangle, clipped to the image."""
        if self.left is None:
            raise ParameterError(message("roi", "PhotoModel.set_roi", "set after the photos are loaded", None))
        h, w = self.current()[0].shape
        xs = sorted((int(np.clip(round(x0), 0, w)), int(np.clip(round(x1), 0, w))))
        ys = sorted((int(np.clip(round(y0), 0, h)), int(np.clip(round(y1), 0, h))))
        roi = (xs[0], ys[0], xs[1] - xs[0], ys[1] - ys[0])
        if roi[2] < 24 or roi[3] < 24:
            raise ParameterError(message("roi", "PhotoModel.set_roi", "at least 24 x 24 pixels inside the image",
                                         roi))
        self.roi = roi
        self.message = f"ROI {self.roi} (x, y, width, height)"
        return self.roi

    def save(self) -> Path:
        """Write the pair used to ``photos-<user>-<name>/`` (or ``-2/``, ... where another pair is)."""
        if not self.ready:
            raise ParameterError(message("photos", "PhotoModel.save", "a rectified pair (press 'Rectify' first)",
                                         self.message))
        left, right, _, _ = self.current()
        record = (self.rectified.to_dict() if self.rectified is not None else
                  {k: v for k, v in self.check.items() if not k.endswith("_xy")} | {"method": "already rectified"})
        record["roi"] = None if self.roi is None else list(self.roi)
        folder = save_pair(left, right, self.folder, f"photos-{self.user}-{self.name}")
        atomic_write_text(folder / "rectify.json", json.dumps(record, indent=2))
        self.saved = folder
        self.message = f"saved to {folder}"
        return folder


def draw_photos(ax, model: PhotoModel) -> dict:
    """The pair side by side and one line per match (level when the pair is rectified)."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Rectangle

    ax.set_axis_off()
    image = ax.imshow(np.zeros((2, 2, 3), np.uint8), interpolation="nearest")
    lines = ax.add_collection(LineCollection([], linewidths=0.8, cmap="coolwarm"))
    lines.set_clim(0, 4)
    roi = ax.add_patch(Rectangle((0, 0), 0, 0, fill=False, ec=OKABE_ITO["yellow"], lw=1.5, visible=False))
    return {"image": image, "lines": lines, "roi": roi, "offset": 0.0}


def update_photos(art: dict, model: PhotoModel) -> None:
    pair = model.current()
    if pair is None:
        return
    left, right, lxy, rxy = pair
    both = side_by_side(left, right)
    art["image"].set_data(grey_rgb(both))
    art["image"].set_extent((-0.5, both.shape[1] - 0.5, both.shape[0] - 0.5, -0.5))
    art["image"].axes.set_xlim(-0.5, both.shape[1] - 0.5)
    art["image"].axes.set_ylim(both.shape[0] - 0.5, -0.5)
    art["offset"] = offset = left.shape[1] + GAP
    segments = np.stack([lxy, rxy + [offset, 0]], axis=1) if len(lxy) else np.zeros((0, 2, 2))
    art["lines"].set_segments(segments)
    art["lines"].set_array(np.abs(lxy[:, 1] - rxy[:, 1]) if len(lxy) else np.zeros(0))
    if model.roi is not None:
        art["roi"].set_bounds(*model.roi)
    art["roi"].set_visible(model.roi is not None)


class FromPhotos:
    """Mixin: :meth:`from_photos` for a widget with a ``from_folder(folder, config=..., **kw)`` classmethod."""

    @classmethod
    def from_photos(cls, *, folder=".", **kw) -> "PhotoLoader":
        """A :class:`PhotoLoader` whose "Use this pair" saves two photos of one's own (rectified) in
        `folder` and opens this widget on them, with the dragged ROI and the window measured on it.

        Parameters
        ----------
        folder : str or os.PathLike, default "."
            Where the pair's folder is made.
        **kw
            Passed to ``from_folder``.

        Returns
        -------
        loader : PhotoLoader
            The loader widget.
        """
        from ..matching.pipeline import MatchConfig

        def open_with(pair_folder, roi):
            config = MatchConfig(roi=roi if roi is not None else "center", shift="auto")
            return cls.from_folder(pair_folder, config=config, **kw)

        return PhotoLoader(open_with, folder=folder)


class PhotoLoader(Base):
    """Bring two photos of one's own: upload, check, rectify, pick the ROI, then use them.

    `open_with(folder, roi) -> widget` is what "Use this pair" opens on the saved pair; the
    other parameters are :class:`PhotoModel`'s.

    Parameters
    ----------
    open_with : callable, optional
        ``open_with(folder, roi) -> widget``, opened on the saved pair.
    folder : str or os.PathLike, default "."
        Where the pair's folder is made.
    user : str, optional
        Whose folder; default :func:`~ismb_lab.labels.classroom.user_name`.
    role : str, default ""
        Added to the folder's name (e.g. ``"background"``).
    homographies : (H_left, H_right, (width, height)), optional
        A rectification of the same cameras, applied as it is.
    title : str, default ""
        A bold line above the loader.

    Notes
    -----
    CSS classes: root ``ismb-photos``; upload ``ismb-upload``; folder field ``ismb-photo-folder``
    and button ``ismb-open-folder``; figure ``ismb-photo-pair``; buttons ``ismb-rectify`` and
    ``ismb-use``; the opened widget's area ``ismb-opened``; ``ismb-status``; ``ismb-log``.
    """

    def __init__(self, open_with: Callable | None = None, *, folder=".", user: str | None = None, role: str = "",
                 homographies=None, title: str = ""):
        super().__init__()
        if open_with is not None and not callable(open_with):
            raise ParameterTypeError(message("open_with", "PhotoLoader", "a callable (folder, roi) -> widget",
                                             open_with))
        self.model = PhotoModel(folder, user, role, homographies)
        self.open_with = open_with
        self.opened = None
        self.pane = Pane((5.8, 2.12), "ismb-photo-pair")
        self.panes = (self.pane,)
        self.ax = self.pane.fig.add_axes((0, 0, 1, 1))
        self.artists = draw_photos(self.ax, self.model)
        self.upload = with_class(ipywidgets.FileUpload(accept="image/*", multiple=True,
                                                       description="Two photos"), "ismb-upload")
        self.folder_field = with_class(ipywidgets.Text(placeholder="or a folder with left.* and right.*",
                                                       layout=ipywidgets.Layout(width="22em")),
                                       "ismb-photo-folder")
        self.open_button = button("Open folder", "ismb-open-folder", icon="folder-open")
        self.rectify_button = button("Rectify", "ismb-rectify", "Rectify the pair from its matches",
                                     icon="magic", disabled=True)
        self.use_button = button("Use this pair", "ismb-use", "Save the pair to your folder and open it",
                                 icon="check", disabled=True)
        self.area = with_class(ipywidgets.VBox([]), "ismb-opened")
        self.upload.observe(self.guard(self._on_upload), names="value")
        self.open_button.on_click(self.guard(lambda _: self.open_folder(self.folder_field.value)))
        self.rectify_button.on_click(self.guard(lambda _: self.rectify()))
        self.use_button.on_click(self.guard(lambda _: self.use()))
        self._selector = None
        if hasattr(self.pane.fig.canvas, "mpl_connect"):
            from matplotlib.widgets import RectangleSelector

            self._selector = RectangleSelector(self.ax, self.guard(self._on_drag), useblit=False,
                                               button=[1], interactive=False, minspanx=5, minspany=5)
        self.widget = with_class(ipywidgets.VBox([
            ipywidgets.HTML(f"<b>{html.escape(title)}</b>" if title else ""),
            row([self.upload, self.folder_field, self.open_button]), self.pane.widget,
            row([self.rectify_button, self.use_button]), self.status, self.log, self.area]), "ismb-photos")
        self.say(self.model.message)

    def load(self, left, right, name: str = "photos") -> str:
        try:
            return self.model.set_photos(left, right, name)
        finally:
            self.refresh()

    def _on_upload(self, change) -> None:
        files = list(change["new"])
        if len(files) != 2:
            raise ParameterError(message("upload", "PhotoLoader", "two photos at once (the left camera's "
                                         "first, or named left... and right...)", f"{len(files)} files"))
        if "right" in files[0]["name"].lower() and "left" in files[1]["name"].lower():
            files.reverse()
        self.load(bytes(files[0]["content"]), bytes(files[1]["content"]), Path(files[0]["name"]).stem)

    def open_folder(self, folder) -> str:
        folder = Path(str(folder).strip()).expanduser()
        found = {}
        for side in ("left", "right"):
            hits = sorted(p for p in folder.glob(f"{side}*") if _IMAGE.search(p.name)) if folder.is_dir() else []
            if not hits:
                raise ParameterError(message("folder", "PhotoLoader.open_folder", "a folder holding left.* and "
                                             "right.* photos", str(folder)))
            found[side] = hits[0]
        return self.load(found["left"], found["right"], folder.name)

    def rectify(self) -> str:
        try:
            return self.model.rectify()
        finally:
            self.refresh()

    def _on_drag(self, press, release) -> None:
        self.model.set_roi(press.xdata, press.ydata, release.xdata, release.ydata)
        self.refresh()

    def use(self):
        """Save the pair to the student's folder and open `open_with` on it."""
        folder = self.model.save()
        self.refresh()
        if self.open_with is not None:
            self.opened = self.open_with(folder, self.model.roi)
            self.area.children = (getattr(self.opened, "widget", self.opened),)
            if hasattr(self.opened, "show"):
                self.opened.show()
        return self.opened

    def refresh(self) -> None:
        update_photos(self.artists, self.model)
        problem = bool(self.model.check and self.model.check["problem"])
        self.rectify_button.disabled = self.model.left is None or self.model.ready or problem
        self.use_button.disabled = not self.model.ready
        self.say(self.model.message)
        self.pane.draw()
