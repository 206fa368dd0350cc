"""Trilinear spring system of *Fold bifurcations in discontinuous systems*, eqs. (1)-(7), Appendix A.

A forced mass on a spring and damper with two supports at distance ``x_c``.
Contact with the lower support (mode ``contact_1``, region V+1) is made when
``x`` passes ``x_c`` (surface ``h1a``, eq. 4) and lost when the support force
``k_f (x - x_c) + c_f x'`` becomes zero (surface ``h1b``, eq. 5); the upper
support mirrors it (``h2a``, ``h2b``, eqs. 6-7).  The regions are those of the
paper, so the transitions list every boundary both ways (backward time).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

import numpy as np

from ..model import Crossing, Mode, PiecewiseSystem, Symmetry, Transition
from .shipped import ShippedModel

RISING, FALLING = Crossing.RISING, Crossing.FALLING

#: Appendix A
DEFAULTS = {"m": 1.0, "c": 0.05, "k": 1.0, "x_c": 1.0, "k_f": 4.0, "c_f": 0.5, "f0": 0.2, "omega": 1.2}


@functools.lru_cache(maxsize=64)  # a model is immutable: building it again (sympy) is wasted
def trilinear(**overrides: float) -> PiecewiseSystem:
    """The trilinear spring system; keyword arguments override Appendix A's values."""
    params = DEFAULTS | overrides
    forcing = "f0*sin(omega*t)"
    return PiecewiseSystem(
        name="trilinear",
        states=["x", "v"],
        parameters=params,
        modes=[
            # V+1: x > x_c and k_f (x - x_c) + c_f x' >= 0
            Mode("contact_1", ["v", f"(-c*v - k*x - c_f*v - k_f*(x - x_c) + {forcing})/m"],
                 domain=["x - x_c > 0", "k_f*(x - x_c) + c_f*v >= 0"]),
            # V+2: x < -x_c and k_f (x + x_c) + c_f x' <= 0
            Mode("contact_2", ["v", f"(-c*v - k*x - c_f*v - k_f*(x + x_c) + {forcing})/m"],
                 domain=["x + x_c < 0", "k_f*(x + x_c) + c_f*v <= 0"]),
            Mode("free", ["v", f"(-c*v - k*x + {forcing})/m"]),
        ],
        surfaces={
            "h1a": "x - x_c",
            "h1b": "k_f*(x - x_c) + c_f*v",
            "h2a": "x + x_c",
            "h2b": "k_f*(x + x_c) + c_f*v",
        },
        transitions=[
            Transition("free", "h1a", RISING, "contact_1", guard=["k_f*(x - x_c) + c_f*v >= 0"]),
            Transition("free", "h1b", RISING, "contact_1", guard=["x - x_c > 0"]),
            Transition("contact_1", "h1b", FALLING, "free"),
            Transition("contact_1", "h1a", FALLING, "free"),
            Transition("free", "h2a", FALLING, "contact_2", guard=["k_f*(x + x_c) + c_f*v <= 0"]),
            Transition("free", "h2b", FALLING, "contact_2", guard=["x + x_c < 0"]),
            Transition("contact_2", "h2b", RISING, "free"),
            Transition("contact_2", "h2a", RISING, "free"),
        ],
        period="2*pi/omega",
        # x -> -x, t -> t + T/2: the supports mirror each other and the forcing changes sign
        symmetry=Symmetry.of_signs([-1, -1]),
    )


def linear_response_state(params: Mapping[str, float]) -> np.ndarray:
    """The state at ``t = 0`` of the harmonic response of the free mode, a closed-form start of shooting.

    Without contact (mode ``free``) the system is ``m x'' + c x' + k x = f0 sin(omega t)``; its periodic
    response is ``x = a sin(omega t) + b cos(omega t)``.  Below the contact (amplitude under ``x_c``)
    this is the orbit; above it, a guess near the orbit.

    Parameters
    ----------
    params : mapping
        Values of ``m``, ``c``, ``k``, ``f0`` and ``omega`` (others are ignored).

    Returns
    -------
    ndarray, shape (2,)
        ``(x, x')`` at ``t = 0``: ``(b, a omega)``.

    Raises
    ------
    KeyError
        If one of the five values is missing.
    """
    m, c, k, f0, w = (params[n] for n in ("m", "c", "k", "f0", "omega"))
    # x = a sin(wt) + b cos(wt)
    det = (k - m * w**2) ** 2 + (c * w) ** 2
    a = f0 * (k - m * w**2) / det
    b = -f0 * c * w / det
    return np.array([b, a * w])


SHIPPED = ShippedModel(
    "trilinear",
    trilinear,
    "forced mass on a spring and damper between two compliant supports (forcing f0 sin(omega t))",
)
