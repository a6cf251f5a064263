"""A class labelling the same pairs: a file per student, saves that lose nothing, pooling.

:func:`targets_path` names each student's own file; :func:`save_merging` saves under a lock,
merging with what another process saved meanwhile; :func:`pool` pools a class's files, one
vote per student, and reports disagreements, dropped pairs and files handed in alike.  Pairs
are compared by their coordinates rounded to 1e-6 px.
"""

from __future__ import annotations

import contextlib
import fcntl
import getpass
import os
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_choice, check_number, message
from .targets import TargetSet, load_targets, save_targets

__all__ = ["collected", "Merged", "Pool", "pool", "save_merging", "SIBLINGS", "targets_path", "user_name",
           "voila_without_hub"]


def user_name() -> str:
    """Who is labelling: ``JUPYTERHUB_USER`` on a hub, else the login name, made safe for a file name.

    Returns
    -------
    name : str
        Letters, digits, ``.``, ``_`` and ``-`` only; ``"student"`` if nothing is left.
    """
    name = os.environ.get("JUPYTERHUB_USER") or getpass.getuser() or "student"
    return _safe(name) or "student"


def _safe(text: str) -> str:
    """`text` for a file name: each run of other characters than letters, digits, ``.``, ``_`` and
    ``-`` becomes one ``-``, and ``-`` and ``.`` are stripped from the ends (so it may be ``""``)."""
    return re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-.")


def voila_without_hub() -> bool:
    """Whether this kernel serves a Voilà page without a hub (Voilà sets ``SERVER_SOFTWARE``):
    one login for every visitor, so the login name does not say who is labelling."""
    return (os.environ.get("SERVER_SOFTWARE", "").startswith("voila")
            and not os.environ.get("JUPYTERHUB_USER"))


#: Where else a notebook looks for a targets file, relative to its folder: nbgrader's folder of
#: the assignment "labels" (notebook 04).
SIBLINGS = ("../labels",)


def targets_path(pair: str, folder=".", user: str | None = None, *, also=SIBLINGS) -> Path:
    """The targets file ``targets-<user>-<pair>.json`` of `user` (default :func:`user_name`).

    It is the file in `folder` if there is one, else the first in the folders `also` (relative
    to `folder`) that holds it, else the path in `folder`; ``also=()`` names what a save writes.

    Parameters
    ----------
    pair : str
        The image pair's name.
    folder : str or Path, default "."
        The notebook's folder.
    user : str, optional
        The student; default :func:`user_name`.
    also : tuple of str, default :data:`SIBLINGS`
        Other folders, relative to `folder`, to look in.

    Returns
    -------
    path : Path
        The targets file to read or write.

    Examples
    --------
    >>> str(targets_path("synthetic", "work", user="ann lee", also=()))
    'work/targets-ann-lee-synthetic.json'
    """
    if not isinstance(pair, str) or not pair:
        raise ParameterTypeError(message("pair", "targets_path", "a non-empty name of the image pair", pair))
    folders = tuple(also) if isinstance(also, (tuple, list)) else None
    if folders is None or not all(isinstance(f, (str, os.PathLike)) for f in folders):
        raise ParameterTypeError(message("also", "targets_path", "a tuple or list of folder names", also))
    who = user_name() if user is None else _safe(str(user)) or "student"
    name = f"targets-{who}-{_safe(pair)}.json"
    here = Path(folder) / name
    if here.is_file():
        return here
    return next((p for p in (Path(folder) / f / name for f in folders) if p.is_file()), here)


def _keys(targets: TargetSet | None) -> dict:
    if targets is None:
        return {}
    return {_point(p) + _point(q): (p, q, e) for p, q, e in zip(targets.left_xy, targets.right_xy, targets.extras)}


@contextlib.contextmanager
def _locked(path: Path):
    """An exclusive lock beside `path` (``.name.lock``, mode 0600, so that no other user can hold
    a student's lock), released on exit."""
    lock = path.with_name(f".{path.name}.lock")
    fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0),
                 0o600)
    with open(fd, "r+") as handle:
        info = os.fstat(fd)
        if info.st_uid == os.geteuid() and info.st_mode & 0o077:
            os.fchmod(fd, 0o600)
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

    Under a lock, the file as it is now ("theirs") is merged three ways with `base` (what we last
    loaded or saved, None if never): our additions and deletions since `base` are applied to
    theirs; a pair of theirs that gives one of our new pairs' points another partner gives way
    (counted in ``replaced``).  Their keys and extras survive; the write is atomic.

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
        taken_left = {_point(v[0]) for v in added.values()}
        taken_right = {_point(v[1]) for v in added.values()}
        result, replaced = {}, 0
        for k, (p, q, e) in disk.items():
            if k in deleted:
                continue
            if k not in added and (_point(p) in taken_left or _point(q) in taken_right):
                replaced += 1
                continue
            result[k] = (p, q, e)
        result.update({k: v for k, v in added.items() if k not in result})
        kept = sum(1 for k in result if k in disk and k not in mine)
        meta = {**ours.meta, **(theirs.meta if theirs is not None else {})}
        # An empty TargetSet is falsy, so theirs is tested against None.
        left, right = (None, None) if theirs is None else (theirs.left_sha256, theirs.right_sha256)
        merged = _from_rows(list(result.values()), ours.left_sha256 or left, ours.right_sha256 or right, meta)
        save_targets(path, merged)
    return Merged(merged, kept, replaced)


@dataclass(frozen=True, eq=False)
class Pool:
    """A class's targets pooled by :func:`pool`.

    `targets` holds the pairs with a strict majority of the votes at their left point and at
    their right point, and at least `min_votes` (extras ``labelled_by``, ``of``, and ``votes`` and
    ``identical`` where alike files voted once).  `disagreements` lists the left points given
    several partners, then the right points; `students` each student's ``pairs`` (``in_key``,
    ``key_share``, ``files``, ``many_to_one``, ``identical`` where they apply); `dropped` every
    pair handed in but not pooled, with its votes, voters, rivals and ``reasons`` (``"left"``,
    ``"right"``, ``"min_votes"``, ``"two_partners"``); `identical` the files of different students
    that hold the same pairs.
    """

    targets: TargetSet
    disagreements: list
    students: dict
    min_votes: int = 1
    dropped: list = field(default_factory=list)
    identical: list = field(default_factory=list)
    identical_votes: str = "once"

    def report(self) -> str:
        """The pool as text: counts, each student's line, identical files and dropped pairs."""
        files = sum(s.get("files", 1) for s in self.students.values())
        source = (f"{files} files" if files == len(self.students)
                  else f"{len(self.students)} students ({files} files)")
        lefts = sum("left_xy" in d for d in self.disagreements)
        rights = len(self.disagreements) - lefts
        lines = [f"{len(self.targets)} pooled pairs from {source}; "
                 f"{lefts} left points with disagreeing partners"
                 + (f"; {rights} right points given several left partners" if rights else "")
                 + (f"; at least {self.min_votes} votes per pair" if self.min_votes > 1 else "")
                 + (f"; {len(self.dropped)} pairs dropped" if self.dropped else "")]
        for name, s in self.students.items():
            extra = (f", {s['in_key']} of them in the answer key ({s['key_share']:.0%} of the key)"
                     if "in_key" in s else "")
            extra += (f"; {s['many_to_one']} pairs dropped: a corner given two partners"
                      if s.get("many_to_one") else "")
            lines.append(f"  {name}: {s['pairs']} pairs{extra}")
        how = "counted as one vote" if self.identical_votes == "once" else "each a vote"
        for g in self.identical:
            names = ", ".join(f"{who} ({Path(f).name})" for who, f in zip(g["students"], g["files"]))
            lines.append(f"  identical files, {how}: {names}; {g['pairs']} pairs")
        if self.dropped:
            lines.append("dropped pairs, each with its votes and why:")
        lines.extend(f"  {_dropped_line(d, self.min_votes)}" for d in self.dropped)
        return "\n".join(lines)


def _votes(n: int) -> str:
    return f"{n} vote" if n == 1 else f"{n} votes"


def _dropped_line(d: dict, min_votes: int) -> str:
    who = f" ({', '.join(d['voters'])})" if d["votes"] else ""
    why = []
    for side in ("left", "right"):
        if side in d["reasons"]:
            rivals = " and ".join(f"{_votes(r['votes'])} for {r['partner']} ({', '.join(r['voters'])})"
                                  for r in d[f"{side}_rivals"])
            why.append(f"its {side} corner has {rivals}")
    if "min_votes" in d["reasons"]:
        why.append(f"fewer than {_votes(min_votes)}")
    if "two_partners" in d["reasons"]:
        why.append(f"no vote from {', '.join(d['no_vote_from'])}, who gave one of its corners two partners")
    return f"{d['left_xy']} -> {d['right_xy']}, {_votes(d['votes'])}{who}: {'; '.join(why)}"


def collected(folder, pattern: str = "targets-*.json") -> dict:
    """The targets files of a collected class, by student: ``{student: [paths]}``.

    `folder` is nbgrader's ``submitted/`` (or the course folder holding it), a folder per student
    named by nbgrader, the files anywhere below.  Symbolic links are never followed.

    >>> import tempfile, pathlib
    >>> course = pathlib.Path(tempfile.mkdtemp())
    >>> for who in ("ann", "bob"):
    ...     (course / "submitted" / who / "labels").mkdir(parents=True)
    ...     _ = save_targets(course / "submitted" / who / "labels" / f"targets-{who}-lab.json",
    ...                      TargetSet([[1, 1]], [[0, 1]]))
    >>> {k: [p.name for p in v] for k, v in collected(course).items()}
    {'ann': ['targets-ann-lab.json'], 'bob': ['targets-bob-lab.json']}
    """
    root = Path(folder)
    if not root.is_dir():
        raise ParameterError(message("folder", "collected", "an existing folder", str(root)))
    if (root / "submitted").is_symlink():
        raise ParameterError(message("folder", "collected", "a course folder whose submitted/ is a folder of its "
                                     "own, not a symbolic link", str(root)))
    if (root / "submitted").is_dir():
        root = root / "submitted"
    found = {}
    # A link is never followed: a student's "folder" that links to / would otherwise vote
    # with every targets file on the machine.
    students = sorted(p for p in root.iterdir() if p.is_dir() and not p.is_symlink() and not p.name.startswith("."))
    for student in students:
        inside = os.path.realpath(student) + os.sep
        files = sorted(p for p in student.rglob(pattern) if p.is_file() and not p.is_symlink()
                       and not any(part.startswith(".") for part in p.relative_to(student).parts)
                       and os.path.realpath(p).startswith(inside))
        if files:
            found[student.name] = files
    if not found:
        raise ParameterError(message("folder", "collected", f"a folder of students' folders holding "
                                     f"{pattern!r} files", str(folder)))
    return found


def _point(xy) -> tuple:
    return tuple(np.round(xy, 6).tolist())


def _from_rows(rows, left_sha256, right_sha256, meta: dict) -> TargetSet:
    """The targets of `rows`, ``(left_xy, right_xy, extras)`` each."""
    left = [row[0] for row in rows]
    right = [row[1] for row in rows]
    extras = [row[2] for row in rows]
    return TargetSet(np.reshape(left, (-1, 2)), np.reshape(right, (-1, 2)), left_sha256, right_sha256,
                     meta=meta, extras=extras)


def _pairs(targets: TargetSet) -> list:
    return [(_point(p), _point(q)) for p, q in zip(targets.left_xy, targets.right_xy)]


def _ballot(targets: list) -> tuple[dict, set]:
    """One student's vote, ``({left: right}, the pairs left out)``: the union of their files'
    pairs, without a corner they gave two partners."""
    pairs = {pq for t in targets for pq in _pairs(t)}
    lefts = Counter(p for p, _ in pairs)
    rights = Counter(q for _, q in pairs)
    ballot = {p: q for p, q in sorted(pairs) if lefts[p] == 1 and rights[q] == 1}
    return ballot, {(p, q) for p, q in pairs if ballot.get(p) != q}


def _identical(groups: dict, sets: dict) -> list:
    """Files of different students holding the same pairs for the same images: one
    ``(students, files, pairs)`` per content, the first file of each student."""
    by_content = {}
    for name, group in groups.items():
        for path in group:
            t = sets[path]
            pairs = frozenset(_pairs(t))
            if pairs:
                by_content.setdefault((t.left_sha256, t.right_sha256, pairs), {}).setdefault(name, path)
    return sorted((list(holders), [holders[n] for n in holders], content[2])
                  for content, holders in by_content.items() if len(holders) > 1)


def _tally(who: list, pair: tuple, copies: list) -> list:
    """The votes on `pair` of the students `who`: lists of students, those holding one file with
    the pair (directly or through a chain of such files) in one list."""
    root = {n: n for n in who}

    def find(n):
        while root[n] != n:
            root[n] = root[root[n]]
            n = root[n]
        return n

    for students, _, pairs in copies:
        inside = [n for n in students if n in root] if pair in pairs else []
        for n in inside[1:]:
            root[find(n)] = find(inside[0])
    votes = {}
    for n in who:
        votes.setdefault(find(n), []).append(n)
    return list(votes.values())


def _disagreements(by_left: dict, by_right: dict) -> list:
    """Left points with disagreeing partners, then right points given several left partners."""
    lefts = [{"left_xy": list(p), "partners": {str(list(q)): who for q, who in partners.items()}}
             for p, partners in by_left.items() if len(partners) > 1]
    rights = [{"right_xy": list(q), "partners": {str(list(p)): who for p, who in partners.items()}}
              for q, partners in by_right.items() if len(partners) > 1]
    return lefts + rights


def pool(paths, answer_key: TargetSet | None = None, tol: float = 1.5, *, min_votes: int = 1,
         identical: str = "once") -> Pool:
    """Pool the targets files of a class (all for the same two images), one vote per student.

    `paths` is a dict of each student's files (e.g. :func:`collected`) or a list, which votes by
    file stem; `tol` is the answer key's tolerance, px; `min_votes` what a pair needs on top of a
    strict majority; `identical` whether a file students handed in alike is one vote among them
    (``"once"``) or one each.

    Two files are alike when they hold the same set of pairs (to 1e-6 px) for the same images.
    Equal bytes would miss the easiest copy (another's file loaded and saved again, its pairs
    sorted) and would catch honest students who save the same pairs once.  Students who label
    exactly alike on their own lose one vote between them, which matters only where others
    dispute those pairs; the report names them.

    Parameters
    ----------
    paths : dict of str to list of path, or list of path
        Each student's targets files, or files voting by stem.
    answer_key : TargetSet, optional
        The teacher's pairs; each student's share of it is reported.
    tol : float, default 1.5
        The answer key's tolerance, px.
    min_votes : int, default 1
        Votes a pair needs on top of a strict majority.
    identical : {"once", "each"}, default "once"
        Whether alike files vote once between them or once each.

    Returns
    -------
    pooled : Pool
        The pooled targets, disagreements, per-student counts and dropped pairs.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> ann = save_targets(folder / "ann.json", TargetSet([[10, 10], [20, 20]], [[5, 10], [15, 20]]))
    >>> bob = save_targets(folder / "bob.json", TargetSet([[10, 10]], [[5, 10]]))
    >>> cy = save_targets(folder / "cy.json", TargetSet([[10, 10]], [[7, 10]]))
    >>> p = pool([ann, bob, cy])
    >>> p.targets.right_xy.tolist(), len(p.disagreements)
    ([[5.0, 10.0], [15.0, 20.0]], 1)
    >>> p.dropped[0]["right_xy"], p.dropped[0]["reasons"], p.dropped[0]["left_rivals"][0]["labelled_by"]
    ([7.0, 10.0], ['left'], ['ann', 'bob'])
    >>> len(pool([ann, bob, cy], min_votes=2).targets)
    1

    A copy of ann's file handed in as dee's is named, and votes once with ann's:

    >>> dee = folder / "dee.json"
    >>> _ = dee.write_bytes(ann.read_bytes())
    >>> p = pool([ann, bob, cy, dee])
    >>> p.identical[0]["students"], p.targets.extras[0]
    (['ann', 'dee'], {'labelled_by': ['ann', 'bob', 'dee'], 'of': 3, 'votes': 2, 'identical': [['ann', 'dee']]})
    """
    min_votes = check_number(min_votes, "min_votes", "pool", low=1, integer=True)
    identical = check_choice(identical, "identical", "pool", ("once", "each"))
    if isinstance(paths, dict):
        groups = {str(k): [Path(p) for p in v] for k, v in paths.items()}
    else:
        groups = {}
        for p in map(Path, paths):
            groups.setdefault(p.stem, []).append(p)
    files = [p for group in groups.values() for p in group]
    if not files or not all(groups.values()):
        raise ParameterError(message("paths", "pool", "one or more targets files", paths))
    sets = {p: load_targets(p) for p in files}
    hashes = {(t.left_sha256, t.right_sha256) for t in sets.values()} - {(None, None)}
    if len(hashes) > 1:
        raise ParameterError(message("paths", "pool", "targets files for the same two images",
                                     f"files for {len(hashes)} different image pairs"))
    copies = _identical(groups, sets)
    by_left, by_right, students, handed = {}, {}, {}, {}
    for name, group in groups.items():
        ballot, left_out = _ballot([sets[p] for p in group])
        for left, right in ballot.items():
            by_left.setdefault(left, {}).setdefault(right, []).append(name)
            by_right.setdefault(right, {}).setdefault(left, []).append(name)
        for pair in sorted({pq for p in group for pq in _pairs(sets[p])}):
            handed.setdefault(pair, []).append(name)
        students[name] = _student(ballot, answer_key, tol)
        students[name].update({"files": len(group)} if len(group) > 1 else {})
        students[name].update({"many_to_one": len(left_out)} if left_out else {})
        same = sorted({n for who, _, _ in copies if name in who for n in who} - {name})
        students[name].update({"identical": same} if same else {})
    votes = {(p, q): _tally(who, (p, q), copies if identical == "once" else [])
             for p, partners in by_left.items() for q, who in partners.items()}
    left_votes = {p: sum(len(votes[p, q]) for q in partners) for p, partners in by_left.items()}
    right_votes = {q: sum(len(votes[p, q]) for p in partners) for q, partners in by_right.items()}
    rows, kept = [], set()
    for left, partners in by_left.items():
        for right, who in partners.items():
            n = len(votes[left, right])
            if n >= min_votes and 2 * n > left_votes[left] and 2 * n > right_votes[right]:
                extras = {"labelled_by": who, "of": left_votes[left]}
                if n < len(who):
                    extras.update(votes=n, identical=[v for v in votes[left, right] if len(v) > 1])
                rows.append((left, right, extras))
                kept.add((left, right))
    first = next(iter(sets.values()))
    pooled = _from_rows(rows, first.left_sha256, first.right_sha256,
                        {"pooled_from": [str(p.name) for p in files], "min_votes": min_votes})
    dropped = [_why(pair, who, votes, by_left, by_right, left_votes, right_votes, min_votes)
               for pair, who in sorted(handed.items()) if pair not in kept]
    found = [{"students": who, "files": [str(f) for f in paths], "pairs": len(pairs)}
             for who, paths, pairs in copies]
    return Pool(pooled, _disagreements(by_left, by_right), students, min_votes, dropped, found, identical)


def _why(pair, handed_by, votes, by_left, by_right, left_votes, right_votes, min_votes) -> dict:
    """Why a pair handed in is not pooled, with the votes of its corners' other partners."""
    (p, q), mine = pair, votes.get(pair, [])
    n = len(mine)

    def rivals(others, own, key):
        return [{"partner": list(o), "votes": len(votes[key(o)]), "labelled_by": who,
                 "voters": ["+".join(v) for v in votes[key(o)]]} for o, who in others.items() if o != own]

    voted = {name for v in mine for name in v}
    d = {"left_xy": list(p), "right_xy": list(q), "votes": n, "labelled_by": [w for w in handed_by if w in voted],
         "reasons": [], "left_rivals": rivals(by_left.get(p, {}), q, lambda o: (p, o)),
         "right_rivals": rivals(by_right.get(q, {}), p, lambda o: (o, q)),
         "no_vote_from": [w for w in handed_by if w not in voted], "voters": ["+".join(v) for v in mine]}
    if n:
        d["reasons"] += ["left"] if 2 * n <= left_votes[p] else []
        d["reasons"] += ["right"] if 2 * n <= right_votes[q] else []
        d["reasons"] += ["min_votes"] if n < min_votes else []
    d["reasons"] += ["two_partners"] if d["no_vote_from"] else []
    return d


def _student(ballot: dict, answer_key: TargetSet | None, tol: float) -> dict:
    s = {"pairs": len(ballot)}
    if answer_key is not None:
        hit = [bool(np.any((np.linalg.norm(answer_key.left_xy - np.asarray(p), axis=1) <= tol)
                           & (np.linalg.norm(answer_key.right_xy - np.asarray(q), axis=1) <= tol)))
               for p, q in ballot.items()]
        s["in_key"] = int(sum(hit))
        s["key_share"] = s["in_key"] / len(answer_key) if len(answer_key) else float("nan")
    return s
