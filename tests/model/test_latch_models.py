"""A model whose mode is memory: a peak-current-mode boost converter with an SR latch, written as a user writes it
from the docs (a phase state ``tau`` for the clock, the latch as a logic state ``q`` that no mode moves).

The comparator's transition resets ``q`` only: a switch, not an impact.  After it, the switch-off field may turn
the current back across ``I_ref`` (the output voltage above the input), and the motion goes on in ``off``: no
sliding motion is called for (``off`` does not watch the comparator's surface).

Reference: every mode is affine, so the stroboscopic map at the clock instants is closed form: the ramp
``i' = T E / L`` to ``I_ref`` (the instant by division), ``v`` decaying, then the ``off`` flow by a matrix
exponential to the next clock instant.  Its fixed point and the eigenvalues of its Jacobian (central differences,
step 1e-6, error ~1e-10) are the orbit's; the autonomous orbit adds the trivial multiplier 1 (along the flow) and 0
(``q`` is reset to a fixed value each period).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import fsolve

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit

RISING, FALLING = Crossing.RISING, Crossing.FALLING
E, L, C, R, T = 10.0, 1e-3, 12e-6, 20.0, 100e-6


def boost() -> PiecewiseSystem:
    on = ["T*E/L", "-T*v/(R*C)", "1", "0"]
    off = ["T*(E - v)/L", "T*(i - v/R)/C", "1", "0"]
    dcm = ["0", "-T*v/(R*C)", "1", "0"]
    return PiecewiseSystem(
        name="test_boost_latch",
        states=["i", "v", "tau", "q"],
        parameters={"E": E, "L": L, "C": C, "R": R, "T": T, "I_ref": 1.5},
        modes=[Mode("on", on, domain=["q - 0.5 > 0"]), Mode("dcm", dcm, domain=["i <= 0"]), Mode("off", off)],
        surfaces={"peak": "i - I_ref", "clock": "tau - 1", "zero": "i"},
        transitions=[
            Transition("on", "peak", RISING, "off", reset=["i", "v", "tau", "0"]),
            Transition("off", "clock", RISING, "on", reset=["i", "v", "0", "1"], guard=["i - I_ref < 0"]),
            Transition("off", "clock", RISING, "off", reset=["i", "v", "0", "0"], guard=["i - I_ref >= 0"]),
            Transition("on", "clock", RISING, "on", reset=["i", "v", "0", "1"]),
            Transition("dcm", "clock", RISING, "on", reset=["i", "v", "0", "1"]),
            Transition("off", "zero", FALLING, "dcm"),
        ],
    )


def stroboscopic(z: np.ndarray, i_ref: float) -> np.ndarray:
    """``(i, v)`` at the next clock instant from ``(i, v)`` at one (switch set, the ramp reaching ``I_ref``)."""
    i0, v0 = z
    t1 = (i_ref - i0) / (T * E / L)
    assert 0.0 < t1 < 1.0
    A = T * np.array([[0.0, -1.0 / L], [1.0 / C, -1.0 / (R * C)]])
    shift = np.linalg.solve(A, T * np.array([E / L, 0.0]))
    return expm(A * (1.0 - t1)) @ (np.array([i_ref, v0 * math.exp(-T * t1 / (R * C))]) + shift) - shift


def reference_multipliers(i_ref: float, guess) -> np.ndarray:
    z = fsolve(lambda z: stroboscopic(z, i_ref) - z, guess, xtol=1e-14)
    h = 1e-6
    J = np.column_stack([(stroboscopic(z + h * e, i_ref) - stroboscopic(z - h * e, i_ref)) / (2 * h) for e in np.eye(2)])
    return np.sort(np.linalg.eigvals(J).real)


@pytest.fixture(scope="module")
def flow() -> Flow:
    return Flow(boost())


def test_a_reset_of_a_logic_state_is_a_switch(flow):
    assert boost().logic_states == (3,)
    # the comparator's reset moves q only (a switch); the clock's move tau back off their surface (impacts that
    # leave it: nothing lands on the surface)
    assert boost().impacts == (False, True, True, True, True, False)
    # from rest: the current keeps rising after the switch opens (v < E), every start-up; bounded by the latch
    traj = flow.run([0.0, 0.0, 0.0, 0.0], 0.0, 60.0, flow.parameters({"I_ref": 1.8}))
    # after the switch opens, i' = T (E - v) / L <= T E / L = 1 per clock period, until the next pulse at most
    assert traj.x_max[0] <= 1.8 + T * E / L
    assert any(e.surface == "peak" for e in traj.events)


@pytest.mark.parametrize(("i_ref", "guess"), [(1.5, (1.33, 16.4, 0.69, 0.0)), (1.95, (1.68, 19.24, 0.8, 0.0))])
def test_the_converter_orbit_against_its_stroboscopic_map(flow, i_ref, guess):
    orbit = find_periodic_orbit(flow, guess, parameters={"I_ref": i_ref}, period=1.0)
    mu = np.sort(orbit.multipliers.real)
    assert np.max(np.abs(orbit.multipliers.imag)) == 0.0
    expected = np.sort(np.concatenate([reference_multipliers(i_ref, (1.2, 17.0)), [0.0, 1.0]]))
    np.testing.assert_allclose(mu, expected, rtol=0, atol=1e-8)  # the reference's differences: ~1e-10
    assert orbit.period == pytest.approx(1.0, abs=1e-10)  # the clock's period, to Newton's tolerance 1e-10


def test_a_relay_output_that_the_field_reads_is_no_logic_state():
    """A relay with hysteresis written as one mode, its output ``u`` a state: ``x' = -x + u``, ``u`` set to -1 at
    ``x = d`` (rising) and to +1 at ``x = -d`` (falling).  ``u`` enters the field, so its resets are impacts (the
    state stays on the surface and the new field takes it back): closed form, the switches ``ln((1 + d) / (1 - d))``
    apart (``x = u - (u + d) exp(-t)`` from ``x = -d`` with ``u = 1``)."""
    d = 0.5
    relay = PiecewiseSystem(
        "test_hysteresis_relay", states=["x", "u"], parameters={"d": d},
        modes=[Mode("m", ["-x + u", "0"])], surfaces={"up": "x - d", "down": "x + d"},
        transitions=[Transition("m", "up", RISING, "m", reset=["x", "-1"]),
                     Transition("m", "down", FALLING, "m", reset=["x", "1"])],
    )
    assert relay.logic_states == () and relay.impacts == (True, True)
    traj = Flow(relay).run([-d, 1.0], 0.0, 10.0, relay.parameter_vector())
    times = np.array([e.t for e in traj.events])
    half = math.log((1 + d) / (1 - d))
    assert len(times) == int(10.0 // half)
    # event location to ~1e-12 per switch, accumulated over a few switches at rtol 1e-10
    np.testing.assert_allclose(times, half * np.arange(1, len(times) + 1), rtol=0, atol=1e-9)
