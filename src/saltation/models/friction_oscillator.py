"""A harmonically forced oscillator with dry friction on a moving belt (a Filippov system).

``x'' + 2 zeta x' + x = -F sgn(x' - v_b) + a cos(omega t)``: Coulomb friction of
level ``F`` against a belt moving at ``v_b``.  Where both fields push into the
surface ``x' = v_b`` the block sticks to the belt: Filippov sliding.  While the
block moves slower than the belt, it obeys the linear oscillator with the
constant force ``+F``; its harmonic response ``x = F + A cos(omega t - phi)``,
``A = a / sqrt((1 - omega^2)^2 + (2 zeta omega)^2)``, reaches the velocity
``A omega`` at its fastest, so it grazes the sliding surface (a grazing-sliding
bifurcation) at ``v_b = A omega`` (di Bernardo, Kowalczyk and Nordmark,
Physica D 170, 2002; Den Hartog, Trans. ASME 53, 1931, for the friction
oscillator).
"""

from __future__ import annotations

import functools

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .shipped import ShippedModel

DEFAULTS = {"zeta": 0.1, "F": 0.5, "a": 1.0, "omega": 0.8, "v_b": 2.0}


@functools.lru_cache(maxsize=64)
def friction_oscillator(**overrides: float) -> PiecewiseSystem:
    """The friction oscillator; keyword arguments override ``zeta, F, a, omega, v_b``."""
    forcing = "a*cos(omega*t)"
    return PiecewiseSystem(
        name="friction_oscillator",
        states=["x", "v"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("slip_plus", ["v", f"-2*zeta*v - x - F + {forcing}"], domain=["v - v_b > 0"]),
            Mode("slip_minus", ["v", f"-2*zeta*v - x + F + {forcing}"]),
        ],
        surfaces={"v_rel": "v - v_b"},
        transitions=[  # a region-based model: the surface listed both ways
            Transition("slip_plus", "v_rel", Crossing.FALLING, "slip_minus"),
            Transition("slip_minus", "v_rel", Crossing.RISING, "slip_plus"),
        ],
        period="2*pi/omega",
    )


SHIPPED = ShippedModel(
    "friction_oscillator",
    friction_oscillator,
    "forced oscillator with Coulomb friction F on a belt moving at v_b (a Filippov system: sticking is sliding)",
)
