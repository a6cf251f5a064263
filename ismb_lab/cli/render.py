"""``ismb-lab render``: the project's rendered stereo pairs, byte for byte as in images/."""

from __future__ import annotations

from pathlib import Path

from ._guard import Files, UsageError

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """Add the ``render`` command: render the project's synthetic pairs into ``images/``."""
    r = sub.add_parser("render", help="render the project's stereo pairs into images/",
                       description="Render the project's synthetic stereo pairs with their ground "
                       "truth. The output is byte for byte what is committed in images/.")
    r.add_argument("--out", type=Path, default=Path("images"), help="folder (default: images)")
    r.set_defaults(run=run, declare_files=files)


def files(args):
    """Render reads nothing; its --out is a folder, whose files :func:`check_outputs` checks."""
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {str(out)!r} is not a folder")
    return Files()


def check_outputs(out: Path) -> None:
    """Before rendering: every file render writes is new or a regular, writable file, and every
    folder below `out` on the way is a real folder, not a link."""
    from .._core.files import OutputError, check_replace
    from ..scenes.gallery import gallery_files

    checked = set()
    for path in gallery_files(out):
        folders = [f for f in path.relative_to(out).parents if f != Path(".")]
        for folder in reversed(folders):
            if folder in checked:
                continue
            checked.add(folder)
            where = out / folder
            if where.is_symlink() or (where.exists() and not where.is_dir()):
                kind = "a symbolic link" if where.is_symlink() else "not a folder"
                raise OutputError(f"--out {str(where)!r} is {kind}; render writes only into real folders")
        check_replace(path, what="--out")


def run(args) -> int:
    """Render the gallery into ``args.out``; returns the exit code."""
    from ..scenes.gallery import render_gallery

    check_outputs(Path(args.out))
    for path in render_gallery(args.out):
        print(path)
    return 0
