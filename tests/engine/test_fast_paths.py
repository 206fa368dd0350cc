"""The plain-float and cached paths that every orbit and branch point takes, against the general code they
replace: the same numbers, and no state kept where it could go stale."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from saltation.branches.corrector import Corrector, Solution, canonical_events
from saltation.engine.flow import EventKind
from saltation.errors import ModelError
from saltation.models import block_on_belt, trilinear
from saltation.orbits.floquet import eigenvalues, is_stable
from saltation.orbits.records import (
    BranchPoint,
    Evaluation,
    event_ids,
    event_labels,
    orbit_events,
)
from saltation.special_points.detection import _flip_test, _ns_test, _plus_one_test

EPS = float(np.finfo(float).eps)
finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
multipliers = st.lists(st.complex_numbers(max_magnitude=1e3, allow_nan=False, allow_infinity=False), max_size=6)


# ------------------------------------------------------------------ event sequences from the event log
def _reference_ids(traj) -> tuple:
    names = traj.system.mode_names
    return tuple((int(e.kind), int(e.transition), names.index(e.mode_to)) for e in orbit_events(traj))


def _reference_labels(traj) -> tuple:
    sys_ = traj.system
    out = []
    for e in orbit_events(traj):
        if e.kind == EventKind.TRANSITION:
            out.append(sys_.transitions[e.transition].label)
        elif e.kind == EventKind.SLIDING_START:
            out.append(f"slide on {e.surface} ({e.mode_from}|{e.mode_to})")
        else:
            out.append(f"leave {e.surface} sliding -> {e.mode_to}")
    return tuple(out)


def test_event_ids_and_labels_match_the_switching_events(contact_orbit, belt_flow, filippov_flow):
    """Read from the kernel's integer log, as from the events themselves: impacts of the trilinear orbit,
    stick-slip of the block on the belt, a Filippov sliding motion, and a shot that starts where a sliding
    motion does and meets it again (its first event is then dropped: the motion is counted by its arrival
    at the end; the log is the Filippov shot's twice over)."""
    sliding = filippov_flow.run([-1.0, -0.8], 0.0, 9.0, filippov_flow.parameters({"q": 0.3, "omega": 1.3, "phi": 0.4}),
                                variational=True)
    assert [e.kind for e in sliding.events] == [EventKind.SLIDING_START, EventKind.SLIDING_END]
    twice = tuple(np.concatenate([a, a]) for a in sliding.event_log)
    seamed = dataclasses.replace(sliding, t0=float(sliding.event_log[0][0]), event_log=twice, sliding_at_end=True)
    assert len(orbit_events(seamed)) == 3
    shots = [contact_orbit.trajectory, belt_flow.run([0.0, 1.0], 0.0, 30.0, belt_flow.parameters(), variational=True),
             sliding, seamed, dataclasses.replace(seamed, sliding_at_end=False)]
    for traj in shots:
        assert event_ids(traj) == _reference_ids(traj)
        assert event_labels(traj) == _reference_labels(traj)


# ------------------------------------------------------------------ multipliers and test functions
@settings(max_examples=200, deadline=None)
@given(multipliers)
def test_test_functions_match_numpy(mu):
    """prod(mu + 1), prod(mu - 1) and prod_{i<j}(mu_i mu_j - 1) in plain complex numbers, as numpy gives
    them (same products in the same order: equal to a few rounding units of the product's terms)."""
    mu = np.array(mu, dtype=complex)
    scale = float(np.prod(np.abs(mu) + 1.0)) if mu.size else 1.0
    assert _flip_test(mu) == pytest.approx(float(np.real(np.prod(mu + 1.0))), rel=0, abs=8 * EPS * mu.size * scale)
    assert _plus_one_test(mu) == pytest.approx(float(np.real(np.prod(mu - 1.0))), rel=0,
                                               abs=8 * EPS * mu.size * scale)
    ns = _ns_test(mu)
    if mu.size < 2:
        assert np.isnan(ns)
    else:
        i, j = np.triu_indices(mu.size, 1)
        pair_scale = float(np.prod(np.abs(mu[i]) * np.abs(mu[j]) + 1.0))
        assert ns == pytest.approx(float(np.real(np.prod(mu[i] * mu[j] - 1.0))), rel=0,
                                   abs=16 * EPS * i.size * pair_scale)


def test_test_functions_skip_infinite_multipliers():
    mu = np.array([complex(np.inf, 0.0), 0.5 + 0.5j, 0.5 - 0.5j])
    assert _flip_test(mu) == pytest.approx(abs(1.5 + 0.5j) ** 2)
    assert _ns_test(mu) == pytest.approx(abs(0.5 + 0.5j) ** 2 - 1.0)  # the one finite pair's product minus 1


@settings(max_examples=200, deadline=None)
@given(st.lists(st.complex_numbers(max_magnitude=10, allow_nan=False, allow_infinity=False), max_size=5),
       st.sampled_from([0.0, 1e-6, 1e-3]))
def test_is_stable_matches_numpy(mu, tol):
    mu = np.array(mu, dtype=complex)
    assert is_stable(mu, autonomous=False, tol=tol) == bool(np.all(np.abs(mu) < 1.0 + tol))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("n", [2, 9])
def test_eigenvalues_refuse_a_matrix_that_is_not_finite(bad, n):
    """Checked in plain floats up to 64 entries, by numpy beyond: the same refusal either way."""
    a = np.eye(n)
    a[n - 1, 0] = bad
    with pytest.raises(np.linalg.LinAlgError, match="infs or NaNs"):
        eigenvalues(a)


# ------------------------------------------------------------------ the tangent of a branch
class _Problem:
    pass


@settings(max_examples=100, deadline=None)
@given(st.lists(finite, min_size=6, max_size=6), st.lists(finite, min_size=3, max_size=3))
@example(entries=[1.0, 5.0, 0.0, 0.5, 0.0, 1.0], previous=[1.0, 5.0, -4.2839675029879674e-78])  # t all but normal to it
def test_tangent_solves_the_bordered_system(entries, previous):
    """LAPACK's dgesv called directly: the unit tangent that numpy.linalg.solve gives, oriented along the previous
    one; a singular system keeps the previous direction."""
    jac_u = np.array(entries[:4]).reshape(2, 2)
    jac_lam = np.array(entries[4:6])
    previous = np.array(previous)
    if not np.linalg.norm(previous) > 1e-3:
        previous = np.array([0.0, 0.0, 1.0])
    sol = Solution(z=np.zeros(3), evaluation=Evaluation(residual=np.zeros(2), jac_u=jac_u, jac_lam=jac_lam,
                                                       trajectory=None), summary=None)
    t = Corrector(_Problem(), None).tangent(sol, previous)
    J = np.vstack([np.column_stack([jac_u, jac_lam]), previous])
    assert np.linalg.norm(t) == pytest.approx(1.0, abs=4 * EPS)
    assert t @ previous >= 0.0
    if np.linalg.cond(J) < 1e8:
        ref = np.linalg.solve(J, np.array([0.0, 0.0, 1.0]))
        ref /= np.linalg.norm(ref)
        ref = ref if ref @ previous >= 0 else -ref
        # two backward-stable solves of the same system: each within a few eps cond(J) of the exact unit vector
        np.testing.assert_allclose(t, ref, rtol=0, atol=8 * EPS * np.linalg.cond(J))


def test_tangent_of_a_singular_system_is_the_previous_direction():
    sol = Solution(z=np.zeros(3), evaluation=Evaluation(residual=np.zeros(2), jac_u=np.zeros((2, 2)),
                                                       jac_lam=np.zeros(2), trajectory=None), summary=None)
    t = Corrector(_Problem(), None).tangent(sol, np.array([0.0, 3.0, 4.0]))
    np.testing.assert_allclose(t, [0.0, 0.6, 0.8])


def test_tangent_of_the_compiled_corrector_is_the_bordered_solve(trilinear_flow, contact_orbit):
    """The compiled corrector solves the next tangent with the row it corrected along: Corrector.tangent takes
    it for that very row, and it is the dgesv solution of [[J_u, J_lam], [row]] t = e_last (two backward-stable
    solves of one system, each within a few eps cond(J) of the exact unit vector).  Another row (even an equal
    copy) is solved afresh."""
    from saltation.branches.continuation import ContinuationSettings
    from saltation.orbits.shooting import ShootingProblem

    problem = ShootingProblem(trilinear_flow, {"omega": 1.0}, continuation_parameter="omega")
    row = np.array([0.3, -0.2, 0.9])
    row /= np.linalg.norm(row)
    z_pred = np.append(contact_orbit.state0, 1.0) + 1e-4 * row
    corrector = Corrector(problem, ContinuationSettings())
    sol = corrector.solve_bordered(z_pred, row)
    ev = sol.evaluation
    assert ev.bordered_tangent is not None and ev.bordered_tangent[0] is row
    t = corrector.tangent(sol, row)
    J = np.vstack([np.column_stack([ev.jac_u, ev.jac_lam]), row])
    ref = np.linalg.solve(J, np.array([0.0, 0.0, 1.0]))
    ref /= np.linalg.norm(ref)
    ref = ref if ref @ row >= 0 else -ref
    np.testing.assert_allclose(t, ref, rtol=0, atol=8 * EPS * np.linalg.cond(J))
    np.testing.assert_allclose(corrector.tangent(sol, row.copy()), ref, rtol=0, atol=8 * EPS * np.linalg.cond(J))


def test_canonical_events_keeps_the_sequence_type():
    """Cached for tuples; a list (as read from a file) is rotated as before, and stays a list."""
    assert canonical_events(((1, 2, 0), (1, 0, 1))) == ((1, 0, 1), (1, 2, 0))
    assert canonical_events([(1, 2, 0), (1, 0, 1)]) == [(1, 0, 1), (1, 2, 0)]
    assert canonical_events(("b", "a", "c")) == ("a", "c", "b")
    assert canonical_events(()) == ()


def test_recorded_branch_point_is_a_copy():
    point = BranchPoint(parameter=float("nan"), state=np.zeros(2), period=1.0, amplitude=1.0, half_peak_to_peak=1.0,
                        multipliers=np.zeros(2, complex), stable=True, event_labels=())
    rec = point.recorded(0.5, 0.01, 2)
    assert (rec.parameter, rec.step, rec.iterations) == (0.5, 0.01, 2)
    assert np.isnan(point.parameter) and point.step == 0.0 and point.iterations == 0
    assert rec == dataclasses.replace(point, parameter=0.5, step=0.01, iterations=2)
    with pytest.raises(dataclasses.FrozenInstanceError):
        rec.parameter = 1.0


# ------------------------------------------------------------------ parameter vectors
def test_parameter_vectors_are_fresh_copies_and_follow_the_defaults():
    system = trilinear()
    i = system.parameter_index("omega")
    p = system.parameter_vector({"omega": 1.3})
    assert p[i] == 1.3
    p[:] = -7.0  # the caller's array: what is remembered is not touched
    again = system.parameter_vector({"omega": 1.3})
    assert again[i] == 1.3 and again[system.parameter_index("m")] == system.defaults["m"]
    m = system.defaults["m"]
    try:  # (the shipped model is shared by every test: its defaults are put back)
        system.defaults["m"] = 2.5  # defaults changed after a vector was remembered
        assert system.parameter_vector({"omega": 1.3})[system.parameter_index("m")] == 2.5
    finally:
        system.defaults["m"] = m
    assert system.parameter_vector({"omega": 1.3})[system.parameter_index("m")] == m
    for _ in range(2):  # refused every time, never remembered
        with pytest.raises(ModelError, match="divides by m"):
            system.parameter_vector({"m": 0.0})
        with pytest.raises(ModelError, match="unknown parameter"):
            system.parameter_vector({"nope": 1.0})
    assert system.parameter_vector({"omega": np.float64(0.9)})[i] == 0.9
    for k in range(100):  # many different sets: the memory stays small
        assert system.parameter_vector({"omega": 1.0 + k * 1e-3})[i] == 1.0 + k * 1e-3
    assert len(system._parameter_vectors) <= 64


def test_a_model_with_a_remembered_vector_still_pickles():
    import pickle

    system = block_on_belt()
    system.parameter_vector({"v_dr": 0.2})
    clone = pickle.loads(pickle.dumps(system))
    np.testing.assert_array_equal(clone.parameter_vector({"v_dr": 0.2}), system.parameter_vector({"v_dr": 0.2}))


# ------------------------------------------------------------------ the exact flow without a sensitivity
@pytest.mark.parametrize("backward", [False, True], ids=["forward", "backward"])
def test_monodromy_without_a_sensitivity_is_the_one_with_it(trilinear_flow, contact_orbit, backward):
    """A shot with no parameter sensitivity does not sum the sensitivity's series (it is zero and stays so):
    the state and the monodromy over three periods are those of the shot that carries d/d omega, to
    rounding."""
    p = trilinear_flow.parameters({"omega": 1.0})
    t1 = -3 * 2 * np.pi if backward else 3 * 2 * np.pi
    plain = trilinear_flow.run(contact_orbit.state0, 0.0, t1, p, variational=True)
    carried = trilinear_flow.run(contact_orbit.state0, 0.0, t1, p, variational=True, sensitivity="omega")
    assert plain.parameter_sensitivity is None and carried.parameter_sensitivity is not None
    assert plain.event_sequence == carried.event_sequence and len(plain.events) >= 9
    # rounding: a few units per step and event (the two series may stop a term apart), grown by the shot's
    # gain at most
    growth = max(1.0, float(np.abs(carried.monodromy).max()))
    rounding = 4 * EPS * (carried.n_steps + len(carried.events)) * growth
    np.testing.assert_allclose(plain.x1, carried.x1, rtol=0, atol=rounding * (1.0 + np.abs(carried.x1).max()))
    np.testing.assert_allclose(plain.monodromy, carried.monodromy, rtol=0, atol=rounding * growth)
