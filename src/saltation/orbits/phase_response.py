"""Phase response curves of hybrid limit cycles: the gradient of the asymptotic phase along the orbit.

A stable autonomous limit cycle ``x(t)`` of period ``T`` gives every state near it an asymptotic phase
``theta``, measured here in time units (``theta(x(t)) = t``, modulo ``T``).  Its gradient along the
orbit, ``Z(t) = grad theta(x(t))``, is the infinitesimal phase response curve (PRC): a small kick ``dx``
at the time ``t`` advances the phase by ``Z(t) . dx``.  It is the periodic solution of the adjoint
equation, carried backward in time through the events by the transposed saltation matrices,

    ``Z' = -f_x^T Z``  on a smooth segment,    ``Z(t_e^-) = S^T Z(t_e^+)``  at an event,

(``S`` the event's saltation matrix, eq. (9) of *Fold bifurcations in discontinuous systems*, with a reset
``g``: ``S = g_x + (f+ - g_x f- - g_t) h_x / (h_x f- + h_t)``), normalised by ``Z^T f = 1``.  In closed
form ``Z(t)^T = Z(0)^T Phi(T, t)`` with ``Phi(T, t)`` the fundamental solution matrix from ``t`` to ``T``,
every saltation jump between them included, and ``Z(0)`` the left eigenvector of the monodromy matrix
``M`` for the trivial multiplier 1, with ``Z(0)^T f(x(0)) = 1`` (``f`` in the mode the orbit starts in,
after any event at ``t = 0``).  ``Z^T f = 1`` holds all along the orbit: on a smooth segment
``(Z^T f)' = -Z^T f_x f + Z^T f_x f = 0``, and at an event ``S f- = f+`` (eq. (9) with an autonomous
surface and reset), so ``Z(t_e^-)^T f- = Z(t_e^+)^T f+``.  It is checked at every point, with the
periodicity ``Z(T) = Z(0)``: a PRC that breaks either beyond the tolerance raises.

How it is computed, and why.  ``Phi(T, t) = M Phi(t, 0)^{-1}`` fails where a reset forgets (a singular
saltation matrix: a reset to a fixed value, the start of a sliding motion); the adjoint's own backward
integration would need the sliding field's Jacobian, which the engine keeps to itself.  Instead the
period is cut at the requested phases and at the orbit's events into pieces, each integrated forward
by the engine with the variational equation from the identity (:meth:`Flow.run` with ``variational``),
one after the other from the previous piece's end: each gives its transfer matrix
``P_k = Phi(t_(k+1), t_k)``, every saltation matrix inside it applied by the engine.  Then, from
``Z(T) = Z(0)`` backward, ``Z(t_k) = P_k^T Z(t_(k+1))``: only products of transfer matrices, never an
inverse, so singular saltation matrices are fine.  The cost is one integration of the period in as many
pieces as points and events (about 10 ms for a hundred points of a three-state orbit), and the backward
recursion is stable where the orbit is (the adjoint's non-trivial components decay backward at the rate the orbit
attracts).

At an event the PRC jumps: :attr:`PhaseResponse.values` holds the value just after it (the function is
right-continuous, as the orbit's mode is), and the event's two sides are :attr:`PhaseResponse.before` and
:attr:`PhaseResponse.after`.  On a sliding motion a perturbation off the switching surface returns to
it; to first order the motion absorbs it along ``f_a - f_b`` (the two fields), whichever side it was
pushed to: the sliding saltation matrix ``Pi = I - (f_a - f_b) h_x / (h_x (f_a - f_b))`` (the same from
both sides).  There ``Z(t)^T = Z_s(t)^T Pi(t)``, with ``Z_s`` the adjoint of the sliding motion: the
response to any kick, off the surface too; it is continuous at the start of a sliding motion and jumps
at its end.  Between the computed points, :meth:`PhaseResponse.at` interpolates by cubic Hermite
polynomials with the adjoint equation's exact derivatives (linearly on sliding motions, where they are
not known), never across an event.

:func:`phase_response_sensitivity` gives ``dZ/dp`` at a fixed phase by central differences of the PRCs
of the orbit re-converged at ``p +- h`` and ``p +- 2 h``, with a Richardson estimate of its error.

References
----------
A. T. Winfree (1980), *The Geometry of Biological Time*, Springer (phase response curves).
G. B. Ermentrout and D. H. Terman (2010), *Mathematical Foundations of Neuroscience*, Springer, ch. 8
(the adjoint method).  S. Shirasaka, W. Kurebayashi and H. Nakao (2017), "Phase reduction theory for
hybrid nonlinear oscillators", Phys. Rev. E 95, 012212 (the jump ``Z(t_e^-) = S^T Z(t_e^+)``).
Y. Park, K. M. Shaw, H. J. Chiel and P. J. Thomas (2018), "The infinitesimal phase response curves of
oscillators in piecewise smooth dynamical systems", Eur. J. Appl. Math. 29 (sliding motions).
R. I. Leine and D. H. Van Campen, *Fold bifurcations in discontinuous systems*, eq. (9) (the saltation
matrix).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from saltation.engine.flow import (
    EventKind,
    Flow,
    SwitchingEvent,
    Tolerances,
    Trajectory,
)
from saltation.errors import (
    ConvergenceError,
    InconsistentResultError,
    ModelError,
)
from saltation.orbits.records import PeriodicOrbit, event_ids, orbit_events
from saltation.orbits.single import TRIVIAL_MULTIPLIER_ACCURACY, ShootingProblem

_log = logging.getLogger(__name__)

#: The number of phases of :func:`phase_response`'s grid when neither ``points`` nor ``phases`` is given.
DEFAULT_POINTS = 100
#: The largest ``|Z^T f - 1|`` (and relative ``|Z(T) - Z(0)|``) a PRC may have by default: beyond it the result
#: contradicts itself and :func:`phase_response` raises.
DEFAULT_TOLERANCE = 1e-6
#: The smallest distance of a non-trivial multiplier from 1: closer, the phase is not isolated (a fold of the
#: orbit, or a family of orbits) and the left eigenvector of the monodromy for 1 is not defined.
SECOND_MULTIPLIER_GAP = 1e-6
#: Events and requested phases closer than this fraction of the period are one instant: the engine locates an
#: event to the integration's accuracy, not to the last bit, and a phase within it of an event's gets the
#: value just after the event.
SAME_INSTANT = 1e-9


@dataclass(frozen=True)
class PhaseResponse:
    """The infinitesimal phase response curve (PRC) of an autonomous periodic orbit.

    The phase is measured in time units: a kick ``dx`` at the phase ``phase`` (the time ``t0 + phase T``)
    advances the orbit by ``values[k] . dx`` time units, so ``values[k] . f(x(t_k)) = 1``.  Divide by the
    period for the phase in cycles (:meth:`in_cycles`).

    Attributes
    ----------
    system_name : str
        The model's name.
    state_names : tuple of str
        The states, in the order of the columns.
    period : float
        The orbit's period ``T``.
    t0 : float
        The time of phase 0: the orbit's ``t0``, where it passes its ``state0``.
    phases : ndarray, shape (m,)
        The phases of the points, in ``[0, 1)``, increasing.
    times : ndarray, shape (m,)
        ``t0 + phases T``.
    values : ndarray, shape (m, n)
        ``Z(t_k)``, the gradient of the asymptotic phase (in time units) at each point; just after the event
        at an event's time.
    states : ndarray, shape (m, n)
        The orbit's state ``x(t_k)`` at each point (after the event at an event's time).
    sliding : ndarray of bool, shape (m,)
        Whether each point lies on a sliding motion (there ``Z`` includes the sliding saltation matrix: the
        response to a kick off the surface, which the motion absorbs; see the module's docstring).
    event_phases : ndarray, shape (k,)
        The phases of the orbit's events, in ``[0, 1)`` (an event at the end of the period at 0).
    event_labels : tuple of str
        Each event's transition, or the sliding motion started or ended.
    before, after : ndarray, shape (k, n)
        ``Z`` just before and just after each event: ``before = S^T after``.
    normalisation_residual : float
        ``max |Z^T f - 1|`` over the points and the events' sides (``f`` the field of the mode there, the
        sliding field on a sliding motion).
    periodicity_residual : float
        ``|Z(0) - P^T Z(T)| / |Z(0)|`` with ``P^T`` the recursion over the whole period: how far the adjoint,
        carried back over one period from the left eigenvector, is from returning to it.
    closure_error : float
        ``|x(t0 + T) - x(t0)| / (1 + |x(t0)|)`` of the pieces integrated one after the other.
    multiplier_gap : float
        ``min |mu - 1|`` over the non-trivial multipliers (``inf`` for a one-state orbit): the left
        eigenvector's error is the monodromy's divided by it.
    accuracy : float
        The PRC's relative accuracy as far as it checks itself: the largest of the residuals above and the
        trivial multiplier's error divided by ``multiplier_gap``.
    """

    system_name: str
    state_names: tuple[str, ...]
    period: float
    t0: float
    phases: np.ndarray
    times: np.ndarray
    values: np.ndarray
    states: np.ndarray
    sliding: np.ndarray
    event_phases: np.ndarray
    event_labels: tuple[str, ...]
    before: np.ndarray
    after: np.ndarray
    normalisation_residual: float
    periodicity_residual: float
    closure_error: float
    multiplier_gap: float
    accuracy: float
    #: the interpolation's nodes: times, values, derivatives (nan where unknown), both sides of every event
    _nodes: tuple[np.ndarray, np.ndarray, np.ndarray] = field(repr=False, compare=False, default=None)

    def at(self, phase: float | Sequence[float] | np.ndarray) -> np.ndarray:
        """``Z`` at any phase, interpolated between the computed points.

        By cubic Hermite polynomials with the adjoint equation's derivatives ``Z' = -f_x^T Z`` at both ends
        (an error of order ``h^4`` in the spacing ``h`` of the points), linearly on sliding motions; never
        across an event (both sides of every event are nodes).  At an event's phase, the value just after it.
        A phase of the grid returns its computed value.

        Parameters
        ----------
        phase : float or array_like, shape (q,)
            Phases, in cycles; taken modulo 1.

        Returns
        -------
        ndarray, shape (n,) or (q, n)
            ``Z`` (time units) at each phase.

        Raises
        ------
        ModelError
            If a phase is not finite.
        """
        scalar = np.ndim(phase) == 0
        ph = np.asarray(phase, dtype=float).reshape(-1)
        if not np.all(np.isfinite(ph)):
            raise ModelError(f"phases must be finite, got {ph.tolist()}")
        ph = np.mod(ph, 1.0)
        t = self.t0 + ph * self.period
        nt, nz, ndz = self._nodes
        i = np.clip(np.searchsorted(nt, t, side="right") - 1, 0, len(nt) - 2)
        out = np.empty((len(t), nz.shape[1]))
        for q, (k, tq) in enumerate(zip(i.tolist(), t.tolist())):
            h = nt[k + 1] - nt[k]
            s = 0.0 if h <= 0.0 else min(max((tq - nt[k]) / h, 0.0), 1.0)
            a, b, da, db = nz[k], nz[k + 1], ndz[k], ndz[k + 1]
            if np.all(np.isfinite(da)) and np.all(np.isfinite(db)):
                h00, h10 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2
                h01, h11 = s * s * (3 - 2 * s), s * s * (s - 1)
                out[q] = h00 * a + h10 * h * da + h01 * b + h11 * h * db
            else:
                out[q] = (1 - s) * a + s * b
        return out[0] if scalar else out

    __call__ = at

    def in_cycles(self) -> np.ndarray:
        """The PRC with the phase in cycles: :attr:`values` divided by the period.

        Returns
        -------
        ndarray, shape (m, n)
            ``Z(t_k) / T``: a kick ``dx`` advances the phase by ``Z . dx / T`` cycles.
        """
        return self.values / self.period

    def to_numpy(self) -> np.ndarray:
        """The PRC as one table: the phase, then ``Z`` state by state.

        Returns
        -------
        ndarray, shape (m, 1 + n)
            Column 0 the phases, then one column per state (in :attr:`state_names` order), time units.
        """
        return np.column_stack([self.phases, self.values])

    def __repr__(self) -> str:
        return (f"PhaseResponse({self.system_name!r}, T={self.period:.10g}, {len(self.phases)} points, "
                f"{len(self.event_phases)} events, states {list(self.state_names)}, accuracy {self.accuracy:.1e})")


@dataclass(frozen=True)
class PhaseResponseSensitivity:
    """The derivative of a PRC with respect to a parameter, at fixed phases.

    Attributes
    ----------
    parameter : str
        The parameter's name.
    value : float
        Its value at the orbit.
    step : float
        The difference step ``h``.
    phases : ndarray, shape (m,)
        The phases, in ``[0, 1)``; phase 0 on the section through the orbit's ``state0`` normal to the flow
        there (where the re-converged orbits start).
    derivative : ndarray, shape (m, n)
        ``dZ/dp`` at each phase (time units per unit state and parameter), Richardson's extrapolation of the
        central differences at ``h`` and ``2 h``; ``nan`` at a phase that an event's phase crosses between
        ``p - 2 h`` and ``p + 2 h`` (the PRC jumps there: it has no derivative at a fixed phase).
    period_derivative : float
        ``dT/dp``, by the same differences.
    error : ndarray, shape (m, n)
        ``|D(h) - D(2 h)| / 3``, Richardson's estimate of the central difference ``D(h)``'s error, which bounds
        the extrapolated value's where the differences are in their asymptotic regime (``nan`` with it).
    response : PhaseResponse
        The PRC at the orbit itself.
    """

    parameter: str
    value: float
    step: float
    phases: np.ndarray
    derivative: np.ndarray
    period_derivative: float
    error: np.ndarray
    response: PhaseResponse

    def __repr__(self) -> str:
        return (f"PhaseResponseSensitivity(d/d{self.parameter} at {self.value:.10g}, h={self.step:.3g}, "
                f"{len(self.phases)} points, max error {float(np.nanmax(self.error, initial=0.0)):.1e})")


# -- the orbit and its flow ---------------------------------------------------------------------------------

def _flow_and_tolerances(orbit: PeriodicOrbit, flow: Flow | None, tolerances: Tolerances | None) -> tuple[Flow, Tolerances]:
    """The flow the orbit was found with (or the one given), and the tolerances to integrate with."""
    problem = getattr(orbit, "problem", None)
    if flow is None:
        if problem is None:
            raise ModelError(f"the orbit of {orbit.system_name!r} does not know the problem that found it: pass its "
                             "flow (flow=Flow(model))")
        flow = problem.flow
    if flow.system.name != orbit.system_name:
        raise ModelError(f"the flow is of model {flow.system.name!r}, the orbit of {orbit.system_name!r}")
    if tolerances is None:
        tolerances = getattr(problem, "tolerances", None) or flow.tolerances
    return flow, tolerances


def _check_orbit(orbit: PeriodicOrbit, flow: Flow) -> None:
    """Refuse the orbits without an isolated asymptotic phase to compute (forced, backward, not converged)."""
    name = orbit.system_name
    if not orbit.autonomous or not flow.system.is_autonomous:
        raise ModelError(
            f"the orbit of {name!r} is forced (its period is the forcing period): a forced orbit's phase is the "
            "forcing's, fixed by the clock, so it has no asymptotic phase and no phase response curve; "
            "phase_response takes autonomous orbits only")
    if orbit.backward:
        raise ModelError(
            f"the orbit of {name!r} was computed in backward time (an orbit that attracts only backward in time): "
            "its phase response in forward time is not defined by the adjoint of a forward monodromy; "
            "phase_response takes orbits computed forward (backward=False)")
    if not orbit.converged:
        raise ModelError(f"the orbit of {name!r} is not converged (residual {orbit.residual_norm:.3g}): no phase "
                         "response of an orbit that is not one")
    if not (orbit.period > 0.0 and math.isfinite(orbit.period)):
        raise ModelError(f"the orbit of {name!r} has the period {orbit.period!r}, not positive and finite")


def _phase_grid(points: int | None, phases: Sequence[float] | np.ndarray | None) -> np.ndarray:
    """The requested phases, checked: ``points`` equally spaced from 0, or ``phases`` modulo 1, sorted."""
    if phases is not None:
        if points is not None:
            raise ModelError("give either points (an equally spaced grid) or phases, not both")
        ph = np.asarray(phases, dtype=float).reshape(-1)
        if ph.size == 0 or not np.all(np.isfinite(ph)):
            raise ModelError(f"phases must be finite numbers, at least one, got {np.asarray(phases).tolist()}")
        return np.unique(np.mod(ph, 1.0))
    points = DEFAULT_POINTS if points is None else points
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or not 1 <= points <= 100_000:
        raise ModelError(f"points must be an integer from 1 to 100000, got {points!r}")
    return np.arange(int(points)) / int(points)


def _left_eigenvector(M: np.ndarray, f0: np.ndarray, orbit: PeriodicOrbit) -> tuple[np.ndarray, float, float]:
    """``Z(0)``: the left eigenvector of ``M`` for 1 with ``Z^T f0 = 1``; the multipliers' gap to 1 and the
    trivial multiplier's error ``|M f0 - f0| / |f0|``."""
    n = len(f0)
    norm = float(np.linalg.norm(f0))
    name = orbit.system_name
    if not (norm > 0.0 and math.isfinite(norm)):
        raise ModelError(f"the orbit of {name!r} does not move at its state0 (|f| = {norm:g}): no phase to respond")
    trivial = float(np.linalg.norm(M @ f0 - f0)) / norm
    if not trivial <= TRIVIAL_MULTIPLIER_ACCURACY:
        raise InconsistentResultError(
            f"the monodromy of the orbit of {name!r} does not map the flow direction to itself: |M f - f| / |f| = "
            f"{trivial:.2e} > {TRIVIAL_MULTIPLIER_ACCURACY:g}, so its trivial multiplier is not 1 to the orbit's "
            "accuracy and no phase response can be normalised on it")
    # the non-trivial multipliers: the monodromy on the hyperplane normal to f0 (Householder basis)
    n_dir = f0 / norm
    v = n_dir.copy()
    v[0] += math.copysign(1.0, v[0] if v[0] != 0.0 else 1.0)
    Q = (np.eye(n) - 2.0 * np.outer(v, v) / float(v @ v))[:, 1:]
    others = np.linalg.eigvals(Q.T @ M @ Q) if n > 1 else np.array([])
    gap = float(np.min(np.abs(others - 1.0))) if len(others) else math.inf
    if not gap > SECOND_MULTIPLIER_GAP:
        raise ModelError(
            f"the orbit of {name!r} has a second Floquet multiplier at 1 (|mu - 1| = {gap:.2e} <= "
            f"{SECOND_MULTIPLIER_GAP:g}, multipliers {np.round(others, 8).tolist()}): its asymptotic phase is not "
            "isolated (a fold of the orbit, or a family of orbits), so it has no phase response curve")
    # [[M^T - I, f0], [f0^T, 0]] [z; s] = [0; 1]: regular exactly where 1 is a simple multiplier
    A = np.zeros((n + 1, n + 1))
    A[:n, :n] = M.T - np.eye(n)
    A[:n, n] = f0
    A[n, :n] = f0
    rhs = np.zeros(n + 1)
    rhs[n] = 1.0
    z = np.linalg.solve(A, rhs)
    return z[:n], gap, trivial


# -- the pieces ---------------------------------------------------------------------------------------------

@dataclass
class _Piece:
    """One piece of the period: from a node to the next, integrated forward with its transfer matrix."""

    t: float  # the node's time
    x: np.ndarray  # the state at the node (after the events at its start)
    mode: str  # the mode the piece starts in
    run: Trajectory  # from the node (or its last event) to the next node
    jumps: list[SwitchingEvent]  # transitions at the node's instant, before the piece (re-run from after them)
    t_run: float  # the time the run starts: the node's, or its last jump's
    sliding: tuple[str, str, str] | None  # (surface, mode a, mode b) when it starts on a sliding motion


def _instant(t: float, T: float) -> float:
    """How close two times are to be one instant (see :data:`SAME_INSTANT`)."""
    return SAME_INSTANT * max(T, abs(t))


def _piece(flow: Flow, x: np.ndarray, ta: float, tb: float, p: np.ndarray, mode: str | None, tol: Tolerances,
           T: float) -> _Piece:
    """Integrate from the node ``ta`` to ``tb``; a transition at the node's instant is applied before the
    piece (the piece is run again from after it), a sliding motion starting there is kept in it."""
    jumps: list[SwitchingEvent] = []
    t = ta
    for _ in range(16):  # (coinciding events at a corner of surfaces: one after the other)
        run = flow.run(x, t, tb, p, mode0=mode, variational=True, tolerances=tol)
        first = run.events[0] if run.events else None
        if first is None or first.kind != EventKind.TRANSITION or first.t - ta > _instant(ta, T):
            break
        jumps.append(first)
        x, mode, t = np.array(first.x_plus), first.mode_to, first.t
    else:
        raise InconsistentResultError(f"more than 16 transitions at one instant t = {ta:.12g} of the orbit of "
                                      f"{flow.system.name!r}: the events chatter")
    sliding = None
    if first is not None and first.kind == EventKind.SLIDING_START and first.t - ta <= _instant(ta, T):
        sliding = (first.surface, first.mode_from, first.mode_to)
    return _Piece(ta, np.array(x), run.mode0, run, jumps, t, sliding)


def _sliding_field(flow: Flow, surface: str, a: str, b: str, t: float, x: np.ndarray, p: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Filippov's sliding field on ``surface`` between modes ``a`` and ``b`` at ``x``, and the sliding
    saltation matrix ``Pi = I - (f_a - f_b) h_x / (h_x (f_a - f_b))``."""
    fa, fb = flow.vector_field(a, t, x, p), flow.vector_field(b, t, x, p)
    hx, ht, _ = flow.indicator_gradient(surface, t, x, p)
    la, lb = float(hx @ fa) + ht, float(hx @ fb) + ht
    alpha = la / (la - lb)
    fs = fa + alpha * (fb - fa)
    Pi = np.eye(len(x)) - np.outer(fa - fb, hx) / (la - lb)
    return fs, Pi


def _at(t: float, node: float, T: float) -> bool:
    """Whether the time ``t`` is the node's instant."""
    return abs(t - node) <= _instant(node, T)


def _restart_event(e: SwitchingEvent, traj: Trajectory) -> bool:
    """Whether an event of the orbit's log is the restart of a sliding motion at its start (not an event)."""
    return (e.kind == EventKind.SLIDING_START and e.t == traj.t0 and traj.sliding_at_end
            and any(q.kind == EventKind.SLIDING_START and q.surface == e.surface and q.t > e.t for q in traj.events))


def _restarts(pieces: list[_Piece], k: int, traj: Trajectory) -> bool:
    """Whether piece ``k`` starts inside a sliding motion that the one before it (or the orbit's end) was on."""
    return pieces[k].sliding is not None and (pieces[k - 1].run.sliding_at_end if k else traj.sliding_at_end)


def _close_seam(flow: Flow, orbit: PeriodicOrbit, pieces: list[_Piece], p: np.ndarray, tol: Tolerances
                ) -> list[SwitchingEvent]:
    """Make the pieces' seam at ``t0 + T`` the orbit's: the events the orbit logs at the end of its period (its
    shot closed by the seam rule, :mod:`saltation.orbits.seam`) and at its start, each once.

    The last piece may fire an event at its end that the orbit logs at its start (the first piece's jumps): it is
    run again without that transition.  An event the orbit logs at its end that the last piece does not fire is
    applied after it (its reset and saltation matrix) and returned."""
    traj, T = orbit.trajectory, float(orbit.period)
    t_end = float(orbit.t0) + T
    last = pieces[-1]
    fired = [e for e in last.run.events if _at(e.t, t_end, T)]
    logged_end = [e for e in traj.events if _at(e.t, t_end, T)]
    twice = {e.transition for e in fired if e.kind == EventKind.TRANSITION} & {e.transition for e in pieces[0].jumps}
    if twice and not any(e.transition in twice for e in logged_end):
        run = flow.run(last.x, last.t_run, t_end, p, mode0=last.mode, variational=True, tolerances=tol, disabled=sorted(twice))
        if len(run.events) != len(last.run.events) - len([e for e in fired if e.transition in twice]):
            raise InconsistentResultError(
                f"the orbit of {flow.system.name!r} crosses a switching surface at the end of its period and "
                "again inside its last piece: its phase response cannot tell the seam's crossing from the other")
        last.run = run
        fired = [e for e in run.events if _at(e.t, t_end, T)]
    missing = [e for e in logged_end if e.signature not in {q.signature for q in fired}]
    seam = []
    x = np.array(last.run.x1)
    for e in missing:
        if e.kind != EventKind.TRANSITION:
            raise InconsistentResultError(
                f"the orbit of {flow.system.name!r} ends its period on a sliding motion's start or end that the "
                "pieces of its phase response do not meet: move its start off the switching surface")
        x_plus, S, _ = flow.transition_jump(e.transition, t_end, x, p)
        seam.append(SwitchingEvent(t_end, e.kind, e.transition, e.surface, e.mode_from, e.mode_to, x, x_plus, S))
        x = x_plus
    return seam


def _sliding_exit(flow: Flow, piece: _Piece, e: SwitchingEvent, t_end: float, z_end: np.ndarray,
                  sliding: tuple[str, str, str], p: np.ndarray, tol: Tolerances, T: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """``Z`` just after and just before the end ``e`` of a sliding motion inside a piece: after, by a run from
    the exit to the piece's end (the exit mode's transitions across the sliding surface off: its field is
    tangent to the surface there); before, ``Pi^T S^T`` of it (the motion absorbs a kick off the surface)."""
    system = flow.system
    off = [i for i, tr in enumerate(system.transitions) if tr.source == e.mode_to and tr.surface == e.surface]
    side = flow.run(e.x_plus, e.t, t_end, p, mode0=e.mode_to, variational=True, tolerances=tol, disabled=off)
    later = [q for q in piece.run.events if q.t > e.t + _instant(e.t, T)]
    if [q.signature for q in side.events] != [q.signature for q in later]:
        raise InconsistentResultError(
            f"the orbit of {system.name!r} leaves its sliding motion on {e.surface!r} at t = {e.t:.12g}, and the "
            "motion run on from there meets other events than the orbit: the exit is too close to a tangency for "
            "its phase response at these tolerances")
    after = side.monodromy.T @ z_end
    _, Pi = _sliding_field(flow, *sliding, e.t, e.x_minus, p)
    return after, Pi.T @ (e.saltation.T @ after)


def _event_label(flow: Flow, e: SwitchingEvent) -> str:
    if e.kind == EventKind.TRANSITION:
        return flow.system.transitions[e.transition].label
    if e.kind == EventKind.SLIDING_START:
        return f"slide on {e.surface} ({e.mode_from}|{e.mode_to})"
    return f"leave {e.surface} sliding -> {e.mode_to}"


def phase_response(
    orbit: PeriodicOrbit,
    *,
    points: int | None = None,
    phases: Sequence[float] | np.ndarray | None = None,
    flow: Flow | None = None,
    tolerances: Tolerances | None = None,
    tol: float = DEFAULT_TOLERANCE,
) -> PhaseResponse:
    """The infinitesimal phase response curve of an autonomous periodic orbit, through its events.

    ``Z(t)^T = Z(0)^T Phi(T, t)``, with ``Z(0)`` the left eigenvector of the monodromy matrix for the trivial
    multiplier 1 normalised by ``Z(0)^T f(x(0)) = 1``, and ``Phi(T, t)`` the fundamental solution matrix from
    ``t`` to the period's end with the saltation matrix of every event (eq. (9)): the periodic solution of
    the adjoint equation ``Z' = -f_x^T Z`` with ``Z(t_e^-) = S^T Z(t_e^+)`` at each event.  The phase is in
    time units (``Z^T f = 1``); see the module's docstring for the method, sliding motions and the checks.

    Parameters
    ----------
    orbit : PeriodicOrbit
        An autonomous orbit computed forward in time (:func:`~saltation.orbits.start.find_periodic_orbit`),
        stable or not.
    points : int, optional
        The number of equally spaced phases ``k / points`` (:data:`DEFAULT_POINTS` by default).
    phases : array_like, optional
        The phases to compute instead (cycles, taken modulo 1; sorted, duplicates dropped).
    flow : Flow, optional
        The model's flow (the orbit's problem's by default; needed for an orbit that does not know it).
    tolerances : Tolerances, optional
        Integration tolerances (the orbit's problem's, or the flow's, by default).
    tol : float
        The largest normalisation residual ``|Z^T f - 1|``, periodicity residual and closure error accepted.

    Returns
    -------
    PhaseResponse
        ``Z`` at the phases, both sides of every event, and the residuals it was checked with.

    Raises
    ------
    ModelError
        For an orbit that has no phase response: a forced orbit, one computed in backward time, one not
        converged, one with a second multiplier at 1 (within :data:`SECOND_MULTIPLIER_GAP`: no isolated phase);
        for an orbit that does not know its flow (and none given), or bad ``points``, ``phases`` or ``tol``.
    InconsistentResultError
        If the orbit's trivial multiplier is not 1 to :data:`~saltation.orbits.single.TRIVIAL_MULTIPLIER_ACCURACY`,
        if the pieces integrated one after the other do not reproduce the orbit's events, or if the result
        breaks ``Z^T f = 1``, ``Z(T) = Z(0)`` or the orbit's closure by more than ``tol``.
    IntegrationError
        If a piece's integration fails.

    References
    ----------
    Ermentrout and Terman (2010), *Mathematical Foundations of Neuroscience*, Springer, ch. 8.  Shirasaka,
    Kurebayashi and Nakao (2017), Phys. Rev. E 95, 012212.  Park, Shaw, Chiel and Thomas (2018),
    Eur. J. Appl. Math. 29.  Leine and Van Campen, *Fold bifurcations in discontinuous systems*, eq. (9).
    """
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not (0.0 < tol < 1.0):
        raise ModelError(f"tol must be a number in (0, 1), got {tol!r}")
    flow, tolerances = _flow_and_tolerances(orbit, flow, tolerances)
    _check_orbit(orbit, flow)
    grid = _phase_grid(points, phases)
    system = flow.system
    n = system.n
    p = np.asarray(orbit.parameters, dtype=float)
    T, t0 = float(orbit.period), float(orbit.t0)
    traj = orbit.trajectory
    f0 = np.asarray(traj.velocity_end, dtype=float)
    z0, gap, trivial = _left_eigenvector(np.asarray(orbit.monodromy, dtype=float), f0, orbit)

    # the nodes: the requested phases and the orbit's transitions and starts of sliding motions (an event at the
    # end of the period at phase 0); a phase within an instant of an event's is that event's node
    cycle = orbit_events(traj)
    event_times = sorted({t0 + ((e.t - t0) % T if abs(e.t - t0 - T) > _instant(e.t, T) else 0.0)
                          for e in cycle if e.kind != EventKind.SLIDING_END})
    node_times: list[float] = []
    for t in sorted([*event_times, *(t0 + grid * T).tolist(), t0]):
        if not node_times or t - node_times[-1] > _instant(t, T):
            node_times.append(t)
        elif t in event_times and len(node_times) > 1:
            node_times[-1] = t  # (an event's time rather than a phase's within the same instant; t0 stays)
    if len(node_times) > 1 and t0 + T - node_times[-1] <= _instant(t0 + T, T):
        node_times.pop()  # the end of the period is phase 0
    at_nodes = np.asarray(node_times)  # each requested phase's node: the nearest, modulo the period
    grid_nodes = [int(np.argmin(np.abs(np.mod(at_nodes - t0 - phi * T + 0.5 * T, T) - 0.5 * T))) for phi in grid.tolist()]

    # forward: the pieces one after the other, each from where the previous ended, from the orbit's own start
    pieces: list[_Piece] = []
    x = np.array(orbit.state0, dtype=float)
    mode = orbit.mode0 or traj.mode0
    ends = [*node_times[1:], t0 + T]
    for ta, tb in zip(node_times, ends):
        piece = _piece(flow, x, ta, tb, p, mode, tolerances, T)
        pieces.append(piece)
        x, mode = piece.run.x1, piece.run.mode1
        mode = None if "|" in mode else mode
    seam = _close_seam(flow, orbit, pieces, p, tolerances)
    x_end = seam[-1].x_plus if seam else pieces[-1].run.x1
    closure = float(np.linalg.norm(x_end - orbit.state0)) / (1.0 + float(np.linalg.norm(orbit.state0)))

    # the events met, against the orbit's (a sliding motion's restart at a node inside it is not an event)
    met: list[SwitchingEvent] = [*seam]
    for k, piece in enumerate(pieces):
        met.extend(piece.jumps)
        met.extend(piece.run.events[1:] if _restarts(pieces, k, traj) else piece.run.events)
    if sorted(e.signature for e in met) != sorted(e.signature for e in traj.events if not _restart_event(e, traj)):
        raise InconsistentResultError(
            f"the orbit of {system.name!r} integrated in {len(pieces)} pieces meets the events "
            f"{[_event_label(flow, e) for e in met]}, not the orbit's {[_event_label(flow, e) for e in cycle]}: "
            "the orbit is too close to a grazing or a corner for its phase response at these tolerances")

    # backward: from Z = Z(0) where the orbit starts (after the events at the end of its period, before those at
    # its start), Z(t_k) = P_k^T Z(t_(k+1)), each P_k with the saltation matrices of the events inside the piece
    zl = z0.copy()
    for e in reversed(seam):  # (events at the end of the period that the last piece did not meet)
        zl = e.saltation.T @ zl
    right = np.empty((len(pieces), n))
    left_of_next = np.empty((len(pieces), n))  # the value each piece's transfer matrix was applied to
    for k in range(len(pieces) - 1, -1, -1):
        left_of_next[k] = zl
        right[k] = pieces[k].run.monodromy.T @ zl
        zl = right[k]
        for e in reversed(pieces[k].jumps):
            zl = e.saltation.T @ zl
    periodicity = float(np.linalg.norm(zl - z0)) / float(np.linalg.norm(z0))

    # the nodes' values, states, fields and derivatives; both sides of every event
    nodes: list[tuple[float, int, np.ndarray, np.ndarray]] = []  # (time, 0 before an event or 1 after, Z, dZ/dt)
    residuals: list[float] = []
    events_out: list[tuple[float, str, np.ndarray, np.ndarray]] = []
    node_sliding = np.zeros(len(pieces), dtype=bool)
    node_states = np.empty((len(pieces), n))
    unknown = np.full(n, np.nan)  # the derivative on a sliding motion

    def derivative(m: str, t: float, xs: np.ndarray, z: np.ndarray) -> np.ndarray:
        return -flow.vector_field_jacobian(m, t, xs, p).T @ z

    def check(z: np.ndarray, f: np.ndarray) -> None:
        residuals.append(abs(float(z @ f) - 1.0))

    sliding_now: tuple[str, str, str] | None = None
    covered = 0  # the orbit's events met at their nodes' instants (or as a sliding motion's end)
    end_events = [e for e in pieces[-1].run.events if _at(e.t, t0 + T, T)] + seam
    for k, piece in enumerate(pieces):
        t, z = piece.t, right[k]
        node_states[k] = piece.x
        if piece.sliding is not None:
            sliding_now = piece.sliding
            fs, _ = _sliding_field(flow, *sliding_now, t, piece.x, p)
            check(z, fs)
            dz = unknown
            node_sliding[k] = True
        else:
            check(z, flow.vector_field(piece.mode, t, piece.x, p))
            dz = derivative(piece.mode, t, piece.x, z)
        # the events at this node's instant: the previous piece's last ones, this piece's jumps, a sliding start
        before = end_events if k == 0 else [e for e in pieces[k - 1].run.events if _at(e.t, t, T)]
        at_node = [e for e in before if e.kind != EventKind.SLIDING_END] + piece.jumps
        if piece.sliding is not None and not _restarts(pieces, k, traj):
            at_node.append(piece.run.events[0])
        if at_node:
            zb = z
            for e in reversed(at_node):
                zb = e.saltation.T @ zb
            first = at_node[0]
            check(zb, flow.vector_field(first.mode_from, first.t, first.x_minus, p))
            nodes.append((t, 0, zb, derivative(first.mode_from, first.t, first.x_minus, zb)))
            events_out.append((t, " + ".join(_event_label(flow, e) for e in at_node), zb, z))
            covered += len(at_node)
        nodes.append((t, 1, z, dz))
        # a sliding motion's end inside the piece: its right side by a run from it, its left by Pi^T S^T
        for e in piece.run.events:
            if e.kind != EventKind.SLIDING_END or sliding_now is None or _at(e.t, ends[k], T):
                continue
            za, zb = _sliding_exit(flow, piece, e, ends[k], left_of_next[k], sliding_now, p, tolerances, T)
            fs, _ = _sliding_field(flow, *sliding_now, e.t, e.x_minus, p)
            check(zb, fs)
            check(za, flow.vector_field(e.mode_to, e.t, e.x_plus, p))
            nodes.append((e.t, 0, zb, unknown))
            nodes.append((e.t, 1, za, derivative(e.mode_to, e.t, e.x_plus, za)))
            events_out.append((e.t, _event_label(flow, e), zb, za))
            covered += 1
        if not piece.run.sliding_at_end:
            sliding_now = None
    # the end of the period from the left, before the events at its end
    z_end = z0
    for e in reversed(end_events):
        z_end = e.saltation.T @ z_end
    last = pieces[-1].run
    if end_events:
        nodes.append((t0 + T, 0, z_end, derivative(end_events[0].mode_from, t0 + T, end_events[0].x_minus, z_end)))
    else:
        nodes.append((t0 + T, 0, z_end, unknown if last.sliding_at_end else derivative(last.mode1, t0 + T, last.x1, z_end)))
    if covered != len(cycle):
        raise InconsistentResultError(
            f"the orbit of {system.name!r} integrated in pieces meets {len(cycle) - covered} of its events away from "
            f"the instants its own log gives them (by more than {SAME_INSTANT:g} of the period): tighten the "
            "integration tolerances for its phase response")
    nodes.sort(key=lambda q: (q[0], q[1]))
    normalisation = max(residuals)
    accuracy = max(normalisation, periodicity, closure, trivial / gap if math.isfinite(gap) else 0.0)
    _log.debug("phase response of %r: %d pieces, %d events, normalisation %.1e, periodicity %.1e, closure %.1e",
                 system.name, len(pieces), len(cycle), normalisation, periodicity, closure)
    for what, value in (("normalisation |Z^T f - 1|", normalisation), ("periodicity |Z(T) - Z(0)| / |Z(0)|", periodicity),
                        ("closure |x(T) - x(0)| / (1 + |x(0)|)", closure)):
        if not value <= tol:
            raise InconsistentResultError(
                f"the phase response of the orbit of {system.name!r} breaks its {what}: {value:.2e} > tol = {tol:g} "
                f"(multiplier gap {gap:.2e}, trivial multiplier error {trivial:.2e}); tighten the integration "
                "tolerances or re-converge the orbit")
    events_out.sort(key=lambda q: q[0])
    return PhaseResponse(
        system_name=system.name,
        state_names=tuple(system.state_names),
        period=T,
        t0=t0,
        phases=grid.copy(),
        times=t0 + grid * T,
        values=right[grid_nodes].copy(),
        states=node_states[grid_nodes].copy(),
        sliding=node_sliding[grid_nodes].copy(),
        event_phases=np.array([(q[0] - t0) / T for q in events_out]),
        event_labels=tuple(q[1] for q in events_out),
        before=np.array([q[2] for q in events_out]).reshape(-1, n),
        after=np.array([q[3] for q in events_out]).reshape(-1, n),
        normalisation_residual=normalisation,
        periodicity_residual=periodicity,
        closure_error=closure,
        multiplier_gap=gap,
        accuracy=accuracy,
        _nodes=(np.array([q[0] for q in nodes]), np.array([q[2] for q in nodes]), np.array([q[3] for q in nodes])),
    )


#: The difference step of :func:`phase_response_sensitivity`, relative to ``max(1, |p|)``, when none is given:
#: the central differences' truncation error (of order ``h^2``) and the PRCs' own noise divided by ``h`` (of
#: order ``rtol / h``) balance near it at the default tolerances.
SENSITIVITY_STEP = 1e-3


def phase_response_sensitivity(
    orbit: PeriodicOrbit,
    parameter: str,
    *,
    step: float | None = None,
    points: int | None = None,
    phases: Sequence[float] | np.ndarray | None = None,
    flow: Flow | None = None,
    tolerances: Tolerances | None = None,
    tol: float = DEFAULT_TOLERANCE,
    newton_tol: float = 1e-12,
) -> PhaseResponseSensitivity:
    """The derivative ``dZ/dp`` of the phase response curve with respect to a parameter, at fixed phases.

    By differences of the PRCs (:func:`phase_response`) of the orbit re-converged at ``p +- h`` and
    ``p +- 2 h``: the central differences ``D(h)`` and ``D(2 h)`` combined by Richardson's extrapolation,
    ``(4 D(h) - D(2 h)) / 3`` (an error of order ``h^4``), with ``|D(h) - D(2 h)| / 3``, the estimate of the
    central difference's own error, as the stated error.  Phase 0 of each orbit is where it crosses the
    hyperplane through the orbit's ``state0`` normal to the field there (the shooting's phase condition), and
    the phases are in cycles, so that ``dZ/dp`` is taken at a fixed fraction of the (changing) period.

    Parameters
    ----------
    orbit : PeriodicOrbit
        An autonomous orbit computed forward in time.
    parameter : str
        The parameter's name.
    step : float, optional
        The difference step ``h`` (``SENSITIVITY_STEP * max(1, |p|)`` by default).
    points, phases
        The phases, as for :func:`phase_response`.
    flow : Flow, optional
        The model's flow (the orbit's problem's by default).
    tolerances : Tolerances, optional
        Integration tolerances of the orbits and their PRCs.
    tol : float
        As for :func:`phase_response`.
    newton_tol : float
        Newton's tolerance for the re-converged orbits.

    Returns
    -------
    PhaseResponseSensitivity
        ``dZ/dp`` and ``dT/dp`` at the phases, the error estimate, and the PRC at the orbit.

    Raises
    ------
    ModelError
        For an unknown parameter, a step that is not positive and finite, or an orbit :func:`phase_response`
        refuses.
    InconsistentResultError
        If an orbit at ``p +- h`` or ``p +- 2 h`` has another event sequence (a non-smooth point lies within
        ``2 h``: no derivative there), or its phase origin moves (the orbit's ``state0`` lies next to an event),
        or a PRC breaks its checks.
    ConvergenceError
        If an orbit does not re-converge at ``p +- h`` or ``p +- 2 h``.

    References
    ----------
    L. F. Richardson (1911), "The approximate arithmetical solution by finite differences of physical problems",
    Phil. Trans. R. Soc. A 210 (the extrapolation).
    """
    flow, tolerances = _flow_and_tolerances(orbit, flow, tolerances)
    _check_orbit(orbit, flow)
    system = flow.system
    index = system.parameter_index(parameter)
    p = np.asarray(orbit.parameters, dtype=float)
    value = float(p[index])
    h = SENSITIVITY_STEP * max(1.0, abs(value)) if step is None else step
    if isinstance(h, bool) or not isinstance(h, (int, float)) or not (0.0 < h < math.inf):
        raise ModelError(f"step must be a positive finite number, got {step!r}")
    h = float(h)
    grid = _phase_grid(points, phases)
    base = phase_response(orbit, phases=grid, flow=flow, tolerances=tolerances, tol=tol)
    problem = getattr(orbit, "problem", None)
    mode0 = orbit.mode0 if problem is None or problem.mode0 is not None else None
    ids = event_ids(orbit.trajectory)
    responses = {}
    for k in (-2, -1, 1, 2):
        values = dict(zip(system.parameter_names, p.tolist()))
        values[parameter] = value + k * h
        shooting = ShootingProblem(flow, values, tolerances=tolerances, mode0=mode0)
        try:
            found = shooting.solve(shooting.pack(orbit.state0, orbit.period), tol=newton_tol)
        except ConvergenceError as exc:
            raise ConvergenceError(f"the orbit of {system.name!r} does not re-converge at {parameter} = "
                                   f"{value + k * h:.12g} (step {h:g}): {exc}", exc.residuals) from exc
        if shooting.x_ref is None or not np.array_equal(shooting.x_ref, np.asarray(orbit.state0, dtype=float)):
            raise InconsistentResultError(
                f"the orbit of {system.name!r} at {parameter} = {value + k * h:.12g} starts elsewhere than the "
                "section through its state0 (the state lies next to an event, and shooting moved it): its phase "
                "origin is not the orbit's; re-converge the orbit with its start away from the events")
        if event_ids(found.trajectory) != ids:
            raise InconsistentResultError(
                f"the orbit of {system.name!r} changes its events between {parameter} = {value:.12g} and "
                f"{value + k * h:.12g} ({list(orbit.event_labels)} -> {list(found.event_labels)}): a non-smooth "
                f"point lies within {abs(k) * h:g}, where the PRC has no derivative; take a smaller step")
        responses[k] = phase_response(found, phases=grid, flow=flow, tolerances=tolerances, tol=tol)
    d1 = (responses[1].values - responses[-1].values) / (2 * h)
    d2 = (responses[2].values - responses[-2].values) / (4 * h)
    # a phase that an event crosses between p - 2 h and p + 2 h: the PRC jumps there, no derivative
    moving = np.array([r.event_phases for r in (base, *responses.values())])
    for lo, hi in zip(moving.min(axis=0).tolist(), moving.max(axis=0).tolist()):
        crossed = (grid >= lo) & (grid <= hi) if hi - lo < 0.5 else (grid >= hi) | (grid <= lo)
        d1[crossed] = d2[crossed] = np.nan
    t1 = (responses[1].period - responses[-1].period) / (2 * h)
    t2 = (responses[2].period - responses[-2].period) / (4 * h)
    _log.debug("dZ/d%s of %r by differences at h = %g: Richardson estimate %.1e", parameter, system.name, h,
                 float(np.max(np.abs(d1 - d2))) / 3.0)
    return PhaseResponseSensitivity(
        parameter=parameter,
        value=value,
        step=h,
        phases=grid.copy(),
        derivative=(4.0 * d1 - d2) / 3.0,
        period_derivative=(4.0 * t1 - t2) / 3.0,
        error=np.abs(d1 - d2) / 3.0,
        response=base,
    )


__all__ = ["DEFAULT_POINTS", "DEFAULT_TOLERANCE", "SAME_INSTANT", "SECOND_MULTIPLIER_GAP", "SENSITIVITY_STEP",
           "PhaseResponse", "PhaseResponseSensitivity", "phase_response", "phase_response_sensitivity"]
