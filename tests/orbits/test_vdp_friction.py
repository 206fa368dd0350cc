"""A Van der Pol oscillator with Coulomb friction, against scipy (``tests/references.py``).

``x'' - eps (1 - x^2) x' + x + mu sgn(x') = 0``, ``eps = 0.5``, written as a user would: two
modes split by the switching surface ``v = 0``, listed both ways (a region-based model).
On ``v = 0`` the motion stops in the sticking set ``|x| <= mu``; outside it every orbit crosses
``v = 0`` transversally, at its turning points.

The references are fixed points of the return map on ``{v = 0, x > mu}`` (DOP853 at rtol
1e-12 with events, the multiplier from the variational equation with the jump at ``v = 0``,
cross-checked by Liouville's formula), each with its accuracy:

* mu = 0.2: a stable cycle (period 6.42127325342, multiplier 0.17650509976, turning point
  1.66540243434) and an unstable one inside it (turning point 0.56455057676, multiplier 3.4564);
* they merge in a fold of cycles at mu = 0.29750294224990; beyond it there is no cycle
  (at mu = 0.3, ``P(a) - a <= -0.0106`` for every turning point ``a``), and every orbit ends in
  the sticking set;
* as mu -> 0 the unstable cycle shrinks onto the origin like ``2.59935 mu`` (scaled by mu it
  tends to the relay oscillator's cycle, in closed form), so it collapses at mu = 0.

Tolerances: the references' own accuracy plus what saltation's integration promises: its
default tolerances (rtol 1e-10) per DOP853 step in these nonlinear modes; over one period of
these cycles we allow ``GLOBAL = 10 rtol`` relative (errors of 5e-12 are observed).
Trivial multipliers are 1 to 1e-8.
"""

from __future__ import annotations

import numpy as np
import pytest
import references as R

import saltation
from saltation import (
    Crossing,
    EventKind,
    Flow,
    Mode,
    PiecewiseSystem,
    Transition,
    continue_orbit,
    find_periodic_orbit,
)
from saltation.branches.branch import SpecialPointKind, StopReason

#: saltation's default integration tolerance per step (``Tolerances().rtol``)
RTOL = 1e-10
#: what we accept as its global error over one period, relative
GLOBAL = 10 * RTOL
#: the trivial multiplier of an autonomous orbit
TRIVIAL = 1e-8
MU = 0.2
FOLD = SpecialPointKind.FOLD
COLLAPSE = SpecialPointKind("cycle_collapse")


def vdp_friction() -> PiecewiseSystem:
    """``x'' - eps (1 - x^2) x' + x + mu sgn(x') = 0``: friction ``mu`` opposes the velocity."""
    return PiecewiseSystem(
        name="vdp_friction",
        states=["x", "v"],
        parameters={"eps": R.VDP_EPS, "mu": MU},
        modes=[
            Mode("plus", ["v", "eps*(1 - x**2)*v - x - mu"], domain=["v > 0"]),
            Mode("minus", ["v", "eps*(1 - x**2)*v - x + mu"]),
        ],
        surfaces={"v": "v"},
        transitions=[  # region-based: the boundary both ways
            Transition("plus", "v", Crossing.FALLING, "minus"),
            Transition("minus", "v", Crossing.RISING, "plus"),
        ],
    )


@pytest.fixture(scope="module")
def flow() -> Flow:
    return Flow(vdp_friction())


@pytest.fixture(scope="module")
def orbit(flow):
    """The stable cycle at mu = 0.2 from a guess on the switching surface, at a turning point."""
    return find_periodic_orbit(flow, [2.0, 0.0], period=7.0)


def split_multipliers(multipliers) -> tuple[complex, complex]:
    """(trivial, nontrivial): the trivial one is the one nearest 1."""
    m = sorted(np.asarray(multipliers, complex), key=lambda z: abs(z - 1.0))
    return m[0], m[1]


def close(value: float, ref: R.Value, scale: float | None = None) -> bool:
    """``value`` within the reference's accuracy plus saltation's global error (relative to ``scale``)."""
    scale = abs(ref.value) if scale is None else scale
    return abs(value - ref.value) <= ref.accuracy + GLOBAL * max(scale, 1.0)


def assert_cycle(period, multipliers, amplitude, ref: R.VdpCycle) -> None:
    """Period, turning point (= max |x|, the cycle is symmetric) and multipliers against a reference cycle."""
    trivial, nontrivial = split_multipliers(multipliers)
    assert abs(trivial - 1.0) <= TRIVIAL, multipliers
    assert abs(nontrivial.imag) <= TRIVIAL and close(nontrivial.real, ref.multiplier), (multipliers, ref.multiplier)
    assert close(period, ref.period), (period, ref.period)
    assert close(amplitude, ref.turning_point), (amplitude, ref.turning_point)


@pytest.mark.parametrize("guess", [[2.0, 0.0], [2.0, 0.5]], ids=["on_the_surface_at_a_turning_point", "off_the_surface"])
def test_stable_cycle(flow, guess):
    found = find_periodic_orbit(flow, guess, period=7.0)
    ref = R.vdp_stable_cycle(MU)
    assert_cycle(found.period, found.multipliers, found.amplitude, ref)
    assert found.stable

    # one crossing each way per period, each once, at the turning points (+-a*, 0)
    events = found.events
    assert len(events) == 2, [(e.t, e.mode_from, e.mode_to) for e in events]
    assert all(e.kind == EventKind.TRANSITION and e.surface == "v" for e in events)
    assert {(e.mode_from, e.mode_to) for e in events} == {("plus", "minus"), ("minus", "plus")}
    for e in events:
        turning = ref.turning_point if e.mode_from == "plus" else R.Value(-ref.crossing.value, ref.crossing.accuracy)
        assert close(abs(e.x_minus[0]), turning), (e.x_minus, turning)
        assert np.sign(e.x_minus[0]) == (1.0 if e.mode_from == "plus" else -1.0)
        assert abs(e.x_minus[1]) <= GLOBAL * ref.turning_point.value
    t0, t1 = found.t0, found.t0 + found.period
    assert all(t0 <= e.t <= t1 for e in events)
    assert abs(events[0].t - events[1].t) > 0.1 * found.period  # two distinct crossings, not one twice


def test_no_cycle_beyond_the_fold(flow):
    """At mu = 0.3 > mu_fold there is no cycle: the guess can only reach a point where the motion stops."""
    fold = R.vdp_fold().mu
    assert 0.3 > fold.value + fold.accuracy
    gap = R.vdp_largest_gap(0.3)  # max over turning points a of P(a) - a
    assert gap.value + gap.accuracy < 0.0, gap
    x_stop, returns = R.vdp_orbit_end(0.3, 2.0)  # the guess's own orbit runs down past the fold's ghost and stops
    assert abs(x_stop) <= 0.3 and returns > 1
    with pytest.raises(saltation.StationaryStateError, match="equilibrium") as info:
        find_periodic_orbit(flow, [2.0, 0.0], parameters={"mu": 0.3}, period=7.0)
    # the only states that do not move: the sticking set |x| <= mu on v = 0 (its edges are modes' equilibria)
    assert len(info.value.state) == 2 and R.vdp_in_sticking_set(info.value.state, 0.3), info.value.state


def test_reference_cross_checks():
    """The references agree with their independent second derivations."""
    # the collapse slope: closed form (the relay limit) and scipy's small cycles extrapolated in mu^2
    slope, (numeric, _) = R.vdp_collapse_slope(), R.vdp_collapse_slope_numeric()
    assert abs(slope.value - numeric.value) <= slope.accuracy + numeric.accuracy, (slope, numeric)
    # the multiplier: variational equation and central differences of the return map (h = 1e-4: truncation
    # h^2 |P'''| / 6 < 2e-9, rounding 1e-12 / h = 1e-8)
    ref = R.vdp_stable_cycle(MU)
    a, h = ref.turning_point.value, 1e-4
    fd = (R.vdp_return_map(a + h, MU).image - R.vdp_return_map(a - h, MU).image) / (2 * h)
    assert abs(fd - ref.multiplier.value) <= 2e-8
    # Liouville's formula at the fold: exp(int div f) prod det S = 1
    fold = R.vdp_fold()
    assert R.vdp_return_map(fold.turning_point.value, fold.mu.value).liouville == pytest.approx(1.0, abs=1e-10)


def folds(branch):
    return [sp for sp in branch.special_points if sp.kind is FOLD]


def assert_the_fold(sp) -> None:
    ref = R.vdp_fold().mu
    assert abs(sp.parameter - ref.value) <= sp.accuracy + ref.accuracy, (sp.parameter, sp.accuracy, ref)
    assert np.max(np.abs(np.asarray(sp.multipliers) - 1.0)) <= 1e-6, sp.multipliers


def test_fold_of_cycles(orbit):
    branch = continue_orbit(orbit, "mu", bounds=(0.2, 0.4))
    # each cycle crosses v = 0 twice, transversally, all along: no change of the event sequence, no corner;
    # planar and autonomous: no flip, no torus.  The fold is all there is.
    assert [sp.kind for sp in branch.special_points] == [FOLD], [(sp.kind, sp.parameter) for sp in branch.special_points]
    (fold,) = folds(branch)
    assert_the_fold(fold)
    # stable up to the fold, unstable beyond it
    stable = branch.stable
    assert stable[: fold.index + 1].all() and not stable[fold.index + 1 :].any(), stable
    # back at mu = 0.2 on the other side of the fold: the unstable cycle
    last = branch.points[-1]
    assert last.parameter == pytest.approx(MU, abs=1e-12)
    assert_cycle(last.period, last.multipliers, last.amplitude, R.vdp_unstable_cycle(MU))


def test_unstable_cycle_collapses_at_mu_zero(orbit):
    branch = continue_orbit(orbit, "mu", bounds=(0.0, 0.5))
    (fold,) = folds(branch)
    assert_the_fold(fold)

    # the branch ends where the unstable cycle shrinks onto the origin: at mu = 0
    collapse = branch.special_points[-1]
    assert collapse.kind is COLLAPSE, [(sp.kind, sp.parameter) for sp in branch.special_points]
    assert collapse.index >= len(branch.points) - 2  # at the end of the branch
    ref = R.vdp_collapse_parameter()
    assert abs(collapse.parameter - ref.value) <= collapse.accuracy + ref.accuracy, (collapse.parameter, collapse.accuracy)
    assert np.linalg.norm(collapse.state) <= 1e-6, collapse.state  # the cycles are symmetric about the origin
    assert "collapse" in branch.stop_reason.value
    assert branch.amplitude.min() > 1e-6

    # the last orbits are the unstable cycles of the scipy reference at their mu, shrinking like 2.5993 mu
    # (a / mu = c + c2 mu^2 + O(mu^4): c in closed form, c2 from scipy's cycles, twice it for the remainder)
    slope, (_, c2) = R.vdp_collapse_slope().value, R.vdp_collapse_slope_numeric()
    for point in branch.points[-2:]:
        assert 0.0 < point.parameter < 0.05
        assert_cycle(point.period, point.multipliers, point.amplitude, R.vdp_unstable_cycle(point.parameter))
        assert abs(point.amplitude / point.parameter - slope) <= 2 * abs(c2) * point.parameter**2

    # the other direction: the stable cycle down to mu = 0, the Van der Pol oscillator's limit cycle
    assert branch.stop_reasons == [StopReason.PARAMETER_BOUND]
    first = branch.points[0]
    assert first.parameter == pytest.approx(0.0, abs=1e-12)
    assert_cycle(first.period, first.multipliers, first.amplitude, R.vdp_stable_cycle(0.0))
