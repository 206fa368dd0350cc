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


def test_return_tangency_rows_of_the_stick_slip_fold():
    """The block on the belt's fold in (v_dr, c): h = 0 and L = 0 at the start, in the stick mode, the
    phase fixed by them (no phase condition), the period an unknown."""
    from saltation.models import block_on_belt
    from saltation.orbits.conditions import ReturnTangency
    from saltation.special_points.grazing import locate_tangential_return

    flow = Flow(block_on_belt())
    (k,) = [i for i, tr in enumerate(flow.system.transitions)
            if (tr.source, tr.surface, tr.target) == ("slip_minus", "band_lower", "stick")]
    found = locate_tangential_return(flow, [0.8902, 1.0981], 1.0982, "v_dr", k, 6.5)
    base = ShootingProblem(flow, {"v_dr": found.parameter}, tolerances=TOL)
    problem = ConditionedProblem(base, [ReturnTangency(flow, k)], free=("v_dr",), continuation="c")
    # the touch lies on the band's edge; the point is moved 3e-5 into the band (v - v_dr + eta = 3e-5), so
    # that the differences' steps (1e-6) start every shot in the stick mode's own domain
    u = problem.pack(found.state, period=found.period) + np.array([1e-4, 2e-5, 1e-3, -1e-5])
    compare_with_differences(problem, u, flow.system.defaults["c"] + 1e-3)


def test_tangency_rows_by_multiple_shooting():
    """The grazing curve of the impact oscillator on 3 segments: the condition read on the segment that
    holds t_g, its rows by that node, and the segments' starts moving with the forcing period 2 pi / omega."""
    from saltation.orbits.shooting import MultipleShootingProblem

    flow = Flow(impact_oscillator())
    w = flow.system.defaults["omega"]
    det = (1 - w**2) ** 2 + (0.1 * w) ** 2
    g = locate_grazing(flow, [(1 - w**2) / det, 0.1 * w * w / det], 2.9, "s", 0, 0.3, parameters={"s": 2.9})
    # shot from t0 = t_g - T/2, so that the touch lies in the middle segment, whose start moves with omega
    T = 2 * np.pi / w
    t0 = g.t_graze - T / 2
    p = flow.parameters({"s": g.parameter})
    x_t0 = flow.run(g.state0, 0.0, g.t_graze + T / 2, p, disabled=[0], tolerances=TOL).x1
    base = MultipleShootingProblem(ShootingProblem(flow, {"s": g.parameter}, t0=t0, tolerances=TOL), 3)
    problem = ConditionedProblem(base, [Tangency(flow, 0, g.t_graze)], free=("s",), continuation="omega")
    u = problem.pack(x_t0, extras=np.array([g.t_graze]))
    u = u + 1e-3 * np.sin(np.arange(len(u)) + 1.0)
    compare_with_differences(problem, u, w + 1e-3)


def test_multiplier_rows_by_multiple_shooting():
    """A fold of the trilinear oscillator on 2 segments, in (omega, f0): g of the product of the segments'
    matrices and its central differences by node (their step 1e-6 inside the rows; here compared with
    steps of 1e-6 of the whole residual: the two agree to the second differences' 1e-6 relative)."""
    from saltation.apps.paper import linear_response_state
    from saltation.models import trilinear
    from saltation.models.trilinear import DEFAULTS as TRI
    from saltation.orbits.conditions import MultiplierCondition
    from saltation.orbits.shooting import MultipleShootingProblem

    flow = Flow(trilinear())
    state = linear_response_state(dict(TRI, omega=1.2))
    base = MultipleShootingProblem(ShootingProblem(flow, {"omega": 1.2}, tolerances=TOL), 2)
    problem = ConditionedProblem(base, [MultiplierCondition(1.0)], free=("omega",), continuation="f0")
    u = problem.pack(state)
    compare_with_differences(problem, u, TRI["f0"])


def test_kept_multiplier_derivatives_locate_the_same_fold_with_fewer_shots():
    """The multiplier condition keeps its finite-difference derivatives while the Newton stays near where they
    were taken (and they predict ``g``): the fold of the trilinear oscillator in omega, at f0 = 0.2, is the same
    to the Newton's tolerance as with derivatives taken at every iterate, for fewer period maps; and it has a
    multiplier +1 (the kept derivatives change the Newton's path, never its equations)."""
    from saltation.apps.paper import linear_response_state
    from saltation.models import trilinear
    from saltation.models.trilinear import DEFAULTS as TRI
    from saltation.orbits.conditions import MultiplierCondition

    from saltation.branches.branch import SpecialPointKind
    from saltation.special_points.continuation import ContinuationSettings, continue_branch

    flow = Flow(trilinear())
    branch = continue_branch(ShootingProblem(flow, {"omega": 0.6}, continuation_parameter="omega"),
                             linear_response_state(dict(TRI, omega=0.6)), 0.6,
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.6, 1.6)), directions=(1,))
    (fold,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.FOLD]
    w0 = fold.parameter - 1e-3  # a start off the fold: Newton has to move in omega and in the state
    guess = find_periodic_orbit(flow, fold.state, parameters={"omega": w0})
    counts, found = {}, {}
    run = flow.run
    for reuse in (0.0, 1e-3):
        calls = []

        def counted(*args, **kwargs):
            calls.append(1)
            return run(*args, **kwargs)

        flow.run = counted
        try:
            problem = ConditionedProblem(ShootingProblem(flow, {"omega": w0}), [MultiplierCondition(1.0, reuse=reuse)],
                                         free=("omega",))
            found[reuse] = problem.solve(problem.pack(guess.state0), tol=1e-11)
        finally:
            flow.run = run
        counts[reuse] = len(calls)
    fresh, kept = found[0.0], found[1e-3]
    assert counts[1e-3] < counts[0.0], counts
    np.testing.assert_allclose(kept.unknowns, fresh.unknowns, rtol=0, atol=1e-9)
    orbit = find_periodic_orbit(flow, kept.state0, parameters=kept.parameters)
    assert np.min(np.abs(orbit.multipliers - 1.0)) < 1e-7
