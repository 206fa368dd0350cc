"""Sections of a sweep (saltation.sweeps.sections) against closed forms.

* The linear undamped oscillator ``x'' = -w^2 x`` (``conftest.oscillator_system``, ``g = 0``), started at
  ``x = 0`` with ``v = R w``: it crosses ``x = 0`` upwards at ``(0, R w)`` and downwards at ``(0, -R w)``,
  and its wall ``x = a`` (a surface without reset) at ``(a, +-w sqrt(R^2 - a^2))``, once each way per
  period ``2 pi / w``.
* The Hopf normal form (``tests/orbits/test_lyapunov.py``): its cycle of radius ``sqrt(mu)`` turns once per
  ``2 pi`` counterclockwise, crossing ``x = 0`` downwards at ``(0, sqrt(mu))`` and the surface ``y = 0``
  upwards at ``(sqrt(mu), 0)``.
* The buck converter below ``E = V_ref + V_L / a`` stays ON at its equilibrium ``(E / R, E)``: the clock
  ``tau = 1`` ends every ramp period there.
* The ball on the vibrating table: its period-1 orbit hits the table at the phase ``phi`` with
  ``cos(phi) = (1 - e) pi g / ((1 + e) A omega^2)``, arriving with ``v- = -g T / 2``.
* The trilinear system without contact: the clock ``sin(omega t)`` rises through zero at ``t = 2 pi k /
  omega``, where the state is the harmonic response (the stroboscopic section of tests/sweeps/test_sweep.py).
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import oscillator_system
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import Crossing
from saltation.apps import cli
from saltation.errors import ModelError
from saltation.models import bouncing_ball, buck_converter, trilinear
from saltation.output.codecs import sweep_from_dict, sweep_to_dict
from saltation.output.io import FileFormatError, load_sweep, save_sweep
from saltation.output.plotting import plot_sweep
from saltation.sweeps import Section, parse_section, sweep

sys.path.insert(0, str(Path(__file__).parents[1] / "orbits"))
from test_lyapunov import hopf  # noqa: E402 (the Hopf normal form in two modes: the same model, the same kernels)

A_WALL = 0.5  # the oscillator's wall x = a (its default)




def oscillator_sweep(ws, R, section, direction=None, periods=4, transient=1, **kw):
    """Each value from ``(0, R w)``: on its own orbit of amplitude ``R`` from the start."""
    return sweep(oscillator_system(), "w", ws, section=section, direction=direction, periods=periods,
                 transient=transient, x0=lambda p: [0.0, R * p["w"]], start="own", workers=1, **kw)


# -- the linear oscillator ---------------------------------------------------------------------------------
def test_crossings_of_an_expression_are_at_the_closed_form_states():
    ws, R = np.array([0.7, 1.0, 2.5]), 0.8
    up = oscillator_sweep(ws, R, "x", +1)
    down = oscillator_sweep(ws, R, "x", -1)
    assert (up.section, down.section) == ("expr:x:rising", "expr:x:falling")
    assert up.failures == () and up.counts.tolist() == [4, 4, 4] and down.counts.tolist() == [4, 4, 4]
    for i, w in enumerate(ws):
        np.testing.assert_allclose(up.at(i), np.tile([0.0, R * w], (4, 1)), rtol=0, atol=1e-9)
        np.testing.assert_allclose(down.at(i), np.tile([0.0, -R * w], (4, 1)), rtol=0, atol=1e-9)
    # either way: they alternate; the start x = 0 itself is no crossing, so the first is downwards
    both = oscillator_sweep(ws[:1], R, "x", 0, periods=5, transient=0)
    assert both.section == "expr:x:either"
    np.testing.assert_allclose(both.states[:, 1], R * ws[0] * np.array([-1, 1, -1, 1, -1]), rtol=0, atol=1e-9)
    # an expression's default direction is rising
    assert oscillator_sweep(ws[:1], R, "x").section == "expr:x:rising"


def test_the_events_of_a_surface_are_at_the_closed_form_states():
    ws, R = np.array([0.7, 1.0, 2.5]), 0.8
    events = oscillator_sweep(ws, R, "wall", periods=6)
    rising = oscillator_sweep(ws, R, "wall", +1)
    falling = oscillator_sweep(ws, R, "wall", -1)
    assert (events.section, rising.section, falling.section) == ("surface:wall", "surface:wall:rising",
                                                                 "surface:wall:falling")
    for i, w in enumerate(ws):
        speed = w * math.sqrt(R**2 - A_WALL**2)
        # from (0, R w) the first event is upwards; one transient event discarded: down, up, down, ...
        np.testing.assert_allclose(events.at(i), [[A_WALL, -speed * (-1) ** k] for k in range(6)], rtol=0, atol=1e-9)
        np.testing.assert_allclose(rising.at(i), np.tile([A_WALL, speed], (4, 1)), rtol=0, atol=1e-9)
        np.testing.assert_allclose(falling.at(i), np.tile([A_WALL, -speed], (4, 1)), rtol=0, atol=1e-9)
    # the surface's indicator as an expression: the same crossings, located on the dense output
    same = oscillator_sweep(ws, R, "x - a", +1)
    assert same.section == "expr:-a + x:rising"
    np.testing.assert_allclose(same.states, rising.states, rtol=0, atol=1e-9)


def test_the_count_is_the_number_of_crossings_within_the_bounded_window():
    """A section crossed less often than asked: the search stops after 10 (transient + periods) time units
    ``period``, and the value has the crossings found there, after the transient ones."""
    R, transient, periods, unit = 0.8, 1, 4, 1.0
    limit = 10 * (transient + periods) * unit  # 50 time units
    ws = np.array([0.3, 0.55, 0.9])  # rising crossings every 2 pi / w: at 20.9, 11.4, 6.98 time units
    res = oscillator_sweep(ws, R, "x", +1, periods=periods, transient=transient, period=unit)
    expected = [min(periods, math.floor(limit * w / (2 * math.pi)) - transient) for w in ws]
    assert expected == [1, 3, 4]
    assert res.counts.tolist() == expected and res.failures == ()
    for i, w in enumerate(ws):
        np.testing.assert_allclose(res.at(i), np.tile([0.0, R * w], (expected[i], 1)), rtol=0, atol=1e-9)


def test_a_section_never_crossed_gives_no_point_and_no_failure():
    res = oscillator_sweep([1.0], 0.8, "x - 2", +1, periods=3, transient=0)
    assert res.counts.tolist() == [0] and res.states.shape == (0, 2) and res.failures == ()
    res = oscillator_sweep([1.0], 0.3, "wall", periods=3, transient=0)  # amplitude below the wall
    assert res.counts.tolist() == [0] and res.failures == ()


@settings(max_examples=25, deadline=None)
@given(R=st.floats(0.05, 3.0), w=st.floats(0.3, 4.0), direction=st.sampled_from([1, -1]),
       periods=st.integers(1, 5), transient=st.integers(0, 3))
def test_crossings_of_the_linear_oscillator(R, w, direction, periods, transient):
    """Whatever the amplitude, frequency and direction: ``periods`` crossings of ``x = 0``, each at ``v =
    direction R w``; and of ``v = 0``, each at ``x = -direction R`` (v falls through zero at the top)."""
    res = oscillator_sweep([w], R, "x", direction, periods=periods, transient=transient)
    assert res.counts.tolist() == [periods]
    np.testing.assert_allclose(res.states, np.tile([0.0, direction * R * w], (periods, 1)),
                               rtol=0, atol=1e-9 * (1 + R * w))
    res = oscillator_sweep([w], R, "v", direction, periods=periods, transient=transient)
    assert res.counts.tolist() == [periods]
    np.testing.assert_allclose(res.states, np.tile([-direction * R, 0.0], (periods, 1)), rtol=0, atol=1e-9 * (1 + R))


# -- a limit cycle, a clocked model, an impact model, the clock of a forced model --------------------------------
def test_sections_of_a_harmonic_limit_cycle():
    mus = np.array([0.25, 0.5])
    # from r = 0.1 inside the cycle: ten transient crossings (20 pi time units at a rate -2 mu) settle it
    start = {"x0": [0.1, 0.0], "start": "own", "workers": 1, "periods": 3, "transient": 10}
    across = sweep(hopf(), "mu", mus, section="x", direction=-1, **start)
    events = sweep(hopf(), "mu", mus, section="axis", direction=+1, **start)
    for i, mu in enumerate(mus):
        np.testing.assert_allclose(across.at(i), np.tile([0.0, math.sqrt(mu)], (3, 1)), rtol=0, atol=1e-9)
        np.testing.assert_allclose(events.at(i), np.tile([math.sqrt(mu), 0.0], (3, 1)), rtol=0, atol=1e-9)


def test_the_clock_of_a_clocked_model():
    """The buck converter stays ON below E = 11.75 V: every clock event is its equilibrium, tau = 1."""
    Es = np.array([10.0, 11.0])
    res = sweep(buck_converter(), "E", Es, section="clock", periods=5, transient=2,
                x0=lambda p: [p["E"] / p["R"], p["E"], 0.3], start="own", workers=1)
    assert res.section == "surface:clock" and res.counts.tolist() == [5, 5] and res.failures == ()
    for i, E in enumerate(Es):
        np.testing.assert_allclose(res.at(i), np.tile([E / 22.0, E, 1.0], (5, 1)), rtol=1e-12, atol=1e-12)
    # the same with the phase as an expression (its reset from 1 to 0 is a jump, no crossing)
    phase = sweep(buck_converter(), "E", Es, section="tau - 1/2", periods=5, transient=2,
                  x0=lambda p: [p["E"] / p["R"], p["E"], 0.3], start="own", workers=1)
    assert phase.section == "expr:tau - 1/2:rising" and phase.counts.tolist() == [5, 5]
    for i, E in enumerate(Es):
        np.testing.assert_allclose(phase.at(i), np.tile([E / 22.0, E, 0.5], (5, 1)), rtol=1e-12, atol=1e-12)


def test_the_impacts_of_the_ball_are_its_period_one_orbit():
    g, e, W = 9.81, 0.5, 2 * math.pi
    As = np.array([0.3, 0.31])
    res = sweep(bouncing_ball(), "A", As, section="table", periods=3, transient=30, x0=[0.522, -4.092], workers=1)
    assert res.section == "surface:table" and res.counts.tolist() == [3, 3]
    for i, A in enumerate(As):
        phi = math.acos((1 - e) * math.pi * g / ((1 + e) * A * W**2))
        np.testing.assert_allclose(res.at(i), np.tile([A * math.sin(phi), -g * (2 * math.pi / W) / 2], (3, 1)),
                                   rtol=0, atol=1e-8)


def test_a_time_clock_of_a_forced_model_is_its_stroboscopic_section():
    ws = np.array([0.6, 1.5])
    det = (1 - ws**2) ** 2 + (0.05 * ws) ** 2
    harmonic = np.column_stack([-0.2 * 0.05 * ws / det, 0.2 * (1 - ws**2) * ws / det])
    clock = sweep(trilinear(), "omega", ws, section="sin(omega*t)", periods=3, transient=300, workers=1)
    strobe = sweep(trilinear(), "omega", ws, periods=3, transient=300, workers=1)
    assert clock.section == "expr:sin(omega*t):rising" and strobe.section == "poincare"
    np.testing.assert_allclose(clock.states, np.repeat(harmonic, 3, axis=0), rtol=0, atol=1e-8)
    np.testing.assert_allclose(clock.states, strobe.states, rtol=0, atol=1e-9)


def test_workers_and_lyapunov_with_a_section():
    """Two worker processes give the values' own runs; the largest exponent of the cycle is its phase's, 0."""
    mus = np.array([0.25, 0.5, 0.75])
    kw = {"section": "axis", "direction": 1, "x0": [0.1, 0.0], "start": "own", "periods": 6, "transient": 10}
    serial = sweep(hopf(), "mu", mus, workers=1, lyapunov=True, **kw)
    parallel = sweep(hopf(), "mu", mus, workers=2, **kw)
    np.testing.assert_array_equal(parallel.states, serial.states)
    assert np.all(np.abs(serial.largest_exponents) < 0.05)


# -- records, files, messages ----------------------------------------------------------------------------------------
def test_the_section_codes():
    for code in ("poincare", "maxima", "surface:clock", "surface:y:rising", "expr:x - 1:falling", "expr:v:either"):
        assert Section.from_code(code).code == code
    assert Section.from_code("expr:x - 1:falling") == Section("expression", "x - 1", -1)
    for bad in ("poincaré", "expr:x - 1", "surface:y:up", "surface:", ""):
        with pytest.raises(ValueError):
            Section.from_code(bad)
    system = oscillator_system()
    assert parse_section(system, "x-1", -1).code == "expr:x - 1:falling"
    assert parse_section(system, "expr:v:falling") == parse_section(system, "v", Crossing.FALLING)
    assert parse_section(system, "wall", "either").code == "surface:wall:either"
    assert parse_section(trilinear(), "poincare").code == "poincare"


def test_bad_sections_are_refused_naming_the_surfaces_and_states():
    system = oscillator_system()
    with pytest.raises(ModelError, match=r"'z' is no section .* surface \(wall, floor\).* states \(x, v\)"):
        parse_section(system, "z")
    with pytest.raises(ModelError, match="no switching surface 'roof'; its surfaces are wall, floor"):
        parse_section(system, "surface:roof")
    with pytest.raises(ModelError, match="depends on no state"):
        parse_section(system, "w - 1")
    with pytest.raises(ModelError, match="'poincare' needs a forced model"):
        parse_section(system, "poincare")
    with pytest.raises(ValueError, match="takes no direction"):
        parse_section(trilinear(), "poincare", 1)
    with pytest.raises(ValueError, match="says falling, but the direction given is [+]1"):
        parse_section(system, "expr:v:falling", 1)
    with pytest.raises(ValueError, match="direction must be"):
        parse_section(system, "v", 2)
    with pytest.raises(ValueError, match="not both"):
        sweep(trilinear(), "omega", [1.0], section="maxima", poincare=False)
    with pytest.raises(ValueError, match="belongs to a section"):
        sweep(trilinear(), "omega", [1.0], direction=1)


def test_a_section_is_written_and_read_back(tmp_path):
    res = oscillator_sweep([1.0, 1.5], 0.8, "x - a", -1, periods=2)
    for section in ("expr:-a + x:falling", "surface:wall", "surface:wall:rising", "poincare", "maxima"):
        record = sweep_to_dict(dataclasses.replace(res, section=section))
        assert sweep_from_dict(json.loads(json.dumps(record))).section == section
    back = load_sweep(save_sweep(res, tmp_path / "sweep.json"))
    assert back.section == "expr:-a + x:falling"
    np.testing.assert_array_equal(back.states, res.states)
    record = sweep_to_dict(res) | {"section": "expr:x - 1"}  # no direction: not a code
    with pytest.raises(FileFormatError, match='section: expected one of "poincare", "maxima", "surface:NAME"'):
        sweep_from_dict(record)
    ax = plot_sweep(res).axes[0]
    assert ax.get_ylabel() == "x at falling crossings of -a + x = 0"


def test_the_command_line_refuses_an_unknown_section(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    base = ["sweep", "buck_converter", "--param", "E", "--from", "10", "--to", "11", "--num", "2"]
    code = cli.main([*base, "--section", "ramp_up"])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    for culprit in ("--section", "'ramp_up' is no section of 'buck_converter'", "surface (ramp, clock)",
                    "states (i, v, tau)"):
        assert culprit in err
    for argv, culprit in [([*base, "--direction", "-1"], "--direction belongs to --section"),
                          ([*base, "--section", "clock", "--direction", "up"], "'up' is not +1"),
                          ([*base, "--section", "poincare"], "needs a forced model")]:
        code = cli.main(argv)
        out, err = capsys.readouterr()
        assert code == 2 and culprit in err, err
    assert list(tmp_path.iterdir()) == []


def test_the_command_line_samples_a_section(capsys, tmp_path):
    code = cli.main(["sweep", "buck_converter", "--param", "E", "--from", "10", "--to", "11", "--num", "2",
                     "--section", "clock", "--periods", "3", "--transient", "0", "--x0", "0.5,11,0", "--start", "own",
                     "--workers", "1", "--out", str(tmp_path)])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert out.startswith("6 events on surface clock at 2 values of E (each from its own start)")
    res = load_sweep(tmp_path / "buck_converter_E_sweep.json")
    assert res.section == "surface:clock" and res.counts.tolist() == [3, 3]
    np.testing.assert_allclose(res.states[:, 2], 1.0, rtol=0, atol=1e-12)
