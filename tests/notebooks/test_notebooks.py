"""Every teaching notebook is committed clean, follows the section order and runs without error."""

import json
import re
from pathlib import Path

import nbformat
import pytest

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"
SECTIONS = ("Overview", "Thesis section and equations", "Try it", "What to notice", "Exercises")

NAMES = sorted(p.name for p in NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))

pytestmark = pytest.mark.notebook


def test_there_are_notebooks():
    assert "00_start_here.ipynb" in NAMES


@pytest.mark.parametrize("name", NAMES)
def test_committed_without_outputs(name):
    raw = json.loads((NOTEBOOKS / name).read_text(encoding="utf-8"))
    ids = [cell.get("id") for cell in raw["cells"]]
    assert None not in ids and len(set(ids)) == len(ids), f"{name}: cells need unique ids (nbformat 4.5)"
    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    nbformat.validate(nb)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [], f"{name}: a code cell has outputs:\n{cell.source}"
            assert cell.execution_count is None, f"{name}: execution_count is set:\n{cell.source}"


@pytest.mark.parametrize("name", NAMES)
def test_interactive_figures_fit_the_column(name):
    """An ipympl figure is drawn at its size in inches times its dpi, whatever the column's width:
    every ``figsize`` of a notebook that draws with ``%matplotlib widget`` fits the column of
    JupyterLab's default layout at 1024 x 768.  (Inline images are scaled to the column.)"""
    from ismb_lab.widgets._common import COLUMN_PX, DPI

    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    code = "\n".join(c.source for c in nb.cells if c.cell_type == "code")
    if "%matplotlib widget" not in code:
        pytest.skip(f"{name} draws inline")
    sizes = re.findall(r"figsize=\(([0-9.]+),\s*([0-9.]+)\)", code)
    wide = [f"figsize=({w}, {h})" for w, h in sizes if float(w) * DPI > COLUMN_PX]
    assert not wide, f"{name}: {wide} wider than the {COLUMN_PX} px column at {DPI} dpi"


@pytest.mark.parametrize("name", NAMES)
def test_sections_in_order_and_thesis_cited(name):
    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    markdown = [c.source for c in nb.cells if c.cell_type == "markdown"]
    headings = [line[3:].strip() for text in markdown for line in text.splitlines()
                if line.startswith("## ")]
    assert [h for h in headings if h in SECTIONS] == list(SECTIONS), headings
    assert re.search(r"\(\d-\d+\)|Table 5\.\d|Fig\. 5\.\d|§\d", "\n".join(markdown)), \
        f"{name} cites no thesis equation, table, figure or section"


@pytest.mark.parametrize("name", NAMES)
def test_runs_headless(name, executed_notebook, notebook_errors):
    nb = executed_notebook(name)
    assert notebook_errors(nb) == []
    # every code cell ran
    assert all(c.execution_count for c in nb.cells if c.cell_type == "code" and c.source.strip())
