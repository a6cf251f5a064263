"""The exercise assignments through nbgrader: ``ismb-lab course source`` writes every
assignment's source from the notebooks, ``nbgrader generate_assignment`` makes student
versions that hold no solution, and ``nbgrader autograde`` gives the solutions full marks.

The student versions' Restart & Run All is tests/notebooks/test_notebooks.py's
``test_runs_headless`` (it executes :func:`ismb_lab.course.student_notebook` of each
notebook, checked here to be what generate_assignment writes); autograde executes the
solutions, so each notebook runs once more here, not twice.
"""

from __future__ import annotations

import inspect
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

pytest.importorskip("nbgrader")

from ismb_lab import exercises  # noqa: E402
from ismb_lab.course import ASSIGNMENTS, CODE_STUB, student_notebook  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXERCISES = sorted(name for name in ASSIGNMENTS if name != "labels")
STUDENT = "ann"
#: The library's own implementation of what an exercise asks for, by assignment.
REFERENCES = {"00-start": ("transfer",), "01-harris": ("harris_response", "harris_from_tensor"),
              "02-hopfield": ("hopfield_form",),
              "03-methods": ("euclidean_disparity",), "05-explorer": ("transfer",)}

pytestmark = pytest.mark.slow


def nbgrader(course: Path, *args: str) -> subprocess.CompletedProcess:
    bin_ = str(Path(sys.executable).parent)       # nbgrader runs alembic from PATH
    env = dict(os.environ, JUPYTER_CONFIG_PATH=str(ROOT / "deploy" / "course"),
               ISMB_NBGRADER_EXCHANGE=str(course / "exchange"), ISMB_COURSE_ID="ismb_lab_test",
               PATH=bin_ + os.pathsep + os.environ.get("PATH", ""), PYTHONPATH=str(ROOT))
    done = subprocess.run([sys.executable, "-m", "nbgrader", *args], cwd=course, env=env,
                          capture_output=True, text=True, timeout=1800)
    assert done.returncode == 0, f"nbgrader {' '.join(args)}:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done


@pytest.fixture(scope="module")
def course(tmp_path_factory):
    course = tmp_path_factory.mktemp("course")
    done = subprocess.run([sys.executable, "-m", "ismb_lab.cli", "course", "source", str(course),
                           "--assignment", "all"], capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in (course / "source").iterdir()) == sorted(ASSIGNMENTS)
    nbgrader(course, "generate_assignment", "*")       # every assignment, in one process
    assert sorted(p.name for p in (course / "release").iterdir()) == sorted(ASSIGNMENTS)
    return course


def notebook(course: Path, step: str, name: str):
    (path,) = (course / step / name).glob("*.ipynb")
    return nbformat.read(path, as_version=4)


def solutions(nb) -> list[str]:
    """The lines between the solution markers of `nb`, and of its hidden tests."""
    found = []
    for cell in nb.cells:
        found += re.findall(r"### BEGIN (?:SOLUTION|HIDDEN TESTS)\n(.*?)### END", cell.source, re.S)
    return [line.strip() for block in found for line in block.splitlines() if line.strip()]


@pytest.mark.parametrize("name", EXERCISES)
def test_the_student_version_holds_no_solution(course, name):
    source, student = notebook(course, "source", name), notebook(course, "release", name)
    answers = solutions(source)
    graded = [c for c in source.cells if c.metadata.get("nbgrader", {}).get("grade")]
    assert answers and graded, f"{name}: no solution or no graded cell in the source"
    text = "\n".join(c.source for c in student.cells)
    assert "BEGIN SOLUTION" not in text and "HIDDEN TESTS" not in text
    leaked = [line for line in answers if line in text]
    assert leaked == [], f"{name}: solution lines in the student version: {leaked}"
    solved = [c for c in student.cells if c.metadata.get("nbgrader", {}).get("solution")]
    assert all(CODE_STUB in c.source for c in solved if c.cell_type == "code")
    assert all(c.source == "YOUR ANSWER HERE" for c in solved if c.cell_type == "markdown")
    # each code exercise keeps a runnable first try and its check
    assert all("fix" in c.source for c in solved if c.cell_type == "code")
    # the hub's copy is made by student_notebook: the same cells as nbgrader's release
    ours = student_notebook(nbformat.read(ROOT / "notebooks" / ASSIGNMENTS[name].notebooks[0], as_version=4))
    assert [c.source for c in ours.cells] == [c.source.replace('"images/', '"../images/')
                                             .replace('"manifests/', '"../manifests/') for c in student.cells]


@pytest.mark.parametrize("name", EXERCISES)
def test_no_answer_is_imported_beside_the_exercises(course, name):
    student = notebook(course, "release", name)
    code = "\n".join(c.source for c in student.cells if c.cell_type == "code")
    imported = set(re.findall(r"from ismb_lab\.\w+ import ([\w, ]+)", code))
    names = {n.strip() for group in imported for n in group.split(",")}
    assert not names & set(REFERENCES.get(name, ())), f"{name} imports {names & set(REFERENCES[name])}"
    # a check's docstring (what `check_transfer?` shows) never states a solution
    answers = [re.sub(r"\s+", "", line.split("=", 1)[-1].replace("return ", "")) for line in
               solutions(notebook(course, "source", name)) if not line.startswith(("#", "assert"))]
    for check in sorted(n for n in names if n.startswith("check_")):
        doc = re.sub(r"\s+", "", inspect.getdoc(getattr(exercises, check)))
        assert [a for a in answers if len(a) > 4 and a in doc] == [], f"{check}'s docstring states the answer"


def test_autograde_gives_the_solutions_full_marks(course):
    from nbgrader.api import Gradebook

    for name in EXERCISES:
        folder = course / "submitted" / STUDENT / name
        folder.mkdir(parents=True)
        for path in (course / "source" / name).iterdir():
            (shutil.copytree if path.is_dir() else shutil.copyfile)(path, folder / path.name)
    nbgrader(course, "autograde", "*", "--create")
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gb:
        for name in EXERCISES:
            sub = gb.find_submission(name, STUDENT)
            grades = [g for nb in sub.notebooks for g in nb.grades]
            tests = [g for g in grades if g.cell.cell_type == "code"]
            assert tests and all(g.auto_score == g.max_score for g in tests), \
                f"{name}: {[(g.name, g.auto_score, g.max_score) for g in tests]}"
            assert sub.max_code_score == len(tests) and sub.code_score == sub.max_code_score
            # the written predictions are graded by the teacher, not counted here
            assert sub.max_written_score == sum(g.max_score for g in grades if g.cell.cell_type == "markdown")
    for name in EXERCISES:
        graded = notebook(course / "autograded", STUDENT, name)
        errors = [c.source for c in graded.cells for out in c.get("outputs", [])
                  if out.get("output_type") == "error"]
        assert errors == [], f"{name}: the solutions raise:\n{errors}"
