"""Pooling a collected class (nbgrader's submitted/ folder), tune's refusal of many-to-one
targets, and lock files no other user can hold."""

import hashlib
import json
import os
import re
import stat
from pathlib import Path

import pytest

from ismb_lab.labels.classroom import collected, pool, save_merging
from ismb_lab.cli import main
from ismb_lab.tuning.cases import Case
from ismb_lab.labels.targets import TargetSet, load_targets, save_targets

IMAGES = Path(__file__).resolve().parents[1] / "images"
LAB = IMAGES / "lab"
KEY = load_targets(LAB / "answer_key.json")


def subset(rows, rights=None):
    """Pairs `rows` of the lab key (with the rights of `rights` instead, when given)."""
    rights = rows if rights is None else rights
    return TargetSet(KEY.left_xy[rows], KEY.right_xy[rights], KEY.left_sha256, KEY.right_sha256)


def hand_in(course, student, targets, name=None):
    """What 'nbgrader collect' leaves: submitted/<student>/labels/<file>."""
    folder = course / "submitted" / student / "labels"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "timestamp.txt").write_text("2026-11-25 21:00:00.000000 UTC")
    return save_targets(folder / (name or f"targets-{student}-lab.json"), targets)


def test_a_student_votes_once_however_many_copies_they_hand_in(tmp_path):
    course = tmp_path / "course"
    hand_in(course, "ann", subset([0, 1]))
    hand_in(course, "bob", subset([0, 1], [1, 0]))        # bob swapped the partners of 0 and 1
    theirs = hand_in(course, "cy", subset([0, 1, 2], [1, 0, 2]))   # so did cy, who labelled 2 as well
    # cy hands in three more copies of the same labels, two of them renamed: still one vote
    for name in ("targets-cy-lab-copy.json", "targets-ann-lab.json", "targets-dee-lab.json"):
        (theirs.parent / name).write_bytes(theirs.read_bytes())
    groups = collected(course)
    assert sorted(groups) == ["ann", "bob", "cy"] and len(groups["cy"]) == 4
    p = pool(groups)
    # counting files, cy's four copies would outvote ann and bob; by student it is 2 against 1
    assert sorted(map(tuple, p.targets.right_xy.tolist())) == sorted(map(tuple, KEY.right_xy[[1, 0, 2]].tolist()))
    assert {tuple(e["labelled_by"]) for e in p.targets.extras} == {("bob", "cy"), ("cy",)}
    assert p.students["cy"] == {"pairs": 3, "files": 4} and p.identical == []
    assert "from 3 students (6 files)" in p.report()


def test_a_renamed_copy_of_another_students_file_is_named_and_votes_once(tmp_path):
    course = tmp_path / "course"
    ann = hand_in(course, "ann", subset([0, 1, 2]))
    # bob hands in ann's file under ann's own file name: the folder says it is bob's
    copy = course / "submitted" / "bob" / "labels" / ann.name
    copy.parent.mkdir(parents=True)
    copy.write_bytes(ann.read_bytes())
    hand_in(course, "cy", subset([0, 1, 2], [1, 0, 2]))
    p = pool(collected(course))
    assert set(p.students) == {"ann", "bob", "cy"}
    assert p.identical == [{"students": ["ann", "bob"], "files": [str(ann), str(copy)], "pairs": 3}]
    # one vote for ann's file ties with cy's on points 0 and 1; only 2, which cy agrees on, is kept
    assert [(e["labelled_by"], e["votes"]) for e in p.targets.extras] == [(["ann", "bob", "cy"], 2)]
    assert "identical files, counted as one vote: ann (targets-ann-lab.json), bob (targets-ann-lab.json)" \
        in p.report()
    each = pool(collected(course), identical="each")    # the teacher knows they labelled alike
    assert sorted(e["labelled_by"] for e in each.targets.extras) == [["ann", "bob"], ["ann", "bob"],
                                                                      ["ann", "bob", "cy"]]


def test_the_same_file_collected_twice_votes_once(tmp_path):
    ann = save_targets(tmp_path / "targets-ann-lab.json", subset([0, 1]))
    (tmp_path / "again").mkdir()
    again = tmp_path / "again" / ann.name
    again.write_bytes(ann.read_bytes())
    bob = save_targets(tmp_path / "targets-bob-lab.json", subset([0, 1], [1, 0]))
    cy = save_targets(tmp_path / "targets-cy-lab.json", subset([0, 1, 2], [1, 0, 2]))
    # ann's file twice would tie 2 against 2 and drop the pairs bob and cy agree on
    p = pool([ann, again, bob, cy])
    assert [e["labelled_by"] for e in p.targets.extras] == [["targets-bob-lab", "targets-cy-lab"]] * 2 + [
        ["targets-cy-lab"]]


def test_many_to_one_pairs_are_reported_and_dropped(tmp_path):
    course = tmp_path / "course"
    # ann gives right corner 0 two left partners in one file: her pairs on it get no vote
    hand_in(course, "ann", TargetSet(KEY.left_xy[[0, 1, 2]], KEY.right_xy[[0, 0, 2]],
                                     KEY.left_sha256, KEY.right_sha256))
    # bob and cy each pair a different left corner with right corner 5: neither is kept
    hand_in(course, "bob", subset([3, 4], [5, 4]))
    hand_in(course, "cy", subset([5, 4]))
    p = pool(collected(course))
    kept = {tuple(x) for x in p.targets.right_xy.tolist()}
    assert tuple(KEY.right_xy[0]) not in kept and tuple(KEY.right_xy[5]) not in kept
    assert kept == {tuple(KEY.right_xy[2]), tuple(KEY.right_xy[4])}
    assert p.students["ann"] == {"pairs": 1, "many_to_one": 2}
    assert [d["right_xy"] for d in p.disagreements if "right_xy" in d] == [KEY.right_xy[5].tolist()]
    report = p.report()
    assert "ann: 1 pairs; 2 pairs dropped: a corner given two partners" in report
    assert "1 right points given several left partners; 4 pairs dropped" in report


def test_min_votes_sets_how_many_students_must_agree(tmp_path):
    course = tmp_path / "course"
    hand_in(course, "ann", subset([0, 1, 2]))
    hand_in(course, "bob", subset([0, 1]))
    hand_in(course, "cy", subset([0]))
    counts = {n: len(pool(collected(course), min_votes=n).targets) for n in (1, 2, 3, 4)}
    assert counts == {1: 3, 2: 2, 3: 1, 4: 0}
    with pytest.raises(ValueError, match="'min_votes' parameter of pool"):
        pool(collected(course), min_votes=0)


def test_targets_merge_reads_a_collected_folder(tmp_path, capsys):
    course = tmp_path / "course"
    hand_in(course, "ann", subset([0, 1, 2]))
    hand_in(course, "bob", subset([0, 1, 2, 3]))
    hand_in(course, "cy", subset([0, 1, 2], [1, 0, 2]))
    before = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in course.rglob("*.json")}
    out = tmp_path / "class.json"
    assert main(["targets", "merge", str(course / "submitted"), "--out", str(out), "--min-votes", "2"]) == 0
    text = capsys.readouterr().out
    assert "3 pooled pairs from 3 files" in text and "at least 2 votes per pair" in text
    pooled = load_targets(out)
    assert len(pooled) == 3 and pooled.meta["min_votes"] == 2
    assert {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in course.rglob("*.json")} == before
    # the course folder holding submitted/ works too; --min-votes 3 keeps only pair 2
    assert main(["targets", "merge", str(course), "--out", str(out), "--min-votes", "3"]) == 0
    assert load_targets(out).left_xy.tolist() == [KEY.left_xy[2].tolist()]


@pytest.mark.parametrize("args, words", [
    (["--min-votes", "0"], "--min-votes must be 1 or more"),
    (["--pattern", "nothing-*.json"], "'nothing-*.json' files"),
    (["EXTRA"], "not both"),
])
def test_targets_merge_bad_input_is_one_line(tmp_path, capsys, args, words):
    course = tmp_path / "course"
    hand_in(course, "ann", subset([0]))
    out = tmp_path / "class.json"
    extra = [str(course / "submitted" / "ann" / "labels" / "targets-ann-lab.json")] if "EXTRA" in args else []
    args = [a for a in args if a != "EXTRA"]
    assert main(["targets", "merge", str(course), *extra, "--out", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "ismb-lab: error:" in err and words in err, err
    assert not out.exists()


def test_tune_refuses_many_to_one_targets_in_one_line(tmp_path, capsys):
    bad = save_targets(tmp_path / "bad.json", TargetSet(KEY.left_xy[[0, 1, 2]], KEY.right_xy[[0, 0, 2]],
                                                        KEY.left_sha256, KEY.right_sha256))
    with pytest.raises(ValueError, match=r"pair each corner once. Got pairs\[0\] and pairs\[1\] sharing "
                                         r"the right point .* 'ismb-lab targets merge .*bad.json"):
        Case.from_files(LAB / "left.png", LAB / "right.png", bad)
    out = tmp_path / "params.json"
    assert main(["tune", str(LAB / "left.png"), str(LAB / "right.png"), str(bad), "--out", str(out),
                 "--generations", "2"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pair each corner once" in err and "targets merge" in err
    assert not out.exists()
    # the merged file is one-to-one: tune's library path accepts it
    fixed = tmp_path / "fixed.json"
    assert main(["targets", "merge", str(bad), "--out", str(fixed)]) == 0
    assert len(Case.from_files(LAB / "left.png", LAB / "right.png", fixed).targets) == 1


def test_a_lock_file_is_private_to_its_owner(tmp_path):
    old = os.umask(0o022)
    try:
        path = tmp_path / "targets-ann-lab.json"
        save_merging(path, subset([0]))
        lock = tmp_path / ".targets-ann-lab.json.lock"
        assert stat.S_IMODE(lock.stat().st_mode) == 0o600
        lock.chmod(0o644)                   # left readable by an older version: tightened
        save_merging(path, subset([0, 1]), load_targets(path))
        assert stat.S_IMODE(lock.stat().st_mode) == 0o600
    finally:
        os.umask(old)


def test_the_assignment_source_is_generated_from_the_notebook(tmp_path):
    from ismb_lab.teaching.course import course_images, make_source

    folder = make_source(tmp_path / "course")
    # the notebook's cells, but for its paths into ../images/, which are the assignment's own
    # images/ in its code and in the commands its text prints
    ours = json.loads((IMAGES.parent / "notebooks" / "04_label_targets.ipynb").read_text(encoding="utf-8"))
    theirs = json.loads((folder / "04_label_targets.ipynb").read_text(encoding="utf-8"))
    assert len(theirs["cells"]) == len(ours["cells"])
    for mine, made in zip(ours["cells"], theirs["cells"]):
        assert {k: v for k, v in made.items() if k != "source"} == {k: v for k, v in mine.items() if k != "source"}
        assert "".join(made["source"]) == re.sub(r"(?<![\w./-])\.\./images/", "images/", "".join(mine["source"]))
    assert "../images/" not in json.dumps(theirs) and "`ismb-lab match images/synthetic/left.png" in json.dumps(theirs)
    assert course_images("synthetic", folder) == folder / "images" / "synthetic"
    (folder / "stale.txt").write_text("hand-edited")
    assert make_source(tmp_path / "course") == folder and not (folder / "stale.txt").exists()
    assert [p.name for p in (tmp_path / "course" / "source").iterdir()] == ["labels"]
    # a notebook without nbgrader metadata is refused, and the old source stays
    repo = tmp_path / "repo"
    (repo / "notebooks").mkdir(parents=True)
    (repo / "notebooks" / "04_label_targets.ipynb").write_text('{"cells": [{"metadata": {}}]}')
    (repo / "images").symlink_to(IMAGES)
    with pytest.raises(ValueError, match="unique grade_id"):
        make_source(tmp_path / "course", repo=repo)
    assert (folder / "04_label_targets.ipynb").is_file()


def test_the_commands_a_notebook_prints_name_the_assignments_own_files(tmp_path):
    """``ismb-lab evaluate ../images/realistic/manifest.json`` in notebooks/ is
    ``ismb-lab evaluate images/realistic/manifest.json`` in the assignment, which holds it; a
    path named only in the text is copied too, and prose and other paths are left alone."""
    from ismb_lab.teaching.course import make_source

    repo = tmp_path / "repo"
    (repo / "notebooks").mkdir(parents=True)
    (repo / "images").symlink_to(IMAGES)
    cells = [{"cell_type": "markdown", "id": "a", "metadata": {"nbgrader": {"grade_id": "a"}},
              "source": "Run `ismb-lab match ../images/lab/left.png ../images/lab/right.png`, or\n\n"
                        "    ismb-lab evaluate ../images/realistic/manifest.json\n\n"
                        "(not ../../images/x/ nor docs/../images/y)"},
             {"cell_type": "code", "id": "b", "execution_count": None, "outputs": [],
              "metadata": {"nbgrader": {"grade_id": "b", "grade": True, "points": 1}},
              "source": "pair = load_pair('../images/synthetic/left.png', '../images/synthetic/right.png')"}]
    nb = {"cells": cells, "metadata": {}, "nbformat": 4, "nbformat_minor": 5}
    (repo / "notebooks" / "03_methods_compared.ipynb").write_text(json.dumps(nb))
    folder = make_source(tmp_path / "course", "03-methods", repo=repo)
    made = json.loads((folder / "03_methods_compared.ipynb").read_text())["cells"]
    assert "".join(made[0]["source"]) == ("Run `ismb-lab match images/lab/left.png images/lab/right.png`, or\n\n"
                                          "    ismb-lab evaluate images/realistic/manifest.json\n\n"
                                          "(not ../../images/x/ nor docs/../images/y)")
    assert "".join(made[1]["source"]) == "pair = load_pair('images/synthetic/left.png', 'images/synthetic/right.png')"
    assert sorted(p.name for p in (folder / "images").iterdir()) == ["lab", "realistic", "synthetic"]


def test_a_submission_is_private_and_filed_under_its_owner(tmp_path):
    import pwd

    from ismb_lab.teaching.exchange import OwnerCollect, PrivateSubmit

    work = tmp_path / "sub" / "labels"
    work.mkdir(parents=True)
    (work / "targets-ann-lab.json").write_text("{}")
    PrivateSubmit().set_perms(str(tmp_path / "sub"), 0o644, 0o755)
    assert stat.S_IMODE((work / "targets-ann-lab.json").stat().st_mode) == 0o640
    assert stat.S_IMODE(work.stat().st_mode) & 0o007 == 0
    claimed = tmp_path / "somebody+labels+2026-11-25 21:00:00.000000 UTC+abc"
    claimed.mkdir()
    record = OwnerCollect()._path_to_record(str(claimed))
    assert record["username"] == pwd.getpwuid(os.getuid()).pw_name
