"""Tuning the energy parameters with the GA: chromosome <-> Params, fitness n_c - n_e (ch. 4).

The GA in :mod:`ismb_lab.genetic` knows nothing of stereo; this module gives it a
fitness.  A chromosome is ``[theta_c, lambda_c]`` for Method-I,
``[theta_c, theta_s, lambda_c, lambda_s]`` for Methods II and III (the thesis'
order) and the same plus ``match_bias`` for Method-NM.  Its fitness (4-1) is
``n_c - n_e`` summed over every training pair.

Gene bounds
-----------
* ``theta_c`` in [0, 60] px: ``X`` is a sum of pixel differences.  Correct pairs of
  neighbours have ``X`` of a few pixels and wrong ones tens (measured on the
  synthetic scenes: median 0 against 22); 60 px already calls almost everything
  compatible.  The thesis' values, 7.45 to 41.57, lie inside.
* ``theta_s`` in [0, 60] grey levels: ``M`` of true matches is about 5, of false
  ones about 45 on the synthetic scenes.
* ``lambda_c``, ``lambda_s`` in [0.05, 10]: from an almost flat transfer function to
  a step one pixel wide (the thesis found 1.16 to 8.89).
* ``match_bias`` (Method-NM's fifth gene) in [-2, 2]: the preferred number of
  matches per feature ``h = 1/2 + beta / 4`` runs from 0 (a match must pay 2 from
  ``S`` and ``C``) through 1/2 ("at most one", ``beta = 0``) to 1 (exactly one: the
  thesis).  ``S`` is in [-1, 1] and one compatible neighbour adds up to 2, so a
  wider range only repeats the ends.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Iterator, Sequence

import numpy as np

from ._validation import ParameterError, ParameterTypeError, check_choice, check_number, message
from .evaluation import Score, score
from .genetic import Bounds, Generation, evolve
from .hopfield import run
from .matching import Prepared
from .methods import Method, Params, get_method

_DEFAULT = Params()
GENE_BOUNDS = {"theta_c": (0.0, 60.0), "theta_s": (0.0, 60.0),
               "lambda_c": (0.05, 10.0), "lambda_s": (0.05, 10.0), "match_bias": (-2.0, 2.0)}


def gene_bounds(method) -> Bounds:
    """The GA's search box for a method's genes.

    Examples
    --------
    >>> gene_bounds("I").names
    ('theta_c', 'lambda_c')
    """
    genes = get_method(method).genes
    return Bounds(low=[GENE_BOUNDS[g][0] for g in genes], high=[GENE_BOUNDS[g][1] for g in genes],
                  names=genes)


def to_params(method, chromosome, base: Params | None = None) -> Params:
    """Chromosome to parameters; genes a method does not use keep `base`'s values.

    Examples
    --------
    >>> to_params("I", [41.57, 4.40])
    Params(theta_c=41.57, theta_s=24.02, lambda_c=4.4, lambda_s=2.2)
    """
    genes = get_method(method).genes
    chromosome = np.asarray(chromosome, dtype=float).ravel()
    if len(chromosome) != len(genes):
        raise ParameterError(message("chromosome", "to_params", f"{len(genes)} genes {genes}",
                                     chromosome.tolist()))
    return replace(base or _DEFAULT, **dict(zip(genes, chromosome.tolist())))


def to_chromosome(method, params: Params) -> np.ndarray:
    """Parameters to the method's chromosome.

    Examples
    --------
    >>> to_chromosome("III", Params()).tolist()
    [17.97, 24.02, 6.37, 2.2]
    """
    return np.array([getattr(params, g) for g in get_method(method).genes])


@dataclass(frozen=True, eq=False)
class Case:
    """One training pair: its prepared features and the targets as feature pairs.

    Attributes
    ----------
    prepared : Prepared
    targets : (t, 2) int ndarray
        Target ``(i, k)`` feature indices.
    unknown : (u,) int ndarray
        Left features whose truth is unknown (matches there are not scored).
    name : str
    """

    prepared: Prepared
    targets: np.ndarray
    unknown: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    name: str = ""


#: How a network's final state is found: the discrete network of the thesis, mean-field
#: annealing (:mod:`ismb_lab.annealing`) or the exact global minimum (:mod:`ismb_lab.exact`, MILP).
SOLVERS = ("network", "anneal", "exact")


def solve(problem, method: Method, params: Params, seed: int = 0, solver: str = "network",
          **run_kwargs) -> np.ndarray:
    """The matched ``(i, k)`` pairs of one run (no bookkeeping: the GA's inner loop).

    `solver` is one of :data:`SOLVERS`; ``"exact"`` ignores `seed`.
    """
    net = method.network(problem, params)
    if solver == "network":
        state = run(net, rng=seed, **run_kwargs).state
    elif solver == "anneal":
        from .annealing import anneal
        state = anneal(net, rng=seed).state
    else:
        from .exact import milp_minimum
        state = milp_minimum(net).state
    on = np.flatnonzero(method.postprocess(problem, state))
    return np.stack([problem.rows[on], problem.cols[on]], axis=1)


def evaluate(cases: Sequence[Case], method, params: Params, seed: int = 0,
             solver: str = "network") -> Score:
    """The summed C/E/T of `params` over `cases`."""
    m = get_method(method)
    check_choice(solver, "solver", "evaluate", SOLVERS)
    total = Score(0, 0, 0, 0)
    for case in cases:
        total = total + score(solve(case.prepared.problem, m, params, seed, solver), case.targets,
                              case.unknown)
    return total


class Fitness:
    """The batch fitness the GA calls: (4-1) summed over the training cases.

    Every chromosome is scored with the same update-order seed(s), so a chromosome's
    fitness is a deterministic function of its genes.  With ``seeds > 1`` the
    fitness is the mean over seeds ``seed, seed + 1, ...``: parameters that only
    work for one visiting order score lower.
    """

    def __init__(self, cases: Sequence[Case], method, *, seed: int = 0, base: Params | None = None,
                 solver: str = "network", seeds: int = 1):
        cases = list(cases)
        if not cases:
            raise ParameterError(message("cases", "Fitness", "at least one training pair", cases))
        if not all(isinstance(c, Case) for c in cases):
            raise ParameterTypeError(message("cases", "Fitness", "a sequence of Case", cases))
        if sum(len(c.targets) for c in cases) == 0:
            raise ParameterError(message("cases", "Fitness", "target pairs to learn from",
                                         "an empty target set"))
        self.cases, self.method, self.base = cases, get_method(method), base
        self.seed = check_number(seed, "seed", "Fitness", low=0, integer=True)
        self.seeds = check_number(seeds, "seeds", "Fitness", low=1, integer=True)
        self.solver = check_choice(solver, "solver", "Fitness", SOLVERS)
        self.target = sum(len(c.targets) for c in cases)

    def params(self, chromosome) -> Params:
        return to_params(self.method, chromosome, self.base)

    def __call__(self, population: np.ndarray) -> np.ndarray:
        return np.array([np.mean([evaluate(self.cases, self.method, self.params(c), self.seed + s,
                                           self.solver).fitness for s in range(self.seeds)])
                         for c in np.atleast_2d(population)], dtype=float)


def tune(cases: Sequence[Case], method="III", *, rng=0, population: int = 30,
         generations: int = 500, seed: int = 0, base: Params | None = None,
         solver: str = "network", seeds: int = 1) -> Iterator[Generation]:
    """Run the GA on `cases`, yielding one :class:`~ismb_lab.genetic.Generation` per generation.

    It stops when the mean fitness reaches the number of targets (every
    chromosome reproduces the targets exactly), as in the thesis, or after
    `generations` generations.  Convert the best chromosome with :func:`to_params`.

    Parameters
    ----------
    cases : sequence of Case
        Training pairs; their fitness is summed.
    method : {"I", "II", "III", "NM"}
    rng : int or numpy.random.Generator
        Seed of the GA.
    population, generations : int
        GA size (thesis: 30 and 500).
    seed : int
        Update-order seed of every network run.
    base : Params, optional
        Values of the genes the method does not use.
    solver : {"network", "anneal", "exact"}
        How each network is solved (see :data:`SOLVERS`).
    seeds : int
        Update-order seeds each chromosome is scored over (mean fitness).
    """
    fitness = Fitness(cases, method, seed=seed, base=base, solver=solver, seeds=seeds)
    return evolve(fitness, gene_bounds(method), rng=rng, population=population,
                  generations=generations, target=fitness.target)
