"""Automatic checks for the notebook exercises.

Each check compares a student's answer with the package's own computation and
returns a :class:`Feedback`: ``"correct"``, or a sentence that names the term
that is off.  The checks recognise the usual slips (a halved quadratic part, a
missing constant, a flipped sign) and say which one it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_number, check_points, message
from .coords import euclidean_disparity, horizontal_disparity, vertical_disparity
from .evaluation import score
from .features import harris_from_tensor, harris_response, image_gradients, structure_tensor
from .hopfield import Network, hopfield_form
from .similarity import transfer

__all__ = ["check_disparity", "check_energy_derivation", "check_fitness", "check_harris_response",
           "check_transfer", "Feedback"]


@dataclass(frozen=True)
class Feedback:
    """The verdict of one exercise check.

    Attributes
    ----------
    correct : bool
    text : str
        ``"correct"``, or what is off and how to fix it.

    Examples
    --------
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


def check_energy_derivation(W, I, net: Network) -> Feedback:
    """Check a Hopfield form ``E = const - 1/2 y'Wy - I'y`` of the energy (3-15).

    The reference is :func:`ismb_lab.hopfield.hopfield_form` with ``rule="exact"``:
    ``W = 2C`` for neighbouring neurons, ``-2`` for two neurons that share a left
    (``i = j``) or a right (``k = l``) feature, ``0`` on the diagonal and for
    neurons that do not interact, and ``I = 2 + S``.

    Parameters
    ----------
    W : (n, n) array_like
        The student's weights over the candidate neurons of `net`.
    I : (n,) array_like
        The student's biases.
    net : Network

    Returns
    -------
    feedback : Feedback
        ``"correct"`` or the terms that are off.

    Examples
    --------
    >>> net = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1],
    ...                           similarity=[0.5, -0.5, -0.5, 0.5],
    ...                           pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.9])
    >>> W, I = hopfield_form(net)
    >>> print(check_energy_derivation(W, I, net))
    correct
    >>> print(check_energy_derivation(W, I - 2, net))
    I (the bias) is off: I_ik = 2 + S_ik; the 2 comes from expanding (1 - sum_k y_ik)^2 and (1 - sum_i y_ik)^2.
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
        return Feedback(False, "W is the thesis' (3-17) taken literally: W = C - delta_ij - delta_kl with "
                               "the self-weight C_ikik - 2 on the diagonal. That halves the quadratic part "
                               "of (3-15): the double sum counts every pair twice, so W = 2C and -2, and a "
                               "neuron has no connection to itself (W_ikik = 0).")
    if _close(W, W_thesis - np.diag(np.diag(W_thesis))):
        return Feedback(False, "W is half of what it should be: the double sum in (3-15) counts every "
                               "pair (ik, jl) twice, so W = 2C for neighbours and -2 for a shared feature.")
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
        (eye, "the diagonal W_ikik (self-connection) is off: it must be 0, since y^2 = y "
              "moves the square terms into I"),
        (same_row, "W for two neurons of the same left feature (i = j) is off: it must be -2, "
                   "from the cross terms of (1 - sum_k y_ik)^2"),
        (same_col, "W for two neurons of the same right feature (k = l) is off: it must be -2, "
                   "from the cross terms of (1 - sum_i y_ik)^2"),
        (neighbour, "W for neighbouring neurons is off: it must be 2 C_ikjl (the double sum "
                    "counts every pair twice)"),
        (rest, "W for neurons that do not interact is off: it must be 0"),
    )
    problems += [text for mask, text in terms if mask.any() and not _close(W[mask], W_ok[mask])]
    if not _close(I, I_ok):
        if _close(I, net.similarity):
            problems.append("I (the bias) is off: I_ik = 2 + S_ik; the 2 comes from expanding "
                            "(1 - sum_k y_ik)^2 and (1 - sum_i y_ik)^2")
        elif _close(I, 1.0 + net.similarity):
            problems.append("I (the bias) is off: I_ik = 2 + S_ik, one 1 from each of the two "
                            "squared constraint terms, not just one of them")
        else:
            problems.append("I (the bias) is off: I_ik = 2 + S_ik")
    return Feedback(False, "; ".join(problems) + ".")


def check_harris_response(R, image, sigma: float = 1.0, k: float = 0.04) -> Feedback:
    """Check a Harris response ``R = det(M) - k tr(M)^2`` (2-1 ... 2-8).

    The reference is :func:`ismb_lab.features.harris_response` (Sobel gradients
    divided by 8, a Gaussian window of standard deviation `sigma`).

    Parameters
    ----------
    R : (H, W) array_like
        The student's response.
    image : (H, W) array_like
        The grey image it was computed from.
    sigma, k : float
        The Gaussian window and Harris' constant used.

    Returns
    -------
    feedback : Feedback

    Examples
    --------
    >>> img = np.zeros((20, 20)); img[10:, 10:] = 100.0
    >>> print(check_harris_response(harris_response(img, 1.5, 0.05), img, 1.5, 0.05))
    correct
    >>> Axx, Axy, Ayy = structure_tensor(img, 1.5)
    >>> print(check_harris_response(Axx * Ayy - Axy ** 2, img, 1.5, 0.05))
    The k tr(M)^2 term is missing: R = det(M) - k tr(M)^2, not det(M) alone.
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
        (det, "The k tr(M)^2 term is missing: R = det(M) - k tr(M)^2, not det(M) alone."),
        (det + k * trace ** 2, "The sign of the k tr(M)^2 term is flipped: R = det(M) - k tr(M)^2."),
        (det - k * trace, "tr(M) must be squared: R = det(M) - k tr(M)^2."),
        (Axx * Ayy + Axy ** 2 - k * trace ** 2,
         "det(M) is off: det(M) = Axx Ayy - Axy^2 (a minus before Axy^2)."),
        (harris_from_tensor(Ix * Ix, Ix * Iy, Iy * Iy, k),
         "The structure tensor is not windowed: average Ix^2, Ix Iy and Iy^2 with a Gaussian "
         f"of sigma = {sigma:g} before forming det and trace."),
    )
    for candidate, text in slips:
        if _close(R, candidate, atol):
            return Feedback(False, text)
    worst = np.unravel_index(np.argmax(np.abs(R - expected)), R.shape)
    return Feedback(False, f"R is off; the largest difference is at (x, y) = ({worst[1]}, {worst[0]}): "
                           f"{R[worst]:.6g} instead of {expected[worst]:.6g}.")


def check_transfer(values, x, theta: float, lam: float) -> Feedback:
    """Check a transfer function ``2 / (1 + exp(lam (x - theta))) - 1`` (3-10, 3-13).

    Parameters
    ----------
    values : array_like
        The student's outputs at `x`.
    x : array_like
        The inputs (``M_ik`` for S, ``X`` for C).
    theta, lam : float
        The tolerance and the steepness used.

    Returns
    -------
    feedback : Feedback

    Examples
    --------
    >>> x = np.linspace(0, 40, 9)
    >>> print(check_transfer(2 / (1 + np.exp(2.0 * (x - 20))) - 1, x, 20, 2.0))
    correct
    >>> print(check_transfer(1 / (1 + np.exp(2.0 * (x - 20))), x, 20, 2.0))
    The output must lie in [-1, 1]: double the logistic and subtract 1, 2 / (1 + exp(lam (x - theta))) - 1.
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
        (-expected, "The sign is flipped: small x (good agreement) must give values near +1, "
                    "so the exponent is +lam (x - theta)."),
        ((expected + 1) / 2, "The output must lie in [-1, 1]: double the logistic and subtract 1, "
                             "2 / (1 + exp(lam (x - theta))) - 1."),
        (expected + 1, "The '- 1' is missing: the output must lie in [-1, 1]."),
        (transfer(x, 0.0, lam), "theta is not used: the output must cross 0 at x = theta."),
        (transfer(x, theta, 1.0), "lambda is not used: it sets how steeply the output switches "
                                  "around theta."),
        (transfer(x, theta, 2.0 * lam), "lambda is doubled: the exponent is lam (x - theta)."),
        (transfer(x, theta, 0.5 * lam), "lambda is halved: the exponent is lam (x - theta)."),
    )
    for candidate, text in slips:
        if _close(values, candidate, 1e-7):
            return Feedback(False, text)
    worst = int(np.argmax(np.abs(values - expected).ravel()))
    return Feedback(False, f"The values are off; the largest difference is at x = {x.ravel()[worst]:g}: "
                           f"{values.ravel()[worst]:.6g} instead of {expected.ravel()[worst]:.6g}.")


def check_disparity(values, left_xy, right_xy) -> Feedback:
    """Check the "disparity" column of the thesis' tables: ``||p - q||`` of matched points.

    Parameters
    ----------
    values : (m,) array_like
        The student's disparities, rounded as they like (compared to 0.01).
    left_xy, right_xy : (m, 2) array_like
        The matched points ``(x, y)``; a table's ``x_left, y_left`` and ``x_right, y_right``.

    Returns
    -------
    feedback : Feedback

    Examples
    --------
    >>> left, right = [[99, 99], [120, 155]], [[88, 100], [98, 158]]   # Tables 5.1 and 5.4
    >>> print(check_disparity([11.05, 22.20], left, right))
    correct
    >>> print(check_disparity([11, 22], left, right))
    That is the horizontal disparity x_left - x_right alone; the tables' column is the distance sqrt(dx^2 + dy^2).
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
        (np.abs(dx), "That is the horizontal disparity x_left - x_right alone; the tables' column "
                     "is the distance sqrt(dx^2 + dy^2)."),
        (expected ** 2, "The square root is missing: disparity = sqrt(dx^2 + dy^2)."),
        (np.abs(dx) + np.abs(dy), "That is |dx| + |dy|; the tables' column is sqrt(dx^2 + dy^2)."),
        (np.abs(dy), "That is the vertical disparity alone; the tables' column is sqrt(dx^2 + dy^2)."),
    )
    for candidate, text in slips:
        if near(values, candidate):
            return Feedback(False, text)
    worst = int(np.argmax(np.abs(values - expected)))
    return Feedback(False, f"Row {worst + 1} is off: {values[worst]:g} instead of {expected[worst]:.2f} "
                           f"= sqrt({dx[worst]:g}^2 + {dy[worst]:g}^2).")


def check_fitness(value, pairs, targets, unknown=()) -> Feedback:
    """Check a GA fitness (4-1) ``f = n_c - n_e`` of matched pairs against target pairs.

    ``n_c`` counts matches that are targets, ``n_e`` every other match (wrong
    partner or extra), except matches of left features in `unknown`; see
    :func:`ismb_lab.evaluation.score`.

    Parameters
    ----------
    value : float
        The student's fitness.
    pairs, targets : (m, 2) int array_like
        Matched and target ``(i, k)`` feature pairs.
    unknown : int array_like
        Left features whose truth is unknown.

    Returns
    -------
    feedback : Feedback

    Examples
    --------
    >>> pairs, targets = [[0, 0], [1, 2], [3, 3]], [[0, 0], [1, 1], [2, 2]]
    >>> print(check_fitness(-1, pairs, targets))
    correct
    >>> print(check_fitness(1, pairs, targets))
    n_c is right, but n_e = 2 is not subtracted: f = n_c - n_e.
    """
    value = check_number(value, "value", "check_fitness")
    s = score(pairs, targets, unknown)
    if value == s.fitness:
        return _OK
    slips = (
        (s.correct, f"n_c is right, but n_e = {s.errors} is not subtracted: f = n_c - n_e."),
        (s.correct - s.wrong_partner, f"n_e must count every match that is not a target: "
                                      f"{s.wrong_partner} with a wrong partner and {s.extra} extra."),
        (s.correct - s.extra, f"n_e must count every match that is not a target: "
                              f"{s.extra} extra and {s.wrong_partner} with a wrong partner."),
        (s.correct + s.errors, "The sign of n_e is flipped: errors lower the fitness, f = n_c - n_e."),
        (s.correct - (s.targets - s.correct), "n_e counts wrong matches, not missed targets: "
                                              "a missed target only fails to add to n_c."),
        (s.recall, "That is n_c / T (the accurate rate); the fitness is the count n_c - n_e."),
    )
    for candidate, text in slips:
        if value == candidate:
            return Feedback(False, text)
    return Feedback(False, f"The fitness is off: {value:g} instead of {s.fitness}; count n_c (matches "
                           f"that are targets) and n_e (all the other matches).")
