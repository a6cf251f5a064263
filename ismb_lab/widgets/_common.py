"""What every widget shares: figure panes, the status line, the error area, the pair view,
folder loading."""

from __future__ import annotations

import contextlib
import functools
import io
import threading
import traceback
from pathlib import Path

import ipywidgets
import matplotlib
import numpy as np
from matplotlib.figure import Figure

from .._core.validation import ParameterError, ParameterTypeError, message
from ..images.io import grey_uint8
from ..network.params import Params

#: Widest figure, CSS px: JupyterLab's column at 1024 x 768 with the file browser open is about 592 px.
COLUMN_PX = 580
#: Dots per inch of every widget figure: inches times DPI are CSS pixels.
DPI = 100


def column_figsize(width: float, height: float) -> tuple[float, float]:
    """Figure size in inches that shows `width` x `height` data units at equal aspect, a column wide.

    >>> column_figsize(648, 240)
    (5.8, 2.148)
    """
    return round(COLUMN_PX / DPI, 3), round(height * (COLUMN_PX / width) / DPI, 3)


def pair_figsize(pair) -> tuple[float, float]:
    """:func:`column_figsize` of a pair's side-by-side view."""
    from ..plotting import GAP

    height, width = pair.shape[:2]
    return column_figsize(2 * width + GAP, height)


def ipympl_active() -> bool:
    """Whether pyplot draws into ipympl canvases (``%matplotlib widget``)."""
    return "ipympl" in matplotlib.get_backend().lower() or matplotlib.get_backend() == "widget"


def _serialise_frames(canvas) -> None:
    """Let one thread at a time render an ipympl canvas, and send every frame whole.

    The GA runner draws from its worker thread while the kernel draws when the browser asks:
    two renders of one Agg canvas at once leave a half-drawn buffer.  Whole frames, never
    diffs, keep ipympl's frame mode from flipping so that no frame is laid over the wrong base.
    """
    lock = threading.RLock()
    draw, diff_image = canvas.draw, canvas.get_diff_image

    def locked_draw(*args, **kwargs):
        with lock:
            return draw(*args, **kwargs)

    def whole_image():
        canvas._force_full = True
        return diff_image()

    canvas.draw, canvas.get_diff_image = locked_draw, whole_image


class Pane:
    """A figure and the ipywidget (CSS class `css`) that shows it.

    Under ``%matplotlib widget`` the widget is the ipympl canvas; elsewhere a PNG in an
    ``ipywidgets.Image``, refreshed after each draw once shown.  `figsize`: inches at :data:`DPI`.
    """

    def __init__(self, figsize, css: str):
        if ipympl_active():
            import matplotlib.pyplot as plt

            with plt.ioff():
                self.fig = plt.figure(figsize=figsize, dpi=DPI)
            canvas = self.widget = self.fig.canvas
            canvas.header_visible = canvas.footer_visible = canvas.resizable = False
            _serialise_frames(canvas)
        else:
            from matplotlib.backends.backend_agg import FigureCanvasAgg

            self.fig = Figure(figsize=figsize, dpi=DPI)
            FigureCanvasAgg(self.fig)
            self.widget = ipywidgets.Image(format="png")
        self.widget.add_class(css)
        self.live = False  # set when shown: only then is a PNG fallback worth encoding

    @property
    def interactive(self) -> bool:
        return self.widget is self.fig.canvas

    def draw(self) -> None:
        """Render now.  ``draw()``, not ``draw_idle()``: idle draws left stale plots in browsers."""
        canvas = self.fig.canvas
        canvas.draw()
        if self.interactive and canvas.syncing_data_url:
            self._seed_first_frame(canvas)
        if self.live and not self.interactive:
            buffer = io.BytesIO()
            self.fig.savefig(buffer, format="png")
            self.widget.value = buffer.getvalue()

    def _seed_first_frame(self, canvas) -> None:
        # Until its browser view is initialised, ipympl 0.10 stores a frame as bare base64 and
        # the size as (0, 0) inside a box: the view then never initialises and stays 0 x 0 px.
        url = canvas._data_url
        if isinstance(url, str) and not url.startswith("data:"):
            canvas._data_url = "data:image/png;base64," + url
        canvas._size = tuple(float(v) for v in self.fig.bbox.size / canvas.device_pixel_ratio)


class Base:
    """Root container, status line, error area and notebook display of a widget.

    Subclasses set :attr:`widget` and :attr:`panes`; every callback goes through :meth:`guard`.
    """

    widget: ipywidgets.Box
    panes: tuple = ()

    def __init__(self):
        self.status = with_class(ipywidgets.HTML(""), "ismb-status")
        self.log = with_class(ipywidgets.Output(), "ismb-log")
        self.errors: list[BaseException] = []
        self._syncing = 0

    @contextlib.contextmanager
    def syncing(self):
        """Set controls from the model without their guarded observers answering.

        >>> demo, calls = Base(), []
        >>> callback = demo.guard(lambda: calls.append(1))
        >>> with demo.syncing():
        ...     callback()
        >>> callback(); calls
        [1]
        """
        self._syncing += 1
        try:
            yield
        finally:
            self._syncing -= 1

    def say(self, text: str) -> None:
        """Show `text` in the status line (plain text; it is HTML-escaped)."""
        import html

        self.status.value = html.escape(text, quote=False)

    def guard(self, callback):
        """Wrap a callback so that an exception is shown in the log, never lost."""
        @functools.wraps(callback)
        def safe(*args, **kwargs):
            if self._syncing:
                return None
            try:
                return callback(*args, **kwargs)
            except Exception as exc:  # a callback has nobody above it to catch
                self.report(exc)
        return safe

    def report(self, exc: BaseException) -> None:
        self.errors.append(exc)
        self.log.append_stderr("".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))
        self.say(f"Error: {exc}")

    def show(self) -> None:
        for pane in self.panes:
            if not pane.live:
                pane.live = True
                pane.draw()

    def _repr_mimebundle_(self, **kwargs):
        self.show()
        return self.widget._repr_mimebundle_(**kwargs)


def button(description: str, css: str, tooltip: str = "", **kw) -> ipywidgets.Button:
    """A button as wide as its label (ipywidgets' fixed width cuts long labels)."""
    kw.setdefault("layout", ipywidgets.Layout(width="auto", min_width="fit-content"))
    return with_class(ipywidgets.Button(description=description, tooltip=tooltip or description, **kw), css)


def row(children) -> ipywidgets.HBox:
    """A row of widgets that wraps where the screen is too narrow (a 1024 px projector)."""
    return ipywidgets.HBox(list(children), layout=ipywidgets.Layout(flex_flow="row wrap"))


def with_class(widget, css: str):
    widget.add_class(css)
    return widget


def seed_field(seed: int, **kw) -> ipywidgets.BoundedIntText:
    """The update-order seed's field (CSS class ``ismb-seed``); `kw` e.g. its ``layout``."""
    return with_class(ipywidgets.BoundedIntText(value=seed, min=0, max=2**31 - 1, description="seed", **kw),
                      "ismb-seed")


def menu(name: str, options, value, **kw) -> ipywidgets.Dropdown:
    """A drop-down of `options` described as `name`, CSS class ``ismb-<name>``, e.g. ``"method"``."""
    return with_class(ipywidgets.Dropdown(options=list(options), value=value, description=name, **kw),
                      "ismb-" + name)


def check_type(value, kind, name: str, owner: str, rule: str):
    """`value` if it is a `kind`, else a ParameterTypeError naming `name`, `owner` and `rule`."""
    if not isinstance(value, kind):
        raise ParameterTypeError(message(name, owner, rule, value))
    return value


def check_params(params, owner: str, default=None):
    """`params`, or `default` when it is None; a ParameterTypeError naming `owner` unless a Params."""
    if params is None:
        return default
    return check_type(params, Params, "params", owner, "None or a Params")


def pair_files(folder, owner: str) -> tuple[Path, Path, Path]:
    """``left.png``, ``right.png`` and ``answer_key.json`` of a pair folder (the key may be absent)."""
    folder = Path(check_type(folder, (str, Path), "folder", owner, "a folder path (str or Path)"))
    for name in ("left.png", "right.png"):
        if not (folder / name).is_file():
            raise ParameterError(f"The 'folder' parameter of {owner} must be a folder holding "
                                 f"left.png and right.png. Got {str(folder)!r} instead (no {name}).")
    return folder / "left.png", folder / "right.png", folder / "answer_key.json"


def grey_rgb(image) -> np.ndarray:
    """A grey image as an ``(H, W, 3)`` uint8 array: drawn without a colour map, so faster."""
    g = grey_uint8(image)
    return np.repeat(g[:, :, None], 3, axis=2)


def path_labels(ax, offsets, strings, colour, *, size: float = 7.0, shift=(2.5, 2.5),
                offset_transform=None, ha: str = "left", declutter: bool = False):
    """Short strings drawn at `offsets` as glyph outlines in ONE collection.

    A ``Text`` artist costs about 1 ms per Agg draw; one collection of paths keeps a redraw
    within 30 ms.  `shift` is in points; ``ha`` aligns on the shifted point.  With `declutter`,
    a label that would cover another moves to a free corner of its point (:func:`_declutter`).
    """
    from matplotlib.collections import PathCollection
    from matplotlib.path import Path as MplPath
    from matplotlib.textpath import TextPath
    from matplotlib.transforms import Affine2D

    paths = []
    for text in strings:
        path = TextPath((0, 0), str(text), size=size)
        width = path.get_extents().x1 if len(path.vertices) else 0.0
        dx = shift[0] - {"left": 0.0, "center": width / 2, "right": width}[ha]
        paths.append(MplPath(path.vertices + [dx, shift[1]], path.codes))
    if declutter and paths:
        where = (offset_transform or ax.transData).transform(np.asarray(offsets, float).reshape(-1, 2))
        kept, paths = _declutter(paths, where, ax.figure.dpi / 72, shift)
        offsets = np.asarray(offsets, float).reshape(-1, 2)[kept]
    points = Affine2D().scale(1 / 72) + ax.figure.dpi_scale_trans
    labels = PathCollection(paths, offsets=offsets, offset_transform=offset_transform or ax.transData,
                            transform=points, facecolors=colour, edgecolors="none")
    labels.set_clip_on(offset_transform is None)  # axis numbers sit outside the axes
    ax.add_collection(labels, autolim=False)
    return labels


def _declutter(paths, where, px_per_point: float, shift):
    """Place each label (glyph `paths` in points, anchored at display pixels `where`) at the first
    corner of its point where it covers no label placed before; returns the kept indices and paths."""
    from matplotlib.path import Path as MplPath

    placed, kept, moved = [], [], []
    for n, path in enumerate(paths):
        if not len(path.vertices):
            continue
        box = path.get_extents()
        width, height = box.x1 - box.x0, box.y1 - box.y0
        # right-above (as given), left-above, right-below, left-below of the point, in points
        for dx, dy in ((0.0, 0.0), (-width - 2 * shift[0], 0.0), (0.0, -height - 2 * shift[1]),
                       (-width - 2 * shift[0], -height - 2 * shift[1])):
            x0 = where[n, 0] + (box.x0 + dx) * px_per_point
            y0 = where[n, 1] + (box.y0 + dy) * px_per_point
            x1, y1 = x0 + width * px_per_point, y0 + height * px_per_point
            if all(x1 <= a0 or x0 >= a1 or y1 <= b0 or y0 >= b1 for a0, b0, a1, b1 in placed):
                placed.append((x0, y0, x1, y1))
                kept.append(n)
                moved.append(MplPath(path.vertices + [dx, dy], path.codes))
                break
    return kept, moved


def draw_pair(ax, model) -> dict:
    """The pair side by side, numbered features and `model`'s matches (``prepared`` and ``pairs``)."""
    from ..plotting import GAP, LEFT_COLOUR, RIGHT_COLOUR, plot_matches

    pair = model.prepared.pair
    left_xy, right_xy = model.prepared.problem.left_xy, model.prepared.problem.right_xy
    art = plot_matches(ax, pair.left, pair.right, left_xy, right_xy, model.pairs, numbers=False)
    art["image"].set_data(grey_rgb(art["image"].get_array()))
    art["image"].set_interpolation("nearest")
    offset = np.array([pair.shape[1] + GAP, 0.0])
    for xy, colour in ((left_xy, LEFT_COLOUR), (right_xy + offset, RIGHT_COLOUR)):
        path_labels(ax, xy, range(1, len(xy) + 1), colour, declutter=True)
    art["lines"].set_clim(0, 40)
    art["offset"] = offset
    return art


def update_pair(art: dict, model) -> None:
    """Show `model`'s current matches in a view made by :func:`draw_pair`."""
    left_xy, right_xy = model.prepared.problem.left_xy, model.prepared.problem.right_xy
    pairs = model.pairs
    art["lines"].set_segments(np.stack([left_xy[pairs[:, 0]], right_xy[pairs[:, 1]] + art["offset"]], axis=1))
    art["lines"].set_array(np.hypot(*(left_xy[pairs[:, 0]] - right_xy[pairs[:, 1]]).T))
