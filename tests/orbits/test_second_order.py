"""Second derivatives of the period map through the events (saltation.orbits.second_order), and the
criticality of period doublings and Neimark-Sacker points from them (saltation.orbits.criticality).

References, each independent of the second-order composition:

* the second derivatives against central differences (with Richardson extrapolation) of the engine's own
  first derivatives, the monodromy matrices with the saltation matrices of eq. (9), at states moved off the
  orbit: impacts (resets), plain switches, Filippov sliding, a smooth forced model, an autonomous orbit's
  time-T map and its Poincare map (whose first derivative is built from engine runs to the section);
* the flow-to-section jet against the closed form of a straight flow reaching a circle (hypothesis, down to
  nearly tangent arrivals);
* the period-doubling coefficient against the period-2 branch that the library follows from the point
  (``follow_period_doubled_branch``): its side and stability, and its size, ``-(1 + mu(p)) / xi^2 -> b``
  (``xi`` half the distance between the two points of the period-2 orbit, ``mu(p)`` the period-1 orbit's
  multiplier at the same parameter): a supercritical doubling (the bouncing ball) and a subcritical one
  (two masses between compliant stops);
* closed forms: a system whose Poincare map is, in a rotating frame, the time-T map of ``w1' = a w1^3``
  (flip coefficient ``b = -a T``) or of the Hopf normal form ``w' = i omega w + c w |w|^2`` (first Lyapunov
  coefficient ``d = 2 Re(c) T``).
"""

from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import (
    Crossing,
    Flow,
    Mode,
    PiecewiseSystem,
    Transition,
    find_periodic_orbit,
)
from saltation.errors import InconsistentResultError, ModelError
from saltation.kinds import Criticality, SpecialPointKind
from saltation.models import (
    bouncing_ball,
    friction_oscillator,
    impact_oscillator,
    relay_feedback,
    trilinear,
    two_mass_stops,
)
from saltation.orbits.criticality import criticality, special_point_criticality
from saltation.orbits.second_order import (
    _to_section,
    period_map_derivatives,
    poincare_map_derivatives,
    section_basis,
)
from saltation.special_points.branch_switching import follow_period_doubled_branch
from saltation.special_points.continuation import ContinuationSettings, continue_orbit

TWO_PI = 2.0 * np.pi


def duffing() -> PiecewiseSystem:
    """The forced Duffing oscillator ``x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t)`` (smooth)."""
    return PiecewiseSystem(
        "test_second_order_duffing", states=["x", "v"],
        parameters={"delta": 0.1, "alpha": 1.0, "beta": 1.0, "gamma": 1.0, "omega": 1.0},
        modes=[Mode("smooth", ["v", "-delta*v - alpha*x - beta*x**3 + gamma*cos(omega*t)"])],
        surfaces={}, transitions=[], period="2*pi/omega",
    )


def clocked() -> PiecewiseSystem:
    """A clock ``(c, s)`` on its attracting unit circle (angular speed Omega, radial rate rho) driving ``u``.

    With ``half = 1``, ``u = R(theta) w`` with ``theta = Omega t / 2`` (the clock's half angle) and
    ``w1' = lam w1 + a w1^3``, ``w2' = -k w2``: the field of ``u`` is written with ``cos 2 theta = c`` and
    ``sin 2 theta = s`` (the cubic is odd, so only even multiples of ``theta`` appear).  The Poincare map on
    ``s = 0`` is ``u -> -w(T)``: a multiplier ``-e^{lam T}`` and, at ``lam = 0``, the flip coefficient
    ``b = -a T`` (``w1(T) = w1 / sqrt(1 - 2 a T w1^2)``).  With ``half = 0, a = k = 0``, ``u`` follows the
    Hopf normal form ``w' = (lam + i omega) w + (cr + i ci) w |w|^2``: multipliers ``e^{(lam +- i omega) T}``
    and, at ``lam = 0``, the first Lyapunov coefficient ``d = 2 cr T`` (``|w(T)|^2 = |w|^2 / (1 - 2 cr T
    |w|^2)``, with ``|q| = 1``: ``w = sqrt(2) zeta``).  The same field on both sides of ``c = 0``: two
    plain switches a period.
    """
    C, S = "(half*c + 1 - half)", "(half*s)"
    r2 = "(u1**2 + u2**2)"
    e2 = f"((u1**2 + u2**2) + {C}*(u1**2 - u2**2) + 2*{S}*u1*u2)/2"  # (e . u)^2, e = (cos theta, sin theta)
    Mu1, Mu2 = f"({C}*u1 + {S}*u2)", f"({S}*u1 - {C}*u2)"  # [[C, S], [S, -C]] u
    f1 = (f"-half*Omega/2*u2 + (lam - k)/2*u1 + (lam + k)/2*{Mu1} + a/2*{e2}*(u1 + {Mu1})"
          f" - omega*u2 + {r2}*(cr*u1 - ci*u2)")
    f2 = (f"half*Omega/2*u1 + (lam - k)/2*u2 + (lam + k)/2*{Mu2} + a/2*{e2}*(u2 + {Mu2})"
          f" + omega*u1 + {r2}*(ci*u1 + cr*u2)")
    field = ["-Omega*s + rho*c*(1 - c**2 - s**2)", "Omega*c + rho*s*(1 - c**2 - s**2)", f1, f2]
    return PiecewiseSystem(
        "test_second_order_clocked", states=["c", "s", "u1", "u2"],
        parameters={"Omega": 1.0, "rho": 1.0, "half": 1.0, "lam": 0.0, "k": 0.5, "a": -0.3, "omega": 0.0,
                    "cr": 0.0, "ci": 0.0},
        modes=[Mode("right", field, domain=["c > 0"]), Mode("left", field)],
        surfaces={"clock": "c"},
        transitions=[Transition("right", "clock", Crossing.FALLING, "left"),
                     Transition("left", "clock", Crossing.RISING, "right")],
    )


# ------------------------------------------------------------------------------ (a) against differences
def _bouncing_ball_state(A: float) -> np.ndarray:
    """The ball's period-1 orbit at t = 0 (closed form, see tests/special_points/test_branch_switching.py)."""
    g, e, w = 9.81, 0.5, TWO_PI
    T = TWO_PI / w
    t_i = np.arccos((1 - e) * np.pi * g / ((1 + e) * A * w**2)) / w
    tau = (-t_i) % T
    return np.array([A * np.sin(w * t_i) + g * T / 2 * tau - g * tau**2 / 2, g * T / 2 - g * tau])


ORBITS = {
    # an impact (a reset) once a period
    "impact_oscillator": lambda: find_periodic_orbit(Flow(impact_oscillator()), parameters={"s": 1.2, "omega": 0.8}),
    # four plain switches (contact made and lost at both supports)
    "trilinear": lambda: find_periodic_orbit(Flow(trilinear()), parameters={"f0": 1.0, "omega": 1.2}),
    # a Filippov sliding motion (stick) started and ended
    "friction_oscillator": lambda: find_periodic_orbit(Flow(friction_oscillator())),
    # smooth
    "duffing": lambda: find_periodic_orbit(Flow(duffing()), parameters={"gamma": 1.0, "omega": 1.2}),
    # an autonomous orbit's time-T map, two switches
    "relay_feedback": lambda: find_periodic_orbit(Flow(relay_feedback())),
}


@pytest.mark.parametrize("name", list(ORBITS))
def test_second_derivatives_against_differences_of_the_monodromy(name):
    orbit = ORBITS[name]()
    traj, flow, p = orbit.trajectory, orbit.problem.flow, orbit.parameters
    assert name == "duffing" or traj.events
    first, second = period_map_derivatives(orbit)
    np.testing.assert_allclose(first, orbit.monodromy, rtol=0, atol=1e-8 * (1 + np.abs(orbit.monodromy).max()))

    def monodromy(x):
        run = flow.run(x, traj.t0, traj.t1, p, mode0=traj.mode0, variational=True, tolerances=orbit.problem.tolerances)
        assert [e.signature for e in run.events] == [e.signature for e in traj.events]
        return run.monodromy

    h = 1e-4
    for j in range(len(orbit.state0)):
        e = np.eye(len(orbit.state0))[j]
        wide = (monodromy(orbit.state0 + h * e) - monodromy(orbit.state0 - h * e)) / (2 * h)
        narrow = (monodromy(orbit.state0 + h / 2 * e) - monodromy(orbit.state0 - h / 2 * e)) / h
        reference = (4 * narrow - wide) / 3  # O(h^4) left
        # the engine's monodromies are good to about 1e-10 (rtol): divided by h, 1e-6 at worst; they are
        # smooth in the state, so their differences do far better (1e-11 is typical)
        np.testing.assert_allclose(second[:, :, j], reference, rtol=0, atol=1e-6 * (1 + np.abs(second).max()))
    np.testing.assert_allclose(second, second.transpose(0, 2, 1), rtol=0, atol=1e-12 * (1 + np.abs(second).max()))


def test_poincare_map_against_differences_of_engine_returns():
    """The relay feedback system's Poincare map on the section through its state normal to the flow: the
    reference's first derivative at a state of the section is the engine's monodromy up to the return (found
    by Newton on engine runs), projected along the flow onto the section."""
    orbit = ORBITS["relay_feedback"]()
    flow, p = orbit.problem.flow, orbit.parameters
    d = poincare_map_derivatives(orbit)
    n, Q, x_star = d.normal, d.basis, orbit.state0
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(d.first).real), np.sort(orbit.multipliers.real[1:]), atol=1e-9)

    def first(y):
        x, tau = x_star + Q @ y, orbit.period
        for _ in range(20):
            run = flow.run(x, 0.0, tau, p, mode0=orbit.mode0, variational=True)
            step = -float(n @ (run.x1 - x_star)) / float(n @ run.velocity_end)
            tau += step
            if abs(step) < 1e-15 * tau:
                break
        run = flow.run(x, 0.0, tau, p, mode0=orbit.mode0, variational=True)
        f = run.velocity_end
        return Q.T @ (run.monodromy - np.outer(f, n @ run.monodromy) / float(n @ f)) @ Q

    h = 1e-4
    for j in range(2):
        e = np.eye(2)[j]
        reference = (4 * (first(h / 2 * e) - first(-h / 2 * e)) / h - (first(h * e) - first(-h * e)) / (2 * h)) / 3
        np.testing.assert_allclose(d.second[:, :, j], reference, rtol=0, atol=1e-6 * (1 + np.abs(d.second).max()))


def test_a_monodromy_that_disagrees_is_refused():
    orbit = ORBITS["impact_oscillator"]()
    wrong = replace(orbit, trajectory=replace(orbit.trajectory, monodromy=orbit.monodromy * 1.001))
    with pytest.raises(InconsistentResultError, match="monodromy"):
        period_map_derivatives(wrong)


def test_an_orbit_that_starts_in_a_sliding_motion():
    """The friction oscillator's orbit started inside its stick phase: the run starts its sliding motion at
    once (an event at t0, whose saltation matrix projects onto the surface), and the derivatives are those of
    that side, as the engine's monodromy is; the criticality's expansion moves off the sliding motion."""
    from saltation.orbits.criticality import _ReturnMap

    orbit = ORBITS["friction_oscillator"]()
    flow, p = orbit.problem.flow, orbit.parameters
    slide, leave = orbit.events[:2]
    t_mid = 0.5 * (slide.t + leave.t)
    mid = flow.run(orbit.state0, orbit.t0, t_mid, p, mode0=orbit.mode0)
    assert mid.sliding_at_end
    traj = flow.run(mid.x1, t_mid, t_mid + orbit.period, p, mode0=mid.mode1, variational=True)
    assert traj.events[0].t == t_mid and traj.events[0].kind.name == "SLIDING_START"
    moved = replace(orbit, trajectory=traj, state0=mid.x1, t0=t_mid, monodromy=traj.monodromy, mode0=mid.mode1)
    first, second = period_map_derivatives(moved)
    np.testing.assert_allclose(first, traj.monodromy, rtol=0, atol=1e-9)
    np.testing.assert_allclose(second[1], 0.0, atol=1e-12)  # v stays on the belt's speed: its map is constant
    expanded = _ReturnMap(moved)
    assert not expanded.trajectory.sliding_at_end and expanded.trajectory.events[0].t > expanded.t0
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(expanded.jets()[0]).real),
                               np.sort(orbit.multipliers.real), atol=1e-9)


def test_a_model_without_expressions_is_refused():
    orbit = ORBITS["impact_oscillator"]()
    compiled = replace(orbit, trajectory=replace(orbit.trajectory, system=object()))
    with pytest.raises(ModelError, match="compiled callables"):
        period_map_derivatives(compiled)
    with pytest.raises(ModelError, match="compiled callables"):
        criticality(compiled)


@pytest.fixture(scope="module")
def straight_to_circle():
    """A straight flow ``x' = v`` and the circle ``|x| = 1`` it reaches; and the closed form of the second
    derivatives of the flow-to-circle map ``x0 -> x0 + v tau(x0)``, ``tau`` the root of ``|x0 + v tau|^2 = 1``
    (by sympy, from the root's formula)."""
    system = PiecewiseSystem("test_second_order_straight", states=["x", "y"], parameters={"v1": 1.0, "v2": 0.0},
                             modes=[Mode("free", ["v1", "v2"])], surfaces={"circle": "x**2 + y**2 - 1"},
                             transitions=[Transition("free", "circle", Crossing.RISING, "free")])
    X, Y, V1, V2 = sp.symbols("X Y V1 V2", real=True)
    x, v = sp.Matrix([X, Y]), sp.Matrix([V1, V2])
    a, b, c = v.dot(v), 2 * x.dot(v), x.dot(x) - 1
    G = x + v * (-b + sp.sqrt(b**2 - 4 * a * c)) / (2 * a)
    second = sp.lambdify([X, Y, V1, V2], [[[sp.diff(G[i], zj, zk) for zk in (X, Y)] for zj in (X, Y)] for i in range(2)])
    return system, second


@settings(max_examples=40, deadline=None)
@given(angle=st.floats(0.02, np.pi / 2 - 1e-3), offset=st.floats(-0.9, 0.9), speed=st.floats(0.1, 10.0))
def test_flow_to_a_circle_against_its_closed_form(straight_to_circle, angle, offset, speed):
    """The flow-to-section jet of a straight flow arriving at a circle at an angle to its normal, down to
    nearly tangent arrivals (where the second derivatives grow like the inverse cube of the normal speed)."""
    system, second = straight_to_circle
    hit = np.array([np.cos(offset), np.sin(offset)])
    v = speed * (np.cos(angle) * hit + np.sin(angle) * np.array([-hit[1], hit[0]]))
    duration = 0.3
    x0 = hit - v * duration
    exact = np.array(second(*x0, *v), dtype=float)
    z, _, (_, Gzz) = _to_section(system, ("mode", 0), ("surface", 0), np.concatenate([[0.0], x0]), duration, v,
                                  1e-12, 1e-12, "a straight flow")
    np.testing.assert_allclose(z[1:], hit, atol=1e-12)
    np.testing.assert_allclose(Gzz[1:, 1:, 1:], exact, rtol=0, atol=1e-9 * (1 + np.abs(exact).max()))


def test_section_basis_is_orthonormal_and_normal_to_the_flow():
    for normal in ([0.0, 1.0, 0.0], [1e-12, 0.0, 1.0], [3.0, -4.0, 0.0, 1e-9]):
        Q = section_basis(np.array(normal))
        np.testing.assert_allclose(Q.T @ Q, np.eye(len(normal) - 1), atol=1e-14)
        np.testing.assert_allclose(np.array(normal) @ Q, 0.0, atol=1e-14 * np.linalg.norm(normal))
    with pytest.raises(ModelError, match="nonzero"):
        section_basis(np.zeros(3))


# -------------------------------------------------------------------- (b) against the period-2 branch
def _coefficient_from_doubled_branch(branch, doubled) -> tuple[float, np.ndarray]:
    """``-(1 + mu(p)) / xi^2`` along the period-2 branch, extrapolated linearly in ``xi^2`` to the doubling;
    and the period-1 orbits' critical multipliers at the branch's parameters."""
    problem = branch.problem
    xi2, estimates, mus = [], [], []
    for point in doubled.points[1:]:
        p = problem.parameters_at(point.parameter)
        other = problem.flow.run(point.state, point.t0, point.t0 + point.period / 2, p).x1
        single = copy.copy(problem)
        single.align_section(point)
        mu = single.solve(single.pack(0.5 * (point.state + other)), point.parameter).multipliers
        mu = float(mu[np.argmin(np.abs(mu + 1))].real)
        xi2.append(float(np.sum((other - point.state) ** 2)) / 4)
        estimates.append(-(1 + mu) / xi2[-1])
        mus.append(mu)
    return float(np.polyfit(xi2, estimates, 1)[1]), np.array(mus)


def test_supercritical_period_doubling_of_the_bouncing_ball():
    """The ball's period-1 orbit doubles at A = 0.3765...: b > 0, and the period-2 branch lies beyond the
    doubling, where the period-1 orbits are unstable, and is stable."""
    flow = Flow(bouncing_ball())
    orbit = find_periodic_orbit(flow, _bouncing_ball_state(0.37), parameters={"A": 0.37})
    branch = continue_orbit(orbit, "A", bounds=(0.37, 0.38), directions=(1,),
                            settings=ContinuationSettings(ds=0.002, ds_max=0.004))
    (pd,) = [sp_ for sp_ in branch.special_points if sp_.kind is SpecialPointKind.PERIOD_DOUBLING]
    result = special_point_criticality(branch, pd)
    assert result.criticality is Criticality.SUPERCRITICAL
    assert result.kind is SpecialPointKind.PERIOD_DOUBLING and result.multiplier == -1
    assert 0 < result.accuracy < 1e-4 * result.coefficient
    # from the problem the branch was computed with, and from the index of the point, the same
    again = special_point_criticality(branch.problem, pd)
    assert abs(again.coefficient - result.coefficient) <= result.accuracy
    assert special_point_criticality(branch, branch.special_points.index(pd)).criticality is Criticality.SUPERCRITICAL
    doubled = follow_period_doubled_branch(branch, pd, settings=ContinuationSettings(ds=5e-4, ds_max=5e-4, max_points=8,
                                                                                    bounds=(0.37, 0.38)))
    assert all(point.parameter > pd.parameter for point in doubled.points[1:])
    assert all(point.stable for point in doubled.points[1:])
    estimate, mus = _coefficient_from_doubled_branch(branch, doubled)
    assert np.all(mus < -1)  # the period-1 orbits there are unstable
    # the estimate's remainder after the linear fit in xi^2 is O(xi^4) (7e-6 of b measured over these points)
    assert estimate == pytest.approx(result.coefficient, rel=1e-4)


#: The state at t = 0 of the two-mass model's orbit at its period doubling near omega = 0.4516 (a start guess).
TWO_MASS_STATE = [0.8869838955762865, 0.02956094651817481, 1.3985524338147999, -0.19102019176461646]


def test_subcritical_period_doubling_of_two_masses_between_stops():
    """Two masses between compliant stops (six plain switches a period): b < 0, and the period-2 branch lies
    before the doubling, where the period-1 orbits are stable, and is unstable."""
    flow = Flow(two_mass_stops())
    orbit = find_periodic_orbit(flow, TWO_MASS_STATE, parameters={"omega": 0.452})
    branch = continue_orbit(orbit, "omega", bounds=(0.4512, 0.452), directions=(-1,),
                            settings=ContinuationSettings(ds=3e-4, ds_max=5e-4))
    (pd,) = [sp_ for sp_ in branch.special_points if sp_.kind is SpecialPointKind.PERIOD_DOUBLING]
    result = special_point_criticality(branch, pd)
    assert result.criticality is Criticality.SUBCRITICAL
    assert 0 < result.accuracy < 1e-4 * abs(result.coefficient)
    doubled = follow_period_doubled_branch(branch, pd, settings=ContinuationSettings(ds=2e-4, ds_max=2e-4, max_points=8,
                                                                                    bounds=(0.4505, 0.453)))
    assert all(point.parameter < pd.parameter for point in doubled.points[1:])
    assert not any(point.stable for point in doubled.points[1:])
    estimate, mus = _coefficient_from_doubled_branch(branch, doubled)
    assert np.all(mus > -1)  # the period-1 orbits there are stable
    assert estimate == pytest.approx(result.coefficient, rel=1e-4)


# --------------------------------------------------------------------------------- (c) closed forms
@pytest.fixture(scope="module")
def clocked_flow():
    return Flow(clocked())


@pytest.mark.parametrize("a, verdict", [(-0.3, Criticality.SUPERCRITICAL), (0.4, Criticality.SUBCRITICAL)])
def test_flip_coefficient_in_closed_form(clocked_flow, a, verdict):
    orbit = find_periodic_orbit(clocked_flow, [1.0, 0.0, 0.0, 0.0], parameters={"a": a}, period=TWO_PI)
    result = criticality(orbit)
    assert result.kind is SpecialPointKind.PERIOD_DOUBLING and result.criticality is verdict
    assert result.coordinates == "section" and result.basis.shape == (4, 3)
    exact = -a * TWO_PI
    assert result.accuracy < 1e-4 * abs(exact)
    assert abs(result.coefficient - exact) <= result.accuracy


@pytest.mark.parametrize("cr, verdict", [(-0.2, Criticality.SUPERCRITICAL), (0.3, Criticality.SUBCRITICAL)])
def test_neimark_sacker_coefficient_in_closed_form(clocked_flow, cr, verdict):
    values = {"half": 0.0, "a": 0.0, "k": 0.0, "omega": 1.3, "cr": cr, "ci": 0.4}
    orbit = find_periodic_orbit(clocked_flow, [1.0, 0.0, 0.0, 0.0], parameters=values, period=TWO_PI)
    result = criticality(orbit, "neimark_sacker")
    assert result.kind is SpecialPointKind.NEIMARK_SACKER and result.criticality is verdict
    assert result.multiplier == pytest.approx(np.exp(1.3j * TWO_PI), abs=1e-9)
    exact = 2 * cr * TWO_PI
    assert result.accuracy < 1e-4 * abs(exact)
    assert abs(result.coefficient - exact) <= result.accuracy


def test_an_orbit_computed_backward_in_time_has_its_forward_coefficient(clocked_flow):
    """The same flip computed from the backward map: its coefficient changes sign with the direction of time,
    and the forward-time one is reported."""
    values = {"a": -0.3, "rho": 0.2}  # (a slower clock: backward in time its radial multiplier is e^{2 rho T})
    orbit = find_periodic_orbit(clocked_flow, [1.0, 0.0, 0.0, 0.0], parameters=values, period=TWO_PI, backward=True)
    result = criticality(orbit)
    assert result.criticality is Criticality.SUPERCRITICAL
    assert abs(result.coefficient - 0.3 * TWO_PI) <= result.accuracy


# ------------------------------------------------------------------------------------------ bad input
def test_orbits_not_at_their_bifurcation_are_refused(clocked_flow):
    away = find_periodic_orbit(clocked_flow, [1.0, 0.0, 0.0, 0.0], parameters={"lam": 0.01}, period=TWO_PI)
    with pytest.raises(ModelError, match="no simple multiplier at -1"):
        criticality(away, "period_doubling")
    with pytest.raises(ModelError, match="no complex multipliers"):
        criticality(away, SpecialPointKind.NEIMARK_SACKER)
    with pytest.raises(ModelError, match="period_doubling and neimark_sacker"):
        criticality(away, "fold")
    values = {"half": 0.0, "a": 0.0, "k": 0.0, "omega": 0.25, "cr": -0.2}  # e^{i omega T} = i
    resonant = find_periodic_orbit(clocked_flow, [1.0, 0.0, 0.0, 0.0], parameters=values, period=TWO_PI)
    with pytest.raises(ModelError, match="1:4 resonance"):
        criticality(resonant)


def test_special_points_of_other_kinds_are_refused():
    flow = Flow(bouncing_ball())
    orbit = find_periodic_orbit(flow, _bouncing_ball_state(0.37), parameters={"A": 0.37})
    branch = continue_orbit(orbit, "A", bounds=(0.37, 0.38), directions=(1,),
                            settings=ContinuationSettings(ds=0.002, ds_max=0.004))
    fold = replace(branch.special_points[0], kind=SpecialPointKind.FOLD)
    with pytest.raises(ModelError, match="period_doubling and neimark_sacker"):
        special_point_criticality(branch, fold)
    with pytest.raises(ModelError, match="not an index"):
        special_point_criticality(branch, 5)
