"""Special points as one periodic-orbit problem with conditions attached.

A special point of a periodic orbit is the orbit's own problem (periodicity, and for an autonomous
orbit the phase condition: :meth:`saltation.orbits.shooting.ShootingProblem.periodicity`) with extra
equations, each a :class:`Condition`, and as many parameters (or extra unknowns) freed to close the
system.  The COCO ``hspo`` idea: an orbit problem plus zero functions.

Each condition reads one shot's pieces (:class:`Shot`): the state, the fundamental solution matrix and
the parameter sensitivities at the instant it looks at, and returns its value and its exact derivatives
with respect to the unknowns and the parameters (:class:`Rows`).  The shot is split at that instant (the
second piece carries on from the first, :meth:`saltation.engine.flow.Flow.run` with ``phi0``/``psi0``), so
one integration of the period per free parameter gives the whole Jacobian.

The conditions:

* :class:`Tangency`: a grazing.  ``h(t_g, x(t_g)) = 0`` and ``L(t_g, x(t_g)) = h_x f + h_t = 0`` with the
  instant ``t_g`` an unknown, on the virtual orbit that passes the grazed surface (its transitions
  disabled).  A corner of the trilinear kind is the grazing of a contact's entry surface;
* :class:`ArrivalTangency`: crossing- and switching-sliding.  Where the orbit arrives at a surface (an
  event named by identity: its surface, the mode it arrives from and its place among such arrivals),
  the far side's field is tangent, ``L_B(t_e, x_e) = 0``;
* :class:`CubicTangency`: adding-sliding.  At an unknown instant ``tau`` of a sliding motion, the exit
  side's field is tangent with zero rate: ``L_A = 0`` and ``L_A,x f_A + L_A,t = 0``;
* :class:`MultiplierCondition`: a fold (``mu = +1``) or a period doubling (``mu = -1``), minimally
  augmented: the bordered test function of Govaerts (*Numerical Methods for Bifurcations of Dynamical
  Equilibria*, SIAM 2000) vanishes where ``M - mu I`` is singular.

:class:`ConditionedProblem` is the augmented problem.  It has the continuation protocol (so a
two-parameter curve is :class:`~saltation.branches.continuation.Continuation` on it) and one Newton
(:meth:`ConditionedProblem.solve`) with one accuracy estimate for every location.
"""

from __future__ import annotations

import abc
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from saltation.engine.flow import EventKind, Flow, SwitchingEvent, Trajectory
from saltation.errors import ConvergenceError, ModelError, SaltationError
from saltation.orbits.floquet import is_stable, multipliers_from_monodromy
from saltation.orbits.problem import BranchProblem, accuracy, bordered_solve, newton
from saltation.orbits.records import (
    BranchPoint,
    Evaluation,
    amplitude_measures,
    event_ids,
    event_labels,
)

_ARRIVALS = (EventKind.TRANSITION, EventKind.SLIDING_START)


@dataclass
class Piece:
    """The shot at an interior instant: time, state, mode, ``Phi(t, t0)`` and the sensitivities ``d x / d p_j``.

    Attributes
    ----------
    t : float
        The instant.
    x : ndarray, shape (n,)
        The state there.
    mode : str
        The mode there.
    fundamental : ndarray, shape (n, n)
        The fundamental solution matrix ``Phi(t, t0)`` (saltation matrices included).
    sensitivities : dict of int to ndarray, shape (n,)
        ``d x(t) / d p_j``, by parameter index.
    sliding : bool
        Whether the shot is on a sliding motion there.
    velocity : ndarray, shape (n,), or None
        The vector field there (the sliding field on a sliding motion).
    """

    t: float
    x: np.ndarray
    mode: str
    fundamental: np.ndarray
    sensitivities: dict[int, np.ndarray]
    sliding: bool = False
    velocity: np.ndarray | None = None


@dataclass
class Shot:
    """One shot of the period and what conditions read from it.

    Attributes
    ----------
    x0 : ndarray, shape (n,)
        The initial state.
    period : float
        The period.
    parameters : ndarray
        Parameter values.
    trajectory : Trajectory
        The whole period, with its monodromy.
    sensitivities : dict of int to ndarray
        ``d x(end) / d p_j`` as carried by the shot (the period's motion with the parameter is added by
        the periodicity rows).
    piece : Piece or None
        The shot at the split instant, when a condition asked for one.
    flow, t0, sign, tolerances, disabled :
        How the shot was run, for conditions that need a further partial run.
    mode0 : str or None
        With multiple shooting: the mode the segment from ``x0`` at ``t0`` starts in (the conditions'
        derivatives by ``x0`` are then by that segment's node); None: the trajectory's.
    """

    x0: np.ndarray
    period: float
    parameters: np.ndarray
    trajectory: Trajectory
    sensitivities: dict[int, np.ndarray]
    piece: Piece | None
    flow: Flow
    t0: float
    sign: float
    tolerances: object
    disabled: tuple[int, ...] = ()
    mode0: str | None = None

    def run_to(self, t: float, params: Sequence[int]) -> Piece:
        """A partial run from ``t0`` to ``t`` with the sensitivities of ``params`` (one integration each).

        Parameters
        ----------
        t : float
            The instant to run to.
        params : sequence of int
            Indices of the parameters whose sensitivities to carry.

        Returns
        -------
        Piece
            The shot at ``t``.

        Raises
        ------
        IntegrationError, ModelError, InitialModeError
            If a run fails (see :meth:`Flow.run`).
        """
        mode0 = self.mode0 if self.mode0 is not None else self.trajectory.mode0
        runs = [self.flow.run(self.x0, self.t0, t, self.parameters, mode0=mode0, variational=True,
                              sensitivity=j, disabled=self.disabled, tolerances=self.tolerances)
                for j in (list(params) or [-1])]
        first = runs[0]
        return Piece(t=float(t), x=first.x1, mode=first.mode1, fundamental=first.monodromy,
                     sensitivities={j: r.parameter_sensitivity for j, r in zip(params, runs)},
                     sliding=first.sliding_at_end, velocity=first.velocity_end)


@dataclass
class Rows:
    """A condition's values and derivatives.

    Attributes
    ----------
    value : ndarray, shape (m,)
        The ``m`` equations' values.
    d_x0 : ndarray, shape (m, n)
        Derivatives by the initial state (or the node of the segment that holds the condition).
    d_period : ndarray, shape (m,)
        Derivatives by the period.
    d_parameters : ndarray, shape (m, k)
        Derivatives by the parameters of the derivative columns, in the problem's order.
    d_extra : ndarray, shape (m, e)
        Derivatives by the condition's own extra unknowns.
    """

    value: np.ndarray
    d_x0: np.ndarray
    d_period: np.ndarray
    d_parameters: np.ndarray
    d_extra: np.ndarray


class Condition(abc.ABC):
    """One or more equations attached to a periodic orbit (see the module docstring).

    A subclass sets the class attributes and writes :meth:`rows`.

    Attributes
    ----------
    size : int
        Number of equations.
    extras : int
        Number of unknowns of its own (an instant).
    disabled : tuple of int
        Transitions the orbit passes as if they were not there (a grazing's virtual orbit).
    name : str
        What it locates, for messages.
    start_mode : str or None
        The mode the shot starts in (None: the model's initial-mode rule at ``x0``).
    anchors_phase : bool
        It fixes the phase of an autonomous orbit, whose phase condition it then replaces.
    """

    size: int = 1
    extras: int = 0
    disabled: tuple[int, ...] = ()
    name: str = "condition"
    #: the mode the shot starts in (None: the model's initial-mode rule at ``x0``)
    start_mode: str | None = None
    #: it fixes the phase of an autonomous orbit, whose phase condition it then replaces
    anchors_phase: bool = False

    def start(self) -> np.ndarray:
        """The initial values of its extra unknowns.

        Returns
        -------
        ndarray, shape (extras,)
            Their guesses (none by default).
        """
        return np.zeros(0)

    def split(self, extra: np.ndarray) -> float | None:
        """The instant to split the shot at (its fundamental matrix there is then free), or None.

        Parameters
        ----------
        extra : ndarray, shape (extras,)
            The condition's own unknowns.

        Returns
        -------
        float or None
            The instant, or None for a shot that is not split.
        """
        return None

    def instant(self, extra: np.ndarray) -> float | None:
        """The instant at which it reads the orbit, or None (the start, or the whole period).

        Multiple shooting reads it from the segment that holds that instant.

        Parameters
        ----------
        extra : ndarray, shape (extras,)
            The condition's own unknowns.

        Returns
        -------
        float or None
            The instant (by default the split instant).
        """
        return self.split(extra)

    @abc.abstractmethod
    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int], problem: ConditionedProblem) -> Rows:
        """Its values and derivatives at the shot.

        Parameters
        ----------
        shot : Shot
            The shot of the period (split where :meth:`split` asked).
        extra : ndarray, shape (extras,)
            The condition's own unknowns.
        params : sequence of int
            The parameter indices of the derivative columns, in order.
        problem : ConditionedProblem
            The problem, for conditions that shoot again (finite differences).

        Returns
        -------
        Rows
            ``size`` equations and their derivatives.
        """

    def accept(self, shot: Shot, extra: np.ndarray) -> None:
        """Called at every accepted point: move the guesses along.

        Parameters
        ----------
        shot : Shot
            The accepted point's shot.
        extra : ndarray, shape (extras,)
            The condition's own unknowns there.
        """


def _rows(size: int, n: int, k: int, e: int) -> Rows:
    return Rows(np.zeros(size), np.zeros((size, n)), np.zeros(size), np.zeros((size, k)), np.zeros((size, e)))


class Tangency(Condition):
    """A grazing: the virtual orbit is tangent to the transition's surface at the unknown instant ``t_g``.

    The virtual orbit passes ``transition`` and ``also_disabled`` without firing them; the equations
    are ``h = 0`` and ``L = h_x f + h_t = 0`` at ``t_g``.

    Derivatives: ``d h / d x0 = h_x Phi(t_g)``, ``d h / d p = h_x psi(t_g) + h_p``, ``d h / d t_g = L``;
    the same for ``L`` with ``L_x``, ``L_p`` and ``d L / d t_g = L_x f + L_t`` (eq. (9)'s ingredients,
    from the model's exact derivatives).

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    transition : int
        Index of the grazed transition (its surface is the one touched).
    t_guess : float
        Guess of the instant of tangency.
    also_disabled : sequence of int
        Further transitions the virtual orbit passes.

    Raises
    ------
    IndexError
        If ``transition`` is not an index of the model's transitions.

    References
    ----------
    di Bernardo, Budd, Champneys and Kowalczyk (2008), *Piecewise-smooth Dynamical Systems: Theory
    and Applications*, Springer (grazing bifurcations).
    """

    size = 2
    extras = 1
    name = "tangency"

    def __init__(self, flow: Flow, transition: int, t_guess: float, *, also_disabled: Sequence[int] = ()):
        system = flow.system
        self.flow = flow
        self.transition = int(transition)
        self.surface = system.surface_index(system.transitions[self.transition].surface)
        self.disabled = (self.transition, *map(int, also_disabled))
        self.t_guess = float(t_guess)

    def start(self) -> np.ndarray:
        return np.array([self.t_guess])

    def split(self, extra: np.ndarray) -> float | None:
        return float(extra[0])

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int], problem: ConditionedProblem) -> Rows:
        """``(h, L)`` at the instant of tangency and their derivatives (see the class docstring).

        Parameters
        ----------
        shot : Shot
            The shot, split at ``t_g``.
        extra : ndarray, shape (1,)
            ``t_g``.
        params : sequence of int
            The parameter indices of the derivative columns.
        problem : ConditionedProblem
            Unused.

        Returns
        -------
        Rows
            Two equations, one extra unknown.

        Raises
        ------
        SaltationError
            If the instant ``t_g`` left the period (the shot has no piece there).
        """
        flow, p, piece = self.flow, shot.parameters, shot.piece
        n = len(shot.x0)
        out = _rows(2, n, len(params), 1)
        if piece is None:
            raise SaltationError(f"the instant of tangency t = {float(extra[0]):.10g} left the period "
                                 f"[{shot.t0:.10g}, {shot.t0 + shot.sign * shot.period:.10g}]")
        t, x = piece.t, piece.x
        h = flow.indicator(self.surface, t, x, p)
        hx, _, hp = flow.indicator_gradient(self.surface, t, x, p)
        L, Lx, Lp, Lt = flow.lie_derivative(piece.mode, self.surface, t, x, p)
        f = flow.vector_field(piece.mode, t, x, p)
        out.value[:] = (h, L)
        out.d_x0[0] = hx @ piece.fundamental
        out.d_x0[1] = Lx @ piece.fundamental
        for c, j in enumerate(params):
            psi = piece.sensitivities[j]
            out.d_parameters[0, c] = hx @ psi + hp[j]
            out.d_parameters[1, c] = Lx @ psi + Lp[j]
        out.d_extra[0, 0] = L
        out.d_extra[1, 0] = Lx @ f + Lt
        return out

    def accept(self, shot: Shot, extra: np.ndarray) -> None:
        self.t_guess = float(extra[0])


class ReturnTangency(Condition):
    """A tangential return (the fold of a stick-slip cycle): the orbit starts where it touches the surface
    of ``transition``, in that transition's target mode (a stick phase), and returns there along the
    source mode's field tangent to the surface, entering the transition: ``h(t0, x0) = 0`` and
    ``L(t0, x0) = h_x f_source + h_t = 0``.

    The shot passes the transition (disabled), so it ends at the touch in the source mode.  The two
    equations read the state at ``t0`` itself (derivatives ``h_x``, ``L_x``, ``h_p``, ``L_p``, exact, no
    integration), and the first fixes the phase: it replaces the phase condition of the autonomous
    orbit, whose period stays an unknown.
    """

    size = 2
    name = "return tangency"
    anchors_phase = True

    def __init__(self, flow: Flow, transition: int):
        system = flow.system
        tr = system.transitions[int(transition)]
        self.flow = flow
        self.transition = int(transition)
        self.surface = system.surface_index(tr.surface)
        self.source = tr.source
        self.start_mode = tr.target
        self.disabled = (self.transition,)

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int], problem: ConditionedProblem) -> Rows:
        flow, p, t, x = self.flow, shot.parameters, shot.t0, shot.x0
        out = _rows(2, len(x), len(params), 0)
        hx, _, hp = flow.indicator_gradient(self.surface, t, x, p)
        L, Lx, Lp, _ = flow.lie_derivative(self.source, self.surface, t, x, p)
        out.value[:] = (flow.indicator(self.surface, t, x, p), L)
        out.d_x0[0] = hx
        out.d_x0[1] = Lx
        for c, j in enumerate(params):
            out.d_parameters[:, c] = (hp[j], Lp[j])
        return out


@dataclass(frozen=True)
class EventIdentity:
    """An orbit's event named by what it is, not by when.

    Attributes
    ----------
    surface : str
        The surface of the event.
    mode_from : str
        The mode it comes from.
    ordinal : int
        Its place among the period's events of that description.
    kinds : tuple of EventKind
        The kinds of events that match (arrivals: transitions and starts of sliding, by default).
    """

    surface: str
    mode_from: str
    ordinal: int = 0
    kinds: tuple[EventKind, ...] = _ARRIVALS

    def matches(self, e: SwitchingEvent) -> bool:
        """Whether an event has this description (kind, surface and mode it comes from).

        Parameters
        ----------
        e : SwitchingEvent
            An event.

        Returns
        -------
        bool
            True if it matches (whatever its place).
        """
        return e.kind in self.kinds and e.surface == self.surface and e.mode_from == self.mode_from

    def find(self, events: Sequence[SwitchingEvent], t_last: float | None = None, period: float = math.inf
             ) -> SwitchingEvent:
        """The event of this identity among ``events``.

        By its place among the events of its description; where their number changed, or that event
        lies more than a quarter period from ``t_last`` (an arrival that moved across the section
        ``t = t0``), the one of them nearest ``t_last`` modulo the period.

        Parameters
        ----------
        events : sequence of SwitchingEvent
            The events of one period.
        t_last : float, optional
            The time of the event last found (None: by its place only).
        period : float
            The period, to measure times modulo it.

        Returns
        -------
        SwitchingEvent
            The event.

        Raises
        ------
        SaltationError
            If the orbit no longer has such an event (or, without ``t_last``, fewer than ``ordinal + 1``).
        """
        found = [e for e in events if self.matches(e)]
        if not found:
            raise SaltationError(f"the orbit no longer arrives at surface {self.surface!r} from mode {self.mode_from!r}")

        def gap(e):
            d = (e.t - t_last) % period if math.isfinite(period) else abs(e.t - t_last)
            return min(d, period - d) if math.isfinite(period) else d

        if self.ordinal < len(found):
            e = found[self.ordinal]
            if t_last is None or gap(e) <= 0.25 * period:
                return e
        if t_last is None:
            raise SaltationError(f"the orbit has {len(found)} arrivals at surface {self.surface!r} from mode "
                                 f"{self.mode_from!r}, not the {self.ordinal + 1}th")
        return min(found, key=gap)


class ArrivalTangency(Condition):
    """Crossing- or switching-sliding: where the orbit arrives at a surface, the far side's field is tangent to it.

    At the event ``identity``, ``L_B(t_e, x_e) = h_x f_B + h_t = 0`` with ``f_B`` the field of
    ``far_mode``.  The event's time and state move with the unknowns as the implicit function theorem
    says (``d t_e = -h_x d x^- / L_A``, ``d x_e = d x^- + f_A d t_e``, with ``L_A`` the arriving field's
    rate); ``d x^-`` is the shot's fundamental matrix just before the event, from the shot split a
    moment ``delta`` before it and carried to the event to second order.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    identity : EventIdentity
        The arrival.
    far_mode : str
        The mode on the far side of the surface, whose field turns tangent.
    t_guess : float
        Guess of the arrival's time.

    References
    ----------
    di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding:
    derivation of normal-form mappings", Physica D 170 (crossing- and switching-sliding).
    """

    name = "arrival tangency"
    #: the split lies this fraction of the period before the arrival
    LEAD = 1e-7

    def __init__(self, flow: Flow, identity: EventIdentity, far_mode: str, t_guess: float):
        self.flow = flow
        self.identity = identity
        self.far_mode = far_mode
        self.t_event = float(t_guess)
        self._t_last_eval = float(t_guess)
        self.event: SwitchingEvent | None = None

    def split(self, extra: np.ndarray) -> float | None:
        return None  # decided by the problem from the last evaluation (see ConditionedProblem._split_time)

    def instant(self, extra: np.ndarray) -> float | None:
        return self._t_last_eval

    def arrival(self, shot: Shot) -> SwitchingEvent:
        """The arrival of this identity in a shot, nearest the last one found.

        Parameters
        ----------
        shot : Shot
            A shot of the period.

        Returns
        -------
        SwitchingEvent
            The arrival event.

        Raises
        ------
        SaltationError
            If the orbit no longer arrives there (see :meth:`EventIdentity.find`).
        """
        return self.identity.find(shot.trajectory.events, self._t_last_eval, shot.period)

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int], problem: ConditionedProblem) -> Rows:
        """``L_B`` at the arrival and its derivatives through the event (see the class docstring).

        Parameters
        ----------
        shot : Shot
            The shot, split just before the arrival.
        extra : ndarray, shape (0,)
            No unknowns of its own.
        params : sequence of int
            The parameter indices of the derivative columns.
        problem : ConditionedProblem
            Unused.

        Returns
        -------
        Rows
            One equation.

        Raises
        ------
        SaltationError
            If the orbit no longer arrives there, or arrives tangentially (the arrival's time is then not a
            smooth function of the unknowns).
        """
        flow, p = self.flow, shot.parameters
        n = len(shot.x0)
        out = _rows(1, n, len(params), 0)
        e = self.arrival(shot)
        self.event = e
        self._t_last_eval = e.t
        piece = shot.piece
        if piece is None or shot.sign * (e.t - piece.t) < 0 or any(
                shot.sign * (other.t - piece.t) >= 0 and shot.sign * (e.t - other.t) > 0
                for other in shot.trajectory.events):
            raise _Resplit(e.t)  # the split must lie before the arrival, with no event between them
        # carry Phi and psi from the split to the arrival, to second order in the gap
        gap = e.t - piece.t
        A = flow.vector_field_jacobian(e.mode_from, piece.t, piece.x, p)
        fp = flow.vector_field_parameters(e.mode_from, piece.t, piece.x, p)
        step = np.eye(n) + gap * A + 0.5 * gap * gap * (A @ A)
        Phi = step @ piece.fundamental
        surface = flow.system.surface_index(e.surface)
        hx, _, hp = flow.indicator_gradient(surface, e.t, e.x_minus, p)
        f_a = flow.vector_field(e.mode_from, e.t, e.x_minus, p)
        rate_a = float(hx @ f_a) + flow.indicator_gradient(surface, e.t, e.x_minus, p)[1]
        if rate_a == 0.0:
            raise SaltationError(f"the orbit arrives at surface {e.surface!r} tangentially: the arrival's time is not "
                                 "a smooth function of the unknowns there")
        L, Lx, Lp, Lt = flow.lie_derivative(self.far_mode, surface, e.t, e.x_minus, p)
        out.value[0] = L

        def through_event(dx_minus: np.ndarray, dh_extra: float | np.ndarray):
            dt = -(hx @ dx_minus + dh_extra) / rate_a
            return dx_minus + np.multiply.outer(f_a, dt) if np.ndim(dt) else dx_minus + f_a * dt, dt

        dx, dt = through_event(Phi, 0.0)
        out.d_x0[0] = Lx @ dx + Lt * dt
        for c, j in enumerate(params):
            psi = piece.sensitivities[j]
            psi = psi + gap * (A @ psi + fp[:, j]) + 0.5 * gap * gap * (A @ (A @ psi + fp[:, j]))
            dxp, dtp = through_event(psi, hp[j])
            out.d_parameters[0, c] = Lx @ dxp + Lt * dtp + Lp[j]
        return out

    def accept(self, shot: Shot, extra: np.ndarray) -> None:
        if self.event is not None:
            self.t_event = self.event.t


class CubicTangency(Condition):
    """Adding-sliding: at an unknown instant ``tau`` of a sliding motion, the exit side's field has a cubic tangency.

    The equations are ``G1 = L_A = 0`` and ``G2 = L_A,x f_A + L_A,t = 0`` at ``(tau, x(tau))``, with
    ``f_A`` the field of ``exit_mode``.  ``x(tau)`` comes from a partial run (a split inside a sliding
    motion would restart it); ``d x(tau) / d tau`` is the sliding velocity there.  The derivatives of
    ``G2`` (second derivatives of the model) are central differences of closed-form functions, no
    integration.

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    exit_mode : str
        The mode the sliding motion would leave into.
    surface : str
        The sliding surface.
    t_guess : float
        Guess of ``tau``.
    h : float
        Relative step of the central differences.

    Raises
    ------
    ModelError
        If ``surface`` names no surface of the model.

    References
    ----------
    di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding:
    derivation of normal-form mappings", Physica D 170 (adding-sliding).
    """

    size = 2
    extras = 1
    name = "cubic tangency"

    def __init__(self, flow: Flow, exit_mode: str, surface: str, t_guess: float, *, h: float = 1e-6):
        self.flow = flow
        self.exit_mode = exit_mode
        self.surface = flow.system.surface_index(surface)
        self.t_guess = float(t_guess)
        self.h = float(h)
        self.piece: Piece | None = None

    def start(self) -> np.ndarray:
        return np.array([self.t_guess])

    def instant(self, extra: np.ndarray) -> float | None:
        return float(extra[0])

    def _g(self, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        L, Lx, _, Lt = self.flow.lie_derivative(self.exit_mode, self.surface, t, x, p)
        return np.array([L, float(Lx @ self.flow.vector_field(self.exit_mode, t, x, p)) + Lt])

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int], problem: ConditionedProblem) -> Rows:
        """``(G1, G2)`` at ``tau`` and their derivatives (see the class docstring).

        Parameters
        ----------
        shot : Shot
            The shot of the period (a partial run to ``tau`` is made from it).
        extra : ndarray, shape (1,)
            ``tau``.
        params : sequence of int
            The parameter indices of the derivative columns.
        problem : ConditionedProblem
            Unused.

        Returns
        -------
        Rows
            Two equations, one extra unknown.

        Raises
        ------
        IntegrationError, ModelError
            If the partial run fails.
        """
        p = shot.parameters
        n = len(shot.x0)
        out = _rows(2, n, len(params), 1)
        tau = float(extra[0])
        piece = shot.run_to(tau, params)
        self.piece = piece
        x = piece.x
        out.value[:] = self._g(tau, x, p)
        gx = np.zeros((2, n))
        for i in range(n):
            d = self.h * max(1.0, abs(x[i]))
            e = np.zeros(n)
            e[i] = d
            gx[:, i] = (self._g(tau, x + e, p) - self._g(tau, x - e, p)) / (2 * d)
        d = self.h * max(1.0, abs(tau))
        gt = (self._g(tau + d, x, p) - self._g(tau - d, x, p)) / (2 * d)
        out.d_x0[:] = gx @ piece.fundamental
        out.d_extra[:, 0] = gt + gx @ piece.velocity
        for c, j in enumerate(params):
            q = p.copy()
            d = self.h * max(1.0, abs(p[j]))
            q[j] = p[j] + d
            up = self._g(tau, x, q)
            q[j] = p[j] - d
            gp = (up - self._g(tau, x, q)) / (2 * d)
            out.d_parameters[:, c] = gx @ piece.sensitivities[j] + gp
        return out

    def accept(self, shot: Shot, extra: np.ndarray) -> None:
        self.t_guess = float(extra[0])


class MultiplierCondition(Condition):
    """A multiplier at ``mu`` (``+1``: fold, ``-1``: period doubling), minimally augmented.

    ``g`` solves ``[[M - mu I, b], [c^T, 0]] [v; g] = [0; 1]`` with ``b``, ``c`` the singular vectors of
    ``M - mu I`` at the first evaluation (kept): ``g = 0`` exactly where ``M - mu I`` is singular.  Its
    derivatives are central differences over further shots (the second derivatives of the flow are
    not carried by the engine): ``2 (n + 1 + k)`` period maps for ``n`` states, the period and ``k``
    parameters.  They are kept, and used again at a point within ``reuse`` (relative, in each of the
    state, the period and the parameters) of where they were taken, if they predict ``g`` there: the
    linearization from the kept point must agree with the new ``g`` to a tenth of the change of ``g``
    (or 1e-12).  The Newton iterations of one continuation step stay that close to its predicted point,
    so a step mostly takes them once; near a corner, where ``g`` bends sharply, the check fails and they
    are taken again.  The residual, ``g`` itself, is always exact: only the Newton's rate depends on
    them.  ``reuse=0`` takes them at every evaluation.

    Parameters
    ----------
    mu : float
        The multiplier: ``+1`` (fold) or ``-1`` (period doubling).
    h : float
        Relative step of the central differences.
    reuse : float
        Relative distance within which the kept derivatives are tried again (0: never).

    References
    ----------
    Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM (minimally
    augmented systems, the bordered test function).
    """

    name = "multiplier"

    def __init__(self, mu: float, *, h: float = 1e-6, reuse: float = 1e-3):
        self.mu = float(mu)
        self.h = float(h)
        self.reuse = float(reuse)
        self._border: tuple[np.ndarray, np.ndarray] | None = None
        self._kept: tuple[np.ndarray, tuple, Rows] | None = None

    def kept_derivatives(self, point: np.ndarray, params: Sequence[int], value: float, n_x: int) -> Rows | None:
        """The derivatives taken last, if they still serve at ``point``; otherwise None.

        They serve when ``point`` is within ``reuse`` of where they were taken, with the same free
        parameters, and they predict ``g`` there (``value``) to a tenth of its change.

        Parameters
        ----------
        point : ndarray
            ``(x0 or nodes, T, parameters)``.
        params : sequence of int
            The parameter indices of the derivative columns.
        value : float
            ``g`` at ``point``.
        n_x : int
            The number of leading entries of ``point`` that are the state or the nodes.

        Returns
        -------
        Rows or None
            The kept rows, or None.
        """
        kept = self._kept
        if kept is None or self.reuse <= 0 or kept[0].shape != point.shape or kept[1] != tuple(params):
            return None
        z0, _, rows = kept
        step = point - z0
        if np.any(np.abs(step) > self.reuse * (1.0 + np.abs(z0))):
            return None
        predicted = (rows.value[0] + rows.d_x0[0] @ step[:n_x] + rows.d_period[0] * step[n_x]
                     + rows.d_parameters[0] @ step[n_x + 1:][list(params)])
        if abs(value - predicted) > max(0.1 * abs(value - rows.value[0]), 1e-12):
            return None
        return rows

    def keep_derivatives(self, point: np.ndarray, params: Sequence[int], rows: Rows) -> None:
        """Keep derivatives for :meth:`kept_derivatives` (copies).

        Parameters
        ----------
        point : ndarray
            ``(x0 or nodes, T, parameters)`` where they were taken.
        params : sequence of int
            The parameter indices of the derivative columns.
        rows : Rows
            The derivatives.
        """
        self._kept = (point.copy(), tuple(params), Rows(rows.value.copy(), rows.d_x0.copy(), rows.d_period.copy(),
                                                        rows.d_parameters.copy(), rows.d_extra.copy()))

    def g(self, M: np.ndarray) -> float:
        """The bordered test function ``g`` of a monodromy.

        The bordering vectors are the singular vectors of ``M - mu I`` at the first call, kept after.

        Parameters
        ----------
        M : ndarray, shape (n, n)
            A monodromy.

        Returns
        -------
        float
            ``g``, zero exactly where ``M - mu I`` is singular.

        Raises
        ------
        SaltationError
            If the bordered matrix is singular.
        numpy.linalg.LinAlgError
            If the singular value decomposition at the first call does not converge.
        """
        n = M.shape[0]
        A = M - self.mu * np.eye(n)
        if self._border is None:
            U, _, Vt = np.linalg.svd(A)
            self._border = (U[:, -1].copy(), Vt[-1].copy())
        b, c = self._border
        rhs = np.zeros(n + 1)
        rhs[n] = 1.0
        solution = bordered_solve(A, b, c, 0.0, rhs)
        if solution is None:
            raise SaltationError(f"the bordered matrix of the multiplier {self.mu:+g} test is singular")
        return float(solution[n])

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int], problem: ConditionedProblem) -> Rows:
        """``g`` of the shot's monodromy and its derivatives (central differences, or the kept ones).

        Parameters
        ----------
        shot : Shot
            The shot of the period.
        extra : ndarray, shape (0,)
            No unknowns of its own.
        params : sequence of int
            The parameter indices of the derivative columns.
        problem : ConditionedProblem
            The problem, whose :meth:`ConditionedProblem.monodromy` the differences shoot.

        Returns
        -------
        Rows
            One equation.

        Raises
        ------
        SaltationError
            If a bordered matrix is singular, or a shot of the differences fails (an
            :class:`IntegrationError`).
        """
        n = len(shot.x0)
        out = _rows(1, n, len(params), 0)
        out.value[0] = self.g(shot.trajectory.monodromy)
        point = np.concatenate([shot.x0, [shot.period], shot.parameters])
        kept = self.kept_derivatives(point, params, out.value[0], n)
        if kept is not None:
            out.d_x0[:], out.d_period[:], out.d_parameters[:] = kept.d_x0, kept.d_period, kept.d_parameters
            return out
        for i in range(n):
            d = self.h * max(1.0, abs(shot.x0[i]))
            e = np.zeros(n)
            e[i] = d
            out.d_x0[0, i] = (self.g(problem.monodromy(shot.x0 + e, shot.period, shot.parameters))
                              - self.g(problem.monodromy(shot.x0 - e, shot.period, shot.parameters))) / (2 * d)
        if problem.autonomous:
            d = self.h * max(1.0, shot.period)
            out.d_period[0] = (self.g(problem.monodromy(shot.x0, shot.period + d, shot.parameters))
                               - self.g(problem.monodromy(shot.x0, shot.period - d, shot.parameters))) / (2 * d)
        for c, j in enumerate(params):
            d = self.h * max(1.0, abs(shot.parameters[j]))
            q = shot.parameters.copy()
            q[j] += d
            up = self.g(problem.monodromy(shot.x0, problem.period_at(shot, q), q))
            q[j] -= 2 * d
            down = self.g(problem.monodromy(shot.x0, problem.period_at(shot, q), q))
            out.d_parameters[0, c] = (up - down) / (2 * d)
        self.keep_derivatives(point, params, out)
        return out


class _Resplit(Exception):
    """The shot must be split again, before the event at ``t``."""

    def __init__(self, t: float):
        super().__init__(t)
        self.t = t


@dataclass
class Located:
    """A solution of a conditioned problem.

    Attributes
    ----------
    unknowns : ndarray
        ``(x0[, T], free parameters..., extras...)``.
    state0 : ndarray
        The orbit's initial state.
    period : float
        Its period.
    parameters : ndarray
        Every parameter's value there.
    shot : Shot
        The shot at the solution.
    accuracy : ndarray
        Per free parameter: the Newton correction that would follow, plus the integration error carried
        to it through the inverse Jacobian (an estimate of its error).
    residuals : list of float
        Newton's residual history.
    """

    unknowns: np.ndarray
    state0: np.ndarray
    period: float
    parameters: np.ndarray
    shot: Shot
    accuracy: np.ndarray
    residuals: list[float] = field(default_factory=list)


class ConditionedProblem(BranchProblem):
    """A periodic-orbit problem with conditions attached and parameters freed (see the module docstring).

    The unknowns are ``u = (x0[, T], p_free..., extras...)``: the base problem's (the state, and the
    period of an autonomous orbit), the freed parameters, and the conditions' own unknowns.  With
    ``continuation`` one more parameter is ``lam``, and the problem is a curve for
    :class:`~saltation.branches.continuation.Continuation`.

    Parameters
    ----------
    problem : ShootingProblem or MultipleShootingProblem
        The orbit's problem (single or multiple shooting, forced or autonomous, forward or backward
        time; one forcing period).
    conditions : sequence of Condition
        The equations attached.
    free : sequence of str
        The parameters that become unknowns.
    continuation : str, optional
        The curve's parameter.
    parameters : ndarray, optional
        The parameter values to start from (the problem's own by default).

    Raises
    ------
    ModelError
        If the equations and unknowns do not balance, a name is not a parameter, a condition that fixes
        the phase is put on a forced orbit, or
        the conditions ask the orbit to start in different modes.

    References
    ----------
    Dankowicz and Schilder (2013), *Recipes for Continuation*, SIAM (an orbit problem extended by zero
    functions, as COCO's ``hspo`` toolbox does).
    """

    def __init__(self, problem, conditions: Sequence[Condition], free: Sequence[str], *,
                 continuation: str | None = None, parameters: np.ndarray | None = None):
        #: forced models: the number of forcing periods the orbit closes after (its period is that many)
        self.periods = int(getattr(problem, "periods", 1))
        #: with multiple shooting (a MultipleShootingProblem): the number of segments, and the single problem
        self.segments = int(getattr(problem, "segments", 1))
        self.single = problem.problem if self.segments > 1 else problem
        self.base = problem
        self.flow = problem.flow
        self.system = problem.system
        self.conditions = list(conditions)
        self.free = [self.system.parameter_index(name) for name in free]
        self.free_names = tuple(free)
        self.autonomous = problem.autonomous
        self.backward = problem.backward
        self.sign = problem.sign
        self.t0 = problem.t0
        self.tolerances = problem.tolerances
        self.p = np.array(problem.p if parameters is None else parameters, dtype=float)
        self.lam_index = -1 if continuation is None else self.system.parameter_index(continuation)
        self.lam_name = continuation
        n = self.system.n
        self.n_nodes = self.segments * n
        self.n_base = self.n_nodes + (1 if self.autonomous else 0)
        self.n_extra = sum(c.extras for c in self.conditions)
        anchored = any(c.anchors_phase for c in self.conditions)
        if anchored and not self.autonomous:
            raise ModelError("a condition that fixes the phase needs an autonomous orbit (a forced orbit's phase is its t0)")
        #: rows of the orbit's own equations: periodicity (or matching), and the phase condition unless a
        #: condition fixes the phase
        self.n_orbit_rows = self.n_nodes + (1 if self.autonomous and not anchored else 0)
        modes = {c.start_mode for c in self.conditions if c.start_mode is not None}
        if len(modes) > 1:
            raise ModelError(f"the conditions ask the orbit to start in different modes: {sorted(modes)}")
        # the mode the orbit starts in: the conditions' (a virtual orbit's), else the problem's own (a memory mode)
        self.mode0 = modes.pop() if modes else getattr(self.single, "mode0", None)
        rows = self.n_orbit_rows + sum(c.size for c in self.conditions)
        if rows != self.dimension:
            raise ModelError(f"{sum(c.size for c in self.conditions)} condition equations need as many unknowns"
                             f"{' (one of them fixes the phase)' if anchored else ''}: "
                             f"{len(self.free)} freed parameter(s) {list(free)} and {self.n_extra} unknown(s) of the "
                             "conditions do not balance them")
        self.disabled = tuple(sorted({k for c in self.conditions for k in c.disabled}))
        self._last: tuple | None = None
        self._segs: list[Trajectory] = []  # multiple shooting: the last evaluation's segments
        self._shots: list[Shot] = []  # multiple shooting: the last evaluation's shot of each condition
        self.event_ids: list[tuple] = []  # the orbit's event sequence (by identity) at every accepted point

    # -- the layout ---------------------------------------------------------------------
    @property
    def dimension(self) -> int:
        return self.n_base + len(self.free) + self.n_extra

    def pack(self, state0: np.ndarray, *, period: float | None = None, extras: np.ndarray | None = None) -> np.ndarray:
        """Unknowns from a state (the period of an autonomous orbit) and the freed parameters' values.

        Parameters
        ----------
        state0 : ndarray
            The initial state; with multiple shooting every node, shape ``(m, n)`` or flat, or one state
            (the nodes are then its trajectory's states at the segments' starts).
        period : float, optional
            The period of an autonomous orbit.
        extras : ndarray, optional
            The conditions' own unknowns (their :meth:`Condition.start` by default).

        Returns
        -------
        ndarray
            ``u``, of size :attr:`dimension`.

        Raises
        ------
        ModelError
            If the state or nodes have the wrong size.
        IntegrationError
            If the trajectory to the nodes cannot be integrated.
        """
        state0 = np.asarray(state0, dtype=float).ravel()
        if self.segments > 1 and state0.size == self.system.n:  # the nodes along the (virtual) orbit from it
            T = float(period) if self.autonomous else self._forcing_period(self.p)
            times = self.t0 + self.sign * T * np.arange(self.segments) / self.segments
            nodes, mode = [state0], None
            for a, b in zip(times[:-1], times[1:]):
                run = self.flow.run(nodes[-1], a, b, self.p, mode0=mode, disabled=self.disabled,
                                    tolerances=self.tolerances)
                nodes.append(run.x1)
                mode = run.mode1
            state0 = np.concatenate(nodes)
        if state0.size != self.n_nodes:
            raise ModelError(f"expected {self.n_nodes} node values ({self.segments} x {self.system.n}), got {state0.size}")
        head = [state0]
        if self.autonomous:
            head.append([float(period)])
        head.append(self.p[self.free])
        head.append(np.concatenate([c.start() for c in self.conditions]) if extras is None else extras)
        return np.concatenate(head)

    def parameters_at(self, lam: float | None = None, u: np.ndarray | None = None) -> np.ndarray:
        """Every parameter's value at ``lam`` and the unknowns ``u`` (the freed parameters are read from them).

        Parameters
        ----------
        lam : float, optional
            Value of the curve's parameter.
        u : ndarray, optional
            The unknowns (without them, the freed parameters keep the problem's values).

        Returns
        -------
        ndarray, shape (n_params,)
            A copy of the parameters.
        """
        if isinstance(lam, np.ndarray) and lam.ndim == 1:  # the order of release 0.1, (u, lam): goes in 0.3.0
            warnings.warn("ConditionedProblem.parameters_at(u, lam) is now parameters_at(lam, u)", DeprecationWarning,
                          stacklevel=2)
            lam, u = u, lam
        p = self.p.copy()
        if u is not None:
            p[self.free] = u[self.n_base : self.n_base + len(self.free)]
        if lam is not None and self.lam_index >= 0:
            p[self.lam_index] = lam
        return p

    @property
    def section_time(self) -> float:
        """A forced orbit's section time ``t0`` (0 for an autonomous one)."""
        return 0.0 if self.autonomous else float(self.t0)

    def lam0(self) -> float:
        """The curve's parameter's value in the problem's parameters.

        Returns
        -------
        float
            The starting value of ``lam``.
        """
        return float(self.p[self.lam_index])

    def period_at(self, shot_or_u, p: np.ndarray) -> float:
        """The period of a shot or of the unknowns, under the parameters ``p``.

        Parameters
        ----------
        shot_or_u : Shot or ndarray
            A shot, or the unknowns.
        p : ndarray
            Parameter values (a forced orbit's period is the forcing period there).

        Returns
        -------
        float
            The period.

        Raises
        ------
        ModelError
            If the forcing period is not positive and finite at ``p``.
        """
        if self.autonomous:
            return shot_or_u.period if isinstance(shot_or_u, Shot) else float(shot_or_u[self.n_nodes])
        return self._forcing_period(p)

    def _forcing_period(self, p: np.ndarray) -> float:
        """A forced orbit's period at the parameters ``p``: ``periods`` forcing periods."""
        return self.periods * self.system.forcing_period(p)

    def _extras(self, u: np.ndarray) -> list[np.ndarray]:
        out, k = [], self.n_base + len(self.free)
        for c in self.conditions:
            out.append(u[k : k + c.extras])
            k += c.extras
        return out

    # -- shots ----------------------------------------------------------------------------
    def _split_time(self, extras: list[np.ndarray]) -> float | None:
        for c, e in zip(self.conditions, extras):
            t = c.split(e)
            if t is not None:
                return t
            if isinstance(c, ArrivalTangency):
                T = self._forcing_period(self.p) if not self.autonomous else 1.0
                return c._t_last_eval - self.sign * c.LEAD * max(T, 1.0)
        return None

    def shoot(self, x0: np.ndarray, T: float, p: np.ndarray, params: Sequence[int], split: float | None) -> Shot:
        """The period from ``x0``, one run per parameter of ``params``, split at ``split`` if given.

        Parameters
        ----------
        x0 : ndarray, shape (n,)
            The initial state.
        T : float
            The period.
        p : ndarray
            Parameter values.
        params : sequence of int
            Indices of the parameters whose sensitivities to carry (one run each).
        split : float or None
            The instant to split the shot at (ignored outside the period).

        Returns
        -------
        Shot
            The shot, with :meth:`ShootingProblem.close_period` applied and its piece at the split.

        Raises
        ------
        IntegrationError, ModelError, InitialModeError
            If a run fails (see :meth:`Flow.run`).
        InconsistentResultError
            A reset exactly at the seam (see :meth:`ShootingProblem.close_period`).
        """
        flow, t0, tol = self.flow, self.t0, self.tolerances
        t1 = t0 + self.sign * T
        if split is not None and not (min(t0, t1) < split < max(t0, t1)):
            split = None
        base = self.base
        mode0 = self.mode0
        for _ in range(2):
            runs, pieces = [], []
            for j in list(params) or [-1]:
                if split is None:
                    traj = flow.run(x0, t0, t1, p, mode0=mode0, variational=True, sensitivity=j,
                                    disabled=self.disabled, tolerances=tol)
                    pieces.append(None)
                else:
                    a = flow.run(x0, t0, split, p, mode0=mode0, variational=True, sensitivity=j,
                                 disabled=self.disabled, tolerances=tol)
                    b = flow.run(a.x1, split, t1, p, mode0=a.mode1, variational=True, sensitivity=j,
                                 phi0=a.monodromy, psi0=a.parameter_sensitivity if j >= 0 else None,
                                 disabled=self.disabled, tolerances=tol)
                    traj = _joined(a, b)
                    pieces.append(a)
                closed = base.close_period(traj, p, j, disabled=self.disabled)
                if closed.mode0 != traj.mode0 and split is not None:
                    mode0 = closed.mode0  # the seam's crossing is run again from the mode it enters: so the pieces
                    break
                runs.append(closed)
            else:
                break
        first = runs[0]
        piece = None
        if split is not None:
            a = pieces[0]
            piece = Piece(t=float(split), x=a.x1, mode=a.mode1, fundamental=a.monodromy,
                          sensitivities={j: pc.parameter_sensitivity for j, pc in zip(params, pieces)},
                          sliding=a.sliding_at_end, velocity=a.velocity_end)
        return Shot(x0=np.asarray(x0, dtype=float), period=float(T), parameters=p, trajectory=first,
                    sensitivities={j: r.parameter_sensitivity for j, r in zip(params, runs)}, piece=piece, flow=flow,
                    t0=t0, sign=self.sign, tolerances=tol, disabled=self.disabled)

    def monodromy(self, x0: np.ndarray, T: float, p: np.ndarray) -> np.ndarray:
        """The monodromy of the period from ``x0`` (finite differences of multiplier conditions).

        Parameters
        ----------
        x0 : ndarray, shape (n,)
            The initial state.
        T : float
            The period.
        p : ndarray
            Parameter values.

        Returns
        -------
        ndarray, shape (n, n)
            The monodromy, the seam closed.

        Raises
        ------
        IntegrationError, ModelError, InitialModeError
            If the run fails.
        """
        traj = self.flow.run(x0, self.t0, self.t0 + self.sign * T, p, mode0=self.mode0, variational=True,
                             disabled=self.disabled, tolerances=self.tolerances)
        return self.single.close_period(traj, p, disabled=self.disabled).monodromy

    # -- the equations ------------------------------------------------------------------
    def _point(self, u: np.ndarray, lam: float | None, need_lam: bool
               ) -> tuple[np.ndarray, float, list[int], list[np.ndarray]]:
        """What the equations at ``(u, lam)`` are evaluated with: the parameters, the period, the
        parameters of the derivative columns (the freed ones, then ``lam``'s) and the conditions' unknowns."""
        p = self.parameters_at(lam, u)
        T = float(u[self.n_nodes]) if self.autonomous else self._forcing_period(p)
        if not (T > 0 and math.isfinite(T)):
            raise ConvergenceError(f"the period must be positive and finite, got {T}")
        params = list(self.free) + ([self.lam_index] if (need_lam and lam is not None and self.lam_index >= 0) else [])
        return p, T, params, self._extras(u)

    def equations(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, Shot]:
        """Residual, ``d/du``, ``d/dlam`` and the shot at ``(u, lam)``.

        Parameters
        ----------
        u : ndarray
            The unknowns.
        lam : float, optional
            Value of the curve's parameter.
        need_lam : bool
            Compute ``d/dlam`` too.

        Returns
        -------
        r : ndarray, shape (dimension,)
            The residual: the orbit's equations, then each condition's.
        J : ndarray, shape (dimension, dimension)
            Its Jacobian by ``u``.
        jl : ndarray or None
            Its derivative by ``lam`` (None without ``lam`` or ``need_lam``).
        shot : Shot
            The shot of the period.

        Raises
        ------
        ConvergenceError
            If the period is not positive and finite, or the shot cannot be split before a condition's
            event.
        SaltationError
            If a condition cannot be evaluated (its instant left the period, its event is gone, a
            bordered matrix is singular) or a run fails (an :class:`IntegrationError`).
        """
        if self.segments > 1:
            return self._segmented_equations(u, lam, need_lam=need_lam)
        n, nb, k = self.system.n, self.n_base, len(self.free)
        p, T, params, extras = self._point(u, lam, need_lam)
        x0 = np.ascontiguousarray(u[:n])
        split = self._split_time(extras)
        for _ in range(3):
            shot = self.shoot(x0, T, p, params, split)
            try:
                blocks = [c.rows(shot, e, params, self) for c, e in zip(self.conditions, extras)]
                break
            except _Resplit as again:
                split = again.t - self.sign * ArrivalTangency.LEAD * max(T, 1.0)
        else:
            raise ConvergenceError("the shot could not be split before the condition's event")
        r0, J0, jp = self.base.periodicity(x0, shot.trajectory, p, shot.sensitivities)
        no = self.n_orbit_rows  # (without the phase condition where a condition fixes the phase)
        m = self.dimension
        r = np.zeros(m)
        J = np.zeros((m, m))
        r[:no] = r0[:no]
        J[:no, :nb] = J0[:no]
        J[:no, nb : nb + k] = jp[:no, :k]
        jl = jp[:no, k].copy() if len(params) > k else None
        if jl is not None:
            jl = np.append(jl, np.zeros(m - no))
        row, col = no, nb + k
        for c, b in zip(self.conditions, blocks):
            rows = slice(row, row + c.size)
            r[rows] = b.value
            J[rows, :n] = b.d_x0
            if self.autonomous:
                J[rows, n] = b.d_period
            J[rows, nb : nb + k] = b.d_parameters[:, :k]
            J[rows, col : col + c.extras] = b.d_extra
            if jl is not None:
                jl[rows] = b.d_parameters[:, k]
            row += c.size
            col += c.extras
        self._last = (shot, extras)
        return r, J, jl, shot

    # -- multiple shooting ----------------------------------------------------------------
    def _segment_of(self, t: float, times: np.ndarray) -> int:
        """The segment whose interval holds the instant ``t`` (the nearest, for an instant just outside)."""
        m = self.segments
        pos = (t - times[0]) / (times[-1] - times[0]) * m
        return int(min(max(math.floor(pos), 0), m - 1))

    def _segmented_equations(self, u: np.ndarray, lam: float | None, *, need_lam: bool = True
                             ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, Shot]:
        """:meth:`equations` with multiple shooting: the matching equations of the segments (the base
        problem's, :class:`~saltation.orbits.shooting.MultipleShootingProblem`), and each condition read
        from the segment that holds its instant, its derivatives by that segment's node.

        A segment ``i`` starts at ``t_i = t0 + s i T / m``: where ``T`` moves (an autonomous orbit's unknown
        period, a forcing period that depends on a parameter), so does ``x(t)`` at a fixed instant ``t`` of
        the segment, by ``-Phi(t, t_i) f(t_i, x_i) dt_i``; the rows get that term.
        """
        n, m, nb, k = self.system.n, self.segments, self.n_base, len(self.free)
        nodes_n = self.n_nodes
        p, T, params, extras = self._point(u, lam, need_lam)
        U = np.ascontiguousarray(u[:nodes_n])
        times = self.t0 + self.sign * T * np.arange(m + 1) / m
        split = self._split_time(extras)
        flow, tol = self.flow, self.tolerances
        for _ in range(3):
            split_seg = None if split is None else self._segment_of(split, times)
            segs: list[list[Trajectory]] = []  # per parameter column (or one without), the segments
            pieces: dict[int, Trajectory] = {}
            for j in params or [-1]:
                mode, row = self.mode0, []
                for i in range(m):
                    x = np.ascontiguousarray(U[i * n:(i + 1) * n])
                    if i == split_seg and min(times[i], times[i + 1]) < split < max(times[i], times[i + 1]):
                        a = flow.run(x, times[i], split, p, mode0=mode, variational=True, sensitivity=j,
                                     disabled=self.disabled, tolerances=tol)
                        b = flow.run(a.x1, split, times[i + 1], p, mode0=a.mode1, variational=True, sensitivity=j,
                                     phi0=a.monodromy, psi0=a.parameter_sensitivity if j >= 0 else None,
                                     disabled=self.disabled, tolerances=tol)
                        traj = _joined(a, b)
                        pieces[j] = a
                    else:
                        traj = flow.run(x, times[i], times[i + 1], p, mode0=mode, variational=True, sensitivity=j,
                                        disabled=self.disabled, tolerances=tol)
                    row.append(traj)
                    mode = traj.mode1
                segs.append(row)
            first = segs[0]
            whole = join(first)
            shots = []
            for c, e in zip(self.conditions, extras):
                t_c = c.instant(e)
                i = 0 if t_c is None else self._segment_of(t_c, times)
                piece = None
                if split_seg is not None and i == split_seg and pieces:
                    a0 = pieces[(params or [-1])[0]]
                    piece = Piece(t=float(a0.t1), x=a0.x1, mode=a0.mode1, fundamental=a0.monodromy,
                                  sensitivities={j: pieces[j].parameter_sensitivity for j in params},
                                  sliding=a0.sliding_at_end, velocity=a0.velocity_end)
                shots.append((i, Shot(
                    x0=np.array(U[i * n:(i + 1) * n]), period=T, parameters=p, trajectory=whole,
                    sensitivities={}, piece=piece, flow=flow, t0=float(times[i]), sign=self.sign, tolerances=tol,
                    disabled=self.disabled, mode0=first[i].mode0)))
            try:
                blocks = []
                for c, e, (i, shot) in zip(self.conditions, extras, shots):
                    if isinstance(c, MultiplierCondition):
                        blocks.append(self._multiplier_rows(c, U, T, p, params, first, times))
                    else:
                        blocks.append(c.rows(shot, e, params, self))
                break
            except _Resplit as again:
                split = again.t - self.sign * ArrivalTangency.LEAD * max(T, 1.0)
        else:
            raise ConvergenceError("the shot could not be split before the condition's event")
        dim = self.dimension
        r, J = np.zeros(dim), np.zeros((dim, dim))
        rows_m, block, jp = self.base.matching(
            U, p, first, [(j, [seg.parameter_sensitivity for seg in segs[c]]) for c, j in enumerate(params)])
        r[:nodes_n] = rows_m
        J[:nodes_n, : block.shape[1]] = block
        no = self.n_orbit_rows
        if no > nodes_n:  # the phase condition (unless a condition fixes the phase)
            single = self.single
            if single.x_ref is None:
                single.anchor_phase(U[:n].copy(), p)
            r[nodes_n] = single.f_ref @ (U[:n] - single.x_ref)
            J[nodes_n, :n] = single.f_ref
        J[:nodes_n, nb:nb + k] = jp[:, :k]
        jl = np.append(jp[:, k], np.zeros(dim - nodes_n)) if len(params) > k else None
        row, col = no, nb + k
        for c, b, (i, shot) in zip(self.conditions, blocks, shots):
            rows = slice(row, row + c.size)
            r[rows] = b.value
            if b.d_x0.shape[1] == nodes_n:  # already by every node (a multiplier condition)
                J[rows, :nodes_n] = b.d_x0
                if self.autonomous:
                    J[rows, nodes_n] = b.d_period
                dp = b.d_parameters
            else:
                J[rows, i * n:(i + 1) * n] = b.d_x0
                # the segment's start moves with T: x(t) at a fixed t moves by -Phi f(t_i, x_i) dt_i
                f_i = flow.vector_field(first[i].mode0, float(times[i]), shot.x0, p)
                moves = -(b.d_x0 @ f_i) * (self.sign * i / m)
                dp = b.d_parameters.copy()
                if self.autonomous:
                    J[rows, nodes_n] = b.d_period + moves
                else:
                    for cc, j in enumerate(params):
                        dp[:, cc] += moves * self.periods * self.system.period_derivative(p, j)
            J[rows, nb:nb + k] = dp[:, :k]
            J[rows, col:col + c.extras] = b.d_extra
            if jl is not None:
                jl[rows] = dp[:, k]
            row += c.size
            col += c.extras
        whole_shot = Shot(x0=np.array(U[:n]), period=T, parameters=p, trajectory=whole, sensitivities={}, piece=None,
                          flow=flow, t0=self.t0, sign=self.sign, tolerances=tol, disabled=self.disabled)
        self._segs = first
        self._last = (whole_shot, extras)
        self._shots = [shot for _, shot in shots]
        return r, J, jl, whole_shot

    def _multiplier_rows(self, c: MultiplierCondition, U: np.ndarray, T: float, p: np.ndarray, params: Sequence[int],
                         segs: list[Trajectory], times: np.ndarray) -> Rows:
        """A multiplier condition under multiple shooting: ``g`` of the product of the segments' matrices,
        its derivatives by every node (one segment rerun per entry), the period and the parameters by
        central differences."""
        n, m = self.system.n, self.segments
        out = Rows(np.zeros(1), np.zeros((1, self.n_nodes)), np.zeros(1), np.zeros((1, len(params))), np.zeros((1, 0)))
        factors = [seg.monodromy for seg in segs]

        def product(fs):
            M = fs[0]
            for F in fs[1:]:
                M = F @ M
            return M

        def segment(i, x, t_a, t_b, q):
            return self.flow.run(x, t_a, t_b, q, mode0=segs[i].mode0, variational=True, disabled=self.disabled,
                                 tolerances=self.tolerances).monodromy

        def whole(TT, q):
            ts = self.t0 + self.sign * TT * np.arange(m + 1) / m
            return product([segment(i, U[i * n:(i + 1) * n], ts[i], ts[i + 1], q) for i in range(m)])

        out.value[0] = c.g(product(factors))
        point = np.concatenate([U[: self.n_nodes], [T], p])
        kept = c.kept_derivatives(point, params, out.value[0], self.n_nodes)
        if kept is not None:
            out.d_x0[:], out.d_period[:], out.d_parameters[:] = kept.d_x0, kept.d_period, kept.d_parameters
            return out
        for i in range(m):
            x = U[i * n:(i + 1) * n]
            for a in range(n):
                d = c.h * max(1.0, abs(x[a]))
                e = np.zeros(n)
                e[a] = d
                up, down = list(factors), list(factors)
                up[i] = segment(i, x + e, times[i], times[i + 1], p)
                down[i] = segment(i, x - e, times[i], times[i + 1], p)
                out.d_x0[0, i * n + a] = (c.g(product(up)) - c.g(product(down))) / (2 * d)
        if self.autonomous:
            d = c.h * max(1.0, T)
            out.d_period[0] = (c.g(whole(T + d, p)) - c.g(whole(T - d, p))) / (2 * d)
        for cc, j in enumerate(params):
            d = c.h * max(1.0, abs(p[j]))
            q = p.copy()
            q[j] += d
            up = c.g(whole(T if self.autonomous else self._forcing_period(q), q))
            q[j] -= 2 * d
            down = c.g(whole(T if self.autonomous else self._forcing_period(q), q))
            out.d_parameters[0, cc] = (up - down) / (2 * d)
        c.keep_derivatives(point, params, out)
        return out

    # -- the continuation protocol --------------------------------------------------------
    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        """The equations at ``(u, lam)`` in the continuation protocol.

        Parameters
        ----------
        u : ndarray
            The unknowns.
        lam : float, optional
            Value of the curve's parameter (its starting value when the problem has one and ``lam`` is
            None).
        need_lam : bool
            Compute ``jac_lam`` too.

        Returns
        -------
        Evaluation
            ``residual``, ``jac_u``, ``jac_lam`` and the shot's trajectory.

        Raises
        ------
        ConvergenceError, SaltationError
            As :meth:`equations`.
        """
        r, J, jl, shot = self.equations(u, self.lam0() if (lam is None and self.lam_index >= 0) else lam,
                                        need_lam=need_lam)
        return Evaluation(residual=r, jac_u=J, jac_lam=jl, trajectory=shot.trajectory)

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> BranchPoint:
        """A curve point's summary: its orbit's multipliers (forward time), amplitude and events.

        Parameters
        ----------
        u : ndarray
            The solved unknowns.
        lam : float or None
            Value of the curve's parameter.
        ev : Evaluation
            Its evaluation.

        Returns
        -------
        BranchPoint
            The record a curve keeps.

        Raises
        ------
        numpy.linalg.LinAlgError
            If the monodromy is not finite.
        StationaryStateError
            Multiple shooting: a node of an autonomous orbit is an equilibrium.
        """
        traj = ev.trajectory
        n = self.system.n
        if self.segments > 1:  # the multipliers from the segments' matrices (periodic Schur)
            U = np.append(u[: self.n_nodes], u[self.n_nodes]) if self.autonomous else np.array(u[: self.n_nodes])
            mu, _ = self.base.multipliers(U, lam, self._segs)
        else:
            mu = multipliers_from_monodromy(traj.monodromy, backward=self.backward)
        return BranchPoint(
            parameter=math.nan if lam is None else float(lam),
            state=np.array(u[:n]), period=float(u[self.n_nodes]) if self.autonomous else self._forcing_period(
                self.parameters_at(lam, u)),
            multipliers=mu, stable=is_stable(mu, autonomous=self.autonomous), event_labels=event_labels(traj),
            monodromy=traj.monodromy, event_ids=event_ids(traj), **amplitude_measures(traj),
        )

    def accept(self, u: np.ndarray, lam: float | None) -> None:
        """Called at every accepted point: move the conditions' guesses along and re-anchor the phase.

        Parameters
        ----------
        u : ndarray
            The accepted unknowns.
        lam : float or None
            Value of the curve's parameter.

        Raises
        ------
        StationaryStateError
            If the phase condition would be anchored at an equilibrium.
        """
        if self._last is not None:
            shot, extras = self._last
            shots = self._shots if self.segments > 1 else [shot] * len(self.conditions)
            for c, e, sh in zip(self.conditions, extras, shots):
                c.accept(sh, e)
            self.event_ids.append(event_ids((shots[0] if shots else shot).trajectory))
        if self.n_orbit_rows > self.n_nodes:
            self.single.anchor_phase(np.asarray(u[: self.system.n], dtype=float), self.parameters_at(lam, u))

    # -- location -------------------------------------------------------------------------
    def solve(self, u0: np.ndarray, *, tol: float = 1e-12, max_iter: int = 20, what: str = "special point",
              history: list[float] | None = None) -> Located:
        """Newton's method on the conditioned problem from ``u0`` (the one Newton of every location).

        Converged when ``|r| <= tol (1 + |u|)``; the accuracy of each freed parameter is the Newton
        correction that would follow plus the integration error carried to it through the inverse
        Jacobian, plus its rounding.

        Parameters
        ----------
        u0 : ndarray
            Guess of the unknowns (:meth:`pack`).
        tol : float
            Newton tolerance.
        max_iter : int
            Largest number of iterations.
        what : str
            What is located, for the error messages.
        history : list of float, optional
            A list to append the residual norms to (a new one by default).

        Returns
        -------
        Located
            The solution, its shot and the accuracy of each freed parameter.

        Raises
        ------
        ConvergenceError
            With the residual history, if Newton does not converge, the Jacobian is singular or a shot
            fails on the way.
        StationaryStateError
            If the phase condition would be anchored at an equilibrium.
        """
        u = np.asarray(u0, dtype=float).copy()
        n, nb, k = self.system.n, self.n_base, len(self.free)
        if self.n_orbit_rows > self.n_nodes and self.single.x_ref is None:
            self.single.anchor_phase(u[:n].copy(), self.parameters_at(None, u))

        def equations(v: np.ndarray):
            r, J, _, shot = self.equations(v, need_lam=False)
            return r, J, shot

        solved = newton(equations, u, tol=tol, max_iter=max_iter, what=what, history=history, wrap_errors=True,
                        size=lambda v: float(np.linalg.norm(v[: nb + k])))
        u, shot = solved.u, solved.extra
        bounds = accuracy(solved, self.flow.integration_error(shot.trajectory, self.tolerances), slice(nb, nb + k))
        return Located(unknowns=u, state0=u[:n].copy(), period=self.period_at(u, shot.parameters),
                       parameters=shot.parameters, shot=shot, accuracy=bounds, residuals=solved.residuals)


def join(segs: Sequence[Trajectory]) -> Trajectory:
    """One trajectory from consecutive segments.

    Their events in order, the product of their transfer matrices as its monodromy (assembled: its
    eigenvalues are not the multipliers' best values).

    Parameters
    ----------
    segs : sequence of Trajectory
        Consecutive segments, with their transfer matrices.

    Returns
    -------
    Trajectory
        From the first segment's start to the last one's end, without parameter sensitivity or dense
        output.

    Raises
    ------
    IndexError
        If ``segs`` is empty.
    """
    first, last = segs[0], segs[-1]
    logs = [seg.event_log for seg in segs]
    event_log = tuple(np.concatenate([log[k] for log in logs]) for k in range(len(first.event_log)))
    M = first.monodromy
    for seg in segs[1:]:
        M = seg.monodromy @ M
    return replace(
        first, t1=last.t1, x1=last.x1, mode1=last.mode1, event_log=event_log, monodromy=M,
        parameter_sensitivity=None, x_min=np.min([s.x_min for s in segs], axis=0),
        x_max=np.max([s.x_max for s in segs], axis=0), sliding_at_end=last.sliding_at_end,
        velocity_end=last.velocity_end, n_steps=sum(s.n_steps for s in segs),
        n_rejected=sum(s.n_rejected for s in segs), _steps=None,
    )


def _joined(a: Trajectory, b: Trajectory) -> Trajectory:
    """Two consecutive pieces as one trajectory: ``b`` carried on from ``a`` (its matrices include ``a``'s)."""

    event_log = tuple(np.concatenate([x, y]) for x, y in zip(a.event_log, b.event_log))
    return replace(b, t0=a.t0, x0=a.x0, mode0=a.mode0, event_log=event_log, x_min=np.minimum(a.x_min, b.x_min),
                   x_max=np.maximum(a.x_max, b.x_max), n_steps=a.n_steps + b.n_steps,
                   n_rejected=a.n_rejected + b.n_rejected, _steps=None)


__all__ = [
    "ArrivalTangency", "Condition", "ConditionedProblem", "CubicTangency", "EventIdentity", "Located",
    "MultiplierCondition", "Piece", "Rows", "Shot", "Tangency", "join",
]
