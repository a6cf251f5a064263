"""The ``ismb-lab`` command line.

Every error the user can cause prints one line on stderr and exits with code 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from . import __version__
from ._files import atomic_write_text
from ._validation import ParameterError, ParameterTypeError
from .methods import METHOD_NAMES, THESIS_PARAMS, Params

PARAM_OPTIONS = ("theta_c", "theta_s", "lambda_c", "lambda_s", "match_bias")


class UsageError(Exception):
    """A mistake in the command line or its files, reported in one line."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line instead of argparse's usage dump
        raise UsageError(f"{message} (see '{self.prog} --help')")


def _add_matching_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--method", choices=METHOD_NAMES, default=None,
                   help="energy recipe (default: the params file's, else III)")
    for name in PARAM_OPTIONS:
        p.add_argument("--" + name.replace("_", "-"), type=float, default=None, metavar="X",
                       help=f"override {name} (thesis default for the method)")
    p.add_argument("--params-file", type=Path, default=None, metavar="P.json",
                   help='parameters as {"method": ..., "params": {...}}, e.g. from ismb-lab tune')
    _add_feature_options(p)
    p.add_argument("--seed", type=int, default=0, help="seed of the update order (default: 0)")
    p.add_argument("--stop-rule", choices=("sweep", "stall"), default="sweep",
                   help="sweep: a full sweep without change (default); stall: 200 idle attempts")
    p.add_argument("--rule", choices=("exact", "thesis"), default="exact",
                   help="exact Hopfield weights (default) or the thesis' literal (3-17)/(3-20)")


def _add_feature_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--roi", default="center", help="center | full | X,Y,W,H (default: center)")
    p.add_argument("--shift", type=float, default=20.0, metavar="PX",
                   help="expected disparity: centre of the candidate window (default: 20)")
    p.add_argument("--n-min", type=int, default=20, help="fewest corners per image (default: %(default)s)")
    p.add_argument("--n-max", type=int, default=30, help="most corners per image (default: %(default)s)")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="ismb-lab", description="Hopfield-network stereo matching of Harris "
                     "corners (the ISMB thesis) from the command line.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    m = sub.add_parser("match", help="match the corners of a stereo pair and print Table 5.3",
                       description="Match the Harris corners of LEFT and RIGHT and print the "
                       "matches in the shape of the thesis' Table 5.3.")
    m.add_argument("left", type=Path, help="left image file")
    m.add_argument("right", type=Path, help="right image file")
    _add_matching_options(m)
    m.add_argument("--json", type=Path, default=None, metavar="OUT", help="write the result as JSON")
    m.add_argument("--plot", type=Path, default=None, metavar="OUT.png",
                   help="draw the pair with features and match lines")
    m.set_defaults(run=_cmd_match)
    t = sub.add_parser("tune", help="fit the parameters to target pairs with the GA (ch. 4)",
                       description="Fit a method's parameters to the target pairs of one image pair "
                       "with the real-coded GA, and write them for 'ismb-lab match --params-file'. "
                       "Ctrl-C stops early and still writes the best parameters so far.")
    t.add_argument("left", type=Path, help="left image file")
    t.add_argument("right", type=Path, help="right image file")
    t.add_argument("targets", type=Path, help="target pairs (JSON, as saved by the labeller)")
    t.add_argument("--method", choices=METHOD_NAMES, default="III", help="energy recipe (default: III)")
    t.add_argument("--generations", type=int, default=500, help="most generations (default: 500)")
    t.add_argument("--population", type=int, default=30, help="chromosomes (default: 30)")
    t.add_argument("--seed", type=int, default=0, help="seed of the GA (default: 0)")
    _add_feature_options(t)
    t.add_argument("--out", type=Path, default=Path("params.json"), metavar="PARAMS.json",
                   help="where to write the parameters (default: params.json)")
    t.set_defaults(run=_cmd_tune)
    e = sub.add_parser("evaluate", help="train on one pair, test on the others (Fig. 5.10)",
                       description="Run the thesis' train/test protocol over the pairs of a "
                       "manifest, with every network figure over several update-order seeds.")
    e.add_argument("manifest", type=Path, help='JSON: {"pairs": [{"left", "right", "targets", '
                   '"roi", "shift"} or {"source": "middlebury-motorcycle", "roi"}, ...]}')
    e.add_argument("--method", choices=METHOD_NAMES, default="III", help="energy recipe (default: III)")
    e.add_argument("--train", type=int, default=0, metavar="INDEX",
                   help="the pair whose GA parameters are tested on the others (default: 0)")
    e.add_argument("--seeds", type=int, default=5, help="update-order seeds per figure (default: 5)")
    e.add_argument("--generations", type=int, default=500, help="GA generations (default: 500)")
    e.add_argument("--peers", action="store_true", help="also score the peer matchers")
    e.add_argument("--solvers", nargs="*", choices=("anneal", "exact"), default=(),
                   help="also solve the tested energies by mean-field annealing and/or exactly (MILP)")
    e.add_argument("--fit-solver", choices=("network", "anneal", "exact"), default="network",
                   help="how the GA solves each network while fitting (default: network)")
    e.add_argument("--fit-seeds", type=int, default=1, metavar="N",
                   help="update-order seeds averaged in each GA fitness (default: 1)")
    e.add_argument("--ga-seed", type=int, default=0, metavar="N",
                   help="seed of the GA (default: 0); a small training pair can leave the GA on "
                   "a plateau, so compare a few")
    e.add_argument("--held-out-only", action="store_true",
                   help="fit only the training pair (the held-out figures are the same; the other "
                   "rows' 'Training' column is skipped)")
    e.add_argument("--json", type=Path, default=None, metavar="OUT", help="write the report as JSON")
    e.set_defaults(run=_cmd_evaluate)
    dp = sub.add_parser("depth", help="rank the objects added to a background by depth (§5.2.3)",
                        description="Match a background pair and a scene pair of the same view, "
                        "remove the scene's background features and rank the objects left "
                        "near -> far, with metric depth Z = f B / d. Defaults: Method-III with "
                        "the parameters fitted on images/lab (scripts/fit_depth_params.py) and "
                        "40 to 60 corners per image; the scene's corners are sought in the part of "
                        "the ROI where its left image differs from the background's.")
    for name in ("bg_left", "bg_right", "scene_left", "scene_right"):
        dp.add_argument(name, type=Path, help=name.replace("_", " ") + " image file")
    _add_matching_options(dp)
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
    dp.set_defaults(run=_cmd_depth, n_min=40, n_max=60)   # ismb_lab.depth.DEPTH_MATCH_CONFIG
    r = sub.add_parser("render", help="render the project's stereo pairs into images/",
                       description="Render the project's synthetic stereo pairs with their ground "
                       "truth. The output is byte for byte what is committed in images/.")
    r.add_argument("--out", type=Path, default=Path("images"), help="folder (default: images)")
    r.set_defaults(run=_cmd_render)
    return parser


def read_params_file(path: Path) -> tuple[str | None, dict]:
    """Read ``{"method": ..., "params": {...}}``; extra keys are allowed."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UsageError(f"--params-file {path}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UsageError(f"--params-file {path}: not a readable JSON file ({exc})") from None
    if not isinstance(data, dict) or not isinstance(data.get("params"), dict):
        raise UsageError(f"--params-file {path}: expected an object with a 'params' object")
    method = data.get("method")
    if method is not None and method not in METHOD_NAMES:
        raise UsageError(f"--params-file {path}: unknown method {method!r} "
                         f"(expected one of {', '.join(METHOD_NAMES)})")
    return method, data["params"]


def resolve_params(args) -> tuple[str, Params]:
    """The method and parameters from --method, --params-file and the single overrides."""
    file_method, values = (None, {})
    if args.params_file is not None:
        file_method, values = read_params_file(args.params_file)
    if args.method and file_method and args.method != file_method:
        raise UsageError(f"--method {args.method} conflicts with --params-file, "
                         f"which holds parameters for Method-{file_method}")
    method = args.method or file_method or "III"
    merged = THESIS_PARAMS[method].to_dict()
    merged.update(values)
    merged.update({k: getattr(args, k) for k in PARAM_OPTIONS if getattr(args, k) is not None})
    return method, Params.from_dict(merged, owner="ismb-lab")


def _progress(total: int, desc: str):
    from tqdm import tqdm
    return tqdm(total=total, desc=desc, unit="gen", file=sys.stderr, dynamic_ncols=True,
                disable=None)


def _cmd_tune(args) -> int:
    from .matching import prepare
    from .targets import load_targets, snap
    from .tuning import Case, evaluate, to_params, tune

    prepared = prepare(args.left, args.right, _config(args))
    targets = load_targets(args.targets, pair=prepared.pair)
    snapped = snap(targets, prepared.problem.left_xy, prepared.problem.right_xy)
    missing = sorted(set(snapped.missing_left.tolist()) | set(snapped.missing_right.tolist()))
    if missing:
        print(f"ismb-lab: note: {len(missing)} of {len(targets)} targets have no corner within "
              f"1.5 px and are left out: {', '.join(f'#{n + 1}' for n in missing)}", file=sys.stderr)
    if len(snapped.pairs) == 0:
        raise UsageError(f"{args.targets}: no target pair lies on the corners found "
                         f"({len(targets)} targets, {len(prepared.problem.left_xy)} left corners)")
    case = Case(prepared, snapped.pairs, name=str(args.left))
    records = tune([case], args.method, rng=args.seed, population=args.population,
                   generations=args.generations)
    best, interrupted = None, False
    with _progress(args.generations + 1, f"Method-{args.method} GA") as bar:
        try:
            for best in records:
                bar.update(1)
                bar.set_postfix(best=f"{best.best:g}", mean=f"{best.mean:.2f}", target=len(case.targets))
        except KeyboardInterrupt:
            interrupted = True
    if best is None:
        raise KeyboardInterrupt
    params = to_params(args.method, best.best_chromosome)
    out = {"method": args.method, "params": params.to_dict(), "fitness": best.best,
           "generations": best.index, "seed": args.seed, "targets": len(case.targets),
           "interrupted": interrupted}
    atomic_write_text(args.out, json.dumps(out, indent=2) + "\n")
    result = evaluate([case], args.method, params)
    print(f"Method-{args.method}: best fitness {best.best:g} of {len(case.targets)} after "
          f"{best.index} generations; C/E/T {result}; parameters {params.to_dict()}")
    print(f"written to {args.out}")
    if interrupted:
        print("ismb-lab: interrupted; the best parameters so far were written", file=sys.stderr)
        return 130
    return 0


def _cmd_evaluate(args) -> int:
    from .evaluation import format_protocol, load_manifest, protocol

    if args.ga_seed < 0:
        raise UsageError(f"--ga-seed must be an integer >= 0, got {args.ga_seed}")
    cases = load_manifest(args.manifest)
    bars = {}

    def progress(name, record):
        if name not in bars:
            for bar in bars.values():
                bar.close()
            bars[name] = _progress(args.generations + 1, f"GA on {name}")
        bars[name].update(1)
        bars[name].set_postfix(best=f"{record.best:g}", mean=f"{record.mean:.2f}")

    try:
        report = protocol(cases, args.method, train=args.train, seeds=args.seeds,
                          generations=args.generations, peers=args.peers, progress=progress,
                          solvers=tuple(args.solvers), fit_solver=args.fit_solver,
                          fit_seeds=args.fit_seeds, rng=args.ga_seed, fit_all=not args.held_out_only)
    finally:
        for bar in bars.values():
            bar.close()
    print(format_protocol(report))
    if args.json is not None:
        data = {"method": report["method"], "train": report["train"],
                "params": report["params"].to_dict(), "seeds": args.seeds, "ga_seed": args.ga_seed,
                "pairs": [{"name": r["name"], "testing": [str(s) for s in r["testing"]],
                           "training": None if r["training"] is None else [str(s) for s in r["training"]]}
                          for r in report["rows"]],
                "held_out": [{"cet": str(s), "recall": s.recall, "precision": s.precision}
                             for s in report["held_out"]],
                "peers": {name: {"held_out": str(p["held_out"]), "recall": p["held_out"].recall,
                                 "precision": p["held_out"].precision} for name, p in report["peers"].items()},
                "solvers": {name: [{"cet": str(s), "recall": s.recall, "precision": s.precision}
                                   for s in v["held_out"]] for name, v in report.get("solvers", {}).items()}}
        atomic_write_text(args.json, json.dumps(data, indent=2) + "\n")
    return 0


def _config(args):
    from .matching import MatchConfig
    return MatchConfig(roi=args.roi, shift=args.shift, n_min=args.n_min, n_max=args.n_max)


def _cmd_match(args) -> int:
    from .matching import match, prepare

    method, params = resolve_params(args)
    prepared = prepare(args.left, args.right, _config(args))
    result = match(method=method, params=params, seed=args.seed, stop_rule=args.stop_rule,
                   rule=args.rule, prepared=prepared)
    print(f"Method-{result.method}  params {params.to_dict()}  seed {result.seed}")
    print(f"{len(result.left_xy)} left / {len(result.right_xy)} right corners, "
          f"{result.n_candidates} candidate neurons, {len(result.pairs)} matches, "
          f"energy {result.energy:.4f}, stopped by '{result.stop_rule}' "
          f"after {result.attempts} attempts")
    print(result.table())
    if args.json is not None:
        atomic_write_text(args.json, result.to_json() + "\n")
    if args.plot is not None:
        from matplotlib.figure import Figure

        from .plotting import plot_matches
        pair = prepared.pair
        fig = Figure(figsize=(10, 4), layout="constrained")
        ax = fig.subplots()
        plot_matches(ax, pair.left, pair.right, result.left_xy, result.right_xy, result.pairs)
        ax.set_title(f"Method-{result.method}: {len(result.pairs)} matches")
        fig.savefig(args.plot, dpi=120)
    return 0


def _cmd_depth(args) -> int:
    from dataclasses import replace

    from .depth import DEPTH_PARAMS, DepthConfig, depth_from_matches, depth_match, scene_match_config
    from .features import resolve_roi
    from .io import load_pair
    from .matching import match, prepare

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
    match_config = _config(args)
    pairs = [load_pair(args.bg_left, args.bg_right), load_pair(args.scene_left, args.scene_right)]
    if pairs[0].shape != pairs[1].shape:
        (h, w), (h2, w2) = pairs[0].shape, pairs[1].shape
        raise UsageError(f"the scene images are {w2}x{h2} but the background images are {w}x{h}: "
                         "both pairs must show the same view at one size")
    configs = match_config, scene_match_config(*pairs, match_config)
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
        atomic_write_text(args.json, json.dumps(result.to_dict(), indent=2) + "\n")
    if args.plot is not None:
        from matplotlib.figure import Figure

        from .plotting import plot_depth
        fig = Figure(figsize=(6, 4.5), layout="constrained")
        ax = fig.subplots()
        plot_depth(ax, pairs[1].left, result)
        ax.set_title(f"Method-{method}: {len(result.objects)} objects, near -> far")
        fig.savefig(args.plot, dpi=120)
    return 0


def _cmd_render(args) -> int:
    from .gallery import render_gallery

    for path in render_gallery(args.out):
        print(path)
    return 0


def main(argv=None) -> int:
    """Entry point of ``ismb-lab``; returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        return args.run(args)
    except UsageError as exc:
        print(f"ismb-lab: error: {exc}", file=sys.stderr)
    except (ParameterError, ParameterTypeError, OSError) as exc:
        print(f"ismb-lab: error: {exc}", file=sys.stderr)
    except KeyboardInterrupt:
        print("ismb-lab: interrupted", file=sys.stderr)
        return 130
    return 2


if __name__ == "__main__":
    sys.exit(main())
