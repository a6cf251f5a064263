"""Tuning the energy parameters with the GA: chromosome <-> Params, fitness n_c - n_e (4-1).

A chromosome holds a method's genes in :attr:`~ismb_lab.network.methods.Method.genes` order;
its fitness is summed over the training cases (anything with ``prepared``, ``targets`` and
``unknown``, such as :class:`ismb_lab.tuning.cases.Case`).
"""

from __future__ import annotations

from dataclasses import fields
from inspect import signature
from typing import Iterator, Sequence

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, message
from .evaluation import Score, Scorer, _tally
from .genetic import Bounds, GAConfig, Generation, evolve
from ..network.kernel import fitness_runs
from ..network.dynamics import KERNELS, STOP_RULES, run
from ..network.hopfield import MAX_INPUT, RULES, SCALE
from ..network.methods import BATCHED, DEFAULT_METHOD, MethodI, get_method
from ..network.params import Params
from ..network.solvers import DEFAULT_SOLVER, NetworkSolver, get_solver, matched_neurons, one_match_per_corner, solve

__all__ = ["Fitness", "evaluate", "gene_bounds", "to_chromosome", "to_params", "tune"]

_FIELDS = tuple(f.name for f in fields(Params))


def gene_bounds(method) -> Bounds:
    """The GA's search box for a method's genes.

    Parameters
    ----------
    method : str or Method
        The method, e.g. ``"I"`` or ``"III"``.

    Returns
    -------
    bounds : Bounds
        Low and high of each gene, named.

    Examples
    --------
    >>> gene_bounds("I").names
    ('theta_c', 'lambda_c')
    """
    genes = get_method(method).genes
    return Bounds(low=[g.low for g in genes], high=[g.high for g in genes], names=tuple(g.name for g in genes))


def to_params(method, chromosome, base: Params | None = None) -> Params:
    """Chromosome to parameters; the genes a method does not use keep `base`'s values
    (default: the method's).

    Parameters
    ----------
    method : str or Method
        The method whose genes `chromosome` holds.
    chromosome : (n_genes,) float array_like
        Gene values in the method's gene order.
    base : Params, optional
        Values of the genes the method does not use; default the method's defaults.

    Returns
    -------
    params : Params
        The parameters.

    Raises
    ------
    ParameterError
        `chromosome` of the wrong length.

    Examples
    --------
    >>> to_params("I", [41.57, 4.40])
    Params(theta_c=41.57, theta_s=24.02, lambda_c=4.4, lambda_s=2.2)
    """
    m = get_method(method)
    genes = m.gene_names
    chromosome = np.asarray(chromosome, dtype=float).ravel()
    if len(chromosome) != len(genes):
        raise ParameterError(message("chromosome", "to_params", f"{len(genes)} genes {genes}",
                                     chromosome.tolist()))
    values = {name: getattr(base or m.defaults, name) for name in _FIELDS}
    values.update(zip(genes, chromosome.tolist()))
    return Params(**values)  # dataclasses.replace(), in less time


def to_chromosome(method, params: Params) -> np.ndarray:
    """Parameters to the method's chromosome.

    >>> to_chromosome("III", Params()).tolist()
    [17.97, 24.02, 6.37, 2.2]
    """
    return np.array([getattr(params, g) for g in get_method(method).gene_names])


def evaluate(cases: Sequence, method, params: Params, seed: int = 0,
             solver=DEFAULT_SOLVER, one_to_one: bool = False) -> Score:
    """The summed C/E/T of `params` over `cases`, each solved by `solver` with `seed`; with
    `one_to_one`, after :func:`~ismb_lab.network.solvers.one_match_per_corner`.  Pass `method`
    as a Method to resolve it once for many calls.

    Parameters
    ----------
    cases : sequence of Case
        The pairs with their targets.
    method : str or Method
        The matching method.
    params : Params
        The parameters to score.
    seed : int, default 0
        Update-order seed, >= 0.
    solver : str or Solver, default ``DEFAULT_SOLVER``
        How the network is solved.
    one_to_one : bool, default False
        Keep at most one match per corner before counting.

    Returns
    -------
    score : Score
        C/E/T summed over the cases.
    """
    m = get_method(method)
    solver = get_solver(solver, "evaluate")
    check_number(seed, "seed", "evaluate", low=0, integer=True)
    if not isinstance(one_to_one, bool):
        raise ParameterTypeError(message("one_to_one", "evaluate", "True or False", one_to_one))
    correct = wrong = extra = targets = 0
    for case in cases:
        c, w, e = _counts(case, m, params, seed, solver, one_to_one)
        correct, wrong, extra = correct + c, wrong + w, extra + e
        targets += (getattr(case, "scorer", None) or Scorer(case.targets, case.unknown)).targets
    return Score(correct, wrong, extra, targets)


def _counts(case, m, params: Params, seed: int, solver, one_to_one: bool = False, net=None) -> tuple[int, int, int]:
    """C, wrong partner and extra of one case, counted over its coded neurons; `net` is
    ``m.network(problem, params)`` if built already."""
    problem = case.prepared.problem
    state = solve(m.network(problem, params) if net is None else net, solver, seed=seed, owner="evaluate").state
    codes = getattr(case, "neuron_codes", None)
    if codes is None:
        codes = Scorer(case.targets, case.unknown).neuron_codes(problem.rows, problem.cols)
    kept = np.asarray(matched_neurons(problem, state, m), dtype=np.int64)
    if one_to_one:
        kept = one_match_per_corner(problem, kept)
    counts = _tally(codes, kept)
    if counts[0] < 0:
        raise ParameterError(message("method", "evaluate", f"a postprocess that keeps neuron indices in "
                                     f"[0, {len(codes)})", kept))
    return counts


class Fitness:
    """The batch fitness the GA calls: (4-1) summed over the training cases, each chromosome
    scored with the same update-order seeds (the mean over ``seed, seed + 1, ...`` when
    ``seeds > 1``), so that a chromosome's fitness depends on its genes only.

    Calling it with an ``(m, n_genes)`` population returns ``m`` fitnesses.

    Parameters
    ----------
    cases : sequence of Case
        The training pairs; at least one, with some targets.
    method : str or Method
        The method being tuned.
    seed : int, default 0
        First update-order seed.
    base : Params, optional
        Values of the genes the method does not use.
    solver : str or Solver, default ``DEFAULT_SOLVER``
        How the network is solved.
    seeds : int, default 1
        Update-order seeds averaged per chromosome.

    Attributes
    ----------
    target : int
        The number of target pairs over all cases (the largest fitness).
    """

    def __init__(self, cases: Sequence, method, *, seed: int = 0, base: Params | None = None,
                 solver=DEFAULT_SOLVER, seeds: int = 1):
        cases = list(cases)
        if not cases:
            raise ParameterError(message("cases", "Fitness", "at least one training pair", cases))
        if not all(hasattr(c, "prepared") and hasattr(c, "targets") and hasattr(c, "unknown")
                   for c in cases):
            raise ParameterTypeError(message("cases", "Fitness", "a sequence of Case", cases))
        if sum(len(c.targets) for c in cases) == 0:
            raise ParameterError(message("cases", "Fitness", "target pairs to learn from",
                                         "an empty target set"))
        self.cases, self.method, self.base = cases, get_method(method), base
        self.seed = check_number(seed, "seed", "Fitness", low=0, integer=True)
        self.seeds = check_number(seeds, "seeds", "Fitness", low=1, integer=True)
        self.solver = get_solver(solver, "Fitness")
        self.target = sum(len(c.targets) for c in cases)

    def params(self, chromosome) -> Params:
        """The :class:`Params` of `chromosome` (:func:`to_params` with this fitness' `base`)."""
        return to_params(self.method, chromosome, self.base)

    def __call__(self, population: np.ndarray) -> np.ndarray:
        population = np.atleast_2d(population)
        totals = self._batch(population)
        # fitnesses are integers: their sum is exact, so this is np.mean's value
        if totals is not None:
            return totals / self.seeds
        return np.array([self._fitness(self.params(c)) / self.seeds for c in population], dtype=float)

    def _batch(self, population: np.ndarray) -> np.ndarray | None:
        """The summed fitness of every chromosome in one compiled call per case
        (:func:`ismb_lab.network.kernel.fitness_runs`), as :meth:`_fitness` computes it; None where
        that path does not apply (another solver, kernel or method class, or values that Params or
        the network would refuse): the general way then raises the error."""
        solver, method = self.solver, self.method
        if not (type(solver) is NetworkSolver and solver.kernel == KERNELS[0] and type(method) in BATCHED):
            return None
        table = _table(method, population, self.base)
        if table is None:
            return None
        exact = solver.rule == RULES[0]
        seeds = np.arange(self.seed, self.seed + self.seeds, dtype=np.int64)
        totals = np.zeros(len(population), dtype=np.int64)
        for case in self.cases:
            problem = case.prepared.problem
            if problem.n_neurons == 0:
                continue
            s, c, self_c, beta = method.batch_columns(problem, table, not exact)
            crowd, neighbours = problem.topology.crowding
            if beta is None or not np.all(np.abs(beta) + 1 + 2 * (crowd + 1) + 2 * neighbours < MAX_INPUT):
                return None   # Network refuses it (_check_fits, uniqueness 1)
            codes = getattr(case, "neuron_codes", None)
            if codes is None:
                codes = Scorer(case.targets, case.unknown).neuron_codes(problem.rows, problem.cols)
            lay, least_dy = problem.topology.layout, type(method).postprocess is MethodI.postprocess
            dy = np.abs(problem.right_xy[problem.cols, 1] - problem.left_xy[problem.rows, 1]) if least_dy else _NONE
            totals += fitness_runs(
                problem.topology.packed, lay.nb_ptr, lay.nb_pair, lay.nb_idx, c, s, s if self_c is None else self_c,
                beta, exact, SCALE, 2.0, np.int64(round((-2.0 if exact else -1.0) * SCALE)), seeds,
                solver.stop_rule == STOP_RULES[0], _RUN["patience"], _RUN["max_sweeps"] * problem.n_neurons,
                np.asarray(codes, dtype=np.uint8), least_dy, problem.rows, problem.cols, problem.topology.n_left,
                problem.topology.n_right, dy)
        return totals

    def _fitness(self, params: Params) -> int:
        """``evaluate(...).fitness`` summed over the seeds, each case's network built once."""
        total = 0
        for case in self.cases:
            net = self.method.network(case.prepared.problem, params)
            for seed in range(self.seed, self.seed + self.seeds):
                correct, wrong, extra = _counts(case, self.method, params, seed, self.solver, net=net)
                total += correct - wrong - extra
        return total


def _table(method, population: np.ndarray, base: Params | None) -> dict | None:
    """Each Params field as an ``(m,)`` array over the chromosomes, as :func:`to_params` fills
    it; None unless every value passes Params' check."""
    genes = method.gene_names
    if population.ndim != 2 or population.shape[1] != len(genes) or len(population) == 0:
        return None
    population = np.asarray(population, dtype=float)
    m, base = len(population), base or method.defaults
    table = {name: getattr(base, name) for name in _FIELDS}
    table.update(zip(genes, population.T))
    for name in _FIELDS:
        value = table[name]
        if value is None:
            continue
        column = np.full(m, float(value)) if np.ndim(value) == 0 else value
        low_open = name.startswith("lambda")
        ok = np.isfinite(column) & ((column > 0) if low_open else (column >= 0) if name != "match_bias" else True)
        if not np.all(ok):
            return None
        table[name] = column
    return table


_NONE = np.zeros(0)
_RUN = {k: v.default for k, v in signature(run).parameters.items()}   # what NetworkSolver.solve leaves at run's defaults


def tune(cases: Sequence, method=DEFAULT_METHOD, *, rng=0, ga: GAConfig | None = None, seed: int = 0,
         base: Params | None = None, solver=DEFAULT_SOLVER, seeds: int = 1,
         **settings) -> Iterator[Generation]:
    """Run the GA on `cases`, yielding one :class:`~ismb_lab.tuning.genetic.Generation` per generation.

    It stops when the mean fitness reaches the number of targets, as in the thesis, or after
    ``ga.generations`` (default: the thesis' 30 chromosomes, 500 generations; `settings` override
    its fields); :func:`to_params` converts the best chromosome.  `rng` seeds the GA; each
    chromosome's fitness is the mean over `seeds` update-order seeds from `seed`, solved by
    `solver`; `base` holds the genes the method does not use.

    Parameters
    ----------
    cases : sequence of Case
        The training pairs.
    method : str or Method, default ``DEFAULT_METHOD``
        The method to tune.
    rng : int or numpy.random.Generator, default 0
        The GA's random source.
    ga : GAConfig, optional
        The GA's settings; default ``GAConfig()``.
    seed : int, default 0
        First update-order seed of the fitness.
    base : Params, optional
        Values of the genes the method does not use.
    solver : str or Solver, default ``DEFAULT_SOLVER``
        How the network is solved.
    seeds : int, default 1
        Update-order seeds averaged per chromosome.
    **settings
        :class:`GAConfig` fields overriding `ga`'s (e.g. ``generations=60``).

    Returns
    -------
    generations : iterator of Generation
        One record per generation, index 0 the initial population.
    """
    fitness = Fitness(cases, method, seed=seed, base=base, solver=solver, seeds=seeds)
    if ga is not None and not isinstance(ga, GAConfig):
        raise ParameterTypeError(message("ga", "tune", "a GAConfig", ga))
    ga = (ga or GAConfig()).updated("tune", **settings)
    return evolve(fitness, gene_bounds(fitness.method), rng=rng, config=ga, target=fitness.target)
