"""Codimension-two points along the curves of sliding bifurcations, against closed-form references.

Along a crossing-, switching- or adding-sliding curve the orbit's period map is continuously differentiable
across the bifurcation (di Bernardo, Kowalczyk and Nordmark, Physica D 170, 2002), so the orbits on both sides
share the multipliers at the curve; where one passes +1 (-1, or a pair the unit circle) the sliding curve is
crossed by a fold (period-doubling, Neimark-Sacker) curve of the orbits.  Where the far field's tangency at the
arrival turns from visible to invisible (a cubic tangency) crossing-sliding turns into switching-sliding.

* the tilted relay ``x'' + 2 zeta x' + x = -F sgn(y + kappa x - v) + a cos(omega t)`` (numpy and scipy only in
  ``tests/tilted_relay_reference.py``): for ``kappa < 0`` the sliding motion ``x' = v - kappa x`` on the line
  expands, and along the switching-sliding curve in ``(v, kappa)`` the sliding orbit's multiplier passes +1 near
  ``kappa = -0.608``.  A sliding orbit in the plane has the multipliers 0 and ``mu``; ``mu`` is the derivative of
  the closed-form map from a state in the middle of the sliding motion to the state a period later (slide, leave
  where ``G = -F``, follow the ``s < 0`` mode back to the line, slide again), by central differences with
  Richardson extrapolation; brentq in ``kappa`` on ``mu - 1`` along the switching-sliding points (fsolve on the
  closed-form orbit) gives the reference;
* the same point as the crossing of the sliding curve by the fold curve followed on its own from a fold of the
  sliding orbits at ``kappa = -0.7``: its orbits change their events there by a switching-sliding;
* the friction oscillator ``x'' + 2 zeta x' + x = -F sgn(x' - v_b) + a cos(omega t)`` in ``(v_b, F)``: the
  switching-sliding curve (arrival from the slower side, the faster side's field ``L_+ = -2 zeta v_b - x - F + a
  cos(omega t)`` tangent) turns into crossing-sliding where that tangency is cubic: ``dL_+/dt = -v_b - a omega
  sin(omega t) = 0`` there too.  Reference: fsolve in ``(t_e, x_e, v_b, F)`` on the closed-form sticking orbit
  (stick from the arrival until the slower side's field turns tangent, slip slower back to the belt) plus both
  conditions.  The crossing-sliding curve meets the mirror image, ``v_b -> -v_b`` (the model's symmetry ``(x,
  x', t, v_b) -> (-x, -x', t + T/2, -v_b)``).

Tolerances: the curve's points are corrected to ``|r| <= 1e-10 (1 + |z|)`` with integration at ``rtol 1e-10``; a
located point states its accuracy (the final bracket of its test function plus the curve point's own error,
the next Newton correction and the integration error carried to the parameters).  The references are good to
about 1e-9 (the central differences' Richardson estimate of ``mu`` through ``d mu / d kappa`` of about 1) and
1e-13 (the fsolve residual), so each point is asked to lie within its accuracy plus 2e-9.
"""

from __future__ import annotations

import numpy as np
import pytest
import tilted_relay_reference as R
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq, fsolve

from saltation import Flow
from saltation.branches.branch import SpecialPointKind, SpecialPointStatus
from saltation.models import friction_oscillator
from saltation.models.friction_oscillator import DEFAULTS as FRICTION
from saltation.models.tilted_relay import tilted_relay
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.codimension_two import TESTS, CurvePoint, others_of
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.special_points.loci import follow_locus

K = SpecialPointKind
REFERENCE = 2e-9  # the references' own error, and the curve's to the digits the located points claim
KAPPA = -0.7
CURVE_SETTINGS = ContinuationSettings(ds=0.01, ds_max=0.02)


def _codimension_two(locus, sides):
    return [sp for sp in locus.special_points if sp.sides == sides]


# -- the tilted relay: a fold curve of sliding orbits crosses the switching-sliding curve ----------------------------
def sliding_multiplier(kappa, guess, h=1e-6):
    """``(mu, its error, v, t_e)`` at the switching-sliding at ``kappa`` (fsolve from ``guess = (t_e, v)``): the
    derivative of the closed-form map from the middle of the sliding motion to a period later, by central
    differences at ``h`` and ``h/2`` extrapolated (their difference is the error estimate)."""
    v, t_e, x_e, _ = R.switching_sliding_point(kappa, guess=guess)
    p = R.params(kappa=kappa, v=v)
    T = R.period(p)
    t_x, _, _, _ = R.slide_and_return(t_e, x_e, p)
    t_m = 0.5 * (t_e + t_x)
    x_m = float(R.sliding_x(x_e, t_e, t_m, p))

    def period_map(x):
        _, _, t_r, z_r = R.slide_and_return(t_m, x, p)
        return float(R.sliding_x(z_r[0], t_r, t_m + T, p))

    assert abs(period_map(x_m) - x_m) < 1e-10
    d1, d2 = ((period_map(x_m + d) - period_map(x_m - d)) / (2 * d) for d in (h, h / 2))
    return (4 * d2 - d1) / 3, abs(d2 - d1), v, t_e


@pytest.fixture(scope="module")
def relay():
    """The tilted relay's slip orbits continued down in v at kappa = -0.7: a fold of the sliding orbits, the
    switching-sliding, a fold of the orbits that cross into s > 0 before they slide."""
    flow = Flow(tilted_relay())
    problem = ShootingProblem(flow, {"v": 3.5, "kappa": KAPPA}, continuation_parameter="v")
    x0 = R.response(0.0, -1, R.params(v=3.5, kappa=KAPPA))
    br = continue_branch(problem, x0, 3.5, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.0, 3.5)),
                         directions=(-1,))
    return br, problem


@pytest.fixture(scope="module")
def switching_curve(relay):
    br, problem = relay
    (sw,) = [sp for sp in br.special_points if sp.kind is K.SWITCHING_SLIDING]
    return follow_locus(problem, sw, "kappa", (-0.9, -0.4), settings=CURVE_SETTINGS)


@pytest.fixture(scope="module")
def fold_curve(relay):
    """The fold of the sliding orbits (the one below the switching-sliding in v) continued in kappa."""
    br, problem = relay
    folds = [sp for sp in br.special_points if sp.kind is K.FOLD]
    assert len(folds) == 2, [(sp.kind.value, sp.parameter) for sp in br.special_points]
    return follow_locus(problem, min(folds, key=lambda sp: sp.parameter), "kappa", (-0.9, -0.4),
                        settings=CURVE_SETTINGS)


@pytest.fixture(scope="module")
def reference_fold_crossing(switching_curve, relay):
    """``(v, kappa)`` where the closed-form sliding orbit's multiplier is 1 on the switching-sliding curve (brentq
    in kappa, each switching-sliding point by fsolve from the last; the first guess from the located point's
    arrival)."""
    _, problem = relay
    (sp,) = _codimension_two(switching_curve, ("switching_sliding", "fold"))
    p = problem.flow.parameters({"v": sp.parameter, "kappa": sp.second_parameter})
    traj = problem.flow.run(sp.state, 0.0, R.period(R.params()), p)
    guess = [next(e.t for e in traj.events if e.mode_from == "minus"), sp.parameter]

    def mu_minus_one(kappa):
        mu, error, v, t_e = sliding_multiplier(kappa, guess)
        assert error < 1e-8
        guess[:] = [t_e, v]
        return mu - 1.0

    kappa = brentq(mu_minus_one, sp.second_parameter - 0.005, sp.second_parameter + 0.005, xtol=1e-13)
    mu, error, v, _ = sliding_multiplier(kappa, guess)
    assert abs(mu - 1.0) < 1e-9 and error < 1e-8
    return v, kappa


def test_the_reference_multiplier_is_the_libraries_along_the_curve(relay, switching_curve):
    """At curve points, the multipliers the test function reads (the curve's orbit, on whichever side of the
    sliding bifurcation its run falls) against the closed-form sliding orbit's: a zero and ``mu`` to 1e-7 (the
    monodromy through the events at rtol 1e-10, and the reference's 1e-8)."""
    flow = relay[1].flow
    points = switching_curve.points
    checked = 0
    for bp in points[:: max(1, len(points) // 8)]:
        p = flow.parameters({"v": bp.parameter, "kappa": bp.second_parameter})
        traj = flow.run(bp.state, 0.0, R.period(R.params()), p)
        guess = [next(e.t for e in traj.events if e.mode_from == "minus"), bp.parameter]
        mu, error, _, _ = sliding_multiplier(bp.second_parameter, guess)
        got = bp.multipliers[np.argmax(np.abs(bp.multipliers))]
        assert abs(got - mu) < 1e-7 + error
        assert np.min(np.abs(bp.multipliers)) < 1e-12
        checked += 1
    assert checked >= 5


def test_switching_sliding_curve_meets_the_fold_curve(switching_curve, reference_fold_crossing):
    """One codimension-two point on the switching-sliding curve over kappa in [-0.9, -0.4]: the multiplier +1,
    labelled with the curve's kind and the fold it meets, located within its accuracy of the reference."""
    v, kappa = reference_fold_crossing
    assert [sp.sides for sp in switching_curve.special_points] == [("switching_sliding", "fold")]
    (sp,) = switching_curve.special_points
    assert sp.status is SpecialPointStatus.LOCATED and sp.codimension_two is None
    assert sp.accuracy < 5e-8
    assert abs(sp.parameter - v) <= sp.accuracy + REFERENCE
    assert abs(sp.second_parameter - kappa) <= sp.accuracy + REFERENCE
    assert sp.bracket[0] <= sp.parameter <= sp.bracket[1]
    assert np.sort(np.abs(sp.multipliers)) == pytest.approx([0.0, 1.0], abs=1e-7)
    assert "multiplier of its orbits passes +1" in sp.note
    # every curve point is a switching-sliding (the far field's tangency stays invisible)
    assert set(switching_curve.curve_kinds) == {K.SWITCHING_SLIDING}


def test_the_fold_curve_crosses_the_sliding_curve_at_the_same_point(fold_curve, switching_curve,
                                                                    reference_fold_crossing):
    """The fold curve followed on its own from the fold of the sliding orbits: where its orbits' events change by
    the switching-sliding (the plus field's rate at the arrival vanishes) it is located at the same point,
    within both points' accuracies, and within its own of the reference."""
    v, kappa = reference_fold_crossing
    (here,) = _codimension_two(fold_curve, ("fold", "switching_sliding"))
    (there,) = switching_curve.special_points
    assert here.status is SpecialPointStatus.LOCATED
    assert abs(here.parameter - v) <= here.accuracy + REFERENCE
    assert abs(here.second_parameter - kappa) <= here.accuracy + REFERENCE
    assert abs(here.parameter - there.parameter) <= here.accuracy + there.accuracy
    assert abs(here.second_parameter - there.second_parameter) <= here.accuracy + there.accuracy
    # the fold curve passes from the orbits that slide at once to those that cross into s > 0 first: the orbits
    # of both sides have the multiplier +1 there
    before, after = fold_curve.points[here.index], fold_curve.points[here.index + 1]
    assert sorted([len(before.event_labels), len(after.event_labels)]) == [2, 3]


def test_the_fold_curve_of_sliding_orbits_has_no_false_points(fold_curve):
    """Along the fold curve the orbits slide (a multiplier 0): the products of the other test functions (1:1 with
    the next multiplier -1, fold-flip +1, fold-Neimark-Sacker none) stay away from zero; the curve carries the
    crossing and the cusp where its two folds meet (kappa near -0.579, past the crossing) and nothing else."""
    kinds = sorted((sp.sides, None if sp.codimension_two is None else sp.codimension_two.value)
                   for sp in fold_curve.special_points)
    assert kinds == [(("fold", "fold"), "cusp"), (("fold", "switching_sliding"), None)]
    assert all(np.min(np.abs(bp.multipliers)) < 1e-12 for bp in fold_curve.points)


# -- the friction oscillator: switching-sliding turns into crossing-sliding --------------------------------------------
ZETA, AF, W = (FRICTION[k] for k in ("zeta", "a", "omega"))
T = 2 * np.pi / W
EPS = 4 * np.finfo(float).eps
_A = np.array([[0.0, 1.0], [-1.0, -2 * ZETA]])
_D = (1 - W**2) ** 2 + (2 * ZETA * W) ** 2
_LAM, _VEC = np.linalg.eig(_A)
_VINV = np.linalg.inv(_VEC)


def _slip_response(t, friction):
    """The harmonic response of the slower-than-belt slip mode (force +friction)."""
    c, s = AF * (1 - W**2) / _D, AF * 2 * ZETA * W / _D
    return np.array([friction + c * np.cos(W * t) + s * np.sin(W * t), W * (-c * np.sin(W * t) + s * np.cos(W * t))])


def _slip(y, t_from, t, friction):
    E = (_VEC @ np.diag(np.exp(_LAM * (t - t_from))) @ _VINV).real
    return _slip_response(t, friction) + E @ (np.asarray(y) - _slip_response(t_from, friction))


def _first_root(g, a, b):
    ts = np.linspace(a, b, 4001)
    v = np.array([g(t) for t in ts])
    k = np.nonzero(np.sign(v[:-1]) != np.sign(v[1:]))[0][0]
    return brentq(g, ts[k], ts[k + 1], xtol=1e-15, rtol=EPS)


def cubic_arrival_residual(z):
    """The sticking orbit that arrives from the slower side at ``(t_e, x_e)`` where the faster side's field has a
    cubic tangency: periodicity (2), ``L_+ = 0`` and ``dL_+/dt = 0`` there."""
    t_e, x_e, v_b, friction = z
    t_x = _first_root(lambda t: -2 * ZETA * v_b - (x_e + v_b * (t - t_e)) + friction + AF * np.cos(W * t),
                      t_e + 1e-6, t_e + T)  # sticking ends: the slower side's field turns tangent
    y = [x_e + v_b * (t_x - t_e), v_b]
    t_h = _first_root(lambda t: _slip(y, t_x, t, friction)[1] - v_b, t_x + 1e-6, t_x + T)  # back at the belt
    faster = -2 * ZETA * v_b - x_e - friction + AF * np.cos(W * t_e)
    return [t_h - t_e - T, _slip(y, t_x, t_h, friction)[0] - x_e, faster, -v_b - AF * W * np.sin(W * t_e)]


@pytest.fixture(scope="module")
def friction():
    """The friction oscillator's slip orbit continued down in v_b: grazing-, switching- and crossing-sliding."""
    flow = Flow(friction_oscillator())
    phi = np.arctan2(2 * ZETA * W, 1 - W**2)
    amplitude = AF / np.sqrt(_D)
    x0 = np.array([FRICTION["F"] + amplitude * np.cos(-phi), -amplitude * W * np.sin(-phi)])
    problem = ShootingProblem(flow, {"v_b": 2.5}, continuation_parameter="v_b")
    br = continue_branch(problem, x0, 2.5, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.85, 2.5)),
                         directions=(-1,))
    return br, problem


def _friction_curve(friction, kind):
    br, problem = friction
    (sp,) = [s for s in br.special_points if s.kind is kind]
    return follow_locus(problem, sp, "F", (0.45, 1.0), settings=ContinuationSettings(ds=0.02, ds_max=0.05))


@pytest.fixture(scope="module")
def cubic_arrival(friction):
    """``(v_b, F)`` of the reference, fsolve from the switching-sliding curve's located point."""
    _, problem = friction
    curve = _friction_curve(friction, K.SWITCHING_SLIDING)
    (sp,) = _codimension_two(curve, ("switching_sliding", "crossing_sliding"))
    traj = problem.flow.run(sp.state, 0.0, T, problem.flow.parameters({"v_b": sp.parameter, "F": sp.second_parameter}))
    e = next(e for e in traj.events if e.mode_from == "slip_minus")
    z = fsolve(cubic_arrival_residual, [e.t, e.x_minus[0], sp.parameter, sp.second_parameter], xtol=1e-13)
    assert np.abs(cubic_arrival_residual(z)).max() < 1e-12
    return curve, z[2], z[3]


def test_switching_sliding_turns_into_crossing_sliding(cubic_arrival):
    """Along the switching-sliding curve in (v_b, F) the one codimension-two point is the cubic tangency at the
    arrival: labelled with the kinds before and after it, located within its accuracy of the reference, and the
    curve's points are of the one kind before it and of the other after it."""
    curve, v_b, friction = cubic_arrival
    assert [sp.sides for sp in curve.special_points] == [("switching_sliding", "crossing_sliding")]
    (sp,) = curve.special_points
    assert sp.status is SpecialPointStatus.LOCATED and sp.accuracy < 5e-8
    assert abs(sp.parameter - v_b) <= sp.accuracy + REFERENCE
    assert abs(sp.second_parameter - friction) <= sp.accuracy + REFERENCE
    kinds = curve.curve_kinds
    assert set(kinds[: sp.index + 1]) == {K.SWITCHING_SLIDING}
    assert set(kinds[sp.index + 1 :]) == {K.CROSSING_SLIDING}


def test_crossing_sliding_curve_meets_the_mirror_image(friction, cubic_arrival):
    """The crossing-sliding curve from the same branch turns into switching-sliding at the mirror image of the
    reference (v_b -> -v_b at the same F)."""
    _, v_b, friction_level = cubic_arrival
    curve = _friction_curve(friction, K.CROSSING_SLIDING)
    (sp,) = curve.special_points
    assert sp.sides == ("crossing_sliding", "switching_sliding")
    assert sp.status is SpecialPointStatus.LOCATED
    assert abs(sp.parameter + v_b) <= sp.accuracy + REFERENCE
    assert abs(sp.second_parameter - friction_level) <= sp.accuracy + REFERENCE


# -- the test functions on a sliding orbit's multipliers -------------------------------------------------------------
_INSIDE = st.lists(st.floats(min_value=0.05, max_value=0.9), min_size=1, max_size=3)
_OUTSIDE = st.lists(st.floats(min_value=1.1, max_value=3.0), min_size=1, max_size=3)


@settings(max_examples=60, deadline=None)
@given(zeros=st.integers(1, 3), moduli=_INSIDE | _OUTSIDE,
       signs=st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3), kind=st.sampled_from(
           [K.CROSSING_SLIDING, K.SWITCHING_SLIDING, K.ADDING_SLIDING]))
def test_multipliers_zero_never_fake_a_zero(zeros, moduli, signs, kind):
    """A sliding orbit's multipliers 0 (one for each direction its sliding motions forget) enter the tests as
    factors -1 (``mu - 1``), 1 (``mu + 1``) and -1 (``mu_i mu_j - 1``): with the other multipliers real, at least
    0.1 off the unit circle and all inside it or all outside (no pair with product 1), every multiplier test is
    the closed-form product over them, and none vanishes."""
    others = np.array([s * m for s, m in zip(signs, moduli)])
    mu = np.concatenate([np.zeros(zeros), others]).astype(complex)
    point = CurvePoint(z=np.zeros(4), multipliers=mu, monodromy=np.diag(mu.real), kappa=None,
                       others=others_of(mu, kind, None))
    expected = {
        "fold": (-1.0) ** zeros * np.prod(others - 1.0),
        "period_doubling": np.prod(others + 1.0),
        "neimark_sacker": np.prod([a * b - 1.0 for i, a in enumerate(mu.real) for b in mu.real[i + 1 :]]),
    }
    tests = {t.meets: t for t in TESTS[kind] if not t.changes_kind}
    assert set(tests) == set(expected)
    for meets, test in tests.items():
        value = test.value(None, point, None)
        assert value == pytest.approx(expected[meets], rel=1e-12, abs=1e-300)
        assert abs(value) > 0.0


# -- a grazing-sliding curve: the multipliers of the orbits that miss the sliding region ----------------------------
def test_the_grazing_sliding_curve_meets_the_neimark_sacker_curve_of_the_orbits_that_miss_it():
    """The tilted relay's grazing-sliding orbit is the harmonic response of mode ``minus`` touching the boundary of
    the sliding region, ``v = kappa F + A sqrt(kappa^2 + omega^2)``, ``A = a / sqrt((1 - omega^2)^2 + (2 zeta
    omega)^2)``; its multipliers are the linear oscillator's, ``exp((-zeta +- i sqrt(1 - zeta^2)) T)``,
    ``T = 2 pi / omega``.  Along the curve in ``zeta`` through 0 they cross the unit circle at ``zeta = 0``, at
    ``e^{+-i T} = +-i`` (``T = 2.5 pi``): a Neimark-Sacker curve of the orbits that miss the sliding region crosses
    the grazing-sliding curve there."""
    params = R.params()
    kappa, F, a, omega = (params[k] for k in ("kappa", "F", "a", "omega"))
    T = 2 * np.pi / omega
    flow = Flow(tilted_relay())
    problem = ShootingProblem(flow, {"v": 3.0}, continuation_parameter="v")
    branch = continue_branch(problem, R.response(0.0, -1, R.params(v=3.0)), 3.0,
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.2, 3.0)), directions=(-1,))
    (grazing,) = [sp for sp in branch.special_points if sp.kind is K.GRAZING_SLIDING]
    locus = follow_locus(problem, grazing, "zeta", (-0.05, 0.15), settings=CURVE_SETTINGS)
    for p in locus.points:  # the curve and its orbits' multipliers in closed form
        zeta = p.second_parameter
        amplitude = a / np.sqrt((1 - omega**2) ** 2 + (2 * zeta * omega) ** 2)
        assert p.parameter == pytest.approx(kappa * F + amplitude * np.sqrt(kappa**2 + omega**2), abs=REFERENCE)
        pair = np.exp((-zeta + 1j * np.sqrt(1 - zeta**2)) * T)
        np.testing.assert_allclose(np.sort_complex(p.multipliers), np.sort_complex([pair.conjugate(), pair]),
                                   rtol=0, atol=1e-7)
    (point,) = locus.special_points
    assert point.kind is K.CODIMENSION_TWO and point.status is SpecialPointStatus.LOCATED
    assert point.sides == ("grazing_sliding", "neimark_sacker")
    assert abs(point.second_parameter) <= point.accuracy + REFERENCE
    assert abs(point.parameter - (kappa * F + a / abs(1 - omega**2) * np.sqrt(kappa**2 + omega**2))) <= (
        point.accuracy + REFERENCE)
    lo, hi = point.bracket
    assert lo <= point.parameter <= hi
    np.testing.assert_allclose(np.sort_complex(point.multipliers), [-1j, 1j], rtol=0, atol=1e-7)
