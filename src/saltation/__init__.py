"""saltation: bifurcation analysis of periodic solutions of discontinuous systems."""

from .errors import (
    ChatteringError,
    ConvergenceError,
    InitialModeError,
    IntegrationError,
    ModelError,
    NonFiniteError,
    SaltationError,
    SlidingError,
    StepSizeError,
)
from .integrate import EventKind, Flow, Status, SwitchingEvent, Tolerances, Trajectory, simulate
from .model import Crossing, Mode, PiecewiseSystem, Transition

__version__ = "0.1.0"

__all__ = [
    "ChatteringError", "ConvergenceError", "Crossing", "EventKind", "Flow", "InitialModeError",
    "IntegrationError", "Mode", "ModelError", "NonFiniteError", "PiecewiseSystem", "SaltationError",
    "SlidingError", "Status", "StepSizeError", "SwitchingEvent", "Tolerances", "Trajectory",
    "Transition", "simulate",
]
