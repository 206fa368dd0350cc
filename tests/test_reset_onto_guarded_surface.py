"""A reset that leaves the state on its surface, moving on across it, where the new mode's transition there has a
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
