"""Energy ingredients: similarity, candidates, compatibility and the three methods."""

import itertools

import numpy as np
import pytest

from ismb_lab.network.compatibility import left_neighbours, neuron_pairs
from ismb_lab.network.methods import THESIS_PARAMS, Params, build_problem, get_method
from ismb_lab.network.similarity import candidate_mask, mean_abs_difference, patches, transfer
from ismb_lab.network.solvers import to_matches


def test_transfer_matches_the_thesis_formula_and_its_limits():
    x = np.linspace(-50, 80, 27)
    for theta, lam in [(10.0, 0.3), (24.02, 2.2), (17.97, 6.37)]:
        literal = 2 / (1 + np.exp(lam * (x - theta))) - 1
        assert np.allclose(transfer(x, theta, lam), literal, atol=1e-12)
    assert transfer(1e9, 1.0, 5.0) == -1.0 and transfer(-1e9, 1.0, 5.0) == 1.0


def test_dissimilarity_is_zero_for_equal_windows_and_ignores_brightness_offset():
    rng = np.random.default_rng(1)
    img = rng.uniform(0, 200, (60, 60))
    xy = [[20, 20], [40, 30]]
    M = mean_abs_difference(img, img + 17, xy, xy, size=9)
    assert np.allclose(np.diag(M), 0) and np.all(M[~np.eye(2, dtype=bool)] > 10)
    w = patches(img, xy, 9)
    assert np.allclose(w.mean(axis=(1, 2)), 0)
    hand = np.abs(w[0] - w[1]).mean()
    assert M[0, 1] == pytest.approx(hand)


@pytest.mark.parametrize("size", [1, 3, 5, 11, 13, 21])
def test_compiled_dissimilarity_equals_the_numpy_expression_bit_for_bit(size):
    """M is the broadcast NumPy mean of |window differences| exactly, for windows below and
    above NumPy's 128-term pairwise block, on images with non-integer grey levels."""
    rng = np.random.default_rng(size)
    left, right = rng.uniform(0, 255, (2, 80, 90))
    lxy, rxy = rng.integers(0, 80, (23, 2)), rng.integers(0, 80, (31, 2))
    lp = patches(left, lxy, size).reshape(len(lxy), -1)
    rp = patches(right, rxy, size).reshape(len(rxy), -1)
    expected = np.abs(lp[:, None, :] - rp[None, :, :]).mean(axis=2)
    np.testing.assert_array_equal(mean_abs_difference(left, right, lxy, rxy, size), expected)


def test_candidate_window_is_30_by_40_centred_shift_pixels_left():
    left = [[120.0, 100.0]]
    right = [[100 + dx, 100 + dy] for dx, dy in [(0, 0), (20, 15), (-20, -15), (20.5, 0), (0, 15.5)]]
    assert candidate_mask(left, right).tolist() == [[True, True, True, False, False]]
    assert candidate_mask(left, right, shift=0).tolist() == [[True, True, False, True, False]]


def brute_force_pairs(lxy, rxy, mask, radius):
    """Every ordered neuron pair of the 4-D definition, with (3-12)'s three terms."""
    out = {}
    for (i, k), (j, l) in itertools.product(zip(*np.nonzero(mask)), repeat=2):
        if i == j or k == l or not np.all(np.abs(lxy[i] - lxy[j]) < radius):
            continue
        d = lambda a, b: np.hypot(*(lxy[a] - rxy[b]))
        dd = abs(d(i, k) - d(j, l))
        dD = abs(np.hypot(*(lxy[i] - lxy[j])) - np.hypot(*(rxy[k] - rxy[l])))
        dY = abs((rxy[k, 1] - lxy[i, 1]) - (rxy[l, 1] - lxy[j, 1]))
        out[(i, k, j, l)] = (dd, dD, dY)
    return out


@pytest.mark.parametrize("seed", range(5))
def test_sparse_pairs_equal_the_dense_definition_and_are_symmetric(seed):
    rng = np.random.default_rng(seed)
    lxy = rng.integers(80, 160, (14, 2)).astype(float)
    rxy = lxy[rng.permutation(14)[:12]] + [-20, 0] + rng.integers(-3, 4, (12, 2))
    problem = build_problem(lxy, rxy, np.zeros((14, 12)))
    dense = brute_force_pairs(lxy, rxy, candidate_mask(lxy, rxy), 20.0)
    p = problem.pairs
    sparse = {}
    for a, b, dd, dD, dY in zip(p.a, p.b, p.dd, p.dD, p.dY):
        i, k, j, l = problem.rows[a], problem.cols[a], problem.rows[b], problem.cols[b]
        sparse[(i, k, j, l)] = sparse[(j, l, i, k)] = (dd, dD, dY)
    assert len(dense) > 20
    assert set(sparse) == set(dense)
    for key, value in dense.items():
        assert np.allclose(sparse[key], value) and np.allclose(dense[key[2:] + key[:2]], value)


def numpy_pairs(lxy, rxy, rows, cols, nb):
    """The vectorised expressions neuron_pairs once was, kept to check the compiled loop."""
    counts = np.bincount(rows, minlength=len(lxy))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    ci, cj = counts[nb[:, 0]], counts[nb[:, 1]]
    sizes = ci * cj
    pair_id = np.repeat(np.arange(len(nb)), sizes)
    local = np.arange(sizes.sum()) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    a = starts[nb[pair_id, 0]] + local // cj[pair_id]
    b = starts[nb[pair_id, 1]] + local % cj[pair_id]
    keep = cols[a] != cols[b]
    a, b = a[keep], b[keep]
    p, q = lxy[rows], rxy[cols]
    disparity = np.hypot(*(p - q).T)
    return (a, b, np.abs(disparity[a] - disparity[b]),
            np.abs(np.hypot(*(p[a] - p[b]).T) - np.hypot(*(q[a] - q[b]).T)),
            np.abs((q[a, 1] - p[a, 1]) - (q[b, 1] - p[b, 1])))


@pytest.mark.parametrize("seed", range(4))
def test_compiled_pairs_equal_the_numpy_expressions_bit_for_bit(seed):
    # sub-pixel points, some left features without candidates, crowded and empty rows
    rng = np.random.default_rng(seed)
    lxy = rng.uniform(0, 300, (150, 2))
    rxy = np.concatenate([lxy[:120] + [-20, 0] + rng.normal(0, 2, (120, 2)), rng.uniform(0, 300, (40, 2))])
    mask = candidate_mask(lxy, rxy)
    rows, cols = (x.astype(np.int64) for x in np.nonzero(mask))
    nb = left_neighbours(lxy)
    got = neuron_pairs(lxy, rxy, rows, cols, nb)
    expected = numpy_pairs(lxy, rxy, rows, cols, nb)
    assert len(got) > 500 and np.bincount(rows, minlength=150).min() == 0
    for name, want in zip(("a", "b", "dd", "dD", "dY"), expected):
        np.testing.assert_array_equal(getattr(got, name), want, err_msg=name)


def test_neighbourhood_rules():
    xy = [[0, 0], [19, 19], [0, 19.9], [20, 0]]
    assert left_neighbours(xy).tolist() == [[0, 1], [0, 2], [1, 2], [1, 3]]
    assert left_neighbours(xy, shape="disc").tolist() == [[0, 2], [1, 2], [1, 3]]


@pytest.mark.parametrize("shape", ["box", "disc"])
def test_neighbours_equal_the_dense_rule_on_and_off_the_border(shape):
    """The k-d tree finds exactly the pairs of the all-pairs comparison, including points at
    exactly the radius (not neighbours) and just inside it, on integer and sub-pixel grids."""
    rng = np.random.default_rng(7)
    grid = rng.integers(0, 200, (400, 2)).astype(float)
    sub = rng.uniform(0, 200, (400, 2))
    edge = np.array([[0, 0], [20, 0], [0, 20], [19.999999, 0], [12, 16], [12, 15.999]])
    for xy in (grid, sub, edge):
        diff = xy[:, None, :] - xy[None, :, :]
        near = (np.all(np.abs(diff) < 20, axis=2) if shape == "box"
                else np.hypot(diff[..., 0], diff[..., 1]) < 20)
        expected = np.stack(np.nonzero(np.triu(near, k=1)), axis=1)
        np.testing.assert_array_equal(left_neighbours(xy, shape=shape), expected)


def test_methods_build_the_documented_energies():
    rng = np.random.default_rng(3)
    lxy = rng.integers(80, 160, (12, 2)).astype(float)
    rxy = lxy + [-20, 1] + rng.integers(-2, 3, (12, 2))
    M = rng.uniform(0, 40, (12, 12))
    problem = build_problem(lxy, rxy, M)
    params = Params(theta_c=9.0, theta_s=20.0, lambda_c=0.7, lambda_s=0.3)
    p = problem.pairs
    m = M[problem.rows, problem.cols]
    net3 = get_method("III").network(problem, params)
    net2 = get_method("II").network(problem, params)
    net1 = get_method("I").network(problem, params)
    assert np.allclose(net3.pair_c, transfer(p.dd + p.dD + p.dY, 9.0, 0.7))
    assert np.allclose(net2.pair_c, transfer(p.dd + p.dD, 9.0, 0.7))
    assert np.allclose(net1.pair_c, transfer(p.dd + p.dD + (m[p.a] + m[p.b]) / 2, 9.0, 0.7))
    assert np.allclose(net3.similarity, transfer(m, 20.0, 0.3))
    assert np.all(net1.similarity == 0)
    assert np.array_equal(net1.pair_c, get_method("I").network(
        problem, Params(theta_c=9.0, lambda_c=0.7, theta_s=1.0, lambda_s=5.0)).pair_c)


def test_method_one_postprocessing_keeps_the_smallest_vertical_disparity():
    lxy = np.array([[100.0, 50.0], [115.0, 50.0]])
    rxy = np.array([[80.0, 58.0], [85.0, 51.0], [110.0, 50.0]])
    problem = build_problem(lxy, rxy, np.zeros((2, 3)))
    assert problem.rows.tolist() == [0, 0, 1, 1, 1] and problem.cols.tolist() == [0, 1, 0, 1, 2]
    kept = get_method("I").postprocess(problem, np.arange(5))
    # left 0 keeps right 1 (|dy| = 1); left 1 keeps right 2 (|dy| = 0)
    assert kept.tolist() == [1, 4]
    kept = get_method("I").postprocess(problem, np.array([0, 2]))
    assert kept.tolist() == [0]  # right 0 is shared: the tie goes to the lower index
    found = to_matches(problem, [1, 1, 1, 1, 1], get_method("I"))
    assert found.pairs.tolist() == [[0, 1], [1, 2]] and found.state.tolist() == [0, 1, 0, 0, 1]


def test_params_validation_and_thesis_values():
    assert THESIS_PARAMS["III"] == Params()
    assert THESIS_PARAMS["II"].to_dict() == dict(theta_c=11.51, theta_s=26.24, lambda_c=8.89, lambda_s=1.16)
    for bad, error in [(dict(theta_c=np.nan), ValueError), (dict(theta_s=-1), ValueError),
                       (dict(lambda_s=0), ValueError), (dict(lambda_c=np.inf), ValueError),
                       (dict(theta_c="12"), TypeError)]:
        with pytest.raises(error, match=f"'{next(iter(bad))}' parameter of Params"):
            Params(**bad)
    with pytest.raises(ValueError, match="unknown keys"):
        Params.from_dict({"theta_c": 1.0, "theta_x": 2.0})
    with pytest.raises(ValueError, match="'method'.*Got 'V'"):
        get_method("V")


def random_problem(seed, n):
    rng = np.random.default_rng(seed)
    lxy = rng.integers(80, 160, (n, 2)).astype(float)
    rxy = lxy + [-20, 1] + rng.integers(-2, 3, (n, 2))
    return build_problem(lxy, rxy, rng.uniform(0, 40, (n, n)))


def test_method_nm_is_method_three_with_a_match_bias():
    problem = random_problem(4, 12)
    base = Params(theta_c=9.0, theta_s=20.0, lambda_c=0.7, lambda_s=0.3)
    three = get_method("III").network(problem, base)
    nm = get_method("NM").network(problem, Params(**base.to_dict(), match_bias=0.25))
    assert np.array_equal(nm.pair_c, three.pair_c) and np.array_equal(nm.similarity, three.similarity)
    assert (nm.uniqueness, nm.match_bias, nm.target_count) == (1.0, 0.25, 0.5625)
    as_thesis = get_method("NM").network(problem, Params(**base.to_dict(), match_bias=2.0))
    from ismb_lab.network.hopfield import hopfield_form
    from ismb_lab.network.dynamics import run
    assert all(np.array_equal(x, y) for x, y in zip(hopfield_form(as_thesis), hopfield_form(three)))
    assert np.array_equal(run(as_thesis, rng=3).state, run(three, rng=3).state)
    assert get_method("NM").gene_names == ("theta_c", "theta_s", "lambda_c", "lambda_s", "match_bias")
    with pytest.raises(ValueError, match="'params' parameter of Method-NM.*match_bias"):
        get_method("NM").network(problem, base)


def test_params_match_bias_is_optional_and_round_trips():
    assert "match_bias" not in Params().to_dict() and "match_bias" not in repr(Params())
    p = Params(theta_c=3.0, match_bias=-0.5)
    assert Params.from_dict(p.to_dict()) == p and p.to_dict()["match_bias"] == -0.5
    assert repr(p).endswith("match_bias=-0.5)")
    assert THESIS_PARAMS["NM"].match_bias == 0.0
    with pytest.raises(ValueError, match="'match_bias' parameter of Params"):
        Params(match_bias=np.inf)
    with pytest.raises(TypeError, match="'match_bias' parameter of Params"):
        Params(match_bias="0")


def test_method_nm4_is_method_nm_with_the_match_bias_fixed_at_zero():
    problem = random_problem(5, 10)
    base = Params(theta_c=9.0, theta_s=20.0, lambda_c=0.7, lambda_s=0.3)
    four = get_method("NM4").network(problem, base)
    nm = get_method("NM").network(problem, Params(**base.to_dict(), match_bias=0.0))
    from ismb_lab.network.hopfield import hopfield_form
    from ismb_lab.network.dynamics import run
    assert all(np.array_equal(x, y) for x, y in zip(hopfield_form(four), hopfield_form(nm)))
    assert np.array_equal(run(four, rng=2).state, run(nm, rng=2).state)
    ignored = get_method("NM4").network(problem, Params(**base.to_dict(), match_bias=1.5))
    assert ignored.match_bias == 0.0 and ignored.target_count == 0.5
    assert get_method("NM4").genes == get_method("III").genes
    assert get_method("NM4").gene_names == ("theta_c", "theta_s", "lambda_c", "lambda_s")
    with pytest.raises(TypeError, match="'params' parameter of Method-NM4"):
        get_method("NM4").network(problem, base.to_dict())


@pytest.mark.parametrize("bad", [dict(theta_c=-1.0), dict(theta_s=-1e-300), dict(lambda_c=0.0),
                                 dict(lambda_s=-0.0), dict(lambda_c=float("inf")),
                                 dict(theta_c=float("-inf")), dict(match_bias=float("nan"))])
def test_plain_floats_are_checked_as_strictly_as_any_number(bad):
    # Params has a shortcut for plain floats in range; everything else takes the full check
    with pytest.raises(ValueError, match=f"'{next(iter(bad))}' parameter of Params"):
        Params(**bad)


def test_params_store_plain_floats_whatever_number_type_they_are_given():
    p = Params(theta_c=np.float64(3.5), theta_s=4, lambda_c=np.float32(0.5), lambda_s=2.0,
               match_bias=np.int64(-1))
    assert [type(v) for v in p.to_dict().values()] == [float] * 5
    assert p == Params(theta_c=3.5, theta_s=4.0, lambda_c=0.5, lambda_s=2.0, match_bias=-1.0)


def test_each_methods_measures_are_computed_once_per_problem_and_stay_in_this_process():
    import pickle

    problem = random_problem(6, 12)
    for name in ("I", "III"):
        method = get_method(name)
        pair_x, self_x = method._measures(problem)
        assert method._measures(problem)[0] is pair_x
        assert np.array_equal(pair_x, method.pair_measure(problem))
        assert np.array_equal(self_x, method.self_measure(problem))
        assert not pair_x.flags.writeable and not self_x.flags.writeable
    assert not problem.neuron_dissimilarity.flags.writeable
    copy = pickle.loads(pickle.dumps(problem))
    assert copy._measures == {} and "neuron_dissimilarity" not in vars(copy)
    params = Params(theta_c=9.0, theta_s=20.0, lambda_c=0.7, lambda_s=0.3)
    a, b = (get_method("III").network(p, params) for p in (problem, copy))
    assert np.array_equal(a.pair_c, b.pair_c) and np.array_equal(a.similarity, b.similarity)


def test_nm3_sets_theta_s_from_the_pair_and_is_nm4_at_that_value():
    """Method-NM3 is Method-NM4 with theta_s = half the median of M, whatever params say."""
    from dataclasses import replace

    from ismb_lab.network.params import Params
    from ismb_lab.matching.peers import default_no_match_cost

    rng = np.random.default_rng(3)
    lxy = rng.uniform(20, 200, (12, 2))
    rxy = lxy - [15.0, 0.0] + rng.normal(0, 0.5, (12, 2))
    p = build_problem(lxy, rxy, rng.uniform(0, 60, (12, 12)))
    assert p.no_match_cut == np.median(p.dissimilarity) / 2 == default_no_match_cost(p)
    nm3, nm4 = get_method("NM3"), get_method("NM4")
    assert "theta_s" not in nm3.gene_names and nm3.derived == ("theta_s",)
    params = Params(theta_c=12.0, theta_s=3.0, lambda_c=2.0, lambda_s=0.5)
    a = nm3.network(p, params)
    b = nm4.network(p, replace(params, theta_s=p.no_match_cut))
    c = nm4.network(p, params)
    assert np.array_equal(a.similarity, b.similarity) and np.array_equal(a.pair_c, b.pair_c)
    assert a.match_bias == 0.0 and not np.array_equal(a.similarity, c.similarity)
    # a camera's gain scales M, and the cut with it: S does not change
    q = build_problem(lxy, rxy, 2.0 * p.dissimilarity)
    assert np.allclose(nm3.network(q, replace(params, lambda_s=0.25)).similarity, a.similarity)
