"""A hand-written scipy implementation for a model that is not piecewise affine: the Duffing oscillator
with an impact stop, the baseline of ``orbit_nonlinear`` in ``run.py``.

    x'' + c x' + k x + beta x^3 = f0 cos(omega t),   impact at x = x_c: v -> -r v

What a competent user would write without saltation, as ``scipy_baseline.Trilinear`` does for the
trilinear system: ``solve_ivp`` with DOP853 (rtol 1e-10, atol 1e-12), the variational equation
``Phi' = f_x(x) Phi`` integrated alongside, a terminal event at the stop, the reset and the saltation
matrix of eq. (9) with a reset, ``S = g_x + (f+ - g_x f-) h_x / (h_x f-)``, and Newton on the period map
converged at ``|r| <= tol (1 + |x0|)``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

DEFAULTS = {"c": 0.1, "k": 1.0, "beta": 0.5, "f0": 0.6, "omega": 1.2, "x_c": 0.6, "r": 0.8}
RTOL, ATOL = 1e-10, 1e-12


def model():
    """The same model for saltation."""
    from saltation import Crossing, Mode, PiecewiseSystem, Transition

    return PiecewiseSystem(
        name="duffing_impact_bench", states=["x", "v"], parameters=dict(DEFAULTS),
        modes=[Mode("free", ["v", "-c*v - k*x - beta*x**3 + f0*cos(omega*t)"])],
        surfaces={"stop": "x - x_c"},
        transitions=[Transition("free", "stop", Crossing.RISING, "free", reset=["x", "-r*v"])],
        period="2*pi/omega",
    )


class DuffingImpact:
    """The Duffing impact oscillator, written out by hand."""

    def __init__(self, rtol: float = RTOL, atol: float = ATOL, **params: float):
        self.p = DEFAULTS | params
        self.rtol, self.atol = rtol, atol

    def field(self, t: float, x: np.ndarray) -> np.ndarray:
        p = self.p
        return np.array([x[1], -p["c"] * x[1] - p["k"] * x[0] - p["beta"] * x[0] ** 3 + p["f0"] * math.cos(p["omega"] * t)])

    def flow(self, x0, t0: float, t1: float) -> tuple[np.ndarray, np.ndarray, list[float]]:
        """The state at ``t1``, the fundamental solution matrix and the impact times."""
        p = self.p
        c, k, beta, f0, w, xc, r = (p[a] for a in ("c", "k", "beta", "f0", "omega", "x_c", "r"))

        def rhs(t, y):
            x, v = y[0], y[1]
            dy = np.empty(6)
            dy[0] = v
            dy[1] = -c * v - k * x - beta * x**3 + f0 * math.cos(w * t)
            a = -k - 3.0 * beta * x * x
            P = y[2:].reshape(2, 2)
            dy[2:4] = P[1]
            dy[4:6] = a * P[0] - c * P[1]
            return dy

        def stop(t, y):
            return y[0] - xc

        stop.terminal, stop.direction = True, 1.0
        y = np.concatenate([np.asarray(x0, dtype=float), np.eye(2).ravel()])
        t = float(t0)
        impacts = []
        while True:
            sol = solve_ivp(rhs, (t, t1), y, method="DOP853", rtol=self.rtol, atol=self.atol, events=[stop])
            if sol.status == -1:
                raise RuntimeError(f"solve_ivp failed at t = {sol.t[-1]}: {sol.message}")
            if sol.status == 0:
                return sol.y[:2, -1].copy(), sol.y[2:, -1].reshape(2, 2).copy(), impacts
            te, ye = sol.t_events[0][0], sol.y_events[0][0]
            x_minus = ye[:2]
            x_plus = np.array([x_minus[0], -r * x_minus[1]])
            G = np.diag([1.0, -r])
            hx = np.array([1.0, 0.0])
            f_minus, f_plus = self.field(te, x_minus), self.field(te, x_plus)
            S = G + np.outer(f_plus - G @ f_minus, hx) / (hx @ f_minus)  # eq. (9) with a reset
            y = np.concatenate([x_plus, (S @ ye[2:].reshape(2, 2)).ravel()])
            t = te
            impacts.append(te)
            if len(impacts) > 10_000:
                raise RuntimeError("too many impacts (chattering?)")

    def shoot(self, x0, *, tol: float = 1e-10, max_iter: int = 30):
        """Newton on the period map; returns (state, monodromy, multipliers, iterations, impact times)."""
        x = np.asarray(x0, dtype=float).copy()
        T = 2.0 * math.pi / self.p["omega"]
        for it in range(max_iter + 1):
            x1, M, impacts = self.flow(x, 0.0, T)
            r = x1 - x
            if np.linalg.norm(r) <= tol * (1.0 + np.linalg.norm(x)):
                return x, M, np.linalg.eigvals(M), it, impacts
            x = x + np.linalg.solve(M - np.eye(2), -r)
        raise RuntimeError(f"Newton did not converge in {max_iter} iterations")
