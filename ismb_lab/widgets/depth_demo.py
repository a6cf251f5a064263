"""Which toy car is nearer: the thesis' depth demonstration as a widget (§5.2.3, Figs. 5.11-5.14)."""

from __future__ import annotations

import html
import math
from dataclasses import fields, replace

import ipywidgets
import numpy as np
from matplotlib.figure import Figure

from .._core.validation import check_number
from ..depth.objects import DepthConfig, DepthObject, DepthResult
from ..depth.pipeline import DEPTH_MATCH_CONFIG, DEPTH_SOLVER, depth_pairs, load_stereo, pair_silhouettes, relative_depth
from ..network.methods import DEFAULT_METHOD, get_method, method_names
from ..network.params import Params
from ..plotting import OKABE_ITO, outlines
from ..matching.recipe import recipe_of
from ._common import (Base, Pane, button, check_params, check_type, grey_rgb, menu, pair_files, path_labels,
                      row, seed_field, with_class)
from .cloud import PointCloudView, depth_cloud

__all__ = ["CMAP", "GROUPING_LABELS", "TOLERANCES", "depth_text", "support_text", "DepthDemo",
           "DepthModel", "disparity_limits", "draw_background", "draw_scene", "label_positions",
           "update_background", "update_scene"]

#: The DepthConfig fields that get a slider, with their labels.
TOLERANCES = {"position_tol_px": "same place (px)", "disparity_tol_px": "same disparity (px)",
              "local_px": "local background (px)"}
CMAP = "plasma"
#: The choices of "objects by".
GROUPING_LABELS = (("outlines and features", "silhouettes"), ("features only (thesis)", "features"))


class DepthModel:
    """A background pair and a scene pair (:func:`ismb_lab.depth.pipeline.load_stereo`), matched
    with :func:`~ismb_lab.depth.pipeline.relative_depth` and ranked near -> far.

    `background_name` is what the ranking sentence calls the background's nearest object; a
    `recipe` (or its path) replaces `method`, `params` and :data:`~ismb_lab.depth.pipeline.DEPTH_SOLVER`.

    >>> from ismb_lab.scenes import lab_scene, toy_car_scene
    >>> model = DepthModel(lab_scene(0), toy_car_scene(0))
    >>> model.result.objects == () or model.ranking()[0].startswith("1. object at (")
    True
    >>> model.set(seed=3).seed, model.set(position_tol_px=4).config.position_tol_px
    (3, 4.0)
    """

    def __init__(self, background, scene, method=DEFAULT_METHOD, params: Params | None = None, seed: int = 0,
                 config: DepthConfig | None = None, match_config=None,
                 background_name: str = "the nearest background object", recipe=None):
        owner = "DepthModel"
        self.solver, self.one_to_one = DEPTH_SOLVER, False
        if recipe is not None:
            recipe = recipe_of(recipe, owner, DEPTH_SOLVER)
            method, params, self.solver, self.one_to_one = (recipe.method, recipe.params, recipe.solver,
                                                            recipe.one_to_one)
        self.background = load_stereo(background, "background", owner)
        self.scene = load_stereo(scene, "scene", owner)
        self.match_config = match_config
        self.background_name = check_type(background_name, str, "background_name", owner, "a str")
        self.method = get_method(method).name
        self.params = check_params(params, owner)
        self.config = self._check_config(DepthConfig() if config is None else config, owner)
        self.seed = check_number(seed, "seed", owner, low=0, integer=True)
        # corners, M and the blobs of change do not depend on the controls: found once, reused
        self.prepared = depth_pairs(self.background, self.scene, match_config)
        self.silhouettes, self._outline = None, None
        self.result: DepthResult = self._compute(self.method, self.params, self.seed, self.config)

    @staticmethod
    def _check_config(config, owner):
        return check_type(config, DepthConfig, "config", owner, "None or a DepthConfig")

    def _blobs(self, config):
        """The blobs of change for `config` (None for features alone), found again on new outline settings."""
        if config.grouping != "silhouettes":
            return None
        if self.silhouettes is None or self._outline != config.outline:
            self.silhouettes, self._outline = pair_silhouettes(self.prepared, config), config.outline
        return self.silhouettes

    def _compute(self, method, params, seed, config) -> DepthResult:
        return relative_depth(self.background, self.scene, method=method, params=params,
                              match_config=self.match_config, config=config, seed=seed, prepared=self.prepared,
                              silhouettes=self._blobs(config), solver=self.solver,
                              one_to_one=self.one_to_one)

    def set(self, *, method=None, params: Params | None = None, seed=None, config=None,
            **tolerances) -> "DepthModel":
        """Change any of method, params, seed, config or single config fields; recompute.
        All or nothing: on an error the model is left as it was.

        Parameters
        ----------
        method : str, optional
            The matching method.
        params : Params, optional
            New parameters.
        seed : int, optional
            New update-order seed.
        config : DepthConfig, optional
            New tolerances.
        **tolerances
            Single DepthConfig fields, e.g. ``position_tol_px=4``.

        Returns
        -------
        model : DepthModel
            This model, recomputed.
        """
        owner = "DepthModel.set"
        new_method = self.method if method is None else get_method(method).name
        new_params = check_params(params, owner, self.params)
        new_seed = self.seed if seed is None else check_number(seed, "seed", owner, low=0, integer=True)
        new_config = self.config if config is None else self._check_config(config, owner)
        if tolerances:
            new_config = replace(new_config, **tolerances)
        result = self._compute(new_method, new_params, new_seed, new_config)
        self.method, self.params, self.seed, self.config = new_method, new_params, new_seed, new_config
        self.result = result
        return self

    @property
    def objects(self) -> tuple:
        return self.result.objects

    def ranking(self) -> list[str]:
        """One line per object, nearest first, with what it rests on, e.g. ``1. object at (98, 163):
        d = 33.9 px, Z = 0.88 m ± 0.01 (13 features, spread 0.0 px; outline 34 px)``."""
        return [f"{o.rank}. object at ({_xy(o)}): d = {o.mean_disparity:.1f} px, "
                f"{depth_text(o)} ({support_text(o)})" for o in self.result.objects]

    def sentence(self) -> str:
        """The thesis' conclusion: which object is nearer, and what they are in front of."""
        objects = self.result.objects
        if not objects:
            return self.result.message or "No objects were found in the scene."
        if len(objects) == 1:
            text = f"One object was found, at ({_xy(objects[0])}), {depth_text(objects[0])}"
        elif len(objects) == 2:
            near, far = objects
            side = "left" if near.centroid_xy[0] < far.centroid_xy[0] else "right"
            other = "right" if side == "left" else "left"
            text = (f"The {side} object is nearer to the cameras than the {other} one: it has "
                    f"the larger disparity ({near.mean_disparity:.1f} px > {far.mean_disparity:.1f} px)")
        else:
            text = (f"The object at ({_xy(objects[0])}) is the nearest ({objects[0].mean_disparity:.1f} px) "
                    f"and the one at ({_xy(objects[-1])}) the farthest ({objects[-1].mean_disparity:.1f} px)")
        return text + self._in_front() + "."

    def _in_front(self) -> str:
        if not self.result.background_objects:
            return ""
        ref = self.result.background_objects[0]  # nearest first: the largest background disparity
        what = (f"{self.background_name} (d = {ref.mean_disparity:.1f} px"
                + (f", Z = {ref.depth_m:.2f} m)" if ref.depth_m is not None else ")"))
        objects = self.result.objects
        ahead = [o.rank for o in objects if o.mean_disparity > ref.mean_disparity]
        if len(ahead) == len(objects):
            who = {1: "it is", 2: "both are"}.get(len(objects), f"all {len(objects)} are")
            return f"; {who} in front of {what}"
        if not ahead:
            return f"; {'it is' if len(objects) == 1 else 'none is'} in front of {what}"
        ranks = [str(r) for r in ahead]
        names = ranks[0] if len(ranks) == 1 else ", ".join(ranks[:-1]) + " and " + ranks[-1]
        verb = "objects {} are" if len(ranks) > 1 else "object {} is"
        return f"; only {verb.format(names)} in front of {what}"

    def ranking_html(self) -> str:
        lines = "<br>".join(html.escape(line, quote=False) for line in self.ranking())
        return (f"<div>{lines or 'no objects'}</div>"
                f"<p>{html.escape(self.sentence(), quote=False)}</p>")

    def describe(self) -> str:
        r = self.result
        text = (f"Method-{self.method}, seed {self.seed}: {len(r.background.pairs)} background and "
                f"{len(r.scene.pairs)} scene matches; {r.background_removed} scene features removed as "
                f"background, {r.behind_background} matches behind it, {r.dropped} features dropped; "
                f"{len(r.objects)} object{'s' if len(r.objects) != 1 else ''}")
        return text + (f"; {r.message}" if r.message else "")


def _xy(obj: DepthObject) -> str:
    return f"{obj.centroid_xy[0]:.0f}, {obj.centroid_xy[1]:.0f}"


def depth_text(obj: DepthObject) -> str:
    """``Z = 0.88 m ± 0.01`` (half the quantisation range), or why there is no depth."""
    d = obj.depth
    if d.z is None:
        return f"Z {d.status}"
    if math.isinf(d.far):
        return f"Z = {d.z:.2f} m (at least {d.near:.2f} m, no far bound)"
    return f"Z = {d.z:.2f} m ± {(d.far - d.near) / 2:.2f}"


def support_text(obj: DepthObject) -> str:
    """What an object rests on: ``13 features, spread 0.0 px; outline 34 px``, or its outline only.

    >>> from ismb_lab.depth.objects import DepthObject, metric_depth
    >>> support_text(DepthObject(1, (0.0, 0.0), 22.0, 0.0, metric_depth(22.0), np.zeros((0, 2)), 0,
    ...                          silhouette_disparity=22.0, silhouette_score=0.98))
    'outline only: 22 px, overlap 0.98'
    """
    if obj.n_features == 0 and obj.silhouette_disparity is not None:
        return f"outline only: {obj.silhouette_disparity:.0f} px, overlap {obj.silhouette_score:.2f}"
    text = f"{obj.n_features} feature{'s' if obj.n_features != 1 else ''}, spread {obj.disparity_spread:.1f} px"
    if obj.silhouette_disparity is not None:
        text += f"; outline {obj.silhouette_disparity:.0f} px"
    return text


def disparity_limits(model: DepthModel) -> tuple[float, float]:
    """One colour scale for both views: the background's and the kept scene disparities."""
    d = np.concatenate([model.result.background.horizontal_disparity, model.result.kept_disparity])
    if not len(d):
        return 0.0, 1.0
    return min(0.0, math.floor(d.min())), max(1.0, math.ceil(d.max()))


def draw_background(ax, model: DepthModel) -> dict:
    """Fig. 5.12: the background's left image, its matched features and their disparities."""
    ax.imshow(grey_rgb(model.background.left), interpolation="nearest")
    features = ax.scatter([], [], c=[], cmap=CMAP, s=22, edgecolors="white", linewidths=0.5)
    ax.set_axis_off()
    return {"ax": ax, "features": features, "numbers": None}


def update_background(art: dict, model: DepthModel) -> None:
    bg = model.result.background
    xy, d = np.asarray(bg.left_match_xy).reshape(-1, 2), np.asarray(bg.horizontal_disparity)
    art["features"].set_offsets(xy)
    art["features"].set_array(d)
    art["features"].set_clim(*disparity_limits(model))
    if art["numbers"] is not None:
        art["numbers"].remove()
    art["numbers"] = path_labels(art["ax"], xy, [f"{v:.0f}" for v in d], OKABE_ITO["sky blue"], size=6.5,
                                  declutter=True)


def draw_scene(ax, cax, model: DepthModel) -> dict:
    """Fig. 5.14: the scene's left image, background features crossed out, new ones by disparity,
    the box where corners were sought and the blobs of change (as :func:`ismb_lab.plotting.plot_depth`)."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Rectangle

    ax.imshow(grey_rgb(model.scene.left), interpolation="nearest")
    drawn = ax.add_collection(LineCollection([], colors=OKABE_ITO["sky blue"], linewidths=0.8, visible=False))
    removed, = ax.plot([], [], "x", color="0.75", alpha=0.7, ms=4, mew=1)
    features = ax.scatter([], [], c=[], cmap=CMAP, s=30, edgecolors="white", linewidths=0.6)
    box = ax.add_patch(Rectangle((0, 0), 0, 0, fill=False, ec=OKABE_ITO["yellow"], lw=0.8, ls="--", visible=False))
    ax.set_axis_off()
    bar = ax.figure.colorbar(features, cax=cax) if cax is not None else ax.figure.colorbar(features, ax=ax)
    bar.set_label("disparity (px)", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    return {"ax": ax, "removed": removed, "features": features, "box": box, "outlines": drawn, "labels": None}


def update_scene(art: dict, model: DepthModel) -> None:
    r = model.result
    art["removed"].set_data(*np.asarray(r.removed_xy).reshape(-1, 2).T)
    art["features"].set_offsets(np.asarray(r.kept_xy).reshape(-1, 2))
    art["features"].set_array(np.asarray(r.kept_disparity))
    art["features"].set_clim(*disparity_limits(model))
    if r.scene_roi is not None:
        x, y, w, h = r.scene_roi
        art["box"].set_bounds(x - 0.5, y - 0.5, w, h)
    art["box"].set_visible(r.scene_roi is not None)
    if r.silhouettes is not None and r.silhouettes is not art.get("outlined"):
        art["outlines"].set_segments(outlines(r.silhouettes.labels))
        art["outlined"] = r.silhouettes
    art["outlines"].set_visible(r.silhouettes is not None)
    if art["labels"] is not None:
        art["labels"].remove()
    strings = [f"#{o.rank} " + (f"{o.depth_m:.2f} m" if o.depth_m is not None else o.depth.status)
               for o in r.objects]
    art["labels"] = path_labels(art["ax"], label_positions(r.objects), strings, OKABE_ITO["yellow"],
                                size=8, shift=(0, 6), ha="center")


def label_positions(objects, width: float = 45.0, height: float = 12.0) -> np.ndarray:
    """Where each object's label goes: above its topmost feature (or centroid), moved up above
    the labels of nearer objects it would cover.

    >>> from types import SimpleNamespace as O
    >>> label_positions([O(centroid_xy=(100, 150), features=np.array([[95, 140], [105, 160]])),
    ...                  O(centroid_xy=(120, 145), features=np.zeros((0, 2)))]).tolist()
    [[100.0, 140.0], [120.0, 128.0]]
    """
    xy = np.array([(o.centroid_xy[0], min([o.centroid_xy[1], *np.asarray(o.features, float).reshape(-1, 2)[:, 1]]))
                   for o in objects], dtype=float).reshape(-1, 2)
    for n in range(1, len(xy)):
        for m in range(n):
            if abs(xy[n, 0] - xy[m, 0]) < width and abs(xy[n, 1] - xy[m, 1]) < height:
                xy[n, 1] = xy[m, 1] - height  # image rows grow downwards: minus is up
    return xy


class DepthDemo(Base):
    """Rank the objects added to a background near -> far, with both figures of the thesis;
    the parameters are :class:`DepthModel`'s.

    Parameters
    ----------
    background, scene : pair folder, (left, right) or object with ``.left`` and ``.right``
        The two stereo pairs of the same view.
    method : str, default ``DEFAULT_METHOD``
        The matching method.
    params : Params, optional
        Default the method's (Method-III: the demo's).
    seed : int, default 0
        Update-order seed of both runs.
    config : DepthConfig, optional
        Tolerances and calibration.
    match_config : MatchConfig, optional
        Corner and window settings.
    background_name : str, default "the nearest background object"
        How the ranking sentence calls the background's nearest object.
    recipe : Recipe or path, optional
        Replaces `method`, `params` and the solver.

    Notes
    -----
    CSS classes: root ``ismb-depth``; ranking ``ismb-ranking``; ``ismb-seed``; ``ismb-method``;
    sliders ``ismb-position-tol-px``, ``ismb-disparity-tol-px``, ``ismb-local-px``; button
    ``ismb-recompute``; figures ``ismb-background`` (Fig. 5.12) and ``ismb-scene`` (Fig. 5.14);
    the matches in 3-D ``ismb-cloud`` (:class:`~ismb_lab.widgets.cloud.PointCloudView`);
    ``ismb-status``; ``ismb-log``.
    """

    def __init__(self, background, scene, *, method=DEFAULT_METHOD, params: Params | None = None, seed: int = 0,
                 config: DepthConfig | None = None, match_config=None,
                 background_name: str = "the nearest background object", recipe=None):
        super().__init__()
        self.model = DepthModel(background, scene, method, params, seed, config, match_config,
                                background_name, recipe)
        self.background_pane = Pane((3.6, 2.7), "ismb-background")
        self.scene_pane = Pane((4.2, 2.7), "ismb-scene")
        self.panes = (self.background_pane, self.scene_pane)
        self.background_artists = draw_background(self.background_pane.fig.add_axes((0, 0, 1, 1)), self.model)
        fig = self.scene_pane.fig
        self.scene_artists = draw_scene(fig.add_axes((0, 0, 0.857, 1)), fig.add_axes((0.87, 0.08, 0.03, 0.84)),
                                        self.model)
        self.cloud = PointCloudView(depth_cloud(self.model))

        self.method_menu = menu("method", method_names(), self.model.method, layout={"width": "160px"})
        self.seed_field = seed_field(self.model.seed, layout={"width": "160px"})
        self.grouping_menu = with_class(ipywidgets.Dropdown(options=GROUPING_LABELS, value=self.model.config.grouping,
                                                            description="objects by", layout={"width": "240px"}),
                                        "ismb-grouping")
        self.recompute_button = button("Recompute", "ismb-recompute", "Match both pairs again", icon="refresh")
        self.sliders = {}
        defaults = {f.name: f.default for f in fields(DepthConfig) if f.name in TOLERANCES}
        for name, label in TOLERANCES.items():
            value = getattr(self.model.config, name)
            s = ipywidgets.FloatSlider(value=value, min=min(0.5, value) if name == "local_px" else 0.0,
                                       max=max(4 * defaults[name], value), step=0.5, description=label,
                                       continuous_update=False, readout_format=".1f",
                                       style={"description_width": "150px"}, layout={"width": "380px"})
            self.sliders[name] = with_class(s, "ismb-" + name.replace("_", "-"))
        self.ranking = with_class(ipywidgets.HTML(""), "ismb-ranking")
        for control in (*self.sliders.values(), self.method_menu, self.seed_field, self.grouping_menu):
            control.observe(self.guard(lambda _: self.recompute()), names="value")
        self.recompute_button.on_click(self.guard(lambda _: self.recompute()))
        menus = [self.method_menu, self.seed_field, self.grouping_menu, self.recompute_button]
        controls = row([ipywidgets.VBox(menus), ipywidgets.VBox(list(self.sliders.values()))])
        views = row([self.background_pane.widget, self.scene_pane.widget])
        self.widget = with_class(ipywidgets.VBox([controls, self.status, self.ranking, views, self.cloud.widget,
                                                  self.log]), "ismb-depth")
        self.refresh()

    @classmethod
    def from_folders(cls, background_folder, scene_folder, **kw) -> "DepthDemo":
        """The demo on two pair folders, e.g. ``images/lab`` and ``images/toy_cars``.

        Parameters
        ----------
        background_folder, scene_folder : str or Path
            Pair folders holding ``left.png`` and ``right.png``.
        **kw
            The constructor's keyword parameters.

        Returns
        -------
        demo : DepthDemo
            The widget.
        """
        pairs = [pair_files(f, "DepthDemo.from_folders")[:2] for f in (background_folder, scene_folder)]
        return cls(*pairs, **kw)

    @classmethod
    def from_photos(cls, *, folder=".", **kw):
        """The §5.2.3 demo on photos of one's own from two fixed cameras: a
        :class:`~ismb_lab.widgets.photos.PhotoLoader` for the empty scene, whose "Use this pair"
        opens a second for the scene (warped with the background's rectification), whose own
        opens the demo on both saved pairs.

        Parameters
        ----------
        folder : str or os.PathLike, default "."
            Where the pairs' folders are made.
        **kw
            The constructor's keyword parameters.

        Returns
        -------
        loader : PhotoLoader
            The first loader widget.
        """
        from .photos import PhotoLoader

        def scene_loader(background_folder, roi):
            rectified = first.model.rectified
            shape = first.model.current()[0].shape
            homographies = (None if rectified is None else
                            (rectified.left_h, rectified.right_h, (shape[1], shape[0])))

            def open_demo(scene_folder, _roi):
                config = replace(DEPTH_MATCH_CONFIG, roi=roi if roi is not None else "center", shift="auto")
                return cls.from_folders(background_folder, scene_folder, match_config=config, **kw)

            return PhotoLoader(open_demo, folder=folder, role="scene", homographies=homographies,
                               title="2. The same view with the objects added")

        first = PhotoLoader(scene_loader, folder=folder, role="background",
                            title="1. The empty scene (the background)")
        return first

    def recompute(self) -> None:
        """Match both pairs again with the controls' settings and redraw; on failure the model and
        the controls keep their last good state."""
        try:
            self.model.set(method=self.method_menu.value, seed=self.seed_field.value,
                           grouping=self.grouping_menu.value, **{name: s.value for name, s in self.sliders.items()})
        except Exception:
            with self.syncing():
                self.method_menu.value = self.model.method
                self.seed_field.value = self.model.seed
                self.grouping_menu.value = self.model.config.grouping
                for name, s in self.sliders.items():
                    s.value = getattr(self.model.config, name)
            raise
        self.refresh()

    def refresh(self) -> None:
        """Update the three views, the ranking and the status from the model, and draw."""
        update_background(self.background_artists, self.model)
        update_scene(self.scene_artists, self.model)
        self.cloud.update(depth_cloud(self.model))
        self.ranking.value = self.model.ranking_html()
        self.say(self.model.describe())
        self.background_pane.draw()
        self.scene_pane.draw()

    @property
    def objects(self):
        """The ranked objects of the current result (``self.model.objects``)."""
        return self.model.objects

    def static_figure(self):
        """A plain Figure: Fig. 5.12 and Fig. 5.14 side by side under the ranking sentence (for print)."""
        fig = Figure(figsize=(9.0, 3.6), layout="constrained")
        bg_ax, scene_ax = fig.subplots(1, 2)
        update_background(draw_background(bg_ax, self.model), self.model)
        update_scene(draw_scene(scene_ax, None, self.model), self.model)
        bg_ax.set_title("background: matches and disparities", fontsize=8)
        scene_ax.set_title("scene: new features by disparity", fontsize=8)
        fig.suptitle(self.model.sentence(), fontsize=8, wrap=True)
        return fig
