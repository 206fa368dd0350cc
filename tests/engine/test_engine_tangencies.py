"""The event engine at near-tangencies, against closed forms (property-based, hypothesis).

``tilted``: the forced Filippov system ``x'' + 2 zeta x' + x = a cos(w t) + b - k sgn(s)`` with the
tilted switching line ``s = x + c x'``.  Each mode is affine: its flow is ``expm`` of the augmented
linear system ``(x, v, cos wt, sin wt, 1)`` (``closed``), exact to rounding.

* A near-tangency that does not cross: a state where ``s = +-d`` and ``s' = 0`` with the curvature
  ``s''`` pointing away from the line is integrated backward and forward in closed form.  From
  there the engine must give the closed-form state, with no event on the exact path (at any
  tolerance: event location on the exact flow's series does not depend on it), and on the DOP853
  path the closed-form state to its tolerance (a sliding start and end pair at a depth below the
  tolerance is within it).
* A switching-sliding neighbourhood on its crossing side: a crossing into ``minus`` where
  ``L_minus = s' = -eps`` and ``L_minus`` grows along ``minus``: the orbit makes an excursion of
  depth ``eps^2 / (2 s'')`` and returns into the attracting sliding region.  Its return time is
  brentq on the closed form (for ``eps < 1e-6``, where the depth is rounding, that of the quadratic
  model: an error of order ``eps^2`` in time); the sliding motion on ``x = -c v`` is
  ``v' = -v / c``, so ``v = v_r exp(-(t - t_r) / c)``.  The engine must start that sliding motion,
  after an excursion of any length.

``poke``: the harmonic oscillator ``x = cos t`` (exact flow) pokes above ``x = a`` for a fraction of
its period; only the way back (falling) has a transition (the rising one's guard fails), at
``t = arccos a``.  A dip whose way in has no transition is searched for its way back.

``wall``: the forced oscillator ``x'' + 2 zeta x' + x = a cos(w t)`` whose orbit misses the wall
``x = x_w`` of a contact spring by ``d``: no event on the exact path, and the free closed form.  The
same orbit reaching ``d`` above the wall: the free and the contact closed forms joined where each
reaches ``x_w`` (brentq), and the contact pair logged at every depth the indicator resolves.

``corner``: constant fields in the four quadrants of ``x = 0`` and ``y = 0``; a straight motion passes
the corner at a distance ``d`` (or through it), and crosses the two surfaces in the order and at the
times of the closed form.

Tolerances: the exact path is exact to rounding, so the closed form is met to ``1e-9`` (the
closed form's own ``expm`` of a matrix of norm ~2 over ~1.4 time units is exact to ~1e-14 and the
engine to rounding; 1e-9 leaves room for the conditioning of ``d`` in ``touch_state``); the DOP853
path to ``100 rtol`` (its global error over a run of some 20 steps, state of size ~1).

Runtime: hypothesis profile ``ci`` of conftest.py (50 examples per property).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from scipy.linalg import expm
from scipy.optimize import brentq

from saltation import Crossing, EventKind, Flow, Mode, PiecewiseSystem, Tolerances, Transition
from saltation.models.block_on_belt import block_on_belt

ZETA, A, W, B, K, C = 0.1, 0.8, 1.3, 0.2, 0.5, 0.4
RTOLS = st.sampled_from([1e-4, 1e-6, 1e-8, 1e-10, 1e-12])
DEPTHS = st.sampled_from([1e-14, 1e-13, 1e-12, 1e-11, 1e-10, 1e-8, 1e-6])


@functools.cache
def tilted_flow() -> Flow:
    return Flow(PiecewiseSystem(
        name="test_tilted_relay", states=["x", "v"],
        parameters={"zeta": ZETA, "a": A, "w": W, "b": B, "k": K, "c": C},
        modes=[Mode("plus", ["v", "-2*zeta*v - x + a*cos(w*t) + b - k"], domain=["x + c*v > 0"]),
               Mode("minus", ["v", "-2*zeta*v - x + a*cos(w*t) + b + k"], domain=["x + c*v < 0"])],
        surfaces={"s": "x + c*v"},
        transitions=[Transition("plus", "s", Crossing.FALLING, "minus"),
                     Transition("minus", "s", Crossing.RISING, "plus")],
        period="2*pi/w"))


def closed(x0, t0: float, t1: float, side: int) -> np.ndarray:
    """The flow of mode ``plus`` (side +1) or ``minus`` (-1) from ``(t0, x0)`` to ``t1``."""
    M = np.zeros((5, 5))
    M[0, 1] = 1.0
    M[1, 0], M[1, 1], M[1, 2], M[1, 4] = -1.0, -2 * ZETA, A, B - side * K
    M[2, 3], M[3, 2] = -W, W
    y0 = np.array([x0[0], x0[1], np.cos(W * t0), np.sin(W * t0), 1.0])
    return (expm(M * (t1 - t0)) @ y0)[:2]


def lie(side: int, t: float, x) -> float:
    """``s' = v + c v'`` along a mode's field."""
    return x[1] + C * (-2 * ZETA * x[1] - x[0] + A * np.cos(W * t) + B - side * K)


def s_value(x) -> float:
    return float(x[0] + C * x[1])


def touch_state(t_touch: float, depth: float, side: int) -> np.ndarray:
    """The state of mode ``side`` at ``s = side * depth`` with ``s' = 0``."""
    forcing = B - side * K + A * np.cos(W * t_touch)
    return np.linalg.solve([[1.0, C], [-C, 1.0 - 2.0 * ZETA * C]], [side * depth, -C * forcing])


def tolerances(rtol: float, exact: bool) -> Tolerances:
    return Tolerances(rtol=rtol, atol=rtol * 1e-2, exact_affine=exact)


def _curvature(t_touch: float, x_touch, side: int) -> float:
    eps = 1e-4
    return (lie(side, t_touch + eps, closed(x_touch, t_touch, t_touch + eps, side))
            - lie(side, t_touch - eps, closed(x_touch, t_touch, t_touch - eps, side))) / (2 * eps)


@given(t_touch=st.floats(0.0, 2 * np.pi / W), depth=DEPTHS, prefer=st.sampled_from([-1, 1]), rtol=RTOLS,
       exact=st.booleans())
def test_near_tangency_without_crossing(t_touch, depth, prefer, rtol, exact):
    tau = 0.3
    for side in (prefer, -prefer):  # the side whose touch at t_touch is a clear minimum of |s|
        x_touch = touch_state(t_touch, depth, side)
        if side * _curvature(t_touch, x_touch, side) > 0.02 and min(
                side * s_value(closed(x_touch, t_touch, t, side)) for t in np.linspace(t_touch - tau, t_touch + tau, 101)
        ) >= 0.0:
            break
    else:
        assume(False)
    x0 = closed(x_touch, t_touch, t_touch - tau, side)
    reference = closed(x_touch, t_touch, t_touch + tau, side)
    traj = tilted_flow().run(x0, t_touch - tau, t_touch + tau, tilted_flow().parameters(),
                             mode0="plus" if side > 0 else "minus", tolerances=tolerances(rtol, exact))
    if exact:
        assert traj.events == []
        assert np.abs(traj.x1 - reference).max() < 1e-9
    else:
        assert np.abs(traj.x1 - reference).max() < 100 * rtol
        assert [e.kind for e in traj.events] in ([], [EventKind.SLIDING_START, EventKind.SLIDING_END])
    assert traj.mode1 == ("plus" if side > 0 else "minus")


@given(t_cross=st.floats(0.0, 2 * np.pi / W), eps=st.sampled_from([1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4]),
       rtol=RTOLS, exact=st.booleans())
def test_excursion_returns_into_sliding(t_cross, eps, rtol, exact):
    forcing = A * np.cos(W * t_cross) + B + K
    v = (-eps - C * forcing) / (1 - 2 * ZETA * C + C * C)
    x_cross = np.array([-C * v, v])  # on the line, with L_minus = -eps
    assume(lie(1, t_cross, x_cross) < -0.05)  # plus crosses towards minus
    d = 1e-3
    s2 = (lie(-1, t_cross + d, closed(x_cross, t_cross, t_cross + d, -1))
          - lie(-1, t_cross - d, closed(x_cross, t_cross, t_cross - d, -1))) / (2 * d)
    assume(s2 > 0.05)  # minus turns back
    tau = 0.5
    before = [s_value(closed(x_cross, t_cross, t, 1)) for t in np.linspace(t_cross - tau, t_cross - 1e-3, 100)]
    assume(min(before) > 0.0)
    if eps < 1e-6:
        t_return = t_cross + 2 * eps / s2
    else:
        t_min = t_cross + eps / s2
        hi = t_cross + 4 * eps / s2
        while s_value(closed(x_cross, t_cross, hi, -1)) < 0:
            hi = t_cross + 2 * (hi - t_cross)
        t_return = brentq(lambda t: s_value(closed(x_cross, t_cross, t, -1)), t_min, hi, xtol=1e-16, rtol=1e-15)
    v_return = closed(x_cross, t_cross, t_return, -1)[1]
    t_end = t_return + 0.3
    for t in np.linspace(t_return, t_end, 50):  # the sliding motion stays in the attracting region
        vs = v_return * np.exp(-(t - t_return) / C)
        assume(lie(1, t, [-C * vs, vs]) < 0.0 < lie(-1, t, [-C * vs, vs]))
    v_end = v_return * np.exp(-(t_end - t_return) / C)
    traj = tilted_flow().run(closed(x_cross, t_cross, t_cross - tau, 1), t_cross - tau, t_end,
                             tilted_flow().parameters(), mode0="plus", tolerances=tolerances(rtol, exact))
    kinds = [e.kind for e in traj.events]
    assert kinds == [EventKind.TRANSITION, EventKind.SLIDING_START]
    assert traj.events[0].t == pytest.approx(t_cross, abs=1e-6 + 100 * rtol)
    assert traj.sliding_at_end
    # the error of the reference's return time (eps^2 in time) and the integration's
    assert np.abs(traj.x1 - [-C * v_end, v_end]).max() < 100 * rtol + 1e-9


@functools.cache
def poke_flow() -> Flow:
    return Flow(PiecewiseSystem(
        name="test_poke", states=["x", "v"], parameters={"a": 0.99, "g": 0.0},
        modes=[Mode("up", ["v", "-x"]), Mode("down", ["v", "-x"])],
        surfaces={"s": "x - a"},
        transitions=[Transition("up", "s", Crossing.FALLING, "down"),
                     Transition("up", "s", Crossing.RISING, "down", guard=["v - g < 0"])]))  # never holds rising


@given(depth=st.floats(1e-12, 0.1), rtol=RTOLS, exact=st.booleans())
def test_crossing_back_within_a_step(depth, rtol, exact):
    """``x = cos t`` above ``x = 1 - depth`` for ``|t| < arccos(1 - depth)``: the falling crossing is found
    at any depth on the exact path, and on the DOP853 path wherever the depth exceeds its tolerance."""
    flow = poke_flow()
    a = 1.0 - depth
    t0 = -1.3
    traj = flow.run([np.cos(t0), -np.sin(t0)], t0, 3.0, flow.parameters({"a": a}), mode0="up",
                    tolerances=tolerances(rtol, exact))
    t_event = np.arccos(a)
    if not exact and depth < 10 * rtol:
        assert len(traj.events) <= 1  # the dip lies within the tolerance: found or not
    else:
        assert [e.mode_to for e in traj.events] == ["down"]
    if traj.events:
        # a state error e moves the crossing of x = a (speed sin t_event) by e / sin t_event
        assert traj.events[0].t == pytest.approx(t_event, abs=(1e-12 if exact else 10 * rtol) / np.sin(t_event))
    assert traj.x1 == pytest.approx([np.cos(3.0), -np.sin(3.0)], abs=1e-12 if exact else 100 * rtol)


@functools.cache
def wall_flow() -> Flow:
    return Flow(PiecewiseSystem(
        name="test_wall_spring", states=["x", "v"],
        parameters={"zeta": ZETA, "a": A, "w": W, "x_w": 1.0, "k_c": 10.0},
        modes=[Mode("free", ["v", "-2*zeta*v - x + a*cos(w*t)"], domain=["x - x_w < 0"]),
               Mode("contact", ["v", "-2*zeta*v - x - k_c*(x - x_w) + a*cos(w*t)"], domain=["x - x_w > 0"])],
        surfaces={"wall": "x - x_w"},
        transitions=[Transition("free", "wall", Crossing.RISING, "contact"),
                     Transition("contact", "wall", Crossing.FALLING, "free")],
        period="2*pi/w"))


@given(t_touch=st.floats(0.0, 2 * np.pi / W), depth=DEPTHS, rtol=RTOLS, exact=st.booleans())
def test_wall_missed_by_a_hair(t_touch, depth, rtol, exact):
    """The free orbit whose maximum of ``x`` lies ``depth`` below the wall: the free closed form (the
    tilted system with ``k = b = 0`` and ``c = 0``), no event on the exact path."""
    flow = wall_flow()
    # x = x_w - depth, v = 0 at t_touch, with x'' = -x + a cos(w t) < 0 there (a maximum)
    x_touch = np.array([1.0 - depth, 0.0])
    assume(-x_touch[0] + A * np.cos(W * t_touch) < -0.05)
    M = np.zeros((5, 5))
    M[0, 1], M[1, 0], M[1, 1], M[1, 2], M[2, 3], M[3, 2] = 1.0, -1.0, -2 * ZETA, A, -W, W

    def free(t1):
        return (expm(M * (t1 - t_touch)) @ [*x_touch, np.cos(W * t_touch), np.sin(W * t_touch), 1.0])[:2]

    tau = 0.6
    assume(max(free(t)[0] for t in np.linspace(t_touch - tau, t_touch + tau, 201)) <= 1.0 - depth)
    traj = flow.run(free(t_touch - tau), t_touch - tau, t_touch + tau, flow.parameters(), mode0="free",
                    tolerances=tolerances(rtol, exact))
    if exact:
        assert traj.events == []
        assert np.abs(traj.x1 - free(t_touch + tau)).max() < 1e-9
    else:
        # a contact shallower than the tolerance, if any, changes the state by less than it
        assert np.abs(traj.x1 - free(t_touch + tau)).max() < 100 * rtol


def test_narrow_stick_band_keeps_its_events():
    """The block on the belt (eq. 17) with a stick band 2e-14 wide (eta = 1e-14) goes through the same
    events as with eta = 1e-12, to the same state: the band is resolved (a state within rounding of a
    surface is on it, rounding being that of the indicator's own terms, not a fixed 1e-12)."""
    runs = {}
    for eta in (1e-12, 1e-14):
        flow = Flow(block_on_belt(eta=eta))
        runs[eta] = flow.run([0.0, 1.0], 0.0, 100.0, flow.parameters({"v_dr": 1.0}))
    wide, narrow = runs[1e-12], runs[1e-14]
    assert [(e.mode_from, e.mode_to, e.surface) for e in narrow.events] == \
        [(e.mode_from, e.mode_to, e.surface) for e in wide.events]
    assert len(wide.events) == 31
    # the two models differ by eta in the band's edges: event times and states by a few eta
    assert np.abs(narrow.x1 - wide.x1).max() < 1e-9


def _wall_pieces(t_touch: float, depth: float):
    """The free and the contact closed forms of the wall oscillator, from the free state ``x_w + depth``
    with ``v = 0`` at ``t_touch`` (a maximum of the free motion)."""
    def augmented(k_c: float) -> np.ndarray:
        M = np.zeros((5, 5))
        M[0, 1], M[1, 0], M[1, 1], M[1, 2], M[1, 4], M[2, 3], M[3, 2] = 1.0, -1.0 - k_c, -2 * ZETA, A, k_c, -W, W
        return M

    free_M, contact_M = augmented(0.0), augmented(10.0)

    def flow(M, t_a, x_a, t_b):
        return (expm(M * (t_b - t_a)) @ [*x_a, np.cos(W * t_a), np.sin(W * t_a), 1.0])[:2]

    return free_M, contact_M, flow


@given(t_touch=st.floats(0.0, 2 * np.pi / W), depth=DEPTHS, rtol=RTOLS, exact=st.booleans())
def test_wall_touched_by_a_hair(t_touch, depth, rtol, exact):
    """The orbit whose free motion would reach ``depth`` above the wall: it enters the contact spring
    where the free closed form reaches ``x_w`` (brentq), and leaves it where the contact closed form
    returns there.  The exact path logs that pair at every depth it can resolve (``1e-12`` and deeper,
    at any tolerance: a contact within the indicator's rounding, ``~4e-15``, may be logged or not), the
    DOP853 path wherever the depth exceeds its tolerance; the end state is the closed form's."""
    flow = wall_flow()
    x_touch = np.array([1.0 + depth, 0.0])
    assume(-x_touch[0] + A * np.cos(W * t_touch) < -0.05)
    free_M, contact_M, piece = _wall_pieces(t_touch, depth)
    tau = 0.6
    xs = [piece(free_M, t_touch, x_touch, t)[0] for t in np.linspace(t_touch - tau, t_touch + tau, 201)]
    assume(xs[0] < 1.0 - 1e-3 and max(xs[:100]) < 1.0 + depth and max(xs[101:]) < 1.0 + depth)
    # the way in: the free motion's rise through x_w, bracketed by the last sample below the wall
    below = max(i for i in range(101) if xs[i] < 1.0)
    t_lo = t_touch - tau + below * (2 * tau / 200)
    t_in = brentq(lambda t: piece(free_M, t_touch, x_touch, t)[0] - 1.0, t_lo, t_touch, xtol=1e-16, rtol=1e-15)
    x_in = piece(free_M, t_touch, x_touch, t_in)
    # the way out: the contact motion, which turns back sooner than the free one, falls through x_w
    # within twice the free motion's time above it
    span = max(t_touch - t_in, 1e-9)
    t_hi = t_in + 2 * span
    while piece(contact_M, t_in, x_in, t_hi)[0] >= 1.0:
        t_hi = t_in + 2 * (t_hi - t_in)
    t_out = brentq(lambda t: piece(contact_M, t_in, x_in, t)[0] - 1.0, t_in + span / 2, t_hi, xtol=1e-16, rtol=1e-15) \
        if piece(contact_M, t_in, x_in, t_in + span / 2)[0] > 1.0 else t_in
    x_out = piece(contact_M, t_in, x_in, t_out)
    reference = piece(free_M, t_out, x_out, t_touch + tau)
    traj = flow.run(piece(free_M, t_touch, x_touch, t_touch - tau), t_touch - tau, t_touch + tau, flow.parameters(),
                    mode0="free", tolerances=tolerances(rtol, exact))
    modes = [(e.mode_from, e.mode_to) for e in traj.events]
    assert modes in ([], [("free", "contact"), ("contact", "free")])
    assert traj.mode1 == "free"
    if exact:
        if depth >= 1e-12:
            assert modes, "a contact 1e-12 deep or deeper is missed"
        assert np.abs(traj.x1 - reference).max() < 1e-9
    else:
        if depth >= 10 * rtol:
            assert modes
        assert np.abs(traj.x1 - reference).max() < 100 * rtol
    if modes and depth >= 1e-8:
        # a state error e moves a crossing of x = x_w, passed at speed |v|, by e / |v|
        err = (1e-12 if exact else 10 * rtol) / abs(x_in[1])
        assert traj.events[0].t == pytest.approx(t_in, abs=err)
        assert traj.events[1].t == pytest.approx(t_out, abs=err)


QUADRANTS = {"mm": ("x < 0", "y < 0"), "pm": ("x > 0", "y < 0"), "mp": ("x < 0", "y > 0"), "pp": ("x > 0", "y > 0")}


@functools.cache
def corner_flow() -> Flow:
    """Constant fields ``(ax_q, by_q)`` in the four quadrants ``q`` of ``x = 0`` and ``y = 0``: the corner
    of two surfaces, every motion a straight line."""
    params = {f"{c}_{q}": 1.0 for q in QUADRANTS for c in ("ax", "by")}
    transitions = []
    for q in QUADRANTS:
        flip_x = ("p" if q[0] == "m" else "m") + q[1]
        flip_y = q[0] + ("p" if q[1] == "m" else "m")
        transitions += [Transition(q, "sx", Crossing.RISING if q[0] == "m" else Crossing.FALLING, flip_x),
                        Transition(q, "sy", Crossing.RISING if q[1] == "m" else Crossing.FALLING, flip_y)]
    return Flow(PiecewiseSystem(
        name="test_corner", states=["x", "y"], parameters=params,
        modes=[Mode(q, [f"ax_{q}", f"by_{q}"], domain=list(QUADRANTS[q])) for q in QUADRANTS],
        surfaces={"sx": "x", "sy": "y"}, transitions=transitions))


@given(fields=st.lists(st.floats(0.5, 2.0), min_size=8, max_size=8),
       d=st.one_of(st.just(0.0), DEPTHS, DEPTHS.map(lambda v: -v)), rtol=RTOLS, exact=st.booleans())
def test_corner_of_two_surfaces(fields, d, rtol, exact):
    """A straight motion from quadrant ``mm`` that meets ``x = 0`` where ``y = d``: for ``d < 0`` it crosses
    ``x = 0`` and then ``y = 0`` (through ``pm``), for ``d > 0`` the other way round (through ``mp``), at
    the closed-form times; through the corner itself (``d = 0``) in either order, at one instant.  The
    end state is the closed form's in every case (the two orders differ by ``O(|d|)``)."""
    flow = corner_flow()
    names = [f"{c}_{q}" for q in QUADRANTS for c in ("ax", "by")]
    values = dict(zip(names, fields))
    p = flow.parameters(values)
    ax, by = (lambda q: values[f"ax_{q}"]), (lambda q: values[f"by_{q}"])
    t_x = 1.0 / ax("mm")  # x reaches 0 from x = -1
    x0 = np.array([-1.0, d - by("mm") * t_x])
    if d <= 0.0:  # through pm: x = 0 at t_x, then y = 0
        t1, t2, first = t_x, t_x - d / by("pm"), ("mm", "pm")
        corner = np.array([ax("pm") * (t2 - t1), 0.0])
    else:  # through mp: y = 0 first, then x = 0
        t1 = t_x - d / by("mm")
        t2, first = t1 + ax("mm") * (t_x - t1) / ax("mp"), ("mm", "mp")
        corner = np.array([0.0, by("mp") * (t2 - t1)])
    t_end = t_x + 1.0
    reference = corner + (t_end - t2) * np.array([ax("pp"), by("pp")])
    traj = flow.run(x0, 0.0, t_end, p, mode0="mm", tolerances=tolerances(rtol, exact))
    modes = [(e.mode_from, e.mode_to) for e in traj.events]
    assert len(modes) == 2 and modes[0][0] == "mm" and modes[0][1] == modes[1][0] and modes[1][1] == "pp", modes
    assert traj.mode1 == "pp"
    # straight lines: both paths are exact, up to the crossings' location: a crossing is located to the
    # indicator's rounding (16 eps times its terms, |x| <= 2: 7e-15) over the speed (>= 0.5), 1.4e-14
    # in time, which moves the end state by at most that times the fields' difference (<= 1.5)
    assert np.abs(traj.x1 - reference).max() < 1e-13
    if abs(d) >= 1e-12:  # resolved: the order is the closed form's, at its times
        assert modes[0] == first
        assert [e.t for e in traj.events] == pytest.approx([t1, t2], abs=2e-14)
    else:
        assert traj.events[1].t - traj.events[0].t == pytest.approx(t2 - t1, abs=2e-14)
