"""Measure every figure a notebook draws, in its kernel, and judge what was measured.

The kernel side (:func:`install`, :func:`measure`) runs inside the notebook's kernel: an
IPython ``post_execute`` callback, placed before the inline backend's (which shows and
closes the figures), draws each figure alive at the end of a cell with the figure's own
canvas, and writes one JSON line per figure that changed since it was last measured: the
bounding box of every text the draw rendered, the area the reader sees, the images and
their colour bars, and the colours of the lines and markers of each axes.  The test side
(:func:`overlaps`, :func:`cut_texts`, :func:`missing_colour_bars`, :func:`hue_clashes`)
reads those lines.

What the reader sees (all in CSS pixels, the unit of the tolerance):

* an inline figure is a PNG cropped to its tight bounding box (the inline backend's
  ``bbox_inches="tight"``), shown at one image pixel per CSS pixel, scaled down to the
  notebook column when wider (:data:`ismb_lab.widgets._common.COLUMN_PX` at 1024 x 768);
* an ipympl figure (``%matplotlib widget``) is its canvas: the figure itself, at its size in
  inches times its dpi over the device pixel ratio, never scaled, its edge a hard cut.

Colours: "differ in hue, not only in lightness" is measured in CIELAB (D65), where hue is
the angle of (a*, b*) and chroma its length.  Two colours clash when both are chromatic
(chroma >= :data:`NEUTRAL_CHROMA`) and their hue angles are less than :data:`MIN_HUE_DEG`
apart, or when both are neutral (black, greys, white: they can differ only in lightness).
Why 30 degrees: Okabe and Ito's palette, which the project uses, holds two kinds of pairs.
Orange/vermillion (21.9 degrees apart by :func:`lch`), orange/yellow (22.5) and sky
blue/blue (15.3) are told apart mainly by lightness, and are the pairs that wash together on
a projector (orange beside vermillion is the pair the lesson review flagged).  Every other
pair of its colours is at least 44 degrees apart (yellow/vermillion 44.4, then bluish
green/yellow 64.4).  30 degrees (a twelfth of the hue circle, one step of a twelve-hue colour
wheel) lies between the two groups, 7.5 degrees above the one and 14 below the other, so the
rule does not hinge on the last digit of a conversion (test_figures.py checks these figures).
Below a chroma of 10 a colour counts as neutral: matplotlib's greys have 0, the palette's
least chromatic colour (sky blue) 37.
"""

from __future__ import annotations

import json
import sys
import threading
import time
import traceback
import weakref

#: Overlap or cut beyond this many CSS pixels (in both directions, for an overlap) fails.
TOLERANCE_PX = 1.0
#: Smallest hue angle, in degrees of CIELAB's (a*, b*) plane, between two chromatic colours.
MIN_HUE_DEG = 30.0
#: Chroma (CIELAB C*ab) below which a colour counts as neutral: black, a grey or white.
NEUTRAL_CHROMA = 10.0
#: Colours closer than this CIELAB distance (Delta E 1976) are the same colour used twice.
SAME_COLOUR_DE = 3.0
#: A collection with more distinct colours than this encodes values (a colour map by hand).
MAX_SERIES_COLOURS = 12
#: The function of ismb_lab.widgets._common that draws short labels as glyph outlines (one
#: PathCollection, no Text artists): its labels are texts too.
GLYPH_LABELS = "path_labels"


# --------------------------------------------------------------------------- kernel side

_recording = threading.local()


def _patch_matplotlib():
    """Wrap Text.draw, PathCollection and Figure.draw once, so a measuring draw learns which
    texts were rendered, glyph-label collections are known, and every figure counts its draws."""
    from matplotlib.collections import PathCollection
    from matplotlib.figure import Figure
    from matplotlib.text import Text

    if getattr(Text.draw, "_figure_text", False):
        return

    text_draw = Text.draw

    def draw_text(self, renderer):
        found = getattr(_recording, "texts", None)
        if found is not None and self.get_visible() and self.get_text() != "":
            # measured now: a 3-D axes' texts stand at their projected place only while drawn;
            # Text's own extent, not an annotation's (which adds its arrow)
            try:
                found.append((self, Text.get_window_extent(self, renderer), _clip(self)))
            except Exception as exc:                      # reported by measure, after the draw
                found.append((self, exc, None))
        return text_draw(self, renderer)

    init = PathCollection.__init__

    def init_collection(self, *args, **kwargs):
        init(self, *args, **kwargs)
        caller = sys._getframe(1)
        if caller.f_code.co_name == GLYPH_LABELS:
            strings = caller.f_locals.get("strings")
            try:
                self._figure_text_labels = [str(s) for s in strings]
            except TypeError:
                self._figure_text_labels = None

    collection_draw = PathCollection.draw

    def draw_collection(self, renderer):
        found = getattr(_recording, "glyphs", None)
        if found is not None and self.get_visible() and hasattr(self, "_figure_text_labels"):
            found.append(self)
        return collection_draw(self, renderer)

    figure_init, figure_draw = Figure.__init__, Figure.draw

    def init_figure(self, *args, **kwargs):
        figure_init(self, *args, **kwargs)
        if _RECORDER is not None:
            _RECORDER.figures.add(self)

    def draw_figure(self, renderer):
        self._figure_text_draws = getattr(self, "_figure_text_draws", 0) + 1
        return figure_draw(self, renderer)

    for f in (draw_text, draw_collection, draw_figure):
        f._figure_text = True
    Text.draw, PathCollection.__init__, PathCollection.draw = draw_text, init_collection, draw_collection
    Figure.__init__, Figure.draw = init_figure, draw_figure


_RECORDER = None


class Recorder:
    """The post_execute callback: measures changed figures, appends JSON lines to `path`."""

    def __init__(self, shell, path: str, column_px: float):
        self.shell, self.path, self.column_px = shell, path, column_px
        self.figures = weakref.WeakSet()        # every Figure made since install
        self.serials = weakref.WeakKeyDictionary()
        self.measured = weakref.WeakKeyDictionary()   # figure -> its draw count after our draw

    def alive(self) -> list:
        from matplotlib._pylab_helpers import Gcf

        managed = [m.canvas.figure for m in Gcf.get_all_fig_managers()]
        # a figure made outside pyplot (a widget's Agg pane) lives as long as it is referenced
        free = [f for f in list(self.figures) if getattr(f.canvas, "manager", None) is None
                and getattr(f, "_figure_text_draws", 0)]
        return managed + [f for f in free if f not in managed]

    def __call__(self):
        cell = self.shell.execution_count - 1     # IPython counts the cell before running it
        lines = []
        try:
            for fig in self.alive():
                if not fig.stale and self.measured.get(fig) == getattr(fig, "_figure_text_draws", 0):
                    continue
                if fig not in self.serials:
                    self.serials[fig] = len(self.serials) + 1
                wall, cpu = time.perf_counter(), time.process_time()
                try:
                    record = measure(fig, self.column_px)
                except Exception:
                    record = {"error": traceback.format_exc()}
                # what measuring costs the notebook's run
                record["seconds"] = [time.perf_counter() - wall, time.process_time() - cpu]
                self.measured[fig] = getattr(fig, "_figure_text_draws", 0)
                lines.append(json.dumps({"cell_count": cell, "figure": self.serials[fig], **record}))
        except Exception:
            lines.append(json.dumps({"cell_count": cell, "figure": 0, "error": traceback.format_exc()}))
        if lines:
            with open(self.path, "a", encoding="utf-8") as out:
                out.write("\n".join(lines) + "\n")


def install(shell, path: str, column_px: float) -> Recorder:
    """Measure, after every cell `shell` runs, each figure alive and changed; append to `path`."""
    global _RECORDER
    _patch_matplotlib()
    _RECORDER = Recorder(shell, path, column_px)
    # first, so the figures are measured before the inline backend shows and closes them (an
    # inline backend loaded later appends its flush after this)
    shell.events.callbacks["post_execute"].insert(0, _RECORDER)
    return _RECORDER


def _interactive(fig) -> bool:
    canvas = type(fig.canvas)
    return "ipympl" in canvas.__module__ or "webagg" in canvas.__module__


def _axes_names(fig) -> dict:
    names = {}
    for i, ax in enumerate(fig.axes):
        title = next((t.get_text() for t in (ax.title, ax._left_title, ax._right_title) if t.get_text()), "")
        bar = getattr(ax, "_colorbar", None)
        if bar is not None:
            owner = bar.mappable.axes if getattr(bar.mappable, "axes", None) is not None else None
            names[ax] = f"colour bar of {names.get(owner, 'an axes')}" if owner in names else f"colour bar {i}"
        else:
            short = title if len(title) <= 32 else title[:30] + "…"
            names[ax] = f"axes {i}" + (f" {short!r}" if title else "")
    # colour bars made before their images' axes were numbered
    for ax in fig.axes:
        bar = getattr(ax, "_colorbar", None)
        if bar is not None and getattr(bar.mappable, "axes", None) in names:
            names[ax] = f"colour bar of {names[bar.mappable.axes]}"
    return names


def _roles(fig, axes: dict) -> dict:
    """id(text) -> what the text is, for the messages."""
    roles = {}

    def legend(leg, where):
        if leg is None:
            return
        for t in leg.get_texts():
            roles[id(t)] = f"legend entry of {where}"
        roles[id(leg.get_title())] = f"legend title of {where}"

    for ax, name in axes.items():
        for t, role in ((ax.title, "title"), (ax._left_title, "left title"), (ax._right_title, "right title")):
            roles[id(t)] = f"{role} of {name}"
        for axis, letter in ((ax.xaxis, "x"), (ax.yaxis, "y")):
            roles[id(axis.label)] = f"{letter} label of {name}"
            roles[id(axis.get_offset_text())] = f"{letter} offset text of {name}"
            for t in axis.get_majorticklabels() + axis.get_minorticklabels():
                roles[id(t)] = f"{letter} tick label of {name}"
        for t in ax.texts:
            kind = "annotation" if hasattr(t, "xyann") else "text"
            roles[id(t)] = f"{kind} in {name}"
        legend(ax.get_legend(), name)
    figures = [fig] + list(fig.subfigs) if hasattr(fig, "subfigs") else [fig]
    for f in figures:
        for attr, role in (("_suptitle", "suptitle"), ("_supxlabel", "supxlabel"), ("_supylabel", "supylabel")):
            t = getattr(f, attr, None)
            if t is not None:
                roles[id(t)] = role
        for t in f.texts:
            roles.setdefault(id(t), "figure text")
        for leg in f.legends:
            legend(leg, "the figure")
    return roles


def _box(bbox) -> list:
    return [float(bbox.x0), float(bbox.y0), float(bbox.x1), float(bbox.y1)]


def _clip(artist):
    """The display-pixel box an artist is clipped to (its clip box and its clip path's
    extents), or None when it is not clipped."""
    if not artist.get_clip_on():
        return None
    boxes = []
    if artist.get_clip_box() is not None:
        boxes.append(_box(artist.get_clip_box()))
    path = artist.get_clip_path()
    if path is not None:
        boxes.append(_box(path.get_fully_transformed_path().get_extents()))
    if not boxes:
        return None
    return [max(b[0] for b in boxes), max(b[1] for b in boxes), min(b[2] for b in boxes), min(b[3] for b in boxes)]


def _rgb_over(colour, background) -> list:
    """An RGBA colour as the reader sees it: composited over `background` (RGB)."""
    r, g, b, a = colour
    return [float(a * c + (1 - a) * bg) for c, bg in zip((r, g, b), background)]


def _series_colours(ax, glyphs) -> list:
    """[(what, rgb)] of the lines and markers of `ax`; values-coded collections left out."""
    import numpy as np
    from matplotlib.collections import LineCollection, PathCollection
    from matplotlib.colors import to_rgba

    back = to_rgba(ax.get_facecolor())[:3]
    found = []
    for i, line in enumerate(ax.get_lines()):
        if not line.get_visible() or len(np.atleast_1d(line.get_xdata())) == 0:
            continue
        label = line.get_label()
        what = f"line {label!r}" if label and not label.startswith("_") else f"line {i}"
        alpha = line.get_alpha()
        drawn = line.get_linestyle() not in ("None", " ", "", "none") and line.get_linewidth() > 0
        marker = line.get_marker() not in (None, "None", " ", "", "none")
        if drawn:
            colour = line.get_color()
        elif marker:
            face = line.get_markerfacecolor()
            colour = face if not (isinstance(face, str) and face.lower() == "none") else line.get_markeredgecolor()
        else:
            continue
        rgba = to_rgba(colour, alpha)
        if rgba[3] > 0:
            found.append((what, _rgb_over(rgba, back)))
    for i, coll in enumerate(ax.collections):
        if not isinstance(coll, (LineCollection, PathCollection)) or not coll.get_visible() \
                or coll in glyphs or hasattr(coll, "_figure_text_labels") or coll.get_array() is not None:
            continue
        if isinstance(coll, PathCollection) and len(coll.get_offsets()) == 0:
            continue
        if isinstance(coll, LineCollection) and len(coll.get_segments()) == 0:
            continue
        face = coll.get_facecolor() if not isinstance(coll, LineCollection) else np.zeros((0, 4))
        colours = face if len(face) and np.any(face[:, 3] > 0) else coll.get_edgecolor()
        colours = [tuple(c) for c in np.asarray(colours) if c[3] > 0]
        distinct = list(dict.fromkeys(colours))
        if not distinct or len(distinct) > MAX_SERIES_COLOURS:
            continue
        label = coll.get_label()
        what = f"{type(coll).__name__} {label!r}" if label and not label.startswith("_") \
            else f"{type(coll).__name__} {i}"
        found += [(what, _rgb_over(c, back)) for c in distinct]
    return found


def measure(fig, column_px: float) -> dict:
    """Draw `fig` with its canvas and describe, in CSS pixels of what the reader sees, its
    rendered texts, the area shown, its images and its line colours."""
    own = fig.canvas
    if not hasattr(own, "get_renderer"):
        # a figure without a canvas of its own is shown as a PNG (display, savefig): drawn
        # with an Agg canvas for the while, as savefig does
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    canvas = fig.canvas
    _recording.texts, _recording.glyphs = [], []
    try:
        canvas.draw()
        texts, glyphs = _recording.texts, _recording.glyphs
        renderer = canvas.get_renderer()
        return _describe(fig, renderer, texts, glyphs, column_px)
    finally:
        _recording.texts = _recording.glyphs = None
        if canvas is not own:
            fig.set_canvas(own)


def _describe(fig, renderer, texts, glyphs, column_px: float) -> dict:
    import numpy as np
    from matplotlib.collections import QuadMesh
    from matplotlib.image import AxesImage
    from matplotlib.transforms import Bbox

    canvas = fig.canvas
    ratio = float(getattr(canvas, "device_pixel_ratio", 1.0) or 1.0)
    interactive = _interactive(fig)
    if interactive:
        shown, scale = fig.bbox, 1.0 / ratio
    else:
        tight = fig.get_tightbbox(renderer)       # in inches, as savefig(bbox_inches="tight")
        import matplotlib

        pad = matplotlib.rcParams["savefig.pad_inches"]
        shown = tight.padded(pad).transformed(fig.dpi_scale_trans)
        scale = min(1.0, column_px / shown.width) / ratio
    # CSS pixels from the shown area's lower left corner
    to_css = lambda b: [(b[0] - shown.x0) * scale, (b[1] - shown.y0) * scale,
                        (b[2] - shown.x0) * scale, (b[3] - shown.y0) * scale]
    axes = _axes_names(fig)
    roles = _roles(fig, axes)
    out_texts = []
    seen = set()
    for t, box, clip in texts:
        if id(t) in seen:
            continue
        seen.add(id(t))
        if isinstance(box, Exception):
            raise RuntimeError(f"the extent of {roles.get(id(t), 'a text')} {t.get_text()!r}") from box
        if not np.all(np.isfinite(box.extents)) or box.width <= 0 or box.height <= 0:
            continue
        clip = to_css(clip) if clip is not None else None
        out_texts.append({"what": roles.get(id(t), "text"), "text": t.get_text()[:60],
                          "box": to_css(_box(box)), "clip": clip})
    for coll in glyphs:
        if coll.axes is None:
            continue
        strings = coll._figure_text_labels or ["?"] * len(coll.get_paths())
        offsets = coll.get_offset_transform().transform(coll.get_offsets())
        transform = coll.get_transform()
        clip = _clip(coll)
        clip = to_css(clip) if clip is not None else None
        for s, path, (ox, oy) in zip(strings, coll.get_paths(), offsets):
            if len(path.vertices) == 0 or not np.isfinite([ox, oy]).all():
                continue
            ext = path.get_extents(transform)
            box = Bbox.from_extents(ext.x0 + ox, ext.y0 + oy, ext.x1 + ox, ext.y1 + oy)
            out_texts.append({"what": f"glyph label in {axes.get(coll.axes, 'an axes')}", "text": s,
                              "box": to_css(_box(box)), "clip": clip})
    images = []
    mappables = []
    for ax, name in axes.items():
        is_bar = getattr(ax, "_colorbar", None) is not None
        for art in list(ax.images) + [c for c in ax.collections if isinstance(c, QuadMesh)]:
            if not art.get_visible():
                continue
            array = art.get_array()
            scalar = array is not None and (np.ndim(array) == 2 if isinstance(art, AxesImage)
                                            else np.ndim(array) in (1, 2))
            bar = getattr(art, "colorbar", None)
            has_bar = bar is not None and bar.ax in axes and bar.ax.get_visible()
            entry = {"axes": name, "kind": type(art).__name__, "scalar": bool(scalar),
                     "cmap": art.get_cmap().name, "clim": [float(v) if v is not None else None
                                                          for v in art.get_clim()],
                     "colour_bar": bool(has_bar),
                     "cmap_rgb": [list(map(float, c[:3])) for c in art.get_cmap()(np.linspace(0, 1, 16))]}
            (mappables if is_bar else images).append(entry)
    colours = {name: [[w, rgb] for w, rgb in _series_colours(ax, glyphs)]
               for ax, name in axes.items() if getattr(ax, "_colorbar", None) is None and ax.get_visible()}
    # the measuring itself (tight box, title positions) marks the figure stale; it is not changed
    fig.stale = False
    label = fig.get_label() or (fig._suptitle.get_text() if getattr(fig, "_suptitle", None) else "")
    return {"kind": "ipympl" if interactive else "inline", "label": label,
            "size_css": [float(shown.width * scale), float(shown.height * scale)],
            "scale": float(scale), "texts": out_texts, "images": images,
            "colours": {k: v for k, v in colours.items() if v}}


def setup_source(path: str, column_px: float, module_path: str) -> str:
    """The source of the unsaved first cell that installs the recorder in a kernel."""
    return (
        "def _figure_text_setup():\n"
        "    import importlib.util, sys\n"
        f"    spec = importlib.util.spec_from_file_location('_figure_text', {module_path!r})\n"
        "    module = importlib.util.module_from_spec(spec)\n"
        "    sys.modules['_figure_text'] = module\n"
        "    spec.loader.exec_module(module)\n"
        f"    module.install(get_ipython(), {path!r}, {column_px!r})\n"
        "_figure_text_setup()\n"
        "del _figure_text_setup\n")


# --------------------------------------------------------------------------- test side

def read_records(path) -> list:
    """The JSON lines the recorder wrote (none if the file is missing)."""
    try:
        text = open(path, encoding="utf-8").read()
    except FileNotFoundError:
        return []
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def _intersection(a, b):
    return min(a[2], b[2]) - max(a[0], b[0]), min(a[3], b[3]) - max(a[1], b[1])


def _visible(t):
    """The part of a text's box its clip box lets through, or None."""
    box = t["box"]
    if t["clip"] is None:
        return box
    c = t["clip"]
    v = [max(box[0], c[0]), max(box[1], c[1]), min(box[2], c[2]), min(box[3], c[3])]
    return v if v[2] > v[0] and v[3] > v[1] else None


def _name(t, height: float) -> str:
    """What a text is, what it says and where: its top left corner, in px from the top left
    of what is shown (two labels may say the same)."""
    text = t["text"] if len(t["text"]) <= 40 else t["text"][:38] + "…"
    return f"{t['what']} {text!r} at ({t['box'][0]:.0f}, {height - t['box'][3]:.0f})"


def overlaps(record, tolerance: float = TOLERANCE_PX) -> list:
    """Pairs of rendered texts whose boxes overlap by more than `tolerance` px both ways."""
    texts = [(t, _visible(t)) for t in record.get("texts", [])]
    texts = [(t, v) for t, v in texts if v is not None]
    height = record["size_css"][1]
    found = []
    for i, (a, va) in enumerate(texts):
        for b, vb in texts[i + 1:]:
            w, h = _intersection(va, vb)
            if w > tolerance and h > tolerance:
                found.append(f"{_name(a, height)} overlaps {_name(b, height)} by {w:.1f} x {h:.1f} px")
    return found


def cut_texts(record, tolerance: float = TOLERANCE_PX) -> list:
    """Texts that run past the edge of the area shown, or past their own clip box."""
    width, height = record["size_css"]
    found = []
    for t in record.get("texts", []):
        box = t["box"]
        visible = _visible(t)
        if visible is None:
            continue
        past = [f"{side} by {d:.1f} px" for side, d in
                (("left", -visible[0]), ("bottom", -visible[1]), ("right", visible[2] - width),
                 ("top", visible[3] - height)) if d > tolerance]
        if past:
            found.append(f"{_name(t, height)} is cut by the figure's edge ({', '.join(past)})")
        elif t["clip"] is not None:
            lost = max(visible[0] - box[0], visible[1] - box[1], box[2] - visible[2], box[3] - visible[3])
            if lost > tolerance:
                found.append(f"{_name(t, height)} is cut by its axes ({lost:.1f} px hidden)")
    return found


def lab(rgb):
    """CIELAB (D65) of sRGB colours in [0, 1]: an array (..., 3)."""
    import numpy as np

    c = np.asarray(rgb, dtype=float)
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    xyz = linear @ np.array([[0.4124564, 0.2126729, 0.0193339],
                             [0.3575761, 0.7151522, 0.1191920],
                             [0.1804375, 0.0721750, 0.9503041]])
    xyz = xyz / np.array([0.95047, 1.0, 1.08883])
    eps, kappa = 216 / 24389, 24389 / 27
    f = np.where(xyz > eps, np.cbrt(xyz), (kappa * xyz + 16) / 116)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], axis=-1)


def lch(rgb):
    """(L*, C*ab, hue in degrees) of an sRGB colour in [0, 1]."""
    import numpy as np

    L, a, b = lab(rgb)
    return float(L), float(np.hypot(a, b)), float(np.degrees(np.arctan2(b, a)) % 360)


def hue_clash(c1, c2) -> str | None:
    """Why two colours (sRGB in [0, 1]) differ only in lightness, or None if they differ in hue
    (or are the same colour)."""
    return _clash(lab(c1), lab(c2))


def _clash(lab1, lab2) -> str | None:
    import numpy as np

    if float(np.linalg.norm(lab1 - lab2)) < SAME_COLOUR_DE:
        return None
    (l1, k1, h1), (l2, k2, h2) = (
        (float(c[0]), float(np.hypot(c[1], c[2])), float(np.degrees(np.arctan2(c[2], c[1])) % 360))
        for c in (lab1, lab2))
    if k1 < NEUTRAL_CHROMA and k2 < NEUTRAL_CHROMA:
        return f"both neutral (L* {l1:.0f} and {l2:.0f})"
    if k1 >= NEUTRAL_CHROMA and k2 >= NEUTRAL_CHROMA:
        dh = abs(h1 - h2) % 360
        dh = min(dh, 360 - dh)
        if dh < MIN_HUE_DEG:
            return f"hues {h1:.0f} and {h2:.0f} deg, {dh:.0f} apart (< {MIN_HUE_DEG:.0f}), L* {l1:.0f} and {l2:.0f}"
    return None


def hue_clashes(record) -> list:
    found = []
    for axes, entries in record.get("colours", {}).items():
        labs = lab([c for _, c in entries])
        for i, (w1, c1) in enumerate(entries):
            for j in range(i + 1, len(entries)):
                w2, c2 = entries[j]
                why = _clash(labs[i], labs[j])
                if why:
                    found.append(f"in {axes}: {w1} ({_hex(c1)}) and {w2} ({_hex(c2)}): {why}")
    return found


def _hex(rgb) -> str:
    return "#" + "".join(f"{round(255 * v):02X}" for v in rgb)


def grey_map(cmap_rgb) -> bool:
    """Whether a colour map's samples are all neutral: a photo's grey scale, not values."""
    import numpy as np

    lab_ = lab(cmap_rgb)
    return bool(np.all(np.hypot(lab_[:, 1], lab_[:, 2]) < NEUTRAL_CHROMA))


def missing_colour_bars(record) -> list:
    """Images of values (a colour map that is not grey) without a colour bar of theirs or of
    one with the same colour map and limits in the same figure."""
    images = record.get("images", [])
    barred = {(m["cmap"], tuple(m["clim"])) for m in images if m["colour_bar"]}
    found = []
    for m in images:
        if m["scalar"] and not grey_map(m["cmap_rgb"]) and not m["colour_bar"] \
                and (m["cmap"], tuple(m["clim"])) not in barred:
            found.append(f"{m['kind']} in {m['axes']} (colour map {m['cmap']!r}) has no colour bar")
    return found
