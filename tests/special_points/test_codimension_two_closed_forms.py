"""Fold- and flip-Neimark-Sacker, Chenciner and generalized period-doubling points against closed forms.

The model: a clocked map whose period map is a normal form (``tests/clocked_normal_form_reference.py``, numpy and
sympy only).  Three states turn about one axis once a period and are kicked once a period, at ``t = 1/2`` (a clock
``-sin(2 pi t)`` with a reset), by ``u -> C + P G(P^-1 (u - C))``: ``G`` a one-dimensional fold (``sel = 1``) or flip
(``sel = 0``) block beside a two-dimensional Neimark-Sacker block with a cubic term, coupled at second order (the
pair's modulus depends on ``x``, ``x`` on ``|z|^2``), mixed by a fixed invertible ``P`` so that no state is
decoupled.  The period map is ``G`` conjugated by an affine map, so its fixed points, multipliers and cubic
normal-form coefficients are known in closed form (the flip's from the second iterate on the invariant line, the
torus's by reduction to the centre manifold), and so are the codimension-two points:

* ``sel = 1``: the fold curve ``a = 0`` meets the Neimark-Sacker curve ``a = b^2`` (``m = -1``) at the
  fold-Neimark-Sacker point ``a = b = 0``, ``(alpha, beta) = (1/6, 1/6)``; there the Neimark-Sacker curve's
  Lyapunov coefficient ``c - 1 / (4 b)`` passes through infinity (not a Chenciner point);
* ``sel = 0``: the period-doubling curve ``a = 0`` and the Neimark-Sacker curve ``b = 0`` meet at the
  flip-Neimark-Sacker point, again ``(1/6, 1/6)``; the flip coefficient ``beta - 1/4`` vanishes at the generalized
  period doubling ``(1/8, 1/4)``, the Lyapunov coefficient ``alpha - 1/10 - 1 / (2 (2 + a))`` at the Chenciner point
  (a root of a quadratic, ``(0.32794, 0.23118)``).

Each is located by :func:`saltation.special_points.loci.follow_locus` (Chenciner and the generalized period doubling
with ``normal_forms=True``) and checked against these, with the orbit there (state, amplitude, multipliers) and the
cubic coefficients along the curves against the closed forms.
"""

from __future__ import annotations

import clocked_normal_form_reference as ref
import numpy as np
import pytest
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
from saltation.kinds import CodimensionTwoKind, SpecialPointKind, SpecialPointStatus
from saltation.orbits.criticality import criticality
from saltation.special_points.continuation import ContinuationSettings, continue_orbit
from saltation.special_points.loci import follow_locus

C2 = CodimensionTwoKind
PD, NS, FOLD = SpecialPointKind.PERIOD_DOUBLING, SpecialPointKind.NEIMARK_SACKER, SpecialPointKind.FOLD
SETTINGS = ContinuationSettings(ds=0.02, ds_max=0.05)
#: the curves' own error: their points solve the defining systems to 1e-10 with exact flows (affine modes, a
#: polynomial reset), which the unit slopes of the unfolding leave at about that in the parameters
CURVE_ERROR = 1e-9
#: the Chenciner point on the flip model's Neimark-Sacker curve: the root with alpha in this range
CHENCINER_ALPHA = (0.2, 0.5)


def clocked_normal_form() -> PiecewiseSystem:
    return PiecewiseSystem(
        name="clocked_normal_form", states=["u1", "u2", "u3"],
        parameters={"alpha": 0.0, "beta": 0.1, "sel": 0.0},
        modes=[Mode("turn", ["-2*pi*u2", "2*pi*u1", "0"])],
        surfaces={"clock": "-sin(2*pi*t)"},
        transitions=[Transition("turn", "clock", Crossing.RISING, "turn", reset=ref.reset_expressions())],
        period="1",
    )


@pytest.fixture(scope="module")
def flow():
    return Flow(clocked_normal_form())


def _orbit(flow, al: float, be: float, sel: int, sign: int = 1):
    v = ref.fixed_point(al, be, sel, sign)
    return find_periodic_orbit(flow, ref.orbit_state(v), parameters={"alpha": al, "beta": be, "sel": float(sel)})


@pytest.fixture(scope="module")
def flip_model(flow):
    """``sel = 0``: the branch in alpha at beta = 0.1 (a Neimark-Sacker point at alpha = 0, a period doubling at
    0.2), and the period-doubling and Neimark-Sacker curves from them in beta, with the normal forms."""
    orbit = _orbit(flow, -0.1, 0.1, 0)
    branch = continue_orbit(orbit, "alpha", bounds=(-0.1, 0.3), directions=(1,), settings=SETTINGS)
    index = {sp.kind: i for i, sp in enumerate(branch.special_points)}
    pd = follow_locus(branch, index[PD], "beta", (0.05, 0.35), settings=SETTINGS, normal_forms=True)
    ns = follow_locus(branch, index[NS], "beta", (0.05, 0.3), settings=SETTINGS, normal_forms=True)
    return branch, pd, ns


@pytest.fixture(scope="module")
def fold_model(flow):
    """``sel = 1``: the branch of ``x* = -sqrt(a)`` in beta at alpha = 0.3, down through a Neimark-Sacker point to
    the fold at beta = -0.1, and the fold and Neimark-Sacker curves from them in alpha (the latter with the normal
    forms: its Lyapunov coefficient has a pole at the fold-Neimark-Sacker point)."""
    orbit = _orbit(flow, 0.3, 0.3, 1, sign=-1)
    branch = continue_orbit(orbit, "beta", bounds=(-0.15, 0.3), directions=(-1,), settings=SETTINGS)
    index = {sp.kind: i for i, sp in enumerate(branch.special_points)}
    fold = follow_locus(branch, index[FOLD], "alpha", (0.1, 0.35), settings=SETTINGS)
    ns = follow_locus(branch, index[NS], "alpha", (0.15, 0.31), settings=SETTINGS, normal_forms=True)
    return branch, fold, ns


def _curve(request, name: str):
    model, which = name.split(":")
    _, first, second = request.getfixturevalue(model)
    return first if which in ("pd", "fold") else second


# ------------------------------------------------------------------------------------------------
# the model


def test_the_period_map_is_the_normal_form_and_a_clocked_reset_is_no_impact(flow):
    """One kick a period at ``t = 1/2`` (the clock's reset moves every state, yet the clock is crossed by time:
    no impact, no sliding), the orbit at the closed-form fixed point, its monodromy ``R P J P^-1 R`` (an affine flow
    and the reset's Jacobian: to rounding), for the fold's two fixed points and the flip's."""
    assert flow.system.impacts == (False,)
    for al, be, sel, sign in ((0.3, 0.3, 1, -1), (0.3, 0.3, 1, 1), (0.0, 0.3, 0, 1)):
        orbit = _orbit(flow, al, be, sel, sign)
        v = ref.fixed_point(al, be, sel, sign)
        assert ref.nf_residual(al, be, sel, v) < 1e-15
        assert [(e.surface, round(e.t, 12)) for e in orbit.events] == [("clock", 0.5)]
        np.testing.assert_allclose(orbit.state0, ref.orbit_state(v), rtol=0, atol=1e-12)
        np.testing.assert_allclose(orbit.monodromy, ref.monodromy(al, be, sel, v), rtol=0, atol=1e-12)
        assert orbit.amplitude == pytest.approx(ref.amplitude(v), abs=1e-12)


def test_the_branches_special_points_and_their_cubic_coefficients(flip_model, fold_model):
    """The one-parameter branches' points at their closed forms (within the stated accuracy plus 1e-9), and the
    criticality there against the centre-manifold reductions, within its stated accuracy plus 1e-10 (the third
    derivative of a cubic map is exact: the differences err by rounding only)."""
    branch, _, _ = flip_model
    (pd,) = [sp for sp in branch.special_points if sp.kind is PD]
    (ns,) = [sp for sp in branch.special_points if sp.kind is NS]
    assert abs(pd.parameter - 0.2) <= pd.accuracy + CURVE_ERROR and abs(ns.parameter) <= ns.accuracy + CURVE_ERROR
    b, accuracy = pd.normal_form
    assert abs(b - ref.flip_coefficient(0.1)) <= accuracy + 1e-10  # beta - 1/4 < 0: subcritical
    d, accuracy = ns.normal_form
    assert abs(d - ref.lyapunov_coefficient(0.0, 0.1, 0, 0.0)) <= accuracy + 1e-10
    branch, _, _ = fold_model
    (fold,) = [sp for sp in branch.special_points if sp.kind is FOLD]
    (ns,) = [sp for sp in branch.special_points if sp.kind is NS]
    assert abs(fold.parameter + 0.1) <= fold.accuracy + CURVE_ERROR
    # the Neimark-Sacker point of x* = t < 0 at alpha = 0.3: a = t^2, b = t, so 6 alpha / 5 = t^2 - t/2 + 1/5
    t = (0.5 - np.sqrt(0.25 - 4 * (0.2 - 0.36))) / 2
    alpha, beta = ref.fold_torus_point(t)
    assert alpha == pytest.approx(0.3, abs=1e-14) and t < 0
    assert abs(ns.parameter - beta) <= ns.accuracy + CURVE_ERROR
    d, accuracy = ns.normal_form
    assert abs(d - ref.lyapunov_coefficient(alpha, beta, 1, t)) <= accuracy + 1e-10


# ------------------------------------------------------------------------------------------------
# the codimension-two points

EXPECTED = {  # the codimension-two points of each curve, and nothing else
    "fold_model:fold": {C2.FOLD_NEIMARK_SACKER},
    "fold_model:ns": {C2.FOLD_NEIMARK_SACKER},
    "flip_model:pd": {C2.FLIP_NEIMARK_SACKER, C2.GENERALIZED_PERIOD_DOUBLING},
    "flip_model:ns": {C2.FLIP_NEIMARK_SACKER, C2.CHENCINER},
}
CASES = [
    ("fold_model:fold", C2.FOLD_NEIMARK_SACKER, ("fold", "neimark_sacker")),
    ("fold_model:ns", C2.FOLD_NEIMARK_SACKER, ("neimark_sacker", "fold")),
    ("flip_model:pd", C2.FLIP_NEIMARK_SACKER, ("period_doubling", "neimark_sacker")),
    ("flip_model:pd", C2.GENERALIZED_PERIOD_DOUBLING, ("period_doubling", "period_doubling")),
    ("flip_model:ns", C2.FLIP_NEIMARK_SACKER, ("neimark_sacker", "period_doubling")),
    ("flip_model:ns", C2.CHENCINER, ("neimark_sacker", "neimark_sacker")),
]


def _exact(name: CodimensionTwoKind) -> tuple[float, float]:
    if name is C2.GENERALIZED_PERIOD_DOUBLING:
        return ref.generalized_period_doubling()
    if name is C2.CHENCINER:
        return ref.chenciner(CHENCINER_ALPHA)
    return ref.fold_neimark_sacker()


@pytest.mark.parametrize("curve_name", list(EXPECTED))
def test_each_curve_follows_its_closed_form_and_carries_its_codimension_two_points_only(request, curve_name):
    """Every curve point on the closed-form curve (``a = 0``; ``|1 + b + m x*| = 1``, the pair at ``e^{+-i theta}``) to 1e-9,
    its orbit the closed-form fixed point; the points found are the expected ones (no cusp: the fold's quadratic
    coefficient is -1; no resonance: ``kappa`` is constant; no Chenciner point at the pole of the fold model's
    Lyapunov coefficient), each once."""
    curve = _curve(request, curve_name)
    assert "reached a parameter bound" in curve.stop_detail and len(curve.points) > 8
    sel = 1 if curve_name.startswith("fold") else 0
    for p in curve.points:
        al, be = (p.parameter, p.second_parameter) if curve_name.startswith("flip") else (p.second_parameter,
                                                                                         p.parameter)
        a, b = (float(t) for t in ref.unfolding(al, be)[:2])
        # the fixed point whose multipliers are critical: x* = b on the fold model's Neimark-Sacker curve, 0 else
        x_star = b if curve_name == "fold_model:ns" else 0.0
        if curve_name.endswith(("fold", "pd")):
            assert abs(a) < CURVE_ERROR  # the fold's x* = +-sqrt(a) = 0, the flip's -(1 + a) = -1
        elif sel:
            assert abs(a - x_star**2) < CURVE_ERROR  # a fixed point x* = b: a = b^2, and |1 + b + m x*| = 1
        else:
            assert abs(b) < CURVE_ERROR  # x* = 0: |1 + b| = 1
        v = np.array([x_star, 0.0, 0.0])
        np.testing.assert_allclose(p.state, ref.orbit_state(v), rtol=0, atol=1e-8)
        mu = ref.multipliers(al, be, sel, v)
        assert all(np.min(np.abs(mu - m)) < 1e-8 for m in p.multipliers)
    names = [sp.codimension_two for sp in curve.special_points]
    assert sorted(names, key=str) == sorted(EXPECTED[curve_name], key=str)


def _parameters(curve_name: str, sp) -> tuple[float, float]:
    """``(alpha, beta)`` of a point of the curve (the fold model's curves are in alpha, the flip model's in beta)."""
    if curve_name.startswith("flip"):
        return sp.parameter, sp.second_parameter
    return sp.second_parameter, sp.parameter


@pytest.mark.parametrize("curve_name, name, sides", CASES)
def test_each_point_lies_at_its_closed_form_with_the_orbit_there(request, curve_name, name, sides):
    """The located point against the closed form, within its stated accuracy (the final bracket and the curve
    point's own error: its next Newton correction and the integration error, carried to the parameters), inside its
    bracket; the orbit it records is the closed-form fixed point at its parameters (state, amplitude,
    multipliers: to 1e-9, the curve's error), and those multipliers are the point's own within their slope along
    the curve (at most 2 per unit parameter) times the distance: ``+1`` or ``-1`` with ``e^{+-i theta}`` where two
    curves meet, ``-(1 + a)`` with ``e^{+-i theta}`` at the Chenciner point, ``-1`` with ``(1 + b) e^{+-i theta}`` at
    the generalized period doubling."""
    curve = _curve(request, curve_name)
    (sp,) = [sp for sp in curve.special_points if sp.codimension_two is name]
    assert sp.kind is SpecialPointKind.CODIMENSION_TWO and sp.status is SpecialPointStatus.LOCATED
    assert sp.sides == sides and sp.accuracy < 2e-8
    lo, hi = sp.bracket
    assert lo <= sp.parameter <= hi and hi - lo <= sp.accuracy
    al, be = _parameters(curve_name, sp)
    exact = _exact(name)
    tol = sp.accuracy + 1e-12  # (the closed form's own rounding)
    assert abs(al - exact[0]) <= tol and abs(be - exact[1]) <= tol
    # the orbit it records
    sel = 1 if curve_name.startswith("fold") else 0
    b = float(ref.unfolding(al, be)[1])
    # the fixed point whose multipliers are critical: x* = b on the fold model's Neimark-Sacker curve (a = b^2,
    # m = -1), 0 on the fold curve (a = 0, a double root: x* = +-sqrt(a) would turn the curve's 1e-10 into 1e-5)
    v = np.array([b if curve_name == "fold_model:ns" else 0.0, 0.0, 0.0])
    np.testing.assert_allclose(sp.state, ref.orbit_state(v), rtol=0, atol=1e-8)
    assert sp.period == 1.0 and sp.amplitude == pytest.approx(ref.amplitude(v), abs=1e-8)
    closed = ref.multipliers(al, be, sel, v)
    assert len(sp.multipliers) == 3
    for mu in sp.multipliers:
        assert np.min(np.abs(closed - mu)) < 1e-8
    # the point's own multipliers
    distance = 2.0 * tol + 1e-8
    exact_al, exact_be = exact
    ea, eb = (float(t) for t in ref.unfolding(exact_al, exact_be)[:2])
    own = {C2.FOLD_NEIMARK_SACKER: [1.0, np.exp(1j * ref.THETA)],
           C2.FLIP_NEIMARK_SACKER: [-1.0, np.exp(1j * ref.THETA)],
           C2.CHENCINER: [-(1.0 + ea), np.exp(1j * ref.THETA)],
           C2.GENERALIZED_PERIOD_DOUBLING: [-1.0, (1.0 + eb) * np.exp(1j * ref.THETA)]}[name]
    for mu in own:
        assert np.min(np.abs(sp.multipliers - mu)) <= distance
        assert np.min(np.abs(sp.multipliers - np.conj(mu))) <= distance


@pytest.mark.parametrize("curve_name, name, kind", [
    ("flip_model:ns", C2.CHENCINER, NS),
    ("flip_model:pd", C2.GENERALIZED_PERIOD_DOUBLING, PD),
])
def test_the_cubic_coefficient_changes_sign_across_the_point_as_the_closed_form_does(flow, request, curve_name, name,
                                                                                     kind):
    """At the two curve points around the point the orbits' cubic coefficients (``criticality``, orbits solved
    again) have opposite signs and equal the closed form at their parameters within their stated accuracy plus
    the closed form's slope in the parameters (below 2) times the curve's error; at the located point the
    coefficient is zero within its slope between them times the stated accuracy, plus its own accuracy."""
    curve = _curve(request, curve_name)
    (sp,) = [sp for sp in curve.special_points if sp.codimension_two is name]
    values = []
    for p in (curve.points[sp.index], curve.points[sp.index + 1]):
        al, be = p.parameter, p.second_parameter
        orbit = find_periodic_orbit(flow, p.state, parameters={"alpha": al, "beta": be, "sel": 0.0})
        result = criticality(orbit, kind)
        expected = ref.lyapunov_coefficient(al, be, 0, 0.0) if kind is NS else ref.flip_coefficient(be)
        assert abs(result.coefficient - expected) <= result.accuracy + 2 * CURVE_ERROR
        values.append((result.coefficient, al, be))
    (d0, al0, be0), (d1, al1, be1) = values
    assert d0 * d1 < 0
    slope = abs(d1 - d0) / max(abs(al1 - al0), abs(be1 - be0))
    orbit = find_periodic_orbit(flow, sp.state, parameters={"alpha": sp.parameter, "beta": sp.second_parameter,
                                                            "sel": 0.0})
    at = criticality(orbit, kind)
    assert abs(at.coefficient) <= slope * (sp.accuracy + CURVE_ERROR) + at.accuracy


def test_a_sign_change_of_the_lyapunov_coefficient_through_its_pole_is_no_chenciner_point(flow, fold_model):
    """On the fold model's Neimark-Sacker curve ``d = c - 1 / (4 b)`` (``x* = b``, ``H = k / (2 x*)``) changes sign
    between the two curve points around the fold-Neimark-Sacker point, through infinity (the centre manifold there
    is three-dimensional): the orbits' coefficients equal the closed form on both sides, and the curve carries no
    Chenciner point.  Tolerance: the coefficient's stated accuracy plus the closed form's slope in ``b`` times the
    curve's error."""
    _, _, curve = fold_model
    (sp,) = [sp for sp in curve.special_points if sp.codimension_two is C2.FOLD_NEIMARK_SACKER]
    values = []
    for p in (curve.points[sp.index], curve.points[sp.index + 1]):
        al, be = p.second_parameter, p.parameter
        b = float(ref.unfolding(al, be)[1])
        orbit = find_periodic_orbit(flow, p.state, parameters={"alpha": al, "beta": be, "sel": 1.0})
        result = criticality(orbit, NS)
        # the closed form at the curve point's parameters, which lie on the curve to its error; there d moves by
        # TORUS_SCALE / (4 b^2) per unit of b (1e3 here)
        slope = float(ref.TORUS_SCALE) / (4 * b * b)
        assert abs(result.coefficient - ref.lyapunov_coefficient(al, be, 1, b)) <= result.accuracy + slope * CURVE_ERROR
        values.append(result.coefficient)
    assert values[0] * values[1] < 0 and min(map(abs, values)) > 1.0
    assert not [sp for sp in curve.special_points if sp.codimension_two is C2.CHENCINER]


@settings(max_examples=12, deadline=None)
@given(st.floats(0.05, 0.45), st.sampled_from([PD, NS]))
def test_the_cubic_coefficients_along_the_flip_models_curves_against_the_centre_manifold(flow, be, kind):
    """At any point of the flip model's period-doubling curve (``alpha = 1/4 - beta/2``) or Neimark-Sacker curve
    (``alpha = 5 (beta - 1/10) / 2``), the library's ``b`` or ``d`` equals the closed form within its stated accuracy
    plus 1e-10 (the differences of an exact cubic's second derivative err by rounding only)."""
    al = 0.25 - be / 2 if kind is PD else 2.5 * (be - 0.1)
    orbit = _orbit(flow, al, be, 0)
    result = criticality(orbit, kind)
    expected = ref.flip_coefficient(be) if kind is PD else ref.lyapunov_coefficient(al, be, 0, 0.0)
    assert abs(result.coefficient - expected) <= result.accuracy + 1e-10
