"""The nbgrader course: which notebooks make which assignment, and their generated source.

``<course>/source/<assignment>/`` is generated here from the repository's notebooks (which carry
the nbgrader cell metadata) and images, never hand-edited; deploy/course/README.md has the
teacher's steps.  A notebook's ``../images/`` and ``../manifests/`` become the assignment's own
``images/`` and ``manifests/``, in its code and in the commands its text prints, so that they work
in the notebook's own folder, the repository's ``notebooks/`` or the assignment's.
"""

from __future__ import annotations

import json
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from .._core.validation import ParameterError, ParameterTypeError, message

__all__ = ["ASSIGNMENTS", "Assignment", "CODE_STUB", "course_images", "make_source", "repository",
           "student_notebook"]


@dataclass(frozen=True)
class Assignment:
    """An nbgrader assignment: notebooks of ``notebooks/`` and pair folders of ``images/``
    (besides those its notebooks name as ``../images/<folder>``)."""

    notebooks: tuple
    images: tuple = ()

    def __post_init__(self):
        for name in ("notebooks", "images"):
            value = getattr(self, name)
            if not isinstance(value, tuple) or (name == "notebooks" and not value) \
                    or not all(isinstance(v, str) and v for v in value):
                raise ParameterTypeError(message(name, "Assignment", "a tuple of names (notebooks: "
                                                 "not empty)", value))


#: The course's assignments by nbgrader id: the labels, and one per notebook with checked exercises.
ASSIGNMENTS = {
    "labels": Assignment(("04_label_targets.ipynb",), ("synthetic",)),
    "00-start": Assignment(("00_start_here.ipynb",)),
    "01-harris": Assignment(("01_harris_features.ipynb",)),
    "02-hopfield": Assignment(("02_hopfield_network.ipynb",)),
    "03-methods": Assignment(("03_methods_compared.ipynb",)),
    "05-explorer": Assignment(("05_parameter_explorer.ipynb",)),
    "06-genetic": Assignment(("06_genetic_algorithm.ipynb",)),
    "07-depth": Assignment(("07_toy_car_depth.ipynb",)),
    "08-peers": Assignment(("08_real_data_and_peers.ipynb",)),
}

#: What replaces a code solution in the student version: a comment, so the cell's first try still runs.
CODE_STUB = "# YOUR CODE HERE"
#: The folders of the repository a notebook reaches with ``../``, copied into an assignment.
_SHARED = ("images", "manifests")

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
    """The repository this package runs from (with ``notebooks/``), else the current folder."""
    here = Path(__file__).resolve().parents[1]
    return here if (here / "notebooks").is_dir() else Path.cwd()


def _check_notebook(path: Path, every_cell: bool) -> dict:
    """The notebook at `path`, refused unless its nbgrader cells (all cells when `every_cell`)
    have unique grade_ids and at least one cell is graded."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    ids = [c.get("metadata", {}).get("nbgrader", {}).get("grade_id") for c in nb["cells"]]
    named = [i for i in ids if i is not None]
    if (every_cell and None in ids) or not named or len(set(named)) != len(named):
        raise ParameterError(f"The notebook {str(path)!r} must give {'every' if every_cell else 'each graded'} "
                             f"cell nbgrader metadata with a unique grade_id. Got {len(named)} cells with one "
                             f"({len(named) - len(set(named))} repeated), {sum(i is None for i in ids)} without.")
    return nb


#: A path into a shared folder in a markdown cell (a printed command): ``../images/<name>``.
_TEXT_PATH = re.compile(rf"""(?<![\w./-])\.\./({'|'.join(_SHARED)})/([^/\s`'"()]*)""")


def _references(nb: dict) -> dict:
    """``{"images": {...}, "manifests": {...}}``: what the code cells open with ``../<folder>/<name>``
    and the markdown cells' commands name so."""
    code = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    text = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")
    found = {part: set(re.findall(rf"""["']\.\./{part}/([^/"']+)""", code)) for part in _SHARED}
    for part, name in _TEXT_PATH.findall(text):
        if name:
            found[part].add(name)
    return found


def _local_paths(nb: dict) -> bool:
    """Make the ``../images/`` and ``../manifests/`` paths of the cells the assignment's own;
    True if anything changed."""
    changed = False
    for cell in nb["cells"]:
        source = "".join(cell["source"])
        if cell["cell_type"] == "code":
            new = re.sub(rf"""(["'])\.\./({'|'.join(_SHARED)})/""", r"\1\2/", source)
        elif cell["cell_type"] == "markdown":
            new = _TEXT_PATH.sub(r"\1/\2", source)
        else:
            continue
        if new != source:
            cell["source"], changed = new, True
    return changed


def student_notebook(nb):
    """The student version of notebook `nb` (an nbformat NotebookNode, changed in place), as
    ``nbgrader generate_assignment`` writes it: solutions replaced by :data:`CODE_STUB` or ``YOUR ANSWER
    HERE``, hidden tests removed.  Needs nbgrader (``[course]``)."""
    from nbgrader.preprocessors import ClearHiddenTests, ClearSolutions

    nb, resources = ClearSolutions(code_stub={"python": CODE_STUB}).preprocess(nb, {})
    return ClearHiddenTests().preprocess(nb, resources)[0]


def _existing(repo: Path, paths: list) -> list:
    missing = [str(p) for p in paths if not p.exists()]
    if missing:
        raise ParameterError(message("repo", "make_source", "the repository (its notebooks/ and images/)",
                                     f"{str(repo)!r}, without {missing[0]}"))
    return paths


def make_source(course, assignment: str = "labels", repo=None) -> Path:
    """Write ``<course>/source/<assignment>/`` from the repository, replacing an older one; returns it.

    The folder is built beside its final place and renamed into it, so nbgrader never sees half of it.

    >>> import tempfile
    >>> folder = make_source(tempfile.mkdtemp())
    >>> sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*.*"))[:3]
    ['04_label_targets.ipynb', 'images/synthetic/answer_key.json', 'images/synthetic/disparity.png']
    >>> folder = make_source(folder.parents[1], "03-methods")
    >>> sorted(p.name for p in folder.iterdir())
    ['03_methods_compared.ipynb', 'images']
    """
    if assignment not in ASSIGNMENTS:
        raise ParameterError(message("assignment", "make_source", f"one of {sorted(ASSIGNMENTS)}", assignment))
    repo = repository() if repo is None else Path(repo)
    spec = ASSIGNMENTS[assignment]
    notebooks = _existing(repo, [repo / "notebooks" / n for n in spec.notebooks])
    loaded = [_check_notebook(p, every_cell=assignment == "labels") for p in notebooks]
    shared = {"images": set(spec.images), "manifests": set()}
    for nb in loaded:
        for part, names in _references(nb).items():
            shared[part] |= names
    copies = _existing(repo, [repo / part / name for part in _SHARED for name in sorted(shared[part])])
    parent = Path(course) / "source"
    parent.mkdir(parents=True, exist_ok=True)
    build = Path(tempfile.mkdtemp(prefix=f".{assignment}-", dir=parent))
    try:
        for path, nb in zip(notebooks, loaded):
            if _local_paths(nb):
                (build / path.name).write_text(json.dumps(nb, indent=1, ensure_ascii=False) + "\n",
                                               encoding="utf-8")
            else:
                shutil.copyfile(path, build / path.name)
        for source in copies:
            target = build / source.parent.name / source.name
            target.parent.mkdir(exist_ok=True)
            if source.is_dir():
                shutil.copytree(source, target, ignore=_SKIP)
            else:
                shutil.copyfile(source, target)
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
