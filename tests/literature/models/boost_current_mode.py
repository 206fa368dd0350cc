"""Peak-current-mode DC-DC boost converter, its clock a time-triggered transition of a forced model.

Deane (IEEE Trans. Circuits Syst. I 39, 1992); Banerjee and Chakrabarty (IEEE Trans. Power Electron. 13, 1998).
Time in clock periods; a clock pulse at every integer t (the surface ``sin(2 pi t)`` rising) turns the switch
ON unless the current is above ``I_ref``; the comparator turns it OFF when the current reaches ``I_ref``;
the diode blocks when the current falls to zero while OFF (discontinuous conduction).  The switch's state is
the mode: ``on`` and ``off`` share states, so an orbit starts in a named mode (``mode0``).

Reference: ``tests/boost_reference.py``, the stroboscopic map in closed form (matrix exponentials, the
switching instant in closed form), its fixed point by Newton and its period doubling by ``brentq``.
"""

from __future__ import annotations

import boost_reference as ref
import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, LocusStep, LyapunovStep, Orbit, SweepStep

from saltation import Crossing, Mode, PiecewiseSystem, Transition

RISING, FALLING = Crossing.RISING, Crossing.FALLING


def boost(**overrides) -> PiecewiseSystem:
    on = ["T*E/L", "-T*v/(R*C)"]
    off = ["T*(E - v)/L", "T*(i - v/R)/C"]
    dcm = ["0", "-T*v/(R*C)"]
    return PiecewiseSystem(
        name="literature_boost_current_mode",
        states=["i", "v"],
        parameters=ref.DEFAULTS | overrides,
        modes=[
            Mode("on", on, domain=["i - I_ref < 0"]),
            Mode("dcm", dcm, domain=["i <= 0"]),
            Mode("off", off),
        ],
        surfaces={"peak": "i - I_ref", "clock": "sin(2*pi*t)", "zero": "i"},
        transitions=[
            Transition("on", "peak", RISING, "off"),
            Transition("off", "clock", RISING, "on", guard=["i - I_ref < 0"]),
            Transition("dcm", "clock", RISING, "on"),
            Transition("off", "zero", FALLING, "dcm"),
        ],
        period="1",
    )


def _period_doubling() -> list[Expected]:
    # brentq to 4 eps on the closed form; the located point's own accuracy is added by the test
    return [Expected(("period_doubling",), ref.period_doubling(dict(ref.DEFAULTS)), 1e-9)]


def _period_doubling_in_C(C: float) -> float:
    return ref.period_doubling(dict(ref.DEFAULTS, C=C), 1.45, 2.0)


def _strobe_any(q: dict, x: np.ndarray, jacobian: bool = False):
    """The closed-form map (and its derivative) also where the ON phase lasts the whole period (a skipped
    cycle: the ON flow, ``i + T E / L`` and ``v exp(-T / (R C))``) or none of it (the current at ``I_ref``
    at the clock: the OFF flow all period)."""
    E, L, C, R, T, I_ref = (q[k] for k in ("E", "L", "C", "R", "T", "I_ref"))
    t_on = L * (I_ref - x[0]) / E
    if t_on >= T:
        decay = np.exp(-T / (R * C))
        y, J = np.array([x[0] + T * E / L, x[1] * decay]), np.diag([1.0, decay])
    elif t_on <= 0.0:  # the current at I_ref or above at the clock: the switch stays OFF all period
        F = ref._off_flow(q, T)
        y, J = (F @ np.array([x[0], x[1], 1.0]))[:2], F[:2, :2]
    else:
        y, J = ref.strobe(q, x)
    return (y, J) if jacobian else y


def _sweep_follows_the_map(result) -> None:
    """Each section state is the closed-form map's image of the one before (where the map applies: an ON
    phase shorter than the period); the first values from rest have skipped cycles."""
    q = dict(ref.DEFAULTS, I_ref=3.0)
    x = np.asarray(result.states, dtype=float)
    assert len(x) == 200
    assert np.all((x[:, 0] > 0.0) & (x[:, 0] < 3.0)), "a clock instant with the current outside (0, I_ref)"
    checked = 0
    for a, b in zip(x[:-1], x[1:]):
        y = _strobe_any(q, a)
        # one period of the map amplifies the sample's rounding by at most |DP| ~ 10
        np.testing.assert_allclose(y, b, rtol=1e-7, atol=1e-7)
        checked += 1
    assert checked == 199


def _lyapunov_against_the_map(exponents: np.ndarray) -> None:
    """The largest exponent per clock period from the closed-form map's Jacobians along its own orbit (QR)."""
    q = dict(ref.DEFAULTS, I_ref=3.0)
    x = np.array([2.0, 18.0])
    for _ in range(500):
        x = _strobe_any(q, x)
    Q, total, n = np.eye(2), np.zeros(2), 4000
    for _ in range(n):
        x, J = _strobe_any(q, x, jacobian=True)
        Q, R = np.linalg.qr(J @ Q)
        total += np.log(np.abs(np.diag(R)))
    reference = np.sort(total / n)[::-1]
    assert reference[0] > 0.05, "the reference's motion is not chaotic at I_ref = 3"
    # two finite-time averages over different stretches of a chaotic motion: a few percent apart
    assert abs(exponents[0] - reference[0]) <= 0.05 * abs(reference[0]) + 0.01


CASE = LiteratureCase(
    name="boost_current_mode",
    field="power electronics",
    source="Deane 1992; Banerjee and Chakrabarty 1998 (peak-current-mode boost converter)",
    model=boost,
    orbit=Orbit(
        parameters=dict(ref.DEFAULTS),
        guess=[1.1, 17.4],
        mode0="off",
        multipliers=lambda p: np.linalg.eigvals(ref.fixed_point(dict(p))[1]),
        state=lambda p: ref.fixed_point(dict(p))[0],
    ),
    branch=BranchStep("I_ref", (1.2, 1.9), _period_doubling, ds_max=0.02),
    locus=LocusStep("period_doubling", "C", (10e-6, 14e-6), _period_doubling_in_C, tol=1e-7),
    sweep=SweepStep("I_ref", [3.0], _sweep_follows_the_map, options={"x0": [0.0, 0.0], "mode0": "on"}),
    lyapunov=LyapunovStep(dict(ref.DEFAULTS, I_ref=3.0), [2.0, 18.0], time=2000.0, transient=200.0,
                          check=_lyapunov_against_the_map, mode0="on"),
)
