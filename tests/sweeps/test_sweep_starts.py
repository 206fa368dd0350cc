"""Where each value of a brute-force sweep starts (saltation.apps.sweeps.SweepStart), against shooting and closed forms.

The block on a belt (Leine & Van Campen, Fig. 7) has a stable stick-slip cycle from small v_dr up to its
fold at v_dr ~= 1.098 and, beyond it, only the equilibrium x = F_slip / k.  A sweep whose values each start
from the model's own start (sticking to the belt at x = 0) shows the cycle over that whole range; its
maxima of x are compared with the cycle found by shooting.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.linalg import expm

from saltation import ModelError
from saltation.models import SHIPPED, block_on_belt, trilinear
from saltation.orbits.shooting import find_periodic_orbit
from saltation.apps.sweeps import PeriodMap, SweepResult, SweepStart, period_map, sweep

#: Below the fold: the stable stick-slip cycle.  Above it (1.2, 1.6): only the equilibrium.
BELOW_FOLD = (0.2, 0.45, 0.7, 0.95, 1.05, 1.09)
ABOVE_FOLD = (1.2, 1.6)
#: The sweep's maxima (dense output, golden-section refined) against the shooting orbit's x_max: both
#: are computed to the integration tolerance (rtol 1e-10); 1e-8 leaves room for the two paths.
MAXIMA_TOL = 1e-8


def belt_start(values):
    """The shipped model's start, as the command line calls it: sticking to the belt at x = 0."""
    return SHIPPED["block_on_belt"].start(values, False)


def stick_slip_cycle(flow, v_dr: float):
    """The stable stick-slip cycle at ``v_dr`` by shooting, from the point where its stick phase ends.

    A stick phase ends where the spring and damper force reaches F_stick: x = (F_stick - c v_dr) / k at
    v = v_dr (Appendix B: F_stick = 2, c = 0.1, k = 1); the guess lies just before it.  The period
    guess is the time between two such ends on a short simulation from there.
    """
    p = flow.parameters({"v_dr": v_dr})
    guess = np.array([2.0 - 0.1 * v_dr - 1e-3, v_dr])
    ends = [e.t for e in flow.run(guess, 0.0, 60.0, p).events if e.surface == "stick_upper"]
    orbit = find_periodic_orbit(flow, guess, parameters={"v_dr": v_dr}, period=ends[1] - ends[0])
    assert orbit.converged and orbit.stable
    return orbit


@pytest.fixture(scope="module")
def own_sweep(belt_flow):
    values = BELOW_FOLD + ABOVE_FOLD
    return sweep(block_on_belt(), "v_dr", values, periods=20, transient=100, x0=belt_start, start="own", workers=1)


def test_own_starts_show_the_stick_slip_cycle_up_to_the_fold(belt_flow, own_sweep):
    res = own_sweep
    assert res.start is SweepStart.OWN and res.failures == ()
    for i, v_dr in enumerate(BELOW_FOLD):
        x_max = stick_slip_cycle(belt_flow, v_dr).trajectory.x_max[0]
        pts = res.at(i)
        assert len(pts) >= 10, v_dr  # about 20 time units of 2 pi, a period of 6.4 ... 12.6
        np.testing.assert_allclose(pts[:, 0], x_max, rtol=0, atol=MAXIMA_TOL, err_msg=f"v_dr = {v_dr}")
        np.testing.assert_allclose(pts[:, 1], 0.0, atol=1e-6)  # v = 0 at a maximum of x
    for k, v_dr in enumerate(ABOVE_FOLD, start=len(BELOW_FOLD)):
        # no oscillation left: the final state once, the equilibrium x = F_slip / k = 1
        assert res.counts[k] == 1, v_dr
        np.testing.assert_allclose(res.at(k)[0], [1.0, 0.0], rtol=0, atol=1e-8)


def test_own_starts_do_not_depend_on_the_chunks(own_sweep):
    """Each value is independent: two workers (two chunks) give the same points to the bit."""
    two = sweep(block_on_belt(), "v_dr", own_sweep.values, periods=20, transient=100, x0=belt_start,
                start=SweepStart.OWN, workers=2)
    np.testing.assert_array_equal(two.counts, own_sweep.counts)
    np.testing.assert_array_equal(two.states, own_sweep.states)


def test_the_start_function_gets_each_values_own_parameters():
    seen = []

    def start(values):
        seen.append(dict(values))
        return [0.0, values["v_dr"]]

    values = [0.3, 0.5, 0.7]
    sweep(block_on_belt(), "v_dr", values, periods=1, transient=0, x0=start, parameters={"c": 0.2}, workers=1)
    assert [s["v_dr"] for s in seen] == values  # once per value, in order, before any simulation
    assert all(s["c"] == 0.2 and set(s) == set(block_on_belt().parameter_names) for s in seen)


# -- the rule, exactly: a linear oscillator with the closed-form flow ---------------------------------------

M, C, K, F0 = 1.0, 0.05, 1.0, 0.2  # Appendix A; |x| < x_c = 1 throughout: no contact, a linear oscillator


def linear_flow(x0, w: float, t: float) -> np.ndarray:
    """``(x, x')(t)`` of ``m x'' + c x' + k x = f0 sin(w t)`` from ``x0`` at t = 0: the exponential of the
    system with the forcing as two more states ``(sin w t, cos w t)``."""
    A = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [-K / M, -C / M, F0 / M, 0.0],
        [0.0, 0.0, 0.0, w],
        [0.0, 0.0, -w, 0.0],
    ])
    return (expm(A * t) @ np.array([x0[0], x0[1], 0.0, 1.0]))[:2]


def test_previous_and_own_starts_against_the_closed_form():
    """No transient, one period per value: ``own`` maps each value's start over its period, ``previous``
    maps the previous value's end (the first value from its start)."""
    ws = [0.6, 0.65, 0.7]

    def start(values):
        return [0.1 * values["omega"], 0.0]

    own = sweep(trilinear(), "omega", ws, periods=1, transient=0, x0=start, start="own", workers=1)
    previous = sweep(trilinear(), "omega", ws, periods=1, transient=0, x0=start, workers=1)
    assert own.start is SweepStart.OWN and previous.start is SweepStart.PREVIOUS  # previous: the default
    x = np.array(start({"omega": ws[0]}))
    for i, w in enumerate(ws):
        T = 2 * np.pi / w
        np.testing.assert_allclose(own.at(i)[0], linear_flow(start({"omega": w}), w, T), rtol=0, atol=1e-10)
        x = linear_flow(x, w, T)
        np.testing.assert_allclose(previous.at(i)[0], x, rtol=0, atol=1e-10)
    assert own.settings["x0"].startswith("function ") and own.settings["x0"].endswith("start")
    fixed = sweep(trilinear(), "omega", ws[:1], periods=1, transient=0, x0=[0.1, 0.0], workers=1)
    assert fixed.settings["x0"] == [0.1, 0.0]


def test_period_map_own_starts_on_the_harmonic_orbit():
    """A start on each cell's own harmonic orbit (closed form) is periodic at once, with no transient;
    from the previous cell's end the next cell has not settled (its free oscillation decays slowly)."""
    ws, f0s = [0.6, 0.65, 0.7], [0.1, 0.2]

    def harmonic(values):
        w, f0 = values["omega"], values["f0"]
        det = (K - M * w**2) ** 2 + (C * w) ** 2
        return [-f0 * C * w / det, f0 * (K - M * w**2) * w / det]

    own = period_map(trilinear(), "omega", ws, "f0", f0s, max_period=1, transient=0, x0=harmonic, start="own",
                     workers=1)
    np.testing.assert_array_equal(own.periods, 1)
    previous = period_map(trilinear(), "omega", ws, "f0", f0s, max_period=1, transient=0, x0=harmonic, workers=1)
    np.testing.assert_array_equal(previous.periods, [[1, 0, 0], [1, 0, 0]])
    assert (own.start, previous.start) == (SweepStart.OWN, SweepStart.PREVIOUS)
    back = PeriodMap.from_dict(json.loads(json.dumps(own.to_dict())))
    assert back.start is SweepStart.OWN
    np.testing.assert_array_equal(back.periods, own.periods)


# -- records -----------------------------------------------------------------------------------------------

def test_the_rule_is_recorded_and_read_back(tmp_path, own_sweep):
    path = own_sweep.save(tmp_path / "sweep.json")
    record = json.loads(path.read_text())
    assert record["start"] == "own"
    assert record["settings"]["x0"] == f"function {__name__}.belt_start"
    back = SweepResult.load(path)
    assert back.start is SweepStart.OWN
    np.testing.assert_array_equal(back.states, own_sweep.states)
    # a file written before the rule was recorded: every value started from the previous one
    del record["start"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(record))
    assert SweepResult.load(old).start is SweepStart.PREVIOUS
    grid = {"format": "saltation.period_map/1", "model": "m", "parameter": "a", "parameter2": "b", "values": [1.0],
            "values2": [2.0], "periods": [[1]], "max_period": 4, "failures": [], "settings": {}}
    assert PeriodMap.from_dict(grid).start is SweepStart.PREVIOUS
    assert [k.value for k in SweepStart] == ["previous", "own"]


def test_bad_starts_are_refused_naming_the_problem():
    system = block_on_belt()
    with pytest.raises(ValueError, match="start must be one of 'previous', 'own'.*'sideways'"):
        sweep(system, "v_dr", [0.5], start="sideways")
    with pytest.raises(ModelError, match=r"x0\(v_dr=0.5\) returned 3 components"):
        sweep(system, "v_dr", [0.5], x0=lambda p: [0.0, 0.0, 0.0], workers=1)
    with pytest.raises(ModelError, match=r"x0\(v_dr=0.7\) returned a state that is not finite"):
        sweep(system, "v_dr", [0.5, 0.7], x0=lambda p: [0.0, 1.0 / (0.7 - p["v_dr"]) if p["v_dr"] != 0.7 else np.nan],
              workers=1)
    with pytest.raises(ModelError, match="x0 must be finite"):
        sweep(system, "v_dr", [0.5], x0=[np.inf, 0.0])
    with pytest.raises(ModelError, match=r"x0\(omega=0.6, f0=0.2\) returned 1 component;"):
        period_map(trilinear(), "omega", [0.6], "f0", [0.2], x0=lambda p: [0.0], workers=1)
    with pytest.raises(ValueError, match="t0 must be finite"):
        sweep(system, "v_dr", [0.5], t0=np.nan)


# -- the command line ----------------------------------------------------------------------------------------

def test_command_line_sweep_starts_each_value_from_its_own_start(tmp_path, capsys, belt_flow):
    """``saltation sweep block_on_belt`` by default starts every value from the model's start at that
    value: the stick-slip cycle below the fold (its maxima those of shooting), the equilibrium above."""
    from saltation.apps import cli

    base = ["sweep", "block_on_belt", "--param", "v_dr", "--from", "0.3", "--to", "1.2", "--num", "4",
            "--periods", "20", "--transient", "100", "--workers", "1"]
    assert cli.main([*base, "--out", str(tmp_path / "own")]) == 0, capsys.readouterr().err
    assert "each from its own start" in capsys.readouterr().out
    res = SweepResult.load(tmp_path / "own" / "block_on_belt_v_dr_sweep.json")
    assert res.start is SweepStart.OWN
    assert res.settings["x0"] == "function saltation.models.block_on_belt._transient_start"
    for i, v_dr in enumerate([0.3, 0.6, 0.9]):
        x_max = stick_slip_cycle(belt_flow, v_dr).trajectory.x_max[0]
        np.testing.assert_allclose(res.at(i)[:, 0], x_max, rtol=0, atol=MAXIMA_TOL, err_msg=f"v_dr = {v_dr}")
    assert res.counts[3] == 1
    np.testing.assert_allclose(res.at(3)[0], [1.0, 0.0], rtol=0, atol=1e-8)  # v_dr = 1.2: F_slip / k
    # --start previous: the rule is the classical one, and recorded
    assert cli.main([*base, "--start", "previous", "--out", str(tmp_path / "previous")]) == 0
    assert "each from the previous value's final state" in capsys.readouterr().out
    assert SweepResult.load(tmp_path / "previous" / "block_on_belt_v_dr_sweep.json").start is SweepStart.PREVIOUS
    # a given --x0 is one state: by default the classical rule from it
    assert cli.main([*base, "--x0", "0,0.5", "--out", str(tmp_path / "x0")]) == 0
    fixed = SweepResult.load(tmp_path / "x0" / "block_on_belt_v_dr_sweep.json")
    assert fixed.start is SweepStart.PREVIOUS and fixed.settings["x0"] == [0.0, 0.5]
