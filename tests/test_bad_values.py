"""The library refuses numbers it cannot use, oversized targets and degenerate rigs with a
ParameterError that names the parameter, the rule and the value (issue 25)."""

import json
from pathlib import Path

import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab._core.validation import MAX_SEED, check_number, check_rng, message
from ismb_lab.network.params import Params
from ismb_lab.cameras.camera import StereoCamera, load_camera
from ismb_lab.labels.targets import MAX_BYTES, MAX_PAIRS, TargetSet, load_targets

LAB = Path(__file__).resolve().parent.parent / "images" / "lab"
HUGE = int("9" * 400)


def test_a_400_digit_parameter_is_refused_in_words():
    with pytest.raises(ParameterError, match="'theta_c' parameter of Params.*an integer of 400 digits"):
        Params(theta_c=HUGE)
    with pytest.raises(ParameterError, match="'lambda_s'"):
        Params.from_dict({"lambda_s": 10**400})
    assert check_number(10**300, "x", "f") == 1e300


def test_a_message_shows_an_int_of_any_size():
    # repr() of an int over 4300 digits raises ValueError; the message must not.
    assert "an integer of 5001 digits" in message("n", "f", "an integer", 10**5000)
    assert "Got 12 instead" in message("n", "f", "an integer", 12)


@pytest.mark.parametrize("seed", [2**63, 2**64, 10**30, -1])
def test_seeds_are_bounded_by_what_the_update_order_takes(seed):
    from ismb_lab.network.dynamics import run
    from ismb_lab.matching.pipeline import match, prepare
    from ismb_lab.network.methods import get_method

    with pytest.raises(ParameterError, match=f"'seed' parameter of match.*{MAX_SEED}"):
        match(LAB / "left.png", LAB / "right.png", seed=seed)
    with pytest.raises(ParameterError, match="2\\*\\*63 - 1"):
        check_rng(seed)
    problem = prepare(LAB / "left.png", LAB / "right.png").problem
    with pytest.raises(ParameterError, match="'rng' parameter of run"):
        run(get_method("III").network(problem, Params()), rng=seed)


def test_the_largest_seed_runs():
    from ismb_lab.matching.pipeline import match

    assert match(LAB / "left.png", LAB / "right.png", seed=MAX_SEED).seed == MAX_SEED
    assert check_rng(MAX_SEED).integers(10) >= 0


def test_a_400_digit_coordinate_is_refused(tmp_path):
    data = json.loads((LAB / "answer_key.json").read_text())
    data["pairs"][3]["right_xy"][1] = HUGE
    path = tmp_path / "t.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ParameterError, match=r"'pairs\[3\].right_xy' parameter of the targets file"):
        load_targets(path)
    with pytest.raises(ParameterError, match="'left_xy' parameter of TargetSet"):
        TargetSet([[HUGE, 1]], [[1, 1]])


def test_a_targets_file_over_the_byte_bound_is_refused_before_parsing(tmp_path, monkeypatch):
    path = tmp_path / "t.json"
    path.write_text((LAB / "answer_key.json").read_text() + " " * MAX_BYTES)

    def no_parsing(*args, **kwargs):
        raise AssertionError("the file was parsed")

    monkeypatch.setattr(json, "loads", no_parsing)
    with pytest.raises(ParameterError, match=f"at most {MAX_BYTES} bytes") as info:
        load_targets(path)
    assert str(info.value).count("must be") == 1 and "JSON" not in str(info.value)


def test_more_pairs_than_the_bound_are_refused_before_they_are_checked():
    pairs = [{"left_xy": [n, 0], "right_xy": [n, 0]} for n in range(MAX_PAIRS + 1)]
    with pytest.raises(ParameterError, match=f"at most {MAX_PAIRS} pairs.*{MAX_PAIRS + 1} pairs"):
        TargetSet.from_dict({"version": 1, "pairs": pairs})
    assert len(TargetSet.from_dict({"version": 1, "pairs": pairs[:MAX_PAIRS]})) == MAX_PAIRS


# --- degenerate rigs ---

def rig_record(**change) -> dict:
    camera = [[300.0, 0.0, 160.0], [0.0, 300.0, 120.0], [0.0, 0.0, 1.0]]
    record = {"format": "ismb_lab-rig-v1", "size": [320, 240], "rms_px": 0.3, "board": [9, 6],
              "square_m": 0.025, "k_left": camera, "d_left": [0.0] * 5, "k_right": camera,
              "d_right": [0.0] * 5, "rotation": np.eye(3).tolist(), "translation": [-0.1, 0.0, 0.0]}
    return {**record, **change}


def test_a_sound_rig_loads():
    rig = load_camera(json.dumps(rig_record()))
    assert rig.focal_px == pytest.approx(300) and rig.baseline_m == pytest.approx(0.1)


@pytest.mark.parametrize("change, field", [
    ({"k_left": [[0.0] * 3] * 3, "k_right": [[0.0] * 3] * 3}, "k_left"),
    ({"k_right": [[300, 0, 160], [0, -300, 120], [0, 0, 1]]}, "k_right"),
    ({"d_left": [float("nan")] * 5}, "d_left"),
    ({"d_right": [0.0, 0.0, 0.0]}, "d_right"),
    ({"translation": [0.0, 0.0, 0.0]}, "translation"),
    ({"rotation": [[2.0, 0, 0], [0, 1, 0], [0, 0, 1]]}, "rotation"),
    ({"rotation": [[-1.0, 0, 0], [0, 1, 0], [0, 0, 1]]}, "rotation"),
    ({"size": [0, 240]}, "size"),
    ({"size": [HUGE, 240]}, "size"),
])
def test_a_degenerate_rig_is_refused_naming_the_field(tmp_path, change, field):
    path = tmp_path / "rig.json"
    path.write_text(json.dumps(rig_record(**change)))
    with pytest.raises(ParameterError, match=f"'{field}' parameter of the rig file '{path}'"):
        load_camera(path)
    good = load_camera(json.dumps(rig_record()))
    arrays = {k: np.asarray(v, dtype=float) for k, v in change.items() if k != "size"}
    if arrays:
        fields = {"size": good.size, "k_left": good.k_left, "d_left": good.d_left, "k_right": good.k_right,
                  "d_right": good.d_right, "rotation": good.rotation, "translation": good.translation,
                  **arrays}
        with pytest.raises(ParameterError, match=f"'{field}' parameter of StereoCamera"):
            StereoCamera(rms=0.3, **fields)


def test_a_bound_of_400_digits_is_shown_by_its_size():
    from ismb_lab.matching.pipeline import MatchConfig

    with pytest.raises(ParameterError) as info:
        MatchConfig(n_min=HUGE)
    assert "an integer >= an integer of 400 digits" in str(info.value) and len(str(info.value)) < 200


def test_family_cases_refuses_an_empty_split_and_bad_counts():
    from ismb_lab.tuning.cases import family_cases

    with pytest.raises(ValueError, match=r"'count'.*family_cases.*>= 1.*Got 0"):
        family_cases("cameras", 2300, 0)
    with pytest.raises(TypeError, match=r"'start'.*family_cases"):
        family_cases("cameras", "2300", 3)


def test_ga_population_has_an_upper_bound():
    from ismb_lab.tuning.genetic import MAX_POPULATION, GAConfig

    assert GAConfig(population=MAX_POPULATION).population == MAX_POPULATION
    with pytest.raises(ValueError, match=r"'population'.*GAConfig.*<= 100000.*401 digits"):
        GAConfig(population=10**400)
