"""One line on stderr and exit 2 for every bad input, never a traceback; a closed stderr,
a full disk or a narrow encoding breaks no command; no exit 0 with nothing useful (the sweep
of issue 42: "Tracebacks", "A closed stderr", "More than one line", "Exit 0 with nothing useful")."""

import io
import json
import os
import subprocess
import sys
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest

import ismb_lab.images.rectify
from ismb_lab import ParameterError
from ismb_lab.cli import main

ROOT = Path(__file__).resolve().parent.parent
LAB = ROOT / "images" / "lab"


def one_line(argv, capsys, match: str = "") -> str:
    """Run `argv`: exit 2, exactly one line on stderr (containing `match`), no traceback."""
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("ismb-lab: error:") and match in err, err
    return err


def synthetic_rig(board=(9, 6), square_m=0.025):
    """A rig calibrated from corners projected by a known camera pair (no photos needed)."""
    from ismb_lab.cameras.camera import BoardPair
    from ismb_lab.cameras.rig import _calibrate, board_points

    points = board_points(board, square_m).astype(np.float64)
    k = np.array([[500.0, 0, 319.5], [0, 500.0, 239.5], [0, 0, 1]])
    rng = np.random.default_rng(0)
    pairs = []
    for n in range(5):
        rvec, tvec = rng.uniform(-0.3, 0.3, 3), np.array([-0.1 + 0.02 * n, -0.06, 0.5 + 0.05 * n])
        left, _ = cv2.projectPoints(points, rvec, tvec, k, None)
        right, _ = cv2.projectPoints(points, rvec, tvec + [-0.08, 0, 0], k, None)
        pairs.append(BoardPair(f"left{n}.jpg", f"right{n}.jpg", left.reshape(-1, 2), right.reshape(-1, 2)))
    return _calibrate(pairs, tuple(f"pair{n}" for n in range(5)), (), (640, 480), board, square_m, "test")


@pytest.fixture
def rig(tmp_path):
    path = tmp_path / "rig.json"
    path.write_text(synthetic_rig().to_json())
    return path


# --- tracebacks: calibrate ---

@pytest.mark.parametrize("edit, words", [
    (lambda d: [p.update(left_corners=p["left_corners"][:5], right_corners=p["right_corners"][:5])
                for p in d["pairs"]], "54 corners"),                         # the sweep's example
    (lambda d: d["pairs"][1].update(left_corners=d["pairs"][1]["left_corners"][:-1],
                                    right_corners=d["pairs"][1]["right_corners"][:-1]), "53 corners in pair left1"),
    (lambda d: [p.update(left_corners=[[0.0, 0.0]] * 54, right_corners=[[0.0, 0.0]] * 54)
                for p in d["pairs"]], "OpenCV"),                             # corners no camera saw
    (lambda d: d.update(square_m=-1), "'square_m'"),                         # 3.34 m baseline before
    (lambda d: d.update(square_m=1e308), "'square_m'"),
    (lambda d: d.update(board=[1, 6]), "'board'"),
    (lambda d: d.update(board=[9.5, 6]), "'board'"),
    (lambda d: d.update(rms_px=int("9" * 4000)), "'rms_px'"),
])
def test_calibrate_from_a_broken_rig_says_why_in_one_line(rig, tmp_path, capsys, edit, words):
    data = json.loads(rig.read_text())
    edit(data)
    rig.write_text(json.dumps(data))
    one_line(["calibrate", "--from", rig, "--drop", "left2.jpg", "--out", tmp_path / "new.json"], capsys, words)
    assert not (tmp_path / "new.json").exists()


def test_a_rig_with_a_negative_square_is_refused_wherever_it_is_read(rig, work, capsys):
    data = json.loads(rig.read_text())
    rig.write_text(json.dumps({**data, "square_m": -1}))
    for argv in (["match", work / "L.png", work / "R.png", "--rig", rig],
                 ["depth", work / "L.png", work / "R.png", work / "L.png", work / "R.png", "--rig", rig],
                 ["rectify", work / "L.png", work / "R.png", "--rig", rig, "--out", work / "rect"]):
        one_line(argv, capsys, "'square_m'")


@pytest.mark.parametrize("option, value, words", [
    ("--square-m", "1e308", "--square-m"), ("--square-m", "1e-300", "--square-m"), ("--square-m", "nan", "--square-m"),
    ("--square-m", "-1", "--square-m"), ("--board", "99999999999999999999x6", "--board"), ("--board", "1x6", "--board"),
    ("--board", "101x6", "--board"), ("--board", "9x6x2", "--board"), ("--board", "9" * 5000 + "x6", "--board"),
])
def test_calibrate_refuses_a_board_or_square_out_of_range_before_reading_photos(work, capsys, monkeypatch, option,
                                                                                value, words):
    import ismb_lab.cameras.rig

    monkeypatch.setattr(ismb_lab.cameras.rig, "find_board", lambda *a: pytest.fail("photos read before the check"))
    photos = [work / "L.png", work / "R.png"] * 3
    one_line(["calibrate", *photos, option, value, "--out", work / "rig.json"], capsys, words)


def test_the_library_checks_the_board_and_square_too():
    from ismb_lab.cameras.camera import MAX_SQUARE_M, MIN_SQUARE_M, check_board
    from ismb_lab.cameras.rig import calibrate_rig

    for board, square in (((9, 6), 1e308), ((9, 6), 0.0), ((99999999999999999999, 6), 0.025), ((1, 6), 0.025)):
        with pytest.raises((ParameterError, TypeError)):
            calibrate_rig([], board, square)
    assert check_board((9, 6), MIN_SQUARE_M, "x") == ((9, 6), MIN_SQUARE_M)
    assert check_board([100, 2], MAX_SQUARE_M, "x") == ((100, 2), MAX_SQUARE_M)
    # the range holds real calibrations: the same corners at its ends give the same rig, scaled
    from ismb_lab.cameras.rig import _calibrate

    rig = synthetic_rig()
    for square in (MIN_SQUARE_M, MAX_SQUARE_M):
        scaled = _calibrate(list(rig.pairs), rig.used, (), rig.size, rig.board, square, "test")
        assert scaled.baseline_m / square == pytest.approx(rig.baseline_m / 0.025, rel=1e-4)


# --- tracebacks: numbers too long for Python, in every JSON file read ---

def test_a_number_of_thousands_of_digits_in_any_file_is_one_line(work, rig, capsys):
    huge = "9" * 4400
    (work / "Mbig.json").write_text('{"pairs": [{"name": "x", "shift": ' + huge + "}]}")
    one_line(["evaluate", work / "Mbig.json"], capsys, "4300 digits")
    (work / "Pbig.json").write_text('{"params": {"theta_c": ' + huge + "}}")
    one_line(["match", work / "L.png", work / "R.png", "--params-file", work / "Pbig.json"], capsys, "4300 digits")
    one_line(["evaluate", work / "M.json", "--recipe", work / "Pbig.json"], capsys, "4300 digits")
    rig.write_text(rig.read_text()[:-1] + ', "extra": ' + huge + "}")
    one_line(["calibrate", "--from", rig, "--out", work / "new.json"], capsys, "4300 digits")
    targets = json.loads((work / "T.json").read_text())
    (work / "Tbig.json").write_text(json.dumps(targets)[:-1] + ', "extra": ' + huge + "}")
    one_line(["tune", work / "L.png", work / "R.png", work / "Tbig.json"], capsys)


# --- streams: a full disk, a closed stderr, a narrow encoding ---

def run_cli(*args, env=None, **kwargs):
    return subprocess.run([sys.executable, "-c", "from ismb_lab.cli import main; raise SystemExit(main())",
                           *map(str, args)], text=True, capture_output=True, timeout=300, cwd=ROOT,
                          env={**os.environ, **(env or {})}, **kwargs)


@pytest.mark.slow   # fresh interpreters
@pytest.mark.parametrize("command", [
    lambda w: ["match", w / "L.png", w / "R.png", "--json", w / "out.json"],
    lambda w: ["targets", "merge", w / "T.json", "--out", w / "out.json"],
])
def test_a_stdout_that_refuses_writes_is_one_line_and_exit_2(work, command):
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "ismb_lab.cli", *map(str, command(work))], stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.splitlines() == ["ismb-lab: error: cannot write the output to stdout: No space left on device"]
    assert json.loads((work / "out.json").read_text())   # the file the command wrote is whole


def test_a_write_error_on_stdout_in_process_is_reported_once(work, capsys, monkeypatch):
    class Full(io.StringIO):
        def flush(self):
            raise OSError(28, "No space left on device")

    monkeypatch.setattr(sys, "stdout", Full())
    assert main(["targets", "merge", str(work / "T.json"), "--out", str(work / "out.json")]) == 2
    err = capsys.readouterr().err
    assert err == "ismb-lab: error: cannot write the output to stdout: No space left on device\n"


@pytest.mark.slow   # fresh interpreters
@pytest.mark.parametrize("closed", ["2>&-", ">&-", "2>&- >&-"])
@pytest.mark.parametrize("command", [
    "match {w}/L.png {w}/R.png --json {w}/out.json",
    "tune {w}/L.png {w}/R.png {w}/T.json --generations 1 --population 4 --out {w}/out.json",   # tqdm on stderr
    "targets merge {w}/T.json --out {w}/out.json",
])
def test_a_closed_stream_breaks_no_command(work, closed, command):
    """``match ... 2>&-`` exited 1 and wrote nothing: sys.stderr was None."""
    line = f"{sys.executable} -m ismb_lab.cli {command.format(w=work)} {closed}"
    proc = subprocess.run(["bash", "-c", line], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0
    assert json.loads((work / "out.json").read_text())


def test_a_closed_stderr_in_process(work, monkeypatch):
    monkeypatch.setattr(sys, "stderr", None)
    assert main(["match", str(work / "L.png"), str(work / "R.png"), "--json", str(work / "out.json")]) == 0
    assert main(["match", str(work / "L.png"), "--no-such-option"]) == 2
    assert sys.stderr is None


@pytest.mark.parametrize("name", ["ñandú.json", "目标.json", "\u2603.json"])
def test_a_name_the_encoding_cannot_show_is_escaped_not_a_crash(work, monkeypatch, name):
    raw = io.BytesIO()
    monkeypatch.setattr(sys, "stdout", io.TextIOWrapper(raw, encoding="ascii"))
    out = work / name
    assert main(["targets", "merge", str(work / "T.json"), "--out", str(out)]) == 0
    sys.stdout.flush()
    assert json.loads(out.read_text())
    assert "written to" in raw.getvalue().decode("ascii") and "\\" in raw.getvalue().decode("ascii")


@pytest.mark.slow   # a fresh interpreter
def test_pythonioencoding_ascii_with_a_non_ascii_output_name(work):
    proc = run_cli("targets", "merge", work / "T.json", "--out", work / "ñandú.json",
                   env={"PYTHONIOENCODING": "ascii"})
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    assert "written to" in proc.stdout


# --- Ctrl-C while the workers start ---

def _blocked():
    import signal
    return sorted(int(s) for s in signal.pthread_sigmask(signal.SIG_BLOCK, []))


@pytest.mark.slow   # a worker process
def test_a_worker_is_born_with_ctrl_c_blocked():
    """A worker still importing when Ctrl-C reached the process group printed a traceback:
    workers are started with SIGINT blocked, and keep it so; the parent gets it back."""
    import signal

    from ismb_lab.tuning.cases import _starting_workers, _workers

    before = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    with _workers(2) as pool:
        with _starting_workers():
            future = pool.submit(_blocked)
        assert signal.pthread_sigmask(signal.SIG_BLOCK, []) == before
        assert int(signal.SIGINT) in future.result(timeout=120)


@pytest.mark.slow   # several runs of evaluate with two workers
def test_ctrl_c_as_evaluate_starts_its_workers_prints_one_line(hard_manifest):
    import signal
    import time

    for delay in (0.0, 0.1, 0.3):
        proc = subprocess.Popen([sys.executable, "-m", "ismb_lab.cli", "evaluate", str(hard_manifest), "--jobs", "2",
                                 "--generations", "50", "--population", "6", "--seeds", "1"], cwd=ROOT,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                                # as from a terminal: a run started as a background job inherits
                                # SIGINT ignored, which the command rightly leaves ignored
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:   # until both workers exist
            children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()
            if len(children) >= 2:
                break
            time.sleep(0.01)
        time.sleep(delay)
        os.killpg(proc.pid, signal.SIGINT)   # what a terminal's Ctrl-C does: the whole group
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 130, err
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err


# --- more than one line: codecs' own messages, warnings, late checks ---

def _png_chunks(data: bytes):
    at = 8
    while at < len(data):
        size = int.from_bytes(data[at:at + 4], "big")
        yield at, data[at + 4:at + 8], size
        at += 12 + size


@pytest.mark.parametrize("damage", ["ihdr-crc", "truncated", "idat-bytes"])
def test_a_broken_png_is_one_line_with_the_codec_s_own_words(work, capfd, damage):
    from ismb_lab.images.io import load_image

    data = bytearray((work / "L.png").read_bytes())
    if damage == "ihdr-crc":
        data[29] ^= 0xFF
    elif damage == "truncated":
        data = data[:len(data) // 2]
    else:
        at, _, size = next(c for c in _png_chunks(bytes(data)) if c[1] == b"IDAT")
        data[at + 8:at + 8 + size] = zlib.compress(b"\1" * 7) + bytes(size - len(zlib.compress(b"\1" * 7)))
        data[at + 8 + size:at + 12 + size] = zlib.crc32(bytes(data[at + 4:at + 8 + size])).to_bytes(4, "big")
    broken = work / "broken.png"
    broken.write_bytes(bytes(data))
    capfd.readouterr()
    with pytest.raises(ParameterError, match="OpenCV cannot decode it as a PNG image"):
        load_image(broken)
    assert capfd.readouterr().err == ""   # libpng's words are in the message, not on stderr
    assert main(["match", str(broken), str(work / "R.png")]) == 2
    err = capfd.readouterr().err
    assert err.count("\n") == 1 and "libpng" in err, err


def test_a_good_image_decodes_as_before_and_keeps_what_its_codec_said(work, capfd):
    from ismb_lab.images.io import _imdecode, load_image

    data = (work / "L.png").read_bytes()
    image, said = _imdecode(data, cv2.IMREAD_UNCHANGED)
    assert said == "" and np.array_equal(image, cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED))
    assert load_image(work / "L.png").shape == (240, 320)
    assert capfd.readouterr().err == ""


@pytest.mark.parametrize("option, value", [("--theta-c", "1e308"), ("--theta-s", "1001"), ("--lambda-s", "1e308"),
                                           ("--lambda-c", "1000.5")])
def test_parameters_beyond_their_range_are_refused_without_a_warning(work, capfd, option, value):
    assert main(["match", str(work / "L.png"), str(work / "R.png"), option, value]) == 2
    err = capfd.readouterr().err
    assert err.count("\n") == 1 and "RuntimeWarning" not in err and option[2:].replace("-", "_") in err, err


def test_the_parameter_range_is_documented_and_holds_its_ends():
    from ismb_lab.network.params import MAX_BIAS, MAX_LAMBDA, MAX_THETA, Params
    from ismb_lab.network.similarity import transfer

    Params(theta_c=MAX_THETA, theta_s=0.0, lambda_c=MAX_LAMBDA, lambda_s=1e-300, match_bias=-MAX_BIAS)
    for bad in ({"theta_c": MAX_THETA * 1.0001}, {"lambda_s": 1e308}, {"match_bias": 1e308},
                {"match_bias": -MAX_BIAS - 1}, {"theta_s": float("inf")}):
        with pytest.raises(ParameterError):
            Params(**bad)
    with np.errstate(all="raise"):   # no overflow warning even at the ends of the range
        assert transfer([0.0, 1e6], MAX_THETA, MAX_LAMBDA).tolist() == [1.0, -1.0]


@pytest.mark.parametrize("option", [
    ["--roi", "1,2,3"], ["--roi", "0,0,5000,10"], ["--roi", "-1,0,10,10"], ["--roi", "a,b,c,d"],
    ["--roi", "1" * 5000 + ",0,1,1"], ["--shift", "1e308"], ["--shift", "-1e308"], ["--shift", "1000"],
    ["--match-bias", "0.5"],
])
def test_match_checks_every_option_before_its_rectification_check(work, capsys, monkeypatch, option):
    """A bad --roi cost a full look for robust matches and printed its warning first."""
    monkeypatch.setattr(ismb_lab.images.rectify, "check_for_matching", lambda *a: pytest.fail("checked the pair first"))
    one_line(["match", work / "L.png", work / "R.png", *option], capsys)


# --- exit 0 with nothing useful ---

def test_a_shift_beyond_the_image_blames_the_shift_not_the_image(work, capsys):
    err = one_line(["match", work / "L.png", work / "R.png", "--shift", "1e308"], capsys, "'shift'")
    assert "local maximum" not in err
    one_line(["depth", work / "L.png", work / "R.png", work / "L.png", work / "R.png", "--shift", "-400"],
             capsys, "'shift'")
    assert main(["match", str(work / "L.png"), str(work / "R.png"), "--shift", "339"]) == 0   # 320 - 1 + 40 / 2
    capsys.readouterr()


def test_a_flat_pair_is_known_at_once(tmp_path, capsys, monkeypatch):
    """Two black 5000 x 5000 PNGs took 46 s and 2.3 GB for "0 matches": a flat image is seen
    before the look for robust matches and before the Harris response."""
    import ismb_lab.images.features

    black = tmp_path / "black.png"
    cv2.imwrite(str(black), np.zeros((3000, 3000), np.uint8))
    monkeypatch.setattr(ismb_lab.images.rectify, "check_for_matching", lambda *a: pytest.fail("looked for matches"))
    monkeypatch.setattr(ismb_lab.images.features, "harris_response", lambda *a: pytest.fail("computed R"))
    out = tmp_path / "m.json"
    assert main(["match", str(black), str(black), "--json", str(out), "--roi", "full"]) == 0
    assert "the image is flat" in capsys.readouterr().out
    assert json.loads(out.read_text())["matches"] == []


def test_a_one_pair_manifest_is_refused_not_reported_as_nan(work, capsys, monkeypatch):
    import ismb_lab.tuning.cases

    one_line(["evaluate", work / "M1.json", "--generations", "1", "--jobs", "1"], capsys, "at least two pairs")
    monkeypatch.setattr(ismb_lab.tuning.cases, "tune", lambda *a, **k: pytest.fail("fitted before the refusal"))
    cases = ismb_lab.tuning.cases.load_manifest(work / "M1.json")
    with pytest.raises(ParameterError, match="at least two pairs"):
        ismb_lab.tuning.cases.protocol(cases)


def test_a_held_out_total_without_targets_says_so_instead_of_nan():
    from ismb_lab.tuning.evaluation import Score
    from ismb_lab.tuning.cases import _figures

    assert _figures(Score(0, 0, 0, 0)).endswith("C/T - (no targets)   precision - (no matches)")
    assert "nan" not in _figures(Score(0, 0, 0, 0))
    assert _figures(Score(3, 1, 0, 4)).endswith("C/T 75.0%   precision 75.0%")


# --- the API: a clear error naming the parameter, the rule and the value ---

@pytest.mark.parametrize("call, words", [
    (lambda: __import__("ismb_lab.images.io", fromlist=["orient"]).orient(np.zeros((2, 2)), 9), "'orientation'"),
    (lambda: __import__("ismb_lab.images.io", fromlist=["orient"]).orient(np.zeros((2, 2)), 0), "'orientation'"),
    (lambda: __import__("ismb_lab.images.io", fromlist=["orient"]).orient(np.zeros(3), 1), "'image'"),
    (lambda: __import__("ismb_lab.images.io", fromlist=["png_bytes"]).png_bytes(np.zeros((0, 0))), "'image'"),
    (lambda: __import__("ismb_lab.images.io", fromlist=["png_bytes"]).png_bytes(np.zeros((3, 0))), "'image'"),
    (lambda: __import__("ismb_lab.images.io", fromlist=["png_bytes"]).png_bytes(np.full((2, 2), np.nan)), "'image'"),
    (lambda: __import__("ismb_lab.network.similarity", fromlist=["transfer"]).transfer([1.0], float("nan"), 1.0), "'theta'"),
    (lambda: __import__("ismb_lab.network.similarity", fromlist=["transfer"]).transfer([1.0], 1.0, float("inf")), "'lam'"),
    (lambda: __import__("ismb_lab.network.similarity", fromlist=["transfer"]).transfer([1.0], np.array([[np.nan]]), 1.0),
     "'theta'"),
])
def test_the_api_names_the_parameter_rule_and_value(call, words):
    with pytest.raises((ParameterError, TypeError), match=words):
        call()


def test_orient_png_bytes_and_transfer_are_unchanged_on_good_values():
    from ismb_lab.images.io import orient, png_bytes
    from ismb_lab.network.similarity import transfer

    image = np.arange(6.0).reshape(2, 3)
    assert orient(image, 6).tolist() == [[3.0, 0.0], [4.0, 1.0], [5.0, 2.0]]
    assert png_bytes(np.full((2, 2), 300.4))[1:4] == b"PNG"
    theta = np.array([[10.0], [20.0]])
    assert np.array_equal(transfer(np.array([5.0, 15.0]), theta, 2.0),
                          -np.tanh(0.5 * 2.0 * (np.array([5.0, 15.0]) - theta)))


def test_what_opencv_still_refuses_is_one_line(work, capsys, monkeypatch):
    """The last guard of the class "tracebacks": a cv2.error no check foresaw is the input's."""
    import ismb_lab.matching.pipeline

    def refuses(*args, **kwargs):
        cv2.calibrateCamera([], [], (1, 1), None, None)   # raises cv2.error

    monkeypatch.setattr(ismb_lab.matching.pipeline, "prepare", refuses)
    err = one_line(["match", work / "L.png", work / "R.png"], capsys, "OpenCV cannot work with this input")
    assert "nimages > 0" in err
