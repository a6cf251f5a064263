"""What every ``ismb-lab`` command gets before and around its work: the limits (each set by an
environment variable, listed by ``ismb-lab --help`` and docs/cli.md), the checks of its inputs and
outputs (:func:`preflight`), the handling of SIGINT, SIGTERM and SIGHUP (:class:`Interrupts`) and
the atomic writes of its JSON and plots.  Each command declares the defaults of its limited options
(``limit_defaults``) and its files (``declare_files``), so this module knows no command by name.
"""

from __future__ import annotations

import json
import math
import os
import signal
import sys
import threading
from pathlib import Path
from typing import NamedTuple

from .._core.files import atomic_write_bytes, check_input, check_output

__all__ = ["LIMITS", "MOST", "Interrupts", "UsageError", "deferred_signals", "interrupted", "interrupted_line",
           "is_interruption", "json_text", "limit", "preflight", "save_plot"]

class UsageError(Exception):
    """A mistake in the command line or its files, reported in one line."""


#: name -> (environment variable, default, what it bounds, the option it bounds)
LIMITS = {
    "n_max": ("ISMB_LAB_MAX_CORNERS", 500, "corners per image", "--n-max"),
    "population": ("ISMB_LAB_MAX_POPULATION", 1000, "chromosomes", "--population"),
    "generations": ("ISMB_LAB_MAX_GENERATIONS", 100_000, "generations", "--generations"),
    "seeds": ("ISMB_LAB_MAX_SEEDS", 100, "seeds", "--seeds"),
    "fit_seeds": ("ISMB_LAB_MAX_SEEDS", 100, "seeds", "--fit-seeds"),
    "jobs": ("ISMB_LAB_MAX_JOBS", 64, "worker processes", "--jobs"),
}

_ACTIVE: list = []


#: The most any ISMB_LAB_MAX_* variable but ISMB_LAB_MAX_PIXELS may be set to.
MOST = 1_000_000_000


def limit(name: str) -> int:
    """The limit in force for `name` (a key of :data:`LIMITS`), from the environment or the default.

    >>> limit("generations") >= 1
    True
    """
    variable, default = LIMITS[name][:2]
    raw = (os.environ.get(variable) or "").strip()
    if raw == "":
        return default
    # Compared as text first: int() of thousands of digits is slow, then refused anyway.
    value = int(raw) if raw.isascii() and raw.isdigit() and len(raw) <= len(str(MOST)) else 0
    if not 1 <= value <= MOST:
        raise UsageError(f"{variable} must be a whole number from 1 to {MOST}, got {_short(raw)!r}")
    return value


def _short(text) -> str:
    """`text` (or a number) cut to 40 characters, for a one-line message."""
    if isinstance(text, int):
        from .._core.validation import shown_int
        return shown_int(text)
    return text if len(text) <= 40 else text[:37] + "..."


def _bound(args, usage_error) -> None:
    """Refuse a typed value above its limit; lower a default above it, with a note."""
    defaults = None
    for name, (variable, _, what, option) in LIMITS.items():
        if not hasattr(args, name):
            continue
        value, most = getattr(args, name), limit(name)
        if value is not None:
            if value > most:
                hint = f"set {variable}={value} to allow it" if value <= MOST else f"a limit is at most {MOST}"
                raise usage_error(f"{option} {_short(value)} is above the limit of {most} {what}; {hint}")
            continue
        if defaults is None:   # each command declares the defaults of its limited options
            declared = getattr(args, "limit_defaults", None)
            defaults = {} if declared is None else declared()
        default = defaults.get(name)
        if default is not None and default > most:
            setattr(args, name, most)
            print(f"ismb-lab: note: {option} defaults to {default}, above {variable}={most}: "
                  f"using {option} {most}", file=sys.stderr)


class Interrupts:
    """Within ``with Interrupts() as i:``, SIGINT, SIGTERM and SIGHUP raise KeyboardInterrupt.

    The first signal is kept in ``i.signum``; while ``i.deferring`` is true a signal is only
    recorded.  Handlers are installed only in the main thread, and a signal ignored when the
    process started (``nohup``) stays ignored.
    """

    NAMES = ("SIGINT", "SIGTERM", "SIGHUP")

    def __init__(self):
        self.signum = None
        self.deferring = False
        self._old = {}

    def _unraisable(self, report):
        # A KeyboardInterrupt raised inside a __del__ or a callback cannot propagate: once a
        # signal came, "Exception ignored ..." reports are its echoes.
        if self.signum is None:
            self._old_hook(report)

    def _excepthook(self, kind, value, trace):
        # C code that calls PyErr_Print (numpy's import_array) prints a KeyboardInterrupt raised
        # inside an import it started; after a signal that print is an echo as well.
        if self.signum is None or not issubclass(kind, KeyboardInterrupt):
            self._old_excepthook(kind, value, trace)

    def _handle(self, signum, frame):
        if self.signum is None:
            self.signum = signum
        if not self.deferring:
            raise KeyboardInterrupt

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for name in self.NAMES:
                number = getattr(signal, name, None)
                if number is None or signal.getsignal(number) == signal.SIG_IGN:
                    continue
                self._old[number] = signal.signal(number, self._handle)
        self._old_hook, sys.unraisablehook = sys.unraisablehook, self._unraisable
        self._old_excepthook, sys.excepthook = sys.excepthook, self._excepthook
        _ACTIVE.append(self)
        return self

    def __exit__(self, *exc):
        for number, old in self._old.items():
            signal.signal(number, old)
        self._old.clear()
        sys.unraisablehook = self._old_hook
        sys.excepthook = self._old_excepthook
        _ACTIVE.remove(self)
        return False

    @property
    def exit_code(self) -> int:
        """``128 + n`` for signal n; 130 (SIGINT) when no signal was recorded."""
        return 128 + (self.signum or signal.SIGINT)


def interrupted() -> bool:
    """True once a signal reached the innermost active :class:`Interrupts`."""
    return bool(_ACTIVE) and _ACTIVE[-1].signum is not None


def is_interruption(exc: BaseException) -> bool:
    """Whether `exc` is how a signal surfaced: a KeyboardInterrupt, or, once a signal came, any
    exception (one raised inside a C extension reaches Python as a SystemError)."""
    return isinstance(exc, KeyboardInterrupt) or (isinstance(exc, Exception) and interrupted())


def interrupted_line(outcome: str = "") -> str:
    """The one line an interrupted command prints: which signal, and what became of its output.

    >>> interrupted_line("nothing was saved")
    'ismb-lab: interrupted; nothing was saved'
    """
    signum = _ACTIVE[-1].signum if _ACTIVE else None
    how = "" if signum in (None, signal.SIGINT) else f" ({signal.Signals(signum).name})"
    return f"ismb-lab: interrupted{how}" + (f"; {outcome}" if outcome else "")


class deferred_signals:
    """Within ``with deferred_signals():`` a signal is recorded but raises nothing: the block runs
    to its end."""

    def __enter__(self):
        self._interrupts = _ACTIVE[-1] if _ACTIVE else None
        self._was = self._interrupts is not None and self._interrupts.deferring
        if self._interrupts is not None:
            self._interrupts.deferring = True
        return self

    def __exit__(self, *exc):
        if self._interrupts is not None:
            self._interrupts.deferring = self._was
        return False


def _plain(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def json_text(data) -> str:
    """Strict JSON (RFC 8259) of `data`: a number that is not finite (an infinite depth) is ``null``.

    >>> json_text({"z": float("inf"), "d": [1.5, float("nan")]})
    '{\\n  "z": null,\\n  "d": [\\n    1.5,\\n    null\\n  ]\\n}\\n'
    """
    return json.dumps(_plain(data), indent=2, allow_nan=False) + "\n"


def save_plot(path, size, draw, title: str) -> Path:
    """A figure of `size` inches drawn by ``draw(ax)`` and titled, written atomically in the format
    of `path`'s suffix (png without one)."""
    import io

    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    ax = fig.subplots()
    draw(ax)
    ax.set_title(title)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=Path(path).suffix[1:].lower() or "png", dpi=120)
    return atomic_write_bytes(path, buffer.getvalue())


class Files(NamedTuple):
    """What a command's ``files(args)`` (the parser's default ``declare_files``) declares: the
    `inputs` and `outputs` as (option, path), and the further files it `reads` (a manifest's pairs)."""

    inputs: tuple = ()
    reads: tuple = ()
    outputs: tuple = ()


def files_of(args) -> Files:
    """The files that `args`' command declares."""
    declared = getattr(args, "declare_files", None)
    return Files() if declared is None else declared(args)


def _check_plot(path, usage_error) -> None:
    from matplotlib.backend_bases import FigureCanvasBase

    suffix = Path(path).suffix[1:].lower()
    formats = FigureCanvasBase.get_supported_filetypes()
    if suffix and suffix not in formats:
        raise usage_error(f"--plot {str(path)!r}: cannot draw a '.{suffix}' file "
                          f"(formats: {', '.join(sorted(formats))})")


def preflight(args, usage_error) -> None:
    """Check the limits, inputs and outputs of a parsed command line before its work starts.

    An option left out whose default is above its limit is lowered to it.  Every input is a regular
    file, and no output is an input, a file read or another output, whatever link or spelling leads
    there.  Raises `usage_error` (or :class:`ismb_lab._core.files.OutputError`) with a one-line message.
    """
    _bound(args, usage_error)
    declared = files_of(args)
    for what, path in declared.inputs:
        check_input(path, what=what)
    read = [path for _, path in declared.inputs] + list(declared.reads)
    seen = []
    for what, path in declared.outputs:
        if what == "--plot":
            _check_plot(path, usage_error)
        for other, other_path in seen:
            if os.path.realpath(other_path) == os.path.realpath(path):
                raise usage_error(f"{what} and {other} name the same file {str(path)!r}")
        check_output(path, inputs=read, force=getattr(args, "force", False), what=what)
        seen.append((what, path))


def add_force_option(p) -> None:
    """``--force``, for a command that writes files the user names."""
    p.add_argument("--force", action="store_true",
                   help="replace a read-only output file, or write into an existing device "
                   "or FIFO (an output that is an input is always refused)")


def output_path(text: str) -> Path:
    """An argparse type for an output file: a name that is not written as a folder's.

    >>> output_path("out.json")
    PosixPath('out.json')
    """
    import argparse

    from .._core.files import OutputError, refuse_folder_name

    try:
        refuse_folder_name(text, "")
    except OutputError as exc:
        raise argparse.ArgumentTypeError(str(exc).strip()) from None
    return Path(text)
