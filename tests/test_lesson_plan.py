"""The lesson plan's minutes are the notebooks' minutes, and each session fits 90 minutes.

Every number between the plan's ``<!-- minutes:... -->`` markers is recomputed here, at test
time, by scripts/lesson_minutes.py from the notebooks' cells (their ``homework`` tags, words,
code lines, exercises) and from notebooks/run_times.json (run times, and the figures, tables
and widget tasks the executed notebooks showed, cell by cell).  A record measured before a
code cell changed is stale and fails the check.  Nothing is executed.
"""

import json
import math
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "notebooks" / "LESSON_PLAN.md"
ANSWERS = ROOT / "notebooks" / "solutions" / "QUIZ_ANSWERS.md"
THESIS = ROOT.parent / "shared" / "thesis"


@pytest.fixture(scope="module")
def tool(load_script):
    return load_script("lesson_minutes")


@pytest.fixture
def copied(tmp_path):
    """A copy of the notebooks and of the run-time record, to change without touching the repository's."""
    for path in (ROOT / "notebooks").glob("0*.ipynb"):
        shutil.copy(path, tmp_path / path.name)
    shutil.copy(ROOT / "notebooks" / "run_times.json", tmp_path / "run_times.json")
    return tmp_path


def load(folder, prefix):
    path = next(Path(folder).glob(f"{prefix}_*.ipynb"))
    return path, json.loads(path.read_text(encoding="utf-8"))


def save(path, nb):
    path.write_text(json.dumps(nb), encoding="utf-8")


def md(text, *tags, cell_id=None):
    return {"cell_type": "markdown", "id": cell_id or f"m{abs(hash(text)) % 10 ** 8}",
            "metadata": {"tags": list(tags)}, "source": text}


def code(text, cell_id, *tags):
    return {"cell_type": "code", "id": cell_id, "metadata": {"tags": list(tags)}, "source": text,
            "execution_count": None, "outputs": []}


def sessions_of(text):
    """``{"Session N": its text}`` of the plan or the answers."""
    parts = re.split(r"^## (Session \d+)[^\n]*\n", text, flags=re.M)
    return dict(zip(parts[1::2], parts[2::2]))


# --- the plan is the notebooks' --------------------------------------------------------------

def test_every_number_of_the_plan_agrees_with_the_notebooks(tool):
    assert tool.check_plan(PLAN.read_text(encoding="utf-8")) == []


def test_each_session_fits_90_minutes_with_at_least_10_of_teacher_talk(tool):
    """Recompute each session from its notebooks' parts at the plan's rates, then hold it to 90 minutes.

    A session is 15 minutes of teacher talk, in Session 1 5 minutes for the logins and the first
    run, its notebooks and a 5-minute quiz.
    """
    rows = tool.table()
    found = tool.sessions(rows)
    assert sorted(found) == ["Session 1", "Session 2"]
    assert [r.name[:2] for r in found["Session 1"].rows] == ["01", "02", "04"] and tool.BEFORE == {"Session 1": ("00",)}
    assert [r.name[:2] for r in found["Session 2"].rows] == ["05", "06", "07"]
    tenth = lambda x: math.ceil(round(x * 10, 9)) / 10                      # noqa: E731
    for s in found.values():
        notebooks = 0
        for r in s.rows:
            reading = tenth(r.plain_words / 130 + r.formula_words / 90)
            lines = tenth(r.code_lines / 15)
            run = tenth(r.run_s / 60)
            tasks = 6 * r.code + 5 * r.prediction + 5 * r.question + 3 * r.widget
            assert (reading, lines, run, tasks) == (r.reading_min, r.code_min, r.run_min, r.allowance_min), r.name
            total = math.ceil(round(reading + lines + (r.figures + r.tables) + run + tasks, 9))
            assert total == r.total_min, r.name
            notebooks += total
        first = s.name == "Session 1"
        assert (s.teacher_min, s.setup_min, s.board_min) == (15, 5 * first, 15 * first), s.name
        assert s.total_min == 15 + s.setup_min + s.board_min + notebooks + 5, s.name
        assert s.total_min <= 90, (f"{s.name}: {s.total_min} min with {s.teacher_min} of teacher talk: "
                                   "move what does not fit to homework (the cell tag 'homework')")
    assert tool.fit_problems(found) == []


def test_the_plan_states_the_model_and_the_teacher_talk(tool):
    """15 minutes of teacher talk a session, and 5 for the logins and the first run of Session 1."""
    text = PLAN.read_text(encoding="utf-8")
    rates = re.search(r"<!-- minutes:rates -->\n(.*?)<!-- /minutes:rates -->", text, re.S).group(1)
    for stated in ("| teacher talk | 15 min a session |", "| logins and first run | 5 min in Session 1 |",
                   "| derivation at the board | 15 min in Session 1 |",
                   "| plain prose | 130 words a minute |",
                   "| prose with formulas | 90 words a minute |", "| code | 15 lines a minute |",
                   "| figures and tables | 1 min each |", "| code exercise | 6 min each |",
                   "| prediction | 5 min each |", "| open question | 5 min each |", "| widget task | 3 min each |",
                   "| quiz | 5 min a session |"):
        assert stated in rates, stated
    last = lambda line: int(line.rstrip(" |").split("|")[-1])                    # noqa: E731
    for session, setup in (("Session 1", [5]), ("Session 2", [])):
        block = re.search(rf"<!-- minutes:{session} -->\n(.*?)<!-- /minutes:{session} -->", text, re.S).group(1)
        talk = next(line for line in block.splitlines() if "| teacher talk |" in line)
        assert last(talk) == 15, session
        assert [last(line) for line in block.splitlines() if "| logins and first run |" in line] == setup, session
    intro = text.split("## How the minutes are counted")[0]
    assert "15 minutes of teacher talk" in intro and "5 minutes for the logins and the first run" in intro and "runs 00, the tour, on their own before Session 1" in " ".join(intro.split())
    assert (tool.TEACHER_MIN, tool.SETUP_MIN, tool.BOARD_MIN, tool.LEAST_TEACHER_MIN) == \
        (15, {"Session 1": 5}, {"Session 1": 15}, 10)


# --- the checks can fail ---------------------------------------------------------------------

@pytest.fixture
def small(tmp_path, tool):
    """Seven small notebooks that fit both sessions, with a record measured for them."""
    record = {"date": "2026-01-01T00:00:00Z", "command": "test", "cpus": 2, "load_before": [0, 0, 0],
              "order": [], "notebooks": {}}
    for prefix in ("00", "01", "02", "04", "05", "06", "07"):
        cells = [md("# A notebook\n\n## Overview\n\n" + "word " * 520),
                 code("x = 1\nprint(x)", f"c{prefix}"),
                 md("## Exercises\n\n**1.** Fix it."), code("x = 2  # a first try: fix it", f"e{prefix}")]
        nb = {"nbformat": 4, "nbformat_minor": 5, "metadata": {}, "cells": cells}
        save(tmp_path / f"{prefix}_small.ipynb", nb)
        record["notebooks"][f"{prefix}_small.ipynb"] = {
            "seconds": 30.0, "errors": 0, "code_sha": tool.code_hash(cells),
            "figures": {f"c{prefix}": 1}, "tables": {}, "widgets": {}}
    (tmp_path / "run_times.json").write_text(json.dumps(record))
    return tmp_path


def test_a_session_over_90_minutes_is_caught(tool, small):
    """Each small notebook is 4.1 + 0.2 + 1 + 0.5 + 6 = 11.8 -> 12 min.

    Session 1, three of them (00 is run before it): 15 teacher + 5 logins + 15 at the board
    + 36 + 5 quiz = 76; Session 2, three: 15 + 36 + 5 = 56.
    """
    rows = tool.table(small, small / "run_times.json")
    assert [r.total_min for r in rows] == [12] * 7
    found = tool.sessions(rows)
    assert found["Session 1"].total_min == 76 and found["Session 2"].total_min == 56
    assert tool.fit_problems(found) == []
    # 2,600 more words of plain prose in 01: 20 minutes more, and Session 1 is 96: over
    path, nb = load(small, "01")
    nb["cells"].insert(1, md("word " * 2600))
    save(path, nb)
    found = tool.sessions(tool.table(small, small / "run_times.json"))
    assert found["Session 1"].total_min == 96
    assert tool.fit_problems(found) == ["Session 1: 96 min with the teacher talk, over 90 by 6"]
    # tagged homework, the same cell leaves the in-class path
    nb["cells"][1]["metadata"]["tags"] = ["homework"]
    save(path, nb)
    assert tool.fit_problems(tool.sessions(tool.table(small, small / "run_times.json"))) == []
    # 900 words of formula prose (90 a minute) in 02: 10 minutes more
    path, nb = load(small, "02")
    nb["cells"].insert(1, md("$x$ " + "word " * 899))
    save(path, nb)
    assert tool.sessions(tool.table(small, small / "run_times.json"))["Session 1"].total_min == 86


def test_too_little_teacher_talk_is_caught(tool, small):
    rows = tool.table(small, small / "run_times.json")
    assert tool.fit_problems(tool.sessions(rows, teacher_min=9)) == [
        "Session 1: 9 min of teacher talk, under 10", "Session 2: 9 min of teacher talk, under 10"]


def test_a_wrong_number_in_the_plan_is_caught(tool):
    text = PLAN.read_text(encoding="utf-8")
    total = re.search(r"\| \| \*\*sum\*\* \|.*\| \*\*(-?\d+)\*\* \|", text)              # Session 1's sum row
    off = total.group(0).replace(f"**{total.group(1)}**", f"**{int(total.group(1)) - 1}**")
    problems = tool.check_plan(text.replace(total.group(0), off, 1))
    assert len(problems) == 1 and problems[0].startswith("Session 1: sum: the plan says"), problems
    rate = text.replace("| plain prose | 130 words a minute |", "| plain prose | 150 words a minute |")
    assert any(p.startswith("rates: plain prose") for p in tool.check_plan(rate))
    gone = re.sub(r"<!-- minutes:where -->.*?<!-- /minutes:where -->\n", "", text, flags=re.S)
    assert "where: no <!-- minutes:where --> block in the plan" in tool.check_plan(gone)


def test_more_words_or_a_homework_tag_change_the_plan(tool, copied):
    """More words in a session's notebook, then its first in-class code exercise moved to homework."""
    plan = PLAN.read_text(encoding="utf-8")
    record = tool.read_record(copied / "run_times.json")["notebooks"]
    rows = tool.table(copied, copied / "run_times.json")
    row = next((r for r in rows if r.name[:2] in tool.SESSIONS["Session 1"] and r.code), None)
    assert row is not None, "no notebook of Session 1 has a code exercise in class"
    path, nb = load(copied, row.name[:2])
    before = tool.minutes(path, record[path.name])
    overview = next(c for c in nb["cells"] if "## Overview" in "".join(c["source"]))
    overview["source"] = "".join(overview["source"]) + "\n\n" + "word " * 300
    save(path, nb)
    problems = tool.check_plan(plan, copied, copied / "run_times.json")
    assert any(p.startswith(f"notebooks: {row.name}") for p in problems), problems
    assert any(p.startswith(f"Session 1: {row.name}") for p in problems), problems
    assert not any("measure again" in p for p in problems), problems        # markdown needs no new run
    # the exercise (its text, starter and the grader's test) to homework
    cells = nb["cells"]
    exercise = next(e for e in tool.exercises(cells) if e.kind == "code" and not e.homework)
    assert [e.cell for e in tool.exercises(cells)].count(exercise.cell) == 1, "the exercise shares its cell"
    test = [n for n, c in enumerate(cells)
            if "".join(c["source"]).startswith(f"# The grader's test of exercise {exercise.number}")]
    for n in [exercise.cell, exercise.cell + 1] + test:
        cells[n]["metadata"]["tags"] = ["homework"]
    cells[exercise.cell]["source"] = "### Homework\n\n" + "".join(cells[exercise.cell]["source"])
    save(path, nb)
    after = tool.minutes(path, record[path.name])
    assert (after.code, after.homework) == (before.code - 1, tuple(sorted(before.homework + (exercise.number,))))
    assert after.allowance_min == before.allowance_min - 6 and after.code_lines < before.code_lines
    assert tool.marking_problems(cells) == []
    text = tool.write_plan(plan, tool.plan_blocks(copied, copied / "run_times.json"))
    assert f"{row.name[:2]} ex. {', '.join(map(str, after.homework))}" in text.split("<!-- /minutes:Session 1 -->")[0]
    assert tool.check_plan(text, copied, copied / "run_times.json") == []


def test_a_changed_code_cell_makes_the_record_stale(tool, copied):
    path, nb = load(copied, "07")
    assert tool.stale(copied, copied / "run_times.json") == []
    cell = next(c for c in nb["cells"] if c["cell_type"] == "markdown")
    cell["metadata"]["tags"] = ["homework"]                                  # a tag: not stale
    save(path, nb)
    assert tool.stale(copied, copied / "run_times.json") == []
    cell = next(c for c in nb["cells"] if c["cell_type"] == "code")
    cell["source"] = "".join(cell["source"]) + "\nprint('one more line')"
    save(path, nb)
    assert tool.stale(copied, copied / "run_times.json") == [path.name]
    problems = tool.check_plan(PLAN.read_text(encoding="utf-8"), copied, copied / "run_times.json")
    assert f"{path.name}: its code changed since {copied / 'run_times.json'} was measured: run --measure again" \
        in problems


def test_unmarked_homework_and_split_exercises_are_caught(tool):
    cells = [md("## Try it"), code("x = 1", "a", "homework"),
             md("## Exercises\n\n**1.** Fix it.", "homework"), code("x = 2  # fix", "b"),
             md("**2. Predict first.** What?"), md("YOUR ANSWER HERE", "homework"), md("Then run it.")]
    assert tool.marking_problems(cells) == [
        "c1 is tagged homework but follows no '### Homework' heading or '**Homework.**'",
        "c2 is tagged homework but follows no '### Homework' heading or '**Homework.**'",
        "c5 is tagged homework but follows no '### Homework' heading or '**Homework.**'",
        "exercise 1 (c2) is homework but c3 is not",
        "exercise 2 (c4) is in class but c5 is not"]
    cells[1] = md("### Homework\n\nAt home.", "homework")
    assert tool.marking_problems(cells)[0].startswith("c5 is tagged")


def test_what_nbgrader_grades_is_read_from_the_cells(tool):
    """A hidden test makes an exercise autograded, a grade cell with a solution hand-graded; else it is not graded."""
    def cell(kind, text, **grader):
        return {"cell_type": kind, "source": text, "metadata": {"nbgrader": grader} if grader else {}}

    cells = [cell("markdown", "## Exercises\n\n**1.** Fix the starter."), cell("code", "x = 2  # fix me"),
             cell("code", "# The grader's test of exercise 1\nassert x", grade=True, solution=False),
             cell("markdown", "**2.** Why?\n\n**3. Predict first.** What?"),
             cell("markdown", "YOUR ANSWER HERE", grade=True, solution=True),
             cell("markdown", "**4.** Label ten pairs."), cell("markdown", "Your answer", grade=False, solution=False),
             cell("markdown", "**5.** Fix this too."), cell("code", "y = 0  # fix", grade=False, solution=True)]
    assert tool.grading(cells) == {"auto": [(1, 2)], "hand": [(3, 4)], "none": [(2, 3), (4, 5), (5, 7)]}
    cells[4]["metadata"]["nbgrader"]["grade"] = False                     # the answer cell is no longer graded
    assert tool.grading(cells)["none"] == [(2, 3), (3, 3), (4, 5), (5, 7)]


def test_a_changed_grade_cell_changes_the_plan(tool, copied):
    """The plan's table of what nbgrader grades follows the notebooks: an answer cell that stops being graded shows."""
    assert "| `09_your_own_photos` | none |" in PLAN.read_text(encoding="utf-8")       # 09 is no assignment
    hand = None
    for path in sorted(copied.glob("0*.ipynb")):
        nb = json.loads(path.read_text(encoding="utf-8"))
        found = tool.grading(nb["cells"])["hand"]
        if found and path.name in tool._assignments():
            hand = path, nb, found[0][1]
            break
    assert hand is not None, "no notebook of an assignment has an answer cell graded by hand"
    path, nb, n = hand
    nb["cells"][n]["metadata"]["nbgrader"]["grade"] = False
    save(path, nb)
    problems = tool.check_plan(PLAN.read_text(encoding="utf-8"), copied, copied / "run_times.json")
    assert any(p.startswith(f"graded: {path.stem}") for p in problems), problems


@pytest.mark.parametrize("name", sorted(p.name for p in (ROOT / "notebooks").glob("0*.ipynb")))
def test_every_homework_cell_is_marked_and_no_exercise_is_split(tool, name):
    cells = json.loads((ROOT / "notebooks" / name).read_text(encoding="utf-8"))["cells"]
    assert tool.marking_problems(cells) == []


# --- what is counted -------------------------------------------------------------------------

def test_words_code_lines_tables_and_exercises_are_counted_from_the_cells(tool):
    text = tool.markdown("## Try it\n\nMove the sliders (`k`, σ).\n\n    ismb-lab evaluate m.json\n\n"
                         "* a list item with $x$\n* and one without\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n"
                         "![a figure](f.png)")
    assert (text.plain_words, text.formula_words, text.code_lines, text.tables, text.images) == (10, 5, 1, 1, 1)
    student = tool.student_code("y = 1  # a first try: fix it\n### BEGIN SOLUTION\ny = 2\nz = 3\n### END SOLUTION\n"
                                "\nprint(y)")
    assert student.splitlines() == ["y = 1  # a first try: fix it", "# YOUR CODE HERE", "", "print(y)"]
    assert tool.code_lines("# The grader's test (hidden in your copy).\n### BEGIN HIDDEN TESTS\nassert y\n"
                           "### END HIDDEN TESTS") == 1
    cells = [md("## Exercises\n\n**1.** Fix the starter."), code("x = 2   # fix me", "s"),
             md("**2.** Why?\n\n**3. Predict first.** Then run.", "homework")]
    assert [(e.number, e.kind, e.homework) for e in tool.exercises(cells)] == [
        (1, "code", False), (2, "question", True), (3, "prediction", True)]


def test_figures_tables_and_widget_tasks_are_counted_from_the_outputs(tool):
    state = {
        "box": {"model_name": "VBoxModel", "state": {"children": ["IPY_MODEL_canvas", "IPY_MODEL_plot",
                                                                  "IPY_MODEL_out"]}},
        "canvas": {"model_name": "MPLCanvasModel", "state": {"toolbar": "IPY_MODEL_bar"}},
        "bar": {"model_name": "ToolbarModel", "state": {}},
        "plot": {"model_name": "AnyModel", "state": {"_anywidget_id": "k3d.plot.Plot"}},
        "out": {"model_name": "OutputModel", "state": {"outputs": [{"data": {"image/png": "…"}}]}},
        "alone": {"model_name": "MPLCanvasModel", "state": {}},
    }
    view = lambda model: {"output_type": "display_data",                     # noqa: E731
                          "data": {"application/vnd.jupyter.widget-view+json": {"model_id": model}}}
    table = "a 1 2\nb 3 4\nc 5 6\n"
    cell = {"cell_type": "code", "outputs": [
        {"output_type": "stream", "name": "stdout", "text": table[:8]},      # one table in two messages
        {"output_type": "stream", "name": "stdout", "text": table[8:]},
        {"output_type": "stream", "name": "stderr", "text": table},          # warnings are no table
        view("box"), view("alone"),
        {"output_type": "display_data", "data": {"image/png": "…", "text/plain": "<Figure>"}},
        {"output_type": "execute_result", "data": {"text/html": "<table></table><table></table>"}}]}
    assert tool.shown(cell, state) == {"figures": 5, "tables": 3, "widgets": 1}
    assert tool.shown({"outputs": [view("alone")]}, state) == {"figures": 1, "tables": 0, "widgets": 0}
    assert tool.printed_tables("x = 1\ny = 2\nz = 3") == 0                  # one number a line: prose
    assert tool.printed_tables("1 2\n3 4\n\n5 6\n7 8\n9 10") == 1


def test_the_run_times_record_how_they_were_measured(tool):
    data = json.loads(tool.RUN_TIMES.read_text(encoding="utf-8"))
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", data["date"])
    assert "--measure" in data["command"] and data["cpus"] >= 1 and len(data["load_before"]) == 3
    names = sorted(p.name for p in (ROOT / "notebooks").glob("0*.ipynb"))
    assert sorted(data["notebooks"]) == names
    assert data["order"] == [n[:2] for n in tool.order(names)] and data["order"][0] == "00"
    for name, entry in data["notebooks"].items():
        assert entry["seconds"] > 0 and entry["errors"] == 0, name
        assert len(entry["load_before"]) == len(entry["load_after"]) == 3, name
        ids = {c["id"] for c in json.loads((ROOT / "notebooks" / name).read_text(encoding="utf-8"))["cells"]
               if c["cell_type"] == "code"}
        for key in ("figures", "tables", "widgets"):
            assert set(entry[key]) <= ids, (name, key)


# --- the rest of the plan ---------------------------------------------------------------------

def test_the_plan_names_each_notebook_by_its_title():
    """05 is the explorer and 06 the GA: the takeaways' headings are the notebooks' own titles."""
    text = PLAN.read_text(encoding="utf-8").split("## Per notebook")[1].split("## Glossary")[0]
    named = dict(re.findall(r"^\*\*(\d\d) · (.+?)\*\*", text, re.M))
    assert sorted(named) == [f"0{n}" for n in range(10)]
    for prefix, label in named.items():
        path = next((ROOT / "notebooks").glob(f"{prefix}_*.ipynb"))
        title = "".join(json.loads(path.read_text(encoding="utf-8"))["cells"][0]["source"]).splitlines()[0]
        title = re.split(r"[:(]", title.split(" · ", 1)[1])[0].strip()
        assert label.rstrip(".").strip() == title, (prefix, label, title)


def test_each_session_has_objectives_prerequisites_a_quiz_of_five_and_references():
    plan = sessions_of(PLAN.read_text(encoding="utf-8"))
    answers = sessions_of(ANSWERS.read_text(encoding="utf-8"))
    assert sorted(plan) == sorted(answers) == ["Session 1", "Session 2"]
    for name, text in plan.items():
        for part in ("**Learning objectives.**", "**Prerequisites.**", "**Quiz**", "**References.**"):
            assert part in text, (name, part)
        quiz = text.split("**Quiz**")[1].split("**References.**")[0]
        assert re.findall(r"^(\d)\. ", quiz, re.M) == list("12345"), name
        assert re.findall(r"^(\d)\. ", answers[name], re.M) == list("12345"), name
        references = text.split("**References.**")[1]
        assert len(re.findall(r"^\* ", references, re.M)) >= 4, name
    # the answers are held apart: in the folder the students' servers never get
    from ismb_lab.teaching.hub_start import IGNORE

    assert ANSWERS.parent.name in IGNORE
    assert "QUIZ_ANSWERS" not in "".join(plan.values()).split("**Quiz**")[0]


def test_the_plan_promises_no_stop_of_the_ga_runner():
    """The runner finishes its 500 generations in seconds: there is no "stop it after 50" to do."""
    text = PLAN.read_text(encoding="utf-8")
    assert "50 generations" not in text and "stop it after" not in text
    assert "tolerant S with a strict C" not in text


def glossary(text):
    rows = text.split("## Glossary")[1].split("\n## ")[0]
    return {c[0]: c for c in (r.strip("|").split("|") for r in rows.splitlines() if r.startswith("| "))}


def test_the_glossary_defines_both_ms_and_annealing_and_cites_the_sections_that_hold_them():
    rows = glossary(PLAN.read_text(encoding="utf-8"))
    cite = {name.strip(): row[-1] for name, row in rows.items()}
    assert "(2-5)" in cite["M (in R)"] and "(3-8)" in cite["M_ik (M in S)"]
    assert "annealing" in cite and "ch. 6" in cite["annealing"]
    assert "§5.2 " in cite["image pair"] + " " and "§5.1" not in cite["target"]
    assert "§5.2.1" in cite["target"] and "§5.2.1" in cite["p_c, p_m"] and "§5.1" in cite["d, Z, f, B"]
    # the thesis prints C/E/T and the accurate rate; the names of the error's summands are this project's
    assert "this project" in cite["C/E/T"] and "this project" in cite["C/T, precision"]


@pytest.mark.skipif(not THESIS.is_dir(), reason="the thesis text (shared/thesis) is not beside the repository")
def test_the_corrected_citations_point_where_the_thesis_says_it():
    """Each fact the corrected rows cite lies in the cited section of the thesis' text."""
    text = "\n".join(p.read_text(encoding="utf-8") for p in sorted(THESIS.glob("*.txt")))
    heads = [(m.start(), m.group(1)) for m in re.finditer(r"^\s*(\d\.\d(?:\.\d)?) [A-Z]", text, re.M)]
    heads.append((text.index("Chapter 6"), "6"))

    def section(fact):
        at = text.index(fact)
        return [name for start, name in heads if start <= at][-1]

    assert section("$p_c=0.8$") == "5.2.1"                 # p_c, p_m: the values
    assert section("mutation rate p_m") == "4.2"            # p_c, p_m: the meaning
    assert section("To establish the target of the matching problem by user") == "5.2.1"
    assert section("a target for the stereo matching problem is established by user") == "4.2"
    assert section("240×320 pixels") == "5.2"               # the image pairs
    assert section("equal to 10 cm") == "5.1"               # B
    assert section("The feature point with large disparity is more closed") == "5.2.3"
    assert section("the training results are the results using another parameters") == "5.2.2"
    assert section("Accurate rate 125/137") == "5.2.2"      # C/T: Fig. 5.10's accurate rate
    assert "fB" not in text.replace(" ", "") and "f·B" not in text   # Z = f·B/d is not written out
    assert "wrong partner" not in text and "extra" not in text.lower().replace("extract", "")


def test_a_board_cell_is_read_at_the_board_not_twice(tool, copied):
    """02's derivation is tagged ``board``: Session 1 gives it BOARD_MIN at the board, and the
    notebook's reading leaves it out; without the tag its words count as reading again."""
    record = tool.read_record(copied / "run_times.json")["notebooks"]
    path, nb = load(copied, "02")
    board = [c for c in nb["cells"] if tool.BOARD in c.get("metadata", {}).get("tags", [])]
    assert len(board) == 1 and "## Thesis section and equations" in "".join(board[0]["source"])
    before = tool.minutes(path, record[path.name])
    board[0]["metadata"]["tags"].remove(tool.BOARD)
    save(path, nb)
    after = tool.minutes(path, record[path.name])
    assert after.formula_words > before.formula_words and after.reading_min > before.reading_min + 3
