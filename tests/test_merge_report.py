"""What `targets merge` drops and why, files two students handed in alike, and tune's word
on a negative fitness."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from ismb_lab.labels.classroom import collected, pool
from ismb_lab.cli import main
from ismb_lab.labels.targets import TargetSet, load_targets, save_targets

IMAGES = Path(__file__).resolve().parents[1] / "images"


def left(i):
    return [10.0 * i + 20, 10.0]


def right(k):
    return [10.0 * k + 15, 10.0]


def pairs(*ik, **meta):
    """Targets pairing left corner i with right corner k, for each (i, k)."""
    ik = list(ik)
    return TargetSet(np.reshape([left(i) for i, _ in ik], (-1, 2)), np.reshape([right(k) for _, k in ik], (-1, 2)),
                     meta=meta)


def hand_in(course, student, targets, name=None):
    """What 'nbgrader collect' leaves: submitted/<student>/labels/<file>."""
    folder = course / "submitted" / student / "labels"
    folder.mkdir(parents=True, exist_ok=True)
    return save_targets(folder / (name or f"targets-{student}-lab.json"), targets)


def as_ik(points):
    """Corner indices (i, k) of a pair's points."""
    return int(round((points[0][0] - 20) / 10)), int(round((points[1][0] - 15) / 10))


def dropped(p):
    return {as_ik((d["left_xy"], d["right_xy"])): d for d in p.dropped}


def kept(p):
    return {as_ik((a, b)) for a, b in zip(p.targets.left_xy.tolist(), p.targets.right_xy.tolist())}


# --- every dropped pair, with its reason -------------------------------------------------

def test_a_pair_lost_to_a_right_corner_conflict_is_reported_when_the_left_corners_are_disputed(tmp_path):
    course = tmp_path / "course"
    hand_in(course, "ann", pairs((9, 10)))           # right
    hand_in(course, "bob", pairs((8, 10)))           # gives right corner 10 to left corner 8
    hand_in(course, "cy", pairs((8, 8)))             # so left corner 8 is disputed too
    p = pool(collected(course))
    assert kept(p) == set()
    d = dropped(p)
    assert set(d) == {(9, 10), (8, 10), (8, 8)}
    nine = d[(9, 10)]
    assert nine["reasons"] == ["right"] and nine["votes"] == 1 and nine["labelled_by"] == ["ann"]
    assert nine["right_rivals"] == [{"partner": left(8), "votes": 1, "labelled_by": ["bob"], "voters": ["bob"]}]
    assert d[(8, 10)]["reasons"] == ["left", "right"]
    report = p.report()
    assert "[110.0, 10.0] -> [115.0, 10.0], 1 vote (ann): its right corner has 1 vote for [100.0, 10.0] (bob)" \
        in report
    # the right corner is counted among the disagreements, though its left corners are disputed
    assert [q["right_xy"] for q in p.disagreements if "right_xy" in q] == [right(10)]
    assert "1 right points given several left partners" in report and "3 pairs dropped" in report


def test_every_reason_is_named_with_its_votes(tmp_path):
    course = tmp_path / "course"
    hand_in(course, "ann", pairs((1, 1), (2, 2), (3, 3), (4, 4), (5, 5), (6, 6)))
    hand_in(course, "bob", pairs((1, 1), (2, 2), (3, 4), (4, 3), (7, 7), (5, 0)))
    hand_in(course, "cy", pairs((1, 1), (2, 8), (3, 3), (4, 4)))
    hand_in(course, "dee", pairs((2, 2), (6, 6), (6, 9)))    # dee gives left corner 6 two partners
    p = pool(collected(course), min_votes=2)
    d = dropped(p)
    assert kept(p) == {(1, 1), (2, 2), (3, 3), (4, 4)}
    assert set(d) == {(3, 4), (4, 3), (2, 8), (7, 7), (5, 0), (5, 5), (6, 6), (6, 9)}
    assert d[(3, 4)]["reasons"] == ["left", "right", "min_votes"]
    assert d[(2, 8)]["left_rivals"] == [{"partner": right(2), "votes": 3, "labelled_by": ["ann", "bob", "dee"],
                                         "voters": ["ann", "bob", "dee"]}]
    assert d[(2, 8)]["reasons"] == ["left", "min_votes"]
    assert d[(7, 7)]["reasons"] == ["min_votes"] and d[(7, 7)]["votes"] == 1
    # ann's 5 -> 5 against bob's 5 -> 0: a tie, and one vote each is below --min-votes 2
    assert d[(5, 5)]["reasons"] == ["left", "min_votes"]
    # dee's 6 -> 6 gets no vote (dee gave left corner 6 a second partner): ann's alone is below 2
    assert d[(6, 6)]["reasons"] == ["min_votes", "two_partners"] and d[(6, 6)]["no_vote_from"] == ["dee"]
    # a pair nobody's vote holds is dropped for that alone, whatever its corners' other partners
    assert d[(6, 9)] == {"left_xy": left(6), "right_xy": right(9), "votes": 0, "labelled_by": [], "voters": [],
                         "reasons": ["two_partners"],
                         "left_rivals": [{"partner": right(6), "votes": 1, "labelled_by": ["ann"], "voters": ["ann"]}],
                         "right_rivals": [], "no_vote_from": ["dee"]}
    report = p.report()
    assert "8 pairs dropped" in report
    for line in ("[90.0, 10.0] -> [85.0, 10.0], 1 vote (bob): fewer than 2 votes",
                 "[40.0, 10.0] -> [95.0, 10.0], 1 vote (cy): its left corner has 3 votes for [35.0, 10.0] "
                 "(ann, bob, dee); fewer than 2 votes",
                 "[50.0, 10.0] -> [55.0, 10.0], 1 vote (bob): its left corner has 2 votes for [45.0, 10.0] "
                 "(ann, cy); its right corner has 2 votes for [60.0, 10.0] (ann, cy); fewer than 2 votes",
                 "[80.0, 10.0] -> [105.0, 10.0], 0 votes: no vote from dee, who gave one of its corners "
                 "two partners",
                 "[80.0, 10.0] -> [75.0, 10.0], 1 vote (ann): fewer than 2 votes; no vote from dee"):
        assert line in report, line


@pytest.mark.parametrize("seed", range(8))
def test_the_pool_and_the_dropped_pairs_are_every_pair_handed_in(tmp_path, seed):
    """Random classes: each pair handed in is pooled or dropped, and a dropped pair's reasons
    are exactly the rules it breaks, with the votes counted here from what was handed in."""
    rng = np.random.default_rng(seed)
    files, handed, ballots = {}, {}, {}
    for n in range(int(rng.integers(2, 8))):
        lefts = rng.choice(8, size=int(rng.integers(1, 7)), replace=False)
        ik = [(int(i), int(i) if rng.random() < 0.6 else int(rng.integers(0, 8))) for i in lefts]
        if rng.random() < 0.3:                                    # a corner given two partners
            ik.append((ik[0][0], (ik[0][1] + 1) % 8))
        ik = list(dict.fromkeys(ik))
        name = f"s{n}"
        files[name] = [save_targets(tmp_path / f"{name}.json", pairs(*ik))]
        for pair in ik:
            handed.setdefault(pair, []).append(name)
        ballots[name] = {(i, k) for i, k in ik
                         if sum(a == i for a, _ in ik) == 1 and sum(b == k for _, b in ik) == 1}
    min_votes = int(rng.integers(1, 3))
    p = pool(files, min_votes=min_votes)
    d = dropped(p)
    assert kept(p).isdisjoint(d) and kept(p) | set(d) == set(handed)
    assert len(p.dropped) == len(d)

    def votes(i, k):
        return sorted(s for s, b in ballots.items() if (i, k) in b)

    for (i, k), rec in d.items():
        lefts = {k2: votes(i, k2) for (i2, k2) in handed if i2 == i and k2 != k and votes(i, k2)}
        rights = {i2: votes(i2, k) for (i2, k2) in handed if k2 == k and i2 != i and votes(i2, k)}
        n = len(votes(i, k))
        expect = ([("left", 2 * n <= n + sum(map(len, lefts.values()))),
                   ("right", 2 * n <= n + sum(map(len, rights.values()))),
                   ("min_votes", n < min_votes)] if n else []) + [("two_partners", n < len(handed[(i, k)]))]
        assert rec["reasons"] == [r for r, on in expect if on] and rec["reasons"]
        assert rec["votes"] == n and rec["labelled_by"] == votes(i, k)
        assert rec["no_vote_from"] == sorted(set(handed[(i, k)]) - set(votes(i, k)))
        assert {as_ik((left(i), r["partner"]))[1]: r["labelled_by"] for r in rec["left_rivals"]} == lefts
        assert {as_ik((r["partner"], right(k)))[0]: r["labelled_by"] for r in rec["right_rivals"]} == rights
    # the report has one line per dropped pair
    assert len([line for line in p.report().splitlines() if " -> " in line]) == len(d)


def test_a_class_without_conflicts_pools_as_before(tmp_path):
    course = tmp_path / "course"
    hand_in(course, "ann", pairs((1, 1), (2, 2), (3, 3)))
    hand_in(course, "bob", pairs((2, 2), (4, 4)))
    out = tmp_path / "class.json"
    assert main(["targets", "merge", str(course), "--out", str(out)]) == 0
    assert json.loads(out.read_text()) == {
        "version": 1, "orientation": "upright",
        "pooled_from": ["targets-ann-lab.json", "targets-bob-lab.json"], "min_votes": 1,
        "pairs": [{"left_xy": left(1), "right_xy": right(1), "labelled_by": ["ann"], "of": 1},
                  {"left_xy": left(2), "right_xy": right(2), "labelled_by": ["ann", "bob"], "of": 2},
                  {"left_xy": left(3), "right_xy": right(3), "labelled_by": ["ann"], "of": 1},
                  {"left_xy": left(4), "right_xy": right(4), "labelled_by": ["bob"], "of": 1}]}
    p = pool(collected(course))
    assert p.dropped == [] and p.identical == [] and "dropped" not in p.report()
    assert "identical" not in p.report()


# --- files handed in alike -----------------------------------------------------------------

def test_a_copy_renamed_after_its_author_counts_once_and_is_named(tmp_path):
    course = tmp_path / "course"
    ann = hand_in(course, "ann", pairs((1, 1), (2, 2), (3, 3)))
    hand_in(course, "bob", pairs((1, 1), (2, 3), (3, 2)))
    copy = course / "submitted" / "cy" / "labels" / "targets-cy-lab.json"
    copy.parent.mkdir(parents=True)
    copy.write_bytes(ann.read_bytes())
    p = pool(collected(course))
    # counted twice, ann's copy would win 2 against 1; counted once it ties with bob
    assert kept(p) == {(1, 1)}
    assert p.identical == [{"students": ["ann", "cy"], "files": [str(ann), str(copy)], "pairs": 3}]
    assert p.students["cy"]["identical"] == ["ann"] and p.students["ann"]["identical"] == ["cy"]
    assert p.students["bob"] == {"pairs": 3}
    d = dropped(p)
    assert d[(2, 2)]["votes"] == 1 and d[(2, 2)]["labelled_by"] == ["ann", "cy"]
    assert d[(2, 2)]["reasons"] == ["left", "right"]
    extras = p.targets.extras[0]
    assert extras == {"labelled_by": ["ann", "bob", "cy"], "of": 2, "votes": 2, "identical": [["ann", "cy"]]}
    report = p.report()
    assert ("identical files, counted as one vote: ann (targets-ann-lab.json), cy (targets-cy-lab.json); "
            "3 pairs") in report
    assert "[40.0, 10.0] -> [35.0, 10.0], 1 vote (ann+cy): its left corner has 1 vote for [45.0, 10.0] (bob)" \
        in report
    # and when the teacher knows they labelled alike on their own, each votes again
    each = pool(collected(course), identical="each")
    assert kept(each) == {(1, 1), (2, 2), (3, 3)} and each.identical == p.identical
    assert "identical files, each a vote" in each.report()


def test_the_same_pairs_in_another_order_or_with_other_keys_are_identical(tmp_path):
    a = save_targets(tmp_path / "targets-ann-lab.json", pairs((1, 1), (2, 2), (3, 3)))
    b = save_targets(tmp_path / "targets-bob-lab.json", pairs((3, 3), (1, 1), (2, 2), labeller="bob"))
    assert a.read_bytes() != b.read_bytes()
    c = save_targets(tmp_path / "targets-cy-lab.json", pairs((1, 2), (2, 1)))
    p = pool([a, b, c])
    assert [g["students"] for g in p.identical] == [["targets-ann-lab", "targets-bob-lab"]]
    assert kept(p) == {(3, 3)}


def test_a_copy_loaded_into_the_labeller_and_saved_under_ones_name_is_identical(tmp_path):
    from ismb_lab.matching.pipeline import prepare
    from ismb_lab.labels.targets import snap
    from ismb_lab.widgets.labeler import LabelModel

    prepared = prepare(IMAGES / "synthetic" / "left.png", IMAGES / "synthetic" / "right.png")
    key = load_targets(IMAGES / "synthetic" / "answer_key.json")
    ik = snap(key, prepared.problem.left_xy, prepared.problem.right_xy).pairs.tolist()[:6]
    ann = LabelModel(prepared)
    for n, (i, k) in enumerate(reversed(ik)):          # clicked last corner first, saved twice
        ann.add_pair(i, k)
        if n == 2:
            ann.save(tmp_path / "targets-ann-synthetic.json")
    ann.save(tmp_path / "targets-ann-synthetic.json")
    cy = LabelModel(prepared)
    cy.load(tmp_path / "targets-ann-synthetic.json")
    cy.save(tmp_path / "targets-cy-synthetic.json")
    files = [tmp_path / f"targets-{who}-synthetic.json" for who in ("ann", "cy")]
    assert files[0].read_bytes() != files[1].read_bytes()     # the labeller sorted cy's copy
    p = pool(files)
    assert [g["students"] for g in p.identical] == [["targets-ann-synthetic", "targets-cy-synthetic"]]
    assert all(e.get("votes") == 1 for e in p.targets.extras) and len(p.targets) == 6


@pytest.mark.parametrize("bob", [
    [(1, 1), (2, 2)],                    # a subset of ann's pairs
    [(1, 1), (2, 2), (3, 3), (4, 4)],    # a superset: bob labelled one more
    [(1, 1), (2, 2), (3, 4)],            # one pair differs
])
def test_files_that_differ_by_a_pair_are_not_identical(tmp_path, bob):
    a = save_targets(tmp_path / "ann.json", pairs((1, 1), (2, 2), (3, 3)))
    b = save_targets(tmp_path / "bob.json", pairs(*bob))
    p = pool([a, b])
    assert p.identical == [] and "identical" not in p.report()
    assert all("votes" not in e for e in p.targets.extras)
    assert next(e for e in p.targets.extras if e["labelled_by"] == ["ann", "bob"])["of"] == 2


def test_copies_within_one_students_folder_are_not_named(tmp_path):
    course = tmp_path / "course"
    mine = hand_in(course, "ann", pairs((1, 1), (2, 2)))
    (mine.parent / "targets-ann-lab-copy.json").write_bytes(mine.read_bytes())
    hand_in(course, "bob", pairs((1, 1), (2, 2), (3, 3)))
    p = pool(collected(course))
    assert p.identical == [] and p.students["ann"] == {"pairs": 2, "files": 2}


def test_a_chain_of_copies_is_one_vote(tmp_path):
    course = tmp_path / "course"
    x = pairs((1, 2), (2, 1), (3, 3))                          # wrong on corners 1 and 2
    hand_in(course, "ann", x)
    hand_in(course, "bob", x, "targets-bob-lab.json")
    hand_in(course, "bob", pairs((3, 3), (5, 5), (6, 6)), "targets-bob-more.json")
    hand_in(course, "cy", pairs((3, 3), (5, 5), (6, 6)))       # cy holds a copy of bob's second file
    hand_in(course, "dee", pairs((1, 1), (2, 2), (3, 4)))
    hand_in(course, "eve", pairs((1, 1), (2, 2), (5, 5)))
    p = pool(collected(course))
    assert [g["students"] for g in p.identical] == [["ann", "bob"], ["bob", "cy"]]
    d = dropped(p)
    # ann and bob are one vote on 1 -> 2: two votes win against it
    assert {(1, 1), (2, 2)} <= kept(p) and (1, 2) in d
    # ann = bob (one file) and bob = cy (another) make one vote on 3 -> 3: a tie with dee
    assert d[(3, 3)]["votes"] == 1 and d[(3, 3)]["labelled_by"] == ["ann", "bob", "cy"]
    assert "1 vote (ann+bob+cy)" in p.report()
    # bob and cy are one vote on 5 -> 5, with eve two
    five = next(e for e, ik in zip(p.targets.extras, map(as_ik, zip(p.targets.left_xy.tolist(),
                                                                     p.targets.right_xy.tolist())))
                if ik == (5, 5))
    assert five == {"labelled_by": ["bob", "cy", "eve"], "of": 2, "votes": 2, "identical": [["bob", "cy"]]}
    with pytest.raises(ValueError, match="'identical' parameter of pool"):
        pool(collected(course), identical="twice")


def test_targets_merge_names_copies_and_every_drop(tmp_path, capsys):
    course = tmp_path / "course"
    ann = hand_in(course, "ann", pairs((1, 1), (2, 2)))
    hand_in(course, "bob", pairs((1, 1), (2, 3)))
    (course / "submitted" / "cy" / "labels").mkdir(parents=True)
    (course / "submitted" / "cy" / "labels" / "targets-cy-lab.json").write_bytes(ann.read_bytes())
    out = tmp_path / "class.json"
    assert main(["targets", "merge", str(course), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "identical files, counted as one vote: ann (targets-ann-lab.json), cy (targets-cy-lab.json)" in text
    assert "2 pairs dropped" in text and re.search(r"\[40.0, 10.0\] -> \[35.0, 10.0\], 1 vote \(ann\+cy\)", text)
    assert len(load_targets(out)) == 1
    assert main(["targets", "merge", str(course), "--out", str(out), "--identical-files", "each"]) == 0
    assert "identical files, each a vote" in capsys.readouterr().out and len(load_targets(out)) == 2
    assert main(["targets", "merge", str(course), "--out", str(out), "--identical-files", "twice"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


# --- tune: a negative fitness explained ----------------------------------------------------

@pytest.fixture(scope="module")
def few_targets(tmp_path_factory):
    key = load_targets(IMAGES / "synthetic" / "answer_key.json")
    return save_targets(tmp_path_factory.mktemp("few") / "five.json",
                        TargetSet(key.left_xy[:5], key.right_xy[:5], key.left_sha256, key.right_sha256))


def test_tune_says_why_its_fitness_is_negative(few_targets, tmp_path, capsys):
    out = tmp_path / "p.json"
    pair = [str(IMAGES / "synthetic" / n) for n in ("left.png", "right.png")]
    assert main(["tune", *pair, str(few_targets), "--generations", "1", "--population", "4",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    fitness = json.loads(out.read_text())["fitness"]
    c, w, e, t = map(int, re.search(r"C/E/T (\d+)/(\d+)\+(\d+)/(\d+)", text).groups())
    assert fitness < 0 and c - w - e < 0, text
    why = [line for line in text.splitlines() if line.startswith("negative fitness")]
    assert len(why) == 1, text
    corners = re.search(r"(\d+) of the (\d+) left corners have no target pair", why[0])
    assert corners and int(corners[2]) - int(corners[1]) == t == 5
    assert f"({c} - {w} - {e} = {c - w - e} in the C/E/T above)" in why[0]
    assert f"the {e} extra are matches on left corners nobody labelled" in why[0]


def test_tune_says_nothing_more_when_its_fitness_is_not_negative():
    from ismb_lab.cli.tune import why_negative
    from ismb_lab.tuning.evaluation import Score

    assert why_negative(3, Score(5, 0, 2, 5), 40, 5) is None
    assert why_negative(0, Score(2, 1, 1, 5), 40, 5) is None
    assert why_negative(-1.5, Score(5, 1, 5, 6), 40, 6) == (
        "negative fitness: fitness = correct - wrong - extra (5 - 1 - 5 = -1 in the C/E/T above); "
        "the 5 extra are matches on left corners nobody labelled (34 of the 40 left corners have no "
        "target pair): label more corners, or judge by C/T")
    # the GA's mean over update-order seeds can be negative where the one run above is not
    assert why_negative(-0.5, Score(3, 0, 2, 6), 40, 6).startswith(
        "negative fitness: fitness = correct - wrong - extra (3 - 0 - 2 = 1 in the C/E/T above); the 2 extra")
    # no extra: the wrong partners are the reason
    assert why_negative(-1, Score(1, 2, 0, 6), 40, 6) == (
        "negative fitness: fitness = correct - wrong - extra (1 - 2 - 0 = -1 in the C/E/T above); "
        "more labelled corners got a wrong partner than the right one")
