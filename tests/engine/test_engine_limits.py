"""Limits of the engine: impacts that accumulate (Zeno) or leave the state on the surface pushed back
into it, and events at large times. None of them may pass through a surface or lose events silently:
each either agrees with a closed form or raises a named error."""

from __future__ import annotations

import math

import numpy as np
import pytest

from saltation import (
    ChatteringError,
    Crossing,
    Flow,
    IntegrationError,
    Mode,
    PiecewiseSystem,
    Transition,
)
from saltation.errors import SlidingError
from saltation.models import trilinear

BALL = {"w": 0.0, "g": 1.0}  # oscillator_system's mode 'ball': x'' = -1, floor x = 0, v -> -e v


def _ball_closed_form(e, t):
    """The ball dropped from x = 1 at rest (g = 1): first impact at t1 = sqrt(2) with speed v1 = sqrt(2);
    the k-th flight after it lasts 2 e^k v1, so the impacts accumulate at the Zeno time
    t_Z = t1 + sum_k 2 e^k v1 = t1 + 2 v1 e / (1 - e). Returns (x, v) at t < t_Z and the impact times."""
    t1 = v1 = math.sqrt(2.0)
    if t < t1:
        return np.array([1.0 - t * t / 2.0, -t]), []
    tk, vk, impacts = t1, v1, [t1]
    while True:
        vk *= e  # the speed leaving the floor
        flight = 2.0 * vk
        if tk + flight > t:
            s = t - tk
            return np.array([vk * s - s * s / 2.0, vk - s]), impacts
        tk += flight
        impacts.append(tk)


@pytest.mark.parametrize("e", [0.5, 1e-3, 1e-6])
def test_zeno_impacts_follow_the_closed_form_or_chatter_never_tunnel(oscillator_flow, e):
    t1 = math.sqrt(2.0)
    t_zeno = t1 + 2.0 * t1 * e / (1.0 - e)
    p = oscillator_flow.parameters(BALL | {"e": e})
    ends = [1.0, t1 + 0.5 * (t_zeno - t1), t_zeno - 1e-3 * (t_zeno - t1), t_zeno + 1e-9, 2.0, 3.0, 10.0, 100.0]
    for t_end in ends:
        try:
            traj = oscillator_flow.run([1.0, 0.0], 0.0, t_end, p, mode0="ball")
        except ChatteringError as err:
            assert "'floor'" in str(err)
            # only where the impacts have crowded together: within 1e-6 of the Zeno time
            t_err = float(str(err).split("at t = ")[1].split(",")[0])
            assert abs(t_err - t_zeno) <= 1e-6, (e, t_end, t_err, t_zeno)
            assert t_end > t_zeno - 1e-6
            continue
        # no error: the run ends before the Zeno time, on the closed form, above the floor
        assert t_end < t_zeno, (e, t_end, traj.x1)
        x_ref, impacts = _ball_closed_form(e, t_end)
        assert traj.x1[0] >= -1e-15
        np.testing.assert_allclose(traj.x1, x_ref, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose([ev.t for ev in traj.events], impacts, rtol=1e-12)


@pytest.mark.parametrize("e", [0.0, -0.5])
def test_a_reset_that_leaves_the_state_pushed_into_the_surface_is_a_sliding_error(oscillator_flow, e):
    """e = 0: after the impact the ball rests on the floor and gravity pushes it in; e < 0 sends it into
    the floor. Both raise SlidingError naming the transition and the surface, at the impact t1 = sqrt(2);
    before the impact the run follows x = 1 - t^2/2."""
    p = oscillator_flow.parameters(BALL | {"e": e})
    traj = oscillator_flow.run([1.0, 0.0], 0.0, 1.0, p, mode0="ball")
    np.testing.assert_allclose(traj.x1, [0.5, -1.0], rtol=1e-13)
    for t_end in [1.5, 2.0, 3.0, 10.0]:
        with pytest.raises(SlidingError, match=r"reset of transition 2 \(ball -> ball on surface 'floor'\)") as info:
            oscillator_flow.run([1.0, 0.0], 0.0, t_end, p, mode0="ball")
        t_err = float(str(info.value).split("at t = ")[1].split(",")[0])
        assert abs(t_err - math.sqrt(2.0)) < 1e-10


def test_a_ball_at_rest_on_the_floor_does_not_fall_through(oscillator_flow):
    p = oscillator_flow.parameters(BALL | {"e": 0.5})
    for t_end in [1e-3, 1.0, 3.0]:
        with pytest.raises((ChatteringError, SlidingError), match="'floor'"):
            oscillator_flow.run([0.0, 0.0], 0.0, t_end, p, mode0="ball")


def _events_and_states(traj, t0):
    return ([ev.transition for ev in traj.events], np.array([ev.t - t0 for ev in traj.events]),
            np.array([ev.x_plus for ev in traj.events]))


@pytest.mark.parametrize("t0", [1e10, 1e12])
def test_events_at_large_times_are_those_at_t0_zero(t0):
    """The trilinear oscillator forced by f0 sin(omega t), from a multiple of the period near t0: the same
    events as from t = 0, at the same phase, to the resolution of the time axis (ulp(1e12) = 1.2e-4, and
    the multiple of the period itself is rounded to it). The chattering window was 1e-9 |t|: 1e3 at 1e12."""
    flow = Flow(trilinear())
    p = flow.parameters({"f0": 2.5})
    period = 2.0 * math.pi / 1.2
    t0 = round(t0 / period) * period
    # the same forcing phase near t = 0: omega t0 as the engine rounds it, reduced mod 2 pi exactly (fmod)
    t_ref = math.fmod(1.2 * t0, 2.0 * math.pi) / 1.2
    ref = flow.run([0.0, 0.0], t_ref, t_ref + 100.0, p)
    far = flow.run([0.0, 0.0], t0, t0 + 100.0, p)
    kinds, times, states = _events_and_states(ref, t_ref)
    kinds_far, times_far, states_far = _events_and_states(far, t0)
    assert len(kinds) > 50
    assert kinds_far == kinds
    # event times to 16 rounding units of t0 (the forcing's phase itself is rounded to one at every step)
    np.testing.assert_allclose(times_far, times, atol=16 * np.spacing(t0))
    # an event state lies on or just past the surface at a representable time: off by |x'| times those
    # rounding units (x' = v, |v'| <= (c + c_f)|v| + (k + k_f)|x| + k_f x_c + f0)
    x_max, v_max = np.abs(states).max(axis=0)
    rate = np.array([v_max, 0.55 * v_max + 5.0 * x_max + 4.0 + 2.5])
    np.testing.assert_allclose(states_far, states, rtol=0, atol=1e-3 + 16 * np.spacing(t0) * rate.max())
    np.testing.assert_allclose(far.x1, ref.x1, atol=1e-3)


def test_events_the_time_axis_cannot_resolve_raise():
    """At t0 = 1e15, ulp(t) = 0.125: the contact phases of the trilinear oscillator cannot be resolved;
    the run raises an IntegrationError that says so, rather than losing events."""
    flow = Flow(trilinear())
    p = flow.parameters({"f0": 2.5})
    with pytest.raises(IntegrationError, match="time axis cannot resolve"):
        flow.run([0.0, 0.0], 1e15, 1e15 + 100.0, p)


def _log_system(n_walls):
    """x' = u, u' = -u^2 from (0, 1): u = 1 / (1 + t), x = ln(1 + t), crossing walls at x = 0.03 k
    (k = 1 .. n_walls) at t_k = exp(0.03 k) - 1: events 0.03 apart, then none over a very long span."""
    field = ["u", "-u**2"]
    walls = {f"w{k}": f"x - {0.03 * k!r}" for k in range(1, n_walls + 1)}
    return PiecewiseSystem(
        name="engine_limits_log",
        states=["x", "u"],
        parameters={},
        modes=[Mode("A", field), Mode("B", field)],
        surfaces=walls,
        transitions=[Transition(a, w, Crossing.RISING, b) for w in walls for a, b in (("A", "B"), ("B", "A"))],
    )


def test_a_long_span_does_not_make_separate_events_chattering():
    """Over a span of 1e10 the window was 1e-8 * span = 100: the 25 events, 0.03 and more apart
    (t_25 = 1.12), were chattering."""
    flow = Flow(_log_system(25))
    p = flow.parameters()
    t_end = 1e10
    traj = flow.run([0.0, 1.0], 0.0, t_end, p, mode0="A")
    t_ref = [math.expm1(0.03 * k) for k in range(1, 26)]
    np.testing.assert_allclose([ev.t for ev in traj.events], t_ref, rtol=1e-8)
    np.testing.assert_allclose(traj.x1, [math.log1p(t_end), 1.0 / (1.0 + t_end)], rtol=1e-6)


def test_a_wall_oscillator_over_many_periods_is_no_chattering(oscillator_flow):
    """x'' = -x with a wall at x = 1/2 crossed both ways, from (0, 1): x = sin t, two crossings per period
    at t = pi/6 and 5 pi/6 (mod 2 pi), over 1e4 periods."""
    p = oscillator_flow.parameters({"w": 1.0, "g": 0.0, "a": 0.5})
    n_per = 10_000
    traj = oscillator_flow.run([0.0, 1.0], 0.0, 2.0 * math.pi * n_per, p)
    times = np.array([ev.t for ev in traj.events])
    assert len(times) == 2 * n_per
    k = np.arange(n_per)
    np.testing.assert_allclose(times[0::2], math.pi / 6 + 2 * math.pi * k, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(times[1::2], 5 * math.pi / 6 + 2 * math.pi * k, rtol=1e-10, atol=1e-9)


@pytest.mark.parametrize("t0", [1e6, 1e12, 1e15])
@pytest.mark.parametrize("e", [0.5, 1e-3, 0.0])
def test_impacts_at_large_times_never_tunnel(oscillator_flow, t0, e):
    """The dropped ball from t0: where the time axis resolves the motion, the closed form (shifted by
    t0, to the rounding of t0's grid); elsewhere a named error, never a ball below the floor."""
    p = oscillator_flow.parameters(BALL | {"e": e})
    t1 = math.sqrt(2.0)
    t_zeno = t1 + 2.0 * t1 * e / (1.0 - e)
    for span in [1.0, t1 + 0.3 * (t_zeno - t1) if e > 0 else 1.2, 10.0]:
        try:
            traj = oscillator_flow.run([1.0, 0.0], t0, t0 + span, p, mode0="ball")
        except IntegrationError as err:
            assert "'floor'" in str(err) or "time axis cannot resolve" in str(err)
            continue
        assert span < t_zeno
        x_ref, impacts = _ball_closed_form(e, span)
        tol = 64 * np.spacing(t0) * 2.0  # |x'|, |v'| <= 2 here
        np.testing.assert_allclose(traj.x1, x_ref, rtol=1e-9, atol=tol)
        assert traj.x1[0] >= -tol
        assert len(traj.events) == len(impacts)


@pytest.mark.parametrize("t0", [1e15, 1e17])
def test_a_wall_the_time_axis_cannot_resolve_raises(oscillator_flow, t0):
    """x'' = -x with its wall at x = 1/2, from t0 where ulp(t0) = 0.125 or 16: the crossing times cannot be
    represented to a useful precision; the run raises instead of drifting off x = sin(t - t0)."""
    p = oscillator_flow.parameters({"w": 1.0, "g": 0.0, "a": 0.5})
    with pytest.raises(IntegrationError, match="time axis cannot resolve"):
        oscillator_flow.run([0.0, 1.0], t0, t0 + 20.0, p)
