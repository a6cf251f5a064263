"""What a notebook's text says about a figure it computes is what its own output shows."""

import re
from pathlib import Path

import pytest

pytestmark = pytest.mark.notebook
NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"


def output_text(nb) -> str:
    """Everything the notebook printed to stdout, and its cells' values.  Streams are joined as
    they are: a printed line can arrive in two stream messages (with a warning on stderr between
    them), which a newline between them would cut."""
    return "".join(o["text"] if o.get("output_type") == "stream" else o.get("data", {}).get("text/plain", "") + "\n"
                   for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
                   if o.get("name") != "stderr")


def test_05_sweep_shows_what_its_text_says(executed_notebook):
    """05's "What to notice" reads the sweep of the lab pair: a tolerant C adds errors and loses no
    target, a strict one removes the thesis' values' errors and loses none, θs loses targets at both
    ends (and adds errors at the tolerant one), every smaller λc changes the score (the smallest
    loses a target).  λs is not in the sweep (exercise 3 asks about it), and exercise 3's check
    shows one score over the gene's whole range."""
    text = output_text(executed_notebook("05_parameter_explorer.ipynb"))
    sweep = {gene: [(float(v), *map(int, s)) for v, *s in
                    re.findall(r"([\d.]+) -> (\d+)/(\d+)\+(\d+)/(\d+)", line)]
             for gene, line in re.findall(r"^ *(theta_c|theta_s|lambda_c|lambda_s): (.*)$", text, re.M)}
    assert set(sweep) == {"theta_c", "theta_s", "lambda_c"}, text
    assert "scored against the lab pair's answer key" in text, text      # the pair the text reads
    C = lambda row: row[1]
    E = lambda row: row[2] + row[3]
    tc = sweep["theta_c"]
    thesis = next(row for row in tc if row[0] == 17.97)
    T = thesis[4]
    tolerant, strict = [r for r in tc if r[0] > 17.97], [r for r in tc if r[0] < 17.97]
    assert E(thesis) == 2 and all(E(r) > E(thesis) and C(r) == C(thesis) == T for r in tolerant), tc
    assert all(E(r) == 0 and C(r) == T for r in strict), tc
    ts = sweep["theta_s"]
    assert C(ts[0]) < T and C(ts[-1]) < T and E(ts[-1]) > E(next(r for r in ts if r[0] == 24.02)), ts
    lc = sweep["lambda_c"]
    default = next(r for r in lc if r[0] == 6.37)
    assert all(r[1:] != default[1:] for r in lc if r[0] < 6.37) and C(lc[0]) < T, lc
    # exercise 3's check: every λs of the gene's range, one score, the thesis' values'
    from ismb_lab.tuning.fitness import gene_bounds

    bounds = gene_bounds("III")
    low, high = (float(b[bounds.names.index("lambda_s")]) for b in (bounds.low, bounds.high))
    found = re.findall(r"^C/E/T = (\S+) at (\d+) of (\d+) values of λs, ([\d.]+) to ([\d.]+)$", text, re.M)
    assert len(found) == 1, found
    score, n, total, first, last = found[0]
    assert score == f"{thesis[1]}/{thesis[2]}+{thesis[3]}/{T}" and n == total == "200", found
    assert (float(first), float(last)) == (low, high), (found, low, high)


def test_05_exercise_1_takes_a_theta_from_arange_and_its_check_agrees_with_the_test(live_notebook):
    """05 ex. 1: the answer computed with np.arange (17.079999..., not 17.08) passes the visible
    check and the hidden test; 0.01 px more fails both."""
    import nbformat

    source = nbformat.read(NOTEBOOKS / "05_parameter_explorer.ipynb", as_version=4)
    cell = next(c.source for c in source.cells if c.get("id") == "81d482b1")
    solution = cell.split("### BEGIN SOLUTION\n", 1)[1].split("### END SOLUTION\n", 1)[0]
    check = cell.split("### END SOLUTION\n", 1)[1]
    hidden = next(c.source for c in source.cells if c.get("id") == "06-ex1-test")
    hidden = hidden.split("### BEGIN HIDDEN TESTS\n", 1)[1].split("### END HIDDEN TESTS", 1)[0]
    assert "np.arange(2, 30, 0.01)" in solution and "round(" not in solution
    _, run_cell = live_notebook("05_parameter_explorer.ipynb")
    answer = printed(run_cell("model.set(params=p)\n" + solution + "print(repr(my_theta_c))"))
    assert answer.strip() != repr(round(float(answer), 2)), answer      # the float np.arange gives
    assert printed(run_cell(check)).splitlines()[-1] == "correct"
    printed(run_cell(hidden))
    printed(run_cell("my_theta_c += 0.01"))
    assert printed(run_cell(check)).splitlines()[-1].startswith("not yet")
    from nbclient.exceptions import CellExecutionError

    with pytest.raises(CellExecutionError, match="AssertionError"):
        run_cell(hidden)


def test_07_counts_its_seed_table_and_warns_nothing(executed_notebook):
    """07 says: no row of the seed table is wrong, the network's car #2 moves with the seed and
    annealing's does not; and its cells print no warning."""
    nb = executed_notebook("07_toy_car_depth.ipynb")
    warned = [o["text"] for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("name") == "stderr" and "Warning" in o.get("text", "")]
    assert not warned, warned
    text = output_text(nb)
    counts = {solver: (int(n), values.split(", ")) for solver, n, values in
              re.findall(r"(network|anneal): (\d+) wrong rows of 10; car #2's disparity over the seeds: "
                         r"\[([\d., ]+)\] px", text)}
    assert set(counts) == {"network", "anneal"}, text
    assert counts["network"][0] == 0 and counts["anneal"][0] == 0, counts
    assert len(counts["network"][1]) > 1 and len(counts["anneal"][1]) == 1, counts


def test_08_exercises_work_after_run_all_and_its_energy_claim_holds(live_notebook):
    nb, run_cell = live_notebook("08_real_data_and_peers.ipynb")
    text = output_text(nb)
    # cell 13: the truth scores every target yet lies above the exact minimum; annealing reaches
    # the minimum's score, no further
    table = text[text.index("Method-III, "):text.index("Method-NM, ")]
    truth = re.search(r"truth +E = +[-\d.]+ +(\d+)/(\d+)\+(\d+)/(\d+) +[\d.]+ above the minimum", table)
    assert truth and truth.group(1) == truth.group(4) and truth.group(2) == truth.group(3) == "0", table
    minimum = re.search(r"exact minimum +E = +[-\d.]+ +(\S+)", table).group(1)
    assert set(re.findall(r"anneal seed \d +E = +[-\d.]+ +(\S+)", table)) == {minimum}, table
    # exercise 1, with the sign fixed, on the Motorcycle cut-out it names
    starter = next(c.source for c in nb.cells if c.cell_type == "code" and "expected = np.stack([x + d, y]" in c.source)
    answer = printed(run_cell(starter.replace("x + d", "x - d")))
    assert answer.strip() == "correct", answer
    # exercise 3: the table rebuilt with NM's genes and beta = 2
    rebuilt = printed(run_cell("""from dataclasses import replace
method = get_method("NM")
net = method.network(problem, replace(report_nm.params, match_bias=2.0))
best = milp_minimum(net)
print(line("anneal seed 0", method, net, anneal(net, rng=0).state, best))
print(line("truth", method, net, truth, best))"""))
    assert re.search(r"anneal seed 0 +E = .*\n +truth +E = ", rebuilt), rebuilt


def printed(outputs) -> str:
    """What one extra cell printed to stdout; it must not have failed."""
    errors = [f"{o['ename']}: {o['evalue']}" for o in outputs if o.get("output_type") == "error"]
    assert not errors, errors
    return "".join(o["text"] for o in outputs if o.get("output_type") == "stream" and o.get("name") == "stdout")


def test_06_fits_the_labels_a_student_saved_in_04_and_05_keeps_the_shared_key(run_notebook):
    """One thread through the class: 04's saved labels are 06's homework exercise 5, scored only
    at the labelled corners (the GA reaches their number) and then tested on the whole key and
    the eleven pairs; 05 and 06's in-class runner stay on the shared pairs and keys."""
    from pathlib import Path

    from ismb_lab.labels.classroom import targets_path
    from ismb_lab.labels.targets import TargetSet, load_targets, save_targets

    notebooks = Path(__file__).resolve().parents[2] / "notebooks"
    mine = notebooks / targets_path("synthetic").name
    assert not mine.exists(), f"{mine} is in the way of this test"
    key = load_targets(notebooks.parent / "images" / "synthetic" / "answer_key.json")
    save_targets(mine, TargetSet(key.left_xy[:6], key.right_xy[:6], key.left_sha256, key.right_sha256))
    try:
        six = output_text(run_notebook("06_genetic_algorithm.ipynb"))
        five = output_text(run_notebook("05_parameter_explorer.ipynb"))
    finally:
        mine.unlink()
        for lock in notebooks.glob(f".{mine.name}.lock"):
            lock.unlink()
    fitted = re.search(rf"your (\d+) pairs \({re.escape(mine.name)}\): best fitness (-?[\d.]+) of (\d+)", six)
    assert fitted and fitted.group(1) == fitted.group(3) == "6" and float(fitted.group(2)) == 6, six
    assert len(re.findall(r"on the eleven pairs, update-order seed \d", six)) == 6, six
    assert "scored against the lab pair's answer key" in five and mine.name not in five


def test_06_shows_the_plateau_it_describes(executed_notebook):
    """06's homework: the best fitness rises in a few steps, then stays flat for many
    generations and may still step up later; after 40 generations most chromosomes share it."""
    text = output_text(executed_notebook("06_genetic_algorithm.ipynb"))
    line = re.search(r"^best fitness: (.*)$", text, re.M).group(1)
    runs = [(int(f), int(a), int(b or a)) for f, a, b in
            re.findall(r"(\d+) \(generations? (\d+)(?:-(\d+))?\)", line)]
    assert runs[0][1] == 0 and runs[-1][2] == 500, runs
    assert all(f1 < f2 for (f1, *_), (f2, *_) in zip(runs, runs[1:])), runs     # it never falls
    assert len(runs) <= 6 and max(b - a + 1 for _, a, b in runs) >= 100, runs   # a few steps, a long plateau
    share = re.search(r"after 40 generations (\d+) of 30 chromosomes have the best fitness", text)
    assert share and int(share.group(1)) >= 20


def test_06_adds_up_the_thesis_fig_5_10(executed_notebook):
    text = output_text(executed_notebook("06_genetic_algorithm.ipynb"))
    assert "the entries add up to C/E/T = 139/13/150 (C/T 92.67%); the thesis prints 125/14/137" in text


# --- symbols before use ----------------------------------------------------------------------
_SYMBOLS = {"ΔY": r"ΔY|\\Delta Y", "Δd": r"Δd|\\Delta d", "ΔD": r"ΔD|\\Delta D",
            "M": r"M_\{?ik|\$M\$", "S": r"S_\{?ik|\$S\$", "C": r"C_\{?ikjl|\$C\$",
            "θ": r"θ|\\theta", "λ": r"λ|\\lambda"}
_POINTER = "notebook 02 defines every symbol"


def test_symbols_are_defined_before_their_first_use():
    """02 defines every symbol of the energy in a cell before any other cell uses one; every
    other notebook's first use of a symbol either defines it there or points to 02."""
    import glob
    import json
    import re

    for path in sorted(glob.glob(str(NOTEBOOKS / "0*.ipynb"))):
        cells = ["".join(c["source"]) for c in json.loads(Path(path).read_text())["cells"]]
        for symbol, pattern in _SYMBOLS.items():
            first = next((n for n, text in enumerate(cells) if re.search(pattern, text)), None)
            if first is None:
                continue
            if path.endswith("02_hopfield_network.ipynb"):
                assert cells[first].startswith("### The symbols used below"), (symbol, first)
                assert re.search(rf"({pattern})[^\n]{{0,12}}=|\*\*[^*]+\*\*", cells[first]), symbol
                continue
            earlier = "\n".join(cells[:first + 1])
            defined = re.search(rf"({pattern})\s*(=|\(3-1[023]\),| is | are |\$?,? the )", cells[first])
            assert defined or _POINTER in earlier.replace("\n", " ").lower(), \
                f"{Path(path).name}: {symbol} first used in cell {first} without a definition or a pointer to 02"


# --- every number in the markdown ------------------------------------------------------------
def _load_rule():
    """markdown_numbers.py, beside this file (pytest imports tests with --import-mode=importlib)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("markdown_numbers", Path(__file__).with_name("markdown_numbers.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


numbers_rule = _load_rule()

THESIS = NOTEBOOKS.parents[1] / "shared" / "thesis"
NAMES = sorted(p.name for p in NOTEBOOKS.glob("0*.ipynb"))


def unaccounted(nb_source, printed_text: str) -> list[str]:
    """Each number of a markdown cell that is no reference, is not printed by the notebook and
    is not listed, with its cell and context."""
    key = nb_source.metadata.get("ismb_key") or ""
    printed, values = numbers_rule.output_numbers(printed_text)
    phrases = [phrase for phrase, _, _ in numbers_rule.LISTED.get(key, [])]
    missing = []
    for index, cell in enumerate(nb_source.cells):
        if cell.cell_type != "markdown":
            continue
        text = numbers_rule.strip_code(cell.source)
        for at, number in numbers_rule.numbers(text, phrases):
            if not numbers_rule.in_output(number, printed, values, text, at, printed_text):
                context = text[max(0, at - 40):at + len(number) + 20].replace("\n", " ")
                missing.append(f"cell {index}: {number} in …{context}…")
    return missing


def _source(name: str):
    import nbformat

    nb = nbformat.read(NOTEBOOKS / name, as_version=4)
    nb.metadata["ismb_key"] = name[:2]
    return nb


@pytest.mark.parametrize("name", NAMES)
def test_every_number_in_the_markdown_is_printed_or_listed(name, executed_notebook):
    """A number the text states is a reference, or the notebook's own output prints it, or
    markdown_numbers.LISTED says what it must match."""
    missing = unaccounted(_source(name), output_text(executed_notebook(name)))
    assert not missing, f"{name}: numbers neither printed nor listed in markdown_numbers.py:\n" + "\n".join(missing)


def test_the_listed_phrases_are_in_the_notebooks_and_their_evidence_holds(executed_notebook):
    """Each listed phrase is still in its notebook's markdown (so a changed number drops out of
    the list), and its evidence holds: the thesis quotation, the library value, the arithmetic,
    the notebook's own code or output."""
    thesis = "\n".join(p.read_text(encoding="utf-8") for p in sorted(THESIS.glob("*.txt"))) \
        if THESIS.is_dir() else None
    scope = _library_scope()
    problems = []
    for key, entries in numbers_rule.LISTED.items():
        name = next(n for n in NAMES if n.startswith(key))
        source = _source(name)
        markdown = "\n".join(numbers_rule.strip_code(c.source) for c in source.cells if c.cell_type == "markdown")
        code = "\n".join(c.source for c in source.cells if c.cell_type == "code")
        printed = None
        for phrase, kind, evidence in entries:
            where = f"{key}: {phrase!r} ({kind})"
            if phrase not in markdown:
                problems.append(f"{where}: the phrase is not in the markdown")
            inside = [n for _, n in numbers_rule.numbers(phrase)]
            if not inside:
                problems.append(f"{where}: the phrase holds no number")
            if kind not in _KINDS:
                problems.append(f"{where}: unknown kind")
                continue
            if kind in ("count", "formula"):
                if len(evidence.split()) < 3:
                    problems.append(f"{where}: give the reason in words")
                continue
            text = evidence
            held = numbers_rule.output_numbers(text)[0]
            absent = [n for n in inside if n.replace(",", "") not in held
                      and not (kind == "thesis" and re.search(rf"\b{_WORDS.get(n, '@')}\b", text.lower()))]
            if absent:
                problems.append(f"{where}: {absent} not in the evidence {evidence[:60]!r}")
            if kind == "thesis" and thesis is not None:
                for quote in evidence.split(" | "):
                    if " ".join(quote.split()) not in " ".join(thesis.split()):
                        problems.append(f"{where}: the quotation {quote!r} is not in the thesis")
            if kind == "code" and evidence not in code:
                problems.append(f"{where}: {evidence!r} is not in the notebook's code")
            if kind == "printed":
                if printed is None:
                    printed = " ".join(output_text(executed_notebook(name)).split())
                if " ".join(evidence.split()) not in printed:
                    problems.append(f"{where}: {evidence!r} is not in the notebook's output")
            if kind in ("library", "arithmetic"):
                try:
                    ok = eval(evidence, dict(scope))          # noqa: S307  (our own list)
                except Exception as exc:                      # noqa: BLE001
                    ok = f"{type(exc).__name__}: {exc}"
                if ok is not True:
                    problems.append(f"{where}: {evidence} gives {ok}")
    assert not problems, "\n".join(problems)


_KINDS = ("thesis", "library", "arithmetic", "printed", "code", "count", "formula")
_WORDS = dict(zip(map(str, range(1, 13)), ("one", "two", "three", "four", "five", "six", "seven", "eight",
                                            "nine", "ten", "eleven", "twelve")))


def _library_scope() -> dict:
    import math

    from ismb_lab.cameras import camera, rig
    from ismb_lab.images import datasets, features
    from ismb_lab.depth import objects as depth, pipeline as depth_demo, outlines as silhouettes
    from ismb_lab.network import exact, methods
    from ismb_lab.scenes import gallery
    from ismb_lab.tuning import cases as protocol, genetic
    from ismb_lab.matching import pipeline as matching, peers
    return {"math": math, "camera": camera, "datasets": datasets, "depth": depth, "depth_demo": depth_demo,
            "exact": exact, "features": features, "gallery": gallery, "genetic": genetic,
            "matching": matching, "methods": methods, "peers": peers, "protocol": protocol, "rig": rig,
            "silhouettes": silhouettes, "ROOT": NOTEBOOKS.parent}


def test_the_number_rule_fails_on_a_changed_number(executed_notebook):
    """The rule can fail: 06's markdown with a listed number changed (the phrase "$p_c = 0.8$" is
    gone, and 0.83 is neither printed nor listed), with a printed number changed (91.24 % is
    printed, 91.42 % is not), and with a small integer changed (the notebook prints "40
    generations", not "28 generations", though it prints 28 elsewhere)."""
    name = "06_genetic_algorithm.ipynb"
    printed = output_text(executed_notebook(name))
    assert unaccounted(_source(name), printed) == []
    for old, new, cell_has in (("$p_c = 0.8$", "$p_c = 0.83$", "Arithmetic crossover"),
                               ("= 91.24 %", "= 91.42 %", "First, the thesis' own Fig. 5.10"),
                               ("after 40 generations", "after 28 generations", "stays flat for long stretches")):
        nb = _source(name)
        cell = next(c for c in nb.cells if c.cell_type == "markdown" and cell_has in c.source)
        assert old in cell.source
        cell.source = cell.source.replace(old, new)
        missing = unaccounted(nb, printed)
        changed = re.search(r"\d+(?:\.\d+)?", new).group(0)
        assert len(missing) == 1 and f": {changed} in" in missing[0], missing


def test_the_number_rule_refuses_a_figure_that_only_a_record_holds(executed_notebook):
    """A research record is linked, not evidence: 07's markdown with a figure of
    docs/experiments/2026-11-24-depth-layouts.md added fails the rule, and a list entry of the
    retired kind "record" is an unknown kind."""
    name = "07_toy_car_depth.ipynb"
    printed = output_text(executed_notebook(name))
    record = (NOTEBOOKS.parent / "docs" / "experiments" / "2026-11-24-depth-layouts.md").read_text(encoding="utf-8")
    assert "119" in record
    nb = _source(name)
    cell = next(c for c in nb.cells if c.cell_type == "markdown" and c.source.startswith("## What to notice"))
    cell.source += ("\n* On 120 held-out layouts it ranks 119 fully right "
                    "(`docs/experiments/2026-11-24-depth-layouts.md`).")
    missing = unaccounted(nb, printed)
    assert any(": 119 in" in m for m in missing), missing
    assert "record" not in _KINDS


# --- docs/depth.md -----------------------------------------------------------------------------
def test_the_depth_page_states_the_library_defaults():
    """docs/depth.md (07's depth stage, moved out of the notebook) writes each value as
    `name = value`; each is the library's default today."""
    import inspect

    from ismb_lab import cameras
    from ismb_lab.depth import pipeline as depth_demo
    from ismb_lab.depth.objects import DepthConfig

    import ast

    def literal(value):
        try:
            return ast.literal_eval(value)
        except (ValueError, SyntaxError):
            return None             # a formula such as `Z = f B / d`, not a value

    text = (NOTEBOOKS.parent / "docs" / "depth.md").read_text(encoding="utf-8")
    stated = [(name, literal(value)) for name, value in re.findall(r"`([A-Za-z_][\w.]*) = ([^`]+)`", text)
              if literal(value) is not None]
    assert len(stated) >= 40, stated
    functions = {"changed_roi": depth_demo.changed_roi, "changed_regions": depth_demo.changed_regions}
    wrong = []
    for name, value in stated:
        owner, _, attribute = name.rpartition(".")
        if owner == "DepthConfig":
            actual = getattr(DepthConfig(), attribute)
        elif owner == "DepthConfig.outline":
            actual = getattr(DepthConfig().outline, attribute)
        elif owner in functions:
            actual = inspect.signature(functions[owner]).parameters[attribute].default
        elif owner == "DEPTH_MATCH_CONFIG":
            actual = getattr(depth_demo.DEPTH_MATCH_CONFIG, attribute)
        elif owner == "cameras":
            actual = getattr(cameras, attribute)
        elif owner == "":
            actual = getattr(depth_demo, attribute)
        else:
            wrong.append(f"{name}: no such owner")
            continue
        if actual != value:
            wrong.append(f"{name} = {value!r}, the library's is {actual!r}")
    assert wrong == [], wrong
