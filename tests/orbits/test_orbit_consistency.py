"""Periodic orbits that agree with themselves, from the most natural (and most degenerate) guesses.

References: the Floquet multipliers of the same cycle from a guess off the switching surface (a
different section, a different Newton path), closed-form equilibria, the forcing period, and the
eigenvalues of matrices built with a known eigenstructure.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import (
    Crossing,
    Flow,
    InconsistentResultError,
    Mode,
    ModelError,
    PiecewiseSystem,
    SaltationError,
    ShootingProblem,
    StationaryStateError,
    Transition,
    find_periodic_orbit,
)
from saltation.models import block_on_belt, trilinear
from saltation.orbits.floquet import autonomous_multipliers
from saltation.orbits.shooting import TRIVIAL_MULTIPLIER_ACCURACY, newton


def vdp_friction() -> PiecewiseSystem:
    """``x'' - eps (1 - x^2) x' + x + mu sgn(x') = 0``, the surface ``v = 0`` listed both ways."""
    return PiecewiseSystem(
        name="vdp_friction_consistency",
        states=["x", "v"],
        parameters={"eps": 0.5, "mu": 0.2},
        modes=[
            Mode("plus", ["v", "eps*(1 - x**2)*v - x - mu"], domain=["v > 0"]),
            Mode("minus", ["v", "eps*(1 - x**2)*v - x + mu"]),
        ],
        surfaces={"v0": "v"},
        transitions=[
            Transition("plus", "v0", Crossing.FALLING, "minus"),
            Transition("minus", "v0", Crossing.RISING, "plus"),
        ],
    )


@pytest.fixture(scope="module")
def vdp_flow() -> Flow:
    return Flow(vdp_friction())


@pytest.fixture(scope="module")
def off_surface_orbit(vdp_flow):
    """The stable cycle from a guess off the surface: the reference for the degenerate starts."""
    return find_periodic_orbit(vdp_flow, [2.0, 0.5], period=7.0)


def _newton_on_the_surface(flow: Flow) -> tuple[ShootingProblem, np.ndarray, list, object]:
    """Shooting with the phase condition anchored at the turning point (2, 0): its hyperplane is the
    switching surface v = 0 itself, so Newton keeps the state on the surface (what the guess's own
    relocation avoids)."""
    prob = ShootingProblem(flow)
    u0 = prob.pack([2.0, 0.0], 7.0)
    prob.set_phase_reference(u0)

    def fun(u):
        ev = prob.evaluate(u, need_lam=False)
        return ev.residual, ev.jac_u, ev

    u, history, ev = newton(fun, u0, damped=True)
    return prob, u, history, ev


def test_a_state_on_the_surface_keeps_every_saltation_matrix_in_the_monodromy(vdp_flow, off_surface_orbit):
    prob, u, history, ev = _newton_on_the_surface(vdp_flow)
    assert abs(u[1]) <= 1e-12  # the state lies on v = 0, as the phase condition says
    orbit = prob.orbit(u, None, ev.trajectory, history)
    # the crossing at t0 + T is applied and logged: one crossing each way per period
    assert sorted(e.mode_to for e in orbit.events) == ["minus", "plus"]
    assert orbit.events[-1].t == pytest.approx(orbit.t0 + orbit.period, abs=1e-12)
    np.testing.assert_allclose(orbit.period, off_surface_orbit.period, rtol=1e-10)
    np.testing.assert_allclose(orbit.multipliers, off_surface_orbit.multipliers, atol=1e-8)
    assert orbit.trivial_multiplier_error <= 1e-8


def test_a_monodromy_without_the_crossing_is_an_error_not_a_printout(vdp_flow, monkeypatch):
    """With the crossing at the end left out (as before it was applied), the trivial multiplier is
    1.27: the orbit is refused, not printed."""
    monkeypatch.setattr(ShootingProblem, "close_period", lambda self, traj, p, sensitivity=-1: traj)
    prob, u, history, ev = _newton_on_the_surface(vdp_flow)
    with pytest.raises(InconsistentResultError, match="trivial multiplier"):
        prob.orbit(u, None, ev.trajectory, history)


def test_a_guess_at_a_turning_point_on_the_surface_finds_the_cycle(vdp_flow, off_surface_orbit):
    orbit = find_periodic_orbit(vdp_flow, [2.0, 0.0], period=7.0)
    np.testing.assert_allclose(orbit.period, off_surface_orbit.period, rtol=1e-10)
    np.testing.assert_allclose(orbit.multipliers, off_surface_orbit.multipliers, atol=1e-8)
    assert len(orbit.events) == 2 and orbit.trivial_multiplier_error <= 1e-8
    # the shooting state was moved off the surface, along the guess's own trajectory
    assert abs(orbit.state0[1]) > 0.1


def test_the_equilibrium_of_the_block_on_a_belt_is_not_an_orbit():
    """At v_dr = 2 shooting from (2, 0) converges to the equilibrium [F_slip / k, 0] of eq. (15)."""
    flow = Flow(block_on_belt())
    with pytest.raises(StationaryStateError, match="equilibrium") as info:
        find_periodic_orbit(flow, [2.0, 0.0], parameters={"v_dr": 2.0}, period=6.3)
    np.testing.assert_allclose(info.value.state, [1.0, 0.0], atol=1e-9)


@pytest.mark.parametrize("period", [1e-300, 1e-12, 0.5, 2.0])
def test_a_period_near_zero_is_never_an_orbit(period):
    """From a state of the stick-slip cycle, a short period guess gives the cycle or a named error."""
    flow = Flow(block_on_belt())
    p = flow.parameters()
    start = flow.run([0.0, 1.0], 0.0, 40.0, p).x1
    cycle = find_periodic_orbit(flow, start, period=6.4)
    try:
        orbit = find_periodic_orbit(flow, start, period=period)
    except (StationaryStateError, SaltationError) as exc:
        assert isinstance(exc, SaltationError)
        return
    assert orbit.period == pytest.approx(cycle.period, rel=1e-9)


def test_a_guess_at_an_equilibrium_is_named():
    flow = Flow(block_on_belt())
    with pytest.raises(StationaryStateError, match="equilibrium"):
        find_periodic_orbit(flow, [1.0, 0.0], period=6.3)


def test_a_forced_orbit_far_from_t0_zero_is_the_same_orbit():
    """t0 = 1e12 is reduced modulo the forcing period: the orbit there is the orbit at t0 = 0,
    integrated to that phase (exact affine flows: rounding)."""
    flow = Flow(trilinear())
    p = flow.parameters({"omega": 1.2})
    near = find_periodic_orbit(flow, [0.5, 0.5], parameters={"omega": 1.2})
    far = find_periodic_orbit(flow, [0.5, 0.5], parameters={"omega": 1.2}, t0=1e12)
    np.testing.assert_allclose(far.multipliers, near.multipliers, rtol=0, atol=1e-12)
    phase = math.fmod(1e12, 2 * math.pi / 1.2)
    on_orbit = flow.run(near.state0, 0.0, phase, p).x1
    np.testing.assert_allclose(far.state0, on_orbit, rtol=0, atol=1e-12)


def test_a_period_that_contradicts_the_forcing_is_refused():
    flow = Flow(trilinear())
    with pytest.raises(ModelError, match="forcing period 5.23598"):
        find_periodic_orbit(flow, [0.5, 0.5], parameters={"omega": 1.2}, period=5.0)
    orbit = find_periodic_orbit(flow, [0.5, 0.5], parameters={"omega": 1.2}, period=2 * math.pi / 1.2)
    assert orbit.period == pytest.approx(2 * math.pi / 1.2, rel=1e-15)


def test_deflated_multipliers_have_the_known_eigenstructure():
    """``M = R [[1, a], [0, mu]] R^-1`` maps ``f = R e1`` to itself: the deflated multipliers are
    exactly ``(1, mu)``; a two-state fold ``mu = 1`` reads 1 and 1, where the full matrix's double
    eigenvalue under a perturbation of 1e-12 splits into a complex pair."""
    rng = np.random.default_rng(3)
    for mu in (0.3, -0.8, 1.0, 2.5):
        R = rng.normal(size=(2, 2))
        M = R @ np.array([[1.0, 0.7], [0.0, mu]]) @ np.linalg.inv(R)
        found = autonomous_multipliers(M, R[:, 0])
        np.testing.assert_allclose(sorted(found.multipliers.real), sorted([1.0, mu]), atol=1e-12)
        assert np.all(found.multipliers.imag == 0.0) and found.trivial_error <= 1e-12
    fold = np.array([[1.0, 1.0], [-1e-12, 1.0]])  # a Jordan block at a fold, with rounding
    assert np.all(np.abs(np.linalg.eigvals(fold).imag) > 1e-7)  # 1 +- 1e-6 i
    found = autonomous_multipliers(fold, np.array([1.0, 0.0]))
    np.testing.assert_allclose(found.multipliers, [1.0, 1.0], atol=1e-11)
    # three states: a complex pair on the section
    A = np.array([[1.0, 0.2, 0.1], [0.0, 0.5, -0.4], [0.0, 0.4, 0.5]])
    R = rng.normal(size=(3, 3))
    found = autonomous_multipliers(R @ A @ np.linalg.inv(R), R[:, 0])
    np.testing.assert_allclose(sorted(found.multipliers, key=lambda z: z.imag), [0.5 - 0.4j, 1.0, 0.5 + 0.4j], atol=1e-12)
    with pytest.raises(ValueError, match="velocity is zero"):
        autonomous_multipliers(np.eye(2), np.zeros(2))


def test_backward_multipliers_zero_to_the_monodromy_accuracy_are_infinite():
    M = np.array([[1.0, 0.3], [1e-12, 5e-13]])  # |M n - n| = 1e-12: the small eigenvalue is that uncertain
    found = autonomous_multipliers(M, np.array([1.0, 0.0]), backward=True)
    assert np.isinf(found.multipliers).sum() == 1


def test_every_fold_of_the_paper_diagram_has_a_multiplier_at_one():
    from saltation.apps.paper import trilinear_diagram

    for sp in trilinear_diagram().special_points:
        if sp.kind.value == "fold":
            assert np.min(np.abs(sp.multipliers - 1.0)) <= sp.multipliers_accuracy
            assert sp.multipliers_accuracy < 1e-6


def test_trivial_multiplier_accuracy_is_what_the_issue_promised():
    assert TRIVIAL_MULTIPLIER_ACCURACY <= 1e-6


def test_a_forced_model_has_no_equilibria():
    from saltation.orbits.shooting import EquilibriumProblem

    with pytest.raises(ModelError, match="forced"):
        EquilibriumProblem(Flow(trilinear()), "free")


def test_a_forcing_period_that_divides_by_zero_is_a_model_error():
    system = trilinear()
    with pytest.raises(ModelError, match="forcing period"):
        system.forcing_period(system.parameter_vector({"omega": 0.0}))


def test_a_guess_that_comes_to_rest_in_the_sticking_set_is_named(vdp_flow):
    """Beyond the fold (mu = 0.2975) there is no cycle: the flow from (2, 0) passes the ghost of the
    cycle and sticks on v = 0 inside the sticking set |x| <= mu, where the motion stops."""
    with pytest.raises(StationaryStateError, match="pseudo-equilibrium") as info:
        find_periodic_orbit(vdp_flow, [2.0, 0.0], parameters={"mu": 0.3}, period=7.0)
    x, v = info.value.state
    assert abs(v) <= 1e-12 and abs(x) <= 0.3


def test_a_sliding_motion_that_ends_at_the_seam_is_logged_with_the_engines_saltation_matrix():
    """The forced friction oscillator sticks once per period (v_b = 1).  Shot from the instant the
    stick ends, the exit falls on the seam: it is logged once, at t0 + T, and its saltation matrix equals
    the one the engine logs at the same exit from an earlier start (both the identity: at a tangential
    exit the sliding field equals the exit side's field); the multipliers agree."""
    from saltation.models import friction_oscillator

    flow = Flow(friction_oscillator())
    pars = {"v_b": 1.0}
    inside = find_periodic_orbit(flow, [0.3, 0.1], parameters=pars)
    exits = [e for e in inside.events if e.kind.name == "SLIDING_END"]
    assert len(exits) == 1
    exit_ = exits[0]
    seam = find_periodic_orbit(flow, exit_.x_plus, parameters=pars, t0=exit_.t)
    last = seam.events[-1]
    assert last.kind.name == "SLIDING_END" and last.t == pytest.approx(seam.t0 + seam.period, abs=1e-12)
    assert [e.kind for e in seam.events].count(last.kind) == 1
    np.testing.assert_allclose(last.saltation, exit_.saltation, rtol=0, atol=1e-9)
    np.testing.assert_allclose(seam.multipliers, inside.multipliers, rtol=0, atol=1e-9)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=4, max_size=4), st.floats(0, 2 * math.pi), st.floats(1e-3, 1e3))
def test_planar_deflation_matches_the_general_path(entries, angle, speed):
    """The two-state multipliers (plain floats) against the general Householder path on the same
    matrix embedded in three states, ``diag(M, 0.25)`` with ``f = (f, 0)``: the extra multiplier is
    0.25 and the other two must agree to rounding; backward, each is the reciprocal of its forward one
    (or infinite, at or below the trivial error).

    Each multiplier, and ``|M n - n|``, is a quadratic form of ``M`` in unit vectors in either path: a
    few products and sums of entries no larger than ``scale``, each rounded, so the two differ by a few
    rounding units of ``scale`` (64 allowed); a backward multiplier is one complex division more."""
    eps = np.finfo(float).eps
    M = np.array(entries, dtype=float).reshape(2, 2)
    f = speed * np.array([math.cos(angle), math.sin(angle)])
    two = autonomous_multipliers(M, f)
    M3 = np.zeros((3, 3))
    M3[:2, :2] = M
    M3[2, 2] = 0.25
    three = autonomous_multipliers(M3, np.append(f, 0.0))
    rest = list(three.multipliers)
    rest.pop(int(np.argmin([abs(m - 0.25) for m in rest])))
    scale = 1.0 + float(np.abs(M).max())
    assert abs(two.trivial_error - three.trivial_error) <= 64 * eps * scale
    # matched by value, not by a sort: two multipliers of equal magnitude may swap places under rounding
    assert max(min(abs(a - b) for b in rest) for a in two.multipliers) <= 64 * eps * scale
    assert max(min(abs(a - b) for a in two.multipliers) for b in rest) <= 64 * eps * scale
    back = autonomous_multipliers(M, f, backward=True)
    zero = max(1e-13, two.trivial_error)
    expected = [complex(np.inf) if abs(m) <= zero else 1.0 / m for m in two.multipliers]
    for a in back.multipliers:
        assert any((np.isinf(a) and np.isinf(b)) or abs(a - b) <= 4 * eps * abs(b) for b in expected)
    assert sorted(np.isinf(back.multipliers)) == sorted(np.isinf(expected))
