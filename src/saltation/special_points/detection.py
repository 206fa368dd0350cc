"""The former home of the special-point detector, kept as an import path until 0.3.0.

Every name it defined is re-exported from where it now lives:
:class:`~saltation.special_points.detector.SpecialPointDetector` (:mod:`~saltation.special_points.detector`),
the set-valued classification :func:`~saltation.orbits.classification.classify_nonsmooth` and
:class:`~saltation.orbits.classification.SetValuedCrossing`
(:mod:`~saltation.orbits.classification`), the records
:func:`~saltation.special_points.points.special_point_between`,
:func:`~saltation.special_points.points.grazing_point`,
:func:`~saltation.special_points.points.unlocated_grazing` and
:func:`~saltation.special_points.points.sliding_bifurcation_point`
(:mod:`~saltation.special_points.points`), and
:func:`~saltation.special_points.symmetric.symmetric_crossing` (:mod:`~saltation.special_points.symmetric`).
The test functions and the smooth location are in :mod:`~saltation.special_points.smooth`, the bracketing of
a change of the event sequence in :mod:`~saltation.special_points.nonsmooth`.
"""

from __future__ import annotations

from saltation._moved import forward_names
from saltation.orbits.classification import (
    SetValuedCrossing,
    classify_nonsmooth,
)
from saltation.special_points.detector import SpecialPointDetector
from saltation.special_points.points import (
    grazing_point,
    sliding_bifurcation_point,
    special_point_between,
    unlocated_grazing,
)
from saltation.special_points.smooth import (  # noqa: F401
    _flip_test,
    _hopf_test,
    _ns_test,
    _plus_one_test,
)
from saltation.special_points.symmetric import symmetric_crossing

__all__ = [
    "SpecialPointDetector",
    "classify_nonsmooth",
    "SetValuedCrossing",
    "special_point_between",
    "grazing_point",
    "unlocated_grazing",
    "sliding_bifurcation_point",
    "symmetric_crossing",
]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.special_points.detector', 'saltation.special_points.nonsmooth', 'saltation.special_points.smooth', 'saltation.special_points.symmetric', 'saltation.special_points.points', 'saltation.special_points.context', 'saltation.special_points.grazing', 'saltation.special_points.sliding', 'saltation.orbits.symmetry', 'saltation.orbits.floquet', 'saltation.orbits.boundary', 'saltation.orbits.single', 'saltation.model.symmetry', 'saltation.branches.branch', 'saltation.branches.continuation', 'saltation.engine.flow', 'saltation.errors', 'saltation.model.system'))
