"""A harmonically forced, damped oscillator between two symmetric rigid stops.

``x'' + 2 zeta x' + x = f0 cos(omega t)`` while ``|x| < d``; at either stop the velocity is reversed
and reduced by Newton's restitution law ``x'+ = -r x'-``.  The model maps to itself under
``(x, x') -> (-x, -x')``, ``t -> t + T/2`` (:class:`~saltation.model.symmetry.Symmetry`): its
symmetric orbits, one impact on each stop per period, lose their symmetry at pitchforks where a
half-period multiplier passes -1 (Shaw and Holmes, "A periodically forced piecewise linear oscillator",
J. Sound Vib. 90, 1983, for the one-sided case; the two-sided backlash oscillator is treated in di
Bernardo, Budd, Champneys and Kowalczyk, *Piecewise-smooth Dynamical Systems*, 2008, ch. 6).  At the
defaults the symmetric orbit's symmetry breaking is at ``omega = 0.981953574906`` (an independent scipy
computation in the test suite).

Forward time only: the impacts dissipate energy.
"""

from __future__ import annotations

import functools

from ..model import Crossing, Mode, PiecewiseSystem, Symmetry, Transition
from .shipped import ShippedModel

DEFAULTS = {"zeta": 0.05, "omega": 0.98, "r": 0.8, "d": 1.0, "f0": 0.5}


@functools.lru_cache(maxsize=64)
def symmetric_impact_oscillator(**overrides: float) -> PiecewiseSystem:
    """The impact oscillator between stops at ``x = -d`` and ``x = d``; keyword arguments override the
    defaults ``zeta, omega, r, d, f0``."""
    return PiecewiseSystem(
        name="symmetric_impact_oscillator",
        states=["x", "v"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("free", ["v", "-2*zeta*v - x + f0*cos(omega*t)"])],
        surfaces={"right": "x - d", "left": "x + d"},
        transitions=[
            Transition("free", "right", Crossing.RISING, "free", reset=["x", "-r*v"]),
            Transition("free", "left", Crossing.FALLING, "free", reset=["x", "-r*v"]),
        ],
        period="2*pi/omega",
        symmetry=Symmetry.of_signs([-1, -1]),
    )


SHIPPED = ShippedModel(
    "symmetric_impact_oscillator",
    symmetric_impact_oscillator,
    "forced damped oscillator x'' + 2 zeta x' + x = f0 cos(omega t) between rigid stops at x = -d and x = d "
    "(restitution r; symmetric under x -> -x, t -> t + T/2)",
)
