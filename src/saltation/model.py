"""Piecewise-smooth dynamical systems: modes, switching surfaces, transitions.

A :class:`PiecewiseSystem` is pure mathematics.  It holds named states and
parameters, a smooth vector field ``f(t, x, p)`` per *mode*, switching
surfaces given by indicator functions ``h(t, x, p)``, and *transitions*
``(source mode, surface, crossing direction) -> target mode`` with an optional
reset map ``g(t, x, p)`` (impacts) and an optional guard.  Expressions are
sympy expressions or strings that sympy parses; every derivative that the
numerical methods need is derived exactly from them.

Semantics
---------
* A transition fires when, *followed in the direction of integration*, the
  indicator of its surface changes sign in the given direction
  (``Crossing.RISING``: from negative to positive) while the system is in the
  source mode, and its guard (if any) holds at the crossing.  The same list
  serves forward and backward time: a region-based model (a Filippov system)
  lists every boundary both ways.
* Sliding (Filippov's convex combination) starts automatically when, after a
  transition without reset, the target field pushes back into the surface.
* The initial mode is the first mode, in declaration order, whose ``domain``
  conditions all hold at the initial state; a mode without conditions matches
  every state.  Pass ``mode0`` to the integrator to choose it yourself.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import sympy as sp

from .errors import InitialModeError, ModelError

TIME = sp.Symbol("t", real=True)

Expr = sp.Expr | str | float | int


class Crossing(enum.IntEnum):
    """Direction in which an indicator changes sign, followed in the direction of integration."""

    RISING = 1
    FALLING = -1
    EITHER = 0


@dataclass(frozen=True)
class Mode:
    """A smooth piece of the system.

    Parameters
    ----------
    name : str
        Name of the mode.
    field : sequence of expressions
        The vector field ``f(t, x, p)``, one expression per state.
    domain : sequence of relations, optional
        Conditions such as ``"x - x_c > 0"`` that define the region of the
        mode; used only to choose the initial mode.
    """

    name: str
    field: Sequence[Expr]
    domain: Sequence[Expr] = ()


@dataclass(frozen=True)
class Transition:
    """A switching event ``source --(surface, direction)--> target``.

    Parameters
    ----------
    source, target : str
        Names of the modes before and after the event.
    surface : str
        Name of the switching surface whose indicator changes sign.
    direction : Crossing
        Required direction of the sign change (in the direction of integration).
    reset : sequence of expressions, optional
        Reset map ``x+ = g(t, x-, p)`` (impacts); identity when omitted.
    guard : sequence of relations, optional
        Conditions that must hold at the crossing for the transition to fire.
    """

    source: str
    surface: str
    direction: Crossing
    target: str
    reset: Sequence[Expr] | None = None
    guard: Sequence[Expr] = ()

    @property
    def label(self) -> str:
        """Human-readable name, e.g. ``free -[h1a+]-> contact``."""
        sign = {1: "+", -1: "-", 0: "+-"}[int(self.direction)]
        return f"{self.source} -[{self.surface}{sign}]-> {self.target}"


@dataclass(frozen=True)
class Condition:
    """A normalised inequality ``sign * expr > 0`` (``>=`` when ``strict`` is False)."""

    expr: sp.Expr
    strict: bool

    def holds(self, value: float) -> bool:
        return value > 0.0 if self.strict else value >= 0.0


def _sympify(value: Expr, symbols: Mapping[str, sp.Symbol], where: str) -> sp.Expr:
    try:
        expr = sp.sympify(value, locals=dict(symbols)) if isinstance(value, str) else sp.sympify(value)
    except (sp.SympifyError, SyntaxError, TypeError) as exc:
        raise ModelError(f"{where}: cannot parse expression {value!r}: {exc}") from None
    unknown = {s.name for s in expr.free_symbols} - set(symbols)
    if unknown:
        raise ModelError(
            f"{where}: unknown symbol(s) {sorted(unknown)} in {value!r}; "
            f"known states, parameters and time: {sorted(symbols)}"
        )
    # Re-bind symbols created elsewhere with other assumptions to ours.
    return expr.xreplace({s: symbols[s.name] for s in expr.free_symbols})


def _condition(value: Expr, symbols: Mapping[str, sp.Symbol], where: str) -> Condition:
    rel = _sympify(value, symbols, where) if not isinstance(value, sp.Basic) else value
    if isinstance(rel, sp.Basic) and not isinstance(rel, sp.core.relational.Relational):
        raise ModelError(f"{where}: {value!r} is not an inequality such as 'x - x_c > 0'")
    if isinstance(rel, (sp.StrictGreaterThan, sp.GreaterThan)):
        expr = rel.lhs - rel.rhs
    elif isinstance(rel, (sp.StrictLessThan, sp.LessThan)):
        expr = rel.rhs - rel.lhs
    else:
        raise ModelError(f"{where}: {value!r} must be a strict or non-strict inequality")
    strict = isinstance(rel, (sp.StrictGreaterThan, sp.StrictLessThan))
    expr = _sympify(expr, symbols, where)
    return Condition(expr=expr, strict=strict)


@dataclass(frozen=True)
class _SurfaceDerivatives:
    h: sp.Expr
    h_x: sp.Matrix
    h_t: sp.Expr
    h_p: sp.Matrix


class NamedParts:
    """Lookups shared by every kind of model: sizes, and indices of modes, surfaces and parameters.

    Needs the attributes ``state_names``, ``parameter_names``, ``mode_names``,
    ``surface_names`` and ``defaults``.
    """

    @property
    def n(self) -> int:
        """Number of states."""
        return len(self.state_names)

    @property
    def n_params(self) -> int:
        return len(self.parameter_names)

    def mode_index(self, name: str | int) -> int:
        if isinstance(name, (int, np.integer)):
            if not 0 <= int(name) < len(self.mode_names):
                raise ModelError(f"mode index {name} out of range 0..{len(self.mode_names) - 1}")
            return int(name)
        try:
            return self.mode_names.index(name)
        except ValueError:
            raise ModelError(f"unknown mode {name!r}; modes are {list(self.mode_names)}") from None

    def surface_index(self, name: str) -> int:
        try:
            return self.surface_names.index(name)
        except ValueError:
            raise ModelError(f"unknown surface {name!r}; surfaces are {list(self.surface_names)}") from None

    def parameter_index(self, name: str) -> int:
        try:
            return self.parameter_names.index(name)
        except ValueError:
            raise ModelError(f"unknown parameter {name!r}; parameters are {list(self.parameter_names)}") from None

    def parameter_vector(self, overrides: Mapping[str, float] | None = None) -> np.ndarray:
        """Parameter values as an array, defaults replaced by ``overrides``.

        Raises
        ------
        ModelError
            If an override names an unknown parameter or is not finite.
        """
        values = dict(self.defaults)
        for key, val in (overrides or {}).items():
            self.parameter_index(key)
            val = float(val)
            if not math.isfinite(val):
                raise ModelError(f"parameter {key!r} must be finite, got {val}")
            values[key] = val
        return np.array([values[k] for k in self.parameter_names], dtype=float)

    @cached_property
    def _period_functions(self):
        args = list(self.p)
        period = sp.lambdify(args, self.period_expr, modules="math")
        derivatives = [sp.lambdify(args, sp.diff(self.period_expr, q), modules="math") for q in self.p]
        return period, derivatives



class PiecewiseSystem(NamedParts):
    """A piecewise-smooth (discontinuous) dynamical system.

    Parameters
    ----------
    name : str
        Name of the model (used for cached compiled kernels and in reports).
    states : sequence of str
        Names of the states, in order.
    parameters : mapping of str to float
        Parameter names with default values.
    modes : sequence of Mode
        The smooth pieces.
    surfaces : mapping of str to expression
        Switching surfaces by name, each an indicator ``h(t, x, p)``.
    transitions : sequence of Transition
        Switching rules.
    period : expression, optional
        For forced (time-periodic) systems, the forcing period in terms of the
        parameters, e.g. ``"2*pi/omega"``.  ``None`` for autonomous systems.

    Raises
    ------
    ModelError
        For an unknown mode, surface, parameter or symbol, a field of the
        wrong length, an indicator that does not depend on the state, or a
        transition to a mode that does not exist.
    """

    def __init__(
        self,
        name: str,
        states: Sequence[str],
        parameters: Mapping[str, float],
        modes: Sequence[Mode],
        surfaces: Mapping[str, Expr],
        transitions: Sequence[Transition],
        *,
        period: Expr | None = None,
    ):
        if not name.replace("_", "").isalnum():
            raise ModelError(f"model name {name!r} must be alphanumeric (underscores allowed)")
        self.name = name
        self.state_names: tuple[str, ...] = tuple(states)
        self.parameter_names: tuple[str, ...] = tuple(parameters)
        self.defaults: dict[str, float] = {}
        for pname, value in parameters.items():
            if value is None:
                raise ModelError(f"parameter {pname!r} has no value")
            try:
                self.defaults[pname] = float(value)
            except (TypeError, ValueError):
                raise ModelError(f"parameter {pname!r} has non-numeric value {value!r}") from None
        names = list(self.state_names) + list(self.parameter_names) + ["t"]
        dupes = {n for n in names if names.count(n) > 1}
        if dupes:
            raise ModelError(f"names used twice among states, parameters and time 't': {sorted(dupes)}")
        if not self.state_names:
            raise ModelError("a model needs at least one state")
        self.x = sp.Matrix([sp.Symbol(s, real=True) for s in self.state_names])
        self.p = sp.Matrix([sp.Symbol(s, real=True) for s in self.parameter_names])
        self.t = TIME
        self._symbols = {s.name: s for s in list(self.x) + list(self.p)} | {"t": TIME}

        if not modes:
            raise ModelError("a model needs at least one mode")
        self.modes: tuple[Mode, ...] = tuple(modes)
        self.mode_names: tuple[str, ...] = tuple(m.name for m in modes)
        if len(set(self.mode_names)) != len(self.mode_names):
            raise ModelError(f"mode names must be unique: {self.mode_names}")
        self.fields: tuple[sp.Matrix, ...] = tuple(self._parse_field(m) for m in modes)
        self.domains: tuple[tuple[Condition, ...], ...] = tuple(
            tuple(_condition(c, self._symbols, f"domain of mode {m.name!r}") for c in m.domain) for m in modes
        )

        self.surface_names: tuple[str, ...] = tuple(surfaces)
        self.indicators: tuple[sp.Expr, ...] = tuple(
            _sympify(expr, self._symbols, f"surface {sname!r}") for sname, expr in surfaces.items()
        )
        for sname, h in zip(self.surface_names, self.indicators):
            if not (h.free_symbols & set(self.x)):
                raise ModelError(
                    f"surface {sname!r}: indicator {h} does not depend on the state {list(self.state_names)}; "
                    "a switching surface must be crossed by moving in state space"
                )

        self.transitions: tuple[Transition, ...] = tuple(transitions)
        self.resets: list[sp.Matrix | None] = []
        self.guards: list[tuple[Condition, ...]] = []
        for k, tr in enumerate(self.transitions):
            where = f"transition {k} ({tr.source} -> {tr.target})"
            for role, mname in (("source", tr.source), ("target", tr.target)):
                if mname not in self.mode_names:
                    raise ModelError(f"{where}: {role} mode {mname!r} does not exist; modes are {list(self.mode_names)}")
            if tr.surface not in self.surface_names:
                raise ModelError(f"{where}: surface {tr.surface!r} does not exist; surfaces are {list(self.surface_names)}")
            try:
                Crossing(int(tr.direction))
            except ValueError:
                raise ModelError(f"{where}: direction must be a Crossing (+1, -1 or 0), got {tr.direction!r}") from None
            if tr.reset is None:
                self.resets.append(None)
            else:
                if len(tr.reset) != self.n:
                    raise ModelError(f"{where}: reset map has {len(tr.reset)} components, the model has {self.n} states")
                self.resets.append(sp.Matrix([_sympify(e, self._symbols, f"{where} reset") for e in tr.reset]))
            self.guards.append(tuple(_condition(c, self._symbols, f"{where} guard") for c in tr.guard))

        if period is None:
            self.period_expr: sp.Expr | None = None
        else:
            self.period_expr = _sympify(period, self._symbols, "forcing period")
            if self.period_expr.free_symbols & (set(self.x) | {TIME}):
                raise ModelError("the forcing period may depend on parameters only")
        if self.period_expr is None and any(TIME in f.free_symbols for f in self.fields):
            raise ModelError("a vector field depends on time t but no forcing period is given (period=...)")

    # -- construction helpers ---------------------------------------------------------------
    def _parse_field(self, mode: Mode) -> sp.Matrix:
        where = f"mode {mode.name!r}"
        if isinstance(mode.field, (str, sp.Basic)) or len(mode.field) != len(self.state_names):
            size = "?" if isinstance(mode.field, (str, sp.Basic)) else len(mode.field)
            raise ModelError(f"{where}: vector field has {size} components, the model has {len(self.state_names)} states")
        return sp.Matrix([_sympify(e, self._symbols, where) for e in mode.field])

    # -- sizes and lookups ------------------------------------------------------------------
    @property
    def is_autonomous(self) -> bool:
        return self.period_expr is None

    def forcing_period(self, p: np.ndarray) -> float:
        """The forcing period for parameter values ``p`` (forced systems only)."""
        if self.period_expr is None:
            raise ModelError(f"model {self.name!r} is autonomous: it has no forcing period")
        try:
            value = float(self._period_functions[0](*np.asarray(p, dtype=float).tolist()))
        except (ZeroDivisionError, OverflowError, ValueError):
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise ModelError(f"forcing period {self.period_expr} evaluates to {value} for these parameters")
        return value

    def period_derivative(self, p: np.ndarray, index: int) -> float:
        """Derivative of the forcing period with respect to parameter ``index``."""
        if self.period_expr is None:
            return 0.0
        return float(self._period_functions[1][index](*np.asarray(p, dtype=float).tolist()))

    # -- initial mode -----------------------------------------------------------------------
    def initial_mode(self, x0: Sequence[float], p: np.ndarray, t0: float = 0.0) -> int:
        """The first mode whose domain conditions all hold at ``(t0, x0)``.

        Raises
        ------
        InitialModeError
            If the state lies in no mode's domain.
        """
        subs = dict(zip(self.x, map(float, x0))) | dict(zip(self.p, map(float, p))) | {TIME: float(t0)}
        for k, conditions in enumerate(self.domains):
            if all(c.holds(float(c.expr.subs(subs))) for c in conditions):
                return k
        raise InitialModeError(
            f"initial state {list(map(float, x0))} at t = {t0} lies in no mode of {self.name!r}; "
            f"domains: { {m: [str(c.expr) for c in d] for m, d in zip(self.mode_names, self.domains)} }"
        )

    # -- exact derivatives ------------------------------------------------------------------
    def jacobian(self, mode: int | str) -> sp.Matrix:
        """``f_x`` of a mode."""
        return self.fields[self.mode_index(mode)].jacobian(self.x)

    def surface_derivatives(self, surface: int | str) -> _SurfaceDerivatives:
        k = surface if isinstance(surface, int) else self.surface_index(surface)
        h = self.indicators[k]
        return _SurfaceDerivatives(
            h=h,
            h_x=sp.Matrix([h]).jacobian(self.x),
            h_t=sp.diff(h, TIME),
            h_p=sp.Matrix([h]).jacobian(self.p) if self.n_params else sp.zeros(1, 0),
        )

    def lie_derivative(self, mode: int | str, surface: int | str) -> sp.Expr:
        """``dh/dt = h_x f + h_t`` of a surface along the field of a mode."""
        d = self.surface_derivatives(surface)
        return sp.expand((d.h_x * self.fields[self.mode_index(mode)])[0, 0] + d.h_t)

    def reset_map(self, transition: int) -> sp.Matrix:
        """The reset map of a transition (the identity when it has none)."""
        g = self.resets[transition]
        return self.x if g is None else g

    def saltation_matrix(self, transition: int, *, on_surface: bool = True, simplify: bool = True) -> sp.Matrix:
        """Closed-form saltation matrix of a transition, eq. (9) generalised to resets.

        ``S = g_x + (f+ - g_x f- - g_t) h_x / (h_x f- + h_t)``, with ``f-`` the
        field of the source mode at ``x``, ``f+`` that of the target mode at
        ``g(x)``.  With ``on_surface`` the indicator's zero set is used to
        simplify (the state lies on the surface when the event happens).
        ``simplify`` gives sympy's most readable form; without it the entries
        are only brought to cancelled fractions (the same functions, some ten
        times faster: what the numerical uses take).
        """
        tr = self.transitions[transition]
        src, dst = self.mode_index(tr.source), self.mode_index(tr.target)
        d = self.surface_derivatives(tr.surface)
        g = self.reset_map(transition)
        g_x = g.jacobian(self.x)
        g_t = sp.diff(g, TIME)
        f_minus = self.fields[src]
        f_plus = self.fields[dst].xreplace(dict(zip(self.x, g)))
        den = (d.h_x * f_minus)[0, 0] + d.h_t
        S = g_x + (f_plus - g_x * f_minus - g_t) * d.h_x / den
        reduce = sp.simplify if simplify else sp.cancel
        S = S.applyfunc(reduce)
        if on_surface:
            S = _simplify_on_surface(S, d.h, self.x, reduce)
        return S

    @cached_property
    def fingerprint(self) -> str:
        """A string that changes whenever the mathematics of the model changes."""
        parts = [
            self.name,
            repr(self.state_names),
            repr(self.parameter_names),
            repr(self.mode_names),
            repr(self.surface_names),
            *(sp.srepr(f) for f in self.fields),
            *(sp.srepr(h) for h in self.indicators),
            *(repr((t.source, t.surface, int(t.direction), t.target)) for t in self.transitions),
            *(sp.srepr(g) if g is not None else "None" for g in self.resets),
            *(repr([(sp.srepr(c.expr), c.strict) for c in gs]) for gs in self.guards),
        ]
        return "\n".join(parts)

    def __getstate__(self) -> dict:
        # compiled helper functions are rebuilt on demand (they do not pickle)
        state = dict(self.__dict__)
        state.pop("_period_functions", None)
        return state

    def _repr_markdown_(self) -> str:
        """A summary for Jupyter (:mod:`saltation.summary`)."""
        from .summary import system_summary

        return system_summary(self)

    def __repr__(self) -> str:
        kind = "autonomous" if self.is_autonomous else f"forced, period {self.period_expr}"
        return (
            f"PiecewiseSystem({self.name!r}, states={list(self.state_names)}, modes={list(self.mode_names)}, "
            f"surfaces={list(self.surface_names)}, {len(self.transitions)} transitions, {kind})"
        )


def _simplify_on_surface(S: sp.Matrix, h: sp.Expr, x: sp.Matrix, reduce=sp.simplify) -> sp.Matrix:
    """Eliminate one state using ``h = 0`` where the indicator is linear in it, then ``reduce`` each entry."""
    for xi in x:
        if h.has(xi) and h.is_polynomial(xi) and sp.degree(h, xi) == 1:
            sol = sp.solve(sp.Eq(h, 0), xi)
            if len(sol) == 1:
                return S.xreplace({xi: sol[0]}).applyfunc(reduce)
    return S
