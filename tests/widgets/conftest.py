"""Widget tests run without a browser: Agg canvases, controls driven from Python."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=True)

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.backend_bases import MouseEvent  # noqa: E402

from ismb_lab.matching.pipeline import prepare  # noqa: E402
from ismb_lab.scenes import synthetic_scene, true_matches  # noqa: E402
from ismb_lab.labels.targets import save_targets, targets_from_matches  # noqa: E402

SYNTHETIC = Path(__file__).resolve().parents[2] / "images" / "synthetic"


@pytest.fixture(scope="session")
def prepared():
    return prepare(SYNTHETIC / "left.png", SYNTHETIC / "right.png")


@pytest.fixture(scope="session")
def truth(prepared, rendered):
    """Ground-truth (i, k) feature pairs of images/synthetic, from the scene that rendered it."""
    partner = true_matches(rendered(synthetic_scene, 0), prepared.problem.left_xy, prepared.problem.right_xy)
    pairs = np.array([(i, k) for i, k in enumerate(partner) if k >= 0])
    # one partner per right feature, as a hand labeller would give
    _, first = np.unique(pairs[:, 1], return_index=True)
    return pairs[np.sort(first)]


@pytest.fixture(scope="session")
def answer_key(prepared, truth):
    p = prepared.pair
    return targets_from_matches(truth, prepared.problem.left_xy, prepared.problem.right_xy,
                                left_sha256=p.left_sha256, right_sha256=p.right_sha256)


@pytest.fixture
def pair_folder(tmp_path, answer_key):
    """A copy of images/synthetic with an answer key."""
    folder = tmp_path / "pair"
    folder.mkdir()
    for name in ("left.png", "right.png"):
        (folder / name).write_bytes((SYNTHETIC / name).read_bytes())
    save_targets(folder / "answer_key.json", answer_key)
    return folder


def _press(fig, ax, x, y, button=1):
    """Send a mouse press at data point (x, y) of `ax` through the canvas' callbacks."""
    px, py = ax.transData.transform((x, y))
    event = MouseEvent("button_press_event", fig.canvas, px, py, button=button)
    fig.canvas.callbacks.process("button_press_event", event)
    return event


@pytest.fixture(scope="session")
def press():
    return _press
