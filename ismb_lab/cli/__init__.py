"""The ``ismb-lab`` command line.

Every error the user can cause prints one line on stderr and exits with code 2.
Each command is a module of this package with ``add_parser(subparsers)``, which
registers its options and its ``run(args) -> exit code``.

Before a command's work starts, :func:`ismb_lab.cli._guard.preflight` checks its
limits, its inputs (regular files only) and its outputs (never an input, a folder,
a device, a FIFO or a read-only file unless ``--force``; symbolic links are written
through, never replaced).  SIGINT, SIGTERM and SIGHUP stop the work alike; the exit
code is 128 + the signal's number (130 for Ctrl-C).

A closed stdout or stderr (``ismb-lab match ... | head``) is not an error: what is
printed after the reader left is dropped, the command's files are still written, and
the exit code is the command's own (0 when it succeeded).

The command modules are imported when the parser is built, not when this package
is, so that a signal during start-up already finds the handlers of :func:`main`.
"""

from __future__ import annotations

import os
import sys

from .. import __version__
from .._files import OutputError
from ._guard import LIMITS, Interrupts, interrupted_line, preflight

__all__ = ["COMMANDS", "UsageError", "build_parser", "main"]

def _epilog() -> str:
    from ..io import MAX_PIXELS, MOST_PIXELS, PIXELS_VARIABLE
    from ..targets import MAX_BYTES, MAX_PAIRS
    from ._guard import MOST

    return (f"limits (each set by its environment variable, a whole number from 1 to {MOST}; a value typed "
            "above its limit is refused, a default above it is lowered to it with a note): " + "; ".join(
        f"{option} <= {default} ({variable})" for variable, default, _, option in LIMITS.values())
        + f"; pixels per image <= {MAX_PIXELS} ({PIXELS_VARIABLE}, at most {MOST_PIXELS}); targets files "
        f"<= {MAX_PAIRS} pairs and {MAX_BYTES} bytes (fixed)")


def _commands():
    from . import calibrate, course, depth, evaluate, match, rectify, render, targets, tune
    return (match, tune, evaluate, depth, rectify, calibrate, render, targets, course)


def __getattr__(name):
    if name == "COMMANDS":   #: The commands, in the order ``--help`` lists them.
        return _commands()
    if name == "UsageError":
        from ._common import UsageError
        return UsageError
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _add_safety_options(p) -> None:
    options = p._option_string_actions
    if any(o in options for o in ("--json", "--plot")) or (
            "--out" in options and p.prog.split()[-1] != "render"):
        p.add_argument("--force", action="store_true",
                       help="replace a read-only output file, or write into an existing device "
                       "or FIFO (an output that is an input is always refused)")
    if p.prog.split()[-1] == "tune":
        p.add_argument("--no-hash-check", action="store_true",
                       help="accept targets labelled on images with other bytes (e.g. re-encoded)")


def build_parser():
    from ._common import Parser

    parser = Parser(prog="ismb-lab", description="Hopfield-network stereo matching of Harris "
                    "corners (the ISMB thesis) from the command line.", epilog=_epilog())
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    sub.required = True
    for command in _commands():
        command.add_parser(sub)
    for p in sub.choices.values():
        _add_safety_options(p)
    return parser


def _cli_words(text: str) -> str:
    # The library's advice names its own keyword; on the command line the flag does that job.
    return text.replace("or pass check_hash=False", "or give --no-hash-check to 'ismb-lab tune'")


def _interrupted(interrupts, running: bool) -> int:
    # Before its command runs, nothing has been written; once it runs, the command says what it kept.
    print(interrupted_line("" if running else "nothing was saved"), file=sys.stderr)
    return interrupts.exit_code


class _ReaderMayLeave:
    """A stand-in for sys.stdout or sys.stderr that drops what is printed once the reader of
    its pipe has gone (a BrokenPipeError), instead of failing the command."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._to_devnull()
            return len(text)

    def flush(self):
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._to_devnull()

    def _to_devnull(self):
        # What is still buffered, and the interpreter's own flush at exit, go to /dev/null.
        devnull = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(devnull, self._stream.fileno())
        finally:
            os.close(devnull)

    def __getattr__(self, name):
        return getattr(self._stream, name)


class _closed_pipes_tolerated:
    """``with _closed_pipes_tolerated():`` sys.stdout and sys.stderr as :class:`_ReaderMayLeave`."""

    NAMES = ("stdout", "stderr")

    def __enter__(self):
        self._old = {name: getattr(sys, name) for name in self.NAMES}
        for name, stream in self._old.items():
            if stream is not None:
                setattr(sys, name, _ReaderMayLeave(stream))

    def __exit__(self, *exc):
        for name, stream in self._old.items():
            if stream is not None:
                getattr(sys, name).flush()
                setattr(sys, name, stream)
        return False


def main(argv=None) -> int:
    """Entry point of ``ismb-lab``; returns the exit code.

    Run as the program (`argv` None), an interrupted run ends with ``os._exit`` once
    its output is flushed: a KeyboardInterrupt that passed through a C extension can
    leave CPython's "unhandled Ctrl-C" flag set, and the interpreter would then kill
    itself with SIGINT at exit instead of returning 130.
    """
    interrupts = Interrupts()
    with _closed_pipes_tolerated():
        code = _main(argv, interrupts)
    if argv is None and interrupts.signum is not None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


#: The commands that run the network, and so compile its kernels on their first run.
_COMPILING = frozenset({"match", "tune", "evaluate", "depth"})


def _announce_compiling() -> None:
    """One line on a terminal's stderr before numba compiles the network's kernels (the first run
    for this user, or after an upgrade): that run is silent for up to a minute otherwise.
    Not said when stderr is a file or a pipe, where a script reads what the command reports."""
    from .._kernel import _solve
    from .._numba import cold

    if sys.stderr.isatty() and cold(_solve):
        print("ismb-lab: compiling the network's kernels, once for this installation and user "
              "(up to a minute); later runs start at once", file=sys.stderr, flush=True)


def _main(argv, interrupts) -> int:
    usage_errors, args, running = (OutputError, OSError), None, False
    with interrupts:
        try:
            from ._common import ParameterError, ParameterTypeError, UsageError

            usage_errors += (UsageError, ParameterError, ParameterTypeError)
            args = build_parser().parse_args(argv)
            preflight(args, UsageError)
            running = True
            if args.command in _COMPILING:
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
                print(f"ismb-lab: error: {_cli_words(str(exc))}", file=sys.stderr)
            elif isinstance(exc, RecursionError):
                files = [f"{name} {str(getattr(args, name))!r}" for name in ("targets", "manifest")
                         if getattr(args, name, None) is not None]
                print(f"ismb-lab: error: {' or '.join(files) or 'an input file'}: its JSON is "
                      "nested too deeply to read", file=sys.stderr)
            elif isinstance(exc, MemoryError):
                print("ismb-lab: error: out of memory: the input is too large for this machine "
                      "(see the limits in 'ismb-lab --help')", file=sys.stderr)
            else:
                raise
    return 2
