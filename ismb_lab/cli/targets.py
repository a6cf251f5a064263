"""``ismb-lab targets merge``: pool a class's targets files and report where students disagree."""

from __future__ import annotations

from pathlib import Path

from ._common import UsageError, given
from ._guard import Files, add_force_option, output_path

__all__ = ["add_parser", "run"]

MERGE_HELP = ("Pool the targets files of a class (all for the same two images), one vote per student. "
              "Give the files, or the one folder that 'nbgrader collect' filled (the course's "
              "submitted/ folder, or the course folder holding it): there the student is the name of "
              "their folder, and all the files a student handed in make one vote. A student's pairs "
              "that give a corner two partners get no vote. Files of different students that hold "
              "the same pairs are named, and (by default) such a file is one vote among them. A pair "
              "is kept when it has a strict majority of the votes on its left corner and of those on "
              "its right corner, and at least --min-votes votes. Prints every pair dropped, with its "
              "votes and why, and, with --answer-key, each student's agreement with the key.")


def add_parser(sub) -> None:
    """Add the ``targets`` command: work with targets files (``merge`` pools a class's labels)."""
    t = sub.add_parser("targets", help="work with targets files (merge a class's labels)",
                       description="Work with targets files as the labeller saves them.")
    actions = t.add_subparsers(dest="action", metavar="ACTION", parser_class=type(t), required=True)
    m = actions.add_parser("merge", help="pool several students' targets files into one",
                           description=MERGE_HELP)
    m.add_argument("files", type=Path, nargs="+", metavar="TARGETS.json|SUBMITTED/",
                   help="the students' files, or the folder 'nbgrader collect' filled")
    m.add_argument("--out", type=output_path, required=True, metavar="ALL.json",
                   help="where to write the pooled targets")
    m.add_argument("--answer-key", type=Path, default=None, metavar="KEY.json",
                   help="ground-truth targets of the same images (e.g. images/synthetic/answer_key.json)")
    m.add_argument("--min-votes", type=int, default=1, metavar="N",
                   help="votes a pair needs, on top of the strict majority of those cast on its "
                   "corners (default 1: students label different corners, so a floor would "
                   "drop the corners few of them found; raise it to 2 or 3 for a class)")
    m.add_argument("--identical-files", choices=("once", "each"), default="once",
                   help="how files of different students that hold the same pairs vote: 'once' (default): "
                   "such a file's pairs are one vote among those students, as for a copy; 'each': a vote "
                   "per student, when you know they labelled the same corners alike on their own. The "
                   "report names them either way")
    m.add_argument("--pattern", default="targets-*.json", metavar="GLOB",
                   help="the files to take from a collected folder (default 'targets-*.json'; "
                   "e.g. 'targets-*-synthetic.json' for one pair)")
    add_force_option(m)
    m.set_defaults(run=run, declare_files=files)


def files(args) -> Files:
    """The students' files (those a collected folder holds) and the answer key read; the pool written."""
    names, _ = _inputs(args)
    inputs = tuple(("a targets file", path) for path in names)
    return Files(inputs=inputs + given(("--answer-key", args.answer_key)), outputs=(("--out", args.out),))


def _inputs(args) -> tuple[list, object]:
    """The input files, and what ``pool`` takes (a list or, for a collected folder, ``{student: files}``)."""
    from ..labels.classroom import collected

    folders = [p for p in args.files if p.is_dir()]
    if not folders:
        if len(set(p.resolve() for p in args.files)) != len(args.files):
            raise UsageError("the same targets file is named twice")
        return list(args.files), list(args.files)
    if len(args.files) > 1:
        raise UsageError(f"give either targets files or one collected folder, not both "
                         f"({str(folders[0])!r} is a folder)")
    groups = collected(folders[0], args.pattern)
    return [p for group in groups.values() for p in group], groups


def run(args) -> int:
    """Pool the students' targets files into ``--out`` and print the report; returns the exit code."""
    from ..labels.classroom import pool
    from ..labels.targets import load_targets, save_targets

    if args.min_votes < 1:
        raise UsageError(f"--min-votes must be 1 or more, not {args.min_votes}")
    _, source = _inputs(args)
    key = None if args.answer_key is None else load_targets(args.answer_key)
    pooled = pool(source, answer_key=key, min_votes=args.min_votes, identical=args.identical_files)
    print(pooled.report())
    save_targets(args.out, pooled.targets)
    print(f"written to {args.out}")
    return 0
