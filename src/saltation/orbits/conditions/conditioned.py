"""The conditioned problem: a periodic orbit's problem with conditions attached and parameters freed.

:class:`ConditionedProblem` lays out the unknowns ``(x0[, T], p_free..., extras...)``, shoots the period
(split where a condition asks), assembles the single-shooting equations (the multiple-shooting ones are
in :mod:`saltation.orbits.conditions.segmented`), keeps the continuation protocol of
:class:`~saltation.orbits.problem.BranchProblem`, and locates a point with the one Newton of
:func:`saltation.orbits.problem.newton` and its accuracy estimate.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np

from saltation.engine.flow import Trajectory
from saltation.errors import ConvergenceError, ModelError
from saltation.orbits.conditions.base import Condition, Resplit
from saltation.orbits.conditions.joining import _joined
from saltation.orbits.conditions.segmented import equations as segmented_equations
from saltation.orbits.conditions.shot import Located, Piece, Shot
from saltation.orbits.floquet import is_stable, multipliers_from_monodromy
from saltation.orbits.problem import BranchProblem, accuracy, newton
from saltation.orbits.records import (
    BranchPoint,
    Evaluation,
    amplitude_measures,
    event_ids,
    event_labels,
)


class ConditionedProblem(BranchProblem):
    """A periodic-orbit problem with conditions attached and parameters freed (see :mod:`saltation.orbits.conditions`).

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
        """The instant to split the next shot at: the first condition's :meth:`Condition.split_hint`."""
        period = None if self.autonomous else self._forcing_period(self.p)
        for c, e in zip(self.conditions, extras):
            t = c.split_hint(e, period, self.sign)
            if t is not None:
                return t
        return None

    def _shot(self, x0: np.ndarray, T: float, p: np.ndarray, trajectory: Trajectory,
              sensitivities: dict[int, np.ndarray], piece: Piece | None) -> Shot:
        """A shot of the period with what conditions may read of this problem."""
        return Shot(x0=x0, period=float(T), parameters=p, trajectory=trajectory, sensitivities=sensitivities,
                    piece=piece, flow=self.flow, t0=self.t0, sign=self.sign, tolerances=self.tolerances,
                    disabled=self.disabled, forcing_period=None if self.autonomous else self._forcing_period,
                    rerun=self.monodromy)

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
        return self._shot(np.asarray(x0, dtype=float), T, p, first,
                          {j: r.parameter_sensitivity for j, r in zip(params, runs)}, piece)

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
            r, J, jl, segments, shots = segmented_equations(self, u, lam, need_lam=need_lam)
            self._segs = segments.trajectories
            self._last = (segments.whole, self._extras(u))
            self._shots = shots
            return r, J, jl, segments.whole
        n, nb, k = self.system.n, self.n_base, len(self.free)
        p, T, params, extras = self._point(u, lam, need_lam)
        x0 = np.ascontiguousarray(u[:n])
        split = self._split_time(extras)
        for _ in range(3):
            shot = self.shoot(x0, T, p, params, split)
            try:
                blocks = [c.rows(shot, e, params) for c, e in zip(self.conditions, extras)]
                break
            except Resplit as again:
                split = again.t
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


__all__ = ["ConditionedProblem"]
