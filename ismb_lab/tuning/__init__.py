"""Scoring matches against targets, the real-coded GA (thesis ch. 4) and the train/test protocol.
"""

from .evaluation import Score, Scorer, score, unlabelled
from .genetic import (Bounds, GAConfig, Generation, arithmetic_crossover, batch, elite, evolve, initial_population,
    next_generation, random_mutation, tournament)
from .fitness import Fitness, evaluate, gene_bounds, to_chromosome, to_params, tune
from .cases import (SOURCES, Case, PairReport, PeerReport, ProtocolReport, SolverReport, Spread, family_cases,
    format_protocol, load_manifest, protocol)

__all__ = ["Bounds", "Case", "Fitness", "GAConfig", "Generation", "PairReport", "PeerReport", "ProtocolReport",
           "SOURCES", "Score", "Scorer", "SolverReport", "Spread", "arithmetic_crossover", "batch", "elite",
           "evaluate", "evolve", "family_cases", "format_protocol", "gene_bounds", "initial_population",
           "load_manifest", "next_generation", "protocol", "random_mutation", "score", "to_chromosome",
           "to_params", "tournament", "tune", "unlabelled"]
