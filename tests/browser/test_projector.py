"""Every widget and figure of every notebook fits a classroom projector: 1024 x 768, no output
area scrolling sideways, no button label cut."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=True)

import pytest  # noqa: E402

pytestmark = pytest.mark.browser

DEADLINE_S = 600
WIDGET_NOTEBOOKS = sorted(p.name for p in (Path(__file__).resolve().parents[2] / "notebooks").glob("0*.ipynb"))

_OVERFLOW = """() => {
  const out = [];
  for (const area of document.querySelectorAll('.jp-OutputArea-output')) {
    if (!area.querySelector('.widget-box, .jupyter-widgets')) continue;
    if (area.scrollWidth > area.clientWidth + 1)
      out.push(`output area ${area.scrollWidth}px wide in ${area.clientWidth}px`);
  }
  for (const b of document.querySelectorAll('.jp-OutputArea-output button')) {
    if (b.offsetParent === null) continue;
    if (b.scrollWidth > b.clientWidth + 1)
      out.push(`button "${b.innerText.trim()}" cut: ${b.scrollWidth}px in ${b.clientWidth}px`);
  }
  return out;
}"""


@pytest.fixture
def projector_page(browser):
    context = browser.new_context(viewport={"width": 1024, "height": 768})
    context.set_default_timeout(60_000)
    page = context.new_page()
    yield page
    context.close()


@pytest.mark.parametrize("name", WIDGET_NOTEBOOKS)
def test_widgets_fit_1024_by_768(name, lab, projector_page, ui, artifacts):
    base, token = lab
    path = f"notebooks/{name}"
    page = ui.run_all(projector_page, f"{base}/lab/tree/{path}?token={token}", path, timeout=180_000)
    # a presenter collapses JupyterLab's side panel; the notebook then has the screen's width
    page.evaluate("""() => { const shell = window.jupyterapp.shell;
                            if (!shell.leftCollapsed) shell.collapseLeft();
                            if (!shell.rightCollapsed) shell.collapseRight(); }""")
    page.wait_for_timeout(1500)        # ipympl canvases size themselves after the first frame
    problems = page.evaluate(_OVERFLOW)
    if problems:
        page.screenshot(path=artifacts / f"projector_{name}.png")
    assert not problems, f"{name}: {problems}"
