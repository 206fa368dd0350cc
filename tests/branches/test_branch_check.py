"""Every change of stability explained: the invariants of a computed branch, and the detection behind them.

* :func:`saltation.branches.check.check_branch` against hand-made branches whose violations are known;
* the Neimark-Sacker test function (the bialternate product ``prod_{i<j} (mu_i mu_j - 1)``) against its
  closed form, and its continuity where a complex pair turns real (the old ``|mu| - 1`` of the largest
  complex multiplier jumped there, and reported a Neimark-Sacker point whose multipliers were all real);
* a real multiplier through +1 without a turning point is a ``branch_point``, on the impact oscillator between
  two stops written without its symmetry (reference: the symmetry breaking of the independent scipy
  implementation in ``tests/symmetry_reference.py``);
* a step that jumps over two changes of stability is cut until it cannot (the Jeffcott rotor with gravity,
  whose two period doublings after the first contact vanished with a large ``ds_max``).
"""

from __future__ import annotations

import cmath
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import Crossing, Flow, PiecewiseSystem, Transition
from saltation.branches.branch import Branch, BranchKind, SpecialPoint, SpecialPointKind, StopReason
from saltation.branches.check import check_branch, count_range
from saltation.model import Mode
from saltation.orbits.records import BranchPoint
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.special_points.detection import _ns_test


# ------------------------------------------------------------------ hand-made branches
def _point(lam: float, mu, *, stable: bool | None = None) -> BranchPoint:
    mu = np.asarray(mu, dtype=complex)
    return BranchPoint(parameter=lam, state=np.zeros(2), period=1.0, amplitude=1.0, half_peak_to_peak=1.0,
                       multipliers=mu, stable=bool(np.all(np.abs(mu) < 1)) if stable is None else stable,
                       event_labels=())


def _sp(kind: SpecialPointKind, lam: float, index: int, **kw) -> SpecialPoint:
    kw.setdefault("bracket", (lam - 1e-9, lam + 1e-9))
    kw.setdefault("accuracy", 2e-9)
    return SpecialPoint(kind=kind, parameter=lam, index=index, state=np.zeros(2), period=1.0, amplitude=1.0, **kw)


def _branch(mus, sps=(), *, autonomous=False, stop=StopReason.PARAMETER_BOUND, detail="") -> Branch:
    return Branch(model="hand-made", parameter_name="lam", kind=BranchKind.PERIODIC, autonomous=autonomous,
                  points=[_point(0.1 * k, mu) for k, mu in enumerate(mus)], special_points=list(sps),
                  stop_reason=stop, stop_detail=detail)


def rules(branch: Branch) -> list[str]:
    return [v.rule for v in check_branch(branch).violations]


def test_a_branch_whose_stability_never_changes_holds():
    assert check_branch(_branch([[0.5, 0.2]] * 4)).ok


def test_a_period_doubling_covers_one_multiplier_through_minus_one():
    mus = [[-0.8, 0.1], [-0.95, 0.1], [-1.05, 0.1], [-1.2, 0.1]]
    assert rules(_branch(mus)) == ["uncovered_change"]
    good = _sp(SpecialPointKind.PERIOD_DOUBLING, 0.15, 1, multipliers=np.array([-1.0 + 0j, 0.1]))
    assert check_branch(_branch(mus, [good])).ok
    # a "fold" there has no multiplier at +1: its kind does not agree with its multipliers
    bad = _sp(SpecialPointKind.FOLD, 0.15, 1, multipliers=np.array([-1.0 + 0j, 0.1]))
    assert rules(_branch(mus, [bad])) == ["kind_mismatch"]


def test_a_pair_leaving_needs_a_neimark_sacker_point_not_a_fold():
    z = cmath.exp(1j)
    mus = [[0.9 * z, 0.9 * z.conjugate()], [1.1 * z, 1.1 * z.conjugate()]]
    fold = _sp(SpecialPointKind.FOLD, 0.05, 0, multipliers=np.array([1.0 + 0j, 0.5]))
    assert "uncovered_change" in rules(_branch(mus, [fold]))  # a fold moves one multiplier, not two
    ns = _sp(SpecialPointKind.NEIMARK_SACKER, 0.05, 0, multipliers=np.array([z, z.conjugate()]))
    assert check_branch(_branch(mus, [ns])).ok
    fake = _sp(SpecialPointKind.NEIMARK_SACKER, 0.05, 0, multipliers=np.array([-1.178 + 0j, -0.455]))
    assert "kind_mismatch" in rules(_branch(mus, [fake]))


def test_a_point_located_on_a_branch_point_covers_both_steps_that_meet_there():
    """A Hopf or period doubling located exactly at a branch point is in the step before it, while the
    multiplier counted at that point is on the circle: the step after it is covered too."""
    mus = [[-0.9, 0.1], [-1.0, 0.1], [-1.1, 0.1]]
    pd = _sp(SpecialPointKind.PERIOD_DOUBLING, 0.1, 0, multipliers=np.array([-1.0 + 0j, 0.1]), accuracy=1e-12,
             bracket=(0.1, 0.1))
    assert check_branch(_branch(mus, [pd])).ok
    assert count_range([-1.0, 0.1], autonomous=False) == (0, 1)


def test_the_trivial_multiplier_of_an_autonomous_orbit_is_one():
    assert check_branch(_branch([[1.0, 0.3], [1.0 + 1e-9, 0.31]], autonomous=True)).ok
    assert rules(_branch([[1.0, 0.3], [0.97, 0.31]], autonomous=True)) == ["trivial_multiplier"]


def test_a_bracketed_point_lies_in_its_bracket_and_its_accuracy_is_its_width():
    mus = [[0.5, 0.1]] * 3
    outside = _sp(SpecialPointKind.GRAZING, 0.15, 1, bracket=(0.1, 0.12), accuracy=0.02)
    assert rules(_branch(mus, [outside])) == ["bracket"]
    narrow = _sp(SpecialPointKind.GRAZING, 0.11, 1, bracket=(0.1, 0.12), accuracy=0.01)
    assert rules(_branch(mus, [narrow])) == ["bracket"]
    honest = _sp(SpecialPointKind.GRAZING, 0.11, 1, bracket=(0.1, 0.12), accuracy=0.02)
    assert check_branch(_branch(mus, [honest])).ok


def test_a_branch_that_stops_says_what_it_found():
    mus = [[0.5, 0.1]] * 3
    assert rules(_branch(mus, stop=StopReason.MIN_STEP)) == ["silent_stop"]
    assert check_branch(_branch(mus, stop=StopReason.MIN_STEP, detail="at lam = 0.2: ConvergenceError: ...")).ok
    end = _sp(SpecialPointKind.DISCONTINUOUS_FOLD, 0.2, 2, crossing_point=1.0 + 0j,
              multipliers_minus=np.array([0.5, 0.1]), multipliers_plus=np.array([np.inf, 0.1]))
    assert check_branch(_branch(mus, [end], stop=StopReason.MIN_STEP)).ok
    with pytest.raises(Exception, match="silent_stop"):
        _branch(mus, stop=StopReason.MIN_STEP).check().raise_if_broken()


# ------------------------------------------------------------------ the Neimark-Sacker test function
@settings(max_examples=200, deadline=None)
@given(st.floats(0.05, 0.95), st.floats(0.05, 3.0), st.floats(-0.9, 0.9), st.floats(1e-3, 0.3))
def test_the_ns_test_keeps_its_sign_where_a_complex_pair_turns_real(r, theta, lam, spread):
    """A complex pair ``lam +- i s`` that meets the real axis and splits into ``lam +- d`` (inside the unit
    circle) beside a pair ``r e^{+-i theta}`` inside it: no product of two multipliers passes 1, so the test
    keeps its sign along the whole path; it changes sign where the other pair's modulus passes 1."""
    inner = [r * cmath.exp(1j * theta), r * cmath.exp(-1j * theta)]
    path = [[complex(lam, s), complex(lam, -s)] for s in np.linspace(spread, 0.0, 8)]
    path += [[complex(lam + d), complex(lam - d)] for d in np.linspace(0.0, min(spread, 0.95 - abs(lam)), 8)]
    signs = {np.sign(_ns_test(np.array(inner + pair))) for pair in path}
    assert len(signs) == 1
    out = [1.05 * cmath.exp(1j * theta) / 1.0, 1.05 * cmath.exp(-1j * theta)]
    pair = path[-1]
    assert np.sign(_ns_test(np.array(out + pair))) != np.sign(_ns_test(np.array(inner + pair)))


def test_the_ns_test_is_the_bialternate_product():
    mu = np.array([0.5 + 0.5j, 0.5 - 0.5j, -0.3])
    expected = ((0.5 + 0.5j) * (0.5 - 0.5j) - 1) * ((0.5 + 0.5j) * -0.3 - 1) * ((0.5 - 0.5j) * -0.3 - 1)
    assert _ns_test(mu) == pytest.approx(expected.real, rel=1e-15)
    assert math.isnan(_ns_test(np.array([0.5])))


# ------------------------------------------------------------------ a pitchfork nobody declared
def undeclared_symmetric_impact_oscillator() -> PiecewiseSystem:
    """The shipped impact oscillator between two stops, written without its symmetry."""
    from saltation.models.symmetric_impact_oscillator import DEFAULTS

    return PiecewiseSystem(
        name="impact_between_stops_undeclared",
        states=["x", "v"],
        parameters=dict(DEFAULTS),
        modes=[Mode("free", ["v", "-2*zeta*v - x + f0*cos(omega*t)"])],
        surfaces={"right": "x - d", "left": "x + d"},
        transitions=[
            Transition("free", "right", Crossing.RISING, "free", reset=["x", "-r*v"]),
            Transition("free", "left", Crossing.FALLING, "free", reset=["x", "-r*v"]),
        ],
        period="2*pi/omega",
    )


def test_a_multiplier_through_plus_one_without_a_turning_point_is_a_branch_point():
    """The symmetric orbit's multiplier passes +1 at its symmetry breaking; without the symmetry declared the
    branch goes on through it (no turning point): a ``branch_point``, at the reference's parameter, with a
    multiplier at +1 (it used to change ``stable`` with no special point)."""
    import symmetry_reference as reference
    from saltation.models.symmetric_impact_oscillator import DEFAULTS

    flow = Flow(undeclared_symmetric_impact_oscillator())
    problem = ShootingProblem(flow, {"omega": 0.95}, continuation_parameter="omega")
    orbit = problem.solve(np.array([0.92, 0.49]), 0.95)
    branch = continue_branch(problem, orbit.state0, 0.95, settings=ContinuationSettings(bounds=(0.9, 1.0)),
                             directions=(1,))
    points = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.BRANCH_POINT]
    assert len(points) == 1
    (bp,) = points
    omega, _, _ = reference.impact_symmetry_breaking(dict(DEFAULTS), 0.97, 0.99, np.array([0.922, 0.4935]))
    # the reference is good to 1e-11; the point is bracketed by the Illinois iteration to its accuracy
    assert abs(bp.parameter - omega) <= 1e-11 + bp.accuracy
    assert min(abs(np.asarray(bp.multipliers) - 1.0)) <= bp.multipliers_accuracy
    assert bool(np.any(branch.stable)) and not bool(np.all(branch.stable))
    assert check_branch(branch).ok


def test_a_nonsmooth_point_where_nothing_changes_is_a_violation():
    """Two sides with the same events up to where the orbit starts (the section moved through an impact or a
    stick phase) and the same stability: not a special point.  A change of the events, or a tangency, is."""
    from saltation.branches.branch import OneSided

    def corner(kind, minus, plus):
        sides = OneSided(multipliers_minus=np.array([0.5, 0.2], dtype=complex),
                         multipliers_plus=np.array([0.4, 0.3], dtype=complex),
                         event_labels_minus=minus, event_labels_plus=plus)
        return _sp(kind, 0.15, 1, one_sided=sides)

    rotated = corner(SpecialPointKind.NONSMOOTH_NO_CROSSING, ("a", "b", "c"), ("b", "c", "a"))
    assert rules(_branch([[0.5, 0.2]] * 4, [rotated])) == ["no_change"]
    changed = corner(SpecialPointKind.NONSMOOTH_NO_CROSSING, ("a", "b"), ("a", "b", "c"))
    assert rules(_branch([[0.5, 0.2]] * 4, [changed])) == []
    touched = corner(SpecialPointKind.GRAZING, ("a", "b"), ("b", "a"))
    assert "no_change" not in rules(_branch([[0.5, 0.2]] * 4, [touched]))
