"""Objects found by their blobs of change (silhouettes) and refined by their features."""

import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.depth.objects import DepthConfig, depth_from_matches
from ismb_lab.depth.outlines import CHANGE_THRESHOLD, OutlineConfig, Silhouettes, silhouettes
from ismb_lab.images.io import load_pair
from ismb_lab.matching.pipeline import MatchResult
from ismb_lab.network.params import Params

H, W = 240, 320


def wall(seed=0):
    return np.random.default_rng(seed).uniform(0, 120, (H, W))


#: The threshold's blobs alone (hysteresis from the threshold itself), where a cut is what is tested.
ALONE = OutlineConfig(threshold_low=CHANGE_THRESHOLD)


def outline(**kw) -> OutlineConfig:
    return OutlineConfig(**kw)


def pairs_with(objects, seed=0):
    """Background and scene pairs of a textured wall; `objects` are (x0, x1, y0, y1, d) rectangles of
    grey 255 at left columns x0..x1-1, drawn d pixels further left in the right image (clipped)."""
    background = wall(seed)
    left, right = background.copy(), background.copy()
    for x0, x1, y0, y1, d in objects:
        left[y0:y1, max(x0, 0):min(x1, W)] = 255.0
        right[y0:y1, max(x0 - d, 0):min(x1 - d, W)] = 255.0
    return load_pair(background, background), load_pair(left, right)


def test_each_blob_gets_the_shift_that_lays_it_on_the_right_image():
    bg, sc = pairs_with([(60, 100, 60, 110, 25), (180, 230, 120, 170, 12)])
    s = silhouettes(bg, sc)
    assert len(s) == 2 and s.disparity.tolist() == [25.0, 12.0]
    assert s.score.min() > 0.95
    assert s.centroid_xy[0, 0] < s.centroid_xy[1, 0]           # numbered left to right
    assert set(np.unique(s.labels)) == {0, 1, 2}
    assert s.labels[85, 80] == 1 and s.labels[145, 205] == 2 and s.labels[20, 20] == 0


@pytest.mark.parametrize("x0, x1", [(-30, 50), (280, 350)])
def test_objects_across_the_image_border_are_compared_where_both_images_see_them(x0, x1):
    bg, sc = pairs_with([(x0, x1, 80, 140, 20)])
    s = silhouettes(bg, sc, roi=(0, 0, W, H))
    assert s.disparity.tolist() == [20.0] and s.score[0] > 0.95
    # One best shift, not a tie that the order of trying decides.
    backwards = silhouettes(bg, sc, roi=(0, 0, W, H), shifts=range(40, -1, -1))
    assert backwards.disparity.tolist() == [20.0]
    if x0 < 0:    # the blob touches the left edge: without padding, slivers of it fit any shift
        assert len(silhouettes(bg, sc, roi=(0, 0, W, H), shifts=range(40, -1, -1), config=outline(pad_px=0))) > 2


def test_an_object_cut_in_two_where_it_looks_like_the_wall_is_one():
    bg, sc = pairs_with([(150, 200, 80, 140, 22)])
    # A band of the object looks exactly like the wall behind it, in both images.
    left, right = sc.left.copy(), sc.right.copy()
    left[:, 170:180] = bg.left[:, 170:180]
    right[:, 148:158] = bg.right[:, 148:158]
    cut = load_pair(left, right)
    apart = silhouettes(bg, cut, config=outline(merge_disparity_px=0, merge_gap_px=0))
    whole = silhouettes(bg, cut)
    assert len(apart) == 2 and apart.disparity.tolist() == [22.0, 22.0]
    assert len(whole) == 1 and whole.disparity.tolist() == [22.0] and whole.score[0] > 0.95


def test_two_objects_that_touch_in_one_blob_are_cut_apart_at_the_column_between_them():
    bg, sc = pairs_with([(90, 140, 80, 160, 10), (150, 195, 100, 170, 20)])
    left, right = sc.left.copy(), sc.right.copy()
    left[120:124, 140:150] = right[120:124, 130:140] = 255.0      # a bridge: one blob in each image
    touching = load_pair(left, right)
    cut = silhouettes(bg, touching)
    assert cut.disparity.tolist() == [10.0, 20.0] and cut.score.min() >= 0.9
    assert cut.labels[100, 100] == 1 and cut.labels[150, 180] == 2
    # Each part must fit as well as a trusted blob does, and their shifts must differ: else one shift
    # lays the one blob, and one object is lost.
    assert len(silhouettes(bg, touching, config=outline(split_score=0.99))) == 1
    assert len(silhouettes(bg, touching, config=outline(split_step_px=11))) == 1


def test_two_objects_side_by_side_stay_apart_when_both_are_moved_at_once():
    """Two objects 5 px apart in the image, at 12 and 17 px.  Each one's own fit counts the change
    of its neighbour, in its padding, against it, so one shift lays their union better than either
    alone.  Moved at once, each by its own shift, the two lay on the right image's change better
    than the union, so the join leaves them apart."""
    bg, sc = pairs_with([(100, 140, 80, 150, 12), (145, 195, 90, 160, 17)])
    kept = silhouettes(bg, sc)
    assert kept.disparity.tolist() == [12.0, 17.0] and kept.score.min() > 0.9
    # The pieces of one object, at one shift, are still one.
    one = silhouettes(bg, pairs_with([(100, 140, 80, 150, 12), (145, 195, 80, 150, 12)])[1])
    assert one.disparity.tolist() == [12.0]


def test_one_object_is_not_cut():
    bg, sc = pairs_with([(90, 195, 80, 160, 14)])
    one = silhouettes(bg, sc)
    assert one.disparity.tolist() == [14.0] and one.score[0] > 0.95
    assert silhouettes(bg, sc, config=ALONE).disparity.tolist() == [14.0]


def test_two_touching_objects_far_apart_in_depth_are_cut_when_both_parts_are_moved_at_once():
    """A wide object at 10 px and a narrow one at 20 px touch in the left image; in the right image
    the near one covers the far one's right end.  The narrow part, fitted alone, counts the far
    object's change in its padding against it (Dice under 0.9), so the cut's own test keeps one
    blob, at one shift (20), and the far object is lost.  Both parts moved at once, at 10 and 20,
    lay on the right image's change better than one shift lays the blob."""
    background = wall()
    left, right = background.copy(), background.copy()
    left[100:140, 100:181] = right[100:140, 90:171] = 200.0      # far: 81 px wide, at 10 px
    left[100:140, 181:205] = right[100:140, 161:185] = 255.0     # near: 24 px wide, at 20 px, in front
    bg, sc = load_pair(background, background), load_pair(left, right)
    cut = silhouettes(bg, sc)                                    # split_far_px=5, split_far_score=0.94
    assert cut.disparity.tolist() == [10.0, 20.0]
    assert cut.labels[120, 120] == 1 and cut.labels[120, 195] == 2
    # Shifts 10 px apart are not 11 or more: one blob at one shift, the far object lost.
    assert silhouettes(bg, sc, config=outline(split_far_px=11.0, threshold_low=CHANGE_THRESHOLD)
                       ).disparity.tolist() == [20.0]
    # The blob as a whole fits one shift at 0.95, not 0.99; nor are the two shifts 11 px apart, as a
    # whole that fits under `split_far_score` needs (``split_far_poor_px``).
    assert len(silhouettes(bg, sc, config=outline(split_far_score=0.99, split_far_poor_px=11.0))) == 1


def test_two_touching_objects_that_one_shift_fits_only_fairly_are_cut_when_far_apart_in_depth():
    """A far box at 12 px and a near one at 23 px touch in the left image, and the near one covers
    the far one's right end in the right image.  One shift (14) lays the blob with a Dice under 0.94,
    so the test of two shifts far apart does not ask; with ``split_far_poor_px`` (the defaults: 8),
    shifts 8 px or more apart that lay both parts at once with 0.94 or more cut it at the true shifts."""
    background = wall()
    left, right = background.copy(), background.copy()
    left[60:100, 40:90] = right[60:100, 28:78] = 255.0           # far: at 12 px
    left[75:115, 90:125] = right[75:115, 67:102] = 200.0         # near: at 23 px, in front
    bg, sc = load_pair(background, background), load_pair(left, right)
    cut = silhouettes(bg, sc)
    assert cut.disparity.tolist() == [12.0, 23.0]
    assert cut.labels[80, 60] == 1 and cut.labels[95, 110] == 2
    # The two shifts lie 11 px apart, not 12 or more: one shift fits the blob fairly, the far box lost.
    one = silhouettes(bg, sc, config=outline(split_far_poor_px=12.0, threshold_low=CHANGE_THRESHOLD))
    assert one.disparity.tolist() == [14.0] and 0.9 <= one.score[0] < 0.94
    # The whole must fit with `split_score` or more, and both parts at once with `split_far_score` or more.
    for kw in ({"split_score": 0.95}, {"split_far_score": 0.99}):
        assert silhouettes(bg, sc, config=outline(threshold_low=CHANGE_THRESHOLD, **kw)).disparity.tolist() == [14.0]


def test_an_object_whose_halves_fit_shifts_two_pixels_apart_is_not_cut():
    """An L-shaped object: its left half (taller) at 14 px, its right half at 16 px.  Each half fits
    its own shift at 0.9 or more, so a cut of parts 2 px apart takes it for two objects; parts must
    lie 3 px or more apart (the default) to be cut."""
    background = wall()
    left, right = background.copy(), background.copy()
    left[80:160, 90:130] = right[80:160, 76:116] = 255.0
    left[100:160, 130:170] = 255.0
    right[100:160, 114:154] = 255.0
    bg, sc = load_pair(background, background), load_pair(left, right)
    assert silhouettes(bg, sc, config=outline(split_step_px=2.0)).disparity.tolist() == [14.0, 16.0]
    one = silhouettes(bg, sc)
    assert one.disparity.tolist() == [14.0] and one.score[0] > 0.95


def test_one_object_is_not_cut_where_its_parts_moved_at_once_lay_worse_than_one_shift():
    """One rectangle at 14 px, with a notch at its left edge that looks like the wall in the left
    image, and a patch inside that looks like the wall in the right image.  A left and a right part
    then fit their own shifts (18 and 14) at 0.92 each, 4 px apart, and the cut's test of each part
    takes them; both moved at once by those shifts lay on the right image's change worse than the
    whole at 14, so it is one object."""
    background = wall()
    left, right = background.copy(), background.copy()
    left[80:160, 90:190] = right[80:160, 76:176] = 255.0
    left[96:150, 90:94] = background[96:150, 90:94]
    right[89:108, 130:136] = background[89:108, 130:136]
    bg, sc = load_pair(background, background), load_pair(left, right)
    one = silhouettes(bg, sc)
    assert one.disparity.tolist() == [14.0] and one.score[0] > 0.95


def test_pieces_of_one_object_that_fit_no_shift_well_are_joined():
    """One object in two pieces (a band between them looks like the wall in the left image only), at
    12 and 14 px.  Each piece's padding holds the other's change, so each fits its own shift under
    0.9, and both moved at once by their own shifts lay better than the union at one: the join that
    keeps two objects apart refuses them.  Neither is a well-seen object, and the union fits better
    than either (0.97), so they are joined."""
    background = wall()
    left, right = background.copy(), background.copy()
    left[80:150, 100:126] = left[80:150, 132:160] = 255.0
    right[80:150, 88:120] = 255.0
    right[80:150, 118:146] = 255.0
    bg, sc = load_pair(background, background), load_pair(left, right)
    one = silhouettes(bg, sc)
    assert len(one) == 1 and one.score[0] > 0.95



def test_blobs_outside_the_roi_and_specks_are_not_objects():
    bg, sc = pairs_with([(150, 190, 100, 140, 22), (30, 33, 30, 33, 5)])
    assert len(silhouettes(bg, sc, roi=(0, 0, 100, 100), config=outline(min_pixels=50))) == 0
    assert len(silhouettes(bg, sc, roi=(0, 0, 100, 100), config=outline(min_pixels=5))) == 1
    assert len(silhouettes(bg, bg)) == 0


def test_silhouettes_bad_input_names_the_parameter():
    bg, sc = pairs_with([(150, 190, 100, 140, 22)])
    with pytest.raises(ParameterError, match="'shifts' parameter of silhouettes"):
        silhouettes(bg, sc, shifts=[])
    with pytest.raises(ParameterTypeError, match="'background' parameter of silhouettes"):
        silhouettes((bg.left, bg.right), sc)
    with pytest.raises(ParameterError, match="'scene' parameter of silhouettes"):
        silhouettes(bg, load_pair(sc.left[:200], sc.right[:200]))
    with pytest.raises(ParameterTypeError, match="'config' parameter of silhouettes"):
        silhouettes(bg, sc, config=DepthConfig())
    for name, value in (("min_pixels", 0), ("split_score", 1.5), ("split_step_px", -1), ("split_far_px", -1),
                        ("split_far_score", 2), ("split_far_poor_px", -1), ("link_score", -0.5),
                        ("max_fraction", 0), ("threshold_low", -1.0), ("threshold_low", 8.5)):
        with pytest.raises(ParameterError, match=f"'{name}' parameter of OutlineConfig"):
            OutlineConfig(**{name: value})
    with pytest.raises(ParameterTypeError, match="'outline' parameter of DepthConfig"):
        DepthConfig(outline={"pad_px": 4})
    with pytest.raises(ParameterError, match="'grouping' parameter of DepthConfig"):
        DepthConfig(grouping="blobs")
    with pytest.raises(ParameterError, match="'silhouette_score' parameter of DepthConfig"):
        DepthConfig(silhouette_score=1.5)
    with pytest.raises(ParameterError, match="'labels' parameter of Silhouettes"):
        Silhouettes(np.zeros((4, 4)), [], [], np.zeros((0, 2)))
    with pytest.raises(ParameterError, match="'disparity' parameter of Silhouettes"):
        Silhouettes(np.ones((4, 4), dtype=int), [1.0, 2.0], [1.0], [[0.0, 0.0]])


def result(left_xy, right_xy):
    left_xy, right_xy = np.asarray(left_xy, float), np.asarray(right_xy, float)
    return MatchResult("III", Params(), 0, "sweep", 0.0, 0, left_xy, right_xy,
                       np.column_stack([np.arange(len(left_xy))] * 2))


def matches(points):
    """Matches of left points (x, y, d): the right point is d pixels left."""
    p = np.asarray(points, float)
    return result(p[:, :2], p[:, :2] - np.column_stack([p[:, 2], np.zeros(len(p))]))


def blob_labels(*boxes):
    labels = np.zeros((H, W), dtype=np.int32)
    for k, (x0, x1, y0, y1) in enumerate(boxes, 1):
        labels[y0:y1, x0:x1] = k
    return labels


def test_a_trusted_blob_is_one_object_at_the_disparity_its_features_agree_on_with_its_outline():
    background = matches([(x, y, 6.0) for x in range(20, 300, 20) for y in (20, 220)])
    scene = matches([(105, 105, 22.0), (115, 110, 22.0), (125, 125, 21.0), (135, 130, 22.0),   # object A
                     (110, 120, 30.0), (120, 130, 30.0), (130, 105, 30.0),                    # A, one period off
                     (205, 105, 26.0), (215, 120, 26.0), (225, 130, 26.0),                    # B, all off
                     (60, 60, 18.0), (62, 66, 18.0),                                          # on no blob
                     (255, 105, 10.0), (265, 115, 10.0), (275, 125, 10.0)])                   # C
    labels = blob_labels((100, 140, 100, 140), (200, 230, 100, 140), (250, 280, 100, 140), (290, 300, 100, 140))
    sil = Silhouettes(labels, [22.0, 14.0, 11.0, -2.0], [0.98, 0.97, 0.5, 0.93],
                      [[120.0, 120.0], [215.0, 120.0], [265.0, 120.0], [295.0, 120.0]])
    r = depth_from_matches(background, scene, None, sil)
    a, b, c = r.objects
    assert (a.rank, a.n_features, a.silhouette_disparity, a.centroid_xy) == (1, 3, 22.0, (120.0, 120.0))
    assert a.mean_disparity == 22.0 and a.silhouette_score == 0.98      # the match at 21 lies behind 22
    # B: no feature agrees with its outline, so the outline alone places it.
    assert (b.n_features, b.mean_disparity, b.silhouette_disparity, b.n_matches) == (0, 14.0, 14.0, 0)
    # C's outline is not trusted (two objects touching, say): its features decide, as without outlines.
    assert (c.n_features, c.mean_disparity, c.silhouette_disparity) == (3, 10.0, None)
    # The last outline lies behind the wall and fits below ``firm_outline``: a sliver that looks like
    # the wall, not an object.
    assert r.silhouettes is sil and r.to_dict()["grouping"] == "silhouettes"
    assert r.to_dict()["objects"][1]["silhouette_disparity"] == 14.0
    # Without outlines the off-period bands and the stray pair are objects of their own.
    alone = depth_from_matches(background, scene, DepthConfig())
    assert len(alone.objects) > 3 and alone.to_dict()["grouping"] == "features"
    assert all(o.silhouette_disparity is None for o in alone.objects)


def test_an_outline_no_features_agree_on_is_an_object_however_poor_its_fit():
    background = matches([(x, y, 6.0) for x in range(20, 300, 20) for y in (20, 220)])
    scene = matches([(105, 105, 22.0), (115, 110, 22.0), (125, 125, 22.0),     # on the trusted blob
                     (210, 110, 25.0), (220, 125, 12.0)])                      # two that disagree
    labels = blob_labels((100, 140, 100, 140), (200, 230, 100, 140), (250, 280, 100, 140))
    sil = Silhouettes(labels, [22.0, 16.0, 3.0], [0.98, 0.6, 0.7],
                      [[120.0, 120.0], [215.0, 120.0], [265.0, 120.0]])
    r = depth_from_matches(background, scene, None, sil)
    assert [(o.silhouette_disparity, o.n_features) for o in r.objects] == [(22.0, 3), (16.0, 0)]
    assert r.objects[1].centroid_xy == (215.0, 120.0) and r.objects[1].silhouette_score == 0.6
    # The third lies behind the wall: no object.


def test_matches_behind_an_outline_do_not_count():
    """An upright cylinder's outline is its farthest visible part: its silhouette disparity (20) is
    below its front (22).  Three wrong matches 2 px behind the outline would outvote the two on the
    front; they do not count, and the front decides.  With no match left, the outline places the
    object."""
    background = matches([(x, y, 6.0) for x in range(20, 300, 40) for y in (20, 220)])
    scene = matches([(105, 105, 18.0), (115, 110, 18.0), (125, 125, 18.0),     # a period off
                     (120, 120, 22.0), (122, 130, 22.0)])                      # the front
    sil = Silhouettes(blob_labels((100, 140, 100, 140)), [20.0], [0.98], [[120.0, 120.0]])
    front = depth_from_matches(background, scene, None, sil).objects[0]
    assert (front.mean_disparity, front.n_features) == (22.0, 2)
    behind = matches([(105, 105, 18.0), (115, 110, 18.0), (125, 125, 19.5)])
    alone = depth_from_matches(background, behind, None, sil).objects[0]
    assert (alone.mean_disparity, alone.n_features) == (20.0, 0)


def test_a_lone_background_match_does_not_put_well_fitting_outlines_behind_the_background():
    """The background pair kept one match, a wrong one at 21 px, on a wall at 6.  Both outlines (21
    and 11 px, Dice 0.99) then lie behind the smallest background disparity, so neither is trusted
    and both objects are lost.  With no two background features agreeing on a disparity, there is
    no floor to lie behind; where the wall's features agree, the floor stays as it was.  (Outlines
    this firm stand in front of any floor, ``firm_outline``: raised out of reach here.)"""
    lone = matches([(160, 200, 21.0)])
    scene = matches([(110, 115, 21.0), (210, 115, 11.0)])
    sil = Silhouettes(blob_labels((100, 140, 100, 140), (200, 230, 100, 140)), [21.0, 11.0], [0.99, 0.99],
                      [[120.0, 120.0], [215.0, 120.0]])
    not_firm = DepthConfig(firm_outline=1.0)
    found = depth_from_matches(lone, scene, not_firm, sil).objects
    assert [o.silhouette_disparity for o in found] == [21.0, 11.0]
    wall_matches = matches([(x, y, 6.0) for x in range(20, 300, 20) for y in (20, 220)] + [(160, 200, 21.0)])
    r = depth_from_matches(wall_matches, scene, not_firm, sil)
    assert [o.silhouette_disparity for o in r.objects] == [21.0, 11.0]
    agreeing = matches([(160, 200, 21.0), (170, 200, 21.0)])      # two that agree: a floor, however wrong
    assert depth_from_matches(agreeing, scene, not_firm, sil).objects == ()
    assert len(depth_from_matches(agreeing, scene, None, sil).objects) == 2       # firm outlines



def two_pieces(right_shifts=(20, 25), one_piece=False):
    """One blob of two pieces (left columns 100-139 and 150-189, rows 100-139; one piece when
    `one_piece`), outline 22, and the right image's change: each piece moved by its shift."""
    labels = blob_labels((100, 190 if one_piece else 140, 100, 140))
    if not one_piece:
        labels[100:140, 150:190] = 1
    right = np.zeros((H, W), dtype=bool)
    for (x0, x1), d in zip(((100, 140), (150, 190)), right_shifts):
        right[100:140, x0 - d:x1 - d] = True
    return Silhouettes(labels, [22.0], [0.97], [[145.0, 120.0]], right, 8, range(0, 41))


def test_two_objects_in_one_blob_are_cut_apart_by_their_features():
    """Two boxes 10 px apart whose outlines fit shifts close enough to make one blob (22): their
    features say 20 and 25, one band on each piece, and each piece lies best at its band's shift.
    The cut needs two pieces, bands that agree with the pieces' outlines, and two bands on either
    side of the gap."""
    background = matches([(x, y, 6.0) for x in range(20, 300, 20) for y in (20, 220)])
    left = [(105, 105, 20.0), (115, 115, 20.0), (125, 125, 20.0), (135, 130, 20.0)]
    right = [(155, 105, 25.0), (165, 115, 25.0), (175, 125, 25.0), (185, 130, 25.0)]
    cut = DepthConfig()
    objects = depth_from_matches(background, matches(left + right), cut, two_pieces()).objects
    assert [(o.mean_disparity, o.n_features) for o in objects] == [(25.0, 4), (20.0, 4)]
    assert [o.centroid_xy for o in objects] == [(169.5, 119.5), (119.5, 119.5)]
    # The right piece's features one period off (33): its outline says 25.
    off = [(x, y, 33.0) for x, y, _ in right]
    assert len(depth_from_matches(background, matches(left + off), cut, two_pieces()).objects) == 1
    # Both pieces' outlines at 25: the left piece lies no better at 20 than at 25.
    assert len(depth_from_matches(background, matches(left + right), cut, two_pieces((25, 25))).objects) == 1
    # Bands mixed across the gap (two of each band on each piece) say nothing of where to cut.
    mixed = left[:2] + [(x, y, 25.0) for x, y, _ in left[2:]] + right[:2] + [(x, y, 20.0) for x, y, _ in right[2:]]
    assert len(depth_from_matches(background, matches(mixed), cut, two_pieces()).objects) == 1
    # Three features each are enough; two are not (``band_features``).
    assert len(depth_from_matches(background, matches(left[:3] + right[:3]), cut, two_pieces()).objects) == 2
    assert len(depth_from_matches(background, matches(left[:2] + right), cut, two_pieces()).objects) == 1


def test_a_cut_blob_is_measured_with_the_right_image_s_change():
    s = two_pieces()
    assert s.cut_dice(1, 145, (20, 25)) == 1.0 and s.cut_dice(1, 145, (22, 22)) < 0.92
    assert s.cut_shifts(1, 145, (22, 22)) == (20, 25)
    bare = Silhouettes(s.labels, s.disparity, s.score, s.centroid_xy)
    assert np.isnan(bare.cut_dice(1, 145, (20, 25)))
    with pytest.raises(ParameterError, match="'right' parameter of Silhouettes.cut_shifts"):
        bare.cut_shifts(1, 145, (20, 25))
    with pytest.raises(ParameterError, match=r"'right' parameter of Silhouettes must be a mask of the labels' shape"):
        Silhouettes(s.labels, s.disparity, s.score, s.centroid_xy, np.zeros((4, 4), dtype=bool))
    assert silhouettes(*pairs_with([(60, 100, 60, 110, 25)])).right.shape == (H, W)


@pytest.mark.parametrize("field, value, error", [("band_features", 0, ParameterError),
                                                 ("band_step_px", -1.0, ParameterError),
                                                 ("firm_outline", 1.5, ParameterError),
                                                 ("band_one_piece", 1.5, ParameterError),
                                                 ("silhouette_grow_px", -1, ParameterError)])
def test_the_band_and_outline_values_are_checked(field, value, error):
    with pytest.raises(error, match=f"'{field}' parameter of DepthConfig"):
        DepthConfig(**{field: value})


def test_an_outline_that_fits_firmly_is_not_behind_a_background_matched_one_period_off():
    """A striped wall at 6 px whose background matches all lie one period off, at 24: the floor is
    24, and both objects (outlines 17 and 12, Dice 0.99 and 0.9) lie behind it and are lost.  A
    surface seen in both images at its shift is not behind the wall: with ``firm_outline=0.95`` the
    firm outline stands in front; the poor one (a sliver like the wall, say) still does not."""
    wrong = matches([(104, 58, 24.0), (104, 81, 24.0), (104, 106, 24.0), (202, 137, 24.0)])
    scene = matches([(110, 115, 17.0), (120, 120, 17.0), (210, 115, 12.0), (220, 120, 12.0)])
    sil = Silhouettes(blob_labels((100, 140, 100, 140), (200, 230, 100, 140)), [17.0, 12.0], [0.99, 0.9],
                      [[120.0, 120.0], [215.0, 120.0]])
    assert depth_from_matches(wrong, scene, DepthConfig(firm_outline=1.0), sil).objects == ()
    firm = depth_from_matches(wrong, scene, DepthConfig(firm_outline=0.95), sil).objects
    assert [(o.silhouette_disparity, o.mean_disparity) for o in firm] == [(17.0, 17.0)]


def test_silhouettes_must_cover_the_scene():
    background = matches([(20, 20, 6.0), (60, 20, 6.0)])
    scene = matches([(300, 200, 20.0), (305, 205, 20.0)])
    small = Silhouettes(np.zeros((100, 100), dtype=np.int32), [], [], np.zeros((0, 2)))
    with pytest.raises(ParameterError, match="'silhouettes' parameter of depth_from_matches"):
        depth_from_matches(background, scene, None, small)
    with pytest.raises(ParameterTypeError, match="'silhouettes' parameter of depth_from_matches"):
        depth_from_matches(background, scene, None, np.zeros((H, W), dtype=int))


@pytest.mark.slow
def test_silhouettes_found_once_give_what_finding_them_each_time_gives():
    from ismb_lab.depth.pipeline import depth_pairs, pair_silhouettes, relative_depth
    from ismb_lab.scenes import object_layout
    from ismb_lab.depth.pipeline import layout_match_config

    layout = object_layout(1001, 2, family="repetitive")
    config = layout_match_config(layout)
    prepared = depth_pairs(layout.background, layout.scene, config)
    blobs = pair_silhouettes(prepared)
    once = relative_depth(layout.background, layout.scene, match_config=config, prepared=prepared,
                          silhouettes=blobs)
    each = relative_depth(layout.background, layout.scene, match_config=config)
    assert once.silhouettes is blobs and once.to_dict() == each.to_dict()
    np.testing.assert_array_equal(each.silhouettes.labels, blobs.labels)
    with pytest.raises(ParameterError, match="'silhouettes' parameter of relative_depth must be None when "
                                             "config.grouping is 'features'"):
        relative_depth(layout.background, layout.scene, prepared=prepared, silhouettes=blobs,
                       config=DepthConfig(grouping="features"))
    with pytest.raises(ParameterTypeError, match="'silhouettes' parameter of relative_depth"):
        relative_depth(layout.background, layout.scene, prepared=prepared, silhouettes=blobs.labels)


@pytest.mark.slow
@pytest.mark.parametrize("gain, offset", [(1.15, 0.0), (0.85, -10.0)])
def test_a_change_of_light_over_the_whole_view_is_no_outline(gain, offset):
    """The toy-car scene photographed in another light: every pixel changed, so the one blob is
    no object, and the features find the two cars as they do without outlines."""
    from ismb_lab.depth.pipeline import depth_pairs, pair_silhouettes, relative_depth
    from ismb_lab.scenes import lab_scene, toy_car_scene

    bg, sc = lab_scene(0), toy_car_scene(0)
    scene = load_pair(np.clip(sc.left * gain + offset, 0, 255), np.clip(sc.right * gain + offset, 0, 255))
    prepared = depth_pairs(load_pair(bg.left, bg.right), scene)
    blobs = pair_silhouettes(prepared)
    assert len(blobs) == 1 and blobs.score.tolist() == [0.0]
    by_outline = relative_depth(None, None, prepared=prepared, silhouettes=blobs)
    by_features = relative_depth(None, None, prepared=prepared, config=DepthConfig(grouping="features"))
    assert len(by_outline.objects) == 2
    assert [o.mean_disparity for o in by_outline.objects] == [o.mean_disparity for o in by_features.objects]



def test_outline_pieces_a_pixel_apart_are_linked_only_when_one_fits_poorly():
    """Two boxes 8 px apart in the image at 14 and 15 px: the link of pieces whose shifts differ by
    ``merge_disparity_px`` or less would make them one blob, and one object would be lost: two pieces
    that both fit with ``link_score`` or more stay apart; a piece that fits poorly (half of its change
    missing in the right image) is still linked to its neighbour."""
    bg, sc = pairs_with([(100, 140, 80, 150, 14), (148, 190, 90, 160, 15)])
    assert len(silhouettes(bg, sc, config=outline(link_score=1.0))) == 1      # every pair counts as poor
    apart = silhouettes(bg, sc)
    assert apart.disparity.tolist() == [14.0, 15.0] and apart.score.min() > 0.9
    right = sc.right.copy()
    right[125:160, 120:190] = bg.right[125:160, 120:190]
    poor = load_pair(sc.left, right)
    assert len(silhouettes(bg, poor)) == 1


def test_two_objects_that_touch_are_cut_by_their_features_where_the_outline_sees_two_shifts():
    """``band_one_piece``: one piece (the two boxes of :func:`two_pieces` touch) whose features say
    20 and 25 is cut when the two shifts lay its parts firmly and the outline itself sees two
    shifts 3 px or more apart; a one-piece outline at one shift (a cylinder whose features form
    two bands), at shifts 2 px apart, or laid less firmly than asked, is not cut."""
    background = matches([(x, y, 6.0) for x in range(20, 300, 20) for y in (20, 220)])
    scene = matches([(105, 105, 20.0), (115, 115, 20.0), (125, 125, 20.0), (135, 130, 20.0),
                     (155, 105, 25.0), (165, 115, 25.0), (175, 125, 25.0), (185, 130, 25.0)])
    cut = DepthConfig()            # band_one_piece=0.97
    objects = depth_from_matches(background, scene, cut, two_pieces(one_piece=True)).objects
    assert [(o.mean_disparity, o.n_features) for o in objects] == [(25.0, 4), (20.0, 4)]
    assert objects[0].centroid_xy[0] > 145 > objects[1].centroid_xy[0]
    for shifts in ((22, 22), (21, 23)):
        assert len(depth_from_matches(background, scene, cut, two_pieces(shifts, one_piece=True)).objects) == 1
    blurred = two_pieces(one_piece=True)
    right = blurred.right.copy()
    right[100:112] = False                       # the right image's change misses a band of rows
    blurred = Silhouettes(blurred.labels, blurred.disparity, blurred.score, blurred.centroid_xy, right, 8,
                          blurred.shifts)
    assert blurred.cut_dice(1, 145, (20, 25)) < 0.97
    assert len(depth_from_matches(background, scene, cut, blurred).objects) == 1


def test_the_features_on_a_poorly_fitting_outline_decide():
    """A blob in front of the wall whose outline fits poorly (Dice 0.7) holds four features at 18 and
    three at 24: its features decide, as without outlines (two objects)."""
    background = matches([(x, y, 6.0) for x in range(20, 300, 20) for y in (20, 220)])
    scene = matches([(105, 105, 18.0), (115, 110, 18.0), (125, 125, 18.0), (132, 130, 18.0),
                     (108, 132, 24.0), (118, 102, 24.0), (128, 112, 24.0)])
    sil = Silhouettes(blob_labels((100, 140, 100, 140)), [20.0], [0.7], [[119.5, 119.5]])
    found = depth_from_matches(background, scene, None, sil).objects
    assert [(o.mean_disparity, o.n_features, o.silhouette_disparity) for o in found] == [(24.0, 3, None),
                                                                                       (18.0, 4, None)]
    assert [o.mean_disparity for o in depth_from_matches(background, scene).objects] == [24.0, 18.0]


def hysteresis_everywhere(bg, sc):
    """The blobs :func:`silhouettes` makes with hysteresis, before it chooses region by region."""
    from ismb_lab.depth.outlines import CHANGE_SIGMA, _partition, changed_in_roi

    changed = [changed_in_roi(b, c, (0, 0, W, H), CHANGE_THRESHOLD, CHANGE_SIGMA, 0, "test", "scene", 5.0)[0]
               for b, c in ((bg.left, sc.left), (bg.right, sc.right))]
    return _partition(*changed, (0, 0, W, H), list(range(41)), OutlineConfig())


def test_hysteresis_keeps_the_faint_half_of_an_object_with_its_outline():
    """``threshold_low``: a box whose right half differs from the wall by 6 grey levels (under the
    threshold of 8) and its left half by 40 is one outline of the whole box with hysteresis at 5, and
    only its left half by the threshold alone.  (Region by region, :func:`silhouettes` keeps the
    half here: it fits better.)"""
    background = wall(3)
    left, right = background.copy(), background.copy()
    for image, x0 in ((left, 150), (right, 128)):               # 22 px nearer in the right image
        image[80:140, x0:x0 + 25] += 40.0
        image[80:140, x0 + 25:x0 + 50] += 6.0
    bg, sc = load_pair(background, background), load_pair(left, right)
    plain = silhouettes(bg, sc, roi=(0, 0, W, H), config=ALONE)
    faint = hysteresis_everywhere(bg, sc)
    assert len(plain) == len(faint) == 1 and plain.disparity[0] == faint.disparity[0] == 22
    width = [int(np.ptp(np.flatnonzero((s.labels == 1).any(axis=0)))) + 1 for s in (plain, faint)]
    assert width[0] < 30 <= 45 < width[1]


def test_hysteresis_is_raised_to_the_noise_of_the_cameras():
    """With noisy cameras (noise of 4 grey levels, independent in the background and the scene), the
    smoothed difference of an unchanged wall is about 4.5: a low threshold of 5 would join the noise
    to whatever crosses 8, so it is raised to twice the median difference."""
    from scipy.ndimage import gaussian_filter
    from skimage.filters import apply_hysteresis_threshold

    from ismb_lab.depth.outlines import changed_in_roi

    rng = np.random.default_rng(5)
    base = wall(5)
    background, scene = (base + rng.normal(0, 4.0, base.shape) for _ in range(2))
    scene[100:140, 150:200] += 40.0
    whole = (0, 0, W, H)
    plain = changed_in_roi(background, scene, whole, 8.0, 1.0, 0, "test", "scene")[0]
    low = changed_in_roi(background, scene, whole, 8.0, 1.0, 0, "test", "scene", low=5.0)[0]
    diff = gaussian_filter(np.abs(scene - background), 1.0)
    assert np.median(diff) > 4
    unraised = apply_hysteresis_threshold(diff, 5.0, 8.0)
    assert unraised.sum() > 2 * plain.sum()                    # the noise joined to the object
    assert plain.sum() <= low.sum() < 1.2 * plain.sum() and not (plain & ~low).any()


def test_each_region_keeps_the_blobs_that_fit_better_with_or_without_hysteresis():
    """A plain box nearly the wall's grey has a ragged outline, which hysteresis mends;
    a faint shadow beside a bright box joins that box under hysteresis and spoils its fit.  Region by
    region, the box keeps the outline with hysteresis and the shadowed box the one without."""
    rng = np.random.default_rng(0)
    background = rng.uniform(0, 120, (H, W))
    left, right = background.copy(), background.copy()
    grey = 60 + rng.normal(0, 3, (70, 60))
    left[80:150, 40:100] = grey
    right[80:150, 18:78] = grey                                 # 22 px nearer
    left[60:140, 180:215] = 250
    right[60:140, 150:185] = 250                                # 30 px nearer
    left[60:140, 225:265] = 230
    right[60:140, 213:253] = 230                                # 12 px nearer
    left[60:140, 215:225] += 6.0                                # the shadow, in the left image only
    bg, sc = load_pair(background, background), load_pair(left, right)
    plain, chosen = (silhouettes(bg, sc, roi=(0, 0, W, H), config=c) for c in (ALONE, None))
    grown = hysteresis_everywhere(bg, sc)
    assert plain.disparity.tolist() == grown.disparity.tolist() == chosen.disparity.tolist() == [22, 30, 12]
    assert plain.score[0] < grown.score[0] == chosen.score[0]
    assert (chosen.labels == 1).sum() > (plain.labels == 1).sum()
    assert grown.score[2] < plain.score[2] == chosen.score[2]
    assert np.array_equal(chosen.labels == 3, plain.labels == 3) and not np.array_equal(plain.labels, grown.labels)
    assert chosen.right is plain.right or np.array_equal(chosen.right, plain.right)
