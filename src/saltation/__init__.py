"""saltation: bifurcation analysis of periodic solutions of discontinuous systems.

The everyday names are here: define a model (:class:`PiecewiseSystem`,
:class:`Mode`, :class:`Transition`, :class:`Crossing`), integrate it
(:class:`Flow`, :func:`simulate`), find a periodic orbit
(:func:`find_periodic_orbit`), follow its branch (:func:`continue_orbit`, or
:class:`ShootingProblem` with :func:`continue_branch`) and read its special
points (:class:`Branch`, :class:`SpecialPoint`, :class:`SpecialPointKind`);
brute-force diagrams with :func:`sweep` and :func:`period_map`.

The package is one folder per layer, each depending only on the ones before it: ``model`` ->
``engine`` -> ``orbits`` -> ``branches`` -> ``special_points`` -> ``sweeps`` -> ``output`` -> ``apps``
(with ``models``, the shipped models, and ``errors`` and ``summary``, which import nothing of the
package).  The flat layout's import paths (``saltation.integrate``, ``saltation.shooting``, ...) work
for one more release, with a ``DeprecationWarning``.
"""

from saltation import _moved

_moved.install()

from saltation.branches.branch import Branch, SpecialPoint
from saltation.engine.flow import (
    EventKind,
    Flow,
    Status,
    SwitchingEvent,
    Tolerances,
    Trajectory,
    simulate,
)
from saltation.errors import (
    ChatteringError,
    ConvergenceError,
    InconsistentResultError,
    InitialModeError,
    IntegrationError,
    ModelError,
    NonFiniteError,
    NoOrbitNearGuessError,
    SaltationError,
    SlidingError,
    StartGuessError,
    StationaryStateError,
    StepSizeError,
)
from saltation.kinds import SpecialPointKind
from saltation.model.symmetry import Symmetry
from saltation.model.system import Crossing, Mode, PiecewiseSystem, Transition
from saltation.orbits.lyapunov import LyapunovExponents, lyapunov_exponents
from saltation.orbits.pseudo_equilibria import (
    PseudoEquilibrium,
    find_pseudo_equilibrium,
)
from saltation.orbits.records import PeriodicOrbit
from saltation.orbits.single import ShootingProblem
from saltation.orbits.start import find_periodic_orbit
from saltation.special_points.continuation import (
    Continuation,
    ContinuationSettings,
    continue_branch,
    continue_orbit,
)
from saltation.sweeps import SweepStart, period_map, sweep

__version__ = "0.1.0"

__all__ = [
    "Branch", "ChatteringError", "Continuation", "ContinuationSettings", "ConvergenceError", "Crossing", "InconsistentResultError", "EventKind", "Flow",
    "InitialModeError", "IntegrationError", "LyapunovExponents", "Mode", "ModelError", "NoOrbitNearGuessError", "NonFiniteError", "PeriodicOrbit",
    "PiecewiseSystem", "PseudoEquilibrium", "SaltationError", "ShootingProblem", "SlidingError", "SpecialPoint", "StartGuessError", "StationaryStateError", "SpecialPointKind",
    "Symmetry",
    "Status", "StepSizeError", "SweepStart", "SwitchingEvent", "Tolerances", "Trajectory", "Transition", "continue_branch",
    "continue_orbit", "find_periodic_orbit", "find_pseudo_equilibrium", "lyapunov_exponents", "period_map", "simulate", "sweep",
]


def _no_terminal_reset_at_exit() -> None:
    """numba formats its warnings (the first comes from the engine's contract, at import) through colorama,
    whose first use registers a reset of the terminal's colours at exit: ``ESC[0m`` written to standard
    output when Python stops, by a program that printed no colour.  Saltation unregisters it (colorama
    registers it once per process, so it does not come back)."""
    import atexit
    import sys

    initialise = sys.modules.get("colorama.initialise")
    if initialise is not None and hasattr(initialise, "reset_all"):
        atexit.unregister(initialise.reset_all)


_no_terminal_reset_at_exit()
