"""``ismb-lab match``: the matches of one pair, shaped like the thesis' Table 5.3."""

from __future__ import annotations

import hashlib
import math
import sys
from pathlib import Path

from .._core.files import atomic_write_text
from .._core.validation import ParameterError
from ..matching.pipeline import MatchConfig
from ..network.solvers import DEFAULT_SOLVER
from ._common import (add_matching_options, add_solver_option, add_solver_settings, match_config, matched_files,
                      resolve_recipe, seed_setting, window_record, write_ply)
from ._guard import Files, UsageError, add_force_option, json_text, limit, output_path, save_plot

__all__ = ["add_parser", "run"]


def add_parser(sub) -> None:
    """Add the ``match`` command: match a pair's corners and print them as the thesis' Table 5.3."""
    m = sub.add_parser("match", help="match the corners of a stereo pair and print Table 5.3",
                       description="Match the Harris corners of LEFT and RIGHT and print the "
                       "matches in the shape of the thesis' Table 5.3.")
    m.add_argument("left", type=Path, help="left image file")
    m.add_argument("right", type=Path, help="right image file")
    add_matching_options(m, MatchConfig())
    add_solver_option(m, f"the params file's, else {DEFAULT_SOLVER}")
    add_solver_settings(m)
    m.add_argument("--rig", type=Path, default=None, metavar="RIG.json",
                   help="a rig from 'ismb-lab calibrate': rectify raw photos with it (a rectified pair is "
                   "matched as it is; stderr says which), refine the corners to sub-pixel, keep the "
                   "candidates on their rows, and give each match its point in metres (xyz_m, the rectified "
                   "left camera's frame: X right, Y down, Z forward); --shift is then auto unless given")
    m.add_argument("--ply", type=output_path, default=None, metavar="OUT.ply",
                   help="with --rig: write the matches' points in metres as a PLY point cloud (x y z, and the "
                   "left image's grey as red green blue), which MeshLab, CloudCompare and Open3D open")
    m.add_argument("--json", type=output_path, default=None, metavar="OUT", help="write the result as JSON")
    m.add_argument("--plot", type=output_path, default=None, metavar="OUT.png",
                   help="draw the pair with features and match lines")
    add_force_option(m)
    m.set_defaults(run=run, declare_files=files, limit_defaults=limit_defaults, compiles=True)


def limit_defaults() -> dict:
    """The defaults of match's limited options."""
    return {"n_max": MatchConfig().n_max}


def files(args) -> Files:
    """The images, the params file and the rig read; the JSON, the plot and the PLY written."""
    return matched_files(args, (("left", args.left), ("right", args.right)))


def _prepared(args):
    """The prepared pair, after refusing a swapped one and warning about an unrectified one."""
    from ..images.io import load_pair
    from ..matching.pipeline import check_window, prepare

    config = match_config(args)
    pair = load_pair(args.left, args.right, min_shape=config.min_shape)
    check_window(config, pair.shape)   # every option before any work on the pair
    warning = _warn_unrectified(pair, pair.left, pair.right, "ismb-lab match")
    try:
        return prepare(pair, None, config)
    except ParameterError as exc:
        if warning and args.shift == "auto":
            raise UsageError(f"{exc} The pair is not rectified: rectify first ('ismb-lab rectify').") from None
        raise


def _warn_unrectified(pair, left, right, who: str) -> str:
    """The warning, said on stderr, if the pair does not look rectified; none for a pair with an
    image of one grey level, which has no corner (and the look for robust matches costs time)."""
    from ..images.rectify import check_for_matching

    flat = any(image.min() == image.max() for image in (pair.left, pair.right))
    warning = "" if flat else check_for_matching(left, right, who)
    if warning:
        print(warning, file=sys.stderr)
    return warning


def _rig_pair(args):
    """The rig, the pair rectified with it (unless it already is) and the match settings."""
    from .._core.files import check_input
    from ..cameras.camera import load_camera
    from ..images.io import load_pair
    from ..matching.pipeline import check_window
    from ..matching.metric import for_camera, photo_config, row_tolerance

    camera = load_camera(check_input(args.rig, what="--rig"))
    if args.shift is None:      # a photo's disparities are the pair's own, not the thesis' 20 px
        args.shift = "auto"
    # corners in proportion to the photo (the thesis' 20-30 are for 320 x 240), within --n-max's limit
    config = match_config(args, photo_config(camera, most=args.n_max if args.n_max is not None else limit("n_max")))
    check_window(config, (camera.size[1], camera.size[0]))   # the rectified pair's size, before the work
    # a rectified camera's rig changes no pixel, but its pair is still checked to fit (rows, order)
    left, right, how = for_camera(args.left, args.right, camera)
    pair = load_pair(left, right, min_shape=config.min_shape)
    print(f"--rig: {how}", file=sys.stderr)
    print(f"--rig: candidates within {row_tolerance(camera, subpixel=True):g} px of their row: "
          + (f"2 x the rig's RMS reprojection error ({camera.rms:.3f} px)" if math.isfinite(camera.rms) else
             "the rig has no measured RMS error (rms_px null, a factory rig), so the band of a camera without "
             "one"), file=sys.stderr)
    _warn_unrectified(pair, left, right, "ismb-lab match --rig")
    return camera, pair, config, how


def rig_record(args, camera, how: str) -> dict:
    """What the JSON says of the rig: its file and SHA-256, f, B, the RMS error, the search band it
    gave, and how the pair was taken."""
    from ..matching.metric import row_tolerance

    return {"path": str(args.rig), "sha256": hashlib.sha256(Path(args.rig).read_bytes()).hexdigest(),
            "focal_px": camera.focal_px, "baseline_m": camera.baseline_m,
            "rms_px": camera.rms if math.isfinite(camera.rms) else None,
            "row_tolerance_px": row_tolerance(camera, subpixel=True), "pair": how}


def run(args) -> int:
    """Match LEFT and RIGHT, print the table and write the optional outputs;
    returns the exit code."""
    from ..matching.pipeline import match

    if args.ply is not None and args.rig is None:
        raise UsageError("--ply writes the matches' points in metres: give the rig with --rig RIG.json "
                         "('ismb-lab calibrate', or 'ismb-lab rig' for a factory-calibrated camera)")
    recipe = resolve_recipe(args, DEFAULT_SOLVER)
    camera = None
    if args.rig is not None:
        from ..matching.metric import match_with_camera

        camera, pair, config, how = _rig_pair(args)
        prepared, found, result = match_with_camera(pair, config, camera, **recipe.match_settings(),
                                                    **seed_setting(args))
        found = len(found.pairs)
    else:
        prepared = _prepared(args)
        result = match(prepared=prepared, **recipe.match_settings(), **seed_setting(args))
    after = ", one match per corner" if result.one_to_one else ""
    print(f"Method-{result.method} ({result.solver}{after})  params {recipe.params.to_dict()}  "
          f"seed {result.seed}")
    print(f"{len(result.left_xy)} left / {len(result.right_xy)} right corners, "
          f"{result.n_candidates} candidate neurons, {len(result.pairs)} matches, "
          f"energy {result.energy:.4f}, stopped by '{result.stop_rule}' "
          f"after {result.attempts} attempts")
    if camera is not None:
        print(f"--rig: {len(result.pairs)} of {found} matches kept, those whose corners are each other's "
              "most similar candidate")
    print(result.table())
    window = window_record(prepared.config, args.shift == "auto")
    if window["auto"]:
        print(f"candidate window measured on the pair: shift {window['shift']:g} px, "
              f"{window['width']:g} x {window['height']:g} px")
    record = {**result.to_dict(), "candidate_window": window}
    # "disparity" is the thesis' Table 5.3 column, the distance between the two corners;
    # "disparity_x_px" is x_left - x_right, the one Z = f B / d takes
    for item, d in zip(record["matches"], result.horizontal_disparity):
        item["disparity_x_px"] = float(d)
    if camera is not None:
        import numpy as np

        from ..matching.metric import match_points

        record["rig"] = rig_record(args, camera, how)
        xyz = match_points(result, camera)
        for item, point in zip(record["matches"], xyz):
            item["xyz_m"] = [float(v) for v in point] if np.all(np.isfinite(point)) else None
        z = xyz[np.isfinite(xyz[:, 2]), 2]
        print(f"--rig: focal length {camera.focal_px:.1f} px, baseline {camera.baseline_m:.4f} m; "
              + (f"{len(z)} matches in metres, depth {z.min():.3f} to {z.max():.3f} m" if len(z) else
                 "no match in front of the cameras"))
    if args.json is not None:
        atomic_write_text(args.json, json_text(record))
    pair = prepared.pair
    if args.ply is not None:
        write_ply(args.ply, xyz, result.left_match_xy, pair.left, camera, "ismb-lab match --rig: ")
    if args.plot is not None:
        from ..plotting import plot_matches

        save_plot(args.plot, (10, 4), lambda ax: plot_matches(ax, pair.left, pair.right, result.left_xy,
                                                              result.right_xy, result.pairs),
                  f"Method-{result.method}: {len(result.pairs)} matches")
    return 0
