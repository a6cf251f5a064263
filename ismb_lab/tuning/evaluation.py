"""Scoring matches against target pairs: C/E/T as in the thesis' Fig. 5.10.

C: matches that are targets; E: the others, split into *wrong partner* (the left feature has
another target) and *extra* (it has none), printed ``14/2+0/16``; T: the targets.  Matches of
left features whose truth is unknown are not counted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from .._core.validation import ParameterError, message

__all__ = ["Score", "Scorer", "score", "unlabelled"]


@dataclass(frozen=True)
class Score:
    """C/E/T counts of one or more pairs (scores add with ``+``).

    Its text form is ``correct/wrong_partner+extra/targets``: ``'14/2+0/16'`` is 14 correct
    matches, 2 matches of a left feature that has a target to another right feature, 0 extra
    matches (of a left feature with no target), and 16 targets; C = 14, E = 2 + 0, T = 16.

    Attributes
    ----------
    correct : int
        C: matches that are target pairs.
    wrong_partner : int
        Matches of a left feature that has a target, to another right feature.
    extra : int
        Matches of a left feature that has no target and is not unknown.
    targets : int
        T: the number of target pairs.

    Examples
    --------
    >>> s = Score(correct=14, wrong_partner=2, extra=0, targets=16)
    >>> str(s), round(s.precision, 3), s.recall
    ('14/2+0/16', 0.875, 0.875)
    >>> str(s + Score(16, 0, 1, 16))
    '30/2+1/32'
    """

    correct: int
    wrong_partner: int
    extra: int
    targets: int

    @property
    def errors(self) -> int:
        """E = wrong_partner + extra."""
        return self.wrong_partner + self.extra

    @property
    def recall(self) -> float:
        """C / T (the thesis' "accurate rate")."""
        return self.correct / self.targets if self.targets else float("nan")

    @property
    def precision(self) -> float:
        """C / (C + E)."""
        matched = self.correct + self.errors
        return self.correct / matched if matched else float("nan")

    @property
    def fitness(self) -> int:
        """The GA's fitness (4-1): n_c - n_e."""
        return self.correct - self.errors

    def __add__(self, other: "Score") -> "Score":
        return Score(self.correct + other.correct, self.wrong_partner + other.wrong_partner,
                     self.extra + other.extra, self.targets + other.targets)

    def __str__(self) -> str:
        return f"{self.correct}/{self.wrong_partner}+{self.extra}/{self.targets}"


class Scorer:
    """:func:`score` against fixed targets, their look-ups built once (for a GA).

    >>> scorer = Scorer([[0, 0], [1, 1], [2, 2]], unknown=[4])
    >>> str(scorer([[0, 0], [1, 2], [3, 3], [4, 4]])), str(scorer([[2, 2]]))
    ('1/1+1/3', '1/0+0/3')
    """

    def __init__(self, targets, unknown=()):
        targets = np.asarray(targets, dtype=np.int64).reshape(-1, 2)
        self._wanted = frozenset(map(tuple, targets.tolist()))
        self._has_target = frozenset(targets[:, 0].tolist())
        self._skip = frozenset(np.asarray(unknown, dtype=np.int64).ravel().tolist())

    def __call__(self, pairs) -> Score:
        """The :class:`Score` of matched ``(i, k)`` pairs, an ``(m, 2)`` int array_like."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        codes = self.neuron_codes(pairs[:, 0], pairs[:, 1])
        return Score(*(int(np.sum(codes == code)) for code in (1, 2, 3)), len(self._wanted))

    @property
    def targets(self) -> int:
        """T: the number of distinct targets."""
        return len(self._wanted)

    def neuron_codes(self, rows, cols) -> np.ndarray:
        """What a match of each candidate neuron ``(rows[a], cols[a])`` would count as: 1 correct,
        2 wrong partner, 3 extra, 0 not counted; :meth:`count` then scores matched neurons.

        >>> scorer = Scorer([[0, 0], [1, 1], [2, 2]], unknown=[4])
        >>> codes = scorer.neuron_codes(rows=[0, 1, 3, 4], cols=[0, 2, 3, 4])
        >>> codes.tolist(), str(scorer.count(codes, [0, 1, 2, 3]))
        ([1, 2, 3, 0], '1/1+1/3')
        """
        wanted, has_target, skip = self._wanted, self._has_target, self._skip
        rows = np.asarray(rows, dtype=np.int64).ravel().tolist()
        cols = np.asarray(cols, dtype=np.int64).ravel().tolist()
        return np.array([1 if (i, k) in wanted else 2 if i in has_target else 0 if i in skip else 3
                         for i, k in zip(rows, cols)], dtype=np.uint8)

    def count(self, codes: np.ndarray, matched) -> Score:
        """The :class:`Score` of the matched neurons (indices into `codes`, each at most once).

        Parameters
        ----------
        codes : uint8 ndarray
            What :meth:`neuron_codes` returned.
        matched : int array_like
            Indices into `codes` of the matched neurons.

        Returns
        -------
        score : Score
            Their counts against this scorer's targets.
        """
        codes, matched = np.asarray(codes, dtype=np.uint8), np.asarray(matched, dtype=np.int64).ravel()
        correct, wrong, extra = _tally(codes, matched)
        if correct < 0:
            raise ParameterError(message("matched", "Scorer.count", f"indices in [0, {len(codes)})",
                                         matched))
        return Score(correct, wrong, extra, len(self._wanted))


@numba.njit(cache=True)
def _tally(codes, matched):
    correct = wrong = extra = 0
    for a in matched:
        if a < 0 or a >= codes.shape[0]:
            return -1, 0, 0
        code = codes[a]
        if code == 1:
            correct += 1
        elif code == 2:
            wrong += 1
        elif code == 3:
            extra += 1
    return correct, wrong, extra


def unlabelled(targets, n_left: int) -> np.ndarray:
    """The left features ``0 .. n_left - 1`` that no target starts from: a person who labels some
    corners says nothing of the others (the thesis' targets are all the true pairs).

    >>> unlabelled([[0, 3], [2, 1]], 4).tolist()
    [1, 3]
    """
    first = np.asarray(targets, dtype=np.int64).reshape(-1, 2)[:, 0]
    return np.setdiff1d(np.arange(int(n_left), dtype=np.int64), first)


def score(pairs, targets, unknown=()) -> Score:
    """Compare matched ``(i, k)`` feature pairs with target pairs; matches of the left features
    in `unknown` are not counted.

    Parameters
    ----------
    pairs : (m, 2) int array_like
        Matched ``(i, k)`` pairs of left and right feature indices.
    targets : (n, 2) int array_like
        Target pairs.
    unknown : int array_like, optional
        Left features whose matches are not counted (see :func:`unlabelled`).

    Returns
    -------
    score : Score
        The C/E/T counts; ``str(score)`` is ``'C/wrong+extra/T'``.

    Examples
    --------
    >>> str(score([[0, 0], [1, 2], [3, 3], [4, 4]], [[0, 0], [1, 1], [2, 2]], unknown=[4]))
    '1/1+1/3'
    """
    return Scorer(targets, unknown)(pairs)
