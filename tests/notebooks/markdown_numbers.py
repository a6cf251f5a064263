"""The rule for numbers in the notebooks' markdown, and the list of those the output cannot show.

Every number in a markdown cell of ``notebooks/0*.ipynb`` must be one of:

* **a reference**, recognised by pattern (``REFERENCES``): an equation "(3-10)", a section
  "§5.2.1", a table or figure "Table 5.3", "Figs. 5.8 and 5.9", a chapter "ch. 2", a notebook or
  pair name "04", "pair 01", "pairs 07–11", an exercise label "**2.**", a numbered list item or
  heading, the words "2-D", "3-D"; or the notation of an equation in LaTeX: a power or index
  "^2", "_{i1}", the transfer function's "2/(1 + e^...) - 1", the intervals "[-1, 1]", "{0, 1}",
  a sign "> 0", "\\le 0", and the 1 of "(1 - \\sum ...)";
* **in the notebook's own output**: the number, as written, is printed by one of its code cells
  (a decimal also counts when a printed value rounds to it; a score such as ``17/2+0/17`` or
  ``125/14/137`` must be printed whole).  A small integer (one or two digits) is printed by
  almost any notebook, so it counts only when it is printed beside the same word as in the text
  ("40 generations", "seed 0");
* **listed** below, per notebook, as ``(phrase, kind, evidence)``.  The phrase is copied from the
  markdown and must still be there; the entry accounts for the numbers inside it.  ``kind`` says
  how the evidence is checked:

  - ``thesis``: evidence is a short quotation of the thesis (or several, joined by " | ") that
    holds every number of the phrase (as digits, or as a word: "three error matched pairs");
    it is looked up in the thesis' text when ``../shared/thesis/`` is beside the repository;
  - ``library``: evidence is a Python expression over ``ismb_lab`` that must be true and holds
    every number of the phrase;
  - ``arithmetic``: evidence is a Python expression that must be true and holds every number of
    the phrase;
  - ``count``: a plain count, size or name in prose whose truth the sentence itself shows
    (``2 × 2``, "16 states" of four binary neurons); evidence is the reason, in words.
  - ``printed``: evidence is a piece of the notebook's output (whitespace aside) that holds
    every number of the phrase, for a number the text words differently from the print
    ("19 of the 20 runs" for "19/20");
  - ``code``: evidence is a piece of the notebook's own code that holds every number of the
    phrase ("max_sweeps=20" for "at most 20 sweeps"): the text describes what the code does;
  - ``formula``: a constant of an equation written out (the 2 and the 1 of the transfer
    function); evidence names the equation.

A measured figure (a count, a share, a time, a disparity, a score) is printed by the notebook
itself or quoted from the thesis: a research record (``docs/experiments/``) is linked from the
text, never the evidence for a number in it, so a figure of older defaults cannot pass.

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
    "numbered heading": r"(?m)^#+\s+\d+\.\s",
    "2-D or 3-D": r"\b[23]-D\b",
    # the notation of an equation written in LaTeX: powers and indices, the transfer function's
    # 2/(1 + e^...) - 1 of (3-10), (3-13), the intervals [-1, 1], {0, 1}, U[0, 1], a sign "> 0",
    # "≤ 0", and the 1 of "(1 - ...)" in (3-15) and in the crossover
    "power or index": r"[\^_]\{?[a-z]*\d+\}?",
    "transfer function": r"\\d?frac\{2\}\{1 \+ e\^|2/\(1 \+ e\^|\)\}\}\s*-\s*1\b|\)\}\)\s*-\s*1\b",
    "interval": r"[\[{]\s*-?[01]\s*,\s*1\s*\\?[\]}]",
    "sign": r"(?:[<>]|\\le|\\ge|≤|≥)\s*0(?![\d.])",
    "one minus": r"\(1 - (?:\\lambda|\\sum|y_)",
}
CODE = re.compile(r"```[a-z]*\n.*?```|`[^`]*`|^(?: {4}|\t)(?:ismb-lab|python|voila).*$", re.S | re.M)


def strip_code(text: str) -> str:
    """The markdown with inline code, fenced code with a language and indented commands blanked
    (same length, so positions stay); a fence without a language (a diagram) is kept."""
    return CODE.sub(lambda m: m.group(0) if m.group(0).startswith("```\n")
                    else re.sub(r"\S", " ", m.group(0)), text)


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


def in_output(number: str, printed: set, values: list, text: str = "", at: int = 0,
              output: str = "") -> bool:
    """Whether ``number`` (as the markdown ``text`` writes it at ``at``) is printed, or a printed
    value rounds to it; a one- or two-digit integer only with the word before or after it."""
    plain = number.replace(",", "")
    if re.fullmatch(r"\d{1,2}", plain):
        flat = " ".join(output.split())
        after = re.match(r"\s*([^\s,.;:)\]|*$`]+)", text[at + len(number):])
        before = re.search(r"([^\s(\[|*$`]+)\s*$", text[:at])
        return bool(after and re.search(rf"(?<![\d.]){plain}\s*{re.escape(after.group(1))}", flat)
                    or before and re.search(rf"{re.escape(before.group(1))}\s*{plain}(?![\d.])", flat))
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
    ("such as 14/2+0/16 in Fig. 5.10", "thesis", "Correct/Error/Target Testing: 14/2+0/16"),
    ("θ = 24.02 and λ = 2.2", "thesis", _THESIS_III),
    ("gives S = 0.5?", "count", "the value the exercise asks a student to solve for, not a claim"),
    ("Solve $f(M) = 0.5$", "count", "the same value the exercise asks for, repeated in its instruction"),
    ("30 rows tall", "library", _WINDOW),
    ("(features numbered from 1)", "count", "the numbering of the table the next cell prints"),
]
LISTED["01"] = [
    ("0.04$–$0.06", "thesis", "k = 0.04 \\sim 0.06"),
    ("R ≈ 0 on flat ground", "formula", "the Harris response of a flat patch, from (2-6)"),
    ("320×240 image", "thesis", "240×320 pixels"),
    ("T ← 0.8·T", "thesis", "*T* will be 0.8*T*"),
    ("(the thesis uses [20, 30])", "thesis", "the feature points is set as [20, 30]"),
    ("relaxed by 0.8", "library", "features.detect_corners.__kwdefaults__['relax'] == 0.8"),
    ("1/255 for 8-bit images", "arithmetic", "1/255 == 1 / (2 ** 8 - 1)"),
    ("a fixed T = 30", "thesis", "the threshold T is set as 30"),
    ("σ = 1.5, k = 0.05", "count", "the values the exercise sets for the student's own computation"),
    ("the 30 strongest", "library", "features.detect_corners.__kwdefaults__['n_max'] == 30"),
    ("T ← 0.8 T", "library", "features.detect_corners.__kwdefaults__['relax'] == 0.8"),
    ("For k = 0.01, 0.02, …, 0.20", "count", "the values of k the exercise asks a student to try: the slider's range"),
]
LISTED["02"] = [
    ("30-tall × 40-wide", "library", _WINDOW),
    ("40 × 40 region", "library", "matching.MatchConfig().neighbour_radius * 2 == 40"),
    ("C = 0.9", "count", "the compatibility the 2 × 2 example sets for both neighbouring pairs"),
    ("only 16 states", "arithmetic", "2 ** 4 == 16"),
    ("$(x_i - 20, y_i)$", "library", "matching.MatchConfig().shift == 20"),
    ("near 1 when $X$ is small, near −1 when it is large, and 0", "formula",
     "(3-13) tends to 1 for small X and to -1 for large X; (3-12) gives non-neighbours none"),
    ("$C$ and $-1$ instead of $2C$ and $-2$", "formula",
     "the literal weights of (3-16)/(3-17) against the exact Hopfield form above them"),
    ("$w = C_{ikik} - 2 < 0$", "formula", "C of a match with itself is at most 1, minus 2"),
    ("$-1$ for every neuron of Methods II and III here", "printed", "Method-II: self-weights C_ikik - 2 from -1 to -1"),
    ("between $-3$ and $-1$ for Method-I", "printed", "Method-I: self-weights C_ikik - 2 from -3 to -1"),
    ("lies between 0 and $-w$", "formula",
     "with a self-weight w < 0 the update (3-19) turns an off neuron on when the rest r > 0 and off again when r + w < 0"),
    ("$(M_{ik} + M_{jl})/2$", "formula", "the mean of the two windows' M in Method-I's measure, as in notebook 03"),
    ("is $-1$ flip", "printed", "Method-III: self-weights C_ikik - 2 from -1 to -1"),
    ("between 0 and 1?", "formula", "the same range of the rest of the input as in the thesis section above"),
]
LISTED["03"] = [
    ("$[7.45, 15.20, 1.47, 4.08]$", "thesis", "[7.45, 15.20, 1.47, 4.08]"),
    ('"[7.45, 15.20, 1.47, 4.08]"', "thesis", "[7.45, 15.20, 1.47, 4.08]"),
    ("(120, 155)", "thesis", "3	8	4	155	120	158	98	22.20"),
    ("20 and 20 in Fig. 5.3", "thesis",
     "the left image with 20 feature points, (b) the right image with 20 feature points"),
    ("(the 40 × 40 box", "library", "matching.MatchConfig().neighbour_radius * 2 == 40"),
    ("left corner (numbered from 1)", "count", "the numbering of the listing the next cell prints"),
]
LISTED["04"] = [
    ("marks 13 target pairs", "thesis", "the target contains 13 matched pairs"),
    ("among 39 candidates", "thesis", "there are 39 pairs to be considered"),
    ("SHA-256", "count", "the name of the hash function, stored by ismb_lab.labels.targets"),
    ("numbers features from 1", "count", "the table's numbering, shown by the table above it"),
    ("at least 5 pairs", "count", "how many pairs the exercise asks a student to label"),
    ("(the thesis' parameters, seed 0)", "code", 'labeler.score_saved("III", seed=0)'),
    ("numbered from 1 as in the table", "count", "the labeller's table numbers features from 1, as the cell prints them"),
    ("numbered from 1 like the labeller's", "count", "ismb-lab match prints its table numbered from 1, as the labeller does"),
]
_GA = "genetic.GAConfig().generations == 500"
LISTED["05"] = [
    ("−0.76 and 0.76 (that is, $\\tanh 1$) only within $2/\\lambda$ of θ, a ramp $4/\\lambda$ wide", "arithmetic",
     "round(math.tanh(1), 2) == 0.76 and 2 * 2 == 4"),
    ("$2/6.37 \\approx 0.3$", "arithmetic", "round(2/6.37, 1) == 0.3"),
    ("$X = 18$", "arithmetic", "round(17.97) == 18  # θc of the thesis' Method-III"),
    ("$2/2.2 \\approx 0.9$", "arithmetic", "round(2/2.2, 1) == 0.9"),
    ("$M = 24$", "arithmetic", "round(24.02) == 24  # θs of the thesis' Method-III"),
    ("$[\\theta_c, \\theta_s, \\lambda_c, \\lambda_s] = [17.97, 24.02, 6.37, 2.2]$", "thesis", _THESIS_III),
    ("Find, to 0.01 px,", "count", "the precision the exercise asks for, the explorer's slider step"),
    ("scans θc in steps of 1 px", "code", "np.arange(2, 30, 1)"),
    ("and 0.01 px above\nit", "code", "theta + 0.01"),
    ("rounds your θc to 0.01 px (so a value such as\n12.339999…", "arithmetic",
     "round(12.339999, 2) == 12.34 and round(0.01, 2) == 0.01  # what the check's round(my_theta_c, 2) does"),
    ("counts as 12.34)", "arithmetic", "round(12.339999, 2) == 12.34  # the example's value, rounded as the check does"),
    ("steps θs by 0.01", "code", "for step in (-0.01, 0.01):"),
    ("$|S| < 0.76$, is θs ± 2/λs: θs ± 20 grey levels at λs = 0.1, from about 4 to\n44, and θs ± 0.2 at λs = 10",
     "arithmetic", "round(math.tanh(1), 2) == 0.76 and 2 / 0.1 == 20 and (round(24.02 - 20), round(24.02 + 20)) == "
     "(4, 44) and 2 / 10 == 0.2"),
]
LISTED["06"] = [
    ("bred for up to 500 generations", "library", _GA),
    ("$p_c = 0.8$", "thesis", "$p_c=0.8$"),
    ("after 500 generations", "library", _GA),
    ("$\\lambda = 0.25$", "count", "the crossover weight the code cell below it sets for the demonstration"),
    ("$125/14/137 = 91.24\\%$", "thesis", "Total: C/E/T = 125/14/137 | Accurate rate 125/137=91.24%"),
    ("as in 14/2+0/16", "thesis", "Testing: 14/2+0/16"),
    ("up to 500 generations", "library", _GA),
    ("(not 500)", "library", _GA),
    ("500 generations and 5 seeds", "library",
     _GA + " and protocol.protocol.__kwdefaults__['seeds'] == 5"),
    ("$[17.97, 24.02, 6.37, 2.2]$", "thesis", _THESIS_III),
    ("$125/137 = 91.24\\%$", "thesis", "Accurate rate 125/137=91.24%"),
    ("Set **generations** to 50", "count", "the limit the exercise asks the student to set in the runner"),
    ("stops by itself after 50 generations", "code", "seed=0, generations=50)"),
    ("in steps of 0.1", "code", "np.arange(low, high + 1e-9, 0.1)"),
    ("(86 targets)", "arithmetic", "9 + 9 + 20 + 17 + 17 + 14 == 86  # pairs 01-06, printed by the first cell"),
]
LISTED["07"] = [
    ("$\\sqrt{2/12} \\approx 0.41$", "arithmetic", "round(math.sqrt(2/12), 2) == 0.41"),
    ("its mean absolute value is 1/3 px", "arithmetic",
     "abs(2 * (1/2 - 1/3) - 1/3) < 1e-12  # E|u - v| = 1/3 for u, v uniform on [0, 1]"),
    ("$f = 300$ px and $B = 0.10$ m", "library", "depth.FOCAL_PX == 300 and depth.BASELINE_M == 0.10"),
    ("sits near 1/2", "formula", "the logistic curve's value at zero net input"),
    ("16-bit, disparity × 256", "library", "gallery.DISPARITY_SCALE == 256 and 16 == 16  # uint16 PNG"),
    ("doubles to 20 cm", "arithmetic", "2 * 10 == 20  # the rig's baseline, depth.BASELINE_M, in cm"),
    ("with the 10 cm rig and with a\n20 cm one", "arithmetic", "2 * 10 == 20  # the rig's baseline, depth.BASELINE_M, in cm"),
    ("matches within 1 px of the\ndisparity", "library", "depth.DepthConfig().consensus_px == 1"),
    ("(right of x = 180)", "code", "if x > 180:"),
]
LISTED["08"] = [
    ("Middlebury 2014", "library", "'Middlebury 2014' in datasets.motorcycle.__doc__"),
    ("125/137 = 91.24 %", "thesis", "Accurate rate 125/137=91.24%"),
    ("that line's 14/0+1/16", "thesis", "Testing: 14/0+1/16"),
    ("within 1.5 px of where the ground truth", "library", "datasets.ground_truth_pairs.__defaults__ == (1.5,)"),
    ("the four 160 × 108 cut-outs", "library", "{r[2:] for r in datasets.MOTORCYCLE_ROIS} == {(160, 108)}"),
    ("Cho et al. 2010", "library", "'Cho et al. 2010' in peers.graph_matching.__doc__"),
    ("(Leordeanu and Hebert 2005)", "library", "'Leordeanu & Hebert 2005' in peers.graph_matching.__doc__"),
    ("after its 60 s limit", "library", "exact.milp_minimum.__kwdefaults__['time_limit'] == 60"),
    ("the thesis' width of 320 px", "thesis", "240×320 pixels"),
    ("nearest right corner within 1.5 px", "library", "datasets.ground_truth_pairs.__defaults__ == (1.5,)"),
]
LISTED["09"] = [
    ("**Aloe** (Middlebury 2006)", "library", "'Middlebury 2006' in datasets.aloe.__doc__"),
    ("(at the thesis' width,\n320 px)", "thesis", "240×320 pixels"),
    ("within 1.5 px of that place", "library", "datasets.ground_truth_pairs.__defaults__ == (1.5,)"),
    ("9 × 6 inner corners", "library", "camera.BOARD == (9, 6)"),
    ("The thesis takes 20 to 30", "thesis", "the feature points is set as [20, 30]"),
    ("in a\n160 × 120 region", "arithmetic", "(320 // 2, 240 // 2) == (160, 120)  # the thesis' ROI, a quarter of 240×320"),
    ("within 1.5 px of a corner", "library", "datasets.ground_truth_pairs.__defaults__ == (1.5,)"),
]

_SHIFT = "matching.MatchConfig().shift == 20"
# the last rows of Tables 5.4 and 5.5: thirteen rows each
_LAST_ROWS = "13	20	15	136	230	141	209	21.59 | 13	21	15	136	230	141	209	21.59"
_EVERY = {
    "00": [
        ("Harris' 2 × 2 matrix", "formula", "M of (2-5) sums products of two gradients, a 2 × 2 matrix"),
        ("shifted down by\n3 rows", "count", "the shift the exercise asks for, as its code span rolls the image"),
        ("move down by 3 rows", "count", "the same shift of the exercise, repeated"),
    ],
    "01": [
        ("$1/(2^{k_\\text{size}-1}\\,", "formula", "OpenCV's documented Sobel scale for cornerHarris"),
        ("shifted 20 px", "library", _SHIFT),
    ],
    "02": [
        ("every other neuron stays at 0", "formula", "a neuron outside the window is never a candidate: y = 0"),
        ("(11 × 11 pixels here;", "library", "matching.MatchConfig().patch_size == 11"),
        ("than 20 px to $i$", "library", "matching.MatchConfig().neighbour_radius == 20"),
        ("$|x_j - x_i| < 20$ and $|y_j - y_i| < 20$", "library", "matching.MatchConfig().neighbour_radius == 20"),
        ("It is 0 for non-neighbours", "formula", "(3-12) applies the compatibility to neighbours only"),
        ("$W_{ikik} = 0$", "formula", "the Hopfield form has no self-connection"),
        ("$I_{ik} = 2 + S_{ik}$,\n−2", "formula", "the Hopfield form derived in the cell above"),
        ("a 2 × 2 network", "count", "two left and two right corners, as the next sentence says"),
        ("(0, 0) with (1, 1) and (0, 1) with (1, 0)", "code", "pair_a=[0, 1], pair_b=[3, 2]"),
        ("most 20 sweeps", "code", "max_sweeps=20"),
        ("20 times (seeds", "code", "for s in range(20)"),
        ("(seeds 0–19)", "arithmetic", "(min(range(20)), max(range(20))) == (0, 19)  # the code's range(20)"),
        ("at most\n50 sweeps", "code", "max_sweeps=50"),
        ("**Step 10**", "count", "the label of the stepper's button that tries ten neurons"),
        ("over 20 seeds (Fig. 5.6)", "code", "for seed in range(20)"),
        ("settles in 19 of the 20 runs", "printed", "Method-II: settled in 20/20 runs with the exact rule, 19/20"),
        ("(2 left, 2 right corners", "count", "the exercise's network, the 2 × 2 one of the cell above"),
        ("in 19 runs of 20", "printed", "Method-II: settled in 20/20 runs with the exact rule, 19/20"),
    ],
    "03": [
        ("none ($S = 0$)", "formula", "Method-I has no similarity term"),
        ("(M_{ik} + M_{jl})/2$", "formula", "the mean of the two windows' M in Method-I's measure"),
        ("30 × 40 window centred 20 px left", "library", _WINDOW + " and " + _SHIFT),
        ("14 matches, 3 errors (pairs 1, 2, 5), target #26 missed", "printed",
         "Table 5.2 (Method-I): 14 matches, errors at pairs [1, 2, 5], missed targets #[1, 26], "
         "fitness n_c - n_e = 11 - 3 = 8"),
        ("| 14 matches, 1 error |", "printed", "Table 5.3 (Method-II): 14 matches, errors at pairs [2], missed targets #[], fitness n_c - n_e = 13 - 1"),
        ("13 matches", "thesis", _LAST_ROWS),
        ("1 error (pair", "count", "the thesis names one error pair of Table 5.4, number 11"),
        ("numbered from 1 like the thesis", "count", "the thesis' tables number their pairs from 1"),
        ("Over 20 seeds", "code", "for s in range(20)"),
        ("$\\sqrt{40^2 + 15^2}$", "thesis", "\\sqrt{40^2 + 15^2}"),
        ("40 px wide centred 20 px left", "library", _WINDOW + " and " + _SHIFT),
        ("$|x_l - x_r| \\le 40$, and 30 px\nhigh, so $|y_l - y_r| \\le 15$", "library",
         _WINDOW + " and 40 == 40 and 30 / 2 == 15"),
        ("Row 4 of Table 5.5 and row 3 of Table 5.4", "thesis", "3	8	4	155	120	158	98	22.20"),
        ("$(98, 158)$", "thesis", "3	8	4	155	120	158	98	22.20"),
        ("whose number is 26", "thesis", "a target pair whose number is 26"),
        ("no row for left feature 1, so target\n  #1 (1 ↔ 1)", "printed", "missed targets #[1, 26]"),
        ("as well as #26: 11 of 13 targets", "printed",
         "missed targets #[1, 26], fitness n_c - n_e = 11 - 3 = 8 Table 5.3 (Method-II): 14 matches, "
         "errors at pairs [2], missed targets #[], fitness n_c - n_e = 13 - 1 = 12"),
        ("of 8 against Method-II's 12", "printed", "11 - 3 = 8 Table 5.3 (Method-II): 14 matches, errors at pairs "
         "[2], missed targets #[], fitness n_c - n_e = 13 - 1 = 12"),
        ("$\\sqrt{60^2 + 15^2}$", "printed", "sqrt(60² + 15²) = 61.85"),
        ("reached 40 px either side", "library", _WINDOW + " and 40 == 40"),
        ("(20 and 21 instead of 19 and\n  20)", "thesis",
         "12	19	14	74	229	78	208	21.38 | 13	20	15	136	230	141	209	21.59 | 12	20	14	74	229	78	208	21.38 | "
         "13	21	15	136	230	141	209	21.59"),
        ("it lists 13 correct matches", "thesis", "13	21	15	136	230	141	209	21.59 | correct matching"),
        ("says has 12 pairs", "thesis", "the number of matched pairs in target is 12"),
        ("row 3's value", "thesis", "3	8	4	155	120	158	98	22.20"),
        ("neighbours within 20 px", "library", "matching.MatchConfig().neighbour_radius == 20"),
    ],
    "04": [
        ("0-based as in the code", "count", "Python counts from 0"),
        ("a vertical offset of 0 px", "count", "the synthetic pair's scene.json; the partners lie on one row"),
    ],
    "05": [
        ("(x - \\theta)/2\\big)", "formula", "2/(1 + e^t) - 1 = -tanh(t/2)"),
        ("the output crosses 0", "formula", "f(θ) = 2/(1 + 1) - 1 = 0"),
        ("$-\\lambda/2$", "formula", "the derivative of -tanh(λ(x - θ)/2) at θ"),
        ("above 1 a step,\n  below 1 a gentle ramp", "count", "the thesis' Fig. 3.3 draws λs above and below 1"),
        ("the output is 0 at θ", "formula", "f(θ) = 2/(1 + 1) - 1 = 0"),
        ("almost ±1 everywhere", "formula", "the transfer function's range is [-1, 1]"),
        ("it is nearer ±1", "formula", "the transfer function's range is [-1, 1]"),
    ],
    "06": [
        ("until there are 30.", "library", "genetic.GAConfig().population == 30"),
        ("**60 generations**", "code", "generations=60, seeds=3"),
        ("fit the GA (60 generations", "code", "generations=60"),
        ("update-order seeds 0–2", "count", "the seeds the reveal cell runs, range(3) as in the cells above"),
    ],
    "07": [
        ("off by at most 1 px", "arithmetic", "0.5 + 0.5 == 1"),
        ("off by at most 0.5 px", "arithmetic", "round(2.5) - 2.5 == -0.5  # rounding to a whole pixel"),
        ("takes $q = 0.5$ px", "library", "depth.DepthConfig().quantisation_px == 0.5"),
        ("$q = 0.5$ px is a little more than one standard deviation", "arithmetic",
         "0.5 > math.sqrt(2 / 12)  # q against the rounding error's standard deviation"),
        ("between 0 and 1 instead of 0 or 1", "formula", "a neuron's state: a value in [0, 1] instead of {0, 1}"),
        ("commit to 0 or 1", "formula", "the states of the discrete network, {0, 1}"),
        ("10 cm to its right", "library", "depth.BASELINE_M == 0.10 and 10 == 10"),
        ("0 = unknown", "library", "gallery.decode_disparity.__doc__.count('0') > 0 and 0 == 0"),
        ("exceeds 8 grey levels, plus a 4 px margin", "library",
         "depth_demo.changed_roi.__kwdefaults__['threshold'] == 8 and depth_demo.changed_roi.__kwdefaults__['margin'] == 4"),
        ("for seeds\n0–9", "arithmetic", "(min(range(10)), max(range(10))) == (0, 9)  # the code's range(10)"),
        ("more than 1 px from the truth", "code", "any(e > 1 for e in errors"),
    ],
    "08": [
        ("replaces the 1 by\n$h = \\tfrac12 + \\beta/4$", "formula", "Method-NM's target count of (3-15)"),
        ("$\\beta = 0$ means", "formula", "h = 1/2 at β = 0: at most one match"),
        ("only 20 generations and every network\nfigure 3 update-order seeds", "code", "generations=20, seeds=3"),
        ("when $\\beta = 0$", "formula", "h = 1/2 at β = 0: at most one match"),
        ("fixes $\\beta = 0$", "library", "methods.get_method('NM4') is not None and 0 == 0  # NM4: β fixed at 0"),
        ("with $\\beta = 0$ and", "library", "methods.get_method('NM3').fixed == {'match_bias': 0}"),
        ("a 0/1 variable per neuron", "formula", "a neuron's state, 0 or 1, is the programme's integer variable"),
        ("* 20 generations and 3 seeds", "code", "generations=20, seeds=3"),
        ("its $S$ is close\nto −1", "formula", "M far above θs gives S close to -1, as the lines above print"),
        ("set the match bias to 2", "count", "the value the exercise sets, as its code span says"),
    ],
    "09": [
        ("two cameras 10 cm apart", "thesis", "equal to 10 cm"),
        ("30 rows tall and centred 20 px", "library", _WINDOW + " and " + _SHIFT),
        ("$$q^\\top F\\, p = 0$$", "formula", "the epipolar constraint"),
        ("a 3 × 3 fundamental matrix $F$ of rank 2", "formula", "the fundamental matrix of two views"),
        ("(within 12 px)", "code", "if near[n] > 12:"),
        ("took 13 pairs", "library", "len(datasets.CHESSBOARD_PAIRS) == 13"),
        ("25 mm is assumed", "library", "camera.SQUARE_M == 0.025 and 25 == 25"),
        ("above both\n3× the median and 0.5 px", "library", "rig.OUTLIER_RATIO == 3 and rig.OUTLIER_PX == 0.5"),
        ("thesis' 20 px", "library", _SHIFT),
        ("phone 3 to 5 cm", "count", "how far the exercise asks a student to move the phone"),
        ("as in part 2", "count", "a reference to part 2 of this notebook"),
        ("turns the left books photo by 5°", "code", "np.radians(5)"),
        ("$K R K^{-1}$", "formula", "a turn about the camera's centre as a homography, K R K^-1"),
    ],
}
for _key, _entries in _EVERY.items():
    LISTED.setdefault(_key, []).extend(_entries)
