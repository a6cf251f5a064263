"""scripts/lesson_minutes.py on the command line, and its --measure on a tiny notebook."""

import json
import math
import re
import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "notebooks" / "LESSON_PLAN.md"


@pytest.fixture(scope="module")
def tool(load_script):
    return load_script("lesson_minutes")


def test_help_names_every_option(tool, capsys):
    with pytest.raises(SystemExit) as done:
        tool.main(["--help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    for option in ("--notebooks", "--run-times", "--json", "--check-plan", "--measure"):
        assert option in out


def test_the_table_lists_every_notebook_with_its_total(tool, capsys):
    assert tool.main([]) == 0
    lines = capsys.readouterr().out.splitlines()
    names = sorted(p.stem for p in (ROOT / "notebooks").glob("0*.ipynb"))
    assert [line.split()[0] for line in lines[1:]] == names
    assert tool.main(["--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    for row in rows:
        parts = row["reading_min"] + row["code_min"] + row["figures_min"] + row["run_min"] + row["allowance_min"]
        assert row["total_min"] == math.ceil(round(parts, 9))
        assert row["reading_min"] == math.ceil(round((row["plain_words"] / tool.PLAIN_WPM
                                                      + row["formula_words"] / tool.FORMULA_WPM) * 10, 9)) / 10


def test_sessions_count_the_teacher_talk_the_logins_and_the_quiz(tool, capsys):
    assert tool.main(["--json", "--sessions"]) == 0
    found = json.loads(capsys.readouterr().out)
    totals = {row["name"]: row["total_min"] for row in found["notebooks"]}
    for name, s in found["sessions"].items():
        first = name == "Session 1"
        assert (s["teacher_min"], s["setup_min"], s["board_min"], s["quiz_min"]) == (15, 5 * first, 15 * first, 5), name
        notebooks = sum(totals[n] for n in s["notebooks"])
        assert s["total_min"] == s["teacher_min"] + s["setup_min"] + s["board_min"] + s["quiz_min"] + notebooks, name
    assert tool.main(["--sessions"]) == 0
    assert "Session 1: 15 teacher + 5 logins and first run + 15 derivation at the board + " in capsys.readouterr().out


def test_check_plan_exits_1_on_a_false_plan(tool, tmp_path, capsys):
    assert tool.main(["--check-plan", str(PLAN)]) == 0
    wrong = tmp_path / "plan.md"
    text = PLAN.read_text(encoding="utf-8")
    total = re.search(r"\| \| \*\*sum\*\* \|.*\| \*\*(\d+)\*\* \|", text)       # session 1's sum row
    wrong.write_text(text.replace(total.group(0), total.group(0).replace(f"**{total.group(1)}**",
                                                                         f"**{int(total.group(1)) - 5}**")),
                     encoding="utf-8")
    assert tool.main(["--check-plan", str(wrong)]) == 1
    assert "Session 1: sum" in capsys.readouterr().out


def test_missing_run_times_give_one_line_and_exit_2(tool, tmp_path, capsys):
    assert tool.main(["--run-times", str(tmp_path / "none.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("lesson_minutes.py: ")
    partial = tmp_path / "partial.json"
    partial.write_text(json.dumps({"notebooks": {"00_start_here.ipynb": {"seconds": 3.0}}}))
    assert tool.main(["--run-times", str(partial)]) == 2
    assert "no measured time for 01_harris_features.ipynb" in capsys.readouterr().err


def test_measure_never_replaces_a_symlink(tool, tmp_path, capsys):
    target = tmp_path / "kept.json"
    target.write_text("{}")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    assert tool.main(["--measure", str(link)]) == 2
    assert "will not replace" in capsys.readouterr().err and target.read_text() == "{}"


@pytest.mark.slow          # starts one kernel (a few seconds)
def test_measure_runs_a_copy_and_records_the_time(tool, tmp_path):
    root = tmp_path / "repo"
    for name in tool.COPIED:
        (root / name).mkdir(parents=True)
    nb = {"nbformat": 4, "nbformat_minor": 5, "metadata": {}, "cells": [
        {"cell_type": "markdown", "id": "a", "metadata": {}, "source": "One cell writes a file beside itself."},
        {"cell_type": "code", "id": "b", "metadata": {}, "execution_count": None, "outputs": [],
         "source": "import os, time\nopen('written.txt', 'w').write(os.environ['NUMBA_CACHE_DIR'])\ntime.sleep(1)"}]}
    (root / "notebooks" / "00_tiny.ipynb").write_text(json.dumps(nb))
    before = dict(os.environ)
    out = tmp_path / "times.json"
    record = tool.measure(root, out, "test")
    assert json.loads(out.read_text()) == record
    entry = record["notebooks"]["00_tiny.ipynb"]
    assert entry["errors"] == 0 and entry["seconds"] >= 1.0
    assert not (root / "notebooks" / "written.txt").exists()        # it ran in the copy
    assert dict(os.environ) == before                                # the environment is restored


def test_the_docstring_examples_hold(tool):
    import doctest

    result = doctest.testmod(tool)
    assert result.attempted >= 4 and result.failed == 0
