"""`ismb-lab match` as a user runs it: a real subprocess for the contract, main() for errors."""

import json
import subprocess
import sys

import cv2
import numpy as np
import pytest

from ismb_lab.cli import main
from ismb_lab.scenes import synthetic_scene


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "ismb_lab.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


@pytest.mark.slow
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
    (lambda p, t: ["match", p[0], p[1], "--method", "VII"], "invalid choice"),
    (lambda p, t: ["match", p[0], p[1], "--theta-c", "nan"], "'theta_c'"),
    (lambda p, t: ["match", p[0], p[1], "--lambda-s", "-2"], "'lambda_s'"),
    (lambda p, t: ["match", p[0], p[1], "--roi", "300,10,50,50"], "'roi'"),
    (lambda p, t: ["match", p[0], p[1], "--roi", "10,10,0,50"], "'roi'"),
    (lambda p, t: ["match", p[0], p[1], "--n-min", "0"], "'n_min'"),
    (lambda p, t: ["match", p[0], p[1], "--params-file", t / "bad.json"], "JSON"),
    (lambda p, t: ["match", p[0], p[1], "--params-file", t / "nope.json"], "existing params file"),
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


@pytest.mark.slow   # a fresh interpreter
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


@pytest.mark.slow   # a fresh interpreter
def test_help_lists_every_option():
    proc = run_cli("match", "--help")
    assert proc.returncode == 0
    for option in ("--method", "--theta-c", "--theta-s", "--lambda-c", "--lambda-s", "--params-file",
                   "--roi", "--shift", "--n-min", "--n-max", "--seed", "--stop-rule", "--json", "--plot"):
        assert option in proc.stdout


# --- ismb-lab tune and ismb-lab evaluate ------------------------------------------------

@pytest.fixture(scope="module")
def targets(pair, tmp_path_factory):
    """Ground-truth targets of the pair, in the labeller's file format, with image hashes."""
    from ismb_lab.matching.pipeline import prepare
    from ismb_lab.scenes import true_matches
    from ismb_lab.labels.targets import save_targets, targets_from_matches

    prepared = prepare(*pair)
    truth = true_matches(synthetic_scene(seed=3), prepared.problem.left_xy, prepared.problem.right_xy)
    pairs = [(i, k) for i, k in enumerate(truth) if k >= 0]
    assert len(pairs) >= 10
    target_set = targets_from_matches(pairs, prepared.problem.left_xy, prepared.problem.right_xy,
                                      left_sha256=prepared.pair.left_sha256,
                                      right_sha256=prepared.pair.right_sha256)
    return save_targets(tmp_path_factory.mktemp("targets") / "targets.json", target_set)


def test_tune_writes_what_match_reads(pair, targets, tmp_path, capsys):
    out = tmp_path / "params.json"
    assert main(["tune", *map(str, pair), str(targets), "--generations", "15", "--seed", "2",
                 "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    assert {"method", "params", "fitness", "generations", "seed"} <= set(data)
    assert data["method"] == "III" and data["seed"] == 2 and 1 <= data["generations"] <= 15
    assert set(data["params"]) == {"theta_c", "theta_s", "lambda_c", "lambda_s"}
    n_targets = len(json.loads(targets.read_text())["pairs"])
    assert -n_targets <= data["fitness"] <= n_targets
    assert f"best fitness {data['fitness']:g} of {n_targets}" in capsys.readouterr().out

    matched = tmp_path / "m.json"
    assert main(["match", *map(str, pair), "--params-file", str(out), "--json", str(matched)]) == 0
    assert json.loads(matched.read_text())["params"] == data["params"]


def test_tune_scores_each_chromosome_over_fit_seeds_as_the_library_does(pair, targets, tmp_path):
    from ismb_lab.tuning.cases import Case
    from ismb_lab.tuning.fitness import to_params, tune

    out = tmp_path / "p.json"
    assert main(["tune", *map(str, pair), str(targets), "--generations", "6", "--seed", "3",
                 "--fit-seeds", "3", "--solver", "anneal", "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["fit_seeds"] == 3 and data["solver"] == "anneal"
    case = Case.from_files(*pair, targets)
    last = list(tune([case], "III", rng=3, generations=6, solver="anneal", seeds=3))[-1]
    assert data["params"] == to_params("III", last.best_chromosome).to_dict()
    assert data["fitness"] == last.best


def test_tune_is_reproducible_and_the_seed_matters(pair, targets, tmp_path):
    runs = []
    for name, seed in (("a", 5), ("b", 5), ("c", 6)):
        out = tmp_path / f"{name}.json"
        assert main(["tune", *map(str, pair), str(targets), "--generations", "8", "--seed", str(seed),
                     "--out", str(out)]) == 0
        runs.append(json.loads(out.read_text())["params"])
    assert runs[0] == runs[1]
    assert runs[0] != runs[2]


def test_tune_interrupted_still_writes_the_best_so_far(pair, targets, tmp_path, monkeypatch, capsys):
    import ismb_lab.tuning.fitness

    real_tune = ismb_lab.tuning.fitness.tune

    def interrupted_after_three(*args, **kwargs):
        for n, record in enumerate(real_tune(*args, **kwargs)):
            if n == 3:
                raise KeyboardInterrupt   # what Ctrl-C raises in the main thread
            yield record

    monkeypatch.setattr(ismb_lab.tuning.fitness, "tune", interrupted_after_three)
    out = tmp_path / "params.json"
    code = main(["tune", *map(str, pair), str(targets), "--generations", "400", "--out", str(out)])
    assert code == 130
    data = json.loads(out.read_text())
    assert data["interrupted"] is True and data["generations"] == 2
    assert "interrupted" in capsys.readouterr().err
    assert main(["match", *map(str, pair), "--params-file", str(out)]) == 0


@pytest.mark.slow
def test_a_real_ctrl_c_stops_tune_cleanly(pair, targets, tmp_path):
    import signal
    import time

    # Two targets with swapped partners: no chromosome reaches the target fitness, so the GA
    # cannot stop by itself before the signal.
    data = json.loads(targets.read_text())
    data["pairs"][0]["right_xy"], data["pairs"][1]["right_xy"] = (data["pairs"][1]["right_xy"],
                                                                  data["pairs"][0]["right_xy"])
    hard = tmp_path / "hard.json"
    hard.write_text(json.dumps(data))
    out = tmp_path / "params.json"
    proc = subprocess.Popen([sys.executable, "-m", "ismb_lab.cli", "tune", *map(str, pair), str(hard),
                             "--generations", "100000", "--population", "60", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # (SIGINT at its default in the child even if this run inherited it ignored, as a
    # background job of a shell does; the CLI respects an ignored SIGINT, like Python.)
    # Signal once main() has its handlers (polled in /proc, so a loaded machine only makes the
    # wait longer), then a little later: in start-up, numba's cache load or a generation.
    # Before the fix a KeyboardInterrupt raised inside numba's dispatcher could be swallowed
    # there, and the GA carried on for its 100000 generations; now every generation checks.
    status = f"/proc/{proc.pid}/status"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        try:
            caught = next(int(line.split()[1], 16) for line in open(status) if line.startswith("SigCgt"))
        except (OSError, StopIteration):
            break
        if caught >> (signal.SIGTERM - 1) & 1:
            break
        time.sleep(0.01)
    time.sleep(2)
    proc.send_signal(signal.SIGINT)
    try:
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:   # never leave a GA of 100000 generations running
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "interrupted" in stderr
    if out.exists():   # written whenever at least one generation had finished
        assert json.loads(out.read_text())["interrupted"] is True


@pytest.mark.parametrize("make_args, words", [
    (lambda p, t, g: ["tune", p[0], p[1], t / "corrupt.json"], "JSON"),
    (lambda p, t, g: ["tune", p[0], p[1], t / "truncated.json"], "JSON"),
    (lambda p, t, g: ["tune", p[0], p[1], t / "v2.json"], "'version'"),
    (lambda p, t, g: ["tune", p[0], p[1], t / "outside.json"], "inside"),
    (lambda p, t, g: ["tune", p[0], p[1], t / "other.json"], "other images"),
    (lambda p, t, g: ["tune", p[0], p[1], t / "empty.json"], "no target"),
    (lambda p, t, g: ["tune", p[0], p[1], g, "--population", "1"], "'population'"),
    (lambda p, t, g: ["tune", p[0], p[1], g, "--generations", "0"], "'generations'"),
    (lambda p, t, g: ["tune", p[0], p[1], g, "--fit-seeds", "0"], "'fit_seeds'"),
    (lambda p, t, g: ["tune", p[0], p[1], g, "--fit-seeds", "101"], "--fit-seeds 101 is above the limit"),
    (lambda p, t, g: ["evaluate", t / "missing_manifest.json"], "existing file"),
    (lambda p, t, g: ["evaluate", t / "missing_manifest.json", "--ga-seed", "-1"], "argument --ga-seed: a seed"),
    (lambda p, t, g: ["evaluate", t / "manifest_missing_file.json"], "existing file"),
])
def test_tune_and_evaluate_bad_input(pair, targets, tmp_path, capsys, make_args, words):
    good = json.loads(targets.read_text())
    (tmp_path / "corrupt.json").write_text("{not json")
    (tmp_path / "truncated.json").write_text(targets.read_text()[: len(targets.read_text()) // 2])
    (tmp_path / "v2.json").write_text(json.dumps({**good, "version": 2}))
    far = {**good, "pairs": [{"left_xy": [5000, 10], "right_xy": [10, 10]}]}
    (tmp_path / "outside.json").write_text(json.dumps(far))
    (tmp_path / "other.json").write_text(json.dumps({**good, "left_image_sha256": "0" * 64}))
    (tmp_path / "empty.json").write_text(json.dumps({"version": 1, "pairs": []}))
    (tmp_path / "manifest_missing_file.json").write_text(json.dumps(
        {"pairs": [{"left": "nope.png", "right": str(pair[1]), "targets": str(targets)}]}))
    before = targets.read_text()
    code = main([str(a) for a in make_args(pair, tmp_path, targets)])
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and err.startswith("ismb-lab: error:")
    assert words in err
    assert targets.read_text() == before


@pytest.fixture
def manifest(pair, targets, tmp_path):
    """A manifest of two pairs, "a" and "b" (the same images), beside copies of the files."""
    import shutil

    folder = tmp_path / "set"
    folder.mkdir()
    for p in (*pair, targets):
        shutil.copy(p, folder / p.name)
    entry = {"left": "left.png", "right": "right.png", "targets": "targets.json"}
    path = folder / "manifest.json"
    path.write_text(json.dumps({"pairs": [{**entry, "name": "a"}, {**entry, "name": "b"}]}))
    return path


@pytest.mark.slow
def test_evaluate_runs_the_train_test_protocol_with_peers(manifest, tmp_path, capsys):
    out = tmp_path / "report.json"
    assert main(["evaluate", str(manifest), "--generations", "6", "--seeds", "2", "--peers",
                 "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "a (training pair): Testing:" in text and "b: Testing:" in text
    report = json.loads(out.read_text())
    assert report["method"] == "III" and report["train"] == 0 and report["seeds"] == 2
    assert [row["name"] for row in report["pairs"]] == ["a", "b"]
    assert {"mutual-nn", "hungarian", "rrwm", "spectral"} <= set(report["peers"])
    for held in report["held_out"]:
        assert 0.0 <= held["recall"] <= 1.0 and 0.0 <= held["precision"] <= 1.0


@pytest.mark.slow
def test_evaluate_ga_seed_and_held_out_only(manifest, tmp_path, capsys):
    """The GA seed reaches the GA (another seed, other parameters; the same seed, the same
    report), and --held-out-only fits only the training pair without changing held-out figures."""
    reports = {}
    for name, extra in (("s0", []), ("s0-again", ["--ga-seed", "0"]), ("s7", ["--ga-seed", "7"]),
                        ("held", ["--held-out-only"])):
        out = tmp_path / f"{name}.json"
        assert main(["evaluate", str(manifest), "--generations", "4", "--seeds", "1",
                     "--json", str(out), *extra]) == 0
        reports[name] = json.loads(out.read_text())
    capsys.readouterr()
    assert reports["s0"] == reports["s0-again"] and reports["s0"]["ga_seed"] == 0
    assert reports["s7"]["ga_seed"] == 7 and reports["s7"]["params"] != reports["s0"]["params"]
    held = reports["held"]
    assert held["pairs"][1]["training"] is None and reports["s0"]["pairs"][1]["training"] is not None
    assert held["held_out"] == reports["s0"]["held_out"] and held["params"] == reports["s0"]["params"]


@pytest.mark.slow
def test_evaluate_on_two_processes_writes_the_same_report_as_on_one(manifest, tmp_path, capsys):
    reports = []
    for jobs in ("1", "2"):
        out = tmp_path / f"jobs{jobs}.json"
        assert main(["evaluate", str(manifest), "--generations", "5", "--seeds", "2", "--peers",
                     "--jobs", jobs, "--json", str(out)]) == 0
        reports.append(out.read_text())
    assert reports[0] == reports[1]
    assert main(["evaluate", str(manifest), "--jobs", "0"]) == 2
    assert "--jobs must be an integer >= 1" in capsys.readouterr().err


@pytest.mark.slow
def test_help_of_tune_and_evaluate():
    for command, options in (("tune", ("--method", "--generations", "--population", "--seed", "--roi",
                                       "--shift", "--n-min", "--n-max", "--out", "--solver", "--fit-seeds")),
                             ("evaluate", ("--method", "--train", "--seeds", "--peers", "--json", "--ga-seed",
                                           "--held-out-only"))):
        proc = run_cli(command, "--help")
        assert proc.returncode == 0
        for option in options:
            assert option in proc.stdout


def test_method_nm_round_trips_its_fifth_gene_through_tune_and_match(pair, targets, tmp_path):
    out, matched = tmp_path / "nm.json", tmp_path / "m.json"
    assert main(["tune", *map(str, pair), str(targets), "--method", "NM", "--generations", "4",
                 "--out", str(out)]) == 0
    params = json.loads(out.read_text())["params"]
    assert set(params) == {"theta_c", "theta_s", "lambda_c", "lambda_s", "match_bias"}
    assert main(["match", *map(str, pair), "--params-file", str(out), "--json", str(matched)]) == 0
    assert json.loads(matched.read_text())["params"] == params


@pytest.mark.slow
def test_evaluate_reports_the_annealed_and_exact_solvers(manifest, tmp_path, capsys):
    out = tmp_path / "report.json"
    assert main(["evaluate", str(manifest), "--generations", "3", "--seeds", "1",
                 "--solvers", "anneal", "exact", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "solver    anneal:" in text and "solver     exact:" in text
    solvers = json.loads(out.read_text())["solvers"]
    assert set(solvers) == {"anneal", "exact"}
    for rows in solvers.values():
        assert all(0.0 <= r["recall"] <= 1.0 and 0.0 <= r["precision"] <= 1.0 for r in rows)
