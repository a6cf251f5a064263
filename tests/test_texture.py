"""The texture inside a blob (ismb_lab.texture): census costs per column, the cut where they step,
and a poorly fitting outline moved to the shift that texture and outline agree on."""

import numpy as np
import pytest

from ismb_lab.io import load_pair
from ismb_lab.silhouettes import Silhouettes
from ismb_lab.texture import census, column_costs, textured, two_shifts

SHAPE = (200, 260)


def scene(boxes, seed=0):
    """A textured wall with boxes ``(x0, x1, y0, y1, disparity, texture)`` in front (the right image
    sees each moved left by its disparity), and the right image's change."""
    rng = np.random.default_rng(seed)
    wall = rng.uniform(0, 255, SHAPE)
    left, right = wall.copy(), wall.copy()
    changed = np.zeros(SHAPE, dtype=bool)
    for x0, x1, y0, y1, d, texture in boxes:
        left[y0:y1, x0:x1] = texture
        right[y0:y1, x0 - d:x1 - d] = texture
        changed[y0:y1, x0 - d:x1 - d] = True
    return load_pair(left, right), changed


def blob(boxes, disparity, score, changed, shifts=range(0, 31)):
    """One blob over all the boxes, with the outline's shift and Dice as given."""
    labels = np.zeros(SHAPE, dtype=np.int32)
    for x0, x1, y0, y1, *_ in boxes:
        labels[y0:y1, x0:x1] = 1
    centroid = np.argwhere(labels == 1).mean(axis=0)[::-1]
    return Silhouettes(labels, [disparity], [score], [centroid], changed, 8, shifts)


def textures(*seeds, shape=(80, 60)):
    return [np.random.default_rng(100 + s).uniform(0, 255, shape) for s in seeds]


def test_census_bits_say_which_neighbours_are_brighter():
    image = np.arange(25, dtype=float).reshape(5, 5)
    bits = np.unpackbits(census(image, 1)[2, 2])[:8]
    assert bits.tolist() == [0, 0, 0, 0, 1, 1, 1, 1]     # rows above are darker, below brighter
    assert census(image).shape == (5, 5, 3)


def test_census_names_the_image_it_refuses():
    with pytest.raises(ValueError, match="image.*2-D"):
        census(np.zeros((4, 4, 3)))


def test_column_costs_find_each_column_s_shift_and_leave_the_image_s_edge_out():
    a, b = textures(0, 1)
    boxes = [(60, 120, 60, 140, 20, a), (120, 180, 60, 140, 16, b)]
    pair, changed = scene(boxes)
    mask = blob(boxes, 18, 0.9, changed).labels == 1
    cols, costs = column_costs(census(pair.left), census(pair.right), mask, range(0, 31))
    best = np.argmin(costs, axis=1)
    assert (best[cols < 118] == 20).all() and (best[cols >= 122] == 16).all()
    assert cols.min() == 62 and cols.max() == 177          # eroded by 2 columns each side
    edge = column_costs(census(pair.left), census(pair.right), mask, [70])[1]
    assert np.isnan(edge[:8]).all() and not np.isnan(edge[8:]).any()   # columns 62-69 leave it


def test_two_shifts_find_the_step_and_need_columns_on_both_sides():
    costs = np.ones((40, 3))
    costs[:25, 0] = costs[25:, 2] = 0.0
    assert two_shifts(costs, wide=10) == (1.0, 25, 0, 2)
    assert two_shifts(costs, wide=21) is None
    assert two_shifts(np.ones((40, 3)), wide=10)[0] == 0.0


def test_two_touching_objects_whose_outline_fits_between_them_are_cut():
    a, b = textures(0, 1)
    boxes = [(60, 120, 60, 140, 20, a), (120, 180, 60, 140, 16, b)]
    pair, changed = scene(boxes)
    s = blob(boxes, 18, 0.95, changed)
    cut = textured(s, pair)
    assert cut.disparity.tolist() == [20.0, 16.0]
    assert (cut.labels[:, 60:120][s.labels[:, 60:120] == 1] == 1).all()
    assert (cut.labels[:, 120:180][s.labels[:, 120:180] == 1] == 2).all()
    assert (cut.score > 0.9).all()
    assert textured(s, pair, gain=None, poor=None) is s


def test_a_surface_that_steps_by_a_pixel_at_a_time_is_not_cut():
    # A cylinder's front is nearer than its sides by a pixel or two: no step of 3 px.
    strips = textures(0, 1, 2, 3, shape=(80, 25))
    boxes = [(60 + 25 * i, 85 + 25 * i, 60, 140, 14 + i, t) for i, t in enumerate(strips)]
    pair, changed = scene(boxes)
    s = blob(boxes, 15, 0.95, changed)
    assert textured(s, pair) is s


def test_a_poorly_fitting_outline_moves_to_the_texture_s_shift():
    (a,) = textures(0)
    boxes = [(100, 160, 60, 140, 12, a)]
    pair, changed = scene(boxes)
    s = blob(boxes, 5, 0.8, changed)
    moved = textured(s, pair)
    assert moved.disparity.tolist() == [12.0] and moved.score[0] == pytest.approx(1.0)
    assert textured(s, pair, poor=None) is s
    assert textured(blob(boxes, 5, 0.95, changed), pair).disparity.tolist() == [5.0]   # fits well: kept


def test_stripes_a_period_off_are_told_apart_by_the_outline():
    columns = 128 + 100 * np.sign(np.sin(2 * np.pi * np.arange(60) / 8))    # a period of 8 px
    stripes = np.tile(columns, (80, 1))
    boxes = [(100, 160, 60, 140, 12, stripes)]
    pair, changed = scene(boxes)
    s = blob(boxes, 12, 0.85, changed)
    cols, costs = column_costs(census(pair.left), census(pair.right), s.labels == 1, range(0, 31))
    inside = (cols >= 110) & (cols <= 140)           # moved by 4, 12 or 20, still on the box
    # The texture alone cannot choose between shifts a period apart; half a period off it can.
    assert np.abs(costs[inside][:, [4, 20]] - costs[inside][:, [12]]).max() < 0.2
    assert costs[inside, 16].min() > 5
    assert textured(s, pair) is s                    # the outline keeps 12
    assert textured(blob(boxes, 3, 0.85, changed), pair).disparity.tolist() == [12.0]


def test_pair_silhouettes_names_a_wrong_texture_option():
    from ismb_lab.depth_demo import depth_pairs, pair_silhouettes
    from ismb_lab.scenes import lab_scene, toy_car_scene

    prepared = depth_pairs(lab_scene(0), toy_car_scene(0))
    for option, value, error in (("texture_gain", 1.5, ValueError), ("texture_poor", -0.1, ValueError),
                                 ("texture_gain", "a", TypeError)):
        with pytest.raises(error, match=option):
            pair_silhouettes(prepared, **{option: value})


def test_the_texture_functions_name_what_they_refuse():
    (a,) = textures(0)
    boxes = [(100, 160, 60, 140, 12, a)]
    pair, changed = scene(boxes)
    s = blob(boxes, 5, 0.8, changed)
    codes = census(pair.left), census(pair.right)
    mask = s.labels == 1
    cases = [
        (lambda: column_costs(pair.left, codes[1], mask, [1]), TypeError, "left"),
        (lambda: column_costs(codes[0], codes[1][:10], mask, [1]), ValueError, "right"),
        (lambda: column_costs(*codes, mask[:10], [1]), ValueError, "mask"),
        (lambda: column_costs(*codes, mask, [1.5]), TypeError, "shifts"),
        (lambda: two_shifts(np.ones(5)), ValueError, "costs"),
        (lambda: two_shifts(np.ones((40, 3)), wide=0), ValueError, "wide"),
        (lambda: textured(pair, pair), TypeError, "silhouettes"),
        (lambda: textured(s, pair.left), TypeError, "scene"),
        (lambda: textured(s, pair, gain=2), ValueError, "gain"),
        (lambda: textured(s, pair, poor=-1), ValueError, "poor"),
        (lambda: textured(s, pair, window=(6, -4)), ValueError, "window"),
        (lambda: textured(s, pair, window=3), TypeError, "window"),
    ]
    for call, error, name in cases:
        with pytest.raises(error, match=name):
            call()
