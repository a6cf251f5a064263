import re

import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.teaching.exercises import (check_depth_range, check_disparity, check_energy_derivation, check_error_kinds,
                                check_fitness, check_harris_response, check_hopfield_form, check_transfer,
                                random_network)
from ismb_lab.images.features import harris_response, image_gradients, structure_tensor
from ismb_lab.network.hopfield import Network, hopfield_form
from ismb_lab.network.similarity import transfer


@pytest.fixture
def net():
    """Two left and three right features: shared rows, shared columns, neighbours and strangers."""
    rows = [0, 0, 0, 1, 1, 1]
    cols = [0, 1, 2, 0, 1, 2]
    similarity = [0.5, -0.2, 0.1, -0.4, 0.8, 0.3]
    # (0,0)-(1,1), (0,1)-(1,0), (0,1)-(1,2) interact; (0,0)-(1,2) etc. do not
    return Network.from_arrays(2, 3, rows, cols, similarity, pair_a=[0, 1, 1], pair_b=[4, 3, 5],
                               pair_c=[0.7, -0.3, 0.25], self_c=[0.9] * 6)


def test_energy_correct(net):
    W, I = hopfield_form(net)
    feedback = check_energy_derivation(W, I, net)
    assert feedback.correct and str(feedback) == "correct"


def test_energy_correct_agrees_with_brute_force(net):
    """A W, I derived independently from (3-15) by finite differences passes."""
    from ismb_lab.network.hopfield import energy

    n = net.n_neurons
    E = lambda y: energy(net, np.array(y, dtype=np.uint8))  # noqa: E731
    zero = np.zeros(n, dtype=int)
    I = np.array([E(zero) - E(np.eye(n, dtype=int)[a]) for a in range(n)])
    W = np.zeros((n, n))
    for a in range(n):
        for b in range(n):
            if a != b:
                y = zero.copy(); y[[a, b]] = 1
                W[a, b] = -(E(y) - E(zero)) - I[a] - I[b]
    assert check_energy_derivation(W, I, net).correct


def test_energy_thesis_literal(net):
    W, I = hopfield_form(net, "thesis")
    feedback = check_energy_derivation(W, I, net)
    assert not feedback.correct and "(3-17)" in feedback.text and "halves" in feedback.text


def test_energy_halved(net):
    W, I = hopfield_form(net)
    assert "half of what it should be" in check_energy_derivation(W / 2, I, net).text


@pytest.mark.parametrize("term, expected", [
    ("diagonal", "the diagonal W_ikik"),
    ("row", "same left feature (i = j)"),
    ("col", "same right feature (k = l)"),
    ("neighbour", "neighbouring neurons is off"),
    ("rest", "do not interact is off"),
])
def test_energy_names_the_wrong_term(net, term, expected):
    W, I = hopfield_form(net)
    W = W.copy()
    a, b = {"diagonal": (2, 2), "row": (0, 2), "col": (0, 3), "neighbour": (0, 4), "rest": (0, 5)}[term]
    W[a, b] += 0.5
    if a != b:
        W[b, a] += 0.5
    feedback = check_energy_derivation(W, I, net)
    assert not feedback.correct
    assert expected in feedback.text
    # only that term is named
    others = {"the diagonal W_ikik", "same left feature (i = j)", "same right feature (k = l)",
              "neighbouring neurons is off", "do not interact is off", "bias"} - {expected}
    assert not any(o in feedback.text for o in others)


def test_energy_asymmetric(net):
    W, I = hopfield_form(net)
    W = W.copy(); W[0, 4] += 1.0
    assert "not symmetric" in check_energy_derivation(W, I, net).text


@pytest.mark.parametrize("shift, expected", [(-2.0, "leaves terms linear in y_ik"),
                                             (-1.0, "(3-15) has two of them"),
                                             (0.3, "I (the bias) is off; hint: collect every term")])
def test_energy_bias(net, shift, expected):
    W, I = hopfield_form(net)
    feedback = check_energy_derivation(W, I + shift, net)
    assert not feedback.correct and expected in feedback.text and "W " not in feedback.text


def test_energy_bad_input(net):
    W, I = hopfield_form(net)
    with pytest.raises(ParameterError, match="'W' parameter of check_energy_derivation.*shape"):
        check_energy_derivation(W[:2], I, net)
    with pytest.raises(ParameterError, match="'I'.*finite"):
        check_energy_derivation(W, np.full(6, np.nan), net)
    with pytest.raises(ParameterTypeError, match="'net'.*a Network"):
        check_energy_derivation(W, I, "net")


@pytest.fixture
def image():
    rng = np.random.default_rng(3)
    img = np.zeros((32, 40))
    img[8:24, 10:30] = 180.0
    return img + rng.normal(0, 2, img.shape)


def test_harris_correct(image):
    assert check_harris_response(harris_response(image, 1.5, 0.05), image, 1.5, 0.05).text == "correct"


def test_harris_slips(image):
    sigma, k = 1.5, 0.05
    Axx, Axy, Ayy = structure_tensor(image, sigma)
    det, tr = Axx * Ayy - Axy ** 2, Axx + Ayy
    Ix, Iy = image_gradients(image)
    cases = [
        (det, "k tr(M)^2 term is missing"),
        (det + k * tr ** 2, "sign of the k tr(M)^2 term is flipped"),
        (det - k * tr, "the k term is off"),
        (Axx * Ayy + Axy ** 2 - k * tr ** 2, "det(M) is off"),
        (Ix * Ix * Iy * Iy - (Ix * Iy) ** 2 - k * (Ix * Ix + Iy * Iy) ** 2, "not windowed"),
    ]
    for R, expected in cases:
        feedback = check_harris_response(R, image, sigma, k)
        assert not feedback.correct and expected in feedback.text, expected


def test_harris_hint_on_the_starters_slip_does_not_state_the_fix(image):
    """01's starter leaves tr(M) unsquared: the check says which term is off, not how to write it."""
    Axx, Axy, Ayy = structure_tensor(image, 1.5)
    text = check_harris_response(Axx * Ayy - Axy ** 2 - 0.05 * (Axx + Ayy), image, 1.5, 0.05).text
    assert "k term is off" in text
    assert not re.search(r"squar|\^ ?2|\*\* ?2|tr\(M\)", text), text


def test_harris_other_error_names_the_place(image):
    R = harris_response(image, 1.0, 0.04).copy()
    R[5, 7] += 1.0
    text = check_harris_response(R, image).text
    assert "(x, y) = (7, 5)" in text


def test_harris_bad_shape(image):
    with pytest.raises(ParameterError, match="'R' parameter of check_harris_response"):
        check_harris_response(np.zeros((3, 3)), image)


def test_transfer_correct_and_slips():
    x = np.linspace(0, 50, 11)
    theta, lam = 20.0, 0.7
    good = 2 / (1 + np.exp(lam * (x - theta))) - 1
    assert check_transfer(good, x, theta, lam).correct
    cases = [
        (-good, "sign is flipped"),
        (1 / (1 + np.exp(lam * (x - theta))), "yours lies in [0, 1]"),
        (good + 1, "yours lies in [0, 2]"),
        (transfer(x, 0.0, lam), "theta is not used"),
        (transfer(x, theta, 1.0), "lambda is not used"),
        (transfer(x, theta, 2 * lam), "lambda is doubled"),
        (transfer(x, theta, lam / 2), "lambda is halved"),
    ]
    for values, expected in cases:
        feedback = check_transfer(values, x, theta, lam)
        assert not feedback.correct and expected in feedback.text, expected
    other = good.copy(); other[3] += 0.1
    text = check_transfer(other, x, theta, lam).text
    assert "at x = 15" in text and f"{good[3]:.6g}" not in text      # a hint, not the answer


def test_transfer_bad_input():
    with pytest.raises(ParameterError, match="'lam' parameter of check_transfer"):
        check_transfer([0.0], [0.0], 1.0, 0.0)
    with pytest.raises(ParameterError, match="'values'.*shape"):
        check_transfer([0.0, 1.0], [0.0], 1.0, 1.0)


# Table 5.4's first three rows as (x, y)
TABLE_LEFT = [[111, 70], [113, 128], [120, 155]]
TABLE_RIGHT = [[92, 73], [95, 131], [98, 158]]


def test_disparity_correct_as_printed():
    assert check_disparity([19.24, 18.25, 22.20], TABLE_LEFT, TABLE_RIGHT).correct


def test_disparity_slips():
    dx = np.array([19.0, 18.0, 22.0]); dy = np.array([3.0, 3.0, 3.0])
    cases = [
        (dx, "horizontal disparity x_left - x_right alone"),
        (dx ** 2 + dy ** 2, "square root is missing"),
        (dx + dy, "|dx| + |dy|"),
        (dy, "vertical disparity alone"),
    ]
    for values, expected in cases:
        feedback = check_disparity(values, TABLE_LEFT, TABLE_RIGHT)
        assert not feedback.correct and expected in feedback.text, expected


def test_disparity_table_5_5_misprint_is_caught():
    """Table 5.5 prints 9.85 for the coordinates Table 5.4 gives 22.20."""
    text = check_disparity([19.24, 18.25, 9.85], TABLE_LEFT, TABLE_RIGHT).text
    assert text.startswith("Row 3 is off (yours: 9.85)") and "22.2" not in text   # a hint, not the answer


def test_disparity_bad_input():
    with pytest.raises(ParameterError, match="'right_xy' parameter of check_disparity"):
        check_disparity([1.0], [[0, 0]], [[0, 0], [1, 1]])
    with pytest.raises(ParameterError, match="'values'.*shape"):
        check_disparity([1.0, 2.0], [[0, 0]], [[1, 1]])


@pytest.fixture
def matches():
    """2 correct, 1 wrong partner, 2 extra, 1 unknown; 4 targets."""
    pairs = [[0, 0], [1, 1], [2, 5], [4, 4], [5, 6], [7, 7]]
    targets = [[0, 0], [1, 1], [2, 2], [3, 3]]
    return pairs, targets, [7]


def test_fitness_correct(matches):
    pairs, targets, unknown = matches
    assert check_fitness(2 - 3, pairs, targets, unknown).text == "correct"
    # without the unknown feature, its match counts as an extra error
    assert check_fitness(2 - 4, pairs, targets).correct


def test_fitness_slips(matches):
    pairs, targets, unknown = matches
    cases = [
        (2, "the errors are not in it"),
        (2 - 1, "you counted the matches with a wrong partner"),
        (2 - 2, "you counted the extra matches"),
        (2 + 3, "sign of n_e is flipped"),
        (0.5, "n_c / T"),
        (7, "The fitness is off (yours: 7)"),
    ]
    for value, expected in cases:
        feedback = check_fitness(value, pairs, targets, unknown)
        assert not feedback.correct and expected in feedback.text, (value, expected)
        assert not re.search(r"(?<!\d)-1(?![\d)])", feedback.text)   # a hint, never the answer (-1)


def test_fitness_missed_targets_are_not_errors():
    pairs, targets = [[0, 0], [1, 1], [2, 2]], [[0, 0], [1, 1], [2, 2], [3, 3], [4, 4], [5, 5]]
    assert "not missed targets" in check_fitness(0, pairs, targets).text


def test_fitness_bad_input():
    with pytest.raises(ParameterTypeError, match="'value' parameter of check_fitness"):
        check_fitness("3", [[0, 0]], [[0, 0]])


#: The answers the exercises ask for, as the thesis writes them and as code would (#28: the
#: checks' docstrings, which ``check_transfer?`` shows a student, once stated them).
ANSWERS = {
    "check_transfer": ("2/(1+exp(", "2/(1+np.exp("),
    "check_harris_response": ("det(M)-ktr(M)^2", "det(M)-k*tr(M)**2", "Axx*Ayy-Axy**2-"),
    "check_energy_derivation": ("W=2C", "I=2+S", "2*C-2*"),
    "check_disparity": ("||p-q||", "hypot(", "sqrt(dx"),
    "check_fitness": ("n_c-n_e", "f=n_c-", "n_c-(len("),
    "check_hopfield_form": ("W=2C", "I=2+S", "2*C-2*", "hopfield_form(net"),
    "check_error_kinds": ("len(errors)-", "inpartnered"),
    "check_depth_range": ("fB/(d+q)", "fB/(d-q)", "/(d+q)", "/(d-q)"),
}


@pytest.mark.parametrize("name", sorted(ANSWERS))
def test_a_checks_docstring_does_not_state_the_answer(name):
    import inspect

    from ismb_lab.teaching import exercises

    doc = re.sub(r"\s+", "", inspect.getdoc(getattr(exercises, name)))
    assert [a for a in ANSWERS[name] if a in doc] == [], f"{name}'s docstring states the answer"


# --- the Hopfield form of any network (02, exercise 1) ------------------------------------------

def _exact_form(net):
    """W and I built from the energy (3-15) alone, by finite differences (no library derivation)."""
    from ismb_lab.network.hopfield import energy

    n = net.n_neurons
    E = lambda y: energy(net, np.array(y, dtype=np.uint8))  # noqa: E731
    zero = np.zeros(n, dtype=int)
    I = np.array([E(zero) - E(np.eye(n, dtype=int)[a]) for a in range(n)])
    W = np.zeros((n, n))
    for a in range(n):
        for b in range(n):
            if a != b:
                y = zero.copy(); y[[a, b]] = 1
                W[a, b] = -(E(y) - E(zero)) - I[a] - I[b]
    return W, I


def test_a_form_derived_from_the_energy_passes_on_random_networks():
    assert check_hopfield_form(_exact_form, rng=3, n_networks=4).correct


@pytest.mark.parametrize("slip, expected", [
    (lambda net: hopfield_form(net, "thesis"), "non-zero diagonal"),
    (lambda net: (hopfield_form(net)[0] / 2, hopfield_form(net)[1]), "differs from E(0)"),
    (lambda net: (np.triu(hopfield_form(net)[0]) * 2, hopfield_form(net)[1]), "not symmetric"),
    (lambda net: (hopfield_form(net)[0], net.similarity), "differs from E(0)"),
])
def test_a_wrong_form_fails_and_says_which_property(slip, expected):
    feedback = check_hopfield_form(slip, rng=3)
    assert not feedback.correct and expected in feedback.text and feedback.text.startswith("On a random network")


def test_a_form_right_only_on_the_small_network_of_the_notebook_fails():
    """A student who fits the numbers of one network by hand passes the check of that network only."""
    small = Network.from_arrays(2, 2, rows=[0, 0, 1, 1], cols=[0, 1, 0, 1], similarity=[0.5, -0.5, -0.5, 0.5],
                                pair_a=[0, 1], pair_b=[3, 2], pair_c=[0.9, -0.9], self_c=[1, 1, 1, 1])
    W, I = hopfield_form(small)
    assert check_energy_derivation(W, I, small)
    assert not check_hopfield_form(lambda net: (W, I) if net.n_neurons == 4 else
                                   (np.zeros((net.n_neurons,) * 2), 2 + net.similarity), rng=3)


def test_random_networks_are_valid_varied_and_reproducible():
    nets = [random_network(np.random.default_rng(s)) for s in range(6)]
    assert len({n.n_neurons for n in nets}) > 2 and all(n.n_pairs > 0 for n in nets)
    again = random_network(np.random.default_rng(0))
    assert np.array_equal(again.rows, nets[0].rows) and np.array_equal(again.pair_c, nets[0].pair_c)


def test_hopfield_form_bad_input():
    with pytest.raises(ParameterTypeError, match="'form' parameter of check_hopfield_form"):
        check_hopfield_form("W", rng=0)
    with pytest.raises(ParameterTypeError, match="'form' parameter of check_hopfield_form"):
        check_hopfield_form(lambda net: hopfield_form(net)[0], rng=0)
    with pytest.raises(ParameterError, match="'rng' parameter of check_hopfield_form"):
        check_hopfield_form(hopfield_form, rng=-1)


# --- the two kinds of error (00, exercise 1) ------------------------------------------------------

@pytest.fixture
def errors():
    """Matches (0,0) right; (0,1) and (2,2) wrong partners; (3,0) and (4,1) extras."""
    return [[0, 0], [0, 1], [2, 2], [3, 0], [4, 1]], [[0, 0], [1, 1], [2, 3]]


def test_error_kinds_correct(errors):
    assert check_error_kinds(2, 2, *errors).correct


@pytest.mark.parametrize("wrong, extra, expected", [
    (4, 0, "every error as a wrong partner"),
    (2, 2 + 1, "add up to 5, but 4 of the 5 matches are errors"),
    (3, 1, "told the kinds apart by the right corner"),
    (0, 4, "The split is off (yours: 0 wrong partners and 4 extras)"),
])
def test_error_kinds_slips(errors, wrong, extra, expected):
    feedback = check_error_kinds(wrong, extra, *errors)
    assert not feedback.correct and expected in feedback.text, feedback.text


def test_error_kinds_swapped():
    pairs, targets = [[0, 1], [3, 0], [4, 4]], [[0, 0]]
    assert "swapped" in check_error_kinds(2, 1, pairs, targets).text


def test_error_kinds_bad_input(errors):
    with pytest.raises(ParameterError, match="'wrong' parameter of check_error_kinds"):
        check_error_kinds(-1, 0, *errors)
    with pytest.raises(ParameterTypeError, match="'extra' parameter of check_error_kinds"):
        check_error_kinds(1, "2", *errors)


# --- a depth range (07, exercise 1) ---------------------------------------------------------------

def test_depth_range_correct_and_slips():
    fB, d, q = 300 * 0.10, 25.0, 0.5
    ok = dict(focal_px=300, baseline_m=0.10, error_px=q)
    assert check_depth_range(fB / (d + q), fB / (d - q), d, **ok).correct
    swapped = check_depth_range(fB / (d - q), fB / (d + q), d, **ok)
    assert not swapped and "farther from the cameras than your far end" in swapped.text
    assert "Both ends are the depth itself" in check_depth_range(fB / d, fB / d, d, **ok).text
    assert "is off; the depth itself is 1.200 m" in check_depth_range(1.0, 1.5, d, **ok).text
    # a hint, never the answer: neither end's value appears in any message
    for near, far in ((fB / (d - q), fB / (d + q)), (fB / d, fB / d), (1.0, 1.5)):
        text = check_depth_range(near, far, d, **ok).text
        assert f"{fB / (d + q):.3f}" not in text and f"{fB / (d - q):.3f}" not in text
        assert "d - q" not in text and "d + q" not in text


def test_depth_range_far_end_at_infinity():
    assert check_depth_range(30 / 0.75, float("inf"), 0.25, focal_px=300, baseline_m=0.1, error_px=0.5).correct


def test_depth_range_bad_input():
    with pytest.raises(ParameterError, match="'disparity' parameter of check_depth_range"):
        check_depth_range(1.0, 2.0, 0.0, focal_px=300, baseline_m=0.1, error_px=0.5)
