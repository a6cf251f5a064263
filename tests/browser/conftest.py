"""JupyterLab and Voila in headless Chromium, driven by Playwright (see the design's TESTING.md).

The server runs on 127.0.0.1 with a token and throw-away config, data, runtime, workspace and
settings folders, on a temporary copy of notebooks/ and images/, so that Save writes there.
"""

import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = ROOT / "test-artifacts"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_http(url: str, proc: subprocess.Popen, log: Path, timeout: float = 90.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"server exited with {proc.returncode}:\n{log.read_text()[-3000:]}")
        try:
            with urllib.request.urlopen(url, timeout=2):
                return
        except (urllib.error.URLError, OSError):
            time.sleep(0.3)
    raise RuntimeError(f"server did not answer {url} within {timeout} s:\n{log.read_text()[-3000:]}")


def _wait_port(port: int, proc: subprocess.Popen, log: Path, timeout: float = 90.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"server exited with {proc.returncode}:\n{log.read_text()[-3000:]}")
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.3)
    raise RuntimeError(f"nothing listens on port {port} after {timeout} s:\n{log.read_text()[-3000:]}")


def _stop(proc: subprocess.Popen) -> None:
    """Terminate the one process this suite started, if it is still running."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


@pytest.fixture(scope="session")
def free_port():
    """``free_port()``: a free TCP port on 127.0.0.1."""
    return _free_port


@pytest.fixture
def page(browser):
    """A 1024 x 768 page: a classroom projector."""
    context = browser.new_context(viewport={"width": 1024, "height": 768})
    context.set_default_timeout(60_000)
    page = context.new_page()
    yield page
    context.close()


@pytest.fixture(autouse=True)
def deadline(request):
    """No browser test may hang the suite: each gets 240 s (a module's DEADLINE_S, if it sets
    one), then fails with a clear error."""
    seconds = getattr(request.module, "DEADLINE_S", 240)

    def expire(signum, frame):
        raise TimeoutError(f"browser test took longer than {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, previous)


@pytest.fixture(scope="session")
def workspace(tmp_path_factory):
    """A copy of notebooks/, images/ and manifests/ with the repository's layout; the notebooks
    are the students' versions (solutions and hidden tests cleared, as the hub stages them)."""
    import nbformat

    from ismb_lab.teaching.course import student_notebook

    root = tmp_path_factory.mktemp("lab")
    shutil.copytree(ROOT / "notebooks", root / "notebooks",
                    ignore=shutil.ignore_patterns(".ipynb_checkpoints", "my_targets*.json", "targets-*.json"))
    for path in (root / "notebooks").glob("[0-9][0-9]_*.ipynb"):
        nbformat.write(student_notebook(nbformat.read(path, as_version=4)), path)
    shutil.copytree(ROOT / "images", root / "images")
    shutil.copytree(ROOT / "manifests", root / "manifests")
    return root


@pytest.fixture(scope="session")
def artifacts():
    ARTIFACTS.mkdir(exist_ok=True)
    return ARTIFACTS


@pytest.fixture(scope="session")
def lab(chromium, workspace, tmp_path_factory):
    """A JupyterLab server: yields (base_url, token)."""
    home = tmp_path_factory.mktemp("jupyter")
    settings = home / "settings"
    for rel, value in (("@jupyterlab/apputils-extension/notification.jupyterlab-settings",
                        {"fetchNews": "false", "checkForUpdates": False}),
                       ("@jupyterlab/notebook-extension/tracker.jupyterlab-settings",
                        {"windowingMode": "none"})):
        (settings / rel).parent.mkdir(parents=True, exist_ok=True)
        (settings / rel).write_text(json.dumps(value))
    env = dict(os.environ, JUPYTER_CONFIG_DIR=str(home / "config"), JUPYTER_DATA_DIR=str(home / "data"),
               JUPYTER_RUNTIME_DIR=str(home / "runtime"))
    token, port = secrets.token_hex(16), _free_port()
    log = home / "server.log"
    with open(log, "w") as out:
        proc = subprocess.Popen(
            [sys.executable, "-m", "jupyterlab", "--no-browser", "--allow-root", "--ip=127.0.0.1",
             f"--port={port}", f"--IdentityProvider.token={token}",
             f"--ServerApp.root_dir={workspace}", "--LabApp.expose_app_in_browser=True",
             f"--LabApp.workspaces_dir={home / 'workspaces'}", f"--LabApp.user_settings_dir={settings}"],
            env=env, stdout=out, stderr=subprocess.STDOUT, cwd=workspace)
    base = f"http://127.0.0.1:{port}"
    try:
        _wait_http(f"{base}/api/status?token={token}", proc, log)
        yield base, token
    finally:
        try:
            request = urllib.request.Request(f"{base}/api/shutdown", method="POST",
                                             headers={"Authorization": f"token {token}"})
            urllib.request.urlopen(request, timeout=10)
            proc.wait(20)
        except (urllib.error.URLError, OSError, subprocess.TimeoutExpired):
            pass
        _stop(proc)


# Every helper finds the notebook by its path, never as "the current widget": JupyterLab
# restores the tabs of earlier tests on page load, and a restored notebook whose kernel is
# still running can be current and ready first, so a Run All sent to "the current widget"
# ran that notebook again and left the new one unrun.
_FIND = ("[...window.jupyterapp.shell.widgets('main')]"
         ".find(w => w.context && w.context.path === path)")

# The kernel-ready wait: the toolbar says idle before the session has a kernel, and a Run All
# issued then silently runs nothing.
_READY = f"""(path) => {{
  const w = window.jupyterapp && {_FIND};
  if (!w) return false;
  if (window.jupyterapp.shell.currentWidget !== w) {{ window.jupyterapp.shell.activateById(w.id); return false; }}
  if (!w.content || !w.content.activeCell || !w.context.isReady) return false;
  const s = w.sessionContext;
  if (!s || !s.isReady || !s.session || !s.session.kernel) return false;
  const k = s.session.kernel;
  return k.connectionStatus === 'connected' && k.status === 'idle';
}}"""

_RUN_ALL = f"""(path) => {{
  if (window.jupyterapp.shell.currentWidget !== {_FIND}) return false;
  window.jupyterapp.commands.execute('notebook:run-all-cells');
  return true;
}}"""

_IDLE = f"""(path) => {_FIND}.sessionContext.session.kernel.status === 'idle'"""

_ALL_RAN = f"""(path) => [...{_FIND}.content.widgets]
  .every(c => c.model.type !== 'code' || c.model.executionCount)"""

_FIRST_ERROR = f"""(path) => {{
  for (const c of {_FIND}.content.widgets) {{
    const outputs = c.model.type === 'code' ? c.model.outputs : null;
    for (let i = 0; outputs && i < outputs.length; i++) {{
      const o = outputs.get(i).toJSON();
      if (o.output_type === 'error') return `${{o.ename}}: ${{o.evalue}}`;
    }}
  }}
  return null;
}}"""

_PROGRESS = f"""(path) => {{
  const w = {_FIND};
  const code = [...w.content.widgets].map((c, i) => [i, c.model]).filter(([i, m]) => m.type === 'code');
  const waiting = code.filter(([i, m]) => !m.executionCount).map(([i, m]) => i);
  const k = w.sessionContext.session && w.sessionContext.session.kernel;
  const current = window.jupyterapp.shell.currentWidget;
  return `kernel ${{k ? k.status + '/' + k.connectionStatus : 'none'}}; code cells not run: ` +
         `${{waiting.join(', ') || 'none'}} of ${{code.length}}; current tab ` +
         `${{current && current.context ? current.context.path : current && current.id}}`;
}}"""


def run_all(page, url: str, path: str, timeout: float = 120_000):
    """Open `url` (a notebook at `path` in JupyterLab), wait for its kernel, run all cells."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    name = Path(path).name
    page.goto(url)
    page.wait_for_function(_READY, arg=path, timeout=timeout, polling=200)
    assert page.evaluate(_RUN_ALL, path), f"{name} is not the current tab"
    # Every code cell has run, or one failed (Run All stops there, so waiting on would
    # only time out).
    try:
        page.wait_for_function(f"(path) => ({_FIRST_ERROR})(path) !== null || ({_ALL_RAN})(path)",
                               arg=path, timeout=timeout, polling=250)
    except PlaywrightTimeout:
        raise AssertionError(f"{name}: Run All did not finish in {timeout / 1000:.0f} s; "
                             f"{page.evaluate(_PROGRESS, path)}") from None
    error = page.evaluate(_FIRST_ERROR, path)
    assert error is None, f"{name}: a cell failed under Run All: {error}"
    page.wait_for_function(_IDLE, arg=path, timeout=timeout, polling=200)
    return page


_DEFAULT_LAYOUT = """() => { const shell = window.jupyterapp.shell;
  const left = document.querySelector('#jp-left-stack');
  return !shell.leftCollapsed && shell.rightCollapsed && left !== null
         && left.getBoundingClientRect().width > 200; }"""


@pytest.fixture
def open_notebook(lab, page):
    """Open notebooks/<name> in JupyterLab as it opens for a student (a workspace of its own, reset:
    the file browser open at its default width, the right panel collapsed) and run all cells;
    returns the page."""
    base, token = lab

    def open_(name: str, timeout: float = 120_000):
        path = f"notebooks/{name}"
        workspace = "t-" + Path(name).stem.replace("_", "-")
        opened = run_all(page, f"{base}/lab/workspaces/{workspace}/tree/{path}?token={token}&reset", path, timeout)
        assert opened.evaluate(_DEFAULT_LAYOUT), "JupyterLab did not open in its default layout"
        return opened

    return open_


@pytest.fixture(scope="session")
def kernel_exec():
    """``kernel_exec(page, code)`` runs code in the open notebook's kernel (e.g. to force a redraw)."""
    return _kernel_exec


def _kernel_exec(page, code: str):
    page.evaluate("""async (code) => {
        const k = window.jupyterapp.shell.currentWidget.sessionContext.session.kernel;
        await k.requestExecute({code, silent: false, store_history: false}).done;
    }""", code)


@pytest.fixture
def voila(chromium, workspace, tmp_path_factory):
    """Start Voila on one notebook; yields a function name -> base URL."""
    started = []

    def serve(name: str) -> str:
        home = tmp_path_factory.mktemp("voila")
        env = dict(os.environ, JUPYTER_CONFIG_DIR=str(home / "config"),
                   JUPYTER_DATA_DIR=str(home / "data"), JUPYTER_RUNTIME_DIR=str(home / "runtime"))
        port = _free_port()
        log = home / "voila.log"
        with open(log, "w") as out:
            proc = subprocess.Popen([sys.executable, "-m", "voila", str(workspace / "notebooks" / name),
                                     "--no-browser", "--Voila.ip=127.0.0.1", f"--port={port}"],
                                    env=env, stdout=out, stderr=subprocess.STDOUT,
                                    cwd=workspace / "notebooks")
        started.append(proc)
        base = f"http://127.0.0.1:{port}"
        _wait_port(port, proc, log)
        return base

    yield serve
    for proc in started:
        _stop(proc)


# --- what a student does on the page -------------------------------------------------------

def label_targets_geometry(workspace):
    """Where left feature 0 and a right feature near it sit, as fractions of the labeler's figure.

    The labeler is built here too (Agg), with the notebook's arguments: same figure, same axes.
    """
    from ismb_lab.widgets import TargetLabeler

    labeler = TargetLabeler.from_folder(workspace / "images" / "synthetic")
    model, fig = labeler.model, labeler.pane.fig
    x, y = model.left_xy[0]
    k = int(np.argmin(np.hypot(*(model.right_xy - (x - 20, y)).T)))
    points = [(x, y), (model.right_xy[k][0] + model.offset, model.right_xy[k][1])]
    fractions = []
    for px, py in (labeler.ax.transData.transform(p) for p in points):
        fractions.append((px / fig.bbox.width, 1 - py / fig.bbox.height))
    return model.left_xy[0], model.right_xy[k], k, fractions


def click_fraction(page, canvas, fraction):
    """Click at a fraction of the element's size; Playwright scrolls it into view, waits until it
    stops moving and measures it at click time (JupyterLab still scrolls after Run All)."""
    box = canvas.bounding_box()
    canvas.click(position={"x": fraction[0] * box["width"], "y": fraction[1] * box["height"]})


def wait_sized(page, canvas):
    """Wait until the ipympl canvas has its figure's size."""
    try:
        canvas.wait_for(state="visible", timeout=60_000)
    except Exception:
        page.screenshot(path=ARTIFACTS / "failed-page.png")
        raise
    for _ in range(200):
        box = canvas.bounding_box()
        if box and box["width"] > 300 and box["height"] > 100:
            return box
        time.sleep(0.1)
    raise AssertionError(f"canvas never got its size: {canvas.bounding_box()}")


def label_one_pair(page, root, workspace):
    from playwright.sync_api import expect

    left_xy, right_xy, k, (left, right) = label_targets_geometry(workspace)
    canvas = root.locator(".ismb-stereo canvas").nth(1)   # the top canvas takes the clicks
    wait_sized(page, canvas)
    click_fraction(page, canvas, left)
    expect(root.locator(".ismb-status")).to_contain_text("left feature 1 chosen", timeout=20_000)
    click_fraction(page, canvas, right)
    row = root.locator(".ismb-pairs tr").nth(1)
    expect(row).to_contain_text(f"1{k + 1}", timeout=20_000)   # Pair 1, Left 1, Right k+1
    cells = row.locator("td").all_inner_texts()
    assert cells[:3] == ["1", "1", str(k + 1)]
    assert [float(c) for c in cells[3:7]] == [left_xy[1], left_xy[0], right_xy[1], right_xy[0]]
    return left_xy, right_xy



@pytest.fixture(scope="session")
def ui():
    """The page actions the tests share: ``run_all``, ``wait_sized``, ``label_one_pair``, ..."""
    return SimpleNamespace(run_all=run_all, wait_sized=wait_sized, click_fraction=click_fraction,
                           label_one_pair=label_one_pair, label_targets_geometry=label_targets_geometry)
