"""Symmetric orbits: the half-period map and symmetry breaking.

For a model that declares a symmetry (:mod:`saltation.model.symmetry`), the symmetric orbits' multipliers
are split by the half-period map (:mod:`saltation.orbits.symmetry`): where a real half-period multiplier
passes -1 the point is a ``symmetry_breaking`` (the full multiplier passes +1, but the branch goes on),
located on the half-period map, where it is regular (:func:`locate_symmetry_breaking`); at corners the
set-valued half-period multipliers classify the point (:func:`symmetric_crossing`:
``discontinuous_symmetry_breaking`` through -1), and a branch that passes at a non-smooth point from
symmetric to asymmetric orbits records a ``discontinuous_symmetry_breaking`` too
(:func:`symmetry_breaking_corner`).

The functions take the detector's context (:class:`~saltation.special_points.context.DetectionContext`)
as ``ctx``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from saltation.branches.branch import SpecialPoint, SpecialPointKind
from saltation.branches.corrector import Solution
from saltation.errors import IntegrationError, SaltationError
from saltation.orbits.boundary import one_sided_limits
from saltation.orbits.classification import SetValuedCrossing
from saltation.orbits.floquet import multipliers_from_monodromy
from saltation.orbits.symmetry import (
    SymmetricMultipliers,
    half_period_trajectory,
    solve_symmetric_orbit,
    split_half_map,
    symmetry_breaking_test,
)
from saltation.special_points.context import DetectionContext, _complex_text, _nearest
from saltation.special_points.points import (
    _sides,
    symmetry_breaking_point,
    unlocated_symmetry_breaking,
)

__all__ = [
    "half_map",
    "locate_symmetry_breaking",
    "meets_symmetric_orbits",
    "symmetry_breaking_value",
    "symmetry_breaking_corner",
    "half_limits",
    "squares_agree",
    "symmetric_crossing",
]


def half_map(ctx: DetectionContext, sol: Solution) -> SymmetricMultipliers | None:
    """The half-period map of a solution's orbit and its split multipliers (kept on the solution).

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    sol : Solution
        A corrected branch point.

    Returns
    -------
    SymmetricMultipliers or None
        None without a declared symmetry or when the half shot fails.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the half-period map's Jacobian is not finite.
    """
    if ctx.symmetry is None:
        return None
    if "half_map" not in sol.tests:
        prob = ctx.problem
        n = prob.system.n
        try:
            traj = half_period_trajectory(
                prob.flow, sol.u[:n], prob.parameters_at(sol.lam), t0=prob.t0, period=prob.period_of(sol.u, sol.lam),
                backward=prob.backward, tolerances=prob.tolerances,
            )
        except IntegrationError:
            sol.tests["half_map"] = None
        else:
            # not checked against the monodromy: next to a corner the monodromy moves like the square root
            # of the distance to it, and the two shots' rounding differs by more than the check allows
            # (the model's equations were checked for the symmetry when it was built)
            sol.tests["half_map"] = split_half_map(ctx.symmetry, traj, sol.u[:n], backward=prob.backward)
    return sol.tests["half_map"]


def locate_symmetry_breaking(ctx: DetectionContext, a: Solution, b: Solution, index: int) -> SpecialPoint:
    """Locate a symmetry breaking between two symmetric orbits on the symmetric orbits themselves.

    On the whole period's map the point is singular (``DG^2 - I`` has a two-dimensional kernel there), and
    the corrector drifts off the symmetric orbits near it.  The symmetric orbit at each trial parameter is
    instead a regular fixed point of the half-period map
    (:func:`~saltation.orbits.symmetry.solve_symmetric_orbit`), and the parameter where its real
    half-period multiplier passes -1 is found by Brent's method between ``a`` and ``b``.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    a, b : Solution
        Symmetric branch points on either side.
    index : int
        The index of ``a`` on the branch.

    Returns
    -------
    SpecialPoint
        Of kind ``symmetry_breaking``, status ``located``, with the half-period multiplier in its note; where
        the location fails (the parameter does not bracket the point, a fold between ``a`` and ``b``, or the
        located orbit's half-period multiplier is not -1 within its accuracy), status ``failed`` with the
        bracket of the two branch points and the reason in its note.

    Raises
    ------
    SaltationError
        If the orbit at the located parameter cannot be evaluated.

    References
    ----------
    Brent (1973), *Algorithms for Minimization without Derivatives*, Prentice-Hall (the root finder).
    """
    prob = ctx.problem
    n = prob.system.n
    la, lb = a.lam, b.lam
    if la == lb:
        return None
    ta, tb = prob.period_of(a.u, la), prob.period_of(b.u, lb)
    found: dict[float, tuple] = {}

    def test(lam: float) -> float:
        w = (lam - la) / (lb - la)
        guess = (1.0 - w) * a.u[:n] + w * b.u[:n]
        x, T, half = solve_symmetric_orbit(
            prob.flow, guess, prob.parameters_at(lam), t0=prob.t0,
            period=(1.0 - w) * ta + w * tb if prob.autonomous else None, backward=prob.backward,
            tolerances=prob.tolerances,
        )
        found[lam] = (x, T, half)
        return symmetry_breaking_test(half.gamma)

    from scipy.optimize import brentq

    xtol = 1e-13 * max(1.0, abs(la))
    try:
        lam = float(brentq(test, la, lb, xtol=xtol, rtol=4 * np.finfo(float).eps))
        if lam not in found:
            test(lam)
    except (ValueError, SaltationError) as exc:
        return unlocated_symmetry_breaking(a, b, index, f"its location on the half-period map failed ({exc})")
    x, T, half = found[lam]
    u = prob.pack(x, T if prob.autonomous else None)
    summary = prob.describe(u, lam, prob.evaluate(u, lam, need_lam=False))
    gamma = _nearest(half.gamma, -1.0)
    accuracy = max(ctx.matrix_error(a), ctx.matrix_error(b))
    if not abs(gamma + 1.0) <= accuracy + 1e-9:
        return unlocated_symmetry_breaking(
            a, b, index, f"the located orbit's half-period multiplier nearest -1 is {_complex_text(gamma)}")
    return symmetry_breaking_point(
        summary, lam, xtol, index=index, multipliers_accuracy=accuracy,
        note=(f"symmetric orbit: its antisymmetric half-period multiplier is {_complex_text(gamma)} "
              f"(located on the half-period map)"),
    )


def meets_symmetric_orbits(ctx: DetectionContext, sol: Solution, index: int) -> SpecialPoint | None:
    """At a turning point of a branch of asymmetric orbits: the symmetry breaking where the branch meets the
    symmetric orbits (the pitchfork seen from its side branch, which turns back there as the mirror
    images of its orbits), located on the symmetric orbits.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    sol : Solution
        The located turning point.
    index : int
        The index of the branch point before it.

    Returns
    -------
    SpecialPoint or None
        Of kind ``symmetry_breaking``, status ``located``; None if the turning point is not one (or the
        symmetric orbits cannot be followed to it).

    Raises
    ------
    numpy.linalg.LinAlgError
        If a half-period map's Jacobian is not finite.
    """
    half = half_map(ctx, sol)
    if half is None or half.symmetric:
        return None
    prob = ctx.problem
    n = prob.system.n

    def symmetric_at(lam: float, guess: np.ndarray):
        return solve_symmetric_orbit(
            prob.flow, guess, prob.parameters_at(lam), t0=prob.t0,
            period=prob.period_of(sol.u, sol.lam) if prob.autonomous else None, backward=prob.backward,
            tolerances=prob.tolerances,
        )

    try:
        x, _, sym = symmetric_at(sol.lam, sol.u[:n])
        if float(np.linalg.norm(x - sol.u[:n])) > 1e-3 * (1.0 + float(np.linalg.norm(x))):
            return None  # another symmetric orbit, not the one this branch meets
        # the secant method on gamma + 1 along the symmetric orbits (regular there)
        lam0, g0 = sol.lam, float(np.real(_nearest(sym.gamma, -1.0))) + 1.0
        lam1 = sol.lam + 1e-6 * max(1.0, abs(sol.lam))
        for _ in range(12):
            x, _, sym = symmetric_at(lam1, x)
            g1 = float(np.real(_nearest(sym.gamma, -1.0))) + 1.0
            if g1 == g0 or abs(lam1 - lam0) <= 1e-14 * max(1.0, abs(lam1)):
                break
            lam0, lam1, g0 = lam1, lam1 - g1 * (lam1 - lam0) / (g1 - g0), g1
        x, _, sym = symmetric_at(lam1, x)
    except SaltationError:
        return None
    gamma = _nearest(sym.gamma, -1.0)
    accuracy = ctx.matrix_error(sol)
    if not (abs(gamma + 1.0) <= accuracy + 1e-9 and abs(lam1 - sol.lam) <= 1e-4 * max(1.0, abs(sol.lam))):
        return None
    u = prob.pack(x, None)
    if prob.autonomous:
        u = prob.pack(x, prob.period_of(sol.u, sol.lam))
    summary = prob.describe(u, lam1, prob.evaluate(u, lam1, need_lam=False))
    step = abs(lam1 - lam0)
    return symmetry_breaking_point(
        summary, lam1, step, index=index, multipliers_accuracy=accuracy,
        note=(f"the branch of asymmetric orbits meets the symmetric orbits here and turns back as the mirror "
              f"images of its orbits; the symmetric orbit's antisymmetric half-period multiplier is "
              f"{_complex_text(gamma)} (located on the half-period map)"),
    )


def symmetry_breaking_value(ctx: DetectionContext, sol: Solution) -> float:
    """The symmetry-breaking test function: ``prod(gamma + 1)`` of a symmetric orbit's half-period multipliers.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    sol : Solution
        A corrected branch point.

    Returns
    -------
    float
        nan for an asymmetric orbit or without a declared symmetry.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the half-period map's Jacobian is not finite.
    """
    half = half_map(ctx, sol)
    if half is None or not half.symmetric:
        return float("nan")
    return symmetry_breaking_test(half.gamma)


def symmetry_breaking_corner(ctx: DetectionContext, point: SpecialPoint, lo: Solution, hi: Solution) -> SpecialPoint:
    """``point`` as a discontinuous symmetry breaking where the branch passes there from symmetric to
    asymmetric orbits (how the full multipliers classified it is kept in the note).

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    point : SpecialPoint
        The non-smooth point, classified by its multipliers.
    lo, hi : Solution
        The branch points the change lies between (a step's ends: the bisection's ``lo`` and ``hi`` may
        both be symmetric, since at a grazing of a symmetric orbit the symmetric orbits with both mirror
        contacts and the asymmetric ones with one meet).

    Returns
    -------
    SpecialPoint
        ``point``, relabelled ``discontinuous_symmetry_breaking`` where the symmetry is lost.

    Raises
    ------
    numpy.linalg.LinAlgError
        If a half-period map's Jacobian is not finite.
    """
    broken = _symmetry_lost(ctx, lo, hi)
    if broken is None:
        return point
    was = f"; its full multipliers alone: {point.kind.value}"
    note = (point.note + "; " if point.note else "") + broken + was
    return replace(point, kind=SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING, note=note)


def _symmetry_lost(ctx: DetectionContext, lo: Solution, hi: Solution) -> str | None:
    """Where the orbits on one side of a non-smooth point are symmetric and those on the other side are
    not, a note saying so (the point is then a discontinuous symmetry breaking: asymmetric orbits, in
    mirror pairs, branch off the symmetric ones there); None otherwise."""
    h_lo, h_hi = half_map(ctx, lo), half_map(ctx, hi)
    if h_lo is None or h_hi is None or h_lo.symmetric == h_hi.symmetric:
        return None
    before, after = ("symmetric", "asymmetric") if h_lo.symmetric else ("asymmetric", "symmetric")
    return (f"the branch passes from {before} to {after} orbits here (symmetry error "
            f"{max(h_lo.symmetry_error, h_hi.symmetry_error):.2g}); the mirror images of the asymmetric "
            "orbits are a second branch through this point")


def half_limits(ctx: DetectionContext, lo: Solution, hi: Solution, *,
                exact: bool) -> tuple[np.ndarray, np.ndarray] | None:
    """The one-sided half-period maps ``(DG on lo's side, DG on hi's side)`` of a symmetric orbit at a
    non-smooth point.

    Parameters
    ----------
    ctx : DetectionContext
        The detector's context.
    lo, hi : Solution
        The bracketing solutions.
    exact : bool
        Whether the sides differ by zero-length segments: the limits are then exact
        (:func:`~saltation.orbits.boundary.one_sided_limits` of the half shots), else the maps of ``lo``
        and ``hi``.

    Returns
    -------
    tuple of ndarray or None
        None without a symmetry or when either side is not symmetric.

    Raises
    ------
    numpy.linalg.LinAlgError
        If a half-period map's Jacobian is not finite.
    """
    h_lo, h_hi = half_map(ctx, lo), half_map(ctx, hi)
    if h_lo is None or h_hi is None or not (h_lo.symmetric and h_hi.symmetric):
        return None
    if exact:
        prob = ctx.problem
        lo_fewer, without, with_, _, _ = _sides(lo, hi)
        p = prob.parameters_at(without.lam)
        n = prob.system.n
        try:
            shots = [
                half_period_trajectory(prob.flow, s.u[:n], prob.parameters_at(s.lam), t0=prob.t0,
                                       period=prob.period_of(s.u, s.lam), backward=prob.backward,
                                       tolerances=prob.tolerances)
                for s in (without, with_)
            ]
            lim = one_sided_limits(prob.flow, shots[0], shots[1], p, tolerances=prob.tolerances)
        except SaltationError:
            lim = None
        if lim is not None:
            g_wo, g_w = ctx.symmetry @ lim.monodromy_without, ctx.symmetry @ lim.monodromy_with
            return (g_wo, g_w) if lo_fewer else (g_w, g_wo)
    return h_lo.half_map, h_hi.half_map


def squares_agree(half: tuple[np.ndarray, np.ndarray], mu_lo: np.ndarray, mu_hi: np.ndarray, *,
                   backward: bool) -> bool:
    """Whether the one-sided half-period maps ``half`` have, on each side, as many eigenvalues whose squares
    lie outside the unit circle as the full one-sided multipliers ``mu_lo``, ``mu_hi`` (``M = G^2``).

    Magnitudes within 1e-6 of 1 (a trivial multiplier, a side at a fold) count either way.

    Parameters
    ----------
    half : tuple of ndarray
        The one-sided half-period maps (:func:`half_limits`).
    mu_lo, mu_hi : ndarray or None
        The full one-sided multipliers.
    backward : bool
        Whether the maps were computed in backward time.

    Returns
    -------
    bool

    Raises
    ------
    numpy.linalg.LinAlgError
        If a map is not finite.
    """
    for g, mu in zip(half, (mu_lo, mu_hi)):
        if mu is None:
            return False
        squares = np.abs(multipliers_from_monodromy(g, backward=backward)) ** 2
        full = np.abs(np.asarray(mu))
        if (np.sum(squares > 1.0 + 1e-6) > np.sum(full > 1.0 - 1e-6)
                or np.sum(full > 1.0 + 1e-6) > np.sum(squares > 1.0 - 1e-6)):
            return False
    return True


def symmetric_crossing(half: SetValuedCrossing) -> SetValuedCrossing:
    """The kind of a symmetric orbit's non-smooth point from how its set-valued *half-period* multiplier
    ``gamma`` crosses the unit circle: through +1 a discontinuous fold, through -1 a discontinuous
    symmetry breaking, through +-i (``gamma^2 = -1``) a discontinuous flip, elsewhere a discontinuous
    Neimark-Sacker.  ``point`` becomes the full multiplier ``gamma^2``; ``gamma`` is kept.

    Parameters
    ----------
    half : SetValuedCrossing
        :func:`classify_nonsmooth` of the one-sided half-period maps.

    Returns
    -------
    SetValuedCrossing
    """
    if half.point is None:
        return half
    gamma = complex(half.point)
    if abs(gamma.imag) <= 1e-6:
        kind = (SpecialPointKind.DISCONTINUOUS_FOLD if gamma.real > 0
                else SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING)
    elif abs(gamma.real) <= 1e-6:
        kind = SpecialPointKind.DISCONTINUOUS_FLIP
    else:
        kind = SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER
    return SetValuedCrossing(kind, half.q, gamma * gamma, gamma)
