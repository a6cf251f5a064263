"""What the photo path says about a pair: sizes as width x height, swapped and unrectified pairs."""

import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab.images.io import load_pair


def test_sizes_are_width_by_height_in_load_pair_messages():
    wide, narrow = np.zeros((4, 6)), np.zeros((4, 5))         # 6 wide, 4 high
    with pytest.raises(ParameterError) as info:
        load_pair(wide, narrow)
    assert "6x4 pixels (width x height)" in str(info.value) and "an image of 5x4 pixels" in str(info.value)
    with pytest.raises(ParameterError) as info:
        load_pair(wide, wide, min_shape=(5, 10))              # (height, width) in, width x height out
    assert "at least 10x5 pixels (width x height)" in str(info.value) and "an image of 6x4 pixels" in str(info.value)


@pytest.mark.parametrize("left, right", [("left.jpg", "right.jpg"), ("left01.jpg", "right01.jpg")])
def test_swapped_photos_are_refused_naming_the_fix(opencv_data, left, right):
    from ismb_lab.images.rectify import check_rectified, rectify_pair

    rectify_pair(opencv_data / left, opencv_data / right)          # the right order is accepted
    with pytest.raises(ParameterError, match="swap the two files") as info:
        rectify_pair(opencv_data / right, opencv_data / left)
    assert "\n" not in str(info.value) and "robust matches put it to the right" in str(info.value)
    assert "swap the two files" in check_rectified(opencv_data / right, opencv_data / left)["problem"]


def test_rectify_cli_refuses_swapped_photos_in_one_line(opencv_data, tmp_path, capsys):
    from ismb_lab.cli import main

    out = tmp_path / "out"
    assert main(["rectify", str(opencv_data / "right.jpg"), str(opencv_data / "left.jpg"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "swap the two files" in err and not out.exists()


def _match(capsys, *args):
    from ismb_lab.cli import main

    code = main(["match", *map(str, args)])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_match_warns_about_an_unrectified_pair_and_names_rectify(opencv_data, pair, capsys):
    code, _, err = _match(capsys, opencv_data / "left.jpg", opencv_data / "right.jpg", "--shift", "10")
    assert code == 0 and err.count("\n") == 1
    assert err.startswith("warning: the pair is not rectified") and "ismb-lab rectify" in err
    code, _, err = _match(capsys, *pair)                          # a rectified pair: nothing to say
    assert code == 0 and err == ""


def test_match_shift_auto_on_an_unrectified_pair_says_rectify_first(opencv_data, capsys):
    code, _, err = _match(capsys, opencv_data / "left.jpg", opencv_data / "right.jpg", "--shift", "auto")
    lines = err.splitlines()
    assert code == 2 and len(lines) == 2 and lines[0].startswith("warning:")
    assert lines[1].startswith("ismb-lab: error:") and "rectify first" in lines[1]


def test_match_refuses_a_swapped_rectified_pair(pair, capsys, tmp_path):
    out = tmp_path / "m.json"
    code, _, err = _match(capsys, pair[1], pair[0], "--json", out)
    assert code == 2 and err.count("\n") == 1 and "swap the two files" in err and not out.exists()


def _photo(path, orientation):
    """A 40x24 colour JPEG with an EXIF Orientation tag (Pillow)."""
    from PIL import Image

    pixels = np.kron(np.random.default_rng(0).integers(0, 256, (6, 10, 3)), np.ones((4, 4, 1))).astype(np.uint8)
    exif = Image.Exif()
    exif[0x0112] = orientation
    Image.fromarray(pixels).save(path, quality=95, exif=exif.tobytes())
    return path


@pytest.mark.parametrize("orientation", [1, 6])
def test_targets_record_the_orientation_and_old_files_on_turned_photos_are_refused(tmp_path, orientation):
    import json

    from ismb_lab.labels.targets import TargetSet, load_targets, save_targets

    left, right = _photo(tmp_path / "l.jpg", orientation), _photo(tmp_path / "r.jpg", orientation)
    pair = load_pair(left, right)
    new = save_targets(tmp_path / "new.json", TargetSet([[3, 4]], [[1, 4]]))
    assert json.loads(new.read_text())["orientation"] == "upright"
    assert load_targets(new, pair=pair).orientation == "upright"
    old = tmp_path / "old.json"                                   # as written before: no orientation key
    old.write_text(json.dumps({"version": 1, "pairs": [{"left_xy": [3, 4], "right_xy": [1, 4]}]}))
    if orientation == 1:
        assert load_targets(old, pair=pair).orientation == "as stored"
        return
    with pytest.raises(ParameterError) as info:
        load_targets(old, pair=pair)
    assert "\n" not in str(info.value) and "orientation 6" in str(info.value) and "label the pair again" in str(info.value)


@pytest.mark.slow
def test_rectify_names_what_its_figures_were_measured_on(opencv_data):
    from ismb_lab.images.rectify import load_photo, measured, rectify_pair

    assert rectify_pair(opencv_data / "left01.jpg", opencv_data / "right01.jpg").measured_on == "RANSAC inliers"
    left, right = load_photo(opencv_data / "aloeL.jpg"), load_photo(opencv_data / "aloeR.jpg")
    eye = np.eye(3)
    result = measured(left, right, eye, eye, "rig")
    assert result.measured_on == "robust matches (no RANSAC)" == result.to_dict()["measured_on"]


def test_an_epipole_near_the_image_gets_a_framing_warning(opencv_data, tmp_path, capsys):
    from ismb_lab.cli import main
    from ismb_lab.images.rectify import epipole_warning, rectify_pair

    # the books pair: the camera stepped mostly forward (an epipole inside the image)
    assert main(["rectify", str(opencv_data / "left.jpg"), str(opencv_data / "right.jpg"),
                 "--out", str(tmp_path / "books")]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("warning: the") and "framing is unstable" in err
    import json
    assert json.loads((tmp_path / "books" / "rectify.json").read_text())["warnings"] == [err.strip()]
    assert rectify_pair(opencv_data / "left01.jpg", opencv_data / "right01.jpg").warnings == ()   # a sideways step
    forward = np.array([[0, -1, 240], [1, 0, -320], [-240, 320, 0]], float)   # [e]x, e at the centre
    assert "0 px from the image" in epipole_warning(forward, (480, 640))
