"""Strong resonances, the 1:2 resonance and a fold-flip located on two-parameter curves, against references.

* The 1:3 and 1:4 resonances on a Neimark-Sacker curve.  The Jeffcott rotor against a snubber ring
  (``../shared/trial-models/jeffcott_snubber.py``; ``zeta = 0.05``, ``beta = 20``, ``mu = -0.05``, no gravity):
  its whirls in contact all round are equilibria of the frame rotating with the forcing
  (``tests/rotor_reference.py``, numpy and scipy only), so the Neimark-Sacker curve in ``(omega, rho)`` is the
  rotating frame's Hopf curve, where the slow pair of the Jacobian is ``lambda = +-i nu``; the orbit's pair is
  ``exp(+-i nu T)``, ``T = 2 pi / omega``, so ``kappa = cos(nu T)``.  Along the curve (brentq in ``omega`` on the
  pair's real part at each ``rho``), ``kappa`` rises from -0.67 to 0.23 for ``rho`` from 0.55 to 0.85 and passes
  ``-1/2`` (1:3, ``nu T = 4 pi / 3``, the pair ``exp(+-2 pi i / 3)``) and 0 (1:4); the resonances are brentq's
  zeros of ``kappa + 1/2`` and ``kappa`` in ``rho``.
* The 1:2 resonance on a period-doubling curve.  Two masses between compliant stops
  (:mod:`saltation.models.two_mass_stops`): every mode is affine, so the orbit with its six events (stop 1, stop 2,
  stop 1 again) is a linear solve for given switching instants, and its monodromy a product of ``expm`` and the
  saltation matrices of the contacts' entries (those of the exits are ``I``; as in
  ``tests/gallery/test_gallery_two_mass_stops.py``).  A 1:2 resonance is a double root ``-1`` of the characteristic
  polynomial ``p`` of the monodromy: ``p(-1) = p'(-1) = 0`` (smooth in the parameters, unlike the two eigenvalues,
  which split like the square root of a perturbation), solved with the six switching conditions by fsolve for the
  six instants, ``omega`` and ``F``.
* A fold-flip: the fold curve of the rotor with gravity (``g = 0.2``) in ``(omega, zeta)`` meets a period-doubling
  curve.  The reference's period map (``solve_ivp`` with its own events, no saltation) at the located orbit has
  the multipliers ``+1`` and ``-1``; the period-doubling curve finds the same point by its own test function.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import rotor_reference as reference
from conftest import trial_model
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from saltation import Flow, find_periodic_orbit
from saltation.branches.branch import (
    CodimensionTwoKind,
    SpecialPointKind,
    SpecialPointStatus,
)
from saltation.models import two_mass_stops
from saltation.models.two_mass_stops import DEFAULTS as TWO_MASS
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import (
    ContinuationSettings,
    continue_branch,
    continue_orbit,
)
from saltation.special_points.loci import follow_locus

TWO_PI = 2.0 * np.pi
C2 = CodimensionTwoKind


def _nearest(multipliers: np.ndarray, target: complex, k: int = 0) -> complex:
    """The ``k``-th nearest multiplier to ``target``."""
    mu = np.asarray(multipliers, dtype=complex)
    return mu[np.argsort(np.abs(mu - target), kind="stable")[k]]


# ------------------------------------------------------------------------------------------------
# (a) 1:3 and 1:4 on the rotor's Neimark-Sacker curve, against the rotating frame's Hopf curve

ROTOR = {"zeta": 0.05, "beta": 20.0, "mu": -0.05}
RHO0, OMEGA0 = 0.55, 1.15
RHO_RANGE = (0.55, 0.85)


def _rotating_eigenvalues(omega: float, rho: float) -> np.ndarray:
    whirls = reference.contact_whirl(omega, rho=rho, **ROTOR)
    assert len(whirls) == 1  # one whirl in contact all round near the Hopf curve
    return np.linalg.eigvals(reference.rotating_jacobian(omega, *whirls[0], rho=rho, **ROTOR))


def hopf(rho: float) -> tuple[float, float]:
    """``(omega, nu T)`` on the rotating frame's Hopf curve at ``rho``: brentq in omega on the largest real part
    (the slow pair's), which changes sign once between 1.10 and 1.20."""
    omega = brentq(lambda om: np.max(_rotating_eigenvalues(om, rho).real), 1.10, 1.20, xtol=1e-15, rtol=8.9e-16)
    lam = _rotating_eigenvalues(omega, rho)
    return omega, abs(lam[np.argmax(lam.real)].imag) * TWO_PI / omega


def strong_resonance(kappa: float, bracket: tuple[float, float]) -> tuple[float, float]:
    """``(omega, rho)`` where ``cos(nu T) = kappa`` on the Hopf curve."""
    rho = brentq(lambda r: np.cos(hopf(r)[1]) - kappa, *bracket, xtol=1e-15, rtol=8.9e-16)
    return hopf(rho)[0], rho


@pytest.fixture(scope="module")
def ns_curve():
    system = trial_model("jeffcott_snubber").rotor(rho=RHO0, **ROTOR)
    problem = ShootingProblem(Flow(system), {"omega": OMEGA0}, continuation_parameter="omega")
    (whirl,) = reference.contact_whirl(OMEGA0, rho=RHO0, **ROTOR)
    branch = continue_branch(problem, reference.contact_whirl_state(OMEGA0, *whirl), OMEGA0,
                             settings=ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(OMEGA0, 1.2)), directions=(1,))
    (ns,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.NEIMARK_SACKER]
    return follow_locus(problem, ns, "rho", RHO_RANGE, settings=ContinuationSettings(ds=0.02, ds_max=0.05))


def test_the_rotor_curve_has_the_1_3_and_1_4_resonances_and_nothing_else(ns_curve):
    """Between the bounds ``kappa`` stays within (-1, 1) (no 1:1 or 1:2) and the other pair of the rotating frame
    stays stable (no fold- or flip-Neimark-Sacker point): the curve carries the two resonances only, in order."""
    assert "reached a parameter bound" in ns_curve.stop_detail and len(ns_curve.points) > 10
    for rho in RHO_RANGE:
        assert -0.7 < np.cos(hopf(rho)[1]) < 0.25
    names = [sp.codimension_two for sp in sorted(ns_curve.special_points, key=lambda sp: sp.second_parameter)]
    assert names == [C2.STRONG_RESONANCE_1_3, C2.STRONG_RESONANCE_1_4]


@pytest.mark.parametrize("name, kappa, bracket, theta", [
    (C2.STRONG_RESONANCE_1_3, -0.5, (0.58, 0.64), TWO_PI / 3),
    (C2.STRONG_RESONANCE_1_4, 0.0, (0.74, 0.80), np.pi / 2),
])
def test_strong_resonances_lie_where_the_closed_form_pair_is_a_cube_or_fourth_root_of_one(ns_curve, name, kappa,
                                                                                           bracket, theta):
    """The located point against brentq's zero of ``cos(nu T) - kappa`` along the Hopf curve.

    Tolerance: the stated accuracy (the final bracket of the test function ``kappa + 1/2`` or ``kappa``, in both
    parameters) plus 1e-9 for the curve's own error: its points solve the defining system to 1e-10 with an
    integration error of about 1e-10, which ``kappa``'s slope along the curve (3 per unit of ``rho``) leaves at
    about 3e-11 in the parameters.  The orbit's pair there is ``exp(+-i theta)`` to the slope of ``theta`` along
    the curve times the same; its multipliers agree with ``exp(lambda T)`` to 1e-8 (the monodromy to the
    integration tolerance, a well-separated spectrum)."""
    (sp,) = [sp for sp in ns_curve.special_points if sp.codimension_two is name]
    assert sp.kind is SpecialPointKind.CODIMENSION_TWO and sp.status is SpecialPointStatus.LOCATED
    assert sp.sides == ("neimark_sacker", "neimark_sacker")
    omega, rho = strong_resonance(kappa, bracket)
    tol = sp.accuracy + 1e-9
    assert sp.accuracy < 2e-8  # located to the search's tolerance, 1e-8 relative
    assert abs(sp.parameter - omega) <= tol and abs(sp.second_parameter - rho) <= tol
    # the orbit there: the closed-form whirl, its multipliers exp(lambda T)
    (whirl,) = reference.contact_whirl(sp.parameter, rho=sp.second_parameter, **ROTOR)
    np.testing.assert_allclose(sp.state, reference.contact_whirl_state(sp.parameter, *whirl), rtol=0, atol=1e-7)
    J = reference.rotating_jacobian(sp.parameter, *whirl, rho=sp.second_parameter, **ROTOR)
    closed = np.linalg.eigvals(expm(J * TWO_PI / sp.parameter))
    for m in sp.multipliers:
        assert np.min(np.abs(closed - m)) < 1e-8
    pair = _nearest(sp.multipliers, np.exp(1j * theta))
    h = 1e-5
    slope = abs(hopf(rho + h)[1] - hopf(rho - h)[1]) / (2 * h)  # of nu T along the curve, per unit rho
    assert abs(abs(pair) - 1.0) < 1e-8
    assert abs(abs(np.angle(pair)) - theta) <= slope * tol + 1e-8
    # the resonance itself: the pair is a cube (fourth) root of one
    order = round(TWO_PI / theta)
    assert abs(pair**order - 1.0) <= order * (slope * tol + 1e-8)


# ------------------------------------------------------------------------------------------------
# (b) 1:2 on the period-doubling curve of two masses between stops, against matrix exponentials

TWO_MASS_STATE = [0.8869838955762865, 0.02956094651817481, 1.3985524338147999, -0.19102019176461646]
F_RANGE = (0.85, 1.005)
I4 = np.eye(4)
# the orbit's modes from t = 0 between its six events (stop 1, stop 2, stop 1 again), and the surfaces crossed
MODES = [(False, False), (True, False), (False, False), (False, True), (False, False), (True, False), (False, False)]
SURFACES = ["gap_1", "force_1", "gap_2", "force_2", "gap_1", "force_1"]


def _mode(stop_1: bool, stop_2: bool, omega: float, F: float):
    """``(A, x_s, Z)``: the mode's field ``A x + c + g cos(omega t)`` and its particular solution
    ``x_s + Re(Z exp(i omega t))``."""
    p = TWO_MASS
    A = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [-(p["k1"] + p["k2"]) / p["m1"], -(p["c1"] + p["c2"]) / p["m1"], p["k2"] / p["m1"], p["c2"] / p["m1"]],
        [0.0, 0.0, 0.0, 1.0],
        [p["k2"] / p["m2"], p["c2"] / p["m2"], -p["k2"] / p["m2"], -p["c2"] / p["m2"]],
    ])
    c = np.zeros(4)
    if stop_1:  # -(k_s1 (x1 - d1) + c_s1 v1) / m1
        A[1, 0] -= p["k_s1"] / p["m1"]
        A[1, 1] -= p["c_s1"] / p["m1"]
        c[1] += p["k_s1"] * p["d1"] / p["m1"]
    if stop_2:  # -(k_s2 (x2 + d2) + c_s2 v2) / m2
        A[3, 2] -= p["k_s2"] / p["m2"]
        A[3, 3] -= p["c_s2"] / p["m2"]
        c[3] -= p["k_s2"] * p["d2"] / p["m2"]
    g = np.array([0.0, F / p["m1"], 0.0, 0.0])
    return A, -np.linalg.solve(A, c), np.linalg.solve(1j * omega * I4 - A, g)


def _surface(name: str, x: np.ndarray) -> float:
    p = TWO_MASS
    return {"gap_1": x[0] - p["d1"], "force_1": p["k_s1"] * (x[0] - p["d1"]) + p["c_s1"] * x[1],
            "gap_2": x[2] + p["d2"], "force_2": p["k_s2"] * (x[2] + p["d2"]) + p["c_s2"] * x[3]}[name]


#: entering a stop on its gap surface: ``I - (c_s / m) e_v e_x^T`` (the stop's force is ``c_s v`` there); leaving it
#: on the force surface the field is continuous: ``I``
_ENTRY = {"gap_1": I4 - TWO_MASS["c_s1"] / TWO_MASS["m1"] * np.outer(I4[1], I4[0]),
          "gap_2": I4 - TWO_MASS["c_s2"] / TWO_MASS["m2"] * np.outer(I4[3], I4[2])}


def two_mass_orbit(times, omega: float, F: float) -> tuple[list[np.ndarray], np.ndarray]:
    """The states at ``t = 0`` and at the six switching instants of the periodic orbit of :data:`MODES`, and its
    monodromy (``expm`` factors and the entries' saltation matrices)."""
    knots = [0.0, *times, TWO_PI / omega]
    maps, L, b = [], I4, np.zeros(4)
    for (s1, s2), ta, tb in zip(MODES, knots[:-1], knots[1:]):
        A, x_s, Z = _mode(s1, s2, omega, F)
        E = expm(A * (tb - ta))
        e = x_s + (Z * np.exp(1j * omega * tb)).real - E @ (x_s + (Z * np.exp(1j * omega * ta)).real)
        maps.append((E, e))
        L, b = E @ L, E @ b + e
    states, M = [np.linalg.solve(I4 - L, b)], I4
    for k, (E, e) in enumerate(maps):
        states.append(E @ states[-1] + e)
        M = E @ M
        if k < len(SURFACES):
            M = _ENTRY.get(SURFACES[k], I4) @ M
    return states, M


def one_two_resonance(times, omega: float, F: float) -> np.ndarray:
    """``(six instants, omega, F)`` of the 1:2 resonance near the guess: the switching conditions and
    ``p(-1) = p'(-1) = 0``, by fsolve; the residual is checked."""

    def residual(z):
        states, M = two_mass_orbit(z[:6], z[6], z[7])
        c = np.poly(M)
        return np.array([_surface(s, states[k + 1]) for k, s in enumerate(SURFACES)]
                        + [np.polyval(c, -1.0), np.polyval(np.polyder(c), -1.0)])

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # (fsolve: "not making good progress" at rounding level)
        z = fsolve(residual, np.array([*times, omega, F]), xtol=1e-13)
    assert np.max(np.abs(residual(z))) < 1e-12
    assert np.all(np.diff([0.0, *z[:6], TWO_PI / z[6]]) > 0)
    return z


@pytest.fixture(scope="module")
def pd_curve():
    flow = Flow(two_mass_stops())
    orbit = find_periodic_orbit(flow, TWO_MASS_STATE, parameters={"omega": 0.452})
    branch = continue_orbit(orbit, "omega", bounds=(0.4512, 0.452), directions=(-1,),
                            settings=ContinuationSettings(ds=3e-4, ds_max=5e-4))
    index = next(i for i, sp in enumerate(branch.special_points) if sp.kind is SpecialPointKind.PERIOD_DOUBLING)
    return flow, follow_locus(branch, index, "F", F_RANGE, settings=ContinuationSettings(ds=0.01, ds_max=0.03))


def _resolved(flow: Flow, state, omega: float, F: float):
    return find_periodic_orbit(flow, state, parameters={"omega": omega, "F": F})


def test_the_1_2_resonances_of_the_two_mass_curve_against_matrix_exponentials(pd_curve):
    """Two 1:2 points (F near 0.8638 and 0.8956, between which the second multiplier lies below -1), each
    against the double root of the characteristic polynomial.

    Tolerance: the stated accuracy (the test function's final bracket, in both parameters) plus 1e-9 for the
    curve's own error (its points solve the defining system to 1e-10; the flows are exact).  The test function
    reads the second multiplier's ``mu + 1`` from the sum of the two multipliers nearest -1, which is as accurate
    as the monodromy; the eigenvalues themselves, 1e-7 apart or less near the point, are split by rounding by
    about 1e-7 (the square root of the monodromy's 1e-14), which is 5e-9 in ``F`` at the test function's slope of
    about 20 per unit ``F``: more than the margin, so the margin checks that the eigenvalues are not read
    one by one."""
    flow, curve = pd_curve
    points = sorted((sp for sp in curve.special_points if sp.codimension_two is C2.STRONG_RESONANCE_1_2),
                    key=lambda sp: sp.second_parameter)
    assert [sp.second_parameter for sp in points] == pytest.approx([0.8638, 0.8956], abs=1e-4)
    for sp in points:
        assert sp.status is SpecialPointStatus.LOCATED and sp.sides == ("period_doubling", "period_doubling")
        orbit = _resolved(flow, sp.state, sp.parameter, sp.second_parameter)
        assert len(orbit.events) == 6
        times = [e.t for e in orbit.events]
        states, M = two_mass_orbit(times, sp.parameter, sp.second_parameter)
        # the same orbit, and the same monodromy (exact flows and saltation matrices: to rounding)
        np.testing.assert_allclose(states[0], orbit.state0, rtol=0, atol=1e-9)
        np.testing.assert_allclose(M, orbit.monodromy, rtol=0, atol=1e-10)
        z = one_two_resonance(times, sp.parameter, sp.second_parameter)
        tol = sp.accuracy + 1e-9
        assert abs(sp.parameter - z[6]) <= tol and abs(sp.second_parameter - z[7]) <= tol


def test_at_a_1_2_resonance_two_multipliers_are_at_minus_one_and_the_second_one_crosses_it(pd_curve):
    """At each located point the orbit, solved again by shooting at its two parameters, has two multipliers at -1,
    and the point lies between two curve points (orbits solved again too) whose second-nearest multiplier to -1
    lies on either side of -1.

    Tolerances.  A double multiplier of a Jordan block moves like the square root of a perturbation: within
    ``d`` (in the parameters) of the resonance each may lie ``sqrt(d)`` (times a constant of order one) from -1,
    with ``d`` the stated accuracy plus 1e-9 (the curve's error, see above): about 1e-4.  Their sum
    (the trace of the monodromy on the pair's invariant plane) is smooth: ``|mu_1 + mu_2 + 2|`` is at most its
    slope along the curve (that of the second multiplier between the bracketing points, doubled) times ``d``,
    and so is ``|mu_1 mu_2 - 1|``."""
    flow, curve = pd_curve
    points = [sp for sp in curve.special_points if sp.codimension_two is C2.STRONG_RESONANCE_1_2]
    assert len(points) == 2
    for sp in points:
        a, b = curve.points[sp.index], curve.points[sp.index + 1]
        for first, second in ((sp.parameter, a.parameter), (sp.second_parameter, a.second_parameter)):
            other = b.parameter if first == sp.parameter else b.second_parameter
            assert min(second, other) <= first <= max(second, other)
        sides = []
        for bp in (a, b):
            mu = _resolved(flow, bp.state, bp.parameter, bp.second_parameter).multipliers
            assert abs(_nearest(mu, -1.0) + 1.0) < 1e-8  # a period doubling (the curve's own)
            second = _nearest(mu, -1.0, 1)
            assert abs(second.imag) < 1e-12
            sides.append(second.real + 1.0)
        assert sides[0] * sides[1] < 0  # the test function changes sign between them
        width = max(abs(b.parameter - a.parameter), abs(b.second_parameter - a.second_parameter))
        slope = abs(sides[1] - sides[0]) / width
        d = sp.accuracy + 1e-9
        mu = _resolved(flow, sp.state, sp.parameter, sp.second_parameter).multipliers
        pair = np.array([_nearest(mu, -1.0, 0), _nearest(mu, -1.0, 1)])
        assert np.all(np.abs(pair + 1.0) <= np.sqrt(d))
        assert abs(pair.sum() + 2.0) <= 2 * slope * d and abs(pair.prod() - 1.0) <= 2 * slope * d
        # the others are far from -1: the resonance is a double multiplier, not a triple one
        assert np.all(np.abs(np.delete(mu, np.argsort(np.abs(mu + 1.0))[:2]) + 1.0) > 0.5)


@settings(max_examples=60, deadline=None)
@given(st.floats(1e-10, 1e-6), st.sampled_from([-1.0, 1.0]), st.sampled_from([-1.0, 1.0]),
       st.integers(0, 2**32 - 1))
def test_the_second_multiplier_is_read_from_the_pair_sum_near_a_jordan_block(size, sign, target, seed):
    """Near a 1:2 (1:1) resonance the monodromy is close to a Jordan block at -1 (+1): ``M = V J V^-1`` with
    ``J`` holding ``target`` (the curve's own), ``target + delta`` coupled to it by 1, and -0.3 and 0.2.  The test
    function is ``delta (-0.3 - target) (0.2 - target)``: the eigenvalues of the pair come out of ``eigvals``
    up to the square root of the rounding (1e-8 here, more than ``delta``), their sum to the rounding; so the
    value agrees to 1e-12 (a few times the rounding of ``M`` through the well-conditioned ``V``) and has the sign
    of ``delta`` for every ``delta`` down to 1e-10."""
    from saltation.special_points.codimension_two import TESTS, CurvePoint, others_of

    delta = sign * size
    rng = np.random.default_rng(seed)
    V = np.eye(4) + 0.3 * rng.uniform(-1.0, 1.0, (4, 4))
    J = np.diag([target, target + delta, -0.3, 0.2])
    J[0, 1] = 1.0
    M = V @ J @ np.linalg.inv(V)
    kind = SpecialPointKind.PERIOD_DOUBLING if target < 0 else SpecialPointKind.FOLD
    name = C2.STRONG_RESONANCE_1_2 if target < 0 else C2.STRONG_RESONANCE_1_1
    (test,) = [t for t in TESTS[kind] if t.name is name]
    mu = np.linalg.eigvals(M)
    point = CurvePoint(z=np.zeros(6), multipliers=mu, monodromy=M, kappa=None, others=others_of(mu, kind, None))
    value = test.value(None, point, None)
    expected = delta * (-0.3 - target) * (0.2 - target)
    assert abs(value - expected) < 1e-12 and value * delta > 0


def test_a_curve_ending_at_a_contact_that_vanishes_where_its_stop_is_met_again_claims_no_end(pd_curve):
    """Below ``F = 0.8509`` the period-doubling curve's first contact with stop 1 shrinks to nothing while the
    orbit meets stop 1 again later in the period: the grazing's virtual orbit, which passes the contact's entry
    without firing it for the whole period, would miss the second contact too.  That end used to be labelled a
    located corner at ``omega = 0.31`` (another orbit's grazing, 0.13 from the curve); it is left unlabelled."""
    flow, curve = pd_curve
    assert curve.stop_detail.endswith("decreasing F: the corrector failed at the minimum step size")
    end = curve.points[0]  # the decreasing run's last point
    assert end.second_parameter == pytest.approx(0.85093, abs=1e-5)
    orbit = _resolved(flow, end.state, end.parameter, end.second_parameter)
    entries = [e for e in orbit.events if e.transition == orbit.events[0].transition]
    assert len(entries) == 2 and orbit.events[1].t - orbit.events[0].t < 0.01  # the vanishing contact first
    # every codimension-two point lies on the curve's span
    for sp in curve.special_points:
        assert curve.values[:, 0].min() <= sp.parameter <= curve.values[:, 0].max()
    assert all(sp.codimension_two is C2.STRONG_RESONANCE_1_2 for sp in curve.special_points)


# ------------------------------------------------------------------------------------------------
# (c) a fold-flip of the rotor with gravity, against solve_ivp's period map

GRAVITY = {"g": 0.2}
ZETA_RANGE = (0.05, 0.12)


@pytest.fixture(scope="module")
def gravity_curves():
    """The fold curve (from the fold near omega = 0.9602) and the period-doubling curve (from the doubling near
    0.9385 beyond it) of the rotor with gravity, in ``(omega, zeta)``."""
    flow = Flow(trial_model("jeffcott_snubber").rotor(**GRAVITY))
    _, _, state, extra = reference.GRAVITY_POINTS[9]  # the fold's
    omega = extra["omega_guess"] - 0.004
    orbit = find_periodic_orbit(flow, state, parameters={"omega": omega})
    branch = continue_orbit(orbit, "omega", bounds=(0.936, 0.965), directions=(1,),
                            settings=ContinuationSettings(ds=0.002, ds_max=0.005))
    index = {sp.kind: i for i, sp in enumerate(branch.special_points)}
    settings = ContinuationSettings(ds=0.005, ds_max=0.02)
    fold = follow_locus(branch, index[SpecialPointKind.FOLD], "zeta", ZETA_RANGE, settings=settings)
    pd = follow_locus(branch, index[SpecialPointKind.PERIOD_DOUBLING], "zeta", ZETA_RANGE, settings=settings)
    return fold, pd


def _reference_multipliers(state, omega: float, zeta: float) -> tuple[float, np.ndarray]:
    """``|P(x) - x|`` and the eigenvalues of the monodromy, from solve_ivp with its own events."""
    P, M = reference.period_map(state, omega, zeta=zeta, **GRAVITY)
    return float(np.max(np.abs(P - np.asarray(state)))), np.linalg.eigvals(M)


def test_a_fold_flip_on_the_rotor_fold_curve_against_solve_ivp(gravity_curves):
    """Where a second multiplier of the fold curve's orbits passes -1.  The reference's period map from the
    located state closes (to 1e-8: the library's orbit at the reference's ``rtol = 1e-12``) and has the
    multipliers +1 (the curve's: to 1e-7, the reference's monodromy to about 1e-9 and a simple eigenvalue) and
    -1 (to the test function's slope along the curve times the stated accuracy, plus 1e-7); its second multiplier
    lies on either side of -1 at the two curve points around the point."""
    fold, _ = gravity_curves
    (ff,) = [sp for sp in fold.special_points if sp.codimension_two is C2.FOLD_FLIP]
    assert ff.status is SpecialPointStatus.LOCATED and ff.sides == ("fold", "period_doubling")
    assert ff.accuracy < 2e-8
    a, b = fold.points[ff.index], fold.points[ff.index + 1]
    sides = []
    for bp in (a, b):
        gap, mu = _reference_multipliers(bp.state, bp.parameter, bp.second_parameter)
        assert gap < 1e-8 and abs(_nearest(mu, 1.0) - 1.0) < 1e-7
        sides.append(float(_nearest(mu, -1.0).real) + 1.0)
    assert sides[0] * sides[1] < 0
    slope = abs(sides[1] - sides[0]) / max(abs(b.parameter - a.parameter), abs(b.second_parameter - a.second_parameter))
    gap, mu = _reference_multipliers(ff.state, ff.parameter, ff.second_parameter)
    assert gap < 1e-8
    assert abs(_nearest(mu, 1.0) - 1.0) < 1e-7
    assert abs(_nearest(mu, -1.0) + 1.0) <= 2 * slope * ff.accuracy + 1e-7


def test_the_period_doubling_curve_meets_the_fold_curve_at_the_same_fold_flip(gravity_curves):
    """The period-doubling curve finds the point by its own test function (a multiplier at +1): within the sum
    of the two stated accuracies plus 1e-9 (the curves' own errors, see the Neimark-Sacker test)."""
    fold, pd = gravity_curves
    (a,) = [sp for sp in fold.special_points if sp.codimension_two is C2.FOLD_FLIP]
    near = [sp for sp in pd.special_points if sp.codimension_two is C2.FOLD_FLIP
            and abs(sp.second_parameter - a.second_parameter) < 1e-3]
    (b,) = near
    assert b.sides == ("period_doubling", "fold") and b.status is SpecialPointStatus.LOCATED
    tol = a.accuracy + b.accuracy + 1e-9
    assert abs(a.parameter - b.parameter) <= tol and abs(a.second_parameter - b.second_parameter) <= tol
