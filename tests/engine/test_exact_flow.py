"""Exact flows of affine modes: detection, and agreement with the general integrator.

Every mode of both paper models is affine, so by default their integration
steps with the exact flow (saltation.engine.affine).  References here: the DOP853 path
of the same kernel at tight tolerances (``exact_affine=False``), closed-form
solutions of linear oscillators, and central differences of the flow.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
from hypothesis import example, given, settings
from hypothesis import strategies as st
import sympy as sp

from saltation.engine._contract import AFFINE_PARTS, AFFINE_PARTS_DP
from saltation import Tolerances
from saltation.engine.affine import affine_form
from saltation.model.system import TIME
from saltation.models import block_on_belt, trilinear

from conftest import TIGHT, central_difference_jacobian

GENERAL_TIGHT = Tolerances(rtol=1e-13, atol=1e-15, exact_affine=False)

x, v, k, c, w, phi, f0 = sp.symbols("x v k c w phi f0", real=True)
STATES = [x, v]


def _form(field):
    return affine_form(sp.Matrix(field), STATES, TIME)


# ---------------------------------------------------------------------------- detection
def test_forced_oscillator_is_affine():
    form = _form([v, -k * x - c * v + 3 + f0 * sp.cos(w * TIME + phi)])
    assert form is not None
    assert form.A == sp.Matrix([[0, 1], [-k, -c]])
    assert form.B == sp.Matrix([[0, 0, 0], [3, f0, 0]])
    assert (form.omega, form.phase) == (w, phi)


def test_sine_forcing_goes_to_the_third_column():
    form = _form([v, -x + 2 * sp.sin(w * TIME)])
    assert form.B == sp.Matrix([[0, 0, 0], [0, 0, 2]])


def test_autonomous_affine_field_has_no_frequency():
    form = _form([v - 1, -x])
    assert form is not None and form.omega == 0 and form.B == sp.Matrix([[-1, 0, 0], [0, 0, 0]])


@pytest.mark.parametrize(
    "field",
    [
        [v, -x**3],  # nonlinear (Duffing)
        [v, -x * sp.cos(TIME)],  # parametric excitation
        [v, -x + sp.cos(TIME) + sp.cos(2 * TIME)],  # two frequencies
        [v, -x + TIME],  # non-harmonic time dependence
        [v, -x + sp.exp(-TIME)],
        [v, -x + sp.cos(TIME**2)],  # phase not linear in t
        [v, -x + sp.cos(TIME) ** 2],  # a harmonic of the harmonic
    ],
    ids=["duffing", "parametric", "two-frequencies", "ramp", "decay", "chirp", "squared"],
)
def test_fields_without_an_exact_flow(field):
    assert _form(field) is None


def test_paper_models_are_piecewise_affine():
    for system in (trilinear(), block_on_belt()):
        assert all(affine_form(f, system.x, TIME) is not None for f in system.fields), system.name


# ---------------------------------------------------------------------------- closed forms
def test_free_flight_against_the_matrix_exponential(trilinear_flow):
    """No contact, no forcing: x(t) = expm(A t) x0 and Phi = expm(A t), at default tolerances."""
    p = trilinear_flow.parameters({"f0": 0.0})
    A = np.array([[0.0, 1.0], [-1.0, -0.05]])
    x0 = np.array([0.5, -0.2])
    traj = trilinear_flow.run(x0, 0.0, 7.3, p, variational=True)
    E = scipy.linalg.expm(A * 7.3)
    # exact up to the rounding of about ten steps
    np.testing.assert_allclose(traj.x1, E @ x0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(traj.monodromy, E, rtol=0, atol=1e-13)


def test_dense_output_of_exact_steps(trilinear_flow):
    """The dense output between steps matches the closed form to the tolerance."""
    p = trilinear_flow.parameters({"f0": 0.0})
    A = np.array([[0.0, 1.0], [-1.0, -0.05]])
    x0 = np.array([0.5, -0.2])
    traj = trilinear_flow.run(x0, 0.0, 7.3, p, dense=True)
    times = np.linspace(0.0, 7.3, 301)
    exact = np.array([scipy.linalg.expm(A * t) @ x0 for t in times])
    assert np.max(np.abs(traj.at(times) - exact)) < 1e-10
    assert traj.x_max[0] == pytest.approx(np.max(exact[:, 0]), abs=1e-10)


def _exact_step_workspace(flow, p, pidx):
    """The affine parts of every mode (and their derivatives by parameter ``pidx``), as the kernel sets them up."""
    n, n_modes, n_par = flow.system.n, len(flow.system.mode_names), len(p)
    A, B, W = np.zeros((n_modes, n, n)), np.zeros((n_modes, n, 3)), np.zeros((n_modes, 4))
    Ap, Bp = np.zeros((n_modes, n, n)), np.zeros((n_modes, n, 3))
    Ap_all, Bp_all, wp_all = np.zeros((n_par, n, n)), np.zeros((n_par, n, 3)), np.zeros((n_par, 2))
    for m in range(n_modes):
        flow._model[AFFINE_PARTS](m, p, A[m], B[m], W[m, :2])
        flow._model[AFFINE_PARTS_DP](m, p, Ap_all, Bp_all, wp_all)
        Ap[m], Bp[m], W[m, 2:] = Ap_all[pidx], Bp_all[pidx], wp_all[pidx]
    return A, B, W, Ap, Bp


@pytest.mark.parametrize("theta", [1e-4, 0.37, 1.0])
def test_a_fraction_of_an_exact_step_is_the_exact_step_to_that_point(trilinear_flow, theta):
    """A rejected step, the step to an event and the steps of its refinement re-use the series of the
    step attempted first, summed at a fraction of it: [x, Phi, psi], the field at the end, the dense
    output and its error bound must be those of a new series for the shorter step."""
    k = trilinear_flow._engine
    system = trilinear_flow.system
    n, N, rows = system.n, 2 * system.n + system.n**2, k.MAX_TAYLOR + 4
    p = trilinear_flow.parameters({"omega": 1.0})
    pidx = system.parameter_index("omega")  # the forcing's terms of the sensitivity count too
    aff = _exact_step_workspace(trilinear_flow, p, pidx)
    mode = system.mode_index("contact_1")
    t, h = 0.7, 0.3
    y = np.concatenate([[1.1, 0.4], [1.2, -0.3, 0.5, 0.9], [0.2, -0.7]])  # x, Phi (row-major), psi

    def step(length, fraction_of=None):
        K, ynew, F = np.zeros((16, N)), np.zeros(N), np.zeros((7, n))
        TW, TP, TC = np.zeros((7, n)), np.zeros((3, n, n)), np.zeros((rows, N))
        err = k._exact_step(mode, t, y, fraction_of or length, True, pidx, 1e-10, 1e-12, *aff, K, ynew, TW, TP, TC)
        if fraction_of is not None:
            err = k._exact_fraction(mode, t, y, fraction_of, length / fraction_of, True, 1e-10, 1e-12, *aff[:3],
                                    K, ynew, TW, TC)
        k._exact_dense(y, ynew, TC, F)
        dense = np.zeros((11, n))
        for i, s in enumerate(np.linspace(0.0, 1.0, 11)):
            k._dense_eval(F, y, s, dense[i])
        return err, ynew, K[12, :n].copy(), dense

    err_f, y_f, f_f, dense_f = step(theta * h, fraction_of=h)
    err_s, y_s, f_s, dense_s = step(theta * h)
    np.testing.assert_allclose(y_f, y_s, rtol=0, atol=1e-14)
    np.testing.assert_allclose(f_f, f_s, rtol=0, atol=1e-14)
    np.testing.assert_allclose(dense_f, dense_s, rtol=0, atol=1e-14)
    # the same bound, up to the tail terms beyond the shorter step's own series (relative size ~ theta h |A|)
    assert err_f == pytest.approx(err_s, rel=1e-3, abs=1e-300)
    # and the step itself is the flow: against DOP853 at tight tolerances from the same state
    ref = trilinear_flow.run(y[:n], t, t + theta * h, p, mode0="contact_1", variational=True, sensitivity=pidx,
                             phi0=y[n : n + n * n].reshape(n, n), tolerances=GENERAL_TIGHT)
    np.testing.assert_allclose(y_f[:n], ref.x1, rtol=0, atol=1e-13)
    np.testing.assert_allclose(y_f[n : n + n * n].reshape(n, n), ref.monodromy, rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------- against the general path
@pytest.mark.parametrize("backward", [False, True], ids=["forward", "backward"])
def test_contact_orbit_matches_the_general_integrator(trilinear_flow, contact_orbit, backward):
    """Three periods of the contact orbit (twelve events), monodromy and d/d omega:
    exact path at default tolerances vs DOP853 at 1e-13."""
    p = trilinear_flow.parameters({"omega": 1.0})
    omega = trilinear_flow.system.parameter_index("omega")
    t1 = -3 * 2 * np.pi if backward else 3 * 2 * np.pi
    x0 = contact_orbit.state0
    fast = trilinear_flow.run(x0, 0.0, t1, p, variational=True, sensitivity=omega)
    ref = trilinear_flow.run(x0, 0.0, t1, p, variational=True, sensitivity=omega, tolerances=GENERAL_TIGHT)
    assert len(fast.events) == 12
    assert fast.event_sequence == ref.event_sequence
    np.testing.assert_allclose([e.t for e in fast.events], [e.t for e in ref.events], rtol=0, atol=1e-10)
    np.testing.assert_allclose(fast.x1, ref.x1, rtol=0, atol=1e-10)
    np.testing.assert_allclose(fast.monodromy, ref.monodromy, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(fast.parameter_sensitivity, ref.parameter_sensitivity, rtol=1e-10, atol=1e-10)
    assert fast.n_steps < ref.n_steps


@pytest.mark.parametrize("name", ["x_c", "k_f", "c", "m", "f0"])
def test_parameter_sensitivity_against_central_differences(trilinear_flow, contact_orbit, name):
    """d x(T) / d p through four contacts: the exact flow's sensitivity equations vs finite differences of the flow."""
    p = trilinear_flow.parameters({"omega": 1.0})
    j = trilinear_flow.system.parameter_index(name)
    x0 = contact_orbit.state0
    traj = trilinear_flow.run(x0, 0.0, 2 * np.pi, p, variational=True, sensitivity=j)
    assert len(traj.events) == 4

    def end_state(q):
        pp = p.copy()
        pp[j] = q[0]
        return trilinear_flow.run(x0, 0.0, 2 * np.pi, pp, tolerances=TIGHT).x1

    fd = central_difference_jacobian(end_state, [p[j]], 1e-6)[:, 0]
    np.testing.assert_allclose(traj.parameter_sensitivity, fd, rtol=1e-6, atol=1e-7)


@pytest.mark.parametrize("backward", [False, True], ids=["forward", "backward"])
def test_stick_slip_matches_the_general_integrator(belt_flow, backward):
    """Stick, slip and (backward) sliding along the stick band: exact steps where affine, DOP853 while sliding."""
    p = belt_flow.parameters()
    x0, t1 = ([0.0, 1.0], 20.0) if not backward else ([1.0, -0.95], -12.0)
    fast = belt_flow.run(x0, 0.0, t1, p, variational=True)
    ref = belt_flow.run(x0, 0.0, t1, p, variational=True, tolerances=GENERAL_TIGHT)
    assert fast.event_sequence == ref.event_sequence
    assert len(fast.events) >= 2
    np.testing.assert_allclose([e.t for e in fast.events], [e.t for e in ref.events], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.x1, ref.x1, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.monodromy, ref.monodromy, rtol=1e-8, atol=1e-8)


@pytest.mark.parametrize("exact", [True, False], ids=["exact", "dop853"])
def test_extrema_agree_forward_and_backward(trilinear_flow, contact_orbit, exact):
    """The extremes of every state over a trajectory are those of the same trajectory run backward."""
    p = trilinear_flow.parameters({"omega": 1.0})
    tol = Tolerances(exact_affine=exact)
    x0 = contact_orbit.state0 + np.array([0.05, -0.02])  # a transient through contacts
    fwd = trilinear_flow.run(x0, 0.0, 2 * np.pi, p, tolerances=tol)
    bwd = trilinear_flow.run(fwd.x1, 2 * np.pi, 0.0, p, mode0=fwd.mode1, tolerances=tol)
    assert len(fwd.events) == len(bwd.events) == 4
    np.testing.assert_allclose(bwd.x1, x0, atol=1e-8)
    np.testing.assert_allclose(bwd.x_max, fwd.x_max, rtol=0, atol=1e-8)
    np.testing.assert_allclose(bwd.x_min, fwd.x_min, rtol=0, atol=1e-8)


@pytest.mark.parametrize("name", ["phi", "omega", "q"])
def test_phase_shifted_forcing_with_sliding(filippov_flow, name):
    """Forcing q sin(omega t + phi) in an affine mode, and sliding in between: the exact path's
    state, monodromy and sensitivities to the forcing's phase, frequency and amplitude vs DOP853."""
    from saltation.engine.affine import affine_form as form_of

    system = filippov_flow.system
    below = form_of(system.fields[system.mode_index("below")], system.x, TIME)
    assert below is not None and below.phase == sp.Symbol("phi", real=True)
    p = filippov_flow.parameters({"q": 0.3, "omega": 1.3, "phi": 0.4})
    j = system.parameter_index(name)
    x0 = [-1.0, -0.8]
    fast = filippov_flow.run(x0, 0.0, 9.0, p, variational=True, sensitivity=j)
    ref = filippov_flow.run(x0, 0.0, 9.0, p, variational=True, sensitivity=j, tolerances=GENERAL_TIGHT)
    kinds = [e.kind.name for e in fast.events]
    assert "SLIDING_START" in kinds and "SLIDING_END" in kinds
    assert fast.event_sequence == ref.event_sequence
    np.testing.assert_allclose([e.t for e in fast.events], [e.t for e in ref.events], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.x1, ref.x1, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.monodromy, ref.monodromy, rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(fast.parameter_sensitivity, ref.parameter_sensitivity, rtol=1e-8, atol=1e-8)


# ---------------------------------------------------------------------------- the step's bound
def _relaxation_system():
    """``x' = -a x + c``: affine, its generator's norm ``max(a, |c|)`` (0 for ``a = c = 0``, a field that is zero)."""
    from saltation import Mode, PiecewiseSystem

    return PiecewiseSystem(name="test_relaxation", states=["x"], parameters={"a": 0.0, "c": 0.0},
                           modes=[Mode("relax", ["-a*x + c"])], surfaces={}, transitions=[])


@pytest.fixture(scope="module")
def relaxation_flow():
    from saltation import Flow

    return Flow(_relaxation_system())


@settings(max_examples=150, deadline=None)
@example(a=0.0, c=0.0, x0=0.3, span=2.0)  # a zero field: no bound on the step, and nothing moves
@example(a=0.0, c=1.5, x0=-0.2, span=-3.0)
@example(a=40.0, c=0.5, x0=1.0, span=1.0)  # ten times the series' bound over the span
@given(a=st.one_of(st.just(0.0), st.floats(1e-3, 40.0)), c=st.floats(-3.0, 3.0), x0=st.floats(-2.0, 2.0),
       span=st.one_of(st.floats(-2.0, -1e-3), st.floats(1e-3, 2.0)))
def test_exact_steps_of_any_norm_against_the_closed_form(relaxation_flow, a, c, x0, span):
    """State and fundamental solution of ``x' = -a x + c`` against ``x = c/a + (x0 - c/a) e^(-a t)``
    (``x0 + c t`` for ``a = 0``), forward and backward, for generator norms from 0 (a zero field, whose
    steps have no bound) to ten times what one exact step may take.  Each step is exact to the
    rounding of its series, at most ``e^4`` rounding units of the state's scale (``EXACT_STEP_BOUND``),
    so the bound is that per step taken, with a factor 4 for the final sums."""
    p = relaxation_flow.parameters({"a": a, "c": c})
    r = relaxation_flow.run([x0], 0.0, span, p, variational=True)
    if a == 0.0:
        x_ref, phi_ref = x0 + c * span, 1.0
    else:
        phi_ref = np.exp(-a * span)
        x_ref = c / a + (x0 - c / a) * phi_ref
    scale = max(1.0, abs(x0), abs(x_ref), abs(c / a) if a else abs(c * span))
    bound = 4.0 * (r.n_steps + 1) * np.exp(4.0) * np.finfo(float).eps
    assert abs(r.x1[0] - x_ref) <= bound * scale
    assert abs(r.monodromy[0, 0] - phi_ref) <= bound * max(1.0, phi_ref)


# ---------------------------------------------------------------------------- independence of the tolerances
# the shipped models whose every mode is affine and whose orbits do not slide (a sliding motion is DOP853's)
_AFFINE_SHIPPED = ("buck_converter", "impact_oscillator", "relay_feedback", "symmetric_impact_oscillator",
                   "trilinear", "two_mass_stops")


@pytest.fixture(scope="module")
def shipped_orbits():
    """Each model's orbit at its default parameters (a transient, then shooting at tight tolerances)."""
    from saltation import Flow
    from saltation.models import SHIPPED
    from saltation.orbits.shooting import find_periodic_orbit

    orbits = {}
    for name in _AFFINE_SHIPPED:
        flow = Flow(SHIPPED[name].factory(), TIGHT)
        orbits[name] = (flow, find_periodic_orbit(flow))
    return orbits


@given(name=st.sampled_from(_AFFINE_SHIPPED), log_rtol=st.floats(-12.0, np.log10(0.5)),
       log_atol=st.floats(-4.0, 0.0), offset=st.floats(-0.05, 0.05))
@example(name="two_mass_stops", log_rtol=np.log10(0.5), log_atol=0.0, offset=0.0)
def test_the_exact_flow_does_not_depend_on_the_tolerances(shipped_orbits, name, log_rtol, log_atol, offset):
    """The exact flow's series are summed to rounding, so the tolerances govern only its dense output
    (README, *Integration settings*): a period from near the orbit, with its monodromy, is the tight
    tolerances' to rounding at any ``rtol`` up to 0.5, with the same events (DOP853 in its place fails this
    by 0.2 at ``rtol`` 0.5).  Bound: a rounding unit per product of an n x n matrix, n terms each, over
    every step and event of the longer shot, twice (both shots carry it), relative to ``1 + |x|`` and
    ``1 + |Phi|``."""
    from saltation import Flow

    flow, orbit = shipped_orbits[name]
    rtol = 10.0**log_rtol
    loose = Flow(flow.system, Tolerances(rtol=rtol, atol=rtol * 10.0**log_atol))
    p = flow.parameters({})
    x0 = orbit.state0 + offset
    t1 = orbit.t0 + orbit.period
    ref = flow.run(x0, orbit.t0, t1, p, variational=True)
    got = loose.run(x0, orbit.t0, t1, p, variational=True)
    assert [(e.surface, e.mode_to) for e in got.events] == [(e.surface, e.mode_to) for e in ref.events]
    n = flow.system.n
    rounding = 2 * n * (max(ref.n_steps, got.n_steps) + len(ref.events) + 1) * np.finfo(float).eps
    assert np.abs(got.x1 - ref.x1).max() <= rounding * (1 + np.abs(ref.x1).max())
    assert np.abs(got.monodromy - ref.monodromy).max() <= rounding * (1 + np.abs(ref.monodromy).max())
