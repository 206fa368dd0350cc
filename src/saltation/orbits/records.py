"""The records a solved point of a problem leaves: its evaluation and its summary for a branch.

They sit below every problem (:mod:`saltation.orbits.shooting`, :mod:`saltation.orbits.conditions`) so
that each can build them, and the continuation engine reads them.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import numpy as np

from saltation.engine.flow import EventKind, SwitchingEvent, Trajectory
from saltation.kinds import SpecialPointKind
from saltation.orbits.floquet import is_stable


@dataclass(frozen=True)
class Evaluation:
    """Residual and Jacobians of a problem at ``(u, lam)``.

    ``bordered_tangent``, where the compiled corrector has solved it, is ``(row, t)`` with
    ``[[J_u, J_lam], [row]] t = e_last`` (``t`` not normalised): the tangent continuation computes next,
    when ``row`` is the tangent it corrected along (:meth:`saltation.branches.corrector.Corrector.tangent`).

    Attributes
    ----------
    residual : ndarray
        ``r(u, lam)``.
    jac_u : ndarray
        ``dr/du``.
    jac_lam : ndarray or None
        ``dr/dlam`` (None where it was not asked for).
    trajectory : Trajectory or None
        The shot behind the residual, where there is one.
    bordered_tangent : tuple of (ndarray, ndarray) or None
        ``(row, t)``, see above.
    """

    residual: np.ndarray
    jac_u: np.ndarray
    jac_lam: np.ndarray | None
    trajectory: Trajectory | None = None
    bordered_tangent: tuple[np.ndarray, np.ndarray] | None = None


@dataclass(frozen=True)
class BranchPoint:
    """A solved point: what a problem's ``describe`` returns and what a branch records, one record.

    Attributes
    ----------
    parameter : float
        Value of the continuation parameter (``nan`` where there is none).
    state : ndarray, shape (n,)
        Initial state of the periodic orbit (or the equilibrium).
    period : float
        Period (``nan`` for equilibria).
    amplitude : float
        ``max |x_1|`` over the period (the equilibrium's ``|x_1|``); see :func:`amplitude_measures`.
    half_peak_to_peak : float
        ``(max x_1 - min x_1) / 2`` (0 for equilibria).
    multipliers : ndarray, complex
        Forward-time Floquet multipliers (eigenvalues for equilibria).
    stable : bool
    event_labels : tuple of str
        The orbit's event sequence, readable (for display).
    step : float
        Arclength step that led to the point.
    iterations : int
        Newton iterations of the corrector.
    monodromy : ndarray or None
        The monodromy matrix (kept in memory for the detectors; not written to files).
    event_ids : tuple of (int, int, int)
        The event sequence by identity, ``(kind, transition, mode entered)`` each (:func:`event_ids`):
        what detectors compare, and what files store beside the labels.
    trivial_error : float
        Autonomous orbits: ``|M n - n|`` along the flow direction ``n``, the monodromy's accuracy figure.
    excursion : float
        ``max_i (max x_i - min x_i)`` over the period: how far the orbit moves (0 for an equilibrium).
    second_parameter : float
        On a two-parameter curve of special points: the value of the second parameter (``nan`` on a
        one-parameter branch).
    mode0 : str or None
        The mode the orbit is in at ``state`` (where its shooting starts); None for an equilibrium, and
        in files written before it was recorded.
    t0 : float
        The time at which the orbit passes ``state``: a forced orbit's section, which a branch moves off an
        event where one reaches it (:meth:`~saltation.orbits.shooting.ShootingProblem.move_section`); 0 for
        autonomous orbits and equilibria, and in files written before it was recorded.
    curve_kind : SpecialPointKind or None
        On a two-parameter curve of non-smooth points: the kind of the special point this curve point
        is, classified from its one-sided limits (it may change along the curve); None elsewhere.
    measures : dict of str to float
        The measures the branch was computed with (:mod:`saltation.orbits.measures`), by their text
        (``{"norm": 1.02}``); empty where none was asked for.
    """

    parameter: float
    state: np.ndarray
    period: float
    amplitude: float
    half_peak_to_peak: float
    multipliers: np.ndarray
    stable: bool
    event_labels: tuple[str, ...]
    step: float = 0.0
    iterations: int = 0
    monodromy: np.ndarray | None = field(default=None, repr=False, compare=False)
    event_ids: tuple[tuple[int, int, int], ...] = ()
    trivial_error: float = float("nan")
    excursion: float = float("nan")
    second_parameter: float = float("nan")
    mode0: str | None = None
    t0: float = 0.0
    curve_kind: SpecialPointKind | None = None
    measures: dict[str, float] = field(default_factory=dict)

    def recorded(self, parameter: float, step: float, iterations: int) -> BranchPoint:
        """This point as a branch records it: with its parameter, the step that led to it and the corrector's
        iterations (``dataclasses.replace``, without its per-call field checks: this runs for every point).

        Parameters
        ----------
        parameter : float
            Value of the continuation parameter.
        step : float
            Arclength step that led to the point.
        iterations : int
            Newton iterations of the corrector.

        Returns
        -------
        BranchPoint
            A new record; this one is unchanged.
        """
        point = copy.copy(self)
        object.__setattr__(point, "parameter", parameter)  # (a fresh copy: the record itself stays frozen)
        object.__setattr__(point, "step", step)
        object.__setattr__(point, "iterations", iterations)
        return point

    def __repr__(self) -> str:
        where = f"{self.parameter:.10g}" + ("" if not math.isfinite(self.second_parameter) else f", {self.second_parameter:.10g}")
        mu = ", ".join(f"{abs(m):.4g}" for m in np.asarray(self.multipliers)[:4])
        return (f"BranchPoint(at {where}, T={self.period:.8g}, amplitude={self.amplitude:.6g}, "
                f"{'stable' if self.stable else 'unstable'}, |mu|=[{mu}], events={'/'.join(self.event_labels) or '-'})")


#: The name of :class:`BranchPoint` where a problem describes a solved point (before a branch records it).
SolutionSummary = BranchPoint


def amplitude_measures(traj: Trajectory) -> dict[str, float]:
    """The amplitude measures of an orbit's period, computed in one place: ``amplitude = max |x_1|``,
    ``half_peak_to_peak = (max x_1 - min x_1) / 2`` and ``excursion = max_i (max x_i - min x_i)``.

    Parameters
    ----------
    traj : Trajectory
        One period of the orbit.

    Returns
    -------
    dict of str to float
        ``amplitude``, ``half_peak_to_peak`` and ``excursion``.
    """
    lo, hi = traj.x_min.tolist(), traj.x_max.tolist()  # plain floats: this runs for every branch point
    return {
        "amplitude": max(abs(hi[0]), abs(lo[0])),
        "half_peak_to_peak": 0.5 * (hi[0] - lo[0]),
        "excursion": max(map(float.__sub__, hi, lo)),
    }


def orbit_events(traj: Trajectory) -> list:
    """The events of a periodic orbit's trajectory, as the orbit's cycle of events.

    An orbit that is sliding at ``t0`` starts its sliding motion there (an
    event at ``t0``) and ends the period on it: that is one sliding motion cut
    by the section ``t = t0``, counted once (by its arrival at the end), so
    that the sequence of an orbit does not change as its events pass ``t0``.

    Parameters
    ----------
    traj : Trajectory
        One period of the orbit.

    Returns
    -------
    list of SwitchingEvent
        The orbit's cycle of events.
    """
    events = traj.events
    if (events and events[0].kind == EventKind.SLIDING_START and events[0].t == traj.t0 and traj.sliding_at_end
            and any(e.kind == EventKind.SLIDING_START and e.surface == events[0].surface for e in events[1:])):
        return events[1:]
    return events


#: the event kind of :func:`event_ids`' one entry for an orbit without events: it stays in one mode
STAYS_IN_MODE = -1


def event_ids(traj: Trajectory) -> tuple[tuple[int, int, int], ...]:
    """The orbit's events by identity: ``(kind, transition index, mode entered)`` each.

    Two transitions that differ only in their guard (or reset) have the same
    label but not the same index; a sliding motion's end is told by the mode
    it leaves into.  Detectors of non-smooth points compare these.  An orbit without events is
    ``((STAYS_IN_MODE, -1, mode),)``: two such orbits in different modes (a whirl inside its clearance
    and one in contact all round) differ, so that the change between them is located like any other.

    Parameters
    ----------
    traj : Trajectory
        One period of the orbit.

    Returns
    -------
    tuple of (int, int, int)
        One identity per event of the cycle.
    """
    ids = tuple((kind, transition, mode_to) for kind, transition, _, _, mode_to in _orbit_event_rows(traj))
    if ids:
        return _chatter_as_one(traj.system, ids)
    return ((STAYS_IN_MODE, -1, list(traj.system.mode_names).index(traj.mode0)),)


def _chatter_as_one(system, ids: tuple) -> tuple:
    """``ids`` with each run of equal impacts that ends in the entry into a stuck mode (complete chatter:
    :mod:`saltation.engine.chatter`) kept once.  How many of its infinitely many impacts the integrator
    resolved before it jumped to their accumulation point depends on the tolerance and the parameters, not
    on the orbit: counted, it would make a change of the event sequence at every step of a branch."""
    stuck = getattr(system, "sticking", None)
    if not stuck:
        return ids
    names = list(system.mode_names)
    stuck_modes = {names.index(name) for name in stuck if name in names}
    n = len(ids)
    drop = set()
    for j, (kind, _, mode_to) in enumerate(ids):
        if mode_to not in stuck_modes or n < 3:
            continue
        impact = ids[(j - 1) % n]
        i = (j - 2) % n
        while i != j and ids[i] == impact and i not in drop and (i + 1) % n != j:
            drop.add(i)
            i = (i - 1) % n
    return tuple(e for k, e in enumerate(ids) if k not in drop)


def event_labels(traj: Trajectory) -> tuple[str, ...]:
    """Readable labels of a trajectory's events (see :func:`orbit_events`): the transition, or the sliding
    motion started or ended.

    Parameters
    ----------
    traj : Trajectory
        One period of the orbit.

    Returns
    -------
    tuple of str
        One label per event of the cycle.
    """
    sys_ = traj.system
    names, surfaces = sys_.mode_names, sys_.surface_names
    labels = []
    for kind, transition, surface, mode_from, mode_to in _orbit_event_rows(traj):
        if kind == EventKind.TRANSITION:
            labels.append(sys_.transitions[transition].label)
        elif kind == EventKind.SLIDING_START:
            labels.append(f"slide on {surfaces[surface]} ({names[mode_from]}|{names[mode_to]})")
        else:
            labels.append(f"leave {surfaces[surface]} sliding -> {names[mode_to]}")
    return tuple(labels)


def _orbit_event_rows(traj: Trajectory) -> list[list[int]]:
    """:func:`orbit_events` as rows ``(kind, transition, surface, mode from, mode to)`` of the
    trajectory's event log (plain integers, without building the events: this runs for every branch
    point)."""
    rows = traj.event_rows()
    if (rows and rows[0][0] == EventKind.SLIDING_START and traj.first_logged.t == traj.t0 and traj.sliding_at_end
            and any(r[0] == EventKind.SLIDING_START and r[2] == rows[0][2] for r in rows[1:])):
        return rows[1:]
    return rows


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic solution found by shooting.

    Attributes
    ----------
    system_name : str
        Name of the model.
    state0 : ndarray, shape (n,)
        State at ``t0`` on the orbit.
    period : float
        The period (a forced orbit's is its forcing period).
    t0 : float
        Initial time (a forced orbit's phase of the forcing).
    backward : bool
        Whether the orbit was computed in backward time.
    autonomous : bool
        Whether the model is autonomous.
    parameters : ndarray
        Parameter values.
    monodromy : ndarray, shape (n, n)
        Monodromy in the direction of integration.
    multipliers : ndarray, complex
        Forward-time Floquet multipliers (``inf`` for an infinitely unstable direction).
    trajectory : Trajectory
        One period, with its events.
    converged : bool
        Whether Newton converged.
    iterations : int
        Newton iterations.
    residual_norm : float
        Norm of the last residual.
    residuals : list of float
        Newton residual history.
    trivial_error : float
        Autonomous orbits: ``|M n - n|`` along the unit velocity ``n`` (see
        :func:`saltation.orbits.floquet.autonomous_multipliers`), at most
        :data:`TRIVIAL_MULTIPLIER_ACCURACY`; ``nan`` for forced orbits.  By multiple shooting, the
        largest ``|Phi_i f(x_i) - f(x_(i+1))| / |f(x_(i+1))|`` over the segments.
    problem : ShootingProblem or None
        The shooting problem that found it (its flow, tolerances and section): what
        :func:`saltation.special_points.continuation.continue_orbit` follows.
    segments : int
        The number of shooting segments (1: single shooting).
    nodes : ndarray, shape (segments, n), or None
        The segments' initial states (multiple shooting); the first is ``state0``.
    mode0 : str or None
        The mode the orbit is in at ``state0``: the one its shooting started in (named by ``mode0`` of
        :func:`find_periodic_orbit`, or the model's initial-mode rule).  None in records made without it.
    """

    system_name: str
    state0: np.ndarray
    period: float
    t0: float
    backward: bool
    autonomous: bool
    parameters: np.ndarray
    monodromy: np.ndarray
    multipliers: np.ndarray
    trajectory: Trajectory
    converged: bool
    iterations: int
    residual_norm: float
    residuals: list[float] = field(default_factory=list)
    trivial_error: float = float("nan")
    #: the shooting problem that found it (its flow, tolerances and section): what
    #: :func:`saltation.special_points.continuation.continue_orbit` follows
    problem: object | None = field(default=None, repr=False, compare=False)  # a ShootingProblem
    #: the number of shooting segments (1: single shooting), and their initial states (multiple shooting)
    segments: int = 1
    nodes: np.ndarray | None = field(default=None, repr=False)
    #: the mode at ``state0`` (where the shooting starts)
    mode0: str | None = None

    @property
    def amplitude(self) -> float:
        """``max |x_1|`` over the period (:func:`~saltation.orbits.records.amplitude_measures`)."""
        return amplitude_measures(self.trajectory)["amplitude"]

    @property
    def half_peak_to_peak(self) -> float:
        """``(max x_1 - min x_1) / 2`` over the period (:func:`~saltation.orbits.records.amplitude_measures`)."""
        return amplitude_measures(self.trajectory)["half_peak_to_peak"]

    @property
    def backward_multipliers(self) -> np.ndarray:
        """Eigenvalues of the monodromy in the direction of integration."""
        return np.linalg.eigvals(self.monodromy)

    @property
    def stable(self) -> bool:
        return is_stable(self.multipliers, autonomous=self.autonomous)

    @property
    def trivial_multiplier_error(self) -> float:
        """How far the trivial multiplier can be from 1 (autonomous orbits): ``|M n - n|``, an accuracy figure."""
        return self.trivial_error

    @property
    def events(self) -> list[SwitchingEvent]:
        """The events of one period (as :attr:`Trajectory.events`)."""
        return self.trajectory.events

    @property
    def event_labels(self) -> tuple[str, ...]:
        """Readable labels of the orbit's cycle of events (see :func:`event_labels`)."""
        return event_labels(self.trajectory)

    def _repr_markdown_(self) -> str:
        """A summary for Jupyter (:mod:`saltation.summary`)."""
        from saltation.summary import orbit_summary

        return orbit_summary(self)

    def __repr__(self) -> str:
        state = ", ".join(f"{v:.6g}" for v in np.asarray(self.state0)[:6]) + (", ..." if len(self.state0) > 6 else "")
        mu = f"{np.max(np.abs(self.multipliers)):.6g}" if len(self.multipliers) else "-"
        how = ("backward" if self.backward else "forward") + (", autonomous" if self.autonomous else ", forced")
        mode = f" in {self.mode0!r}" if self.mode0 is not None else ""
        return (f"PeriodicOrbit({self.system_name!r}, T={self.period:.10g}, x0=[{state}]{mode}, max |mu|={mu}, "
                f"{'stable' if self.stable else 'unstable'}, {len(self.events)} events, {how}"
                + ("" if self.converged else ", NOT converged") + ")")


__all__ = ["STAYS_IN_MODE", "BranchPoint", "Evaluation", "PeriodicOrbit", "SolutionSummary", "amplitude_measures", "event_ids", "event_labels",
           "orbit_events"]
