"""The 2-D Hopfield network (thesis ch. 3): similarity, compatibility, the energy of Methods I-III and
beyond, its exact weights, and the solvers that minimise it.
"""

from .similarity import (MAX_CANDIDATE_PAIRS, MAX_WINDOW_VALUES, candidate_mask, mean_abs_difference, no_match_cut, patches,
    transfer)
from .compatibility import left_neighbours, neuron_pairs, NeuronPairs
from .params import (LAMBDA_C, LAMBDA_S, MATCH_BIAS, MAX_BIAS, MAX_LAMBDA, MAX_THETA, THETA_C, THETA_S, Gene, Params)
from .methods import (BATCHED, all_genes, Method, MethodI, MethodII, MethodIII, MethodNM, MethodNM3, MethodNM4,
    DEFAULT_METHOD, Problem, THESIS_PARAMS, build_problem, get_method, method_names, register_method,
    unregister_method)
from .hopfield import MAX_INPUT, MAX_NEURONS, RULES, SCALE, energy, hopfield_form, Network, Topology
from .kernel import fitness_runs, run_network
from .dynamics import KERNELS, STOP_RULES, iter_updates, run, RunResult, Update, visiting_order
from .annealing import MAX_SWEEPS, anneal, AnnealResult, AnnealStep, iter_annealing
from .exact import MAX_EXHAUSTIVE, MAX_TIME_LIMIT, exhaustive_minimum, milp_minimum, Minimum
from .solvers import (ANNEAL, ASSIGN, DEFAULT_SOLVER, EXACT, NETWORK, SOLVERS, AnnealSolver, AssignSolver, ExactSolver,
    Matches, NetworkSolver, Solution, Solver, get_solver, matched_neurons, one_match_per_corner,
    register_solver, similarity_assignment, solve, solver_names, to_matches, unregister_solver)

__all__ = ["ANNEAL", "ASSIGN", "AnnealResult", "AnnealSolver", "AnnealStep", "AssignSolver", "BATCHED",
           "DEFAULT_METHOD", "DEFAULT_SOLVER", "EXACT", "ExactSolver", "Gene", "KERNELS", "LAMBDA_C",
           "LAMBDA_S", "MATCH_BIAS", "MAX_BIAS", "MAX_CANDIDATE_PAIRS", "MAX_EXHAUSTIVE", "MAX_INPUT",
           "MAX_LAMBDA", "MAX_NEURONS", "MAX_SWEEPS", "MAX_THETA", "MAX_TIME_LIMIT", "MAX_WINDOW_VALUES",
           "Matches", "Method", "MethodI", "MethodII", "MethodIII", "MethodNM", "MethodNM3", "MethodNM4",
           "Minimum", "NETWORK", "Network", "NetworkSolver", "NeuronPairs", "Params", "Problem", "RULES",
           "RunResult", "SCALE", "SOLVERS", "STOP_RULES", "Solution", "Solver", "THESIS_PARAMS", "THETA_C",
           "THETA_S", "Topology", "Update", "all_genes", "anneal", "build_problem", "candidate_mask", "energy",
           "exhaustive_minimum", "fitness_runs", "get_method", "get_solver", "hopfield_form", "iter_annealing",
           "iter_updates", "left_neighbours", "matched_neurons", "mean_abs_difference", "method_names",
           "milp_minimum", "neuron_pairs", "no_match_cut", "one_match_per_corner", "patches",
           "register_method", "register_solver", "run", "run_network", "similarity_assignment",
           "solve", "solver_names", "to_matches", "transfer", "unregister_method", "unregister_solver",
           "visiting_order"]
