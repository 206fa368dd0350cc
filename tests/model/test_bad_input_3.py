"""Bad input to the Lyapunov exponents, the pseudo-equilibria, multiple shooting and symmetries is refused up
front with an error naming the argument and what it must be: no crash of an internal variable, no run that never
returns, no accuracy of 0 from a run too short to estimate one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from saltation.errors import ModelError, SaltationError
from saltation.orbits.lyapunov import MAX_INTERVALS, MIN_BLOCK, lyapunov_exponents

OMEGA = 0.7
#: the trilinear model's forcing period at omega = 0.7
PERIOD = 2.0 * math.pi / OMEGA


# --------------------------------------------------------------------------------------------------------------
# Lyapunov exponents
# --------------------------------------------------------------------------------------------------------------

def _lyapunov(flow, **kwargs):
    return lyapunov_exponents(flow, [0.1, 0.0], parameters={"omega": OMEGA}, **kwargs)


@pytest.mark.parametrize("t0", [math.nan, math.inf, -math.inf])
def test_a_start_time_that_is_not_finite_is_named(trilinear_flow, t0):
    with pytest.raises(ModelError, match=r"t0 \(the start time\) must be finite"):
        _lyapunov(trilinear_flow, time=100.0, t0=t0)


@pytest.mark.parametrize("blocks", [math.nan, None, 2.5, "ten", True, 1, 10**7])
def test_blocks_must_be_an_integer_from_2_to_the_cap(trilinear_flow, blocks):
    with pytest.raises(ModelError, match=rf"blocks must be an integer from 2 to {MAX_INTERVALS}") as info:
        _lyapunov(trilinear_flow, time=100.0, blocks=blocks)
    assert repr(blocks) in str(info.value)
    assert MAX_INTERVALS == 10**6


@pytest.mark.parametrize("time", [None, "long", True])
def test_a_time_that_is_not_a_number_is_named(trilinear_flow, time):
    with pytest.raises(ModelError, match="time must be a real number"):
        _lyapunov(trilinear_flow, time=time)


@pytest.mark.parametrize("time", [1e-300, 0.5, 10.0])
def test_a_run_too_short_to_estimate_an_accuracy_is_refused(trilinear_flow, time):
    """Ten blocks of a run of 0.5 see the same part of the forcing period: an accuracy of 0 (1e-300) or a twentieth
    of the error (0.5) would be reported.  Each block must cover half the forcing period 2 pi / omega: the shortest
    time is 10 pi / omega."""
    with pytest.raises(ModelError, match="too short to estimate an accuracy") as info:
        _lyapunov(trilinear_flow, time=time)
    shortest = 10 * MIN_BLOCK * PERIOD
    assert shortest == pytest.approx(10 * math.pi / OMEGA, rel=1e-15)
    assert f"time must be at least {shortest:g}" in str(info.value)


def test_the_shortest_accepted_run_has_an_honest_accuracy(trilinear_flow):
    """At the shortest time (ten blocks of half a forcing period) the linear oscillator's exponents, both -c/(2m) =
    -0.025, are within three times the stated accuracy, which is not 0."""
    result = _lyapunov(trilinear_flow, time=10 * MIN_BLOCK * PERIOD)
    assert np.all(result.accuracy > 0)
    assert np.all(np.abs(result.exponents + 0.025) <= 3 * result.accuracy)


def test_an_autonomous_model_needs_half_a_time_unit_a_block(belt_flow):
    """An autonomous model's time scale is one time unit: four blocks need a time of at least 4 / 2 = 2."""
    with pytest.raises(ModelError, match=r"at least 0.5 times a time unit .* so time must be at least 2$"):
        lyapunov_exponents(belt_flow, [0.5, 0.0], time=1.9, blocks=4)


@pytest.mark.parametrize(("kwargs", "culprit", "count"), [
    ({"time": 1e300}, "time", 1e300 / PERIOD),
    ({"time": 100.0, "interval": 1e-300}, "interval", 1e302),
    ({"time": 1e300, "interval": 1e-300}, "interval", math.inf),  # (time / interval overflows)
    ({"time": 100.0, "interval": 1e-5}, "interval", 1e7),
])
def test_a_run_of_more_intervals_than_the_cap_is_refused_up_front(trilinear_flow, kwargs, culprit, count):
    """The number of intervals is time / interval (the forcing period by default), refused above a million."""
    with pytest.raises(ModelError, match=rf"^{culprit}: .* takes (\S+) intervals, more than the 1000000") as info:
        _lyapunov(trilinear_flow, **kwargs)
    stated = float(str(info.value).split(" takes ")[1].split()[0])
    assert stated == pytest.approx(count, rel=1e-2) if math.isfinite(count) else stated == math.inf


def test_intervals_the_clock_cannot_resolve_are_refused(trilinear_flow):
    """At t0 = 1e20 an interval of 5 (100 / 10 blocks, below the forcing period) does not move the clock."""
    with pytest.raises(ModelError, match=r"intervals of 5 .* below 1e-09 of the run's largest time .* = 1e\+20"):
        _lyapunov(trilinear_flow, time=100.0, t0=1e20)


def test_the_command_refuses_a_run_that_would_not_end(capsys):
    from saltation.apps import cli

    assert cli.main(["lyapunov", "trilinear", "--time", "1e300", "--x0", "0.5,0.5"]) == 2
    err = capsys.readouterr().err
    assert "--time" in err and "intervals, more than the 1000000" in err
    assert cli.main(["lyapunov", "trilinear", "--time", "0.5", "--x0", "0.5,0.5"]) == 2
    err = capsys.readouterr().err
    # omega = 1.2 by default: ten blocks of half the forcing period 2 pi / 1.2
    assert "too short to estimate an accuracy" in err and f"--time must be at least {10 * math.pi / 1.2:g}" in err


# --------------------------------------------------------------------------------------------------------------
# Pseudo-equilibria
# --------------------------------------------------------------------------------------------------------------

def _relay():
    """x' = 1 (x < 0) or -2 (x > 0), y' = -y + 1/2 or -y - 3/10: a pseudo-equilibrium at y = (2 (1/2) - 3/10) / 3."""
    from saltation import Crossing, Mode, PiecewiseSystem, Transition

    return PiecewiseSystem(
        "test_bad_input_relay", states=["x", "y"], parameters={"a": 1.0, "b": 2.0, "c": 0.5, "d": 0.3},
        modes=[Mode("left", ["a", "-y + c"], domain=["x < 0"]), Mode("right", ["-b", "-y - d"], domain=["x >= 0"])],
        surfaces={"s": "x"},
        transitions=[Transition("left", "s", Crossing.RISING, "right"),
                     Transition("right", "s", Crossing.FALLING, "left")])


def _vanishing():
    """x' = x, y' = -y (x < 0) and x' = -x, y' = -y (x > 0): both fields vanish at the origin, on the surface x = 0,
    where both components normal to it are 0 (the sliding weight 0/0)."""
    from saltation import Crossing, Mode, PiecewiseSystem, Transition

    return PiecewiseSystem(
        "test_bad_input_vanishing", states=["x", "y"], parameters={"a": 1.0},
        modes=[Mode("left", ["a*x", "-y"], domain=["x < 0"]), Mode("right", ["-a*x", "-y"], domain=["x >= 0"])],
        surfaces={"s": "x"},
        transitions=[Transition("left", "s", Crossing.RISING, "right"),
                     Transition("right", "s", Crossing.FALLING, "left")])


@pytest.fixture(scope="module")
def relay_flow():
    from saltation import Flow

    return Flow(_relay())


@pytest.mark.parametrize("guess", [[math.nan, 1.0], [0.0, math.nan], [math.inf, 0.0]])
def test_a_guess_that_is_not_finite_is_named(relay_flow, guess):
    from saltation.orbits.pseudo_equilibria import find_pseudo_equilibrium

    with pytest.raises(ModelError, match="the guess is not finite"):
        find_pseudo_equilibrium(relay_flow, "s", guess)


@pytest.mark.parametrize("tol", [math.nan, -1.0, 0.0, math.inf, None, "small"])
def test_tol_must_be_positive(relay_flow, tol):
    from saltation.orbits.pseudo_equilibria import find_pseudo_equilibrium

    with pytest.raises(ModelError, match="tol must be positive and finite") as info:
        find_pseudo_equilibrium(relay_flow, "s", [0.1, 1.0], tol=tol)
    assert repr(tol) in str(info.value)


@pytest.mark.parametrize("max_iter", [-1, 2.5, math.nan, None])
def test_max_iter_must_be_a_non_negative_integer(relay_flow, max_iter):
    from saltation.orbits.pseudo_equilibria import find_pseudo_equilibrium

    with pytest.raises(ModelError, match="max_iter must be a non-negative integer"):
        find_pseudo_equilibrium(relay_flow, "s", [0.1, 1.0], max_iter=max_iter)


def test_a_good_call_still_finds_the_closed_form(relay_flow):
    from saltation.orbits.pseudo_equilibria import find_pseudo_equilibrium

    point = find_pseudo_equilibrium(relay_flow, "s", [0.1, 1.0], tol=1e-12, max_iter=30)
    np.testing.assert_allclose(point.state, [0.0, (2.0 * 0.5 - 1.0 * 0.3) / 3.0], rtol=0, atol=1e-12)
    assert point.weights == pytest.approx((2 / 3, 1 / 3), abs=1e-12)


def test_two_fields_that_vanish_on_the_surface_leave_the_weight_undefined():
    """Newton lands on the origin, an equilibrium of both modes: every weight makes the combination vanish there,
    and next to it on the surface both normal components are 0."""
    from saltation import Flow
    from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem, find_pseudo_equilibrium

    flow = Flow(_vanishing())
    with pytest.raises(ModelError, match="both fields vanish here: the sliding weight is undefined") as info:
        find_pseudo_equilibrium(flow, "s", [0.1, 1.0])
    assert "[0.0, 0.0]" in str(info.value) and "'left' and 'right'" in str(info.value)
    problem = PseudoEquilibriumProblem(flow, "s", ("left", "right"))
    u = np.array([0.0, 0.0, 0.5])
    with pytest.raises(ModelError, match="both fields vanish here: the sliding weight is undefined"):
        problem.describe(u, None, problem.evaluate(u, need_lam=False))


# --------------------------------------------------------------------------------------------------------------
# Multiple shooting and symmetry
# --------------------------------------------------------------------------------------------------------------

BAD_SEGMENTS = [math.nan, math.inf, 2**63, 10**6, 1001, 0, -3, 2.5, None, "3", True]


@pytest.mark.parametrize("segments", BAD_SEGMENTS)
def test_segments_must_be_a_positive_integer_up_to_the_cap(trilinear_flow, segments):
    from saltation.orbits.shooting import MAX_SEGMENTS, MultipleShootingProblem, ShootingProblem

    assert MAX_SEGMENTS == 1000
    problem = ShootingProblem(trilinear_flow)
    with pytest.raises(ModelError, match=r"segments must be a positive integer of at most 1000 \(each segment holds "
                                         r"an n x n transfer matrix") as info:
        MultipleShootingProblem(problem, segments)
    assert f"got {segments!r}" in str(info.value)


@pytest.mark.parametrize("segments", BAD_SEGMENTS)
def test_find_periodic_orbit_checks_segments_before_any_work(trilinear_flow, segments):
    from saltation.orbits.shooting import find_periodic_orbit

    with pytest.raises(ModelError, match="segments must be a positive integer of at most 1000"):
        find_periodic_orbit(trilinear_flow, None, segments=segments)  # (a guess would need a transient)


def test_the_cap_says_why_in_closed_form():
    """1000 segments bring a multiplier of 1e300 down to 1e300 ** (1 / 1000) = 10 ** 0.3, about 2, per segment."""
    from saltation.orbits.shooting import MAX_SEGMENTS

    assert (1e300) ** (1 / MAX_SEGMENTS) == pytest.approx(10**0.3, rel=1e-12)
    assert round(10**0.3) == 2


def test_a_large_model_is_held_to_its_node_values():
    """A chain of 5 masses has 10 states: 500 segments make 5000 node values, more than the 4000 of a dense Newton
    matrix of 128 MB; at most 4000 // 10 = 400 segments."""
    from saltation.orbits.shooting import MAX_NODE_VALUES, check_segments

    assert MAX_NODE_VALUES == 4000 and (MAX_NODE_VALUES**2 * 8) / 1e6 == 128.0
    with pytest.raises(ModelError, match=r"segments = 500 with 10 states makes 5000 node values, more than the 4000 "
                                         r".* at most 400 segments for this model"):
        check_segments(500, 10)
    assert check_segments(400, 10) == 400 and check_segments(3.0) == 3


def test_good_segments_still_find_the_orbit(trilinear_flow):
    """Multiple shooting with 3 segments finds the orbit single shooting finds."""
    from saltation.orbits.shooting import find_periodic_orbit

    single = find_periodic_orbit(trilinear_flow, [0.5, 0.5])
    multiple = find_periodic_orbit(trilinear_flow, [0.5, 0.5], segments=3)
    assert multiple.segments == 3
    np.testing.assert_allclose(multiple.state0, single.state0, rtol=0, atol=1e-8)


@pytest.mark.parametrize("command", [
    ["orbit", "trilinear", "--x0", "0.5,0.5"],
    ["continue", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.7", "--no-progress"],
    ["locus", "trilinear", "--kind", "fold", "--param", "omega", "--range", "0.6,1.6", "--param2", "f0",
     "--range2", "0.1,0.3"],
])
@pytest.mark.parametrize("value", ["100000", "1001", "0", "nan", "2.5"])
def test_the_command_line_refuses_segments_out_of_range(capsys, command, value):
    from saltation.apps import cli

    assert cli.main([*command, "--segments", value]) == 2
    err = capsys.readouterr().err
    assert "--segments" in err and "internal error" not in err and "MemoryError" not in err
    if value in ("100000", "1001"):
        assert "above the largest accepted value 1000" in err and "n x n transfer matrix" in err


@pytest.mark.parametrize("signs", ["ab", None, -1, 1.0, [1, 2], [0, 1], [[1, -1]], [], [1, "a"], {1: -1}])
def test_symmetry_signs_must_be_plus_and_minus_ones(signs):
    from saltation.model.symmetry import Symmetry

    with pytest.raises(ModelError, match=r"signs must be a list of \+1 and -1, one per state") as info:
        Symmetry.of_signs(signs)
    assert repr(signs) in str(info.value)


def test_good_signs_make_the_diagonal_symmetry():
    from saltation.model.symmetry import Symmetry

    assert Symmetry.of_signs([-1, 1.0]).matrix == ((-1.0, 0.0), (0.0, 1.0))
    assert Symmetry.of_signs((-1, -1)).matrix == ((-1.0, 0.0), (0.0, -1.0))


def test_a_band_narrower_than_the_state_resolution_is_refused():
    """block_on_belt with ``eta = 1e-16`` (half an ulp of ``v_dr = 1``) ran onto the equilibrium without an error;
    the band between ``band_upper`` and ``band_lower`` (``h_u - h_l = -2 eta``) is no wider than the resolution of
    its edges there (16 rounding units of ``|v| + |v_dr| + |eta|``, 7.1e-15): a named error.  A band above it runs,
    and its stick-slip orbit is the one of wider bands (the trajectory from the same start at eta = 1e-14 and
    1e-10 agree to the integration's accuracy)."""
    from saltation import Flow
    from saltation.errors import ModelError
    from saltation.models import block_on_belt

    flow = Flow(block_on_belt())
    with pytest.raises(ModelError, match=r"band between surfaces 'band_upper' and 'band_lower' is 2e-16 wide.*eta"):
        flow.run([0.0, 1.0], 0.0, 100.0, flow.parameters({"eta": 1e-16}))
    narrow = flow.run([0.0, 1.0], 0.0, 100.0, flow.parameters({"eta": 1e-14})).x1
    wide = flow.run([0.0, 1.0], 0.0, 100.0, flow.parameters({"eta": 1e-10})).x1
    # the band's width moves the orbit by O(eta); the integration's error over 100 time units is below 1e-7
    np.testing.assert_allclose(narrow, wide, atol=1e-7)
