"""The smoothed models of saltation.model.regularize, and the paper's smoothing claim."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from saltation import Flow
from saltation.errors import ModelError
from saltation.models import block_on_belt, impact_oscillator
from saltation.apps.paper import PaperSettings, smoothing_study, stable_stick_slip_cycle
from saltation.model.regularize import regularize
from saltation.orbits.shooting import find_periodic_orbit


def sigma(c, eps):
    return 0.5 * (1.0 + math.tanh(c / eps))


def test_smoothed_field_is_the_first_match_blend(filippov_flow):
    """Two modes, 'above' (y > 0) first: f = s f_above + (1 - s) f_below with s = sigma(y / eps)."""
    system = filippov_flow.system
    smooth = regularize(system, 0.01)
    assert smooth.mode_names == ("smooth",) and not smooth.transitions and smooth.period_expr == system.period_expr
    field = sp.lambdify((smooth.t, list(smooth.x), list(smooth.p)), list(smooth.fields[0]), modules="math")
    p = dict(system.defaults) | {"q": 0.3, "omega": 1.3, "phi": 0.4}
    values = [p[k] for k in system.parameter_names] + [0.02]
    for t, x, y in [(0.3, -1.0, 0.01), (1.0, 0.5, -0.03), (2.0, 0.2, 0.0)]:
        s = sigma(y, 0.02)
        below = np.array([2.0, 1 - x + p["q"] * math.sin(p["omega"] * t + p["phi"])])
        expected = s * np.array([1.0, -1.0]) + (1 - s) * below
        np.testing.assert_allclose(np.ravel(field(t, [x, y], values)), expected, rtol=1e-14, atol=1e-15)


def test_regularize_refuses_what_it_cannot_smooth():
    with pytest.raises(ModelError, match=r"transition 0 \(free -\[stop\+\]-> free\) has a reset map"):
        regularize(impact_oscillator(), 1e-3)
    with pytest.raises(ModelError, match="must be positive"):
        regularize(block_on_belt(), 0.0)
    with pytest.raises(ModelError, match="'eta' is already a name"):
        regularize(block_on_belt(), 1e-5, parameter="eta")


def test_smoothed_stable_cycle_converges_to_the_switch_model():
    """The stable stick-slip cycle of the smoothed model tends to that of the switch model like O(epsilon)."""
    reference = stable_stick_slip_cycle(Flow(block_on_belt()), 1.0)
    flow = Flow(regularize(block_on_belt(), 1e-5))
    errors = []
    for eps in (1e-5, 3e-6, 1e-6):
        values = {"v_dr": 1.0, "epsilon": eps}
        start = flow.run([0.0, 1.0], 0.0, 60.0, flow.parameters(values)).x1
        orbit = find_periodic_orbit(flow, start, parameters=values, period=6.5)
        errors.append(abs(orbit.period - reference.period))
        assert np.abs(orbit.multipliers).min() < 1e-3  # the smoothed stick phase still contracts strongly
    ratios = np.array(errors) / np.array([1e-5, 3e-6, 1e-6])
    assert ratios.max() < 1.0 and ratios.max() / ratios.min() < 2.0  # first order in epsilon


def test_smoothing_never_reaches_the_infinitely_unstable_branch():
    """Forward continuation of the smoothed models turns at (or stops at) the fold of the discontinuous
    model, 1.0982581347 (located by its tangential return), ever closer as epsilon shrinks; the smoothed
    unstable cycle's multiplier grows without bound (beyond double precision at 3e-6)."""
    rows, branches = smoothing_study(PaperSettings(), widths=(1e-5, 3e-6, 1e-6))
    fold = 1.0982581347
    gaps = [fold - r.turning_point for r in rows]
    assert all(g > 0 for g in gaps) and gaps[0] > gaps[1] > gaps[2]
    assert rows[0].unstable_multiplier > 1e3
    assert all(math.isinf(r.unstable_multiplier) for r in rows[1:])
    for r, branch in zip(rows, branches):
        assert r.points_beyond < 30 and "minimum step" in r.stop_reason
        # the last point is still near the stable branch's fold, far from the unstable cycle at v_dr = 1
        assert branch.amplitude[-1] > 2.37
