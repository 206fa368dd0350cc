"""Brute-force diagrams (saltation.apps.sweeps) against closed forms and periodic orbits."""

from __future__ import annotations

import json

import numpy as np
import pytest
from matplotlib.figure import Figure

from saltation import ModelError, Tolerances
from saltation.models import block_on_belt, trilinear
from saltation.apps.sweeps import SweepResult, sweep

M, C, K, F0 = 1.0, 0.05, 1.0, 0.2  # Appendix A


def harmonic_state(w: float) -> np.ndarray:
    """``(x(0), x'(0))`` of the steady response of ``m x'' + c x' + k x = f0 sin(w t)``."""
    det = (K - M * w**2) ** 2 + (C * w) ** 2
    return np.array([-F0 * C * w / det, F0 * (K - M * w**2) * w / det])


def harmonic_amplitude(w: float) -> float:
    return F0 / np.sqrt((K - M * w**2) ** 2 + (C * w) ** 2)


NO_CONTACT = np.array([0.6, 0.65, 0.7, 1.5, 1.55, 1.6])  # amplitude < x_c = 1


@pytest.fixture(scope="module")
def no_contact_sweep(trilinear_flow):
    # 300 transient periods: the free oscillation decays like exp(-c t / 2m), below 1e-10 after t ~ 920
    return sweep(trilinear(), "omega", NO_CONTACT, periods=5, transient=300, x0=harmonic_state(0.6), workers=2)


def test_poincare_points_are_the_harmonic_response(no_contact_sweep):
    res = no_contact_sweep
    assert res.section == "poincare" and res.failures == ()
    np.testing.assert_array_equal(res.values, NO_CONTACT)
    np.testing.assert_array_equal(res.counts, 5)
    assert res.states.shape == (30, 2) and res.parameter_points.shape == (30,)
    np.testing.assert_array_equal(res.parameter_points, np.repeat(NO_CONTACT, 5))
    for i, w in enumerate(NO_CONTACT):
        np.testing.assert_allclose(res.at(i), np.tile(harmonic_state(w), (5, 1)), rtol=0, atol=1e-8)
    lam, x = res.points()
    np.testing.assert_array_equal(x, res.x)
    np.testing.assert_array_equal(res.points("v")[1], res.states[:, 1])


def test_poincare_points_are_the_periodic_orbit(trilinear_flow, no_contact_sweep):
    from saltation.orbits.shooting import find_periodic_orbit

    for i in (0, 4):
        w = NO_CONTACT[i]
        orb = find_periodic_orbit(trilinear_flow, no_contact_sweep.at(i)[-1], parameters={"omega": w})
        np.testing.assert_allclose(no_contact_sweep.at(i), np.tile(orb.state0, (5, 1)), rtol=0, atol=1e-8)


def test_one_worker_gives_the_same_points(no_contact_sweep):
    serial = sweep(trilinear(), "omega", NO_CONTACT, periods=5, transient=300, x0=harmonic_state(0.6), workers=1)
    # the chunks differ (one chunk continues through all values), so the transients differ a little
    np.testing.assert_allclose(serial.states, no_contact_sweep.states, rtol=0, atol=1e-8)


def test_contact_orbit_section_points_repeat(trilinear_flow, contact_orbit):
    """At omega = 1.0 (contact with both supports) the section points are the shooting orbit's state."""
    res = sweep(trilinear(), "omega", [1.0], periods=4, transient=100, x0=contact_orbit.state0 + 1e-3, workers=1)
    np.testing.assert_allclose(res.states, np.tile(contact_orbit.state0, (4, 1)), rtol=0, atol=1e-8)


def test_maxima_of_a_forced_system(no_contact_sweep):
    ws = NO_CONTACT[:3]
    res = sweep(trilinear(), "omega", ws, periods=4, transient=300, x0=harmonic_state(0.6), poincare=False, workers=1)
    assert res.section == "maxima"
    np.testing.assert_array_equal(res.counts, 4)  # one maximum per forcing period
    for i, w in enumerate(ws):
        pts = res.at(i)
        np.testing.assert_allclose(pts[:, 0], harmonic_amplitude(w), rtol=0, atol=1e-9)
        np.testing.assert_allclose(pts[:, 1], 0.0, atol=1e-6)  # x' = 0 at a maximum of x


def test_maxima_of_an_autonomous_system(stable_cycle):
    """Block-on-belt at v_dr = 1: the maxima of x are the stick-slip cycle's; beyond the fold, the equilibrium."""
    system = block_on_belt()
    res = sweep(system, "v_dr", [1.0], periods=20, transient=10, x0=stable_cycle.state0, workers=1)
    assert res.section == "maxima" and res.settings["period"] == pytest.approx(2 * np.pi)
    pts = res.at(0)
    assert len(pts) >= 15  # the cycle's period is about 6.4
    np.testing.assert_allclose(pts[:, 0], stable_cycle.trajectory.x_max[0], rtol=0, atol=1e-6)
    eq = sweep(system, "v_dr", [1.3], periods=5, transient=100, x0=[1.0, 0.01], workers=1)
    np.testing.assert_array_equal(eq.counts, [1])  # no oscillation: the final state, once
    np.testing.assert_allclose(eq.states[0], [1.0, 0.0], atol=1e-6)  # F_slip / k


def test_failures_are_recorded_and_the_sweep_goes_on():
    tight = Tolerances(max_steps=50)
    res = sweep(trilinear(), "omega", [0.6, 0.7], periods=2, transient=10, workers=1, tolerances=tight)
    assert res.counts.tolist() == [0, 0] and res.states.shape == (0, 2)
    assert [v for v, _ in res.failures] == [0.6, 0.7]
    assert "max_steps" in res.failures[0][1]


def test_bad_input():
    with pytest.raises(ModelError, match="unknown parameter 'omegaa'"):
        sweep(trilinear(), "omegaa", [1.0])
    with pytest.raises(ValueError, match="at least one"):
        sweep(trilinear(), "omega", [])
    with pytest.raises(ModelError, match="x0 must have 2 components"):
        sweep(trilinear(), "omega", [1.0], x0=[0.0])
    with pytest.raises(ValueError, match="periods"):
        sweep(trilinear(), "omega", [1.0], periods=0)


def test_save_and_load(tmp_path, no_contact_sweep):
    res = no_contact_sweep
    path = res.save(tmp_path / "sweep.json")
    back = SweepResult.load(path)
    np.testing.assert_array_equal(back.states, res.states)
    np.testing.assert_array_equal(back.parameter_points, res.parameter_points)
    np.testing.assert_array_equal(back.counts, res.counts)
    assert (back.model, back.parameter_name, back.section, back.state_names) == ("trilinear", "omega", "poincare", ("x", "v"))
    assert json.loads(path.read_text())["settings"]["transient"] == 300

    csv_path = res.save(tmp_path / "sweep.csv")
    rows = csv_path.read_text().splitlines()
    assert rows[0] == "omega,x,v" and len(rows) == 1 + len(res.states)
    table = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table[:, 0], res.parameter_points)
    np.testing.assert_array_equal(table[:, 1:], res.states)


def test_plot_leaves_no_pyplot_state(no_contact_sweep):
    import matplotlib.pyplot as plt

    before = plt.get_fignums()
    fig = no_contact_sweep.plot()
    assert isinstance(fig, Figure) and plt.get_fignums() == before
    ax = fig.axes[0]
    assert ax.get_xlabel() == "omega" and "Poincare" in ax.get_ylabel()
    offsets = ax.collections[0].get_offsets()
    np.testing.assert_array_equal(np.asarray(offsets)[:, 0], no_contact_sweep.parameter_points)
    other = Figure()
    ax2 = other.add_subplot()
    assert no_contact_sweep.plot(ax2, state="v") is other


def test_workers_started_by_spawn_load_the_kernels_from_disk(monkeypatch, no_contact_sweep):
    """Where fork is not available, fresh worker processes re-load the compiled kernels from the cache."""
    import multiprocessing

    import saltation.sweeps.parallel as sweep_module

    monkeypatch.setattr(sweep_module, "_context", lambda: multiprocessing.get_context("spawn"))
    res = sweep(trilinear(), "omega", NO_CONTACT, periods=5, transient=300, x0=harmonic_state(0.6), workers=2)
    np.testing.assert_allclose(res.states, no_contact_sweep.states, rtol=0, atol=1e-12)
