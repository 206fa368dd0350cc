"""Sliding bifurcations of a forced relay with a tilted switching line, against closed forms.

    x' = y,  y' = -x - 2 zeta y - F sgn(s) + a cos(omega t),  s = y + kappa x - v

(zeta, F, a, omega, kappa) = (0.1, 0.5, 1, 0.8, 0.5), continued in v and then in (v, kappa).  The
references (``tests/tilted_relay_reference.py``, numpy and scipy only) are the modes' flows in closed
form, the sliding motion x' = v - kappa x on the line in closed form, event times by brentq:

* grazing-sliding: the s < 0 slip orbit touches the line at v = kappa F + A sqrt(kappa^2 + omega^2)
  (v = 2.6446891410941484 at kappa = 0.5);
* switching-sliding: periodicity plus G(t_e, x_e) = F at the arrival from s < 0 (the plus field tangent
  there, invisibly), fsolve in (t_e, v) (v = 2.3642021348755 at kappa = 0.5).

Along kappa in [0.3, 0.7] both curves keep their orbits' event sequence: the arrival, the sliding
exit into s < 0 and the grazing all stay inside (0, T) (checked on the references below).

The references are checked by scipy's DOP853 with event location (Filippov's convex combination
integrated as an ODE), so that they cannot be wrong silently.
"""

from __future__ import annotations

import numpy as np
import pytest
import tilted_relay_reference as R

from saltation import Flow
from saltation.branches.branch import SpecialPointKind
from saltation.models.tilted_relay import DEFAULTS, tilted_relay
from saltation.orbits.shooting import ShootingProblem, find_periodic_orbit
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.special_points.loci import follow_locus

T = 2 * np.pi / DEFAULTS["omega"]
KAPPA_RANGE = (0.3, 0.7)
V_GRAZING_SLIDING, T_GRAZING_SLIDING = R.grazing_sliding()
V_SWITCHING, T_SWITCHING, X_SWITCHING, CURVATURE_SWITCHING = R.switching_sliding_point()
V_SLIDING = 2.5  # between the two: the orbit arrives, slides and leaves into s < 0


def test_the_reference_model_is_the_model():
    assert R.DEFAULTS == DEFAULTS


# -- the references, checked on their own ------------------------------------------------------------------------
def test_reference_sliding_orbit_against_brute_force():
    """The closed-form orbit with sliding, integrated over a period by DOP853 (rtol 1e-12) with event
    location and Filippov's convex combination: it returns to itself and its events are the closed form's.
    (DOP853 at rtol 1e-12 over one period with two located events: about 1e-11; 1e-9 leaves room.)"""
    p = R.params(v=V_SLIDING)
    orbit = R.sliding_orbit(p)
    t_e, x_e, t_x, x_x = orbit
    z0 = R.orbit_state(0.0, orbit, p)
    z1, events = R.brute_force(z0, 0.0, T, p)
    assert [kind for _, kind in events] == ["sliding_start", "sliding_end"]
    assert events[0][0] == pytest.approx(t_e, abs=1e-9)
    assert events[1][0] == pytest.approx(t_x, abs=1e-9)
    np.testing.assert_allclose(z1, z0, rtol=0, atol=1e-9)
    # at the arrival both fields push into the line, at the exit the s < 0 field is tangent
    assert abs(R.G(t_e, x_e, p)) < p["F"]
    assert R.G(t_x, x_x, p) == pytest.approx(-p["F"], abs=1e-12)


def test_reference_grazing_sliding_closed_form():
    """The closed form against one root (the maximum of s along the slip orbit); the slip orbit misses the
    line above it (no event for DOP853 over a period) and slides below it."""
    v_root, t_root = R.grazing_sliding_by_root()
    assert V_GRAZING_SLIDING == pytest.approx(v_root, abs=1e-12)
    assert T_GRAZING_SLIDING == pytest.approx(t_root, abs=1e-8)
    above = R.params(v=V_GRAZING_SLIDING + 1e-3)
    z0 = R.response(0.0, -1, above)
    z1, events = R.brute_force(z0, 0.0, T, above)
    assert events == [] and np.abs(z1 - z0).max() < 1e-9
    below = R.params(v=V_GRAZING_SLIDING - 1e-3)
    orbit = R.sliding_orbit(below)
    z0 = R.orbit_state(0.0, orbit, below)
    z1, events = R.brute_force(z0, 0.0, T, below)
    assert [kind for _, kind in events] == ["sliding_start", "sliding_end"]
    assert orbit[0] < T_GRAZING_SLIDING < orbit[2]  # the short sliding motion lies around the touch
    np.testing.assert_allclose(z1, z0, rtol=0, atol=1e-9)


@pytest.mark.parametrize("kappa", [KAPPA_RANGE[0], DEFAULTS["kappa"], KAPPA_RANGE[1]])
def test_reference_switching_sliding_against_brute_force(kappa):
    """At the reference switching-sliding the plus field is tangent (invisibly) where the orbit arrives; the
    orbit is periodic for DOP853; a little above v it slides at once, a little below it first crosses into
    s > 0 and comes back to slide (transients of 12 periods from the bifurcating orbit, DOP853)."""
    (v, t_e, _, curvature), = R.switching_sliding_walk([kappa])
    q, orbit = R.switching_sliding_orbit(kappa, guess=(t_e, v))
    assert q["v"] == pytest.approx(v, abs=1e-12)
    t_e, x_e, _, _ = orbit
    assert R.G(t_e, x_e, q) == pytest.approx(q["F"], abs=1e-12)
    assert curvature < 0  # invisible from s > 0: the plus orbit returns to the line
    z0 = R.orbit_state(0.0, orbit, q)
    z1, _ = R.brute_force(z0, 0.0, T, q)
    np.testing.assert_allclose(z1, z0, rtol=0, atol=1e-9)
    for dv, expected in ((1e-3, ["sliding_start", "sliding_end"]), (-1e-3, ["crossing", "sliding_start", "sliding_end"])):
        p = R.params(kappa=kappa, v=v + dv)
        z = z0
        for _ in range(12):
            z, events = R.brute_force(z, 0.0, T, p)
        assert [kind for _, kind in events] == expected


def test_reference_curves_keep_their_event_sequences():
    """Over the kappa range of the curves: the switching-sliding orbit arrives, slides and leaves into s < 0
    inside (0, T), its tangency stays invisible, and the grazing-sliding touch stays inside (0, T)."""
    kappas = np.linspace(*KAPPA_RANGE, 9)
    for kappa, (v, t_e, x_e, curvature) in zip(kappas, R.switching_sliding_walk(kappas)):
        q = R.params(kappa=kappa, v=v)
        t_x, _, _, _ = R.slide_and_return(t_e, x_e, q)
        assert 0.5 < t_e < t_x < T - 0.3
        assert curvature < -0.5
        _, t_touch = R.grazing_sliding(kappa)
        assert 0.5 < t_touch < T - 0.3
        assert v < R.grazing_sliding(kappa)[0] - 0.2  # the two curves stay apart


# -- saltation against the references -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def flow():
    return Flow(tilted_relay())


def test_periodic_orbit_with_sliding(flow):
    """find_periodic_orbit from the slip orbit's state (a guess off the sliding orbit) converges to the
    reference.  Shooting stops at |r| <= 1e-10 (1 + |u|) with integration at rtol 1e-10, and the
    sliding motion contracts (one multiplier is 0), so the state is good to about 1e-10: 1e-9 is asked."""
    p = R.params(v=V_SLIDING)
    orbit = R.sliding_orbit(p)
    reference = R.orbit_state(0.0, orbit, p)
    found = find_periodic_orbit(flow, R.response(0.0, -1, p), parameters={"v": V_SLIDING})
    np.testing.assert_allclose(found.state0, reference, rtol=0, atol=1e-9)
    assert [e.kind.name for e in found.events] == ["SLIDING_START", "SLIDING_END"]
    assert found.events[0].t == pytest.approx(orbit[0], abs=1e-9)
    assert found.events[1].t == pytest.approx(orbit[2], abs=1e-9)
    assert found.events[1].mode_to == "minus"
    assert np.min(np.abs(found.multipliers)) < 1e-12  # sliding on a line in the plane forgets one direction


@pytest.fixture(scope="module")
def branch(flow):
    """The s < 0 slip orbits continued down in v from 3 to 2.2: through the grazing-sliding and the
    switching-sliding."""
    problem = ShootingProblem(flow, {"v": 3.0}, continuation_parameter="v")
    x0 = R.response(0.0, -1, R.params(v=3.0))
    br = continue_branch(problem, x0, 3.0, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.2, 3.0)),
                         directions=(-1,))
    return br, problem


def _the(br, kind):
    found = [sp for sp in br.special_points if sp.kind is kind]
    assert len(found) == 1, [(sp.kind.value, sp.parameter) for sp in br.special_points]
    return found[0]


def test_branch_grazing_sliding(branch):
    """Located by Newton on the grazing defining system (periodicity of the virtual orbit plus the tangency),
    exact Jacobians; the point states its accuracy (the next Newton correction plus the integration error
    carried to the parameter): the error must lie within it, and it within 1e-9."""
    br, _ = branch
    g = _the(br, SpecialPointKind.GRAZING_SLIDING)
    assert g.accuracy < 1e-9
    assert abs(g.parameter - V_GRAZING_SLIDING) <= g.accuracy + 1e-12
    assert (g.touch_surface, g.touch_mode) == ("s", "minus")
    assert g.touch_time == pytest.approx(T_GRAZING_SLIDING, abs=1e-7)
    np.testing.assert_allclose(g.state, R.response(0.0, -1, R.params(v=V_GRAZING_SLIDING)), rtol=0, atol=1e-9)


def test_branch_switching_sliding(branch):
    """Located by Newton on periodicity plus h_x f_plus = 0 at the arrival (the condition's derivatives by
    central differences); the stated accuracy must cover the error, and be within 1e-9."""
    br, _ = branch
    c = _the(br, SpecialPointKind.SWITCHING_SLIDING)
    assert c.accuracy < 1e-9
    assert abs(c.parameter - V_SWITCHING) <= c.accuracy + 1e-12
    assert (c.touch_surface, c.touch_mode) == ("s", "plus")
    assert c.touch_time == pytest.approx(T_SWITCHING, abs=1e-7)
    assert "field of 'plus' is tangent to it, invisible" in c.note
    q, orbit = R.switching_sliding_orbit()
    np.testing.assert_allclose(c.state, R.orbit_state(0.0, orbit, q), rtol=0, atol=1e-9)
    sides = {c.event_labels_minus, c.event_labels_plus}
    assert ("slide on s (minus|plus)", "leave s sliding -> minus") in sides


# -- the two-parameter curves in (v, kappa) -------------------------------------------------------------------------
# The curve corrector stops at |r| <= 1e-10 (1 + |z|) (integration at rtol 1e-10); the references are
# exact to about 1e-13.  Curve points are asked to 1e-9 in v, as for the other loci of the suite.
CURVE_SETTINGS = ContinuationSettings(ds=0.01, ds_max=0.02)


def _locus(branch, kind):
    br, problem = branch
    return follow_locus(problem, _the(br, kind), "kappa", KAPPA_RANGE, settings=CURVE_SETTINGS)


@pytest.fixture(scope="module")
def grazing_sliding_locus(branch):
    return _locus(branch, SpecialPointKind.GRAZING_SLIDING)


@pytest.fixture(scope="module")
def switching_sliding_locus(branch):
    return _locus(branch, SpecialPointKind.SWITCHING_SLIDING)


def _reaches_both_bounds(locus):
    assert "increasing kappa: reached a parameter bound" in locus.stop_detail, locus.stop_detail
    assert "decreasing kappa: reached a parameter bound" in locus.stop_detail, locus.stop_detail
    assert locus.values[:, 1].min() == pytest.approx(KAPPA_RANGE[0], abs=1e-12)
    assert locus.values[:, 1].max() == pytest.approx(KAPPA_RANGE[1], abs=1e-12)


def test_grazing_sliding_curve_points(grazing_sliding_locus):
    """Every point of the grazing-sliding curve against v = kappa F + A sqrt(kappa^2 + omega^2)."""
    v, kappa = grazing_sliding_locus.values.T
    assert len(v) > 10
    reference = np.array([R.grazing_sliding(k)[0] for k in kappa])
    np.testing.assert_allclose(v, reference, rtol=0, atol=1e-9)


def test_grazing_sliding_curve_reaches_its_bounds(grazing_sliding_locus):
    _reaches_both_bounds(grazing_sliding_locus)


def test_grazing_sliding_curve_has_no_codimension_two_point(grazing_sliding_locus):
    """Nothing happens to the grazing-sliding along kappa in [0.3, 0.7] (see the reference's check)."""
    assert grazing_sliding_locus.special_points == []


def test_switching_sliding_curve_points(switching_sliding_locus):
    """Every point of the switching-sliding curve against fsolve on the closed-form orbit at its kappa."""
    v, kappa = switching_sliding_locus.values.T
    assert len(v) > 10
    np.testing.assert_allclose(v, R.switching_sliding(kappa), rtol=0, atol=1e-9)


def test_switching_sliding_curve_reaches_its_bounds(switching_sliding_locus):
    _reaches_both_bounds(switching_sliding_locus)


def test_switching_sliding_curve_has_no_codimension_two_point(switching_sliding_locus):
    """Nothing happens to the switching-sliding along kappa in [0.3, 0.7] (see the reference's check)."""
    assert switching_sliding_locus.special_points == []


# -- the same curves by multiple shooting ---------------------------------------------------------------------------
@pytest.mark.parametrize("kind", [SpecialPointKind.SWITCHING_SLIDING, SpecialPointKind.GRAZING_SLIDING])
def test_curves_by_multiple_shooting_against_the_references(branch, kind):
    """The defining systems with the orbit cut into 3 segments (the arrival tangency and the grazing read
    from the segment that holds their instant): every point against the same closed forms, to the same
    1e-9, over the whole range."""
    from saltation.orbits.shooting import MultipleShootingProblem

    br, problem = branch
    locus = follow_locus(MultipleShootingProblem(problem, 3), _the(br, kind), "kappa", KAPPA_RANGE,
                         settings=CURVE_SETTINGS)
    _reaches_both_bounds(locus)
    v, kappa = locus.values.T
    assert len(v) > 10
    reference = (R.switching_sliding(kappa) if kind is SpecialPointKind.SWITCHING_SLIDING
                 else np.array([R.grazing_sliding(k)[0] for k in kappa]))
    np.testing.assert_allclose(v, reference, rtol=0, atol=1e-9)
    assert locus.special_points == []
