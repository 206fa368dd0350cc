"""Branch switching at the period doubling of an autonomous cycle: Chua's circuit with its piecewise-linear
diode, against an independent Poincare map of scipy's solve_ivp.

Chua's circuit (Matsumoto 1984; Chua, Komuro and Matsumoto 1986), dimensionless,

    x' = alpha (y - x - g(x)),   y' = x - y + z,   z' = -beta y,
    g(x) = m1 x + (m0 - m1) / 2 (|x + 1| - |x - 1|),

with ``beta = 14.286, m0 = -8/7, m1 = -5/7``: the cycle around the equilibrium in ``x > 1`` doubles its
period at ``alpha ~ 8.175`` (the route to the spiral attractor), and the period-2 cycle born there is
stable up to the next doubling near ``alpha = 8.37``.  The library follows the period-1 cycle, locates the
period doubling, and follows the period-2 branch with the doubled period ``T2 ~ 2 T`` an unknown.

The reference knows nothing of the library: in each of the three regions ``x < -1``, ``|x| < 1``,
``x > 1`` the affine field is integrated by ``solve_ivp`` (DOP853, ``rtol = atol = 1e-13``) up to its own
events at ``x = +-1`` (each region's field extended smoothly, the integration restarted at each crossing);
the Poincare map is the return to ``x = 1`` falling out of ``x > 1``, in ``(y, z)``.  The period-2 cycle is
the fixed point of its second iterate by Newton with central differences (``h = 1e-6``), its multipliers
the eigenvalues of that difference Jacobian.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from saltation import Flow, Mode, PiecewiseSystem
from saltation.apps import cli
from saltation.branches.branch import SpecialPointKind
from saltation.errors import InconsistentResultError, ModelError
from saltation.orbits.single import ShootingProblem
from saltation.special_points.branch_switching import (
    follow_period_doubled_branch,
    half_period_gap,
    period_doubled_problem,
    period_doubling_direction,
    section_direction,
)
from saltation.special_points.continuation import ContinuationSettings, continue_branch

DEFAULTS = {"alpha": 8.0, "beta": 14.286, "m0": -8.0 / 7.0, "m1": -5.0 / 7.0}
RANGE = (8.0, 8.3)
MODEL = '''
from saltation import Mode, PiecewiseSystem


def chua():
    g = "m1*x + (m0 - m1)/2*(Abs(x + 1) - Abs(x - 1))"
    return PiecewiseSystem(
        name="literature_chua_pwl", states=["x", "y", "z"],
        parameters={"alpha": 8.0, "beta": 14.286, "m0": -8.0 / 7.0, "m1": -5.0 / 7.0},
        modes=[Mode("circuit", [f"alpha*(y - x - ({g}))", "x - y + z", "-beta*y"])], surfaces={}, transitions=[],
    )
'''


def chua() -> PiecewiseSystem:
    """The circuit as written on paper, with ``Abs`` (the same model as the literature corpus's)."""
    g = "m1*x + (m0 - m1)/2*(Abs(x + 1) - Abs(x - 1))"
    return PiecewiseSystem(
        name="literature_chua_pwl", states=["x", "y", "z"], parameters=dict(DEFAULTS),
        modes=[Mode("circuit", [f"alpha*(y - x - ({g}))", "x - y + z", "-beta*y"])], surfaces={}, transitions=[],
    )


# --- the reference: solve_ivp region by region, the Poincare map on x = 1 -------------------------------

#: The crossings watched from each region: (level, direction, region entered).  Each run starts on the
#: boundary it has just crossed, moving away from it, so only the crossing into the next region is watched.
WATCH = {0: [(1.0, 1, 1), (-1.0, -1, -1)], 1: [(1.0, -1, 0)], -1: [(-1.0, 1, 0)]}


def _region(x: float) -> int:
    return 1 if x > 1.0 else (-1 if x < -1.0 else 0)


def _field(alpha: float, region: int):
    """The affine field of one region, ``g(x) = m x + c`` there, extended beyond it."""
    beta, m0, m1 = DEFAULTS["beta"], DEFAULTS["m0"], DEFAULTS["m1"]
    m, c = (m0, 0.0) if region == 0 else (m1, region * (m0 - m1))

    def f(t, s):
        x, y, z = s
        return [alpha * (y - x - (m * x + c)), x - y + z, -beta * y]

    return f


def _crossing(level: float, direction: int):
    def event(t, s):
        return s[0] - level

    event.terminal, event.direction = True, direction
    return event


def to_section(state, alpha: float, returns: int = 1, region: int | None = None) -> tuple[np.ndarray, float]:
    """From ``state`` to its ``returns``-th falling crossing of ``x = 1`` out of ``x > 1``: (state, time)."""
    s, t, count = np.array(state, dtype=float), 0.0, 0
    region = _region(s[0]) if region is None else region
    while t < 60.0:
        watched = WATCH[region]
        sol = solve_ivp(_field(alpha, region), (t, 60.0), s, method="DOP853", rtol=1e-13, atol=1e-13,
                        events=[_crossing(level, d) for level, d, _ in watched])
        (k,) = [k for k, times in enumerate(sol.t_events) if len(times)][:1]
        t, s = float(sol.t_events[k][0]), sol.y_events[k][0].copy()
        level, _, entered = watched[k]
        s[0] = level
        if region == 1 and entered == 0:
            count += 1
            if count == returns:
                return s, t
        region = entered
    raise AssertionError("the reference's orbit does not return to x = 1")


def return_map(q: np.ndarray, alpha: float, returns: int) -> tuple[np.ndarray, float]:
    """The ``returns``-th return of ``(1, y, z)`` (falling into ``|x| < 1``) to the section: ``((y, z), time)``."""
    s, t = to_section([1.0, q[0], q[1]], alpha, returns, region=0)
    return s[1:], t


def return_jacobian(q: np.ndarray, alpha: float, returns: int, h: float = 1e-6) -> np.ndarray:
    return np.column_stack([(return_map(q + h * e, alpha, returns)[0] - return_map(q - h * e, alpha, returns)[0])
                            / (2 * h) for e in np.eye(2)])


def reference_cycle(q: np.ndarray, alpha: float, returns: int):
    """The fixed point of the ``returns``-th iterate near ``q`` by Newton: ``(q, period, multipliers)``."""
    q = np.array(q, dtype=float)
    for _ in range(20):
        step = np.linalg.solve(return_jacobian(q, alpha, returns) - np.eye(2), return_map(q, alpha, returns)[0] - q)
        q = q - step
        if np.linalg.norm(step) < 1e-12:
            break
    image, period = return_map(q, alpha, returns)
    assert np.linalg.norm(image - q) < 1e-11
    return q, period, np.linalg.eigvals(return_jacobian(q, alpha, returns))


# --- the library ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def chua_branches():
    flow = Flow(chua())
    problem = ShootingProblem(flow, {"alpha": RANGE[0]}, continuation_parameter="alpha")
    orbit = problem.solve(problem.pack([1.0, -0.35, -1.31], 2.25), RANGE[0])
    settings = ContinuationSettings(ds=0.01, ds_max=0.02, bounds=RANGE)
    branch = continue_branch(problem, problem.pack(orbit.state0, orbit.period), RANGE[0], settings=settings,
                             directions=(1,))
    (pd,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    doubled = follow_period_doubled_branch(branch, branch.special_points.index(pd), settings=settings)
    return problem, branch, pd, doubled


def _nontrivial(multipliers) -> np.ndarray:
    mu = np.asarray(multipliers, dtype=complex)
    return np.delete(mu, int(np.argmin(np.abs(mu - 1.0))))


def test_the_period_doubling_has_the_multiplier_minus_one(chua_branches):
    _, branch, pd, _ = chua_branches
    assert branch.check().ok, branch.check().violations
    assert np.min(np.abs(pd.multipliers + 1.0)) < 1e-8
    # the reference's return map at the library's point: its cycle there, of the library's period, with a
    # multiplier -1 (differences of a map integrated to ~1e-13: good to ~1e-7; the point is located to 1e-9
    # in alpha, which moves the multiplier by less)
    q0, _ = to_section(pd.state, pd.parameter)
    q, period, mu = reference_cycle(q0[1:], pd.parameter, 1)
    np.testing.assert_allclose(q, q0[1:], rtol=0, atol=1e-9)
    assert period == pytest.approx(pd.period, abs=1e-9)
    assert np.min(np.abs(mu + 1.0)) < 1e-6


def test_the_period_2_branch_against_the_reference(chua_branches):
    _, _, pd, doubled = chua_branches
    assert doubled.special_points[0].kind is SpecialPointKind.PERIOD_DOUBLING
    assert doubled.points[0].parameter == pytest.approx(pd.parameter, abs=1e-3)
    assert all(p.parameter >= pd.parameter - 1e-9 for p in doubled.points)  # supercritical: beyond the doubling
    assert doubled.points[-1].parameter == pytest.approx(RANGE[1])
    assert doubled.check().ok, doubled.check().violations
    checked = 0
    for point in doubled.points[2::3]:
        alpha = point.parameter
        # the library's invariant: the trivial multiplier 1 of the autonomous period-2 orbit
        assert point.trivial_error <= 1e-6
        assert np.min(np.abs(point.multipliers - 1.0)) <= 1e-6
        # its state, carried by the reference to the section, is the reference's period-2 cycle there
        q0, _ = to_section(point.state, alpha)
        q, period, mu = reference_cycle(q0[1:], alpha, 2)
        # Newton to 1e-10 on maps integrated to ~1e-13; (P2 - I)^-1 grows to ~20 near the doubling
        np.testing.assert_allclose(q, q0[1:], rtol=0, atol=1e-8)
        assert period == pytest.approx(point.period, abs=1e-9)  # the doubled period, an unknown of the branch
        assert period == pytest.approx(2 * pd.period, rel=0.01)
        # central differences of the second return map: ~1e-7 from the integration's noise
        np.testing.assert_allclose(np.sort(_nontrivial(point.multipliers).real), np.sort(mu.real), rtol=0, atol=1e-6)
        assert point.stable == bool(np.all(np.abs(mu) < 1.0))
        assert point.stable  # stable from the doubling up to the next one, near alpha = 8.37
        checked += 1
    assert checked >= 3


def test_the_period_2_cycle_leaves_the_doubled_cycle_as_a_square_root(chua_branches):
    """The two loops of the period-2 cycle cross the section at ``q`` and ``P(q)``: ``|P(q) - q|`` grows
    like ``sqrt(alpha - alpha*)`` (the pitchfork of the second iterate), and is never 0 away from the
    doubling (the branch is not the period-1 cycle traversed twice)."""
    _, _, pd, doubled = chua_branches
    distance, gap, loops = [], [], []
    for point in doubled.points:
        q, _ = to_section(point.state, point.parameter)
        distance.append(point.parameter - pd.parameter)
        loops.append(np.linalg.norm(return_map(q[1:], point.parameter, 1)[0] - q[1:]))
        gap.append(half_period_gap(doubled.problem, np.append(point.state, point.period), point.parameter))
    distance, loops, gap = map(np.array, (distance, loops, gap))
    assert np.all(distance > 0)
    near = distance < 0.03
    assert near.sum() >= 3
    slope = np.polyfit(np.log(distance[near]), np.log(loops[near]), 1)[0]
    assert slope == pytest.approx(0.5, abs=0.02)
    # bounded away from 0: at least half the square-root law fitted near the doubling
    c = np.median(loops[near] / np.sqrt(distance[near]))
    assert np.all(loops >= 0.5 * c * np.sqrt(distance))
    assert np.all(gap[distance > 1e-3] > 1e-2)  # x(T2/2) is far from x(0): no orbit closes after half its period


def test_the_first_orbit_leaves_along_the_flip_direction_on_the_section(chua_branches):
    problem, _, pd, doubled = chua_branches
    v = period_doubling_direction(problem, pd)
    w = section_direction(problem, pd, v)
    p = problem.parameters_at(pd.parameter)
    f = problem.flow.vector_field(problem.start_mode(pd.state, p), 0.0, pd.state, p)
    assert abs(w @ f) <= 1e-12 * np.linalg.norm(f)
    # the monodromy maps w to -w up to the flow direction
    M = problem.evaluate(problem.pack(pd.state, pd.period), pd.parameter, need_lam=False).trajectory.monodromy
    residual = M @ w + w
    residual -= (residual @ f) / (f @ f) * f
    assert np.linalg.norm(residual) < 1e-7
    first = doubled.points[0]
    step = first.state - pd.state
    assert abs(abs(step @ w) - 1e-3 * (1 + np.linalg.norm(pd.state))) < 1e-12  # the step along w, fixed
    twin = period_doubled_problem(problem)
    assert twin.autonomous and twin.periods == 1 and twin.lam_name == "alpha" and twin.x_ref is None


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3), st.floats(-10.0, 10.0))
def test_the_section_direction_is_the_projection_along_the_flow(chua_branches, v, along):
    """Any direction plus any multiple of the flow projects onto the same unit vector of the section."""
    problem, _, pd, _ = chua_branches
    p = problem.parameters_at(pd.parameter)
    f = problem.flow.vector_field(problem.start_mode(pd.state, p), 0.0, pd.state, p)
    f_hat = f / np.linalg.norm(f)
    v = np.array(v)
    off = v - (v @ f_hat) * f_hat
    assume(np.linalg.norm(off) > 1e-3)
    w = section_direction(problem, pd, v + along * f_hat)
    np.testing.assert_allclose(w, off / np.linalg.norm(off), rtol=0, atol=1e-9)


def test_bad_points_are_refused(chua_branches):
    problem, branch, pd, _ = chua_branches
    with pytest.raises(ModelError, match="needs a period_doubling point, got fold"):
        follow_period_doubled_branch(problem, replace(pd, kind=SpecialPointKind.FOLD))
    # a point called a period doubling whose orbit has none: the first orbit of the branch
    start = branch.points[0]
    fake = replace(pd, parameter=start.parameter, state=start.state, period=start.period)
    with pytest.raises(ModelError, match=r"no multiplier near -1 \(the nearest is -0\.677"):
        follow_period_doubled_branch(problem, fake)
    p = problem.parameters_at(pd.parameter)
    f = problem.flow.vector_field(problem.start_mode(pd.state, p), 0.0, pd.state, p)
    with pytest.raises(InconsistentResultError, match="lies along the flow"):
        section_direction(problem, pd, f)


def test_the_command_line_follows_the_period_2_branch(tmp_path, capsys, chua_branches):
    """``saltation continue --period-doubled`` on the autonomous circuit: the second branch file is the
    period-2 branch, of doubled period, starting at the period doubling."""
    from saltation.output import io

    _, _, pd, _ = chua_branches
    path = tmp_path / "circuits.py"
    path.write_text(MODEL)
    status = cli.main([
        "continue", f"{path}:chua", "--param", "alpha", "--from", "8.0", "--to", "8.3", "--x0", "1.0,-0.35,-1.31",
        "--period", "2.25", "--ds", "0.01", "--ds-max", "0.02", "--period-doubled", "--out", str(tmp_path / "out"),
        "--no-progress",
    ])
    out, err = capsys.readouterr()
    assert status == 0, err
    assert "on 2 branches" in out
    doubled = io.load_branch_json(tmp_path / "out" / "literature_chua_pwl_alpha_branch_1.json")
    assert doubled.special_points[0].kind is SpecialPointKind.PERIOD_DOUBLING
    assert doubled.special_points[0].parameter == pytest.approx(pd.parameter, abs=1e-9)
    assert np.all(np.abs(doubled.period / (2 * pd.period) - 1.0) < 0.01)
    status = cli.main(["continue", f"{path}:chua", "--param", "alpha", "--from", "8.0", "--to", "8.3",
                       "--period-doubled", "--segments", "2", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and "--period-doubled" in err[0] and "--segments" in err[0]
    status = cli.main(["continue", f"{path}:chua", "--param", "alpha", "--from", "8.0", "--to", "8.3",
                       "--equilibrium", "circuit[x+1+,x-1+]", "--period-doubled", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and "--period-doubled does not apply to --equilibrium" in err[0]
