"""Models shipped with saltation, each a short file that reads like its source."""

from .block_on_belt import WRegion, block_on_belt
from .bouncing_ball import bouncing_ball
from .buck_converter import buck_converter
from .chain import chain
from .friction_oscillator import friction_oscillator
from .impact_oscillator import impact_oscillator
from .relay_feedback import relay_feedback
from .trilinear import trilinear
from .two_mass_stops import two_mass_stops

__all__ = [
    "WRegion", "block_on_belt", "bouncing_ball", "buck_converter", "chain", "friction_oscillator",
    "impact_oscillator", "relay_feedback", "trilinear", "two_mass_stops",
]
