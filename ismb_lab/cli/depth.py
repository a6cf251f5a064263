"""``ismb-lab depth``: rank the objects added to a background by depth (§5.2.3)."""

from __future__ import annotations

import math
from pathlib import Path

from .._core.files import atomic_write_text
from .._core.validation import ParameterError
from ..depth.objects import GROUPINGS, DepthConfig
from ..depth.pipeline import DEPTH_MATCH_CONFIG, DEPTH_METHOD, DEPTH_PARAMS, DEPTH_SOLVER
from ._common import (UsageError, add_matching_options, add_solver_option, match_config, matched_files,
                      resolve_recipe, seed_setting, window_record, write_ply)
from ._guard import Files, add_force_option, json_text, output_path, save_plot

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """Add the ``depth`` command: rank the objects added to a background pair by depth (§5.2.3)."""
    dp = sub.add_parser("depth", help="rank the objects added to a background by depth (§5.2.3)",
                        description="Match a background pair and a scene pair of the same view, "
                        "remove the scene's background features and rank the objects left "
                        "near -> far, with metric depth Z = f B / d. An object is a blob where the "
                        "scene's left image differs from the background's, at the shift that lays it "
                        "on the right image's blob, refined by the features that agree "
                        "(--grouping features: the features alone, as the thesis). Defaults: Method-III with "
                        "the parameters fitted on images/lab (scripts/fit_depth_params.py) and "
                        f"{DEPTH_MATCH_CONFIG.n_min} to {DEPTH_MATCH_CONFIG.n_max} corners per image; "
                        "the scene's corners are sought in the part of the ROI where its left image "
                        "differs from the background's.")
    for name in ("bg_left", "bg_right", "scene_left", "scene_right"):
        dp.add_argument(name, type=Path, help=name.replace("_", " ") + " image file")
    add_matching_options(dp, DEPTH_MATCH_CONFIG)
    add_solver_option(dp, f"the params file's, else {DEPTH_SOLVER}")
    calibration = DepthConfig()
    dp.add_argument("--focal-px", type=float, default=None, metavar="F",
                    help=f"focal length in pixels (default: {calibration.focal_px:g}, the rendered rig's)")
    dp.add_argument("--baseline-m", type=float, default=None, metavar="B",
                    help=f"baseline in metres (default: {calibration.baseline_m:g}, the thesis' rig)")
    dp.add_argument("--rig", type=Path, default=None, metavar="RIG.json",
                    help="take F and B from a rig calibrated with 'ismb-lab calibrate' (the pairs must "
                    "be rectified with it: 'ismb-lab rectify --rig'); the candidate window is then measured on "
                    "the background pair along its rows, or the command refuses")
    dp.add_argument("--grouping", choices=GROUPINGS, default=calibration.grouping,
                    help="find the objects by their blobs of change in both images, each at the shift "
                    "that lays the left blob on the right one, refined by the features on it "
                    "(silhouettes, the default), or by the features alone as the thesis does (features)")
    dp.add_argument("--ply", type=output_path, default=None, metavar="OUT.ply",
                    help="write the scene's kept matches as a PLY point cloud in metres (the rig's rectified "
                    "left camera, or a pinhole camera of F and B centred on the image; X right, Y down, "
                    "Z forward), grey from the scene's left image")
    dp.add_argument("--json", type=output_path, default=None, metavar="OUT", help="write the objects as JSON")
    dp.add_argument("--plot", type=output_path, default=None, metavar="OUT.png",
                    help="draw the scene's features by disparity with the ranked objects")
    add_force_option(dp)
    dp.set_defaults(run=run, declare_files=files, limit_defaults=limit_defaults, compiles=True)


def limit_defaults() -> dict:
    """The defaults of depth's limited options."""
    return {"n_max": DEPTH_MATCH_CONFIG.n_max}


def files(args) -> Files:
    """The four images, the params file and the rig read; the JSON, the plot and the PLY written."""
    return matched_files(args, ((name.replace("_", "-"), getattr(args, name))
                                for name in ("bg_left", "bg_right", "scene_left", "scene_right")))


def run(args) -> int:
    """Match the background and scene pairs and print the objects near to far;
    returns the exit code."""
    from ..depth.pipeline import relative_depth

    calibration = {}
    if args.rig is not None:
        from .._core.files import check_input
        from ..cameras.camera import load_camera

        if args.focal_px is not None or args.baseline_m is not None:
            raise UsageError("--rig gives the focal length and the baseline: leave out --focal-px and --baseline-m")
        rig = load_camera(check_input(args.rig, what="--rig"))
        from ..images.io import load_image

        shape = load_image(args.bg_left).shape
        if (shape[1], shape[0]) != tuple(rig.size):
            raise UsageError(f"--rig {str(args.rig)!r} was calibrated at {rig.size[0]}x{rig.size[1]}, the images are "
                             f"{shape[1]}x{shape[0]}: its focal length in pixels does not apply (rectify the "
                             "pairs with 'ismb-lab rectify --rig' first)")
        calibration = {"focal_px": rig.focal_px, "baseline_m": rig.baseline_m}
        if args.shift is not None and args.shift != "auto":
            raise UsageError("--rig measures the disparity window from the background pair: leave out --shift "
                             "(or give --shift auto)")
        args.shift = "auto"
    for name in ("focal_px", "baseline_m"):
        value = getattr(args, name)
        if value is not None:
            if not value > 0 or math.isinf(value):
                raise UsageError(f"--{name.replace('_', '-')} must be a finite number > 0, got {value:g}")
            calibration[name] = value
    recipe = resolve_recipe(args, DEPTH_SOLVER, defaults={DEPTH_METHOD: DEPTH_PARAMS})
    method = recipe.method.name
    config = match_config(args, DEPTH_MATCH_CONFIG)
    if config.shift == "auto":
        from ..images.io import load_pair
        from ..matching.pipeline import auto_window

        background = load_pair(args.bg_left, args.bg_right)
        if args.rig is not None:
            from ..matching.metric import rig_config

            try:
                config = rig_config(rig, config, background)
            except ParameterError as exc:
                raise UsageError(f"--rig: the background pair gives no disparity range to set the window by "
                                 f"({exc}); is it a rectified pair of this rig ('ismb-lab rectify --rig')?") from None
        else:
            config = auto_window(background, config)
        print(f"candidate window measured on the background pair: shift {config.shift:g} px, "
              f"{config.window_width:g} x {config.window_height:g} px")
    result = relative_depth((args.bg_left, args.bg_right), (args.scene_left, args.scene_right),
                            match_config=config, config=DepthConfig(grouping=args.grouping, **calibration),
                            **recipe.match_settings(), **seed_setting(args))
    for what, res in (("background", result.background), ("scene", result.scene)):
        if not len(res.pairs):
            why = f"no matches in the {what} pair" + (f": {res.message}" if res.message else "")
            if what == "scene" or result.silhouettes is None:
                raise UsageError(why)
            # A plain wall has no corners: nothing to remove, the blobs of change still find the objects.
            print(f"note: {why}; no scene feature is removed as background")
    after = ", one match per corner" if recipe.one_to_one else ""
    print(f"Method-{method} ({result.scene.solver}{after}): {len(result.background.pairs)} background matches, "
          f"{len(result.scene.pairs)} scene matches; {result.background_removed} scene features "
          "removed as background")
    if not result.objects:
        print(result.message or "no objects")
    for obj in result.objects:
        x, y = obj.centroid_xy
        if obj.depth_m is None:
            depth = obj.depth.status
        else:
            far = "inf" if obj.depth.far == float("inf") else f"{obj.depth.far:.3f}"
            depth = f"{obj.depth_m:.3f} m ({obj.depth.near:.3f}-{far})"
        outline = "" if obj.silhouette_disparity is None else f", outline {obj.silhouette_disparity:.0f} px"
        print(f"#{obj.rank}  at ({x:.0f}, {y:.0f})  disparity {obj.mean_disparity:.2f} px  "
              f"depth {depth}  {len(obj.features)} features{outline}")
    if args.json is not None:
        atomic_write_text(args.json, json_text({**result.to_dict(),
                                                "candidate_window": window_record(config, args.shift == "auto")}))
    if args.ply is not None:
        _ply(args, result, rig if args.rig is not None else None)
    if args.plot is not None:
        from ..images.io import load_pair
        from ..plotting import plot_depth

        left = load_pair(args.scene_left, args.scene_right).left
        save_plot(args.plot, (6, 4.5), lambda ax: plot_depth(ax, left, result),
                  f"Method-{method}: {len(result.objects)} objects, near -> far")
    return 0


def _ply(args, result, rig) -> None:
    """Write the scene's kept matches as a PLY cloud: through `rig`, or the pinhole camera of the
    result's focal length and baseline at the scene's image centre."""
    from ..cameras.camera import StereoCamera
    from ..images.io import load_image

    left = load_image(args.scene_left)
    h, w = left.shape
    camera = rig if rig is not None else StereoCamera.pinhole(w, h, focal_px=result.config.focal_px,
                                                              baseline_m=result.config.baseline_m)
    write_ply(args.ply, result.points(camera), result.kept_xy, left, camera,
              "ismb-lab depth: the scene's kept matches, ")
