"""Step the Hopfield network one update attempt at a time (thesis §3.3, Fig. 5.6), through
:func:`ismb_lab.network.dynamics.iter_updates`, the generator the core runs."""

from __future__ import annotations

import ipywidgets
import numpy as np
from matplotlib.figure import Figure

from .._core.validation import check_choice, check_number
from ..network.hopfield import RULES, energy
from ..network.dynamics import STOP_RULES, Update, iter_updates
from ..matching.pipeline import MatchConfig, Prepared, prepare
from ..plotting import OKABE_ITO
from ..network.methods import DEFAULT_METHOD, get_method
from ..network.params import Params
from ..network.solvers import to_matches
from ._common import (Base, Pane, button, check_params, check_type, draw_pair, pair_figsize, pair_files,
                      path_labels, row, seed_field, update_pair, with_class)

__all__ = ["draw_energy", "draw_grid", "HopfieldStepper", "StepperModel", "update_energy", "update_grid"]


class StepperModel:
    """A network being run attempt by attempt.

    `seed` orders the visits as in :func:`ismb_lab.network.dynamics.run`; ``rule="thesis"`` is the
    literal (3-17)/(3-20) rule, whose energy can rise.

    >>> from ismb_lab.scenes import synthetic_scene
    >>> scene = synthetic_scene(0)
    >>> model = StepperModel(prepare(scene.left, scene.right))
    >>> [u.attempt for u in model.step(3)], len(model.energies)
    ([0, 1, 2], 4)
    >>> model.run() > 0, model.stop
    (True, 'sweep')
    """

    def __init__(self, prepared: Prepared, method=DEFAULT_METHOD, params: Params | None = None, seed: int = 0,
                 rule: str = "exact", stop_rule: str = "sweep"):
        owner = "StepperModel"
        self.prepared = check_type(prepared, Prepared, "prepared", owner, "a Prepared (see matching.prepare)")
        self.method = get_method(method)
        self.params = check_params(params, owner, self.method.defaults)
        self.stop_rule = check_choice(stop_rule, "stop_rule", owner, STOP_RULES)
        self.network = self.method.network(prepared.problem, self.params)
        self.reset(seed, rule)

    def reset(self, seed: int | None = None, rule: str | None = None) -> None:
        """Start again from every candidate on, optionally with another seed or rule."""
        owner = "StepperModel.reset"
        if seed is not None:
            self.seed = check_number(seed, "seed", owner, low=0, integer=True)
        if rule is not None:
            self.rule = check_choice(rule, "rule", owner, RULES)
        self._updates = iter_updates(self.network, rng=self.seed, rule=self.rule, stop_rule=self.stop_rule)
        self.state = self.network.initial_state().copy()
        self.energies = [energy(self.network, self.state)]
        self.last: Update | None = None
        self.stop: str | None = None if self.network.n_neurons else "empty"
        self.flips = 0

    @property
    def done(self) -> bool:
        return self.stop is not None

    @property
    def attempts(self) -> int:
        return len(self.energies) - 1

    def step(self, n: int = 1) -> list[Update]:
        """Make up to `n` update attempts (fewer if the network stops); return their records."""
        n = check_number(n, "n", "StepperModel.step", low=0, integer=True)
        out = []
        while len(out) < n and not self.done:
            update = next(self._updates, None)
            if update is None:  # the generator ended without a stop record
                self.stop = self.stop or "ended"
                break
            self.state[update.neuron] = update.new
            self.energies.append(update.energy)
            self.flips += update.changed
            self.last, self.stop = update, update.stop
            out.append(update)
        return out

    def run(self, limit: int = 50_000) -> int:
        """Step until the network stops or `limit` attempts were made; return the attempts made.

        Parameters
        ----------
        limit : int, default 50000
            Most attempts.

        Returns
        -------
        attempts : int
            The attempts made.
        """
        limit = check_number(limit, "limit", "StepperModel.run", low=1, integer=True)
        return len(self.step(limit))

    def grid(self) -> np.ndarray:
        """The ``N_l x N_r`` grid: -1 where no candidate neuron exists, else its output 0/1."""
        net = self.network
        g = np.full((net.n_left, net.n_right), -1, dtype=np.int8)
        g[net.rows, net.cols] = self.state
        return g

    @property
    def pairs(self) -> np.ndarray:
        """``(i, k)`` of the neurons that are on now (before any post-processing)."""
        return to_matches(self.network, self.state).pairs

    def rises(self) -> np.ndarray:
        """Attempt numbers (1-based, as plotted) after which the energy went up."""
        e = np.asarray(self.energies)
        return np.flatnonzero(np.diff(e) > 1e-9) + 1

    def describe(self) -> str:
        """The status line: the last attempt's neuron, its net input u and Δy, and the energy."""
        head = f"Method-{self.method.name}, {self.rule} rule, seed {self.seed}"
        if self.stop == "empty":
            return f"{head}: no candidate neurons (no right corner lies in any candidate window)"
        if self.last is None:
            return f"{head}: {self.network.n_neurons} candidate neurons on, E = {self.energies[0]:.3f}"
        u = self.last
        dy = u.new - u.old
        text = (f"{head}: attempt {u.attempt + 1}, neuron (i={u.i + 1}, k={u.k + 1}) "
                f"u = {u.u:+.3f}, Δy = {dy:+d} ({u.old}→{u.new}), E = {u.energy:.3f}, {self.flips} flips")
        if self.stop == "max_attempts":
            text += "; stopped at the attempt limit without settling"
        elif self.stop:
            text += f"; converged ({self.stop} rule)"
        return text


#: The cursor on the neuron just attempted: orange when it flipped, black when it kept its state.
CURSOR_COLOURS = {True: OKABE_ITO["orange"], False: OKABE_ITO["black"]}


def draw_grid(ax, model: StepperModel) -> dict:
    """The ``N_l x N_r`` neuron grid with a cursor on the neuron just attempted."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Rectangle
    from matplotlib.transforms import blended_transform_factory

    colours = ListedColormap(["#d9d9d9", "#ffffff", "#1f4e9c"])  # no neuron, off, on
    grid = ax.imshow(model.grid() + 1, cmap=colours, vmin=0, vmax=2, interpolation="nearest")
    ax.set_xlabel("right feature k", labelpad=12)
    ax.set_ylabel("left feature i", labelpad=16)
    ax.set_xticks([])
    ax.set_yticks([])
    # a key for the three states; the ticks sit at the middles of the colour map's three bins
    key = ax.figure.colorbar(grid, ax=ax, ticks=[1 / 3, 1, 5 / 3], fraction=0.06, pad=0.03, shrink=0.75)
    key.set_ticklabels(["no neuron", "off", "on"])
    key.ax.tick_params(labelsize=8)
    # feature numbers (from 1, as in the thesis' tables) as cheap path labels, not tick texts
    n_left, n_right = model.network.n_left, model.network.n_right
    cols = [k for k in range(n_right) if k == 0 or (k + 1) % 5 == 0]
    rows = [i for i in range(n_left) if i == 0 or (i + 1) % 5 == 0]
    below = blended_transform_factory(ax.transData, ax.transAxes)
    beside = blended_transform_factory(ax.transAxes, ax.transData)
    path_labels(ax, [(k, 0) for k in cols], [k + 1 for k in cols], "black", size=7, shift=(0, -9),
                offset_transform=below, ha="center")
    path_labels(ax, [(0, i) for i in rows], [i + 1 for i in rows], "black", size=7, shift=(-3, -2.5),
                offset_transform=beside, ha="right")
    cursor = ax.add_patch(Rectangle((-0.5, -0.5), 1, 1, fill=False, ec=CURSOR_COLOURS[False], lw=2.5,
                                    visible=False))
    return {"grid": grid, "cursor": cursor}


def update_grid(art: dict, model: StepperModel) -> None:
    art["grid"].set_data(model.grid() + 1)
    cursor = art["cursor"]
    cursor.set_visible(model.last is not None)
    if model.last is not None:
        cursor.set_xy((model.last.k - 0.5, model.last.i - 0.5))
        cursor.set_edgecolor(CURSOR_COLOURS[bool(model.last.changed)])


def draw_energy(ax, model: StepperModel) -> dict:
    """The energy (3-15) after each attempt, as in the thesis' Fig. 5.6."""
    from matplotlib.ticker import MaxNLocator

    line, = ax.plot([0], model.energies[:1], "-", color=OKABE_ITO["blue"], lw=1.2)
    rises = ax.scatter([], [], s=14, color=OKABE_ITO["vermillion"], zorder=3, label="energy went up")

    ax.set_xlabel("update attempt")
    ax.set_ylabel("energy E (3-15)")
    ax.xaxis.set_major_locator(MaxNLocator(4, integer=True))
    ax.yaxis.set_major_locator(MaxNLocator(3))
    ax.grid(alpha=0.3)
    return {"line": line, "rises": rises, "ax": ax}


def update_energy(art: dict, model: StepperModel) -> None:
    e = np.asarray(model.energies)
    x = np.arange(len(e))
    art["line"].set_data(x, e)
    up = model.rises()
    art["rises"].set_offsets(np.column_stack([up, e[up]]) if len(up) else np.zeros((0, 2)))
    ax = art["ax"]
    ax.set_xlim(0, max(10, len(e) - 1))
    low, high = float(e.min()), float(e.max())
    pad = max(0.5, 0.05 * (high - low))
    ax.set_ylim(low - pad, high + pad)


class HopfieldStepper(Base):
    """Buttons to step the network, with its grid, its matches and its energy curve.

    `left` and `right` are paths or images, or `left` a Prepared; "Run to convergence" makes
    at most `run_limit` attempts per click.

    Parameters
    ----------
    left, right : path or ndarray, or a Prepared as `left`
        The image pair.
    method : str, default ``DEFAULT_METHOD``
        The matching method.
    params : Params, optional
        Default the method's.
    seed : int, default 0
        Seed of the random visiting order.
    config : MatchConfig, optional
        Corner settings.
    run_limit : int, default 50000
        Most attempts per click of "Run to convergence".

    Notes
    -----
    CSS classes: root ``ismb-stepper``; buttons ``ismb-step``, ``ismb-step10``, ``ismb-run``,
    ``ismb-reset``; seed field ``ismb-seed``; checkbox ``ismb-thesis-rule``; figures
    ``ismb-grid`` (neurons), ``ismb-matches`` (image pair) and ``ismb-energy``;
    ``ismb-status``, ``ismb-log``.
    """

    def __init__(self, left, right=None, *, method=DEFAULT_METHOD, params: Params | None = None, seed: int = 0,
                 config: MatchConfig | None = None, run_limit: int = 50_000):
        super().__init__()
        prepared = left if isinstance(left, Prepared) else prepare(left, right, config)
        self.model = StepperModel(prepared, method, params, seed)
        self.run_limit = check_number(run_limit, "run_limit", "HopfieldStepper", low=1, integer=True)
        # Three figures, so that an attempt that flips nothing redraws neither the images
        # nor their matches: only the grid's cursor and the energy curve move.
        self.grid_pane = Pane((3.6, 3.2), "ismb-grid")
        self.pair_pane = Pane(pair_figsize(prepared.pair), "ismb-matches")
        self.energy_pane = Pane((5.8, 2.6), "ismb-energy")
        self.panes = (self.grid_pane, self.pair_pane, self.energy_pane)
        self.grid_pane.fig.subplots_adjust(left=0.18, bottom=0.16, right=0.76, top=0.97)
        self.grid_artists = draw_grid(self.grid_pane.fig.add_subplot(), self.model)
        self.pair_artists = draw_pair(self.pair_pane.fig.add_axes((0, 0, 1, 1)), self.model)
        self.energy_pane.fig.subplots_adjust(left=0.14, bottom=0.18, right=0.97, top=0.95)
        self.energy_artists = draw_energy(self.energy_pane.fig.add_subplot(), self.model)

        self.step_button = button("Step", "ismb-step", "One update attempt", icon="step-forward")
        self.step10_button = button("Step 10", "ismb-step10", "Ten update attempts", icon="forward")
        self.run_button = button("Run to convergence", "ismb-run",
                                 f"Run until a stop rule fires (at most {run_limit} attempts per click)",
                                 icon="fast-forward")
        self.reset_button = button("Reset", "ismb-reset", "All candidates on again", icon="refresh")
        self.seed_field = seed_field(self.model.seed, layout={"width": "140px"})
        self.rule_box = with_class(ipywidgets.Checkbox(value=False, description="literal thesis rule (3-20)",
                                                       indent=False), "ismb-thesis-rule")
        self.step_button.on_click(self.guard(lambda _: self.step(1)))
        self.step10_button.on_click(self.guard(lambda _: self.step(10)))
        self.run_button.on_click(self.guard(lambda _: self.run()))
        self.reset_button.on_click(self.guard(lambda _: self.reset()))
        self.seed_field.observe(self.guard(lambda _: self.reset()), names="value")
        self.rule_box.observe(self.guard(lambda _: self.reset()), names="value")
        bar = row([self.step_button, self.step10_button, self.run_button, self.reset_button,
                   self.seed_field, self.rule_box])
        views = row([self.grid_pane.widget, self.pair_pane.widget])
        self.widget = with_class(ipywidgets.VBox([bar, self.status, views, self.energy_pane.widget,
                                                  self.log]), "ismb-stepper")
        self.refresh()

    @classmethod
    def from_folder(cls, folder, **kw) -> "HopfieldStepper":
        """Step the network on ``folder/left.png`` and ``folder/right.png``.

        Parameters
        ----------
        folder : str or Path
            A pair folder.
        **kw
            The constructor's keyword parameters.

        Returns
        -------
        stepper : HopfieldStepper
            The widget.
        """
        left, right, _ = pair_files(folder, "HopfieldStepper.from_folder")
        return cls(left, right, **kw)

    def step(self, n: int = 1) -> list[Update]:
        """`n` update attempts, then one redraw (the image pair only if an output changed)."""
        updates = self.model.step(n)
        self.refresh(matches=any(u.changed for u in updates))
        return updates

    def run(self) -> int:
        """Run to a stop (at most `run_limit` attempts), drawing once at the end."""
        made = self.model.run(self.run_limit)
        self.refresh()
        if not self.model.done:
            self.say(self.model.describe() + f"; paused after {made} attempts, press Run again")
        return made

    def reset(self) -> None:
        """Start again with the seed field's seed and the rule checkbox's rule."""
        self.model.reset(self.seed_field.value, "thesis" if self.rule_box.value else "exact")
        self.refresh()

    def refresh(self, matches: bool = True) -> None:
        """Update the views from the model and draw them (the pair only when `matches`)."""
        update_grid(self.grid_artists, self.model)
        update_energy(self.energy_artists, self.model)
        for b in (self.step_button, self.step10_button, self.run_button):
            b.disabled = self.model.done
        self.say(self.model.describe())
        self.grid_pane.draw()
        if matches:
            update_pair(self.pair_artists, self.model)
            self.pair_pane.draw()
        self.energy_pane.draw()

    def static_figure(self):
        """A plain Figure: grid, matches and energy curve of the current state (for print)."""
        fig = Figure(figsize=(10.0, 6.0), layout="constrained")
        grid_ax, pair_ax, energy_ax = fig.subplot_mosaic([["grid", "pair"], ["energy", "energy"]],
                                                         width_ratios=[1, 2.2]).values()
        update_grid(draw_grid(grid_ax, self.model), self.model)
        update_pair(draw_pair(pair_ax, self.model), self.model)
        update_energy(draw_energy(energy_ax, self.model), self.model)
        return fig
