"""Voilà without a hub serves one notebook to every visitor under one login: the labeller asks
each for a name and never mixes two visitors' labels."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=True)

import pytest  # noqa: E402

from ismb_lab.matching.pipeline import prepare  # noqa: E402
from ismb_lab.labels.targets import load_targets  # noqa: E402
from ismb_lab.widgets import TargetLabeler  # noqa: E402

SYNTHETIC = Path(__file__).resolve().parents[1] / "images" / "synthetic"


@pytest.fixture(scope="module")
def prepared():
    return prepare(SYNTHETIC / "left.png", SYNTHETIC / "right.png")


@pytest.fixture
def voila_page(monkeypatch, tmp_path):
    """A kernel as Voilà starts one for a page: SERVER_SOFTWARE set, no hub user."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SERVER_SOFTWARE", "voila/0.5.8")
    monkeypatch.delenv("JUPYTERHUB_USER", raising=False)
    return tmp_path


def test_voila_asks_for_a_name_before_it_saves(prepared, voila_page):
    labeler = TargetLabeler(prepared, pair_name="synthetic")
    assert labeler.name_box is not None and labeler.name_box in labeler.widget.children
    assert labeler.model.path is None and "type your name" in labeler.path_label.value
    labeler.add_pair(0, 0)
    labeler.save_button.click()
    assert "'Your name' box" in labeler.status.value and not list(voila_page.glob("*.json"))
    labeler.name_box.value = "Ann Lee"
    assert labeler.model.path == voila_page / "targets-Ann-Lee-synthetic.json"
    labeler.save_button.click()
    assert len(load_targets(voila_page / "targets-Ann-Lee-synthetic.json")) == 1


def test_two_visitors_never_share_a_file_nor_the_message(prepared, voila_page):
    ann, bob = (TargetLabeler(prepared, pair_name="synthetic") for _ in range(2))
    ann.name_box.value, bob.name_box.value = "ann", "bob"
    ann.add_pair(0, 0)
    ann.save()
    bob.add_pair(1, 1)
    bob.save()
    assert "someone else" not in bob.status.value and "another tab" not in bob.status.value
    assert load_targets(voila_page / "targets-bob-synthetic.json").left_xy.tolist() == [
        prepared.problem.left_xy[1].tolist()]
    # a third visitor typing bob's name does not merge into bob's file unless they load it
    eve = TargetLabeler(prepared, pair_name="synthetic")
    eve.name_box.value = "bob"
    eve.add_pair(2, 2)
    with pytest.raises(ValueError, match="holds labels this page did not load"):
        eve.save()
    assert "save failed" in eve.status.value
    assert len(load_targets(voila_page / "targets-bob-synthetic.json")) == 1


def test_the_hub_user_needs_no_name(prepared, voila_page, monkeypatch):
    monkeypatch.setenv("JUPYTERHUB_USER", "cy")
    labeler = TargetLabeler(prepared, pair_name="synthetic")
    assert labeler.name_box is None and labeler.model.path == voila_page / "targets-cy-synthetic.json"
