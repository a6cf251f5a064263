"""The labeller in JupyterLab's default layout on a 1024 x 768 projector: the file browser open
at its default width, the right panel collapsed, 100 % zoom.  Nothing is collapsed by the test:
the notebook column is what a student gets (about 592 px).  The canvas fits the column, and a
click on a feature's screen position reaches the kernel as that feature's image coordinate."""

import json
from pathlib import Path
import time

import matplotlib

matplotlib.use("Agg", force=True)

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from playwright.sync_api import expect  # noqa: E402

pytestmark = pytest.mark.browser

DEADLINE_S = 500

_LAYOUT = """() => { const shell = window.jupyterapp.shell;
  const panel = shell.currentWidget.content.node.getBoundingClientRect();
  const left = document.querySelector('#jp-left-stack');
  return {leftCollapsed: shell.leftCollapsed, rightCollapsed: shell.rightCollapsed,
          sidebar: left ? left.getBoundingClientRect().width : 0,
          panelRight: panel.left + shell.currentWidget.content.node.clientWidth}; }"""

# every element of the labeller whose right edge passes x
_PAST = """([selector, x]) => [...document.querySelectorAll(selector + ', ' + selector + ' *')]
  .filter(e => e.getBoundingClientRect().width > 0 && e.getBoundingClientRect().right > x + 0.5)
  .map(e => `${e.tagName.toLowerCase()}.${[...e.classList].join('.')} to ${e.getBoundingClientRect().right.toFixed(1)}`)"""

# every press the canvas receives, in data coordinates, appended to a file the test reads
_RECORD = """
import json as _json
def _record(event, _path={path!r}):
    with open(_path, "a") as _f:
        _f.write(_json.dumps([event.xdata, event.ydata]) + "\\n")
labeler.pane.fig.canvas.mpl_connect("button_press_event", _record)
"""


def test_labeller_fits_default_layout_and_clicks_map(lab, page, ui, kernel_exec, workspace,
                                                     artifacts, tmp_path):
    base, token = lab
    path = "notebooks/04_label_targets.ipynb"
    # a workspace of its own, reset: JupyterLab's layout as it opens, whatever earlier tests did
    url = f"{base}/lab/workspaces/column-04/tree/{path}?token={token}&reset"
    page = ui.run_all(page, url, path, timeout=180_000)
    layout = page.evaluate(_LAYOUT)
    assert not layout["leftCollapsed"] and layout["rightCollapsed"], layout
    assert layout["sidebar"] > 200, f"the file browser is not open at its default width: {layout}"

    root = page.locator(".ismb-labeler")
    canvas = root.locator(".ismb-stereo canvas").nth(1)   # the top canvas takes the clicks
    box = ui.wait_sized(page, canvas)
    page.wait_for_timeout(1000)                           # ipympl sizes the canvas after a frame
    box = canvas.bounding_box()
    right = layout["panelRight"]
    past = page.evaluate(_PAST, [".ismb-labeler", right])
    if past or box["x"] + box["width"] > right:
        root.screenshot(path=artifacts / "column_04_labeler.png")
    assert box["x"] + box["width"] <= right + 0.5, f"canvas {box} past the panel's edge {right}"
    assert not past, f"past the panel's edge at {right:.1f}: {past[:5]}"

    # each image gets about half the column: corners stay apart without zooming
    model = _labeler(workspace).model
    shown = box["width"] * model.width / (model.offset + model.width)
    assert shown >= 280, f"each image is {shown:.0f} px wide on screen"

    record = tmp_path / "presses.jsonl"
    kernel_exec(page, _RECORD.format(path=str(record)))
    errors = []
    status = root.locator(".ismb-status")
    # at the column's scale, then zoomed in 3x on the left image (what the toolbar's zoom does)
    for n, limits in enumerate([None, ((126.0, 232.7), (100.0, 20.0))]):
        if limits is not None:
            kernel_exec(page, f"labeler.ax.set_xlim{limits[0]}; labeler.ax.set_ylim{limits[1]}; "
                              "labeler.model.pending = None; labeler.model.message = 'zoomed'; "
                              "labeler.refresh()")
            expect(status).to_have_text("zoomed", timeout=20_000)
            page.wait_for_timeout(1000)
        xy, fraction = _where(workspace, limits)
        ui.click_fraction(page, canvas, fraction)
        expect(status).to_contain_text("left feature 1 chosen", timeout=20_000)
        x, y = json.loads(_press(record, n + 1))
        errors.append(float(np.hypot(x - xy[0], y - xy[1])))
        assert errors[-1] <= 1.5, f"clicked feature 1 at {tuple(xy)}, the kernel got ({x:.2f}, {y:.2f})"
        root.screenshot(path=artifacts / f"column_04_labeler_{n}.png")
    (artifacts / "column_04_labeler.json").write_text(json.dumps(
        {"canvas": box, "panel_right": right, "sidebar": layout["sidebar"], "image_px": shown,
         "click_error_px": errors}))


def _labeler(workspace):
    from ismb_lab.widgets import TargetLabeler

    return TargetLabeler.from_folder(workspace / "images" / "synthetic")


def _where(workspace, limits):
    """Left feature 0 and where it sits, as fractions of the figure, in the kernel's labeller
    (built here too, with the notebook's arguments and the same axis limits)."""
    labeler = _labeler(workspace)
    if limits is not None:
        labeler.ax.set_xlim(*limits[0])
        labeler.ax.set_ylim(*limits[1])
    xy = labeler.model.left_xy[0]
    px, py = labeler.ax.transData.transform(xy)
    fig = labeler.pane.fig
    return xy, (px / fig.bbox.width, 1 - py / fig.bbox.height)


def _press(record, count: int) -> str:
    """The `count`-th press the kernel recorded (the labeller's own handler runs first)."""
    for _ in range(100):
        lines = record.read_text().splitlines() if record.exists() else []
        if len(lines) >= count and record.read_text().endswith("\n"):
            return lines[count - 1]
        time.sleep(0.1)
    raise AssertionError(f"the kernel recorded {len(lines)} presses, not {count}")


# every element of an output past x, unless an ancestor inside the output clips it before x
# (k3d's hidden KaTeX MathML, for one, sits in a 1 px box with overflow hidden)
_OUTPUTS_PAST = """(x) => {
  const clipped = (e) => {
    for (let a = e.parentElement; a && !a.classList.contains('jp-OutputArea-output'); a = a.parentElement) {
      const style = getComputedStyle(a);
      if ((style.overflowX !== 'visible' || style.clip !== 'auto')
          && a.getBoundingClientRect().right <= x + 0.5) return true;
    }
    return false;
  };
  return [...document.querySelectorAll('.jp-OutputArea-output, .jp-OutputArea-output *')]
    .filter(e => e.offsetParent !== null && e.getBoundingClientRect().width > 0
                 && e.getBoundingClientRect().right > x + 0.5 && !clipped(e))
    .map(e => [e.closest('[class*="ismb-"]') !== null,
               `${e.tagName.toLowerCase()}.${[...e.classList].slice(0, 3).join('.')} `
               + `to ${e.getBoundingClientRect().right.toFixed(0)}`]);
}"""

# a button whose label does not fit it, or an output area that scrolls sideways
_CUT = """() => {
  const out = [];
  for (const area of document.querySelectorAll('.jp-OutputArea-output'))
    if (area.scrollWidth > area.clientWidth + 1)
      out.push(`output area ${area.scrollWidth}px wide in ${area.clientWidth}px`);
  for (const b of document.querySelectorAll('.jp-OutputArea-output button'))
    if (b.offsetParent !== null && b.scrollWidth > b.clientWidth + 1)
      out.push(`button "${b.innerText.trim()}" cut: ${b.scrollWidth}px in ${b.clientWidth}px`);
  return out;
}"""

NOTEBOOKS = sorted(p.name for p in (Path(__file__).resolve().parents[2] / "notebooks").glob("0*.ipynb"))


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_every_output_fits_default_layout(name, lab, page, ui, artifacts):
    base, token = lab
    path = f"notebooks/{name}"
    url = f"{base}/lab/workspaces/column-{name[:2]}/tree/{path}?token={token}&reset"
    page = ui.run_all(page, url, path, timeout=240_000)
    layout = page.evaluate(_LAYOUT)
    assert not layout["leftCollapsed"] and layout["rightCollapsed"] and layout["sidebar"] > 200, layout
    past = []
    for _ in range(3):                      # widgets render, and ipympl canvases size, after their cell ran
        page.wait_for_timeout(1500)
        past = page.evaluate(_OUTPUTS_PAST, layout["panelRight"])
    edge = layout["panelRight"]
    widgets = [text for inside, text in past if inside]
    figures = [text for inside, text in past if not inside]
    (artifacts / f"column_{name[:2]}.json").write_text(json.dumps(
        {"panel_right": edge, "widgets": widgets, "others": figures}))
    assert not widgets, f"{name}: widget parts past the panel's edge at {edge:.0f}: {widgets[:8]}"
    assert not figures, f"{name}: outputs past the panel's edge at {edge:.0f}: {figures[:8]}"
    cut = page.evaluate(_CUT)
    assert not cut, f"{name}: {cut}"
