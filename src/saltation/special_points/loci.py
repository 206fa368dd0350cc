"""Two-parameter curves (loci) of special points of periodic orbits.

A special point located on a branch in one parameter is continued in a
second one by pseudo-arclength continuation of its defining system, with the
first parameter as one more unknown:

Every curve is the orbit's problem with a condition attached
(:mod:`saltation.orbits.conditions`), the first parameter freed and the second the curve's:

* grazing and corner collisions (:class:`GrazingCurve`): periodicity of the
  virtual orbit plus tangency to the grazed surface
  (:class:`~saltation.orbits.conditions.Tangency`, exact Jacobians).  A corner of
  the paper's trilinear kind is a grazing of the contact's entry surface at
  the point where the contact force vanishes, so it is continued by the same
  system;
* crossing-, switching- and adding-sliding (:class:`SlidingCurve`):
  periodicity plus the far field's tangency at the orbit's arrival, named by
  identity (:class:`~saltation.orbits.conditions.ArrivalTangency`), or the
  exit field's cubic tangency (:class:`~saltation.orbits.conditions.CubicTangency`);
* smooth folds and period doublings (:class:`MultiplierCurve`): periodicity
  plus a bordered test function ``g`` that vanishes where ``M - mu I`` is
  singular (``mu = +1`` or ``-1``), the minimally augmented system of Govaerts
  (*Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM 2000);
  derivatives of ``g`` by central differences
  (:class:`~saltation.orbits.conditions.MultiplierCondition`);
* Neimark-Sacker points (:class:`NeimarkSackerCurve`): periodicity plus two
  entries of the bordered ``M^2 - 2 kappa M + I``, ``kappa = cos theta`` one
  more unknown (:class:`~saltation.orbits.conditions.NeimarkSackerCondition`).
  The same system holds at a neutral saddle (a real pair ``mu``, ``1/mu``,
  ``|kappa| > 1``): those points of the curve have no ``curve_kind`` (the
  Neimark-Sacker ones have ``neimark_sacker``), and a curve does not start
  from one.

A curve ends at its bounds, at a located or bracketed codimension-two point,
or with a stop reason that says what failed.

Along a grazing or corner curve the kind of the non-smooth point (its
set-valued multipliers, classified as on a branch) is followed; where it
changes the curve carries a codimension-two point, labelled with both kinds
and located between two curve points (its ``accuracy`` is their distance).
Along a fold or period-doubling curve the orbit's event sequence is
followed; where it changes, the curve meets a corner or grazing there (a
fold born at a corner, a grazing that ends a fold curve), labelled with the
curve's kind and the non-smooth point's.

Along fold, period-doubling and Neimark-Sacker curves the smooth
codimension-two points (cusp, the strong resonances 1:1 to 1:4, fold-flip,
fold- and flip-Neimark-Sacker) are found by test functions and located on the
curve (:mod:`saltation.special_points.codimension_two`); their
``codimension_two`` names them.  Where such a curve's orbits change their events
by a crossing- or switching-sliding, the crossing is located on it too (the far
field's rate at the orbit's arrival vanishes there).

Along a crossing-, switching- or adding-sliding curve the period map is
continuously differentiable across the bifurcation, so the orbits on both sides
share the curve's multipliers: where one passes +1 or -1, or a pair the unit
circle, the curve meets a fold, period-doubling or Neimark-Sacker curve of the
orbits (``sides`` ``("switching_sliding", "fold")``...), and where the far
field's tangency at the arrival turns from visible to invisible (a cubic
tangency) crossing-sliding turns into switching-sliding (``sides`` the kinds
before and after; each point's kind is its ``curve_kind``).  These are located
by the same test functions' search; their ``codimension_two`` is None.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from saltation.branches.branch import (
    Branch,
    BranchKind,
    SpecialPoint,
    SpecialPointKind,
    SpecialPointStatus,
    StopReason,
    problem_and_point,
)
from saltation.branches.corrector import Corrector
from saltation.engine.flow import EventKind, Flow
from saltation.errors import IntegrationError, ModelError, SaltationError
from saltation.orbits.boundary import corner_saltation_is_bounded, saltation_at_corner
from saltation.orbits.classification import classify_nonsmooth
from saltation.orbits.conditions import (
    ArrivalTangency,
    ConditionedProblem,
    CubicTangency,
    EventIdentity,
    MultiplierCondition,
    NeimarkSackerCondition,
    Tangency,
)
from saltation.orbits.conditions.neimark_sacker import nearest_pair_kappa
from saltation.orbits.records import BranchPoint
from saltation.orbits.single import ShootingProblem
from saltation.special_points.codimension_two import CodimensionTwoSearch, TestFunction
from saltation.special_points.continuation import (
    Continuation,
    ContinuationSettings,
    canonical_events,
)
from saltation.special_points.grazing import (
    grazing_candidates,
    locate_grazing,
    tangency_time,
)
from saltation.special_points.sliding import sliding_change

_log = logging.getLogger(__name__)

#: Special points continued by the defining systems of :mod:`saltation.special_points.sliding`.
SLIDING_KINDS = frozenset(
    {SpecialPointKind.CROSSING_SLIDING, SpecialPointKind.SWITCHING_SLIDING, SpecialPointKind.ADDING_SLIDING}
)


@dataclass(repr=False)  # (the repr of a Branch)
class Locus(Branch):
    """A curve of special points in two parameters: a :class:`~saltation.branches.branch.Branch` with
    ``curve_of`` set and nothing of its own.

    Its points carry both parameters (``parameter`` the first, ``second_parameter`` the second) and, on a
    corner's curve, the kind of the corner at each point (``curve_kind``; the column
    :attr:`~saltation.branches.branch.Branch.curve_kinds`).  Its special points are of kind
    CODIMENSION_TWO, where two defining conditions meet.  ``stop_reason`` is why the run of increasing
    second parameter stopped, ``stop_reasons[0]`` why the decreasing one did, and ``stop_detail`` says both
    in words (``"increasing f0: reached a parameter bound; decreasing f0: failed after 12 points: ..."``).

    The class is kept for release 0.2 (``isinstance`` tests, :meth:`record`, :attr:`kinds`); release 0.3.0
    returns plain branches.

    Attributes
    ----------
    model, parameter_name, kind, points, special_points, stop_reason, stop_reasons, stop_detail, ...
        Those of :class:`~saltation.branches.branch.Branch`, as described above.
    """

    @property
    def values(self) -> np.ndarray:
        """``(first, second parameter)`` per curve point, shape (m, 2)."""
        return np.column_stack([self.parameter, self.second_parameter]).reshape(-1, 2)

    @property
    def kinds(self) -> list[str]:
        """Deprecated (goes in release 0.3.0): the values of :attr:`Branch.curve_kinds`."""
        _deprecated("Locus.kinds", "Branch.curve_kinds")
        return [k.value for k in self.curve_kinds if k is not None]

    def record(self) -> dict:
        """Deprecated (goes in release 0.3.0): :func:`saltation.output.codecs.locus_record`.

        Returns
        -------
        dict
            The curve as ``saltation locus --json`` writes it.
        """
        _deprecated("Locus.record", "saltation.output.codecs.locus_record")
        from saltation.output.codecs import locus_record

        return locus_record(self)


def codimension_two_record(sp: SpecialPoint) -> dict:
    """Deprecated (goes in release 0.3.0): :func:`saltation.output.codecs.codimension_two_record`."""
    _deprecated("saltation.special_points.loci.codimension_two_record", "saltation.output.codecs.codimension_two_record")
    from saltation.output.codecs import codimension_two_record as record

    return record(sp)


def _deprecated(old: str, new: str) -> None:
    warnings.warn(f"{old} is deprecated and goes in release 0.3.0: use {new}", DeprecationWarning, stacklevel=3)


def curve_stops(results: Sequence[tuple[Continuation, str, str | None]]) -> dict:
    """How the two runs of a curve ended, as the fields of its branch.

    Parameters
    ----------
    results : sequence of (Continuation, str, str or None)
        What :func:`run_curve` returned for each direction (increasing, then decreasing).

    Returns
    -------
    dict
        ``stop_reason`` (the first run's), ``stop_reasons`` (the others') and ``stop_detail`` (each run's
        direction and reason in words, the error where one stopped it).
    """
    reasons = [StopReason.ERROR if failure else cont.branch.stop_reason for cont, _, failure in results]
    detail = "; ".join(f"{way}: {failure or cont.branch.stop_reason.value}" for cont, way, failure in results)
    return {"stop_reason": reasons[0], "stop_reasons": reasons[1:], "stop_detail": detail}


def _codimension_two(sides: tuple[str, str], values: Sequence[float], accuracy: float, index: int,
                     near: BranchPoint, status: SpecialPointStatus = SpecialPointStatus.BRACKETED,
                     bracket: tuple[float, float] | None = None) -> SpecialPoint:
    """The record of a codimension-two point of a curve, near its curve point ``near`` (index ``index``)."""
    first, second = (float(v) for v in values)
    return SpecialPoint(
        kind=SpecialPointKind.CODIMENSION_TWO, parameter=first, second_parameter=second,
        bracket=bracket or (first, first), accuracy=float(accuracy), index=int(index), state=np.array(near.state),
        period=float(near.period), amplitude=float(near.amplitude), status=status, sides=tuple(sides),
        note=f"{sides[0]} -> {sides[1]}",
    )


class _Curve(ConditionedProblem):
    """A conditioned problem followed as a curve: ``u = (x0, lam1, extras)``, the curve's parameter ``lam2``."""

    def __init__(self, problem: ShootingProblem, conditions, parameters: np.ndarray, first: str, second: str):
        if problem.autonomous or problem.backward:
            raise ModelError("two-parameter curves are implemented for forced models in forward time; "
                             f"{problem.system.name!r} is {'autonomous' if problem.autonomous else 'in backward time'}")
        super().__init__(problem, conditions, free=(first,), continuation=second, parameters=parameters)
        self.first = first

    def snapshot(self) -> dict:
        """The state that :meth:`accept` moves along a run (restored before a run in the other direction).

        Returns
        -------
        dict
            The last evaluation (none), the event sequences (none) and the conditions' starting guesses.
        """
        return {"_last": None, "event_ids": [], "_guesses": [c.start() for c in self.conditions]}

    def restore(self, state: dict) -> None:
        """Restore a :meth:`snapshot` before a run in the other direction.

        Parameters
        ----------
        state : dict
            What :meth:`snapshot` returned.
        """
        for key, value in state.items():
            if key == "_guesses":
                for c, g in zip(self.conditions, value):
                    if len(g):
                        c.t_guess = float(g[0])
            else:
                setattr(self, key, list(value) if isinstance(value, list) else value)  # each run its own lists


class GrazingCurve(_Curve):
    """Grazings (and corners) of a forced orbit in two parameters.

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the branch (forced, forward time).
    parameters : ndarray
        Parameter values at the start.
    first, second : str
        The parameter of the branch (an unknown here) and the one the curve is followed in.
    transition : int
        The transition whose surface is grazed.
    t_guess : float
        Instant of tangency at the start.
    others : sequence of (int, float)
        Transitions touched at the same time (by symmetry), passed too.

    Raises
    ------
    ModelError
        For an autonomous or backward-time problem, or an unknown parameter.
    IndexError
        If ``transition`` is not an index of the model's transitions.

    References
    ----------
    di Bernardo, Budd, Champneys and Kowalczyk (2008), *Piecewise-smooth Dynamical Systems: Theory
    and Applications*, Springer (grazing bifurcations).
    """

    def __init__(self, problem: ShootingProblem, parameters: np.ndarray, first: str, second: str, transition: int,
                 t_guess: float, *, others: Sequence[tuple[int, float]] = ()):
        self.tangency = Tangency(problem.flow, transition, t_guess, also_disabled=[int(k) for k, _ in others])
        super().__init__(problem, [self.tangency], parameters, first, second)
        self.transition = int(transition)
        self.others = [(int(k), float(t)) for k, t in others]
        self.kinds: list[str] = []  # the corner's kind at every accepted point
        self.t_start = float(t_guess)  # the others' touches keep their offsets from the first one's, in periods
        self.period_start = self.system.forcing_period(self.p)

    def accept(self, u: np.ndarray, lam: float) -> None:
        """Called at every accepted curve point: move the guesses along, and classify the corner there.

        Parameters
        ----------
        u : ndarray
            The accepted unknowns ``(x0, lam1, t_g)``.
        lam : float
            The second parameter's value.

        Raises
        ------
        SaltationError
            If the kind of the corner cannot be classified (see :meth:`corner_kind`).
        """
        super().accept(u, lam)
        self.kinds.append(self.corner_kind(u, lam))

    def snapshot(self) -> dict:
        """The state that :meth:`accept` moves along a run, with the corner kinds found (none).

        Returns
        -------
        dict
            As :meth:`_Curve.snapshot`, with ``kinds``.
        """
        return super().snapshot() | {"kinds": []}

    def corner_kind(self, u: np.ndarray, lam: float) -> str:
        """The kind of the non-smooth point at a curve point ``u = (x0, lam1, t_g)``.

        The set-valued multipliers between the grazing orbit's monodromy and the
        same with the excursion's saltation matrices inserted, classified as on a
        branch; ``grazing`` when those saltation matrices are unbounded there.

        Parameters
        ----------
        u : ndarray
            The curve point's unknowns.
        lam : float
            The second parameter's value.

        Returns
        -------
        str
            The value of a :class:`~saltation.branches.branch.SpecialPointKind` (``grazing``,
            ``discontinuous_fold``, ``nonsmooth_no_crossing``...).

        Raises
        ------
        SaltationError
            If a simultaneous touch is lost along the curve, or a run fails.
        numpy.linalg.LinAlgError
            If a fundamental matrix to a touch is singular.

        References
        ----------
        Leine and Van Campen, "Fold bifurcations in discontinuous systems", eq. (9) simplified on the
        switching surface (the saltation matrices at the corner).
        """
        n = self.system.n
        p = self.parameters_at(lam, u)
        shot = self._last[0] if self._last is not None and np.array_equal(self._last[0].x0, u[:n]) \
            and np.array_equal(self._last[0].parameters, p) else self.equations(u, lam, need_lam=False)[3]
        disabled = list(self.disabled)
        t_graze = float(u[-1])
        product = np.eye(n)
        stretch = shot.period / self.period_start
        touches = [(self.transition, t_graze)] + [(k, t_graze + (t - self.t_start) * stretch) for k, t in self.others]
        for k, t_k in sorted(touches, key=lambda kt: kt[1]):
            if k != self.transition:
                surface = self.system.surface_index(self.system.transitions[k].surface)
                t_k = tangency_time(self.flow, u[:n], self.t0, p, surface, t_k, shot.period, disabled=disabled,
                                    tolerances=self.tolerances)
                if t_k is None:
                    raise SaltationError(f"the second touch of transition {k} was lost along the curve")
            to_k = self.flow.run(u[:n], self.t0, t_k, p, variational=True, disabled=disabled, tolerances=self.tolerances)
            P = saltation_at_corner(self.system, self._excursion(k, t_k, to_k.x1, p), t_k, to_k.x1, p)
            if not corner_saltation_is_bounded(self.system, k, t_k, to_k.x1, p, P):
                return SpecialPointKind.GRAZING.value
            phi = to_k.monodromy
            product = np.linalg.solve(phi, P @ phi) @ product
        M = shot.trajectory.monodromy
        return classify_nonsmooth(M, M @ product).kind.value

    def _excursion(self, transition: int, t: float, x: np.ndarray, p: np.ndarray) -> list[int]:
        """A grazed transition, then the exit back that holds at the corner (a surface through it), if any."""
        sys_ = self.system
        entry = sys_.transitions[transition]
        if entry.target == entry.source:
            return [transition]
        scale = 1.0 + float(np.linalg.norm(x))
        for k, tr in enumerate(sys_.transitions):
            if tr.source == entry.target and tr.target == entry.source and tr.surface != entry.surface:
                if abs(self.flow.indicator(tr.surface, t, x, p)) <= 1e-7 * scale:
                    return [transition, k]
        return [transition]


def grazed_transitions(
    flow: Flow, state: np.ndarray, p: np.ndarray, *, t0: float = 0.0, tolerances=None
) -> list[tuple[int, float]]:
    """The transitions whose surfaces a boundary orbit touches, and when: ``(transition, time)`` pairs.

    The closest touch comes first; the others are those as close to within
    ``1e-6`` of the state's scale (simultaneous touches, such as both supports
    of a symmetric orbit).

    Parameters
    ----------
    flow : Flow
        The flow of a forced model.
    state : ndarray
        The orbit's state at ``t0``.
    p : ndarray
        Parameter values.
    t0 : float
        Initial time.
    tolerances : Tolerances, optional
        Integration tolerances.

    Returns
    -------
    list of tuple of (int, float)
        The touched transitions and the instants of the touches.

    Raises
    ------
    SaltationError
        If the orbit touches no surface of a transition of its modes, or a run fails (an
        :class:`IntegrationError`).
    ModelError
        For an autonomous model (it has no forcing period).
    """
    system = flow.system
    T = system.forcing_period(p)
    try:
        traj = flow.run(state, t0, t0 + T, p, dense=True, tolerances=tolerances)
    except IntegrationError:  # exactly tangent: look at the virtual orbit
        traj = flow.run(state, t0, t0 + T, p, dense=True, tolerances=tolerances, disabled=range(len(system.transitions)))
    touches = []
    for k, t in grazing_candidates(flow, traj, p):
        surface = system.surface_index(system.transitions[k].surface)
        t = tangency_time(flow, state, t0, p, surface, t, T, tolerances=tolerances)  # the extremum itself
        if t is None or any(k == k2 and abs(t - t2) <= 1e-9 * T for _, k2, t2 in touches):
            continue
        x = flow.run(state, t0, t, p, tolerances=tolerances).x1
        touches.append((abs(flow.indicator(surface, t, x, p)), k, t))
    if not touches:
        raise SaltationError(f"the orbit at {state.tolist()} touches no switching surface: not a grazing or corner orbit")
    touches.sort()
    scale = 1e-6 * (1.0 + float(np.linalg.norm(state)))
    return [(k, t) for gap, k, t in touches if gap <= touches[0][0] + scale]


def follow_locus(
    problem: Branch | ShootingProblem,
    point: SpecialPoint | int,
    second: str,
    bounds: tuple[float, float],
    *,
    settings: ContinuationSettings | None = None,
    progress: Callable | None = None,
    normal_forms: bool = False,
) -> Locus:
    """Continue a special point of a branch in a second parameter, in both directions.

    Parameters
    ----------
    problem : Branch or ShootingProblem
        The branch (it holds its problem), or the problem of the branch (forced, forward time, its
        continuation parameter set; the form of release 0.1).
    point : SpecialPoint or int
        A grazing or a non-smooth point (corner) of that branch, a crossing-, switching- or
        adding-sliding, or a fold or period doubling; from a branch, also its index in
        ``branch.special_points``.
    second : str
        The second parameter.
    bounds : (float, float)
        The range of the second parameter.
    settings : ContinuationSettings, optional
        Step sizes and tolerances (``bounds`` overrides theirs; special points of the curve itself are
        not detected).
    progress : callable, optional
        Called with each new curve point.
    normal_forms : bool
        On a period-doubling or Neimark-Sacker curve, also locate where its cubic normal-form coefficient
        changes sign (generalised period doubling, Chenciner): the coefficient is computed at every curve point
        (:func:`saltation.special_points.codimension_two.normal_form_coefficient`, a tenth of a second to
        seconds a point).

    Returns
    -------
    Locus
        ``stop_reason`` and ``stop_reasons[0]`` say why the increasing and the decreasing run stopped, ``stop_detail`` both in words.
        Its special points are the codimension-two points along it (see the module's docstring); on a sliding
        bifurcation's curve each point's ``curve_kind`` is its kind.

    Raises
    ------
    ModelError
        For an autonomous or backward-time problem, one over several forcing periods, or a kind
        without a defining system here.
    SaltationError
        If the curve cannot start: the special point's defining system has no solution at its start.
    ValueError
        If ``bounds`` is not increasing.

    References
    ----------
    Keller (1977), "Numerical solution of bifurcation and nonlinear eigenvalue problems", in
    Rabinowitz (ed.), *Applications of Bifurcation Theory*, Academic Press (pseudo-arclength
    continuation).  Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*,
    SIAM (minimally augmented systems of folds and period doublings).  di Bernardo, Kowalczyk and
    Nordmark (2002), "Bifurcations of dynamical systems with sliding: derivation of normal-form
    mappings", Physica D 170 (the sliding bifurcations).
    """
    problem, point = problem_and_point(problem, point, "a two-parameter curve")
    if problem.autonomous or problem.backward or problem.periods != 1:
        raise ModelError("two-parameter curves are implemented for forced models in forward time, over one forcing period")
    getattr(problem, "align_section", lambda point: None)(point)  # (the point's state lies at its own section)
    # with multiple shooting the curve's defining system shoots by segments; what is read off a curve point
    # (the kind of a corner, the grazing that ends a fold curve) is computed on the single problem
    single = getattr(problem, "problem", problem)
    p = problem.parameters_at(point.parameter)
    state = np.asarray(point.state, dtype=float)
    curve, classify = _curve_for(problem, single, point, p, second)
    u0 = curve.pack(state)
    settings = settings or ContinuationSettings(bounds=bounds)
    # the curve's own turning points and the multipliers of its orbits are not special points of the curve
    settings = replace(settings, bounds=bounds, detect=False)
    lam0 = float(p[curve.lam_index])
    runs, records, results, kinds_by_run, events_by_run, ends = [], [], [], [], [], []
    raw, summaries = [], []  # the curve's points in its own layout, and their records (codimension two)
    start = curve.snapshot()
    n = problem.system.n
    for direction in (1, -1):
        curve.restore(start)  # each direction starts from the special point's own guesses
        cont, way, failure = run_curve(
            curve, settings, u0, lam0, direction, progress,
            f"the {point.kind.value} curve in {second} cannot start from the point at "
            f"{problem.lam_name} = {point.parameter:.10g}", second=second, curve_of=point.kind,
        )
        # the run's own branch is the curve (in its second parameter): its orbits' multipliers may pass the unit
        # circle at a codimension-two point, which is not a change of stability of a branch of orbits
        cont.branch.curve_of = point.kind
        # the curve's points in the single-shooting layout (x0, the first parameter, extras, the second)
        runs.append([np.concatenate([sol.z[:n], sol.z[curve.n_base:]]) for sol in cont.solutions])
        # the curve's points carry both parameters: the first (an unknown of the curve) and the second
        records.append([replace(bp, parameter=float(sol.z[curve.n_base]), second_parameter=float(sol.z[-1]))
                        for bp, sol in zip(cont.branch.points, cont.solutions)])
        kinds_by_run.append(list(getattr(curve, "kinds", [])))
        raw.append([sol.z for sol in cont.solutions])
        summaries.append(list(cont.branch.points))
        results.append((cont, way, failure))
        events_by_run.append([canonical_events(e) for e in curve.event_ids])
        if (isinstance(curve, MultiplierCurve) and failure is None
                and cont.branch.stop_reason is not StopReason.PARAMETER_BOUND):
            end = _end_at_a_corner(single, curve, point.kind, runs[-1], records[-1])
            if end is not None:
                ends.append((len(runs) - 1, end))

    def joined(by_run: list) -> list:
        return list(reversed(by_run[1]))[:-1] + by_run[0]

    zs = joined(runs)
    locus = Locus(
        model=problem.system.name, parameter_name=problem.lam_name, kind=BranchKind.PERIODIC,
        points=joined(records), fixed_parameters=dict(zip(problem.system.parameter_names, map(float, p))),
        label=f"{point.kind.value} curve", autonomous=problem.autonomous, second_parameter_name=second,
        curve_of=point.kind, state_names=tuple(problem.system.state_names), **curve_stops(results),
    )
    _mark_codimension_two(locus, zs, joined(kinds_by_run) if classify else None, joined(events_by_run),
                          curve, single, point.kind, raw=joined(raw), summaries=joined(summaries),
                          corrector=Corrector(curve, settings))
    if isinstance(curve, NeimarkSackerCurve):  # a neutral saddle's points are not Neimark-Sacker points
        locus.points = [replace(bp, curve_kind=SpecialPointKind.NEIMARK_SACKER if abs(z[-2]) < 1 else None)
                        for bp, z in zip(locus.points, joined(raw))]
    if isinstance(curve, (MultiplierCurve, NeimarkSackerCurve, SlidingCurve)) or (
            isinstance(curve, GrazingCurve) and point.kind is SpecialPointKind.GRAZING_SLIDING):
        search = CodimensionTwoSearch(curve, point.kind, Corrector(curve, settings), normal_forms=normal_forms)
        for index, sp in search.search(joined(raw), joined(summaries)):
            locus.special_points.append(sp)
        locus.special_points.sort(key=lambda sp: sp.index)
    if isinstance(curve, SlidingCurve):  # the kind at every point (crossing- or switching-sliding may change)
        locus.points = [replace(bp, curve_kind=_kind_or_none(curve, z)) for bp, z in zip(locus.points, joined(raw))]
    # a corner that ends a run lies beyond its last point: the curve's last (increasing) or first (decreasing)
    locus.special_points.extend(replace(e, index=(len(zs) - 1 if run == 0 else 0)) for run, e in ends)
    return locus


def _kind_or_none(curve: SlidingCurve, z: np.ndarray) -> SpecialPointKind | None:
    """The sliding bifurcation at a curve point (None where its shot fails)."""
    try:
        return curve.kind_at(z)
    except SaltationError as exc:
        _log.info("the kind of the sliding bifurcation at %s = %.10g is not known: %s", curve.lam_name, z[-1], exc)
        return None


def _curve_for(problem: ShootingProblem, single: ShootingProblem, point: SpecialPoint, p: np.ndarray,
               second: str) -> tuple[_Curve, bool]:
    """The defining system of ``point``'s curve in ``second``, and whether its points' kinds are classified
    (a corner's curve: the kind of the corner may change along it)."""
    state = np.asarray(point.state, dtype=float)
    if point.kind in SLIDING_KINDS:
        return SlidingCurve(problem, p, second, point), False
    if point.kind.is_nonsmooth:
        touched = _touch_of(single, point)
        if point.kind is SpecialPointKind.GRAZING_SLIDING and touched is not None:
            # the located orbit touches the sliding region's boundary: its run may slide for a rounding
            # there, so the transition and instant come from the point itself
            transition, t_g, others = *touched, []
        else:
            try:
                (transition, t_g), *others = grazed_transitions(single.flow, state, p, t0=single.t0,
                                                                tolerances=single.tolerances)
            except SaltationError:
                if touched is None:
                    raise
                transition, t_g, others = *touched, []
        return GrazingCurve(problem, p, problem.lam_name, second, transition, t_g, others=others), True
    if point.kind in (SpecialPointKind.FOLD, SpecialPointKind.PERIOD_DOUBLING):
        return MultiplierCurve(problem, p, second, mu=1.0 if point.kind is SpecialPointKind.FOLD else -1.0), False
    if point.kind is SpecialPointKind.NEIMARK_SACKER:
        if point.multipliers is None:
            raise ModelError("the Neimark-Sacker point does not record its multipliers")
        kappa = nearest_pair_kappa(point.multipliers)
        return NeimarkSackerCurve(problem, p, second, kappa=kappa), False
    raise ModelError(f"no two-parameter continuation for special points of kind {point.kind.value}")


def _mark_codimension_two(locus: Locus, zs: list, kinds: list | None, events: list, curve: _Curve,
                          single: ShootingProblem, kind: SpecialPointKind, *, raw: list | None = None,
                          summaries: list | None = None, corrector: Corrector | None = None) -> None:
    """The codimension-two points along a curve: where a corner's kind changes (``kinds``), and where a fold or
    period-doubling curve's orbits change their event sequence; each between two curve points, at their
    midpoint.  A change by a crossing- or switching-sliding is located on the curve (:func:`_meets_sliding`;
    ``raw``, ``summaries`` and ``corrector`` are the curve's points in its own layout, their records and its
    corrector)."""
    points = locus.values

    def label(a: int, sides: tuple[str, str]) -> SpecialPoint:
        return _codimension_two(sides, 0.5 * (points[a] + points[a + 1]), np.linalg.norm(points[a + 1] - points[a]),
                                a, locus.points[a], bracket=(float(points[a][0]), float(points[a + 1][0])))

    if kinds is not None:
        locus.points = [replace(bp, curve_kind=SpecialPointKind(k)) for bp, k in zip(locus.points, kinds)]
        for a in range(len(zs) - 1):
            if kinds[a] != kinds[a + 1]:
                locus.special_points.append(label(a, (kinds[a], kinds[a + 1])))
    if isinstance(curve, MultiplierCurve) and len(events) == len(zs):  # (a fold curve follows its orbits' events)
        for a in range(len(zs) - 1):
            if events[a] != events[a + 1]:
                sliding = None if raw is None else _meets_sliding(single, curve, kind, zs[a], zs[a + 1], a,
                                                                  raw, summaries, corrector)
                if isinstance(sliding, SpecialPoint):
                    locus.special_points.append(sliding)
                    continue
                touch = sliding or _touch_kind(single, curve, zs[a] if len(events[a]) <= len(events[a + 1])
                                               else zs[a + 1])
                locus.special_points.append(label(a, (kind.value, touch)))


def _meets_sliding(single: ShootingProblem, curve: MultiplierCurve, kind: SpecialPointKind, za: np.ndarray,
                   zb: np.ndarray, a: int, raw: list, summaries: list, corrector: Corrector
                   ) -> SpecialPoint | str | None:
    """Where a fold or period-doubling curve's orbits change their events between curve points ``a`` and ``a +
    1`` by a sliding bifurcation (:func:`saltation.special_points.sliding.sliding_change`): the curve crosses that
    sliding bifurcation's curve.  A crossing- or switching-sliding is located on the curve where the far field's
    rate ``h_x f_B + h_t`` at the orbit's arrival (named by identity) vanishes, by the search's Illinois on the
    curve (:class:`~saltation.special_points.codimension_two.CodimensionTwoSearch`); an adding-sliding is only
    named (its kind is returned, for a bracketed label).  None where the change is not a sliding bifurcation or
    the location fails."""
    n = single.system.n
    flow = single.flow
    try:
        trajs, ps = [], []
        for z in (za, zb):
            p = _parameters_of(curve, z)
            trajs.append(flow.run(z[:n], single.t0, single.t0 + single.system.forcing_period(p), p,
                                  tolerances=single.tolerances))
            ps.append(p)
        change, without = sliding_change(flow, trajs[0], trajs[1], ps[1], ps[0]), 0
        if change is None:
            change, without = sliding_change(flow, trajs[1], trajs[0], ps[0], ps[1]), 1
    except SaltationError:
        return None
    if change is None:
        return None
    if change.kind is SpecialPointKind.ADDING_SLIDING or change.count != 1:
        return change.kind.value
    arrival = trajs[without].events[change.index]
    same = [e for e in trajs[without].events if e.kind in (EventKind.TRANSITION, EventKind.SLIDING_START)
            and e.surface == arrival.surface and e.mode_from == arrival.mode_from]
    identity = EventIdentity(surface=arrival.surface, mode_from=arrival.mode_from, ordinal=same.index(arrival))
    surface = single.system.surface_index(arrival.surface)
    last = [arrival.t]

    def far_rate(c, point, reference) -> float:
        p = c.parameters_at(float(point.z[-1]), point.z[:-1])
        T = single.system.forcing_period(p)
        traj = flow.run(np.asarray(point.z[:n], dtype=float), single.t0, single.t0 + T, p,
                        tolerances=single.tolerances)
        e = identity.find(traj.events, last[0], T)
        last[0] = e.t
        return float(flow.lie_derivative(change.mode, surface, e.t, e.x_minus, p)[0])

    test = TestFunction(None, change.kind.value, far_rate,
                        label=f"its orbits' events change by a {change.kind.value.replace('_', '-')} (the field of "
                              f"{change.mode!r} turns tangent to surface {arrival.surface!r} where the orbit arrives "
                              "there)")
    search = CodimensionTwoSearch(curve, kind, corrector)
    search.tests = (test,)
    try:
        ea, eb = (search.evaluate(search.point(raw[i], summaries[i].multipliers, summaries[i].monodromy), None)
                  for i in (a, a + 1))
        if ea.values[0] is None or eb.values[0] is None or ea.values[0] * eb.values[0] > 0:
            return change.kind.value
        found = search._locate(test, 0, ea, eb, a, summaries[a])
    except (SaltationError, np.linalg.LinAlgError) as exc:
        _log.info("the %s on the %s curve not located: %s", change.kind.value, kind.value, exc)
        return change.kind.value
    return found if found is not None else change.kind.value


def run_curve(curve, settings: ContinuationSettings, u0: np.ndarray, lam0: float, direction: int,
              progress: Callable | None, cannot_start: str, *, second: str,
              curve_of: SpecialPointKind | None = None) -> tuple[Continuation, str, str | None]:
    """One direction of a two-parameter curve: ``(the continuation, "increasing NAME", the failure or None)``.

    Parameters
    ----------
    curve
        The curve's problem (continuation protocol; its continuation parameter is the second parameter).
    settings : ContinuationSettings
    u0 : ndarray
        The unknowns at the special point.
    lam0 : float
        The second parameter there.
    direction : int
        +1 or -1.
    progress : callable or None
        Called with each new curve point.
    cannot_start : str
        The message of the error raised when not even the first point is found.
    second : str
        The second parameter's name (for the direction in words).
    curve_of : SpecialPointKind, optional
        The kind of special point the curve continues: its continuation's branch is a curve
        (:attr:`~saltation.branches.branch.Branch.curve_of`), checked as one (a second multiplier that crosses the
        unit circle along it is a codimension-two point, which the curve's caller looks for, not a special point
        of the continuation).

    Returns
    -------
    tuple
        The finished :class:`Continuation`, the direction in words, and a sentence on why it failed (None when
        it stopped for another reason, which its branch's ``stop_reason`` gives).

    Raises
    ------
    SaltationError
        If the curve cannot start (``cannot_start: <the error>``).
    """
    cont = Continuation(curve, settings)
    cont.branch.curve_of = curve_of
    way = f"{'increasing' if direction > 0 else 'decreasing'} {second}"
    try:
        for pt in cont.run(u0, lam0, direction=direction):
            if progress is not None:
                progress(pt)
    except (SaltationError, np.linalg.LinAlgError) as exc:
        if not cont.solutions:
            raise SaltationError(f"{cannot_start}: {exc}") from exc
        return cont, way, f"failed after {len(cont.solutions)} points: {exc}"
    return cont, way, None


def _touch_of(problem: ShootingProblem, point: SpecialPoint) -> tuple[int, float] | None:
    """``(transition, instant)`` of a grazing point's touch, from what the point records (the surface, the
    mode the grazed transition leaves, the instant), or None."""
    if not point.touch_surface or not np.isfinite(point.touch_time):
        return None
    for k, tr in enumerate(problem.system.transitions):
        if tr.surface == point.touch_surface and tr.source == point.touch_mode:
            return k, float(point.touch_time)
    return None


def _end_at_a_corner(problem: ShootingProblem, curve: MultiplierCurve, kind: SpecialPointKind,
                     zs: list[np.ndarray], records: list[BranchPoint], *, gap: float = 1e-3,
                     last: int = 12) -> SpecialPoint | None:
    """Where a fold or period-doubling curve stops short of its bounds because its orbit comes to touch a
    switching surface (a segment of the orbit shrinks to nothing: a smooth fold born at a corner), the
    curve ends on the corner curve.  Of its last points, the one whose orbit comes nearest to a surface
    (within ``gap`` of the state's size) is taken; the corner at its value of the second parameter is
    located by the grazing defining system in the first.  That corner is the label's position, and the
    distance from the curve point to it the label's accuracy.  The grazing system's virtual orbit passes
    the transition without firing it for the whole period: where the orbit passes that transition
    elsewhere too (a second contact with the same stop), the virtual orbit misses that passage as well and
    its grazing is another orbit's, so no end is labelled (None)."""
    n = problem.system.n
    best = None
    for z, record in zip(zs[-last:], records[-last:]):
        p = _parameters_of(curve, z)
        touches = []
        try:
            (transition, t_g), *_ = grazed_transitions(problem.flow, z[:n], p, t0=problem.t0,
                                                       tolerances=problem.tolerances)
            surface = problem.system.transitions[transition].surface
            x = problem.flow.run(z[:n], problem.t0, t_g, p, tolerances=problem.tolerances).x1
            # a near miss: the orbit does not pass the transition there
            touches.append((abs(problem.flow.indicator(surface, t_g, x, p)) / (1.0 + float(np.linalg.norm(x))),
                            transition, t_g, 0))
        except SaltationError:
            pass
        # a vanishing excursion: the orbit passes the transition once there, on its way in
        touches += [(*e, 1) for e in short_excursions(problem.flow, z[:n], p, t0=problem.t0,
                                                      tolerances=problem.tolerances)]
        for g, transition, t_g, own in touches:
            if g <= gap and (best is None or g < best[0]):
                best = (g, z, p, transition, t_g, record, own)
    if best is None:
        return None
    _, z, p, transition, t_g, record, own = best
    passes = _passages(problem, z[:n], p, transition)
    if passes is None or passes > own:
        _log.info("the %s curve ends where its orbit touches the surface of transition %d, which it passes %s "
                  "elsewhere in the period: the grazing's virtual orbit (that transition disabled) would miss "
                  "that passage too, so the end is not located", kind.value, transition,
                  "(a run failed)" if passes is None else f"{passes - own} more time(s)")
        return None
    try:
        corner = locate_grazing(problem.flow, z[:n], float(z[n]), problem.lam_name, transition, t_g, parameters=p,
                                t0=problem.t0, tolerances=problem.tolerances)
    except SaltationError:
        return None
    at = np.concatenate([corner.state0, [corner.parameter, z[-1]]])
    return _codimension_two((kind.value, _touch_kind(problem, curve, at)), (corner.parameter, float(z[-1])),
                            max(abs(corner.parameter - float(z[n])), corner.accuracy), 0, record,
                            status=SpecialPointStatus.LOCATED)


def _passages(problem: ShootingProblem, state: np.ndarray, p: np.ndarray, transition: int) -> int | None:
    """How many times the orbit from ``state`` fires ``transition`` in one forcing period (None: the run
    fails)."""
    T = problem.system.forcing_period(p)
    try:
        traj = problem.flow.run(state, problem.t0, problem.t0 + T, p, tolerances=problem.tolerances)
    except SaltationError:
        return None
    return sum(1 for e in traj.events if e.kind is EventKind.TRANSITION and e.transition == transition)


def short_excursions(flow: Flow, state: np.ndarray, p: np.ndarray, *, t0: float = 0.0, tolerances=None,
                     samples: int = 32) -> list[tuple[float, int, float]]:
    """The orbit's excursions into a mode and back (a transition into a mode, then one out of it to the
    mode it came from, across the same surface or another, as contact made on one surface and lost on
    another): ``(depth, transition in, time of the depth)``, the depth the largest ``|h|`` of the
    surface crossed in, reached in between (from ``samples`` points of the dense output), relative to
    ``1 + |x|``.  An excursion that shrinks to nothing is the other side of a grazing: where the orbit
    without that transition would touch the surface."""
    system = flow.system
    T = system.forcing_period(p)
    try:
        traj = flow.run(state, t0, t0 + T, p, dense=True, tolerances=tolerances)
    except SaltationError:
        return []
    events = [e for e in traj.events if e.kind is EventKind.TRANSITION]
    found = []
    for into, back in zip(events, events[1:]):
        if not (into.mode_to == back.mode_from and back.mode_to == into.mode_from):
            continue
        times = np.linspace(into.t, back.t, samples + 2)[1:-1]
        if times.size == 0 or not np.all(np.isfinite(times)):
            continue
        xs = traj.at(times)
        h = np.array([abs(flow.indicator(into.surface, t, x, p)) for t, x in zip(times.tolist(), xs)])
        i = int(np.argmax(h))
        found.append((float(h[i]) / (1.0 + float(np.linalg.norm(xs[i]))), into.transition, float(times[i])))
    return found


def _parameters_of(curve: _Curve, z: np.ndarray) -> np.ndarray:
    """Every parameter's value at a curve point in the single-shooting layout ``(x0, first, extras, second)``."""
    n = curve.system.n
    p = curve.p.copy()
    p[curve.free] = z[n : n + len(curve.free)]
    p[curve.lam_index] = z[-1]
    return p


def _touch_kind(problem: ShootingProblem, curve: _Curve, z: np.ndarray) -> str:
    """The kind of the non-smooth point a curve's orbit meets where its event sequence changes (a smooth
    fold born at a corner, a fold curve ended by a grazing): classified at the curve point on the side
    without the extra events, as on a corner curve; ``"nonsmooth"`` when that fails."""
    n = problem.system.n
    p = _parameters_of(curve, z)
    try:
        (transition, t_g), *others = grazed_transitions(problem.flow, z[:n], p, t0=problem.t0,
                                                        tolerances=problem.tolerances)
        corner = GrazingCurve(problem, p, problem.lam_name, curve.lam_name, transition, t_g, others=others)
        return corner.corner_kind(np.concatenate([z[: n + 1], [t_g]]), z[-1])
    except (SaltationError, np.linalg.LinAlgError):
        return "nonsmooth"


def arrival_identity(flow: Flow, state: np.ndarray, p: np.ndarray, surface: str, t_touch: float, *,
                     t0: float = 0.0, tolerances=None) -> tuple[EventIdentity, float]:
    """The arrival at ``surface`` of the orbit from ``state`` nearest ``t_touch``, named by identity.

    The identity is the mode it arrives from and its place among such arrivals.

    Parameters
    ----------
    flow : Flow
        The flow of a forced model.
    state : ndarray
        The orbit's state at ``t0``.
    p : ndarray
        Parameter values.
    surface : str
        The surface arrived at.
    t_touch : float
        The instant of the arrival, roughly.
    t0 : float
        Initial time.
    tolerances : Tolerances, optional
        Integration tolerances.

    Returns
    -------
    identity : EventIdentity
        The arrival's identity.
    t : float
        Its time.

    Raises
    ------
    SaltationError
        If the orbit does not arrive at the surface, or its run fails (an :class:`IntegrationError`).
    ModelError
        For an autonomous model (it has no forcing period).
    """
    T = flow.system.forcing_period(p)
    traj = flow.run(state, t0, t0 + T, p, tolerances=tolerances)
    arrivals = [e for e in traj.events if e.surface == surface and e.kind in (EventKind.TRANSITION, EventKind.SLIDING_START)]
    if not arrivals:
        raise SaltationError(f"the orbit at {state.tolist()} does not arrive at surface {surface!r}")

    def gap(e):
        d = (e.t - t_touch) % T
        return min(d, T - d)

    e = min(arrivals, key=gap)
    same = [a for a in arrivals if a.mode_from == e.mode_from]
    return EventIdentity(surface=surface, mode_from=e.mode_from, ordinal=same.index(e)), e.t


class SlidingCurve(_Curve):
    """Crossing-, switching- or adding-sliding bifurcations of a forced orbit in two parameters.

    Periodicity plus the far field's tangency at the orbit's arrival at the surface (crossing- and
    switching-sliding; unknowns ``(x0, lam1)``), the arrival named once, at the start, by the mode it
    arrives from and its place among such arrivals (:class:`~saltation.orbits.conditions.EventIdentity`):
    a short excursion into the far side that re-arrives moments later comes from the other mode and
    is never taken for it.  Or the exit field's cubic tangency at an instant ``tau`` of a sliding motion
    (adding-sliding; unknowns ``(x0, lam1, tau)``).

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the branch (forced, forward time).
    parameters : ndarray
        Parameter values at the start.
    second : str
        The parameter the curve is followed in.
    point : SpecialPoint
        The located sliding bifurcation (with its ``touch_surface``, ``touch_mode`` and
        ``touch_time``).

    Raises
    ------
    ModelError
        If the point does not say where the orbit touches the surface, or the problem is autonomous
        or in backward time.
    SaltationError
        If the orbit does not arrive at the surface (crossing- and switching-sliding), or its run fails.

    References
    ----------
    di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding:
    derivation of normal-form mappings", Physica D 170.
    """

    def __init__(self, problem: ShootingProblem, parameters: np.ndarray, second: str, point: SpecialPoint):
        if not point.touch_surface:
            raise ModelError(f"the {point.kind.value} point does not say where the orbit touches the surface")
        flow = problem.flow
        self.adding = point.kind is SpecialPointKind.ADDING_SLIDING
        if self.adding:
            condition = CubicTangency(flow, point.touch_mode, point.touch_surface, float(point.touch_time))
        else:
            identity, t_e = arrival_identity(flow, np.asarray(point.state, dtype=float), parameters, point.touch_surface,
                                             float(point.touch_time), t0=problem.t0, tolerances=problem.tolerances)
            condition = ArrivalTangency(flow, identity, point.touch_mode, t_e)
        self.condition = condition
        self._visibility: dict[bytes, float] = {}  # arrival_visibility by curve point
        super().__init__(problem, [condition], parameters, problem.lam_name, second)

    def arrival_visibility(self, z: np.ndarray) -> float:
        """The far field's curvature at the arrival of a curve point ``z = (u, lam)``, signed positive where its
        tangency is visible from its own side (crossing-sliding) and negative where invisible (switching-sliding).

        ``d2h/dt2 = L_B,x f_B + L_B,t`` along the far field ``f_B`` (``L_B = h_x f_B + h_t``, exact derivatives of
        the model), times the sign of the arriving field's rate ``h_x f_A + h_t`` (the side of the surface the
        far mode lies on).  A zero is a cubic tangency at the arrival, where the curve's kind changes.

        Parameters
        ----------
        z : ndarray
            A point of the curve, in its layout.

        Returns
        -------
        float
            The signed curvature.

        Raises
        ------
        ModelError
            On an adding-sliding curve (no arrival).
        SaltationError
            If the point's shot fails or the orbit no longer arrives there.
        """
        if self.adding:
            raise ModelError("an adding-sliding curve has no arrival whose visibility could change")
        z = np.asarray(z, dtype=float)
        key = z.tobytes()
        if key not in self._visibility:
            u, lam = z[:-1], float(z[-1])
            self.equations(u, lam, need_lam=False)
            e = self.condition.event
            p = self.parameters_at(lam, u)
            flow, surface = self.flow, self.system.surface_index(e.surface)
            _, Lx, _, Lt = flow.lie_derivative(self.condition.far_mode, surface, e.t, e.x_minus, p)
            curvature = float(Lx @ flow.vector_field(self.condition.far_mode, e.t, e.x_minus, p)) + float(Lt)
            hx, ht, _ = flow.indicator_gradient(surface, e.t, e.x_minus, p)
            rate_a = float(hx @ flow.vector_field(e.mode_from, e.t, e.x_minus, p)) + float(ht)
            self._visibility[key] = curvature if rate_a > 0 else -curvature
        return self._visibility[key]

    def anchor_at(self, z: np.ndarray) -> None:
        """Move the arrival's time the condition looks near to a curve point ``z = (u, lam)``, before a location
        that starts there.

        Parameters
        ----------
        z : ndarray
            A point of the curve, in its layout.

        Raises
        ------
        SaltationError
            If the point's shot fails.
        """
        z = np.asarray(z, dtype=float)
        self.equations(z[:-1], float(z[-1]), need_lam=False)

    def kind_at(self, z: np.ndarray) -> SpecialPointKind:
        """The sliding bifurcation at a curve point ``z = (u, lam)``: crossing- or switching-sliding as the far
        field's tangency at the arrival is visible or not (:meth:`arrival_visibility`); adding-sliding on its
        curve.

        Parameters
        ----------
        z : ndarray
            A point of the curve, in its layout.

        Returns
        -------
        SpecialPointKind

        Raises
        ------
        SaltationError
            If the point's shot fails or the orbit no longer arrives there.
        """
        if self.adding:
            return SpecialPointKind.ADDING_SLIDING
        return SpecialPointKind.CROSSING_SLIDING if self.arrival_visibility(z) > 0 \
            else SpecialPointKind.SWITCHING_SLIDING

    def snapshot(self) -> dict:
        """The state that :meth:`accept` moves along a run, with the arrival's time.

        Returns
        -------
        dict
            As :meth:`_Curve.snapshot`, with the arrival's last time (crossing- and switching-sliding).
        """
        state = super().snapshot()
        if not self.adding:
            state["_arrival"] = self.condition.t_event
        return state

    def restore(self, state: dict) -> None:
        """Restore a :meth:`snapshot` before a run in the other direction (the arrival's time too).

        Parameters
        ----------
        state : dict
            What :meth:`snapshot` returned.
        """
        state = dict(state)
        t = state.pop("_arrival", None)
        if t is not None:
            self.condition.t_event = self.condition._t_last_eval = t
        super().restore(state)


class MultiplierCurve(_Curve):
    """Folds (``mu = 1``) or period doublings (``mu = -1``) of a forced orbit in two parameters.

    The condition is :class:`~saltation.orbits.conditions.MultiplierCondition`.

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the branch (forced, forward time).
    parameters : ndarray
        Parameter values at the start.
    second : str
        The parameter the curve is followed in.
    mu : float
        ``+1`` (fold) or ``-1`` (period doubling).
    h : float
        Relative step of the central differences of the test function.

    Raises
    ------
    ModelError
        For an autonomous or backward-time problem, or an unknown parameter.

    References
    ----------
    Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM (minimally
    augmented systems).
    """

    def __init__(self, problem: ShootingProblem, parameters: np.ndarray, second: str, *, mu: float, h: float = 1e-6):
        self.mu = float(mu)
        super().__init__(problem, [MultiplierCondition(mu, h=h)], parameters, problem.lam_name, second)


class NeimarkSackerCurve(_Curve):
    """Neimark-Sacker points of a forced orbit in two parameters.

    Periodicity plus :class:`~saltation.orbits.conditions.NeimarkSackerCondition`; the unknowns are
    ``(x0, lam1, kappa)``, ``kappa = cos theta`` of the pair ``exp(+-i theta)`` on the unit circle.  Where
    ``|kappa|`` passes 1 (a 1:1 or 1:2 resonance) the same system goes on as a neutral saddle.

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the branch (forced, forward time).
    parameters : ndarray
        Parameter values at the start.
    second : str
        The parameter the curve is followed in.
    kappa : float
        ``cos theta`` at the start (:func:`~saltation.orbits.conditions.neimark_sacker.nearest_pair_kappa`).
    h : float
        Relative step of the central differences of the conditions.

    Raises
    ------
    ModelError
        For an autonomous or backward-time problem, or an unknown parameter.
    SaltationError
        If ``|kappa| >= 1``: the start is a neutral saddle, not a Neimark-Sacker point.

    References
    ----------
    Kuznetsov (2004), *Elements of Applied Bifurcation Theory*, 3rd ed., Springer, section 10.3.
    """

    def __init__(self, problem: ShootingProblem, parameters: np.ndarray, second: str, *, kappa: float,
                 h: float = 1e-6):
        if not abs(kappa) < 1.0:
            raise SaltationError(f"kappa = {kappa:.10g}: the multipliers are a real pair with product 1 (a neutral "
                                 "saddle), not a Neimark-Sacker point")
        self.condition = NeimarkSackerCondition(kappa, h=h)
        super().__init__(problem, [self.condition], parameters, problem.lam_name, second)

    def snapshot(self) -> dict:
        """The state that :meth:`accept` moves along a run, with the condition's borders.

        Returns
        -------
        dict
            As :meth:`_Curve.snapshot`, with the condition's state.
        """
        return super().snapshot() | {"_ns": self.condition.state()}

    def restore(self, state: dict) -> None:
        """Restore a :meth:`snapshot` before a run in the other direction (the borders too).

        Parameters
        ----------
        state : dict
            What :meth:`snapshot` returned.
        """
        state = dict(state)
        self.condition.restore(state.pop("_ns"))
        super().restore(state)

    def reborder_at(self, z: np.ndarray) -> None:
        """Border the condition again at a curve point ``z = (u, lam)`` (before a location that starts there).

        Parameters
        ----------
        z : ndarray
            A point of the curve, in its layout.

        Raises
        ------
        SaltationError
            If the point's shot fails or the bordered matrix is singular there.
        """
        self.equations(z[:-1], float(z[-1]), need_lam=False)  # (the condition keeps its monodromy)
        self.condition.reborder(*self.condition.last)


__all__ = [
    "SLIDING_KINDS", "GrazingCurve", "Locus", "MultiplierCurve", "NeimarkSackerCurve", "SlidingCurve", "arrival_identity",
    "curve_stops", "follow_locus", "grazed_transitions", "run_curve",
]
