"""Impacts (reset maps) and sliding in a forced system, against closed forms and finite differences."""

from __future__ import annotations

import numpy as np
import pytest

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Tolerances, Transition
from saltation.errors import ChatteringError


@pytest.fixture(scope="module")
def ball():
    system = PiecewiseSystem(
        name="test_bouncing_ball",
        states=["x", "v"],
        parameters={"g": 9.81, "e": 0.8},
        modes=[Mode("flight", ["v", "-g"])],
        surfaces={"floor": "x"},
        transitions=[Transition("flight", "floor", Crossing.FALLING, "flight", reset=["x", "-e*v"])],
    )
    return Flow(system, Tolerances(rtol=1e-12, atol=1e-14))


def flow_map(flow, x0, t0, t1, p):
    return flow.run(x0, t0, t1, p).x1


def central_differences(fun, x0, h=1e-6):
    cols = []
    for i in range(len(x0)):
        e = np.zeros(len(x0))
        e[i] = h
        cols.append((fun(x0 + e) - fun(x0 - e)) / (2 * h))
    return np.array(cols).T


def test_impact_event_times_and_saltation(ball):
    p = ball.parameters()
    g, e = p
    h0 = 1.0
    traj = ball.run([h0, 0.0], 0.0, 2.5, p, variational=True)
    t1 = np.sqrt(2 * h0 / g)
    v_minus = -g * t1
    t2 = t1 + 2 * e * g * t1 / g
    times = [ev.t for ev in traj.events]
    assert times[0] == pytest.approx(t1, abs=1e-12)
    assert times[1] == pytest.approx(t2, abs=1e-11)
    ev = traj.events[0]
    assert ev.x_plus[1] == pytest.approx(-e * v_minus, rel=1e-12)
    # S = g_x + (f+ - g_x f-) h_x / (h_x f-) with h = x, g = (x, -e v)
    expected = np.array([[-e, 0.0], [-g * (1 + e) / v_minus, -e]])
    assert np.allclose(ev.saltation, expected, atol=1e-10)
    # the fundamental solution matrix through two impacts against central differences
    fd = central_differences(lambda x: flow_map(ball, x, 0.0, 2.5, p), np.array([h0, 0.0]))
    assert np.allclose(traj.monodromy, fd, atol=1e-6)


def test_zeno_bouncing_is_reported_as_chattering(ball):
    p = ball.parameters()
    with pytest.raises(ChatteringError, match="floor"):
        ball.run([1.0, 0.0], 0.0, 10.0, p)


@pytest.fixture(scope="module")
def forced_friction():
    # a forced oscillator with Coulomb friction: it sticks (slides on v = 0) and breaks away
    system = PiecewiseSystem(
        name="test_forced_coulomb",
        states=["x", "v"],
        parameters={"m": 1.0, "k": 1.0, "F": 0.5, "f0": 1.0, "omega": 0.5},
        modes=[
            Mode("slip_pos", ["v", "(-k*x - F + f0*cos(omega*t))/m"], domain=["v > 0"]),
            Mode("slip_neg", ["v", "(-k*x + F + f0*cos(omega*t))/m"]),
        ],
        surfaces={"v": "v"},
        transitions=[
            Transition("slip_pos", "v", Crossing.FALLING, "slip_neg"),
            Transition("slip_neg", "v", Crossing.RISING, "slip_pos"),
        ],
        period="2*pi/omega",
    )
    return Flow(system, Tolerances(rtol=1e-12, atol=1e-14))


def test_forced_sliding_exit_and_monodromy(forced_friction):
    flow = forced_friction
    p = flow.parameters()
    T = 2 * np.pi / p[4]
    x0 = np.array([1.291, 0.1407])
    traj = flow.run(x0, 0.0, T, p, variational=True)
    kinds = [ev.kind.name for ev in traj.events]
    assert "SLIDING_START" in kinds and "SLIDING_END" in kinds
    for ev in traj.events:
        if ev.kind.name == "SLIDING_END":
            # the sliding field equals the exit field where the motion leaves: S = I (eq. 9 with f+ = f-)
            assert np.allclose(ev.saltation, np.eye(2), atol=1e-6)
            # sticking ends where the spring and forcing overcome friction: |-k x + f0 cos(w t)| = F
            k, F, f0, w = p[1], p[2], p[3], p[4]
            assert abs(-k * ev.x_minus[0] + f0 * np.cos(w * ev.t)) == pytest.approx(F, abs=1e-9)
        if ev.kind.name == "SLIDING_START":
            assert abs(np.linalg.det(ev.saltation)) < 1e-9  # entering sliding loses a direction
    fd = central_differences(lambda x: flow_map(flow, x, 0.0, T, p), x0, h=1e-7)
    assert np.allclose(traj.monodromy, fd, atol=1e-5)
