"""Continuation, special points and the paper's diagrams against independent references."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from saltation import Flow
from saltation.special_points.detection import classify_nonsmooth, symmetric_crossing
from saltation.branches.branch import Limits, SpecialPointKind, SpecialPointStatus
from saltation.special_points.continuation import Continuation, ContinuationSettings, continue_branch
from saltation.models import block_on_belt, trilinear
from saltation.models.block_on_belt import DEFAULTS as BELT
from saltation.models.trilinear import DEFAULTS as TRI
from saltation.apps.paper import PaperSettings, block_on_belt_diagram, linear_response_state
from saltation.orbits.shooting import EquilibriumProblem, ShootingProblem

M, C, K, F0, XC, CF = (TRI[k] for k in ("m", "c", "k", "f0", "x_c", "c_f"))
A_FREE = np.array([[0.0, 1.0], [-K / M, -C / M]])
S_CONTACT = np.array([[1.0, 0.0], [-CF / M, 1.0]])  # eqs. (11), (13); S_1b = S_2b = I


def linear_amplitude(w):
    return F0 / np.sqrt((K - M * w**2) ** 2 + (C * w) ** 2)


def corner_frequencies():
    """Roots of m^2 w^4 + (c^2 - 2km) w^2 + k^2 - (f0/x_c)^2 = 0 (amplitude = x_c)."""
    w2 = np.roots([M**2, C**2 - 2 * K * M, K**2 - (F0 / XC) ** 2])
    return np.sort(np.sqrt(w2[w2 > 0].real))


@pytest.fixture(scope="module")
def tri_flow():
    return Flow(trilinear())


@pytest.fixture(scope="module")
def tri_branch(tri_flow):
    lo, hi = 0.6, 1.6
    problem = ShootingProblem(tri_flow, {"omega": lo}, continuation_parameter="omega")
    settings = ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(lo, hi))
    x0 = linear_response_state(dict(TRI) | {"omega": lo})
    return continue_branch(problem, x0, lo, settings=settings, directions=(1,)), problem


@pytest.fixture(scope="module")
def belt_diagram():
    return block_on_belt_diagram(PaperSettings(ds=0.02, ds_max=0.05))


def test_no_contact_branch_matches_closed_form_amplitude(tri_branch):
    branch, _ = tri_branch
    free = [p for p in branch.points if not p.event_labels]
    assert len(free) > 20
    for p in free:
        assert p.amplitude == pytest.approx(linear_amplitude(p.parameter), rel=1e-8)
        mu = np.sort_complex(np.linalg.eigvals(expm(A_FREE * 2 * np.pi / p.parameter)))
        assert np.allclose(np.sort_complex(p.multipliers), mu, atol=1e-8)


def test_corners_located_at_closed_form(tri_branch):
    branch, _ = tri_branch
    w_a, w_b = corner_frequencies()
    nonsmooth = [sp for sp in branch.special_points if sp.kind.is_nonsmooth]
    assert len(nonsmooth) == 2
    at_a = min(nonsmooth, key=lambda sp: abs(sp.parameter - w_a))
    at_b = min(nonsmooth, key=lambda sp: abs(sp.parameter - w_b))
    assert at_a.parameter == pytest.approx(w_a, abs=1e-8)
    assert at_b.parameter == pytest.approx(w_b, abs=1e-8)
    # the jump at w_A stays inside the unit circle, the one at w_B crosses through +1
    assert at_a.kind is SpecialPointKind.NONSMOOTH_NO_CROSSING
    assert at_b.kind is SpecialPointKind.DISCONTINUOUS_FOLD
    assert at_b.crossing_point == pytest.approx(1.0, abs=1e-8)
    assert 0.0 < at_b.crossing_q < 1.0
    assert at_a.amplitude == pytest.approx(XC, abs=1e-7)


def test_smooth_fold_at_top_of_peak(tri_branch):
    branch, problem = tri_branch
    folds = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.FOLD]
    assert len(folds) == 1
    fold = folds[0]
    # a fold of a forced orbit has a multiplier +1 ...
    assert np.min(np.abs(fold.multipliers - 1.0)) < 1e-5
    # ... and is the largest frequency reached by the contact part of the branch
    contact = np.array([p.parameter for p in branch.points if p.event_labels])
    assert fold.parameter >= contact.max() - 1e-12
    assert fold.parameter == pytest.approx(contact.max(), abs=1e-3)


def one_sided_monodromies(w):
    """Free-flight monodromy, and the same with the contact saltation matrices at the touching instants."""
    T = 2 * np.pi / w
    det = (K - M * w**2) ** 2 + (C * w) ** 2
    a, b = F0 * (K - M * w**2) / det, -F0 * C * w / det  # x = a sin(wt) + b cos(wt)
    t_max = (np.arctan2(a, b) / w) % T  # where x reaches +X
    t_min = (t_max + T / 2) % T
    t1, t2 = sorted((t_max, t_min))
    m_minus = expm(A_FREE * T)
    m_plus = expm(A_FREE * (T - t2)) @ S_CONTACT @ expm(A_FREE * (t2 - t1)) @ S_CONTACT @ expm(A_FREE * t1)
    return m_minus, m_plus


def one_sided_half_maps(w):
    """The half-period maps' Jacobians ``-Phi(T/2)`` without and with the contact at the first touch."""
    T = 2 * np.pi / w
    det = (K - M * w**2) ** 2 + (C * w) ** 2
    a, b = F0 * (K - M * w**2) / det, -F0 * C * w / det
    t1 = (np.arctan2(a, b) / w) % (T / 2)  # the first touch (the other is half a period later)
    return -expm(A_FREE * T / 2), -expm(A_FREE * (T / 2 - t1)) @ S_CONTACT @ expm(A_FREE * t1)


def test_one_sided_multipliers_at_corners(tri_branch):
    """M- and M+ are the limits at the boundary orbit: eig(expm(A T)) and the same product with S_1a and
    S_2a inserted at the touching instants (the contact lasts zero time), at the located parameter."""
    branch, _ = tri_branch
    corners = [sp for sp in branch.special_points if sp.kind.is_nonsmooth]
    assert len(corners) == 2
    for sp in corners:
        assert sp.limits == "exact"
        m_free, m_contact = one_sided_monodromies(sp.parameter)
        free_side, contact_side = (
            (sp.multipliers_minus, sp.multipliers_plus) if not sp.event_labels_minus else (sp.multipliers_plus, sp.multipliers_minus)
        )
        np.testing.assert_allclose(np.sort_complex(free_side), np.sort_complex(np.linalg.eigvals(m_free)), rtol=0, atol=1e-9)
        np.testing.assert_allclose(np.sort_complex(contact_side), np.sort_complex(np.linalg.eigvals(m_contact)), rtol=0, atol=1e-9)
        # the crossing of the set-valued multipliers, from the reference matrices: the orbit is symmetric
        # (x -> -x, t -> t + T/2), so the set is that of the half-period map, S Phi(T/2) with the contact
        # saltation matrix at the touch of the first half; the full monodromies give the same kind
        h_free, h_contact = one_sided_half_maps(sp.parameter)
        ref = symmetric_crossing(classify_nonsmooth(*((h_free, h_contact) if not sp.event_labels_minus
                                                      else (h_contact, h_free))))
        assert ref.kind is sp.kind
        full = classify_nonsmooth(*((m_free, m_contact) if not sp.event_labels_minus else (m_contact, m_free)))
        assert full.kind is sp.kind
        # where the set crosses: on the convex hull (1 - q) M- + q M+ of the full monodromies (Leine, Van Campen
        # and Van de Vrande 2000), not on that of the half-period maps, whose squares are not in it (w_B: q =
        # 0.441652, the complement of 0.558348 as the sides are ordered here)
        if full.q is not None:
            assert sp.crossing_q == pytest.approx(full.q, abs=1e-9)
            assert sp.crossing_point == pytest.approx(full.point, abs=1e-9)
            assert abs(abs(sp.crossing_point) - 1.0) <= 1e-9
        # the stated accuracy covers the distance to the exact corner (closed-form frequency)
        w_exact = min(corner_frequencies(), key=lambda w: abs(w - sp.parameter))
        m_free_exact, m_contact_exact = one_sided_monodromies(w_exact)
        err = max(
            np.abs(np.sort_complex(free_side) - np.sort_complex(np.linalg.eigvals(m_free_exact))).max(),
            np.abs(np.sort_complex(contact_side) - np.sort_complex(np.linalg.eigvals(m_contact_exact))).max(),
        )
        assert err <= sp.multipliers_accuracy < 1e-8


def test_branch_invariants(tri_branch, belt_diagram):
    branch, problem = tri_branch
    for br in [branch, *belt_diagram.branches]:
        assert br.check_stability_flags()
        lam = br.parameter
        for sp in br.special_points:
            lo, hi = sp.bracket
            assert lo <= sp.parameter <= hi
            assert hi - lo <= 1e-6
            turning = sp.kind in (SpecialPointKind.FOLD, SpecialPointKind.DISCONTINUOUS_FOLD)
            if sp.index >= 0 and sp.index + 1 < len(br) and not turning:  # folds turn back in lam
                a, b = lam[sp.index], lam[sp.index + 1]
                assert min(a, b) - 1e-9 <= sp.parameter <= max(a, b) + 1e-9
    # stored multipliers equal recomputed ones
    for point in branch.points[:: max(1, len(branch) // 12)]:
        ev = problem.evaluate(point.state, point.parameter, need_lam=False)
        mu = np.linalg.eigvals(ev.trajectory.monodromy)
        assert np.allclose(np.sort_complex(mu), np.sort_complex(point.multipliers), atol=1e-9)


def stick_slip_fold_reference():
    """Belt velocity where the slip arc leaving the stick band returns to it tangentially (switch model band edge)."""
    k, c, m, f_slip, f_stick, eta = (BELT[n] for n in ("k", "c", "m", "F_slip", "F_stick", "eta"))

    def max_velocity(v_dr):
        x_exit = (f_stick - c * v_dr) / k

        def rhs(t, y):
            return [y[1], (-k * y[0] - c * y[1] + f_slip) / m]

        def velocity_max(t, y):
            return (-k * y[0] - c * y[1] + f_slip) / m

        velocity_max.direction = -1
        sol = solve_ivp(rhs, [0, 30], [x_exit, v_dr], events=velocity_max, rtol=1e-12, atol=1e-14, method="DOP853")
        return sol.y_events[0][0][1]

    return brentq(lambda v: max_velocity(v) - (v - eta), 1.0, 1.2, xtol=1e-13)


def switch_model_fold_reference():
    """The fold of the switch model (eq. 17, eta = 1e-4), independently: the touching point (x_g, v_dr - eta)
    on the band's edge, the stick phase in closed form (v = v_dr - eta exp(-sqrt(k/m) t), x = x_g + v_dr t)
    up to k x + c v = F_stick, the slip arc by solve_ivp to its velocity maximum, which must be the
    touching point again: fsolve on (x_g, v_dr)."""
    k, c, m, f_slip, f_stick, eta = (BELT[n] for n in ("k", "c", "m", "F_slip", "F_stick", "eta"))
    w_s = np.sqrt(k / m)

    def rhs(t, y):
        return [y[1], (-k * y[0] - c * y[1] + f_slip) / m]

    def velocity_max(t, y):
        return (-k * y[0] - c * y[1] + f_slip) / m

    velocity_max.direction = -1

    def residual(z):
        x_g, v_dr = z
        stick_force = lambda t: k * (x_g + v_dr * t) + c * (v_dr - eta * np.exp(-w_s * t)) - f_stick  # noqa: E731
        t_e = brentq(stick_force, 0.0, 100.0, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        y_e = [x_g + v_dr * t_e, v_dr - eta * np.exp(-w_s * t_e)]
        sol = solve_ivp(rhs, [0, 30], y_e, events=velocity_max, rtol=1e-13, atol=1e-15, method="DOP853")
        x_m, v_m = sol.y_events[0][0]
        return [x_m - x_g, v_m - (v_dr - eta)]

    z = fsolve(residual, [0.89, stick_slip_fold_reference()], xtol=1e-13)
    assert np.abs(residual(z)).max() < 1e-12
    return z[1]


def test_stick_slip_fold_located_by_tangential_return(belt_diagram):
    """The paper's stick-slip fold is where the slip arc that leaves the stick band returns to it
    tangentially: located by that condition, not as the midpoint of two branch ends."""
    (fold,) = [sp for sp in belt_diagram.special_points if sp.kind is SpecialPointKind.DISCONTINUOUS_FOLD]
    assert "returns tangentially to surface 'band_lower'" in fold.note
    assert fold.accuracy < 1e-10
    # the reference integrates to rtol 1e-13 (errors ~1e-12 in the touching point)
    assert fold.parameter == pytest.approx(switch_model_fold_reference(), abs=1e-9)


def test_stick_slip_fold_and_unstable_branch(belt_diagram):
    stable, unstable, equilibrium = belt_diagram.branches
    folds = [sp for sp in belt_diagram.special_points if sp.kind is SpecialPointKind.DISCONTINUOUS_FOLD]
    assert folds, "the discontinuous fold joining the stable and unstable branches was not found"
    fold = folds[0]
    # the idealised reference starts the slip arc at v = v_dr; the switch model leaves the band at
    # v_dr - O(eta): the two agree to O(eta)
    assert fold.parameter == pytest.approx(stick_slip_fold_reference(), abs=2 * BELT["eta"])
    assert np.any(np.isinf(np.abs(fold.multipliers_plus)))
    # the stable branch: multipliers (1, ~0) away from the fold
    far = [p for p in stable.points if abs(p.parameter - fold.parameter) > 0.1]
    assert far
    for p in far:
        mu = np.sort(np.abs(p.multipliers))
        assert mu[1] == pytest.approx(1.0, abs=1e-6)
        assert mu[0] < 1e-3
        assert p.stable
    # the unstable branch: backward multipliers (1, 0), i.e. forward (1, inf)
    assert unstable.backward
    for p in unstable.points:
        finite = p.multipliers[np.isfinite(p.multipliers)]
        assert np.isinf(np.abs(p.multipliers)).sum() == 1
        assert finite[0] == pytest.approx(1.0, abs=1e-6)
        assert not p.stable
    assert unstable.parameter.min() < 0.3  # followed far from the fold
    # the equilibrium [F_slip/k, 0] (eq. 18 corrected), stable for c > 0
    for p in equilibrium.points:
        assert p.state == pytest.approx([BELT["F_slip"] / BELT["k"], 0.0], abs=1e-12)
        assert p.stable


def test_equilibrium_branch_eigenvalues():
    flow = Flow(block_on_belt())
    problem = EquilibriumProblem(flow, "slip_minus", continuation_parameter="c")
    branch = continue_branch(
        problem, [1.0, 0.0], 0.1, settings=ContinuationSettings(ds=0.05, ds_max=0.05, bounds=(-0.2, 0.2)), directions=(1, -1)
    )
    # eigenvalues of [[0, 1], [-k/m, -c/m]]: a Hopf point at c = 0
    hopf = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.HOPF]
    assert len(hopf) == 1
    assert hopf[0].parameter == pytest.approx(0.0, abs=1e-9)
    for p in branch.points:
        ref = np.linalg.eigvals(np.array([[0, 1], [-1.0, -p.parameter]]))
        assert np.allclose(np.sort_complex(p.multipliers), np.sort_complex(ref), atol=1e-12)


def test_step_by_step_iteration_and_bounds(tri_flow):
    problem = ShootingProblem(tri_flow, {"omega": 0.6}, continuation_parameter="omega")
    cont = Continuation(problem, ContinuationSettings(ds=0.02, ds_max=0.02, bounds=(0.5, 0.7)))
    x0 = linear_response_state(dict(TRI) | {"omega": 0.6})
    params = [pt.parameter for pt in cont.run(x0, 0.6, direction=1)]
    assert params[0] == pytest.approx(0.6)
    assert np.all(np.diff(params) > 0)
    assert params[-1] == pytest.approx(0.7, abs=1e-12)
    assert cont.branch.stop_reason.name == "PARAMETER_BOUND"


def test_bad_continuation_input(tri_flow):
    from saltation.errors import SaltationError

    with pytest.raises(SaltationError, match="continuation parameter"):
        Continuation(ShootingProblem(tri_flow, {"omega": 0.6}))
    with pytest.raises(ValueError, match="ds_min"):
        ContinuationSettings(ds=1e-9)
    problem = ShootingProblem(tri_flow, {"omega": 0.6}, continuation_parameter="omega")
    with pytest.raises(SaltationError, match="outside the bounds"):
        list(Continuation(problem, ContinuationSettings(bounds=(0.8, 1.0))).run(np.zeros(2), 0.6))


def test_neimark_sacker_of_the_linear_response(tri_flow):
    """Without contact the multipliers are eig(expm(A T)), |mu| = exp(-c T / 2m): a complex pair leaves
    the unit circle exactly at c = 0 (a Neimark-Sacker point of the forced linear oscillator)."""
    w, f0 = 0.7, 0.01  # amplitude ~0.02, far from the supports
    problem = ShootingProblem(tri_flow, {"omega": w, "f0": f0, "c": 0.05}, continuation_parameter="c")
    x0 = linear_response_state(dict(TRI) | {"omega": w, "f0": f0, "c": 0.05})
    settings = ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(-0.05, 0.05))
    branch = continue_branch(problem, x0, 0.05, settings=settings, directions=(-1,))
    ns = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.NEIMARK_SACKER]
    assert len(ns) == 1
    assert ns[0].parameter == pytest.approx(0.0, abs=1e-9)
    assert np.allclose(np.abs(ns[0].multipliers), 1.0, atol=1e-8)
    for p in branch.points:
        A = np.array([[0.0, 1.0], [-K / M, -p.parameter / M]])
        mu = np.linalg.eigvals(expm(A * 2 * np.pi / w))
        assert np.allclose(np.sort_complex(p.multipliers), np.sort_complex(mu), atol=1e-8)
        assert p.stable == (p.parameter > 0)


# -- a harder, impacting regime: period doubling and a closed branch ---------------------------
#: stiff, lightly damped supports and strong forcing: the response curve from w = 0.5 leaves the
#: symmetric branch at a grazing point onto a loop of one-sided contact orbits (and their mirror
#: images), with a smooth period doubling on each half
IMPACTING = {"k_f": 25.0, "c": 0.01, "f0": 0.6, "c_f": 0.5}
LOOP_SETTINGS = ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(0.5, 3.0), max_points=3000)


@pytest.fixture(scope="module")
def impacting_branch(tri_flow):
    problem = ShootingProblem(tri_flow, IMPACTING | {"omega": 0.5}, continuation_parameter="omega")
    x0 = linear_response_state(dict(TRI) | IMPACTING | {"omega": 0.5})
    return continue_branch(problem, x0, 0.5, settings=LOOP_SETTINGS, directions=(1,))


def test_period_doubling_located_where_a_multiplier_is_minus_one(tri_flow, impacting_branch):
    """Reference: the monodromy by central differences of the period map (no saltation matrices)."""
    from conftest import TIGHT, central_difference_jacobian

    pds = [sp for sp in impacting_branch.special_points if sp.kind is SpecialPointKind.PERIOD_DOUBLING]
    assert len(pds) == 2  # one on each half of the loop: mirror images, at the same frequency
    assert pds[0].parameter == pytest.approx(pds[1].parameter, abs=1e-9)
    for sp in pds:
        p = tri_flow.parameters(IMPACTING | {"omega": sp.parameter})
        T = 2 * np.pi / sp.parameter
        fd = central_difference_jacobian(lambda x: tri_flow.run(x, 0.0, T, p, tolerances=TIGHT).x1, sp.state, 1e-6)
        mu = np.linalg.eigvals(fd)
        assert np.min(np.abs(mu + 1.0)) < 1e-6
        # stability changes across it, by a real multiplier through -1
        before, after = impacting_branch.points[sp.index], impacting_branch.points[sp.index + 1]
        assert before.stable != after.stable
        unstable = after if before.stable else before
        worst = unstable.multipliers[np.argmax(np.abs(unstable.multipliers))]
        assert abs(worst.imag) < 1e-12 and worst.real < -1.0


def test_branch_stops_when_it_comes_round_a_loop(impacting_branch):
    """The run meets its first special point of the loop again: it stops instead of circling
    until max_points, and records each special point once."""
    assert impacting_branch.stop_reason.name == "CLOSED_LOOP"
    assert len(impacting_branch.points) < LOOP_SETTINGS.max_points // 10
    sps = impacting_branch.special_points
    keys = [(sp.kind, round(sp.parameter, 7), tuple(np.round(sp.state, 6))) for sp in sps]
    assert len(keys) == len(set(keys))
    # the loop's turning point is where it meets the symmetric orbits (with both contacts): a symmetry
    # breaking seen from its side branch (tests/orbits/test_symmetry.py), not a fold
    assert {sp.kind for sp in sps} >= {SpecialPointKind.PERIOD_DOUBLING, SpecialPointKind.SYMMETRY_BREAKING}


def test_branch_stops_when_it_passes_its_start_again(tri_flow, impacting_branch):
    """Started on the loop, the run ends one step past its first point."""
    start = next(pt for pt in impacting_branch.points if 0.80 < pt.parameter < 0.82 and len(pt.event_labels) == 2)
    problem = ShootingProblem(tri_flow, IMPACTING | {"omega": start.parameter}, continuation_parameter="omega")
    branch = continue_branch(problem, start.state, start.parameter, settings=LOOP_SETTINGS, directions=(1,))
    assert branch.stop_reason.name == "CLOSED_LOOP"
    assert 20 < len(branch.points) < LOOP_SETTINGS.max_points // 10
    last = branch.points[-1]
    gap = np.hypot(last.parameter - start.parameter, np.linalg.norm(last.state - start.state))
    assert gap <= 1.5 * LOOP_SETTINGS.ds_max


def test_stick_slip_fold_stable_side_limit(belt_diagram, belt_flow):
    """Towards the tangential return, the stable cycle's second multiplier grows like d^(-1/2) (the entry
    into the stick band turns tangent: its saltation matrix is O(1/sqrt(d))), so its limit at the fold is
    unbounded. Checked on orbits at d = 1e-5 and 1e-4 with the period map's Jacobian by central
    differences (no saltation matrices)."""
    from saltation.orbits.shooting import find_periodic_orbit

    (fold,) = [sp for sp in belt_diagram.special_points if sp.kind is SpecialPointKind.DISCONTINUOUS_FOLD]
    assert fold.limits is Limits.EXTRAPOLATED and fold.status is SpecialPointStatus.LOCATED
    (exponent,) = fold.growth_exponents  # the one that grows: |mu| ~ d^a, a = -1/2
    assert exponent == pytest.approx(-0.5, abs=0.05)
    assert np.isinf(np.abs(fold.multipliers_minus)).sum() == 1
    stable = belt_diagram.branches[0]
    near = stable.points[int(np.argmax(stable.parameter))]
    mags = []
    for d in (1e-4, 1e-5):
        v = fold.parameter - d
        orbit = find_periodic_orbit(belt_flow, near.state, parameters={"v_dr": v}, period=near.period)
        p = belt_flow.parameters({"v_dr": v})
        h = 1e-8
        J = np.column_stack([
            (belt_flow.run(orbit.state0 + h * e, 0.0, orbit.period, p).x1
             - belt_flow.run(orbit.state0 - h * e, 0.0, orbit.period, p).x1) / (2 * h)
            for e in np.eye(2)
        ])
        mu = np.linalg.eigvals(J)
        mags.append(abs(mu[np.argmax(np.abs(mu - 1.0))]))
        np.testing.assert_allclose(np.sort(np.abs(orbit.multipliers)), np.sort(np.abs(mu)), rtol=0, atol=1e-5)
    # d^(-1/2): a tenfold smaller distance, a sqrt(10) larger multiplier (to 10 %: the O(1) term)
    assert mags[1] / mags[0] == pytest.approx(np.sqrt(10.0), rel=0.1)


def test_continue_orbit_is_the_explicit_path(trilinear_flow):
    """continue_orbit(orbit, name, bounds=...) follows the same branch as a ShootingProblem with
    continue_branch from the same start (the orbit keeps its flow, parameters and section)."""
    from dataclasses import replace

    from saltation import ContinuationSettings, continue_orbit, find_periodic_orbit
    from saltation.special_points.continuation import continue_branch
    from saltation.apps.paper import linear_response_state
    from saltation.models.trilinear import DEFAULTS

    x0 = linear_response_state(dict(DEFAULTS, omega=0.6))
    orbit = find_periodic_orbit(trilinear_flow, x0, parameters={"omega": 0.6})
    settings = ContinuationSettings(ds=0.02, ds_max=0.05)
    branch = continue_orbit(orbit, "omega", bounds=(0.6, 1.0), directions=(1,), settings=settings)
    problem = ShootingProblem(trilinear_flow, {"omega": 0.6}, continuation_parameter="omega")
    reference = continue_branch(problem, orbit.state0, 0.6, settings=replace(settings, bounds=(0.6, 1.0)),
                                directions=(1,))
    np.testing.assert_array_equal(branch.parameter, reference.parameter)
    assert [sp.kind for sp in branch.special_points] == [sp.kind for sp in reference.special_points]
    assert branch.special_points  # the corner at w_A lies in (0.6, 1.0)
    with pytest.raises(TypeError):
        ContinuationSettings(0.02)  # keyword-only: a positional value is an error, not a silent ds


def test_everyday_names_are_exported():
    import saltation

    for name in ("PiecewiseSystem", "Flow", "find_periodic_orbit", "continue_orbit", "ShootingProblem",
                 "continue_branch", "ContinuationSettings", "Branch", "SpecialPoint", "SpecialPointKind", "sweep",
                 "period_map"):
        assert name in saltation.__all__ and hasattr(saltation, name)


def test_the_package_continuation_locates_what_continue_branch_does(tri_flow, tri_branch):
    """``saltation.Continuation`` (the user guide's step-by-step form) has the special-point detector: run to the end,
    its branch holds the same special points as ``continue_branch``'s (the closed-form corners w_A, w_B and the fold),
    at the same parameters to their stated accuracy."""
    import saltation

    branch, problem = tri_branch
    cont = saltation.Continuation(problem, ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.6, 1.6)))
    points = list(cont.run(linear_response_state(dict(TRI) | {"omega": 0.6}), 0.6, direction=1))
    assert points and cont.branch.special_points
    ours = [(sp.kind, sp.parameter, sp.accuracy) for sp in cont.branch.special_points]
    theirs = [(sp.kind, sp.parameter, sp.accuracy) for sp in branch.special_points]
    assert [k for k, _, _ in ours] == [k for k, _, _ in theirs]
    for (_, a, da), (_, b, db) in zip(ours, theirs):
        assert abs(a - b) <= da + db + 1e-12
