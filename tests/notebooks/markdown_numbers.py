"""The rule for numbers in the notebooks' markdown, and the list of those the output cannot show.

Every number in a markdown cell of ``notebooks/0*.ipynb`` must be one of:

* **a reference**, recognised by pattern (``REFERENCES``): an equation "(3-10)", a section
  "§5.2.1", a table or figure "Table 5.3", "Figs. 5.8 and 5.9", a chapter "ch. 2", a notebook or
  pair name "04", "pair 01", "pairs 07–11", an exercise label "**2.**" or a numbered list item;
* **in the notebook's own output**: the number, as written, is printed by one of its code cells
  (a decimal also counts when a printed value rounds to it; a score such as ``17/2+0/17`` or
  ``125/14/137`` must be printed whole);
* **listed** below, per notebook, as ``(phrase, kind, evidence)``.  The phrase is copied from the
  markdown and must still be there; the entry accounts for the numbers inside it.  ``kind`` says
  how the evidence is checked:

  - ``thesis``: evidence is a short quotation of the thesis that holds every number of the phrase;
    it is looked up in the thesis' text when ``../shared/thesis/`` is beside the repository;
  - ``library``: evidence is a Python expression over ``ismb_lab`` that must be true and holds
    every number of the phrase;
  - ``record``: evidence is a file of the repository, a dated record ``docs/experiments/<file>.md``
    or the test that measures the figure; every number of the phrase appears in that file;
  - ``arithmetic``: evidence is a Python expression that must be true and holds every number of
    the phrase;
  - ``count``: a plain count, size or name in prose whose truth the sentence itself shows
    (``2 × 2``, "16 states" of four binary neurons); evidence is the reason, in words.
  - ``formula``: a constant of an equation written out (the 2 and the 1 of the transfer
    function); evidence names the equation.

Not checked: inline code spans (`` `...` ``) and fenced or indented code blocks with a command in
them, which are code a student types, not claims; the unlabelled fenced diagram of 00 is prose
and is checked.
"""

import re

# --- tokens ----------------------------------------------------------------------------------
# a score "17/2+0/17", "125/14/137", a fraction "2/12" is one token; then any number "1,200", "0.5"
NUMBER = re.compile(r"(?<![\w.])(?:\d+(?:\.\d+)?(?:[/+]\d+(?:\.\d+)?)+|\d+(?:,\d{3})*(?:\.\d+)?)(?![\w])")

REFERENCES = {
    "equation": r"(?<![\w.])[2-6]-\d{1,2}(?![\w.])",
    "section": r"§\s*\d+(?:\.\d+)*(?:\s*[–-]\s*\d+(?:\.\d+)*)?",
    "table or figure": r"\b(?:Tables?|Figs?\.|Figures?)\s*\d+\.\d+(?:(?:\s*[–,]\s*|\s+and\s+)\d+\.\d+)*",
    "chapter": r"\b(?:[Cc]h\.|[Cc]hapters?)\s*\d+",
    "pair name": r"\b[Pp]airs?\s+\d{2}(?:\s*–\s*\d{2})?",
    "notebook name": r"(?<![\w.,])0\d(?:\s*–\s*0\d)?(?![\w%]|[.,]\d)",
    "exercise label": r"\*\*\d+\.(?:\s[^*]*)?\*\*|\b[Ee]xercises?\s+\d+(?:\s+and\s+\d+)?",
    "list item": r"(?m)^\s*\d+\.\s",
}
CODE = re.compile(r"```[a-z]+\n.*?```|`[^`\n]*`|^(?: {4}|\t)(?:ismb-lab|python|voila).*$", re.S | re.M)


def strip_code(text: str) -> str:
    """The markdown with inline code, fenced code with a language and indented commands blanked
    (same length, so positions stay)."""
    return CODE.sub(lambda m: re.sub(r"\S", " ", m.group(0)), text)


def numbers(text: str, listed=()) -> list[tuple[int, str]]:
    """``(position, number)`` of every number in ``text`` (code already stripped) that no reference
    pattern and no listed phrase covers."""
    covered = [m.span() for pattern in REFERENCES.values() for m in re.finditer(pattern, text)]
    for phrase in listed:
        covered += [m.span() for m in re.finditer(re.escape(phrase), text)]
    return [(m.start(), m.group(0)) for m in NUMBER.finditer(text)
            if not any(a <= m.start() and m.end() <= b for a, b in covered)]


def output_numbers(text: str) -> tuple[set, list]:
    """The numbers an output prints, as strings (scores whole and in parts), and as floats."""
    found = set()
    for m in NUMBER.finditer(text):
        found.add(m.group(0).replace(",", ""))
        found.update(re.split(r"[/+]", m.group(0)))
    for m in re.finditer(r"\d+(?:\.\d+)?", text):     # digits inside words too: "C/T 92.67%"
        found.add(m.group(0))
    return found, sorted({float(s) for s in found if re.fullmatch(r"\d+(?:\.\d+)?", s)})


def in_output(number: str, printed: set, values: list) -> bool:
    """Whether ``number`` (as the markdown writes it) is printed, or a printed value rounds to it."""
    plain = number.replace(",", "")
    if plain in printed:
        return True
    if re.fullmatch(r"\d+\.\d+", plain):
        digits = len(plain.split(".")[1])
        return any(round(v, digits) == float(plain) for v in values)
    return False


# --- the list --------------------------------------------------------------------------------
LISTED: dict[str, list[tuple[str, str, str]]] = {}

_WINDOW = ("matching.MatchConfig().window_height == 30 and matching.MatchConfig().window_width == 40")
_THESIS_III = "the parameters of Method-III are set as [17.97, 24.02, 6.37, 2.2]"

LISTED["00"] = [
    ("30×40 window", "library", _WINDOW),
    ("θ = 24.02 and λ = 2.2", "thesis", _THESIS_III),
    ("gives S = 0.5?", "count", "the value the exercise asks a student to solve for, not a claim"),
    ("Solve $f(M) = 0.5$", "count", "the same value the exercise asks for, repeated in its instruction"),
    ("30 rows tall", "library", _WINDOW),
]
LISTED["01"] = [
    ("0.04$–$0.06", "thesis", "k = 0.04 \\sim 0.06"),
    ("R > 0 at corners", "formula", "the sign of the Harris response at a corner, from (2-6)"),
    ("R < 0 on edges", "formula", "the sign of the Harris response on an edge, from (2-6)"),
    ("R ≈ 0 on flat ground", "formula", "the Harris response of a flat patch, from (2-6)"),
    ("320×240 image", "thesis", "240×320 pixels"),
    ("T ← 0.8·T", "thesis", "*T* will be 0.8*T*"),
    ("(the thesis uses [20, 30])", "thesis", "the feature points is set as [20, 30]"),
    ("relaxed by 0.8", "library", "features.detect_corners.__kwdefaults__['relax'] == 0.8"),
    ("1/255 for 8-bit images", "arithmetic", "1/255 == 1 / (2 ** 8 - 1)"),
    ("the thesis uses T = 30", "thesis", "the threshold T is set as 30"),
    ("relaxing by\n  0.8", "library", "features.detect_corners.__kwdefaults__['relax'] == 0.8"),
    ("σ = 1.5, k = 0.05", "count", "the values the exercise sets for the student's own computation"),
    ("the 30 strongest", "library", "features.detect_corners.__kwdefaults__['n_max'] == 30"),
    ("T ← 0.8 T", "library", "features.detect_corners.__kwdefaults__['relax'] == 0.8"),
]
LISTED["02"] = [
    ("30-tall × 40-wide", "library", _WINDOW),
    ("40 × 40 region", "library", "matching.MatchConfig().neighbour_radius * 2 == 40"),
    ("C = 0.9", "count", "the compatibility the 2 × 2 example sets for both neighbouring pairs"),
    ("only 16 states", "arithmetic", "2 ** 4 == 16"),
]
LISTED["03"] = [
    ("$[7.45, 15.20, 1.47, 4.08]$", "thesis", "[7.45, 15.20, 1.47, 4.08]"),
    ('"[7.45, 15.20, 1.47, 4.08]"', "thesis", "[7.45, 15.20, 1.47, 4.08]"),
    ("(120, 155)", "thesis", "3	8	4	155	120	158	98	22.20"),
    ("a 240 × 320 render", "thesis", "240×320 pixels"),
]
LISTED["04"] = [
    ("marks 13 target pairs", "thesis", "the target contains 13 matched pairs"),
    ("among 39 candidates", "thesis", "there are 39 pairs to be considered"),
    ("SHA-256", "count", "the name of the hash function, stored by ismb_lab.targets"),
    ("numbers features from 1", "count", "the table's numbering, shown by the table above it"),
    ("at least 10 pairs", "count", "how many pairs the exercise asks a student to label"),
]
_GA = "genetic.GAConfig().generations == 500"
LISTED["05"] = [
    ("bred for up to 500 generations", "library", _GA),
    ("$p_c = 0.8$", "thesis", "$p_c=0.8$"),
    ("after 500 generations", "library", _GA),
    ("$\\lambda = 0.25$", "count", "the crossover weight the code cell below it sets for the demonstration"),
    ("up to 500 generations", "library", _GA),
    ("(not 500)", "library", _GA),
    ("500 generations and 5 seeds", "library",
     _GA + " and protocol.protocol.__kwdefaults__['seeds'] == 5"),
    ("$[17.97, 24.02, 6.37, 2.2]$", "thesis", _THESIS_III),
    ("$125/137 = 91.24\\%$", "thesis", "Accurate rate 125/137=91.24%"),
    ("about 50 generations", "count", "when the exercise asks the student to stop the runner"),
    ("(86 targets)", "arithmetic", "9 + 9 + 20 + 17 + 17 + 14 == 86  # pairs 01-06, printed by the first cell"),
]
LISTED["06"] = [
    ("±0.76 within $2/\\lambda$", "arithmetic", "round(math.tanh(1), 2) == 0.76 and 2 == 2"),
    ("$2/6.37 \\approx 0.3$", "arithmetic", "round(2/6.37, 1) == 0.3"),
    ("$X = 18$", "arithmetic", "round(17.97) == 18  # θc of the thesis' Method-III"),
    ("$2/2.2 \\approx 0.9$", "arithmetic", "round(2/2.2, 1) == 0.9"),
    ("$M = 24$", "arithmetic", "round(24.02) == 24  # θs of the thesis' Method-III"),
]

_REPETITIVE = "docs/experiments/2026-11-24-matching-families.md"
LISTED["07"] = [
    ("$\\sqrt{2/12} \\approx 0.41$", "arithmetic", "round(math.sqrt(2/12), 2) == 0.41"),
    ("$f = 300$ px and $B = 0.10$ m", "library", "depth.FOCAL_PX == 300 and depth.BASELINE_M == 0.10"),
    ("sits near\n1/2", "formula", "the logistic curve's value at zero net input"),
    ("16-bit, disparity × 256", "library", "gallery.DISPARITY_SCALE == 256 and 16 == 16  # uint16 PNG"),
    ("On 40 rendered car layouts", "record", "tests/test_depth.py"),
    ("on all 40 this way, and on 19 of the first 20", "record", "tests/test_depth.py"),
    ("68 of 120 held-out layouts", "record", "docs/experiments/2026-11-24-depth-layouts.md"),
    ("(57%)", "arithmetic", "round(100 * 68 / 120) == 57"),
    ("ranks 119 fully right", "record", "docs/experiments/2026-11-24-depth-layouts.md"),
    ("(99.2%;", "arithmetic", "round(100 * 119 / 120, 1) == 99.2"),
    ("355 of 360", "record", "docs/experiments/2026-11-24-depth-layouts.md"),
    ("by its outline it is at 20 px", "library", "grouped(810001, 1, 'silhouettes')[0] == (20, 0)"),
    ("its neighbour 8 px\naway fits 17 px (true 17.8)", "library",
     "unmerged(880022, 22) == ([16, 17, 21], 8, [22.3, 17.8, 13.9])"),
    ("doubles to 20 cm", "arithmetic", "2 * 10 == 20  # the rig's baseline, depth.BASELINE_M, in cm"),
]
LISTED["08"] = [
    ("Middlebury 2014", "library", "'Middlebury 2014' in datasets.motorcycle.__doc__"),
    ("125/137 = 91.24 %", "thesis", "Accurate rate 125/137=91.24%"),
    ("within 1.5 px of where the\nground truth", "library",
     "datasets.ground_truth_pairs.__defaults__ == (1.5,)"),
    ("the four 160 × 108 cut-outs", "library", "{r[2:] for r in datasets.MOTORCYCLE_ROIS} == {(160, 108)}"),
    ("the 125-neuron bottom-left ROI", "library",
     "[c.prepared.problem.n_neurons for c in protocol.load_manifest(ROOT / 'manifests/middlebury.json')][2] == 125"),
    ("within its 60 s\nlimit", "library", "exact.milp_minimum.__kwdefaults__['time_limit'] == 60"),
    ("mutual nearest neighbour 55.6%, Hungarian 63.7%, Method-III\n41.1%", "record", _REPETITIVE),
    ("27.1%, 35.6%, 34.7%, 2.8% and 18.3%", "record", _REPETITIVE),
    ("about a\nminute per call with 200 generations", "library",
     "'(default 200)' in (ROOT / 'scripts/matching_families.py').read_text()"),
    ("(79.9% C/T on a third held-out split, against 68.4% for\nHungarian)", "record", _REPETITIVE),
    ("it found 76.6% of this family's targets with 73.8% precision, against\nHungarian's 59.3% and 40.0%",
     "record", _REPETITIVE),
    ("93.8% with 90.9% precision", "record", _REPETITIVE),
    ("(Hungarian 91.5% and 85.3%, mutual nearest neighbour 85.4%\nand 86.3%)", "record", _REPETITIVE),
    ("found 96.3% of the\ncameras targets of a held-out split (seeds 990000-), as Hungarian did (97.1%), but with 82.7%\n"
     "precision against 93.4%", "record", _REPETITIVE),
    ("is 42–48 grey levels", "arithmetic", "round(42.4) == 42 and round(47.5) == 48  # the M printed above"),
    ("(87.2% against\n89.4% precision", "record", _REPETITIVE),
    ("nearest right corner within 1.5 px", "library", "datasets.ground_truth_pairs.__defaults__ == (1.5,)"),
]
LISTED["09"] = [
    ("**Aloe** (Middlebury 2006)", "library", "'Middlebury 2006' in datasets.aloe.__doc__"),
    ("(at the thesis' width,\n320 px)", "thesis", "240×320 pixels"),
    ("within 1.5 px of that place", "library", "datasets.ground_truth_pairs.__defaults__ == (1.5,)"),
    ("9 × 6 inner corners", "library", "camera.BOARD == (9, 6)"),
    ("150 to 200 corners per image", "record", "docs/experiments/2026-11-25-board-metres.md"),
    ("suit a 160 × 120 region,\nand on this 640 × 480 photo", "record",
     "docs/experiments/2026-11-25-board-metres.md"),
    ("within 1.5 px of a corner", "library", "datasets.ground_truth_pairs.__defaults__ == (1.5,)"),
]
