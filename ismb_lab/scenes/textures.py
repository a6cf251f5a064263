"""Procedural grey textures on a surface's 2-D coordinates: posters, checkers, ripple."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._core.validation import ParameterError, check_number, check_points, check_rng, message
from .geometry import _vector

__all__ = ["random_texture", "Texture"]


@dataclass(frozen=True, eq=False)
class Texture:
    """A procedural grey texture on a surface's 2-D coordinates ``(u, v)`` in metres, clipped to [0, 1].

    1. a ``base`` albedo, optionally a checker of period ``checker`` (``base +- checker_contrast / 2``);
    2. posters: cells of size ``cell`` from ``origin``; cell ``(row, col)`` may hold one rectangle
       ``rects[row, col] = (u0, v0, u1, v1)`` in fractions of the cell (NaN = empty) of albedo
       ``levels[row, col]``, which keeps corners apart and makes evaluation a look-up;
    3. a factor ``1 + ripple * mean(sin(k_u u + k_v v + phase))`` over the rows of ``waves``.

    >>> tex = Texture(base=0.5, cell=1.0, origin=(0, 0),
    ...               rects=[[[0.25, 0.25, 0.75, 0.75]]], levels=[[0.9]])
    >>> tex([[0.5, 0.5], [0.1, 0.5], [1.5, 0.5]])
    array([0.9, 0.5, 0.5])
    >>> Texture(checker=0.1, checker_contrast=0.4)([[0.05, 0.05], [0.15, 0.05]])
    array([0.3, 0.7])
    """

    base: float = 0.5
    cell: tuple = (1.0, 1.0)
    origin: tuple = (0.0, 0.0)
    rects: np.ndarray = field(default_factory=lambda: np.full((0, 0, 4), np.nan))
    levels: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    checker: float = 0.0
    checker_contrast: float = 0.0
    waves: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    ripple: float = 0.0

    def __post_init__(self):
        own = "Texture"
        object.__setattr__(self, "base", check_number(self.base, "base", own, low=0, high=1))
        cell = (self.cell,) * 2 if np.ndim(self.cell) == 0 else self.cell
        cell = _vector(cell, "cell", own, 2)
        if not np.all(cell > 0):
            raise ParameterError(message("cell", own, "a positive size or (cu, cv) pair of sizes",
                                         self.cell))
        object.__setattr__(self, "cell", tuple(float(c) for c in cell))
        object.__setattr__(self, "origin", tuple(_vector(self.origin, "origin", own, 2)))
        object.__setattr__(self, "checker", check_number(self.checker, "checker", own, low=0))
        object.__setattr__(self, "checker_contrast",
                           check_number(self.checker_contrast, "checker_contrast", own, low=0, high=1))
        object.__setattr__(self, "ripple", check_number(self.ripple, "ripple", own, low=0, high=1))
        rects = np.array(self.rects, dtype=float)
        levels = np.array(self.levels, dtype=float)
        if rects.ndim != 3 or rects.shape[2] != 4:
            raise ParameterError(message("rects", own, "an array of shape (rows, cols, 4)",
                                         f"an array of shape {rects.shape}"))
        if levels.shape != rects.shape[:2]:
            raise ParameterError(message("levels", own, f"an array of shape {rects.shape[:2]}",
                                         f"an array of shape {levels.shape}"))
        if not np.all((levels >= 0) & (levels <= 1)):
            raise ParameterError(message("levels", own, "an array of albedos in [0, 1]", levels))
        waves = np.array(self.waves, dtype=float).reshape(-1, 3) if np.size(self.waves) else \
            np.zeros((0, 3))
        if not np.all(np.isfinite(waves)):
            raise ParameterError(message("waves", own, "an (M, 3) array of finite (k_u, k_v, phase)",
                                         waves))
        for name, arr in (("rects", rects), ("levels", levels), ("waves", waves)):
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    def __call__(self, uv) -> np.ndarray:
        uv = check_points(uv, "uv", "Texture")
        u, v = uv[:, 0], uv[:, 1]
        value = np.full(len(u), self.base)
        if self.checker > 0 and self.checker_contrast > 0:
            parity = (np.floor(u / self.checker) + np.floor(v / self.checker)) % 2
            value = value + self.checker_contrast * (parity - 0.5)
        if self.levels.size:
            rows, cols = self.levels.shape
            fu = (u - self.origin[0]) / self.cell[0]
            fv = (v - self.origin[1]) / self.cell[1]
            iu, iv = np.floor(fu).astype(np.int64), np.floor(fv).astype(np.int64)
            inside = (iu >= 0) & (iu < cols) & (iv >= 0) & (iv < rows)
            iu, iv = np.clip(iu, 0, cols - 1), np.clip(iv, 0, rows - 1)
            r = self.rects[iv, iu]
            su, sv = fu - iu, fv - iv
            with np.errstate(invalid="ignore"):
                hit = inside & (su >= r[:, 0]) & (su < r[:, 2]) & (sv >= r[:, 1]) & (sv < r[:, 3])
            value = np.where(hit, self.levels[iv, iu], value)
        if self.ripple > 0 and len(self.waves):
            k = self.waves
            value = value * (1 + self.ripple * np.sin(np.outer(u, k[:, 0]) + np.outer(v, k[:, 1])
                                                      + k[:, 2]).mean(axis=1))
        return np.clip(value, 0.0, 1.0)


def random_texture(rng, extent, *, cell: float, fill: float = 0.6, base: float = 0.55,
                   contrast=(0.25, 0.45), sizes=(0.4, 0.76), margin: float = 0.12,
                   checker: float = 0.0, checker_contrast: float = 0.0,
                   ripple: float = 0.08, wavelengths=(0.4, 1.5)) -> Texture:
    """A random corner-rich :class:`Texture`: posters on a grid, plus mild ripple.

    `extent` ``(u_min, v_min, u_max, v_max)`` is covered by cells of about `cell` metres, stretched
    so that whole cells tile it; `fill` of them hold a rectangle (at least one) whose side is in
    `sizes` and whose gap to the cell's border is at least `margin` (fractions of a cell), its
    ``|level - base|`` in `contrast` of random sign.  `ripple` is the relative amplitude of 3
    random plane waves of `wavelengths` (m).

    Examples
    --------
    >>> tex = random_texture(0, (0, 0, 1, 1), cell=0.25)
    >>> tex.levels.shape
    (4, 4)
    >>> bool(np.array_equal(tex([[0.3, 0.6]]), random_texture(0, (0, 0, 1, 1), cell=0.25)([[0.3, 0.6]])))
    True
    """
    own = "random_texture"
    rng = check_rng(rng, "rng", own)
    ext = _vector(extent, "extent", own, 4)
    if not (ext[2] > ext[0] and ext[3] > ext[1]):
        raise ParameterError(message("extent", own, "(u_min, v_min, u_max, v_max) with "
                                     "u_max > u_min and v_max > v_min", tuple(ext)))
    cell = check_number(cell, "cell", own, low=0, low_open=True)
    fill = check_number(fill, "fill", own, low=0, high=1)
    base = check_number(base, "base", own, low=0, high=1)
    margin = check_number(margin, "margin", own, low=0, high=0.25)
    lo_c, hi_c = (check_number(c, "contrast", own, low=0, high=1) for c in contrast)
    lo_s, hi_s = (check_number(s, "sizes", own, low=0, low_open=True, high=1 - 2 * margin)
                  for s in sizes)
    lo_w, hi_w = (check_number(w, "wavelengths", own, low=0, low_open=True) for w in wavelengths)
    cols = max(1, round((ext[2] - ext[0]) / cell))
    rows = max(1, round((ext[3] - ext[1]) / cell))
    shape = (rows, cols)
    cells = rows * cols
    w = rng.uniform(lo_s, hi_s, shape)
    h = rng.uniform(lo_s, hi_s, shape)
    u0 = margin + rng.uniform(0, 1, shape) * (1 - 2 * margin - w)
    v0 = margin + rng.uniform(0, 1, shape) * (1 - 2 * margin - h)
    rects = np.stack([u0, v0, u0 + w, v0 + h], axis=-1)
    rects[(rng.permutation(cells) >= max(1, round(fill * cells))).reshape(shape)] = np.nan
    step = rng.uniform(lo_c, hi_c, shape) * rng.choice([-1.0, 1.0], shape)
    levels = base + step
    levels = np.where((levels < 0.04) | (levels > 0.96), base - step, levels)
    angle = rng.uniform(0, 2 * np.pi, 3)
    k = 2 * np.pi / rng.uniform(lo_w, hi_w, 3)
    waves = np.stack([k * np.cos(angle), k * np.sin(angle), rng.uniform(0, 2 * np.pi, 3)], axis=1)
    cell = ((ext[2] - ext[0]) / cols, (ext[3] - ext[1]) / rows)
    return Texture(base=base, cell=cell, origin=(ext[0], ext[1]), rects=rects,
                   levels=np.clip(levels, 0, 1), checker=checker,
                   checker_contrast=checker_contrast, waves=waves, ripple=ripple)
