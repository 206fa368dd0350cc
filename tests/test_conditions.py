"""The rows of special points' defining systems (:mod:`saltation.orbits.conditions`) against central
differences of their own residuals.

Each condition claims exact derivatives from one shot's pieces (the shot split at the instant it reads,
the implicit function theorem at an event). Here the whole Jacobian of the conditioned problem, by the
unknowns and by the curve's parameter, is compared with central differences of the residual at a point
near the solution, integrated at rtol 1e-12 (exact affine steps in these piecewise-linear models; DOP853
on the sliding motion). Steps of 1e-6 leave a truncation error O(h^2 |r'''|) ~ 1e-12 and a rounding
error ~ 1e-16 / 1e-6 = 1e-10 relative: the rows must agree to 1e-6 of the Jacobian's scale, far
tighter than any sign or factor error, and looser than what central differences can promise.
"""

from __future__ import annotations

import numpy as np
import pytest

from saltation import Flow
from saltation.engine.flow import Tolerances
from saltation.models import friction_oscillator, impact_oscillator
from saltation.models.tilted_relay import tilted_relay
from saltation.orbits.conditions import (
    ArrivalTangency,
    ConditionedProblem,
    CubicTangency,
    Tangency,
)
from saltation.orbits.shooting import ShootingProblem, find_periodic_orbit
from saltation.special_points.grazing import locate_grazing
from saltation.special_points.loci import arrival_identity

TOL = Tolerances(rtol=1e-12, atol=1e-14)
H = 1e-6


def compare_with_differences(problem: ConditionedProblem, u: np.ndarray, lam: float) -> None:
    ev = problem.evaluate(u, lam)
    m = len(u)
    numeric = np.empty((m, m + 1))
    for i in range(m + 1):
        z = np.append(u, lam)
        e = np.zeros(m + 1)
        e[i] = H * max(1.0, abs(z[i]))
        plus = problem.evaluate((z + e)[:m], (z + e)[m], need_lam=False).residual
        minus = problem.evaluate((z - e)[:m], (z - e)[m], need_lam=False).residual
        numeric[:, i] = (plus - minus) / (2 * e[i])
    exact = np.column_stack([ev.jac_u, ev.jac_lam])
    np.testing.assert_allclose(exact, numeric, rtol=0, atol=1e-6 * np.abs(numeric).max())


def test_tangency_rows_of_a_grazing_curve():
    """The impact oscillator's grazing in (s, omega): h = 0 and h_x f + h_t = 0 at the unknown t_g."""
    flow = Flow(impact_oscillator())
    w = flow.system.defaults["omega"]
    det = (1 - w**2) ** 2 + (0.1 * w) ** 2
    g = locate_grazing(flow, [(1 - w**2) / det, 0.1 * w * w / det], 2.9, "s", 0, 0.3, parameters={"s": 2.9})
    base = ShootingProblem(flow, {"s": g.parameter}, tolerances=TOL)
    problem = ConditionedProblem(base, [Tangency(flow, 0, g.t_graze)], free=("s",), continuation="omega")
    u = problem.pack(g.state0, extras=np.array([g.t_graze])) + np.array([1e-3, -2e-3, 1e-3, 1e-2])
    compare_with_differences(problem, u, w + 1e-3)


def test_arrival_tangency_rows_of_a_sliding_curve():
    """The tilted relay's orbit that arrives at the line from 'minus' and slides, in (v, kappa): the far
    field's rate L_plus at the arrival, through the event's time and state."""
    flow = Flow(tilted_relay())
    p = flow.parameters({"v": 2.5})
    orbit = find_periodic_orbit(flow, [0.0, 1.0], parameters={"v": 2.5})
    identity, t_e = arrival_identity(flow, orbit.state0, p, "s", orbit.trajectory.events[0].t, tolerances=TOL)
    assert identity.mode_from == "minus"
    base = ShootingProblem(flow, {"v": 2.5}, tolerances=TOL)
    problem = ConditionedProblem(base, [ArrivalTangency(flow, identity, "plus", t_e)], free=("v",),
                                 continuation="kappa")
    u = problem.pack(orbit.state0) + np.array([1e-3, -1e-3, 0.0])
    compare_with_differences(problem, u, 0.5)


def test_cubic_tangency_rows_of_an_adding_sliding_curve():
    """The friction oscillator sticking through the instant tau where the faster side's field has zero
    rate: L_A and its rate along f_A at the unknown tau, x(tau) on the sticking motion, in (F, v_b)."""
    flow = Flow(friction_oscillator())
    v_b, a, w = 0.2, 1.0, 0.8
    tau = (2 * np.pi - np.arcsin(v_b / (a * w))) / w
    orbit = find_periodic_orbit(flow, [a * np.cos(w * tau) - 0.5 - 0.04, v_b], parameters={"v_b": v_b})
    base = ShootingProblem(flow, {"v_b": v_b}, tolerances=TOL)
    problem = ConditionedProblem(base, [CubicTangency(flow, "slip_plus", "v_rel", tau)], free=("F",),
                                 continuation="v_b")
    u = problem.pack(orbit.state0) + np.array([1e-4, 0.0, 1e-3, 1e-3])
    assert orbit.trajectory.events, "the orbit sticks"
    compare_with_differences(problem, u, v_b)


def test_unbalanced_conditions_are_refused():
    from saltation.errors import ModelError

    flow = Flow(impact_oscillator())
    base = ShootingProblem(flow)
    with pytest.raises(ModelError, match="do not balance"):
        ConditionedProblem(base, [Tangency(flow, 0, 0.3)], free=("s", "omega"))
