"""A harmonically forced, damped oscillator against a rigid stop (an impact oscillator).

``x'' + 2 zeta x' + x = cos(omega t)`` while ``x < s``; at the stop ``x = s`` the
velocity is reversed and reduced by Newton's restitution law ``x'+ = -r x'-``.
Without impacts the orbit is the harmonic response of amplitude
``1 / sqrt((1 - omega^2)^2 + (2 zeta omega)^2)``; it grazes the stop when that
amplitude equals ``s``, the classic setting of Nordmark's square-root map
(Nordmark, J. Sound Vib. 145, 1991; di Bernardo, Budd, Champneys and Kowalczyk,
*Piecewise-smooth Dynamical Systems*, 2008, sec. 2.2).

Forward time only: the impact is a reset that dissipates energy.
"""

from __future__ import annotations

import functools

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .shipped import ShippedModel

DEFAULTS = {"zeta": 0.05, "omega": 0.8, "r": 0.8, "s": 2.0}


@functools.lru_cache(maxsize=64)
def impact_oscillator(**overrides: float) -> PiecewiseSystem:
    """The impact oscillator; keyword arguments override the defaults ``zeta, omega, r, s``."""
    return PiecewiseSystem(
        name="impact_oscillator",
        states=["x", "v"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("free", ["v", "-2*zeta*v - x + cos(omega*t)"])],
        surfaces={"stop": "x - s"},
        transitions=[Transition("free", "stop", Crossing.RISING, "free", reset=["x", "-r*v"])],
        period="2*pi/omega",
    )


SHIPPED = ShippedModel(
    "impact_oscillator",
    impact_oscillator,
    "forced damped oscillator x'' + 2 zeta x' + x = cos(omega t) against a rigid stop at x = s (restitution r)",
)
