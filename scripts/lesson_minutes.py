"""The minutes of each notebook's in-class path, and the lesson plan's tables made from them.

A notebook's *in-class path* is every cell without the cell tag ``homework``.  For it the
tool counts, from the notebook's text and from a record of one measured run:

* **reading**: the words of its markdown (a word is a run of characters between spaces that
  holds a letter or a digit), plain prose at :data:`PLAIN_WPM` words a minute, prose that
  holds LaTeX math at :data:`FORMULA_WPM`.  The unit is a paragraph (text between blank
  lines), a list item or a heading: a unit with ``$...$`` or ``$$...$$`` in it is formula
  prose.  Markdown tables and code blocks are not words;
* **code read**: the non-blank lines of its code cells as the student's copy shows them (a
  solution between ``### BEGIN SOLUTION`` and ``### END SOLUTION`` is one stub line, hidden
  tests are gone), and of the code blocks in its markdown, at :data:`CODE_LPM` lines a minute;
* **figures and tables**: :data:`FIGURE_MIN` minute each.  A figure is an image a code cell
  shows (a PNG, JPEG or SVG output) or an interactive figure it shows (an ipympl canvas, a
  k3d plot, an image widget, also inside a widget), and an image in its markdown.  A table
  is a markdown table, an HTML table in an output, or a printed table: three or more
  consecutive lines of a cell's printed output that each hold at least two numbers;
* **run**: the measured wall time of *Restart & Run All* in a fresh kernel;
* **tasks**: an allowance per exercise of its ``## Exercises`` section (code, prediction,
  open question) and per widget task, a cell before the exercises that shows a widget a
  student works with (:data:`ALLOWANCE`).  An exercise whose text cell is tagged
  ``homework`` is homework.

Each part is rounded up to a tenth of a minute, and a notebook's total (their sum) up to a
whole minute.  A session adds its teacher talk (:data:`TEACHER_MIN`), its start-up time
(:data:`SETUP_MIN`: the logins and the first run of the first session) and its quiz
(:data:`QUIZ_MIN`) to its notebooks' totals (:data:`SESSIONS`).

Figures, tables and widget tasks come from the executed notebooks, so ``--measure`` writes
them into the run-time record with the times, cell by cell, together with a hash of each
notebook's code cells; a notebook whose code changed since is reported *stale* until it is
measured again.  The lesson plan's generated tables sit between ``<!-- minutes:NAME -->``
and ``<!-- /minutes:NAME -->``; ``--write-plan`` rewrites them and ``--check-plan`` reports
every line that differs.  One of them is not minutes: what nbgrader grades in each notebook
of a course assignment (:func:`grading`), read from the notebooks' nbgrader cells.

    python scripts/lesson_minutes.py --sessions                       # every notebook, and each session's total
    python scripts/lesson_minutes.py --json --sessions                # the same as JSON
    python scripts/lesson_minutes.py --write-plan notebooks/LESSON_PLAN.md   # regenerate the plan's tables
    python scripts/lesson_minutes.py --check-plan notebooks/LESSON_PLAN.md   # is the plan true? (exit 1 if not)
    python scripts/lesson_minutes.py --measure notebooks/run_times.json      # run all ten (minutes)
"""

import argparse
import datetime
import hashlib
import json
import math
import os
import re
import shutil
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"
RUN_TIMES = NOTEBOOKS / "run_times.json"
PATTERN = "0*.ipynb"
COPIED = ("notebooks", "images", "manifests")
#: Files of those folders a measuring run leaves out: what a class's runs write there.
LEFT_OUT = (".ipynb_checkpoints", "targets-*.json", "my_targets*.json", "params-*.json", ".targets-*.lock",
            "photos-*")
HOMEWORK = "homework"
#: The tag of a markdown cell the teacher presents at the board: its reading is the board's minutes.
BOARD = "board"

#: Reading speeds: words a minute of plain prose and of prose that holds formulas; code lines a minute.
PLAIN_WPM, FORMULA_WPM, CODE_LPM = 130, 90, 15
#: Minutes for one figure or table.
FIGURE_MIN = 1

#: Minutes allowed for one task, by kind, and the reason (:data:`WHY`).
ALLOWANCE = {"code": 6, "prediction": 5, "question": 5, "widget": 3}
WHY = {
    "code": "read the starter and the check's hint, fix one line, run again: two tries",
    "prediction": "write a prediction, run the cell that reveals it, one sentence on the difference",
    "question": "look up a table or change one argument, write two sentences",
    "widget": "one widget to try before the exercises: a few clicks or slider moves, read the status",
    "quiz": "five short questions on paper, a minute each",
    "setup": "everyone logs in to the class's JupyterLab, the whole class on one server at once; whoever could "
             "not run 00 before the session runs its first cells now",
    "board": "the derivation in the cells tagged `board` (02: the Hopfield form of (3-15) and what the thesis' "
             "literal weights change), at the board with the class following; their reading is not counted again",
}

#: A session's length, its teacher talk and its quiz, in minutes.
SESSION_MIN, TEACHER_MIN, QUIZ_MIN = 90, 15, 5
#: The least teacher talk a session may plan.
LEAST_TEACHER_MIN = 10
#: Minutes before the first notebook, by session: the logins and the first run (:data:`WHY`).
SETUP_MIN = {"Session 1": 5}
#: Minutes at the board, by session (:data:`WHY`).
BOARD_MIN = {"Session 1": 15}
#: The name of that step in the plan's session table.
BOARD_STEP = "derivation at the board"
#: The name of that step in the plan's session table.
SETUP = "logins and first run"
#: The notebooks of each session, by their two-digit prefix; the others are optional.
SESSIONS = {"Session 1": ("01", "02", "04"), "Session 2": ("05", "06", "07")}
#: Notebooks each student runs before a session, on their own: their minutes are not the session's.
BEFORE = {"Session 1": ("00",)}
OPTIONAL = ("03", "08", "09")
#: What the teacher talk of a session is for.
TEACHER_TALK = "an opening, a few minutes to introduce each notebook, and the discussions (the questions below)"

#: An exercise starts a line of the Exercises section with its bold number: ``**2.**``, ``**4. Predict first.**``.
_EXERCISE = re.compile(r"^\*\*(\d+)\.(.*?)\*\*", re.M)
_LIST_ITEM = re.compile(r"^\s*(?:[*+-]|\d+[.)])\s")
_MATH = re.compile(r"(?<!\\)\$[^$]+?(?<!\\)\$", re.S)
_INLINE_CODE = re.compile(r"`[^`\n]*`")
_IMAGE = re.compile(r"!\[[^\]]*\]\([^)]*\)|<img\b[^>]*>", re.I)
_NUMBER = re.compile(r"\d+(?:\.\d+)?")
_SEPARATOR = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")
#: Widget models that draw a figure: ipympl's canvas, an image widget, k3d's plot (an anywidget since k3d 3).
FIGURE_MODELS = ("MPLCanvasModel", "ImageModel", "k3d.plot.Plot")
_IMAGE_MIME = ("image/png", "image/jpeg", "image/svg+xml")
_WIDGET_MIME = "application/vnd.jupyter.widget-view+json"
_STATE = "application/vnd.jupyter.widget-state+json"


# --- the text of the cells -------------------------------------------------------------------

def _source(cell) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def _tags(cell) -> list:
    return cell.get("metadata", {}).get("tags", [])


def on_path(cell) -> bool:
    """Whether `cell` is on the in-class path: it has no ``homework`` tag."""
    return HOMEWORK not in _tags(cell)


def words(text: str) -> int:
    """The words of a text: runs of characters between spaces that hold a letter or a digit.

    >>> words("The energy $E$ never rises -- see (3-5).")
    7
    """
    return sum(1 for token in text.split() if re.search(r"\w", token))


def student_code(source: str) -> str:
    """A code cell's source as the student's copy shows it: a solution is one stub line, hidden tests are gone.

    >>> print(student_code("x = 1  # fix\\n### BEGIN SOLUTION\\nx = 2\\n### END SOLUTION\\n"
    ...                    "### BEGIN HIDDEN TESTS\\nassert x == 2\\n### END HIDDEN TESTS\\nprint(x)"))
    x = 1  # fix
    # YOUR CODE HERE
    print(x)
    """
    kept, end = [], None
    for line in source.splitlines():
        marker = line.strip()
        if end:
            end = None if marker.startswith(end) else end
        elif marker.startswith("### BEGIN SOLUTION"):
            kept.append(line[:len(line) - len(line.lstrip())] + "# YOUR CODE HERE")
            end = "### END SOLUTION"
        elif marker.startswith("### BEGIN HIDDEN TESTS"):
            end = "### END HIDDEN TESTS"
        else:
            kept.append(line)
    return "\n".join(kept)


def code_lines(source: str) -> int:
    """The non-blank lines of a code cell's student copy."""
    return sum(1 for line in student_code(source).splitlines() if line.strip())


@dataclass
class Text:
    """What one markdown text holds for a reader."""

    plain_words: int = 0
    formula_words: int = 0
    code_lines: int = 0
    tables: int = 0
    images: int = 0


def markdown(text: str) -> Text:
    """The plain and formula words, code lines, tables and images of a markdown text.

    >>> markdown("Energy:\\n\\n$$E = -y W y$$\\n\\n* it never rises;\\n* with $W_{ii} = 0$ too.\\n\\n"
    ...          "```python\\nrun(net)\\n\\nnet\\n```\\n\\n| a | b |\\n|---|---|\\n| 1 | 2 |")
    Text(plain_words=4, formula_words=8, code_lines=2, tables=1, images=0)
    """
    found = Text()
    units, unit, fence, previous = [], [], None, ""

    def close():
        if unit:
            units.append("\n".join(unit))
            unit.clear()

    lines = text.splitlines()
    for n, line in enumerate(lines):
        stripped = line.strip()
        if fence:
            if stripped.startswith(fence):
                fence = None
            elif stripped:
                found.code_lines += 1
            continue
        if stripped.startswith(("```", "~~~")):
            close()
            fence = stripped[:3]
            continue
        if not stripped:
            close()
            previous = ""
            continue
        if stripped.startswith("|"):
            close()
            if _SEPARATOR.match(stripped) and n > 0 and lines[n - 1].strip().startswith("|"):
                found.tables += 1
            previous = line
            continue
        indented = len(line) - len(line.lstrip()) >= 4
        if indented and not previous and not unit and not _LIST_ITEM.match(line) and \
                not any(_LIST_ITEM.match(u.splitlines()[0]) for u in units[-1:]):
            found.code_lines += 1      # an indented code block after a blank line, outside a list
            continue
        if _LIST_ITEM.match(line) or stripped.startswith("#"):
            close()
        unit.append(line)
        previous = line
    close()
    for part in units:
        found.images += len(_IMAGE.findall(part))
        part = _IMAGE.sub(" ", part)
        n_words = words(part)
        if _MATH.search(_INLINE_CODE.sub(" ", part)):
            found.formula_words += n_words
        else:
            found.plain_words += n_words
    return found


def _exercise_start(cells: list) -> int:
    return next((n for n, c in enumerate(cells) if c["cell_type"] == "markdown"
                 and re.search(r"^## Exercises\s*$", _source(c), re.M)), len(cells))


@dataclass(frozen=True)
class Exercise:
    """One exercise: its number, kind, the index of the markdown cell that holds it, and whether that is homework."""

    number: int
    kind: str
    cell: int
    homework: bool


def exercises(cells: list) -> list[Exercise]:
    """The exercises of a notebook's cells (nbformat dicts), in order.

    An exercise is a bold number at the start of a line of the ``## Exercises`` section; it
    is a ``prediction`` when its bold title says "Predict", else ``code`` when it is the last
    exercise of its markdown cell and the next cell is a starter (a code cell that says "fix"),
    else a ``question``.  It is homework when its markdown cell is tagged ``homework``.

    >>> md = lambda s, *tags: {"cell_type": "markdown", "source": s, "metadata": {"tags": list(tags)}}
    >>> [(e.number, e.kind, e.homework) for e in exercises([
    ...     md("## Exercises\\n\\n**1.** Fix it."), {"cell_type": "code", "source": "x = 0  # fix me"},
    ...     md("**2.** Why?"), md("**3. Predict first.** Then run.", "homework")])]
    [(1, 'code', False), (2, 'question', False), (3, 'prediction', True)]
    """
    found = []
    for n in range(_exercise_start(cells), len(cells)):
        if cells[n]["cell_type"] != "markdown":
            continue
        numbered = _EXERCISE.findall(_source(cells[n]))
        starter = n + 1 < len(cells) and cells[n + 1]["cell_type"] == "code" \
            and "fix" in _source(cells[n + 1]).lower()
        for index, (number, title) in enumerate(numbered):
            if "predict" in title.lower():
                kind = "prediction"
            elif starter and index == len(numbered) - 1:
                kind = "code"
            else:
                kind = "question"
            found.append(Exercise(int(number), kind, n, not on_path(cells[n])))
    return found


def exercise_kinds(cells: list) -> dict:
    """``{number: kind}`` of :func:`exercises`, homework included."""
    return {e.number: e.kind for e in exercises(cells)}


def grading(cells: list) -> dict:
    """How nbgrader grades each exercise: ``{"auto": [...], "hand": [...], "none": [...]}``.

    An exercise owns the cells after its markdown cell up to the next exercise's (when one
    markdown cell holds several, the last of them owns them).  It is *auto* when one of them is
    a grade cell without a solution (a hidden test, which ``nbgrader autograde`` runs), *hand*
    when one is a grade cell with a solution or a task (an answer scored in the Formgrader),
    and *none* otherwise.  Entries are ``(number, cell index)``; for *none* the exercise's own cell.

    >>> md = lambda s, **g: {"cell_type": "markdown", "source": s, "metadata": {"nbgrader": g} if g else {}}
    >>> grading([md("## Exercises\\n\\n**1.** Fix it."), {"cell_type": "code", "source": "x = 0  # fix"},
    ...          {"cell_type": "code", "source": "assert x", "metadata": {"nbgrader": {"grade": True}}},
    ...          md("**2.** Why?\\n\\n**3. Predict first.**"), md("YOUR ANSWER HERE", grade=True, solution=True),
    ...          md("**4.** And?"), md("Your answer", grade=False, solution=False)])
    {'auto': [(1, 2)], 'hand': [(3, 4)], 'none': [(2, 3), (4, 5)]}
    """
    found = {"auto": [], "hand": [], "none": []}
    listed = exercises(cells)
    for n, e in enumerate(listed):
        later = [x.cell for x in listed[n + 1:] if x.cell > e.cell]
        owned = [] if any(x.cell == e.cell for x in listed[n + 1:]) else \
            range(e.cell + 1, later[0] if later else len(cells))
        kinds = []
        for m in owned:
            meta = cells[m].get("metadata", {}).get("nbgrader", {})
            if meta.get("grade") and not meta.get("solution"):
                kinds.append(("auto", m))
            elif (meta.get("grade") and meta.get("solution")) or meta.get("task"):
                kinds.append(("hand", m))
        if not kinds:
            found["none"].append((e.number, e.cell))
        for kind, m in kinds:
            found[kind].append((e.number, m))
    return found


# --- what an executed notebook shows ---------------------------------------------------------

def printed_tables(text: str) -> int:
    """The printed tables of an output text: runs of three or more lines that each hold two numbers or more.

    >>> printed_tables("pair 01: 12/0/12\\npair 02: 15/0/15\\npair 03: 14/2/16\\n\\nmean 13.7 of 14.3\\nthe end")
    1
    """
    count = run = 0
    for line in text.splitlines() + [""]:
        if len(_NUMBER.findall(line)) >= 2:
            run += 1
        else:
            count += run >= 3
            run = 0
    return count


def _models(ref, state: dict, seen: set):
    """The model ids reachable from a widget reference (``IPY_MODEL_<id>``, or an id)."""
    if isinstance(ref, str):
        model = ref[len("IPY_MODEL_"):] if ref.startswith("IPY_MODEL_") else ref
        if model in state and model not in seen:
            seen.add(model)
            yield model
            yield from _models(state[model].get("state", {}), state, seen)
    elif isinstance(ref, dict):
        for value in ref.values():
            if isinstance(value, (str, list, dict)):
                yield from _models(value, state, seen)
    elif isinstance(ref, list):
        for value in ref:
            yield from _models(value, state, seen)


def _is_figure(entry: dict) -> bool:
    """Whether a widget model of the saved state draws a figure (:data:`FIGURE_MODELS`)."""
    return entry.get("model_name") in FIGURE_MODELS or entry.get("state", {}).get("_anywidget_id") in FIGURE_MODELS


def _output_figures(outputs: list) -> int:
    return sum(1 for o in outputs if any(m in o.get("data", {}) for m in _IMAGE_MIME))


def shown(cell, state: dict) -> dict:
    """``{"figures", "tables", "widgets"}`` of one executed code cell; `state` is the notebook's widget state.

    A widget output counts its figure models (:data:`FIGURE_MODELS`, and images in its output
    widgets) as figures, and is a widget task unless it is a figure alone.
    """
    figures = tables = widgets = 0
    printed = ""
    for out in cell.get("outputs", []) + [{}]:
        kind, data = out.get("output_type"), out.get("data", {})
        if kind == "stream":
            printed += "".join(out.get("text", "")) if out.get("name") == "stdout" else ""
            continue
        tables += printed_tables(printed)      # the printed text up to here, however many messages it came in
        printed = ""
        if kind in ("display_data", "execute_result"):
            if any(m in data for m in _IMAGE_MIME):
                figures += 1
            elif _WIDGET_MIME in data:
                root = data[_WIDGET_MIME].get("model_id", "")
                models = list(_models(root, state, set()))
                figures += sum(_is_figure(state[m]) for m in models)
                figures += sum(_output_figures(state[m].get("state", {}).get("outputs", []))
                               for m in models if state[m].get("model_name") == "OutputModel")
                widgets += bool(models) and not _is_figure(state[models[0]])
            elif "text/html" in data:
                tables += "".join(data["text/html"]).count("<table")
            elif "text/plain" in data:
                tables += printed_tables("".join(data["text/plain"]))
    return {"figures": figures, "tables": tables, "widgets": int(widgets > 0)}


def code_hash(cells: list) -> str:
    """A hash of a notebook's code cells (ids and sources, in order): what a run depends on."""
    digest = hashlib.sha256()
    for cell in cells:
        if cell["cell_type"] == "code":
            digest.update(f"{cell.get('id', '')}\0{_source(cell)}\0".encode())
    return digest.hexdigest()[:16]


def count_executed(nb: dict) -> dict:
    """The per-cell figures, tables and widget tasks of an executed notebook, non-zero counts only."""
    state = nb.get("metadata", {}).get("widgets", {}).get(_STATE, {}).get("state", {})
    counts = {"figures": {}, "tables": {}, "widgets": {}}
    for cell in nb["cells"]:
        if cell["cell_type"] == "code":
            for key, value in shown(cell, state).items():
                if value:
                    counts[key][cell["id"]] = value
    return counts


# --- minutes of a notebook -------------------------------------------------------------------

def _tenths(x: float) -> float:
    """`x` rounded up to a tenth (a float error below 1e-9 is not a tenth)."""
    return math.ceil(round(x * 10, 9)) / 10


@dataclass(frozen=True)
class Minutes:
    """The in-class path of one notebook; every ``*_min`` part is rounded up to a tenth, the total to a minute."""

    name: str
    plain_words: int
    formula_words: int
    reading_min: float
    code_lines: int
    code_min: float
    figures: int
    tables: int
    figures_min: int
    run_s: float
    run_min: float
    code: int
    prediction: int
    question: int
    widget: int
    allowance_min: int
    total_min: int
    in_class: tuple = ()
    homework: tuple = ()
    where: dict = field(default_factory=dict)
    stale: bool = False


def read_record(path: Path) -> dict:
    """The run-time record that ``--measure`` wrote."""
    return json.loads(Path(path).read_text(encoding="utf-8"))


def read_run_times(path: Path) -> dict:
    """The measured seconds per notebook name."""
    return {name: entry["seconds"] for name, entry in read_record(path)["notebooks"].items()}


def minutes(path: Path, entry: dict) -> Minutes:
    """The :class:`Minutes` of the notebook at `path`; `entry` is its record (seconds and per-cell counts)."""
    cells = json.loads(Path(path).read_text(encoding="utf-8"))["cells"]
    start = _exercise_start(cells)
    text, figures, tables, widgets, lines = Text(), 0, 0, 0, 0
    where = {"figures": [], "tables": [], "widgets": []}
    for n, cell in enumerate(cells):
        if not on_path(cell):
            continue
        if cell["cell_type"] == "markdown":
            if BOARD in _tags(cell):
                continue
            part = markdown(_source(cell))
            for key in ("plain_words", "formula_words", "code_lines", "tables", "images"):
                setattr(text, key, getattr(text, key) + getattr(part, key))
            for key, value in (("tables", part.tables), ("figures", part.images)):
                if value:
                    where[key].append((n, value))
        elif cell["cell_type"] == "code":
            lines += code_lines(_source(cell))
            for key in ("figures", "tables", "widgets"):
                value = entry.get(key, {}).get(cell.get("id"), 0)
                if key == "widgets":
                    value = value if n < start else 0
                if value:
                    where[key].append((n, value))
            figures += entry.get("figures", {}).get(cell.get("id"), 0)
            tables += entry.get("tables", {}).get(cell.get("id"), 0)
            widgets += 1 if n < start and entry.get("widgets", {}).get(cell.get("id"), 0) else 0
    figures += text.images
    tables += text.tables
    lines += text.code_lines
    found = exercises(cells)
    counts = dict.fromkeys(("code", "prediction", "question"), 0)
    for e in found:
        if not e.homework:
            counts[e.kind] += 1
    counts["widget"] = widgets
    reading = _tenths(text.plain_words / PLAIN_WPM + text.formula_words / FORMULA_WPM)
    code = _tenths(lines / CODE_LPM)
    run_s = float(entry["seconds"])
    run = _tenths(run_s / 60)
    shown_min = FIGURE_MIN * (figures + tables)
    allowance = sum(ALLOWANCE[k] * v for k, v in counts.items())
    total = math.ceil(round(reading + code + shown_min + run + allowance, 9))
    return Minutes(Path(path).stem, text.plain_words, text.formula_words, reading, lines, code, figures, tables,
                   shown_min, run_s, run, **counts, allowance_min=allowance, total_min=total,
                   in_class=tuple((e.number, e.kind) for e in found if not e.homework),
                   homework=tuple(e.number for e in found if e.homework), where=where,
                   stale=entry.get("code_sha") != code_hash(cells))


def stale(folder: Path = NOTEBOOKS, run_times: Path = RUN_TIMES) -> list[str]:
    """The notebooks of `folder` whose code cells changed since the record was measured (or that it lacks)."""
    record = read_record(run_times)["notebooks"]
    found = []
    for path in sorted(Path(folder).glob(PATTERN)):
        entry = record.get(path.name)
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        if entry is None or entry.get("code_sha") != code_hash(cells):
            found.append(path.name)
    return found


def table(folder: Path = NOTEBOOKS, run_times: Path = RUN_TIMES) -> list[Minutes]:
    """The :class:`Minutes` of every notebook of `folder`, in name order."""
    record = read_record(run_times)["notebooks"]
    paths = sorted(Path(folder).glob(PATTERN))
    missing = [p.name for p in paths if p.name not in record]
    if missing:
        raise ValueError(f"run_times: no measured time for {', '.join(missing)} in {run_times}")
    return [minutes(p, record[p.name]) for p in paths]


@dataclass(frozen=True)
class Session:
    """One session: its notebooks' minutes, its teacher talk and quiz, and the total."""

    name: str
    rows: tuple
    teacher_min: int
    quiz_min: int
    total_min: int
    setup_min: int = 0
    board_min: int = 0


def sessions(rows: list[Minutes], teacher_min: int = TEACHER_MIN) -> dict:
    """``{"Session N": Session}`` of :data:`SESSIONS` from the notebooks' `rows`.

    A session's total is `teacher_min`, its :data:`SETUP_MIN` and :data:`BOARD_MIN`, its notebooks'
    totals and :data:`QUIZ_MIN`.
    """
    by_prefix = {r.name[:2]: r for r in rows}
    found = {}
    for name, prefixes in SESSIONS.items():
        missing = [p for p in prefixes if p not in by_prefix]
        if missing:
            raise ValueError(f"sessions: no notebook {', '.join(missing)} for {name}")
        picked = tuple(by_prefix[p] for p in prefixes)
        setup, board = SETUP_MIN.get(name, 0), BOARD_MIN.get(name, 0)
        found[name] = Session(name, picked, teacher_min, QUIZ_MIN,
                              teacher_min + setup + board + QUIZ_MIN + sum(r.total_min for r in picked), setup, board)
    return found


def fit_problems(found: dict, session_min: int = SESSION_MIN, least_teacher: int = LEAST_TEACHER_MIN) -> list[str]:
    """Every session longer than `session_min`, or with less teacher talk than `least_teacher`."""
    problems = []
    for s in found.values():
        if s.teacher_min < least_teacher:
            problems.append(f"{s.name}: {s.teacher_min} min of teacher talk, under {least_teacher}")
        if s.total_min > session_min:
            problems.append(f"{s.name}: {s.total_min} min with the teacher talk, over {session_min} by "
                            f"{s.total_min - session_min}")
    return problems


# --- the plan's generated tables -------------------------------------------------------------

def _tasks(r: Minutes) -> str:
    parts = [f"{r.widget} widget{'s' if r.widget != 1 else ''} {ALLOWANCE['widget'] * r.widget}"] if r.widget else []
    parts += [f"ex. {n} {kind} {ALLOWANCE[kind]}" for n, kind in r.in_class]
    return " + ".join(parts) or "none"


def _minutes(x: float) -> str:
    return f"{x:.1f}"


def _assignments() -> dict:
    """``{notebook file name: nbgrader assignment id}`` of the course (``ismb_lab.teaching.course.ASSIGNMENTS``)."""
    from ismb_lab.teaching.course import ASSIGNMENTS

    return {name: key for key, spec in ASSIGNMENTS.items() for name in spec.notebooks}


def _graded(folder: Path, assignments: dict) -> str:
    """The plan's table of what nbgrader grades in each notebook of `folder`."""
    def listed(entries, cells=False):
        return ", ".join(f"ex. {n}" + (f" (c{m})" if cells else "") for n, m in entries) or "none"

    lines = ["| notebook | assignment | autograded: a hidden test | graded by hand in the Formgrader: the answer "
             "cell | not graded |", "|---|---|---|---|---|"]
    for path in sorted(Path(folder).glob(PATTERN)):
        key = assignments.get(path.name)
        if key is None:
            lines.append(f"| `{path.stem}` | none | | | |")
            continue
        found = grading(json.loads(path.read_text(encoding="utf-8"))["cells"])
        lines.append(f"| `{path.stem}` | `{key}` | {listed(found['auto'])} | {listed(found['hand'], True)} | "
                     f"{listed(found['none'])} |")
    return "\n".join(lines)


def render(rows: list[Minutes], found: dict, record: dict, graded: str | None = None) -> dict:
    """The text of every generated block of the plan: ``{name: markdown}``; `graded` is :func:`_graded`'s table."""
    blocks = {}
    blocks["rates"] = "\n".join([
        "| part | rate | what is counted |",
        "|---|---:|---|",
        f"| teacher talk | {TEACHER_MIN} min a session | {TEACHER_TALK}; at least {LEAST_TEACHER_MIN} |",
        *(f"| {SETUP} | {minutes} min in {name} | {WHY['setup']} |" for name, minutes in SETUP_MIN.items()),
        *(f"| {BOARD_STEP} | {minutes} min in {name} | {WHY['board']} |" for name, minutes in BOARD_MIN.items()),
        f"| plain prose | {PLAIN_WPM} words a minute | the words of markdown paragraphs, list items and headings "
        "without LaTeX math |",
        f"| prose with formulas | {FORMULA_WPM} words a minute | the words of a paragraph, list item or heading that "
        "holds `$...$` or `$$...$$` |",
        f"| code | {CODE_LPM} lines a minute | non-blank lines of the code cells as the student's copy shows them, "
        "and of code blocks in markdown |",
        f"| figures and tables | {FIGURE_MIN} min each | every image or interactive figure a cell shows, every "
        "markdown table, every printed table (as defined above) |",
        "| run | measured | one *Restart & Run All* in a fresh kernel, from `run_times.json` |",
        *(f"| {label} | {ALLOWANCE[kind]} min each | {WHY[kind]} |" for kind, label in
          (("code", "code exercise"), ("prediction", "prediction"), ("question", "open question"),
           ("widget", "widget task"))),
        f"| quiz | {QUIZ_MIN} min a session | {WHY['quiz']} |",
    ])
    head = ("| notebook | plain words | formula words | reading min | code lines | code min | figures | tables "
            "| run s | run min | in class | tasks min | total min |\n"
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|")
    blocks["notebooks"] = "\n".join([head] + [
        f"| `{r.name}` | {r.plain_words} | {r.formula_words} | {_minutes(r.reading_min)} | {r.code_lines} | "
        f"{_minutes(r.code_min)} | {r.figures} | {r.tables} | {r.run_s:.1f} | {_minutes(r.run_min)} | {_tasks(r)} | "
        f"{r.allowance_min} | {r.total_min} |" for r in rows])
    for name, s in found.items():
        lines = ["| step | notebook | reading min | code min | figures + tables min | run min | in class "
                 "| tasks min | total min |",
                 "|---:|---|---:|---:|---:|---:|---|---:|---:|",
                 f"| 1 | teacher talk | | | | | {TEACHER_TALK} | | {s.teacher_min} |"]
        first = 2
        for minutes, step, why in ((s.setup_min, SETUP, WHY["setup"]), (s.board_min, BOARD_STEP, WHY["board"])):
            if minutes:
                lines.append(f"| {first} | {step} | | | | | {why} | | {minutes} |")
                first += 1
        for n, r in enumerate(s.rows, first):
            lines.append(f"| {n} | `{r.name}` | {_minutes(r.reading_min)} | {_minutes(r.code_min)} | "
                         f"{r.figures_min} | {_minutes(r.run_min)} | {_tasks(r)} | {r.allowance_min} | "
                         f"{r.total_min} |")
        lines.append(f"| {len(s.rows) + first} | quiz | | | | | 5 questions, 1 min each | {s.quiz_min} | "
                     f"{s.quiz_min} |")
        steps = [s.teacher_min] + [m for m in (s.setup_min, s.board_min) if m] + [r.total_min for r in s.rows] \
            + [s.quiz_min]
        lines.append(f"| | **sum** | | | | | {' + '.join(map(str, steps))} = {s.total_min} | | **{s.total_min}** |")
        left = SESSION_MIN - s.total_min
        lines.append(f"| | **left of {SESSION_MIN}** | | | | | {SESSION_MIN} − {s.total_min} = {left} | "
                     f"| **{left}** |")
        by_prefix = {r.name[:2]: r for r in rows}
        before = [by_prefix[p] for p in BEFORE.get(name, ()) if p in by_prefix]
        if before:
            lines += ["", "**Before the session**, each student on their own, as soon as their login works: "
                      + ", ".join(f"`{r.name}` ({r.total_min} min)" for r in before) + "."]
        work = [f"{r.name[:2]} ex. {', '.join(map(str, r.homework))}" for r in before + list(s.rows) if r.homework]
        lines += ["", "**Homework** (cells tagged `homework`): " + ("; ".join(work) if work else "none") + "."]
        blocks[name] = "\n".join(lines)
    where = []
    for r in rows:
        parts = []
        for key, label in (("figures", "figures"), ("tables", "tables"), ("widgets", "widget tasks")):
            cells = r.where.get(key, [])
            if cells:
                parts.append(f"{label} " + ", ".join(f"c{n}" + (f" ×{k}" if k > 1 else "") for n, k in cells))
        where.append(f"* `{r.name}`: " + ("; ".join(parts) or "none") + ".")
    blocks["where"] = "\n".join(where)
    if graded is not None:
        blocks["graded"] = graded
    notebooks = record.get("notebooks", {})
    blocks["measured"] = "\n".join([
        f"Measured {record.get('date', '?')} with `{record.get('command', '?')}` on {record.get('cpus', '?')} cores, "
        f"load average {', '.join(f'{x:.2f}' for x in record.get('load_before', []))} before the first notebook; "
        f"order {', '.join(record.get('order', list(notebooks)))}.",
    ])
    return blocks


def _block(name: str) -> re.Pattern:
    tag = re.escape(name)
    return re.compile(rf"(^<!-- minutes:{tag} -->\n)(.*?)(^<!-- /minutes:{tag} -->$)", re.S | re.M)


def plan_blocks(folder: Path = NOTEBOOKS, run_times: Path = RUN_TIMES) -> dict:
    """The generated blocks for the notebooks of `folder` and the record `run_times`."""
    rows = table(folder, run_times)
    return render(rows, sessions(rows), read_record(run_times), _graded(folder, _assignments()))


def write_plan(text: str, blocks: dict) -> str:
    """`text` with every generated block replaced; a block without its markers is an error."""
    for name, body in blocks.items():
        pattern = _block(name)
        if not pattern.search(text):
            raise ValueError(f"plan: no <!-- minutes:{name} --> ... <!-- /minutes:{name} --> markers")
        text = pattern.sub(lambda m: m.group(1) + body + "\n" + m.group(3), text)
    return text


def _label(line: str) -> str:
    cells = [c.strip().strip("*`") for c in line.strip().strip("|").split("|")]
    return next((c for c in cells if c and not re.fullmatch(r"[\d.]+", c)), line.strip())[:50]


def check_plan(text: str, folder: Path = NOTEBOOKS, run_times: Path = RUN_TIMES) -> list[str]:
    """Every line of the plan's generated blocks that differs from what the notebooks give, and every stale record.

    An empty list means every number of the plan's tables is the notebooks' (the fit to
    :data:`SESSION_MIN` is :func:`fit_problems`' question).
    """
    problems = [f"{name}: its code changed since {run_times} was measured: run --measure again"
                for name in stale(folder, run_times)]
    for name, body in plan_blocks(folder, run_times).items():
        match = _block(name).search(text)
        if not match:
            problems.append(f"{name}: no <!-- minutes:{name} --> block in the plan")
            continue
        have, want = match.group(2).rstrip("\n").splitlines(), body.splitlines()
        for n in range(max(len(have), len(want))):
            a = have[n] if n < len(have) else ""
            b = want[n] if n < len(want) else ""
            if a != b:
                problems.append(f"{name}: {_label(b or a)}: the plan says {a!r}, the notebooks give {b!r}")
    return problems


def marking_problems(cells: list) -> list[str]:
    """Homework cells not marked for the student, and exercises split between class and homework.

    A homework cell is marked when it, or a homework cell before it in an unbroken run of them,
    begins with ``### Homework`` or ``**Homework.**``.  A code exercise's starter and the
    grader's test, and a prediction's answer cell and the cell after it, share the tag of the
    exercise's text.
    """
    problems, marked = [], False
    for n, cell in enumerate(cells):
        if on_path(cell):
            marked = False
            continue
        marked = marked or _source(cell).lstrip().startswith(("### Homework", "**Homework.**"))
        if not marked:
            problems.append(f"c{n} is tagged homework but follows no '### Homework' heading or '**Homework.**'")
    for e in exercises(cells):
        if e.kind == "code":
            tied = [e.cell + 1] + [n for n, c in enumerate(cells) if c["cell_type"] == "code" and
                                   _source(c).startswith(f"# The grader's test of exercise {e.number}")]
        elif e.kind == "prediction" and e.cell + 1 < len(cells) and \
                _source(cells[e.cell + 1]).strip().startswith("YOUR ANSWER HERE"):
            tied = [e.cell + 1, e.cell + 2]
        else:
            tied = []
        for n in tied:
            if n < len(cells) and on_path(cells[n]) == e.homework:
                problems.append(f"exercise {e.number} (c{e.cell}) is {'homework' if e.homework else 'in class'} "
                                f"but c{n} is not")
    return problems


# --- measuring ------------------------------------------------------------------------------

def _run_once(path: Path, folder: Path, timeout: int, keep: Path | None) -> dict:
    """Wall seconds, load averages, errors and per-cell counts of one Restart & Run All of `path`."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    sha = code_hash(nb.cells)
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3", resources={"metadata": {"path": str(folder)}})
    load = os.getloadavg()
    start = time.perf_counter()
    client.execute()
    seconds = time.perf_counter() - start
    errors = sum(1 for c in nb.cells for o in c.get("outputs", []) if o.get("output_type") == "error")
    if keep:
        nbformat.write(nb, Path(keep) / path.name)
    slow = {}
    for cell in nb.cells:
        timing = cell.get("metadata", {}).get("execution", {})
        begin, end = timing.get("iopub.execute_input"), timing.get("shell.execute_reply")
        if begin and end:
            took = (datetime.datetime.fromisoformat(end.replace("Z", "+00:00"))
                    - datetime.datetime.fromisoformat(begin.replace("Z", "+00:00"))).total_seconds()
            if took >= 1:
                slow[cell["id"]] = round(took, 1)
    return {"seconds": round(seconds, 1), "load_before": [round(x, 2) for x in load],
            "load_after": [round(x, 2) for x in os.getloadavg()], "errors": errors, "code_sha": sha,
            **count_executed(nb), "cells_over_1s": slow}


def order(names) -> list[str]:
    """`names` in the order a class meets them: the sessions' notebooks, then the optional ones, then the rest.

    >>> order(["09_x.ipynb", "04_y.ipynb", "03_z.ipynb", "00_a.ipynb", "zz.ipynb"])
    ['00_a.ipynb', '04_y.ipynb', '03_z.ipynb', '09_x.ipynb', 'zz.ipynb']
    """
    ranked = [p for name, prefixes in SESSIONS.items() for p in BEFORE.get(name, ()) + prefixes] + list(OPTIONAL)
    return sorted(names, key=lambda n: (ranked.index(n[:2]) if n[:2] in ranked else len(ranked), n))


def measure(root: Path, out: Path, command: str, timeout: int = 900, keep: Path | None = None) -> dict:
    """Run every notebook of `root` once in a copy of its layout; write and return the record.

    The notebooks run one at a time in :func:`order`, each in a fresh kernel, with one numba
    cache that is empty at the first and kept for the next ones, as a student's server keeps
    it.  `keep` is a folder for the executed notebooks.
    """
    record = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
              "command": command, "cpus": os.cpu_count(), "load_before": list(os.getloadavg()),
              "what": "wall seconds of one Restart & Run All per notebook (kernel start included), each in a "
                      "fresh kernel, one at a time in the order below; the numba cache empty at the first notebook "
                      "and kept for the next ones, as a student's server keeps it. Per notebook: the hash of its "
                      "code cells (code_sha), and per cell id the figures, tables and widget tasks its outputs "
                      "show (scripts/lesson_minutes.py says what counts), and the cells that took 1 s or more",
              "order": [], "notebooks": {}}
    saved = {k: os.environ.get(k) for k in ("NUMBA_CACHE_DIR", "PYTHONPATH")}
    with tempfile.TemporaryDirectory(prefix="lesson-minutes-") as tmp:
        for name in COPIED:
            # a student's labels or parameters left in the folder would change what 05 and 06 run on
            shutil.copytree(root / name, Path(tmp) / name, ignore=shutil.ignore_patterns(*LEFT_OUT))
        cache = Path(tmp) / "numba-cache"
        cache.mkdir()
        # the kernels inherit the environment: an empty numba cache, and this checkout's package
        os.environ["NUMBA_CACHE_DIR"] = str(cache)
        os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(root), saved["PYTHONPATH"]) if p)
        try:
            folder = Path(tmp) / "notebooks"
            for name in order(p.name for p in folder.glob(PATTERN)):
                record["order"].append(name[:2])
                record["notebooks"][name] = entry = _run_once(folder / name, folder, timeout, keep)
                print(f"{name}: {entry['seconds']} s, load {entry['load_before'][0]} -> "
                      f"{entry['load_after'][0]}, {entry['errors']} errors", flush=True)
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value
    record["notebooks"] = dict(sorted(record["notebooks"].items()))
    Path(out).write_text(json.dumps(record, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return record


def recount(executed: Path, run_times: Path) -> list[str]:
    """Count again the figures, tables and widget tasks of the executed notebooks in `executed`
    (``--measure --keep``) into the record `run_times`; only those whose code hash is the record's.
    Returns the names recounted."""
    record = read_record(run_times)
    done = []
    for path in sorted(Path(executed).glob(PATTERN)):
        nb = json.loads(path.read_text(encoding="utf-8"))
        entry = record["notebooks"].get(path.name)
        if entry and entry.get("code_sha") == code_hash(nb["cells"]):
            entry.update(count_executed(nb))
            done.append(path.name)
    Path(run_times).write_text(json.dumps(record, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return done


# --- the command line ------------------------------------------------------------------------

def format_table(rows: list[Minutes]) -> str:
    """The rows as a plain text table: one header line and one line per notebook."""
    head = ("notebook", "plain", "formula", "read", "lines", "code", "fig", "tab", "run s", "run", "tasks", "total")
    lines = ["{:<26} {:>5} {:>7} {:>5} {:>5} {:>5} {:>3} {:>3} {:>6} {:>4} {:>5} {:>5}".format(*head)]
    for r in rows:
        lines.append(f"{r.name:<26} {r.plain_words:>5} {r.formula_words:>7} {r.reading_min:>5.1f} {r.code_lines:>5} "
                     f"{r.code_min:>5.1f} {r.figures:>3} {r.tables:>3} {r.run_s:>6.1f} {r.run_min:>4.1f} "
                     f"{r.allowance_min:>5} {r.total_min:>5}" + ("  (stale: measure again)" if r.stale else ""))
    return "\n".join(lines)


def _writable(out: Path) -> bool:
    return not (out.is_symlink() or (out.exists() and (not out.is_file() or not os.access(out, os.W_OK))))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="lesson_minutes.py", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--notebooks", type=Path, default=NOTEBOOKS,
                        help="folder of the notebooks (default notebooks/)")
    parser.add_argument("--run-times", type=Path, default=RUN_TIMES,
                        help="measured run times and counts (default notebooks/run_times.json)")
    parser.add_argument("--json", action="store_true",
                        help="print the notebooks' rows as JSON (with --sessions: the notebooks and the sessions)")
    parser.add_argument("--sessions", action="store_true", help="print each session's total after the table")
    parser.add_argument("--check-plan", type=Path, metavar="PLAN",
                        help="compare the generated tables of PLAN (notebooks/LESSON_PLAN.md) with the notebooks; "
                             "exit 1 on a difference")
    parser.add_argument("--write-plan", type=Path, metavar="PLAN", help="rewrite the generated tables of PLAN")
    parser.add_argument("--measure", type=Path, metavar="FILE",
                        help="run every notebook once in a copy of the layout and write the times and counts to FILE")
    parser.add_argument("--keep", type=Path, metavar="DIR", help="with --measure: keep the executed notebooks in DIR")
    parser.add_argument("--recount", type=Path, metavar="DIR",
                        help="count figures and tables again from the executed notebooks in DIR into --run-times")
    args = parser.parse_args(argv)
    if args.measure:
        if not _writable(args.measure):
            print(f"lesson_minutes.py: --measure: will not replace {args.measure}: a symlink, a device, a folder "
                  "or read-only", file=sys.stderr)
            return 2
        if args.keep:
            args.keep.mkdir(parents=True, exist_ok=True)
        command = "python scripts/lesson_minutes.py --measure " + str(args.measure) + \
            (f" --keep {args.keep}" if args.keep else "")
        measure(ROOT, args.measure, command, keep=args.keep)
        return 0
    try:
        if args.recount:
            print("recounted: " + (", ".join(recount(args.recount, args.run_times)) or "none"))
            return 0
        if args.write_plan:
            if not _writable(args.write_plan):
                raise ValueError(f"--write-plan: will not replace {args.write_plan}: a symlink, a folder or "
                                 "read-only")
            text = write_plan(args.write_plan.read_text(encoding="utf-8"), plan_blocks(args.notebooks, args.run_times))
            args.write_plan.write_text(text, encoding="utf-8")
            late = stale(args.notebooks, args.run_times)
            print(f"{args.write_plan}: tables written" + (f"; stale run times: {', '.join(late)}" if late else ""))
            return 0
        if args.check_plan:
            problems = check_plan(args.check_plan.read_text(encoding="utf-8"), args.notebooks, args.run_times)
            print("\n".join(problems) or f"{args.check_plan}: every number agrees with the notebooks")
            return 1 if problems else 0
        rows = table(args.notebooks, args.run_times)
        found = sessions(rows) if args.sessions else {}
    except (OSError, ValueError, KeyError) as exc:
        print(f"lesson_minutes.py: {exc}", file=sys.stderr)
        return 2
    if args.json:
        notebooks = [asdict(r) for r in rows]
        print(json.dumps({"notebooks": notebooks,
                          "sessions": {n: {"notebooks": [r.name for r in s.rows], "teacher_min": s.teacher_min,
                                           "setup_min": s.setup_min, "board_min": s.board_min,
                                           "quiz_min": s.quiz_min,
                                           "total_min": s.total_min}
                                       for n, s in found.items()}} if found else notebooks, indent=1))
        return 0
    print(format_table(rows))
    for s in found.values():
        print(f"{s.name}: {s.teacher_min} teacher + " + (f"{s.setup_min} {SETUP} + " if s.setup_min else "")
              + (f"{s.board_min} {BOARD_STEP} + " if s.board_min else "")
              + " + ".join(f"{r.total_min} ({r.name[:2]})" for r in s.rows)
              + f" + {s.quiz_min} quiz = {s.total_min} min of {SESSION_MIN}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
