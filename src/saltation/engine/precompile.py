"""Compiling the engines and model functions several models need at once (a cold cache only).

The engine of a state dimension (about 25 s on two free cores, 40 s on one) and a model's functions
(seconds) compile on first use and are cached per machine; the message says how long it should take
here (:mod:`saltation.engine.buildtime`).  A process that
needs several (the paper's figures, the test suite) compiles them here in
parallel: in this process and in fresh interpreters, one per further core, which
start before the models are built and then load what they compiled from the
cache.  The jobs (the groups of each engine's functions, each model's
functions) are shared out longest first, each to the process with the least
work so far (:func:`schedule`): the models' functions fill in beside the
engine's longer group, in a process that has already imported and warmed up
numba.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from collections.abc import Iterable

from saltation.engine.buildtime import estimate_build
from saltation.engine.codegen import (  # (COMPILE_GROUP_SECONDS: a name of release 0.1 here)
    COMPILE_GROUP_SECONDS,  # noqa: F401
    COMPILE_GROUPS,
    SPECIALIZED_DIMENSIONS,
    active_cache_directory,
    building,
    engine_dimension,
    engine_kind,
    engine_seconds,
    is_compiled,
    is_engine_compiled,
    load_engine,
    load_model_functions,
    model_seconds,
)
from saltation.model.system import PiecewiseSystem

Job = tuple[str, object]


def _compile_in_worker(jobs: list[Job], report=None) -> None:
    """Compile groups of engines' functions and models' functions, in turn (or load them, where cached).

    A job that fails is skipped (the caller's first use compiles it again, and reports the error); the
    index of each that succeeds is written to ``report`` (a worker's standard output), as a line.  The
    jobs are one build, the caller's: none is announced or recorded on its own.
    """
    with building(None):
        _compile_jobs(jobs, report)


def _compile_jobs(jobs: list[Job], report) -> None:
    for k, (kind, what) in enumerate(jobs):
        try:
            if kind == "engine":
                dimension, entry_points = what
                load_engine(int(dimension), tuple(entry_points))
            else:
                load_model_functions(what)
        except Exception:  # noqa: BLE001, S112 - not lost: the first use compiles it again and reports it
            continue
        if report is not None:
            report.write(f"{k}\n")
            report.flush()


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


_WORKER_CODE = """
import importlib.util, os, pickle, sys, types
spec = importlib.util.find_spec("saltation")
package = types.ModuleType("saltation")
package.__path__, package.__spec__ = list(spec.submodule_search_locations), spec
sys.modules["saltation"] = package
from saltation.engine.precompile import _compile_in_worker
_compile_in_worker(pickle.load(sys.stdin.buffer), sys.stdout)
os._exit(0)
"""
"""A worker's program: import what compiling needs, read the jobs, compile them, saying which are done,
and exit at once (what it compiled is in the cache, each file written whole; tearing numba's compiler
down would keep the caller waiting a second).  A bare module stands in for the package's ``__init__``,
whose public names (orbits, continuation, scipy...) compiling does not use: the imports take 0.5 s
instead of 1 s, on the path of the build's longer half."""


def _start_worker() -> subprocess.Popen:
    """A fresh interpreter that imports saltation at once, then waits for its jobs on standard input
    (:func:`_give_jobs`): it gets through its imports while this process still builds the models."""
    # a failure there is not fatal: the caller's first use compiles (and reports) what it did not
    return subprocess.Popen([sys.executable, "-c", _WORKER_CODE], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=False)


def _give_jobs(worker: subprocess.Popen, jobs: list[Job]) -> None:
    """Send a worker its jobs (none: it exits); a worker that has died is left to the first use."""
    assert worker.stdin is not None
    try:
        worker.stdin.write(pickle.dumps(jobs))
        worker.stdin.close()
    except OSError:  # (BrokenPipeError: the interpreter failed to start or to import saltation)
        pass


def _job_cost(job: Job) -> float:
    kind, what = job
    if kind == "engine":
        dimension, group = what
        return engine_seconds(engine_dimension(dimension), group)
    return model_seconds(what)


def _run_in_processes(jobs: list[Job], workers: list[subprocess.Popen]) -> None:
    """Compile ``jobs`` here and in ``workers`` (started by :func:`_start_worker`), shared out by
    :func:`schedule`: this process takes the share with the longest job (the loop of the integrator,
    whose loading from the cache afterwards would cost most), each worker one of the others."""
    shares = schedule([_job_cost(job) for job in jobs], len(workers) + 1)
    given = [[jobs[j] for j in shares[k + 1]] if k + 1 < len(shares) else [] for k in range(len(workers))]
    for worker, share in zip(workers, given):
        _give_jobs(worker, share)
    _compile_in_worker([jobs[j] for j in shares[0]])
    # then load here what each worker has compiled, as it says so: while the last job still compiles
    for worker, share in zip(workers, given):
        for line in worker.stdout or ():
            k = line.strip()
            if k.isdigit() and int(k) < len(share):
                _compile_in_worker([share[int(k)]])  # (from the cache: a load)
        worker.wait()


def compile_in_parallel(systems: Iterable[PiecewiseSystem], workers: int | None = None, *,
                        dimensions: Iterable[int] = ()) -> list[str]:
    """Compile the engines and the functions of several models at once (a cold cache only).

    Engines and models already cached are skipped; the rest is compiled in this process and in
    fresh interpreters (so this is safe from any script), at most ``workers`` (default: the number of
    cores) in all, shared out by :func:`schedule`.

    Parameters
    ----------
    systems : iterable of PiecewiseSystem
        The models (callables' flows need their engines only).  A generator is consumed after the
        interpreters have started, so that building the models overlaps their start.
    workers : int, optional
        Processes in all, this one included (default: the number of cores).
    dimensions : iterable of int
        State dimensions whose engines are needed, known before the models are built: when one is not
        compiled, the interpreters start before ``systems`` is consumed.

    Returns
    -------
    list of str
        The names of the models compiled (none when there is at most one thing to compile: the caller's
        first use compiles it as fast).
    """
    workers = workers or os.cpu_count() or 1
    early = sorted({engine_dimension(n) for n in dimensions if not is_engine_compiled(n)})
    # as many as the engines' groups will keep busy (more, once the models' jobs are known)
    started = [_start_worker() for _ in range(min(workers - 1, len(early) * len(COMPILE_GROUPS)))]
    spare: list[subprocess.Popen] = []
    finished = False
    try:
        systems = list(systems)
        todo = [s for s in systems if isinstance(s, PiecewiseSystem) and not is_compiled(s)]  # (not callables)
        needed = {s.n for s in systems} | set(dimensions)  # (callables' too)
        dims = sorted({engine_dimension(n) for n in needed if not is_engine_compiled(n)})
        # an engine's functions compile in two groups of about equal time (COMPILE_GROUPS), 0: any larger dimension
        engines = [("engine", (d or SPECIALIZED_DIMENSIONS.stop, group)) for d in dims for group in COMPILE_GROUPS]
        if len(todo) + len(engines) <= 1 or workers <= 1:
            return []
        # the models' functions do not need an engine to compile: they fill in beside the engines' longer groups
        jobs = engines + [("model", s) for s in todo]
        helpers = min(workers, len(jobs)) - 1
        spare = started[helpers:]
        for worker in spare:
            _give_jobs(worker, [])  # (more were started than there are jobs to share: each exits)
        started = started[:helpers] + [_start_worker() for _ in range(helpers - len(started))]
        sizes = [f"{d}-state models" if d else f"models of {SPECIALIZED_DIMENSIONS.stop} or more states" for d in dims]
        models = f"{len(todo)} model{'s' if len(todo) != 1 else ''}"
        functions = f"the functions of {models}"
        # how long: each process's share of the work, on the cores free now, at this machine's scale
        costs = [_job_cost(job) for job in jobs]
        work = [sum(costs[j] for j in share) for share in schedule(costs, helpers + 1)]
        kind = ", ".join(engine_kind(d) for d in dims) if dims else "model functions"
        estimate = estimate_build(active_cache_directory(), kind, work)
        when = f"{estimate.text}, " if estimate.text else ""
        if engines:
            what = f"compiling the integrator for {' and '.join(sizes)}" + (f" and {functions}" if todo else "")
            what += f", once for this machine ({when}side by side on the cores)"
        else:
            what = f"compiling {functions} ({when}side by side on the cores)"
        with building(what, estimate=estimate):
            _run_in_processes(jobs, started)
        finished = True
        return [s.name for s in todo]
    finally:
        for worker in started + spare:
            if not finished and worker.poll() is None:
                worker.kill()  # (interrupted, or nothing to share out)
            elif worker.stdin is not None and not worker.stdin.closed:
                worker.stdin.close()  # (never given its jobs: it reads the end of its input, and exits)
            worker.wait()
            if worker.stdout is not None:
                worker.stdout.close()


__all__ = ["compile_in_parallel", "model_seconds", "schedule"]
