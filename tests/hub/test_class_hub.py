"""The class hub as deploy/README.md sets it up, with real accounts: logins, privacy, the
course copy, culling and the memory limit.

The hub runs deploy/jupyterhub_config.py unchanged, as root, on 127.0.0.1; the test sets only
the environment variables that deploy/README.md documents (ports, venv, course folder,
state folder, timeouts, memory limit, and PATH for the proxy). Students log in through the
login form with their own passwords, as a browser would.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import socket
import stat
import subprocess
import tempfile
import time
import uuid
from pathlib import Path

import pytest

from ismb_lab.teaching import hub_start

from .conftest import venv_env

pytestmark = pytest.mark.hub

ROOT = Path(__file__).resolve().parents[2]
IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")


def _unavailable(text: str):
    """Missing tools fail under CI=true (so a broken install step cannot hide), else skip."""
    if IN_CI:
        pytest.fail(text)
    pytest.skip(text)

DEPLOY = ROOT / "deploy" / "jupyterhub_config.py"
ARTIFACTS = ROOT / "test-artifacts"
MEM_LIMIT = "768M"
CULL_TIMEOUT = 40            # seconds; the servers' idle timeout
KERNEL_CULL_TIMEOUT = 10     # seconds; a kernel without a tab


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="session")
def proxy_folder() -> str:
    """The folder holding configurable-http-proxy: .ci/run installs it into .node/."""
    local = ROOT / ".node" / "node_modules" / ".bin"
    if (local / "configurable-http-proxy").exists():
        return str(local)
    found = shutil.which("configurable-http-proxy")
    if found is None:
        _unavailable("configurable-http-proxy is missing (npm install --prefix .node configurable-http-proxy)")
    return str(Path(found).parent)


def cgroups_writable() -> bool:
    probe = hub_start.CGROUP_ROOT / "memory" / f"ismb-probe-{uuid.uuid4().hex[:8]}"
    try:
        probe.mkdir()
    except OSError:
        return False
    probe.rmdir()
    return True


def wait_for(check, timeout: float, what: str, step: float = 0.5):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(step)
    raise AssertionError(f"{what}: not within {timeout} s")


class Student:
    """One student's browser session: the login form, then their server's APIs."""

    def __init__(self, url: str, account):
        import requests

        self.url, self.account, self.name = url, account, account.name
        self.http = requests.Session()

    def log_in(self) -> int:
        page = self.http.get(f"{self.url}/hub/login")
        page.raise_for_status()
        form = {"username": self.name, "password": self.account.password,
                "_xsrf": self.http.cookies.get("_xsrf", path="/hub/")}
        answer = self.http.post(f"{self.url}/hub/login?next=", data=form, allow_redirects=False)
        self.next = answer.headers.get("Location", "/hub/spawn")
        return answer.status_code

    def spawn(self) -> None:
        """Follow the login's redirect, as a browser does: /hub/spawn starts the server."""
        self.http.get(f"{self.url}{self.next}" if self.next.startswith("/") else self.next, timeout=60)

    def open_lab(self, timeout: float = 120) -> float:
        """GET /user/NAME/lab, following the hub's redirects, until the lab answers; the seconds."""
        start, lab = time.monotonic(), f"{self.url}/user/{self.name}/lab"

        def ready():
            answer = self.http.get(lab, timeout=30)
            return answer.status_code == 200 and answer.url.split("?")[0].rstrip("/") == lab
        wait_for(ready, timeout, f"{self.name}'s JupyterLab", step=1)
        return time.monotonic() - start

    def api(self, method: str, path: str, **kwargs):
        xsrf = self.http.cookies.get("_xsrf", path=f"/user/{self.name}/") or self.http.cookies.get("_xsrf")
        headers = {"X-XSRFToken": xsrf} if xsrf else {}
        return self.http.request(method, f"{self.url}/user/{self.name}/api/{path}", headers=headers,
                                 timeout=60, **kwargs)

    def terminal(self, commands: str, timeout: float = 180) -> str:
        """Type `commands` into a new JupyterLab terminal of this student's (the terminals API and
        its websocket, as JupyterLab's Terminal tab does); what the terminal showed."""
        import websocket

        made = self.api("POST", "terminals")
        assert made.status_code == 200, (made.status_code, made.text[:300])
        name = made.json()["name"]
        url = f"{self.url.replace('http', 'ws', 1)}/user/{self.name}/terminals/websocket/{name}"
        cookie = "; ".join(f"{c.name}={c.value}" for c in self.http.cookies)
        xsrf = self.http.cookies.get("_xsrf", path=f"/user/{self.name}/")
        ws = websocket.create_connection(f"{url}?_xsrf={xsrf}" if xsrf else url, header=[f"Cookie: {cookie}"],
                                         timeout=timeout)
        shown, deadline = "", time.monotonic() + timeout
        try:
            # the mark is split in what is typed, so only its output completes it
            ws.send(json.dumps(["stdin", f"{commands}; echo ISMB-TERM''INAL-DONE\r"]))
            while "ISMB-TERMINAL-DONE" not in shown and time.monotonic() < deadline:
                message = json.loads(ws.recv())
                if message[0] == "stdout":
                    shown += message[1]
        finally:
            ws.close()
            self.api("DELETE", f"terminals/{name}")
        return shown

    def start_kernel(self) -> str:
        answer = self.api("POST", "kernels", json={"name": "python3"})
        assert answer.status_code == 201, (answer.status_code, answer.text[:300])
        return answer.json()["id"]

    def execute(self, kernel: str, code: str, timeout: float = 90) -> dict:
        """Run `code` in `kernel` over its websocket; what the student's cell would show."""
        import websocket

        url = f"{self.url.replace('http', 'ws', 1)}/user/{self.name}/api/kernels/{kernel}/channels"
        cookie = "; ".join(f"{c.name}={c.value}" for c in self.http.cookies)
        xsrf = self.http.cookies.get("_xsrf", path=f"/user/{self.name}/")
        ws = websocket.create_connection(f"{url}?_xsrf={xsrf}" if xsrf else url, header=[f"Cookie: {cookie}"],
                                         timeout=timeout)
        msg_id = uuid.uuid4().hex
        ws.send(json.dumps({
            "header": {"msg_id": msg_id, "msg_type": "execute_request", "username": self.name,
                       "session": uuid.uuid4().hex, "date": "", "version": "5.3"},
            "parent_header": {}, "metadata": {}, "channel": "shell",
            "content": {"code": code, "silent": False, "store_history": False, "user_expressions": {},
                        "allow_stdin": False, "stop_on_error": True}}))
        seen = {"status": None, "ename": None, "evalue": None, "stdout": "", "states": []}
        deadline = time.monotonic() + timeout
        try:
            while time.monotonic() < deadline and seen["status"] is None:
                try:
                    message = json.loads(ws.recv())
                except websocket.WebSocketConnectionClosedException:
                    seen["status"] = "closed"
                    break
                kind, content = message.get("msg_type"), message.get("content", {})
                if kind == "status":
                    seen["states"].append(content.get("execution_state"))
                    if content.get("execution_state") in ("restarting", "dead"):
                        seen["status"] = content["execution_state"]
                if message.get("parent_header", {}).get("msg_id") != msg_id:
                    continue
                if kind == "stream":
                    seen["stdout"] += content.get("text", "")
                elif kind == "error":
                    seen["ename"], seen["evalue"] = content.get("ename"), content.get("evalue")
                elif kind == "execute_reply":
                    seen["status"] = content.get("status")
        finally:
            ws.close()
        return seen


def snapshot(folder: Path) -> dict:
    return {str(p): (p.lstat().st_uid, p.lstat().st_gid, stat.S_IMODE(p.lstat().st_mode))
            for p in [folder, *folder.rglob("*")]}


def root_owned(home: Path) -> list[str]:
    return [str(p) for p in [home, *home.rglob("*")] if p.lstat().st_uid == 0]


SWAPPER = r"""
import glob, os, sys, time
home, stop, targets = os.path.expanduser("~"), sys.argv[1], sys.argv[2:]
swaps, end = 0, time.monotonic() + 120
while not os.path.exists(stop) and time.monotonic() < end:
    # The folders the copy is writing: its parts, in the private building folder or in place.
    places = glob.glob(home + "/.ismb_lab-*") + [home + "/ismb_lab"]
    for place in [p + "/" + part for p in places for part in ("notebooks", "images", "manifests")]:
        target = targets[swaps % len(targets)]
        try:
            if os.path.isdir(place) and not os.path.islink(place):
                os.rename(place, place + ".moved")
            os.symlink(target, place)
            swaps += 1
            time.sleep(0.001)
            os.unlink(place)
        except OSError:
            pass
print(swaps)
"""


@pytest.fixture
def class_hub(request, proxy_folder, accounts, deployment, tmp_path):
    """deploy/jupyterhub_config.py (the deployment's copy of the repository) run by the venv's
    jupyterhub as root, with three students, one outsider and the teacher (conftest.deployment);
    yields a namespace of what the test needs. Stops the hub by the PID file the docs use, the
    students' processes, and removes the cgroups and the state folder. An indirect parameter
    changes documented variables (e.g. ``{"MEM_LIMIT": "2G"}``)."""
    settings = {"MEM_LIMIT": MEM_LIMIT, "CULL_TIMEOUT": str(CULL_TIMEOUT),
                "KERNEL_CULL_TIMEOUT": str(KERNEL_CULL_TIMEOUT), **getattr(request, "param", {})}
    try:
        import requests  # noqa: F401
        import websocket  # noqa: F401
    except ImportError as error:
        _unavailable(f"{error.name} is missing (pip install -e '.[test]')")
    students = [accounts.add(role) for role in ("ann", "bob", "cat")]
    outsider, teacher = accounts.add("out", in_group=False), deployment.teacher
    shared, course, state = deployment.shared, deployment.course, tmp_path / "state"
    port = free_port()
    env = venv_env(deployment.venv, PATH=f"{proxy_folder}:{deployment.venv / 'bin'}:/usr/bin:/bin",
                   ISMB_HUB_GROUP=accounts.group, ISMB_HUB_ADMINS=teacher.name,
                   ISMB_HUB_IP="127.0.0.1", ISMB_HUB_PORT=str(port), ISMB_HUB_API_PORT=str(free_port()),
                   ISMB_HUB_HUB_PORT=str(free_port()), ISMB_HUB_VENV=str(deployment.venv),
                   ISMB_HUB_COURSE=str(course), ISMB_HUB_STATE=str(state), **deployment.env,
                   **{f"ISMB_HUB_{name}": value for name, value in settings.items()})
    log = tmp_path / "hub.log"
    with open(log, "w") as out:      # deploy/README.md: nohup ... >> LOG 2>&1 &
        hub = subprocess.Popen([str(deployment.venv / "bin" / "jupyterhub"), "-f",
                                str(deployment.repo / "deploy" / "jupyterhub_config.py")],
                               cwd=tmp_path, env=env, stdout=out, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}"
    try:
        import requests

        def healthy():
            if hub.poll() is not None:
                raise AssertionError(f"the hub exited with {hub.returncode}:\n{log.read_text()[-3000:]}")
            try:
                return requests.get(f"{url}/hub/health", timeout=2).status_code == 200
            except requests.RequestException:
                return False
        wait_for(healthy, 90, "the hub's health check")
        yield dict(url=url, students=students, outsider=outsider, teacher=teacher, course=course,
                   state=state, log=log, hub=hub, shared=shared, deployment=deployment)
    finally:
        if hub.poll() is None:       # as the docs stop it: SIGTERM to the PID in the state folder
            pid_file = state / "jupyterhub.pid"
            pid = int(pid_file.read_text()) if pid_file.exists() else hub.pid
            assert pid == hub.pid, (pid, hub.pid)
            os.kill(pid, signal.SIGTERM)   # the hub stops the proxy and the servers it started
            try:
                hub.wait(60)
            except subprocess.TimeoutExpired:
                hub.kill()
                hub.wait(10)
        ARTIFACTS.mkdir(exist_ok=True)
        shutil.copy(log, ARTIFACTS / f"hub_real_accounts_{request.node.name[:40]}.log")
        for account in accounts.made:
            accounts.stop_processes(account)
            busy = hub_start.remove_cgroups(hub_start.cgroup_dirs(account.name))
            assert not busy, f"cgroups left behind: {busy}"
        hub_start.remove_cgroups({d.parent for d in hub_start.cgroup_dirs("any")})   # if no other hub uses it


def test_real_accounts_log_in_to_private_copies_with_culling_and_a_memory_limit(class_hub, accounts):
    figures = {}
    url, (ann, bob, cat) = class_hub["url"], class_hub["students"]
    limit = hub_start.parse_size(MEM_LIMIT)

    # A process of cat's keeps swapping the folders the copy writes for symbolic links to a
    # root-only folder and an /etc-like one while cat's server starts (a link in place of
    # ~/ismb_lab itself: test_hub_start.py).
    shared = class_hub["shared"]
    secret, etc = Path(tempfile.mkdtemp(prefix="ismb-secret-")), Path(tempfile.mkdtemp(prefix="ismb-etc-"))
    try:
        (secret / "key").write_text("root only\n")
        (secret / "key").chmod(0o600)
        etc.chmod(0o755)
        (etc / "passwd").write_text("root:x:0:0::/root:/bin/sh\n")
        (etc / "passwd").chmod(0o644)
        before = {**snapshot(secret), **snapshot(etc)}
        stop = shared / "stop-swapping"
        swapper = accounts.popen_as(cat, f"/usr/bin/python3 -c {shlex_quote(SWAPPER)} {stop} {secret} {etc}",
                                    stdout=subprocess.PIPE, text=True)
        time.sleep(1)

        # Logins through the form: students in, the outsider refused, the teacher (admin) in.
        sessions = {s.name: Student(url, s) for s in (cat, ann, bob)}
        start = time.monotonic()
        for name, student in sessions.items():      # three logins, three servers starting at once
            assert student.log_in() == 302, f"{name}'s login was refused"
            student.spawn()
        for name, student in sessions.items():
            student.open_lab()
            figures[f"login_to_lab_s_{name[-3:]}"] = round(time.monotonic() - start, 1)
        stop.touch()
        swaps = int(swapper.communicate(timeout=30)[0].strip() or 0)
        figures["symlink_swaps_during_start"] = swaps
        outsider = Student(url, class_hub["outsider"])
        assert outsider.log_in() == 403 or "not allowed" in outsider.http.get(f"{url}/hub/").text.lower()
        assert Student(url, class_hub["teacher"]).log_in() == 302

        # The swap gained nothing: both folders as they were, the secret still unreadable to cat.
        assert swaps > 0
        assert {**snapshot(secret), **snapshot(etc)} == before
        assert (etc / "passwd").read_text() == "root:x:0:0::/root:/bin/sh\n"
        assert accounts.run_as(cat, f"cat {secret}/key").returncode != 0
    finally:
        shutil.rmtree(secret, ignore_errors=True)
        shutil.rmtree(etc, ignore_errors=True)

    figures["cat_start_said"] = [line for line in class_hub["log"].read_text().splitlines()
                                 if line.startswith("ismb_lab:") and f"/{cat.name}/" in line]

    # Each has their own private copy, made by their own process; nothing in a home is root's.
    for student in (ann, bob):
        listing = sessions[student.name].api("GET", "contents/ismb_lab/notebooks")
        assert listing.status_code == 200, listing.text[:300]
        files = {item["name"] for item in listing.json()["content"]}
        assert "04_label_targets.ipynb" in files and "solutions" not in files
        copy = student.home / "ismb_lab"
        assert copy.lstat().st_uid == student.uid and stat.S_IMODE(copy.lstat().st_mode) == 0o700
        assert all(p.lstat().st_uid == student.uid for p in copy.rglob("*"))
    for student in (ann, bob, cat):
        assert root_owned(student.home) == []

    # The course's nbgrader config reaches the students' servers, with the teacher's tools
    # hidden from their JupyterLab and the Assignments tab kept.
    page = sessions[ann.name].http.get(f"{url}/user/{ann.name}/lab", timeout=30).text
    found = re.search(r'<script id="jupyter-config-data" type="application/json">(.*?)</script>', page, re.S)
    disabled = json.loads(found.group(1))["disabledExtensions"]
    assert set(hub_start.TEACHER_TOOLS) <= set(disabled) and "@jupyter/nbgrader:assignment-list" not in disabled
    for reader, owner in ((bob, ann), (ann, bob), (cat, ann)):
        for command in (f"cat {owner.home}/ismb_lab/notebooks/04_label_targets.ipynb",
                        f"ls {owner.home}/ismb_lab"):
            assert accounts.run_as(reader, command).returncode != 0, f"{reader.name}: {command}"

    # The hub's state: a 700 folder of 600 files.
    state = class_hub["state"]
    assert stat.S_IMODE(state.stat().st_mode) == 0o700
    modes = {p.name: stat.S_IMODE(p.stat().st_mode) for p in state.iterdir() if p.is_file()}
    assert "jupyterhub.sqlite" in modes and "jupyterhub_cookie_secret" in modes, modes
    assert all(mode == 0o600 for mode in modes.values()), modes

    # The memory limit: one allocation past it is a MemoryError in the student's cell; the
    # student's cgroup never went past it; bob's kernel still answers.
    in_cgroups = cgroups_writable()
    ann_kernel, bob_kernel = sessions[ann.name].start_kernel(), sessions[bob.name].start_kernel()
    assert sessions[bob.name].execute(bob_kernel, "print(6 * 7)")["stdout"].strip() == "42"
    started = time.monotonic()
    big = sessions[ann.name].execute(ann_kernel, f"import numpy as np\nx = np.ones({limit // 8 + 2**20})")
    figures["one_allocation_past_limit"] = {k: big[k] for k in ("status", "ename", "evalue")}
    assert big["status"] == "error" and big["ename"] == "MemoryError", big
    # Two processes of ann's, each under RLIMIT_DATA, together past the limit: the cgroup
    # kills one (the kernel dies and restarts, or its child is killed), nobody else is touched.
    if in_cgroups:
        both = sessions[ann.name].execute(ann_kernel, (
            "import subprocess, sys\nheld = np.ones(%d)\n" % (limit // 2 // 8)
            + "child = subprocess.run([sys.executable, '-c', 'import numpy as np; "
              "x = [np.ones(2**22) for _ in range(400)]'], capture_output=True, text=True)\n"
            + "print('child exit', child.returncode, child.stderr.strip().splitlines()[-1:])"), timeout=120)
        figures["two_processes_past_limit"] = {k: both[k] for k in ("status", "ename", "stdout")}
        assert both["status"] in ("restarting", "dead", "closed") or "child exit -9" in both["stdout"], both
        if both["status"] != "ok":
            ann_kernel = sessions[ann.name].start_kernel()
    grow = sessions[ann.name].execute(
        ann_kernel, "import numpy as np\nchunks = []\nwhile True:\n    chunks.append(np.ones(2**22))", timeout=120)
    figures["growing_past_limit"] = {k: grow[k] for k in ("status", "ename", "evalue")}
    figures["memory_checks_s"] = round(time.monotonic() - started, 1)
    assert grow["status"] in ("restarting", "dead", "closed") or grow["ename"] == "MemoryError", grow
    if in_cgroups:
        memory = hub_start.cgroup_dirs(ann.name)[0]
        assert int((memory / "memory.limit_in_bytes").read_text()) == limit
        peak = int((memory / "memory.max_usage_in_bytes").read_text())
        figures["ann_cgroup_peak_mb"] = round(peak / 2**20)
        assert peak <= limit
        server_pids = {int(p) for p in (memory / "cgroup.procs").read_text().split()}
        assert server_pids and set(accounts.processes(ann)) >= server_pids
        oom = (memory / "memory.oom_control").read_text()
        figures["ann_oom_kills"] = int(re.search(r"oom_kill (\d+)", oom).group(1))
        assert figures["ann_oom_kills"] >= 1
    assert sessions[bob.name].execute(bob_kernel, "print(6 * 7)")["stdout"].strip() == "42"
    figures["cgroups"] = in_cgroups

    # Culling: bob's kernel, with no tab open, is shut down after its idle timeout; cat's
    # idle server is stopped by jupyterhub-idle-culler, and its cgroups go with it.
    started = time.monotonic()
    wait_for(lambda: bob_kernel not in {k["id"] for k in sessions[bob.name].api("GET", "kernels").json()},
             KERNEL_CULL_TIMEOUT + 30, "the idle kernel's culling")
    figures["kernel_culled_after_s"] = round(time.monotonic() - started, 1)

    def cat_culled():
        sessions[ann.name].api("GET", "status")      # ann and bob stay active meanwhile
        sessions[bob.name].api("GET", "status")
        return not any("jupyterhub.singleuser" in command_line(pid) for pid in accounts.processes(cat))
    wait_for(cat_culled, CULL_TIMEOUT * 3, "the idle server's culling", step=2)
    figures["server_culled_within_s_of_start"] = round(time.monotonic() - started, 1)
    assert "Culling server" in class_hub["log"].read_text() or "culling" in class_hub["log"].read_text().lower()
    if in_cgroups:     # the hub removes them once the server's stop has returned
        wait_for(lambda: not any(d.exists() for d in hub_start.cgroup_dirs(cat.name)), 30,
                 "the culled server's cgroups removed")
    assert sessions[ann.name].api("GET", "status").status_code == 200

    ARTIFACTS.mkdir(exist_ok=True)
    (ARTIFACTS / "hub_real_accounts.json").write_text(json.dumps(figures, indent=2))
    print(json.dumps(figures, indent=2))


def command_line(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def shlex_quote(text: str) -> str:
    import shlex

    return shlex.quote(text)


# --- one student in Chromium, through the real login form --------------------------------

def _browser_helpers():
    """tests/browser/conftest.py's page actions, loaded by path (the two folders' conftests do
    not see each other); Chromium itself is the session's one, from tests/conftest.py."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("ismb_browser_helpers", ROOT / "tests" / "browser" / "conftest.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_browser = _browser_helpers()
ui = _browser.ui
LAB_SETTINGS = {"@jupyterlab/apputils-extension/notification.jupyterlab-settings":
                {"fetchNews": "false", "checkForUpdates": False},
                "@jupyterlab/notebook-extension/tracker.jupyterlab-settings": {"windowingMode": "none"}}


def own_settings(accounts, student) -> None:
    """What this student sets in their own ~/.jupyter: the app exposed to the page's scripts
    (the page actions use it), every notebook cell rendered, no news pop-up."""
    files = {".jupyter/jupyter_server_config.json": {"LabApp": {"expose_app_in_browser": True}},
             **{f".jupyter/lab/user-settings/{k}": v for k, v in LAB_SETTINGS.items()}}
    for rel, value in files.items():
        done = accounts.run_as(student, f"mkdir -p {shlex_quote(str(Path(rel).parent))} && "
                                        f"printf %s {shlex_quote(json.dumps(value))} > {shlex_quote(rel)}")
        assert done.returncode == 0, done.stderr


@pytest.mark.browser
@pytest.mark.parametrize("class_hub", [{"MEM_LIMIT": "2G", "CULL_TIMEOUT": "600",
                                        "KERNEL_CULL_TIMEOUT": "600"}], indirect=True)
def test_a_student_logs_in_in_chromium_and_labels_a_pair_in_notebook_04(class_hub, accounts, browser, ui):
    from playwright.sync_api import expect

    url, ann = class_hub["url"], class_hub["students"][0]
    own_settings(accounts, ann)
    context = browser.new_context(viewport={"width": 1400, "height": 1000})
    context.set_default_timeout(120_000)
    page = context.new_page()
    try:
        page.goto(f"{url}/hub/login")
        page.fill("#username_input", ann.name)
        page.fill("#password_input", ann.password)
        page.click("#login_submit")
        page.wait_for_url(re.compile(rf".*/user/{ann.name}/lab.*"), timeout=120_000)
        notebook = "ismb_lab/notebooks/04_label_targets.ipynb"
        ui.run_all(page, f"{url}/user/{ann.name}/lab/tree/{notebook}", notebook, timeout=180_000)
        root = page.locator(".ismb-labeler")
        ui.label_one_pair(page, root, class_hub["course"])
        root.locator("button.ismb-save").click()
        expect(root.locator(".ismb-dirty")).to_have_text("saved", timeout=30_000)
    except Exception:
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=ARTIFACTS / "hub_real_account_failed.png")
        raise
    finally:
        context.close()
    saved = [p for p in (ann.home / "ismb_lab").rglob(f"targets-{ann.name}-*.json")]
    assert len(saved) == 1, saved
    from ismb_lab.labels.targets import load_targets

    assert len(load_targets(saved[0])) == 1
    assert saved[0].stat().st_uid == ann.uid and stat.S_IMODE(saved[0].stat().st_mode) == 0o600
    assert root_owned(ann.home) == []


# --- the class from the docs: terminals, grading, no solution in reach, compiled kernels -----

#: Run as a student with Debian's python3: every file under the given folders that this
#: account can read, searched for solutions and hidden tests.  A marker counts where a line
#: (or a notebook's source line, also as an escaped "\\n" inside JSON) starts with it, not
#: where code or prose mentions it.  Files that pip installed for other distributions are
#: counted apart (nbgrader ships example notebooks with markers).
SEARCH = r"""
import json, os, sys, time
MARKERS = (b"### BEGIN SOLUTION", b"### BEGIN HIDDEN TESTS")
started, roots = time.monotonic(), sys.argv[1:]
seen = {"files": 0, "mb": 0.0, "unreadable": 0, "unlisted_folders": 0, "hits": [], "third_party_hits": 0,
        "solution_paths": []}
third = set()
for root in roots:
    for top, dirs, names in os.walk(root):
        name = os.path.basename(top)
        if name.endswith(".dist-info") and "RECORD" in names and not name.lower().startswith("ismb_lab"):
            try:
                for line in open(os.path.join(top, "RECORD"), encoding="utf-8"):
                    if line.strip():
                        third.add(os.path.normpath(os.path.join(os.path.dirname(top), line.rsplit(",", 2)[0])))
            except OSError:
                pass

def marked(data):
    for marker in MARKERS:
        at = data.find(marker)
        while at >= 0:
            newline, escaped = data.rfind(b"\n", 0, at), data.rfind(b"\\n", 0, at)
            start = max(newline + 1, escaped + 2 if escaped >= 0 else 0)
            if data[start:at].strip().lstrip(b'"') == b"":
                return marker.decode()
            at = data.find(marker, at + 1)
    return None

def walk_error(error):
    seen["unlisted_folders"] += 1

for root in roots:
    if os.path.isfile(root):
        entries = [(os.path.dirname(root), [], [os.path.basename(root)])]
    else:
        entries = os.walk(root, onerror=walk_error)
    for top, dirs, names in entries:
        for name in dirs + names:
            path = os.path.join(top, name)
            if "notebooks/solutions" in path and os.access(path, os.R_OK):
                seen["solution_paths"].append(path)
        for name in names:
            path = os.path.join(top, name)
            if os.path.islink(path) or not os.path.isfile(path):
                continue
            try:
                with open(path, "rb") as handle:
                    data = handle.read(64 << 20)
            except OSError:
                seen["unreadable"] += 1
                continue
            seen["files"] += 1
            seen["mb"] += len(data) / 2**20
            found = marked(data) if b"### BEGIN" in data else None
            if found and os.path.normpath(path) in third:
                seen["third_party_hits"] += 1
            elif found:
                seen["hits"].append([path, found])
seen["mb"] = round(seen["mb"], 1)
seen["seconds"] = round(time.monotonic() - started, 1)
print(json.dumps(seen))
"""

WARM_UP = """
import json, time
t0 = time.process_time()
from ismb_lab._core import numba_share
from ismb_lab.matching.pipeline import warm_up
from ismb_lab.teaching.kernels import cached_kernels
wall = warm_up()
kernels = cached_kernels().values()
print(json.dumps({"cpu_s": round(time.process_time() - t0, 2), "warm_up_s": round(wall, 2),
                  "hits": sum(sum(k.stats.cache_hits.values()) for k in kernels),
                  "misses": sum(sum(k.stats.cache_misses.values()) for k in kernels),
                  "caches": [numba_share.own_cache_folder(f) for f in numba_share.KERNEL_SOURCES]}))
"""


def search_as(accounts, account, roots) -> dict:
    done = subprocess.run(["su", "-s", "/bin/sh", account.name, "-c",
                           "cd && /usr/bin/python3 - " + " ".join(shlex_quote(str(r)) for r in roots)],
                          input=SEARCH, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def config_data(student, path: str) -> dict:
    page = student.http.get(f"{student.url}/user/{student.name}/{path}", timeout=60).text
    found = re.search(r'<script id="jupyter-config-data" type="application/json">(.*?)</script>', page, re.S)
    return json.loads(found.group(1))


@pytest.mark.parametrize("class_hub", [{"MEM_LIMIT": "2G", "CULL_TIMEOUT": "600",
                                        "KERNEL_CULL_TIMEOUT": "600"}], indirect=True)
def test_the_class_from_the_docs_terminals_grading_no_solution_in_reach_and_compiled_kernels(class_hub, accounts):
    figures, url = {}, class_hub["url"]
    ann, teacher, deployment = class_hub["students"][0], class_hub["teacher"], class_hub["deployment"]
    # deploy/course/README.md, "Each term, as the teacher", in the teacher's login shell
    setup = accounts.login(teacher, "mkdir -p -m 700 ~/course && cd ~/course && ismb-lab course source . --repo "
                                    f"{shlex_quote(str(deployment.repo))} && nbgrader generate_assignment labels "
                                    "&& nbgrader release_assignment labels")
    assert setup.returncode == 0, setup.stdout + setup.stderr
    sessions = {a.name: Student(url, a) for a in (ann, teacher)}
    for session in sessions.values():
        assert session.log_in() == 302
        session.spawn()
    for session in sessions.values():
        session.open_lab()
    student, grader = sessions[ann.name], sessions[teacher.name]

    # A student's JupyterLab terminal (a login shell: /etc/profile resets PATH) finds the tools
    # and the course: deploy/course/README.md's terminal route fetches the assignment.
    started = time.monotonic()
    shown = student.terminal("nbgrader --version; ismb-lab --version; nbgrader fetch_assignment labels")
    figures["terminal_s"] = round(time.monotonic() - started, 1)
    assert "command not found" not in shown and "No nbgrader_config.py" not in shown, shown
    assert re.search(r"nbgrader version \d", shown, re.I) and re.search(r"ismb-lab \d", shown), shown
    assert (ann.home / "labels" / "04_label_targets.ipynb").is_file(), shown

    # The Formgrader: the teacher's server lists the course's assignments; a student's has none.
    listed = grader.http.get(f"{url}/user/{teacher.name}/formgrader/api/assignments", timeout=60)
    assert listed.status_code == 200, listed.text[:500]
    figures["formgrader_assignments"] = [a["name"] for a in listed.json()]
    assert figures["formgrader_assignments"] == ["labels"]
    assert student.http.get(f"{url}/user/{ann.name}/formgrader/api/assignments", timeout=60).status_code == 404
    assert "@jupyter/nbgrader:formgrader" in config_data(student, "lab")["disabledExtensions"]
    assert "@jupyter/nbgrader:formgrader" not in config_data(grader, "lab")["disabledExtensions"]
    news = student.http.get(f"{url}/user/{ann.name}/lab/api/settings/@jupyterlab/apputils-extension:notification",
                            timeout=60).json()["schema"]["properties"]["fetchNews"]["default"]
    assert news == "false"            # nobody is asked about Jupyter news

    # A student's first warm-up loads the teacher's kernels, copied into their own cache.
    kernel = student.start_kernel()
    ran = student.execute(kernel, WARM_UP, timeout=300)
    assert ran["status"] == "ok", ran
    warm = json.loads(ran["stdout"].strip().splitlines()[-1])
    figures["first_warm_up"] = warm
    assert warm["misses"] == 0 and warm["hits"] > 0, warm
    own = [Path(folder) for folder in warm["caches"]]
    assert all(ann.home in folder.parents for folder in own)
    shared = {p.name: p.stat().st_mtime_ns for p in (deployment.course / "numba").rglob("*.nb*")}
    copies = [p for folder in own for p in folder.iterdir() if shared.get(p.name) == p.stat().st_mtime_ns]
    assert len(copies) == len(shared) and all(p.stat().st_uid == ann.uid and stat.S_IMODE(p.stat().st_mode) == 0o600
                                              for p in copies)

    # No solution or hidden test in any file the student can read under the documented paths;
    # the teacher, who can read the repository, finds them (so the search can find them).
    homes = sorted({str(a.home) for a in accounts.made})
    roots = [deployment.shared, deployment.venv.parent, *homes, "/etc/profile.d/ismb-lab.sh", class_hub["state"]]
    found = search_as(accounts, ann, roots)
    figures["student_search"] = {k: v for k, v in found.items() if k != "hits"}
    assert found["hits"] == [] and found["solution_paths"] == [], found
    assert found["files"] > 1000
    control = search_as(accounts, teacher, [deployment.repo, teacher.home])
    figures["teacher_search_hits"] = len(control["hits"])
    assert any("/notebooks/" in path for path, _ in control["hits"]) and control["solution_paths"]

    ARTIFACTS.mkdir(exist_ok=True)
    (ARTIFACTS / "hub_docs_walk.json").write_text(json.dumps(figures, indent=2))
    print(json.dumps(figures, indent=2))
