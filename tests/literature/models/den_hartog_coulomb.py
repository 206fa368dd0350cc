"""Den Hartog's forced oscillator with Coulomb friction (a Filippov system).

Den Hartog, "Forced vibrations with combined Coulomb and viscous friction", Trans. ASME 53 (APM-53-9), 107-115
(1931), the case without viscous friction: ``m x'' + k x + F sgn(x') = P cos(omega t)``, here with ``m = k = 1``
(time in units of ``1/omega_n``, ``omega`` the frequency ratio).  Written as on paper with ``sign(v)``; the
integrator sticks (slides on ``v = 0``) where ``|x - P cos(omega t)| < F``.

Reference (closed form, independent of saltation).  The symmetric non-sticking period-1 motion slips forward for
half a period ``tau = pi / omega`` from the turning point ``x = -X`` and back for the other half.  In the forward
half, with ``s`` the time since the turning point and the forcing ``P cos(omega s + phi)``,
``x = -F + Q cos(omega s + phi) + A cos s + B sin s`` with ``Q = P / (1 - omega^2)``.  The four conditions
``x(0) = -X, x'(0) = 0, x(tau) = X, x'(tau) = 0`` give ``B = Q omega sin phi``, ``A = B cot(tau/2)``,
``sin phi = F tan(tau/2) / (Q omega)``, ``X = -Q cos phi``, so Den Hartog's amplitude

    X = sqrt(Q^2 - (F U)^2),  U = tan(pi / (2 omega)) / omega.

The motion does not stop at the turning point while the spring and forcing there beat the friction,
``X + P cos(phi) > F``, i.e. ``omega^2 X > F``: Den Hartog's boundary of non-stop motion is ``omega^2 X = F``,

    F_b / P = 1 / ((1 - omega^2) sqrt(1 / omega^4 + U^2)).

The monodromy is ``D R(tau) D R(tau)``: ``R`` the rotation of the undamped oscillator over a half period and
``D = diag(1, a+ / a-)`` the saltation matrix at a reversal of the velocity (the accelerations just after and
just before, ``omega^2 X -+ F``), so ``det M = ((omega^2 X - F) / (omega^2 X + F))^2`` vanishes at the onset of
sticking.  There the orbit arrives at ``v = 0`` where the field beyond is tangent, its second derivative
``-P omega sin(phi) > 0`` (for ``1/2 < omega < 1``): the tangency is visible, a crossing-sliding bifurcation.
"""

from __future__ import annotations

import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, LocusStep, Orbit, SweepStep

from saltation import Mode, PiecewiseSystem

DEFAULTS = {"F": 0.5, "P": 1.0, "omega": 0.8}


def den_hartog(**overrides) -> PiecewiseSystem:
    return PiecewiseSystem(
        name="literature_den_hartog_coulomb",
        states=["x", "v"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("slip", ["v", "-x - F*sign(v) + P*cos(omega*t)"])],
        surfaces={},
        transitions=[],
        period="2*pi/omega",
    )


# --- the reference: Den Hartog's closed form ------------------------------------------------------------------


def _phases(p):
    F, P, w = p["F"], p["P"], p["omega"]
    tau = np.pi / w
    Q = P / (1.0 - w * w)
    U = np.tan(tau / 2.0) / w
    X = np.sqrt(Q * Q - (F * U) ** 2)
    sin_phi, cos_phi = F * np.tan(tau / 2.0) / (Q * w), -X / Q
    return F, P, w, tau, Q, X, sin_phi, cos_phi


def amplitude(p) -> float:
    """Den Hartog's amplitude of the non-stop motion."""
    return float(_phases(p)[5])


def boundary(omega: float, P: float = 1.0) -> float:
    """Den Hartog's boundary of non-stop motion: the friction level ``F`` where ``omega^2 X = F``."""
    U = np.tan(np.pi / (2.0 * omega)) / omega
    return P / ((1.0 - omega * omega) * np.sqrt(1.0 / omega**4 + U * U))


def monodromy(p) -> np.ndarray:
    F, _, w, tau, _, X, _, _ = _phases(p)
    R = np.array([[np.cos(tau), np.sin(tau)], [-np.sin(tau), np.cos(tau)]])
    D = np.diag([1.0, (w * w * X - F) / (w * w * X + F)])
    return D @ R @ D @ R


def multipliers(p) -> np.ndarray:
    return np.linalg.eigvals(monodromy(p))


def _half(p, s):
    """The forward slip half, ``s`` in ``[0, tau]`` after the turning point ``x = -X``: ``(x, v)``."""
    F, _, w, tau, Q, _, sin_phi, cos_phi = _phases(p)
    B = Q * w * sin_phi
    A = B / np.tan(tau / 2.0)
    phi = np.arctan2(sin_phi, cos_phi)
    x = -F + Q * np.cos(w * s + phi) + A * np.cos(s) + B * np.sin(s)
    v = -Q * w * np.sin(w * s + phi) - A * np.sin(s) + B * np.cos(s)
    return np.array([x, v])


def state(p) -> np.ndarray:
    """The orbit at the forcing phase ``t = 0``: ``omega s + phi = 0`` modulo ``2 pi``."""
    _, _, w, tau, _, _, sin_phi, cos_phi = _phases(p)
    s = np.mod(-np.arctan2(sin_phi, cos_phi) / w, 2.0 * tau)
    return _half(p, s) if s <= tau else -_half(p, s - tau)


def _onset() -> list[Expected]:
    p = dict(DEFAULTS)
    # the forward half slips throughout (no intermediate stop) below the boundary: checked on the closed form
    s = np.linspace(1e-6, np.pi / p["omega"] - 1e-6, 2001)
    assert np.all(_half(dict(p, F=boundary(p["omega"]) - 1e-3), s)[1] > 0.0)
    # closed form to rounding; the located point's own accuracy is added by the runner
    return [Expected(("crossing_sliding",), boundary(p["omega"], p["P"]), 1e-9)]


def _sweep_is_den_hartog(result) -> None:
    """Below the boundary the stroboscopic samples after the transient are Den Hartog's motion at t = 0."""
    for k, F in enumerate(result.values):
        ref = state(dict(DEFAULTS, F=F))
        pts = np.asarray(result.at(k), dtype=float)
        assert len(pts) == 5
        # the slowest multiplier of the three values is |r| <= 0.67 per period: 300 periods leave < 1e-12
        np.testing.assert_allclose(pts, np.broadcast_to(ref, pts.shape), rtol=0, atol=1e-7)


CASE = LiteratureCase(
    name="den_hartog_coulomb",
    field="mechanics; Filippov benchmark",
    source="Den Hartog, Trans. ASME 53 (1931) (forced oscillator with Coulomb friction)",
    model=den_hartog,
    orbit=Orbit(parameters=dict(DEFAULTS), guess=[2.0, 0.0], multipliers=multipliers, state=state),
    branch=BranchStep("F", (0.2, 0.85), _onset, ds_max=0.02),
    locus=LocusStep("crossing_sliding", "omega", (0.7, 0.9), boundary, tol=1e-8),
    sweep=SweepStep("F", [0.2, 0.35, 0.5], _sweep_is_den_hartog,
                    options={"x0": [0.0, 0.0], "periods": 5, "transient": 300}),
)
