"""A class on one JupyterHub: start-up, memory per student, latency, and saves with no label lost.

    python benchmarks/bench_class.py [--students 30] [--repeats 30] [--savers 10] [--burst 5]
    python benchmarks/bench_class.py --smoke        # two students, a few repeats

The hub runs ``deploy/jupyterhub_config.py``, with its ``ISMB_HUB_*`` settings (ports,
state folder, venv, course, users) pointed at this run, loaded with ``load_subconfig`` by a
small config of this script's own that changes only what a benchmark must change:

* where it listens: 127.0.0.1, free ports for the hub, ``hub_port`` and the proxy's API;
* where its state goes (database, cookie secret, proxy PID): a temporary folder;
* **the dummy login and the simple local-process spawner**, not PAM and real accounts:
  thirty OS accounts, and a venv outside ``/root`` that they can run, are too heavy for a
  benchmark.  ``tests/hub/`` tests the real-account hub.  So every server here runs as
  the user who starts the script, with a home folder under the temporary folder;
* the server command (this environment's ``jupyterhub.singleuser``; the deployment's
  arguments plus ``--allow-root`` as root; the home as root folder) and no ``pre_spawn_hook``: each home gets its copy of
  ``notebooks/``, ``images/`` and ``manifests/`` before start-up (timed on its own);
* a numba cache in each home, as students get who cannot write into the venv: every
  kernel compiles the numba kernels on its first run, as in a class's first lesson;
* a service of its own, with a token, that asks the hub's REST API for the servers.

No browser: each student's own single-user server runs their kernel, driven through the
hub's proxy with the Jupyter server's sessions and kernel websocket API, as JupyterLab does.
What a browser draws, and the transfer of the figure's frames to it, is not included.

Measured, in order:

1. **start-up:** all servers asked for at once (``POST /hub/api/users/NAME/server``);
   the time until each answers 200 on ``/user/NAME/api/status``;
2. **memory, idle:** each single-user server's resident memory (RSS) and its own share
   (USS, not shared with other processes), read with psutil, and how far the machine's
   available memory fell;
3. **notebook 04** opened and run by every student at once, cell by cell (Run All), then
   each student's server + kernel memory;
4. **one execution while the others idle:** one student repeats a labeller click with its
   redraw, and a one-line cell, median and 90th percentile (round trip through the proxy,
   and the click's time inside the kernel);
5. **a burst:** ``--burst`` students click at the same moment, each ``--repeats`` times;
6. **saves at once:** ``--savers`` students label pairs of their own and press Save
   (``labeler.save()`` in their kernel) at the same moment, three rounds; each student's
   targets file must hold exactly the pairs that student saved, else the script exits 1;
7. **notebook 05** (its GA cells as committed) opened by one student beside notebook 04:
   that kernel's memory.

Out of CI: only ``--smoke`` runs in ``tests/test_benchmarks.py``.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import os
import secrets
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEPLOY = ROOT / "deploy" / "jupyterhub_config.py"
NOTEBOOK = "ismb_lab/notebooks/04_label_targets.ipynb"
NOTEBOOK_05 = "ismb_lab/notebooks/05_genetic_algorithm.ipynb"
COURSE = ("notebooks", "images", "manifests")
LEFT_OUT = ("solutions", ".ipynb_checkpoints", "targets-*.json", "my_targets*.json", "params-*.json",
            ".targets-*.lock", "photos-*")
#: The click timed in the kernel: select (or release) left feature 1, with the full redraw.
CLICK = ("_t = time.perf_counter(); labeler.click(*labeler.model.left_xy[0], side='left'); "
         "print(time.perf_counter() - _t)")
SMALL = "1 + 1"


# --- figures -----------------------------------------------------------------------------
def p90(values) -> float:
    """The 90th percentile by nearest rank: the smallest value with 90% of them at or below it.

    >>> p90(range(1, 11)), p90(range(1, 31)), p90([5])
    (9, 27, 5)
    """
    v = sorted(values)
    return v[max(0, math.ceil(0.9 * len(v)) - 1)]


def spread(values, unit: float = 1000.0, suffix: str = "ms") -> str:
    """``median X, p90 Y`` of `values` (seconds) in `suffix` units.

    >>> spread([0.010, 0.020, 0.030])
    'median 20.0 ms, p90 30.0 ms (3)'
    """
    v = list(values)
    return f"median {statistics.median(v) * unit:.1f} {suffix}, p90 {p90(v) * unit:.1f} {suffix} ({len(v)})"


def mb(values) -> str:
    """``median X MB (min-max)`` of sizes in MB.

    >>> mb([100.4, 120.0, 110.2])
    'median 110 MB (100-120)'
    """
    v = list(values)
    return f"median {statistics.median(v):.0f} MB ({min(v):.0f}-{max(v):.0f})"


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
        sys.exit("bench_class: configurable-http-proxy is missing (npm install --prefix .node "
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


def hub_config(work: Path, token: str, ports: tuple, proxy: str) -> str:
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
c.Spawner.environment.update({{"NUMBA_CACHE_DIR": lambda spawner: spawner.home_dir + "/.cache/numba"}})
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
def running_hub(work: Path, students: list):
    """Start the hub in `work` (its cwd, state and homes) and stop it, whatever happens."""
    token, ports = secrets.token_hex(32), (free_port(), free_port(), free_port())
    config = work / "bench_config.py"
    config.write_text(hub_config(work, token, ports, proxy_command()))
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


async def run_notebook(kernel: Kernel, cells: list) -> float:
    t0 = time.perf_counter()
    for code in cells:
        await kernel.run_ok(code)
    await kernel.run_ok("import json, time")
    return time.perf_counter() - t0


async def open_and_run(client: Client, name: str, cells: list, t0: float) -> tuple:
    """`name` opens notebook 04 and runs it; (their kernel, seconds from `t0` until done)."""
    kernel = await client.open_kernel(name)
    await run_notebook(kernel, cells)
    return kernel, time.perf_counter() - t0


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


# --- the phases ----------------------------------------------------------------------------
async def start_up(client: Client, names: list, timeout: float) -> list:
    reply = await client.call("POST", "/hub/api/users", {"usernames": names})
    if reply.code not in (201, 409):      # 409: all exist already (the config's allowed users)
        raise RuntimeError(f"the hub answered {reply.code} when asked for the users: {reply.body!r}")
    t0 = time.perf_counter()
    return await asyncio.gather(*(client.start_server(n, t0, timeout) for n in names))


async def repeat(kernel: Kernel, code: str, repeats: int) -> tuple:
    """Round trips and the seconds the cell printed (when it prints one number)."""
    trips, inside = [], []
    for _ in range(repeats):
        result = await kernel.run_ok(code)
        trips.append(result.seconds)
        if result.text.strip():
            inside.append(float(result.text.split()[-1]))
    return trips, inside


FEATURES = "print(json.dumps([labeler.model.left_xy.tolist(), labeler.model.right_xy.tolist()]))"
SAVE = """
_t = time.perf_counter(); _path = labeler.save(); _dt = time.perf_counter() - _t
print(json.dumps({"path": str(_path.resolve()), "seconds": _dt}))
"""


def own_pairs(student: int, round_: int, sizes: tuple) -> list:
    """The three pairs (left i, right k) that `student` adds in `round_`: no two students'
    files hold the same set, and no feature is used twice by one student.

    >>> own_pairs(1, 0, (20, 20)), own_pairs(1, 1, (20, 20))
    ([(0, 1), (1, 2), (2, 3)], [(3, 4), (4, 5), (5, 6)])
    """
    n_left, n_right = sizes
    return [(j % n_left, (j + student) % n_right) for j in range(3 * round_, 3 * round_ + 3)]


def point_pair(p, q) -> tuple:
    """A pair of points as a set member, to 0.001 px.

    >>> point_pair([1.00001, 2], [3, 4.5])
    (1.0, 2.0, 3.0, 4.5)
    """
    return tuple(round(float(v), 3) for v in (*p, *q))


def lost_labels(home: Path, path: Path, expected: set) -> str | None:
    """None when the targets file at `path` holds exactly the `expected` coordinate pairs."""
    from ismb_lab.targets import load_targets

    if home.resolve() not in path.resolve().parents:
        return f"saved outside the student's home: {path}"
    saved = load_targets(path)
    on_disk = {point_pair(p, q) for p, q in zip(saved.left_xy, saved.right_xy)}
    if on_disk != expected or len(saved) != len(expected):
        return (f"{path}: {len(expected - on_disk)} of {len(expected)} pairs lost, "
                f"{len(on_disk - expected)} pairs not theirs")
    return None


async def saves_at_once(kernels: list, homes: Path, rounds: int = 3) -> tuple:
    """Each round every saver adds three pairs, then all press Save together; each file is
    then checked against the pairs this script chose.  Returns (save times, problems)."""
    left, right = json.loads((await kernels[0].run_ok(FEATURES)).text)
    expected = {k.name: set() for k in kernels}
    times, problems = [], []
    for r in range(rounds):
        for s, k in enumerate(kernels):
            pairs = own_pairs(s, r, (len(left), len(right)))
            await k.run_ok(f"labeler.model.select(None)\nfor _i, _k in {pairs!r}:\n    labeler.add_pair(_i, _k)")
            expected[k.name] |= {point_pair(left[i], right[j]) for i, j in pairs}
        results = await asyncio.gather(*(k.run_ok(SAVE) for k in kernels))
        for k, result in zip(kernels, results):
            report = json.loads(result.text.strip().splitlines()[-1])
            times.append(report["seconds"])
            problem = lost_labels(homes / k.name, Path(report["path"]), expected[k.name])
            if problem:
                problems.append(f"round {r + 1}, {k.name}: {problem}")
    return times, problems


# --- the run -----------------------------------------------------------------------------
def machine() -> str:
    import psutil

    load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    return (f"{os.cpu_count()} cores, {psutil.virtual_memory().total / 2**20:.0f} MB, "
            f"{psutil.virtual_memory().available / 2**20:.0f} MB available; load average {load}")


async def class_starts(hub: Hub, client: Client, names: list, timeout: float) -> None:
    import psutil

    available = psutil.virtual_memory().available
    ready = await start_up(client, names, timeout)
    print(f"start-up: {len(names)} servers asked for at once, all answered 200 in {max(ready):.1f} s "
          f"(first {min(ready):.1f} s, median {statistics.median(ready):.1f} s)")
    idle = memory_per_student(hub.proc.pid, names, with_kernel=False)
    fell = (available - psutil.virtual_memory().available) / 2**20
    print(f"memory, idle single-user server: RSS {mb(v[0] for v in idle.values())}, "
          f"USS {mb(v[1] for v in idle.values())}; available memory fell {fell:.0f} MB during start-up")
    print(f"CPU time of a server's start: {spread((v[2] for v in idle.values()), 1, 's')}")


async def class_runs_04(hub: Hub, client: Client, names: list) -> list:
    """Every student opens notebook 04 and runs it, all at once; returns their kernels."""
    import psutil

    available, cells, t0 = psutil.virtual_memory().available, notebook_cells(hub.homes / names[0]), time.perf_counter()
    kernels, took = zip(*await asyncio.gather(*(open_and_run(client, n, cells, t0) for n in names)))
    print(f"notebook 04 opened and run by all {len(names)} at once: all done {max(took):.1f} s after asking "
          f"(first {min(took):.1f} s, median {statistics.median(took):.1f} s)")
    after = memory_per_student(hub.proc.pid, names, with_kernel=True)
    rss, uss = [v[0] for v in after.values()], [v[1] for v in after.values()]
    alone = [kernel_usage(hub.proc.pid, k) for k in kernels]
    print(f"memory after notebook 04, server + kernel: RSS {mb(rss)}, USS {mb(uss)}; the kernel alone: "
          f"RSS {mb(v[0] for v in alone)}, USS {mb(v[1] for v in alone)}")
    print(f"CPU time of a kernel's start and notebook 04: {spread((v[2] for v in alone), 1, 's')}")
    side = hub_side_mb(hub.proc.pid, names)
    fell = (available - psutil.virtual_memory().available) / 2**20
    print(f"hub, proxy and services: RSS {side:.0f} MB")
    print(f"the class of {len(names)}: RSS {sum(rss) + side:.0f} MB in all, USS {sum(uss):.0f} MB for the "
          f"students; available memory fell {fell:.0f} MB while the kernels started and ran notebook 04 "
          "(every process on the machine moves this figure)")
    return list(kernels)


async def latency(kernels: list, repeats: int, burst: int) -> None:
    one, rest = kernels[0], len(kernels) - 1
    trips, inside = await repeat(one, CLICK, repeats)
    print(f"one labeller click + redraw while {rest} idle: round trip {spread(trips)}; "
          f"in the kernel {spread(inside)}")
    trips, _ = await repeat(one, SMALL, repeats)
    print(f"one small cell ({SMALL}) while {rest} idle: round trip {spread(trips)}")
    results = await asyncio.gather(*(repeat(k, CLICK, repeats) for k in kernels[:burst]))
    print(f"labeller click + redraw, {burst} students at once: round trip "
          f"{spread(t for r in results for t in r[0])}; in the kernel {spread(t for r in results for t in r[1])}")


async def saves(hub: Hub, kernels: list) -> int:
    times, problems = await saves_at_once(kernels, hub.homes)
    print(f"{len(kernels)} students saving at once, 3 rounds: each save {spread(times)}")
    for problem in problems:
        print(f"LABELS LOST: {problem}")
    if not problems:
        print(f"no label lost: each of {len(kernels)} targets files held exactly what its student saved, "
              "every round")
    return 1 if problems else 0


async def one_runs_05(hub: Hub, client: Client, name: str) -> None:
    """One student also opens notebook 05 (its GA cells as committed), beside notebook 04."""
    kernel = await client.open_kernel(name, NOTEBOOK_05)
    took = await run_notebook(kernel, notebook_cells(hub.homes / name, NOTEBOOK_05))
    rss, uss, cpu = kernel_usage(hub.proc.pid, kernel)
    total = memory_per_student(hub.proc.pid, [name], with_kernel=True)[name]
    print(f"notebook 05 run by {name} in {took:.1f} s ({cpu:.1f} s CPU): its kernel RSS {rss:.0f} MB "
          f"(USS {uss:.0f} MB); "
          f"{name} with both notebooks open: RSS {total[0]:.0f} MB, USS {total[1]:.0f} MB")


async def measure(hub: Hub, names: list, args) -> int:
    client = Client(hub, args.students)
    await class_starts(hub, client, names, args.timeout)
    kernels = await class_runs_04(hub, client, names)
    await latency(kernels, args.repeats, args.burst)
    status = await saves(hub, kernels[:args.savers])
    if args.notebook05:
        await one_runs_05(hub, client, names[0])
    return status


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=30, help="executions timed per latency figure")
    parser.add_argument("--savers", type=int, default=10, help="students who save at the same moment")
    parser.add_argument("--burst", type=int, default=5, help="students who click at the same moment")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds to wait for the servers")
    parser.add_argument("--no-notebook05", dest="notebook05", action="store_false",
                        help="leave out one student's run of notebook 05")
    parser.add_argument("--smoke", action="store_true", help="two students, five repeats, no notebook 05")
    args = parser.parse_args(argv)
    if args.smoke:
        args.students, args.repeats, args.savers, args.burst, args.notebook05 = 2, 5, 2, 2, False
    if min(args.students, args.repeats, args.savers, args.burst) < 1:
        parser.error("--students, --repeats, --savers and --burst must be at least 1")
    args.savers, args.burst = min(args.savers, args.students), min(args.burst, args.students)
    print(f"before: {machine()}")
    with tempfile.TemporaryDirectory(prefix="bench-class-") as tmp:
        work = Path(tmp)
        t0 = time.perf_counter()
        names = [f"student{n:02d}" for n in range(1, args.students + 1)]
        for name in names:
            stage_course(work / "homes" / name)
        print(f"course copy: {(time.perf_counter() - t0) / args.students:.2f} s per student "
              "(made before start-up, not in its figure)")
        with running_hub(work, names) as hub:
            try:
                status = asyncio.run(measure(hub, names, args))
            except Exception:
                print(f"the hub's log ends:\n{hub.log.read_text()[-4000:]}", file=sys.stderr)
                raise
    print(f"after: {machine()}")
    return status


if __name__ == "__main__":
    sys.exit(main())
