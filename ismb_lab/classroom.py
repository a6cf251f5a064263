"""A class labelling the same pairs: a file per student, saves that lose nothing, pooling.

* :func:`targets_path` names each student's own targets file, from the user
  (``JUPYTERHUB_USER`` on a hub, else the login name) and the pair, so thirty
  students on one server never write the same file.
* :func:`save_merging` saves under a lock and merges with whatever another process
  saved since we last read the file (a three-way merge): nobody's pair is lost.
* :func:`pool` pools a class's files into one targets set and reports where the
  students disagree, and how each agrees with an answer key.

Pairs are compared by their coordinates (:mod:`ismb_lab.coords`), rounded to 1e-6 px.
"""

from __future__ import annotations

import contextlib
import fcntl
import getpass
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._validation import ParameterError, ParameterTypeError, message
from .targets import TargetSet, load_targets, save_targets

__all__ = ["Merged", "Pool", "pool", "save_merging", "targets_path", "user_name"]

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def user_name() -> str:
    """Who is labelling: ``JUPYTERHUB_USER`` on a JupyterHub, else the login name.

    Characters that do not belong in a file name are replaced by ``-``.
    """
    name = os.environ.get("JUPYTERHUB_USER") or getpass.getuser() or "student"
    return _UNSAFE.sub("-", name).strip("-.") or "student"


def targets_path(pair: str, folder=".", user: str | None = None) -> Path:
    """The default targets file of `user` (default :func:`user_name`) for `pair` in `folder`.

    >>> str(targets_path("synthetic", "work", user="ann lee"))
    'work/targets-ann-lee-synthetic.json'
    """
    if not isinstance(pair, str) or not pair:
        raise ParameterTypeError(message("pair", "targets_path", "a non-empty name of the image pair", pair))
    who = user_name() if user is None else _UNSAFE.sub("-", str(user)).strip("-.") or "student"
    return Path(folder) / f"targets-{who}-{_UNSAFE.sub('-', pair).strip('-.')}.json"


def _key(left, right) -> tuple:
    return tuple(np.round(np.concatenate([left, right]), 6).tolist())


def _keys(targets: TargetSet | None) -> dict:
    if targets is None:
        return {}
    return {_key(p, q): (p, q, e) for p, q, e in zip(targets.left_xy, targets.right_xy, targets.extras)}


@contextlib.contextmanager
def _locked(path: Path):
    """An exclusive lock beside `path` (``.name.lock``), released on exit."""
    lock = path.with_name(f".{path.name}.lock")
    with open(lock, "a+") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


@dataclass(frozen=True, eq=False)
class Merged:
    """What :func:`save_merging` wrote: the targets, and what it took from the file on disk."""

    targets: TargetSet
    kept_from_disk: int
    replaced: int


def save_merging(path, ours: TargetSet, base: TargetSet | None = None) -> Merged:
    """Save `ours` to `path`, keeping every change another process saved there meanwhile.

    Under a lock beside the file, the file as it is now ("theirs") is read and
    merged three ways with `base` (what we last loaded or saved; None when we
    never did): our additions and our deletions since `base` are applied to
    theirs.  A pair of theirs that uses one of our new pairs' points with another
    partner gives way to ours (counted in ``replaced``).  Top-level keys and
    per-pair extras of theirs survive.  The write is atomic.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "t.json"
    >>> a = save_merging(path, TargetSet([[10, 10]], [[5, 10]])).targets   # student A's first save
    >>> b = save_merging(path, TargetSet([[20, 20]], [[15, 20]])).targets   # B never read the file
    >>> b.left_xy.tolist()
    [[10.0, 10.0], [20.0, 20.0]]
    """
    path = Path(path)
    if not isinstance(ours, TargetSet):
        raise ParameterTypeError(message("ours", "save_merging", "a TargetSet", ours))
    if not path.parent.is_dir():
        raise ParameterError(f"The 'path' parameter of save_merging must be a file in an existing "
                             f"folder. Got {str(path)!r} instead.")
    with _locked(path):
        theirs = load_targets(path) if path.exists() else None
        if theirs is not None and any(a and b and a != b for a, b in (
                (theirs.left_sha256, ours.left_sha256), (theirs.right_sha256, ours.right_sha256))):
            raise ParameterError(f"The 'path' parameter of save_merging must be a targets file for the "
                                 f"same images. Got {str(path)!r}, which holds targets for other images "
                                 "(choose another file name)")
        mine, old, disk = _keys(ours), _keys(base), _keys(theirs)
        added = {k: v for k, v in mine.items() if k not in old}
        deleted = {k for k in old if k not in mine}
        taken_left = {tuple(np.round(v[0], 6)) for v in added.values()}
        taken_right = {tuple(np.round(v[1], 6)) for v in added.values()}
        result, replaced = {}, 0
        for k, (p, q, e) in disk.items():
            if k in deleted:
                continue
            if k not in added and (tuple(np.round(p, 6)) in taken_left or tuple(np.round(q, 6)) in taken_right):
                replaced += 1
                continue
            result[k] = (p, q, e)
        result.update({k: v for k, v in added.items() if k not in result})
        kept = sum(1 for k in result if k in disk and k not in mine)
        rows = list(result.values())
        meta = {**ours.meta, **(theirs.meta if theirs is not None else {})}
        merged = TargetSet(np.reshape([r[0] for r in rows], (-1, 2)), np.reshape([r[1] for r in rows], (-1, 2)),
                           ours.left_sha256 or (theirs and theirs.left_sha256),
                           ours.right_sha256 or (theirs and theirs.right_sha256),
                           meta=meta, extras=[r[2] for r in rows])
        save_targets(path, merged)
    return Merged(merged, kept, replaced)


@dataclass(frozen=True, eq=False)
class Pool:
    """A class's targets pooled by :func:`pool`.

    Attributes
    ----------
    targets : TargetSet
        One pair per left point that the students who labelled it agree on (a strict
        majority of them); each pair's extras say who labelled it.
    disagreements : list of dict
        Left points whose students named different partners, with each partner's votes.
    students : dict of str to dict
        Per file: its number of pairs and, with an answer key, how many of them are in
        the key (within ``tol`` px) and the share of the key it covers.
    """

    targets: TargetSet
    disagreements: list
    students: dict

    def report(self) -> str:
        lines = [f"{len(self.targets)} pooled pairs from {len(self.students)} files; "
                 f"{len(self.disagreements)} left points with disagreeing partners"]
        for name, s in self.students.items():
            extra = (f", {s['in_key']} of them in the answer key ({s['key_share']:.0%} of the key)"
                     if "in_key" in s else "")
            lines.append(f"  {name}: {s['pairs']} pairs{extra}")
        for d in self.disagreements:
            votes = "; ".join(f"{r} by {', '.join(who)}" for r, who in d["partners"].items())
            lines.append(f"  left {d['left_xy']}: {votes}")
        return "\n".join(lines)


def pool(paths, answer_key: TargetSet | None = None, tol: float = 1.5) -> Pool:
    """Pool the targets files of a class (all for the same two images).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> for who, right in (("ann", 5), ("bob", 5), ("cy", 7)):
    ...     _ = save_targets(folder / f"{who}.json", TargetSet([[10, 10]], [[right, 10]]))
    >>> p = pool(sorted(folder.glob("*.json")))
    >>> p.targets.right_xy.tolist(), len(p.disagreements)
    ([[5.0, 10.0]], 1)
    """
    paths = [Path(p) for p in paths]
    if not paths:
        raise ParameterError(message("paths", "pool", "one or more targets files", paths))
    sets = {str(p): load_targets(p) for p in paths}
    hashes = {(t.left_sha256, t.right_sha256) for t in sets.values()} - {(None, None)}
    if len(hashes) > 1:
        raise ParameterError(message("paths", "pool", "targets files for the same two images",
                                     f"files for {len(hashes)} different image pairs"))
    votes: dict = {}
    for name, t in sets.items():
        for p, q in zip(t.left_xy, t.right_xy):
            left, right = tuple(np.round(p, 6).tolist()), tuple(np.round(q, 6).tolist())
            votes.setdefault(left, {}).setdefault(right, []).append(Path(name).stem)
    lefts, rights, extras, disagreements = [], [], [], []
    for left, partners in votes.items():
        counts = sorted(((len(who), right) for right, who in partners.items()), reverse=True)
        labelled = sum(c for c, _ in counts)
        if len(partners) > 1:
            disagreements.append({"left_xy": list(left), "partners": {str(list(r)): who
                                                                      for r, who in partners.items()}})
        if counts[0][0] * 2 > labelled:
            lefts.append(left)
            rights.append(counts[0][1])
            extras.append({"labelled_by": partners[counts[0][1]], "of": labelled})
    first = next(iter(sets.values()))
    pooled = TargetSet(np.reshape(lefts, (-1, 2)), np.reshape(rights, (-1, 2)), first.left_sha256,
                       first.right_sha256, meta={"pooled_from": [Path(p).name for p in paths]},
                       extras=extras)
    students = {}
    for name, t in sets.items():
        s = {"pairs": len(t)}
        if answer_key is not None:
            hit = [bool(np.any((np.linalg.norm(answer_key.left_xy - p, axis=1) <= tol)
                               & (np.linalg.norm(answer_key.right_xy - q, axis=1) <= tol)))
                   for p, q in zip(t.left_xy, t.right_xy)]
            s["in_key"] = int(sum(hit))
            s["key_share"] = s["in_key"] / len(answer_key) if len(answer_key) else float("nan")
        students[Path(name).stem] = s
    return Pool(pooled, disagreements, students)
