"""The minutes a class spends on each notebook: reading, running, and the exercises.

For each teaching notebook (``notebooks/0*.ipynb``) the tool prints

* the words a student reads: the words of the markdown cells (a fenced code block in a
  markdown cell is code, not counted; a word is a run of characters between spaces that
  holds a letter or a digit);
* the reading minutes, those words at :data:`WPM` words a minute;
* the measured run time of *Restart & Run All* (a fresh kernel, the compiled kernels not yet
  cached at the first notebook), read from a JSON file that ``--measure`` writes;
* the exercises of its ``## Exercises`` section by kind, the widget tasks before it, and the
  allowance for them (:data:`ALLOWANCE`);
* the total: reading + run + allowance, each rounded up to whole minutes first.

``--check-plan`` compares the tables of the lesson plan with those figures
(:func:`check_plan`): the plan's sessions name the exercises done in class, and each
session's steps, sum and buffer must be what the notebooks give.

``--measure FILE`` executes every notebook once, one at a time, each in a fresh kernel, in a
copy of the repository's layout (``notebooks/``, ``images/``, ``manifests/`` in a temporary
folder: the notebooks write files next to themselves) with an empty numba cache, and writes
the wall time of each with the load average, the date and the command to FILE.

    python scripts/lesson_minutes.py                          # the table, from notebooks/run_times.json
    python scripts/lesson_minutes.py --json                   # the same as JSON
    python scripts/lesson_minutes.py --check-plan notebooks/LESSON_PLAN.md   # is the plan true?
    python scripts/lesson_minutes.py --measure notebooks/run_times.json   # run all ten (minutes)
"""

import argparse
import datetime
import json
import math
import os
import re
import shutil
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = ROOT / "notebooks"
RUN_TIMES = NOTEBOOKS / "run_times.json"
PATTERN = "0*.ipynb"
COPIED = ("notebooks", "images", "manifests")

#: Reading speed of a student, words a minute (the issue's figure for technical text).
WPM = 130

#: Minutes allowed for one exercise or widget task, by kind, with the reason.
ALLOWANCE = {
    "code": 6,         # read the starter and the check's hint, fix one line, run again: two tries
    "prediction": 5,   # write a prediction, run the cell that reveals it, one sentence on the difference
    "question": 5,     # an open question: look up a table or change one argument, write two sentences
    "widget": 3,       # one widget to try before the exercises: a few clicks or slider moves, read the status
}

#: A session's length, and the least buffer it keeps for what no allowance foresees.
SESSION_MIN, BUFFER_MIN = 90, 10
#: The quiz of a session: five short questions answered on paper, a minute each.
QUIZ_MIN = 5

#: An exercise starts a line of the Exercises section with its bold number: ``**2.**``, ``**4. Predict first.**``.
_EXERCISE = re.compile(r"^\*\*(\d+)\.(.*?)\*\*", re.M)
_FENCE = re.compile(r"```.*?```", re.S)
#: A code cell that makes a widget a student works with: the package's widgets, or ipywidgets' controls.
_WIDGET = re.compile(r"\b(TargetLabeler|HopfieldStepper|GARunner|ParameterExplorer|DepthDemo|PointCloudView|"
                     r"\w*Slider|SelectMultiple|Dropdown|Button|Checkbox|ToggleButtons|FileUpload)\s*[.(]")


@dataclass(frozen=True)
class Minutes:
    """The minutes of one notebook for the exercises `chosen`; every ``*_min`` is rounded up."""

    name: str
    words: int
    reading_min: int
    run_s: float
    run_min: int
    code: int
    prediction: int
    question: int
    widget: int
    allowance_min: int
    total_min: int
    chosen: tuple = ()


def words(text: str) -> int:
    """The words of a markdown text, fenced code blocks left out.

    >>> words("The energy $E$ never rises.\\n\\n```python\\nrun(net)\\n```\\n| a | b |")
    7
    """
    return sum(1 for token in _FENCE.sub(" ", text).split() if re.search(r"\w", token))


def _source(cell) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def _exercise_start(cells: list) -> int:
    return next((n for n, c in enumerate(cells) if c["cell_type"] == "markdown"
                 and re.search(r"^## Exercises\s*$", _source(c), re.M)), len(cells))


def exercise_kinds(cells: list) -> dict:
    """``{number: kind}`` of the exercises of a notebook's cells (nbformat dicts).

    An exercise is a bold number at the start of a line of the ``## Exercises`` section; it
    is a ``prediction`` when its bold title says "Predict", else ``code`` when it is the last
    exercise of its markdown cell and the next cell is a starter (a code cell that says "fix"),
    else a ``question``.

    >>> md = lambda s: {"cell_type": "markdown", "source": s}
    >>> exercise_kinds([md("## Exercises\\n\\n**1.** Fix it."), {"cell_type": "code", "source": "x = 0  # fix me"},
    ...                 md("**2.** Why?\\n\\n**3. Predict first.** Then run.")])
    {1: 'code', 2: 'question', 3: 'prediction'}
    """
    kinds = {}
    for n in range(_exercise_start(cells), len(cells)):
        if cells[n]["cell_type"] != "markdown":
            continue
        found = _EXERCISE.findall(_source(cells[n]))
        starter = n + 1 < len(cells) and cells[n + 1]["cell_type"] == "code" \
            and "fix" in _source(cells[n + 1]).lower()
        for index, (number, title) in enumerate(found):
            if "predict" in title.lower():
                kind = "prediction"
            elif starter and index == len(found) - 1:
                kind = "code"
            else:
                kind = "question"
            kinds[int(number)] = kind
    return kinds


def widget_tasks(cells: list) -> int:
    """The code cells before the ``## Exercises`` section that make a widget (:data:`_WIDGET`).

    >>> widget_tasks([{"cell_type": "code", "source": "s = w.FloatSlider(value=1)"},
    ...               {"cell_type": "code", "source": "stepper = HopfieldStepper(p)"},
    ...               {"cell_type": "markdown", "source": "## Exercises"},
    ...               {"cell_type": "code", "source": "TargetLabeler.from_photos()"}])
    2
    """
    return sum(1 for c in cells[:_exercise_start(cells)]
               if c["cell_type"] == "code" and _WIDGET.search(_source(c)))


def read_run_times(path: Path) -> dict:
    """The measured seconds per notebook name, from a file that ``--measure`` wrote."""
    data = json.loads(Path(path).read_text(encoding="utf-8"))
    return {name: entry["seconds"] for name, entry in data["notebooks"].items()}


def minutes(path: Path, run_s: float, chosen=None) -> Minutes:
    """The :class:`Minutes` of the notebook at `path`, which runs in `run_s` seconds.

    `chosen` is the exercise numbers done in class (default: all of them); every widget task
    is done.  Reading covers the whole notebook, the exercises' text included.
    """
    cells = json.loads(Path(path).read_text(encoding="utf-8"))["cells"]
    kinds = exercise_kinds(cells)
    chosen = tuple(sorted(kinds)) if chosen is None else tuple(sorted(chosen))
    unknown = [n for n in chosen if n not in kinds]
    if unknown:
        raise ValueError(f"chosen: {Path(path).stem} has no exercise {unknown} (it has {sorted(kinds)})")
    counts = dict.fromkeys(("code", "prediction", "question"), 0)
    for n in chosen:
        counts[kinds[n]] += 1
    counts["widget"] = widget_tasks(cells)
    n_words = sum(words(_source(c)) for c in cells if c["cell_type"] == "markdown")
    reading, run = math.ceil(n_words / WPM), math.ceil(run_s / 60)
    allowance = sum(ALLOWANCE[k] * v for k, v in counts.items())
    return Minutes(Path(path).stem, n_words, reading, run_s, run, **counts,
                   allowance_min=allowance, total_min=reading + run + allowance, chosen=chosen)


def table(folder: Path = NOTEBOOKS, run_times: Path = RUN_TIMES) -> list[Minutes]:
    """The :class:`Minutes` of every notebook of `folder` with all its exercises, in name order."""
    seconds = read_run_times(run_times)
    paths = sorted(Path(folder).glob(PATTERN))
    missing = [p.name for p in paths if p.name not in seconds]
    if missing:
        raise ValueError(f"run_times: no measured time for {', '.join(missing)} in {run_times}")
    return [minutes(p, seconds[p.name]) for p in paths]


def format_table(rows: list[Minutes]) -> str:
    """The rows as a plain text table."""
    head = ("notebook", "words", "read", "run s", "run", "code", "pred", "quest", "widget", "allow", "total")
    lines = ["{:<26} {:>5} {:>4} {:>6} {:>3} {:>4} {:>4} {:>5} {:>6} {:>5} {:>5}".format(*head)]
    for r in rows:
        lines.append(f"{r.name:<26} {r.words:>5} {r.reading_min:>4} {r.run_s:>6.1f} {r.run_min:>3} {r.code:>4} "
                     f"{r.prediction:>4} {r.question:>5} {r.widget:>6} {r.allowance_min:>5} {r.total_min:>5}")
    return "\n".join(lines)


# --- the lesson plan's tables -------------------------------------------------------------

def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def _number(text: str):
    text = text.replace("*", "").strip()
    return float(text) if "." in text else int(text) if text.lstrip("-").isdigit() else None


def plan_tables(text: str) -> dict:
    """The plan's tables: ``{"every": [...], "Session 1": [...], ...}`` of rows as lists of cells.

    The table of every notebook follows a heading holding "every notebook", the allowances a
    heading holding "how the minutes"; a session's table follows a heading ``## Session N``.  Each table is the rows after its separator line.
    """
    tables, heading, rows, in_table = {}, None, None, False
    for line in text.splitlines():
        if line.startswith("#"):
            match = re.match(r"#+\s+(Session \d+)", line)
            lower = line.lower()
            heading = match.group(1) if match else "every" if "every notebook" in lower else \
                "allowance" if "how the minutes" in lower else None
            in_table = False
        elif line.startswith("|") and heading:
            if re.fullmatch(r"\|[\s:|-]+\|", line.strip()):
                rows = tables.setdefault(heading, [])
                in_table = True
            elif in_table:
                rows.append(_cells(line))
        else:
            in_table = False
    return tables


def homework(text: str) -> dict:
    """``{"Session N": {notebook prefix: {numbers}}}`` from each session's ``**Homework:**`` line."""
    found, heading = {}, None
    for line in text.splitlines():
        match = re.match(r"#+\s+(Session \d+)", line)
        if match:
            heading = match.group(1)
        elif line.startswith("**Homework:**") and heading:
            found[heading] = {nb: {int(n) for n in re.findall(r"\d+", numbers)}
                              for nb, numbers in re.findall(r"\b(\d\d) ex\. ([\d, ]+)", line)}
    return found


def check_plan(text: str, folder: Path = NOTEBOOKS, run_times: Path = RUN_TIMES,
               session_min: int = SESSION_MIN, buffer_min: int = BUFFER_MIN) -> list[str]:
    """Every way the plan's tables differ from the notebooks and the measured run times.

    Checks the allowances, the table of every notebook (all columns), and for each session: each step's
    words, reading, run, allowance and total minutes for the exercises it names in class
    (``ex. 1 code, 3 prediction``: numbers and kinds), the widget tasks (``2 widgets``), the
    quiz (:data:`QUIZ_MIN`), the sum, the buffer (``session_min`` minus the sum, at least
    ``buffer_min``), and that every exercise of a session's notebooks is in class or homework.
    An empty list means the plan is true.
    """
    seconds = read_run_times(run_times)
    paths = {p.stem: p for p in sorted(Path(folder).glob(PATTERN))}
    tables, problems = plan_tables(text), []
    stated = {kind: _number(row[1]) for row in tables.get("allowance", [])
              for kind in (*ALLOWANCE, "quiz") if kind in row[0]}
    if stated != {**ALLOWANCE, "quiz": QUIZ_MIN}:
        problems.append(f"allowances: plan {stated}, the tool's {ALLOWANCE} and quiz {QUIZ_MIN}")
    every = {r[0].strip("`"): r for r in tables.get("every", [])}
    if sorted(every) != sorted(paths):
        problems.append(f"table of every notebook: lists {sorted(every)}, the folder holds {sorted(paths)}")
    for name, row in every.items():
        if name not in paths:
            continue
        m = minutes(paths[name], seconds[paths[name].name])
        want = [m.words, m.reading_min, m.run_s, m.run_min, m.code, m.prediction, m.question, m.widget,
                m.allowance_min, m.total_min]
        got = [_number(c) for c in row[1:11]]
        if got != want:
            problems.append(f"table of every notebook, {name}: plan {got}, notebooks {want}")
    sessions = {k: v for k, v in tables.items() if k.startswith("Session")}
    if not sessions:
        problems.append("no session table")
    work = homework(text)
    for session, rows in sessions.items():
        total, named, steps = 0, {}, []
        for row in rows:
            label = row[1].strip("`* ")
            if label in paths:
                chosen = {int(n): k for n, k in re.findall(r"(\d+) (code|prediction|question)", row[5])}
                m = minutes(paths[label], seconds[paths[label].name], chosen=chosen)
                kinds = exercise_kinds(json.loads(paths[label].read_text(encoding="utf-8"))["cells"])
                wrong = {n: k for n, k in chosen.items() if kinds.get(n) != k}
                if wrong:
                    problems.append(f"{session}, {label}: exercises {wrong} in the plan, the notebook's are {kinds}")
                widgets = re.search(r"(\d+) widget", row[5])
                if (int(widgets.group(1)) if widgets else 0) != m.widget:
                    problems.append(f"{session}, {label}: widget tasks in the plan {row[5]!r}, notebook {m.widget}")
                want = [m.words, m.reading_min, m.run_min, m.allowance_min, m.total_min]
                got = [_number(row[i]) for i in (2, 3, 4, 6, 7)]
                if got != want:
                    problems.append(f"{session}, {label}: plan [words, read, run, allow, total] {got}, "
                                    f"notebooks {want}")
                total += m.total_min
                steps.append(m.total_min)
                named[label[:2]] = (set(kinds), set(chosen))
            elif label == "quiz":
                if [_number(row[6]), _number(row[7])] != [QUIZ_MIN, QUIZ_MIN]:
                    problems.append(f"{session}, quiz: plan {row[6:8]}, the quiz takes {QUIZ_MIN} min")
                total += QUIZ_MIN
                steps.append(QUIZ_MIN)
            elif label == "sum":
                if _number(row[7]) != total:
                    problems.append(f"{session}: sum {row[7]} in the plan, the steps add up to {total}")
                if [int(n) for n in re.findall(r"\d+", row[5])] != steps + [total]:
                    problems.append(f"{session}: the sum's arithmetic {row[5]!r}, the steps are {steps} = {total}")
            elif label.startswith("buffer"):
                if _number(row[7]) != session_min - total:
                    problems.append(f"{session}: buffer {row[7]} in the plan, {session_min} - {total} = "
                                    f"{session_min - total}")
                if [int(n) for n in re.findall(r"\d+", row[5])] != [session_min, total, session_min - total]:
                    problems.append(f"{session}: the buffer's arithmetic {row[5]!r}, want "
                                    f"{session_min} - {total} = {session_min - total}")
                if session_min - total < buffer_min:
                    problems.append(f"{session}: buffer {session_min - total} min, under {buffer_min}")
            else:
                problems.append(f"{session}: unknown step {label!r}")
        for prefix, (all_of, in_class) in named.items():
            left = all_of - in_class - work.get(session, {}).get(prefix, set())
            if left:
                problems.append(f"{session}: exercises {sorted(left)} of {prefix} are neither in class nor homework")
    return problems


def _run_once(path: Path, folder: Path, timeout: int) -> dict:
    """Wall seconds, load averages and error count of one Restart & Run All of `path`."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3", resources={"metadata": {"path": str(folder)}})
    load = os.getloadavg()
    start = time.perf_counter()
    client.execute()
    seconds = time.perf_counter() - start
    errors = sum(1 for c in nb.cells for o in c.get("outputs", []) if o.get("output_type") == "error")
    return {"seconds": round(seconds, 1), "load_before": [round(x, 2) for x in load],
            "load_after": [round(x, 2) for x in os.getloadavg()], "errors": errors}


def measure(root: Path, out: Path, command: str, timeout: int = 900) -> dict:
    """Run every notebook of `root` once in a copy of its layout; write and return the record."""
    record = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
              "command": command, "cpus": os.cpu_count(), "load_before": list(os.getloadavg()),
              "what": "wall seconds of one Restart & Run All per notebook (kernel start included), in name "
                      "order, each in a fresh kernel, one at a time; the numba cache empty at the first notebook "
                      "and kept for the next ones, as a student's server keeps it",
              "notebooks": {}}
    saved = {k: os.environ.get(k) for k in ("NUMBA_CACHE_DIR", "PYTHONPATH")}
    with tempfile.TemporaryDirectory(prefix="lesson-minutes-") as tmp:
        for name in COPIED:
            shutil.copytree(root / name, Path(tmp) / name)
        cache = Path(tmp) / "numba-cache"
        cache.mkdir()
        # the kernels inherit the environment: an empty numba cache, and this checkout's package
        os.environ["NUMBA_CACHE_DIR"] = str(cache)
        os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(root), saved["PYTHONPATH"]) if p)
        try:
            folder = Path(tmp) / "notebooks"
            for path in sorted(folder.glob(PATTERN)):
                record["notebooks"][path.name] = _run_once(path, folder, timeout)
                entry = record["notebooks"][path.name]
                print(f"{path.name}: {entry['seconds']} s, load {entry['load_before'][0]} -> "
                      f"{entry['load_after'][0]}", flush=True)
        finally:
            for key, value in saved.items():
                if value is None:
                    os.environ.pop(key, None)
                else:
                    os.environ[key] = value
    Path(out).write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    return record


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="lesson_minutes.py", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--notebooks", type=Path, default=NOTEBOOKS, help="folder of the notebooks (default notebooks/)")
    parser.add_argument("--run-times", type=Path, default=RUN_TIMES, help="measured run times (default notebooks/run_times.json)")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON")
    parser.add_argument("--check-plan", type=Path, metavar="PLAN",
                        help="compare the tables of PLAN (notebooks/LESSON_PLAN.md) with the notebooks; exit 1 on a difference")
    parser.add_argument("--measure", type=Path, metavar="FILE",
                        help="run every notebook once in a copy of the layout and write the times to FILE")
    args = parser.parse_args(argv)
    if args.measure:
        out = args.measure
        if out.is_symlink() or (out.exists() and (not out.is_file() or not os.access(out, os.W_OK))):
            print(f"lesson_minutes.py: --measure: will not replace {out}: a symlink, a device, a folder or "
                  "read-only", file=sys.stderr)
            return 2
        command = "python scripts/lesson_minutes.py --measure " + str(args.measure)
        measure(ROOT, args.measure, command)
        return 0
    try:
        if args.check_plan:
            problems = check_plan(args.check_plan.read_text(encoding="utf-8"), args.notebooks, args.run_times)
            print("\n".join(problems) or f"{args.check_plan}: every number agrees with the notebooks")
            return 1 if problems else 0
        rows = table(args.notebooks, args.run_times)
    except (OSError, ValueError, KeyError) as exc:
        print(f"lesson_minutes.py: {exc}", file=sys.stderr)
        return 2
    print(json.dumps([asdict(r) for r in rows], indent=1) if args.json else format_table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
