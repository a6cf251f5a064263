"""A class on one JupyterHub: start-up, memory per student, latency, and saves with no label lost.

    python benchmarks/bench_class.py [--students 30] [--repeats 30] [--savers 10] [--burst 5]
                                     [--numba shared|private] [--first-runs]
    python benchmarks/bench_class.py --smoke        # two students, a few repeats

The hub runs ``deploy/jupyterhub_config.py`` (see ``class_hub.py`` for the few settings a
run changes), with **the dummy login and the simple local-process spawner**, not PAM and
real accounts: thirty OS accounts, and a venv outside ``/root`` that they can run, are too
heavy for a benchmark, and ``tests/hub/`` tests the real-account hub.  So every server runs
as the user who starts the script, with a home folder in a temporary folder, and the
deployment's memory limits (cgroups, RLIMIT_DATA) are not applied.  Each home gets its copy
of the course before start-up (timed on its own), and a numba cache of its own, as students
who cannot write into the venv.  ``--numba shared`` (the default, as deployed): the teacher's
step compiles the kernels once into a read-only folder (``ismb_lab.teaching.kernels.compile_into``,
what ``hub_start stage`` runs; timed), and each student's process copies them into their
own cache.  ``--numba private`` (the deployment before that step): every student's kernels
compile on their first run.

No browser: each student's own single-user server runs their kernel, driven through the
hub's proxy with the Jupyter server's sessions and kernel websocket API, as JupyterLab does.
What a browser draws, and the transfer of the figure's frames to it, is not included.

Measured, in order:

1. **start-up:** all servers asked for at once (``POST /hub/api/users/NAME/server``);
   the time until each answers 200 on ``/user/NAME/api/status``;
2. **memory, idle:** each single-user server's resident memory (RSS) and its own share
   (USS, not shared with other processes), read with psutil, and how far the machine's
   available memory fell;
3. **notebooks 00, then 04**, opened and run by every student at once, cell by cell (Run
   All), each student closing 00's kernel before opening 04: when the last student's first
   cell, warm-up cell and whole notebook were done, and the CPU time of each student's two
   kernels; then each student's server + kernel memory (``--first-runs`` stops here);
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
import statistics
import sys
import tempfile
import time
from pathlib import Path

from class_hub import (NOTEBOOK_00, Client, Hub, Kernel, hub_side_mb, kernel_usage, memory_per_student,
                       notebook_cells, open_and_run, run_notebook, running_hub, shut_down, stage_course)

NOTEBOOK_GA = "ismb_lab/notebooks/06_genetic_algorithm.ipynb"
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
    from ismb_lab.labels.targets import load_targets

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
def teachers_step(work: Path) -> Path:
    """The kernels compiled once, as ``hub_start stage`` does, for the package the servers
    import (this repository, on their PYTHONPATH); the folder, made read-only."""
    import resource

    from ismb_lab.teaching.kernels import compile_into

    root = Path(__file__).resolve().parents[1]
    os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), os.environ.get("PYTHONPATH")]))
    folder, before, t0 = work / "teacher" / "numba", resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    report = compile_into(folder, isolated=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    for top, _, names in os.walk(work / "teacher"):
        os.chmod(top, 0o755)
        for name in names:
            os.chmod(os.path.join(top, name), 0o644)
    print(f"the teacher's step: {report['kernels']} kernels compiled once in {time.perf_counter() - t0:.1f} s "
          f"({cpu:.1f} CPU-s){'; not compiled: ' + ', '.join(report['cold']) if report['cold'] else ''}; "
          "each student's process copies them into their own cache")
    return folder


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


async def first_runs(client: Client, name: str, cells: tuple, t0: float, pid: int) -> dict:
    """`name` runs notebook 00, closes its kernel, then runs notebook 04 (kept open)."""
    k00, done00 = await open_and_run(client, name, cells[0], t0, NOTEBOOK_00)
    cpu00 = kernel_usage(pid, k00)[2]
    await shut_down(client, k00)
    k04, done04 = await open_and_run(client, name, cells[1], t0)
    return {"kernel": k04, "00": done00, "04": done04, "cpu00": cpu00, "cpu04": kernel_usage(pid, k04)[2]}


async def class_runs_00_and_04(hub: Hub, client: Client, names: list) -> list:
    """Every student opens notebook 00 and runs it, then 04, all at once; returns their 04 kernels."""
    import psutil

    home = hub.homes / names[0]
    cells = (notebook_cells(home, NOTEBOOK_00), notebook_cells(home))
    warm = next(i for i, code in enumerate(cells[0]) if "warm_up()" in code)
    available, t0 = psutil.virtual_memory().available, time.perf_counter()
    runs = await asyncio.gather(*(first_runs(client, n, cells, t0, hub.proc.pid) for n in names))
    last = {what: max(r[nb][i] for r in runs) for what, nb, i in
            (("first", "00", 0), ("warm", "00", warm), ("00", "00", -1), ("04", "04", -1))}
    print(f"notebooks 00 then 04 run by all {len(names)} at once, seconds until the last student was done: "
          f"00's first cell {last['first']:.1f} s, its warm-up cell {last['warm']:.1f} s, notebook 00 "
          f"{last['00']:.1f} s, notebook 04 {last['04']:.1f} s")
    print(f"CPU time per student: 00's kernel {spread((r['cpu00'] for r in runs), 1, 's')}, "
          f"04's kernel {spread((r['cpu04'] for r in runs), 1, 's')}, both "
          f"{spread((r['cpu00'] + r['cpu04'] for r in runs), 1, 's')}")
    kernels = [r["kernel"] for r in runs]
    after = memory_per_student(hub.proc.pid, names, with_kernel=True)
    rss, uss = [v[0] for v in after.values()], [v[1] for v in after.values()]
    alone = [kernel_usage(hub.proc.pid, k) for k in kernels]
    print(f"memory after notebook 04, server + kernel: RSS {mb(rss)}, USS {mb(uss)}; the kernel alone: "
          f"RSS {mb(v[0] for v in alone)}, USS {mb(v[1] for v in alone)}")
    side = hub_side_mb(hub.proc.pid, names)
    fell = (available - psutil.virtual_memory().available) / 2**20
    print(f"hub, proxy and services: RSS {side:.0f} MB")
    print(f"the class of {len(names)}: RSS {sum(rss) + side:.0f} MB in all, USS {sum(uss):.0f} MB for the "
          f"students; available memory fell {fell:.0f} MB while the kernels started and ran notebooks 00 and 04 "
          "(every process on the machine moves this figure)")
    return kernels


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
    kernel = await client.open_kernel(name, NOTEBOOK_GA)
    took = await run_notebook(kernel, notebook_cells(hub.homes / name, NOTEBOOK_GA))
    rss, uss, cpu = kernel_usage(hub.proc.pid, kernel)
    total = memory_per_student(hub.proc.pid, [name], with_kernel=True)[name]
    print(f"notebook 05 run by {name} in {took:.1f} s ({cpu:.1f} s CPU): its kernel RSS {rss:.0f} MB "
          f"(USS {uss:.0f} MB); "
          f"{name} with both notebooks open: RSS {total[0]:.0f} MB, USS {total[1]:.0f} MB")


async def measure(hub: Hub, names: list, args) -> int:
    client = Client(hub, args.students)
    await class_starts(hub, client, names, args.timeout)
    kernels = await class_runs_00_and_04(hub, client, names)
    if args.first_runs:
        return 0
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
    parser.add_argument("--numba", choices=("shared", "private"), default="shared",
                        help="shared: the teacher's step compiles the kernels once and every student loads "
                             "them (as deployed); private: every student compiles their own")
    parser.add_argument("--first-runs", action="store_true",
                        help="stop after the class's first runs of notebooks 00 and 04")
    parser.add_argument("--smoke", action="store_true", help="two students, five repeats, no notebook 05")
    args = parser.parse_args(argv)
    if args.smoke:
        args.students, args.repeats, args.savers, args.burst, args.notebook05 = 2, 5, 2, 2, False
    if min(args.students, args.repeats, args.savers, args.burst) < 1:
        parser.error("--students, --repeats, --savers and --burst must be at least 1")
    args.savers, args.burst = min(args.savers, args.students), min(args.burst, args.students)
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, numba kernels: {args.numba}; before: {machine()}")
    with tempfile.TemporaryDirectory(prefix="bench-class-") as tmp:
        work = Path(tmp)
        t0 = time.perf_counter()
        names = [f"student{n:02d}" for n in range(1, args.students + 1)]
        for name in names:
            stage_course(work / "homes" / name)
        print(f"course copy: {(time.perf_counter() - t0) / args.students:.2f} s per student "
              "(made before start-up, not in its figure)")
        kernels = teachers_step(work) if args.numba == "shared" else None
        with running_hub(work, names, kernels) as hub:
            try:
                status = asyncio.run(measure(hub, names, args))
            except Exception:
                print(f"the hub's log ends:\n{hub.log.read_text()[-4000:]}", file=sys.stderr)
                raise
    print(f"after: {machine()}")
    return status


if __name__ == "__main__":
    sys.exit(main())
