"""A JupyterHub for measuring a class: the deployment's config, students driven through their servers.

:func:`running_hub` starts ``deploy/jupyterhub_config.py``, with its ``ISMB_HUB_*``
settings (ports, state folder, venv, course, users) pointed at the run, loaded with
``load_subconfig`` by a small config of its own that changes only what a benchmark must:

* where it listens: 127.0.0.1, free ports for the hub, ``hub_port`` and the proxy's API;
* where its state goes (database, cookie secret, proxy PID): the run's folder;
* the dummy login and the simple local-process spawner (no OS accounts): every server runs
  as the user who starts it, with a home folder in the run's folder;
* the server command: this environment's ``jupyterhub.singleuser``, with the deployment's
  arguments plus ``--allow-root`` as root, the home as root folder, and no
  ``pre_spawn_hook``; :func:`stage_course` gives each home its copy of the course instead;
* Jupyter's runtime folder (the kernels' Unix sockets) in the run's folder, with a short path
  as ``hub_start serve`` gives each server;
* a numba cache in each home, as students get who cannot write into the venv, and the
  teacher's compiled kernels (``ISMB_NUMBA_SHARED``) only when a run passes a folder of them
  (``hub_start stage`` compiles them into ``COURSE/numba``; here the course is the repository);
* a service of its own whose token asks the REST API for users and servers, and reaches
  each server through the proxy.

:class:`Client` asks for servers and opens kernels the way JupyterLab does (a session, then
the kernel's websocket); :class:`Kernel` executes cells there.  Used by ``bench_class.py``.
"""

from __future__ import annotations

import asyncio
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import time
import uuid
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEPLOY = ROOT / "deploy" / "jupyterhub_config.py"
NOTEBOOK = "ismb_lab/notebooks/04_label_targets.ipynb"
NOTEBOOK_00 = "ismb_lab/notebooks/00_start_here.ipynb"
COURSE = ("notebooks", "images", "manifests")
LEFT_OUT = ("solutions", ".ipynb_checkpoints", "targets-*.json", "my_targets*.json", "params-*.json",
            ".targets-*.lock", "photos-*")


# --- the hub -----------------------------------------------------------------------------
def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def proxy_command() -> str:
    """configurable-http-proxy: the repository's ``.node/`` (as .ci/run installs it), else PATH."""
    local = ROOT / ".node" / "node_modules" / ".bin" / "configurable-http-proxy"
    found = str(local) if local.exists() else shutil.which("configurable-http-proxy")
    if found is None:
        sys.exit("configurable-http-proxy is missing (npm install --prefix .node "
                 "configurable-http-proxy, or put it on PATH)")
    return found


@dataclass(frozen=True)
class Hub:
    """A running hub: its process, its URL, the benchmark service's token and the homes."""

    proc: subprocess.Popen
    url: str
    token: str
    homes: Path
    log: Path


def hub_config(work: Path, token: str, ports: tuple, proxy: str, shared_kernels: Path | None = None) -> str:
    """The benchmark's config: the deployment's, with only the overrides the docstring lists."""
    port, hub_port, api_port = ports
    args = ["--allow-root"] if os.geteuid() == 0 else []
    return f"""
c = get_config()  # noqa
load_subconfig({str(DEPLOY)!r})
c.JupyterHub.ip = "127.0.0.1"
c.JupyterHub.port = {port}
c.JupyterHub.bind_url = "http://127.0.0.1:{port}"
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = {hub_port}
c.ConfigurableHTTPProxy.api_url = "http://127.0.0.1:{api_port}"
c.ConfigurableHTTPProxy.command = [{proxy!r}]
c.ConfigurableHTTPProxy.pid_file = {str(work / "proxy.pid")!r}
c.JupyterHub.db_url = "sqlite:///{work / 'hub.sqlite'}"
c.JupyterHub.cookie_secret_file = {str(work / "cookie_secret")!r}
c.JupyterHub.authenticator_class = "dummy"
c.Authenticator.allow_all = True
c.JupyterHub.spawner_class = "simple"
c.SimpleLocalProcessSpawner.home_dir_template = {str(work / "homes" / "{username}")!r}
c.Spawner.cmd = [{sys.executable!r}, "-m", "jupyterhub.singleuser"]
c.Spawner.args.extend({args!r})
c.Spawner.notebook_dir = "~"
c.Spawner.pre_spawn_hook = None
c.Spawner.environment.update({{"NUMBA_CACHE_DIR": lambda spawner: spawner.home_dir + "/.cache/numba",
                              "ISMB_NUMBA_SHARED": {str(shared_kernels or "")!r},
                              # short: the kernels' Unix sockets (hub_start serve makes one in /tmp)
                              "JUPYTER_RUNTIME_DIR": lambda spawner: {str(work / "rt")!r} + "/" + spawner.user.name}})
c.JupyterHub.services.append({{"name": "bench-class", "api_token": {token!r}}})
c.JupyterHub.load_roles.append({{"name": "bench-class", "services": ["bench-class"],
    "scopes": ["admin:users", "admin:servers", "access:servers"]}})
"""


def wait_healthy(proc: subprocess.Popen, url: str, log: Path, timeout: float = 120.0) -> None:
    import urllib.error
    import urllib.request

    deadline = time.monotonic() + timeout
    while True:
        if proc.poll() is not None:
            raise RuntimeError(f"the hub exited with {proc.returncode}:\n{log.read_text()[-3000:]}")
        try:
            with urllib.request.urlopen(f"{url}/hub/health", timeout=2):
                return
        except (urllib.error.URLError, OSError):
            if time.monotonic() > deadline:
                raise RuntimeError(f"the hub did not answer:\n{log.read_text()[-3000:]}") from None
            time.sleep(0.5)


def stop(proc: subprocess.Popen) -> None:
    """SIGTERM the hub (it stops the proxy and the servers it started), then end any of its
    descendants still running, by PID."""
    import psutil

    try:
        family = psutil.Process(proc.pid).children(recursive=True)
    except psutil.NoSuchProcess:
        family = []
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(90)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)
    _, alive = psutil.wait_procs(family, timeout=15)
    for p in alive:
        try:
            p.kill()
        except psutil.NoSuchProcess:
            pass


def deploy_settings(work: Path, ports: tuple, students: list) -> dict:
    """The deployment's own settings (deploy/README.md's ``ISMB_HUB_*``) for this run, so that
    loading its config checks and creates nothing outside `work`."""
    port, hub_port, api_port = ports
    return {"ISMB_HUB_IP": "127.0.0.1", "ISMB_HUB_PORT": str(port), "ISMB_HUB_HUB_PORT": str(hub_port),
            "ISMB_HUB_API_PORT": str(api_port), "ISMB_HUB_STATE": str(work / "state"),
            "ISMB_HUB_VENV": sys.prefix, "ISMB_HUB_COURSE": str(ROOT), "ISMB_HUB_USERS": " ".join(students)}


@contextmanager
def running_hub(work: Path, students: list, shared_kernels: Path | None = None):
    """Start the hub in `work` (its cwd, state and homes) and stop it, whatever happens; with
    `shared_kernels`, the servers get that folder of compiled kernels (``ISMB_NUMBA_SHARED``)."""
    token, ports = secrets.token_hex(32), (free_port(), free_port(), free_port())
    config = work / "bench_config.py"
    config.write_text(hub_config(work, token, ports, proxy_command(), shared_kernels))
    log = work / "hub.log"
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, PYTHONPATH=path, JUPYTER_RUNTIME_DIR=str(work / "runtime"), MPLBACKEND="Agg",
               **deploy_settings(work, ports, students))
    with open(log, "w") as out:
        proc = subprocess.Popen([sys.executable, "-m", "jupyterhub", "-f", str(config)], cwd=work,
                                env=env, stdout=out, stderr=subprocess.STDOUT)
    try:
        url = f"http://127.0.0.1:{ports[0]}"
        wait_healthy(proc, url, log)
        yield Hub(proc, url, token, work / "homes", log)
    finally:
        stop(proc)


def stage_course(home: Path) -> None:
    """A student's copy of the course, as the deployment gives it, before their server starts."""
    for name in COURSE:
        shutil.copytree(ROOT / name, home / "ismb_lab" / name, ignore=shutil.ignore_patterns(*LEFT_OUT))


# --- the REST API and the kernels ----------------------------------------------------------
class Client:
    """The benchmark service's HTTP calls to the hub and, through its proxy, to the servers."""

    def __init__(self, hub: Hub, students: int):
        from tornado.httpclient import AsyncHTTPClient

        AsyncHTTPClient.configure(None, max_clients=students + 10)
        self.http = AsyncHTTPClient()
        self.hub = hub

    async def call(self, method: str, path: str, body=None, **kw):
        from tornado.httpclient import HTTPRequest

        request = HTTPRequest(self.hub.url + path, method=method, follow_redirects=False,
                              headers={"Authorization": f"token {self.hub.token}"},
                              body=None if body is None and method == "GET" else json.dumps(body or {}),
                              request_timeout=kw.pop("timeout", 60), **kw)
        return await self.http.fetch(request, raise_error=False)

    async def start_server(self, name: str, t0: float, timeout: float) -> float:
        """Ask for `name`'s server; seconds from `t0` until its API answers 200."""
        reply = await self.call("POST", f"/hub/api/users/{name}/server")
        if reply.code not in (201, 202):
            raise RuntimeError(f"{name}: the hub answered {reply.code} to the spawn: {reply.body!r}")
        while time.perf_counter() - t0 < timeout:
            if (await self.call("GET", f"/user/{name}/api/status", timeout=10)).code == 200:
                return time.perf_counter() - t0
            await asyncio.sleep(0.25)
        raise RuntimeError(f"{name}: no answer from /user/{name}/api/status after {timeout:.0f} s")

    async def open_kernel(self, name: str, notebook: str = NOTEBOOK) -> "Kernel":
        """A kernel for `notebook` in `name`'s server (a session, as JupyterLab opens one)."""
        from tornado.httpclient import HTTPRequest
        from tornado.websocket import websocket_connect

        body = {"path": notebook, "name": Path(notebook).name, "type": "notebook", "kernel": {"name": "python3"}}
        reply = await self.call("POST", f"/user/{name}/api/sessions", body, timeout=180)
        if reply.code != 201:
            raise RuntimeError(f"{name}: no kernel ({reply.code}): {reply.body[:500]!r}")
        kernel_id = json.loads(reply.body)["kernel"]["id"]
        ws_url = self.hub.url.replace("http", "ws", 1) + f"/user/{name}/api/kernels/{kernel_id}/channels"
        request = HTTPRequest(ws_url, headers={"Authorization": f"token {self.hub.token}"},
                              connect_timeout=180, request_timeout=180)
        conn = await websocket_connect(request, max_message_size=256 * 2**20)
        return Kernel(name, kernel_id, conn)


@dataclass(frozen=True)
class Result:
    """One execution: seconds from request to reply and idle, its printed text, its error."""

    seconds: float
    text: str
    error: str | None


class Kernel:
    """One student's kernel, over the Jupyter server's websocket (JSON messages)."""

    def __init__(self, name: str, kernel_id: str, conn):
        self.name, self.id, self.conn, self.session = name, kernel_id, conn, uuid.uuid4().hex

    def _request(self, code: str) -> dict:
        header = {"msg_id": uuid.uuid4().hex, "msg_type": "execute_request", "username": self.name,
                  "session": self.session, "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                  "version": "5.3"}
        content = {"code": code, "silent": False, "store_history": True, "user_expressions": {},
                   "allow_stdin": False, "stop_on_error": True}
        return {"header": header, "parent_header": {}, "metadata": {}, "content": content,
                "channel": "shell", "buffers": []}

    async def run(self, code: str, timeout: float = 600.0) -> Result:
        """Execute `code`; wait for its reply and for the kernel to be idle again."""
        request = self._request(code)
        msg_id, text, error, replied, idle = request["header"]["msg_id"], [], None, False, False
        t0 = time.perf_counter()
        await self.conn.write_message(json.dumps(request))
        while not (replied and idle):
            raw = await asyncio.wait_for(self.conn.read_message(), timeout)
            if raw is None:
                raise ConnectionError(f"{self.name}: the kernel's websocket closed")
            if isinstance(raw, bytes):     # frames with buffers (the figure's images): not ours
                continue
            msg = json.loads(raw)
            if msg.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            kind, content = msg["header"]["msg_type"], msg["content"]
            if kind == "execute_reply":
                replied = True
                if content.get("status") == "error":
                    error = f"{content.get('ename')}: {content.get('evalue')}"
            elif kind == "stream":
                text.append(content.get("text", ""))
            elif kind == "error":
                error = f"{content.get('ename')}: {content.get('evalue')}"
            elif kind == "status" and content.get("execution_state") == "idle":
                idle = True
        return Result(time.perf_counter() - t0, "".join(text), error)

    async def run_ok(self, code: str) -> Result:
        result = await self.run(code)
        if result.error:
            raise RuntimeError(f"{self.name}: {result.error}\nin the cell:\n{code}")
        return result


def notebook_cells(home: Path, notebook: str = NOTEBOOK) -> list:
    import nbformat

    nb = nbformat.read(home / notebook, as_version=4)
    return [cell.source for cell in nb.cells if cell.cell_type == "code"]


async def run_cells(kernel: Kernel, cells: list, t0: float) -> list:
    """Run `cells` in order; the seconds from `t0` at which each was done."""
    done = []
    for code in cells:
        await kernel.run_ok(code)
        done.append(time.perf_counter() - t0)
    await kernel.run_ok("import json, time")
    return done


async def run_notebook(kernel: Kernel, cells: list) -> float:
    t0 = time.perf_counter()
    await run_cells(kernel, cells, t0)
    return time.perf_counter() - t0


async def open_and_run(client: Client, name: str, cells: list, t0: float, notebook: str = NOTEBOOK) -> tuple:
    """`name` opens `notebook` and runs it; (their kernel, the seconds from `t0` at which each
    cell was done)."""
    kernel = await client.open_kernel(name, notebook)
    return kernel, await run_cells(kernel, cells, t0)


async def shut_down(client: Client, kernel: Kernel) -> None:
    """Close `kernel` as JupyterLab's "Shut Down Kernel" does."""
    kernel.conn.close()
    await client.call("DELETE", f"/user/{kernel.name}/api/kernels/{kernel.id}", allow_nonstandard_methods=True)


# --- processes and memory ----------------------------------------------------------------
def student_processes(hub_pid: int, names) -> tuple:
    """({student: {"server": Process, "kernels": [Process]}}, [the hub's other processes]).

    A process is a student's when its ``JUPYTERHUB_USER`` is one of `names` (the hub's
    services have one too)."""
    import psutil

    students, others = {}, [psutil.Process(hub_pid)]
    for p in psutil.Process(hub_pid).children(recursive=True):
        try:
            name = p.environ().get("JUPYTERHUB_USER")
            kernel = any("ipykernel" in part for part in p.cmdline())
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        if name not in names:
            others.append(p)
        else:
            entry = students.setdefault(name, {"server": None, "kernels": []})
            if kernel:
                entry["kernels"].append(p)
            elif p.ppid() == hub_pid:
                entry["server"] = p
    return students, others


def usage(processes) -> tuple:
    """Summed RSS and USS (MB) of `processes`, and the CPU time (s) they have used so far."""
    rss = uss = cpu = 0.0
    for p in processes:
        info, times = p.memory_full_info(), p.cpu_times()
        rss, uss, cpu = rss + info.rss / 2**20, uss + info.uss / 2**20, cpu + times.user + times.system
    return rss, uss, cpu


def memory_per_student(hub_pid: int, names, with_kernel: bool) -> dict:
    students, _ = student_processes(hub_pid, names)
    out = {}
    for name, entry in students.items():
        procs = [entry["server"]] + (entry["kernels"] if with_kernel else [])
        out[name] = usage([p for p in procs if p is not None])
    return out


def kernel_usage(hub_pid: int, kernel: "Kernel") -> tuple:
    """:func:`usage` of `kernel`'s process, found by its connection file's name."""
    students, _ = student_processes(hub_pid, [kernel.name])
    procs = [p for p in students[kernel.name]["kernels"] if any(kernel.id in a for a in p.cmdline())]
    return usage(procs)


def hub_side_mb(hub_pid: int, names) -> float:
    return usage(student_processes(hub_pid, names)[1])[0]
