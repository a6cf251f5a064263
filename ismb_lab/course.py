"""The nbgrader course: which notebooks make which assignment, and their generated source.

nbgrader hands assignments out from ``<course>/source/<assignment>/``.  That folder is
generated here from the repository's notebooks, which carry the nbgrader cell
metadata, and images; it is never a hand-edited copy:

    ismb-lab course source ~/course           # writes ~/course/source/labels/
    cd ~/course && nbgrader generate_assignment labels && nbgrader release_assignment labels

An assignment folder holds its notebooks and, under ``images/``, the image pairs they
open, so the fetched assignment (``~/labels/`` on a student's server) finds them
without the repository: :func:`course_images` looks beside the notebook first.  The
labeller saves ``targets-<user>-<pair>.json`` in the notebook's folder, so
``nbgrader submit`` hands it in and ``nbgrader collect`` gathers it into
``submitted/<student>/labels/``, which ``ismb-lab targets merge`` reads.
deploy/course/README.md has the teacher's steps.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from ._validation import ParameterError, ParameterTypeError, message

__all__ = ["ASSIGNMENTS", "Assignment", "course_images", "make_source", "repository"]


@dataclass(frozen=True)
class Assignment:
    """An nbgrader assignment: notebooks of ``notebooks/`` and pair folders of ``images/``."""

    notebooks: tuple
    images: tuple

    def __post_init__(self):
        for name in ("notebooks", "images"):
            value = getattr(self, name)
            if not isinstance(value, tuple) or not value or not all(isinstance(v, str) and v for v in value):
                raise ParameterTypeError(message(name, "Assignment", "a non-empty tuple of names", value))


#: The course's assignments, by nbgrader assignment id.
ASSIGNMENTS = {"labels": Assignment(("04_label_targets.ipynb",), ("synthetic",))}

#: Files of the repository's folders that never go into an assignment.
_SKIP = shutil.ignore_patterns(".ipynb_checkpoints", "targets-*.json", ".*.lock", "__pycache__")


def course_images(name: str, folder=".") -> Path:
    """The folder of image pair `name`: ``images/<name>`` beside the notebook (a fetched
    assignment) or ``../images/<name>`` (the repository and the course copy).

    >>> course_images("synthetic", "notebooks").as_posix()
    'notebooks/../images/synthetic'
    """
    if not isinstance(name, str) or not name or "/" in name:
        raise ParameterTypeError(message("name", "course_images", "the name of a folder of images/", name))
    tried = [Path(folder) / "images" / name, Path(folder) / ".." / "images" / name]
    for path in tried:
        if (path / "left.png").is_file():
            return path
    raise ParameterError(message("name", "course_images", "a pair in images/ beside the notebook or "
                                 "in ../images/", f"{name!r}, found in neither {tried[0]} nor {tried[1]}"))


def repository() -> Path:
    """The repository this package runs from (its ``notebooks/`` beside the package), else the
    current folder."""
    here = Path(__file__).resolve().parents[1]
    return here if (here / "notebooks").is_dir() else Path.cwd()


def _check_notebook(path: Path) -> None:
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    ids = [c.get("metadata", {}).get("nbgrader", {}).get("grade_id") for c in cells]
    if None in ids or len(set(ids)) != len(ids):
        raise ParameterError(f"The notebook {str(path)!r} must give every cell nbgrader metadata with a "
                             f"unique grade_id. Got {sum(i is None for i in ids)} cells without one instead.")


def make_source(course, assignment: str = "labels", repo=None) -> Path:
    """Write ``<course>/source/<assignment>/`` from the repository, replacing an older one.

    The folder is built beside its final place and renamed into it, so nbgrader never
    sees half of it.  Returns its path.

    >>> import tempfile
    >>> folder = make_source(tempfile.mkdtemp())
    >>> sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*.*"))[:3]
    ['04_label_targets.ipynb', 'images/synthetic/answer_key.json', 'images/synthetic/disparity.png']
    """
    if assignment not in ASSIGNMENTS:
        raise ParameterError(message("assignment", "make_source", f"one of {sorted(ASSIGNMENTS)}", assignment))
    repo = repository() if repo is None else Path(repo)
    spec = ASSIGNMENTS[assignment]
    sources = [repo / "notebooks" / n for n in spec.notebooks] + [repo / "images" / n for n in spec.images]
    missing = [str(p) for p in sources if not p.exists()]
    if missing:
        raise ParameterError(message("repo", "make_source", "the repository (its notebooks/ and images/)",
                                     f"{str(repo)!r}, without {missing[0]}"))
    for notebook in sources[:len(spec.notebooks)]:
        _check_notebook(notebook)
    parent = Path(course) / "source"
    parent.mkdir(parents=True, exist_ok=True)
    build = Path(tempfile.mkdtemp(prefix=f".{assignment}-", dir=parent))
    try:
        for notebook in sources[:len(spec.notebooks)]:
            shutil.copyfile(notebook, build / notebook.name)
        for pair in sources[len(spec.notebooks):]:
            shutil.copytree(pair, build / "images" / pair.name, ignore=_SKIP)
        build.chmod(0o755)
        final = parent / assignment
        if final.exists():
            old = parent / f".{assignment}.old"
            shutil.rmtree(old, ignore_errors=True)
            final.rename(old)
            build.rename(final)
            shutil.rmtree(old)
        else:
            build.rename(final)
    except BaseException:
        shutil.rmtree(build, ignore_errors=True)
        raise
    return final
