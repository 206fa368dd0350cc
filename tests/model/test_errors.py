"""Bad input and failures: each raises the documented exception, and its message names the culprit."""

from __future__ import annotations

import numpy as np
import pytest

from saltation import (
    ChatteringError,
    ConvergenceError,
    Crossing,
    InitialModeError,
    Mode,
    ModelError,
    NonFiniteError,
    PiecewiseSystem,
    Tolerances,
    Transition,
)
from saltation.orbits.shooting import find_periodic_orbit

RISING, FALLING = Crossing.RISING, Crossing.FALLING


def _model(**changes):
    """A small valid two-mode model; keyword arguments replace its parts."""
    parts = dict(
        name="bad_input_probe",
        states=["x", "v"],
        parameters={"k": 1.0, "a": 0.5},
        modes=[Mode("left", ["v", "-k*x"], domain=["x - a < 0"]), Mode("right", ["v", "-k*x"], domain=["x - a > 0"])],
        surfaces={"wall": "x - a"},
        transitions=[Transition("left", "wall", RISING, "right"), Transition("right", "wall", FALLING, "left")],
    )
    parts.update(changes)
    return PiecewiseSystem(**parts)


# ----------------------------------------------------------------- construction (ModelError)
def test_valid_probe_model_builds():
    assert _model().mode_names == ("left", "right")


def test_unknown_source_mode_in_transition():
    with pytest.raises(ModelError, match="nowhere"):
        _model(transitions=[Transition("nowhere", "wall", RISING, "right")])


def test_transition_to_a_mode_that_does_not_exist():
    with pytest.raises(ModelError, match="nowhere") as info:
        _model(transitions=[Transition("left", "wall", RISING, "nowhere")])
    assert "target" in str(info.value)


def test_unknown_surface_in_transition():
    with pytest.raises(ModelError, match="ceiling"):
        _model(transitions=[Transition("left", "ceiling", RISING, "right")])


def test_unknown_parameter_in_vector_field():
    with pytest.raises(ModelError, match="nope") as info:
        _model(modes=[Mode("left", ["v", "-k*x - nope"]), Mode("right", ["v", "-k*x"])])
    assert "left" in str(info.value)  # and the mode it appears in


def test_unknown_parameter_in_indicator():
    with pytest.raises(ModelError, match="nope") as info:
        _model(surfaces={"wall": "x - nope"})
    assert "wall" in str(info.value)


def test_unknown_parameter_in_parameter_vector(trilinear_flow):
    with pytest.raises(ModelError, match="nope"):
        trilinear_flow.system.parameter_vector({"nope": 1.0})
    with pytest.raises(ModelError, match="nope"):
        trilinear_flow.parameters({"nope": 1.0})


def test_indicator_without_state_dependence():
    with pytest.raises(ModelError, match="wall"):
        _model(surfaces={"wall": "a - 1"})


def test_bad_tolerances():
    with pytest.raises(ValueError, match="rtol"):
        Tolerances(rtol=0.0)


# ----------------------------------------------------------------- integration
def test_initial_state_in_no_mode(filippov_flow):
    """The domains y > 0 and y < 0 leave y = 0 uncovered."""
    p = filippov_flow.parameters()
    with pytest.raises(InitialModeError) as info:
        filippov_flow.run([0.25, 0.0], 0.0, 1.0, p)
    message = str(info.value)
    assert "[0.25, 0.0]" in message and "test_filippov" in message


def test_initial_fundamental_matrix_of_the_wrong_shape(trilinear_flow):
    """The kernel reads phi0 as n x n (n is a constant of the compiled model): another shape is refused."""
    p = trilinear_flow.parameters()
    with pytest.raises(ModelError, match=r"\(2, 2\), got \(3, 3\)"):
        trilinear_flow.run([0.1, 0.0], 0.0, 1.0, p, variational=True, phi0=np.eye(3))


def test_initial_state_on_the_wall(oscillator_flow):
    p = oscillator_flow.parameters({"a": 0.5})
    with pytest.raises(InitialModeError, match=r"\[0\.5, 0\.0\]"):
        oscillator_flow.run([0.5, 0.0], 0.0, 1.0, p)


def test_unknown_initial_mode(oscillator_flow):
    with pytest.raises(ModelError, match="nowhere"):
        oscillator_flow.run([0.0, 0.0], 0.0, 1.0, oscillator_flow.parameters(), mode0="nowhere")


def test_nan_at_the_start_names_the_mode(oscillator_flow):
    """Mode 'root' has the field [v, -sqrt(x)]: NaN for x < 0."""
    with pytest.raises(NonFiniteError, match="'root'"):
        oscillator_flow.run([-1.0, 0.0], 0.0, 1.0, oscillator_flow.parameters(), mode0="root")


def test_nan_on_the_way_names_the_mode(oscillator_flow):
    """From x = 1 moving down, x reaches 0 in finite time (x'' = -sqrt(x) < 0), then sqrt(x) is NaN."""
    with pytest.raises(NonFiniteError, match="'root'"):
        oscillator_flow.run([1.0, -1.0], 0.0, 5.0, oscillator_flow.parameters(), mode0="root")


def test_a_transition_into_a_mode_whose_domain_excludes_the_state(oscillator_flow):
    """'above' begins at x = a + gap but the transition into it fires at the wall x = a, and no transition
    leaves it there: the run stops and names the mode and the transition, instead of going on."""
    p = oscillator_flow.parameters({"gap": 0.3})
    with pytest.raises(ModelError, match=r"after 'below' -> 'above' on surface 'wall' lies outside the domain of mode 'above'"):
        oscillator_flow.run([0.0, 1.0], 0.0, 2.0, p)
    # consistent domains (gap = 0): the same run crosses the wall
    traj = oscillator_flow.run([0.0, 1.0], 0.0, 2.0, oscillator_flow.parameters())
    assert [(e.mode_from, e.mode_to) for e in traj.events][:1] == [("below", "above")]


def test_zeno_bouncing_ball_is_chattering(oscillator_flow):
    """Restitution e = 1/2: the impact times accumulate at t = sqrt(2) (1 + 2e / (1 - e)) = 3 sqrt(2)."""
    p = oscillator_flow.parameters({"w": 0.0, "g": 1.0, "e": 0.5})
    with pytest.raises(ChatteringError, match="'floor'"):
        oscillator_flow.run([1.0, 0.0], 0.0, 10.0, p, mode0="ball")


def test_max_events_is_chattering(trilinear_flow):
    p = trilinear_flow.parameters({"omega": 1.0})
    with pytest.raises(ChatteringError, match="max_events"):
        trilinear_flow.run([0.0, 0.0], 0.0, 200.0, p, tolerances=Tolerances(max_events=3))


# ----------------------------------------------------------------- Newton
def test_shooting_that_does_not_converge(belt_flow):
    """From a state near the equilibrium (inside the unstable cycle) there is no cycle to converge to."""
    p = belt_flow.parameters()
    guess = belt_flow.run([0.0, 0.0], 0.0, 100.0, p).x1  # spirals to the equilibrium [1, 0]
    assert np.linalg.norm(guess - [1.0, 0.0]) < 0.05
    with pytest.raises(ConvergenceError) as info:
        find_periodic_orbit(belt_flow, guess, period=6.5, max_iter=8)
    err = info.value
    assert len(err.residuals) >= 2
    assert all(np.isfinite(err.residuals))
    assert min(err.residuals) > 1e-10 * (1 + np.linalg.norm(guess))  # never converged
    assert "block_on_belt" in str(err)


def test_impacts_accumulating_on_a_moving_table_are_chattering():
    """A ball thrown up from a vibrating table (A = 0.36, e = 0.5) comes to rest on it: its impacts
    accumulate (their intervals shrink like e^k) below the resolution of the state.  Without a sticking
    contact the run stops with ChatteringError, naming the surface and where the ball comes to rest; it used to
    go on and let the ball fall through the table.  The shipped model's impact sticks (sticks=True): the run
    jumps to each accumulation point and goes on with the table (tests/engine/test_complete_chatter.py)."""
    from saltation import Flow
    from saltation.models import bouncing_ball

    ball = bouncing_ball()
    loose = PiecewiseSystem(name="bouncing_ball_no_sticking", states=["y", "v"], parameters=dict(ball.defaults),
                            modes=[Mode("flight", ["v", "-g"])], surfaces={"table": "y - A*sin(omega*t)"},
                            transitions=[Transition("flight", "table", Crossing.FALLING, "flight",
                                                    reset=["y", "(1 + e)*A*omega*cos(omega*t) - e*v"])],
                            period="2*pi/omega")
    flow = Flow(loose)
    with pytest.raises(ChatteringError, match=r"'table'.*accumulate \(Zeno\) at t = 1\.0998308\d*.*comes to rest"):
        flow.run([0.0, 3.0], 0.0, 3.0, flow.parameters({"A": 0.36}))
    sticking = Flow(ball)
    run = sticking.run([0.0, 3.0], 0.0, 3.0, sticking.parameters({"A": 0.36}))
    assert run.accumulations[0].t == pytest.approx(1.0998308812, abs=1e-9)
    assert run.mode1 == "flight@table"