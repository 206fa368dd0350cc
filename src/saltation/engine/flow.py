"""Event-driven integration of piecewise-smooth systems, forward and backward in time.

The work happens in the compiled engine, shared by every model, with the
model's own compiled functions (see :mod:`saltation.engine.codegen`); this module is
the thin typed driver around it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from saltation._moved import forward_names
from saltation.engine import _contract as kc
from saltation.engine import _no_terminal_reset_at_exit, chatter, kernel_newton
from saltation.engine.codegen import (
    is_engine_compiled,
    load_engine,
    load_model_functions,
    model_addresses,
    transition_table,
)
from saltation.engine.kernel_newton import CompiledNewton, _c_array, _newton_unpack  # noqa: F401 (see __all__)
from saltation.engine.trajectory import (  # noqa: F401 (the private names: imported from here until 0.3.0)
    _STATUS_OK,
    EventKind,
    Status,
    SwitchingEvent,
    Trajectory,
    _dense_eval,
    _dense_values,
    _error,
    _steps,
    _switching_events,
    unpack_result,
)
from saltation.errors import InitialModeError, IntegrationError, ModelError
from saltation.model.system import TIME, PiecewiseSystem

_no_terminal_reset_at_exit()

#: A state outside a named start mode's domain by at most this much (relative to ``1 + max |x_i|``) lies on
#: its boundary, within rounding (the engine's tolerance for a state that leaves its mode's domain).
DOMAIN_ROUNDING = 1e-8
#: the steps per forcing period, at least, of a forced model with a surface that moves with time (Flow)
TIME_SURFACE_STEPS = 16


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
    return _dense_values(F, y0, s)


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

    # The model's compiled functions, one method each: the mode, surface or transition by index or name, then
    # (t, x, p), as the engine calls them (saltation.engine._contract.MODEL_SIGNATURES), into fresh arrays.

    def _call(self, function: int, index: int, t: float, x: Sequence[float], p: np.ndarray, *out: np.ndarray):
        """The model's compiled ``function`` (its row in the contract's model tuple) at ``(index, t, x, p)``,
        writing into ``out``."""
        return self._model[function](index, float(t), _c_array(x), _c_array(p), *out)

    def _surface(self, surface: int | str) -> int:
        return int(surface) if isinstance(surface, (int, np.integer)) else self.system.surface_index(surface)

    def _parameter_buffer(self) -> np.ndarray:
        return np.zeros(max(self.system.n_params, 1))  # (a model without parameters still takes one entry)

    def vector_field(self, mode: int | str, t: float, x: Sequence[float], p: np.ndarray) -> np.ndarray:
        """The vector field ``f(t, x, p)`` of a mode.

        Parameters
        ----------
        mode : int or str
            Index or name of the mode.
        t, x, p : float, array_like of shape (n,), ndarray of shape (n_params,)
            Time, state and parameter values.

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
        self._call(kc.VECTOR_FIELD, self.system.mode_index(mode), t, x, p, f)
        return f

    def vector_field_jacobian(self, mode: int | str, t: float, x: Sequence[float], p: np.ndarray) -> np.ndarray:
        """The Jacobian ``f_x`` of a mode's vector field (arguments and errors as :meth:`vector_field`).

        Parameters
        ----------
        mode : int or str
            Index or name of the mode.
        t, x, p : float, array_like of shape (n,), ndarray of shape (n_params,)
            Time, state and parameter values.

        Returns
        -------
        ndarray, shape (n, n)
            ``f_x`` at ``(t, x)``.
        """
        J = np.zeros((self.system.n, self.system.n))
        self._call(kc.VECTOR_FIELD_JAC, self.system.mode_index(mode), t, x, p, J)
        return J

    def vector_field_parameters(self, mode: int | str, t: float, x: Sequence[float], p: np.ndarray) -> np.ndarray:
        """The parameter derivative ``f_p`` of a mode's vector field (arguments and errors as :meth:`vector_field`).

        Parameters
        ----------
        mode : int or str
            Index or name of the mode.
        t, x, p : float, array_like of shape (n,), ndarray of shape (n_params,)
            Time, state and parameter values.

        Returns
        -------
        ndarray, shape (n, n_params)
            ``f_p`` at ``(t, x)``.
        """
        fp = np.zeros((self.system.n, max(self.system.n_params, 1)))
        self._call(kc.VECTOR_FIELD_DP, self.system.mode_index(mode), t, x, p, fp)
        return fp[:, : self.system.n_params]

    def indicator(self, surface: int | str, t: float, x: Sequence[float], p: np.ndarray) -> float:
        """The indicator ``h(t, x, p)`` of a switching surface.

        Parameters
        ----------
        surface : int or str
            Index or name of the surface.
        t, x, p : float, array_like of shape (n,), ndarray of shape (n_params,)
            Time, state and parameter values.

        Returns
        -------
        float
            The value of the indicator (zero on the surface).

        Raises
        ------
        ModelError
            If ``surface`` names no surface of the model.
        """
        return float(self._call(kc.INDICATOR, self._surface(surface), t, x, p))

    def indicator_gradient(self, surface: int | str, t: float, x: Sequence[float], p: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
        """The derivatives ``(h_x, h_t, h_p)`` of a switching surface's indicator (arguments and errors as
        :meth:`indicator`).

        Parameters
        ----------
        surface : int or str
            Index or name of the surface.
        t, x, p : float, array_like of shape (n,), ndarray of shape (n_params,)
            Time, state and parameter values.

        Returns
        -------
        h_x : ndarray, shape (n,)
            Gradient in the state.
        h_t : float
            Derivative in time (non-zero for a moving surface).
        h_p : ndarray, shape (n_params,)
            Gradient in the parameters.
        """
        hx, hp = np.zeros(self.system.n), self._parameter_buffer()
        ht = self._call(kc.INDICATOR_GRAD, self._surface(surface), t, x, p, hx, hp)
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
        t, x, p : float, array_like of shape (n,), ndarray of shape (n_params,)
            Time, state and parameter values.

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
        m, k = self.system.mode_index(mode), self._surface(surface)
        gx, gp = np.zeros(self.system.n), self._parameter_buffer()
        x, p = _c_array(np.array(x, dtype=float)), _c_array(p)
        value = float(self._model[kc.LIE_DERIVATIVE](m, k, float(t), x, p, gx, gp))
        rate_t = float(self._model[kc.LIE_DERIVATIVE_DT](m, k, float(t), x, p))
        return value, gx, gp[: self.system.n_params], rate_t

    def guard_holds(self, transition: int, t: float, x: Sequence[float], p: np.ndarray) -> bool:
        """Whether every condition of a transition's guard holds at ``(t, x)``.

        Parameters
        ----------
        transition : int
            Index of the transition.
        t, x, p : float, array_like of shape (n,), ndarray of shape (n_params,)
            Time, state and parameter values.

        Returns
        -------
        bool
            True when the guard holds (always, for a transition without a guard).
        """
        return bool(self._call(kc.GUARD, int(transition), t, x, p))

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
        Filippov's convex combination where both fields push into it.  Impacts that accumulate where the
        contact sticks (``sticks=True``, restitution ``0 < e < 1``: complete chatter) are jumped to their
        accumulation point, and the run goes on in the stuck mode (:mod:`saltation.engine.chatter`).

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
            (with ``variational``) and dense output (with ``dense``); each complete chatter jumped is one
            event into the stuck mode at its accumulation point, recorded in
            :attr:`Trajectory.accumulations`.

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
            If the integration fails: :class:`ChatteringError` (too many events, events closer than
            the time axis resolves, a Zeno accumulation of impacts that do not stick, or a run that ends
            too shortly before an accumulation point to resolve the impacts left), :class:`StepSizeError`, :class:`NonFiniteError`,
            :class:`SlidingError` (a sliding motion the model does not define), or an
            :class:`IntegrationError` itself (a tangential event, too many steps, a degenerate case).
            The message names the mode and surface involved.

        References
        ----------
        Hairer, Norsett and Wanner (1993), *Solving Ordinary Differential Equations I: Nonstiff Problems*,
        2nd ed., Springer (DOP853).  Filippov (1988), *Differential Equations with Discontinuous
        Righthand Sides*, Kluwer (sliding).  Leine and Van Campen, "Fold bifurcations in discontinuous
        systems", eq. (9) (saltation matrices).  Nordmark and Piiroinen (2009), "Simulation and stability
        analysis of impacting systems with complete chattering", *Nonlinear Dynamics* 58 (complete chatter).
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
        table = self._table
        if len(disabled):
            table = table.copy()
            for k in disabled:
                table[int(k), 0] = -1  # a source mode that is never current
        traj, accumulates = self._piece(x0, t0, t1, m0, p, variational, sens, dense, tol, phi, psi, table)
        if accumulates:  # impacts that accumulate where the contact sticks: jumped to their limit
            return chatter.run_through_accumulations(self, traj, t1=t1, p=p, variational=bool(variational),
                                                     sensitivity=sens, dense=bool(dense), tolerances=tol, table=table)
        return traj

    def _piece(self, x0: np.ndarray, t0: float, t1: float, m0: int, p: np.ndarray, variational: bool, sens: int,
               dense: bool, tol: Tolerances, phi: np.ndarray | None, psi: np.ndarray | None,
               table: np.ndarray) -> tuple[Trajectory, bool]:
        """One run of the engine (arguments checked by :meth:`run`), and whether it stopped where impacts
        accumulate (then the trajectory ends just after the last impact kept)."""
        sys_ = self.system
        steps, limits, flags = self._kernel_tolerances(tol, p)
        phi = self._identity if phi is None else _c_array(phi)
        psi = self._zeros if psi is None else _c_array(psi)
        x0 = _c_array(x0)
        try:
            out = self._engine.integrate_kernel(
                self._addresses, self._affine_modes, float(t0), float(t1), x0, int(m0), p, bool(variational), int(sens),
                *steps, 0.0, *limits, table, self._n_surfaces, bool(dense), phi, psi, *flags,
            )
        except ArithmeticError as exc:  # the compiled engine raises Python's errors for a division by zero
            raise IntegrationError(
                f"the engine failed ({type(exc).__name__}: {exc}) integrating {sys_.name!r} from t = {t0:.12g} to "
                f"{t1:.12g}, x0 = {x0.tolist()}, parameters {p.tolist()}: a degenerate case it does not resolve"
            ) from None
        accumulates = int(out[0][kc.INFO_STATUS]) == kc.STATUS_ACCUMULATION
        traj = unpack_result(sys_, out, x0, float(t0), int(m0), variational, sens, dense, self._offsets,
                             accumulation=accumulates)
        return traj, accumulates

    def compiled_newton(
        self, z0: np.ndarray, normal: np.ndarray | None, p: np.ndarray, *, t0: float, sign: float, lam_index: int,
        span: float, phase: tuple[np.ndarray, np.ndarray] | None, tol: float, max_iter: int, max_correction: float,
        damped: bool, tolerances: Tolerances | None = None,
    ) -> CompiledNewton | None:
        """Run the kernel's Newton loop on periodic orbits (no return to Python per shot):
        :func:`saltation.engine.kernel_newton.compiled_newton` on this flow.

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
        return kernel_newton.compiled_newton(
            self, z0, normal, p, t0=t0, sign=sign, lam_index=lam_index, span=span, phase=phase, tol=tol,
            max_iter=max_iter, max_correction=max_correction, damped=damped, tolerances=tolerances)

    def shot_trajectory(self, result: CompiledNewton, x0: np.ndarray, t0: float, p: np.ndarray, sensitivity: int) -> Trajectory:
        """The trajectory of the last shot of :meth:`compiled_newton`
        (:func:`saltation.engine.kernel_newton.shot_trajectory`).

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
        return kernel_newton.shot_trajectory(self, result, x0, t0, p, sensitivity)

    def _unpack(self, out, x0, t0, m0, variational, sensitivity, dense) -> Trajectory:
        return unpack_result(self.system, out, x0, t0, m0, variational, sensitivity, dense, self._offsets)


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


# Names re-exported from the modules they moved to (saltation.engine.trajectory, saltation.engine.kernel_newton):
# importable from here until 0.3.0.
__all__ = ["CompiledNewton", "EventKind", "Flow", "Status", "SwitchingEvent", "Tolerances", "Trajectory", "dense_evaluate",
           "simulate"]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.errors',))
