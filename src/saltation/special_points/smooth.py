"""Smooth special points: test functions and their location by the Illinois method on the secant.

Smooth special points are found by test functions and located by the Illinois method along the secant
between two branch points (:func:`locate_smooth`):

* fold (turning point): the parameter component of the tangent changes sign;
* period doubling: a real multiplier passes -1 (``prod(mu + 1)`` changes sign);
* Neimark-Sacker: a complex pair leaves the unit circle (a product of two multipliers passes 1);
* branch point: a real multiplier passes +1 without a turning point (``prod(mu - 1)`` changes sign), or,
  for a declared symmetry, a symmetry breaking (:mod:`~saltation.special_points.symmetric`);
* Hopf (equilibria): a complex pair of eigenvalues crosses the imaginary axis.

The functions take the detector's context (:class:`~saltation.special_points.context.DetectionContext`)
as ``ctx``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from saltation.branches.branch import SpecialPoint, SpecialPointKind
from saltation.branches.corrector import Solution, canonical_events
from saltation.branches.monitors import illinois_on_secant
from saltation.errors import SaltationError
from saltation.orbits.single import ShootingProblem
from saltation.special_points.context import (
    DetectionContext,
    _finite,
    _nearest,
    _nontrivial,
    _unit,
)
from saltation.special_points.nonsmooth import hidden_corner
from saltation.special_points.points import period_doubling_of_half_point, smooth_point
from saltation.special_points.symmetric import (
    locate_symmetry_breaking,
    meets_symmetric_orbits,
    symmetry_breaking_value,
)

__all__ = ["smooth_points", "locate_smooth"]


def smooth_points(ctx: DetectionContext, a: Solution, b: Solution, index: int) -> list[SpecialPoint]:
    """Smooth special points between two solutions with the same event sequence (test functions).

    Where a multiplier moves so far from ``a`` to ``b`` that it may have left the unit circle and come
    back (two changes of stability in one step, which no test function's sign shows), the step is
    split on the secant first (:func:`_pieces`) and each piece is tested.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    a, b : Solution
        Consecutive corrected points, or the ends of a smooth piece of a step.
    index : int
        The index of the branch point before them.

    Returns
    -------
    list of SpecialPoint
        The located points in branch order (folds and multiplier crossings that fail their check are left
        out).

    Raises
    ------
    SaltationError
        If a point that a test function finds must be classified from one-sided monodromies that are
        missing (:func:`~saltation.special_points.nonsmooth.hidden_corner`).
    """
    secant = _unit(b.z - a.z)
    pieces = _pieces(ctx, a, b, budget=[32])
    found = []
    for s0, s1 in zip(pieces, pieces[1:]):
        found += _smooth_points_of_piece(ctx, s0, s1, index, secant)
    return found


def _pieces(ctx: DetectionContext, a: Solution, b: Solution, depth: int = 0, *, budget: list[int]) -> list[Solution]:
    """``[a, ..., b]``: the step cut at the middle of its secant, again and again, until no multiplier
    moves across a piece by more than it lies from the unit circle at the piece's ends
    (:func:`_may_hide_a_pair`), the piece is within the location tolerance, 12 cuts deep, or the step's
    ``budget`` of corrections is spent.  A middle whose event sequence differs (a corner inside the
    step) or that cannot be solved is not cut."""
    if (ctx.equilibrium or depth >= 12 or budget[0] <= 0 or float(np.linalg.norm(b.z - a.z)) <= 10.0 * ctx.tol
            or not _may_hide_a_pair(_nontrivial(a, ctx.autonomous), _nontrivial(b, ctx.autonomous))):
        return [a, b]
    budget[0] -= 1
    try:
        mid = ctx.on_secant(a, b, 0.5)
    except SaltationError:
        return [a, b]
    if canonical_events(mid.summary.event_ids) != canonical_events(a.summary.event_ids):
        return [a, b]
    return _pieces(ctx, a, mid, depth + 1, budget=budget)[:-1] + _pieces(ctx, mid, b, depth + 1, budget=budget)


def _smooth_points_of_piece(ctx: DetectionContext, a: Solution, b: Solution, index: int,
                            secant: np.ndarray) -> list[SpecialPoint]:
    """:func:`smooth_points` on one piece of a step (``secant``: the whole step's direction)."""
    found = []
    # a point's test values are kept for the next pair: both secants point along the branch,
    # so the tangent (fold test) is oriented alike
    fold = _remembered("fold", lambda s: ctx.oriented_tangent(s, secant)[-1])
    if _crosses(fold(a), fold(b)):
        found.append(locate_smooth(ctx, a, b, index, SpecialPointKind.FOLD, fold))
    if ctx.equilibrium:
        hopf = _remembered("hopf", _hopf_test)
        if _crosses(hopf(a), hopf(b)):
            found.append(locate_smooth(ctx, a, b, index, SpecialPointKind.HOPF, hopf))
        return [sp for sp in found if sp is not None]
    for kind, test in ((SpecialPointKind.PERIOD_DOUBLING, _flip_test), (SpecialPointKind.NEIMARK_SACKER, _ns_test)):
        g = _remembered(kind.value, lambda s, test=test: test(_nontrivial(s, ctx.autonomous)))
        if _crosses(g(a), g(b)):
            found.append(locate_smooth(ctx, a, b, index, kind, g))
    # a real multiplier through +1 without a turning point: a branch point (a pitchfork or transcritical
    # point), or, for a declared symmetry, a symmetry breaking where a half-period multiplier passes -1
    plus = _remembered("plus_one", lambda s: _plus_one_test(_nontrivial(s, ctx.autonomous)))
    if _crosses(plus(a), plus(b)) and not _crosses(fold(a), fold(b)):
        g = (_remembered("symmetry_breaking", lambda s: symmetry_breaking_value(ctx, s))
             if ctx.symmetry is not None else None)
        if g is not None and _crosses(g(a), g(b)):
            found.append(locate_symmetry_breaking(ctx, a, b, index))
        else:
            found.append(locate_smooth(ctx, a, b, index, SpecialPointKind.BRANCH_POINT, plus))
    return [sp for sp in found if sp is not None]


def locate_smooth(
    ctx: DetectionContext, a: Solution, b: Solution, index: int, kind: SpecialPointKind,
    test: Callable[[Solution], float],
) -> SpecialPoint | None:
    """Illinois iteration on a continuous test function along the secant from ``a`` to ``b``.

    A fold or period doubling is reported only if the located orbit has a (nontrivial)
    multiplier at +1 or -1 (an equilibrium's fold an eigenvalue at 0) within the point's
    ``multipliers_accuracy``: how much the multipliers change across the final bracket plus
    the error of the monodromy matrices.  A turning point without it is no fold (a corner
    of the branch that the event sequence does not show, or an orbit the integration cannot
    resolve), and None is returned.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    a, b : Solution
        Corrected points on either side of the sign change.
    index : int
        The index of ``a`` on the branch.
    kind : SpecialPointKind
        The kind looked for.
    test : callable
        The test function of a :class:`Solution`.

    Returns
    -------
    SpecialPoint or None
        The located point, or None (see above).

    Raises
    ------
    SaltationError
        If the multipliers jump across the final bracket (a non-smooth point the event sequence does not
        show) and the one-sided monodromies needed to classify it are missing.

    References
    ----------
    Dowell and Jarratt (1971), "A modified regula falsi method for computing the root of an
    equation", BIT 11 (the Illinois method).  Govaerts (2000), *Numerical Methods for Bifurcations
    of Dynamical Equilibria*, SIAM (test functions).
    """
    lo, hi = illinois_on_secant(lambda sigma: ctx.on_secant(a, b, sigma), test, a, b, tol=ctx.tol,
                                distance=lambda p, q: float(np.linalg.norm(q.z - p.z)))
    best = lo if abs(test(lo)) <= abs(test(hi)) else hi
    bracket = (min(lo.lam, hi.lam), max(lo.lam, hi.lam))
    multipliers_accuracy = float("nan")
    target = _CRITICAL_MULTIPLIER.get((kind, ctx.equilibrium))
    if target is not None or kind is SpecialPointKind.NEIMARK_SACKER:
        def off(s: Solution) -> float:  # how far the orbit's multipliers are from the kind's condition
            mu = _nontrivial(s, ctx.autonomous)
            return abs(_nearest(mu, target) - target) if target is not None else _off_circle_pair(mu)
        mu_lo, mu_hi = _nontrivial(lo, ctx.autonomous), _nontrivial(hi, ctx.autonomous)
        # how much the multipliers change across the final bracket: the critical one's, or any (NS)
        change = (abs(_nearest(mu_lo, target) - _nearest(mu_hi, target)) if target is not None
                  else _multiplier_change(mu_lo, mu_hi))
        multipliers_accuracy = change + max(ctx.matrix_error(lo), ctx.matrix_error(hi))
        if not off(best) <= multipliers_accuracy:
            # the test changed sign without the multipliers meeting the condition: where they jump
            # across the final bracket, a non-smooth point that the event sequence does not show; else
            # no bifurcation (a corner of the branch the integration cannot resolve, a neutral saddle)
            if _jumps(lo, hi, ctx.autonomous, float(np.linalg.norm(hi.z - lo.z))):
                return hidden_corner(ctx, lo, hi, index)
            return None
    if kind is SpecialPointKind.FOLD and ctx.symmetry is not None:
        meets = meets_symmetric_orbits(ctx, best, index)
        if meets is not None:
            return meets
    if kind in (SpecialPointKind.FOLD, SpecialPointKind.BRANCH_POINT):
        doubling = _period_doubling_of_half(ctx, best, index)
        if doubling is not None:
            return doubling
    accuracy = float(np.linalg.norm(hi.z - lo.z))
    note = ""
    widen = _parameter_error(ctx, a, b, lo, hi, kind, target)
    if widen > 0.0:
        # the integration's error moves the multipliers, and with them the point: the bracket holds it
        bracket = (bracket[0] - widen, bracket[1] + widen)
        note = (f"bracket widened by {widen:.1e} on each side for the multipliers' integration error "
                f"({max(ctx.matrix_error(lo), ctx.matrix_error(hi)):.1e}) over their rate of change")
    return smooth_point(kind, best, bracket=bracket, accuracy=max(accuracy, bracket[1] - bracket[0]), index=index,
                        multipliers_accuracy=multipliers_accuracy, note=note)


def _period_doubling_of_half(ctx: DetectionContext, best: Solution, index: int) -> SpecialPoint | None:
    """The period doubling of the orbits of half the period, where a branch of orbits of twice their period
    meets them (its orbit's multiplier +1 is the square of their -1): the end of a period-doubled branch,
    which the fold and branch-point tests see as a turning point or a crossing, located poorly (the branch is
    a parabola there).  None where ``best``'s orbit does not close after half its period (to 1e-3 of its
    size: near the point the doubled orbits differ from the repeated ones like the square root of the
    distance), or no period doubling of the half-period orbits lies within 1e-4 of it.

    The point is located by brentq on ``prod(mu + 1)`` of the half-period orbits (Newton at each parameter).
    """
    prob = ctx.problem
    if ctx.equilibrium or not prob.single_shooting is not None:
        return None
    n = prob.system.n
    x0 = np.asarray(best.u[:n], dtype=float)
    if prob.autonomous:
        half = prob
        T_half = 0.5 * float(best.u[n])
    elif prob.periods % 2 == 0:
        half = ShootingProblem(prob.flow, prob.p, continuation_parameter=prob.lam_name, backward=prob.backward,
                               t0=prob.t0, tolerances=prob.tolerances, periods=prob.periods // 2, mode0=prob.mode0)
        T_half = half.period_of(half.pack(x0, None), best.lam)
    else:
        return None
    p = prob.parameters_at(best.lam)
    try:
        run = prob.flow.run(x0, prob.t0, prob.t0 + prob.sign * T_half, p, mode0=prob.mode0, tolerances=prob.tolerances)
    except SaltationError:
        return None
    scale = 1.0 + float(np.max(np.abs(x0)))
    if not float(np.max(np.abs(run.x1 - x0))) <= 1e-3 * scale:
        return None
    cache: dict[float, object] = {}

    def half_orbit(lam: float):
        if lam not in cache:
            guess = half.pack(x0, T_half if half.autonomous else None)
            cache[lam] = half.solve(guess, lam)
        return cache[lam]

    def flip(lam: float) -> float:
        orbit = half_orbit(lam)
        mu = np.asarray(orbit.multipliers, dtype=complex)
        if half.autonomous and mu.size:
            mu = np.delete(mu, int(np.argmin(np.where(np.isfinite(mu), np.abs(mu - 1.0), np.inf))))
        return _flip_test(mu)

    lam0 = best.lam
    try:
        for width in (1e-7, 1e-6, 1e-5, 1e-4):
            w = width * (1.0 + abs(lam0))
            lo_lam, hi_lam = lam0 - w, lam0 + w
            if _crosses(flip(lo_lam), flip(hi_lam)):
                break
        else:
            return None
        from scipy.optimize import brentq

        lam_pd = brentq(flip, lo_lam, hi_lam, xtol=ctx.tol * 1e-3, rtol=4 * np.finfo(float).eps)
        orbit = half_orbit(lam_pd)
    except (SaltationError, ValueError):
        return None
    step = abs(hi_lam - lo_lam)
    half_width = max(ctx.tol * 1e-3, 4 * np.finfo(float).eps * abs(lam_pd))
    bracket = (float(lam_pd - half_width), float(lam_pd + half_width))
    return period_doubling_of_half_point(
        orbit, lam_pd, bracket, amplitude=best.summary.amplitude, index=index,
        multipliers_accuracy=ctx.matrix_error(best),
        note=(f"the branch's orbits of period {2 * T_half:.10g} meet the repeated orbits of period {T_half:.10g} "
              f"here, whose multiplier passes -1 (its square is this branch's +1): located by brentq on the "
              f"half-period orbits within {step:.1e} of the turning point seen at {lam0:.10g}"),
    )


def _parameter_error(ctx: DetectionContext, a: Solution, b: Solution, lo: Solution, hi: Solution,
                     kind: SpecialPointKind, target: float | None) -> float:
    """How far the integration's error can move a multiplier crossing in the parameter: the multipliers'
    matrix error over the rate at which the critical multiplier's modulus crosses 1 across the step
    (0 for a fold, whose test is the tangent, and for equilibria)."""
    if (ctx.equilibrium or kind is SpecialPointKind.FOLD
            or (target is None and kind is not SpecialPointKind.NEIMARK_SACKER)):
        return 0.0

    def modulus(s: Solution) -> float:
        mu = _nontrivial(s, ctx.autonomous)
        if target is not None:
            return abs(_nearest(mu, target))
        fin = np.array(_finite(mu), dtype=complex)
        cplx = fin[np.abs(fin.imag) > 1e-10 * (1.0 + np.abs(fin))]
        return float(cplx[np.argmin(np.abs(np.abs(cplx) - 1.0))].__abs__()) if cplx.size else math.nan

    span = abs(b.lam - a.lam)
    slope = abs(modulus(b) - modulus(a)) / span if span > 0.0 else math.nan
    error = max(ctx.matrix_error(lo), ctx.matrix_error(hi))
    return float(error / slope) if slope > 0.0 and math.isfinite(slope) and math.isfinite(error) else 0.0


def _remembered(name: str, test: Callable[[Solution], float]) -> Callable[[Solution], float]:
    """``test``, evaluated once per solution (the value is kept in ``solution.tests``)."""

    def value(sol: Solution) -> float:
        if name not in sol.tests:
            sol.tests[name] = test(sol)
        return sol.tests[name]

    return value


#: The multiplier (eigenvalue, for equilibria) a smooth special point must have, by kind and
#: whether the branch is of equilibria.
_CRITICAL_MULTIPLIER = {
    (SpecialPointKind.FOLD, False): 1.0,
    (SpecialPointKind.BRANCH_POINT, False): 1.0,
    (SpecialPointKind.PERIOD_DOUBLING, False): -1.0,
    (SpecialPointKind.SYMMETRY_BREAKING, False): 1.0,
    (SpecialPointKind.FOLD, True): 0.0,
}


def _crosses(ga: float, gb: float) -> bool:
    """A test function changes sign from ``a`` to ``b`` (a zero at ``b`` counts, a zero at ``a`` or nan not)."""
    return (ga < 0.0 <= gb) or (ga > 0.0 >= gb)


def _flip_test(mu: np.ndarray) -> float:
    """``prod(mu + 1)`` over the finite multipliers (changes sign at period doubling)."""
    prod = 1.0 + 0.0j
    for m in _finite(mu):
        prod *= m + 1.0
    return prod.real


def _plus_one_test(mu: np.ndarray) -> float:
    """``prod(mu - 1)`` over the finite multipliers (changes sign where a real one passes +1)."""
    prod = 1.0 + 0.0j
    for m in _finite(mu):
        prod *= m - 1.0
    return prod.real


def _ns_test(mu: np.ndarray) -> float:
    """``prod_{i<j} (mu_i mu_j - 1)`` over the finite multipliers (the bialternate product's determinant,
    nan when there are fewer than two: never a crossing).

    It is continuous in the multipliers and changes sign where a product ``mu_i mu_j`` passes 1: a complex
    pair through the unit circle (Neimark-Sacker) or a real pair with product 1 (a neutral saddle, no
    bifurcation, which the location's check of the multipliers rejects).  Unlike ``|mu| - 1`` of the largest
    complex multiplier, it does not jump where a complex pair turns real.

    References
    ----------
    Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM, section 4.4.
    """
    fin = _finite(mu)
    if len(fin) < 2:
        return float("nan")
    prod = 1.0 + 0.0j
    for i in range(len(fin)):
        for j in range(i + 1, len(fin)):
            prod *= fin[i] * fin[j] - 1.0
    return prod.real


def _off_circle_pair(mu: np.ndarray) -> float:
    """How far the complex pair nearest the unit circle lies from it (inf when there is no complex pair)."""
    fin = np.array(_finite(mu), dtype=complex)
    cplx = fin[np.abs(fin.imag) > 1e-10 * (1.0 + np.abs(fin))]
    return float(np.min(np.abs(np.abs(cplx) - 1.0))) if cplx.size else math.inf


def _matched(ma: np.ndarray, mb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The finite multipliers of two nearby orbits, paired so that the total distance is least."""
    from scipy.optimize import linear_sum_assignment

    a = np.array(_finite(ma), dtype=complex)
    b = np.array(_finite(mb), dtype=complex)
    if not a.size or not b.size:
        return a[:0], b[:0]
    rows, cols = linear_sum_assignment(np.abs(a[:, None] - b[None, :]))
    return a[rows], b[cols]


def _multiplier_change(ma: np.ndarray, mb: np.ndarray) -> float:
    """The largest distance between paired multipliers of two nearby orbits."""
    a, b = _matched(ma, mb)
    return float(np.max(np.abs(a - b))) if a.size else 0.0


def _may_hide_a_pair(ma: np.ndarray, mb: np.ndarray) -> bool:
    """Whether some multiplier moves between two orbits by more than 0.05 and by more than half the sum of
    its two distances from the unit circle: far enough to have left the circle and come back (or passed
    it twice) between them, though it lies on the same side at both."""
    a, b = _matched(ma, mb)
    if not a.size:
        return False
    move = np.abs(a - b)
    room = np.abs(np.abs(a) - 1.0) + np.abs(np.abs(b) - 1.0)
    return bool(np.any((move > 0.05) & (move > 0.5 * room)))


def _jumps(lo: Solution, hi: Solution, autonomous: bool, width: float) -> bool:
    """Whether the multipliers of two orbits a location tolerance apart differ by more than a smooth (even a
    square-root) dependence on the branch allows: ``1e-3`` and ``100 sqrt(width)``."""
    change = _multiplier_change(_nontrivial(lo, autonomous), _nontrivial(hi, autonomous))
    return change > max(1e-3, 100.0 * math.sqrt(width))


def _hopf_test(sol: Solution) -> float:
    """Largest real part among complex eigenvalues of an equilibrium (nan when there is none)."""
    ev = np.asarray(sol.summary.multipliers, dtype=complex)
    cplx = ev[np.abs(ev.imag) > 1e-10]
    if cplx.size == 0:
        return float("nan")
    return float(np.max(cplx.real))
