"""The size of an image file, read from its header before anything decodes it.

OpenCV decodes a whole image before its size can be refused (a 12000 x 12000 Radiance ``.hdr``
of a few kilobytes takes 3.46 GB), so only the formats of :data:`FORMATS`, whose size is read
here from the signature OpenCV picks its decoder by, are ever decoded.
"""

from __future__ import annotations

import io
import re
import warnings

__all__ = ["FORMATS", "HeaderError", "image_size"]

#: The formats whose size is read.
FORMATS = ("PNG", "JPEG", "BMP", "TIFF", "WebP", "Sun raster", "PBM/PGM/PPM", "PFM", "Radiance HDR")

_REFUSED = ((b"GIF8", "GIF"), (b"\x00\x00\x00\x0cjP  ", "JPEG 2000"), (b"\xffO\xffQ", "JPEG 2000"),
            (b"P7", "PAM"), (b"v/1\x01", "OpenEXR"))
_PILLOW = ((b"\xff\xd8\xff", "JPEG", "JPEG"), (b"BM", "BMP", "BMP"), (b"II*\x00", "TIFF", "TIFF"),
           (b"MM\x00*", "TIFF", "TIFF"), (b"II+\x00", "TIFF", "TIFF"), (b"MM\x00+", "TIFF", "TIFF"),
           (b"\x59\xa6\x6a\x95", "Sun raster", "SUN"))
#: OpenCV's fgets() buffer for Radiance header lines: a longer line is read in pieces.
_HDR_LINE = 127
_HDR_SIZE = re.compile(rb"-Y\s*([+-]?\d+)\s*\+X\s*([+-]?\d+)")
_DIGITS = re.compile(rb"\d+")
#: The largest number OpenCV's PNM reader accepts (a C int).
_INT_MAX = 2**31 - 1


class HeaderError(ValueError):
    """The size cannot be read from the header; the message says why, in a few words."""


def _png(data: bytes):
    if data[12:16] != b"IHDR" or len(data) < 24:
        raise HeaderError("a PNG file without its IHDR header")
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def _pillow(data: bytes, name: str, pillow: str):
    from PIL import Image

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with Image.open(io.BytesIO(data), formats=[pillow]) as image:   # the header only
                return image.size
    except Image.DecompressionBombError:   # Pillow gives no size above 2 * MAX_IMAGE_PIXELS
        raise HeaderError(f"a {name} file whose header declares more than {2 * Image.MAX_IMAGE_PIXELS} "
                          "pixels") from None
    except Exception:   # noqa: BLE001  Pillow raises many kinds on a broken header
        raise HeaderError(f"a {name} file whose header cannot be read") from None


def _pnm(data: bytes):
    """Width and height after the two-byte magic: numbers between blanks and ``#`` comments."""
    numbers, pos = [], 2
    while len(numbers) < 2:
        while pos < len(data) and (data[pos:pos + 1].isspace() or data[pos] == ord("#")):
            if data[pos] == ord("#"):
                end = data.find(b"\n", pos)
                pos = len(data) if end < 0 else end
            pos += 1
        # OpenCV reads every digit, leading zeros included, and refuses a number above INT_MAX
        digits = _DIGITS.match(data, pos)
        if digits is None:
            raise HeaderError("a PNM or PFM file whose header has no width and height")
        value = digits.group().lstrip(b"0") or b"0"
        if len(value) > len(str(_INT_MAX)) or int(value) > _INT_MAX:
            raise HeaderError("a PNM or PFM file whose header declares a size above 2**31 - 1 pixels a side")
        numbers.append(int(value))
        pos = digits.end()
    return numbers[0], numbers[1]


def _fgets(data: bytes, pos: int):
    """One fgets() of OpenCV's Radiance reader: up to a newline or :data:`_HDR_LINE` bytes."""
    end = data.find(b"\n", pos, pos + _HDR_LINE)
    stop = pos + _HDR_LINE if end < 0 else end + 1
    return data[pos:stop], stop


def _hdr(data: bytes):
    line, pos = _fgets(data, 0)
    while True:   # the header ends at an empty line
        line, pos = _fgets(data, pos)
        if not line:
            raise HeaderError("a Radiance HDR file whose header does not end")
        if line == b"\n":
            break
    line, pos = _fgets(data, pos)
    size = _HDR_SIZE.match(line)
    if size is None:
        raise HeaderError("a Radiance HDR file without its '-Y height +X width' line")
    height, width = int(size.group(1)), int(size.group(2))
    if height < 1 or width < 1:
        raise HeaderError(f"a Radiance HDR file of {width}x{height} pixels")
    return width, height


def image_size(data: bytes) -> tuple[str, int, int]:
    """``(format, width, height)`` of an image file's bytes, from its header alone.

    >>> image_size(b"#?RADIANCE\\nFORMAT=32-bit_rle_rgbe\\n\\n-Y 12000 +X 9000\\n")
    ('Radiance HDR', 9000, 12000)
    >>> image_size(b"GIF89a...")
    Traceback (most recent call last):
    ...
    ismb_lab._core.header.HeaderError: a GIF file, a format whose size is not read before decoding
    """
    if not data:
        raise HeaderError("the file is empty")
    if data.startswith(b"\x89PNG\r\n\x1a\n"):
        return ("PNG", *_png(data))
    if data[:4] == b"RIFF" and data[8:12] == b"WEBP":
        return ("WebP", *_pillow(data, "WebP", "WEBP"))
    for magic, name, pillow in _PILLOW:
        if data.startswith(magic):
            return (name, *_pillow(data, name, pillow))
    if data[:1] == b"P" and data[1:2] in (b"1", b"2", b"3", b"4", b"5", b"6", b"F", b"f"):
        return ("PFM" if data[1:2] in b"Ff" else "PBM/PGM/PPM", *_pnm(data))
    if data.startswith((b"#?RGBE", b"#?RADIANCE")):
        return ("Radiance HDR", *_hdr(data))
    for magic, name in _REFUSED:
        if data.startswith(magic):
            raise HeaderError(f"a {name} file, a format whose size is not read before decoding")
    if data[4:8] == b"ftyp":
        raise HeaderError("an AVIF or HEIF file, a format whose size is not read before decoding")
    raise HeaderError("not an image file of a format read here (" + ", ".join(FORMATS) + ")")
