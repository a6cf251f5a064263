"""How tests/test_matching.py's SYNTHETIC_PARAMS were chosen: a grid search on training scenes.

Scores Method-III on synthetic scenes 100-109 (never used by the tests) over a small
grid of (theta_c, lambda_c, theta_s, lambda_s) and prints the best by min(C/T, precision),
then both the thesis' and the chosen parameters on held-out scenes 0-19.

    python scripts/grid_search_synthetic.py
"""

import itertools

import numpy as np

from ismb_lab.matching.pipeline import match, prepare
from ismb_lab.network.methods import THESIS_PARAMS, Params
from ismb_lab.scenes import synthetic_scene, true_matches


def load(seeds):
    data = []
    for seed in seeds:
        scene = synthetic_scene(seed=seed)
        prepared = prepare(scene.left, scene.right)
        data.append((prepared, true_matches(scene, prepared.problem.left_xy, prepared.problem.right_xy)))
    return data


def score(data, params, method="III"):
    correct = wrong = partners = 0
    for prepared, truth in data:
        result = match(method=method, params=params, prepared=prepared, seed=0)
        ok = sum(truth[i] == k for i, k in result.pairs)
        correct, wrong = correct + ok, wrong + len(result.pairs) - ok
        partners += np.count_nonzero(truth >= 0)
    return correct / partners, correct / max(correct + wrong, 1)


def main():
    train = load(range(100, 110))
    grid = itertools.product([2, 3, 5, 8, 12, 18], [0.5, 1, 3, 6.37], [15, 24.02], [0.3, 2.2])
    ranked = sorted(((min(score(train, Params(tc, ts, lc, ls))), (tc, ts, lc, ls))
                     for tc, lc, ts, ls in grid), reverse=True)
    for value, genes in ranked[:5]:
        print(f"train min(C/T, precision) {value:.3f}  [theta_c, theta_s, lambda_c, lambda_s] = {genes}")
    test = load(range(20))
    for name, params in (("thesis", THESIS_PARAMS["III"]), ("chosen", Params(*ranked[0][1]))):
        recall, precision = score(test, params)
        print(f"held-out scenes 0-19, {name} parameters: C/T {recall:.3f}, precision {precision:.3f}")


if __name__ == "__main__":
    main()
