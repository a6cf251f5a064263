"""Trials on the scene families: cleanups of a fitted variant's matches, the kinds of its errors,
and NM3 with its cleanup inside the GA's fitness.

Their figures are the third and fourth records of ``docs/experiments/2026-11-24-matching-families.md``.

Each family's GA is fitted as ``matching_families.py`` fits the chosen variant (annealing for
fitting and testing, each chromosome over 3 update orders, 200 generations, GA seeds 0-2, the
training pair alone); the other pairs are then solved with annealing, update seeds 0-2.

    python scripts/matching_trials.py cleanups --method NM4 --seeds-from 3000   # the cleanups' rows
    python scripts/matching_trials.py errors --method NM4 --seeds-from 3000     # errors by kind
    python scripts/matching_trials.py fitted-cleanup --seeds-from 3000          # NM3, cleanup in the fitness

``cleanups`` scores every test pair's matches as they are and after keeping one match per
corner by: the largest net input u; u without the uniqueness terms ("evidence"); the largest
S; the smallest M (``one_match_per_corner``, the library's ``--one-to-one``); the smallest
|dy|; an assignment of largest total evidence; or dropping every doubled match; and, after
the u cleanup, vetoes of matches with S <= 0, S <= -0.5, S <= -0.9, M >= 1.5 theta_s and
M >= 2 theta_s.  ``errors`` counts, at update seed 0, second matches (a corner matched twice),
single wrong partners and single matches of corners whose partner was not detected.
Times on this 2-core machine, one run alone: 3000- about 1.5 min per command, 2000- about
6 min (its repetitive family is slow to fit).  Development splits only: 2000- and 3000-.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import linear_sum_assignment

from ismb_lab.tuning.evaluation import score
from ismb_lab.network.hopfield import hopfield_form
from ismb_lab.network.methods import MethodNM3, get_method, method_names, register_method
from ismb_lab.tuning.cases import family_cases, protocol
from ismb_lab.scenes import FAMILIES
from ismb_lab.network.solvers import matched_neurons, one_match_per_corner, solve

CLEANUPS = ("none", "u", "evidence", "S", "M", "dy", "drop doubled", "assignment",
            "u, S > 0", "u, S > -0.5", "u, S > -0.9", "u, M < 1.5 theta_s", "u, M < 2 theta_s")


class NM3FittedCleanup(MethodNM3):
    """Method-NM3 with one match per corner (smallest M) as its post-processing, so that the
    GA's fitness applies it too (a trial, not registered by the library)."""

    name = "NM3-fitted-cleanup"
    description = "Method-NM3, one match per corner inside the GA's fitness (trial)"

    def postprocess(self, problem, on):
        return one_match_per_corner(problem, on)


def fits(method: str, start: int):
    """``(family, GA seed, cases, fitted params)`` of every family and GA seed 0-2."""
    for n, family in enumerate(FAMILIES):
        cases = family_cases(family, start + 100 * n, 12)
        for ga_seed in range(3):
            report = protocol(cases, method, generations=200, seeds=3, solver="anneal", fit_solver="anneal",
                              rng=ga_seed, fit_seeds=3, fit_all=False)
            yield family, ga_seed, cases, report.params


def cleaned(problem, net, state, method, params) -> dict:
    """Each cleanup's kept neurons."""
    on = np.asarray(matched_neurons(problem, state, method), dtype=np.int64)
    rows, cols = problem.rows, problem.cols
    W, bias = hopfield_form(net)
    support = W.copy()
    support[W == -2.0 * net.uniqueness] = 0.0        # the uniqueness weights; C is never exactly -1 here
    u, evidence = bias + W @ state, bias + support @ state
    M, S = problem.neuron_dissimilarity, net.similarity
    dy = np.abs(problem.right_xy[cols, 1] - problem.left_xy[rows, 1])
    orders = {"u": -u[on], "evidence": -evidence[on], "S": -S[on], "M": M[on], "dy": dy[on]}
    out = {"none": on} | {name: one_match_per_corner(problem, on, key) for name, key in orders.items()}
    left, right = np.bincount(rows[on], minlength=len(problem.left_xy)), np.bincount(cols[on], minlength=len(problem.right_xy))
    out["drop doubled"] = on[(left[rows[on]] == 1) & (right[cols[on]] == 1)]
    if len(on):
        li, ki = np.unique(rows[on], return_inverse=True), np.unique(cols[on], return_inverse=True)
        gain = np.full((len(li[0]), len(ki[0])), -1e9)
        gain[li[1], ki[1]] = evidence[on]
        a, b = linear_sum_assignment(gain, maximize=True)
        chosen = {(li[0][i], ki[0][k]) for i, k in zip(a, b) if gain[i, k] > -1e8}
        out["assignment"] = np.array([n for n in on if (rows[n], cols[n]) in chosen], dtype=np.int64)
    else:
        out["assignment"] = on
    by_u = out["u"]
    theta_s = problem.no_match_cut if method.name == "NM3" else params.theta_s
    for name, keep in (("u, S > 0", S[by_u] > 0), ("u, S > -0.5", S[by_u] > -0.5), ("u, S > -0.9", S[by_u] > -0.9),
                       ("u, M < 1.5 theta_s", M[by_u] < 1.5 * theta_s), ("u, M < 2 theta_s", M[by_u] < 2 * theta_s)):
        out[name] = by_u[keep]
    return out


def cleanups(method: str, start: int) -> None:
    m = get_method(method)
    totals = {name: {} for name in CLEANUPS}
    for family, _, cases, params in fits(method, start):
        for case in cases[1:]:
            p = case.prepared.problem
            net = m.network(p, params)
            for seed in range(3):
                for name, kept in cleaned(p, net, solve(net, "anneal", seed=seed).state, m, params).items():
                    s = score(np.stack([p.rows[kept], p.cols[kept]], axis=1), case.targets, case.unknown)
                    t = totals[name].setdefault(family, [0, 0, 0])
                    t[0], t[1], t[2] = t[0] + s.correct, t[1] + s.errors, t[2] + s.targets
    for name in CLEANUPS:
        c, e, t = (sum(v[i] for v in totals[name].values()) for i in range(3))
        per = "  ".join(f"{f} {100 * v[0] / v[2]:.1f}/{100 * v[0] / max(v[0] + v[1], 1):.1f}"
                        for f, v in totals[name].items())
        print(f"{name:>20}: C/T {100 * c / t:5.1f}%  precision {100 * c / max(c + e, 1):5.1f}%  "
              f"[C {c} E {e} T {t}]   {per}")


def errors(method: str, start: int) -> None:
    m = get_method(method)
    kinds = {}
    for family, _, cases, params in fits(method, start):
        row = kinds.setdefault(family, {"second": 0, "wrong partner": 0, "no partner": 0})
        for case in cases[1:]:
            p = case.prepared.problem
            on = np.asarray(matched_neurons(p, solve(m.network(p, params), "anneal", seed=0).state, m))
            partner, skip = dict(case.targets.tolist()), set(np.asarray(case.unknown).ravel().tolist())
            left = np.bincount(p.rows[on], minlength=len(p.left_xy))
            right = np.bincount(p.cols[on], minlength=len(p.right_xy))
            for a in on.tolist():
                i, k = int(p.rows[a]), int(p.cols[a])
                if partner.get(i) == k or (i not in partner and i in skip):
                    continue
                row["second" if left[i] > 1 or right[k] > 1 else "wrong partner" if i in partner else "no partner"] += 1
    for family, row in kinds.items():
        print(f"{family:>10}: " + ", ".join(f"{v} {k}" for k, v in row.items()))
    print("all: " + ", ".join(f"{sum(r[k] for r in kinds.values())} {k}" for k in ("second", "wrong partner", "no partner")))


def fitted_cleanup(start: int) -> None:
    if NM3FittedCleanup.name not in method_names():
        register_method(NM3FittedCleanup())
    c = e = t = 0
    for n, family in enumerate(FAMILIES):
        cases = family_cases(family, start + 100 * n, 12)
        for ga_seed in range(3):
            report = protocol(cases, NM3FittedCleanup.name, generations=200, seeds=3, solver="anneal",
                              fit_solver="anneal", rng=ga_seed, fit_seeds=3, fit_all=False)
            for s in report.held_out:
                c, e, t = c + s.correct, e + s.errors, t + s.targets
        print(f"{family:>10} done", flush=True)
    print(f"NM3, one match per corner inside the fitness: C/T {100 * c / t:.1f}%  precision {100 * c / max(c + e, 1):.1f}%")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("trial", choices=("cleanups", "errors", "fitted-cleanup"))
    parser.add_argument("--method", default="NM4", help="the fitted variant (NM4 or NM3; default NM4)")
    parser.add_argument("--seeds-from", type=int, default=3000, help="first layout seed (2000 or 3000)")
    args = parser.parse_args(argv)
    began = time.perf_counter()
    if args.trial == "cleanups":
        cleanups(args.method, args.seeds_from)
    elif args.trial == "errors":
        errors(args.method, args.seeds_from)
    else:
        fitted_cleanup(args.seeds_from)
    print(f"elapsed {time.perf_counter() - began:.0f} s")


if __name__ == "__main__":
    main()
