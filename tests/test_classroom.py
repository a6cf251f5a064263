"""A class on one server: per-student files, saves that lose nothing across processes, pooling."""

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ismb_lab.labels.classroom import pool, save_merging, targets_path, user_name
from ismb_lab.cli import main
from ismb_lab.labels.targets import TargetSet, load_targets, save_targets

IMAGES = Path(__file__).resolve().parents[1] / "images"

CYCLES = """
import sys
from pathlib import Path
from ismb_lab.labels.classroom import save_merging
from ismb_lab.labels.targets import TargetSet, load_targets

path, worker, cycles, reload = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), sys.argv[4] == "load"
mine = base = None
for n in range(cycles):
    point = [[10.0 + n, 10.0 + worker * 100]], [[5.0 + n, 10.0 + worker * 100]]
    if reload:                              # load, add one pair, save: the issue's cycle
        base = load_targets(path)
        ours = base.add(point[0][0], point[1][0])
    else:                                   # never reload: keep one's own labels and save
        mine = TargetSet(*point) if mine is None else mine.add(point[0][0], point[1][0])
        ours = mine
    result = save_merging(path, ours, base)
    if not reload:
        base = mine = result.targets
"""


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["load", "keep"])
def test_two_processes_saving_one_file_lose_no_pair(tmp_path, mode):
    path = tmp_path / "class.json"
    save_targets(path, TargetSet([[1, 1]], [[0, 1]]))
    script = tmp_path / "cycles.py"
    script.write_text(CYCLES)
    cycles = 150
    procs = [subprocess.Popen([sys.executable, str(script), str(path), str(w), str(cycles), mode])
             for w in (1, 2)]
    assert [p.wait(timeout=600) for p in procs] == [0, 0]
    saved = load_targets(path)
    assert len(saved) == 2 * cycles + 1
    assert not list(tmp_path.glob(".class.json.*.tmp"))    # no temporary file left behind


def test_each_student_and_pair_has_its_own_file(monkeypatch):
    monkeypatch.setenv("JUPYTERHUB_USER", "ann/../x")
    assert user_name() == "ann-..-x" and targets_path("lab", "w").name == "targets-ann-..-x-lab.json"
    monkeypatch.delenv("JUPYTERHUB_USER")
    assert targets_path("lab", user="bob") != targets_path("synthetic", user="bob")
    assert targets_path("lab", user="bob") != targets_path("lab", user="cy")
    assert user_name()     # the login name when no hub says who it is
    with pytest.raises(TypeError, match="'pair' parameter of targets_path"):
        targets_path("")


def test_a_notebook_finds_the_labels_saved_in_the_released_labels_folder(tmp_path, monkeypatch):
    """nbgrader's release: 04 is the assignment "labels", 05 and 06 have folders of their own
    beside it (``~/labels/``, ``~/05-explorer/``, ``~/06-genetic/``).  Labels saved by the
    labeller in ``labels/`` are found with ``targets_path(pair)`` in theirs (06 trains on them)."""
    from ismb_lab.teaching.course import ASSIGNMENTS
    from ismb_lab.widgets.labeler import TargetLabeler

    monkeypatch.setenv("JUPYTERHUB_USER", "ann")
    names = [name for name in ASSIGNMENTS if name != "labels" and
             any(nb.startswith(("05_", "06_")) for nb in ASSIGNMENTS[name].notebooks)]
    assert "labels" in ASSIGNMENTS and len(names) == 2
    for name in ["labels", *names]:
        (tmp_path / name).mkdir()
    monkeypatch.chdir(tmp_path / "labels")
    labeler = TargetLabeler.from_folder(IMAGES / "synthetic")
    labeler.add_pair(0, 0)
    saved = labeler.save().resolve()
    assert saved == (tmp_path / "labels" / "targets-ann-synthetic.json").resolve()
    for name in names:
        monkeypatch.chdir(tmp_path / name)
        found = targets_path("synthetic")
        assert found.is_file() and found.resolve() == saved, (name, found)
        assert load_targets(found).left_xy.tolist() == load_targets(saved).left_xy.tolist()
    # no labels anywhere: the path in the notebook's own folder, which does not exist
    monkeypatch.setenv("JUPYTERHUB_USER", "bob")
    assert targets_path("synthetic") == Path("targets-bob-synthetic.json")


def test_the_hub_copy_reads_and_saves_the_labels_beside_the_notebooks(tmp_path, monkeypatch):
    """The hub's copy keeps every notebook in one folder: the file there is the one read, even
    when a ``../labels/`` beside it holds another; and the labeller never saves elsewhere."""
    from ismb_lab.widgets.labeler import TargetLabeler

    monkeypatch.setenv("JUPYTERHUB_USER", "ann")
    (tmp_path / "notebooks").mkdir()
    (tmp_path / "labels").mkdir()
    other = save_targets(tmp_path / "labels" / "targets-ann-synthetic.json", TargetSet([[1, 1]], [[0, 1]]))
    monkeypatch.chdir(tmp_path / "notebooks")
    labeler = TargetLabeler.from_folder(IMAGES / "synthetic")
    assert labeler.model.path == Path.cwd() / "targets-ann-synthetic.json"    # not ../labels/
    labeler.add_pair(0, 0)
    saved = labeler.save()
    assert targets_path("synthetic") == Path("targets-ann-synthetic.json") and saved.parent == Path.cwd()
    assert len(load_targets(other)) == 1
    assert targets_path("synthetic", also=()) == Path("targets-ann-synthetic.json")
    with pytest.raises(TypeError, match="'also' parameter of targets_path"):
        targets_path("synthetic", also="../labels")


def test_a_merge_refuses_a_file_for_other_images(tmp_path):
    path = save_targets(tmp_path / "t.json", TargetSet([[1, 1]], [[0, 1]], "a" * 64, "b" * 64))
    with pytest.raises(ValueError, match="same images"):
        save_merging(path, TargetSet([[2, 2]], [[1, 2]], "c" * 64, "d" * 64))
    assert len(load_targets(path)) == 1


@pytest.mark.parametrize("hashes", [(), ("a" * 64, "b" * 64)])
def test_a_merge_onto_an_empty_file_keeps_the_hashes_of_either_side(tmp_path, hashes):
    # An empty TargetSet is falsy: the file on disk once stood in for its own missing hash.
    path = save_targets(tmp_path / "t.json", TargetSet(np.zeros((0, 2)), np.zeros((0, 2)), *hashes))
    merged = save_merging(path, TargetSet([[10, 10]], [[5, 10]])).targets
    assert merged.left_xy.tolist() == [[10.0, 10.0]]
    assert (merged.left_sha256, merged.right_sha256) == (hashes or (None, None))
    assert load_targets(path).left_sha256 == merged.left_sha256


def test_a_file_listing_every_pair_twice_is_refused(tmp_path):
    path = tmp_path / "twice.json"
    pairs = [{"left_xy": [10, 10], "right_xy": [5, 10]}, {"left_xy": [20, 20], "right_xy": [15, 20]}]
    path.write_text(json.dumps({"version": 1, "pairs": pairs + pairs}))
    with pytest.raises(ValueError, match=r"holds each pair once. Got 'pairs\[0\] repeated as pairs\[2\]'"):
        load_targets(path)


def class_files(tmp_path):
    key = load_targets(IMAGES / "lab" / "answer_key.json")
    students = {
        "ann": key,                                                  # all right
        "bob": TargetSet(key.left_xy[:5], key.right_xy[:5], key.left_sha256, key.right_sha256),
        "cy": TargetSet(key.left_xy[:3], key.right_xy[[1, 0, 2]], key.left_sha256, key.right_sha256),
    }
    return key, [save_targets(tmp_path / f"targets-{n}-lab.json", t) for n, t in students.items()]


def test_pool_keeps_majorities_and_reports_disagreement_and_agreement_with_the_key(tmp_path):
    key, files = class_files(tmp_path)
    p = pool(files, answer_key=key)
    assert len(p.targets) == len(key)                 # two of three agree everywhere cy is wrong
    # cy swapped the partners of points 0 and 1: left points 0 and 1, and right points 0 and 1,
    # each have two partners, and cy's two pairs are dropped
    assert [d.get("left_xy", d.get("right_xy")) for d in p.disagreements] == [
        key.left_xy[0].tolist(), key.left_xy[1].tolist(), key.right_xy[0].tolist(), key.right_xy[1].tolist()]
    assert [(d["left_xy"], d["right_xy"], d["votes"], d["reasons"]) for d in p.dropped] == sorted(
        (key.left_xy[a].tolist(), key.right_xy[b].tolist(), 1, ["left", "right"]) for a, b in ((0, 1), (1, 0)))
    assert p.students["targets-ann-lab"] == {"pairs": len(key), "in_key": len(key), "key_share": 1.0}
    assert p.students["targets-cy-lab"]["in_key"] == 1
    assert "2 left points with disagreeing partners; 2 right points given several left partners; " \
           "2 pairs dropped" in p.report()


def test_targets_merge_command_pools_a_class(tmp_path, capsys):
    key, files = class_files(tmp_path)
    before = [hashlib.sha256(f.read_bytes()).hexdigest() for f in files]
    out = tmp_path / "all.json"
    assert main(["targets", "merge", *map(str, files), "--answer-key",
                 str(IMAGES / "lab" / "answer_key.json"), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "3 files" in text and "targets-cy-lab: 3 pairs, 1 of them in the answer key" in text
    assert len(load_targets(out)) == len(key)
    assert [hashlib.sha256(f.read_bytes()).hexdigest() for f in files] == before
    assert main(["targets", "merge", str(files[0]), "--out", str(files[0])]) == 2
    assert "ismb-lab: error:" in capsys.readouterr().err
