"""A reset that leaves the state on its surface, moving on across it, where no transition of the new mode fires that
crossing: its guard fails, or none watches that direction (a block pivoting onto its other corner).  First, one with a
guard that fails: the motion goes on (a walker's legs swapped at heel strike), against the closed form.

``x1' = 1, x2' = 0`` from ``(-2, -1)``: the surface ``x1 + x2`` rises through zero at ``t = 3`` where the
transition swaps the states, ``(1, -1) -> (-1, 1)``; the sum stays zero and keeps rising, and the guard
``x1 - x2 > 0`` fails after the swap, so no transition fires and the motion goes on to ``(1, 1)`` at ``t = 5``.
The saltation matrix, eq. (9) with the reset ``g = (x2, x1)``: ``S = g_x + (f+ - g_x f-) h_x^T / (h_x f-)`` with
``f- = f+ = (1, 0)``, ``h_x = (1, 1)``: ``[[1, 2], [0, -1]]``, the monodromy over ``[0, 5]``.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from saltation import Crossing, Flow, Mode, PiecewiseSystem, SlidingError, Transition


@functools.cache
def swap(guard: str) -> Flow:
    return Flow(PiecewiseSystem(
        name="test_swap_onto_surface", states=["x1", "x2"], parameters={"k": 1.0},
        modes=[Mode("m", ["k", "0"])], surfaces={"h": "x1 + x2"},
        transitions=[Transition("m", "h", Crossing.RISING, "m", reset=["x2", "x1"], guard=[guard])],
    ))


def test_a_swap_whose_guard_then_fails_goes_on_across_the_surface():
    flow = swap("x1 - x2 > 0")
    traj = flow.run([-2.0, -1.0], 0.0, 5.0, flow.parameters(), variational=True)
    assert [(e.surface, e.mode_to) for e in traj.events] == [("h", "m")]
    assert traj.events[0].t == pytest.approx(3.0, abs=1e-12)
    np.testing.assert_allclose(traj.x1, [1.0, 1.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(traj.monodromy, [[1.0, 2.0], [0.0, -1.0]], rtol=0, atol=1e-12)


def test_a_swap_whose_guard_still_holds_is_refused():
    """The same reset with a guard that holds after it: the transition would fire again at once, for ever; no
    motion is defined there (a named error, not a silent pass through the surface)."""
    flow = swap("x1 + 10 > 0")
    with pytest.raises(SlidingError, match="leaves the state on the surface"):
        flow.run([-2.0, -1.0], 0.0, 5.0, flow.parameters())


@functools.cache
def pivot() -> Flow:
    """Two regions of free flight either side of ``x = 0``, an impact on each crossing that keeps the velocity's
    sign (``v -> r v``): a block that pivots onto its other corner."""
    return Flow(PiecewiseSystem(
        name="test_pivot_onto_other_side", states=["x", "v"], parameters={"r": 0.9},
        modes=[Mode("right", ["v", "0"], domain=["x > 0"]), Mode("left", ["v", "0"])],
        surfaces={"ground": "x"},
        transitions=[Transition("right", "ground", Crossing.FALLING, "left", reset=["x", "r*v"]),
                     Transition("left", "ground", Crossing.RISING, "right", reset=["x", "r*v"])],
    ))


@pytest.mark.parametrize("r", [0.9, 0.5, 1.0])
def test_an_impact_onto_the_far_side_goes_on_into_the_target_mode(r):
    """From ``(1, -1)``: the ground at ``t = 1``, ``v -> -r``, then ``left`` to ``(-r, -r)`` at ``t = 2``.  Eq. (9)
    with ``g_x = diag(1, r)``, ``f- = (-1, 0)``, ``f+ = (-r, 0)``, ``h_x = (1, 0)``: ``S = r I``, and the monodromy
    ``[[1, 1], [0, 1]] S [[1, 1], [0, 1]] = r [[1, 2], [0, 1]]``."""
    flow = pivot()
    traj = flow.run([1.0, -1.0], 0.0, 2.0, flow.parameters({"r": r}), variational=True)
    assert [(e.surface, e.mode_to) for e in traj.events] == [("ground", "left")] and traj.mode1 == "left"
    np.testing.assert_allclose(traj.x1, [-r, -r], rtol=0, atol=1e-12)
    np.testing.assert_allclose(traj.monodromy, r * np.array([[1.0, 2.0], [0.0, 1.0]]), rtol=0, atol=1e-12)
