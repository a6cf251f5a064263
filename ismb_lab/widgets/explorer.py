"""Explore the energy parameters: move a slider, the pair is matched again and scored, and the
transfer functions S and C (thesis Fig. 3.3) follow."""

from __future__ import annotations

import html
from dataclasses import replace

import ipywidgets
import numpy as np
from matplotlib.figure import Figure

from .._core.validation import check_number
from ..tuning.evaluation import Score, score, unlabelled
from ..matching.pipeline import MatchConfig, MatchResult, Prepared, match, prepare
from ..network.methods import DEFAULT_METHOD, all_genes, get_method, method_names
from ..plotting import OKABE_ITO
from ..network.params import THETA_C, Params
from ..network.similarity import transfer
from ..network.solvers import DEFAULT_SOLVER, SOLVERS, get_solver
from ..labels.targets import TargetSet, load_targets, snap
from ._common import (Base, Pane, check_params, check_type, draw_pair, menu, pair_figsize, pair_files, row,
                      seed_field, update_pair, with_class)
from .photos import FromPhotos

__all__ = ["draw_transfer", "ExplorerModel", "ParameterExplorer", "similarity_theta", "update_transfer"]


class ExplorerModel:
    """Match one pair with given parameters and score it against target feature pairs.

    `targets` are ``(i, k)`` feature pairs (:func:`ismb_lab.labels.targets.snap`); matches of
    the `unknown` left features are not scored.

    >>> from ismb_lab.scenes import synthetic_scene
    >>> scene = synthetic_scene(0)
    >>> model = ExplorerModel(prepare(scene.left, scene.right), targets=[[0, 0]])
    >>> model.set(theta_c=5.0).params.theta_c, type(model.score).__name__
    (5.0, 'Score')
    """

    def __init__(self, prepared: Prepared, method=DEFAULT_METHOD, params: Params | None = None, seed: int = 0,
                 targets=None, solver: str = DEFAULT_SOLVER, unknown=()):
        owner = "ExplorerModel"
        self.solver = get_solver(solver, owner).name
        self.prepared = check_type(prepared, Prepared, "prepared", owner, "a Prepared (see matching.prepare)")
        self.method = get_method(method).name
        self.params = check_params(params, owner, get_method(self.method).defaults)
        self.seed = check_number(seed, "seed", owner, low=0, integer=True)
        self.targets = None if targets is None else np.asarray(targets, dtype=np.intp).reshape(-1, 2)
        self.unknown = np.asarray(unknown, dtype=np.intp).ravel()
        self.result: MatchResult | None = None
        self.score: Score | None = None
        self.rematch()

    def set(self, *, method=None, params: Params | None = None, seed=None, solver=None,
            **genes) -> "ExplorerModel":
        """Change any of method, params (whole or gene by gene, e.g. ``theta_c=12``), seed and
        solver; rematch.

        Parameters
        ----------
        method : str, optional
            The matching method.
        params : Params, optional
            New parameters.
        seed : int, optional
            New update-order seed.
        solver : str, optional
            New solver.
        **genes
            Single parameters, e.g. ``theta_c=12``.

        Returns
        -------
        model : ExplorerModel
            This model, rematched.
        """
        owner = "ExplorerModel.set"
        before = (self.method, self.params, self.seed, self.solver)
        try:
            if solver is not None:
                self.solver = get_solver(solver, owner).name
            if method is not None:
                self.method = get_method(method).name
            if params is not None:
                self.params = check_type(params, Params, "params", owner, "a Params")
            if genes:
                self.params = replace(self.params, **genes)
            if seed is not None:
                self.seed = check_number(seed, "seed", owner, low=0, integer=True)
            m = get_method(self.method)
            unset = {g: getattr(m.defaults, g) for g in m.gene_names if getattr(self.params, g) is None}
            if unset:   # e.g. Method-NM's match bias after a four-gene method
                self.params = replace(self.params, **unset)
            return self.rematch()
        except Exception:
            # e.g. the exact solver on a problem too large for it: keep the last working state
            self.method, self.params, self.seed, self.solver = before
            raise

    def rematch(self) -> "ExplorerModel":
        self.result = match(prepared=self.prepared, method=self.method, params=self.params, seed=self.seed,
                            solver=self.solver)
        self.score = None if self.targets is None else score(self.result.pairs, self.targets, self.unknown)
        return self

    @property
    def pairs(self) -> np.ndarray:
        return self.result.pairs

    def describe(self) -> str:
        r = self.result
        text = f"Method-{self.method} ({self.solver}), seed {self.seed}: {len(r.pairs)} matches, E = {r.energy:.3f}"
        return text + (f"; {r.message}" if r.message else "")

    def score_text(self) -> str:
        s = self.score
        if s is None:
            return "no targets loaded: C/E/T needs target pairs"
        pct = lambda v: "-" if np.isnan(v) else f"{100 * v:.1f}%"  # noqa: E731
        return (f"C/E/T = {s} (correct / wrong partner + extra / targets): "
                f"C/T {pct(s.recall)}, precision {pct(s.precision)}, fitness {s.fitness}")


def draw_transfer(axes, model: ExplorerModel) -> dict:
    """S(M) and C(X) (thesis 3-10, 3-13; Fig. 3.3) with a marker at the current θ."""
    x = np.linspace(0, THETA_C.high, 241)
    art = {"x": x}
    for ax, key, title, xlabel in ((axes[0], "s", "similarity S(M)", "M (grey levels)"),
                                   (axes[1], "c", "compatibility C(X)", "X (pixels)")):
        art[key], = ax.plot(x, np.zeros_like(x), "-", color=OKABE_ITO["blue"], lw=1.5)
        art[key + "_theta"] = ax.axvline(0, color=OKABE_ITO["vermillion"], ls="--", lw=1)
        art[key + "_dot"], = ax.plot([0], [0], "o", color=OKABE_ITO["vermillion"], ms=5)
        ax.axhline(0, color="grey", lw=0.6)
        ax.set_ylim(-1.08, 1.08)
        ax.set_xlim(x[0], x[-1])
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_yticks([-1, 0, 1])
        ax.set_xticks([0, 20, 40, 60])
        ax.tick_params(labelsize=7)
    return art


#: The λs that reads back a derived θs: far below tanh's saturation for any M, so no digit is lost.
_PROBE_LAMBDA = 1e-3


def similarity_theta(model: ExplorerModel) -> float | None:
    """The θs the model's method really uses on its pair, or None when it forms no ``S(M)``.

    A θs derived from each pair (as Method-NM3's) is read back from the method's own
    ``S = -tanh(λs (M - θs) / 2)`` at the neuron whose ``S`` is nearest 0.

    >>> from ismb_lab.scenes import synthetic_scene
    >>> pair = synthetic_scene(0)
    >>> model = ExplorerModel(prepare(pair.left, pair.right), "NM3")
    >>> bool(np.isclose(similarity_theta(model), model.prepared.problem.no_match_cut))
    True
    >>> similarity_theta(model.set(method="III")) == model.params.theta_s
    True
    >>> similarity_theta(model.set(method="I")) is None
    True
    """
    method, params = get_method(model.method), model.params
    if "theta_s" in method.derived:
        problem = model.prepared.problem
        if problem.n_neurons == 0:
            return None
        s = method.similarity(problem, replace(params, lambda_s=_PROBE_LAMBDA))
        n = int(np.argmin(np.abs(s)))
        return float(problem.neuron_dissimilarity[n] + 2 * np.arctanh(s[n]) / _PROBE_LAMBDA)
    return params.theta_s if "theta_s" in method.gene_names else None


def update_transfer(art: dict, model: ExplorerModel) -> None:
    p = model.params
    theta_s = similarity_theta(model)
    for key, theta, lam in (("s", p.theta_s if theta_s is None else theta_s, p.lambda_s),
                            ("c", p.theta_c, p.lambda_c)):
        art[key].set_ydata(transfer(art["x"], theta, lam))
        art[key + "_theta"].set_xdata([theta, theta])
        art[key + "_dot"].set_data([theta], [0.0])
        art[key].set_alpha(0.25 if key == "s" and theta_s is None else 1.0)


class ParameterExplorer(FromPhotos, Base):
    """Sliders for the four energy parameters with live matches, score and transfer functions.

    `left` and `right` are paths or images, or `left` a Prepared; C/E/T is scored against `targets`
    (a TargetSet, its path or feature pairs), only on their left corners when `partial`.

    Parameters
    ----------
    left, right : path or ndarray, or a Prepared as `left`
        The image pair.
    method : str, default ``DEFAULT_METHOD``
        The matching method.
    params : Params, optional
        Starting slider values; default the method's.
    seed : int, default 0
        Update-order seed.
    config : MatchConfig, optional
        Corner settings.
    targets : TargetSet, path or (t, 2) int array_like, optional
        What C/E/T is scored against.
    solver : str, default ``DEFAULT_SOLVER``
        How the network is solved.
    partial : bool, default False
        The targets label only some corners: matches of the others are not scored.

    Notes
    -----
    CSS classes: root ``ismb-explorer``; sliders ``ismb-theta-c``, ``ismb-theta-s``,
    ``ismb-lambda-c``, ``ismb-lambda-s``; ``ismb-method``; ``ismb-solver``; ``ismb-seed``; ``ismb-score``;
    figures ``ismb-matches`` and ``ismb-transfer``; ``ismb-status``; ``ismb-log``.
    """

    def __init__(self, left, right=None, *, method=DEFAULT_METHOD, params: Params | None = None, seed: int = 0,
                 config: MatchConfig | None = None, targets=None, solver: str = DEFAULT_SOLVER,
                 partial: bool = False):
        super().__init__()
        prepared = left if isinstance(left, Prepared) else prepare(left, right, config)
        if targets is not None and not isinstance(targets, (np.ndarray, list)):
            if not isinstance(targets, TargetSet):
                targets = load_targets(targets, pair=prepared.pair)
            targets = snap(targets, prepared.problem.left_xy, prepared.problem.right_xy).pairs
        check_type(partial, bool, "partial", "ParameterExplorer", "True or False")
        unknown = unlabelled(targets, len(prepared.problem.left_xy)) if partial and targets is not None else ()
        self.model = ExplorerModel(prepared, method, params, seed, targets, solver, unknown)
        self.pair_pane = Pane(pair_figsize(prepared.pair), "ismb-matches")
        self.transfer_pane = Pane((5.8, 2.2), "ismb-transfer")
        self.panes = (self.pair_pane, self.transfer_pane)
        self.pair_artists = draw_pair(self.pair_pane.fig.add_axes((0, 0, 1, 1)), self.model)
        self.transfer_pane.fig.subplots_adjust(left=0.08, right=0.98, bottom=0.2, top=0.88, wspace=0.25)
        self.transfer_artists = draw_transfer(self.transfer_pane.fig.subplots(1, 2), self.model)

        self.sliders = {}
        # a gene the current parameters leave unset shows the value of a method that uses it
        fallback = {g: getattr(get_method(m).defaults, g) for m in reversed(method_names())
                    for g in get_method(m).gene_names}
        for gene in all_genes():
            value = getattr(self.model.params, gene.name)
            s = ipywidgets.FloatSlider(value=fallback[gene.name] if value is None else value, min=gene.low,
                                       max=gene.high, step=0.01, description=gene.symbol or gene.name,
                                       continuous_update=False, readout_format=".2f")
            s.observe(self.guard(self._on_slider), names="value")
            self.sliders[gene.name] = with_class(s, "ismb-" + gene.name.replace("_", "-"))
        self.method_menu = menu("method", method_names(), self.model.method)
        self.seed_field = seed_field(self.model.seed)
        self.solver_menu = menu("solver", SOLVERS, self.model.solver)
        self.score_label = with_class(ipywidgets.HTML(""), "ismb-score")
        self.solver_menu.observe(self.guard(lambda c: self._change(solver=c["new"])), names="value")
        self.method_menu.observe(self.guard(lambda c: self._change(method=c["new"])), names="value")
        self.seed_field.observe(self.guard(lambda c: self._change(seed=c["new"])), names="value")
        controls = row([ipywidgets.VBox(list(self.sliders.values())),
                        ipywidgets.VBox([self.method_menu, self.solver_menu, self.seed_field])])
        self.widget = with_class(ipywidgets.VBox([controls, self.score_label, self.status,
                                                  self.pair_pane.widget, self.transfer_pane.widget,
                                                  self.log]), "ismb-explorer")
        self.refresh()

    @classmethod
    def from_folder(cls, folder, **kw) -> "ParameterExplorer":
        """Explore ``folder/left.png``, ``folder/right.png``, scored against ``answer_key.json`` if present.

        Parameters
        ----------
        folder : str or Path
            A pair folder.
        **kw
            The constructor's keyword parameters.

        Returns
        -------
        explorer : ParameterExplorer
            The widget.
        """
        left, right, key = pair_files(folder, "ParameterExplorer.from_folder")
        if key.is_file():
            kw.setdefault("targets", key)
        return cls(left, right, **kw)

    @property
    def params(self) -> Params:
        return self.model.params

    def set_params(self, params: Params) -> None:
        """Show and use `params` (e.g. the GA's best): one rematch, whatever changed."""
        check_type(params, Params, "params", "ParameterExplorer.set_params", "a Params")
        with self.syncing():
            for gene, slider in self.sliders.items():
                if getattr(params, gene) is not None:
                    slider.value = min(max(getattr(params, gene), slider.min), slider.max)
        self._change(params=params)

    def _on_slider(self, change) -> None:
        gene = next(g for g, s in self.sliders.items() if s is change["owner"])
        self._change(**{gene: float(change["new"])})

    def _change(self, **what) -> None:
        try:
            self.model.set(**what)
        finally:    # a refused change leaves the controls showing the state still in use
            with self.syncing():
                self.method_menu.value = self.model.method
                self.solver_menu.value = self.model.solver
                self.seed_field.value = self.model.seed
        self.refresh()

    def refresh(self) -> None:
        update_pair(self.pair_artists, self.model)
        update_transfer(self.transfer_artists, self.model)
        used = get_method(self.model.method).gene_names
        for gene, slider in self.sliders.items():
            slider.disabled = gene not in used
        self.score_label.value = html.escape(self.model.score_text(), quote=False)
        self.say(self.model.describe())
        self.pair_pane.draw()
        self.transfer_pane.draw()

    def static_figure(self):
        """A plain Figure: the matches and the transfer functions (for print)."""
        fig = Figure(figsize=(6.6, 5.0), layout="constrained")
        top, bottom = fig.subfigures(2, 1, height_ratios=[1.2, 1])
        update_pair(draw_pair(top.add_subplot(), self.model), self.model)
        top.suptitle(self.model.score_text(), fontsize=8)
        update_transfer(draw_transfer(bottom.subplots(1, 2), self.model), self.model)
        return fig
