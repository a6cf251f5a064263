"""End-to-end matching on scenes whose answer is known exactly."""

import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.network.dynamics import iter_updates
from ismb_lab.matching.pipeline import MatchConfig, match, prepare
from ismb_lab.network.methods import THESIS_PARAMS, Params, get_method
from ismb_lab.scenes import synthetic_scene, true_matches

# Chosen by scripts/grid_search_synthetic.py on training scenes 100-109 only; the
# scenes below (0-9) were never used for the choice.  The thesis' own parameters
# were fitted to its webcam images and over-reward compatibility here (see the note
# in test_thesis_parameters_find_partners_but_add_extra_matches).
SYNTHETIC_PARAMS = Params(theta_c=2.0, theta_s=24.02, lambda_c=0.5, lambda_s=2.2)
HELD_OUT = range(10)


@pytest.fixture(scope="module")
def held_out(rendered):
    """``held_out(seed)``: (scene, prepared, truth) of a held-out scene, made on first use."""
    made = {}

    def get(seed):
        if seed not in made:
            scene = rendered(synthetic_scene, seed)
            prepared = prepare(scene.left, scene.right)
            truth = true_matches(scene, prepared.problem.left_xy, prepared.problem.right_xy)
            made[seed] = scene, prepared, truth
        return made[seed]

    return get


@pytest.fixture(scope="module")
def scenes(held_out):
    """All ten held-out scenes (about 5 s to render: for the slow tests)."""
    return [held_out(seed) for seed in HELD_OUT]


def tally(scenes, method, params):
    correct = extra = partners = 0
    for scene, prepared, truth in scenes:
        result = match(method=method, params=params, prepared=prepared, seed=0)
        for (i, k), d in zip(result.pairs, result.horizontal_disparity):
            true_d = scene.disparity[int(result.left_xy[i, 1]), int(result.left_xy[i, 0])]
            ok = truth[i] == k and abs(d - true_d) <= 1.5
            correct += ok
            extra += not ok
        partners += np.count_nonzero(truth >= 0)
    return correct / partners, correct / max(correct + extra, 1), partners


@pytest.mark.slow   # five rendered scenes, each matched: about 7 s
def test_method_three_recovers_ground_truth_disparity_on_held_out_scenes(scenes):
    recall, precision, partners = tally(scenes, "III", SYNTHETIC_PARAMS)
    assert partners > 150
    assert recall >= 0.90
    assert precision >= 0.90


@pytest.mark.slow   # the ten scenes
def test_thesis_parameters_find_partners_but_add_extra_matches(scenes):
    # Measured: about 90% of the partners but only about 70% precision.  The thesis'
    # theta_c = 17.97 px calls wrong pairs compatible, and the (1 - sum y)^2 term
    # pushes every corner, even one without a partner, towards one match.
    recall, precision, _ = tally(scenes, "III", THESIS_PARAMS["III"])
    assert recall >= 0.85
    assert precision < 0.85


@pytest.mark.slow
def test_vertical_disparity_term_helps_an_unrectified_rig():
    results = {}
    for method in ("II", "III"):
        correct = total = 0
        for seed in range(3):
            scene = synthetic_scene(seed=seed, vertical_offset_px=4.0, roll_deg=1.0)
            prepared = prepare(scene.left, scene.right)
            truth = true_matches(scene, prepared.problem.left_xy, prepared.problem.right_xy)
            r = match(method=method, params=SYNTHETIC_PARAMS, prepared=prepared)
            correct += sum(truth[i] == k for i, k in r.pairs)
            total += len(r.pairs)
        results[method] = correct / total
    assert results["III"] >= results["II"]
    assert results["III"] >= 0.9


def test_every_method_runs_and_is_reproducible(held_out):
    _, prepared, _ = held_out(0)
    for method in ("I", "II", "III"):
        a = match(method=method, prepared=prepared, seed=7)
        b = match(method=method, prepared=prepared, seed=7)
        assert np.array_equal(a.pairs, b.pairs) and a.energy == b.energy
        assert a.stop_rule == "sweep" and len(a.pairs) > 0
        slow = match(method=method, prepared=prepared, seed=7, kernel="textbook")
        assert np.array_equal(a.pairs, slow.pairs) and a.energy == slow.energy


def test_method_one_leaves_each_feature_matched_at_most_once(held_out):
    for _, prepared, _ in map(held_out, HELD_OUT[:4]):
        pairs = match(method="I", prepared=prepared).pairs
        assert len(np.unique(pairs[:, 0])) == len(pairs) == len(np.unique(pairs[:, 1]))


def test_literal_thesis_rule_misbehaves_on_a_real_problem(held_out):
    _, prepared, _ = held_out(0)
    net = get_method("III").network(prepared.problem, THESIS_PARAMS["III"])
    energies = [u.energy for u in iter_updates(net, rng=0, rule="thesis", max_sweeps=30)]
    rises = sum(b > a + 1e-9 for a, b in zip(energies, energies[1:]))
    assert rises > 0
    result = match(prepared=prepared, rule="thesis")
    assert result.stop_rule == "max_attempts" and "did not settle" in result.message


def test_table_and_json_follow_the_thesis_and_the_contract(held_out):
    _, prepared, _ = held_out(1)
    result = match(prepared=prepared, params=SYNTHETIC_PARAMS, seed=3)
    lines = result.table().splitlines()
    assert lines[0].split() == ["Pair", "Left", "Right", "y_left", "x_left", "y_right", "x_right",
                                "disparity"]
    first = lines[1].split()
    i, k = result.pairs[0]
    assert first[:3] == ["1", str(i + 1), str(k + 1)]
    assert float(first[3]) == result.left_xy[i, 1] and float(first[6]) == result.right_xy[k, 0]
    data = result.to_dict()
    assert data["seed"] == 3 and data["params"] == SYNTHETIC_PARAMS.to_dict()
    assert len(data["matches"]) == len(result.pairs)
    assert data["matches"][0]["left_xy"] == [int(v) for v in result.left_xy[i]]


def test_a_flat_pair_gives_an_empty_match_with_a_reason():
    flat = np.full((240, 320), 90.0)
    result = match(flat, flat)
    assert len(result.pairs) == 0 and "no corners" in result.message


def test_no_candidates_is_an_empty_match_with_a_reason(rendered):
    scene = rendered(synthetic_scene, 0)
    result = match(scene.left, scene.right, config=MatchConfig(shift=300, right_roi="same"))
    assert len(result.pairs) == 0 and "no candidate pairs" in result.message


@pytest.mark.parametrize("kwargs, error, words", [
    (dict(right=np.zeros((200, 320))), ParameterError, "'right'"),
    (dict(left=np.zeros((8, 8)), right=np.zeros((8, 8))), ParameterError, "'left'"),
    (dict(method="IV"), ParameterError, "'method'"),
    (dict(params={"theta_c": 1}), ParameterTypeError, "'params'"),
    (dict(seed=-1), ParameterError, "'seed'"),
    (dict(stop_rule="never"), ParameterError, "'stop_rule'"),
    (dict(config=MatchConfig(roi=(300, 0, 50, 50))), ParameterError, "'roi'"),
])
def test_bad_input_names_the_parameter(rendered, kwargs, error, words):
    scene = rendered(synthetic_scene, 0)
    args = dict(left=scene.left, right=scene.right)
    args.update(kwargs)
    with pytest.raises(error, match=words):
        match(**args)


@pytest.mark.parametrize("field, value", [("n_min", 0), ("patch_size", 10), ("harris_k", 0.3),
                                          ("shift", float("nan")), ("window_width", -1),
                                          ("neighbourhood", "ring"), ("right_roi", "left")])
def test_match_config_validates(field, value):
    with pytest.raises((ParameterError, ParameterTypeError), match=f"'{field}'"):
        MatchConfig(**{field: value})


def test_warm_up_prepares_the_first_match_and_refuses_a_bare_name():
    from ismb_lab.matching.pipeline import warm_up

    assert warm_up(("network", "anneal")) >= 0.0
    with pytest.raises(TypeError, match=r"solvers.*warm_up.*tuple of solver names.*'network'"):
        warm_up("network")
