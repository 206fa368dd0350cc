"""A trajectory of the engine and its switching events: the records of an integration, read from the engine's result.

:class:`Trajectory` (with :class:`SwitchingEvent`, :class:`EventKind` and the run's :class:`Status`) is what
:meth:`~saltation.engine.flow.Flow.run` returns; :func:`unpack_result` reads it from the engine's packed
arrays (laid out as :mod:`saltation.engine._contract` says), raising the error its status names, and
:func:`join`, :func:`continued` and :func:`log_with_event` assemble trajectories from pieces.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import NamedTuple

import numpy as np

from saltation.engine import _contract as kc
from saltation.errors import (
    ChatteringError,
    IntegrationError,
    ModelError,
    NonFiniteError,
    SlidingError,
    StepSizeError,
)
from saltation.model.contacts import sticking_twins
from saltation.model.system import PiecewiseSystem


class Status(enum.IntEnum):
    """Outcome of an integration (the kernel's status codes, :mod:`saltation.engine._contract`)."""

    OK = kc.STATUS_OK
    MAX_EVENTS = kc.STATUS_MAX_EVENTS
    CHATTERING = kc.STATUS_CHATTERING
    STEP_TOO_SMALL = kc.STATUS_STEP_TOO_SMALL
    NON_FINITE = kc.STATUS_NON_FINITE
    SLIDING_UNDEFINED = kc.STATUS_SLIDING_UNDEFINED
    MAX_STEPS = kc.STATUS_MAX_STEPS
    TANGENTIAL = kc.STATUS_TANGENTIAL
    OUTSIDE_DOMAIN = kc.STATUS_OUTSIDE_DOMAIN
    ACCUMULATION = kc.STATUS_ACCUMULATION


# Status.OK as a plain int (an enum member costs a class attribute lookup per integration)
_STATUS_OK = kc.STATUS_OK


class EventKind(enum.IntEnum):
    """What happened at a switching event (the kernel's event kinds, :mod:`saltation.engine._contract`)."""

    TRANSITION = kc.EVENT_TRANSITION
    SLIDING_START = kc.EVENT_SLIDING_START
    SLIDING_END = kc.EVENT_SLIDING_END


class SwitchingEvent(NamedTuple):
    """One switching event of a trajectory.

    Attributes
    ----------
    t : float
        Event time.
    kind : EventKind
        A transition, the start of a sliding motion, or its end.
    transition : int
        Index of the transition that fired (-1 for the end of sliding).
    surface : str
        Name of the switching surface.
    mode_from, mode_to : str
        Modes before and after (for the start of sliding, ``mode_to`` is the
        mode on the far side of the surface).
    x_minus, x_plus : ndarray, shape (n,)
        State just before and just after the event (they differ for resets).
    saltation : ndarray, shape (n, n)
        Saltation matrix ``S`` with ``Phi(t+) = S Phi(t-)`` (eq. 8).
    """

    t: float
    kind: EventKind
    transition: int
    surface: str
    mode_from: str
    mode_to: str
    x_minus: np.ndarray
    x_plus: np.ndarray
    saltation: np.ndarray

    @property
    def signature(self) -> tuple[int, int, str]:
        """What identifies the event in an orbit's event sequence."""
        return (int(self.kind), self.transition, self.surface)

    def __repr__(self) -> str:
        which = f"transition {self.transition}" if self.transition >= 0 else "end of sliding"
        return (f"SwitchingEvent(t={self.t:.12g}, {self.kind.name.lower()}, {which}: {self.mode_from} -> {self.mode_to} "
                f"on {self.surface})")


class LoggedEvent(NamedTuple):
    """One switching event as the engine logs it (:meth:`Trajectory.logged`): plain numbers, no names.

    Attributes
    ----------
    t : float
        Event time.
    kind : int
        An :class:`EventKind` value.
    transition, surface, mode_from, mode_to : int
        Indices into the model's transitions (-1 for the end of sliding), surfaces and modes.
    """

    t: float
    kind: int
    transition: int
    surface: int
    mode_from: int
    mode_to: int


@dataclass(frozen=True)
class Accumulation:
    """Impacts that accumulate where the contact sticks (complete chatter), jumped to their limit.

    The run keeps the impacts until their times extrapolate to the accumulation point to the integration
    tolerance, then logs one event at that point into the stuck mode (:mod:`saltation.engine.chatter`).

    Attributes
    ----------
    t : float
        The accumulation time ``t_inf``, where the relative velocity vanishes.
    accuracy : float
        A bound on the error of ``t`` (the last two levels of its extrapolation differ by this much).
    impacts : int
        The impacts of the sequence kept in the event log (the last before the jump included).
    transition : int
        Index of the impact that accumulates.
    surface : str
        Its surface.
    mode : str
        The stuck mode the motion continues in.
    relative_speed : float
        The relative velocity after the last impact kept; the motion skipped stays within about
        ``relative_speed^2 / |a|`` of the surface (``a`` the relative acceleration of the free motion).
    x : ndarray, shape (n,)
        The state at ``t``, on the surface at zero relative velocity.
    """

    t: float
    accuracy: float
    impacts: int
    transition: int
    surface: str
    mode: str
    relative_speed: float
    x: np.ndarray = field(repr=False)


@dataclass(frozen=True)
class Trajectory:
    """Result of :func:`simulate`.

    Attributes
    ----------
    system : PiecewiseSystem
        The model.
    t0, t1 : float
        Start and end time (``t1 < t0`` in backward time).
    x0, x1 : ndarray, shape (n,)
        Initial and final state.
    mode0, mode1 : str
        Initial and final mode.
    event_log : tuple of ndarray
        The kernel's event log (times, integer columns, x-, x+, S); read it as
        :attr:`events`.
    monodromy : ndarray, shape (n, n) or None
        Fundamental solution matrix ``Phi(t1, t0)`` with every saltation
        matrix applied, when ``variational=True``.
    parameter_sensitivity : ndarray, shape (n,) or None
        ``d x(t1) / d p_k`` for the requested parameter ``k``.
    x_min, x_max : ndarray, shape (n,)
        Extremes of every state over the trajectory (from the dense output).
    sliding_at_end : bool
        Whether the trajectory ends on a sliding motion.
    velocity_end : ndarray, shape (n,)
        The vector field at the end: the final mode's, or Filippov's sliding
        field when the trajectory ends on a sliding motion.
    n_steps, n_rejected : int
        Accepted and rejected steps.
    accumulations : tuple of Accumulation
        The impact sequences that accumulated into a stuck mode (complete chatter) and were jumped to their
        limit, each with its event in :attr:`events` (a transition into the stuck mode at its time).
    """

    system: PiecewiseSystem
    t0: float
    t1: float
    x0: np.ndarray
    x1: np.ndarray
    mode0: str
    mode1: str
    event_log: tuple[np.ndarray, ...] = field(repr=False)
    monodromy: np.ndarray | None
    parameter_sensitivity: np.ndarray | None
    x_min: np.ndarray
    x_max: np.ndarray
    sliding_at_end: bool
    velocity_end: np.ndarray
    n_steps: int
    n_rejected: int
    _steps: tuple[np.ndarray, ...] | None = field(default=None, repr=False)
    accumulations: tuple[Accumulation, ...] = field(default=(), repr=False)

    @cached_property
    def events(self) -> list[SwitchingEvent]:
        """The switching events, in the order met."""
        return _switching_events(self.system, self.event_log)

    @property
    def n_events(self) -> int:
        """The number of switching events (without building their records)."""
        return len(self.event_log[0])

    def logged(self, k: int) -> LoggedEvent:
        """Event ``k`` (negative from the end) as the engine logged it: its time and plain integers.

        Cheap beside :attr:`events` (no record, no names): what a rule that runs at every evaluation reads,
        such as the seam rule of shooting, which compares the first and last events' kinds and modes.

        Parameters
        ----------
        k : int
            Index of the event, in the order met (``-1``: the last).

        Returns
        -------
        LoggedEvent
            ``(t, kind, transition, surface, mode_from, mode_to)``, the last four as indices into the model's
            transitions, surfaces and modes.

        Raises
        ------
        IndexError
            If the trajectory has no event ``k``.
        """
        row = self.event_log[1][k]
        return LoggedEvent(float(self.event_log[0][k]), int(row[kc.LOG_KIND]), int(row[kc.LOG_TRANSITION]),
                           int(row[kc.LOG_SURFACE]), int(row[kc.LOG_MODE_FROM]), int(row[kc.LOG_MODE_TO]))

    @property
    def first_logged(self) -> LoggedEvent | None:
        """The first event as :meth:`logged` gives it (None without events)."""
        return self.logged(0) if self.n_events else None

    @property
    def last_logged(self) -> LoggedEvent | None:
        """The last event as :meth:`logged` gives it (None without events)."""
        return self.logged(-1) if self.n_events else None

    def event_rows(self) -> list[list[int]]:
        """The events' integer columns, one plain list per event: ``[kind, transition, surface, mode_from,
        mode_to]`` (the contract's ``LOG_*`` order), without building the records.

        Returns
        -------
        list of list of int
            One row per event, in the order met.
        """
        return self.event_log[1].tolist()

    def __repr__(self) -> str:
        x1 = ", ".join(f"{v:.6g}" for v in np.asarray(self.x1)[:6]) + (", ..." if len(self.x1) > 6 else "")
        modes = self.modes
        path = " -> ".join(modes[:5]) + (f" -> ... ({len(modes)} modes)" if len(modes) > 5 else "")
        return (f"Trajectory({self.system.name!r}, t {self.t0:.8g} .. {self.t1:.8g}, {len(self.events)} events, "
                f"{path}, x1=[{x1}]" + (", with monodromy" if self.monodromy is not None else "") + ")")

    @property
    def event_sequence(self) -> tuple[tuple[int, int, str], ...]:
        """The orbit's sequence of events (kind, transition, surface)."""
        return tuple(e.signature for e in self.events)

    @property
    def modes(self) -> list[str]:
        """Sequence of modes visited (sliding motions named ``a|b``)."""
        seq = [self.mode0]
        for e in self.events:
            seq.append(f"{e.mode_from}|{e.mode_to}" if e.kind == EventKind.SLIDING_START else e.mode_to)
        return seq

    @property
    def dense_steps(self) -> tuple[np.ndarray, ...]:
        """The recorded steps: start times, sizes, end fractions, start states, coefficients.

        Each step ``k`` covers ``t_old[k] + s h[k]`` for ``s`` in ``[0, s_end[k]]``
        (``s_end < 1`` for a step cut short by an event).

        Raises
        ------
        ValueError
            If the trajectory was computed without ``dense=True``.
        """
        if self._steps is None:
            raise ValueError("this trajectory was computed without dense=True")
        return tuple(np.asarray(a) for a in self._steps)

    def at(self, times: Sequence[float] | np.ndarray) -> np.ndarray:
        """States at the given times (inside the time span) from the dense output.

        At an event time the state before the event is returned.

        Parameters
        ----------
        times : array_like, shape (m,)
            Times inside the span from :attr:`t0` to :attr:`t1`.

        Returns
        -------
        ndarray, shape (m, n)
            The state at each time, from DOP853's continuous extension of the step that covers it.

        Raises
        ------
        ValueError
            If the trajectory was computed without ``dense=True``.
        """
        _, _, _, y0, F = self.dense_steps
        times = np.asarray(times, dtype=float).reshape(-1)
        if y0.shape[0] == 0:
            return np.repeat(self.x1[None, :], len(times), axis=0)
        k, s = self.locate(times)
        return _dense_values(F[k], y0[k], s)

    def locate(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For each time, the index of the recorded step that covers it and the fraction within it.

        Parameters
        ----------
        times : ndarray, shape (m,)
            Times inside the span of the trajectory.

        Returns
        -------
        k : ndarray of int, shape (m,)
            Index of the recorded step (:attr:`dense_steps`) that covers each time.
        s : ndarray, shape (m,)
            Fraction of that step, in ``[0, s_end[k]]``.

        Raises
        ------
        ValueError
            If the trajectory was computed without ``dense=True``.
        """
        t_old, h, s_end, _, _ = self.dense_steps
        times = np.asarray(times, dtype=float)
        forward = h[0] > 0 if h.size else True
        key, starts = (times, t_old) if forward else (-times, -t_old)
        k = np.clip(np.searchsorted(starts, key, side="right") - 1, 0, len(t_old) - 1)
        s = np.clip((times - t_old[k]) / h[k], 0.0, s_end[k])
        return k, s

    def sample(self, num_per_step: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """Dense states along the trajectory.

        Parameters
        ----------
        num_per_step : int
            Number of intervals each recorded step is cut into (``num_per_step + 1`` points per step, the
            step's ends included).

        Returns
        -------
        t : ndarray, shape (m,)
            Times, in the direction of integration.
        x : ndarray, shape (m, n)
            States at those times (the initial state alone for a trajectory without steps).

        Raises
        ------
        ValueError
            If the trajectory was computed without ``dense=True``.
        """
        t_old, h, s_end, y0, F = self.dense_steps
        ts = []
        xs = []
        s = np.linspace(0.0, 1.0, num_per_step + 1)
        for k in range(len(t_old)):
            sk = s * s_end[k]
            ts.append(t_old[k] + sk * h[k])
            xs.append(_dense_eval(F[k], y0[k], sk))
        if not ts:
            return np.array([self.t0]), self.x0[None, :]
        return np.concatenate(ts), np.concatenate(xs)


def _dense_eval(F: np.ndarray, y0: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Evaluate DOP853's continuous extension of one step at fractions ``s`` (vectorised)."""
    s = np.asarray(s, dtype=float)
    return _dense_values(np.broadcast_to(F, (len(s),) + F.shape), np.broadcast_to(y0, (len(s),) + y0.shape), s)


def _dense_values(F: np.ndarray, y0: np.ndarray, s: np.ndarray) -> np.ndarray:
    """DOP853's continuous extension of steps ``(F[k], y0[k])`` at fractions ``s[k]``
    (:func:`saltation.engine.flow.dense_evaluate`)."""
    out = np.zeros(y0.shape)
    for j in range(kc.DENSE_ROWS):
        out += F[:, kc.DENSE_ROWS - 1 - j, :]
        out *= (s if j % 2 == 0 else 1.0 - s)[:, None]
    return out + y0


def _steps(packed: np.ndarray, n: int) -> tuple[np.ndarray, ...]:
    """The kernel's record of steps: starts, sizes, end fractions, start states, dense-output coefficients."""
    w_rec = kc.step_record_width(n)
    n_rec = packed.size // (w_rec + kc.DENSE_ROWS * n)
    rec = packed[: n_rec * w_rec].reshape(n_rec, w_rec)
    return rec[:, 0], rec[:, 1], rec[:, 2], rec[:, 3:], packed[n_rec * w_rec :].reshape(n_rec, kc.DENSE_ROWS, n)


def _switching_events(system: PiecewiseSystem, event_log: tuple[np.ndarray, ...]) -> list[SwitchingEvent]:
    """The kernel's event log as :class:`SwitchingEvent` records."""
    ev_t, ev_int, ev_xm, ev_xp, ev_S = event_log
    names, surfaces = system.mode_names, system.surface_names
    return [
        SwitchingEvent(
            t=float(ev_t[k]),
            kind=EventKind(int(ev_int[k, kc.LOG_KIND])),
            transition=int(ev_int[k, kc.LOG_TRANSITION]),
            surface=surfaces[int(ev_int[k, kc.LOG_SURFACE])],
            mode_from=names[int(ev_int[k, kc.LOG_MODE_FROM])],
            mode_to=names[int(ev_int[k, kc.LOG_MODE_TO])],
            x_minus=ev_xm[k],
            x_plus=ev_xp[k],
            saltation=ev_S[k],
        )
        for k in range(len(ev_t))
    ]


def _error(status: Status, system: PiecewiseSystem, info: np.ndarray, t: float, x: np.ndarray, events) -> IntegrationError:
    """The exception of a failed integration: its ``status``, with the mode, surface and sliding state the engine
    left in ``info``, at ``(t, x)`` after ``events``."""
    m, k = int(info[kc.INFO_FAILED_MODE]), int(info[kc.INFO_FAILED_SURFACE])
    mode = system.mode_names[m] if m >= 0 else "?"
    surface = system.surface_names[k] if k >= 0 else "?"
    where = f"at t = {t:.12g}, x = {np.array2string(np.asarray(x), precision=6)}, in mode {mode!r}"
    if status == Status.CHATTERING and int(info[kc.INFO_SLIDE]) == kc.TIME_UNRESOLVED:
        return IntegrationError(
            f"the time axis cannot resolve the motion {where}: switching events on surface {surface!r} closer than a "
            f"few rounding units of t (ulp(t) = {np.spacing(abs(t)):.3g}); integrate from a smaller t0 (shift the time "
            "origin by a multiple of the forcing period)"
        )
    if status == Status.CHATTERING:
        recent = ", ".join(f"{e.surface}@{e.t:.6g}" for e in events[-5:])
        rest = _comes_to_rest(system, events)
        return ChatteringError(
            f"chattering {where}: many switching events on surface {surface!r} in a vanishing time interval "
            f"(last events: {recent}); " + (rest or "the model may need a sliding mode or a different transition")
        )
    if status == Status.ACCUMULATION:
        return IntegrationError(
            f"the impacts on surface {surface!r} accumulate {where} (complete chatter): Flow.run jumps to their limit "
            "and goes on in the stuck mode; this caller reads the engine's result without it"
        )
    if status == Status.MAX_EVENTS:
        return ChatteringError(f"more switching events than max_events {where} (last surface {surface!r})")
    if status == Status.STEP_TOO_SMALL:
        hint = ""
        if np.spacing(abs(t)) > 1e-9 or k >= 0:  # far from t = 0, or at an event on surface k
            hint = (f": the time axis cannot resolve the motion at this t (ulp(t) = {np.spacing(abs(t)):.3g}); integrate "
                    "from a smaller t0 (shift the time origin by a multiple of the forcing period)")
        return StepSizeError(f"step size fell below floating-point resolution {where}{hint}")
    if status == Status.NON_FINITE:
        return NonFiniteError(f"the vector field of mode {mode!r} returned NaN or infinity {where} (the field, or "
                              "its derivatives f_x, f_p where the variational equation is carried: a power below 1 "
                              "of the distance to a surface has none at the surface)")
    if status == Status.SLIDING_UNDEFINED:
        cause = int(info[kc.INFO_SLIDE])
        if cause == kc.SLIDE_RESET_INTO:
            k_tr = int(info[kc.INFO_SLIDE + 1])
            tr = system.transitions[k_tr]
            return SlidingError(
                f"the reset of transition {k_tr} ({tr.source} -> {tr.target} on surface {surface!r}) leaves the state "
                f"on the surface {where}, and the field of mode {tr.target!r} pushes it back across (an impact with "
                "restitution 0 or below, or a state at rest on the surface): sliding with a reset map is not defined; "
                "the model needs a sticking mode"
            )
        if cause not in (kc.SLIDE_LEAVES_REGION, kc.SLIDE_BLOCKED):
            return SlidingError(
                f"sliding on surface {surface!r} {where} is required (the target field pushes back into the surface) "
                "but is not defined: the transition has a reset map or both fields are tangent"
            )
        # a sliding motion that cannot go on: its modes and surface are kept in the sliding state
        a, b = (system.mode_names[int(info[kc.INFO_SLIDE + j])] for j in (1, 2))
        own = int(info[kc.INFO_SLIDE + 3])
        motion = f"the sliding motion on surface {system.surface_names[own]!r} ({a}|{b})"
        at = f"at t = {t:.12g}, x = {np.array2string(np.asarray(x), precision=6)}"
        if cause == kc.SLIDE_LEAVES_REGION:
            across = f"across surface {surface!r}" if k != own else "where no other switching surface lies"
            return SlidingError(
                f"{motion} leaves the domain of mode {mode!r} {across} {at}, and no transition out of {a!r} or {b!r} "
                "holds there: the model does not say how the motion goes on (a sliding motion is defined only where "
                "both its modes are)"
            )
        if m >= 0:
            return SlidingError(
                f"{motion} meets surface {surface!r} {at}, where a transition leads into mode {mode!r}, whose field "
                f"pushes back across {surface!r}: that would be sliding on two surfaces at once, which is not supported"
            )
        return SlidingError(
            f"{motion} meets surface {surface!r} {at}, where the transitions out of {a!r} and {b!r} lead into two "
            f"modes whose fields both leave surface {system.surface_names[own]!r}: the motion beyond is not unique"
        )
    if status == Status.TANGENTIAL:
        return IntegrationError(f"switching event exactly tangent to surface {surface!r} {where}: the saltation matrix is undefined")
    if status == Status.MAX_STEPS:
        return IntegrationError(f"more steps than max_steps {where}")
    if status == Status.OUTSIDE_DOMAIN:
        last = events[-1] if events else None
        after = f"after {last.mode_from!r} -> {last.mode_to!r} on surface {last.surface!r} " if last else ""
        return ModelError(
            f"the state {after}lies outside the domain of mode {mode!r} {where}, by more than rounding, and no "
            "transition out of that mode holds there: the model's domains and transitions disagree"
        )
    return IntegrationError(f"integration failed with status {status.name} {where}")


def _comes_to_rest(system: PiecewiseSystem, events: Sequence[SwitchingEvent]) -> str | None:
    """Where a run that stopped chattering comes to rest, if its last events are impacts of one transition whose
    times accumulate (Zeno): the accumulation time (extrapolated from the impacts resolved best) and the last
    state, as a sentence; None otherwise."""
    last = events[-1] if events else None
    if last is None or last.kind != EventKind.TRANSITION or np.allclose(last.x_minus, last.x_plus, rtol=0, atol=0):
        return None
    k = len(events) - 1
    while k >= 0 and events[k].transition == last.transition and events[k].kind == EventKind.TRANSITION:
        k -= 1
    chain = [e.t for e in events[k + 1:]]
    best = (math.inf, math.nan)
    for i in range(5, len(chain)):
        d = np.diff(chain[i - 5 : i + 1])
        lam = d[-1] / d[-2] if d[-2] > 0 else math.nan  # the ratio of the intervals: the restitution's estimate
        estimate, error = kc.accumulation_point(*chain[i - 4 : i + 1], lam)
        if error < best[0]:
            best = (error, estimate)
    if not best[0] < math.inf:
        return None
    x = np.array2string(np.asarray(last.x_plus), precision=6)
    where = (f"the impacts on surface {last.surface!r} accumulate (Zeno) at t = {best[1]:.10g} (to about "
             f"{max(best[0], 1e-15):.0e}), where the state comes to rest on the surface, at about x = {x}")
    twin = sticking_twins(system).get(last.transition)
    if twin is not None:
        return (f"{where}, but mode {system.transitions[twin].target!r} does not hold it there (the contact force "
                "vanishes, or another event comes first): the chatter is not complete")
    return (f"{where}: declare the impact sticks=True (transition {last.transition}, {last.mode_from} -> "
            f"{last.mode_to}) to go on in the motion on the surface there")


def unpack_result(system: PiecewiseSystem, out: tuple[np.ndarray, np.ndarray], x0: np.ndarray, t0: float, mode0: int,
                  variational: bool, sensitivity: int, dense: bool, offsets: tuple[int, ...] | None = None, *,
                  accumulation: bool = False) -> Trajectory:
    """The trajectory of the engine's packed result (``integrate_kernel``, laid out as ``_contract.py`` says).

    Parameters
    ----------
    system : PiecewiseSystem
        The model integrated.
    out : tuple of ndarray
        The engine's two packed arrays, ``(ints, floats)``.
    x0 : ndarray, shape (n,)
        The initial state (kept by the trajectory).
    t0 : float
        The initial time.
    mode0 : int
        Index of the initial mode.
    variational : bool
        Whether the run carried the fundamental solution matrix.
    sensitivity : int
        Index of the parameter whose sensitivity the run carried (-1: none).
    dense : bool
        Whether the run recorded its steps.
    offsets : tuple of int, optional
        ``result_offsets(n)`` of the contract, if the caller keeps them.
    accumulation : bool
        Read a run that stopped at impacts that accumulate (``Status.ACCUMULATION``) as the trajectory up to
        the last impact kept (its end state and matrices just after it), instead of raising.

    Returns
    -------
    Trajectory
        The run.

    Raises
    ------
    IntegrationError
        If the run failed: the subclass its status names (see :meth:`~saltation.engine.flow.Flow.run`), or
        :class:`~saltation.errors.ModelError` for a state outside every domain.
    """
    n = system.n
    info, res = out
    o_x, o_phi, o_psi, o_min, o_max, o_vel, n_out = offsets or kc.result_offsets(n)
    o_xm, o_xp, o_s, w_ev = kc.event_row_offsets(n)
    n_ev = int(info[kc.INFO_EVENTS])
    ev_int = info[kc.INFO_EVENT_LOG :].reshape(n_ev, kc.EVENT_LOG_INTS)
    ev = res[n_out : n_out + n_ev * w_ev].reshape(n_ev, w_ev)
    t = res[0]
    x = res[o_x : o_x + n]
    event_log = (ev[:, 0], ev_int, ev[:, o_xm:o_xp], ev[:, o_xp:o_s], ev[:, o_s:].reshape(-1, n, n))
    if info[kc.INFO_STATUS] != _STATUS_OK and not (accumulation and info[kc.INFO_STATUS] == kc.STATUS_ACCUMULATION):
        raise _error(Status(int(info[kc.INFO_STATUS])), system, info, float(t), x, _switching_events(system, event_log))
    names = system.mode_names
    return Trajectory(
        system=system,
        t0=t0,
        t1=float(t),
        x0=x0,
        x1=x,
        mode0=names[mode0],
        mode1=names[int(info[kc.INFO_FINAL_MODE])],
        event_log=event_log,
        monodromy=res[o_phi : o_phi + n * n].reshape(n, n) if variational else None,
        parameter_sensitivity=res[o_psi : o_psi + n] if (variational and sensitivity >= 0) else None,
        x_min=res[o_min : o_min + n],
        x_max=res[o_max : o_max + n],
        sliding_at_end=bool(info[kc.INFO_SLIDE]),
        velocity_end=res[o_vel : o_vel + n],
        n_steps=int(info[kc.INFO_STEPS]),
        n_rejected=int(info[kc.INFO_REJECTED]),
        _steps=_steps(res[n_out + n_ev * w_ev :], n) if dense else None,
    )


def join(segs: Sequence[Trajectory]) -> Trajectory:
    """One trajectory from consecutive segments.

    Their events in order, the product of their transfer matrices as its monodromy (assembled: its
    eigenvalues are not the multipliers' best values).

    Parameters
    ----------
    segs : sequence of Trajectory
        Consecutive segments, with their transfer matrices.

    Returns
    -------
    Trajectory
        From the first segment's start to the last one's end, without parameter sensitivity or dense
        output.

    Raises
    ------
    IndexError
        If ``segs`` is empty.
    """
    first, last = segs[0], segs[-1]
    logs = [seg.event_log for seg in segs]
    event_log = tuple(np.concatenate([log[k] for log in logs]) for k in range(len(first.event_log)))
    M = first.monodromy
    for seg in segs[1:]:
        M = seg.monodromy @ M
    return replace(
        first, t1=last.t1, x1=last.x1, mode1=last.mode1, event_log=event_log, monodromy=M,
        parameter_sensitivity=None, x_min=np.min([s.x_min for s in segs], axis=0),
        x_max=np.max([s.x_max for s in segs], axis=0), sliding_at_end=last.sliding_at_end,
        velocity_end=last.velocity_end, n_steps=sum(s.n_steps for s in segs),
        n_rejected=sum(s.n_rejected for s in segs), _steps=None,
        accumulations=tuple(a for s in segs for a in s.accumulations),
    )


def continued(a: Trajectory, b: Trajectory) -> Trajectory:
    """Two consecutive pieces as one trajectory: ``b`` carried on from ``a`` (``b``'s matrices already include ``a``'s).

    Parameters
    ----------
    a, b : Trajectory
        The first piece and the piece run on from its end (with ``phi0``, ``psi0`` of
        :meth:`~saltation.engine.flow.Flow.run` at ``a``'s end).

    Returns
    -------
    Trajectory
        From ``a``'s start to ``b``'s end, with both pieces' events and ``b``'s matrices, without dense output.
    """
    event_log = tuple(np.concatenate([x, y]) for x, y in zip(a.event_log, b.event_log))
    return replace(b, t0=a.t0, x0=a.x0, mode0=a.mode0, event_log=event_log, x_min=np.minimum(a.x_min, b.x_min),
                   x_max=np.maximum(a.x_max, b.x_max), n_steps=a.n_steps + b.n_steps,
                   n_rejected=a.n_rejected + b.n_rejected, _steps=None, accumulations=a.accumulations + b.accumulations)


def log_with_event(traj: Trajectory, kind: EventKind, transition: int, surface: str, mode_from: str, mode_to: str,
                   x_minus: np.ndarray, x_plus: np.ndarray, S: np.ndarray) -> tuple[np.ndarray, ...]:
    """The trajectory's event log with one more event at its end, at ``t1`` (in the engine's layout).

    Parameters
    ----------
    traj : Trajectory
        The trajectory.
    kind : EventKind
        The event's kind.
    transition : int
        Index of the transition (-1 for the end of sliding).
    surface, mode_from, mode_to : str
        Names of the surface and of the modes before and after.
    x_minus, x_plus : ndarray, shape (n,)
        The state before and after the event.
    S : ndarray, shape (n, n)
        Its saltation matrix.

    Returns
    -------
    tuple of ndarray
        The event log (for :class:`Trajectory`'s ``event_log``).

    Raises
    ------
    ModelError
        If ``surface`` or a mode names none of the model's.
    """
    sys_ = traj.system
    ev_t, ev_int, ev_xm, ev_xp, ev_S = traj.event_log
    row = np.zeros((1, kc.EVENT_LOG_INTS), dtype=ev_int.dtype)
    row[0, kc.LOG_KIND] = int(kind)
    row[0, kc.LOG_TRANSITION] = transition
    row[0, kc.LOG_SURFACE] = sys_.surface_index(surface)
    row[0, kc.LOG_MODE_FROM] = sys_.mode_index(mode_from)
    row[0, kc.LOG_MODE_TO] = sys_.mode_index(mode_to)
    return (np.append(ev_t, traj.t1), np.vstack([ev_int, row]), np.vstack([ev_xm, x_minus[None, :]]),
            np.vstack([ev_xp, x_plus[None, :]]), np.concatenate([ev_S, S[None, :, :]]))


__all__ = ["Accumulation", "EventKind", "LoggedEvent", "Status", "SwitchingEvent", "Trajectory", "continued", "join", "log_with_event",
           "unpack_result"]
