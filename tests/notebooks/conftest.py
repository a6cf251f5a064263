"""Run the student versions of the teaching notebooks headlessly, from the notebooks/ folder, as
Restart & Run All would."""

import importlib.util
import sys
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from nbclient.util import ensure_async

NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"
FIGURE_TEXT = Path(__file__).resolve().with_name("figure_text.py")


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
        from ismb_lab.teaching.course import student_notebook
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


class MeasuringClient(NotebookClient):
    """A client that first runs `setup` in the kernel, silently: no cell of the notebook, no
    history entry, so the notebook's cells keep their execution counts."""

    def __init__(self, nb, setup: str, **kw):
        super().__init__(nb, **kw)
        self._setup = setup

    async def async_execute_cell(self, cell, cell_index, execution_count=None, store_history=True):
        if self._setup is not None:
            source, self._setup = self._setup, None
            # silent: no output, no history, no execution count; the cells' own messages are
            # told apart from its by their parent message id
            msg_id = await ensure_async(self.kc.execute(source, silent=True, store_history=False))
            reply = await self.async_wait_for_reply(msg_id)
            if reply is None or reply["content"]["status"] != "ok":
                content = reply["content"] if reply else {}
                raise RuntimeError(f"the measuring set-up failed: {content.get('ename')}: {content.get('evalue')}")
        return await super().async_execute_cell(cell, cell_index, execution_count, store_history)


def load_figure_text():
    """figure_text.py, beside this file (pytest imports tests with --import-mode=importlib)."""
    if "figure_text" not in sys.modules:
        spec = importlib.util.spec_from_file_location("figure_text", FIGURE_TEXT)
        module = importlib.util.module_from_spec(spec)
        sys.modules["figure_text"] = module
        spec.loader.exec_module(module)
    return sys.modules["figure_text"]


@pytest.fixture(scope="session")
def figure_text():
    return load_figure_text()


_EXECUTED: dict = {}
_FIGURES: dict = {}


@pytest.fixture(scope="session")
def executed_notebook(tmp_path_factory):
    """A notebook executed once per test session, as Restart & Run All would, shared by every
    test that only reads its outputs (a test must not change it).  A test whose run depends on
    files it writes first, such as a student's saved labels, uses ``run_notebook`` instead.

    The run also measures every figure the notebook draws (figure_text.py; the kernel writes
    what it measured to a file, the notebook is unchanged): ``figure_records`` reads it."""
    from ismb_lab.widgets._common import COLUMN_PX

    setup_source = load_figure_text().setup_source
    folder = tmp_path_factory.mktemp("figure_text")

    def get(name: str):
        if name not in _EXECUTED:
            found = folder / f"{name}.jsonl"
            found.unlink(missing_ok=True)
            plain = client(name)
            c = MeasuringClient(plain.nb, setup_source(str(found), COLUMN_PX, str(FIGURE_TEXT)),
                                timeout=plain.timeout, kernel_name=plain.kernel_name,
                                resources=plain.resources)
            c.execute()
            _EXECUTED[name] = c.nb
            _FIGURES[name] = found
        return _EXECUTED[name]
    return get


@pytest.fixture(scope="session")
def figure_records(executed_notebook):
    """``get(name) -> (nb, records)``: the executed notebook and what was measured of its
    figures, one record per figure and cell at whose end it was new or changed, each with
    ``cell`` (the cell's index in the notebook) and ``figure`` (a number per figure)."""
    read_records = load_figure_text().read_records

    def get(name: str):
        nb = executed_notebook(name)
        index = {c.execution_count: i for i, c in enumerate(nb.cells)
                 if c.cell_type == "code" and c.execution_count}
        records = read_records(_FIGURES[name])
        for r in records:
            r["cell"] = index.get(r["cell_count"])
        return nb, records
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
