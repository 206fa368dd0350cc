"""Block-on-belt stick-slip system of *Fold bifurcations in discontinuous systems*, eqs. (15)-(17), Appendix B.

A mass on a spring and damper rides a belt moving at ``v_dr``; dry friction
follows the switch model of eq. (17): slip with ``F = -F_slip sgn(v_rel)``,
``v_rel = x' - v_dr``, outside the band ``|v_rel| < eta``; stick (region D,
field ``[v_dr, -v_rel sqrt(k/m)]``) inside the band where the spring and
damper force ``|k x + c x'|`` is below ``F_stick``.

In the band where ``|k x + c x'| > F_stick`` (region W) eq. (17) as printed
uses the slip field (``WRegion.SLIP``, the default); ``WRegion.STICK_FRICTION``
gives W its own field with friction ``F_stick sgn(k x + c x')`` instead.

The model is region-based (a Filippov system), so every boundary is listed
both ways; in backward time the unstable limit cycle slides along the border
of the stick band (an attraction sliding mode in backward time).
"""

from __future__ import annotations

import enum
import functools
import math
from collections.abc import Mapping

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .shipped import ShippedModel

RISING, FALLING = Crossing.RISING, Crossing.FALLING

#: Appendix B (the second "F_slip" of the appendix is F_stick = 2 N)
DEFAULTS = {"m": 1.0, "c": 0.1, "k": 1.0, "v_dr": 1.0, "F_slip": 1.0, "F_stick": 2.0, "eta": 1e-4}


class WRegion(enum.Enum):
    """Vector field in the band ``|v_rel| < eta`` where ``|k x + c x'| > F_stick``."""

    SLIP = "slip"  #: eq. (17) as printed: the slip field
    STICK_FRICTION = "stick_friction"  #: its own field, friction F_stick sgn(k x + c x')


SPRING = "k*x + c*v"
IN_BAND = ["v - v_dr - eta < 0", "v - v_dr + eta > 0"]
BELOW_STICK = [f"{SPRING} - F_stick < 0", f"{SPRING} + F_stick > 0"]


def _slip(force: str) -> list[str]:
    return ["v", f"(-k*x - c*v + {force})/m"]


@functools.lru_cache(maxsize=64)  # a model is immutable: building it again (sympy) is wasted
def block_on_belt(w_region: WRegion = WRegion.SLIP, **overrides: float) -> PiecewiseSystem:
    """The block-on-belt switch model; keyword arguments override Appendix B's values."""
    params = DEFAULTS | overrides
    stick = Mode("stick", ["v_dr", "-(v - v_dr)*sqrt(k/m)"], domain=IN_BAND + BELOW_STICK)
    surfaces = {
        "band_upper": "v - v_dr - eta",
        "band_lower": "v - v_dr + eta",
        "stick_upper": f"{SPRING} - F_stick",
        "stick_lower": f"{SPRING} + F_stick",
    }
    into_stick = [
        Transition("slip_plus", "band_upper", FALLING, "stick", guard=BELOW_STICK),
        Transition("slip_minus", "band_lower", RISING, "stick", guard=BELOW_STICK),
        Transition("stick", "band_upper", RISING, "slip_plus"),
        Transition("stick", "band_lower", FALLING, "slip_minus"),
    ]
    if WRegion(w_region) is WRegion.SLIP:
        surfaces["v_rel"] = "v - v_dr"
        modes = [
            stick,
            Mode("slip_plus", _slip("-F_slip"), domain=["v - v_dr > 0"]),
            Mode("slip_minus", _slip("F_slip")),
        ]
        transitions = into_stick + [
            Transition("slip_plus", "v_rel", FALLING, "slip_minus"),
            Transition("slip_minus", "v_rel", RISING, "slip_plus"),
            # in the band, slip turns into stick when the spring force drops below F_stick
            Transition("slip_plus", "stick_upper", FALLING, "stick", guard=["v - v_dr - eta < 0"]),
            Transition("slip_plus", "stick_lower", RISING, "stick", guard=["v - v_dr - eta < 0"]),
            Transition("slip_minus", "stick_upper", FALLING, "stick", guard=["v - v_dr + eta > 0"]),
            Transition("slip_minus", "stick_lower", RISING, "stick", guard=["v - v_dr + eta > 0"]),
            # stick ends when the spring force exceeds F_stick: slip in the direction of v_rel
            Transition("stick", "stick_upper", RISING, "slip_plus", guard=["v - v_dr > 0"]),
            Transition("stick", "stick_upper", RISING, "slip_minus", guard=["v - v_dr <= 0"]),
            Transition("stick", "stick_lower", FALLING, "slip_plus", guard=["v - v_dr > 0"]),
            Transition("stick", "stick_lower", FALLING, "slip_minus", guard=["v - v_dr <= 0"]),
        ]
        name = "block_on_belt"
    else:
        modes = [
            stick,
            Mode("w_plus", _slip("F_stick"), domain=IN_BAND + [f"{SPRING} - F_stick >= 0"]),
            Mode("w_minus", _slip("-F_stick"), domain=IN_BAND + [f"{SPRING} + F_stick <= 0"]),
            Mode("slip_plus", _slip("-F_slip"), domain=["v - v_dr > 0"]),
            Mode("slip_minus", _slip("F_slip")),
        ]
        above = [f"{SPRING} - F_stick >= 0"]
        below = [f"{SPRING} + F_stick <= 0"]
        transitions = into_stick + [
            Transition("slip_plus", "band_upper", FALLING, "w_plus", guard=above),
            Transition("slip_plus", "band_upper", FALLING, "w_minus", guard=below),
            Transition("slip_minus", "band_lower", RISING, "w_plus", guard=above),
            Transition("slip_minus", "band_lower", RISING, "w_minus", guard=below),
            Transition("stick", "stick_upper", RISING, "w_plus"),
            Transition("stick", "stick_lower", FALLING, "w_minus"),
            Transition("w_plus", "stick_upper", FALLING, "stick"),
            Transition("w_minus", "stick_lower", RISING, "stick"),
            Transition("w_plus", "band_upper", RISING, "slip_plus"),
            Transition("w_plus", "band_lower", FALLING, "slip_minus"),
            Transition("w_minus", "band_upper", RISING, "slip_plus"),
            Transition("w_minus", "band_lower", FALLING, "slip_minus"),
        ]
        name = "block_on_belt_w"
    return PiecewiseSystem(
        name=name,
        states=["x", "v"],
        parameters=params,
        modes=modes,
        surfaces=surfaces,
        transitions=transitions,
    )


def _transient_start(p: Mapping[str, float], backward: bool) -> list[float]:
    """Where a transient starts: sticking to the belt (it leads onto the stable stick-slip cycle), or in
    backward time just off the equilibrium ``[F_slip/k, 0]``, from which the flow spirals out onto the
    unstable (infinitely unstable) limit cycle."""
    if backward:
        return [p["F_slip"] / p["k"] + 0.1 * p["v_dr"] * math.sqrt(p["m"] / p["k"]), 0.0]
    return [0.0, p["v_dr"]]


def _transient_length(p: Mapping[str, float]) -> float:
    """50 periods of the undamped oscillator."""
    return 50 * 2 * math.pi * math.sqrt(p["m"] / p["k"])


SHIPPED = ShippedModel(
    "block_on_belt",
    block_on_belt,
    "stick-slip oscillator: a mass on a spring and damper riding a belt at v_dr",
    start=_transient_start,
    transient_length=_transient_length,
)
