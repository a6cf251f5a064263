"""``ismb-lab depth``: rank the objects added to a background by depth (§5.2.3)."""

from __future__ import annotations

from pathlib import Path

from .._files import atomic_write_text
from ..methods import Params
from ._common import PARAM_OPTIONS, UsageError, add_matching_options, match_config, resolve_params
from ._guard import json_text, save_figure


def add_parser(sub) -> None:
    dp = sub.add_parser("depth", help="rank the objects added to a background by depth (§5.2.3)",
                        description="Match a background pair and a scene pair of the same view, "
                        "remove the scene's background features and rank the objects left "
                        "near -> far, with metric depth Z = f B / d. Defaults: Method-III with "
                        "the parameters fitted on images/lab (scripts/fit_depth_params.py) and "
                        "40 to 60 corners per image; the scene's corners are sought in the part of "
                        "the ROI where its left image differs from the background's.")
    for name in ("bg_left", "bg_right", "scene_left", "scene_right"):
        dp.add_argument(name, type=Path, help=name.replace("_", " ") + " image file")
    add_matching_options(dp)
    dp.add_argument("--solver", choices=("anneal", "network"), default="anneal",
                    help="solve each pair's energy by mean-field annealing (default, as the demo "
                    "does) or with the discrete network alone (honours --stop-rule and --rule)")
    dp.add_argument("--focal-px", type=float, default=300.0, metavar="F",
                    help="focal length in pixels (default: 300, the rendered rig's)")
    dp.add_argument("--baseline-m", type=float, default=0.10, metavar="B",
                    help="baseline in metres (default: 0.10, the thesis' rig)")
    dp.add_argument("--json", type=Path, default=None, metavar="OUT", help="write the objects as JSON")
    dp.add_argument("--plot", type=Path, default=None, metavar="OUT.png",
                    help="draw the scene's features by disparity with the ranked objects")
    dp.set_defaults(run=run, n_min=40, n_max=60)   # ismb_lab.depth.DEPTH_MATCH_CONFIG


def run(args) -> int:
    from dataclasses import replace

    from ..depth import DEPTH_PARAMS, DepthConfig, depth_from_matches, depth_match, scene_match_config
    from ..features import resolve_roi
    from ..io import load_pair
    from ..matching import match, prepare

    for name in ("focal_px", "baseline_m"):
        value = getattr(args, name)
        if not value > 0 or value == float("inf"):
            raise UsageError(f"--{name.replace('_', '-')} must be a finite number > 0, got {value:g}")
    config = DepthConfig(focal_px=args.focal_px, baseline_m=args.baseline_m)
    method, params = resolve_params(args)
    if method == "III" and args.params_file is None:
        # The demo's own fit (images/lab) replaces the thesis' values; single options still win.
        values = DEPTH_PARAMS.to_dict()
        values.update({k: getattr(args, k) for k in PARAM_OPTIONS if getattr(args, k) is not None})
        params = Params.from_dict(values, owner="ismb-lab")
    base_config = match_config(args)
    pairs = [load_pair(args.bg_left, args.bg_right), load_pair(args.scene_left, args.scene_right)]
    if pairs[0].shape != pairs[1].shape:
        (h, w), (h2, w2) = pairs[0].shape, pairs[1].shape
        raise UsageError(f"the scene images are {w2}x{h2} but the background images are {w}x{h}: "
                         "both pairs must show the same view at one size")
    configs = base_config, scene_match_config(*pairs, base_config)
    if args.solver == "network":
        results = [match(method=method, params=params, seed=args.seed, stop_rule=args.stop_rule,
                         rule=args.rule, prepared=prepare(p, None, c)) for p, c in zip(pairs, configs)]
    else:
        results = [depth_match(p, method=method, params=params, match_config=c, seed=args.seed,
                               solver=args.solver) for p, c in zip(pairs, configs)]
    for what, res in zip(("background", "scene"), results):
        if not len(res.pairs):
            raise UsageError(f"no matches in the {what} pair" + (f": {res.message}" if res.message else ""))
    result = replace(depth_from_matches(*results, config),
                     scene_roi=resolve_roi(configs[1].roi, pairs[1].shape))
    print(f"Method-{method}: {len(results[0].pairs)} background matches, {len(results[1].pairs)} "
          f"scene matches; {result.background_removed} scene features removed as background")
    if not result.objects:
        print(result.message or "no objects")
    for obj in result.objects:
        x, y = obj.centroid_xy
        if obj.depth_m is None:
            depth = obj.depth.status
        else:
            far = "inf" if obj.depth.far == float("inf") else f"{obj.depth.far:.3f}"
            depth = f"{obj.depth_m:.3f} m ({obj.depth.near:.3f}-{far})"
        print(f"#{obj.rank}  at ({x:.0f}, {y:.0f})  disparity {obj.mean_disparity:.2f} px  "
              f"depth {depth}  {len(obj.features)} features")
    if args.json is not None:
        atomic_write_text(args.json, json_text(result.to_dict()))
    if args.plot is not None:
        from matplotlib.figure import Figure

        from ..plotting import plot_depth
        fig = Figure(figsize=(6, 4.5), layout="constrained")
        ax = fig.subplots()
        plot_depth(ax, pairs[1].left, result)
        ax.set_title(f"Method-{method}: {len(result.objects)} objects, near -> far")
        save_figure(fig, args.plot, dpi=120)
    return 0
