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
order.  Layout ``n`` of a split has the family ``names[n % k]`` of the ``k`` families it
cycles through (``--families``; default every registered one, :func:`ismb_lab.scenes.families`)
and ``2 + (n // k) % 2`` objects, so the families and object counts are balanced.
``--families unseen`` draws from :data:`ismb_lab.scenes.UNSEEN`, a family with wider sizes,
kinds, gaps, textures and cameras than the four, which the library does not register.

Protocol.  Every choice of :mod:`ismb_lab.depth`, :mod:`ismb_lab.silhouettes` and
:mod:`ismb_lab.depth_demo` was made on the development split (seeds ``DEV_START`` onwards,
of the four families and of ``unseen``).  ``--held-out`` runs the held-out split (seeds
``HELD_OUT_START`` onwards), drawn after those choices and run once.

The figures of the defaults on both splits, and of every variant tried on the development
split, are in ``docs/experiments/2026-11-24-depth-layouts.md``,
``docs/experiments/2026-11-25-depth-unseen.md``, ``docs/experiments/2026-11-26-depth-unseen-2.md``,
``docs/experiments/2026-11-26-depth-unseen-3.md``, ``docs/experiments/2026-11-26-depth-unseen-4.md``,
``docs/experiments/2026-11-26-depth-unseen-5.md`` and ``docs/experiments/2026-11-26-depth-unseen-6.md``.

    python scripts/depth_layouts.py --count 360     # development split, 360 layouts (2 min)
    python scripts/depth_layouts.py --count 120 --families unseen     # the unseen family's
    python scripts/depth_layouts.py --held-out      # the first held-out split, 880000- (40 s)
    python scripts/depth_layouts.py --held-out --seeds-from 1200000 --variants   # the second, every variant
    python scripts/depth_layouts.py --held-out --seeds-from 1600000 --variants   # the third (spent too)
    python scripts/depth_layouts.py --held-out --seeds-from 1700000 --variants   # the fourth (spent too)
    python scripts/depth_layouts.py --held-out --seeds-from 1800000 --variants   # the fifth (spent too)
    python scripts/depth_layouts.py --held-out --seeds-from 1900000 --variants   # the sixth (spent too)
    python scripts/depth_layouts.py --held-out --seeds-from 1950000 --variants   # the seventh (spent too)
    python scripts/depth_layouts.py --held-out --seeds-from 2000000 --variants   # the eighth (spent too)
    python scripts/depth_layouts.py --held-out --seeds-from 2050000 --variants   # the ninth (spent too)
    python scripts/depth_layouts.py --held-out --seeds-from 2100000 --variants   # the tenth (spent too)
    python scripts/depth_layouts.py --held-out --cli                  # through the CLI (3 min)
    python scripts/depth_layouts.py --count 12      # the first 12 (the test's set)
    python scripts/depth_layouts.py --solver assign # a variant: --method, --solver, --set, --blobs
    python scripts/depth_layouts.py --set grouping=features          # the thesis' grouping
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

from ismb_lab.depth import DepthConfig, depth_from_matches
from ismb_lab.depth_demo import DEPTH_SOLVER, depth_pairs, layout_match_config, pair_silhouettes, relative_depth
from ismb_lab.io import load_pair
from ismb_lab.scenes import UNSEEN, families, object_layout, register_family
from ismb_lab.silhouettes import silhouettes
from ismb_lab.texture import textured


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


def run_layout(seed: int, n: int, names=None, blobs=None, **kw):
    """Layout `n` of the split from `seed`, the demo's result and its verdict; `blobs` are
    options of :func:`ismb_lab.silhouettes.silhouettes` for a variant (``{"split": False}``)."""
    layout = layout_of(seed, n, names)
    prepared = depth_pairs(layout.background, layout.scene, layout_match_config(layout))
    grouped = pair_silhouettes(prepared, **blobs) if blobs else None
    result = relative_depth(layout.background, layout.scene, prepared=prepared, silhouettes=grouped, **kw)
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


SIXTH_OFF = {"band_one_piece": None, "band_join_px": None, "poor_one": False}
SEVENTH_OFF = {"texture_gain": None, "texture_poor": None}
NINTH_OFF = {"split_far_poor_px": None}
ELEVENTH_OFF = {"threshold_low": None}
BEFORE = ({"silhouette_score": 0.9, "outline_alone": False, "silhouette_behind_px": 3.0, "floor_agreed": False,
           "band_cut": False, "firm_outline": None, **SIXTH_OFF},
          {"join": False, "split": False, "keep_apart": False, "split_far_px": None, "split_step_px": 2.0,
           "split_placed": False, "join_weak": False, "link_score": None, **SEVENTH_OFF, **NINTH_OFF,
           **ELEVENTH_OFF})
RULES = {"silhouette_score": 0.8, "outline_alone": True, "silhouette_behind_px": 3.0, "floor_agreed": False,
         "band_cut": False, "firm_outline": None, **SIXTH_OFF}
BLOBS = {"join": True, "split": True, "keep_apart": False, "split_far_px": None, "split_step_px": 2.0,
         "split_placed": False, "join_weak": False, "link_score": None, **SEVENTH_OFF, **NINTH_OFF, **ELEVENTH_OFF}
VARIANTS = {
    "before": BEFORE,
    "rules": (RULES, BLOBS),
    "apart": (RULES, {**BLOBS, "keep_apart": True}),
    "behind": ({**RULES, "silhouette_behind_px": 1.0}, BLOBS),
    "apart+behind": ({**RULES, "silhouette_behind_px": 1.0}, {**BLOBS, "keep_apart": True}),
    "apart+behind0": ({**RULES, "silhouette_behind_px": 0.0}, {**BLOBS, "keep_apart": True}),
}
_NOW = VARIANTS["apart+behind0"]
FAR = {"split_far_px": 5.0, "split_far_score": 0.94}
VARIANTS.update({
    "far": (_NOW[0], {**_NOW[1], **FAR}),
    "floor": ({**_NOW[0], "floor_agreed": True}, _NOW[1]),
    "far+floor": ({**_NOW[0], "floor_agreed": True}, {**_NOW[1], **FAR}),
})
_NOW = VARIANTS["far+floor"]
CUT = {"split_step_px": 3.0, "split_placed": True}
VARIANTS.update({
    "cut": (_NOW[0], {**_NOW[1], **CUT}),
    "weak": (_NOW[0], {**_NOW[1], "join_weak": True}),
    "cut+weak": (_NOW[0], {**_NOW[1], **CUT, "join_weak": True}),
})
_NOW = VARIANTS["cut+weak"]
VARIANTS.update({
    "band": ({**_NOW[0], "band_cut": True}, _NOW[1]),
    "firm": ({**_NOW[0], "firm_outline": 0.98}, _NOW[1]),
    "band+firm": ({**_NOW[0], "band_cut": True, "firm_outline": 0.98}, _NOW[1]),
})
_NOW = VARIANTS["band+firm"]
SIXTH = {"band_one_piece": 0.97, "band_join_px": 1.0, "poor_one": True}
VARIANTS.update({
    "link": (_NOW[0], {**_NOW[1], "link_score": 0.9}),
    "one": ({**_NOW[0], "band_one_piece": 0.97}, _NOW[1]),
    "join": ({**_NOW[0], "band_join_px": 1.0}, _NOW[1]),
    "poor": ({**_NOW[0], "poor_one": True}, _NOW[1]),
    "link+one+join": ({**_NOW[0], "band_one_piece": 0.97, "band_join_px": 1.0}, {**_NOW[1], "link_score": 0.9}),
    "sixth": ({**_NOW[0], **SIXTH}, {**_NOW[1], "link_score": 0.9}),
})
_NOW = VARIANTS["sixth"]
VARIANTS.update({
    "seventh": (_NOW[0], {**_NOW[1], "texture_gain": 0.09, "texture_poor": 0.9}),
    "eighth": ({**_NOW[0], "firm_outline": 0.95}, _NOW[1]),
})
_NOW = VARIANTS["eighth"]
VARIANTS.update({
    "ninth": (_NOW[0], {**_NOW[1], "split_far_poor_px": 8.0}),
})
_NOW = VARIANTS["ninth"]
VARIANTS.update({
    "eleventh": (_NOW[0], {**_NOW[1], "threshold_low": 5.0, "by_region": False}),
})
VARIANTS.update({
    "twelfth": (_NOW[0], {**_NOW[1], "threshold_low": 5.0, "by_region": True}),
})
"""``--variants``: as DepthConfig fields and silhouettes options.  "before" is the defaults up to
docs/experiments/2026-11-26-depth-unseen-2.md, "rules" the rules of
docs/experiments/2026-11-25-depth-unseen.md, "apart" and "behind" the rules with the join's test of
both parts at once and with no match counted more than 1 px (0 px) behind its outline;
"apart+behind0" was the defaults from docs/experiments/2026-11-26-depth-unseen-2.md on.  "far", "floor"
and "far+floor" add to "apart+behind0" the cut
of a blob that two shifts 5 px or more apart lay better than one (``silhouettes(split_far_px=5,
split_far_score=0.94)``) and the background floor of agreeing matches only
(``DepthConfig.floor_agreed``): docs/experiments/2026-11-26-depth-unseen-3.md; "far+floor" is the
defaults from then to the fourth study.  "cut", "weak" and "cut+weak" add to "far+floor" a cut
only of parts whose shifts differ by 3 px or more and that, both moved at once, lay no worse than one shift
(``split_step_px=3, split_placed=True``), and the join of two neighbours neither of which fits
well (``join_weak=True``): docs/experiments/2026-11-26-depth-unseen-4.md; "cut+weak" is the defaults
from then to the fifth study.  "band", "firm" and "band+firm" add to "cut+weak" the cut of a blob of
two pieces whose features agree on two disparities (``DepthConfig.band_cut``) and an outline that
fits with a Dice of 0.98 or more standing in front of the background whatever its matches say
(``DepthConfig.firm_outline``): docs/experiments/2026-11-26-depth-unseen-5.md; "band+firm" is the
defaults from then to the sixth study.  "link", "one", "join" and "poor" add to "band+firm" the link of
outline pieces a pixel apart only when one fits poorly (``silhouettes(link_score=0.9)``), the band cut
of a blob of one piece (``DepthConfig.band_one_piece``), the join of neighbouring objects whose
features agree (``DepthConfig.band_join_px``) and one object per poorly fitting blob
(``DepthConfig.poor_one``); "link+one+join" the first three, "sixth" all four:
docs/experiments/2026-11-26-depth-unseen-6.md; "sixth" was the defaults from then to the eighth
study.  "seventh" adds to "sixth" the texture inside each blob (census costs per column): a cut
where it steps and a poorly fitting outline moved to the shift its texture and outline agree on
(``pair_silhouettes(texture_gain=0.09, texture_poor=0.9)``, ``ismb_lab.texture.textured``):
docs/experiments/2026-11-26-depth-unseen-7.md; it was the defaults for its held-out draw only.
"eighth" is "sixth" with a firm outline from a Dice of 0.95 (``DepthConfig(firm_outline=0.95)``):
docs/experiments/2026-11-26-depth-unseen-8.md, the defaults to the ninth study.  "ninth" adds to
"eighth" the cut of a blob that one shift fits only fairly (Dice 0.9-0.94) when two shifts 8 px or
more apart lay its parts with 0.94 or more (``silhouettes(split_far_poor_px=8.0)``):
docs/experiments/2026-11-26-depth-unseen-9.md.
"eleventh" adds to "ninth" changed pixels above 5 grey levels that connect to ones above 8 (hysteresis,
``silhouettes(threshold_low=5.0)``): docs/experiments/2026-11-26-depth-unseen-11.md.  "twelfth" makes the
blobs of "ninth" and of "eleventh" and keeps, region by region, those that fit better on average
(``silhouettes(threshold_low=5.0, by_region=True)``): docs/experiments/2026-11-26-depth-unseen-12.md;
"ninth" was the defaults from the ninth study to the twelfth, "twelfth" since."""


def run_variants(seed: int, n: int, names, variants: dict, **kw):
    """:func:`run_layout` for every variant, matching both pairs once (the matches do not depend on
    the tolerances or the blobs): ``{name: (result, verdict)}`` and the layout."""
    layout = layout_of(seed, n, names)
    prepared = depth_pairs(layout.background, layout.scene, layout_match_config(layout))
    out, first, found = {}, None, {}
    for name, (fields, blobs) in variants.items():
        config = DepthConfig(**fields)
        key = tuple(sorted(blobs.items()))
        if key not in found:        # variants with the same blob options share the blobs
            found[key] = pair_silhouettes(prepared, **blobs)
        grouped = found[key]
        if first is None:
            first = result = relative_depth(layout.background, layout.scene, prepared=prepared, config=config,
                                            silhouettes=grouped, **kw)
        else:
            result = depth_from_matches(first.background, first.scene, config, grouped)
        out[name] = (result, verdict(layout, result))
    return layout, out


def check_blobs(blobs: dict) -> None:
    """Raise what the silhouettes (and the texture, for ``texture_*``) raise for `blobs`: asked on a blank
    16 x 16 pair, so that a value out of range is refused before any layout is matched."""
    blank = load_pair(np.zeros((16, 16)), np.zeros((16, 16)))
    options = {k: v for k, v in blobs.items() if not k.startswith("texture_")}
    found = silhouettes(blank, blank, "full", shifts=[0], **options)
    textured(found, blank, gain=blobs.get("texture_gain"), poor=blobs.get("texture_poor"))


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
    parser.add_argument("--variants", nargs="?", const=",".join(VARIANTS), default=None, metavar="NAME,...",
                        help=f"score every variant of VARIANTS ({', '.join(VARIANTS)}), or those named, "
                        "on the same matches")
    parser.add_argument("--blobs", action="append", default=[], metavar="OPTION=VALUE",
                        help="an option of ismb_lab.silhouettes.silhouettes for a variant, e.g. --blobs split=False")
    parser.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                        help="a DepthConfig field for a variant, e.g. --set min_features=3")
    args = parser.parse_args(argv)
    fields = {f.name: f.type for f in dataclasses.fields(DepthConfig)}
    overrides = {}
    for item in args.set:
        name, _, value = item.partition("=")
        if name not in fields:
            parser.error(f"--set {item}: no DepthConfig field {name!r}")
        kind = str(fields[name])
        if value == "None" and "None" in kind:
            overrides[name] = None
        elif kind == "bool":
            if value not in ("True", "False"):
                parser.error(f"--set {item}: {name} takes True or False")
            overrides[name] = value == "True"
        else:
            try:
                overrides[name] = {"int": int, "str": str}.get(kind, float)(value)
            except ValueError:
                parser.error(f"--set {item}: {name} takes {kind}")
    try:
        config = DepthConfig(**overrides)
    except (ValueError, TypeError) as error:
        parser.error(f"--set {', '.join(args.set)}: {error}")
    blobs = {}
    flags = ("join", "split", "keep_apart", "split_placed", "join_weak", "by_region")
    numbers = ("split_score", "split_step_px", "split_far_score")
    optional = ("split_far_px", "split_far_poor_px", "link_score", "threshold_low", "texture_gain",
                "texture_poor")
    for item in args.blobs:
        name, _, value = item.partition("=")
        if name not in (*flags, *numbers, *optional):
            parser.error(f"--blobs {item}: not one of {', '.join((*flags, *numbers, *optional))}")
        if name in flags:
            if value not in ("True", "False"):
                parser.error(f"--blobs {item}: {name} takes True or False")
            blobs[name] = value == "True"
        elif name in optional and value == "None":
            blobs[name] = None
        else:
            try:
                blobs[name] = float(value)
            except ValueError:
                parser.error(f"--blobs {item}: {name} takes a number" + (" or None" if name in optional else ""))
    try:
        check_blobs(blobs)
    except (ValueError, TypeError) as error:
        parser.error(f"--blobs {', '.join(args.blobs)}: {error}")
    names = families() if args.families is None else tuple(args.families.split(","))
    if UNSEEN.name in names and UNSEEN.name not in families():
        register_family(UNSEEN)
    for name in names:
        if name not in families():
            parser.error(f"--families {args.families}: no family {name!r} (registered: {', '.join(families())})")
    if args.cli and (set(overrides) - {"grouping"} or blobs or args.variants):
        parser.error("--cli takes no --variants, no --blobs and no --set but grouping=...")
    if args.variants and (overrides or blobs):
        parser.error("--variants takes no --set and no --blobs")
    label = ", ".join(args.set + args.blobs) or "defaults"
    if args.variants:
        for name in args.variants.split(","):
            if name not in VARIANTS:
                parser.error(f"--variants {args.variants}: no variant {name!r} (known: {', '.join(VARIANTS)})")
    variants = ({name: VARIANTS[name] for name in args.variants.split(",")} if args.variants
                else {label: (overrides, blobs)})
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
            outcome = {label: (result, what)}
        elif args.variants:
            layout, outcome = run_variants(start + n, n, names, variants, method=args.method, solver=args.solver)
        else:
            layout, result, what = run_layout(start + n, n, names, blobs, config=config, method=args.method,
                                              solver=args.solver)
            outcome = {label: (result, what)}
        for variant, (result, what) in outcome.items():
            for key in ("all", layout.family, f"{len(layout.objects)} objects"):
                by[variant, key][0] += what == "ok"
                by[variant, key][1] += 1
                kinds_by[variant, key][what] += 1
            if what != "ok":
                failures.append((variant, start + n, layout, result, what))
    elapsed = time.perf_counter() - t0
    split = "held-out" if args.held_out else "development"
    folder.cleanup()
    print(f"{split} split, seeds {start}..{start + args.count - 1}, Method-{args.method}, {args.solver}"
          + (", through ismb-lab depth" if args.cli else "") + f": {elapsed:.0f} s "
          f"({elapsed / max(args.count, 1):.2f} s per layout)")
    for variant in variants:
        print(f" {variant}:")
        for key in ("all", *names, "2 objects", "3 objects"):
            if (variant, key) in by:
                ok, total = by[variant, key]
                wrong = ", ".join(f"{k} {v}" for k, v in sorted(kinds_by[variant, key].items()) if k != "ok")
                print(f"  {key:<12} {ok:>4} / {total:<4} ranked correctly ({100 * ok / total:.1f}%)"
                      + (f"; {wrong}" if wrong else ""))
    if not args.quiet:
        for variant, seed, layout, result, what in failures:
            print(f"{variant}: seed {seed} {layout.family} {what}: {describe(layout, result)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
