"""How often is the network's fixed point the global minimum, and is the minimum the right matching?

Small problems (at most 26 candidate neurons) from synthetic scenes with a small ROI and few
corners; Method-III (thesis parameters for synthetic scenes used in the tests) and Method-NM
(the same with match_bias 0); 10 update-order seeds per problem.

    python scripts/exact_minimum_stats.py
"""

import numpy as np

from ismb_lab.network.annealing import anneal
from ismb_lab.tuning.evaluation import Score, score
from ismb_lab.network.exact import MAX_EXHAUSTIVE, exhaustive_minimum
from ismb_lab.network.dynamics import run
from ismb_lab.matching.pipeline import MatchConfig, prepare
from ismb_lab.network.methods import Params, get_method
from ismb_lab.scenes import synthetic_scene, true_matches

BASE = Params(theta_c=2.0, theta_s=24.02, lambda_c=0.5, lambda_s=2.2)


def problems():
    for seed in range(12):
        scene = synthetic_scene(seed=seed)
        for roi in [(100, 80, 100, 80), (150, 100, 100, 80)]:
            prepared = prepare(scene.left, scene.right, MatchConfig(roi=roi, n_min=4, n_max=10))
            p = prepared.problem
            if 4 <= p.n_neurons <= MAX_EXHAUSTIVE:
                truth = true_matches(scene, p.left_xy, p.right_xy)
                left = np.flatnonzero(truth >= 0)
                yield p, np.stack([left, truth[left]], axis=1)


def pairs(p, state):
    on = np.flatnonzero(state)
    return np.stack([p.rows[on], p.cols[on]], axis=1)


def main():
    items = list(problems())
    print(f"{len(items)} problems, {min(p.n_neurons for p, _ in items)}-"
          f"{max(p.n_neurons for p, _ in items)} candidate neurons")
    for method, params in [("III", BASE), ("NM", Params(**BASE.to_dict(), match_bias=0.0))]:
        m = get_method(method)
        hit_net = hit_ann = runs = unique = 0
        total = {"minimum": Score(0, 0, 0, 0), "network": Score(0, 0, 0, 0), "anneal": Score(0, 0, 0, 0)}
        perfect = 0
        for p, targets in items:
            net = m.network(p, params)
            best = exhaustive_minimum(net)
            unique += best.n_minima == 1
            s = score(pairs(p, best.state), targets)
            perfect += s.correct == s.targets and s.errors == 0
            total["minimum"] += s
            for seed in range(10):
                r, a = run(net, rng=seed), anneal(net, rng=seed)
                hit_net += r.energy <= best.energy + 1e-9
                hit_ann += a.energy <= best.energy + 1e-9
                total["network"] += score(pairs(p, r.state), targets)
                total["anneal"] += score(pairs(p, a.state), targets)
                runs += 1
        print(f"Method-{method}: fixed point = global minimum in {hit_net}/{runs} network runs, "
              f"{hit_ann}/{runs} annealed runs; unique minimum in {unique}/{len(items)}; "
              f"the minimum is exactly the true matching in {perfect}/{len(items)} problems")
        for name, sc in total.items():
            print(f"    {name:8s} {sc}  C/T {100 * sc.recall:.1f}%  precision {100 * sc.precision:.1f}%")


if __name__ == "__main__":
    main()
