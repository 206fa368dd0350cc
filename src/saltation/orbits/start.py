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

from collections.abc import Mapping, Sequence

import numpy as np

from saltation.engine.flow import Flow, Tolerances, Trajectory
from saltation.errors import ModelError, SaltationError, StartGuessError
from saltation.model.system import PiecewiseSystem
from saltation.orbits.multiple import MultipleShootingProblem, check_segments
from saltation.orbits.records import PeriodicOrbit
from saltation.orbits.single import ShootingProblem

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


def find_periodic_orbit(
    flow: Flow | PiecewiseSystem,
    state0: Sequence[float] | None = None,
    *,
    parameters: Mapping[str, float] | None = None,
    period: float | None = None,
    backward: bool = False,
    t0: float = 0.0,
    tol: float = 1e-10,
    max_iter: int = 30,
    tolerances: Tolerances | None = None,
    segments: int = 1,
    transient_length: float | None = None,
    mode0: str | None = None,
) -> PeriodicOrbit:
    """Find one periodic orbit by shooting from a guess.

    Parameters
    ----------
    flow : Flow or PiecewiseSystem
        The flow of the model (a model is given a :class:`Flow` of its own, with its default tolerances).
    state0 : array_like, optional
        Guess of the state at ``t0``.  Without one, the guess is the end of a transient from zeros
        (:func:`saltation.orbits.start.transient`, in the direction of integration).
    parameters : mapping, optional
        Parameter overrides.
    period : float, optional
        Period guess of an autonomous system; without one, it is read from a transient from
        ``state0`` (:func:`saltation.orbits.start.estimate_period`).  A forced system's period is its
        forcing period; a ``period`` given for it must equal that.
    backward : bool
        Shoot in backward time.
    t0 : float
        Initial time (forced systems: the phase of the forcing; reduced modulo
        the forcing period before integrating).
    tol : float
        Newton tolerance: converged when ``|r| <= tol (1 + |u|)``.
    max_iter : int
        Largest number of Newton iterations.
    tolerances : Tolerances, optional
        Integration tolerances (the flow's by default).
    segments : int
        Shooting segments: 1 is single shooting; ``m > 1`` is multiple shooting
        (:class:`MultipleShootingProblem`), for strongly unstable orbits, long periods and large
        models.  ``state0`` is then either one state (the nodes are taken from its trajectory, which
        on a strongly unstable orbit drifts away within the period) or a guess of every node, shape
        ``(m, n)``, at ``t0 + i T / m``.  At most :data:`MAX_SEGMENTS`, and ``m n`` at most
        :data:`MAX_NODE_VALUES` (the Newton matrix of multiple shooting is dense).
    transient_length : float, optional
        Length of the transient of an autonomous model, when one is needed
        (:data:`saltation.orbits.start.TRANSIENT_TIME` by default).
    mode0 : str, optional
        The mode the orbit starts in at ``state0``: for a mode that is memory (a latch, a relay with
        hysteresis, a thermostat), which the state alone does not tell from another mode with the same
        domain.  ``state0`` must lie in its domain (or on its boundary).  Every shot starts in it (with
        multiple shooting the first segment; each further one in the mode the one before it ends in),
        and the orbit must close in it.  Without ``state0`` the transient starts in ``mode0`` and the
        orbit in the mode the transient ends in.  An autonomous guess moved off the switching surfaces
        stays in ``mode0`` where the orbit spends a long enough stretch in it.  The orbit records its
        mode as :attr:`PeriodicOrbit.mode0`.  None (the default): the model's domains give the mode.

    Returns
    -------
    PeriodicOrbit
        With its forward-time multipliers; for autonomous orbits the trivial
        direction is deflated (:func:`saltation.orbits.floquet.autonomous_multipliers`).

    Raises
    ------
    ModelError
        A ``period`` that contradicts the forcing period, a state of the wrong size, a guess of every
        node without a period, an invalid parameter or number of segments, a ``mode0`` that is not a
        mode of the model (the message lists its modes).
    ConvergenceError
        Newton did not converge (with its residual history); a :class:`NoOrbitNearGuessError` when,
        in addition, the flow from an autonomous guess comes to rest.
    StationaryStateError
        Shooting converged to a state that does not move: an equilibrium, a
        pseudo-equilibrium, or a period shrunk to zero.
    InconsistentResultError
        An autonomous orbit whose trivial multiplier is not 1 to
        :data:`TRIVIAL_MULTIPLIER_ACCURACY`.
    StartGuessError
        Without a guess: the transient failed, diverged or shows no oscillation.
    IntegrationError, InitialModeError
        The shot from the guess itself fails (Newton's later trial steps that fail are shortened); a
        guess state outside the domain of ``mode0`` (the message names the mode and its conditions).
    KernelCacheError
        A model given as such cannot be compiled into the kernel cache.

    References
    ----------
    Stoer and Bulirsch, *Introduction to Numerical Analysis*, Springer, section 7.3 (single and
    multiple shooting).  Leine and Van Campen, "Fold bifurcations in discontinuous systems", eq. (9)
    (the saltation matrices in the monodromy).
    """
    if not isinstance(flow, Flow):  # a model
        flow = Flow(flow, tolerances=tolerances)
    segments = check_segments(segments, flow.system.n)  # (before a transient is integrated for a guess)
    if state0 is not None and np.ndim(state0) == 2 and period is None and flow.system.is_autonomous:
        raise ModelError(f"a guess of every node of the autonomous model {flow.system.name!r} needs a period guess")
    prob = ShootingProblem(flow, parameters, backward=backward, t0=t0, tolerances=tolerances, mode0=mode0)
    if state0 is None or (flow.system.is_autonomous and period is None):
        state0, period, prob.mode0 = starting_guess_and_mode(
            flow, prob.p, state0, period, t0=t0, backward=backward, length=transient_length, mode0=prob.mode0)
    if prob.mode0 is not None:  # the guess (its first node) lies in the mode's domain, or an error says why
        first = np.asarray(state0, dtype=float)
        prob.start_mode(first[0] if first.ndim == 2 else first, prob.p)
    if not prob.autonomous and period is not None:
        forced = prob.period_of(prob.pack(state0))
        if not abs(float(period) - forced) <= 1e-12 * forced:
            raise ModelError(
                f"model {flow.system.name!r} is forced: its period is the forcing period {forced:.10g} at these "
                f"parameters, not the period {period!r} given (omit period, or change the forcing parameters)"
            )
    guess = np.asarray(state0, dtype=float)
    if segments == 1 or guess.ndim == 1:
        if segments == 1:
            return prob.solve(prob.pack(state0, period), tol=tol, max_iter=max_iter)
        multiple = MultipleShootingProblem(prob, segments)
        u0 = prob.start_off_surfaces(prob.pack(state0, period))
        # the nodes together along the orbit: off the events, and out of its sliding motions where they fit
        U0 = multiple.start_off_surfaces(multiple.pack(u0), sliding_only=True)
        return multiple.solve(U0, tol=tol, max_iter=max_iter)
    multiple = MultipleShootingProblem(prob, segments)
    if guess.shape != (multiple.segments, flow.system.n):
        raise ModelError(f"a guess of every node of {segments} segments has shape ({segments}, {flow.system.n}), "
                         f"got {guess.shape}")
    prob.pack(guess[0], period)  # checks the period guess of an autonomous model
    U0 = guess.ravel()
    return multiple.solve(np.append(U0, float(period)) if prob.autonomous else U0, tol=tol, max_iter=max_iter)


# -- multiple shooting ---------------------------------------------------------------------
