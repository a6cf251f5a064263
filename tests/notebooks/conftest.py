"""Run the student versions of the teaching notebooks headlessly, from the notebooks/ folder, as
Restart & Run All would."""

from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"


def errors(nb) -> list[str]:
    """The error outputs of an executed notebook, as readable text."""
    found = []
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            if out.get("output_type") == "error":
                found.append(f"{out['ename']}: {out['evalue']}\nin cell:\n{cell.source}")
            elif out.get("output_type") == "stream" and out.get("name") == "stderr" \
                    and "Traceback" in out.get("text", ""):
                found.append(f"traceback on stderr:\n{out['text']}\nin cell:\n{cell.source}")
    return found


def student_version(nb):
    """The student version of `nb` (what the hub copies and nbgrader releases): the
    repository's notebooks hold the exercises' solutions and hidden tests, which
    tests/test_course_assignments.py runs through ``nbgrader autograde``.  Without nbgrader
    (the ``[course]`` extra) the notebook is run as it is, solutions included."""
    try:
        from ismb_lab.course import student_notebook
        return student_notebook(nb)
    except ImportError:
        return nb


def client(name: str, timeout: int = 300) -> NotebookClient:
    nb = student_version(nbformat.read(NOTEBOOKS / name, as_version=4))
    return NotebookClient(nb, timeout=timeout, kernel_name="python3",
                          resources={"metadata": {"path": str(NOTEBOOKS)}})


@pytest.fixture(scope="session")
def notebook_errors():
    return errors


_EXECUTED: dict = {}


@pytest.fixture(scope="session")
def executed_notebook():
    """A notebook executed once per test session, as Restart & Run All would, shared by every
    test that only reads its outputs (a test must not change it).  A test whose run depends on
    files it writes first, such as a student's saved labels, uses ``run_notebook`` instead."""
    def get(name: str):
        if name not in _EXECUTED:
            c = client(name)
            c.execute()
            _EXECUTED[name] = c.nb
        return _EXECUTED[name]
    return get


@pytest.fixture
def run_notebook():
    """Execute a notebook completely, in a fresh kernel; returns the executed notebook."""
    def run(name: str):
        c = client(name)
        c.execute()
        return c.nb
    return run


@pytest.fixture
def live_notebook():
    """Execute a notebook and keep its kernel, so a test can run more cells in it.

    Yields ``run_cell(source) -> outputs``; the notebook's own cells have run first.
    """
    started = []

    def start(name: str):
        c = client(name)
        started.append(c)
        c.setup_kernel_context = c.setup_kernel()
        c.setup_kernel_context.__enter__()
        for index, cell in enumerate(c.nb.cells):
            c.execute_cell(cell, index)

        def run_cell(source: str):
            cell = nbformat.v4.new_code_cell(source)
            c.nb.cells.append(cell)
            c.execute_cell(cell, len(c.nb.cells) - 1)
            return cell.outputs
        return c.nb, run_cell

    yield start
    for c in started:
        c.setup_kernel_context.__exit__(None, None, None)
