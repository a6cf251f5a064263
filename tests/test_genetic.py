"""The real-coded GA of thesis chapter 4: operators, one generation, the run loop."""

import numpy as np
import pytest
from scipy.stats import chisquare

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.tuning.genetic import (Bounds, Generation, arithmetic_crossover, batch, elite, evolve,
                              initial_population, next_generation, random_mutation, tournament)

UNIT4 = Bounds([0, 0, 0, 0], [1, 1, 1, 1])
BOX = Bounds([-2.0, -5.0], [2.0, 5.0])


def sphere(pop, centre=0.3):
    return -np.sum((pop - centre) ** 2, axis=1)


def counted(fitness):
    """Wrap a batch fitness so that it records how many chromosomes it evaluated."""
    def wrapped(pop):
        wrapped.rows += len(pop)
        wrapped.calls += 1
        return fitness(pop)
    wrapped.rows = wrapped.calls = 0
    return wrapped


# --- Bounds ---------------------------------------------------------------------------

def test_bounds_reject_low_not_below_high_naming_gene_and_values():
    with pytest.raises(ParameterError, match=r"'bounds' .* low < high .*gene 2: low=3.0, high=3.0"):
        Bounds([0, 0, 3], [1, 1, 3])


@pytest.mark.parametrize("low, high, names, name", [
    ([0, 0], [1], None, "high"), ([], [], None, "low"), ([0, np.nan], [1, 1], None, "low"),
    ([[0, 0]], [[1, 1]], None, "low"), ([0, 0], [1, 1], ("a",), "names"),
])
def test_bounds_reject_bad_arrays(low, high, names, name):
    with pytest.raises(ParameterError, match=f"'{name}' parameter of Bounds"):
        Bounds(low, high, names)


def test_bounds_are_read_only_float_arrays():
    b = Bounds([0, 1], [2, 3], names=["x", "y"])
    assert b.low.dtype == float and b.names == ("x", "y") and b.n_genes == 2
    with pytest.raises(ValueError):
        b.low[0] = 5.0


# --- operators ------------------------------------------------------------------------

def test_initial_population_is_uniform_in_bounds():
    pop = initial_population(np.random.default_rng(1), BOX, 4000)
    assert pop.shape == (4000, 2)
    assert np.all(pop >= BOX.low) and np.all(pop <= BOX.high)
    unit = (pop - BOX.low) / (BOX.high - BOX.low)
    for gene in unit.T:
        assert chisquare(np.histogram(gene, bins=10, range=(0, 1))[0]).pvalue > 1e-3


def test_initial_population_rejects_bad_size():
    with pytest.raises(ParameterError, match=r"'size' parameter of initial_population .* >= 1. Got 0"):
        initial_population(0, BOX, 0)


@pytest.mark.parametrize("lam", [0.0, 0.2, 0.5, 0.93])
def test_crossover_children_lie_on_the_segment_and_sum_to_the_parents(lam):
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=5), rng.normal(size=5)
    c1, c2 = arithmetic_crossover(a, b, lam)
    np.testing.assert_allclose(c1 + c2, a + b, atol=1e-12)
    np.testing.assert_allclose((c1 - b) / (a - b), lam, atol=1e-9)   # c1 at position lam from b to a
    np.testing.assert_allclose((c2 - a) / (b - a), lam, atol=1e-9)


def test_crossover_lambda_one_returns_the_parents_and_zero_swaps_them():
    a, b = np.array([0.1, 7.0]), np.array([3.3, -2.0])
    c1, c2 = arithmetic_crossover(a, b, 1.0)
    assert np.array_equal(c1, a) and np.array_equal(c2, b)
    c1, c2 = arithmetic_crossover(a, b, 0.0)
    assert np.array_equal(c1, b) and np.array_equal(c2, a)


@pytest.mark.parametrize("lam", [-0.1, 1.5, float("nan")])
def test_crossover_rejects_lambda_outside_unit_interval(lam):
    with pytest.raises(ParameterError, match="'lam' parameter of arithmetic_crossover"):
        arithmetic_crossover([0.0], [1.0], lam)


def test_mutation_changes_exactly_one_gene_within_bounds_and_copies():
    rng = np.random.default_rng(4)
    parent = np.full(4, 0.5)
    for _ in range(200):
        child = random_mutation(rng, parent, UNIT4)
        assert np.sum(child != parent) == 1
        assert np.all(child >= 0) and np.all(child <= 1)
    assert np.all(parent == 0.5)


def test_mutation_gene_and_value_are_uniform():
    rng = np.random.default_rng(5)
    bounds = Bounds([0, 10, -3, 100], [1, 20, 3, 101])
    parent = (bounds.low + bounds.high) / 2
    genes, values = [], []
    for _ in range(4000):
        child = random_mutation(rng, parent, bounds)
        g = int(np.flatnonzero(child != parent)[0])
        genes.append(g)
        values.append((child[g] - bounds.low[g]) / (bounds.high[g] - bounds.low[g]))
    assert chisquare(np.bincount(genes, minlength=4)).pvalue > 1e-3
    assert chisquare(np.histogram(values, bins=10, range=(0, 1))[0]).pvalue > 1e-3


def test_mutation_rejects_wrong_length():
    with pytest.raises(ParameterError, match=r"'chromosome' parameter of random_mutation .*\(4,\)"):
        random_mutation(0, [0.5, 0.5], UNIT4)


def test_tournament_worst_never_wins_and_wins_follow_rank():
    n, k = 6, 30000
    fitness = np.array([3.0, -1.0, 10.0, 2.5, 7.0, 0.0])
    winners = tournament(np.random.default_rng(6), fitness, k)
    rank = np.argsort(np.argsort(fitness))           # 0 = worst
    counts = np.bincount(rank[winners], minlength=n)
    assert counts[0] == 0                            # the worst beats nobody
    expected = 2 * np.arange(n) / (n * (n - 1)) * k  # rank r beats r of the n-1 others
    assert chisquare(counts[1:], expected[1:]).pvalue > 1e-3


def test_tournament_ties_go_to_the_first_drawn():
    winners = tournament(np.random.default_rng(7), np.zeros(5), 50)
    first = np.random.default_rng(7).integers(5, size=50)   # the documented first draw
    assert np.array_equal(winners, first)


def test_tournament_needs_two_chromosomes():
    with pytest.raises(ParameterError, match=r"'fitness' parameter of tournament .*>= 2.*shape \(1,\)"):
        tournament(0, [1.0], 3)


def test_elite_orders_best_first_and_breaks_ties_by_lower_index():
    fitness = [1.0, 3.0, 3.0, 0.0, 2.0, 3.0]
    assert elite(fitness, 4).tolist() == [1, 2, 5, 4]
    assert elite(fitness).tolist() == [1, 2]
    assert elite(fitness, 0).tolist() == []
    with pytest.raises(ParameterError, match=r"'n' parameter of elite .*<= 6. Got 7"):
        elite(fitness, 7)


# --- one generation -------------------------------------------------------------------

def population_and_fitness(seed, size=30):
    pop = initial_population(seed, BOX, size)
    return pop, sphere(pop)


@pytest.mark.parametrize("p_c, p_m", [(0.8, 0.05), (1.0, 1.0), (0.0, 0.0), (0.5, 0.5)])
def test_next_generation_keeps_size_elite_and_bounds(p_c, p_m):
    pop, fit = population_and_fitness(8)
    new = next_generation(np.random.default_rng(9), pop, fit, BOX, p_crossover=p_c, p_mutation=p_m)
    assert new.shape == pop.shape
    assert np.array_equal(new[:2], pop[elite(fit, 2)])
    assert np.all(new >= BOX.low) and np.all(new <= BOX.high)


@pytest.mark.parametrize("p_m", [0.0, 1.0])
def test_without_crossover_the_population_is_made_of_intermediate_members(p_m):
    """p_c = 0: only P' members, and (thesis §4.2) no mutation without crossover."""
    pop, fit = population_and_fitness(10)
    new = next_generation(np.random.default_rng(11), pop, fit, BOX, p_crossover=0.0, p_mutation=p_m)
    assert all(any(np.array_equal(row, old) for old in pop) for row in new)
    assert np.mean(sphere(new)) > np.mean(fit)       # tournaments favour the fitter


def test_crossover_uses_one_lambda_per_generation():
    pop, fit = population_and_fitness(12, size=31)   # 29 winners: 14 pairs and one copied
    new = next_generation(np.random.default_rng(13), pop, fit, BOX, p_crossover=1.0, p_mutation=0.0)
    lams = []
    for c1, c2 in zip(new[2:-1:2], new[3::2]):
        total = c1 + c2
        sums = pop[:, None, :] + pop[None, :, :]
        i, j = np.unravel_index(np.argmin(np.abs(sums - total).sum(axis=2)), sums.shape[:2])
        np.testing.assert_allclose(pop[i] + pop[j], total, atol=1e-9)
        if i != j:
            lam = (c1 - pop[j]) / (pop[i] - pop[j])
            np.testing.assert_allclose(lam, lam[0], atol=1e-7)
            lams.append(min(lam[0], 1 - lam[0]))
    assert len(lams) > 5
    np.testing.assert_allclose(lams, lams[0], atol=1e-7)
    assert any(np.array_equal(new[-1], old) for old in pop)   # the odd winner is copied


def test_next_generation_rejects_bad_inputs():
    pop, fit = population_and_fitness(14)
    with pytest.raises(ParameterError, match=r"'p_crossover' parameter of next_generation .*Got 1.2"):
        next_generation(0, pop, fit, BOX, p_crossover=1.2)
    with pytest.raises(ParameterError, match=r"'fitness' parameter of next_generation .*shape \(29,\)"):
        next_generation(0, pop, fit[:-1], BOX)
    with pytest.raises(ParameterError, match=r"'population' parameter of next_generation"):
        next_generation(0, pop[:, :1], fit, BOX)


# --- the run loop ---------------------------------------------------------------------

def records(seed, **kw):
    kw = {"generations": 25, "keep_population": True, **kw}
    return list(evolve(lambda p: np.cos(3 * p).sum(axis=1) - 0.1 * (p ** 2).sum(axis=1), BOX,
                       rng=np.random.default_rng(seed), **kw))


def test_same_seed_gives_bit_identical_records_and_another_seed_differs():
    one, two, other = records(15), records(15), records(16)
    assert len(one) == len(two) == 26
    for a, b in zip(one, two):
        for name in ("index", "best", "mean", "worst", "evaluations"):
            assert getattr(a, name) == getattr(b, name)
        for name in ("best_chromosome", "population", "fitness"):
            assert np.array_equal(getattr(a, name), getattr(b, name))
    assert not np.array_equal(one[-1].population, other[-1].population)


def test_records_summarise_the_population():
    for rec in records(17, generations=5):
        assert isinstance(rec, Generation)
        assert rec.best == rec.fitness.max() and rec.worst == rec.fitness.min()
        assert rec.mean == pytest.approx(rec.fitness.mean())
        assert np.array_equal(rec.best_chromosome, rec.population[np.argmax(rec.fitness)])
        np.testing.assert_array_equal(rec.fitness, np.cos(3 * rec.population).sum(axis=1)
                                      - 0.1 * (rec.population ** 2).sum(axis=1))
    assert records(17, keep_population=False)[0].population is None


@pytest.mark.parametrize("seed", range(5))
def test_best_never_decreases(seed):
    best = [r.best for r in records(seed, generations=80, p_mutation=0.5)]
    assert np.all(np.diff(best) >= 0)
    assert best[-1] > best[0]


def test_stops_when_the_mean_reaches_the_target():
    run = list(evolve(sphere, UNIT4, rng=18, target=-0.01))
    assert run[-1].index < 500 and run[-1].mean >= -0.01
    assert all(r.mean < -0.01 for r in run[:-1])
    assert [r.index for r in run] == list(range(len(run)))


def test_stops_at_the_generation_limit_otherwise():
    run = list(evolve(sphere, UNIT4, rng=19, generations=7, target=1.0))   # unreachable target
    assert [r.index for r in run] == list(range(8))


def test_evaluations_count_only_changed_chromosomes():
    fitness = counted(sphere)
    run = list(evolve(fitness, UNIT4, rng=20, population=10, generations=30))
    assert run[0].evaluations == 10 and run[-1].evaluations == fitness.rows
    assert run[-1].evaluations < 10 * 31                     # elite and uncrossed copies are reused
    frozen = counted(sphere)
    run = list(evolve(frozen, UNIT4, rng=20, population=10, generations=30, p_crossover=0.0))
    assert frozen.calls == 1 and run[-1].evaluations == 10   # nothing new ever appears


def test_a_consumer_can_stop_mid_run_and_the_generator_closes():
    fitness = counted(sphere)
    run = evolve(fitness, UNIT4, rng=21, generations=500)
    assert fitness.calls == 0                                # lazy: nothing done yet
    for rec in run:
        if rec.index == 3:
            break
    assert fitness.rows == rec.evaluations                   # no generation computed ahead
    run.close()
    with pytest.raises(StopIteration):
        next(run)


def test_converges_on_a_smooth_two_gene_function():
    def bowl(p):
        return -((p[:, 0] - 0.7) ** 2 + 3 * (p[:, 1] + 2.5) ** 2)
    errors = [np.abs(list(evolve(bowl, BOX, rng=seed, generations=60))[-1].best_chromosome
                     - [0.7, -2.5]).max() for seed in range(10)]
    assert np.median(errors) < 0.05 and max(errors) < 0.25   # the search box is 4 x 10


def test_batch_wraps_a_per_chromosome_score():
    def score(c):
        return float(-np.sum((c - 0.3) ** 2))
    pop = initial_population(23, UNIT4, 6)
    np.testing.assert_allclose(batch(score)(pop), sphere(pop))
    with pytest.raises(ParameterTypeError, match="'score' parameter of batch"):
        batch(3)


@pytest.mark.parametrize("kw, pattern", [
    ({"population": 1}, r"The 'population' parameter of evolve must be an integer >= 2 and <= 100000. Got 1 instead."),
    ({"population": 2.5}, r"'population' parameter of evolve .*Got 2.5"),
    ({"generations": 0}, r"'generations' parameter of evolve .*>= 1. Got 0"),
    ({"p_crossover": 1.5}, r"'p_crossover' parameter of evolve .*>= 0 and <= 1. Got 1.5"),
    ({"p_mutation": -0.1}, r"'p_mutation' parameter of evolve .*Got -0.1"),
    ({"n_elite": 31}, r"'n_elite' parameter of evolve .*<= 30. Got 31"),
    ({"target": float("nan")}, r"'target' parameter of evolve .*Got nan"),
    ({"rng": None}, r"'rng' parameter of evolve"),
    ({"bounds": ([0], [1])}, r"'bounds' parameter of evolve must be a Bounds"),
    ({"fitness": "sphere"}, r"'fitness' parameter of evolve must be a callable"),
    ({"keep_population": 1}, r"'keep_population' parameter of evolve"),
])
def test_evolve_rejects_bad_arguments_at_call_time(kw, pattern):
    kw = {"fitness": sphere, "bounds": UNIT4, "rng": 0, **kw}
    with pytest.raises((ParameterError, ParameterTypeError), match=pattern):
        evolve(kw.pop("fitness"), kw.pop("bounds"), **kw)


@pytest.mark.parametrize("fitness, pattern", [
    (lambda p: np.where(p[:, 0] > 0.5, np.nan, 0.0), r"finite number per chromosome. Got array\(\[.*nan"),
    (lambda p: np.zeros((len(p), 1)), r"Got 'an array of shape \(30, 1\)'"),
    (lambda p: 0.0, r"Got 'an array of shape \(\)'"),
])
def test_bad_fitness_values_are_reported_naming_fitness(fitness, pattern):
    with pytest.raises(ParameterError, match=r"The 'fitness' parameter of evolve .*" + pattern):
        next(evolve(fitness, UNIT4, rng=0))


def _breed_by_the_operators(rng, population, fitness, bounds, p_c, p_m, n_elite):
    """One generation composed of the public operators, as _breed's docstring describes it."""
    size = len(population)
    origin = np.concatenate([elite(fitness, n_elite), tournament(rng, fitness, size - n_elite)])
    children = population[origin]
    lam = rng.random()
    first = n_elite + 2 * np.flatnonzero(rng.random((size - n_elite) // 2) < p_c)
    children[first], children[first + 1] = arithmetic_crossover(children[first], children[first + 1], lam)
    crossed = np.sort(np.concatenate([first, first + 1]))
    origin[crossed] = -1
    for i in crossed[rng.random(crossed.size) < p_m]:
        children[i] = random_mutation(rng, children[i], bounds)
    return children, origin


@pytest.mark.parametrize("size, n_elite, p_m", [(30, 2, 0.05), (31, 0, 0.5), (2, 1, 1.0), (9, 9, 0.3)])
def test_a_generation_draws_and_computes_as_its_operators(size, n_elite, p_m):
    from ismb_lab.tuning.genetic import _breed

    bounds = Bounds([0, 0, 0.05], [60, 60, 10])
    for seed in range(20):
        rng = np.random.default_rng(seed)
        population = initial_population(rng, bounds, size)
        fitness = np.round(rng.normal(size=size), 1)   # ties too
        fast_rng, slow_rng = np.random.default_rng(100 + seed), np.random.default_rng(100 + seed)
        fast = _breed(fast_rng, population.copy(), fitness, bounds, 0.8, p_m, n_elite)
        slow = _breed_by_the_operators(slow_rng, population.copy(), fitness, bounds, 0.8, p_m, n_elite)
        assert np.array_equal(fast[0], slow[0]) and np.array_equal(fast[1], slow[1])
        assert fast_rng.random() == slow_rng.random()   # the same number of draws
