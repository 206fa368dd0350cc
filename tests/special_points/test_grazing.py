"""Grazing of the impact oscillator x'' + 2 zeta x' + x = cos(w t), stop at x = s, v -> -r v.

References, derived independently of the library:

* the grazing value s* = 1 / sqrt((1 - w^2)^2 + (2 zeta w)^2), the amplitude of the harmonic response;
* the impacting period-1 orbits, from the closed-form flow between impacts
  y(t) = y_p(t) + expm(A (t - t_i)) (y(t_i) - y_p(t_i)) and the impact map
  (t_i, v+) -> (t_i', v+') solved for a fixed point t_i' = t_i + T, v+' = v+;
* their multipliers, the eigenvalues of the impact map's Jacobian by central differences
  (the impact map and the period map are conjugate).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from saltation import Flow
from saltation.branches.branch import SpecialPointKind
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.errors import ModelError
from saltation.special_points.grazing import growth_exponent, locate_grazing
from saltation.models import impact_oscillator
from saltation.models.impact_oscillator import DEFAULTS
from saltation.orbits.shooting import ShootingProblem, find_periodic_orbit

ZETA, W, R = DEFAULTS["zeta"], DEFAULTS["omega"], DEFAULTS["r"]
T = 2 * np.pi / W
A = np.array([[0.0, 1.0], [-1.0, -2 * ZETA]])
D = (1 - W**2) ** 2 + (2 * ZETA * W) ** 2
S_STAR = 1 / np.sqrt(D)


def harmonic(t):
    """The forced response y_p(t) = (a cos wt + b sin wt, its derivative)."""
    a, b = (1 - W**2) / D, 2 * ZETA * W / D
    return np.array([a * np.cos(W * t) + b * np.sin(W * t), W * (-a * np.sin(W * t) + b * np.cos(W * t))])


def flow_closed_form(y, t_from, t_to):
    return harmonic(t_to) + expm(A * (t_to - t_from)) @ (np.asarray(y) - harmonic(t_from))


EIGENVALUES, EIGENVECTORS = np.linalg.eig(A)


def flow_closed_form_many(y, t_from, ts):
    """flow_closed_form at many times, with expm(A tau) = V exp(Lambda tau) V^-1."""
    tau = np.asarray(ts) - t_from
    E = np.einsum("ij,mj,jk->mik", EIGENVECTORS, np.exp(np.outer(tau, EIGENVALUES)), np.linalg.inv(EIGENVECTORS)).real
    return harmonic(np.asarray(ts)).T + E @ (np.asarray(y) - harmonic(t_from))


def next_impact(s, t_i, v_plus):
    """The next time after t_i where x reaches s from below, and the velocity there."""
    y0 = np.array([s, v_plus])
    x = lambda t: flow_closed_form(y0, t_i, t)[0] - s  # noqa: E731
    ts = t_i + np.linspace(1e-9, 3 * T, 6001)
    xs = flow_closed_form_many(y0, t_i, ts)[:, 0] - s
    rising = np.nonzero((xs[:-1] < 0) & (xs[1:] >= 0))[0]
    if v_plus > 0 or rising.size == 0:
        return t_i + 10 * T, 1e3  # no impact from below: far from a fixed point
    k = rising[0]
    t_next = brentq(x, ts[k], ts[k + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return t_next, flow_closed_form(y0, t_i, t_next)[1]


def impact_map(s, u):
    t_i, v_plus = u
    t_next, v_minus = next_impact(s, t_i, v_plus)
    return np.array([t_next - T, -R * v_minus])


def impacting_orbit(s, guess):
    """Fixed point (t_i, v+) of the impact map, and the orbit's state at t = 0."""
    u = fsolve(lambda u: impact_map(s, u) - u, guess, xtol=1e-13)
    t_i, v_plus = u
    t_i = t_i % T
    state0 = flow_closed_form([s, v_plus], t_i, T)  # the state at t = T, that is at t = 0 on the orbit
    return np.array([t_i, v_plus]), state0


def impact_map_multipliers(s, u, h=2e-6):
    """Eigenvalues of the impact map's Jacobian: central differences at h and h/2, Richardson-extrapolated
    (the map is strongly curved near grazing: a plain central difference at h = 1e-6 is off by 4e-5)."""

    def central(h):
        return np.column_stack([(impact_map(s, u + h * e) - impact_map(s, u - h * e)) / (2 * h) for e in np.eye(2)])

    J = (4 * central(h / 2) - central(h)) / 3
    return np.sort_complex(np.linalg.eigvals(J))


@pytest.fixture(scope="module")
def impact_flow():
    return Flow(impact_oscillator())


GRAZING_TIME = np.arctan2(2 * ZETA * W, 1 - W**2) / W  # where the harmonic response reaches its maximum s*


def reference_orbits(stops):
    """Closed-form impacting period-1 orbits at decreasing ``stops`` below s*, each from the previous one
    (the first from the grazing orbit: impact velocity sqrt(2 |x''| d) at distance d)."""
    acc = abs(-S_STAR + np.cos(W * GRAZING_TIME))
    guess = np.array([GRAZING_TIME, -R * np.sqrt(2 * acc * (S_STAR - stops[0]))])
    out = []
    for s in stops:
        u, state0 = impacting_orbit(s, guess)
        out.append((u, state0))
        guess = u
    return out


def impact_state(flow, s):
    """The state at t = 0 of the impacting period-1 orbit at s (from the closed form, walking down from
    s* - 0.02, where the walk's first guess is good)."""
    stops = np.linspace(S_STAR - 0.02, s, 2 + int((S_STAR - s) / 0.05))
    return reference_orbits(stops)[-1][1]


def test_grazing_located_by_defining_system(impact_flow):
    g = locate_grazing(impact_flow, harmonic(0.0), 2.9, "s", 0, 0.3, parameters={"s": 2.9})
    assert g.parameter == pytest.approx(S_STAR, abs=1e-12)
    assert g.accuracy < 1e-12
    assert g.x_graze[0] == pytest.approx(S_STAR, abs=1e-12) and abs(g.x_graze[1]) < 1e-12
    np.testing.assert_allclose(g.state0, harmonic(0.0), rtol=0, atol=1e-12)
    # the grazing orbit's monodromy: the no-impact limit, expm(A T)
    np.testing.assert_allclose(g.monodromy, expm(A * T), rtol=0, atol=1e-12)


def test_grazing_from_both_sides(impact_flow):
    """Continuation records the grazing at the closed-form s*, from the non-impacting side (where it
    passes through onto the impacting branch) and from the impacting side."""
    down = continue_branch(
        ShootingProblem(impact_flow, {"s": 3.0}, continuation_parameter="s"), harmonic(0.0), 3.0,
        settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.2, 3.0)), directions=(-1,),
    )
    up = continue_branch(
        ShootingProblem(impact_flow, {"s": 2.4}, continuation_parameter="s"), impact_state(impact_flow, 2.4), 2.4,
        settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.4, 3.0)), directions=(1,),
    )
    for branch, crossing_side in ((down, "plus"), (up, "minus")):
        grazings = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.GRAZING]
        assert len(grazings) == 1
        g = grazings[0]
        assert g.parameter == pytest.approx(S_STAR, abs=1e-9)
        assert g.accuracy < 1e-9
        # the side without impacts: the harmonic response, exp(A T); the other side unbounded
        free = g.multipliers_minus if crossing_side == "plus" else g.multipliers_plus
        impacting = g.multipliers_plus if crossing_side == "plus" else g.multipliers_minus
        np.testing.assert_allclose(np.sort_complex(free), np.sort_complex(np.linalg.eigvals(expm(A * T))), rtol=0, atol=1e-10)
        assert np.isinf(np.abs(impacting)).sum() == 1
        assert g.crossing_q is None
        assert f"the side with the crossing is '{crossing_side}'" in g.note
        # both sides of the branch are there: orbits with and without impacts
        assert any(p.event_labels for p in branch.points) and any(not p.event_labels for p in branch.points)
    assert down.parameter.min() < S_STAR - 0.1  # followed onto the impacting branch, away from grazing


def test_impacting_orbits_against_closed_form(impact_flow):
    """State, period-1 condition and multipliers of impacting orbits vs the closed-form impact map."""
    stops = [2.7, 2.6, 2.5, 2.4, 2.3]
    for s, (u, state0) in zip(stops, reference_orbits(stops)):
        np.testing.assert_allclose(impact_map(s, u), u, rtol=0, atol=1e-12)  # a fixed point of the closed form
        orbit = find_periodic_orbit(impact_flow, state0 + 1e-3, parameters={"s": s})
        (t_impact,) = [e.t for e in orbit.events]
        assert u[0] % T == pytest.approx(t_impact, abs=1e-9)
        np.testing.assert_allclose(orbit.state0, state0, rtol=0, atol=1e-9)
        mu_ref = impact_map_multipliers(s, u)
        # Richardson-extrapolated central differences of a map evaluated to ~1e-15 (relative): error
        # O(h^4) plus rounding ~1e-15 |P| / h = 5e-10 |P|; |mu| reaches 150 at s = 2.7
        scale = np.abs(mu_ref).max()
        np.testing.assert_allclose(np.sort_complex(orbit.multipliers), mu_ref, rtol=0, atol=1e-7 * scale)


def test_growth_exponent_near_grazing(impact_flow):
    """Nordmark's square-root map: the period map's Jacobian at the grazing orbit's state, whose
    virtual orbit penetrates the stop by d = s* - s, grows like d^(-1/2) (the impact velocity is
    sqrt(2 |x''| d) and the saltation matrix of the impact is O(1/v))."""
    distances = np.array([1e-3, 1e-4, 1e-5, 1e-6, 1e-7])
    norms = []
    for d in distances:
        p = impact_flow.parameters({"s": S_STAR - d})
        traj = impact_flow.run(harmonic(0.0), 0.0, T, p, variational=True)
        assert len(traj.events) == 1
        norms.append(np.linalg.norm(traj.monodromy, 2))
    # |M| = C d^(-1/2) + O(1): over d in [1e-7, 1e-3] the fitted slope is -1/2 to within 0.02
    assert growth_exponent(distances, np.array(norms)) == pytest.approx(-0.5, abs=0.02)


def orbit_with_impact_velocity(v):
    """The impacting period-1 orbit whose impact velocity is v: solve y(t_i + T) = (s, v) from
    (s, -r v) at t_i for (t_i, s). Smooth in v (unlike in s)."""

    def residual(z):
        t_i, s = z
        return flow_closed_form([s, -R * v], t_i, t_i + T) - [s, v]

    t_i, s = fsolve(residual, [GRAZING_TIME, S_STAR], xtol=1e-13)
    assert np.abs(residual([t_i, s])).max() < 1e-13
    return s, flow_closed_form([s, -R * v], t_i % T, T)


def test_impacting_fixed_points_near_grazing_grow_like_one_over_distance(impact_flow):
    """On the impacting branch itself the impact velocity is proportional to d = s* - s, not to
    sqrt(d): an impact of velocity v moves the next virtual penetration by O(v), so the fixed point
    has v ~ d (the closed form gives d = 0.84 v here). Its penetration is O(d^2), and the largest
    multiplier, O(1/v), grows like 1/d."""
    distances, magnitudes = [], []
    for v in (1e-2, 1e-3, 1e-4):
        s, state0 = orbit_with_impact_velocity(v)
        orbit = find_periodic_orbit(impact_flow, state0, parameters={"s": s})
        np.testing.assert_allclose(orbit.state0, state0, rtol=0, atol=1e-10)
        assert len(orbit.events) == 1
        distances.append(S_STAR - s)
        magnitudes.append(np.abs(orbit.multipliers).max())
    assert growth_exponent(np.array(distances), np.array(magnitudes)) == pytest.approx(-1.0, abs=0.02)


def test_grazing_of_an_autonomous_limit_cycle():
    """r' = r (1 - r^2), theta' = 1 in Cartesian form: the unit circle, period 2 pi, multipliers 1 and
    exp(-4 pi). A soft wall beyond x = s (an extra force -k (x - s), continuous at the wall): the cycle
    grazes it at s = 1, located with the period as an unknown and a phase condition; the field is
    continuous, so the saltation matrices are the identity and both one-sided limits are the cycle's."""
    from saltation import Crossing, Mode, PiecewiseSystem, Transition

    field = ["x*(1 - x**2 - y**2) - y", "y*(1 - x**2 - y**2) + x"]
    system = PiecewiseSystem(
        name="test_circle_with_soft_wall", states=["x", "y"], parameters={"s": 1.3, "k": 3.0},
        modes=[Mode("beyond", [field[0] + " - k*(x - s)", field[1]], domain=["x - s > 0"]), Mode("inside", field)],
        surfaces={"wall": "x - s"},
        transitions=[Transition("inside", "wall", Crossing.RISING, "beyond"),
                     Transition("beyond", "wall", Crossing.FALLING, "inside")],
    )
    flow = Flow(system)
    problem = ShootingProblem(flow, {"s": 1.3}, continuation_parameter="s")
    branch = continue_branch(problem, problem.pack([0.0, -1.0], 2 * np.pi), 1.3,
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.8, 1.3)), directions=(-1,))
    (g,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.GRAZING]
    # DOP853 (a nonlinear field) at the location's rtol 1e-12: the stated accuracy includes that error
    assert abs(g.parameter - 1.0) <= g.accuracy < 1e-10
    assert g.period == pytest.approx(2 * np.pi, abs=1e-9)
    for side in (g.multipliers_minus, g.multipliers_plus):  # the monodromy from DOP853 at rtol 1e-12
        np.testing.assert_allclose(np.sort(np.abs(side)), [np.exp(-4 * np.pi), 1.0], rtol=1e-6, atol=1e-9)
    assert "bounded" in g.note
    # a locate_grazing without a period guess for an autonomous model is an error that says so
    with pytest.raises(ModelError, match="give the period guess"):
        locate_grazing(flow, [0.0, -1.0], 1.2, "s", 0, np.pi / 2)
