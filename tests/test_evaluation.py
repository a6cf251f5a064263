"""C/E/T arithmetic on hand-made cases."""

import math

import pytest

from ismb_lab.evaluation import Score, score


@pytest.mark.parametrize("pairs, targets, unknown, expected", [
    ([], [[0, 0]], (), "0/0+0/1"),
    ([[0, 0], [1, 1]], [[0, 0], [1, 1]], (), "2/0+0/2"),
    ([[0, 1]], [[0, 0]], (), "0/1+0/1"),                    # wrong partner
    ([[5, 5]], [[0, 0]], (), "0/0+1/1"),                    # extra: left 5 has no target
    ([[5, 5]], [[0, 0]], [5], "0/0+0/1"),                   # unknown truth: not counted
    ([[0, 0], [0, 1]], [[0, 0]], (), "1/1+0/1"),            # a second match of a labelled feature
    ([[0, 0], [0, 0]], [[0, 0], [0, 0]], (), "2/0+0/1"),    # duplicate targets count once in T
])
def test_cet_counts(pairs, targets, unknown, expected):
    assert str(score(pairs, targets, unknown)) == expected


def test_rates_and_fitness():
    s = score([[0, 0], [1, 1], [2, 0], [7, 3]], [[0, 0], [1, 1], [2, 2], [3, 3]])
    assert (s.correct, s.wrong_partner, s.extra, s.targets) == (2, 1, 1, 4)
    assert s.recall == 0.5 and s.precision == 0.5 and s.fitness == 0
    assert math.isnan(Score(0, 0, 0, 0).recall) and math.isnan(Score(0, 0, 0, 3).precision)


def test_the_thesis_fig_5_10_rows_do_not_add_up_to_its_printed_total():
    # Fig. 5.10 prints "Total: C/E/T = 125/14/137"; its eleven testing rows add up to
    # 139/13/150 (92.7%, not 91.24%).  A lesson in checking totals.
    rows = ["12/0+0/12", "15/0+0/15", "14/2+0/16", "16/1+1/17", "11/0+1/12", "5/0+2/5",
            "14/0+1/16", "16/0+1/20", "11/0+1/12", "13/0+1/13", "12/0+2/12"]
    total = Score(0, 0, 0, 0)
    for row in rows:
        c, e, t = row.split("/")
        w, x = e.split("+")
        total = total + Score(int(c), int(w), int(x), int(t))
    assert (total.correct, total.errors, total.targets) == (139, 13, 150)
    assert (total.correct, total.errors, total.targets) != (125, 14, 137)
