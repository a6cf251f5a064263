"""Every figure the notebooks draw is readable at 1024 x 768: no two texts overlap, none is
cut by the figure's edge, every image of values has a colour bar, and the lines and markers
of one axes differ in hue, not only in lightness.

The figures are measured in the notebooks' own kernels, at the end of every cell, during the
one execution per test session that tests/notebooks/conftest.py's ``executed_notebook`` makes
(figure_text.py says how and why; the thresholds are its constants).  The tests without the
``notebook`` mark check the measuring itself on figures drawn here.
"""

from pathlib import Path

import matplotlib
import numpy as np
import pytest

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"
NAMES = sorted(p.name for p in NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))


#: Findings listed per figure and cell in a message; the rest are counted.
SHOWN = 12


def problems(records, judge) -> list:
    """``judge(record)``'s findings over a notebook's records, each once (at the first cell
    where it shows), as 'cell N, figure F: finding'; past :data:`SHOWN` per figure and cell,
    one line counts the rest."""
    seen, found = set(), []
    for r in records:
        new = [f for f in judge(r) if (r["figure"], f) not in seen]
        seen.update((r["figure"], f) for f in new)
        label = f" ({r['label']})" if r.get("label") else ""
        where = f"cell {r['cell']}, figure {r['figure']}{label}, {r['kind']}"
        found += [f"{where}: {f}" for f in new[:SHOWN]]
        if len(new) > SHOWN:
            found.append(f"{where}: and {len(new) - SHOWN} more")
    return found


def count(found) -> int:
    more = [int(f.rsplit("and ", 1)[1].split()[0]) for f in found if f.endswith(" more")]
    return len(found) - len(more) + sum(more)


@pytest.mark.notebook
@pytest.mark.parametrize("name", NAMES)
def test_every_figure_was_measured(name, figure_records):
    nb, records = figure_records(name)
    errors = [f"cell {r['cell']}: {r['error']}" for r in records if "error" in r]
    assert errors == [], f"{name}: figures that could not be measured:\n" + "\n".join(errors)
    code = "\n".join(c.source for c in nb.cells if c.cell_type == "code")
    draws = "plt." in code or any(c.outputs and any("image/png" in o.get("data", {}) for o in c.outputs)
                                  for c in nb.cells if c.cell_type == "code")
    if draws:
        assert records, f"{name} draws figures, but none was measured"
    assert all(r["cell"] is not None for r in records), f"{name}: a record names no cell of the notebook"


@pytest.mark.notebook
@pytest.mark.parametrize("name", NAMES)
def test_no_text_overlaps_or_is_cut(name, figure_records, figure_text):
    _, records = figure_records(name)
    found = problems(records, figure_text.overlaps) + problems(records, figure_text.cut_texts)
    assert found == [], f"{name}: {count(found)} text problems:\n" + "\n".join(found)


@pytest.mark.notebook
@pytest.mark.parametrize("name", NAMES)
def test_images_of_values_have_colour_bars(name, figure_records, figure_text):
    _, records = figure_records(name)
    found = problems(records, figure_text.missing_colour_bars)
    assert found == [], f"{name}: {count(found)} images without a colour bar:\n" + "\n".join(found)


@pytest.mark.notebook
@pytest.mark.parametrize("name", NAMES)
def test_line_colours_differ_in_hue(name, figure_records, figure_text):
    _, records = figure_records(name)
    found = problems(records, figure_text.hue_clashes)
    assert found == [], f"{name}: {count(found)} pairs of colours alike in hue:\n" + "\n".join(found)


# ---------------------------------------------------------------- the measuring itself

@pytest.fixture
def measured(figure_text):
    """``measure(fig)``: figure_text.measure of an Agg figure, as an inline figure is measured."""
    from ismb_lab.widgets._common import COLUMN_PX

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    figure_text._patch_matplotlib()

    def measure(fig):
        if not hasattr(fig.canvas, "get_renderer"):
            FigureCanvasAgg(fig)
        return figure_text.measure(fig, COLUMN_PX)
    return measure


def test_overlapping_titles_are_found_and_side_by_side_ones_pass(measured, figure_text):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4, 2))
    a, b = fig.subplots(1, 2)
    a.set_title("a title much too long for its half")
    b.set_title("and a second one")
    found = figure_text.overlaps(measured(fig))
    assert len(found) == 1 and "title of axes 0" in found[0] and "title of axes 1" in found[0]
    a.set_title("left")
    b.set_title("right")
    assert figure_text.overlaps(measured(fig)) == []
    assert figure_text.cut_texts(measured(fig)) == []


def test_tick_labels_and_annotations_are_texts(measured, figure_text):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3, 2))
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1])
    ax.set_xticks([0.5, 0.52], ["half", "just past"])
    ax.annotate("a note", (0.1, 0.8), xytext=(0.5, 0.5), arrowprops={"arrowstyle": "->"})
    record = measured(fig)
    kinds = {t["what"].split(" of ")[0].split(" in ")[0] for t in record["texts"]}
    assert {"x tick label", "y tick label", "annotation"} <= kinds
    assert any("'half'" in f and "'just past'" in f for f in figure_text.overlaps(record))
    # the annotation's box is its text, not its arrow: nothing else overlaps
    assert len(figure_text.overlaps(record)) == 1


def test_glyph_labels_are_texts(measured, figure_text):
    from matplotlib.figure import Figure

    from ismb_lab.widgets._common import path_labels

    fig = Figure(figsize=(3, 2))
    ax = fig.subplots()
    ax.set_xlim(0, 10), ax.set_ylim(0, 10)
    path_labels(ax, np.array([[2.0, 2.0], [2.1, 2.1], [8.0, 8.0]]), ["12", "34", "56"], "#F0E442")
    record = measured(fig)
    glyphs = [t for t in record["texts"] if t["what"].startswith("glyph label")]
    assert [t["text"] for t in glyphs] == ["12", "34", "56"]
    found = figure_text.overlaps(record)
    assert len(found) == 1 and "'12'" in found[0] and "'34'" in found[0]


def test_a_text_past_the_edge_of_an_interactive_figure_is_cut(figure_text):
    # an ipympl canvas shows the figure itself: 200 x 100 css px here
    record = {"size_css": [200.0, 100.0], "texts": [
        {"what": "title", "text": "wide", "box": [-5.0, 80.0, 150.0, 95.0], "clip": None},
        {"what": "x label", "text": "fits", "box": [50.0, 0.0, 120.0, 12.0], "clip": None},
        {"what": "text in axes 0", "text": "half hidden", "box": [150.0, 40.0, 190.0, 52.0],
         "clip": [20.0, 20.0, 170.0, 80.0]}]}
    found = figure_text.cut_texts(record)
    assert len(found) == 2
    assert "'wide'" in found[0] and "left by 5.0 px" in found[0]
    assert "'half hidden'" in found[1] and "cut by its axes" in found[1]


def test_an_image_of_values_needs_a_colour_bar_and_a_photo_does_not(measured, figure_text):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4, 2))
    a, b = fig.subplots(1, 2)
    values = a.imshow(np.arange(12.0).reshape(3, 4), cmap="plasma")
    b.imshow(np.arange(12.0).reshape(3, 4), cmap="gray")
    found = figure_text.missing_colour_bars(measured(fig))
    assert len(found) == 1 and "'plasma'" in found[0] and "axes 0" in found[0]
    fig.colorbar(values, ax=a)
    assert figure_text.missing_colour_bars(measured(fig)) == []


def test_hue_threshold_on_the_palette(figure_text):
    from matplotlib.colors import to_rgb

    from ismb_lab.plotting import OKABE_ITO

    clash = lambda a, b: figure_text.hue_clash(to_rgb(OKABE_ITO[a]), to_rgb(OKABE_ITO[b]))
    # the palette's pairs told apart mainly by lightness
    for a, b in (("orange", "vermillion"), ("orange", "yellow"), ("sky blue", "blue")):
        assert clash(a, b), (a, b)
    # the threshold lies between those and every other pair, with room on both sides
    chromatic = [c for c in OKABE_ITO if c != "black"]
    close = {frozenset(p) for p in (("orange", "vermillion"), ("orange", "yellow"), ("sky blue", "blue"))}
    for i, a in enumerate(chromatic):
        for b in chromatic[i + 1:]:
            hues = [figure_text.lch(to_rgb(OKABE_ITO[c]))[2] for c in (a, b)]
            gap = abs(hues[0] - hues[1]) % 360
            gap = min(gap, 360 - gap)
            if frozenset((a, b)) in close:
                assert gap < figure_text.MIN_HUE_DEG - 7, (a, b, gap)
            else:
                assert clash(a, b) is None and gap > figure_text.MIN_HUE_DEG + 14, (a, b, gap)
    assert clash("black", "orange") is None
    assert figure_text.hue_clash((0, 0, 0), (0.5, 0.5, 0.5))      # two greys: lightness only
    assert figure_text.hue_clash((1, 0.5, 0), (1, 0.5, 0)) is None  # one colour used twice


def test_line_colours_are_read_from_lines_markers_and_collections(measured, figure_text):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3, 2))
    ax = fig.subplots()
    ax.plot([0, 1], [0, 1], color="#E69F00", label="orange")
    ax.plot([0, 1], [1, 0], "o", color="#D55E00", label="vermillion")
    ax.scatter([0.5], [0.5], color="#0072B2")
    found = figure_text.hue_clashes(measured(fig))
    assert len(found) == 1 and "'orange'" in found[0] and "'vermillion'" in found[0]


def test_the_recorder_measures_each_changed_figure_once_per_cell(tmp_path, figure_text):
    """The kernel side, with a stand-in shell: a figure unchanged since the last cell is not
    measured again, a changed one is."""
    import matplotlib.pyplot as plt

    events = type("Events", (), {"callbacks": {"post_execute": [print]}})()
    shell = type("Shell", (), {"execution_count": 2, "events": events})()   # after cell 1
    path = tmp_path / "records.jsonl"
    backend = matplotlib.get_backend()
    plt.switch_backend("Agg")
    try:
        recorder = figure_text.install(shell, str(path), 580)
        assert events.callbacks["post_execute"][0] is recorder
        fig, ax = plt.subplots(figsize=(3, 2))
        ax.set_title("first")
        recorder()
        shell.execution_count = 3
        recorder()                      # unchanged: not measured again
        ax.set_title("second")
        shell.execution_count = 4
        recorder()
        plt.close(fig)
    finally:
        figure_text._RECORDER = None
        plt.switch_backend(backend)
    records = figure_text.read_records(path)
    assert [(r["cell_count"], r["figure"]) for r in records] == [(1, 1), (3, 1)]
    assert [t["text"] for t in records[1]["texts"] if t["what"].startswith("title")] == ["second"]
