"""The ball on a vibrating table: period-1 orbits in closed form, their period doubling, and the
period-2 branch born there, against an independent shooting on the closed-form impact map (scipy).

Between impacts the ball flies ballistically, y(t) = y_i + v+ (t - t_i) - g (t - t_i)^2 / 2; the next
impact is the first root of y(t) = A sin(omega t); there v+' = (1 + e) A omega cos(omega t) - e v-.
The impact map P: (t_i, v+) -> (t_i', v+') needs no integration at all.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq, fsolve

from saltation import Flow
from saltation.branches.branch import SpecialPointKind
from saltation.special_points.branch_switching import follow_period_doubled_branch
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.errors import ModelError
from saltation.models import bouncing_ball
from saltation.models.bouncing_ball import DEFAULTS
from saltation.orbits.shooting import ShootingProblem

G, E, A0, W = (DEFAULTS[k] for k in ("g", "e", "A", "omega"))
T = 2 * np.pi / W


def impact_map(A, u, e=E):
    """(impact time, velocity after it) -> the next impact, of the ball with restitution e."""
    t_i, v_plus = u
    y_i = A * np.sin(W * t_i)
    gap = lambda tau: y_i + v_plus * tau - G * tau**2 / 2 - A * np.sin(W * (t_i + tau))  # noqa: E731
    taus = np.linspace(1e-9, 3 * T, 3001)
    gaps = gap(taus)
    k = np.nonzero((gaps[:-1] > 0) & (gaps[1:] <= 0))[0][0]
    tau = brentq(gap, taus[k], taus[k + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps)
    t_next = t_i + tau
    v_minus = v_plus - G * tau
    return np.array([t_next, (1 + e) * A * W * np.cos(W * t_next) - e * v_minus])


def period_1(A):
    """The stable period-1 fixed point (t_i, v+) in closed form: cos(phi) = (1 - e) pi g / ((1 + e) A w^2)."""
    phi = np.arccos((1 - E) * np.pi * G / ((1 + E) * A * W**2))
    return np.array([phi / W, G * T / 2])


def jacobian(fun, u, h=1e-6):
    return np.column_stack([(fun(u + h * e) - fun(u - h * e)) / (2 * h) for e in np.eye(2)])


def state_at_zero(A, u):
    """The ball's state at t = 0 (mod T) after the impact u = (t_i, v+)."""
    t_i, v_plus = u
    tau = (-t_i) % T
    return np.array([A * np.sin(W * t_i) + v_plus * tau - G * tau**2 / 2, v_plus - G * tau])


@pytest.fixture(scope="module")
def ball():
    flow = Flow(bouncing_ball())
    problem = ShootingProblem(flow, {"A": A0}, continuation_parameter="A")
    branch = continue_branch(
        problem, state_at_zero(A0, period_1(A0)), A0, settings=ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(A0, 0.5)),
        directions=(1,),
    )
    return flow, problem, branch


def test_period_1_orbits_in_closed_form(ball):
    flow, _, branch = ball
    for point in branch.points[::10]:
        A = point.parameter  # beyond the period doubling too (unstable there)
        u = period_1(A)
        np.testing.assert_allclose(point.state, state_at_zero(A, u), rtol=0, atol=1e-9)
        # multipliers: the eigenvalues of the impact map's Jacobian (shifted by T in time)
        mu = np.linalg.eigvals(jacobian(lambda q: impact_map(A, q), u))
        np.testing.assert_allclose(np.sort_complex(point.multipliers), np.sort_complex(mu), rtol=0, atol=1e-6)


def test_period_doubling_located_against_closed_form(ball):
    _, _, branch = ball
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]

    def smallest_multiplier_plus_one(A):
        mu = np.linalg.eigvals(jacobian(lambda q: impact_map(A, q), period_1(A)))
        return float(np.min(mu.real)) + 1.0

    reference = brentq(smallest_multiplier_plus_one, 0.35, 0.4, xtol=1e-12)
    # located to locate_tol = 1e-9 in (x, A); the reference's multipliers by central differences are
    # good to ~1e-9, which moves its root by ~1e-10 (they agree to 1e-11)
    assert pd.parameter == pytest.approx(reference, abs=1e-9)
    assert np.min(np.abs(pd.multipliers + 1.0)) < 1e-8


# near the doubling the period-2 map has a multiplier near +1: fsolve stalls once the residual is at
# rounding level and says so; the residual is asserted below
@pytest.mark.filterwarnings("ignore:The iteration is not making good progress")
def test_period_2_branch_against_independent_shooting(ball):
    flow, problem, branch = ball
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    settings = ContinuationSettings(ds=0.005, ds_max=0.01, bounds=(0.3, 0.41))
    doubled = follow_period_doubled_branch(problem, pd, settings=settings)
    assert len(doubled) > 10
    assert doubled.points[0].parameter == pytest.approx(pd.parameter, abs=1e-4)
    assert all(p.parameter >= pd.parameter - 1e-9 for p in doubled.points)  # supercritical: beyond the doubling
    checked = 0
    for point in doubled.points[3::5]:
        A = point.parameter
        assert len(point.event_labels) == 2 and np.isclose(point.period, 2 * T)
        # the library's two impacts as the guess; the fixed point of P(P(u)) = u + (2T, 0) by fsolve
        traj = problem.flow.run(point.state, 0.0, 2 * T, problem.flow.parameters({"A": A}))
        first = traj.events[0]
        guess = np.array([first.t, first.x_plus[1]])
        u = fsolve(lambda q: impact_map(A, impact_map(A, q)) - q - [2 * T, 0.0], guess, xtol=1e-13)
        np.testing.assert_allclose(impact_map(A, impact_map(A, u)) - u, [2 * T, 0.0], rtol=0, atol=1e-11)
        second = impact_map(A, u)
        assert abs(second[1] - u[1]) > 1e-3  # two different impacts: a true period-2 orbit
        # the state at t = 2T (= 0 on the orbit) is the flight from the second impact
        tau = 2 * T - second[0]
        y_at_2T = [A * np.sin(W * second[0]) + second[1] * tau - G * tau**2 / 2, second[1] - G * tau]
        np.testing.assert_allclose(point.state, y_at_2T, rtol=0, atol=1e-8)
        mu = np.linalg.eigvals(jacobian(lambda q: impact_map(A, impact_map(A, q)), u))
        # central differences with h = 1e-6 of a map computed to ~1e-15: about 1e-9 from rounding, more
        # where a multiplier is ill-conditioned (near +1 at the doubling)
        np.testing.assert_allclose(np.sort_complex(point.multipliers), np.sort_complex(mu), rtol=0, atol=1e-5)
        checked += 1
    assert checked >= 2
    # shooting over two periods from a perturbed state finds the same orbit
    p2 = doubled.points[-1]
    orbit = ShootingProblem(flow, {"A": p2.parameter}, periods=2).solve(p2.state + 1e-4)
    assert orbit.period == pytest.approx(2 * T)
    np.testing.assert_allclose(orbit.state0, p2.state, rtol=0, atol=1e-9)


def test_branch_switching_rejects_other_points(ball):
    _, problem, branch = ball
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    from dataclasses import replace

    with pytest.raises(ModelError, match="period_doubling"):
        follow_period_doubled_branch(problem, replace(pd, kind=SpecialPointKind.FOLD))
    with pytest.raises(ModelError, match="positive integer"):
        ShootingProblem(problem.flow, periods=0)


def test_period_doubling_curve_against_closed_form(ball):
    """The period doubling continued in (A, e): Gamma = A w^2 / g at the doubling is
    sqrt((pi (1 - e) / (1 + e))^2 + (2 (1 + e^2) / (1 + e)^2)^2) (Holmes 1982; from the closed-form
    impact map's trace, tr J = -(1 + det J), det J = e^2)."""
    from saltation.special_points.loci import follow_locus

    _, problem, branch = ball
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    locus = follow_locus(problem, pd, "e", (0.3, 0.7))
    A, e = locus.values.T
    assert e.min() == pytest.approx(0.3) and e.max() == pytest.approx(0.7)
    reference = G / W**2 * np.sqrt((np.pi * (1 - e) / (1 + e)) ** 2 + (2 * (1 + e**2) / (1 + e) ** 2) ** 2)
    # the bordered test function's derivatives by central differences (h = 1e-6): Newton still converges
    # to the residual tolerance 1e-10, so the curve is exact to about that
    np.testing.assert_allclose(A, reference, rtol=0, atol=1e-9)
