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
from stick_slip_forced import reference_flow, stick_slip

from saltation import ContinuationSettings, find_periodic_orbit
from saltation.special_points.continuation import continue_orbit

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
