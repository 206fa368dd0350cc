"""The largest Lyapunov exponent on a chaotic attractor of the impact oscillator, against an independent
implementation with scipy.

The model (saltation.models.impact_oscillator) is ``x'' + 2 zeta x' + x = cos(omega t)`` while ``x < s``, with
the impact ``v -> -r v`` at the stop ``x = s``.

The reference
-------------
:func:`reference_lyapunov` below shares nothing with saltation's engine.  It integrates the state and the
2x2 fundamental matrix (``Phi' = A Phi``, ``A = [[0, 1], [-1, -2 zeta]]``: the field is linear between
impacts) with ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-10, atol 1e-12), stops at the stop with a
terminal event, resets the state and multiplies ``Phi`` by the saltation matrix in closed form, derived here
from eq. (9) of *Fold bifurcations in discontinuous systems*, ``S = g_x + (f+ - g_x f-) h_x / (h_x f-)``:
with ``h = x - s`` (``h_x = (1, 0)``), ``g = (x, -r v)`` (``g_x = diag(1, -r)``), ``f- = (v, a-)`` and
``f+ = (-r v, a+)`` at the impact (``v = v-`` the velocity before it, ``a = -2 zeta v - s + cos(omega t)``),
``h_x f- = v``, ``f+ - g_x f- = (-(1 + r) v, a+ + r a-)`` and ``a+ + r a- = (1 + r) (cos(omega t) - s)``::

    S = [[-r,                              0 ],
         [(1 + r) (cos(omega t) - s) / v, -r ]],      det S = r^2.

A near-grazing impact can begin and end inside one step, where the end points of the step do not see the
sign change of ``x - s``; the reference also watches every maximum of ``x`` (``v`` falling through 0) and,
at one beyond the stop, finds the impact it missed inside that step on the dense output (these low-velocity
impacts, with their large ``S_21``, stretch the most: losing them would bias the exponent).  At saltation's
times (every forcing period, or nearly: see ``runs``) the carried frame is reorthonormalised by QR
(Benettin), and ``log |R_ii|`` summed over the run and divided by its time are the exponents; their accuracy
is the standard error of the estimates of 10 equal blocks, as saltation's.  The closed form of ``S`` is also
checked against the engine's at its impacts.

The chaotic parameters
----------------------
``zeta = 0.05, r = 0.8`` (the defaults), ``omega = 0.6, s = 1.35``, found by scanning ``omega`` and ``s``
(as a fraction of the free amplitude ``1 / sqrt((1 - omega^2)^2 + (2 zeta omega)^2) = 1.556``) with saltation's
exponents over a few hundred periods.  The chaos is robust, not a narrow window: over ``omega`` in
[0.595, 0.605] and ``s`` in [1.30, 1.40] (3000 periods each) the largest exponent stays at 0.029 - 0.041,
30 - 100 accuracies above zero, and from five initial states over 5000 periods it is 0.0342 - 0.0358
(40000 periods: 0.0352 +- 0.0002; scipy over 6000 periods: 0.0350 +- 0.0005).  With ``s > 1`` the force at
the stop, ``cos(omega t) - s``, always pulls away from it: no sticking and no chattering (an accumulation of
impacts), which rule out the chaotic regimes at higher frequency (omega ~ 2.5 - 3, s < 0.2).  About 1.46
impacts a period, the slowest at ``v ~ 0.01 - 0.03``.

What the tolerances promise
---------------------------
* Both implementations start from the same state at the same time (the end of a 200-period transient with
  saltation) and average over the same 2000 forcing periods.  On a chaotic attractor the two trajectories
  separate within a few dozen periods (the exponent is 0.37 per period), so only the time averages compare:
  they must agree within 3 times their combined statistical accuracy ``sqrt(acc_saltation^2 + acc_scipy^2)``
  (a 3-sigma test of equal means; the accuracies, from 10 blocks, are 2 - 4% of the exponent each).  A wrong
  saltation matrix is far outside it: the reference without the factor ``1 + r`` of ``S_21`` gives -0.018
  (38 combined accuracies off), with its sign flipped -0.056, and without ``S_21`` both exponents would be
  ``-zeta + (N / T) ln r = -0.08``.
* Chaos: the largest exponent of each is positive by more than 3 of its accuracies.
* The sum of the exponents is exact, not statistical: ``det Phi`` grows like ``exp(trace(A) t) = exp(-2 zeta t)``
  between impacts (Liouville) and by ``det S = r^2`` at each, and QR with an orthonormal frame keeps
  ``|det|``, so ``sum = -2 zeta + (N / T) ln(r^2)`` for ``N`` impacts in time ``T``.  It is checked to 1e-8
  per unit time: the integration error (rtol 1e-10) leaves about 1e-12, while one impact too many or too few
  (or a saltation matrix of the wrong determinant at one impact) shifts the sum by ``2 |ln r| / T = 2e-5``.
  The reference counts its impacts; saltation does not report its count, so its sum must be the closed form of
  some whole number of impacts in each block, and its impact rate must agree with the reference's within
  3 combined standard errors (over the blocks).

The comparison is deterministic on one platform; another platform's rounding gives another (equally valid)
draw of the chaotic trajectories, for which a 3-sigma test fails with a probability of about 1%.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from saltation import Flow, lyapunov_exponents
from saltation.models import impact_oscillator

pytestmark = pytest.mark.slow  # long runs on a chaotic attractor

ZETA, OMEGA, R, S = 0.05, 0.6, 0.8, 1.35
VALUES = {"zeta": ZETA, "omega": OMEGA, "r": R, "s": S}
PERIOD = 2.0 * math.pi / OMEGA
TRANSIENT_PERIODS = 200
PERIODS = 2000
BLOCKS = 10
RTOL, ATOL = 1e-10, 1e-12
#: The tolerance of the sum of the exponents (per unit time): far above the integration error (~1e-12),
#: far below one impact's share 2 |ln r| / T (~2e-5).
SUM_TOL = 1e-8


def saltation_matrix(t: float, v_minus: float) -> np.ndarray:
    """Eq. (9) for the impact at time ``t`` with velocity ``v_minus`` before it (derived in the docstring)."""
    return np.array([[-R, 0.0], [(1.0 + R) * (math.cos(OMEGA * t) - S) / v_minus, -R]])


def closed_form_sum(impacts: float, time: float) -> float:
    """The sum of the exponents: ``trace(A) + (impacts / time) ln det S``."""
    return -2.0 * ZETA + impacts / time * math.log(R**2)


@dataclass
class Reference:
    """The reference's exponents, as saltation's LyapunovExponents, with its impacts."""

    exponents: np.ndarray  # descending
    accuracy: np.ndarray  # standard error over the blocks
    block_exponents: np.ndarray  # (blocks, 2), columns in the order of `exponents`
    block_impacts: np.ndarray  # impacts in each block
    caught_grazing: int  # impacts found at a maximum beyond the stop (missed by the step's end points)
    slowest_impact: float  # the smallest impact velocity


def _field(t: float, y: np.ndarray) -> np.ndarray:
    """The state and the fundamental matrix (row-major): ``Phi' = [[0, 1], [-1, -2 zeta]] Phi``."""
    x, v, p11, p12, p21, p22 = y
    return np.array([v, -2.0 * ZETA * v - x + math.cos(OMEGA * t),
                     p21, p22, -p11 - 2.0 * ZETA * p21, -p12 - 2.0 * ZETA * p22])


def _stop(t: float, y: np.ndarray) -> float:
    return y[0] - S


_stop.terminal = True
_stop.direction = 1.0


def _maximum(t: float, y: np.ndarray) -> float:
    return y[1]


_maximum.direction = -1.0


def _first_impact(sol) -> tuple[float, np.ndarray, bool] | None:
    """The first impact of a solve_ivp run: (time, state with Phi just before it, caught at a maximum), or None."""
    hit = (sol.t_events[0][0], sol.y_events[0][0], False) if sol.t_events[0].size else None
    for tm, ym in zip(sol.t_events[1], sol.y_events[1]):
        if hit is not None and tm >= hit[0]:
            break
        if ym[0] > S:  # a maximum beyond the stop: the impact was inside this step, unseen at its end points
            ts = sol.sol.ts
            start = ts[max(int(np.searchsorted(ts, tm)) - 1, 0)]
            assert sol.sol(start)[0] < S
            th = brentq(lambda tt: sol.sol(tt)[0] - S, start, tm, xtol=1e-14, rtol=4 * np.finfo(float).eps)
            return th, sol.sol(th), True
    return hit


def reference_lyapunov(x0: np.ndarray, t0: float, time: float, blocks: int, per_block: int) -> Reference:
    """Benettin's method with scipy: reset and saltation matrix at every impact, QR every ``time / (blocks *
    per_block)`` (``blocks`` equal blocks of ``per_block`` intervals)."""
    interval = time / (blocks * per_block)
    y = np.concatenate((np.asarray(x0, dtype=float), [1.0, 0.0, 0.0, 1.0]))
    t = float(t0)
    logs = np.zeros((blocks, 2))
    impacts = np.zeros(blocks, dtype=int)
    caught, slowest = 0, math.inf
    for k in range(blocks * per_block):
        t_end = t0 + (k + 1) * interval
        while True:
            sol = solve_ivp(_field, (t, t_end), y, method="DOP853", rtol=RTOL, atol=ATOL,
                            events=(_stop, _maximum), dense_output=True)
            assert sol.success, sol.message
            impact = _first_impact(sol)
            if impact is None:
                y, t = sol.y[:, -1], t_end
                break
            t, y_minus, at_maximum = impact
            v_minus = y_minus[1]
            assert v_minus > 0.0
            phi = saltation_matrix(t, v_minus) @ y_minus[2:].reshape(2, 2)
            y = np.concatenate(([S, -R * v_minus], phi.ravel()))
            impacts[k // per_block] += 1
            caught += at_maximum
            slowest = min(slowest, v_minus)
        q, r = np.linalg.qr(y[2:].reshape(2, 2))
        logs[k // per_block] += np.log(np.abs(np.diag(r)))
        q = q * np.where(np.diag(r) < 0.0, -1.0, 1.0)
        y = np.concatenate((y[:2], q.ravel()))
    block_exponents = logs / (time / blocks)
    totals = logs.sum(axis=0) / time
    order = np.argsort(-totals)
    block_exponents = block_exponents[:, order]
    accuracy = block_exponents.std(axis=0, ddof=1) / math.sqrt(blocks)
    return Reference(totals[order], accuracy, block_exponents, impacts, caught, slowest)


@pytest.fixture(scope="module")
def flow() -> Flow:
    return Flow(impact_oscillator())


@pytest.fixture(scope="module")
def runs(flow):
    """Saltation's and the reference's exponents from the same state, at the same time, over the same time."""
    transient = flow.run([0.0, 0.0], 0.0, TRANSIENT_PERIODS * PERIOD, flow.parameters(VALUES))
    x0, t0 = np.array(transient.x1), transient.t1
    time = PERIODS * PERIOD
    ours = lyapunov_exponents(flow, x0, parameters=VALUES, time=time, t0=t0, blocks=BLOCKS)
    # QR every forcing period, give or take: saltation counts its intervals per block as ceil(time / blocks /
    # period), which rounding can make one more than PERIODS / BLOCKS; the reference takes the same intervals
    per_block = round(time / BLOCKS / ours.interval)
    assert ours.interval == pytest.approx(time / (BLOCKS * per_block), rel=1e-12)
    assert abs(ours.interval - PERIOD) <= PERIOD / (PERIODS // BLOCKS)
    return ours, reference_lyapunov(x0, t0, time, BLOCKS, per_block)


def test_the_closed_form_saltation_matrix_is_the_engines(flow):
    run = flow.run([0.0, 0.0], 0.0, 30 * PERIOD, flow.parameters(VALUES), variational=True)
    assert len(run.events) > 20
    for event in run.events:
        assert event.x_minus[0] == pytest.approx(S, abs=1e-9)
        np.testing.assert_allclose(event.saltation, saltation_matrix(event.t, event.x_minus[1]), rtol=1e-9, atol=1e-12)


def test_the_attractor_is_chaotic(runs):
    ours, ref = runs
    assert ours.exponents[0] > 3.0 * ours.accuracy[0]
    assert ref.exponents[0] > 3.0 * ref.accuracy[0]
    # the comparison below means something: the accuracies are small against the exponent
    assert 0.0 < math.hypot(ours.accuracy[0], ref.accuracy[0]) < 0.2 * ours.exponents[0]


def test_the_exponents_agree_within_their_statistics(runs):
    ours, ref = runs
    for i in range(2):
        combined = math.hypot(ours.accuracy[i], ref.accuracy[i])
        assert abs(ours.exponents[i] - ref.exponents[i]) <= 3.0 * combined, (i, ours, ref.exponents, ref.accuracy)


def test_the_sum_of_the_exponents_is_the_closed_form(runs):
    ours, ref = runs
    time = PERIODS * PERIOD
    # the reference: with the impacts it counted
    assert abs(ref.exponents.sum() - closed_form_sum(ref.block_impacts.sum(), time)) <= SUM_TOL
    block_time = time / BLOCKS
    for b in range(BLOCKS):
        assert abs(ref.block_exponents[b].sum() - closed_form_sum(ref.block_impacts[b], block_time)) <= SUM_TOL * BLOCKS
    # saltation: a whole number of impacts in each block (SUM_TOL is far below half an impact's share)
    implied = (ours.block_exponents.sum(axis=1) + 2.0 * ZETA) * block_time / math.log(R**2)
    counts = np.round(implied)
    for b in range(BLOCKS):
        assert counts[b] > 0
        # (plus the rounding the run itself bounds: past an impact that nearly grazes, its saltation matrix's
        # 1/v puts the contracted direction's digits at eps |R_11| / |R_nn|, whose size depends on the CPU)
        assert (abs(ours.block_exponents[b].sum() - closed_form_sum(counts[b], block_time))
                <= SUM_TOL * BLOCKS + ours.block_sum_rounding[b])
    assert abs(ours.exponents.sum() - closed_form_sum(counts.sum(), time)) <= SUM_TOL + ours.block_sum_rounding.mean()
    # and the two impact rates agree within their statistics
    rates = [counts / block_time, ref.block_impacts / block_time]
    errors = [np.std(r, ddof=1) / math.sqrt(BLOCKS) for r in rates]
    assert abs(rates[0].mean() - rates[1].mean()) <= 3.0 * math.hypot(*errors)
