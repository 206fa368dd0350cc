"""Grazing bifurcations of periodic orbits: location by their defining system.

An orbit grazes a switching surface when it becomes tangent to it: at one
instant ``t_g``, ``h(t_g, x(t_g)) = 0`` and ``dh/dt = h_x f + h_t = 0``, with
``d2h/dt2 != 0``.  On one side of a grazing the orbit misses the surface, on
the other it crosses it (an impact, a contact).  Near grazing, the crossing
side's monodromy grows like ``1/sqrt(d)`` in the distance ``d`` to the
grazing (Nordmark's square-root map: the saltation matrix of an impact is
``O(1/v)`` in the impact velocity ``v ~ sqrt(d)``), so no convex combination
of two finite matrices describes the jump of the multipliers.

The defining system, for a forced system with ``z = (x0, lam)`` (an
autonomous one adds the period to the unknowns and a phase condition):

* periodicity ``x(t0 + T; x0, lam) - x0 = 0`` (``n`` equations), of the
  *virtual* orbit that passes the grazed surface as if it were not there
  (its transitions disabled, :meth:`saltation.engine.flow.Flow.run`);
* tangency ``G(x0, lam) = h(t_g, x(t_g)) = 0``, where ``t_g`` is the local
  extremum of ``h`` along the orbit (``dh/dt = 0``).

By the envelope theorem ``dG/dx0 = h_x Phi(t_g, t0)`` and
``dG/dlam = h_x psi(t_g) + h_lam``, so Newton's method runs with exact
Jacobians and converges quadratically.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from saltation.engine.flow import Flow, Trajectory
from saltation.errors import ConvergenceError, ModelError
from saltation.orbits.conditions import ConditionedProblem, ReturnTangency, Tangency
from saltation.orbits.single import ShootingProblem


def location_tolerances(flow: Flow, tolerances=None):
    """The integration tolerances of a special point's defining system.

    Those given, at most ``rtol = 1e-12``, ``atol = 1e-14``: a location costs a few tens of period
    maps, and tight tolerances keep the integration error below the location's target where DOP853
    steps.

    Parameters
    ----------
    flow : Flow
        The flow (its tolerances by default).
    tolerances : Tolerances, optional
        The tolerances to tighten.

    Returns
    -------
    Tolerances
        A copy with ``rtol`` and ``atol`` capped.
    """
    tol = tolerances or flow.tolerances
    return replace(tol, rtol=min(tol.rtol, 1e-12), atol=min(tol.atol, 1e-14))


@dataclass(frozen=True)
class GrazingOrbit:
    """A located grazing periodic orbit.

    Attributes
    ----------
    parameter : float
        The value of the continuation parameter at grazing.
    state0 : ndarray, shape (n,)
        The orbit's state at ``t0``.
    period : float
        Its period.
    t_graze : float
        The instant of tangency.
    x_graze : ndarray, shape (n,)
        The state at tangency (on the surface).
    transition : int
        The transition whose surface is grazed.
    monodromy : ndarray, shape (n, n)
        Monodromy of the grazing orbit itself: the limit on the side without
        the crossing (forward time).
    fundamental_to_graze : ndarray, shape (n, n)
        ``Phi(t_g, t0)`` along the grazing orbit.
    trajectory : Trajectory
        One period of the grazing orbit (with the grazed transition disabled).
    accuracy : float
        The Newton correction of the parameter that would follow the last
        iterate: an estimate of its error.
    residuals : list of float
        Newton residual history.
    """

    parameter: float
    state0: np.ndarray
    period: float
    t_graze: float
    x_graze: np.ndarray
    transition: int
    monodromy: np.ndarray
    fundamental_to_graze: np.ndarray
    trajectory: Trajectory
    accuracy: float
    residuals: list[float]


def indicator_rate(flow: Flow, surface: int, traj: Trajectory, p: np.ndarray) -> float:
    """``dh/dt = h_x f + h_t`` of a surface at the end of a trajectory (in forward time).

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    surface : int
        Index of the surface.
    traj : Trajectory
        A trajectory (its end state and velocity are used).
    p : ndarray
        Parameter values.

    Returns
    -------
    float
        The rate; zero where the flow is tangent to the surface.
    """
    hx, ht, _ = flow.indicator_gradient(surface, traj.t1, traj.x1, p)
    return float(hx @ traj.velocity_end + ht)


def tangency_time(
    flow: Flow, x0: np.ndarray, t0: float, p: np.ndarray, surface: int, t_guess: float, span: float, *,
    mode0: int | str | None = None, disabled: Sequence[int] = (), tolerances=None, sign: float = 1.0,
) -> float | None:
    """The extremum of ``h`` along the orbit from ``(t0, x0)`` nearest ``t_guess``: a root of ``dh/dt``.

    Searches ``t_guess +- delta`` for a sign change of the rate, ``delta``
    growing to ``span / 4``, within ``t0 .. t0 + sign span`` (``sign`` -1: backward time), and
    refines it by Brent's method.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    x0 : ndarray, shape (n,)
        The initial state.
    t0 : float
        The initial time.
    p : ndarray
        Parameter values.
    surface : int
        Index of the surface.
    t_guess : float
        Guess of the instant.
    span : float
        The length of the interval searched (the period).
    mode0 : int or str, optional
        The initial mode (the model's rule by default).
    disabled : sequence of int
        Transitions the orbit passes without firing (the grazed one).
    tolerances : Tolerances, optional
        Integration tolerances.
    sign : float
        +1 forward in time, -1 backward.

    Returns
    -------
    float or None
        The instant, or None when the rate does not change sign near ``t_guess``.

    Raises
    ------
    IntegrationError, InitialModeError
        If a run to a trial instant fails.
    """
    def rate(t: float) -> float:
        traj = flow.run(x0, t0, t, p, mode0=mode0, disabled=disabled, tolerances=tolerances)
        return indicator_rate(flow, surface, traj, p)

    lo_limit, hi_limit = (t0, t0 + span) if sign > 0 else (t0 - span, t0)
    delta = 1e-6 * span
    while delta <= 0.25 * span:
        a, b = max(lo_limit, t_guess - delta), min(hi_limit, t_guess + delta)
        if b > a:
            ra, rb = rate(a), rate(b)
            if ra == 0.0:
                return a
            if rb == 0.0:
                return b
            if ra * rb < 0.0:
                return float(brentq(rate, a, b, xtol=1e-15 * max(1.0, abs(a)), rtol=1e-15, maxiter=200))
        delta *= 4.0
    return None


def locate_grazing(
    flow: Flow,
    x0: Sequence[float],
    lam: float,
    lam_name: str,
    transition: int,
    t_guess: float,
    *,
    parameters=None,
    t0: float = 0.0,
    tol: float = 1e-12,
    max_iter: int = 20,
    tolerances=None,
    period: float | None = None,
    backward: bool = False,
    also_disabled: Sequence[int] = (),
    periods: int = 1,
    mode0: str | None = None,
) -> GrazingOrbit:
    """Locate a grazing periodic orbit.

    The orbit's problem with a :class:`~saltation.orbits.conditions.Tangency` attached and the
    parameter freed, solved by the one Newton of
    :class:`~saltation.orbits.conditions.ConditionedProblem`.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    x0 : array_like, shape (n,)
        Guess of the orbit's state at ``t0`` (a nearby orbit that misses the surface).
    lam : float
        Guess of the parameter value.
    lam_name : str
        The parameter that moves.
    transition : int
        The transition whose surface the orbit grazes (disabled along the way).
    t_guess : float
        Guess of the instant of tangency.
    parameters : mapping or ndarray, optional
        The other parameters' values (the model's defaults by default).
    t0 : float
        Initial time (forced models: the phase of the forcing).
    tol : float
        Newton tolerance.
    max_iter : int
        Largest number of Newton iterations.
    tolerances : Tolerances, optional
        Integration tolerances (tightened by :func:`location_tolerances`).
    period : float, optional
        Autonomous models: the guess of the period, then an unknown too, with
        the phase condition ``f(x_ref) . (x0 - x_ref) = 0`` anchored at the guess.
    backward : bool
        The orbit is one of backward time (the grazing of an orbit that is unstable in forward time).
    also_disabled : sequence of int
        Further transitions the virtual orbit passes (touched at the same time, by symmetry).
    periods : int
        Forced models: the number of forcing periods the orbit closes after (a period-``k`` orbit grazes
        once in ``k`` forcing periods; its monodromy is that of ``k`` periods).
    mode0 : str, optional
        The mode the orbit starts in at ``x0`` (a memory mode: the start mode of the branch it lies
        on, :attr:`~saltation.orbits.shooting.ShootingProblem.mode0`); by default the model's domains give it.

    Returns
    -------
    GrazingOrbit
        The grazing orbit, its instant and state of tangency, monodromy and accuracy.

    Raises
    ------
    ConvergenceError
        If no tangency lies near ``t_guess``, or Newton's method does not converge (with the residual
        history).
    ModelError
        For an autonomous model without a period guess, or an unknown parameter.
    IntegrationError, InitialModeError
        If the guess's orbit cannot be integrated while the instant of tangency is sought.
    StationaryStateError
        If the phase condition of an autonomous orbit would be anchored at an equilibrium.

    References
    ----------
    di Bernardo, Budd, Champneys and Kowalczyk (2008), *Piecewise-smooth Dynamical Systems: Theory
    and Applications*, Springer (grazing bifurcations).
    """
    system = flow.system
    tolerances = location_tolerances(flow, tolerances)
    autonomous = system.is_autonomous
    if autonomous and period is None:
        raise ModelError(f"model {system.name!r} is autonomous: give the period guess to locate its grazing")
    p = flow.parameters(parameters).copy()
    p[system.parameter_index(lam_name)] = float(lam)
    x0 = np.asarray(x0, dtype=float)
    base = ShootingProblem(flow, p, backward=backward, t0=t0, tolerances=tolerances, periods=periods, mode0=mode0)
    sign = base.sign
    T = float(period) if autonomous else periods * system.forcing_period(p)
    surface = system.surface_index(system.transitions[transition].surface)
    disabled = (int(transition), *map(int, also_disabled))
    mode0 = base.start_mode(x0, p)
    t_g = tangency_time(flow, x0, base.t0, p, surface, t_guess, T, mode0=mode0, disabled=disabled,
                        tolerances=tolerances, sign=sign)
    if t_g is None:
        raise ConvergenceError(f"grazing of surface {system.surface_names[surface]!r}: no tangency near t = {t_guess:.6g}",
                               [])
    tangency = Tangency(flow, transition, t_g, also_disabled=also_disabled)
    problem = ConditionedProblem(base, [tangency], free=(lam_name,))
    found = problem.solve(problem.pack(x0, period=period), tol=tol, max_iter=max_iter,
                          what=f"grazing of surface {system.surface_names[surface]!r}")
    shot = found.shot
    return GrazingOrbit(
        parameter=float(found.parameters[system.parameter_index(lam_name)]), state0=found.state0,
        period=found.period, t_graze=float(found.unknowns[-1]), x_graze=shot.piece.x.copy(),
        transition=int(transition), monodromy=shot.trajectory.monodromy.copy(),
        fundamental_to_graze=shot.piece.fundamental.copy(), trajectory=shot.trajectory,
        accuracy=float(found.accuracy[0]), residuals=found.residuals,
    )


@dataclass(frozen=True)
class TangentialReturn:
    """A periodic orbit that returns to a surface tangentially and enters its transition there.

    Attributes
    ----------
    parameter : float
        The parameter's value.
    state : ndarray, shape (n,)
        The touching point (on the surface).
    period : float
        Time from the touching point around the orbit back to it.
    transition : int
        The transition entered at the touch (into a stick phase, for example).
    accuracy : float
        Estimate of the error of ``parameter`` (the Newton correction that would follow).
    residuals : list of float
        Newton's residual history.
    """

    parameter: float
    state: np.ndarray
    period: float
    transition: int
    accuracy: float
    residuals: list[float]


def locate_tangential_return(
    flow: Flow,
    x_touch: Sequence[float],
    lam: float,
    lam_name: str,
    transition: int,
    period: float,
    *,
    parameters=None,
    tol: float = 1e-12,
    max_iter: int = 30,
    tolerances=None,
) -> TangentialReturn:
    """Locate an orbit whose return to a surface is tangential, for an autonomous model.

    The defining system of the fold of a stick-slip cycle (the slip arc that leaves the stick band
    returns to it tangentially): the orbit's problem with a
    :class:`~saltation.orbits.conditions.ReturnTangency` attached and the parameter freed.  The orbit
    starts at the touching point, in the target mode of ``transition`` (the stick phase), and returns
    there with the transition passed; ``h = 0`` and ``L = h_x f_source + h_t = 0`` at the start fix the
    touching point and the phase, and the period is an unknown.  Solved by the one Newton of
    :class:`~saltation.orbits.conditions.ConditionedProblem`, its Jacobian exact (variational equations
    and the model's Lie derivatives).

    Parameters
    ----------
    flow : Flow
        The flow of an autonomous model.
    x_touch : array_like
        Guess of the touching point (the state where the orbit enters the transition); it is first
        projected onto the surface.
    lam : float
        Guess of the parameter.
    lam_name : str
        The parameter that moves.
    transition : int
        The transition entered at the touch.
    period : float
        Guess of the period.
    parameters : mapping or ndarray, optional
        The other parameters' values (the model's defaults by default).
    tol : float
        Newton tolerance.
    max_iter : int
        Largest number of Newton iterations.
    tolerances : Tolerances, optional
        Integration tolerances (tightened by :func:`location_tolerances`).

    Returns
    -------
    TangentialReturn
        The touching point, parameter, period and accuracy.

    Raises
    ------
    ConvergenceError
        If Newton's method does not converge (with the residual history).
    ModelError
        For a forced model (the condition fixes the phase), or an unknown parameter.

    References
    ----------
    Leine and Van Campen, "Fold bifurcations in discontinuous systems" (the stick-slip fold).
    """
    system = flow.system
    tolerances = location_tolerances(flow, tolerances)
    tr = system.transitions[transition]
    p = flow.parameters(parameters).copy()
    p[system.parameter_index(lam_name)] = float(lam)
    base = ShootingProblem(flow, p, tolerances=tolerances)
    condition = ReturnTangency(flow, transition)
    # the guess onto the surface (along its gradient): a start off it may lie outside the stick mode's domain
    x = np.asarray(x_touch, dtype=float).copy()
    for _ in range(8):
        h = flow.indicator(condition.surface, 0.0, x, p)
        hx, _, _ = flow.indicator_gradient(condition.surface, 0.0, x, p)
        if abs(h) <= 1e-15 * (1.0 + float(np.linalg.norm(x))) or not float(hx @ hx) > 0:
            break
        x = x - h * hx / float(hx @ hx)
    problem = ConditionedProblem(base, [condition], free=(lam_name,))
    found = problem.solve(problem.pack(x, period=float(period)), tol=tol,
                          max_iter=max_iter, what=f"tangential return to surface {tr.surface!r}")
    return TangentialReturn(
        parameter=float(found.parameters[system.parameter_index(lam_name)]), state=found.state0.copy(),
        period=float(found.period), transition=int(transition), accuracy=float(found.accuracy[0]),
        residuals=found.residuals,
    )


def grazing_candidates(flow: Flow, traj: Trajectory, p: np.ndarray, *, relative_gap: float = 1e-2) -> list[tuple[int, float]]:
    """Transitions whose surface the orbit nearly touches without crossing: ``(transition, time)`` pairs.

    Along a period of ``traj`` (computed with ``dense=True``), an indicator of
    a transition of the current mode that comes within ``relative_gap`` of
    zero (relative to its range over the period) at a local extremum, from
    the side it would cross from, is a candidate for grazing.  Of a stretch of
    consecutive samples that all qualify (an indicator that stays flat near
    zero, as in a stick phase), the one nearest zero is the candidate.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    traj : Trajectory
        One period, with dense output.
    p : ndarray
        Parameter values.
    relative_gap : float
        How near zero, relative to the indicator's range, a candidate comes.

    Returns
    -------
    list of tuple of (int, float)
        The candidates, nearest first.

    Raises
    ------
    ValueError
        If the trajectory was computed without dense output.
    """
    system = flow.system
    t, x = traj.sample(16)
    events = _without_grazing_visits(traj)
    modes = np.full(t.shape, system.mode_index(traj.mode0))
    for e in events:
        after = (t > e.t) if traj.t1 >= traj.t0 else (t < e.t)
        modes[after] = system.mode_index(e.mode_to)
    found: list[tuple[float, int, float]] = []  # (relative gap, transition, time)
    present = set(modes.tolist())
    values: dict[int, np.ndarray] = {}  # per surface: its indicator along the samples (transitions share them)
    for k, tr in enumerate(system.transitions):
        if system.mode_index(tr.source) not in present:
            continue  # the orbit never is in the mode this transition leaves
        s = system.surface_index(tr.surface)
        if s not in values:
            values[s] = np.array([flow.indicator(s, ti, xi, p) for ti, xi in zip(t.tolist(), x)])
        h = values[s]
        rng = float(h.max() - h.min())
        if rng == 0.0:
            continue
        src = system.mode_index(tr.source)
        sign = int(tr.direction)  # it fires when h becomes of this sign
        best, last = None, -2
        for i in range(1, len(t) - 1):
            if modes[i] != src:
                continue
            extremum = (h[i] >= h[i - 1] and h[i] >= h[i + 1]) if sign >= 0 else (h[i] <= h[i - 1] and h[i] <= h[i + 1])
            # from the side it would cross from, or on the surface to rounding (a grazing orbit itself)
            approaching_from_other_side = (h[i] * sign < 0 or abs(h[i]) <= 1e-9 * rng) if sign != 0 else True
            if not (extremum and approaching_from_other_side and abs(h[i]) <= relative_gap * rng):
                continue
            gap = abs(h[i]) / rng
            if i == last + 1 and best is not None:  # the same stretch: keep its sample nearest zero
                if gap < best[0]:
                    best = (gap, k, float(t[i]))
            else:
                if best is not None:
                    found.append(best)
                best = (gap, k, float(t[i]))
            last = i
        if best is not None:
            found.append(best)
    return [(k, t_k) for _, k, t_k in sorted(found, key=lambda c: c[0])]


#: A visit across a surface and back that lasts at most this fraction of the period is a touch: a visit's depth
#: grows like the square of its length, so one of 1e-6 of the period reaches about 1e-12 (relative) past the
#: surface, as far as a grazing orbit located to 1e-13 in its parameter does (a grazing of the corpus's
#: saturated controller, located to 8.6e-14, visits the saturated mode for 7e-9 of its period)
GRAZING_VISIT = 1e-6


def _without_grazing_visits(traj: Trajectory) -> list:
    """The trajectory's events without the visits to another mode that last no more than
    :data:`GRAZING_VISIT` of the trajectory's span and return to the mode they left through the surface they
    crossed: at a grazing, the location's accuracy decides whether the integration records such a visit across
    the surface touched, and the orbit is in the mode it does not leave."""
    events = list(traj.events)
    longest = GRAZING_VISIT * abs(traj.t1 - traj.t0)
    out, k = [], 0
    while k < len(events):
        e = events[k]
        if (k + 1 < len(events) and abs(events[k + 1].t - e.t) <= longest
                and events[k + 1].mode_to == e.mode_from and e.surface == events[k + 1].surface):
            k += 2
            continue
        out.append(e)
        k += 1
    return out


def growth_exponent(distances: np.ndarray, magnitudes: np.ndarray) -> float:
    """The exponent ``a`` of ``y ~ d^a``, fitted in log-log (-1/2 for the period map near a grazing).

    Parameters
    ----------
    distances : array_like
        Distances ``d`` to the grazing, positive.
    magnitudes : array_like
        The magnitudes ``y`` at those distances, positive.

    Returns
    -------
    float
        The least-squares slope of ``log y`` against ``log d``.

    References
    ----------
    Nordmark (1991), "Non-periodic motion caused by grazing incidence in an impact oscillator",
    J. Sound Vib. 145 (the square-root singularity).
    """
    slope, _ = np.polyfit(np.log(np.asarray(distances, float)), np.log(np.asarray(magnitudes, float)), 1)
    return float(slope)


__all__ = ["GRAZING_VISIT", "GrazingOrbit", "TangentialReturn", "grazing_candidates", "growth_exponent", "indicator_rate", "locate_grazing", "locate_tangential_return", "location_tolerances", "tangency_time"]
