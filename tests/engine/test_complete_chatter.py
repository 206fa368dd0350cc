"""Complete chatter: impacts with restitution 0 < e < 1 that accumulate where the contact sticks, jumped to their
limit (:mod:`saltation.engine.chatter`).

The ball on the table ``s(t) = A sin(omega t)`` (``omega = 2 pi``, ``g = 9.81``, ``e = 0.5``, ``A = 0.26``:
``A omega^2 = 1.046 g``), its impact declared ``sticks=True``.  References, none of them from the engine:

* the release at ``t_r = asin(g / (A omega^2)) / omega`` (closed form);
* every flight in closed form, relative to the table: ``z(tau) = w tau - g tau^2 / 2 - (s(t + tau) - s(t) -
  s'(t) tau)`` (the table's term written without cancellation), its root by scipy's ``brentq`` impact by
  impact, ``w+ = -e w-`` at each impact, until the relative velocity is below ``1e-8``; then the geometric
  tail ``2 w / ((1 - e) (g + s''))``, whose error ``~ (2 w / g)^2 omega`` is below ``1e-15``;
* the ball on a fixed floor: rest at ``t_inf = t_1 + (2 v_1 / g) e / (1 - e)`` in closed form;
* monodromies: zero for the ball's states (the stuck state depends on time alone), ``expm`` of a decoupled
  harmonic oscillator, central differences (Richardson) of the period map of a ball on a table that is a
  forced mass on a spring (the impacts and the contact force act on both: a coupled contact).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm
from scipy.optimize import brentq

from saltation import ChatteringError, Crossing, Flow, Mode, PiecewiseSystem, Tolerances, Transition, find_periodic_orbit
from saltation.models import bouncing_ball

G, OMEGA, E, A = 9.81, 2 * math.pi, 0.5, 0.26
TIGHT = Tolerances(rtol=1e-12, atol=1e-14)


# ------------------------------------------------------------------------------ the reference: flight by flight
def _table_rest(t0: float, tau: float, amplitude: float) -> float:
    """``s(t0 + tau) - s(t0) - s'(t0) tau`` without cancellation."""
    a, b = OMEGA * t0, OMEGA * tau
    sin_b_minus_b = math.sin(b) - b if b > 1e-3 else -b**3 / 6 * (1 - b * b / 20 * (1 - b * b / 42))
    return amplitude * (-2 * math.sin(a) * math.sin(b / 2) ** 2 + math.cos(a) * sin_b_minus_b)


def _height_over_tau(t0: float, w0: float, tau: float, amplitude: float) -> float:
    """The height over the table after ``tau`` of free flight from the table at relative velocity ``w0``,
    divided by ``tau``."""
    return w0 - G * tau / 2 - _table_rest(t0, tau, amplitude) / tau


def _relative_velocity(t0: float, w0: float, tau: float, amplitude: float) -> float:
    return w0 - G * tau + 2 * amplitude * OMEGA * math.sin(OMEGA * t0 + OMEGA * tau / 2) * math.sin(OMEGA * tau / 2)


def _flight(t0: float, w0: float, amplitude: float) -> float:
    """The duration of the flight from the table at ``t0`` with relative velocity ``w0 >= 0``."""
    decel = G - amplitude * OMEGA**2 * math.sin(OMEGA * t0)
    guess = 2 * w0 / decel if w0 > 0 else 0.0
    if guess > 1e-3 or w0 == 0:
        taus = np.linspace(1e-4, 1.0, 10001)
        values = [_height_over_tau(t0, w0, s, amplitude) for s in taus]
        k = next(i for i in range(len(taus) - 1) if values[i] > 0 >= values[i + 1])
        lo, hi = taus[k], taus[k + 1]
    else:
        lo, hi = 0.5 * guess, 1.5 * guess
    return brentq(lambda s: _height_over_tau(t0, w0, s, amplitude), lo, hi, xtol=1e-300, rtol=8.9e-16, maxiter=500)


def release_time(amplitude: float) -> float:
    return math.asin(G / (amplitude * OMEGA**2)) / OMEGA


def reference_chatter(amplitude: float = A, e: float = E) -> tuple[list[float], float]:
    """From the release at ``t_r`` (at rest on the table): the impact times until the relative velocity is below
    1e-8, and the accumulation time."""
    t, w = release_time(amplitude), 0.0
    times = []
    while True:
        tau = _flight(t, w, amplitude)
        w = -e * _relative_velocity(t, w, tau, amplitude)
        t += tau
        times.append(t)
        if w < 1e-8:
            decel = G - amplitude * OMEGA**2 * math.sin(OMEGA * t)
            return times, t + 2 * w / ((1 - e) * decel)


REF_IMPACTS, REF_T_INF = reference_chatter()


def table(t: float, amplitude: float = A) -> np.ndarray:
    return np.array([amplitude * math.sin(OMEGA * t), amplitude * OMEGA * math.cos(OMEGA * t)])


# ------------------------------------------------------------------------------ the ball on the vibrating table
@pytest.fixture(scope="module")
def ball_flow() -> Flow:
    return Flow(bouncing_ball(e=E, A=A))


def test_the_ball_lands_chatters_and_sticks_where_the_flights_in_closed_form_say(ball_flow):
    """From rest on the table at t = 0: released at t_r, it lands, bounces ever lower and comes to rest on the
    table at t_inf; the impacts kept and t_inf agree with the reference flight by flight."""
    run = ball_flow.run(table(0.0), 0.0, 0.99, ball_flow.parameters(), dense=True)
    events = run.events
    assert events[0].surface == "table@release"
    assert events[0].t == pytest.approx(release_time(A), abs=1e-12)
    impacts = [e for e in events if e.surface == "table" and e.mode_to == "flight"]
    assert len(impacts) >= 6
    # each impact kept where the reference has it (event location: to about 1e-15 per impact, growing with the
    # impacts' 1/w; the last kept ~1e-13)
    np.testing.assert_allclose([e.t for e in impacts], REF_IMPACTS[: len(impacts)], rtol=0, atol=1e-11)
    assert impacts[0].t == pytest.approx(REF_IMPACTS[0], abs=1e-13)  # the first landing
    # then one event into the stuck mode at the accumulation point, recorded with its accuracy
    (acc,) = run.accumulations
    chatter = events[len(impacts) + 1]
    assert (chatter.mode_from, chatter.mode_to, chatter.surface) == ("flight", "flight@table", "table")
    assert ball_flow.system.transitions[chatter.transition].target == "flight@table"
    assert chatter.t == acc.t and acc.mode == "flight@table" and acc.impacts == len(impacts)
    # the extrapolation's accuracy, plus (t_inf - t_n) r^2 for the contact force's change by r of itself over the
    # tail (N = g - A omega^2 sin(omega t) in closed form)
    tail = acc.t - impacts[-1].t
    drift = A * OMEGA**3 * abs(math.cos(OMEGA * acc.t)) * tail / (G - A * OMEGA**2 * math.sin(OMEGA * acc.t))
    assert tail * drift**2 <= acc.accuracy <= 1e-10 * (acc.t - impacts[0].t) + 64 * np.spacing(acc.t) + tail * drift**2
    assert abs(acc.t - REF_T_INF) <= 2 * acc.accuracy + 1e-15
    assert acc.relative_speed == pytest.approx(impacts[-1].x_plus[1] - table(impacts[-1].t)[1], rel=1e-9)
    # on the table at zero relative velocity there, and with it to the end
    np.testing.assert_allclose(chatter.x_plus, table(acc.t), rtol=0, atol=1e-13)
    np.testing.assert_allclose(acc.x, chatter.x_plus, rtol=0, atol=0)
    assert len(events) == len(impacts) + 2 and run.mode1 == "flight@table"
    np.testing.assert_allclose(run.x1, table(0.99), rtol=0, atol=1e-12)
    # never through the table, on the dense output across the chatter
    t, x = run.sample(16)
    assert np.min(x[:, 0] - A * np.sin(OMEGA * t)) >= -1e-12


def test_the_periodic_orbit_sticks_at_t0_with_both_multipliers_zero(ball_flow):
    """The period-1 orbit: on the table at t = 0 (y = 0, v = A omega), released at t_r, chattering to rest at
    t_inf; the stuck state is fixed by time alone, so the period map forgets everything."""
    orbit = find_periodic_orbit(bouncing_ball(e=E, A=A), [0.0, 0.0])
    assert orbit.period == pytest.approx(1.0, rel=1e-15)
    assert orbit.state0 == pytest.approx([0.0, A * OMEGA], abs=1e-12)
    assert orbit.mode0 == "flight@table"
    assert np.all(np.abs(orbit.multipliers) <= 1e-12)
    assert np.all(np.abs(orbit.monodromy) <= 1e-12)
    (acc,) = orbit.trajectory.accumulations
    assert abs(acc.t - REF_T_INF) <= 2 * acc.accuracy + 1e-15
    release = [e for e in orbit.trajectory.events if e.surface == "table@release"]
    assert len(release) == 1 and release[0].t == pytest.approx(release_time(A), abs=1e-12)


def test_every_period_chatters_to_the_same_phase(ball_flow):
    """Over three periods: an accumulation per period, each one period after the last (the stuck motion
    forgets where the last one was)."""
    run = ball_flow.run(table(0.0), 0.0, 3.0, ball_flow.parameters(), variational=True)
    assert [round(a.t - REF_T_INF) for a in run.accumulations] == [0, 1, 2]
    for k, acc in enumerate(run.accumulations):
        assert abs(acc.t - k - REF_T_INF) <= 2 * acc.accuracy + 4 * np.spacing(3.0)
    assert np.all(run.monodromy == 0.0)


def test_the_sensitivity_to_the_amplitude_after_sticking_is_the_tables():
    """From a state in flight to t = 1.15, stuck to the table (from t_inf to t_r + 1): dx/dA = (sin(omega t),
    omega cos(omega t)) at the end, the derivative of the table's motion (the stuck state depends on A and time
    alone)."""
    flow = Flow(bouncing_ball(e=E, A=A))
    p = flow.parameters()
    x0 = flow.run(table(0.0), 0.0, 0.3, p).x1  # in flight, released at t_r
    run = flow.run(x0, 0.3, 1.15, p, variational=True, sensitivity="A")
    assert run.mode1 == "flight@table" and len(run.accumulations) == 1
    np.testing.assert_allclose(run.parameter_sensitivity, [math.sin(OMEGA * 1.15), OMEGA * math.cos(OMEGA * 1.15)],
                               rtol=0, atol=1e-12)


def test_a_run_that_ends_before_the_accumulation_integrates_the_impacts_left(ball_flow):
    """Ending 1e-5 before t_inf: the impacts up to there one by one, on the reference (the state on the last
    flight in closed form); ending within the last 1e-3 of the chatter's remaining time, where the impacts are
    below the resolution of the state, raises ChatteringError naming the accumulation point."""
    p = ball_flow.parameters()
    t1 = REF_T_INF - 1e-5
    run = ball_flow.run(table(0.0), 0.0, t1, p)
    assert not run.accumulations and run.mode1 == "flight"
    last = max(t for t in REF_IMPACTS if t < t1)
    assert [e.t for e in run.events][-1] == pytest.approx(last, abs=1e-11)
    k = REF_IMPACTS.index(last)
    # the relative velocity after the last impact, then the free flight to t1
    t, w = release_time(A), 0.0
    for tk in REF_IMPACTS[: k + 1]:
        w = -E * _relative_velocity(t, w, tk - t, A)
        t = tk
    tau = t1 - last
    height = tau * _height_over_tau(last, w, tau, A)
    np.testing.assert_allclose(run.x1 - table(t1), [height, _relative_velocity(last, w, tau, A)], rtol=0, atol=1e-9)
    with pytest.raises(ChatteringError, match=r"before the accumulation point t = 0\.4457684773\d* of the impacts on "
                                              r"surface 'table'"):
        ball_flow.run(table(0.0), 0.0, REF_T_INF - 1e-9, p)


# ------------------------------------------------------------------------------ a fixed floor
@pytest.fixture(scope="module")
def floor_flow() -> Flow:
    return Flow(PiecewiseSystem(
        name="ball_rests_after_bouncing", states=["y", "v"], parameters={"g": G, "e": E},
        modes=[Mode("flight", ["v", "-g"])], surfaces={"floor": "y"},
        transitions=[Transition("flight", "floor", Crossing.FALLING, "flight", reset=["y", "-e*v"], sticks=True)]))


def _floor_rest(height: float, e: float) -> tuple[float, float]:
    t1 = math.sqrt(2 * height / G)
    v1 = G * t1
    return t1, t1 + 2 * v1 / G * e / (1 - e)


@settings(max_examples=25, deadline=None)
@given(height=st.floats(1e-3, 10.0), e=st.floats(0.05, 0.9))
def test_a_ball_on_a_fixed_floor_comes_to_rest_at_the_closed_form_time_and_stays(floor_flow, height, e):
    """Dropped from rest: impacts at t_1 + (2 v_1 / g)(e + ... + e^k), at rest from t_inf = t_1 + (2 v_1 / g)
    e / (1 - e) on; gravity never lets go (no release).  The flights' intervals are exactly geometric: the
    extrapolation is exact but for rounding."""
    p = floor_flow.parameters({"e": e})
    t1, t_inf = _floor_rest(height, e)
    run = floor_flow.run([height, 0.0], 0.0, 2 * t_inf + 1.0, p, variational=True)
    (acc,) = run.accumulations
    assert abs(acc.t - t_inf) <= 1e-12 * t_inf
    impacts = [ev.t for ev in run.events if ev.mode_to == "flight"]
    expected = t1 + 2 * G * t1 / G * np.cumsum(np.r_[0.0, e ** np.arange(1, len(impacts))])
    np.testing.assert_allclose(impacts, expected, rtol=1e-12)
    assert run.events[-1].mode_to == "flight@floor" and run.events[-1].t == acc.t
    np.testing.assert_allclose(run.x1, [0.0, 0.0], rtol=0, atol=1e-12 * height)
    assert run.mode1 == "flight@floor"
    assert np.all(run.monodromy == 0.0)


def test_a_floor_without_sticking_still_says_where_the_ball_comes_to_rest(oscillator_flow):
    """No sticks=True: the Zeno accumulation is a ChatteringError, which gives the accumulation time (g = 1,
    dropped from 1: 3 sqrt(2)) and the state at rest."""
    p = oscillator_flow.parameters({"w": 0.0, "g": 1.0, "e": 0.5})
    with pytest.raises(ChatteringError, match=r"accumulate \(Zeno\) at t = 4\.2426406\d*.*comes to rest on the "
                                              r"surface, at about x = \[") as info:
        oscillator_flow.run([1.0, 0.0], 0.0, 10.0, p, mode0="ball")
    assert "sticks=True" in str(info.value)


# ------------------------------------------------------------------------------ monodromies through a chatter
def _central_differences(F, x0: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """Richardson's combination of central differences with steps h and h/2 (error O(h^4) plus rounding/h)."""
    J = np.zeros((len(F(x0)), len(x0)))
    for j in range(len(x0)):
        cols = []
        for step in (h, h / 2):
            d = np.zeros(len(x0))
            d[j] = step
            cols.append((F(x0 + d) - F(x0 - d)) / (2 * step))
        J[:, j] = (4 * cols[1] - cols[0]) / 3
    return J


def test_the_monodromy_of_a_ball_beside_a_decoupled_oscillator():
    """The period map from a state in flight: the ball's block 0 (it ends stuck), the oscillator's expm(A T),
    against central differences of the period map too."""
    system = PiecewiseSystem(
        name="ball_on_table_beside_oscillator", states=["y", "v", "q", "u"],
        parameters={"g": G, "e": E, "A": A, "omega": OMEGA, "w0": 3.0},
        modes=[Mode("flight", ["v", "-g", "u", "-w0**2*q"])],
        surfaces={"table": "y - A*sin(omega*t)"},
        transitions=[Transition("flight", "table", Crossing.FALLING, "flight",
                                reset=["y", "(1 + e)*A*omega*cos(omega*t) - e*v", "q", "u"], sticks=True)],
        period="2*pi/omega")
    flow = Flow(system, TIGHT)
    p = flow.parameters()
    t0 = 0.3
    x0 = flow.run([0.0, A * OMEGA, 0.3, -0.2], 0.0, t0, p).x1
    run = flow.run(x0, t0, t0 + 1.0, p, variational=True)
    assert len(run.accumulations) == 1 and run.mode1 == "flight"  # stuck, then released again
    closed = np.zeros((4, 4))
    closed[2:, 2:] = expm(np.array([[0.0, 1.0], [-9.0, 0.0]]))
    np.testing.assert_allclose(run.monodromy, closed, rtol=0, atol=1e-10)
    fd = _central_differences(lambda x: flow.run(x, t0, t0 + 1.0, p).x1, x0)
    np.testing.assert_allclose(run.monodromy, fd, rtol=0, atol=1e-7)


def test_the_monodromy_through_a_coupled_chatter_against_finite_differences():
    """A ball (mass 1) on a table that is a forced mass (4) on a spring: the impacts conserve momentum, the contact
    force acts on both (sticks=[0, 1/m, 0, -1/M]), so the chatter's Jacobian is not trivial.  After 20 periods
    the motion chatters to rest on the table once a period; the period map from a state in flight, and its
    derivative in the forcing amplitude, against central differences.  (The jump's Jacobian is the plastic
    projection at the last impact kept followed by the stuck motion: first order in that impact's relative
    velocity, ~4e-4 here; the differences agree to their own accuracy, ~1e-8.)"""
    system = PiecewiseSystem(
        name="ball_on_spring_table", states=["y", "v", "X", "V"],
        parameters={"g": G, "e": E, "m": 1.0, "M": 4.0, "k": 355.3, "c": 7.54, "F": 61.0, "omega": OMEGA},
        modes=[Mode("flight", ["v", "-g", "V", "(-k*X - c*V + F*cos(omega*t))/M"])],
        surfaces={"table": "y - X"},
        transitions=[Transition("flight", "table", Crossing.FALLING, "flight",
                                reset=["y", "v - (1 + e)*(v - V)*M/(m + M)", "X", "V + (1 + e)*(v - V)*m/(m + M)"],
                                sticks=["0", "1/m", "0", "-1/M"])],
        period="2*pi/omega")
    flow = Flow(system, TIGHT)
    p = flow.parameters()
    settle = flow.run([0.5, 0.0, 0.0, 0.0], 0.0, 20.95, p)
    assert len(settle.accumulations) >= 15 and settle.mode1 == "flight"
    t0, x0 = 20.95, settle.x1
    run = flow.run(x0, t0, t0 + 1.0, p, variational=True, sensitivity="F")
    assert len(run.accumulations) == 1 and run.mode1 == "flight"  # stuck, then released again
    fd = _central_differences(lambda x: flow.run(x, t0, t0 + 1.0, p).x1, x0)
    np.testing.assert_allclose(run.monodromy, fd, rtol=0, atol=1e-7)
    k = system.parameter_index("F")

    def at(value: float) -> np.ndarray:
        q = p.copy()
        q[k] = value
        return flow.run(x0, t0, t0 + 1.0, q).x1

    h = 1e-4
    dF = (4 * (at(61.0 + h / 2) - at(61.0 - h / 2)) / h - (at(61.0 + h) - at(61.0 - h)) / (2 * h)) / 3
    np.testing.assert_allclose(run.parameter_sensitivity, dF, rtol=0, atol=1e-7)


def test_the_chattering_orbit_is_followed_in_the_amplitude():
    """Continuation in A from 0.26 to 0.28: every orbit chatters to rest once a period (the kernel's corrector hands
    the shots that stop at the accumulation to the Python iteration), both multipliers 0 all along, no special
    point.  (Farther on, the number of impacts kept before the jump changes with A, which the event-sequence
    detectors still take for a change of the orbit.)"""
    from saltation import ContinuationSettings, continue_orbit

    start = find_periodic_orbit(bouncing_ball(e=E, A=A), [0.0, 0.0])
    branch = continue_orbit(start, "A", bounds=(0.26, 0.28), directions=(1,),
                            settings=ContinuationSettings(ds=0.005, ds_max=0.01))
    assert branch.points[-1].parameter == pytest.approx(0.28, abs=1e-12)
    assert not branch.special_points
    for point in branch.points:
        assert np.all(np.abs(point.multipliers) <= 1e-12)
        assert point.event_labels[-1] == "flight -[table-]-> flight@table"


# ------------------------------------------------------------------------------ a chatter that ends near its release
@settings(max_examples=6, deadline=None)
@given(amplitude=st.floats(0.39, 0.3968))
def test_a_chatter_that_ends_where_the_table_nearly_lets_go_loses_no_impact(amplitude):
    """Near A = 0.397 the chatter ends just before the release: its last flights are short while the relative
    acceleration ``g - A omega^2 sin(omega t)`` falls towards zero, and within one long step the ball bounces off
    the table and falls back through it while the acceleration changes sign.  Each such short flight must be
    found (a step from the surface that ends on its side, moving away, is searched for a dip), or the ball goes
    through its table.  Over one period from the flight after the release, the impacts, the accumulation point
    and the return to the start against the flights in closed form (``reference_chatter``)."""
    flow = Flow(bouncing_ball(e=E, A=amplitude))
    t_r = release_time(amplitude)
    s, ds = table(t_r, amplitude)
    tau = 0.3  # in the first flight, from rest on the table at the release
    start = np.array([s + ds * tau - G * tau**2 / 2, ds - G * tau])
    run = flow.run(start, t_r + tau, t_r + tau + 1.0, flow.parameters(), dense=True)
    ref_impacts, ref_t_inf = reference_chatter(amplitude)
    impacts = [e.t for e in run.events if e.surface == "table" and e.mode_to == "flight"]
    assert len(impacts) >= 6
    # event location to about 1e-15 per impact, growing with the impacts' 1/w to ~1e-11 for the last kept
    np.testing.assert_allclose(impacts, ref_impacts[: len(impacts)], rtol=0, atol=1e-10)
    (acc,) = run.accumulations
    # the reference's tail after w < 1e-8: 2 w / ((1 - e) a), to about 1e-12 here
    assert abs(acc.t - ref_t_inf) <= 2 * acc.accuracy + 1e-11
    assert [e.surface for e in run.events[len(impacts) + 1:]] == ["table@release"]
    np.testing.assert_allclose(run.x1, start, rtol=0, atol=1e-9)  # the period-1 orbit: back where it started
    t, x = run.sample(16)
    assert np.min(x[:, 0] - amplitude * np.sin(OMEGA * t)) >= -1e-12  # never through the table


def stick_length(amplitude: float) -> float | None:
    """The stuck phase of the period-1 orbit that sticks, from the flights in closed form: from rest on the table at
    the release ``t_r``, flight by flight to a relative velocity of 1e-13 and the tail ``2 w / ((1 - e) a)``; the
    phase lasts from that accumulation point to the next release, ``t_r + 1``.  None where the impacts escape
    (the table's deceleration reaches ``g`` first): no such orbit."""
    t_r = release_time(amplitude)
    t, w = t_r, 0.0
    while True:
        try:
            tau = _flight(t, w, amplitude)
        except ValueError:  # the flight does not come back where a bounce of its size would: it escapes
            return None
        w = -E * _relative_velocity(t, w, tau, amplitude)
        t += tau
        decel = G - amplitude * OMEGA**2 * math.sin(OMEGA * t)
        if not decel > 0 or t > t_r + 1:
            return None
        if w < 1e-13:
            rest = t_r + 1 - (t + 2 * w / ((1 - E) * decel))
            return rest if rest > 0 else None


def sticking_ends() -> float:
    """Where the stuck phase vanishes (the chatter's accumulation point reaches the release), by bisection on the
    existence of the orbit that sticks; the stuck phase there shrinks steeply, about like ``(A* - A)^0.6``."""
    lo, hi = 0.3965, 0.3975
    assert stick_length(lo) is not None and stick_length(hi) is None
    while hi - lo > 1e-13:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stick_length(mid) is not None else (lo, mid)
    return 0.5 * (lo + hi)


def test_the_sticking_branch_ends_where_the_chatter_reaches_the_release():
    """e = 0.5: along A the stuck phase shrinks, and vanishes where the accumulation point reaches the release
    (A* = 0.39692553514 from the flights in closed form).  Beyond it the impacts escape before they accumulate
    (the relative acceleration vanishes during the tail, which the jump to the accumulation point refuses), and
    a cascade of grazings follows, each impact of the chatter in turn.  The branch's first special point is that
    end, located within its accuracy of the reference, with multipliers 0 on the sticking side."""
    from saltation import ContinuationSettings, continue_orbit

    a_star = sticking_ends()
    amplitude = 0.3965
    t_r = release_time(amplitude)
    s, ds = table(t_r, amplitude)
    tau = 0.3
    start = find_periodic_orbit(bouncing_ball(e=E, A=amplitude), [s + ds * tau - G * tau**2 / 2, ds - G * tau],
                                t0=t_r + tau)
    branch = continue_orbit(start, "A", bounds=(amplitude, a_star + 1e-8), directions=(1,),
                            settings=ContinuationSettings(ds=0.0002, ds_max=0.0002))
    end = branch.special_points[0]
    assert end.parameter <= min(sp.parameter for sp in branch.special_points)
    lo, hi = end.bracket
    assert lo <= end.parameter <= hi
    assert abs(end.parameter - a_star) <= end.accuracy + 1e-12
    assert np.all(np.abs(end.one_sided.multipliers_minus) <= 1e-10)  # the sticking side
    assert np.all(np.abs(end.one_sided.multipliers_plus) < 1)
    for p in branch.points:
        length = stick_length(p.parameter)
        if p.parameter < end.parameter - end.accuracy:  # it sticks: the stuck phase against the reference
            assert length is not None and np.all(np.abs(p.multipliers) <= 1e-10)
            t_release = release_time(p.parameter)
            events = find_periodic_orbit(bouncing_ball(e=E, A=p.parameter), p.state, t0=p.t0).trajectory.events
            (landing,) = [e.t for e in events if e.mode_to == "flight@table"]
            stuck = (t_release - landing) % 1.0
            assert stuck == pytest.approx(length, abs=1e-9)
        elif p.parameter > end.parameter + end.accuracy:
            assert length is None
            assert not any("table@release" in label for label in p.event_labels)
