"""Tangencies of the orbit to a surface at an unknown instant, or at its start.

* :class:`Tangency`: a grazing.  ``h(t_g, x(t_g)) = 0`` and ``L(t_g, x(t_g)) = h_x f + h_t = 0`` with the
  instant ``t_g`` an unknown, on the virtual orbit that passes the grazed surface (its transitions
  disabled).  A corner of the trilinear kind is the grazing of a contact's entry surface;
* :class:`ReturnTangency`: a tangential return (the fold of a stick-slip cycle), read at ``t0``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from saltation.engine.flow import Flow
from saltation.errors import SaltationError
from saltation.orbits.conditions.base import Condition
from saltation.orbits.conditions.shot import Rows, Shot


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

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int]) -> Rows:
        """``(h, L)`` at the instant of tangency and their derivatives (see the class docstring).

        Parameters
        ----------
        shot : Shot
            The shot, split at ``t_g``.
        extra : ndarray, shape (1,)
            ``t_g``.
        params : sequence of int
            The parameter indices of the derivative columns.

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
        out = Rows.zeros(2, n, len(params), 1)
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

    Parameters
    ----------
    flow : Flow
        The flow of the model.
    transition : int
        Index of the transition the orbit returns to (its target mode is the stick phase the orbit
        starts in).

    Raises
    ------
    IndexError
        If ``transition`` is not an index of the model's transitions.
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

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int]) -> Rows:
        flow, p, t, x = self.flow, shot.parameters, shot.t0, shot.x0
        out = Rows.zeros(2, len(x), len(params), 0)
        hx, _, hp = flow.indicator_gradient(self.surface, t, x, p)
        L, Lx, Lp, _ = flow.lie_derivative(self.source, self.surface, t, x, p)
        out.value[:] = (flow.indicator(self.surface, t, x, p), L)
        out.d_x0[0] = hx
        out.d_x0[1] = Lx
        for c, j in enumerate(params):
            out.d_parameters[:, c] = (hp[j], Lp[j])
        return out


__all__ = ["ReturnTangency", "Tangency"]
