"""``ismb-lab course source``: write the nbgrader course's ``source/`` from the notebooks."""

from __future__ import annotations

from pathlib import Path

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """Add the ``course`` command: write the nbgrader course's source folders from the notebooks."""
    from ..teaching.course import ASSIGNMENTS

    c = sub.add_parser("course", help="the nbgrader course (deploy/course/README.md)",
                       description="The nbgrader course of deploy/course/.")
    actions = c.add_subparsers(dest="action", metavar="ACTION", parser_class=type(c), required=True)
    s = actions.add_parser("source", help="write COURSE/source/ASSIGNMENT/ from the notebooks",
                           description="Write the course's source/<assignment>/ folder from the "
                           "repository's notebooks (which carry the nbgrader metadata) and images, "
                           "replacing an older one; then run 'nbgrader generate_assignment' and "
                           "'nbgrader release_assignment' in COURSE.")
    s.add_argument("course", type=Path, metavar="COURSE", help="the teacher's course folder")
    s.add_argument("--assignment", default="labels", choices=sorted(ASSIGNMENTS) + ["all"],
                   help="the assignment, or all of them (default: labels)")
    s.add_argument("--repo", type=Path, default=None,
                   help="the repository to take notebooks/ and images/ from (default: this package's)")
    s.set_defaults(run=run)


def run(args) -> int:
    """Write ``source/<assignment>/`` of the chosen assignments; returns the exit code."""
    from ..teaching.course import ASSIGNMENTS, make_source

    names = sorted(ASSIGNMENTS) if args.assignment == "all" else [args.assignment]
    for name in names:
        print(make_source(args.course, name, args.repo))
    return 0
