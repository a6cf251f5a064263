"""A student's own photos in notebook 09, in JupyterLab's default layout at 1024 x 768 (nothing
collapsed): upload two JPEGs, rectify, label a pair, save."""

import json

import matplotlib

matplotlib.use("Agg", force=True)

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from playwright.sync_api import expect  # noqa: E402

from ismb_lab.labels.classroom import user_name  # noqa: E402

pytestmark = pytest.mark.browser
DEADLINE_S = 300


@pytest.fixture
def data(opencv_data):
    return opencv_data


def geometry(folder):
    """Where left feature 0 and the right feature on its row sit, as fractions of the labeller's
    figure, built here as the kernel builds it (same folder, ROI and window)."""
    from ismb_lab.matching.pipeline import MatchConfig
    from ismb_lab.widgets import TargetLabeler

    labeler = TargetLabeler.from_folder(folder, config=MatchConfig(roi="center", shift="auto"))
    model, fig = labeler.model, labeler.pane.fig
    x, y = model.left_xy[0]
    k = int(np.argmin(np.abs(model.right_xy[:, 1] - y) * 10 + np.abs(model.right_xy[:, 0] - x) * 0.01))
    points = [(x, y), (model.right_xy[k][0] + model.offset, model.right_xy[k][1])]
    fractions = [(px / fig.bbox.width, 1 - py / fig.bbox.height)
                 for px, py in (labeler.ax.transData.transform(p) for p in points)]
    return model.left_xy[0], model.right_xy[k], fractions


def test_upload_rectify_label_and_save(open_notebook, ui, workspace, artifacts, data):
    # notebook 09 as a student meets it: Run All, the file browser open, at 1024 x 768
    page = open_notebook("09_your_own_photos.ipynb", timeout=240_000)
    root = page.locator(".ismb-photos")
    with page.expect_file_chooser() as chooser:       # the upload button opens the file dialog
        root.locator("button.ismb-upload").click()
    chooser.value.set_files([str(data / "left.jpg"), str(data / "right.jpg")])
    expect(root.locator(".ismb-status").first).to_contain_text("not rectified", timeout=60_000)
    root.locator("button.ismb-rectify").click()
    expect(root.locator(".ismb-status").first).to_contain_text("rectified (uncalibrated)", timeout=60_000)
    root.locator("button.ismb-use").click()
    labeler = root.locator(".ismb-labeler")
    expect(labeler).to_be_visible(timeout=60_000)
    folder = workspace / "notebooks" / f"photos-{user_name()}-left"
    assert (folder / "left.png").is_file() and json.loads((folder / "rectify.json").read_text())["median_abs_dy_px"] <= 1
    left_xy, right_xy, (left, right) = geometry(folder)
    canvas = labeler.locator(".ismb-stereo canvas").nth(1)
    ui.wait_sized(page, canvas)
    ui.click_fraction(page, canvas, left)
    expect(labeler.locator(".ismb-status")).to_contain_text("left feature 1 chosen", timeout=20_000)
    ui.click_fraction(page, canvas, right)
    expect(labeler.locator(".ismb-dirty")).to_contain_text("unsaved", timeout=20_000)
    labeler.locator("button.ismb-save").click()
    expect(labeler.locator(".ismb-dirty")).to_have_text("saved", timeout=20_000)
    saved = json.loads((workspace / "notebooks" / f"targets-{user_name()}-{folder.name}.json").read_text())
    assert [(p["left_xy"], p["right_xy"]) for p in saved["pairs"]] == [(list(left_xy), list(right_xy))]
    root.screenshot(path=artifacts / "09_own_photos.png")
