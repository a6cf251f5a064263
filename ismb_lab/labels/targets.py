"""Target pairs: hand-labelled left/right points, their file, and snapping to features.

Targets are ``(x, y)`` coordinates, never feature indices (:func:`snap` makes those).  The file::

    {"version": 1, "left_image_sha256": "...", "right_image_sha256": "...",  (optional)
     "orientation": "upright",
     "pairs": [{"left_xy": [x, y], "right_xy": [x, y]}, ...]}

``"upright"``: clicked on the photos turned by their EXIF orientation, as the loaders show
them; a file without it predates that, and is refused for a photo its tag turns.  Other keys
(top-level and per pair) survive a load and a save.  :data:`MAX_PAIRS` and :data:`MAX_BYTES`
are checked before parsing (a class's pool holds a few thousand pairs).
"""

from __future__ import annotations

import copy
import json
import math
import numbers
import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .._core.files import atomic_write_text
from .._core.validation import ParameterError, ParameterTypeError, check_number, check_points, message
from ..images.io import StereoPair

__all__ = ["MAX_BYTES", "MAX_PAIRS", "VERSION", "check_one_to_one", "load_targets", "many_to_one", "save_targets",
           "snap", "Snapped", "targets_from_matches", "TargetSet"]

VERSION = 1
#: Most pairs in a targets file or a :meth:`TargetSet.from_dict` object.
MAX_PAIRS = 10_000
#: Most bytes of a targets file: 10,000 pairs with a few extra keys each.
MAX_BYTES = 4 << 20
_HASHES = ("left_image_sha256", "right_image_sha256")
_POINTS = ("left_xy", "right_xy")
_ORIENTATIONS = ("upright", "as stored")
_RESERVED = ("version", "pairs", "orientation") + _HASHES
_HEX = re.compile(r"[0-9a-fA-F]{64}")
_SHORT_LIST = re.compile(r"\[\s+([^\s,\[\]{}\"]+),\s+([^\s,\[\]{}\"]+)\s+\]")


def _hash(value, name, owner):
    if value is not None and not (isinstance(value, str) and _HEX.fullmatch(value)):
        kind = ParameterError if isinstance(value, str) else ParameterTypeError
        raise kind(message(name, owner, "None or a SHA-256 hex digest (64 hex characters)", value))
    return value and value.lower()


def _json_dict(value, name, owner, reserved):
    rule = "a dict of JSON values without the keys " + ", ".join(map(repr, reserved))
    if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
        raise ParameterTypeError(message(name, owner, rule, value))
    if any(k in value for k in reserved):
        raise ParameterError(message(name, owner, rule, value))
    try:
        return json.loads(json.dumps(value, allow_nan=False))   # a deep, JSON-only copy
    except (TypeError, ValueError):
        raise ParameterTypeError(message(name, owner, rule, value)) from None


def _xy(value, name, owner) -> list[float]:
    rule = "an [x, y] list of 2 finite numbers >= 0"
    value = value.tolist() if isinstance(value, np.ndarray) else value
    if not isinstance(value, (list, tuple)) or not all(
            isinstance(v, numbers.Real) and not isinstance(v, bool) for v in value):
        raise ParameterTypeError(message(name, owner, rule, value))
    try:
        xy = [float(v) for v in value]
    except OverflowError:   # an int of hundreds of digits
        raise ParameterError(message(name, owner, rule, value)) from None
    if len(xy) != 2 or not all(math.isfinite(v) and v >= 0 for v in xy):
        raise ParameterError(message(name, owner, rule, value))
    return xy


def _check_unique(left_xy, right_xy, owner) -> None:
    """A pair listed twice would count twice in every score (and a GA could never reach it)."""
    rows = np.hstack([np.reshape(left_xy, (-1, 2)), np.reshape(right_xy, (-1, 2))])
    _, first, counts = np.unique(rows, axis=0, return_index=True, return_counts=True)
    if (counts > 1).any():
        j = int(np.sort(first[counts > 1])[0])
        again = int(np.flatnonzero((rows == rows[j]).all(axis=1))[1])
        raise ParameterError(message("pairs", owner, "a list that holds each pair once",
                                     f"pairs[{j}] repeated as pairs[{again}]"))


def _plain(xy) -> list:
    return [int(v) if float(v).is_integer() else float(v) for v in np.asarray(xy).tolist()]


def _set(obj, name, value):
    if isinstance(value, np.ndarray):
        value.setflags(write=False)
    object.__setattr__(obj, name, value)


@dataclass(frozen=True, eq=False)
class TargetSet:
    """Target pairs ``left_xy[j] <-> right_xy[j]``; immutable, methods return new sets.

    Attributes
    ----------
    left_xy, right_xy : (m, 2) float ndarray
        Read-only ``(x, y)`` points >= 0, each pair at most once.
    left_sha256, right_sha256 : str or None
        The images' SHA-256 hashes, or None.
    meta : dict
        The file's other top-level keys (JSON values).
    extras : tuple of dict
        Other keys per pair; None when built means all empty.
    orientation : {"upright", "as stored"}, default "upright"
        Whether the points were clicked on photos with their EXIF orientation applied.

    Examples
    --------
    >>> t = TargetSet([[99, 99]], [[88, 100]], meta={"labeller": "ann"})
    >>> len(t), t.left_xy.tolist(), t.extras
    (1, [[99.0, 99.0]], ({},))
    """

    left_xy: np.ndarray
    right_xy: np.ndarray
    left_sha256: str | None = None
    right_sha256: str | None = None
    meta: dict = field(default_factory=dict)
    extras: tuple | None = None
    orientation: str = "upright"

    def __post_init__(self):
        owner = "TargetSet"
        if self.orientation not in _ORIENTATIONS:
            raise ParameterError(message("orientation", owner, "'upright' or 'as stored'", self.orientation))
        for name in _POINTS:
            xy = check_points(getattr(self, name), name, owner).copy()
            if (xy < 0).any():
                raise ParameterError(message(name, owner, "an (m, 2) array of (x, y) points >= 0",
                                             f"the point {xy[(xy < 0).any(axis=1)][0].tolist()}"))
            _set(self, name, xy)
        m = len(self.left_xy)
        if len(self.right_xy) != m:
            raise ParameterError(message("right_xy", owner, f"{m} points, one per left point",
                                         f"{len(self.right_xy)} points"))
        _check_unique(self.left_xy, self.right_xy, owner)
        for name in ("left_sha256", "right_sha256"):
            _set(self, name, _hash(getattr(self, name), name, owner))
        _set(self, "meta", _json_dict(self.meta, "meta", owner, _RESERVED))
        extras = [{}] * m if self.extras is None else self.extras
        if not isinstance(extras, (tuple, list)) or len(extras) != m:
            raise ParameterError(message("extras", owner, f"None or {m} dicts, one per pair", extras))
        _set(self, "extras", tuple(_json_dict(e, f"extras[{j}]", owner, _POINTS)
                                   for j, e in enumerate(extras)))

    def __len__(self) -> int:
        return len(self.left_xy)

    def add(self, left_xy, right_xy, **extra) -> "TargetSet":
        """A new set with the pair ``left_xy <-> right_xy`` (and `extra` keys) appended.

        >>> t = TargetSet([[1, 2]], [[0, 2]])
        >>> len(t.add([5, 6], [4, 6], note="corner")), len(t)
        (2, 1)
        """
        p, q = (_xy(v, n, "TargetSet.add") for v, n in zip((left_xy, right_xy), _POINTS))
        return replace(self, left_xy=np.vstack([self.left_xy, [p]]),
                       right_xy=np.vstack([self.right_xy, [q]]), extras=self.extras + (extra,))

    def remove(self, index) -> "TargetSet":
        """A new set without pair `index` (0-based; negative indices are refused).

        >>> TargetSet([[1, 2], [5, 6]], [[0, 2], [4, 6]]).remove(0).left_xy.tolist()
        [[5.0, 6.0]]
        """
        j = check_number(index, "index", "TargetSet.remove", low=0, high=len(self) - 1, integer=True)
        keep = np.arange(len(self)) != j
        return replace(self, left_xy=self.left_xy[keep], right_xy=self.right_xy[keep],
                       extras=self.extras[:j] + self.extras[j + 1:])

    def to_dict(self) -> dict:
        """The file's JSON object (integral coordinates as integers, no hash key for None).

        Returns
        -------
        d : dict
            ``version``, hashes, ``orientation``, `meta` and ``pairs``.

        Examples
        --------
        >>> TargetSet([[1, 2.5]], [[0, 2.5]]).to_dict()
        {'version': 1, 'orientation': 'upright', 'pairs': [{'left_xy': [1, 2.5], 'right_xy': [0, 2.5]}]}
        """
        d = {"version": VERSION}
        d.update({k: h for k, h in zip(_HASHES, (self.left_sha256, self.right_sha256)) if h})
        if self.orientation == "upright":      # a file without the key is "as stored"
            d["orientation"] = self.orientation
        d.update(copy.deepcopy(self.meta))
        d["pairs"] = [{"left_xy": _plain(p), "right_xy": _plain(q), **copy.deepcopy(e)}
                      for p, q, e in zip(self.left_xy, self.right_xy, self.extras)]
        return d

    @classmethod
    def from_dict(cls, d, *, source: str = "TargetSet.from_dict") -> "TargetSet":
        """Read the file's JSON object; errors name `source` and the key (pairs from 0).

        >>> TargetSet.from_dict({"version": 1, "pairs": [{"left_xy": [1, 2], "right_xy": [0, "2"]}]})
        Traceback (most recent call last):
        ismb_lab.ParameterTypeError: The 'pairs[0].right_xy' parameter of TargetSet.from_dict must be
        an [x, y] list of 2 finite numbers >= 0. Got [0, '2'] instead.
        """
        if not isinstance(d, dict):
            raise ParameterTypeError(message("d", source, "a dict (a JSON object)", d))
        version = d.get("version", "no 'version' key")
        if type(version) is not int or version != VERSION:
            raise ParameterError(message("version", source, f"{VERSION}", version))
        pairs = d.get("pairs", "no 'pairs' key")
        if not isinstance(pairs, list):
            raise ParameterTypeError(message("pairs", source, "a list of objects", pairs))
        if len(pairs) > MAX_PAIRS:
            raise ParameterError(message("pairs", source, f"a list of at most {MAX_PAIRS} pairs",
                                         f"{len(pairs)} pairs"))
        xy, rule = {k: [] for k in _POINTS}, "an object with 'left_xy' and 'right_xy' keys"
        for j, item in enumerate(pairs):
            if not isinstance(item, dict) or not all(k in item for k in _POINTS):
                kind = ParameterError if isinstance(item, dict) else ParameterTypeError
                raise kind(message(f"pairs[{j}]", source, rule, item))
            for key in _POINTS:
                xy[key].append(_xy(item[key], f"pairs[{j}].{key}", source))
        _check_unique(xy["left_xy"], xy["right_xy"], source)
        orientation = d.get("orientation", "as stored")
        if orientation not in _ORIENTATIONS:
            raise ParameterError(message("orientation", source, "'upright' or 'as stored'", orientation))
        return cls(np.reshape(xy["left_xy"], (-1, 2)), np.reshape(xy["right_xy"], (-1, 2)),
                   *(_hash(d.get(k), k, source) for k in _HASHES),
                   meta={k: v for k, v in d.items() if k not in _RESERVED},
                   extras=[{k: v for k, v in p.items() if k not in _POINTS} for p in pairs],
                   orientation=orientation)


def _path(path, owner) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise ParameterTypeError(message("path", owner, "a str or os.PathLike file path", path))
    return Path(path)


def _path_error(path, owner, rule) -> ParameterError:
    # The shared message() shortens long values, but a path is only useful whole.
    return ParameterError(f"The 'path' parameter of {owner} must be {rule}. Got {str(path)!r} instead.")


def save_targets(path, targets: TargetSet) -> Path:
    """Write `targets` as pretty JSON ending in a newline, atomically (temp file, fsync, rename).

    Parameters
    ----------
    path : str or os.PathLike
        The file, in an existing folder.
    targets : TargetSet
        The pairs to save.

    Returns
    -------
    path : Path
        The file written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = save_targets(pathlib.Path(tempfile.mkdtemp()) / "t.json", TargetSet([[1, 2]], [[0, 2]]))
    >>> path.read_text().splitlines()[5]
    '      "left_xy": [1, 2],'
    """
    path = _path(path, "save_targets")
    if not isinstance(targets, TargetSet):
        raise ParameterTypeError(message("targets", "save_targets", "a TargetSet", targets))
    if not path.parent.is_dir():
        raise _path_error(path, "save_targets", "a file in an existing folder")
    text = _SHORT_LIST.sub(r"[\1, \2]", json.dumps(targets.to_dict(), indent=2, allow_nan=False))
    return atomic_write_text(path, text + "\n")


def load_targets(path, *, pair: StereoPair | None = None, shape=None,
                 check_hash: bool = True) -> TargetSet:
    """Read and check a targets file: its points must lie in an image of `shape` ``(H, W)`` and
    of `pair`, whose hashes must be the file's (if it has any) unless not `check_hash`.

    Parameters
    ----------
    path : str or os.PathLike
        The targets JSON file, at most :data:`MAX_BYTES`.
    pair : StereoPair, optional
        The images the targets belong to: their size and hashes are checked.
    shape : (H, W) tuple of int, optional
        An image size the points must lie in.
    check_hash : bool, default True
        Refuse targets whose hashes are not `pair`'s.

    Returns
    -------
    targets : TargetSet
        The checked pairs.

    Raises
    ------
    ParameterError
        An unreadable or invalid file, other images' hashes, or points outside the image.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = save_targets(pathlib.Path(tempfile.mkdtemp()) / "t.json", TargetSet([[9, 2]], [[7, 2]]))
    >>> len(load_targets(path, shape=(10, 10)))
    1
    >>> load_targets(path, shape=(5, 5))
    Traceback (most recent call last):
    ismb_lab.ParameterError: The 'pairs[0].left_xy' parameter of the targets file '...' must be inside
    the 5x5 (width x height) image (0 <= x <= 4, 0 <= y <= 4). Got [9, 2] instead.
    """
    owner = "load_targets"
    path = _path(path, owner)
    if not isinstance(check_hash, bool):
        raise ParameterTypeError(message("check_hash", owner, "True or False", check_hash))
    if pair is not None and not isinstance(pair, StereoPair):
        raise ParameterTypeError(message("pair", owner, "None or a StereoPair", pair))
    if shape is not None:
        rule = "None or a (height, width) pair of integers >= 1"
        if isinstance(shape, (str, bytes)) or not hasattr(shape, "__len__") or len(shape) != 2:
            raise ParameterTypeError(message("shape", owner, rule, shape))
        shape = tuple(check_number(v, "shape", owner, low=1, integer=True) for v in shape)
    try:
        with open(path, "rb") as handle:   # at most one byte more than allowed
            raw = handle.read(MAX_BYTES + 1)
    except OSError as exc:   # FileNotFoundError: "No such file or directory"
        raise _path_error(path, owner, f"a readable targets file ({exc.strerror or exc})") from None
    if len(raw) > MAX_BYTES:
        raise _path_error(path, owner, f"a targets file of at most {MAX_BYTES} bytes ({MAX_PAIRS} pairs "
                          "at most)")
    try:
        data = json.loads(raw.decode("utf-8"))
    except ValueError as exc:   # JSONDecodeError names line, column and char; or bad UTF-8
        raise _path_error(path, owner, f"a targets file (it is not valid JSON: {exc})") from None
    if not isinstance(data, dict):
        raise _path_error(path, owner, "a targets file (its JSON is not an object)")
    source = f"the targets file {str(path)!r}"
    targets = TargetSet.from_dict(data, source=source)

    have = (targets.left_sha256, targets.right_sha256)
    want = pair and (pair.left_sha256.lower(), pair.right_sha256.lower())
    if pair is not None and check_hash and any(h and h != w for h, w in zip(have, want)):
        short = [f"left {(a or '-')[:12]}, right {(b or '-')[:12]}" for a, b in (want, have)]
        raise ParameterError(f"The 'path' parameter of {owner} must be targets for the given images "
                             f"({short[0]}), or pass check_hash=False. Got {str(path)!r}, "
                             f"targets made for other images ({short[1]}) instead.")
    if pair is not None and targets.orientation == "as stored":
        _refuse_turned(pair, path, owner)
    bounds = [s for s in (shape, pair and tuple(pair.shape)) if s]
    for (h, w), key in ((hw, key) for hw in bounds for key in _POINTS):
        xy = getattr(targets, key)
        if (bad := np.flatnonzero((xy[:, 0] > w - 1) | (xy[:, 1] > h - 1))).size:
            raise ParameterError(message(f"pairs[{bad[0]}].{key}", source, f"inside the {w}x{h} (width x height) image "
                                         f"(0 <= x <= {w - 1}, 0 <= y <= {h - 1})", _plain(xy[bad[0]])))
    return targets


def _refuse_turned(pair: StereoPair, path, owner: str) -> None:
    """Refuse a file from before EXIF orientation was applied on a photo its tag turns."""
    from ..images.io import exif_orientation

    for side, photo in (("left", pair.left_path), ("right", pair.right_path)):
        if photo is None:
            continue
        with open(photo, "rb") as handle:
            turn = exif_orientation(handle.read(1 << 17))   # the Exif segment is at most 64 KB, near the start
        if turn != 1:
            raise ParameterError(f"The 'path' parameter of {owner} must be targets clicked on the photos shown "
                                 f"upright. Got {str(path)!r}, made before EXIF orientation was applied, on a "
                                 f"{side} photo with orientation {turn} instead: label the pair again.")


def many_to_one(targets: TargetSet) -> np.ndarray:
    """Indices of the pairs whose left or right point another pair also uses (to 1e-6 px).

    >>> many_to_one(TargetSet([[10, 10], [20, 10], [30, 10]], [[5, 10], [5, 10], [25, 10]])).tolist()
    [0, 1]
    """
    if not isinstance(targets, TargetSet):
        raise ParameterTypeError(message("targets", "many_to_one", "a TargetSet", targets))
    return np.flatnonzero(_repeated(np.round(targets.left_xy, 6), axis=0)
                          | _repeated(np.round(targets.right_xy, 6), axis=0))


def _repeated(values, axis=None) -> np.ndarray:
    """True where a value of `values` (a row, with ``axis=0``) occurs more than once."""
    _, inverse, counts = np.unique(values, axis=axis, return_inverse=True, return_counts=True)
    return counts[inverse.reshape(-1)] > 1


def check_one_to_one(targets: TargetSet, source: str, owner: str) -> TargetSet:
    """Refuse targets that give a corner two partners, naming the first such pairs and the fix.

    >>> check_one_to_one(TargetSet([[10, 10], [20, 10]], [[5, 10], [5, 10]]), "t.json", "tune")
    Traceback (most recent call last):
    ismb_lab.ParameterError: The targets file 't.json' given to tune must pair each corner once. Got pairs[0] ...
    """
    bad = many_to_one(targets)
    if bad.size:
        j = int(bad[0])
        right = np.round(targets.right_xy, 6)
        side = "right" if (right[bad] == right[j]).all(axis=1).sum() > 1 else "left"
        xy = np.round(getattr(targets, f"{side}_xy"), 6)
        other = int(next(k for k in bad[1:] if (xy[k] == xy[j]).all()))
        raise ParameterError(f"The targets file {source!r} given to {owner} must pair each corner once. "
                             f"Got pairs[{j}] and pairs[{other}] sharing the {side} point "
                             f"{_plain(getattr(targets, f'{side}_xy')[j])} ({bad.size} pairs share a "
                             f"corner) instead; 'ismb-lab targets merge {source} --out FIXED.json' "
                             "drops them")
    return targets


@dataclass(frozen=True, eq=False)
class Snapped:
    """Targets snapped to features by :func:`snap` (read-only arrays).

    `pairs` ``(s, 2)`` are the feature pairs of the targets that snapped on both sides,
    `target_index` their targets, `distance` the larger snap distance; `missing_left` and
    `missing_right` the targets with no feature in reach on that side.

    >>> Snapped([[0, 1], [0, 2]], [0, 3], [1], [1, 2], [0.0, 1.2]).shared.tolist()
    [0, 3]
    """

    pairs: np.ndarray
    target_index: np.ndarray
    missing_left: np.ndarray
    missing_right: np.ndarray
    distance: np.ndarray

    def __post_init__(self):
        for name in ("pairs", "target_index", "missing_left", "missing_right", "distance"):
            dtype, shape = (float, -1) if name == "distance" else (np.intp, (-1, 2) if name == "pairs" else -1)
            _set(self, name, np.array(getattr(self, name), dtype=dtype).reshape(shape))

    @property
    def shared(self) -> np.ndarray:
        """Snapped targets whose left or right feature another snapped target also uses."""
        return self.target_index[_repeated(self.pairs[:, 0]) | _repeated(self.pairs[:, 1])]


def snap(targets: TargetSet, left_xy, right_xy, tol=1.5) -> Snapped:
    """Snap each target point to the nearest feature within `tol` px (inclusive; ties to the lower
    index).  Targets that snap to the same feature are both kept (:attr:`Snapped.shared`).

    Parameters
    ----------
    targets : TargetSet
        The labelled points.
    left_xy, right_xy : (n, 2) float array_like
        The left and right features (corners).
    tol : float, default 1.5
        Largest snap distance, px.

    Returns
    -------
    snapped : Snapped
        Feature pairs of the snapped targets and the targets that did not snap.

    Examples
    --------
    >>> t = TargetSet([[10, 10], [50, 50]], [[5, 10], [40, 50]])
    >>> s = snap(t, [[10, 11], [30, 30]], [[5, 10], [40, 51]])
    >>> s.pairs.tolist(), s.target_index.tolist(), s.missing_left.tolist(), s.distance.tolist()
    ([[0, 0]], [0], [1], [1.0])
    """
    if not isinstance(targets, TargetSet):
        raise ParameterTypeError(message("targets", "snap", "a TargetSet", targets))
    tol = check_number(tol, "tol", "snap", low=0)
    near, dist = [], []
    for name, features in zip(_POINTS, (left_xy, right_xy)):
        features, points = check_points(features, name, "snap"), getattr(targets, name)
        d = np.linalg.norm(points[:, None, :] - features[None, :, :], axis=2)
        d = np.hstack([d, np.full((len(points), 1), np.inf)])   # a far sentinel for n == 0
        near.append(d.argmin(axis=1))
        dist.append(d[np.arange(len(points)), near[-1]])
    ok = (dist[0] <= tol) & (dist[1] <= tol)
    return Snapped(np.column_stack([near[0][ok], near[1][ok]]), np.flatnonzero(ok),
                   np.flatnonzero(dist[0] > tol), np.flatnonzero(dist[1] > tol),
                   np.maximum(dist[0], dist[1])[ok])


def targets_from_matches(pairs, left_xy, right_xy, *, left_sha256=None, right_sha256=None,
                         **meta) -> TargetSet:
    """Targets at the coordinates of feature pairs ``(i, k)``; extra keywords become `meta`.

    >>> t = targets_from_matches([[1, 0]], [[0, 0], [9, 4]], [[7, 4]], labeller="ann")
    >>> t.left_xy.tolist(), t.right_xy.tolist(), t.meta
    ([[9.0, 4.0]], [[7.0, 4.0]], {'labeller': 'ann'})
    """
    owner = "targets_from_matches"
    left_xy, right_xy = check_points(left_xy, "left_xy", owner), check_points(right_xy, "right_xy", owner)
    rule = f"an (m, 2) array of feature pairs (i, k), 0 <= i < {len(left_xy)}, 0 <= k < {len(right_xy)}"
    arr = np.asarray(pairs)
    arr = arr.reshape(0, 2).astype(np.intp) if arr.size == 0 else arr
    if not np.issubdtype(arr.dtype, np.integer):
        raise ParameterTypeError(message("pairs", owner, rule, f"an array of dtype {arr.dtype}"))
    if arr.ndim != 2 or arr.shape[1] != 2 or (arr < 0).any() or (arr >= [len(left_xy), len(right_xy)]).any():
        raise ParameterError(message("pairs", owner, rule, pairs))
    return TargetSet(left_xy[arr[:, 0]], right_xy[arr[:, 1]], left_sha256, right_sha256, meta=meta)
