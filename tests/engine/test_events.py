"""Event location against closed forms, grazing, and impacts (transitions with a reset map).

Model: conftest.oscillator_system, ``x'' = -w^2 x - g`` with a wall at ``x = a``
(modes ``below`` / ``above``, no reset) and a floor at ``x = 0`` for mode ``ball``
(reset ``v -> -e v``).
"""

from __future__ import annotations

import numpy as np
import pytest

from saltation import EventKind, Tolerances

from conftest import TIGHT, central_difference_jacobian


def _params(flow, **values):
    return flow.parameters(values)


# ----------------------------------------------------------------- piecewise-linear and quadratic motion
@pytest.mark.parametrize("backward", [False, True], ids=["forward", "backward"])
def test_uniform_motion_crossing(oscillator_flow, backward):
    """x' = v0: the wall x = a is met at t = (a - x0) / v0."""
    p = _params(oscillator_flow, w=0.0, g=0.0, a=0.7)
    x0, v0 = 0.1, (-0.3 if backward else 0.3)
    traj = oscillator_flow.run([x0, v0], 0.0, -5.0 if backward else 5.0, p)
    assert len(traj.events) == 1
    (e,) = traj.events
    assert (e.mode_from, e.mode_to, e.surface) == ("below", "above", "wall")
    assert e.t == pytest.approx((0.7 - x0) / v0, abs=1e-14)
    np.testing.assert_allclose(traj.x1, [x0 + v0 * (-5.0 if backward else 5.0), v0], atol=1e-13)


def test_uniformly_accelerated_crossings(oscillator_flow):
    """x = 2 t - t^2 / 2 meets x = 3/2 at t = 1 (rising) and t = 3 (falling)."""
    p = _params(oscillator_flow, w=0.0, g=1.0, a=1.5)
    traj = oscillator_flow.run([0.0, 2.0], 0.0, 4.0, p)
    assert [(e.mode_from, e.mode_to) for e in traj.events] == [("below", "above"), ("above", "below")]
    np.testing.assert_allclose([e.t for e in traj.events], [1.0, 3.0], atol=1e-13)
    np.testing.assert_allclose(traj.x1, [0.0, -2.0], atol=1e-12)


# ----------------------------------------------------------------- harmonic oscillator, x = R sin(w t)
W, A = 1.3, 0.5
PERIODS = 3


def _harmonic_event_times(R=1.0, w=W, a=A, periods=PERIODS):
    up = np.arcsin(a / R) / w + 2 * np.pi / w * np.arange(periods)
    down = (np.pi - np.arcsin(a / R)) / w + 2 * np.pi / w * np.arange(periods)
    return np.sort(np.concatenate([up, down]))


@pytest.mark.parametrize(
    "tolerances, bound",
    [(TIGHT, 1e-12), (Tolerances(), 1e-12), (Tolerances(exact_affine=False), 1e-9)],
    ids=["rtol=1e-13", "default", "default-general-path"],
)
def test_harmonic_crossing_times(oscillator_flow, tolerances, bound):
    p = _params(oscillator_flow, w=W, a=A, g=0.0)
    t_end = PERIODS * 2 * np.pi / W
    traj = oscillator_flow.run([0.0, W], 0.0, t_end, p, tolerances=tolerances)
    expected = _harmonic_event_times()
    assert len(traj.events) == len(expected)
    np.testing.assert_allclose([e.t for e in traj.events], expected, rtol=0, atol=bound)
    assert [e.mode_to for e in traj.events] == ["above", "below"] * PERIODS


def test_event_states_on_or_past_the_surface(oscillator_flow):
    """The state logged at an event lies on the wall or just past it, never before it."""
    p = _params(oscillator_flow, w=W, a=A, g=0.0)
    traj = oscillator_flow.run([0.0, W], 0.0, PERIODS * 2 * np.pi / W, p)
    for e in traj.events:
        gap = e.x_minus[0] - A
        assert abs(gap) < 1e-12
        if e.mode_to == "above":
            assert gap >= 0.0, e
        else:
            assert gap <= 0.0, e
        np.testing.assert_array_equal(e.x_minus, e.x_plus)  # no reset
        np.testing.assert_allclose(e.saltation, np.eye(2), atol=1e-12)  # same field on both sides


# ----------------------------------------------------------------- grazing
GRAZE = 1e-6


@pytest.mark.parametrize("backward", [False, True], ids=["forward", "backward"])
def test_near_grazing_contact_is_detected(oscillator_flow, backward):
    """Amplitude 1 + 1e-6 against the wall x = 1: the contact lasts ~2 sqrt(2e-6) = 2.8e-3,
    a small fraction of one step (max_step is unbounded)."""
    p = _params(oscillator_flow, w=1.0, a=1.0, g=0.0)
    R = 1.0 + GRAZE
    T = 2 * np.pi
    if backward:
        traj = oscillator_flow.run([0.0, R], T, 0.0, p)
    else:
        traj = oscillator_flow.run([0.0, R], 0.0, T, p)
    expected = np.array([np.arcsin(1 / R), np.pi - np.arcsin(1 / R)])
    if backward:
        expected = expected[::-1]
    assert [e.surface for e in traj.events] == ["wall", "wall"]
    # the crossing is ill-conditioned: dt = dx / |x'|, |x'| = sqrt(R^2 - 1) ~ 1.4e-3
    np.testing.assert_allclose([e.t for e in traj.events], expected, rtol=0, atol=1e-8)
    contact = expected.max() - expected.min()
    assert contact == pytest.approx(2 * np.sqrt(2 * GRAZE), rel=1e-3)
    mean_step = T / traj.n_steps
    assert mean_step > 10 * contact  # the contact is well inside one step


def test_near_grazing_without_contact_has_no_event(oscillator_flow):
    p = _params(oscillator_flow, w=1.0, a=1.0, g=0.0)
    R = 1.0 - GRAZE
    traj = oscillator_flow.run([0.0, R], 0.0, 2 * np.pi, p)
    assert traj.events == []
    assert traj.mode1 == "below"
    # x_max comes from the dense output, accurate to the local tolerance (rtol 1e-10), not beyond
    assert traj.x_max[0] == pytest.approx(R, abs=1e-9)
    assert traj.x_max[0] < 1.0


# ----------------------------------------------------------------- impacts: a bouncing ball
def test_bouncing_ball_impacts(oscillator_flow):
    """x'' = -1 from x = 1 at rest, v -> -e v at x = 0 (e = 1/2).

    Impacts at t_1 = sqrt(2), t_2 = t_1 + 2 e sqrt(2); the saltation matrix of an impact
    is, by eq. (9) with the reset g(x, v) = (x, -e v):
    S = g_x + (f+ - g_x f-) h_x / (h_x f-) = [[-e, 0], [-(1 + e) g / v-, -e]].
    """
    e, g = 0.5, 1.0
    p = _params(oscillator_flow, w=0.0, g=g, e=e, a=5.0)
    t_end = 3.4
    traj = oscillator_flow.run([1.0, 0.0], 0.0, t_end, p, mode0="ball", variational=True)
    t1 = np.sqrt(2.0)
    t2 = t1 + 2 * e * np.sqrt(2.0)
    assert [ev.surface for ev in traj.events] == ["floor", "floor"]
    assert all(ev.kind == EventKind.TRANSITION for ev in traj.events)
    np.testing.assert_allclose([ev.t for ev in traj.events], [t1, t2], atol=1e-12)
    for ev, v_minus in zip(traj.events, [-np.sqrt(2.0), -e * np.sqrt(2.0)]):
        np.testing.assert_allclose(ev.x_minus, [0.0, v_minus], atol=1e-12)
        np.testing.assert_allclose(ev.x_plus, [0.0, -e * v_minus], atol=1e-12)
        np.testing.assert_allclose(ev.saltation, [[-e, 0.0], [-(1 + e) * g / v_minus, -e]], atol=1e-12)
    v_after = e * e * np.sqrt(2.0)
    np.testing.assert_allclose(traj.x1, [v_after * (t_end - t2) - (t_end - t2) ** 2 / 2, v_after - (t_end - t2)], atol=1e-12)
    fd = central_difference_jacobian(
        lambda x0: oscillator_flow.run(x0, 0.0, t_end, p, mode0="ball", tolerances=TIGHT).x1, [1.0, 0.0], 1e-6
    )
    np.testing.assert_allclose(traj.monodromy, fd, atol=1e-7)


# ----------------------------------------------------------------- rates of the event functions
def test_indicator_rates_against_central_differences():
    """The generated ``indicator_rate(s, t, x, f, p) = h_t + h_x f`` that event detection evaluates at
    every step: against central differences of ``h`` along ``(1, f)`` in ``(t, x)``, for a moving
    surface (``h_t != 0``) and a state-only one. The model functions run as plain Python here."""
    from saltation import Crossing, Mode, PiecewiseSystem, Transition
    from saltation.engine.codegen import model_source

    system = PiecewiseSystem(
        name="test_moving_wall",
        states=["x", "v"],
        parameters={"a": 0.3, "w": 2.0, "k": 1.5},
        modes=[Mode("left", ["v", "-k*x"], domain=["x - a*sin(w*t) < 0"]), Mode("right", ["v", "-x"])],
        surfaces={"moving": "x - a*sin(w*t)", "energy": "k*x**2 + v**2 - 1"},
        transitions=[
            Transition("left", "moving", Crossing.RISING, "right"),
            Transition("right", "moving", Crossing.FALLING, "left"),
        ],
        period="2*pi/w",  # a surface that moves with time belongs to a forced model
    )
    namespace = {"njit": lambda *args, **kwargs: (lambda f: f)}
    source = model_source(system).replace("from numba import njit\n", "")
    exec(compile(source, "<generated>", "exec"), namespace)  # noqa: S102
    indicator, rate = namespace["indicator"], namespace["indicator_rate"]
    p = system.parameter_vector()
    rng = np.random.default_rng(3)
    eps = 1e-6
    for _ in range(20):
        t, x, f = rng.normal(), rng.normal(size=2), rng.normal(size=2)
        for s in range(2):
            fd = (indicator(s, t + eps, x + eps * f, p) - indicator(s, t - eps, x - eps * f, p)) / (2 * eps)
            assert rate(s, t, x, f, p, np.zeros(2), np.zeros(3)) == pytest.approx(fd, rel=1e-8, abs=1e-8)


def test_transitions_that_differ_only_in_their_guard_have_their_own_identity():
    """A ball falling on a floor, with a harder restitution for fast impacts: two transitions with the same
    source, surface, direction and target (the same label) but other guards and resets. Detectors compare
    event sequences by identity, so an orbit that switches from one to the other is seen to change."""
    from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition
    from saltation.branches.corrector import canonical_events
    from saltation.orbits.shooting import event_ids, event_labels

    system = PiecewiseSystem(
        name="two_restitutions",
        states=["x", "v"],
        parameters={"g": 1.0, "v_c": 1.0},
        modes=[Mode("flight", ["v", "-g"], domain=["x > 0"])],
        surfaces={"floor": "x"},
        transitions=[
            Transition("flight", "floor", Crossing.FALLING, "flight", reset=["x", "-0.5*v"], guard=["-v - v_c > 0"]),
            Transition("flight", "floor", Crossing.FALLING, "flight", reset=["x", "-0.9*v"], guard=["-v - v_c < 0"]),
        ],
    )
    flow = Flow(system)
    p = flow.parameters()
    # dropped from heights 2 and 0.2: impact speeds 2 and 0.63 (v^2 = 2 g h), one bounce before t = 2.1 / 0.7
    fast = flow.run([2.0, 0.0], 0.0, 2.1, p)
    slow = flow.run([0.2, 0.0], 0.0, 0.7, p)
    assert event_labels(fast) == event_labels(slow) == ("flight -[floor-]-> flight",)
    assert [e.transition for e in fast.events] == [0] and [e.transition for e in slow.events] == [1]
    assert canonical_events(event_ids(fast)) != canonical_events(event_ids(slow))
    # the resets applied are the guarded ones: v+ = -0.5 v- and -0.9 v-
    assert fast.events[0].x_plus[1] == pytest.approx(-0.5 * fast.events[0].x_minus[1], rel=1e-14)
    assert slow.events[0].x_plus[1] == pytest.approx(-0.9 * slow.events[0].x_minus[1], rel=1e-14)
