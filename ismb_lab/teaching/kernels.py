"""The kernels the lessons run, compiled once by the teacher for the class hub, whose servers
load them (:mod:`ismb_lab._core.numba_share`)."""

from __future__ import annotations

import os
import sys

from .._core.numba_share import cold

__all__ = ["cached_kernels", "compile_into", "compile_kernels"]


def compile_kernels() -> dict:
    """Compile (or load) every kernel the lessons run, in this process's numba cache; returns
    ``{"seconds": ..., "kernels": n, "cold": [kernels with no compiled version in the cache]}``."""
    import time

    import numpy as np

    from ..matching.pipeline import warm_up
    from ..network import annealing, exact, hopfield
    from ..network.methods import get_method
    from ..network.solvers import solver_names
    from ..scenes import synthetic_scene
    from ..tuning import fitness
    from ..tuning.cases import Case

    start = time.perf_counter()
    warm_up(solver_names())
    case = Case.from_scene(synthetic_scene(seed=0))
    for method in ("I", "III"):       # Method-I's post-processing is a kernel of its own
        bounds = fitness.gene_bounds(method)
        fitness.Fitness([case], method)(np.array([(bounds.low + bounds.high) / 2]))
    net = hopfield.Network.from_arrays(1, 2, rows=[0, 0], cols=[0, 1], similarity=[0.5, 0.0],
                                       pair_a=[], pair_b=[], pair_c=[])
    fitness.evaluate([case], "III", get_method("III").defaults)
    list(annealing.iter_annealing(net))
    exact.exhaustive_minimum(net)
    kernels = cached_kernels()
    # a kernel that only other kernels call is linked into them when they are loaded from the
    # cache, so it may have no signature of its own in this process: its index file counts
    return {"seconds": round(time.perf_counter() - start, 1), "kernels": len(kernels),
            "cold": sorted(name for name, kernel in kernels.items() if not kernel.signatures and cold(kernel))}


def cached_kernels() -> dict:
    """Every cached numba kernel of the package's modules imported so far, by name."""
    from numba.core.registry import CPUDispatcher

    found = {}
    for name, module in list(sys.modules.items()):
        if name.split(".")[0] != __name__.split(".")[0]:
            continue
        for attribute, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == name \
                    and value._cache.__class__.__name__ != "NullCache":
                found[f"{name}.{attribute}"] = value
    return found


def compile_into(folder, python=None, isolated: bool = True, timeout: float = 1800) -> dict:
    """Run :func:`compile_kernels` in a new interpreter (`python`, by default this one) whose
    numba cache is `folder`; returns its report plus ``"source"``, the package folder compiled for.

    `isolated` (``python -I``): the package is the one installed in that interpreter, as the hub's
    servers import it, whatever the current folder or ``PYTHONPATH``.  Raises OSError if it fails.
    """
    import json
    import subprocess

    os.makedirs(folder, exist_ok=True)
    env = {**os.environ, "NUMBA_CACHE_DIR": os.path.abspath(folder), "MPLBACKEND": "Agg"}
    code = ("import json, os, ismb_lab, ismb_lab.teaching.kernels as k; report = k.compile_kernels(); "
            "report['source'] = os.path.dirname(ismb_lab.__file__); print(json.dumps(report))")
    done = subprocess.run([python or sys.executable, *(["-I"] if isolated else []), "-c", code], env=env,
                          capture_output=True, text=True, timeout=timeout)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise OSError(f"compiling the kernels failed (exit {done.returncode}): {last}")
    return json.loads(done.stdout.strip().splitlines()[-1])
