"""The records of the special points the detector finds: every :class:`~saltation.branches.branch.SpecialPoint`
it builds is built here.

Three of them locate their point first, by its defining system: a grazing (:func:`grazing_point`,
:func:`unlocated_grazing` where that fails) and a sliding bifurcation (:func:`sliding_bifurcation_point`).
The others record what :mod:`~saltation.special_points.smooth`,
:mod:`~saltation.special_points.nonsmooth` and :mod:`~saltation.special_points.symmetric` located.
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from saltation.branches.branch import (
    BorderScenario,
    Limits,
    OneSided,
    SpecialPoint,
    SpecialPointKind,
    SpecialPointStatus,
    Touch,
)
from saltation.branches.corrector import Solution
from saltation.engine.flow import EventKind
from saltation.errors import SaltationError
from saltation.model.system import PiecewiseSystem
from saltation.orbits.border_collision import feigin_scenario
from saltation.orbits.boundary import (
    corner_saltation_is_bounded,
    saltation_at_corner,
    zero_length_segments,
)
from saltation.orbits.classification import SetValuedCrossing
from saltation.orbits.floquet import multipliers_from_monodromy
from saltation.special_points.grazing import locate_grazing
from saltation.special_points.sliding import (
    locate_adding_sliding,
    locate_tangent_arrival,
    sliding_change,
)

__all__ = [
    "grazing_point",
    "on_surface_point",
    "period_doubling_of_half_point",
    "sliding_bifurcation_point",
    "smooth_point",
    "special_point_between",
    "symmetry_breaking_point",
    "two_sides",
    "unbounded_limit",
    "unlocated_grazing",
    "unlocated_symmetry_breaking",
    "with_border_scenario",
]


def unbounded_limit(nearest: complex) -> complex:
    """The limit of a multiplier that grows without bound towards a point, from its value on the nearest orbit.

    Along the real axis where the nearest orbit's is real (the crossing side of an impact's grazing:
    Nordmark's square-root map, whose large multiplier is real), with its sign: ``complex(-inf, 0)`` for a
    negative one; the point at infinity ``complex(inf, 0)`` otherwise.

    Parameters
    ----------
    nearest : complex
        The multiplier of the nearest orbit that grows.

    Returns
    -------
    complex
        ``complex(+-inf, 0)``.

    Raises
    ------
    TypeError
        If ``nearest`` is not a number.
    """
    z = complex(nearest)
    real = abs(z.imag) <= 1e-9 * abs(z)
    return complex(-np.inf, 0.0) if real and z.real < 0 else complex(np.inf, 0.0)


def with_border_scenario(sp: SpecialPoint, *, autonomous: bool) -> SpecialPoint:
    """A non-smooth point with Feigin's prediction of its border collision filled in (``one_sided.scenario``
    and ``period_two``), from its one-sided multipliers (:func:`saltation.orbits.border_collision.feigin_scenario`).

    The tolerance within which a multiplier counts as on the unit circle is ten times the point's
    ``multipliers_accuracy`` (at least ``1e-6``; ``1e-6`` where it is unknown).  A
    ``discontinuous_symmetry_breaking`` point is ``undetermined``: the jump through -1 is the half-period
    map's, which the whole period's multipliers (its squares) do not show.  Points without both sides'
    multipliers are returned as they are.

    Parameters
    ----------
    sp : SpecialPoint
        A special point.
    autonomous : bool
        Whether its orbit is autonomous (the trivial multiplier is left out of the count).

    Returns
    -------
    SpecialPoint
        The point, with the scenario where it has both sides' multipliers.

    Raises
    ------
    ValueError
        If its two sides have different numbers of multipliers.

    References
    ----------
    di Bernardo, Feigin, Hogan and Homer (1999), "Local analysis of C-bifurcations in n-dimensional
    piecewise-smooth dynamical systems", Chaos, Solitons & Fractals 10.
    """
    if sp.one_sided is None or sp.multipliers_minus is None or sp.multipliers_plus is None:
        return sp
    accuracy = sp.multipliers_accuracy
    tolerance = 10.0 * accuracy if np.isfinite(accuracy) else 0.0
    found = feigin_scenario(sp.multipliers_minus, sp.multipliers_plus, autonomous=autonomous, tolerance=tolerance)
    scenario, period_two = found.scenario, found.period_two
    if sp.kind is SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING:
        scenario, period_two = BorderScenario.UNDETERMINED, None
    return replace(sp, one_sided=replace(sp.one_sided, scenario=scenario, period_two=period_two))


def two_sides(lo: Solution, hi: Solution, **more) -> OneSided:
    """The two sides of a non-smooth point between ``lo`` (minus) and ``hi`` (plus): their orbits'
    multipliers, monodromies and event sequences (by label and by identity).

    Parameters
    ----------
    lo, hi : Solution
        The solutions on either side.
    **more
        Further fields of :class:`~saltation.branches.branch.OneSided` (or replacements of these).

    Returns
    -------
    OneSided
    """
    a, b = lo.summary, hi.summary
    sides = {
        "multipliers_minus": a.multipliers, "multipliers_plus": b.multipliers,
        "monodromy_minus": a.monodromy, "monodromy_plus": b.monodromy,
        "event_labels_minus": a.event_labels, "event_labels_plus": b.event_labels,
        "event_ids_minus": a.event_ids, "event_ids_plus": b.event_ids,
    }
    return OneSided(**{**sides, **more})


def special_point_between(
    lo: Solution,
    hi: Solution,
    crossing: SetValuedCrossing,
    *,
    index: int,
    bracket: tuple[float, float],
    accuracy: float,
    monodromy_plus: np.ndarray | None,
    note: str = "",
) -> SpecialPoint:
    """The record of a non-smooth point from the solutions on its two sides (``lo`` on the side of point ``index``).

    Parameters
    ----------
    lo, hi : Solution
        The bracketing solutions.
    crossing : SetValuedCrossing
        The classification.
    index : int
        The index of the branch point before the point.
    bracket : tuple of float
        The parameter interval that holds it.
    accuracy : float
        The distance between ``lo`` and ``hi``.
    monodromy_plus : ndarray or None
        The monodromy on ``hi``'s side.
    note : str
        A note for the record.

    Returns
    -------
    SpecialPoint
        At the middle of the bracket, with ``lo``'s state and both sides' multipliers.
    """
    return SpecialPoint(
        kind=crossing.kind,
        parameter=0.5 * (lo.lam + hi.lam),
        bracket=bracket,
        accuracy=accuracy,
        index=index,
        state=lo.summary.state,
        period=lo.summary.period,
        amplitude=lo.summary.amplitude,
        one_sided=two_sides(lo, hi, monodromy_plus=monodromy_plus, crossing_q=crossing.q, crossing_point=crossing.point),
        note=note,
    )


def sliding_bifurcation_point(problem, lo: Solution, hi: Solution, index: int) -> SpecialPoint | None:
    """The record of a crossing-, switching- or adding-sliding between two branch points.

    Located by its defining system (:mod:`saltation.special_points.sliding`).  Its one-sided
    multipliers are those of the two bracketing orbits (the extra segment shrinks linearly or like a
    square root), and their difference is the stated accuracy bound.

    Parameters
    ----------
    problem : ShootingProblem
        The branch's problem (forward time, one forcing period).
    lo, hi : Solution
        The bracketing solutions (``lo`` on the side of point ``index``).
    index : int
        The index of the branch point before the point.

    Returns
    -------
    SpecialPoint or None
        The located point; None when the change is not a sliding bifurcation, the problem is not a
        forward-time one over one period, or the location fails or lands outside the bracket.

    References
    ----------
    di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding:
    derivation of normal-form mappings", Physica D 170.
    """
    flow = problem.flow
    sides = _sides(lo, hi)
    if flow is None or sides is None or problem.backward or problem.periods != 1:
        return None
    lo_fewer, without, with_, traj_wo, traj_w = sides
    change = sliding_change(flow, traj_wo, traj_w, problem.parameters_at(with_.lam), problem.parameters_at(without.lam))
    if change is None:
        return None
    n = problem.system.n
    options = {"parameters": problem.parameters_at(without.lam), "t0": problem.t0, "tolerances": problem.tolerances}
    try:
        if change.kind is SpecialPointKind.ADDING_SLIDING:
            found = locate_adding_sliding(flow, without.u[:n], without.lam, problem.lam_name, change.t_guess,
                                          change.mode, change.surface, change.side, **options)
        else:
            period = problem.period_of(without.u, without.lam) if problem.system.is_autonomous else None
            found = locate_tangent_arrival(flow, without.u[:n], without.lam, problem.lam_name, change.index,
                                           change.mode, change.side, period=period, **options)
    except SaltationError:
        return None
    width = abs(hi.lam - lo.lam)
    if found.kind is not change.kind \
            or abs(found.parameter - 0.5 * (lo.lam + hi.lam)) > width + 1e-9 * (1.0 + abs(found.parameter)):
        return None
    traj = found.trajectory
    where = {
        SpecialPointKind.CROSSING_SLIDING: "arrives at the surface where the field of {m!r} is tangent to it, "
                                           "visible from that side (the orbit of that field leaves the surface)",
        SpecialPointKind.SWITCHING_SLIDING: "arrives at the surface where the field of {m!r} is tangent to it, "
                                            "invisible from that side (the orbit of that field returns to it)",
        SpecialPointKind.ADDING_SLIDING: "slides through a point where the field of {m!r} has a cubic tangency "
                                         "with the surface (the sliding motion touches the boundary of its region)",
    }[found.kind].format(m=found.mode)
    return SpecialPoint(
        kind=found.kind,
        parameter=found.parameter,
        bracket=(found.parameter - found.accuracy, found.parameter + found.accuracy),
        accuracy=found.accuracy,
        index=index,
        state=found.state0,
        period=found.trajectory.t1 - found.trajectory.t0,
        amplitude=float(max(abs(traj.x_max[0]), abs(traj.x_min[0]))),
        one_sided=two_sides(lo, hi, limits=Limits.NEAREST_ORBITS),
        note=(f"the orbit {where} (surface {change.surface!r}, t = {found.t_touch:.10g}, d2h/dt2 there "
              f"{found.curvature:.3g}){'' if change.count == 1 else f', at {change.count} points of the orbit at once'}; "
              f"the side with the extra events is {'plus' if lo_fewer else 'minus'}"),
        multipliers_accuracy=float(np.linalg.norm(hi.summary.monodromy - lo.summary.monodromy)),
        status=SpecialPointStatus.LOCATED,
        touch=Touch(change.surface, found.mode, found.t_touch),
    )


def _sides(lo: Solution, hi: Solution):
    """``(lo has fewer events, side without the extra events, side with them, their trajectories)``, or None."""
    lo_fewer = len(lo.summary.event_labels) <= len(hi.summary.event_labels)
    without, with_ = (lo, hi) if lo_fewer else (hi, lo)
    traj_wo, traj_w = without.evaluation.trajectory, with_.evaluation.trajectory
    if traj_wo is None or traj_w is None:
        return None
    return lo_fewer, without, with_, traj_wo, traj_w


def grazing_point(problem, lo: Solution, hi: Solution, index: int) -> SpecialPoint | None:
    """The record of a grazing between two branch points, located by its defining system.

    ``lo`` (the side of point ``index``) and ``hi`` differ by events on a
    surface that the orbit on one side misses: the grazing orbit is located
    from the orbit that misses it (:func:`saltation.special_points.grazing.locate_grazing`).
    Its monodromy is the limit on that side.  On the crossing side the limit
    is the grazing orbit with the crossing's saltation matrices inserted at
    the instant of tangency when they stay bounded (a continuous field), and
    unbounded otherwise (an impact: ``S = O(1/v)``): the largest multiplier
    there is reported as infinite (:func:`unbounded_limit`: ``-inf`` where the nearest crossing orbit's is
    real and negative), the others are those of the nearest orbit.

    Parameters
    ----------
    problem : ShootingProblem
        The branch's problem (one forcing period).
    lo, hi : Solution
        The bracketing solutions.
    index : int
        The index of the branch point before the grazing.

    Returns
    -------
    SpecialPoint or None
        The ``grazing`` (or ``grazing_sliding``) record; None when the change is not a grazing, or the
        location fails or lands outside the bracket.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the fundamental matrix at the instant of tangency is singular.

    References
    ----------
    di Bernardo, Budd, Champneys and Kowalczyk (2008), *Piecewise-smooth Dynamical Systems: Theory
    and Applications*, Springer.  Nordmark (1991), "Non-periodic motion caused by grazing incidence in
    an impact oscillator", J. Sound Vib. 145 (the square-root singularity of impacts).
    """
    flow = problem.flow
    sides = _sides(lo, hi)
    if flow is None or sides is None:
        return None
    lo_fewer, without, with_, traj_wo, traj_w = sides
    span = abs(traj_wo.t1 - traj_wo.t0)
    groups = zero_length_segments(traj_wo.events, traj_w.events, time_tol=1e-3 * span)
    if not groups:
        return None
    first = traj_w.events[groups[0][0]]
    try:
        orbit = locate_grazing(
            flow, without.u[: problem.system.n], without.lam, problem.lam_name, first.transition, first.t,
            parameters=problem.parameters_at(without.lam), t0=problem.t0, tolerances=problem.tolerances,
            period=problem.period_of(without.u, without.lam) if problem.system.is_autonomous else None,
            backward=problem.backward, periods=problem.periods, mode0=problem.mode0,
        )
    except SaltationError:
        return None
    width = abs(hi.lam - lo.lam)
    if abs(orbit.parameter - 0.5 * (lo.lam + hi.lam)) > width + 1e-9 * (1.0 + abs(orbit.parameter)):
        return None  # a grazing elsewhere: not the change between these points
    m_without = orbit.monodromy
    mu_without = multipliers_from_monodromy(m_without, backward=problem.backward)
    crossing = _crossing_side_limit(problem, orbit, [traj_w.events[i] for i in groups[0]], with_)
    side = "plus" if lo_fewer else "minus"
    surface = problem.system.transitions[orbit.transition].surface
    m_lo, m_hi = (m_without, crossing.monodromy) if lo_fewer else (crossing.monodromy, m_without)
    mu_lo, mu_hi = (mu_without, crossing.multipliers) if lo_fewer else (crossing.multipliers, mu_without)
    traj = orbit.trajectory
    return SpecialPoint(
        kind=SpecialPointKind.GRAZING_SLIDING if crossing.sliding else SpecialPointKind.GRAZING,
        parameter=orbit.parameter,
        bracket=(orbit.parameter - orbit.accuracy, orbit.parameter + orbit.accuracy),
        accuracy=orbit.accuracy,
        index=index,
        state=orbit.state0,
        period=orbit.period,
        amplitude=float(max(abs(traj.x_max[0]), abs(traj.x_min[0]))),
        one_sided=two_sides(lo, hi, multipliers_minus=mu_lo, multipliers_plus=mu_hi, monodromy_minus=m_lo,
                            monodromy_plus=m_hi, limits=crossing.limits),
        note=(f"grazing of surface {surface!r} at t = {orbit.t_graze:.10g}; the side with the crossing is "
              f"'{side}', {crossing.text}"),
        multipliers_accuracy=crossing.accuracy,
        status=SpecialPointStatus.LOCATED,
        touch=Touch(surface, problem.system.transitions[orbit.transition].source, orbit.t_graze),
    )


class _CrossingSide(NamedTuple):
    """The one-sided limit at a grazing on the side with the crossing (:func:`_crossing_side_limit`)."""

    monodromy: np.ndarray | None
    multipliers: np.ndarray
    text: str
    accuracy: float
    limits: Limits
    sliding: bool


def _crossing_side_limit(problem, orbit, group: list, with_: Solution) -> _CrossingSide:
    """The limit of the monodromy and multipliers at the grazing ``orbit`` on the side with the crossing,
    whose nearest orbit is ``with_`` and whose excursion is the events ``group`` of that orbit.

    Bounded saltation matrices at the tangency are inserted into the grazing orbit's monodromy; a sliding
    segment's are those of the nearest orbit; an unbounded one (an impact) gives an infinite multiplier,
    or, for an autonomous orbit, a limit extrapolated in ``sqrt(distance)``.  The accuracy: the grazing
    orbit is exact to the located parameter; the finite multipliers of an unbounded side are those of the
    nearest orbit, of unknown accuracy (nan)."""
    p = problem.parameters_at(orbit.parameter)
    sliding = any(e.kind != EventKind.TRANSITION for e in group)
    backward = problem.backward
    # the excursion's transitions in forward time (a backward shot meets them in reverse order)
    excursion = [e.transition for e in (reversed(group) if backward else group)]
    P = None if sliding else saltation_at_corner(problem.system, excursion, orbit.t_graze, orbit.x_graze, p)
    bounded_corner = not sliding and corner_saltation_is_bounded(problem.system, excursion[0], orbit.t_graze,
                                                                 orbit.x_graze, p, P)
    if bounded_corner and backward:  # run backward, the excursion's map is the inverse of the forward one
        bounded_corner = np.linalg.cond(P) < 1e12
        P = np.linalg.inv(P) if bounded_corner else None
    m_without = orbit.monodromy
    if sliding:
        # the orbit grazes the boundary of a sliding region: the sliding segment's saltation matrices are
        # 0/0 at the tangency; those of the nearest orbit with the segment stand in for their limit
        P = np.eye(problem.system.n)
        for e in group:
            P = e.saltation @ P
        phi = orbit.fundamental_to_graze
        m_with = m_without @ np.linalg.solve(phi, P @ phi)
        error = float(np.linalg.norm(with_.summary.monodromy - m_with))
        text = ("a sliding segment: the limit uses the saltation matrices of the nearest orbit that slides "
                f"(multipliers known to about {np.linalg.norm(with_.summary.monodromy - m_with):.1e})")
        return _CrossingSide(m_with, multipliers_from_monodromy(m_with, backward=backward), text, error,
                             Limits.NEAREST_SALTATION, True)
    if bounded_corner:
        phi = orbit.fundamental_to_graze
        m_with = m_without @ np.linalg.solve(phi, P @ phi)
        return _CrossingSide(m_with, multipliers_from_monodromy(m_with, backward=backward),
                             "bounded: the crossing's saltation matrices at the tangency are finite",
                             orbit.accuracy * float(np.linalg.norm(m_without)) + 1e-13, Limits.GRAZING, False)
    extrapolated = _autonomous_crossing_limit(problem, orbit, with_) if problem.autonomous else None
    if extrapolated is not None:
        mu_with, limit_error = extrapolated
        text = ("unbounded saltation matrix along the flow: an autonomous orbit's kick at the tangency "
                "moves its phase only, so its multipliers stay finite; their limit is extrapolated in "
                f"sqrt(distance) from two crossing orbits (to about {limit_error:.1e})")
        return _CrossingSide(None, mu_with, text, limit_error, Limits.EXTRAPOLATED, False)
    nearest = np.asarray(with_.summary.multipliers, dtype=complex)
    order = np.argsort(np.abs(nearest))
    mu_with = np.concatenate([[unbounded_limit(nearest[order[-1]])], nearest[order[:-1]]])
    text = ("unbounded: the crossing's saltation matrix grows like 1/sqrt(distance); the largest "
            "multiplier on that side is infinite in the limit (along the real axis where the nearest orbit's is "
            "real: -inf for a negative one), the others are those of the nearest orbit")
    return _CrossingSide(None, mu_with, text, float("nan"), Limits.GRAZING, False)


def unlocated_grazing(problem, lo: Solution, hi: Solution, index: int, *, bracket: tuple[float, float],
                      accuracy: float, note: str = "") -> SpecialPoint | None:
    """The record of a grazing with an unbounded side that its defining system could not locate.

    Where the two sides differ by a zero-length excursion of transitions whose saltation matrices are
    unbounded at the tangency (an impact: ``S = O(1/v)``), the one-sided limit on the crossing side is
    infinite, whatever the finite multipliers of the nearest crossing orbit are (they grow like
    ``d^(-1/2)`` towards the point).  Whether the excursion is unbounded is decided from the nearest
    crossing orbit's own excursion by :func:`~saltation.orbits.boundary.corner_saltation_is_bounded` (its
    normal speed there is small, not zero, and the test's margin is ``sqrt`` of the ratio of the two).

    Parameters
    ----------
    problem : ShootingProblem
        The branch's problem.
    lo, hi : Solution
        The bracketing solutions (``lo`` on the side of point ``index``).
    index : int
        The index of the branch point before the grazing.
    bracket, accuracy, note
        As for :func:`special_point_between`.

    Returns
    -------
    SpecialPoint or None
        A ``grazing`` record, ``bracketed`` (not located), the crossing side's largest multiplier infinite
        (:func:`unbounded_limit`) and
        the others those of the nearest orbit; None when the sides do not differ by such an excursion, or
        its saltation matrices stay bounded (then the set-valued multipliers classify it).

    Raises
    ------
    numpy.linalg.LinAlgError
        On a backward-time branch, if an event's saltation matrix is singular (a reset that cannot be
        run backwards).
    """
    sides = _sides(lo, hi)
    if sides is None or not isinstance(problem.system, PiecewiseSystem):
        return None
    lo_fewer, without, with_, traj_wo, traj_w = sides
    groups = zero_length_segments(traj_wo.events, traj_w.events, time_tol=1e-3 * abs(traj_wo.t1 - traj_wo.t0))
    if not groups:
        return None
    group = [traj_w.events[i] for i in groups[0]]
    if any(e.kind != EventKind.TRANSITION for e in group):
        return None
    if problem.backward:
        group = group[::-1]  # the excursion in forward time
    first = group[0]
    p = problem.parameters_at(with_.lam)
    P = np.eye(problem.system.n)
    for e in group:
        P = (np.linalg.inv(e.saltation) if problem.backward else e.saltation) @ P
    if corner_saltation_is_bounded(problem.system, first.transition, first.t,
                                   first.x_plus if problem.backward else first.x_minus, p, P):
        return None
    nearest = np.asarray(with_.summary.multipliers, dtype=complex)
    order = np.argsort(np.abs(nearest))
    mu_with = np.concatenate([[unbounded_limit(nearest[order[-1]])], nearest[order[:-1]]])
    mu_without = np.asarray(without.summary.multipliers, dtype=complex)
    mu_lo, mu_hi = (mu_without, mu_with) if lo_fewer else (mu_with, mu_without)
    side = "plus" if lo_fewer else "minus"
    why = (f"grazing of surface {first.surface!r} near t = {first.t:.10g}, bracketed (its defining system did not "
           f"converge); the side with the crossing is '{side}', unbounded: the crossing's saltation matrix grows "
           "like 1/sqrt(distance), so the largest multiplier on that side is infinite in the limit (-inf where the "
           "nearest orbit's is real and negative), the others are those of the nearest orbit")
    crossing = SetValuedCrossing(SpecialPointKind.GRAZING, None, None)
    sp = special_point_between(lo, hi, crossing, index=index, bracket=bracket, accuracy=accuracy,
                               monodromy_plus=None, note=(note + "; " if note else "") + why)
    return replace(sp, one_sided=replace(sp.one_sided, multipliers_minus=mu_lo, multipliers_plus=mu_hi, monodromy_minus=None,
                                         limits=Limits.NEAREST_ORBITS),
                   multipliers_accuracy=float("nan"), touch=Touch(first.surface, first.mode_from, float(first.t)))


def _autonomous_crossing_limit(problem, orbit, with_: Solution) -> tuple[np.ndarray, float] | None:
    """The crossing side's multipliers at an autonomous grazing, extrapolated to the grazing orbit.

    On an autonomous orbit the unbounded part of an impact's saltation matrix at the tangency points
    along the flow (the kick shifts the phase), so the multipliers have finite limits, approached like
    ``sqrt(d)``.  Two crossing orbits at ``d`` and ``4 d`` give ``mu(0) ~ 2 mu(d) - mu(4 d)``; the error
    estimate is ``|mu(d) - mu(4 d)|``, the size of the square-root term at ``d``.  None when they cannot
    be solved.
    """
    if not problem.single_shooting is not None:
        return None
    direction = 1.0 if with_.lam >= orbit.parameter else -1.0
    saved = (problem.x_ref, problem.f_ref)  # the branch's phase anchor stays
    values = []
    try:
        for d in (1e-7, 4e-7):
            lam = orbit.parameter + direction * d * max(1.0, abs(orbit.parameter))
            found = problem.solve(problem.pack(orbit.state0, orbit.period), lam)
            values.append(np.asarray(found.multipliers, dtype=complex))
    except SaltationError:
        return None
    finally:
        problem.x_ref, problem.f_ref = saved
    near, far = (v[np.argsort(np.abs(v))] for v in values)
    if len(near) != len(far) or not np.all(np.isfinite(near)):
        return None
    return 2.0 * near - far, float(np.max(np.abs(near - far)))



def smooth_point(kind: SpecialPointKind, best: Solution, *, bracket: tuple[float, float], accuracy: float,
                 index: int, multipliers_accuracy: float, note: str = "") -> SpecialPoint:
    """The record of a smooth special point located on the secant (a fold, a multiplier crossing, a Hopf point).

    Parameters
    ----------
    kind : SpecialPointKind
        The kind located.
    best : Solution
        The end of the final bracket whose test value is the smaller: the point's orbit.
    bracket : tuple of float
        The parameter interval that holds it.
    accuracy : float
        The distance between the final bracket's ends.
    index : int
        The index of the branch point before it.
    multipliers_accuracy : float
        How well the multipliers meet the kind's condition (nan for a kind without one).
    note : str
        A note for the record.

    Returns
    -------
    SpecialPoint
        Status ``bracketed``, with ``best``'s orbit and multipliers.
    """
    return SpecialPoint(
        kind=kind,
        parameter=best.lam,
        bracket=bracket,
        accuracy=accuracy,
        index=index,
        state=best.summary.state,
        period=best.summary.period,
        amplitude=best.summary.amplitude,
        multipliers=best.summary.multipliers,
        event_ids=best.summary.event_ids,
        multipliers_accuracy=multipliers_accuracy,
        note=note,
    )


def period_doubling_of_half_point(orbit, parameter: float, bracket: tuple[float, float], *, amplitude: float,
                                  index: int, multipliers_accuracy: float, note: str) -> SpecialPoint:
    """The record of the period doubling of the orbits of half the period, where a branch of orbits of twice
    their period meets them.

    Parameters
    ----------
    orbit : PeriodicOrbit
        The half-period orbit at the located parameter.
    parameter : float
        The located parameter.
    bracket : tuple of float
        The parameter interval that holds it.
    amplitude : float
        The orbit's amplitude, where the orbit has none of its own.
    index : int
        The index of the branch point before it.
    multipliers_accuracy : float
        The error of the branch point's multipliers.
    note : str
        A note for the record.

    Returns
    -------
    SpecialPoint
        Of kind ``period_doubling``, with the half-period orbit's state, period and multipliers.
    """
    return SpecialPoint(
        kind=SpecialPointKind.PERIOD_DOUBLING, parameter=float(parameter),
        bracket=bracket, accuracy=bracket[1] - bracket[0], index=index,
        state=np.asarray(orbit.state0, dtype=float), period=float(orbit.period),
        amplitude=float(getattr(orbit, "amplitude", amplitude)),
        multipliers=np.asarray(orbit.multipliers, dtype=complex),
        multipliers_accuracy=multipliers_accuracy, note=note,
    )


def symmetry_breaking_point(summary, parameter: float, half_width: float, *, index: int,
                            multipliers_accuracy: float, note: str) -> SpecialPoint:
    """The record of a symmetry breaking located on the symmetric orbits (the half-period map).

    Parameters
    ----------
    summary : BranchPoint
        The symmetric orbit at the located parameter.
    parameter : float
        The located parameter.
    half_width : float
        Half the width of its bracket (its accuracy).
    index : int
        The index of the branch point before it.
    multipliers_accuracy : float
        The error of the branch points' multipliers.
    note : str
        A note for the record (the half-period multiplier found).

    Returns
    -------
    SpecialPoint
        Of kind ``symmetry_breaking``, status ``located``.
    """
    return SpecialPoint(
        kind=SpecialPointKind.SYMMETRY_BREAKING,
        parameter=parameter,
        bracket=(parameter - half_width, parameter + half_width),
        accuracy=half_width,
        index=index,
        state=summary.state,
        period=summary.period,
        amplitude=summary.amplitude,
        multipliers=summary.multipliers,
        event_ids=summary.event_ids,
        multipliers_accuracy=multipliers_accuracy,
        status=SpecialPointStatus.LOCATED,
        note=note,
    )


def unlocated_symmetry_breaking(a: Solution, b: Solution, index: int, why: str) -> SpecialPoint:
    """A symmetry breaking known only to lie between ``a`` and ``b``: the test function changed sign there,
    so it is reported, not dropped.

    Parameters
    ----------
    a, b : Solution
        The branch points on either side.
    index : int
        The index of ``a`` on the branch.
    why : str
        Why the location failed (for the note).

    Returns
    -------
    SpecialPoint
        Of kind ``symmetry_breaking``, status ``failed``, with the bracket of the two branch points.
    """
    return SpecialPoint(
        kind=SpecialPointKind.SYMMETRY_BREAKING, parameter=0.5 * (a.lam + b.lam),
        bracket=(min(a.lam, b.lam), max(a.lam, b.lam)), accuracy=float(np.linalg.norm(b.z - a.z)), index=index,
        state=a.summary.state, period=a.summary.period, amplitude=a.summary.amplitude,
        multipliers=a.summary.multipliers, event_ids=a.summary.event_ids, status=SpecialPointStatus.FAILED,
        note=f"a real half-period multiplier passes -1 between two branch points, but {why}",
    )


def on_surface_point(good: Solution, failed: float, on, crossing: SetValuedCrossing,
                     monodromies: tuple[np.ndarray, np.ndarray], multipliers: tuple[np.ndarray, np.ndarray], *,
                     index: int, multipliers_accuracy: float) -> SpecialPoint:
    """The record of the end of a branch whose last orbit lies on a switching surface all round.

    Parameters
    ----------
    good : Solution
        The last orbit of the branch.
    failed : float
        The nearest parameter value beyond it at which the corrector failed.
    on : OrbitOnSurface
        How the orbit lies on the surface (:func:`~saltation.orbits.on_surface.orbit_on_surface`).
    crossing : SetValuedCrossing
        The classification from the one-sided limits.
    monodromies, multipliers : tuple of ndarray
        ``(M-, M+)`` and their multipliers: along the orbit with its own mode's Jacobian and with the
        Jacobian of the mode across the surface.
    index : int
        The index of the branch point before it.
    multipliers_accuracy : float
        The error of the orbit's monodromy.

    Returns
    -------
    SpecialPoint
        Status ``bracketed`` between the last orbit and the failure, limits ``on_surface``.
    """
    lo_lam, hi_lam = sorted((good.lam, failed))
    return SpecialPoint(
        kind=crossing.kind, parameter=good.lam, bracket=(lo_lam, hi_lam), accuracy=hi_lam - lo_lam,
        index=index, state=good.summary.state, period=good.summary.period,
        amplitude=good.summary.amplitude,
        one_sided=OneSided(multipliers_minus=multipliers[0], multipliers_plus=multipliers[1],
                           monodromy_minus=monodromies[0], monodromy_plus=monodromies[1], crossing_q=crossing.q,
                           crossing_point=crossing.point, event_labels_minus=good.summary.event_labels,
                           event_ids_minus=good.summary.event_ids, limits=Limits.ON_SURFACE),
        multipliers_accuracy=multipliers_accuracy, touch=Touch(on.surface, on.mode),
        note=(f"the orbit lies on {on.surface} all round (|h| <= {on.distance:.1e}) in mode {on.mode}; beyond it "
              f"the orbits lie in {on.other_mode}, where the corrector cannot follow them from this side: "
              f"one-sided limits from the variational equation along it with {on.mode}'s and {on.other_mode}'s "
              f"Jacobians"),
    )
