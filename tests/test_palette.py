"""Colours a colour-blind student can tell apart: Okabe and Ito's palette for every verdict,
and no green against red for right against wrong anywhere in the package or the notebooks."""

import json
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=True)

import matplotlib.colors as mcolors  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from ismb_lab.plotting import LEFT_COLOUR, OKABE_ITO, RIGHT_COLOUR, VERDICT_COLOURS, plot_matches, verdicts  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
# named colours and matplotlib's tab10 outside the palette (white, black and greys are allowed;
# the palette's own keys, OKABE_ITO["blue"], are not colours named outside it)
OFF_PALETTE = re.compile(r"""(?<!\[)["'](lime|green|darkgreen|limegreen|red|cyan|yellow|orange|magenta|blue|purple|"""
                         r"""tab:\w+|#1f77b4|#ff7f0e|#2ca02c|#d62728|#9467bd|#00ff00|#ff00ff)["'](?!\s*[:\]])""", re.IGNORECASE)


def test_the_palette_is_okabe_ito():
    assert OKABE_ITO == {"black": "#000000", "orange": "#E69F00", "sky blue": "#56B4E9",
                         "bluish green": "#009E73", "yellow": "#F0E442", "blue": "#0072B2",
                         "vermillion": "#D55E00", "reddish purple": "#CC79A7"}
    chosen = list(VERDICT_COLOURS.values()) + [LEFT_COLOUR, RIGHT_COLOUR]
    assert set(chosen) <= set(OKABE_ITO.values()) and len(set(chosen)) == len(chosen)
    assert VERDICT_COLOURS["correct"] not in (OKABE_ITO["bluish green"],)


def test_the_labeller_marks_right_and_wrong_in_the_palette():
    from ismb_lab.widgets.labeler import _KEY_COLOURS

    assert _KEY_COLOURS["correct"] == VERDICT_COLOURS["correct"]
    assert _KEY_COLOURS["wrong"] == VERDICT_COLOURS["wrong partner"]
    assert set(_KEY_COLOURS.values()) <= set(OKABE_ITO.values())


def _code():
    for path in sorted((ROOT / "ismb_lab").rglob("*.py")):
        yield path.relative_to(ROOT), path.read_text(encoding="utf-8")
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        yield path.relative_to(ROOT), "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")


@pytest.mark.parametrize("name, text", list(_code()), ids=lambda v: str(v) if isinstance(v, Path) else "")
def test_every_chosen_colour_is_from_the_palette(name, text):
    """Green beside red is the pair a red-green colour-blind reader cannot tell apart: every
    colour the code names comes from :data:`OKABE_ITO` (or is white, black or a grey)."""
    found = [c for c in OFF_PALETTE.findall(text)]
    assert not found, f"{name}: {found}"


def test_plot_matches_colours_each_line_by_its_verdict():
    from matplotlib.figure import Figure

    ax = Figure().subplots()
    left_xy = np.array([[5.0, 5.0], [10.0, 10.0], [15.0, 15.0]])
    right_xy = left_xy - [2.0, 0.0]
    pairs = np.array([[1, 2], [0, 0], [2, 2]])
    art = plot_matches(ax, np.zeros((20, 20)), np.zeros((20, 20)), left_xy, right_xy, pairs,
                       targets=[[0, 0], [1, 1]], numbers=False)
    assert verdicts(pairs, [[0, 0], [1, 1]]) == ["wrong partner", "correct", "extra"]
    expected = [mcolors.to_rgba(VERDICT_COLOURS[v]) for v in ("correct", "wrong partner", "extra")]
    assert [tuple(c) for c in art["lines"].get_colors()] == expected      # the correct line under the others
    assert np.allclose(art["lines"].get_segments()[0], [left_xy[0], right_xy[0] + [20 + 8, 0]])
    plain = plot_matches(Figure().subplots(), np.zeros((20, 20)), np.zeros((20, 20)), left_xy, right_xy, pairs)
    assert plain["lines"].get_array() is not None       # without targets: coloured by disparity
