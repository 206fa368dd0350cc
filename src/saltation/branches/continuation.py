"""Pseudo-arclength continuation of solutions of ``r(u, lam) = 0``.

One engine for every problem of the small protocol of
:mod:`saltation.orbits.shooting` (periodic orbits by forward or backward shooting,
equilibria): ``evaluate(u, lam) -> Evaluation``, ``describe``, ``accept``.

* Predictor: the unit tangent ``t`` of the branch in ``z = (u, lam)``,
  ``z_pred = z + ds t``.
* Corrector: Newton on the bordered system ``r(z) = 0``,
  ``t . (z - z_pred) = 0``.
* Step control: the step grows after quick convergence and is halved when
  the corrector fails or the tangent turns by more than ``max_angle`` --
  except across a corner of the branch (the orbit's event sequence changes),
  where the tangent genuinely jumps and the step is accepted.
* After every step, a detector handed in from outside (the special-point layer's
  :class:`~saltation.special_points.detection.SpecialPointDetector`, see
  :mod:`saltation.special_points.continuation`) looks for special points between the last two
  points and locates them; where the corrector fails, it may carry the branch past the failure
  (a grazing).  Without one, the engine follows the branch and finds no special point.
* A run stops when the branch closes: a step passes the first point again
  in the same direction, or a special point is located a second time from
  the same side (a loop that the run entered away from its start).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from saltation._moved import forward_names
from saltation.branches.branch import (
    Branch,
    BranchKind,
    BranchPoint,
    SpecialPoint,
    SpecialPointKind,
    SpecialPointStatus,
    StopReason,
)
from saltation.branches.corrector import Corrector, Solution, canonical_events
from saltation.branches.monitors import illinois_on_secant, parse_monitors
from saltation.errors import SaltationError
from saltation.orbits.measures import parse_measures
from saltation.orbits.problem import BranchProblem

_log = logging.getLogger(__name__)


def _axis_labels(system) -> dict[str, str]:
    """Every state's and parameter's axis label as the model gives it (none for a model without labels)."""
    label = getattr(system, "axis_label", None)
    if label is None:
        return {}
    return {name: label(name) for name in (*system.state_names, *system.parameter_names)}

class Detector(Protocol):
    """What the engine asks of a special-point detector.

    A protocol: :class:`~saltation.special_points.detection.SpecialPointDetector` is the one the
    special-point layer hands in.
    """

    def check(self, a: Solution, b: Solution, index: int) -> list[SpecialPoint]:
        """The special points between consecutive branch points ``a`` (point ``index``) and ``b``.

        Parameters
        ----------
        a, b : Solution
            Consecutive corrected points of the branch.
        index : int
            The index of ``a`` on the branch.

        Returns
        -------
        list of SpecialPoint
            The special points located between them (none, usually).
        """

    def past_failure(self, prev: Solution) -> tuple[Solution, SpecialPoint] | None:
        """Where the corrector failed beyond ``prev``: the first solution past the special point that stopped it.

        Parameters
        ----------
        prev : Solution
            The last point the corrector reached.

        Returns
        -------
        tuple of (Solution, SpecialPoint) or None
            The first solution past the special point and that point, or None.
        """


    def at_failure(self, prev: Solution, failed: float) -> SpecialPoint | None:
        """What stopped the corrector between ``prev`` and the parameter ``failed``, where nothing was passed.

        Parameters
        ----------
        prev : Solution
            The last point the corrector reached.
        failed : float
            A parameter value at which it failed.

        Returns
        -------
        SpecialPoint or None
            The special point that ends the branch there (an orbit that lies on a switching surface all
            round, located between the last orbit and the first failure), or None.
        """


#: ``detector(problem, corrector, branch) -> Detector``: how the engine makes its detector.
DetectorFactory = Callable[..., Detector]


@dataclass(frozen=True, kw_only=True)
class ContinuationSettings:
    """Options of a continuation run (keyword-only, so a typo is an error).

    Attributes
    ----------
    ds : float
        Initial arclength step.
    ds_min, ds_max : float
        Step bounds; the run stops when the corrector fails at ``ds_min``.
    max_points : int
        Largest number of points of a run.
    bounds : (float, float)
        Interval of the continuation parameter.
    tol : float
        Newton tolerance on the residual.
    max_newton : int
        Corrector iterations before a step counts as failed.
    max_angle : float
        Largest angle (radians) between consecutive tangents in a smooth stretch.
    detect : bool
        Look for and locate special points.
    locate_tol : float
        Distance in ``(u, lam)`` to which special points are located.
    max_correction : float
        A corrector step longer than this (relative to ``1 + |z|``) counts as divergence.
    measures : tuple of str
        Measures of the orbits every branch point records (:mod:`saltation.orbits.measures`: ``"norm"``,
        ``"ptp:x"``, ``"sqrt(x**2 + y**2)"``, ...), in :attr:`BranchPoint.measures` and
        :attr:`Branch.measures`.
    monitors : tuple of Monitor or str
        The user's test functions, located where they cross zero and recorded as special points of kind
        ``monitor`` (:mod:`saltation.branches.monitors`; a text is parsed by ``Monitor.parse``); one with
        ``stop=True`` ends the run there.

    Raises
    ------
    ValueError
        If not ``0 < ds_min <= ds <= ds_max``, or the bounds are not increasing.
    """

    ds: float = 0.02
    ds_min: float = 1e-6
    ds_max: float = 0.05
    max_points: int = 400
    bounds: tuple[float, float] = (-math.inf, math.inf)
    tol: float = 1e-10
    max_newton: int = 7
    max_angle: float = 0.3
    detect: bool = True
    locate_tol: float = 1e-9
    max_correction: float = 0.2
    measures: tuple[str, ...] = ()
    monitors: tuple = ()

    def __post_init__(self):
        if not 0 < self.ds_min <= self.ds <= self.ds_max:
            raise ValueError(f"need 0 < ds_min <= ds <= ds_max, got {self.ds_min}, {self.ds}, {self.ds_max}")
        lo, hi = self.bounds
        if not lo < hi:
            raise ValueError(f"parameter bounds must satisfy lower < upper, got {self.bounds}")


#: What :meth:`Continuation._step` returns where the parameter bound lies closer than the smallest step.
_AT_BOUND = object()


class Continuation:
    """Pseudo-arclength continuation of one branch in one direction.

    Parameters
    ----------
    problem : ShootingProblem or EquilibriumProblem
        The problem, with its continuation parameter set (any problem of the protocol, e.g. a
        :class:`~saltation.orbits.conditions.ConditionedProblem` for a two-parameter curve).
    settings : ContinuationSettings, optional
        The options (``ContinuationSettings()`` by default).
    detector : callable, optional
        ``detector(problem, corrector, branch)`` makes the :class:`Detector` used when
        ``settings.detect``; None (the default) finds no special points.

    Raises
    ------
    SaltationError
        If the problem has no continuation parameter.

    References
    ----------
    Keller (1977), "Numerical solution of bifurcation and nonlinear eigenvalue problems", in
    Rabinowitz (ed.), *Applications of Bifurcation Theory*, Academic Press.

    Examples
    --------
    Iterate step by step::

        cont = Continuation(problem, ContinuationSettings(ds=0.01))
        for point in cont.run(u0, lam0, direction=+1):
            print(point.parameter, point.amplitude)
        branch = cont.branch
    """

    def __init__(self, problem: BranchProblem, settings: ContinuationSettings | None = None, *,
                 detector: DetectorFactory | None = None):
        if problem.lam_index < 0:
            raise SaltationError("the problem needs a continuation parameter (continuation_parameter=...)")
        self.problem = problem
        self.settings = settings or ContinuationSettings()
        self.monitors = parse_monitors(self.settings.monitors, problem.system, problem.lam_name)
        wanted = (*self.settings.measures, *(m for monitor in self.monitors for m in monitor.measures))
        if wanted or problem.measures:
            problem.measures = parse_measures(wanted, problem.system)
        self.corrector = Corrector(problem, self.settings)
        self.branch = Branch(
            model=problem.system.name,
            parameter_name=problem.lam_name,
            kind=BranchKind(problem.branch_kind),
            backward=bool(problem.backward),
            fixed_parameters=dict(zip(problem.system.parameter_names, map(float, problem.p))),
            autonomous=bool(problem.system.is_autonomous),
            state_names=tuple(problem.system.state_names),
            axis_labels=_axis_labels(problem.system),
            measures=tuple(m.text for m in problem.measures),
        )
        self.branch.problem = problem
        self._monitor_stop = False
        self.solutions: list[Solution] = []
        self.last_failure: np.ndarray | None = None
        self.last_error: SaltationError | None = None
        self.detector_factory = detector

    # ---------------------------------------------------------------------------------
    def run(self, u0: np.ndarray, lam0: float, *, direction: int = 1) -> Iterator[BranchPoint]:
        """Yield branch points, starting with the corrected start point.

        The branch grows in :attr:`branch` as the points are yielded; its ``stop_reason`` says why the
        run ended (a parameter bound, the largest number of points, the smallest step, a closed loop, a
        cycle collapse).

        Parameters
        ----------
        u0 : ndarray
            Guess of the unknowns at the start.
        lam0 : float
            Start value of the continuation parameter (corrected at fixed ``lam0``).
        direction : int
            +1 for increasing parameter at the start, -1 for decreasing.

        Yields
        ------
        BranchPoint
            Each accepted point, as recorded on the branch.

        Raises
        ------
        SaltationError
            If ``lam0`` lies outside ``settings.bounds``, or the start point cannot be corrected: a
            :class:`ConvergenceError`, or the error of the problem's evaluation (an
            :class:`IntegrationError`, a :class:`StationaryStateError` ...).
        """

        s = self.settings
        lo, hi = s.bounds
        if not lo <= lam0 <= hi:
            raise SaltationError(f"start value {lam0} of {self.problem.lam_name!r} lies outside the bounds {s.bounds}")
        self.problem.accept(np.asarray(u0, float), lam0)
        sol = self.corrector.solve_fixed(np.asarray(u0, dtype=float), float(lam0))
        e_lam = np.zeros(len(sol.z))
        e_lam[-1] = 1.0 if direction >= 0 else -1.0
        sol.tangent = self.corrector.tangent(sol, e_lam)
        self._accept(sol)
        yield self.branch.points[-1]

        detector = (self.detector_factory(self.problem, self.corrector, self.branch)
                    if s.detect and self.detector_factory is not None else None)
        ds = s.ds
        tried_at, rephased = -1, False
        while True:
            if len(self.branch.points) >= s.max_points:
                self.branch.stop_reason = StopReason.MAX_POINTS
                return
            prev = self.solutions[-1]
            if len(self.solutions) != tried_at:  # a new point: it may be re-phased once
                tried_at, rephased = len(self.solutions), False
            new, ds = self._step(prev, ds)
            if new is _AT_BOUND:
                self.branch.stop_reason = StopReason.PARAMETER_BOUND
                return
            if new is None and ds < s.ds_min and not rephased:
                # before giving up: the shooting state may have drifted onto an event (an autonomous orbit's
                # phase moves from step to step); moved off every event along its orbit, the step is retried
                moved = self._rephased(prev)
                rephased = True
                if moved is not None:
                    ds = max(s.ds_min, min(s.ds, s.ds_max))
                    continue
            jumped = detector.past_failure(prev) if new is None and detector is not None else None
            if jumped is not None:
                new = jumped[0]
            if new is None:
                self._end_at_failure(prev, detector)
                return
            closed, collapse = self._record(prev, new, jumped, detector)
            yield self.branch.points[-1]
            reason = (StopReason.CYCLE_COLLAPSE if collapse is not None else StopReason.CLOSED_LOOP if closed
                      else StopReason.MONITOR if self._monitor_stop
                      else StopReason.PARAMETER_BOUND if new.lam >= hi or new.lam <= lo else None)
            if reason is not None:
                self.branch.stop_reason = reason
                return
            if jumped is not None:
                ds = s.ds
            if new.iterations <= 3:
                ds = min(ds * 1.5, s.ds_max)
            elif new.iterations >= 6:
                ds = max(ds * 0.5, s.ds_min)

    def _step(self, prev: Solution, ds: float) -> tuple[Solution | None | object, float]:
        """One corrected step from ``prev``, halving ``ds`` until it is accepted or below ``ds_min``.

        Returns the new solution (None where every step failed; ``_AT_BOUND`` where the parameter bound
        lies closer than the smallest step) and the step it took.
        """
        s = self.settings
        lo, hi = s.bounds
        while ds >= s.ds_min:
            z_pred = self._predict(ds)
            if z_pred[-1] > hi or z_pred[-1] < lo:
                # land exactly on the bound
                bound = hi if z_pred[-1] > hi else lo
                frac = (bound - prev.z[-1]) / (z_pred[-1] - prev.z[-1])
                if frac * ds < s.ds_min:
                    return _AT_BOUND, ds
                try:
                    cand = self.corrector.solve_fixed(prev.u + frac * ds * prev.tangent[:-1], bound)
                except SaltationError:
                    ds *= 0.5
                    continue
                cand.tangent = self.corrector.tangent(cand, prev.tangent)
                cand.step = frac * ds
                return cand, ds
            try:
                cand = self.corrector.solve_bordered(z_pred, prev.tangent)
            except SaltationError as exc:
                self.last_failure = z_pred
                self.last_error = exc
                ds *= 0.5
                continue
            cand.tangent = self.corrector.tangent(cand, prev.tangent)
            cand.step = ds
            angle = math.acos(max(-1.0, min(1.0, float(cand.tangent @ prev.tangent))))
            corner = canonical_events(cand.summary.event_ids) != canonical_events(prev.summary.event_ids)
            if angle > s.max_angle and not corner and ds > 2 * s.ds_min:
                ds *= 0.5
                continue
            if corner and ds > 4 * s.ds_min and angle > s.max_angle and cand.iterations > 4:
                ds *= 0.5
                continue
            return cand, ds
        return None, ds

    def _end_at_failure(self, prev: Solution, detector: Detector | None) -> None:
        """The run ends where no step succeeds: at a cycle collapse ahead, or at the smallest step, with what the
        detector finds there and the last error."""
        collapse = self._collapse(strict=False)
        if collapse is not None:
            self._add_special(collapse)
            self.branch.stop_reason = StopReason.CYCLE_COLLAPSE
            return
        self.branch.stop_reason = StopReason.MIN_STEP
        ending = (detector.at_failure(prev, float(self.last_failure[-1]))
                  if detector is not None and self.last_failure is not None else None)
        if ending is not None:
            self._add_special(replace(ending, index=len(self.branch.points) - 1))
        if self.last_error is not None:
            self.branch.stop_detail = (f"at {self.problem.lam_name} = {prev.lam:.10g}: "
                                       f"{type(self.last_error).__name__}: {self.last_error}")

    def _record(self, prev: Solution, new: Solution, jumped, detector: Detector | None
                ) -> tuple[bool, SpecialPoint | None]:
        """Accept ``new`` with the special points between ``prev`` and it; whether the branch has closed, and
        the cycle collapse ahead of it (or None)."""
        self._accept(new)
        closed = self._passes_start(prev, new)
        if jumped is not None:
            self._add_special(replace(jumped[1], index=len(self.branch.points) - 2))
        elif detector is not None:
            for sp in detector.check(self.solutions[-2], self.solutions[-1], len(self.branch.points) - 2):
                if any(_same_special_point(sp, old) for old in self.branch.special_points):
                    closed = True  # met again, from the same side: the branch has come round a loop
                else:
                    self._add_special(sp)
        for sp in self._monitor_points(self.solutions[-2], self.solutions[-1], len(self.branch.points) - 2):
            self._add_special(sp)
        collapse = self._collapse(strict=True)
        if collapse is not None:
            self._add_special(collapse)
        return closed, collapse

    def _monitor_points(self, a: Solution, b: Solution, index: int) -> list[SpecialPoint]:
        """Where the monitors cross zero between two consecutive points, located on their secant by the
        Illinois iteration of the smooth special points (:func:`~saltation.branches.monitors.illinois_on_secant`)."""
        found = []
        for monitor in self.monitors:
            ga, gb = monitor(a.summary), monitor(b.summary)
            if not (math.isfinite(ga) and math.isfinite(gb)) or not ((ga < 0.0 <= gb) or (ga > 0.0 >= gb)):
                continue
            d = b.z - a.z
            lo, hi = illinois_on_secant(
                lambda sigma: self.corrector.solve_bordered(a.z + sigma * d, d / np.linalg.norm(d)),
                lambda sol: monitor(sol.summary), a, b, tol=self.settings.locate_tol,
                distance=lambda p, q: float(np.linalg.norm(q.z - p.z)))
            best = lo if abs(monitor(lo.summary)) <= abs(monitor(hi.summary)) else hi
            width = float(np.linalg.norm(hi.z - lo.z))
            found.append(SpecialPoint(
                kind=SpecialPointKind.MONITOR, parameter=best.lam, bracket=(min(lo.lam, hi.lam), max(lo.lam, hi.lam)),
                accuracy=width, index=index, state=best.summary.state, period=best.summary.period,
                amplitude=best.summary.amplitude, multipliers=best.summary.multipliers,
                event_ids=best.summary.event_ids, t0=best.summary.t0,
                status=(SpecialPointStatus.LOCATED if width <= self.settings.locate_tol
                        else SpecialPointStatus.BRACKETED),
                note=f"monitor {monitor.name}: {monitor(best.summary):.3g} there" + (" (it stops the run)"
                                                                                      if monitor.stop else ""),
            ))
            self._monitor_stop = self._monitor_stop or monitor.stop
        return found

    def _collapse(self, *, strict: bool) -> SpecialPoint | None:
        """The cycle collapse ahead of the last three orbits of an autonomous branch, or None.

        Where the orbits shrink onto an equilibrium their excursion ``e`` (see
        :class:`~saltation.orbits.records.BranchPoint`) tends to zero.  With the last three points
        shrinking, ``e`` is extrapolated linearly in the parameter from the last two; if it reaches
        zero within 1.5 steps ahead (4 when the corrector has failed: ``strict`` False), the branch
        ends there.  The bracket reaches the distance ``d`` between that extrapolation and the one from the
        two points before (which tend to the limit together) on either side, and the accuracy is its width
        ``2 d``.
        """
        prob = self.problem
        if not prob.can_collapse or len(self.solutions) < 3:
            return None
        sols = self.solutions[-3:]
        e = [float(s.summary.excursion) for s in sols]
        lam = [s.lam for s in sols]
        if not (np.all(np.isfinite(e)) and e[0] > e[1] > e[2] > 0.0) or lam[2] == lam[1] or lam[1] == lam[0]:
            return None

        def zero_of(i: int, j: int) -> float:
            return lam[j] - e[j] * (lam[j] - lam[i]) / (e[j] - e[i])

        limit, before = zero_of(1, 2), zero_of(0, 1)
        step = lam[2] - lam[1]
        ahead = (limit - lam[2]) / step
        if not 0.0 <= ahead <= (1.5 if strict else 4.0):
            return None
        spread = abs(limit - before)
        accuracy = 2.0 * spread  # the bracket's width: ``accuracy`` is never less than its bracket
        last = sols[-1]
        traj = last.evaluation.trajectory
        return SpecialPoint(
            kind=SpecialPointKind.CYCLE_COLLAPSE,
            parameter=float(limit),
            bracket=(float(limit - spread), float(limit + spread)),
            accuracy=float(accuracy),
            index=len(self.branch.points) - 1,
            state=0.5 * (traj.x_max + traj.x_min),
            period=last.summary.period,
            amplitude=0.0,
            note=(f"the orbits shrink onto an equilibrium: excursions {e[0]:.3g}, {e[1]:.3g}, {e[2]:.3g} at "
                  f"{prob.lam_name} = {lam[0]:.6g}, {lam[1]:.6g}, {lam[2]:.6g} extrapolate to zero at "
                  f"{limit:.10g} (within {accuracy:.1e}); the state is the centre of the last orbit"),
        )

    def _predict(self, ds: float) -> np.ndarray:
        """Predictor along the last tangent, with the curvature of the last step where the branch is smooth.

        The second-order term ``ds^2 / 2 (t_k - t_{k-1}) / ds_{k-1}`` leaves a
        predictor error of ``O(ds^3)``, so that the corrector usually converges
        with one Newton step; across a corner (a change of the event sequence)
        the tangents differ by a jump, not by curvature, and it is left out.
        """
        prev = self.solutions[-1]
        z = prev.z + ds * prev.tangent
        if len(self.solutions) >= 2 and prev.step > 0.0:
            before = self.solutions[-2]
            if canonical_events(before.summary.event_ids) == canonical_events(prev.summary.event_ids):
                z = z + (0.5 * ds * ds / prev.step) * (prev.tangent - before.tangent)
        return z

    def _passes_start(self, prev: Solution, new: Solution) -> bool:
        """Whether the step from ``prev`` to ``new`` passes the run's first point again, in the same direction."""
        if len(self.solutions) < 4:
            return False
        start = self.solutions[0]
        step = new.z - prev.z
        length2 = float(step @ step)
        if length2 == 0.0 or step @ start.tangent <= 0.0:
            return False
        along = min(max(float((start.z - prev.z) @ step) / length2, 0.0), 1.0)
        if not 0.0 < along < 1.0:
            return False
        offset = prev.z + along * step - start.z
        return float(offset @ offset) <= 0.0025 * length2  # a gap of at most 5 % of the step

    def _rephased(self, prev: Solution) -> Solution | None:
        """``prev``'s orbit with its shooting state moved off the switching events (the middle of its longest
        stretch between them: :meth:`~saltation.orbits.shooting.ShootingProblem.start_off_surfaces` for an
        autonomous orbit, :meth:`~saltation.orbits.shooting.ShootingProblem.move_section` with its section time
        for a forced one), corrected at the same parameter and put in ``prev``'s place; None where the problem
        cannot move its state, the state is not near an event, or the moved state does not give the same orbit
        back (the problem's section and start mode are then as before)."""
        problem = self.problem
        saved = problem.section_settings

        def restore() -> None:
            problem.restore_section(saved)
            problem.accept(prev.u, prev.lam)

        try:
            u = problem.rephase(prev.u, prev.lam)
        except SaltationError:
            restore()
            return None
        if u is None or np.array_equal(u, prev.u):
            return None
        try:
            self.problem.accept(u, prev.lam)
            sol = self.corrector.solve_fixed(u, prev.lam)
        except SaltationError:
            restore()
            return None
        if canonical_events(sol.summary.event_ids) != canonical_events(prev.summary.event_ids):
            restore()
            return None
        # the tangent oriented as before: along the same direction of the period and the parameter
        n = self.problem.system.n
        reference = np.zeros(len(sol.z))
        reference[n:] = prev.tangent[n:]
        if not np.any(reference):
            reference[-1] = 1.0
        sol.tangent = self.corrector.tangent(sol, reference)
        # no step leads to it from the point before in these coordinates (its state lies elsewhere on the orbit):
        # the predictor's curvature term, (t_k - t_{k-1}) / ds_{k-1}, is left out after it (with the tiny step
        # that failed it predicted far off the branch, and the corrector landed on the parameter bound)
        sol.step = 0.0
        self.problem.accept(sol.u, sol.lam)
        self.solutions[-1] = sol
        return sol

    def _section(self) -> float:
        """The problem's section time (a forced orbit's, which :meth:`_rephased` may move); 0 otherwise."""
        return self.problem.section_time

    def _add_special(self, sp) -> None:
        """A located special point, stamped with the section its state lies at."""
        _log.info("%s: %s at %s = %.10g (%s, to %.1e)", self.branch.model, sp.kind.value, self.branch.parameter_name,
                  sp.parameter, sp.status.value, sp.accuracy)
        t0 = self._section()
        self.branch.special_points.append(sp if t0 == sp.t0 else replace(sp, t0=t0))

    def _accept(self, sol: Solution) -> None:
        self.problem.accept(sol.u, sol.lam)
        self.solutions.append(sol)
        point = sol.summary.recorded(sol.lam, sol.step, sol.iterations)
        _log.debug("%s: point %d at %s = %.10g (step %.3g, %d Newton iterations, %s)", self.branch.model,
                   len(self.branch.points), self.branch.parameter_name, sol.lam, sol.step, sol.iterations,
                   "stable" if point.stable else "unstable")
        t0 = self._section()
        if t0 != point.t0:
            object.__setattr__(point, "t0", t0)  # (a fresh record: see BranchPoint.recorded)
        self.branch.points.append(point)


def _same_special_point(a, b, rtol: float = 1e-6) -> bool:
    """The same special point located twice: kind, event sequences by identity (the orbit's, or the two
    sides'), parameter and state agree."""
    return (
        a.kind is b.kind
        and a.event_ids == b.event_ids
        and (a.event_ids_minus, a.event_ids_plus) == (b.event_ids_minus, b.event_ids_plus)
        and abs(a.parameter - b.parameter) <= rtol * (1.0 + abs(b.parameter))
        and float(np.linalg.norm(np.asarray(a.state) - np.asarray(b.state))) <= rtol * (1.0 + float(np.linalg.norm(b.state)))
    )


def continue_branch(
    problem,
    u0: np.ndarray,
    lam0: float | None = None,
    *,
    settings: ContinuationSettings | None = None,
    directions: tuple[int, ...] = (1, -1),
    label: str = "",
    progress=None,
    detector: DetectorFactory | None = None,
) -> Branch:
    """Follow a branch from a start point in one or both directions and return it.

    Parameters
    ----------
    problem : ShootingProblem or EquilibriumProblem
        The problem, with its continuation parameter set (any problem of the protocol).
    u0 : ndarray
        Guess of the unknowns at the start (see ``problem.pack``).
    lam0 : float, optional
        Start value of the parameter (the problem's value by default).
    settings : ContinuationSettings, optional
        The options (``ContinuationSettings()`` by default).
    directions : tuple of int
        +1 (increasing parameter first), -1, or both.
    label : str
        A label for the branch (legends, files).
    progress : callable, optional
        Called with each new BranchPoint.
    detector : callable, optional
        Makes the special-point detector (see :class:`Continuation`); None finds none.
        :func:`saltation.continue_branch` hands in the special-point layer's.

    Returns
    -------
    Branch
        The points of every direction (the second direction's reversed and put before the first's),
        with the special points found and each run's stop reason.

    Raises
    ------
    SaltationError
        If no direction is given, the problem has no continuation parameter, ``lam0`` lies outside
        the bounds, or the start point cannot be corrected (see :meth:`Continuation.run`).

    References
    ----------
    Keller (1977), "Numerical solution of bifurcation and nonlinear eigenvalue problems", in
    Rabinowitz (ed.), *Applications of Bifurcation Theory*, Academic Press.
    """
    lam0 = problem.lam0() if lam0 is None else float(lam0)
    branch = run_both_ways(lambda d: Continuation(problem, settings, detector=detector), u0, lam0, directions,
                           progress=progress)
    branch.label = label
    return branch


def run_both_ways(make_run: Callable[[int], Continuation], u0: np.ndarray, lam0: float,
                  directions: tuple[int, ...] = (1, -1), *, progress=None) -> Branch:
    """Run a continuation from one start point in each direction, and stitch the runs into one branch.

    The one stitching of the package: the second direction's points (its start point dropped) are
    reversed and put before the first's, every special point's index moved to match, and each run's
    stop reason kept (:attr:`Branch.stop_reason` the first's, :attr:`Branch.stop_reasons` the others').

    Parameters
    ----------
    make_run : callable
        ``make_run(direction)`` returns a fresh :class:`Continuation` for that direction.
    u0 : ndarray
        Guess of the unknowns at the start.
    lam0 : float
        Start value of the parameter.
    directions : tuple of int
        +1 (increasing parameter first), -1, or both.
    progress : callable, optional
        Called with each new BranchPoint.

    Returns
    -------
    Branch
        The stitched branch.

    Raises
    ------
    SaltationError
        If no direction is given, or a run cannot start (see :meth:`Continuation.run`).
    """
    branch: Branch | None = None
    for d in directions:
        cont = make_run(d)
        _log.info("%s: following %s from %.10g, %s", cont.branch.model, cont.branch.parameter_name, lam0,
                  "increasing" if d > 0 else "decreasing")
        for point in cont.run(np.asarray(u0, dtype=float), lam0, direction=d):
            if progress is not None:
                progress(point)
        run = cont.branch
        _log.info("%s: %d points, stopped: %s%s", run.model, len(run), run.stop_reason.value if run.stop_reason else "-",
                  f" ({run.stop_detail})" if run.stop_detail else "")
        if branch is None:
            branch = cont.branch
        else:
            branch.extend(cont.branch)
            branch.stop_reasons.append(cont.branch.stop_reason)
    if branch is None:
        raise SaltationError("no continuation direction given")
    return branch


__all__ = [
    "Continuation", "ContinuationSettings", "Corrector", "Detector", "DetectorFactory", "Solution", "canonical_events",
    "continue_branch", "run_both_ways",
]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.orbits.single',))
