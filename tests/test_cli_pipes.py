"""A reader that leaves (``ismb-lab ... | head``) is not an error: files written, no traceback, exit 0.

The reader is gone before the command starts: its stdout is a pipe whose reading end is
already closed, so the first write of every run meets the closed pipe (no timing).
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

pytestmark = pytest.mark.slow   # every test runs the CLI in a fresh interpreter
LAB = ROOT / "images" / "lab"


@pytest.fixture
def lab(tmp_path):
    for name in ("left.png", "right.png", "answer_key.json"):
        shutil.copy(LAB / name, tmp_path / name)
    return [str(tmp_path / n) for n in ("left.png", "right.png", "answer_key.json")]


def run_with_closed(stream: str, *args, timeout=300):
    """Run ``ismb-lab *args`` with `stream` ("stdout" or "both") a pipe nobody reads any more."""
    read, write = os.pipe()
    os.close(read)
    try:
        err = write if stream == "both" else subprocess.PIPE
        return subprocess.run([sys.executable, "-m", "ismb_lab.cli", *args], stdout=write, stderr=err,
                              text=True, timeout=timeout, cwd=ROOT)
    finally:
        os.close(write)


def clean(stderr):
    assert not any(word in (stderr or "") for word in ("Traceback", "BrokenPipe", "Exception ignored")), stderr


@pytest.mark.parametrize("stream", ["stdout", "both"])
def test_match_into_a_closed_pipe_still_writes_its_json(lab, tmp_path, stream):
    out = tmp_path / "m.json"
    proc = run_with_closed(stream, "match", *lab[:2], "--json", str(out))
    assert proc.returncode == 0, proc.stderr
    clean(proc.stderr)
    assert json.loads(out.read_text())["method"] == "III"


def test_tune_into_a_closed_pipe_still_writes_its_parameters(lab, tmp_path):
    out = tmp_path / "p.json"
    proc = run_with_closed("stdout", "tune", *lab, "--generations", "2", "--population", "6",
                           "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    clean(proc.stderr)
    assert json.loads(out.read_text())["generations"] <= 2
