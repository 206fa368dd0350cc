"""The continuation corrector iterates Newton in the compiled kernel (ShootingProblem.correct, Flow.compiled_newton).

References: finite differences of the shooting residual in the unknowns and
the parameter (independent shots at tight tolerances), the same bordered
Newton iteration in Python (Corrector.solve_bordered without the kernel),
and finite differences in time for the velocity at the end of a shot.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import TIGHT, central_difference_jacobian
from saltation import ConvergenceError, InitialModeError
from saltation.special_points.continuation import ContinuationSettings, Corrector
from saltation.orbits.shooting import ShootingProblem

SETTINGS = ContinuationSettings()


def _case(name, trilinear_flow, belt_flow, contact_orbit, stable_cycle, unstable_cycle):
    """A shooting problem with a continuation parameter and a point on its branch."""
    if name.startswith("trilinear"):
        backward = name.endswith("backward")
        problem = ShootingProblem(trilinear_flow, {"omega": 1.0}, continuation_parameter="omega", backward=backward)
        return problem, np.append(contact_orbit.state0, 1.0)
    orbit = unstable_cycle if name.endswith("backward") else stable_cycle
    problem = ShootingProblem(belt_flow, {"v_dr": 1.0}, continuation_parameter="v_dr", backward=orbit.backward)
    u = problem.pack(orbit.state0, orbit.period)
    problem.set_phase_reference(u, 1.0)
    return problem, np.append(u, 1.0)


CASES = ["trilinear", "trilinear backward", "block_on_belt", "block_on_belt backward"]


@pytest.fixture
def case(request, trilinear_flow, belt_flow, contact_orbit, stable_cycle, unstable_cycle):
    return _case(request.param, trilinear_flow, belt_flow, contact_orbit, stable_cycle, unstable_cycle)


def _residual(problem: ShootingProblem, z: np.ndarray) -> np.ndarray:
    """The shooting residual by a plain shot at tight tolerances (no kernel Newton, no variational equation)."""
    n = problem.system.n
    u, lam = z[:-1], float(z[-1])
    p = problem.parameters_at(lam)
    T = problem.period_of(u, lam)
    end = problem.flow.run(u[:n], problem.t0, problem.t0 + problem.sign * T, p, tolerances=TIGHT).x1
    r = end - u[:n]
    if problem.autonomous:
        r = np.append(r, problem.f_ref @ (u[:n] - problem.x_ref))
    return r


@pytest.mark.parametrize("case", CASES, indirect=True)
def test_corrector_jacobians_against_finite_differences(case):
    """J_u (monodromy - I, end velocity, phase row) and J_lam (psi, plus dT/dlam times the end
    velocity for the forcing frequency) of the converged point."""
    problem, z0 = case
    normal = np.zeros(z0.size)
    normal[-1] = 1.0
    found = problem.correct(z0, normal, tol=SETTINGS.tol, max_newton=SETTINGS.max_newton,
                            max_correction=SETTINGS.max_correction)
    assert found is not None
    z, ev, _ = found
    assert z[-1] == z0[-1]  # the normal fixes the parameter
    np.testing.assert_allclose(ev.residual, _residual(problem, z), rtol=0, atol=1e-9)
    fd = central_difference_jacobian(lambda zz: _residual(problem, zz), z, 1e-6)
    np.testing.assert_allclose(ev.jac_u, fd[:, :-1], rtol=0, atol=2e-6)
    np.testing.assert_allclose(ev.jac_lam, fd[:, -1], rtol=0, atol=2e-6)


@pytest.mark.parametrize("case", CASES, indirect=True)
def test_compiled_corrector_matches_the_python_iteration(case, monkeypatch):
    """From a predictor off the branch along an oblique normal: same iterates, same point, same Jacobians."""
    problem, z0 = case
    rng = np.random.default_rng(7)
    normal = np.zeros(z0.size)
    normal[-1] = 1.0
    normal[0] = 0.3
    normal /= np.linalg.norm(normal)
    z_pred = z0 + 1e-3 * rng.standard_normal(z0.size)
    corrector = Corrector(problem, SETTINGS)
    fast = corrector.solve_bordered(z_pred, normal)
    monkeypatch.setattr(problem, "correct", lambda *args, **kwargs: None)
    slow = corrector.solve_bordered(z_pred, normal)
    assert fast.iterations == slow.iterations >= 1
    np.testing.assert_allclose(fast.z, slow.z, rtol=0, atol=1e-13)
    assert abs(normal @ (fast.z - z_pred)) < 1e-13  # on the hyperplane
    np.testing.assert_allclose(fast.evaluation.residual, slow.evaluation.residual, rtol=0, atol=1e-13)
    np.testing.assert_allclose(fast.evaluation.jac_u, slow.evaluation.jac_u, rtol=0, atol=1e-11)
    np.testing.assert_allclose(fast.evaluation.jac_lam, slow.evaluation.jac_lam, rtol=0, atol=1e-11)
    np.testing.assert_allclose(fast.summary.multipliers, slow.summary.multipliers, rtol=0, atol=1e-11)
    assert fast.summary.event_labels == slow.summary.event_labels


def test_corrector_failure_raises_with_the_residual_history(trilinear_flow, contact_orbit):
    problem = ShootingProblem(trilinear_flow, {"omega": 1.0}, continuation_parameter="omega")
    z_pred = np.append(contact_orbit.state0 + np.array([0.3, -0.2]), 1.0)
    normal = np.array([0.0, 0.0, 1.0])
    with pytest.raises(ConvergenceError) as info:
        problem.correct(z_pred, normal, tol=1e-10, max_newton=1, max_correction=1e3)
    assert len(info.value.residuals) == 2
    assert info.value.residuals[0] > 1e-3


def test_corrector_start_in_no_mode_names_the_state(oscillator_flow):
    """The wall x = a of the test oscillator belongs to no mode's domain."""
    problem = ShootingProblem(oscillator_flow, {}, continuation_parameter="w")
    a = oscillator_flow.system.defaults["a"]
    problem.set_phase_reference(np.array([0.1, 0.3, 2 * np.pi]), 1.0)
    with pytest.raises(InitialModeError):
        problem.correct(np.array([a, 0.3, 2 * np.pi, 1.0]), np.array([0.0, 0.0, 0.0, 1.0]), tol=1e-10,
                        max_newton=5, max_correction=1e3)


def _time_derivative(flow, x0, t1, p, h=1e-5):
    return (flow.run(x0, 0.0, t1 + h, p, tolerances=TIGHT).x1 - flow.run(x0, 0.0, t1 - h, p, tolerances=TIGHT).x1) / (2 * h)


def test_end_velocity_of_a_mode_and_of_a_sliding_motion(filippov_flow, trilinear_flow, contact_orbit):
    """``Trajectory.velocity_end`` is dx/dt at the end: in a mode, and on a sliding motion (Filippov's field)."""
    p = filippov_flow.parameters({"q": 0.0})
    x0 = [-0.5, 0.5]
    sliding = filippov_flow.run(x0, 0.0, 1.0, p)
    assert sliding.sliding_at_end
    np.testing.assert_allclose(sliding.velocity_end, _time_derivative(filippov_flow, x0, 1.0, p), atol=1e-8)
    assert sliding.velocity_end[1] == 0.0 and sliding.velocity_end[0] > 1.0
    p = trilinear_flow.parameters({"omega": 1.0})
    for t1 in (1.0, -2.5):
        traj = trilinear_flow.run(contact_orbit.state0, 0.0, t1, p)
        assert not traj.sliding_at_end
        np.testing.assert_allclose(traj.velocity_end, _time_derivative(trilinear_flow, contact_orbit.state0, t1, p), atol=1e-8)


def test_pivoted_solve_against_lapack(trilinear_flow):
    """The kernel's Newton solve (Gaussian elimination with partial pivoting) against numpy.linalg.solve
    (LAPACK dgesv), on random matrices, one that needs row exchanges, and singular ones."""
    solve = trilinear_flow._engine._solve_pivoted
    rng = np.random.default_rng(7)
    matrices = [rng.standard_normal((m, m)) for m in (1, 2, 3, 4, 6)]
    matrices.append(np.array([[0.0, 2.0, 1.0], [1.0, 0.0, 0.0], [3.0, 1.0, 4.0]]))  # zero leading pivot
    for A in matrices:
        b = rng.standard_normal(A.shape[0])
        expected = np.linalg.solve(A, b)
        x = np.zeros_like(b)
        assert solve(A.copy(), b.copy(), x)
        cond = np.linalg.cond(A)
        assert np.max(np.abs(x - expected)) <= 1e-14 * cond * (1.0 + np.max(np.abs(expected)))
        assert np.max(np.abs(A @ x - b)) <= 1e-13 * (1.0 + np.max(np.abs(b)))
    for A in (np.array([[1.0, 2.0], [2.0, 4.0]]), np.zeros((3, 3)), np.array([[np.nan, 0.0], [0.0, 1.0]])):
        assert not solve(A.copy(), np.ones(A.shape[0]), np.zeros(A.shape[0]))


def test_singular_bordered_matrix_is_left_to_the_python_iteration(trilinear_flow, contact_orbit):
    """A zero pseudo-arclength normal makes the bordered matrix singular: the kernel's solve reports it
    (no step is taken), and the shooting problem's compiled corrector declines (returns None), so the
    Python iteration explains it."""
    from saltation.engine._contract import SHOOT_SINGULAR

    p = trilinear_flow.parameters({"omega": 1.0})
    lam = trilinear_flow.system.parameter_index("omega")
    z = np.append(contact_orbit.state0 + 1e-3, 1.0)  # off the orbit: Newton must solve
    kwargs = dict(t0=0.0, sign=1.0, lam_index=lam, span=0.0, phase=None, tol=1e-10, max_iter=5, max_correction=1.0,
                  damped=False)
    singular = trilinear_flow.compiled_newton(z, np.zeros(3), p, **kwargs)
    assert singular.code == SHOOT_SINGULAR and singular.unsupported and singular.iterations == 0
    problem = ShootingProblem(trilinear_flow, {"omega": 1.0}, continuation_parameter="omega")
    assert problem.correct(z, np.zeros(3), tol=1e-10, max_newton=5, max_correction=1.0) is None
    normal = np.array([0.0, 0.0, 1.0])  # the same point with a proper normal converges
    found = trilinear_flow.compiled_newton(z, normal, p, **kwargs)
    assert found.converged and found.iterations >= 1 and abs(found.z[-1] - 1.0) < 1e-12
