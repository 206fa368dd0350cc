"""Layer 3, orbits: periodic solutions, equilibria, their multipliers and one-sided limits.

Depends on the engine and the model.  Its modules:

- :mod:`~saltation.orbits.problem`: the problem base of every branch (:class:`BranchProblem`), the plain
  Newton iteration, its accuracy estimate and the bordered solve;
- :mod:`~saltation.orbits.records`: what a solved point leaves (:class:`PeriodicOrbit`, branch points);
- :mod:`~saltation.orbits.single`: periodic orbits by single shooting (:class:`ShootingProblem`);
- :mod:`~saltation.orbits.multiple`: periodic orbits by multiple shooting;
- :mod:`~saltation.orbits.seam`: the seam rule, an event at both ends of a shot counted once;
- :mod:`~saltation.orbits.equilibria`: equilibria of one mode;
- :mod:`~saltation.orbits.pseudo_equilibria`: rest points of a sliding motion;
- :mod:`~saltation.orbits.start`: start guesses and the everyday :func:`find_periodic_orbit`;
- :mod:`~saltation.orbits.conditions`: defining conditions attached to an orbit (special points, curves);
- :mod:`~saltation.orbits.floquet`: Floquet multipliers from the monodromy matrix;
- :mod:`~saltation.orbits.classification`: the set-valued classification of a corner from its one-sided
  monodromies;
- :mod:`~saltation.orbits.border_collision`: Feigin's classification of a border collision from the one-sided
  multipliers (persistence, non-smooth fold, a period-two orbit);
- :mod:`~saltation.orbits.parameter_jacobian`: the derivatives of an orbit's initial state and period by the
  parameters (implicit function theorem on the periodicity equations);
- :mod:`~saltation.orbits.boundary`: the one-sided monodromies at a boundary orbit, exact limits;
- :mod:`~saltation.orbits.symmetry`: symmetric orbits by the half-period map;
- :mod:`~saltation.orbits.lyapunov`: Lyapunov exponents;
- :mod:`~saltation.orbits.phase_response`: phase response curves of autonomous orbits, the adjoint carried through
  the events by the transposed saltation matrices, and their parameter derivatives;
- :mod:`~saltation.orbits.second_order`: second derivatives of the period map, exact through the events;
- :mod:`~saltation.orbits.criticality`: criticality of period doublings and Neimark-Sacker points, from the
  period map's normal form;
- :mod:`~saltation.orbits.measures`: scalar measures of an orbit (``max |x|``, ``norm``, an expression's largest
  value) that branches record and figures plot;
- :mod:`~saltation.orbits.on_surface`: orbits that lie on a switching surface;
- :mod:`~saltation.orbits.shooting`: the names of release 0.1's shooting module (goes in 0.3.0).
"""
