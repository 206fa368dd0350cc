"""A third-order relay feedback system (a Filippov system with a symmetric self-oscillation).

di Bernardo, Johansson and Vasca, *Self-oscillations and sliding in relay
feedback systems: symmetry and bifurcations*, Int. J. Bifurcation and Chaos
11 (2001) 1121-1140: a linear plant under an ideal relay,

    x' = A x + B u,    y = C x,    u = -sgn(y),

    A = [[-(2 zeta w + lam), 1, 0],          B = [1, -2 sigma, 1]^T,
         [-(2 zeta w lam + w^2), 0, 1],      C = [1, 0, 0],
         [-lam w^2, 0, 0]],

the observer form of the transfer function
``G(s) = (s^2 - 2 sigma s + 1) / ((s^2 + 2 zeta w s + w^2)(s + lam))``.  The
two modes are ``u_plus`` (``u = +1``, ``y < 0``) and ``u_minus`` (``u = -1``,
``y > 0``); the switching surface is ``y = x1 = 0``.  There ``C B = 1``, so
``y' = x2 + u``: both fields push into the surface, and the system slides
(Filippov, ``u_eq = -x2``), on the band ``|x2| < 1``.  A relay gain would
only scale the state (the system is homogeneous), so it is left out.

The system is symmetric under ``x -> -x``.  Its symmetric unimodal
self-oscillation crosses the surface downwards at ``x(0) = (0, x2, x3)``,
``x2 < -1``, and upwards at ``x(T/2) = -x(0)``.  At the defaults
(``zeta = 0.05, w = 1, lam = 0.05, sigma = 0.5``) it has the period
``T = 7.144`` and is stable, with multipliers ``(1, 0.49, 0.27)``.  These
defaults were chosen and checked numerically, not copied from the paper:
``w = 1`` puts the lightly damped resonance at the numerator's zeros (on
``|s| = 1`` for ``|sigma| < 1``).  With ``w = 10, zeta = lam = 0.05`` no crossing
symmetric orbit turned up for ``sigma`` in ``[-3, 3]`` (half periods up to 10):
the relay oscillation near ``|s| = 1`` has ``|x2| < 1`` at its switches, so it
slides.
As ``sigma`` decreases the crossing point's ``x2`` rises to ``-1`` (at
``sigma = 0.04098543792``): the orbit arrives where the far side's field is
tangent to the surface (a visible tangency), at both switches at once, and
below that it slides briefly after each switch (a crossing-sliding bifurcation
of the symmetric orbit; at ``sigma = 0.03`` the period is ``6.4494``).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

from ..model import Crossing, Mode, PiecewiseSystem, Symmetry, Transition
from .shipped import ShippedModel

DEFAULTS = {"zeta": 0.05, "w": 1.0, "lam": 0.05, "sigma": 0.5}


def _field(u: str) -> list[str]:
    """``A x + B u`` with the relay output ``u``."""
    return [
        f"-(2*zeta*w + lam)*x1 + x2 + ({u})",
        f"-(2*zeta*w*lam + w**2)*x1 + x3 - 2*sigma*({u})",
        f"-lam*w**2*x1 + ({u})",
    ]


@functools.lru_cache(maxsize=64)
def relay_feedback(**overrides: float) -> PiecewiseSystem:
    """The relay feedback system; keyword arguments override ``zeta, w, lam, sigma``."""
    return PiecewiseSystem(
        name="relay_feedback",
        states=["x1", "x2", "x3"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("u_plus", _field("1"), domain=["x1 < 0"]),
            Mode("u_minus", _field("-1")),
        ],
        surfaces={"y": "x1"},
        transitions=[  # a region-based model: the surface listed both ways
            Transition("u_plus", "y", Crossing.RISING, "u_minus"),
            Transition("u_minus", "y", Crossing.FALLING, "u_plus"),
        ],
        symmetry=Symmetry.of_signs([-1, -1, -1]),  # x -> -x (the relay is odd, the plant linear)
    )


def _transient_start(p: Mapping[str, float], backward: bool) -> list[float]:
    """Off the switching surface (the origin slides)."""
    return [0.1, 0.0, 0.0]


SHIPPED = ShippedModel(
    "relay_feedback",
    relay_feedback,
    "third-order linear plant under an ideal relay u = -sgn(x1) (autonomous; sliding on x1 = 0)",
    start=_transient_start,
)
