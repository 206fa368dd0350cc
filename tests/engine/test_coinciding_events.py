"""Events due at one instant: a clock and a threshold that fire together, against an exact reference.

A latched ramp, the skeleton of a current-mode converter: ``x`` rises at ``a`` while the latch ``q`` is set
(mode ``on``) and falls at ``b`` while it is reset (``off``); a clock of period 1 (the phase ``tau``, reset at
``tau = 1``) sets the latch unless ``x >= c``, and the comparator ``x = c`` resets it.  ``q`` is a logic state
(no mode moves it), so the comparator's reset is a switch, not an impact: after it the field of ``off`` is
free to turn ``x`` back across ``c`` (no sliding motion is called for, ``off`` does not watch ``x = c``).

The start is chosen so that the ramp reaches ``c`` exactly at the ``k``-th clock instant.  Whatever order the
two events are taken in, the latch ends reset there (the clock does not set it at ``x = c``), and the motion
goes on from ``(c, 0, off)``.  The reference is the same automaton in exact rational arithmetic (every flow is
a ramp), so its events and states are exact; the integration's (the exact flow of these affine modes) agree
to rounding.
"""

from __future__ import annotations

import functools
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition

RISING = Crossing.RISING


@functools.cache
def latched_ramp() -> PiecewiseSystem:
    return PiecewiseSystem(
        "test_latched_ramp", states=["x", "tau", "q"], parameters={"a": 1.0, "b": 1.0, "c": 1.0},
        modes=[Mode("on", ["a", "1", "0"], domain=["q - 0.5 > 0"]), Mode("off", ["-b", "1", "0"])],
        surfaces={"peak": "x - c", "clock": "tau - 1"},
        transitions=[
            Transition("on", "peak", RISING, "off", reset=["x", "tau", "0"]),
            Transition("off", "clock", RISING, "on", reset=["x", "0", "1"], guard=["x - c < 0"]),
            Transition("off", "clock", RISING, "off", reset=["x", "0", "0"], guard=["x - c >= 0"]),
            Transition("on", "clock", RISING, "on", reset=["x", "0", "1"]),
        ],
    )


@pytest.fixture(scope="module")
def flow() -> Flow:
    return Flow(latched_ramp())


def reference(x: Fraction, tau: Fraction, on: bool, a: Fraction, b: Fraction, c: Fraction, t_end: Fraction):
    """The automaton in exact arithmetic from ``t = 0``: ``(x, tau, on)`` at ``t_end``, and the instants at which
    the latch is reset (comparator) and the clock ticks.  At an instant where the ramp reaches ``c`` as the
    clock ticks, the latch ends reset."""
    t, resets, ticks = Fraction(0), [], []
    while True:
        to_clock = 1 - tau
        to_peak = (c - x) / a if on and x < c else None
        if to_peak is not None and to_peak <= to_clock and t + to_peak <= t_end:
            t, x, tau, on = t + to_peak, c, tau + to_peak, False
            resets.append(t)
            continue
        if t + to_clock > t_end:
            dt = t_end - t
            return (x + (a if on else -b) * dt, tau + dt, on), resets, ticks
        t, x, tau = t + to_clock, x + (a if on else -b) * to_clock, Fraction(0)
        ticks.append(t)
        on = on or x < c  # a latch set stays set; a reset one is set unless x >= c


rationals = st.builds(Fraction, st.integers(1, 8), st.integers(1, 8))


@settings(max_examples=60, deadline=None)
@given(a=rationals, b=rationals, tau0=st.builds(Fraction, st.integers(0, 7), st.just(8)), k=st.integers(1, 3),
       x0=st.builds(Fraction, st.integers(-4, 4), st.just(4)))
def test_a_clock_and_a_threshold_at_one_instant(flow, a, b, tau0, k, x0):
    t_k = k - tau0  # the k-th clock instant
    c = x0 + a * t_k  # the ramp, set all along, reaches c exactly then
    t_end = t_k + Fraction(7, 2)  # (not a clock instant)
    (x, tau, on), resets, ticks = reference(x0, tau0, True, a, b, c, t_end)
    assert resets[0] == t_k and t_k in ticks  # the instant the test is about
    p = flow.parameters({"a": float(a), "b": float(b), "c": float(c)})
    traj = flow.run([float(x0), float(tau0), 1.0], 0.0, float(t_end), p, mode0="on")
    scale = float(max(abs(c), 1, a * 4, b * 4))
    # ramps integrated exactly (affine modes): a few rounding units of the scale per event, far below 1e-12
    np.testing.assert_allclose(traj.x1, [float(x), float(tau), 1.0 if on else 0.0], rtol=0, atol=1e-12 * scale)
    assert traj.mode1 == ("on" if on else "off")
    # the instants of each surface's events (at the coinciding instant the latch may be set and reset again in
    # zero time: the clock's guard is read a hair along the reset latch's motion)
    for surface, expected in (("peak", resets), ("clock", ticks)):
        instants = np.unique(np.round([e.t for e in traj.events if e.surface == surface], 9))
        np.testing.assert_allclose(instants, [float(r) for r in expected], rtol=0, atol=1e-9)  # (the grouping's 1e-9)
        assert all(min(abs(e.t - float(r)) for r in expected) <= 1e-12 * float(t_end)
                   for e in traj.events if e.surface == surface)


def test_the_comparator_at_a_clock_instant_is_not_lost(flow):
    """The case that lost it: a ramp of 1 per period from 0 reaches c = 3 at the third clock instant, and the
    latch was left set for ever (x grew by 1 a period).  Exact: x(4) = 3 - b (falling), then set again."""
    p = flow.parameters({"a": 1.0, "b": 0.5, "c": 3.0})
    traj = flow.run([0.0, 0.0, 1.0], 0.0, 4.0, p, mode0="on")
    at_three = [(e.surface, e.mode_to) for e in traj.events if abs(e.t - 3.0) <= 1e-12]
    assert ("peak", "off") in at_three and at_three[-1][1] == "off"  # the latch ends reset at that instant
    assert traj.x1[0] == pytest.approx(2.5, abs=1e-12) and traj.x1[0] < 3.0


@functools.cache
def clocked_ramp() -> PiecewiseSystem:
    """The same automaton with the clock a time-triggered transition of a forced model: the surface
    ``sin(2 pi t)`` rises through zero at every integer ``t``, and the latch is the mode (no logic state)."""
    return PiecewiseSystem(
        "test_clocked_ramp", states=["x"], parameters={"a": 1.0, "b": 1.0, "c": 1.0},
        modes=[Mode("on", ["a"], domain=["x - c < 0"]), Mode("off", ["-b"])],
        surfaces={"peak": "x - c", "clock": "sin(2*pi*t)"},
        transitions=[
            Transition("on", "peak", RISING, "off"),
            Transition("off", "clock", RISING, "on", guard=["x - c < 0"]),
        ],
        period="1",
    )


@pytest.fixture(scope="module")
def clocked_flow() -> Flow:
    return Flow(clocked_ramp())


@settings(max_examples=60, deadline=None)
@given(a=rationals, b=rationals, tau0=st.builds(Fraction, st.integers(1, 7), st.just(8)), k=st.integers(1, 3),
       x0=st.builds(Fraction, st.integers(-4, 4), st.just(4)))
def test_a_time_clock_and_a_threshold_at_one_instant(clocked_flow, a, b, tau0, k, x0):
    """As above with the clock ``sin(2 pi t)``: the run starts at ``t = tau0`` (the clock's phase), and after the
    comparator and the clock at one instant the clock, still at zero there, is not crossed again (it chattered)."""
    t_k = k - tau0
    c = x0 + a * t_k
    t_end = t_k + Fraction(7, 2)
    (x, _, on), resets, ticks = reference(x0, tau0, True, a, b, c, t_end)
    p = clocked_flow.parameters({"a": float(a), "b": float(b), "c": float(c)})
    traj = clocked_flow.run([float(x0)], float(tau0), float(tau0 + t_end), p, mode0="on")
    scale = float(max(abs(c), 1, a * 4, b * 4))
    # ramps integrated exactly; the clock's instants are roots of sin(2 pi t), found to the resolution of t
    np.testing.assert_allclose(traj.x1, [float(x)], rtol=0, atol=1e-12 * scale)
    assert traj.mode1 == ("on" if on else "off")
    for surface, expected in (("peak", resets), ("clock", [r for r in ticks if r not in resets or True])):
        fired = [e.t - float(tau0) for e in traj.events if e.surface == surface]
        assert len(np.unique(np.round(fired, 9))) == len(fired) or surface == "peak", f"{surface} crossed twice at one instant"
        if surface == "peak":
            np.testing.assert_allclose(np.unique(np.round(fired, 9)), [float(r) for r in expected], rtol=0, atol=1e-9)
