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
