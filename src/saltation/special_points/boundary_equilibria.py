"""Boundary-equilibrium bifurcations: where an equilibrium of a mode reaches a switching surface.

On a branch of pseudo-equilibria (:class:`~saltation.orbits.pseudo_equilibria.PseudoEquilibriumProblem`)
the weight ``a`` of the sliding combination leaves ``(0, 1)`` where one of the two fields vanishes on the
surface: there the pseudo-equilibrium is an equilibrium of that mode, on its boundary.  The point is
located by its defining system, the mode's equilibrium plus ``h = 0`` (unknowns ``(x, lam)``, exact
Jacobians), and classified by where the two equilibria are admissible: on opposite sides of the point the
one persists as the other (``persistence``); on the same side they meet and vanish together
(``nonsmooth_fold``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import replace as _replace

import numpy as np

from saltation.branches.branch import (
    Branch,
    SpecialPoint,
    SpecialPointKind,
    SpecialPointStatus,
    Touch,
    problem_and_point,
)
from saltation.errors import ConvergenceError, ModelError, SaltationError
from saltation.orbits.equilibria import EquilibriumProblem
from saltation.orbits.problem import BranchProblem
from saltation.orbits.pseudo_equilibria import (
    PseudoEquilibriumProblem,
    find_pseudo_equilibrium,
)
from saltation.orbits.pseudo_equilibria import sliding_weight as pseudo_weight


def sliding_weight(problem: PseudoEquilibriumProblem, state: np.ndarray, lam: float) -> float:
    """The weight ``a`` of the positive side's field in the sliding combination at ``state``.

    Parameters
    ----------
    problem : PseudoEquilibriumProblem
    state : ndarray, shape (n,)
    lam : float
        Value of the continuation parameter.

    Returns
    -------
    float
        ``h_x f_minus / (h_x f_minus - h_x f_plus)`` (``nan`` where the two are equal).
    """
    return pseudo_weight(problem.flow, problem.surface, problem.minus, problem.plus, np.asarray(state, dtype=float),
                         problem.parameters_at(lam))


def boundary_equilibria(problem: PseudoEquilibriumProblem, branch: Branch, *, tol: float = 1e-12) -> list[SpecialPoint]:
    """The boundary equilibria between consecutive points of a branch of pseudo-equilibria.

    Parameters
    ----------
    problem : PseudoEquilibriumProblem
        The branch's problem.
    branch : Branch
    tol : float
        Newton tolerance of the defining system.

    Returns
    -------
    list of SpecialPoint
        Of kind BOUNDARY_EQUILIBRIUM, located (``accuracy`` the last Newton correction in the parameter),
        with the mode's equilibrium's eigenvalues as ``multipliers``, the mode in ``touch_mode``, the
        surface in ``touch_surface`` and the ``classification``.

    Raises
    ------
    ConvergenceError
        If a bracketed point cannot be located.

    References
    ----------
    M. di Bernardo, C. J. Budd, A. R. Champneys and P. Kowalczyk (2008), *Piecewise-smooth Dynamical
    Systems: Theory and Applications*, Springer, section 5.2 (boundary-equilibrium bifurcations).
    Yu. A. Kuznetsov, S. Rinaldi and A. Gragnani (2003), "One-parameter bifurcations in planar Filippov
    systems", International Journal of Bifurcation and Chaos 13.
    """
    points = branch.points
    weights = [sliding_weight(problem, pt.state, pt.parameter) for pt in points]
    found = []
    for i in range(len(points) - 1):
        for edge, mode in ((0.0, problem.minus), (1.0, problem.plus)):
            w0, w1 = weights[i] - edge, weights[i + 1] - edge
            if not (math.isfinite(w0) and math.isfinite(w1)) or not _changes_sign(w0, w1):
                continue
            s = w0 / (w0 - w1)
            x = (1 - s) * points[i].state + s * points[i + 1].state
            lam = (1 - s) * points[i].parameter + s * points[i + 1].parameter
            x, lam, step = _locate(problem, problem.surface, mode, x, lam, tol)
            inside = points[i + 1] if 0.0 < weights[i + 1] < 1.0 else points[i]  # the admissible pseudo side
            pseudo_side = math.copysign(1.0, inside.parameter - lam)
            sign = -1.0 if mode == problem.minus else 1.0  # the negative side's mode lives where h < 0
            span = abs(points[i + 1].parameter - points[i].parameter)
            regular_side = _admissible_side(problem, problem.surface, mode, sign, x, lam, span)
            found.append(_with_cycle(problem, _record(problem, problem.surface, mode, x, lam, step, i, points,
                                                      "nonsmooth_fold" if regular_side == pseudo_side else "persistence"),
                                     span))
    return found


def boundary_equilibria_of_mode(problem: EquilibriumProblem, branch: Branch, *, tol: float = 1e-12) -> list[SpecialPoint]:
    """The boundary equilibria of a branch of one mode's equilibria: where the equilibrium crosses a surface that
    one of the mode's transitions watches.

    The partner that meets it there is the pseudo-equilibrium of the sliding motion when the surface slides
    at the point, otherwise the equilibrium of the mode across the surface; the classification compares the
    sides of the point where each is admissible (in its own region, or in the sliding region).

    Parameters
    ----------
    problem : EquilibriumProblem
        The branch's problem.
    branch : Branch
    tol : float
        Newton tolerance of the defining system.

    Returns
    -------
    list of SpecialPoint
        As :func:`boundary_equilibria`.

    Raises
    ------
    ConvergenceError
        If a bracketed point cannot be located.

    References
    ----------
    M. di Bernardo, C. J. Budd, A. R. Champneys and P. Kowalczyk (2008), *Piecewise-smooth Dynamical
    Systems: Theory and Applications*, Springer, section 5.2.
    """
    system, flow, mode = problem.system, problem.flow, problem.mode
    points = branch.points
    found = []
    for transition in system.transitions:
        if system.mode_index(transition.source) != mode:
            continue
        surface, sign = transition.surface, -float(int(transition.direction))  # the mode lives where h has this sign
        values = [flow.indicator(surface, 0.0, pt.state, problem.parameters_at(pt.parameter)) for pt in points]
        for i in range(len(points) - 1):
            if not _changes_sign(values[i], values[i + 1]):
                continue
            s = values[i] / (values[i] - values[i + 1])
            x = (1 - s) * points[i].state + s * points[i + 1].state
            lam = (1 - s) * points[i].parameter + s * points[i + 1].parameter
            x, lam, step = _locate(problem, surface, mode, x, lam, tol)
            span = abs(points[i + 1].parameter - points[i].parameter)
            regular_side = _admissible_side(problem, surface, mode, sign, x, lam, span)
            partner_side = _partner_side(problem, surface, system.mode_index(transition.target), -sign, x, lam, span)
            found.append(_with_cycle(problem, _record(problem, surface, mode, x, lam, step, i, points,
                                                      "nonsmooth_fold" if regular_side == partner_side else "persistence"),
                                     span))
    return found


def _changes_sign(a: float, b: float) -> bool:
    """``a`` and ``b`` on opposite sides of 0, a zero at ``b`` counting (a branch point exactly on the edge is
    found once, from the step that ends on it) and a zero at ``a`` not."""
    return (a < 0.0 <= b) or (a > 0.0 >= b)


def _record(problem, surface: str, mode: int, x: np.ndarray, lam: float, step: float, i: int, points,
            classification: str) -> SpecialPoint:
    eig = np.linalg.eigvals(problem.flow.vector_field_jacobian(mode, 0.0, x, problem.parameters_at(lam)))
    name = problem.system.mode_names[mode]
    return SpecialPoint(
        kind=SpecialPointKind.BOUNDARY_EQUILIBRIUM, parameter=lam,
        bracket=(float(points[i].parameter), float(points[i + 1].parameter)), accuracy=step, index=i,
        state=x, period=math.nan, amplitude=float(abs(x[0])), multipliers=eig.astype(complex),
        note=f"the equilibrium of {name!r} on surface {surface!r}", touch=Touch(surface, name),
        status=SpecialPointStatus.LOCATED, classification=classification,
    )


#: how long a planar system is simulated near a boundary equilibrium to see whether a cycle attracts: this
#: many turns of the mode's focus (or time units where its eigenvalues are real)
CYCLE_TURNS = 60


@dataclass(frozen=True)
class BoundaryCycle:
    """An attracting cycle that a boundary equilibrium creates or destroys (planar models).

    Attributes
    ----------
    kind : str
        ``sliding`` (the cycle has a sliding segment) or ``crossing``.
    side : int
        +1 where it exists for parameters above the point, -1 below.
    parameter : float
        Where it was computed (``delta`` from the point).
    period : float
    size : float
        Its largest extent in any state.
    state : ndarray
        A state of it.
    sizes : tuple of float
        Its sizes at ``delta`` and ``delta / 2``: it shrinks onto the point.
    """

    kind: str
    side: int
    parameter: float
    period: float
    size: float
    state: np.ndarray
    sizes: tuple[float, float]

    def describe(self, name: str, at: float) -> str:
        """The sentence a special point's note carries.

        Parameters
        ----------
        name : str
            The parameter's name.
        at : float
            The boundary equilibrium's parameter.

        Returns
        -------
        str
        """
        where = f"{name} {'>' if self.side > 0 else '<'} {at:.6g}"
        return (f"an attracting {self.kind} cycle surrounds it for {where} (period {self.period:.4g}, size "
                f"{self.size:.3g} at {name} = {self.parameter:.6g}), shrinking onto it")


def cycle_at_boundary_equilibrium(problem, point: SpecialPoint, span: float) -> BoundaryCycle | None:
    """For a planar model: the attracting cycle that a boundary equilibrium creates or destroys (None where
    none is found).

    On each side of the point, at ``delta = span / 20`` and ``delta / 2`` from it, the model is simulated from
    beside the mode's equilibrium (virtual or not) for :data:`CYCLE_TURNS` turns; where the motion does not
    come to rest, the cycle it reaches is found by shooting
    (:func:`~saltation.orbits.shooting.find_periodic_orbit`).  A cycle that shrinks onto the point with
    ``delta`` (its size at ``delta / 2`` between 0.3 and 0.8 of its size at ``delta``: the linear scaling of
    a piecewise-linear normal form, or a square root) is reported, named by its events: a *sliding* cycle
    (a sliding segment) or a *crossing* cycle.  Only attracting cycles are found (a Filippov system is not
    simulated in backward time).

    Parameters
    ----------
    problem : EquilibriumProblem or PseudoEquilibriumProblem
        The branch's problem (its flow and continuation parameter).
    point : SpecialPoint
        A located ``boundary_equilibrium`` (its state, parameter and ``touch_mode``).
    span : float
        The length of the branch step that held the point (sets ``delta``).

    Returns
    -------
    BoundaryCycle or None
        None when the model is not planar or no such cycle is found.

    Raises
    ------
    SaltationError
        Never: a side whose simulation or shooting fails is reported as having no cycle.

    References
    ----------
    Yu. A. Kuznetsov, S. Rinaldi and A. Gragnani (2003), "One-parameter bifurcations in planar Filippov
    systems", International Journal of Bifurcation and Chaos 13 (boundary foci and the cycles they create).
    """
    from saltation.engine.flow import EventKind
    from saltation.orbits.start import find_periodic_orbit

    flow, system = problem.flow, problem.system
    if system.n != 2:
        return None
    mode = system.mode_index(point.touch_mode)
    eig = np.asarray(point.multipliers, dtype=complex)
    turn = 2.0 * math.pi / float(np.max(np.abs(eig.imag))) if np.max(np.abs(eig.imag)) > 1e-9 else 1.0
    delta = max(span, 1e-6) / 20.0
    for side in (1.0, -1.0):
        sizes = []
        for d in (delta, 0.5 * delta):
            lam = point.parameter + side * d
            p = problem.parameters_at(lam)
            try:
                near = _mode_equilibrium(flow, mode, np.asarray(point.state, dtype=float), p)
                # (an equilibrium that stays put while the surface moves: the start is set off by delta)
                reach = max(float(np.linalg.norm(near - point.state)), d)
                start = near + 0.5 * reach * np.array([1.0, 1.0]) / math.sqrt(2.0)
                end = flow.run(start, 0.0, CYCLE_TURNS * turn, p).x1
                last = flow.run(end, 0.0, 2.0 * turn, p)
                if float(np.max(last.x_max - last.x_min)) <= max(1e-6 * reach, 1e-9 * (1.0 + float(np.linalg.norm(end)))):
                    break  # the motion comes to rest: no attracting cycle on this side
                orbit = find_periodic_orbit(flow, end, parameters=p, period=_recurrence(last.events))
                once = flow.run(orbit.state0, 0.0, orbit.period, p)
            except (SaltationError, np.linalg.LinAlgError):
                break
            sizes.append((lam, orbit, float(np.max(once.x_max - once.x_min))))
        if len(sizes) == 2 and sizes[0][2] > 0.0 and 0.3 <= sizes[1][2] / sizes[0][2] <= 0.8:
            lam, orbit, size = sizes[0]
            kind = "sliding" if any(e.kind == EventKind.SLIDING_START for e in orbit.events) else "crossing"
            return BoundaryCycle(kind=kind, side=int(side), parameter=lam, period=float(orbit.period), size=size,
                                 state=np.array(orbit.state0), sizes=(sizes[0][2], sizes[1][2]))
    return None


def _with_cycle(problem, point: SpecialPoint, span: float) -> SpecialPoint:
    """The point, its note naming the attracting cycle it creates or destroys (planar models), if any."""
    cycle = cycle_at_boundary_equilibrium(problem, point, span)
    if cycle is None:
        return point
    return _replace(point, note=f"{point.note}; {cycle.describe(problem.lam_name, point.parameter)}")


def _recurrence(events) -> float | None:
    """The time between the first event of a run and the next event of the same signature (None without)."""
    if not events:
        return None
    first = events[0]
    again = next((e for e in events[1:] if e.signature == first.signature), None)
    return None if again is None else abs(again.t - first.t)


def _mode_equilibrium(flow, mode: int, x: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Newton on one mode's field from ``x`` (the equilibrium may be virtual)."""
    y = x.copy()
    for _ in range(30):
        dy = np.linalg.solve(flow.vector_field_jacobian(mode, 0.0, y, p), flow.vector_field(mode, 0.0, y, p))
        y = y - dy
        if np.linalg.norm(dy) <= 1e-14 * (1.0 + np.linalg.norm(y)):
            return y
    raise ConvergenceError("the mode's equilibrium near a boundary equilibrium: Newton did not converge", [])


def _partner_side(problem, surface: str, other: int, other_sign: float, x: np.ndarray, lam: float, span: float) -> float:
    """Where the equilibrium's partner is admissible: the pseudo-equilibrium if the surface slides there, else
    the equilibrium of the mode across the surface (0 where neither is)."""
    delta = 1e-3 * max(span, 1e-6)
    for side in (1.0, -1.0):
        try:
            point = find_pseudo_equilibrium(problem.flow, surface, x, parameters=problem.parameters_at(lam + side * delta))
        except SaltationError:
            continue
        if point.admissible:
            return side
    return _admissible_side(problem, surface, other, other_sign, x, lam, span)


def _locate(problem, surface: str, mode: int, x: np.ndarray, lam: float, tol: float):
    """Newton on ``f_mode(x, lam) = 0``, ``h(x, lam) = 0``: the point, the parameter and the last correction."""
    flow, n, k = problem.flow, problem.system.n, problem.lam_index
    history = []
    step = math.inf
    for _ in range(30):
        p = problem.parameters_at(lam)
        f = flow.vector_field(mode, 0.0, x, p)
        hx, _, hp = flow.indicator_gradient(surface, 0.0, x, p)
        r = np.append(f, flow.indicator(surface, 0.0, x, p))
        history.append(float(np.linalg.norm(r)))
        J = np.zeros((n + 1, n + 1))
        J[:n, :n] = flow.vector_field_jacobian(mode, 0.0, x, p)
        J[:n, n] = flow.vector_field_parameters(mode, 0.0, x, p)[:, k]
        J[n, :n], J[n, n] = hx, hp[k]
        try:
            d = np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            raise ConvergenceError("boundary equilibrium: singular defining system", history) from None
        x, lam = x - d[:n], lam - float(d[n])
        step = abs(float(d[n]))
        if history[-1] <= tol * (1.0 + float(np.linalg.norm(x))) and step <= 1e3 * tol * (1.0 + abs(lam)):
            return x, lam, max(step, np.finfo(float).eps * (1.0 + abs(lam)))
    raise ConvergenceError("boundary equilibrium: Newton did not converge", history)


def _admissible_side(problem, surface: str, mode: int, sign: float, x: np.ndarray, lam: float, span: float) -> float:
    """On which side of ``lam`` (+1 or -1) the mode's equilibrium near ``x`` lies where ``sign * h > 0`` (the
    mode's side of the surface); 0 where it does on neither (or has no equilibrium there)."""
    flow = problem.flow
    delta = 1e-3 * max(span, 1e-6)
    for side in (1.0, -1.0):
        p = problem.parameters_at(lam + side * delta)
        y = x.copy()
        try:
            for _ in range(30):  # Newton on the mode's field alone
                dy = np.linalg.solve(flow.vector_field_jacobian(mode, 0.0, y, p), flow.vector_field(mode, 0.0, y, p))
                y = y - dy
                if np.linalg.norm(dy) <= 1e-14 * (1.0 + np.linalg.norm(y)):
                    break
            else:
                continue
        except np.linalg.LinAlgError:
            continue
        if sign * flow.indicator(surface, 0.0, y, p) > 0.0:
            return side
    return 0.0


class BoundaryEquilibriumCurve(BranchProblem):
    """Boundary equilibria in two parameters, in the continuation protocol.

    The defining system of a boundary equilibrium, ``f_mode(x, p) = 0`` and ``h(x, p) = 0``, with the first
    parameter one more unknown: ``u = (x, lam1)``, and the second parameter the continuation parameter.
    Exact Jacobians (the compiled field's and indicator's derivatives).

    Parameters
    ----------
    flow : Flow
        The compiled flow of an autonomous model.
    mode : str or int
        The mode whose equilibrium reaches the surface.
    surface : str
        The switching surface.
    parameters : mapping or ndarray, optional
        Parameter values (the model's defaults otherwise).
    first, second : str
        The two parameters: the first is an unknown of the curve, the second its continuation parameter.

    Raises
    ------
    ModelError
        For an unknown mode, surface or parameter, two equal parameters, or a forced model.
    """

    #: what a branch of this problem is (:class:`saltation.branches.branch.BranchKind` by value)
    branch_kind = "equilibrium"

    def __init__(self, flow, mode, surface: str, parameters=None, *, first: str, second: str):
        self.flow = flow
        self.system = flow.system
        if not self.system.is_autonomous:
            raise ModelError(f"model {self.system.name!r} is forced: it has no equilibria")
        self.mode = self.system.mode_index(mode)
        self.surface = surface
        self.system.surface_index(surface)
        if first == second:
            raise ModelError(f"the two parameters of a curve must differ, got {first!r} twice")
        self.first, self.first_index = first, self.system.parameter_index(first)
        self.lam_name, self.lam_index = second, self.system.parameter_index(second)
        self.p = flow.parameters(parameters)

    @property
    def dimension(self) -> int:
        return self.system.n + 1

    def parameters_at(self, lam: float | None = None, u: np.ndarray | None = None) -> np.ndarray:
        """The parameters with the second parameter at ``lam`` and the first read from ``u = (x, lam1)``.

        Parameters
        ----------
        lam : float, optional
            The second parameter.
        u : ndarray, optional
            The unknowns (without them the first parameter keeps the problem's value).

        Returns
        -------
        ndarray
            A copy of the parameters.
        """
        p = self.p.copy()
        if lam is not None:
            p[self.lam_index] = lam
        if u is not None:
            p[self.first_index] = float(u[self.system.n])
        return p

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True):
        """``(f_mode, h)`` at ``u = (x, lam1)`` and their Jacobians.

        Parameters
        ----------
        u : ndarray, shape (n + 1,)
        lam : float, optional
            The second parameter.
        need_lam : bool
            Compute ``jac_lam`` too.

        Returns
        -------
        Evaluation
        """
        from saltation.orbits.records import Evaluation

        flow, n = self.flow, self.system.n
        x = np.asarray(u[:n], dtype=float)
        p = self.parameters_at(lam, u)
        hx, _, hp = flow.indicator_gradient(self.surface, 0.0, x, p)
        fp = flow.vector_field_parameters(self.mode, 0.0, x, p)
        r = np.append(flow.vector_field(self.mode, 0.0, x, p), flow.indicator(self.surface, 0.0, x, p))
        J = np.zeros((n + 1, n + 1))
        J[:n, :n] = flow.vector_field_jacobian(self.mode, 0.0, x, p)
        J[:n, n] = fp[:, self.first_index]
        J[n, :n], J[n, n] = hx, hp[self.first_index]
        jl = None
        if need_lam and lam is not None:
            jl = np.append(fp[:, self.lam_index], hp[self.lam_index])
        return Evaluation(residual=r, jac_u=J, jac_lam=jl)

    def describe(self, u: np.ndarray, lam: float | None, ev):
        """A curve point: the equilibrium, the first parameter as ``parameter``, the second as
        ``second_parameter``, and the mode's eigenvalues as ``multipliers``.

        Parameters
        ----------
        u : ndarray
        lam : float or None
        ev : Evaluation

        Returns
        -------
        BranchPoint
        """
        from saltation.orbits.records import BranchPoint

        n = self.system.n
        eig = np.linalg.eigvals(ev.jac_u[:n, :n]).astype(complex)
        eig = eig[np.lexsort((-eig.imag, -eig.real))]
        return BranchPoint(
            parameter=float(u[n]), state=np.array(u[:n]), period=math.nan, amplitude=float(abs(u[0])),
            half_peak_to_peak=0.0, multipliers=eig, stable=bool(np.all(eig.real < 0)), event_labels=(),
            second_parameter=math.nan if lam is None else float(lam),
        )

    def accept(self, u: np.ndarray, lam: float | None) -> None:
        """Nothing to re-anchor.

        Parameters
        ----------
        u : ndarray
        lam : float or None
        """


def follow_boundary_equilibrium_curve(
    flow,
    point: SpecialPoint,
    first: str,
    second: str,
    bounds: tuple[float, float],
    *,
    parameters=None,
    settings=None,
    progress=None,
):
    """Continue a boundary equilibrium in a second parameter, in both directions.

    Parameters
    ----------
    flow : Flow or Branch
        The compiled flow of the model; or the equilibrium branch the point lies on (its problem gives
        the flow, and the parameters unless ``parameters`` is given).
    point : SpecialPoint or int
        A located ``boundary_equilibrium`` (its ``touch_mode``, ``touch_surface``, state and parameter);
        from a branch, also its index in ``branch.special_points``.
    first : str
        The parameter of the branch it was found on.
    second : str
        The second parameter.
    bounds : (float, float)
        The range of the second parameter.
    parameters : mapping or ndarray, optional
        The other parameters' values (the model's defaults otherwise).
    settings : ContinuationSettings, optional
        Step sizes (``bounds`` overrides theirs).
    progress : callable, optional
        Called with each new curve point.

    Returns
    -------
    Locus
        The curve (``parameter`` the first parameter, ``second_parameter`` the second), with a stop reason
        per direction.

    Raises
    ------
    ModelError
        If the point is not a boundary equilibrium, or a name is unknown.
    SaltationError
        If the curve cannot start from the point.

    References
    ----------
    M. di Bernardo, C. J. Budd, A. R. Champneys and P. Kowalczyk (2008), *Piecewise-smooth Dynamical
    Systems: Theory and Applications*, Springer, section 5.2.
    """
    from dataclasses import replace

    from saltation.branches.branch import BranchKind
    from saltation.branches.continuation import ContinuationSettings
    from saltation.special_points.loci import Locus, curve_stops, run_curve

    if isinstance(flow, Branch):
        problem, point = problem_and_point(flow, point, "a boundary-equilibrium curve")
        flow, parameters = problem.flow, problem.p if parameters is None else parameters
    if point.kind is not SpecialPointKind.BOUNDARY_EQUILIBRIUM:
        raise ModelError(f"a boundary-equilibrium curve starts at a boundary_equilibrium point, got {point.kind.value}")
    values = flow.parameters(parameters)
    values[flow.system.parameter_index(first)] = point.parameter
    curve = BoundaryEquilibriumCurve(flow, point.touch_mode, point.touch_surface, values, first=first, second=second)
    settings = replace(settings or ContinuationSettings(), bounds=(min(bounds), max(bounds)), detect=False)
    u0 = np.append(np.asarray(point.state, dtype=float), point.parameter)
    lam0 = curve.lam0()
    runs, results = [], []
    for direction in (1, -1):
        cont, way, failure = run_curve(
            curve, settings, u0, lam0, direction, progress,
            f"the boundary_equilibrium curve in {second} cannot start from the point at {first} = {point.parameter:.10g}",
            second=second, curve_of=SpecialPointKind.BOUNDARY_EQUILIBRIUM,
        )
        n = flow.system.n  # the engine records the continuation parameter as ``parameter``: put both back
        runs.append([replace(bp, parameter=float(sol.z[n]), second_parameter=float(sol.z[-1]))
                     for bp, sol in zip(cont.branch.points, cont.solutions)])
        results.append((cont, way, failure))
    points = list(reversed(runs[1]))[:-1] + runs[0]
    return Locus(
        model=flow.system.name, parameter_name=first, kind=BranchKind.EQUILIBRIUM, points=points,
        fixed_parameters=dict(zip(flow.system.parameter_names, map(float, values))),
        label="boundary_equilibrium curve", autonomous=True, second_parameter_name=second,
        curve_of=SpecialPointKind.BOUNDARY_EQUILIBRIUM, state_names=tuple(flow.system.state_names),
        **curve_stops(results),
    )


__all__ = [
    "CYCLE_TURNS", "BoundaryCycle", "BoundaryEquilibriumCurve", "boundary_equilibria", "cycle_at_boundary_equilibrium", "boundary_equilibria_of_mode", "follow_boundary_equilibrium_curve",
    "sliding_weight",
]
