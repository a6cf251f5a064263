"""The labeler notebook, executed, then driven from an extra cell in the same kernel."""

import json

import pytest

pytestmark = pytest.mark.notebook


def _text(outputs) -> str:
    return "".join(o.get("text", "") or o.get("data", {}).get("text/plain", "") for o in outputs)


def test_add_pair_and_save_in_the_live_kernel(live_notebook, tmp_path):
    _, run_cell = live_notebook("04_label_targets.ipynb")
    target = tmp_path / "targets.json"
    out = run_cell(
        "import json\n"
        "i = 0\n"
        "x, y = labeler.model.left_xy[i]\n"
        "k = int(((labeler.model.right_xy - (x - 20, y)) ** 2).sum(1).argmin())\n"
        "labeler.add_pair(i, k)\n"
        f"labeler.save({str(target)!r})\n"
        "print(json.dumps({'pairs': labeler.pairs.tolist(), 'k': k, 'table': labeler.table.value,\n"
        "                  'dirty': labeler.dirty_label.value, 'status': labeler.status.value}))\n")
    state = json.loads(_text(out))
    assert state["pairs"] == [[0, state["k"]]]
    assert "no pairs yet" not in state["table"] and "<td>1</td>" in state["table"]
    assert state["dirty"] == "saved"
    saved = json.loads(target.read_text())
    assert len(saved["pairs"]) == 1


def test_undo_in_the_live_kernel(live_notebook):
    _, run_cell = live_notebook("04_label_targets.ipynb")
    out = run_cell("labeler.add_pair(0, 0); labeler.add_pair(1, 1); labeler.undo()\n"
                   "print(labeler.pairs.tolist(), labeler.dirty_label.value)")
    assert _text(out).strip() == "[[0, 0]] * unsaved changes"
