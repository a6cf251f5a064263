"""ismb_lab.teaching.hub_start without a hub: staging, the student's copy, sizes and cgroup folders."""

import json
import os
import shlex
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from ismb_lab import ParameterError
from ismb_lab.teaching import hub_start

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
    assert hub_start.main(["stage", str(repository), str(course), "--skip-kernels"]) == 0
    assert files(course) == {"notebooks/04_label_targets.ipynb", "images/synthetic/left.png", "profile.sh"}
    assert all(stat.S_IMODE(p.stat().st_mode) in (0o755, 0o644) for p in [course, *course.rglob("*")])
    assert hub_start.main(["stage", str(repository), str(course), "--skip-kernels"]) == 2     # never mixed into an old one


def test_stage_copies_the_student_versions_of_the_exercises(repository, tmp_path):
    pytest.importorskip("nbgrader")
    notebook = ROOT / "notebooks" / "05_parameter_explorer.ipynb"
    assert "### BEGIN SOLUTION" in notebook.read_text(encoding="utf-8")
    (repository / "notebooks" / notebook.name).write_bytes(notebook.read_bytes())
    course = tmp_path / "course"
    assert hub_start.main(["stage", str(repository), str(course), "--skip-kernels"]) == 0
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


def load_nbgrader_config(folder: Path, environ: dict) -> dict:
    """What nbgrader's config loader makes of `folder`'s nbgrader_config.py, with `environ`."""
    from traitlets.config.loader import PyFileConfigLoader

    saved = dict(os.environ)
    os.environ.clear()
    os.environ.update(environ)
    try:
        config = PyFileConfigLoader("nbgrader_config.py", path=str(folder)).load_config()
    finally:
        os.environ.clear()
        os.environ.update(saved)
    return {section: dict(values) for section, values in config.items()}


def test_stage_puts_the_course_config_beside_the_copy_never_into_it(repository, tmp_path, monkeypatch):
    (repository / "deploy" / "course").mkdir(parents=True)
    (repository / "deploy" / "course" / "nbgrader_config.py").write_text("c = get_config()\n")
    course = tmp_path / "course"
    monkeypatch.setenv("ISMB_COURSE_ID", "term1")
    monkeypatch.setenv("ISMB_NBGRADER_EXCHANGE", "/srv/x/exchange")
    assert hub_start.main(["stage", str(repository), str(course), "--skip-kernels"]) == 0
    config, teacher = course / "config", course / "teacher-config"
    assert (config / "nbgrader_config.py").read_text().startswith("c = get_config()\n")
    # the values stage ran with are the course's, for shells that do not have them; a variable wins
    staged = load_nbgrader_config(config, {"HOME": "/home/t"})
    assert staged["CourseDirectory"] == {"course_id": "term1"} and staged["Exchange"] == {"root": "/srv/x/exchange"}
    assert load_nbgrader_config(config, {"ISMB_COURSE_ID": "other"})["CourseDirectory"]["course_id"] == "other"
    # the teachers' folder: the same, with their course folder as the root
    graded = load_nbgrader_config(teacher, {"HOME": "/home/t"})
    assert graded["CourseDirectory"] == {"course_id": "term1", "root": "/home/t/course"}
    assert load_nbgrader_config(teacher, {"HOME": "/home/t", "ISMB_COURSE_ROOT": "/srv/grading"}
                                )["CourseDirectory"]["root"] == "/srv/grading"
    page = json.loads((config / "labconfig" / "page_config.json").read_text())
    assert set(page["disabledExtensions"]) == set(hub_start.TEACHER_TOOLS)
    assert not (teacher / "labconfig").exists()
    server = json.loads((config / "jupyter_server_config.json").read_text())
    assert server["ServerApp"]["jpserver_extensions"] == {name: False for name in hub_start.STUDENT_SERVER_OFF}
    assert "ServerApp" not in json.loads((teacher / "jupyter_server_config.json").read_text())
    settings = Path(server["LabApp"]["app_settings_dir"])
    assert settings == course.resolve() / "lab-settings" and server["LabApp"]["news_url"] is None
    assert json.loads((settings / "overrides.json").read_text()) == hub_start.LAB_OVERRIDES
    assert stat.S_IMODE((config / "nbgrader_config.py").stat().st_mode) == 0o644
    home = tmp_path / "home"
    home.mkdir()
    hub_start.copy_course(course, home)
    assert not (home / hub_start.COPY / "config").exists()


def login_shell(profile: Path, uid_zero: bool, environ: dict) -> dict:
    """PATH and the course's variables after Debian's /etc/profile (PATH reset) and `profile`."""
    reset = "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin" if uid_zero else \
        "/usr/local/bin:/usr/bin:/bin:/usr/local/games:/usr/games"
    script = (f"id() {{ echo {0 if uid_zero else 1000}; }}; PATH={reset}; . {shlex.quote(str(profile))}; "
              "echo \"$PATH\"; echo \"$JUPYTER_CONFIG_PATH\"; echo \"$ISMB_NUMBA_SHARED\"")
    out = subprocess.run(["sh", "-c", script], env=environ, capture_output=True, text=True, check=True).stdout
    return dict(zip(("PATH", "JUPYTER_CONFIG_PATH", "ISMB_NUMBA_SHARED"), out.splitlines()))


def test_the_profile_gives_login_shells_the_venv_the_course_config_and_the_kernels(repository, tmp_path):
    course = tmp_path / "a course"          # a space in the path, quoted
    assert hub_start.main(["stage", str(repository), str(course), "--skip-kernels"]) == 0
    profile, bin_ = course / "profile.sh", str(Path(sys.prefix).resolve() / "bin")
    student = login_shell(profile, False, {})
    assert student["PATH"].split(":")[0] == bin_
    assert student["JUPYTER_CONFIG_PATH"] == str(course.resolve() / "config")
    assert student["ISMB_NUMBA_SHARED"] == str(course.resolve() / "numba")
    root = login_shell(profile, True, {})
    assert root["PATH"].split(":")[-1] == bin_ and root["PATH"].split(":")[0] == "/usr/local/sbin"
    teacher = login_shell(profile, False, {"JUPYTER_CONFIG_PATH": "/srv/teacher-config"})   # a server's own
    assert teacher["JUPYTER_CONFIG_PATH"] == "/srv/teacher-config"


def test_the_runtime_folder_is_private_and_short(tmp_path):
    folder = Path(hub_start.runtime_folder(str(tmp_path)))
    assert folder == tmp_path / f"ismb-lab-rt-{os.getuid()}" and stat.S_IMODE(folder.stat().st_mode) == 0o700
    assert hub_start.runtime_folder(str(tmp_path)) == str(folder)          # the same one next time
    folder.chmod(0o755)                        # opened to others (or made by someone else): not used
    other = Path(hub_start.runtime_folder(str(tmp_path)))
    assert other != folder and other.parent == tmp_path and stat.S_IMODE(other.stat().st_mode) == 0o700
    link = tmp_path / "elsewhere"
    folder.chmod(0o700)
    folder.rename(link)
    folder.symlink_to(link)                    # a link in its place: not followed
    assert Path(hub_start.runtime_folder(str(tmp_path))) not in (folder, link)
