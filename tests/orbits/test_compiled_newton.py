"""Shooting for forced systems iterates Newton in the compiled kernel (Flow.compiled_newton).

Reference: the same damped Newton iteration in Python (saltation.orbits.shooting.newton),
which the solver falls back to whenever the compiled iteration fails.
"""

from __future__ import annotations

import numpy as np
import pytest

from saltation import ConvergenceError
from saltation.orbits.shooting import ShootingProblem, find_periodic_orbit


@pytest.fixture
def python_newton(trilinear_flow, monkeypatch):
    """Make the compiled iteration decline, so that shooting runs the Python one."""

    def solve_in_python(flow):
        monkeypatch.setattr(flow, "compiled_newton", lambda *args, **kwargs: None)

    return solve_in_python


@pytest.mark.parametrize("backward", [False, True], ids=["forward", "backward"])
def test_compiled_newton_matches_the_python_iteration(trilinear_flow, contact_orbit, python_newton, backward):
    guess = contact_orbit.state0 + np.array([2e-3, -1e-3])
    fast = find_periodic_orbit(trilinear_flow, guess, parameters={"omega": 1.0}, backward=backward)
    python_newton(trilinear_flow)
    slow = find_periodic_orbit(trilinear_flow, guess, parameters={"omega": 1.0}, backward=backward)
    assert fast.iterations == slow.iterations >= 2
    np.testing.assert_allclose(fast.residuals, slow.residuals, rtol=1e-6, atol=1e-15)
    np.testing.assert_allclose(fast.state0, slow.state0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(fast.monodromy, slow.monodromy, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast.multipliers, slow.multipliers, rtol=0, atol=1e-12)
    assert [e.surface for e in fast.trajectory.events] == [e.surface for e in slow.trajectory.events]
    np.testing.assert_allclose(fast.trajectory.x1, fast.state0, atol=1e-9)  # the trajectory is the orbit's
    assert fast.backward is backward


def test_newton_result_checked_against_the_period_map(trilinear_flow, contact_orbit):
    """The state returned is a fixed point of the period map, integrated independently."""
    guess = contact_orbit.state0 + np.array([1e-3, 1e-3])
    orbit = find_periodic_orbit(trilinear_flow, guess, parameters={"omega": 1.0})
    p = trilinear_flow.parameters({"omega": 1.0})
    end = trilinear_flow.run(orbit.state0, 0.0, 2 * np.pi, p).x1
    np.testing.assert_allclose(end, orbit.state0, atol=1e-9)
    assert orbit.residual_norm <= 1e-10 * (1 + np.linalg.norm(orbit.state0))


def test_failure_falls_back_to_python_for_the_explanation(trilinear_flow, contact_orbit):
    """Too few iterations: the compiled iteration gives up, the Python one raises with its history."""
    guess = contact_orbit.state0 + np.array([0.3, -0.2])
    with pytest.raises(ConvergenceError) as info:
        find_periodic_orbit(trilinear_flow, guess, parameters={"omega": 1.0}, max_iter=1)
    assert "did not converge in 1 iterations" in str(info.value)
    assert len(info.value.residuals) == 2


def test_compiled_iteration_declines_a_singular_jacobian(filippov_flow):
    """Uniform drift (q = 0): the period map's Jacobian M - I is singular. No answer from the kernel,
    an error from Python."""
    problem = ShootingProblem(filippov_flow, {"q": 0.0, "omega": 1.0})
    p = problem.parameters_at(None)
    found = filippov_flow.compiled_newton([0.0, -0.5], None, p, t0=0.0, sign=1.0, lam_index=-1, span=2 * np.pi,
                                          phase=None, tol=1e-10, max_iter=5, max_correction=0.0, damped=True)
    assert not found.converged
    with pytest.raises(ConvergenceError):
        problem.solve(np.array([0.0, -0.5]), max_iter=5)
