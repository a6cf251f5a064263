"""Read images as grey float arrays and fingerprint them.

Every image in the package is a C-contiguous ``float64`` array of grey values in
``[0, 255]``, indexed ``image[y, x]`` (see :mod:`ismb_lab.images.coords`).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass

import cv2
import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, message

__all__ = ["MAX_PIXELS", "MOST_PIXELS", "PIXELS_VARIABLE", "decode", "exif_orientation",
           "grey_uint8", "image_sha256", "load_image", "load_pair", "max_pixels", "orient", "png_bytes",
           "save_image", "save_pair", "StereoPair"]

_ARRAY_TAG = b"ismb_lab-array-v1\n"


def _is_path(source) -> bool:
    return isinstance(source, (str, os.PathLike))


def _path_error(name: str, owner: str, why: str, path: str) -> ParameterError:
    # The shared message() shortens long values, but a path is only useful whole.
    return ParameterError(f"The {name!r} parameter of {owner} must be a readable image file "
                      f"({why}). Got {path!r} instead.")


#: Default most pixels of one image; ISMB_LAB_MAX_PIXELS changes it.  The pipeline keeps several
#: float64 copies of each image: about 90 bytes a pixel, so 25 million pixels is about 2.3 GB.
MAX_PIXELS = 25_000_000
#: The most that ISMB_LAB_MAX_PIXELS may allow: OpenCV's own default limit (2**30 pixels).
MOST_PIXELS = 1 << 30
PIXELS_VARIABLE = "ISMB_LAB_MAX_PIXELS"


def max_pixels() -> int:
    """The pixel limit in force: ``ISMB_LAB_MAX_PIXELS`` (1 to :data:`MOST_PIXELS`) if set, else
    :data:`MAX_PIXELS`.

    >>> max_pixels() >= 1
    True
    """
    raw = os.environ.get(PIXELS_VARIABLE, "").strip()
    if not raw:
        return MAX_PIXELS
    # Compared as text first: int() of thousands of digits is slow, then refused anyway.
    value = int(raw) if raw.isascii() and raw.isdigit() and len(raw) <= len(str(MOST_PIXELS)) else 0
    if not 1 <= value <= MOST_PIXELS:
        shown = raw if len(raw) <= 40 else raw[:37] + "..."
        raise ParameterError(f"The environment variable {PIXELS_VARIABLE} must be a whole number from 1 to "
                             f"{MOST_PIXELS} (OpenCV's own limit). Got {shown!r} instead.")
    return value


def _too_large(error, what: str, limit: int) -> ParameterError:
    return error(f"at most {limit} pixels, and {what}; set the environment variable "
                 f"{PIXELS_VARIABLE} to allow more")


def exif_orientation(data: bytes) -> int:
    """The EXIF Orientation tag (1-8) of a JPEG file's bytes; 1 (upright) when there is none.

    >>> exif_orientation(b"not a JPEG")
    1
    """
    at = 2
    while data[:2] == b"\xff\xd8" and at + 4 <= len(data) and data[at] == 0xFF and data[at + 1] not in (0xD9, 0xDA):
        end = at + 2 + int.from_bytes(data[at + 2:at + 4], "big")
        if data[at + 1] == 0xE1 and data[at + 4:at + 10] == b"Exif\x00\x00":
            return _tiff_orientation(data[at + 10:end])
        at = end
    return 1


def _tiff_orientation(tiff: bytes) -> int:
    order = {b"II": "little", b"MM": "big"}.get(tiff[:2])
    if order is None or len(tiff) < 8:
        return 1
    number = lambda at, size: int.from_bytes(tiff[at:at + size], order)   # noqa: E731
    ifd = number(4, 4)
    for entry in range(number(ifd, 2) if ifd + 2 <= len(tiff) else 0):
        at = ifd + 2 + 12 * entry
        if at + 12 <= len(tiff) and number(at, 2) == 0x0112:
            value = number(at + 8, 2)
            return value if 1 <= value <= 8 else 1
    return 1


def orient(image: np.ndarray, orientation: int) -> np.ndarray:
    """`image` (``image[y, x]``) turned upright by its EXIF `orientation`, as viewers show it.

    >>> orient(np.array([[1, 2], [3, 4]]), 6).tolist()   # 6: turn 90 degrees clockwise
    [[3, 1], [4, 2]]
    >>> orient(np.zeros((2, 2)), 9)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'orientation' parameter of orient must be an integer >= 1 and <= 8. Got 9 instead.
    """
    orientation = check_number(orientation, "orientation", "orient", low=1, high=8, integer=True)
    image = np.asarray(image)
    if image.ndim < 2:
        raise ParameterError(message("image", "orient", "an image[y, x] of 2 or more dimensions",
                                     f"an array of shape {image.shape}"))
    turned = {1: image, 2: image[:, ::-1], 3: image[::-1, ::-1], 4: image[::-1],
              5: np.swapaxes(image, 0, 1), 6: np.rot90(image, -1), 7: np.swapaxes(image, 0, 1)[::-1, ::-1],
              8: np.rot90(image, 1)}[orientation]
    return np.ascontiguousarray(turned)


def _imdecode(data: bytes, flags: int):
    """``cv2.imdecode``, and what its codecs printed to fd 2 meanwhile: passed on for a decoded
    image (a warning), returned for a failed one (for the caller's one-line message)."""
    buffer = np.frombuffer(data, dtype=np.uint8)
    try:
        saved = os.dup(2)
    except OSError:   # no stderr at all: nothing to keep apart
        return cv2.imdecode(buffer, flags), ""
    import tempfile

    try:
        with tempfile.TemporaryFile() as capture:
            os.dup2(capture.fileno(), 2)
            try:
                image = cv2.imdecode(buffer, flags)
            finally:
                os.dup2(saved, 2)
            capture.seek(0)
            said = capture.read(1 << 16)
    finally:
        os.close(saved)
    if image is not None and said:
        os.write(2, said)
    return image, said.decode("utf-8", "replace")


def decode(data: bytes, flags: int, error) -> np.ndarray:
    """Decode an image file's bytes once its header shows a size within :func:`max_pixels`.

    A JPEG is turned upright by its EXIF orientation with every flag, ``IMREAD_UNCHANGED``
    included.  `error(why)` makes the exception raised.
    """
    from .._core.header import HeaderError, image_size

    limit = max_pixels()
    try:
        kind, width, height = image_size(data)
    except HeaderError as exc:
        raise error(str(exc)) from None
    if width * height > limit:
        raise _too_large(error, f"its header says {width}x{height}", limit)
    image, said = _imdecode(data, flags)
    if image is None:
        said = next((line for line in said.splitlines() if "error" in line.lower()), "")
        raise error(f"OpenCV cannot decode it as a {kind} image" + (f": {said.strip()[:200]}" if said else ""))
    if flags == cv2.IMREAD_UNCHANGED and kind == "JPEG":   # OpenCV turns the other reads itself
        image = orient(image, exif_orientation(data))
    if image.shape[0] * image.shape[1] > limit:
        raise _too_large(error, f"it is {image.shape[1]}x{image.shape[0]}", limit)
    return image


def _read(path: str, name: str, owner: str, flags: int = cv2.IMREAD_UNCHANGED) -> np.ndarray:
    error = lambda why: _path_error(name, owner, why, path)   # noqa: E731
    if not os.path.exists(path):
        raise error("the file does not exist")
    if not os.path.isfile(path):   # a folder, a device, a FIFO: never opened
        raise error("it is not a file")
    limit = max_pixels()
    # The largest honest file of `limit` pixels: 16-bit RGBA, uncompressed, plus headers.
    most_bytes = 8 * limit + (1 << 20)
    size = os.path.getsize(path)
    if size > most_bytes:
        raise _too_large(error, f"a file of {size} bytes holds more", limit)
    try:   # bytes read here, so any file name works (cv2.imread crashes on non-UTF-8 names)
        with open(path, "rb") as handle:
            data = handle.read(most_bytes + 1)
    except OSError as exc:
        raise error(exc.strerror or str(exc)) from None
    return decode(data, flags, error)


def _to_grey(image, name: str, owner: str, *, bgr: bool) -> np.ndarray:
    rule = ("a 2-D grey or 3-D (H, W, 3 or 4) colour image of uint8, uint16 or finite "
            "float values in [0, 255]")
    image = np.asarray(image)
    if image.dtype == np.uint8:
        grey = image.astype(np.float64)
    elif image.dtype == np.uint16:
        grey = image * (255.0 / 65535.0)
    elif np.issubdtype(image.dtype, np.floating):
        grey = image.astype(np.float64)
        if not np.all(np.isfinite(grey)):
            raise ParameterError(message(name, owner, rule, "an array with NaN or infinite values"))
        if grey.size and (grey.min() < 0 or grey.max() > 255):
            raise ParameterError(message(name, owner, rule,
                                     f"values in [{grey.min():g}, {grey.max():g}]"))
    else:
        raise ParameterTypeError(message(name, owner, rule, f"an array of dtype {image.dtype}"))
    colour = grey.ndim == 3 and grey.shape[2] in (3, 4)
    if not (grey.ndim == 2 or colour) or grey.size == 0:
        raise ParameterError(message(name, owner, rule, f"an array of shape {image.shape}"))
    if colour:
        # cvtColor has no float64 path; float32 keeps the fractions
        code = cv2.COLOR_BGR2GRAY if bgr else cv2.COLOR_RGB2GRAY
        grey = cv2.cvtColor(np.ascontiguousarray(grey[:, :, :3], dtype=np.float32), code)
        grey = np.clip(grey.astype(np.float64), 0.0, 255.0)
    return np.ascontiguousarray(grey)


def _load(source, name: str, owner: str) -> np.ndarray:
    if _is_path(source):
        return _to_grey(_read(os.fspath(source), name, owner), name, owner, bgr=True)
    image = np.asarray(source)
    limit = max_pixels()
    if image.ndim >= 2 and image.shape[0] * image.shape[1] > limit:   # before any copy is made
        raise ParameterError(message(name, owner, f"an image of at most {limit} pixels (set the environment "
                                     f"variable {PIXELS_VARIABLE} to allow more)",
                                     f"an array of shape {image.shape}"))
    return _to_grey(image, name, owner, bgr=False)


def load_image(source, name: str = "image") -> np.ndarray:
    """Load an image file or array as C-contiguous grey ``float64`` values in ``[0, 255]``.

    A file is read unchanged (8 or 16 bit, grey, BGR or BGRA) in a format whose size is read
    from its header (:mod:`ismb_lab._core.header`); an array is ``(H, W)`` grey or ``(H, W, 3|4)``
    RGB(A).  ``uint16`` is scaled by ``255 / 65535``; floats must be finite and in ``[0, 255]``.
    Colour becomes BT.601 luma in float32 (no rounding); alpha is dropped.  `name` names
    `source` in error messages.

    Parameters
    ----------
    source : str, PathLike or array
        An image file, or an ``(H, W)`` or ``(H, W, 3|4)`` array.
    name : str, default "image"
        Name of `source` in error messages.

    Returns
    -------
    image : (H, W) float64 array
        Grey values in ``[0, 255]``.

    Raises
    ------
    ParameterError
        An unreadable file, a bad shape or values, or more than :func:`max_pixels` pixels.
    ParameterTypeError
        An array of an unsupported dtype.

    Examples
    --------
    >>> load_image(np.array([[0, 65535]], dtype=np.uint16))
    array([[  0., 255.]])
    >>> load_image(np.full((1, 1, 3), [255, 0, 0], dtype=np.uint8)).round(3)   # pure red
    array([[76.245]])
    """
    return _load(source, name, "load_image")


def image_sha256(source) -> str:
    """SHA-256 hex digest of an image file's bytes (as ``sha256sum``), or of an array: of
    ``b"ismb_lab-array-v1\\n"``, then ``f"{dtype.str} {shape}\\n"`` in ASCII, then its C-order bytes.

    >>> a = np.zeros((2, 3), dtype=np.uint8)
    >>> image_sha256(a) == image_sha256(a.copy())
    True
    >>> image_sha256(a) == image_sha256(a.astype(np.float64))
    False
    """
    digest = hashlib.sha256()
    if _is_path(source):
        path = os.fspath(source)
        try:
            with open(path, "rb") as handle:
                for block in iter(lambda: handle.read(1 << 20), b""):
                    digest.update(block)
        except OSError as exc:
            raise _path_error("source", "image_sha256", exc.strerror or str(exc), path) from None
        return digest.hexdigest()
    array = np.asarray(source)
    if array.dtype.hasobject:
        raise ParameterTypeError(message("source", "image_sha256", "a path or a numeric array",
                                f"an array of dtype {array.dtype}"))
    digest.update(_ARRAY_TAG)
    digest.update(f"{array.dtype.str} {array.shape}\n".encode("ascii"))
    digest.update(array.tobytes(order="C"))
    return digest.hexdigest()


@dataclass(frozen=True, eq=False)
class StereoPair:
    """A left and a right grey image of equal size, with their :func:`image_sha256` and paths
    (None for arrays).

    Attributes
    ----------
    left, right : (H, W) float64 array
        Grey images in ``[0, 255]``.
    left_sha256, right_sha256 : str
        Their :func:`image_sha256`.
    left_path, right_path : str or None
        Their files, or None for arrays.
    """

    left: np.ndarray
    right: np.ndarray
    left_sha256: str
    right_sha256: str
    left_path: str | None = None
    right_path: str | None = None

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)`` of both images."""
        return self.left.shape


def load_pair(left, right, *, min_shape=(1, 1)) -> StereoPair:
    """Load a stereo pair with :func:`load_image`; `min_shape` is the smallest ``(height, width)``.

    Parameters
    ----------
    left, right : str, PathLike or array
        The two images, of equal size.
    min_shape : tuple of int, default (1, 1)
        Smallest ``(height, width)`` accepted.

    Returns
    -------
    pair : StereoPair
        Both grey images, their digests and paths.

    Raises
    ------
    ParameterError
        An unreadable image, images of different sizes, or smaller than `min_shape`.
    ParameterTypeError
        `min_shape` not a pair.

    Examples
    --------
    >>> pair = load_pair(np.zeros((4, 6)), np.ones((4, 6)))
    >>> pair.shape, pair.left_path
    ((4, 6), None)
    >>> load_pair(np.zeros((4, 6)), np.zeros((4, 5)))
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'right' parameter of load_pair must be an image of the same size as 'left',
    6x4 pixels (width x height). Got 'an image of 5x4 pixels' instead.
    """
    owner = "load_pair"
    rule = "a (height, width) pair of integers >= 1"
    if isinstance(min_shape, (str, bytes)) or not hasattr(min_shape, "__len__"):
        raise ParameterTypeError(message("min_shape", owner, rule, min_shape))
    if len(min_shape) != 2:
        raise ParameterError(message("min_shape", owner, rule, min_shape))
    min_h, min_w = (check_number(v, "min_shape", owner, low=1, integer=True) for v in min_shape)

    grey = _load(left, "left", owner), _load(right, "right", owner)
    (h, w), (rh, rw) = grey[0].shape, grey[1].shape
    if h < min_h or w < min_w:
        raise ParameterError(message(
            "left", owner, f"an image of at least {min_w}x{min_h} pixels (width x height) "
            "to hold the matching windows", f"an image of {w}x{h} pixels"))
    if (rh, rw) != (h, w):
        raise ParameterError(message(
            "right", owner, f"an image of the same size as 'left', {w}x{h} pixels "
            "(width x height)", f"an image of {rw}x{rh} pixels"))
    path = lambda src: os.fspath(src) if _is_path(src) else None
    return StereoPair(*grey, image_sha256(left), image_sha256(right), path(left), path(right))


def grey_uint8(image) -> np.ndarray:
    """A grey image rounded to whole grey levels and clipped to 0-255, as ``uint8``.

    >>> grey_uint8([[-3.0, 127.5, 300.0]])
    array([[  0, 128, 255]], dtype=uint8)
    """
    return np.clip(np.rint(np.asarray(image, dtype=float)), 0, 255).astype(np.uint8)


def png_bytes(image) -> bytes:
    """A grey image as 8-bit PNG bytes: rounded to whole grey levels and clipped to 0-255.

    >>> import cv2, numpy as np
    >>> data = png_bytes(np.full((2, 2), 300.4))
    >>> data[1:4], cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED).tolist()
    (b'PNG', [[255, 255], [255, 255]])
    """
    rule = "a non-empty 2-D grey image of finite numbers, at most 2**31 - 1 pixels a side"
    try:
        grey = np.asarray(image, dtype=float)
    except (TypeError, ValueError):
        raise ParameterTypeError(message("image", "png_bytes", rule, image)) from None
    if grey.ndim != 2 or grey.size == 0 or max(grey.shape) >= 2**31:
        raise ParameterError(message("image", "png_bytes", rule, f"an array of shape {grey.shape}"))
    if not np.all(np.isfinite(grey)):
        raise ParameterError(message("image", "png_bytes", rule, "an array with NaN or infinite values"))
    ok, data = cv2.imencode(".png", grey_uint8(grey))
    if not ok:  # pragma: no cover - OpenCV refuses only what the checks above refuse
        raise ParameterError(message("image", "png_bytes", rule, f"an array of shape {grey.shape}"))
    return data.tobytes()


def save_image(path, image):
    """Write a grey image as an 8-bit PNG at `path`, atomically; returns the path.

    >>> import tempfile, pathlib, numpy as np
    >>> path = save_image(pathlib.Path(tempfile.mkdtemp()) / "grey.png", np.full((3, 4), 127.6))
    >>> load_image(path).shape, float(load_image(path)[0, 0])
    ((3, 4), 128.0)
    """
    from .._core.files import atomic_write_bytes

    return atomic_write_bytes(path, png_bytes(image))


def save_pair(left, right, parent, name: str):
    """Write a pair as ``left.png`` and ``right.png`` into ``parent/name``, never over another pair.

    A folder holding other images (labels may rest on them), a file or a link is skipped for
    ``name-2``, ``name-3``, ...; the same pair saved again reuses its folder.  Returns the folder.

    Parameters
    ----------
    left, right : (H, W) float array
        The grey images.
    parent : str or Path
        Folder that holds the pair's folder.
    name : str
        The pair's folder name.

    Returns
    -------
    folder : Path
        The folder written.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> parent = pathlib.Path(tempfile.mkdtemp())
    >>> a, b = np.zeros((4, 4)), np.full((4, 4), 9.0)
    >>> [save_pair(*p, parent, "books").name for p in ((a, b), (a, b), (b, a))]
    ['books', 'books', 'books-2']
    """
    import itertools
    from pathlib import Path

    from .._core.files import atomic_write_bytes

    images = {"left.png": png_bytes(left), "right.png": png_bytes(right)}
    for n in itertools.count(1):
        folder = Path(parent) / (name if n == 1 else f"{name}-{n}")
        if not folder.exists() and not folder.is_symlink():
            break
        if folder.is_symlink() or not folder.is_dir():
            continue
        if all(not (folder / f).exists() or ((folder / f).is_file() and (folder / f).read_bytes() == data)
               for f, data in images.items()):
            break
    folder.mkdir(parents=True, exist_ok=True)
    for f, data in images.items():
        atomic_write_bytes(folder / f, data)
    return folder
