"""Feigin's scenario at the border collisions a branch finds, against what the branch itself does there.

A non-smooth fold (two orbits on one side meet at the point and vanish) is where the continuation parameter
turns back: the branch points before and after the point lie on the same side of it (the paper's
discontinuous fold of the trilinear model at w_B, Figs. 3 and 4).  Persistence is where the branch goes on
through it: the corner at w_A, the impact oscillator's grazing and the friction oscillator's sliding
bifurcations.  The branch checker holds that invariant; the scenario is kept in files and shown in the
summaries and the command line's table.
"""

from __future__ import annotations

import copy
import json
from dataclasses import replace

import numpy as np
import pytest

from saltation import Flow
from saltation.branches.check import check_branch
from saltation.kinds import BorderScenario
from saltation.models import friction_oscillator, impact_oscillator, trilinear
from saltation.models.friction_oscillator import DEFAULTS as FRICTION
from saltation.models.impact_oscillator import DEFAULTS as IMPACT
from saltation.models.trilinear import DEFAULTS as TRI
from saltation.models.trilinear import linear_response_state
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import ContinuationSettings, continue_branch


@pytest.fixture(scope="module")
def trilinear_branch():
    problem = ShootingProblem(Flow(trilinear()), {"omega": 0.6}, continuation_parameter="omega")
    return continue_branch(problem, linear_response_state(dict(TRI, omega=0.6)), 0.6,
                           settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.6, 1.6)), directions=(1,))


def sides_of(branch, sp) -> tuple[float, float]:
    """The branch parameter before and after the point, relative to it."""
    lam = branch.parameter
    return lam[sp.index] - sp.parameter, lam[sp.index + 1] - sp.parameter


def test_the_discontinuous_fold_of_the_trilinear_model_is_a_nonsmooth_fold_where_the_branch_turns(trilinear_branch):
    (fold,) = [sp for sp in trilinear_branch.special_points if sp.kind.value == "discontinuous_fold"]
    assert fold.scenario is BorderScenario.NONSMOOTH_FOLD and fold.period_two is False
    before, after = sides_of(trilinear_branch, fold)
    assert before > 0 and after > 0  # both orbits lie above w_B: the parameter turns back at the corner
    # the real multiplier 1.418 of the contact side is the odd count
    assert np.count_nonzero((np.abs(fold.multipliers_minus.imag) < 1e-12) & (fold.multipliers_minus.real > 1)) == 1


def test_the_corner_at_w_a_is_a_persistence_where_the_branch_goes_on(trilinear_branch):
    (corner,) = [sp for sp in trilinear_branch.special_points if sp.kind.value == "nonsmooth_no_crossing"]
    assert corner.scenario is BorderScenario.PERSISTENCE and corner.period_two is False
    before, after = sides_of(trilinear_branch, corner)
    assert before < 0 < after
    (smooth,) = [sp for sp in trilinear_branch.special_points if sp.kind.value == "fold"]
    assert smooth.scenario is None and smooth.period_two is None  # a smooth point has no border


def test_the_impact_oscillators_grazing_persists_with_a_period_two_orbit():
    """The crossing side's multiplier grows without bound along the negative real axis (Nordmark's map, its
    nearest orbit's is -656): counted as < -1 it makes a persistence with a period-two orbit born, and the
    branch goes on into the impacting orbits."""
    zeta, w = IMPACT["zeta"], IMPACT["omega"]
    det = (1 - w**2) ** 2 + (2 * zeta * w) ** 2
    problem = ShootingProblem(Flow(impact_oscillator()), {"s": 3.0}, continuation_parameter="s")
    branch = continue_branch(problem, np.array([(1 - w**2) / det, 2 * zeta * w**2 / det]), 3.0,
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.5, 3.0)), directions=(-1,))
    (g,) = [sp for sp in branch.special_points if sp.kind.value == "grazing"]
    assert complex(-np.inf, 0.0) in list(g.multipliers_plus)
    assert g.scenario is BorderScenario.PERSISTENCE and g.period_two is True
    before, after = sides_of(branch, g)
    assert before * after < 0
    assert branch.points[g.index + 1].multipliers.real.min() < -1  # the impacting orbits are flip-unstable


def test_the_sliding_bifurcations_of_the_friction_oscillator_persist():
    zeta, f_, a, w = (FRICTION[k] for k in ("zeta", "F", "a", "omega"))
    det = (1 - w**2) ** 2 + (2 * zeta * w) ** 2
    amplitude, phi = a / np.sqrt(det), np.arctan2(2 * zeta * w, 1 - w**2)
    x0 = np.array([f_ + amplitude * np.cos(-phi), -amplitude * w * np.sin(-phi)])
    problem = ShootingProblem(Flow(friction_oscillator()), {"v_b": 2.5}, continuation_parameter="v_b")
    branch = continue_branch(problem, x0, 2.5, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.85, 2.5)),
                             directions=(-1,))
    kinds = {sp.kind.value: sp for sp in branch.special_points}
    assert {"grazing_sliding", "switching_sliding", "crossing_sliding"} <= set(kinds)
    for sp in branch.special_points:
        assert sp.scenario is BorderScenario.PERSISTENCE, sp
        before, after = sides_of(branch, sp)
        assert before * after < 0


def test_the_checker_holds_the_scenario_against_the_branch(trilinear_branch):
    assert check_branch(trilinear_branch).ok
    wrong = copy.copy(trilinear_branch)
    wrong.special_points = [
        replace(sp, one_sided=replace(sp.one_sided, scenario=(BorderScenario.PERSISTENCE if sp.scenario is
                                                              BorderScenario.NONSMOOTH_FOLD else BorderScenario.NONSMOOTH_FOLD)))
        if sp.scenario is not None else sp for sp in trilinear_branch.special_points]
    found = [v for v in check_branch(wrong).violations if v.rule == "border_scenario"]
    assert len(found) == 2
    assert any("says persistence, but the branch turns back at it" in v.message for v in found)
    assert any("says nonsmooth_fold, but the branch goes on through it" in v.message for v in found)
    # an undetermined scenario claims nothing
    vague = copy.copy(trilinear_branch)
    vague.special_points = [replace(sp, one_sided=replace(sp.one_sided, scenario=BorderScenario.UNDETERMINED,
                                                          period_two=None)) if sp.scenario is not None else sp
                            for sp in trilinear_branch.special_points]
    assert check_branch(vague).ok


def test_the_scenario_is_kept_in_files_and_shown(trilinear_branch, tmp_path):
    from saltation.apps.paper import special_point_table
    from saltation.output.codecs import (
        branch_from_dict,
        branch_to_dict,
        special_point_record,
    )
    from saltation.output.io import (
        load_branch_csv,
        load_branch_json,
        load_special_points_json,
        save_branch_csv,
        save_branch_json,
        save_special_points_json,
    )
    from saltation.summary import special_point_summary

    branch = copy.copy(trilinear_branch)
    # a side along the negative real axis, as at an impact's grazing
    branch.special_points = [replace(sp, one_sided=replace(sp.one_sided, multipliers_plus=np.array(
        [complex(-np.inf, 0.0), 0.5]), period_two=True)) if sp.kind.value == "nonsmooth_no_crossing" else sp
        for sp in trilinear_branch.special_points]
    for again in (load_branch_json(save_branch_json(branch, tmp_path / "b.json")),
                  load_branch_csv(save_branch_csv(branch, tmp_path / "b.csv"))):
        for a, b in zip(again.special_points, branch.special_points):
            assert (a.scenario, a.period_two) == (b.scenario, b.period_two)
            if b.multipliers_plus is not None:
                np.testing.assert_array_equal(a.multipliers_plus, b.multipliers_plus)
    d = json.loads((tmp_path / "b.json").read_text())
    # files of the same version before these keys (no "scenario", "period_two") read as not asked
    for sp in d["special_points"]:
        if sp["one_sided"] is not None:
            sp["one_sided"].pop("scenario")
            sp["one_sided"].pop("period_two")
            sp["one_sided"]["a_key_of_a_later_release"] = 1  # and readers skip keys they do not know
    older = branch_from_dict(d)
    assert all(sp.scenario is None and sp.period_two is None for sp in older.special_points)
    assert branch_to_dict(older)["version"] == 2
    records = [special_point_record(sp, "trilinear", "omega") for sp in trilinear_branch.special_points]
    assert [r.get("scenario") for r in records] == ["persistence", None, "nonsmooth_fold"]
    assert load_special_points_json(save_special_points_json(records, tmp_path / "sp.json")) == records
    table = special_point_table(records).splitlines()
    assert table[0].endswith("border collision")
    assert table[1].endswith("persistence") and table[3].endswith("nonsmooth_fold") and table[2].endswith("-")
    text = special_point_summary(trilinear_branch.special_points[2])
    assert "| border collision (Feigin) | nonsmooth_fold |" in text
