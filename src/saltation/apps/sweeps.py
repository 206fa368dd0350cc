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

Where each value starts is a documented choice, ``start=`` (a
:class:`SweepStart`), applied to ``x0``: a state, or a function
``parameters -> state`` of the parameter values (a mapping of every
parameter's name to its value, the swept one included), called once per
value in the calling process before any simulation:

* :attr:`SweepStart.PREVIOUS` (the default, what brute-force diagrams
  classically do): each value starts from the final state (and mode) of the
  value before it, so a branch is followed as long as it stays attracting,
  and a jump shows where it stops; the first value of each chunk, and the
  value after a failed one, start from ``x0`` (evaluated at that value),
  in the mode ``mode0`` names (a memory mode; by default the mode the
  model's domains give ``x0``).
  Near a fold the previous final state can lie in the basin of another
  attractor of the next value (for the block on a belt, inside the unstable
  stick-slip cycle, so the sweep falls onto the equilibrium while the stable
  cycle still exists): what a diagram shows then depends on the path.
* :attr:`SweepStart.OWN`: every value runs its own transient from ``x0``
  evaluated at its own parameters.  The values are then independent: the
  diagram shows the attractor whose basin holds that start, whatever the
  order of the values and the number of workers.

The values are split into one contiguous chunk of equal length per worker
process (the integrator's work per forcing period hardly depends on the
period, so equal numbers of values are about equal work).  A value
whose simulation fails (chattering, a state in no mode, ...) is recorded in
:attr:`SweepResult.failures`.  The rule used is recorded as
:attr:`SweepResult.start` (and in its file).

Each value costs two calls of the compiled integrator: one over the transient,
one over the sampling window with dense output; the samples are read off the
dense output (DOP853's continuous extension, accurate to the integration
tolerance), not by stopping the integrator at every section crossing.
"""

from __future__ import annotations

import csv
import enum
import math
import multiprocessing
import os
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from io import StringIO
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # matplotlib is imported where a figure is drawn: `import saltation` does not import it
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

from saltation.engine.flow import Flow, Tolerances, Trajectory, dense_evaluate
from saltation.errors import ModelError, SaltationError
from saltation.model.system import PiecewiseSystem
from saltation.output.io import (
    PERIOD_MAP_FORMAT,
    SWEEP_FORMAT,
    _Fields,
    _read_json,
    check_format,
    format_header,
    write_atomically,
    write_json,
)

__all__ = ["PeriodMap", "SweepResult", "SweepStart", "attractor_period", "period_map", "sweep"]

_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: Dense-output evaluations per integration step when looking for maxima.
_MAXIMA_GRID = 12
#: Golden-section iterations refining each maximum (0.618**60 ~ 3e-13 of the bracket).
_MAXIMA_ITERATIONS = 60
#: ``x_1`` varying by less than this (relative) over the sampling window has no maxima.
_FLAT = 1e-9


class SweepStart(enum.Enum):
    """Where each parameter value of a sweep (or each cell of a row of a period map) starts.

    The values are the command line's words (``saltation sweep --start previous|own``) and the
    files' (``"start"``).
    """

    #: From the final state and mode of the value before it (the first value of each chunk, and the
    #: value after a failed one, from ``x0``): follows an attractor for as long as it lasts.
    PREVIOUS = "previous"
    #: Each value its own transient, from ``x0`` evaluated at that value's parameters.
    OWN = "own"


#: A start state, or a function of the parameter values (every parameter's name to its value) giving one.
StartState = Sequence[float] | np.ndarray | Callable[[Mapping[str, float]], Sequence[float]]


def _start_rule(start: SweepStart | str) -> SweepStart:
    """``start`` as a :class:`SweepStart` (its value as a string is accepted)."""
    try:
        return SweepStart(start.value if isinstance(start, SweepStart) else start)
    except ValueError:
        raise ValueError(
            f"start must be one of {', '.join(repr(k.value) for k in SweepStart)} (a SweepStart), got {start!r}"
        ) from None


def _start_states(
    system: PiecewiseSystem, x0: StartState | None, rows: np.ndarray, where: Callable[[np.ndarray], str]
) -> np.ndarray:
    """The start state of every parameter vector in ``rows`` (shape (m, len(parameters))): ``x0`` itself,
    zeros, or ``x0`` called with each row's parameters (in order, once each); shape (m, n).

    Raises
    ------
    ModelError
        If a state (given or returned) has the wrong number of components or is not finite; the
        message names the parameter values (``where(row)``) of a returned one.
    """
    n, m = system.n, rows.shape[0]
    if x0 is None:
        return np.zeros((m, n))
    if not callable(x0):
        state = np.asarray(x0, dtype=float).reshape(-1)
        if state.shape != (n,):
            raise ModelError(f"x0 must have {n} components {list(system.state_names)}, got {state.size}")
        if not np.all(np.isfinite(state)):
            raise ModelError(f"x0 must be finite, got {state.tolist()}")
        return np.tile(state, (m, 1))
    out = np.empty((m, n))
    for i, p in enumerate(rows):
        values = dict(zip(system.parameter_names, map(float, p)))
        try:
            state = np.asarray(x0(values), dtype=float).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ModelError(f"x0({where(p)}) did not return {n} numbers: {exc}") from exc
        if state.shape != (n,):
            raise ModelError(
                f"x0({where(p)}) returned {state.size} component{'s' if state.size != 1 else ''}; the states are "
                f"{list(system.state_names)}"
            )
        if not np.all(np.isfinite(state)):
            raise ModelError(f"x0({where(p)}) returned a state that is not finite: {state.tolist()}")
        out[i] = state
    return out


def _describe_x0(x0: StartState | None) -> list[float] | str:
    """``x0`` as the files record it: the state, or the name of the function."""
    if x0 is None:
        return "zeros"
    if callable(x0):
        name = getattr(x0, "__qualname__", None) or type(x0).__name__
        module = getattr(x0, "__module__", None)
        return f"function {module}.{name}" if module else f"function {name}"
    return [float(v) for v in np.asarray(x0, dtype=float).reshape(-1)]


@dataclass(frozen=True)
class SweepResult:
    """Points of a brute-force diagram.

    Attributes
    ----------
    model : str
        Name of the model.
    parameter_name : str
        Name of the swept parameter (``"parameter"`` in files).
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
        ``periods``, ``transient``, ``t0``, the time of one period for autonomous systems,
        ``x0``: the start state, ``"zeros"``, or ``"function NAME"`` for a function of the parameters,
        and ``mode0``, the mode the starts are in, where it was named (:func:`sweep`).
    start : SweepStart
        Where each value started: from the previous value's final state, or its own start
        (:class:`SweepStart`).  Files written before it was recorded were all ``PREVIOUS``.
    largest_exponents : ndarray, shape (m,), or None
        With ``lyapunov=True``: the largest Lyapunov exponent at each value, over the sampled periods
        (:func:`saltation.orbits.lyapunov.lyapunov_exponents`; ``nan`` where the value failed): it tells
        a long period or a slow transient (negative) from chaos (positive).
    """

    model: str
    parameter_name: str
    values: np.ndarray
    counts: np.ndarray
    parameter_points: np.ndarray
    states: np.ndarray
    state_names: tuple[str, ...]
    section: str
    failures: tuple[tuple[float, str], ...] = ()
    settings: dict = field(default_factory=dict)
    start: SweepStart = SweepStart.PREVIOUS
    largest_exponents: np.ndarray | None = None

    @property
    def x(self) -> np.ndarray:
        """First state of every point: with :attr:`parameter_points`, the pair to plot."""
        return self.states[:, 0]

    def points(self, state: int | str = 0) -> tuple[np.ndarray, np.ndarray]:
        """``(parameter_points, states[:, state])``: the flat pair of arrays to plot.

        Parameters
        ----------
        state : int or str
            The state, by index or name.

        Returns
        -------
        parameter_points : ndarray, shape (N,)
            The parameter value of each point.
        values : ndarray, shape (N,)
            That state at each point.

        Raises
        ------
        ModelError
            For an unknown state name or an index out of range.
        """
        return self.parameter_points, self.states[:, self._state_index(state)]

    def at(self, value_index: int) -> np.ndarray:
        """States sampled at ``values[value_index]``.

        Parameters
        ----------
        value_index : int
            Index into :attr:`values`.

        Returns
        -------
        ndarray, shape (counts[value_index], n)
            The states sampled at that value (none where its simulation failed).
        """
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
        """A JSON-ready dictionary (non-finite numbers as strings).

        Returns
        -------
        dict
            The record :meth:`from_dict` reads, with the format header.
        """

        def enc(v: float) -> float | str:
            return float(v) if math.isfinite(v) else str(float(v))

        return {
            **format_header(SWEEP_FORMAT),
            "model": self.model,
            "parameter": self.parameter_name,
            "section": self.section,
            "start": self.start.value,
            "state_names": list(self.state_names),
            "settings": dict(self.settings),
            "values": [enc(v) for v in self.values],
            "counts": [int(c) for c in self.counts],
            "parameter_points": [enc(v) for v in self.parameter_points],
            "states": [[enc(v) for v in row] for row in self.states],
            "failures": [[enc(v), msg] for v, msg in self.failures],
            **({} if self.largest_exponents is None else {"largest_exponents": [enc(v) for v in self.largest_exponents]}),
        }

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "sweep record") -> SweepResult:
        """The result :meth:`to_dict` describes, every field checked (a record without ``"start"``, written
        before it was recorded, started each value from the previous one: :attr:`SweepStart.PREVIOUS`).

        Parameters
        ----------
        d : dict
            A record as :meth:`to_dict` returns it (or as read from its JSON file).
        source : str
            What ``d`` was read from, for the messages (a file name).

        Returns
        -------
        SweepResult

        Raises
        ------
        FileFormatError
            If ``d`` is not a sweep record, or a field is missing, of the wrong type or of the wrong
            length (``counts`` as long as ``values``, as many ``states`` and ``parameter_points`` as
            the counts add up to, each state as long as ``state_names``, each point's parameter its
            value's); the message names ``source`` and the field.
        """
        f = _Fields(source)
        d = check_format(d, SWEEP_FORMAT, f)  # (or a name of an earlier release: FORMAT_NAMES)
        names = f.take(d, "", "state_names", f.strings)
        if not names:
            f.fail("state_names", "expected at least one state name")
        values = f.take(d, "", "values", lambda v, field: f.reals(v, field, finite=True))
        counts = f.take(d, "", "counts", lambda v, field: f.list(v, field, len(values)))
        counts = np.array([f.integer(c, f"counts[{k}]", minimum=0) for k, c in enumerate(counts)], dtype=int)
        total = int(counts.sum())
        points = f.take(d, "", "parameter_points", lambda v, field: f.reals(v, field, total, finite=True))
        expected = np.repeat(values, counts)
        for k in np.flatnonzero(points != expected)[:1]:
            f.fail(f"parameter_points[{k}]", f"is {float(points[k])!r}; by the counts it is a point of the value "
                   f"{float(expected[k])!r}")
        rows = f.take(d, "", "states", lambda v, field: f.list(v, field, total))
        states = np.array([f.reals(r, f"states[{k}]", len(names)) for k, r in enumerate(rows)],
                          dtype=float).reshape(-1, len(names))
        failures = [f.list(v, f"failures[{k}]", 2) for k, v in enumerate(f.take(d, "", "failures", f.list))]
        return cls(
            model=f.take(d, "", "model", f.string),
            parameter_name=f.take(d, "", "parameter", f.string),
            values=values,
            counts=counts,
            parameter_points=points,
            states=states,
            state_names=names,
            section=f.take(d, "", "section", lambda v, field: f.choice(v, field, {"poincare": "poincare",
                                                                                   "maxima": "maxima"})),
            failures=tuple((f.real(v, f"failures[{k}][0]"), f.string(m, f"failures[{k}][1]"))
                           for k, (v, m) in enumerate(failures)),
            settings=dict(f.take(d, "", "settings", f.obj, {})),
            start=f.take(d, "", "start", lambda v, field: f.choice(v, field, {k.value: k for k in SweepStart}), SweepStart.PREVIOUS),
            largest_exponents=f.take(d, "", "largest_exponents", lambda v, field: f.reals(v, field, len(values)), None),
        )

    def save(self, path: str | PathLike[str]) -> Path:
        """Write the points as JSON (``.json``) or CSV (any other suffix), atomically.

        The CSV has one row per point: the parameter value, then every state
        (full precision); the JSON keeps everything, :meth:`load` reads it back.
        The file is written to a temporary file next to it and renamed over it
        (:func:`saltation.output.io.write_atomically`): on a failure the old file is untouched.

        Parameters
        ----------
        path : str or path-like
            The file to write.

        Returns
        -------
        Path
            The file written.

        Raises
        ------
        OSError
            If the file cannot be written.
        """
        path = Path(path)
        if path.suffix.lower() == ".json":
            return write_json(self.to_dict(), path)
        buffer = StringIO(newline="")
        w = csv.writer(buffer)
        w.writerow([self.parameter_name, *self.state_names])
        for lam, row in zip(self.parameter_points, self.states):
            w.writerow([repr(float(lam)), *(repr(float(v)) for v in row)])
        return write_atomically({path: buffer.getvalue()})[0]

    @classmethod
    def load(cls, path: str | PathLike[str]) -> SweepResult:
        """Read a sweep written by :meth:`save` as JSON.

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        SweepResult

        Raises
        ------
        FileFormatError
            If the file is not a complete sweep record (naming the file and the field).
        OSError
            If the file cannot be read.
        """
        return cls.from_dict(_read_json(path, bare_constants=True), source=str(path))

    def __repr__(self) -> str:
        v = self.values
        span = f"{v[0]:.6g} .. {v[-1]:.6g}" if v.size else "no values"
        return (f"SweepResult({self.model!r}, {self.parameter_name} {span}, {v.size} values, {len(self.parameter_points)} "
                f"points ({self.section}), {len(self.failures)} failed)")

    # -- figure ------------------------------------------------------------------------------
    def plot(self, ax: Axes | None = None, *, state: int | str = 0, **style) -> Figure:
        """Scatter the points over the parameter; draws on ``ax`` or on a new Figure (no pyplot state).

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on (a new figure by default).
        state : int or str
            The state plotted, by index or name.
        **style
            Keyword arguments of :meth:`matplotlib.axes.Axes.scatter`, over the defaults (black dots of 2
            points square).

        Returns
        -------
        matplotlib.figure.Figure
            The figure drawn on.

        Raises
        ------
        ModelError
            For an unknown state name or an index out of range.
        """
        from saltation.output.plotting import figure_of, new_figure

        k = self._state_index(state)
        exponent_ax = None
        if ax is None and self.largest_exponents is not None:  # the diagram over the largest exponent
            fig = new_figure((6.4, 6.0))
            ax, exponent_ax = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
        elif ax is None:
            fig = new_figure((6.4, 4.4))
            ax = fig.add_subplot()
        else:
            fig = figure_of(ax)
        # dots of 2 points square: seen on a page at any density (a point per sample, no edge)
        kw = {"s": 2.0, "color": "k", "marker": ".", "linewidths": 0, "rasterized": True} | style
        ax.scatter(self.parameter_points, self.states[:, k], **kw)
        ax.set_xlabel(self.parameter_name)
        name = self.state_names[k]
        if self.section == "poincare":
            ax.set_ylabel(f"{name} (Poincare section)")
        else:
            ax.set_ylabel(f"{name} at maxima of {self.state_names[0]}")
        ax.set_title(f"{self.model}: brute-force diagram")
        if exponent_ax is not None:
            exponent_ax.axhline(0.0, color="0.6", linewidth=0.8)
            exponent_ax.plot(self.values, self.largest_exponents, color="k", linewidth=1.0, marker=".", markersize=2.5,
                             gid="largest_exponent")
            exponent_ax.set_ylabel(r"largest Lyapunov exponent $\lambda_1$")
            exponent_ax.set_xlabel(self.parameter_name)
        return fig


# -- the sweep ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Job:
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


def sweep(
    system: PiecewiseSystem,
    parameter: str,
    values: Sequence[float],
    *,
    periods: int = 200,
    transient: int = 100,
    x0: StartState | None = None,
    start: SweepStart | str = SweepStart.PREVIOUS,
    poincare: bool = True,
    workers: int | None = None,
    tolerances: Tolerances | None = None,
    parameters: Mapping[str, float] | None = None,
    period: float | None = None,
    t0: float = 0.0,
    client=None,
    lyapunov: bool = False,
    mode0: str | None = None,
) -> SweepResult:
    """Brute-force diagram: simulate at each parameter value and sample the attractor.

    Parameters
    ----------
    system : PiecewiseSystem
        The model.
    parameter : str
        Name of the swept parameter.
    values : sequence of float
        Parameter values, simulated in this order.
    periods : int
        Number of periods sampled per value (forced systems: section points).
    transient : int
        Number of periods simulated and discarded first.
    x0 : array_like, shape (n,), or callable, optional
        The start state (zeros by default), or a function
        ``parameters -> state`` of a mapping of every parameter's name to its
        value at the value being started (called once per value, here,
        before any simulation).  Which values start from it is ``start``'s rule.
    start : SweepStart or {"previous", "own"}
        ``PREVIOUS`` (default): each value starts from the final state of the
        value before it in its worker's chunk; the first value of a chunk,
        and the value after a failed one, start from ``x0``.  ``OWN``: every
        value starts from ``x0`` at its own parameters (the values are
        independent: the result does not depend on ``workers``).
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
    client : dask.distributed.Client, optional
        Run the chunks as tasks on this Dask cluster instead of local
        processes (``workers`` chunks; default: one per thread of the
        cluster).  The same chunks give the same results as a local run.
    lyapunov : bool
        Also compute, at each value, the largest Lyapunov exponent over the sampled periods
        (:func:`saltation.orbits.lyapunov.lyapunov_exponents`), as
        :attr:`SweepResult.largest_exponents` (``nan`` where the value failed).
    mode0 : str, optional
        The mode every start from ``x0`` is in: a memory mode (a latch, a relay with hysteresis, a
        thermostat), which the state alone does not tell from another mode with the same domain.  A
        value that starts from the previous one's final state continues in that one's final mode.  A
        start outside the mode's domain fails its value (:attr:`SweepResult.failures` says why).  It
        is recorded in :attr:`SweepResult.settings`.  None (the default): the model's domains give
        the mode.

    Returns
    -------
    SweepResult
        With the rule used as :attr:`SweepResult.start`.

    Raises
    ------
    ModelError
        For an unknown parameter or mode (the message lists the model's), or a start state (given or
        returned by ``x0``) with the wrong number of components or not finite.
    ValueError
        For no values, values or ``t0`` not finite, ``periods`` not a
        positive integer, ``transient`` not a non-negative one, ``period``
        not positive and finite, ``workers`` below 1, or an unknown ``start``.
    KernelCacheError
        If the model cannot be compiled into the kernel cache.

    References
    ----------
    Hairer, Norsett and Wanner (1993), *Solving Ordinary Differential Equations I: Nonstiff Problems*,
    2nd ed., Springer (DOP853's dense output, on which the samples are read).  Kiefer (1953),
    "Sequential minimax search for a maximum", Proc. Amer. Math. Soc. 4 (golden-section search of the
    maxima).
    """
    p_index = system.parameter_index(parameter)
    mode0 = None if mode0 is None else system.mode_names[system.mode_index(mode0)]
    rule = _start_rule(start)
    values = np.asarray(values, dtype=float).reshape(-1)
    if values.size == 0:
        raise ValueError("sweep needs at least one parameter value")
    if not np.all(np.isfinite(values)):
        raise ValueError(f"parameter values must be finite, got {values.tolist()}")
    if int(periods) != periods or periods < 1 or int(transient) != transient or transient < 0:
        raise ValueError(f"periods must be a positive and transient a non-negative integer, got {periods}, {transient}")
    if not math.isfinite(t0):
        raise ValueError(f"t0 must be finite, got {t0}")
    base = system.parameter_vector(parameters)
    autonomous = system.is_autonomous
    if autonomous:
        period = 2.0 * math.pi if period is None else float(period)
        if not (math.isfinite(period) and period > 0):
            raise ValueError(f"period must be positive and finite, got {period}")
    else:
        period = None
    rows = np.tile(base, (values.size, 1))
    rows[:, p_index] = values
    starts = _start_states(system, x0, rows, lambda p: f"{parameter}={p[p_index]:.10g}")
    use_poincare = bool(poincare) and not autonomous

    n_workers = _workers(workers, client)
    n_workers = min(n_workers, values.size)
    pieces = np.array_split(np.arange(values.size), n_workers)
    jobs = [
        _Job(values[k], starts[k], rule is SweepStart.OWN, p_index, base, int(periods), int(transient), use_poincare,
             period, float(t0), tolerances, bool(lyapunov), mode0)
        for k in pieces
    ]
    results = _run_jobs(system, jobs, client)

    counts, samples, failures, exponents = [], [], [], []
    for chunk_counts, chunk_samples, chunk_failures, chunk_exponents in results:
        counts += chunk_counts
        samples += chunk_samples
        failures += chunk_failures
        exponents += chunk_exponents
    counts_arr = np.array(counts, dtype=int)
    states = np.concatenate(samples) if samples else np.zeros((0, system.n))
    settings = {"periods": int(periods), "transient": int(transient), "t0": float(t0), "x0": _describe_x0(x0)}
    if period is not None:
        settings["period"] = period
    if mode0 is not None:
        settings["mode0"] = mode0
    return SweepResult(
        model=system.name,
        parameter_name=parameter,
        values=values,
        counts=counts_arr,
        parameter_points=np.repeat(values, counts_arr),
        states=states.reshape(-1, system.n),
        state_names=tuple(system.state_names),
        section="poincare" if use_poincare else "maxima",
        failures=tuple(failures),
        settings=settings,
        start=rule,
        largest_exponents=np.array(exponents, dtype=float) if lyapunov else None,
    )


# -- two-parameter maps -------------------------------------------------------------------------
@dataclass(frozen=True)
class PeriodMap:
    """A two-parameter brute-force map: the period of the attractor in each cell of a grid.

    Attributes
    ----------
    model : str
    parameter_name, parameter2_name : str
        The parameters of the columns and of the rows (``"parameter"``, ``"parameter2"`` in files).
    values, values2 : ndarray
        Their values.
    periods : ndarray of int, shape (len(values2), len(values))
        The attractor's period in forcing periods; 0 where none up to
        ``max_period`` was found (chaos, a longer period, or not settled),
        -1 where the simulation failed.
    max_period : int
    failures : tuple of (float, float, str)
        ``(value, value2, message)`` of each failed cell.
    settings : dict
        ``periods``, ``transient``, ``tolerance``, ``t0``, ``x0`` and ``mode0`` where named (as in
        :class:`SweepResult`).
    start : SweepStart
        Where each cell started (:class:`SweepStart`); ``PREVIOUS`` for files written before it was
        recorded.
    largest_exponents : ndarray, shape (len(values2), len(values)), or None
        With ``lyapunov=True``: each cell's largest Lyapunov exponent over the sampled periods
        (``nan`` where the cell failed).
    """

    model: str
    parameter_name: str
    parameter2_name: str
    values: np.ndarray
    values2: np.ndarray
    periods: np.ndarray
    max_period: int
    failures: tuple[tuple[float, float, str], ...] = ()
    settings: dict = field(default_factory=dict)
    start: SweepStart = SweepStart.PREVIOUS
    largest_exponents: np.ndarray | None = None

    def to_dict(self) -> dict:
        """A JSON-ready dictionary.

        Returns
        -------
        dict
            The record :meth:`from_dict` reads, with the format header.
        """
        return {
            **format_header(PERIOD_MAP_FORMAT),
            "model": self.model,
            "parameter": self.parameter_name,
            "parameter2": self.parameter2_name,
            "start": self.start.value,
            "values": [float(v) for v in self.values],
            "values2": [float(v) for v in self.values2],
            "periods": [[int(c) for c in row] for row in self.periods],
            "max_period": int(self.max_period),
            "failures": [[float(a), float(b), m] for a, b, m in self.failures],
            "settings": dict(self.settings),
            **({} if self.largest_exponents is None else {"largest_exponents": [
                [float(v) if math.isfinite(v) else str(float(v)) for v in row] for row in self.largest_exponents]}),
        }

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "period map record") -> PeriodMap:
        """The map :meth:`to_dict` describes, every field checked (a record without ``"start"`` is
        :attr:`SweepStart.PREVIOUS`).

        Parameters
        ----------
        d : dict
            A record as :meth:`to_dict` returns it (or as read from its JSON file).
        source : str
            What ``d`` was read from, for the messages (a file name).

        Returns
        -------
        PeriodMap

        Raises
        ------
        FileFormatError
            If ``d`` is not a period map, or a field is missing, of the wrong type or of the wrong
            length (``periods`` one row of ``len(values)`` integers from -1 to ``max_period`` per
            value of ``values2``); the message names ``source`` and the field.
        """
        f = _Fields(source)
        d = check_format(d, PERIOD_MAP_FORMAT, f)  # (or a name of an earlier release: FORMAT_NAMES)
        values = f.take(d, "", "values", lambda v, field: f.reals(v, field, finite=True))
        values2 = f.take(d, "", "values2", lambda v, field: f.reals(v, field, finite=True))
        max_period = f.take(d, "", "max_period", lambda v, field: f.integer(v, field, minimum=1))
        rows = f.take(d, "", "periods", lambda v, field: f.list(v, field, len(values2)))
        periods = np.array(
            [[f.integer(c, f"periods[{i}][{j}]", minimum=-1, maximum=max_period)
              for j, c in enumerate(f.list(row, f"periods[{i}]", len(values)))] for i, row in enumerate(rows)],
            dtype=int,
        ).reshape(len(values2), len(values))
        failures = [f.list(v, f"failures[{k}]", 3) for k, v in enumerate(f.take(d, "", "failures", f.list))]
        return cls(
            model=f.take(d, "", "model", f.string),
            parameter_name=f.take(d, "", "parameter", f.string),
            parameter2_name=f.take(d, "", "parameter2", f.string),
            values=values,
            values2=values2,
            periods=periods,
            max_period=max_period,
            failures=tuple((f.real(a, f"failures[{k}][0]"), f.real(b, f"failures[{k}][1]"),
                            f.string(m, f"failures[{k}][2]")) for k, (a, b, m) in enumerate(failures)),
            settings=dict(f.take(d, "", "settings", f.obj)),
            start=f.take(d, "", "start", lambda v, field: f.choice(v, field, {k.value: k for k in SweepStart}), SweepStart.PREVIOUS),
            largest_exponents=f.take(d, "", "largest_exponents", lambda v, field: np.array(
                [f.reals(row, f"{field}[{k}]", len(values)) for k, row in enumerate(f.list(v, field, len(values2)))]), None),
        )

    def save(self, path: str | PathLike[str]) -> Path:
        """Write the map as JSON, atomically (:func:`saltation.output.io.write_atomically`); :meth:`load` reads it.

        Parameters
        ----------
        path : str or path-like
            The file to write.

        Returns
        -------
        Path
            The file written.

        Raises
        ------
        OSError
            If the file cannot be written.
        """
        return write_json(self.to_dict(), path)

    @classmethod
    def load(cls, path: str | PathLike[str]) -> PeriodMap:
        """Read a map written by :meth:`save`.

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        PeriodMap

        Raises
        ------
        FileFormatError
            If the file is not a complete period map (naming the file and the field).
        OSError
            If the file cannot be read.
        """
        return cls.from_dict(_read_json(path, bare_constants=True), source=str(path))

    def __repr__(self) -> str:
        found = self.periods[self.periods > 0]
        return (f"PeriodMap({self.model!r}, {self.parameter_name} x {self.parameter2_name}: {self.values.size} x "
                f"{self.values2.size} cells, periods up to {self.max_period}: {found.size} periodic, "
                f"{int(np.count_nonzero(self.periods == 0))} not, {len(self.failures)} failed)")

    def plot(self, ax: Axes | None = None) -> Figure:
        """The map: one colour per period (1 ... max_period).

        Grey where no period up to ``max_period`` settled within the transient (chaos, a longer period,
        or a slow transient: the colour bar says "not periodic"); white for failures.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on (a new figure by default).

        Returns
        -------
        matplotlib.figure.Figure
            The figure drawn on, with its colour bar.
        """
        from matplotlib.colors import BoundaryNorm, ListedColormap

        from saltation.output.plotting import figure_of, new_figure

        own = ax is None
        exponent_ax = None
        if own and self.largest_exponents is not None:  # the periods above, the largest exponent below
            fig = new_figure((6.4, 8.4))
            ax, exponent_ax = fig.subplots(2, 1, sharex=True)
        elif own:
            fig = new_figure((6.4, 4.8))
            ax = fig.add_subplot()
        else:
            fig = figure_of(ax)
        import matplotlib

        base = matplotlib.colormaps["tab20"]
        colours = ["white", "0.6"] + [base(k % 20) for k in range(self.max_period)]
        cmap = ListedColormap(colours)
        norm = BoundaryNorm(np.arange(-1.5, self.max_period + 1.5), cmap.N)
        mesh = ax.pcolormesh(_edges(self.values), _edges(self.values2), self.periods, cmap=cmap, norm=norm)
        bar = fig.colorbar(mesh, ax=ax, ticks=np.arange(-1, self.max_period + 1))
        # "not periodic": no period up to max_period within the transient (chaos, a longer period, or not settled)
        bar.ax.set_yticklabels(["failed", f"no period <= {self.max_period}"]
                               + [str(k) for k in range(1, self.max_period + 1)])
        bar.set_label("period of the attractor (forcing periods)")
        ax.set_xlabel(self.parameter_name)
        ax.set_ylabel(self.parameter2_name)
        ax.set_title(f"{self.model}: period of the attractor")
        if exponent_ax is not None:
            limit = float(np.nanmax(np.abs(self.largest_exponents))) if np.isfinite(self.largest_exponents).any() else 1.0
            mesh2 = exponent_ax.pcolormesh(_edges(self.values), _edges(self.values2), self.largest_exponents,
                                           cmap="RdBu_r", vmin=-limit, vmax=limit)
            fig.colorbar(mesh2, ax=exponent_ax).set_label(r"largest Lyapunov exponent $\lambda_1$ (red: chaos)")
            exponent_ax.set_xlabel(self.parameter_name)
            exponent_ax.set_ylabel(self.parameter2_name)
        return fig


def _edges(v: np.ndarray) -> np.ndarray:
    """Cell edges around grid values (midpoints; a single value gets a unit cell)."""
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


def attractor_period(samples: np.ndarray, max_period: int, tolerance: float = 1e-6) -> int:
    """The smallest period of a sequence of stroboscopic samples, or 0 when there is none.

    The smallest ``k <= max_period`` with ``x_{j+k} = x_j`` for every sample (to ``tolerance``
    relative to the samples' size).

    Parameters
    ----------
    samples : ndarray, shape (m, n)
        States at consecutive forcing periods.
    max_period : int
        Longest period looked for.
    tolerance : float
        Relative tolerance of the comparison.

    Returns
    -------
    int
        The period in forcing periods, or 0 (chaos, a longer period, or not settled).
    """
    samples = np.asarray(samples, dtype=float)
    scale = tolerance * (1.0 + float(np.abs(samples).max(initial=0.0)))
    for k in range(1, max_period + 1):
        if samples.shape[0] > k and float(np.abs(samples[k:] - samples[:-k]).max()) <= scale:
            return k
    return 0


def period_map(
    system: PiecewiseSystem,
    parameter: str,
    values: Sequence[float],
    parameter2: str,
    values2: Sequence[float],
    *,
    max_period: int = 16,
    periods: int | None = None,
    transient: int = 200,
    tolerance: float = 1e-6,
    x0: StartState | None = None,
    start: SweepStart | str = SweepStart.PREVIOUS,
    parameters: Mapping[str, float] | None = None,
    workers: int | None = None,
    client=None,
    tolerances: Tolerances | None = None,
    t0: float = 0.0,
    lyapunov: bool = False,
    mode0: str | None = None,
) -> PeriodMap:
    """Two-parameter brute-force map of a forced system: the attractor's period in each grid cell.

    Each row (a value of ``parameter2``) is simulated like :func:`sweep` over
    ``values``, and the period is read off the stroboscopic samples
    (:func:`attractor_period`).  Rows run in local worker processes, or as
    Dask tasks on ``client``.

    Parameters
    ----------
    system : PiecewiseSystem
        A forced model.
    parameter, parameter2 : str
        The parameters of the columns and of the rows.
    values, values2 : sequence of float
        Their values (a row is simulated in the order of ``values``).
    max_period : int
        Longest period looked for; ``periods`` samples (default ``4 max_period``) are taken after
        ``transient`` forcing periods.
    periods : int, optional
        Forcing periods sampled per cell; more than ``max_period``.
    transient : int
        Forcing periods simulated and discarded first.
    tolerance : float
        Relative tolerance of the periodicity test.
    x0 : array_like, shape (n,), or callable, optional
        The start state (zeros by default), or a function ``parameters -> state``
        of a mapping of every parameter's name to its value in the cell being
        started (called once per cell, here, before any simulation).
    start : SweepStart or {"previous", "own"}
        ``PREVIOUS`` (default): each cell starts from the final state of the
        cell before it in its row (the first cell of a row, and the cell after
        a failed one, from ``x0``).  ``OWN``: every cell starts from ``x0`` at
        its own parameters.
    parameters : mapping, optional
        Values of the other parameters.
    workers : int, optional
        Worker processes (default: every available core); rows are dealt to them in turn.
    client : dask.distributed.Client, optional
        Run the rows as tasks on this Dask cluster.
    tolerances : Tolerances, optional
        Integration tolerances.
    t0 : float
        Initial time, the phase of the section.
    lyapunov : bool
        Also compute each cell's largest Lyapunov exponent over the sampled periods, as
        :attr:`PeriodMap.largest_exponents` (``nan`` where the cell failed).
    mode0 : str, optional
        The mode every start from ``x0`` is in (a memory mode; see :func:`sweep`), recorded in
        :attr:`PeriodMap.settings`.  None (the default): the model's domains give the mode.

    Returns
    -------
    PeriodMap
        With the rule used as :attr:`PeriodMap.start`.

    Raises
    ------
    ModelError
        For an autonomous model (its period is not a number of forcing periods), unknown or equal
        parameters, an unknown mode, or a start state (given or returned by ``x0``) with the wrong number of
        components or not finite.
    ValueError
        For no values or values not finite, ``max_period`` not a positive integer, ``periods`` not
        above it, ``transient`` not a non-negative integer, ``t0`` not finite, ``workers`` below 1,
        or an unknown ``start``.
    KernelCacheError
        If the model cannot be compiled into the kernel cache.
    """
    if system.is_autonomous:
        raise ModelError(f"a period map counts forcing periods; {system.name!r} is autonomous")
    p1, p2 = system.parameter_index(parameter), system.parameter_index(parameter2)
    if p1 == p2:
        raise ModelError(f"the two parameters of a map must differ, got {parameter!r} twice")
    values = np.asarray(values, dtype=float).reshape(-1)
    values2 = np.asarray(values2, dtype=float).reshape(-1)
    if values.size == 0 or values2.size == 0 or not (np.all(np.isfinite(values)) and np.all(np.isfinite(values2))):
        raise ValueError("a period map needs finite values of both parameters")
    if int(max_period) != max_period or max_period < 1:
        raise ValueError(f"max_period must be a positive integer, got {max_period}")
    periods = 4 * int(max_period) if periods is None else int(periods)
    if periods <= max_period or int(transient) != transient or transient < 0:
        raise ValueError(
            f"periods must exceed max_period and transient be a non-negative integer, got {periods}, {transient}"
        )
    if not math.isfinite(t0):
        raise ValueError(f"t0 must be finite, got {t0}")
    rule = _start_rule(start)
    mode0 = None if mode0 is None else system.mode_names[system.mode_index(mode0)]
    base = system.parameter_vector(parameters)
    jobs = []
    for v2 in values2:
        row = base.copy()
        row[p2] = v2
        cells = np.tile(row, (values.size, 1))
        cells[:, p1] = values
        starts = _start_states(
            system, x0, cells, lambda p: f"{parameter}={p[p1]:.10g}, {parameter2}={p[p2]:.10g}"
        )
        jobs.append(_Job(values, starts, rule is SweepStart.OWN, p1, row, periods, int(transient), True, None,
                         float(t0), tolerances, bool(lyapunov), mode0))
    n_workers = min(_workers(workers, client), len(jobs))
    grouped = [_RowsJob(jobs[k::n_workers]) for k in range(n_workers)]  # rows dealt round-robin to the workers
    results: list = [None] * len(jobs)
    for k, out in enumerate(_run_jobs(system, grouped, client)):
        for r, res in enumerate(out):
            results[k + r * n_workers] = res
    grid = np.zeros((values2.size, values.size), dtype=int)
    exponent_grid = np.full((values2.size, values.size), math.nan)
    failures = []
    for i, (counts, samples, fails, row_exponents) in enumerate(results):
        exponent_grid[i] = row_exponents
        failed = {v for v, _ in fails}
        it = iter(samples)
        for j, (value, c) in enumerate(zip(values, counts)):
            if c == 0 or float(value) in failed:
                grid[i, j] = -1
                continue
            grid[i, j] = attractor_period(next(it), int(max_period), tolerance)
        failures += [(float(v), float(values2[i]), m) for v, m in fails]
    return PeriodMap(
        model=system.name, parameter_name=parameter, parameter2_name=parameter2, values=values, values2=values2, periods=grid,
        max_period=int(max_period), failures=tuple(failures),
        settings={"periods": periods, "transient": int(transient), "tolerance": float(tolerance), "t0": float(t0),
                  "x0": _describe_x0(x0), **({} if mode0 is None else {"mode0": mode0})},
        start=rule,
        largest_exponents=exponent_grid if lyapunov else None,
    )


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
    from saltation.orbits.lyapunov import lyapunov_exponents

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
            t_sample = job.t0 + job.transient * T
            t_end = t_sample + job.periods * T
            if job.transient:
                traj = flow.run(x, job.t0, t_sample, p, mode0=mode, tolerances=job.tolerances)
                x, mode = traj.x1, traj.mode1
            exponent = math.nan
            if job.lyapunov:  # over the sampled periods, from the same state (a variational run beside the samples)
                exponent = lyapunov_exponents(flow, x, parameters=p, time=job.periods * T, t0=t_sample, interval=T,
                                              blocks=max(2, min(10, job.periods)), tolerances=job.tolerances,
                                              mode0=None if mode is None or "|" in mode else mode).largest
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
            largest.append(math.nan)
            x, mode = None, None  # the next value starts afresh
            continue
        counts.append(len(pts))
        samples.append(np.asarray(pts, dtype=float))
        largest.append(float(exponent))
    return counts, samples, failures, largest


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
