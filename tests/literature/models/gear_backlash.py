"""A spur gear pair with backlash: a single-degree-of-freedom oscillator with a dead zone.

Kahraman and Singh, "Non-linear dynamics of a spur gear pair", J. Sound Vib. 142 (1990) 49-75, and
"Interactions between time-varying mesh stiffness and clearance non-linearities in a geared system",
J. Sound Vib. 146 (1991) 135-156, with a constant mesh stiffness: the dynamic transmission error ``x`` (scaled by
the half backlash) obeys

    x'' + 2 zeta x' + f(x) = F_m + F_a cos(omega t),   f(x) = x - b (x > b), 0 (|x| <= b), x + b (x < -b).

Three modes: ``drive`` (the teeth in contact on the drive side), ``free`` (the gap: no contact) and ``back``
(back-side contact).  Parameters after Kahraman and Singh: ``zeta = 0.05``, the mean load ``F_m = 0.1``, the
alternating load ``F_a = 0.05``, ``b = 1``.

Reference (numpy/scipy only).  Each mode is linear in ``z = (x, v, cos omega t, sin omega t, 1)``; its flow is a
matrix exponential, the contact instants are located by ``brentq`` on the closed-form ``x(t)``.  The restoring
force is continuous at ``x = +-b``, so every saltation matrix is the identity and the period map's derivative is
the product of the modes' ``exp(A dt)`` (their ``(x, v)`` block).  The linear drive-side response
``x = b + F_m + A cos(omega t - theta)``, ``A = F_a / sqrt((1 - omega^2)^2 + (2 zeta omega)^2)``, loses contact
(grazes ``x = b`` from the contact side) where ``A = F_m``: two frequencies either side of the resonance, in closed
form, and so is its curve in a second parameter (the lower root in ``omega`` as the mean load ``F_m`` varies).
Between them the teeth separate once a period and the resonance bends to lower frequencies (softening):
the folds are the solutions of periodicity plus ``det(DP - I) = 0`` (``fsolve`` on the reference map).
"""

from __future__ import annotations

import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, LocusStep, Orbit, SweepStep
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from saltation import Crossing, Mode, PiecewiseSystem, Transition

RISING, FALLING = Crossing.RISING, Crossing.FALLING
DEFAULTS = {"zeta": 0.05, "F_m": 0.1, "F_a": 0.05, "b": 1.0, "omega": 0.6}


def gear_pair(**overrides) -> PiecewiseSystem:
    load = "F_m + F_a*cos(omega*t)"
    return PiecewiseSystem(
        name="literature_gear_backlash",
        states=["x", "v"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("drive", ["v", f"-2*zeta*v - (x - b) + {load}"], domain=["x - b > 0"]),
            Mode("back", ["v", f"-2*zeta*v - (x + b) + {load}"], domain=["x + b < 0"]),
            Mode("free", ["v", f"-2*zeta*v + {load}"]),
        ],
        surfaces={"drive_side": "x - b", "back_side": "x + b"},
        transitions=[  # a region-based model: each boundary listed both ways
            Transition("free", "drive_side", RISING, "drive"),
            Transition("drive", "drive_side", FALLING, "free"),
            Transition("free", "back_side", FALLING, "back"),
            Transition("back", "back_side", RISING, "free"),
        ],
        period="2*pi/omega",
    )


# --- the reference: matrix exponentials and brentq -------------------------------------------------------------


def _generators(p) -> dict[str, np.ndarray]:
    z, w, Fm, Fa, b = p["zeta"], p["omega"], p["F_m"], p["F_a"], p["b"]
    out = {}
    for mode, (k, offset) in {"drive": (1.0, b), "free": (0.0, 0.0), "back": (1.0, -b)}.items():
        A = np.zeros((5, 5))
        A[0, 1] = 1.0
        A[1] = [-k, -2.0 * z, Fa, 0.0, Fm + k * offset]
        A[2, 3], A[3, 2] = -w, w
        out[mode] = A
    return out


def _mode_of(x: float, b: float) -> str:
    return "drive" if x > b else ("back" if x < -b else "free")


def period_map(p, x0, with_jacobian: bool = False):
    """The stroboscopic map from ``t = 0`` over one forcing period, and its derivative."""
    G = _generators(p)
    b, T = p["b"], 2.0 * np.pi / p["omega"]
    n = 100  # scan steps per period for the contact instants (each phase here lasts far longer than T / 100)
    dt = T / n
    steps = {m: expm(A * dt) for m, A in G.items()}
    z = np.array([x0[0], x0[1], 1.0, 0.0, 1.0])
    mode = _mode_of(z[0], b) if z[0] != b else ("drive" if z[1] > 0 else "free")
    J, t = np.eye(2), 0.0
    surfaces = {"drive": [b], "free": [b, -b], "back": [-b]}
    while t < T - 1e-14:
        h = min(dt, T - t)
        E = steps[mode] if h == dt else expm(G[mode] * h)
        z1 = E @ z
        hit = None
        for s in surfaces[mode]:
            # a sign change over the step (the orbits here do not dip through a surface within T / 100)
            if (z1[0] - s) * (z[0] - s) < 0.0 and abs(z[0] - s) > 1e-13:
                A, z_start = G[mode], z.copy()
                tau = brentq(lambda u, A=A, z_start=z_start, s=s: (expm(A * u) @ z_start)[0] - s, 0.0, h,
                             xtol=1e-15, rtol=1e-15)
                if hit is None or tau < hit[0]:
                    hit = (tau, s)
        if hit is None:
            J = E[:2, :2] @ J
            z, t = z1, t + h
            continue
        tau, s = hit
        E = expm(G[mode] * tau)
        z = E @ z
        z[0] = s
        J = E[:2, :2] @ J
        t += tau
        mode = "free" if mode != "free" else ("drive" if s > 0 else "back")
    return (z[:2], J) if with_jacobian else z[:2]


def fixed_point(p, guess):
    x = fsolve(lambda u: period_map(p, u) - u, guess, xtol=1e-14)
    y, J = period_map(p, x, with_jacobian=True)
    assert np.max(np.abs(y - x)) < 1e-11
    return x, J


def linear_state(p) -> np.ndarray:
    """The drive-side harmonic response at t = 0 (valid while it stays in contact)."""
    z, w, Fm, Fa, b = p["zeta"], p["omega"], p["F_m"], p["F_a"], p["b"]
    c = Fa / complex(1.0 - w * w, 2.0 * z * w)  # x = b + F_m + Re(c e^{i w t})
    return np.array([b + Fm + c.real, -w * c.imag])


def grazing_frequencies(p) -> list[float]:
    """``A(omega) = F_m``: ``(1 - w^2)^2 + 4 zeta^2 w^2 = (F_a / F_m)^2``, a quadratic in ``w^2``."""
    z, Fm, Fa = p["zeta"], p["F_m"], p["F_a"]
    roots = np.roots([1.0, 4.0 * z * z - 2.0, 1.0 - (Fa / Fm) ** 2])
    return sorted(float(np.sqrt(r)) for r in roots.real if r > 0)


def fold(p, omega, state):
    """A fold of the reference branch: periodicity and ``det(DP - I) = 0`` by ``fsolve`` from a nearby guess."""

    def residual(u):
        q = dict(p, omega=u[2])
        y, J = period_map(q, u[:2], with_jacobian=True)
        return [*(y - u[:2]), np.linalg.det(J - np.eye(2))]

    u = fsolve(residual, [*state, omega], xtol=1e-13)
    assert np.max(np.abs(residual(u))) < 1e-10
    return float(u[2])


def _lower_grazing_in_F_m(F_m: float) -> float:
    """The curve of the lower grazing: the smaller root of the quadratic at the mean load ``F_m``."""
    return grazing_frequencies(dict(DEFAULTS, F_m=F_m))[0]


def _expected() -> list[Expected]:
    p = dict(DEFAULTS)
    low, high = grazing_frequencies(p)
    # the folds from rough guesses (two digits) of the turning points of the resonance
    upper = fold(p, 0.75, [1.23, 0.02])
    lower = fold(p, 0.45, [0.45, 0.40])
    return [
        Expected(("grazing",), low, 1e-9),  # closed form; the location's own accuracy is added
        Expected(("grazing",), high, 1e-9),
        Expected(("fold",), upper, 1e-8),  # fsolve to 1e-13 on the reference map; the location ~1e-9
        Expected(("fold",), lower, 1e-8),
    ]


def _sweep_on_the_resonance(result) -> None:
    """Between the upper fold and the upper grazing only the separating orbit exists: after the transient every
    sample is one fixed point of the reference map, stable by the reference's multipliers."""
    for k, omega in enumerate(result.values):
        p = dict(DEFAULTS, omega=omega)
        pts = np.asarray(result.at(k), dtype=float)
        assert len(pts) == 5
        np.testing.assert_allclose(pts, np.broadcast_to(pts[-1], pts.shape), rtol=0, atol=1e-8)
        y, J = period_map(p, pts[-1], with_jacobian=True)
        np.testing.assert_allclose(y, pts[-1], rtol=0, atol=1e-8)  # a fixed point of the reference map
        assert np.max(np.abs(np.linalg.eigvals(J))) < 1.0


CASE = LiteratureCase(
    name="gear_backlash",
    field="mechanics",
    source="Kahraman and Singh, J. Sound Vib. 142 (1990) and 146 (1991) (spur gear pair with backlash)",
    model=gear_pair,
    orbit=Orbit(parameters=dict(DEFAULTS), guess=[1.1, 0.0], multipliers=lambda p: np.linalg.eigvals(
        fixed_point(dict(p), linear_state(p))[1]), state=linear_state),
    branch=BranchStep("omega", (0.4, 1.4), _expected, ds_max=0.05),
    # the lower grazing (contact loss below the resonance) continued in the mean load: F_a / F_m from 0.71 to 0.33;
    # each point of the curve is a grazing solved to the shooting tolerance (1e-10), a few 1e-10 in omega
    locus=LocusStep("grazing", "F_m", (0.07, 0.15), _lower_grazing_in_F_m, tol=1e-8),
    sweep=SweepStep("omega", [0.9, 1.0, 1.1], _sweep_on_the_resonance,
                    options={"x0": [1.1, 0.0], "periods": 5, "transient": 300}),
)
