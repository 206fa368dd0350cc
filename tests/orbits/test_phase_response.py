"""Phase response curves of hybrid limit cycles (:mod:`saltation.orbits.phase_response`).

References, none of them the library's adjoint:

* the leaky integrate-and-fire neuron ``v' = I - v``, ``v -> 0`` at ``v = 1``, in closed form: its period
  ``T = ln(I / (I - 1))`` and PRC ``Z = 1 / (I - v(t))`` (time units), ``1 / (I - 1)`` before the reset and
  ``1 / I`` after it; the PRC's parameter derivative by central differences of that closed form;
* the Izhikevich neuron (``tests/literature/models/izhikevich.py``, regular spiking, ``I = 10``): the shift of
  its asymptotic phase under kicks ``+- eps e_j`` measured by scipy's ``solve_ivp`` with its own events and
  resets (no saltation matrix), central differences with Richardson's extrapolation;
* the shipped relay feedback system, crossing (``sigma = 0.5``) and sliding (``sigma = 0.03``): the same
  differences, the kicked states integrated by the library's event-driven flow at rtol 1e-13 over 40 periods
  (the state alone: no variational equation, no saltation matrix), the phase read off the time of the last
  event of the kind chosen as the marker.
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from saltation import (
    Crossing,
    EventKind,
    Flow,
    Mode,
    PiecewiseSystem,
    ShootingProblem,
    Tolerances,
    Transition,
    find_periodic_orbit,
)
from saltation.errors import InconsistentResultError, ModelError
from saltation.models import relay_feedback
from saltation.orbits.phase_response import (
    PhaseResponse,
    phase_response,
    phase_response_sensitivity,
)

sys.path[:0] = [str(Path(__file__).parents[1] / "literature" / "models"), str(Path(__file__).parents[1] / "literature")]

import izhikevich

TIGHT = Tolerances(rtol=1e-13, atol=1e-15)


# -- the leaky integrate-and-fire neuron, in closed form -------------------------------------------------------

def lif_model() -> PiecewiseSystem:
    return PiecewiseSystem(
        name="test_lif",
        states=["v"],
        parameters={"I": 2.0},
        modes=[Mode("sub", ["I - v"])],
        surfaces={"th": "v - 1"},
        transitions=[Transition("sub", "th", Crossing.RISING, "sub", reset=["0"])],
    )


@pytest.fixture(scope="module")
def lif_flow() -> Flow:
    return Flow(lif_model())


def lif_orbit(flow: Flow, I: float, v0: float):
    T = np.log(I / (I - 1.0))
    return find_periodic_orbit(flow, [v0], period=1.02 * T, parameters={"I": I})


def lif_z(I: float, v0: float, t: np.ndarray) -> tuple[np.ndarray, float]:
    """The closed form: ``Z = 1 / (I - v(t))`` from ``v(0) = v0``, and the reset's time."""
    t_reset = np.log((I - v0) / (I - 1.0))
    v = np.where(t < t_reset, I - (I - v0) * np.exp(-t), I - I * np.exp(-(t - t_reset)))
    return 1.0 / (I - v), float(t_reset)


@given(I=st.floats(1.05, 50.0), v0=st.floats(0.05, 0.95), points=st.integers(20, 60),
       probe=st.lists(st.floats(0.0, 0.999999), min_size=1, max_size=5))
def test_lif_closed_form(lif_flow, I, v0, points, probe):
    orbit = lif_orbit(lif_flow, I, v0)
    T = np.log(I / (I - 1.0))
    assert orbit.period == pytest.approx(T, rel=1e-9)
    prc = phase_response(orbit, points=points)
    x0 = float(orbit.state0[0])
    exact, t_reset = lif_z(I, x0, prc.phases * T)
    away = np.abs(prc.phases * T - t_reset) > 1e-9  # (a point at the reset: either side, within rounding)
    # Newton leaves the period and the state to ~1e-10, which moves Z = e^t / I by as much relatively
    np.testing.assert_allclose(prc.values[away, 0], exact[away], rtol=1e-8)
    np.testing.assert_allclose(prc.values[:, 0] * (I - prc.states[:, 0]), 1.0, rtol=1e-12)
    assert prc.event_phases == pytest.approx([t_reset / T], abs=1e-9)
    np.testing.assert_allclose(prc.before[:, 0], [1.0 / (I - 1.0)], rtol=1e-9)
    np.testing.assert_allclose(prc.after[:, 0], [1.0 / I], rtol=1e-9)
    assert prc.normalisation_residual < 1e-10 and prc.periodicity_residual < 1e-10
    # between the points: cubic Hermite with the adjoint's derivatives, h^4 Z'''' / 384 with h <= T / 20 <= 0.16
    phases = np.array(probe)
    want, _ = lif_z(I, x0, phases * T)
    np.testing.assert_allclose(prc.at(phases)[:, 0], want, rtol=2e-6)
    np.testing.assert_allclose(prc(phases[0]), [want[0]], rtol=2e-6)


@pytest.mark.parametrize("v0", [1.0, 1.0 - 1e-13, 1e-14])
def test_lif_orbit_that_starts_at_its_reset(lif_flow, v0):
    """An orbit whose state lies on the threshold (its shot logs the reset at its start), just below it (the reset
    an instant after the start) or just after the reset (the reset at the end): one reset a period, and the PRC
    of the closed form, its value at phase 0 the one just after the reset."""
    I = 2.0
    problem = ShootingProblem(lif_flow, {"I": I})
    u = np.array([v0, np.log(I / (I - 1.0))])
    orbit = problem.orbit(u, None, problem.evaluate(u, None, need_lam=False).trajectory, [0.0])
    prc = phase_response(orbit, points=8)
    np.testing.assert_allclose(prc.values[:, 0] * (I - prc.states[:, 0]), 1.0, rtol=1e-12)
    assert len(prc.event_phases) == 1
    np.testing.assert_allclose([prc.before[0, 0], prc.after[0, 0]], [1.0 / (I - 1.0), 1.0 / I], rtol=1e-9)
    np.testing.assert_allclose(prc.at(0.0), [1.0 / I], rtol=1e-9)


def test_lif_parameter_derivative(lif_flow):
    """dZ/dI at fixed phases (phase 0 at v = v0, the section through the orbit's state) against central
    differences of the closed form at h = 1e-6 (their error ~1e-11), and dT/dI = -1 / (I (I - 1))."""
    I = 2.0
    orbit = lif_orbit(lif_flow, I, 0.5)
    x0 = float(orbit.state0[0])
    found = phase_response_sensitivity(orbit, "I", points=10)
    h = 1e-6

    def closed(J):
        return lif_z(J, x0, found.phases * np.log(J / (J - 1.0)))[0]

    want = (closed(I + h) - closed(I - h)) / (2 * h)
    np.testing.assert_allclose(found.derivative[:, 0], want, rtol=1e-8, atol=1e-9)
    assert np.all(np.abs(found.derivative[:, 0] - want) <= found.error[:, 0] + 1e-9)
    assert found.period_derivative == pytest.approx(-1.0 / (I * (I - 1.0)), rel=1e-8)
    np.testing.assert_allclose(found.response.values[:, 0], closed(I), rtol=1e-8)
    # a phase that the reset's phase crosses between I - 2h and I + 2h has no derivative there
    event = found.response.event_phases[0]
    across = phase_response_sensitivity(orbit, "I", phases=[0.1, event], step=1e-3)
    assert np.isfinite(across.derivative[0]).all() and np.isnan(across.derivative[1]).all()


# -- the Izhikevich neuron against the asymptotic phase of scipy's own integration -------------------------------

@pytest.fixture(scope="module")
def izhikevich_orbit():
    return find_periodic_orbit(Flow(izhikevich.izhikevich()), [-65.0, -5.0], period=40.0)


def _izhikevich_second_spike(q: dict, t: float, x: np.ndarray) -> float:
    """The time of the second apex after ``(t, x)``: solve_ivp (DOP853, rtol 1e-12) to its own event, the reset,
    on to the next apex.  The reset forgets ``v`` and the other multiplier is ~1e-9: after one spike the state is
    on the orbit, so the second spike's time is the asymptotic phase."""
    field = izhikevich._field(q)
    sol = solve_ivp(field, (t, t + 1e4), x, method="DOP853", rtol=1e-12, atol=1e-12, events=izhikevich._apex)
    te, xe = sol.t_events[0][0], sol.y_events[0][0]
    sol = solve_ivp(field, (te, te + 1e4), [q["c"], xe[1] + q["d"]], method="DOP853", rtol=1e-12, atol=1e-12,
                    events=izhikevich._apex)
    return float(sol.t_events[0][0])


def test_izhikevich_against_the_asymptotic_phase(izhikevich_orbit):
    """Z(t_k) at six phases against central differences of the second spike's time under kicks of v (eps = 1e-2)
    and u (1e-3), Richardson with 2 eps (error ~eps^4): agreement measured 1.1e-9 of the larger component at
    worst, asserted to 1e-7."""
    q = dict(izhikevich.DEFAULTS)
    prc = phase_response(izhikevich_orbit, points=6)
    assert prc.event_labels == ("subthreshold -[apex+]-> subthreshold",)
    for k in range(len(prc.phases)):
        x, t = prc.states[k], prc.times[k]
        fd = np.zeros(2)
        for j, eps in enumerate((1e-2, 1e-3)):
            d = {}
            for e in (eps, 2 * eps):
                dx = np.zeros(2)
                dx[j] = e
                d[e] = -(_izhikevich_second_spike(q, t, x + dx) - _izhikevich_second_spike(q, t, x - dx)) / (2 * e)
            fd[j] = (4 * d[eps] - d[2 * eps]) / 3
        np.testing.assert_allclose(prc.values[k], fd, rtol=0, atol=1e-7 * np.abs(fd).max())


def test_izhikevich_normalisation_and_periodicity(izhikevich_orbit):
    """Z^T f = 1 with the field written out here, Z(0) a left eigenvector of the orbit's monodromy for 1, and the
    adjoint's value at the end of the period the one at its start (no event at the seam)."""
    q = dict(izhikevich.DEFAULTS)
    prc = phase_response(izhikevich_orbit, points=40)
    v, u = prc.states.T
    f = np.column_stack([0.04 * v * v + 5 * v + 140 - u + q["I"], q["a"] * (q["b"] * v - u)])
    np.testing.assert_allclose(np.sum(prc.values * f, axis=1), 1.0, rtol=0, atol=1e-9)
    z0 = prc.values[0]
    M = izhikevich_orbit.monodromy
    np.testing.assert_allclose(z0 @ M, z0, rtol=0, atol=1e-9 * np.abs(z0).max())
    np.testing.assert_allclose(prc.at(1.0 - 1e-12), z0, rtol=1e-9)
    assert prc.periodicity_residual < 1e-9 and prc.normalisation_residual < 1e-9 and prc.closure_error < 1e-9
    # the reset forgets v: Z jumps there by S^T, with S = g_x + (f+ - g_x f-) h_x / (h_x f-)
    (vm, um), (vp, up) = (izhikevich_orbit.events[0].x_minus, izhikevich_orbit.events[0].x_plus)
    fm = np.array([0.04 * vm**2 + 5 * vm + 140 - um + q["I"], q["a"] * (q["b"] * vm - um)])
    fp = np.array([0.04 * vp**2 + 5 * vp + 140 - up + q["I"], q["a"] * (q["b"] * vp - up)])
    gx = np.diag([0.0, 1.0])
    S = gx + np.outer(fp - gx @ fm, [1.0, 0.0]) / fm[0]
    np.testing.assert_allclose(prc.before[0], S.T @ prc.after[0], rtol=1e-9)
    # the same PRC whatever the other points of the grid (other pieces)
    alone = phase_response(izhikevich_orbit, phases=[prc.phases[7]])
    np.testing.assert_allclose(alone.values[0], prc.values[7], rtol=1e-9)


def test_izhikevich_period_derivative_is_the_averaged_response(izhikevich_orbit):
    """A constant current I enters v' alone, so dT/dI = -integral over the period of Z_v dt: the PRC (200 points,
    integrated by Gauss-Legendre on each side of the spike through prc.at) against central differences
    (h = 1e-3) of the reference's period (scipy's brentq on the return map).  Measured 9e-9 relative; asserted
    to 1e-7 (the differences' error ~h^2 T'(3) / 6, the interpolation's ~1e-9)."""
    prc = phase_response(izhikevich_orbit, points=200)
    spike = prc.event_phases[0]
    nodes, weights = np.polynomial.legendre.leggauss(100)
    integral = 0.0
    for a, b in ((0.0, spike), (spike, 1.0)):
        integral += 0.5 * (b - a) * np.sum(weights * prc.at(0.5 * (b - a) * nodes + 0.5 * (a + b))[:, 0])
    h = 1e-3
    period = {s: izhikevich.fixed_point(dict(izhikevich.DEFAULTS, I=10.0 + s * h))[1] for s in (-1, 1)}
    assert -integral * prc.period == pytest.approx((period[1] - period[-1]) / (2 * h), rel=1e-7)


# -- the relay feedback system, crossing and sliding, against the asymptotic phase -----------------------------

def _last_marker(flow: Flow, x: np.ndarray, t: float, t_end: float, p: np.ndarray) -> float:
    """The time of the last event into ``u_minus`` (a crossing or the end of a sliding motion) before ``t_end``."""
    run = flow.run(x, t, t_end, p, tolerances=TIGHT)
    return [e.t for e in run.events if e.kind != EventKind.SLIDING_START and e.mode_to == "u_minus"][-1]


def _phase_shift(flow, orbit, t, x, dx):
    """How far a kick ``dx`` at ``(t, x)`` advances the phase: the marker's delay, over 40 periods (the other
    multipliers 0.51 and 0.42 at most: their part has decayed below 1e-11 by then)."""
    t_end = t + 40.5 * orbit.period
    p = orbit.parameters
    return -(_last_marker(flow, x + dx, t, t_end, p) - _last_marker(flow, x, t, t_end, p))


@pytest.mark.parametrize("sigma", [0.5, 0.03])
def test_relay_feedback_against_the_asymptotic_phase(sigma):
    """Central differences (eps = 1e-4, Richardson with 2 eps) of the phase shift at seven points (none on a
    sliding motion): measured 2.7e-8 (crossing) and 8e-9 (sliding orbit) of the largest component, asserted to
    1e-7."""
    flow = Flow(relay_feedback(sigma=sigma))
    orbit = find_periodic_orbit(flow, None, tolerances=TIGHT)
    prc = phase_response(orbit, points=7)
    assert not prc.sliding.any()
    for k in range(len(prc.phases)):
        x, t = prc.states[k], prc.times[k]
        fd = np.zeros(3)
        for j in range(3):
            d = {}
            for eps in (1e-4, 2e-4):
                e = np.zeros(3)
                e[j] = eps
                d[eps] = (_phase_shift(flow, orbit, t, x, e) - _phase_shift(flow, orbit, t, x, -e)) / (2 * eps)
            fd[j] = (4 * d[1e-4] - d[2e-4]) / 3
        np.testing.assert_allclose(prc.values[k], fd, rtol=0, atol=1e-7 * np.abs(fd).max())


def test_relay_feedback_on_its_sliding_motions():
    """At sigma = 0.03 the orbit slides after each switching.  Mid-way along a sliding motion: along the surface
    (x2, x3) by central differences; across it (x1), by one-sided differences from either side (eps = 1e-5,
    Richardson with 2 eps), both equal to Z's x1-component: the motion absorbs a kick from either side along
    f_a - f_b to first order.  Measured 3e-9 along and 6e-7 across (of the largest component); asserted to 1e-7
    and 1e-5 (the kick's return to the surface is located to ~1e-12 in time over a kick of 1e-5).  Just after the
    exit, the kick into the exit mode's side only."""
    flow = Flow(relay_feedback(sigma=0.03))
    orbit = find_periodic_orbit(flow, None, tolerances=TIGHT)
    whole = phase_response(orbit, points=50)
    assert "slide on y (u_plus|u_minus)" in whole.event_labels and whole.sliding.any()
    starts = [ph for ph, label in zip(whole.event_phases, whole.event_labels) if label.startswith("slide")]
    ends = [ph for ph, label in zip(whole.event_phases, whole.event_labels) if label.startswith("leave")]
    # Z is continuous at the start of a sliding motion and jumps (across the surface only) at its end
    for k, label in enumerate(whole.event_labels):
        if label.startswith("slide"):
            np.testing.assert_allclose(whole.before[k], whole.after[k], rtol=1e-12)
        else:
            np.testing.assert_allclose(whole.before[k, 1:], whole.after[k, 1:], rtol=1e-9)
    middle = [0.5 * (a + b) for a, b in zip(sorted(starts), sorted(ends))]
    exit_phase, exit_label = min((ph, label) for ph, label in zip(whole.event_phases, whole.event_labels)
                                 if label.startswith("leave"))
    prc = phase_response(orbit, phases=[*middle, exit_phase + 1e-4])
    assert prc.sliding.sum() == 2
    B = np.array([1.0, -0.06, 1.0])  # (1, -2 sigma, 1): Filippov's field is f_plus - B (1 + x2), u_eq = -x2
    f_s = np.array([flow.vector_field("u_plus", 0.0, x, orbit.parameters) - B * (1.0 + x[1])
                    for x in prc.states[prc.sliding]])
    np.testing.assert_allclose(np.sum(prc.values[prc.sliding] * f_s, axis=1), 1.0, rtol=1e-9)
    for k in range(3):
        x, t = prc.states[k], prc.times[k]
        scale = np.abs(prc.values[k]).max()
        for j in (1, 2):
            d = {}
            for eps in (1e-4, 2e-4):
                e = np.zeros(3)
                e[j] = eps
                d[eps] = (_phase_shift(flow, orbit, t, x, e) - _phase_shift(flow, orbit, t, x, -e)) / (2 * eps)
            assert (4 * d[1e-4] - d[2e-4]) / 3 == pytest.approx(prc.values[k, j], abs=1e-7 * scale)
        # after the exit, only a kick to the exit mode's side (u_minus: x1 > 0): the other side crosses back
        sides = (1.0, -1.0) if prc.sliding[k] else ((1.0,) if exit_label.endswith("u_minus") else (-1.0,))
        for side in sides:
            d = {}
            for eps in (1e-5, 2e-5):
                e = np.array([side * eps, 0.0, 0.0])
                d[eps] = _phase_shift(flow, orbit, t, x, e) / (side * eps)
            assert 2 * d[1e-5] - d[2e-5] == pytest.approx(prc.values[k, 0], abs=1e-5 * scale)


# -- what it refuses --------------------------------------------------------------------------------------------

def test_a_forced_orbit_is_refused(contact_orbit):
    with pytest.raises(ModelError, match="is forced .* no asymptotic phase"):
        phase_response(contact_orbit)


def test_an_orbit_computed_backward_is_refused(unstable_cycle):
    with pytest.raises(ModelError, match="backward time"):
        phase_response(unstable_cycle)


def test_degenerate_orbits_are_refused(izhikevich_orbit):
    orbit = izhikevich_orbit
    with pytest.raises(InconsistentResultError, match="trivial multiplier is not 1"):
        phase_response(replace(orbit, monodromy=0.5 * orbit.monodromy))
    with pytest.raises(ModelError, match="second Floquet multiplier at 1 .* not isolated"):
        phase_response(replace(orbit, monodromy=np.eye(2)))
    with pytest.raises(ModelError, match="not converged"):
        phase_response(replace(orbit, converged=False))
    with pytest.raises(ModelError, match="does not know the problem"):
        phase_response(replace(orbit, problem=None))
    assert isinstance(phase_response(replace(orbit, problem=None), flow=orbit.problem.flow, points=4), PhaseResponse)
    with pytest.raises(ModelError, match="points must be an integer"):
        phase_response(orbit, points=0)
    with pytest.raises(ModelError, match="either points .* or phases"):
        phase_response(orbit, points=4, phases=[0.1])
    with pytest.raises(ModelError, match="phases must be finite"):
        phase_response(orbit, phases=[0.1, float("nan")])
    with pytest.raises(ModelError, match="tol must be"):
        phase_response(orbit, tol=0.0)
    with pytest.raises(ModelError, match="'J'"):
        phase_response_sensitivity(orbit, "J")
    with pytest.raises(ModelError, match="step must be"):
        phase_response_sensitivity(orbit, "I", step=-1.0)


def test_a_result_that_breaks_its_checks_raises(izhikevich_orbit):
    """Loose tolerances for the pieces (rtol 1e-5): the normalisation holds to 3.5e-6 only (measured), and a
    tolerance below that raises."""
    loose = Tolerances(rtol=1e-5, atol=1e-7)
    prc = phase_response(izhikevich_orbit, points=10, tolerances=loose, tol=1e-2)
    assert prc.accuracy > 1e-8
    with pytest.raises(InconsistentResultError, match="breaks its"):
        phase_response(izhikevich_orbit, points=10, tolerances=loose, tol=prc.accuracy / 10)
