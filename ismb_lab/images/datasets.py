"""Real stereo photographs from installed packages (scikit-image, Debian's ``opencv-doc``); nothing
is downloaded.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .._core.validation import ParameterError, check_number, message

__all__ = ["CHESSBOARD_PAIRS", "MOTORCYCLE_ROIS", "OPENCV_DATA", "OPENCV_DATA_VARIABLE", "SampleDataMissing",
           "aloe", "aloe_files", "books", "chessboard_pairs", "ground_truth_pairs", "GroundTruthPair", "motorcycle",
           "motorcycle_files", "opencv_samples"]

#: Where Debian's ``opencv-doc`` installs OpenCV's sample data.
OPENCV_DATA = Path("/usr/share/doc/opencv-doc/examples/data")
#: Environment variable naming another folder that holds the same files.
OPENCV_DATA_VARIABLE = "ISMB_LAB_OPENCV_DATA"
#: The chessboard rig's pairs: ``left01.jpg``/``right01.jpg`` ... 14 (there is no 10).
CHESSBOARD_PAIRS = tuple(f"{n:02d}" for n in range(1, 15) if n != 10)

#: Four non-overlapping 160 x 108 ROIs (x, y, w, h) of the 320 x 216 pair.
MOTORCYCLE_ROIS = ((0, 0, 160, 108), (160, 0, 160, 108), (0, 108, 160, 108), (160, 108, 160, 108))


@dataclass(frozen=True, eq=False)
class GroundTruthPair:
    """A rectified grey pair in ``[0, 255]`` and its left view's ``x_left - x_right`` (NaN: unknown)."""

    left: np.ndarray
    right: np.ndarray
    disparity: np.ndarray
    name: str


def motorcycle(width: int = 320) -> GroundTruthPair:
    """The Middlebury 2014 Motorcycle pair (scikit-image's copy), grey, scaled to `width` pixels.

    Area averaging; a scaled disparity averages known pixels only, and is unknown where less
    than half its footprint was known (the whole would leave half the corners, on depth edges,
    unknown).

    Parameters
    ----------
    width : int, default 320
        Width of the scaled pair, 16 to 741 pixels.

    Returns
    -------
    pair : GroundTruthPair
        The grey pair and its disparity map.

    Raises
    ------
    ImportError
        scikit-image is not installed.

    Examples
    --------
    >>> pair = motorcycle()
    >>> pair.left.shape, bool(np.nanmax(pair.disparity) < 30)
    ((216, 320), True)
    """
    width = check_number(width, "width", "motorcycle", low=16, high=741, integer=True)
    try:
        from skimage.data import stereo_motorcycle
    except ImportError:  # pragma: no cover - scikit-image is in the test extra
        raise ImportError("motorcycle() needs scikit-image: pip install scikit-image") from None
    left, right, disparity = stereo_motorcycle()
    grey = lambda rgb: cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    return _scaled(grey(left), grey(right), disparity, width, f"motorcycle@{width}")


def _scaled(left, right, disparity, width: int, name: str) -> GroundTruthPair:
    """A grey pair and its disparity map scaled to `width` (area averaging; see :func:`motorcycle`)."""
    scale = width / left.shape[1]
    size = (width, int(round(left.shape[0] * scale)))
    # float32 area averages can land a hair above 255: clip to the package's grey range
    grey = lambda g: np.clip(cv2.resize(np.asarray(g, np.float32), size, interpolation=cv2.INTER_AREA)
                             .astype(float), 0.0, 255.0)
    known = np.isfinite(disparity)
    total = cv2.resize(np.where(known, disparity, 0).astype(np.float32), size, interpolation=cv2.INTER_AREA)
    share = cv2.resize(known.astype(np.float32), size, interpolation=cv2.INTER_AREA)
    small = np.full(share.shape, np.nan)
    known_enough = share >= 0.5
    small[known_enough] = total[known_enough] / share[known_enough] * scale
    return GroundTruthPair(grey(left), grey(right), small, name)


def motorcycle_files() -> tuple:
    """The files :func:`motorcycle` reads: scikit-image's copies of the pair and its disparity."""
    import skimage.data

    folder = Path(skimage.data.__file__).parent
    return tuple(folder / name for name in ("motorcycle_left.png", "motorcycle_right.png", "motorcycle_disp.npz"))


def aloe_files(folder=None) -> tuple:
    """The files :func:`aloe` reads (`folder`: see :func:`opencv_samples`)."""
    root = opencv_samples(folder)
    return tuple(root / name for name in ("aloeL.jpg", "aloeR.jpg", "aloeGT.png"))


class SampleDataMissing(FileNotFoundError):
    """OpenCV's sample data is not installed (or not in the folder given)."""


def opencv_samples(folder=None) -> Path:
    """The folder of OpenCV's sample data: `folder`, else ``ISMB_LAB_OPENCV_DATA``, else
    :data:`OPENCV_DATA`; :class:`SampleDataMissing` says how to install it.

    Parameters
    ----------
    folder : str or Path, optional
        A folder holding the sample files.

    Returns
    -------
    folder : Path
        The folder.

    Raises
    ------
    SampleDataMissing
        OpenCV's sample data is not installed.
    """
    chosen = folder if folder is not None else os.environ.get(OPENCV_DATA_VARIABLE) or OPENCV_DATA
    path = Path(chosen)
    if not (path / "aloeL.jpg").is_file():
        raise SampleDataMissing(
            f"OpenCV's sample photos are not in {str(path)!r}: install them with "
            f"'sudo apt-get install opencv-doc', or name a folder holding aloeL.jpg, left.jpg and "
            f"left01.jpg in the environment variable {OPENCV_DATA_VARIABLE} (or the 'folder' argument).")
    return path


def _sample(name: str, folder, flags=cv2.IMREAD_GRAYSCALE) -> np.ndarray:
    path = opencv_samples(folder) / name
    with open(path, "rb") as handle:   # bytes: any file name works
        image = cv2.imdecode(np.frombuffer(handle.read(), np.uint8), flags)
    if image is None:
        raise SampleDataMissing(f"{str(path)!r} is missing or is not an image OpenCV can read")
    return image


def aloe(width: int | None = None, *, folder=None) -> GroundTruthPair:
    """Middlebury 2006 Aloe, grey, with its ground-truth disparity (0 in the file: unknown).

    `width` scales it as :func:`motorcycle` does (default: the full 1282 x 1110); `folder`: see
    :func:`opencv_samples`.

    >>> pair = aloe(320)                                  # doctest: +SKIP
    >>> pair.left.shape                                   # doctest: +SKIP
    (277, 320)
    """
    left = _sample("aloeL.jpg", folder, cv2.IMREAD_COLOR)
    right = _sample("aloeR.jpg", folder, cv2.IMREAD_COLOR)
    truth = _sample("aloeGT.png", folder).astype(float)
    truth[truth == 0] = np.nan
    full = left.shape[1]
    width = full if width is None else check_number(width, "width", "aloe", low=16, high=full, integer=True)
    grey = lambda bgr: cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    if width == full:
        return GroundTruthPair(grey(left).astype(float), grey(right).astype(float), truth, "aloe")
    return _scaled(grey(left), grey(right), truth, width, f"aloe@{width}")


def books(*, folder=None) -> tuple[np.ndarray, np.ndarray]:
    """Two hand-held photographs of books on a floor (612 x 459, grey): not rectified."""
    return (_sample("left.jpg", folder).astype(float), _sample("right.jpg", folder).astype(float))


def chessboard_pairs(*, folder=None) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The 13 ``(name, left, right)`` grey 640 x 480 pairs of OpenCV's calibration rig.

    Parameters
    ----------
    folder : str or Path, optional
        Folder of OpenCV's sample data (:func:`opencv_samples`).

    Returns
    -------
    pairs : list of tuple
        ``(name, left, right)``: the name of :data:`CHESSBOARD_PAIRS`, two (480, 640) float arrays.

    Raises
    ------
    SampleDataMissing
        OpenCV's sample data is not installed.
    """
    return [(n, _sample(f"left{n}.jpg", folder).astype(float), _sample(f"right{n}.jpg", folder).astype(float))
            for n in CHESSBOARD_PAIRS]


def ground_truth_pairs(disparity: np.ndarray, left_xy, right_xy, tol: float = 1.5):
    """Target pairs ``(i, k)`` from a ground-truth disparity map, and the unknown left corners.

    A left corner's partner is the right corner within `tol` pixels of ``(x - d(x, y), y)``;
    where ``d`` is unknown (NaN), the corner is neither a target nor an error when matched.

    Parameters
    ----------
    disparity : (H, W) float array
        Ground-truth ``x_left - x_right``, NaN where unknown.
    left_xy, right_xy : (n, 2) float array
        Corners ``(x, y)`` of each image.
    tol : float, default 1.5
        Largest distance, pixels, from the expected position.

    Returns
    -------
    pairs : (m, 2) int array
        Target ``(i, k)`` pairs.
    unknown : (u,) int array
        Left corners where the disparity is unknown.

    Raises
    ------
    ParameterError
        A left corner outside the map.

    Examples
    --------
    >>> d = np.full((10, 20), 5.0); d[:, :3] = np.nan
    >>> pairs, unknown = ground_truth_pairs(d, [[10, 4], [2, 4], [15, 4]], [[5, 4], [10.5, 4]])
    >>> pairs.tolist(), unknown.tolist()
    ([[0, 0], [2, 1]], [1])
    """
    tol = check_number(tol, "tol", "ground_truth_pairs", low=0)
    lxy = np.asarray(left_xy, float).reshape(-1, 2)
    rxy = np.asarray(right_xy, float).reshape(-1, 2)
    if lxy.size and (np.any(lxy < 0) or np.any(lxy[:, 0] > disparity.shape[1] - 1)
                     or np.any(lxy[:, 1] > disparity.shape[0] - 1)):
        raise ParameterError(message("left_xy", "ground_truth_pairs",
                                     f"points inside the {disparity.shape[1]}x{disparity.shape[0]} map",
                                     "points outside it"))
    d = disparity[np.rint(lxy[:, 1]).astype(int), np.rint(lxy[:, 0]).astype(int)]
    unknown = np.flatnonzero(~np.isfinite(d))
    pairs = []
    if len(rxy):
        expected = np.stack([lxy[:, 0] - d, lxy[:, 1]], axis=1)
        dist = np.hypot(*(expected[:, None, :] - rxy[None, :, :]).transpose(2, 0, 1))
        for i in np.flatnonzero(np.isfinite(d)):
            k = int(np.argmin(dist[i]))
            if dist[i, k] <= tol:
                pairs.append((i, k))
    return np.array(pairs, dtype=np.int64).reshape(-1, 2), unknown
