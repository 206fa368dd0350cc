"""A relay with hysteresis around the plant ``G(s) = K / (s + 1)^3``: Astrom's relay autotuner.

Astrom and Hagglund, *Automatic tuning of simple regulators with specifications on phase and amplitude
margins*, Automatica 20 (1984) 645-651 (the relay experiment with hysteresis); Astrom, *Oscillations in
systems with relay feedback*, IMA Vol. Math. Appl. 74 (1995) 1-25 (the limit cycle by matrix
exponentials); Johansson, Rantzer and Astrom, *Fast switches in relay feedback systems*, Automatica 35
(1999) 539-552.  The plant in observer form (``y = x1``):

    x' = A x + B u,   A = [[-3, 1, 0], [-3, 0, 1], [-1, 0, 0]],   B = [0, 0, K]^T,   y = x1,

under a relay with hysteresis: ``u`` turns to ``-1`` when ``y`` rises through ``+eps`` and to ``+1`` when
``y`` falls through ``-eps``.  The relay's output is memory: the two modes ``plus`` and ``minus`` have no
domains, and an orbit starts in a named mode (``mode0``).  The system is odd (``x -> -x`` swaps the
modes and the two thresholds).

Reference (numpy/scipy only): the symmetric limit cycle switches to ``minus`` at ``x0`` (``y = eps``) and
reaches ``-x0`` after the half period ``h``, so ``(I + e^{Ah}) x0 = A^{-1}(e^{Ah} - I) B``; ``h`` solves
``C x0(h) = eps`` (``brentq``).  The half-period map's derivative is ``S e^{Ah}`` with the saltation matrix
``S = I + (f+ - f-) C / (C f-)`` at the switch (``f-+ = A x0 +- B``; the one at ``-x0`` is the same
matrix by the symmetry), and the monodromy ``(S e^{Ah})^2``.  With ``CB = 0`` there is no sliding and no
fast switch; the cycle is stable over the whole range ``0 < eps < K`` (no special point on the branch).
"""

from __future__ import annotations

import numpy as np
from corpus import BranchStep, LiteratureCase, Orbit, SweepStep
from scipy.linalg import expm
from scipy.optimize import brentq

from saltation import Crossing, Mode, PiecewiseSystem, Symmetry, Transition

DEFAULTS = {"K": 2.0, "eps": 0.1}


def relay_hysteresis(**overrides) -> PiecewiseSystem:
    def field(u: str) -> list[str]:
        return ["-3*x1 + x2", "-3*x1 + x3", f"-x1 + K*({u})"]

    return PiecewiseSystem(
        name="literature_relay_hysteresis",
        states=["x1", "x2", "x3"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("plus", field("1")), Mode("minus", field("-1"))],  # memory: no domains
        surfaces={"hi": "x1 - eps", "lo": "x1 + eps"},
        transitions=[
            Transition("plus", "hi", Crossing.RISING, "minus"),
            Transition("minus", "lo", Crossing.FALLING, "plus"),
        ],
        symmetry=Symmetry.of_signs([-1, -1, -1]),
    )


# --- the reference: matrix exponentials and brentq ---------------------------------------------------

A = np.array([[-3.0, 1.0, 0.0], [-3.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
C = np.array([1.0, 0.0, 0.0])


def _B(p) -> np.ndarray:
    return np.array([0.0, 0.0, p["K"]])


def _x0(h: float, p) -> np.ndarray:
    """The state at the switch to ``minus`` of the symmetric cycle of half period ``h``."""
    E = expm(A * h)
    return np.linalg.solve(np.eye(3) + E, np.linalg.solve(A, (E - np.eye(3)) @ _B(p)))


def _y_minus(t: float, x0: np.ndarray, p) -> float:
    """``y`` a time ``t`` after the switch to ``u = -1`` at ``x0``."""
    E = expm(A * t)
    return float(C @ (E @ x0 - np.linalg.solve(A, (E - np.eye(3)) @ _B(p))))


def half_period(p) -> float:
    """The first root of ``C x0(h) = eps`` that is a genuine cycle: ``y`` rising at the switch, and above
    ``-eps`` in between (``brentq`` to rounding)."""
    g = lambda h: float(C @ _x0(h, p)) - p["eps"]
    grid = np.arange(0.05, 40.0, 0.05)
    values = [g(h) for h in grid]
    for a, b, ga, gb in zip(grid[:-1], grid[1:], values[:-1], values[1:]):
        if ga * gb < 0.0:
            h = brentq(g, a, b, xtol=1e-15, rtol=1e-15)
            x0 = _x0(h, p)
            rising = C @ (A @ x0 + _B(p)) > 0.0
            inside = min(_y_minus(t, x0, p) for t in np.linspace(0.0, h, 200)[1:-1]) > -p["eps"]
            if rising and inside:
                return h
    raise ValueError(f"no symmetric cycle at {p}")


def half_map_jacobian(p) -> np.ndarray:
    h = half_period(p)
    x0 = _x0(h, p)
    f_minus, f_plus = A @ x0 + _B(p), A @ x0 - _B(p)
    S = np.eye(3) + np.outer(f_plus - f_minus, C) / (C @ f_minus)
    return S @ expm(A * h)


def multipliers(p) -> np.ndarray:
    """The nontrivial Floquet multipliers: the monodromy ``(S e^{Ah})^2`` without its eigenvalue 1."""
    H = half_map_jacobian(p)
    mu = np.linalg.eigvals(H @ H)
    return np.delete(mu, int(np.argmin(np.abs(mu - 1.0))))


def y_max(p) -> float:
    """The largest output of the cycle: the maximum of ``y`` after the switch at ``x0`` (scipy's bounded
    minimiser on the closed form, to 1e-12 in time; ``y'`` vanishes there, so ``y`` is right to rounding)."""
    from scipy.optimize import minimize_scalar

    h = half_period(p)
    x0 = _x0(h, p)
    ts = np.linspace(0.0, h, 400)
    k = int(np.argmax([_y_minus(t, x0, p) for t in ts]))
    lo, hi = ts[max(k - 1, 0)], ts[min(k + 1, len(ts) - 1)]
    r = minimize_scalar(lambda t: -_y_minus(t, x0, p), bounds=(lo, hi), method="bounded",
                        options={"xatol": 1e-12})
    return -r.fun


def _guess(p) -> list[float]:
    """The natural guess: the cycle's state half-way through its ``plus`` half, rounded to 2 decimals."""
    h = half_period(p)
    x0 = -_x0(h, p)  # the switch to plus
    E = expm(A * h / 2)
    x = E @ x0 + np.linalg.solve(A, (E - np.eye(3)) @ _B(p))
    return [round(float(v), 2) for v in x]


SWEEP_EPS = [0.2, 0.6, 1.0]


def _sweep_maxima_on_the_cycle(result) -> None:
    """After the transient every sampled maximum of ``y = x1`` is the reference cycle's largest output."""
    assert not result.failures, result.failures
    for k, eps in enumerate(SWEEP_EPS):
        y = result.at(k)[:, 0]
        assert len(y) >= 10
        reference = y_max(dict(DEFAULTS, eps=eps))
        # the maxima come from the dense output at the integration's rtol 1e-10
        np.testing.assert_allclose(y, reference, rtol=0, atol=1e-8)


CASE = LiteratureCase(
    name="relay_hysteresis",
    field="control",
    source="Astrom and Hagglund 1984; Astrom 1995; Johansson, Rantzer and Astrom 1999 (relay with hysteresis)",
    model=relay_hysteresis,
    orbit=Orbit(
        parameters=dict(DEFAULTS),
        guess=_guess(DEFAULTS),
        period=round(2 * half_period(DEFAULTS), 1),
        mode0="plus",
        multipliers=lambda p: multipliers(p),
    ),
    # the cycle stays stable from eps = 0.1 to 1.5 (K = 2): the reference has no special point there
    branch=BranchStep("eps", (0.02, 1.5), list, ds=0.05, ds_max=0.1),
    sweep=SweepStep("eps", SWEEP_EPS, _sweep_maxima_on_the_cycle,
                    options={"x0": [0.5, 0.0, 0.0], "mode0": "plus", "transient": 60, "periods": 20,
                             "period": 5.0}),
)
