"""The passive compass-gait walker on a slope: swing phase, heel strike, impact and leg swap.

Goswami, Thuilot and Espiau, "A study of the passive gait of a compass-like biped robot: symmetry and chaos",
Int. J. Robotics Research 17 (1998).  Two rigid legs (mass ``m`` at distance ``b`` from the hip and ``a`` from
the foot, ``l = a + b``) and a hip mass ``m_H``; angles from the vertical, ``q = (theta_ns, theta_s)`` (swing,
stance).  Swing phase: ``M(q) q'' + N(q, q') q' + G(q) = 0`` (the paper's eq. 1).  Heel strike where the swing
foot meets the slope of angle ``phi``, ``theta_ns + theta_s + 2 phi = 0``, with the swing leg ahead of the
stance leg (the guard ``theta_ns - theta_s > 0`` excludes the foot scuffing as the legs pass, near
stance-leg-vertical).  Impact (angular momentum conserved about the contact and, for the trailing leg, about
the hip): ``Q+(alpha) q'+ = Q-(alpha) q'-`` with ``2 alpha = theta_ns - theta_s``, and the legs swap.
Parameters of the paper: ``m = 5, m_H = 10, a = b = 0.5, g = 9.81``.

Reference (scipy only): ``solve_ivp`` (DOP853, rtol 1e-12) of the swing phase in two stages (to the legs
passing, then to the heel strike: each its own event), then the impact map; the Poincare map on the
post-impact section ``(theta_s, theta_ns', theta_s')`` (``theta_ns = -theta_s - 2 phi``), its fixed point by
Newton, its derivative by fourth-order central differences, whose eigenvalues are the orbit's three
nontrivial multipliers.  At ``phi = 3 deg`` the fixed point is ``(-0.32339, 0.21867, -0.37737, -1.09238)``, the
gait tabulated by Goswami et al. (``-0.3234, 0.2187, -0.3772, -1.0918``).  As the slope grows, the complex
pair of multipliers turns real and one passes -1: the period-1 gait loses its stability by a period doubling
at ``phi = 4.391 deg`` (``brentq`` on ``det(DP + I)``); Goswami et al. report the period doubling of the gait in
this range of slopes, followed by a cascade to chaos.
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from corpus import BranchStep, Expected, LiteratureCase, Orbit, SweepStep
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from saltation import Crossing, Mode, PiecewiseSystem, Transition

DEFAULTS = {"m": 5.0, "m_H": 10.0, "a": 0.5, "b": 0.5, "g": 9.81, "phi": float(np.deg2rad(3.0))}


def compass_gait(**overrides) -> PiecewiseSystem:
    m, m_H, a, b, g = sp.symbols("m m_H a b g")
    th_ns, th_s, w_ns, w_s = sp.symbols("theta_ns theta_s omega_ns omega_s")
    l = a + b
    M = sp.Matrix([[m * b**2, -m * l * b * sp.cos(th_s - th_ns)],
                   [-m * l * b * sp.cos(th_s - th_ns), (m_H + m) * l**2 + m * a**2]])
    N = sp.Matrix([[0, m * l * b * sp.sin(th_s - th_ns) * w_s],
                   [-m * l * b * sp.sin(th_s - th_ns) * w_ns, 0]])
    G = sp.Matrix([m * b * g * sp.sin(th_ns), -(m_H * l + m * a + m * l) * g * sp.sin(th_s)])
    acc = M.inv() * (-N * sp.Matrix([w_ns, w_s]) - G)
    c2 = sp.cos(th_ns - th_s)  # cos(2 alpha) at the heel strike
    Q_minus = sp.Matrix([[-m * a * b, -m * a * b + (m_H * l**2 + 2 * m * a * l) * c2], [0, -m * a * b]])
    Q_plus = sp.Matrix([[m * b * (b - l * c2), m * l * (l - b * c2) + m * a**2 + m_H * l**2],
                        [m * b**2, -m * b * l * c2]])
    w_plus = Q_plus.inv() * Q_minus * sp.Matrix([w_ns, w_s])
    return PiecewiseSystem(
        name="literature_compass_gait",
        states=["theta_ns", "theta_s", "omega_ns", "omega_s"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("swing", [w_ns, w_s, acc[0], acc[1]])],
        surfaces={"heel": "theta_ns + theta_s + 2*phi"},
        transitions=[Transition("swing", "heel", Crossing.FALLING, "swing",
                                reset=[th_s, th_ns, w_plus[0], w_plus[1]],  # the legs swap
                                guard=["theta_ns - theta_s > 0"])],
    )


# ---------------------------------------------------------------------------------------------------------
# the reference: scipy solve_ivp with its own events, the impact map, the Poincare map (no saltation)

def _field(q):
    m, mH, a, b, g = q["m"], q["m_H"], q["a"], q["b"], q["g"]
    l = a + b

    def f(t, x):
        tn, ts, wn, ws = x
        c, s = np.cos(ts - tn), np.sin(ts - tn)
        M = np.array([[m * b * b, -m * l * b * c], [-m * l * b * c, (mH + m) * l * l + m * a * a]])
        Nw = np.array([m * l * b * s * ws * ws, -m * l * b * s * wn * wn])
        G = np.array([m * b * g * np.sin(tn), -(mH * l + m * a + m * l) * g * np.sin(ts)])
        return [wn, ws, *np.linalg.solve(M, -Nw - G)]

    return f


def _impact(q, x):
    m, mH, a, b = q["m"], q["m_H"], q["a"], q["b"]
    l = a + b
    tn, ts, wn, ws = x
    c2 = np.cos(tn - ts)
    Qm = np.array([[-m * a * b, -m * a * b + (mH * l * l + 2 * m * a * l) * c2], [0.0, -m * a * b]])
    Qp = np.array([[m * b * (b - l * c2), m * l * (l - b * c2) + m * a * a + mH * l * l], [m * b * b, -m * b * l * c2]])
    w = np.linalg.solve(Qp, Qm @ np.array([wn, ws]))
    return np.array([ts, tn, w[0], w[1]])


def _step(q, x):
    """One step from a post-impact state: the time to the next heel strike and the post-impact state."""
    f = _field(q)
    opts = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-12}

    def passing(t, y):  # the legs pass each other (the swing foot scuffs the slope here: no heel strike)
        return y[0] - y[1]

    def heel(t, y):
        return y[0] + y[1] + 2 * q["phi"]

    passing.terminal, passing.direction = True, 1
    heel.terminal, heel.direction = True, -1
    s1 = solve_ivp(f, (0.0, 10.0), x, events=passing, **opts)
    assert s1.status == 1, "the legs do not pass"
    t1, x1 = s1.t_events[0][0], s1.y_events[0][0]
    s2 = solve_ivp(f, (t1, t1 + 10.0), x1, events=heel, **opts)
    assert s2.status == 1, "no heel strike"
    return s2.t_events[0][0], _impact(q, s2.y_events[0][0])


def poincare(q, y):
    """The map on the post-impact section, ``y = (theta_s, omega_ns, omega_s)``, and the step time."""
    t, z = _step(q, np.array([-y[0] - 2 * q["phi"], y[0], y[1], y[2]]))
    return z[1:], t


def poincare_jacobian(q, y, h=2e-4):
    """Fourth-order central differences (truncation ~h^4, rounding ~1e-12 / h): with h = 1e-3 the truncation
    is 3.5e-7 in the multipliers (measured against h = 3e-4 and 1e-4, which agree to 1e-9); 2e-4 keeps both
    errors below 1e-8."""
    cols = []
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        P = [poincare(q, y + s * e)[0] for s in (2, 1, -1, -2)]
        cols.append((-P[0] + 8 * P[1] - 8 * P[2] + P[3]) / (12 * h))
    return np.array(cols).T


def fixed_point(q, guess=(0.2187, -0.3772, -1.0918)):
    """The period-1 gait on the post-impact section (Newton), the map's derivative there, the step time."""
    y = np.array(guess, dtype=float)
    for _ in range(20):
        dy = np.linalg.solve(poincare_jacobian(q, y) - np.eye(3), -(poincare(q, y)[0] - y))
        y = y + dy
        if np.linalg.norm(dy) < 1e-13:
            break
    return y, poincare_jacobian(q, y), poincare(q, y)[1]


def multipliers(p):
    return np.linalg.eigvals(fixed_point(dict(p))[1])


def period_doubling(q, lo=0.0698, hi=0.0785):
    """The slope where a multiplier of the period-1 gait is -1 (bracketed by 4.0 and 4.5 degrees)."""
    return brentq(lambda phi: np.linalg.det(fixed_point(dict(q, phi=phi))[1] + np.eye(3)), lo, hi, xtol=1e-13)


def swing_apex(q) -> float:
    """The largest swing-leg angle of the period-1 gait: where ``omega_ns`` falls through zero in the swing
    (``solve_ivp``'s own event on the reference step from the gait's post-impact state)."""
    y, _, T = fixed_point(q)
    apex = lambda t, z: z[2]  # noqa: E731
    apex.direction = -1
    sol = solve_ivp(_field(q), (0.0, T), np.array([-y[0] - 2 * q["phi"], y[0], y[1], y[2]]), events=apex,
                    method="DOP853", rtol=1e-12, atol=1e-12)
    assert sol.t_events[0].size == 1, "one apex of the swing leg per step"
    return float(sol.y_events[0][0][0])


def _sweep_is_the_gait(result) -> None:
    """The sampled maxima of ``theta_ns`` (the first state) after 60 steps of transient (the multipliers'
    modulus 0.58 leaves 1e-14 of the start) are the reference gait's swing apex, to 1e-8 (the default
    integration's rtol 1e-10 and the reference's 1e-12 on an angle of 0.36)."""
    x = np.asarray(result.states, dtype=float)
    assert len(x) >= 4
    np.testing.assert_allclose(x[:, 0], swing_apex(dict(DEFAULTS)), rtol=0, atol=1e-8)
    np.testing.assert_allclose(x[:, 2], 0.0, rtol=0, atol=1e-6)  # (at a maximum the swing leg stops)


def _period_doubling():
    # brentq to 1e-13 on a map whose derivative is good to ~1e-9: the root to ~1e-9
    return [Expected(("period_doubling",), period_doubling(dict(DEFAULTS)), 1e-8)]


CASE = LiteratureCase(
    name="compass_gait",
    field="robotics",
    source="Goswami, Thuilot and Espiau, Int. J. Robotics Research 17 (1998) (passive compass-gait walker)",
    model=compass_gait,
    # the natural guess: the gait tabulated by Goswami et al. at 3 deg, a post-impact state, and its step time
    orbit=Orbit(parameters=dict(DEFAULTS), guess=[-0.3234, 0.2187, -0.3772, -1.0918], period=0.75,
                multipliers=multipliers),
    branch=BranchStep("phi", (float(np.deg2rad(3.0)), float(np.deg2rad(5.0))), _period_doubling,
                      ds=0.002, ds_max=0.005),
    sweep=SweepStep("phi", [DEFAULTS["phi"]], _sweep_is_the_gait,
                    options={"x0": [-0.3234, 0.2187, -0.3772, -1.0918], "period": 0.75, "periods": 5,
                             "transient": 60}),
)
