"""What one student costs a shared server: kernel memory after notebooks 04 and 05, and the
labeller's click-to-redraw latency when several students click at once.

    python benchmarks/bench_hub.py [--students 5] [--clicks 40]
    python benchmarks/bench_hub.py --smoke

* Memory: each notebook is executed headlessly (nbclient, as a student's Run All) in a
  fresh kernel; then the kernel's resident memory (RSS) is read with psutil.  Notebook 05
  is executed with its GA cells as they are committed.
* Latency: ``--students`` processes each build notebook 04's labeller (Agg canvas, as the
  kernel renders it) and time ``--clicks`` clicks, each a click on a feature plus the full
  redraw, first one student alone, then all at once.  This is the server's share of a
  click; the browser's own drawing is not included.

Prints medians and 90th percentiles, and the students one 2-core, 8 GB server holds by
memory (kernel plus an idle single-user server, whose RSS tests/browser/test_hub.py records
in test-artifacts/hub_kernels_rss_mb.json).
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import shutil
import statistics
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def kernel_rss_after(notebook: str) -> float:
    """RSS (MB) of the kernel that just ran `notebook` to the end."""
    import nbformat
    import psutil
    from nbclient import NotebookClient

    nb = nbformat.read(ROOT / "notebooks" / notebook, as_version=4)
    with tempfile.TemporaryDirectory() as work:      # a student's copy: notebooks/ beside images/
        for name in ("notebooks", "images"):
            shutil.copytree(ROOT / name, Path(work) / name)
        client = NotebookClient(nb, timeout=600, kernel_name="python3",
                                resources={"metadata": {"path": str(Path(work) / "notebooks")}})
        with client.setup_kernel(cwd=str(Path(work) / "notebooks")):
            client.execute(cleanup_kc=False)
            pid = client.km.provisioner.process.pid
            rss = psutil.Process(pid).memory_info().rss / 2**20
    return rss


def _clicks(args) -> list:
    n_clicks, start = args
    import matplotlib

    matplotlib.use("Agg", force=True)
    from ismb_lab.widgets import TargetLabeler

    labeler = TargetLabeler.from_folder(ROOT / "images" / "synthetic", path=Path(tempfile.mkdtemp()) / "t.json")
    model = labeler.model
    while time.time() < start:          # all students start clicking together
        time.sleep(0.001)
    times = []
    for n in range(n_clicks):
        x, y = model.left_xy[n % len(model.left_xy)]
        t0 = time.perf_counter()
        labeler.click(x, y, side="left")
        labeler.pane.draw()
        times.append(time.perf_counter() - t0)
        labeler.click(x, y, side="left")   # unselect, untimed
    return times


def click_latency(students: int, clicks: int) -> list:
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(students) as pool:
        start = time.time() + 8.0          # time for every process to import and build
        results = pool.map(_clicks, [(clicks, start)] * students)
    return [t for r in results for t in r[2:]]   # the first two clicks warm the caches


def summary(values, unit=1000.0, suffix="ms") -> str:
    v = sorted(values)
    p90 = v[min(len(v) - 1, int(0.9 * len(v)))]
    return f"median {statistics.median(v) * unit:.1f} {suffix}, p90 {p90 * unit:.1f} {suffix} ({len(v)} clicks)"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=5)
    parser.add_argument("--clicks", type=int, default=40)
    parser.add_argument("--smoke", action="store_true", help="two students, five clicks, notebook 04 only")
    args = parser.parse_args(argv)
    if args.smoke:
        args.students, args.clicks = 2, 5
    print(f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.2f}")
    notebooks = ["04_label_targets.ipynb"] + ([] if args.smoke else ["05_genetic_algorithm.ipynb"])
    rss = {}
    for nb in notebooks:
        rss[nb] = kernel_rss_after(nb)
        print(f"kernel RSS after {nb}: {rss[nb]:.0f} MB")
    alone = click_latency(1, args.clicks)
    print(f"labeller click + redraw, 1 student: {summary(alone)}")
    together = click_latency(args.students, args.clicks)
    print(f"labeller click + redraw, {args.students} students at once: {summary(together)}")
    worst = max(rss.values())
    print(f"students per 8 GB by kernel memory alone (worst notebook, {worst:.0f} MB): {int(8192 // worst)}")


if __name__ == "__main__":
    main()
