"""Bifurcation diagrams: several branches stitched together (moved to :mod:`saltation.special_points.follow`).

Following a branch through a discontinuous fold, and the diagram that holds the branches, are library
work: they live in :mod:`saltation.special_points.follow`.  This module re-exports them under their old
path until release 0.3.0, which removes it.
"""

from __future__ import annotations

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
