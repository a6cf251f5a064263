"""Time the widgets' interactive paths on the Agg canvas: model work plus a full redraw.

* one HopfieldStepper step plus redraw (target <= 30 ms), split into attempts that
  flipped an output (three figures redrawn) and attempts that did not (two);
* one ParameterExplorer slider change: rematch, score, redraw (target <= 100 ms);
* one TargetLabeler canvas click (a mouse event through the canvas callbacks):
  snap, edit, table, redraw (target <= 30 ms);
* one DepthDemo seed change on images/lab + images/toy_cars: both pairs matched
  again, objects ranked, two figures redrawn (target <= 100 ms, as a slider move).

Prints medians (and the 90th percentile) over many repeats in this process.

    python benchmarks/bench_widgets.py
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=True)

from matplotlib.backend_bases import MouseEvent  # noqa: E402

from ismb_lab.matching.pipeline import prepare  # noqa: E402
from ismb_lab.widgets import DepthDemo, HopfieldStepper, ParameterExplorer, TargetLabeler  # noqa: E402

IMAGES = Path(__file__).resolve().parents[1] / "images"
PAIR = IMAGES / "synthetic"


def timed(action) -> float:
    start = time.perf_counter()
    action()
    return (time.perf_counter() - start) * 1e3


def summary(name: str, times: list, target: float) -> None:
    times = sorted(times)
    median = statistics.median(times)
    p90 = times[int(0.9 * (len(times) - 1))]
    print(f"{name:<44} median {median:6.1f} ms   p90 {p90:6.1f} ms   n={len(times):<4} "
          f"target {target:g} ms (median/target {median / target:.2f})")


def bench_stepper(prepared, n: int = 200) -> None:
    stepper = HopfieldStepper(prepared, seed=0)
    flipped, still = [], []
    while len(flipped) + len(still) < n:
        if stepper.model.done:
            stepper.model.reset(stepper.model.seed + 1)
        before = stepper.model.flips
        t = timed(lambda: stepper.step(1))
        (flipped if stepper.model.flips > before else still).append(t)
    summary("HopfieldStepper step + redraw (all)", flipped + still, 30)
    summary("  attempts that flipped (3 figures)", flipped, 30)
    summary("  attempts that changed nothing (2 figures)", still, 30)


def bench_explorer(prepared, n: int = 40) -> None:
    explorer = ParameterExplorer(prepared, targets=[[0, 0]])
    slider = explorer.sliders["theta_c"]
    values = [10.0 + (i % 20) for i in range(n)]
    summary("ParameterExplorer slider -> rematch + redraw",
            [timed(lambda v=v: setattr(slider, "value", v)) for v in values], 100)


def bench_labeler(prepared, n: int = 120) -> None:
    labeler = TargetLabeler(prepared)
    model, fig, ax = labeler.model, labeler.pane.fig, labeler.ax
    times = []
    for j in range(n):
        # left i, right i, then both again (selecting), cycling over the features
        i = (j // 4) % min(len(model.left_xy), len(model.right_xy))
        right = j % 2 == 1
        x, y = (model.right_xy[i] + [model.offset, 0]) if right else model.left_xy[i]
        px, py = ax.transData.transform((x, y))
        event = MouseEvent("button_press_event", fig.canvas, px, py, button=1)
        times.append(timed(lambda: fig.canvas.callbacks.process("button_press_event", event)))
    assert labeler.errors == []
    summary("TargetLabeler canvas click + redraw", times, 30)


def bench_depth(n: int = 30) -> None:
    demo = DepthDemo.from_folders(IMAGES / "lab", IMAGES / "toy_cars")
    times = [timed(lambda s=s: setattr(demo.seed_field, "value", s)) for s in range(1, n + 1)]
    assert demo.errors == []
    summary("DepthDemo seed -> recompute + redraw", times, 100)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help="a few repeats of each")
    smoke = parser.parse_args(argv).smoke
    prepared = prepare(PAIR / "left.png", PAIR / "right.png")
    problem = prepared.problem
    print(f"pair {PAIR.name}: {len(problem.left_xy)}x{len(problem.right_xy)} corners, "
          f"{problem.n_neurons} candidate neurons; matplotlib backend {matplotlib.get_backend()}")
    if smoke:
        bench_stepper(prepared, 12)
        bench_explorer(prepared, 3)
        bench_labeler(prepared, 8)
        bench_depth(2)
        return
    bench_stepper(prepared)
    bench_explorer(prepared)
    bench_labeler(prepared)
    bench_depth()


if __name__ == "__main__":
    main()
