"""Real OS accounts for the class tests: made for one test run, removed with all they left.

CI runs as root on a machine that later runs get back, so every account and group has a
name of its own (``ismb`` + 6 random hex digits + a role) and is removed in a ``finally``,
its processes first, even when the test fails.

Students cannot run the interpreter under ``/root`` (mode 700), so their servers and
commands run from :func:`student_python`'s venv: Debian's ``/usr/bin/python3`` in a folder
every user can read.
"""

from __future__ import annotations

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
