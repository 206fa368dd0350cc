"""Sensitivities of special points: how a located point moves with every other parameter of the model.

A special point of a branch in the parameter ``p`` is a solution of its defining system
``G(u, p; q) = 0``: the orbit's periodicity equations with the conditions that make the point special
attached (:mod:`saltation.orbits.conditions`), ``p`` freed, ``u = (x0, extras)`` the orbit's state and the
conditions' own unknowns, every other parameter ``q`` fixed.  The systems are those the two-parameter
curves follow (:mod:`saltation.special_points.loci`):

* fold and branch point: a multiplier at +1, period doubling: one at -1, minimally augmented
  (:class:`~saltation.orbits.conditions.MultiplierCondition`);
* grazing and the corners (discontinuous fold, flip and Neimark-Sacker, a jump without crossing, grazing-
  sliding): the virtual orbit tangent to the grazed surface (:class:`~saltation.orbits.conditions.Tangency`);
* crossing- and switching-sliding: the far field tangent where the orbit arrives at the surface
  (:class:`~saltation.orbits.conditions.ArrivalTangency`); adding-sliding: the exit field's cubic tangency
  on a sliding motion (:class:`~saltation.orbits.conditions.CubicTangency`).

Where ``[G_u G_p]`` is regular the point persists when ``q`` moves, and by the implicit function theorem

    d(u, p) / dq = -[G_u G_p]^-1 G_q,

one solve per parameter with the Jacobian already at hand; ``G_q`` is the same system with ``q`` as the
curve's parameter (the column two-parameter continuation takes).  :func:`sensitivities` relocates the
point by its defining system (to the integration's accuracy, tolerances tightened as for every location),
and returns ``d p / d q`` for every other parameter with the derivatives of the period and the state, and
an error estimate of each; :func:`add_sensitivities` stores ``d p / d q`` on a branch's special points
(:attr:`~saltation.branches.branch.SpecialPoint.sensitivities`), which files keep.

They are computed on demand, not when a point is located: each costs a relocation and one shot of the
period per parameter (with a fold or period doubling, ``2 (n + 2)`` further period maps per parameter for
the central differences of the test function, twice for the error estimate), about what locating the
point cost in the first place; most points are never asked, and a kind without a defining system here
(Neimark-Sacker, a symmetry breaking, a cycle collapse, the points of equilibria) would leave a hole anyway.

A branch point of a branch without symmetry is not persistent: under a generic change of ``q`` it
splits into two folds or none, and its defining system is singular there.  That is reported
(:class:`~saltation.errors.SaltationError`), not differentiated.
"""

from __future__ import annotations

import copy
import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from saltation.branches.branch import (
    Branch,
    SpecialPoint,
    SpecialPointKind,
    problem_and_point,
)
from saltation.errors import ModelError, SaltationError
from saltation.orbits.conditions import (
    ArrivalTangency,
    ConditionedProblem,
    CubicTangency,
    MultiplierCondition,
    Tangency,
)
from saltation.special_points.grazing import location_tolerances
from saltation.special_points.loci import (
    SLIDING_KINDS,
    _touch_of,
    arrival_identity,
    grazed_transitions,
)

_log = logging.getLogger(__name__)

__all__ = ["SINGULAR_CONDITION", "PointSensitivities", "add_sensitivities", "defining_system", "sensitivities"]

#: a defining system whose Jacobian has a larger condition number is singular: the point does not persist
SINGULAR_CONDITION = 1e12

#: the kinds located by a multiplier condition, and their multiplier
_MULTIPLIER_KINDS = {SpecialPointKind.FOLD: 1.0, SpecialPointKind.BRANCH_POINT: 1.0,
                     SpecialPointKind.PERIOD_DOUBLING: -1.0}


@dataclass(frozen=True)
class PointSensitivities:
    """How a special point moves with the model's other parameters (see the module's description).

    Attributes
    ----------
    kind : SpecialPointKind
        The point's kind.
    parameter_name : str
        The branch's parameter ``p``.
    parameter : float
        The point's value of ``p``, relocated by its defining system.
    location_accuracy : float
        The error estimate of that location (:meth:`ConditionedProblem.solve`).
    state : ndarray, shape (n,)
        The point's orbit's state at its section.
    period : float
        Its period.
    d_parameter : dict of str to float
        ``d p / d q`` for every other parameter ``q``, in the model's order.
    d_period : dict of str to float
        ``d T / d q`` (a forced orbit's period is its forcing period's, which moves with ``q`` and ``p``).
    d_state : dict of str to ndarray
        ``d x0 / d q`` (the state at the forced orbit's section ``t0``).
    accuracy : dict of str to float
        An error estimate of each ``d p / d q``: the integration's error carried through the inverse
        Jacobian, and for a multiplier condition the change when its central differences take twice the step.
    condition : float
        The condition number of the defining system's Jacobian ``[G_u G_p]``.
    """

    kind: SpecialPointKind
    parameter_name: str
    parameter: float
    location_accuracy: float
    state: np.ndarray
    period: float
    d_parameter: dict[str, float]
    d_period: dict[str, float]
    d_state: dict[str, np.ndarray]
    accuracy: dict[str, float]
    condition: float

    def __str__(self) -> str:
        lines = [f"{self.kind.value} at {self.parameter_name} = {self.parameter:.12g} (to {self.location_accuracy:.1e})"]
        width = max((len(q) for q in self.d_parameter), default=0)
        for q, value in self.d_parameter.items():
            lines.append(f"  d {self.parameter_name} / d {q:<{width}} = {value: .10g}  (to {self.accuracy[q]:.1e})")
        return "\n".join(lines)


def _own_copy(problem):
    """A copy of a branch's problem whose phase anchor and section this module may set (with multiple shooting,
    of its single-shooting problem too)."""
    own = copy.copy(problem)
    if hasattr(own, "problem"):
        own.problem = copy.copy(own.problem)
    return own


def defining_system(problem, point: SpecialPoint) -> tuple[ConditionedProblem, np.ndarray]:
    """The defining system of a special point of a branch: the branch's problem with the point's conditions
    attached and its parameter freed, and the unknowns to start from (the point's own).

    Which problems: single or multiple shooting, forced or autonomous, forward or backward time, for every
    kind whose defining condition the point says enough to write down.  A grazing or corner needs the
    transition touched and when: from the orbit itself for a forced forward-time orbit over one forcing
    period (:func:`~saltation.special_points.loci.grazed_transitions`), from the point's ``touch`` otherwise
    (a located grazing has one; a corner bracketed on such a branch has not).  A crossing- or
    switching-sliding needs its arrival named (:func:`~saltation.special_points.loci.arrival_identity`):
    forced forward-time orbits over one forcing period.  An autonomous orbit's fold has none here (its
    trivial multiplier makes ``M - I`` singular all along the branch); its period doubling has.  An
    autonomous orbit's phase is anchored at the point's state.

    Parameters
    ----------
    problem : ShootingProblem or MultipleShootingProblem
        The branch's problem (its continuation parameter set).  It is not changed: the system is built on a
        copy.
    point : SpecialPoint
        A fold, branch point or period doubling; a grazing or corner; a sliding bifurcation.

    Returns
    -------
    ConditionedProblem
        The system, its integration tolerances tightened as for a location
        (:func:`~saltation.special_points.grazing.location_tolerances`).
    ndarray
        Its unknowns at the point.

    Raises
    ------
    ModelError
        For a problem without a continuation parameter, or a kind (or a problem for that kind) without a
        defining system here: the message says which.
    SaltationError
        If the orbit touches no surface (a grazing or corner), or does not arrive at the surface (a
        sliding bifurcation), or its run fails.
    """
    if problem.lam_name is None:
        raise ModelError("the branch's problem has no continuation parameter: the special point's parameter is unknown")
    problem = _own_copy(problem)
    single = getattr(problem, "problem", problem)
    flow = problem.flow
    p = problem.parameters_at(point.parameter)
    state = np.asarray(point.state, dtype=float)
    kind = point.kind
    # the orbit's own touches and arrivals are read over one forcing period, forward in time
    plain = not problem.autonomous and not problem.backward and getattr(problem, "periods", 1) == 1
    what = ("an autonomous orbit" if problem.autonomous else "a backward-time orbit" if problem.backward
            else f"an orbit of {getattr(problem, 'periods', 1)} forcing periods")
    if kind in _MULTIPLIER_KINDS:
        mu = _MULTIPLIER_KINDS[kind]
        if problem.autonomous and mu > 0:
            raise ModelError(f"no defining system for the sensitivities of the {kind.value} of an autonomous orbit: its "
                             "trivial multiplier makes M - I singular all along the branch")
        conditions = [MultiplierCondition(mu)]
    elif kind in SLIDING_KINDS:
        if not point.touch_surface:
            raise ModelError(f"the {kind.value} point does not say where the orbit touches the surface")
        if kind is SpecialPointKind.ADDING_SLIDING:
            conditions = [CubicTangency(flow, point.touch_mode, point.touch_surface, float(point.touch_time))]
        elif plain:
            identity, t_e = arrival_identity(flow, state, p, point.touch_surface, float(point.touch_time),
                                             t0=single.t0, tolerances=single.tolerances)
            conditions = [ArrivalTangency(flow, identity, point.touch_mode, t_e)]
        else:
            raise ModelError(f"no defining system for the sensitivities of the {kind.value} of {what}: its arrival is "
                             "named for forced orbits in forward time over one forcing period")
    elif kind.is_nonsmooth:
        touched = _touch_of(single, point)
        if touched is not None and (kind is SpecialPointKind.GRAZING_SLIDING or not plain):
            transition, t_g, others = *touched, []  # (a grazing-sliding's run may slide for a rounding at the touch)
        elif plain:
            try:
                (transition, t_g), *others = grazed_transitions(flow, state, p, t0=single.t0,
                                                                tolerances=single.tolerances)
            except SaltationError:
                if touched is None:
                    raise
                transition, t_g, others = *touched, []
        else:
            raise ModelError(f"no defining system for the sensitivities of the {kind.value} of {what}: the point does "
                             "not say which surface its orbit touches, and when")
        conditions = [Tangency(flow, transition, t_g, also_disabled=[k for k, _ in others])]
    else:
        raise ModelError(f"no defining system for the sensitivities of special points of kind {kind.value} (those of "
                         "folds, branch points, period doublings, grazings, corners and sliding bifurcations)")
    if problem.autonomous:
        single.x_ref = single.f_ref = None  # (anchored at the point's state when the system is solved)
    system = ConditionedProblem(problem, conditions, free=(problem.lam_name,), parameters=p)
    system.tolerances = location_tolerances(flow, problem.tolerances)
    return system, system.pack(state, period=float(point.period) if problem.autonomous else None)


def _columns(system: ConditionedProblem, u: np.ndarray, p: np.ndarray, names: Sequence[str]
             ) -> tuple[np.ndarray, np.ndarray, object]:
    """``G_u`` (by the unknowns, the freed parameter among them) and ``G_q`` for each of ``names`` (a column
    each), and the shot there."""
    J, columns, shot = None, [], None
    for q in names:
        with_q = ConditionedProblem(system.base, system.conditions, free=system.free_names, continuation=q, parameters=p)
        with_q.tolerances = system.tolerances
        _, J_q, g_q, shot_q = with_q.equations(u, float(p[with_q.lam_index]), need_lam=True)
        if J is None:
            J, shot = J_q, shot_q
        columns.append(g_q)
    if J is None:  # no other parameter
        _, J, _, shot = system.equations(u, need_lam=False)
    return J, np.column_stack(columns) if columns else np.zeros((len(u), 0)), shot


def sensitivities(source, point: SpecialPoint | int, *, parameters: Sequence[str] | None = None,
                  tol: float = 1e-12) -> PointSensitivities:
    """``d p / d q`` of a special point for every other parameter ``q``, by the implicit function theorem on its
    defining system (see the module's description), with the derivatives of its period and state.

    Parameters
    ----------
    source : Branch or ShootingProblem
        The branch (it holds its problem), or its problem (its continuation parameter set; which problems,
        for which kinds: :func:`defining_system`).
    point : SpecialPoint or int
        The special point, or its index in ``branch.special_points``.
    parameters : sequence of str, optional
        The parameters ``q`` (every parameter of the model but the branch's by default).
    tol : float
        The Newton tolerance of the relocation.

    Returns
    -------
    PointSensitivities
        The relocated point and its derivatives, each with an error estimate.

    Raises
    ------
    ModelError
        For a problem or a kind without a defining system here (see :func:`defining_system`), or a name that
        is not a parameter of the model (or is the branch's own).
    SaltationError
        If the branch holds no problem, the point cannot be relocated by its defining system (or is
        relocated farther from where it was found than their accuracies allow), or the system is singular
        there (a branch point: the point does not persist).

    References
    ----------
    Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM (minimally
    augmented systems; the implicit function theorem on defining systems).  Dankowicz and Schilder (2013),
    *Recipes for Continuation*, SIAM (an orbit problem extended by zero functions).
    """
    problem, point = problem_and_point(source, point, "the sensitivities of a special point")
    problem = _own_copy(problem)  # (the user's problem is left as it is)
    getattr(problem, "align_section", lambda point: None)(point)  # (the point's state lies at its own section)
    system, u0 = defining_system(problem, point)
    sys_ = problem.system
    lam = problem.lam_name
    names = [q for q in sys_.parameter_names if q != lam] if parameters is None else list(parameters)
    for q in names:
        if q == lam:
            raise ModelError(f"{q!r} is the branch's own parameter: d {q} / d {q} = 1")
        sys_.parameter_index(q)
    located = system.solve(u0, tol=tol, what=f"the {point.kind.value} point")
    u, p = located.unknowns, located.parameters
    lam_index = sys_.parameter_index(lam)
    found = float(p[lam_index])
    claimed = point.accuracy if np.isfinite(point.accuracy) else np.inf  # (a point known only so well)
    allowed = 100.0 * (max(claimed, 0.0) + float(located.accuracy[0])) + 1e-7 * (1.0 + abs(found))
    if not abs(found - point.parameter) <= allowed:
        raise SaltationError(f"the {point.kind.value} point at {lam} = {point.parameter:.12g} was relocated by its "
                             f"defining system at {found:.12g}, farther than their accuracies allow ({allowed:.1e})")
    J, G, shot = _columns(system, u, p, names)
    condition = float(np.linalg.cond(J))
    if not condition < SINGULAR_CONDITION:
        raise SaltationError(
            f"the defining system of the {point.kind.value} point at {lam} = {found:.12g} is singular (condition "
            f"number {condition:.1e}): the point does not persist as a smooth function of the other parameters"
            + (" (a branch point splits into folds or none)" if point.kind is SpecialPointKind.BRANCH_POINT else ""))
    inverse = np.linalg.inv(J)
    V = -inverse @ G
    traj = shot.trajectory
    relative = system.flow.integration_error(traj, system.tolerances) / (1.0 + float(np.abs(traj.x1).max())) + 1e-15
    bound = np.abs(inverse) @ (relative * (np.abs(J) @ np.abs(V) + np.abs(G)))
    k = system.n_base  # the freed parameter's place among the unknowns
    error = bound[k] + 4e-16 * np.maximum(1.0, np.abs(V[k]))
    if any(isinstance(c, MultiplierCondition) for c in system.conditions):
        # the test function's derivatives are central differences: the change with twice their step
        doubled = []
        for c in system.conditions:
            c2 = copy.copy(c)
            if isinstance(c2, MultiplierCondition):
                c2.h, c2._kept = 2.0 * c.h, None
            doubled.append(c2)
        twice = ConditionedProblem(system.base, doubled, free=system.free_names, parameters=p)
        twice.tolerances = system.tolerances
        J2, G2, _ = _columns(twice, u, p, names)
        error = error + np.abs(V[k] - (-np.linalg.solve(J2, G2))[k])
    n = sys_.n
    d_parameter = {q: float(V[k, c]) for c, q in enumerate(names)}
    if problem.autonomous:  # the period is an unknown
        d_period = {q: float(V[system.n_nodes, c]) for c, q in enumerate(names)}
    else:
        periods = getattr(problem, "periods", 1)
        d_period = {q: periods * (sys_.period_derivative(p, sys_.parameter_index(q))
                                  + sys_.period_derivative(p, lam_index) * d_parameter[q]) for q in names}
    return PointSensitivities(
        kind=point.kind, parameter_name=lam, parameter=found, location_accuracy=float(located.accuracy[0]),
        state=np.array(located.state0), period=float(located.period), d_parameter=d_parameter, d_period=d_period,
        d_state={q: V[:n, c].copy() for c, q in enumerate(names)},
        accuracy={q: float(error[c]) for c, q in enumerate(names)}, condition=condition,
    )


def add_sensitivities(branch: Branch, *, parameters: Sequence[str] | None = None) -> list[PointSensitivities | None]:
    """Store on each special point of a branch how its parameter moves with the other parameters
    (:attr:`SpecialPoint.sensitivities <saltation.branches.branch.SpecialPoint.sensitivities>`, ``d p / d q``
    by :func:`sensitivities`).

    The branch's ``special_points`` are replaced by copies with ``sensitivities`` set; a point whose kind
    has no defining system here, or whose system fails or is singular, keeps ``None`` (the reason is logged).

    Parameters
    ----------
    branch : Branch
        A branch as continuation returned it (it holds its problem).
    parameters : sequence of str, optional
        The parameters ``q`` (every other parameter by default).

    Returns
    -------
    list of PointSensitivities or None
        One per special point, in their order (None where there is none).

    Raises
    ------
    SaltationError
        If the branch holds no problem (it was read from a file).
    """
    if branch.problem is None and branch.special_points:
        raise SaltationError("the sensitivities of a branch's special points: this branch holds no problem (it was read "
                             "from a file); pass its problem to sensitivities(problem, point)")
    found: list[PointSensitivities | None] = []
    for i, sp in enumerate(branch.special_points):
        try:
            result = sensitivities(branch, i, parameters=parameters)
        except SaltationError as exc:  # (ModelError too)
            _log.info("%s at %s = %.10g: no sensitivities (%s)", sp.kind.value, branch.parameter_name, sp.parameter, exc)
            found.append(None)
            continue
        found.append(result)
        branch.special_points[i] = replace(sp, sensitivities=dict(result.d_parameter))
    return found
