"""scripts/matching_trials.py's cleanups on one pair: each keeps a subset, one match per corner."""

import numpy as np


def test_every_cleanup_keeps_a_subset_and_the_one_per_corner_ones_are_one_per_corner(load_script, rendered):
    from ismb_lab.matching.pipeline import prepare
    from ismb_lab.network.methods import get_method
    from ismb_lab.network.params import Params
    from ismb_lab.scenes import synthetic_scene
    from ismb_lab.network.solvers import matched_neurons, one_match_per_corner, solve

    script = load_script("matching_trials")
    scene = rendered(synthetic_scene, seed=3)
    p = prepare(scene.left, scene.right).problem
    m = get_method("III")
    params = Params(theta_c=60.0, theta_s=24.0, lambda_c=2.0, lambda_s=2.0)   # corners matched twice
    net = m.network(p, params)
    state = solve(net, "network", seed=0).state
    kept = script.cleaned(p, net, state, m, params)
    assert set(kept) == set(script.CLEANUPS)
    on = set(kept["none"].tolist())
    assert len(on) > len(set(p.rows[kept["none"]].tolist()))
    for name, k in kept.items():
        assert set(k.tolist()) <= on, name
        if name != "none":
            assert len(set(p.rows[k].tolist())) == len(k) == len(set(p.cols[k].tolist())), name
    assert np.array_equal(kept["M"], one_match_per_corner(p, matched_neurons(p, state, m)))
    assert set(kept["u, S > 0"].tolist()) <= set(kept["u"].tolist())
