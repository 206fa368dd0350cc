"""An impact oscillator with a pre-stressed elastic stop: a forced linear oscillator meeting a preloaded support.

After Ing, Pavlovskaia, Wiercigroch and Banerjee (Phil. Trans. R. Soc. A 366 (2008) 679-705, experiments, and
Physica D 239 (2010) 312-321, bifurcations near grazing), the oscillator with a one-sided elastic constraint at the
gap ``e``, here with the support spring pre-stressed (preload ``P_0``), so that the contact force jumps to ``P_0``
when the mass reaches the stop:

    x'' + 2 zeta x' + x = a cos(omega t)                               (x < e, free flight)
    x'' + 2 zeta x' + x + beta (x - e) + P_0 = a cos(omega t)        (x > e, in contact)

A Filippov-type discontinuity: the field jumps by ``-P_0`` across ``x = e``.  Both fields have ``h' = v`` on the
surface, so there is no sliding; the saltation matrix of a crossing at velocity ``v`` is
``[[1, 0], [-+P_0 / v, 1]]``, unbounded at grazing.  Parameters: ``zeta = 0.05``, ``beta = 10``, ``P_0 = 0.2``,
``e = 1``, ``a = 0.5``.

Reference (numpy/scipy only).  Each mode is linear in ``z = (x, v, cos omega t, sin omega t, 1)``: its flow is a
matrix exponential, the crossings of ``x = e`` are located by ``brentq`` on it, and the derivative of the period map
is the product of the modes' ``(x, v)`` blocks and the saltation matrices above.  The free orbit
``x = A cos(omega t - theta)``, ``A = a / sqrt((1 - omega^2)^2 + (2 zeta omega)^2)``, grazes the stop where
``A = e``: in closed form, and so is its curve in the gap ``e`` (the lower root in ``omega``).
"""

from __future__ import annotations

import itertools

import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, LocusStep, Orbit, SweepStep
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from saltation import Crossing, Mode, PiecewiseSystem, Transition

RISING, FALLING = Crossing.RISING, Crossing.FALLING
DEFAULTS = {"zeta": 0.05, "beta": 10.0, "P_0": 0.2, "e": 1.0, "a": 0.5, "omega": 0.8}


def prestressed_stop(**overrides) -> PiecewiseSystem:
    forcing = "a*cos(omega*t)"
    return PiecewiseSystem(
        name="literature_prestressed_stop",
        states=["x", "v"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("contact", ["v", f"-2*zeta*v - x - beta*(x - e) - P_0 + {forcing}"], domain=["x - e > 0"]),
            Mode("free", ["v", f"-2*zeta*v - x + {forcing}"]),
        ],
        surfaces={"stop": "x - e"},
        transitions=[  # a region-based model: the boundary listed both ways
            Transition("free", "stop", RISING, "contact"),
            Transition("contact", "stop", FALLING, "free"),
        ],
        period="2*pi/omega",
    )


# --- the reference: matrix exponentials, brentq and the saltation matrices in closed form ---------------------


def _generators(p) -> dict[str, np.ndarray]:
    z, w, a, beta, e, P0 = (p[k] for k in ("zeta", "omega", "a", "beta", "e", "P_0"))
    out = {}
    for mode, (k, c) in {"free": (1.0, 0.0), "contact": (1.0 + beta, beta * e - P0)}.items():
        A = np.zeros((5, 5))
        A[0, 1] = 1.0
        A[1] = [-k, -2.0 * z, a, 0.0, c]
        A[2, 3], A[3, 2] = -w, w
        out[mode] = A
    return out


def period_map(p, x0, with_jacobian: bool = False, n: int = 200):
    """The stroboscopic map from ``t = 0`` over one forcing period, and its derivative."""
    G = _generators(p)
    e, P0, T = p["e"], p["P_0"], 2.0 * np.pi / p["omega"]
    dt = T / n  # scan step for the crossings (each phase of the orbits here lasts far longer)
    steps = {m: expm(A * dt) for m, A in G.items()}
    z = np.array([x0[0], x0[1], 1.0, 0.0, 1.0])
    mode = "contact" if z[0] > e else "free"
    J, t = np.eye(2), 0.0
    while t < T - 1e-14:
        h = min(dt, T - t)
        E = steps[mode] if h == dt else expm(G[mode] * h)
        z1 = E @ z
        if (z1[0] - e) * (z[0] - e) >= 0.0 or abs(z[0] - e) <= 1e-13:
            J, z, t = E[:2, :2] @ J, z1, t + h
            continue
        A, start = G[mode], z.copy()
        tau = brentq(lambda u, A=A, start=start: (expm(A * u) @ start)[0] - e, 0.0, h, xtol=1e-15, rtol=1e-15)
        E = expm(A * tau)
        z = E @ z
        z[0] = e
        jump = -P0 if mode == "free" else P0  # the field's jump f+ - f- in the v component
        S = np.array([[1.0, 0.0], [jump / z[1], 1.0]])
        J = S @ E[:2, :2] @ J
        t += tau
        mode = "contact" if mode == "free" else "free"
    return (z[:2], J) if with_jacobian else z[:2]


def fixed_point(p, guess):
    x = fsolve(lambda u: period_map(p, u) - u, guess, xtol=1e-14)
    y, J = period_map(p, x, with_jacobian=True)
    assert np.max(np.abs(y - x)) < 1e-11
    return x, J


def free_state(p) -> np.ndarray:
    z, w, a = p["zeta"], p["omega"], p["a"]
    c = a / complex(1.0 - w * w, 2.0 * z * w)  # x = Re(c e^{i w t})
    return np.array([c.real, -w * c.imag])


def grazing_frequencies(p) -> list[float]:
    """``A(omega) = e``: ``(1 - w^2)^2 + 4 zeta^2 w^2 = (a / e)^2``, a quadratic in ``w^2``."""
    z, a, e = p["zeta"], p["a"], p["e"]
    roots = np.roots([1.0, 4.0 * z * z - 2.0, 1.0 - (a / e) ** 2])
    return sorted(float(np.sqrt(r)) for r in roots.real if r > 0)


def _lower_grazing_in_e(e: float) -> float:
    """The curve of the lower grazing: the smaller root of the quadratic at the gap ``e``."""
    return grazing_frequencies(dict(DEFAULTS, e=e))[0]


def _solve(p, omega, state, sign):
    """Periodicity and ``det(DP - sign I) = 0`` (a fold for +1, a period doubling for -1) by ``fsolve``."""

    def residual(u):
        y, J = period_map(dict(p, omega=u[2]), u[:2], with_jacobian=True)
        return [*(y - u[:2]), np.linalg.det(J - sign * np.eye(2))]

    u = fsolve(residual, [*state, omega], xtol=1e-13)
    assert np.max(np.abs(residual(u))) < 1e-10
    return float(u[2])


def _expected() -> list[Expected]:
    p = dict(DEFAULTS)
    low, high = grazing_frequencies(p)
    return [
        Expected(("grazing",), low, 1e-9),  # closed form; the location's own accuracy is added
        Expected(("grazing",), high, 1e-9),
        # fsolve to 1e-13 on the reference map from two-digit guesses; the location ~1e-9
        Expected(("period_doubling",), _solve(p, 0.86, [1.09, 0.39], -1.0), 1e-8),
        Expected(("fold",), _solve(p, 1.41, [-2.8, 3.3], 1.0), 1e-8),
    ]


def _sweep_follows_the_map(result) -> None:
    """Each sample is the reference map's image of the one before; at omega = 0.8 (beyond the period doubling)
    the attractor is a period-2 orbit, at omega = 1 the stable period-1 orbit."""
    for k, (omega, period) in enumerate(zip(result.values, (2, 1), strict=True)):
        p = dict(DEFAULTS, omega=omega)
        pts = np.asarray(result.at(k), dtype=float)
        assert len(pts) == 6
        for a, b in itertools.pairwise(pts):
            # one period amplifies the samples' rounding by at most |DP| ~ 10
            np.testing.assert_allclose(period_map(p, a), b, rtol=0, atol=1e-7)
        distinct = {tuple(np.round(x, 6)) for x in pts}
        assert len(distinct) == period


CASE = LiteratureCase(
    name="prestressed_stop",
    field="mechanics",
    source="Ing, Pavlovskaia, Wiercigroch and Banerjee, Phil. Trans. R. Soc. A 366 (2008), Physica D 239 (2010) "
           "(impact oscillator with a one-sided elastic constraint), with a pre-stressed support",
    model=prestressed_stop,
    orbit=Orbit(parameters=dict(DEFAULTS), guess=[1.0, 0.5], multipliers=lambda p: np.linalg.eigvals(
        fixed_point(dict(p), [1.06, 0.28])[1]), state=lambda p: fixed_point(dict(p), [1.06, 0.28])[0]),
    branch=BranchStep("omega", (0.5, 1.5), _expected, ds_max=0.05),
    # the lower grazing (first contact with the stop below the resonance) continued in the gap: a / e from 0.67 to
    # 0.33; each point of the curve is a grazing solved to the shooting tolerance (1e-10)
    locus=LocusStep("grazing", "e", (0.75, 1.5), _lower_grazing_in_e, tol=1e-8),
    sweep=SweepStep("omega", [0.8, 1.0], _sweep_follows_the_map,
                    options={"x0": [1.0, 0.5], "periods": 6, "transient": 400}),
)
