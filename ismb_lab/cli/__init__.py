"""The ``ismb-lab`` command line (docs/cli.md).

Each command is a module here with ``add_parser(subparsers)``, which registers its options and its
``run(args) -> exit code``.  A user's error is one line on stderr and exit code 2; a signal exits
with 128 + its number.  The command modules are imported when the parser is built, not when this
package is, so that a signal during start-up already finds the handlers of :func:`main`.
"""

from __future__ import annotations

import os
import sys

from .. import __version__
from .._core.files import OutputError
from ._guard import LIMITS, Interrupts, UsageError, interrupted_line, preflight

__all__ = ["UsageError", "build_parser", "main"]

def _epilog() -> str:
    from .._core.files import MAX_JSON_BYTES
    from ..images.io import MAX_PIXELS, MOST_PIXELS, PIXELS_VARIABLE
    from ..labels.targets import MAX_BYTES, MAX_PAIRS
    from ._guard import MOST

    return (f"limits (each set by its environment variable, a whole number from 1 to {MOST}; a value typed "
            "above its limit is refused, a default above it is lowered to it with a note): " + "; ".join(
        f"{option} <= {default} ({variable})" for variable, default, _, option in LIMITS.values())
        + f"; pixels per image <= {MAX_PIXELS} ({PIXELS_VARIABLE}, at most {MOST_PIXELS}); targets files "
        f"<= {MAX_PAIRS} pairs and {MAX_BYTES} bytes, params, rig and manifest files <= {MAX_JSON_BYTES} bytes "
        "(fixed)")


def _commands():
    from . import calibrate, course, depth, evaluate, match, rectify, render, rig, targets, tune
    return (match, tune, evaluate, depth, rectify, calibrate, rig, render, targets, course)


def build_parser():
    """The ``ismb-lab`` argument parser, with every command's subparser added."""
    from ._common import Parser

    parser = Parser(prog="ismb-lab", description="Hopfield-network stereo matching of Harris "
                    "corners (the ISMB thesis) from the command line.", epilog=_epilog())
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser, required=True)
    for command in _commands():
        command.add_parser(sub)
    return parser


def _interrupted(interrupts, running: bool) -> int:
    # Before its command runs, nothing has been written; once it runs, the command says what it kept.
    print(interrupted_line("" if running else "nothing was saved"), file=sys.stderr)
    return interrupts.exit_code


class _ReaderMayLeave:
    """sys.stdout or sys.stderr that never fails the command: a write after the pipe's reader left
    is dropped, one the device refuses (``> /dev/full``) is dropped and kept in `failed`, and a
    character the encoding cannot write is written as a backslash escape."""

    def __init__(self, stream):
        self._stream = stream
        self.failed = None

    def write(self, text):
        try:
            try:
                return self._stream.write(text)
            except UnicodeEncodeError:
                encoding = getattr(self._stream, "encoding", None) or "ascii"
                return self._stream.write(text.encode(encoding, "backslashreplace").decode(encoding))
        except OSError as exc:
            self._lost(exc)
        return len(text)

    def flush(self):
        try:
            self._stream.flush()
        except OSError as exc:
            self._lost(exc)

    def _lost(self, exc):
        if not isinstance(exc, BrokenPipeError):
            self.failed = self.failed or exc
        # What is still buffered, and the interpreter's own flush at exit, go to /dev/null.
        try:
            fd = self._stream.fileno()
        except (OSError, ValueError):   # a stream without a file (a test's capture)
            return
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, fd)
        finally:
            os.close(devnull)
        try:
            self._stream.flush()
        except OSError:
            pass

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _open_standard_fds() -> None:
    """Open /dev/null on each closed one of the file descriptors 0, 1 and 2 (``2>&-``): else the
    next file opened gets that number, and what a C library writes to "stderr" lands in it."""
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            devnull = os.open(os.devnull, os.O_RDWR)
            if devnull != fd:
                os.dup2(devnull, fd)
                os.close(devnull)


class _closed_pipes_tolerated:
    """``with _closed_pipes_tolerated():`` sys.stdout and sys.stderr as :class:`_ReaderMayLeave`;
    a stream that is None (closed when the program started) as one on /dev/null."""

    NAMES = ("stdout", "stderr")

    def __enter__(self):
        self._old = {name: getattr(sys, name) for name in self.NAMES}
        self._opened = []
        for name, stream in self._old.items():
            if stream is None:
                stream = open(os.devnull, "w")
                self._opened.append(stream)
            setattr(sys, name, _ReaderMayLeave(stream))
        return self

    def __exit__(self, *exc):
        for name in self.NAMES:
            getattr(sys, name).flush()
        streams = {name: getattr(sys, name) for name in self.NAMES}
        self.errors = {name: stream.failed if isinstance(stream, _ReaderMayLeave) else None
                       for name, stream in streams.items()}
        for name, stream in self._old.items():
            setattr(sys, name, stream)
        for stream in self._opened:
            stream.close()
        return False


def main(argv=None) -> int:
    """Entry point of ``ismb-lab``; returns the exit code.

    Run as the program (`argv` None), an interrupted run ends with ``os._exit``: a KeyboardInterrupt
    that passed through a C extension can leave CPython's "unhandled Ctrl-C" flag set, and the
    interpreter would then kill itself with SIGINT at exit instead of returning 130.
    """
    interrupts = Interrupts()
    if argv is None:
        _open_standard_fds()
    with _closed_pipes_tolerated() as streams:
        code = _main(argv, interrupts)
    lost = streams.errors["stdout"]
    if lost is not None and code == 0:
        code = 2
        if sys.stderr is not None:
            try:
                print(f"ismb-lab: error: cannot write the output to stdout: {lost.strerror or lost}",
                      file=sys.stderr, flush=True)
            except (OSError, ValueError):
                pass
    if argv is None and interrupts.signum is not None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


def _announce_compiling() -> None:
    """One line on a terminal's stderr before numba compiles the network's kernels (silent for up
    to a minute otherwise); not on a file or a pipe, where a script reads what the command reports."""
    from ..network.kernel import run_network
    from .._core.numba_cache import cold

    if sys.stderr.isatty() and cold(run_network):
        print("ismb-lab: compiling the network's kernels, once for this installation and user "
              "(up to a minute); later runs start at once", file=sys.stderr, flush=True)


def _main(argv, interrupts) -> int:
    usage_errors, args, running = (OutputError, OSError), None, False
    with interrupts:
        try:
            from ._common import ParameterError, ParameterTypeError

            usage_errors += (UsageError, ParameterError, ParameterTypeError)
            args = build_parser().parse_args(argv)
            preflight(args, UsageError)
            running = True
            if getattr(args, "compiles", False):   # a command that runs the network says so
                _announce_compiling()
            code = args.run(args)
            if code == 130 and interrupts.signum is not None:
                return interrupts.exit_code   # the command said "interrupted": say by which signal
            return code
        except KeyboardInterrupt:
            return _interrupted(interrupts, running)
        except Exception as exc:
            # A signal inside a C extension (numba's compiler, an import) can surface as a
            # SystemError or another exception: it is still an interruption, not a crash.
            if interrupts.signum is not None:
                return _interrupted(interrupts, running)
            if isinstance(exc, usage_errors):
                # The library's advice names its own keyword; on the command line the flag does that job.
                said = str(exc).replace("or pass check_hash=False", "or give --no-hash-check to 'ismb-lab tune'")
                print(f"ismb-lab: error: {said}", file=sys.stderr)
            elif isinstance(exc, RecursionError):
                files = [f"{name} {str(getattr(args, name))!r}" for name in ("targets", "manifest")
                         if getattr(args, name, None) is not None]
                print(f"ismb-lab: error: {' or '.join(files) or 'an input file'}: its JSON is "
                      "nested too deeply to read", file=sys.stderr)
            elif isinstance(exc, MemoryError):
                print("ismb-lab: error: out of memory: the input is too large for this machine "
                      "(see the limits in 'ismb-lab --help')", file=sys.stderr)
            elif (type(exc).__module__, type(exc).__name__) == ("cv2", "error"):
                # OpenCV refuses what no check here foresaw: still the input's fault (cv2.error is
                # named, so that importing the CLI imports no OpenCV)
                said = " ".join(str(exc).split())
                print(f"ismb-lab: error: OpenCV cannot work with this input: "
                      f"{said if len(said) <= 300 else said[:297] + '...'}", file=sys.stderr)
            else:
                raise
    return 2
