"""The class hands its labels in through nbgrader's exchange, with real OS accounts.

deploy/README.md's root steps (conftest.deployment), then every command as the docs print it,
in each user's login shell (``su - NAME``: Debian's /etc/profile resets PATH, the course's
/etc/profile.d file puts the venv and the course's nbgrader config back).  A teacher
generates and releases "labels" (notebook 04), without its answer key; three students fetch
it, save labels through the library as themselves and submit; the teacher collects and pools
with ``ismb-lab targets merge``; a student submits again after that collect, and the
teacher's second collect pools the new labels.  Students cannot read each other's submissions.
"""

from __future__ import annotations

import json
import shlex
import shutil
import stat
import tempfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.hub

LABEL = """
import sys
from ismb_lab.labels.classroom import targets_path
from ismb_lab.teaching.course import course_images
from ismb_lab.matching.pipeline import prepare
from ismb_lab.labels.targets import load_targets, snap
from ismb_lab.widgets.labeler import LabelModel

folder = course_images("synthetic")
prepared = prepare(folder / "left.png", folder / "right.png")
key = snap(load_targets(sys.argv[1]), prepared.problem.left_xy, prepared.problem.right_xy).pairs
model = LabelModel(prepared, path=targets_path("synthetic", "."))
if model.path.exists():
    model.load()
for a, b in (p.split(":") for p in sys.argv[2:]):     # a:b pairs key[a]'s left with key[b]'s right
    model.add_pair(int(key[int(a)][0]), int(key[int(b)][1]))
print(model.save())
"""


def test_a_class_hands_in_labels_and_the_teachers_second_collect_takes_the_latest(accounts, deployment):
    teacher, repo = deployment.teacher, deployment.repo
    # the answer key, for this test's students to choose pairs with: it is not in the release
    keys = Path(tempfile.mkdtemp(prefix="ismb-test-key-"))

    def run(account, command):
        done = accounts.login(account, command)
        assert done.returncode == 0, f"{account.name}: {command}\n{done.stdout}\n{done.stderr}"
        return done.stdout + done.stderr

    try:
        keys.chmod(0o755)
        key = keys / "answer_key.json"
        shutil.copyfile(repo / "images" / "synthetic" / "answer_key.json", key)
        key.chmod(0o644)
        ann, bob, cy = (accounts.add(n) for n in ("ann", "bob", "cy"))
        # deploy/course/README.md, "Each term, as the teacher"
        run(teacher, f"mkdir -p -m 700 ~/course && cd ~/course && ismb-lab course source . --repo {shlex.quote(str(repo))}"
                     " && nbgrader generate_assignment labels && nbgrader release_assignment labels")
        # a student's login shell finds the tools and the course (su - resets the environment)
        found = run(ann, "nbgrader --version && ismb-lab --version && jupyter --version && nbgrader list")
        assert deployment.course_id in found and "labels" in found, found
        for student in (ann, bob, cy):
            run(student, "nbgrader fetch_assignment labels")
            synthetic = student.home / "labels" / "images" / "synthetic"
            assert (synthetic / "left.png").is_file()
            assert not (synthetic / "answer_key.json").exists() and not (synthetic / "disparity.png").exists()

        def label(pairs):
            return f"cd labels && python -c {shlex.quote(LABEL)} {shlex.quote(str(key))} {pairs}"

        run(ann, label("0:0 1:1 2:2") + " && cd && nbgrader submit labels")
        run(bob, label("0:1 1:0 2:2 3:3 5:6") + " && cd && nbgrader submit labels")  # swaps 0/1; 5 -> 6's right
        run(cy, label("0:0 1:1 2:2 4:4") + " && cd && nbgrader submit labels")   # not ann's file: one more pair

        # the exchange: students can neither list the inbound folder nor read a submission
        inbound = deployment.exchange / deployment.course_id / "inbound"
        mine = [p for p in inbound.iterdir() if p.name.startswith(ann.name + "+")]
        target = next(mine[0].rglob("targets-*.json"))
        for other in (bob, cy):
            assert accounts.run_as(other, f"ls {shlex.quote(str(inbound))}").returncode != 0
            peek = accounts.run_as(other, f"cat {shlex.quote(str(target))}")
            assert peek.returncode != 0 and "Permission denied" in peek.stderr
        assert stat.S_IMODE(target.stat().st_mode) & 0o007 == 0
        assert stat.S_IMODE(mine[0].stat().st_mode) & 0o007 == 0

        course = teacher.home / "course"
        collect = ("cd ~/course && nbgrader collect labels && ismb-lab targets merge submitted "
                   "--pattern 'targets-*-synthetic.json' --out class.json")
        run(teacher, collect)
        assert sorted(p.name for p in (course / "submitted").iterdir()) == sorted(a.name for a in (ann, bob, cy))
        first = json.loads((course / "class.json").read_text())

        # ann labels three more pairs and submits again, after the teacher's collect
        run(ann, label("3:3 4:4 6:6") + " && cd && nbgrader submit labels")
        said = run(teacher, collect)
        second = json.loads((course / "class.json").read_text())
        print(said)
        assert "use --update" not in said
        def ann_pairs(pool):
            return sum(ann.name in p["labelled_by"] for p in pool["pairs"])

        # first: key pairs 0-4 and bob's 5 -> 6; second: ann's 3 and 4 join, and 6 is disputed
        # (ann's left 6 and bob's left 5 both take right 6: one vote each, neither kept)
        assert ann_pairs(first) == 3 and ann_pairs(second) == 5
        assert len(first["pairs"]) == 6 and len(second["pairs"]) == 5
        assert sorted(len(p["labelled_by"]) for p in first["pairs"]) == [1, 1, 1, 2, 2, 3]
        assert sorted(len(p["labelled_by"]) for p in second["pairs"]) == [2, 2, 2, 2, 3]
        # then tune and match on the pool, as the docs print the two commands
        pair = "source/labels/images/synthetic/left.png source/labels/images/synthetic/right.png"
        said = run(teacher, f"cd ~/course && ismb-lab tune {pair} class.json --out params-class.json"
                            f" && ismb-lab match {pair} --params-file params-class.json")
        assert set(json.loads((course / "params-class.json").read_text())["params"]) >= {"theta_c", "lambda_c"}, said
    finally:
        shutil.rmtree(keys, ignore_errors=True)
