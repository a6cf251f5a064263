"""The class hub's compiled kernels: compiled once by the teacher, loaded by every student.

numba caches a ``cache=True`` kernel only in a folder it can write to: a cache that root
compiled into the class venv, or any other folder students can read but not write, is
skipped, and every student compiles the kernels again at the start of the lesson.  So:

* the teacher's step, ``python -m ismb_lab.hub_start stage``, runs :func:`compile_kernels`
  in a new interpreter with ``NUMBA_CACHE_DIR`` set to ``COURSE/numba``
  (:func:`compile_into`); the folder ends up root's and read-only (folders 755, files 644);
* the hub names that folder in :data:`VARIABLE` for every server, and the course's
  ``/etc/profile.d`` file for every login shell;
* when :mod:`ismb_lab` is imported, :func:`seed` copies the compiled kernels of this
  installation from there into the cache that numba uses for this user (their own, which
  numba writes itself), unless theirs is as new.

The student's own process makes the copy, into a folder of theirs: no one ever loads a
cache that another student can write.  The shared folder is used only if it, every folder
above it and every file copied belong to root or to this user and no one else may write
to them (a cache is code that numba loads).  numba keys the index of a cached kernel on
its source file (the folder's path and the file's contents) and on the CPU, so the
teacher's copy fits every student of the same installation on the same machine; for any
other source it is not used, and numba compiles as before.
"""

from __future__ import annotations

import os
import shutil
import stat
import sys
import tempfile

__all__ = ["VARIABLE", "compile_into", "compile_kernels", "own_cache_folder", "seed", "shared_folder",
           "trusted"]

#: The environment variable naming the teacher's read-only cache (``COURSE/numba``).
VARIABLE = "ISMB_NUMBA_SHARED"
_PACKAGE = os.path.dirname(os.path.abspath(__file__))


def trusted(path) -> bool:
    """Whether `path` (a file or folder) and every folder above it belong to root or to this
    user, and no one else may write to them (a folder with the sticky bit, such as /tmp, may
    be world-writable above it).  Symbolic links are resolved first.

    >>> trusted("/")
    True
    """
    real = os.path.realpath(path)
    chain, current = [real], real
    while os.path.dirname(current) != current:
        current = os.path.dirname(current)
        chain.append(current)
    for depth, place in enumerate(chain):
        try:
            info = os.lstat(place)
        except OSError:
            return False
        if info.st_uid not in (0, os.getuid()):
            return False
        open_to_others = info.st_mode & (stat.S_IWGRP | stat.S_IWOTH)
        if open_to_others and not (depth > 0 and stat.S_ISDIR(info.st_mode) and info.st_mode & stat.S_ISVTX):
            return False
    return True


def _subpath() -> str:
    """numba's folder name for this package's kernels inside a cache root."""
    from numba.core.caching import _CacheLocator

    return _CacheLocator.get_suitable_cache_subpath(os.path.join(_PACKAGE, "_kernel.py"))


def shared_folder(root) -> str:
    """The folder of a cache root (as ``NUMBA_CACHE_DIR`` names one) holding this package's kernels."""
    return os.path.join(root, _subpath())


def own_cache_folder() -> str | None:
    """The folder numba caches this package's kernels in for this process: ``NUMBA_CACHE_DIR``'s
    or the user's own cache folder (``~/.cache/numba``).  None when numba would cache beside
    the source instead (the user can write into the installation) or nowhere."""
    from numba.core import caching

    def named(name):       # numba 0.68 dropped the leading underscore of these names
        return getattr(caching, name, None) or getattr(caching, f"_{name}")

    per_user = (named("UserProvidedCacheLocator"), named("UserWideCacheLocator"))
    source = os.path.join(_PACKAGE, "_kernel.py")
    for kind in named("CacheImpl")._locator_classes:
        locator = kind.from_function(own_cache_folder, source)
        if locator is not None:
            return locator.get_cache_path() if isinstance(locator, per_user) else None
    return None


def _units(folder: str) -> dict:
    """``{index file: [its data files]}`` of a numba cache folder."""
    names = os.listdir(folder)
    units = {}
    for name in names:
        if name.endswith(".nbi"):
            base = name[:-len(".nbi")]
            units[name] = sorted(n for n in names if n.startswith(base + ".") and n.endswith(".nbc")
                                 and n[len(base) + 1:-len(".nbc")].isdigit())
    return units


def _copy(source: str, target: str) -> None:
    """Copy a file (contents, modification time) into place in one rename: numba never
    reads half of it."""
    fd, temporary = tempfile.mkstemp(prefix=".ismb-seed-", dir=os.path.dirname(target))
    try:
        with os.fdopen(fd, "wb") as out, open(source, "rb") as src:
            shutil.copyfileobj(src, out)
        shutil.copystat(source, temporary)
        os.chmod(temporary, 0o600)
        os.replace(temporary, target)
    except BaseException:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise


def seed(environ=None) -> int | None:
    """Copy the teacher's compiled kernels (the folder :data:`VARIABLE` names) into this
    user's own numba cache; returns the number of kernels copied, or None when there is no
    shared folder to use (not set, not found, or not trusted: see :func:`trusted`).

    A kernel is copied, its data files first and its index last, when this user has no
    index for it or an older one than the teacher's; one the user's numba wrote since (a
    newer index) is kept.  Never raises: without the copy numba compiles, as it always did.
    """
    environ = os.environ if environ is None else environ
    root = environ.get(VARIABLE, "")
    if not root or not hasattr(os, "getuid"):
        return None
    try:
        source = shared_folder(root)
        if not os.path.isdir(source) or not trusted(source):
            return None
        target = own_cache_folder()
        if target is None or os.path.realpath(target) == os.path.realpath(source):
            return 0
        copied = 0
        for index, data in sorted(_units(source).items()):
            theirs, mine = os.path.join(source, index), os.path.join(target, index)
            try:
                if os.stat(mine).st_mtime >= os.stat(theirs).st_mtime:
                    continue
                os.unlink(mine)       # no moment where an old index points at new data files
            except FileNotFoundError:
                pass
            files = [os.path.join(source, name) for name in (*data, index)]
            if not all(trusted(path) and os.path.isfile(path) for path in files):
                continue
            for path in files:
                _copy(path, os.path.join(target, os.path.basename(path)))
            copied += 1
        return copied
    except (OSError, ImportError, AttributeError, ValueError):
        return None


def compile_kernels() -> dict:
    """Compile (or load) every kernel the lessons run, in this process's numba cache; returns
    ``{"seconds": ..., "kernels": n, "cold": [kernels with no compiled version in the cache]}``.

    The runs: a first match with every solver (:func:`ismb_lab.matching.warm_up`), the
    genetic algorithm's batched fitness, a scored evaluation, the step-by-step annealing and
    the exhaustive search.
    """
    import time

    import numpy as np

    from . import annealing, exact, hopfield, tuning
    from .matching import warm_up
    from .methods import get_method
    from .protocol import Case
    from .scenes import synthetic_scene
    from .solvers import solver_names

    start = time.perf_counter()
    warm_up(solver_names())
    case = Case.from_scene(synthetic_scene(seed=0))
    for method in ("I", "III"):       # Method-I's post-processing is a kernel of its own
        bounds = tuning.gene_bounds(method)
        tuning.Fitness([case], method)(np.array([(bounds.low + bounds.high) / 2]))
    net = hopfield.Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, 0.0],
                                       pair_a=[], pair_b=[], pair_c=[])
    tuning.evaluate([case], "III", get_method("III").defaults)
    list(annealing.iter_annealing(net))
    exact.exhaustive_minimum(net)
    kernels = _kernels()
    # a kernel that only other kernels call is linked into them when they are loaded from the
    # cache, so it may have no signature of its own in this process: its index file counts
    return {"seconds": round(time.perf_counter() - start, 1), "kernels": len(kernels),
            "cold": sorted(name for name, kernel in kernels.items() if not kernel.signatures and cold(kernel))}


def _kernels() -> dict:
    """Every cached numba kernel of the package's modules imported so far, by name."""
    from numba.core.registry import CPUDispatcher

    found = {}
    for name, module in list(sys.modules.items()):
        if name.split(".")[0] != __name__.split(".")[0]:
            continue
        for attribute, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == name \
                    and value._cache.__class__.__name__ != "NullCache":
                found[f"{name}.{attribute}"] = value
    return found


def compile_into(folder, python=None, isolated: bool = True, timeout: float = 1800) -> dict:
    """Run :func:`compile_kernels` in a new interpreter (`python`, by default this one) whose
    numba cache is `folder`; returns its report plus ``"source"``, the package folder the
    kernels were compiled for (students load them only if their servers import that one).

    `isolated` (``python -I``): the package is the one installed in that interpreter, as the
    hub's servers import it, whatever the current folder or ``PYTHONPATH`` (a repository's
    copy would be a different source for numba).  An existing cache (the folder
    :data:`VARIABLE` names, such as an earlier course's) is seeded in first, so kernels whose
    source has not changed are not compiled again.  Raises OSError if the interpreter fails.
    """
    import json
    import subprocess

    os.makedirs(folder, exist_ok=True)
    env = {**os.environ, "NUMBA_CACHE_DIR": os.path.abspath(folder), "MPLBACKEND": "Agg"}
    code = ("import json, os, ismb_lab._numba_share as s; report = s.compile_kernels(); "
            "report['source'] = os.path.dirname(s.__file__); print(json.dumps(report))")
    done = subprocess.run([python or sys.executable, *(["-I"] if isolated else []), "-c", code], env=env,
                          capture_output=True, text=True, timeout=timeout)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise OSError(f"compiling the kernels failed (exit {done.returncode}): {last}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def cold(kernel) -> bool:
    """Whether numba holds no cached machine code of `kernel` (a ``cache=True`` dispatcher) yet,
    so that its first call will compile.  False when numba's cache cannot be inspected.

    >>> import numba
    >>> cold(numba.njit(lambda x: x))      # no cache at all: nothing to announce
    False
    """
    try:
        folder = kernel._cache._cache_path
        stem = f"{kernel.py_func.__module__.rsplit('.', 1)[-1]}.{kernel.py_func.__qualname__}-"
        names = os.listdir(folder) if os.path.isdir(folder) else []
    except (AttributeError, OSError):
        return False
    return not any(name.startswith(stem) and name.endswith(".nbi") for name in names)
