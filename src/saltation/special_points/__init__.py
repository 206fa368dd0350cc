"""Layer 5, special points: detection, location by defining systems, two-parameter curves.

:mod:`~saltation.special_points.detection` (test functions for smooth bifurcations, changes of the
event sequence and their set-valued multipliers: the detector the continuation engine is handed),
:mod:`~saltation.special_points.continuation` (continuation with that detector:
:func:`continue_orbit`, :func:`continue_branch`), :mod:`~saltation.special_points.grazing` and
:mod:`~saltation.special_points.sliding` (the defining systems of grazing and of the sliding
bifurcations), :mod:`~saltation.special_points.loci` (curves of special points in two parameters),
:mod:`~saltation.special_points.branch_switching` (the period-2 branch at a period doubling) and
:mod:`~saltation.special_points.follow` (a branch as far as it goes: the branches born on it, and the one
beyond a discontinuous fold).
"""
