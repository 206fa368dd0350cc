"""Continuation with special points: the engine of :mod:`saltation.branches.continuation` handed the
detector of :mod:`saltation.special_points.detection`.

These are the everyday entry points (:func:`saltation.continue_orbit`,
:func:`saltation.continue_branch`): every step is checked for folds, period doublings, Neimark-Sacker
and Hopf points, changes of the event sequence (corners, grazings, the sliding bifurcations, with
their set-valued multipliers) and cycle collapses, each located and recorded in the branch.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from saltation.branches import continuation as engine
from saltation.branches.branch import Branch
from saltation.branches.continuation import (
    ContinuationSettings,
    Corrector,
    Solution,
    canonical_events,
)
from saltation.errors import ModelError, SaltationError
from saltation.kinds import SpecialPointKind
from saltation.orbits.multiple import MultipleShootingProblem
from saltation.orbits.records import PeriodicOrbit
from saltation.orbits.single import ShootingProblem
from saltation.special_points.detector import SpecialPointDetector

_log = logging.getLogger(__name__)


class Continuation(engine.Continuation):
    """:class:`saltation.branches.continuation.Continuation` with the special-point detector.

    The detector is :class:`~saltation.special_points.detection.SpecialPointDetector` unless another is
    given.

    Parameters
    ----------
    problem : ShootingProblem or EquilibriumProblem
        The problem, with its continuation parameter set.
    settings : ContinuationSettings, optional
        The options (``ContinuationSettings()`` by default).
    detector : callable, optional
        ``detector(problem, corrector, branch)`` makes the detector; None finds no special points.

    Raises
    ------
    SaltationError
        If the problem has no continuation parameter.
    """

    def __init__(self, problem, settings: ContinuationSettings | None = None, *,
                 detector: engine.DetectorFactory | None = SpecialPointDetector):
        super().__init__(problem, settings, detector=detector)


def continue_branch(
    problem,
    u0: np.ndarray,
    lam0: float | None = None,
    *,
    settings: ContinuationSettings | None = None,
    directions: tuple[int, ...] = (1, -1),
    label: str = "",
    progress=None,
    detector: engine.DetectorFactory | None = SpecialPointDetector,
) -> Branch:
    """Follow a branch from a start point in one or both directions, with its special points.

    As :func:`saltation.branches.continuation.continue_branch`, with the special-point detector
    by default (``settings.detect = False`` or ``detector=None`` turn it off).

    Parameters
    ----------
    problem : ShootingProblem or EquilibriumProblem
        The problem, with its continuation parameter set (any problem of the protocol).
    u0 : ndarray
        Guess of the unknowns at the start (see ``problem.pack``).
    lam0 : float, optional
        Start value of the parameter (the problem's value by default).
    settings : ContinuationSettings, optional
        Step sizes, bounds and tolerances (``ContinuationSettings()`` by default).
    directions : tuple of int
        +1 (increasing parameter first), -1, or both.
    label : str
        A label for the branch (legends, files).
    progress : callable, optional
        Called with each new BranchPoint.
    detector : callable, optional
        Makes the special-point detector (:class:`SpecialPointDetector` by default; None finds none).

    Returns
    -------
    Branch
        The points of every direction, the special points located on the way and each run's stop
        reason.

    Raises
    ------
    SaltationError
        If no direction is given, the problem has no continuation parameter, ``lam0`` lies outside
        the bounds, or the start point cannot be corrected (a :class:`ConvergenceError`, or the error
        of the problem's evaluation).

    References
    ----------
    Keller (1977), "Numerical solution of bifurcation and nonlinear eigenvalue problems", in
    Rabinowitz (ed.), *Applications of Bifurcation Theory*, Academic Press (pseudo-arclength
    continuation).  Leine and Van Campen, "Fold bifurcations in discontinuous systems"
    (set-valued multipliers at the corners).
    """
    branch = engine.continue_branch(problem, u0, lam0, settings=settings, directions=directions, label=label,
                                    progress=progress, detector=detector)
    if detector is not None:
        add_criticality(branch)
    return branch


def add_criticality(branch: Branch) -> Branch:
    """Give the period doublings and Neimark-Sacker points of a branch their criticality.

    Each point's orbit is solved again and the cubic coefficient of its period map's normal form computed
    (:func:`saltation.orbits.criticality.special_point_criticality`): ``SpecialPoint.criticality`` and
    ``SpecialPoint.normal_form``.  Where it cannot be computed (a model of compiled callables, a strong
    resonance, an event sequence that changes within the differences' steps, a branch without its problem),
    the point keeps None and the log says why.

    Parameters
    ----------
    branch : Branch
        A branch with the problem it was computed with.

    Returns
    -------
    Branch
        The same branch, its special points replaced.

    Raises
    ------
    None
        A point whose criticality cannot be computed keeps None (its reason is logged).
    """
    from saltation.orbits.criticality import special_point_criticality

    kinds = (SpecialPointKind.PERIOD_DOUBLING, SpecialPointKind.NEIMARK_SACKER)
    if branch.problem is None or not any(sp.kind in kinds for sp in branch.special_points):
        return branch
    points = []
    for sp in branch.special_points:
        if sp.kind in kinds and sp.criticality is None:
            try:
                nf = special_point_criticality(branch, sp)
            except SaltationError as exc:
                _log.info("the criticality of the %s at %s = %.10g is not known: %s", sp.kind.value,
                          branch.parameter_name, sp.parameter, exc)
            else:
                sp = replace(sp, criticality=nf.criticality, normal_form=(nf.coefficient, nf.accuracy))
        points.append(sp)
    branch.special_points = points
    return branch


def continue_orbit(
    orbit: PeriodicOrbit,
    parameter: str,
    *,
    bounds: tuple[float, float],
    directions: tuple[int, ...] = (1, -1),
    settings: ContinuationSettings | None = None,
    segments: int | None = None,
) -> Branch:
    """Follow the branch of a periodic orbit in one parameter, with its special points.

    The direct path from :func:`saltation.orbits.shooting.find_periodic_orbit` to a
    branch: the orbit's own flow, parameter values, time direction, section
    and tolerances are kept, and so is its start mode where it was found from one (``mode0``, a
    memory mode): every point's shooting starts in the orbit's :attr:`~PeriodicOrbit.mode0`, and
    each branch point records it.

    Parameters
    ----------
    orbit : PeriodicOrbit
        A periodic orbit found by shooting.
    parameter : str
        The continuation parameter.
    bounds : (float, float)
        Its interval.
    directions : tuple of int
        ``(1, -1)``: both ways from the orbit; ``(1,)`` or ``(-1,)``: one.
    settings : ContinuationSettings, optional
        Step sizes and tolerances (``bounds`` overrides theirs).
    segments : int, optional
        Shooting segments (the orbit's own by default): ``m > 1`` follows the branch by multiple
        shooting (:class:`~saltation.orbits.shooting.MultipleShootingProblem`), the multipliers of each
        point from the segments' matrices by the periodic Schur decomposition.  The jump through a
        grazing that stalls the corrector and the cycle-collapse test are those of single shooting
        and are not run; special points are located by their single-shooting defining systems.

    Returns
    -------
    Branch
        The orbit's branch, with its special points (folds, period doublings, Neimark-Sacker points,
        corners, grazings, sliding bifurcations, cycle collapses) and stop reasons.

    Raises
    ------
    ModelError
        For an unknown parameter, an orbit that does not know its problem, or an invalid number of
        segments.
    ValueError
        If ``bounds`` is not increasing.
    SaltationError
        If the orbit's parameter value lies outside ``bounds``, or its point cannot be corrected again
        (see :meth:`Continuation.run`).

    References
    ----------
    Keller (1977), "Numerical solution of bifurcation and nonlinear eigenvalue problems", in
    Rabinowitz (ed.), *Applications of Bifurcation Theory*, Academic Press (pseudo-arclength
    continuation).  Leine and Van Campen, "Fold bifurcations in discontinuous systems"
    (set-valued multipliers at the corners).
    """
    base = orbit.problem
    if base is None:
        raise ModelError("this orbit does not know the problem that found it: build a ShootingProblem instead")
    system = base.system
    system.parameter_index(parameter)  # names the parameter in its error
    values = dict(zip(system.parameter_names, map(float, orbit.parameters)))
    # a start mode the orbit was found from (a memory mode) is kept along the branch: the orbit's own
    problem = ShootingProblem(base.flow, values, continuation_parameter=parameter, backward=orbit.backward,
                              t0=orbit.t0, tolerances=base.tolerances, periods=base.periods,
                              mode0=None if base.mode0 is None else orbit.mode0)
    settings = replace(settings or ContinuationSettings(), bounds=tuple(bounds))
    u0 = problem.pack(orbit.state0, orbit.period if orbit.autonomous else None)
    m = orbit.segments if segments is None else segments
    if m != 1:
        multiple = MultipleShootingProblem(problem, m)
        if orbit.nodes is not None and len(orbit.nodes) == multiple.segments:
            nodes = np.asarray(orbit.nodes, dtype=float).ravel()
            u0 = np.append(nodes, orbit.period) if orbit.autonomous else nodes
        else:
            u0 = multiple.pack(u0)
        return continue_branch(multiple, u0, values[parameter], settings=settings, directions=directions)
    return continue_branch(problem, u0, values[parameter], settings=settings, directions=directions)


__all__ = [
    "Continuation", "ContinuationSettings", "Corrector", "Solution", "add_criticality", "canonical_events",
    "continue_branch", "continue_orbit",
]
