"""Bifurcation diagrams: several branches stitched together (moved to :mod:`saltation.special_points.follow`).

Following a branch through a discontinuous fold, and the diagram that holds the branches, are library
work: they live in :mod:`saltation.special_points.follow`.  This module re-exports them under their old
path until release 0.3.0, which removes it.
"""

from __future__ import annotations

from saltation._moved import forward_names
from saltation.special_points.follow import (
    BifurcationDiagram,
    distinct_special_points,
    find_backward_seed,
    follow_through_discontinuous_fold,
    locate_branch_end,
)

__all__ = [
    "BifurcationDiagram",
    "distinct_special_points",
    "find_backward_seed",
    "follow_through_discontinuous_fold",
    "locate_branch_end",
]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.special_points.follow', 'saltation.special_points.points', 'saltation.special_points.grazing', 'saltation.orbits.classification', 'saltation.orbits.single', 'saltation.branches.branch', 'saltation.branches.continuation', 'saltation.engine.flow', 'saltation.errors'))
