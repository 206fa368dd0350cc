"""Compiling the engines and model functions several models need at once (a cold cache only).

The engine of a state dimension (about 25 s on two cores, 40 s on one) and a model's functions
(seconds) compile on first use and are cached per machine.  A process that
needs several (the paper's figures, the test suite) compiles them here in
parallel, one fresh interpreter per core, and then loads them all from the
cache.  The jobs (the groups of each engine's functions, each model's
functions) are shared out longest first, each to the interpreter with the least
work so far (:func:`schedule`): the models' functions fill in beside the
engine's longer group, in an interpreter that has already imported and warmed
up numba.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from saltation.engine.codegen import (
    COMPILE_GROUP_SECONDS,
    COMPILE_GROUPS,
    SPECIALIZED_DIMENSIONS,
    building,
    engine_dimension,
    is_compiled,
    is_engine_compiled,
    load_engine,
    load_model_functions,
)
from saltation.model.system import PiecewiseSystem


def model_seconds(system: PiecewiseSystem) -> float:
    """About how long a model's functions take to compile, in an interpreter that has compiled something
    already (one core of a 2-core machine, as :data:`~saltation.engine.codegen.COMPILE_GROUP_SECONDS`):
    2 s, and a tenth of a second for each pair of a mode and a surface (the Lie derivatives) and each
    transition (the guards).  Measured: 3.3 s for ``trilinear`` (3 modes, 4 surfaces, 8 transitions), 5 s
    for ``block_on_belt`` (3, 5, 14)."""
    return 2.0 + 0.1 * (len(system.modes) * len(system.surface_names) + len(system.transitions))

Job = tuple[str, object]


def _compile_in_worker(jobs: list[Job]) -> None:
    """Run in a fresh interpreter: compile groups of engines' functions and models' functions, in turn.

    A job that fails is skipped (the caller's first use compiles it again, and reports the error).
    """
    for kind, what in jobs:
        try:
            if kind == "engine":
                dimension, entry_points = what
                load_engine(int(dimension), tuple(entry_points))
            else:
                load_model_functions(what)
        except Exception:  # noqa: BLE001, S112 - not lost: the first use compiles it again and reports it
            continue


def schedule(costs: list[float], workers: int) -> list[list[int]]:
    """Share jobs out between ``workers`` interpreters: longest first, each to the least loaded so far.

    The longest-processing-time rule (Graham, 1969) finishes within 4/3 of the best possible time.

    Parameters
    ----------
    costs : list of float
        Estimated time of each job.
    workers : int
        Number of interpreters.

    Returns
    -------
    list of list of int
        The indices of the jobs each interpreter runs, in order (empty lists dropped).
    """
    loads = [0.0] * max(workers, 1)
    shares: list[list[int]] = [[] for _ in loads]
    for k in sorted(range(len(costs)), key=lambda j: -costs[j]):  # (a stable sort: ties keep their order)
        w = loads.index(min(loads))
        shares[w].append(k)
        loads[w] += costs[k]
    return [share for share in shares if share]


def _run_in_processes(jobs: list[Job], workers: int) -> None:
    costs = [COMPILE_GROUP_SECONDS[COMPILE_GROUPS.index(tuple(what[1]))] if kind == "engine" else model_seconds(what)
             for kind, what in jobs]
    shares = [[jobs[k] for k in share] for share in schedule(costs, workers)]
    code = (
        "import pickle, sys; from saltation.engine.precompile import _compile_in_worker; "
        "_compile_in_worker(pickle.load(open(sys.argv[1], 'rb')))"
    )
    with tempfile.TemporaryDirectory() as tmp:

        def run(k: int) -> None:
            path = Path(tmp) / f"jobs{k}.pickle"
            path.write_bytes(pickle.dumps(shares[k]))
            # a failure here is not fatal: the caller's first use compiles (and reports) it
            subprocess.run([sys.executable, "-c", code, str(path)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                           check=False)

        with ThreadPoolExecutor(len(shares)) as pool:
            list(pool.map(run, range(len(shares))))


def compile_in_parallel(systems: list[PiecewiseSystem], workers: int | None = None) -> list[str]:
    """Compile the engines and the functions of several models at once (a cold cache only).

    Engines and models already cached are skipped; the rest is compiled in at
    most ``workers`` (default: the number of cores) fresh interpreters (so this
    is safe from any script), shared out by :func:`schedule`.  Returns the names
    of the models compiled (none when there is at most one thing to compile:
    the caller's first use compiles it as fast).
    """
    todo = [s for s in systems if isinstance(s, PiecewiseSystem) and not is_compiled(s)]  # (not callables)
    dims = sorted({engine_dimension(s.n) for s in systems if not is_engine_compiled(s.n)})  # (callables' too)
    # an engine's functions compile in two groups of about equal time (COMPILE_GROUPS), 0: any larger dimension
    engines = [("engine", (d or SPECIALIZED_DIMENSIONS.stop, group)) for d in dims for group in COMPILE_GROUPS]
    workers = workers or os.cpu_count() or 1
    if len(todo) + len(engines) <= 1 or workers <= 1:
        return []
    # the models' functions do not need an engine to compile: they fill in beside the engines' longer groups
    jobs = engines + [("model", s) for s in todo]
    sizes = [f"{d}-state models" if d else f"models of {SPECIALIZED_DIMENSIONS.stop} or more states" for d in dims]
    models = f"{len(todo)} model{'s' if len(todo) != 1 else ''}"
    functions = f"the functions of {models}"
    if engines:
        what = f"compiling the integrator for {' and '.join(sizes)} (about 25 s, side by side on the cores)"
        what += (f" and {functions}" if todo else "") + ", once for this machine"
    else:
        what = f"compiling {functions}"
    with building(what):
        _run_in_processes(jobs, min(workers, len(jobs)))
    return [s.name for s in todo]


__all__ = ["compile_in_parallel", "model_seconds", "schedule"]
