"""What the photo path says about a pair: sizes as width x height, swapped and unrectified pairs."""

import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab.io import load_pair


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
    from ismb_lab.rectify import check_rectified, rectify_pair

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
