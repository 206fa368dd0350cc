"""The job runner of sweeps and period maps: chunks of parameter values in this process, in local worker
processes, or as Dask tasks, and what one chunk computes.

A job (:class:`_Job`) is a contiguous chunk of values of one parameter, with their start states; a
period map gives each worker several rows (:class:`_RowsJob`).  A value is sampled over windows of
a time unit ``T`` (the stroboscopic section, the maxima: :func:`_window_samples`), or at the crossings
of a section, counted (:func:`_crossing_samples`, with :mod:`~saltation.sweeps.sections`).
:func:`_run_jobs` runs the jobs and returns, per job, the sample counts, the samples, the failures and
the largest Lyapunov exponents (:func:`_run_chunk`).  Forked workers inherit the loaded kernels;
elsewhere, and on a Dask cluster, each worker process loads (or compiles) them once.
"""

from __future__ import annotations

import math
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from saltation.engine.flow import Flow, Tolerances, Trajectory, dense_evaluate
from saltation.errors import SaltationError
from saltation.model.system import PiecewiseSystem
from saltation.sweeps.sections import (
    Section,
    _expression_crossings,
    _expression_function,
    _surface_crossings,
)

_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: Dense-output evaluations per integration step when looking for maxima.
_MAXIMA_GRID = 12
#: Golden-section iterations refining each maximum (0.618**60 ~ 3e-13 of the bracket).
_MAXIMA_ITERATIONS = 60
#: ``x_1`` varying by less than this (relative) over the sampling window has no maxima.
_FLAT = 1e-9
#: A value's section crossings are looked for over at most this many time units ``T`` per crossing asked for.
_PATIENCE = 10


@dataclass(frozen=True)
class _Job:
    """A chunk of values of one parameter for one worker, with how to simulate each."""

    values: np.ndarray
    #: the start state of each value, shape (len(values), n): used by every value (own starts), or by the
    #: first one and the one after a failure (previous starts)
    starts: np.ndarray
    own: bool
    parameter_index: int
    base: np.ndarray
    periods: int
    transient: int
    poincare: bool
    period: float | None
    t0: float
    tolerances: Tolerances | None
    lyapunov: bool = False
    #: the mode each start state is in (None: the model's initial-mode rule)
    mode0: str | None = None
    #: a section of crossings (a surface or an expression), whose counts ``transient`` and ``periods`` are;
    #: None: the stroboscopic section or the maxima (``poincare``), over windows of ``T``
    section: Section | None = None


_WORKER_FLOW: Flow | None = None


def _init_worker(system: PiecewiseSystem) -> None:
    global _WORKER_FLOW
    _WORKER_FLOW = Flow(system)  # in a forked worker the kernels are already loaded; otherwise from the disk cache


def _run_job_in_worker(job):
    assert _WORKER_FLOW is not None
    return _run_any(_WORKER_FLOW, job)


def _run_any(flow: Flow, job):
    """A chunk of a sweep, or the rows of a period map (a list of chunks)."""
    if isinstance(job, _RowsJob):
        return [_run_chunk(flow, j) for j in job.rows]
    return _run_chunk(flow, job)



@dataclass(frozen=True)
class _RowsJob:
    """Several rows of a period map for one worker."""

    rows: list



def _workers(workers: int | None, client) -> int:
    """The number of chunks: ``workers``, or every local core, or every thread of a Dask cluster."""
    if workers is None:
        return max(1, sum(client.nthreads().values())) if client is not None else _available_cores()
    if int(workers) < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    return int(workers)


def _run_jobs(system: PiecewiseSystem, jobs: list[_Job], client) -> list:
    """Run the jobs: in this process (one job), in local worker processes, or as Dask tasks."""
    if client is not None:
        futures = client.map(_run_job_as_task, [system] * len(jobs), jobs, pure=False)
        return client.gather(futures)
    if len(jobs) == 1:
        return [_run_any(Flow(system), jobs[0])]
    Flow(system)  # load (or compile) the kernels once here, so that forked workers inherit them
    pool = ProcessPoolExecutor(max_workers=len(jobs), mp_context=_context(), initializer=_init_worker, initargs=(system,))
    with pool as ex:
        return list(ex.map(_run_job_in_worker, jobs))


_TASK_FLOWS: dict[str, Flow] = {}


def _run_job_as_task(system: PiecewiseSystem, job: _Job):
    """A Dask task: one chunk, with the model's flow kept per worker process (its kernels compiled or
    loaded from that machine's cache once)."""
    flow = _TASK_FLOWS.get(system.fingerprint)
    if flow is None:
        flow = _TASK_FLOWS[system.fingerprint] = Flow(system)
    return _run_any(flow, job)


def _available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _context():
    # fork: workers inherit the loaded kernels (no import, no cache read); elsewhere they load them from disk
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else None)


def _run_chunk(flow: Flow, job: _Job) -> tuple[list[int], list[np.ndarray], list[tuple[float, str]], list[float]]:
    """Simulate one chunk of values, each from its own start or from the previous final state: the sample
    counts, the samples, the failures, and per value the largest Lyapunov exponent over the sampled
    periods (``nan`` unless the job asks for them, or where the value failed)."""
    system = flow.system
    p = job.base.copy()
    x: np.ndarray | None = None  # a fresh start: the job's start state of the value
    mode: str | None = None
    counts: list[int] = []
    samples: list[np.ndarray] = []
    failures: list[tuple[float, str]] = []
    largest: list[float] = []
    for i, value in enumerate(job.values):
        p[job.parameter_index] = value
        fresh = job.own or x is None
        if fresh:
            x, mode = job.starts[i].copy(), job.mode0
        try:
            if fresh and mode is not None:
                flow.start_mode(x, p, job.t0, mode)  # a start outside the mode's domain fails this value, saying why
            T = job.period if job.period is not None else system.forcing_period(p)
            if job.section is not None:
                pts, x, mode, t_end = _crossing_samples(flow, job, x, mode, p, T)
                exponent = _exponent(flow, job, x, mode, p, t_end, T) if job.lyapunov else math.nan
            else:
                pts, x, mode, exponent = _window_samples(flow, job, x, mode, p, T)
        except (SaltationError, ValueError, ArithmeticError) as exc:
            failures.append((float(value), f"{type(exc).__name__}: {exc}"))
            counts.append(0)
            largest.append(math.nan)
            x, mode = None, None  # the next value starts afresh
            continue
        counts.append(len(pts))
        samples.append(np.asarray(pts, dtype=float))
        largest.append(float(exponent))
    return counts, samples, failures, largest


def _exponent(flow: Flow, job: _Job, x: np.ndarray, mode: str | None, p: np.ndarray, t: float, T: float) -> float:
    """The largest Lyapunov exponent over ``job.periods`` times ``T`` from ``(t, x)`` in ``mode``, in blocks of
    ``T``."""
    from saltation.orbits.lyapunov import lyapunov_exponents

    return float(lyapunov_exponents(flow, x, parameters=p, time=job.periods * T, t0=t, interval=T,
                                    blocks=max(2, min(10, job.periods)), tolerances=job.tolerances,
                                    mode0=None if mode is None or "|" in mode else mode).largest)


def _window_samples(flow: Flow, job: _Job, x: np.ndarray, mode: str | None, p: np.ndarray, T: float):
    """One value sampled over windows of ``T``: ``transient`` of them discarded, then the stroboscopic section or
    the maxima over ``periods`` more; the samples, the final state and mode, and the largest Lyapunov exponent
    over the sampled windows (``nan`` unless asked for)."""
    t_sample = job.t0 + job.transient * T
    t_end = t_sample + job.periods * T
    if job.transient:
        traj = flow.run(x, job.t0, t_sample, p, mode0=mode, tolerances=job.tolerances)
        x, mode = traj.x1, traj.mode1
    exponent = math.nan
    if job.lyapunov:  # over the sampled periods, from the same state (a variational run beside the samples)
        exponent = _exponent(flow, job, x, mode, p, t_sample, T)
    traj = flow.run(x, t_sample, t_end, p, mode0=mode, dense=True, tolerances=job.tolerances)
    if job.poincare:
        times = t_sample + T * np.arange(1, job.periods + 1)
        pts = traj.at(times)
        pts[-1] = traj.x1  # the integrator ends exactly there
    else:
        pts = _maxima(traj)
        if len(pts) == 0:
            pts = traj.x1[None, :].copy()
    return pts, traj.x1.copy(), traj.mode1, exponent


def _crossing_samples(flow: Flow, job: _Job, x: np.ndarray, mode: str | None, p: np.ndarray, T: float):
    """One value sampled at its section's crossings: ``transient`` crossings discarded, the next ``periods``
    sampled; the samples (fewer where the crossings stopped), the final state, mode and time.

    The run goes on in windows until it has crossed the section ``transient + periods`` times, or for at most
    :data:`_PATIENCE` times as many time units ``T``: the first window lasts ``T`` per crossing asked for, the
    next as long as the crossings seen so far say the rest takes (a quarter more), or, without any, as long
    as the run so far.
    """
    section = job.section
    needed = job.transient + job.periods
    t, limit = job.t0, job.t0 + _PATIENCE * needed * T
    dense = section.kind == "expression"
    g = _expression_function(flow.system, section.target) if dense else None
    g_last = None
    found: list[np.ndarray] = []
    count, window = 0, needed * T
    while count < needed and t < limit:
        t_next = min(t + window, limit)
        traj = flow.run(x, t, t_next, p, mode0=mode, dense=dense, tolerances=job.tolerances)
        if dense:
            _, states, g_last = _expression_crossings(traj, g, p, section.direction, g_last)
        else:
            _, states = _surface_crossings(traj, section, p)
        found.append(states)
        count += len(states)
        x, mode, t = traj.x1.copy(), traj.mode1, t_next
        elapsed = t - job.t0
        window = elapsed if count == 0 else max(T, 1.25 * (needed - count) * elapsed / count)
    pts = np.concatenate(found)[job.transient:needed] if found else np.zeros((0, x.size))
    return pts, x, mode, t


# -- reading the dense output --------------------------------------------------------------------
def _maxima(traj: Trajectory) -> np.ndarray:
    """States at the local maxima of ``x_1`` along a dense trajectory, refined on the dense output."""
    t_old, h, s_end, y0, F = traj.dense_steps
    if t_old.size < 2:
        return np.zeros((0, traj.x1.size))
    g = np.linspace(0.0, 1.0, _MAXIMA_GRID + 1)[:-1]
    ks = np.repeat(np.arange(len(t_old)), g.size)
    ss = (g[None, :] * s_end[:, None]).reshape(-1)
    x1 = dense_evaluate(F[ks], y0[ks], ss)[:, 0]
    times = t_old[ks] + ss * h[ks]
    scale = max(1.0, float(np.max(np.abs(x1))))
    if np.ptp(x1) <= _FLAT * scale:  # an equilibrium: round-off is no maximum
        return np.zeros((0, traj.x1.size))
    interior = np.nonzero((x1[1:-1] > x1[:-2]) & (x1[1:-1] >= x1[2:]))[0] + 1
    if interior.size == 0:
        return np.zeros((0, traj.x1.size))
    # golden-section search for the maximum of x_1 on [t_{i-1}, t_{i+1}], every candidate at once
    a, b = times[interior - 1].copy(), times[interior + 1].copy()

    def x1_at(t):
        return traj.at(t)[:, 0]

    c = b - _GOLDEN * (b - a)
    d = a + _GOLDEN * (b - a)
    fc, fd = x1_at(c), x1_at(d)
    for _ in range(_MAXIMA_ITERATIONS):
        left = fc >= fd  # the maximum lies in [a, d]
        b = np.where(left, d, b)
        a = np.where(left, a, c)
        new_c = b - _GOLDEN * (b - a)
        new_d = a + _GOLDEN * (b - a)
        c_next = np.where(left, new_c, d)
        d_next = np.where(left, c, new_d)
        fc_next = np.where(left, np.nan, fd)
        fd_next = np.where(left, fc, np.nan)
        need_c = np.isnan(fc_next)
        need_d = np.isnan(fd_next)
        if need_c.any():
            fc_next[need_c] = x1_at(c_next[need_c])
        if need_d.any():
            fd_next[need_d] = x1_at(d_next[need_d])
        c, d, fc, fd = c_next, d_next, fc_next, fd_next
    return traj.at(0.5 * (a + b))
