"""Where numba keeps the compiled kernels: its own places, else a private folder of this user.

When numba can write neither beside the source nor to the user's cache folder, it refuses to
define a ``cache=True`` kernel; :func:`configure`, run at ``import ismb_lab``, then sets
``NUMBA_CACHE_DIR`` to a private folder (a cache is code numba loads).  A set one always wins.
"""

from __future__ import annotations

import os
import sys
import tempfile

__all__ = ["VARIABLE", "cold", "configure", "fallback_folder", "writable"]

VARIABLE = "NUMBA_CACHE_DIR"
# numba caches beside the source when it can: the kernels' own folder
_IN_TREE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "network/__pycache__")


def writable(folder) -> bool:
    """Whether `folder` can be made and written to, tested as numba tests it (a temporary file).

    >>> writable(tempfile.gettempdir())
    True
    """
    try:
        os.makedirs(folder, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def fallback_folder(temp: str | None = None) -> str:
    """``<temp>/ismb_lab-numba-<uid>`` if private to this user, else a new private folder there."""
    from .files import private_folder

    path = private_folder("ismb_lab-numba", temp)
    if writable(path):
        return path
    return tempfile.mkdtemp(prefix="ismb_lab-numba-", dir=temp or tempfile.gettempdir())


def _user_wide_cache() -> str:
    from numba.misc.appdirs import AppDirs   # numba's own rule (XDG_CACHE_HOME, ~/.cache, ...)

    return AppDirs(appname="numba", appauthor=False).user_cache_dir


def configure() -> str | None:
    """Set ``NUMBA_CACHE_DIR`` to :func:`fallback_folder` when numba has nowhere to cache;
    return the folder set, or None when nothing was changed."""
    if os.environ.get(VARIABLE) or not hasattr(os, "getuid") or writable(_IN_TREE):
        return None
    if writable(_user_wide_cache()):
        return None
    try:
        folder = fallback_folder()
    except OSError:   # nowhere to write at all: numba says so when a kernel is defined
        return None
    os.environ[VARIABLE] = folder
    if "numba" in sys.modules:   # read at numba's import; this process imported it already
        from numba.core import config

        config.reload_config()
    return folder


configure()
# On the class hub: the kernels the teacher compiled, copied into this user's own cache.
from .numba_share import cold, seed as _seed  # noqa: E402,F401  (cold: re-exported)

_seed()
