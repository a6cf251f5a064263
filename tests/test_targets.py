"""Target pairs: the file, its checks, and snapping to features."""

import json
import os

import cv2
import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.images.io import load_pair
from ismb_lab.labels.targets import Snapped, TargetSet, load_targets, save_targets, snap, targets_from_matches

H1 = "a" * 64
H2 = "b" * 64


def says(info, *fragments):
    """The exception message names every fragment (parameter, rule, received value)."""
    text = str(info.value)
    missing = [f for f in fragments if f not in text]
    assert not missing, f"{missing} not in {text!r}"


def write_json(path, data):
    path.write_text(data if isinstance(data, str) else json.dumps(data), encoding="utf-8")
    return path


def pairs_file(tmp_path, *pairs, **top):
    return write_json(tmp_path / "t.json", {"version": 1, **top, "pairs": list(pairs)})


def pair_of_pngs(tmp_path, seed, size=(20, 30)):
    rng = np.random.default_rng(seed)
    paths = []
    for side in ("left", "right"):
        path = tmp_path / f"{side}{seed}.png"
        assert cv2.imwrite(str(path), rng.integers(0, 256, size, dtype=np.uint8))
        paths.append(path)
    return load_pair(*paths)


@pytest.fixture
def full():
    return TargetSet([[10, 20], [3.25, 4.5]], [[8, 20], [1.5, 4.5]], H1, H2,
                     meta={"notes": "by hand", "labeller": "ann", "answer_key": True,
                           "nested": {"list": [1, 2, 3]}},
                     extras=[{"comment": "window corner"}, {}])


# --- round trip -------------------------------------------------------------------------

def test_round_trip_preserves_everything(tmp_path, full):
    path = save_targets(tmp_path / "t.json", full)
    back = load_targets(path)
    assert back.to_dict() == full.to_dict()
    assert np.array_equal(back.left_xy, full.left_xy) and np.array_equal(back.right_xy, full.right_xy)
    assert (back.left_sha256, back.right_sha256) == (H1, H2)
    assert back.meta == full.meta and back.extras == full.extras
    text = path.read_text()
    assert text.endswith("}\n") and '"left_xy": [10, 20]' in text


def test_hand_written_file_survives_load_and_save(tmp_path):
    data = {"version": 1, "labeller": "bob", "answer_key": True, "right_image_sha256": H2,
            "pairs": [{"left_xy": [1, 2], "right_xy": [0.5, 2], "sure": False, "tags": ["t"]}]}
    path = write_json(tmp_path / "t.json", data)
    save_targets(path, load_targets(path))
    assert json.loads(path.read_text()) == data


def test_saved_set_holds_no_hash_keys_when_none(tmp_path):
    path = save_targets(tmp_path / "t.json", TargetSet([[1, 1]], [[0, 1]]))
    assert set(json.loads(path.read_text())) == {"version", "orientation", "pairs"}


# --- atomic save ------------------------------------------------------------------------

@pytest.mark.parametrize("broken", ["replace", "fsync"])
def test_crash_while_saving_keeps_old_file_and_leaves_no_temp(tmp_path, monkeypatch, full, broken):
    path = save_targets(tmp_path / "t.json", TargetSet([[1, 1]], [[0, 1]]))
    old = path.read_bytes()

    def crash(*args, **kwargs):
        raise OSError("disk on fire")

    monkeypatch.setattr(os, broken, crash)
    with pytest.raises(OSError, match="disk on fire"):
        save_targets(path, full)
    monkeypatch.undo()
    assert path.read_bytes() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.json"]
    assert len(load_targets(path)) == 1


def test_save_into_missing_folder_names_path(tmp_path, full):
    with pytest.raises(ParameterError) as info:
        save_targets(tmp_path / "nope" / "t.json", full)
    says(info, "'path'", "existing folder", "nope")


# --- bad files --------------------------------------------------------------------------

def test_missing_file_names_path(tmp_path):
    with pytest.raises(ParameterError) as info:
        load_targets(tmp_path / "absent.json")
    says(info, "'path'", "load_targets", "absent.json", "No such file")


@pytest.mark.parametrize("text, where", [
    ('{"version": 1, "pairs": [{"left_xy": [1, 2],', "line 1 column 45"),   # truncated
    ('{"version": 1,, "pairs": []}', "line 1 column 15"),                     # corrupt
    ("", "line 1 column 1"),                                                  # empty
])
def test_corrupt_or_truncated_json_names_path_and_position(tmp_path, text, where):
    path = write_json(tmp_path / "t.json", text)
    with pytest.raises(ParameterError) as info:
        load_targets(path)
    says(info, "'path'", "not valid JSON", where, str(path))


def test_json_that_is_not_an_object(tmp_path):
    with pytest.raises(ParameterError) as info:
        load_targets(write_json(tmp_path / "t.json", "[1, 2]"))
    says(info, "'path'", "not an object")


@pytest.mark.parametrize("version, shown", [(2, "Got 2 "), ("1", "Got '1' "), (None, "no 'version' key")])
def test_wrong_version(tmp_path, version, shown):
    top = {} if version is None else {"version": version}
    path = write_json(tmp_path / "t.json", {**top, "pairs": []})
    with pytest.raises(ParameterError) as info:
        load_targets(path)
    says(info, "'version'", "must be 1", shown, "t.json")


@pytest.mark.parametrize("left, error, shown", [
    (["1", 2], ParameterTypeError, "Got ['1', 2] instead"),
    ([1, 2, 3], ParameterError, "Got [1, 2, 3] instead"),
    ([1], ParameterError, "Got [1] instead"),
    ([True, 2], ParameterTypeError, "Got [True, 2] instead"),
    ("1, 2", ParameterTypeError, "Got '1, 2' instead"),
    ([-1, 2], ParameterError, "Got [-1, 2] instead"),
])
def test_wrong_coordinates_name_key_and_pair_number(tmp_path, left, error, shown):
    path = pairs_file(tmp_path, {"left_xy": [1, 1], "right_xy": [0, 1]},
                      {"left_xy": left, "right_xy": [0, 1]})
    with pytest.raises(error) as info:
        load_targets(path)
    says(info, "'pairs[1].left_xy'", "2 finite numbers", shown)


@pytest.mark.parametrize("literal", ["NaN", "Infinity"])
def test_non_finite_coordinates(tmp_path, literal):
    path = write_json(tmp_path / "t.json",
                      f'{{"version": 1, "pairs": [{{"left_xy": [1, 2], "right_xy": [{literal}, 2]}}]}}')
    with pytest.raises(ParameterError) as info:
        load_targets(path)
    says(info, "'pairs[0].right_xy'", "finite", "Got [" + ("nan" if literal == "NaN" else "inf"))


@pytest.mark.parametrize("pairs, error, name", [
    ({"left_xy": [1, 2]}, ParameterTypeError, "'pairs'"),
    (None, ParameterTypeError, "'pairs'"),
    ([[1, 2]], ParameterTypeError, "'pairs[0]'"),
    ([{"left_xy": [1, 2]}], ParameterError, "'pairs[0]'"),
])
def test_wrong_pairs_structure(tmp_path, pairs, error, name):
    data = {"version": 1} if pairs is None else {"version": 1, "pairs": pairs}
    with pytest.raises(error) as info:
        load_targets(write_json(tmp_path / "t.json", data))
    says(info, name)


def test_malformed_hash_is_refused(tmp_path):
    with pytest.raises(ParameterError) as info:
        load_targets(pairs_file(tmp_path, left_image_sha256="abc"))
    says(info, "'left_image_sha256'", "64 hex", "Got 'abc'")


@pytest.mark.parametrize("left, right, bad", [
    ([29, 19], [0, 0], None),                            # the last pixel is inside
    ([30, 5], [0, 0], ("'pairs[0].left_xy'", "Got [30, 5]")),
    ([3, 5], [2, 20], ("'pairs[0].right_xy'", "Got [2, 20]")),
    ([29.5, 5], [0, 0], ("'pairs[0].left_xy'", "Got [29.5, 5]")),
])
def test_points_outside_the_image(tmp_path, left, right, bad):
    path = pairs_file(tmp_path, {"left_xy": left, "right_xy": right})
    if bad is None:
        assert len(load_targets(path, shape=(20, 30))) == 1
        return
    with pytest.raises(ParameterError) as info:
        load_targets(path, shape=(20, 30))
    says(info, *bad, "inside the 30x20 (width x height) image", "0 <= x <= 29, 0 <= y <= 19")


def test_pair_shape_bounds_the_points(tmp_path):
    pair = pair_of_pngs(tmp_path, 0, size=(20, 30))
    path = pairs_file(tmp_path, {"left_xy": [30, 1], "right_xy": [0, 0]})
    with pytest.raises(ParameterError) as info:
        load_targets(path, pair=pair)
    says(info, "'pairs[0].left_xy'", "30x20 (width x height)")
    assert len(load_targets(path, shape=(40, 40))) == 1


@pytest.mark.parametrize("kwargs, error, name", [
    ({"shape": (0, 5)}, ParameterError, "'shape'"),
    ({"shape": 5}, ParameterTypeError, "'shape'"),
    ({"pair": "left.png"}, ParameterTypeError, "'pair'"),
    ({"check_hash": "no"}, ParameterTypeError, "'check_hash'"),
])
def test_bad_load_arguments(tmp_path, kwargs, error, name):
    with pytest.raises(error) as info:
        load_targets(pairs_file(tmp_path), **kwargs)
    says(info, name)


# --- image hashes -----------------------------------------------------------------------

def test_hash_check(tmp_path):
    mine, other = pair_of_pngs(tmp_path, 1), pair_of_pngs(tmp_path, 2)
    made = TargetSet([[1, 2]], [[0, 2]], mine.left_sha256, mine.right_sha256)
    path = save_targets(tmp_path / "t.json", made)

    assert load_targets(path, pair=mine).left_sha256 == mine.left_sha256
    with pytest.raises(ParameterError) as info:
        load_targets(path, pair=other)
    says(info, "'path'", "other images", "check_hash=False", str(path),
         mine.left_sha256[:12], mine.right_sha256[:12],
         other.left_sha256[:12], other.right_sha256[:12])
    loaded = load_targets(path, pair=other, check_hash=False)
    assert loaded.left_sha256 == mine.left_sha256   # the file's hashes, not the pair's


def test_swapped_images_fail_the_hash_check(tmp_path):
    mine = pair_of_pngs(tmp_path, 1)
    path = save_targets(tmp_path / "t.json", TargetSet([[1, 2]], [[0, 2]], mine.left_sha256,
                                                       mine.right_sha256))
    swapped = load_pair(mine.right_path, mine.left_path)
    with pytest.raises(ParameterError, match="other images"):
        load_targets(path, pair=swapped)


def test_one_matching_and_one_wrong_hash_fails(tmp_path):
    mine = pair_of_pngs(tmp_path, 1)
    path = pairs_file(tmp_path, left_image_sha256=mine.left_sha256, right_image_sha256=H2)
    with pytest.raises(ParameterError, match="other images"):
        load_targets(path, pair=mine)


def test_file_without_hashes_loads_for_any_pair(tmp_path):
    path = pairs_file(tmp_path, {"left_xy": [1, 2], "right_xy": [0, 2]})
    for seed in (1, 2):
        assert len(load_targets(path, pair=pair_of_pngs(tmp_path, seed))) == 1


# --- snapping ---------------------------------------------------------------------------

LEFT_FEATURES = [[10, 10], [20, 20], [30, 30]]
RIGHT_FEATURES = [[5, 10], [15, 20], [25, 30]]


def test_snap_exact_hits():
    t = TargetSet([[20, 20], [10, 10]], [[15, 20], [5, 10]])
    s = snap(t, LEFT_FEATURES, RIGHT_FEATURES)
    assert s.pairs.tolist() == [[1, 1], [0, 0]] and s.target_index.tolist() == [0, 1]
    assert s.distance.tolist() == [0, 0] and s.missing_left.size == s.missing_right.size == 0


def test_snap_within_tolerance_and_on_its_edge():
    t = TargetSet([[11, 11], [21.5, 20]], [[5, 10], [15, 21.5]])
    s = snap(t, LEFT_FEATURES, RIGHT_FEATURES, tol=1.5)
    assert s.pairs.tolist() == [[0, 0], [1, 1]]
    assert np.allclose(s.distance, [np.sqrt(2), 1.5])


def test_snap_just_outside_tolerance_is_reported_missing():
    t = TargetSet([[11.6, 10], [20, 20], [30, 30]], [[5, 10], [15, 21.51], [26.6, 30]])
    s = snap(t, LEFT_FEATURES, RIGHT_FEATURES, tol=1.5)
    assert s.pairs.size == 0 and s.target_index.size == 0
    assert s.missing_left.tolist() == [0] and s.missing_right.tolist() == [1, 2]
    assert snap(t, LEFT_FEATURES, RIGHT_FEATURES, tol=1.7).pairs.tolist() == [[0, 0], [1, 1], [2, 2]]


def test_snap_chooses_the_nearest_of_two_features():
    left = [[10, 10], [11.2, 10], [10.6, 10]]   # 1.0, 0.2 and 0.4 away from the target
    t = TargetSet([[11, 10]], [[5, 10]])
    s = snap(t, left, RIGHT_FEATURES, tol=1.5)
    assert s.pairs.tolist() == [[1, 0]]         # the nearest, not the first or last in reach
    assert np.isclose(s.distance[0], 0.2)


def test_snap_keeps_targets_sharing_a_feature_and_reports_them():
    t = TargetSet([[10, 10], [10.5, 10], [30, 30]], [[5, 10], [15, 20], [25, 30]])
    s = snap(t, LEFT_FEATURES, RIGHT_FEATURES)
    assert s.pairs.tolist() == [[0, 0], [0, 1], [2, 2]]
    assert s.shared.tolist() == [0, 1]


def test_snap_with_no_features_reports_every_target():
    t = TargetSet([[10, 10]], [[5, 10]])
    s = snap(t, np.empty((0, 2)), RIGHT_FEATURES)
    assert s.pairs.shape == (0, 2) and s.missing_left.tolist() == [0] and s.missing_right.size == 0


def test_snap_arguments_are_checked():
    t = TargetSet([[10, 10]], [[5, 10]])
    with pytest.raises(ParameterError) as info:
        snap(t, LEFT_FEATURES, RIGHT_FEATURES, tol=-1)
    says(info, "'tol'", "Got -1")
    with pytest.raises(ParameterTypeError, match="'targets'"):
        snap([[10, 10]], LEFT_FEATURES, RIGHT_FEATURES)


def test_snapped_is_read_only():
    s = snap(TargetSet([[10, 10]], [[5, 10]]), LEFT_FEATURES, RIGHT_FEATURES)
    assert isinstance(s, Snapped)
    with pytest.raises(ValueError):
        s.pairs[0, 0] = 2


# --- the set itself ---------------------------------------------------------------------

def test_add_and_remove_are_pure(full):
    before = full.to_dict()
    more = full.add([7, 8], [6, 8], comment="new")
    fewer = full.remove(0)
    assert full.to_dict() == before and len(full) == 2
    assert len(more) == 3 and more.left_xy[-1].tolist() == [7, 8] and more.extras[-1] == {"comment": "new"}
    assert len(fewer) == 1 and fewer.left_xy.tolist() == [[3.25, 4.5]] and fewer.extras == ({},)
    assert fewer.meta == full.meta and fewer.left_sha256 == H1
    with pytest.raises(ValueError):
        full.left_xy[0, 0] = 99


@pytest.mark.parametrize("index, error", [(2, ParameterError), (-1, ParameterError),
                                          (0.5, ParameterTypeError)])
def test_remove_checks_the_index(full, index, error):
    with pytest.raises(error) as info:
        full.remove(index)
    says(info, "'index'", f"Got {index!r}")


def test_add_checks_the_point(full):
    with pytest.raises(ParameterError) as info:
        full.add([1, 2, 3], [0, 2])
    says(info, "'left_xy'", "TargetSet.add", "Got [1, 2, 3]")


@pytest.mark.parametrize("kwargs, name", [
    ({"left_xy": [[1, 2]], "right_xy": [[1, 2], [3, 4]]}, "'right_xy'"),
    ({"left_xy": [[-1, 2]], "right_xy": [[1, 2]]}, "'left_xy'"),
    ({"left_xy": [[1, 2]], "right_xy": [[1, 2]], "meta": {"pairs": 1}}, "'meta'"),
    ({"left_xy": [[1, 2]], "right_xy": [[1, 2]], "extras": [{}, {}]}, "'extras'"),
    ({"left_xy": [[1, 2]], "right_xy": [[1, 2]], "extras": [{"left_xy": 1}]}, "'extras[0]'"),
    ({"left_xy": [[1, 2]], "right_xy": [[1, 2]], "left_sha256": "xyz"}, "'left_sha256'"),
])
def test_target_set_is_validated(kwargs, name):
    with pytest.raises(ParameterError) as info:
        TargetSet(**kwargs)
    says(info, name, "TargetSet")


def test_meta_must_be_json(tmp_path):
    with pytest.raises(ParameterTypeError, match="'meta'"):
        TargetSet([[1, 2]], [[1, 2]], meta={"when": object()})


def test_targets_from_matches(tmp_path):
    t = targets_from_matches([[2, 0], [0, 1]], LEFT_FEATURES, RIGHT_FEATURES,
                             left_sha256=H1, labeller="ga")
    assert t.left_xy.tolist() == [[30, 30], [10, 10]] and t.right_xy.tolist() == [[5, 10], [15, 20]]
    assert t.left_sha256 == H1 and t.right_sha256 is None and t.meta == {"labeller": "ga"}
    assert snap(t, LEFT_FEATURES, RIGHT_FEATURES).pairs.tolist() == [[2, 0], [0, 1]]
    assert len(targets_from_matches([], LEFT_FEATURES, RIGHT_FEATURES)) == 0


@pytest.mark.parametrize("pairs, error", [([[3, 0]], ParameterError), ([[0, -1]], ParameterError),
                                          ([0, 1], ParameterError), ([[0.0, 1.0]], ParameterTypeError)])
def test_targets_from_matches_checks_indices(pairs, error):
    with pytest.raises(error) as info:
        targets_from_matches(pairs, LEFT_FEATURES, RIGHT_FEATURES)
    says(info, "'pairs'", "0 <= i < 3")
