"""Bifurcation diagrams: several branches stitched together.

The main non-smooth case handled here is the one of the block-on-belt
system (Fig. 7): a stable branch ends at a discontinuous fold that forward
shooting cannot pass, because the branch beyond it is *infinitely unstable*
(its orbits slide along a repulsion sliding mode; multipliers ``(1, inf)``).
:func:`follow_through_discontinuous_fold` locates the end of the stable
branch, restarts continuation with backward-time shooting, in which the
unstable orbits are attracting, and records the discontinuous fold joining
the two branches.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from saltation.special_points.detection import classify_nonsmooth, special_point_between
from saltation.branches.branch import Branch, Limits, SpecialPoint, SpecialPointStatus
from saltation.special_points.continuation import Continuation, ContinuationSettings, Corrector, Solution, canonical_events
from saltation.errors import SaltationError
from saltation.special_points.grazing import locate_tangential_return
from saltation.engine.flow import EventKind
from saltation.orbits.shooting import ShootingProblem


@dataclass
class BifurcationDiagram:
    """Branches of one model over one parameter (a fold joining two branches is a special point of one)."""

    model: str
    parameter_name: str
    branches: list[Branch] = field(default_factory=list)

    @property
    def special_points(self) -> list[SpecialPoint]:
        """Every special point of every branch; a point where two branches join (a discontinuous fold that
        ends one and starts the other) is listed once."""
        return distinct_special_points(self.branches)


def distinct_special_points(branches) -> list[SpecialPoint]:
    """Every special point of the branches, in order; a point where two branches join (the same kind at the
    same parameter, recorded at the end of one and the start of the other) listed once."""
    seen: set[tuple[str, float]] = set()
    out = []
    for sp in (sp for b in branches for sp in b.special_points):
        key = (sp.kind.value, float(sp.parameter))
        if key not in seen:
            seen.add(key)
            out.append(sp)
    return out


def locate_branch_end(corrector: Corrector, last: Solution, lam_fail: float, *, tol: float = 1e-9) -> tuple[Solution, float]:
    """Bisection in the parameter for the end of a branch that the corrector cannot pass.

    Returns the last solution found (with the branch's event sequence) and
    the smallest parameter value known to fail.
    """
    seq = canonical_events(last.summary.event_ids)
    good, bad = last, float(lam_fail)
    for _ in range(80):
        if abs(bad - good.lam) <= tol:
            break
        lam = 0.5 * (good.lam + bad)
        try:
            sol = corrector.solve_fixed(good.u, lam)
            ok = canonical_events(sol.summary.event_ids) == seq
        except SaltationError:
            ok = False
        if ok:
            good = sol
        else:
            bad = lam
    return good, bad


def _branch_end(cont: Continuation) -> tuple[Solution, float]:
    """Locate where a run that stopped at the minimum step really ends (natural-parameter bisection)."""
    last = cont.solutions[-1]
    if cont.last_failure is not None:
        lam_fail = float(cont.last_failure[-1])
    else:
        lam_fail = last.lam + 1e-3 * (1.0 + abs(last.lam)) * float(np.sign(last.tangent[-1]) or 1.0)
    return locate_branch_end(cont.corrector, last, lam_fail, tol=cont.settings.locate_tol)


def find_backward_seed(
    forward_problem: ShootingProblem, stable: Solution, *, periods: int = 3, offset: float = 1e-3, phases: int = 8
) -> np.ndarray | None:
    """An infinitely unstable orbit near a stable one, by a backward-time transient.

    Such orbits attract in backward time.  Points of the stable orbit (at
    ``phases`` instants of its period) are pushed by ``offset`` (relative)
    both ways along each coordinate, integrated backward over ``periods``
    periods, and refined by backward shooting; the first orbit whose event
    sequence differs from the stable orbit's is returned as unknowns ``u``
    of a backward problem (or None).
    """
    flow = forward_problem.flow
    params = forward_problem.parameters_at(stable.lam)
    backward = ShootingProblem(
        flow, params, backward=True, t0=forward_problem.t0, tolerances=forward_problem.tolerances
    )
    n = forward_problem.system.n
    x0 = stable.u[:n]
    period = forward_problem.period_of(stable.u, stable.lam)
    t_samples, x_samples = flow.run(x0, forward_problem.t0, forward_problem.t0 + period, params, dense=True).sample(4)
    picks = np.linspace(0, len(t_samples) - 1, phases, endpoint=False).astype(int)
    for k in picks:
        xk, tk = x_samples[k], float(t_samples[k])
        scale = offset * (1.0 + float(np.linalg.norm(xk)))
        for i in range(n):
            for sign in (1.0, -1.0):
                start = xk.copy()
                start[i] += sign * scale
                try:
                    traj = flow.run(start, tk, tk - periods * period, params)
                    backward.t0 = traj.t1 if backward.autonomous else forward_problem.t0
                    if not backward.autonomous:
                        # forced systems: return to the forcing phase t0 before shooting
                        traj = flow.run(traj.x1, traj.t1, traj.t1 - ((traj.t1 - forward_problem.t0) % period), params)
                    u0 = backward.pack(traj.x1, period if backward.autonomous else None)
                    backward.set_phase_reference(u0) if backward.autonomous else None
                    orbit = backward.solve(u0, max_iter=20)
                except SaltationError:
                    continue
                if not orbit.stable:
                    # attracting in backward time: not the stable orbit traversed backward
                    backward.t0 = forward_problem.t0
                    return backward.pack(orbit.state0, orbit.period if backward.autonomous else None)
    return None


def _same_orbit(xa: np.ndarray, xb: np.ndarray, ta: float, tb: float) -> bool:
    return bool(np.linalg.norm(xa - xb) < 1e-6 * (1 + np.linalg.norm(xb)) and abs(ta - tb) < 1e-6 * tb)


def follow_through_discontinuous_fold(
    forward: Continuation,
    *,
    settings: ContinuationSettings | None = None,
    progress: Callable | None = None,
    offset: float = 1e-3,
) -> tuple[Branch, SpecialPoint]:
    """Locate the end of a forward-time branch and follow the infinitely unstable branch beyond it.

    1. The end of the stable branch is located by bisection in the parameter.
    2. A little inside (``offset`` relative in the parameter), an unstable
       orbit is found by a backward-time transient and backward shooting
       (:func:`find_backward_seed`).
    3. That branch is continued with backward-time shooting both ways: away
       from the fold, and towards it, where its end is located too.
    4. The discontinuous fold is recorded with the multipliers of both
       branches at their ends (stable ``(1, 0)``, unstable ``(1, inf)``).

    Parameters
    ----------
    forward : Continuation
        A finished continuation run of a forward-shooting problem that
        stopped because the corrector failed (``StopReason.MIN_STEP``).

    Returns
    -------
    branch : Branch
        The backward-time branch, ordered from the fold outwards.
    fold : SpecialPoint
        The discontinuous fold joining the two branches (also the first
        special point of ``branch``, at its first point).

    Raises
    ------
    SaltationError
        If no backward-time orbit can be found near the end of the branch.
    """
    prob_f = forward.problem
    if not isinstance(prob_f, ShootingProblem) or prob_f.backward:
        raise SaltationError("follow_through_discontinuous_fold needs a forward-time shooting continuation")
    settings = settings or forward.settings
    end, bad = _branch_end(forward)
    towards = float(np.sign(bad - end.lam)) or 1.0
    lam_in = end.lam - towards * offset * (1.0 + abs(end.lam))
    stable_in = forward.corrector.solve_fixed(end.u, lam_in)
    seed = find_backward_seed(prob_f, stable_in, offset=offset)
    if seed is None:
        raise SaltationError(
            f"no backward-time orbit found near the end of the branch at {prob_f.lam_name} = {end.lam:.10g}"
        )
    prob_b = ShootingProblem(
        prob_f.flow, prob_f.p, continuation_parameter=prob_f.lam_name, backward=True, t0=prob_f.t0,
        tolerances=prob_f.tolerances,
    )
    away = Continuation(prob_b, settings)
    for point in away.run(seed, lam_in, direction=-int(towards)):
        if progress is not None:
            progress(point)
    near = Continuation(prob_b, settings)
    for point in near.run(seed, lam_in, direction=int(towards)):
        if progress is not None:
            progress(point)
    end_b, bad_b = _branch_end(near)
    # the joined branch, ordered from the fold outwards
    branch = away.branch
    near.branch.points.append(_point_of(near, end_b))
    branch.extend(near.branch)
    branch.stop_reasons.append(near.branch.stop_reason)

    lo, hi = sorted((max(end.lam, end_b.lam) if towards > 0 else min(end.lam, end_b.lam), min(bad, bad_b) if towards > 0 else max(bad, bad_b)))
    crossing = classify_nonsmooth(
        end.summary.monodromy, None, autonomous=prob_f.autonomous,
        mu_minus=end.summary.multipliers, mu_plus=end_b.summary.multipliers,
    )
    fold = special_point_between(
        end, end_b, crossing, index=0,
        bracket=(min(end.lam, end_b.lam, lo), max(end.lam, end_b.lam, hi)),
        accuracy=abs(end.lam - end_b.lam),
        monodromy_plus=None,  # the other side's monodromy is a backward-time one
        note=(
            "end of the forward-time branch, joined to the infinitely unstable branch found by backward-time "
            "shooting; bracket from both branch ends"
        ),
    )
    fold = _fold_by_tangential_return(prob_f, end, fold, forward.corrector)
    branch.special_points.insert(0, fold)
    # the two runs that stopped there (the corrector failed) say what they found: this fold, at their ends
    for run in (forward, near):
        if not any(sp is fold or _same_point(sp, fold) for sp in run.branch.special_points):
            run.branch.special_points.append(replace(fold, index=len(run.branch.points) - 1))
    return branch, fold


def _same_point(a: SpecialPoint, b: SpecialPoint) -> bool:
    return a.kind is b.kind and a.parameter == b.parameter


def _fold_by_tangential_return(
    problem: ShootingProblem, end: Solution, fold: SpecialPoint, corrector: Corrector | None = None
) -> SpecialPoint:
    """The fold located by its defining condition, where the stable orbit's return is tangential.

    At the end of the stable branch of a stick-slip cycle, the slip arc that
    leaves the stick phase returns to it tangentially: the entry into the
    stick phase whose crossing is the slowest (``|dh/dt|`` relative to
    ``|h_x| |f|``) is the one that turns tangent.  The fold is located by
    :func:`saltation.special_points.grazing.locate_tangential_return` from there; when that
    fails the record keeps the bracket of the two branch ends.
    """
    flow = problem.flow
    traj = end.evaluation.trajectory
    p = problem.parameters_at(end.lam)
    best, slowest = None, np.inf
    for e in traj.events:
        if e.kind != EventKind.TRANSITION:
            continue
        f = flow.vector_field(e.mode_from, e.t, e.x_minus, p)
        hx, ht, _ = flow.indicator_gradient(e.surface, e.t, e.x_minus, p)
        rate = abs(hx @ f + ht) / max(np.linalg.norm(hx) * np.linalg.norm(f), 1e-300)
        if rate < slowest:
            best, slowest = e, rate
    if best is None:
        return fold
    try:
        found = locate_tangential_return(
            flow, best.x_minus, end.lam, problem.lam_name, best.transition, problem.period_of(end.u, end.lam),
            parameters=p, tolerances=problem.tolerances,
        )
    except SaltationError:
        return fold
    lo, hi = fold.bracket
    if not lo - 10 * (hi - lo) <= found.parameter <= hi + 10 * (hi - lo):
        return fold  # a tangency elsewhere
    limit = None if corrector is None else _stable_side_limit(corrector, end, found.parameter)
    extra = {}
    if limit is not None:
        mu, error, exponents = limit
        extra = {"multipliers_minus": mu, "multipliers_accuracy": error, "limits": Limits.EXTRAPOLATED,
                 "growth_exponents": exponents}
    return replace(
        fold, **extra, parameter=found.parameter, status=SpecialPointStatus.LOCATED,
        bracket=(found.parameter - found.accuracy, found.parameter + found.accuracy), accuracy=found.accuracy,
        note=(
            f"located where the orbit returns tangentially to surface {best.surface!r} and enters "
            f"{best.mode_to!r} there (the branch ends bracket it: {lo:.12g} .. {hi:.12g}); joined to the infinitely "
            "unstable branch found by backward-time shooting"
        ),
    )


def _stable_side_limit(corrector: Corrector, end: Solution, fold: float
                       ) -> tuple[np.ndarray, float, tuple[float, ...]] | None:
    """The multipliers at the fold as the limit along the stable branch: ``(mu, error, growth exponents
    of the unbounded ones)``, or None.

    As the slip arc's return to the stick band turns tangential, the entry into
    the stick phase has a saltation matrix that is 0/0 at the fold.  Along the
    branch, at distances ``d = 1e-6, 1e-5, 1e-4`` from the fold, the
    non-trivial multipliers are fitted to ``|mu| ~ d^a``: a growing one
    (``a < -1/4``) is unbounded in the limit and reported as ``inf``; the
    others are extrapolated linearly in ``sqrt(d)`` from the two nearest
    orbits, their error estimated by the third.
    """
    side = float(np.sign(end.lam - fold)) or -1.0
    distances = np.array([1e-6, 1e-5, 1e-4])
    mus = []
    try:
        for d in distances:
            sol = corrector.solve_fixed(end.u, fold + side * d)
            mu = np.asarray(sol.summary.multipliers, dtype=complex)
            mus.append(mu[np.argsort(np.abs(mu))])
    except SaltationError:
        return None
    if any(len(m) != len(mus[0]) or not np.all(np.isfinite(m)) for m in mus):
        return None
    mus = np.array(mus)  # (3 distances, n multipliers), each row by magnitude
    root = np.sqrt(distances)
    limit, error, notes = [], 0.0, []
    for k in range(mus.shape[1]):
        mags = np.abs(mus[:, k])
        exponent = np.polyfit(np.log(distances), np.log(np.maximum(mags, 1e-300)), 1)[0] if np.all(mags > 0) else 0.0
        if exponent < -0.25:
            limit.append(complex(np.inf, 0.0))
            notes.append(float(exponent))
            continue
        # mu(d) = mu_0 + C sqrt(d): from the two nearest orbits, checked against the third
        c = (mus[1, k] - mus[0, k]) / (root[1] - root[0])
        mu0 = mus[0, k] - c * root[0]
        c2 = (mus[2, k] - mus[1, k]) / (root[2] - root[1])
        error = max(error, abs(mu0 - (mus[1, k] - c2 * root[1])))
        limit.append(complex(mu0))
    return np.array(limit), float(error), tuple(notes)


def _point_of(cont: Continuation, sol: Solution):
    """A branch point for a solution found outside the continuation loop."""
    cont._accept(sol)
    return cont.branch.points.pop()
