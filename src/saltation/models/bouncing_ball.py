"""A ball bouncing on a table that vibrates harmonically.

The table's height is ``s(t) = A sin(omega t)``; between impacts the ball
flies freely, ``y'' = -g``; at an impact (``y - s(t)`` falling through zero)
Newton's restitution law reverses the relative velocity,
``v+ = (1 + e) s'(t) - e v-``.  The impact surface moves (``h_t != 0``), which
the saltation matrix of eq. (9) takes into account.

Period-1 orbits impact once per forcing period ``T = 2 pi / omega`` at a phase
``phi`` with ``cos(phi) = (1 - e) pi g / ((1 + e) A omega^2)``: the ball leaves
with ``v+ = g T / 2`` and returns with ``-g T / 2``.  As ``A`` grows they lose
stability in a period doubling (Holmes, J. Sound Vib. 84, 1982; Luck and
Mehta, Phys. Rev. E 48, 1993).

The impact sticks (``sticks=True``, :mod:`saltation.model.contacts`): an impact that leaves no relative
velocity (``e = 0``) continues as the motion with the table, mode ``flight@table``, until the contact
force ``g - A omega^2 sin(omega t)`` vanishes, at ``t_r = asin(g / (A omega^2)) / omega``, where the
ball leaves (surface ``table@release``).
"""

from __future__ import annotations

import functools

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .shipped import ShippedModel

DEFAULTS = {"g": 9.81, "e": 0.5, "A": 0.3, "omega": 6.283185307179586}


@functools.lru_cache(maxsize=64)
def bouncing_ball(**overrides: float) -> PiecewiseSystem:
    """The ball on the vibrating table; keyword arguments override ``g, e, A, omega``."""
    return PiecewiseSystem(
        name="bouncing_ball",
        states=["y", "v"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("flight", ["v", "-g"])],
        surfaces={"table": "y - A*sin(omega*t)"},
        transitions=[
            Transition("flight", "table", Crossing.FALLING, "flight", reset=["y", "(1 + e)*A*omega*cos(omega*t) - e*v"],
                       sticks=True),
        ],
        period="2*pi/omega",
    )


SHIPPED = ShippedModel(
    "bouncing_ball",
    bouncing_ball,
    "a ball bouncing on a table that vibrates as A sin(omega t) (gravity g, restitution e)",
)
