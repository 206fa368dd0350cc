"""Branch switching: the branch of period-2 orbits born at a period doubling.

At a period doubling of a forced orbit ``x*`` (parameter ``lam*``) a multiplier
of its monodromy ``M`` is -1, with eigenvector ``v``.  Over two forcing
periods ``M^2`` has the multiplier +1 along ``v``: the period-2 map has a
pitchfork at ``x*``, whose new branch leaves ``x*`` along ``v``
(``lam - lam* = O(eps^2)``).  The first period-2 orbit is found by the
bordered Newton system of continuation with the normal ``(v, 0)``:
``r_2(x, lam) = 0`` and ``v . (x - x* - eps v) = 0`` (the step along ``v`` is
fixed, the parameter free), and the branch is followed from there by
pseudo-arclength continuation of the two-period shooting problem.
"""

from __future__ import annotations

import numpy as np

from saltation.branches.branch import Branch, SpecialPoint, SpecialPointKind
from saltation.special_points.continuation import ContinuationSettings, Corrector, continue_branch
from saltation.errors import ConvergenceError, ModelError, SaltationError
from saltation.orbits.shooting import ShootingProblem


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
    SaltationError
        If the orbit at the point cannot be evaluated (an :class:`IntegrationError`, say).
    numpy.linalg.LinAlgError
        If the monodromy is not finite.
    """
    ev = problem.evaluate(np.asarray(point.state, dtype=float), point.parameter, need_lam=False)
    mu, vectors = np.linalg.eig(ev.trajectory.monodromy)
    k = int(np.argmin(np.abs(mu + 1.0)))
    v = np.real(vectors[:, k])
    return v / np.linalg.norm(v)


def period_doubled_problem(problem: ShootingProblem) -> ShootingProblem:
    """The same shooting problem over twice as many forcing periods.

    Parameters
    ----------
    problem : ShootingProblem
        A forced problem.

    Returns
    -------
    ShootingProblem
        With ``periods`` doubled, and the same flow, parameters, continuation parameter, time
        direction, ``t0`` and tolerances.

    Raises
    ------
    ModelError
        If the problem is autonomous (its period is an unknown, not a number of periods).
    """
    return ShootingProblem(
        problem.flow, problem.p, continuation_parameter=problem.lam_name, backward=problem.backward, t0=problem.t0,
        tolerances=problem.tolerances, periods=2 * problem.periods,
    )


def follow_period_doubled_branch(
    problem: ShootingProblem,
    point: SpecialPoint,
    *,
    settings: ContinuationSettings | None = None,
    epsilon: float = 1e-3,
    label: str = "period 2",
) -> Branch:
    """Follow the branch of period-2 orbits born at a located period doubling.

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the period-1 branch (forced; its continuation parameter set).
    point : SpecialPoint
        A special point of kind ``period_doubling`` on that branch.
    settings : ContinuationSettings, optional
        For the period-2 branch.
    epsilon : float
        Distance along the critical eigenvector of the first period-2 orbit
        (tried smaller and larger if Newton fails there).
    label : str
        The label of the new branch.

    Returns
    -------
    Branch
        The period-2 branch, followed from its first orbit away from the period doubling.

    Raises
    ------
    ModelError
        If the point is not a period doubling, or the problem is autonomous.
    ConvergenceError
        If no period-2 orbit is found near the period doubling.
    SaltationError
        If the period-1 orbit at the point cannot be evaluated.

    References
    ----------
    Kuznetsov (2004), *Elements of Applied Bifurcation Theory*, 3rd ed., Springer (the period
    doubling as a pitchfork of the second iterate).  Keller (1977), "Numerical solution of bifurcation
    and nonlinear eigenvalue problems", in Rabinowitz (ed.), *Applications of Bifurcation Theory*,
    Academic Press (bordered systems and branch switching).
    """
    if point.kind is not SpecialPointKind.PERIOD_DOUBLING:
        raise ModelError(f"branch switching needs a period_doubling point, got {point.kind.value}")
    if problem.autonomous:
        raise ModelError("branch switching at period doubling is implemented for forced models")
    doubled = period_doubled_problem(problem)
    settings = settings or ContinuationSettings()
    corrector = Corrector(doubled, settings)
    v = period_doubling_direction(problem, point)
    x_star = np.asarray(point.state, dtype=float)
    normal = np.append(v, 0.0)
    scale = 1.0 + float(np.linalg.norm(x_star))
    last: Exception | None = None
    for eps in (epsilon, 3 * epsilon, 0.3 * epsilon, 10 * epsilon, 0.1 * epsilon):
        z_pred = np.append(x_star + eps * scale * v, point.parameter)
        try:
            first = corrector.solve_bordered(z_pred, normal)
        except SaltationError as exc:
            last = exc
            continue
        # a period-1 orbit on the other branch would have moved back onto x* (its v-component is fixed,
        # so it cannot): check that the orbit found does not close after one period
        single = problem.evaluate(first.u, first.lam, need_lam=False)
        if np.linalg.norm(single.residual) <= 1e-6 * scale:
            continue
        lo, hi = settings.bounds
        if not lo <= first.lam <= hi:
            continue
        direction = 1 if first.lam >= point.parameter else -1
        branch = continue_branch(doubled, first.u, first.lam, settings=settings, directions=(direction,), label=label)
        return branch
    raise ConvergenceError(
        f"no period-2 orbit found near the period doubling at {problem.lam_name} = {point.parameter:.10g}"
        + (f" (last failure: {last})" if last else ""),
        [],
    )


__all__ = ["follow_period_doubled_branch", "period_doubled_problem", "period_doubling_direction"]
