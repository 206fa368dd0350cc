"""Every period doubling and Neimark-Sacker point of a branch says whether what is born is stable.

``SpecialPoint.criticality`` comes from the cubic coefficient of the period map's normal form
(:mod:`saltation.orbits.criticality`, itself checked against the period-2 branches followed from the points in
``tests/orbits/test_second_order.py``).  Here: it is on the points a continuation locates, it agrees with the
period-2 branch followed from the point (born beyond the doubling and stable: supercritical; before it and
unstable: subcritical), and it survives a branch file.  Along a period-doubling curve in two parameters the
coefficient changes sign at a generalised period doubling: located there, and checked against the sign of the
coefficient at the period doublings of one-parameter branches on either side of it.
"""

from __future__ import annotations

import numpy as np
import pytest

from saltation import Flow, find_periodic_orbit
from saltation.kinds import CodimensionTwoKind, Criticality, SpecialPointKind
from saltation.models import bouncing_ball, two_mass_stops
from saltation.output.io import load_branch_json, save_branch_json
from saltation.special_points.branch_switching import follow_period_doubled_branch
from saltation.special_points.continuation import ContinuationSettings, continue_orbit
from saltation.special_points.loci import follow_locus

TWO_PI = 2.0 * np.pi
TWO_MASS_STATE = [0.8869838955762865, 0.02956094651817481, 1.3985524338147999, -0.19102019176461646]


def _ball_state(A: float) -> np.ndarray:
    """The ball's period-1 orbit at t = 0, in closed form (one impact a period, ``v+ = g T / 2``)."""
    g, e, w = 9.81, 0.5, TWO_PI
    T = TWO_PI / w
    t_i = np.arccos((1 - e) * np.pi * g / ((1 + e) * A * w**2)) / w
    tau = (-t_i) % T
    return np.array([A * np.sin(w * t_i) + g * T / 2 * tau - g * tau**2 / 2, g * T / 2 - g * tau])


def test_a_located_period_doubling_carries_its_criticality_and_keeps_it_in_files(tmp_path):
    orbit = find_periodic_orbit(Flow(bouncing_ball()), _ball_state(0.37), parameters={"A": 0.37})
    branch = continue_orbit(orbit, "A", bounds=(0.37, 0.38), directions=(1,),
                            settings=ContinuationSettings(ds=0.002, ds_max=0.004))
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    assert pd.criticality is Criticality.SUPERCRITICAL
    b, accuracy = pd.normal_form
    assert b > accuracy > 0
    # what it predicts: the period-2 branch leaves beyond the doubling, where the period-1 orbits are unstable,
    # and is stable there
    doubled = follow_period_doubled_branch(branch, pd, settings=ContinuationSettings(ds=0.001, ds_max=0.001,
                                                                                     max_points=6))
    assert all(p.parameter > pd.parameter for p in doubled.points[1:])
    assert all(p.stable for p in doubled.points[1:])
    path = save_branch_json(branch, tmp_path / "ball.json")
    again = load_branch_json(path)
    (pd2,) = [sp for sp in again.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    assert pd2.criticality is Criticality.SUPERCRITICAL and pd2.normal_form == pytest.approx(pd.normal_form)


def test_a_subcritical_period_doubling_is_said_so_and_its_doubled_orbits_are_unstable():
    orbit = find_periodic_orbit(Flow(two_mass_stops()), TWO_MASS_STATE, parameters={"omega": 0.452})
    branch = continue_orbit(orbit, "omega", bounds=(0.4512, 0.452), directions=(-1,),
                            settings=ContinuationSettings(ds=3e-4, ds_max=5e-4))
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    assert pd.criticality is Criticality.SUBCRITICAL
    doubled = follow_period_doubled_branch(branch, pd, settings=ContinuationSettings(
        ds=2e-4, ds_max=2e-4, max_points=6, bounds=(0.4505, 0.453)))
    assert all(p.parameter < pd.parameter for p in doubled.points[1:])
    assert not any(p.stable for p in doubled.points[1:])


def _flip_coefficient_at(F: float, state, omega: float) -> tuple[float, float]:
    """The period doubling of the one-parameter branch in omega at fixed F near ``omega``, and its ``b``."""
    flow = Flow(two_mass_stops())
    orbit = find_periodic_orbit(flow, state, parameters={"omega": omega - 0.002, "F": F})
    branch = continue_orbit(orbit, "omega", bounds=(omega - 0.002, omega + 0.004), directions=(1,),
                            settings=ContinuationSettings(ds=5e-4, ds_max=1e-3))
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    return pd.parameter, pd.normal_form[0]


def test_a_generalized_period_doubling_lies_where_the_flip_coefficient_changes_sign():
    orbit = find_periodic_orbit(Flow(two_mass_stops()), TWO_MASS_STATE, parameters={"omega": 0.452})
    branch = continue_orbit(orbit, "omega", bounds=(0.4512, 0.452), directions=(-1,),
                            settings=ContinuationSettings(ds=3e-4, ds_max=5e-4))
    index = next(i for i, sp in enumerate(branch.special_points) if sp.kind is SpecialPointKind.PERIOD_DOUBLING)
    locus = follow_locus(branch, index, "F", (0.87, 1.01), settings=ContinuationSettings(ds=0.01, ds_max=0.03),
                         normal_forms=True)
    (gpd,) = [sp for sp in locus.special_points if sp.codimension_two is CodimensionTwoKind.GENERALIZED_PERIOD_DOUBLING]
    lo, hi = gpd.bracket
    assert lo <= gpd.parameter <= hi
    F = gpd.second_parameter
    delta = 0.004
    below = _flip_coefficient_at(F - delta, gpd.state, gpd.parameter)
    above = _flip_coefficient_at(F + delta, gpd.state, gpd.parameter)
    assert below[1] * above[1] < 0  # the coefficient changes sign across it
    # the root of the coefficient between the two, by the secant, lies within the secant's error of the point
    root = F - delta + 2 * delta * below[1] / (below[1] - above[1])
    assert abs(root - F) < 0.2 * delta
