"""Automatic checks for the notebook exercises.

Each check compares a student's answer with the package's own computation and returns a
:class:`Feedback`: ``"correct"``, or a sentence that names the slip it recognised (a halved
quadratic part, a missing constant, a flipped sign) or the term that is off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, check_points, check_rng, message
from ..images.coords import euclidean_disparity, horizontal_disparity, vertical_disparity
from ..depth.objects import metric_depth
from ..tuning.evaluation import score
from ..images.features import harris_from_tensor, harris_response, image_gradients, structure_tensor
from ..network.hopfield import Network, energy, hopfield_form
from ..network.similarity import transfer

__all__ = ["check_depth_range", "check_disparity", "check_energy_derivation", "check_error_kinds",
           "check_fitness", "check_harris_response", "check_hopfield_form", "check_transfer", "Feedback",
           "random_network"]


@dataclass(frozen=True)
class Feedback:
    """The verdict of one exercise check: `text` is ``"correct"``, or what is off and a hint.

    >>> print(Feedback(True, "correct"))
    correct
    """

    correct: bool
    text: str

    def __str__(self) -> str:
        return self.text

    def __bool__(self) -> bool:
        return self.correct


_OK = Feedback(True, "correct")


def _array(value, name: str, owner: str, shape) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterTypeError(message(name, owner, "an array of numbers",
                                         type(value).__name__)) from None
    if arr.shape != tuple(shape):
        raise ParameterError(message(name, owner, f"an array of shape {tuple(shape)}",
                                     f"shape {arr.shape}"))
    if not np.all(np.isfinite(arr)):
        raise ParameterError(message(name, owner, "finite", "NaN or infinite values"))
    return arr


def _close(a, b, atol: float = 1e-9) -> bool:
    return bool(np.allclose(a, b, rtol=1e-9, atol=atol))


def _slip(slips, same, otherwise: str) -> Feedback:
    """The text of the first of `slips` ((answer, text) pairs) whose answer is `same` as the student's,
    else `otherwise`."""
    return Feedback(False, next((text for answer, text in slips if same(answer)), otherwise))


def check_energy_derivation(W, I, net: Network) -> Feedback:
    """Check the weights `W` (n, n) and biases `I` (n,) a student derived from the energy (3-15).

    They are compared with the package's own derivation (``rule="exact"``) term by term: the
    diagonal, neurons of the same left or right feature, neighbouring neurons, neurons that do not
    interact, and the bias.

    Parameters
    ----------
    W : (n, n) float array_like
        The student's weights, n the network's neurons.
    I : (n,) float array_like
        The student's biases.
    net : Network
        The network the energy is of.

    Returns
    -------
    feedback : Feedback
        ``"correct"``, or what is off and a hint; true when correct.

    Examples
    --------
    >>> net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1],
    ...                           similarity=[0.5, -0.5, -0.5, 0.5],
    ...                           pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.9])
    >>> print(check_energy_derivation(np.zeros((4, 4)), np.zeros(4), net))
    W for two neurons of the same left feature (i = j) is off; hint: expand (1 - sum_k y_ik)^2 and ...
    """
    owner = "check_energy_derivation"
    if not isinstance(net, Network):
        raise ParameterTypeError(message("net", owner, "a Network", type(net).__name__))
    n = net.n_neurons
    W = _array(W, "W", owner, (n, n))
    I = _array(I, "I", owner, (n,))
    W_ok, I_ok = hopfield_form(net, rule="exact")
    if _close(W, W_ok) and _close(I, I_ok):
        return _OK
    W_thesis, _ = hopfield_form(net, "thesis")
    if _close(W, W_thesis):
        return Feedback(False, "W is the thesis' (3-17) taken literally, with the neuron's own term of "
                               "(3-20) on the diagonal. That halves the quadratic part of (3-15) and adds a "
                               "self-connection. Hint: how many times does the double sum count the pair "
                               "(ik, jl), and what does y^2 = y do to a neuron's own square term?")
    if _close(W, W_thesis - np.diag(np.diag(W_thesis))):
        return Feedback(False, "W is half of what it should be. Hint: how many times does the double "
                               "sum in (3-15) count the pair (ik, jl)?")
    problems = []
    if not _close(W, W.T):
        problems.append("W is not symmetric: W_ikjl must equal W_jlik")
    eye = np.eye(n, dtype=bool)
    same_row = (net.rows[:, None] == net.rows[None, :]) & ~eye
    same_col = (net.cols[:, None] == net.cols[None, :]) & ~eye
    neighbour = np.zeros((n, n), dtype=bool)
    neighbour[net.pair_a, net.pair_b] = neighbour[net.pair_b, net.pair_a] = True
    rest = ~(eye | same_row | same_col | neighbour)
    terms = (
        (eye, "the diagonal W_ikik (self-connection) is off; hint: where do the square terms "
              "y_ik^2 go once y^2 = y?"),
        (same_row, "W for two neurons of the same left feature (i = j) is off; hint: expand "
                   "(1 - sum_k y_ik)^2 and collect its cross terms"),
        (same_col, "W for two neurons of the same right feature (k = l) is off; hint: expand "
                   "(1 - sum_i y_ik)^2 and collect its cross terms"),
        (neighbour, "W for neighbouring neurons is off; hint: how many times does the double sum "
                    "count each pair?"),
        (rest, "W for neurons that do not interact is off; hint: which term of (3-15) could "
               "connect them?"),
    )
    problems += [text for mask, text in terms if mask.any() and not _close(W[mask], W_ok[mask])]
    if not _close(I, I_ok):
        if _close(I, net.similarity):
            problems.append("I (the bias) is off by a constant; hint: expanding (1 - sum_k y_ik)^2 and "
                            "(1 - sum_i y_ik)^2 leaves terms linear in y_ik: where do they go?")
        elif _close(I, 1.0 + net.similarity):
            problems.append("I (the bias) is off by a constant; hint: you kept the linear term of one "
                            "squared constraint term, and (3-15) has two of them")
        else:
            problems.append("I (the bias) is off; hint: collect every term of (3-15) that is linear "
                            "in y_ik")
    text = "; ".join(problems)
    return Feedback(False, text if text.endswith("?") else text + ".")


def random_network(rng) -> Network:
    """A small random network (2 to 5 features a side, at least two candidates), for checking a
    derivation on more than one example; every value drawn in [-1, 1].

    >>> net = random_network(0)
    >>> 2 <= net.n_neurons <= 25, bool(np.all(np.abs(net.similarity) <= 1))
    (True, True)
    """
    gen = check_rng(rng, "rng", "random_network")
    n_left, n_right = (int(v) for v in gen.integers(2, 6, size=2))
    grid = gen.random((n_left, n_right)) < 0.7
    grid[0, 0] = grid[-1, -1] = True
    rows, cols = np.nonzero(grid)
    n = len(rows)
    a, b = np.triu_indices(n, 1)
    keep = (rows[a] != rows[b]) & (cols[a] != cols[b]) & (gen.random(len(a)) < 0.5)
    return Network.from_arrays(n_left, n_right, rows, cols, gen.uniform(-1, 1, n), a[keep], b[keep],
                               gen.uniform(-1, 1, int(keep.sum())), self_c=gen.uniform(-1, 1, n))


def _form_problems(W, I, net: Network, gen: np.random.Generator) -> list[str]:
    """What the derivation must give, asked of `W`, `I` with the energy (3-15) itself."""
    n = net.n_neurons
    problems = []
    if not _close(W, W.T):
        problems.append("W is not symmetric, so a flip's energy change is not -u dy")
    if not _close(np.diag(W), 0):
        problems.append("W has a non-zero diagonal: a neuron feeds back on itself")
    E = lambda y: energy(net, y)  # noqa: E731
    zero = np.zeros(n, dtype=np.uint8)
    const = E(zero)
    states = [np.eye(n, dtype=np.uint8)[a] for a in range(n)]
    states += [gen.integers(0, 2, n).astype(np.uint8) for _ in range(12)]
    if not all(abs(E(y) - (const - 0.5 * y @ W @ y - I @ y)) <= 1e-6 for y in states):
        problems.append("E(y) from (3-15) differs from E(0) - 1/2 y'Wy - I'y for some states y")
    for y in states[n:n + 4]:
        u = W @ y + I
        for a in range(n):
            flipped = y.copy()
            flipped[a] = 1 - y[a]
            if abs(E(flipped) - E(y) + u[a] * (int(flipped[a]) - int(y[a]))) > 1e-6:
                problems.append("a single flip changes E by something other than -u dy, with u = W y + I")
                return problems
    return problems


def check_hopfield_form(form, *, rng, n_networks: int = 3) -> Feedback:
    """Check a student's ``form(net) -> (W, I)``, the energy (3-15) of any network in Hopfield form.

    It is called on `n_networks` random networks drawn from `rng` (:func:`random_network`); on each,
    W must be symmetric with a zero diagonal, ``E(y) = E(0) - 1/2 y'Wy - I'y`` must hold for
    one-neuron and random states, and ``dE = -u dy`` (``u = W y + I``) for single flips, with E
    computed from (3-15) directly.  Then :func:`check_energy_derivation` names a term that is off.

    Parameters
    ----------
    form : callable
        ``form(net) -> (W, I)``, the student's function.
    rng : int or numpy.random.Generator
        Draws the networks.
    n_networks : int, default 3
        How many networks to check it on.

    Returns
    -------
    feedback : Feedback
        ``"correct"``, or what is off and a hint; true when correct.

    Examples
    --------
    >>> print(check_hopfield_form(lambda net: (np.zeros((net.n_neurons,) * 2), np.zeros(net.n_neurons)), rng=0))
    On a random network of 12 neurons: E(y) from (3-15) differs from E(0) - 1/2 y'Wy - I'y for some states y; ...
    """
    owner = "check_hopfield_form"
    if not callable(form):
        raise ParameterTypeError(message("form", owner, "a function of a Network returning (W, I)",
                                         type(form).__name__))
    gen = check_rng(rng, "rng", owner)
    count = check_number(n_networks, "n_networks", owner, low=1, integer=True)
    for _ in range(count):
        net = random_network(gen)
        n = net.n_neurons
        answer = form(net)
        if not isinstance(answer, tuple) or len(answer) != 2:
            raise ParameterTypeError(message("form", owner, "a function returning a pair (W, I)",
                                             type(answer).__name__))
        W, I = _array(answer[0], "W", owner, (n, n)), _array(answer[1], "I", owner, (n,))
        problems = _form_problems(W, I, net, gen)
        terms = check_energy_derivation(W, I, net)
        if problems or not terms:
            text = "; ".join(problems) + (". " if problems else "") + (terms.text if not terms else "")
            return Feedback(False, f"On a random network of {n} neurons: {text.strip()}")
    return _OK


def check_harris_response(R, image, sigma: float = 1.0, k: float = 0.04) -> Feedback:
    """Check a Harris response `R` (H, W) a student computed from `image` (2-1 ... 2-8).

    Compared with :func:`ismb_lab.images.features.harris_response` (Sobel gradients divided by 8, a
    Gaussian window of standard deviation `sigma`, Harris' constant `k`).

    Parameters
    ----------
    R : (H, W) float array_like
        The student's response.
    image : (H, W) float array_like
        The grey image.
    sigma : float, default 1.0
        Standard deviation of the Gaussian window.
    k : float, default 0.04
        Harris' constant.

    Returns
    -------
    feedback : Feedback
        ``"correct"``, or what is off and a hint; true when correct.

    Examples
    --------
    >>> img = np.zeros((20, 20)); img[10:, 10:] = 100.0
    >>> print(check_harris_response(harris_response(img, 1.5, 0.05), img, 1.5, 0.05))
    correct
    >>> print(check_harris_response(2 * harris_response(img, 1.5, 0.05), img, 1.5, 0.05))
    R is off; the largest difference is at (x, y) = (10, 10), where yours is 593170. Hint: compute M there by hand.
    """
    owner = "check_harris_response"
    expected = harris_response(image, sigma, k)
    R = _array(R, "R", owner, expected.shape)
    sigma = check_number(sigma, "sigma", owner, low=0, low_open=True)
    # the scale of R, so that the comparison does not depend on the image's contrast
    atol = 1e-9 * max(1.0, float(np.abs(expected).max()))
    if _close(R, expected, atol):
        return _OK
    Axx, Axy, Ayy = structure_tensor(image, sigma)
    det, trace = Axx * Ayy - Axy ** 2, Axx + Ayy
    Ix, Iy = image_gradients(image)
    slips = (
        (det, "The k tr(M)^2 term is missing: you have det(M) alone. Hint: read (2-6) again."),
        (det + k * trace ** 2, "The sign of the k tr(M)^2 term is flipped. Hint: an edge must give "
                               "a negative R."),
        # the starter's slip: the hint leads to the fix without stating it
        (det - k * trace, "det(M) is right; the k term is off. Hint: double the image's contrast: "
                          "det(M) grows 16 times. Does your k term grow as much?"),
        (Axx * Ayy + Axy ** 2 - k * trace ** 2,
         "det(M) is off. Hint: the determinant of [[a, b], [b, c]]."),
        (harris_from_tensor(Ix * Ix, Ix * Iy, Iy * Iy, k),
         "The structure tensor is not windowed: average Ix^2, Ix Iy and Iy^2 with a Gaussian "
         f"of sigma = {sigma:g} before forming det and trace."),
    )
    worst = np.unravel_index(np.argmax(np.abs(R - expected)), R.shape)
    return _slip(slips, lambda answer: _close(R, answer, atol),
                 f"R is off; the largest difference is at (x, y) = ({worst[1]}, {worst[0]}), "
                 f"where yours is {R[worst]:.6g}. Hint: compute M there by hand.")


def check_transfer(values, x, theta: float, lam: float) -> Feedback:
    """Check a student's transfer function (3-10, 3-13): its `values` at `x` (``M_ik`` for S, ``X``
    for C), with tolerance `theta` and steepness `lam`.

    >>> x = np.linspace(0, 40, 9)
    >>> print(check_transfer(transfer(x, 20, 2.0), x, 20, 2.0))
    correct
    >>> print(check_transfer((transfer(x, 20, 2.0) + 1) / 2, x, 20, 2.0))
    The output must lie in [-1, 1], yours lies in [0, 1]. Hint: which two operations map [0, 1] onto [-1, 1]?
    """
    owner = "check_transfer"
    theta = check_number(theta, "theta", owner)
    lam = check_number(lam, "lam", owner, low=0, low_open=True)
    x = np.asarray(x, dtype=float)
    values = _array(values, "values", owner, x.shape)
    expected = transfer(x, theta, lam)
    if _close(values, expected, 1e-7):
        return _OK
    slips = (
        (-expected, "The sign is flipped: small x (good agreement) must give values near +1. "
                    "Hint: which sign must the exponent have for that?"),
        ((expected + 1) / 2, "The output must lie in [-1, 1], yours lies in [0, 1]. Hint: which two "
                             "operations map [0, 1] onto [-1, 1]?"),
        (expected + 1, "The output must lie in [-1, 1], yours lies in [0, 2]. Hint: one operation "
                       "is missing."),
        (transfer(x, 0.0, lam), "theta is not used: the output must cross 0 at x = theta."),
        (transfer(x, theta, 1.0), "lambda is not used: it sets how steeply the output switches "
                                  "around theta."),
        (transfer(x, theta, 2.0 * lam), "lambda is doubled: the exponent is lam (x - theta)."),
        (transfer(x, theta, 0.5 * lam), "lambda is halved: the exponent is lam (x - theta)."),
    )
    worst = int(np.argmax(np.abs(values - expected).ravel()))
    return _slip(slips, lambda answer: _close(values, answer, 1e-7),
                 f"The values are off; the largest difference is at x = {x.ravel()[worst]:g}, "
                 f"where yours is {values.ravel()[worst]:.6g}. Hint: evaluate (3-10) there by hand.")


def check_disparity(values, left_xy, right_xy) -> Feedback:
    """Check a student's "disparity" column of the thesis' tables for the matched points
    `left_xy`, `right_xy` ((m, 2), x then y); compared to 0.01.

    Parameters
    ----------
    values : (m,) float array_like
        The student's disparities.
    left_xy, right_xy : (m, 2) float array_like
        The matched points.

    Returns
    -------
    feedback : Feedback
        ``"correct"``, or what is off and a hint; true when correct.

    Examples
    --------
    >>> left, right = [[99, 99], [120, 155]], [[88, 100], [98, 158]]   # Tables 5.1 and 5.4
    >>> print(check_disparity([11.05, 22.20], left, right))
    correct
    >>> print(check_disparity([11, 22], left, right))
    That is the horizontal disparity x_left - x_right alone. Hint: the tables' column is a distance between the two points; which components does it use?
    """
    owner = "check_disparity"
    left = check_points(left_xy, "left_xy", owner)
    right = check_points(right_xy, "right_xy", owner)
    if left.shape != right.shape:
        raise ParameterError(message("right_xy", owner, f"an array of shape {left.shape}, like left_xy",
                                     f"shape {right.shape}"))
    values = _array(values, "values", owner, (len(left),))
    expected = euclidean_disparity(left, right)
    near = lambda a, b: bool(np.all(np.abs(a - b) <= 0.01 + 1e-9))  # noqa: E731
    if near(values, expected):
        return _OK
    dx, dy = horizontal_disparity(left, right), vertical_disparity(left, right)
    slips = (
        (np.abs(dx), "That is the horizontal disparity x_left - x_right alone. Hint: the tables' "
                     "column is a distance between the two points; which components does it use?"),
        (expected ** 2, "The square root is missing. Hint: your values are in px^2."),
        (np.abs(dx) + np.abs(dy), "That is |dx| + |dy|, the distance along the grid. Hint: the tables "
                                  "use the straight-line distance."),
        (np.abs(dy), "That is the vertical disparity alone. Hint: the tables' column is a distance "
                     "between the two points; which components does it use?"),
    )
    worst = int(np.argmax(np.abs(values - expected)))
    return _slip(slips, lambda answer: near(values, answer), f"Row {worst + 1} is off (yours: "
                 f"{values[worst]:g}). Hint: recompute it from its x_left, y_left, x_right and y_right.")


def check_error_kinds(wrong, extra, pairs, targets) -> Feedback:
    """Check a student's count of the two kinds of error of matched `pairs` against `targets`.

    A *wrong partner* is a match of a left feature that has a target, to another right feature; an
    *extra* is a match of a left feature that has no target (:func:`ismb_lab.tuning.evaluation.score`).

    Parameters
    ----------
    wrong, extra : int
        The student's counts of wrong partners and extras.
    pairs : (m, 2) int array_like
        Matched ``(i, k)`` feature pairs.
    targets : (n, 2) int array_like
        Target pairs.

    Returns
    -------
    feedback : Feedback
        ``"correct"``, or what is off and a hint; true when correct.

    Examples
    --------
    >>> pairs, targets = [[0, 0], [0, 1], [2, 2], [3, 0]], [[0, 0], [1, 1], [2, 3]]
    >>> print(check_error_kinds(2, 1, pairs, targets))
    correct
    >>> print(check_error_kinds(3, 0, pairs, targets))
    You counted every error as a wrong partner. Hint: an extra is a match of a left corner with no true partner at all; do all your errors have one?
    """
    owner = "check_error_kinds"
    wrong = check_number(wrong, "wrong", owner, low=0, integer=True)
    extra = check_number(extra, "extra", owner, low=0, integer=True)
    s = score(pairs, targets)
    if (wrong, extra) == (s.wrong_partner, s.extra):
        return _OK
    matches = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    true = np.asarray(targets, dtype=np.int64).reshape(-1, 2)
    wanted = set(map(tuple, true.tolist()))
    errors = [(i, k) for i, k in matches.tolist() if (i, k) not in wanted]
    by_right = sum(k not in set(true[:, 1].tolist()) for _, k in errors)
    if wrong + extra != s.errors:
        return Feedback(False, f"Your two counts add up to {wrong + extra}, but {s.errors} of the "
                               f"{len(matches)} matches are errors (not true matches). Hint: every error "
                               "is of exactly one kind.")
    slips = (
        ((s.errors, 0), "You counted every error as a wrong partner. Hint: an extra is a match of a "
                        "left corner with no true partner at all; do all your errors have one?"),
        ((s.extra, s.wrong_partner), "The two counts are swapped. Hint: which kind of error has a true "
                                     "partner for its left corner?"),
        ((len(errors) - by_right, by_right), "You told the kinds apart by the right corner of each error. "
                                             "Hint: the definitions look at the left corner i of a match (i, k)."),
    )
    return _slip(slips, lambda answer: (wrong, extra) == answer,
                 f"The split is off (yours: {wrong} wrong partners and {extra} extras). Hint: for each "
                 "error, ask whether its left corner has a true partner.")


def check_depth_range(near, far, disparity, *, focal_px: float, baseline_m: float, error_px: float) -> Feedback:
    """Check a student's depth range ``(near, far)`` in metres of a `disparity` (px) with an error
    bar of `error_px`, without naming the formula.

    Parameters
    ----------
    near, far : float
        The student's range, m.
    disparity : float
        The disparity, px.
    focal_px : float
        Focal length, px.
    baseline_m : float
        Baseline, m.
    error_px : float
        The disparity's error bar, px.

    Returns
    -------
    feedback : Feedback
        ``"correct"``, or what is off and a hint; true when correct.

    Examples
    --------
    >>> print(check_depth_range(0.9, 1.2, 30.0, focal_px=300, baseline_m=0.1, error_px=0.5))
    Your range [0.900, 1.200] m is off; the depth itself is 1.000 m. Hint: work out Z at each end of the disparity's error bar.
    """
    owner = "check_depth_range"
    near = check_number(near, "near", owner)
    far = check_number(far, "far", owner) if not (isinstance(far, float) and far == np.inf) else far
    d = check_number(disparity, "disparity", owner, low=0, low_open=True)
    want = metric_depth(d, focal_px, baseline_m, error_px)
    if _close((near, far), (want.near, want.far), 1e-12):
        return _OK
    if _close((far, near), (want.near, want.far), 1e-12):
        return Feedback(False, "Your near end is farther from the cameras than your far end. Hint: Z = fB/d; "
                               "does a nearer point have the larger or the smaller disparity?")
    if _close((near, far), (want.z, want.z), 1e-8):
        return Feedback(False, "Both ends are the depth itself. Hint: the range comes from the disparity's "
                               "error bar.")
    return Feedback(False, f"Your range [{near:.3f}, {far:.3f}] m is off; the depth itself is {want.z:.3f} m. "
                           "Hint: work out Z at each end of the disparity's error bar.")


def check_fitness(value, pairs, targets, unknown=()) -> Feedback:
    """Check a student's GA fitness (4-1) of matched `pairs` against `targets`; matches of the left
    features in `unknown` do not count.

    Parameters
    ----------
    value : float
        The student's fitness.
    pairs : (m, 2) int array_like
        Matched ``(i, k)`` feature pairs.
    targets : (n, 2) int array_like
        Target pairs.
    unknown : int array_like, optional
        Left features whose matches do not count.

    Returns
    -------
    feedback : Feedback
        ``"correct"``, or what is off and a hint; true when correct.

    Examples
    --------
    >>> pairs, targets = [[0, 0], [1, 2], [3, 3]], [[0, 0], [1, 1], [2, 2]]
    >>> print(check_fitness(-1, pairs, targets))
    correct
    >>> print(check_fitness(1, pairs, targets))
    n_c is right, but the errors are not in it. Hint: what does (4-1) do with n_e?
    """
    value = check_number(value, "value", "check_fitness")
    s = score(pairs, targets, unknown)
    if value == s.fitness:
        return _OK
    slips = (
        (s.correct, "n_c is right, but the errors are not in it. Hint: what does (4-1) do with n_e?"),
        (s.correct - s.wrong_partner, "n_e misses some errors: you counted the matches with a wrong "
                                      "partner. Hint: what about a match of a left corner that has no target?"),
        (s.correct - s.extra, "n_e misses some errors: you counted the extra matches. Hint: what about a "
                              "match whose left corner has a target, but another partner?"),
        (s.correct + s.errors, "The sign of n_e is flipped. Hint: should an error raise the fitness?"),
        (s.correct - (s.targets - s.correct), "n_e counts wrong matches, not missed targets. Hint: "
                                              "what does a missed target do to n_c?"),
        (s.recall, "That is a rate (n_c / T). Hint: the fitness (4-1) is a count."),
    )
    return _slip(slips, lambda answer: value == answer, f"The fitness is off (yours: {value:g}). Hint: "
                 "count n_c (matches that are targets) and n_e (all the other matches) again.")
