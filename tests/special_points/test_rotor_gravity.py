"""Every special point of a rotor's branch, whatever the step: the Jeffcott rotor with gravity against a snubber ring.

``jeffcott_gravity`` (``../shared/trial-models/jeffcott_snubber.py``, written by a user from the docs): the free
whirl is a circle offset by gravity, so contact starts at one point of it (a grazing, in closed form where
``|Z(omega)| + g = delta``), and the branch of T-periodic orbits beyond goes through period doublings,
Neimark-Sacker points, folds and more grazings.  With ``ds_max = 0.1`` the two period doublings just past the
first contact (0.78767 and 0.79621, where a multiplier reaches -2.4 between them) used to vanish in one step,
and a false Neimark-Sacker point was reported where a complex pair turned real (1.0026).

Reference: ``tests/rotor_reference.py``, a scipy implementation written without the library (event-located
contact arcs, variational equations checked against finite differences, each point located by its own defining
condition with brentq or Newton), :data:`GRAVITY_REFERENCE`: each point with its error bound.
"""

from __future__ import annotations

import numpy as np
import pytest

import rotor_reference as reference
from conftest import trial_model
from saltation import Flow
from saltation.branches.branch import SpecialPointKind as K
from saltation.branches.check import check_branch
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import ContinuationSettings, continue_branch

KINDS = {"period doubling": {K.PERIOD_DOUBLING}, "torus": {K.NEIMARK_SACKER}, "fold": {K.FOLD},
         # a grazing of a continuous field changes the event sequence without a jump of the multipliers'
         # count: located as a grazing, or classified from its sides as a corner without crossing
         "grazing": {K.GRAZING, K.NONSMOOTH_NO_CROSSING}}


def gravity_branch(ds_max: float):
    system = trial_model("jeffcott_snubber").jeffcott_gravity()
    q = dict(system.defaults)
    omega0 = 0.7
    z = q["rho"] * omega0**2 / (1.0 - omega0**2 + 2j * q["zeta"] * omega0)
    x0 = np.array([z.real, z.imag - q["g"], (1j * omega0 * z).real, (1j * omega0 * z).imag])
    problem = ShootingProblem(Flow(system), {"omega": omega0}, continuation_parameter="omega")
    return continue_branch(problem, x0, omega0, settings=ContinuationSettings(bounds=(0.7, 1.03), ds_max=ds_max),
                           directions=(1,))


@pytest.mark.parametrize("ds_max", [0.02, 0.1])
def test_every_special_point_of_the_rotor_with_gravity(ds_max):
    branch = gravity_branch(ds_max)
    assert check_branch(branch).ok
    points = branch.special_points
    first, rest = points[0], points[1:]
    # first contact: |Z| + g = delta in closed form (the reference's brentq, to rounding)
    assert first.kind in KINDS["grazing"]
    assert abs(first.parameter - reference.contact_onsets(**reference.GRAVITY)[0]) <= first.accuracy + 1e-12
    assert len(rest) == len(reference.GRAVITY_REFERENCE)
    for sp, (kind, omega, bound) in zip(rest, reference.GRAVITY_REFERENCE):
        assert sp.kind in KINDS[kind], (sp, kind, omega)
        assert abs(sp.parameter - omega) <= sp.accuracy + bound, (sp, kind, omega)


def test_the_first_contact_continued_in_gravity_against_its_closed_form(capsys):
    """``saltation locus --kind grazing`` from the first contact: the touched transition is the free mode's (the
    one the orbit does not cross), whatever rounding leaves at the touch (it used to pick contact -> free on the
    last digit of omega, and the curve could not start).  On the curve, ``|Z(omega)| + g = delta``."""
    import json

    from saltation.apps import cli

    model = f"{trial_model('jeffcott_snubber').__file__}:jeffcott_gravity"
    status = cli.main(["locus", model, "--kind", "grazing", "--param", "omega", "--range", "0.7,0.8", "--param2", "g",
                       "--range2", "0.1,0.3", "--json", "--no-progress", "--ds-max", "0.05"])
    assert status == 0
    record = json.loads(capsys.readouterr().out)
    (curve,) = record["curves"]
    points = np.array(curve["points"])
    assert len(points) > 5 and np.ptp(points[:, 1]) > 0.1
    q = dict(reference.GRAVITY)
    for omega, g in points:
        z = q["rho"] * omega**2 / (1.0 - omega**2 + 2j * q["zeta"] * omega)
        # the defining system is solved to the corrector's tolerance (1e-10) on a state of size 1
        assert abs(z) + g - q["delta"] == pytest.approx(0.0, abs=1e-8)


def test_a_locus_whose_branch_stops_short_says_so(capsys):
    """No fold reached because the branch stopped at --max-points: an error that says where and why, not an
    empty list of curves with exit status 0."""
    from saltation.apps import cli

    model = f"{trial_model('jeffcott_snubber').__file__}:jeffcott_gravity"
    status = cli.main(["locus", model, "--kind", "fold", "--param", "omega", "--range", "0.7,1.0", "--param2", "g",
                       "--range2", "0.1,0.3", "--json", "--no-progress", "--max-points", "20"])
    assert status == 1
    err = capsys.readouterr().err
    assert "no fold point" in err and "maximum number of points" in err and "--max-points" in err
