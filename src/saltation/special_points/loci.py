"""Two-parameter curves (loci) of special points of periodic orbits.

A special point located on a branch in one parameter is continued in a
second one by pseudo-arclength continuation of its defining system, with the
first parameter as one more unknown:

* grazing and corner collisions (:class:`GrazingCurve`): periodicity of the
  virtual orbit plus tangency to the grazed surface
  (:func:`saltation.special_points.grazing.grazing_system`, exact Jacobians).  A corner of
  the paper's trilinear kind is a grazing of the contact's entry surface at
  the point where the contact force vanishes, so it is continued by the same
  system;
* crossing-, switching- and adding-sliding (:class:`SlidingCurve`):
  periodicity plus the tangency conditions of :mod:`saltation.special_points.sliding`;
* smooth folds and period doublings (:class:`MultiplierCurve`): periodicity
  plus a bordered test function ``g`` that vanishes where ``M - mu I`` is
  singular (``mu = +1`` or ``-1``), the minimally augmented system of Govaerts
  (*Numerical Bifurcation Analysis of Dynamical Systems*, SIAM 2000);
  derivatives of ``g`` by central differences.

Along a grazing or corner curve the kind of the non-smooth point (its
set-valued multipliers, classified as on a branch) is followed; where it
changes the curve carries a codimension-two point, labelled with both kinds
and located between two curve points (its ``accuracy`` is their distance).
Along a fold or period-doubling curve the orbit's event sequence is
followed; where it changes, the curve meets a corner or grazing there (a
fold born at a corner, a grazing that ends a fold curve), labelled with the
curve's kind and the non-smooth point's.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from saltation.special_points.detection import classify_nonsmooth
from saltation.orbits.boundary import saltation_at_corner
from saltation.branches.branch import SpecialPoint, SpecialPointKind, StopReason
from saltation.special_points.continuation import Continuation, ContinuationSettings, canonical_events
from saltation.errors import IntegrationError, ModelError, SaltationError
from saltation.orbits.floquet import is_stable, multipliers_from_monodromy
from saltation.special_points.grazing import grazing_candidates, grazing_system, locate_grazing, tangency_time
from saltation.engine.flow import EventKind, Flow
from saltation.orbits.shooting import Evaluation, ShootingProblem, SolutionSummary, event_ids
from saltation.special_points.sliding import exit_rate, rate_along

#: Special points continued by the defining systems of :mod:`saltation.special_points.sliding`.
SLIDING_KINDS = frozenset(
    {SpecialPointKind.CROSSING_SLIDING, SpecialPointKind.SWITCHING_SLIDING, SpecialPointKind.ADDING_SLIDING}
)


@dataclass
class Codim2Point:
    """A point of a curve where two conditions meet (the kind of the special point changes).

    Attributes
    ----------
    kinds : (str, str)
        The kinds on either side along the curve.
    values : (float, float)
        The two parameters there (the midpoint of the two curve points around it).
    accuracy : float
        Distance between those two curve points (in the two parameters).
    """

    kinds: tuple[str, str]
    values: tuple[float, float]
    accuracy: float

    def record(self) -> dict:
        return {
            "kind": f"{self.kinds[0]} -> {self.kinds[1]}",
            "value": [float(self.values[0]), float(self.values[1])],
            "accuracy": float(self.accuracy),
        }


@dataclass
class Locus:
    """A curve of special points in two parameters.

    Attributes
    ----------
    kind : SpecialPointKind
        The kind of the special point it started from.
    param, param2 : str
    points : ndarray, shape (m, 2)
        ``(value of param, value of param2)`` along the curve.
    states : ndarray, shape (m, n)
    stop_reason : str
        Why each direction stopped.
    special_points : list of Codim2Point
    kinds : list of str
        The kind of the special point at each curve point.
    """

    kind: SpecialPointKind
    param: str
    param2: str
    points: np.ndarray
    states: np.ndarray
    stop_reason: str
    special_points: list[Codim2Point] = field(default_factory=list)
    kinds: list[str] = field(default_factory=list)

    def record(self) -> dict:
        return {
            "points": [[float(a), float(b)] for a, b in self.points],
            "stop_reason": self.stop_reason,
            "special_points": [c.record() for c in self.special_points],
        }


class _CurveProblem:
    """What :class:`Continuation` needs of a problem: unknowns ``u = (x0, lam1)``, parameter ``lam2``."""

    def __init__(self, flow: Flow, parameters: np.ndarray, first: str, second: str):
        self.flow = flow
        self.system = flow.system
        self.p = np.asarray(parameters, dtype=float).copy()
        self.j1 = self.system.parameter_index(first)
        self.lam_index = self.system.parameter_index(second)
        self.lam_name = second
        self.first = first
        self.backward = False
        self.autonomous = self.system.is_autonomous
        if self.autonomous:
            raise ModelError(f"two-parameter curves are implemented for forced models; {self.system.name!r} is autonomous")

    def parameters_at(self, u: np.ndarray, lam: float) -> np.ndarray:
        p = self.p.copy()
        p[self.j1] = u[-1]
        p[self.lam_index] = lam
        return p

    def lam0(self) -> float:
        return float(self.p[self.lam_index])

    def accept(self, u: np.ndarray, lam: float) -> None:
        """Nothing to re-anchor by default."""

    def snapshot(self) -> dict:
        """The state that :meth:`accept` moves along a run (restored before a run in the other direction)."""
        return {}

    def restore(self, state: dict) -> None:
        for key, value in state.items():
            setattr(self, key, list(value) if isinstance(value, list) else value)  # each run its own lists

    def _summary(self, u: np.ndarray, monodromy: np.ndarray, period: float, traj) -> SolutionSummary:
        mu = multipliers_from_monodromy(monodromy)
        return SolutionSummary(
            state=np.array(u[:-1]), period=period, amplitude=float(max(abs(traj.x_max[0]), abs(traj.x_min[0]))),
            half_peak_to_peak=float(0.5 * (traj.x_max[0] - traj.x_min[0])), multipliers=mu,
            stable=is_stable(mu, autonomous=False), event_labels=(), monodromy=monodromy,
        )


class GrazingCurve(_CurveProblem):
    """Grazings (and corners) of a forced orbit in two parameters.

    Parameters
    ----------
    flow : Flow
    parameters : ndarray
        Parameter values at the start.
    first, second : str
        The parameter of the branch (an unknown here) and the one the curve is followed in.
    transition : int
        The transition whose surface is grazed.
    t_guess : float
        Instant of tangency at the start.
    """

    def __init__(self, flow: Flow, parameters: np.ndarray, first: str, second: str, transition: int, t_guess: float,
                 *, t0: float = 0.0, tolerances=None, others: Sequence[tuple[int, float]] = ()):
        super().__init__(flow, parameters, first, second)
        self.transition = int(transition)
        self.t_guess = float(t_guess)
        self.others = [(int(k), float(t)) for k, t in others]  # touched at the same time (by symmetry): passed too
        self.kinds: list[str] = []  # the corner's kind at every accepted point
        self.t_start = float(t_guess)  # the others' touches keep their offsets from the first one's, in periods
        self.period_start = self.system.forcing_period(self.p)
        self.t0 = float(t0)
        self.tolerances = tolerances
        self._last = None

    @property
    def dimension(self) -> int:
        return self.system.n + 1

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        n = self.system.n
        p = self.parameters_at(u, self.lam0() if lam is None else lam)
        gs = grazing_system(self.flow, u[:n], p, self.transition, self.t_guess, (self.j1, self.lam_index), t0=self.t0,
                            tolerances=self.tolerances, also_disabled=[k for k, _ in self.others])
        self._last = gs
        jac_u = np.column_stack([gs.jac_x, gs.jac_p[:, 0]])
        return Evaluation(residual=gs.residual, jac_u=jac_u, jac_lam=gs.jac_p[:, 1].copy(), trajectory=gs.trajectory)

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> SolutionSummary:
        gs = self._last
        return self._summary(u, gs.monodromy, gs.period, gs.trajectory)

    def accept(self, u: np.ndarray, lam: float) -> None:
        if self._last is not None:  # the accepted point's own evaluation (the corrector's last)
            self.t_guess = self._last.t_graze
            self.kinds.append(self.corner_kind(u, lam, self.t_guess, gs=self._last))

    def snapshot(self) -> dict:
        return {"t_guess": self.t_guess, "_last": None, "kinds": []}

    def corner_kind(self, u: np.ndarray, lam: float, t_guess: float, *, gs=None) -> str:
        """The kind of the non-smooth point at a curve point (``gs``: its grazing system, if evaluated).

        The set-valued multipliers between the grazing orbit's monodromy and the
        same with the excursion's saltation matrices inserted, classified as on a
        branch; ``grazing`` when those saltation matrices are unbounded there.
        """
        n = self.system.n
        p = self.parameters_at(u, lam)
        disabled = [self.transition] + [k for k, _ in self.others]
        if gs is None:
            gs = grazing_system(self.flow, u[:n], p, self.transition, t_guess, (self.j1,), t0=self.t0,
                                tolerances=self.tolerances, also_disabled=disabled[1:])
        product = np.eye(n)
        stretch = gs.period / self.period_start
        touches = [(self.transition, gs.t_graze)] + [(k, gs.t_graze + (t - self.t_start) * stretch) for k, t in self.others]
        for k, t_k in sorted(touches, key=lambda kt: kt[1]):
            if k != self.transition:
                surface = self.system.surface_index(self.system.transitions[k].surface)
                t_k = tangency_time(self.flow, u[:n], self.t0, p, surface, t_k, gs.period, disabled=disabled,
                                    tolerances=self.tolerances)
                if t_k is None:
                    raise SaltationError(f"the second touch of transition {k} was lost along the curve")
            to_k = self.flow.run(u[:n], self.t0, t_k, p, variational=True, disabled=disabled, tolerances=self.tolerances)
            P = saltation_at_corner(self.system, self._excursion(k, t_k, to_k.x1, p), t_k, to_k.x1, p)
            if P is None or not np.linalg.norm(P) < 1e8:
                return SpecialPointKind.GRAZING.value
            phi = to_k.monodromy
            product = np.linalg.solve(phi, P @ phi) @ product
        return classify_nonsmooth(gs.monodromy, gs.monodromy @ product).kind.value

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

    Raises
    ------
    SaltationError
        If the orbit touches no surface of a transition of its modes.
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
    problem: ShootingProblem,
    point: SpecialPoint,
    second: str,
    bounds: tuple[float, float],
    *,
    settings: ContinuationSettings | None = None,
    progress: Callable | None = None,
) -> Locus:
    """Continue a special point of a branch in a second parameter, in both directions.

    Parameters
    ----------
    problem : ShootingProblem
        The problem of the branch (forced, forward time, its continuation parameter set).
    point : SpecialPoint
        A grazing or a non-smooth point (corner) of that branch, or a fold or period doubling.
    second : str
        The second parameter.
    bounds : (float, float)
        The range of the second parameter.

    Raises
    ------
    ModelError
        For an autonomous or backward-time problem, or a kind without a defining system here.
    """
    if problem.autonomous or problem.backward or problem.periods != 1:
        raise ModelError("two-parameter curves are implemented for forced models in forward time, over one forcing period")
    p = problem.parameters_at(point.parameter)
    u0 = np.append(np.asarray(point.state, dtype=float), point.parameter)
    if point.kind in SLIDING_KINDS:
        curve = SlidingCurve(problem, p, second, point)
        u0 = curve.start(np.asarray(point.state, dtype=float), point.parameter)
        classify = False
    elif point.kind.is_nonsmooth:
        (transition, t_g), *others = grazed_transitions(problem.flow, point.state, p, t0=problem.t0,
                                                        tolerances=problem.tolerances)
        curve = GrazingCurve(problem.flow, p, problem.lam_name, second, transition, t_g, t0=problem.t0,
                             tolerances=problem.tolerances, others=others)
        classify = True
    elif point.kind in (SpecialPointKind.FOLD, SpecialPointKind.PERIOD_DOUBLING):
        curve = MultiplierCurve(problem, p, second, mu=1.0 if point.kind is SpecialPointKind.FOLD else -1.0)
        classify = False
    else:
        raise ModelError(f"no two-parameter continuation for special points of kind {point.kind.value}")
    settings = settings or ContinuationSettings(bounds=bounds)
    # the curve's own turning points and the multipliers of its orbits are not special points of the curve
    settings = replace(settings, bounds=bounds, detect=False)
    lam0 = float(p[curve.lam_index])
    runs, reasons, kinds_by_run, events_by_run, ends = [], [], [], [], []
    start = curve.snapshot()
    for direction in (1, -1):
        curve.restore(start)  # each direction starts from the special point's own guesses
        cont = Continuation(curve, settings)
        for pt in cont.run(u0, lam0, direction=direction):
            if progress is not None:
                progress(pt)
        runs.append([sol.z.copy() for sol in cont.solutions])
        kinds_by_run.append(list(getattr(curve, "kinds", [])))
        reasons.append(f"{'increasing' if direction > 0 else 'decreasing'} {second}: {cont.branch.stop_reason.value}")
        events_by_run.append(list(getattr(curve, "event_ids", [])))
        if not classify and cont.branch.stop_reason is not StopReason.PARAMETER_BOUND:
            end = _end_at_a_corner(problem, curve, point.kind, runs[-1])
            if end is not None:
                ends.append(end)
    zs = list(reversed(runs[1]))[:-1] + runs[0]
    n = problem.system.n
    points = np.array([[z[n], z[-1]] for z in zs])
    locus = Locus(kind=point.kind, param=problem.lam_name, param2=second, points=points,
                  states=np.array([z[:n] for z in zs]), stop_reason="; ".join(reasons))
    if classify:
        locus.kinds = list(reversed(kinds_by_run[1]))[:-1] + kinds_by_run[0]
        for a in range(len(zs) - 1):
            if locus.kinds[a] != locus.kinds[a + 1]:
                mid = 0.5 * (points[a] + points[a + 1])
                locus.special_points.append(Codim2Point(
                    kinds=(locus.kinds[a], locus.kinds[a + 1]), values=(float(mid[0]), float(mid[1])),
                    accuracy=float(np.linalg.norm(points[a + 1] - points[a])),
                ))
    events = list(reversed(events_by_run[1]))[:-1] + events_by_run[0]
    if not classify and len(events) == len(zs):  # (curves that follow their orbits' event sequences)
        for a in range(len(zs) - 1):
            if events[a] != events[a + 1]:
                touch = _touch_kind(problem, curve, zs[a] if len(events[a]) <= len(events[a + 1]) else zs[a + 1])
                mid = 0.5 * (points[a] + points[a + 1])
                locus.special_points.append(Codim2Point(
                    kinds=(point.kind.value, touch), values=(float(mid[0]), float(mid[1])),
                    accuracy=float(np.linalg.norm(points[a + 1] - points[a])),
                ))
    locus.special_points.extend(ends)
    return locus


def _end_at_a_corner(problem: ShootingProblem, curve: _CurveProblem, kind: SpecialPointKind,
                     zs: list[np.ndarray], *, gap: float = 1e-3, last: int = 12) -> Codim2Point | None:
    """Where a fold or period-doubling curve stops short of its bounds because its orbit comes to touch a
    switching surface (a segment of the orbit shrinks to nothing: a smooth fold born at a corner), the
    curve ends on the corner curve.  Of its last points, the one whose orbit comes nearest to a surface
    (within ``gap`` of the state's size) is taken; the corner at its value of the second parameter is
    located by the grazing defining system in the first.  That corner is the label's position, and the
    distance from the curve point to it the label's accuracy."""
    n = problem.system.n
    best = None
    for z in zs[-last:]:
        p = curve.parameters_at(z[:-1], z[-1])
        try:
            (transition, t_g), *_ = grazed_transitions(problem.flow, z[:n], p, t0=problem.t0,
                                                       tolerances=problem.tolerances)
            surface = problem.system.transitions[transition].surface
            x = problem.flow.run(z[:n], problem.t0, t_g, p, tolerances=problem.tolerances).x1
        except SaltationError:
            continue
        g = abs(problem.flow.indicator(surface, t_g, x, p)) / (1.0 + float(np.linalg.norm(x)))
        if g <= gap and (best is None or g < best[0]):
            best = (g, z, p, transition, t_g)
    if best is None:
        return None
    _, z, p, transition, t_g = best
    try:
        corner = locate_grazing(problem.flow, z[:n], float(z[n]), problem.lam_name, transition, t_g, parameters=p,
                                t0=problem.t0, tolerances=problem.tolerances)
    except SaltationError:
        return None
    at = np.concatenate([corner.state0, [corner.parameter, z[-1]]])
    return Codim2Point(kinds=(kind.value, _touch_kind(problem, curve, at)), values=(corner.parameter, float(z[-1])),
                       accuracy=abs(corner.parameter - float(z[n])))


def _touch_kind(problem: ShootingProblem, curve: _CurveProblem, z: np.ndarray) -> str:
    """The kind of the non-smooth point a curve's orbit meets where its event sequence changes (a smooth
    fold born at a corner, a fold curve ended by a grazing): classified at the curve point on the side
    without the extra events, as on a corner curve; ``"nonsmooth"`` when that fails."""
    n = problem.system.n
    p = curve.parameters_at(z[:-1], z[-1])
    try:
        (transition, t_g), *others = grazed_transitions(problem.flow, z[:n], p, t0=problem.t0,
                                                        tolerances=problem.tolerances)
        corner = GrazingCurve(problem.flow, p, problem.lam_name, curve.lam_name, transition, t_g, t0=problem.t0,
                              tolerances=problem.tolerances, others=others)
        return corner.corner_kind(z[: n + 1], z[-1], t_g)
    except SaltationError:
        return "nonsmooth"


class SlidingCurve(_CurveProblem):
    """Crossing-, switching- or adding-sliding bifurcations of a forced orbit in two parameters.

    Periodicity plus the conditions of :mod:`saltation.special_points.sliding`: the far
    field's tangency where the orbit arrives at the surface (crossing- and
    switching-sliding; unknowns ``(x0, lam1)``), or the exit field's cubic
    tangency at an instant ``tau`` of a sliding motion (adding-sliding;
    unknowns ``(x0, lam1, tau)``).  The conditions' derivatives are taken by
    central differences.  The arrival followed is the one on the surface
    nearest in time to the last accepted touch.
    """

    def __init__(self, problem: ShootingProblem, parameters: np.ndarray, second: str, point: SpecialPoint,
                 *, h: float = 1e-7):
        super().__init__(problem.flow, parameters, problem.lam_name, second)
        if not point.touch_surface:
            raise ModelError(f"the {point.kind.value} point does not say where the orbit touches the surface")
        self.shooting = problem
        self.adding = point.kind is SpecialPointKind.ADDING_SLIDING
        self.surface, self.mode, self.t_touch = point.touch_surface, point.touch_mode, float(point.touch_time)
        self.h = float(h)
        self._last = None

    @property
    def dimension(self) -> int:
        return self.system.n + (2 if self.adding else 1)

    def parameters_at(self, u: np.ndarray, lam: float) -> np.ndarray:
        p = self.p.copy()
        p[self.j1] = u[self.system.n]
        p[self.lam_index] = lam
        return p

    def start(self, state: np.ndarray, lam1: float) -> np.ndarray:
        """The unknowns at the special point."""
        return np.concatenate([state, [lam1], [self.t_touch] if self.adding else []])

    def _conditions(self, u: np.ndarray, lam: float) -> tuple[np.ndarray, float]:
        n = self.system.n
        p = self.parameters_at(u, lam)
        t0, tol = self.shooting.t0, self.shooting.tolerances
        if self.adding:
            tau = float(u[n + 1])
            x = self.flow.run(u[:n], t0, tau, p, tolerances=tol).x1

            def g(s, y):
                return exit_rate(self.flow, self.mode, self.surface, s, y, p)

            return np.array([g(tau, x), rate_along(self.flow, self.mode, g, tau, x, p)]), tau
        traj = self.flow.run(u[:n], t0, t0 + self.system.forcing_period(p), p, tolerances=tol)
        arrivals = [e for e in traj.events if e.surface == self.surface
                    and e.kind in (EventKind.TRANSITION, EventKind.SLIDING_START)]
        if not arrivals:
            raise SaltationError(f"the orbit no longer arrives at surface {self.surface!r}")
        period = self.system.forcing_period(p)

        def distance(a):  # in time, modulo the period (the arrival may pass the section t = t0)
            d = (a.t - self.t_touch) % period
            return min(d, period - d)

        e = min(arrivals, key=distance)
        return np.array([exit_rate(self.flow, self.mode, e.surface, e.t, e.x_minus, p)]), e.t

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        n, m = self.system.n, self.dimension
        lam = self.lam0() if lam is None else lam
        p = self.parameters_at(u, lam)
        T = self.system.forcing_period(p)
        t0, tol = self.shooting.t0, self.shooting.tolerances
        traj1 = self.flow.run(u[:n], t0, t0 + T, p, variational=True, sensitivity=self.j1, tolerances=tol)
        traj2 = self.flow.run(u[:n], t0, t0 + T, p, variational=True, sensitivity=self.lam_index, tolerances=tol)
        c, t_touch = self._conditions(u, lam)
        residual = np.concatenate([traj1.x1 - u[:n], c])
        jac_u = np.zeros((m, m))
        jac_u[:n, :n] = traj1.monodromy - np.eye(n)
        jac_u[:n, n] = traj1.parameter_sensitivity + self.system.period_derivative(p, self.j1) * traj1.velocity_end
        jac_lam = np.zeros(m)
        jac_lam[:n] = traj2.parameter_sensitivity + self.system.period_derivative(p, self.lam_index) * traj2.velocity_end
        for i in range(m + 1):  # the conditions' derivatives, by central differences
            z = np.append(u, lam)
            step = self.h * max(1.0, abs(z[i]))
            e = np.zeros(m + 1)
            e[i] = step
            d = (self._conditions((z + e)[:m], (z + e)[m])[0] - self._conditions((z - e)[:m], (z - e)[m])[0]) / (2 * step)
            if i < m:
                jac_u[n:, i] = d
            else:
                jac_lam[n:] = d
        self._last = (traj1.monodromy, T, traj1, t_touch)
        return Evaluation(residual=residual, jac_u=jac_u, jac_lam=jac_lam, trajectory=traj1)

    def accept(self, u: np.ndarray, lam: float) -> None:
        if self._last is not None:
            self.t_touch = self._last[3]

    def snapshot(self) -> dict:
        return {"t_touch": self.t_touch, "_last": None}

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> SolutionSummary:
        M, T, traj, _ = self._last
        return self._summary(u[: self.system.n + 1], M, T, traj)


class MultiplierCurve(_CurveProblem):
    """Folds (``mu = 1``) or period doublings (``mu = -1``) of a forced orbit in two parameters.

    The test function ``g`` solves the bordered system
    ``[[M - mu I, b], [c^T, 0]] [v; g] = [0; 1]``, with ``b`` and ``c`` the
    singular vectors of ``M - mu I`` at the start (kept fixed): ``g = 0``
    exactly where ``M - mu I`` is singular, and ``g`` is a smooth function of
    the unknowns.  Its derivatives are taken by central differences.
    """

    def __init__(self, problem: ShootingProblem, parameters: np.ndarray, second: str, *, mu: float, h: float = 1e-6):
        super().__init__(problem.flow, parameters, problem.lam_name, second)
        self.shooting = problem
        self.mu = float(mu)
        self.h = float(h)
        self._border: tuple[np.ndarray, np.ndarray] | None = None  # b, c: fixed at the first evaluation
        self._last = None
        self.event_ids: list[tuple] = []  # the orbit's event sequence (by identity) at every accepted point

    @property
    def dimension(self) -> int:
        return self.system.n + 1

    def _shot(self, x0: np.ndarray, p: np.ndarray, j: int):
        T = self.system.forcing_period(p)
        traj = self.flow.run(x0, self.shooting.t0, self.shooting.t0 + T, p, variational=True, sensitivity=j,
                             tolerances=self.shooting.tolerances)
        return traj, T

    def _g(self, M: np.ndarray) -> float:
        n = M.shape[0]
        A = M - self.mu * np.eye(n)
        if self._border is None:
            U, _, Vt = np.linalg.svd(A)
            self._border = (U[:, -1].copy(), Vt[-1].copy())
        b, c = self._border
        B = np.zeros((n + 1, n + 1))
        B[:n, :n] = A
        B[:n, n] = b
        B[n, :n] = c
        rhs = np.zeros(n + 1)
        rhs[n] = 1.0
        return float(np.linalg.solve(B, rhs)[n])

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        n = self.system.n
        lam = self.lam0() if lam is None else lam
        p = self.parameters_at(u, lam)
        traj1, T = self._shot(u[:n], p, self.j1)
        traj2, _ = self._shot(u[:n], p, self.lam_index)
        M = traj1.monodromy
        residual = np.append(traj1.x1 - u[:n], self._g(M))
        jac_u = np.zeros((n + 1, n + 1))
        jac_u[:n, :n] = M - np.eye(n)
        jac_u[:n, n] = traj1.parameter_sensitivity + self.system.period_derivative(p, self.j1) * traj1.velocity_end
        jac_lam = np.zeros(n + 1)
        jac_lam[:n] = traj2.parameter_sensitivity + self.system.period_derivative(p, self.lam_index) * traj2.velocity_end
        z = np.append(u, lam)
        for i in range(n + 2):  # the test function's derivatives, by central differences
            step = self.h * max(1.0, abs(z[i]))
            e = np.zeros(n + 2)
            e[i] = step
            gp = self._g(self._monodromy(z + e))
            gm = self._g(self._monodromy(z - e))
            d = (gp - gm) / (2 * step)
            if i <= n:
                jac_u[n, i] = d
            else:
                jac_lam[n] = d
        self._last = (M, T, traj1)
        return Evaluation(residual=residual, jac_u=jac_u, jac_lam=jac_lam, trajectory=traj1)

    def accept(self, u: np.ndarray, lam: float) -> None:
        if self._last is not None:
            self.event_ids.append(canonical_events(event_ids(self._last[2])))

    def snapshot(self) -> dict:
        return {"_last": None, "event_ids": []}

    def _monodromy(self, z: np.ndarray) -> np.ndarray:
        n = self.system.n
        p = self.parameters_at(z[: n + 1], z[n + 1])
        return self._shot(z[:n], p, -1)[0].monodromy

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> SolutionSummary:
        M, T, traj = self._last
        return self._summary(u, M, T, traj)


__all__ = [
    "SLIDING_KINDS", "Codim2Point", "GrazingCurve", "Locus", "MultiplierCurve", "SlidingCurve", "follow_locus",
    "grazed_transitions",
]
