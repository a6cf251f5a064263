"""``ismb-lab targets merge``: pool a class's targets files and report where students disagree."""

from __future__ import annotations

from pathlib import Path

from .._files import check_input, check_output
from ._common import UsageError

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    t = sub.add_parser("targets", help="work with targets files (merge a class's labels)",
                       description="Work with targets files as the labeller saves them.")
    actions = t.add_subparsers(dest="action", metavar="ACTION", parser_class=type(t))
    actions.required = True
    m = actions.add_parser("merge", help="pool several students' targets files into one",
                           description="Pool the targets files of a class (all for the same two images): "
                           "a left point's pair is kept when a strict majority of the students who "
                           "labelled it agree on its partner. Prints every disagreement and, with "
                           "--answer-key, each student's agreement with the key.")
    m.add_argument("files", type=Path, nargs="+", metavar="TARGETS.json", help="the students' files")
    m.add_argument("--out", type=Path, required=True, metavar="ALL.json", help="where to write the pooled targets")
    m.add_argument("--answer-key", type=Path, default=None, metavar="KEY.json",
                   help="ground-truth targets of the same images (e.g. images/synthetic/answer_key.json)")
    m.set_defaults(run=run)


def run(args) -> int:
    from ..classroom import pool
    from ..targets import load_targets, save_targets

    inputs = list(args.files) + ([args.answer_key] if args.answer_key is not None else [])
    for path in inputs:
        check_input(path, what="a targets file")
    check_output(args.out, inputs=inputs, force=getattr(args, "force", False), what="--out")
    if len(set(p.resolve() for p in args.files)) != len(args.files):
        raise UsageError("the same targets file is named twice")
    key = None if args.answer_key is None else load_targets(args.answer_key)
    pooled = pool(args.files, answer_key=key)
    print(pooled.report())
    save_targets(args.out, pooled.targets)
    print(f"written to {args.out}")
    return 0
