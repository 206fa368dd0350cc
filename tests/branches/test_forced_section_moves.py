"""A forced orbit whose event drifts onto the section: the branch moves its section off it and records where.

A forced oscillator on a moving belt whose static friction exceeds the kinetic one, the stick phase a mode of its
own (``tests/stick_slip_forced.py``, written as a user wrote it).  Continued in the forcing amplitude ``a`` from
1 downwards, its orbit's slip-to-stick event reaches the section ``t0 = 0`` near ``a = 0.51918``: the section
state then lies on the stick surface, where the stroboscopic map has a kink (the stick phase collapses the
velocity), and Newton cycled across it; the branch stopped there at the minimum step size, at an ordinary
orbit.  The branch now moves its section to the middle of the orbit's longest stretch between events
(:meth:`~saltation.orbits.shooting.ShootingProblem.move_section`) and goes on to its bound; each point records
its section ``t0``.  Reference: the same oscillator integrated by ``solve_ivp`` with its own stick-slip logic
(``reference_flow``): every point's state returns to itself over one forcing period from its own ``t0``, and
its multipliers are those of central differences of that map.
"""

from __future__ import annotations

import math

import numpy as np
import sys
from pathlib import Path

from stick_slip_forced import reference_flow, stick_slip

from saltation import ContinuationSettings, find_periodic_orbit
from saltation.special_points.continuation import continue_orbit

sys.path.insert(0, str(Path(__file__).parents[1] / "literature"))  # (the corpus's models, for the converter)

OMEGA = 0.8
PERIOD = 2 * math.pi / OMEGA


def reference_multipliers(x: np.ndarray, t0: float, a: float, h: float = 1e-6) -> np.ndarray:
    cols = []
    for k in range(2):
        e = np.zeros(2)
        e[k] = h
        plus, minus = (reference_flow(x + s * e, t0, t0 + PERIOD, a=a) for s in (1.0, -1.0))
        cols.append((plus - minus) / (2 * h))
    return np.linalg.eigvals(np.array(cols).T)


def test_an_event_that_reaches_the_section_moves_it_and_the_branch_goes_on():
    orbit = find_periodic_orbit(stick_slip(), [1.2, 0.7], parameters={"a": 1.0})
    branch = continue_orbit(orbit, "a", bounds=(0.3, 1.0), settings=ContinuationSettings(ds=0.02, ds_max=0.05),
                            directions=(-1,))
    assert branch.stop_reason.value == "reached a parameter bound", (branch.stop_reason, branch.stop_detail)
    assert min(branch.parameter) <= 0.3 + 1e-9
    moved = [pt for pt in branch.points if pt.t0 != 0.0]
    assert moved and all(pt.parameter < 0.5192 for pt in moved), "the section moved where the event reached it"
    assert {round(pt.t0, 9) for pt in moved} == {round(moved[0].t0, 9)}, "and once"
    for pt in branch.points[::6] + moved[:3] + moved[-1:]:
        back = reference_flow(pt.state, pt.t0, pt.t0 + PERIOD, a=pt.parameter)
        # shooting to 1e-10, the default integration and the reference's rtol 1e-12: the state closes to 1e-8
        np.testing.assert_allclose(back, pt.state, rtol=0, atol=1e-8)
    for pt in (branch.points[len(branch.points) // 3], moved[len(moved) // 2]):
        mu = np.sort(np.abs(np.asarray(pt.multipliers)))
        ref = np.sort(np.abs(reference_multipliers(np.asarray(pt.state), pt.t0, pt.parameter)))
        # central differences of step 1e-6 on a map integrated to 1e-12: about 1e-6
        np.testing.assert_allclose(mu, ref, rtol=0, atol=1e-5)


def test_a_special_point_is_continued_at_its_own_section():
    """A special point carries the section its state lies at: a curve started from it with a problem whose
    section differs (a branch's problem after it moved its section) takes the point's.  The current-mode boost
    converter's period doubling (the literature corpus's model, a clock h(t) on a forced model), located at
    ``t0 = 0``, continued in ``C`` by a problem built at ``t0 = 0.5``, against the closed-form map's brentq."""
    import boost_reference as ref
    from corpus import load_cases

    from saltation import Flow, ShootingProblem
    from saltation.special_points.loci import follow_locus

    case = next(c for c in load_cases() if c.name == "boost_current_mode")
    orbit = find_periodic_orbit(case.model(), case.orbit.guess, parameters=dict(case.orbit.parameters), mode0="off")
    branch = continue_orbit(orbit, "I_ref", bounds=(1.5, 1.8), settings=ContinuationSettings(ds_max=0.02),
                            directions=(1,))
    point = next(sp for sp in branch.special_points if sp.kind.value == "period_doubling")
    assert point.t0 == 0.0
    problem = ShootingProblem(Flow(case.model()), {"I_ref": point.parameter}, continuation_parameter="I_ref",
                              t0=0.5, mode0="off")
    locus = follow_locus(problem, point, "C", (11e-6, 13e-6))
    assert problem.t0 == 0.0
    assert len(locus.values) >= 5, locus.stop_reason
    for I_ref, C in locus.values:
        # the curve's corrector to 1e-10 on the shooting residual: its points within 1e-7 of the closed form
        assert abs(I_ref - ref.period_doubling(dict(ref.DEFAULTS, C=C), 1.45, 2.0)) <= 1e-7


def test_the_sections_travel_with_the_branch_file(tmp_path):
    """Each point's and special point's section is written to the branch file and read back (files written
    before it was recorded read as 0)."""
    from saltation.output.io import load_branch_json, save_branch_json

    orbit = find_periodic_orbit(stick_slip(), [1.2, 0.7], parameters={"a": 1.0})
    branch = continue_orbit(orbit, "a", bounds=(0.45, 1.0), settings=ContinuationSettings(ds=0.02, ds_max=0.05),
                            directions=(-1,))
    assert any(pt.t0 != 0.0 for pt in branch.points)
    path = tmp_path / "branch.json"
    save_branch_json(branch, path)
    back = load_branch_json(path)
    assert [pt.t0 for pt in back.points] == [pt.t0 for pt in branch.points]
    assert [sp.t0 for sp in back.special_points] == [sp.t0 for sp in branch.special_points]
