"""Run the GA (thesis ch. 4) live: fitness curves grow while the notebook stays usable.

The GA runs in a worker thread, not an asyncio task on the kernel's loop: clicks on Pause
and Stop are handled at once, and scripts and tests need no event loop.  The thread checks a
stop event between generations and waits on a resume event while paused.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Callable

import ipywidgets
import numpy as np
from matplotlib.figure import Figure

from .._core.validation import ParameterError, ParameterTypeError, check_number, message
from ..tuning.genetic import GAConfig, Generation
from ..matching.pipeline import MatchConfig
from ..network.methods import DEFAULT_METHOD, get_method
from ..plotting import OKABE_ITO
from ..network.params import Params
from ..tuning.cases import Case
from ..matching.recipe import Recipe, save_recipe
from ..network.solvers import DEFAULT_SOLVER, SOLVERS, get_solver
from ..tuning.fitness import to_params, tune
from ._common import Base, Pane, button, menu, pair_files, row, with_class

__all__ = ["as_cases", "case_from_folder", "chromosome_html", "draw_fitness", "GAModel", "GARunner",
           "update_fitness"]


def case_from_folder(folder, config: MatchConfig | None = None) -> Case:
    """A training :class:`~ismb_lab.tuning.cases.Case` from a pair folder with an ``answer_key.json``."""
    left, right, key = pair_files(folder, "case_from_folder")
    if not key.is_file():
        raise ParameterError(f"The 'folder' parameter of case_from_folder must be a folder with an "
                             f"answer_key.json (the GA's targets). Got {str(folder)!r} instead.")
    return Case.from_files(left, right, key, config, name=Path(folder).name)


def as_cases(cases_or_folder, config: MatchConfig | None = None) -> list[Case]:
    """Accept a Case, a folder, or a sequence of either."""
    items = cases_or_folder if isinstance(cases_or_folder, (list, tuple)) else [cases_or_folder]
    out = []
    for item in items:
        if isinstance(item, Case):
            out.append(item)
        elif isinstance(item, (str, Path)):
            out.append(case_from_folder(item, config))
        else:
            raise ParameterTypeError(message("cases_or_folder", "GARunner", "a Case, a pair folder or a "
                                             "list of them", item))
    if not out:
        raise ParameterError(message("cases_or_folder", "GARunner", "at least one training pair", items))
    return out


class GAModel:
    """A GA run in a worker thread, with pause, resume and stop.

    `seed` seeds the GA and every run's update order, as in ``tune``; `save_to`, a params file,
    is rewritten atomically whenever the best fitness improves, so that a killed kernel loses nothing.

    >>> from ismb_lab.matching.pipeline import prepare
    >>> from ismb_lab.scenes import synthetic_scene, true_matches
    >>> scene = synthetic_scene(0)
    >>> p = prepare(scene.left, scene.right)
    >>> k = true_matches(scene, p.problem.left_xy, p.problem.right_xy)
    >>> case = Case(p, np.array([(i, j) for i, j in enumerate(k) if j >= 0]))
    >>> ga = GAModel([case], population=6, generations=3)
    >>> ga.start()
    True
    >>> ga.wait(60), ga.status, len(ga.history) >= 1
    (True, 'finished', True)
    """

    def __init__(self, cases, method=DEFAULT_METHOD, *, population: int | None = None, generations: int | None = None,
                 seed: int = 0, save_to=None, solver: str = DEFAULT_SOLVER):
        owner = "GAModel"
        self.save_to = None if save_to is None else Path(save_to)
        if self.save_to is not None and not self.save_to.parent.is_dir():
            raise ParameterError(f"The 'save_to' parameter of {owner} must be a file in an existing folder. "
                                 f"Got {str(save_to)!r} instead.")
        self.cases = list(cases)
        self.method = get_method(method)
        self.solver = get_solver(solver, owner).name
        self.ga = GAConfig().updated(owner, population=population, generations=generations)
        self.population, self.generations = self.ga.population, self.ga.generations
        self.seed = check_number(seed, "seed", owner, low=0, integer=True)
        self.target = sum(len(c.targets) for c in self.cases)
        self.history: list[Generation] = []
        #: Seconds the GA has computed so far in this run (pauses and listeners left out).
        self.elapsed = 0.0
        self.status = "idle"
        self.error: BaseException | None = None
        self.listeners: list[Callable[[Generation], None]] = []
        self._stop = threading.Event()
        self._resume = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @property
    def best(self) -> Generation | None:
        return self.history[-1] if self.history else None

    @property
    def best_params(self) -> Params | None:
        """The best chromosome so far as Params (None before generation 0)."""
        return None if not self.history else to_params(self.method, self.history[-1].best_chromosome)

    def start(self) -> bool:
        """Start a fresh run in a worker thread; False if one is running already."""
        if self.running:
            return False
        self.history, self.error, self.elapsed = [], None, 0.0
        self._stop.clear()
        self._resume.set()
        self.status = "running"
        # it checks its arguments now, in the caller's thread
        records = tune(self.cases, self.method, rng=self.seed, ga=self.ga, seed=self.seed, solver=self.solver)
        self._thread = threading.Thread(target=self._work, args=(records,), name="ismb-ga", daemon=True)
        self._thread.start()
        return True

    def _work(self, records) -> None:
        try:
            began = time.monotonic()
            for record in records:
                self.elapsed += time.monotonic() - began
                improved = not self.history or record.best > self.history[-1].best
                self.history.append(record)
                if improved and self.save_to is not None:
                    recipe = Recipe(self.method, to_params(self.method, record.best_chromosome), self.solver)
                    save_recipe(self.save_to, recipe, fitness=record.best, generations=record.index, seed=self.seed,
                                targets=self.target)
                for listener in list(self.listeners):
                    listener(record)
                while not (self._resume.wait(0.1) or self._stop.is_set()):
                    pass
                if self._stop.is_set():
                    self.status = "stopped"
                    return
                began = time.monotonic()
            self.status = "finished"
        except BaseException as exc:  # noqa: BLE001 - kept for the caller, the thread must end cleanly
            self.error, self.status = exc, "failed"

    def set_generations(self, generations: int) -> None:
        """Run at most `generations` generations from the next Start on (refused while a run is going)."""
        owner = "GAModel.set_generations"
        if self.running:
            raise ParameterError(message("generations", owner, "changed only while no GA is running (Stop it "
                                         "first)", generations))
        self.ga = self.ga.updated(owner, generations=generations)
        self.generations = self.ga.generations

    def pause(self) -> None:
        if self.running:
            self._resume.clear()
            self.status = "paused"

    def resume(self) -> None:
        if self.running:
            self.status = "running"
            self._resume.set()

    def stop(self) -> None:
        """Ask the run to end after the generation in progress."""
        self._stop.set()
        self._resume.set()

    def wait(self, timeout: float | None = None) -> bool:
        """Wait for the run to end; True when no run is alive any more."""
        if self._thread is not None:
            self._thread.join(timeout)
        return not self.running

    def describe(self) -> str:
        g = self.best
        head = f"Method-{self.method.name} ({self.solver}) GA ({self.population} chromosomes, target fitness {self.target})"
        if g is None:
            return f"{head}: {self.status}"
        text = (f"{head}: {self.status}, generation {g.index}/{self.generations}, best {g.best:g}, "
                f"mean {g.mean:.2f}, {g.evaluations} network evaluations in {self.elapsed:.1f} s")
        if self.status == "finished" and g.mean >= self.target:
            text += "; every chromosome reproduces the targets"
        if self.error is not None:
            text += f"; failed: {self.error}"
        return text


def draw_fitness(ax, model: GAModel) -> dict:
    """Best and mean fitness per generation (thesis Figs. 5.4, 5.5)."""
    from matplotlib.ticker import MaxNLocator

    best, = ax.plot([], [], "-", color=OKABE_ITO["vermillion"], lw=1.5, label="best")
    mean, = ax.plot([], [], "-", color=OKABE_ITO["blue"], lw=1.2, label="mean")
    ax.axhline(model.target, color="grey", ls=":", lw=1, label="target n_c")
    ax.set_xlabel("generation")
    ax.set_ylabel("fitness n_c - n_e")
    ax.xaxis.set_major_locator(MaxNLocator(5, integer=True))
    ax.yaxis.set_major_locator(MaxNLocator(4))
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(alpha=0.3)
    return {"best": best, "mean": mean, "ax": ax, "target": model.target}


def update_fitness(art: dict, history: list) -> None:
    x = np.array([g.index for g in history], dtype=float)
    best = np.array([g.best for g in history])
    mean = np.array([g.mean for g in history])
    art["best"].set_data(x, best)
    art["mean"].set_data(x, mean)
    ax = art["ax"]
    ax.set_xlim(0, max(10, x[-1] if len(x) else 0))
    if len(x):
        low = min(float(mean.min()), float(best.min()))
        high = max(float(best.max()), art["target"])
        ax.set_ylim(low - 1, high + 1)


def chromosome_html(model: GAModel) -> str:
    g = model.best
    if g is None:
        return ""
    cells = "".join(f"<td><b>{name}</b> = {value:.2f}</td>"
                    for name, value in zip(model.method.gene_names, g.best_chromosome))
    return f'<table class="ismb-table"><tr><td>best chromosome:</td>{cells}</tr></table>'


class GARunner(Base):
    """Start, pause and stop the GA and watch its fitness; apply the best parameters elsewhere.

    `cases_or_folder` is a Case, a pair folder with an ``answer_key.json`` (corners by `config`),
    or a list of them; the curves are redrawn at most every `redraw_every` s while running.

    Parameters
    ----------
    cases_or_folder : Case, folder, or a list of them
        The training pairs.
    method : str, default ``DEFAULT_METHOD``
        The method to tune.
    population, generations : int, optional
        GA size; default :class:`~ismb_lab.tuning.genetic.GAConfig`'s.
    seed : int, default 0
        Seed of the GA and of every network run's update order.
    config : MatchConfig, optional
        Corner settings for folders.
    redraw_every : float, default 0.2
        Seconds between redraws of the curves while running.
    save_to : str or os.PathLike, optional
        A params file rewritten whenever the best fitness improves.
    solver : str, default ``DEFAULT_SOLVER``
        How each chromosome's network is solved.

    Notes
    -----
    CSS classes: root ``ismb-ga``; buttons ``ismb-start``, ``ismb-pause``, ``ismb-stop``,
    ``ismb-apply``; ``ismb-solver``; ``ismb-generations``; ``ismb-progress``; figure ``ismb-fitness``; best chromosome
    ``ismb-chromosome``; ``ismb-status``; ``ismb-log``.
    """

    def __init__(self, cases_or_folder, *, method=DEFAULT_METHOD, population: int | None = None,
                 generations: int | None = None, seed: int = 0, config: MatchConfig | None = None,
                 redraw_every: float = 0.2, save_to=None, solver: str = DEFAULT_SOLVER):
        super().__init__()
        self.model = GAModel(as_cases(cases_or_folder, config), method, population=population,
                             generations=generations, seed=seed, save_to=save_to, solver=solver)
        self.redraw_every = check_number(redraw_every, "redraw_every", "GARunner", low=0)
        self._apply: list[Callable[[Params], object]] = []
        self._lock = threading.Lock()
        self._drawn_at = 0.0
        self._watcher: threading.Thread | None = None
        self.pane = Pane((5.8, 3.0), "ismb-fitness")
        self.panes = (self.pane,)
        self.pane.fig.subplots_adjust(left=0.13, bottom=0.17, right=0.97, top=0.95)
        self.artists = draw_fitness(self.pane.fig.add_subplot(), self.model)

        self.start_button = button("Start", "ismb-start", "Start a fresh GA run", icon="play")
        self.pause_button = button("Pause", "ismb-pause", "Pause or resume the run", icon="pause",
                                   disabled=True)
        self.stop_button = button("Stop", "ismb-stop", "Stop after the current generation", icon="stop",
                                  disabled=True)
        self.apply_button = button("Apply best parameters", "ismb-apply",
                                   "Send the best chromosome to the registered widgets", disabled=True)
        self.progress = with_class(ipywidgets.IntProgress(value=0, min=0, max=self.model.generations,
                                                          description="generation"), "ismb-progress")
        self.chromosome = with_class(ipywidgets.HTML(""), "ismb-chromosome")
        self.solver_menu = menu("solver", SOLVERS, self.model.solver, layout=ipywidgets.Layout(width="auto"))
        self.solver_menu.observe(self.guard(lambda c: self.set_solver(c["new"])), names="value")
        self.generations_field = with_class(ipywidgets.BoundedIntText(
            value=self.model.generations, min=1, max=100_000, description="generations",
            layout=ipywidgets.Layout(width="190px")), "ismb-generations")
        self.generations_field.observe(self.guard(lambda c: self.set_generations(c["new"])), names="value")
        self.start_button.on_click(self.guard(lambda _: self.start()))
        self.pause_button.on_click(self.guard(lambda _: self.toggle_pause()))
        self.stop_button.on_click(self.guard(lambda _: self.stop()))
        self.apply_button.on_click(self.guard(lambda _: self.apply()))
        self.model.listeners.append(self._on_generation)
        bar = row([self.start_button, self.pause_button, self.stop_button, self.apply_button, self.solver_menu,
                   self.generations_field])
        self.widget = with_class(ipywidgets.VBox([bar, self.progress, self.status, self.pane.widget,
                                                  self.chromosome, self.log]), "ismb-ga")
        self.refresh()

    @classmethod
    def from_folder(cls, folder, **kw) -> "GARunner":
        """Tune on one pair folder (targets: its ``answer_key.json``).

        Parameters
        ----------
        folder : str or Path
            A pair folder with ``answer_key.json``.
        **kw
            The constructor's keyword parameters.

        Returns
        -------
        runner : GARunner
            The widget.
        """
        return cls(Path(folder) if isinstance(folder, str) else folder, **kw)

    def on_apply(self, callback: Callable[[Params], object]) -> None:
        """Call ``callback(params)`` when "Apply best parameters" is pressed.

        Parameters
        ----------
        callback : callable
            Called with the best :class:`~ismb_lab.network.params.Params`, e.g. an explorer's ``set_params``.
        """
        if not callable(callback):
            raise ParameterTypeError(message("callback", "GARunner.on_apply", "a callable", callback))
        self._apply.append(callback)

    def set_solver(self, name: str) -> None:
        """Solve with `name` from the next Start on (refused while a run is going)."""
        try:
            if self.model.running:
                raise ParameterError(message("solver", "GARunner.set_solver", "changed only while no GA "
                                             "is running (Stop it first)", name))
            self.model.solver = get_solver(name, "GARunner.set_solver").name
        finally:
            with self.syncing():
                self.solver_menu.value = self.model.solver
        self.say(self.model.describe())

    def set_generations(self, generations: int) -> None:
        """Run at most `generations` generations from the next Start on (refused while a run is going)."""
        try:
            self.model.set_generations(generations)
            self.progress.max = self.model.generations
        finally:
            with self.syncing():
                self.generations_field.value = self.model.generations
        self.say(self.model.describe())

    def start(self) -> bool:
        if not self.model.start():
            self.say("the GA is running already: Stop it first")
            return False
        self._drawn_at = 0.0
        self._buttons()
        self.say(self.model.describe())
        self._watcher = threading.Thread(target=self._finish, name="ismb-ga-watch", daemon=True)
        self._watcher.start()
        return True

    def toggle_pause(self) -> None:
        if self.model.status == "paused":
            self.model.resume()
        else:
            self.model.pause()
        self._buttons()
        self.say(self.model.describe())

    def stop(self) -> None:
        # The watcher writes the final status once the run has ended, under this lock: a
        # run still alive here has not had it yet, so this line never hides "stopped".
        with self._lock:
            if self.model.running:
                self.say("stopping after the current generation")
            self.model.stop()

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until the run and its final redraw are done; True if nothing is left running."""
        end = None if timeout is None else time.monotonic() + timeout
        done = self.model.wait(timeout)
        watcher = self._watcher
        if watcher is not None:
            watcher.join(None if end is None else max(0.0, end - time.monotonic()))
            done = done and not watcher.is_alive()
        return done

    def apply(self) -> Params | None:
        """Send the best parameters so far to every :meth:`on_apply` callback."""
        params = self.model.best_params
        if params is None:
            self.say("no generation yet: Start the GA first")
            return None
        for callback in self._apply:
            callback(params)
        self.say(f"applied {params} to {len(self._apply)} widget(s)")
        return params

    def _on_generation(self, record: Generation) -> None:
        self.progress.value = record.index
        self.say(self.model.describe())
        now = time.monotonic()
        if now - self._drawn_at >= self.redraw_every:
            self._drawn_at = now
            self.refresh()

    def _finish(self) -> None:
        self.model.wait()
        if self.model.error is not None:
            self.report(self.model.error)
        try:
            self.refresh()
        except Exception as exc:  # noqa: BLE001 - in this thread it would be lost, and the status stale
            self.report(exc)

    def _buttons(self) -> None:
        running = self.model.running and self.model.status in ("running", "paused")
        self.start_button.disabled = running
        self.pause_button.disabled = not running
        self.stop_button.disabled = not running
        self.pause_button.description = "Resume" if self.model.status == "paused" else "Pause"
        self.pause_button.icon = "play" if self.model.status == "paused" else "pause"
        self.apply_button.disabled = self.model.best is None
        self.solver_menu.disabled = running
        self.generations_field.disabled = running

    def refresh(self) -> None:
        with self._lock:
            history = list(self.model.history)
            update_fitness(self.artists, history)
            self.chromosome.value = chromosome_html(self.model)
            if history:
                self.progress.value = history[-1].index
            self._buttons()
            if self.model.error is None:
                self.say(self.model.describe())
            self.pane.draw()

    def static_figure(self):
        """A plain Figure of the fitness curves so far (for print)."""
        fig = Figure(figsize=(6.0, 3.0), layout="constrained")
        update_fitness(draw_fitness(fig.add_subplot(), self.model), list(self.model.history))
        return fig
