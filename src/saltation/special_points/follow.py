"""Following a branch as far as it goes, and the branches born on it: the decisions a diagram needs.

:func:`follow_branch` is what ``saltation continue`` does for one branch, as a library call: it
continues the branch one way (:class:`~saltation.special_points.continuation.Continuation`), records
the boundary equilibria of a branch of equilibria, follows the branches born at its special points
(:func:`switch_branches`) and, where a forward-time branch of periodic orbits stops at the
minimum step, the infinitely unstable branch beyond the discontinuous fold in backward time
(:func:`follow_through_discontinuous_fold`).  :func:`switch_branches` decides which branches are
followed from which special points: the asymmetric orbits from a symmetry breaking, the other
equilibrium branch through a boundary equilibrium, the period-2 orbits from a period doubling
(:mod:`saltation.special_points.branch_switching`, :mod:`saltation.special_points.boundary_equilibria`).

The discontinuous fold is the one of the block-on-belt system (Fig. 7 of *Fold bifurcations in
discontinuous systems*): a stable branch ends at a fold that forward shooting cannot pass, because the
branch beyond it is *infinitely unstable* (its orbits slide along a repulsion sliding mode;
multipliers ``(1, inf)``).  :func:`follow_through_discontinuous_fold` locates the end of the stable
branch, restarts continuation with backward-time shooting, in which the unstable orbits are
attracting, and records the discontinuous fold joining the two branches.  :class:`BifurcationDiagram`
holds the branches of one model over one parameter.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from saltation.branches.branch import (
    Branch,
    Limits,
    SpecialPoint,
    SpecialPointKind,
    SpecialPointStatus,
    StopReason,
)
from saltation.engine.flow import EventKind
from saltation.errors import SaltationError
from saltation.orbits.classification import classify_nonsmooth
from saltation.orbits.equilibria import EquilibriumProblem
from saltation.orbits.pseudo_equilibria import (
    PseudoEquilibriumProblem,
    find_pseudo_equilibrium,
)
from saltation.orbits.records import BranchPoint
from saltation.orbits.single import ShootingProblem
from saltation.special_points.boundary_equilibria import (
    boundary_equilibria,
    boundary_equilibria_of_mode,
)
from saltation.special_points.branch_switching import (
    follow_asymmetric_branch,
    follow_period_doubled_branch,
)
from saltation.special_points.continuation import (
    Continuation,
    ContinuationSettings,
    Corrector,
    Solution,
    canonical_events,
)
from saltation.special_points.grazing import locate_tangential_return
from saltation.special_points.points import special_point_between, with_border_scenario

#: A callback handed each new branch point (a progress bar's counter).
Progress = Callable[[BranchPoint], None]


@dataclass
class BifurcationDiagram:
    """Branches of one model over one parameter (a fold joining two branches is a special point of one).

    Attributes
    ----------
    model : str
        The model's name.
    parameter_name : str
        The parameter the branches are followed in.
    branches : list of Branch
        The branches.
    """

    model: str
    parameter_name: str
    branches: list[Branch] = field(default_factory=list)

    @property
    def special_points(self) -> list[SpecialPoint]:
        """Every special point of every branch; a point where two branches join (a discontinuous fold that
        ends one and starts the other) is listed once."""
        return distinct_special_points(self.branches)


def distinct_special_points(branches: Sequence[Branch]) -> list[SpecialPoint]:
    """Every special point of the branches, in order, where two branches join listed once.

    Parameters
    ----------
    branches : sequence of Branch
        The branches of a diagram.

    Returns
    -------
    list of SpecialPoint
        Their special points, in order; a point where two branches join (the same kind at the same
        parameter, recorded at the end of one and the start of the other) once.

    Raises
    ------
    Nothing of its own: it compares kinds and parameters.
    """
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

    Parameters
    ----------
    corrector : Corrector
        The corrector of the branch's run.
    last : Solution
        The last solution of the branch.
    lam_fail : float
        A parameter value where the corrector fails.
    tol : float
        The bracket's width at which the bisection stops.

    Returns
    -------
    end : Solution
        The last solution found (with the branch's event sequence).
    bad : float
        The parameter value nearest to it known to fail.

    Raises
    ------
    Nothing of its own: a failed correction narrows the bracket.
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

    Parameters
    ----------
    forward_problem : ShootingProblem
        The forward-time problem of the stable branch.
    stable : Solution
        A stable orbit of that branch.
    periods : int
        Periods of the backward transients.
    offset : float
        The push off the stable orbit, relative to ``1 + |x|``.
    phases : int
        Instants of the period the pushes start from.

    Returns
    -------
    ndarray or None
        The unknowns of the infinitely unstable orbit for backward shooting, or None when none is found.

    Raises
    ------
    SaltationError
        If the stable orbit cannot be integrated (a failed transient or shooting is skipped).
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


def _check_no_resets(problem, end) -> None:
    """Refuse the backward-time branch beyond a fold whose orbits pass a reset: backward in time the engine
    applies resets as written, so its orbits would be another model's (and a reset that forgets cannot be run
    backwards at all)."""
    resets = getattr(problem.system, "resets", None)
    ids = getattr(getattr(end, "summary", None), "event_ids", ()) or ()
    if resets is None:
        return
    with_reset = sorted({int(k) for kind, k, _ in ids
                         if kind == int(EventKind.TRANSITION) and 0 <= int(k) < len(resets) and resets[int(k)] is not None})
    if with_reset:
        labels = ", ".join(f"{k} ({problem.system.transitions[k].label})" for k in with_reset)
        raise SaltationError(
            f"the orbits at the end of the branch pass transitions with a reset ({labels}): backward-time shooting "
            "applies resets as written, so the branch beyond the fold in backward time would not be this model's "
            "(a Filippov model's, without resets, is)")


def follow_through_discontinuous_fold(
    forward: Continuation,
    *,
    settings: ContinuationSettings | None = None,
    progress: Progress | None = None,
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
    settings : ContinuationSettings, optional
        For the backward-time branch (the run's own by default).
    progress : callable, optional
        Called with each new point of the backward-time branch.
    offset : float
        How far inside the end the unstable orbit is looked for, relative to ``1 + |lam|``.

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
    if prob_f.single_shooting is None or prob_f.backward:
        raise SaltationError("follow_through_discontinuous_fold needs a forward-time shooting continuation")
    settings = settings or forward.settings
    end, bad = _branch_end(forward)
    _check_no_resets(prob_f, end)
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
    away = _run(prob_b, seed, lam_in, settings, -int(towards), progress)
    near = _run(prob_b, seed, lam_in, settings, int(towards), progress)
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
    fold = with_border_scenario(_fold_by_tangential_return(prob_f, end, fold, forward.corrector),
                                autonomous=prob_f.autonomous)
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


# --------------------------------------------------------------------------------------------
# which branches to follow from which special points
# --------------------------------------------------------------------------------------------

#: The special points :func:`switch_branches` follows new branches from by default.
SWITCHES = (SpecialPointKind.SYMMETRY_BREAKING, SpecialPointKind.BOUNDARY_EQUILIBRIUM)


def switch_branches(
    problem,
    branch: Branch,
    *,
    settings: ContinuationSettings | None = None,
    kinds: Sequence[SpecialPointKind] = SWITCHES,
) -> list[Branch]:
    """The branches born at the special points of a branch, each followed from its first point.

    * At a symmetry breaking of a branch of symmetric periodic orbits (single shooting): the branch of
      asymmetric orbits (:func:`~saltation.special_points.branch_switching.follow_asymmetric_branch`),
      one of each mirror pair; a branch that meets the symmetric orbits again at another symmetry
      breaking is not started again from there.
    * At a boundary equilibrium of a branch of equilibria: the other branch through it, both ways: the
      pseudo-equilibria on the surface from a mode's equilibria, the mode's equilibria from a branch of
      pseudo-equilibria.  The boundary equilibria are those recorded on the branch
      (:func:`follow_branch` records them).
    * At a period doubling of a branch of periodic orbits (single shooting; forced, or autonomous with
      the doubled period an unknown), only when ``kinds`` names it: the branch of period-2 orbits
      (:func:`~saltation.special_points.branch_switching.follow_period_doubled_branch`).

    A branch that cannot start (no new orbit or equilibrium is found there) is left out.

    Parameters
    ----------
    problem : ShootingProblem, EquilibriumProblem or PseudoEquilibriumProblem
        The problem of ``branch``, its continuation parameter set.
    branch : Branch
        The branch, with its special points.
    settings : ContinuationSettings, optional
        For the new branches (``ContinuationSettings()`` by default).
    kinds : sequence of SpecialPointKind
        The special points to switch at (:data:`SWITCHES`: symmetry breakings and boundary equilibria).

    Returns
    -------
    list of Branch
        The new branches, in the order of their special points on ``branch``.

    Raises
    ------
    Nothing of its own: a branch that cannot start is left out.
    """
    settings = settings or ContinuationSettings()
    if isinstance(problem, EquilibriumProblem):
        if SpecialPointKind.BOUNDARY_EQUILIBRIUM not in kinds:
            return []
        return _through_boundary_equilibria(problem, branch, settings)
    if problem.single_shooting is None:
        return []
    others = _asymmetric_branches(problem, branch, settings) if SpecialPointKind.SYMMETRY_BREAKING in kinds else []
    if SpecialPointKind.PERIOD_DOUBLING in kinds:
        others += _period_doubled_branches(problem, branch, settings)
    return others


def boundary_equilibria_on(problem: EquilibriumProblem, branch: Branch) -> list[SpecialPoint]:
    """The boundary equilibria of a branch of equilibria: where it reaches a switching surface.

    Parameters
    ----------
    problem : EquilibriumProblem or PseudoEquilibriumProblem
        The branch's problem: a mode's equilibria (where one reaches a surface of the mode's domain) or
        the pseudo-equilibria of a sliding motion (where one reaches the end of the sliding region).
    branch : Branch
        The branch.

    Returns
    -------
    list of SpecialPoint
        Of kind ``boundary_equilibrium``, located
        (:func:`~saltation.special_points.boundary_equilibria.boundary_equilibria`,
        :func:`~saltation.special_points.boundary_equilibria.boundary_equilibria_of_mode`).

    Raises
    ------
    SaltationError
        If a boundary equilibrium bracketed on the branch cannot be located.
    """
    if isinstance(problem, PseudoEquilibriumProblem):
        return boundary_equilibria(problem, branch)
    return boundary_equilibria_of_mode(problem, branch)


def _asymmetric_branches(problem: ShootingProblem, branch: Branch, settings: ContinuationSettings) -> list[Branch]:
    """From each symmetry breaking of a branch of symmetric orbits, the branch of asymmetric orbits born there."""
    others, reached = [], []
    for sp in branch.special_points:
        if sp.kind is not SpecialPointKind.SYMMETRY_BREAKING:
            continue
        if any(abs(sp.parameter - lam) <= 1e-8 * max(1.0, abs(lam)) for lam in reached):
            continue
        try:
            side = follow_asymmetric_branch(problem, sp, settings=settings,
                                            label=f"asymmetric, from {problem.lam_name} = {sp.parameter:.9g}")
        except SaltationError:
            continue
        reached += [p.parameter for p in side.special_points if p.kind is SpecialPointKind.SYMMETRY_BREAKING]
        others.append(side)
    return others


def _period_doubled_branches(problem: ShootingProblem, branch: Branch, settings: ContinuationSettings) -> list[Branch]:
    """From each period doubling of a branch of periodic orbits, the branch of period-2 orbits born there."""
    others = []
    for sp in branch.special_points:
        if sp.kind is not SpecialPointKind.PERIOD_DOUBLING:
            continue
        try:
            others.append(follow_period_doubled_branch(
                problem, sp, settings=settings, label=f"period 2, from {problem.lam_name} = {sp.parameter:.9g}"))
        except SaltationError:
            continue
    return others


def _through_boundary_equilibria(problem: EquilibriumProblem, branch: Branch,
                                 settings: ContinuationSettings) -> list[Branch]:
    """From each boundary equilibrium of an equilibrium branch, the other branch through it, both ways."""
    flow, parameter = problem.flow, problem.lam_name
    sliding = isinstance(problem, PseudoEquilibriumProblem)
    others = []
    for sp in branch.special_points:
        if sp.kind is not SpecialPointKind.BOUNDARY_EQUILIBRIUM:
            continue
        values = problem.parameters_at(sp.parameter)
        try:
            if sliding:  # from the pseudo-equilibria to the mode's equilibria
                other = EquilibriumProblem(flow, sp.touch_mode, values, continuation_parameter=parameter)
                u0 = other.solve(sp.state, sp.parameter).state
            else:
                point = find_pseudo_equilibrium(flow, sp.touch_surface, sp.state, parameters=values)
                other = PseudoEquilibriumProblem(flow, sp.touch_surface, point.modes, values,
                                                 continuation_parameter=parameter)
                u0 = PseudoEquilibriumProblem.unknowns(point)
            for direction in (1, -1):
                cont = _run(other, u0, sp.parameter, settings, direction, None)
                cont.branch.label = f"equilibrium of {sp.touch_mode}" if sliding else f"pseudo-equilibria on {sp.touch_surface}"
                if len(cont.branch) > 1:
                    others.append(cont.branch)
        except SaltationError:
            continue
    return others


# --------------------------------------------------------------------------------------------
# one branch as far as it goes
# --------------------------------------------------------------------------------------------

class BranchEnd(enum.Enum):
    """What :func:`follow_branch` found where the branch stopped, beyond its run's stop reason."""

    #: the run's stop reason says it all (a parameter bound, the number of points, ...)
    RUN = "run"
    #: the corrector failed at the minimum step at a special point whose orbit lies on a switching surface
    #: all round (``FollowedBranch.ended_at``)
    ON_SURFACE = "on_surface"
    #: the corrector failed at the minimum step at a discontinuous fold, and the infinitely unstable branch
    #: beyond it was followed in backward time (``FollowedBranch.beyond``)
    DISCONTINUOUS_FOLD = "discontinuous_fold"
    #: the corrector failed at the minimum step, and no branch was found beyond (``FollowedBranch.error``)
    CORRECTOR_FAILED = "corrector_failed"


@dataclass
class FollowedBranch:
    """What :func:`follow_branch` found.

    Attributes
    ----------
    branch : Branch
        The branch followed, with its special points (the boundary equilibria of a branch of equilibria
        included, and the discontinuous fold at its end where one was passed).
    continuation : Continuation
        The run that followed it.
    switched : list of Branch
        The branches born at its special points (:func:`switch_branches`).
    end : BranchEnd
        What ended it.
    beyond : Branch or None
        The backward-time branch past a discontinuous fold, ordered from the fold outwards.
    fold : SpecialPoint or None
        That fold.
    ended_at : SpecialPoint or None
        The special point at the end, where ``end`` is ``ON_SURFACE``.
    error : SaltationError or None
        Why no branch beyond was found, where ``end`` is ``CORRECTOR_FAILED``.
    boundary_equilibria : list of SpecialPoint
        The boundary equilibria located on a branch of equilibria.
    """

    branch: Branch
    continuation: Continuation
    switched: list[Branch] = field(default_factory=list)
    end: BranchEnd = BranchEnd.RUN
    beyond: Branch | None = None
    fold: SpecialPoint | None = None
    ended_at: SpecialPoint | None = None
    error: SaltationError | None = None
    boundary_equilibria: list[SpecialPoint] = field(default_factory=list)

    @property
    def branches(self) -> list[Branch]:
        """The branch, the branches born on it, and the branch beyond its end (where there is one)."""
        return [self.branch, *self.switched, *([self.beyond] if self.beyond is not None else [])]


def follow_branch(
    problem,
    u0: np.ndarray,
    lam0: float,
    *,
    settings: ContinuationSettings | None = None,
    direction: int = 1,
    progress: Progress | None = None,
    switch: bool = True,
    through_fold: bool = True,
    switch_at: Sequence[SpecialPointKind] = SWITCHES,
) -> FollowedBranch:
    """Follow a branch one way from a start point, and the branches that go on from it.

    1. The branch is continued from ``(u0, lam0)`` in ``direction`` with its special points
       (:class:`~saltation.special_points.continuation.Continuation`).
    2. On a branch of equilibria its boundary equilibria are located and recorded
       (:func:`boundary_equilibria_on`).
    3. With ``switch``, the branches born at its special points of the kinds ``switch_at`` are followed
       (:func:`switch_branches`).
    4. Where the run stops at the minimum step: at a special point whose orbit lies on a switching
       surface all round the branch ends there; otherwise, with ``through_fold``, a forward-time
       single-shooting branch is followed through the discontinuous fold
       (:func:`follow_through_discontinuous_fold`), which adds the fold to the branch.

    Parameters
    ----------
    problem : ShootingProblem, MultipleShootingProblem, EquilibriumProblem or PseudoEquilibriumProblem
        The problem, its continuation parameter set.
    u0 : ndarray
        The unknowns of the start point (``problem.pack``).
    lam0 : float
        The parameter's value there.
    settings : ContinuationSettings, optional
        Step sizes and bounds of every branch (``ContinuationSettings()`` by default).
    direction : int
        +1 towards larger parameter values, -1 towards smaller ones.
    progress : callable, optional
        Called with each new point of the branch and of the branch beyond a fold.
    switch : bool
        Follow the branches born at its special points.
    through_fold : bool
        Follow the branch beyond a discontinuous fold.
    switch_at : sequence of SpecialPointKind
        The special points to switch branches at (:data:`SWITCHES`: symmetry breakings and boundary
        equilibria; add ``SpecialPointKind.PERIOD_DOUBLING`` for the period-2 branches).

    Returns
    -------
    FollowedBranch
        The branch, the branches switched to, and what ended it.

    Raises
    ------
    SaltationError
        If the start point cannot be corrected (see
        :meth:`~saltation.branches.continuation.Continuation.run`), or a boundary equilibrium cannot be
        located.  A failure beyond the end is recorded (``CORRECTOR_FAILED``), not raised.

    References
    ----------
    Leine and Van Campen, "Fold bifurcations in discontinuous systems" (the discontinuous fold and the
    infinitely unstable branch, Fig. 7).
    """
    settings = settings or ContinuationSettings()
    cont = _run(problem, u0, lam0, settings, direction, progress)
    branch = cont.branch
    found = []
    if isinstance(problem, EquilibriumProblem):  # where an equilibrium reaches a switching surface
        found = boundary_equilibria_on(problem, branch)
        branch.special_points = sorted([*branch.special_points, *found], key=lambda sp: sp.index)
    followed = FollowedBranch(branch, cont, boundary_equilibria=found)
    if switch:
        followed.switched = switch_branches(problem, branch, settings=settings, kinds=switch_at)
    if branch.stop_reason is not StopReason.MIN_STEP:
        return followed
    ended = [sp for sp in branch.special_points if sp.index >= len(branch.points) - 1 and sp.limits == Limits.ON_SURFACE]
    if ended:
        followed.end, followed.ended_at = BranchEnd.ON_SURFACE, ended[0]
    elif through_fold and problem.single_shooting is not None and not problem.backward:
        try:
            followed.beyond, followed.fold = follow_through_discontinuous_fold(cont, settings=settings,
                                                                                progress=progress)
            followed.end = BranchEnd.DISCONTINUOUS_FOLD
        except SaltationError as exc:
            followed.end, followed.error = BranchEnd.CORRECTOR_FAILED, exc
    return followed


def _run(problem, u0: np.ndarray, lam0: float, settings: ContinuationSettings, direction: int,
         progress: Progress | None) -> Continuation:
    """One continuation run, each new point handed to ``progress``."""
    cont = Continuation(problem, settings)
    for point in cont.run(u0, lam0, direction=direction):
        if progress is not None:
            progress(point)
    return cont


__all__ = [
    "SWITCHES",
    "BifurcationDiagram",
    "BranchEnd",
    "FollowedBranch",
    "boundary_equilibria_on",
    "distinct_special_points",
    "find_backward_seed",
    "follow_branch",
    "follow_through_discontinuous_fold",
    "locate_branch_end",
    "switch_branches",
]
