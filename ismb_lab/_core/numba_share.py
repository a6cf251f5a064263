"""The class hub's compiled kernels: compiled once by the teacher, loaded by every student.

numba skips a cache folder it cannot write to, so the teacher's read-only ``COURSE/numba``
(:func:`ismb_lab.teaching.kernels.compile_into`, named by :data:`VARIABLE`) is copied by
:func:`seed`, at ``import ismb_lab``, into this user's own cache, in their own process.  It is used
only if it, every folder above it and every file copied belong to root or to this user and no
one else may write to them (a cache is code that numba loads).
"""

from __future__ import annotations

import os
import shutil
import stat
import tempfile

__all__ = ["KERNEL_SOURCES", "VARIABLE", "cold", "own_cache_folder", "seed", "shared_folder", "trusted"]

#: The environment variable naming the teacher's read-only cache (``COURSE/numba``).
VARIABLE = "ISMB_NUMBA_SHARED"
_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: A source file of each folder with cached kernels: numba keeps one cache folder per source folder.
KERNEL_SOURCES = ("network/kernel.py", "tuning/evaluation.py")


def trusted(path) -> bool:
    """Whether `path` (links resolved) and every folder above it belong to root or this user and
    no one else may write to them (a sticky folder such as /tmp above it may).

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


def _source(file: str) -> str:
    return os.path.join(_PACKAGE, *file.split("/"))


def shared_folder(root, source: str = KERNEL_SOURCES[0]) -> str:
    """The folder of a cache root (as ``NUMBA_CACHE_DIR`` names one) holding the kernels beside
    `source`, one of :data:`KERNEL_SOURCES`."""
    from numba.core.caching import _CacheLocator

    return os.path.join(root, _CacheLocator.get_suitable_cache_subpath(_source(source)))


def own_cache_folder(source: str = KERNEL_SOURCES[0]) -> str | None:
    """The folder numba caches the kernels beside `source` in for this process, if it is
    ``NUMBA_CACHE_DIR``'s or the user's own cache folder; else None."""
    from numba.core import caching

    def named(name):       # numba 0.68 dropped the leading underscore of these names
        return getattr(caching, name, None) or getattr(caching, f"_{name}")

    per_user = (named("UserProvidedCacheLocator"), named("UserWideCacheLocator"))
    source = _source(source)
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
    """Copy a file (contents, modification time) into place in one rename."""
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


def _seed_folder(source: str, target: str | None) -> int:
    """Copy the kernels of one shared cache folder into `target`; returns how many."""
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


def seed(environ=None) -> int | None:
    """Copy the teacher's compiled kernels into this user's own numba cache; the number copied,
    or None when there is no trusted shared folder.

    A kernel is copied, data files first and index last, unless this user's index is as new.
    Never raises: without the copy numba compiles.
    """
    environ = os.environ if environ is None else environ
    root = environ.get(VARIABLE, "")
    if not root or not hasattr(os, "getuid"):
        return None
    try:
        copied = None
        for source in KERNEL_SOURCES:
            folder = shared_folder(root, source)
            if not os.path.isdir(folder) or not trusted(folder):
                continue
            copied = (copied or 0) + _seed_folder(folder, own_cache_folder(source))
        return copied
    except (OSError, ImportError, AttributeError, ValueError):
        return None


def cold(kernel) -> bool:
    """Whether the first call of `kernel` (a ``cache=True`` dispatcher) will compile; False when
    numba's cache cannot be inspected.

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
