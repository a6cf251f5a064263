"""A class on JupyterHub: deploy/jupyterhub_config.py on 127.0.0.1, five students in Chromium.

The hub runs the project's own configuration with two test overrides: a dummy
authenticator (one shared password) and a simple spawner that gives each student a
folder under a temporary directory (no OS accounts).  Each student logs in, runs
notebook 04, labels one pair and saves; then each has their own targets file and
``ismb-lab targets merge`` pools the five.
"""

import json
import os
import secrets
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=True)

import psutil  # noqa: E402
import pytest  # noqa: E402
from playwright.sync_api import expect  # noqa: E402

from ismb_lab.cli import main  # noqa: E402
from ismb_lab.targets import load_targets  # noqa: E402

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parents[2]
DEPLOY = ROOT / "deploy" / "jupyterhub_config.py"
STUDENTS = [f"student{n}" for n in range(1, 6)]
DEADLINE_S = 600     # five students take longer than one notebook (see conftest's deadline)
NOTEBOOK = "ismb_lab/notebooks/04_label_targets.ipynb"


def proxy_command() -> str:
    """configurable-http-proxy from npm: .ci/run installs it into .node/ (or it is on PATH)."""
    local = ROOT / ".node" / "node_modules" / ".bin" / "configurable-http-proxy"
    found = str(local) if local.exists() else shutil.which("configurable-http-proxy")
    if found is None:
        text = "configurable-http-proxy is missing (npm install --prefix .node configurable-http-proxy)"
        if os.environ.get("CI", "").lower() in ("1", "true", "yes"):
            pytest.fail(text)
        pytest.skip(text)
    return found


@pytest.fixture
def class_hub(tmp_path, chromium, free_port):
    """The project's hub configuration on 127.0.0.1 with test accounts; yields (url, password, homes)."""
    pytest.importorskip("jupyterhub")
    chp = proxy_command()
    password, port, hub_port = secrets.token_hex(8), free_port(), free_port()
    homes, settings = tmp_path / "homes", tmp_path / "lab-settings"
    for rel, value in (("@jupyterlab/apputils-extension/notification.jupyterlab-settings",
                        {"fetchNews": "false", "checkForUpdates": False}),
                       ("@jupyterlab/notebook-extension/tracker.jupyterlab-settings",
                        {"windowingMode": "none"})):
        (settings / rel).parent.mkdir(parents=True, exist_ok=True)
        (settings / rel).write_text(json.dumps(value))
    config = tmp_path / "test_config.py"
    config.write_text(f"""
c = get_config()
load_subconfig({str(DEPLOY)!r})
c.JupyterHub.port = {port}
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = {hub_port}
c.JupyterHub.authenticator_class = "dummy"
c.DummyAuthenticator.password = {password!r}
c.Authenticator.allow_all = True
c.JupyterHub.spawner_class = "simple"
c.SimpleLocalProcessSpawner.home_dir_template = {str(homes / "{username}")!r}
c.Spawner.default_url = "/lab/tree/{NOTEBOOK}"
c.Spawner.cmd = [{sys.executable!r}, "-m", "jupyterhub.singleuser"]   # this environment's
c.Spawner.args = ["--allow-root", "--LabApp.expose_app_in_browser=True",
                  "--LabApp.user_settings_dir={settings}", "--LabApp.workspaces_dir={tmp_path / 'ws'}"]
c.ConfigurableHTTPProxy.command = [{chp!r}]
c.ConfigurableHTTPProxy.pid_file = {str(tmp_path / "proxy.pid")!r}
c.JupyterHub.db_url = "sqlite:///{tmp_path / 'hub.sqlite'}"
c.JupyterHub.cookie_secret_file = {str(tmp_path / "cookie_secret")!r}
""")
    log = tmp_path / "hub.log"
    env = dict(os.environ, ISMB_HUB_IP="127.0.0.1", JUPYTER_RUNTIME_DIR=str(tmp_path / "runtime"))
    with open(log, "w") as out:
        proc = subprocess.Popen([sys.executable, "-m", "jupyterhub", "-f", str(config)], cwd=tmp_path,
                                env=env, stdout=out, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        import urllib.error
        import urllib.request
        while True:
            if proc.poll() is not None:
                raise RuntimeError(f"the hub exited with {proc.returncode}:\n{log.read_text()[-3000:]}")
            try:
                with urllib.request.urlopen(f"{url}/hub/health", timeout=2):
                    break
            except (urllib.error.URLError, OSError):
                if time.monotonic() > deadline:
                    raise RuntimeError(f"the hub did not answer:\n{log.read_text()[-3000:]}") from None
                time.sleep(0.5)
        yield url, password, homes, proc
    finally:
        if proc.poll() is None:          # the hub stops the proxy and the servers it started
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(60)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(10)


def kernels_rss(hub_proc) -> dict:
    """Resident memory (MB) of each student's kernel process, by student, and of their servers."""
    out, servers = {}, []
    for child in psutil.Process(hub_proc.pid).children(recursive=True):
        try:
            cmd = " ".join(child.cmdline())
            if "ipykernel_launcher" in cmd:
                home = Path(child.cwd())
                student = next((p for p in home.parts if p in STUDENTS), None)
                out[student] = round(child.memory_info().rss / 2**20)
            elif "jupyterhub.singleuser" in cmd:
                servers.append(round(child.memory_info().rss / 2**20))
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
    return out, servers


def test_five_students_label_and_save_their_own_files(class_hub, browser, ui, tmp_path, artifacts):
    url, password, homes, hub_proc = class_hub
    pages = {}
    for name in STUDENTS:                         # log in: the hub starts five servers
        context = browser.new_context(viewport={"width": 1400, "height": 1000})
        context.set_default_timeout(120_000)
        page = context.new_page()
        page.goto(f"{url}/hub/login")
        page.fill("#username_input", name)
        page.fill("#password_input", password)
        page.click("#login_submit")
        pages[name] = page
    for name, page in pages.items():              # each runs notebook 04, labels one pair, saves
        try:
            ui.run_all(page, f"{url}/user/{name}/lab/tree/{NOTEBOOK}", NOTEBOOK, timeout=180_000)
        except Exception:
            page.screenshot(path=artifacts / f"hub_{name}_failed.png")
            raise AssertionError(f"{name} at {page.url}; homes: {sorted(p.name for p in homes.iterdir())}; "
                                 f"copy: {(homes / name / 'ismb_lab' / 'notebooks').exists()}") from None
        root = page.locator(".ismb-labeler")
        expect(root.locator(".ismb-path")).to_contain_text(f"targets-{name}-synthetic.json")
        ui.label_one_pair(page, root, homes / name / "ismb_lab")
        root.locator("button.ismb-save").click()
        expect(root.locator(".ismb-dirty")).to_have_text("saved", timeout=30_000)
    memory, servers = kernels_rss(hub_proc)
    (artifacts / "hub_kernels_rss_mb.json").write_text(json.dumps({"kernels": memory, "servers": servers},
                                                                  indent=2))
    pages[STUDENTS[-1]].locator(".ismb-labeler").screenshot(path=artifacts / "hub_student5_labeler.png")

    files = [homes / n / "ismb_lab" / "notebooks" / f"targets-{n}-synthetic.json" for n in STUDENTS]
    assert all(f.is_file() for f in files), [f for f in files if not f.is_file()]
    saved = [load_targets(f) for f in files]
    assert all(len(t) == 1 for t in saved)
    assert len({f.resolve() for f in files}) == 5 and len(set(map(Path.read_text, files))) == 1
    # No student wrote anywhere else in another student's folder.
    for n in STUDENTS:
        others = [p for p in (homes / n).rglob("targets-*.json") if f"targets-{n}-" not in p.name]
        assert not others

    pooled = tmp_path / "class.json"
    assert main(["targets", "merge", *map(str, files), "--out", str(pooled)]) == 0
    everyone = load_targets(pooled)
    assert len(everyone) == 1 and len(everyone.extras[0]["labelled_by"]) == 5
    assert set(memory) == set(STUDENTS) and len(servers) == 5, (memory, servers)
