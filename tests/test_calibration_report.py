"""The calibration report: each pair's own error, the outlier mark, the corners kept so a
pair can be dropped without the photos, v1 rigs, and the rectified zoom's warning."""

import json
import subprocess
import sys

import cv2
import numpy as np
import pytest

from ismb_lab._core.validation import ParameterError
from ismb_lab.images.datasets import CHESSBOARD_PAIRS, chessboard_pairs
from ismb_lab.cameras.camera import MAX_ZOOM, BoardPair, load_camera
from ismb_lab.cameras.rig import calibrate_rig, leave_one_out, outliers, recalibrate


def cli(*args):
    return subprocess.run([sys.executable, "-m", "ismb_lab.cli", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


@pytest.fixture(scope="module")
def pairs(opencv_data):
    return chessboard_pairs()


@pytest.fixture(scope="module")
def rig(pairs):
    return calibrate_rig(pairs)


def files(folder, names):
    return [folder / f"{side}{n}.jpg" for n in names for side in ("left", "right")]


@pytest.fixture(scope="module")
def runs(opencv_data, tmp_path_factory):
    """The CLI on all 13 pairs, on the 12 without pair 02, and --from the first --drop .../left02.jpg."""
    out = tmp_path_factory.mktemp("calibrate")
    all13 = cli("calibrate", *files(opencv_data, CHESSBOARD_PAIRS), "--out", out / "all.json")
    direct = cli("calibrate", *files(opencv_data, [n for n in CHESSBOARD_PAIRS if n != "02"]),
                 "--out", out / "direct.json")
    dropped = cli("calibrate", "--from", out / "all.json", "--drop", opencv_data / "left02.jpg",   # as typed
                  "--out", out / "dropped.json")
    for proc in (all13, direct, dropped):
        assert proc.returncode == 0, proc.stderr
    return out, all13, direct, dropped


def pair_rms(rig, pair):
    """A pair's RMS reprojection error recomputed with cv2.projectPoints from the board's pose."""
    cols, rows = rig.board
    grid = np.zeros((rows * cols, 3), np.float32)
    grid[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * rig.square_m
    left, _ = cv2.projectPoints(grid, pair.rvec, pair.tvec, rig.k_left, rig.d_left)
    pose, _ = cv2.Rodrigues(pair.rvec)
    rvec_right, _ = cv2.Rodrigues(rig.rotation @ pose)
    tvec_right = rig.rotation @ pair.tvec.reshape(3, 1) + rig.translation.reshape(3, 1)
    right, _ = cv2.projectPoints(grid, rvec_right, tvec_right, rig.k_right, rig.d_right)
    residuals = np.concatenate([left.reshape(-1, 2) - pair.left_corners, right.reshape(-1, 2) - pair.right_corners])
    return float(np.sqrt(np.mean(np.sum(residuals ** 2, axis=1))))


def test_each_pair_has_its_own_reprojection_error_in_the_json(rig):
    record = json.loads(rig.to_json())
    assert record["format"] == "ismb_lab-rig-v2" and len(record["pairs"]) == 13
    assert [p["left"] for p in record["pairs"]] == [f"{n} left" for n in CHESSBOARD_PAIRS]
    errors = np.array([p["rms_px"] for p in record["pairs"]])
    assert len(set(errors.round(6))) == 13                       # each its own, not the rig's RMS
    assert np.sqrt(np.mean(errors ** 2)) == pytest.approx(rig.rms, rel=1e-6)
    for n in (0, 1, 12):
        assert pair_rms(rig, rig.pairs[n]) == pytest.approx(errors[n], rel=1e-4)
    assert int(np.argmax(errors)) == CHESSBOARD_PAIRS.index("02")


def test_the_rig_keeps_its_corners_through_json(rig):
    again = load_camera(rig.to_json())
    assert len(again.pairs) == len(rig.pairs)
    for a, b in zip(again.pairs, rig.pairs):
        assert a.names == b.names and a.rms_px == b.rms_px
        assert np.array_equal(a.left_corners, b.left_corners) and np.array_equal(a.tvec, b.tvec)


def test_a_v1_rig_still_loads_but_cannot_be_recalibrated(rig, tmp_path):
    record = rig.to_dict()
    v1 = {k: v for k, v in record.items() if k not in ("pairs", "zoom", "cropped")} | {"format": "ismb_lab-rig-v1"}
    path = tmp_path / "v1.json"
    path.write_text(json.dumps(v1))
    old = load_camera(path)
    assert old.pairs == () and old.focal_px == pytest.approx(rig.focal_px) and old.used == rig.used
    with pytest.raises(ParameterError, match="corners"):
        recalibrate(old, ["01 left"])
    proc = cli("calibrate", "--from", path, "--drop", "left01.jpg", "--out", tmp_path / "new.json")
    assert proc.returncode == 2 and "corners" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "new.json").exists()


@pytest.mark.slow
def test_drop_gives_the_rig_of_the_other_photos(runs):
    out, _, direct, dropped = runs
    a, b = (json.loads((out / name).read_text()) for name in ("direct.json", "dropped.json"))
    assert [p["left"] for p in b["pairs"]] == [p["left"] for p in a["pairs"]] and len(a["pairs"]) == 12
    for key in ("rms_px", "focal_px", "baseline_m", "k_left", "d_left", "k_right", "d_right", "rotation",
                "translation"):
        assert np.allclose(a[key], b[key], rtol=1e-6, atol=1e-9), key   # the same to rounding
    assert np.allclose([p["rms_px"] for p in a["pairs"]], [p["rms_px"] for p in b["pairs"]], rtol=1e-6)
    assert a["used"] == b["used"]
    assert b["rms_px"] < 0.35                                     # 0.302 px measured, from 0.448 with pair 02


@pytest.mark.slow
def test_the_table_marks_the_outlier_pair(runs):
    _, all13, _, dropped = runs
    rows = [line for line in all13.stdout.splitlines() if line.startswith("left") and ".jpg" in line]
    assert len(rows) == 13
    assert [row.split()[0] for row in rows if "outlier" in row] == ["left02.jpg"]
    assert "median" in all13.stdout                               # the rule is said where the mark is
    assert "outlier" not in dropped.stdout


def test_outlier_rule():
    make = lambda errors: [BoardPair("l", "r", [[0, 0]], [[0, 0]], e) for e in errors]
    assert outliers(make([0.2, 0.25, 0.3, 1.2])) == (3,)
    assert outliers(make([0.1, 0.1, 0.1, 0.45])) == ()           # 4.5x the median, but under 0.5 px
    assert outliers(make([0.5, 0.6, 0.55, 1.2])) == ()           # over 0.5 px, but not 3x the median


@pytest.mark.slow
def test_three_pairs_zoom_and_crop_warn_naming_the_fix(pairs, rig, opencv_data, tmp_path):
    few = calibrate_rig([p for p in pairs if p[0] in ("03", "05", "14")])
    assert few.zoom > MAX_ZOOM and few.to_dict()["zoom"] == few.zoom
    assert few.cropped() and all("more pairs" in text for text in few.warnings())
    assert rig.zoom < MAX_ZOOM and rig.warnings() == () and rig.cropped() == ()
    proc = cli("calibrate", *files(opencv_data, ("03", "05", "14")), "--out", tmp_path / "few.json")
    assert proc.returncode == 0 and "warning: the rectified views are zoomed" in proc.stderr
    assert "more pairs" in proc.stderr and "different poses" in proc.stderr


@pytest.mark.slow
def test_calibrate_from_refusals(runs, opencv_data):
    out = runs[0]
    before = (out / "all.json").read_bytes()
    for args, said in ((["--from", out / "all.json", "--drop", "left99.jpg"], "left99.jpg"),
                       (["--drop", "left02.jpg", *files(opencv_data, ("01", "03", "04"))], "--from"),
                       (["--from", out / "all.json", *files(opencv_data, ("01",))], "not both"),
                       (["--from", out / "all.json", "--board", "7x5"], "--board"),
                       (["--from", out / "all.json", "--drop", "left02.jpg", "--drop", "left01.jpg",
                         "--drop", "left03.jpg", "--drop", "left04.jpg", "--drop", "left05.jpg",
                         "--drop", "left06.jpg", "--drop", "left07.jpg", "--drop", "left08.jpg",
                         "--drop", "left09.jpg", "--drop", "left11.jpg", "--drop", "left12.jpg"], "at least 3")):
        proc = cli("calibrate", *args, "--out", out / "refused.json")
        assert proc.returncode == 2 and said in proc.stderr, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr
    proc = cli("calibrate", "--from", out / "all.json", "--out", out / "all.json")
    assert proc.returncode == 2 and (out / "all.json").read_bytes() == before
    assert not (out / "refused.json").exists()


def test_calibration_runs_opencv_on_one_thread_and_restores_its_setting(monkeypatch):
    """OpenCV's calibration on several threads gives results that differ in the 6th digit from
    run to run under load; on one thread the same corners give the same rig."""
    import ismb_lab.cameras.rig

    seen, real = [], cv2.calibrateCamera

    def calibrate_camera(*args, **kwargs):
        seen.append(cv2.getNumThreads())
        return real(*args, **kwargs)

    monkeypatch.setattr(ismb_lab.cameras.rig.cv2, "calibrateCamera", calibrate_camera)
    before = cv2.getNumThreads()
    cv2.setNumThreads(3)
    try:
        rig = calibrate_rig(chessboard_pairs()[:4])
        assert seen == [1, 1] and cv2.getNumThreads() == 3
        again = recalibrate(rig)
        assert seen == [1, 1, 1, 1]
        assert again.d_left.tobytes() == rig.d_left.tobytes() and again.rms == rig.rms
    finally:
        cv2.setNumThreads(before)


def test_drop_takes_a_path_as_typed_or_the_bare_name(rig):
    by_name = recalibrate(rig, ["02 left"])
    assert [p.left for p in by_name.pairs] == [p.left for p in rig.pairs if p.left != "02 left"]
    assert recalibrate(rig, ["boards/02 left"]).rms == by_name.rms
    with pytest.raises(ParameterError, match="Got 'boards/99 left' instead"):
        recalibrate(rig, ["boards/99 left"])


@pytest.mark.slow
def test_leave_one_out_holds_each_pair_out_and_scores_it_under_the_others(rig):
    held = leave_one_out(rig)
    assert len(held) == 13
    px = np.array([h.reprojection_px for h in held])
    assert np.isfinite(px).all() and int(np.argmax(px)) == CHESSBOARD_PAIRS.index("02")
    # held out, a board fits worse than inside the fit, pair by pair (0.19 to 1.25 px against 0.17 to 1.22)
    assert np.all(px >= np.array([p.rms_px for p in rig.pairs]) - 1e-3)
    # the figure is the pair's own under the rig without it: computed here again for one pair
    without = recalibrate(rig, ["05 left"])
    pair = rig.pairs[CHESSBOARD_PAIRS.index("05")]
    cols, rows = rig.board
    grid = np.zeros((rows * cols, 3))
    grid[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * rig.square_m
    _, rvec, tvec = cv2.solvePnP(grid, pair.left_corners, without.k_left, without.d_left)
    left, _ = cv2.projectPoints(grid, rvec, tvec, without.k_left, without.d_left)
    pose, _ = cv2.Rodrigues(rvec)
    right, _ = cv2.projectPoints(grid, cv2.Rodrigues(without.rotation @ pose)[0],
                                 without.rotation @ tvec + without.translation, without.k_right, without.d_right)
    residual = np.concatenate([left.reshape(-1, 2) - pair.left_corners, right.reshape(-1, 2) - pair.right_corners])
    assert held[CHESSBOARD_PAIRS.index("05")].reprojection_px == pytest.approx(
        np.sqrt(np.mean(np.sum(residual ** 2, axis=1))), rel=1e-5)
    depth = np.array([h.depth_error for h in held])
    assert np.all((depth >= 0) & (depth < 0.01))                   # 0.06 to 0.25 % measured
    with pytest.raises(ParameterError, match="more than 3 pairs"):
        leave_one_out(calibrate_rig(chessboard_pairs()[:3]))


@pytest.mark.slow
def test_the_report_gives_the_held_out_figures_beside_the_rms(runs):
    _, all13, _, dropped = runs
    rows = [line for line in all13.stdout.splitlines() if line.startswith("left") and ".jpg" in line]
    assert all(len(row.split()) >= 5 and row.split()[4].endswith("%") for row in rows)
    for proc in (all13, dropped):
        summary = [line for line in proc.stdout.splitlines() if line.startswith("leave-one-out:")]
        assert len(summary) == 1 and "held-out boards" in summary[0] and "median depth error" in summary[0]
    held = lambda proc: float(proc.stdout.split("RMS reprojection error ")[1].split(" px")[0])
    assert held(dropped) < held(all13)                            # 0.342 against 0.479 px measured
