"""`ismb-lab depth` as a user runs it: the committed pairs, the JSON contract and bad input."""

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from ismb_lab.cli import main

IMAGES = Path(__file__).resolve().parent.parent / "images"
BG = [IMAGES / "lab" / "left.png", IMAGES / "lab" / "right.png"]
CARS = [IMAGES / "toy_cars" / "left.png", IMAGES / "toy_cars" / "right.png"]


@pytest.mark.slow
def test_depth_ranks_the_left_car_first_and_writes_json_and_plot(tmp_path):
    out, plot = tmp_path / "d.json", tmp_path / "d.png"
    proc = subprocess.run([sys.executable, "-m", "ismb_lab.cli", "depth", *map(str, BG + CARS),
                           "--json", str(out), "--plot", str(plot)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    data = json.loads(out.read_text())
    objects = data["objects"]
    assert data["background_removed"] >= 5 and len(objects) >= 2
    assert [o["mean_disparity"] for o in objects] == sorted((o["mean_disparity"] for o in objects),
                                                            reverse=True)
    for o in objects:
        assert set(o) >= {"centroid_xy", "mean_disparity", "depth_m", "features"}
        assert o["depth_m"] == pytest.approx(300 * 0.1 / o["mean_disparity"])
    # The nearest object lies on the left car (left half of the view), in front of the box.
    first = objects[0]
    assert first["centroid_xy"][0] < 160 and first["depth_m"] < 1.3
    # With the defaults fitted on images/lab: the two cars and nothing else (0.885 and 1.183 m).
    assert len(objects) == 2 and objects[1]["centroid_xy"][0] > 160
    assert [o["depth_m"] for o in objects] == pytest.approx([0.885, 1.183], rel=0.10)
    rows = [line for line in proc.stdout.splitlines() if line.startswith("#")]
    assert len(rows) == len(objects) and rows[0].startswith("#1 ")
    image = cv2.imread(str(plot))
    assert image is not None and image.shape[0] > 100
    # Each car is one blob of change, and its features agree with the blob's shift.
    assert data["grouping"] == "silhouettes"
    for o, row in zip(objects, rows):
        assert o["silhouette_score"] >= 0.9 and abs(o["mean_disparity"] - o["silhouette_disparity"]) <= 3
        assert row.endswith(f"outline {o['silhouette_disparity']:.0f} px")


@pytest.mark.slow
def test_grouping_by_features_alone_is_the_thesis_variant(tmp_path):
    out = tmp_path / "d.json"
    proc = subprocess.run([sys.executable, "-m", "ismb_lab.cli", "depth", *map(str, BG + CARS),
                           "--grouping", "features", "--json", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    data = json.loads(out.read_text())
    assert data["grouping"] == "features" and len(data["objects"]) == 2
    assert all(o["silhouette_disparity"] is None for o in data["objects"])
    assert [o["depth_m"] for o in data["objects"]] == pytest.approx([0.885, 1.183], rel=0.10)
    bad = subprocess.run([sys.executable, "-m", "ismb_lab.cli", "depth", *map(str, BG + CARS),
                          "--grouping", "blobs"], capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "--grouping" in bad.stderr and "Traceback" not in bad.stderr


def test_calibration_options_scale_the_depth(tmp_path):
    out = tmp_path / "d.json"
    assert main(["depth", *map(str, BG + CARS), "--focal-px", "600", "--baseline-m", "0.2",
                 "--json", str(out)]) == 0
    for o in json.loads(out.read_text())["objects"]:
        assert o["depth_m"] == pytest.approx(600 * 0.2 / o["mean_disparity"])


def test_a_scene_identical_to_the_background_has_no_objects(capsys):
    assert main(["depth", *map(str, BG + BG)]) == 0
    assert "no objects" in capsys.readouterr().out


def write(path, image):
    cv2.imwrite(str(path), image.astype(np.uint8))
    return str(path)


@pytest.mark.parametrize("args, words", [
    (["--focal-px", "-300"], "--focal-px must be a finite number > 0"),
    (["--focal-px", "0"], "--focal-px must be a finite number > 0"),
    (["--baseline-m", "0"], "--baseline-m must be a finite number > 0"),
    (["--baseline-m", "-0.1"], "--baseline-m must be a finite number > 0"),
])
def test_bad_calibration_exits_2_with_one_line(args, words, capsys):
    assert main(["depth", *map(str, BG + CARS), *args]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err


def test_pairs_of_different_sizes_exit_2(tmp_path, capsys):
    small = cv2.imread(str(CARS[0]), cv2.IMREAD_GRAYSCALE)[:200, :300]
    paths = [write(tmp_path / "l.png", small), write(tmp_path / "r.png", small)]
    assert main(["depth", *map(str, BG), *paths]) == 2
    err = capsys.readouterr().err
    assert "300x200" in err and "320x240" in err and err.count("\n") == 1


def test_no_matches_says_so_and_exits_2(tmp_path, capsys):
    flat = np.full((240, 320), 128.0)
    paths = [write(tmp_path / "l.png", flat), write(tmp_path / "r.png", flat)]
    assert main(["depth", *map(str, BG), *paths]) == 2
    err = capsys.readouterr().err
    assert "no matches in the scene pair" in err and err.count("\n") == 1


def test_a_plain_background_is_a_note_with_silhouettes_and_an_error_without(tmp_path, capsys):
    rng = np.random.default_rng(3)
    wall = np.full((240, 320), 100.0)                  # no corners at all
    left, right = wall.copy(), wall.copy()
    left[100:150, 120:170] = right[100:150, 100:150] = rng.integers(0, 2, (50, 50)) * 200.0 + 20
    paths = [write(tmp_path / f"{n}.png", a) for n, a in (("bl", wall), ("br", wall), ("sl", left),
                                                        ("sr", right))]
    out = tmp_path / "d.json"
    assert main(["depth", *paths, "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "note: no matches in the background pair" in printed
    (obj,) = json.loads(out.read_text())["objects"]
    assert obj["silhouette_disparity"] == 20.0 and abs(obj["mean_disparity"] - 20.0) <= 1
    assert main(["depth", *paths, "--grouping", "features"]) == 2
    err = capsys.readouterr().err
    assert "no matches in the background pair" in err and err.count("\n") == 1


def test_missing_file_exits_2(tmp_path, capsys):
    assert main(["depth", *map(str, BG), str(tmp_path / "nope.png"), str(CARS[1])]) == 2
    assert capsys.readouterr().err.startswith("ismb-lab: error:")


def test_the_command_agrees_with_the_library_demo_and_can_use_the_plain_network(tmp_path):
    from ismb_lab.depth.pipeline import relative_depth

    out, plain = tmp_path / "d.json", tmp_path / "n.json"
    assert main(["depth", *map(str, BG + CARS), "--json", str(out)]) == 0
    demo = relative_depth(BG, CARS).to_dict()
    written = json.loads(out.read_text())
    assert written["objects"] == json.loads(json.dumps(demo["objects"]))
    assert written["scene_roi"] == demo["scene_roi"] and demo["scene_roi"] is not None
    assert main(["depth", *map(str, BG + CARS), "--solver", "network", "--json", str(plain)]) == 0
    objects = json.loads(plain.read_text())["objects"]
    assert objects and objects[0]["centroid_xy"][0] < 160
