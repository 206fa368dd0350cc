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


class StationaryStateError(SaltationError, RuntimeError):
    """Shooting converged to a state that does not move: not a periodic orbit.

    An equilibrium of a mode, a point of a sliding or sticking set where the
    motion stops (a pseudo-equilibrium), or a period that shrank to zero.  The
    message says "equilibrium" and gives the state.

    Attributes
    ----------
    state : ndarray, shape (n,)
        The state shooting converged to.
    period : float
        The period it converged to.
    """

    def __init__(self, message: str, state: Sequence[float] = (), period: float = float("nan")):
        self.state = [float(v) for v in state]
        self.period = float(period)
        super().__init__(message)


class StartGuessError(SaltationError, RuntimeError):
    """No starting guess of a periodic orbit could be made: the transient failed, diverged, or shows no
    oscillation to read a period from (:mod:`saltation.orbits.start`)."""


class InconsistentResultError(SaltationError, RuntimeError):
    """A computed result contradicts itself beyond its stated accuracy.

    For example the trivial multiplier of an autonomous orbit that is not 1, or
    a state on a switching surface whose event the monodromy misses.  Raised
    instead of returning the result.
    """


class NoOrbitNearGuessError(StationaryStateError, ConvergenceError):
    """Shooting did not converge, and the flow from the guess comes to rest: at an equilibrium or in a
    sticking set (a pseudo-equilibrium).  Both a :class:`ConvergenceError` (with the residual
    history) and a :class:`StationaryStateError` (with the state where the flow stops).
    """

    def __init__(self, message: str, residuals: Sequence[float], state: Sequence[float], period: float):
        ConvergenceError.__init__(self, message, residuals)
        self.state = [float(v) for v in state]
        self.period = float(period)


class MissingDependencyError(SaltationError, ImportError):
    """An optional dependency a function needs is not installed; the message names the package and the
    extra that installs it (``pip install 'saltation[xarray]'``)."""
