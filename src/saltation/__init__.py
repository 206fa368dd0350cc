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

import importlib as _importlib
import logging as _logging

from saltation import _moved

_moved.install()
# quiet unless the application configures logging: each module logs to ``saltation.<layer>.<module>``
_logging.getLogger("saltation").addHandler(_logging.NullHandler())

#: Where each of the everyday names lives.  They are imported when first used (``saltation.Flow``,
#: ``from saltation import Flow``), so ``import saltation`` loads neither sympy nor numba, and the command
#: line answers ``--version`` and ``--help`` at once.
_HOMES: dict[str, tuple[str, ...]] = {
    "saltation.branches.branch": ("Branch", "SpecialPoint"),
    "saltation.engine.flow": ("EventKind", "Flow", "Status", "SwitchingEvent", "Tolerances", "Trajectory", "simulate"),
    "saltation.errors": (
        "ChatteringError", "ConvergenceError", "InconsistentResultError", "InitialModeError", "IntegrationError",
        "ModelError", "NonFiniteError", "NoOrbitNearGuessError", "SaltationError", "SlidingError", "StartGuessError",
        "StationaryStateError", "StepSizeError",
    ),
    "saltation.kinds": ("SpecialPointKind",),
    "saltation.model.symmetry": ("Symmetry",),
    "saltation.model.system": ("Crossing", "Mode", "PiecewiseSystem", "Transition"),
    "saltation.orbits.lyapunov": ("LyapunovExponents", "lyapunov_exponents"),
    "saltation.orbits.phase_response": ("PhaseResponse", "PhaseResponseSensitivity", "phase_response",
                                        "phase_response_sensitivity"),
    "saltation.orbits.pseudo_equilibria": ("PseudoEquilibrium", "find_pseudo_equilibrium"),
    "saltation.orbits.records": ("PeriodicOrbit",),
    "saltation.orbits.single": ("ShootingProblem",),
    "saltation.orbits.start": ("find_periodic_orbit",),
    "saltation.special_points.continuation": ("Continuation", "ContinuationSettings", "continue_branch", "continue_orbit"),
    "saltation.sweeps": ("SweepStart", "period_map", "sweep"),
}
_HOME_OF = {name: module for module, names in _HOMES.items() for name in names}


def __getattr__(name: str):
    """An everyday name, imported from its module on first use (PEP 562)."""
    module = _HOME_OF.get(name)
    if module is None:
        raise AttributeError(f"module 'saltation' has no attribute {name!r}")
    value = getattr(_importlib.import_module(module), name)
    globals()[name] = value  # the next use is a plain lookup
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOME_OF})


__version__ = "0.1.0"

__all__ = [
    "Branch", "ChatteringError", "Continuation", "ContinuationSettings", "ConvergenceError", "Crossing", "InconsistentResultError", "EventKind", "Flow",
    "InitialModeError", "IntegrationError", "LyapunovExponents", "Mode", "ModelError", "NoOrbitNearGuessError", "NonFiniteError", "PeriodicOrbit", "PhaseResponse", "PhaseResponseSensitivity",
    "PiecewiseSystem", "PseudoEquilibrium", "SaltationError", "ShootingProblem", "SlidingError", "SpecialPoint", "StartGuessError", "StationaryStateError", "SpecialPointKind",
    "Symmetry",
    "Status", "StepSizeError", "SweepStart", "SwitchingEvent", "Tolerances", "Trajectory", "Transition", "continue_branch",
    "continue_orbit", "find_periodic_orbit", "find_pseudo_equilibrium", "lyapunov_exponents", "period_map", "phase_response",
    "phase_response_sensitivity", "simulate", "sweep",
]
