"""Does the depth demo rank the objects right?  ``relative_depth`` on random object layouts.

Each layout (:func:`ismb_lab.scenes.object_layout`) holds two or three boxes or cylinders
at distinct depths (at least 3 px of disparity apart) in front of a textured wall, a
background pair without them and the truth.  Every layout goes through
:func:`ismb_lab.depth.pipeline.relative_depth` -- the code path of ``ismb-lab depth`` -- with the
demo's defaults, the layout's ROI ``(40, 40, 240, 160)`` and the layout's window shift
(``--shift`` on the command line; the middle of the layout's disparity range).

A layout is *ranked correctly* when the demo reports exactly one object per object put
into the scene (an object is "on" a true object when its centroid lies in that object's
left-image box, 4 px margin), nothing else, and the objects nearest first in the true
order.  Layout ``n`` of a split has the family ``names[n % k]`` of the ``k`` families it
cycles through (``--families``; default every registered one, :func:`ismb_lab.scenes.families`)
and ``2 + (n // k) % 2`` objects, so the families and object counts are balanced.
``--families unseen`` draws from :data:`ismb_lab.scenes.UNSEEN`, a family with wider sizes,
kinds, gaps, textures and cameras than the four, which the library does not register.

Protocol.  Every choice of :mod:`ismb_lab.depth.objects`, :mod:`ismb_lab.depth.outlines` and
:mod:`ismb_lab.depth.pipeline` was made on the development split (seeds ``DEV_START`` onwards,
of the four families and of ``unseen``).  ``--held-out`` runs the held-out split (seeds
``HELD_OUT_START`` onwards), drawn after those choices and run once.  The records of every
study, with the seeds of each split and which of them are spent, are
``docs/experiments/2026-11-24-depth-layouts.md``, ``docs/experiments/2026-11-25-depth-unseen.md``
and ``docs/experiments/2026-11-26-depth-unseen-2.md`` to ``-12.md``.

The variants those studies compared are not carried here: :data:`VARIANTS` names, for each, the
commit whose defaults it is (or whose options give it).  Up to commit d5bf071 this script carried
every variant, so, from a checkout of d5bf071 (``git worktree add ../at-d5bf071 d5bf071``),
``PYTHONPATH=../at-d5bf071 python ../at-d5bf071/scripts/depth_layouts.py --variants NAME,...``
scores them side by side on the same matches.

    python scripts/depth_layouts.py --count 360     # development split, 360 layouts (2 min)
    python scripts/depth_layouts.py --count 120 --families unseen     # the unseen family's
    python scripts/depth_layouts.py --held-out --seeds-from 2200000   # a fresh held-out split
    python scripts/depth_layouts.py --held-out --cli                  # through the CLI (3 min)
    python scripts/depth_layouts.py --count 12      # the first 12 (the test's set)
    python scripts/depth_layouts.py --solver assign # a variant: --method, --solver, --set
    python scripts/depth_layouts.py --set grouping=features          # the thesis' grouping
    python scripts/depth_layouts.py --set outline.split_score=0.85   # an outline setting
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np

from ismb_lab.depth.objects import DepthConfig
from ismb_lab.depth.pipeline import DEPTH_SOLVER, layout_match_config, relative_depth
from ismb_lab.scenes import UNSEEN, families, object_layout, register_family
from ismb_lab.depth.outlines import OutlineConfig


DEV_START = 1000
HELD_OUT_START = 880_000
MARGIN_PX = 4.0


def layout_of(seed: int, n: int, names=None):
    """Layout number `n` of a split: its family (of `names`, default every registered one) and
    object count follow `n`, the rest `seed`."""
    names = families() if names is None else names
    return object_layout(seed, 2 + (n // len(names)) % 2, family=names[n % len(names)])


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


def run_layout(seed: int, n: int, names=None, **kw):
    """Layout `n` of the split from `seed`, the demo's result and its verdict; `kw` go to
    :func:`ismb_lab.depth.pipeline.relative_depth` (``config=``, ``solver=``, ...)."""
    layout = layout_of(seed, n, names)
    result = relative_depth(layout.background, layout.scene, match_config=layout_match_config(layout), **kw)
    return layout, result, verdict(layout, result)


def run_layout_cli(seed: int, n: int, folder: Path, *, method: str, solver: str, grouping: str, names=None):
    """:func:`run_layout` through ``ismb-lab depth`` itself: the four images as PNG files
    (the renderer's grey levels are whole numbers, so nothing is lost), the layout's ROI
    and shift as options, the objects read back from ``--json``."""
    layout = layout_of(seed, n, names)
    paths = []
    for pair, name in ((layout.background, "bg"), (layout.scene, "scene")):
        for side in ("left", "right"):
            path = folder / f"{name}_{side}.png"
            cv2.imwrite(str(path), np.asarray(getattr(pair, side)).astype(np.uint8))
            paths.append(str(path))
    out = folder / "depth.json"
    cmd = [sys.executable, "-m", "ismb_lab.cli", "depth", *paths, "--roi", ",".join(map(str, layout.roi)),
           "--shift", f"{layout.shift:g}", "--method", method, "--solver", solver, "--grouping", grouping,
           "--json", str(out), "--force"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode:
        raise SystemExit(f"seed {seed}: ismb-lab depth failed: {proc.stderr.strip()}")
    objects = [SimpleNamespace(centroid_xy=tuple(o["centroid_xy"]), mean_disparity=o["mean_disparity"],
                               n_features=o["n_features"], disparity_spread=o["disparity_spread"])
               for o in json.loads(out.read_text())["objects"]]
    result = SimpleNamespace(objects=objects)
    return layout, result, verdict(layout, result)


def describe(layout, result) -> str:
    truth = ", ".join(f"{t.name} {t.kind} {t.contrast} d={t.disparity:.1f}" for t in layout.objects)
    found = ", ".join(f"({o.centroid_xy[0]:.0f},{o.centroid_xy[1]:.0f}) d={o.mean_disparity:.1f} "
                      f"n={o.n_features} sd={o.disparity_spread:.1f}" for o in result.objects)
    return f"truth [{truth}] wall {layout.wall_disparity:.1f} shift {layout.shift:g}; found [{found}]"


#: The variants of the depth studies, each with the commit whose defaults it is ("defaults") or whose
#: ``--variants NAME`` gives it ("option"), and the record that measured it.
VARIANTS = {
    "before": ("2b523b5", "defaults", "2026-11-25-depth-unseen.md"),
    "rules": ("b3dea3b", "defaults", "2026-11-25-depth-unseen.md"),
    "apart": ("c6ec087", "option", "2026-11-26-depth-unseen-2.md"),
    "behind": ("c6ec087", "option", "2026-11-26-depth-unseen-2.md"),
    "apart+behind": ("c6ec087", "option", "2026-11-26-depth-unseen-2.md"),
    "apart+behind0": ("754ee34", "defaults", "2026-11-26-depth-unseen-2.md"),
    "far": ("4cb8e10", "option", "2026-11-26-depth-unseen-3.md"),
    "floor": ("4cb8e10", "option", "2026-11-26-depth-unseen-3.md"),
    "far+floor": ("c3bd608", "defaults", "2026-11-26-depth-unseen-3.md"),
    "cut": ("522f49a", "option", "2026-11-26-depth-unseen-4.md"),
    "weak": ("522f49a", "option", "2026-11-26-depth-unseen-4.md"),
    "cut+weak": ("0a62161", "defaults", "2026-11-26-depth-unseen-4.md"),
    "band": ("22ce4f9", "option", "2026-11-26-depth-unseen-5.md"),
    "firm": ("22ce4f9", "option", "2026-11-26-depth-unseen-5.md"),
    "band+firm": ("0ee8c94", "defaults", "2026-11-26-depth-unseen-5.md"),
    "link": ("33e91e1", "option", "2026-11-26-depth-unseen-6.md"),
    "one": ("33e91e1", "option", "2026-11-26-depth-unseen-6.md"),
    "join": ("33e91e1", "option", "2026-11-26-depth-unseen-6.md"),
    "poor": ("33e91e1", "option", "2026-11-26-depth-unseen-6.md"),
    "link+one+join": ("33e91e1", "option", "2026-11-26-depth-unseen-6.md"),
    "sixth": ("3873c4b", "defaults", "2026-11-26-depth-unseen-6.md"),
    "seventh": ("a3cb019", "defaults", "2026-11-26-depth-unseen-7.md"),
    "eighth": ("1d7133d", "defaults", "2026-11-26-depth-unseen-8.md"),
    "ninth": ("6de3e00", "defaults", "2026-11-26-depth-unseen-9.md"),
    "eleventh": ("8d7cb56", "option", "2026-11-26-depth-unseen-11.md"),
    "twelfth": ("ff50597", "defaults", "2026-11-26-depth-unseen-12.md"),
}


def config_of(items) -> DepthConfig:
    """The DepthConfig of ``--set`` items ``FIELD=VALUE`` (``outline.FIELD=VALUE`` for its outline
    section); ValueError naming the item when a field is unknown or its value of the wrong kind."""
    top, outline = {}, {}
    for item in items:
        name, _, value = item.partition("=")
        section, cls = (outline, OutlineConfig) if name.startswith("outline.") else (top, DepthConfig)
        name = name.removeprefix("outline.")
        kinds = {f.name: str(f.type) for f in dataclasses.fields(cls) if f.name != "outline"}
        if name not in kinds:
            raise ValueError(f"--set {item}: no {cls.__name__} field {name!r}")
        kind = kinds[name]
        try:
            section[name] = {"int": int, "str": str}.get(kind, float)(value)
        except ValueError:
            raise ValueError(f"--set {item}: {name} takes {kind}") from None
    try:
        return DepthConfig(**top, outline=OutlineConfig(**outline))
    except (ValueError, TypeError) as error:
        raise ValueError(f"--set {', '.join(items)}: {error}") from None


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--held-out", action="store_true", help="run the held-out split (once)")
    parser.add_argument("--count", type=int, default=120, help="layouts to run (default 120)")
    parser.add_argument("--quiet", action="store_true", help="do not list the failures")
    parser.add_argument("--method", default="III", help="energy recipe of both runs (default III)")
    parser.add_argument("--solver", default=DEPTH_SOLVER, help=f"solver of both runs (default {DEPTH_SOLVER})")
    parser.add_argument("--seeds-from", type=int, default=None, metavar="SEED",
                        help=f"first layout seed (default {DEV_START}, or {HELD_OUT_START} with --held-out)")
    parser.add_argument("--cli", action="store_true",
                        help="run every layout through 'ismb-lab depth' on PNG files (about 2 s more each)")
    parser.add_argument("--families", default=None, metavar="NAME,...",
                        help="the families to cycle through (default every registered one; "
                        f"{UNSEEN.name!r} is registered when named)")
    parser.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                        help="a DepthConfig field for a variant, e.g. --set min_features=3, or one of its "
                        "outline section, e.g. --set outline.split_score=0.85")
    args = parser.parse_args(argv)
    try:
        config = config_of(args.set)
    except ValueError as error:
        parser.error(str(error))
    names = families() if args.families is None else tuple(args.families.split(","))
    if UNSEEN.name in names and UNSEEN.name not in families():
        register_family(UNSEEN)
    for name in names:
        if name not in families():
            parser.error(f"--families {args.families}: no family {name!r} (registered: {', '.join(families())})")
    if args.cli and config != DepthConfig(grouping=config.grouping):
        parser.error("--cli takes no --set but grouping=...")
    label = ", ".join(args.set) or "defaults"
    start = args.seeds_from if args.seeds_from is not None else HELD_OUT_START if args.held_out else DEV_START
    t0 = time.perf_counter()
    by = defaultdict(lambda: [0, 0])
    kinds_by = defaultdict(lambda: defaultdict(int))
    failures = []
    folder = tempfile.TemporaryDirectory(prefix="depth_layouts-")
    for n in range(args.count):
        if args.cli:
            layout, result, what = run_layout_cli(start + n, n, Path(folder.name), method=args.method,
                                                  solver=args.solver, grouping=config.grouping, names=names)
        else:
            layout, result, what = run_layout(start + n, n, names, config=config, method=args.method,
                                              solver=args.solver)
        for key in ("all", layout.family, f"{len(layout.objects)} objects"):
            by[key][0] += what == "ok"
            by[key][1] += 1
            kinds_by[key][what] += 1
        if what != "ok":
            failures.append((start + n, layout, result, what))
    elapsed = time.perf_counter() - t0
    split = "held-out" if args.held_out else "development"
    folder.cleanup()
    print(f"{split} split, seeds {start}..{start + args.count - 1}, Method-{args.method}, {args.solver}"
          + (", through ismb-lab depth" if args.cli else "") + f": {elapsed:.0f} s "
          f"({elapsed / max(args.count, 1):.2f} s per layout)")
    print(f" {label}:")
    for key in ("all", *names, "2 objects", "3 objects"):
        if key in by:
            ok, total = by[key]
            wrong = ", ".join(f"{k} {v}" for k, v in sorted(kinds_by[key].items()) if k != "ok")
            print(f"  {key:<12} {ok:>4} / {total:<4} ranked correctly ({100 * ok / total:.1f}%)"
                  + (f"; {wrong}" if wrong else ""))
    if not args.quiet:
        for seed, layout, result, what in failures:
            print(f"seed {seed} {layout.family} {what}: {describe(layout, result)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
