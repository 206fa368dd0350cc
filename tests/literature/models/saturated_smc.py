"""Sliding-mode control with a saturated actuator (a boundary layer) of an unstable plant under a periodic load.

Slotine, *Sliding controller design for non-linear systems*, Int. J. Control 40 (1984) 421-434, and Slotine
and Li, *Applied Nonlinear Control*, Prentice Hall 1991, section 7.2 (the boundary layer: ``sgn(s)`` replaced
by ``sat(s / phi)``); Utkin, *Sliding Modes in Control and Optimization*, Springer 1992.  A linearised
inverted pendulum (``k < 0``) with light damping, a set-point ``r`` and a periodic disturbance:

    y'' + c y' + k y = u + D cos(omega t),    u = -U sat(s / phi),    s = y' + lam (y - r).

Three affine modes with a continuous field: ``linear`` (``|s| < phi``, ``u = -U s / phi``), ``sat_minus``
(``s > phi``, ``u = -U``) and ``sat_plus`` (``s < -phi``, ``u = +U``); the saltation matrices are the
identity, only the Jacobian jumps.  The actuator's limit ``U`` bounds the disturbance the loop can reject:
the stable forced orbit saturates as ``D`` grows and is lost at a fold, where it meets an unstable orbit
that lives in ``sat_minus`` (near the plant's saddle ``y = -U / k``).  The set-point ``r != 0`` breaks the
odd symmetry, so only the upper boundary is reached.

Reference (numpy/scipy only): in each mode ``x' = A x + b + e D cos(omega t)`` has the closed-form solution
``x(t) = x_p(t) + e^{A (t - t0)} (x0 - x_p(t0))`` with ``x_p = -A^{-1} b + P cos(omega t) + Q sin(omega t)``,
``(omega^2 I + A^2) Q = omega D e``, ``P = -A Q / omega``; the switching times are the roots of
``s(t) -+ phi`` (a scan and ``brentq``).  The monodromy is the product of the ``e^{A_i dt_i}`` (identity
saltation matrices).  Where the orbit stays in one mode it is that mode's forced response,
``x = x_eq + Re(X e^{i omega t})`` with ``X = D (i omega I - A)^{-1} e``, so its grazings of ``s = phi`` are
in closed form: ``D_g = |phi - s_eq| / |C (i omega I - A)^{-1} e|`` (``C = [lam, 1]``).  The fold solves
``P(x, D) = x``, ``det(DP - I) = 0`` for ``(x, D)`` (``fsolve`` on the reference map).
"""

from __future__ import annotations

import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, LocusStep, Orbit, SweepStep
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from saltation import Crossing, Mode, PiecewiseSystem, Transition

RISING, FALLING = Crossing.RISING, Crossing.FALLING
DEFAULTS = {"k": -1.0, "c": 0.2, "U": 1.0, "lam": 1.0, "phi": 0.2, "r": 0.1, "D": 0.5, "omega": 1.0}


def saturated_smc(**overrides) -> PiecewiseSystem:
    plant = "-k*y - c*v + D*cos(omega*t)"
    s = "v + lam*(y - r)"
    return PiecewiseSystem(
        name="literature_saturated_smc",
        states=["y", "v"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("sat_minus", ["v", f"{plant} - U"], domain=[f"{s} - phi > 0"]),
            Mode("sat_plus", ["v", f"{plant} + U"], domain=[f"{s} + phi < 0"]),
            Mode("linear", ["v", f"{plant} - U*({s})/phi"]),
        ],
        surfaces={"upper": f"{s} - phi", "lower": f"{s} + phi"},
        transitions=[  # region-based: every boundary both ways
            Transition("linear", "upper", RISING, "sat_minus"),
            Transition("sat_minus", "upper", FALLING, "linear"),
            Transition("linear", "lower", FALLING, "sat_plus"),
            Transition("sat_plus", "lower", RISING, "linear"),
        ],
        period="2*pi/omega",
    )


# --- the reference: matrix exponentials and brentq ---------------------------------------------------

E = np.array([0.0, 1.0])  # where the control and the disturbance enter


def _modes(p) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    k, c, U, lam, phi, r = (p[n] for n in ("k", "c", "U", "lam", "phi", "r"))
    A_sat = np.array([[0.0, 1.0], [-k, -c]])
    A_lin = np.array([[0.0, 1.0], [-k - U * lam / phi, -c - U / phi]])
    return {
        "sat_minus": (A_sat, np.array([0.0, -U])),
        "sat_plus": (A_sat, np.array([0.0, U])),
        "linear": (A_lin, np.array([0.0, U * lam * r / phi])),
    }


def _s(x, p) -> float:
    return float(x[1] + p["lam"] * (x[0] - p["r"]))


def _mode_of(x, p) -> str:
    s = _s(x, p)
    return "sat_minus" if s > p["phi"] else ("sat_plus" if s < -p["phi"] else "linear")


def _particular(mode: str, p):
    """The mode's periodic particular solution ``x_p(t)`` and its matrix ``A``."""
    A, b = _modes(p)[mode]
    w = p["omega"]
    Q = np.linalg.solve(w * w * np.eye(2) + A @ A, w * p["D"] * E)
    P = -A @ Q / w
    xc = -np.linalg.solve(A, b)
    return (lambda s: xc + P * np.cos(w * s) + Q * np.sin(w * s)), A


def _flow(mode: str, t0: float, x0: np.ndarray, t: float, p) -> np.ndarray:
    """The closed-form solution of one mode from ``(t0, x0)`` at ``t``."""
    xp, A = _particular(mode, p)
    return xp(t) + expm(A * (t - t0)) @ (np.asarray(x0, float) - xp(t0))


# the surfaces each mode watches: (offset of s, the mode entered)
_EXITS = {"linear": [(1.0, "sat_minus"), (-1.0, "sat_plus")], "sat_minus": [(1.0, "linear")],
          "sat_plus": [(-1.0, "linear")]}


def period_map(x0, p, t0: float = 0.0, n_grid: int = 400):
    """``(P(x0), DP(x0), events)``: one forcing period from ``t0``; a scan of ``n_grid`` steps per period
    brackets every crossing of ``s = +-phi`` (transversal ones: the reference is for regular orbits)."""
    T = 2 * np.pi / p["omega"]
    t, x, mode = t0, np.asarray(x0, float), _mode_of(x0, p)
    M, events, h = np.eye(2), [], T / n_grid
    while t < t0 + T:
        xp, A = _particular(mode, p)
        step = expm(A * h)
        hit, ta, xa = None, t, x
        while hit is None and ta < t0 + T:
            tb = min(ta + h, t0 + T)
            xb = xp(tb) + (step if tb - ta == h else expm(A * (tb - ta))) @ (xa - xp(ta))
            for a, target in _EXITS[mode]:
                ga, gb = _s(xa, p) - a * p["phi"], _s(xb, p) - a * p["phi"]
                if ga * gb < 0.0 and not (ta == t and abs(ga) < 1e-12):  # not the surface just crossed
                    g = lambda tt, a=a, ta=ta, xa=xa: _s(_flow(mode, ta, xa, tt, p), p) - a * p["phi"]
                    root = brentq(g, ta, tb, xtol=1e-15, rtol=1e-15)
                    if hit is None or root < hit[0]:
                        hit = (root, target)
            ta, xa = tb, xb
        t1 = hit[0] if hit else t0 + T
        M = expm(_modes(p)[mode][0] * (t1 - t)) @ M
        x, t = _flow(mode, t, x, t1, p), t1
        if hit:
            events.append((t1, mode, hit[1]))
            mode = hit[1]
    return x, M, events


def fixed_point(p, x0) -> tuple[np.ndarray, np.ndarray]:
    """The orbit's state at ``t = 0`` by Newton on the reference map, and its monodromy."""
    x = np.asarray(x0, float)
    for _ in range(50):
        y, M, _ = period_map(x, p)
        dx = np.linalg.solve(M - np.eye(2), x - y)
        x = x + dx
        if np.linalg.norm(dx) < 1e-14 * (1.0 + np.linalg.norm(x)):
            break
    return x, period_map(x, p)[1]


def forced_response(mode: str, p) -> tuple[np.ndarray, complex]:
    """A mode's own periodic response: its equilibrium and the complex amplitude of ``s``."""
    A, b = _modes(p)[mode]
    x_eq = -np.linalg.solve(A, b)
    X = np.linalg.solve(1j * p["omega"] * np.eye(2) - A, p["D"] * E)
    return x_eq, complex(p["lam"] * X[0] + X[1])


def grazing_D(mode: str, p) -> float:
    """The ``D`` at which the one-mode orbit of ``mode`` touches ``s = phi`` (closed form: ``s`` is linear
    in ``D`` about the mode's equilibrium)."""
    x_eq, S = forced_response(mode, dict(p, D=1.0))
    return abs(p["phi"] - _s(x_eq, p)) / abs(S)


def fold_D(p, x_guess=(0.3, 0.2), D_guess=1.05) -> float:
    """The fold: ``P(x, D) = x`` and ``det(DP - I) = 0`` for ``(x, D)`` (``fsolve``, xtol 1e-14)."""
    def equations(z):
        q = dict(p, D=z[2])
        y, M, _ = period_map(z[:2], q)
        return [*(y - z[:2]), np.linalg.det(M - np.eye(2))]

    z = fsolve(equations, [*x_guess, D_guess], xtol=1e-14)
    assert np.max(np.abs(equations(z))) < 1e-11
    return float(z[2])


def _special_points() -> list[Expected]:
    p = dict(DEFAULTS)
    return [
        # the stable orbit's excursion from the linear band touches s = phi: closed form
        Expected(("grazing",), grazing_D("linear", p), 1e-9),
        # the stable orbit (two events a period) meets the unstable one
        Expected(("fold",), fold_D(p), 1e-8),
        # the unstable orbit leaves sat_minus for the band, with the same closed form in sat_minus
        Expected(("grazing",), grazing_D("sat_minus", p), 1e-9),
    ]


def _grazing_in_omega(omega: float) -> float:
    return grazing_D("linear", dict(DEFAULTS, omega=omega))


SWEEP_D = [0.6, 0.9, 1.03]


def _sweep_on_the_fixed_points(result) -> None:
    """After the transient every section state is the reference map's fixed point (the stable orbit: one
    point a period, below the fold)."""
    assert not result.failures, result.failures
    x = np.array([0.2, 0.1])
    for k, D in enumerate(SWEEP_D):
        x, _ = fixed_point(dict(DEFAULTS, D=D), x)
        states = result.at(k)
        assert len(states) == 20
        # the least stable multiplier is at most 0.24 here: 60 transient periods leave nothing; the section
        # states are as good as the integration's rtol 1e-10
        np.testing.assert_allclose(states, np.tile(x, (len(states), 1)), rtol=0, atol=1e-8)


CASE = LiteratureCase(
    name="saturated_smc",
    field="control",
    source="Slotine 1984; Slotine and Li 1991 (sliding-mode control with a boundary layer); Utkin 1992",
    model=saturated_smc,
    orbit=Orbit(
        parameters=dict(DEFAULTS),
        guess=[0.17, 0.07],  # the linear band's forced response at D = 0.5, to two decimals
        multipliers=lambda p: np.linalg.eigvals(fixed_point(p, [0.17, 0.07])[1]),
        state=lambda p: fixed_point(p, [0.17, 0.07])[0],
    ),
    branch=BranchStep("D", (0.5, 1.2), _special_points),
    locus=LocusStep("grazing", "omega", (0.8, 1.3), _grazing_in_omega, tol=1e-8),
    sweep=SweepStep("D", SWEEP_D, _sweep_on_the_fixed_points,
                    options={"x0": [0.2, 0.1], "transient": 60, "periods": 20, "start": "own"}),
)
