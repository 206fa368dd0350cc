"""The seam rule of a shot over one period: an event at ``t0`` and at ``t0 + T`` is one event.

A shooting state on a switching surface meets the crossing at both ends of the shooting interval, and the
engine may log it at the start, at the end, at both or at neither, as rounding falls.
:func:`close_period` logs it once, at the end, with its saltation matrix (eq. (9) of *Fold bifurcations in
discontinuous systems*), so that the monodromy matrix and the event sequence of an orbit do not depend on
where its section lies.
"""


from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from saltation.engine.flow import (
    EventKind,
    Trajectory,
)
from saltation.engine.trajectory import log_with_event
from saltation.errors import (
    InconsistentResultError,
)

#: the kernel's event kinds as plain integers (an Enum member costs an attribute lookup in a hot path)
_TRANSITION, _SLIDING_START, _SLIDING_END = (int(EventKind.TRANSITION), int(EventKind.SLIDING_START),
                                             int(EventKind.SLIDING_END))



def close_period(problem, traj: Trajectory, p: np.ndarray, sensitivity: int = -1, *,
                 disabled: Sequence[int] = ()) -> Trajectory:
    """The shot with the crossing at the seam ``t0 = t0 + T`` counted once, as the orbit crosses there.

    A shooting state on a switching surface (wherever the phase condition, or a forced orbit's
    ``t0``, put it) meets the crossing at both ends of the interval, and the engine, which fires
    an event once the indicator has changed sign, may log it at the start, at the end, at
    both or at neither, as rounding falls:

    * at both (the first and the last event are the same transition, within ``1e-7 T`` of the
      ends): the shot is run again from the start in the mode that crossing enters, so that it
      is logged at most at the end (a reset there is ambiguous: InconsistentResultError), and
      then as below;
    * at neither (the shot starts in mode ``a`` with no event and ends, within rounding, on the
      surface of a transition from its final mode ``b`` back to ``a``): that transition is
      applied at the end (reset, saltation matrix of eq. (9), parameter sensitivity) and logged.

    Any other shot is returned as it is; the transitions in ``disabled`` (passed by a virtual orbit)
    are never applied at the seam.

    Parameters
    ----------
    problem : ShootingProblem
        The orbit's problem (its flow, model and tolerances).
    traj : Trajectory
        A shot over one period (a shot without monodromy is returned as it is).
    p : ndarray
        Its parameter values.
    sensitivity : int
        Index of the parameter whose sensitivity the shot carries (-1: none).
    disabled : sequence of int
        Transitions the shot passes without firing (see :meth:`Flow.run`).

    Returns
    -------
    Trajectory
        The shot, the seam's event logged once.

    Raises
    ------
    InconsistentResultError
        For a reset (an impact) exactly at the seam, logged at both ends.
    IntegrationError
        If the shot run again fails, or the transition applied at the end is tangent to its surface.
    """
    sys_ = problem.system
    if traj.monodromy is None:
        return traj
    if traj.n_events >= 2:
        # the first, second and last events as the engine logged them (plain integers, no records)
        first, last = traj.logged(0), traj.logged(-1)
        delta = 1e-7 * max(1.0, abs(traj.t1 - traj.t0))
        # (or the last event, a sliding motion's end, enters the mode the first has entered)
        if (first.kind == _TRANSITION and last.kind in (_TRANSITION, _SLIDING_END)
                and first.mode_to == last.mode_to and (last.kind != _TRANSITION or first.transition == last.transition)
                and abs(first.t - traj.t0) <= delta and abs(traj.t1 - last.t) <= delta):
            if sys_.resets[first.transition] is not None:
                raise InconsistentResultError(
                    f"transition {sys_.transitions[first.transition].label!r} (a reset) happens at the start and at "
                    f"the end of the shooting interval of {sys_.name!r}, at t = {traj.t0:.12g}: the state there is "
                    "ambiguous (before or after the reset); shoot from another t0"
                )
            traj = problem.flow.run(traj.x0, traj.t0, traj.t1, p, mode0=sys_.mode_names[first.mode_to], variational=True,
                                    sensitivity=sensitivity, tolerances=problem.tolerances,
                                    disabled=disabled)  # then as below
        elif traj.n_events >= 3:
            second = traj.logged(1)
            if (first.kind == _SLIDING_START and second.kind == _SLIDING_END and last.kind == _SLIDING_END
                    and second.mode_to == last.mode_to and abs(first.t - traj.t0) <= delta
                    and abs(second.t - traj.t0) <= delta and abs(traj.t1 - last.t) <= delta):
                # a sliding motion ends at the seam (logged at t0 + T) and is met again at t0, with no length:
                # a state on the sliding region's edge starts there a sliding motion that ends at once.  That
                # pair is dropped from the log; its matrices (the projection onto the surface, and the
                # identity of the exit) stay in the monodromy matrix M, whose range lies in the surface's
                # tangent space after the sliding motion, so that they leave its multipliers as they are; the
                # shot starts in the mode that sliding motion leaves into
                traj = replace(traj, mode0=sys_.mode_names[second.mode_to],
                               event_log=tuple(column[2:] for column in traj.event_log))
    if traj.sliding_at_end:
        return leave_sliding_at_the_end(problem, traj, p, sensitivity)
    if traj.mode1 == traj.mode0:
        return traj
    if traj.n_events and traj.first_logged.t == traj.t0:
        return traj  # the start fired its own event: the shot starts after it
    flow, t1, x1 = problem.flow, traj.t1, traj.x1
    scale = 1.0 + float(np.abs(x1).max())
    for k, tr in enumerate(sys_.transitions):
        if tr.source != traj.mode1 or tr.target != traj.mode0 or k in disabled:
            continue
        h = flow.indicator(tr.surface, t1, x1, p)
        hx, _, _ = flow.indicator_gradient(tr.surface, t1, x1, p)
        # within Newton's closing error of the state (1e-8 relative): the orbit crosses here, at the seam
        if abs(h) > 1e-8 * scale * float(np.linalg.norm(hx)) or not flow.guard_holds(k, t1, x1, p):
            continue
        x_plus, S, dp = flow.transition_jump(k, t1, x1, p)
        psi = traj.parameter_sensitivity
        if psi is not None and sensitivity >= 0:
            psi = S @ psi + dp[:, sensitivity]
        log = log_with_event(traj, EventKind.TRANSITION, k, tr.surface, tr.source, tr.target, x1, x_plus, S)
        return replace(
            traj, x1=x_plus, mode1=tr.target, event_log=log, monodromy=S @ traj.monodromy,
            parameter_sensitivity=psi, velocity_end=flow.vector_field(tr.target, t1, x_plus, p),
        )
    return traj


def leave_sliding_at_the_end(problem, traj: Trajectory, p: np.ndarray, sensitivity: int) -> Trajectory:
    """A shot that starts off a sliding motion, in one of its modes, and ends on it where that mode's
    field turns tangent to the surface: the orbit leaves the sliding motion at the seam.  Its end is
    applied and logged at ``t0 + T``, with the saltation matrix the engine uses at a sliding exit
    (eq. 9 with the exit side's Lie derivative ``L = h_x f + h_t`` as the event function and the
    sliding field before it).

    Parameters
    ----------
    problem : ShootingProblem
        The orbit's problem (its flow and model).
    traj : Trajectory
        A shot over one period.
    p : ndarray
        Its parameter values.
    sensitivity : int
        Index of the parameter whose sensitivity the shot carries (-1: none).

    Returns
    -------
    Trajectory
        The shot, its sliding exit at the seam applied and logged (or as it was).
    """
    starts = [e for e in traj.events if e.kind == EventKind.SLIDING_START]
    if not starts or (traj.events[0].kind == EventKind.SLIDING_START and traj.events[0].t == traj.t0):
        return traj
    last = starts[-1]
    if traj.mode0 not in (last.mode_from, last.mode_to):
        return traj
    flow, t1, x1 = problem.flow, traj.t1, traj.x1
    L, L_x, L_p, L_t = flow.lie_derivative(traj.mode0, last.surface, t1, x1, p)
    scale = 1.0 + float(np.abs(x1).max())
    if abs(L) > 1e-8 * scale * float(np.linalg.norm(L_x)):
        return traj
    f_slide = traj.velocity_end
    f_out = flow.vector_field(traj.mode0, t1, x1, p)
    den = float(L_x @ f_slide) + L_t
    if den == 0.0:
        return traj
    w = f_out - f_slide
    S = np.eye(problem.system.n) + np.outer(w, L_x) / den
    psi = traj.parameter_sensitivity
    if psi is not None and sensitivity >= 0:
        psi = S @ psi + w * L_p[sensitivity] / den
    other = last.mode_to if traj.mode0 == last.mode_from else last.mode_from
    log = log_with_event(traj, EventKind.SLIDING_END, -1, last.surface, other, traj.mode0, x1, x1, S)
    return replace(traj, mode1=traj.mode0, event_log=log, monodromy=S @ traj.monodromy, sliding_at_end=False,
                   parameter_sensitivity=psi, velocity_end=f_out)



__all__ = ["close_period", "leave_sliding_at_the_end"]
