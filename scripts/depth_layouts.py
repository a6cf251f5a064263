"""Does the depth demo rank the objects right?  ``relative_depth`` on random object layouts.

Each layout (:func:`ismb_lab.scenes.object_layout`) holds two or three boxes or cylinders
at distinct depths (at least 3 px of disparity apart) in front of a textured wall, a
background pair without them and the truth.  Every layout goes through
:func:`ismb_lab.depth_demo.relative_depth` -- the code path of ``ismb-lab depth`` -- with the
demo's defaults, the layout's ROI ``(40, 40, 240, 160)`` and the layout's window shift
(``--shift`` on the command line; the middle of the layout's disparity range).

A layout is *ranked correctly* when the demo reports exactly one object per object put
into the scene (an object is "on" a true object when its centroid lies in that object's
left-image box, 4 px margin), nothing else, and the objects nearest first in the true
order.  Layout ``n`` of a split has the family ``FAMILIES[n % 4]`` and ``2 + (n // 4) % 2``
objects, so the families and object counts are balanced.

Protocol.  Every choice of :mod:`ismb_lab.depth` and :mod:`ismb_lab.depth_demo` was made on
the development split (seeds ``DEV_START`` onwards).  ``--held-out`` runs the held-out
split (seeds ``HELD_OUT_START`` onwards), drawn after those choices and run once.

Measured (120 layouts each, about 0.5 s per layout on one core then; 0.3 s since the
annealing is compiled, with the same figures):

    split (seeds)            all     contrast repetitive border  cameras  2 obj   3 obj
    development (1000-)      79/120  23/30    6/30       25/30   25/30    43/60   36/60
    held-out (810000-)       78/120  23/30    7/30       20/30   28/30    40/60   38/60

The ranking holds on contrast, border and camera layouts in three or four cases of five
and fails on most repetitive ones, where a whole object is matched one period off or
splits into bands one period apart.  The variants tried on the development split, with
its figure, are listed in ``VARIANTS`` below.

    python scripts/depth_layouts.py                 # development split, 120 layouts
    python scripts/depth_layouts.py --held-out      # held-out split, 120 layouts
    python scripts/depth_layouts.py --count 12      # the first 12 (the test's set)
    python scripts/depth_layouts.py --solver assign # a variant: --method, --solver, --set
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections import defaultdict

from ismb_lab.depth import DepthConfig
from ismb_lab.depth_demo import DEPTH_SOLVER, layout_match_config, relative_depth
from ismb_lab.scenes import FAMILIES, object_layout

VARIANTS = """
development split figures of every variant tried (first 40 layouts = seeds 1000-1039;
"120" = the whole split):
  demo as it was (changed box, 40-60 corners, single linkage)     40: 10/40 (25%)
  + corners per blob of change, 20-40 each                         40: 23/40 (57.5%)
  + peeling consensus bands, merging like halves (45 px, 1.5 px)   40: 24/40 (60%)
    variants of that: min_features=3 25/40, consensus_px=1.5 24/40, link_px=45 24/40,
    20-40 -> 30-60 corners per blob 25/40, 12-30 22/40
  + corners only near changed pixels (grow 3 px)                   40: 26/40; 1 px 27/40;
    6 px 24/40; 120: 77/120 (64.2%) -- dropped: noise-level, and nothing left for the
    background removal to remove
  without it, border boxes across the image edge                   120: 74/120 (61.7%);
    a first held-out run (seeds 730000-730119) of this variant: 76/120 (63.3%)
  + the changed box's own 40-60 corners kept beside the blobs'     120: 79/120 (65.8%)
    (chosen: the committed toy-car pair keeps its background removal); held-out 78/120
  after that choice, on 2026-11-25, not chosen:
    --set min_features=3                                           120: 83/120 (69.2%)
    --set min_features=4                                           120: 83/120 (69.2%)
    both trade splits and spurious fragments for missing objects (missing 6 -> 16 and
    23); issue #15 asks that an object with few features be kept when its disparity is
    consistent, and four more layouts (69%, against 95% asked) are not worth breaking that for
    --solver assign                                                120: 80/120 (66.7%), in
    half the time (0.24 s per layout); one layout more is within noise, not chosen
    --method NM4 (its own default parameters, not fitted)          120: 3/120 (2.5%)
    --method NM4 --solver assign                                   120: 5/120 (4.2%)
    NM4 with Method-III's thesis parameters breaks every layout into spurious fragments; a fair
    trial needs parameters fitted for it (scripts/fit_depth_params.py), not done
"""

DEV_START = 1000
HELD_OUT_START = 810_000
MARGIN_PX = 4.0


def layout_of(seed: int, n: int):
    """Layout number `n` of a split: its family and object count follow `n`, the rest `seed`."""
    return object_layout(seed, 2 + (n // 4) % 2, family=FAMILIES[n % len(FAMILIES)])


def assign(layout, result) -> list:
    """For each reported object (nearest first), the name of the true object it lies on, or None."""
    names = []
    for obj in result.objects:
        x, y = obj.centroid_xy
        on = [t.name for t in layout.objects
              if t.box_xy[0] - MARGIN_PX <= x <= t.box_xy[2] + MARGIN_PX
              and t.box_xy[1] - MARGIN_PX <= y <= t.box_xy[3] + MARGIN_PX]
        names.append(on[0] if len(on) == 1 else None)
    return names


def verdict(layout, result) -> str:
    """``"ok"`` or what went wrong: missing, split, spurious or order."""
    names = assign(layout, result)
    truth = list(layout.order)
    if None in names:
        return "spurious"
    if len(set(names)) < len(names):
        return "split"
    if len(names) < len(truth):
        return "missing"
    return "ok" if names == truth else "order"


def run_layout(seed: int, n: int, **kw):
    layout = layout_of(seed, n)
    result = relative_depth(layout.background, layout.scene, match_config=layout_match_config(layout),
                            **kw)
    return layout, result, verdict(layout, result)


def describe(layout, result) -> str:
    truth = ", ".join(f"{t.name} {t.kind} {t.contrast} d={t.disparity:.1f}" for t in layout.objects)
    found = ", ".join(f"({o.centroid_xy[0]:.0f},{o.centroid_xy[1]:.0f}) d={o.mean_disparity:.1f} "
                      f"n={o.n_features} sd={o.disparity_spread:.1f}" for o in result.objects)
    return f"truth [{truth}] wall {layout.wall_disparity:.1f} shift {layout.shift:g}; found [{found}]"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--held-out", action="store_true", help="run the held-out split (once)")
    parser.add_argument("--count", type=int, default=120, help="layouts to run (default 120)")
    parser.add_argument("--quiet", action="store_true", help="do not list the failures")
    parser.add_argument("--method", default="III", help="energy recipe of both runs (default III)")
    parser.add_argument("--solver", default=DEPTH_SOLVER, help=f"solver of both runs (default {DEPTH_SOLVER})")
    parser.add_argument("--seeds-from", type=int, default=None, metavar="SEED",
                        help=f"first layout seed (default {DEV_START}, or {HELD_OUT_START} with --held-out)")
    parser.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                        help="a DepthConfig field for a variant, e.g. --set min_features=3")
    args = parser.parse_args(argv)
    fields = {f.name: f.type for f in dataclasses.fields(DepthConfig)}
    overrides = {}
    for item in args.set:
        name, _, value = item.partition("=")
        if name not in fields:
            parser.error(f"--set {item}: no DepthConfig field {name!r}")
        overrides[name] = {"int": int, "bool": lambda v: v == "True"}.get(fields[name], float)(value)
    config = DepthConfig(**overrides)
    start = args.seeds_from if args.seeds_from is not None else HELD_OUT_START if args.held_out else DEV_START
    t0 = time.perf_counter()
    by = defaultdict(lambda: [0, 0])
    failures = []
    for n in range(args.count):
        layout, result, what = run_layout(start + n, n, config=config, method=args.method, solver=args.solver)
        for key in ("all", layout.family, f"{len(layout.objects)} objects"):
            by[key][0] += what == "ok"
            by[key][1] += 1
        if what != "ok":
            failures.append((start + n, layout, result, what))
    elapsed = time.perf_counter() - t0
    split = "held-out" if args.held_out else "development"
    print(f"{split} split, seeds {start}..{start + args.count - 1}, Method-{args.method}, {args.solver}"
          + (f", {', '.join(args.set)}" if args.set else "") + f": {elapsed:.0f} s "
          f"({elapsed / max(args.count, 1):.2f} s per layout)")
    for key in ("all", *FAMILIES, "2 objects", "3 objects"):
        if key in by:
            ok, total = by[key]
            print(f"  {key:<12} {ok:>4} / {total:<4} ranked correctly ({100 * ok / total:.1f}%)")
    kinds = defaultdict(int)
    for *_, what in failures:
        kinds[what] += 1
    if kinds:
        print("  failures: " + ", ".join(f"{k} {v}" for k, v in sorted(kinds.items())))
    if not args.quiet:
        for seed, layout, result, what in failures:
            print(f"seed {seed} {layout.family} {what}: {describe(layout, result)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
