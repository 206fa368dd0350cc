"""Starting guesses from a transient (:mod:`saltation.orbits.start`) and :func:`find_periodic_orbit` without a
guess, against closed forms: the harmonic response of a forced linear oscillator, and the limit cycle of
the Hopf normal form (radius ``sqrt(mu)``, period ``2 pi``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from saltation import (
    Crossing,
    Flow,
    Mode,
    PiecewiseSystem,
    StartGuessError,
    Transition,
    find_periodic_orbit,
)
from saltation.orbits.start import estimate_period, starting_guess, transient

C, K, W, F0 = 0.2, 1.0, 1.3, 0.5


def forced_oscillator() -> PiecewiseSystem:
    """``x'' + c x' + k x = f0 cos(w t)`` with a wall far beyond its response (it never reaches it)."""
    return PiecewiseSystem(
        name="test_start_forced_oscillator", states=["x", "v"],
        parameters={"c": C, "k": K, "omega": W, "f0": F0, "xc": 50.0},
        modes=[Mode("free", ["v", "-c*v - k*x + f0*cos(omega*t)"])],
        surfaces={"wall": "x - xc"},
        transitions=[Transition("free", "wall", Crossing.RISING, "free", reset=["x", "-v"])],
        period="2*pi/omega",
    )


def harmonic_response() -> np.ndarray:
    """``(x, x')`` at ``t = 0`` of the response ``a cos(w t) + b sin(w t)``."""
    den = (K - W**2) ** 2 + (C * W) ** 2
    a, b = F0 * (K - W**2) / den, F0 * C * W / den
    return np.array([a, W * b])


def hopf(mu: float = 0.25) -> PiecewiseSystem:
    """The Hopf normal form; its cycle of radius ``sqrt(mu)`` stays clear of the wall at ``x = 2``."""
    return PiecewiseSystem(
        name="test_start_hopf", states=["x", "y"], parameters={"mu": mu, "c": 2.0, "r": 0.5},
        modes=[Mode("free", ["mu*x - y - x*(x**2 + y**2)", "x + mu*y - y*(x**2 + y**2)"])],
        surfaces={"wall": "x - c"},
        transitions=[Transition("free", "wall", Crossing.RISING, "free", reset=["x", "-r*y"])],
    )


@pytest.fixture(scope="module")
def forced_flow() -> Flow:
    return Flow(forced_oscillator())


@pytest.fixture(scope="module")
def hopf_flow() -> Flow:
    return Flow(hopf())


def test_forced_orbit_without_a_guess_is_the_harmonic_response(forced_flow):
    orbit = find_periodic_orbit(forced_flow)
    # Newton stops at |r| <= 1e-10 (1 + |x|); the orbit is strongly attracting, so the state is as good
    assert np.allclose(orbit.state0, harmonic_response(), rtol=0, atol=1e-9)
    assert orbit.period == pytest.approx(2 * math.pi / W, rel=1e-15)


def test_a_model_is_accepted_in_place_of_a_flow():
    orbit = find_periodic_orbit(forced_oscillator(), parameters={"f0": 2 * F0})
    assert np.allclose(orbit.state0, 2 * harmonic_response(), rtol=0, atol=1e-9)


def test_autonomous_period_is_read_from_the_transient(hopf_flow):
    p = hopf_flow.parameters({})
    run = transient(hopf_flow, p, [0.1, 0.0], length=60.0)
    # the section's crossings are interpolated linearly on the dense samples: a few digits, enough to start
    assert estimate_period(run) == pytest.approx(2 * math.pi, rel=1e-3)
    orbit = find_periodic_orbit(hopf_flow, [0.45, 0.1])  # the state is kept as the guess; the period estimated
    assert orbit.period == pytest.approx(2 * math.pi, rel=1e-9)
    assert np.hypot(*orbit.state0) == pytest.approx(0.5, rel=1e-9)


def test_a_given_state_is_kept_and_only_the_period_estimated(hopf_flow):
    p = hopf_flow.parameters({})
    x0, period = starting_guess(hopf_flow, p, [0.3, 0.4], None)
    assert x0.tolist() == [0.3, 0.4]
    assert period == pytest.approx(2 * math.pi, rel=1e-3)
    x0, period = starting_guess(hopf_flow, p, [0.3, 0.4], 6.0)
    assert (x0.tolist(), period) == ([0.3, 0.4], 6.0)


def test_a_transient_that_settles_to_an_equilibrium_gives_no_period(hopf_flow):
    with pytest.raises(StartGuessError, match="no repeating events or oscillation"):
        find_periodic_orbit(hopf_flow, np.zeros(2))  # from zeros: the equilibrium itself


def test_an_autonomous_model_without_a_guess_starts_where_it_moves(hopf_flow):
    """The origin is the Hopf normal form's equilibrium: the transient that finds the cycle starts from a
    unit state instead (the cycle: radius sqrt(mu), period 2 pi)."""
    orbit = find_periodic_orbit(hopf_flow)
    assert orbit.period == pytest.approx(2 * math.pi, rel=1e-9)
    assert np.hypot(*orbit.state0) == pytest.approx(math.sqrt(0.25), rel=1e-9)
    with pytest.raises(StartGuessError, match=r"from \[0.0, 0.0\].*from \[1.0, 0.0\]"):
        find_periodic_orbit(hopf_flow, parameters={"mu": -0.25})  # every start settles to the stable origin


def test_a_diverging_transient_is_reported(forced_flow):
    # backward in time the damped oscillator's free response grows like exp(c t / 2) = exp(31) over 50 periods
    with pytest.raises(StartGuessError, match="backward transient .* diverges"):
        find_periodic_orbit(forced_flow, backward=True)


def test_node_guesses_of_an_autonomous_model_need_a_period(hopf_flow):
    with pytest.raises(Exception, match="needs a period guess"):
        find_periodic_orbit(hopf_flow, np.zeros((4, 2)), segments=4)
