"""Event-driven integration of piecewise-smooth systems, forward and backward in time.

The work happens in the compiled engine, shared by every model, with the
model's own compiled functions (see :mod:`saltation.engine.codegen`); this module is
the thin typed driver around it.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np

from saltation.engine import _contract as kc
from saltation.engine.codegen import (
    is_engine_compiled,
    load_engine,
    load_model_functions,
    model_addresses,
    transition_table,
)
from saltation.errors import (
    ChatteringError,
    InitialModeError,
    IntegrationError,
    ModelError,
    NonFiniteError,
    SlidingError,
    StepSizeError,
)
from saltation.model.system import TIME, PiecewiseSystem


class Status(enum.IntEnum):
    """Outcome of an integration (the kernel's status codes, :mod:`saltation.engine._contract`)."""

    OK = kc.STATUS_OK
    MAX_EVENTS = kc.STATUS_MAX_EVENTS
    CHATTERING = kc.STATUS_CHATTERING
    STEP_TOO_SMALL = kc.STATUS_STEP_TOO_SMALL
    NON_FINITE = kc.STATUS_NON_FINITE
    SLIDING_UNDEFINED = kc.STATUS_SLIDING_UNDEFINED
    MAX_STEPS = kc.STATUS_MAX_STEPS
    TANGENTIAL = kc.STATUS_TANGENTIAL
    OUTSIDE_DOMAIN = kc.STATUS_OUTSIDE_DOMAIN


# Status.OK as a plain int (an enum member costs a class attribute lookup per integration)
_STATUS_OK = kc.STATUS_OK

#: A state outside a named start mode's domain by at most this much (relative to ``1 + max |x_i|``) lies on
#: its boundary, within rounding (the engine's tolerance for a state that leaves its mode's domain).
DOMAIN_ROUNDING = 1e-8
#: the steps per forcing period, at least, of a forced model with a surface that moves with time (Flow)
TIME_SURFACE_STEPS = 16


@dataclass(frozen=True)
class CompiledNewton:
    """The outcome of the kernel's Newton loop (:meth:`Flow.compiled_newton`).

    Attributes
    ----------
    code : int
        ``SHOOT_*`` of :mod:`saltation.engine._contract` (``converged``, ``bad_period``...).
    iterations : int
    z : ndarray
        The last iterate.
    history : list of float
        Residual norms.
    jacobian : ndarray
        ``[r | J_u | J_lam]`` at ``z`` (rows of the periodicity and phase conditions).
    shot : tuple
        The kernel's packed result of the shot from ``z`` (read by :meth:`Flow.shot_trajectory`).
    tangent : ndarray or None
        The bordered system only: ``t`` with ``[[J_u, J_lam], [normal]] t = e_last`` at the converged ``z``,
        not normalised (the next tangent of pseudo-arclength continuation, whose ``normal`` is the last
        tangent); None for the period map alone, or where the matrix is singular or Newton has not converged.
    """

    code: int
    iterations: int
    z: np.ndarray
    history: list[float]
    jacobian: np.ndarray
    shot: tuple = field(repr=False)
    tangent: np.ndarray | None = field(default=None, repr=False)

    @property
    def converged(self) -> bool:
        return self.code == kc.SHOOT_CONVERGED

    @property
    def unsupported(self) -> bool:
        """A period that is not positive, or a singular Newton matrix: iterate in Python for the reason."""
        return self.code in (kc.SHOOT_BAD_PERIOD, kc.SHOOT_SINGULAR)


class EventKind(enum.IntEnum):
    """What happened at a switching event (the kernel's event kinds, :mod:`saltation.engine._contract`)."""

    TRANSITION = kc.EVENT_TRANSITION
    SLIDING_START = kc.EVENT_SLIDING_START
    SLIDING_END = kc.EVENT_SLIDING_END


class SwitchingEvent(NamedTuple):
    """One switching event of a trajectory.

    Attributes
    ----------
    t : float
        Event time.
    kind : EventKind
        A transition, the start of a sliding motion, or its end.
    transition : int
        Index of the transition that fired (-1 for the end of sliding).
    surface : str
        Name of the switching surface.
    mode_from, mode_to : str
        Modes before and after (for the start of sliding, ``mode_to`` is the
        mode on the far side of the surface).
    x_minus, x_plus : ndarray, shape (n,)
        State just before and just after the event (they differ for resets).
    saltation : ndarray, shape (n, n)
        Saltation matrix ``S`` with ``Phi(t+) = S Phi(t-)`` (eq. 8).
    """

    t: float
    kind: EventKind
    transition: int
    surface: str
    mode_from: str
    mode_to: str
    x_minus: np.ndarray
    x_plus: np.ndarray
    saltation: np.ndarray

    @property
    def signature(self) -> tuple[int, int, str]:
        """What identifies the event in an orbit's event sequence."""
        return (int(self.kind), self.transition, self.surface)

    def __repr__(self) -> str:
        which = f"transition {self.transition}" if self.transition >= 0 else "end of sliding"
        return (f"SwitchingEvent(t={self.t:.12g}, {self.kind.name.lower()}, {which}: {self.mode_from} -> {self.mode_to} "
                f"on {self.surface})")


@dataclass(frozen=True)
class Trajectory:
    """Result of :func:`simulate`.

    Attributes
    ----------
    system : PiecewiseSystem
        The model.
    t0, t1 : float
        Start and end time (``t1 < t0`` in backward time).
    x0, x1 : ndarray, shape (n,)
        Initial and final state.
    mode0, mode1 : str
        Initial and final mode.
    event_log : tuple of ndarray
        The kernel's event log (times, integer columns, x-, x+, S); read it as
        :attr:`events`.
    monodromy : ndarray, shape (n, n) or None
        Fundamental solution matrix ``Phi(t1, t0)`` with every saltation
        matrix applied, when ``variational=True``.
    parameter_sensitivity : ndarray, shape (n,) or None
        ``d x(t1) / d p_k`` for the requested parameter ``k``.
    x_min, x_max : ndarray, shape (n,)
        Extremes of every state over the trajectory (from the dense output).
    sliding_at_end : bool
        Whether the trajectory ends on a sliding motion.
    velocity_end : ndarray, shape (n,)
        The vector field at the end: the final mode's, or Filippov's sliding
        field when the trajectory ends on a sliding motion.
    n_steps, n_rejected : int
        Accepted and rejected steps.
    """

    system: PiecewiseSystem
    t0: float
    t1: float
    x0: np.ndarray
    x1: np.ndarray
    mode0: str
    mode1: str
    event_log: tuple[np.ndarray, ...] = field(repr=False)
    monodromy: np.ndarray | None
    parameter_sensitivity: np.ndarray | None
    x_min: np.ndarray
    x_max: np.ndarray
    sliding_at_end: bool
    velocity_end: np.ndarray
    n_steps: int
    n_rejected: int
    _steps: tuple[np.ndarray, ...] | None = field(default=None, repr=False)

    @cached_property
    def events(self) -> list[SwitchingEvent]:
        """The switching events, in the order met."""
        return _switching_events(self.system, self.event_log)

    def __repr__(self) -> str:
        x1 = ", ".join(f"{v:.6g}" for v in np.asarray(self.x1)[:6]) + (", ..." if len(self.x1) > 6 else "")
        modes = self.modes
        path = " -> ".join(modes[:5]) + (f" -> ... ({len(modes)} modes)" if len(modes) > 5 else "")
        return (f"Trajectory({self.system.name!r}, t {self.t0:.8g} .. {self.t1:.8g}, {len(self.events)} events, "
                f"{path}, x1=[{x1}]" + (", with monodromy" if self.monodromy is not None else "") + ")")

    @property
    def event_sequence(self) -> tuple[tuple[int, int, str], ...]:
        """The orbit's sequence of events (kind, transition, surface)."""
        return tuple(e.signature for e in self.events)

    @property
    def modes(self) -> list[str]:
        """Sequence of modes visited (sliding motions named ``a|b``)."""
        seq = [self.mode0]
        for e in self.events:
            seq.append(f"{e.mode_from}|{e.mode_to}" if e.kind == EventKind.SLIDING_START else e.mode_to)
        return seq

    @property
    def dense_steps(self) -> tuple[np.ndarray, ...]:
        """The recorded steps: start times, sizes, end fractions, start states, coefficients.

        Each step ``k`` covers ``t_old[k] + s h[k]`` for ``s`` in ``[0, s_end[k]]``
        (``s_end < 1`` for a step cut short by an event).

        Raises
        ------
        ValueError
            If the trajectory was computed without ``dense=True``.
        """
        if self._steps is None:
            raise ValueError("this trajectory was computed without dense=True")
        return tuple(np.asarray(a) for a in self._steps)

    def at(self, times: Sequence[float] | np.ndarray) -> np.ndarray:
        """States at the given times (inside the time span) from the dense output.

        At an event time the state before the event is returned.

        Parameters
        ----------
        times : array_like, shape (m,)
            Times inside the span from :attr:`t0` to :attr:`t1`.

        Returns
        -------
        ndarray, shape (m, n)
            The state at each time, from DOP853's continuous extension of the step that covers it.

        Raises
        ------
        ValueError
            If the trajectory was computed without ``dense=True``.
        """
        _, _, _, y0, F = self.dense_steps
        times = np.asarray(times, dtype=float).reshape(-1)
        if y0.shape[0] == 0:
            return np.repeat(self.x1[None, :], len(times), axis=0)
        k, s = self.locate(times)
        return dense_evaluate(F[k], y0[k], s)

    def locate(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For each time, the index of the recorded step that covers it and the fraction within it.

        Parameters
        ----------
        times : ndarray, shape (m,)
            Times inside the span of the trajectory.

        Returns
        -------
        k : ndarray of int, shape (m,)
            Index of the recorded step (:attr:`dense_steps`) that covers each time.
        s : ndarray, shape (m,)
            Fraction of that step, in ``[0, s_end[k]]``.

        Raises
        ------
        ValueError
            If the trajectory was computed without ``dense=True``.
        """
        t_old, h, s_end, _, _ = self.dense_steps
        times = np.asarray(times, dtype=float)
        forward = h[0] > 0 if h.size else True
        key, starts = (times, t_old) if forward else (-times, -t_old)
        k = np.clip(np.searchsorted(starts, key, side="right") - 1, 0, len(t_old) - 1)
        s = np.clip((times - t_old[k]) / h[k], 0.0, s_end[k])
        return k, s

    def sample(self, num_per_step: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """Dense states along the trajectory.

        Parameters
        ----------
        num_per_step : int
            Number of intervals each recorded step is cut into (``num_per_step + 1`` points per step, the
            step's ends included).

        Returns
        -------
        t : ndarray, shape (m,)
            Times, in the direction of integration.
        x : ndarray, shape (m, n)
            States at those times (the initial state alone for a trajectory without steps).

        Raises
        ------
        ValueError
            If the trajectory was computed without ``dense=True``.
        """
        t_old, h, s_end, y0, F = self.dense_steps
        ts = []
        xs = []
        s = np.linspace(0.0, 1.0, num_per_step + 1)
        for k in range(len(t_old)):
            sk = s * s_end[k]
            ts.append(t_old[k] + sk * h[k])
            xs.append(_dense_eval(F[k], y0[k], sk))
        if not ts:
            return np.array([self.t0]), self.x0[None, :]
        return np.concatenate(ts), np.concatenate(xs)


def _dense_eval(F: np.ndarray, y0: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Evaluate DOP853's continuous extension of one step at fractions ``s`` (vectorised)."""
    s = np.asarray(s, dtype=float)
    return dense_evaluate(np.broadcast_to(F, (len(s),) + F.shape), np.broadcast_to(y0, (len(s),) + y0.shape), s)


def dense_evaluate(F: np.ndarray, y0: np.ndarray, s: np.ndarray) -> np.ndarray:
    """DOP853's continuous extension of steps ``(F[k], y0[k])`` at fractions ``s[k]``.

    Parameters
    ----------
    F : ndarray, shape (m, 7, n)
        Dense-output coefficients of each step (the last item of :attr:`Trajectory.dense_steps`).
    y0 : ndarray, shape (m, n)
        State at the start of each step.
    s : ndarray, shape (m,)
        Fraction of each step at which to evaluate (0 at its start, 1 at its full length).

    Returns
    -------
    ndarray, shape (m, n)
        The interpolated states.

    References
    ----------
    Hairer, Norsett and Wanner (1993), *Solving Ordinary Differential Equations I: Nonstiff Problems*,
    2nd ed., Springer, section II.6 (dense output of DOP853).
    """
    out = np.zeros(y0.shape)
    for j in range(7):
        out += F[:, 6 - j, :]
        out *= (s if j % 2 == 0 else 1.0 - s)[:, None]
    return out + y0


@dataclass(frozen=True)
class Tolerances:
    """Integration tolerances.

    Attributes
    ----------
    rtol, atol : float
        Relative and absolute local error tolerances on the state.
    max_step : float
        Largest step size (inf for none).  A forced model with a surface that moves with time (a clock
        ``h(t)``, a moving wall) steps at most a sixteenth of its forcing period in any case.
    max_events : int
        Largest number of switching events in one integration.
    max_steps : int
        Largest number of steps in one integration.
    control_variational : bool
        Control the local error of the fundamental solution matrix (and the
        parameter sensitivity) too, not only of the state.  Off, steps are
        chosen for the state alone, which can leave the monodromy matrix far
        less accurate than the orbit (e.g. along a sliding motion).
    exact_affine : bool
        In modes whose field is affine in the state with at most one harmonic
        forcing term (:mod:`saltation.engine.affine`), step with the exact flow
        (its Taylor series summed to rounding error) instead of DOP853; the
        tolerances then only govern the dense output between steps.

    Raises
    ------
    ValueError
        If ``rtol`` is not in ``(0, 1)``, ``atol`` is not positive and finite, or ``max_step`` is not
        positive.
    """

    rtol: float = 1e-10
    atol: float = 1e-12
    max_step: float = np.inf
    max_events: int = 100_000
    max_steps: int = 1_000_000
    control_variational: bool = True
    exact_affine: bool = True

    def __post_init__(self):
        if not (0 < self.rtol < 1 and 0 < self.atol < math.inf):
            raise ValueError(f"tolerances must satisfy 0 < rtol < 1 and atol > 0, got rtol={self.rtol}, atol={self.atol}")
        if not self.max_step > 0:
            raise ValueError(f"max_step must be positive, got {self.max_step}")

    @cached_property
    def kernel_arguments(self) -> tuple[tuple[float, float], tuple[float, int, int], tuple[bool, bool]]:
        """The settings as the kernel takes them: ``(rtol, atol)``, ``(max_step, max_events, max_steps)``,
        ``(control_variational, exact_affine)``, typed once."""
        return (
            (float(self.rtol), float(self.atol)),
            (float(self.max_step), int(self.max_events), int(self.max_steps)),
            (bool(self.control_variational), bool(self.exact_affine)),
        )


class Flow:
    """The compiled flow of one model: integrate, with events and saltation matrices.

    The first flow of a model compiles its functions (and, on a cold cache, the engine for its
    number of states) into the kernel cache; later flows load them from there.

    Parameters
    ----------
    system : PiecewiseSystem
        The model.
    tolerances : Tolerances, optional
        Default integration tolerances (``Tolerances()`` by default).

    Raises
    ------
    KernelCacheError
        If the kernel cache cannot be written, or a compiled module cannot be rebuilt in it
        (:mod:`saltation.engine.codegen`).
    """

    def __init__(self, system: PiecewiseSystem, tolerances: Tolerances | None = None):
        self.system = system
        self.tolerances = tolerances or Tolerances()
        if not is_engine_compiled(system.n):  # a cold cache: the integrator, the Newton and the model side by side
            from saltation.engine.precompile import compile_in_parallel

            compile_in_parallel([system])
        self._model = load_model_functions(system)  # the engine's first argument (see saltation.engine._contract)
        self._engine = load_engine(system.n)
        self._addresses = model_addresses(self._model, self._engine)  # how the engine takes the model (see the engine)
        self._affine_modes = self._model[kc.AFFINE_MODES]
        self._table = transition_table(system)
        self._n_surfaces = len(system.surface_names)
        self._identity = np.eye(system.n)  # read-only inputs of the kernel
        self._offsets = kc.result_offsets(system.n)
        self._zeros = np.zeros(system.n)
        #: a forced model with a surface that moves with time (a clock h(t), a moving wall): its steps are at most
        #: 1 / TIME_SURFACE_STEPS of the forcing period, so that no step passes two of its crossings (the exact
        #: flow of a mode whose field is constant has no step bound of its own)
        indicators = getattr(system, "indicators", ())
        self._time_surfaces = bool(indicators) and not system.is_autonomous and any(
            TIME in h.free_symbols for h in indicators)

    def _kernel_tolerances(self, tol: Tolerances, p: np.ndarray):
        """``tol`` as the kernel takes it, the step bounded for surfaces that move with time (see above)."""
        steps, limits, flags = tol.kernel_arguments
        if self._time_surfaces:
            bound = self.system.forcing_period(p) / TIME_SURFACE_STEPS
            if bound < limits[0]:
                limits = (float(bound), limits[1], limits[2])
        return steps, limits, flags

    def __repr__(self) -> str:
        t = self.tolerances
        return f"Flow({self.system.name!r}, {self.system.n} states, rtol={t.rtol:g}, atol={t.atol:g})"

    def __reduce__(self):
        # a flow travels as its model and tolerances (to a worker process, a Dask task): the compiled
        # functions and their addresses belong to one process, and the receiver loads its own
        return (Flow, (self.system, self.tolerances))

    def parameters(self, overrides: Mapping[str, float] | np.ndarray | None = None) -> np.ndarray:
        """Parameter vector from a mapping of overrides (or an array passed through).

        Parameters
        ----------
        overrides : mapping or ndarray, optional
            Values by parameter name, the others at the model's defaults; or a full parameter vector,
            shape ``(n_params,)``, which is checked and copied.

        Returns
        -------
        ndarray, shape (n_params,)
            The parameter values, in the model's order.

        Raises
        ------
        ModelError
            An unknown parameter name, a value that is not a finite number, an array of the wrong shape,
            or parameters at which one of the model's expressions divides by zero.
        """
        if isinstance(overrides, np.ndarray):
            if overrides.shape != (self.system.n_params,):
                raise ModelError(f"parameter array must have shape ({self.system.n_params},), got {overrides.shape}")
            p = overrides.astype(float)
            check = getattr(self.system, "check_parameters", None)
            if check is not None:
                check(p)
            return p
        return self.system.parameter_vector(overrides)

    def initial_mode(self, x0: np.ndarray, p: np.ndarray, t0: float = 0.0) -> int:
        """The model's initial-mode rule, compiled: the first mode whose domain holds.

        Parameters
        ----------
        x0 : ndarray, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.
        t0 : float
            Time.

        Returns
        -------
        int
            Index of the mode.

        Raises
        ------
        InitialModeError
            If the state lies in no mode's domain.
        """
        m = int(self._model[kc.INITIAL_MODE](float(t0), _c_array(x0), _c_array(p)))
        if m < 0:
            return self.system.initial_mode(x0, p, t0)  # raises with the full explanation
        return m

    def start_mode(self, x0: Sequence[float], p: np.ndarray, t0: float = 0.0, mode0: int | str | None = None) -> int:
        """The mode a run from ``(t0, x0)`` starts in: ``mode0``, checked against its domain, or the model's rule.

        A mode may be memory (a latch, a relay with hysteresis, a thermostat): its domain overlaps
        another's, or it has none, and only ``mode0`` tells which of them a state is in.  A named mode
        must hold the state: every condition of its domain holds, or fails by rounding only (the state
        lies on the domain's boundary).

        Parameters
        ----------
        x0 : array_like, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.
        t0 : float
            Time.
        mode0 : int or str, optional
            The mode (name or index); None: the model's initial-mode rule (:meth:`initial_mode`).

        Returns
        -------
        int
            Index of the mode.

        Raises
        ------
        ModelError
            For an unknown mode (the message lists the model's modes), or a state or parameter vector of
            the wrong size.
        InitialModeError
            If the state lies outside the named mode's domain (naming the mode and the conditions that
            do not hold), or, without ``mode0``, in no mode's domain.
        """
        if mode0 is None:
            return self.initial_mode(x0, p, t0)
        sys_ = self.system
        m = sys_.mode_index(mode0)
        x, pc = _c_array(np.asarray(x0, dtype=float).reshape(-1)), _c_array(p)
        if x.shape != (sys_.n,) or pc.shape != (sys_.n_params,):
            raise ModelError(f"{sys_.name!r}: a state has {sys_.n} components {list(sys_.state_names)} and the "
                             f"parameters {sys_.n_params}, got {x.size} and {pc.size}")
        if bool(self._model[kc.IN_DOMAIN](m, float(t0), x, pc)):
            return m
        margin = float(self._model[kc.DOMAIN_MARGIN](m, float(t0), x, pc))
        if margin >= -DOMAIN_ROUNDING * (1.0 + float(np.max(np.abs(x)))):
            return m  # on the boundary of its domain
        explain = getattr(sys_, "domain_violations", None)
        why = (f"its domain condition(s) {', '.join(explain(m, x, pc, t0))} do not hold there" if explain is not None
               else "its in_domain function is false there")
        raise InitialModeError(
            f"the state {x.tolist()} at t = {float(t0):.12g} lies outside the domain of mode {sys_.mode_names[m]!r} "
            f"of {sys_.name!r}: {why}; a mode can be named as the start only where its domain holds (a memory mode "
            "has no domain, or shares it with another mode)"
        )

    def indicator(self, surface: int | str, t: float, x: Sequence[float], p: np.ndarray) -> float:
        """The indicator ``h(t, x, p)`` of a switching surface (by index or name).

        Parameters
        ----------
        surface : int or str
            Index or name of the surface.
        t : float
            Time.
        x : array_like, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        float
            The value of the indicator (zero on the surface).

        Raises
        ------
        ModelError
            If ``surface`` names no surface of the model.
        """
        s = surface if isinstance(surface, (int, np.integer)) else self.system.surface_index(surface)
        return float(self._model[kc.INDICATOR](int(s), float(t), _c_array(x), _c_array(p)))

    def integration_error(self, traj: Trajectory, tolerances: Tolerances | None = None) -> float:
        """An estimate of the global error of a trajectory's end state.

        Zero (rounding) when every mode it visits was stepped with the exact flow
        (affine modes, ``exact_affine``) and it never slides; otherwise ``rtol``
        times the state's size times the number of events plus one (the error of
        DOP853 per stretch between events, at the requested tolerance).

        Parameters
        ----------
        traj : Trajectory
            A trajectory of this flow.
        tolerances : Tolerances, optional
            The tolerances it was computed with (the flow's by default).

        Returns
        -------
        float
            The estimate, in the units of the state.
        """
        tol = tolerances or self.tolerances
        affine = self._model[kc.AFFINE_MODES]
        visited = {traj.mode0, traj.mode1, *(e.mode_to for e in traj.events), *(e.mode_from for e in traj.events)}
        sliding = any(e.kind != EventKind.TRANSITION for e in traj.events) or traj.sliding_at_end
        if tol.exact_affine and not sliding and all(affine[self.system.mode_index(m)] for m in visited):
            return 1e-14 * (1.0 + float(np.abs(traj.x1).max()))
        return tol.rtol * (1.0 + float(np.abs(traj.x1).max())) * (1 + len(traj.events))

    def vector_field(self, mode: int | str, t: float, x: Sequence[float], p: np.ndarray) -> np.ndarray:
        """The vector field ``f(t, x, p)`` of a mode.

        Parameters
        ----------
        mode : int or str
            Index or name of the mode.
        t : float
            Time.
        x : array_like, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        ndarray, shape (n,)
            The mode's field at ``(t, x)``.

        Raises
        ------
        ModelError
            If ``mode`` names no mode of the model.
        """
        f = np.zeros(self.system.n)
        self._model[kc.VECTOR_FIELD](self.system.mode_index(mode), float(t), _c_array(x), _c_array(p), f)
        return f

    def vector_field_jacobian(self, mode: int | str, t: float, x: Sequence[float], p: np.ndarray) -> np.ndarray:
        """The Jacobian ``f_x`` of a mode's vector field.

        Parameters
        ----------
        mode : int or str
            Index or name of the mode.
        t : float
            Time.
        x : array_like, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        ndarray, shape (n, n)
            ``f_x`` at ``(t, x)``.

        Raises
        ------
        ModelError
            If ``mode`` names no mode of the model.
        """
        J = np.zeros((self.system.n, self.system.n))
        self._model[kc.VECTOR_FIELD_JAC](self.system.mode_index(mode), float(t), _c_array(x), _c_array(p), J)
        return J

    def vector_field_parameters(self, mode: int | str, t: float, x: Sequence[float], p: np.ndarray) -> np.ndarray:
        """The parameter derivative ``f_p`` of a mode's vector field.

        Parameters
        ----------
        mode : int or str
            Index or name of the mode.
        t : float
            Time.
        x : array_like, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        ndarray, shape (n, n_params)
            ``f_p`` at ``(t, x)``.

        Raises
        ------
        ModelError
            If ``mode`` names no mode of the model.
        """
        fp = np.zeros((self.system.n, max(self.system.n_params, 1)))
        self._model[kc.VECTOR_FIELD_DP](self.system.mode_index(mode), float(t), _c_array(x), _c_array(p), fp)
        return fp[:, : self.system.n_params]

    def _check_bands(self, x0: np.ndarray, t0: float, p: np.ndarray) -> None:
        """Refuse a band between two parallel surfaces (:attr:`~saltation.model.system.PiecewiseSystem.parallel_surfaces`)
        that is no wider than either edge's resolution at a state of size 1, 16 rounding units of the terms of its
        indicator, ``|h_x_i| + |h_t| max(1, |t|) + |h_p_j p_j|`` there (as the engine resolves a surface): the
        integration cannot tell the band's inside from its edges (a stick band of ``eta = 1e-16`` ran onto the
        equilibrium without an error).  (A band that only a huge state cannot resolve is the state's problem.)"""
        key = (p.tobytes(), float(t0))
        cache = self.__dict__.setdefault("_bands", {"checked": set(), "gaps": None})
        if key in cache["checked"]:
            return
        sys_ = self.system
        if cache["gaps"] is None:
            import sympy as sp

            cache["gaps"] = [(i, j, sp.lambdify([sys_.t, *sys_.p], gap, modules="math"))
                             for i, j, gap in sys_.parallel_surfaces]
        eps = float(np.finfo(float).eps)
        unit = np.clip(x0, -1.0, 1.0)  # a state of size 1 on the start's side (a huge start is its own problem)
        for i, j, gap in cache["gaps"]:
            width = abs(float(gap(t0, *p)))
            resolution = 0.0
            for k in (i, j):
                hx, ht, hp = self.indicator_gradient(k, t0, unit, p)
                with np.errstate(all="ignore"):
                    parts = np.concatenate([np.abs(hx), [abs(ht) * max(1.0, abs(t0))], np.abs(hp * p)])
                resolution = max(resolution, 16.0 * eps * float(parts[np.isfinite(parts)].sum()))
            if width <= resolution:
                names = sys_.surface_names
                raise ModelError(
                    f"model {sys_.name!r}: the band between surfaces {names[i]!r} and {names[j]!r} is {width:.3g} wide "
                    f"({sys_.indicators[i] - sys_.indicators[j]} at parameters {dict(zip(sys_.parameter_names, p.tolist()))}), "
                    f"no wider than the state's resolution there ({resolution:.3g}): the integration cannot tell the band "
                    f"from its edges; widen it")
        if len(cache["checked"]) > 1024:
            cache["checked"].clear()
        cache["checked"].add(key)

    def indicator_gradient(self, surface: int | str, t: float, x: Sequence[float], p: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
        """The derivatives ``(h_x, h_t, h_p)`` of a switching surface's indicator at ``(t, x)``.

        Parameters
        ----------
        surface : int or str
            Index or name of the surface.
        t : float
            Time.
        x : array_like, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        h_x : ndarray, shape (n,)
            Gradient in the state.
        h_t : float
            Derivative in time (non-zero for a moving surface).
        h_p : ndarray, shape (n_params,)
            Gradient in the parameters.

        Raises
        ------
        ModelError
            If ``surface`` names no surface of the model.
        """
        s = surface if isinstance(surface, (int, np.integer)) else self.system.surface_index(surface)
        hx = np.zeros(self.system.n)
        hp = np.zeros(max(self.system.n_params, 1))
        ht = self._model[kc.INDICATOR_GRAD](int(s), float(t), _c_array(x), _c_array(p), hx, hp)
        return hx, float(ht), hp[: self.system.n_params]

    def lie_derivative(
        self, mode: int | str, surface: int | str, t: float, x: Sequence[float], p: np.ndarray
    ) -> tuple[float, np.ndarray, np.ndarray, float]:
        """The Lie derivative ``L = h_x f + h_t`` of a surface along a mode's field, with ``L_x``, ``L_p`` and ``L_t``.

        ``L`` is the speed at which the mode's flow crosses the surface: the denominator of the saltation
        matrix, eq. (9) of *Fold bifurcations in discontinuous systems*, zero at a tangency.

        Parameters
        ----------
        mode : int or str
            Index or name of the mode.
        surface : int or str
            Index or name of the surface.
        t : float
            Time.
        x : array_like, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        L : float
            The Lie derivative at ``(t, x)``.
        L_x : ndarray, shape (n,)
            Its gradient in the state.
        L_p : ndarray, shape (n_params,)
            Its gradient in the parameters.
        L_t : float
            Its derivative in time.

        Raises
        ------
        ModelError
            If ``mode`` or ``surface`` names no mode or surface of the model.
        """
        m = self.system.mode_index(mode)
        k = surface if isinstance(surface, (int, np.integer)) else self.system.surface_index(surface)
        gx = np.zeros(self.system.n)
        gp = np.zeros(max(self.system.n_params, 1))
        x, p = _c_array(np.array(x, dtype=float)), _c_array(p)
        value = float(self._model[kc.LIE_DERIVATIVE](m, int(k), float(t), x, p, gx, gp))
        rate_t = float(self._model[kc.LIE_DERIVATIVE_DT](m, int(k), float(t), x, p))
        return value, gx, gp[: self.system.n_params], rate_t

    def guard_holds(self, transition: int, t: float, x: Sequence[float], p: np.ndarray) -> bool:
        """Whether every condition of a transition's guard holds at ``(t, x)``.

        Parameters
        ----------
        transition : int
            Index of the transition.
        t : float
            Time.
        x : array_like, shape (n,)
            State.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        bool
            True when the guard holds (always, for a transition without a guard).
        """
        return bool(self._model[kc.GUARD](int(transition), float(t), _c_array(x), _c_array(p)))

    def transition_jump(
        self, transition: int, t: float, x: Sequence[float], p: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fire a transition at a state on its surface: ``(x+, S, dx+/dp)``.

        The saltation matrix by the general formula (eq. (9) of *Fold bifurcations in discontinuous
        systems*, with a reset ``g``),
        ``S = g_x + (f+ - g_x f- - g_t) h_x / (h_x f- + h_t)``, with ``f-`` the
        field of the transition's source mode and ``f+`` that of its target at
        ``x+ = g(t, x, p)``; the same formula as the engine's at every event,
        and the same in backward time (reversing time flips the numerator and
        the denominator alike).

        Parameters
        ----------
        transition : int
            Index of the transition.
        t : float
            Time of the event.
        x : array_like, shape (n,)
            State on the transition's surface, before the event.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        x_plus : ndarray, shape (n,)
            The state after the event (``x`` itself without a reset).
        S : ndarray, shape (n, n)
            The saltation matrix.
        dx_plus_dp : ndarray, shape (n, n_params)
            The jump's own parameter derivative
            ``g_p + (f+ - g_x f- - g_t) h_p / (h_x f- + h_t)``.

        Raises
        ------
        IntegrationError
            If the flow is tangent to the surface there (the saltation matrix is undefined).

        References
        ----------
        Aizerman and Gantmakher (1958), "On the stability of periodic motions", *Journal of Applied
        Mathematics and Mechanics* 22.  Leine and Van Campen, "Fold bifurcations in discontinuous
        systems", eq. (9).
        """
        sys_ = self.system
        n, k = sys_.n, int(transition)
        tr = sys_.transitions[k]
        x = _c_array(np.array(x, dtype=float))
        p = _c_array(p)
        gx, gt, gp = np.eye(n), np.zeros(n), np.zeros((n, max(sys_.n_params, 1)))
        x_plus = x.copy()
        if sys_.resets[k] is not None:
            self._model[kc.RESET_MAP](k, float(t), x, p, x_plus)
            self._model[kc.RESET_JAC](k, float(t), x, p, gx, gt, gp)
        f_minus = self.vector_field(tr.source, t, x, p)
        f_plus = self.vector_field(tr.target, t, x_plus, p)
        hx, ht, hp = self.indicator_gradient(tr.surface, t, x, p)
        den = float(hx @ f_minus) + ht
        if den == 0.0 or not math.isfinite(den):
            raise IntegrationError(f"transition {tr.label!r} at t = {t:.12g}: the flow is tangent to surface "
                                   f"{tr.surface!r}, the saltation matrix is undefined")
        w = f_plus - gx @ f_minus - gt
        S = gx + np.outer(w, hx) / den
        dp = gp[:, : sys_.n_params] + np.outer(w, hp) / den
        return x_plus, S, dp

    def run(
        self,
        x0: Sequence[float],
        t0: float,
        t1: float,
        p: np.ndarray,
        *,
        mode0: int | str | None = None,
        variational: bool = False,
        sensitivity: int | str = -1,
        dense: bool = False,
        tolerances: Tolerances | None = None,
        phi0: np.ndarray | None = None,
        psi0: np.ndarray | None = None,
        disabled: Sequence[int] = (),
    ) -> Trajectory:
        """Integrate from ``t0`` to ``t1`` (``t1 < t0`` integrates backward in time).

        Between events the compiled engine steps with DOP853 (or with the exact flow of an affine mode);
        it locates every event, applies its reset and saltation matrix, and slides along a surface with
        Filippov's convex combination where both fields push into it.

        Parameters
        ----------
        x0 : array_like, shape (n,)
            Initial state.
        t0, t1 : float
            Start and end time.
        p : ndarray, shape (n_params,)
            Parameter values (see :meth:`parameters`).
        mode0 : int or str, optional
            Initial mode; by default the model's initial-mode rule.
        variational : bool
            Carry the fundamental solution matrix through modes and events.
        sensitivity : int or str
            The parameter (index or name) whose sensitivity ``dx/dp`` to carry
            (-1: none); with ``variational``, :attr:`Trajectory.parameter_sensitivity`.
        dense : bool
            Keep the dense output for :meth:`Trajectory.sample`.
        tolerances : Tolerances, optional
            Integration tolerances (the flow's by default).
        phi0, psi0 : ndarray, optional
            The fundamental solution matrix, shape (n, n), and the parameter
            sensitivity, shape (n,), at ``t0`` (identity and zero by default):
            a shot continued from an interior instant carries on from there.
        disabled : sequence of int
            Indices of transitions that never fire in this run (the orbit
            passes their surfaces as if they were not there): the virtual
            orbits that define a grazing (:mod:`saltation.special_points.grazing`).

        Returns
        -------
        Trajectory
            The end state and mode, the events with their saltation matrices, and the monodromy
            (with ``variational``) and dense output (with ``dense``).

        Raises
        ------
        ModelError
            An initial state, parameter vector, ``phi0`` or ``psi0`` of the wrong size or not finite, an
            unknown mode or parameter, or a state that leaves a mode's domain where no transition holds.
        ValueError
            If ``t0`` or ``t1`` is not finite.
        InitialModeError
            If ``mode0`` is not given and ``x0`` lies in no mode's domain.
        IntegrationError
            If the integration fails: :class:`ChatteringError` (too many events, or events closer than
            the time axis resolves), :class:`StepSizeError`, :class:`NonFiniteError`,
            :class:`SlidingError` (a sliding motion the model does not define), or an
            :class:`IntegrationError` itself (a tangential event, too many steps, a degenerate case).
            The message names the mode and surface involved.

        References
        ----------
        Hairer, Norsett and Wanner (1993), *Solving Ordinary Differential Equations I: Nonstiff Problems*,
        2nd ed., Springer (DOP853).  Filippov (1988), *Differential Equations with Discontinuous
        Righthand Sides*, Kluwer (sliding).  Leine and Van Campen, "Fold bifurcations in discontinuous
        systems", eq. (9) (saltation matrices).
        """
        sys_ = self.system
        tol = tolerances or self.tolerances
        x0 = np.array(x0, dtype=float).reshape(-1)  # a copy: the trajectory keeps it
        if x0.shape != (sys_.n,):
            raise ModelError(f"initial state must have {sys_.n} components {list(sys_.state_names)}, got {x0.size}")
        if not np.isfinite(x0).all():  # (a sum of finite values may overflow)
            raise ModelError(f"initial state {x0.tolist()} is not finite")
        p = _c_array(p)
        if p.shape != (sys_.n_params,) or not np.isfinite(p).all():
            raise ModelError(f"parameters of {sys_.name!r}: expected {sys_.n_params} finite values "
                             f"{list(sys_.parameter_names)}, got {p.tolist()}")
        t0, t1 = float(t0), float(t1)
        if not (math.isfinite(t0) and math.isfinite(t1)):
            raise ValueError(f"integration times must be finite, got t0={t0}, t1={t1}")
        if getattr(sys_, "parallel_surfaces", ()):
            self._check_bands(x0, t0, p)
        m0 = self.initial_mode(x0, p, t0) if mode0 is None else sys_.mode_index(mode0)
        sens = sys_.parameter_index(sensitivity) if isinstance(sensitivity, str) else int(sensitivity)
        if not -1 <= sens < sys_.n_params:
            raise ModelError(f"sensitivity: parameter index {sens} out of range (the model has {sys_.n_params} parameters)")
        phi = self._identity if phi0 is None else _c_array(phi0)
        if phi.shape != (sys_.n, sys_.n):
            raise ModelError(f"initial fundamental matrix must have shape ({sys_.n}, {sys_.n}), got {phi.shape}")
        psi = self._zeros if psi0 is None else _c_array(psi0)
        if psi.shape != (sys_.n,):
            raise ModelError(f"initial parameter sensitivity must have shape ({sys_.n},), got {psi.shape}")
        steps, limits, flags = self._kernel_tolerances(tol, p)
        table = self._table
        if len(disabled):
            table = table.copy()
            for k in disabled:
                table[int(k), 0] = -1  # a source mode that is never current
        try:
            out = self._engine.integrate_kernel(
                self._addresses, self._affine_modes, t0, t1, x0, int(m0), p, bool(variational), sens, *steps, 0.0,
                *limits, table, self._n_surfaces, bool(dense), phi, psi, *flags,
            )
        except ArithmeticError as exc:  # the compiled engine raises Python's errors for a division by zero
            raise IntegrationError(
                f"the engine failed ({type(exc).__name__}: {exc}) integrating {sys_.name!r} from t = {t0:.12g} to "
                f"{t1:.12g}, x0 = {x0.tolist()}, parameters {p.tolist()}: a degenerate case it does not resolve"
            ) from None
        return self._unpack(out, x0, float(t0), m0, variational, sens, dense)

    def compiled_newton(
        self, z0: np.ndarray, normal: np.ndarray | None, p: np.ndarray, *, t0: float, sign: float, lam_index: int,
        span: float, phase: tuple[np.ndarray, np.ndarray] | None, tol: float, max_iter: int, max_correction: float,
        damped: bool, tolerances: Tolerances | None = None,
    ) -> CompiledNewton | None:
        """Run the kernel's Newton loop on periodic orbits (no return to Python per shot).

        The loop is compiled with the integrator it calls; what it solves is
        the shooting layer's business (:mod:`saltation.orbits.shooting`): the period
        map at a fixed span (``normal`` None, ``damped``), or the bordered
        pseudo-arclength system of ``z = (x0[, T], lam)`` (``span`` 0: the
        forcing period follows ``lam``; ``phase = (x_ref, f_ref)`` for
        autonomous orbits).

        Parameters
        ----------
        z0 : ndarray
            Initial iterate: ``x0`` (and ``T`` for an autonomous orbit), then ``lam`` for the bordered
            system.
        normal : ndarray or None
            The pseudo-arclength row of the bordered system (None: the period map at a fixed ``lam``).
        p : ndarray, shape (n_params,)
            Parameter values (the continuation parameter's entry is taken from ``z``).
        t0 : float
            Initial time of every shot.
        sign : float
            +1 to shoot forward in time, -1 backward.
        lam_index : int
            Index of the continuation parameter.
        span : float
            The length of a shot of a forced orbit at fixed parameters (0: the forcing period at ``lam``).
        phase : tuple of ndarray or None
            ``(x_ref, f_ref)``, the phase condition of an autonomous orbit.
        tol : float
            Newton tolerance: converged when ``|r| <= tol (1 + |u|)``.
        max_iter : int
            Largest number of iterations.
        max_correction : float
            The bordered loop stops when a correction exceeds ``max_correction (1 + |z|)``.
        damped : bool
            Newton on the period map at a fixed ``lam`` (``normal`` unused), each step halved (up to 8
            times) until the residual decreases; False: the bordered pseudo-arclength system.
        tolerances : Tolerances, optional
            Integration tolerances (the flow's by default).

        Returns
        -------
        CompiledNewton or None
            The loop's outcome (its ``code`` says whether it converged, and why not), or None when the
            kernel cannot run the problem (a forcing period given as a Python callable).
        """
        if span == 0.0 and phase is None and not isinstance(self.system, PiecewiseSystem):
            return None  # the forcing period is a Python callable
        steps, limits, flags = self._kernel_tolerances(tolerances or self.tolerances, _c_array(p))
        x_ref, f_ref = (_c_array(a) for a in phase) if phase is not None else (self._zeros, self._zeros)
        z0 = _c_array(z0)
        code, it, packed, *out = self._engine.correct_periodic(
            self._addresses, self._affine_modes, z0, self._zeros if normal is None else _c_array(normal), float(t0), float(sign),
            bool(phase is not None), int(lam_index), float(span), _c_array(p), x_ref, f_ref,
            float(tol), int(max_iter), float(max_correction), bool(damped), *steps, *limits, self._table,
            self._n_surfaces, self._identity, self._zeros, *flags,
        )
        m_u = len(z0) - (0 if normal is None else 1)
        z, history, jac, tangent = _newton_unpack(packed, len(z0), m_u)
        return CompiledNewton(code=int(code), iterations=int(it), z=z, history=history.tolist(), jacobian=jac,
                              shot=out, tangent=tangent if tangent.size and tangent.any() else None)

    def shot_trajectory(self, result: CompiledNewton, x0: np.ndarray, t0: float, p: np.ndarray, sensitivity: int) -> Trajectory:
        """The trajectory of the last shot of :meth:`compiled_newton`.

        Parameters
        ----------
        result : CompiledNewton
            The outcome of :meth:`compiled_newton`.
        x0 : ndarray, shape (n,)
            The initial state of that shot.
        t0 : float
            Its initial time.
        p : ndarray, shape (n_params,)
            Its parameter values.
        sensitivity : int
            Index of the parameter whose sensitivity the shot carried (-1: none).

        Returns
        -------
        Trajectory
            The shot, with its monodromy (no dense output).

        Raises
        ------
        IntegrationError
            The error of the shot, if it failed (as :meth:`run` raises it: a subclass such as
            :class:`ChatteringError`, or :class:`ModelError` for a state outside every domain).
        InitialModeError
            If the shot failed and ``x0`` lies in no mode's domain.
        """
        ok = int(result.shot[0][kc.INFO_STATUS]) == _STATUS_OK
        # the shot's initial mode; after a failure the rule itself, which raises for a state in no mode
        m0 = int(result.shot[0][kc.INFO_INITIAL_MODE]) if ok else self.initial_mode(x0, p, t0)
        return self._unpack(result.shot, x0, float(t0), m0, True, sensitivity, False)

    def _unpack(self, out, x0, t0, m0, variational, sensitivity, dense) -> Trajectory:
        sys_ = self.system
        n = sys_.n
        info, res = out  # the kernel's two packed arrays, laid out as saltation.engine._contract says
        o_x, o_phi, o_psi, o_min, o_max, o_vel, n_out = self._offsets
        n_ev, w_ev = int(info[kc.INFO_EVENTS]), 1 + 2 * n + n * n
        ev_int = info[kc.INFO_EVENT_LOG :].reshape(n_ev, kc.EVENT_LOG_INTS)
        ev = res[n_out : n_out + n_ev * w_ev].reshape(n_ev, w_ev)
        t = res[0]
        x = res[o_x : o_x + n]
        Phi = res[o_phi : o_phi + n * n].reshape(n, n)
        psi = res[o_psi : o_psi + n]
        xmin = res[o_min : o_min + n]
        xmax = res[o_max : o_max + n]
        velocity = res[o_vel : o_vel + n]
        event_log = (ev[:, 0], ev_int, ev[:, 1 : 1 + n], ev[:, 1 + n : 1 + 2 * n], ev[:, 1 + 2 * n :].reshape(-1, n, n))
        names = sys_.mode_names
        if info[kc.INFO_STATUS] != _STATUS_OK:
            raise _error(Status(int(info[kc.INFO_STATUS])), sys_, info, float(t), x, _switching_events(sys_, event_log))
        return Trajectory(
            system=sys_,
            t0=t0,
            t1=float(t),
            x0=x0,
            x1=x,
            mode0=names[m0],
            mode1=names[int(info[kc.INFO_FINAL_MODE])],
            event_log=event_log,
            monodromy=Phi if variational else None,
            parameter_sensitivity=psi if (variational and sensitivity >= 0) else None,
            x_min=xmin,
            x_max=xmax,
            sliding_at_end=bool(info[kc.INFO_SLIDE]),
            velocity_end=velocity,
            n_steps=int(info[kc.INFO_STEPS]),
            n_rejected=int(info[kc.INFO_REJECTED]),
            _steps=_steps(res[n_out + n_ev * w_ev :], n) if dense else None,
        )


def _c_array(a) -> np.ndarray:
    """``a`` as the engine and the model functions take arrays (their signatures are fixed): float64,
    C-contiguous and writeable, copied only when it is not already."""
    if type(a) is np.ndarray and a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable:
        return a  # the common case, without np.require's general checks (a few microseconds a call)
    return np.require(a, dtype=np.float64, requirements=("C", "W"))


def _newton_unpack(packed: np.ndarray, m_z: int, m_u: int) -> tuple[np.ndarray, ...]:
    """The kernel Newton's packed result: ``z``, the residual history, ``[r | J_u | J_lam]`` (``m_u`` rows)
    and the bordered system's tangent direction (``m_z`` entries, none for the period map alone)."""
    n_tan = m_z if m_z > m_u else 0
    end = packed.size - n_tan
    n_jac = m_u * (m_u + 2)
    return (packed[:m_z], packed[m_z : end - n_jac], packed[end - n_jac : end].reshape(m_u, m_u + 2),
            packed[end:])


def _steps(packed: np.ndarray, n: int) -> tuple[np.ndarray, ...]:
    """The kernel's record of steps: starts, sizes, end fractions, start states, dense-output coefficients."""
    w_rec = 3 + n
    n_rec = packed.size // (w_rec + 7 * n)
    rec = packed[: n_rec * w_rec].reshape(n_rec, w_rec)
    return rec[:, 0], rec[:, 1], rec[:, 2], rec[:, 3:], packed[n_rec * w_rec :].reshape(n_rec, 7, n)


def _switching_events(system: PiecewiseSystem, event_log: tuple[np.ndarray, ...]) -> list[SwitchingEvent]:
    """The kernel's event log as :class:`SwitchingEvent` records."""
    ev_t, ev_int, ev_xm, ev_xp, ev_S = event_log
    names, surfaces = system.mode_names, system.surface_names
    return [
        SwitchingEvent(
            t=float(ev_t[k]),
            kind=EventKind(int(ev_int[k, 0])),
            transition=int(ev_int[k, 1]),
            surface=surfaces[int(ev_int[k, 2])],
            mode_from=names[int(ev_int[k, 3])],
            mode_to=names[int(ev_int[k, 4])],
            x_minus=ev_xm[k],
            x_plus=ev_xp[k],
            saltation=ev_S[k],
        )
        for k in range(len(ev_t))
    ]


def _error(status: Status, system: PiecewiseSystem, info: np.ndarray, t: float, x: np.ndarray, events) -> IntegrationError:
    m, k = int(info[kc.INFO_FAILED_MODE]), int(info[kc.INFO_FAILED_SURFACE])
    mode = system.mode_names[m] if m >= 0 else "?"
    surface = system.surface_names[k] if k >= 0 else "?"
    where = f"at t = {t:.12g}, x = {np.array2string(np.asarray(x), precision=6)}, in mode {mode!r}"
    if status == Status.CHATTERING and int(info[kc.INFO_SLIDE]) == kc.TIME_UNRESOLVED:
        return IntegrationError(
            f"the time axis cannot resolve the motion {where}: switching events on surface {surface!r} closer than a "
            f"few rounding units of t (ulp(t) = {np.spacing(abs(t)):.3g}); integrate from a smaller t0 (shift the time "
            "origin by a multiple of the forcing period)"
        )
    if status == Status.CHATTERING:
        recent = ", ".join(f"{e.surface}@{e.t:.6g}" for e in events[-5:])
        return ChatteringError(
            f"chattering {where}: many switching events on surface {surface!r} in a vanishing time interval "
            f"(last events: {recent}); the model may need a sliding mode or a different transition"
        )
    if status == Status.MAX_EVENTS:
        return ChatteringError(f"more switching events than max_events {where} (last surface {surface!r})")
    if status == Status.STEP_TOO_SMALL:
        hint = ""
        if np.spacing(abs(t)) > 1e-9 or k >= 0:  # far from t = 0, or at an event on surface k
            hint = (f": the time axis cannot resolve the motion at this t (ulp(t) = {np.spacing(abs(t)):.3g}); integrate "
                    "from a smaller t0 (shift the time origin by a multiple of the forcing period)")
        return StepSizeError(f"step size fell below floating-point resolution {where}{hint}")
    if status == Status.NON_FINITE:
        return NonFiniteError(f"the vector field of mode {mode!r} returned NaN or infinity {where}")
    if status == Status.SLIDING_UNDEFINED:
        cause = int(info[kc.INFO_SLIDE])
        if cause == kc.SLIDE_RESET_INTO:
            k_tr = int(info[kc.INFO_SLIDE + 1])
            tr = system.transitions[k_tr]
            return SlidingError(
                f"the reset of transition {k_tr} ({tr.source} -> {tr.target} on surface {surface!r}) leaves the state "
                f"on the surface {where}, and the field of mode {tr.target!r} pushes it back across (an impact with "
                "restitution 0 or below, or a state at rest on the surface): sliding with a reset map is not defined; "
                "the model needs a sticking mode"
            )
        if cause not in (kc.SLIDE_LEAVES_REGION, kc.SLIDE_BLOCKED):
            return SlidingError(
                f"sliding on surface {surface!r} {where} is required (the target field pushes back into the surface) "
                "but is not defined: the transition has a reset map or both fields are tangent"
            )
        # a sliding motion that cannot go on: its modes and surface are kept in the sliding state
        a, b = (system.mode_names[int(info[kc.INFO_SLIDE + j])] for j in (1, 2))
        own = int(info[kc.INFO_SLIDE + 3])
        motion = f"the sliding motion on surface {system.surface_names[own]!r} ({a}|{b})"
        at = f"at t = {t:.12g}, x = {np.array2string(np.asarray(x), precision=6)}"
        if cause == kc.SLIDE_LEAVES_REGION:
            across = f"across surface {surface!r}" if k != own else "where no other switching surface lies"
            return SlidingError(
                f"{motion} leaves the domain of mode {mode!r} {across} {at}, and no transition out of {a!r} or {b!r} "
                "holds there: the model does not say how the motion goes on (a sliding motion is defined only where "
                "both its modes are)"
            )
        if m >= 0:
            return SlidingError(
                f"{motion} meets surface {surface!r} {at}, where a transition leads into mode {mode!r}, whose field "
                f"pushes back across {surface!r}: that would be sliding on two surfaces at once, which is not supported"
            )
        return SlidingError(
            f"{motion} meets surface {surface!r} {at}, where the transitions out of {a!r} and {b!r} lead into two "
            f"modes whose fields both leave surface {system.surface_names[own]!r}: the motion beyond is not unique"
        )
    if status == Status.TANGENTIAL:
        return IntegrationError(f"switching event exactly tangent to surface {surface!r} {where}: the saltation matrix is undefined")
    if status == Status.MAX_STEPS:
        return IntegrationError(f"more steps than max_steps {where}")
    if status == Status.OUTSIDE_DOMAIN:
        last = events[-1] if events else None
        after = f"after {last.mode_from!r} -> {last.mode_to!r} on surface {last.surface!r} " if last else ""
        return ModelError(
            f"the state {after}lies outside the domain of mode {mode!r} {where}, by more than rounding, and no "
            "transition out of that mode holds there: the model's domains and transitions disagree"
        )
    return IntegrationError(f"integration failed with status {status.name} {where}")


def simulate(
    system: PiecewiseSystem,
    x0: Sequence[float],
    t_span: tuple[float, float],
    *,
    parameters: Mapping[str, float] | None = None,
    mode0: int | str | None = None,
    variational: bool = False,
    dense: bool = True,
    tolerances: Tolerances | None = None,
) -> Trajectory:
    """Integrate a model over ``t_span = (t0, t1)``; backward in time when ``t1 < t0``.

    A convenience around :class:`Flow` (which keeps the compiled kernels for
    repeated use).

    Parameters
    ----------
    system : PiecewiseSystem
        The model.
    x0 : array_like, shape (n,)
        Initial state.
    t_span : tuple of float
        ``(t0, t1)``, start and end time.
    parameters : mapping, optional
        Parameter values by name (the model's defaults for the others).
    mode0 : int or str, optional
        Initial mode; by default the model's initial-mode rule.
    variational : bool
        Carry the fundamental solution matrix (the monodromy over the span).
    dense : bool
        Keep the dense output (:meth:`Trajectory.sample`, :meth:`Trajectory.at`).
    tolerances : Tolerances, optional
        Integration tolerances (``Tolerances()`` by default).

    Returns
    -------
    Trajectory
        The solution over the span, with its events.

    Raises
    ------
    ModelError
        A state or parameter of the wrong size or not finite, an unknown mode or parameter name, or a
        state that leaves a mode's domain where no transition holds.
    ValueError
        If a time of ``t_span`` is not finite.
    InitialModeError
        If ``mode0`` is not given and ``x0`` lies in no mode's domain.
    IntegrationError
        If the integration fails (:class:`ChatteringError`, :class:`StepSizeError`,
        :class:`NonFiniteError`, :class:`SlidingError`, or :class:`IntegrationError` itself).
    KernelCacheError
        If the model cannot be compiled into the kernel cache.

    References
    ----------
    Hairer, Norsett and Wanner (1993), *Solving Ordinary Differential Equations I: Nonstiff Problems*,
    2nd ed., Springer (DOP853).  Filippov (1988), *Differential Equations with Discontinuous
    Righthand Sides*, Kluwer (sliding).
    """
    flow = Flow(system, tolerances)
    return flow.run(x0, t_span[0], t_span[1], flow.parameters(parameters), mode0=mode0, variational=variational, dense=dense)
