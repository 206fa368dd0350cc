"""The bracket of a change of the event sequence, closed around a located grazing orbit.

Where the two sides of a corner differ by an excursion through a surface that one side misses, the
detector locates the grazing orbit by its defining system and corrects two points just either side of
it (``SpecialPointDetector._bracket_at_grazing``) instead of bisecting the secant down to the location
tolerance.  The bracket must be the same kind of object either way: two corrected points whose event
sequences differ, within ``locate_tol`` of each other, around the closed-form corner.

Reference: the onset of contact of the two-mass oscillator with stops (``tests/gallery/test_gallery_two_mass_stops.py``):
the free orbit is the harmonic response, and mass 1 reaches its stop at ``F = d1 / |X1|`` (closed form,
exact to rounding).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from saltation import Flow
from saltation.errors import ConvergenceError
from saltation.models.two_mass_stops import two_mass_stops
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points import detection, nonsmooth, points
from saltation.special_points.continuation import ContinuationSettings, continue_branch
sys.path.insert(0, str(Path(__file__).parents[1] / "gallery"))  # (a sibling folder's closed forms)
from test_gallery_two_mass_stops import F_ONSET_1, free_state0

F0 = 0.3
SETTINGS = ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(F0, 0.75))


def onset(monkeypatch, *, grazing_fails: bool):
    """The branch over the onset of contact, and the corrections spent bracketing its corner."""
    spent, inside = [], []
    bisect = detection.SpecialPointDetector._bisect_event_change
    on_secant = detection.SpecialPointDetector.on_secant

    def counting_bisect(self, a, b):
        spent.append(0)
        inside.append(True)
        try:
            return bisect(self, a, b)
        finally:
            inside.pop()

    def counting_on_secant(self, a, b, sigma):
        if inside:  # the corrections of the bracketing (not those of the smooth pieces' tests)
            spent[-1] += 1
        return on_secant(self, a, b, sigma)

    monkeypatch.setattr(detection.SpecialPointDetector, "_bisect_event_change", counting_bisect)
    monkeypatch.setattr(detection.SpecialPointDetector, "on_secant", counting_on_secant)
    if grazing_fails:
        def failing(*args, **kwargs):
            raise ConvergenceError("no grazing here (the test's stand-in)", [])

        for module in (nonsmooth, points):
            monkeypatch.setattr(module, "locate_grazing", failing)
    problem = ShootingProblem(Flow(two_mass_stops()), {"F": F0}, continuation_parameter="F")
    branch = continue_branch(problem, free_state0(F0), F0, settings=SETTINGS, directions=(1,))
    (sp,) = branch.special_points
    return sp, spent


@pytest.mark.parametrize("grazing_fails", [False, True], ids=["around the grazing orbit", "bisection"])
def test_the_bracket_holds_the_closed_form_corner(monkeypatch, grazing_fails):
    sp, spent = onset(monkeypatch, grazing_fails=grazing_fails)
    assert sp.kind.is_nonsmooth
    # the two ends have different event sequences and lie within locate_tol of each other (in the
    # unknowns and the parameter), and the corner is between them: exact to rounding, so 1e-14 of slack
    assert sp.event_labels_minus != sp.event_labels_plus
    assert sp.accuracy <= SETTINGS.locate_tol
    assert min(sp.bracket) - 1e-14 <= F_ONSET_1 <= max(sp.bracket) + 1e-14
    assert len(spent) == 1
    if grazing_fails:
        # bisection from a step of about 0.05 down to 1e-9: some 25 halvings
        assert spent[0] >= 20
    else:
        # the grazing orbit is missed by the first try (from the far end, the mirror grazing at -F is
        # found), found by the second after 7 halvings, then two corrections, up to three pairs
        assert spent[0] <= 7 + 6


def test_a_grazing_outside_the_bracket_is_not_used(monkeypatch):
    """A grazing orbit located elsewhere (here: at another parameter) places no point: bisection goes on."""
    located = nonsmooth.locate_grazing

    def elsewhere(*args, **kwargs):
        orbit = located(*args, **kwargs)
        return type(orbit)(**{**vars(orbit), "parameter": orbit.parameter + 1.0})

    for module in (nonsmooth, points):
        monkeypatch.setattr(module, "locate_grazing", elsewhere)
    sp, spent = onset(monkeypatch, grazing_fails=False)
    assert min(sp.bracket) - 1e-14 <= F_ONSET_1 <= max(sp.bracket) + 1e-14
    assert sp.accuracy <= SETTINGS.locate_tol
    assert spent[0] >= 20
