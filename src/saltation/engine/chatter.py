"""Complete chatter: impacts that accumulate where the contact sticks, jumped to their limit.

An impact with restitution ``0 < e < 1`` against a surface whose contact force holds the state there (a
ball on a floor, on a vibrating table) repeats at relative velocities ``w_k ~ e^k`` and intervals ``~ e^k``:
infinitely many impacts in a finite time, accumulating at ``t_inf``, where the state arrives on the
surface at zero relative velocity and moves on with it (the stuck mode that ``sticks=True`` adds,
:mod:`saltation.model.contacts`).  The engine keeps the impacts until their times extrapolate to
``t_inf`` to the integration tolerance (``accumulation_point`` of ``saltation.engine._contract``:
Richardson's elimination of the powers of ``e``; the engine stops there with ``Status.ACCUMULATION``),
and :func:`run_through_accumulations` goes on from there:

* from the last impact kept, at ``(t_n, x_n)`` with relative velocity ``w_n``, the state is projected onto
  the stuck motion's manifold ``M = {h = 0, Lh = 0}`` (``Lh = h_x f + h_t`` the relative velocity) along
  the contact direction ``b`` (``f_stuck - f``, the contact force's) and ``f_x b`` (the displacement an
  impulse along ``b`` makes: for a mechanical contact, ``b``'s velocities as positions), the plastic
  version of the impact, and the stuck mode is integrated from there to ``t_inf``;
* one event at ``t_inf`` into the stuck mode is logged: its state before is the free flow's from
  ``(t_n, x_n)`` (the flow of the mode the impacts leave into, through the surface), after it the stuck
  state, and its saltation matrix ``S = Phi_stuck P_x Phi_free^-1`` (``P_x`` the projection's
  Jacobian), so that ``Phi(t_inf+) = S Phi(t_inf-)`` with ``Phi(t_inf-)`` the free flow's, as at any
  event;
* the run goes on in the stuck mode from ``t_inf``.

The chatter's Jacobian (Nordmark and Piiroinen 2009): the impacts left after ``(t_n, x_n)`` and the
plastic projection at ``t_n`` followed by the stuck motion arrive at the same state at any time after
``t_inf``, up to terms of second order in ``w_n``: both take the relative velocity from ``w_n`` to 0
while the free motion's relative acceleration ``a`` acts, so the impulses of the impacts (``(1 + e) w_n /
(1 - e)`` in all, over the remaining time ``2 w_n / ((1 - e) |a|)``) and the projection with the contact
force move the state along ``b`` by the same amount, whatever ``t_inf``.  So the monodromy through the chatter is ``Phi_stuck(t, t_n) P_x
Phi(t_n+)``, exact where the stuck state does not depend on the state before (the ball on a table:
the period map forgets it) or the contact is decoupled from the other states, and with an error of
order ``w_n`` (the relative velocity at the last impact kept) where the skipped motion feeds back into
the others: on a ball on a sprung table (``w_n = 4e-4``) it matches central differences of the period
map to their accuracy, ``2e-8`` (``tests/engine/test_complete_chatter.py``).

References
----------
Budd and Dux (1994), "Chattering and related behaviour in impact oscillators", *Philosophical
Transactions of the Royal Society A* 347.  Nordmark and Piiroinen (2009), "Simulation and stability
analysis of impacting systems with complete chattering", *Nonlinear Dynamics* 58.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import Any

import numpy as np

from saltation.engine import _contract as kc
from saltation.engine.trajectory import Accumulation, Trajectory
from saltation.errors import ChatteringError, IntegrationError, ModelError
from saltation.model.contacts import sticking_twins

__all__ = ["accumulation_time", "run_through_accumulations"]

_log = logging.getLogger(__name__)

_Flow = Any  # a saltation.engine.flow.Flow (which imports this module)

#: Newton steps of the projection onto the stuck manifold (each squares the residual; two or three reach rounding)
PROJECTION_STEPS = 6
#: a run that ends before an accumulation point integrates the impacts left one by one, where it ends at least this
#: fraction of the time from the last impact kept to the accumulation point before it (relative velocities down to
#: about this fraction of the last kept one: the engine resolves them); closer, it raises ChatteringError
RESOLVED_TAIL = 1e-3


def accumulation_time(times: np.ndarray, lam: float) -> tuple[float, float]:
    """The accumulation point of a sequence of impact times and a bound on its error.

    Parameters
    ----------
    times : ndarray, shape (m,)
        The impact times of the sequence, in order (``m >= 6``).
    lam : float
        The ratio of the relative velocities across the last impact (``-w+ / w-``, the restitution), the
        ratio of successive intervals in the limit.

    Returns
    -------
    t_inf : float
        The extrapolated accumulation time: of the last five times, or of the five before where those are
        better (the engine stops where the estimate no longer improves).
    error : float
        A bound on its error (infinite where the times do not accumulate).

    References
    ----------
    Richardson's extrapolation with the known ratios ``lam, lam^2, lam^3, lam^4`` (``accumulation_point``
    of the engine's contract).
    """
    t = [float(v) for v in times]
    if len(t) < kc.ACCUMULATION_IMPACTS:
        return (t[-1] if t else math.nan), math.inf
    now = kc.accumulation_point(*t[-5:], lam)
    before = kc.accumulation_point(*t[-6:-1], lam)
    return min(now, before, key=lambda pair: pair[1])


def _chain(events_log: tuple[np.ndarray, ...], transition: int) -> np.ndarray:
    """The times of the impacts of ``transition`` that end the event log, consecutive."""
    ev_t, ev_int = events_log[0], events_log[1]
    k = len(ev_t) - 1
    while k >= 0 and ev_int[k, kc.LOG_TRANSITION] == transition and ev_int[k, kc.LOG_KIND] == kc.EVENT_TRANSITION:
        k -= 1
    return ev_t[k + 1:]


class _Contact:
    """The constraint ``h = 0``, ``Lh = 0`` of a stuck mode, the directions the projection moves along, and
    the projection (a few Newton steps) with its Jacobians."""

    def __init__(self, flow: _Flow, free: int, stuck: int, surface: int, p: np.ndarray):
        self.flow, self.free, self.stuck, self.surface, self.p = flow, free, stuck, surface, p

    def residual(self, t: float, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(h, Lh)``, their state gradients (rows) and parameter gradients (rows) at ``(t, x)``."""
        fl = self.flow
        hx, _, hp = fl.indicator_gradient(self.surface, t, x, self.p)
        L, Lx, Lp, _ = fl.lie_derivative(self.free, self.surface, t, x, self.p)
        r = np.array([fl.indicator(self.surface, t, x, self.p), L])
        return r, np.vstack([hx, Lx]), np.vstack([hp, Lp])

    def directions(self, t: float, x: np.ndarray) -> np.ndarray:
        """``[b, f_x b]`` (columns): the contact force's direction and the displacement an impulse along it makes."""
        fl = self.flow
        b = fl.vector_field(self.stuck, t, x, self.p) - fl.vector_field(self.free, t, x, self.p)
        scale = np.linalg.norm(b)
        if not scale > 0.0:
            raise ChatteringError(
                f"the impacts on surface {self.flow.system.surface_names[self.surface]!r} accumulate at t = {t:.12g}, "
                f"x = {np.array2string(x, precision=6)}, where the contact force of mode "
                f"{self.flow.system.mode_names[self.stuck]!r} vanishes: the stuck motion does not hold the state there")
        b = b / scale
        c = fl.vector_field_jacobian(self.free, t, x, self.p) @ b
        return np.column_stack([b, c])

    def project(self, t: float, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The state moved onto ``h = 0, Lh = 0`` along the directions at ``x``, and the projection's Jacobians in
        the state (``P_x``) and the parameters (``P_p``) at the result."""
        B = self.directions(t, x)
        y = np.array(x, dtype=float)
        scale = 1.0 + float(np.max(np.abs(y)))
        for _ in range(PROJECTION_STEPS):
            r, G, _ = self.residual(t, y)
            if np.max(np.abs(r)) <= 4.0 * np.finfo(float).eps * scale:
                break
            y = y - B @ np.linalg.solve(G @ B, r)
        r, G, Gp = self.residual(t, y)
        GB = G @ B
        if not np.isfinite(np.linalg.cond(GB)) or np.linalg.cond(GB) > 1e12:
            raise ChatteringError(
                f"the impacts on surface {self.flow.system.surface_names[self.surface]!r} accumulate at t = {t:.12g}, "
                f"but the contact direction and the impulse's displacement {B.T.tolist()} do not move the state onto "
                "the surface at zero relative velocity (a degenerate contact)")
        Px = np.eye(len(y)) - B @ np.linalg.solve(GB, G)
        Pp = -B @ np.linalg.solve(GB, Gp)
        return y, Px, Pp


def _jump(flow: _Flow, piece: Trajectory, p: np.ndarray, t1: float, sensitivity: int, dense: bool, tolerances: Any,
         table: np.ndarray):
    """The jump from the last impact kept (``piece`` ends just after it) to the accumulation point.

    Parameters
    ----------
    flow : Flow
        The flow.
    piece : Trajectory
        The run up to the last impact kept (stopped with ``Status.ACCUMULATION``), with its monodromy.
    p : ndarray, shape (n_params,)
        Parameter values.
    t1 : float
        The end of the run.
    sensitivity : int
        Index of the parameter whose sensitivity is carried (-1: none).
    dense : bool
        Whether the stuck motion's steps to the accumulation point are kept.
    tolerances : Tolerances
        Integration tolerances.
    table : ndarray
        The run's transition table.

    Returns
    -------
    tuple or None
        ``(accumulation, event row, stuck piece, Phi, psi)``: the record, the event at ``t_inf`` (the
        indices of the twin transition, the surface, the modes before and after, then x-, x+, S), the stuck
        motion from the last impact to ``t_inf``, the fundamental solution matrix and parameter sensitivity
        just after it; None where the impacts left are to be integrated one by one: the run ends before the
        accumulation point, or the stuck motion does not hold the state there (it meets another event on
        the way, or the contact force does not hold it at ``t_inf``).

    Raises
    ------
    ChatteringError
        Where the contact force vanishes along the contact direction, the projection onto the surface is
        degenerate, or the run ends too close before the accumulation point to resolve the impacts left
        (:data:`RESOLVED_TAIL`).
    """
    sys_ = flow.system
    ev_t, ev_int, ev_xm, ev_xp, _ = piece.event_log
    k = int(ev_int[-1, kc.LOG_TRANSITION])
    s = int(ev_int[-1, kc.LOG_SURFACE])
    free = int(ev_int[-1, kc.LOG_MODE_TO])
    twin = sticking_twins(sys_)[k]
    stuck = sys_.mode_index(sys_.transitions[twin].target)
    t_n, x_n, x_before = float(ev_t[-1]), np.array(ev_xp[-1]), np.array(ev_xm[-1])
    w_minus = flow.lie_derivative(int(ev_int[-1, kc.LOG_MODE_FROM]), s, t_n, x_before, p)[0]
    w_plus = flow.lie_derivative(free, s, t_n, x_n, p)[0]
    times = _chain(piece.event_log, k)
    t_inf, accuracy = accumulation_time(times, -w_plus / w_minus)
    if not accuracy < math.inf:
        raise ChatteringError(f"the impacts of transition {k} on surface {sys_.surface_names[s]!r} at t = {t_n:.12g} "
                              "stopped as accumulating, but their times do not extrapolate to a limit")
    if t1 < t_inf <= t1 + accuracy:
        t_inf = t1  # the run ends at the accumulation point, within the accuracy of its extrapolation
    if t_inf > t1:
        if t_inf - t1 >= RESOLVED_TAIL * (t_inf - t_n):
            return None
        raise ChatteringError(
            f"the run ends at t = {t1:.12g}, {t_inf - t1:.1e} before the accumulation point t = {t_inf:.12g} of the "
            f"impacts on surface {sys_.surface_names[s]!r} (complete chatter into mode "
            f"{sys_.transitions[twin].target!r}): the impacts left before it are below the resolution of the state; "
            f"end the run before t = {t_inf - RESOLVED_TAIL * (t_inf - t_n):.12g} or at or after the accumulation point")
    contact = _Contact(flow, free, stuck, s, p)
    y_n, Px, Pp = contact.project(t_n, x_n)
    # the free flow through the surface to t_inf: the state and matrix before the event
    x_free, Phi_f = _free_flow(flow, x_n, t_n, t_inf, free, s, p, tolerances, table)
    # the stuck motion from the plastic projection at t_n
    psi0 = (Px @ piece.parameter_sensitivity + Pp[:, sensitivity]
            if sensitivity >= 0 and piece.parameter_sensitivity is not None else None)
    no_stop = table.copy()
    no_stop[:, 6] = -1
    stuck_run, _ = flow._piece(y_n, t_n, t_inf, stuck, p, True, sensitivity, dense, tolerances, None, psi0, no_stop)
    x_inf, _, _ = contact.project(t_inf, stuck_run.x1)
    if stuck_run.n_events or not bool(flow._model[kc.IN_DOMAIN](stuck, t_inf, x_inf, p)):
        # the stuck motion to t_inf meets another event (where the contact force vanishes, say), or the force does
        # not hold the state there: the impacts do not end in the stuck motion, and are integrated one by one
        _log.debug("impacts of transition %d extrapolate to t = %.15g, where mode %r does not hold the state: "
                   "integrated one by one", k, t_inf, sys_.mode_names[stuck])
        return None
    # the impacts' times extrapolate with a relative acceleration that does not change over the tail; where the
    # contact force changes by a fraction r of itself over it (near its release), the limit moves by about
    # (t_inf - t_n) r^2, which the accuracy takes in (tested against flights in closed form near the release)
    if _tail_escapes(flow, free, s, t_n, x_n, t_inf, x_inf, p, -w_plus / w_minus):
        # the relative acceleration vanishes before the impacts left accumulate (near the contact's release): they
        # do not end in the stuck motion, and are integrated one by one
        _log.debug("impacts of transition %d extrapolate to t = %.15g, but the relative acceleration that drives them "
                   "back vanishes before they accumulate: integrated one by one", k, t_inf)
        return None
    drift = _force_drift(flow, stuck, t_inf, x_inf, p, t_inf - t_n)
    accuracy = float(accuracy) + abs(t_inf - t_n) * min(drift, 1.0) ** 2
    Phi_s = stuck_run.monodromy
    S = Phi_s @ Px @ np.linalg.inv(Phi_f)
    Phi = Phi_s @ Px @ piece.monodromy if piece.monodromy is not None else None
    psi = stuck_run.parameter_sensitivity if sensitivity >= 0 else None
    record = Accumulation(t=t_inf, accuracy=max(float(accuracy), 4.0 * float(np.spacing(abs(t_inf)))), impacts=len(times), transition=k,
                          surface=sys_.surface_names[s], mode=sys_.mode_names[stuck], relative_speed=float(abs(w_plus)),
                          x=x_inf)
    _log.debug("impacts of transition %d accumulate at t = %.15g (+- %.1e) after %d kept, into mode %r", k, t_inf,
                 accuracy, len(times), record.mode)
    row = (twin, s, free, stuck, x_free, x_inf, S)
    return record, row, replace(stuck_run, x1=x_inf), Phi, psi


#: the relative velocity, as a fraction of the first, below which the tail of a model chatter is summed as a series
TAIL_CUT = 1e-12


def _tail_escapes(flow: _Flow, free: int, s: int, t_n: float, x_n: np.ndarray, t_inf: float, x_inf: np.ndarray,
                  p: np.ndarray, lam: float) -> bool:
    """Whether the impacts left after ``(t_n, x_n)`` escape before they accumulate, in a model of the tail.

    The relative acceleration ``a = -(L_x f + L_t)`` that drives the motion back to the surface is taken
    linear in time between the last impact kept and the extrapolated accumulation point ``(t_inf, x_inf)``;
    the flights of ``z'' = -a(t)`` from ``z = 0`` at relative velocity ``w`` (cubics) and the impacts
    ``w -> lam w`` are iterated.  Where ``a`` vanishes before the relative velocity does (the contact force
    reaches its release during the tail), the impacts do not accumulate: the extrapolation of their times,
    which assumes a relative acceleration that changes little, is refused.
    """
    def second(t: float, x: np.ndarray) -> tuple[float, float]:
        rate, rate_x, _, rate_t = flow.lie_derivative(free, s, t, x, p)
        return float(rate_x @ flow.vector_field(free, t, x, p) + rate_t), float(rate)

    h2_n, w = second(t_n, x_n)
    if not (w != 0.0 and 0.0 < lam < 1.0 and t_inf > t_n):
        return False
    sign = 1.0 if w > 0 else -1.0
    w = abs(w)
    a_n = -sign * h2_n
    a_inf = -sign * second(t_inf, x_inf)[0]
    slope = (a_inf - a_n) / (t_inf - t_n)
    t, w0 = t_n, w
    for _ in range(10000):
        a0 = a_n + slope * (t - t_n)
        if not a0 > 0.0:
            return True
        # the flight's end: w = a0 tau / 2 + slope tau^2 / 6 (its root near 2 w / a0)
        b, c = a0 / 2.0, slope / 6.0
        disc = b * b + 4.0 * c * w
        if disc < 0.0:
            return True  # the deceleration turns before the motion comes back
        tau = 2.0 * w / (b + math.sqrt(disc))
        w = lam * (a0 * tau + slope * tau * tau / 2.0 - w)
        t += tau
        if w <= TAIL_CUT * w0:
            return not a_n + slope * (t + 2.0 * w / ((1.0 - lam) * a0) - t_n) > 0.0
    return False


def _force_drift(flow: _Flow, stuck: int, t: float, x: np.ndarray, p: np.ndarray, tail: float) -> float:
    """``|N'| tail / N``: how much the contact force ``N`` of the stuck mode (its release surface's indicator)
    changes, relative to itself, over the time ``tail`` left to the accumulation point at ``(t, x)``; 0 for a
    contact force without a release (a constant one), infinite where it does not hold the state."""
    sys_ = flow.system
    sticking = getattr(sys_, "sticking", {}).get(sys_.mode_names[stuck])
    if sticking is None or sticking.release not in sys_.surface_names:
        return 0.0
    r = sys_.surface_names.index(sticking.release)
    force = float(flow.indicator(r, t, x, p))
    rate = float(flow.lie_derivative(stuck, r, t, x, p)[0])
    return abs(rate) * abs(tail) / force if force > 0 else math.inf


def _free_flow(flow: _Flow, x_n: np.ndarray, t_n: float, t_inf: float, free: int, s: int, p: np.ndarray,
               tolerances: Any, table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The state and fundamental solution matrix of the free mode's flow from the last impact kept to ``t_inf``,
    through the surface (its transitions there disabled): the event's state and matrix before it.  Where the
    mode's domain stops that flow below the surface, its Taylor expansion to second order (the time is that
    of a few of the last flights: its error is of the third order in it)."""
    off = table.copy()
    off[(table[:, 0] == free) & (table[:, 1] == s), 0] = -1
    try:
        run, _ = flow._piece(x_n, t_n, t_inf, free, p, True, -1, False, tolerances, None, None, off)
        if not run.n_events:
            return run.x1, run.monodromy
    except (IntegrationError, ModelError) as exc:
        _log.debug("the free flow through surface %d to t = %.15g fails (%s): its Taylor expansion", s, t_inf, exc)
    tau = t_inf - t_n
    f = flow.vector_field(free, t_n, x_n, p)
    f_later = flow.vector_field(free, t_inf, x_n, p)  # (f_later - f) / tau: the field's rate in time
    J = flow.vector_field_jacobian(free, t_n, x_n, p)
    J_later = flow.vector_field_jacobian(free, t_inf, x_n, p)
    x = x_n + tau * f + tau**2 / 2 * (J @ f) + tau / 2 * (f_later - f)
    return x, np.eye(len(x_n)) + tau * J + tau**2 / 2 * (J @ J) + tau / 2 * (J_later - J)


def run_through_accumulations(flow: _Flow, first: Trajectory, *, t1: float, p: np.ndarray, variational: bool,
                              sensitivity: int, dense: bool, tolerances: Any, table: np.ndarray) -> Trajectory:
    """A run that stopped where impacts accumulate, continued through each accumulation to ``t1``.

    Parameters
    ----------
    flow : Flow
        The flow.
    first : Trajectory
        The run up to its first stop, just after the last impact kept.
    t1 : float
        The end of the run.
    p : ndarray, shape (n_params,)
        Parameter values.
    variational : bool
        Whether the run carries the fundamental solution matrix.
    sensitivity : int
        Index of the parameter whose sensitivity is carried (-1: none).
    dense : bool
        Whether the steps are kept for dense output.
    tolerances : Tolerances
        Integration tolerances.
    table : ndarray
        The run's transition table.

    Returns
    -------
    Trajectory
        From ``first``'s start to ``t1``: the events of every piece, one event into the stuck mode at each
        accumulation point (:attr:`Trajectory.accumulations` records them), the monodromy through all of them.

    Raises
    ------
    IntegrationError
        As :meth:`~saltation.engine.flow.Flow.run`, from any piece; :class:`ChatteringError` where the
        contact force vanishes along its direction or the projection onto the surface is degenerate, or the run
        ends too close before an accumulation point to resolve the impacts left.

    References
    ----------
    Nordmark and Piiroinen (2009), "Simulation and stability analysis of impacting systems with complete
    chattering", *Nonlinear Dynamics* 58.  Budd and Dux (1994), "Chattering and related behaviour in impact
    oscillators", *Philosophical Transactions of the Royal Society A* 347.
    """
    parts: list[Trajectory] = []
    rows: list[tuple | None] = []  # the event after each part (None: none)
    records: list[Accumulation] = []
    piece, stopped = first, True
    while stopped:
        jumped = _jump(flow, piece, p, t1, sensitivity, dense, tolerances, table)
        parts.append(piece)
        rows.append(None)
        if jumped is None:
            # the run ends before the accumulation point, or the impacts do not end in the stuck motion: the
            # impacts of that transition one by one from here on
            table = table.copy()
            table[int(piece.event_log[1][-1, kc.LOG_TRANSITION]), 6] = -1
            x, t, mode, Phi, psi = np.array(piece.x1), piece.t1, piece.mode1, piece.monodromy, piece.parameter_sensitivity
        else:
            record, row, stuck_piece, Phi, psi = jumped
            records.append(record)
            parts.append(stuck_piece)
            rows.append(row)
            x, t, mode = np.array(record.x), record.t, record.mode
        piece, stopped = flow._piece(x, t, t1, flow.system.mode_index(mode), p, variational, sensitivity, dense,
                                     tolerances, Phi, psi, table)
    parts.append(piece)
    rows.append(None)
    return _assemble(flow, parts, rows, records, first, piece, dense)


def _assemble(flow: _Flow, parts: list[Trajectory], rows: list, records: list[Accumulation], first: Trajectory,
              last: Trajectory, dense: bool) -> Trajectory:
    """One trajectory of the pieces and the events between them."""
    n = flow.system.n
    ev_t, ev_int, ev_xm, ev_xp, ev_S = [], [], [], [], []
    for part, row in zip(parts, rows):
        if part.n_events:
            for a, b in zip((ev_t, ev_int, ev_xm, ev_xp, ev_S), part.event_log):
                a.append(b)
        if row is not None:
            twin, s, free, stuck, x_minus, x_plus, S = row
            ints = np.zeros((1, kc.EVENT_LOG_INTS), dtype=np.int64)
            ints[0, kc.LOG_KIND] = kc.EVENT_TRANSITION
            ints[0, kc.LOG_TRANSITION] = twin
            ints[0, kc.LOG_SURFACE] = s
            ints[0, kc.LOG_MODE_FROM] = free
            ints[0, kc.LOG_MODE_TO] = stuck
            ev_t.append(np.array([part.t1]))
            ev_int.append(ints)
            ev_xm.append(np.asarray(x_minus, dtype=float).reshape(1, n))
            ev_xp.append(np.asarray(x_plus, dtype=float).reshape(1, n))
            ev_S.append(np.asarray(S, dtype=float).reshape(1, n, n))
    empty = first.event_log
    log = tuple(np.concatenate(a) if a else e[:0] for a, e in zip((ev_t, ev_int, ev_xm, ev_xp, ev_S), empty))
    steps = None
    if dense:
        steps = tuple(np.concatenate([part._steps[j] for part in parts]) for j in range(len(first._steps)))
    return replace(
        last, t0=first.t0, x0=first.x0, mode0=first.mode0, event_log=log,
        x_min=np.min([part.x_min for part in parts], axis=0), x_max=np.max([part.x_max for part in parts], axis=0),
        n_steps=sum(part.n_steps for part in parts), n_rejected=sum(part.n_rejected for part in parts), _steps=steps,
        accumulations=first.accumulations + tuple(records),
    )
