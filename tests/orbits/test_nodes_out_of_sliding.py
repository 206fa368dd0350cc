"""Multiple shooting places its nodes out of the orbit's sliding motions where they fit.

The corpus's two blocks on a belt (``tests/literature/models/two_block_chain.py``): block 1 sticks (slides on
its surface) twice a period, 59 % of it.  A node inside a sliding motion starts its segment on the surface; the
nodes, moved together along the orbit, are placed where the fewest of them lie inside one (then as far from the
events as they can).  Reference: the fewest possible, counted on a fine scan of every shift of the equally
spaced nodes against the sliding stretches of the single-shooting orbit; and the multipliers of the corpus's
``solve_ivp`` reference, whatever the nodes.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from saltation import EventKind, Flow, find_periodic_orbit

sys.path[:0] = [str(Path(__file__).parents[1] / "literature" / "models"), str(Path(__file__).parents[1] / "literature")]


def _sliding_stretches(flow, x0, T, p) -> list[tuple[float, float]]:
    traj = flow.run(x0, 0.0, T, p)
    out = []
    for k, e in enumerate(traj.events):
        if e.kind == EventKind.SLIDING_START:
            out.append((e.t, traj.events[k + 1].t if k + 1 < len(traj.events) else T))
    return out


def _inside(times, stretches) -> int:
    return sum(1 for t in times if any(a < t < b for a, b in stretches))


@pytest.mark.parametrize("segments", [3, 4, 6])
def test_the_fewest_nodes_lie_inside_sliding_motions(segments):
    import two_block_chain as case

    flow = Flow(case.CASE.model())
    p = dict(case.DEFAULTS)
    single = find_periodic_orbit(flow, case.CASE.orbit.guess, period=case.CASE.orbit.period, parameters=p)
    pv, T = flow.parameters(p), single.period
    stretches = _sliding_stretches(flow, single.state0, T, pv)
    assert sum(b - a for a, b in stretches) > 0.5 * T  # (the case this test is about)
    offsets = T * np.arange(segments) / segments
    fewest = min(_inside((offsets + s) % T, stretches) for s in np.linspace(0.0, T / segments, 5001))

    orbit = find_periodic_orbit(flow, case.CASE.orbit.guess, period=case.CASE.orbit.period, parameters=p,
                                segments=segments)
    mine = _sliding_stretches(flow, orbit.state0, orbit.period, pv)
    assert _inside(offsets, mine) == fewest
    mu = np.sort(np.abs(np.asarray(orbit.multipliers)))[:-1]  # (the trivial 1 is the largest here)
    np.testing.assert_allclose(mu, np.sort(np.abs(case.multipliers(p))), rtol=0, atol=1e-7)
