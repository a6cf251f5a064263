"""How ismb_lab.depth.pipeline.DEPTH_PARAMS were fitted: the GA on the background pair images/lab only.

The depth demo finds corners with ``ismb_lab.depth.pipeline.DEPTH_MATCH_CONFIG`` (more corners
than the thesis' 20-30, so that the small toy cars get some).  The GA (Method-III,
``ismb_lab.tuning.fitness.tune``) fits on images/lab with its answer key, scored as
``ismb-lab tune`` scores it: fitness (4-1) ``n_c - n_e``, where a match of a corner the
key does not list counts as an error (the key lists the corners of the default
matcher, so the denser corners' matches must earn their place).  Each chromosome is scored over
``--seeds`` update orders, so that parameters working for one visiting order only
score lower.  No toy-car scene is used.  The demo solves the energy with mean-field
annealing (``ismb_lab.depth.pipeline.DEPTH_SOLVER``); the GA scores with the discrete network,
and the script also prints the fitted parameters' score under annealing.

    python scripts/fit_depth_params.py [--out PARAMS.json] [--generations 500] [--seed 0]

It prints the parameters and, with ``--out``, writes a recipe (``ismb_lab.matching.recipe``)
for ``ismb-lab depth --params-file``: Method-III, the fitted parameters, ``--seeds`` as its
``fit_seeds``, and the demo's solver, annealing, under which ``depth`` runs them (not the
discrete network the GA scored with).
"""

import argparse
import time
from pathlib import Path

from ismb_lab._core.files import check_output
from ismb_lab.depth.pipeline import DEPTH_MATCH_CONFIG, DEPTH_SOLVER
from ismb_lab.matching.recipe import Recipe, save_recipe
from ismb_lab.tuning.cases import Case
from ismb_lab.tuning.fitness import evaluate, to_params, tune

LAB = Path(__file__).resolve().parents[1] / "images" / "lab"


def lab_case(config=DEPTH_MATCH_CONFIG) -> Case:
    """The lab pair with its answer key snapped to the corners of `config`."""
    return Case.from_files(LAB / "left.png", LAB / "right.png", LAB / "answer_key.json", config,
                           name="images/lab")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None, help="write the parameters here")
    parser.add_argument("--generations", type=int, default=500)
    parser.add_argument("--population", type=int, default=30)
    parser.add_argument("--seeds", type=int, default=5, help="update orders per chromosome")
    parser.add_argument("--seed", type=int, default=0, help="seed of the GA")
    args = parser.parse_args(argv)
    if args.out is not None:
        check_output(args.out)   # before the GA's minutes, not after
    case = lab_case()
    start = time.perf_counter()
    best = None
    for best in tune([case], "III", rng=args.seed, population=args.population,
                     generations=args.generations, seeds=args.seeds):
        pass
    seconds = time.perf_counter() - start
    params = to_params("III", best.best_chromosome)
    scores = [evaluate([case], "III", params, seed=s) for s in range(args.seeds)]
    print(f"images/lab: {len(case.prepared.problem.left_xy)} left corners, {len(case.targets)} "
          f"targets; GA seed {args.seed}, {best.index} generations "
          f"in {seconds:.1f} s; best mean fitness {best.best:g}")
    print("C/E/T per update-order seed:", ", ".join(map(str, scores)))
    annealed = [evaluate([case], "III", params, seed=s, solver="anneal") for s in range(args.seeds)]
    print("annealed, per seed:", ", ".join(map(str, annealed)))
    print("params:", {k: round(v, 4) for k, v in params.to_dict().items()})
    if args.out is not None:
        recipe = Recipe("III", params, DEPTH_SOLVER, fit_seeds=args.seeds)
        save_recipe(args.out, recipe, fitness=best.best, generations=best.index, seed=args.seed,
                    targets=len(case.targets), interrupted=False)
        print(f"written to {args.out}")


if __name__ == "__main__":
    main()
