"""Two-parameter brute-force maps and sweeps on a Dask cluster.

Reference: the ball on a vibrating table, iterated as its closed-form impact map (free flight
y = y_i + v t - g t^2 / 2 until it meets s(t) = A sin(w t), found by brentq; Newton's restitution law),
written with numpy and scipy only (tests/special_points/test_branch_switching.py). Its period-1 orbits lose stability at
A w^2 / g = sqrt((pi (1 - e) / (1 + e))^2 + (2 (1 + e^2) / (1 + e)^2)^2) (Holmes 1982).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from saltation import ModelError
from saltation.models import bouncing_ball, friction_oscillator
from saltation.models.bouncing_ball import DEFAULTS
from saltation.apps.sweeps import PeriodMap, attractor_period, period_map, sweep

sys.path.insert(0, str(Path(__file__).parents[1] / "special_points"))  # (a sibling folder's closed forms)
from test_branch_switching import impact_map  # the closed-form impact map (restitution e an argument)

G, W = DEFAULTS["g"], DEFAULTS["omega"]
T = 2 * np.pi / W
A_VALUES = [0.32, 0.34, 0.36, 0.385, 0.395, 0.40]
E_VALUES = [0.45, 0.5, 0.55]


def reference_period(A, e, max_period=8):
    """The attractor's period in forcing periods: the impact map iterated from beside the period-1 orbit,
    its impacts (phase mod T, velocity) compared after a transient; 0 when none up to max_period."""
    phi = np.arccos((1 - e) * np.pi * G / ((1 + e) * A * W**2))
    u = np.array([phi / W + 1e-3, G * T / 2])
    for _ in range(400):
        u = impact_map(A, u, e)
    seq = []
    for _ in range(4 * max_period):
        u = impact_map(A, u, e)
        seq.append([u[0] % T, u[1]])
    return attractor_period(np.array(seq), max_period)


def start_state(A=0.32, e=0.5):
    """The ball's state at t = 0 on the period-1 orbit (closed form)."""
    phi = np.arccos((1 - e) * np.pi * G / ((1 + e) * A * W**2))
    t_i, v_plus = phi / W, G * T / 2
    tau = (-t_i) % T
    return [A * np.sin(W * t_i) + v_plus * tau - G * tau**2 / 2, v_plus - G * tau]


def test_attractor_period_of_sequences():
    k = np.arange(40)[:, None]
    assert attractor_period(np.hstack([np.cos(np.pi * k), k * 0.0]), 8) == 2
    assert attractor_period(np.hstack([np.cos(2 * np.pi * k / 3), k * 0.0 + 1]), 8) == 3
    assert attractor_period(np.hstack([np.cos(2 * np.pi * k / 11), k * 0.0]), 8) == 0  # longer than max_period
    assert attractor_period(np.ones((40, 2)), 8) == 1


def test_period_map_against_the_closed_form_impact_map():
    """Period 1 below the doubling, 2 above it, none found (a longer period or chaos) further on: every
    cell equals the period of the closed-form impact map's attractor (the tolerance 1e-6 of both
    periodicity tests is far above the integration error and far below the attractors' distances)."""
    system = bouncing_ball()
    grid = period_map(system, "A", A_VALUES, "e", E_VALUES, max_period=8, x0=start_state(), workers=2)
    reference = np.array([[reference_period(A, e) for A in A_VALUES] for e in E_VALUES])
    np.testing.assert_array_equal(grid.periods, reference)
    assert {1, 2, 0} <= set(grid.periods.ravel().tolist())  # the map shows the doubling and beyond
    assert grid.failures == ()
    # the doubling lies between the last period-1 and the first period-2 cell of each row (closed form)
    for e, row in zip(E_VALUES, grid.periods):
        a_pd = G / W**2 * np.sqrt((np.pi * (1 - e) / (1 + e)) ** 2 + (2 * (1 + e**2) / (1 + e) ** 2) ** 2)
        ones = [A for A, c in zip(A_VALUES, row) if c == 1]
        assert max(ones) < a_pd
        assert all(A > a_pd for A, c in zip(A_VALUES, row) if c == 2)


def test_period_map_round_trip_and_plot(tmp_path):
    grid = period_map(bouncing_ball(), "A", [0.33, 0.39], "e", [0.5], max_period=4, x0=start_state(), workers=1)
    again = PeriodMap.from_dict(grid.to_dict())
    np.testing.assert_array_equal(again.periods, grid.periods)
    assert (again.parameter_name, again.parameter2_name, again.max_period) == ("A", "e", 4)
    fig = grid.plot()
    assert fig.axes[0].get_xlabel() == "A" and fig.axes[0].get_ylabel() == "e"
    assert grid.save(tmp_path / "map.json").exists()


def test_period_map_refuses_what_it_cannot_count():
    with pytest.raises(ModelError, match="autonomous"):
        from saltation.models import block_on_belt

        period_map(block_on_belt(), "v_dr", [0.5], "k", [1.0])
    with pytest.raises(ModelError, match="must differ"):
        period_map(bouncing_ball(), "A", [0.3], "A", [0.3])
    with pytest.raises(ModelError, match="unknown parameter|no parameter|'nope'"):
        period_map(bouncing_ball(), "A", [0.3], "nope", [0.3])


def test_sweeps_on_a_dask_cluster_match_local_runs():
    """The same chunks on a LocalCluster's workers give the same points as local processes, to the bit.
    (The local runs come first: they fork worker processes, which must not happen while the cluster's
    threads run in this process.)"""
    import distributed  # installed with the test extras (the [distributed] extra for users)

    values = np.linspace(0.32, 0.40, 6)
    local = sweep(bouncing_ball(), "A", values, periods=20, transient=50, x0=start_state(), workers=2, lyapunov=True)
    map_args = (friction_oscillator(), "v_b", [1.0, 1.6, 2.2], "F", [0.4, 0.6])
    grid_local = period_map(*map_args, max_period=4, workers=2)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = sweep(bouncing_ball(), "A", values, periods=20, transient=50, x0=start_state(), workers=2, client=client,
                       lyapunov=True)
        grid_remote = period_map(*map_args, max_period=4, workers=2, client=client)
    np.testing.assert_array_equal(remote.states, local.states)
    np.testing.assert_array_equal(remote.counts, local.counts)
    np.testing.assert_array_equal(remote.largest_exponents, local.largest_exponents)  # (--lyapunov on Dask too)
    assert np.all(np.isfinite(local.largest_exponents))
    np.testing.assert_array_equal(grid_remote.periods, grid_local.periods)
