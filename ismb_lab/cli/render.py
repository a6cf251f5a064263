"""``ismb-lab render``: the project's rendered stereo pairs, byte for byte as in images/."""

from __future__ import annotations

from pathlib import Path

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    r = sub.add_parser("render", help="render the project's stereo pairs into images/",
                       description="Render the project's synthetic stereo pairs with their ground "
                       "truth. The output is byte for byte what is committed in images/.")
    r.add_argument("--out", type=Path, default=Path("images"), help="folder (default: images)")
    r.set_defaults(run=run)


def run(args) -> int:
    from ..gallery import render_gallery

    for path in render_gallery(args.out):
        print(path)
    return 0
