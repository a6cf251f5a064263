"""The default ``match --rig`` on OpenCV's 13 chessboard pairs, each held out in turn.

For each pair, the rig is calibrated on the other 12 (``recalibrate``), and the held-out raw
pair goes the way ``ismb-lab match LEFT RIGHT --rig RIG.json --shift auto --roi full`` takes
it, with no ``--n-min``/``--n-max``: :func:`ismb_lab.matching.metric.for_camera`, then
:func:`ismb_lab.matching.metric.match_with_camera` with the settings the rig gives the photo
(:func:`ismb_lab.matching.metric.photo_config`) and the default recipe.  The matches are scored as
``scripts/board_metres.py`` scores them: those whose left corner lies on the board, and the
share of them within 5% of the board's plane (``solvePnP`` on the raw left image).

Usage::

    python scripts/rig_defaults.py                        # all 13 pairs
    python scripts/rig_defaults.py --pairs 01 05 12       # a development subset
    python scripts/rig_defaults.py --scale 1.5            # corner counts 1.5 times the defaults'
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

from ismb_lab.images.datasets import CHESSBOARD_PAIRS, opencv_samples
from ismb_lab.images.io import load_pair
from ismb_lab.matching.pipeline import MatchConfig
from ismb_lab.network.methods import DEFAULT_METHOD
from ismb_lab.matching.metric import for_camera, match_points, match_with_camera, photo_config
from ismb_lab.matching.recipe import Recipe
from ismb_lab.images.rectify import load_photo
from ismb_lab.cameras.rig import calibrate_rig, recalibrate
from ismb_lab.network.solvers import DEFAULT_SOLVER


def _board_metres():
    spec = importlib.util.spec_from_file_location("board_metres", Path(__file__).with_name("board_metres.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def held_out(full, name: str, data: Path, scale: float = 1.0, **fields) -> dict:
    """One held-out pair the default command's way, scored (`scale` and `fields` change the
    settings :func:`photo_config` gives, for a study)."""
    board = _board_metres()
    camera = recalibrate(full, [name])
    left, right = data / f"left{name}.jpg", data / f"right{name}.jpg"
    base = replace(MatchConfig(), roi="full", shift="auto")
    config = photo_config(camera, base, scale=scale)
    config = replace(config, **fields)
    start = time.perf_counter()
    a, b, how = for_camera(left, right, camera)
    pair = load_pair(a, b, min_shape=config.min_shape)
    recipe = Recipe(DEFAULT_METHOD, None, DEFAULT_SOLVER)
    prepared, found, result = match_with_camera(pair, config, camera, **recipe.match_settings())
    seconds = time.perf_counter() - start
    xyz = match_points(result, camera)
    matches = [{"left_xy": [float(v) for v in p], "xyz_m": [float(v) for v in q] if (q == q).all() else None}
               for p, q in zip(result.left_match_xy, xyz)]
    scored = board.score(camera, load_photo(left), matches)
    return {"pair": name, "n_min": config.n_min, "n_max": config.n_max, "corners": len(result.left_xy),
            "rectified_by_rig": "rectified with the rig" in how, "seconds": round(seconds, 2), **scored}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", nargs="+", default=list(CHESSBOARD_PAIRS), choices=CHESSBOARD_PAIRS,
                        metavar="NN", help="the pairs to hold out (default: all 13)")
    parser.add_argument("--data", type=Path, default=None, help="OpenCV's sample folder (default: opencv-doc's)")
    parser.add_argument("--scale", type=float, default=1.0, help="corner counts times this (a study; default 1)")
    parser.add_argument("--json", type=Path, default=None, help="write the rows as JSON")
    args = parser.parse_args(argv)
    data = opencv_samples(args.data)
    full = calibrate_rig([(n, data / f"left{n}.jpg", data / f"right{n}.jpg") for n in CHESSBOARD_PAIRS])
    board = _board_metres()
    rows = []
    print("pair  corners (n_min-n_max)  matches  board  within 5%  share  passes  seconds")
    for name in args.pairs:
        row = held_out(full, name, data, args.scale)
        rows.append(row)
        print(f"{name:>4}  {row['corners']:>7} ({row['n_min']}-{row['n_max']})  {row['matches']:>7}  "
              f"{row['board_matches']:>5}  {row['on_plane']:>9}  {row['share']:>5.2f}  "
              f"{'yes' if row['passes'] else 'NO':>6}  {row['seconds']:>7.1f}", flush=True)
    print(f"{sum(r['passes'] for r in rows)} of {len(rows)} pairs pass (>= {board.MIN_MATCHES} board matches, "
          f">= {board.MIN_SHARE:.0%} within {board.TOLERANCE:.0%} of the plane's depth)")
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
