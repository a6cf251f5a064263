"""Every limit bounds the work before it starts, whether the value comes from an option, a
file or the environment (the sweep of issue 42, "Limits that bound nothing")."""

import json
from pathlib import Path

import numpy as np
import pytest

import ismb_lab.matching.pipeline
import ismb_lab.tuning.cases
from ismb_lab import ParameterError
from ismb_lab.cli import main

ROOT = Path(__file__).resolve().parent.parent
LAB = ROOT / "images" / "lab"


@pytest.fixture
def no_work(monkeypatch):
    """Any matching work fails the test: a refusal must come before it.  Every module that
    binds ``prepare`` at import is imported first, so none binds the stand-in for later tests."""
    import importlib
    import pkgutil

    commands = importlib.import_module("ismb_lab.cli")
    for module in pkgutil.iter_modules(commands.__path__):
        if module.name != "__main__":
            importlib.import_module(f"ismb_lab.cli.{module.name}")
    for name in ("depth.pipeline", "matching.metric"):
        importlib.import_module(f"ismb_lab.{name}")

    def work(*args, **kwargs):
        raise AssertionError("the work started before the refusal")

    monkeypatch.setattr(ismb_lab.matching.pipeline, "prepare", work)
    monkeypatch.setattr(ismb_lab.tuning.cases, "prepare", work)


def refused(argv, capsys, match: str):
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and match in err, err
    return err


# --- the solvers' own options, from the command line and from a params file ---

@pytest.mark.parametrize("solver, option, words", [
    ("anneal", "sweeps=1000000000000", "'sweeps'"),
    ("anneal", "sweeps=60000", "'cooling'"),               # 44 temperatures x 60000 sweeps
    ("anneal", "cooling=0.99999999999", "'cooling'"),      # the schedule alone: 4.1 GB before
    ("anneal", "t_end=1e-300", None),                      # 6,600 temperatures of 2 sweeps: within the limit
    ("exact", "time_limit=1e308", "'time_limit'"),
    ("exact", "time_limit=3601", "'time_limit'"),
])
def test_a_solver_option_beyond_its_limit_is_refused_before_the_work(work, capsys, no_work, solver, option, words):
    argv = ["match", work / "L.png", work / "R.png", "--solver", solver, "--solver-option", option]
    if words is None:
        with pytest.raises(AssertionError, match="the work started"):   # accepted: the work starts
            main([str(a) for a in argv])
        return
    refused(argv, capsys, words)


@pytest.mark.parametrize("options", [{"sweeps": 10**12}, {"cooling": 0.99999999999}, {"t_end": 1e-300, "sweeps": 20}])
def test_a_params_file_is_held_to_the_same_limits(work, capsys, no_work, options):
    (work / "P.json").write_text(json.dumps({"version": 2, "method": "III", "params": {}, "solver": "anneal",
                                             "solver_options": options}))
    refused(["match", work / "L.png", work / "R.png", "--params-file", work / "P.json"], capsys, "AnnealSolver")


def test_the_library_bounds_a_schedule_before_it_starts():
    from ismb_lab.network.annealing import MAX_SWEEPS, anneal, iter_annealing
    from ismb_lab.network.exact import milp_minimum
    from ismb_lab.network.hopfield import Network
    from ismb_lab.network.solvers import AnnealSolver, ExactSolver

    net = Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, -0.7], pair_a=[], pair_b=[],
                              pair_c=[])
    for call in (lambda: anneal(net, sweeps=10**9), lambda: anneal(net, cooling=1 - 1e-11),
                 lambda: iter_annealing(net, cooling=1 - 1e-11), lambda: AnnealSolver(sweeps=MAX_SWEEPS + 1),
                 lambda: AnnealSolver(sweeps=MAX_SWEEPS // 44 + 1), lambda: ExactSolver(time_limit=1e308),
                 lambda: milp_minimum(net, time_limit=float("inf"))):
        with pytest.raises(ParameterError):
            call()
    assert anneal(net, sweeps=MAX_SWEEPS // 44).state.tolist() == [1, 0]   # the longest default schedule runs


# --- worker processes ---

def test_jobs_has_a_limit_from_the_environment(work, capsys, no_work, monkeypatch):
    refused(["evaluate", work / "M.json", "--jobs", "1000000"], capsys, "ISMB_LAB_MAX_JOBS")
    monkeypatch.setenv("ISMB_LAB_MAX_JOBS", "3")
    refused(["evaluate", work / "M.json", "--jobs", "4"], capsys, "above the limit of 3 worker processes")


def test_a_default_jobs_above_the_limit_is_lowered_with_a_note(monkeypatch, capsys):
    from ismb_lab.cli import build_parser
    from ismb_lab.cli import evaluate as command
    from ismb_lab.cli._guard import UsageError, preflight

    monkeypatch.setattr(command, "available_cores", lambda: 200)
    monkeypatch.setenv("ISMB_LAB_MAX_JOBS", "4")
    args = build_parser().parse_args(["evaluate", "M.json"])
    preflight(args, UsageError)
    assert args.jobs == 4 and "ISMB_LAB_MAX_JOBS=4" in capsys.readouterr().err


def test_the_protocol_starts_no_more_workers_than_pairs(monkeypatch):
    """``jobs=1000000`` started an interpreter per task (2.76 GB): the pool is no larger than the pairs."""
    import ismb_lab.tuning.cases as protocol
    from ismb_lab.tuning.cases import Case

    asked = []

    class Serial:
        def __init__(self, jobs):
            asked.append(jobs)

        def __enter__(self):
            return None

        def __exit__(self, *exc):
            return False

    monkeypatch.setattr(protocol, "_workers", Serial)
    cases = protocol.load_manifest(ROOT / "manifests" / "middlebury.json")[:2]
    assert all(isinstance(c, Case) for c in cases)
    protocol.protocol(cases, "III", seeds=1, generations=1, population=4, jobs=10**6)
    assert asked == [2]


# --- files: params, rig and manifest JSON, and image headers ---

def _padded(path, text):
    from ismb_lab._core.files import MAX_JSON_BYTES

    path.write_text(" " * MAX_JSON_BYTES + text)   # valid JSON, one byte per blank over the cap
    return path


def test_json_files_above_the_cap_are_refused_unparsed(work, capsys, no_work, monkeypatch):
    import json as json_module

    parsed = []
    real = json_module.loads
    monkeypatch.setattr(json_module, "loads", lambda text, *a, **k: parsed.append(len(text)) or real(text, *a, **k))
    params = _padded(work / "P.json", json.dumps({"params": {}}))
    refused(["match", work / "L.png", work / "R.png", "--params-file", params], capsys, "larger than")
    manifest = _padded(work / "big_manifest.json", (work / "M.json").read_text())
    refused(["evaluate", manifest], capsys, "larger than")
    rig = _padded(work / "rig.json", "{}")
    refused(["match", work / "L.png", work / "R.png", "--rig", rig], capsys, "larger than")
    refused(["calibrate", "--from", rig, "--out", work / "new.json"], capsys, "larger than")
    refused(["evaluate", work / "M.json", "--recipe", params], capsys, "larger than")
    assert not [n for n in parsed if n > 1 << 20], "a file over the cap reached the JSON parser"


def test_read_json_reads_no_more_than_the_cap(tmp_path):
    from ismb_lab._core.files import read_json

    path = tmp_path / "big.json"
    with open(path, "wb") as handle:   # 1 GB of holes: reading it all would take a while and the memory
        handle.truncate(1 << 30)
    with pytest.raises(ValueError, match="larger than 100 bytes"):
        read_json(path, most_bytes=100)


@pytest.mark.parametrize("header, size", [
    (b"P4\n" + b"0" * 70 + b"30000 30000\n", (30000, 30000)),            # the sweep's example
    (b"P5\n" + b"0" * 5000 + b"20000\n" + b"0" * 64 + b"20000\n255\n", (20000, 20000)),
    (b"P6\n# a comment\n00000000000000000000000000000000000000000000000000000000000000009000 9000\n255\n",
     (9000, 9000)),
])
def test_a_netpbm_header_is_read_whole_before_decoding(tmp_path, monkeypatch, header, size):
    import cv2

    from ismb_lab._core.header import image_size
    from ismb_lab.images.io import load_image

    assert image_size(header + b"\0" * 10)[1:] == size
    monkeypatch.setattr(cv2, "imdecode", lambda *a: pytest.fail("decoded before the size was refused"))
    path = tmp_path / "attack.pnm"
    path.write_bytes(header + b"\0" * 100)
    with pytest.raises(ParameterError, match=f"{size[0]}x{size[1]}"):
        load_image(path)


@pytest.mark.parametrize("number", [b"2147483648", b"0" * 100 + b"99999999999", b"9" * 5000])
def test_a_netpbm_size_beyond_a_c_int_is_refused(number):
    from ismb_lab._core.header import HeaderError, image_size

    with pytest.raises(HeaderError, match="2\\*\\*31 - 1"):
        image_size(b"P5\n" + number + b" 10\n255\n")


# --- the API's sizes ---

def test_an_array_image_is_held_to_the_pixel_limit_before_any_copy(monkeypatch):
    from ismb_lab.images.io import load_image, load_pair

    huge = np.broadcast_to(np.uint8(0), (65537, 16385))   # no memory: a view of one byte
    with pytest.raises(ParameterError, match="ISMB_LAB_MAX_PIXELS"):
        load_image(huge)
    with pytest.raises(ParameterError, match="'right'"):
        load_pair(np.zeros((4, 4)), np.broadcast_to(np.float64(0), (6000, 5000)))
    monkeypatch.setenv("ISMB_LAB_MAX_PIXELS", "20")
    with pytest.raises(ParameterError, match="at most 20 pixels"):
        load_image(np.zeros((5, 5)))
    assert load_image(np.zeros((4, 5))).shape == (4, 5)


def test_windows_and_candidate_masks_are_bounded_before_they_are_made():
    from ismb_lab.network.similarity import MAX_CANDIDATE_PAIRS, candidate_mask, patches

    image = np.zeros((40, 60))
    for size in (10**9 + 1, 81):   # 2 * 40 - 1 = 79 is the widest window the mirror completes
        with pytest.raises(ParameterError, match="'size'"):
            patches(image, [[5, 5]], size)
    assert patches(image, [[5, 5]], 79).shape == (1, 79, 79)
    with pytest.raises(ParameterError, match="'size'"):
        patches(np.zeros((4000, 4000)), np.zeros((200, 2)), 999)   # 200 x 999 x 999 values
    with pytest.raises(ParameterError, match=str(MAX_CANDIDATE_PAIRS)):
        candidate_mask(np.zeros((60000, 2)), np.zeros((60000, 2)))
    rng = np.random.default_rng(0)
    left, right = rng.uniform(0, 300, (3000, 2)), rng.uniform(0, 300, (2000, 2))
    dx = right[None, :, 0] - (left[:, None, 0] - 20)
    dy = right[None, :, 1] - left[:, None, 1]
    expected = (np.abs(dx) <= 20) & (np.abs(dy) <= 15)
    assert np.array_equal(candidate_mask(left, right), expected)   # computed by blocks: the same mask


def test_a_huge_harris_window_is_refused_and_an_empty_search_skips_the_response(monkeypatch):
    import ismb_lab.images.features as features

    image = np.random.default_rng(0).uniform(0, 255, (60, 80))
    for call in (lambda: features.detect_corners(image, sigma=1e6),
                 lambda: features.structure_tensor(image, sigma=51),
                 lambda: features.harris_response(image, sigma=1e300)):
        with pytest.raises(ParameterError, match="'sigma'"):
            call()
    monkeypatch.setattr(features, "harris_response", lambda *a: pytest.fail("R computed for nothing"))
    corners = features.detect_corners(image, sigma=25, roi="full")   # a border of 76 px: nothing to search
    assert len(corners) == 0 and corners.message == ("no corners: R has no positive local maximum inside the "
                                                     "ROI, at least 76 pixels from the image edge")
    flat = features.detect_corners(np.full((3000, 3000), 7.0), roi="full")
    assert flat.message == "no corners: the image is flat inside the ROI"


def test_a_recipe_s_fit_seeds_are_held_to_the_seeds_limit(work, capsys, no_work, monkeypatch):
    """--fit-seeds above ISMB_LAB_MAX_SEEDS was refused, the same number in a --recipe file ran."""
    (work / "P.json").write_text(json.dumps({"version": 2, "method": "III", "params": {}, "fit_seeds": 10**6}))
    argv = ["evaluate", work / "M.json", "--recipe", work / "P.json", "--jobs", "1"]
    refused(argv, capsys, "ISMB_LAB_MAX_SEEDS=1000000")
    with pytest.raises(AssertionError, match="the work started"):   # an option given replaces the file's
        main([str(a) for a in argv + ["--fit-seeds", "2"]])
    monkeypatch.setenv("ISMB_LAB_MAX_SEEDS", str(10**6))
    with pytest.raises(AssertionError, match="the work started"):
        main([str(a) for a in argv])
