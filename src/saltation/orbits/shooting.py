"""The shooting layer's names at their release-0.1 path (kept for one release: they go in 0.3.0).

The module was split by job: :mod:`~saltation.orbits.problem` (the problem base and Newton),
:mod:`~saltation.orbits.records` (:class:`PeriodicOrbit`), :mod:`~saltation.orbits.seam` (the seam
rule), :mod:`~saltation.orbits.single` (:class:`ShootingProblem`), :mod:`~saltation.orbits.multiple`
(:class:`MultipleShootingProblem`), :mod:`~saltation.orbits.equilibria` (:class:`EquilibriumProblem`)
and :mod:`~saltation.orbits.start` (:func:`find_periodic_orbit`).  Import from those.
"""

from saltation._moved import forward_names
from saltation.orbits.equilibria import Equilibrium, EquilibriumProblem
from saltation.orbits.multiple import (
    MAX_NODE_VALUES,
    MAX_SEGMENTS,
    MultipleShootingProblem,
    check_segments,
)
from saltation.orbits.problem import BranchProblem, newton
from saltation.orbits.records import (
    BranchPoint,
    Evaluation,
    PeriodicOrbit,
    SolutionSummary,
)
from saltation.orbits.single import (
    PERIOD_GROWTH,
    SEAM_MARGIN,
    STATIONARY_FACTOR,
    STATIONARY_FRACTION,
    TRIVIAL_MULTIPLIER_ACCURACY,
    ShootingProblem,
    stationary_floor,
)
from saltation.orbits.start import find_periodic_orbit

__all__ = [
    "MAX_NODE_VALUES", "MAX_SEGMENTS", "PERIOD_GROWTH", "SEAM_MARGIN", "STATIONARY_FACTOR", "STATIONARY_FRACTION",
    "TRIVIAL_MULTIPLIER_ACCURACY", "BranchPoint", "BranchProblem", "Equilibrium", "EquilibriumProblem", "Evaluation",
    "MultipleShootingProblem", "PeriodicOrbit", "ShootingProblem", "SolutionSummary", "check_segments",
    "find_periodic_orbit", "newton", "stationary_floor",
]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.orbits.records', 'saltation.orbits.conditions', 'saltation.orbits.floquet', 'saltation.orbits.start', 'saltation.engine.flow', 'saltation.errors', 'saltation.model.system'))
