"""Starting guesses of periodic orbits: a transient and the period read from it.

When no guess of a periodic orbit is at hand, the flow itself makes one: a
transient in the direction of integration (forward for attracting orbits,
backward for the infinitely unstable stick-slip orbits of Fig. 7) ends near an
attracting orbit, and the period of an autonomous one is read from the
transient's repeating events, or from its crossings of a Poincaré section.
:func:`saltation.orbits.shooting.find_periodic_orbit` uses these when it is
given no state or, for an autonomous model, no period; the command line uses
them with the shipped models' own start states.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from saltation.engine.flow import Flow, Trajectory
from saltation.errors import SaltationError, StartGuessError

#: Forcing periods of a forced model's transient.
TRANSIENT_PERIODS = 50
#: Length of an autonomous model's transient when none is given.
TRANSIENT_TIME = 200.0
#: A transient whose end state exceeds this factor times the start's size (plus one) diverges.
DIVERGENCE_FACTOR = 1e6


def transient(
    flow: Flow,
    parameters: np.ndarray,
    state: Sequence[float] | None = None,
    *,
    t0: float = 0.0,
    backward: bool = False,
    length: float | None = None,
    mode0: str | None = None,
) -> Trajectory:
    """Simulate a transient in the direction of integration.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    parameters : ndarray
        Parameter vector (:meth:`Flow.parameters`).
    state : array_like, optional
        Where it starts (zeros by default).
    t0 : float
        Start time; a forced model's transient runs whole forcing periods, so that its end state has
        the forcing phase of ``t0``.
    backward : bool
        Run backward in time.
    length : float, optional
        Its length for an autonomous model (:data:`TRANSIENT_TIME` by default); a forced model runs
        :data:`TRANSIENT_PERIODS` forcing periods.  A run that would end on a sliding motion is
        extended (by one forcing period, or 1 % of the length) until it does not.
    mode0 : str, optional
        The mode it starts in (a memory mode, see :meth:`Flow.start_mode`); by default the model's
        initial-mode rule.  The mode it ends in is the trajectory's ``mode1``.

    Returns
    -------
    Trajectory
        With dense output for an autonomous model (its period is read from it).

    Raises
    ------
    StartGuessError
        If the run fails (any :class:`SaltationError` of the integration, chained: a state outside the
        domain of ``mode0`` too) or diverges, or ``length`` is not positive; the message says where it
        started and ended.
    ModelError
        If the forcing period of a forced model is not positive and finite at these parameters.
    """
    system = flow.system
    p = np.asarray(parameters, dtype=float)
    x = np.zeros(system.n) if state is None else np.asarray(state, dtype=float).reshape(-1)
    sign = -1.0 if backward else 1.0
    if system.is_autonomous:
        span = TRANSIENT_TIME if length is None else float(length)
        if not span > 0.0:
            raise StartGuessError(f"the transient of {system.name!r} needs a positive length, got {length!r}")
        extra = 0.01 * span
    else:
        T = system.forcing_period(p)
        span, extra = TRANSIENT_PERIODS * T, T
    direction = "backward" if backward else "forward"
    for attempt in range(20):
        try:
            m0 = None if mode0 is None else flow.start_mode(x, p, t0, mode0)
            traj = flow.run(x, t0, t0 + sign * (span + attempt * extra), p, mode0=m0, dense=system.is_autonomous)
        except SaltationError as exc:
            raise StartGuessError(f"the {direction} transient of {system.name!r} from {x.tolist()} failed ({exc})") from exc
        if not traj.sliding_at_end:
            break
    if not np.all(np.isfinite(traj.x1)) or np.max(np.abs(traj.x1)) > DIVERGENCE_FACTOR * (1.0 + np.max(np.abs(x))):
        raise StartGuessError(
            f"the {direction} transient of {system.name!r} from {x.tolist()} diverges (ends at {traj.x1.tolist()})"
        )
    return traj


def period_from_events(traj: Trajectory) -> float | None:
    """The period of the event sequence at the end of a trajectory (its shortest repeating lag), or None.

    Parameters
    ----------
    traj : Trajectory
        A transient.

    Returns
    -------
    float or None
        The time between the last event and the one a lag earlier, for the shortest lag over which
        the sequence of event signatures repeats (checked back from the end); None if none repeats.
    """
    events = traj.events
    sig = [e.signature for e in events]
    n = len(sig)
    for lag in range(1, n // 2 + 1):
        if all(sig[n - 1 - j] == sig[n - 1 - lag - j] for j in range(lag)):
            return abs(events[-1].t - events[-1 - lag].t)
    return None


def period_from_section(traj: Trajectory) -> float | None:
    """The period from the last two upward crossings of a Poincaré section.

    The section is ``x_1 =`` mid-range of ``x_1`` over the trajectory's second half.

    Parameters
    ----------
    traj : Trajectory
        A transient with dense output.

    Returns
    -------
    float or None
        The time between the last two upward crossings, or None if the trajectory oscillates too
        little (fewer than three crossings, or a range of ``x_1`` within rounding).

    Raises
    ------
    ValueError
        If the trajectory was computed without dense output.
    """
    t, x = traj.sample(16)
    if t.size < 4:
        return None
    half = np.abs(t - t[0]) >= 0.5 * abs(t[-1] - t[0])
    t, x1 = t[half], x[half, 0]
    lo, hi = float(np.min(x1)), float(np.max(x1))
    if hi - lo <= 1e-8 * (1.0 + abs(hi)):
        return None  # settles to an equilibrium
    g = x1 - 0.5 * (lo + hi)
    up = np.nonzero((g[:-1] < 0) & (g[1:] >= 0))[0]
    if up.size < 3:
        return None
    times = [t[i] - g[i] * (t[i + 1] - t[i]) / (g[i + 1] - g[i]) for i in up[-2:]]
    return abs(times[1] - times[0])


def estimate_period(traj: Trajectory) -> float:
    """The period of the oscillation a transient of an autonomous model ends on.

    From the repeating events (:func:`period_from_events`), else from a Poincaré section
    (:func:`period_from_section`).

    Parameters
    ----------
    traj : Trajectory
        A transient (with dense output, for the section).

    Returns
    -------
    float
        The period, positive.

    Raises
    ------
    StartGuessError
        If the transient shows no repeating events and no oscillation (it settles to an equilibrium).
    ValueError
        If the events do not repeat and the trajectory has no dense output.
    """
    T = period_from_events(traj)
    if T is None or not T > 0:
        T = period_from_section(traj)
    if T is None or not T > 0:
        raise StartGuessError(
            f"cannot estimate a period: the transient (t = {traj.t0:.6g} to {traj.t1:.6g}, ending at "
            f"{traj.x1.tolist()}) shows no repeating events or oscillation (an equilibrium?)"
        )
    return float(T)


def candidate_starts(n: int) -> list[np.ndarray]:
    """Where an autonomous model's transient starts when no state is given, in the order tried.

    The origin, then one unit along each state, then one along every state.  The origin alone often
    does not move (an equilibrium, or the sticking set of a friction model).

    Parameters
    ----------
    n : int
        Number of states.

    Returns
    -------
    list of ndarray, shape (n,)
        The ``n + 2`` starting states.
    """
    return [np.zeros(n), *np.eye(n), np.ones(n)]


def oscillating_transient(
    flow: Flow, parameters: np.ndarray, *, t0: float = 0.0, backward: bool = False, length: float | None = None,
    mode0: str | None = None,
) -> tuple[Trajectory, float]:
    """The first transient of an autonomous model that ends in an oscillation, and its period.

    The transients start from :func:`candidate_starts`, in order; the period is read by
    :func:`estimate_period`.

    Parameters
    ----------
    flow : Flow
        The flow of an autonomous model.
    parameters : ndarray
        Parameter vector.
    t0 : float
        Start time.
    backward : bool
        Run backward in time.
    length : float, optional
        Length of each transient (:data:`TRANSIENT_TIME` by default).
    mode0 : str, optional
        The mode each transient starts in (by default the model's initial-mode rule).

    Returns
    -------
    traj : Trajectory
        The transient that oscillates.
    period : float
        Its period.

    Raises
    ------
    StartGuessError
        If none does; the message names the starts tried and why each failed.
    """
    tried = []
    for x in candidate_starts(flow.system.n):
        try:
            traj = transient(flow, parameters, x, t0=t0, backward=backward, length=length, mode0=mode0)
            return traj, estimate_period(traj)
        except StartGuessError as exc:
            tried.append(f"from {x.tolist()}: {exc}")
    raise StartGuessError(f"no transient of {flow.system.name!r} ends in an oscillation (" + "; ".join(tried) + ")")


def starting_guess(
    flow: Flow,
    parameters: np.ndarray,
    state: Sequence[float] | None = None,
    period: float | None = None,
    *,
    t0: float = 0.0,
    backward: bool = False,
    length: float | None = None,
) -> tuple[np.ndarray, float | None]:
    """A guess ``(state, period)`` of a periodic orbit, completed from a transient where one is missing.

    A given state is kept, and a given period; the transient (:func:`transient`, from ``state``) runs
    only when the state is None or, for an autonomous model, the period is.  A forced model's period is
    its forcing period (returned as None).  :func:`starting_guess_and_mode` also gives the guess's mode.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    parameters : ndarray
        Parameter vector.
    state : array_like, optional
        Guess of the state (the end of a transient by default).
    period : float, optional
        Guess of the period of an autonomous model (read from a transient by default).
    t0 : float
        Start time of the transient.
    backward : bool
        Run the transient backward in time.
    length : float, optional
        Length of an autonomous model's transient (:data:`TRANSIENT_TIME` by default).

    Returns
    -------
    state : ndarray, shape (n,)
        The state guess.
    period : float or None
        The period guess (None for a forced model whose period was not given).

    Raises
    ------
    StartGuessError
        If the transient fails, diverges, or shows no oscillation to read a period from.
    ModelError
        If the forcing period of a forced model is not positive and finite at these parameters.
    """
    x0, period, _ = starting_guess_and_mode(flow, parameters, state, period, t0=t0, backward=backward, length=length)
    return x0, period


def starting_guess_and_mode(
    flow: Flow,
    parameters: np.ndarray,
    state: Sequence[float] | None = None,
    period: float | None = None,
    *,
    t0: float = 0.0,
    backward: bool = False,
    length: float | None = None,
    mode0: str | None = None,
) -> tuple[np.ndarray, float | None, str | None]:
    """A guess ``(state, period, mode)`` of a periodic orbit: :func:`starting_guess`, with the guess's mode.

    The transient starts in ``mode0``; a guess state read from its end is in the mode the transient
    ends in, a given state in ``mode0``.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    parameters : ndarray
        Parameter vector.
    state : array_like, optional
        Guess of the state (the end of a transient by default).
    period : float, optional
        Guess of the period of an autonomous model (read from a transient by default).
    t0 : float
        Start time of the transient.
    backward : bool
        Run the transient backward in time.
    length : float, optional
        Length of an autonomous model's transient (:data:`TRANSIENT_TIME` by default).
    mode0 : str, optional
        The mode of ``state``, where the transient starts (a memory mode, see :meth:`Flow.start_mode`);
        None: the model's initial-mode rule.

    Returns
    -------
    state : ndarray, shape (n,)
        The state guess.
    period : float or None
        The period guess (None for a forced model whose period was not given).
    mode : str or None
        The guess state's mode: the transient's final mode where the state is its end, else ``mode0``
        (None without ``mode0``: the domains give the mode).

    Raises
    ------
    StartGuessError
        If the transient fails (a state outside the domain of ``mode0`` too), diverges, or shows no
        oscillation to read a period from.
    ModelError
        If the forcing period of a forced model is not positive and finite at these parameters.
    """
    autonomous = flow.system.is_autonomous
    if state is not None and (period is not None or not autonomous):
        return np.asarray(state, dtype=float), period, mode0
    if state is None and autonomous:
        traj, found = oscillating_transient(flow, parameters, t0=t0, backward=backward, length=length, mode0=mode0)
        return traj.x1.copy(), found if period is None else period, None if mode0 is None else traj.mode1
    traj = transient(flow, parameters, state, t0=t0, backward=backward, length=length, mode0=mode0)
    if autonomous and period is None:
        period = estimate_period(traj)
    if state is not None:
        return np.asarray(state, dtype=float), period, mode0
    return traj.x1.copy(), period, None if mode0 is None else traj.mode1
