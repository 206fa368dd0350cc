"""Layer 4, branches: pseudo-arclength continuation and the branch records.

Depends on the orbit layer and those below it.  Its modules:

- :mod:`~saltation.branches.continuation`: the engine (predictor, step control, the stitching of the
  two directions); special points are looked for by a detector handed in from outside;
- :mod:`~saltation.branches.corrector`: the bordered Newton corrector and the tangent;
- :mod:`~saltation.branches.branch`: :class:`Branch`, :class:`SpecialPoint` and their vocabulary;
- :mod:`~saltation.branches.check`: the invariants that make a computed branch trustworthy;
- :mod:`~saltation.branches.monitors`: the user's test functions along a branch, located like the special points.
"""
