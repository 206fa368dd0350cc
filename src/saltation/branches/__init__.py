"""Layer 4, branches: pseudo-arclength continuation and the branch records.

:mod:`~saltation.branches.continuation` (the engine: predictor, bordered corrector of
:mod:`~saltation.branches.corrector`, step control; special points are looked for by a detector
handed in from outside) and :mod:`~saltation.branches.branch` (:class:`Branch`,
:class:`BranchPoint`, :class:`SpecialPoint`).  Depends on the orbit layer and those above it.
"""
