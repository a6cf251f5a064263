"""The exercise assignments through nbgrader: ``ismb-lab course source`` writes every
assignment's source from the notebooks, ``nbgrader generate_assignment`` makes student
versions that hold no solution, and ``nbgrader autograde`` gives the solutions full marks.

Each released student notebook runs unsolved to its end in its assignment's folder, as a
student who has solved nothing would run it, and every command its text prints works as
printed there (:func:`printed_commands` says which spans are commands and where each runs).
:func:`ismb_lab.teaching.course.student_notebook` (the hub's copy, run from ``notebooks/`` by
tests/notebooks/test_notebooks.py's ``test_runs_headless``) is checked here to be what
generate_assignment writes, apart from the paths into ``images/`` and ``manifests/``.
"""

from __future__ import annotations

import inspect
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest

pytest.importorskip("nbgrader")

from ismb_lab.teaching import exercises  # noqa: E402
from ismb_lab.teaching.course import ASSIGNMENTS, CODE_STUB, _local_paths, student_notebook  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXERCISES = sorted(name for name in ASSIGNMENTS if name != "labels")
STUDENT = "ann"
#: The library's own implementation of what an exercise asks for, by assignment.
REFERENCES = {"00-start": ("verdicts",), "01-harris": ("harris_response", "harris_from_tensor"),
              "02-hopfield": ("hopfield_form",), "03-methods": ("euclidean_disparity",)}

pytestmark = pytest.mark.slow


def course_env(course: Path) -> dict:
    """The environment of the teacher's and the students' shells: deploy/course's config, this
    course's exchange, and the venv's programs (ismb-lab, nbgrader, voila) on PATH."""
    bin_ = str(Path(sys.executable).parent)       # nbgrader runs alembic from PATH
    return dict(os.environ, JUPYTER_CONFIG_PATH=str(ROOT / "deploy" / "course"),
                ISMB_NBGRADER_EXCHANGE=str(course / "exchange"), ISMB_COURSE_ID="ismb_lab_test",
                PATH=bin_ + os.pathsep + os.environ.get("PATH", ""), PYTHONPATH=str(ROOT))


def nbgrader(course: Path, *args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    done = subprocess.run([sys.executable, "-m", "nbgrader", *args], cwd=cwd or course, env=course_env(course),
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
    # the hub's copy is made by student_notebook: the same cells as nbgrader's release, but
    # for the paths into the assignment's own images/ and manifests/
    ours = student_notebook(nbformat.read(ROOT / "notebooks" / ASSIGNMENTS[name].notebooks[0], as_version=4))
    _local_paths(ours)
    assert [c.source for c in ours.cells] == [c.source for c in student.cells]


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


def test_feedback_shows_the_scores_but_never_the_hidden_tests(course):
    """A student hands in 01-harris unsolved: autograde fails its test cell, and the feedback
    says so (AssertionError) without the hidden test's lines, nbgrader's own default."""
    name, student = "01-harris", "unsolved"
    folder = course / "submitted" / student / name
    shutil.copytree(course / "release" / name, folder)
    nbgrader(course, "autograde", name, "--student", student, "--create")
    test = next(c for c in notebook(course / "autograded", student, name).cells
                if "### BEGIN HIDDEN TESTS" in c.source)
    hidden = [line.strip() for line in test.source.split("### BEGIN HIDDEN TESTS")[1].split("### END")[0].splitlines()
              if line.strip()]
    assert hidden and any(o.get("output_type") == "error" for o in test.outputs)
    nbgrader(course, "generate_feedback", name, "--student", student)
    (html,) = (course / "feedback" / student / name).glob("*.html")
    text = html.read_text(encoding="utf-8")
    assert "AssertionError" in text and "HIDDEN TESTS" not in text
    shown = [line for line in hidden if line.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;") in text
             or line in text]
    assert shown == [], shown


# ------------------------------------------------ the released notebooks, as a student has them

#: Programs whose lines and code spans in a notebook's text are commands to run.
PROGRAMS = ("ismb-lab", "python", "python3", "voila", "jupyter", "nbgrader", "pip")
#: nbgrader's student commands: run from the folder that holds the fetched assignment.
STUDENT_NBGRADER = ("fetch_assignment", "submit", "list", "fetch_feedback")
#: A command that finishes later than this fails.
COMMAND_TIMEOUT = 300


def printed_commands(nb) -> list:
    """``[(cell index, command)]``: the shell commands a notebook's markdown prints, in order.

    A command is a line of a fenced or indented code block, or a code span, whose first word
    is one of :data:`PROGRAMS`; a shell comment after it is the shell's to drop.
    """
    found = []
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "markdown":
            continue
        text, lines = cell.source, []
        for block in re.findall(r"^```[^\n]*\n(.*?)^```", text, re.S | re.M):
            lines += block.splitlines()
        text = re.sub(r"^```[^\n]*\n.*?^```", "", text, flags=re.S | re.M)
        lines += [line.strip() for line in re.findall(r"(?:^|\n\s*\n)((?:(?: {4}|\t)\S[^\n]*\n?)+)", text)
                  for line in line.splitlines()]
        text = re.sub(r"(?:^|\n\s*\n)(?:(?: {4}|\t)\S[^\n]*\n?)+", "\n\n", text)
        lines += re.findall(r"`([^`\n]+)`", text)
        for line in lines:
            words = line.strip().split()
            if words and words[0] in PROGRAMS:
                found.append((i, line.strip()))
    return found


def _paths(words) -> list:
    """The words of a command that name input files or folders (an output after --out is made)."""
    found = []
    for before, word in zip([""] + words, words):
        if word.startswith("-") or before in ("--out", "-o") or word.startswith("#"):
            continue
        if "/" in word or re.search(r"\.(ipynb|json|png|jpg|py)$", word):
            found.append(word)
    return found


def plan(command: str, folder: Path, course: Path) -> tuple:
    """``(argv or None, cwd, why)`` for a printed command: where and how it runs.

    * a student's command runs in the released assignment's folder (`folder`), as printed;
    * ``nbgrader submit`` and its like, from the folder holding the fetched assignment;
    * the teacher's nbgrader commands, and a command on the collected work (``submitted/``),
      in the course folder;
    * a command that starts a server (voila, jupyter lab) is checked with ``--help``, and the
      files it names must exist: it would wait for a browser;
    * a program and subcommand named alone (``ismb-lab tune``) names the command, not a run:
      checked with ``--help``.
    """
    words = shlex.split(command, comments=True)
    if words[0] == "nbgrader":
        student = len(words) > 1 and words[1] in STUDENT_NBGRADER
        return None, folder.parent if student else course, "student's nbgrader" if student else "teacher's nbgrader"
    if any(w.rstrip("/") == "submitted" or w.startswith("submitted/") for w in words[1:]):
        return None, course, "on the collected work"
    server = words[0] == "voila" or (words[0] == "jupyter" and len(words) > 1
                                     and words[1] in ("lab", "notebook", "server"))
    if server:
        head = words[:2] if words[0] == "jupyter" else words[:1]
        return head + ["--help"], folder, "a server: --help, and its files must exist"
    if words[0] == "ismb-lab" and len(words) <= 2:
        return words + ["--help"], folder, "a command named, not run: --help"
    return None, folder, "as printed"


def run_command(command, cwd: Path, env: dict) -> tuple:
    """Run `command` (a shell line, or argv) in `cwd`; ``(returncode, output, seconds)``.  Its
    process group is stopped after :data:`COMMAND_TIMEOUT` (returncode None)."""
    shell = isinstance(command, str)
    start = time.monotonic()
    proc = subprocess.Popen(["bash", "-c", command] if shell else command, cwd=cwd, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        out, _ = proc.communicate(timeout=COMMAND_TIMEOUT)
        code = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGTERM)
        out, _ = proc.communicate()
        code = None
    return code, out, time.monotonic() - start


def released_copy(course: Path, name: str, home: Path) -> Path:
    """The assignment as a student's server holds it: ``home/<name>/``, released to the
    exchange by the course's own release (which leaves out ground truth no notebook names)
    and fetched by ``nbgrader fetch_assignment``, as a student fetches it."""
    target = home / name
    if not target.exists():
        (course / "exchange").mkdir(exist_ok=True)
        nbgrader(course, "release_assignment", name, "--force")
        nbgrader(course, "fetch_assignment", name, cwd=home)
    return target


def _repo_commands():
    for name in sorted(ASSIGNMENTS):
        for notebook in ASSIGNMENTS[name].notebooks:
            if printed_commands(nbformat.read(ROOT / "notebooks" / notebook, as_version=4)):
                yield name


def _save_labels(folder: Path) -> Path:
    """What the labeller's Save leaves in the assignment: the student's targets file, here
    five pairs of the answer key."""
    from ismb_lab.labels.classroom import targets_path
    from ismb_lab.teaching.course import course_images
    from ismb_lab.matching.pipeline import prepare
    from ismb_lab.labels.targets import load_targets, snap
    from ismb_lab.widgets.labeler import LabelModel

    images = course_images("synthetic", folder)
    prepared = prepare(images / "left.png", images / "right.png")
    # the release holds no ground truth (deploy/course/README.md): the key is the repository's
    key = snap(load_targets(ROOT / "images" / "synthetic" / "answer_key.json"), prepared.problem.left_xy,
               prepared.problem.right_xy).pairs
    model = LabelModel(prepared, path=targets_path("synthetic", folder))
    for i, k in key[:5]:
        model.add_pair(int(i), int(k))
    return model.save()


@pytest.mark.parametrize("name", sorted(ASSIGNMENTS))
def test_the_released_notebooks_run_unsolved_to_their_end(course, name, tmp_path):
    """Restart & Run All of the released notebook, nothing solved, in the assignment's own
    folder.  A cell may raise NotImplementedError only where a solution is missing (nbgrader's
    stub); the project's stub is a comment, so today nothing may raise at all."""
    from nbclient import NotebookClient

    folder = released_copy(course, name, tmp_path)
    for path in sorted(folder.glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        client = NotebookClient(nb, timeout=600, kernel_name="python3", allow_errors=True,
                                resources={"metadata": {"path": str(folder)}})
        client.execute()
        failed = []
        for i, cell in enumerate(nb.cells):
            if cell.cell_type != "code":
                continue
            if cell.source.strip() and not cell.execution_count:
                failed.append(f"cell {i} did not run")
            for out in cell.outputs:
                unsolved = out.get("ename") == "NotImplementedError" and cell.metadata.get("nbgrader", {}).get("solution")
                if out.get("output_type") == "error" and not unsolved:
                    failed.append(f"cell {i}: {out['ename']}: {out['evalue']}\n{cell.source[:300]}")
                elif out.get("output_type") == "stream" and out.get("name") == "stderr" \
                        and "Traceback" in out.get("text", ""):
                    failed.append(f"cell {i}: a traceback on stderr:\n{out['text'][-1500:]}")
        assert failed == [], f"{name}/{path.name}, unsolved:\n" + "\n".join(failed)


@pytest.mark.parametrize("name", list(_repo_commands()))
def test_every_printed_command_works_in_the_assignment_and_in_notebooks(course, name, tmp_path):
    """Every command the released notebook prints runs as printed where :func:`plan` says,
    in printed order; an assignment whose text has the student submit is fetched through
    the exchange, and the labeller's Save is made first when the teacher's commands pool it.
    The same commands as the repository's notebook prints them name files that exist from
    ``notebooks/``: the two differ only in those paths (ismb_lab.teaching.course)."""
    student = notebook(course, "release", name)
    commands = printed_commands(student)
    env = course_env(course)
    home = tmp_path / "home"
    home.mkdir()
    words = [shlex.split(c, comments=True) for _, c in commands]
    folder = released_copy(course, name, home)
    if any(w[:3] == ["ismb-lab", "targets", "merge"] for w in words):
        _save_labels(folder)
    failed, ran = [], []
    for (cell, command), w in zip(commands, words):
        argv, cwd, why = plan(command, folder, course)
        if argv is not None and "--help" in argv:
            missing = [p for p in _paths(w) if not (cwd / p).exists()]
            if missing:
                failed.append(f"cell {cell}: `{command}` ({why}): {missing} not in {cwd.name}/")
        code, out, seconds = run_command(argv if argv is not None else command, cwd, env)
        ran.append(f"cell {cell}: `{command}` in {cwd} ({why}): "
                   f"exit {code}, {seconds:.1f} s")
        if code != 0:
            failed.append(f"cell {cell}: `{command}` ({why}) in {cwd}: "
                          + (f"still running after {COMMAND_TIMEOUT} s" if code is None else f"exit {code}")
                          + f"\n{out[-1500:]}")
    print("\n".join(ran))
    # as the repository prints them, from notebooks/
    repo = nbformat.read(ROOT / "notebooks" / ASSIGNMENTS[name].notebooks[0], as_version=4)
    for cell, command in printed_commands(repo):
        w = shlex.split(command, comments=True)
        if plan(command, folder, course)[1] != folder:
            continue                       # the teacher's and nbgrader's: not run in a notebook's folder
        missing = [p for p in _paths(w) if not (ROOT / "notebooks" / p).exists()]
        if missing:
            failed.append(f"cell {cell}: `{command}` as notebooks/{repo_name(name)} prints it: "
                          f"{missing} not in notebooks/")
    assert len(commands) == len(printed_commands(repo))
    assert failed == [], f"{name}:\n" + "\n\n".join(failed)


def repo_name(name: str) -> str:
    return ASSIGNMENTS[name].notebooks[0]
