"""Non-smooth special points: where the orbit's event sequence changes along a branch.

A change of the event sequence between two branch points is bracketed by bisection along the secant to the
location tolerance (:func:`bisect_event_change`); where the two sides differ by an excursion through a
surface that one side misses, the grazing orbit is located by its defining system first and the bracket
closed around it.  The monodromies on both sides, ``M-`` and ``M+``, are then taken as exact one-sided
limits where the sides differ by segments of zero length (:mod:`saltation.orbits.boundary`), and the
point is classified by its set-valued multipliers (:func:`nonsmooth_point`,
:mod:`~saltation.orbits.classification`).  Two ends of a branch are non-smooth points too: a
grazing that stops the corrector (:func:`past_grazing`) and an orbit that comes to lie on a switching
surface all round (:func:`on_surface_end`).

The functions take the detector's context (:class:`~saltation.special_points.context.DetectionContext`)
as ``ctx``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from saltation.branches.branch import Limits, SpecialPoint, SpecialPointKind
from saltation.branches.corrector import Solution, canonical_events
from saltation.engine.flow import EventKind
from saltation.errors import SaltationError
from saltation.orbits.boundary import one_sided_limits, zero_length_segments
from saltation.orbits.classification import (
    SetValuedCrossing,
    classify_nonsmooth,
)
from saltation.orbits.floquet import multipliers_from_monodromy
from saltation.special_points.context import DetectionContext, _complex_text, _unit
from saltation.special_points.grazing import grazing_candidates, locate_grazing
from saltation.special_points.points import (
    _sides,
    grazing_point,
    on_surface_point,
    sliding_bifurcation_point,
    special_point_between,
    unlocated_grazing,
)
from saltation.special_points.symmetric import (
    half_limits,
    squares_agree,
    symmetric_crossing,
)

__all__ = ["bisect_event_change", "nonsmooth_point", "hidden_corner", "past_grazing", "on_surface_end"]


def past_grazing(ctx: DetectionContext, prev: Solution) -> tuple[Solution, SpecialPoint] | None:
    """Past a grazing that stopped the corrector: ``(first solution beyond, grazing special point)`` or None.

    Near a grazing the branch on the crossing side leaves the grazing orbit
    with a tangent of unbounded slope (its monodromy grows like
    ``1/sqrt(d)``), and pseudo-arclength steps from the side that misses
    the surface fail.  When the last orbit nearly touches a surface that
    a transition of its mode would cross, the grazing orbit is located by
    its defining system (:mod:`saltation.special_points.grazing`), and the branch is
    restarted just beyond it, at growing distances, from the grazing
    orbit's state.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    prev : Solution
        The last point the corrector reached.

    Returns
    -------
    tuple of (Solution, SpecialPoint) or None
        The first solution across the grazing and the grazing's record; None for a problem other
        than a single-shooting one over one period, or when no grazing explains the failure.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the fundamental matrix at the instant of tangency is singular
        (:func:`~saltation.special_points.points.grazing_point`).
    """
    prob = ctx.problem
    if not prob.single_shooting is not None or prob.periods != 1:
        return None
    flow, p = prob.flow, prob.parameters_at(prev.lam)
    n = prob.system.n
    T = prob.period_of(prev.u, prev.lam)
    try:
        traj = flow.run(prev.u[:n], prob.t0, prob.t0 + prob.sign * T, p, mode0=prob.mode0, dense=True,
                        tolerances=prob.tolerances)
    except SaltationError:
        return None
    direction = 1.0 if prev.tangent[-1] >= 0 else -1.0
    s = ctx.corrector.settings
    for transition, t_guess in grazing_candidates(flow, traj, p):
        try:
            orbit = locate_grazing(
                flow, prev.u[:n], prev.lam, prob.lam_name, transition, t_guess, parameters=p, t0=prob.t0,
                tolerances=prob.tolerances, period=T if prob.autonomous else None, backward=prob.backward,
                mode0=prob.mode0,
            )
        except SaltationError:
            continue
        ahead = (orbit.parameter - prev.lam) * direction
        if not -1e-9 <= ahead <= 4.0 * s.ds_max:
            continue
        u_graze = prob.pack(orbit.state0, orbit.period if prob.autonomous else None)
        z_graze = np.append(u_graze, orbit.parameter)
        for delta in (1e-6, 1e-5, 1e-4, 1e-3, 1e-2):
            lam = orbit.parameter + direction * delta * max(1.0, abs(orbit.parameter))
            if not s.bounds[0] <= lam <= s.bounds[1]:
                break
            try:
                start = prob.solve(u_graze, lam)
                cand = ctx.corrector.solve_fixed(prob.pack(start.state0, start.period if prob.autonomous else None),
                                                 lam)
            except SaltationError:
                continue
            if canonical_events(cand.summary.event_ids) == canonical_events(prev.summary.event_ids):
                continue  # the same side again: not across the grazing
            away = cand.z - z_graze
            cand.tangent = ctx.corrector.tangent(cand, away / np.linalg.norm(away))
            cand.step = float(np.linalg.norm(away))
            special = grazing_point(prob, prev, cand, len(ctx.branch.points) - 1)
            if special is None:
                continue
            return cand, special
    return None


def on_surface_end(ctx: DetectionContext, prev: Solution, failed: float) -> SpecialPoint | None:
    """The end of a branch whose last orbit comes to lie on a switching surface all round.

    The end is first bracketed in the parameter, between the last orbit the corrector reaches (from
    ``prev``) and ``failed``, to the location tolerance.  If that orbit has no events and lies on a
    surface over its whole period (:func:`~saltation.orbits.on_surface.orbit_on_surface`), the point is
    classified by its one-sided limits there (``Limits.ON_SURFACE``): the variational equation along
    it with its own mode's Jacobian (``M-``) and the Jacobian of the mode across the surface (``M+``).

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    prev : Solution
        The last point the corrector reached.
    failed : float
        A parameter value beyond it at which the corrector failed.

    Returns
    -------
    SpecialPoint or None
        A ``bracketed`` point between the last orbit and the first failure, or None for anything else
        (a single-shooting problem over one period is needed).

    Raises
    ------
    numpy.linalg.LinAlgError
        If a one-sided monodromy is not finite.
    """
    from saltation.orbits.on_surface import monodromy_in_mode, orbit_on_surface

    prob = ctx.problem
    if ctx.equilibrium or not prob.single_shooting is not None or prob.periods != 1 or prob.backward:
        return None
    good, bad = prev, float(failed)
    sequence = canonical_events(prev.summary.event_ids)
    for _ in range(60):
        if abs(bad - good.lam) <= ctx.tol * (1.0 + abs(good.lam)):
            break
        mid = 0.5 * (good.lam + bad)
        try:
            cand = ctx.corrector.solve_fixed(good.u, mid)
        except SaltationError:
            bad = mid
            continue
        if canonical_events(cand.summary.event_ids) == sequence:
            good = cand
        else:  # another orbit (the corrector jumped across the end): not the branch's
            bad = mid
    n = prob.system.n
    p = prob.parameters_at(good.lam)
    T = prob.period_of(good.u, good.lam)
    try:
        traj = prob.flow.run(good.u[:n], prob.t0, prob.t0 + T, p, mode0=prob.mode0, variational=True,
                             dense=True, tolerances=prob.tolerances)
    except SaltationError:
        return None
    on = orbit_on_surface(prob.flow, traj, p)
    if on is None:
        return None
    m_minus = traj.monodromy
    m_plus = monodromy_in_mode(prob.flow, traj, p, on.other_mode)
    mu_minus = multipliers_from_monodromy(m_minus)
    mu_plus = multipliers_from_monodromy(m_plus)
    crossing = classify_nonsmooth(m_minus, m_plus, autonomous=ctx.autonomous, mu_minus=mu_minus, mu_plus=mu_plus)
    return on_surface_point(good, bad, on, crossing, (m_minus, m_plus), (mu_minus, mu_plus),
                            index=len(ctx.branch.points) - 1, multipliers_accuracy=ctx.matrix_error(good))


def bisect_event_change(ctx: DetectionContext, a: Solution, b: Solution) -> tuple[Solution, Solution]:
    """The two solutions, with ``a``'s event sequence and without it, that bracket where it changes,
    down to the location tolerance.

    Where the two sides differ by an excursion through a surface that the orbit on one side misses,
    the boundary orbit is first located by its defining system (a grazing,
    :func:`~saltation.special_points.grazing.locate_grazing`) and the bracket is closed around it with
    two corrections (:func:`_bracket_at_grazing`, up to three pairs), in place of some 25 halvings.
    Every corrected point moves the end of the bracket whose event sequence it shares, as a
    bisection's does, so the bracket holds the change whether or not the grazing orbit is found
    (bisection along the secant then goes on from it).  Every correction is the context's
    :meth:`~saltation.special_points.context.DetectionContext.on_secant`.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    a, b : Solution
        Corrected points with different event sequences.

    Returns
    -------
    tuple of Solution
        ``(lo, hi)``: ``lo`` with ``a``'s event sequence, ``hi`` without it.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the grazing orbit's fundamental matrix is singular.
    """
    seq_a = canonical_events(a.summary.event_ids)
    lo, hi = a, b
    sa, sb = 0.0, 1.0
    trials = [0, 8]  # the grazing is tried at the start and, if that failed, once more after 7 halvings
    for it in range(80):
        if np.linalg.norm(hi.z - lo.z) <= ctx.tol:
            break
        if trials and it == trials[0]:
            trials.pop(0)
            placed = _bracket_at_grazing(ctx, a, b, lo, hi, sa, sb)
            if placed:
                trials.clear()
            for sm, mid in placed:
                if not sa < sm < sb:
                    continue
                if canonical_events(mid.summary.event_ids) == seq_a:
                    sa, lo = sm, mid
                else:
                    sb, hi = sm, mid
            continue
        sm = 0.5 * (sa + sb)
        try:
            mid = ctx.on_secant(a, b, sm)
        except SaltationError:
            break
        if canonical_events(mid.summary.event_ids) == seq_a:
            sa, lo = sm, mid
        else:
            sb, hi = sm, mid
    return lo, hi


def _bracket_at_grazing(ctx: DetectionContext, a: Solution, b: Solution, lo: Solution, hi: Solution, sa: float,
                        sb: float) -> list[tuple[float, Solution]]:
    """Corrected points on the secant from ``a`` to ``b`` just before and just after a grazing orbit
    between ``lo`` (at the secant's fraction ``sa``) and ``hi`` (at ``sb``), or none.

    The grazing orbit ``z*`` is located from the side without the excursion by its defining system
    (as :func:`~saltation.special_points.points.grazing_point`); it lies on the branch, so the hyperplane
    normal to the secant through it is the one at ``s* = (z* - a) . d / |d|^2`` (``d = b - a``).  The points are corrected on the
    hyperplanes at ``s* -+ delta``, ``delta |d|`` a quarter of the location tolerance (nearer, up to
    twice more, where the branch crosses the hyperplanes at a slant and the two land farther apart
    than the tolerance): their event sequences, not the grazing orbit, decide the bracket.  Returns
    ``[(fraction, solution), ...]``:
    empty where the change is no grazing, the problem is not a one-period single shooting, the
    location fails, or ``s*`` is outside ``(sa, sb)``.
    """
    prob = ctx.problem
    if ctx.equilibrium or not prob.single_shooting is not None or prob.periods != 1:
        return []
    sides = _sides(lo, hi)
    if sides is None:
        return []
    _, without, _, traj_wo, traj_w = sides
    span = abs(traj_wo.t1 - traj_wo.t0)
    groups = zero_length_segments(traj_wo.events, traj_w.events, time_tol=1e-3 * span)
    if not groups:
        return []
    first, last = traj_w.events[groups[0][0]], traj_w.events[groups[0][-1]]
    if first.kind != EventKind.TRANSITION:
        return []
    n = prob.system.n
    try:
        # the tangency lies within the excursion, whose ends are near each other
        orbit = locate_grazing(
            prob.flow, without.u[:n], without.lam, prob.lam_name, first.transition, 0.5 * (first.t + last.t),
            parameters=prob.parameters_at(without.lam), t0=prob.t0, tolerances=prob.tolerances,
            period=prob.period_of(without.u, without.lam) if prob.autonomous else None, backward=prob.backward,
            mode0=prob.mode0,
        )
    except SaltationError:
        return []
    d = b.z - a.z
    length2 = float(d @ d)
    z_star = np.append(prob.pack(orbit.state0, orbit.period if prob.autonomous else None), orbit.parameter)
    if z_star.shape != a.z.shape or length2 == 0.0:
        return []
    s_star = float((z_star - a.z) @ d) / length2
    delta = 0.25 * ctx.tol / math.sqrt(length2)
    placed = []
    for _ in range(3):
        # (the branch may cross the hyperplanes at a slant: where the two points are farther apart than
        # the tolerance, they are placed again, nearer; never at s* itself, where an orbit grazes to
        # rounding and neither side's events can be told)
        if not sa + delta < s_star < sb - delta:
            break
        pair = []
        for sm in (s_star - delta, s_star + delta):
            try:
                pair.append((sm, ctx.on_secant(a, b, sm)))
            except SaltationError:
                return placed
        placed += pair
        apart = float(np.linalg.norm(pair[1][1].z - pair[0][1].z))
        if apart <= ctx.tol:
            break
        delta *= 0.5 * ctx.tol / apart
    return placed


def nonsmooth_point(
    ctx: DetectionContext, lo: Solution, hi: Solution, index: int, note: str = "", *,
    far: tuple[Solution, Solution] | None = None,
) -> SpecialPoint:
    """Special point record from the two one-sided solutions around a non-smooth point.

    Where the two sides differ by segments of zero length (a corner
    collision), ``M-`` and ``M+`` are the exact limits at the boundary
    orbit (:mod:`saltation.orbits.boundary`), and the point is placed at the
    boundary orbit used.  Otherwise a grazing or sliding bifurcation is located by its defining
    system, and failing that ``M-`` and ``M+`` are the monodromies of ``lo`` and ``hi``.  ``far``
    are the branch points beyond ``lo`` and ``hi`` (on the same sides), used to estimate how well
    the multipliers are known.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    lo, hi : Solution
        The bracketing solutions (``lo`` on the side of point ``index``).
    index : int
        The index of the branch point before the non-smooth point.
    note : str
        A note for the record.
    far : tuple of Solution, optional
        The branch points beyond ``lo`` and ``hi``.

    Returns
    -------
    SpecialPoint
        The classified point, with its one-sided multipliers and their accuracy.

    Raises
    ------
    SaltationError
        If the one-sided monodromies needed to classify it are missing.

    References
    ----------
    Leine and Van Campen, "Fold bifurcations in discontinuous systems" (set-valued Floquet
    multipliers at corners).
    """
    bracket = (min(lo.lam, hi.lam), max(lo.lam, hi.lam))
    accuracy = float(np.linalg.norm(hi.z - lo.z))
    if ctx.equilibrium:
        crossing = SetValuedCrossing(SpecialPointKind.NONSMOOTH_NO_CROSSING, None, None)
        return special_point_between(
            lo, hi, crossing, index=index, bracket=bracket, accuracy=accuracy,
            monodromy_plus=hi.summary.monodromy, note=note,
        )
    limits = _limits(ctx, lo, hi, far)
    if limits is None:
        for locate in (grazing_point, sliding_bifurcation_point):
            found = locate(ctx.problem, lo, hi, index)
            if found is not None:
                return found
        found = unlocated_grazing(ctx.problem, lo, hi, index, bracket=bracket, accuracy=accuracy, note=note)
        if found is not None:
            return found
        m_lo, m_hi = lo.summary.monodromy, hi.summary.monodromy
        mu_lo, mu_hi = lo.summary.multipliers, hi.summary.multipliers
        how, mu_accuracy, at = Limits.NEAREST_ORBITS, _sqrt_extrapolated_error(lo, hi, far), None
    else:
        m_lo, m_hi, how, mu_accuracy, at = limits
        mu_lo = multipliers_from_monodromy(m_lo, backward=ctx.branch.backward)
        mu_hi = multipliers_from_monodromy(m_hi, backward=ctx.branch.backward)
    crossing = classify_nonsmooth(
        m_lo, m_hi, backward=ctx.branch.backward, autonomous=ctx.autonomous, mu_minus=mu_lo, mu_plus=mu_hi,
    )
    half = half_limits(ctx, lo, hi, exact=limits is not None)
    if half is not None and not squares_agree(half, mu_lo, mu_hi, backward=ctx.branch.backward):
        # the half-period maps' limits must square to the full ones' (M = G^2): where they do not even
        # agree on how many multipliers lie outside the unit circle, they missed the jump (an event of a
        # half period not resolved at loose tolerances), and the full multipliers classify the point
        note = (note + "; " if note else "") + (
            "symmetric orbit, but its half-period limits do not square to the full ones: classified from "
            "the full multipliers")
        half = None
    if half is not None:
        # the kind from the half-period maps (a symmetric orbit's multipliers are their squares); where the
        # set crosses, from the full ones: the set-valued monodromy is the convex hull (1 - q) M- + q M+ of
        # the full one-sided monodromies, and ((1 - q) G- + q G+)^2 is not in it
        full = crossing
        crossing = symmetric_crossing(classify_nonsmooth(
            half[0], half[1], backward=ctx.branch.backward, autonomous=ctx.autonomous,
        ))
        if crossing.point is not None:
            note = (note + "; " if note else "") + (
                f"symmetric orbit: the half-period multiplier crosses the unit circle at "
                f"{_complex_text(crossing.gamma)} (at q = {crossing.q:.6g} between the half-period maps)")
        if full.q is not None:
            crossing = replace(crossing, q=full.q, point=full.point)
    sp = special_point_between(
        lo, hi, crossing, index=index, bracket=bracket, accuracy=accuracy, monodromy_plus=m_hi, note=note,
    )
    return replace(
        sp, parameter=sp.parameter if at is None else at.lam,
        state=sp.state if at is None else at.summary.state,
        period=sp.period if at is None else at.summary.period,
        amplitude=sp.amplitude if at is None else at.summary.amplitude,
        multipliers_minus=mu_lo, multipliers_plus=mu_hi, monodromy_minus=m_lo,
        multipliers_accuracy=mu_accuracy, limits=how,
    )


def _limits(ctx: DetectionContext, lo: Solution, hi: Solution, far: tuple[Solution, Solution] | None):
    """Exact one-sided monodromies ``(M_lo, M_hi, how, accuracy, boundary solution)``, or None."""
    flow = ctx.problem.flow
    sides = _sides(lo, hi)
    if flow is None or sides is None:
        return None
    lo_fewer, without, with_, traj_wo, traj_w = sides
    try:
        lim = one_sided_limits(
            flow, traj_wo, traj_w, ctx.problem.parameters_at(without.lam),
            tolerances=ctx.problem.tolerances,
        )
    except SaltationError:
        return None
    if lim is None:
        return None
    # the limits are exact at ``without``, within the bracket of the true boundary: from there to the
    # boundary they move by about the distance along the branch times |dM/ds|, estimated on the side
    # without the segments.  Distances are taken along the branch, not in the parameter, which at a
    # corner that is a fold (both sides on one side of it) is no measure of the distance: the boundary's
    # hyperplane (normal to the secant ``d`` of ``far``) lies between those of ``lo`` and ``hi``, so
    # ``without`` is at most ``|(hi - lo) . d| / |e . d|`` from it along its side's direction ``e``
    width = float(np.linalg.norm(hi.z - lo.z))
    rate = 0.0
    if far is not None:
        other = far[0] if lo_fewer else far[1]
        leg = other.z - without.z
        leg_length = float(np.linalg.norm(leg))
        if other.summary.monodromy is not None and leg_length > 0.0:
            rate = float(np.linalg.norm(other.summary.monodromy - lim.monodromy_without)) / leg_length
            d = _unit(far[1].z - far[0].z)
            along = abs(float((hi.z - lo.z) @ d))
            slope = abs(float(leg @ d)) / leg_length
            width = along / slope if slope > 0.0 else math.inf
    scale = max(1.0, float(np.linalg.norm(lim.monodromy_with)))
    mu_accuracy = width * rate + 1e-13 * scale
    how = Limits.EXACT if lim.exact else Limits.NEAREST_SALTATION
    if not lim.exact:
        mu_accuracy += float(np.linalg.norm(traj_w.monodromy - lim.monodromy_with))
    m_lo, m_hi = ((lim.monodromy_without, lim.monodromy_with) if lo_fewer
                  else (lim.monodromy_with, lim.monodromy_without))
    return m_lo, m_hi, how, mu_accuracy, without


def hidden_corner(ctx: DetectionContext, lo: Solution, hi: Solution, index: int) -> SpecialPoint:
    """A non-smooth point where the multipliers jump but the event sequence is the same on both sides
    (an orbit that touches a surface whose saltation matrix is the identity while the field's Jacobian
    jumps, or a change of a mode that no event records), classified from the two nearest orbits'
    monodromies (``Limits.NEAREST_ORBITS``).

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    lo, hi : Solution
        The final bracket of a test function's sign change, across which the multipliers jump.
    index : int
        The index of the branch point before it.

    Returns
    -------
    SpecialPoint

    Raises
    ------
    SaltationError
        If the one-sided monodromies needed to classify it are missing.
    """
    crossing = classify_nonsmooth(
        lo.summary.monodromy, hi.summary.monodromy, backward=ctx.branch.backward, autonomous=ctx.autonomous,
        mu_minus=lo.summary.multipliers, mu_plus=hi.summary.multipliers,
    )
    sp = special_point_between(
        lo, hi, crossing, index=index, bracket=(min(lo.lam, hi.lam), max(lo.lam, hi.lam)),
        accuracy=float(np.linalg.norm(hi.z - lo.z)), monodromy_plus=hi.summary.monodromy,
        note=("the multipliers jump across the bracket while the event sequence stays the same: a non-smooth "
              "point, classified from the monodromies of the two nearest orbits"),
    )
    return replace(sp, limits=Limits.NEAREST_ORBITS,
                   multipliers_accuracy=max(ctx.matrix_error(lo), ctx.matrix_error(hi)))


def _sqrt_extrapolated_error(lo: Solution, hi: Solution, far: tuple[Solution, Solution] | None) -> float:
    """Error estimate of the monodromies of the two bracketing orbits as one-sided limits.

    On a side whose monodromy moves like the square root of the distance to
    the boundary, ``M(d) = M(0) + C sqrt(d)``: ``C`` from the bracket end and
    the branch point beyond it, the error ``C sqrt(d)`` at the bracket end.
    """
    if far is None:
        return float("nan")
    mid = 0.5 * (lo.lam + hi.lam)
    worst = 0.0
    for near, other in ((lo, far[0]), (hi, far[1])):
        d_near, d_far = abs(near.lam - mid), abs(other.lam - mid)
        if near.summary.monodromy is None or other.summary.monodromy is None or d_far <= d_near:
            return float("nan")  # no second point on that side: the error is not known
        c = float(np.linalg.norm(other.summary.monodromy - near.summary.monodromy)) / (np.sqrt(d_far) - np.sqrt(d_near))
        worst = max(worst, c * np.sqrt(d_near))
    return worst
