"""Hand-label target pairs on a stereo pair: click a left feature, then its right partner.

:meth:`LabelModel.click` takes side-by-side coordinates by default (the right image starts at
``W + GAP``, :data:`ismb_lab.plotting.GAP`), image coordinates with ``side="left"`` or ``"right"``.
"""

from __future__ import annotations

import html
from dataclasses import dataclass
from pathlib import Path

import ipywidgets
import numpy as np
from matplotlib.figure import Figure

from .._core.validation import ParameterError, ParameterTypeError, check_choice, check_number, message
from ..tuning.evaluation import Score, score, unlabelled
from ..matching.pipeline import MatchConfig, Prepared, match, prepare
from ..network.methods import DEFAULT_METHOD
from ..plotting import GAP, OKABE_ITO, VERDICT_COLOURS
from ..labels.classroom import save_merging, targets_path, voila_without_hub
from ..labels.targets import TargetSet, load_targets, snap, targets_from_matches
from ._common import Base, Pane, button, check_type, column_figsize, draw_pair, pair_files, with_class
from .photos import FromPhotos

__all__ = ["COLUMNS", "KEY_AFTER", "Comparison", "draw_labels", "LabelModel", "pairs_html", "SavedScore", "TargetLabeler",
           "update_labels"]

COLUMNS = ("Pair", "Left", "Right", "y_left", "x_left", "y_right", "x_right", "disparity")

#: The answer key opens, for good, once this many pairs of the student's own are saved or loaded.
KEY_AFTER = 5


@dataclass(frozen=True)
class Comparison:
    """Student labels against the answer key, as feature pairs ``(i, k)``; `off_feature` counts
    key pairs with no feature within reach (not missing: they cannot be labelled)."""

    correct: np.ndarray
    wrong: np.ndarray
    missing: np.ndarray
    off_feature: int

    def __str__(self) -> str:
        text = f"{len(self.correct)} correct, {len(self.wrong)} wrong, {len(self.missing)} missing"
        return text + (f" ({self.off_feature} key pairs lie off the features)" if self.off_feature else "")


@dataclass(frozen=True, eq=False)
class SavedScore:
    """A method's matches scored against the labels saved in a file (:meth:`LabelModel.score_saved`):
    E counts only wrong partners of labelled left corners, T the saved pairs."""

    path: Path
    method: str
    seed: int
    pairs: np.ndarray
    score: Score
    errors: np.ndarray

    def __str__(self) -> str:
        wrong = [(int(i) + 1, int(k) + 1) for i, k in self.errors]
        return (f"{self.path.name}: {len(self.pairs)} pairs; Method-{self.method}, seed {self.seed}: "
                f"C/E/T = {self.score}; its errors (left, right), numbered from 1: {wrong}")


def _pair_array(pairs) -> np.ndarray:
    return np.array(sorted(pairs), dtype=np.intp).reshape(-1, 2)


class LabelModel:
    """The labels of one stereo pair and every edit on them.

    A click snaps to a feature within `snap_radius` px, an answer-key point within `key_tol` px.
    With `exclusive`, :meth:`save` refuses an existing file this model did not load or save
    instead of merging with it (on a page many visitors share).

    >>> from ismb_lab.scenes import synthetic_scene
    >>> scene = synthetic_scene(0)
    >>> model = LabelModel(prepare(scene.left, scene.right))
    >>> x, y = model.left_xy[0]
    >>> model.click(x + 1, y, side="left")
    'left feature 1 chosen: now click its partner in the right image'
    >>> model.click(0, 0)
    'no feature within 8 px of (0, 0) in the left image: click nearer a numbered feature'
    """

    def __init__(self, prepared: Prepared, *, path=None, answer_key: TargetSet | None = None,
                 snap_radius: float = 8.0, key_tol: float = 3.0, exclusive: bool = False):
        owner = "LabelModel"
        self.exclusive = check_type(exclusive, bool, "exclusive", owner, "True or False")
        check_type(prepared, Prepared, "prepared", owner, "a Prepared (see matching.prepare)")
        if answer_key is not None and not isinstance(answer_key, TargetSet):
            raise ParameterTypeError(message("answer_key", owner, "None or a TargetSet", answer_key))
        self.prepared = prepared
        self.path = None if path is None else Path(path)
        self.answer_key = answer_key
        self.snap_radius = check_number(snap_radius, "snap_radius", owner, low=0, low_open=True)
        self.key_tol = check_number(key_tol, "key_tol", owner, low=0)
        self.left_xy = prepared.problem.left_xy
        self.right_xy = prepared.problem.right_xy
        self.height, self.width = prepared.pair.shape
        self.offset = self.width + GAP
        self._pairs: list[tuple[int, int]] = []
        self._history: list[tuple] = []
        self._saved: tuple = ()
        self.key_open = False      # see KEY_AFTER
        self._base: TargetSet | None = None   # the file as last loaded or saved here
        self._base_path: Path | None = None
        self.pending: int | None = None   # a left feature waiting for its partner
        self.selected: int | None = None  # index into pairs
        self.message = "click a left feature, then its partner in the right image"

    @property
    def pairs(self) -> np.ndarray:
        """The labelled ``(i, k)`` feature pairs, sorted: an ``(m, 2)`` array."""
        return _pair_array(self._pairs)

    @property
    def save_status(self) -> str:
        """``"unsaved"``, ``"saved"`` (as last saved or loaded here) or ``""`` (nothing yet)."""
        if tuple(self._pairs) != self._saved:
            return "unsaved"
        return "saved" if self._base is not None else ""

    def rows(self) -> list[tuple]:
        """The table in the thesis' column order (:data:`COLUMNS`); features numbered from 1."""
        out = []
        for n, (i, k) in enumerate(self._pairs, 1):
            (xl, yl), (xr, yr) = self.left_xy[i], self.right_xy[k]
            out.append((n, i + 1, k + 1, float(yl), float(xl), float(yr), float(xr),
                        float(np.hypot(xl - xr, yl - yr))))
        return out

    def targets(self) -> TargetSet:
        """The labels as a :class:`~ismb_lab.labels.targets.TargetSet` bound to the two images."""
        pair = self.prepared.pair
        return targets_from_matches(self.pairs, self.left_xy, self.right_xy,
                                    left_sha256=pair.left_sha256, right_sha256=pair.right_sha256,
                                    **(self._base.meta if self._base is not None else {}))

    def compare(self) -> Comparison:
        """Compare the labels with the answer key (ParameterError without one)."""
        if self.answer_key is None:
            raise ParameterError(message("answer_key", "LabelModel.compare", "a TargetSet", None))
        snapped = snap(self.answer_key, self.left_xy, self.right_xy, tol=self.key_tol)
        key = {tuple(p) for p in snapped.pairs.tolist()}
        mine = set(self._pairs)
        off = len(self.answer_key) - len(snapped.pairs)
        return Comparison(_pair_array(mine & key), _pair_array(mine - key), _pair_array(key - mine), off)

    def locate(self, x, y, side=None):
        """``(side, x, y)`` in image coordinates of a click, or None off both images."""
        x = check_number(x, "x", "LabelModel.click")
        y = check_number(y, "y", "LabelModel.click")
        if side is None:
            if x > self.width - 0.5:
                if x < self.offset - 0.5:
                    return None
                side, x = "right", x - self.offset
            else:
                side = "left"
        check_choice(side, "side", "LabelModel.click", ("left", "right"))
        if not (-0.5 <= x <= self.width - 0.5 and -0.5 <= y <= self.height - 0.5):
            return None
        return side, x, y

    def nearest(self, side: str, x: float, y: float) -> tuple[int | None, float]:
        """The nearest feature of one image to ``(x, y)`` and its distance (None, inf if none)."""
        xy = self.left_xy if side == "left" else self.right_xy
        if not len(xy):
            return None, float("inf")
        d = np.hypot(xy[:, 0] - x, xy[:, 1] - y)
        j = int(np.argmin(d))
        return j, float(d[j])

    def _say(self, text: str) -> str:
        self.message = text
        return text

    def _remember(self):
        self._history.append((tuple(self._pairs), self.pending, self.selected))

    def click(self, x, y, side=None) -> str:
        """Handle a click (coordinates: see the module docstring); returns the status text.

        A left feature starts a pair, a right one completes it; a feature already paired
        selects its pair; the pending left feature clicked again is released.
        """
        where = self.locate(x, y, side)
        if where is None:
            return self._say(f"({x:g}, {y:g}) is not on either image: click a numbered feature")
        side, ix, iy = where
        j, dist = self.nearest(side, ix, iy)
        if j is None or dist > self.snap_radius:
            return self._say(f"no feature within {self.snap_radius:g} px of ({ix:g}, {iy:g}) in the "
                             f"{side} image: click nearer a numbered feature")
        column = 0 if side == "left" else 1
        owner = [n for n, p in enumerate(self._pairs) if p[column] == j]
        if owner:
            self.pending, self.selected = None, owner[0]
            i, k = self._pairs[owner[0]]
            return self._say(f"pair {owner[0] + 1} selected (left {i + 1} - right {k + 1}): "
                             "Delete removes it")
        if side == "left":
            self.selected = None
            if self.pending == j:
                self.pending = None
                return self._say(f"left feature {j + 1} released")
            self.pending = j
            return self._say(f"left feature {j + 1} chosen: now click its partner in the right image")
        if self.pending is None:
            return self._say(f"right feature {j + 1}: click a left feature first")
        self.add_pair(self.pending, j)
        return self.message

    def add_pair(self, i, k) -> None:
        """Label left feature `i` with right feature `k` (0-based); each feature pairs once."""
        owner = "LabelModel.add_pair"
        i = check_number(i, "i", owner, low=0, high=len(self.left_xy) - 1, integer=True)
        k = check_number(k, "k", owner, low=0, high=len(self.right_xy) - 1, integer=True)
        for col, j, name in ((0, i, "i"), (1, k, "k")):
            taken = [p for p in self._pairs if p[col] == j]
            if taken:
                raise ParameterError(message(name, owner, "a feature not yet in a pair (delete that "
                                             "pair first)", f"{j}, already in the pair {taken[0]}"))
        self._remember()
        self._pairs = sorted(self._pairs + [(i, k)])
        self.pending, self.selected = None, None
        d = np.hypot(*(self.left_xy[i] - self.right_xy[k]))
        self._say(f"pair added: left {i + 1} - right {k + 1}, disparity {d:.2f} px "
                  f"({len(self._pairs)} pairs)")

    def select(self, index) -> None:
        """Select pair `index` (0-based, table order) or None."""
        if index is not None:
            index = check_number(index, "index", "LabelModel.select", low=0,
                                 high=len(self._pairs) - 1, integer=True)
        self.selected, self.pending = index, None

    def delete_selected(self) -> bool:
        """Remove the selected pair; False (and a message) when none is selected."""
        if self.selected is None:
            self._say("nothing selected: click a feature of a pair to select it")
            return False
        self._remember()
        i, k = self._pairs.pop(self.selected)
        self.selected = None
        self._say(f"pair left {i + 1} - right {k + 1} deleted ({len(self._pairs)} pairs)")
        return True

    def undo(self) -> bool:
        """Take back the last add, delete or load; False when there is nothing to undo."""
        if not self._history:
            self._say("nothing to undo")
            return False
        pairs, self.pending, self.selected = self._history.pop()
        self._pairs = list(pairs)
        self._say(f"undone ({len(self._pairs)} pairs)")
        return True

    def _path(self, path, owner) -> Path:
        path = self.path if path is None else path
        if path is None:
            raise ParameterError(message("path", owner, "a file path (none was given here or to the "
                                         "labeler)", None))
        return Path(check_type(path, (str, Path), "path", owner, "a str or Path"))

    def _on_disk(self, pairs: list, targets: TargetSet, path: Path) -> None:
        """Take `pairs` as the labels, as the file `path` now holds them (`targets`)."""
        self._pairs = pairs
        self._saved = tuple(pairs)
        self.key_open = self.key_open or len(pairs) >= KEY_AFTER
        self._base, self._base_path = targets, path

    def save(self, path=None) -> Path:
        """Write the labels atomically, merged with what others saved to the file meanwhile
        (:func:`ismb_lab.labels.classroom.save_merging`); on failure the old file is untouched."""
        path = self._path(path, "LabelModel.save")
        base = self._base if self._base is not None and path == self._base_path else None
        if self.exclusive and base is None and path.exists():
            raise ParameterError(f"The 'path' parameter of LabelModel.save must be a new file or one "
                                 f"this page loaded. Got {str(path)!r}, which holds labels this page "
                                 "did not load, instead: Load them if they are yours, or use another name")
        merged = save_merging(path, self.targets(), base)
        snapped = snap(merged.targets, self.left_xy, self.right_xy)
        self._on_disk(sorted(set(map(tuple, snapped.pairs.tolist()))), merged.targets, path)
        others = (f"; kept {merged.kept_from_disk} pairs saved to it meanwhile from another tab"
                  if merged.kept_from_disk else "")
        self._say(f"saved {len(self._pairs)} pairs to {path}{others}")
        return path

    def score_saved(self, method=DEFAULT_METHOD, *, seed: int = 0, params=None, path=None) -> SavedScore | None:
        """Match the pair with `method` and score it against the labels saved in `path` (default:
        the labeller's file), leaving out unlabelled left corners; None when nothing is saved there.

        Parameters
        ----------
        method : str, default ``DEFAULT_METHOD``
            The matching method.
        seed : int, default 0
            Update-order seed.
        params : Params, optional
            Default the method's.
        path : str or os.PathLike, optional
            The targets file; default the model's.

        Returns
        -------
        result : SavedScore or None
            The score and its errors.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from ismb_lab.scenes import synthetic_scene
        >>> scene = synthetic_scene(0)
        >>> model = LabelModel(prepare(scene.left, scene.right), path=pathlib.Path(tempfile.mkdtemp()) / "t.json")
        >>> model.score_saved() is None
        True
        """
        owner = "LabelModel.score_saved"
        path = self._path(path, owner)
        if not path.is_file():
            return None
        saved = snap(load_targets(path, pair=self.prepared.pair), self.left_xy, self.right_xy).pairs
        result = match(prepared=self.prepared, method=method, params=params, seed=seed)
        mine = set(map(tuple, saved.tolist()))
        labelled = set(saved[:, 0].tolist())
        errors = [(i, k) for i, k in result.pairs.tolist() if i in labelled and (i, k) not in mine]
        unknown = unlabelled(saved, len(self.left_xy))
        return SavedScore(path, result.method, seed, saved, score(result.pairs, saved, unknown),
                          np.array(errors, dtype=np.intp).reshape(-1, 2))

    def load(self, path=None) -> int:
        """Replace the labels by a targets file's, each on its own feature (within 1.5 px); any
        error leaves the labels as they were."""
        owner = "LabelModel.load"
        path = self._path(path, owner)
        targets = load_targets(path, pair=self.prepared.pair)
        snapped = snap(targets, self.left_xy, self.right_xy)
        lost = np.union1d(snapped.missing_left, snapped.missing_right)
        if lost.size:
            raise ParameterError(f"The 'path' parameter of {owner} must be targets on this pair's "
                                 f"features. Got {str(path)!r}, where {lost.size} of {len(targets)} "
                                 f"pairs have no feature within 1.5 px (first: pair {lost[0]}) instead.")
        if snapped.shared.size:
            raise ParameterError(f"The 'path' parameter of {owner} must be targets using each "
                                 f"feature once. Got {str(path)!r}, where pairs "
                                 f"{snapped.shared.tolist()} share a feature instead.")
        self._remember()
        self._on_disk(sorted(map(tuple, snapped.pairs.tolist())), targets, path)
        self.pending = self.selected = None
        self._say(f"loaded {len(self._pairs)} pairs from {path}")
        return len(self._pairs)


#: The labeller's lines: the key's verdicts (a key pair not labelled yet black dashed, so that
#: no orange sits beside the vermillion), orange before the key is shown, purple when selected.
_KEY_COLOURS = {"correct": VERDICT_COLOURS["correct"], "wrong": VERDICT_COLOURS["wrong partner"],
                "missing": OKABE_ITO["black"], "plain": OKABE_ITO["orange"],
                "selected": OKABE_ITO["reddish purple"]}


def draw_labels(ax, model: LabelModel) -> dict:
    """The labeler's artists on `ax`: the pair view (:func:`draw_pair`), the key's lines, the markers."""
    from matplotlib.collections import LineCollection

    art = draw_pair(ax, model)
    art["lines"].set_array(None)
    art["lines"].set_linewidths(1.6)
    art["missing"] = ax.add_collection(LineCollection([], colors=_KEY_COLOURS["missing"], linestyles="dashed",
                                                      linewidths=1.4))
    art["pending"], = ax.plot([], [], "o", mfc="none", mec=_KEY_COLOURS["selected"], ms=12, mew=2)
    ax.set_xlim(-0.5, model.offset + model.width - 0.5)
    ax.set_ylim(model.height - 0.5, -0.5)
    return art


def update_labels(art: dict, model: LabelModel, show_key: bool = False) -> Comparison | None:
    """Bring the artists of :func:`draw_labels` up to date with `model`."""
    pairs = model.pairs
    shift = np.array([model.offset, 0.0])
    segments = np.stack([model.left_xy[pairs[:, 0]], model.right_xy[pairs[:, 1]] + shift], axis=1)
    colours = [_KEY_COLOURS["plain"]] * len(pairs)
    widths = [1.6] * len(pairs)
    comparison = None
    missing = np.zeros((0, 2, 2))
    if show_key and model.answer_key is not None:
        comparison = model.compare()
        good = {tuple(p) for p in comparison.correct.tolist()}
        colours = [_KEY_COLOURS["correct" if tuple(p) in good else "wrong"] for p in pairs.tolist()]
        gone = comparison.missing
        missing = np.stack([model.left_xy[gone[:, 0]], model.right_xy[gone[:, 1]] + shift], axis=1)
    if model.selected is not None:
        colours[model.selected] = _KEY_COLOURS["selected"]
        widths[model.selected] = 3.5
    art["lines"].set_segments(segments)
    art["lines"].set_colors(colours)
    art["lines"].set_linewidths(widths)
    art["missing"].set_segments(missing)
    if model.pending is not None:
        art["pending"].set_data(*model.left_xy[[model.pending]].T)
    else:
        art["pending"].set_data([], [])
    return comparison


def pairs_html(model: LabelModel) -> str:
    """The live table of pairs as HTML (thesis column order)."""
    head = "".join(f"<th>{c}</th>" for c in COLUMNS)
    body = []
    for n, row in enumerate(model.rows()):
        style = ' style="background:#fde"' if n == model.selected else ""
        cells = [f"{v}" for v in row[:3]] + [f"{v:g}" for v in row[3:7]] + [f"{row[7]:.2f}"]
        body.append(f"<tr{style}>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    if not body:
        body = [f'<tr><td colspan="{len(COLUMNS)}">no pairs yet</td></tr>']
    return f'<table class="ismb-table"><tr>{head}</tr>{"".join(body)}</table>'


class TargetLabeler(FromPhotos, Base):
    """Label target pairs by clicking; save them in the targets format.

    `path`, the targets file of Save and Load, is by default the student's own
    (:func:`ismb_lab.labels.classroom.targets_path`, named after `pair_name`); under Voilà without
    a hub, where visitors share one login, the labeller asks for a name first.

    Parameters
    ----------
    left, right : path or ndarray, or a Prepared as `left`
        The image pair.
    path : str or os.PathLike, optional
        The targets file of Save and Load; default the student's own.
    config : MatchConfig, optional
        Corner settings: labels snap to the features the matcher sees.
    answer_key : TargetSet or path, optional
        Ground truth for "Show answer key".
    pair_name : str, optional
        The pair's name in the default file name.

    Notes
    -----
    CSS classes: root ``ismb-labeler``, figure ``ismb-stereo``, buttons ``ismb-undo``,
    ``ismb-delete``, ``ismb-save``, ``ismb-load``, toggle ``ismb-answer-key``, table
    ``ismb-pairs``, unsaved-changes flag ``ismb-dirty``, key summary ``ismb-key-summary``,
    status ``ismb-status``, error log ``ismb-log``.
    """

    def __init__(self, left, right=None, *, path=None, config: MatchConfig | None = None,
                 answer_key=None, pair_name: str | None = None):
        super().__init__()
        prepared = left if isinstance(left, Prepared) else prepare(left, right, config)
        if answer_key is not None and not isinstance(answer_key, TargetSet):
            answer_key = load_targets(answer_key, pair=prepared.pair)
        self.pair_name = pair_name or prepared.pair.left_sha256[:12]
        ask = path is None and voila_without_hub()
        if path is None and not ask:
            path = targets_path(self.pair_name, Path.cwd(), also=())
        self.model = LabelModel(prepared, path=path, answer_key=answer_key, exclusive=ask)
        # each image gets half the column (286 px of 320 px images); on larger photos the
        # toolbar's zoom tells corners apart, and clicks still land in image coordinates
        self.pane = Pane(column_figsize(self.model.offset + self.model.width, self.model.height), "ismb-stereo")
        self.panes = (self.pane,)
        self.ax = self.pane.fig.add_axes((0, 0, 1, 1))
        self.artists = draw_labels(self.ax, self.model)

        self.undo_button = button("Undo", "ismb-undo", icon="undo")
        self.delete_button = button("Delete", "ismb-delete", "Delete the selected pair", icon="trash")
        self.save_button = button("Save", "ismb-save", "Save the pairs to the targets file", icon="save")
        self.load_button = button("Load", "ismb-load", "Load the pairs from the targets file",
                                  icon="folder-open")
        self.key_toggle = with_class(ipywidgets.ToggleButton(
            description="Show answer key", disabled=True, layout=ipywidgets.Layout(width="auto"),
            tooltip=f"Save {KEY_AFTER} pairs of your own first, then compare them with the ground truth"
            if answer_key is not None else "This pair has no answer key"), "ismb-answer-key")
        self.dirty_label = with_class(ipywidgets.HTML(""), "ismb-dirty")
        self.path_label = with_class(ipywidgets.HTML(""), "ismb-path")
        self.name_box = None
        if ask:
            self.name_box = with_class(ipywidgets.Text(
                description="Your name:", placeholder="type it before you save",
                style={"description_width": "initial"}), "ismb-name")
            self.name_box.observe(self.guard(lambda change: self.set_name(change["new"])), names="value")
        self._show_path()
        self.key_summary = with_class(ipywidgets.HTML(""), "ismb-key-summary")
        self.table = with_class(ipywidgets.HTML(""), "ismb-pairs")

        self.undo_button.on_click(self.guard(lambda _: self.undo()))
        self.delete_button.on_click(self.guard(lambda _: self.delete_selected()))
        self.save_button.on_click(self.guard(lambda _: self._quietly(self.save)))
        self.load_button.on_click(self.guard(lambda _: self._quietly(self.load)))
        self.key_toggle.observe(self.guard(lambda _: self.refresh()), names="value")
        self.pane.fig.canvas.mpl_connect("button_press_event", self.guard(self._on_press))

        bar = ipywidgets.HBox([self.undo_button, self.delete_button, self.save_button,
                               self.load_button, self.key_toggle, self.dirty_label])
        head = [self.name_box, self.path_label] if self.name_box is not None else [self.path_label]
        self.widget = with_class(ipywidgets.VBox([self.pane.widget, *head, bar, self.status, self.key_summary,
                                                  self.table, self.log]), "ismb-labeler")
        self.refresh()

    @classmethod
    def from_folder(cls, folder, *, path=None, config: MatchConfig | None = None) -> "TargetLabeler":
        """Label ``folder/left.png`` and ``folder/right.png`` (answer key: ``answer_key.json``, if any).

        Parameters
        ----------
        folder : str or Path
            A pair folder.
        path : str or os.PathLike, optional
            The targets file; default the student's own, named after the folder.
        config : MatchConfig, optional
            Corner settings.

        Returns
        -------
        labeler : TargetLabeler
            The widget.
        """
        left, right, key = pair_files(folder, "TargetLabeler.from_folder")
        return cls(left, right, path=path, config=config, answer_key=key if key.is_file() else None,
                   pair_name=Path(folder).resolve().name)

    @property
    def pairs(self) -> np.ndarray:
        return self.model.pairs

    def _redrawn(self, value):
        self.refresh()
        return value

    def click(self, x, y, side=None) -> str:
        """:meth:`LabelModel.click` (side-by-side coordinates unless `side` is given), redrawn."""
        return self._redrawn(self.model.click(x, y, side))

    def add_pair(self, i, k) -> None:
        self._redrawn(self.model.add_pair(i, k))

    def undo(self) -> bool:
        return self._redrawn(self.model.undo())

    def delete_selected(self) -> bool:
        return self._redrawn(self.model.delete_selected())

    def set_name(self, name: str) -> None:
        """Choose the visitor's own targets file by their name (Voilà without a hub)."""
        check_type(name, str, "name", "TargetLabeler.set_name", "a str")
        self.model.path = targets_path(self.pair_name, Path.cwd(), user=name, also=()) if name.strip() else None
        self._show_path()

    def _show_path(self) -> None:
        self.path_label.value = ("type your name to choose your targets file" if self.model.path is None
                                 else f"your targets file: <code>{html.escape(str(self.model.path))}</code>")

    def save(self, path=None) -> Path:
        """Save (raising on failure, after saying so in the status line)."""
        try:
            if path is None and self.model.path is None and self.name_box is not None:
                raise ParameterError("The 'name' parameter of TargetLabeler.save must be typed in the "
                                     "'Your name' box first: this page serves every visitor, and your "
                                     "labels are saved under your name. Got '' instead.")
            return self.model.save(path)
        except Exception as exc:
            self.model.message = (f"save failed, the file on disk is unchanged and your "
                                  f"{len(self.model.pairs)} pairs are kept: {exc}")
            raise
        finally:
            self.refresh()

    def load(self, path=None) -> int:
        """Load (raising on failure, after saying so; the current labels stay)."""
        try:
            return self.model.load(path)
        except Exception as exc:
            self.model.message = f"load failed, your {len(self.model.pairs)} pairs are kept: {exc}"
            raise
        finally:
            self.refresh()

    def score_saved(self, method=DEFAULT_METHOD, *, seed: int = 0, params=None, path=None) -> SavedScore | None:
        """:meth:`LabelModel.score_saved`: `method`'s matches against the saved labels.

        Parameters
        ----------
        method : str, default ``DEFAULT_METHOD``
            The matching method.
        seed : int, default 0
            Update-order seed.
        params : Params, optional
            Default the method's.
        path : str or os.PathLike, optional
            The targets file; default the labeller's.

        Returns
        -------
        result : SavedScore or None
            The score and its errors; None when nothing is saved there.
        """
        return self.model.score_saved(method, seed=seed, params=params, path=path)

    @staticmethod
    def _quietly(action):
        try:
            action()
        except (OSError, ValueError, TypeError):
            pass  # already in the status line

    def _on_press(self, event):
        if event.inaxes is not self.ax or event.xdata is None or event.button not in (1, None):
            return
        toolbar = getattr(event.canvas, "toolbar", None)
        if toolbar is not None and getattr(toolbar, "mode", ""):
            return  # zooming or panning, not labelling
        self.click(event.xdata, event.ydata)

    def refresh(self) -> None:
        """Update the figure, table, flags and status from the model, then draw."""
        locked = self.model.answer_key is None or not self.model.key_open
        if locked and self.key_toggle.value:
            with self.syncing():
                self.key_toggle.value = False
        self.key_toggle.disabled = locked
        comparison = update_labels(self.artists, self.model, self.key_toggle.value)
        self.key_summary.value = "" if comparison is None else f"Answer key: {html.escape(str(comparison))}"
        self.table.value = pairs_html(self.model)
        # "saved" only once something was: a fresh labeller has nothing on disk to speak of
        self.dirty_label.value = {"unsaved": "* unsaved changes", "saved": "saved", "": ""}[self.model.save_status]
        self.delete_button.disabled = self.model.selected is None
        self.undo_button.disabled = not self.model._history
        self.say(self.model.message)
        self.pane.draw()

    def static_figure(self):
        """A plain matplotlib Figure of the pair and its labels (for print)."""
        fig = Figure(figsize=(9.0, 3.6))
        update_labels(draw_labels(fig.add_axes((0, 0, 1, 1)), self.model), self.model, self.key_toggle.value)
        return fig
