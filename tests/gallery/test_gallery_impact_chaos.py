"""The gallery page "Impact oscillator: the route to chaos" (docs/gallery/impact_chaos.md): the largest Lyapunov
exponents of its period map against independent references.

The figure (``docs/hooks/gallery_chaos.py``) is a period map of ``saltation.models.impact_oscillator`` at
``s = 1.3`` over ``(omega, r)`` with ``lyapunov=True``: each cell starts from rest at ``t = 0`` (``start="own"``),
runs 200 forcing periods of transient, and reports the attractor's period (up to 8) and its largest exponent
over the next 64 periods.  The cells are independent, so a cell recomputed alone (a 1 x 1 map with the figure's
settings) is the figure's cell (checked to the bit below): the tests recompute a few cells, not the map.

References
----------
* A periodic cell: its attractor is found by shooting (``saltation.find_periodic_orbit`` for period 1, a
  ``ShootingProblem`` over ``k`` forcing periods for period ``k``: Newton on the period map, not a simulation
  over many periods), and its largest exponent is ``ln|mu_max| / (k T)`` from the Floquet multipliers.  At
  ``omega = 0.66, r = 0.8`` the multipliers are a complex pair, so also in closed form: ``|mu|^2 = det M`` and
  ``det M = exp(-2 zeta T) r^(2N)`` for ``N`` impacts per period (Liouville's formula between impacts, ``det S =
  r^2`` at each; see tests/orbits/test_lyapunov_chaos.py), hence ``ln|mu| / T = -zeta + (N / T) ln r``.
* A chaotic cell: the same run continued for 2000 more periods.

Tolerances
----------
The map's exponent is a time average over ``tau = 64 T``; its ``accuracy`` (standard error over 10 blocks) is
not in the map, so each test reruns ``lyapunov_exponents`` from rest with the map's settings and checks that it
gives the map's number exactly, then reads the accuracy off it.  On a periodic orbit the average also has a bias
of order ``1 / tau`` from the frame it starts with: for a monodromy ``M = V D V^-1`` the first frame vector
grows like ``|mu_max|^k`` times a factor between ``1 / kappa(V)`` and ``kappa(V)`` (for a complex pair exactly,
for a real pair once the subdominant part has died out, if the frame vector has an order-one component along the
leading direction), so the test allows ``accuracy + ln kappa(V) / tau``, ``kappa`` the condition number of the
eigenvectors.  Measured: at most a third of that (the largest difference 2.3e-3, at omega = 0.66 with an
accuracy of 4.4e-3).
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

import saltation
from saltation import Flow, ShootingProblem, find_periodic_orbit, lyapunov_exponents
from saltation.apps.sweeps import PeriodMap, SweepResult
from saltation.models.impact_oscillator import DEFAULTS

pytestmark = pytest.mark.slow  # computes a gallery diagram

HOOK = Path(__file__).parents[2] / "docs" / "hooks" / "gallery_chaos.py"


def _load_figure_module():
    spec = importlib.util.spec_from_file_location("gallery_chaos", HOOK)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


G = _load_figure_module()
OMEGA, R = G.grid(G.OMEGA), G.grid(G.R)
TRANSIENT, PERIODS = G.MAP_SETTINGS["transient"], G.MAP_SETTINGS["periods"]
#: The continuation of a run, for the long averages.
LONG = 2000


@pytest.fixture(scope="module")
def flow() -> Flow:
    return Flow(G.system())


def cell(omega: float, r: float) -> tuple[float, float]:
    """The grid point of the figure's map nearest to ``(omega, r)``."""
    return float(OMEGA[np.argmin(np.abs(OMEGA - omega))]), float(R[np.argmin(np.abs(R - r))])


def map_cell(flow: Flow, omega: float, r: float):
    """The map's period and exponent in one cell (a 1 x 1 map with the figure's settings), and the same run by
    ``lyapunov_exponents`` (for its accuracy and its end state), checked to give the map's number."""
    pmap = G.chaos_map([omega], [r])
    period, largest = int(pmap.periods[0, 0]), float(pmap.largest_exponents[0, 0])
    T = 2 * math.pi / omega
    run = lyapunov_exponents(flow, G.MAP_SETTINGS["x0"], parameters={"omega": omega, "r": r}, time=PERIODS * T,
                             transient=TRANSIENT * T, interval=T, blocks=10)
    assert run.largest == pytest.approx(largest, rel=1e-12, abs=1e-15)  # the map's own run
    return period, largest, run


# (omega, r, the period the map reports): the period-1 orbit at the top of the route, the period-2 orbit after
# the first doublings, the period-4 window inside the chaotic band, the period-5 window below it
PERIODIC = [(0.660, 0.80, 1), (0.633, 0.80, 2), (0.570, 0.80, 4), (0.546, 0.80, 5)]


@pytest.mark.parametrize("omega, r, period", PERIODIC, ids=[f"period {k} at omega={w}" for w, _, k in PERIODIC])
def test_periodic_cell_exponent_is_the_floquet_exponent(flow, omega, r, period):
    omega, r = cell(omega, r)
    found, largest, run = map_cell(flow, omega, r)
    assert found == period
    T = 2 * math.pi / omega
    p = {"omega": omega, "r": r}
    guess = flow.run(G.MAP_SETTINGS["x0"], 0.0, TRANSIENT * T, flow.parameters(p)).x1  # where the map's cell samples
    if period == 1:
        orbit = find_periodic_orbit(flow, guess, parameters=p)
    else:
        problem = ShootingProblem(flow, p, periods=period)
        orbit = problem.solve(problem.pack(guess))
    assert orbit.converged
    assert np.max(np.abs(orbit.state0 - guess)) < 1e-6  # the cell's attractor, not another orbit
    mu = np.abs(orbit.multipliers)
    assert np.all(mu < 1.0)
    floquet = math.log(mu.max()) / (period * T)
    kappa = np.linalg.cond(np.linalg.eig(orbit.monodromy)[1])
    bias = math.log(kappa) / (PERIODS * T)
    assert abs(largest - floquet) <= run.accuracy[0] + bias
    # the same run continued: the bias and the spread shrink like 1 / time, the average stays on ln|mu| / (k T)
    long = lyapunov_exponents(flow, run.state, parameters=p, time=LONG * T, t0=(TRANSIENT + PERIODS) * T,
                              interval=T, blocks=10)
    assert abs(long.largest - floquet) <= long.accuracy[0] + math.log(kappa) / (LONG * T)


def test_period_one_exponent_in_closed_form(flow):
    """A complex pair: ln|mu| / T = -zeta + (N / T) ln r, N the impacts per period (two here)."""
    omega, r = cell(0.66, 0.80)
    T = 2 * math.pi / omega
    orbit = find_periodic_orbit(flow, parameters={"omega": omega, "r": r})
    assert abs(orbit.multipliers[0].imag) > 0.1
    impacts = len(orbit.trajectory.events)
    assert impacts == 2
    closed = -DEFAULTS["zeta"] + impacts / T * math.log(r)
    assert math.log(np.abs(orbit.multipliers).max()) / T == pytest.approx(closed, abs=1e-9)
    _, largest, run = map_cell(flow, omega, r)
    kappa = np.linalg.cond(np.linalg.eig(orbit.monodromy)[1])
    assert abs(largest - closed) <= run.accuracy[0] + math.log(kappa) / (PERIODS * T)


def test_cell_without_period_is_chaotic(flow):
    """In the chaotic band on r = 0.8: no period up to 8, and a positive exponent beyond 5 accuracies; continued
    for 2000 periods, beyond 10, and within 3 combined accuracies of the map's (a statistical test of equal
    means; the accuracies are standard errors)."""
    omega, r = cell(0.594, 0.80)
    period, largest, run = map_cell(flow, omega, r)
    assert period == 0
    assert largest > 5 * run.accuracy[0] > 0
    T = 2 * math.pi / omega
    long = lyapunov_exponents(flow, run.state, parameters={"omega": omega, "r": r}, time=LONG * T,
                              t0=(TRANSIENT + PERIODS) * T, interval=T, blocks=10)
    assert long.largest > 10 * long.accuracy[0] > 0
    assert abs(long.largest - largest) <= 3 * math.hypot(long.accuracy[0], run.accuracy[0])


def test_figure_draws_what_period_map_and_sweep_return(monkeypatch):
    """The figure's colour maps, diagram and exponent curve are the arrays period_map and sweep return (on small
    grids here); the map's cells are independent (a cell alone gives the same numbers to the bit); the page's
    special points are the period doublings of the continuations, in order down the swept line."""
    returned: dict[str, object] = {}
    period_map, sweep = saltation.period_map, saltation.sweep

    def spy_map(*args, **kwargs):
        returned["map"] = period_map(*args, **kwargs)
        return returned["map"]

    def spy_sweep(*args, **kwargs):
        returned["sweep"] = sweep(*args, **kwargs)
        return returned["sweep"]

    monkeypatch.setattr(saltation, "period_map", spy_map)
    monkeypatch.setattr(saltation, "sweep", spy_sweep)
    omega, r = OMEGA[[18, 31, 40]], R[[0, 24]]
    fig, points = G.figure_impact_chaos(omega, r, G.grid(G.SWEEP_OMEGA)[[0, 40, 100]])
    pmap, swept = returned["map"], returned["sweep"]
    assert isinstance(pmap, PeriodMap) and isinstance(swept, SweepResult)
    assert pmap.largest_exponents is not None and swept.largest_exponents is not None

    def drawn(gid):
        (artist,) = fig.findobj(lambda a: a.get_gid() == gid)
        return artist

    np.testing.assert_array_equal(np.asarray(drawn("exponent_map").get_array()), pmap.largest_exponents)
    np.testing.assert_array_equal(np.asarray(drawn("period_map").get_array()), pmap.periods)
    limit = np.nanmax(np.abs(pmap.largest_exponents))
    assert drawn("exponent_map").norm.vmin == -limit and drawn("exponent_map").norm.vmax == limit  # 0 is white
    np.testing.assert_array_equal(drawn("diagram").get_offsets(), np.column_stack(swept.points("x")))
    np.testing.assert_array_equal(drawn("largest_exponent").get_ydata(), swept.largest_exponents)
    np.testing.assert_array_equal(swept.values, G.grid(G.SWEEP_OMEGA)[[0, 40, 100]])
    assert swept.settings["x0"] == [0.0, 0.0] and swept.start.value == "previous"

    alone = G.chaos_map(omega[[1]], r[[1]], workers=1)
    assert alone.periods[0, 0] == pmap.periods[1, 1]
    assert alone.largest_exponents[0, 0] == pmap.largest_exponents[1, 1]

    # period 1 -> 2 -> 4 on the first two branches, then the period-2 orbit below the grazing doubles in turn; the
    # period-2 branch may end at the grazing where its fourth impact appears (an impact: never a discontinuous flip)
    doublings = [p for p in points if p["kind"] == "period_doubling"]
    assert len(doublings) == 3
    assert {p["kind"] for p in points} <= {"period_doubling", "grazing"}
    assert all(p["parameter"] == "omega" and min(G.BRANCH) < p["value"] < max(G.BRANCH) for p in points)
    assert doublings[0]["value"] > doublings[1]["value"] > doublings[2]["value"]
