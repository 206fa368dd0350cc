"""Brute-force (simulation-based) bifurcation diagrams.

:func:`sweep` simulates a model at each value of one parameter and samples what
it settles to:

* forced systems: the stroboscopic Poincare section ``x(t0 + k T)``, ``T`` the
  forcing period, for ``k`` = ``transient`` + 1, ..., ``transient + periods``;
* autonomous systems (or ``poincare=False``): the local maxima of the first
  state ``x_1`` (the state at each maximum is kept), found on the integrator's
  dense output and refined by golden-section search on it.  An orbit whose
  ``x_1`` has no maximum in the sampling window (an equilibrium) contributes
  its final state once.

The values are split into one contiguous chunk of equal length per worker
process (the integrator's work per forcing period hardly depends on the
period, so equal numbers of values are about equal work); within a
chunk each value starts from the final state of the previous one, as
brute-force diagrams do (so a branch is followed as far as it stays
attracting), and the first value of each chunk starts from ``x0``.  A value
whose simulation fails (chattering, a state in no mode, ...) is recorded in
:attr:`SweepResult.failures`, and the next value restarts from ``x0``.

Each value costs two calls of the compiled integrator: one over the transient,
one over the sampling window with dense output; the samples are read off the
dense output (DOP853's continuous extension, accurate to the integration
tolerance), not by stopping the integrator at every section crossing.
"""

from __future__ import annotations

import csv
import json
import math
import multiprocessing
import os
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .errors import ModelError, SaltationError
from .integrate import Flow, Tolerances, Trajectory, dense_evaluate
from .model import PiecewiseSystem

__all__ = ["SweepResult", "sweep"]

_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: Dense-output evaluations per integration step when looking for maxima.
_MAXIMA_GRID = 12
#: Golden-section iterations refining each maximum (0.618**60 ~ 3e-13 of the bracket).
_MAXIMA_ITERATIONS = 60
#: ``x_1`` varying by less than this (relative) over the sampling window has no maxima.
_FLAT = 1e-9


@dataclass(frozen=True)
class SweepResult:
    """Points of a brute-force diagram.

    Attributes
    ----------
    model : str
        Name of the model.
    parameter : str
        Name of the swept parameter.
    values : ndarray, shape (m,)
        The parameter values, in the order given.
    counts : ndarray of int, shape (m,)
        Number of points sampled at each value (0 where the simulation failed).
    parameter_points : ndarray, shape (N,)
        Parameter value of each sampled point (``N = counts.sum()``).
    states : ndarray, shape (N, n)
        The sampled states.
    state_names : tuple of str
    section : str
        ``"poincare"`` (stroboscopic section of a forced system) or ``"maxima"``
        (local maxima of the first state).
    failures : tuple of (float, str)
        Parameter values whose simulation failed, with the error message.
    settings : dict
        ``periods``, ``transient`` and the time of one period for autonomous systems.
    """

    model: str
    parameter: str
    values: np.ndarray
    counts: np.ndarray
    parameter_points: np.ndarray
    states: np.ndarray
    state_names: tuple[str, ...]
    section: str
    failures: tuple[tuple[float, str], ...] = ()
    settings: dict = field(default_factory=dict)

    @property
    def x(self) -> np.ndarray:
        """First state of every point: with :attr:`parameter_points`, the pair to plot."""
        return self.states[:, 0]

    def points(self, state: int | str = 0) -> tuple[np.ndarray, np.ndarray]:
        """``(parameter_points, states[:, state])``: the flat pair of arrays to plot."""
        return self.parameter_points, self.states[:, self._state_index(state)]

    def at(self, value_index: int) -> np.ndarray:
        """States sampled at ``values[value_index]``, shape (counts[value_index], n)."""
        start = int(np.sum(self.counts[:value_index]))
        return self.states[start : start + int(self.counts[value_index])]

    def _state_index(self, state: int | str) -> int:
        if isinstance(state, str):
            try:
                return self.state_names.index(state)
            except ValueError:
                raise ModelError(f"unknown state {state!r}; states are {list(self.state_names)}") from None
        if not -len(self.state_names) <= state < len(self.state_names):
            raise ModelError(f"state index {state} out of range for states {list(self.state_names)}")
        return int(state)

    # -- export ------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """A JSON-ready dictionary (non-finite numbers as strings)."""

        def enc(v: float) -> float | str:
            return float(v) if math.isfinite(v) else str(float(v))

        return {
            "format": "saltation.sweep/1",
            "model": self.model,
            "parameter": self.parameter,
            "section": self.section,
            "state_names": list(self.state_names),
            "settings": dict(self.settings),
            "values": [enc(v) for v in self.values],
            "counts": [int(c) for c in self.counts],
            "parameter_points": [enc(v) for v in self.parameter_points],
            "states": [[enc(v) for v in row] for row in self.states],
            "failures": [[enc(v), msg] for v, msg in self.failures],
        }

    @classmethod
    def from_dict(cls, d: dict) -> SweepResult:
        if d.get("format") != "saltation.sweep/1":
            raise ValueError(f"not a saltation sweep record (format {d.get('format')!r})")
        names = tuple(d["state_names"])
        return cls(
            model=d["model"],
            parameter=d["parameter"],
            values=np.array(d["values"], dtype=float),
            counts=np.array(d["counts"], dtype=int),
            parameter_points=np.array(d["parameter_points"], dtype=float),
            states=np.array(d["states"], dtype=float).reshape(-1, len(names)),
            state_names=names,
            section=d["section"],
            failures=tuple((float(v), str(m)) for v, m in d["failures"]),
            settings=dict(d.get("settings", {})),
        )

    def save(self, path: str | PathLike[str]) -> Path:
        """Write the points as JSON (``.json``) or CSV (any other suffix).

        The CSV has one row per point: the parameter value, then every state
        (full precision); the JSON keeps everything, :meth:`load` reads it back.
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix.lower() == ".json":
            path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
            return path
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow([self.parameter, *self.state_names])
            for lam, row in zip(self.parameter_points, self.states):
                w.writerow([repr(float(lam)), *(repr(float(v)) for v in row)])
        return path

    @classmethod
    def load(cls, path: str | PathLike[str]) -> SweepResult:
        """Read a sweep written by :meth:`save` as JSON."""
        return cls.from_dict(json.loads(Path(path).read_text()))

    # -- figure ------------------------------------------------------------------------------
    def plot(self, ax: Axes | None = None, *, state: int | str = 0, **style) -> Figure:
        """Scatter the points over the parameter; draws on ``ax`` or on a new Figure (no pyplot state)."""
        k = self._state_index(state)
        if ax is None:
            fig = Figure(figsize=(6.4, 4.4), layout="constrained")
            ax = fig.add_subplot()
        else:
            fig = ax.get_figure()
        kw = {"s": 1.0, "color": "k", "marker": ".", "linewidths": 0, "rasterized": True} | style
        ax.scatter(self.parameter_points, self.states[:, k], **kw)
        ax.set_xlabel(self.parameter)
        name = self.state_names[k]
        if self.section == "poincare":
            ax.set_ylabel(f"{name} (Poincare section)")
        else:
            ax.set_ylabel(f"{name} at maxima of {self.state_names[0]}")
        ax.set_title(f"{self.model}: brute-force diagram")
        return fig


# -- the sweep ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Job:
    values: np.ndarray
    x0: np.ndarray
    parameter_index: int
    base: np.ndarray
    periods: int
    transient: int
    poincare: bool
    period: float | None
    t0: float
    tolerances: Tolerances | None


_WORKER_FLOW: Flow | None = None


def _init_worker(system: PiecewiseSystem) -> None:
    global _WORKER_FLOW
    _WORKER_FLOW = Flow(system)  # in a forked worker the kernels are already loaded; otherwise from the disk cache


def _run_job_in_worker(job: _Job):
    assert _WORKER_FLOW is not None
    return _run_chunk(_WORKER_FLOW, job)


def sweep(
    system: PiecewiseSystem,
    parameter: str,
    values: Sequence[float],
    *,
    periods: int = 200,
    transient: int = 100,
    x0: Sequence[float] | None = None,
    poincare: bool = True,
    workers: int | None = None,
    tolerances: Tolerances | None = None,
    parameters: dict[str, float] | None = None,
    period: float | None = None,
    t0: float = 0.0,
) -> SweepResult:
    """Brute-force diagram: simulate at each parameter value and sample the attractor.

    Parameters
    ----------
    system : PiecewiseSystem
        The model.
    parameter : str
        Name of the swept parameter.
    values : sequence of float
        Parameter values, simulated in this order (within each worker's chunk
        each starts from the previous one's final state).
    periods : int
        Number of periods sampled per value (forced systems: section points).
    transient : int
        Number of periods simulated and discarded first.
    x0 : array_like, shape (n,), optional
        Initial state of the first value of each chunk (and after a failure);
        zeros by default.
    poincare : bool
        Forced systems: sample the Poincare section ``x(t0 + k T)`` (True) or
        the maxima of ``x_1`` (False).  Autonomous systems always sample maxima.
    workers : int, optional
        Worker processes (default: every available core; 1 runs in this process).
    tolerances : Tolerances, optional
        Integration tolerances (the flow's defaults otherwise).
    parameters : dict, optional
        Values of the other parameters.
    period : float, optional
        Autonomous systems: the time of one "period" in ``periods`` and
        ``transient`` (default ``2 pi``).  Ignored for forced systems.
    t0 : float
        Initial time (forced systems: the phase of the section).

    Returns
    -------
    SweepResult
    """
    p_index = system.parameter_index(parameter)
    values = np.asarray(values, dtype=float).reshape(-1)
    if values.size == 0:
        raise ValueError("sweep needs at least one parameter value")
    if not np.all(np.isfinite(values)):
        raise ValueError(f"parameter values must be finite, got {values.tolist()}")
    if int(periods) != periods or periods < 1 or int(transient) != transient or transient < 0:
        raise ValueError(f"periods must be a positive and transient a non-negative integer, got {periods}, {transient}")
    base = system.parameter_vector(parameters)
    x0 = np.zeros(system.n) if x0 is None else np.asarray(x0, dtype=float).reshape(-1)
    if x0.shape != (system.n,):
        raise ModelError(f"x0 must have {system.n} components {list(system.state_names)}, got {x0.size}")
    autonomous = system.is_autonomous
    if autonomous:
        period = 2.0 * math.pi if period is None else float(period)
        if not period > 0:
            raise ValueError(f"period must be positive, got {period}")
    else:
        period = None
    use_poincare = bool(poincare) and not autonomous

    n_workers = _available_cores() if workers is None else int(workers)
    if n_workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    n_workers = min(n_workers, values.size)
    chunks = np.array_split(values, n_workers)
    jobs = [
        _Job(c, x0, p_index, base, int(periods), int(transient), use_poincare, period, float(t0), tolerances)
        for c in chunks
    ]
    if n_workers == 1:
        results = [_run_chunk(Flow(system), jobs[0])]
    else:
        Flow(system)  # load (or compile) the kernels once here, so that forked workers inherit them
        pool = ProcessPoolExecutor(max_workers=n_workers, mp_context=_context(), initializer=_init_worker, initargs=(system,))
        with pool as ex:
            results = list(ex.map(_run_job_in_worker, jobs))

    counts, samples, failures = [], [], []
    for chunk_counts, chunk_samples, chunk_failures in results:
        counts += chunk_counts
        samples += chunk_samples
        failures += chunk_failures
    counts_arr = np.array(counts, dtype=int)
    states = np.concatenate(samples) if samples else np.zeros((0, system.n))
    settings = {"periods": int(periods), "transient": int(transient), "t0": float(t0)}
    if period is not None:
        settings["period"] = period
    return SweepResult(
        model=system.name,
        parameter=parameter,
        values=values,
        counts=counts_arr,
        parameter_points=np.repeat(values, counts_arr),
        states=states.reshape(-1, system.n),
        state_names=tuple(system.state_names),
        section="poincare" if use_poincare else "maxima",
        failures=tuple(failures),
        settings=settings,
    )


def _available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _context():
    # fork: workers inherit the loaded kernels (no import, no cache read); elsewhere they load them from disk
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else None)


def _run_chunk(flow: Flow, job: _Job) -> tuple[list[int], list[np.ndarray], list[tuple[float, str]]]:
    """Simulate one chunk of values, each from the previous final state."""
    system = flow.system
    p = job.base.copy()
    x = job.x0.copy()
    mode: str | None = None
    counts: list[int] = []
    samples: list[np.ndarray] = []
    failures: list[tuple[float, str]] = []
    for value in job.values:
        p[job.parameter_index] = value
        try:
            T = job.period if job.period is not None else system.forcing_period(p)
            t_sample = job.t0 + job.transient * T
            t_end = t_sample + job.periods * T
            if job.transient:
                traj = flow.run(x, job.t0, t_sample, p, mode0=mode, tolerances=job.tolerances)
                x, mode = traj.x1, traj.mode1
            traj = flow.run(x, t_sample, t_end, p, mode0=mode, dense=True, tolerances=job.tolerances)
            if job.poincare:
                times = t_sample + T * np.arange(1, job.periods + 1)
                pts = traj.at(times)
                pts[-1] = traj.x1  # the integrator ends exactly there
            else:
                pts = _maxima(traj)
                if len(pts) == 0:
                    pts = traj.x1[None, :].copy()
            x, mode = traj.x1.copy(), traj.mode1
        except (SaltationError, ValueError, ArithmeticError) as exc:
            failures.append((float(value), f"{type(exc).__name__}: {exc}"))
            counts.append(0)
            x, mode = job.x0.copy(), None
            continue
        counts.append(len(pts))
        samples.append(np.asarray(pts, dtype=float))
    return counts, samples, failures


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
