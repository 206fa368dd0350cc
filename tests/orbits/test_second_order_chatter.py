"""Second derivatives of the period map through a complete chatter (saltation.orbits.second_order), and the
criticality of a period doubling of an orbit that chatters to rest (saltation.orbits.criticality).

The model is the coupled one of ``tests/engine/test_complete_chatter.py``: a ball (mass ``m``) bouncing on a table
that is a forced mass (``M = 4``) on a spring, restitution ``e = 0.5``, the impacts conserving momentum and the
contact force acting on both (``sticks=[0, 1/m, 0, -1/M]``).  Once a period the impacts accumulate, the engine
jumps from the last impact it kept onto the stuck motion (:mod:`saltation.engine.chatter`), and the ball rides the
table until the contact force lets go; the period map keeps two nonzero multipliers.  The chatter is
differentiated as the engine maps it (the impacts kept, the plastic projection from the last onto the stuck
motion, the stuck motion), with an estimate of its distance from the chatter's limit.

References, each independent of the second-order composition:

* the second derivatives against central differences (Richardson) of the engine's monodromy at states moved off
  the orbit;
* the chatter's error estimate against the actual distance from those differences, with the jump made from
  earlier impacts (where that distance is large enough to see); runs that resolved different numbers of impacts
  (other tolerances), jumped from the same impact, against each other;
* the jump's 2-jet against central differences of the jumped state itself (hypothesis: a curved table and a
  contact direction that turns with the state);
* the ball on a vibrating table (``saltation.models.bouncing_ball``): the stuck state depends on time alone, so
  the period map is constant and its derivatives vanish;
* the period doubling of the chattering orbit at ``m = 2.41232``: the period-2 branch that the library follows
  from the point (``follow_period_doubled_branch``): its side and stability (supercritical: beyond the doubling
  and stable), its chatter (twice a period), and its size ``-(1 + mu) / xi^2 -> b`` at the time the map was
  expanded at (``xi`` half the distance between the two points of the period-2 orbit there, ``mu`` the period-1
  orbit's multiplier at the same parameter).
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import (
    Crossing,
    Flow,
    Mode,
    PiecewiseSystem,
    Tolerances,
    Transition,
    find_periodic_orbit,
)
from saltation.engine.chatter import _Contact
from saltation.kinds import Criticality, SpecialPointKind
from saltation.models import bouncing_ball
from saltation.orbits.criticality import (
    _sequence,
    criticality,
    special_point_criticality,
)
from saltation.orbits.second_order import (
    _Jump,
    _jump_jets,
    chatter_impacts,
    period_map_derivatives,
    run_jets,
    run_map_derivatives,
)
from saltation.special_points.branch_switching import follow_period_doubled_branch
from saltation.special_points.continuation import ContinuationSettings, continue_orbit

G, OMEGA, E = 9.81, 2 * math.pi, 0.5
TIGHT = Tolerances(rtol=1e-12, atol=1e-14)
#: the chattering period-1 orbit at m = 1 at t = 0 (a start guess; in flight there), and at m = 2.38 (on the table)
STATE_M1 = [0.32599466269892424, 1.131925519283411, 0.32160482669154, 0.940662364036372]
STATE_M238 = [0.22673522797910173, 2.0466122454536064, 0.22673522797910173, 2.0466122454536064]


def spring_table(curved: bool = False) -> PiecewiseSystem:
    """The ball on a sprung table (the model of tests/engine/test_complete_chatter.py); ``curved``: the table's
    surface ``y = X + kappa X^2`` and the contact direction turning with ``X`` by ``beta`` (only the jump is
    computed on that one: no flow is compiled for it)."""
    return PiecewiseSystem(
        name="ball_on_curved_spring_table" if curved else "ball_on_spring_table",
        states=["y", "v", "X", "V"],
        parameters={"g": G, "e": E, "m": 1.0, "M": 4.0, "k": 355.3, "c": 7.54, "F": 61.0, "omega": OMEGA,
                    **({"kappa": 0.5, "beta": 0.2} if curved else {})},
        modes=[Mode("flight", ["v", "-g", "V", "(-k*X - c*V + F*cos(omega*t))/M"])],
        surfaces={"table": "y - X - kappa*X**2" if curved else "y - X"},
        transitions=[Transition("flight", "table", Crossing.FALLING, "flight",
                                reset=["y", "v - (1 + e)*(v - V)*M/(m + M)", "X", "V + (1 + e)*(v - V)*m/(m + M)"],
                                sticks=["0", "1/m", "0", "-(1 + beta*X)/M" if curved else "-1/M"])],
        period="2*pi/omega")


@pytest.fixture(scope="module")
def curved() -> PiecewiseSystem:
    return spring_table(curved=True)


@pytest.fixture(scope="module")
def flow() -> Flow:
    return Flow(spring_table(), TIGHT)


@pytest.fixture(scope="module")
def orbit(flow):
    orbit = find_periodic_orbit(flow, STATE_M1)
    (acc,) = orbit.trajectory.accumulations
    assert orbit.mode0 == "flight" and acc.mode == "flight@table" and acc.impacts >= 10
    return orbit


def _jump(system: PiecewiseSystem) -> _Jump:
    return _Jump(0, system.mode_index("flight"), system.mode_index("flight@table"), system.surface_index("table"),
                 "the chatter")


def _monodromy_differences(flow, x0: np.ndarray, p: np.ndarray, h: float, events: int) -> tuple[np.ndarray, float]:
    """``d M_ij / d x_k`` by central differences of the engine's monodromy with steps h and h/2 (Richardson), and the
    two levels' difference.  Every run keeps as many impacts as the orbit (so that the monodromies are one map's)."""
    D = np.zeros((4, 4, 4))
    spread = 0.0
    for k in range(4):
        columns = []
        for step in (h, h / 2):
            d = np.zeros(4)
            d[k] = step
            plus, minus = (flow.run(x0 + s * d, 0.0, 1.0, p, variational=True) for s in (1.0, -1.0))
            assert len(plus.events) == len(minus.events) == events
            columns.append((plus.monodromy - minus.monodromy) / (2 * step))
        D[:, :, k] = (4 * columns[1] - columns[0]) / 3
        spread = max(spread, float(np.max(np.abs(columns[1] - columns[0]))))
    return D, spread


@pytest.fixture(scope="module")
def differences(flow, orbit):
    return _monodromy_differences(flow, orbit.state0, orbit.parameters, 1e-4, len(orbit.trajectory.events))


# ------------------------------------------------------------------------------ through the chatter
def test_the_period_map_is_differentiated_through_the_chatter(orbit, differences):
    """The first derivative is the engine's monodromy (the same map: the jump from the last impact kept); the
    second agrees with Richardson central differences of the monodromy (h = 1e-4: their own error ~1e-8, measured
    agreement 6e-9 of entries up to 2.5), and its chatter error estimate is of that order or below."""
    d = period_map_derivatives(orbit)
    np.testing.assert_allclose(d.first, orbit.monodromy, rtol=0, atol=1e-10)
    D, spread = differences
    assert spread < 1e-6  # the differences with h and h/2 agree: their extrapolation is good to far below that
    np.testing.assert_allclose(d.second, D, rtol=0, atol=1e-7)
    assert 0 < d.second_error < 1e-7 and 0 < d.first_error < 1e-9
    (earlier,) = d.earlier
    assert earlier[0] == pytest.approx(E, rel=1e-6)  # the ratio of relative velocities across an impact


def test_the_chatter_error_estimate_covers_the_jump_from_earlier_impacts(flow, orbit, differences):
    """Jumping from the n-th impact instead of the last kept, the derivatives move away from the chatter's limit,
    geometrically (here by e^3 an impact); the estimate each carries (from the jump one impact earlier still)
    covers that distance, measured against the differences of the engine's monodromy."""
    D, _ = differences
    traj, p = orbit.trajectory, orbit.parameters
    ((_, chain),) = chatter_impacts(traj)
    kept = len(chain)
    assert run_jets(traj, p).impacts == (kept,)
    errors, distances = [], []
    for level in (kept - 2, kept - 4, kept - 6):
        d = run_map_derivatives(traj, p, traj.monodromy, levels={0: level})
        distance = float(np.max(np.abs(d.second - D)))
        assert distance <= d.second_error + 1e-7
        assert float(np.max(np.abs(d.first - orbit.monodromy))) <= d.first_error + 1e-10
        errors.append(d.second_error)
        distances.append(distance)
    assert distances[-1] > 1e-5  # far enough from the limit for the estimate to be tested
    assert errors[0] < errors[1] < errors[2]


def test_runs_that_resolve_different_impacts_are_differentiated_as_one_map(flow, orbit):
    """The integrator's tolerance decides how many impacts it resolves before it jumps (13, 11, 10 here): the event
    sequences, each chatter counted once, are the same, and jumped from the same impact the runs have the same
    derivatives (to the differences of their logged states); each run's own jump is within its estimate of that."""
    p = orbit.parameters
    common = run_map_derivatives(orbit.trajectory, p, None, levels={0: 9})
    kept = []
    for tolerances in (TIGHT, Tolerances(rtol=1e-10, atol=1e-12), Tolerances(rtol=1e-8, atol=1e-10)):
        run = flow.run(orbit.state0, 0.0, 1.0, p, variational=True, tolerances=tolerances)
        signature, (impacts,) = _sequence(run)
        assert signature == _sequence(orbit.trajectory)[0]
        kept.append(impacts)
        same = run_map_derivatives(run, p, run.monodromy, levels={0: 9})
        np.testing.assert_allclose(same.second, common.second, rtol=0, atol=1e-8)
        own = run_map_derivatives(run, p, run.monodromy)
        assert float(np.max(np.abs(own.second - common.second))) <= common.second_error + 1e-8
    assert len(set(kept)) == 3


def test_the_ball_on_a_table_forgets_everything():
    """The ball on a vibrating table: from the release on, the stuck state depends on time alone, so the period map
    is constant (closed form: both derivatives zero); through the chatter the composition gives zero to the
    integration error (amplified by the short flights' 1 / w)."""
    orbit = find_periodic_orbit(bouncing_ball(e=0.5, A=0.26), [0.0, 0.0])
    assert orbit.mode0 == "flight@table" and len(orbit.trajectory.accumulations) == 1
    d = period_map_derivatives(orbit)
    assert np.max(np.abs(d.first)) <= 1e-9 and np.max(np.abs(d.second)) <= 1e-7
    assert d.first_error <= 1e-9 and d.second_error <= 1e-7


@settings(max_examples=30, deadline=None)
@given(kappa=st.floats(-1.0, 1.0), beta=st.floats(-0.5, 0.5), X=st.floats(-0.3, 0.3), V=st.floats(-2.0, 2.0),
       w=st.floats(1e-4, 1.0), t=st.floats(0.0, 1.0))
def test_the_jump_and_its_two_jet_against_differences_of_the_jumped_state(curved, kappa, beta, X, V, w, t):
    """The jump from a state just after an impact (on the surface, at relative velocity ``w``) onto the stuck motion:
    on ``h = 0, Lh = 0``, moved along the contact direction and the displacement of an impulse along it; its first
    and second derivatives in ``z = (t, x)`` against central differences of the jumped state (steps 1e-3 and
    5e-4, Richardson: error ~1e-10 from rounding)."""
    system = curved
    p = system.parameter_vector({"kappa": kappa, "beta": beta})
    jump = _jump(system)
    kap, bet, m, M, c = (p[system.parameter_index(n)] for n in ("kappa", "beta", "m", "M", "c"))
    slope = 1 + 2 * kap * X
    z = np.array([t, X + kap * X**2, slope * V + w, X, V])
    y, (first, second) = _jump_jets(system, jump, z, p)
    np.testing.assert_allclose(y[0], t, atol=0)
    assert abs(y[1] - y[3] - kap * y[3] ** 2) <= 1e-13  # on the surface
    assert abs(y[2] - (1 + 2 * kap * y[3]) * y[4]) <= 1e-13  # at no relative velocity
    b = np.array([0.0, 1 / m, 0.0, -(1 + bet * X) / M])
    c_b = np.array([b[1], 0.0, b[3], -c / M * b[3]])  # f_x b
    moved = np.linalg.lstsq(np.column_stack([b, c_b]), y[1:] - z[1:], rcond=None)
    assert np.max(np.abs(np.column_stack([b, c_b]) @ moved[0] - (y[1:] - z[1:]))) <= 1e-13

    def state(at: np.ndarray) -> np.ndarray:
        return _jump_jets(system, jump, at, p)[0]

    def central(fun, j: int, h: float) -> np.ndarray:
        e = np.zeros(5)
        e[j] = h
        return (fun(z + e) - fun(z - e)) / (2 * h)

    for j in range(5):
        d1 = (4 * central(state, j, 5e-4) - central(state, j, 1e-3)) / 3
        np.testing.assert_allclose(first[:, j], d1, rtol=0, atol=1e-8)
        for k in range(5):
            def partial(at: np.ndarray, k=k) -> np.ndarray:
                e = np.zeros(5)
                e[k] = 1e-3
                return (state(at + e) - state(at - e)) / 2e-3

            coarse, fine = central(partial, j, 1e-3), central(partial, j, 5e-4)
            np.testing.assert_allclose(second[:, j, k], (4 * fine - coarse) / 3, rtol=0, atol=2e-6)


def test_the_jump_is_the_engines(flow, orbit):
    """The state the jump reaches from the last impact kept is the engine's plastic projection there."""
    traj, p = orbit.trajectory, orbit.parameters
    ((_, chain),) = chatter_impacts(traj)
    last = traj.events[chain[-1]]
    system = flow.system
    ours = _jump_jets(system, _jump(system), np.concatenate([[last.t], last.x_plus]), p)[0][1:]
    engine = _Contact(flow, 0, system.mode_index("flight@table"), 0, p).project(last.t, last.x_plus)[0]
    np.testing.assert_allclose(ours, engine, rtol=0, atol=1e-14)


# ------------------------------------------------------------------------------ a period doubling that chatters
def test_a_period_doubling_of_a_chattering_orbit_is_supercritical_as_its_period_two_branch_says(flow):
    """Heavier balls (m from 2.38) push the multiplier through -1 at m = 2.41232, the orbit chattering to rest once
    a period throughout.  The point carries b > 0 (supercritical); the period-2 branch followed from it lies beyond
    the doubling, where the period-1 orbits are unstable (mu < -1), is stable and chatters twice a period; and
    ``-(1 + mu) / xi^2``, extrapolated linearly in ``xi^2``, is b (the fit's remainder O(xi^4): 1e-5 of b
    measured)."""
    start = find_periodic_orbit(flow, STATE_M238, parameters={"m": 2.38})
    assert len(start.trajectory.accumulations) == 1
    branch = continue_orbit(start, "m", bounds=(2.38, 2.44), directions=(1,),
                            settings=ContinuationSettings(ds=0.01, ds_max=0.02))
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    assert pd.parameter == pytest.approx(2.41232, abs=1e-5)
    assert pd.criticality is Criticality.SUPERCRITICAL
    result = special_point_criticality(branch, pd)
    b, accuracy = pd.normal_form
    assert result.coefficient == pytest.approx(b, abs=accuracy) and result.accuracy == pytest.approx(accuracy)
    assert 0 < accuracy < 1e-3 * b
    finer = criticality(problem_orbit(branch, pd), step=result.step / 4)
    assert abs(finer.coefficient - b) <= accuracy and finer.accuracy < accuracy

    doubled = follow_period_doubled_branch(branch, pd, settings=ContinuationSettings(
        ds=1e-3, ds_max=1e-3, max_points=8, bounds=(2.38, 2.44)))
    assert len(doubled.points) >= 6
    assert all(point.parameter > pd.parameter for point in doubled.points[1:])
    assert all(point.stable for point in doubled.points[1:])
    problem = branch.problem
    xi2, estimates = [], []
    for point in doubled.points[1:]:
        p = problem.parameters_at(point.parameter)
        run = problem.flow.run(point.state, point.t0, point.t0 + point.period, p)
        assert len(run.accumulations) == 2
        # the two points of the period-2 orbit at the time the map was expanded at
        here = problem.flow.run(point.state, point.t0, result.t0, p).x1
        there = problem.flow.run(point.state, point.t0, result.t0 + point.period / 2, p).x1
        single = copy.copy(problem)
        single.align_section(point)
        mu = single.solve(single.pack(point.state), point.parameter).multipliers
        mu = float(mu[np.argmin(np.abs(mu + 1))].real)
        assert mu < -1
        xi2.append(float(np.sum((here - there) ** 2)) / 4)
        estimates.append(-(1 + mu) / xi2[-1])
    estimate = float(np.polyfit(xi2, estimates, 1)[1])
    assert estimate == pytest.approx(b, rel=1e-4)


def problem_orbit(branch, point):
    """The special point's orbit solved again on a copy of the branch's problem."""
    problem = copy.copy(branch.problem)
    problem.align_section(point)
    return problem.solve(problem.pack(point.state, point.period), float(point.parameter))
