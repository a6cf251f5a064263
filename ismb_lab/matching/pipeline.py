"""Match one stereo pair end to end: corners, energy, network, result (thesis Fig. 3.4).

>>> from ismb_lab.scenes import synthetic_scene
>>> scene = synthetic_scene(seed=0)
>>> result = match(scene.left, scene.right, method="III", seed=0)
>>> result.stop_rule, len(result.pairs) > 10
('sweep', True)
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .._core.files import JsonRecord
from .._core.validation import MAX_SEED, ParameterError, ParameterTypeError, check_choice, check_number, message
from ..images.coords import euclidean_disparity, horizontal_disparity
from ..images.features import MAX_SIGMA, Corners, check_roi, detect_corners, resolve_roi
from ..images.io import StereoPair, load_pair
from ..network.methods import DEFAULT_METHOD, Problem, build_problem, get_method
from ..network.params import Params
from ..network.similarity import mean_abs_difference
from ..network.solvers import DEFAULT_SOLVER, get_solver, one_match_per_corner, solve, to_matches

__all__ = ["AUTO_MARGIN", "MatchConfig", "MatchResult", "Prepared", "auto_window", "check_window", "corner_problem",
           "match", "prepare", "shift_roi", "warm_up"]


@dataclass(frozen=True)
class MatchConfig:
    """Everything about a match that is not an energy parameter.

    `roi` is ``"center"`` (the thesis' centre quarter), ``"full"`` or ``(x, y, w, h)``; `n_min`,
    `n_max` bound the corners per image; `threshold` is Harris' initial ``T`` (None: the strongest
    response); `patch_size` the odd side of ``M_ik``'s window (3-8).  The candidate window is
    ``window_height x window_width`` centred `shift` px left (§3.3; ``"auto"``: measured on the
    pair by :func:`auto_window`, the numbers then in ``Prepared.config``); `neighbour_radius` and
    `neighbourhood` say which left features interact (3-12).  `right_roi` ``"shifted"`` moves the
    right ROI `shift` px left, so that corners near the left ROI's edge keep their partners;
    ``"same"`` is the thesis' (it loses one corner in eight).

    Attributes
    ----------
    roi : str or tuple of int, default "center"
        ``"center"``, ``"full"`` or ``(x, y, w, h)``.
    n_min, n_max : int, default 20, 30
        Bounds on the number of corners per image.
    threshold : float or None, default None
        Initial Harris threshold ``T``; None starts at the strongest response.
    harris_sigma : float, default 1.0
        Gaussian window of the structure tensor.
    harris_k : float, default 0.04
        Harris ``k``, in (0, 0.25).
    min_distance : int, default 3
        Local-maximum radius of the corners.
    patch_size : int, default 11
        Odd side of the window for ``M_ik`` (3-8).
    shift : float or "auto", default 20.0
        Pixels left of each left corner at which the candidate window is centred.
    window_height, window_width : float, default 30.0, 40.0
        Size of the candidate window.
    neighbour_radius : float, default 20.0
        Radius within which left features interact (3-12).
    neighbourhood : {"box", "disc"}, default "box"
        Shape of that neighbourhood.
    right_roi : {"shifted", "same"}, default "shifted"
        The right image's ROI: the left one moved `shift` px left, or the same.

    Raises
    ------
    ParameterError
        A field out of its range.
    """

    roi: object = "center"
    n_min: int = 20
    n_max: int = 30
    threshold: float | None = None
    harris_sigma: float = 1.0
    harris_k: float = 0.04
    min_distance: int = 3
    patch_size: int = 11
    shift: float | str = 20.0
    window_height: float = 30.0
    window_width: float = 40.0
    neighbour_radius: float = 20.0
    neighbourhood: str = "box"
    right_roi: str = "shifted"

    def __post_init__(self):
        owner = "MatchConfig"
        check_number(self.n_min, "n_min", owner, low=1, integer=True)
        check_number(self.n_max, "n_max", owner, low=self.n_min, integer=True)
        if self.threshold is not None:
            check_number(self.threshold, "threshold", owner, low=0, low_open=True)
        check_number(self.harris_sigma, "harris_sigma", owner, low=0, low_open=True, high=MAX_SIGMA)
        k = check_number(self.harris_k, "harris_k", owner, low=0, low_open=True)
        if k >= 0.25:
            raise ParameterError(message("harris_k", owner, "a finite number > 0 and < 0.25", k))
        check_number(self.min_distance, "min_distance", owner, low=1, integer=True)
        size = check_number(self.patch_size, "patch_size", owner, low=1, integer=True)
        if size % 2 == 0:
            raise ParameterError(message("patch_size", owner, "an odd integer", size))
        if not (isinstance(self.shift, str) and self.shift == "auto"):
            if isinstance(self.shift, str):
                raise ParameterError(message("shift", owner, "a number of pixels or 'auto'", self.shift))
            check_number(self.shift, "shift", owner)
        check_number(self.window_height, "window_height", owner, low=0, low_open=True)
        check_number(self.window_width, "window_width", owner, low=0, low_open=True)
        check_number(self.neighbour_radius, "neighbour_radius", owner, low=0, low_open=True)
        check_choice(self.neighbourhood, "neighbourhood", owner, ("box", "disc"))
        check_choice(self.right_roi, "right_roi", owner, ("shifted", "same"))
        if isinstance(self.roi, list):
            object.__setattr__(self, "roi", tuple(self.roi))
        check_roi(self.roi, owner)   # its form now; whether it lies inside the images when they are read

    @property
    def min_shape(self) -> tuple[int, int]:
        """Smallest image (height, width) that holds the similarity and Harris windows."""
        border = int(np.ceil(3 * self.harris_sigma)) + 1
        side = max(self.patch_size, 2 * border + 1)
        return side, side


#: Margin, in pixels, added on each side of the robust matches' disparity range by :func:`auto_window`.
AUTO_MARGIN = 5.0


def auto_window(pair, config: MatchConfig, *, rows_px: float | None = None) -> MatchConfig:
    """`config` with ``shift="auto"`` replaced by numbers measured on `pair`.

    The robust matches (:func:`ismb_lab.images.rectify.robust_matches`) in the ROI (the whole
    image if fewer than 8) whose rows differ by at most `rows_px` (default 2 px) give the
    2nd-98th percentile disparity range; the window is centred on it and widened to hold it
    plus :data:`AUTO_MARGIN` on each side.  `rows_px` (a calibrated camera's) also makes the
    robust matches search their own rows at positive disparities only.

    Raises
    ------
    ParameterError
        Fewer than 8 such matches.
    """
    from ..images.rectify import robust_matches

    if config.shift != "auto":
        return config
    matches = robust_matches(pair.left, pair.right, rows_px=rows_px)
    rows_px = 2.0 if rows_px is None else rows_px
    x, y, w, h = resolve_roi(config.roi, pair.shape)
    lxy, rxy = matches.left_xy, matches.right_xy
    inside = ((lxy[:, 0] >= x) & (lxy[:, 0] < x + w) & (lxy[:, 1] >= y) & (lxy[:, 1] < y + h)
              & (matches.abs_dy <= rows_px)) if len(lxy) else np.zeros(0, bool)
    if inside.sum() < 8:      # a small ROI: the whole pair's range is the best guess there is
        inside = matches.abs_dy <= rows_px if len(lxy) else inside
    d = lxy[inside, 0] - rxy[inside, 0]
    if len(d) < 8:
        raise ParameterError(message("shift", "MatchConfig", "a number of pixels when the pair has fewer than "
                                     "8 robust matches on the same rows ('auto' measures the disparities)",
                                     f"'auto' with {len(d)} such matches"))
    lo, hi = np.percentile(d, [2, 98])
    width = max(float(config.window_width), float(hi - lo) + 2 * AUTO_MARGIN)
    return replace(config, shift=round(float(lo + hi) / 2, 2), window_width=round(width, 2))


def check_window(config: MatchConfig, shape) -> MatchConfig:
    """Check that `config`'s ROI lies in an image of `shape` ``(height, width)`` and that its
    window can reach it (a shift beyond ``width - 1 + window_width / 2`` cannot); returns `config`.

    >>> check_window(MatchConfig(shift=1e308), (240, 320))
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'shift' parameter of MatchConfig must be at most 339 pixels either way, so that
    the 40-pixel-wide candidate window can reach the 320-pixel-wide image. Got 1e+308 instead.
    """
    resolve_roi(config.roi, shape)
    if config.shift != "auto":
        most = shape[1] - 1 + config.window_width / 2
        if abs(config.shift) > most:
            raise ParameterError(message("shift", "MatchConfig", f"at most {most:g} pixels either way, so that the "
                                         f"{config.window_width:g}-pixel-wide candidate window can reach the "
                                         f"{shape[1]}-pixel-wide image", config.shift))
    return config


def shift_roi(roi, shift: float, shape) -> tuple[int, int, int, int]:
    """Move an ``(x, y, w, h)`` ROI ``shift`` pixels left, cropped to the image.

    >>> shift_roi((80, 60, 160, 120), 20, (240, 320))
    (60, 60, 160, 120)
    >>> shift_roi((10, 60, 160, 120), 20, (240, 320))
    (0, 60, 150, 120)
    """
    x, y, w, h = roi
    height, width = shape
    start = min(max(x - int(round(shift)), 0), width - 1)
    stop = max(min(x + w - int(round(shift)), width), start + 1)
    return start, y, stop - start, h


@dataclass(frozen=True, eq=False)
class Prepared:
    """A loaded pair with its corners and parameter-free energy ingredients."""

    pair: StereoPair
    config: MatchConfig
    left_corners: Corners
    right_corners: Corners
    problem: Problem


def prepare(left, right, config: MatchConfig | None = None) -> Prepared:
    """Load a pair (paths, arrays, or a StereoPair with `right` None), detect corners in both
    images and compute ``M`` and the geometry.

    Parameters
    ----------
    left, right : path, ndarray or StereoPair
        The images (see :func:`ismb_lab.images.io.load_pair`); `right` None with a StereoPair.
    config : MatchConfig, optional
        Corners, candidate window and neighbourhood; default ``MatchConfig()``.

    Returns
    -------
    prepared : Prepared
        The pair, its corners and the energy's ingredients.

    Raises
    ------
    ParameterTypeError
        `config` is not a MatchConfig.
    ParameterError
        The images or the window are not usable.
    """
    config = MatchConfig() if config is None else config
    if not isinstance(config, MatchConfig):
        raise ParameterTypeError(message("config", "prepare", "a MatchConfig", config))
    pair = left if isinstance(left, StereoPair) and right is None else load_pair(
        left, right, min_shape=config.min_shape)
    check_window(config, pair.shape)
    config = auto_window(pair, config)
    check_window(config, pair.shape)
    left_roi = resolve_roi(config.roi, pair.shape)
    right_roi = left_roi if config.right_roi == "same" else shift_roi(left_roi, config.shift, pair.shape)
    kwargs = dict(n_min=config.n_min, n_max=config.n_max, threshold=config.threshold,
                  sigma=config.harris_sigma, k=config.harris_k, min_distance=config.min_distance)
    lc = detect_corners(pair.left, roi=left_roi, **kwargs)
    rc = detect_corners(pair.right, roi=right_roi, **kwargs)
    return Prepared(pair, config, lc, rc, corner_problem(pair, lc.xy, rc.xy, config))


def corner_problem(pair: StereoPair, left_xy, right_xy, config: MatchConfig, dissimilarity=None) -> Problem:
    """The energy's ingredients for corners of `pair`: ``M`` (3-8) unless given, and the
    candidates and neighbours of `config`'s window (:func:`ismb_lab.network.methods.build_problem`).

    Parameters
    ----------
    pair : StereoPair
        The loaded pair.
    left_xy, right_xy : (n, 2) float array
        Corners ``(x, y)`` in each image.
    config : MatchConfig
        Patch size, candidate window and neighbourhood.
    dissimilarity : (n_left, n_right) float array, optional
        ``M`` to use instead of the mean absolute difference of patches.

    Returns
    -------
    problem : Problem
        ``M``, the candidate neurons and their neighbour pairs.

    Examples
    --------
    >>> from ismb_lab.scenes import synthetic_scene
    >>> s = synthetic_scene(0)
    >>> p = prepare(s.left, s.right)
    >>> q = corner_problem(p.pair, p.left_corners.xy, p.right_corners.xy, p.config)
    >>> bool((q.rows == p.problem.rows).all()), q.dissimilarity.shape == p.problem.dissimilarity.shape
    (True, True)
    """
    M = (mean_abs_difference(pair.left, pair.right, left_xy, right_xy, config.patch_size)
         if dissimilarity is None else dissimilarity)
    return build_problem(left_xy, right_xy, M, shift=config.shift, window_height=config.window_height,
                         window_width=config.window_width, radius=config.neighbour_radius,
                         neighbourhood=config.neighbourhood)


@dataclass(frozen=True, eq=False)
class MatchResult(JsonRecord):
    """The outcome of matching one pair: all features ``left_xy``, ``right_xy`` (``(x, y)`` in the
    full image), the matched ``pairs`` ``(i, k)`` sorted by ``i``, the final ``energy`` (3-15), the
    candidate neurons' ``state`` after post-processing, and ``message``, why the match is empty or
    partial ("" when all went well).

    Attributes
    ----------
    method : str
        The energy recipe's name.
    params : Params
        The energy parameters used.
    seed : int
        Seed of the update order.
    stop_rule : str
        What stopped the network (``"sweep"``, ``"stall"``, ``"max_attempts"``) or ``"minimum"``.
    energy : float
        Final energy (3-15).
    attempts : int
        Update attempts made.
    left_xy, right_xy : (n, 2) float array
        All features, ``(x, y)`` in the full image.
    pairs : (m, 2) int array
        Matched ``(i, k)`` feature indices, sorted by ``i``.
    message : str
        Empty when all went well, otherwise why the match is empty or partial.
    n_candidates : int
        Candidate neurons.
    state : (n_candidates,) uint8 array
        Final outputs of the candidate neurons, after post-processing.
    solver : str
        Name of the solver that found the state.
    one_to_one : bool
        Whether at most one match per corner was kept.
    """

    method: str
    params: Params
    seed: int
    stop_rule: str
    energy: float
    attempts: int
    left_xy: np.ndarray
    right_xy: np.ndarray
    pairs: np.ndarray
    message: str = ""
    n_candidates: int = 0
    state: np.ndarray = field(default=None, repr=False)
    solver: str = DEFAULT_SOLVER
    one_to_one: bool = False

    @property
    def left_match_xy(self) -> np.ndarray:
        """(m, 2) float array: the matched left features ``(x, y)``."""
        return self.left_xy[self.pairs[:, 0]]

    @property
    def right_match_xy(self) -> np.ndarray:
        """(m, 2) float array: the matched right features ``(x, y)``."""
        return self.right_xy[self.pairs[:, 1]]

    @property
    def disparity(self) -> np.ndarray:
        """(m,) float array: Euclidean disparity of each match, as in the thesis' tables."""
        return euclidean_disparity(self.left_match_xy, self.right_match_xy)

    @property
    def horizontal_disparity(self) -> np.ndarray:
        """(m,) float array: ``x_left - x_right`` of each match."""
        return horizontal_disparity(self.left_match_xy, self.right_match_xy)

    def table(self) -> str:
        """A plain-text table shaped like Table 5.3 (features numbered from 1).

        Returns
        -------
        text : str
            One line per match, then `message` if any.
        """
        head = ("Pair", "Left", "Right", "y_left", "x_left", "y_right", "x_right", "disparity")
        lines = ["{:>4} {:>5} {:>5} {:>7} {:>7} {:>7} {:>7} {:>9}".format(*head)]
        for n, ((i, k), p, q, d) in enumerate(zip(self.pairs, self.left_match_xy,
                                                  self.right_match_xy, self.disparity), 1):
            lines.append(f"{n:>4} {i + 1:>5} {k + 1:>5} {p[1]:>7g} {p[0]:>7g} {q[1]:>7g} "
                         f"{q[0]:>7g} {d:>9.2f}")
        if self.message:
            lines.append(self.message)
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """The JSON contract of ``ismb-lab match --json``.

        Returns
        -------
        data : dict
            Method, solver, params, seed, energy, stop rule, features and matches.
        """
        return {
            "method": self.method,
            "solver": self.solver,
            "one_to_one": self.one_to_one,
            "params": self.params.to_dict(),
            "seed": self.seed,
            "energy": self.energy,
            "stop_rule": self.stop_rule,
            "attempts": self.attempts,
            "message": self.message,
            "left_features": _xy_list(self.left_xy),
            "right_features": _xy_list(self.right_xy),
            "matches": [
                {"left": int(i), "right": int(k), "left_xy": _xy_list(p), "right_xy": _xy_list(q),
                 "disparity": float(d)}
                for (i, k), p, q, d in zip(self.pairs, self.left_match_xy, self.right_match_xy,
                                           self.disparity)
            ],
        }


def _xy_list(xy):
    xy = np.asarray(xy, dtype=float)
    if np.all(xy == np.round(xy)):
        return xy.astype(int).tolist()
    return xy.tolist()


def match(left=None, right=None, method=DEFAULT_METHOD, params: Params | None = None, *,
          config: MatchConfig | None = None, seed: int = 0, solver=DEFAULT_SOLVER,
          stop_rule: str | None = None, rule: str | None = None, kernel: str | None = None,
          prepared: Prepared | None = None, one_to_one: bool = False) -> MatchResult:
    """Match the Harris corners of a stereo pair with the Hopfield network.

    `method` is a name of :func:`ismb_lab.network.methods.method_names`, `params` default to its
    own; `seed` (0 to 2**63 - 1) orders the updates; `solver` is a name of
    :data:`ismb_lab.network.solvers.SOLVERS` or a Solver, whose options `stop_rule`, `rule` and
    `kernel` replace unless None.  `prepared` (from :func:`prepare`) replaces `left` and `right`;
    `one_to_one` keeps at most one match per corner, the most similar.

    Parameters
    ----------
    left, right : path, ndarray or StereoPair, optional
        The image pair; ignored when `prepared` is given.
    method : str, default "III"
        Energy recipe, a name of :func:`ismb_lab.network.methods.method_names`.
    params : Params, optional
        Energy parameters; by default the method's.
    config : MatchConfig, optional
        Corners, candidate window and neighbourhood; default ``MatchConfig()``.
    seed : int, default 0
        Seed of the random update order (and of annealing), 0 to 2**63 - 1.
    solver : str or Solver, default "network"
        How the energy is minimised.
    stop_rule, rule, kernel : str, optional
        Solver options that replace the solver's own; None keeps them.
    prepared : Prepared, optional
        Corners and geometry from :func:`prepare`.
    one_to_one : bool, default False
        Keep at most one match per corner, the most similar.

    Returns
    -------
    result : MatchResult
        The matches, the final energy and why it stopped.

    Raises
    ------
    ParameterTypeError
        `params`, `one_to_one` or `prepared` of the wrong type.
    ParameterError
        An unknown method or solver, a seed out of range, or unusable images.
    """
    m = get_method(method)
    params = m.defaults if params is None else params
    if not isinstance(params, Params):
        raise ParameterTypeError(message("params", "match", "a Params instance", params))
    # the settings are checked before the images are read
    solver = get_solver(solver, "match", stop_rule=stop_rule, rule=rule, kernel=kernel)
    check_number(seed, "seed", "match", low=0, high=MAX_SEED, integer=True)
    if not isinstance(one_to_one, bool):
        raise ParameterTypeError(message("one_to_one", "match", "True or False", one_to_one))
    if prepared is None:
        prepared = prepare(left, right, config)
    elif not isinstance(prepared, Prepared):
        raise ParameterTypeError(message("prepared", "match", "a Prepared from prepare()", prepared))
    problem = prepared.problem
    result = solve(m.network(problem, params), solver, seed=seed, owner="match")
    found = to_matches(problem, result.state, m)
    if one_to_one:
        kept = np.zeros_like(found.state)
        kept[one_match_per_corner(problem, np.flatnonzero(found.state))] = 1
        found = to_matches(problem, kept)
    return MatchResult(m.name, params, int(seed), result.stop_rule, result.energy, result.attempts,
                       problem.left_xy, problem.right_xy, found.pairs, _explain(prepared, result),
                       problem.n_neurons, found.state, solver.name, one_to_one)


def _explain(prepared: Prepared, result) -> str:
    lc, rc, problem = prepared.left_corners, prepared.right_corners, prepared.problem
    notes = [f"{side} image: {c.message}" for side, c in (("left", lc), ("right", rc)) if c.message]
    if len(lc) and len(rc) and problem.n_neurons == 0:
        c = prepared.config
        notes.append(f"no candidate pairs: no right corner lies in the {c.window_height:g}x"
                     f"{c.window_width:g} window shifted {c.shift:g} px left of any left corner")
    elif problem.n_neurons:
        lonely = len(lc) - len(np.unique(problem.rows))
        if lonely:
            notes.append(f"{lonely} of {len(lc)} left corners have no candidate in their window")
    if not result.converged:
        notes.append("the network did not settle within the attempt limit")
    return "; ".join(notes)


def warm_up(solvers=(DEFAULT_SOLVER,)) -> float:
    """Compile (or load from numba's cache) the kernels a first match of each of `solvers`
    runs, on a small texture made in memory; returns the seconds.

    Parameters
    ----------
    solvers : tuple of str, default ("network",)
        Names of the solvers to prepare; each compiles its own kernels.

    Returns
    -------
    seconds : float
        Time spent.

    Examples
    --------
    >>> warm_up() >= 0
    True
    """
    import time

    if isinstance(solvers, str) or not isinstance(solvers, (tuple, list)):
        raise ParameterTypeError(message("solvers", "warm_up", "a tuple of solver names", solvers))
    start = time.perf_counter()
    texture = np.random.default_rng(0).integers(0, 256, (60, 100)).astype(float)
    texture = np.kron(texture, np.ones((2, 2)))[:120, :160]      # blocks: corners at their edges
    for solver in solvers:
        match(texture, np.roll(texture, -8, axis=1), method=DEFAULT_METHOD, solver=solver,
              config=MatchConfig(roi="full", shift=8))
    return time.perf_counter() - start
