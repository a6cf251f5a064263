"""``ismb-lab evaluate``: the train/test protocol of Fig. 5.10 over a manifest's pairs."""

from __future__ import annotations

from pathlib import Path

from .._files import atomic_write_text
from ..methods import METHOD_NAMES
from ._common import BestSoFar, UsageError, progress_bar
from ._guard import json_text


def add_parser(sub) -> None:
    e = sub.add_parser("evaluate", help="train on one pair, test on the others (Fig. 5.10)",
                       description="Run the thesis' train/test protocol over the pairs of a "
                       "manifest, with every network figure over several update-order seeds.")
    e.add_argument("manifest", type=Path, help='JSON: {"pairs": [{"left", "right", "targets", '
                   '"roi", "shift"} or {"source": "middlebury-motorcycle", "roi"}, ...]}')
    e.add_argument("--method", choices=METHOD_NAMES, default="III", help="energy recipe (default: III)")
    e.add_argument("--train", type=int, default=0, metavar="INDEX",
                   help="the pair whose GA parameters are tested on the others (default: 0)")
    e.add_argument("--seeds", type=int, default=5, help="update-order seeds per figure (default: 5)")
    e.add_argument("--generations", type=int, default=500, help="GA generations (default: 500)")
    e.add_argument("--peers", action="store_true", help="also score the peer matchers")
    e.add_argument("--solvers", nargs="*", choices=("anneal", "exact"), default=(),
                   help="also solve the tested energies by mean-field annealing and/or exactly (MILP)")
    e.add_argument("--fit-solver", choices=("network", "anneal", "exact"), default="network",
                   help="how the GA solves each network while fitting (default: network)")
    e.add_argument("--fit-seeds", type=int, default=1, metavar="N",
                   help="update-order seeds averaged in each GA fitness (default: 1)")
    e.add_argument("--ga-seed", type=int, default=0, metavar="N",
                   help="seed of the GA (default: 0); a small training pair can leave the GA on "
                   "a plateau, so compare a few")
    e.add_argument("--held-out-only", action="store_true",
                   help="fit only the training pair (the held-out figures are the same; the other "
                   "rows' 'Training' column is skipped)")
    e.add_argument("--json", type=Path, default=None, metavar="OUT", help="write the report as JSON")
    e.set_defaults(run=run)


def run(args) -> int:
    from ..evaluation import format_protocol, load_manifest, protocol

    if args.ga_seed < 0:
        raise UsageError(f"--ga-seed must be an integer >= 0, got {args.ga_seed}")
    cases = load_manifest(args.manifest)
    bars, best = {}, BestSoFar(args.method)

    def progress(name, record):
        best(name, record)
        if name not in bars:
            for bar in bars.values():
                bar.close()
            bars[name] = progress_bar(args.generations + 1, f"GA on {name}")
        bars[name].update(1)
        bars[name].set_postfix(best=f"{record.best:g}", mean=f"{record.mean:.2f}")

    try:
        report = protocol(cases, args.method, train=args.train, seeds=args.seeds,
                          generations=args.generations, peers=args.peers, progress=progress,
                          solvers=tuple(args.solvers), fit_solver=args.fit_solver,
                          fit_seeds=args.fit_seeds, rng=args.ga_seed, fit_all=not args.held_out_only)
    except KeyboardInterrupt:
        return best.save(args.json)
    finally:
        for bar in bars.values():
            bar.close()
    print(format_protocol(report))
    if args.json is not None:
        data = {"method": report["method"], "train": report["train"],
                "params": report["params"].to_dict(), "seeds": args.seeds, "ga_seed": args.ga_seed,
                "pairs": [{"name": r["name"], "testing": [str(s) for s in r["testing"]],
                           "training": None if r["training"] is None else [str(s) for s in r["training"]]}
                          for r in report["rows"]],
                "held_out": [{"cet": str(s), "recall": s.recall, "precision": s.precision}
                             for s in report["held_out"]],
                "peers": {name: {"held_out": str(p["held_out"]), "recall": p["held_out"].recall,
                                 "precision": p["held_out"].precision} for name, p in report["peers"].items()},
                "solvers": {name: [{"cet": str(s), "recall": s.recall, "precision": s.precision}
                                   for s in v["held_out"]] for name, v in report.get("solvers", {}).items()}}
        atomic_write_text(args.json, json_text(data))
    return 0
