"""Lyapunov exponents through the saltation matrices (saltation.orbits.lyapunov), against closed forms and
against the Floquet multipliers of periodic orbits (a second method, through the same saltation matrices
but by the eigenvalues of the monodromy matrix)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition
from saltation.errors import ModelError
from saltation.orbits.lyapunov import lyapunov_exponents
from saltation.orbits.shooting import find_periodic_orbit


def _within(value: float, expected: float, accuracy: float, slack: float = 1e-6) -> bool:
    """The exponent agrees with the reference to three times its stated accuracy (plus a slack for the
    integration's own error over the run)."""
    return abs(value - expected) <= 3.0 * accuracy + slack


def test_a_damped_linear_oscillator_has_its_eigenvalues_real_part_twice(trilinear_flow):
    """The trilinear system below the contact is linear: x'' + c x' + k x = f: both exponents are
    Re(lambda) = -c / (2 m) = -0.025 (a complex pair of eigenvalues)."""
    result = lyapunov_exponents(trilinear_flow, [0.1, 0.0], parameters={"omega": 0.7}, time=600.0, transient=100.0)
    assert result.exponents.shape == (2,)
    for e, a in zip(result.exponents, result.accuracy):
        assert 0 < a < 1e-3
        assert _within(e, -0.025, a)


def hopf(mu: float = 0.25) -> PiecewiseSystem:
    """The Hopf normal form in two modes split by the line y = 0 (the same field): its cycle of radius sqrt(mu)
    crosses the line twice a period (saltation matrices of identity); Lyapunov exponents 0 and -2 mu."""
    field = ["mu*x - y - x*(x**2 + y**2)", "x + mu*y - y*(x**2 + y**2)"]
    return PiecewiseSystem(
        "test_lyapunov_hopf", states=["x", "y"], parameters={"mu": mu},
        modes=[Mode("upper", field, domain=["y >= 0"]), Mode("lower", field, domain=["y < 0"])],
        surfaces={"axis": "y"},
        transitions=[Transition("upper", "axis", Crossing.FALLING, "lower"),
                     Transition("lower", "axis", Crossing.RISING, "upper")],
    )


def test_an_autonomous_cycle_has_a_zero_exponent_and_its_radial_contraction():
    result = lyapunov_exponents(Flow(hopf()), [0.5, 0.0], time=400.0, transient=40.0)
    (zero, radial), (a0, a1) = result.exponents, result.accuracy
    assert _within(zero, 0.0, a0, 1e-4)  # (the phase direction: its estimate decays like 1/time)
    assert _within(radial, -0.5, a1, 1e-4)


def sliding_relay() -> PiecewiseSystem:
    """x' = -sgn(x), y' = -y: both fields push into x = 0, where a Filippov sliding motion starts in finite time
    (its saltation matrix maps the x direction onto the surface): exponents -1 (y) and -inf (x)."""
    return PiecewiseSystem(
        "test_lyapunov_sliding_relay", states=["x", "y"], parameters={"a": 1.0},
        modes=[Mode("right", ["-a", "-y"], domain=["x > 0"]), Mode("left", ["a", "-y"], domain=["x <= 0"])],
        surfaces={"s": "x"},
        transitions=[Transition("right", "s", Crossing.FALLING, "left"),
                     Transition("left", "s", Crossing.RISING, "right")],
    )


def test_a_sliding_motion_collapses_a_direction_to_minus_infinity():
    result = lyapunov_exponents(Flow(sliding_relay()), [0.5, 1.0], time=20.0)
    assert result.exponents[0] == pytest.approx(-1.0, abs=3 * result.accuracy[0] + 1e-6)
    assert result.exponents[1] == -math.inf and result.accuracy[1] == 0.0
    assert "-inf" in repr(result)


def test_an_impacting_orbit_has_the_exponents_of_its_floquet_multipliers():
    """A periodic orbit with impacts (resets): the exponents are ln|mu_i| / T of the multipliers of its monodromy
    matrix, both through the saltation matrices of the impacts."""
    from saltation.models import impact_oscillator

    flow = Flow(impact_oscillator())
    values = {"s": 1.2, "omega": 0.8}
    orbit = find_periodic_orbit(flow, parameters=values)
    assert orbit.events and orbit.stable  # it impacts, once a period, and attracts
    reference = np.sort(np.log(np.abs(orbit.multipliers)) / orbit.period)[::-1]
    # the impact's restitution is in them: without it the free oscillator's would be -zeta = -0.05
    assert np.all(reference < -0.06)
    result = lyapunov_exponents(flow, orbit.state0, parameters=values, time=300 * orbit.period)
    for e, a, ref in zip(result.exponents, result.accuracy, reference):
        assert _within(e, ref, a, 1e-5)


def test_bad_input_is_named(trilinear_flow):
    with pytest.raises(ModelError, match="time must be positive"):
        lyapunov_exponents(trilinear_flow, [0.0, 0.0], time=0.0)
    with pytest.raises(ModelError, match="2 components"):
        lyapunov_exponents(trilinear_flow, [0.0], time=1.0)
    with pytest.raises(ModelError, match="blocks"):
        lyapunov_exponents(trilinear_flow, [0.0, 0.0], time=1.0, blocks=1)
    # a transient longer than any integration's step budget is refused before it runs (it ran to the step limit)
    period = trilinear_flow.system.forcing_period(trilinear_flow.parameters())
    with pytest.raises(ModelError, match=r"transient = .* is 1e\+07 times the forcing period"):
        lyapunov_exponents(trilinear_flow, [0.0, 0.0], time=100 * period, transient=1e7 * period)


def test_the_command_prints_the_exponents_as_json(capsys):
    from saltation.apps import cli

    assert cli.main(["lyapunov", "trilinear", "--set", "omega=0.7", "--time", "300", "--transient", "100",
                     "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {"model", "exponents", "accuracy", "time"} <= set(out)
    assert out["model"] == "trilinear" and out["time"] == 300.0
    for e, a in zip(out["exponents"], out["accuracy"]):
        assert _within(e, -0.025, a)


def test_a_sweep_records_the_largest_exponent_and_reads_it_back(tmp_path):
    """``sweep(..., lyapunov=True)``: without contact (omega = 1.4, 1.5) the response is the linear one, largest
    exponent -c / (2 m); where the orbit touches the supports it is ln|mu_1| / T of the orbit found by shooting
    (a second method). Files keep it; files without it read as None."""
    from saltation.apps.sweeps import SweepResult, period_map, sweep
    from saltation.models import trilinear

    values = np.array([1.2, 1.4, 1.5])
    result = sweep(trilinear(), "omega", values, periods=40, transient=300, workers=1, lyapunov=True)
    lam = result.largest_exponents
    flow = Flow(trilinear())
    orbit = find_periodic_orbit(flow, result.at(0)[-1], parameters={"omega": 1.2})
    assert orbit.stable
    assert lam[0] == pytest.approx(np.log(np.max(np.abs(orbit.multipliers))) / orbit.period, abs=2e-3)
    np.testing.assert_allclose(lam[1:], -0.025, atol=1e-3)  # (over 40 periods: the QR's oscillation, about 1/time)
    back = SweepResult.load(result.save(tmp_path / "s.json"))
    np.testing.assert_array_equal(back.largest_exponents, lam)
    d = result.to_dict()
    del d["largest_exponents"]
    assert SweepResult.from_dict(d).largest_exponents is None
    assert len(result.plot().axes) == 2  # the diagram over its exponent
    grid = period_map(trilinear(), "omega", [1.4, 1.5], "f0", [0.1, 0.15], periods=20, transient=300, workers=1,
                      lyapunov=True)
    assert grid.largest_exponents.shape == (2, 2)
    np.testing.assert_allclose(grid.largest_exponents, -0.025, atol=2e-3)


def test_a_filippov_orbit_has_the_exponents_of_its_floquet_multipliers():
    """The friction oscillator's stick-slip orbit slides once a period: one multiplier is 0 (the sliding start's
    saltation matrix is singular), the other ln|mu| / T; the exponents are -inf and that one."""
    from saltation.models import friction_oscillator

    flow = Flow(friction_oscillator())
    orbit = find_periodic_orbit(flow)
    assert any(e.kind.name == "SLIDING_START" for e in orbit.events)
    mu = np.sort(np.abs(orbit.multipliers))[::-1]
    # M = Phi S Phi with S of rank one: its second eigenvalue is 0, computed to the rounding of the products and of
    # the eigenvalue solver, some eps |M| per operation (5.55e-17 with one BLAS kernel, 0.0 with another)
    assert mu[1] <= 1e3 * np.finfo(float).eps * max(1.0, np.linalg.norm(orbit.monodromy))
    result = lyapunov_exponents(flow, orbit.state0, time=100 * orbit.period)
    assert _within(result.exponents[0], math.log(mu[0]) / orbit.period, result.accuracy[0])
    assert result.exponents[1] == -math.inf


def test_the_exponents_add_up_to_the_divergence_and_the_saltation_determinants():
    """Liouville's formula through the events: the exponents sum to the time average of div f plus
    sum ln|det S| per unit time.  The impact oscillator's field has div f = -2 zeta; its impact (h = x - s, v -> -r v)
    has S = [[-r, 0], [(f+_v + r f-_v) / v, -r]] by eq. (9), det S = r^2; its stable orbit at s = 1.2, omega = 0.8
    impacts once a forcing period: -2 zeta + 2 ln(r) omega / (2 pi).  The sum
    is kept exactly by the QR steps (ln|det| of each interval), so only rounding over the run separates them."""
    from saltation.models import impact_oscillator

    system = impact_oscillator()
    flow = Flow(system)
    values = {"s": 1.2, "omega": 0.8}
    orbit = find_periodic_orbit(flow, parameters=values)
    assert len(orbit.events) == 1
    result = lyapunov_exponents(flow, orbit.state0, parameters=values, time=200 * orbit.period)
    zeta, r = system.defaults["zeta"], system.defaults["r"]
    expected = -2 * zeta + 2 * math.log(r) * values["omega"] / (2 * math.pi)
    assert result.exponents.sum() == pytest.approx(expected, abs=1e-9)


def test_a_strongly_damped_direction_has_a_finite_exponent():
    """x' = -40 x, y' = -y (two modes split by y = 0, the same field): over one time unit the x direction contracts
    by e^-39 against y, past what one QR step resolves; with no singular saltation matrix there, the interval is
    cut into pieces and the exponents are -1 and -40 (not -inf)."""
    field = ["-40*x", "-y"]
    system = PiecewiseSystem(
        "test_lyapunov_stiff", states=["x", "y"], parameters={"k": 1.0},
        modes=[Mode("upper", field, domain=["y >= 0"]), Mode("lower", field, domain=["y < 0"])],
        surfaces={"axis": "y"},
        transitions=[Transition("upper", "axis", Crossing.FALLING, "lower"),
                     Transition("lower", "axis", Crossing.RISING, "upper")],
    )
    result = lyapunov_exponents(Flow(system), [1.0, 1.0], time=20.0)
    np.testing.assert_allclose(result.exponents, [-1.0, -40.0], rtol=0, atol=1e-6)
