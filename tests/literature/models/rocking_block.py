"""Hogan's rigid block rocking on a horizontally forced base (the slender-block equations).

S. J. Hogan, "On the dynamics of rigid-block motion under harmonic forcing", Proc. R. Soc. Lond. A 425 (1989)
441-476.  The angle ``phi`` in units of the block's critical angle, time in units of ``1/p`` (``p`` the block's
frequency parameter), the base acceleration ``beta cos(omega t)`` in units of ``g alpha``: rocking about the
right corner (``phi > 0``) and the left one (``phi < 0``),

    phi'' - phi = -1 - beta cos(omega t)   (phi > 0),      phi'' - phi = 1 - beta cos(omega t)   (phi < 0),

and at each impact (``phi`` through 0) the angular velocity is multiplied by the coefficient ``r``.

Reference (numpy/scipy only): in each mode the explicit solution
``phi = s + c1 e^(t - ts) + c2 e^-(t - ts) + q cos(omega t)``, ``q = beta / (1 + omega^2)``, the impact instants
by ``brentq`` on it (after a grid search for the first sign change), the stroboscopic map over one forcing
period from ``t = 0``, its fixed point by Newton and its Jacobian by central differences (h = 1e-6 on a map
exact to rounding).  The natural orbit is the symmetric period-1 rocking motion, one impact each half period;
its multipliers have ``|mu| = r^2`` while complex (the map's determinant is ``r^4``).
"""

from __future__ import annotations

import numpy as np
from corpus import BranchStep, LiteratureCase, Orbit, SweepStep
from scipy.optimize import brentq

from saltation import Crossing, Mode, PiecewiseSystem, Transition

DEFAULTS = {"beta": 2.0, "omega": 4.0, "r": 0.9}


def rocking_block(**overrides) -> PiecewiseSystem:
    return PiecewiseSystem(
        name="literature_rocking_block",
        states=["phi", "w"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("right", ["w", "phi - 1 - beta*cos(omega*t)"], domain=["phi > 0"]),
               Mode("left", ["w", "phi + 1 - beta*cos(omega*t)"])],
        surfaces={"ground": "phi"},
        transitions=[
            Transition("right", "ground", Crossing.FALLING, "left", reset=["phi", "r*w"]),
            Transition("left", "ground", Crossing.RISING, "right", reset=["phi", "r*w"]),
        ],
        period="2*pi/omega",
    )


# --- the reference: the explicit solution of each linear mode, brentq for the impacts ----------------------


def _coefficients(ts, phi, w, s, p):
    q = p["beta"] / (1.0 + p["omega"] ** 2)
    a = phi - s - q * np.cos(p["omega"] * ts)
    b = w + q * p["omega"] * np.sin(p["omega"] * ts)
    return (a + b) / 2.0, (a - b) / 2.0, q


def _solution(t, ts, c1, c2, q, s, p):
    om, tau = p["omega"], t - ts
    phi = s + c1 * np.exp(tau) + c2 * np.exp(-tau) + q * np.cos(om * t)
    w = c1 * np.exp(tau) - c2 * np.exp(-tau) - q * om * np.sin(om * t)
    return phi, w


def strobe(x, p, grid: int = 400) -> np.ndarray:
    """One forcing period from ``t = 0``: the state at ``2 pi / omega``."""
    T = 2.0 * np.pi / p["omega"]
    t, phi, w = 0.0, float(x[0]), float(x[1])
    s = 1.0 if (phi > 0.0 or (phi == 0.0 and w > 0.0)) else -1.0
    while True:
        c1, c2, q = _coefficients(t, phi, w, s, p)
        g = lambda tt: s * _solution(tt, t, c1, c2, q, s, p)[0]  # noqa: B023
        ts = np.linspace(t, T, max(int(grid * (T - t) / T), 4) + 1)
        gs = g(ts)
        if phi == 0.0:
            gs[0] = abs(gs[0])
        below = np.nonzero(gs[1:] < 0.0)[0]
        if len(below) == 0:
            return np.array(_solution(T, t, c1, c2, q, s, p))
        k = below[0]
        ti = brentq(g, ts[k], ts[k + 1], xtol=1e-15, rtol=1e-15)
        t, phi, w, s = ti, 0.0, p["r"] * _solution(ti, t, c1, c2, q, s, p)[1], -s


def jacobian(x, p, h: float = 1e-6) -> np.ndarray:
    J = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        J[:, j] = (strobe(x + e, p) - strobe(x - e, p)) / (2.0 * h)
    return J


def fixed_point(p, x0=(0.188, -0.074)) -> np.ndarray:
    x = np.array(x0, float)
    for _ in range(40):
        dx = -np.linalg.solve(jacobian(x, p) - np.eye(2), strobe(x, p) - x)
        x = x + dx
        if np.max(np.abs(dx)) < 1e-13:
            break
    assert np.max(np.abs(strobe(x, p) - x)) < 1e-13
    return x


def multipliers(p) -> np.ndarray:
    return np.linalg.eigvals(jacobian(fixed_point(p), p))


SWEEP_BETA = [1.8, 2.0, 2.4]


def _sweep_on_the_fixed_point(result) -> None:
    """Each value starts from the orbit's state at beta = 2: after 120 periods (|mu| = r^2 = 0.81, so 0.81^120
    ~ 1e-11 of a start 0.03 away) every stroboscopic sample is the reference's fixed point, and each sample is
    the reference map of the one before it."""
    assert not result.failures, result.failures
    for k, beta in enumerate(SWEEP_BETA):
        p = dict(DEFAULTS, beta=beta)
        pts = np.asarray(result.at(k), dtype=float)
        assert len(pts) == 5
        # the integration's rtol 1e-10 over one period of the saddle-like modes (e^T ~ 5): 1e-9
        np.testing.assert_allclose(pts, np.broadcast_to(fixed_point(p), pts.shape), rtol=0, atol=1e-9)
        for i in range(len(pts) - 1):
            np.testing.assert_allclose(pts[i + 1], strobe(pts[i], p), rtol=0, atol=1e-9)


CASE = LiteratureCase(
    name="rocking_block",
    field="mechanics",
    source="Hogan, Proc. R. Soc. Lond. A 425 (1989) 441-476 (rigid block rocking under harmonic forcing)",
    model=rocking_block,
    orbit=Orbit(parameters=dict(DEFAULTS), guess=[0.19, -0.07], multipliers=multipliers, state=fixed_point),
    # the reference's scan of beta from 0.5 to 4.75 at omega = 4: the multipliers stay a complex pair of modulus
    # r^2 (the map's determinant is r^4), so the branch has no special point
    branch=BranchStep("beta", (1.6, 3.0), list, ds_max=0.05),
    # measured: the samples within 8e-12 of the fixed point, each within 1.3e-11 of the reference map of the last
    sweep=SweepStep("beta", SWEEP_BETA, _sweep_on_the_fixed_point,
                    options={"x0": [0.18807298, -0.07367735], "start": "own", "transient": 120, "periods": 5}),
)
