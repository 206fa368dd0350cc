"""A mode may be memory: orbits, branches and sweeps that start in a named mode (``mode0``).

The model is a thermostat (a relay with hysteresis) written without a made-up logic state: the states are
the temperature ``x`` and a driven second state ``y``,

    heat:  x' = 1 - x,   y' = x - b y         cool:  x' = -1 - x,   y' = x - b y,

with ``heat -> cool`` where ``x - a`` rises and ``cool -> heat`` where ``x + a`` falls (the band
``[-a, a]``).  Neither mode has a domain: both hold every state, so only ``mode0`` tells them apart (the
model's rule takes the first, ``heat``).

Reference (closed form, checked against ``scipy.integrate.solve_ivp`` with its own event location below):

* from ``x = -a`` in ``heat``, ``x(t) = 1 - (1 + a) e^{-t}`` reaches ``a`` at ``t1 = ln((1 + a)/(1 - a))``;
  by the symmetry ``(x, y) -> (-x, -y)`` the ``cool`` half is the mirror image, and ``T = 2 t1``;
* ``y`` along the ``heat`` half, ``t`` after ``x = -a``: ``y(t) = e^{-bt} y_h + (1 - e^{-bt})/b
  - (1 + a)(e^{-t} - e^{-bt})/(b - 1)``, and periodicity with the mirror gives ``y_h = -K / (1 + e^{-b t1})``,
  ``K`` the last two terms at ``t1``; at a state ``x`` of the heat half, ``t = ln((1 + a)/(1 - x))``, and
  the ``cool`` half has ``y_cool(x) = -y_heat(-x)``;
* the nontrivial multiplier is ``e^{-bT}``: ``det M = exp(int div f) prod det S_i`` with ``div f = -1 - b``
  and ``det S = (h_x f+)/(h_x f-) = -(1 + a)/(1 - a)`` at both switches, so ``det M = e^{-(1 + b)T} e^{T}``,
  and the trivial multiplier is 1.  The test checks it also by central differences of the return map to
  the section ``x = 0`` (heating), integrated by ``solve_ivp``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from saltation import (
    Crossing,
    Flow,
    InconsistentResultError,
    InitialModeError,
    Mode,
    ModelError,
    PiecewiseSystem,
    ShootingProblem,
    Transition,
    continue_orbit,
    find_periodic_orbit,
    sweep,
)
from saltation.apps import cli
from saltation.output import io

A, B = 0.5, 0.3
#: Newton's tolerance of these tests (``|r| <= tol (1 + |u|)``); both modes are affine, so the engine's flow is
#: exact and the period and states are as accurate as Newton leaves them
NEWTON_TOL = 1e-12
#: what that promises of the period and the state, with margin
ACCURACY = 1e-10
#: what a branch point or a command's orbit promises: Newton's default tolerance 1e-10 on states of size 1, and
#: the default rtol 1e-10 integrated over a period of ~2 (the multipliers inherit both)
SOLVED = 1e-9
#: the scipy reference (DOP853 at rtol 1e-13, atol 1e-15) over one period, against the closed form
REFERENCE = 1e-11
#: a central difference with h = 1e-3 of a return map affine in y (exact but for the reference's 1e-13 error / h)
DIFFERENCE = 1e-9

MODEL_SOURCE = '''
from saltation import Crossing, Mode, PiecewiseSystem, Transition


def thermostat():
    return PiecewiseSystem(
        name="test_thermostat_memory",
        states=["x", "y"],
        parameters={"a": 0.5, "b": 0.3},
        modes=[Mode("heat", ["1 - x", "x - b*y"]), Mode("cool", ["-1 - x", "x - b*y"])],
        surfaces={"hi": "x - a", "lo": "x + a"},
        transitions=[Transition("heat", "hi", Crossing.RISING, "cool"),
                     Transition("cool", "lo", Crossing.FALLING, "heat")],
    )
'''


def thermostat() -> PiecewiseSystem:
    """The thermostat of the module docstring (the same model as ``MODEL_SOURCE``, for the command line)."""
    return PiecewiseSystem(
        name="test_thermostat_memory",
        states=["x", "y"],
        parameters={"a": A, "b": B},
        modes=[Mode("heat", ["1 - x", "x - b*y"]), Mode("cool", ["-1 - x", "x - b*y"])],
        surfaces={"hi": "x - a", "lo": "x + a"},
        transitions=[Transition("heat", "hi", Crossing.RISING, "cool"),
                     Transition("cool", "lo", Crossing.FALLING, "heat")],
    )


# -- the reference ----------------------------------------------------------------------------
def period(a: float = A) -> float:
    return 2.0 * math.log((1.0 + a) / (1.0 - a))


def _forced_y(t: float, a: float, b: float) -> float:
    """``y(t) - e^{-bt} y(0)`` along the heat half from ``x = -a``."""
    return (1.0 - math.exp(-b * t)) / b - (1.0 + a) * (math.exp(-t) - math.exp(-b * t)) / (b - 1.0)


def y_on_orbit(x: float, mode: str, a: float = A, b: float = B) -> float:
    """``y`` of the periodic orbit where it passes ``x`` in ``mode``."""
    if mode == "cool":
        return -y_on_orbit(-x, "heat", a, b)
    t1 = 0.5 * period(a)
    y_h = -_forced_y(t1, a, b) / (1.0 + math.exp(-b * t1))
    t = math.log((1.0 + a) / (1.0 - x))
    return math.exp(-b * t) * y_h + _forced_y(t, a, b)


def multiplier(a: float = A, b: float = B) -> float:
    return math.exp(-b * period(a))


def leg(z, mode: str, level: float, direction: int, a: float = A, b: float = B) -> tuple[float, np.ndarray]:
    """``solve_ivp`` in ``mode`` from ``z`` until ``x`` crosses ``level`` in ``direction``: (time, state)."""
    u = 1.0 if mode == "heat" else -1.0

    def crossing(t, s):
        return s[0] - level

    crossing.terminal, crossing.direction = True, direction
    sol = solve_ivp(lambda t, s: [u - s[0], s[0] - b * s[1]], (0.0, 50.0), list(z), method="DOP853", rtol=1e-13,
                    atol=1e-15, events=crossing)
    return float(sol.t_events[0][0]), sol.y_events[0][0]


def return_map(y: float, a: float = A, b: float = B) -> tuple[float, float]:
    """From ``(0, y)`` heating, once around to ``x = 0`` heating again: (time, y)."""
    t1, z = leg([0.0, y], "heat", a, 1, a, b)
    t2, z = leg(z, "cool", -a, -1, a, b)
    t3, z = leg(z, "heat", 0.0, 1, a, b)
    return t1 + t2 + t3, float(z[1])


@pytest.fixture(scope="module")
def flow() -> Flow:
    return Flow(thermostat())


def test_the_reference_agrees_with_solve_ivp():
    """Closed form against solve_ivp's events: the period, y on both halves, and the multiplier e^{-bT} as the
    slope of the return map (central differences; the map is affine in y, so the difference is exact)."""
    y0 = y_on_orbit(0.0, "heat")
    T, y1 = return_map(y0)
    assert T == pytest.approx(period(), rel=REFERENCE)
    assert y1 == pytest.approx(y0, abs=REFERENCE)
    _, z = leg([0.0, y0], "heat", A, 1)
    _, z = leg(z, "cool", 0.0, -1)
    assert z[1] == pytest.approx(y_on_orbit(0.0, "cool"), abs=REFERENCE)
    h = 1e-3
    slope = (return_map(y0 + h)[1] - return_map(y0 - h)[1]) / (2 * h)
    assert slope == pytest.approx(multiplier(), rel=DIFFERENCE)


# -- orbits -----------------------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["heat", "cool"])
def test_an_orbit_starts_in_the_named_memory_mode(flow, mode):
    """From x = 0 the same state is on the heating or the cooling half: mode0 picks which, and the orbit
    records it.  Its period, state and multipliers are the closed form's."""
    orbit = find_periodic_orbit(flow, [0.0, 0.0], period=1.05 * period(), mode0=mode, tol=NEWTON_TOL)
    assert orbit.mode0 == mode and orbit.trajectory.mode0 == mode and orbit.trajectory.mode1 == mode
    assert orbit.period == pytest.approx(period(), rel=ACCURACY)
    x, y = orbit.state0
    assert y == pytest.approx(y_on_orbit(x, mode), abs=ACCURACY)
    mu = np.sort(orbit.multipliers.real)
    assert mu == pytest.approx([multiplier(), 1.0], abs=SOLVED)
    assert f"in {mode!r}" in repr(orbit)


def test_without_mode0_the_domains_choose_as_before(flow):
    """No mode0: the model's rule (the first mode whose domain holds, here heat) and an unpinned problem."""
    orbit = find_periodic_orbit(flow, [0.0, 0.0], period=1.05 * period(), tol=NEWTON_TOL)
    assert orbit.mode0 == "heat" and orbit.problem.mode0 is None
    assert orbit.state0[1] == pytest.approx(y_on_orbit(orbit.state0[0], "heat"), abs=ACCURACY)


def test_an_orbit_from_the_switching_surface_keeps_its_mode(flow):
    """x = -a lies on the surface of cool -> heat; in heat no transition watches it.  The guess is moved off the
    surfaces along its own trajectory, within its heating stretch: the orbit stays in heat."""
    orbit = find_periodic_orbit(flow, [-A, 0.0], period=1.02 * period(), mode0="heat", tol=NEWTON_TOL)
    assert orbit.mode0 == "heat"
    x, y = orbit.state0
    assert -A < x < A
    assert y == pytest.approx(y_on_orbit(x, "heat"), abs=ACCURACY)
    assert orbit.period == pytest.approx(period(), rel=ACCURACY)


def test_multiple_shooting_nodes_keep_the_mode_of_their_segment(flow):
    """Three segments from cool: the first starts in cool, each further one in the mode its predecessor ends in;
    every node lies on the half of the orbit of its own segment's mode."""
    orbit = find_periodic_orbit(flow, [0.0, 0.0], period=1.05 * period(), mode0="cool", segments=3, tol=NEWTON_TOL)
    assert orbit.mode0 == "cool"
    assert orbit.period == pytest.approx(period(), rel=ACCURACY)
    modes, mode = [], "cool"  # each segment run again from its node, in the mode the one before ends in
    for i, node in enumerate(orbit.nodes):
        modes.append(mode)
        assert node[1] == pytest.approx(y_on_orbit(node[0], mode), abs=ACCURACY), i
        run = flow.run(node, i * orbit.period / 3, (i + 1) * orbit.period / 3, flow.parameters(), mode0=mode)
        mode = run.mode1
    assert mode == "cool" and "heat" in modes
    assert np.sort(orbit.multipliers.real) == pytest.approx([multiplier(), 1.0], abs=SOLVED)


def test_a_shot_that_closes_its_state_but_not_its_mode_is_no_orbit(flow):
    """Half the period from x = 0 heating: up to a, cooling back to x = 0.  The state closes (for the right y)
    in cool, not in heat: with mode0 that is refused by name, whatever the multipliers say."""
    with pytest.raises(InconsistentResultError, match="not in the mode 'heat'"):
        find_periodic_orbit(flow, [0.0, 0.0], period=0.5 * period(), mode0="heat")


def test_an_unknown_mode_names_the_modes(flow):
    with pytest.raises(ModelError, match=r"unknown mode 'warm'; modes are \['heat', 'cool'\]") as info:
        find_periodic_orbit(flow, [0.0, 0.0], period=period(), mode0="warm")
    assert isinstance(info.value, ValueError)
    with pytest.raises(ModelError, match="unknown mode 'warm'"):
        ShootingProblem(flow, mode0="warm")
    with pytest.raises(ModelError, match="unknown mode 'warm'"):
        sweep(thermostat(), "a", [0.5], x0=[0.0, 0.0], mode0="warm", workers=1)


def test_a_state_outside_the_named_modes_domain_names_mode_and_condition(oscillator_flow):
    """``above`` of the test oscillator holds ``x - a - gap > 0`` only: x = 0 is not in it.  A state on its
    boundary (x = a) is."""
    p = oscillator_flow.parameters()
    with pytest.raises(InitialModeError, match=r"outside the domain of mode 'above'.*-a - gap \+ x > 0 \(it is -0\.5\)"):
        find_periodic_orbit(oscillator_flow, [0.0, 1.0], period=6.0, mode0="above")
    assert oscillator_flow.start_mode([0.5, 1.0], p, 0.0, "above") == 1
    assert oscillator_flow.start_mode([0.0, 1.0], p, 0.0, "below") == 0


# -- records ----------------------------------------------------------------------------------
def test_the_orbit_record_carries_its_mode(flow):
    orbit = find_periodic_orbit(flow, [0.0, 0.0], period=period(), mode0="cool")
    record = cli.orbit_to_dict(orbit, flow.system)
    assert json.loads(json.dumps(record))["mode0"] == "cool"


# -- branches ---------------------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["heat", "cool"])
def test_a_branch_keeps_the_start_mode(flow, mode, tmp_path):
    """Along a in [0.3, 0.7] every point starts in the orbit's mode (heat: the compiled corrector, whose shots
    start in the rule's mode, which is heat; cool: the Python corrector); periods, states and multipliers are
    the closed form's at each a.  The branch's JSON keeps the mode, and a file without it reads None."""
    orbit = find_periodic_orbit(flow, [0.0, 0.0], period=period(), mode0=mode)
    branch = continue_orbit(orbit, "a", bounds=(0.3, 0.7))
    assert len(branch) > 10 and branch.parameter.min() == pytest.approx(0.3) and branch.parameter.max() == pytest.approx(0.7)
    assert set(branch.mode0) == {mode}
    for p in branch.points:
        a = p.parameter
        assert p.period == pytest.approx(period(a), rel=SOLVED)
        assert p.state[1] == pytest.approx(y_on_orbit(p.state[0], mode, a), abs=SOLVED)
        assert np.sort(p.multipliers.real) == pytest.approx([multiplier(a), 1.0], abs=1e-8)
    path = io.save_branch_json(branch, tmp_path / "branch.json")
    assert io.load_branch_json(path).mode0 == branch.mode0
    old = io.branch_to_dict(branch)
    for point in old["points"]:
        del point["mode0"]
    assert set(io.branch_from_dict(old).mode0) == {None}


# -- sweeps -----------------------------------------------------------------------------------
def test_a_sweep_starts_in_the_named_mode():
    """No transient: the first maximum of x (the switch at x = a) after a start at (0, 0) is reached at once
    when heating, after a turn through x = -a when cooling; y there is solve_ivp's."""
    _, heating = leg([0.0, 0.0], "heat", A, 1)
    _, z = leg([0.0, 0.0], "cool", -A, -1)
    _, cooling = leg(z, "heat", A, 1)
    for mode, reference in (("heat", heating), ("cool", cooling), (None, heating)):
        result = sweep(thermostat(), "a", [A], x0=[0.0, 0.0], mode0=mode, periods=2, transient=0, period=2.0,
                       workers=1)
        assert not result.failures
        first = result.at(0)[0]
        assert first == pytest.approx(reference, abs=1e-8), mode
        assert result.settings.get("mode0") == mode


def test_a_sweep_start_outside_the_modes_domain_fails_that_value(oscillator_system_model):
    result = sweep(oscillator_system_model, "w", [1.0], x0=[0.0, 1.0], mode0="above", periods=2, transient=0,
                   workers=1)
    assert len(result.failures) == 1
    assert "outside the domain of mode 'above'" in result.failures[0][1]


@pytest.fixture(scope="module")
def oscillator_system_model(oscillator_flow):
    return oscillator_flow.system


# -- the command line -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def model_file(tmp_path_factory, flow):
    path = tmp_path_factory.mktemp("models") / "thermostat_model.py"
    path.write_text(MODEL_SOURCE)
    return f"{path}:thermostat"


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("mode", ["heat", "cool"])
def test_cli_orbit_mode0(capsys, model_file, mode):
    code, out, err = _run(capsys, "orbit", model_file, "--x0", "0,0", "--period", "2.2", "--mode0", mode, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["mode0"] == mode
    assert data["period"] == pytest.approx(period(), rel=SOLVED)
    assert data["state0"][1] == pytest.approx(y_on_orbit(data["state0"][0], mode), abs=SOLVED)
    code, out, err = _run(capsys, "orbit", model_file, "--x0", "0,0", "--period", "2.2", "--mode0", mode)
    assert code == 0, err
    assert f"in mode {mode}" in out


def test_cli_unknown_mode0_is_bad_usage(capsys, model_file):
    for argv in (["orbit", model_file, "--mode0", "warm"],
                 ["continue", model_file, "--param", "a", "--from", "0.5", "--to", "0.6", "--mode0", "warm"],
                 ["sweep", model_file, "--param", "a", "--from", "0.5", "--to", "0.6", "--num", "2", "--mode0", "warm"]):
        code, out, err = _run(capsys, *argv)
        assert code == 2 and out == ""
        assert "unknown mode 'warm' in --mode0" in err and "modes are heat, cool" in err


def test_cli_continue_and_sweep_mode0(capsys, model_file, tmp_path):
    code, out, err = _run(capsys, "continue", model_file, "--param", "a", "--from", "0.5", "--to", "0.56", "--x0", "0,0",
                          "--period", "2.2", "--mode0", "cool", "--out", str(tmp_path), "--no-progress")
    assert code == 0, err
    branch = io.load_branch_json(tmp_path / "test_thermostat_memory_a_branch.json")
    assert len(branch) > 2 and set(branch.mode0) == {"cool"}
    assert branch.period == pytest.approx([period(a) for a in branch.parameter], rel=SOLVED)
    code, out, err = _run(capsys, "sweep", model_file, "--param", "a", "--from", "0.5", "--to", "0.5", "--num", "1",
                          "--x0", "0,0", "--mode0", "cool", "--periods", "2", "--transient", "0", "--workers", "1",
                          "--out", str(tmp_path))
    assert code == 0, err
    data = json.loads((tmp_path / "test_thermostat_memory_a_sweep.json").read_text())
    assert data["settings"]["mode0"] == "cool"
