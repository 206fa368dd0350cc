"""Sliding bifurcations of the forced friction oscillator x'' + 2 zeta x' + x = -F sgn(x' - v_b) + a cos(w t),
against independent computations (closed-form flows of the two slip modes, brentq and fsolve).

* grazing-sliding: the slower-than-belt harmonic response x = F + A cos(w t - phi) reaches the velocity
  A w at its fastest, so it grazes the sliding surface x' = v_b at v_b = A w;
* switching-sliding: the sticking orbit in closed form. It arrives at the surface at (t_e, x_e), sticks
  (x = x_e + v_b (t - t_e)) until the slower side's field turns tangent
  (-2 zeta v_b - x + F + a cos(w t) = 0), then moves as the linear oscillator with the force +F
  (closed form by the eigenvectors of A) until x' = v_b again. Periodicity plus the condition
  -2 zeta v_b - x_e - F + a cos(w t_e) = 0 (the faster side's field tangent where the orbit
  arrives; that tangency is invisible from the faster side), solved by fsolve for (t_e, x_e, v_b);
* crossing-sliding: the orbit that slips both ways. It arrives from the faster side at (t_1, x_1) exactly
  where the slower side's field is tangent (-2 zeta v_b - x_1 + F + a cos(w t_1) = 0, a tangency
  visible from the slower side), slips slower until x' = v_b, then faster until it is back at
  (t_1 + T, x_1); fsolve for (t_1, x_1, v_b);
* adding-sliding (continued in F at v_b = 0.2): the sticking motion x = x* + v_b (t - tau) touches the
  boundary of the sticking region where the faster side's field has a cubic tangency:
  2 zeta v_b + x + F - a cos(w t) = 0 and its rate v_b + a w sin(w t) = 0, so tau =
  (2 pi - arcsin(v_b / (a w))) / w and x* = a cos(w tau) - F - 2 zeta v_b in closed form. From there
  the orbit sticks until the slower side's field turns tangent, slips slower until x' = v_b and sticks
  until tau + T; brentq on F for x(tau + T) = x*.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq, fsolve

from saltation import Flow
from saltation.branches.branch import SpecialPointKind
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.special_points.loci import follow_locus
from saltation.models import friction_oscillator
from saltation.models.friction_oscillator import DEFAULTS
from saltation.orbits.shooting import ShootingProblem

ZETA, F, AF, W = (DEFAULTS[k] for k in ("zeta", "F", "a", "omega"))
T = 2 * np.pi / W
A = np.array([[0.0, 1.0], [-1.0, -2 * ZETA]])
D = (1 - W**2) ** 2 + (2 * ZETA * W) ** 2
AMPLITUDE = AF / np.sqrt(D)
V_GRAZING_SLIDING = AMPLITUDE * W
EIGENVALUES, EIGENVECTORS = np.linalg.eig(A)
EIGENVECTORS_INV = np.linalg.inv(EIGENVECTORS)


def slip_response(t, sign=1.0, friction=F):
    """The particular solution of x'' + 2 zeta x' + x = sign F + a cos(w t) (sign +1: slower than the belt)."""
    t = np.asarray(t, dtype=float)
    c, s = AF * (1 - W**2) / D, AF * 2 * ZETA * W / D
    return np.array([sign * friction + c * np.cos(W * t) + s * np.sin(W * t), W * (-c * np.sin(W * t) + s * np.cos(W * t))])


def slip_flow(y, t_from, ts, sign=1.0, friction=F):
    """A slip mode's flow from (t_from, y) at the times ts, shape (len(ts), 2)."""
    tau = np.asarray(ts) - t_from
    E = np.einsum("ij,mj,jk->mik", EIGENVECTORS, np.exp(np.outer(tau, EIGENVALUES)), EIGENVECTORS_INV).real
    return slip_response(ts, sign, friction).T + E @ (np.asarray(y) - slip_response(t_from, sign, friction))


def return_to_belt(y, t_from, v_b, sign, rising, friction=F, span=T):
    """The first time after t_from where a slip mode's velocity returns to v_b (rising or falling), and x there."""
    ts = t_from + np.linspace(1e-9, span, 4001)
    v = slip_flow(y, t_from, ts, sign, friction)[:, 1] - v_b
    k = np.nonzero((v[:-1] < 0) & (v[1:] >= 0) if rising else (v[:-1] > 0) & (v[1:] <= 0))[0][0]
    t_h = brentq(lambda t: slip_flow(y, t_from, [t], sign, friction)[0, 1] - v_b, ts[k], ts[k + 1],
                 xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return t_h, slip_flow(y, t_from, [t_h], sign, friction)[0, 0]


def sticking_orbit_residual(z):
    t_e, x_e, v_b = z
    slower_field = lambda t: -2 * ZETA * v_b - (x_e + v_b * (t - t_e)) + F + AF * np.cos(W * t)  # noqa: E731
    t_x = brentq(slower_field, t_e, t_e + T, xtol=1e-15, rtol=4 * np.finfo(float).eps)  # sticking ends
    t_h, x_h = return_to_belt([x_e + v_b * (t_x - t_e), v_b], t_x, v_b, sign=1.0, rising=True)
    faster_field = -2 * ZETA * v_b - x_e - F + AF * np.cos(W * t_e)
    return [t_h - t_e - T, x_h - x_e, faster_field]


def two_slip_orbit_residual(z, friction=F):
    """The orbit that arrives from the faster side where the slower side's field is tangent (crossing-sliding)."""
    t_1, x_1, v_b = z
    t_2, x_2 = return_to_belt([x_1, v_b], t_1, v_b, sign=1.0, rising=True, friction=friction)
    t_3, x_3 = return_to_belt([x_2, v_b], t_2, v_b, sign=-1.0, rising=False, friction=friction)
    slower_field = -2 * ZETA * v_b - x_1 + friction + AF * np.cos(W * t_1)
    return [t_3 - t_1 - T, x_3 - x_1, slower_field]


V_ADDING = 0.2


def touch_time(v_b):
    """Where the faster side's field has its cubic tangency on a sticking motion (rate v_b + a w sin(w t) = 0)."""
    return (2 * np.pi - np.arcsin(v_b / (AF * W))) / W


TAU_ADDING = touch_time(V_ADDING)


def adding_sliding_residual(friction, v_b=V_ADDING):
    """x(tau + T) - x* of the orbit through the cubic tangency at tau (see the module's docstring)."""
    tau = touch_time(v_b)
    x_star = AF * np.cos(W * tau) - friction - 2 * ZETA * v_b
    slower_field = lambda t: -2 * ZETA * v_b - (x_star + v_b * (t - tau)) + friction + AF * np.cos(W * t)  # noqa: E731
    ts = tau + np.linspace(1e-6, T, 4001)
    k = np.nonzero(slower_field(ts) <= 0)[0][0]
    t_x = brentq(slower_field, ts[k - 1], ts[k], xtol=1e-15, rtol=4 * np.finfo(float).eps)  # sticking ends
    t_a, x_a = return_to_belt([x_star + v_b * (t_x - tau), v_b], t_x, v_b, sign=1.0, rising=True, friction=friction)
    return x_a + v_b * (tau + T - t_a) - x_star


@pytest.fixture(scope="module")
def branch():
    flow = Flow(friction_oscillator())
    phi = np.arctan2(2 * ZETA * W, 1 - W**2)
    x0 = np.array([F + AMPLITUDE * np.cos(-phi), -AMPLITUDE * W * np.sin(-phi)])  # the slower-than-belt response
    problem = ShootingProblem(flow, {"v_b": 2.5}, continuation_parameter="v_b")
    return continue_branch(problem, x0, 2.5, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.85, 2.5)),
                           directions=(-1,)), problem


def test_grazing_sliding_against_closed_form(branch):
    br, problem = branch
    (g,) = [sp for sp in br.special_points if sp.kind is SpecialPointKind.GRAZING_SLIDING]
    assert g.parameter == pytest.approx(V_GRAZING_SLIDING, abs=1e-9)
    assert g.accuracy < 1e-9
    # the side that misses the surface: the linear oscillator's multipliers exp(lambda T)
    free = g.multipliers_minus if "the side with the crossing is 'plus'" in g.note else g.multipliers_plus
    np.testing.assert_allclose(np.sort_complex(free), np.sort_complex(np.exp(EIGENVALUES * T)), rtol=0, atol=1e-10)
    # the sliding side: a sliding motion on a line in the plane forgets one direction
    sliding = g.multipliers_plus if "the side with the crossing is 'plus'" in g.note else g.multipliers_minus
    assert np.min(np.abs(sliding)) < 1e-12


def test_switching_sliding_against_independent_computation(branch):
    br, problem = branch
    (c,) = [sp for sp in br.special_points if sp.kind is SpecialPointKind.SWITCHING_SLIDING]
    traj = problem.flow.run(c.state, 0.0, T, problem.parameters_at(c.parameter))
    start = next(e for e in traj.events if e.kind.name in ("SLIDING_START", "TRANSITION"))
    z = fsolve(sticking_orbit_residual, [start.t, start.x_minus[0], c.parameter], xtol=1e-14)
    assert np.abs(sticking_orbit_residual(z)).max() < 1e-12
    # the reference is exact to ~1e-13 (closed forms and brentq); the located point claims 1e-9 or better
    assert c.accuracy < 1e-9
    assert c.parameter == pytest.approx(z[2], abs=1e-9)
    assert "field of 'slip_plus' is tangent to it, invisible" in c.note


def test_crossing_sliding_against_independent_computation(branch):
    br, problem = branch
    (c,) = [sp for sp in br.special_points if sp.kind is SpecialPointKind.CROSSING_SLIDING]
    traj = problem.flow.run(c.state, 0.0, T, problem.parameters_at(c.parameter))
    arrival = next(e for e in traj.events if e.mode_from == "slip_plus")
    z = fsolve(two_slip_orbit_residual, [arrival.t, arrival.x_minus[0], c.parameter], xtol=1e-14)
    assert np.abs(two_slip_orbit_residual(z)).max() < 1e-12
    assert c.accuracy < 1e-9
    assert c.parameter == pytest.approx(z[2], abs=1e-9)
    assert "field of 'slip_minus' is tangent to it, visible" in c.note
    # one side crosses into the slower mode, the other sticks for a moment and leaves into it
    sides = {c.event_labels_minus, c.event_labels_plus}
    assert ("slip_plus -[v_rel-]-> slip_minus", "slip_minus -[v_rel+]-> slip_plus") in sides


@pytest.fixture(scope="module")
def adding():
    """The stick-slip orbit continued in F at v_b = 0.2, through its adding-sliding."""
    flow = Flow(friction_oscillator(v_b=V_ADDING, F=1.0))
    problem = ShootingProblem(flow, {"F": 1.0}, continuation_parameter="F")
    x = np.array([0.0, V_ADDING])
    for _ in range(100):  # the stable stick-slip orbit
        x = flow.run(x, 0.0, T, problem.parameters_at(1.0)).x1
    br = continue_branch(problem, x, 1.0, settings=ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(0.85, 1.0)),
                         directions=(-1,))
    return br, problem


def test_adding_sliding_against_closed_form(adding):
    """The sticking motion splits in two where it touches the boundary of the sticking region (a cubic
    tangency of the faster side's field)."""
    br, _ = adding
    (a,) = [sp for sp in br.special_points if sp.kind is SpecialPointKind.ADDING_SLIDING]
    reference = brentq(adding_sliding_residual, 0.89, 0.91, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    assert abs(adding_sliding_residual(reference)) < 1e-12
    assert a.accuracy < 1e-9
    assert a.parameter == pytest.approx(reference, abs=1e-9)
    assert f"t = {TAU_ADDING:.10g}" in a.note
    # the side with the extra events has a second sticking motion
    assert sorted(len(ev) for ev in (a.event_labels_minus, a.event_labels_plus)) == [2, 4]
    assert (a.touch_surface, a.touch_mode) == ("v_rel", "slip_plus")
    assert a.touch_time == pytest.approx(TAU_ADDING, abs=1e-9)


def test_adding_sliding_curve_against_closed_form(adding):
    """The adding-sliding continued in (F, v_b) by its defining system: every curve point against the
    closed-form construction at that v_b (brentq in F)."""
    br, problem = adding
    (a,) = [sp for sp in br.special_points if sp.kind is SpecialPointKind.ADDING_SLIDING]
    locus = follow_locus(problem, a, "v_b", (0.12, 0.3), settings=ContinuationSettings(ds=0.01, ds_max=0.02))
    assert locus.values[:, 1].min() == pytest.approx(0.12) and locus.values[:, 1].max() == pytest.approx(0.3)
    for friction, v_b in locus.values[::6]:
        reference = brentq(adding_sliding_residual, friction - 0.01, friction + 0.01, args=(v_b,), xtol=1e-15,
                           rtol=4 * np.finfo(float).eps)
        assert friction == pytest.approx(reference, abs=1e-9)


# fsolve starts from the located event, often already a root to rounding: "not making good progress" then
# says it cannot improve it, and the residual is checked below
@pytest.mark.filterwarnings("ignore:The iteration is not making good progress:RuntimeWarning")
def test_crossing_sliding_curve_against_independent_computation(branch):
    """The crossing-sliding continued in (v_b, F): every few curve points against fsolve on the closed-form
    two-slip orbit at that F."""
    br, problem = branch
    (c,) = [sp for sp in br.special_points if sp.kind is SpecialPointKind.CROSSING_SLIDING]
    locus = follow_locus(problem, c, "F", (0.45, 0.55), settings=ContinuationSettings(ds=0.005, ds_max=0.01))
    assert locus.values[:, 1].min() == pytest.approx(0.45) and locus.values[:, 1].max() == pytest.approx(0.55)
    for (v_b, friction), state in zip(locus.values[::5], locus.states[::5]):
        traj = problem.flow.run(state, 0.0, T, problem.flow.parameters({"v_b": v_b, "F": friction}))
        arrival = next(e for e in traj.events if e.mode_from == "slip_plus")
        z = fsolve(two_slip_orbit_residual, [arrival.t, arrival.x_minus[0], v_b], args=(friction,), xtol=1e-13)
        assert np.abs(two_slip_orbit_residual(z, friction)).max() < 1e-12
        assert v_b == pytest.approx(z[2], abs=1e-9)


def test_grazing_sliding_from_the_sliding_side(branch):
    """Continuing the sticking orbits upwards passes the grazing-sliding onto the non-sticking orbits."""
    br, problem = branch
    last = br.points[-1]
    up = continue_branch(problem, last.state, last.parameter,
                         settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(last.parameter, 2.5)), directions=(1,))
    kinds = {sp.kind for sp in up.special_points}
    assert {SpecialPointKind.GRAZING_SLIDING, SpecialPointKind.SWITCHING_SLIDING, SpecialPointKind.CROSSING_SLIDING} <= kinds
    (g,) = [sp for sp in up.special_points if sp.kind is SpecialPointKind.GRAZING_SLIDING]
    assert g.parameter == pytest.approx(V_GRAZING_SLIDING, abs=1e-9)


# -- the integrator's sliding motions, against the closed form x = x0 + v_b (t - t0) of sticking ---------------
# (the sliding field x' = v_b, v' = 0 is integrated exactly, and events are located to near machine
# precision: 1e-12 in time states what the event location promises)


def first_root(g, a, b, num=20001):
    ts = np.linspace(a, b, num)
    k = np.nonzero(g(ts) <= 0)[0][0]
    return brentq(g, ts[k - 1], ts[k], xtol=1e-15, rtol=4 * np.finfo(float).eps)


@pytest.mark.parametrize("dv", [2e-16, 0.0, -2e-16, 1e-13, -1e-13])
def test_a_start_on_the_sticking_surface_slides(dv):
    """A state on the surface where both fields push into it starts sliding at t0 (the transition fires at
    once) and leaves where the slower side's field turns tangent. (The run used to go on in its start mode
    beyond the surface, or to stop with 'exactly tangent' when it left.)  A state 1e-13 off the surface
    (some 450 rounding units of v, beyond the surface's resolution) is not on it: its field takes it there
    in |dv| / |v'| (|v'| >= 0.7 here), where the sliding motion starts."""
    friction, v_b, x0 = 1.2, 1.05, 1.27134977
    flow = Flow(friction_oscillator(F=friction, v_b=v_b))
    traj = flow.run([x0, v_b + dv], 0.0, 2.0, flow.parameters())
    leave = first_root(lambda t: -2 * ZETA * v_b - (x0 + v_b * t) + friction + AF * np.cos(W * t), 0.0, 2.0)
    assert [e.kind.name for e in traj.events] == ["SLIDING_START", "SLIDING_END"]
    if abs(dv) < 1e-15:
        assert traj.events[0].t == 0.0
    else:
        assert 0.0 < traj.events[0].t <= abs(dv) / 0.7
    assert traj.events[1].t == pytest.approx(leave, abs=1e-12)
    assert traj.events[1].mode_to == "slip_minus"


def test_a_sliding_exit_inside_a_long_step_is_found():
    """The sticking field is so simple that its steps could span the forcing period, while the exit function
    dips below zero and recovers: the first exit is the one found (it used to be the second, a period later)."""
    friction, v_b, x0 = 1.3, 0.05, 0.4517736162663617
    flow = Flow(friction_oscillator(F=friction, v_b=v_b))
    traj = flow.run([x0, v_b], 0.0, 2 * T, flow.parameters())
    leave = first_root(lambda t: -2 * ZETA * v_b - (x0 + v_b * t) + friction + AF * np.cos(W * t), 0.0, T)
    assert traj.events[1].kind.name == "SLIDING_END"
    assert traj.events[1].t == pytest.approx(leave, abs=1e-12)


def test_a_shallow_dip_of_the_exit_function_is_found():
    """Just past an adding-sliding: the sticking motion dips 1e-6 below the boundary of its region for
    about 4e-3 in time (far less than a step); the orbit leaves there and sticks again at once."""
    friction, depth = 0.9, 1e-6
    x_tau = AF * np.cos(W * TAU_ADDING) - friction - 2 * ZETA * V_ADDING - depth  # the faster side's g = -depth
    flow = Flow(friction_oscillator(F=friction, v_b=V_ADDING))
    traj = flow.run([x_tau - V_ADDING, V_ADDING], TAU_ADDING - 1.0, TAU_ADDING + 1.0, flow.parameters())
    g_faster = lambda t: 2 * ZETA * V_ADDING + x_tau + V_ADDING * (t - TAU_ADDING) + friction - AF * np.cos(W * t)  # noqa: E731
    leave = first_root(g_faster, TAU_ADDING - 0.1, TAU_ADDING)
    assert [e.kind.name for e in traj.events[:3]] == ["SLIDING_START", "SLIDING_END", "SLIDING_START"]
    assert traj.events[1].mode_to == "slip_plus" and traj.events[2].mode_from == "slip_plus"
    assert traj.events[1].t == pytest.approx(leave, abs=1e-12)
    assert TAU_ADDING < traj.events[2].t < TAU_ADDING + 0.01
