"""The ``ismb-lab`` command line.

Every error the user can cause prints one line on stderr and exits with code 2.
Each command is a module of this package with ``add_parser(subparsers)``, which
registers its options and its ``run(args) -> exit code``.
"""

from __future__ import annotations

import sys

from .. import __version__
from . import depth, evaluate, match, render, tune
from ._common import ParameterError, ParameterTypeError, Parser, UsageError

__all__ = ["COMMANDS", "UsageError", "build_parser", "main"]

#: The commands, in the order ``--help`` lists them.
COMMANDS = (match, tune, evaluate, depth, render)


def build_parser() -> Parser:
    parser = Parser(prog="ismb-lab", description="Hopfield-network stereo matching of Harris "
                    "corners (the ISMB thesis) from the command line.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    sub.required = True
    for command in COMMANDS:
        command.add_parser(sub)
    return parser


def main(argv=None) -> int:
    """Entry point of ``ismb-lab``; returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        return args.run(args)
    except UsageError as exc:
        print(f"ismb-lab: error: {exc}", file=sys.stderr)
    except (ParameterError, ParameterTypeError, OSError) as exc:
        print(f"ismb-lab: error: {exc}", file=sys.stderr)
    except KeyboardInterrupt:
        print("ismb-lab: interrupted", file=sys.stderr)
        return 130
    return 2
