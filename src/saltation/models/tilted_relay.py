"""A harmonically forced relay oscillator whose switching line is tilted (a Filippov system).

``x' = y``, ``y' = -x - 2 zeta y - F sgn(s) + a cos(omega t)`` with ``s = y + kappa x - v``: a relay of
level ``F`` switched by a combination of position and velocity (``kappa = 0`` is the friction
oscillator on a belt moving at ``v``).  Mode ``plus`` holds where ``s > 0`` (force ``-F``), mode
``minus`` where ``s < 0`` (force ``+F``).

The rate of ``s`` along a mode's field, ``h_x f + h_t`` with ``h_x = (kappa, 1)``, ``h_t = 0``, is on
the line ``y = v - kappa x``::

    L_pm = G(t, x) -+ F,   G = (kappa - 2 zeta) v - (1 + kappa^2 - 2 zeta kappa) x + a cos(omega t).

Both fields push into the line (Filippov sliding) where ``L_+ < 0 < L_-``, that is ``|G| < F``.  Both
fields have the first component ``y``, so the sliding motion is ``x' = v - kappa x`` on the line,
independent of the forcing: ``x = v / kappa + (x0 - v / kappa) exp(-kappa (t - t0))``.  It ends where
a mode's field turns tangent to the line: into ``minus`` where ``G = -F``, into ``plus`` where ``G = F``.

Tangency conditions: the harmonic response of ``minus``, ``x = F + A cos(omega t - phi)`` with
``A = a / sqrt((1 - omega^2)^2 + (2 zeta omega)^2)``, has ``s = kappa F - v + A sqrt(kappa^2 + omega^2)
cos(omega t - psi)``; it touches the line, where ``L_- = 0`` and ``L_+ = -2F < 0`` (the boundary of
the sliding region), at ``v = kappa F + A sqrt(kappa^2 + omega^2)``: a grazing-sliding bifurcation
(di Bernardo, Kowalczyk and Nordmark, Physica D 170, 2002).  An orbit that arrives at the line from
``minus`` where ``L_+ = 0`` (``G = F``), a tangency of ``plus`` that is invisible (its orbit returns
to the line), is at a switching-sliding bifurcation.
"""

from __future__ import annotations

import functools

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .shipped import ShippedModel

DEFAULTS = {"zeta": 0.1, "F": 0.5, "a": 1.0, "omega": 0.8, "kappa": 0.5, "v": 2.0}


@functools.lru_cache(maxsize=64)
def tilted_relay(**overrides: float) -> PiecewiseSystem:
    """The forced relay with a tilted switching line; keyword arguments override ``zeta, F, a, omega, kappa, v``."""
    forcing = "a*cos(omega*t)"
    return PiecewiseSystem(
        name="tilted_relay",
        states=["x", "y"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("plus", ["y", f"-x - 2*zeta*y - F + {forcing}"], domain=["y + kappa*x - v > 0"]),
            Mode("minus", ["y", f"-x - 2*zeta*y + F + {forcing}"]),
        ],
        surfaces={"s": "y + kappa*x - v"},
        transitions=[  # a region-based model: the line listed both ways
            Transition("plus", "s", Crossing.FALLING, "minus"),
            Transition("minus", "s", Crossing.RISING, "plus"),
        ],
        period="2*pi/omega",
    )


SHIPPED = ShippedModel(
    "tilted_relay",
    tilted_relay,
    "forced relay oscillator switched on the tilted line y + kappa x = v (a Filippov system with sliding)",
)
