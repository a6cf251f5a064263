"""A rig from a factory calibration (``ismb-lab rig``, StereoCamera.from_factory / from_opencv), every
field of a rig file checked by name, and the PLY cloud of ``match --rig --ply`` read back by a reader
written here from the PLY format's description (not the writer's code)."""

import hashlib
import json
import math
import struct

import cv2
import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab.cameras.camera import StereoCamera, load_camera
from ismb_lab.cli import main
from ismb_lab.matching.metric import row_tolerance
from ismb_lab.matching.ply import ply_bytes
from ismb_lab.scenes import lab_scene


def one_line(argv, capsys, *words) -> str:
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("ismb-lab: error:"), err
    assert all(w in err for w in words), err
    return err


# --- a PLY reader, from the format's description ---

_TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h", "ushort": "H",
          "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I", "float": "f", "float32": "f",
          "double": "d", "float64": "d"}


def read_ply(data: bytes) -> dict:
    """The vertices of a PLY file as ``{property: list}``: the header's lines up to ``end_header``
    name the format and each element's count and properties; then the rows, as text or as packed
    little-endian binary in the declared types."""
    head, _, body = data.partition(b"end_header\n")
    lines = head.decode("ascii").splitlines()
    assert lines[0] == "ply"
    fmt, elements = None, []
    for line in lines[1:]:
        words = line.split()
        if words[0] == "format":
            fmt = words[1]
            assert words[2] == "1.0"
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            assert words[1] != "list"
            elements[-1][2].append((words[2], words[1]))
        else:
            assert words[0] in ("comment", "obj_info"), line
    assert [e[0] for e in elements] == ["vertex"]
    _, count, props = elements[0]
    if fmt == "ascii":
        rows = [row.split() for row in body.decode("ascii").splitlines() if row.strip()]
        assert len(rows) == count and all(len(r) == len(props) for r in rows)
        return {name: [float(r[n]) if _TYPES[kind] in "fd" else int(r[n]) for r in rows]
                for n, (name, kind) in enumerate(props)}
    assert fmt == "binary_little_endian"
    layout = "<" + "".join(_TYPES[kind] for _, kind in props)
    assert len(body) == count * struct.calcsize(layout)
    rows = list(struct.iter_unpack(layout, body))
    return {name: [r[n] for r in rows] for n, (name, _) in enumerate(props)}


@pytest.mark.parametrize("binary", [False, True])
def test_the_ply_reader_reads_both_encodings_of_the_writer(binary):
    rng = np.random.default_rng(0)
    points = rng.uniform(-3, 3, (20, 3))
    grey = rng.integers(0, 256, 20)
    cloud = read_ply(ply_bytes(points, grey, binary=binary, comments=["test"]))
    assert list(cloud) == ["x", "y", "z", "red", "green", "blue"]
    got = np.column_stack([cloud["x"], cloud["y"], cloud["z"]])
    assert np.allclose(got, points, rtol=1e-6, atol=0)                    # 32-bit floats
    assert cloud["red"] == cloud["green"] == cloud["blue"] == grey.tolist()


def test_ply_bytes_refuses_bad_points_and_colours():
    with pytest.raises(ParameterError, match="'points' parameter of ply_bytes"):
        ply_bytes([[0.0, 0.0, np.nan]])
    with pytest.raises(ParameterError, match="'colours' parameter of ply_bytes"):
        ply_bytes([[0.0, 0.0, 1.0]], [300])
    with pytest.raises(ParameterError, match="'comments' parameter of ply_bytes"):
        ply_bytes([[0.0, 0.0, 1.0]], comments=["two\nlines"])
    assert read_ply(ply_bytes(np.zeros((0, 3)))) == {k: [] for k in ("x", "y", "z", "red", "green", "blue")}


# --- the factory rig ---

def test_a_factory_rig_is_a_rectified_camera_with_no_rms_and_a_one_pixel_band():
    cam = StereoCamera.from_factory(520.8, 0.0836, (640, 480), centre=(350.6, 243.1))
    assert cam.is_rectified and not cam.distorted and math.isnan(cam.rms)
    assert (cam.focal_px, cam.baseline_m) == (520.8, 0.0836)
    assert cam.rectified_centre.tolist() == [350.6, 243.1]
    assert row_tolerance(cam) == row_tolerance(cam, subpixel=True) == 1.0     # the documented default band
    z = cam.points_from_disparity([[350.6, 243.1], [450.6, 243.1]], [52.08, 52.08])
    assert np.allclose(z, [[0, 0, 0.836], [0.1605, 0, 0.836]], atol=1e-4)
    record = cam.to_dict()
    assert record["rms_px"] is None and record["board"] is None and record["square_m"] is None
    again = load_camera(cam.to_json())
    assert again.is_rectified and again.to_dict() == record
    assert StereoCamera.from_factory(500, 0.1, (320, 240)).rectified_centre.tolist() == [159.5, 119.5]
    assert StereoCamera().is_rectified and not StereoCamera.pinhole(vertical_offset_px=1).is_rectified


@pytest.mark.parametrize("kwargs, name", [
    ({"focal_px": 0}, "focal_px"), ({"focal_px": np.inf}, "focal_px"), ({"baseline_m": -0.1}, "baseline_m"),
    ({"baseline_m": 80.0}, "baseline_m"), ({"size": (640, 0)}, "size"), ({"size": (640.5, 480)}, "size"),
    ({"centre": (700, 10)}, "centre"), ({"centre": (np.nan, 10)}, "centre"), ({"centre": 3}, "centre"),
])
def test_from_factory_names_each_bad_value(kwargs, name):
    values = {"focal_px": 500.0, "baseline_m": 0.06, "size": (640, 480), **kwargs}
    with pytest.raises((ParameterError, TypeError), match=f"'{name}' parameter of StereoCamera.from_factory"):
        StereoCamera.from_factory(**values)


def test_the_rig_command_writes_what_match_rig_reads(tmp_path, capsys):
    out = tmp_path / "rig.json"
    assert main(["rig", "--focal-px", "300", "--baseline-m", "0.1", "--size", "320x240", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "focal length 300.0 px" in said and "within 1 px of their row" in said
    cam = load_camera(out)
    assert (cam.focal_px, cam.baseline_m, cam.size) == (300.0, 0.1, (320, 240)) and cam.is_rectified


@pytest.mark.parametrize("argv, words", [
    (["--focal-px", "300", "--size", "320x240"], ["--baseline-m"]),
    (["--focal-px", "-3", "--baseline-m", "0.1", "--size", "320x240"], ["--focal-px", "-3"]),
    (["--focal-px", "nan", "--baseline-m", "0.1", "--size", "320x240"], ["--focal-px", "nan"]),
    (["--focal-px", "300", "--baseline-m", "100", "--size", "320x240"], ["--baseline-m", "100"]),
    (["--focal-px", "300", "--baseline-m", "0.1", "--size", "320"], ["--size", "'320'"]),
    (["--focal-px", "300", "--baseline-m", "0.1", "--size", "320x240", "--centre", "400,2"], ["--centre", "400,2"]),
    (["--focal-px", "300", "--baseline-m", "0.1", "--size", "320x240", "--centre", "a,b"], ["--centre"]),
    (["--focal-px", "300", "--baseline-m", "0.1", "--size", "320x240", "--units", "mm"], ["--units"]),
])
def test_the_rig_command_refuses_bad_values_in_one_line(tmp_path, capsys, argv, words):
    one_line(["rig", *argv, "--out", tmp_path / "rig.json"], capsys, *words)
    assert not (tmp_path / "rig.json").exists()


def opencv_files(folder, cam, unit=1.0, names=("K1", "D1", "K2", "D2")):
    """`cam` written as OpenCV's stereo_calib sample writes it: intrinsics and extrinsics, T in `unit`s."""
    storage = cv2.FileStorage(str(folder / "intrinsics.yml"), cv2.FILE_STORAGE_WRITE)
    for name, value in zip(names, (cam.k_left, cam.d_left, cam.k_right, cam.d_right)):
        storage.write(name, value)
    storage.release()
    storage = cv2.FileStorage(str(folder / "extrinsics.yml"), cv2.FILE_STORAGE_WRITE)
    storage.write("R", cam.rotation)
    storage.write("T", cam.translation / unit)
    storage.write("image_width", cam.size[0])
    storage.write("image_height", cam.size[1])
    storage.release()
    return folder / "intrinsics.yml", folder / "extrinsics.yml"


def distorted_camera():
    k = np.array([[520.0, 0, 318], [0, 522.0, 242], [0, 0, 1]])
    rotation, _ = cv2.Rodrigues(np.array([0.01, -0.02, 0.005]))
    return StereoCamera((640, 480), k, [[-0.2, 0.1, 0.001, -0.001, 0.0]], k * [[1.01], [1.0], [1.0]],
                        [[-0.25, 0.12, 0.0, 0.001, 0.0]], rotation, [-0.08, 0.001, 0.002])


def test_from_opencv_reads_the_cameras_of_a_filestorage_calibration(tmp_path):
    cam = distorted_camera()
    files = opencv_files(tmp_path, cam, unit=0.001, names=("M1", "D1", "M2", "D2"))
    read = StereoCamera.from_opencv(*files, units="mm")
    for name in ("k_left", "d_left", "k_right", "d_right", "rotation", "translation"):
        assert np.allclose(getattr(read, name), getattr(cam, name), rtol=1e-12, atol=1e-15), name
    assert read.focal_px == pytest.approx(cam.focal_px) and read.baseline_m == pytest.approx(cam.baseline_m)
    assert not read.is_rectified and math.isnan(read.rms) and read.size == (640, 480)
    with pytest.raises(ParameterError, match="'units'.*units='mm'"):      # millimetres read as metres: 80 m
        StereoCamera.from_opencv(*files)
    with pytest.raises(ParameterError, match="'paths'.*no R, T"):
        StereoCamera.from_opencv(files[0])
    with pytest.raises(ParameterError, match="'paths'.*K1 once"):
        StereoCamera.from_opencv(files[0], files[0], files[1])
    with pytest.raises(ParameterError, match="'size'.*640x480"):
        StereoCamera.from_opencv(*files, size=(320, 240), units="mm")
    (tmp_path / "bad.yml").write_text("K1: [1, 2\n")
    with pytest.raises(ParameterError, match="'paths'.*OpenCV can parse"):
        StereoCamera.from_opencv(tmp_path / "bad.yml")


def test_the_rig_command_reads_opencv_files(tmp_path, capsys):
    cam = distorted_camera()
    files = opencv_files(tmp_path, cam)
    out = tmp_path / "rig.json"
    assert main(["rig", "--from-opencv", str(files[0]), "--from-opencv", str(files[1]), "--out", str(out)]) == 0
    assert "raw photos are rectified with it" in capsys.readouterr().out
    assert load_camera(out).baseline_m == pytest.approx(cam.baseline_m)
    one_line(["rig", "--from-opencv", files[0], "--from-opencv", files[1], "--focal-px", "3", "--out",
              tmp_path / "x.json"], capsys, "--focal-px")
    one_line(["rig", "--from-opencv", files[0], "--out", tmp_path / "x.json"], capsys, "'paths'", "R, T")


# --- every field of a rig file, by name ---

def rig_text(**change) -> str:
    record = json.loads(StereoCamera.from_factory(300.0, 0.1, (320, 240)).to_json())
    record.update(change)
    return json.dumps(record)


@pytest.mark.parametrize("change, name", [
    ({"rms_px": 0}, "rms_px"), ({"rms_px": -0.2}, "rms_px"), ({"rms_px": float("nan")}, "rms_px"),
    ({"rms_px": "0.3"}, "rms_px"), ({"rms_px": True}, "rms_px"), ({"rms_px": 10 ** 400}, "rms_px"),
    ({"size": [320.5, 240]}, "size"), ({"size": [320]}, "size"), ({"board": [9.5, 6], "square_m": 0.025, "used": ["a"]}, "board"),
    ({"board": None, "square_m": 0.025, "used": ["a"]}, "board"), ({"square_m": "x", "board": [9, 6]}, "square_m"),
    ({"k_left": [[300, 0, 160], [0, 300, 120]]}, "k_left"), ({"k_right": "eye"}, "k_right"),
    ({"d_left": [0, 0, float("inf"), 0, 0]}, "d_left"), ({"rotation": [[1, 0], [0, 1]]}, "rotation"),
    ({"translation": [-0.1, 0]}, "translation"), ({"translation": [0, 0, 0]}, "translation"),
    ({"used": "left01.jpg"}, "used"), ({"skipped": [1]}, "skipped"), ({"pairs": {}}, "pairs"),
    ({"focal_px": 500.0}, "focal_px"), ({"baseline_m": 0.2}, "baseline_m"), ({"zoom": None}, "zoom"),
    ({"pairs": [{"left": "a"}]}, "pairs[0].right"),
])
def test_every_bad_field_of_a_rig_file_is_named_with_its_rule_and_value(tmp_path, change, name):
    path = tmp_path / "rig.json"
    path.write_text(rig_text(**change))
    with pytest.raises((ParameterError, TypeError)) as info:
        load_camera(path)
    text = str(info.value)
    assert text.startswith(f"The '{name}' parameter of the rig file '{path}' must be ") and " Got " in text, text


@pytest.mark.parametrize("name", ["rms_px", "k_left", "translation", "size"])
def test_a_missing_field_is_named(name):
    record = json.loads(rig_text())
    del record[name]
    with pytest.raises(ParameterError, match=f"'{name}' parameter of the rig file must be given: a complete rig "
                                             "file has"):
        load_camera(json.dumps(record))


def test_rms_px_null_means_not_measured_and_a_measured_one_sets_the_band():
    assert math.isnan(load_camera(rig_text(rms_px=None)).rms)
    cam = load_camera(rig_text(rms_px=0.3))
    assert cam.rms == 0.3 and row_tolerance(cam, subpixel=True) == pytest.approx(0.6)
    with pytest.raises(ParameterError, match="'rms' parameter of StereoCamera"):
        StereoCamera(rms=0.0)


@pytest.mark.parametrize("value, words", [
    ("0", ["'rms_px'", "Got 0 instead"]), ("NaN", ["'rms_px'", "Got nan instead"]),
])
def test_match_rig_names_a_bad_rms_in_one_line(tmp_path, capsys, value, words):
    scene = lab_scene()
    path = tmp_path / "rig.json"
    path.write_text(rig_text().replace('"rms_px": null', f'"rms_px": {value}'))
    cv2.imwrite(str(tmp_path / "L.png"), scene.left.astype(np.uint8))
    cv2.imwrite(str(tmp_path / "R.png"), scene.right.astype(np.uint8))
    one_line(["match", tmp_path / "L.png", tmp_path / "R.png", "--rig", path], capsys, *words)


# --- match --rig with a factory rig: the PLY cloud and the JSON's record of the rig ---

@pytest.fixture
def lab_pair(tmp_path):
    scene = lab_scene()
    for name, image in (("L.png", scene.left), ("R.png", scene.right)):
        cv2.imwrite(str(tmp_path / name), np.clip(np.rint(image), 0, 255).astype(np.uint8))
    rig = tmp_path / "rig.json"
    assert main(["rig", "--focal-px", str(scene.rig.focal_px), "--baseline-m", str(scene.rig.baseline_m),
                 "--size", f"{scene.rig.width}x{scene.rig.height}", "--out", str(rig)]) == 0
    return tmp_path, scene


def test_match_rig_writes_a_ply_that_an_independent_reader_gives_back_as_the_json(lab_pair, capsys):
    folder, scene = lab_pair
    capsys.readouterr()
    argv = ["match", folder / "L.png", folder / "R.png", "--rig", folder / "rig.json", "--roi", "full",
            "--n-min", "60", "--n-max", "80", "--json", folder / "m.json", "--ply", folder / "m.ply"]
    assert main([str(a) for a in argv]) == 0
    err = capsys.readouterr().err
    assert "already rectified: matched as given" in err and "within 1 px of their row" in err and "no measured RMS" in err
    record = json.loads((folder / "m.json").read_text())
    rig = record["rig"]
    assert rig["sha256"] == hashlib.sha256((folder / "rig.json").read_bytes()).hexdigest()
    assert rig["path"] == str(folder / "rig.json") and rig["rms_px"] is None and rig["row_tolerance_px"] == 1.0
    assert (rig["focal_px"], rig["baseline_m"]) == (scene.rig.focal_px, scene.rig.baseline_m)
    assert record["candidate_window"]["height"] == 2.0                     # the band, not widened
    points = [m for m in record["matches"] if m["xyz_m"] is not None]
    assert len(points) >= 10
    for m in record["matches"]:
        (xl, yl), (xr, yr) = m["left_xy"], m["right_xy"]
        assert m["disparity_x_px"] == pytest.approx(xl - xr)               # the one Z = f B / d takes
        assert m["disparity"] == pytest.approx(math.hypot(xl - xr, yl - yr))   # the thesis' column
        if m["xyz_m"] is not None:
            assert m["xyz_m"][2] == pytest.approx(rig["focal_px"] * rig["baseline_m"] / m["disparity_x_px"])
    cloud = read_ply((folder / "m.ply").read_bytes())
    xyz = np.column_stack([cloud["x"], cloud["y"], cloud["z"]])
    assert np.allclose(xyz, [m["xyz_m"] for m in points], rtol=1e-6, atol=1e-7)
    from ismb_lab.images.io import load_image
    grey = load_image(folder / "L.png")
    expected = [int(np.clip(np.rint(grey[int(round(m["left_xy"][1])), int(round(m["left_xy"][0]))]), 0, 255))
                for m in points]
    assert cloud["red"] == cloud["green"] == cloud["blue"] == expected
    # the rendered scene's own depth at each left corner: most points agree with it
    truth = np.array([scene.depth[int(round(m["left_xy"][1])), int(round(m["left_xy"][0]))] for m in points])
    assert np.mean(np.abs(xyz[:, 2] - truth) <= 0.05 * truth) >= 0.8


def test_ply_needs_a_rig_and_obeys_the_output_rules(lab_pair, capsys):
    folder, _ = lab_pair
    pair = [folder / "L.png", folder / "R.png"]
    one_line(["match", *pair, "--ply", folder / "m.ply"], capsys, "--ply", "--rig")
    before = (folder / "L.png").read_bytes()
    one_line(["match", *pair, "--rig", folder / "rig.json", "--ply", folder / "L.png"], capsys, "--ply")
    assert (folder / "L.png").read_bytes() == before
    one_line(["match", *pair, "--rig", folder / "rig.json", "--ply", folder / "rig.json"], capsys, "--ply")
    one_line(["match", *pair, "--rig", folder / "rig.json", "--ply", folder / "o.json", "--json", folder / "o.json"],
             capsys, "same file")
    (folder / "ro.ply").write_text("old")
    (folder / "ro.ply").chmod(0o444)
    one_line(["match", *pair, "--rig", folder / "rig.json", "--ply", folder / "ro.ply"], capsys, "read-only")
    assert not (folder / "m.ply").exists()


def test_depth_writes_its_scene_points_as_ply(tmp_path, capsys):
    from pathlib import Path

    images = Path(__file__).resolve().parents[1] / "images"
    argv = ["depth", images / "lab" / "left.png", images / "lab" / "right.png", images / "toy_cars" / "left.png",
            images / "toy_cars" / "right.png", "--json", tmp_path / "d.json", "--ply", tmp_path / "d.ply"]
    assert main([str(a) for a in argv]) == 0
    record = json.loads((tmp_path / "d.json").read_text())
    cloud = read_ply((tmp_path / "d.ply").read_bytes())
    z = np.array(cloud["z"])
    assert len(z) >= 5 and np.all(z > 0)
    depths = [o["depth_m"] for o in record["objects"] if o["depth_m"] is not None]
    assert depths and z.min() <= min(depths) * 1.05 and max(depths) * 0.95 <= z.max()
    one_line([*argv[:5], "--ply", images / "lab" / "left.png"], capsys, "--ply")
