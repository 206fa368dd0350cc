"""Sliding bifurcations of periodic orbits in Filippov systems.

Where a periodic orbit's sequence of events changes by a sliding segment, the
change is one of the four codimension-one sliding bifurcations (di Bernardo,
Kowalczyk and Nordmark, Physica D 170, 2002; Kuznetsov, Rinaldi and
Gragnani, Int. J. Bif. Chaos 13, 2003).  Each happens where the orbit meets
the boundary of a sliding region, a point where the field ``f_B`` of one side
is tangent to the switching surface (``h_x f_B + h_t = 0``):

* grazing-sliding: the orbit grazes the surface there.  One side misses the
  surface, the other slides for a moment.  Located by the grazing defining
  system of :mod:`saltation.special_points.grazing` with the transition into sliding
  disabled;
* crossing-sliding: the orbit arrives at the surface there, and the
  tangency is *visible* from ``B`` (the orbit of ``f_B`` through the point
  leaves the surface).  One side crosses into ``B``; the other slides first,
  for a time that shrinks to zero, and then leaves into ``B``.  Event
  sequences: ``crossing into B`` and ``sliding start, sliding end into B``;
* switching-sliding: the same arrival, with the tangency *invisible* from
  ``B`` (the orbit of ``f_B`` returns to the surface).  One side starts
  sliding at once; the other first crosses into ``B`` and comes back to
  slide.  Event sequences: ``sliding start`` and ``crossing into B, sliding
  start``.  Both arrival cases are located by periodicity plus
  ``h_x f_B + h_t = 0`` at the arrival (:func:`locate_tangent_arrival`);
* adding-sliding: a sliding motion touches the boundary of its sliding region
  from inside, where the exit side's field ``f_A`` has a cubic tangency with
  the surface (``h_x f_A + h_t = 0`` and its derivative along ``f_A`` zero).
  One side keeps sliding; on the other the motion leaves into ``A`` and
  returns to slide again: a sliding segment is added.  Event sequences:
  ``..., sliding end`` and ``..., sliding end into A, sliding start, sliding
  end``.  Located by periodicity plus both conditions at the touch
  (:func:`locate_adding_sliding`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from saltation.branches.branch import SpecialPointKind
from saltation.engine.flow import EventKind, Flow, SwitchingEvent, Trajectory
from saltation.errors import ConvergenceError, ModelError
from saltation.orbits.conditions import (
    ArrivalTangency,
    ConditionedProblem,
    CubicTangency,
    EventIdentity,
)
from saltation.orbits.single import ShootingProblem
from saltation.special_points.grazing import location_tolerances

_ARRIVALS = (EventKind.TRANSITION, EventKind.SLIDING_START)


@dataclass(frozen=True)
class SlidingChange:
    """How two orbits on either side of a sliding bifurcation differ.

    Attributes
    ----------
    kind : SpecialPointKind
        ``crossing_sliding``, ``switching_sliding`` or ``adding_sliding``.
    index : int
        In the events of the side without the extra events: the arrival at
        the surface (crossing- and switching-sliding), or the end of the
        sliding motion that touches the boundary (adding-sliding).
    mode : str
        The mode whose field is tangent to the surface at the bifurcation.
    surface : str
        The sliding surface.
    t_guess : float
        Where the side with the extra events has them (the touch lies between).
    side : float
        The side of the surface (the sign of ``h``) where ``mode`` lies.
    count : int
        At how many points of the orbit the change happens at once (2 for the two switchings of a
        symmetric orbit); the defining system holds at the first, symmetry gives the others.
    """

    kind: SpecialPointKind
    index: int
    mode: str
    surface: str
    t_guess: float
    side: float
    count: int = 1


def _arrival_side(flow: Flow, e: SwitchingEvent, p: np.ndarray) -> float:
    """The side of the surface an arrival moves to (the sign of ``dh/dt`` along the arriving field)."""
    return 1.0 if exit_rate(flow, e.mode_from, e.surface, e.t, e.x_minus, p) > 0 else -1.0


def _cyclic(traj: Trajectory) -> list[SwitchingEvent]:
    """The orbit's events as a cycle: a sliding start at ``t0`` that continues the sliding motion the
    period ends on is the section cutting that motion, not an event of its own."""
    ev = traj.events
    if ev and ev[0].kind == EventKind.SLIDING_START and ev[0].t == traj.t0 and traj.sliding_at_end \
            and any(e.kind == EventKind.SLIDING_START and e.surface == ev[0].surface for e in ev[1:]):
        return ev[1:]
    return ev


def _signature(e: SwitchingEvent) -> tuple:
    """What identifies an event in a change of sequence: its kind and surface, and the mode it enters
    (not for a sliding start, whose arrival side is what changes at a switching-sliding)."""
    return (int(e.kind), e.surface, "" if e.kind == EventKind.SLIDING_START else e.mode_to)


def _reduce(sigs: list, i: int, kind: SpecialPointKind) -> list | None:
    """The cycle of signatures with the extra events of a ``kind`` change at position ``i`` turned into
    the other side's form (rotated to start there), or None when there is no such change at ``i``."""
    m = len(sigs)
    if m < 2:
        return None
    rot = [sigs[(i + k) % m] for k in range(m)]
    (k0, s0, _), (k1, s1, m1) = rot[0], rot[1]
    if s0 != s1:
        return None
    tr, ss, se = int(EventKind.TRANSITION), int(EventKind.SLIDING_START), int(EventKind.SLIDING_END)
    if kind is SpecialPointKind.SWITCHING_SLIDING and (k0, k1) == (tr, ss):
        return rot[1:]  # [crossing into B, sliding start] -> [sliding start]
    if kind is SpecialPointKind.CROSSING_SLIDING and (k0, k1) == (ss, se):
        return [(tr, s0, m1)] + rot[2:]  # [sliding start, sliding end into B] -> [crossing into B]
    if kind is SpecialPointKind.ADDING_SLIDING and (k0, k1) == (se, ss) and m > 2 and rot[2][:2] == (se, s0):
        return rot[2:]  # [sliding end into A, sliding start, sliding end] -> [sliding end]
    return None


def _same_cycle(a: list, b: list) -> bool:
    n = len(a)
    return n == len(b) and any(all(a[k] == b[(k + r) % n] for k in range(n)) for r in range(max(n, 1)))


def _nearest(events: list[SwitchingEvent], kind: EventKind, surface: str, t: float, span: float,
             mode_to: str | None = None) -> SwitchingEvent | None:
    """Of the events of a kind on a surface (entering ``mode_to``, if given), the nearest in time to ``t``,
    modulo the period ``span``."""

    def distance(e):
        d = (e.t - t) % span
        return min(d, span - d)

    found = [e for e in events if e.kind == kind and e.surface == surface and (mode_to is None or e.mode_to == mode_to)]
    return min(found, key=distance) if found else None


def sliding_change(flow: Flow, without: Trajectory, with_: Trajectory, p_with: np.ndarray,
                   p_without: np.ndarray) -> SlidingChange | None:
    """Recognise a crossing-, switching- or adding-sliding change between two orbits.

    ``with_`` has the extra events: one more (crossing- and switching-sliding)
    or two more (adding-sliding), or twice that where the change happens at
    two points of the orbit at once (the two switchings of a symmetric orbit).
    The event sequences are compared as cycles (events may pass the section
    ``t = t0`` between the two orbits).

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    without : Trajectory
        One period of the orbit without the extra events.
    with_ : Trajectory
        One period of the orbit with them.
    p_with, p_without : ndarray
        Their parameter values.

    Returns
    -------
    SlidingChange or None
        The change, or None for any other change of the event sequence.

    References
    ----------
    di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding:
    derivation of normal-form mappings", Physica D 170.
    """
    w, wo = _cyclic(with_), _cyclic(without)
    if not wo:
        return None
    sw, swo = [_signature(e) for e in w], [_signature(e) for e in wo]
    span = with_.t1 - with_.t0
    for kind, per in ((SpecialPointKind.SWITCHING_SLIDING, 1), (SpecialPointKind.CROSSING_SLIDING, 1),
                      (SpecialPointKind.ADDING_SLIDING, 2)):
        for count in (1, 2):
            if len(w) - len(wo) != per * count:
                continue
            for i in range(len(w)):
                reduced = _reduce(sw, i, kind)
                if reduced is None:
                    continue
                if count == 2:
                    seconds = (_reduce(reduced, j, kind) for j in range(1, len(reduced)))
                    if not any(r is not None and _same_cycle(r, swo) for r in seconds):
                        continue
                elif not _same_cycle(reduced, swo):
                    continue
                change = _change(flow, kind, w, i, without, span, p_with, p_without)
                if change is not None:
                    return replace(change, count=count)
    return None


def _change(flow: Flow, kind: SpecialPointKind, w: list[SwitchingEvent], i: int, without: Trajectory, span: float,
            p_with: np.ndarray, p_without: np.ndarray) -> SlidingChange | None:
    """The change of ``kind`` whose extra events start at ``w[i]``, tied to the other side's event."""
    m = len(w)
    e, nxt = w[i], w[(i + 1) % m]
    if kind is SpecialPointKind.SWITCHING_SLIDING:  # the arrival: a sliding start on the other side
        arrival = _nearest(without.events, EventKind.SLIDING_START, e.surface, nxt.t, span)
        return None if arrival is None else SlidingChange(
            kind, without.events.index(arrival), e.mode_to, e.surface, e.t, _arrival_side(flow, e, p_with))
    if kind is SpecialPointKind.CROSSING_SLIDING:  # the arrival: a crossing into B on the other side
        crossing = _nearest(without.events, EventKind.TRANSITION, e.surface, e.t, span, nxt.mode_to)
        return None if crossing is None else SlidingChange(
            kind, without.events.index(crossing), nxt.mode_to, e.surface, e.t,
            _arrival_side(flow, crossing, p_without))
    late = w[(i + 2) % m]  # adding-sliding: the touch lies between the extra exit and re-entry
    exit_ = _nearest(without.events, EventKind.SLIDING_END, e.surface, late.t, span, late.mode_to)
    if exit_ is None:
        return None
    t_guess = without.t0 + (e.t - without.t0 + 0.5 * ((nxt.t - e.t) % span)) % span
    return SlidingChange(kind, without.events.index(exit_), e.mode_to, e.surface, t_guess,
                         -_arrival_side(flow, nxt, p_with))


@dataclass(frozen=True)
class SlidingBifurcationOrbit:
    """A located orbit at a crossing-, switching- or adding-sliding bifurcation.

    Attributes
    ----------
    kind : SpecialPointKind
        ``crossing_sliding``, ``switching_sliding`` or ``adding_sliding``.
    parameter : float
        The parameter's value at the bifurcation.
    state0 : ndarray
        The orbit's state at ``t0``.
    t_touch : float
        Where the orbit meets the boundary of the sliding region.
    x_touch : ndarray
        The state there.
    mode : str
        The mode whose field is tangent to the surface there.
    curvature : float
        ``d2h/dt2`` along that field at the touch, signed so that positive
        means the field's orbit leaves the surface to the mode's side (a
        visible tangency); zero to rounding at an adding-sliding, where the
        third derivative decides.
    accuracy : float
        The Newton correction of the parameter that would follow, plus the
        integration error carried to the parameter (an error estimate).
    residuals : list of float
        Newton's residual history.
    trajectory : Trajectory
        The period from ``state0``, with its monodromy.
    """

    kind: SpecialPointKind
    parameter: float
    state0: np.ndarray
    t_touch: float
    x_touch: np.ndarray
    mode: str
    curvature: float
    accuracy: float
    residuals: list[float]
    trajectory: Trajectory


def exit_rate(flow: Flow, mode: str, surface: str, t: float, x: np.ndarray, p: np.ndarray) -> float:
    """``h_x f + h_t``: the rate of the indicator along a mode's field (zero where the field is tangent).

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    mode : str
        The mode.
    surface : str
        The surface.
    t : float
        Time.
    x : ndarray
        State.
    p : ndarray
        Parameter values.

    Returns
    -------
    float
        The Lie derivative of the indicator along the mode's field.

    Raises
    ------
    ModelError
        If ``mode`` or ``surface`` names no mode or surface of the model.
    """
    hx, ht, _ = flow.indicator_gradient(surface, t, x, p)
    return float(hx @ flow.vector_field(mode, t, x, p) + ht)


def rate_along(flow: Flow, mode: str, fn: Callable[[float, np.ndarray], float], t: float, x: np.ndarray,
               p: np.ndarray, delta: float = 1e-3) -> float:
    """The derivative of ``fn(t, x)`` along the field of ``mode``.

    A fourth-order central difference along the straight line ``(t + s, x + s f(t, x))`` (exact to
    ``O(delta^4)``, rounding ``O(eps / delta)``).

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    mode : str
        The mode whose field is followed.
    fn : callable
        ``fn(t, x) -> float``.
    t : float
        Time.
    x : ndarray
        State.
    p : ndarray
        Parameter values.
    delta : float
        Relative step (scaled by the time and the field's size).

    Returns
    -------
    float
        The derivative.

    Raises
    ------
    ModelError
        If ``mode`` names no mode of the model.
    """
    f = flow.vector_field(mode, t, x, p)
    d = delta * max(1.0, abs(t)) / max(1.0, float(np.linalg.norm(f)))
    v = [fn(t + k * d, x + k * d * f) for k in (-2, -1, 1, 2)]
    return (v[0] - 8.0 * v[1] + 8.0 * v[2] - v[3]) / (12.0 * d)


def _curvature(flow: Flow, mode: str, surface: str, side: float, t: float, x: np.ndarray, p: np.ndarray) -> float:
    """``d2h/dt2`` along a mode's field, signed positive when its orbit leaves the surface into the mode
    (on ``side``)."""
    return side * rate_along(flow, mode, lambda s, y: exit_rate(flow, mode, surface, s, y, p), t, x, p)


def locate_tangent_arrival(
    flow: Flow, x0: np.ndarray, lam: float, lam_name: str, index: int, far_mode: str, side: float, *, parameters=None,
    t0: float = 0.0, tol: float = 1e-12, max_iter: int = 20, fd_step: float = 1e-7, tolerances=None,
    period: float | None = None,
) -> SlidingBifurcationOrbit:
    """Locate a crossing- or switching-sliding: periodicity plus ``h_x f_B + h_t = 0`` at the arrival.

    Where the orbit arrives at the surface, the far side's field is tangent to it.
    ``index`` is the position of that arrival among the orbit's events: a
    crossing into ``B`` or a sliding start, the same point on either side of
    the bifurcation (continuous across it), so the condition is well defined
    there.  The kind follows from the tangency's curvature:
    visible from ``B`` (its orbit leaves the surface) is a crossing-sliding,
    invisible a switching-sliding.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    x0 : ndarray
        Guess of the orbit's state at ``t0``.
    lam : float
        Guess of the parameter.
    lam_name : str
        The parameter that moves.
    index : int
        Position of the arrival among the guess's events.
    far_mode : str
        The mode ``B`` on the far side, whose field turns tangent.
    side : float
        The sign of ``h`` on ``B``'s side.
    parameters : mapping or ndarray, optional
        The other parameters' values (the model's defaults by default).
    t0 : float
        Initial time (forced models: the phase of the forcing).
    tol : float
        Newton tolerance.
    max_iter : int
        Largest number of Newton iterations.
    fd_step : float
        Unused (kept for the callers' signature; the condition's derivatives are exact).
    tolerances : Tolerances, optional
        Integration tolerances (tightened by
        :func:`~saltation.special_points.grazing.location_tolerances`).
    period : float, optional
        Guess of the period (autonomous models).

    Returns
    -------
    SlidingBifurcationOrbit
        The located orbit, its kind from the curvature at the touch.

    Raises
    ------
    ConvergenceError
        If Newton does not converge, or the guess's event ``index`` is not an arrival.
    ModelError
        For an autonomous model without a ``period`` guess, or an unknown parameter.
    IntegrationError, InitialModeError
        If the guess's orbit cannot be integrated.

    References
    ----------
    di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding:
    derivation of normal-form mappings", Physica D 170.
    """
    system = flow.system
    tolerances = location_tolerances(flow, tolerances)
    autonomous = system.is_autonomous
    if autonomous and period is None:
        raise ModelError(f"{system.name!r} is autonomous: locating its sliding bifurcation needs a period guess")
    p = flow.parameters(parameters).copy()
    j = system.parameter_index(lam_name)
    p[j] = float(lam)
    x0 = np.asarray(x0, dtype=float)[: system.n]
    base = ShootingProblem(flow, p, t0=t0, tolerances=tolerances)
    T = float(period) if autonomous else system.forcing_period(p)
    events = flow.run(x0, base.t0, base.t0 + T, p, tolerances=tolerances).events
    if len(events) <= index or events[index].kind not in _ARRIVALS:
        raise ConvergenceError(f"sliding bifurcation: the orbit's event {index} is not an arrival at a surface", [])
    e = events[index]
    same = [a for a in events if a.kind in _ARRIVALS and a.surface == e.surface and a.mode_from == e.mode_from]
    identity = EventIdentity(surface=e.surface, mode_from=e.mode_from, ordinal=same.index(e))
    condition = ArrivalTangency(flow, identity, far_mode, e.t)
    problem = ConditionedProblem(base, [condition], free=(lam_name,))
    found = problem.solve(problem.pack(x0, period=period), tol=tol, max_iter=max_iter, what="sliding bifurcation")
    hit = condition.event
    q = found.parameters
    curvature = _curvature(flow, far_mode, hit.surface, side, hit.t, hit.x_minus, q)
    kind = SpecialPointKind.CROSSING_SLIDING if curvature > 0 else SpecialPointKind.SWITCHING_SLIDING
    return SlidingBifurcationOrbit(
        kind=kind, parameter=float(q[j]), state0=found.state0, t_touch=hit.t, x_touch=hit.x_minus.copy(),
        mode=far_mode, curvature=curvature, accuracy=float(found.accuracy[0]), residuals=found.residuals,
        trajectory=found.shot.trajectory,
    )


def locate_adding_sliding(
    flow: Flow, x0: np.ndarray, lam: float, lam_name: str, t_guess: float, exit_mode: str, surface: str, side: float, *,
    parameters=None, t0: float = 0.0, tol: float = 1e-12, max_iter: int = 20, fd_step: float = 1e-6,
    tolerances=None,
) -> SlidingBifurcationOrbit:
    """Locate an adding-sliding: periodicity plus the exit side's cubic tangency at an instant of a sliding motion.

    At an unknown instant ``tau`` of a sliding motion, ``g = h_x f_A + h_t = 0`` and ``dg/dt = 0``
    along ``f_A``.  The unknowns are ``(x0, lam, tau)``; ``t_guess`` starts ``tau`` (for
    example between the extra exit and re-entry of the orbit that has them).
    ``g`` and its rate are taken at the state reached at ``tau`` (on the
    surface while the orbit slides; on the side that leaves, a state a little
    off it, where both are continuous).

    Parameters
    ----------
    flow : Flow
        The flow of a forced model.
    x0 : ndarray
        Guess of the orbit's state at ``t0``.
    lam : float
        Guess of the parameter.
    lam_name : str
        The parameter that moves.
    t_guess : float
        Guess of ``tau``.
    exit_mode : str
        The mode ``A`` the sliding motion would leave into.
    surface : str
        The sliding surface.
    side : float
        The sign of ``h`` on ``A``'s side.
    parameters : mapping or ndarray, optional
        The other parameters' values (the model's defaults by default).
    t0 : float
        Initial time (the phase of the forcing).
    tol : float
        Newton tolerance.
    max_iter : int
        Largest number of Newton iterations.
    fd_step : float
        Relative step of the central differences of the second derivatives.
    tolerances : Tolerances, optional
        Integration tolerances (tightened by
        :func:`~saltation.special_points.grazing.location_tolerances`).

    Returns
    -------
    SlidingBifurcationOrbit
        The located orbit (``adding_sliding``).

    Raises
    ------
    ConvergenceError
        If Newton does not converge, or the touch does not lie on a sliding motion.
    ModelError
        For an autonomous model, an unknown parameter or surface.

    References
    ----------
    di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding:
    derivation of normal-form mappings", Physica D 170.
    """
    system = flow.system
    tolerances = location_tolerances(flow, tolerances)
    if system.is_autonomous:
        raise ModelError(f"locating a sliding bifurcation is implemented for forced models; {system.name!r} is autonomous")
    p = flow.parameters(parameters).copy()
    j = system.parameter_index(lam_name)
    p[j] = float(lam)
    base = ShootingProblem(flow, p, t0=t0, tolerances=tolerances)
    condition = CubicTangency(flow, exit_mode, surface, float(t_guess), h=fd_step)
    problem = ConditionedProblem(base, [condition], free=(lam_name,))
    history: list[float] = []
    found = problem.solve(problem.pack(np.asarray(x0, dtype=float)), tol=tol, max_iter=max_iter,
                          what="adding-sliding", history=history)
    q = found.parameters
    tau = float(found.unknowns[-1])
    x = condition.piece.x
    # at the touch the orbit slides (or, exactly at the bifurcation, leaves and returns at once)
    if abs(flow.indicator(surface, tau, x, q)) > 1e-9 * (1.0 + float(np.linalg.norm(x))):
        raise ConvergenceError("adding-sliding: the located touch does not lie on the switching surface", history)
    curvature = _curvature(flow, exit_mode, surface, side, tau, x, q)
    return SlidingBifurcationOrbit(
        kind=SpecialPointKind.ADDING_SLIDING, parameter=float(q[j]), state0=found.state0, t_touch=tau,
        x_touch=x.copy(), mode=exit_mode, curvature=curvature, accuracy=float(found.accuracy[0]), residuals=history,
        trajectory=found.shot.trajectory,
    )


__all__ = [
    "SlidingBifurcationOrbit", "SlidingChange", "exit_rate", "locate_adding_sliding", "locate_tangent_arrival",
    "rate_along", "sliding_change",
]
