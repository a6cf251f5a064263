"""``match --rig`` and ``depth --rig`` on OpenCV's chessboard rig: metres for every match, or a refusal."""

import json
import subprocess
import sys

import numpy as np
import pytest

from ismb_lab.cameras.camera import load_camera
from ismb_lab.images.datasets import CHESSBOARD_PAIRS
from ismb_lab.cameras.rig import calibrate_rig, recalibrate


def cli(*args):
    return subprocess.run([sys.executable, "-m", "ismb_lab.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=600)


@pytest.fixture(scope="module")
def full(opencv_data):
    return calibrate_rig([(n, opencv_data / f"left{n}.jpg", opencv_data / f"right{n}.jpg") for n in CHESSBOARD_PAIRS])


@pytest.fixture(scope="module")
def without_14(full, tmp_path_factory):
    path = tmp_path_factory.mktemp("rig") / "rig.json"
    path.write_text(recalibrate(full, ["14"]).to_json())
    return path


@pytest.mark.slow   # the module's rig fixture calibrates 13 pairs (about 10 s)
def test_match_rig_rectifies_raw_photos_and_gives_every_match_its_point(opencv_data, without_14, tmp_path):
    out = tmp_path / "m.json"
    proc = cli("match", opencv_data / "left14.jpg", opencv_data / "right14.jpg", "--rig", without_14,
               "--shift", "auto", "--roi", "full", "--json", out)
    assert proc.returncode == 0, proc.stderr
    assert "raw photos, rectified with the rig" in proc.stderr
    matches = json.loads(out.read_text())["matches"]
    assert matches and all(m["xyz_m"] is not None for m in matches)
    camera = load_camera(without_14)
    for m in matches:                      # Z = f B / d, X and Y on the left corner's ray
        x, y = m["left_xy"]
        d = x - m["right_xy"][0]
        X, Y, Z = m["xyz_m"]
        assert Z == pytest.approx(camera.focal_px * camera.baseline_m / d)
        assert X == pytest.approx((x - camera.rectified_centre[0]) * Z / camera.focal_px)
        assert Y == pytest.approx((y - camera.rectified_centre[1]) * Z / camera.focal_px)
        assert abs(m["left_xy"][1] - m["right_xy"][1]) <= 2 * camera.rms    # sub-pixel, on their rows
    assert any(x != round(x) for m in matches for x in m["left_xy"])
    assert "matches in metres" in proc.stdout


@pytest.mark.slow   # the module's rig fixture calibrates 13 pairs (about 10 s)
def test_match_rig_keeps_a_rectified_pair_and_says_so(opencv_data, without_14, tmp_path):
    rect = tmp_path / "rect"
    proc = cli("rectify", opencv_data / "left14.jpg", opencv_data / "right14.jpg", "--rig", without_14, "--out", rect)
    assert proc.returncode == 0, proc.stderr
    proc = cli("match", rect / "left.png", rect / "right.png", "--rig", without_14, "--roi", "full",
               "--json", tmp_path / "m.json")
    assert proc.returncode == 0, proc.stderr
    assert "already rectified" in proc.stderr and "rectified with the rig" not in proc.stderr
    assert json.loads((tmp_path / "m.json").read_text())["candidate_window"]["auto"]    # --shift auto by default


@pytest.mark.slow   # the module's rig fixture calibrates 13 pairs (about 10 s)
def test_match_rig_refuses_photos_of_another_size(opencv_data, without_14):
    proc = cli("match", opencv_data / "aloeL.jpg", opencv_data / "aloeR.jpg", "--rig", without_14)
    assert proc.returncode == 2 and "calibrated at" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


@pytest.mark.slow   # the module's rig fixture calibrates 13 pairs (about 10 s)
def test_depth_rig_measures_the_window_or_refuses(opencv_data, without_14, tmp_path):
    rect = tmp_path / "rect"
    assert cli("rectify", opencv_data / "left14.jpg", opencv_data / "right14.jpg", "--rig", without_14,
               "--out", rect).returncode == 0
    pair = (rect / "left.png", rect / "right.png")
    fixed = cli("depth", *pair, *pair, "--rig", without_14, "--shift", "20")
    assert fixed.returncode == 2 and "leave out --shift" in fixed.stderr
    assert len(fixed.stderr.strip().splitlines()) == 1
    measured = cli("depth", *pair, *pair, "--rig", without_14, "--json", tmp_path / "d.json")
    assert measured.returncode == 0, measured.stderr
    window = json.loads((tmp_path / "d.json").read_text())["candidate_window"]
    assert window["auto"] and window["height"] == pytest.approx(2 * (1 + 2 * load_camera(without_14).rms))
    import cv2
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((480, 640), 128, np.uint8))
    refused = cli("depth", blank, blank, *pair, "--rig", without_14)
    assert refused.returncode == 2 and "no disparity range" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_held_out_boards_get_their_plane_through_the_command_line(opencv_data, load_script):
    """Pairs 01-03, 09 and 12 held out in turn (issue 27's rule; all 13 are in the experiment record)."""
    script = load_script("board_metres")
    full = calibrate_rig([(n, opencv_data / f"left{n}.jpg", opencv_data / f"right{n}.jpg") for n in CHESSBOARD_PAIRS])
    import tempfile
    from pathlib import Path
    with tempfile.TemporaryDirectory() as tmp:
        rows = [script.held_out(full, name, opencv_data, Path(tmp), script.N_MIN, script.N_MAX)
                for name in ("01", "02", "03", "09", "12")]
    for row in rows:
        assert row["rectified_by_rig"]
        assert row["board_matches"] >= 20 and row["share"] >= 0.90, row


@pytest.mark.slow   # the module's rig fixture calibrates 13 pairs (about 10 s)
def test_the_plane_score_counts_only_board_matches_and_fails_wrong_depths(opencv_data, full, load_script):
    script = load_script("board_metres")
    camera = recalibrate(full, ["14"])
    from ismb_lab.images.rectify import load_photo
    raw = load_photo(opencv_data / "left14.jpg")
    normal, c, outline = script.board_plane(camera, raw)
    centre = outline.mean(axis=0)
    f, (cx, cy) = camera.focal_px, camera.rectified_centre
    z = c / float(normal @ [(centre[0] - cx) / f, (centre[1] - cy) / f, 1.0])
    on = {"left_xy": centre.tolist(), "xyz_m": [0.0, 0.0, z]}
    off = {"left_xy": centre.tolist(), "xyz_m": [0.0, 0.0, 1.2 * z]}
    outside = {"left_xy": [1.0, 1.0], "xyz_m": [0.0, 0.0, z]}
    result = script.score(camera, raw, [on] * 19 + [off] + [outside] * 5)
    assert (result["board_matches"], result["on_plane"], result["passes"]) == (20, 19, True)
    assert not script.score(camera, raw, [on] * 17 + [off] * 3)["passes"]       # 85%
    assert not script.score(camera, raw, [on] * 19)["passes"]                   # too few


def test_the_script_says_what_it_does(load_script, capsys):
    with pytest.raises(SystemExit) as stop:
        load_script("board_metres").main(["--help"])
    assert stop.value.code == 0 and "leave one pair out" in capsys.readouterr().out.lower()
