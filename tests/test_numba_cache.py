"""The kernels import, and cache, for a user who can write neither beside the package nor in
HOME; and the test session's warm-up reaches every kernel.

Each cache case runs a fresh interpreter on a copy of the package (slow).  Its two default
cache places are made unwritable in a way that holds for root as well, who ignores file
modes: the ``__pycache__`` of the copy's kernel folders is a regular file (no folder can be made there) and
HOME is a regular file (nor under it).  A read-only mode would not stop root, and the
interpreter under /work/main/.venv cannot be run by an unprivileged account.
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ismb_lab._core.numba_share import KERNEL_SOURCES

ROOT = Path(__file__).resolve().parent.parent

#: The package's folders with compiled kernels: numba caches beside the source, in their __pycache__.
KERNEL_FOLDERS = [Path(source).parent for source in KERNEL_SOURCES]
POSIX = pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX users")

PROBE = """
import json, os
import numpy as np
import ismb_lab.network.dynamics, ismb_lab.network.similarity
from numba.core import config
ismb_lab.network.similarity._block_sum(np.arange(3.0), 0, 3)   # compiles, and writes its cache
print(json.dumps({"variable": os.environ.get("NUMBA_CACHE_DIR"), "config": config.CACHE_DIR}))
"""


@pytest.fixture
def nowhere(tmp_path):
    """An environment and a copy of the package where numba's default cache places cannot be written."""
    site = tmp_path / "site"
    shutil.copytree(ROOT / "ismb_lab", site / "ismb_lab", ignore=shutil.ignore_patterns("__pycache__"))
    for folder in KERNEL_FOLDERS:
        (site / "ismb_lab" / folder / "__pycache__").write_text("not a folder\n")
    home = tmp_path / "home"
    home.write_text("not a folder\n")
    temp = tmp_path / "temp"
    temp.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env.update(PYTHONPATH=str(site), HOME=str(home), TMPDIR=str(temp), PYTHONDONTWRITEBYTECODE="1")
    return env, temp


def probe(env):
    proc = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True,
                          timeout=300, cwd=env["TMPDIR"])
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.splitlines()[-1])


@pytest.mark.slow
@POSIX
def test_with_nowhere_to_cache_the_kernels_use_a_private_temporary_folder(nowhere):
    env, temp = nowhere
    folder = temp / f"ismb_lab-numba-{os.getuid()}"
    assert probe(env) == {"variable": str(folder), "config": str(folder)}
    assert folder.stat().st_mode & 0o777 == 0o700
    assert list(folder.rglob("*.nbi"))   # the cache index was written there
    assert probe(env)["config"] == str(folder)   # and the next run uses it again


@pytest.mark.slow
@POSIX
def test_a_fallback_folder_that_others_may_write_to_is_never_used(nowhere):
    env, temp = nowhere
    shared = temp / f"ismb_lab-numba-{os.getuid()}"
    shared.mkdir()
    shared.chmod(0o777)
    used = Path(probe(env)["config"])
    assert used != shared and used.parent == temp and used.stat().st_mode & 0o777 == 0o700
    assert not any(shared.iterdir())


@pytest.mark.slow
@POSIX
def test_a_numba_cache_dir_that_is_set_always_wins(nowhere, tmp_path):
    env, temp = nowhere
    mine = tmp_path / "mine"
    env["NUMBA_CACHE_DIR"] = str(mine)
    assert probe(env) == {"variable": str(mine), "config": str(mine)}
    assert list(mine.rglob("*.nbi")) and not list(temp.iterdir())


@pytest.mark.slow
@POSIX
def test_where_numba_can_cache_nothing_is_changed(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(HOME=str(tmp_path), TMPDIR=str(tmp_path))   # a writable HOME, as most users have
    site = tmp_path / "site"
    shutil.copytree(ROOT / "ismb_lab", site / "ismb_lab", ignore=shutil.ignore_patterns("__pycache__"))
    for folder in KERNEL_FOLDERS:   # not beside the package (for a user other than root) ...
        (site / "ismb_lab" / folder).chmod(0o555)
    env["PYTHONPATH"] = str(site)
    try:
        assert probe(env) == {"variable": None, "config": ""}   # ... numba's own places serve
    finally:
        for folder in KERNEL_FOLDERS:
            (site / "ismb_lab" / folder).chmod(0o755)
    assert not list(tmp_path.glob("ismb_lab-numba-*"))



WARM = """
import importlib, importlib.util, json, pkgutil, sys
spec = importlib.util.spec_from_file_location("shared_fixtures", sys.argv[1])
fixtures = importlib.util.module_from_spec(spec)
spec.loader.exec_module(fixtures)
report = fixtures.warm_kernels()
import ismb_lab
from ismb_lab._core.numba_cache import cold
for info in pkgutil.walk_packages(ismb_lab.__path__, "ismb_lab."):
    if not info.name.endswith(".__main__"):
        importlib.import_module(info.name)
found = fixtures.kernels()
print(json.dumps({"report": report, "kernels": sorted(found), "cold": sorted(n for n, k in found.items() if cold(k))}))
"""


@pytest.mark.slow   # compiles every kernel from nothing (about 30 s)
def test_the_session_warm_up_compiles_every_kernel_of_the_package(tmp_path):
    """tests/conftest.py's warm-up, run with an empty cache, leaves no kernel of the package
    without cached code: no test compiles a kernel of the library from nothing."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", WARM, str(ROOT / "tests" / "conftest.py")], env=env,
                          capture_output=True, text=True, timeout=900, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.splitlines()[-1])
    assert len(out["kernels"]) >= 20 and out["cold"] == []
    assert out["report"] == {"cold": len(out["kernels"]), "all": len(out["kernels"])}
