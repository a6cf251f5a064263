"""``ismb-lab rectify`` and ``ismb-lab calibrate``: what they write, and the inputs they refuse."""

import json
import subprocess
import sys

import pytest

from ismb_lab.cli import main
from ismb_lab.images.datasets import CHESSBOARD_PAIRS


@pytest.fixture(scope="session")
def data(opencv_data):
    return opencv_data


def cli(*args):
    return subprocess.run([sys.executable, "-m", "ismb_lab.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


def test_rectify_writes_the_pair_and_its_figures(data, tmp_path):
    out = tmp_path / "books"
    assert main(["rectify", str(data / "left.jpg"), str(data / "right.jpg"), "--out", str(out)]) == 0
    record = json.loads((out / "rectify.json").read_text())
    assert {"method", "inliers", "median_abs_dy_px", "p90_abs_dy_px", "disparity_range_px", "size"} <= set(record)
    assert record["method"] == "uncalibrated" and record["median_abs_dy_px"] <= 1.0
    assert (out / "left.png").stat().st_size > 1000 and (out / "right.png").stat().st_size > 1000


@pytest.mark.slow
def test_refused_pairs_exit_2_in_one_line_and_write_nothing(data, tmp_path):
    cases = [[data / "left.jpg", data / "left.jpg"],               # the same photo twice
             [data / "left.jpg", data / "left01.jpg"],             # different sizes
             [tmp_path / "missing.jpg", data / "right.jpg"]]
    (tmp_path / "corrupt.jpg").write_bytes(b"\xff\xd8\xff\xe0garbage")
    cases.append([tmp_path / "corrupt.jpg", data / "right.jpg"])
    for n, (left, right) in enumerate(cases):
        proc = cli("rectify", left, right, "--out", tmp_path / f"out{n}")
        assert proc.returncode == 2, proc.stderr
        assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr, proc.stderr
        assert not (tmp_path / f"out{n}").exists()


@pytest.mark.slow
def test_calibrate_then_rectify_and_depth_with_the_rig(data, tmp_path):
    files = [data / f"{side}{n}.jpg" for n in CHESSBOARD_PAIRS if n != "14" for side in ("left", "right")]
    rig = tmp_path / "rig.json"
    proc = cli("calibrate", *files, "--out", rig)
    assert proc.returncode == 0, proc.stderr
    record = json.loads(rig.read_text())
    assert record["rms_px"] < 1.0 and record["baseline_m"] > 0 and record["focal_px"] > 0
    assert "RMS reprojection error" in proc.stdout
    held = cli("rectify", data / "left14.jpg", data / "right14.jpg", "--rig", rig, "--out", tmp_path / "held")
    assert held.returncode == 0, held.stderr
    record = json.loads((tmp_path / "held" / "rectify.json").read_text())
    # the rig's figures come from robust matches that never went through RANSAC: said so
    assert record["method"] == "rig" and record["measured_on"] == "robust matches (no RANSAC)"
    assert "robust matches (no RANSAC)" in held.stdout and "inliers" not in held.stdout
    proc = cli("rectify", data / "left.jpg", data / "right.jpg", "--rig", rig, "--out", tmp_path / "x")
    assert proc.returncode == 2 and "640x480" in proc.stderr and not (tmp_path / "x").exists()


@pytest.mark.slow
def test_calibrate_refusals(data, tmp_path):
    one = [data / "left01.jpg", data / "right01.jpg"]
    for args, said in (([*one, "--out", tmp_path / "r.json"], "at least 3 pairs"),
                       ([data / "left01.jpg", "--out", tmp_path / "r.json"], "in pairs"),
                       ([*one, "--board", "9by6", "--out", tmp_path / "r.json"], "--board"),
                       ([*one, "--square-m", "0", "--out", tmp_path / "r.json"], "--square-m"),
                       ([*one, "--out", data / "left01.jpg"], "left01.jpg")):
        proc = cli("calibrate", *args)
        assert proc.returncode == 2 and said in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert not (tmp_path / "r.json").exists()


@pytest.mark.slow
def test_shift_auto_measures_the_window_and_records_it(data, tmp_path):
    import numpy as np

    from ismb_lab.images.datasets import aloe
    from ismb_lab.matching.pipeline import MatchConfig, prepare

    pair = aloe(320)
    config = prepare(pair.left, pair.right, MatchConfig(shift="auto")).config
    known = pair.disparity[np.isfinite(pair.disparity)]
    lo, hi = np.percentile(known, [2, 98])
    assert lo - 2 <= config.shift <= hi + 2                     # inside the true disparities
    assert config.window_width >= 40
    out = tmp_path / "m.json"
    rect = tmp_path / "rect"
    assert main(["rectify", str(data / "left.jpg"), str(data / "right.jpg"), "--out", str(rect)]) == 0
    assert main(["match", str(rect / "left.png"), str(rect / "right.png"), "--shift", "auto", "--roi", "full",
                 "--json", str(out)]) == 0
    window = json.loads(out.read_text())["candidate_window"]
    lo, hi = json.loads((rect / "rectify.json").read_text())["disparity_range_px"]
    assert window["auto"] and window["width"] >= 40 and lo - 5 <= window["shift"] <= hi + 5
    proc = cli("match", rect / "left.png", rect / "right.png", "--shift", "sideways")
    assert proc.returncode == 2 and "--shift" in proc.stderr and "'auto'" in proc.stderr


def test_shift_auto_needs_matches():
    import numpy as np
    import pytest as _pytest

    from ismb_lab import ParameterError
    from ismb_lab.matching.pipeline import MatchConfig, prepare

    flat = np.full((120, 160), 80.0)
    flat[40:80, 50:110] = np.random.default_rng(0).uniform(0, 255, (40, 60))
    with _pytest.raises(ParameterError, match="'shift' parameter of MatchConfig must be a number of pixels"):
        prepare(flat, np.roll(flat, 40, axis=0), MatchConfig(shift="auto", n_min=5, n_max=10))
    with _pytest.raises(ParameterError, match="a number of pixels or 'auto'"):
        MatchConfig(shift="sideways")


@pytest.mark.slow
def test_depth_takes_f_and_b_from_a_rig_of_its_size(data, tmp_path):
    from pathlib import Path

    import cv2

    from ismb_lab.cameras.rig import calibrate_rig
    from ismb_lab.images.datasets import chessboard_pairs

    rig = calibrate_rig(chessboard_pairs()[:5])
    (tmp_path / "rig.json").write_text(rig.to_json())
    images = Path(__file__).resolve().parents[1] / "images"
    pairs = [images / "lab" / "left.png", images / "lab" / "right.png",
             images / "toy_cars" / "left.png", images / "toy_cars" / "right.png"]
    proc = cli("depth", *pairs, "--rig", tmp_path / "rig.json")
    assert proc.returncode == 2 and "calibrated at 640x480, the images are 320x240" in proc.stderr
    proc = cli("depth", *pairs, "--rig", tmp_path / "rig.json", "--focal-px", "300")
    assert proc.returncode == 2 and "leave out --focal-px" in proc.stderr
    big = []                                   # the same pairs at the rig's size
    for path in pairs:
        out = tmp_path / f"{path.parent.name}-{path.name}"
        cv2.imwrite(str(out), cv2.resize(cv2.imread(str(path), cv2.IMREAD_UNCHANGED), (640, 480)))
        big.append(out)
    assert main(["depth", *map(str, big), "--rig", str(tmp_path / "rig.json"), "--json", str(tmp_path / "d.json")]) == 0
    objects = json.loads((tmp_path / "d.json").read_text())["objects"]
    assert objects and all(o["depth_m"] is None or o["depth_m"] == pytest.approx(
        rig.focal_px * rig.baseline_m / o["mean_disparity"], rel=1e-6) for o in objects)
