"""ismb_lab.hub_start without a hub: staging, the student's copy, sizes and cgroup folders."""

import json
import os
import stat
from pathlib import Path

import pytest

from ismb_lab import ParameterError, hub_start

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def repository(tmp_path):
    """A small repository: two notebooks, a solution, a student's labels and lock, an image."""
    repo = tmp_path / "repo"
    (repo / "notebooks" / "solutions").mkdir(parents=True)
    (repo / "notebooks" / "04_label_targets.ipynb").write_text("{}")
    (repo / "notebooks" / "solutions" / "04.ipynb").write_text("answers")
    (repo / "notebooks" / "targets-someone-synthetic.json").write_text("[]")
    (repo / "notebooks" / ".targets-someone-synthetic.lock").write_text("")
    (repo / "images" / "synthetic").mkdir(parents=True)
    (repo / "images" / "synthetic" / "left.png").write_bytes(b"png")
    return repo


def files(folder: Path) -> set:
    return {str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()}


def test_stage_keeps_solutions_labels_and_locks_out_and_is_readable_by_all(repository, tmp_path):
    course = tmp_path / "course"
    assert hub_start.main(["stage", str(repository), str(course)]) == 0
    assert files(course) == {"notebooks/04_label_targets.ipynb", "images/synthetic/left.png"}
    assert all(stat.S_IMODE(p.stat().st_mode) in (0o755, 0o644) for p in [course, *course.rglob("*")])
    assert hub_start.main(["stage", str(repository), str(course)]) == 2     # never mixed into an old one


def test_stage_copies_the_student_versions_of_the_exercises(repository, tmp_path):
    pytest.importorskip("nbgrader")
    notebook = ROOT / "notebooks" / "05_parameter_explorer.ipynb"
    assert "### BEGIN SOLUTION" in notebook.read_text(encoding="utf-8")
    (repository / "notebooks" / notebook.name).write_bytes(notebook.read_bytes())
    course = tmp_path / "course"
    assert hub_start.main(["stage", str(repository), str(course)]) == 0
    staged = (course / "notebooks" / notebook.name).read_text(encoding="utf-8")
    assert "BEGIN SOLUTION" not in staged and "HIDDEN TESTS" not in staged and "# YOUR CODE HERE" in staged
    assert (course / "notebooks" / "04_label_targets.ipynb").read_text() == "{}"


def test_the_students_copy_is_private_and_made_once(repository, tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    said = hub_start.copy_course(repository, home)
    copy = home / "ismb_lab"
    assert said.startswith("copied notebooks, images") and stat.S_IMODE(copy.stat().st_mode) == 0o700
    assert files(copy) == {"notebooks/04_label_targets.ipynb", "images/synthetic/left.png"}
    assert [p.name for p in home.iterdir()] == ["ismb_lab"]       # no temporary folder left
    (copy / "notebooks" / "mine.ipynb").write_text("kept")
    copy.chmod(0o755)
    assert hub_start.copy_course(repository, home).startswith("kept")
    assert (copy / "notebooks" / "mine.ipynb").read_text() == "kept"
    assert stat.S_IMODE(copy.stat().st_mode) == 0o700


def test_a_link_in_place_of_the_copy_is_left_alone(repository, tmp_path):
    home, elsewhere = tmp_path / "home", tmp_path / "elsewhere"
    home.mkdir()
    elsewhere.mkdir(mode=0o755)
    os.symlink(elsewhere, home / "ismb_lab")
    assert hub_start.copy_course(repository, home).startswith("left")
    assert list(elsewhere.iterdir()) == [] and stat.S_IMODE(elsewhere.stat().st_mode) == 0o755


@pytest.mark.parametrize("text", ["", "2X", "-1G", "1" * 30, "1M", "G"])
def test_sizes_are_checked(text):
    with pytest.raises(ParameterError, match="'size' parameter of parse_size"):
        hub_start.parse_size(text)


def test_cgroup_folders_are_made_limited_and_removed(tmp_path):
    """cgroup v1 files as plain files: the limit is written, read back, and the folders go."""
    root = tmp_path / "cgroup"
    memory, cpu = hub_start.cgroup_dirs("student", root)
    for folder, control in ((memory, "memory.limit_in_bytes"), (cpu, "cpu.shares")):
        folder.mkdir(parents=True)
        (folder / control).write_text("9223372036854771712\n")
    made = hub_start.make_cgroups("student", 2**30, root=root)
    assert made == [memory, cpu]
    assert int((memory / "memory.limit_in_bytes").read_text()) == 2**30
    assert int((cpu / "cpu.shares").read_text()) == 1024
    for folder in made:                # a real cgroup folder holds only kernel files
        for entry in folder.iterdir():
            entry.unlink()
    assert hub_start.remove_cgroups(made) == [] and not memory.exists()


def test_no_memory_controller_means_no_cgroups(tmp_path):
    assert hub_start.make_cgroups("student", 2**30, root=tmp_path / "none") == []
    (tmp_path / "plain" / "memory").mkdir(parents=True)      # a folder, not a cgroup file system
    assert hub_start.make_cgroups("student", 2**30, root=tmp_path / "plain") == []
    assert not (tmp_path / "plain" / "memory" / "ismb-hub" / "student").exists()


def test_stage_puts_the_course_config_beside_the_copy_never_into_it(repository, tmp_path):
    (repository / "deploy" / "course").mkdir(parents=True)
    (repository / "deploy" / "course" / "nbgrader_config.py").write_text("c = get_config()\n")
    course = tmp_path / "course"
    assert hub_start.main(["stage", str(repository), str(course)]) == 0
    config = course / "config"
    assert (config / "nbgrader_config.py").read_text() == "c = get_config()\n"
    page = json.loads((config / "labconfig" / "page_config.json").read_text())
    assert set(page["disabledExtensions"]) == set(hub_start.TEACHER_TOOLS)
    assert stat.S_IMODE((config / "nbgrader_config.py").stat().st_mode) == 0o644
    home = tmp_path / "home"
    home.mkdir()
    hub_start.copy_course(course, home)
    assert not (home / hub_start.COPY / "config").exists()
