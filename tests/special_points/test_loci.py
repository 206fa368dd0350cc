"""Two-parameter curves of special points against closed forms and independent computations."""

from __future__ import annotations

import json
from dataclasses import fields

import numpy as np
import pytest

from saltation import Flow
from saltation.apps import cli
from saltation.branches.branch import Branch, SpecialPointKind, SpecialPointStatus, StopReason
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.engine.flow import Tolerances
from saltation.special_points.loci import follow_locus
from saltation.models import impact_oscillator
from saltation.models.impact_oscillator import DEFAULTS as IMPACT
from saltation.models.trilinear import DEFAULTS as TRI
from saltation.apps.paper import linear_response_state
from saltation.orbits.shooting import ShootingProblem

M, C, K, XC = (TRI[k] for k in ("m", "c", "k", "x_c"))
BRANCH_FIELDS = {f.name for f in fields(Branch)}
F0_RANGE = (0.05, 0.4)


@pytest.fixture(scope="module")
def trilinear_loci(trilinear_flow):
    problem = ShootingProblem(trilinear_flow, {"omega": 0.6}, continuation_parameter="omega")
    branch = continue_branch(
        problem, linear_response_state(dict(TRI, omega=0.6)), 0.6,
        settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.6, 1.6)), directions=(1,),
    )
    settings = ContinuationSettings(ds=0.01, ds_max=0.02, bounds=F0_RANGE)
    loci = {sp.kind: follow_locus(problem, sp, "f0", F0_RANGE, settings=settings) for sp in branch.special_points}
    return problem, loci


def test_corner_curves_against_closed_form(trilinear_loci):
    """The corners at w_A and w_B, where the free orbit's amplitude is x_c: f0 = x_c sqrt((k - m w^2)^2 + (c w)^2)."""
    _, loci = trilinear_loci
    for kind in (SpecialPointKind.NONSMOOTH_NO_CROSSING, SpecialPointKind.DISCONTINUOUS_FOLD):
        locus = loci[kind]
        w, f0 = locus.values.T
        assert len(w) > 50
        # the defining system is solved to 1e-10 in the residual; the closed form is exact
        np.testing.assert_allclose(f0, XC * np.sqrt((K - M * w**2) ** 2 + (C * w) ** 2), rtol=0, atol=1e-9)
        assert StopReason.PARAMETER_BOUND in (locus.stop_reason, *locus.stop_reasons)
        assert "reached a parameter bound" in locus.stop_detail
        assert f0.min() == pytest.approx(F0_RANGE[0]) or f0.max() == pytest.approx(F0_RANGE[1])


def test_fold_curve_points_satisfy_the_fold_conditions(trilinear_loci, trilinear_flow):
    """At points of the smooth fold curve: periodic, and the period map (by central differences of
    DOP853 integrations, no variational equation) has a multiplier +1."""
    _, loci = trilinear_loci
    locus = loci[SpecialPointKind.FOLD]
    assert len(locus) > 20
    tol = Tolerances(rtol=1e-12, atol=1e-14, exact_affine=False)
    for (w, f0), x0 in list(zip(locus.values, locus.states))[:: max(1, len(locus) // 6)]:
        p = trilinear_flow.parameters({"omega": w, "f0": f0})
        T = 2 * np.pi / w
        assert np.abs(trilinear_flow.run(x0, 0.0, T, p, tolerances=tol).x1 - x0).max() < 1e-9
        def differences(h):
            return np.column_stack([
                (trilinear_flow.run(x0 + h * e, 0.0, T, p, tolerances=tol).x1
                 - trilinear_flow.run(x0 - h * e, 0.0, T, p, tolerances=tol).x1) / (2 * h)
                for e in np.eye(2)
            ])

        # central differences extrapolated (Richardson): O(h^4) plus rounding 1e-12 / h, about 1e-6 with
        # h = 1e-6.  Plain central differences are off by O(h^2) times the third derivative of the period
        # map, which grows without bound towards the corner where the curve ends (1e-5 at 2e-6 from it).
        J = (4 * differences(5e-7) - differences(1e-6)) / 3
        assert np.min(np.abs(np.linalg.eigvals(J) - 1.0)) < 1e-5


def test_the_fold_curve_is_born_at_a_corner(trilinear_loci):
    """A codimension-two point on the w_B corner curve: the corner's set-valued multipliers stop crossing
    the unit circle where the smooth fold curve ends on it (the fold is born at the corner)."""
    _, loci = trilinear_loci
    corner = loci[SpecialPointKind.DISCONTINUOUS_FOLD]
    births = [c for c in corner.special_points if set(c.sides) == {"nonsmooth_no_crossing", "discontinuous_fold"}]
    assert births
    fold = loci[SpecialPointKind.FOLD]
    # the fold curve ends: it does not go on past the corner
    assert StopReason.MIN_STEP in (fold.stop_reason, *fold.stop_reasons) and "the corrector failed" in fold.stop_detail
    # on the fold curve itself: its end is labelled where it meets the corner curve (the corner located at
    # the f0 of the curve point whose orbit comes nearest to touching), within the stated accuracy of that
    # point, which is an end of the curve (near the corner the curve turns back in f0: its end is not its
    # lowest forcing), and of the birth
    # (the fold curve's cusp, a smooth codimension-two point, is named by codimension_two: test_neimark_sacker_curves)
    (label,) = [sp for sp in fold.special_points if sp.codimension_two is None]
    at = np.array([label.parameter, label.second_parameter])
    i_end = int(np.argmin(np.linalg.norm(fold.values - at, axis=1)))
    assert i_end in (0, len(fold) - 1)
    end = fold.values[i_end]
    nearest = min(births, key=lambda c: np.hypot(*(np.array([c.parameter, c.second_parameter]) - end)))
    step = np.max(np.linalg.norm(np.diff(fold.values, axis=0), axis=1))
    assert np.hypot(*(np.array([nearest.parameter, nearest.second_parameter]) - end)) <= nearest.accuracy + step
    assert label.sides[0] == "fold" and label.sides[1] in ("nonsmooth_no_crossing", "discontinuous_fold")
    assert np.hypot(*(np.array([label.parameter, label.second_parameter]) - end)) <= label.accuracy * (1 + 1e-9)
    assert label.second_parameter == pytest.approx(XC * np.sqrt((K - M * label.parameter ** 2) ** 2 + (C * label.parameter) ** 2),
                                            abs=1e-9)  # on the corner curve
    assert np.hypot(*(np.array([nearest.parameter - label.parameter, nearest.second_parameter - label.second_parameter]))) <= nearest.accuracy + label.accuracy


def test_grazing_curve_of_the_impact_oscillator_against_closed_form():
    flow = Flow(impact_oscillator())
    zeta = IMPACT["zeta"]
    problem = ShootingProblem(flow, {"s": 3.0}, continuation_parameter="s")
    w = IMPACT["omega"]
    det = (1 - w**2) ** 2 + (2 * zeta * w) ** 2
    x0 = np.array([(1 - w**2) / det, 2 * zeta * w**2 / det])
    branch = continue_branch(problem, x0, 3.0, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.5, 3.0)),
                             directions=(-1,))
    (grazing,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.GRAZING]
    locus = follow_locus(problem, grazing, "omega", (0.6, 0.95))
    s, omega = locus.values.T
    np.testing.assert_allclose(s, 1 / np.sqrt((1 - omega**2) ** 2 + (2 * zeta * omega) ** 2), rtol=0, atol=1e-9)
    assert omega.min() == pytest.approx(0.6) and omega.max() == pytest.approx(0.95)
    assert set(locus.curve_kinds) == {SpecialPointKind.GRAZING}  # an impact: unbounded all along, no codimension-two point


def test_a_curve_is_a_branch_written_and_read_as_one(trilinear_loci, tmp_path):
    """A curve is a Branch (its kinds a column, its stops per direction): it round-trips through a branch file,
    and the release-0.1 views (``kinds``, ``record()``) still answer, with a warning."""
    from saltation.output.codecs import locus_record
    from saltation.output.io import load_branch_json, save_branch_json

    _, loci = trilinear_loci
    corner = loci[SpecialPointKind.DISCONTINUOUS_FOLD]
    assert type(corner).__mro__[1] is Branch and not any(f.name not in BRANCH_FIELDS for f in fields(corner))
    assert corner.curve_of is SpecialPointKind.DISCONTINUOUS_FOLD
    assert all(isinstance(k, SpecialPointKind) for k in corner.curve_kinds)
    assert [c.sides for c in corner.special_points] == [
        (a.value, b.value) for a, b in zip(corner.curve_kinds, corner.curve_kinds[1:]) if a is not b]
    again = load_branch_json(save_branch_json(corner, tmp_path / "curve.json"))
    assert again.curve_kinds == corner.curve_kinds and again.curve_of is corner.curve_of
    assert (again.stop_reason, again.stop_reasons, again.stop_detail) == (
        corner.stop_reason, corner.stop_reasons, corner.stop_detail)
    np.testing.assert_array_equal(again.second_parameter, corner.second_parameter)
    with pytest.warns(DeprecationWarning, match="Branch.curve_kinds"):
        assert corner.kinds == [k.value for k in corner.curve_kinds]
    with pytest.warns(DeprecationWarning, match="locus_record"):
        assert corner.record() == locus_record(corner)


def test_locus_command_line_contract(tmp_path, capsys):
    status = cli.main([
        "locus", "trilinear", "--kind", "nonsmooth_no_crossing", "--param", "omega", "--range", "0.6,1.6",
        "--param2", "f0", "--range2", "0.05,0.4", "--json", "--no-progress", "--out", str(tmp_path),
    ])
    out, err = capsys.readouterr()
    assert status == 0, err
    record = json.loads(out)
    assert set(record) == {"model", "kind", "param", "param2", "curves"}
    assert (record["model"], record["kind"], record["param"], record["param2"]) == ("trilinear", "nonsmooth_no_crossing", "omega", "f0")
    (curve,) = record["curves"]
    assert set(curve) == {"points", "stop_reason", "special_points"}
    w, f0 = np.array(curve["points"]).T
    np.testing.assert_allclose(f0, XC * np.sqrt((K - M * w**2) ** 2 + (C * w) ** 2), rtol=0, atol=1e-9)
    written = json.loads((tmp_path / "trilinear_nonsmooth_no_crossing_omega_f0_locus.json").read_text())
    assert written == record
    assert (tmp_path / "trilinear_nonsmooth_no_crossing_omega_f0_locus.png").exists()
    # bad usage: exit 2, one line
    assert cli.main(["locus", "trilinear", "--kind", "nope", "--param", "omega", "--range", "0.6,1.6",
                     "--param2", "f0", "--range2", "0.05,0.4"]) == 2
    assert "unknown kind 'nope'" in capsys.readouterr().err


def test_a_curve_is_a_branch_in_two_parameters(trilinear_loci):
    """A curve is a Branch: its points carry both parameters and their orbits' records, and its
    codimension-two points are SpecialPoint records.  Every fold-curve orbit has the multiplier +1 that
    defines it (the condition is solved to 1e-10 on the bordered test function, whose slope in the
    multiplier is of order one here)."""
    _, loci = trilinear_loci
    fold = loci[SpecialPointKind.FOLD]
    assert isinstance(fold, Branch)
    assert (fold.parameter_name, fold.second_parameter_name, fold.curve_of) == ("omega", "f0", SpecialPointKind.FOLD)
    np.testing.assert_array_equal(fold.values, np.column_stack([fold.parameter, fold.second_parameter]))
    for point in fold.points:
        assert np.min(np.abs(point.multipliers - 1.0)) <= 1e-7
        assert np.isfinite(point.period) and point.event_labels
    # (the fold curve's cusp, a smooth codimension-two point, is named by codimension_two: test_neimark_sacker_curves)
    (label,) = [sp for sp in fold.special_points if sp.codimension_two is None]
    assert label.kind is SpecialPointKind.CODIMENSION_TWO
    assert label.status is SpecialPointStatus.LOCATED
    corner = loci[SpecialPointKind.DISCONTINUOUS_FOLD]
    assert corner.special_points
    for c in corner.special_points:
        assert c.kind is SpecialPointKind.CODIMENSION_TWO and c.status is SpecialPointStatus.BRACKETED
        a, b = corner.values[c.index], corner.values[c.index + 1]
        assert min(a[0], b[0]) <= c.parameter <= max(a[0], b[0])
        assert min(a[1], b[1]) <= c.second_parameter <= max(a[1], b[1])
