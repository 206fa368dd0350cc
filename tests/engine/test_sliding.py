"""Filippov sliding on a planar example with a closed-form solution.

Model (conftest.filippov_system): ``above`` (y > 0) ``[1, -1]``, ``below`` (y < 0)
``[2, 1 - x + q sin(omega t)]``.  For ``q = 0``, from ``(x0, y0) = (-1, 1/2)``:

* ``above`` reaches ``y = 0`` at ``t1 = y0``, ``x1 = x0 + y0``; ``below`` pushes back
  (``1 - x1 > 0``): attraction sliding starts, with the singular saltation matrix
  ``S = I + (f_s - f_a) n^T / (n^T f_a) = [[1, -alpha], [0, 0]]``, ``alpha = 1/(2 - x1)``;
* the sliding field is ``f_a + alpha (f_b - f_a)``, ``alpha = s_a / (s_a - s_b) = 1/(2 - x)``,
  i.e. ``x' = (3 - x)/(2 - x)``, ``y' = 0``: ``t - t1 = x - x1 + ln((3 - x)/(3 - x1))``;
* it ends where ``below`` turns tangent, ``x = 1``, at ``t2 = t1 + 1 - x1 + ln(2/(3 - x1))``,
  with ``S = I`` (the sliding field equals ``f_b`` there);
* then ``x = 1 + 2 (t - t2)``, ``y = -(t - t2)^2``.

So ``x(3), y(3)`` depend on ``(x0, y0)`` through ``t2`` only:
``dt2/dx0 = -1 + 1/(3 - x1)``, ``dt2/dy0 = 1/(3 - x1)`` and the monodromy has rank one.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from saltation import EventKind

from conftest import TIGHT, central_difference_jacobian

X0 = np.array([-1.0, 0.5])
T_END = 3.0
T1 = X0[1]
X1 = X0[0] + X0[1]
T2 = T1 + (1.0 - X1) + np.log(2.0 / (3.0 - X1))


def sliding_x(t: float) -> float:
    """x(t) on the sliding motion, from the implicit closed form (root finding)."""
    return brentq(lambda x: (x - X1) + np.log((3.0 - x) / (3.0 - X1)) - (t - T1), X1, 1.0, xtol=1e-15, rtol=1e-15)


@pytest.fixture(scope="module")
def trajectory(filippov_flow):
    p = filippov_flow.parameters({"q": 0.0})
    return filippov_flow.run(X0, 0.0, T_END, p, variational=True, dense=True)


def test_sliding_event_times_and_states(trajectory):
    start, end = trajectory.events
    assert (start.kind, end.kind) == (EventKind.SLIDING_START, EventKind.SLIDING_END)
    assert start.surface == end.surface == "s"
    assert (start.mode_from, start.mode_to) == ("above", "below")
    assert end.mode_to == "below"
    assert trajectory.mode1 == "below" and not trajectory.sliding_at_end
    assert start.t == pytest.approx(T1, abs=1e-12)
    np.testing.assert_allclose(start.x_minus, [X1, 0.0], atol=1e-12)
    assert end.t == pytest.approx(T2, abs=1e-10)
    np.testing.assert_allclose(end.x_minus, [1.0, 0.0], atol=1e-10)
    np.testing.assert_allclose(trajectory.x1, [1 + 2 * (T_END - T2), -((T_END - T2) ** 2)], atol=1e-9)


def test_sliding_saltation_matrices(trajectory):
    start, end = trajectory.events
    alpha = 1.0 / (2.0 - X1)
    np.testing.assert_allclose(start.saltation, [[1.0, -alpha], [0.0, 0.0]], atol=1e-12)
    assert abs(np.linalg.det(start.saltation)) < 1e-15  # entering sliding forgets y
    np.testing.assert_allclose(end.saltation, np.eye(2), atol=1e-9)


def test_sliding_motion_dense_output(trajectory):
    t, xs = trajectory.sample(16)
    on = (t > T1 + 1e-6) & (t < T2 - 1e-6)
    assert on.sum() >= 2
    assert np.max(np.abs(xs[on, 1])) < 1e-12  # stays on y = 0
    np.testing.assert_allclose(xs[on, 0], [sliding_x(tk) for tk in t[on]], atol=1e-9)


def test_monodromy_through_sliding_closed_form(trajectory):
    a = -1.0 + 1.0 / (3.0 - X1)
    b = 1.0 / (3.0 - X1)
    tau = T_END - T2
    expected = np.array([[-2 * a, -2 * b], [2 * tau * a, 2 * tau * b]])
    np.testing.assert_allclose(trajectory.monodromy, expected, rtol=0, atol=1e-9)
    assert abs(np.linalg.det(trajectory.monodromy)) < 1e-12


@pytest.mark.parametrize("t_end", [1.0, T_END], ids=["mid-sliding", "after-exit"])
@pytest.mark.parametrize("q", [0.0, 0.3], ids=["q=0", "q=0.3"])
def test_monodromy_through_sliding_finite_differences(filippov_flow, q, t_end):
    """q != 0: the sliding field and the exit condition depend on time."""
    p = filippov_flow.parameters({"q": q})
    traj = filippov_flow.run(X0, 0.0, t_end, p, variational=True)
    assert traj.events[0].kind == EventKind.SLIDING_START
    assert traj.sliding_at_end == (t_end < T2)
    if t_end < T2 and q == 0.0:
        np.testing.assert_allclose(traj.x1, [sliding_x(t_end), 0.0], atol=1e-9)
    fd = central_difference_jacobian(lambda x0: filippov_flow.run(x0, 0.0, t_end, p, tolerances=TIGHT).x1, X0, 1e-5)
    np.testing.assert_allclose(traj.monodromy, fd, rtol=0, atol=1e-7)


@pytest.mark.parametrize("name", ["q", "omega"])
def test_parameter_sensitivity_through_sliding(filippov_flow, name):
    p = filippov_flow.parameters({"q": 0.3})
    idx = filippov_flow.system.parameter_index(name)
    traj = filippov_flow.run(X0, 0.0, T_END, p, variational=True, sensitivity=idx)

    def end_state(pk):
        pp = p.copy()
        pp[idx] = pk[0]
        return filippov_flow.run(X0, 0.0, T_END, pp, tolerances=TIGHT).x1

    fd = central_difference_jacobian(end_state, [p[idx]], 1e-6)[:, 0]
    assert np.max(np.abs(fd)) > 0.1
    np.testing.assert_allclose(traj.parameter_sensitivity, fd, rtol=0, atol=1e-7)
