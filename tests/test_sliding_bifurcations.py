"""Sliding bifurcations of the forced friction oscillator x'' + 2 zeta x' + x = -F sgn(x' - v_b) + a cos(w t),
against independent computations.

* grazing-sliding: the slower-than-belt harmonic response x = F + A cos(w t - phi) reaches the velocity
  A w at its fastest, so it grazes the sliding surface x' = v_b at v_b = A w;
* crossing-sliding: the sticking orbit in closed form. It arrives at the surface at (t_e, x_e), sticks
  (x = x_e + v_b (t - t_e)) until the slower side's field turns tangent
  (-2 zeta v_b - x + F + a cos(w t) = 0), then moves as the linear oscillator with the force +F
  (closed form by the eigenvectors of A) until x' = v_b again. Periodicity plus the crossing-sliding
  condition -2 zeta v_b - x_e - F + a cos(w t_e) = 0 (the faster side's field tangent where the orbit
  arrives), solved by fsolve for (t_e, x_e, v_b).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq, fsolve

from saltation import Flow
from saltation.branch import SpecialPointKind
from saltation.continuation import ContinuationSettings, continue_branch
from saltation.models import friction_oscillator
from saltation.models.friction_oscillator import DEFAULTS
from saltation.shooting import ShootingProblem

ZETA, F, AF, W = (DEFAULTS[k] for k in ("zeta", "F", "a", "omega"))
T = 2 * np.pi / W
A = np.array([[0.0, 1.0], [-1.0, -2 * ZETA]])
D = (1 - W**2) ** 2 + (2 * ZETA * W) ** 2
AMPLITUDE = AF / np.sqrt(D)
V_GRAZING_SLIDING = AMPLITUDE * W
EIGENVALUES, EIGENVECTORS = np.linalg.eig(A)
EIGENVECTORS_INV = np.linalg.inv(EIGENVECTORS)


def slow_response(t):
    """The particular solution of x'' + 2 zeta x' + x = F + a cos(w t)."""
    t = np.asarray(t, dtype=float)
    c, s = AF * (1 - W**2) / D, AF * 2 * ZETA * W / D
    return np.array([F + c * np.cos(W * t) + s * np.sin(W * t), W * (-c * np.sin(W * t) + s * np.cos(W * t))])


def slow_flow(y, t_from, ts):
    """The slower-than-belt mode's flow from (t_from, y) at the times ts, shape (len(ts), 2)."""
    tau = np.asarray(ts) - t_from
    E = np.einsum("ij,mj,jk->mik", EIGENVECTORS, np.exp(np.outer(tau, EIGENVALUES)), EIGENVECTORS_INV).real
    return slow_response(ts).T + E @ (np.asarray(y) - slow_response(t_from))


def sticking_orbit_residual(z):
    t_e, x_e, v_b = z
    slower_field = lambda t: -2 * ZETA * v_b - (x_e + v_b * (t - t_e)) + F + AF * np.cos(W * t)  # noqa: E731
    t_x = brentq(slower_field, t_e, t_e + T, xtol=1e-15, rtol=4 * np.finfo(float).eps)  # sticking ends
    y_x = [x_e + v_b * (t_x - t_e), v_b]
    ts = t_x + np.linspace(1e-9, T, 4001)
    v = slow_flow(y_x, t_x, ts)[:, 1] - v_b
    k = np.nonzero((v[:-1] < 0) & (v[1:] >= 0))[0][0]
    t_h = brentq(lambda t: slow_flow(y_x, t_x, [t])[0, 1] - v_b, ts[k], ts[k + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps)
    x_h = slow_flow(y_x, t_x, [t_h])[0, 0]
    faster_field = -2 * ZETA * v_b - x_e - F + AF * np.cos(W * t_e)
    return [t_h - t_e - T, x_h - x_e, faster_field]


@pytest.fixture(scope="module")
def branch():
    flow = Flow(friction_oscillator())
    phi = np.arctan2(2 * ZETA * W, 1 - W**2)
    x0 = np.array([F + AMPLITUDE * np.cos(-phi), -AMPLITUDE * W * np.sin(-phi)])  # the slower-than-belt response
    problem = ShootingProblem(flow, {"v_b": 2.5}, continuation_parameter="v_b")
    return continue_branch(problem, x0, 2.5, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(1.5, 2.5)),
                           directions=(-1,)), problem


def test_grazing_sliding_against_closed_form(branch):
    br, problem = branch
    (g,) = [sp for sp in br.special_points if sp.kind is SpecialPointKind.GRAZING_SLIDING]
    assert g.parameter == pytest.approx(V_GRAZING_SLIDING, abs=1e-9)
    assert g.accuracy < 1e-9
    # the side that misses the surface: the linear oscillator's multipliers exp(lambda T)
    free = g.multipliers_minus if "the side with the crossing is 'plus'" in g.note else g.multipliers_plus
    np.testing.assert_allclose(np.sort_complex(free), np.sort_complex(np.exp(EIGENVALUES * T)), rtol=0, atol=1e-10)
    # the sliding side: a sliding motion on a line in the plane forgets one direction
    sliding = g.multipliers_plus if "the side with the crossing is 'plus'" in g.note else g.multipliers_minus
    assert np.min(np.abs(sliding)) < 1e-12


def test_crossing_sliding_against_independent_computation(branch):
    br, problem = branch
    (c,) = [sp for sp in br.special_points if sp.kind is SpecialPointKind.CROSSING_SLIDING]
    traj = problem.flow.run(c.state, 0.0, T, problem.parameters_at(c.parameter))
    start = next(e for e in traj.events if e.kind.name in ("SLIDING_START", "TRANSITION"))
    z = fsolve(sticking_orbit_residual, [start.t, start.x_minus[0], c.parameter], xtol=1e-14)
    assert np.abs(sticking_orbit_residual(z)).max() < 1e-12
    # the reference is exact to ~1e-13 (closed forms and brentq); the located point claims 1e-9 or better
    assert c.accuracy < 1e-9
    assert c.parameter == pytest.approx(z[2], abs=1e-9)
    assert "exactly where the field of 'slip_plus' is tangent" in c.note


def test_grazing_sliding_from_the_sliding_side(branch):
    """Continuing the sticking orbits upwards passes the grazing-sliding onto the non-sticking orbits."""
    br, problem = branch
    last = br.points[-1]
    up = continue_branch(problem, last.state, last.parameter,
                         settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(last.parameter, 2.5)), directions=(1,))
    kinds = {sp.kind for sp in up.special_points}
    assert {SpecialPointKind.GRAZING_SLIDING, SpecialPointKind.CROSSING_SLIDING} <= kinds
    (g,) = [sp for sp in up.special_points if sp.kind is SpecialPointKind.GRAZING_SLIDING]
    assert g.parameter == pytest.approx(V_GRAZING_SLIDING, abs=1e-9)
