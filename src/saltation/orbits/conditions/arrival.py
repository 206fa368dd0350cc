"""Conditions at the orbit's arrivals at a surface and on its sliding motions (sliding bifurcations).

* :class:`EventIdentity`: an event named by identity (its surface, the mode it arrives from and its
  place among such arrivals), found again in every shot;
* :class:`ArrivalTangency`: crossing- and switching-sliding.  Where the orbit arrives at a surface (an
  event of that identity), the far side's field is tangent, ``L_B(t_e, x_e) = 0``;
* :class:`CubicTangency`: adding-sliding.  At an unknown instant ``tau`` of a sliding motion, the exit
  side's field is tangent with zero rate: ``L_A = 0`` and ``L_A,x f_A + L_A,t = 0``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from saltation.engine.flow import EventKind, Flow, SwitchingEvent
from saltation.errors import SaltationError
from saltation.orbits.conditions.base import Condition, Resplit
from saltation.orbits.conditions.shot import Piece, Rows, Shot

_ARRIVALS = (EventKind.TRANSITION, EventKind.SLIDING_START)


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

    def split_hint(self, extra: np.ndarray, period: float | None, sign: float) -> float | None:
        """A moment before the arrival found last: ``LEAD`` of the period (of 1 for an autonomous orbit) earlier.

        Parameters
        ----------
        extra : ndarray, shape (0,)
            No unknowns of its own.
        period : float or None
            A forced orbit's period at the problem's parameters; None for an autonomous orbit.
        sign : float
            The direction of time.

        Returns
        -------
        float
            The instant to split the shot at.
        """
        return self._t_last_eval - sign * self.LEAD * max(1.0 if period is None else period, 1.0)

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

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int]) -> Rows:
        """``L_B`` at the arrival and its derivatives through the event (see the class docstring).

        Parameters
        ----------
        shot : Shot
            The shot, split just before the arrival.
        extra : ndarray, shape (0,)
            No unknowns of its own.
        params : sequence of int
            The parameter indices of the derivative columns.

        Returns
        -------
        Rows
            One equation.

        Raises
        ------
        SaltationError
            If the orbit no longer arrives there, or arrives tangentially (the arrival's time is then not a
            smooth function of the unknowns).
        Resplit
            If the shot is not split before the arrival with no event between them: split ``LEAD`` of
            the period (of 1 at least) before it.
        """
        flow, p = self.flow, shot.parameters
        n = len(shot.x0)
        out = Rows.zeros(1, n, len(params), 0)
        e = self.arrival(shot)
        self.event = e
        self._t_last_eval = e.t
        piece = shot.piece
        if piece is None or shot.sign * (e.t - piece.t) < 0 or any(
                shot.sign * (other.t - piece.t) >= 0 and shot.sign * (e.t - other.t) > 0
                for other in shot.trajectory.events):
            # the split must lie before the arrival, with no event between them
            raise Resplit(e.t - shot.sign * self.LEAD * max(shot.period, 1.0))
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

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int]) -> Rows:
        """``(G1, G2)`` at ``tau`` and their derivatives (see the class docstring).

        Parameters
        ----------
        shot : Shot
            The shot of the period (a partial run to ``tau`` is made from it).
        extra : ndarray, shape (1,)
            ``tau``.
        params : sequence of int
            The parameter indices of the derivative columns.

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
        out = Rows.zeros(2, n, len(params), 1)
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


__all__ = ["ArrivalTangency", "CubicTangency", "EventIdentity"]
