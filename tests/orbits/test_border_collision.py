"""Feigin's classification of border collisions (:mod:`saltation.orbits.border_collision`), against the
piecewise-linear continuous maps it is a theorem about, and its rule for the cases the library meets.

The reference is independent of the counting: for ``x -> A x + mu b`` where ``x_1 <= 0`` and
``x -> B x + mu b`` where ``x_1 > 0`` with ``B = A + c e_1^T`` (continuous on ``x_1 = 0``), every fixed point
and every period-two orbit is found by solving the linear system of each side (and of each pair of sides)
and keeping the solutions that lie where their pieces apply, at ``mu = -1`` and ``mu = +1``.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from saltation.kinds import BorderScenario
from saltation.orbits.border_collision import CIRCLE_TOL, feigin_scenario

INF = complex(np.inf, 0.0)


def fixed_points(A, B, b, mu):
    """The fixed points of the piecewise-linear map at ``mu``: one per side whose solution lies on that side."""
    n = len(b)
    found = []
    for M, on_side in ((A, lambda x: x[0] <= 0.0), (B, lambda x: x[0] > 0.0)):
        x = np.linalg.solve(np.eye(n) - M, mu * b)
        if on_side(x):
            found.append(x)
    return found


def period_two_orbits(A, B, b, mu):
    """Its period-two orbits: one point on the A side whose image lies on the B side, and back."""
    n = len(b)
    x = np.linalg.solve(np.eye(n) - B @ A, mu * (B @ b + b))
    y = A @ x + mu * b
    return [x] if x[0] <= 0.0 and y[0] > 0.0 else []


matrices = st.lists(st.floats(-2.5, 2.5, allow_nan=False), min_size=4, max_size=4)
vectors = st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=2, max_size=2)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(a=matrices, c=vectors, b=vectors)
def test_the_counts_predict_the_fixed_points_of_piecewise_linear_maps(a, c, b):
    """Persistence: one fixed point at mu = -1 and one at +1; a non-smooth fold: two on one side, none on
    the other; an odd count below -1: a period-two orbit at mu = -1 or +1 (Feigin's theorem)."""
    A = np.array(a).reshape(2, 2)
    B = A + np.outer(c, [1.0, 0.0])
    b = np.array(b)
    mu_a, mu_b = np.linalg.eigvals(A), np.linalg.eigvals(B)
    # generic: multipliers off the unit circle, regular systems, fixed points off the border
    assume(np.min(np.abs(np.abs(np.concatenate([mu_a, mu_b])) - 1.0)) > 1e-3)
    assume(np.min(np.abs(np.concatenate([mu_a, mu_b]).imag)) > 1e-6 or
           np.min(np.abs(np.concatenate([mu_a, mu_b]).imag)) == 0.0)
    assume(abs(np.linalg.det(np.eye(2) - B @ A)) > 1e-3)
    for M in (A, B):
        x = np.linalg.solve(np.eye(2) - M, b)
        assume(abs(x[0]) > 1e-3)
    found = feigin_scenario(mu_a, mu_b)
    counts = sorted(len(fixed_points(A, B, b, mu)) for mu in (-1.0, 1.0))
    if found.scenario is BorderScenario.PERSISTENCE:
        assert counts == [1, 1]
    else:
        assert found.scenario is BorderScenario.NONSMOOTH_FOLD and counts == [0, 2]
    # the determinants say the same (the fixed-point index), whatever the counting
    assert (np.linalg.det(np.eye(2) - A) * np.linalg.det(np.eye(2) - B) > 0) == (found.scenario is BorderScenario.PERSISTENCE)
    assert (np.linalg.det(np.eye(2) + A) * np.linalg.det(np.eye(2) + B) < 0) == found.period_two
    if found.period_two:
        assert any(period_two_orbits(A, B, b, mu) for mu in (-1.0, 1.0))


def test_the_counts_of_hand_made_sides():
    cases = [
        # (minus, plus, autonomous, scenario, period two, sigma+, sigma-)
        ([0.5, 0.2], [0.8 + 0.3j, 0.8 - 0.3j], False, "persistence", False, (0, 0), (0, 0)),
        ([1.42, 0.53], [0.75 + 0.44j, 0.75 - 0.44j], False, "nonsmooth_fold", False, (1, 0), (0, 0)),
        ([-1.5, 0.2], [0.5, 0.2], False, "persistence", True, (0, 0), (1, 0)),
        ([-1.5, 1.3], [2.0, -3.0], False, "persistence", False, (1, 1), (1, 1)),
        # the trivial multiplier of an autonomous orbit is not counted, however near 1 the rounding leaves it
        ([1.0 + 1e-9, 0.3], [1.0 - 1e-9, 2.0], True, "nonsmooth_fold", False, (0, 1), (0, 0)),
        # an impact's grazing: the crossing side's large multiplier tends to -inf (Nordmark's map)
        ([0.0066 + 0.675j, 0.0066 - 0.675j], [complex(-np.inf, 0.0), -4.4e-4], False, "persistence", True, (0, 0), (0, 1)),
        # the point at infinity counts as real > 1 (the paper's infinitely unstable side, lambda = (1, inf))
        ([1.0, 0.3], [INF, 1.0], True, "nonsmooth_fold", False, (0, 1), (0, 0)),
    ]
    for minus, plus, autonomous, scenario, two, sp, sm in cases:
        found = feigin_scenario(minus, plus, autonomous=autonomous)
        assert (found.scenario.value, found.period_two, found.sigma_plus, found.sigma_minus) == (scenario, two, sp, sm), (
            minus, plus, found)
        assert found.reason


@pytest.mark.parametrize("minus, plus, why", [
    ([1.0 + 1e-8, 0.3], [0.5, 0.2], "unit circle"),  # a forced orbit's multiplier at +1 within the accuracy
    ([-1.0 + 5e-7, 0.3], [0.5, 0.2], "unit circle"),
    ([0.6 + 0.8j, 0.6 - 0.8j], [0.5, 0.2], "unit circle"),
    ([INF, 0.2], [INF, 0.3], "both sides"),  # the stick-slip fold: neither side's map has a finite Jacobian
    ([complex(np.inf, np.inf), 0.2], [0.5, 0.3], "off the real axis"),
])
def test_undetermined_where_the_theorem_does_not_apply(minus, plus, why):
    found = feigin_scenario(minus, plus)
    assert found.scenario is BorderScenario.UNDETERMINED and found.period_two is None
    assert why in found.reason


def test_the_tolerance_is_the_multipliers_accuracy():
    assert feigin_scenario([1.001, 0.3], [0.5, 0.2]).scenario is BorderScenario.NONSMOOTH_FOLD
    assert feigin_scenario([1.001, 0.3], [0.5, 0.2], tolerance=1e-2).scenario is BorderScenario.UNDETERMINED
    assert feigin_scenario([1.001, 0.3], [0.5, 0.2], tolerance=0.0).tolerance == CIRCLE_TOL


def test_sides_of_different_sizes_are_refused():
    with pytest.raises(ValueError, match="2 and 3 multipliers"):
        feigin_scenario([0.5, 0.2], [0.5, 0.2, 0.1])
