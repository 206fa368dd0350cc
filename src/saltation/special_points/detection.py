"""Detection, location and classification of special points along a branch.

Smooth special points are found by test functions and located by the
Illinois method along the secant between two branch points:

* fold (turning point): the parameter component of the tangent changes sign;
* period doubling: a real multiplier passes -1 (``prod(mu + 1)`` changes sign);
* Neimark-Sacker: a complex pair leaves the unit circle (a product of two multipliers passes 1);
* branch point: a real multiplier passes +1 without a turning point (``prod(mu - 1)`` changes sign);
* Hopf (equilibria): a complex pair of eigenvalues crosses the imaginary axis.

*Discontinuous* (non-smooth) points are where the orbit's event sequence
changes.  They are located by bisection along the secant to ``locate_tol``;
the monodromies on both sides, ``M-`` and ``M+``, give the set-valued
Floquet multipliers, the eigenvalues of ``(1 - q) M- + q M+`` for ``q`` in
``[0, 1]``.  Where that set crosses the unit circle the point is a
discontinuous fold (through +1), flip (through -1) or Neimark-Sacker (a
complex pair); if it stays on one side it is a jump without crossing.

For a model that declares a symmetry (:mod:`saltation.model.symmetry`), the symmetric orbits' multipliers
are split by the half-period map (:mod:`saltation.orbits.symmetry`): where a real half-period multiplier
passes -1 the point is a ``symmetry_breaking`` (the full multiplier passes +1, but the branch goes on),
located on the half-period map, where it is regular; at corners the set-valued half-period multipliers
classify the point (``discontinuous_symmetry_breaking`` through -1), and a branch that passes at a
non-smooth point from symmetric to asymmetric orbits records a ``discontinuous_symmetry_breaking`` too.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from saltation.orbits.boundary import (
    corner_saltation_is_bounded,
    one_sided_limits,
    saltation_at_corner,
    zero_length_segments,
)
from saltation.branches.branch import Branch, BranchKind, Limits, SpecialPoint, SpecialPointKind, SpecialPointStatus
from saltation.branches.corrector import Corrector, Solution, canonical_events
from saltation.errors import SaltationError
from saltation.orbits.floquet import eigenvalues, multipliers_from_monodromy, set_valued_multipliers
from saltation.special_points.grazing import grazing_candidates, locate_grazing
from saltation.engine.flow import EventKind
from saltation.orbits.shooting import ShootingProblem
from saltation.orbits.symmetry import (
    SymmetricMultipliers,
    half_period_trajectory,
    solve_symmetric_orbit,
    split_half_map,
    symmetry_breaking_test,
)
from saltation.errors import IntegrationError, ModelError
from saltation.model.symmetry import check_symmetry
from saltation.model.system import PiecewiseSystem
from saltation.special_points.sliding import locate_adding_sliding, locate_tangent_arrival, sliding_change


@dataclass(frozen=True)
class SetValuedCrossing:
    """How the set-valued multipliers of a non-smooth point meet the unit circle.

    Attributes
    ----------
    kind : SpecialPointKind
        ``discontinuous_fold`` (through +1), ``discontinuous_flip`` (through -1),
        ``discontinuous_neimark_sacker`` (a complex pair) or ``nonsmooth_no_crossing``.
    q : float or None
        Where the crossing happens on the convex combination ``(1 - q) M- + q M+`` (None without one).
    point : complex or None
        The forward-time multiplier on the unit circle there (None without a crossing).
    gamma : complex or None
        For a symmetric orbit classified by its half-period map: the half-period multiplier on the
        unit circle (``point = gamma**2``).
    """

    kind: SpecialPointKind
    q: float | None
    point: complex | None
    gamma: complex | None = None


def classify_nonsmooth(
    m_minus: np.ndarray | None,
    m_plus: np.ndarray | None,
    *,
    backward: bool = False,
    autonomous: bool = False,
    mu_minus: np.ndarray | None = None,
    mu_plus: np.ndarray | None = None,
    num: int = 801,
) -> SetValuedCrossing:
    """Classify a non-smooth point from its one-sided monodromies.

    The eigenvalue paths of ``(1 - q) M- + q M+`` are followed for ``q`` in
    ``[0, 1]``.  Where the two sides have as many multipliers outside the unit circle, the first
    non-trivial path whose magnitude passes 1 decides the kind; where they differ, the crossing that takes
    a path out (or in) for good does: the last crossing of a path that ends outside, the first of one that
    starts outside (a path that leaves through +1 and returns before a complex pair leaves does not make
    the jump a fold).  Monodromies computed in backward time are combined in backward
    time (their eigenvalues are reciprocals of the forward multipliers, and
    the unit circle, +1 and -1 are the same).  When one side is infinitely
    unstable (a forward multiplier is infinite; ``M`` is then not available
    in forward time), the jump runs along the real axis from the finite
    multiplier to infinity and crosses at ``q = 0``.

    Parameters
    ----------
    m_minus, m_plus : ndarray, shape (n, n), or None
        The one-sided monodromies, in the direction of integration (None for an infinitely unstable
        side).
    backward : bool
        Whether they were computed in backward time.
    autonomous : bool
        Whether the orbit is autonomous (its trivial path, at 1 throughout, is skipped).
    mu_minus, mu_plus : ndarray, complex, optional
        The one-sided forward multipliers, needed where a monodromy is None.
    num : int
        Number of values of ``q`` on which the paths are followed (each crossing is then refined by
        bisection).

    Returns
    -------
    SetValuedCrossing
        The kind, and where the set crosses the unit circle.

    Raises
    ------
    SaltationError
        If a monodromy is missing and the multipliers do not make up for it (both sides' multipliers
        are needed, and one side must be infinitely unstable).
    numpy.linalg.LinAlgError
        If a monodromy is not finite.

    References
    ----------
    Leine and Van Campen, "Fold bifurcations in discontinuous systems" (set-valued Floquet
    multipliers and discontinuous bifurcations).
    """
    if m_minus is None or m_plus is None:
        fin = mu_minus if m_minus is not None else mu_plus
        inf_side = mu_plus if m_minus is not None else mu_minus
        if fin is None or inf_side is None:
            raise SaltationError("a non-smooth point needs both one-sided monodromies or multipliers")
        if any(np.isinf(np.abs(inf_side))):
            finite_partner = [m for m in fin if abs(m - 1.0) > 1e-6 or not autonomous]
            m = finite_partner[0] if finite_partner else fin[-1]
            if abs(m.imag) < 1e-9 and m.real >= 0:
                return SetValuedCrossing(SpecialPointKind.DISCONTINUOUS_FOLD, 0.0, complex(1.0, 0.0))
            if abs(m.imag) < 1e-9:
                return SetValuedCrossing(SpecialPointKind.DISCONTINUOUS_FLIP, 0.0, complex(-1.0, 0.0))
            return SetValuedCrossing(SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER, 0.0, m / abs(m))
        raise SaltationError("one-sided monodromy missing for a finite jump")
    sv = set_valued_multipliers(m_minus, m_plus, num=num, backward=False)
    paths = sv.paths
    mags = np.abs(paths)
    n = paths.shape[1]
    trivial = -1
    if autonomous:
        dev = np.max(np.abs(paths - 1.0), axis=0)
        trivial = int(np.argmin(dev)) if np.min(dev) < 1e-5 else -1
    # where the number of multipliers outside the unit circle differs between the two sides, the kind is that
    # of the crossing that takes a path out for good: the last crossing of a path outside at q = 1, the
    # first of one outside at q = 0 (a path may leave through +1 and come back before a complex pair leaves
    # for good: the jump is then a discontinuous Neimark-Sacker).  Otherwise the set's first crossing.
    g_all = np.where(np.isfinite(mags), mags - 1.0, 1e300)
    keep = [i for i in range(n) if i != trivial]
    net = bool(keep) and int(np.sum(g_all[0, keep] > 0)) != int(np.sum(g_all[-1, keep] > 0))
    best = None
    for i in keep:
        g = g_all[:, i]
        sign_change = np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0]
        if sign_change.size == 0:
            continue
        if net:
            if (g[0] > 0) == (g[-1] > 0):
                continue  # out and back (or in and out again): not what changes the count
            k = int(sign_change[-1] if g[-1] > 0 else sign_change[0])
        else:
            k = int(sign_change[0])
        if g[k] == g[k + 1]:
            qc = float(sv.q[k])
        else:
            qc = float(sv.q[k] + (sv.q[k + 1] - sv.q[k]) * g[k] / (g[k] - g[k + 1]))
        qc, point = _refine_crossing(m_minus, m_plus, paths[k, i], qc, float(sv.q[k]), float(sv.q[k + 1]))
        if best is None or qc < best[0]:
            best = (qc, point)
    if best is None:
        return SetValuedCrossing(SpecialPointKind.NONSMOOTH_NO_CROSSING, None, None)
    qc, point = best
    if backward:
        point = 1.0 / point
    if abs(point.imag) > 1e-6:
        kind = SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER
    elif point.real > 0:
        kind = SpecialPointKind.DISCONTINUOUS_FOLD
    else:
        kind = SpecialPointKind.DISCONTINUOUS_FLIP
    return SetValuedCrossing(kind, qc, complex(point))


def _squares_agree(half: tuple[np.ndarray, np.ndarray], mu_lo: np.ndarray, mu_hi: np.ndarray, *,
                   backward: bool) -> bool:
    """Whether the one-sided half-period maps ``half`` have, on each side, as many eigenvalues whose squares
    lie outside the unit circle as the full one-sided multipliers ``mu_lo``, ``mu_hi`` (``M = G^2``).

    Magnitudes within 1e-6 of 1 (a trivial multiplier, a side at a fold) count either way."""
    for g, mu in zip(half, (mu_lo, mu_hi)):
        if mu is None:
            return False
        squares = np.abs(multipliers_from_monodromy(g, backward=backward)) ** 2
        full = np.abs(np.asarray(mu))
        if np.sum(squares > 1.0 + 1e-6) > np.sum(full > 1.0 - 1e-6) or np.sum(full > 1.0 + 1e-6) > np.sum(squares > 1.0 - 1e-6):
            return False
    return True


def _refine_crossing(m_minus, m_plus, guide: complex, q0: float, qa: float, qb: float) -> tuple[float, complex]:
    """Refine the crossing ``|mu(q)| = 1`` of the eigenvalue path near ``guide`` by bisection."""

    def mu_at(q: float, near: complex) -> complex:
        ev = eigenvalues((1.0 - q) * m_minus + q * m_plus)  # (LAPACK's dgeev as numpy's eigvals, without its dispatch)
        return complex(ev[np.argmin(np.abs(ev - near))])

    ma = mu_at(qa, guide)
    ga = abs(ma) - 1.0
    near = ma
    for _ in range(60):
        qm = 0.5 * (qa + qb)
        mm = mu_at(qm, near)
        gm = abs(mm) - 1.0
        if np.sign(gm) == np.sign(ga) and gm != 0.0:
            qa, ga, near = qm, gm, mm
        else:
            qb = qm
            near = mm
        if qb - qa < 1e-13:
            break
    q = 0.5 * (qa + qb)
    return q, mu_at(q, near)


class SpecialPointDetector:
    """Looks for special points between consecutive branch points and locates them.

    Made by the continuation engine as ``SpecialPointDetector(problem, corrector, branch)`` (a
    :data:`~saltation.branches.continuation.DetectorFactory`).

    Parameters
    ----------
    problem : ShootingProblem or EquilibriumProblem
        The branch's problem.
    corrector : Corrector
        The branch's corrector (its settings give the location tolerance ``locate_tol``).
    branch : Branch
        The branch being followed (its kind, time direction and whether it is autonomous).
    """

    def __init__(self, problem, corrector: Corrector, branch: Branch):
        self.problem = problem
        self.corrector = corrector
        self.branch = branch
        self.tol = corrector.settings.locate_tol
        self.equilibrium = branch.kind is BranchKind.EQUILIBRIUM
        self.autonomous = branch.autonomous and not self.equilibrium
        symmetry = getattr(problem.system, "symmetry", None)
        # the half-period map splits the multipliers of the symmetric orbits of one-period shooting, where the
        # model has its symmetry at the branch's parameters (it may hold at some values only)
        self.symmetry = None
        if symmetry is not None and isinstance(problem, ShootingProblem) and problem.periods == 1:
            try:
                check_symmetry(problem.system, symmetry, problem.parameters_at(branch.points[0].parameter
                                                                               if branch.points else None))
            except ModelError:
                pass
            else:
                self.symmetry = symmetry.S

    def past_failure(self, prev: Solution) -> tuple[Solution, SpecialPoint] | None:
        """Past a grazing that stopped the corrector: ``(first solution beyond, grazing special point)`` or None.

        Near a grazing the branch on the crossing side leaves the grazing orbit
        with a tangent of unbounded slope (its monodromy grows like
        ``1/sqrt(d)``), and pseudo-arclength steps from the side that misses
        the surface fail.  When the last orbit nearly touches a surface that
        a transition of its mode would cross, the grazing orbit is located by
        its defining system (:mod:`saltation.special_points.grazing`), and the branch is
        restarted just beyond it, at growing distances, from the grazing
        orbit's state.

        Parameters
        ----------
        prev : Solution
            The last point the corrector reached.

        Returns
        -------
        tuple of (Solution, SpecialPoint) or None
            The first solution across the grazing and the grazing's record; None for a problem other
            than a single-shooting one over one period, or when no grazing explains the failure.
        """
        prob = self.problem
        if not isinstance(prob, ShootingProblem) or prob.periods != 1:
            return None
        flow, p = prob.flow, prob.parameters_at(prev.lam)
        n = prob.system.n
        T = prob.period_of(prev.u, prev.lam)
        try:
            traj = flow.run(prev.u[:n], prob.t0, prob.t0 + prob.sign * T, p, mode0=prob.mode0, dense=True,
                            tolerances=prob.tolerances)
        except SaltationError:
            return None
        direction = 1.0 if prev.tangent[-1] >= 0 else -1.0
        s = self.corrector.settings
        for transition, t_guess in grazing_candidates(flow, traj, p):
            try:
                orbit = locate_grazing(
                    flow, prev.u[:n], prev.lam, prob.lam_name, transition, t_guess, parameters=p, t0=prob.t0,
                    tolerances=prob.tolerances, period=T if prob.autonomous else None, backward=prob.backward,
                    mode0=prob.mode0,
                )
            except SaltationError:
                continue
            ahead = (orbit.parameter - prev.lam) * direction
            if not -1e-9 <= ahead <= 4.0 * s.ds_max:
                continue
            u_graze = prob.pack(orbit.state0, orbit.period if prob.autonomous else None)
            z_graze = np.append(u_graze, orbit.parameter)
            for delta in (1e-6, 1e-5, 1e-4, 1e-3, 1e-2):
                lam = orbit.parameter + direction * delta * max(1.0, abs(orbit.parameter))
                if not s.bounds[0] <= lam <= s.bounds[1]:
                    break
                try:
                    start = prob.solve(u_graze, lam)
                    cand = self.corrector.solve_fixed(prob.pack(start.state0, start.period if prob.autonomous else None),
                                                      lam)
                except SaltationError:
                    continue
                if canonical_events(cand.summary.event_ids) == canonical_events(prev.summary.event_ids):
                    continue  # the same side again: not across the grazing
                away = cand.z - z_graze
                cand.tangent = self.corrector.tangent(cand, away / np.linalg.norm(away))
                cand.step = float(np.linalg.norm(away))
                special = grazing_point(prob, prev, cand, len(self.branch.points) - 1)
                if special is None:
                    continue
                return cand, special
        return None

    # -- detection ------------------------------------------------------------------------
    def at_failure(self, prev: Solution, failed: float) -> SpecialPoint | None:
        """The end of a branch whose last orbit comes to lie on a switching surface all round.

        The end is first bracketed in the parameter, between the last orbit the corrector reaches (from
        ``prev``) and ``failed``, to the location tolerance.  If that orbit has no events and lies on a
        surface over its whole period (:func:`~saltation.orbits.on_surface.orbit_on_surface`), the point is
        classified by its one-sided limits there (``Limits.ON_SURFACE``): the variational equation along
        it with its own mode's Jacobian (``M-``) and the Jacobian of the mode across the surface (``M+``).

        Parameters
        ----------
        prev : Solution
            The last point the corrector reached.
        failed : float
            A parameter value beyond it at which the corrector failed.

        Returns
        -------
        SpecialPoint or None
            A ``bracketed`` point between the last orbit and the first failure, or None for anything else
            (a single-shooting problem over one period is needed).
        """
        from saltation.orbits.on_surface import monodromy_in_mode, orbit_on_surface

        prob = self.problem
        if self.equilibrium or not isinstance(prob, ShootingProblem) or prob.periods != 1 or prob.backward:
            return None
        good, bad = prev, float(failed)
        sequence = canonical_events(prev.summary.event_ids)
        for _ in range(60):
            if abs(bad - good.lam) <= self.tol * (1.0 + abs(good.lam)):
                break
            mid = 0.5 * (good.lam + bad)
            try:
                cand = self.corrector.solve_fixed(good.u, mid)
            except SaltationError:
                bad = mid
                continue
            if canonical_events(cand.summary.event_ids) == sequence:
                good = cand
            else:  # another orbit (the corrector jumped across the end): not the branch's
                bad = mid
        n = prob.system.n
        p = prob.parameters_at(good.lam)
        T = prob.period_of(good.u, good.lam)
        try:
            traj = prob.flow.run(good.u[:n], prob.t0, prob.t0 + T, p, mode0=prob.mode0, variational=True,
                                 dense=True, tolerances=prob.tolerances)
        except SaltationError:
            return None
        on = orbit_on_surface(prob.flow, traj, p)
        if on is None:
            return None
        m_minus = traj.monodromy
        m_plus = monodromy_in_mode(prob.flow, traj, p, on.other_mode)
        mu_minus = multipliers_from_monodromy(m_minus)
        mu_plus = multipliers_from_monodromy(m_plus)
        crossing = classify_nonsmooth(m_minus, m_plus, autonomous=self.autonomous, mu_minus=mu_minus, mu_plus=mu_plus)
        lo_lam, hi_lam = sorted((good.lam, bad))
        return SpecialPoint(
            kind=crossing.kind, parameter=good.lam, bracket=(lo_lam, hi_lam), accuracy=hi_lam - lo_lam,
            index=len(self.branch.points) - 1, state=good.summary.state, period=good.summary.period,
            amplitude=good.summary.amplitude, multipliers_minus=mu_minus, multipliers_plus=mu_plus,
            monodromy_minus=m_minus, monodromy_plus=m_plus, crossing_q=crossing.q, crossing_point=crossing.point,
            event_labels_minus=good.summary.event_labels, limits=Limits.ON_SURFACE,
            multipliers_accuracy=self._matrix_error(good), touch_surface=on.surface, touch_mode=on.mode,
            note=(f"the orbit lies on {on.surface} all round (|h| <= {on.distance:.1e}) in mode {on.mode}; beyond it "
                  f"the orbits lie in {on.other_mode}, where the corrector cannot follow them from this side: "
                  f"one-sided limits from the variational equation along it with {on.mode}'s and {on.other_mode}'s "
                  f"Jacobians"),
        )

    def check(self, a: Solution, b: Solution, index: int) -> list[SpecialPoint]:
        """The special points between two consecutive branch points, in branch order.

        Where the event sequence changes, the non-smooth point is located first; the smooth test
        functions are then evaluated on each smooth piece of the step (from ``a`` to the located
        point's near side, from its far side to ``b``), so that a fold or a multiplier crossing in the
        same step as the change is found too.

        Parameters
        ----------
        a, b : Solution
            Consecutive corrected points.
        index : int
            The index of ``a`` on the branch.

        Returns
        -------
        list of SpecialPoint
            The located points (folds and multiplier crossings that fail their check are left out).

        Raises
        ------
        SaltationError
            If the one-sided monodromies needed to classify a non-smooth point are missing.
        """
        return self._check(a, b, index, None)

    def _check(self, a: Solution, b: Solution, index: int,
               bracket: tuple[Solution, Solution] | None) -> list[SpecialPoint]:
        """:meth:`check`, with the bracket of the step's first change when it is already located."""
        if canonical_events(a.summary.event_ids) == canonical_events(b.summary.event_ids):
            return self._smooth_points(a, b, index)
        lo, hi = bracket if bracket is not None else self._bisect_event_change(a, b)
        hi, following = self._past_unresolved_sequences(hi, b)
        corner = self._symmetry_breaking_corner(self.nonsmooth_point(lo, hi, index, far=(a, b)), a, b)
        before = self._smooth_points(a, lo, index) if lo is not a else []
        # a step may hold more than one change: the rest of it is checked as a step of its own, from the
        # next change's bracket where that was located already
        after = self._check(hi, b, index, following) if hi is not b else []
        return [*before, corner, *after]

    def _past_unresolved_sequences(
        self, hi: Solution, b: Solution,
    ) -> tuple[Solution, tuple[Solution, Solution] | None]:
        """``hi``, or the far side of the changes beyond it that lie within the resolution of the first;
        and the bracket of the next change, where one was located and is not merged.

        Between ``hi`` (just past a change) and ``b`` the sequence may change again.  Where the orbits of
        ``hi``'s sequence span no more than the location tolerance or the integration's error estimate
        (:meth:`~saltation.engine.flow.Flow.integration_error`), the two changes are one point: a
        simultaneous change (two corners collided at once, as the symmetric orbit's two contacts of Fig. 3,
        which DOP853's error splits by some 1e-10 in the parameter), classified from its outer sides.
        A change farther away is a point of its own: its bracket is returned, so that it is not located a
        second time.
        """
        seq_b = canonical_events(b.summary.event_ids)
        while canonical_events(hi.summary.event_ids) != seq_b:
            lo2, hi2 = self._bisect_event_change(hi, b)
            width = float(np.linalg.norm(lo2.z - hi.z))
            if width > max(self.tol, self._state_resolution(hi)):
                return hi, (lo2, hi2)
            hi = hi2
        return hi, None

    def _state_resolution(self, sol: Solution) -> float:
        """The flow's estimate of the error of a solution's end state (0 for an equilibrium)."""
        if self.equilibrium:
            return 0.0
        return self.problem.flow.integration_error(sol.evaluation.trajectory, self.problem.tolerances)

    def _smooth_points(self, a: Solution, b: Solution, index: int) -> list[SpecialPoint]:
        """Smooth special points between two solutions with the same event sequence (test functions).

        Where a multiplier moves so far from ``a`` to ``b`` that it may have left the unit circle and come
        back (two changes of stability in one step, which no test function's sign shows), the step is
        split on the secant first (:meth:`_pieces`) and each piece is tested."""
        secant = _unit(b.z - a.z)
        pieces = self._pieces(a, b, budget=[32])
        found = []
        for s0, s1 in zip(pieces, pieces[1:]):
            found += self._smooth_points_of_piece(s0, s1, index, secant)
        return found

    def _pieces(self, a: Solution, b: Solution, depth: int = 0, *, budget: list[int]) -> list[Solution]:
        """``[a, ..., b]``: the step cut at the middle of its secant, again and again, until no multiplier
        moves across a piece by more than it lies from the unit circle at the piece's ends
        (:func:`_may_hide_a_pair`), the piece is within the location tolerance, 12 cuts deep, or the step's
        ``budget`` of corrections is spent.  A middle whose event sequence differs (a corner inside the
        step) or that cannot be solved is not cut."""
        if (self.equilibrium or depth >= 12 or budget[0] <= 0 or float(np.linalg.norm(b.z - a.z)) <= 10.0 * self.tol
                or not _may_hide_a_pair(_nontrivial(a, self.autonomous), _nontrivial(b, self.autonomous))):
            return [a, b]
        budget[0] -= 1
        try:
            mid = self.on_secant(a, b, 0.5)
        except SaltationError:
            return [a, b]
        if canonical_events(mid.summary.event_ids) != canonical_events(a.summary.event_ids):
            return [a, b]
        return self._pieces(a, mid, depth + 1, budget=budget)[:-1] + self._pieces(mid, b, depth + 1, budget=budget)

    def _smooth_points_of_piece(self, a: Solution, b: Solution, index: int, secant: np.ndarray) -> list[SpecialPoint]:
        """:meth:`_smooth_points` on one piece of a step (``secant``: the whole step's direction)."""
        found = []
        # a point's test values are kept for the next pair: both secants point along the branch,
        # so the tangent (fold test) is oriented alike
        fold = _remembered("fold", lambda s: self._oriented_tangent(s, secant)[-1])
        if _crosses(fold(a), fold(b)):
            found.append(self.locate_smooth(a, b, index, SpecialPointKind.FOLD, fold))
        if self.equilibrium:
            hopf = _remembered("hopf", _hopf_test)
            if _crosses(hopf(a), hopf(b)):
                found.append(self.locate_smooth(a, b, index, SpecialPointKind.HOPF, hopf))
            return [sp for sp in found if sp is not None]
        for kind, test in ((SpecialPointKind.PERIOD_DOUBLING, _flip_test), (SpecialPointKind.NEIMARK_SACKER, _ns_test)):
            g = _remembered(kind.value, lambda s, test=test: test(_nontrivial(s, self.autonomous)))
            if _crosses(g(a), g(b)):
                found.append(self.locate_smooth(a, b, index, kind, g))
        # a real multiplier through +1 without a turning point: a branch point (a pitchfork or transcritical
        # point), or, for a declared symmetry, a symmetry breaking where a half-period multiplier passes -1
        plus = _remembered("plus_one", lambda s: _plus_one_test(_nontrivial(s, self.autonomous)))
        if _crosses(plus(a), plus(b)) and not _crosses(fold(a), fold(b)):
            g = _remembered("symmetry_breaking", self._symmetry_breaking_test) if self.symmetry is not None else None
            if g is not None and _crosses(g(a), g(b)):
                found.append(self.locate_symmetry_breaking(a, b, index))
            else:
                found.append(self.locate_smooth(a, b, index, SpecialPointKind.BRANCH_POINT, plus))
        return [sp for sp in found if sp is not None]

    # -- symmetric orbits -----------------------------------------------------------------------
    def half_map(self, sol: Solution) -> SymmetricMultipliers | None:
        """The half-period map of a solution's orbit and its split multipliers (kept on the solution).

        Parameters
        ----------
        sol : Solution
            A corrected branch point.

        Returns
        -------
        SymmetricMultipliers or None
            None without a declared symmetry or when the half shot fails.

        Raises
        ------
        numpy.linalg.LinAlgError
            If the half-period map's Jacobian is not finite.
        """
        if self.symmetry is None:
            return None
        if "half_map" not in sol.tests:
            prob = self.problem
            n = prob.system.n
            try:
                traj = half_period_trajectory(
                    prob.flow, sol.u[:n], prob.parameters_at(sol.lam), t0=prob.t0, period=prob.period_of(sol.u, sol.lam),
                    backward=prob.backward, tolerances=prob.tolerances,
                )
            except IntegrationError:
                sol.tests["half_map"] = None
            else:
                # not checked against the monodromy: next to a corner the monodromy moves like the square root
                # of the distance to it, and the two shots' rounding differs by more than the check allows
                # (the model's equations were checked for the symmetry when it was built)
                sol.tests["half_map"] = split_half_map(self.symmetry, traj, sol.u[:n], backward=prob.backward)
        return sol.tests["half_map"]

    def locate_symmetry_breaking(self, a: Solution, b: Solution, index: int) -> SpecialPoint:
        """Locate a symmetry breaking between two symmetric orbits on the symmetric orbits themselves.

        On the whole period's map the point is singular (``DG^2 - I`` has a two-dimensional kernel there), and
        the corrector drifts off the symmetric orbits near it.  The symmetric orbit at each trial parameter is
        instead a regular fixed point of the half-period map
        (:func:`~saltation.orbits.symmetry.solve_symmetric_orbit`), and the parameter where its real
        half-period multiplier passes -1 is found by Brent's method between ``a`` and ``b``.

        Parameters
        ----------
        a, b : Solution
            Symmetric branch points on either side.
        index : int
            The index of ``a`` on the branch.

        Returns
        -------
        SpecialPoint
            Of kind ``symmetry_breaking``, status ``located``, with the half-period multiplier in its note; where
            the location fails (the parameter does not bracket the point, a fold between ``a`` and ``b``, or the
            located orbit's half-period multiplier is not -1 within its accuracy), status ``failed`` with the
            bracket of the two branch points and the reason in its note.

        Raises
        ------
        SaltationError
            If the orbit at the located parameter cannot be evaluated.

        References
        ----------
        Brent (1973), *Algorithms for Minimization without Derivatives*, Prentice-Hall (the root finder).
        """
        prob = self.problem
        n = prob.system.n
        la, lb = a.lam, b.lam
        if la == lb:
            return None
        ta, tb = prob.period_of(a.u, la), prob.period_of(b.u, lb)
        found: dict[float, tuple] = {}

        def test(lam: float) -> float:
            w = (lam - la) / (lb - la)
            guess = (1.0 - w) * a.u[:n] + w * b.u[:n]
            x, T, half = solve_symmetric_orbit(
                prob.flow, guess, prob.parameters_at(lam), t0=prob.t0,
                period=(1.0 - w) * ta + w * tb if prob.autonomous else None, backward=prob.backward,
                tolerances=prob.tolerances,
            )
            found[lam] = (x, T, half)
            return symmetry_breaking_test(half.gamma)

        from scipy.optimize import brentq

        xtol = 1e-13 * max(1.0, abs(la))
        try:
            lam = float(brentq(test, la, lb, xtol=xtol, rtol=4 * np.finfo(float).eps))
            if lam not in found:
                test(lam)
        except (ValueError, SaltationError) as exc:
            return self._unlocated_symmetry_breaking(a, b, index, f"its location on the half-period map failed ({exc})")
        x, T, half = found[lam]
        u = prob.pack(x, T if prob.autonomous else None)
        summary = prob.describe(u, lam, prob.evaluate(u, lam, need_lam=False))
        gamma = _nearest(half.gamma, -1.0)
        accuracy = max(self._matrix_error(a), self._matrix_error(b))
        if not abs(gamma + 1.0) <= accuracy + 1e-9:
            return self._unlocated_symmetry_breaking(
                a, b, index, f"the located orbit's half-period multiplier nearest -1 is {_complex_text(gamma)}")
        return SpecialPoint(
            kind=SpecialPointKind.SYMMETRY_BREAKING,
            parameter=lam,
            bracket=(lam - xtol, lam + xtol),
            accuracy=xtol,
            index=index,
            state=summary.state,
            period=summary.period,
            amplitude=summary.amplitude,
            multipliers=summary.multipliers,
            multipliers_accuracy=accuracy,
            status=SpecialPointStatus.LOCATED,
            note=(f"symmetric orbit: its antisymmetric half-period multiplier is {_complex_text(gamma)} "
                  f"(located on the half-period map)"),
        )

    def _unlocated_symmetry_breaking(self, a: Solution, b: Solution, index: int, why: str) -> SpecialPoint:
        """A symmetry breaking known only to lie between ``a`` and ``b`` (status ``failed``, ``why`` in its note):
        the test function changed sign there, so it is reported, not dropped."""
        return SpecialPoint(
            kind=SpecialPointKind.SYMMETRY_BREAKING, parameter=0.5 * (a.lam + b.lam),
            bracket=(min(a.lam, b.lam), max(a.lam, b.lam)), accuracy=float(np.linalg.norm(b.z - a.z)), index=index,
            state=a.summary.state, period=a.summary.period, amplitude=a.summary.amplitude,
            multipliers=a.summary.multipliers, status=SpecialPointStatus.FAILED,
            note=f"a real half-period multiplier passes -1 between two branch points, but {why}",
        )

    def _meets_symmetric_orbits(self, sol: Solution, index: int) -> SpecialPoint | None:
        """At a turning point of a branch of asymmetric orbits: the symmetry breaking where the branch meets the
        symmetric orbits (the pitchfork seen from its side branch, which turns back there as the mirror
        images of its orbits), located on the symmetric orbits; None if the turning point is not one."""
        half = self.half_map(sol)
        if half is None or half.symmetric:
            return None
        prob = self.problem
        n = prob.system.n

        def symmetric_at(lam: float, guess: np.ndarray):
            return solve_symmetric_orbit(
                prob.flow, guess, prob.parameters_at(lam), t0=prob.t0,
                period=prob.period_of(sol.u, sol.lam) if prob.autonomous else None, backward=prob.backward,
                tolerances=prob.tolerances,
            )

        try:
            x, _, sym = symmetric_at(sol.lam, sol.u[:n])
            if float(np.linalg.norm(x - sol.u[:n])) > 1e-3 * (1.0 + float(np.linalg.norm(x))):
                return None  # another symmetric orbit, not the one this branch meets
            # the secant method on gamma + 1 along the symmetric orbits (regular there)
            lam0, g0 = sol.lam, float(np.real(_nearest(sym.gamma, -1.0))) + 1.0
            lam1 = sol.lam + 1e-6 * max(1.0, abs(sol.lam))
            for _ in range(12):
                x, _, sym = symmetric_at(lam1, x)
                g1 = float(np.real(_nearest(sym.gamma, -1.0))) + 1.0
                if g1 == g0 or abs(lam1 - lam0) <= 1e-14 * max(1.0, abs(lam1)):
                    break
                lam0, lam1, g0 = lam1, lam1 - g1 * (lam1 - lam0) / (g1 - g0), g1
            x, _, sym = symmetric_at(lam1, x)
        except SaltationError:
            return None
        gamma = _nearest(sym.gamma, -1.0)
        accuracy = self._matrix_error(sol)
        if not (abs(gamma + 1.0) <= accuracy + 1e-9 and abs(lam1 - sol.lam) <= 1e-4 * max(1.0, abs(sol.lam))):
            return None
        u = prob.pack(x, None)
        if prob.autonomous:
            u = prob.pack(x, prob.period_of(sol.u, sol.lam))
        summary = prob.describe(u, lam1, prob.evaluate(u, lam1, need_lam=False))
        step = abs(lam1 - lam0)
        return SpecialPoint(
            kind=SpecialPointKind.SYMMETRY_BREAKING, parameter=lam1, bracket=(lam1 - step, lam1 + step),
            accuracy=step, index=index, state=summary.state, period=summary.period, amplitude=summary.amplitude,
            multipliers=summary.multipliers, multipliers_accuracy=accuracy, status=SpecialPointStatus.LOCATED,
            note=(f"the branch of asymmetric orbits meets the symmetric orbits here and turns back as the mirror "
                  f"images of its orbits; the symmetric orbit's antisymmetric half-period multiplier is "
                  f"{_complex_text(gamma)} (located on the half-period map)"),
        )

    def _symmetry_breaking_test(self, sol: Solution) -> float:
        """``prod(gamma + 1)`` of a symmetric orbit's half-period multipliers (nan for an asymmetric one)."""
        half = self.half_map(sol)
        if half is None or not half.symmetric:
            return float("nan")
        return symmetry_breaking_test(half.gamma)

    def _oriented_tangent(self, sol: Solution, direction: np.ndarray) -> np.ndarray:
        """The unit tangent at ``sol`` oriented along ``direction`` (the one continuation computed, if any)."""
        if sol.tangent is None:
            return self.corrector.tangent(sol, direction)
        return sol.tangent if sol.tangent @ direction >= 0.0 else -sol.tangent

    # -- location along the secant ----------------------------------------------------------
    def on_secant(self, a: Solution, b: Solution, sigma: float) -> Solution:
        """The branch point on the secant from ``a`` to ``b`` at the fraction ``sigma``.

        Parameters
        ----------
        a, b : Solution
            Two corrected points.
        sigma : float
            Fraction of the secant (0 at ``a``, 1 at ``b``).

        Returns
        -------
        Solution
            The point corrected on the hyperplane normal to the secant through ``a + sigma (b - a)``.

        Raises
        ------
        ConvergenceError, SaltationError
            As :meth:`Corrector.solve_bordered`.
        """
        d = b.z - a.z
        return self.corrector.solve_bordered(a.z + sigma * d, _unit(d))

    def locate_smooth(
        self, a: Solution, b: Solution, index: int, kind: SpecialPointKind, test: Callable[[Solution], float]
    ) -> SpecialPoint | None:
        """Illinois iteration on a continuous test function along the secant from ``a`` to ``b``.

        A fold or period doubling is reported only if the located orbit has a (nontrivial)
        multiplier at +1 or -1 (an equilibrium's fold an eigenvalue at 0) within the point's
        ``multipliers_accuracy``: how much the multipliers change across the final bracket plus
        the error of the monodromy matrices.  A turning point without it is no fold (a corner
        of the branch that the event sequence does not show, or an orbit the integration cannot
        resolve), and None is returned.

        Parameters
        ----------
        a, b : Solution
            Corrected points on either side of the sign change.
        index : int
            The index of ``a`` on the branch.
        kind : SpecialPointKind
            The kind looked for.
        test : callable
            The test function of a :class:`Solution`.

        Returns
        -------
        SpecialPoint or None
            The located point, or None (see above).

        References
        ----------
        Dowell and Jarratt (1971), "A modified regula falsi method for computing the root of an
        equation", BIT 11 (the Illinois method).  Govaerts (2000), *Numerical Methods for Bifurcations
        of Dynamical Equilibria*, SIAM (test functions).
        """
        sa, sb = 0.0, 1.0
        ga, gb = test(a), test(b)
        lo, hi = a, b
        side = 0
        for _ in range(80):
            if np.linalg.norm(hi.z - lo.z) <= self.tol:
                break
            sm = sb - gb * (sb - sa) / (gb - ga) if gb != ga else 0.5 * (sa + sb)
            if not (sa < sm < sb) or (sb - sa) < 1e-14:
                sm = 0.5 * (sa + sb)
            try:
                mid = self.on_secant(a, b, sm)
            except SaltationError:
                break
            gm = test(mid)
            if gm == 0.0:
                lo = hi = mid
                break
            if np.sign(gm) == np.sign(ga):
                sa, ga, lo = sm, gm, mid
                if side == -1:
                    gb *= 0.5
                side = -1
            else:
                sb, gb, hi = sm, gm, mid
                if side == 1:
                    ga *= 0.5
                side = 1
        best = lo if abs(test(lo)) <= abs(test(hi)) else hi
        bracket = (min(lo.lam, hi.lam), max(lo.lam, hi.lam))
        multipliers_accuracy = float("nan")
        target = _CRITICAL_MULTIPLIER.get((kind, self.equilibrium))
        if target is not None or kind is SpecialPointKind.NEIMARK_SACKER:
            def off(s: Solution) -> float:  # how far the orbit's multipliers are from the kind's condition
                mu = _nontrivial(s, self.autonomous)
                return abs(_nearest(mu, target) - target) if target is not None else _off_circle_pair(mu)
            mu_lo, mu_hi = _nontrivial(lo, self.autonomous), _nontrivial(hi, self.autonomous)
            # how much the multipliers change across the final bracket: the critical one's, or any (NS)
            change = (abs(_nearest(mu_lo, target) - _nearest(mu_hi, target)) if target is not None
                      else _multiplier_change(mu_lo, mu_hi))
            multipliers_accuracy = change + max(self._matrix_error(lo), self._matrix_error(hi))
            if not off(best) <= multipliers_accuracy:
                # the test changed sign without the multipliers meeting the condition: where they jump
                # across the final bracket, a non-smooth point that the event sequence does not show; else
                # no bifurcation (a corner of the branch the integration cannot resolve, a neutral saddle)
                if _jumps(lo, hi, self.autonomous, float(np.linalg.norm(hi.z - lo.z))):
                    return self._hidden_corner(lo, hi, index)
                return None
        if kind is SpecialPointKind.FOLD and self.symmetry is not None:
            meets = self._meets_symmetric_orbits(best, index)
            if meets is not None:
                return meets
        if kind in (SpecialPointKind.FOLD, SpecialPointKind.BRANCH_POINT):
            doubling = self._period_doubling_of_half(best, index)
            if doubling is not None:
                return doubling
        accuracy = float(np.linalg.norm(hi.z - lo.z))
        note = ""
        widen = self._parameter_error(a, b, lo, hi, kind, target)
        if widen > 0.0:
            # the integration's error moves the multipliers, and with them the point: the bracket holds it
            bracket = (bracket[0] - widen, bracket[1] + widen)
            note = (f"bracket widened by {widen:.1e} on each side for the multipliers' integration error "
                    f"({max(self._matrix_error(lo), self._matrix_error(hi)):.1e}) over their rate of change")
        return SpecialPoint(
            kind=kind,
            parameter=best.lam,
            bracket=bracket,
            accuracy=max(accuracy, bracket[1] - bracket[0]),
            index=index,
            state=best.summary.state,
            period=best.summary.period,
            amplitude=best.summary.amplitude,
            multipliers=best.summary.multipliers,
            multipliers_accuracy=multipliers_accuracy,
            note=note,
        )

    def _period_doubling_of_half(self, best: Solution, index: int) -> SpecialPoint | None:
        """The period doubling of the orbits of half the period, where a branch of orbits of twice their period
        meets them (its orbit's multiplier +1 is the square of their -1): the end of a period-doubled branch,
        which the fold and branch-point tests see as a turning point or a crossing, located poorly (the branch is
        a parabola there).  None where ``best``'s orbit does not close after half its period (to 1e-3 of its
        size: near the point the doubled orbits differ from the repeated ones like the square root of the
        distance), or no period doubling of the half-period orbits lies within 1e-4 of it.

        The point is located by brentq on ``prod(mu + 1)`` of the half-period orbits (Newton at each parameter).
        """
        prob = self.problem
        if self.equilibrium or not isinstance(prob, ShootingProblem):
            return None
        n = prob.system.n
        x0 = np.asarray(best.u[:n], dtype=float)
        if prob.autonomous:
            half = prob
            T_half = 0.5 * float(best.u[n])
        elif prob.periods % 2 == 0:
            half = ShootingProblem(prob.flow, prob.p, continuation_parameter=prob.lam_name, backward=prob.backward,
                                   t0=prob.t0, tolerances=prob.tolerances, periods=prob.periods // 2, mode0=prob.mode0)
            T_half = half.period_of(half.pack(x0, None), best.lam)
        else:
            return None
        p = prob.parameters_at(best.lam)
        try:
            run = prob.flow.run(x0, prob.t0, prob.t0 + prob.sign * T_half, p, mode0=prob.mode0, tolerances=prob.tolerances)
        except SaltationError:
            return None
        scale = 1.0 + float(np.max(np.abs(x0)))
        if not float(np.max(np.abs(run.x1 - x0))) <= 1e-3 * scale:
            return None
        cache: dict[float, object] = {}

        def half_orbit(lam: float):
            if lam not in cache:
                guess = half.pack(x0, T_half if half.autonomous else None)
                cache[lam] = half.solve(guess, lam)
            return cache[lam]

        def flip(lam: float) -> float:
            orbit = half_orbit(lam)
            mu = np.asarray(orbit.multipliers, dtype=complex)
            if half.autonomous and mu.size:
                mu = np.delete(mu, int(np.argmin(np.where(np.isfinite(mu), np.abs(mu - 1.0), np.inf))))
            return _flip_test(mu)

        lam0 = best.lam
        try:
            for width in (1e-7, 1e-6, 1e-5, 1e-4):
                w = width * (1.0 + abs(lam0))
                lo_lam, hi_lam = lam0 - w, lam0 + w
                if _crosses(flip(lo_lam), flip(hi_lam)):
                    break
            else:
                return None
            from scipy.optimize import brentq

            lam_pd = brentq(flip, lo_lam, hi_lam, xtol=self.tol * 1e-3, rtol=4 * np.finfo(float).eps)
            orbit = half_orbit(lam_pd)
        except (SaltationError, ValueError):
            return None
        mu = np.asarray(orbit.multipliers, dtype=complex)
        step = abs(hi_lam - lo_lam)
        half_width = max(self.tol * 1e-3, 4 * np.finfo(float).eps * abs(lam_pd))
        bracket = (float(lam_pd - half_width), float(lam_pd + half_width))
        return SpecialPoint(
            kind=SpecialPointKind.PERIOD_DOUBLING, parameter=float(lam_pd),
            bracket=bracket, accuracy=bracket[1] - bracket[0], index=index,
            state=np.asarray(orbit.state0, dtype=float), period=float(orbit.period),
            amplitude=float(getattr(orbit, "amplitude", best.summary.amplitude)), multipliers=mu,
            multipliers_accuracy=self._matrix_error(best),
            note=(f"the branch's orbits of period {2 * T_half:.10g} meet the repeated orbits of period {T_half:.10g} "
                  f"here, whose multiplier passes -1 (its square is this branch's +1): located by brentq on the "
                  f"half-period orbits within {step:.1e} of the turning point seen at {lam0:.10g}"),
        )

    def _parameter_error(self, a: Solution, b: Solution, lo: Solution, hi: Solution, kind: SpecialPointKind,
                         target: float | None) -> float:
        """How far the integration's error can move a multiplier crossing in the parameter: the multipliers'
        matrix error over the rate at which the critical multiplier's modulus crosses 1 across the step
        (0 for a fold, whose test is the tangent, and for equilibria)."""
        if self.equilibrium or kind is SpecialPointKind.FOLD or (target is None and kind is not SpecialPointKind.NEIMARK_SACKER):
            return 0.0

        def modulus(s: Solution) -> float:
            mu = _nontrivial(s, self.autonomous)
            if target is not None:
                return abs(_nearest(mu, target))
            fin = np.array(_finite(mu), dtype=complex)
            cplx = fin[np.abs(fin.imag) > 1e-10 * (1.0 + np.abs(fin))]
            return float(cplx[np.argmin(np.abs(np.abs(cplx) - 1.0))].__abs__()) if cplx.size else math.nan

        span = abs(b.lam - a.lam)
        slope = abs(modulus(b) - modulus(a)) / span if span > 0.0 else math.nan
        error = max(self._matrix_error(lo), self._matrix_error(hi))
        return float(error / slope) if slope > 0.0 and math.isfinite(slope) and math.isfinite(error) else 0.0

    def _hidden_corner(self, lo: Solution, hi: Solution, index: int) -> SpecialPoint:
        """A non-smooth point where the multipliers jump but the event sequence is the same on both sides
        (an orbit that touches a surface whose saltation matrix is the identity while the field's Jacobian
        jumps, or a change of a mode that no event records), classified from the two nearest orbits'
        monodromies (``Limits.NEAREST_ORBITS``)."""
        crossing = classify_nonsmooth(
            lo.summary.monodromy, hi.summary.monodromy, backward=self.branch.backward, autonomous=self.autonomous,
            mu_minus=lo.summary.multipliers, mu_plus=hi.summary.multipliers,
        )
        sp = special_point_between(
            lo, hi, crossing, index=index, bracket=(min(lo.lam, hi.lam), max(lo.lam, hi.lam)),
            accuracy=float(np.linalg.norm(hi.z - lo.z)), monodromy_plus=hi.summary.monodromy,
            note=("the multipliers jump across the bracket while the event sequence stays the same: a non-smooth "
                  "point, classified from the monodromies of the two nearest orbits"),
        )
        return replace(sp, limits=Limits.NEAREST_ORBITS,
                       multipliers_accuracy=max(self._matrix_error(lo), self._matrix_error(hi)))

    def _matrix_error(self, sol: Solution) -> float:
        """An error estimate of the multipliers' matrix at a solution: for autonomous orbits
        ``|M n - n|`` (the trivial multiplier's error), for forced ones the flow's error estimate
        relative to the state, times ``|M|``; rounding for an equilibrium's Jacobian."""
        ev = sol.evaluation
        if self.equilibrium:
            return 1e-12 * (1.0 + float(np.linalg.norm(ev.jac_u)))
        if self.autonomous:
            return float(sol.summary.trivial_error)
        traj = ev.trajectory
        flow = self.problem.flow
        relative = flow.integration_error(traj, self.problem.tolerances) / (1.0 + float(np.abs(traj.x1).max()))
        return relative * (1.0 + float(np.linalg.norm(traj.monodromy)))

    def locate_nonsmooth(self, a: Solution, b: Solution, index: int) -> SpecialPoint:
        """Bisection along the secant on the event sequence, then set-valued multipliers.

        Parameters
        ----------
        a, b : Solution
            Corrected points with different event sequences.
        index : int
            The index of ``a`` on the branch.

        Returns
        -------
        SpecialPoint
            The non-smooth point (see :meth:`nonsmooth_point`).

        Raises
        ------
        SaltationError
            If the one-sided monodromies needed to classify it are missing.
        """
        lo, hi = self._bisect_event_change(a, b)
        return self.nonsmooth_point(lo, hi, index, far=(a, b))

    def _bisect_event_change(self, a: Solution, b: Solution) -> tuple[Solution, Solution]:
        """The two solutions, with ``a``'s event sequence and without it, that bracket where it changes,
        down to the location tolerance.

        Where the two sides differ by an excursion through a surface that the orbit on one side misses,
        the boundary orbit is first located by its defining system (a grazing,
        :func:`~saltation.special_points.grazing.locate_grazing`) and the bracket is closed around it with
        two corrections (:meth:`_bracket_at_grazing`, up to three pairs), in place of some 25 halvings.
        Every corrected point moves the end of the bracket whose event sequence it shares, as a
        bisection's does, so the bracket holds the change whether or not the grazing orbit is found
        (bisection along the secant then goes on from it).
        """
        seq_a = canonical_events(a.summary.event_ids)
        lo, hi = a, b
        sa, sb = 0.0, 1.0
        trials = [0, 8]  # the grazing is tried at the start and, if that failed, once more after 7 halvings
        for it in range(80):
            if np.linalg.norm(hi.z - lo.z) <= self.tol:
                break
            if trials and it == trials[0]:
                trials.pop(0)
                placed = self._bracket_at_grazing(a, b, lo, hi, sa, sb)
                if placed:
                    trials.clear()
                for sm, mid in placed:
                    if not sa < sm < sb:
                        continue
                    if canonical_events(mid.summary.event_ids) == seq_a:
                        sa, lo = sm, mid
                    else:
                        sb, hi = sm, mid
                continue
            sm = 0.5 * (sa + sb)
            try:
                mid = self.on_secant(a, b, sm)
            except SaltationError:
                break
            if canonical_events(mid.summary.event_ids) == seq_a:
                sa, lo = sm, mid
            else:
                sb, hi = sm, mid
        return lo, hi

    def _bracket_at_grazing(self, a: Solution, b: Solution, lo: Solution, hi: Solution, sa: float,
                            sb: float) -> list[tuple[float, Solution]]:
        """Corrected points on the secant from ``a`` to ``b`` just before and just after a grazing orbit
        between ``lo`` (at the secant's fraction ``sa``) and ``hi`` (at ``sb``), or none.

        The grazing orbit ``z*`` is located from the side without the excursion by its defining system
        (as :func:`grazing_point`); it lies on the branch, so the hyperplane normal to the secant through
        it is the one at ``s* = (z* - a) . d / |d|^2`` (``d = b - a``).  The points are corrected on the
        hyperplanes at ``s* -+ delta``, ``delta |d|`` a quarter of the location tolerance (nearer, up to
        twice more, where the branch crosses the hyperplanes at a slant and the two land farther apart
        than the tolerance): their event sequences, not the grazing orbit, decide the bracket.  Returns
        ``[(fraction, solution), ...]``:
        empty where the change is no grazing, the problem is not a one-period single shooting, the
        location fails, or ``s*`` is outside ``(sa, sb)``.
        """
        prob = self.problem
        if self.equilibrium or not isinstance(prob, ShootingProblem) or prob.periods != 1:
            return []
        sides = _sides(lo, hi)
        if sides is None:
            return []
        _, without, _, traj_wo, traj_w = sides
        span = abs(traj_wo.t1 - traj_wo.t0)
        groups = zero_length_segments(traj_wo.events, traj_w.events, time_tol=1e-3 * span)
        if not groups:
            return []
        first, last = traj_w.events[groups[0][0]], traj_w.events[groups[0][-1]]
        if first.kind != EventKind.TRANSITION:
            return []
        n = prob.system.n
        try:
            # the tangency lies within the excursion, whose ends are near each other
            orbit = locate_grazing(
                prob.flow, without.u[:n], without.lam, prob.lam_name, first.transition, 0.5 * (first.t + last.t),
                parameters=prob.parameters_at(without.lam), t0=prob.t0, tolerances=prob.tolerances,
                period=prob.period_of(without.u, without.lam) if prob.autonomous else None, backward=prob.backward,
                mode0=getattr(prob, "mode0", None),
            )
        except SaltationError:
            return []
        d = b.z - a.z
        length2 = float(d @ d)
        z_star = np.append(prob.pack(orbit.state0, orbit.period if prob.autonomous else None), orbit.parameter)
        if z_star.shape != a.z.shape or length2 == 0.0:
            return []
        s_star = float((z_star - a.z) @ d) / length2
        delta = 0.25 * self.tol / math.sqrt(length2)
        placed = []
        for _ in range(3):
            # (the branch may cross the hyperplanes at a slant: where the two points are farther apart than
            # the tolerance, they are placed again, nearer; never at s* itself, where an orbit grazes to
            # rounding and neither side's events can be told)
            if not sa + delta < s_star < sb - delta:
                break
            pair = []
            for sm in (s_star - delta, s_star + delta):
                try:
                    pair.append((sm, self.on_secant(a, b, sm)))
                except SaltationError:
                    return placed
            placed += pair
            apart = float(np.linalg.norm(pair[1][1].z - pair[0][1].z))
            if apart <= self.tol:
                break
            delta *= 0.5 * self.tol / apart
        return placed

    def nonsmooth_point(
        self, lo: Solution, hi: Solution, index: int, note: str = "", *, far: tuple[Solution, Solution] | None = None
    ) -> SpecialPoint:
        """Special point record from the two one-sided solutions around a non-smooth point.

        Where the two sides differ by segments of zero length (a corner
        collision), ``M-`` and ``M+`` are the exact limits at the boundary
        orbit (:mod:`saltation.orbits.boundary`), and the point is placed at the
        boundary orbit used.  Otherwise a grazing or sliding bifurcation is located by its defining
        system, and failing that ``M-`` and ``M+`` are the monodromies of ``lo`` and ``hi``.  ``far``
        are the branch points beyond ``lo`` and ``hi`` (on the same sides), used to estimate how well
        the multipliers are known.

        Parameters
        ----------
        lo, hi : Solution
            The bracketing solutions (``lo`` on the side of point ``index``).
        index : int
            The index of the branch point before the non-smooth point.
        note : str
            A note for the record.
        far : tuple of Solution, optional
            The branch points beyond ``lo`` and ``hi``.

        Returns
        -------
        SpecialPoint
            The classified point, with its one-sided multipliers and their accuracy.

        Raises
        ------
        SaltationError
            If the one-sided monodromies needed to classify it are missing.

        References
        ----------
        Leine and Van Campen, "Fold bifurcations in discontinuous systems" (set-valued Floquet
        multipliers at corners).
        """
        bracket = (min(lo.lam, hi.lam), max(lo.lam, hi.lam))
        accuracy = float(np.linalg.norm(hi.z - lo.z))
        if self.equilibrium:
            crossing = SetValuedCrossing(SpecialPointKind.NONSMOOTH_NO_CROSSING, None, None)
            return special_point_between(
                lo, hi, crossing, index=index, bracket=bracket, accuracy=accuracy,
                monodromy_plus=hi.summary.monodromy, note=note,
            )
        limits = self._limits(lo, hi, far)
        if limits is None:
            for locate in (grazing_point, sliding_bifurcation_point):
                found = locate(self.problem, lo, hi, index)
                if found is not None:
                    return found
            found = unlocated_grazing(self.problem, lo, hi, index, bracket=bracket, accuracy=accuracy, note=note)
            if found is not None:
                return found
            m_lo, m_hi = lo.summary.monodromy, hi.summary.monodromy
            mu_lo, mu_hi = lo.summary.multipliers, hi.summary.multipliers
            how, mu_accuracy, at = Limits.NEAREST_ORBITS, _sqrt_extrapolated_error(lo, hi, far), None
        else:
            m_lo, m_hi, how, mu_accuracy, at = limits
            mu_lo = multipliers_from_monodromy(m_lo, backward=self.branch.backward)
            mu_hi = multipliers_from_monodromy(m_hi, backward=self.branch.backward)
        crossing = classify_nonsmooth(
            m_lo, m_hi, backward=self.branch.backward, autonomous=self.autonomous, mu_minus=mu_lo, mu_plus=mu_hi,
        )
        half = self._half_limits(lo, hi, exact=limits is not None)
        if half is not None and not _squares_agree(half, mu_lo, mu_hi, backward=self.branch.backward):
            # the half-period maps' limits must square to the full ones' (M = G^2): where they do not even
            # agree on how many multipliers lie outside the unit circle, they missed the jump (an event of a
            # half period not resolved at loose tolerances), and the full multipliers classify the point
            note = (note + "; " if note else "") + (
                "symmetric orbit, but its half-period limits do not square to the full ones: classified from "
                "the full multipliers")
            half = None
        if half is not None:
            # the kind from the half-period maps (a symmetric orbit's multipliers are their squares); where the
            # set crosses, from the full ones: the set-valued monodromy is the convex hull (1 - q) M- + q M+ of
            # the full one-sided monodromies, and ((1 - q) G- + q G+)^2 is not in it
            full = crossing
            crossing = symmetric_crossing(classify_nonsmooth(
                half[0], half[1], backward=self.branch.backward, autonomous=self.autonomous,
            ))
            if crossing.point is not None:
                note = (note + "; " if note else "") + (
                    f"symmetric orbit: the half-period multiplier crosses the unit circle at "
                    f"{_complex_text(crossing.gamma)} (at q = {crossing.q:.6g} between the half-period maps)")
            if full.q is not None:
                crossing = replace(crossing, q=full.q, point=full.point)
        sp = special_point_between(
            lo, hi, crossing, index=index, bracket=bracket, accuracy=accuracy, monodromy_plus=m_hi, note=note,
        )
        return replace(
            sp, parameter=sp.parameter if at is None else at.lam,
            state=sp.state if at is None else at.summary.state,
            period=sp.period if at is None else at.summary.period,
            amplitude=sp.amplitude if at is None else at.summary.amplitude,
            multipliers_minus=mu_lo, multipliers_plus=mu_hi, monodromy_minus=m_lo,
            multipliers_accuracy=mu_accuracy, limits=how,
        )

    def _symmetry_breaking_corner(self, point: SpecialPoint, lo: Solution, hi: Solution) -> SpecialPoint:
        """``point`` as a discontinuous symmetry breaking where the branch passes there from symmetric to
        asymmetric orbits, from ``a`` to ``b`` (how the full multipliers classified it is kept in the note).
        The bisection's ``lo`` and ``hi`` may both be symmetric: at a grazing of a symmetric orbit the
        symmetric orbits with both mirror contacts and the asymmetric ones with one meet."""
        broken = self._symmetry_lost(lo, hi)
        if broken is None:
            return point
        was = f"; its full multipliers alone: {point.kind.value}"
        note = (point.note + "; " if point.note else "") + broken + was
        return replace(point, kind=SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING, note=note)

    def _symmetry_lost(self, lo: Solution, hi: Solution) -> str | None:
        """Where the orbits on one side of a non-smooth point are symmetric and those on the other side are
        not, a note saying so (the point is then a discontinuous symmetry breaking: asymmetric orbits, in
        mirror pairs, branch off the symmetric ones there); None otherwise."""
        h_lo, h_hi = self.half_map(lo), self.half_map(hi)
        if h_lo is None or h_hi is None or h_lo.symmetric == h_hi.symmetric:
            return None
        before, after = ("symmetric", "asymmetric") if h_lo.symmetric else ("asymmetric", "symmetric")
        return (f"the branch passes from {before} to {after} orbits here (symmetry error "
                f"{max(h_lo.symmetry_error, h_hi.symmetry_error):.2g}); the mirror images of the asymmetric "
                "orbits are a second branch through this point")

    def _half_limits(self, lo: Solution, hi: Solution, *, exact: bool) -> tuple[np.ndarray, np.ndarray] | None:
        """The one-sided half-period maps ``(DG on lo's side, DG on hi's side)`` of a symmetric orbit at a
        non-smooth point: exact limits where the sides differ by zero-length segments (``exact``), else
        the maps of ``lo`` and ``hi``; None without a symmetry or when either side is not symmetric."""
        h_lo, h_hi = self.half_map(lo), self.half_map(hi)
        if h_lo is None or h_hi is None or not (h_lo.symmetric and h_hi.symmetric):
            return None
        if exact:
            prob = self.problem
            lo_fewer, without, with_, _, _ = _sides(lo, hi)
            p = prob.parameters_at(without.lam)
            n = prob.system.n
            try:
                shots = [
                    half_period_trajectory(prob.flow, s.u[:n], prob.parameters_at(s.lam), t0=prob.t0,
                                           period=prob.period_of(s.u, s.lam), backward=prob.backward,
                                           tolerances=prob.tolerances)
                    for s in (without, with_)
                ]
                lim = one_sided_limits(prob.flow, shots[0], shots[1], p, tolerances=prob.tolerances)
            except SaltationError:
                lim = None
            if lim is not None:
                g_wo, g_w = self.symmetry @ lim.monodromy_without, self.symmetry @ lim.monodromy_with
                return (g_wo, g_w) if lo_fewer else (g_w, g_wo)
        return h_lo.half_map, h_hi.half_map

    def _limits(self, lo: Solution, hi: Solution, far: tuple[Solution, Solution] | None):
        """Exact one-sided monodromies ``(M_lo, M_hi, how, accuracy, boundary solution)``, or None."""
        flow = getattr(self.problem, "flow", None)
        sides = _sides(lo, hi)
        if flow is None or sides is None:
            return None
        lo_fewer, without, with_, traj_wo, traj_w = sides
        try:
            lim = one_sided_limits(
                flow, traj_wo, traj_w, self.problem.parameters_at(without.lam),
                tolerances=getattr(self.problem, "tolerances", None),
            )
        except SaltationError:
            return None
        if lim is None:
            return None
        # the limits are exact at ``without``, within the bracket of the true boundary: from there to the
        # boundary they move by about the distance along the branch times |dM/ds|, estimated on the side
        # without the segments.  Distances are taken along the branch, not in the parameter, which at a
        # corner that is a fold (both sides on one side of it) is no measure of the distance: the boundary's
        # hyperplane (normal to the secant ``d`` of ``far``) lies between those of ``lo`` and ``hi``, so
        # ``without`` is at most ``|(hi - lo) . d| / |e . d|`` from it along its side's direction ``e``
        width = float(np.linalg.norm(hi.z - lo.z))
        rate = 0.0
        if far is not None:
            other = far[0] if lo_fewer else far[1]
            leg = other.z - without.z
            leg_length = float(np.linalg.norm(leg))
            if other.summary.monodromy is not None and leg_length > 0.0:
                rate = float(np.linalg.norm(other.summary.monodromy - lim.monodromy_without)) / leg_length
                d = _unit(far[1].z - far[0].z)
                along = abs(float((hi.z - lo.z) @ d))
                slope = abs(float(leg @ d)) / leg_length
                width = along / slope if slope > 0.0 else math.inf
        scale = max(1.0, float(np.linalg.norm(lim.monodromy_with)))
        mu_accuracy = width * rate + 1e-13 * scale
        how = Limits.EXACT if lim.exact else Limits.NEAREST_SALTATION
        if not lim.exact:
            mu_accuracy += float(np.linalg.norm(traj_w.monodromy - lim.monodromy_with))
        m_lo, m_hi = (lim.monodromy_without, lim.monodromy_with) if lo_fewer else (lim.monodromy_with, lim.monodromy_without)
        return m_lo, m_hi, how, mu_accuracy, without


def special_point_between(
    lo: Solution,
    hi: Solution,
    crossing: SetValuedCrossing,
    *,
    index: int,
    bracket: tuple[float, float],
    accuracy: float,
    monodromy_plus: np.ndarray | None,
    note: str = "",
) -> SpecialPoint:
    """The record of a non-smooth point from the solutions on its two sides (``lo`` on the side of point ``index``).

    Parameters
    ----------
    lo, hi : Solution
        The bracketing solutions.
    crossing : SetValuedCrossing
        The classification.
    index : int
        The index of the branch point before the point.
    bracket : tuple of float
        The parameter interval that holds it.
    accuracy : float
        The distance between ``lo`` and ``hi``.
    monodromy_plus : ndarray or None
        The monodromy on ``hi``'s side.
    note : str
        A note for the record.

    Returns
    -------
    SpecialPoint
        At the middle of the bracket, with ``lo``'s state and both sides' multipliers.
    """
    return SpecialPoint(
        kind=crossing.kind,
        parameter=0.5 * (lo.lam + hi.lam),
        bracket=bracket,
        accuracy=accuracy,
        index=index,
        state=lo.summary.state,
        period=lo.summary.period,
        amplitude=lo.summary.amplitude,
        multipliers_minus=lo.summary.multipliers,
        multipliers_plus=hi.summary.multipliers,
        monodromy_minus=lo.summary.monodromy,
        monodromy_plus=monodromy_plus,
        crossing_q=crossing.q,
        crossing_point=crossing.point,
        event_labels_minus=lo.summary.event_labels,
        event_labels_plus=hi.summary.event_labels,
        note=note,
    )


def sliding_bifurcation_point(problem, lo: Solution, hi: Solution, index: int) -> SpecialPoint | None:
    """The record of a crossing-, switching- or adding-sliding between two branch points.

    Located by its defining system (:mod:`saltation.special_points.sliding`).  Its one-sided
    multipliers are those of the two bracketing orbits (the extra segment shrinks linearly or like a
    square root), and their difference is the stated accuracy bound.

    Parameters
    ----------
    problem : ShootingProblem
        The branch's problem (forward time, one forcing period).
    lo, hi : Solution
        The bracketing solutions (``lo`` on the side of point ``index``).
    index : int
        The index of the branch point before the point.

    Returns
    -------
    SpecialPoint or None
        The located point; None when the change is not a sliding bifurcation, the problem is not a
        forward-time one over one period, or the location fails or lands outside the bracket.

    References
    ----------
    di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding:
    derivation of normal-form mappings", Physica D 170.
    """
    flow = getattr(problem, "flow", None)
    sides = _sides(lo, hi)
    if flow is None or sides is None or problem.backward or getattr(problem, "periods", 1) != 1:
        return None
    lo_fewer, without, with_, traj_wo, traj_w = sides
    change = sliding_change(flow, traj_wo, traj_w, problem.parameters_at(with_.lam), problem.parameters_at(without.lam))
    if change is None:
        return None
    n = problem.system.n
    options = {"parameters": problem.parameters_at(without.lam), "t0": problem.t0, "tolerances": problem.tolerances}
    try:
        if change.kind is SpecialPointKind.ADDING_SLIDING:
            found = locate_adding_sliding(flow, without.u[:n], without.lam, problem.lam_name, change.t_guess,
                                          change.mode, change.surface, change.side, **options)
        else:
            period = problem.period_of(without.u, without.lam) if problem.system.is_autonomous else None
            found = locate_tangent_arrival(flow, without.u[:n], without.lam, problem.lam_name, change.index,
                                           change.mode, change.side, period=period, **options)
    except SaltationError:
        return None
    width = abs(hi.lam - lo.lam)
    if found.kind is not change.kind \
            or abs(found.parameter - 0.5 * (lo.lam + hi.lam)) > width + 1e-9 * (1.0 + abs(found.parameter)):
        return None
    traj = found.trajectory
    where = {
        SpecialPointKind.CROSSING_SLIDING: "arrives at the surface where the field of {m!r} is tangent to it, "
                                           "visible from that side (the orbit of that field leaves the surface)",
        SpecialPointKind.SWITCHING_SLIDING: "arrives at the surface where the field of {m!r} is tangent to it, "
                                            "invisible from that side (the orbit of that field returns to it)",
        SpecialPointKind.ADDING_SLIDING: "slides through a point where the field of {m!r} has a cubic tangency "
                                         "with the surface (the sliding motion touches the boundary of its region)",
    }[found.kind].format(m=found.mode)
    return SpecialPoint(
        kind=found.kind,
        parameter=found.parameter,
        bracket=(found.parameter - found.accuracy, found.parameter + found.accuracy),
        accuracy=found.accuracy,
        index=index,
        state=found.state0,
        period=found.trajectory.t1 - found.trajectory.t0,
        amplitude=float(max(abs(traj.x_max[0]), abs(traj.x_min[0]))),
        multipliers_minus=lo.summary.multipliers,
        multipliers_plus=hi.summary.multipliers,
        monodromy_minus=lo.summary.monodromy,
        monodromy_plus=hi.summary.monodromy,
        event_labels_minus=lo.summary.event_labels,
        event_labels_plus=hi.summary.event_labels,
        note=(f"the orbit {where} (surface {change.surface!r}, t = {found.t_touch:.10g}, d2h/dt2 there "
              f"{found.curvature:.3g}){'' if change.count == 1 else f', at {change.count} points of the orbit at once'}; "
              f"the side with the extra events is {'plus' if lo_fewer else 'minus'}"),
        multipliers_accuracy=float(np.linalg.norm(hi.summary.monodromy - lo.summary.monodromy)),
        limits=Limits.NEAREST_ORBITS,
        status=SpecialPointStatus.LOCATED,
        touch_surface=change.surface,
        touch_mode=found.mode,
        touch_time=found.t_touch,
    )


def _sides(lo: Solution, hi: Solution):
    """``(lo has fewer events, side without the extra events, side with them, their trajectories)``, or None."""
    lo_fewer = len(lo.summary.event_labels) <= len(hi.summary.event_labels)
    without, with_ = (lo, hi) if lo_fewer else (hi, lo)
    traj_wo, traj_w = without.evaluation.trajectory, with_.evaluation.trajectory
    if traj_wo is None or traj_w is None:
        return None
    return lo_fewer, without, with_, traj_wo, traj_w


def grazing_point(problem, lo: Solution, hi: Solution, index: int) -> SpecialPoint | None:
    """The record of a grazing between two branch points, located by its defining system.

    ``lo`` (the side of point ``index``) and ``hi`` differ by events on a
    surface that the orbit on one side misses: the grazing orbit is located
    from the orbit that misses it (:func:`saltation.special_points.grazing.locate_grazing`).
    Its monodromy is the limit on that side.  On the crossing side the limit
    is the grazing orbit with the crossing's saltation matrices inserted at
    the instant of tangency when they stay bounded (a continuous field), and
    unbounded otherwise (an impact: ``S = O(1/v)``): the largest multiplier
    there is reported as ``inf``, the others are those of the nearest orbit.

    Parameters
    ----------
    problem : ShootingProblem
        The branch's problem (one forcing period).
    lo, hi : Solution
        The bracketing solutions.
    index : int
        The index of the branch point before the grazing.

    Returns
    -------
    SpecialPoint or None
        The ``grazing`` (or ``grazing_sliding``) record; None when the change is not a grazing, or the
        location fails or lands outside the bracket.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the fundamental matrix at the instant of tangency is singular.

    References
    ----------
    di Bernardo, Budd, Champneys and Kowalczyk (2008), *Piecewise-smooth Dynamical Systems: Theory
    and Applications*, Springer.  Nordmark (1991), "Non-periodic motion caused by grazing incidence in
    an impact oscillator", J. Sound Vib. 145 (the square-root singularity of impacts).
    """
    flow = getattr(problem, "flow", None)
    sides = _sides(lo, hi)
    if flow is None or sides is None:
        return None
    lo_fewer, without, with_, traj_wo, traj_w = sides
    span = abs(traj_wo.t1 - traj_wo.t0)
    groups = zero_length_segments(traj_wo.events, traj_w.events, time_tol=1e-3 * span)
    if not groups:
        return None
    first = traj_w.events[groups[0][0]]
    try:
        orbit = locate_grazing(
            flow, without.u[: problem.system.n], without.lam, problem.lam_name, first.transition, first.t,
            parameters=problem.parameters_at(without.lam), t0=problem.t0, tolerances=problem.tolerances,
            period=problem.period_of(without.u, without.lam) if problem.system.is_autonomous else None,
            backward=problem.backward, periods=getattr(problem, "periods", 1), mode0=getattr(problem, "mode0", None),
        )
    except SaltationError:
        return None
    width = abs(hi.lam - lo.lam)
    if abs(orbit.parameter - 0.5 * (lo.lam + hi.lam)) > width + 1e-9 * (1.0 + abs(orbit.parameter)):
        return None  # a grazing elsewhere: not the change between these points
    p = problem.parameters_at(orbit.parameter)
    group = [traj_w.events[i] for i in groups[0]]
    sliding = any(e.kind != EventKind.TRANSITION for e in group)
    backward = problem.backward
    # the excursion's transitions in forward time (a backward shot meets them in reverse order)
    excursion = [e.transition for e in (reversed(group) if backward else group)]
    P = None if sliding else saltation_at_corner(problem.system, excursion, orbit.t_graze, orbit.x_graze, p)
    bounded_corner = not sliding and corner_saltation_is_bounded(problem.system, excursion[0], orbit.t_graze,
                                                                 orbit.x_graze, p, P)
    if bounded_corner and backward:  # run backward, the excursion's map is the inverse of the forward one
        bounded_corner = np.linalg.cond(P) < 1e12
        P = np.linalg.inv(P) if bounded_corner else None
    m_without = orbit.monodromy
    mu_without = multipliers_from_monodromy(m_without, backward=backward)
    limit_error = None
    if sliding:
        # the orbit grazes the boundary of a sliding region: the sliding segment's saltation matrices are
        # 0/0 at the tangency; those of the nearest orbit with the segment stand in for their limit
        P = np.eye(problem.system.n)
        for e in group:
            P = e.saltation @ P
        phi = orbit.fundamental_to_graze
        m_with = m_without @ np.linalg.solve(phi, P @ phi)
        mu_with = multipliers_from_monodromy(m_with, backward=backward)
        bounded = ("a sliding segment: the limit uses the saltation matrices of the nearest orbit that slides "
                   f"(multipliers known to about {np.linalg.norm(with_.summary.monodromy - m_with):.1e})")
    elif bounded_corner:
        phi = orbit.fundamental_to_graze
        m_with = m_without @ np.linalg.solve(phi, P @ phi)
        mu_with = multipliers_from_monodromy(m_with, backward=backward)
        bounded = "bounded: the crossing's saltation matrices at the tangency are finite"
    else:
        m_with = None
        extrapolated = _autonomous_crossing_limit(problem, orbit, with_) if problem.autonomous else None
        if extrapolated is not None:
            mu_with, limit_error = extrapolated
            bounded = ("unbounded saltation matrix along the flow: an autonomous orbit's kick at the tangency "
                       "moves its phase only, so its multipliers stay finite; their limit is extrapolated in "
                       f"sqrt(distance) from two crossing orbits (to about {limit_error:.1e})")
        else:
            nearest = np.asarray(with_.summary.multipliers, dtype=complex)
            keep = np.argsort(np.abs(nearest))[:-1]
            mu_with = np.concatenate([[complex(np.inf, 0.0)], nearest[keep]])
            bounded = ("unbounded: the crossing's saltation matrix grows like 1/sqrt(distance); the largest "
                       "multiplier on that side is infinite in the limit, the others are those of the nearest orbit")
    side = "plus" if lo_fewer else "minus"
    surface = problem.system.transitions[orbit.transition].surface
    m_lo, m_hi = (m_without, m_with) if lo_fewer else (m_with, m_without)
    mu_lo, mu_hi = (mu_without, mu_with) if lo_fewer else (mu_with, mu_without)
    traj = orbit.trajectory
    return SpecialPoint(
        kind=SpecialPointKind.GRAZING_SLIDING if sliding else SpecialPointKind.GRAZING,
        parameter=orbit.parameter,
        bracket=(orbit.parameter - orbit.accuracy, orbit.parameter + orbit.accuracy),
        accuracy=orbit.accuracy,
        index=index,
        state=orbit.state0,
        period=orbit.period,
        amplitude=float(max(abs(traj.x_max[0]), abs(traj.x_min[0]))),
        multipliers_minus=mu_lo,
        multipliers_plus=mu_hi,
        monodromy_minus=m_lo,
        monodromy_plus=m_hi,
        event_labels_minus=lo.summary.event_labels,
        event_labels_plus=hi.summary.event_labels,
        note=f"grazing of surface {surface!r} at t = {orbit.t_graze:.10g}; the side with the crossing is '{side}', {bounded}",
        # the grazing orbit is exact to the located parameter; the finite multipliers of an unbounded side
        # are those of the nearest orbit, of unknown accuracy
        multipliers_accuracy=(
            limit_error if limit_error is not None
            else float("nan") if m_with is None
            else float(np.linalg.norm(with_.summary.monodromy - m_with)) if sliding
            else orbit.accuracy * float(np.linalg.norm(m_without)) + 1e-13
        ),
        limits=(Limits.NEAREST_SALTATION if sliding else Limits.EXTRAPOLATED if limit_error is not None
                else Limits.GRAZING),
        status=SpecialPointStatus.LOCATED,
        touch_surface=surface,
        touch_mode=problem.system.transitions[orbit.transition].source,
        touch_time=orbit.t_graze,
    )


def unlocated_grazing(problem, lo: Solution, hi: Solution, index: int, *, bracket: tuple[float, float],
                      accuracy: float, note: str = "") -> SpecialPoint | None:
    """The record of a grazing with an unbounded side that its defining system could not locate.

    Where the two sides differ by a zero-length excursion of transitions whose saltation matrices are
    unbounded at the tangency (an impact: ``S = O(1/v)``), the one-sided limit on the crossing side is
    infinite, whatever the finite multipliers of the nearest crossing orbit are (they grow like
    ``d^(-1/2)`` towards the point).  Whether the excursion is unbounded is decided from the nearest
    crossing orbit's own excursion by :func:`~saltation.orbits.boundary.corner_saltation_is_bounded` (its
    normal speed there is small, not zero, and the test's margin is ``sqrt`` of the ratio of the two).

    Parameters
    ----------
    problem : ShootingProblem
        The branch's problem.
    lo, hi : Solution
        The bracketing solutions (``lo`` on the side of point ``index``).
    index : int
        The index of the branch point before the grazing.
    bracket, accuracy, note
        As for :func:`special_point_between`.

    Returns
    -------
    SpecialPoint or None
        A ``grazing`` record, ``bracketed`` (not located), the crossing side's largest multiplier ``inf`` and
        the others those of the nearest orbit; None when the sides do not differ by such an excursion, or
        its saltation matrices stay bounded (then the set-valued multipliers classify it).

    Raises
    ------
    numpy.linalg.LinAlgError
        On a backward-time branch, if an event's saltation matrix is singular (a reset that cannot be
        run backwards).
    """
    sides = _sides(lo, hi)
    if sides is None or not isinstance(problem.system, PiecewiseSystem):
        return None
    lo_fewer, without, with_, traj_wo, traj_w = sides
    groups = zero_length_segments(traj_wo.events, traj_w.events, time_tol=1e-3 * abs(traj_wo.t1 - traj_wo.t0))
    if not groups:
        return None
    group = [traj_w.events[i] for i in groups[0]]
    if any(e.kind != EventKind.TRANSITION for e in group):
        return None
    if problem.backward:
        group = group[::-1]  # the excursion in forward time
    first = group[0]
    p = problem.parameters_at(with_.lam)
    P = np.eye(problem.system.n)
    for e in group:
        P = (np.linalg.inv(e.saltation) if problem.backward else e.saltation) @ P
    if corner_saltation_is_bounded(problem.system, first.transition, first.t,
                                   first.x_plus if problem.backward else first.x_minus, p, P):
        return None
    nearest = np.asarray(with_.summary.multipliers, dtype=complex)
    mu_with = np.concatenate([[complex(np.inf, 0.0)], nearest[np.argsort(np.abs(nearest))[:-1]]])
    mu_without = np.asarray(without.summary.multipliers, dtype=complex)
    mu_lo, mu_hi = (mu_without, mu_with) if lo_fewer else (mu_with, mu_without)
    side = "plus" if lo_fewer else "minus"
    why = (f"grazing of surface {first.surface!r} near t = {first.t:.10g}, bracketed (its defining system did not "
           f"converge); the side with the crossing is '{side}', unbounded: the crossing's saltation matrix grows "
           "like 1/sqrt(distance), so the largest multiplier on that side is infinite in the limit, the others "
           "are those of the nearest orbit")
    crossing = SetValuedCrossing(SpecialPointKind.GRAZING, None, None)
    sp = special_point_between(lo, hi, crossing, index=index, bracket=bracket, accuracy=accuracy,
                               monodromy_plus=None, note=(note + "; " if note else "") + why)
    return replace(sp, multipliers_minus=mu_lo, multipliers_plus=mu_hi, monodromy_minus=None,
                   multipliers_accuracy=float("nan"), limits=Limits.NEAREST_ORBITS,
                   touch_surface=first.surface, touch_mode=first.mode_from, touch_time=float(first.t))


def _autonomous_crossing_limit(problem, orbit, with_: Solution) -> tuple[np.ndarray, float] | None:
    """The crossing side's multipliers at an autonomous grazing, extrapolated to the grazing orbit.

    On an autonomous orbit the unbounded part of an impact's saltation matrix at the tangency points
    along the flow (the kick shifts the phase), so the multipliers have finite limits, approached like
    ``sqrt(d)``.  Two crossing orbits at ``d`` and ``4 d`` give ``mu(0) ~ 2 mu(d) - mu(4 d)``; the error
    estimate is ``|mu(d) - mu(4 d)|``, the size of the square-root term at ``d``.  None when they cannot
    be solved.
    """
    if not isinstance(problem, ShootingProblem):
        return None
    direction = 1.0 if with_.lam >= orbit.parameter else -1.0
    saved = (problem.x_ref, problem.f_ref)  # the branch's phase anchor stays
    values = []
    try:
        for d in (1e-7, 4e-7):
            lam = orbit.parameter + direction * d * max(1.0, abs(orbit.parameter))
            found = problem.solve(problem.pack(orbit.state0, orbit.period), lam)
            values.append(np.asarray(found.multipliers, dtype=complex))
    except SaltationError:
        return None
    finally:
        problem.x_ref, problem.f_ref = saved
    near, far = (v[np.argsort(np.abs(v))] for v in values)
    if len(near) != len(far) or not np.all(np.isfinite(near)):
        return None
    return 2.0 * near - far, float(np.max(np.abs(near - far)))


def _sqrt_extrapolated_error(lo: Solution, hi: Solution, far: tuple[Solution, Solution] | None) -> float:
    """Error estimate of the monodromies of the two bracketing orbits as one-sided limits.

    On a side whose monodromy moves like the square root of the distance to
    the boundary, ``M(d) = M(0) + C sqrt(d)``: ``C`` from the bracket end and
    the branch point beyond it, the error ``C sqrt(d)`` at the bracket end.
    """
    if far is None:
        return float("nan")
    mid = 0.5 * (lo.lam + hi.lam)
    worst = 0.0
    for near, other in ((lo, far[0]), (hi, far[1])):
        d_near, d_far = abs(near.lam - mid), abs(other.lam - mid)
        if near.summary.monodromy is None or other.summary.monodromy is None or d_far <= d_near:
            return float("nan")  # no second point on that side: the error is not known
        c = float(np.linalg.norm(other.summary.monodromy - near.summary.monodromy)) / (np.sqrt(d_far) - np.sqrt(d_near))
        worst = max(worst, c * np.sqrt(d_near))
    return worst


def symmetric_crossing(half: SetValuedCrossing) -> SetValuedCrossing:
    """The kind of a symmetric orbit's non-smooth point from how its set-valued *half-period* multiplier
    ``gamma`` crosses the unit circle: through +1 a discontinuous fold, through -1 a discontinuous
    symmetry breaking, through +-i (``gamma^2 = -1``) a discontinuous flip, elsewhere a discontinuous
    Neimark-Sacker.  ``point`` becomes the full multiplier ``gamma^2``; ``gamma`` is kept.

    Parameters
    ----------
    half : SetValuedCrossing
        :func:`classify_nonsmooth` of the one-sided half-period maps.

    Returns
    -------
    SetValuedCrossing
    """
    if half.point is None:
        return half
    gamma = complex(half.point)
    if abs(gamma.imag) <= 1e-6:
        kind = SpecialPointKind.DISCONTINUOUS_FOLD if gamma.real > 0 else SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING
    elif abs(gamma.real) <= 1e-6:
        kind = SpecialPointKind.DISCONTINUOUS_FLIP
    else:
        kind = SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER
    return SetValuedCrossing(kind, half.q, gamma * gamma, gamma)


def _complex_text(z: complex) -> str:
    return f"{z.real:.9g}" if abs(z.imag) <= 1e-12 else f"{z.real:.9g}{z.imag:+.9g}i"


def _remembered(name: str, test: Callable[[Solution], float]) -> Callable[[Solution], float]:
    """``test``, evaluated once per solution (the value is kept in ``solution.tests``)."""

    def value(sol: Solution) -> float:
        if name not in sol.tests:
            sol.tests[name] = test(sol)
        return sol.tests[name]

    return value


#: The multiplier (eigenvalue, for equilibria) a smooth special point must have, by kind and
#: whether the branch is of equilibria.
_CRITICAL_MULTIPLIER = {
    (SpecialPointKind.FOLD, False): 1.0,
    (SpecialPointKind.BRANCH_POINT, False): 1.0,
    (SpecialPointKind.PERIOD_DOUBLING, False): -1.0,
    (SpecialPointKind.SYMMETRY_BREAKING, False): 1.0,
    (SpecialPointKind.FOLD, True): 0.0,
}


def _nearest(mu: np.ndarray, target: float) -> complex:
    """The multiplier nearest ``target`` (``inf`` when there is none)."""
    mu = np.asarray(mu, dtype=complex)
    mu = mu[np.isfinite(mu)]
    return complex(mu[int(np.argmin(np.abs(mu - target)))]) if mu.size else complex(np.inf)


def _crosses(ga: float, gb: float) -> bool:
    """A test function changes sign from ``a`` to ``b`` (a zero at ``b`` counts, a zero at ``a`` or nan not)."""
    return (ga < 0.0 <= gb) or (ga > 0.0 >= gb)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / math.sqrt(float(v @ v))  # numpy's norm of a vector, without its per-call dispatch


def _nontrivial(sol: Solution, autonomous: bool) -> np.ndarray:
    """Multipliers without the trivial one (closest to 1) of an autonomous orbit."""
    mu = sol.summary.multipliers
    if not autonomous:
        return mu
    mu = np.asarray(mu, dtype=complex)
    if mu.size:
        finite = np.where(np.isfinite(mu), np.abs(mu - 1.0), np.inf)
        keep = np.ones(mu.size, dtype=bool)
        keep[int(np.argmin(finite))] = False
        mu = mu[keep]
    return mu


def _finite(mu: np.ndarray) -> list[complex]:
    """The finite multipliers, as plain complex numbers (the tests below run for every branch point, on a
    few numbers: numpy's per-call cost would exceed the arithmetic)."""
    return [m for m in np.asarray(mu, dtype=complex).tolist() if cmath.isfinite(m)]


def _flip_test(mu: np.ndarray) -> float:
    """``prod(mu + 1)`` over the finite multipliers (changes sign at period doubling)."""
    prod = 1.0 + 0.0j
    for m in _finite(mu):
        prod *= m + 1.0
    return prod.real


def _plus_one_test(mu: np.ndarray) -> float:
    """``prod(mu - 1)`` over the finite multipliers (changes sign where a real one passes +1)."""
    prod = 1.0 + 0.0j
    for m in _finite(mu):
        prod *= m - 1.0
    return prod.real


def _ns_test(mu: np.ndarray) -> float:
    """``prod_{i<j} (mu_i mu_j - 1)`` over the finite multipliers (the bialternate product's determinant,
    nan when there are fewer than two: never a crossing).

    It is continuous in the multipliers and changes sign where a product ``mu_i mu_j`` passes 1: a complex
    pair through the unit circle (Neimark-Sacker) or a real pair with product 1 (a neutral saddle, no
    bifurcation, which the location's check of the multipliers rejects).  Unlike ``|mu| - 1`` of the largest
    complex multiplier, it does not jump where a complex pair turns real.

    References
    ----------
    Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM, section 4.4.
    """
    fin = _finite(mu)
    if len(fin) < 2:
        return float("nan")
    prod = 1.0 + 0.0j
    for i in range(len(fin)):
        for j in range(i + 1, len(fin)):
            prod *= fin[i] * fin[j] - 1.0
    return prod.real


def _off_circle_pair(mu: np.ndarray) -> float:
    """How far the complex pair nearest the unit circle lies from it (inf when there is no complex pair)."""
    fin = np.array(_finite(mu), dtype=complex)
    cplx = fin[np.abs(fin.imag) > 1e-10 * (1.0 + np.abs(fin))]
    return float(np.min(np.abs(np.abs(cplx) - 1.0))) if cplx.size else math.inf


def _matched(ma: np.ndarray, mb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The finite multipliers of two nearby orbits, paired so that the total distance is least."""
    from scipy.optimize import linear_sum_assignment

    a = np.array(_finite(ma), dtype=complex)
    b = np.array(_finite(mb), dtype=complex)
    if not a.size or not b.size:
        return a[:0], b[:0]
    rows, cols = linear_sum_assignment(np.abs(a[:, None] - b[None, :]))
    return a[rows], b[cols]


def _multiplier_change(ma: np.ndarray, mb: np.ndarray) -> float:
    """The largest distance between paired multipliers of two nearby orbits."""
    a, b = _matched(ma, mb)
    return float(np.max(np.abs(a - b))) if a.size else 0.0


def _may_hide_a_pair(ma: np.ndarray, mb: np.ndarray) -> bool:
    """Whether some multiplier moves between two orbits by more than 0.05 and by more than half the sum of
    its two distances from the unit circle: far enough to have left the circle and come back (or passed
    it twice) between them, though it lies on the same side at both."""
    a, b = _matched(ma, mb)
    if not a.size:
        return False
    move = np.abs(a - b)
    room = np.abs(np.abs(a) - 1.0) + np.abs(np.abs(b) - 1.0)
    return bool(np.any((move > 0.05) & (move > 0.5 * room)))


def _jumps(lo: Solution, hi: Solution, autonomous: bool, width: float) -> bool:
    """Whether the multipliers of two orbits a location tolerance apart differ by more than a smooth (even a
    square-root) dependence on the branch allows: ``1e-3`` and ``100 sqrt(width)``."""
    change = _multiplier_change(_nontrivial(lo, autonomous), _nontrivial(hi, autonomous))
    return change > max(1e-3, 100.0 * math.sqrt(width))


def _hopf_test(sol: Solution) -> float:
    """Largest real part among complex eigenvalues of an equilibrium (nan when there is none)."""
    ev = np.asarray(sol.summary.multipliers, dtype=complex)
    cplx = ev[np.abs(ev.imag) > 1e-10]
    if cplx.size == 0:
        return float("nan")
    return float(np.max(cplx.real))
