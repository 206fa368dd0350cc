"""A grazing followed by a plastic landing: one-sided multipliers 0, and the branch goes on through it.

A self-excited oscillator with a plastic stop at ``x = d`` (restitution 0, the contact declared to stick):

    x' = v,   v' = -x + (mu - x^2 - v^2) v,   at x = d (rising):  v -> 0.

Without the stop its limit cycle is the circle ``x^2 + v^2 = mu`` with period ``2 pi`` (on it the field is the
harmonic oscillator's), and the distance ``delta = x^2 + v^2 - mu`` obeys ``delta' = -2 v^2 delta``, so its
non-trivial multiplier is ``exp(-2 int v^2 dt) = exp(-2 pi mu)``.  The circle grazes the stop where
``sqrt(mu) = d``: ``mu* = d^2``.  Beyond it every orbit lands on the stop plastically at ``(d, 0)``, where the
contact force ``x = d`` pulls it away at once: the reset forgets the whole state, every orbit that lands
starts again from the same point, and the non-trivial multiplier is exactly 0 (the saltation matrix has
rank one).  The period there is the time from ``(d, 0)`` back to the stop, from scipy's ``solve_ivp`` with its
own event (no saltation).

So the grazing's one-sided multipliers are ``exp(-2 pi d^2)`` and 0: Feigin's persistence, nothing
infinitely unstable, no fold, the branch goes on through it; and backward-time shooting of an orbit that
lands is refused, naming the transition whose reset forgets.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from saltation import Crossing, Mode, PiecewiseSystem, Transition, continue_orbit, find_periodic_orbit
from saltation.errors import ModelError
from saltation.orbits.border_collision import BorderScenario

#: the monodromy's accuracy at the default tolerances, which bounds a multiplier's (a simple one's)
MULTIPLIER_ACCURACY = 1e-7


def oscillator(mu: float = 0.2, d: float = 0.5) -> PiecewiseSystem:
    """The oscillator with its plastic stop, written as a user writes it from the models guide."""
    return PiecewiseSystem(
        name="plastic_stop_oscillator", states=["x", "v"], parameters={"mu": mu, "d": d},
        modes=[Mode("free", ["v", "-x + (mu - x**2 - v**2)*v"])],
        surfaces={"stop": "d - x"},
        transitions=[Transition("free", "stop", Crossing.FALLING, "free", reset=["x", "0"], sticks=True)],
    )


def free_field(mu: float):
    return lambda t, z: [z[1], -z[0] + (mu - z[0] ** 2 - z[1] ** 2) * z[1]]


def landing_period(mu: float, d: float) -> float:
    """The time from ``(d, 0)`` back to the stop (``x = d`` rising), integrated by scipy without saltation."""
    hit = lambda t, z: z[0] - d  # noqa: E731
    hit.terminal, hit.direction = True, 1
    sol = solve_ivp(free_field(mu), (0.0, 50.0), [d, 0.0], events=hit, rtol=1e-12, atol=1e-13, method="DOP853")
    assert sol.status == 1, "the reference run from (d, 0) does not return to the stop"
    return float(sol.t_events[0][0])


def nontrivial(multipliers) -> complex:
    mu = np.asarray(multipliers)
    return complex(np.delete(mu, np.argmin(np.abs(mu - 1)))[0])


def test_the_branch_goes_on_through_the_grazing_with_one_sided_multipliers_zero():
    d = 0.5
    orbit = find_periodic_orbit(oscillator(mu=0.16, d=d), [0.0, 0.4], period=6.3)
    branch = continue_orbit(orbit, "mu", bounds=(0.16, 0.36), directions=(1,))
    assert branch.points[-1].parameter == pytest.approx(0.36, abs=1e-12), "the branch stops before its bound"
    (point,) = branch.special_points  # nothing else changes along the branch
    assert point.kind.value == "grazing"
    assert point.status.value == "located"
    lo, hi = point.bracket
    assert lo <= point.parameter <= hi
    assert abs(point.parameter - d**2) <= point.accuracy + 1e-9
    sided = point.one_sided
    assert nontrivial(sided.multipliers_minus) == pytest.approx(math.exp(-2 * math.pi * d**2), abs=MULTIPLIER_ACCURACY)
    assert abs(nontrivial(sided.multipliers_plus)) <= 1e-6  # extrapolated to the grazing
    assert sided.scenario is BorderScenario.PERSISTENCE
    for p in branch.points:  # every orbit against its closed form or scipy
        mu = p.parameter
        if mu < d**2 - 1e-6:
            assert nontrivial(p.multipliers) == pytest.approx(math.exp(-2 * math.pi * mu), abs=MULTIPLIER_ACCURACY)
            assert p.period == pytest.approx(2 * math.pi, rel=1e-9)
        elif mu > d**2 + 1e-6:
            assert abs(nontrivial(p.multipliers)) <= MULTIPLIER_ACCURACY
            assert p.period == pytest.approx(landing_period(mu, d), rel=1e-9)
        assert min(abs(np.asarray(p.multipliers) - 1)) <= MULTIPLIER_ACCURACY  # the trivial multiplier


@settings(max_examples=12, deadline=None)
@given(d=st.floats(0.3, 0.9), offset=st.floats(0.02, 0.3), lands=st.booleans())
def test_orbits_on_either_side_of_the_grazing_against_closed_forms_and_scipy(d, offset, lands):
    mu = d**2 + offset if lands else max(d**2 - offset, 0.04)
    # near the orbit, with no period (the transient from the guess gives one)
    guess = [0.0, 0.95 * math.sqrt(mu)] if not lands else [d * math.cos(2.0), -d * math.sin(2.0)]
    orbit = find_periodic_orbit(oscillator(mu=mu, d=d), guess)
    events = orbit.trajectory.events
    if lands:
        assert len(events) >= 1 and all(e.surface == "stop" for e in events)
        assert abs(nontrivial(orbit.multipliers)) <= MULTIPLIER_ACCURACY
        assert orbit.period == pytest.approx(landing_period(mu, d), rel=1e-9)
    else:
        assert not events
        assert nontrivial(orbit.multipliers) == pytest.approx(math.exp(-2 * math.pi * mu), abs=MULTIPLIER_ACCURACY)
        assert orbit.period == pytest.approx(2 * math.pi, rel=1e-9)
        assert float(np.hypot(*orbit.state0)) == pytest.approx(math.sqrt(mu), rel=1e-8)
    assert min(abs(np.asarray(orbit.multipliers) - 1)) <= MULTIPLIER_ACCURACY


def test_backward_shooting_of_an_orbit_that_lands_names_the_reset_that_forgets():
    system = oscillator(mu=0.3)
    orbit = find_periodic_orbit(system, [0.0, 0.5], period=6.3)
    with pytest.raises(ModelError, match=r"free -\[stop-\]-> free.*forgets.*shoot in forward time"):
        find_periodic_orbit(system, orbit.state0, period=orbit.period, backward=True)
