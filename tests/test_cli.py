"""`ismb-lab match` as a user runs it: a real subprocess for the contract, main() for errors."""

import json
import subprocess
import sys

import cv2
import numpy as np
import pytest

from ismb_lab.cli import main
from ismb_lab.scenes import synthetic_scene


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pair")
    scene = synthetic_scene(seed=3)
    paths = []
    for name, image in (("left.png", scene.left), ("right.png", scene.right)):
        path = folder / name
        cv2.imwrite(str(path), np.clip(np.rint(image), 0, 255).astype(np.uint8))
        paths.append(path)
    return paths


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "ismb_lab.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_match_prints_the_table_and_writes_the_json_contract(pair, tmp_path):
    out, plot = tmp_path / "m.json", tmp_path / "m.png"
    proc = run_cli("match", *pair, "--json", out, "--plot", plot, "--seed", 4)
    assert proc.returncode == 0, proc.stderr
    assert "Pair  Left Right  y_left  x_left y_right x_right disparity" in proc.stdout
    data = json.loads(out.read_text())
    assert {"method", "params", "seed", "energy", "stop_rule", "left_features",
            "right_features", "matches"} <= set(data)
    assert data["method"] == "III" and data["seed"] == 4 and data["stop_rule"] == "sweep"
    assert data["params"] == {"theta_c": 17.97, "theta_s": 24.02, "lambda_c": 6.37, "lambda_s": 2.2}
    assert len(data["matches"]) > 5
    for m in data["matches"]:
        assert data["left_features"][m["left"]] == m["left_xy"]
        assert data["right_features"][m["right"]] == m["right_xy"]
        assert m["disparity"] == pytest.approx(np.hypot(*np.subtract(m["left_xy"], m["right_xy"])))
    rows = [line for line in proc.stdout.splitlines() if line[:4].strip().isdigit()]
    assert len(rows) == len(data["matches"])
    image = cv2.imread(str(plot))
    assert image is not None and image.shape[1] > image.shape[0]


def test_params_file_and_single_overrides(pair, tmp_path):
    params = tmp_path / "p.json"
    params.write_text(json.dumps({"method": "II", "params": {"theta_c": 5.0, "theta_s": 20.0,
                                  "lambda_c": 1.0, "lambda_s": 0.5}, "fitness": 12}))
    out = tmp_path / "m.json"
    assert main(["match", *map(str, pair), "--params-file", str(params), "--lambda-s", "0.75",
                 "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["method"] == "II"
    assert data["params"] == {"theta_c": 5.0, "theta_s": 20.0, "lambda_c": 1.0, "lambda_s": 0.75}


def test_same_seed_same_output_and_stop_rules(pair, tmp_path):
    a, b, c = (tmp_path / f"{n}.json" for n in "abc")
    main(["match", *map(str, pair), "--seed", "9", "--json", str(a)])
    main(["match", *map(str, pair), "--seed", "9", "--json", str(b)])
    assert a.read_text() == b.read_text()
    main(["match", *map(str, pair), "--stop-rule", "stall", "--json", str(c)])
    assert json.loads(c.read_text())["stop_rule"] in ("stall", "max_attempts")


@pytest.mark.parametrize("make_args, words", [
    (lambda p, t: ["match", t / "missing.png", p[1]], "does not exist"),
    (lambda p, t: ["match", t / "text.png", p[1]], "image"),
    (lambda p, t: ["match", p[0], t / "small.png"], "'right'"),
    (lambda p, t: ["match", p[0], p[1], "--method", "IV"], "invalid choice"),
    (lambda p, t: ["match", p[0], p[1], "--theta-c", "nan"], "'theta_c'"),
    (lambda p, t: ["match", p[0], p[1], "--lambda-s", "-2"], "'lambda_s'"),
    (lambda p, t: ["match", p[0], p[1], "--roi", "300,10,50,50"], "'roi'"),
    (lambda p, t: ["match", p[0], p[1], "--roi", "10,10,0,50"], "'roi'"),
    (lambda p, t: ["match", p[0], p[1], "--n-min", "0"], "'n_min'"),
    (lambda p, t: ["match", p[0], p[1], "--params-file", t / "bad.json"], "JSON"),
    (lambda p, t: ["match", p[0], p[1], "--params-file", t / "nope.json"], "no such file"),
    (lambda p, t: ["match", p[0], p[1], "--params-file", t / "p3.json", "--method", "II"], "conflicts"),
    (lambda p, t: ["match", p[0]], "required"),
])
def test_bad_input_is_one_line_on_stderr_with_exit_2(pair, tmp_path, capsys, make_args, words):
    (tmp_path / "text.png").write_text("not an image")
    cv2.imwrite(str(tmp_path / "small.png"), np.zeros((100, 100), np.uint8))
    (tmp_path / "bad.json").write_text("{oops")
    (tmp_path / "p3.json").write_text(json.dumps({"method": "III", "params": {}}))
    code = main([str(a) for a in make_args(pair, tmp_path)])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and err.startswith("ismb-lab: error:")
    assert words in err
    assert "Traceback" not in err


def test_a_real_process_fails_cleanly_too(pair, tmp_path):
    proc = run_cli("match", tmp_path / "missing.png", pair[1])
    assert proc.returncode == 2 and proc.stdout == ""
    assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr


def test_a_flat_pair_is_an_empty_match_not_an_error(tmp_path, capsys):
    flat = tmp_path / "flat.png"
    cv2.imwrite(str(flat), np.full((240, 320), 128, np.uint8))
    out = tmp_path / "m.json"
    assert main(["match", str(flat), str(flat), "--json", str(out)]) == 0
    assert "no corners" in capsys.readouterr().out
    assert json.loads(out.read_text())["matches"] == []


def test_help_lists_every_option():
    proc = run_cli("match", "--help")
    assert proc.returncode == 0
    for option in ("--method", "--theta-c", "--theta-s", "--lambda-c", "--lambda-s", "--params-file",
                   "--roi", "--shift", "--n-min", "--n-max", "--seed", "--stop-rule", "--json", "--plot"):
        assert option in proc.stdout
