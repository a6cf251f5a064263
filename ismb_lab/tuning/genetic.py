"""A real-coded genetic algorithm (thesis chapter 4) maximising a batch fitness within :class:`Bounds`.

The fitness maps ``(m, n_genes)`` chromosomes to ``(m,)`` (:func:`batch` wraps a per-chromosome
score).  One generation (§4.2): evaluate the changed chromosomes; keep the ``n_elite`` best,
then binary-tournament winners; draw one λ ~ U[0, 1) and cross the winners in order, pair by
pair, with probability p_c; each child mutates one gene with probability p_m.

Where the thesis is ambiguous: winners are independent draws, so pairing them in order is a
random pairing (an odd one is copied); only crossover children mutate; children replace their
parents (the size stays constant); a tournament draws two distinct indices, a tie keeps the
first; a mutated gene is drawn within its bounds; the GA stops when ``mean >= target`` on an
evaluated population.  The fitness must be deterministic: unchanged chromosomes keep theirs.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Callable, Iterator

import numpy as np

from .._core.validation import ParameterError, ParameterTypeError, check_number, check_rng, message, readonly

__all__ = ["Bounds", "GAConfig", "Generation", "arithmetic_crossover", "batch", "elite", "evolve",
           "initial_population", "next_generation", "random_mutation", "tournament"]


@dataclass(frozen=True)
class GAConfig:
    """The GA's settings; the defaults are the thesis' (§4.2, §5.2.1).

    Attributes
    ----------
    population : int, default 30
        Chromosomes per generation, 2 to :data:`MAX_POPULATION`.
    generations : int, default 500
        The last generation's index.
    p_crossover : float, default 0.8
        Probability that a pair of tournament winners is crossed.
    p_mutation : float, default 0.05
        Probability that a crossed child mutates.
    n_elite : int, default 2
        Best chromosomes copied unchanged into the next generation.

    Examples
    --------
    >>> GAConfig()
    GAConfig(population=30, generations=500, p_crossover=0.8, p_mutation=0.05, n_elite=2)
    >>> GAConfig().updated("tune", generations=60, population=None).generations
    60
    >>> GAConfig(population=1)
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'population' parameter of GAConfig must be an integer >= 2 and <= 100000. Got 1 instead.
    """

    population: int = 30
    generations: int = 500
    p_crossover: float = 0.8
    p_mutation: float = 0.05
    n_elite: int = 2

    def __post_init__(self):
        for name, value in _check_settings(asdict(self), "GAConfig").items():
            object.__setattr__(self, name, value)

    def updated(self, owner: str, **changes) -> "GAConfig":
        """A copy with the `changes` that are not None, checked in the name of `owner`."""
        unknown = sorted(set(changes) - {f.name for f in fields(self)})
        if unknown:
            raise ParameterTypeError(message("settings", owner, "GAConfig fields", unknown))
        values = {**asdict(self), **{k: v for k, v in changes.items() if v is not None}}
        return GAConfig(**_check_settings(values, owner))


#: The largest population :class:`GAConfig` accepts.
MAX_POPULATION = 100_000


def _check_settings(values: dict, owner: str) -> dict:
    # each chromosome is a row of the population array: a bound keeps a typo from asking for
    # an array no machine holds (the thesis uses 30)
    size = check_number(values["population"], "population", owner, low=2, high=MAX_POPULATION, integer=True)
    return {"population": size,
            "generations": check_number(values["generations"], "generations", owner, low=1, integer=True),
            "p_crossover": check_number(values["p_crossover"], "p_crossover", owner, low=0, high=1),
            "p_mutation": check_number(values["p_mutation"], "p_mutation", owner, low=0, high=1),
            "n_elite": check_number(values["n_elite"], "n_elite", owner, low=0, high=size, integer=True)}


@dataclass(frozen=True, eq=False)
class Bounds:
    """Per-gene search interval ``low[i] <= gene i <= high[i]`` (read-only arrays).

    >>> Bounds([0, 0], [50, 10], names=("theta_c", "lambda_c")).n_genes
    2
    >>> Bounds([0, 2], [1, 1])
    Traceback (most recent call last):
    ...
    ismb_lab.ParameterError: The 'bounds' parameter of Bounds must be low < high for every gene.
    Got 'gene 1: low=2.0, high=1.0' instead.
    """

    low: np.ndarray
    high: np.ndarray
    names: tuple[str, ...] | None = None

    def __post_init__(self):
        size = np.size(self.low)
        for name, value in (("low", self.low), ("high", self.high)):
            rule = "a non-empty 1-D array of finite numbers" + (", as long as low" if name == "high" else "")
            try:
                arr = readonly(value)
            except (TypeError, ValueError):
                raise ParameterTypeError(message(name, "Bounds", rule, value)) from None
            if arr.ndim != 1 or arr.size == 0 or arr.size != size or not np.all(np.isfinite(arr)):
                raise ParameterError(message(name, "Bounds", rule, value))
            object.__setattr__(self, name, arr)
        bad = np.flatnonzero(self.low >= self.high)
        if bad.size:
            i = int(bad[0])
            raise ParameterError(message("bounds", "Bounds", "low < high for every gene",
                                         f"gene {i}: low={float(self.low[i])}, high={float(self.high[i])}"))
        if self.names is not None:
            names = tuple(self.names)
            if len(names) != size or not all(isinstance(n, str) for n in names):
                raise ParameterError(message("names", "Bounds", f"{size} strings", self.names))
            object.__setattr__(self, "names", names)

    @property
    def n_genes(self) -> int:
        """The number of genes."""
        return int(self.low.size)


@dataclass(frozen=True, eq=False)
class Generation:
    """The record of one evaluated generation (index 0 is the initial population).

    ``evaluations`` counts the chromosomes evaluated so far; ``population`` and ``fitness`` are
    None unless ``keep_population=True``.  Arrays are read-only copies.

    >>> Generation(0, 1.0, 0.5, 0.0, [0.2, 0.3], None, None, 30).best_chromosome
    array([0.2, 0.3])
    """

    index: int
    best: float
    mean: float
    worst: float
    best_chromosome: np.ndarray
    population: np.ndarray | None
    fitness: np.ndarray | None
    evaluations: int

    def __post_init__(self):
        for name in ("best_chromosome", "population", "fitness"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, readonly(getattr(self, name)))

    @classmethod
    def _of(cls, *values) -> "Generation":
        """The same record without the frozen ``__init__``'s ``object.__setattr__`` calls."""
        g = object.__new__(cls)
        d = g.__dict__
        for f, value in zip(fields(cls), values):
            d[f.name] = readonly(value) if f.name in _ARRAYS and value is not None else value
        return g


_ARRAYS = ("best_chromosome", "population", "fitness")


def _check_bounds(bounds, owner: str) -> Bounds:
    if isinstance(bounds, Bounds):
        return bounds
    raise ParameterTypeError(message("bounds", owner, "a Bounds", bounds))


def _scores(values, owner: str, rule: str, ok=lambda n: n > 0) -> np.ndarray:
    """Check fitness values: a finite 1-D array whose length passes `ok`."""
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterTypeError(message("fitness", owner, rule, values)) from None
    if arr.ndim != 1 or not ok(arr.size):
        raise ParameterError(message("fitness", owner, rule, f"an array of shape {arr.shape}"))
    if not np.all(np.isfinite(arr)):
        raise ParameterError(message("fitness", owner, rule, arr))
    return arr


def batch(score: Callable) -> Callable:
    """Turn a per-chromosome ``score(chromosome) -> float`` into a batch fitness.

    >>> batch(lambda c: float(c.sum()))(np.array([[1.0, 2.0], [0.0, 0.5]]))
    array([3. , 0.5])
    """
    if not callable(score):
        raise ParameterTypeError(message("score", "batch", "a callable", score))
    return lambda chromosomes: np.array([score(c) for c in chromosomes], dtype=float)


def initial_population(rng, bounds: Bounds, size: int) -> np.ndarray:
    """Draw ``size`` chromosomes uniformly within `bounds`: a ``(size, n_genes)`` array.

    Parameters
    ----------
    rng : int or numpy.random.Generator
        Random source.
    bounds : Bounds
        The search box.
    size : int
        Number of chromosomes, >= 1.

    Returns
    -------
    population : (size, n_genes) float ndarray
        The chromosomes.

    Examples
    --------
    >>> initial_population(0, Bounds([0, 10], [1, 20]), 3).shape
    (3, 2)
    """
    rng = check_rng(rng, "rng", "initial_population")
    bounds = _check_bounds(bounds, "initial_population")
    size = check_number(size, "size", "initial_population", low=1, integer=True)
    return rng.uniform(bounds.low, bounds.high, size=(size, bounds.n_genes))


def arithmetic_crossover(a, b, lam: float):
    """Children ``lam*a + (1-lam)*b`` and ``lam*b + (1-lam)*a`` (thesis §4.1).

    Parameters
    ----------
    a, b : float array_like
        The two parents, of one shape.
    lam : float
        Mixing weight in [0, 1].

    Returns
    -------
    children : (ndarray, ndarray) tuple
        The two children.

    Examples
    --------
    >>> arithmetic_crossover([0.0, 4.0], [2.0, 0.0], 0.25)
    (array([1.5, 1. ]), array([0.5, 3. ]))
    """
    lam = check_number(lam, "lam", "arithmetic_crossover", low=0, high=1)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        raise ParameterError(message("b", "arithmetic_crossover", f"an array of shape {a.shape}, like a",
                                     f"an array of shape {b.shape}"))
    return lam * a + (1 - lam) * b, lam * b + (1 - lam) * a


def random_mutation(rng, chromosome, bounds: Bounds) -> np.ndarray:
    """Return a copy with one uniformly chosen gene redrawn uniformly within its bounds.

    Parameters
    ----------
    rng : int or numpy.random.Generator
        Random source.
    chromosome : (n_genes,) float array_like
        The chromosome to mutate (not changed).
    bounds : Bounds
        The search box.

    Returns
    -------
    child : (n_genes,) float ndarray
        The mutated copy.

    Examples
    --------
    >>> child = random_mutation(0, [0.5, 0.5, 0.5], Bounds([0, 0, 0], [1, 1, 1]))
    >>> int(np.sum(child != 0.5))
    1
    """
    rng = check_rng(rng, "rng", "random_mutation")
    bounds = _check_bounds(bounds, "random_mutation")
    child, shape = np.array(chromosome, dtype=float), (bounds.n_genes,)
    if child.shape != shape:
        raise ParameterError(message("chromosome", "random_mutation", f"an array of shape {shape}",
                                     f"an array of shape {child.shape}"))
    gene = rng.integers(bounds.n_genes)
    child[gene] = rng.uniform(bounds.low[gene], bounds.high[gene])
    return child


def tournament(rng, fitness, k: int) -> np.ndarray:
    """Indices of `k` binary-tournament winners: two distinct indices each (the first drawn
    from all, the second from the others), the fitter kept, the first on a tie.

    Parameters
    ----------
    rng : int or numpy.random.Generator
        Random source.
    fitness : (m,) float array_like
        Fitness of each chromosome, m >= 2.
    k : int
        Number of winners, >= 0.

    Returns
    -------
    winners : (k,) int ndarray
        Indices of the winners.

    Examples
    --------
    >>> bool(np.all(tournament(0, [0.0, 1.0, 2.0], 100) > 0))
    True
    """
    rng = check_rng(rng, "rng", "tournament")
    fitness = _scores(fitness, "tournament", "a 1-D array of >= 2 finite numbers", lambda n: n >= 2)
    k = check_number(k, "k", "tournament", low=0, integer=True)
    first = rng.integers(fitness.size, size=k)
    second = rng.integers(fitness.size - 1, size=k)
    second += second >= first
    return np.where(fitness[second] > fitness[first], second, first)


def elite(fitness, n: int = 2) -> np.ndarray:
    """Indices of the `n` fittest chromosomes, best first; ties go to the lower index.

    Parameters
    ----------
    fitness : (m,) float array_like
        Fitness of each chromosome.
    n : int, default 2
        How many to keep, 0 to m.

    Returns
    -------
    indices : (n,) int ndarray
        The fittest, best first.

    Examples
    --------
    >>> elite([1.0, 3.0, 3.0, 0.0], 3)
    array([1, 2, 0])
    """
    fitness = _scores(fitness, "elite", "a non-empty 1-D array of finite numbers")
    n = check_number(n, "n", "elite", low=0, high=fitness.size, integer=True)
    return np.argsort(-fitness, kind="stable")[:n]


def _breed(rng, population, fitness, bounds, p_c, p_m, n_elite):
    """The next population and, per row, its unchanged source row (-1 if new): the steps of
    :func:`elite`, :func:`tournament`, :func:`arithmetic_crossover` and :func:`random_mutation`
    with the same draws and arithmetic, without their checks (they cost more than the selection)."""
    size = len(population)
    k = size - n_elite
    first = rng.integers(size, size=k)
    second = rng.integers(size - 1, size=k)
    second += second >= first
    origin = np.concatenate([np.argsort(-fitness, kind="stable")[:n_elite],
                             np.where(fitness[second] > fitness[first], second, first)])
    children = population[origin]
    lam = rng.random()
    first = n_elite + 2 * np.flatnonzero(rng.random(k // 2) < p_c)
    a, b = children[first], children[first + 1]
    children[first], children[first + 1] = lam * a + (1 - lam) * b, lam * b + (1 - lam) * a
    crossed = np.empty(2 * len(first), dtype=np.int64)
    crossed[0::2], crossed[1::2] = first, first + 1   # ascending, as np.sort would give
    origin[crossed] = -1
    for i in crossed[rng.random(crossed.size) < p_m].tolist():
        gene = rng.integers(bounds.n_genes)
        children[i, gene] = rng.uniform(bounds.low[gene], bounds.high[gene])
    return children, origin


def next_generation(rng, population, fitness, bounds: Bounds, *, p_crossover: float | None = None,
                    p_mutation: float | None = None, n_elite: int | None = None) -> np.ndarray:
    """Selection, crossover and mutation of one generation (§4.2); rates left at None take
    :class:`GAConfig`'s defaults.

    >>> pop = np.array([[0.1], [0.9], [0.5], [0.3]])
    >>> new = next_generation(0, pop, [1.0, 4.0, 3.0, 2.0], Bounds([0], [1]))
    >>> new.shape, new[:2].ravel().tolist()
    ((4, 1), [0.9, 0.5])
    """
    owner = "next_generation"
    rng = check_rng(rng, "rng", owner)
    bounds = _check_bounds(bounds, owner)
    pop = np.asarray(population, dtype=float)
    if pop.ndim != 2 or pop.shape[1] != bounds.n_genes or len(pop) < 2:
        raise ParameterError(message("population", owner, f"an (m >= 2, {bounds.n_genes}) array",
                                     f"an array of shape {pop.shape}"))
    size = len(pop)
    fitness = _scores(fitness, owner, f"{size} finite numbers, one per chromosome", lambda n: n == size)
    ga = GAConfig(population=size).updated(owner, p_crossover=p_crossover, p_mutation=p_mutation,
                                           n_elite=n_elite)
    return _breed(rng, pop, fitness, bounds, ga.p_crossover, ga.p_mutation, ga.n_elite)[0]


def evolve(fitness: Callable, bounds: Bounds, *, rng, config: GAConfig | None = None,
           target: float | None = None, keep_population: bool = False,
           **settings) -> Iterator[Generation]:
    """Maximise `fitness` (an ``(m, n_genes)`` array -> ``m`` finite numbers) within `bounds`,
    yielding one :class:`Generation` per generation.

    The arguments are checked at once; a generation is bred only when its record is asked for,
    so a consumer stops the GA by not iterating further.  `rng` is the only source of randomness;
    `target` stops after the first generation whose mean fitness reaches it; `settings` are
    GAConfig fields that override `config` (None keeps its value).

    Parameters
    ----------
    fitness : callable
        Batch fitness: ``(m, n_genes)`` array -> ``m`` finite numbers, larger is better.
    bounds : Bounds
        The search box.
    rng : int or numpy.random.Generator
        The GA's random source.
    config : GAConfig, optional
        The GA's settings; default ``GAConfig()``.
    target : float, optional
        Stop after the first generation whose mean fitness reaches it.
    keep_population : bool, default False
        Keep each generation's population and fitnesses in its record.
    **settings
        GAConfig fields overriding `config`'s.

    Returns
    -------
    generations : iterator of Generation
        One record per generation, bred lazily.

    Examples
    --------
    >>> sphere = lambda pop: -np.sum((pop - 0.3) ** 2, axis=1)
    >>> runs = list(evolve(sphere, Bounds([-1, -1], [1, 1]), rng=0, generations=40))
    >>> runs[-1].index, runs[-1].best > -1e-3, runs[-1].best >= runs[0].best
    (40, True, True)
    """
    owner = "evolve"
    if not callable(fitness):
        raise ParameterTypeError(message("fitness", owner, "a callable", fitness))
    bounds = _check_bounds(bounds, owner)
    rng = check_rng(rng, "rng", owner)
    if config is not None and not isinstance(config, GAConfig):
        raise ParameterTypeError(message("config", owner, "a GAConfig", config))
    ga = (config or GAConfig()).updated(owner, **settings)
    target = None if target is None else check_number(target, "target", owner)
    if not isinstance(keep_population, bool):
        raise ParameterTypeError(message("keep_population", owner, "a bool", keep_population))
    rates = ga.p_crossover, ga.p_mutation, ga.n_elite
    return _run(fitness, bounds, rng, ga.population, ga.generations, target, rates, keep_population)


def _run(fitness, bounds, rng, size, generations, target, rates, keep) -> Iterator[Generation]:
    pop, scores, new, count = initial_population(rng, bounds, size), np.empty(size), np.ones(size, bool), 0
    rule = "a callable returning one finite number per chromosome"
    for index in range(generations + 1):
        if index:
            pop, origin = _breed(rng, pop, scores, bounds, *rates)
            scores, new = scores[origin], origin < 0  # rows with origin -1 are overwritten below
        changed = np.flatnonzero(new)
        if changed.size:
            scores[changed] = _scores(fitness(pop[changed]), "evolve", rule, lambda n: n == changed.size)
            count += changed.size
        best, mean = int(np.argmax(scores)), float(scores.mean())
        yield Generation._of(index, float(scores[best]), mean, float(scores.min()), pop[best],
                             pop if keep else None, scores if keep else None, count)
        if target is not None and mean >= target:
            return
