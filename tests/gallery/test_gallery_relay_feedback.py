"""The relay feedback system of di Bernardo, Johansson and Vasca (IJBC 11, 2001), x' = A x + B u,
y = x1, u = -sgn(y), against independent computations with matrix exponentials (numpy/scipy only).

* The symmetric unimodal self-oscillation: crossing the surface downwards at x0 = (0, x2, x3) it
  stays in y < 0 under u = +1 for half a period h and arrives at -x0,
  x(h) = E(h) x0 + A^-1 (E(h) - I) B = -x0 with E(h) = expm(A h). For a given h this is linear in
  x0: (E + I) x0 = -A^-1 (E - I) B; brentq on h for x0_1(h) = 0. Its monodromy is assembled from
  expm factors and the saltation matrices S = I + (f_after - f_before) C / (C f_before) of the two
  crossings (the perturbed orbit reaches the surface later by -C dx / (C f_before) and flows with
  the other field for that time, hence the rank-one correction).
* The onset of sliding along sigma: the same system with x2 = -1 at the crossing (there the arriving
  orbit meets the boundary of the sliding band |x2| < 1, where u_plus's field y' = x2 + 1 is tangent
  to the surface), fsolve for (x3, h, sigma).
* A sliding orbit below the onset: it arrives from y > 0 at (0, a2, a3) inside the band, slides with
  Filippov's field f_s = (I - B C) A x (u_eq = -C A x, so that C f_s = 0) until x2 = -1, where
  f_s = f_plus, and leaves into u_plus for a time h, arriving at -(0, a2, a3); fsolve for
  (a2, a3, tau, h). Its monodromy: expm factors, the entry's saltation matrix
  I + (f_s - f_minus) C / (C f_minus) and none at the exit (f_s = f_plus there).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from saltation import Flow, Tolerances
from saltation.branches.branch import SpecialPointKind
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.models.relay_feedback import DEFAULTS, relay_feedback
from saltation.orbits.shooting import ShootingProblem, find_periodic_orbit

pytestmark = pytest.mark.slow  # computes a gallery diagram (and the three-state engine)

ZETA, W, LAM, SIGMA = (DEFAULTS[k] for k in ("zeta", "w", "lam", "sigma"))
C = np.array([1.0, 0.0, 0.0])
I3 = np.eye(3)
EPS = np.finfo(float).eps


def matrices(sigma=SIGMA):
    A = np.array([[-(2 * ZETA * W + LAM), 1.0, 0.0], [-(2 * ZETA * W * LAM + W**2), 0.0, 1.0], [-LAM * W**2, 0.0, 0.0]])
    return A, np.array([1.0, -2.0 * sigma, 1.0])


def relay_flow(x, t, u, sigma=SIGMA):
    """The flow of x' = A x + B u (u constant) from x over the time t, in closed form."""
    A, B = matrices(sigma)
    E = expm(A * t)
    return E @ x + np.linalg.solve(A, (E - I3) @ B) * u


def field(x, u, sigma=SIGMA):
    A, B = matrices(sigma)
    return A @ x + B * u


def crossing_saltation(x, u_before, u_after, sigma=SIGMA):
    """S = I + (f_after - f_before) C / (C f_before) at a crossing of y = 0 at x."""
    f_b, f_a = field(x, u_before, sigma), field(x, u_after, sigma)
    return I3 + np.outer(f_a - f_b, C) / (C @ f_b)


def start_of_half_period(h, sigma=SIGMA):
    """x0 with x(h) = -x0 under u = +1 (linear in x0 for a given h)."""
    A, B = matrices(sigma)
    E = expm(A * h)
    return np.linalg.solve(E + I3, -np.linalg.solve(A, (E - I3) @ B))


def symmetric_orbit(sigma=SIGMA):
    """(x0, h): the downward crossing and the half period of the symmetric crossing orbit."""
    hs = np.linspace(0.5, 6.0, 551)  # its half period lies near pi / w (a closed-form scan, then brentq)
    g = np.array([start_of_half_period(h, sigma)[0] for h in hs])
    roots = []
    for k in np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]:
        h = brentq(lambda h: start_of_half_period(h, sigma)[0], hs[k], hs[k + 1], xtol=1e-15, rtol=4 * EPS)
        x0 = start_of_half_period(h, sigma)
        inside = [relay_flow(x0, t, 1.0, sigma)[0] for t in np.linspace(0.0, h, 402)[1:-1]]
        if x0[1] < -1 and max(inside) < 0:  # crosses (outside the sliding band) and stays in y < 0
            roots.append((x0, h))
    assert len(roots) == 1, roots
    return roots[0]


X0_REF, H_REF = symmetric_orbit()
T_REF = 2 * H_REF


def half_period_monodromy(x0, h, sigma=SIGMA):
    """From just before the downward crossing at x0 to just before the upward one at -x0."""
    A, _ = matrices(sigma)
    return expm(A * h) @ crossing_saltation(x0, -1.0, 1.0, sigma)


def reference_multipliers(x0, h, sigma=SIGMA):
    """The cycle: the upward crossing is the downward one mirrored (x -> -x, u -> -u)."""
    A, _ = matrices(sigma)
    M = expm(A * h) @ crossing_saltation(-x0, 1.0, -1.0, sigma) @ half_period_monodromy(x0, h, sigma)
    return np.sort_complex(np.linalg.eigvals(M))


def onset_residual(z):
    x3, h, sigma = z
    return start_of_half_period(h, sigma) - np.array([0.0, -1.0, x3])


@functools.lru_cache(maxsize=1)
def onset():
    """(x3, h, sigma) of the symmetric orbit that arrives at (0, -1, x3), the edge of the sliding band."""
    x0, h = symmetric_orbit(0.05)  # the crossing orbit just above the onset
    z = fsolve(onset_residual, [x0[2], h, 0.05], xtol=1e-14)
    assert np.abs(onset_residual(z)).max() < 1e-13
    return tuple(z)


@pytest.fixture(scope="module")
def flow():
    return Flow(relay_feedback())


@pytest.fixture(scope="module")
def orbit(flow):
    # a rough guess in y > 0, and a period guess: Newton does the rest. tol=1e-12 so that the
    # Newton residual, times the conditioning of the shooting Jacobian (|J^-1| = 2 here), stays far
    # below the 1e-9 of the comparisons
    return find_periodic_orbit(flow, [0.5, -4.0, -1.5], period=7.0, tol=1e-12)


def test_reference_is_a_relay_orbit():
    """Self-checks of the reference: periodic, symmetric, and the trivial multiplier 1."""
    assert abs(X0_REF[0]) < 1e-14
    np.testing.assert_allclose(relay_flow(X0_REF, H_REF, 1.0), -X0_REF, rtol=0, atol=1e-13)
    mu = reference_multipliers(X0_REF, H_REF)
    assert np.min(np.abs(mu - 1)) < 1e-12
    assert np.all(np.abs(mu) <= 1 + 1e-12)  # stable: a self-oscillation


def test_symmetric_orbit_against_closed_form(flow, orbit):
    # piecewise-affine modes are stepped with the exact flow (README), so the orbit is exact to
    # rounding, and the Newton residual (<= 1e-12 (1 + |u|)) bounds the rest: 1e-9 is the promise
    assert orbit.period == pytest.approx(T_REF, abs=1e-9)
    ev = orbit.trajectory.events
    assert [(e.kind.name, e.mode_from, e.mode_to) for e in ev] == [
        ("TRANSITION", "u_minus", "u_plus"), ("TRANSITION", "u_plus", "u_minus")]
    down, up = ev
    np.testing.assert_allclose(down.x_minus, X0_REF, rtol=0, atol=1e-9)
    np.testing.assert_allclose(up.x_minus, -X0_REF, rtol=0, atol=1e-9)
    assert up.t - down.t == pytest.approx(H_REF, abs=1e-9)
    # the state at t = 0: the reference orbit flowed back from its downward crossing (u = -1 before it)
    np.testing.assert_allclose(orbit.state0, relay_flow(X0_REF, -down.t, -1.0), rtol=0, atol=1e-9)
    # the saltation matrices against S = I + (f_after - f_before) C / (C f_before)
    np.testing.assert_allclose(down.saltation, crossing_saltation(X0_REF, -1.0, 1.0), rtol=0, atol=1e-9)
    np.testing.assert_allclose(up.saltation, crossing_saltation(-X0_REF, 1.0, -1.0), rtol=0, atol=1e-9)


def test_symmetric_orbit_monodromy_and_multipliers(orbit):
    A, _ = matrices()
    t_e = orbit.trajectory.events[0].t
    # from t = 0: u_minus until the downward crossing, u_plus for h, u_minus for the rest of the period
    M = expm(A * (H_REF - t_e)) @ crossing_saltation(-X0_REF, 1.0, -1.0) @ half_period_monodromy(X0_REF, H_REF) \
        @ expm(A * t_e)
    # entries of order 1-10, exact flows and saltation matrices on both sides: 1e-9 absolute
    np.testing.assert_allclose(orbit.monodromy, M, rtol=0, atol=1e-9)
    mu_ref = reference_multipliers(X0_REF, H_REF)  # independent of t_e (a cyclic permutation)
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), mu_ref, rtol=0, atol=1e-9)
    assert orbit.trivial_multiplier_error < 1e-9
    assert orbit.stable


@pytest.fixture(scope="module")
def branch(flow, orbit):
    """The symmetric orbit followed from sigma = 0.5 down to 0.03, through the onset of sliding."""
    problem = ShootingProblem(flow, {"sigma": SIGMA}, continuation_parameter="sigma")
    br = continue_branch(problem, np.append(orbit.state0, orbit.period), SIGMA,
                         settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.03, SIGMA)), directions=(-1,))
    return br, problem


def test_onset_of_sliding_against_independent_computation(branch):
    x3, h, sigma_star = onset()
    x_arrival = np.array([0.0, -1.0, x3])
    # a crossing orbit up to the onset: it stays in y < 0 over the half period, where u_plus's tangency
    # at the arrival is visible (y'' < 0 along u_plus: its orbit bends back into y < 0)
    A, _ = matrices(sigma_star)
    assert C @ A @ field(x_arrival, 1.0, sigma_star) < 0
    assert max(relay_flow(x_arrival, t, 1.0, sigma_star)[0] for t in np.linspace(0.0, h, 402)[1:-1]) < 0

    br, _ = branch
    points = [sp for sp in br.special_points if sp.bracket[0] != sp.bracket[1]]
    assert len(points) == 1, [(sp.kind, sp.parameter) for sp in br.special_points]
    (sp,) = points
    # both switches of the symmetric orbit meet the band's edge at once (two extra events on the sliding
    # side): a crossing-sliding at two points, located by its defining system (autonomous: the period an
    # unknown, with a phase condition)
    assert sp.kind is SpecialPointKind.CROSSING_SLIDING
    assert "at 2 points of the orbit at once" in sp.note
    assert sp.accuracy < 1e-9
    assert min(sp.bracket) - 1e-13 <= sigma_star <= max(sp.bracket) + 1e-13  # the reference is exact to ~1e-15
    assert sp.parameter == pytest.approx(sigma_star, abs=1e-9)
    sides = sorted((sorted(sp.event_labels_minus), sorted(sp.event_labels_plus)), key=len)  # the cycles, in any rotation
    assert sides == [
        ["u_minus -[y-]-> u_plus", "u_plus -[y+]-> u_minus"],
        ["leave y sliding -> u_minus", "leave y sliding -> u_plus", "slide on y (u_minus|u_plus)",
         "slide on y (u_plus|u_minus)"],
    ]
    # at the onset the downward crossing's saltation matrix is I - B C (C f_before = x2 - 1 = -2),
    # a projection along B: both sides have the multipliers of the boundary orbit, 0 among them
    mu_ref = reference_multipliers(x_arrival, h, sigma_star)
    assert np.min(np.abs(mu_ref)) < 1e-12
    for mu in (sp.multipliers_minus, sp.multipliers_plus):
        # the one-sided multipliers come from orbits within the bracket (< 1e-9 in sigma) of the onset,
        # and the multipliers are Lipschitz in sigma there (no square-root singularity: C f_before
        # stays -2), so they agree to the bracket times a moderate derivative
        np.testing.assert_allclose(np.sort_complex(mu), mu_ref, rtol=0, atol=1e-8)
        assert np.abs(np.sort_complex(mu) - mu_ref).max() <= sp.multipliers_accuracy  # and the library's own bound


SIGMA_SLIDING = 0.03


def sliding_flow(x, tau, sigma=SIGMA_SLIDING):
    """Filippov's sliding flow on y = 0: x' = (I - B C) A x (C B = 1), in closed form."""
    A, B = matrices(sigma)
    return expm((I3 - np.outer(B, C)) @ A * tau) @ np.asarray(x, dtype=float)


def sliding_orbit_residual(z, sigma=SIGMA_SLIDING):
    a2, a3, tau, h = z
    x_s = sliding_flow([0.0, a2, a3], tau, sigma)
    return np.concatenate([[x_s[1] + 1.0], relay_flow(x_s, h, 1.0, sigma) + np.array([0.0, a2, a3])])


def test_sliding_orbit_against_independent_computation(flow):
    """Below the onset the symmetric orbit slides at both switches."""
    x3, h_star, _ = onset()
    z = fsolve(sliding_orbit_residual, [-0.9, x3, 0.05, h_star], xtol=1e-13)  # started from the onset orbit
    assert np.abs(sliding_orbit_residual(z)).max() < 1e-13
    a2, a3, tau, h = z
    assert -1 < a2 < 1 and tau > 0  # it arrives inside the sliding band
    x_a = np.array([0.0, a2, a3])

    tight = Tolerances(rtol=1e-12, atol=1e-14)
    orbit = find_periodic_orbit(flow, [0.5, -1.0, -1.0], parameters={"sigma": SIGMA_SLIDING}, period=6.5, tol=1e-12,
                                tolerances=tight)
    ev = orbit.trajectory.events
    assert sorted((e.kind.name, e.mode_from) for e in ev) == [
        ("SLIDING_END", "u_minus"), ("SLIDING_END", "u_plus"), ("SLIDING_START", "u_minus"), ("SLIDING_START", "u_plus")]
    entry = next(e for e in ev if e.kind.name == "SLIDING_START" and e.mode_from == "u_minus")
    exit_ = next(e for e in ev if e.kind.name == "SLIDING_END" and e.mode_to == "u_plus")
    # DOP853 along the sliding motions at rtol 1e-12 (exact flows elsewhere): the library's own
    # estimate of the end state's error is ~1e-11; 1e-9 leaves the conditioning of the shooting
    # problem a factor 100
    assert flow.integration_error(orbit.trajectory, tight) < 1e-10
    assert orbit.period == pytest.approx(2 * (tau + h), abs=1e-9)
    assert (exit_.t - entry.t) % orbit.period == pytest.approx(tau, abs=1e-9)
    np.testing.assert_allclose(entry.x_minus, x_a, rtol=0, atol=1e-9)
    np.testing.assert_allclose(exit_.x_minus, sliding_flow(x_a, tau), rtol=0, atol=1e-9)

    # the monodromy: the entry's saltation matrix maps onto the surface (C S = 0), the exit has none
    A, B = matrices(SIGMA_SLIDING)
    f_s = (I3 - np.outer(B, C)) @ A @ x_a
    f_minus = field(x_a, -1.0, SIGMA_SLIDING)
    S_entry = I3 + np.outer(f_s - f_minus, C) / (C @ f_minus)
    np.testing.assert_allclose(entry.saltation, S_entry, rtol=0, atol=1e-9)
    np.testing.assert_allclose(exit_.saltation, I3, rtol=0, atol=1e-9)
    half = expm(A * h) @ expm((I3 - np.outer(B, C)) @ A * tau) @ S_entry  # the second half is its mirror image
    mu_ref = np.sort_complex(np.linalg.eigvals(half @ half))
    assert np.min(np.abs(mu_ref - 1)) < 1e-12 and np.min(np.abs(mu_ref)) < 1e-12
    # the monodromy is carried along the sliding motion by DOP853 with its error controlled too
    # (control_variational): 1e-9 as for the state
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), mu_ref, rtol=0, atol=1e-9)
