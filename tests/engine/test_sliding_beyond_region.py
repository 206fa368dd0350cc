"""A sliding motion that meets another switching surface, where its region ends.

A Filippov sliding motion on a surface is defined only where the two modes it
combines are the modes on either side of it.  Where the sliding state crosses
another surface on which a transition out of either mode holds, that side of
the surface belongs to another mode: the sliding motion ends there, by that
transition.  Where it leaves a mode's domain and no transition says what
comes next, the run stops with ``SlidingError``.

``wall_system``: ``up`` (y > 0) ``[1.5, -1]`` and ``down`` (y < 0) ``[1.5, 1]``
slide on ``y = 0`` with ``x' = 1.5`` (``alpha = 1/2``); both end at the wall
``x = x_w`` (domains ``x < x_w``) and, when ``open > 0``, both pass into
``beyond``: ``[b_x, x - x_w]``, ``b_x = 1``.  From ``(x0, y0)``, ``y0 > 0``:

* sliding starts at ``t1 = y0``, ``x1 = x0 + 1.5 y0``;
* the wall is reached at ``t_w = (x_w - x0) / 1.5`` (independent of ``y0``), with
  ``S = I + (f_beyond - f_s) h_x^T / (h_x f_s) = [[2/3, 0], [0, 1]]``;
* then ``x = x_w + tau``, ``y = tau^2 / 2``, ``tau = t - t_w``: ``dx/dx0 = 2/3``,
  ``dy/dx0 = 2 tau / 3``, nothing depends on ``y0``; ``dx/dx_w = 1/3``,
  ``dy/dx_w = -2 tau / 3``.

``split_system``: at the wall ``up`` passes into ``left_up`` ``[1, a_u]`` and
``down`` into ``left_down`` ``[1, a_d]``; the signs of ``a_u``, ``a_d`` decide
(``x = x_w + tau`` in each case): both leave ``y = 0`` (``a_u = 1, a_d = -1``):
not unique, ``SlidingError``; ``left_up`` crosses it and ``left_down`` leaves
(``-1, -1``): ``left_down``, ``y = -tau``; ``left_up`` leaves (``1, 1``):
``left_up``, ``y = tau``; both push into it (``-1, 1``): a new sliding motion
``left_up|left_down``, ``alpha = 1/2``, ``y = 0``.  The same with every field negated,
integrated backward in time, gives the same states at ``-t``.

``half_wall_system``: only ``up`` ends at the wall, into ``fast`` ``[3, v_f]``
above ``y = 0`` (``down`` goes on below it).  With ``v_f = -2`` the new mode
crosses ``y = 0`` at once and ``down`` pushes back: a new sliding motion
``fast|down`` with ``alpha = 2/3``, ``f_s = (2, 0)``; with ``v_f = 2`` the motion
leaves in ``fast``: ``x = x_w + 3 tau``, ``y = 2 tau``.

The block-on-belt model (eq. 17) at ``v_dr = 0.2`` from ``[0, 1]``: the block
enters the stick band from above, sticks, and leaves it where the spring force
reaches ``F_stick`` with ``v`` still a little above ``v_dr``, so that the listed
exit ``stick -> slip_plus`` leads into a field that pushes back: a sliding
motion ``stick|slip_plus`` along ``k x + c v = F_stick`` in the upper half of
the band, with ``v' ~ -2``.  It reaches ``v = v_dr`` (surface ``v_rel``) within
about 2e-8, where the model lists ``slip_plus -> slip_minus``: beyond it the
side of ``stick_upper`` outside the stick region is ``slip_minus``, whose field
leaves the surface (``d(k x + c v)/dt = 0.1 > 0``).  So the motion is defined
and goes on in ``slip_minus``: the run ends on the stable stick-slip cycle
(before, the sliding motion went on past ``v_rel`` down to the pseudo-
equilibrium ``(2.068, -0.681)`` of a field the model does not define there).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from saltation import Crossing, EventKind, Flow, Mode, PiecewiseSystem, SlidingError, Tolerances, Transition
from saltation.orbits.shooting import find_periodic_orbit

from conftest import TIGHT, central_difference_jacobian

RISING, FALLING = Crossing.RISING, Crossing.FALLING

X_W = 1.5
X0 = np.array([-0.25, 0.5])
T_END = 3.0
T1 = X0[1]
T_W = (X_W - X0[0]) / 1.5  # 7/6, whatever y0
TAU = T_END - T_W


def wall_system() -> PiecewiseSystem:
    return PiecewiseSystem(
        name="test_sliding_wall",
        states=["x", "y"],
        parameters={"x_w": X_W, "open": 1.0, "b_x": 1.0},
        modes=[
            Mode("up", ["1.5", "-1"], domain=["y > 0", "x - x_w < 0"]),
            Mode("down", ["1.5", "1"], domain=["y < 0", "x - x_w < 0"]),
            Mode("beyond", ["b_x", "x - x_w"]),
        ],
        surfaces={"s": "y", "wall": "x - x_w"},
        transitions=[
            Transition("up", "s", FALLING, "down"),
            Transition("down", "s", RISING, "up"),
            Transition("up", "wall", RISING, "beyond", guard=["open > 0"]),
            Transition("down", "wall", RISING, "beyond", guard=["open > 0"]),
        ],
    )


def half_wall_system() -> PiecewiseSystem:
    return PiecewiseSystem(
        name="test_sliding_half_wall",
        states=["x", "y"],
        parameters={"x_w": X_W, "v_f": -2.0},
        modes=[
            Mode("up", ["1.5", "-1"], domain=["y > 0", "x - x_w < 0"]),
            Mode("down", ["1.5", "1"], domain=["y < 0"]),
            Mode("fast", ["3", "v_f"], domain=["y > 0"]),
        ],
        surfaces={"s": "y", "wall": "x - x_w"},
        transitions=[
            Transition("up", "s", FALLING, "down"),
            Transition("down", "s", RISING, "up", guard=["x - x_w < 0"]),
            Transition("down", "s", RISING, "fast", guard=["x - x_w >= 0"]),
            Transition("up", "wall", RISING, "fast"),
            Transition("fast", "wall", FALLING, "up"),
            Transition("fast", "s", FALLING, "down"),
        ],
    )


@pytest.fixture(scope="module")
def wall_flow() -> Flow:
    return Flow(wall_system(), TIGHT)


@pytest.fixture(scope="module")
def half_wall_flow() -> Flow:
    return Flow(half_wall_system(), TIGHT)


def _kinds(traj):
    return [(e.kind, e.surface, e.mode_from, e.mode_to) for e in traj.events]


# -- both sides end at the wall -------------------------------------------------------------------

@pytest.fixture(scope="module")
def through_wall(wall_flow):
    return wall_flow.run(X0, 0.0, T_END, wall_flow.parameters(), variational=True, sensitivity="x_w")


def test_sliding_ends_at_the_wall_by_its_transition(through_wall):
    traj = through_wall
    assert _kinds(traj) == [
        (EventKind.SLIDING_START, "s", "up", "down"),
        (EventKind.TRANSITION, "wall", "up", "beyond"),
    ]
    start, wall = traj.events
    assert wall.transition == 2  # up -> beyond: side a of the sliding motion decides when both lead into one mode
    assert start.t == pytest.approx(T1, abs=1e-14)
    assert wall.t == pytest.approx(T_W, abs=1e-14)
    np.testing.assert_allclose(wall.x_minus, [X_W, 0.0], atol=1e-14)
    np.testing.assert_allclose(wall.saltation, [[2.0 / 3.0, 0.0], [0.0, 1.0]], atol=1e-14)
    assert traj.mode1 == "beyond" and not traj.sliding_at_end
    np.testing.assert_allclose(traj.x1, [X_W + TAU, TAU**2 / 2.0], rtol=1e-13, atol=1e-13)  # not x = 4.25


def test_monodromy_through_the_wall_closed_form_and_differences(wall_flow, through_wall):
    closed = np.array([[2.0 / 3.0, 0.0], [2.0 * TAU / 3.0, 0.0]])
    np.testing.assert_allclose(through_wall.monodromy, closed, atol=1e-12)
    p = wall_flow.parameters()
    fd = central_difference_jacobian(lambda x0: wall_flow.run(x0, 0.0, T_END, p).x1, X0, 1e-6)
    np.testing.assert_allclose(through_wall.monodromy, fd, atol=1e-8)


def test_parameter_sensitivity_through_the_wall(wall_flow, through_wall):
    closed = np.array([1.0 / 3.0, -2.0 * TAU / 3.0])
    np.testing.assert_allclose(through_wall.parameter_sensitivity, closed, atol=1e-12)

    def end(x_w):
        return wall_flow.run(X0, 0.0, T_END, wall_flow.parameters({"x_w": x_w})).x1

    fd = (end(X_W + 1e-6) - end(X_W - 1e-6)) / 2e-6
    np.testing.assert_allclose(through_wall.parameter_sensitivity, fd, atol=1e-8)


def test_sliding_out_of_its_region_without_a_transition_raises(wall_flow):
    # the guards of both wall transitions fail: the domains of up and down end at x = x_w and the
    # model says nothing of what follows
    p = wall_flow.parameters({"open": -1.0})
    with pytest.raises(SlidingError) as info:
        wall_flow.run(X0, 0.0, T_END, p)
    message = str(info.value)
    assert "surface 's' (up|down)" in message and "surface 'wall'" in message
    assert "domain of mode 'up'" in message or "domain of mode 'down'" in message  # (both end there)
    t_stop = float(message.split("at t = ")[1].split(",")[0])
    assert t_stop == pytest.approx(T_W, abs=1e-7)  # where the domain ends, not later


def test_new_mode_pushing_back_across_the_wall_raises(wall_flow):
    # beyond's field points back across the wall: sliding on y = 0 and x = x_w at once, not defined
    with pytest.raises(SlidingError) as info:
        wall_flow.run(X0, 0.0, T_END, wall_flow.parameters({"b_x": -1.0}))
    message = str(info.value)
    assert "surface 's' (up|down)" in message and "mode 'beyond'" in message
    assert "pushes back across 'wall'" in message
    assert float(message.split("at t = ")[1].split(",")[0]) == pytest.approx(T_W, abs=1e-11)  # (12 digits printed)


# -- both sides end at the wall, in different modes -------------------------------------------------

def split_system(reversed_time: bool = False) -> PiecewiseSystem:
    """With ``reversed_time`` every field is negated: integrated backward from ``t = 0`` to ``-t``, the
    motion is the forward one at ``t`` (the transitions, followed in the direction of integration, are
    the same)."""
    sign = "-" if reversed_time else ""
    return PiecewiseSystem(
        name="test_sliding_split_reversed" if reversed_time else "test_sliding_split",
        states=["x", "y"],
        parameters={"x_w": X_W, "a_u": 1.0, "a_d": -1.0},
        modes=[
            Mode("up", [f"{sign}1.5", f"{sign}(-1)"], domain=["y > 0", "x - x_w < 0"]),
            Mode("down", [f"{sign}1.5", f"{sign}1"], domain=["y < 0", "x - x_w < 0"]),
            Mode("left_up", [f"{sign}1", f"{sign}a_u"], domain=["y > 0"]),
            Mode("left_down", [f"{sign}1", f"{sign}a_d"], domain=["y < 0"]),
        ],
        surfaces={"s": "y", "wall": "x - x_w"},
        transitions=[
            Transition("up", "s", FALLING, "down"),
            Transition("down", "s", RISING, "up"),
            Transition("up", "wall", RISING, "left_up"),
            Transition("down", "wall", RISING, "left_down"),
            Transition("left_up", "wall", FALLING, "up"),
            Transition("left_down", "wall", FALLING, "down"),
            Transition("left_up", "s", FALLING, "left_down"),
            Transition("left_down", "s", RISING, "left_up"),
        ],
    )


@pytest.fixture(scope="module", params=[False, True], ids=["forward", "backward"])
def split_flow(request) -> tuple[Flow, float]:
    """The split system and the sign of time: forward, or time-reversed and integrated backward."""
    return Flow(split_system(request.param), TIGHT), -1.0 if request.param else 1.0


@pytest.mark.parametrize(
    ("a_u", "a_d", "after", "y_end"),
    [
        (-1.0, -1.0, [(EventKind.TRANSITION, "wall", "down", "left_down")], -TAU),
        (1.0, 1.0, [(EventKind.TRANSITION, "wall", "up", "left_up")], TAU),
        (-1.0, 1.0, [(EventKind.TRANSITION, "wall", "up", "left_up"),
                     (EventKind.SLIDING_START, "s", "left_up", "left_down")], 0.0),
    ],
    ids=["into left_down", "into left_up", "sliding again"],
)
def test_two_transitions_into_different_modes(split_flow, a_u, a_d, after, y_end):
    flow, sign = split_flow
    p = flow.parameters({"a_u": a_u, "a_d": a_d})
    traj = flow.run(X0, 0.0, sign * T_END, p, variational=True)
    assert _kinds(traj) == [(EventKind.SLIDING_START, "s", "up", "down"), *after]
    assert all(e.t == pytest.approx(sign * T_W, abs=1e-14) for e in traj.events[1:])
    assert traj.sliding_at_end == (y_end == 0.0)
    np.testing.assert_allclose(traj.x1, [X_W + TAU, y_end], rtol=1e-13, atol=1e-13)
    # x(T) = x_w + T - t_w, y(T) = y_end(T - t_w): only x0 matters, through t_w = (x_w - x0) / 1.5
    closed = np.array([[2.0 / 3.0, 0.0], [y_end / TAU * 2.0 / 3.0, 0.0]])
    np.testing.assert_allclose(traj.monodromy, closed, atol=1e-12)


def test_two_transitions_whose_modes_both_leave_raise(split_flow):
    flow, sign = split_flow
    with pytest.raises(SlidingError) as info:
        flow.run(X0, 0.0, sign * T_END, flow.parameters({"a_u": 1.0, "a_d": -1.0}))
    message = str(info.value)
    assert "surface 's' (up|down) meets surface 'wall'" in message and "not unique" in message
    assert float(message.split("at t = ")[1].split(",")[0]) == pytest.approx(sign * T_W, abs=1e-11)  # (12 digits printed)


# -- one side ends at the wall ---------------------------------------------------------------------

def test_new_mode_crossing_the_surface_slides_again(half_wall_flow):
    traj = half_wall_flow.run(X0, 0.0, T_END, half_wall_flow.parameters(), variational=True)
    assert _kinds(traj) == [
        (EventKind.SLIDING_START, "s", "up", "down"),
        (EventKind.TRANSITION, "wall", "up", "fast"),
        (EventKind.SLIDING_START, "s", "fast", "down"),
    ]
    _, wall, again = traj.events
    assert wall.t == pytest.approx(T_W, abs=1e-14) and again.t == wall.t  # at once, without a step
    np.testing.assert_allclose(wall.saltation, [[2.0, 0.0], [-4.0 / 3.0, 1.0]], atol=1e-14)
    np.testing.assert_allclose(again.saltation, [[1.0, 0.5], [0.0, 0.0]], atol=1e-14)
    assert traj.sliding_at_end and traj.modes[-1] == "fast|down"
    np.testing.assert_allclose(traj.x1, [X_W + 2.0 * TAU, 0.0], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(traj.velocity_end, [2.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(traj.monodromy, [[4.0 / 3.0, 0.0], [0.0, 0.0]], atol=1e-12)
    p = half_wall_flow.parameters()
    fd = central_difference_jacobian(lambda x0: half_wall_flow.run(x0, 0.0, T_END, p).x1, X0, 1e-6)
    np.testing.assert_allclose(traj.monodromy, fd, atol=1e-8)


def test_new_mode_leaving_the_surface(half_wall_flow):
    p = half_wall_flow.parameters({"v_f": 2.0})
    traj = half_wall_flow.run(X0, 0.0, T_END, p, variational=True)
    assert _kinds(traj) == [
        (EventKind.SLIDING_START, "s", "up", "down"),
        (EventKind.TRANSITION, "wall", "up", "fast"),
    ]
    assert traj.mode1 == "fast" and not traj.sliding_at_end
    np.testing.assert_allclose(traj.x1, [X_W + 3.0 * TAU, 2.0 * TAU], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(traj.monodromy, [[2.0, 0.0], [4.0 / 3.0, 0.0]], atol=1e-12)
    fd = central_difference_jacobian(lambda x0: half_wall_flow.run(x0, 0.0, T_END, p).x1, X0, 1e-6)
    np.testing.assert_allclose(traj.monodromy, fd, atol=1e-8)


# -- a curved sliding surface ---------------------------------------------------------------------

CURVE = "y - 0.1*sin(3*x)"


def curved_half_wall_system() -> PiecewiseSystem:
    """``half_wall_system`` with the sliding surface ``y = 0.1 sin(3 x)``: the integration drifts off it
    by its local errors (about 1e-6 at rtol 1e-3), which the transition at the wall must tolerate."""
    return PiecewiseSystem(
        name="test_sliding_curved_half_wall",
        states=["x", "y"],
        parameters={"x_w": X_W, "v_f": -2.0},
        modes=[
            Mode("up", ["1.5", "-1"], domain=[f"{CURVE} > 0", "x - x_w < 0"]),
            Mode("down", ["1.5", "1"], domain=[f"{CURVE} < 0"]),
            Mode("fast", ["3", "v_f"], domain=[f"{CURVE} > 0"]),
        ],
        surfaces={"s": CURVE, "wall": "x - x_w"},
        transitions=[
            Transition("up", "s", FALLING, "down"),
            Transition("down", "s", RISING, "up", guard=["x - x_w < 0"]),
            Transition("down", "s", RISING, "fast", guard=["x - x_w >= 0"]),
            Transition("up", "wall", RISING, "fast"),
            Transition("fast", "wall", FALLING, "up"),
            Transition("fast", "s", FALLING, "down"),
        ],
    )


def _curved_reference(x0, t_end):
    """scipy: ``up`` to the curve (an event), along it at ``x' = 1.5`` to the wall, then Filippov's field of
    ``fast`` and ``down`` on the curve, ``x' = 3 - 1.5 alpha(x)``, ``alpha = s_f / (s_f - s_d)``."""
    def curve(t, z):
        return z[1] - 0.1 * np.sin(3 * z[0])

    curve.terminal, curve.direction = True, -1.0
    tol = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-15}
    first = solve_ivp(lambda t, z: [1.5, -1.0], (0.0, t_end), x0, events=curve, **tol)
    t1, x1 = first.t_events[0][0], first.y_events[0][0][0]
    t_w = t1 + (X_W - x1) / 1.5

    def sliding(t, z):
        g = -0.3 * np.cos(3 * z[0])  # d(curve)/dx
        s_f, s_d = 3.0 * g - 2.0, 1.5 * g + 1.0
        return [3.0 - 1.5 * s_f / (s_f - s_d)]

    x_end = solve_ivp(sliding, (t_w, t_end), [X_W], **tol).y[0, -1]
    return t1, t_w, np.array([x_end, 0.1 * np.sin(3 * x_end)])


@pytest.mark.parametrize("rtol", [1e-10, 1e-3])
def test_curved_surface_slides_again_after_the_wall(rtol):
    flow = Flow(curved_half_wall_system(), Tolerances(rtol=rtol, atol=1e-2 * rtol))
    p = flow.parameters()
    traj = flow.run(X0, 0.0, T_END, p, variational=True)
    assert _kinds(traj) == [
        (EventKind.SLIDING_START, "s", "up", "down"),
        (EventKind.TRANSITION, "wall", "up", "fast"),
        (EventKind.SLIDING_START, "s", "fast", "down"),
    ]
    t1, t_w, x_end = _curved_reference(X0, T_END)
    accuracy = 1e-9 if rtol < 1e-6 else 1e-4
    assert traj.events[0].t == pytest.approx(t1, abs=accuracy)
    assert traj.events[1].t == pytest.approx(t_w, abs=accuracy)
    assert traj.sliding_at_end
    np.testing.assert_allclose(traj.x1, x_end, atol=accuracy)
    if rtol < 1e-6:
        fd = central_difference_jacobian(lambda z: flow.run(z, 0.0, T_END, p).x1, X0, 1e-6)
        np.testing.assert_allclose(traj.monodromy, fd, atol=1e-7)


# -- the block on the belt --------------------------------------------------------------------------

V_DR = 0.2


@pytest.fixture(scope="module")
def belt_cycle(belt_flow):
    """The stable stick-slip cycle at v_dr = 0.2, by shooting from a state of a brute-force run."""
    p = belt_flow.parameters({"v_dr": V_DR})
    guess = belt_flow.run([0.0, V_DR], 0.0, 60.0, p).x1
    orbit = find_periodic_orbit(belt_flow, guess, parameters={"v_dr": V_DR}, period=12.6)
    cycle = belt_flow.run(orbit.state0, 0.0, orbit.period, p, dense=True)
    return orbit, cycle


@pytest.mark.parametrize("x0", [[0.0, 1.0], [0.0, V_DR]], ids=["from above the band", "sticking"])
def test_block_on_belt_ends_on_the_stable_cycle(belt_flow, belt_cycle, x0):
    orbit, cycle = belt_cycle
    assert orbit.stable
    p = belt_flow.parameters({"v_dr": V_DR})
    traj = belt_flow.run(x0, 0.0, 100 * math.pi, p)  # 50 undamped periods
    assert not traj.sliding_at_end
    # the run's last stick phase ends where the cycle's does, and so does its last entry into the band
    for surface in ("stick_upper", "band_lower"):
        on_cycle = [e for e in cycle.events if e.surface == surface]
        last = [e for e in traj.events if e.surface == surface][-1]
        assert len(on_cycle) == 1 and (last.mode_from, last.mode_to) == (on_cycle[0].mode_from, on_cycle[0].mode_to)
        np.testing.assert_allclose(last.x_minus, on_cycle[0].x_minus, rtol=0, atol=1e-10)
    # the end state is the cycle's state as long after its stick phase ends
    leave_cycle = next(e for e in cycle.events if e.surface == "stick_upper")
    leave_run = [e for e in traj.events if e.surface == "stick_upper"][-1]
    phase = (leave_cycle.t + traj.t1 - leave_run.t) % orbit.period
    np.testing.assert_allclose(traj.x1, cycle.at([phase])[0], rtol=0, atol=5e-10)


def test_block_on_belt_sliding_ends_on_v_rel(belt_flow):
    p = belt_flow.parameters({"v_dr": V_DR})
    pv = dict(zip(belt_flow.system.parameter_names, p))
    traj = belt_flow.run([0.0, 1.0], 0.0, 13.0, p)
    kinds = _kinds(traj)
    assert kinds[:4] == [
        (EventKind.TRANSITION, "band_upper", "slip_plus", "stick"),
        (EventKind.SLIDING_START, "stick_upper", "stick", "slip_plus"),
        (EventKind.TRANSITION, "v_rel", "slip_plus", "slip_minus"),
        (EventKind.TRANSITION, "band_lower", "slip_minus", "stick"),
    ]
    slide, leave, enter = traj.events[1:4]
    assert 0.0 < leave.t - slide.t < 1e-7
    # where the sliding motion (on k x + c v = F_stick) reaches v = v_dr
    x_leave = (pv["F_stick"] - pv["c"] * V_DR) / pv["k"]
    np.testing.assert_allclose(leave.x_minus, [x_leave, V_DR], rtol=0, atol=1e-13)
    m, c, k, f = pv["m"], pv["c"], pv["k"], pv["F_slip"]
    # eq. (9) on h = v - v_dr from the sliding field (v' = -k v_dr / c there: alpha = m k v_dr / (c (F_stick +
    # F_slip))) into slip_minus (v' = (F_slip - F_stick) / m)
    np.testing.assert_allclose(leave.saltation, [[1.0, 0.0], [0.0, c * (pv["F_stick"] - f) / (m * k * V_DR)]],
                               rtol=0, atol=1e-12)
    # slip_minus from there, independently: m x'' + c x' + k x = F_slip until v = v_dr - eta (rising)

    def band(t, z):
        return z[1] - (V_DR - pv["eta"])

    band.terminal, band.direction = True, 1.0
    ref = solve_ivp(lambda t, z: [z[1], (-k * z[0] - c * z[1] + f) / m], (leave.t, leave.t + 20.0), leave.x_plus,
                    method="DOP853", rtol=1e-13, atol=1e-15, events=band)
    # the first rising crossing (the orbit starts just on v = v_dr, moving down)
    assert enter.t == pytest.approx(ref.t_events[0][0], abs=1e-9)
    np.testing.assert_allclose(enter.x_minus, ref.y_events[0][0], atol=1e-9)


def test_block_on_belt_monodromy_through_the_sliding_end(belt_flow):
    """Stick, sliding along stick_upper, its end on v_rel, slip: the monodromy against central
    differences of the end state."""
    p = belt_flow.parameters({"v_dr": V_DR})
    x0 = np.array([1.975, V_DR + 5e-5])
    traj = belt_flow.run(x0, 0.0, 1.0, p, variational=True, tolerances=TIGHT)
    assert [e[:2] for e in _kinds(traj)] == [
        (EventKind.SLIDING_START, "stick_upper"),
        (EventKind.TRANSITION, "v_rel"),
    ]
    fd = central_difference_jacobian(lambda z: belt_flow.run(z, 0.0, 1.0, p, tolerances=TIGHT).x1, x0, 1e-6)
    # (the second column, about 5e-5, is the response to v0 that the stick phase's decay leaves: the
    # differences carry about 1e-9 of rounding in it)
    np.testing.assert_allclose(traj.monodromy, fd, rtol=1e-8, atol=2e-9)
    assert abs(traj.monodromy[0, 0]) > 1.0 and abs(traj.monodromy[0, 1]) > 1e-5
