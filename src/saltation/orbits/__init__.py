"""Layer 3, orbits: periodic solutions, their multipliers and one-sided limits.

:mod:`~saltation.orbits.shooting` (the periodic-orbit and equilibrium problems, Newton, the
everyday :func:`~saltation.orbits.shooting.find_periodic_orbit`), :mod:`~saltation.orbits.floquet`
(Floquet multipliers from the monodromy matrix) and :mod:`~saltation.orbits.boundary` (the
one-sided monodromies at a boundary orbit, exact limits).  Depends on the engine and the model.
"""
