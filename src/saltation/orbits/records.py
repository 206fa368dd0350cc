"""The records a solved point of a problem leaves: its evaluation and its summary for a branch.

They sit below every problem (:mod:`saltation.orbits.shooting`, :mod:`saltation.orbits.conditions`) so
that each can build them, and the continuation engine reads them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from saltation.engine.flow import EventKind, Trajectory


@dataclass(frozen=True)
class Evaluation:
    """Residual and Jacobians of a problem at ``(u, lam)``."""

    residual: np.ndarray
    jac_u: np.ndarray
    jac_lam: np.ndarray | None
    trajectory: Trajectory | None = None


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

    def __repr__(self) -> str:
        where = f"{self.parameter:.10g}" + ("" if not math.isfinite(self.second_parameter) else f", {self.second_parameter:.10g}")
        mu = ", ".join(f"{abs(m):.4g}" for m in np.asarray(self.multipliers)[:4])
        return (f"BranchPoint(at {where}, T={self.period:.8g}, amplitude={self.amplitude:.6g}, "
                f"{'stable' if self.stable else 'unstable'}, |mu|=[{mu}], events={'/'.join(self.event_labels) or '-'})")


#: The name of :class:`BranchPoint` where a problem describes a solved point (before a branch records it).
SolutionSummary = BranchPoint


def amplitude_measures(traj: Trajectory) -> dict[str, float]:
    """The amplitude measures of an orbit's period, computed in one place: ``amplitude = max |x_1|``,
    ``half_peak_to_peak = (max x_1 - min x_1) / 2`` and ``excursion = max_i (max x_i - min x_i)``."""
    lo, hi = traj.x_min, traj.x_max
    return {
        "amplitude": float(max(abs(hi[0]), abs(lo[0]))),
        "half_peak_to_peak": float(0.5 * (hi[0] - lo[0])),
        "excursion": float(np.max(hi - lo)),
    }


def orbit_events(traj: Trajectory) -> list:
    """The events of a periodic orbit's trajectory, as the orbit's cycle of events.

    An orbit that is sliding at ``t0`` starts its sliding motion there (an
    event at ``t0``) and ends the period on it: that is one sliding motion cut
    by the section ``t = t0``, counted once (by its arrival at the end), so
    that the sequence of an orbit does not change as its events pass ``t0``.
    """
    events = traj.events
    if (events and events[0].kind == EventKind.SLIDING_START and events[0].t == traj.t0 and traj.sliding_at_end
            and any(e.kind == EventKind.SLIDING_START and e.surface == events[0].surface for e in events[1:])):
        return events[1:]
    return events


def event_ids(traj: Trajectory) -> tuple[tuple[int, int, int], ...]:
    """The orbit's events by identity: ``(kind, transition index, mode entered)`` each.

    Two transitions that differ only in their guard (or reset) have the same
    label but not the same index; a sliding motion's end is told by the mode
    it leaves into.  Detectors of non-smooth points compare these.
    """
    names = traj.system.mode_names
    return tuple((int(e.kind), int(e.transition), names.index(e.mode_to)) for e in orbit_events(traj))


def event_labels(traj: Trajectory) -> tuple[str, ...]:
    """Readable labels of a trajectory's events (see :func:`orbit_events`): the transition, or the sliding
    motion started or ended."""
    sys_ = traj.system
    labels = []
    for e in orbit_events(traj):
        if e.kind == EventKind.TRANSITION:
            labels.append(sys_.transitions[e.transition].label)
        elif e.kind == EventKind.SLIDING_START:
            labels.append(f"slide on {e.surface} ({e.mode_from}|{e.mode_to})")
        else:
            labels.append(f"leave {e.surface} sliding -> {e.mode_to}")
    return tuple(labels)


__all__ = ["BranchPoint", "Evaluation", "SolutionSummary", "amplitude_measures", "event_ids", "event_labels", "orbit_events"]
