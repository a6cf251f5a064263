"""The 3-D point clouds in real Chromium: WebGL drawn in 07, 09 and Voila, nothing fetched from
beyond 127.0.0.1 (every such request is refused and recorded)."""

import json

import matplotlib

matplotlib.use("Agg", force=True)

import pytest  # noqa: E402

pytestmark = pytest.mark.browser

DEADLINE_S = 420

# A canvas holding a 2-D context answers getContext("2d"); one holding a WebGL context answers
# null there, and getContext("webgl2"/"webgl") then returns that context (never a new one).
_WEBGL = """(root) => [...root.querySelectorAll('canvas')].map(c => {
  if (c.getContext('2d') !== null) return null;
  const gl = c.getContext('webgl2') || c.getContext('webgl');
  if (!gl || gl.isContextLost()) return null;
  const r = c.getBoundingClientRect();
  return {kind: gl.constructor.name, width: r.width, height: r.height, buffer: gl.drawingBufferWidth};
}).filter(x => x)"""


@pytest.fixture
def offline(page):
    """Refuse every request that leaves 127.0.0.1; return the list of refused URLs."""
    refused = []

    def route(r):
        url = r.request.url
        if url.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:")):
            r.continue_()
        else:
            refused.append(url)
            r.abort()

    page.route("**/*", route)
    return refused


# Voila's own page template (share/jupyter/voila/templates/lab/index.html.j2) links Font Awesome's
# icon CSS from jsDelivr; refused, it changes nothing here.  Nothing else may leave 127.0.0.1.
VOILA_TEMPLATE_CDN = ("https://cdn.jsdelivr.net/npm/@fortawesome/fontawesome-free@%5E5/css/all.min.css",
                      "https://cdn.jsdelivr.net/npm/@fortawesome/fontawesome-free@%5E5/css/v4-shims.min.css")


def webgl_view(page, root, artifacts, name):
    """Wait for the cloud's WebGL canvas in `root`; check its size against the output area's."""
    root.locator("canvas").first.wait_for(state="visible", timeout=90_000)
    for _ in range(100):
        found = root.evaluate(_WEBGL)
        if found and found[0]["width"] > 300:
            break
        page.wait_for_timeout(200)
    root.scroll_into_view_if_needed()
    page.wait_for_timeout(1500)          # let k3d draw its first frames before the screenshot
    root.screenshot(path=artifacts / f"{name}_cloud.png")
    assert found, f"{name}: no WebGL context on the 3-D view's canvases"
    gl = found[0]
    assert gl["kind"] in ("WebGL2RenderingContext", "WebGLRenderingContext") and gl["buffer"] > 0
    area = root.evaluate("e => (e.closest('.jp-OutputArea-output') || e.parentElement).clientWidth")
    assert gl["width"] == pytest.approx(area, abs=30), f"{name}: the view is {gl['width']} px in {area} px"
    return gl


def test_toy_car_cloud_draws_with_webgl(open_notebook, offline, artifacts):
    page = open_notebook("07_toy_car_depth.ipynb")
    root = page.locator(".ismb-depth .ismb-cloud")
    webgl_view(page, root, artifacts, "07")
    caption = root.locator(".ismb-cloud-caption")
    assert "scene matches kept" in caption.inner_text()
    # a change of method in the page updates the same view: its caption follows the model
    page.locator(".ismb-depth .ismb-method select").select_option(label="I")
    from playwright.sync_api import expect
    expect(page.locator(".ismb-depth .ismb-status")).to_contain_text("Method-I,", timeout=60_000)
    assert root.evaluate(_WEBGL), "the WebGL context was lost after an update"
    assert offline == [], f"requests beyond 127.0.0.1: {offline[:5]}"


def coloured_share(locator) -> float:
    """The share of a screenshot's pixels in colour (the points: grey axes, cameras and text aside)."""
    import io

    import matplotlib.image

    rgb = matplotlib.image.imread(io.BytesIO(locator.screenshot()), format="png")[:, :, :3]
    return float(((rgb.max(axis=2) - rgb.min(axis=2)) > 0.25).mean())


def settled_share(page, locator, differs=None, timeout_s: float = 30.0) -> float:
    """:func:`coloured_share` once two screenshots 0.5 s apart agree (k3d draws in frames), and
    when `differs` is given, once it is no longer that value."""
    last = None
    for _ in range(int(timeout_s / 0.5)):
        share = coloured_share(locator)
        if share == last and (differs is None or abs(share - differs) > 1e-9):
            return share
        last = share
        page.wait_for_timeout(500)
    return last


_SHOWN_TEXT = """(root, text) => [...root.querySelectorAll('*')].filter(n => n.childElementCount === 0
  && n.textContent.trim() === text && n.getClientRects().length > 0
  && getComputedStyle(n).visibility !== 'hidden').length"""


def test_held_out_pair_cloud_draws_with_webgl(open_notebook, offline, opencv_data, artifacts, kernel_exec):
    """09's rig-driven cloud (RigCloud on held-out pair 14): WebGL in the column, the network's
    points drawn in colour, each axis titled once, the colour scale above the canvas; the toggle
    adds SGBM's points; a swapped pair is refused in one line and leaves no point drawn."""
    from playwright.sync_api import expect

    page = open_notebook("09_your_own_photos.ipynb", timeout=400_000)
    widget = page.locator(".ismb-rig-cloud")
    assert widget.count() == 1
    root = widget.locator(".ismb-cloud")
    assert root.count() == 1
    webgl_view(page, root, artifacts, "09")
    caption = root.locator(".ismb-cloud-caption").inner_text()
    assert "the network's" in caption and "matches (Method-III) in metres" in caption
    status = widget.locator(".ismb-status")
    expect(status).to_contain_text("pair 14: raw photos, rectified with the rig", timeout=30_000)
    assert "SGBM agrees with the network at" in status.inner_text()
    for title in ("X (m)", "Z (m)", "-Y (m)"):
        assert root.evaluate(_SHOWN_TEXT, title) == 1, f"{title} is not drawn exactly once"
    canvas = root.locator("canvas").first
    scale = root.locator(".ismb-cloud-colours").bounding_box()
    assert scale["height"] > 5 and scale["y"] + scale["height"] <= canvas.bounding_box()["y"] + 1
    sparse = settled_share(page, canvas)
    assert sparse > 0, "the network's points are not drawn"
    widget.locator("button.ismb-dense").click()
    dense = settled_share(page, canvas, differs=sparse)
    canvas.screenshot(path=artifacts / "09_cloud_sgbm.png")
    assert dense > 2 * sparse, f"SGBM's points did not appear: {sparse:.4f} -> {dense:.4f} of the pixels in colour"
    kernel_exec(page, "cloud14.load(right14, left14, 'pair 14 swapped')")
    expect(status).to_contain_text("pair 14 swapped refused:", timeout=60_000)
    said = status.inner_text()
    assert "swap the two files" in said and "\n" not in said.strip()
    assert settled_share(page, canvas, differs=dense) == 0, "a refused pair left points drawn"
    root.screenshot(path=artifacts / "09_cloud_refused.png")
    assert offline == [], f"requests beyond 127.0.0.1: {offline[:5]}"


def test_voila_cloud_draws_with_webgl(voila, page, offline, workspace, artifacts):
    notebook = {"cells": [{"cell_type": "code", "execution_count": None, "id": "cloud", "metadata": {},
                           "outputs": [], "source": [
                               "from ismb_lab.widgets.cloud import PointCloudView, depth_cloud\n",
                               "from ismb_lab.widgets import DepthModel\n",
                               "model = DepthModel('../images/lab', '../images/toy_cars')\n",
                               "PointCloudView(depth_cloud(model)).widget"]}],
                "metadata": {"kernelspec": {"display_name": "Python 3 (ipykernel)", "language": "python",
                                            "name": "python3"}},
                "nbformat": 4, "nbformat_minor": 5}
    (workspace / "notebooks" / "cloud_voila.ipynb").write_text(json.dumps(notebook))
    page.goto(voila("cloud_voila.ipynb"), timeout=120_000)
    root = page.locator(".ismb-cloud")
    root.wait_for(timeout=120_000)
    webgl_view(page, root, artifacts, "voila")
    others = [url for url in offline if url not in VOILA_TEMPLATE_CDN]
    assert others == [], f"requests beyond 127.0.0.1: {others[:5]}"
