"""Monodromy matrices and parameter sensitivities against central finite differences.

The reference re-integrates the period map without variational equations at tight
tolerances (rtol 1e-13) and differences it with step ``h``: its error is about
``h^2 |P'''| + rtol / h``, i.e. ~1e-9 for ``h = 1e-5``.  The variational monodromy
is computed at the library's default tolerances (rtol 1e-10).  A missing or wrong
saltation matrix changes the monodromy by O(0.1).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import TIGHT, central_difference_jacobian, unstable_orbit

FD_STEP = 1e-5
FD_RTOL = 1e-7  # relative to the largest entry; measured 2e-10 ... 3e-9


def _assert_close_relative(actual, expected, rtol):
    scale = np.max(np.abs(expected))
    err = np.max(np.abs(np.asarray(actual) - np.asarray(expected)))
    assert err <= rtol * scale, f"max error {err:.3e} > {rtol:.1e} * {scale:.3e}\n{actual}\nvs\n{expected}"


def _period_map(flow, p, t0, t1):
    return lambda x0: flow.run(x0, t0, t1, p, tolerances=TIGHT).x1


# ----------------------------------------------------------------- trilinear, forced
def test_contact_orbit_monodromy_forward(trilinear_flow, contact_orbit):
    orb = contact_orbit
    assert len(orb.trajectory.events) == 4
    fd = central_difference_jacobian(_period_map(trilinear_flow, orb.parameters, 0.0, orb.period), orb.state0, FD_STEP)
    _assert_close_relative(orb.monodromy, fd, FD_RTOL)


def test_contact_orbit_monodromy_backward(trilinear_flow, contact_orbit):
    """Backward time, from T to 0 (the same four surfaces, crossed the other way)."""
    orb = contact_orbit
    T = orb.period
    back = trilinear_flow.run(orb.state0, T, 0.0, orb.parameters, variational=True)
    assert len(back.events) == 4
    np.testing.assert_allclose(back.x1, orb.state0, atol=1e-8)
    fd = central_difference_jacobian(_period_map(trilinear_flow, orb.parameters, T, 0.0), orb.state0, FD_STEP)
    _assert_close_relative(back.monodromy, fd, FD_RTOL)
    # one period backward undoes one period forward
    np.testing.assert_allclose(back.monodromy @ orb.monodromy, np.eye(2), atol=1e-8)


def test_contact_orbit_liouville(contact_orbit):
    """det Phi = exp(int div f dt) prod det S_i; div f = -c/m free, -(c + c_f)/m in contact."""
    orb = contact_orbit
    names = orb.trajectory.system.parameter_names
    pv = dict(zip(names, orb.parameters))
    m, c, c_f = pv["m"], pv["c"], pv["c_f"]
    events = orb.trajectory.events
    # durations per mode from the event times (the orbit starts and ends in 'free')
    assert orb.trajectory.mode0 == "free" and orb.trajectory.mode1 == "free"
    in_contact = sum(b.t - a.t for a, b in zip(events[0::2], events[1::2]))
    assert all(a.mode_to.startswith("contact") and b.mode_to == "free" for a, b in zip(events[0::2], events[1::2]))
    integral = -c / m * orb.period - c_f / m * in_contact
    det_s = np.prod([np.linalg.det(e.saltation) for e in events])
    assert det_s == pytest.approx(1.0, abs=1e-12)  # det S_1a = det S_1b = 1 (eqs. 11-14)
    assert np.linalg.det(orb.monodromy) == pytest.approx(np.exp(integral) * det_s, rel=1e-9)


@pytest.mark.parametrize("name", ["x_c", "c_f", "k_f", "omega"])
def test_trilinear_parameter_sensitivity(trilinear_flow, contact_orbit, name):
    """d x(T) / d p at fixed times; x_c enters indicators and guards, omega the forcing."""
    orb = contact_orbit
    idx = trilinear_flow.system.parameter_index(name)
    traj = trilinear_flow.run(orb.state0, 0.0, orb.period, orb.parameters, variational=True, sensitivity=idx)

    def end_state(pk):
        p = orb.parameters.copy()
        p[idx] = pk[0]
        return trilinear_flow.run(orb.state0, 0.0, orb.period, p, tolerances=TIGHT).x1

    fd = central_difference_jacobian(end_state, [orb.parameters[idx]], 1e-6)[:, 0]
    _assert_close_relative(traj.parameter_sensitivity, fd, 1e-6)


def test_forward_backward_round_trip(trilinear_flow):
    """Forward over two periods, then backward from the end: back to x0 through the same events reversed."""
    p = trilinear_flow.parameters({"omega": 1.0})
    T = 2 * np.pi
    x0 = np.array([0.3, 1.5])
    fwd = trilinear_flow.run(x0, 0.0, 2 * T, p, variational=True)
    back = trilinear_flow.run(fwd.x1, 2 * T, 0.0, p, variational=True, mode0=fwd.mode1)
    assert len(fwd.events) >= 4
    np.testing.assert_allclose(back.x1, x0, atol=1e-8)
    assert back.mode1 == fwd.mode0
    assert [e.surface for e in back.events] == [e.surface for e in reversed(fwd.events)]
    assert [(e.mode_from, e.mode_to) for e in back.events] == [(e.mode_to, e.mode_from) for e in reversed(fwd.events)]
    np.testing.assert_allclose([e.t for e in back.events], [e.t for e in reversed(fwd.events)], atol=1e-9)
    for eb, ef in zip(back.events, reversed(fwd.events)):
        np.testing.assert_allclose(eb.saltation @ ef.saltation, np.eye(2), atol=1e-9)
    np.testing.assert_allclose(back.monodromy @ fwd.monodromy, np.eye(2), atol=1e-8)


# ----------------------------------------------------------------- block on belt, autonomous
def test_stick_slip_monodromy(belt_flow, stable_cycle):
    orb = stable_cycle
    assert [e.surface for e in orb.trajectory.events] == ["band_lower", "stick_upper"]
    fd = central_difference_jacobian(_period_map(belt_flow, orb.parameters, 0.0, orb.period), orb.state0, FD_STEP)
    _assert_close_relative(orb.monodromy, fd, FD_RTOL)


def test_stick_slip_liouville(stable_cycle):
    """det Phi = exp(int div f) prod det S: div f = -sqrt(k/m) in stick, -c/m in slip.

    det Phi is the non-trivial multiplier; it is ~5e-5 and comes from entries of size ~1,
    so it is compared in absolute terms at the accuracy of the entries.
    """
    orb = stable_cycle
    pv = dict(zip(orb.trajectory.system.parameter_names, orb.parameters))
    into, out = orb.trajectory.events
    assert (into.mode_to, out.mode_from) == ("stick", "stick")
    t_stick = out.t - into.t
    integral = -np.sqrt(pv["k"] / pv["m"]) * t_stick - pv["c"] / pv["m"] * (orb.period - t_stick)
    # det S by hand: slip -> stick eta w / a-, a- the slip acceleration at the band edge
    a_minus = (-pv["k"] * into.x_minus[0] - pv["c"] * (pv["v_dr"] - pv["eta"]) + pv["F_slip"]) / pv["m"]
    det_alpha = pv["eta"] * np.sqrt(pv["k"] / pv["m"]) / a_minus
    expected = np.exp(integral) * det_alpha * np.linalg.det(out.saltation)
    assert np.linalg.det(into.saltation) == pytest.approx(det_alpha, rel=1e-10)
    assert np.linalg.det(orb.monodromy) == pytest.approx(expected, abs=1e-9)
    assert np.abs(orb.multipliers).min() == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("name", ["F_stick", "v_dr", "c"])
def test_stick_slip_parameter_sensitivity(belt_flow, stable_cycle, name):
    """F_stick enters the stick boundary (the indicator), v_dr every field and the band."""
    orb = stable_cycle
    idx = belt_flow.system.parameter_index(name)
    traj = belt_flow.run(orb.state0, 0.0, orb.period, orb.parameters, variational=True, sensitivity=idx)

    def end_state(pk):
        p = orb.parameters.copy()
        p[idx] = pk[0]
        return belt_flow.run(orb.state0, 0.0, orb.period, p, tolerances=TIGHT).x1

    fd = central_difference_jacobian(end_state, [orb.parameters[idx]], 1e-6)[:, 0]
    _assert_close_relative(traj.parameter_sensitivity, fd, 1e-6)


@pytest.fixture(scope="module")
def unstable_cycles(belt_flow, unstable_cycle):
    return {1e-4: unstable_cycle} | {eta: unstable_orbit(belt_flow, eta=eta) for eta in (1e-5, 1e-6)}


@pytest.mark.parametrize("eta", [1e-4, 1e-5, 1e-6])
def test_unstable_cycle_monodromy_backward(belt_flow, unstable_cycles, eta):
    """Backward time through the attraction sliding mode along the border of D.

    The paper takes eta "very small in numerical calculations"; eta = 1e-5 and 1e-6
    are parameter values of the same compiled model.
    """
    orb = unstable_cycles[eta]
    assert orb.backward
    assert orb.parameters[belt_flow.system.parameter_index("eta")] == eta
    fd = central_difference_jacobian(_period_map(belt_flow, orb.parameters, 0.0, -orb.period), orb.state0, FD_STEP)
    _assert_close_relative(orb.monodromy, fd, FD_RTOL)
    assert abs(np.linalg.det(orb.monodromy)) < 1e-12  # singular: the sliding start forgets


@pytest.mark.parametrize("name", ["v_dr", "F_slip", "c"])
def test_unstable_cycle_parameter_sensitivity(belt_flow, unstable_cycle, name):
    """Parameter sensitivity through a sliding motion (the sliding field depends on p)."""
    orb = unstable_cycle
    idx = belt_flow.system.parameter_index(name)
    traj = belt_flow.run(orb.state0, 0.0, -orb.period, orb.parameters, variational=True, sensitivity=idx)

    def end_state(pk):
        p = orb.parameters.copy()
        p[idx] = pk[0]
        return belt_flow.run(orb.state0, 0.0, -orb.period, p, tolerances=TIGHT).x1

    fd = central_difference_jacobian(end_state, [orb.parameters[idx]], 1e-6)[:, 0]
    _assert_close_relative(traj.parameter_sensitivity, fd, 1e-6)
