"""A rotor whose synchronous whirl lies on its clearance circle: the end of the free branch, located and classified.

The Jeffcott rotor with a snubber ring (Karpenko, Wiercigroch and Cartmell 2002), written as a user would from
the docs (``../shared/trial-models/jeffcott_snubber.py``, beside the checkout): states ``(x, y, vx, vy)``, free flight inside
``r = sqrt(x^2 + y^2) = delta`` and a contact force ``beta (1 - delta / r)`` outside; the field is continuous
across the circle, its Jacobian jumps.

Closed forms (derived here, independently of the library):

* the free synchronous whirl is ``x + i y = Z e^{i omega t}``, ``Z = rho omega^2 / (1 - omega^2 + 2 i zeta omega)``
  (gravity ``g = 0``), a circle of radius ``|Z|``; it lies on the clearance circle where ``|Z(omega)| = delta``
  (brentq), at ``omega = 0.820631087712087`` and ``1.407088466022592`` for the defaults;
* its multipliers are ``eig(expm(A T))`` of the free linear system;
* on the far side the orbits lie in contact all round: the one-sided limit ``M+`` is the solution of the
  variational equation along the same circle with the contact field's Jacobian at ``r = delta+``:
  ``beta / delta^2 [[x (x - mu y), y (x - mu y)], [x (mu x + y), y (mu x + y)]]`` added to the stiffness,
  integrated here with scipy.

No event marks the change (both orbits have no events); the branch's corrector fails where the free orbits
come to touch the circle all round, and the branch ends there with a special point whose bracket holds the
closed form, classified from ``M-`` and ``M+``: without friction a jump without crossing, with friction
``mu = 0.1`` a discontinuous Neimark-Sacker (a complex pair leaves the unit circle, modulus 1.18356); from
above the resonance, at 1.40709, a discontinuous fold (a real multiplier jumps from 0.80 to 33.6).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.optimize import brentq

from conftest import trial_model
from saltation import Flow
from saltation.branches.branch import Limits, SpecialPointKind
from saltation.branches.check import check_branch, unstable_count
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import ContinuationSettings, continue_branch



def trial_module():
    return trial_model("jeffcott_snubber")


def whirl_amplitude(q: dict, omega: float) -> complex:
    return q["rho"] * omega**2 / (1.0 - omega**2 + 2j * q["zeta"] * omega)


def onset(q: dict, lo: float = 0.5, hi: float = 1.0) -> float:
    """Where the free whirl's radius reaches the clearance (the root in ``[lo, hi]``)."""
    return brentq(lambda w: abs(whirl_amplitude(q, w)) - q["delta"], lo, hi, xtol=1e-15, rtol=1e-15)


def whirl_state(q: dict, omega: float) -> np.ndarray:
    z = whirl_amplitude(q, omega)
    return np.array([z.real, z.imag, (1j * omega * z).real, (1j * omega * z).imag])


def free_monodromy(q: dict, omega: float) -> np.ndarray:
    z = q["zeta"]
    A = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [-1, 0, -2 * z, 0], [0, -1, 0, -2 * z]], dtype=float)
    return expm(A * 2 * math.pi / omega)


def contact_side_monodromy(q: dict, omega: float) -> np.ndarray:
    """The variational equation along the whirl on the circle with the contact field's Jacobian (scipy)."""
    zeta, beta, delta, mu = q["zeta"], q["beta"], q["delta"], q["mu"]
    Z = whirl_amplitude(q, omega)

    def rhs(t, y):
        w = Z * np.exp(1j * omega * t)
        x1, x2 = w.real, w.imag
        K = beta / delta**2 * np.array([[x1 * (x1 - mu * x2), x2 * (x1 - mu * x2)],
                                        [x1 * (mu * x1 + x2), x2 * (mu * x1 + x2)]])
        J = np.zeros((4, 4))
        J[0, 2] = J[1, 3] = 1.0
        J[2:, :2] = -np.eye(2) - K
        J[2:, 2:] = -2 * zeta * np.eye(2)
        return (J @ y.reshape(4, 4)).ravel()

    sol = solve_ivp(rhs, (0.0, 2 * math.pi / omega), np.eye(4).ravel(), method="DOP853", rtol=1e-12, atol=1e-14)
    return sol.y[:, -1].reshape(4, 4)


def end_of_free_branch(mu: float, start: float, bounds: tuple[float, float]):
    system = trial_module().rotor(mu=mu)
    q = dict(system.defaults)
    flow = Flow(system)
    problem = ShootingProblem(flow, {"omega": start}, continuation_parameter="omega")
    direction = 1 if bounds[1] > start else -1
    branch = continue_branch(problem, whirl_state(q, start), start,
                             settings=ContinuationSettings(bounds=(min(bounds), max(bounds))), directions=(direction,))
    return q, branch


@pytest.mark.parametrize("mu, start, bounds, roots, kind", [
    (0.0, 0.75, (0.7, 0.9), (0.5, 1.0), SpecialPointKind.NONSMOOTH_NO_CROSSING),
    (0.1, 0.75, (0.7, 0.9), (0.5, 1.0), SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER),
    # from above the resonance, the free whirl grows onto the circle at 1.40709 from outside the contact branch's
    # reach: one contact multiplier jumps to 33.6, a discontinuous fold
    (0.0, 1.6, (1.6, 1.2), (1.0, 2.0), SpecialPointKind.DISCONTINUOUS_FOLD),
])
def test_the_free_whirl_ends_where_it_lies_on_the_clearance_circle(mu, start, bounds, roots, kind):
    q, branch = end_of_free_branch(mu, start, bounds)
    assert check_branch(branch).ok
    (sp,) = branch.special_points
    assert sp.kind is kind
    assert sp.limits is Limits.ON_SURFACE and sp.touch_surface == "gap" and sp.touch_mode == "free"
    assert sp.index == len(branch.points) - 1
    # bracketed between the last orbit the corrector reaches and a failure, to the location tolerance
    w = onset(q, *roots)
    lo, hi = sp.bracket
    assert lo <= w <= hi
    assert sp.accuracy >= hi - lo and hi - lo <= 1e-8
    # the one-sided limits at the boundary orbit: the default rtol 1e-10 over one period bounds their error
    # well within 1e-7 (|M| <= 1 on both sides: the damping is the same, the contact stiffness only turns them)
    np.testing.assert_allclose(sp.monodromy_minus, free_monodromy(q, sp.parameter), atol=1e-7)
    np.testing.assert_allclose(sp.monodromy_plus, contact_side_monodromy(q, sp.parameter), atol=1e-6)
    mu_minus = np.linalg.eigvals(free_monodromy(q, w))
    mu_plus = np.linalg.eigvals(contact_side_monodromy(q, w))
    assert unstable_count(sp.multipliers_minus, autonomous=False) == unstable_count(mu_minus, autonomous=False) == 0
    assert unstable_count(sp.multipliers_plus, autonomous=False) == unstable_count(mu_plus, autonomous=False)
    # the limit at the point's own parameter: the library integrates the variational equation along its dense
    # output (rtol 1e-10), and a multiplier of 33.6 of a non-normal matrix amplifies that: 1e-6 relative
    at_point = np.linalg.eigvals(contact_side_monodromy(q, sp.parameter))
    assert np.max(np.abs(at_point)) == pytest.approx(np.max(np.abs(sp.multipliers_plus)), rel=1e-6)
    if mu > 0:
        assert np.max(np.abs(mu_plus)) == pytest.approx(1.18356, abs=1e-5)  # the trial's value, to its digits
        assert abs(sp.crossing_point) == pytest.approx(1.0, abs=1e-9) and abs(sp.crossing_point.imag) > 0.1
