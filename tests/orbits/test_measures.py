"""Measures of orbits and monitors along branches, against the closed form of a forced linear oscillator.

Below its contact (``|x| < x_c``) the trilinear system is ``m x'' + c x' + k x = f0 sin(omega t)``, whose periodic
orbit is ``x = A sin(omega t - phi)`` with ``A = f0 / sqrt((k - m omega^2)^2 + (c omega)^2)``: ``max |x| = A``,
``max x - min x = 2 A``, ``max sqrt(x^2 + v^2) = A max(1, omega)`` (``v = A omega cos(...)``), and the monitor
``amplitude = a`` is met where ``(k - m omega^2)^2 + (c omega)^2 = (f0 / a)^2``, a quadratic in ``omega^2``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation.apps import cli
from saltation.branches.branch import SpecialPointKind, SpecialPointStatus, StopReason
from saltation.branches.monitors import Monitor
from saltation.errors import ModelError
from saltation.models.trilinear import DEFAULTS as TRI
from saltation.models.trilinear import linear_response_state
from saltation.orbits.measures import Measure, measure_orbit, measure_state, parse_measures
from saltation.orbits.start import find_periodic_orbit
from saltation.special_points.continuation import ContinuationSettings, continue_orbit

M, C, K, F0 = (TRI[k] for k in ("m", "c", "k", "f0"))
#: the steady state is shot to a residual of 1e-10 and integrated with rtol 1e-10: its extremes hold to about
#: 1e-9 relative; the dense output's own error (DOP853's interpolant) is smaller still
RTOL = 1e-8


def amplitude(w: float) -> float:
    return F0 / math.sqrt((K - M * w**2) ** 2 + (C * w) ** 2)


def frequency_of(a: float) -> float:
    """The lower frequency where the linear response's amplitude is ``a`` (below the resonance)."""
    b = (C**2 - 2 * K * M) / M**2
    c = (K**2 - (F0 / a) ** 2) / M**2
    return math.sqrt((-b - math.sqrt(b * b - 4 * c)) / 2)


@settings(max_examples=12, deadline=None)
@given(st.floats(0.3, 0.85))
def test_measures_of_the_linear_response_against_its_closed_form(trilinear_flow, w):
    params = dict(TRI, omega=w)
    orbit = find_periodic_orbit(trilinear_flow, linear_response_state(params), parameters={"omega": w})
    p = trilinear_flow.parameters({"omega": w})
    measures = parse_measures(["x", "ptp:x", "norm", "sqrt(x**2 + v**2)", "min:x", "section:v", "max:omega*x"],
                              trilinear_flow.system)
    got = measure_orbit(trilinear_flow, orbit.state0, orbit.period, p, measures, t0=orbit.t0, mode0=orbit.mode0)
    a = amplitude(w)
    assert got["x"] == pytest.approx(a, rel=RTOL)
    assert got["ptp:x"] == pytest.approx(2 * a, rel=RTOL)
    assert got["norm"] == pytest.approx(a * max(1.0, w), rel=RTOL)
    assert got["sqrt(x**2 + v**2)"] == pytest.approx(got["norm"], rel=RTOL)
    assert got["min:x"] == pytest.approx(-a, rel=RTOL)
    assert got["max:omega*x"] == pytest.approx(w * a, rel=RTOL)
    assert got["section:v"] == orbit.state0[1]  # the state at the section itself, exactly


def test_an_equilibrium_measures_its_state():
    from saltation.models import trilinear

    system = trilinear()
    x = np.array([0.3, -0.4])
    p = system.parameter_vector({})
    got = measure_state(x, p, parse_measures(["x", "ptp:v", "norm", "section:v", "x + k*v"], system))
    assert got == {"x": 0.3, "ptp:v": 0.0, "norm": 0.5, "section:v": -0.4, "x + k*v": pytest.approx(0.3 - 0.4 * K)}


@pytest.mark.parametrize(("text", "problem"), [
    ("ptp:y", "'y' is not a state of the model (states: x, v)"),
    ("section:", "'' is not a state"),
    ("sqrt(x**2 + y**2)", "'y' is not a state, a parameter or t"),
    ("x +* v", "does not parse"),
])
def test_a_measure_that_names_nothing_of_the_model_is_refused(text, problem):
    from saltation.models import trilinear

    with pytest.raises(ModelError) as info:
        Measure.parse(text, trilinear())
    assert str(info.value).startswith(f"measure {text!r}") and problem in str(info.value)


@pytest.fixture(scope="module")
def monitored(trilinear_flow):
    orbit = find_periodic_orbit(trilinear_flow, linear_response_state(dict(TRI, omega=0.6)), parameters={"omega": 0.6})
    settings = ContinuationSettings(bounds=(0.6, 0.88), measures=("ptp:x",),
                                    monitors=("amplitude = 0.5", "norm = 0.6",
                                              Monitor("period = 8", lambda point: point.period - 8.0)))
    return continue_orbit(orbit, "omega", bounds=(0.6, 0.88), directions=(1,), settings=settings)


def test_monitors_are_located_where_the_closed_form_meets_them(monitored):
    branch = monitored
    found = {sp.note.split(":")[0]: sp for sp in branch.special_points if sp.kind is SpecialPointKind.MONITOR}
    assert set(found) == {"monitor amplitude = 0.5", "monitor norm = 0.6", "monitor period = 8"}
    # located to locate_tol 1e-9 in (u, lam); the amplitude itself is known to ~1e-9 (RTOL), so the frequency
    # where it reaches a value to ~1e-9 / |dA/domega| (|dA/domega| > 1 here)
    for name, a in (("monitor amplitude = 0.5", 0.5), ("monitor norm = 0.6", 0.6)):
        sp = found[name]
        assert sp.status is SpecialPointStatus.LOCATED
        assert sp.bracket[0] <= sp.parameter <= sp.bracket[1]
        assert sp.parameter == pytest.approx(frequency_of(a), abs=1e-8)
    assert found["monitor period = 8"].parameter == pytest.approx(2 * math.pi / 8, abs=1e-9)
    # every point records the measures it was asked for, and those the monitors read
    assert branch.measures == ("ptp:x", "norm")
    np.testing.assert_allclose(branch.measure("ptp:x"), 2 * np.array([amplitude(w) for w in branch.parameter]),
                               rtol=RTOL)
    assert branch.check().ok


def test_a_monitor_that_stops_ends_the_run_past_it(trilinear_flow):
    orbit = find_periodic_orbit(trilinear_flow, linear_response_state(dict(TRI, omega=0.6)), parameters={"omega": 0.6})
    stop = Monitor.parse("x = 0.5", trilinear_flow.system, "omega", stop=True)
    branch = continue_orbit(orbit, "omega", bounds=(0.6, 1.6), directions=(1,),
                            settings=ContinuationSettings(bounds=(0.6, 1.6), monitors=(stop,)))
    (sp,) = branch.special_points
    assert branch.stop_reason is StopReason.MONITOR
    assert sp.parameter == pytest.approx(frequency_of(0.5), abs=1e-8)
    assert branch.parameter[-2] <= sp.parameter <= branch.parameter[-1]  # the run ends with the step that met it


def test_a_monitor_of_nothing_in_the_record_is_refused():
    from saltation.models import trilinear

    with pytest.raises(ModelError, match="monitor 'zz = 1'.*neither an expression of the record's numbers"):
        Monitor.parse("zz = 1", trilinear(), "omega")
    with pytest.raises(ModelError, match="a side of '=' is empty"):
        Monitor.parse("amplitude =", trilinear(), "omega")


def test_the_command_line_measures_an_orbit_and_monitors_a_branch(tmp_path, capsys):
    w = 0.7
    assert cli.main(["orbit", "trilinear", "--set", f"omega={w}", "--x0", "0.5,0.5", "--measure", "norm",
                     "--measure", "ptp:x", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["measures"]["norm"] == pytest.approx(amplitude(w), rel=RTOL)
    assert record["measures"]["ptp:x"] == pytest.approx(2 * amplitude(w), rel=RTOL)
    assert cli.main(["continue", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.85", "--measure",
                     "ptp:x", "--monitor", "ptp:x = 1", "--stop-at-monitor", "--out", str(tmp_path),
                     "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "stopped: a monitor that stops the branch reached its value" in out
    (record,) = json.loads((tmp_path / "trilinear_omega_special_points.json").read_text())
    assert record["kind"] == "monitor" and record["value"] == pytest.approx(frequency_of(0.5), abs=1e-8)
    branch = json.loads((tmp_path / "trilinear_omega_branch.json").read_text())
    assert branch["measures"] == ["ptp:x"] and "ptp:x" in branch["points"][0]["measures"]
    assert cli.main(["continue", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.85", "--monitor",
                     "y = 1", "--out", str(tmp_path), "--no-progress"]) == 2
    assert "--monitor: monitor 'y = 1'" in capsys.readouterr().err
