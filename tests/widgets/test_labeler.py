import json

import numpy as np
import pytest

from ismb_lab import ParameterError
from ismb_lab.labels.targets import load_targets, targets_from_matches
from ismb_lab.widgets.labeler import COLUMNS, LabelModel, TargetLabeler


@pytest.fixture
def labeler(prepared, tmp_path, answer_key):
    return TargetLabeler(prepared, path=tmp_path / "targets.json", answer_key=answer_key)


def side_xy(model, side, j):
    x, y = (model.left_xy if side == "left" else model.right_xy)[j]
    return (x + (model.offset if side == "right" else 0), y)


@pytest.fixture
def canvas_click(press):
    def click(labeler, side, j, jitter=(0.0, 0.0)):
        x, y = side_xy(labeler.model, side, j)
        press(labeler.pane.fig, labeler.ax, x + jitter[0], y + jitter[1])
    return click


def test_canvas_clicks_add_a_pair_and_redraw(labeler, canvas_click):
    canvas_click(labeler, "left", 2, (2.0, -1.0))
    assert labeler.model.pending == 2
    assert "left feature 3 chosen" in labeler.status.value
    canvas_click(labeler, "right", 4, (-1.5, 1.0))
    assert labeler.pairs.tolist() == [[2, 4]]
    segments = labeler.artists["lines"].get_segments()
    assert len(segments) == 1
    np.testing.assert_allclose(segments[0][0], labeler.model.left_xy[2])
    np.testing.assert_allclose(segments[0][1], labeler.model.right_xy[4] + [labeler.model.offset, 0])
    assert "<td>3</td><td>5</td>" in labeler.table.value
    assert "*" in labeler.dirty_label.value


def test_table_columns_follow_the_thesis(labeler):
    labeler.add_pair(0, 1)
    assert [c for c in COLUMNS] == ["Pair", "Left", "Right", "y_left", "x_left", "y_right", "x_right",
                                    "disparity"]
    row = labeler.model.rows()[0]
    (xl, yl), (xr, yr) = labeler.model.left_xy[0], labeler.model.right_xy[1]
    assert row == pytest.approx((1, 1, 2, yl, xl, yr, xr, np.hypot(xl - xr, yl - yr)))
    header = labeler.table.value.split("</tr>")[0]
    assert [h.split("</th>")[0] for h in header.split("<th>")[1:]] == list(COLUMNS)


def test_far_click_does_nothing_and_says_why(labeler, canvas_click, press):
    labeler.add_pair(0, 0)
    before = labeler.pairs.copy()
    canvas_click(labeler, "left", 1, (30.0, 30.0))  # nowhere near a corner of the ROI
    assert labeler.model.pending is None
    assert "no feature within" in labeler.status.value
    press(labeler.pane.fig, labeler.ax, labeler.model.width + 3, 100)  # in the gap
    assert "not on either image" in labeler.status.value
    np.testing.assert_array_equal(labeler.pairs, before)


def test_right_click_first_is_refused(labeler, canvas_click):
    canvas_click(labeler, "right", 0)
    assert len(labeler.pairs) == 0 and "left feature first" in labeler.status.value


def test_clicking_a_paired_feature_selects_and_delete_removes(labeler, canvas_click):
    labeler.add_pair(1, 2)
    labeler.add_pair(3, 4)
    assert labeler.delete_button.disabled
    canvas_click(labeler, "right", 4)
    assert labeler.model.selected == 1 and not labeler.delete_button.disabled
    assert labeler.artists["lines"].get_linewidths()[1] > labeler.artists["lines"].get_linewidths()[0]
    labeler.delete_button.click()
    assert labeler.pairs.tolist() == [[1, 2]]
    labeler.delete_button.click()  # nothing selected now
    assert labeler.pairs.tolist() == [[1, 2]]


def test_undo_button_takes_back_add_and_delete(labeler):
    labeler.add_pair(1, 2)
    labeler.add_pair(3, 4)
    labeler.model.select(0)
    labeler.delete_selected()
    labeler.undo_button.click()
    assert labeler.pairs.tolist() == [[1, 2], [3, 4]]
    labeler.undo_button.click()
    assert labeler.pairs.tolist() == [[1, 2]]
    labeler.undo_button.click()
    labeler.undo()
    assert len(labeler.pairs) == 0 and "nothing to undo" in labeler.status.value


def test_a_feature_pairs_only_once(labeler):
    labeler.add_pair(1, 2)
    with pytest.raises(ParameterError, match="'k' parameter .* already in the pair"):
        labeler.add_pair(5, 2)
    with pytest.raises(ParameterError, match="'i' parameter"):
        labeler.add_pair(99, 0)


def test_save_load_round_trip(labeler, tmp_path, prepared):
    for i, k in ((0, 1), (4, 3), (2, 2)):
        labeler.add_pair(i, k)
    labeler.save_button.click()
    assert "saved 3 pairs" in labeler.status.value and "*" not in labeler.dirty_label.value
    on_disk = load_targets(tmp_path / "targets.json", pair=prepared.pair)
    np.testing.assert_allclose(on_disk.left_xy, prepared.problem.left_xy[[0, 2, 4]])
    fresh = TargetLabeler(prepared, path=tmp_path / "targets.json")
    fresh.load_button.click()
    np.testing.assert_array_equal(fresh.pairs, labeler.pairs)
    assert "saved" == fresh.dirty_label.value


def test_a_fresh_labeller_does_not_say_saved(labeler):
    assert labeler.dirty_label.value == "" and labeler.model.save_status == ""
    labeler.add_pair(0, 1)
    assert labeler.model.save_status == "unsaved" and "*" in labeler.dirty_label.value
    labeler.undo()
    assert labeler.model.save_status == "" and labeler.dirty_label.value == ""


@pytest.mark.parametrize("content", ["{not json", '{"version": 1, "pairs": [{"left_xy": [1, 2]}]}',
                                     '{"version": 1, "pairs": [{"left_xy": [1, 1], "right_xy": [2, 2]}]}'])
def test_a_bad_file_keeps_the_labels(labeler, tmp_path, content):
    labeler.add_pair(0, 1)
    (tmp_path / "targets.json").write_text(content)
    labeler.load_button.click()
    assert labeler.pairs.tolist() == [[0, 1]]
    assert "load failed, your 1 pairs are kept" in labeler.status.value
    with pytest.raises(ParameterError):
        labeler.load()
    assert labeler.pairs.tolist() == [[0, 1]]


def test_a_failing_save_leaves_the_old_file(labeler, tmp_path):
    labeler.add_pair(0, 1)
    labeler.save()
    old = (tmp_path / "targets.json").read_text()
    labeler.add_pair(2, 3)
    labeler.save_button.click()  # fine: two pairs
    assert json.loads((tmp_path / "targets.json").read_text())["pairs"].__len__() == 2
    (tmp_path / "targets.json").write_text(old)
    labeler.model.path = tmp_path / "missing-folder" / "targets.json"
    labeler.add_pair(4, 4)
    labeler.save_button.click()
    assert "save failed" in labeler.status.value and "3 pairs are kept" in labeler.status.value
    assert len(labeler.pairs) == 3 and "*" in labeler.dirty_label.value
    assert (tmp_path / "targets.json").read_text() == old


def test_without_a_path_each_student_gets_their_own_file(prepared, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    files = []
    for user in ("ann", "bob"):
        monkeypatch.setenv("JUPYTERHUB_USER", user)
        labeler = TargetLabeler(prepared, pair_name="synthetic")
        assert labeler.model.path == tmp_path / f"targets-{user}-synthetic.json"
        assert f"targets-{user}-synthetic.json" in labeler.path_label.value
        labeler.add_pair(0, 0) if user == "ann" else labeler.add_pair(1, 1)
        labeler.save_button.click()
        files.append(labeler.model.path)
    assert all(f.is_file() for f in files) and files[0].read_text() != files[1].read_text()


def test_two_labellers_on_one_file_keep_both_pairs(prepared, tmp_path):
    path = tmp_path / "shared.json"
    first, second = LabelModel(prepared, path=path), LabelModel(prepared, path=path)
    first.add_pair(0, 0)
    second.add_pair(1, 1)
    first.save()
    second.save()
    assert load_targets(path).left_xy.tolist() == [first.left_xy[0].tolist(), first.left_xy[1].tolist()]
    assert second.pairs.tolist() == [[0, 0], [1, 1]]      # the other's pair appears after a save


def test_a_deletion_survives_another_labellers_save(prepared, tmp_path):
    path = tmp_path / "shared.json"
    a, b = LabelModel(prepared, path=path), LabelModel(prepared, path=path)
    a.add_pair(0, 0)
    a.add_pair(1, 1)
    a.save()
    b.load()
    b.add_pair(2, 2)
    a.selected = 0
    a.delete_selected()          # a removes (0, 0) and saves; b then saves its addition
    a.save()
    b.save()
    c = LabelModel(prepared, path=path)
    c.load()
    assert c.pairs.tolist() == [[1, 1], [2, 2]]


def test_load_then_save_keeps_the_files_keys_and_notes(prepared, tmp_path):
    path = tmp_path / "t.json"
    base = targets_from_matches([[0, 0], [1, 1]], prepared.problem.left_xy, prepared.problem.right_xy,
                                left_sha256=prepared.pair.left_sha256,
                                right_sha256=prepared.pair.right_sha256, labeller="ann", course="cv1")
    data = base.to_dict()
    data["pairs"][1]["note"] = "occluded in the right image?"
    path.write_text(json.dumps(data))
    model = LabelModel(prepared, path=path)
    model.load()
    model.add_pair(2, 2)
    model.save()
    saved = json.loads(path.read_text())
    assert saved["labeller"] == "ann" and saved["course"] == "cv1"
    assert saved["pairs"][1]["note"] == "occluded in the right image?" and len(saved["pairs"]) == 3


def test_answer_key_counts_and_markers(labeler, truth):
    (i, k), (j, _) = truth[0], truth[1]
    wrong_k = next(r for r in range(len(labeler.model.right_xy)) if r not in truth[:, 1])
    labeler.add_pair(i, k)
    labeler.add_pair(j, wrong_k)
    labeler.model.key_open = True        # as after five saved pairs (the gate has its own test)
    labeler.key_toggle.value = True
    c = labeler.model.compare()
    assert (len(c.correct), len(c.wrong), len(c.missing)) == (1, 1, len(truth) - 1)
    assert "1 correct, 1 wrong" in labeler.key_summary.value
    assert len(labeler.artists["missing"].get_segments()) == len(truth) - 1
    colours = labeler.artists["lines"].get_colors()
    assert not np.allclose(colours[0], colours[1])
    labeler.key_toggle.value = False
    assert labeler.key_summary.value == "" and len(labeler.artists["missing"].get_segments()) == 0


def test_from_folder_finds_the_answer_key_and_opens_it_after_five_saved_pairs(pair_folder):
    from ismb_lab.widgets.labeler import KEY_AFTER

    labeler = TargetLabeler.from_folder(pair_folder, path=pair_folder / "mine.json")
    assert labeler.key_toggle.disabled and KEY_AFTER == 5      # label first, then compare
    for i in range(KEY_AFTER - 1):
        labeler.add_pair(i, i)
    labeler.save()
    assert labeler.key_toggle.disabled                          # four saved: still the student's own work
    labeler.add_pair(KEY_AFTER - 1, KEY_AFTER - 1)
    assert labeler.key_toggle.disabled                          # five labelled, not yet saved
    labeler.save()
    assert not labeler.key_toggle.disabled
    labeler.key_toggle.value = True
    labeler.undo()
    assert not labeler.key_toggle.disabled and labeler.key_toggle.value   # once open, it stays open
    reopened = TargetLabeler.from_folder(pair_folder, path=pair_folder / "mine.json")
    reopened.load()
    assert not reopened.key_toggle.disabled                     # five of one's own, loaded back
    assert "ismb-labeler" in labeler.widget._dom_classes
    assert "ismb-stereo" in labeler.pane.widget._dom_classes
    (pair_folder / "answer_key.json").unlink()
    assert TargetLabeler.from_folder(pair_folder).key_toggle.disabled


@pytest.mark.slow
def test_rapid_clicks_leave_a_consistent_state(labeler, canvas_click):
    rng = np.random.default_rng(1)
    model = labeler.model
    for _ in range(120):
        side = ("left", "right")[rng.integers(2)]
        n = len(model.left_xy if side == "left" else model.right_xy)
        action = rng.integers(10)
        if action == 0:
            labeler.undo_button.click()
        elif action == 1:
            labeler.delete_button.click()
        else:
            canvas_click(labeler, side, rng.integers(n), rng.normal(0, 3, 2))
        pairs = labeler.pairs
        assert len(set(pairs[:, 0])) == len(pairs) and len(set(pairs[:, 1])) == len(pairs)
        assert model.selected is None or 0 <= model.selected < len(pairs)
        assert len(labeler.artists["lines"].get_segments()) == len(pairs)
        assert labeler.table.value.count("<tr>") + labeler.table.value.count("<tr style") == max(len(pairs), 1) + 1
    assert labeler.errors == []


def test_callback_exceptions_land_in_the_log(labeler, monkeypatch):
    def broken(*args):
        raise RuntimeError("boom")
    monkeypatch.setattr(labeler.model, "undo", broken)
    labeler.undo_button.click()
    assert any("RuntimeError: boom" in o["text"] for o in labeler.log.outputs)
    assert "boom" in labeler.status.value


def test_static_figure_and_repr(labeler):
    from matplotlib.figure import Figure

    labeler.add_pair(0, 1)
    fig = labeler.static_figure()
    assert isinstance(fig, Figure) and len(fig.axes[0].collections[0].get_segments()) == 1
    bundle = labeler._repr_mimebundle_()
    assert "application/vnd.jupyter.widget-view+json" in bundle
    assert labeler.pane.widget.value[:4] == b"\x89PNG"


def test_model_refuses_bad_arguments(prepared):
    with pytest.raises(TypeError, match="'prepared' parameter"):
        LabelModel("left.png")
    model = LabelModel(prepared)
    with pytest.raises(ValueError, match="'side' parameter"):
        model.click(1, 1, side="top")
    with pytest.raises(ParameterError, match="'path' parameter"):
        model.save()


def test_the_figure_fits_the_notebook_column_with_half_for_each_image(labeler):
    from ismb_lab.widgets._common import COLUMN_PX

    fig, model = labeler.pane.fig, labeler.model
    width, height = fig.bbox.width, fig.bbox.height
    assert width <= COLUMN_PX < 592            # JupyterLab's column at 1024 x 768, file browser open
    # the pair fills the figure at equal aspect: no pixel of the width is wasted on margins
    corners = labeler.ax.transData.transform([(-0.5, model.height - 0.5), (model.offset + model.width - 0.5, -0.5)])
    np.testing.assert_allclose(corners, [(0, 0), (width, height)], atol=1.0)
    image = width * model.width / (model.offset + model.width)
    assert image >= 0.45 * COLUMN_PX, f"each image gets {image:.0f} px"


def test_the_key_draws_its_three_kinds_of_line_in_far_apart_colours(labeler, truth):
    """Right, wrong and not yet labelled are shown together: no orange beside the vermillion,
    every two of them far apart (CIE ΔE above 50, where orange and vermillion are about 37)."""
    from matplotlib.colors import to_hex, to_rgb

    def _lab(colour):
        """CIE L*a*b* (D65) of a matplotlib colour."""
        rgb = np.array(to_rgb(colour))
        lin = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
        xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ lin
        f = lambda t: np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)  # noqa: E731
        fx, fy, fz = f(xyz / np.array([0.9505, 1.0, 1.089]))
        return np.array([116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)])

    (i, k), (j, _) = truth[0], truth[1]
    wrong_k = next(r for r in range(len(labeler.model.right_xy)) if r not in truth[:, 1])
    labeler.add_pair(i, k)
    labeler.add_pair(j, wrong_k)
    labeler.model.key_open = True
    labeler.key_toggle.value = True
    shown = [to_hex(c) for c in labeler.artists["lines"].get_colors()] + \
        [to_hex(c) for c in labeler.artists["missing"].get_colors()]
    assert len(set(shown)) == 3, shown
    assert all(np.linalg.norm(_lab(a) - _lab(b)) > 50 for a in set(shown) for b in set(shown) if a != b)


def test_score_saved_counts_the_labelled_corners_only(prepared, tmp_path, truth):
    """04's exercise: Method-III against a student's saved labels, which cover some corners."""
    from ismb_lab.tuning.evaluation import score
    from ismb_lab.matching.pipeline import match

    labeler = TargetLabeler(prepared, path=tmp_path / "t.json")
    assert labeler.score_saved() is None                      # nothing saved yet
    result = match(prepared=prepared, method="III", seed=0).pairs.tolist()
    # every second true pair, and one wrong label: a corner's true partner replaced by another
    mine = [tuple(p) for p in truth[::2].tolist()]
    used = {b for _, b in mine}
    i, other = next((a, b) for a, b in zip(prepared.problem.rows.tolist(), prepared.problem.cols.tolist())
                    if a in dict(mine) and b not in used)
    mine[[a for a, _ in mine].index(i)] = (i, other)
    for p in mine:
        labeler.add_pair(*p)
    labeler.save()
    unsaved = next(p for p in truth[1::2].tolist() if p[1] != other)
    labeler.add_pair(*unsaved)                                  # not saved: not scored
    found = labeler.score_saved("III", seed=0)
    lefts = {a for a, _ in mine}
    assert found.score.correct == sum(tuple(p) in mine for p in result)
    assert found.errors.tolist() == [p for p in result if p[0] in lefts and tuple(p) not in mine]
    assert (found.score.wrong_partner, found.score.extra, found.score.targets) == (len(found.errors), 0, len(mine))
    assert found.score == score(result, mine, unknown=sorted(set(range(len(prepared.problem.left_xy))) - lefts))
    assert f"{len(mine)} pairs; Method-III, seed 0: C/E/T = {found.score}" in str(found)
    assert str([(a + 1, b + 1) for a, b in found.errors.tolist()]) in str(found)
