"""The teacher's compiled kernels reach a student's own cache (ismb_lab._core.numba_share), without a hub.

Each check runs a new interpreter: numba reads its cache settings when it is imported. The
kernel used is ``evaluation._tally``, small enough to compile in a second or two.
"""

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from ismb_lab._core import numba_share as _numba_share

#: Each check starts interpreters that compile a kernel: more than a CPU-second apiece.
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
#: Call the kernel once; report whether numba's cache was cold, and where it loaded from.
CALL = """
import json, os, numpy as np
from ismb_lab._core import numba_cache as _numba
from ismb_lab.tuning.evaluation import _tally
cold = _numba.cold(_tally)
_tally(np.zeros(3, dtype=np.uint8), np.zeros(1, dtype=np.int64))
print(json.dumps({"cold": cold, "hits": sum(_tally.stats.cache_hits.values()),
                  "misses": sum(_tally.stats.cache_misses.values())}))
"""


def call(env: dict) -> dict:
    done = subprocess.run([sys.executable, "-c", CALL], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(ROOT), **env})
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def shared(tmp_path_factory):
    """The teacher's cache: `_tally` compiled into a folder, then made read-only (as stage leaves it)."""
    root = tmp_path_factory.mktemp("teacher") / "numba"
    first = call({"NUMBA_CACHE_DIR": str(root), _numba_share.VARIABLE: ""})
    assert first["misses"] == 1
    for folder, _, names in os.walk(root):
        os.chmod(folder, 0o755)
        for name in names:
            os.chmod(os.path.join(folder, name), 0o644)
    return root


def files(folder: Path) -> dict:
    return {p.name: p for p in folder.rglob("*") if p.is_file()}


def test_a_students_first_call_loads_the_teachers_kernel_from_their_own_copy(shared, tmp_path):
    own = tmp_path / "own"
    seen = call({"NUMBA_CACHE_DIR": str(own), _numba_share.VARIABLE: str(shared)})
    assert seen == {"cold": False, "hits": 1, "misses": 0}      # nothing compiled, nothing announced
    copied = files(own)
    assert {n for n in copied if n.startswith("evaluation._tally-")} == \
           {n for n in files(shared) if n.startswith("evaluation._tally-")}
    assert all(stat.S_IMODE(p.stat().st_mode) == 0o600 for p in copied.values())     # the student's own
    assert all(stat.S_IMODE(p.stat().st_mode) == 0o644 for p in files(shared).values())     # untouched


def test_outside_the_hub_the_first_call_compiles_and_is_announced(tmp_path):
    seen = call({"NUMBA_CACHE_DIR": str(tmp_path / "own"), _numba_share.VARIABLE: ""})
    assert seen == {"cold": True, "hits": 0, "misses": 1}


def copied_from(shared: Path, own: Path) -> list:
    """Files of `own` that are copies of `shared`'s (same name and modification time)."""
    theirs = {p.name: p.stat().st_mtime_ns for p in shared.rglob("*") if p.is_file()}
    return [p for p in own.rglob("*") if p.is_file() and theirs.get(p.name) == p.stat().st_mtime_ns]


def test_a_cache_others_can_write_is_never_used(shared, tmp_path):
    open_copy = tmp_path / "open"
    subprocess.run(["cp", "-a", str(shared), str(open_copy)], check=True)
    folders = list(open_copy.iterdir())        # one per folder of kernels (network, tuning)
    for folder in folders:
        folder.chmod(0o777)                    # anyone may swap a kernel in
    assert folders and not any(_numba_share.trusted(folder) for folder in folders)
    own = tmp_path / "own"
    assert call({"NUMBA_CACHE_DIR": str(own), _numba_share.VARIABLE: str(open_copy)})["misses"] == 1
    assert copied_from(open_copy, own) == []


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="chown needs root")
def test_a_cache_of_another_account_is_never_used(shared, tmp_path):
    theirs = tmp_path / "theirs"
    subprocess.run(["cp", "-a", str(shared), str(theirs)], check=True)
    for path in [theirs, *theirs.rglob("*")]:
        os.chown(path, 65534, 65534)
    assert not any(_numba_share.trusted(folder) for folder in theirs.iterdir())
    own = tmp_path / "own"
    assert call({"NUMBA_CACHE_DIR": str(own), _numba_share.VARIABLE: str(theirs)})["misses"] == 1
    assert copied_from(theirs, own) == []


def test_a_kernel_the_student_compiled_since_is_kept(shared, tmp_path):
    own = tmp_path / "own"
    env = {"NUMBA_CACHE_DIR": str(own), _numba_share.VARIABLE: str(shared)}
    call(env)
    index = next(own.rglob("evaluation._tally-*.nbi"))
    later = index.stat().st_mtime_ns + 60 * 10**9     # as numba leaves it after adding a signature
    os.utime(index, ns=(later, later))
    assert call(env) == {"cold": False, "hits": 1, "misses": 0}
    assert index.stat().st_mtime_ns == later
    older = later - 3600 * 10**9                      # an index older than the teacher's is replaced
    os.utime(index, ns=(older, older))
    call(env)
    assert index.stat().st_mtime_ns == next(shared.rglob("evaluation._tally-*.nbi")).stat().st_mtime_ns


def test_seed_says_none_without_a_shared_folder(tmp_path):
    assert _numba_share.seed({}) is None
    assert _numba_share.seed({_numba_share.VARIABLE: str(tmp_path / "missing")}) is None


def test_trusted_refuses_a_group_writable_folder_but_not_a_sticky_one_above(tmp_path):
    top = tmp_path / "top"
    top.mkdir()
    leaf = top / "cache"
    leaf.mkdir(mode=0o755)
    top.chmod(0o1777)
    assert _numba_share.trusted(leaf)
    leaf.chmod(0o775)
    assert not _numba_share.trusted(leaf)
    leaf.chmod(0o755)
    top.chmod(0o777)                           # no sticky bit: anyone may rename the folder away
    assert not _numba_share.trusted(leaf)
    top.chmod(0o755)
