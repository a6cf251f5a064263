"""Scene families for the depth demo: their truth is right, their cameras differ, their renders repeat."""

import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.scenes import (FAMILIES, LAYOUT_ROI, MIN_GAP_PX, Cylinder, Group, Layout, Texture, border_scene,
                             camera_scene, contrast_scene, object_ids, object_layout, repetitive_scene)

SCENES = {"contrast": contrast_scene, "repetitive": repetitive_scene, "border": border_scene,
          "cameras": camera_scene}


@pytest.fixture(scope="module")
def layouts(rendered):
    return [rendered(object_layout, seed, 2 + seed % 2, family=family) for family in FAMILIES for seed in (3, 4)]


@pytest.mark.slow
def test_disparity_at_each_object_centre_is_the_designed_one(layouts):
    for lay in layouts:
        ids = object_ids(lay.scene)
        for o in lay.objects:
            x, y = (int(round(v)) for v in o.centre_xy)
            assert ids[y, x] == o.index, (lay.family, o)
            assert lay.scene.disparity[y, x] == pytest.approx(o.disparity, abs=0.5), (lay.family, o)
            assert lay.scene.primitives[o.index].name == o.name


def test_objects_are_ranked_by_depth_with_the_documented_gaps(layouts):
    for lay in layouts:
        d = [o.disparity for o in lay.objects]
        assert [o.rank for o in lay.objects] == list(range(1, len(d) + 1))
        assert np.all(np.diff(d) <= -MIN_GAP_PX)
        assert min(d) >= lay.wall_disparity + MIN_GAP_PX
        assert 5 <= lay.wall_disparity <= 9 and 10 <= min(d) and max(d) <= 26
        # every true match lies inside the 40 px candidate window around the layout's shift
        assert abs(max(d) - lay.shift) <= 20 and abs(lay.wall_disparity - lay.shift) <= 20
        assert lay.roi == LAYOUT_ROI
        assert {o.kind for o in lay.objects} <= {"box", "cylinder"}


def test_the_background_is_the_scene_without_its_objects(layouts):
    for lay in layouts:
        assert len(lay.background.primitives) == 1 and lay.background.primitives[0] is lay.scene.primitives[0]
        assert (lay.background.gain, lay.background.offset) == (lay.scene.gain, lay.scene.offset)
        ids = object_ids(lay.scene)
        wall = ids == 0
        # same wall, same cameras, only fresh noise where no object stands
        diff = np.abs(lay.scene.left - lay.background.left)[wall]
        assert diff.mean() < 3 * lay.scene.noise_std + 1
        assert not np.array_equal(lay.scene.left[wall], lay.background.left[wall])


@pytest.mark.slow
def test_family_functions_give_the_layout_pairs_bit_for_bit():
    for family, make in SCENES.items():
        lay = object_layout(11, 3, family=family)
        scene, empty = make(11, n_objects=3), make(11, n_objects=3, empty=True)
        assert np.array_equal(scene.left, lay.scene.left) and np.array_equal(scene.right, lay.scene.right)
        assert np.array_equal(empty.left, lay.background.left)
        again = object_layout(11, 3, family=family)
        assert np.array_equal(again.scene.right, lay.scene.right)
        assert np.array_equal(again.background.left, lay.background.left)
    assert not np.array_equal(contrast_scene(12).left, contrast_scene(11).left)
    rng_made = object_layout(np.random.default_rng(5), 2)
    assert isinstance(rng_made, Layout) and rng_made.seed is None


def test_camera_family_has_noise_and_gain_and_offset_that_differ_between_views():
    for seed in range(4):
        lay = object_layout(seed, 2, family="cameras")
        s = lay.scene
        assert 2 <= s.noise_std <= 4 and 0.75 <= s.gain <= 1.3 and -20 <= s.offset <= 20
        assert abs(s.gain - 1) > 1e-6 or abs(s.offset) > 1e-6
        # The same stretch of wall in both views of the empty pair: right = gain * left + offset.
        bg, d = lay.background, int(round(lay.wall_disparity))
        left, right = bg.left[20:220, 60:300], bg.right[20:220, 60 - d:300 - d]
        assert right.mean() == pytest.approx(s.gain * left.mean() + s.offset, abs=3)
        # Two photographs of the same wall differ by the noise of both: std sqrt(2) * noise_std.
        ids = object_ids(s)
        diff = (s.left - bg.left)[ids == 0]
        assert diff.std() == pytest.approx(np.sqrt(2) * s.noise_std, rel=0.15)
    quiet = object_layout(0, 2, family="contrast").scene
    assert quiet.noise_std == 1.0


def test_objects_near_the_border_are_partly_out_of_the_right_view(rendered):
    for seed in range(6):
        lay = rendered(object_layout, seed, 2 + seed % 2, family="border")
        o = min(lay.objects, key=lambda t: t.box_xy[0])
        mine = object_ids(lay.scene) == o.index
        cols = np.nonzero(mine)[1]
        out = mine & lay.scene.occluded
        assert out.sum() > 50, seed                                # its left part is out of the right view
        assert np.nonzero(out)[1].max() < cols.min() + o.disparity + 1
        assert (mine & ~lay.scene.occluded).sum() > 200             # the rest of it is seen
        assert o.box_xy[2] > LAYOUT_ROI[0] + 20                 # and reaches into the ROI
        assert o.box_xy[0] < LAYOUT_ROI[0]


def test_repetitive_family_uses_stripes_and_tiles_with_a_short_period():
    lay = object_layout(2, 3, family="repetitive")
    assert {o.texture for o in lay.objects} <= {"stripes", "tiles"}
    for o in lay.objects:
        y = int(o.centre_xy[1])
        x0, x1 = (int(o.box_xy[0] + f * (o.box_xy[2] - o.box_xy[0])) for f in (0.25, 0.75))
        row = lay.scene.left[y, x0:x1] - lay.scene.left[y, x0:x1].mean()
        ac = np.correlate(row, row, "full")[len(row) - 1:]
        lag = 4 + int(np.argmax(ac[4:16]))
        assert 6 <= lag <= 14 and ac[lag] > 0.2 * ac[0], (o, lag)


@pytest.mark.slow
def test_contrast_family_has_low_and_high_contrast_objects():
    seen = {o.contrast for seed in range(8) for o in object_layout(seed, 3, family="contrast").objects}
    assert seen == {"low", "high"}


def test_cylinder_side_and_caps():
    can = Cylinder((0.0, 1.2), 0.1, (-0.1, 0.1), Texture(base=0.3), name="can")
    t, info = can.intersect([[0.05, 0, 0], [0, -1.0, 1.2]], [[0, 0, 1], [0, 1, 0]])
    assert t[0] == pytest.approx(1.2 - np.sqrt(0.1 ** 2 - 0.05 ** 2))
    assert info[0, 0] == pytest.approx(0.1 * np.arcsin(0.5)) and info[0, 2] == 0
    assert t[1] == pytest.approx(0.9) and info[1, 2] == 1
    n = can.normals(info)
    assert np.allclose(np.linalg.norm(n, axis=1), 1) and np.allclose(n[1], [0, -1, 0])
    assert isinstance(object_layout(0, 3).scene.primitives[1], (Group, Cylinder))


@pytest.mark.parametrize("make, name, error", [
    (lambda: object_layout(0, 1), "n_objects", ParameterError),
    (lambda: object_layout(0, 2, family="stripes"), "family", ParameterError),
    (lambda: object_layout(-1), "seed", ParameterError),
    (lambda: object_layout("a"), "seed", ParameterTypeError),
    (lambda: contrast_scene(0, empty="yes"), "empty", ParameterTypeError),
    (lambda: object_ids(None), "scene", ParameterTypeError),
    (lambda: Cylinder((0, 1), 0.1, (0.2, 0.1), Texture()), "y_range", ParameterError),
    (lambda: Cylinder((0, 1), -0.1, (0.0, 0.1), Texture()), "radius", ParameterError),
])
def test_bad_input_names_the_parameter(make, name, error):
    with pytest.raises(error, match=rf"^The '{name}' parameter of \w[\w.]* must be .* Got .* instead\.$"):
        make()
