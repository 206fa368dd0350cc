"""The DC-DC buck converter under voltage-mode (ramp, PWM) control.

A switch chops the input voltage ``E`` feeding an inductor ``L`` and a capacitor
``C`` in parallel with the load ``R``; a freewheeling diode carries the inductor
current while the switch is open (continuous conduction: the current stays
positive, so the pair is one ideal change-over switch ``s``)::

    L di/dt = s E - v,        C dv/dt = i - v/R,        s in {0, 1}.

The output voltage is compared with a sawtooth ramp of period ``T``
(Hamill, Deane and Jefferies, IEEE Trans. Power Electron. 7, 1992; Fossas and
Olivar, IEEE Trans. Circuits Syst. I 43, 1996; di Bernardo, Garofalo, Glielmo
and Vasca, IEEE Trans. Circuits Syst. I 45, 1998): the control voltage
``v_con = a (v - V_ref)`` against the ramp ``V_r(t) = V_L + (V_U - V_L) (t mod T) / T``,
with the comparator's convention in these papers (the one under which the loop
regulates, for this sign of ``v_con``)

    s = 1 (switch ON)  while  v_con < V_r(t),        s = 0 (OFF) while v_con > V_r(t),

so that a higher output voltage shortens the ON time.  There is no latch: the
comparator alone decides, and a period may hold several switchings.  Within a
period the rising ramp turns the switch ON where it overtakes ``v_con``
(surface ``ramp``), and its reset to ``V_L`` at ``t = kT`` turns it OFF again
(surface ``clock``) unless ``v_con`` lies below ``V_L`` (duty cycle 1).  The
defaults are those of Fossas and Olivar and di Bernardo et al.: ``R = 22 ohm,
L = 20 mH, C = 47 uF, V_ref = 11.3 V, a = 8.4, V_L = 3.8 V, V_U = 8.2 V,
T = 400 us``, with the input voltage ``E`` the bifurcation parameter.  The
period-1 orbit (OFF, then ON from the phase ``d``, about 0.4 at ``E = 20 V``)
loses stability by a smooth period doubling at ``E = 24.51657 V``, the route to
the chaos these papers describe.  Below ``E = V_ref + V_L / a = 11.7524 V`` the
switch stays ON (duty cycle 1) and the period-1 orbit is the ON mode's
equilibrium ``(E / R, E)``: at that value the OFF interval shrinks to zero, a
border collision of the ON switching with the ramp's reset, where the
multipliers jump without leaving the unit circle.

Time is measured in units of the ramp period ``T`` (``t' = t / T``), and the
sawtooth is carried by a state: the phase ``tau = (t mod T) / T`` with
``tau' = 1``, reset to 0 on the surface ``tau = 1``.  The model is therefore
autonomous with the states ``(i, v, tau)`` (amperes, volts, periods): its orbits
have period 1 (or a multiple), one Floquet multiplier 1 belongs to the phase
``tau``, and the others are those of the stroboscopic map of the converter.
Both modes are affine, so the integrator steps with their exact flow.
Forward time only: the ramp's reset forgets the phase.
"""

from __future__ import annotations

import functools

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .shipped import ShippedModel

DEFAULTS = {
    "R": 22.0,
    "L": 20e-3,
    "C": 47e-6,
    "V_ref": 11.3,
    "a": 8.4,
    "V_L": 3.8,
    "V_U": 8.2,
    "T": 400e-6,
    "E": 20.0,
}

#: v_con - V_r: negative while the switch is ON
RAMP = "a*(v - V_ref) - V_L - (V_U - V_L)*tau"
#: the same just after the ramp's reset (tau = 0)
AFTER_RESET = "a*(v - V_ref) - V_L"


@functools.lru_cache(maxsize=64)
def buck_converter(**overrides: float) -> PiecewiseSystem:
    """The buck converter; keyword arguments override ``R, L, C, V_ref, a, V_L, V_U, T, E``."""
    capacitor = "T*(i - v/R)/C"
    reset = ["i", "v", "0"]
    return PiecewiseSystem(
        name="buck_converter",
        states=["i", "v", "tau"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("on", ["T*(E - v)/L", capacitor, "1"], domain=[f"{RAMP} < 0"]),
            Mode("off", ["-T*v/L", capacitor, "1"]),
        ],
        surfaces={"ramp": RAMP, "clock": "tau - 1"},
        transitions=[  # the comparator, both ways (no latch)
            Transition("off", "ramp", Crossing.FALLING, "on"),
            Transition("on", "ramp", Crossing.RISING, "off"),
            # the ramp's reset: OFF unless v_con lies below the ramp's foot V_L
            Transition("on", "clock", Crossing.RISING, "off", reset=reset, guard=[f"{AFTER_RESET} >= 0"]),
            Transition("on", "clock", Crossing.RISING, "on", reset=reset, guard=[f"{AFTER_RESET} < 0"]),
            Transition("off", "clock", Crossing.RISING, "off", reset=reset, guard=[f"{AFTER_RESET} >= 0"]),
            Transition("off", "clock", Crossing.RISING, "on", reset=reset, guard=[f"{AFTER_RESET} < 0"]),
        ],
    )


SHIPPED = ShippedModel(
    "buck_converter",
    buck_converter,
    "DC-DC buck converter under ramp (PWM) control, time in ramp periods (autonomous, phase state tau)",
)
