"""Grazing bifurcations located and passed on backward-time branches and on autonomous branches.

References, derived here independently of the library (and checked against scipy's ``solve_ivp`` in
the ``test_reference_*`` tests):

**1. A forced oscillator with negative damping against a wall, followed in backward time.**
``x'' + c x' + k x = f0 cos(w t)`` with ``c < 0`` for ``x < x_c``.

* Its free (contact-less) periodic response is the harmonic solution ``x_p = a cos(w t) + b sin(w t)``,
  ``a = f0 (k - w^2) / D^2``, ``b = f0 c w / D^2``, ``D = sqrt((k - w^2)^2 + (c w)^2)`` (substitute and
  compare the cos and sin coefficients), of amplitude ``f0 / D``, largest at
  ``t_g = atan2(c w, k - w^2) / w (mod T)``, ``T = 2 pi / w``.
* It grazes the wall where the amplitude is ``x_c``: ``f0_g = x_c D``.
* A deviation from it obeys ``y' = A y``, ``A = [[0, 1], [-k, -c]]``: its monodromy is ``expm(A T)``,
  whatever ``f0``, with the forward multipliers ``exp(lambda_i T)``,
  ``lambda = -c/2 +- i sqrt(k - c^2/4)``, of modulus ``exp(-c T / 2) > 1``.  Unstable in forward time,
  the orbit is found and followed by backward-time shooting (stable there).
* Two walls.  (i) An impact with Newton's law ``v+ = -r v-`` (forward time).  A transition fires on a
  sign change *as followed in the direction of integration*, and its reset is applied as written:
  backward in time the orbit reaches ``x = x_c`` with ``v < 0`` (the forward post-impact state, ``x``
  rising as ``t`` falls) and must leave with the pre-impact velocity ``-v / r``; the model therefore
  lists ``RISING`` with the reset ``v -> -v / r``, and its backward-time orbits are the forward-time
  orbits of the impact oscillator with restitution ``r``.  An impacting orbit's monodromy has
  ``det M = det(S) exp(trace(A) T) = r^2 exp(-c T)`` (the impact's saltation matrix is
  ``S = [[-r, 0], [*, -r]]``), and near grazing one forward multiplier grows like ``1/d`` (the impact
  velocity is ``O(d)`` and ``S = O(1/v)``): infinite in the limit.  (ii) A stiff contact spring
  ``-k_c (x - x_c)`` beyond the wall (a region-based model, time-reversible, force continuous at the
  wall): the saltation matrices are the identity, so both one-sided limits at the grazing are
  ``expm(A T)``, and every contacting orbit has ``det M = exp(-c T)``.

**2. The Hopf normal form against a wall (autonomous).**
``x' = mu x - y - x (x^2 + y^2)``, ``y' = x + mu y - y (x^2 + y^2)``; in polar coordinates
``rho' = rho (mu - rho^2)``, ``theta' = 1``.

* The limit cycle ``rho = sqrt(mu)``, period ``2 pi``; linearised, ``delta rho' = -2 mu delta rho``:
  the multipliers are ``1`` (trivial) and ``exp(-4 pi mu)``.
* A wall at ``x = c`` with the reset ``y -> -r y`` (an impact: the orbit arrives with ``y < 0`` and
  leaves into ``x < c``).  The cycle grazes it where ``sqrt(mu) = c``: ``mu_g = c^2``, at ``(c, 0)``.
* Impacting period-1 orbits (``mu > c^2``), in closed form: ``w = rho^2`` solves the logistic equation
  ``w' = 2 w (mu - w)``, ``w(t) = mu / (1 + (mu / w0 - 1) exp(-2 mu t))``.  From the pre-impact state
  ``(c, -sqrt(Y))`` the impact gives ``(c, r sqrt(Y))``: ``w0 = c^2 + r^2 Y``, angle
  ``theta0 = atan(r sqrt(Y) / c)``; the next impact is the root ``t`` of
  ``sqrt(w(t)) cos(theta0 + t) = c`` with ``theta0 + t`` in ``(3 pi/2, 2 pi)``, where
  ``Y' = w(t) - c^2``.  A fixed point ``Y*`` of this return map ``F`` is the impacting orbit; its
  period is ``t``, its multipliers ``1`` and ``F'(Y*)`` (by implicit differentiation).  As
  ``mu -> c^2``, ``F' -> r^2 exp(-4 pi c^2)`` (linearising ``w - c^2`` about ``mu - c^2``: the map is
  affine in ``Y``, ``Y' = (mu - c^2)(1 - E) + r^2 E Y``, ``E = exp(-4 pi c^2)``), with an ``O(sqrt(mu - c^2))``
  error: in a planar autonomous system the impact's ``O(1/v)`` kick is along the flow at grazing
  (a shift of phase), so the multipliers stay bounded on the impacting side.
* Backward time: the field ``-f`` with the same wall and reset, followed backward, is the model above
  run forward; its cycle is unstable in forward time, with the multipliers ``1`` and
  ``exp(+4 pi mu)``, and its impacting orbits have the forward multipliers ``1`` and ``1 / F'(Y*)``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.optimize import brentq

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition
from saltation.branches.branch import SpecialPointKind, StopReason
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import ContinuationSettings, continue_branch

# --------------------------------------------------------------------------------------------------
# 1. forced oscillator with negative damping, backward time
# --------------------------------------------------------------------------------------------------
K, C, W, XC, R, KC = 1.0, -0.1, 0.8, 1.0, 0.8, 20.0
T = 2 * np.pi / W
DEN = np.hypot(K - W**2, C * W)
F0_G = XC * DEN
A_FREE = np.array([[0.0, 1.0], [-K, -C]])
MU_FREE = np.sort_complex(np.linalg.eigvals(expm(A_FREE * T)))
T_G = (np.arctan2(C * W, K - W**2) / W) % T
IMPACT = "free -[wall+]-> free"
ENTER, LEAVE = "free -[wall+]-> contact", "contact -[wall-]-> free"
FREE_FIELD = ["v", "-c*v - k*x + f0*cos(omega*t)"]
FORCED_PARAMETERS = {"k": K, "c": C, "omega": W, "xc": XC, "f0": 0.3}


def impact_model() -> PiecewiseSystem:
    """The wall as an impact, written for backward time (reset ``v -> -v/r``: Newton's ``v -> -r v`` forward)."""
    return PiecewiseSystem(
        name="test_backward_negative_damping_impact", states=["x", "v"], parameters=FORCED_PARAMETERS | {"r": R},
        modes=[Mode("free", FREE_FIELD)],
        surfaces={"wall": "x - xc"},
        transitions=[Transition("free", "wall", Crossing.RISING, "free", reset=["x", "-v/r"])],
        period="2*pi/omega",
    )


def soft_wall_model() -> PiecewiseSystem:
    """The wall as a stiff contact spring (force continuous at the wall; the boundary listed both ways)."""
    return PiecewiseSystem(
        name="test_backward_negative_damping_soft_wall", states=["x", "v"], parameters=FORCED_PARAMETERS | {"kc": KC},
        modes=[Mode("contact", ["v", "-c*v - k*x - kc*(x - xc) + f0*cos(omega*t)"], domain=["x - xc > 0"]),
               Mode("free", FREE_FIELD)],
        surfaces={"wall": "x - xc"},
        transitions=[Transition("free", "wall", Crossing.RISING, "contact"),
                     Transition("contact", "wall", Crossing.FALLING, "free")],
        period="2*pi/omega",
    )


def free_response(f0: float, t: float = 0.0) -> np.ndarray:
    """The harmonic response ``(x_p, x_p')`` at ``t``."""
    a, b = f0 * (K - W**2) / DEN**2, f0 * C * W / DEN**2
    return np.array([a * np.cos(W * t) + b * np.sin(W * t), W * (-a * np.sin(W * t) + b * np.cos(W * t))])


def forced_rhs(f0: float, contact: bool):
    def rhs(t, z):
        x, v = z
        return [v, -C * v - K * x + f0 * np.cos(W * t) - (KC * (x - XC) if contact else 0.0)]
    return rhs


def forward_period_scipy(state0, f0: float, soft: bool) -> np.ndarray:
    """One forcing period forward in time by scipy (DOP853, rtol 1e-12), the wall handled by events:
    the impact by Newton's law ``v -> -r v``, the soft wall by switching the field.  Steps of at most
    T/200: scipy looks for events between steps only, and a long step would miss a shallow impact."""
    t, z = 0.0, np.array(state0, dtype=float)
    contact = soft and z[0] > XC
    while True:
        def wall(t, z):
            return z[0] - XC
        wall.terminal, wall.direction = True, (-1 if contact else 1)
        sol = solve_ivp(forced_rhs(f0, contact), (t, T), z, method="DOP853", rtol=1e-12, atol=1e-14, events=wall,
                        max_step=T / 200)
        t, z = float(sol.t[-1]), sol.y[:, -1].copy()
        if sol.status != 1:
            return z
        if soft:
            contact = not contact
        else:
            z[1] = -R * z[1]


@pytest.fixture(scope="module")
def impact_flow():
    return Flow(impact_model())


@pytest.fixture(scope="module")
def soft_flow():
    return Flow(soft_wall_model())


def backward_forced_branch(flow, f0_start: float, f0_end: float, ds: float, ds_max: float):
    problem = ShootingProblem(flow, {"f0": f0_start}, continuation_parameter="f0", backward=True)
    return continue_branch(problem, free_response(f0_start), f0_start, directions=(1,),
                           settings=ContinuationSettings(ds=ds, ds_max=ds_max, bounds=(f0_start, f0_end)))


def the_grazing(branch):
    grazings = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.GRAZING]
    found = [(sp.kind.value, sp.parameter, sp.accuracy) for sp in branch.special_points]
    assert len(grazings) == 1, f"special points found: {found}; stop: {branch.stop_reason}"
    return grazings[0]


def wrapped(dt: float, period: float) -> float:
    """``dt`` modulo ``period``, in ``[-period/2, period/2)``."""
    return (dt + 0.5 * period) % period - 0.5 * period


def test_reference_forced_free_response():
    """The closed forms of part 1 against scipy: the harmonic response is periodic, touches x_c at t_g
    (with zero velocity) when f0 = f0_g, and its monodromy has the eigenvalues of expm(A T)."""
    tight = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-14}
    x0 = free_response(F0_G)
    ts = np.linspace(0.0, T, 4001)
    sol = solve_ivp(forced_rhs(F0_G, False), (0.0, T), x0, t_eval=ts, dense_output=True, **tight)
    # DOP853 at rtol 1e-12 over one period of a linear oscillator: global error ~1e-11
    np.testing.assert_allclose(sol.y[:, -1], x0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sol.sol(T_G), [XC, 0.0], rtol=0, atol=1e-10)
    assert sol.y[0].max() <= XC + 1e-10  # the largest x on the orbit (sampled) is the wall
    np.testing.assert_allclose(free_response(F0_G, T_G), [XC, 0.0], rtol=0, atol=1e-14)  # the formula itself
    assert np.abs(MU_FREE) == pytest.approx(np.exp(-C * T / 2) * np.ones(2), rel=1e-13)

    def variational(t, z):
        return np.concatenate([forced_rhs(F0_G, False)(t, z[:2]), (A_FREE @ z[2:].reshape(2, 2)).ravel()])

    M = solve_ivp(variational, (0.0, T), np.concatenate([x0, np.eye(2).ravel()]), **tight).y[2:, -1].reshape(2, 2)
    # the fundamental matrix by DOP853 at rtol 1e-12: ~1e-11 of |M| ~ 1.5
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(M)), MU_FREE, rtol=0, atol=1e-10)


@pytest.mark.parametrize(
    "f0_start, f0_end, ds, ds_max",
    [(0.30, 0.45, 0.02, 0.05),  # large steps: the branch steps across the grazing
     (0.36, 0.40, 0.001, 0.001)],  # small steps: from the free side the corrector stalls at the grazing
    ids=["large-steps", "small-steps"],
)
def test_backward_branch_locates_and_passes_the_grazing_of_an_impact(impact_flow, f0_start, f0_end, ds, ds_max):
    branch = backward_forced_branch(impact_flow, f0_start, f0_end, ds, ds_max)
    assert branch.backward
    g = the_grazing(branch)
    # located by its defining system (Newton, exact affine flow): far below the branch's locate_tol 1e-9,
    # which bisection along a secant would reach at best
    assert g.accuracy < 1e-9
    assert abs(g.parameter - F0_G) <= g.accuracy + 1e-15  # + the closed form's own rounding
    assert g.period == pytest.approx(T, abs=1e-12)  # the forcing period, a closed form of omega
    # the grazing orbit is the free response at f0_g: its state is known to |d x_p / d f0| * accuracy < 1e-8
    np.testing.assert_allclose(g.state, free_response(F0_G), rtol=0, atol=1e-8)
    # the tangency is the maximum of x_p: a simple root of x_p' (|x_p''| = w^2 x_c), known to ~1e-12
    assert g.touch_surface == "wall" and abs(wrapped(g.touch_time - T_G, T)) < 1e-8
    # the side without impacts: expm(A T) as forward multipliers; exact affine flow, rounding ~1e-13 |M|
    np.testing.assert_allclose(np.sort_complex(g.multipliers_minus), MU_FREE, rtol=0, atol=1e-9)
    # the impacting side: one forward multiplier grows like 1/d, infinite in the limit
    assert np.isinf(np.abs(g.multipliers_plus)).sum() == 1
    assert g.event_labels_minus == () and g.event_labels_plus == (IMPACT,)
    assert "the side with the crossing is 'plus'" in g.note

    # both sides of the branch are there, and it goes on to the bound past the grazing
    before = [p for p in branch.points if p.parameter < F0_G]
    beyond = [p for p in branch.points if p.parameter > F0_G]
    assert before and all(p.event_labels == () for p in before)
    for p in before:  # expm(A T) whatever f0 (exact affine flow: rounding)
        np.testing.assert_allclose(np.sort_complex(p.multipliers), MU_FREE, rtol=0, atol=1e-9)
    assert len(beyond) >= 3 and all(p.event_labels == (IMPACT,) for p in beyond)
    assert branch.stop_reason is StopReason.PARAMETER_BOUND
    assert branch.parameter.max() == pytest.approx(f0_end, abs=1e-12)
    # det M = r^2 exp(-c T) on every impacting orbit.  The large forward multiplier mu is the reciprocal of
    # the backward monodromy's small eigenvalue 1/mu, known to eps |M_b| ~ eps |mu|: a relative error
    # eps |mu|^2, below 1e-10 for |mu| <= 1e3 (nearer the grazing, where |mu| ~ 1/d, it is not resolvable)
    resolved = [p for p in beyond if np.abs(p.multipliers).max() <= 1e3]
    assert len(resolved) >= 3
    for p in resolved:
        assert np.prod(p.multipliers).real == pytest.approx(R**2 * np.exp(-C * T), rel=1e-8)
    # the orbits beyond are impacting periodic orbits, forward in time with Newton's law (scipy): the
    # corrector's 1e-10 grows by at most |mu_max| <= 100 over the period, scipy adds ~1e-11
    checked = [p for p in beyond if np.abs(p.multipliers).max() <= 100]
    assert checked
    for p in checked:
        np.testing.assert_allclose(forward_period_scipy(p.state, p.parameter, soft=False), p.state, rtol=0, atol=1e-7)


def test_backward_branch_locates_and_passes_the_grazing_of_a_soft_wall(soft_flow):
    branch = backward_forced_branch(soft_flow, 0.30, 0.45, 0.02, 0.05)
    g = the_grazing(branch)
    assert g.accuracy < 1e-9  # the defining system, as for the impact
    assert abs(g.parameter - F0_G) <= g.accuracy + 1e-15
    np.testing.assert_allclose(g.state, free_response(F0_G), rtol=0, atol=1e-8)
    assert g.touch_surface == "wall" and abs(wrapped(g.touch_time - T_G, T)) < 1e-8
    # a continuous force: the saltation matrices at the tangency are the identity, both one-sided limits
    # are expm(A T) (exact affine flow in both modes: rounding)
    for side in (g.multipliers_minus, g.multipliers_plus):
        np.testing.assert_allclose(np.sort_complex(side), MU_FREE, rtol=0, atol=1e-9)
    assert g.event_labels_minus == () and set(g.event_labels_plus) == {ENTER, LEAVE}
    assert "the side with the crossing is 'plus'" in g.note and "unbounded" not in g.note

    before = [p for p in branch.points if p.parameter < F0_G]
    beyond = [p for p in branch.points if p.parameter > F0_G]
    assert before and all(p.event_labels == () for p in before)
    assert len(beyond) >= 2 and all(sorted(p.event_labels) == sorted([ENTER, LEAVE]) for p in beyond)
    assert branch.stop_reason is StopReason.PARAMETER_BOUND
    assert branch.parameter.max() == pytest.approx(0.45, abs=1e-12)
    for p in beyond:
        # det M = exp(-c T) (trace -c in both modes, identity saltation); multipliers of size ~5: rounding
        assert np.prod(p.multipliers).real == pytest.approx(np.exp(-C * T), rel=1e-8)
        # forward in time by scipy: the corrector's 1e-10 grows by at most |mu_max| ~ 6, scipy adds ~1e-11
        np.testing.assert_allclose(forward_period_scipy(p.state, p.parameter, soft=True), p.state, rtol=0, atol=1e-8)


# --------------------------------------------------------------------------------------------------
# 2. the Hopf normal form against a wall, autonomous (forward and backward time)
# --------------------------------------------------------------------------------------------------
CW, RA = 0.5, 0.8
MU_G = CW**2
E_G = np.exp(-4 * np.pi * MU_G)
MU_START, MU_END = 0.2, 0.3


def hopf_model(backward: bool) -> PiecewiseSystem:
    """The Hopf normal form (``-f`` for backward time) with the wall ``x = c`` and the reset ``y -> -r y``."""
    s = "-" if backward else ""
    return PiecewiseSystem(
        name=f"test_hopf_impact_{'backward' if backward else 'forward'}", states=["x", "y"],
        parameters={"mu": MU_START, "c": CW, "r": RA},
        modes=[Mode("free", [f"{s}(mu*x - y - x*(x**2 + y**2))", f"{s}(x + mu*y - y*(x**2 + y**2))"])],
        surfaces={"wall": "x - c"},
        transitions=[Transition("free", "wall", Crossing.RISING, "free", reset=["x", "-r*y"])],
    )


def logistic(w0: float, t: float, mu: float) -> float:
    return mu / (1.0 + (mu / w0 - 1.0) * np.exp(-2.0 * mu * t))


def impact_return(Y: float, mu: float) -> tuple[float, float]:
    """The closed-form return map: pre-impact ``y^2 = Y`` -> next pre-impact ``y^2``, and the time between."""
    th0 = np.arctan2(RA * np.sqrt(Y), CW)
    w0 = CW**2 + RA**2 * Y
    t = brentq(lambda t: np.sqrt(logistic(w0, t, mu)) * np.cos(th0 + t) - CW, 1.5 * np.pi - th0, 2 * np.pi - th0,
               xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return logistic(w0, t, mu) - CW**2, t


def impact_return_derivative(Y: float, mu: float) -> float:
    """``dY'/dY`` of :func:`impact_return`, by implicit differentiation of ``w(t) cos^2(theta0 + t) = c^2``."""
    _, t = impact_return(Y, mu)
    y = np.sqrt(Y)
    th0 = np.arctan2(RA * y, CW)
    w0 = CW**2 + RA**2 * Y
    w = logistic(w0, t, mu)
    w_w0 = w**2 * np.exp(-2 * mu * t) / w0**2  # dw/dw0
    w_t = 2 * w * (mu - w)  # dw/dt
    dw0 = RA**2  # dw0/dY
    dth0 = (RA / (2 * CW * y)) / (1 + (RA * y / CW) ** 2)  # dtheta0/dY
    cs, sn = np.cos(th0 + t), np.sin(th0 + t)
    G_Y = w_w0 * dw0 * cs**2 - 2 * w * cs * sn * dth0
    G_t = w_t * cs**2 - 2 * w * cs * sn
    return w_w0 * dw0 + w_t * (-G_Y / G_t)


def impacting_orbit(mu: float) -> tuple[float, float, float]:
    """``(Y*, period, F'(Y*))`` of the impacting period-1 orbit at ``mu > c^2``."""
    d = mu - CW**2
    linear = d * (1 - E_G) / (1 - RA**2 * E_G)  # the fixed point of the linearised map
    Y = brentq(lambda Y: impact_return(Y, mu)[0] - Y, 0.5 * linear, 2.0 * linear, xtol=1e-300, rtol=4 * np.finfo(float).eps)
    return Y, impact_return(Y, mu)[1], impact_return_derivative(Y, mu)


def hopf_rhs(mu: float):
    def rhs(t, z):
        x, y = z
        q = x * x + y * y
        return [mu * x - y - x * q, x + mu * y - y * q]
    return rhs


def hopf_period_scipy(z0, mu: float, T_end: float) -> np.ndarray:
    """Forward in time from ``z0`` for ``T_end`` by scipy (DOP853, rtol 1e-12, steps of at most 2 pi / 200 so
    that no shallow impact falls between two steps), impacts by ``y -> -r y``."""
    t, z = 0.0, np.array(z0, dtype=float)
    while True:
        def wall(t, z):
            return z[0] - CW
        wall.terminal, wall.direction = True, 1
        sol = solve_ivp(hopf_rhs(mu), (t, T_end), z, method="DOP853", rtol=1e-12, atol=1e-14, events=wall,
                        max_step=np.pi / 100)
        t, z = float(sol.t[-1]), sol.y[:, -1].copy()
        if sol.status != 1:
            return z
        z[1] = -RA * z[1]


def next_impact_scipy(z0, mu: float) -> tuple[float, np.ndarray]:
    """The first time and state where the orbit from ``z0`` reaches the wall from ``x < c`` (scipy, rtol 1e-12)."""
    def wall(t, z):
        return z[0] - CW
    wall.terminal, wall.direction = True, 1
    sol = solve_ivp(hopf_rhs(mu), (0.0, 4 * np.pi), z0, method="DOP853", rtol=1e-12, atol=1e-14, events=wall,
                    max_step=np.pi / 100)
    assert sol.status == 1
    return float(sol.t_events[0][0]), sol.y_events[0][0]


def test_reference_hopf_cycle_and_impacting_orbits():
    """The closed forms of part 2 against scipy."""
    tight = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-14}
    # the cycle of radius sqrt(mu), period 2 pi, nontrivial multiplier exp(-4 pi mu) (central differences
    # of DOP853 at rtol 1e-12 with h = 1e-5: O(h^2) + 1e-12 / h, ~1e-7)
    mu = MU_G
    z0 = np.array([0.0, -np.sqrt(mu)])
    sol = solve_ivp(hopf_rhs(mu), (0.0, 2 * np.pi), z0, dense_output=True, **tight)
    np.testing.assert_allclose(sol.y[:, -1], z0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sol.sol(np.pi / 2), [CW, 0.0], rtol=0, atol=1e-10)  # the tangency at (c, 0)
    h = 1e-5
    J = np.column_stack([(solve_ivp(hopf_rhs(mu), (0, 2 * np.pi), z0 + h * e, **tight).y[:, -1]
                          - solve_ivp(hopf_rhs(mu), (0, 2 * np.pi), z0 - h * e, **tight).y[:, -1]) / (2 * h)
                         for e in np.eye(2)])
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(J).real), [E_G, 1.0], rtol=0, atol=1e-7)

    for mu in (0.2589, 0.3):
        Y, period, slope = impacting_orbit(mu)
        # the return map's derivative against its own central differences (h = 1e-6 Y: O(h^2) truncation,
        # rounding 1e-16 / 1e-6)
        hY = 1e-6 * Y
        fd = (impact_return(Y + hY, mu)[0] - impact_return(Y - hY, mu)[0]) / (2 * hY)
        assert slope == pytest.approx(fd, abs=1e-8)
        # the impacting orbit by scipy: from the post-impact state (c, r sqrt(Y*)) the next impact is at
        # (c, -sqrt(Y*)) after the closed-form period (DOP853 at rtol 1e-12, its event located to ~1e-12)
        t_hit, z_hit = next_impact_scipy([CW, RA * np.sqrt(Y)], mu)
        assert t_hit == pytest.approx(period, abs=1e-9)
        np.testing.assert_allclose(z_hit, [CW, -np.sqrt(Y)], rtol=0, atol=1e-9)
        # and a state away from the wall comes back after one period, impact included
        z_mid = hopf_period_scipy([CW, RA * np.sqrt(Y)], mu, 2.0)
        np.testing.assert_allclose(hopf_period_scipy(z_mid, mu, period), z_mid, rtol=0, atol=1e-9)
        # its multipliers: 1 and F'(Y*) (central differences of the scipy period map there: ~1e-7 as above)
        J = np.column_stack([(hopf_period_scipy(z_mid + h * e, mu, period) - hopf_period_scipy(z_mid - h * e, mu, period))
                             / (2 * h) for e in np.eye(2)])
        np.testing.assert_allclose(np.sort(np.linalg.eigvals(J).real), [slope, 1.0], rtol=0, atol=1e-6)
    # the limit at grazing of the impacting side's nontrivial multiplier: r^2 exp(-4 pi c^2), approached
    # like sqrt(mu - c^2)
    for d in (1e-4, 1e-6):
        assert abs(impacting_orbit(MU_G + d)[2] - RA**2 * E_G) <= 0.05 * np.sqrt(d)


@pytest.fixture(scope="module", params=[False, True], ids=["forward", "backward"])
def hopf_branch(request):
    backward = request.param
    flow = Flow(hopf_model(backward))
    problem = ShootingProblem(flow, {"mu": MU_START}, continuation_parameter="mu", backward=backward)
    branch = continue_branch(problem, problem.pack([0.0, -np.sqrt(MU_START)], 2 * np.pi), MU_START, directions=(1,),
                             settings=ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(MU_START, MU_END)))
    return backward, branch


def by_modulus(mu) -> np.ndarray:
    mu = np.asarray(mu, dtype=complex)
    return mu[np.argsort(np.abs(mu))]


def test_autonomous_branch_locates_and_passes_the_grazing_of_an_impact(hopf_branch):
    backward, branch = hopf_branch
    assert branch.autonomous and branch.backward is backward
    g = the_grazing(branch)
    # the defining system by Newton at rtol 1e-12 (location_tolerances): its accuracy, Newton's last
    # correction plus the integration error carried to mu, is far below the branch's locate_tol 1e-9
    assert g.accuracy < 1e-9
    assert abs(g.parameter - MU_G) <= g.accuracy + 1e-15  # mu_g = c^2 = 0.25 is exact
    assert g.period == pytest.approx(2 * np.pi, abs=1e-9)  # theta' = 1, the period error ~ rtol 1e-12
    assert np.linalg.norm(g.state) == pytest.approx(CW, abs=1e-9)  # on the circle of radius sqrt(mu_g) = c
    assert g.touch_surface == "wall"
    # the side without impacts: 1 and exp(-+4 pi mu_g) (forward multipliers), from a monodromy integrated
    # at rtol 1e-12: ~1e-12 relative
    free = by_modulus(g.multipliers_minus)
    expected = [1.0, 1.0 / E_G] if backward else [E_G, 1.0]
    np.testing.assert_allclose(free, expected, rtol=1e-9, atol=1e-12)
    assert g.event_labels_minus == () and g.event_labels_plus == (IMPACT,)
    assert "the side with the crossing is 'plus'" in g.note

    before = [p for p in branch.points if p.parameter < MU_G]
    beyond = [p for p in branch.points if p.parameter > MU_G]
    assert before and all(p.event_labels == () for p in before)
    for p in before:
        # the cycle at mu: period 2 pi, multipliers 1 and exp(-+4 pi mu); DOP853 at the default rtol 1e-10
        # over one period: ~1e-10 in the period and relative in the monodromy
        assert p.period == pytest.approx(2 * np.pi, abs=1e-8)
        nontrivial = np.exp(4 * np.pi * p.parameter) if backward else np.exp(-4 * np.pi * p.parameter)
        np.testing.assert_allclose(by_modulus(p.multipliers), sorted([1.0, nontrivial]), rtol=1e-7, atol=1e-9)
    assert len(beyond) >= 3 and all(p.event_labels == (IMPACT,) for p in beyond)
    assert branch.stop_reason is StopReason.PARAMETER_BOUND
    assert branch.parameter.max() == pytest.approx(MU_END, abs=1e-12)
    for p in beyond:
        # the impacting orbits of the closed-form return map (DOP853 at rtol 1e-10: ~1e-10 in the period,
        # ~1e-9 in the multiplier, which the return map knows to ~1e-12)
        _, period, slope = impacting_orbit(p.parameter)
        assert p.period == pytest.approx(period, abs=1e-8)
        nontrivial = 1.0 / slope if backward else slope
        np.testing.assert_allclose(by_modulus(p.multipliers), sorted([1.0, nontrivial]), rtol=1e-7, atol=1e-8)


def test_autonomous_grazing_crossing_side_multipliers_are_bounded(hopf_branch):
    """On the impacting side the multipliers tend to 1 and r^2 exp(-4 pi c^2) (forward; the reciprocal
    backward): finite, although the monodromy itself grows like 1/sqrt(d) (along the flow)."""
    backward, branch = hopf_branch
    g = the_grazing(branch)
    crossing = by_modulus(g.multipliers_plus)
    assert np.all(np.isfinite(crossing)), crossing
    limit = 1.0 / (RA**2 * E_G) if backward else RA**2 * E_G
    trivial = crossing[np.argmin(np.abs(crossing - 1.0))]
    other = crossing[np.argmax(np.abs(crossing - 1.0))]
    # the trivial multiplier: to the shooting's TRIVIAL_MULTIPLIER_ACCURACY 1e-6
    assert abs(trivial - 1.0) <= 1e-6
    # the limit, or a crossing orbit's value within d <= 5e-4 of the grazing (the closed form moves by
    # ~0.05 sqrt(d), about 4 % of r^2 E there); this excludes inf and the free side's exp(-4 pi c^2) (56 % off)
    assert other == pytest.approx(limit, rel=0.04)
