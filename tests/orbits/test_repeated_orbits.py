"""An autonomous orbit is returned with its minimal period, however Newton reaches it.

Newton on ``(x0, T)`` solves ``phi(T; x0) = x0``, which a closed curve covered ``k`` times satisfies too.  From a
period guess ``k`` times the true one, or from a guess where a reset that forgets flattens the residual, it
can converge there; the orbit must then be the curve once.  References in closed form: the oscillator
``x' = v, v' = -x + (mu - x^2 - v^2) v`` has the limit cycle ``x^2 + v^2 = mu``, period ``2 pi``, non-trivial
multiplier ``exp(-2 pi mu)`` (the distance to the circle obeys ``delta' = -2 v^2 delta``).  With a plastic
stop at ``x = d < sqrt(mu)`` (restitution 0), every orbit that lands restarts from ``(d, 0)``: its period is
the time from there back to the stop (scipy, without saltation) and its non-trivial multiplier 0.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from saltation import Crossing, Mode, PiecewiseSystem, Transition, find_periodic_orbit

#: the monodromy's accuracy at the default tolerances, which bounds a simple multiplier's
MULTIPLIER_ACCURACY = 1e-7


def oscillator(mu: float, d: float | None = None) -> PiecewiseSystem:
    field = Mode("free", ["v", "-x + (mu - x**2 - v**2)*v"])
    if d is None:
        return PiecewiseSystem(name="circle_oscillator", states=["x", "v"], parameters={"mu": mu}, modes=[field],
                               surfaces={}, transitions=[])
    return PiecewiseSystem(
        name="plastic_stop_oscillator", states=["x", "v"], parameters={"mu": mu, "d": d}, modes=[field],
        surfaces={"stop": "d - x"},
        transitions=[Transition("free", "stop", Crossing.FALLING, "free", reset=["x", "0"], sticks=True)],
    )


def landing_orbit(mu: float, d: float):
    """The orbit that lands, from ``(d, 0)`` back to the stop, integrated by scipy without saltation."""
    hit = lambda t, z: z[0] - d  # noqa: E731
    hit.terminal, hit.direction = True, 1
    field = lambda t, z: [z[1], -z[0] + (mu - z[0] ** 2 - z[1] ** 2) * z[1]]  # noqa: E731
    return solve_ivp(field, (0.0, 50.0), [d, 0.0], events=hit, rtol=1e-12, atol=1e-13, method="DOP853",
                     dense_output=True)


def nontrivial(multipliers) -> complex:
    mu = np.asarray(multipliers)
    return complex(np.delete(mu, np.argmin(np.abs(mu - 1)))[0])


@settings(max_examples=10, deadline=None)
@given(mu=st.floats(0.1, 1.0), k=st.sampled_from([2, 3, 4, 6]), phase=st.floats(0.0, 2 * math.pi))
def test_a_smooth_cycle_from_a_multiple_of_its_period_is_returned_once(mu, k, phase):
    r = math.sqrt(mu)
    orbit = find_periodic_orbit(oscillator(mu), [r * math.cos(phase), r * math.sin(phase)], period=k * 2 * math.pi)
    assert orbit.period == pytest.approx(2 * math.pi, rel=1e-9)
    assert nontrivial(orbit.multipliers) == pytest.approx(math.exp(-2 * math.pi * mu), abs=MULTIPLIER_ACCURACY)


@settings(max_examples=8, deadline=None)
@given(d=st.floats(0.3, 0.8), offset=st.floats(0.05, 0.3), k=st.sampled_from([1, 2, 3]))
def test_an_orbit_through_a_reset_that_forgets_is_returned_once(d, offset, k):
    mu = d**2 + offset
    reference = landing_orbit(mu, d)
    T = float(reference.t_events[0][0])
    # a state on the orbit, half a period after the landing, with k times its period
    orbit = find_periodic_orbit(oscillator(mu, d), reference.sol(T / 2), period=k * T)
    assert orbit.period == pytest.approx(T, rel=1e-9)
    assert len(orbit.trajectory.events) == 1
    assert abs(nontrivial(orbit.multipliers)) <= MULTIPLIER_ACCURACY
