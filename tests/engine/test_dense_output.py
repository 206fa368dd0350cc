"""Dense output of a trajectory against the closed-form harmonic response."""

from __future__ import annotations

import numpy as np
import pytest

from saltation import Flow
from saltation.models import trilinear
from saltation.apps.paper import linear_response_state


@pytest.mark.parametrize("backward", [False, True])
def test_states_at_times_match_closed_form(backward):
    flow = Flow(trilinear())
    w = 0.7
    params = dict(flow.system.defaults) | {"omega": w}
    x0 = linear_response_state(params)  # on the no-contact periodic orbit: x = a sin(wt) + b cos(wt)
    T = 2 * np.pi / w
    t1 = -T if backward else T
    traj = flow.run(x0, 0.0, t1, flow.parameters({"omega": w}), dense=True)
    times = np.linspace(0.0, t1, 57)
    det = (1 - w**2) ** 2 + (0.05 * w) ** 2
    a, b = 0.2 * (1 - w**2) / det, -0.2 * 0.05 * w / det
    exact = np.c_[a * np.sin(w * times) + b * np.cos(w * times), a * w * np.cos(w * times) - b * w * np.sin(w * times)]
    assert np.allclose(traj.at(times), exact, atol=1e-8)
    ts, xs = traj.sample(4)
    assert np.allclose(xs[:, 0], a * np.sin(w * ts) + b * np.cos(w * ts), atol=1e-8)


def test_dense_output_needs_dense_run():
    flow = Flow(trilinear())
    traj = flow.run([0.1, 0.0], 0.0, 1.0, flow.parameters())
    with pytest.raises(ValueError, match="dense=True"):
        traj.at([0.5])
