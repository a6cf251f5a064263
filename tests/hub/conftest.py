"""Real OS accounts for the class tests: made for one test run, removed with all they left.

CI runs as root on a machine that later runs get back, so every account and group has a
name of its own (``ismb`` + 6 random hex digits + a role) and is removed in a ``finally``,
its processes first, even when the test fails.

Students cannot run the interpreter under ``/root`` (mode 700), so their servers and
commands run from :func:`student_python`'s venv: Debian's ``/usr/bin/python3`` in a folder
every user can read.

:func:`deployment` does deploy/README.md's root steps for one test, in a temporary folder
standing for ``/opt/ismb-lab`` and ``/srv/nbgrader``: the repository readable by root and the
teacher only, the course staged from it with the venv's python (its kernels compiled once
per session, :func:`teacher_kernels`), the exchange, and the course's profile installed as
``/etc/profile.d/ismb-lab.sh`` (one test at a time on the machine; an earlier file is put back).
"""

from __future__ import annotations

import fcntl
import grp
import os
import pwd
import secrets
import shutil
import signal
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import pytest

ROOT = Path(__file__).resolve().parents[2]
SYSTEM_PYTHON = Path("/usr/bin/python3")
IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def _unavailable(text: str):
    if IN_CI:
        pytest.fail(text)
    pytest.skip(text)


@dataclass(frozen=True)
class Account:
    name: str
    password: str
    uid: int
    gid: int
    home: Path


class Accounts:
    """Makes accounts in one course group; :meth:`remove_all` undoes everything it made."""

    def __init__(self) -> None:
        self.tag = f"ismb{secrets.token_hex(3)}"
        self.group = f"{self.tag}class"
        self.made: list[Account] = []
        self._group_made = False

    def add(self, role: str, in_group: bool = True) -> Account:
        if not self._group_made:
            subprocess.run(["groupadd", self.group], check=True)
            self._group_made = True
        name = f"{self.tag}{role}"
        password = secrets.token_urlsafe(12)
        cmd = ["useradd", "-m", "-s", "/bin/bash"] + (["-G", self.group] if in_group else []) + [name]
        subprocess.run(cmd, check=True)
        entry = pwd.getpwnam(name)
        account = Account(name, password, entry.pw_uid, entry.pw_gid, Path(entry.pw_dir))
        self.made.append(account)
        subprocess.run(["chpasswd"], input=f"{name}:{password}\n", text=True, check=True)
        return account

    def run_as(self, account: Account, command: str, timeout: float = 120, **kwargs):
        """``su -s /bin/sh NAME -c COMMAND``: the command as that student, in their home."""
        return subprocess.run(["su", "-s", "/bin/sh", account.name, "-c", f"cd && {command}"],
                              capture_output=True, text=True, timeout=timeout, **kwargs)

    def login(self, account: Account, command: str, timeout: float = 300, **kwargs):
        """``su - NAME -c COMMAND``: the command in that user's login shell (``/etc/profile``
        and ``/etc/profile.d``, environment reset), as the docs have users type it."""
        return subprocess.run(["su", "-", account.name, "-c", command], capture_output=True, text=True,
                              timeout=timeout, **kwargs)

    def popen_as(self, account: Account, command: str, **kwargs) -> subprocess.Popen:
        return subprocess.Popen(["su", "-s", "/bin/sh", account.name, "-c", f"cd && {command}"], **kwargs)

    def processes(self, account: Account) -> list[int]:
        out = subprocess.run(["pgrep", "-u", str(account.uid)], capture_output=True, text=True)
        return [int(p) for p in out.stdout.split()]

    def stop_processes(self, account: Account) -> None:
        """TERM, then KILL, every process of `account` (by its PIDs, never by name)."""
        for sig in (signal.SIGTERM, signal.SIGKILL):
            for pid in self.processes(account):
                try:
                    os.kill(pid, sig)
                except ProcessLookupError:
                    pass
            deadline = time.monotonic() + 5
            while self.processes(account) and time.monotonic() < deadline:
                time.sleep(0.1)

    def remove_all(self) -> None:
        for account in self.made:
            self.stop_processes(account)
            for top in (Path("/tmp"), Path("/var/tmp"), Path("/dev/shm")):
                for entry in top.iterdir() if top.is_dir() else ():
                    try:
                        if entry.lstat().st_uid == account.uid:
                            if entry.is_dir() and not entry.is_symlink():
                                shutil.rmtree(entry, ignore_errors=True)
                            else:
                                entry.unlink()
                    except OSError:
                        pass
            subprocess.run(["userdel", "-r", "-f", account.name], capture_output=True)
            shutil.rmtree(account.home, ignore_errors=True)
        if self._group_made:
            subprocess.run(["groupdel", self.group], capture_output=True)


@pytest.fixture
def accounts():
    """Real OS accounts (root only); all removed afterwards, with their processes and files."""
    if os.geteuid() != 0 or shutil.which("useradd") is None:
        _unavailable("the real-account tests need root and useradd")
    made = Accounts()
    try:
        yield made
    finally:
        made.remove_all()
        leftover = [a.name for a in made.made if _exists(a.name)]
        assert not leftover, f"accounts left behind: {leftover}"
        with pytest.raises(KeyError):
            grp.getgrnam(made.group)


def _exists(name: str) -> bool:
    try:
        pwd.getpwnam(name)
        return True
    except KeyError:
        return False


@pytest.fixture(scope="session")
def student_python():
    """A venv of Debian's Python that every user can run, with this project (and the hub's
    single-user server) installed into it; removed at the end of the session."""
    if not SYSTEM_PYTHON.exists():
        _unavailable("/usr/bin/python3 is missing (apt-get install python3-venv)")
    folder = Path(tempfile.mkdtemp(prefix="ismb-hub-venv-"))
    try:
        folder.chmod(0o755)
        started = time.monotonic()
        venv = folder / "venv"
        subprocess.run([str(SYSTEM_PYTHON), "-m", "venv", str(venv)], check=True)
        pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet"]
        subprocess.run(pip + [f"{ROOT}[hub]"], check=True, timeout=900)
        subprocess.run(["chmod", "-R", "a+rX", str(folder)], check=True)
        print(f"the students' venv was built in {time.monotonic() - started:.0f} s")
        yield venv
    finally:
        shutil.rmtree(folder, ignore_errors=True)


#: What deploy/README.md has root install from the repository (the rest is the venv's).
REPOSITORY_PARTS = ("notebooks", "images", "manifests", "deploy")
PROFILE = Path("/etc/profile.d/ismb-lab.sh")
PROFILE_LOCK = Path("/run/lock/ismb-lab-hub-test.lock") if Path("/run/lock").is_dir() else \
    Path(tempfile.gettempdir()) / "ismb-lab-hub-test.lock"


def _read_only_for_all(folder: Path) -> None:
    for top, _, names in os.walk(folder):
        os.chmod(top, 0o755)
        for name in names:
            os.chmod(os.path.join(top, name), 0o644)


@pytest.fixture(scope="session")
def teacher_kernels(student_python):
    """The kernels compiled once for the session by the students' venv (a cache root as
    ``stage`` leaves it: root's, read-only); each test's ``stage`` starts from it, and compiles
    only what changed (nothing)."""
    from ismb_lab.teaching.kernels import compile_into

    folder = Path(tempfile.mkdtemp(prefix="ismb-hub-kernels-"))
    try:
        started = time.monotonic()
        report = compile_into(folder / "numba", python=str(student_python / "bin" / "python"))
        _read_only_for_all(folder)
        print(f"the teacher's kernels: {report}, {time.monotonic() - started:.0f} s")
        assert not report["cold"], report
        yield folder / "numba"
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def venv_env(venv: Path, **extra) -> dict:
    """Root's environment for the venv's commands: no PYTHONPATH (the venv's own copy of the
    package is the one the students run)."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR")}
    return {**env, "PATH": f"{venv / 'bin'}:{env.get('PATH', '/usr/bin:/bin')}", **extra}


@pytest.fixture
def deployment(accounts, student_python, teacher_kernels):
    """deploy/README.md's root steps; yields a namespace: ``teacher``, ``repo``, ``course``,
    ``exchange``, ``course_id``, ``venv``, ``shared`` (the /opt stand-in) and ``env`` (the
    course's variables, for the hub and the teacher alike)."""
    teacher = accounts.add("teach", in_group=False)
    shared = Path(tempfile.mkdtemp(prefix="ismb-hub-opt-"))
    lock, installed, saved = open(PROFILE_LOCK, "a"), False, None
    try:
        shared.chmod(0o755)
        # the repository: root's, readable by the teacher's group only (it holds the solutions)
        repo = shared / "repo"
        subprocess.run(["install", "-d", "-m", "0750", "-o", "root", "-g", str(teacher.gid), str(repo)], check=True)
        for part in REPOSITORY_PARTS:
            shutil.copytree(ROOT / part, repo / part, ignore=shutil.ignore_patterns(
                ".ipynb_checkpoints", "targets-*.json", "params-*.json", ".*.lock", "__pycache__"))
        subprocess.run(["chmod", "-R", "o-rwx", str(repo)], check=True)
        subprocess.run(["chgrp", "-R", str(teacher.gid), str(repo)], check=True)
        # the exchange
        srv = shared / "srv"
        subprocess.run(["install", "-d", "-m", "0755", str(srv)], check=True)
        subprocess.run(["install", "-d", "-m", "1777", str(srv / "exchange")], check=True)
        course_id = f"{accounts.tag}course"
        env = {"ISMB_COURSE_ID": course_id, "ISMB_NBGRADER_EXCHANGE": str(srv / "exchange")}
        # the course, staged with the venv's python (the kernels: from the session's, unchanged)
        course = shared / "course"
        started = time.monotonic()
        staged = subprocess.run([str(student_python / "bin" / "python"), "-m", "ismb_lab.teaching.hub_start", "stage",
                                 str(repo), str(course)], cwd=shared, capture_output=True, text=True,
                                env=venv_env(student_python, ISMB_NUMBA_SHARED=str(teacher_kernels), **env))
        assert staged.returncode == 0, staged.stderr
        print(f"stage: {time.monotonic() - started:.1f} s: {staged.stdout.strip()}")
        fcntl.flock(lock, fcntl.LOCK_EX)       # one test's profile at a time on this machine
        saved, installed = (PROFILE.read_bytes() if PROFILE.exists() else None), True
        subprocess.run(["install", "-m", "0644", str(course / "profile.sh"), str(PROFILE)], check=True)
        yield SimpleNamespace(teacher=teacher, repo=repo, course=course, exchange=srv / "exchange",
                              course_id=course_id, venv=student_python, shared=shared, env=env)
    finally:
        if installed and saved is None:
            PROFILE.unlink(missing_ok=True)
        elif installed:
            PROFILE.write_bytes(saved)
        fcntl.flock(lock, fcntl.LOCK_UN)
        lock.close()
        shutil.rmtree(shared, ignore_errors=True)
