"""Independent references for the test suite: closed forms and scipy, without saltation.

Nothing here imports saltation.  Every function returns its value together with
how well that value is known (a :class:`Value`, or records of them), so that a test
can state its tolerance as "the reference's accuracy plus what saltation promises".

1. ``vdp_friction``: ``x'' - eps (1 - x^2) x' + x + mu sgn(x') = 0``, ``eps = 0.5``.
   Two modes split by ``v = 0``: ``plus`` (``v > 0``, ``v' = eps (1 - x^2) v - x - mu``)
   and ``minus`` (``v' = eps (1 - x^2) v - x + mu``).

   *The section.*  On ``v = 0`` the two fields are ``v' = -x - mu`` (plus) and
   ``v' = -x + mu`` (minus).  For ``x > mu`` both are negative: every orbit crosses
   ``v = 0`` there downwards, transversally, from ``plus`` into ``minus``, and ``x``
   has a maximum (a turning point).  For ``|x| <= mu`` the fields point at each other:
   the sticking set, where Filippov's sliding motion has ``x' = v = 0`` (every point
   of it is a pseudo-equilibrium: the motion stops).  A periodic orbit turns somewhere
   (``x' = v`` changes sign), never in the sticking set (it would stop), so it crosses
   ``Sigma = {v = 0, x > mu}`` (or its mirror image ``x < -mu``; the model is symmetric
   under ``(x, v) -> (-x, -v)``, so it crosses both).  The return map ``P`` on
   ``Sigma``, parametrised by ``x = a``, is smooth where the orbit from ``(a, 0)``
   crosses ``v = 0`` upwards at ``x < -mu`` and comes back to ``Sigma``; an orbit that
   meets ``v = 0`` inside the sticking set stops and has no return.  Cycles are the
   fixed points of ``P``, the period the return time, and the nontrivial Floquet
   multiplier ``P'(a)`` (the section is transversal, and the multiplier does not depend
   on the section).

   *The derivative* ``P'`` comes from the variational equation with the jump at the
   upward crossing: ``Phi(t+) = S Phi(t-)``, ``S = I + (f_after - f_before) h_x /
   (h_x f_before)`` with ``h = v`` (no reset); at the return, the arrival time's change
   is projected out, ``P' = Phi_00 - f_0 Phi_10 / f_1`` (``f`` the arriving field; its
   ``f_0 = v`` is 0 there).  It is cross-checked by Liouville's formula:
   ``det M = exp(int div f dt) prod det S_i`` with ``div f = eps (1 - x^2)`` and
   ``det S = v'_after / v'_before = (|x_i| - mu) / (|x_i| + mu)`` at both turning points.

   *Accuracy.*  Everything is computed twice, with DOP853 at ``rtol = 1e-12,
   atol = 1e-14`` (the value) and at ``rtol = 1e-10, atol = 1e-12``; the difference
   bounds the error of the tighter run (the global error grows with the tolerance),
   and the variational/Liouville discrepancy is added for multipliers.

2. Piecewise-affine models in closed form (matrix exponentials, root finding):
   the relay oscillator with negative damping, Coulomb friction on fixed ground, and
   the forced bilinear oscillator (a switching surface that the orbit never reaches,
   one it crosses without effect, and one it crosses into a stiffer spring).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import expm, solve_continuous_lyapunov
from scipy.optimize import brentq, minimize_scalar

DBL_EPS = float(np.finfo(float).eps)


class Value(NamedTuple):
    """A reference value and a bound on its error."""

    value: float
    accuracy: float


def _value(tight: float, loose: float, *extra: float) -> Value:
    """``tight`` with the accuracy ``|tight - loose|`` (plus ``extra`` error terms and a rounding floor)."""
    return Value(float(tight), abs(tight - loose) + sum(abs(e) for e in extra) + 16 * DBL_EPS * max(1.0, abs(tight)))


# =========================================================================================
# 1. vdp_friction
# =========================================================================================

VDP_EPS = 0.5
TIGHT = (1e-12, 1e-14)
LOOSE = (1e-10, 1e-12)


class Stuck(ValueError):
    """The orbit meets ``v = 0`` inside the sticking set ``|x| <= mu`` and stops there: no return."""

    def __init__(self, x: float, mu: float):
        self.x = x
        super().__init__(f"the orbit stops at x = {x} in the sticking set |x| <= {mu}")


def vdp_field(x: float, v: float, mu: float, side: int) -> np.ndarray:
    """The field of mode ``plus`` (``side = +1``, ``v > 0``) or ``minus`` (``side = -1``)."""
    return np.array([v, VDP_EPS * (1.0 - x * x) * v - x - side * mu])


def _vdp_rhs(side: int, mu: float) -> Callable:
    """State, fundamental matrix, sensitivity to mu and ``int div f``: 9 components."""

    def rhs(t, y):
        x, v = y[0], y[1]
        a11 = VDP_EPS * (1.0 - x * x)
        a10 = -2.0 * VDP_EPS * x * v - 1.0
        out = np.empty(9)
        out[0] = v
        out[1] = a11 * v - x - side * mu
        # Phi' = A Phi, A = [[0, 1], [a10, a11]] (row-major Phi00, Phi01, Phi10, Phi11)
        out[2], out[3] = y[4], y[5]
        out[4] = a10 * y[2] + a11 * y[4]
        out[5] = a10 * y[3] + a11 * y[5]
        # s' = A s + df/dmu
        out[6] = y[7]
        out[7] = a10 * y[6] + a11 * y[7] - side
        out[8] = a11  # div f
        return out

    return rhs


def _v_rising(t, y):
    return y[1]


_v_rising.terminal, _v_rising.direction = True, 1.0


def _v_falling(t, y):
    return y[1]


_v_falling.terminal, _v_falling.direction = True, -1.0


class ReturnMap(NamedTuple):
    """One return to ``Sigma = {v = 0, x > mu}`` from ``(a, 0)``."""

    image: float  # P(a)
    derivative: float  # P'(a), variational equation
    derivative_mu: float  # dP/dmu
    period: float  # return time
    liouville: float  # exp(int div f) prod det S over the return (= P'(P^-1...) at a fixed point)
    crossing: float  # x at the upward crossing of v = 0


def vdp_return_map(a: float, mu: float, rtol: float = TIGHT[0], atol: float = TIGHT[1]) -> ReturnMap:
    """The return map on ``Sigma`` and its derivatives, by DOP853 with events.

    Raises
    ------
    Stuck
        If the orbit meets ``v = 0`` in the sticking set before it returns.
    """
    if not a > mu:
        raise Stuck(a, mu)
    y = np.zeros(9)
    y[0], y[2], y[5] = a, 1.0, 1.0
    period, dets, f_end = 0.0, 1.0, None
    crossing = math.nan
    for side, event in ((-1, _v_rising), (+1, _v_falling)):
        sol = solve_ivp(_vdp_rhs(side, mu), (0.0, 200.0), y, method="DOP853", rtol=rtol, atol=atol, events=event)
        if sol.status != 1:
            raise RuntimeError(f"no return to v = 0 from a = {a}, mu = {mu}: {sol.message}")
        y = sol.y_events[0][0].copy()
        y[1] = 0.0
        period += float(sol.t_events[0][0])
        x = float(y[0])
        if abs(x) <= mu:
            raise Stuck(x, mu)
        before, after = vdp_field(x, 0.0, mu, side), vdp_field(x, 0.0, mu, -side)
        dets *= after[1] / before[1]
        if side == -1:  # the upward crossing: jump of Phi and of the sensitivity (no reset, h = v)
            crossing = x
            S = np.eye(2) + np.outer(after - before, [0.0, 1.0]) / before[1]
            y[2:6] = (S @ y[2:6].reshape(2, 2)).ravel()
            y[6:8] = S @ y[6:8]
        else:
            f_end = before
    Phi, s = y[2:6].reshape(2, 2), y[6:8]
    return ReturnMap(
        image=float(y[0]),
        derivative=float(Phi[0, 0] - f_end[0] * Phi[1, 0] / f_end[1]),
        derivative_mu=float(s[0] - f_end[0] * s[1] / f_end[1]),
        period=period,
        liouville=float(math.exp(y[8]) * dets),
        crossing=crossing,
    )


class VdpCycle(NamedTuple):
    """A limit cycle of vdp_friction: its turning point ``(turning_point, 0)`` on ``Sigma``."""

    mu: float
    turning_point: Value
    period: Value
    multiplier: Value  # nontrivial; the other is 1
    crossing: Value  # the other turning point, (crossing, 0) with crossing < -mu


def _vdp_fixed_point(mu: float, a0: float, rtol: float, atol: float) -> tuple[float, ReturnMap]:
    """Newton on ``P(a) - a`` (with ``P'`` from the variational equation), to the map's own accuracy.

    ``P`` is computed by DOP853 at ``rtol``, so its value carries an error of some ``rtol`` that depends on the
    rounding of every step (the BLAS kernel, the CPU): Newton's steps settle at that level, not at the rounding
    of ``a``.  It stops once a step is below ``rtol |a|`` (quadratic convergence leaves the remaining error far
    below the map's own), and the tight-loose difference of :func:`_vdp_cycle` states the accuracy.
    """
    a = float(a0)
    for _ in range(40):
        m = vdp_return_map(a, mu, rtol, atol)
        step = (m.image - a) / (m.derivative - 1.0)
        a -= step
        if abs(step) <= max(rtol, 4 * DBL_EPS) * abs(a):
            return a, vdp_return_map(a, mu, rtol, atol)
    raise RuntimeError(f"no fixed point of the return map near {a0} at mu = {mu}")


def _vdp_cycle(mu: float, a0: float) -> VdpCycle:
    a, m = _vdp_fixed_point(mu, a0, *TIGHT)
    b, n = _vdp_fixed_point(mu, a, *LOOSE)
    return VdpCycle(
        mu=mu,
        turning_point=_value(a, b),
        period=_value(m.period, n.period),
        multiplier=_value(m.derivative, n.derivative, m.derivative - m.liouville),
        crossing=_value(m.crossing, n.crossing),
    )


@functools.cache
def vdp_cycles(mu: float, a_max: float = 3.0, n_grid: int = 60) -> tuple[VdpCycle, ...]:
    """Every limit cycle with a turning point in ``(mu, a_max]``, smallest first.

    Sign changes of ``P(a) - a`` on a grid (orbits that stop in the sticking set have
    no return and are skipped), each refined by Newton.  Beyond ``a = 3`` the return
    ``P(a)`` is below 2.1 (2.016, 1.734, 1.540 at mu = 0, 0.2, 0.3 for a = 3 .. 10: the
    Van der Pol relaxation pulls every large orbit in), so no cycle turns there.
    """
    grid = np.linspace(mu, a_max, n_grid + 1)[1:]
    gaps = []
    for a in grid:
        try:
            gaps.append((a, vdp_return_map(a, mu, *LOOSE).image - a))
        except Stuck:
            gaps.append((a, math.nan))
    cycles = []
    for (a1, g1), (a2, g2) in itertools.pairwise(gaps):
        if g1 * g2 < 0:  # nan compares False
            root_ = brentq(lambda a: vdp_return_map(a, mu, *LOOSE).image - a, a1, a2, xtol=1e-10)
            cycles.append(_vdp_cycle(mu, root_))
    return tuple(cycles)


@functools.cache
def vdp_stable_cycle(mu: float = 0.2) -> VdpCycle:
    """The stable (attracting) limit cycle.

    At mu = 0.2: turning point 1.6654024343419, period 6.4212732534186, multiplier
    0.1765050997573, each to about 1e-11.
    """
    stable = [c for c in vdp_cycles(mu) if abs(c.multiplier.value) < 1.0]
    if len(stable) != 1:
        raise RuntimeError(f"expected one stable cycle at mu = {mu}, found {len(stable)}")
    return stable[0]


@functools.cache
def vdp_unstable_cycle(mu: float = 0.2) -> VdpCycle:
    """The unstable limit cycle inside the stable one (it shrinks onto the origin as mu -> 0).

    At mu = 0.2: turning point 0.5645505767584, period 6.4819642560665, multiplier
    3.456378480520, each to about 4e-11.
    """
    if mu < 0.05:  # small cycles: start Newton from the scaled limit a = c mu
        return _vdp_cycle(mu, vdp_collapse_slope().value * mu)
    unstable = [c for c in vdp_cycles(mu) if abs(c.multiplier.value) > 1.0]
    if len(unstable) != 1:
        raise RuntimeError(f"expected one unstable cycle at mu = {mu}, found {len(unstable)}")
    return unstable[0]


class VdpFold(NamedTuple):
    """The fold of cycles: ``P(a) = a`` and ``P'(a) = 1``."""

    mu: Value
    turning_point: Value
    period: Value


def _vdp_fold(a0: float, mu0: float, rtol: float, atol: float) -> tuple[float, float, ReturnMap]:
    """Newton on ``(P(a, mu) - a, P_a(a, mu) - 1)``; the second row of the Jacobian by central differences.

    The Jacobian's error only slows convergence; the solution is as accurate as the
    residual.  And ``mu`` is insensitive to the error of ``P_a``: along the branch of
    cycles, ``mu`` is stationary at the fold, so an error ``d`` in the fold's ``a``
    moves the located ``mu`` by ``O(d^2)``.
    """
    a, mu = float(a0), float(mu0)
    h = 1e-5
    for _ in range(30):
        m = vdp_return_map(a, mu, rtol, atol)
        F = np.array([m.image - a, m.derivative - 1.0])
        da = (vdp_return_map(a + h, mu, rtol, atol).derivative - vdp_return_map(a - h, mu, rtol, atol).derivative) / (2 * h)
        dm = (vdp_return_map(a, mu + h, rtol, atol).derivative - vdp_return_map(a, mu - h, rtol, atol).derivative) / (2 * h)
        J = np.array([[m.derivative - 1.0, m.derivative_mu], [da, dm]])
        step = np.linalg.solve(J, -F)
        a, mu = a + step[0], mu + step[1]
        if abs(step[1]) <= 1e-14 and abs(step[0]) <= 1e-8:
            return a, mu, vdp_return_map(a, mu, rtol, atol)
    raise RuntimeError("the fold's Newton iteration did not converge")


@functools.cache
def vdp_fold() -> VdpFold:
    """The fold of cycles in mu, where the stable and the unstable cycle merge and vanish.

    mu = 0.29750294224990, turning point a = 1.16055761789, period 6.45864342934.  The
    augmented system is regular at the fold, so ``a`` is as well determined as ``mu``
    (it is the location *along a branch* that is only known to the square root).
    """
    a, mu, m = _vdp_fold(1.15, 0.297, *TIGHT)
    b, nu, n = _vdp_fold(a, mu, *LOOSE)
    return VdpFold(mu=_value(mu, nu), turning_point=_value(a, b), period=_value(m.period, n.period))


@functools.cache
def vdp_largest_gap(mu: float) -> Value:
    """``max_a (P(a) - a)`` over ``a in (mu, 10]``: negative means no cycle at this mu.

    A grid (spacing ~0.05 up to 3, then 4, 6, 10), the maximum refined by a bounded
    scalar search around the best grid point.  Orbits that stop in the sticking set
    have no return and count as no cycle.  (A spike narrower than the grid would be
    missed; ``P`` is smooth, ``|P'| < 5`` on the grid.  At mu = 0.3 the largest gap is
    -0.0106, at a = 1.16: the ghost of the fold.)
    """
    grid = list(np.linspace(mu, 3.0, 60)[1:]) + [4.0, 6.0, 10.0]
    best, best_a = -math.inf, math.nan
    for a in grid:
        try:
            g = vdp_return_map(a, mu, *LOOSE).image - a
        except Stuck:
            continue
        if g > best:
            best, best_a = g, a
    res = minimize_scalar(lambda a: -(vdp_return_map(a, mu, *TIGHT).image - a), bounds=(best_a - 0.06, best_a + 0.06),
                          method="bounded", options={"xatol": 1e-8})
    tight = -float(res.fun)
    loose = vdp_return_map(float(res.x), mu, *LOOSE).image - float(res.x)
    return _value(max(tight, best), loose)


def vdp_collapse_slope() -> Value:
    """The limit of (turning point of the unstable cycle) / mu as mu -> 0, in closed form.

    Scaling ``x = mu X`` turns the model into ``X'' - eps (1 - mu^2 X^2) X' + X +
    sgn(X') = 0``: as ``mu -> 0`` the relay oscillator with negative damping
    ``X'' - 2 z X' + X = -sgn(X')``, ``z = eps / 2`` (see :func:`relay_cycle`), whose
    symmetric cycle turns at ``(r + 1) / (r - 1)``, ``r = exp(pi z / sqrt(1 - z^2))``:
    2.5993507 for eps = 0.5 (averaging, which drops the friction's shift of the centre,
    gives ``4 / (pi eps) = 2.546``).  The correction is ``O(mu^2)`` (mu enters only as
    mu^2, and the relay cycle is hyperbolic, multiplier ``r^2``).  So the unstable cycle
    shrinks onto the origin like ``2.5993 mu`` and collapses at ``mu = 0`` exactly.
    """
    return Value(relay_cycle(VDP_EPS / 2, 1.0).turning_point, 16 * DBL_EPS * 3)


@functools.cache
def vdp_collapse_slope_numeric() -> tuple[Value, float]:
    """The same limit from scipy's unstable cycles at mu = 0.01, 0.02, 0.04, extrapolated in mu^2.

    Returns the extrapolated slope (its accuracy: the change of the Richardson
    extrapolation between the pairs (0.01, 0.02) and (0.02, 0.04), plus the
    references' own accuracies over mu) and the coefficient ``c2`` of
    ``a / mu = c + c2 mu^2 + O(mu^4)``.
    """
    mus = (0.01, 0.02, 0.04)
    cyc = [vdp_unstable_cycle(m) for m in mus]
    s = [c.turning_point.value / m for c, m in zip(cyc, mus)]
    err = max(c.turning_point.accuracy / m for c, m in zip(cyc, mus))
    fine = s[0] + (s[0] - s[1]) / 3.0
    coarse = s[1] + (s[1] - s[2]) / 3.0
    c2 = (s[1] - s[0]) / (mus[1] ** 2 - mus[0] ** 2)
    return Value(fine, abs(fine - coarse) + 2 * err), c2


@functools.cache
def vdp_orbit_end(mu: float, a0: float) -> tuple[float, int]:
    """Where the orbit from the turning point ``(a0, 0)`` stops in the sticking set, and after how many returns.

    (Beyond the fold every orbit ends there: at mu = 0.3 the one from (2, 0) stops at
    x = 0.2445 after 24 returns, slowed down near the fold's ghost at a = 1.16.)
    """
    a, returns = float(a0), 0
    while returns < 10_000:
        try:
            a = vdp_return_map(a, mu, *LOOSE).image
        except Stuck as stop:
            return stop.x, returns
        returns += 1
    raise RuntimeError(f"the orbit from {a0} at mu = {mu} does not stop")


def vdp_collapse_parameter() -> Value:
    """Where the unstable cycle collapses onto the origin: mu = 0 (see :func:`vdp_collapse_slope`), exactly."""
    return Value(0.0, 0.0)


def vdp_in_sticking_set(state, mu: float, atol: float = 1e-8) -> bool:
    """Whether ``state`` is a stationary point: ``v = 0``, ``|x| <= mu`` (the edges are equilibria of a mode)."""
    x, v = float(state[0]), float(state[1])
    return abs(v) <= atol and abs(x) <= mu + atol


# =========================================================================================
# 2. Piecewise-affine models in closed form
# =========================================================================================

# -- 2a. the relay oscillator with negative damping ----------------------------------------
#
# x'' - 2 z x' + x = -F sgn(x'), 0 < z < 1, F > 0; modes plus (v > 0) [v, 2 z v - x - F] and
# minus [v, 2 z v - x + F], split by v = 0, sticking set |x| <= F on v = 0 (as for vdp_friction).
# In minus, y = x - F obeys y'' - 2 z y' + y = 0: from (a, 0),
#     y = (a - F) e^{z t} (cos w t - (z / w) sin w t),  v = -(a - F) / w e^{z t} sin w t,  w = sqrt(1 - z^2),
# so v = 0 again at t = pi / w, at x = F - (a - F) r, r = e^{z pi / w}.  By the symmetry (x, v) -> (-x, -v)
# the half-cycle map of turning points is H(a) = r (a - F) - F: one fixed point a* = F (r + 1) / (r - 1)
# (every cycle is symmetric: a cycle and its mirror image both surround the sticking set, so they meet
# unless equal), period 2 pi / w, nontrivial multiplier H'(a*)^2 = r^2 > 1: unstable.
# Determinant rule: exp(int div f) = exp(2 z T) = r^4, det S = v'_after / v'_before = (a* - F) / (a* + F)
# = 1 / r at each turning point: r^4 / r^2 = r^2.

class RelayCycle(NamedTuple):
    """The relay oscillator's symmetric cycle: turning points ``(+-turning_point, 0)``."""

    turning_point: float
    period: float
    multiplier: float  # nontrivial (the other is 1)
    multiplier_det_rule: float  # exp(int div f) prod det S, the cross-check
    omega: float
    r: float


def relay_cycle(z: float, F: float) -> RelayCycle:
    """The symmetric limit cycle of ``x'' - 2 z x' + x = -F sgn(x')`` in closed form (unstable)."""
    w = math.sqrt(1.0 - z * z)
    r = math.exp(z * math.pi / w)
    a = F * (r + 1.0) / (r - 1.0)
    T = 2.0 * math.pi / w
    det_s = (a - F) / (a + F)
    return RelayCycle(turning_point=a, period=T, multiplier=r * r, multiplier_det_rule=math.exp(2 * z * T) * det_s**2,
                      omega=w, r=r)


def relay_matrices(z: float, F: float, side: int) -> tuple[np.ndarray, np.ndarray]:
    """``A``, ``b`` of mode ``plus`` (``side = +1``) or ``minus``: ``y' = A y + b``."""
    return np.array([[0.0, 1.0], [-1.0, 2.0 * z]]), np.array([0.0, -side * F])


def relay_half_cycle_by_expm(z: float, F: float, a: float) -> np.ndarray:
    """The state after half a period ``pi / w`` in mode minus from ``(a, 0)``, by the matrix exponential."""
    A, b = relay_matrices(z, F, -1)
    eq = -np.linalg.solve(A, b)
    return eq + expm(A * math.pi / math.sqrt(1.0 - z * z)) @ (np.array([a, 0.0]) - eq)


def relay_cycle_state(z: float, F: float, t: float) -> np.ndarray:
    """The state on the cycle ``t`` after the right turning point ``(a*, 0)`` (any ``t``, periodic)."""
    c = relay_cycle(z, F)
    t = math.fmod(t, c.period)
    t += c.period if t < 0 else 0.0
    sign = 1.0
    if t > c.period / 2:  # the upper half is the mirror image of the lower one
        t -= c.period / 2
        sign = -1.0
    k = (c.turning_point - F) * math.exp(z * t)
    y = k * (math.cos(c.omega * t) - z / c.omega * math.sin(c.omega * t))
    v = -k / c.omega * math.sin(c.omega * t)
    return sign * np.array([F + y, v])


def relay_distance_to_cycle(z: float, F: float, state) -> float:
    """Distance from ``state`` to the point of the cycle at the same polar angle (an upper bound of the distance).

    The lower half (``v <= 0``) in ``y = x - F``: ``y - z v = R cos(theta)``,
    ``-w v = R sin(theta)`` with ``R = (a* - F) e^{z theta / w}`` on the cycle,
    ``theta = w t`` in ``[0, pi]``; the upper half by the symmetry.
    """
    c = relay_cycle(z, F)
    x, v = float(state[0]), float(state[1])
    if v > 0 or (v == 0 and x < 0):
        x, v = -x, -v
    y = x - F
    theta = math.atan2(-c.omega * v, y - z * v)
    theta = min(max(theta, 0.0), math.pi)
    t = theta / c.omega
    return float(np.linalg.norm(relay_cycle_state(z, F, t) - np.array([x, v])))


def relay_stationary(state, F: float, atol: float = 1e-8) -> bool:
    """Whether ``state`` is stationary: in the sticking set ``|x| <= F`` on ``v = 0`` (for relay and Coulomb)."""
    return abs(float(state[1])) <= atol and abs(float(state[0])) <= F + atol


# -- 2b. Coulomb friction on fixed ground ---------------------------------------------------
#
# x'' + x = -F sgn(x'): the energy (x^2 + v^2) / 2 decreases at the rate F |v|, so there is no
# periodic orbit; every orbit ends in the sticking set |x| <= F on v = 0 (each of its points a
# pseudo-equilibrium; (+-F, 0) are the equilibria of the modes).  In plus (v > 0) the orbit is a
# circle about (-F, 0), in minus about (F, 0); from a turning point (a, 0), |a| > F, the next
# turning point is (-(|a| - 2F) sgn(a), 0).

def coulomb_sticking_set(F: float) -> tuple[float, float]:
    """The interval of ``x`` on ``v = 0`` where the motion of ``x'' + x = -F sgn(x')`` stops: ``[-F, F]``."""
    return (-F, F)


def coulomb_next_turning_point(F: float, a: float) -> float:
    """The turning point after ``(a, 0)``, ``|a| > F``: half a circle about ``(F sgn(a), 0)``, time pi."""
    return -(abs(a) - 2.0 * F) * math.copysign(1.0, a)


# -- 2c. the forced bilinear oscillator -----------------------------------------------------
#
# x'' + 2 z x' + x + k2 max(x - d, 0) = a cos(w t): modes left (x < d) and right (x > d), each affine,
# y' = A y + b + c cos(w t).  The field is continuous at x = d (only its Jacobian jumps), so every
# saltation matrix is the identity and the monodromy is the product of the modes' matrix exponentials.
# Per mode the flow is y(t) = y_p(t) + E(t - s) (y(s) - y_p(s)) with y_p(t) = -A^-1 b + Re(Y e^{i w t}),
# Y = (i w I - A)^-1 c, and, A having the eigenvalues -z +- i om (om^2 = k - z^2 > 0 for the stiffness
# k of the mode), E(tau) = expm(A tau) = e^{-z tau} (cos(om tau) I + sin(om tau) / om (A + z I)).
# A periodic orbit: a fixed point of the period map, followed event by event in closed form (the
# crossings of x = d located by a scan and brentq on the closed-form x(t)), by Newton with the
# closed-form monodromy.  With k2 = 0 the surface changes nothing (the orbit is the linear one); with
# d beyond the orbit's reach it is never reached (multipliers: eig(expm(A T))).
#
# Uniqueness: the difference e of two solutions obeys e'' + 2 z e' + k(t) e = 0 with k(t) in
# [1, 1 + k2] (the restoring force is monotone and piecewise linear).  V = e'^2 + 2 z e e' + g e^2,
# g = 1 + k2 / 2 + 2 z^2, has dV/dt = -2 z e'^2 - 2 z k e^2 + 2 (g - k - 2 z^2) e e' < 0 whenever
# (k2 / 2)^2 < 4 z^2 k, i.e. for k2 < 4 z: every difference decays, so there is one periodic orbit and
# it attracts every solution (:func:`bilinear_unique` checks it, :func:`common_lyapunov` numerically).

class AffineMode(NamedTuple):
    """``y' = A y + b + c cos(w t)`` with ``A = [[0, 1], [-k, -2 z]]``."""

    A: np.ndarray
    b: np.ndarray
    c: np.ndarray  # coefficient of cos(w t)
    w: float

    def _Y(self) -> np.ndarray:
        return np.linalg.solve(1j * self.w * np.eye(2) - self.A, self.c.astype(complex))

    def particular(self, t) -> np.ndarray:
        """``y_p(t)``, shape (2,) or (2, m) for an array of times."""
        t = np.asarray(t, float)
        eq = -np.linalg.solve(self.A, self.b)
        return eq.reshape((2,) + (1,) * t.ndim) + np.real(np.multiply.outer(self._Y(), np.exp(1j * self.w * t)))

    def field(self, t: float, y) -> np.ndarray:
        return self.A @ np.asarray(y, float) + self.b + self.c * math.cos(self.w * t)

    def exp(self, tau) -> np.ndarray:
        """``expm(A tau)`` in closed form, shape (2, 2) or (2, 2, m)."""
        tau = np.asarray(tau, float)
        z = -0.5 * self.A[1, 1]
        om = math.sqrt(-self.A[1, 0] - z * z)
        e, co, si = np.exp(-z * tau), np.cos(om * tau), np.sin(om * tau) / om
        I, B = np.eye(2), self.A + z * np.eye(2)
        return e * (np.multiply.outer(I, co) + np.multiply.outer(B, si))

    def flow(self, s: float, y, t) -> np.ndarray:
        """The state at time(s) ``t`` from ``y`` at ``s``, shape (2,) or (2, m)."""
        t = np.asarray(t, float)
        E = self.exp(t - s)
        d0 = np.asarray(y, float) - self.particular(s)
        return self.particular(t) + np.einsum("ij...,j->i...", E, d0)


def bilinear_modes(z: float, a: float, w: float, k2: float, d: float) -> tuple[AffineMode, AffineMode]:
    """``left`` (x < d) and ``right`` (x > d) modes of the forced bilinear oscillator."""
    c = np.array([0.0, a])
    left = AffineMode(np.array([[0.0, 1.0], [-1.0, -2.0 * z]]), np.zeros(2), c, w)
    right = AffineMode(np.array([[0.0, 1.0], [-(1.0 + k2), -2.0 * z]]), np.array([0.0, k2 * d]), c, w)
    return left, right


def bilinear_unique(z: float, k2: float) -> bool:
    """Whether the quadratic form of the comment above proves one attracting periodic orbit: ``k2 < 4 z``."""
    return 0 <= k2 < 4.0 * z


def common_lyapunov(matrices) -> np.ndarray | None:
    """A ``P > 0`` with ``A^T P + P A < 0`` for every ``A`` given, or None if this simple search finds none.

    Tries the Lyapunov solutions of the average and of each matrix.
    """
    mats = [np.asarray(m, float) for m in matrices]
    for cand in [sum(mats) / len(mats)] + mats:
        P = solve_continuous_lyapunov(cand.T, -np.eye(len(cand)))
        P = 0.5 * (P + P.T)
        if np.all(np.linalg.eigvalsh(P) > 0) and all(np.all(np.linalg.eigvalsh(m.T @ P + P @ m) < 0) for m in mats):
            return P
    return None


class ForcedOrbit(NamedTuple):
    """A periodic orbit of a forced piecewise-affine model, in closed form."""

    period: float
    state0: np.ndarray  # at t = 0
    crossings: tuple[tuple[float, int], ...]  # (time in [0, T), +1 up / -1 down) of x = d over one period
    multipliers: np.ndarray  # sorted by magnitude, largest first, then by imaginary part
    modes: tuple[AffineMode, AffineMode]
    d: float

    @property
    def kind(self) -> str:
        """``"crossing"``, or the single mode of an orbit that never reaches ``x = d``."""
        if self.crossings:
            return "crossing"
        return "right" if self.state0[0] > self.d else "left"

    def mode_at(self, t: float) -> AffineMode:
        """The mode the orbit is in at time ``t`` (after a crossing at ``t``, the new one)."""
        left, right = self.modes
        if not self.crossings:
            return right if self.state0[0] > self.d else left
        tm = t % self.period
        last = [c for c in self.crossings if c[0] <= tm]
        direction = (last[-1] if last else self.crossings[-1])[1]
        return right if direction > 0 else left

    def state(self, t: float) -> np.ndarray:
        """The state at any time (periodic), in closed form."""
        T = self.period
        tm = t % T
        y, s = self.state0, 0.0
        for tc, _ in self.crossings:
            if tc > tm:
                break
            y, s = self.mode_at(0.5 * (s + tc)).flow(s, y, tc), tc
        return self.mode_at(0.5 * (s + tm) if tm > s else s).flow(s, y, tm)

    def velocity(self, t: float) -> np.ndarray:
        return self.mode_at(t).field(t, self.state(t))

    def transition(self, t: float) -> np.ndarray:
        """The fundamental matrix ``Phi(t, 0)`` for ``t`` in ``[0, T)``: the modes' exponentials (saltation I)."""
        times = [0.0] + [c[0] for c in self.crossings if c[0] < t] + [t]
        Phi = np.eye(2)
        for s, u in itertools.pairwise(times):
            Phi = self.mode_at(0.5 * (s + u)).exp(u - s) @ Phi
        return Phi

    def monodromy(self, t0: float) -> np.ndarray:
        """The monodromy over ``[t0, t0 + T]``: ``Phi(t0, 0) M(0) Phi(t0, 0)^-1`` by periodicity."""
        t0 = t0 % self.period
        M0 = self.transition(self.period)
        Phi = self.transition(t0)
        return Phi @ M0 @ np.linalg.inv(Phi)

    def turning_times(self) -> list[float]:
        """The times in ``[0, T)`` where ``v = 0`` (turning points), by a scan and brentq on the closed form."""
        ts = np.linspace(0.0, self.period, 721)
        vs = [self.state(t)[1] for t in ts]
        return [brentq(lambda t: self.state(t)[1], ts[k], ts[k + 1], xtol=1e-15)
                for k in range(len(ts) - 1) if vs[k] * vs[k + 1] < 0]


def sorted_multipliers(mults) -> np.ndarray:
    """Multipliers by decreasing magnitude, then decreasing imaginary part."""
    mults = np.asarray(mults, complex)
    return mults[np.lexsort((-mults.imag, -np.abs(mults)))]


class Grazing(ValueError):
    """A crossing within rounding of the start of a segment: a tangency, where the reference says nothing."""


#: a crossing function whose maximum between two scan points comes within this of 0 (relative) is a
#: tangency: the reference does not decide whether the orbit touches the surface
GRAZE = 1e-9


def _first_crossing(g: Callable, s: float, t_end: float, n: int, immediate: bool = False) -> float | None:
    """The first ``t`` in ``(s, t_end]`` where the vectorised ``g`` changes sign from ``<= 0`` to ``> 0``.

    A scan on ``n`` points; between them, every local maximum of the scan is refined
    (bounded scalar search), so that a short excursion above 0 between two scan points
    is not missed; the crossing itself by brentq.  ``g(s)`` is 0 or negative (a segment
    starts on its surface, leaving it).  If ``g`` is positive already within ``1e-12``
    of ``s``: ``s`` itself with ``immediate`` (a state that leaves at once), else
    :class:`Grazing`.

    Raises
    ------
    Grazing
        Also where a maximum of ``g`` comes within :data:`GRAZE` of 0 without crossing.
    """
    ts = np.linspace(s, t_end, max(3, n))
    vals = np.asarray(g(ts), float)
    scale = 1.0 + float(np.max(np.abs(vals)))
    f = lambda t: float(g(t))
    for k in range(len(ts) - 1):
        if vals[k] <= 0 < vals[k + 1]:
            lo = ts[k]
            if k == 0:
                lo = s + 1e-12 * max(1.0, abs(s))
                if f(lo) > 0:
                    if immediate:
                        return s
                    raise Grazing(f"a crossing within rounding of t = {s}")
            return brentq(f, lo, ts[k + 1], xtol=1e-15, rtol=4 * DBL_EPS)
        if 0 < k and vals[k - 1] <= vals[k] >= vals[k + 1] and vals[k] <= 0:  # a maximum below 0 on the scan
            res = minimize_scalar(lambda t: -f(t), bounds=(ts[k - 1], ts[k + 1]), method="bounded",
                                  options={"xatol": 1e-13 * max(1.0, abs(ts[k]))})
            peak = -float(res.fun)
            if k + 1 == len(ts) - 1 and float(res.x) >= t_end - 1e-9 * (t_end - s):
                continue  # rising to the surface at the very end: a crossing at t_end, the next segment's business
            if abs(peak) <= GRAZE * scale:
                raise Grazing(f"a tangency near t = {float(res.x)} ({peak:.1e} from the surface)")
            if peak > 0:
                return brentq(f, ts[k - 1] if vals[k - 1] <= 0 else ts[k], float(res.x), xtol=1e-15, rtol=4 * DBL_EPS)
    return None


def _period_map(modes, d: float, y0, T: float, n_scan: int = 400):
    """``y(T)`` from ``y(0) = y0``, the crossings of ``x = d`` and the monodromy, event by event in closed form."""
    left, right = modes
    y, s = np.asarray(y0, float), 0.0
    mode = right if y[0] > d or (y[0] == d and y[1] > 0) else left
    M = np.eye(2)
    crossings = []
    while True:
        direction = -1.0 if mode is right else 1.0  # the crossing that leaves the mode
        tc = _first_crossing(lambda t, m=mode, s=s, y=y, c=direction: c * (m.flow(s, y, t)[0] - d), s, T,
                             int(n_scan * (T - s) / T) + 2)
        if tc is None:
            M = mode.exp(T - s) @ M
            return mode.flow(s, y, T), tuple(crossings), M
        y = mode.flow(s, y, tc)
        y[0] = d
        M = mode.exp(tc - s) @ M  # saltation matrix I: the field is continuous at x = d
        crossings.append((tc, int(direction)))
        mode = left if mode is right else right
        s = tc


def bilinear_orbit(z: float, a: float, w: float, k2: float, d: float) -> ForcedOrbit | None:
    """The period-``2 pi / w`` orbit of the forced bilinear oscillator (None if Newton does not settle).

    Newton on the closed-form period map from the linear orbit's state at ``t = 0``
    (a few plain iterations first: the orbit attracts).  Within ``k2 < 4 z`` it is the
    only periodic orbit (see above).
    """
    try:
        return _bilinear_orbit(z, a, w, k2, d)
    except Grazing:
        return None


def _bilinear_orbit(z: float, a: float, w: float, k2: float, d: float) -> ForcedOrbit | None:
    T = 2.0 * math.pi / w
    modes = bilinear_modes(z, a, w, k2, d)
    y = modes[0].particular(0.0)
    for _ in range(3):
        y = _period_map(modes, d, y, T)[0]
    previous = math.inf
    for _ in range(30):
        y1, crossings, M = _period_map(modes, d, y, T)
        step = np.linalg.solve(M - np.eye(2), -(y1 - y))
        y = y + step
        size, scale = float(np.linalg.norm(step)), 1.0 + float(np.linalg.norm(y))
        # converged at rounding, or at the map's rounding floor (a step that no longer halves: the crossing
        # instants' brentq and the exponentials round differently on each CPU); the residual is checked below
        if size <= 4 * DBL_EPS * scale or (size > 0.5 * previous and size <= 1e-13 * scale):
            break
        previous = size
    else:
        return None
    y1, crossings, M = _period_map(modes, d, y, T)
    if np.linalg.norm(y1 - y) > 1e-13 * (1.0 + np.linalg.norm(y)):
        return None
    # no crossing missed by the scan: a ten times finer one finds the same
    fine = _period_map(modes, d, y, T, n_scan=4000)[1]
    if len(fine) != len(crossings) or any(abs(f[0] - c[0]) > 1e-9 * T or f[1] != c[1] for f, c in zip(fine, crossings)):
        return None
    return ForcedOrbit(T, y, crossings, sorted_multipliers(np.linalg.eigvals(M)), modes, d)


def bilinear_monodromy_by_expm(orbit: ForcedOrbit) -> np.ndarray:
    """The orbit's monodromy from ``t = 0`` with scipy's ``expm`` (the cross-check of the closed-form ``E``)."""
    times = [0.0] + [c[0] for c in orbit.crossings] + [orbit.period]
    M = np.eye(2)
    for s, t in itertools.pairwise(times):
        M = expm(orbit.mode_at(0.5 * (s + t)).A * (t - s)) @ M
    return M


# -- 2d. the forced relay: Coulomb friction on fixed ground, forced -------------------------
#
# x'' + 2 z x' + x = a cos(w t) - F sgn(x'), z >= 0, 0 < F < a: modes plus (v > 0) and minus (v < 0),
# each affine, split by v = 0.  On v = 0 the fields are v' = -x + a cos(w t) -+ F.  The orbit crosses
# v = 0 where both have the same sign, and sticks where |x - a cos(w t)| < F (Filippov's sliding
# motion: x' = v = 0, v' = 0), until a cos(w t) reaches x + F (it leaves into plus) or x - F (into
# minus).  Saltation matrices (h = v, no reset): a crossing S = I + (f_after - f_before) e_v^T /
# v'_before = diag(1, v'_after / v'_before); entering the stick, with the sliding field 0,
# S = I - f_before e_v^T / v'_before = diag(1, 0); leaving it S = I (the leaving field vanishes
# there, so the instant of leaving does not move the state to first order).  With F < a the state
# cannot stay stuck for a whole period (a cos(w t) sweeps [-a, a], wider than 2F).  The period map is
# followed event by event in closed form; a returned orbit is checked by it from its own state (no
# uniqueness needed), and an orbit of the reference is found by a transient and Newton.

#: how near the edge of the sticking set a crossing may be for the reference to tell crossing from sticking
#: (the states it checks are known to Newton's tolerance, some 1e-9 .. 1e-8)
KNIFE_EDGE = 1e-6


def forced_relay_modes(z: float, a: float, w: float, F: float) -> tuple[AffineMode, AffineMode]:
    """``plus`` (v > 0) and ``minus`` (v < 0)."""
    A, c = np.array([[0.0, 1.0], [-1.0, -2.0 * z]]), np.array([0.0, a])
    return AffineMode(A, np.array([0.0, -F]), c, w), AffineMode(A, np.array([0.0, F]), c, w)


class RelayEvent(NamedTuple):
    t: float
    kind: str  # "cross_down", "cross_up", "stick", "leave_plus", "leave_minus"
    x: float


def forced_relay_period_map(z: float, a: float, w: float, F: float, y0, t0: float, t1: float, n_scan: int = 400):
    """``(y(t1), events, Phi(t1, t0))`` from ``y(t0) = y0``, event by event in closed form.

    A state stuck at the instant a field turns to leave leaves at once.

    Raises
    ------
    Grazing
        Where an event falls within rounding of the previous one (a tangency), or the orbit
        meets ``v = 0`` within :data:`KNIFE_EDGE` of the sticking set's edge.
    """
    plus, minus = forced_relay_modes(z, a, w, F)
    y, s = np.array(y0, float), float(t0)
    n = lambda t_end: int(n_scan * (t_end - s) / (2 * math.pi / w)) + 3
    fplus = lambda t, x: -x - F + a * np.cos(w * t)
    fminus = lambda t, x: -x + F + a * np.cos(w * t)
    if y[1] > 0 or (y[1] == 0 and fplus(s, y[0]) > 0):
        mode = "plus"
    elif y[1] < 0 or fminus(s, y[0]) < 0:
        mode = "minus"
    else:
        mode = "stick"
    Phi, events = np.eye(2), []
    while True:
        if mode == "stick":
            xs = y[0]
            t_p = _first_crossing(lambda t, xs=xs: fplus(t, xs), s, t1, n(t1), immediate=True)
            t_m = _first_crossing(lambda t, xs=xs: -fminus(t, xs), s, t1, n(t1), immediate=True)
            if t_p is None and t_m is None:
                return np.array([xs, 0.0]), tuple(events), Phi
            into_plus = t_m is None or (t_p is not None and t_p < t_m)
            s = t_p if into_plus else t_m
            mode = "plus" if into_plus else "minus"
            events.append(RelayEvent(s, "leave_" + mode, xs))
            continue
        m = plus if mode == "plus" else minus
        sign = -1.0 if mode == "plus" else 1.0  # v leaves plus downwards, minus upwards
        tc = _first_crossing(lambda t, m=m, s=s, y=y, c=sign: c * m.flow(s, y, t)[1], s, t1, n(t1))
        if tc is None:
            return m.flow(s, y, t1), tuple(events), m.exp(t1 - s) @ Phi
        Phi = m.exp(tc - s) @ Phi
        x = float(m.flow(s, y, tc)[0])
        before, other = (fplus(tc, x), fminus(tc, x)) if mode == "plus" else (fminus(tc, x), fplus(tc, x))
        if abs(other) <= KNIFE_EDGE * (1.0 + abs(x) + a + F):
            raise Grazing(f"at t = {tc} the orbit meets v = 0 within {KNIFE_EDGE:g} of the sticking set's edge")
        if other * sign > 0:  # the other field carries on across: a crossing
            Phi = np.diag([1.0, other / before]) @ Phi
            events.append(RelayEvent(tc, "cross_down" if mode == "plus" else "cross_up", x))
            mode = "minus" if mode == "plus" else "plus"
        else:  # it pushes back: stick
            Phi = np.diag([1.0, 0.0]) @ Phi
            events.append(RelayEvent(tc, "stick", x))
            mode = "stick"
        y, s = np.array([x, 0.0]), tc


class ForcedRelayOrbit(NamedTuple):
    """A periodic orbit of the forced relay (period ``2 pi / w``), its state at ``t = 0``."""

    z: float
    a: float
    w: float
    F: float
    state0: np.ndarray
    events: tuple[RelayEvent, ...]
    multipliers: np.ndarray

    @property
    def period(self) -> float:
        return 2.0 * math.pi / self.w

    def state(self, t: float) -> np.ndarray:
        """The state at time ``t`` (periodic)."""
        return forced_relay_period_map(self.z, self.a, self.w, self.F, self.state0, 0.0, t % self.period)[0]

    def monodromy(self, t0: float) -> np.ndarray:
        return forced_relay_check(self.z, self.a, self.w, self.F, self.state(t0), t0)[2]


def forced_relay_check(z: float, a: float, w: float, F: float, y0, t0: float):
    """The closed-form period map from ``(t0, y0)``: ``(closure y(t0 + T) - y0, events, monodromy)``.

    The closure is taken from ``t0`` itself.  The events and the monodromy are those of
    the period from the middle of the longest stretch between events: a start on the
    surface at the instant of a crossing would leave it undecided whether that crossing
    belongs to the period's start or to its end (the multipliers do not depend on the
    base point; the event count is the cycle's).
    """
    T = 2.0 * math.pi / w
    y1, events, M = forced_relay_period_map(z, a, w, F, y0, t0, t0 + T)
    closure = y1 - np.asarray(y0, float)
    if not events:
        return closure, events, M
    bounds = [t0] + [e.t for e in events] + [t0 + T]
    gaps = [(u - s, 0.5 * (s + u)) for s, u in itertools.pairwise(bounds)]
    t_mid = max(gaps)[1]
    y_mid = forced_relay_period_map(z, a, w, F, y0, t0, t_mid)[0]
    _, events_mid, M_mid = forced_relay_period_map(z, a, w, F, y_mid, t_mid, t_mid + T)
    return closure, events_mid, M_mid


@functools.lru_cache(maxsize=4096)
def forced_relay_orbit(z: float, a: float, w: float, F: float) -> ForcedRelayOrbit | None:
    """The period-1 orbit reached from rest by a transient (60 periods), polished by Newton; None if there is none.

    None also where the reference meets a tangency (:class:`Grazing`) or the transient
    settles on no period-1 orbit.
    """
    T = 2.0 * math.pi / w
    try:
        y = np.zeros(2)
        for _ in range(60):
            y = forced_relay_period_map(z, a, w, F, y, 0.0, T)[0]
        for _ in range(30):
            y1, _, M = forced_relay_period_map(z, a, w, F, y, 0.0, T)
            step = np.linalg.solve(M - np.eye(2), -(y1 - y))
            y = y + step
            if np.linalg.norm(step) <= 8 * DBL_EPS * (1.0 + np.linalg.norm(y)):
                break
        else:
            return None
        closure, events, M = forced_relay_check(z, a, w, F, y, 0.0)
    except (Grazing, np.linalg.LinAlgError):
        return None
    if np.linalg.norm(closure) > 1e-12 * (1.0 + np.linalg.norm(y)):
        return None
    return ForcedRelayOrbit(z, a, w, F, y, events, sorted_multipliers(np.linalg.eigvals(M)))


def reduced_time(t0: float, w: float, digits: int = 40) -> float:
    """``t0 mod (2 pi / w)`` for the doubles ``t0`` and ``w``, in exact arithmetic (mpmath), rounded once."""
    import mpmath

    with mpmath.workdps(digits):
        T = 2 * mpmath.pi / mpmath.mpf(w)
        return float(mpmath.mpf(t0) - mpmath.floor(mpmath.mpf(t0) / T) * T)


def orbit_time_of(orbit: ForcedOrbit, state, t_guess: float, iterations: int = 8) -> tuple[float, float]:
    """The time ``t`` near ``t_guess`` where the closed-form orbit passes nearest ``state``, and that distance.

    Newton on ``(y(t) - state) . y'(t) = 0`` (``y''`` by a central difference).
    """
    t = float(t_guess)
    target = np.asarray(state, float)
    for _ in range(iterations):
        y, f = orbit.state(t), orbit.velocity(t)
        h = 1e-6
        fp = (orbit.velocity(t + h) - orbit.velocity(t - h)) / (2 * h)
        g = (y - target) @ f
        dg = f @ f + (y - target) @ fp
        t -= g / dg
    return t, float(np.linalg.norm(orbit.state(t) - target))
