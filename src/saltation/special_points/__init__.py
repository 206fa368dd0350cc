"""Layer 5, special points: detection, location by defining systems, two-parameter curves.

Modules:

* :mod:`~saltation.special_points.detector`: the detector the continuation engine is handed
  (:class:`SpecialPointDetector`), the sequence of detection at each step;
* :mod:`~saltation.special_points.context`: what the detector's parts share (its context, multiplier helpers);
* :mod:`~saltation.special_points.smooth`: test functions of smooth bifurcations, their location on the secant;
* :mod:`~saltation.special_points.nonsmooth`: bracketing a change of the event sequence, one-sided limits;
* :mod:`~saltation.special_points.symmetric`: the half-period map of symmetric orbits, symmetry breaking;
* :mod:`~saltation.special_points.points`: the records of the special points the detector finds;
* :mod:`~saltation.special_points.detection`: the detector's former path, re-exporting its names until 0.3.0;
* :mod:`~saltation.special_points.continuation`: continuation with that detector (:func:`continue_orbit`,
  :func:`continue_branch`);
* :mod:`~saltation.special_points.grazing`: the defining systems of grazing;
* :mod:`~saltation.special_points.sliding`: the defining systems of the sliding bifurcations;
* :mod:`~saltation.special_points.boundary_equilibria`: equilibria on a switching surface and their curves;
* :mod:`~saltation.special_points.loci`: curves of special points in two parameters;
* :mod:`~saltation.special_points.codimension_two`: the smooth codimension-two points along fold,
  period-doubling and Neimark-Sacker curves (test functions, their location);
* :mod:`~saltation.special_points.branch_switching`: the period-2 branch at a period doubling and the
  asymmetric branches at a symmetry breaking;
* :mod:`~saltation.special_points.follow`: a branch as far as it goes: the branches born on it, and the one
  beyond a discontinuous fold;
* :mod:`~saltation.special_points.sensitivity`: how a located special point moves with every other parameter
  (the implicit function theorem on its defining system).
"""
