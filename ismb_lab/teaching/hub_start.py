"""A student's server on the class hub: the course copy, made by the student, and limits.

``stage`` (the teacher, once) makes the course folder, readable by everyone; ``serve`` (the hub's
start command) copies it into the student's ``~/ismb_lab`` as the student, so root never writes in a
home.  Root gives each student a memory and a CPU cgroup (v1) where the machine has them, and
``RLIMIT_DATA``: not ``RLIMIT_AS``, which also counts what numba's LLVM reserves unused.
deploy/README.md has the steps.
"""

from __future__ import annotations

import argparse
import errno
import json
import os
import pwd
import re
import resource
import shlex
import shutil
import sys
import tempfile
from pathlib import Path

from .._core.files import private_folder
from .._core.validation import ParameterError, message

__all__ = ["PARTS", "IGNORE", "TEACHER_TOOLS", "STUDENT_SERVER_OFF", "parse_size", "stage", "profile",
           "copy_course", "runtime_folder", "cgroup_dirs", "make_cgroups", "enter", "remove_cgroups", "main"]

#: What a student gets a copy of.
PARTS = ("notebooks", "images", "manifests")
#: Never copied: teachers' solutions, anyone's labels, parameters, lock files and photos.
IGNORE = (".ipynb_checkpoints", "targets-*.json", "my_targets*.json", "params-*.json", ".targets-*.lock",
          "photos-*", "solutions")
#: nbgrader's JupyterLab plugins that only a teacher's course folder can use.
TEACHER_TOOLS = ("@jupyter/nbgrader:formgrader", "@jupyter/nbgrader:create-assignment",
                 "@jupyter/nbgrader:course-list")
#: nbgrader's server extensions that students' servers do not load (the teachers' do).
STUDENT_SERVER_OFF = ("nbgrader.server_extensions.formgrader", "nbgrader.server_extensions.course_list")
#: JupyterLab's settings for everyone: no question about news, no update check.
LAB_OVERRIDES = {"@jupyterlab/apputils-extension:notification": {"fetchNews": "false", "checkForUpdates": False}}
#: The folder in each home, and the cgroup folder that holds one cgroup per student.
COPY = "ismb_lab"
CGROUP_GROUP = "ismb-hub"
CGROUP_ROOT = Path("/sys/fs/cgroup")
_UNITS = {"": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}


def parse_size(text) -> int:
    """Bytes from a size such as ``"2G"``, ``"512M"`` or ``"1.5G"`` (powers of 1024).

    >>> parse_size("512M"), parse_size("1.5G"), parse_size(2**30)
    (536870912, 1610612736, 1073741824)
    """
    found = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*([KMGT]?)B?\s*", str(text), re.IGNORECASE)
    if found is None or len(found.group(1)) > 15:
        raise ParameterError(message("size", "parse_size", "a number of bytes with an optional K, M, G "
                                     "or T, such as 2G", text))
    size = int(float(found.group(1)) * _UNITS[found.group(2).upper()])
    if size < 2**26:
        raise ParameterError(message("size", "parse_size", "at least 64M (a kernel needs more)", text))
    return size


def _copy_parts(source: Path, target: Path) -> list[str]:
    copied = []
    for part in PARTS:
        if (source / part).is_dir():
            shutil.copytree(source / part, target / part, ignore=shutil.ignore_patterns(*IGNORE))
            copied.append(part)
    return copied


def stage(repository, course, kernels: bool = True) -> list[str]:
    """The teacher's step: copy the course parts of `repository` into a new folder `course` that
    every account can read (folders 755, files 644), with the Jupyter config folders, the login
    shells' profile and (with `kernels`) the compiled kernels; returns what was made.

    `course` must not exist yet, so that nothing staged earlier is mixed in.
    """
    source, course = Path(repository), Path(course)
    if os.path.lexists(course):
        raise ParameterError(message("course", "stage", "a folder that does not exist yet", str(course)))
    if not (source / "notebooks").is_dir():
        raise ParameterError(message("repository", "stage", "a folder with notebooks/ in it", str(source)))
    course.mkdir(parents=True)
    copied = _copy_parts(source, course)
    try:
        _student_versions(course / "notebooks")
    except ImportError:
        shutil.rmtree(course)
        raise ParameterError(message("repository", "stage", "notebooks whose solutions nbgrader can "
                                     "clear (install the [course] extra)", str(source))) from None
    if (source / "deploy" / "course" / "nbgrader_config.py").is_file():
        _stage_config(source / "deploy" / "course", course)
        copied += ["config", "teacher-config", "lab-settings"]
    (course / "profile.sh").write_text(profile(course))
    copied.append("profile.sh")
    if kernels:
        from .kernels import compile_into

        try:
            report = compile_into(course / "numba")
        except OSError as error:
            shutil.rmtree(course)
            raise OSError(f"{course}: {error}") from None
        copied.append(f"numba ({report['kernels']} kernels compiled in {report['seconds']} s for "
                      f"{report['source']}" + (f"; not compiled: {', '.join(report['cold'])}" if report["cold"]
                                               else "") + ")")
    for folder, dirs, files in os.walk(course):
        os.chmod(folder, 0o755)
        for name in files:
            os.chmod(os.path.join(folder, name), 0o644)
    return copied


def _student_versions(folder: Path) -> None:
    """Replace each notebook of `folder` with exercise solutions or hidden tests by its student version."""
    for path in sorted(folder.glob("*.ipynb")):
        text = path.read_text(encoding="utf-8")
        if "### BEGIN SOLUTION" in text or "### BEGIN HIDDEN TESTS" in text:
            import nbformat

            from .course import student_notebook
            nbformat.write(student_notebook(nbformat.reads(text, as_version=4)), path)


_STAGED = """
# Written by `python -m ismb_lab.teaching.hub_start stage`: the course id and exchange it was run with
# are this course's, for every server and login shell that reads this folder.
import os  # noqa: E402

c.CourseDirectory.course_id = os.environ.get("ISMB_COURSE_ID", {course_id!r})
c.Exchange.root = os.environ.get("ISMB_NBGRADER_EXCHANGE", {exchange!r})
"""
_TEACHER = """
# The teacher's course folder (source/, release/, submitted/, gradebook.db): the Formgrader of
# the teacher's server and nbgrader in its terminals work on it, from whatever folder.
c.CourseDirectory.root = os.path.expanduser(os.environ.get("ISMB_COURSE_ROOT", "~/course"))
"""


def _json(path: Path, value) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(value, indent=1) + "\n")


def _stage_config(course_config: Path, course: Path) -> None:
    """The students' and the teachers' Jupyter config folders, and JupyterLab's settings."""
    text = (course_config / "nbgrader_config.py").read_text(encoding="utf-8").rstrip("\n") + "\n"
    text += _STAGED.format(course_id=os.environ.get("ISMB_COURSE_ID", "ismb_lab"),
                           exchange=os.environ.get("ISMB_NBGRADER_EXCHANGE", "/srv/nbgrader/exchange"))
    settings = course.resolve() / "lab-settings"
    _json(settings / "overrides.json", LAB_OVERRIDES)
    lab = {"news_url": None, "app_settings_dir": str(settings)}
    students, teachers = course / "config", course / "teacher-config"
    students.mkdir()
    (students / "nbgrader_config.py").write_text(text)
    _json(students / "labconfig" / "page_config.json", {"disabledExtensions": {name: True for name in TEACHER_TOOLS}})
    _json(students / "jupyter_server_config.json",
          {"ServerApp": {"jpserver_extensions": {name: False for name in STUDENT_SERVER_OFF}}, "LabApp": lab})
    teachers.mkdir()
    (teachers / "nbgrader_config.py").write_text(text + _TEACHER)
    _json(teachers / "jupyter_server_config.json", {"LabApp": lab})


def profile(course) -> str:
    """``/etc/profile.d/ismb-lab.sh`` for a course staged in `course` by this interpreter's venv.

    Login shells (Debian's ``/etc/profile`` resets PATH) find the venv's commands (after the system's
    for root), the course's nbgrader config and the compiled kernels; values a server set are kept.
    """
    course, bin_ = Path(course).resolve(), Path(sys.prefix).resolve() / "bin"
    quoted = shlex.quote(str(bin_))
    return f"""# ismb_lab's class hub: written by `python -m ismb_lab.teaching.hub_start stage`, installed as
# /etc/profile.d/ismb-lab.sh (deploy/README.md). Login shells (JupyterLab's terminals, su -,
# ssh) find the class venv's commands, the course's nbgrader config and compiled kernels.
case ":${{PATH}}:" in
    *:{quoted}:*) ;;
    *) if [ "$(id -u)" -eq 0 ]; then PATH="${{PATH}}:"{quoted}; else PATH={quoted}":${{PATH}}"; fi ;;
esac
export PATH
JUPYTER_CONFIG_PATH=${{JUPYTER_CONFIG_PATH:-{shlex.quote(str(course / 'config'))}}}
ISMB_NUMBA_SHARED=${{ISMB_NUMBA_SHARED:-{shlex.quote(str(course / 'numba'))}}}
export JUPYTER_CONFIG_PATH ISMB_NUMBA_SHARED
"""


def _private_folder(path: Path) -> bool:
    """Make `path` mode 700 if it is a real folder of ours; never follows a symbolic link."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
    except OSError:
        return False
    try:
        if os.fstat(fd).st_uid != os.getuid():
            return False
        os.fchmod(fd, 0o700)
        return True
    finally:
        os.close(fd)


def copy_course(course, home, name: str = COPY) -> str:
    """Copy the course folder into ``home/name`` (mode 700) unless something is there already;
    returns one line saying what happened.

    Run it as the student: the copy is built in a private temporary folder in `home` and renamed into
    place, and a folder already there is kept (only made private).
    """
    course, target = Path(course), Path(home) / name
    if os.path.lexists(target):
        if _private_folder(target):
            return f"kept {target} (mode 700)"
        return f"left {target} alone: it is not a folder of this account"
    building = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=home))     # mode 700
    try:
        copied = _copy_parts(course, building)
        os.rename(building, target)
    except OSError:
        shutil.rmtree(building, ignore_errors=True)
        if os.path.lexists(target):
            return f"left {target} alone: it appeared while the copy was made"
        raise
    return f"copied {', '.join(copied) or 'nothing'} from {course} into {target} (mode 700)"


def cgroup_dirs(user: str, root=CGROUP_ROOT) -> list[Path]:
    """The memory and CPU cgroup folders of `user` (cgroup v1 layout)."""
    return [Path(root) / controller / CGROUP_GROUP / user for controller in ("memory", "cpu")]


def _write(path: Path, value) -> None:
    with open(path, "w") as out:
        out.write(f"{value}\n")


def _make_cgroup(folder: Path, control: str) -> None:
    """Make `folder` under an existing controller; the kernel fills a real cgroup with its
    control files, so a plain folder (no cgroup file system there) is refused."""
    folder.parent.mkdir(exist_ok=True)      # FileNotFoundError: no such controller
    folder.mkdir(exist_ok=True)
    if not (folder / control).exists():
        raise OSError(errno.ENOTSUP, "not a cgroup v1 folder", str(folder))


def make_cgroups(user: str, limit: int, root=CGROUP_ROOT) -> list[Path]:
    """As root: the student's memory cgroup limited to `limit` bytes (swap included where counted)
    and their CPU cgroup with the default share; returns the folders made, or ``[]`` where the machine
    has no writable cgroup v1 memory controller."""
    memory, cpu = cgroup_dirs(user, root)
    try:
        _make_cgroup(memory, "memory.limit_in_bytes")
        _write(memory / "memory.limit_in_bytes", limit)
        if (memory / "memory.memsw.limit_in_bytes").exists():
            _write(memory / "memory.memsw.limit_in_bytes", limit)
        if int((memory / "memory.limit_in_bytes").read_text()) > limit:
            raise OSError(errno.EINVAL, "the memory limit did not hold", str(memory))
    except OSError:
        remove_cgroups([memory])
        return []
    made = [memory]
    try:
        _make_cgroup(cpu, "cpu.shares")
        _write(cpu / "cpu.shares", 1024)      # every student the same share of the cores
        made.append(cpu)
    except OSError:
        remove_cgroups([cpu])
    return made


def enter(cgroups, limit: int) -> None:
    """In the new server process, before it drops root: join `cgroups` and set ``RLIMIT_DATA``
    (soft and hard) to `limit` bytes."""
    for folder in cgroups:
        _write(Path(folder) / "cgroup.procs", os.getpid())
    resource.setrlimit(resource.RLIMIT_DATA, (limit, limit))


def remove_cgroups(cgroups) -> list[Path]:
    """Remove the cgroup folders that no process uses any more; returns those still in use."""
    busy = []
    for folder in cgroups:
        try:
            Path(folder).rmdir()
        except FileNotFoundError:
            pass
        except OSError:
            busy.append(Path(folder))
    return busy


def runtime_folder(temp: str | None = None) -> str:
    """A private folder with a short path for Jupyter's runtime files: ``<temp>/ismb-lab-rt-<uid>``.

    The kernels' Unix sockets live in it, and a socket's path holds at most 107 bytes.
    """
    return private_folder("ismb-lab-rt", temp)


def serve(args, course) -> None:
    """The single-user server's start command: umask 077, the course copied as this account,
    Jupyter's runtime files in :func:`runtime_folder`, then ``jupyterhub-singleuser`` with `args`."""
    os.umask(0o077)
    home = pwd.getpwuid(os.getuid()).pw_dir
    try:
        os.environ["JUPYTER_RUNTIME_DIR"] = runtime_folder()
    except OSError as error:      # Jupyter's own folder in the home, then
        print(f"ismb_lab: no runtime folder in {tempfile.gettempdir()}: {error}", file=sys.stderr, flush=True)
    try:
        if not course or not Path(course).is_dir():
            raise FileNotFoundError(errno.ENOENT, "no course folder (ISMB_HUB_COURSE)", str(course))
        print(f"ismb_lab: {copy_course(course, home)}", file=sys.stderr, flush=True)
    except OSError as error:     # the student still gets their server, and the reason in its log
        print(f"ismb_lab: the course was not copied: {error}", file=sys.stderr, flush=True)
    os.execv(sys.executable, [sys.executable, "-m", "jupyterhub.singleuser", *args])


def main(argv=None) -> int:
    """``python -m ismb_lab.teaching.hub_start stage REPOSITORY COURSE`` or ``... serve [ARGS...]``."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["serve"]:     # everything after it is jupyterhub-singleuser's
        serve(argv[1:], os.environ.get("ISMB_HUB_COURSE", ""))
        return 0     # not reached: serve replaces this process
    parser = argparse.ArgumentParser(prog="python -m ismb_lab.teaching.hub_start", description=__doc__.split("\n")[0],
                                     epilog="serve [ARGS...]: copy the course into ~/ismb_lab, then start "
                                            "jupyterhub-singleuser with ARGS (the hub's start command)")
    sub = parser.add_subparsers(dest="command", required=True)
    staging = sub.add_parser("stage", help="copy the course parts of a repository into a new course folder, "
                                           "with its config and the compiled kernels")
    staging.add_argument("repository")
    staging.add_argument("course")
    staging.add_argument("--skip-kernels", action="store_true",
                         help="do not compile the kernels (every student then compiles their own)")
    options = parser.parse_args(argv)
    try:
        copied = stage(options.repository, options.course, kernels=not options.skip_kernels)
    except (ParameterError, OSError) as error:
        print(f"ismb_lab.teaching.hub_start: {error}", file=sys.stderr)
        return 2
    print(f"staged {', '.join(copied)} in {options.course}")
    print(f"then, as root: install -m 0644 {Path(options.course).resolve() / 'profile.sh'} /etc/profile.d/ismb-lab.sh")
    return 0


if __name__ == "__main__":
    sys.exit(main())
