"""Point clouds as PLY files (MeshLab, CloudCompare and Open3D open them): one ``vertex`` element
with ``x y z`` (float32) and ``red green blue`` (uchar), in ASCII or binary little-endian."""

from __future__ import annotations

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_points, message

__all__ = ["ply_bytes"]

_PROPERTIES = ("property float x", "property float y", "property float z",
               "property uchar red", "property uchar green", "property uchar blue")


def ply_bytes(points, colours=None, *, binary: bool = False, comments=()) -> bytes:
    """The PLY file of `points` (finite ``(x, y, z)``, written as float32) with their `colours`
    (``(red, green, blue)`` or grey, 0 to 255; default mid-grey), ASCII or `binary`, with header
    `comments` (printable ASCII).

    Parameters
    ----------
    points : (n, 3) float array
        Finite ``(x, y, z)``.
    colours : (n, 3) or (n,) float array, optional
        RGB rows or grey levels, 0 to 255; default 128.
    binary : bool, default False
        Binary little-endian instead of ASCII.
    comments : iterable of str, optional
        Header comment lines, printable ASCII.

    Returns
    -------
    data : bytes
        The PLY file.

    Raises
    ------
    ParameterError, ParameterTypeError
        Bad points, colours or comments.

    Examples
    --------
    >>> print(ply_bytes([[0.5, -0.25, 2.0]], [200], comments=["metres"]).decode())
    ply
    format ascii 1.0
    comment metres
    element vertex 1
    property float x
    property float y
    property float z
    property uchar red
    property uchar green
    property uchar blue
    end_header
    0.5 -0.25 2 200 200 200
    <BLANKLINE>
    >>> len(ply_bytes([[0.5, -0.25, 2.0]], binary=True).split(b"end_header\\n")[1])
    15
    """
    own = "ply_bytes"
    xyz = check_points(points, "points", own, dims=3).astype("<f4")
    if colours is None:
        colours = np.full(len(xyz), 128)
    try:
        rgb = np.asarray(colours, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ParameterTypeError(message("colours", own, "numbers from 0 to 255", colours)) from None
    if rgb.ndim == 1:
        rgb = np.repeat(rgb[:, None], 3, axis=1)
    if rgb.shape != (len(xyz), 3) or not np.all(np.isfinite(rgb)) or rgb.min(initial=0) < 0 \
            or rgb.max(initial=0) > 255:
        raise ParameterError(message("colours", own, f"{len(xyz)} grey levels or (red, green, blue) rows of "
                                     "numbers from 0 to 255, one per point", f"an array of shape {rgb.shape}"))
    rgb = np.rint(rgb).astype(np.uint8)
    for text in comments:
        if not isinstance(text, str) or not text.isascii() or not text.isprintable():
            raise ParameterError(message("comments", own, "lines of printable ASCII text", text))
    header = ["ply", f"format {'binary_little_endian' if binary else 'ascii'} 1.0",
              *(f"comment {text}" for text in comments), f"element vertex {len(xyz)}", *_PROPERTIES, "end_header"]
    head = ("\n".join(header) + "\n").encode("ascii")
    if binary:
        # one record per vertex, in the header's order: three little-endian float32, three uint8
        rows = np.empty(len(xyz), dtype=np.dtype({"names": ["x", "y", "z", "r", "g", "b"],
                                                  "formats": ["<f4"] * 3 + ["u1"] * 3}))
        for n, name in enumerate("xyzrgb"):
            rows[name] = (xyz if n < 3 else rgb)[:, n % 3]
        return head + rows.tobytes()
    # 9 significant digits give a 32-bit float back exactly
    lines = [" ".join([*(f"{float(v):.9g}" for v in p), *(str(int(c)) for c in c3)]) for p, c3 in zip(xyz, rgb)]
    return head + "".join(line + "\n" for line in lines).encode("ascii")
