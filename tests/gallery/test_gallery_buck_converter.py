"""The buck converter under voltage-mode ramp control (``saltation.models.buck_converter``) against an
independent closed-form computation (numpy and scipy only).

Time is in units of the ramp period T.  Both modes are linear, ``x' = A x + s b`` with ``x = (i, v)``,
``A = [[0, -T/L], [T/C, -T/(R C)]]`` and ``b = (T E / L, 0)``, so each segment is a matrix exponential
(``expm`` of the augmented matrix ``[[A, b], [0, 0]]``).  With ``v_con = a (v - V_ref)`` and the ramp
``V_L + (V_U - V_L) tau``, the period-1 orbit in the regulated range starts each period OFF (the ramp's
foot lies below ``v_con``), turns ON at ``tau = d`` where the ramp overtakes ``v_con``, and is turned OFF
by the ramp's reset at ``tau = 1``.  So

* ``x0 = (I - e^A)^-1 c(1 - d)``, with ``c(s) = int_0^s e^{A u} b du`` (periodicity, for each ``d``), and
  ``d`` the root of ``h(x(d), d) = a (v(d) - V_ref) - V_L - (V_U - V_L) d`` (brentq);
* the monodromy of the stroboscopic map is ``M = e^{A (1 - d)} S e^{A d}`` with the saltation matrix of
  the state- and time-dependent switch, ``S = I + (f+ - f-) h_x / (h_x f- + h_t)``, ``h_x = (0, a)``,
  ``h_t = -(V_U - V_L)``, ``f+ - f- = b``; the reset of the ramp happens at a fixed time and has no
  saltation (``S = I``);
* in the model's phase-augmented form ``(i, v, tau)``, the monodromy from the phase ``tau0`` is the
  product of ``blockdiag(e^{A s}, 1)`` and the two saltation matrices written out in three dimensions
  (the reset ``g = (i, v, 0)`` on ``tau = 1``: ``S = g_x + (f+ - g_x f-) e_tau^T``);
* the period doubling is where ``det(M + I) = 0`` (brentq in ``E``);
* below ``E = V_ref + V_L / a`` the switch stays ON: the period-1 orbit is the ON mode's equilibrium
  ``(E / R, E)``; the OFF interval shrinks to zero there (a border collision), and the one-sided
  monodromies are ``e^A`` (saturated) and ``e^A S`` with ``S`` at that equilibrium.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

from saltation import Flow
from saltation.branches.branch import SpecialPointKind
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.models.buck_converter import DEFAULTS, buck_converter
from saltation.orbits.shooting import ShootingProblem, find_periodic_orbit

pytestmark = pytest.mark.slow  # computes a gallery diagram

R, L, C, V_REF, GAIN, V_L, V_U, T = (DEFAULTS[k] for k in ("R", "L", "C", "V_ref", "a", "V_L", "V_U", "T"))
A = np.array([[0.0, -T / L], [T / C, -T / (R * C)]])
H_X = np.array([0.0, GAIN])  # the ramp surface's gradient in (i, v)
H_T = -(V_U - V_L)  # and its rate in the phase
EPS = np.finfo(float).eps


def b_on(E):
    return np.array([T * E / L, 0.0])


def segment(x, s, E, on):
    """The state after a time ``s`` in the ON or OFF mode from ``x``, and ``e^{A s}``."""
    aug = np.zeros((3, 3))
    aug[:2, :2] = A
    if on:
        aug[:2, 2] = b_on(E)
    P = expm(aug * s)
    return P[:2, :2] @ x + P[:2, 2], P[:2, :2]


def ramp(x, tau):
    """v_con - V_r: positive while the switch is OFF."""
    return GAIN * (x[1] - V_REF) - V_L - (V_U - V_L) * tau


E_A = expm(A)  # one period's e^A


def start_state(d, E):
    """The state at tau = 0 of the period-1 orbit that is OFF on (0, d) and ON on (d, 1)."""
    c, _ = segment(np.zeros(2), 1.0 - d, E, True)
    return np.linalg.solve(np.eye(2) - E_A, c)


def switching_residual(d, E):
    x_d, _ = segment(start_state(d, E), d, E, False)
    return ramp(x_d, d)


def reference_orbit(E):
    """``(d, x0, x_d)``: the switching phase, the state at tau = 0 and at the switch."""
    grid = np.linspace(1e-9, 1.0 - 1e-9, 21)
    g = np.array([switching_residual(d, E) for d in grid])
    (k,) = np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]  # exactly one switching phase
    d = brentq(switching_residual, grid[k], grid[k + 1], args=(E,), xtol=1e-15, rtol=4 * EPS)
    x0 = start_state(d, E)
    return d, x0, segment(x0, d, E, False)[0]


def ramp_saltation(x_d, E):
    """``I + (f+ - f-) h_x / (h_x f- + h_t)`` at the OFF -> ON switch (2 x 2, the stroboscopic view)."""
    f_minus = A @ x_d
    f_plus = f_minus + b_on(E)
    return np.eye(2) + np.outer(f_plus - f_minus, H_X) / (H_X @ f_minus + H_T)


def monodromy(E):
    """The monodromy of the stroboscopic map (from tau = 0) and the orbit ``(d, x0, x_d)``."""
    d, x0, x_d = reference_orbit(E)
    _, e_off = segment(x0, d, E, False)
    _, e_on = segment(x_d, 1.0 - d, E, True)
    return e_on @ ramp_saltation(x_d, E) @ e_off, (d, x0, x_d)


def lifted(e_as):
    """``blockdiag(e^{A s}, 1)``: a segment's fundamental matrix in (i, v, tau)."""
    P = np.eye(3)
    P[:2, :2] = e_as
    return P


def monodromy_3d(E, tau0):
    """The monodromy in (i, v, tau) of the period from phase ``tau0`` (OFF at tau0 < d), both saltation
    matrices derived in three dimensions."""
    d, _, x_d = reference_orbit(E)
    assert 0.0 < tau0 < d
    x_1, _ = segment(x_d, 1.0 - d, E, True)  # just before the reset

    def f_off(x):
        return np.append(A @ x, 1.0)

    def f_on(x):
        return np.append(A @ x + b_on(E), 1.0)

    def e(s):
        return lifted(expm(A * s))

    h_x = np.array([0.0, GAIN, -(V_U - V_L)])  # the ramp surface in (i, v, tau)
    s_ramp = np.eye(3) + np.outer(f_on(x_d) - f_off(x_d), h_x) / (h_x @ f_off(x_d))
    g_x = np.diag([1.0, 1.0, 0.0])  # the reset (i, v, tau) -> (i, v, 0) on tau - 1 = 0 (h_x = e_tau)
    s_clock = g_x + np.outer(f_off(x_1) - g_x @ f_on(x_1), [0.0, 0.0, 1.0]) / 1.0  # h_x f- = tau' = 1
    return e(tau0) @ s_clock @ e(1.0 - d) @ s_ramp @ e(d - tau0)


def flip_test(E):
    M, _ = monodromy(E)
    return np.linalg.det(M + np.eye(2))


E_ORBIT = 20.0
E_PD = brentq(flip_test, 24.0, 25.0, xtol=1e-15, rtol=4 * EPS)
E_BC = V_REF + V_L / GAIN  # below it the duty cycle saturates at 1


def nontrivial(mu):
    """The multipliers without the one closest to 1 (the phase's)."""
    mu = np.asarray(mu)
    return np.delete(mu, np.argmin(np.abs(mu - 1.0)))


def same_multipliers(mu, ref):
    return np.sort_complex(np.asarray(mu, dtype=complex)), np.sort_complex(np.asarray(ref, dtype=complex))


@pytest.fixture(scope="module")
def flow():
    return Flow(buck_converter())


def test_reference_orbit_switches_twice_per_period():
    """The closed-form orbit is the one the model describes: OFF before d, ON after, no other crossing."""
    for E in (15.0, E_ORBIT, E_PD):
        d, x0, x_d = reference_orbit(E)
        off = [ramp(segment(x0, s, E, False)[0], s) for s in np.linspace(0.0, d, 100, endpoint=False)]
        on = [ramp(segment(x_d, s - d, E, True)[0], s) for s in np.linspace(d, 1.0, 100)[1:]]
        assert min(off) > 0.0 and max(on) < 0.0
        assert ramp(x0, 0.0) > 0.0  # the reset turns the switch OFF
    assert 0.4 < reference_orbit(E_ORBIT)[0] < 0.41


def test_period_one_orbit_against_closed_form(flow):
    """State, switching instants, monodromy and multipliers of the period-1 orbit at E = 20 V.

    Both modes are affine, so the integrator steps with their exact flow and locates the events to near
    machine precision (README, *Integration settings*); shooting converges to |r| <= 1e-12 (1 + |u|) and
    the orbit is hyperbolic (|mu| about 0.82), so the state is known to some 1e-11. The reference is exact
    to rounding (expm, brentq to 4 eps). 1e-10 on states, times and matrix entries states that.
    """
    orbit = find_periodic_orbit(flow, [0.6, 12.0, 0.2], parameters={"E": E_ORBIT}, period=1.0, tol=1e-12)
    d, x0, _ = reference_orbit(E_ORBIT)
    tau0 = orbit.state0[2]
    assert 0.0 < tau0 < d  # the phase condition keeps the start near the guess: in the OFF interval
    x_tau0, _ = segment(x0, tau0, E_ORBIT, False)
    np.testing.assert_allclose(orbit.state0[:2], x_tau0, rtol=0, atol=1e-10)
    assert orbit.period == pytest.approx(1.0, abs=1e-12)
    # the switch turns ON at d T = 160.9 us into the ramp's period, OFF at its reset
    assert [e.surface for e in orbit.events] == ["ramp", "clock"]
    np.testing.assert_allclose([e.t for e in orbit.events], [d - tau0, 1.0 - tau0], rtol=0, atol=1e-10)
    assert d * T == pytest.approx(160.94e-6, abs=1e-8)
    np.testing.assert_allclose(orbit.monodromy, monodromy_3d(E_ORBIT, tau0), rtol=0, atol=1e-10)
    M, _ = monodromy(E_ORBIT)
    np.testing.assert_allclose(*same_multipliers(nontrivial(orbit.multipliers), np.linalg.eigvals(M)), rtol=0, atol=1e-10)
    assert np.min(np.abs(orbit.multipliers - 1.0)) < 1e-12  # the phase's
    assert orbit.stable


@pytest.fixture(scope="module")
def branch(flow):
    problem = ShootingProblem(flow, {"E": E_ORBIT}, continuation_parameter="E")
    start = find_periodic_orbit(flow, [0.6, 12.0, 0.2], parameters={"E": E_ORBIT}, period=1.0)
    return continue_branch(problem, problem.pack(start.state0, start.period), E_ORBIT,
                           settings=ContinuationSettings(bounds=(E_ORBIT, 26.0), tol=1e-12), directions=(1,))


def test_period_doubling_against_closed_form(branch):
    """The smooth flip of the period-1 orbit, located by continuation in E, against brentq on det(M + I).

    The detector locates the flip test prod(mu + 1) to 1e-9 in (u, E) (``locate_tol``), and the
    multipliers it tests are exact to about 1e-10 (see below), against a slope d(mu)/dE of 0.23 per volt
    there: 1e-9 in E states what the method promises.  The multipliers at the located point are then
    within 0.23 * 1e-9 + 1e-10 of the closed form's at E_PD: 1e-9.
    """
    kinds = [sp.kind for sp in branch.special_points]
    assert kinds == [SpecialPointKind.PERIOD_DOUBLING]  # no border collision between 20 V and 26 V
    (pd,) = branch.special_points
    assert pd.accuracy <= 1e-9
    assert pd.parameter == pytest.approx(E_PD, abs=1e-9)
    assert E_PD == pytest.approx(24.5166, abs=1e-4)
    mu = nontrivial(pd.multipliers)
    assert np.min(np.abs(mu + 1.0)) < 1e-9
    M, _ = monodromy(E_PD)
    np.testing.assert_allclose(*same_multipliers(mu, np.linalg.eigvals(M)), rtol=0, atol=1e-9)
    assert all(p.stable for p in branch.points if p.parameter < E_PD - 1e-6)
    assert not any(p.stable for p in branch.points if p.parameter > E_PD + 1e-6)


def test_branch_multipliers_against_closed_form(branch):
    """Every few branch points: the multipliers against the closed-form monodromy at that E.

    The flow is exact (rounding only); the corrector stops at |r| <= 1e-12 (1 + |z|), about 3e-11, and
    ||(M - I)^-1|| stays below 0.75 on this branch (every multiplier is negative or complex), so the states
    are known to some 5e-11 and the multipliers, through the switch's saltation matrix, to 1e-10."""
    assert branch.parameter.max() == pytest.approx(26.0)
    for point in branch.points[::5]:
        M, _ = monodromy(point.parameter)
        np.testing.assert_allclose(*same_multipliers(nontrivial(point.multipliers), np.linalg.eigvals(M)),
                                   rtol=0, atol=1e-10)
        assert point.period == pytest.approx(1.0, abs=1e-12)


def test_saturation_border_collision_against_closed_form(flow):
    """Below E = V_ref + V_L / a the switch stays ON (duty cycle 1): the OFF interval shrinks to zero there
    and the monodromy jumps from e^A S to e^A (a discontinuous bifurcation without crossing: S has
    determinant 1 and both pairs are complex, so the magnitudes stay 0.82).  Located by bisection on the
    event sequence to 1e-9 in (u, E) (``locate_tol``).  (With the default steps; with ds_max = 0.5 the
    corrector's Newton iteration cycles across the kink at the first bisection step, and the point is
    reported with a bracket 0.5 V wide.)"""
    problem = ShootingProblem(flow, {"E": 12.5}, continuation_parameter="E")
    start = find_periodic_orbit(flow, [0.55, 11.8, 0.2], parameters={"E": 12.5}, period=1.0)
    low = continue_branch(problem, problem.pack(start.state0, start.period), 12.5,
                          settings=ContinuationSettings(bounds=(11.5, 12.5), tol=1e-12), directions=(-1,))
    (bc,) = low.special_points
    assert bc.kind is SpecialPointKind.NONSMOOTH_NO_CROSSING
    assert bc.accuracy <= 1e-9
    assert bc.parameter == pytest.approx(E_BC, abs=1e-9)
    saturated = low.points[-1]
    assert saturated.event_labels == ("on -[clock+]-> on",)
    np.testing.assert_allclose(saturated.state[:2], [saturated.parameter / R, saturated.parameter], rtol=0, atol=1e-10)
    x_bc = np.array([E_BC / R, E_BC])  # the ON equilibrium, on the ramp's foot
    saturated_mu = np.linalg.eigvals(E_A)
    regulated_mu = np.linalg.eigvals(E_A @ ramp_saltation(x_bc, E_BC))
    # the side with the OFF interval comes first (the branch runs down in E)
    assert bc.event_labels_minus == ("on -[clock+]-> off", "off -[ramp-]-> on") and bc.event_labels_plus == saturated.event_labels
    # the saturated side: only the reset, whose saltation is the identity in (i, v); exact to rounding
    np.testing.assert_allclose(*same_multipliers(nontrivial(bc.multipliers_plus), saturated_mu), rtol=0, atol=1e-10)
    # the regulated side's limit, from the nearest orbit, as accurate as the point claims (1.6e-6)
    assert bc.multipliers_accuracy < 1e-5
    np.testing.assert_allclose(*same_multipliers(nontrivial(bc.multipliers_minus), regulated_mu), rtol=0,
                               atol=bc.multipliers_accuracy)
    assert np.abs(regulated_mu) == pytest.approx(np.abs(saturated_mu), abs=1e-12)
