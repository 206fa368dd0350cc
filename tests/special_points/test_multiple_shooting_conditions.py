"""Special points located by multiple shooting: the defining systems of :mod:`saltation.orbits.conditions`
on :class:`~saltation.orbits.shooting.MultipleShootingProblem`, each condition read from the segment that
holds its instant, against closed forms and against single shooting.

* A grazing of the impact oscillator (forced): the free response's amplitude reaches the stop,
  ``s = 1 / sqrt((1 - w^2)^2 + (2 zeta w)^2)``.
* A grazing of the Hopf normal form with a wall at ``x = c`` (autonomous; the period is an unknown and
  the segments' starts move with it): the cycle of radius ``sqrt(mu)`` touches the wall at ``c = sqrt(mu)``,
  with period ``2 pi``.
* Folds of the trilinear oscillator (the minimally augmented multiplier condition, its derivatives by
  node): the curve in ``(omega, f0)`` by multiple shooting, whose every checked point has a multiplier
  +1 of the period map by central differences of DOP853 integrations (no variational equation).

The defining systems are solved to ``|r| <= 1e-12 (1 + |u|)``; the stated accuracy must cover the error.
"""

from __future__ import annotations

import numpy as np
import pytest

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition
from saltation.branches.branch import SpecialPointKind
from saltation.engine.flow import Tolerances
from saltation.models import impact_oscillator
from saltation.models.impact_oscillator import DEFAULTS as IMPACT
from saltation.orbits.conditions import Tangency
from saltation.orbits.shooting import MultipleShootingProblem, ShootingProblem


def _shooting(problem: ShootingProblem, segments: int):
    return problem if segments == 1 else MultipleShootingProblem(problem, segments)


@pytest.mark.parametrize("segments", [1, 3, 4])
def test_forced_grazing_against_closed_form(segments):
    flow = Flow(impact_oscillator())
    zeta, w = IMPACT["zeta"], IMPACT["omega"]
    det = (1 - w**2) ** 2 + (2 * zeta * w) ** 2
    a, b = (1 - w**2) / det, 2 * zeta * w / det  # x = a cos(w t) + b sin(w t) per unit forcing amplitude
    x0 = np.array([a, w * b])
    T = 2 * np.pi / w
    t_max = (np.arctan2(b, a) / w) % T
    problem = _shooting(ShootingProblem(flow, {"s": 3.0}), segments)
    located = problem.with_conditions([Tangency(flow, 0, t_max)], free=("s",)).solve(
        problem.with_conditions([Tangency(flow, 0, t_max)], free=("s",)).pack(x0, extras=np.array([t_max + 0.05])))
    s = located.parameters[flow.system.parameter_index("s")]
    assert located.accuracy[0] < 1e-9
    assert abs(s - 1 / np.sqrt(det)) <= located.accuracy[0] + 1e-12
    assert located.unknowns[-1] == pytest.approx(t_max, abs=1e-8)


def hopf_with_wall() -> PiecewiseSystem:
    return PiecewiseSystem(
        name="test_ms_hopf_wall", states=["x", "y"], parameters={"mu": 0.25, "c": 0.49, "r": 0.5},
        modes=[Mode("free", ["mu*x - y - x*(x**2 + y**2)", "x + mu*y - y*(x**2 + y**2)"])],
        surfaces={"wall": "x - c"},
        transitions=[Transition("free", "wall", Crossing.RISING, "free", reset=["x", "-r*y"])],
    )


@pytest.mark.parametrize("segments", [1, 4])
def test_autonomous_grazing_against_closed_form(segments):
    flow = Flow(hopf_with_wall())
    problem = _shooting(ShootingProblem(flow, {}), segments)
    conditioned = problem.with_conditions([Tangency(flow, 0, np.pi / 2)], free=("c",))
    # from (0, -0.5) the cycle turns counter-clockwise: x = 0.5 sin(t) peaks at t = pi/2
    located = conditioned.solve(conditioned.pack([0.0, -0.5], period=6.2, extras=np.array([np.pi / 2 + 0.05])))
    c = located.parameters[flow.system.parameter_index("c")]
    assert located.accuracy[0] < 1e-9
    assert abs(c - 0.5) <= located.accuracy[0] + 1e-12
    # DOP853 at the default rtol 1e-10 over one period: the period to 1e-9
    assert located.period == pytest.approx(2 * np.pi, abs=1e-9)


@pytest.fixture(scope="module")
def fold_curve_by_segments():
    from saltation.apps.paper import linear_response_state
    from saltation.models import trilinear
    from saltation.models.trilinear import DEFAULTS as TRI
    from saltation.special_points.continuation import (
        ContinuationSettings,
        continue_branch,
    )
    from saltation.special_points.loci import follow_locus

    flow = Flow(trilinear())
    problem = ShootingProblem(flow, {"omega": 0.6}, continuation_parameter="omega")
    branch = continue_branch(problem, linear_response_state(dict(TRI, omega=0.6)), 0.6,
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.6, 1.6)), directions=(1,))
    fold = next(sp for sp in branch.special_points if sp.kind is SpecialPointKind.FOLD)
    single = follow_locus(problem, fold, "f0", (0.2, 0.3), settings=ContinuationSettings(ds=0.01, ds_max=0.02))
    multiple = follow_locus(MultipleShootingProblem(problem, 2), fold, "f0", (0.2, 0.3),
                            settings=ContinuationSettings(ds=0.01, ds_max=0.02))
    return flow, single, multiple


def test_fold_curve_by_multiple_shooting_has_a_multiplier_one(fold_curve_by_segments):
    flow, _, curve = fold_curve_by_segments
    assert "increasing f0: reached a parameter bound" in curve.stop_detail
    assert len(curve) > 5
    tol = Tolerances(rtol=1e-12, atol=1e-14, exact_affine=False)
    for point in curve.points[:: max(1, len(curve) // 4)]:
        # the multipliers from the segments' matrices (periodic Schur): +1 to the condition's accuracy
        assert np.min(np.abs(point.multipliers - 1.0)) < 1e-7
        w, f0, x0 = point.parameter, point.second_parameter, point.state
        p = flow.parameters({"omega": w, "f0": f0})
        T = 2 * np.pi / w
        assert np.abs(flow.run(x0, 0.0, T, p, tolerances=tol).x1 - x0).max() < 1e-9
        h = 1e-6
        J = np.column_stack([(flow.run(x0 + h * e, 0.0, T, p, tolerances=tol).x1
                              - flow.run(x0 - h * e, 0.0, T, p, tolerances=tol).x1) / (2 * h) for e in np.eye(2)])
        # central differences: O(h^2) plus rounding 1e-12 / h, about 1e-6
        assert np.min(np.abs(np.linalg.eigvals(J) - 1.0)) < 1e-5


def test_fold_curves_by_single_and_multiple_shooting_agree(fold_curve_by_segments):
    """Both solve the same equations to 1e-12: where their f0 ranges overlap, omega(f0) interpolated on the
    single-shooting curve (a smooth curve, points 0.02 apart: cubic interpolation error below 1e-7)."""
    _, single, multiple = fold_curve_by_segments
    order = np.argsort(single.second_parameter)
    f0s, ws = single.second_parameter[order], single.parameter[order]
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(f0s, ws)
    inside = (multiple.second_parameter > f0s[0]) & (multiple.second_parameter < f0s[-1])
    assert inside.sum() > 5
    np.testing.assert_allclose(multiple.parameter[inside], spline(multiple.second_parameter[inside]), rtol=0, atol=1e-7)


def test_the_locus_command_shoots_with_segments(capsys):
    """``locus --segments 3``: the trilinear corner curve by multiple shooting, on its closed form
    ``f0 = x_c sqrt((k - m w^2)^2 + (c w)^2)`` to the corrector's 1e-9, as with single shooting."""
    import json

    from saltation.apps import cli
    from saltation.models.trilinear import DEFAULTS as TRI

    status = cli.main(["locus", "trilinear", "--kind", "nonsmooth_no_crossing", "--param", "omega", "--range",
                       "0.6,1.6", "--param2", "f0", "--range2", "0.05,0.2", "--segments", "3", "--json",
                       "--no-progress"])
    out, err = capsys.readouterr()
    assert status == 0, err
    (curve,) = json.loads(out)["curves"]
    w, f0 = np.array(curve["points"]).T
    assert len(w) > 5 and "reached a parameter bound" in curve["stop_reason"]
    m, c, k, xc = (TRI[a] for a in ("m", "c", "k", "x_c"))
    np.testing.assert_allclose(f0, xc * np.sqrt((k - m * w**2) ** 2 + (c * w) ** 2), rtol=0, atol=1e-9)
