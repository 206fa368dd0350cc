"""Periodic solutions by shooting, and equilibria, as problems ``r(u, lambda) = 0``.

A shooting problem exposes the residual of the period map and its exact
Jacobian (the monodromy matrix, with every saltation matrix applied) through
the small protocol that :mod:`saltation.continuation` uses:
``evaluate(u, lam) -> Evaluation(residual, jac_u, jac_lam, ...)``.

* Forced systems: ``u = x0``, period ``T`` fixed by the forcing,
  ``r = phi(t0 + s T; t0, x0) - x0`` with ``s = +1`` (forward) or ``-1``
  (backward time).
* Autonomous systems: ``u = (x0, T)``, the same residual closed by the phase
  condition ``f(x_ref) . (x0 - x_ref) = 0``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .errors import ConvergenceError, IntegrationError, ModelError, SaltationError
from .floquet import is_stable, multipliers_from_monodromy, trivial_multiplier_error
from .integrate import EventKind, Flow, SwitchingEvent, Tolerances, Trajectory


@dataclass(frozen=True)
class Evaluation:
    """Residual and Jacobians of a problem at ``(u, lam)``."""

    residual: np.ndarray
    jac_u: np.ndarray
    jac_lam: np.ndarray | None
    trajectory: Trajectory | None = None


@dataclass(frozen=True)
class SolutionSummary:
    """What a branch records of a solved point."""

    state: np.ndarray
    period: float
    amplitude: float
    half_peak_to_peak: float
    multipliers: np.ndarray
    stable: bool
    event_labels: tuple[str, ...]
    monodromy: np.ndarray | None = None
    #: the event sequence by identity (see :func:`event_ids`): what detectors compare
    event_ids: tuple[tuple[int, int, int], ...] = ()


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


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic solution found by shooting.

    Attributes
    ----------
    state0 : ndarray, shape (n,)
        State at ``t0`` on the orbit.
    period : float
    t0 : float
    backward : bool
        Whether the orbit was computed in backward time.
    parameters : ndarray
        Parameter values.
    monodromy : ndarray, shape (n, n)
        Monodromy in the direction of integration.
    multipliers : ndarray, complex
        Forward-time Floquet multipliers (``inf`` for an infinitely unstable direction).
    trajectory : Trajectory
        One period, with its events.
    converged : bool
    iterations : int
    residual_norm : float
    residuals : list of float
        Newton residual history.
    """

    system_name: str
    state0: np.ndarray
    period: float
    t0: float
    backward: bool
    autonomous: bool
    parameters: np.ndarray
    monodromy: np.ndarray
    multipliers: np.ndarray
    trajectory: Trajectory
    converged: bool
    iterations: int
    residual_norm: float
    residuals: list[float] = field(default_factory=list)
    #: the shooting problem that found it (its flow, tolerances and section): what
    #: :func:`saltation.continuation.continue_orbit` follows
    problem: ShootingProblem | None = field(default=None, repr=False, compare=False)

    @property
    def amplitude(self) -> float:
        """``max |x_1|`` over the period."""
        return float(max(abs(self.trajectory.x_max[0]), abs(self.trajectory.x_min[0])))

    @property
    def half_peak_to_peak(self) -> float:
        """``(max x_1 - min x_1) / 2`` over the period."""
        return float(0.5 * (self.trajectory.x_max[0] - self.trajectory.x_min[0]))

    @property
    def backward_multipliers(self) -> np.ndarray:
        """Eigenvalues of the monodromy in the direction of integration."""
        return np.linalg.eigvals(self.monodromy)

    @property
    def stable(self) -> bool:
        return is_stable(self.multipliers, autonomous=self.autonomous)

    @property
    def trivial_multiplier_error(self) -> float:
        """Distance of the trivial multiplier from 1 (autonomous orbits): an accuracy figure."""
        return trivial_multiplier_error(self.multipliers) if self.autonomous else float("nan")

    @property
    def events(self) -> list[SwitchingEvent]:
        """The events of one period (as :attr:`Trajectory.events`)."""
        return self.trajectory.events

    @property
    def event_labels(self) -> tuple[str, ...]:
        """Readable labels of the orbit's cycle of events (see :func:`event_labels`)."""
        return event_labels(self.trajectory)

    def _repr_markdown_(self) -> str:
        """A summary for Jupyter (:mod:`saltation.summary`)."""
        from .summary import orbit_summary

        return orbit_summary(self)


def newton(
    fun, u0: np.ndarray, *, tol: float = 1e-10, max_iter: int = 30, what: str = "Newton", damped: bool = False
) -> tuple[np.ndarray, list[float], object]:
    """Newton's method on ``fun(u) -> (r, J, extra)``.

    Converged when ``|r| <= tol * (1 + |u|)``.  With ``damped``, a step is
    halved (up to 8 times) until the residual decreases.

    Raises
    ------
    ConvergenceError
        With the residual history, after ``max_iter`` iterations or when the
        Jacobian is singular.
    """
    u = np.array(u0, dtype=float)
    history: list[float] = []
    r, J, extra = fun(u)
    for it in range(max_iter + 1):
        rn = float(np.linalg.norm(r))
        history.append(rn)
        if not np.isfinite(rn):
            raise ConvergenceError(f"{what}: residual is not finite at iteration {it}", history)
        if rn <= tol * (1.0 + float(np.linalg.norm(u))):
            return u, history, extra
        if it == max_iter:
            break
        try:
            du = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            raise ConvergenceError(f"{what}: singular Jacobian at iteration {it}", history) from None
        trial = None
        for _ in range(9 if damped else 1):
            try:
                trial = fun(u + du)
            except SaltationError:
                trial = None
            if trial is not None and (not damped or np.linalg.norm(trial[0]) < rn):
                break
            du = 0.5 * du
            trial = None
        if trial is None:
            raise ConvergenceError(f"{what}: no step reduces the residual at iteration {it}", history)
        u = u + du
        r, J, extra = trial
    raise ConvergenceError(f"{what} did not converge in {max_iter} iterations", history)


class ShootingProblem:
    """Periodic orbits of a model by single shooting.

    Parameters
    ----------
    flow : Flow
        The compiled flow of the model.
    parameters : mapping or ndarray, optional
        Parameter values (defaults of the model otherwise).
    continuation_parameter : str, optional
        Name of the parameter ``lam`` for :meth:`evaluate` (continuation).
    backward : bool
        Shoot in backward time (infinitely unstable orbits).
    t0 : float
        Initial time (forced systems: the phase of the forcing).
    tolerances : Tolerances, optional
    periods : int
        Forced systems: the number of forcing periods the orbit takes to
        close (2 for the branch born at a period doubling).  Such problems
        iterate Newton in Python rather than in the compiled kernel.
    """

    def __init__(
        self,
        flow: Flow,
        parameters: Mapping[str, float] | np.ndarray | None = None,
        *,
        continuation_parameter: str | None = None,
        backward: bool = False,
        t0: float = 0.0,
        tolerances: Tolerances | None = None,
        periods: int = 1,
    ):
        if int(periods) != periods or periods < 1:
            raise ModelError(f"periods must be a positive integer, got {periods!r}")
        if periods != 1 and flow.system.is_autonomous:
            raise ModelError(f"model {flow.system.name!r} is autonomous: its period is an unknown, not a number of periods")
        self.periods = int(periods)
        self.flow = flow
        self.system = flow.system
        self.p = flow.parameters(parameters)
        self.lam_index = -1 if continuation_parameter is None else self.system.parameter_index(continuation_parameter)
        self.lam_name = continuation_parameter
        self.backward = bool(backward)
        self.sign = -1.0 if backward else 1.0
        self.t0 = float(t0)
        self.tolerances = tolerances
        self.autonomous = self.system.is_autonomous
        self.x_ref: np.ndarray | None = None
        self.f_ref: np.ndarray | None = None

    # -- the protocol used by continuation ----------------------------------------------
    @property
    def dimension(self) -> int:
        """Number of unknowns ``u``."""
        return self.system.n + (1 if self.autonomous else 0)

    def parameters_at(self, lam: float | None) -> np.ndarray:
        p = self.p.copy()
        if lam is not None:
            if self.lam_index < 0:
                raise ModelError("this problem has no continuation parameter")
            p[self.lam_index] = lam
        return p

    def lam0(self) -> float:
        if self.lam_index < 0:
            raise ModelError("this problem has no continuation parameter")
        return float(self.p[self.lam_index])

    def pack(self, state0: Sequence[float], period: float | None = None) -> np.ndarray:
        """Unknowns ``u`` from an initial state (and period, autonomous systems)."""
        x0 = np.asarray(state0, dtype=float)
        if x0.shape != (self.system.n,):
            raise ModelError(f"initial state must have {self.system.n} components {list(self.system.state_names)}")
        if not self.autonomous:
            return x0.copy()
        if period is None or not period > 0:
            raise ModelError(f"model {self.system.name!r} is autonomous: give a positive period guess")
        return np.append(x0, float(period))

    def set_phase_reference(self, u: np.ndarray, lam: float | None = None) -> None:
        """Anchor the phase condition ``f(x_ref) . (x0 - x_ref) = 0`` at ``u``."""
        x = u[: self.system.n]
        p = self.parameters_at(lam)
        f = self.flow.vector_field(self.flow.initial_mode(x, p, self.t0), self.t0, x, p)
        norm = np.linalg.norm(f)
        if norm == 0:
            raise ModelError(f"phase condition undefined: the vector field vanishes at {x.tolist()}")
        self.x_ref = x.copy()
        self.f_ref = f / norm

    def period_of(self, u: np.ndarray, lam: float | None = None) -> float:
        return float(u[-1]) if self.autonomous else self.periods * self.system.forcing_period(self.parameters_at(lam))

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        """Residual ``r(u, lam)`` and its exact Jacobians."""
        n = self.system.n
        p = self.parameters_at(lam)
        x0 = np.ascontiguousarray(u[:n])
        T = self.period_of(u, lam)
        if not T > 0:
            raise IntegrationError(f"shooting period must be positive, got {T}")
        pidx = self.lam_index if (need_lam and lam is not None) else -1
        traj = self.flow.run(
            x0, self.t0, self.t0 + self.sign * T, p, variational=True, sensitivity=pidx, tolerances=self.tolerances
        )
        M = traj.monodromy
        jl = None
        if not self.autonomous:
            r = traj.x1 - x0
            J = M - np.eye(n)
            if pidx >= 0:
                jl = traj.parameter_sensitivity.copy()
                dT = self.periods * self.system.period_derivative(p, pidx)
                if dT:  # the period moves with the parameter: the end point moves along the flow
                    jl += (self.sign * dT) * traj.velocity_end
            return Evaluation(residual=r, jac_u=J, jac_lam=jl, trajectory=traj)
        if self.x_ref is None:
            self.set_phase_reference(u, lam)
        r = np.empty(n + 1)
        r[:n] = traj.x1 - x0
        r[n] = self.f_ref @ (x0 - self.x_ref)
        J = np.zeros((n + 1, n + 1))
        J[:n, :n] = M
        J[:n, :n] -= np.eye(n)
        J[:n, n] = self.sign * traj.velocity_end
        J[n, :n] = self.f_ref
        if pidx >= 0:
            jl = np.zeros(n + 1)
            jl[:n] = traj.parameter_sensitivity
        return Evaluation(residual=r, jac_u=J, jac_lam=jl, trajectory=traj)

    def correct(
        self, z_pred: np.ndarray, normal: np.ndarray, *, tol: float, max_newton: int, max_correction: float
    ) -> tuple[np.ndarray, Evaluation, int] | None:
        """The corrector of pseudo-arclength continuation, iterated in the compiled kernel.

        Solves ``r(u, lam) = 0``, ``normal . (z - z_pred) = 0`` for
        ``z = (u, lam)`` by the Newton iteration of
        :meth:`saltation.continuation.Corrector.solve_bordered`.  Returns the
        solution, its evaluation and the number of iterations, or None when
        the kernel cannot run it (then iterate in Python).

        Raises
        ------
        ConvergenceError
            If Newton does not converge.
        """
        if self.lam_index < 0 or self.periods != 1:
            return None  # the kernel's corrector closes orbits after one forcing period
        phase = None
        if self.autonomous:
            if self.x_ref is None:
                self.set_phase_reference(z_pred[:-1], float(z_pred[-1]))
            phase = (self.x_ref, self.f_ref)
        found = self.flow.compiled_newton(
            z_pred, normal, self.p, t0=self.t0, sign=self.sign, lam_index=self.lam_index, span=0.0, phase=phase,
            tol=tol, max_iter=max_newton, max_correction=max_correction, damped=False, tolerances=self.tolerances,
        )
        if found is None or found.unsupported:
            return None  # iterate in Python
        n, z = self.system.n, found.z
        p_end = self.p.copy()
        p_end[self.lam_index] = z[-1]
        traj = self.flow.shot_trajectory(found, z[:n].copy(), self.t0, p_end, self.lam_index)  # a failed shot raises
        if not found.converged:
            raise ConvergenceError("corrector did not converge", found.history)
        m, jac = len(z) - 1, found.jacobian
        ev = Evaluation(residual=jac[:, 0].copy(), jac_u=jac[:, 1 : 1 + m].copy(), jac_lam=jac[:, 1 + m].copy(),
                        trajectory=traj)
        return z, ev, found.iterations

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> SolutionSummary:
        """Summary of a solved point for a branch (multipliers, amplitude, events)."""
        traj = ev.trajectory
        mu = multipliers_from_monodromy(traj.monodromy, backward=self.backward)
        return SolutionSummary(
            state=np.array(u[: self.system.n]),
            period=self.period_of(u, lam),
            amplitude=float(max(abs(traj.x_max[0]), abs(traj.x_min[0]))),
            half_peak_to_peak=float(0.5 * (traj.x_max[0] - traj.x_min[0])),
            multipliers=mu,
            stable=is_stable(mu, autonomous=self.autonomous),
            event_labels=event_labels(traj),
            monodromy=traj.monodromy,
            event_ids=event_ids(traj),
        )

    def accept(self, u: np.ndarray, lam: float | None) -> None:
        """Called by continuation at every accepted point: re-anchor the phase condition."""
        if self.autonomous:
            self.set_phase_reference(u, lam)

    # -- solving ------------------------------------------------------------------------
    def solve(self, u0: np.ndarray, lam: float | None = None, *, tol: float = 1e-10, max_iter: int = 30) -> PeriodicOrbit:
        """Newton on the period map from the guess ``u0``.

        Raises
        ------
        ConvergenceError
            With the residual history when Newton fails.
        """
        u0 = np.asarray(u0, dtype=float)
        if self.autonomous:
            self.set_phase_reference(u0, lam)
        else:
            # the period is fixed: the whole iteration runs in the compiled kernel
            p = self.parameters_at(lam)
            T = self.period_of(u0, lam)
            found = self.flow.compiled_newton(
                u0, None, p, t0=self.t0, sign=self.sign, lam_index=-1, span=T, phase=None, tol=tol, max_iter=max_iter,
                max_correction=0.0, damped=True, tolerances=self.tolerances,
            ) if T > 0 else None
            if found is not None and found.converged:  # otherwise the Python iteration explains the failure
                x = found.z.copy()
                traj = self.flow.shot_trajectory(found, x, self.t0, p, -1)
                return self.orbit(x, lam, traj, found.history, period=T, parameters=p)

        def fun(u):
            ev = self.evaluate(u, lam, need_lam=False)
            return ev.residual, ev.jac_u, ev

        direction = "backward" if self.backward else "forward"
        u, history, ev = newton(
            fun, u0, tol=tol, max_iter=max_iter, what=f"shooting ({direction} time) for {self.system.name!r}", damped=True
        )
        return self.orbit(u, lam, ev.trajectory, history)

    def orbit(
        self, u: np.ndarray, lam: float | None, trajectory: Trajectory, history: Sequence[float], *,
        period: float | None = None, parameters: np.ndarray | None = None,
    ) -> PeriodicOrbit:
        """Package a solved point ``u`` and its trajectory over one period as a :class:`PeriodicOrbit`.

        ``period`` and ``parameters`` (at ``lam``) when the caller has them already.
        """
        M = trajectory.monodromy
        return PeriodicOrbit(
            system_name=self.system.name,
            state0=np.array(u[: self.system.n]),
            period=self.period_of(u, lam) if period is None else period,
            t0=self.t0,
            backward=self.backward,
            autonomous=self.autonomous,
            parameters=self.parameters_at(lam) if parameters is None else parameters,
            monodromy=M,
            multipliers=multipliers_from_monodromy(M, backward=self.backward),
            trajectory=trajectory,
            converged=True,
            iterations=max(len(history) - 1, 0),
            residual_norm=float(history[-1]),
            residuals=list(history),
            problem=self,
        )


def find_periodic_orbit(
    flow: Flow,
    state0: Sequence[float],
    *,
    parameters: Mapping[str, float] | None = None,
    period: float | None = None,
    backward: bool = False,
    t0: float = 0.0,
    tol: float = 1e-10,
    max_iter: int = 30,
    tolerances: Tolerances | None = None,
) -> PeriodicOrbit:
    """Find one periodic orbit by shooting from a guess.

    Parameters
    ----------
    flow : Flow
    state0 : array_like
        Guess of the state at ``t0``.
    parameters : mapping, optional
        Parameter overrides.
    period : float, optional
        Period guess (autonomous systems; forced systems use the forcing period).
    backward : bool
        Shoot in backward time.
    """
    prob = ShootingProblem(flow, parameters, backward=backward, t0=t0, tolerances=tolerances)
    return prob.solve(prob.pack(state0, period), tol=tol, max_iter=max_iter)


@dataclass(frozen=True)
class Equilibrium:
    """An equilibrium of one mode, with the eigenvalues of ``f_x`` there."""

    mode: str
    state: np.ndarray
    parameters: np.ndarray
    eigenvalues: np.ndarray
    residuals: list[float]

    @property
    def stable(self) -> bool:
        return bool(np.all(self.eigenvalues.real < 0))


class EquilibriumProblem:
    """Equilibria ``f(x, p) = 0`` of one mode (autonomous systems), in the continuation protocol."""

    def __init__(
        self,
        flow: Flow,
        mode: str | int,
        parameters: Mapping[str, float] | np.ndarray | None = None,
        *,
        continuation_parameter: str | None = None,
    ):
        self.flow = flow
        self.system = flow.system
        self.mode = self.system.mode_index(mode)
        self.p = flow.parameters(parameters)
        self.lam_index = -1 if continuation_parameter is None else self.system.parameter_index(continuation_parameter)
        self.lam_name = continuation_parameter
        self.autonomous = True
        self.backward = False

    @property
    def dimension(self) -> int:
        return self.system.n

    def parameters_at(self, lam: float | None) -> np.ndarray:
        p = self.p.copy()
        if lam is not None:
            p[self.lam_index] = lam
        return p

    def lam0(self) -> float:
        return float(self.p[self.lam_index])

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        p = self.parameters_at(lam)
        x = np.asarray(u, dtype=float)
        f = self.flow.vector_field(self.mode, 0.0, x, p)
        J = self.flow.vector_field_jacobian(self.mode, 0.0, x, p)
        jl = None
        if need_lam and lam is not None:
            jl = self.flow.vector_field_parameters(self.mode, 0.0, x, p)[:, self.lam_index].copy()
        return Evaluation(residual=f, jac_u=J, jac_lam=jl)

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> SolutionSummary:
        eig = np.linalg.eigvals(ev.jac_u).astype(complex)
        eig = eig[np.lexsort((-eig.imag, -eig.real))]
        return SolutionSummary(
            state=np.array(u),
            period=float("nan"),
            amplitude=float(abs(u[0])),
            half_peak_to_peak=0.0,
            multipliers=eig,
            stable=bool(np.all(eig.real < 0)),
            event_labels=(),
        )

    def accept(self, u: np.ndarray, lam: float | None) -> None:
        """Nothing to re-anchor for equilibria."""

    def solve(self, x0: Sequence[float], lam: float | None = None, *, tol: float = 1e-12, max_iter: int = 30) -> Equilibrium:
        def fun(u):
            ev = self.evaluate(u, lam, need_lam=False)
            return ev.residual, ev.jac_u, ev

        mname = self.system.mode_names[self.mode]
        x, history, ev = newton(fun, np.asarray(x0, dtype=float), tol=tol, max_iter=max_iter, what=f"equilibrium of mode {mname!r}")
        return Equilibrium(
            mode=mname,
            state=x,
            parameters=self.parameters_at(lam),
            eigenvalues=np.linalg.eigvals(ev.jac_u),
            residuals=history,
        )
