"""Floquet multipliers and amplitudes against closed forms and the paper's claims.

* Trilinear orbits without contact are those of the linear oscillator
  ``m x'' + c x' + k x = f0 sin(w t)``: multipliers ``eig(expm(A T))``, amplitude
  ``f0 / sqrt((k - m w^2)^2 + (c w)^2)``.
* Stable stick-slip cycle: multipliers (1, 0) up to O(eta) (eq. 19 makes the
  monodromy singular as eta -> 0).
* Unstable cycle, found in backward time: backward multipliers (1, 0), forward
  (1, inf); it leaves the border of the stick band where the slip field is tangent
  to it, at x = (F_slip - c v_dr)/k up to O(eta) (eq. 18 as printed, see NOTES.md).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import EventKind
from saltation.orbits.shooting import EquilibriumProblem, find_periodic_orbit

from conftest import stick_slip_orbit, unstable_orbit


# ----------------------------------------------------------------- trilinear without contact
@pytest.fixture(scope="module", params=[0.7, 1.4], ids=lambda w: f"omega={w}")
def linear_orbit(request, trilinear_flow):
    omega = request.param
    return omega, find_periodic_orbit(trilinear_flow, [0.0, 0.0], parameters={"omega": omega})


def _linear_constants(orb):
    pv = dict(zip(orb.trajectory.system.parameter_names, orb.parameters))
    return pv["m"], pv["c"], pv["k"], pv["f0"], pv["x_c"]


def test_linear_orbit_has_no_contact(linear_orbit):
    omega, orb = linear_orbit
    *_, x_c = _linear_constants(orb)
    assert orb.trajectory.events == []
    assert orb.amplitude < x_c
    assert orb.period == pytest.approx(2 * np.pi / omega, rel=1e-15)


def test_linear_orbit_multipliers(linear_orbit):
    omega, orb = linear_orbit
    m, c, k, _, _ = _linear_constants(orb)
    A = np.array([[0.0, 1.0], [-k / m, -c / m]])
    expected = np.linalg.eigvals(expm(A * 2 * np.pi / omega))
    key = lambda z: (round(z.imag, 6), z.real)  # noqa: E731  (complex pair: order by imaginary part)
    got = sorted(orb.multipliers, key=key)
    want = sorted(expected.astype(complex), key=key)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-8)
    assert abs(got[0]) == pytest.approx(np.exp(-c / (2 * m) * 2 * np.pi / omega), rel=1e-8)
    assert orb.stable


def test_linear_orbit_monodromy_accuracy(linear_orbit):
    """The monodromy along the orbit equals expm(A T) to 10 x the default rtol (1e-10).

    scipy's DOP853 at the same tolerances, with the variational equations in the
    error norm, is within 6e-11 of expm(A T) at omega = 0.7.
    """
    omega, orb = linear_orbit
    m, c, k, _, _ = _linear_constants(orb)
    A = np.array([[0.0, 1.0], [-k / m, -c / m]])
    np.testing.assert_allclose(orb.monodromy, expm(A * 2 * np.pi / omega), rtol=0, atol=1e-9)


def test_linear_orbit_amplitude_and_phase(linear_orbit):
    """x(t) = A sin(w t - phi), A = f0 / sqrt((k - m w^2)^2 + (c w)^2), tan phi = c w / (k - m w^2)."""
    omega, orb = linear_orbit
    m, c, k, f0, _ = _linear_constants(orb)
    amplitude = f0 / np.hypot(k - m * omega**2, c * omega)
    phi = np.arctan2(c * omega, k - m * omega**2)
    assert orb.amplitude == pytest.approx(amplitude, rel=1e-8)
    assert orb.half_peak_to_peak == pytest.approx(amplitude, rel=1e-8)
    np.testing.assert_allclose(
        orb.state0, [-amplitude * np.sin(phi), amplitude * omega * np.cos(phi)], rtol=0, atol=1e-9 * amplitude
    )


# ----------------------------------------------------------------- stable stick-slip cycle
ETA = 1e-4  # Appendix B


def test_stable_cycle_multipliers(stable_cycle):
    orb = stable_cycle
    assert orb.parameters[orb.trajectory.system.parameter_index("eta")] == ETA
    big, small = orb.multipliers  # sorted by decreasing magnitude
    assert big == pytest.approx(1.0, abs=1e-8)  # trivial multiplier (autonomous)
    assert abs(small) < 10 * ETA
    assert abs(small) > 0.01 * ETA  # O(eta), not zero: the band has a width
    assert orb.stable
    assert orb.period == pytest.approx(6.494, abs=1e-3)


def test_stable_cycle_multiplier_scales_with_eta(belt_flow, stable_cycle):
    """Reducing eta tenfold (a parameter value: same compiled model) divides the second multiplier by ~10."""
    small = stick_slip_orbit(belt_flow, eta=ETA / 10)
    assert small.parameters[belt_flow.system.parameter_index("eta")] == ETA / 10
    assert small.multipliers[0] == pytest.approx(1.0, abs=1e-8)
    ratio = abs(stable_cycle.multipliers[1]) / abs(small.multipliers[1])
    assert ratio == pytest.approx(10.0, rel=1e-2)
    # the cycle itself moves by O(eta) only
    assert small.period == pytest.approx(stable_cycle.period, abs=10 * ETA)


# ----------------------------------------------------------------- unstable cycle, backward time
@pytest.fixture(scope="module", params=[1e-4, 1e-5], ids=lambda e: f"eta={e:g}")
def unstable(request, belt_flow, unstable_cycle):
    eta = request.param
    return eta, (unstable_cycle if eta == ETA else unstable_orbit(belt_flow, eta=eta))


def test_unstable_cycle_multipliers(unstable):
    eta, orb = unstable
    assert orb.backward
    back = sorted(orb.backward_multipliers, key=abs)
    assert abs(back[0]) < 1e-12  # the attraction sliding mode (backward time) forgets
    assert back[1] == pytest.approx(1.0, abs=1e-8)
    forward = orb.multipliers
    assert np.isinf(forward[0])  # infinitely unstable
    assert forward[1] == pytest.approx(1.0, abs=1e-8)
    assert not orb.stable


def test_unstable_cycle_leaves_the_band_where_the_slip_field_is_tangent(unstable):
    """Sliding along v = v_dr - eta ends where the slip field turns tangent: eq. (18)'s printed point."""
    eta, orb = unstable
    pv = dict(zip(orb.trajectory.system.parameter_names, orb.parameters))
    k, c, m, v_dr, F_slip = pv["k"], pv["c"], pv["m"], pv["v_dr"], pv["F_slip"]
    kinds = [e.kind for e in orb.trajectory.events]
    assert kinds == [EventKind.SLIDING_START, EventKind.SLIDING_END]
    start, end = orb.trajectory.events
    assert start.surface == end.surface == "band_lower"
    assert {start.mode_from, start.mode_to} == {"slip_minus", "stick"}
    assert end.mode_to == "slip_minus"
    x_touch, v_touch = end.x_minus
    assert x_touch == pytest.approx((F_slip - c * v_dr) / k, abs=10 * eta)  # eq. (18), first component
    assert x_touch == pytest.approx((F_slip - c * (v_dr - eta)) / k, abs=1e-9)  # eta-exact
    assert v_touch == pytest.approx(v_dr - eta, abs=1e-12)
    # tangency: the slip acceleration vanishes there
    assert abs(-k * x_touch - c * v_touch + F_slip) / m < 1e-9


def test_unstable_cycle_lies_between_equilibrium_and_stable_cycle(stable_cycle, unstable_cycle):
    assert unstable_cycle.amplitude < stable_cycle.amplitude
    assert unstable_cycle.period < stable_cycle.period


def test_equilibrium_is_not_eq18_as_printed(belt_flow):
    """NOTES.md: the equilibrium of eq. (15) is [F_slip/k, 0], stable for c > 0."""
    eq = EquilibriumProblem(belt_flow, "slip_minus").solve([0.5, 0.5])
    pv = dict(zip(belt_flow.system.parameter_names, eq.parameters))
    np.testing.assert_allclose(eq.state, [pv["F_slip"] / pv["k"], 0.0], atol=1e-12)
    m, c, k = pv["m"], pv["c"], pv["k"]
    np.testing.assert_allclose(
        sorted(eq.eigenvalues, key=lambda z: z.imag),
        sorted(np.roots([m, c, k]).astype(complex), key=lambda z: z.imag),
        atol=1e-12,
    )
    assert eq.stable


# ----------------------------------------------------------------- eigenvalues (LAPACK dgeev)
def test_eigenvalues_against_numpy_and_invariants():
    """floquet.eigenvalues calls dgeev directly: the same spectrum as numpy.linalg.eigvals, conjugate
    pairs and real eigenvalues kept exactly, and trace and determinant reproduced."""
    from saltation.orbits.floquet import eigenvalues

    rng = np.random.default_rng(7)
    for n in (1, 2, 3, 6):
        for _ in range(50):
            a = rng.normal(size=(n, n))
            mu = eigenvalues(a)
            ref = np.linalg.eigvals(a).astype(complex)
            np.testing.assert_allclose(np.sort_complex(mu), np.sort_complex(ref), rtol=0, atol=1e-12)
            assert np.sum(mu).real == pytest.approx(np.trace(a), abs=1e-12)
            assert np.prod(mu).real == pytest.approx(np.linalg.det(a), rel=1e-10, abs=1e-12)
            assert sorted(mu.imag.tolist()) == sorted((-mu.imag).tolist())  # exact conjugate pairs
    rotation = np.array([[0.0, -2.0], [2.0, 0.0]])
    np.testing.assert_allclose(np.sort_complex(eigenvalues(rotation)), [-2j, 2j], rtol=0, atol=1e-15)


def test_eigenvalues_of_a_non_finite_matrix_raise():
    from saltation.orbits.floquet import eigenvalues

    with pytest.raises(np.linalg.LinAlgError, match="infs or NaNs"):
        eigenvalues(np.array([[1.0, np.nan], [0.0, 1.0]]))


def _greedy_reference(prev, new):
    """Greedy nearest-neighbour matching, written plainly: each multiplier of ``prev`` in turn takes the
    nearest of the values left (the first of equally near ones)."""
    left = list(range(len(new)))
    out = []
    for m in prev:
        j = min(left, key=lambda jj: abs(new[jj] - m))
        out.append(new[j])
        left.remove(j)
    return np.array(out)


@settings(max_examples=60, deadline=None)
@given(st.integers(min_value=1, max_value=4), st.integers(min_value=0, max_value=2**32 - 1))
def test_set_valued_paths_follow_greedy_nearest_neighbours(n, seed):
    """The paths of the set-valued multipliers are the eigenvalues along the hull, each row matched to
    the row before by greedy nearest neighbours (the fast path for two multipliers included)."""
    from saltation.orbits.floquet import set_valued_multipliers, sort_multipliers

    rng = np.random.default_rng(seed)
    m_minus, m_plus = rng.normal(size=(2, n, n))
    sv = set_valued_multipliers(m_minus, m_plus, num=41)
    hull = (1.0 - sv.q)[:, None, None] * m_minus + sv.q[:, None, None] * m_plus
    eig = np.linalg.eigvals(hull).astype(complex)
    expected = [sort_multipliers(eig[0])]
    for row in eig[1:]:
        expected.append(_greedy_reference(expected[-1], row))
    np.testing.assert_array_equal(sv.paths, np.array(expected))
