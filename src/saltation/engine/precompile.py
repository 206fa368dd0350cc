"""Compiling the engines and model functions several models need at once (a cold cache only).

The engine of a state dimension (about 25 s on two cores, 40 s on one) and a model's functions
(seconds) compile on first use and are cached per machine.  A process that
needs several (the paper's figures, the test suite) compiles them here in
parallel, one fresh interpreter each, the engines of the dimensions not yet
compiled started first and the models' functions beside them, and then loads
them all from the cache.
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


def _compile_in_worker(job: tuple[str, object]) -> None:
    """Run in a fresh interpreter: compile a group of an engine's functions, or one model's functions."""
    kind, what = job
    if kind == "engine":
        dimension, entry_points = what
        load_engine(int(dimension), tuple(entry_points))
    else:
        load_model_functions(what)


def _run_in_processes(jobs: list[tuple[str, object]], workers: int) -> None:
    code = (
        "import pickle, sys; from saltation.engine.precompile import _compile_in_worker; "
        "_compile_in_worker(pickle.load(open(sys.argv[1], 'rb')))"
    )
    with tempfile.TemporaryDirectory() as tmp:

        def run(k: int) -> None:
            path = Path(tmp) / f"job{k}.pickle"
            path.write_bytes(pickle.dumps(jobs[k]))
            # a failure here is not fatal: the caller's first use compiles (and reports) it
            subprocess.run([sys.executable, "-c", code, str(path)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                           check=False)

        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(run, range(len(jobs))))


def compile_in_parallel(systems: list[PiecewiseSystem], workers: int | None = None) -> list[str]:
    """Compile the engines and the functions of several models at once (a cold cache only).

    Engines and models already cached are skipped; each is compiled in a fresh
    interpreter (so this is safe from any script), at most ``workers``
    (default: the number of cores) at a time, engines first.  Returns the names
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
    # one pool, the engines first: the models' functions do not need an engine to compile, so they take
    # the other cores while an engine (the longest job by far) compiles
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


__all__ = ["compile_in_parallel"]
