"""Brute-force (simulation-based) bifurcation diagrams.

:func:`sweep` simulates a model at each value of one parameter and samples what
it settles to:

* forced systems: the stroboscopic Poincare section ``x(t0 + k T)``, ``T`` the
  forcing period, for ``k`` = ``transient`` + 1, ..., ``transient + periods``;
* autonomous systems (or ``poincare=False``): the local maxima of the first
  state ``x_1`` (the state at each maximum is kept), found on the integrator's
  dense output and refined by golden-section search on it.  An orbit whose
  ``x_1`` has no maximum in the sampling window (an equilibrium) contributes
  its final state once;
* or a section named by ``section=`` (:mod:`~saltation.sweeps.sections`): a
  switching surface of the model (its switching events), or an expression of
  the states, parameters and time crossed in a ``direction`` (located on the
  dense output), such as the clock of a clocked model.  ``transient`` and
  ``periods`` then count crossings: the first ``transient`` are discarded,
  the next ``periods`` sampled.

What a "period" is: for a forced model, its forcing period ``T``; for an
autonomous model, a time unit ``period`` (``2 pi`` unless given), which is not
the period of its orbits.  The maxima are those within the ``periods`` time
units that follow ``transient`` of them.  With a section of crossings the time
unit only bounds the search: a value that has not crossed ``transient +
periods`` times within ``10 (transient + periods)`` time units gives the
crossings it has (its count may be 0: an equilibrium, or an attractor that does
not cross the section).

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
tolerance), not by stopping the integrator at every section crossing.  A
section of crossings is run in windows (with dense output for an expression)
until it has been crossed often enough.
"""

from __future__ import annotations

import enum
import logging
import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # matplotlib is imported where a figure is drawn: `import saltation` does not import it
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

from saltation.engine.flow import Tolerances
from saltation.errors import ModelError
from saltation.model.system import PiecewiseSystem
from saltation.sweeps.parallel import _Job, _RowsJob, _run_jobs, _workers
from saltation.sweeps.sections import Section, parse_section

_log = logging.getLogger(__name__)

__all__ = ["PeriodMap", "StartState", "SweepResult", "SweepStart", "attractor_period", "period_map", "sweep"]


def _deprecated(method: str, instead: str) -> None:
    """Warn that a record's method moved to the output layer (the method goes in release 0.3.0)."""
    warnings.warn(f"{method} is deprecated and goes in release 0.3.0: use {instead}", DeprecationWarning, stacklevel=3)


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


def _described(system: PiecewiseSystem, base: np.ndarray, tolerances: Tolerances | None) -> dict[str, Any]:
    """What a sweep's settings record of the model: every parameter's value (the swept ones at their base
    value), the integration tolerances and the units the model declares."""
    tol = tolerances or Tolerances()
    return {
        "parameters": {name: float(v) for name, v in zip(system.parameter_names, base)},
        "tolerances": {"rtol": float(tol.rtol), "atol": float(tol.atol),
                       "max_step": float(tol.max_step) if math.isfinite(tol.max_step) else "inf"},
        "units": {name: unit for name, unit in getattr(system, "units", {}).items() if unit},
    }


def _attributes(settings: Mapping[str, Any], **more: Any) -> dict[str, Any]:
    """NetCDF-ready attributes (strings and numbers): ``more``, the library's version, and each setting (a
    mapping or a list as JSON text)."""
    import json

    from saltation import __version__

    out: dict[str, Any] = {**more, "saltation_version": __version__}
    for key, value in settings.items():
        plain = isinstance(value, (str, int, float)) and not isinstance(value, bool)
        out[f"settings_{key}"] = value if plain else json.dumps(value)
    return out


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
        Number of points sampled at each value (0 where the simulation failed, listed in
        :attr:`failures`, or, with a section of crossings, where none was sampled).
    parameter_points : ndarray, shape (N,)
        Parameter value of each sampled point (``N = counts.sum()``).
    states : ndarray, shape (N, n)
        The sampled states.
    state_names : tuple of str
    section : str
        What was sampled, as :attr:`Section.code <saltation.sweeps.sections.Section.code>` writes it:
        ``"poincare"`` (stroboscopic section of a forced system), ``"maxima"`` (local maxima of the
        first state), ``"surface:NAME"`` (the switching events on a surface), ``"surface:NAME:WORD"``
        (those in one direction) or ``"expr:EXPRESSION:WORD"`` (the crossings of ``EXPRESSION = 0``),
        ``WORD`` one of ``rising``, ``falling``, ``either``.  :meth:`Section.from_code
        <saltation.sweeps.sections.Section.from_code>` reads it.
    failures : tuple of (float, str)
        Parameter values whose simulation failed, with the error message.
    settings : dict
        ``periods``, ``transient`` (windows of a time unit, or with a section of crossings numbers of
        crossings), ``t0``, ``period``, the time unit of an autonomous system,
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

    def to_xarray(self):
        """The sweep as an ``xarray.Dataset``: the swept parameter a dimension, the samples another.

        One variable per state (``state_<name>`` where the name is taken), of dimensions
        ``(parameter, "sample")``, padded with ``nan`` beyond each value's ``count`` (a variable of its
        own); ``largest_exponent`` where it was computed.  The attributes hold the model, the section,
        the start rule, the library's version, the failures and every setting (the model's parameters,
        the tolerances, the units: mappings as JSON text); each state's variable has its ``units`` where
        the model declares one.  ``dataset.to_netcdf(path)`` (or
        :func:`saltation.output.io.save_netcdf`) writes it, and ``xarray.open_dataset`` reads it back.

        Returns
        -------
        xarray.Dataset

        Raises
        ------
        MissingDependencyError
            If xarray is not installed (``pip install 'saltation[xarray]'``).
        """
        import json

        from saltation._optional import require

        xr = require("xarray", "xarray", "SweepResult.to_xarray")
        width = int(self.counts.max()) if self.counts.size else 0
        padded = np.full((self.values.size, width, len(self.state_names)), np.nan)
        ends = np.cumsum(self.counts)
        for k, (end, count) in enumerate(zip(ends, self.counts)):
            padded[k, :count] = self.states[end - count:end]
        dims = (self.parameter_name, "sample")
        units = self.settings.get("units", {})
        data = {}
        for j, name in enumerate(self.state_names):
            key = f"state_{name}" if name in (self.parameter_name, "sample", "count", "largest_exponent") else name
            data[key] = xr.Variable(dims, padded[:, :, j], attrs={"units": units[name]} if name in units else {})
        data["count"] = xr.Variable(dims[:1], np.asarray(self.counts, dtype=np.int64))
        if self.largest_exponents is not None:
            data["largest_exponent"] = xr.Variable(dims[:1], np.asarray(self.largest_exponents, dtype=float))
        coords = {self.parameter_name: xr.Variable(dims[:1], np.asarray(self.values, dtype=float),
                                                   attrs={"units": units[self.parameter_name]}
                                                   if self.parameter_name in units else {}),
                  "sample": np.arange(width)}
        attrs = _attributes(self.settings, model=self.model, parameter=self.parameter_name, section=self.section,
                            start=self.start.value, state_names=json.dumps(list(self.state_names)),
                            failures=json.dumps([[float(v), m] for v, m in self.failures]))
        return xr.Dataset(data, coords=coords, attrs=attrs)

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
        return self.parameter_points, self.states[:, self.state_index(state)]

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

    def state_index(self, state: int | str) -> int:
        """The index of a state given by index or name.

        Parameters
        ----------
        state : int or str
            The state, by index (negative ones count from the end) or name.

        Returns
        -------
        int

        Raises
        ------
        ModelError
            For an unknown state name or an index out of range.
        """
        if isinstance(state, str):
            try:
                return self.state_names.index(state)
            except ValueError:
                raise ModelError(f"unknown state {state!r}; states are {list(self.state_names)}") from None
        if not -len(self.state_names) <= state < len(self.state_names):
            raise ModelError(f"state index {state} out of range for states {list(self.state_names)}")
        return int(state)

    def __repr__(self) -> str:
        v = self.values
        span = f"{v[0]:.6g} .. {v[-1]:.6g}" if v.size else "no values"
        return (f"SweepResult({self.model!r}, {self.parameter_name} {span}, {v.size} values, {len(self.parameter_points)} "
                f"points ({self.section}), {len(self.failures)} failed)")

    # -- deprecated: files and figures are the output layer's (removed in release 0.3.0) -------
    def to_dict(self) -> dict:
        """The sweep's JSON record; deprecated, use :func:`saltation.output.codecs.sweep_to_dict`.

        Returns
        -------
        dict
            The record :meth:`from_dict` reads, with the format header.
        """
        _deprecated("SweepResult.to_dict", "saltation.output.codecs.sweep_to_dict")
        from saltation.output.codecs import sweep_to_dict

        return sweep_to_dict(self)

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "sweep record") -> SweepResult:
        """The sweep a record describes; deprecated, use :func:`saltation.output.codecs.sweep_from_dict`.

        Parameters
        ----------
        d : dict
            A record as :meth:`to_dict` returns it.
        source : str
            What ``d`` was read from, for the messages.

        Returns
        -------
        SweepResult
        """
        _deprecated("SweepResult.from_dict", "saltation.output.codecs.sweep_from_dict")
        from saltation.output.codecs import sweep_from_dict

        return sweep_from_dict(d, source=source)

    def save(self, path: str | PathLike[str]) -> Path:
        """Write the sweep as JSON or CSV; deprecated, use :func:`saltation.output.io.save_sweep`.

        Parameters
        ----------
        path : str or path-like
            The file to write (``.json``: JSON; any other suffix: CSV).

        Returns
        -------
        Path
            The file written.
        """
        _deprecated("SweepResult.save", "saltation.output.io.save_sweep")
        from saltation.output.io import save_sweep

        return save_sweep(self, path)

    @classmethod
    def load(cls, path: str | PathLike[str]) -> SweepResult:
        """Read a sweep's JSON file; deprecated, use :func:`saltation.output.io.load_sweep`.

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        SweepResult
        """
        _deprecated("SweepResult.load", "saltation.output.io.load_sweep")
        from saltation.output.io import load_sweep

        return load_sweep(path)

    def plot(self, ax: Axes | None = None, *, state: int | str = 0, **style: Any) -> Figure:
        """Draw the diagram; deprecated, use :func:`saltation.output.plotting.plot_sweep`.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on (a new figure by default).
        state : int or str
            The state plotted, by index or name.
        **style
            Keyword arguments of :meth:`matplotlib.axes.Axes.scatter`.

        Returns
        -------
        matplotlib.figure.Figure
            The figure drawn on.
        """
        _deprecated("SweepResult.plot", "saltation.output.plotting.plot_sweep")
        from saltation.output.plotting import plot_sweep

        return plot_sweep(self, ax, state=state, **style)


def sweep(
    system: PiecewiseSystem,
    parameter: str,
    values: Sequence[float],
    *,
    periods: int = 200,
    transient: int = 100,
    x0: StartState | None = None,
    start: SweepStart | str = SweepStart.PREVIOUS,
    poincare: bool | None = None,
    section: str | Section | None = None,
    direction: int | None = None,
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
        Number of periods sampled per value (forced systems: section points; autonomous systems: time
        units ``period``), or, with a section of crossings, number of crossings sampled.
    transient : int
        Number of periods (or crossings) simulated and discarded first.
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
    poincare : bool, optional
        Without ``section``: forced systems sample the Poincare section ``x(t0 + k T)``
        (True, the default) or the maxima of ``x_1`` (False); autonomous systems sample maxima.
    section : str or Section, optional
        What to sample (:func:`~saltation.sweeps.sections.parse_section`): ``"poincare"``
        (forced systems), ``"maxima"``, the name of a switching surface (its switching events: the
        transitions that fire on it and the sliding motions that start on it, each sampled just
        before the event), or an expression of the states, parameters and time ``t`` (``"x - 1"``,
        ``"v"``, ``"sin(omega*t)"``), sampled where it crosses zero in ``direction``, located on the
        dense output to rounding.  A name that is both a surface and a state is the surface
        (``"expr:NAME"`` is the state).  With a surface or an expression, ``periods`` and
        ``transient`` count crossings.  Recorded as :attr:`SweepResult.section`.
    direction : int, optional
        With a surface or an expression: +1 the crossings where it rises through zero, -1 where
        it falls, 0 both.  None (the default): a surface's every switching event (each in its
        transition's direction), an expression's rising crossings.
    workers : int, optional
        Worker processes (default: every available core; 1 runs in this process).
    tolerances : Tolerances, optional
        Integration tolerances (the flow's defaults otherwise).
    parameters : dict, optional
        Values of the other parameters.
    period : float, optional
        Autonomous systems: the time unit of ``periods`` and ``transient``, default ``2 pi`` (a
        time unit, not the period of an orbit: the maxima are sampled over ``periods * period``
        time units after ``transient * period``).  With a section of crossings it bounds the
        search: at most ``10 (transient + periods)`` of these units per value (forced systems:
        forcing periods).  Ignored for forced systems.
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
        For an unknown parameter or mode (the message lists the model's), a start state (given or
        returned by ``x0``) with the wrong number of components or not finite, an unknown section
        (the message lists the model's surfaces and states), or the section ``"poincare"`` of an
        autonomous model.
    ValueError
        For no values, values or ``t0`` not finite, ``periods`` not a
        positive integer, ``transient`` not a non-negative one, ``period``
        not positive and finite, ``workers`` below 1, an unknown ``start``,
        both ``section`` and ``poincare`` given, or a ``direction`` other than
        +1, -1, 0, or without a surface or an expression.
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
    chosen = _sweep_section(system, poincare, section, direction)
    rows = np.tile(base, (values.size, 1))
    rows[:, p_index] = values
    starts = _start_states(system, x0, rows, lambda p: f"{parameter}={p[p_index]:.10g}")
    use_poincare = chosen.kind == "poincare"

    n_workers = _workers(workers, client)
    n_workers = min(n_workers, values.size)
    pieces = np.array_split(np.arange(values.size), n_workers)
    jobs = [
        _Job(values[k], starts[k], rule is SweepStart.OWN, p_index, base, int(periods), int(transient), use_poincare,
             period, float(t0), tolerances, bool(lyapunov), mode0, chosen if chosen.crossings else None)
        for k in pieces
    ]
    _log.info("%s: sweep of %s over %d values in %d jobs", system.name, parameter, values.size, len(jobs))
    results = _run_jobs(system, jobs, client)

    counts, samples, failures, exponents = [], [], [], []
    for chunk_counts, chunk_samples, chunk_failures, chunk_exponents in results:
        counts += chunk_counts
        samples += chunk_samples
        failures += chunk_failures
        exponents += chunk_exponents
    counts_arr = np.array(counts, dtype=int)
    for value, message in failures:
        _log.warning("%s: the sweep failed at %s = %.10g: %s", system.name, parameter, value, message)
    states = np.concatenate(samples) if samples else np.zeros((0, system.n))
    settings = {"periods": int(periods), "transient": int(transient), "t0": float(t0), "x0": _describe_x0(x0),
                **_described(system, base, tolerances)}
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
        section=chosen.code,
        failures=tuple(failures),
        settings=settings,
        start=rule,
        largest_exponents=np.array(exponents, dtype=float) if lyapunov else None,
    )


def _sweep_section(system: PiecewiseSystem, poincare: bool | None, section: str | Section | None,
                   direction: int | None) -> Section:
    """The section a sweep samples: ``section`` read against the model, or without it the stroboscopic section
    of a forced model (unless ``poincare`` is False) and the maxima otherwise.

    Raises
    ------
    ModelError
        From :func:`~saltation.sweeps.sections.parse_section`.
    ValueError
        For both ``section`` and ``poincare``, a ``direction`` without a section, or a bad direction.
    """
    if section is None:
        if direction is not None:
            raise ValueError(f"direction {direction!r} belongs to a section (section=a surface or an expression)")
        return Section("poincare" if (poincare is None or poincare) and not system.is_autonomous else "maxima")
    if poincare is not None:
        raise ValueError("give section= or poincare=, not both (section='poincare' or 'maxima' says what "
                         "poincare= did)")
    return parse_section(system, section, direction)


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

    def to_xarray(self):
        """The map as an ``xarray.Dataset``: ``period`` (and ``largest_exponent`` where computed) over the
        dimensions ``(parameter2, parameter)``, attributes as :meth:`SweepResult.to_xarray` gives them (and
        ``max_period``).

        Returns
        -------
        xarray.Dataset

        Raises
        ------
        MissingDependencyError
            If xarray is not installed (``pip install 'saltation[xarray]'``).
        """
        import json

        from saltation._optional import require

        xr = require("xarray", "xarray", "PeriodMap.to_xarray")
        dims = (self.parameter2_name, self.parameter_name)
        units = self.settings.get("units", {})
        data = {"period": xr.Variable(dims, np.asarray(self.periods, dtype=np.int64),
                                      attrs={"description": "the attractor's period in forcing periods; 0: none up "
                                                            "to max_period; -1: the simulation failed"})}
        if self.largest_exponents is not None:
            data["largest_exponent"] = xr.Variable(dims, np.asarray(self.largest_exponents, dtype=float))
        coords = {name: xr.Variable((name,), np.asarray(values, dtype=float),
                                    attrs={"units": units[name]} if name in units else {})
                  for name, values in ((self.parameter_name, self.values), (self.parameter2_name, self.values2))}
        attrs = _attributes(self.settings, model=self.model, parameter=self.parameter_name,
                            parameter2=self.parameter2_name, max_period=int(self.max_period), start=self.start.value,
                            failures=json.dumps([[float(a), float(b), m] for a, b, m in self.failures]))
        return xr.Dataset(data, coords=coords, attrs=attrs)

    def __repr__(self) -> str:
        found = self.periods[self.periods > 0]
        return (f"PeriodMap({self.model!r}, {self.parameter_name} x {self.parameter2_name}: {self.values.size} x "
                f"{self.values2.size} cells, periods up to {self.max_period}: {found.size} periodic, "
                f"{int(np.count_nonzero(self.periods == 0))} not, {len(self.failures)} failed)")

    # -- deprecated: files and figures are the output layer's (removed in release 0.3.0) -------
    def to_dict(self) -> dict:
        """The map's JSON record; deprecated, use :func:`saltation.output.codecs.period_map_to_dict`.

        Returns
        -------
        dict
            The record :meth:`from_dict` reads, with the format header.
        """
        _deprecated("PeriodMap.to_dict", "saltation.output.codecs.period_map_to_dict")
        from saltation.output.codecs import period_map_to_dict

        return period_map_to_dict(self)

    @classmethod
    def from_dict(cls, d: dict, *, source: str = "period map record") -> PeriodMap:
        """The map a record describes; deprecated, use :func:`saltation.output.codecs.period_map_from_dict`.

        Parameters
        ----------
        d : dict
            A record as :meth:`to_dict` returns it.
        source : str
            What ``d`` was read from, for the messages.

        Returns
        -------
        PeriodMap
        """
        _deprecated("PeriodMap.from_dict", "saltation.output.codecs.period_map_from_dict")
        from saltation.output.codecs import period_map_from_dict

        return period_map_from_dict(d, source=source)

    def save(self, path: str | PathLike[str]) -> Path:
        """Write the map as JSON; deprecated, use :func:`saltation.output.io.save_period_map`.

        Parameters
        ----------
        path : str or path-like
            The file to write.

        Returns
        -------
        Path
            The file written.
        """
        _deprecated("PeriodMap.save", "saltation.output.io.save_period_map")
        from saltation.output.io import save_period_map

        return save_period_map(self, path)

    @classmethod
    def load(cls, path: str | PathLike[str]) -> PeriodMap:
        """Read a map's JSON file; deprecated, use :func:`saltation.output.io.load_period_map`.

        Parameters
        ----------
        path : str or path-like

        Returns
        -------
        PeriodMap
        """
        _deprecated("PeriodMap.load", "saltation.output.io.load_period_map")
        from saltation.output.io import load_period_map

        return load_period_map(path)

    def plot(self, ax: Axes | None = None) -> Figure:
        """Draw the map; deprecated, use :func:`saltation.output.plotting.plot_period_map`.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on (a new figure by default).

        Returns
        -------
        matplotlib.figure.Figure
            The figure drawn on, with its colour bar.
        """
        _deprecated("PeriodMap.plot", "saltation.output.plotting.plot_period_map")
        from saltation.output.plotting import plot_period_map

        return plot_period_map(self, ax)


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
                  "x0": _describe_x0(x0), **({} if mode0 is None else {"mode0": mode0}),
                  **_described(system, base, tolerances)},
        start=rule,
        largest_exponents=exponent_grid if lyapunov else None,
    )


