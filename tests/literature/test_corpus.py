"""Every model of the literature corpus (``tests/literature/models``) through the steps a researcher takes.

See :mod:`corpus` for what a case declares.  The orbit and the branch of a case are computed once and shared
by its later steps.  Every branch is checked against the invariants by ``tests/conftest.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from corpus import LiteratureCase, load_cases

from saltation import ContinuationSettings, Flow, ShootingProblem, continue_orbit, find_periodic_orbit, lyapunov_exponents, sweep
from saltation.special_points.loci import follow_locus

CASES = load_cases()
IDS = [c.name for c in CASES]
_ORBITS: dict[str, object] = {}
_BRANCHES: dict[str, object] = {}


def _skip_unless(step, request, case: LiteratureCase, name: str) -> None:
    if step is None:
        pytest.skip("the case has no such step")
    if getattr(step, "thorough", False) and not request.config.getoption("--thorough"):
        pytest.skip("runs with --thorough")
    _known_failure(request, case, name)


def _known_failure(request, case: LiteratureCase, name: str) -> None:
    if name in case.known_failures:
        request.applymarker(pytest.mark.xfail(strict=True, reason=case.known_failures[name]))


def _orbit(case: LiteratureCase):
    if case.name not in _ORBITS:
        o = case.orbit
        _ORBITS[case.name] = find_periodic_orbit(
            case.model(), o.guess, parameters=dict(o.parameters), period=o.period, t0=o.t0, mode0=o.mode0
        )
    return _ORBITS[case.name]


def _branch(case: LiteratureCase):
    if case.name not in _BRANCHES:
        b = case.branch
        settings = ContinuationSettings(ds=b.ds, ds_max=b.ds_max, max_points=b.max_points)
        _BRANCHES[case.name] = continue_orbit(_orbit(case), b.parameter, bounds=b.bounds, settings=settings)
    return _BRANCHES[case.name]


def _matched(computed: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``computed`` reordered to face ``reference`` (greedy nearest match, each computed value used once)."""
    left = list(np.asarray(computed, dtype=complex))
    out = []
    for r in np.asarray(reference, dtype=complex):
        k = int(np.argmin([abs(c - r) for c in left]))
        out.append(left.pop(k))
    return np.array(out)


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_case_is_described(case: LiteratureCase):
    """Each case names its field and its source, and its model builds."""
    assert case.field and case.source
    system = case.model()
    assert system.n >= 1


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_orbit_from_the_natural_guess(case: LiteratureCase, request):
    """The orbit from the case's natural guess; its multipliers against the reference's."""
    _known_failure(request, case, "orbit")
    orbit = _orbit(case)
    assert orbit.converged
    mu = np.asarray(orbit.multipliers, dtype=complex)
    p = dict(orbit.parameters) if isinstance(orbit.parameters, dict) else dict(case.orbit.parameters)
    if orbit.autonomous:
        k = int(np.argmin(np.abs(mu - 1.0)))
        assert abs(mu[k] - 1.0) <= 1e-6, f"trivial multiplier {mu[k]} is not 1"
        mu = np.delete(mu, k)
    ref = np.asarray(case.orbit.multipliers(p), dtype=complex)
    assert len(ref) == len(mu)
    got = _matched(mu, ref)
    np.testing.assert_allclose(got, ref, rtol=0, atol=case.orbit.rtol * max(1.0, float(np.max(np.abs(ref)))))
    if case.orbit.state is not None:
        ref_x = np.asarray(case.orbit.state(p), dtype=float)
        np.testing.assert_allclose(orbit.state0, ref_x, rtol=0, atol=case.orbit.rtol * (1.0 + np.max(np.abs(ref_x))))


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_branch_special_points(case: LiteratureCase, request):
    """The branch's special points are the reference's, kind by kind, and no others."""
    _skip_unless(case.branch, request, case, "branch")
    branch = _branch(case)
    expected = list(case.branch.expected())
    found = list(branch.special_points)
    unexplained = []
    for sp in found:
        match = [e for e in expected if sp.kind.value in e.kinds and abs(sp.parameter - e.value) <= e.tol + sp.accuracy]
        if match:
            expected.remove(match[0])
        else:
            unexplained.append(f"{sp.kind.value} at {sp.parameter:.12g} (accuracy {sp.accuracy:.2g})")
    missing = [f"{'/'.join(e.kinds)} at {e.value:.12g} (tol {e.tol:.2g})" for e in expected]
    assert not missing and not unexplained, (
        f"{case.name}: missing {missing}; not in the reference {unexplained}; branch stopped: {branch.stop_reason}"
    )
    # the invariants in the test itself too (tests/conftest.py checks them after the test): a branch whose points
    # are right but whose one-sided multipliers break them fails here, where a known failure can declare it
    check = branch.check()
    assert check.ok, f"{case.name}: the branch breaks its invariants:\n{check}"


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_two_parameter_curve(case: LiteratureCase, request):
    """The curve of one special point in a second parameter against the reference's curve."""
    _skip_unless(case.locus, request, case, "locus")
    step = case.locus
    branch = _branch(case)
    points = [sp for sp in branch.special_points if sp.kind.value == step.kind]
    assert points, f"no {step.kind} on the branch to continue"
    # built as a user builds it: the start mode only where the case names one (a memory mode); the special
    # point's orbit may start in another mode than the natural orbit's, and its own section (align_section)
    problem = ShootingProblem(
        Flow(case.model()), dict(case.orbit.parameters), continuation_parameter=case.branch.parameter,
        t0=case.orbit.t0, mode0=case.orbit.mode0,
    )
    locus = follow_locus(problem, points[0], step.second, step.bounds)
    values = locus.values
    assert len(values) >= 5, f"the curve has {len(values)} points: {locus.stop_detail}"
    errors = [abs(first - step.reference(second)) for first, second in values]
    assert max(errors) <= step.tol, f"largest distance to the reference curve {max(errors):.3g} > {step.tol:.3g}"


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_sweep(case: LiteratureCase, request):
    """A brute-force sweep, checked by the case against its reference."""
    _skip_unless(case.sweep, request, case, "sweep")
    step = case.sweep
    result = sweep(case.model(), step.parameter, step.values, parameters=dict(case.orbit.parameters),
                   workers=1, **dict(step.options))
    step.check(result)


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_lyapunov_exponents(case: LiteratureCase, request):
    """Lyapunov exponents where the motion is chaotic, against the reference."""
    _skip_unless(case.lyapunov, request, case, "lyapunov")
    step = case.lyapunov
    result = lyapunov_exponents(Flow(case.model()), step.state0, parameters=dict(step.parameters), time=step.time,
                                transient=step.transient, mode0=step.mode0)
    step.check(np.asarray(result.exponents))
