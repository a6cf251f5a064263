"""The lesson plan's minutes are the notebooks' minutes, and each session is complete.

Every number of notebooks/LESSON_PLAN.md's tables is recomputed here, at test time, from the
notebooks' text (words, exercises, widget tasks) and the measured run times of
notebooks/run_times.json, by scripts/lesson_minutes.py.  A notebook whose text changes, or an
exercise added, makes this test fail until the plan is updated.  Nothing is executed.
"""

import json
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
    """A copy of the notebooks, to change one without touching the repository's."""
    for path in (ROOT / "notebooks").glob("0*.ipynb"):
        shutil.copy(path, tmp_path / path.name)
    return tmp_path


def edit_cell(folder, name, find, change):
    """Apply `change` to the source of the first markdown cell of `name` that holds `find`."""
    path = next(folder.glob(f"{name}_*.ipynb"))
    nb = json.loads(path.read_text(encoding="utf-8"))
    cell = next(c for c in nb["cells"] if c["cell_type"] == "markdown" and find in "".join(c["source"]))
    cell["source"] = change("".join(cell["source"]))
    path.write_text(json.dumps(nb), encoding="utf-8")


def sessions(text):
    """``{"Session N": its text}`` of the plan or the answers."""
    parts = re.split(r"^## (Session \d+)[^\n]*\n", text, flags=re.M)
    return dict(zip(parts[1::2], parts[2::2]))


def test_every_number_of_the_plan_agrees_with_the_notebooks(tool):
    assert tool.check_plan(PLAN.read_text(encoding="utf-8")) == []


def test_the_plan_has_two_sessions_each_with_at_least_ten_minutes_of_buffer(tool):
    text = PLAN.read_text(encoding="utf-8")
    tables = tool.plan_tables(text)
    assert sorted(k for k in tables if k.startswith("Session")) == ["Session 1", "Session 2"]
    for name in ("Session 1", "Session 2"):
        buffer = next(r for r in tables[name] if r[1].strip("* ") == "buffer")
        assert tool._number(buffer[7]) >= tool.BUFFER_MIN, name
    # the same check with a 80-minute session finds the buffers too short
    short = tool.check_plan(text, session_min=80)
    assert any("under 10" in p for p in short), short


def test_more_words_in_a_notebook_are_caught(tool, copied):
    edit_cell(copied, "00", "## Overview", lambda s: s + "\n\n" + "word " * 300)
    problems = tool.check_plan(PLAN.read_text(encoding="utf-8"), folder=copied)
    assert any(p.startswith("table of every notebook, 00_start_here") for p in problems), problems
    assert any(p.startswith("Session 1, 00_start_here") for p in problems), problems


def test_a_new_exercise_is_caught(tool, copied):
    edit_cell(copied, "04", "## Exercises", lambda s: s + "\n\n**3.** One more question.")
    problems = tool.check_plan(PLAN.read_text(encoding="utf-8"), folder=copied)
    assert "Session 1: exercises [3] of 04 are neither in class nor homework" in problems, problems
    assert any(p.startswith("table of every notebook, 04_label_targets") for p in problems), problems


def test_a_wrong_sum_kind_or_allowance_in_the_plan_is_caught(tool):
    text = PLAN.read_text(encoding="utf-8")
    total = re.search(r"\| \| \*\*sum\*\* \|.*\| \*\*(\d+)\*\* \|", text).group(0)    # session 1's sum row
    assert "ex. 3 prediction 5" in text and "| code exercise | 6 |" in text
    off_by_one = re.sub(r"\*\*(\d+)\*\* \|$", lambda m: f"**{int(m.group(1)) - 1}** |", total)
    assert any("sum" in p for p in tool.check_plan(text.replace(total, off_by_one, 1)))
    kind = tool.check_plan(text.replace("ex. 3 prediction 5", "ex. 3 question 5"))
    assert any("02_hopfield_network: exercises {3: 'question'}" in p for p in kind), kind
    assert any(p.startswith("allowances") for p in tool.check_plan(text.replace("| code exercise | 6 |",
                                                                                "| code exercise | 4 |")))


def test_words_exercises_and_widget_tasks_are_counted_from_the_cells(tool):
    md = lambda s: {"cell_type": "markdown", "source": s}          # noqa: E731
    code = lambda s: {"cell_type": "code", "source": s}            # noqa: E731
    cells = [md("## Try it\n\nMove the sliders (`k`, σ)."), code("view = w.IntSlider(3)\nview"),
             code("demo = DepthDemo.from_folders(a, b)"), code("print(1)"),
             md("## Exercises\n\n**1.** Fix the starter.\n\n```python\nx = 1\n```"), code("x = 2   # fix me"),
             md("**2.** Why?\n\n**3. Predict first.** Then run."), code("TargetLabeler.from_photos()")]
    assert tool.exercise_kinds(cells) == {1: "code", 2: "question", 3: "prediction"}
    assert tool.widget_tasks(cells) == 2
    assert tool.words(cells[0]["source"]) == 7 and tool.words(cells[4]["source"]) == 5


def test_the_run_times_record_how_they_were_measured(tool):
    data = json.loads(tool.RUN_TIMES.read_text(encoding="utf-8"))
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", data["date"])
    assert "--measure" in data["command"] and data["cpus"] >= 1 and len(data["load_before"]) == 3
    names = sorted(p.name for p in (ROOT / "notebooks").glob("0*.ipynb"))
    assert sorted(data["notebooks"]) == names
    for name, entry in data["notebooks"].items():
        assert entry["seconds"] > 0 and entry["errors"] == 0, name
        assert len(entry["load_before"]) == len(entry["load_after"]) == 3, name


def test_each_session_has_objectives_prerequisites_a_quiz_of_five_and_references():
    plan = sessions(PLAN.read_text(encoding="utf-8"))
    answers = sessions(ANSWERS.read_text(encoding="utf-8"))
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
    from ismb_lab.hub_start import IGNORE

    assert ANSWERS.parent.name in IGNORE
    assert "QUIZ_ANSWERS" not in "".join(plan.values()).split("**Quiz**")[0]


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
    assert "fB" not in text.replace(" ", "") and "f·B" not in text   # Z = f·B/d is not written out
