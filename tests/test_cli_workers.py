"""``evaluate --jobs N``: its worker processes end with the command, however it ends.

A worker is recognised in /proc: a child of the command whose command line runs
multiprocessing's ``spawn_main`` (the pool's resource tracker is a child too, and
ends by itself when its pipe closes).  A worker is ready once it ignores SIGINT, the
last step of its start (:func:`ismb_lab.tuning.cases._start_worker`), so the signal is
sent when the workers are known to have started: no timing.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

# process pools and signals to whole process trees: slow (README's fast tier leaves them out)
pytestmark = [pytest.mark.skipif(not sys.platform.startswith("linux"), reason="needs Linux /proc"), pytest.mark.slow]


def _stat(pid: int):
    """(state, parent pid) of a process, or None once it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text.rsplit(")", 1)[1].split()
    return fields[0], int(fields[1])


def _sigint_ignored(pid: int) -> bool:
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = next(int(line.split()[1], 16) for line in status.splitlines() if line.startswith("SigIgn"))
    return bool(mask >> (signal.SIGINT - 1) & 1)


def workers_of(parent: int) -> list[int]:
    """The pool workers among `parent`'s children."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (_stat(int(entry.name)) or ("", 0))[1] == parent:
            try:
                cmdline = (entry / "cmdline").read_bytes()
            except OSError:
                continue
            if b"spawn_main" in cmdline:
                found.append(int(entry.name))
    return found


def ready_workers(parent: int, n: int, timeout: float = 180.0) -> list[int]:
    """Wait until `parent` has `n` workers that finished their start; return their pids."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready = [pid for pid in workers_of(parent) if _sigint_ignored(pid)]
        if len(ready) >= n:
            return ready
        time.sleep(0.05)
    raise AssertionError(f"{n} workers of {parent} did not start within {timeout} s")


def alive(pids, within: float) -> list[int]:
    """The pids still running (zombies count as ended) after waiting up to `within` seconds."""
    deadline = time.monotonic() + within
    while True:
        running = [pid for pid in pids if (_stat(pid) or ("Z",))[0] not in ("Z", "X")]
        if not running or time.monotonic() > deadline:
            return running
        time.sleep(0.05)


def kill_all(pids) -> None:
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def test_leaving_the_pool_by_an_interrupt_ends_its_workers():
    """In a notebook the process lives on after Ctrl-C: the workers must not work on."""
    from ismb_lab.tuning.cases import _workers

    workers = []
    try:
        with pytest.raises(KeyboardInterrupt):
            with _workers(2) as pool:
                for _ in range(2):
                    pool.submit(time.sleep, 600)
                workers = ready_workers(os.getpid(), 2)
                raise KeyboardInterrupt
        assert alive(workers, within=5.0) == []
    finally:
        kill_all(workers)


@pytest.fixture
def evaluate(hard_manifest, tmp_path):
    """``ismb-lab evaluate --jobs 2`` with fits that run for hours; everything it left is killed.

    Its stderr goes to a file: a worker that outlived it would hold a pipe open."""
    out, log = tmp_path / "report.json", tmp_path / "stderr.txt"
    with open(log, "w") as stderr:
        proc = subprocess.Popen([sys.executable, "-m", "ismb_lab.cli", "evaluate", str(hard_manifest), "--jobs",
                                 "2", "--seeds", "1", "--generations", "100000", "--json", str(out)],
                                stdout=subprocess.DEVNULL, stderr=stderr, cwd=ROOT,
                                preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL))
    workers = []
    try:
        workers.extend(ready_workers(proc.pid, 2))
        yield proc, workers, out, log
    finally:
        kill_all(workers)
        if proc.poll() is None:
            proc.kill()
        proc.wait()


def test_sigterm_to_evaluate_ends_its_workers_and_says_what_was_written(evaluate):
    proc, workers, out, log = evaluate
    proc.send_signal(signal.SIGTERM)
    proc.wait(timeout=60)
    stderr = log.read_text()
    assert proc.returncode == 128 + signal.SIGTERM, stderr
    assert alive(workers, within=5.0) == []
    assert "Traceback" not in stderr, stderr
    lines = [line for line in stderr.splitlines() if line.startswith("ismb-lab:")]
    assert lines == [f"ismb-lab: interrupted (SIGTERM); nothing was written to {out}: "
                     "no GA fit had finished"], stderr
    assert not out.exists()


def test_sigkill_to_evaluate_ends_its_workers(evaluate):
    proc, workers, _, _ = evaluate
    proc.kill()
    proc.wait(timeout=60)
    assert alive(workers, within=5.0) == []
