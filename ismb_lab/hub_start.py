"""A student's server on the class hub: the course copy, made by the student, and limits.

The hub (``deploy/jupyterhub_config.py``) starts every student's server as that student
with ``python -m ismb_lab.hub_start serve``. That command, running with the student's
own rights, copies the course folder into ``~/ismb_lab`` (mode 700) if it is not there
yet, then becomes ``jupyterhub-singleuser``. Root never writes in a home, so a symbolic
link the student swaps in mid-copy leads only where the student could write anyway.

The teacher prepares the course folder once with ``python -m ismb_lab.hub_start stage
REPOSITORY COURSE``: the notebooks (their student versions: exercise solutions and hidden
tests cleared as ``nbgrader generate_assignment`` clears them), images and manifests, without
the solutions folder, labels or lock files, readable by everyone, and ``COURSE/config``, the folder the hub puts on the
students' ``JUPYTER_CONFIG_PATH``: the course's ``nbgrader_config.py`` (its exchange, from
``deploy/course/``) and a page config that hides nbgrader's teacher tools from students.

Memory: :func:`make_cgroups` (run by the hub, as root) gives each student a memory and
a CPU cgroup (cgroup v1) where the machine has them; :func:`enter` (run in the new
process before it drops root) moves it there and sets ``RLIMIT_DATA``, which every
process the server starts, kernels included, inherits. ``RLIMIT_AS`` is not used: it
also counts address space that numba's LLVM reserves without using, and stops it.
"""

from __future__ import annotations

import argparse
import errno
import json
import os
import pwd
import re
import resource
import shutil
import sys
import tempfile
from pathlib import Path

from ._validation import ParameterError, message

__all__ = ["PARTS", "IGNORE", "TEACHER_TOOLS", "parse_size", "stage", "copy_course", "cgroup_dirs", "make_cgroups",
           "enter", "remove_cgroups", "main"]

#: What a student gets a copy of.
PARTS = ("notebooks", "images", "manifests")
#: Never copied: teachers' solutions, anyone's labels, parameters, lock files and photos.
IGNORE = (".ipynb_checkpoints", "targets-*.json", "my_targets*.json", "params-*.json", ".targets-*.lock",
          "photos-*", "solutions")
#: nbgrader's JupyterLab plugins that only a teacher's course folder can use.
TEACHER_TOOLS = ("@jupyter/nbgrader:formgrader", "@jupyter/nbgrader:create-assignment",
                 "@jupyter/nbgrader:course-list")
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


def stage(repository, course) -> list[str]:
    """The teacher's step: copy the course parts of `repository` into a new folder `course`
    that every account can read (folders 755, files 644); returns the parts copied.

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
        _stage_config(source / "deploy" / "course", course / "config")
        copied.append("config")
    for folder, dirs, files in os.walk(course):
        os.chmod(folder, 0o755)
        for name in files:
            os.chmod(os.path.join(folder, name), 0o644)
    return copied


def _student_versions(folder: Path) -> None:
    """Replace each notebook of `folder` that holds exercise solutions or hidden tests by its
    student version (:func:`ismb_lab.course.student_notebook`)."""
    for path in sorted(folder.glob("*.ipynb")):
        text = path.read_text(encoding="utf-8")
        if "### BEGIN SOLUTION" in text or "### BEGIN HIDDEN TESTS" in text:
            import nbformat

            from .course import student_notebook
            nbformat.write(student_notebook(nbformat.reads(text, as_version=4)), path)


def _stage_config(course_config: Path, target: Path) -> None:
    """The students' Jupyter config folder: the course's nbgrader config, teacher tools hidden."""
    (target / "labconfig").mkdir(parents=True)
    shutil.copy(course_config / "nbgrader_config.py", target / "nbgrader_config.py")
    page = {"disabledExtensions": {name: True for name in TEACHER_TOOLS}}
    (target / "labconfig" / "page_config.json").write_text(json.dumps(page, indent=1) + "\n")


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

    Run it as the student: the copy is built in a private temporary folder in `home` and
    renamed into place, and a folder already there is kept (only made private).
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
    """As root: the student's memory cgroup limited to `limit` bytes (swap included where the
    kernel counts it) and their CPU cgroup with the default share; returns the folders made,
    or ``[]`` where the machine has no writable cgroup v1 memory controller."""
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
    (soft and hard, so the student cannot raise it) to `limit` bytes."""
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


def serve(args, course) -> None:
    """The single-user server's start command: new files private (umask 077), the course
    copied as this account, then ``jupyterhub-singleuser`` with `args` in this process."""
    os.umask(0o077)
    home = pwd.getpwuid(os.getuid()).pw_dir
    try:
        if not course or not Path(course).is_dir():
            raise FileNotFoundError(errno.ENOENT, "no course folder (ISMB_HUB_COURSE)", str(course))
        print(f"ismb_lab: {copy_course(course, home)}", file=sys.stderr, flush=True)
    except OSError as error:     # the student still gets their server, and the reason in its log
        print(f"ismb_lab: the course was not copied: {error}", file=sys.stderr, flush=True)
    os.execv(sys.executable, [sys.executable, "-m", "jupyterhub.singleuser", *args])


def main(argv=None) -> int:
    """``python -m ismb_lab.hub_start stage REPOSITORY COURSE`` or ``... serve [ARGS...]``."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["serve"]:     # everything after it is jupyterhub-singleuser's
        serve(argv[1:], os.environ.get("ISMB_HUB_COURSE", ""))
        return 0     # not reached: serve replaces this process
    parser = argparse.ArgumentParser(prog="python -m ismb_lab.hub_start", description=__doc__.split("\n")[0],
                                     epilog="serve [ARGS...]: copy the course into ~/ismb_lab, then start "
                                            "jupyterhub-singleuser with ARGS (the hub's start command)")
    sub = parser.add_subparsers(dest="command", required=True)
    staging = sub.add_parser("stage", help="copy the course parts of a repository into a new course folder")
    staging.add_argument("repository")
    staging.add_argument("course")
    options = parser.parse_args(argv)
    try:
        copied = stage(options.repository, options.course)
    except (ParameterError, OSError) as error:
        print(f"ismb_lab.hub_start: {error}", file=sys.stderr)
        return 2
    print(f"staged {', '.join(copied)} in {options.course}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
