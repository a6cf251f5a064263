"""The class hands its labels in through nbgrader's exchange, with real OS accounts.

A teacher generates and releases "labels" (notebook 04); three students fetch it, save labels
through the library as themselves, and submit (one twice, one with a renamed copy of another
student's file); the teacher collects and pools with ``ismb-lab targets merge``.  Students
cannot read each other's submissions in the exchange.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import stat
import tempfile
from pathlib import Path

import pytest

from .conftest import ROOT, _unavailable

pytestmark = pytest.mark.hub

LABEL = """
import sys
from ismb_lab.classroom import targets_path
from ismb_lab.course import course_images
from ismb_lab.matching import prepare
from ismb_lab.targets import load_targets, snap
from ismb_lab.widgets.labeler import LabelModel

folder = course_images("synthetic")
prepared = prepare(folder / "left.png", folder / "right.png")
key = snap(load_targets(folder / "answer_key.json"), prepared.problem.left_xy, prepared.problem.right_xy).pairs
model = LabelModel(prepared, path=targets_path("synthetic", "."))
if model.path.exists():
    model.load()
for a, b in (p.split(":") for p in sys.argv[1:]):     # a:b pairs key[a]'s left with key[b]'s right
    model.add_pair(int(key[int(a)][0]), int(key[int(b)][1]))
print(model.save())
"""


def test_a_class_hands_in_labels_and_the_teacher_pools_them(accounts, student_python):
    bin_ = student_python / "bin"
    if not (bin_ / "nbgrader").exists():
        _unavailable("nbgrader is missing from the students' venv (the course extra)")
    exchange_top = Path(tempfile.mkdtemp(prefix="ismb-exchange-"))
    try:
        exchange = exchange_top / "exchange"
        exchange.mkdir(mode=0o755)
        exchange_top.chmod(0o755)
        exchange.chmod(0o1777)            # deploy/course/README.md: the teacher's setup
        env = (f"export JUPYTER_CONFIG_PATH={shlex.quote(str(ROOT / 'deploy' / 'course'))} "
               f"ISMB_NBGRADER_EXCHANGE={shlex.quote(str(exchange))} ISMB_COURSE_ID={accounts.tag}course "
               f"PATH={shlex.quote(str(bin_))}:/usr/bin:/bin; ")

        def run(account, command):
            done = accounts.run_as(account, env + command, timeout=300)
            assert done.returncode == 0, f"{account.name}: {command}\n{done.stdout}\n{done.stderr}"
            return done.stdout + done.stderr

        teacher = accounts.add("teacher", in_group=False)
        ann, bob, cy = (accounts.add(n) for n in ("ann", "bob", "cy"))
        run(teacher, f"mkdir course && cd course && ismb-lab course source . --repo {shlex.quote(str(ROOT))}"
                     " && nbgrader generate_assignment labels && nbgrader release_assignment labels")
        for student in (ann, bob, cy):
            run(student, "nbgrader fetch_assignment labels")
            assert (student.home / "labels" / "images" / "synthetic" / "left.png").is_file()
        def label(pairs):
            return f"(cd labels && python -c {shlex.quote(LABEL)} {pairs})"

        run(ann, label("0:0 1:1 2:2") + " && nbgrader submit labels")         # ann submits twice,
        run(ann, label("3:3 4:4 6:6") + " && nbgrader submit labels")         # the last one counts
        run(bob, label("0:1 1:0 2:2 3:3 5:6") + " && nbgrader submit labels")  # swaps 0/1; 5 -> 6's right
        run(cy, label("0:0 1:1 2:2"))
        # cy also hands in a renamed copy of ann's file: it counts for cy, once
        copy = cy.home / "labels" / "targets-copy-synthetic.json"
        shutil.copyfile(ann.home / "labels" / f"targets-{ann.name}-synthetic.json", copy)
        os.chown(copy, cy.uid, cy.gid)
        run(cy, "nbgrader submit labels")

        # the exchange: students can neither list the inbound folder nor read a submission
        inbound = exchange / f"{accounts.tag}course" / "inbound"
        mine = [p for p in inbound.iterdir() if p.name.startswith(ann.name + "+")]
        assert len(mine) == 2
        target = next(mine[0].rglob("targets-*.json"))
        for other in (bob, cy):
            assert accounts.run_as(other, f"ls {shlex.quote(str(inbound))}").returncode != 0
            peek = accounts.run_as(other, f"cat {shlex.quote(str(target))}")
            assert peek.returncode != 0 and "Permission denied" in peek.stderr
        assert stat.S_IMODE(target.stat().st_mode) & 0o007 == 0
        assert stat.S_IMODE(mine[0].stat().st_mode) & 0o007 == 0

        run(teacher, "cd course && nbgrader collect labels")
        submitted = teacher.home / "course" / "submitted"
        assert sorted(p.name for p in submitted.iterdir()) == sorted(a.name for a in (ann, bob, cy))
        out = run(teacher, "cd course && ismb-lab targets merge submitted --out class.json "
                           "--pattern 'targets-*-synthetic.json'")
        pooled = json.loads((teacher.home / "course" / "class.json").read_text())
        figures = {}
        for n in (2, 3):
            run(teacher, f"cd course && ismb-lab targets merge submitted --min-votes {n} --out class{n}.json")
            figures[n] = json.loads((teacher.home / "course" / f"class{n}.json").read_text())
        print(out)
        # one vote each: ann 6 pairs, bob 5, cy 6 (3 of their own and ann's 6, as one ballot)
        assert f"{cy.name}: 6 pairs" in out and "from 3 students (4 files)" in out
        assert f"{ann.name}: 6 pairs" in out and f"{bob.name}: 5 pairs" in out
        # key pairs 0-4 and 6 are kept; bob's 5 -> 6's right (many-to-one with 6) is dropped
        assert len(pooled["pairs"]) == 6
        assert "1 right points given several left partners (dropped)" in out
        assert "2 left points with disagreeing partners" in out
        votes = sorted(len(p["labelled_by"]) for p in pooled["pairs"])
        assert votes == [2, 2, 2, 2, 3, 3]
        assert len(figures[2]["pairs"]) == 6 and len(figures[3]["pairs"]) == 2
    finally:
        shutil.rmtree(exchange_top, ignore_errors=True)
