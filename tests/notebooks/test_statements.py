"""What a notebook's text says about a figure it computes is what its own output shows."""

import re

import pytest

pytestmark = pytest.mark.notebook


def output_text(nb) -> str:
    return "\n".join(o.get("text", "") or o.get("data", {}).get("text/plain", "")
                     for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []))


def test_02_shows_the_literal_rule_failing(run_notebook):
    text = output_text(run_notebook("02_hopfield_network.ipynb"))
    exact = re.search(r"exact: +\d+ attempts, energy rose (\d+) times.*stopped at a fixed point", text)
    thesis = re.search(r"thesis: +\d+ attempts, energy rose (\d+) times.*never reached a fixed point", text)
    assert exact and int(exact.group(1)) == 0, text
    assert thesis and int(thesis.group(1)) > 0, text
    # the markdown says Methods I and III never settle under the thesis rule, Method-II always does
    assert re.search(r"Method-I: settled in 20/20 runs with the exact rule, 0/20 with the thesis rule", text)
    assert re.search(r"Method-II: settled in 20/20 runs with the exact rule, 20/20 with the thesis rule", text)
    assert re.search(r"Method-III: settled in 20/20 runs with the exact rule, 0/20 with the thesis rule", text)
