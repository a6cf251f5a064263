"""Loading images and pairs, and their fingerprints."""

import hashlib

import cv2
import numpy as np
import pytest

from ismb_lab.images.io import StereoPair, image_sha256, load_image, load_pair


def bt601(rgb):
    rgb = np.asarray(rgb, dtype=float)
    return 0.299 * rgb[..., 0] + 0.587 * rgb[..., 1] + 0.114 * rgb[..., 2]


@pytest.fixture
def rgb():
    return np.random.default_rng(0).integers(0, 256, (7, 9, 3), dtype=np.uint8)


def says(info, *fragments):
    """The exception message names every fragment (parameter, rule, received value)."""
    text = str(info.value)
    missing = [f for f in fragments if f not in text]
    assert not missing, f"{missing} not in {text!r}"


def write(path, array):
    assert cv2.imwrite(str(path), array)
    return path


def test_grey_png_loads_exactly_as_float64(tmp_path):
    grey = np.arange(7 * 9, dtype=np.uint8).reshape(7, 9) * 4
    img = load_image(write(tmp_path / "g.png", grey))
    assert img.dtype == np.float64 and img.flags.c_contiguous
    assert np.array_equal(img, grey.astype(float))


def test_colour_file_is_bgr_and_colour_array_is_rgb(tmp_path, rgb):
    from_file = load_image(write(tmp_path / "c.png", rgb[..., ::-1]))   # imwrite takes BGR
    from_array = load_image(rgb)
    assert from_file.shape == (7, 9)
    assert np.allclose(from_file, bt601(rgb), atol=1e-3)
    assert np.allclose(from_array, from_file, atol=1e-9)
    assert 0 <= from_file.min() and from_file.max() <= 255


def test_alpha_is_dropped(tmp_path, rgb):
    alpha = np.random.default_rng(1).integers(0, 256, rgb.shape[:2], dtype=np.uint8)
    bgra = np.dstack([rgb[..., ::-1], alpha])
    assert np.allclose(load_image(write(tmp_path / "a.png", bgra)), bt601(rgb), atol=1e-3)
    assert np.allclose(load_image(np.dstack([rgb, alpha])), bt601(rgb), atol=1e-3)


def test_16_bit_file_is_scaled_to_0_255(tmp_path):
    deep = np.array([[0, 257, 65535], [1000, 30000, 65534]], dtype=np.uint16)
    img = load_image(write(tmp_path / "d.png", deep))
    assert img.dtype == np.float64
    assert np.allclose(img, deep * (255 / 65535), rtol=0, atol=1e-12)
    assert img.max() == 255.0 and img[0, 1] == pytest.approx(1.0)


def test_float_array_is_copied_not_aliased():
    src = np.full((3, 4), 7.5)
    img = load_image(src)
    img[0, 0] = 0
    assert src[0, 0] == 7.5 and np.array_equal(load_image(src.astype(np.float32)), src)


def test_file_hash_is_sha256_of_its_bytes(tmp_path, rgb):
    path = write(tmp_path / "c.png", rgb)
    expected = hashlib.sha256(path.read_bytes()).hexdigest()
    assert image_sha256(path) == image_sha256(str(path)) == expected
    pair = load_pair(path, rgb)
    assert pair.left_sha256 == expected and pair.left_path == str(path)
    assert pair.right_sha256 == image_sha256(rgb) and pair.right_path is None


def test_array_hash_follows_its_documented_definition(rgb):
    head = b"ismb_lab-array-v1\n" + f"{rgb.dtype.str} {rgb.shape}\n".encode()
    assert image_sha256(rgb) == hashlib.sha256(head + rgb.tobytes()).hexdigest()
    view = rgb[:, ::2]                              # not contiguous: hashed in C order
    assert image_sha256(view) == image_sha256(np.ascontiguousarray(view))


def test_array_hash_is_stable_and_tells_dtype_and_shape_apart():
    a = np.zeros((2, 6), dtype=np.uint8)
    digests = {image_sha256(x) for x in (a, a.reshape(3, 4), a.reshape(12), a.view(np.int8),
                                         a.astype(np.uint16), a.astype(float))}
    assert len(digests) == 6
    assert image_sha256(a) == image_sha256(np.zeros((2, 6), dtype=np.uint8))
    b = a.copy()
    b[1, 5] = 1
    assert image_sha256(b) != image_sha256(a)


def test_pair_holds_equal_size_float_images():
    pair = load_pair(np.zeros((40, 50), np.uint8), np.ones((40, 50)), min_shape=(31, 41))
    assert isinstance(pair, StereoPair) and pair.shape == (40, 50)
    assert pair.left.dtype == pair.right.dtype == np.float64


def test_missing_file_names_the_parameter_and_the_path(tmp_path):
    path = tmp_path / "nowhere" / "y.png"
    with pytest.raises(ValueError) as info:
        load_pair(path, np.zeros((3, 3)))
    says(info, "'left'", "load_pair", repr(str(path)), "does not exist")
    with pytest.raises(ValueError) as info:
        load_image(path)
    says(info, "'image'", "load_image", str(path))
    with pytest.raises(ValueError) as info:
        image_sha256(path)
    says(info, "image_sha256", str(path))


def test_text_file_named_png_is_not_an_image(tmp_path):
    path = tmp_path / "fake.png"
    path.write_text("not a picture")
    with pytest.raises(ValueError) as info:
        load_pair(np.zeros((3, 3)), path)
    says(info, "'right'", str(path), "not an image file of a format read here")


def test_sizes_must_match_and_reach_the_minimum():
    with pytest.raises(ValueError) as info:
        load_pair(np.zeros((40, 50)), np.zeros((40, 51)))
    says(info, "'right'", "50x40", "51x40", "(width x height)")
    with pytest.raises(ValueError) as info:
        load_pair(np.zeros((30, 50)), np.zeros((30, 50)), min_shape=(31, 41))
    says(info, "'left'", "at least 41x31", "50x30", "matching windows")
    with pytest.raises(ValueError) as info:
        load_pair(np.zeros((3, 3)), np.zeros((3, 3)), min_shape=(0, 3))
    says(info, "'min_shape'", "0")


@pytest.mark.parametrize("array, exc, fragment", [
    (np.array([[1.0, np.nan]]), ValueError, "NaN"),
    (np.array([[-1.0, 5.0]]), ValueError, "-1"),
    (np.array([[255.5]]), ValueError, "255.5"),
    (np.zeros((2, 2), dtype=bool), TypeError, "bool"),
    (np.zeros((2, 2), dtype=np.int32), TypeError, "int32"),
    (np.zeros((2, 2, 2)), ValueError, "(2, 2, 2)"),
    (np.zeros((0, 4)), ValueError, "(0, 4)"),
])
def test_bad_arrays_are_refused_with_the_received_value(array, exc, fragment):
    with pytest.raises(exc) as info:
        load_pair(array, np.zeros((2, 2)))
    says(info, "'left'", "load_pair", fragment)


# --- the pixel limit is read from the header, before anything decodes (issue 25) ---

def hdr_header(width, height):
    """A Radiance header declaring width x height pixels, and no pixel data."""
    return b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width)


def no_decoding(monkeypatch):
    def refuse(*args):
        raise AssertionError("cv2.imdecode was called")
    monkeypatch.setattr(cv2, "imdecode", refuse)


def test_an_empty_file_is_refused_in_words(tmp_path):
    path = tmp_path / "empty.png"
    path.write_bytes(b"")
    with pytest.raises(ValueError) as info:
        load_image(path)
    says(info, "'image'", str(path), "the file is empty")


def test_a_huge_radiance_header_is_refused_before_decoding(tmp_path, monkeypatch):
    path = tmp_path / "huge.hdr"
    path.write_bytes(hdr_header(12000, 12000))
    no_decoding(monkeypatch)
    with pytest.raises(ValueError) as info:
        load_image(path)
    says(info, "header says 12000x12000", "ISMB_LAB_MAX_PIXELS")


def test_radiance_lines_are_read_in_opencvs_pieces():
    from ismb_lab._core.header import image_size

    # OpenCV reads header lines 127 bytes at a time: the newline after a 127-byte line is
    # an empty line to it, so the size it uses is the next line, not the later one.
    data = b"#?RADIANCE\n" + b"A" * 127 + b"\n-Y 12000 +X 12000\n\n-Y 1 +X 1\n"
    assert image_size(data) == ("Radiance HDR", 12000, 12000)
    assert image_size(b"#?RGBE\nFORMAT=32-bit_rle_rgbe\n\n-Y 99999999999999999999 +X 1\n")[1:] == (
        1, 99999999999999999999)


ENCODED = [(".png", 1), (".jpg", 1), (".bmp", 1), (".tiff", 1), (".webp", 3), (".pgm", 1), (".pbm", 1),
           (".ppm", 3), (".pfm", 1), (".pfm", 3), (".sr", 1), (".hdr", 3)]


@pytest.mark.parametrize("ext, channels", ENCODED, ids=[f"{e}-{c}" for e, c in ENCODED])
def test_every_format_read_gives_opencvs_size_from_its_header(ext, channels):
    from ismb_lab._core.header import image_size

    image = (np.arange(7 * 12 * channels).reshape(7, 12, channels) % 251).astype(np.uint8).squeeze()
    if ext in (".pfm", ".hdr"):
        image = image.astype(np.float32)
    ok, data = cv2.imencode(ext, image)
    assert ok
    assert image_size(data.tobytes())[1:] == (12, 7)
    assert cv2.imdecode(data, cv2.IMREAD_UNCHANGED).shape[:2] == (7, 12)


@pytest.mark.parametrize("data, words", [
    (b"GIF89a\x0c\x00\x07\x00", "GIF"), (b"\x00\x00\x00\x0cjP  \r\n\x87\n", "JPEG 2000"),
    (b"P7\nWIDTH 4\n", "PAM"), (b"\x00\x00\x00\x1cftypavif", "AVIF"), (b"v/1\x01", "OpenEXR"),
    (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n+X 4 -Y 4\n", "'-Y height +X width'"),
    (b"\x89PNG\r\n\x1a\n", "IHDR"), (b"P5 # no size", "width and height"),
    (b"\xff\xd8\xff\xe0 broken", "JPEG file whose header cannot be read")])
def test_formats_without_a_readable_size_are_refused_before_decoding(tmp_path, monkeypatch, data, words):
    path = tmp_path / "image"
    path.write_bytes(data)
    no_decoding(monkeypatch)
    with pytest.raises(ValueError) as info:
        load_image(path)
    says(info, words)


@pytest.mark.parametrize("value", ["9" * 400, "0", "-5", "2e6", str((1 << 30) + 1)])
def test_the_pixel_variable_is_bounded(monkeypatch, value):
    from ismb_lab.images.io import max_pixels

    monkeypatch.setenv("ISMB_LAB_MAX_PIXELS", value)
    with pytest.raises(ValueError) as info:
        max_pixels()
    says(info, "ISMB_LAB_MAX_PIXELS", "from 1 to 1073741824")


def test_uploaded_bytes_pass_the_same_header_check(monkeypatch):
    from ismb_lab.images.rectify import load_photo

    no_decoding(monkeypatch)
    with pytest.raises(ValueError) as info:
        load_photo(hdr_header(12000, 12000), "left")
    says(info, "'left'", "header says 12000x12000")
    with pytest.raises(ValueError) as info:
        load_photo(b"", "left")
    says(info, "'left'", "the file is empty")


def test_a_header_pillow_will_not_size_is_refused_in_words(tmp_path, monkeypatch):
    import struct

    def bmp(width, height):
        return b"BM" + struct.pack("<IHHI", 54, 0, 0, 54) + struct.pack("<IiiHHIIiiII", 40, width, height, 1, 24,
                                                                        0, 0, 0, 0, 0, 0)

    path = tmp_path / "huge.bmp"
    path.write_bytes(bmp(20000, 20000))
    no_decoding(monkeypatch)
    monkeypatch.setenv("ISMB_LAB_MAX_PIXELS", str(1 << 30))
    with pytest.raises(ValueError) as info:
        load_image(path)
    says(info, "BMP file whose header declares more than")
    path.write_bytes(bmp(9000, 9000))
    monkeypatch.setenv("ISMB_LAB_MAX_PIXELS", "1000000")
    with pytest.raises(ValueError) as info:
        load_image(path)
    says(info, "header says 9000x9000")


def _jpeg_with_orientation(path, orientation: int):
    """A small colour JPEG, 40 wide and 24 high, with an EXIF Orientation tag (Pillow)."""
    from PIL import Image

    rng = np.random.default_rng(orientation)
    pixels = np.kron(rng.integers(0, 256, (6, 10, 3)), np.ones((4, 4, 1))).astype(np.uint8)
    exif = Image.Exif()
    exif[0x0112] = orientation
    Image.fromarray(pixels).save(path, quality=95, exif=exif.tobytes())
    return path


@pytest.mark.parametrize("orientation", range(1, 9))
def test_every_loader_turns_a_jpeg_upright_as_opencv_and_rectify_do(tmp_path, orientation):
    import cv2

    from ismb_lab.images.io import exif_orientation, load_pair
    from ismb_lab.images.rectify import load_photo

    path = _jpeg_with_orientation(tmp_path / "photo.jpg", orientation)
    assert exif_orientation(path.read_bytes()) == orientation
    upright = cv2.imread(str(path), cv2.IMREAD_COLOR)                # OpenCV applies the tag here
    want = cv2.cvtColor(upright.astype(np.float32), cv2.COLOR_BGR2GRAY).astype(float)
    image = load_image(path)
    assert image.shape == want.shape == ((40, 24) if orientation >= 5 else (24, 40))
    np.testing.assert_allclose(image, want, atol=1e-3)
    assert load_pair(path, path).shape == image.shape              # what match, tune and depth read
    assert load_photo(path).shape == image.shape                   # what rectify reads
