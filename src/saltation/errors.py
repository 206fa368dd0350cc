"""Exceptions raised by saltation.

Every failure names its culprit (mode, surface, transition, parameter) so
that a user can find the offending part of a model without a debugger.
"""

from __future__ import annotations

from collections.abc import Sequence


class SaltationError(Exception):
    """Base class of every error raised by saltation."""


class ModelError(SaltationError, ValueError):
    """A piecewise-smooth model is malformed (raised at construction)."""


class InitialModeError(SaltationError, ValueError):
    """The initial state lies in no mode's domain."""


class IntegrationError(SaltationError, RuntimeError):
    """Event-driven integration failed."""


class ChatteringError(IntegrationError):
    """Too many switching events in too short a time (chattering / Zeno)."""


class StepSizeError(IntegrationError):
    """The step size fell below the resolution of floating point."""


class NonFiniteError(IntegrationError):
    """A vector field, indicator or reset returned NaN or infinity."""


class SlidingError(IntegrationError):
    """A sliding motion is required that the model does not define."""


class ConvergenceError(SaltationError, RuntimeError):
    """Newton's method did not converge.

    Attributes
    ----------
    residuals : list of float
        Norm of the residual at every iteration, first to last.
    """

    def __init__(self, message: str, residuals: Sequence[float] = ()):
        self.residuals = [float(r) for r in residuals]
        history = ", ".join(f"{r:.3e}" for r in self.residuals)
        super().__init__(f"{message} (residual history: [{history}])" if self.residuals else message)
