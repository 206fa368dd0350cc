"""Branch switching: the branch of period-2 orbits born at a period doubling, and the asymmetric orbits
born at a symmetry breaking.

At a period doubling of a periodic orbit ``x*`` (parameter ``lam*``) a multiplier
of its monodromy ``M`` is -1, with eigenvector ``v``.  Over two periods
``M^2`` has the multiplier +1 along ``v``: the period-2 map has a
pitchfork at ``x*``, whose new branch leaves ``x*`` along ``v``
(``lam - lam* = O(eps^2)``).  The first period-2 orbit is found by the
bordered Newton system of continuation with the normal ``(v, 0)``:
``r_2(x, lam) = 0`` and ``v . (x - x* - eps v) = 0`` (the step along ``v`` is
fixed, the parameter free), and the branch is followed from there by
pseudo-arclength continuation of the two-period shooting problem.

A forced orbit's two periods are two forcing periods (``ShootingProblem(..., periods=2)``).  An
autonomous orbit's period is an unknown: the period-2 orbit is an autonomous orbit like any other, with
unknowns ``(x0, T2)``, its period ``T2`` starting from ``2 T*`` and its phase condition
``f(x*) . (x0 - x*) = 0`` anchored at the period doubling; ``v`` is first projected onto that section along
the flow, ``w = v - (f^ . v) f^`` (``f^ = f(x*) / |f(x*)|``), the eigenvector of the Poincare map's
derivative for -1 (``M f = f``, so ``M w = -w`` modulo ``f``).  The first orbit is
``(x* + eps w, 2 T*)`` corrected with the step along ``w`` fixed.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from saltation.branches.branch import (
    Branch,
    SpecialPoint,
    SpecialPointKind,
    problem_and_point,
)
from saltation.errors import (
    ConvergenceError,
    InconsistentResultError,
    ModelError,
    SaltationError,
    StationaryStateError,
)
from saltation.orbits.single import ShootingProblem
from saltation.orbits.symmetry import symmetric_multipliers
from saltation.special_points.continuation import (
    ContinuationSettings,
    Corrector,
    continue_branch,
)

#: The largest distance from -1 of the multiplier at a point that branch switching takes for a period doubling
#: (a located one's is within its location accuracy; a point only bracketed may be a step away).
FLIP_DISTANCE = 0.1


def period_doubling_direction(problem: ShootingProblem, point: SpecialPoint) -> np.ndarray:
    """The unit eigenvector of the monodromy at a period doubling for its multiplier nearest -1.

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the period-1 branch.
    point : SpecialPoint
        The period doubling (its state and parameter).

    Returns
    -------
    ndarray, shape (n,)
        The real part of that eigenvector, normalised.

    Raises
    ------
    ModelError
        If no multiplier of the orbit at the point lies within :data:`FLIP_DISTANCE` of -1 (the point is
        no period doubling of this problem's orbits).
    SaltationError
        If the orbit at the point cannot be evaluated (an :class:`IntegrationError`, say).
    numpy.linalg.LinAlgError
        If the monodromy is not finite.
    """
    u = problem.pack(np.asarray(point.state, dtype=float), point.period if problem.autonomous else None)
    ev = problem.evaluate(u, point.parameter, need_lam=False)
    mu, vectors = np.linalg.eig(ev.trajectory.monodromy)
    k = int(np.argmin(np.abs(mu + 1.0)))
    if not abs(mu[k] + 1.0) <= FLIP_DISTANCE:
        raise ModelError(
            f"the orbit at the {point.kind.value} at {problem.lam_name} = {point.parameter:.10g} has no multiplier "
            f"near -1 (the nearest is {complex(mu[k]):.6g}): not a period doubling of this problem's orbits")
    v = np.real(vectors[:, k])
    return v / np.linalg.norm(v)


def period_doubled_problem(problem: ShootingProblem) -> ShootingProblem:
    """The shooting problem of the period-2 orbits born at a period doubling of ``problem``'s orbits.

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the period-1 branch.

    Returns
    -------
    ShootingProblem
        The same flow, parameters, continuation parameter, time direction, ``t0``, tolerances and start
        mode; a forced problem over twice as many forcing periods (``periods`` doubled).  An autonomous
        problem's period is an unknown already: a new autonomous problem, its phase condition not yet
        anchored, whose unknowns ``(x0, T2)`` take the doubled period ``T2 ~ 2 T`` (see
        :func:`follow_period_doubled_branch`).

    Raises
    ------
    ModelError
        If the problem's parameters are invalid (as :class:`ShootingProblem` raises it).
    """
    return ShootingProblem(
        problem.flow, problem.p, continuation_parameter=problem.lam_name, backward=problem.backward, t0=problem.t0,
        tolerances=problem.tolerances, periods=1 if problem.autonomous else 2 * problem.periods, mode0=problem.mode0,
    )


def section_direction(problem: ShootingProblem, point: SpecialPoint, v: np.ndarray) -> np.ndarray:
    """A direction at an autonomous orbit's state projected onto its phase section along the flow.

    The phase condition of an autonomous orbit is the plane through ``x*`` normal to ``f(x*)``; with
    ``f^ = f(x*) / |f(x*)|`` the projection is ``w = v - (f^ . v) f^``.  For the eigenvector ``v`` of the
    monodromy ``M`` at a period doubling (``M v = -v``, ``M f = f``), ``M w = -w - 2 (f^ . v) f``: ``w`` is
    the eigenvector of the Poincare map's derivative on that section for the multiplier -1.

    Parameters
    ----------
    problem : ShootingProblem
        An autonomous problem.
    point : SpecialPoint
        The orbit's point (its state ``x*`` and parameter).
    v : ndarray, shape (n,)
        The direction.

    Returns
    -------
    ndarray, shape (n,)
        ``w``, normalised.

    Raises
    ------
    InconsistentResultError
        If ``v`` is (numerically) along the flow: no direction is left on the section.
    StationaryStateError
        If the vector field vanishes at ``x*`` (an equilibrium, not a periodic orbit).
    """
    x_star = np.asarray(point.state, dtype=float)
    p = problem.parameters_at(point.parameter)
    f = problem.flow.vector_field(problem.start_mode(x_star, p), problem.t0, x_star, p)
    size = float(np.linalg.norm(f))
    if not size > 0:
        raise StationaryStateError(
            f"the state x = {x_star.tolist()} of the {point.kind.value} at {problem.lam_name} = {point.parameter:.10g} "
            "is an equilibrium (its vector field vanishes): not a periodic orbit", x_star)
    f_hat = f / size
    w = v - (f_hat @ v) * f_hat
    norm = float(np.linalg.norm(w))
    if not norm > 1e-8 * float(np.linalg.norm(v)):
        raise InconsistentResultError(
            f"the critical eigenvector at the {point.kind.value} at {problem.lam_name} = {point.parameter:.10g} lies "
            "along the flow: its multiplier is the trivial one, not a period doubling's -1")
    return w / norm


def follow_period_doubled_branch(
    problem: Branch | ShootingProblem,
    point: SpecialPoint | int,
    *,
    settings: ContinuationSettings | None = None,
    epsilon: float = 1e-3,
    label: str = "period 2",
) -> Branch:
    """Follow the branch of period-2 orbits born at a located period doubling.

    A forced orbit's period-2 branch is followed over two forcing periods
    (``ShootingProblem(..., periods=2)``).  An autonomous orbit's is followed as autonomous orbits with
    the unknowns ``(x0, T2)``: the doubled period ``T2`` starts from ``2 T*`` (``T*`` the period at the
    point) and stays an unknown, closed by the phase condition ``f(x*) . (x0 - x*) = 0`` anchored at the
    point's state ``x*`` (re-anchored at each point of the branch, as on every autonomous branch); the
    first orbit leaves ``x*`` along the critical eigenvector projected onto that section
    (:func:`section_direction`).  Every orbit of the new branch is checked as every autonomous orbit is
    (its trivial multiplier 1, see :meth:`ShootingProblem.verify`), and the first one must not be the
    period-1 orbit traversed twice (``|x(T2/2) - x0|`` of the order of ``epsilon``, not of the Newton
    tolerance).

    Parameters
    ----------
    problem : Branch or ShootingProblem
        The branch (it holds its problem), or, as in release 0.1, its problem:
        The problem of the period-1 branch (forced or autonomous; its continuation parameter set).
    point : SpecialPoint or int
        The point (from a branch, also its index in ``branch.special_points``):
        A special point of kind ``period_doubling`` on that branch.
    settings : ContinuationSettings, optional
        For the period-2 branch.
    epsilon : float
        Distance along the critical eigenvector of the first period-2 orbit, relative to ``1 + |x*|``
        (tried smaller and larger if Newton fails there).
    label : str
        The label of the new branch.

    Returns
    -------
    Branch
        The period-2 branch, followed from its first orbit away from the period doubling (its first
        special point the period doubling itself).  An autonomous branch's periods are the doubled periods.

    Raises
    ------
    ModelError
        If the point is not a period doubling (its kind, or no multiplier of the orbit at it near -1).
    ConvergenceError
        If no period-2 orbit is found near the period doubling.
    SaltationError
        If the period-1 orbit at the point cannot be evaluated.

    References
    ----------
    Kuznetsov (2004), *Elements of Applied Bifurcation Theory*, 3rd ed., Springer (the period
    doubling as a pitchfork of the second iterate; the Poincare map of an autonomous cycle).  Keller
    (1977), "Numerical solution of bifurcation and nonlinear eigenvalue problems", in Rabinowitz (ed.),
    *Applications of Bifurcation Theory*, Academic Press (bordered systems and branch switching).
    Doedel, Keller and Kernevez (1991), "Numerical analysis and control of bifurcation problems (II):
    bifurcation in infinite dimensions", Int. J. Bifurcation and Chaos 1, 745-772 (the doubled period and
    the phase condition of period-doubled cycles).
    """
    problem, point = problem_and_point(problem, point, "the period-2 branch")
    if point.kind is not SpecialPointKind.PERIOD_DOUBLING:
        raise ModelError(f"branch switching needs a period_doubling point, got {point.kind.value}")
    getattr(problem, "align_section", lambda point: None)(point)  # (the point's state lies at its own section)
    doubled = period_doubled_problem(problem)
    v = period_doubling_direction(problem, point)
    x_star = np.asarray(point.state, dtype=float)
    scale = 1.0 + float(np.linalg.norm(x_star))
    if not problem.autonomous:
        def closes_after_one_period(first) -> bool:
            # a period-1 orbit on the other branch would have moved back onto x* (its v-component is fixed,
            # so it cannot): check that the orbit found does not close after one period
            single = problem.evaluate(first.u, first.lam, need_lam=False)
            return bool(np.linalg.norm(single.residual) <= 1e-6 * scale)

        return _leave_along(doubled, point, v, closes_after_one_period, settings=settings, epsilon=epsilon,
                            label=label, what="period-2 orbit", at="period doubling")

    # autonomous: the section through x* normal to f(x*), the direction on it, the doubled period
    w = section_direction(problem, point, v)
    doubled.anchor_phase(x_star, problem.parameters_at(point.parameter))

    def traversed_twice(first) -> bool:
        # the period-1 orbit at a nearby parameter, traversed twice, also solves the doubled problem with
        # the step along w fixed: it closes after half its period
        return half_period_gap(doubled, first.u, first.lam) <= 1e-6 * scale

    return _leave_along(doubled, point, w, traversed_twice, settings=settings, epsilon=epsilon, label=label,
                        what="period-2 orbit", at="period doubling", period=2.0 * float(point.period))


def half_period_gap(problem: ShootingProblem, u: np.ndarray, lam: float | None = None) -> float:
    """How far an autonomous orbit of period ``T2`` is from closing after ``T2 / 2``: ``|x(T2/2) - x0|``.

    Zero (to the Newton tolerance) for a period-1 orbit traversed twice; of the order of the distance
    between the two loops for a true period-2 orbit.

    Parameters
    ----------
    problem : ShootingProblem
        An autonomous problem.
    u : ndarray
        Its unknowns ``(x0, T2)``.
    lam : float, optional
        The continuation parameter's value.

    Returns
    -------
    float
        The distance.

    Raises
    ------
    ModelError
        If the problem is forced (its period is fixed: compare with the one-period problem instead).
    SaltationError
        If the shot over half the period fails.
    """
    if not problem.autonomous:
        raise ModelError(f"half_period_gap needs an autonomous problem; {problem.system.name!r} is forced")
    n = problem.system.n
    x0 = np.asarray(u[:n], dtype=float)
    half = 0.5 * problem.period_of(u, lam)
    p = problem.parameters_at(lam)
    traj = problem.flow.run(x0, problem.t0, problem.t0 + problem.sign * half, p, mode0=problem.mode0,
                            tolerances=problem.tolerances)
    return float(np.linalg.norm(traj.x1 - x0))


def _leave_along(problem: ShootingProblem, point: SpecialPoint, v: np.ndarray, reject, *,
                 settings: ContinuationSettings | None, epsilon: float, label: str, what: str, at: str,
                 period: float | None = None) -> Branch:
    """The first orbit of a new branch, found at a distance from ``point`` along ``v`` with the parameter
    free (Keller's bordered system), and the branch followed from it; ``reject(first)`` says when the orbit
    found is on the old branch.  ``period``: an autonomous orbit's period guess (the point's by default)."""
    settings = settings or ContinuationSettings()
    corrector = Corrector(problem, settings)
    x_star = np.asarray(point.state, dtype=float)
    u_star = problem.pack(x_star, (point.period if period is None else period) if problem.autonomous else None)
    along = np.zeros(u_star.size)
    along[: v.size] = v
    normal = np.append(along, 0.0)
    scale = 1.0 + float(np.linalg.norm(x_star))
    last: Exception | None = None
    for eps in (epsilon, 3 * epsilon, 0.3 * epsilon, 10 * epsilon, 0.1 * epsilon):
        z_pred = np.append(u_star + eps * scale * along, point.parameter)
        try:
            first = corrector.solve_bordered(z_pred, normal)
        except SaltationError as exc:
            last = exc
            continue
        if reject(first):
            continue
        lo, hi = settings.bounds
        if not lo <= first.lam <= hi:
            continue
        direction = 1 if first.lam >= point.parameter else -1
        branch = continue_branch(problem, first.u, first.lam, settings=settings, directions=(direction,), label=label)
        # the new branch is born at the point: its first special point, where its first orbit's multiplier
        # (at +1 on the circle, within the step from it) begins
        branch.special_points.insert(0, replace(point, index=0))
        return branch
    raise ConvergenceError(
        f"no {what} found near the {at} at {problem.lam_name} = {point.parameter:.10g}"
        + (f" (last failure: {last})" if last else ""),
        [],
    )


def symmetry_breaking_direction(problem: ShootingProblem, point: SpecialPoint) -> np.ndarray:
    """The unit eigenvector of the half-period map at a symmetry breaking for its eigenvalue nearest -1.

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the branch of symmetric orbits.
    point : SpecialPoint
        The symmetry breaking (its state and parameter).

    Returns
    -------
    ndarray, shape (n,)
        The real part of that (antisymmetric) eigenvector, normalised.

    Raises
    ------
    ModelError
        If the model declares no symmetry.
    SaltationError
        If the orbit at the point cannot be evaluated.
    """
    half = symmetric_multipliers(
        problem.flow, point.state, parameters=problem.parameters_at(point.parameter),
        period=point.period if problem.autonomous else None, t0=problem.t0, backward=problem.backward,
        tolerances=problem.tolerances,
    )
    gamma, vectors = np.linalg.eig(half.half_map)
    if problem.backward:
        gamma = 1.0 / gamma
    k = int(np.argmin(np.abs(gamma + 1.0)))
    v = np.real(vectors[:, k])
    return v / np.linalg.norm(v)


def follow_asymmetric_branch(
    problem: Branch | ShootingProblem,
    point: SpecialPoint | int,
    *,
    settings: ContinuationSettings | None = None,
    epsilon: float = 1e-3,
    label: str = "asymmetric",
) -> Branch:
    """Follow a branch of asymmetric orbits born at a symmetry breaking of a branch of symmetric ones.

    At a symmetry breaking the half-period map ``G`` of the symmetric orbit ``x*`` has the eigenvalue -1
    with an eigenvector ``v``, and the period map ``G^2`` the multiplier +1 along it: a pitchfork of the
    period map, whose two new branches leave ``x*`` along ``+v`` and ``-v`` and are mirror images of each
    other (``x(t) -> S x(t + T/2)``).  The branch along ``+v`` is found by the bordered Newton system of
    the same one-period problem, with the step along ``v`` fixed and the parameter free, and followed by
    pseudo-arclength continuation; the mirror images of its orbits are the other branch.

    Parameters
    ----------
    problem : Branch or ShootingProblem
        The branch (it holds its problem), or, as in release 0.1, its problem:
        The one-period problem of the symmetric branch (its continuation parameter set).
    point : SpecialPoint or int
        The point (from a branch, also its index in ``branch.special_points``):
        A special point of kind ``symmetry_breaking`` (or ``discontinuous_symmetry_breaking``: the
        direction is then the eigenvector of the orbit's half-period map on the side of the point's
        state).
    settings : ContinuationSettings, optional
        For the new branch.
    epsilon : float
        Distance along ``v`` of the first asymmetric orbit, relative to ``1 + |x*|`` (tried smaller and
        larger if Newton fails there).
    label : str
        The label of the new branch.

    Returns
    -------
    Branch
        The branch of asymmetric orbits, followed away from the symmetry breaking.

    Raises
    ------
    ModelError
        If the point is not a symmetry breaking, or the model declares no symmetry.
    ConvergenceError
        If no asymmetric orbit is found near the point.
    SaltationError
        If the orbit at the point cannot be evaluated.

    References
    ----------
    Golubitsky, Stewart and Schaeffer (1988), *Singularities and Groups in Bifurcation Theory*, vol. II,
    Springer (symmetry-breaking pitchforks).  Keller (1977), "Numerical solution of bifurcation and
    nonlinear eigenvalue problems", in Rabinowitz (ed.), *Applications of Bifurcation Theory*, Academic
    Press (bordered systems and branch switching).
    """
    problem, point = problem_and_point(problem, point, "the asymmetric branch")
    kinds = (SpecialPointKind.SYMMETRY_BREAKING, SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING)
    if point.kind not in kinds:
        raise ModelError(f"branch switching to asymmetric orbits needs a symmetry_breaking point, got {point.kind.value}")
    v = symmetry_breaking_direction(problem, point)
    n = problem.system.n

    def symmetric(first) -> bool:
        half = symmetric_multipliers(
            problem.flow, first.u[:n], parameters=problem.parameters_at(first.lam),
            period=problem.period_of(first.u, first.lam) if problem.autonomous else None, t0=problem.t0,
            backward=problem.backward, tolerances=problem.tolerances,
        )
        return half.symmetric

    return _leave_along(problem, point, v, symmetric, settings=settings, epsilon=epsilon, label=label,
                        what="asymmetric orbit", at="symmetry breaking")


__all__ = [
    "FLIP_DISTANCE", "follow_asymmetric_branch", "follow_period_doubled_branch", "half_period_gap", "period_doubled_problem",
    "period_doubling_direction", "section_direction", "symmetry_breaking_direction",
]
