"""A branch never stops at a regular point because its shooting state drifted onto an event.

The peak-current-mode boost converter (``../shared/trial-models/boost_current_mode.py``, written by a user from the
docs: a clock phase ``tau`` reset at ``tau = 1``, a latch ``q``), an autonomous model.  Along a branch the phase
condition lets the shooting state slide along the orbit from step to step, until it sits on the clock's reset:
there the period map jumps (``tau`` is 1 or 0), and the corrector failed at the minimum step (at ``I_ref =
1.91034`` upwards, 1.32894 downwards), an ordinary orbit.  Before giving up, continuation now moves the state
off the events along its orbit and retries.

Reference: the stroboscopic map in closed form (``tests/boost_reference.py``: the ON phase's ramp, the OFF
phase's matrix exponential, derivatives through the switching instant), its fixed point by Newton and its
period doubling by brentq (1.7059824906081211; the trial's own figure is 1.7059824906081227).
"""

from __future__ import annotations

import numpy as np
import pytest

import boost_reference as reference
from conftest import trial_model
from saltation import Flow
from saltation.branches.branch import SpecialPointKind, StopReason
from saltation.branches.check import check_branch
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import ContinuationSettings, continue_branch


def converter_branch(lo: float, hi: float, start: float):
    flow = Flow(trial_model("boost_current_mode").boost())
    q = dict(flow.system.defaults)
    x, _ = reference.fixed_point(dict(q, I_ref=start))
    problem = ShootingProblem(flow, {"I_ref": start}, continuation_parameter="I_ref")
    # the orbit at the clock instant, just after the latch is set (tau = 0, switch ON)
    u0 = problem.pack(np.array([x[0], x[1], 0.0, 1.0]), 1.0)
    direction = 1 if hi > start else -1
    return q, continue_branch(problem, u0, start, settings=ContinuationSettings(bounds=(lo, hi)),
                              directions=(direction,))


def test_the_converter_branch_reaches_its_bounds_through_its_period_doubling():
    q, branch = converter_branch(1.5, 3.0, 1.5)
    assert branch.stop_reason is StopReason.PARAMETER_BOUND
    assert branch.points[-1].parameter == pytest.approx(3.0, abs=1e-12)
    assert check_branch(branch).ok
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    # the reference is good to rounding (brentq to 4 eps on a closed form); the point to its accuracy
    assert abs(pd.parameter - reference.period_doubling(q)) <= pd.accuracy + 1e-13
    # the multipliers: the trivial 1 (along tau), the latch's 0 (its reset forgets), and the map's two
    for p in branch.points[:: max(1, len(branch.points) // 8)]:
        if p.parameter >= 2.0:  # the period-1 orbit of the reference has t_on < T up to here
            continue
        _, J = reference.fixed_point(dict(q, I_ref=p.parameter))
        mu = np.sort_complex(np.asarray(p.multipliers))
        ref = np.sort_complex(np.concatenate([np.linalg.eigvals(J), [1.0, 0.0]]))
        np.testing.assert_allclose(mu, ref, atol=1e-8)


def test_the_converter_branch_reaches_its_lower_bound():
    _, branch = converter_branch(0.8, 1.5, 1.5)
    assert branch.stop_reason is StopReason.PARAMETER_BOUND
    assert branch.points[-1].parameter == pytest.approx(0.8, abs=1e-12)
    assert check_branch(branch).ok


def test_the_period_two_branch_ends_at_the_period_doubling_it_was_born_at():
    """Followed back to where it was born, the branch of period-2 orbits meets the period-1 orbits run twice: its
    multiplier +1 is the square of their -1, and the turning point the fold test sees there is poorly located
    (8.8e-8 off, the branch being a parabola).  It is the period doubling, located on the half-period orbits."""
    flow = Flow(trial_model("boost_current_mode").boost())
    q = dict(flow.system.defaults, I_ref=1.8)
    x = reference.period_two_orbit(q)
    problem = ShootingProblem(flow, {"I_ref": 1.8}, continuation_parameter="I_ref")
    branch = continue_branch(problem, problem.pack(np.array([x[0], x[1], 0.0, 1.0]), 2.0), 1.8,
                             settings=ContinuationSettings(bounds=(1.6, 1.8)), directions=(-1,))
    assert branch.points[0].period == pytest.approx(2.0, abs=1e-9)
    assert check_branch(branch).ok
    kinds = [sp.kind for sp in branch.special_points]
    assert kinds == [SpecialPointKind.PERIOD_DOUBLING]
    (pd,) = branch.special_points
    assert abs(pd.parameter - reference.period_doubling(dict(q, I_ref=1.7))) <= pd.accuracy + 1e-13
    assert pd.period == pytest.approx(1.0, abs=1e-9)
    assert min(abs(np.asarray(pd.multipliers) + 1.0)) <= 1e-8


def test_multiple_shooting_moves_its_nodes_off_the_clock():
    """With four segments a node drifts onto the clock's reset (the corrector failed at 1.78838): the nodes are
    moved together along the orbit, off every event, and the branch goes on through its period doubling."""
    from saltation.orbits.shooting import MultipleShootingProblem

    flow = Flow(trial_model("boost_current_mode").boost())
    q = dict(flow.system.defaults)
    x, _ = reference.fixed_point(dict(q, I_ref=1.5))
    single = ShootingProblem(flow, {"I_ref": 1.5}, continuation_parameter="I_ref")
    problem = MultipleShootingProblem(single, 4)
    U0 = problem.pack(single.pack(np.array([x[0], x[1], 0.0, 1.0]), 1.0), 1.5)
    branch = continue_branch(problem, U0, 1.5, settings=ContinuationSettings(bounds=(1.5, 2.0)), directions=(1,))
    assert branch.stop_reason is StopReason.PARAMETER_BOUND
    assert check_branch(branch).ok
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    assert abs(pd.parameter - reference.period_doubling(q)) <= pd.accuracy + 1e-13
