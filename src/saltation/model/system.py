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

import cmath
import enum
import math
import threading
import unicodedata
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.logic.boolalg import Boolean
from sympy.printing.pycode import PythonCodePrinter

from saltation.errors import InitialModeError, ModelError
from saltation.model.contacts import Sticking, expand_sticking
from saltation.model.nonsmooth import Expansion, expand_nonsmooth
from saltation.model.symmetry import Symmetry, SymmetryMap, check_symmetry
from saltation.model.sides import on_its_side

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
    sticks : bool or sequence of expressions, optional
        An impact that can leave no relative velocity (a plastic impact) continues as a motion
        constrained to its moving surface until the contact force changes sign
        (:mod:`saltation.model.contacts`); True takes the contact force along the one state the reset
        changes, a sequence gives its direction, one expression per state.
    """

    source: str
    surface: str
    direction: Crossing
    target: str
    reset: Sequence[Expr] | None = None
    guard: Sequence[Expr] = ()
    sticks: bool | Sequence[Expr] = False

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


#: Functions that are not smooth: in a field, an indicator or a reset they are switching surfaces in disguise.
_NONSMOOTH = (sp.sign, sp.Heaviside, sp.Abs, sp.Min, sp.Max, sp.Piecewise, sp.floor, sp.ceiling, sp.frac, sp.Mod,
              sp.DiracDelta)
#: Numbers that no compiled model can use.
_NOT_FINITE = (sp.nan, sp.zoo, sp.oo, -sp.oo)


#: Seconds sympy may take to parse one expression of a model (some evaluate special functions at huge
#: arguments for ever).
SYMPY_TIME_LIMIT = 10.0


def _bounded(work, where: str, value):
    """``work()`` in a helper thread, or a :class:`ModelError` if sympy takes longer than
    :data:`SYMPY_TIME_LIMIT` (the thread cannot be stopped; it finishes in the background)."""
    outcome: list = []

    def run():
        try:
            outcome.append((True, work()))
        except BaseException as exc:  # noqa: BLE001 (handed to the caller)
            outcome.append((False, exc))

    thread = threading.Thread(target=run, daemon=True)  # a daemon: a hung sympy does not block the exit
    thread.start()
    thread.join(SYMPY_TIME_LIMIT)
    if not outcome:
        raise _SympyTimeout(f"{where}: sympy did not finish evaluating {value!r} within {SYMPY_TIME_LIMIT:g} s; "
                            "simplify the expression")
    ok, result = outcome[0]
    if not ok:
        raise result
    return result


class _SympyTimeout(ModelError):
    """sympy took longer than :data:`SYMPY_TIME_LIMIT`."""


class _StrictPrinter(PythonCodePrinter):
    """Python's code printer in strict mode: what it cannot print, the compiled model cannot compute."""

    def __init__(self):
        super().__init__({"standard": "python3", "strict": True, "fully_qualified_modules": True})


_PRINTER = _StrictPrinter()


def _sympify(value: Expr, symbols: Mapping[str, sp.Symbol], where: str, *, relation: bool = False) -> sp.Expr:
    """Parse one expression of a model and check that it can be compiled.

    ``relation`` allows an inequality (domains and guards).  Raises :class:`ModelError` naming
    ``where`` for anything else: a wrong type, a relation where an expression is expected, an
    unknown symbol or function, a complex or non-finite value, a function the compiled model
    cannot compute.
    """
    if isinstance(value, bool) or value is None or not isinstance(value, (str, int, float, sp.Basic, np.number)):
        raise ModelError(f"{where}: expected an expression (a string or a sympy expression), got "
                         f"{type(value).__name__} {value!r}")
    if isinstance(value, str) and not value.strip():
        raise ModelError(f"{where}: the expression is empty")

    def parse():
        return sp.sympify(value, locals=dict(symbols)) if isinstance(value, str) else sp.sympify(value)

    try:
        expr = _bounded(parse, where, value)
    except _SympyTimeout:
        raise
    except (sp.SympifyError, SyntaxError, TypeError, AttributeError, ValueError, ZeroDivisionError) as exc:
        raise ModelError(f"{where}: cannot parse expression {value!r}: {type(exc).__name__}: {exc}") from None
    except (RecursionError, OverflowError, MemoryError) as exc:  # sympy evaluating while it parses
        raise ModelError(f"{where}: sympy cannot evaluate expression {value!r} ({type(exc).__name__}: "
                         f"{' '.join(str(exc).split())[:200]}): it is nested too deeply or holds a number too large "
                         "for sympy; simplify it") from None
    if not isinstance(expr, sp.Basic):
        raise ModelError(f"{where}: {value!r} is not an expression")
    if isinstance(expr, Boolean) and not isinstance(expr, sp.Expr) and not relation:
        raise ModelError(f"{where}: {value!r} is a relation or a truth value; an expression such as 'x - a' is expected")
    if not isinstance(expr, (sp.Expr, Boolean)):
        raise ModelError(f"{where}: {value!r} is not an expression (it parses as a {type(expr).__name__})")
    undefined = sorted({str(f.func) for f in expr.atoms(AppliedUndef)})
    if undefined:
        raise ModelError(f"{where}: unknown function(s) {undefined} in {value!r}")
    unknown = {s.name for s in expr.free_symbols} - set(symbols)
    if unknown:
        raise ModelError(
            f"{where}: unknown symbol(s) {sorted(unknown)} in {value!r}; "
            f"known states, parameters and time: {sorted(symbols)}"
        )
    # Re-bind symbols created elsewhere with other assumptions to ours.
    expr = expr.xreplace({s: symbols[s.name] for s in expr.free_symbols})
    if any(expr.has(z) for z in _NOT_FINITE):  # (first: sympy's oo is not "real" either)
        infinite = "infinite" if any(expr.has(z) for z in (sp.oo, -sp.oo, sp.zoo)) else "not a number (NaN)"
        raise ModelError(f"{where}: {value!r} is not finite: it is {infinite} (it evaluates to {expr})")
    if expr.has(sp.I) or any(a.is_real is False for a in expr.atoms(sp.Number)):
        raise ModelError(f"{where}: {value!r} is complex-valued; a model's expressions are real")
    return expr


def _check_compilable(expr: sp.Expr, variables: Sequence[sp.Symbol], where: str, *, smooth: bool) -> None:
    """An expression, and (``smooth``) its first derivatives in ``variables``, can be compiled.

    A non-smooth function (``sign``, ``Heaviside``, ``Abs``, ``Min``, ``Max``, ``Piecewise``...) in a
    field, an indicator or a reset is a switching surface in disguise: its derivative is not a
    function the integrator can use, and the saltation matrix at its switch would be missing.
    """
    if smooth:
        bad = sorted({str(f) for f in expr.atoms(*_NONSMOOTH)})
        if bad:
            raise ModelError(
                f"{where}: {bad[0]} in {expr} is not smooth; write it as modes split by a switching surface where "
                "its argument changes sign (listed both ways, see 'Writing models'), so that the switch gets its "
                "saltation matrix"
            )
    try:
        parts = [expr]
        if smooth:
            parts += [sp.diff(expr, v) for v in variables if expr.has(v)]
    except Exception as exc:  # noqa: BLE001 (sympy raises many kinds on what it cannot differentiate)
        raise ModelError(f"{where}: {expr} cannot be differentiated ({type(exc).__name__}: "
                         f"{' '.join(str(exc).split())[:200]})") from None
    for part in parts:
        try:
            _PRINTER.doprint(part)
        except Exception as exc:  # noqa: BLE001 (sympy's printers raise many kinds)
            raise ModelError(f"{where}: {expr} cannot be compiled ({type(exc).__name__}: "
                             f"{' '.join(str(exc).split())[:200]})") from None


def _condition(value: Expr, symbols: Mapping[str, sp.Symbol], where: str) -> Condition:
    rel = _sympify(value, symbols, where, relation=True) if not isinstance(value, sp.Basic) else value
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
    _check_compilable(expr, (), where, smooth=False)
    return Condition(expr=expr, strict=strict)


def _conditions(values, symbols: Mapping[str, sp.Symbol], where: str) -> tuple[Condition, ...]:
    """A sequence of conditions (a plain string would be iterated character by character)."""
    if isinstance(values, (str, sp.Basic)) or not isinstance(values, Sequence):
        raise ModelError(f"{where}: expected a list of conditions such as ['x - a > 0'], got {values!r}")
    return tuple(_condition(c, symbols, where) for c in values)


def _name(value, what: str) -> str:
    """A name of a state, parameter, mode or surface: a non-empty identifier that sympy and Python keep as written."""
    if not isinstance(value, str) or not value.isidentifier() or unicodedata.normalize("NFKC", value) != value:
        raise ModelError(f"{what} name {value!r} must be a non-empty identifier (letters, digits, underscores, "
                         "not starting with a digit, without compatibility characters such as ligatures)")
    return value


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
            If an override names an unknown parameter, is not finite, or makes a divisor of the
            model zero (see :meth:`check_parameters`).
        """
        if overrides is not None and not isinstance(overrides, Mapping):
            raise ModelError(f"parameter overrides must be a mapping of names to values, got {overrides!r}")
        # the vectors of the last few sets of overrides are kept (every orbit found asks again for the same)
        try:
            key = (tuple(self.defaults.items()), tuple(overrides.items()) if overrides else ())
            known = self._parameter_vectors.get(key)
        except TypeError:  # a value that is not hashable: no memory
            key, known = None, None
        if known is not None:
            return known.copy()
        p = self._checked_parameter_vector(overrides)
        if key is not None:
            if len(self._parameter_vectors) >= 64:
                self._parameter_vectors.clear()
            self._parameter_vectors[key] = p.copy()
        return p

    @cached_property
    def _parameter_vectors(self) -> dict:
        """Parameter vectors by ``(defaults, overrides)``, for :meth:`parameter_vector`."""
        return {}

    def _checked_parameter_vector(self, overrides: Mapping[str, float] | None) -> np.ndarray:
        """:meth:`parameter_vector` built and checked (what is remembered)."""
        values = dict(self.defaults)
        for key, val in (overrides or {}).items():
            self.parameter_index(key)
            try:
                val = float(val)
            except (TypeError, ValueError):
                raise ModelError(f"parameter {key!r} must be a number, got {val!r}") from None
            if not math.isfinite(val):
                raise ModelError(f"parameter {key!r} must be finite, got {val}")
            values[key] = val
        p = np.array([values[k] for k in self.parameter_names], dtype=float)
        self.check_parameters(p)
        return p

    def check_parameters(self, p: np.ndarray) -> None:
        """Parameter values a compiled model can use: the right number, finite, and no divisor of the
        model's expressions that depends on parameters alone equal to zero (``m = 0`` in ``F/m``).

        Raises
        ------
        ModelError
            Naming the parameter (and the expression whose divisor vanishes).
        """
        p = np.asarray(p, dtype=float)
        if p.shape != (self.n_params,):
            raise ModelError(f"{self.name!r} has {self.n_params} parameters {list(self.parameter_names)}, "
                             f"got an array of shape {p.shape}")
        bad = [name for name, v in zip(self.parameter_names, p) if not math.isfinite(v)]
        if bad:
            raise ModelError(f"parameter {bad[0]!r} must be finite, got {p[self.parameter_names.index(bad[0])]}")
        for divisor, function, where in self._parameter_divisors:
            try:
                value = float(function(*p.tolist()))
            except (ZeroDivisionError, ValueError, OverflowError):
                value = 0.0
            if value == 0.0:
                names = sorted(str(q) for q in divisor.free_symbols)
                values = ", ".join(f"{q} = {p[self.parameter_names.index(q)]:g}" for q in names)
                raise ModelError(f"{where} divides by {divisor}, which is zero at {values}")

    @cached_property
    def _parameter_divisors(self) -> list:
        """``(divisor, compiled divisor, where)`` for each divisor that depends on parameters only."""
        found, seen = [], set()
        expressions = list(self._expressions())
        params = set(self.p) if expressions else set()
        for expr, where in expressions:
            for power in expr.atoms(sp.Pow):
                base, exponent = power.as_base_exp()
                if exponent.is_negative and base.free_symbols and base.free_symbols <= params and base not in seen:
                    seen.add(base)
                    found.append((base, sp.lambdify(list(self.p), base, modules="math"), where))
        return found

    def _expressions(self):
        """Every expression of the model with where it stands (overridden by models that have them)."""
        return []

    @cached_property
    def _period_functions(self):
        args = list(self.p)
        period = sp.lambdify(args, self.period_expr, modules="math")
        derivatives = [sp.lambdify(args, sp.diff(self.period_expr, q), modules="math") for q in self.p]
        return period, derivatives



def _name_texts(texts: Mapping[str, str] | None, what: str, names: Sequence[str]) -> dict[str, str]:
    """A model's ``labels`` or ``units``: texts by state or parameter name (``t`` too), checked."""
    if texts is None:
        return {}
    if not isinstance(texts, Mapping):
        raise ModelError(f"{what} must be a mapping of state or parameter names to text, got {type(texts).__name__}")
    out = {}
    for key, text in texts.items():
        if key not in names:
            raise ModelError(f"{what}: {key!r} is not a state or parameter of the model (they are {list(names)})")
        if not isinstance(text, str):
            raise ModelError(f"{what}[{key!r}] must be a string, got {text!r}")
        out[key] = text
    return out


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
    labels : mapping of str to str, optional
        How plots write states and parameters, as mathtext without ``$`` (``{"v": r"\\dot x"}``);
        by default the name, with Greek letters by name (``omega`` as ``\\omega``) and the part after
        an underscore as a subscript.
    units : mapping of str to str, optional
        Their units, written after the label (``{"omega": "rad/s"}``).
    symmetry : Symmetry, optional
        A symmetry ``x -> S x``, ``t -> t + T/2`` of the model (:mod:`saltation.model.symmetry`),
        verified when the model is built.  Its symmetric orbits then get their multipliers split into
        symmetric and antisymmetric ones, and symmetry-breaking bifurcations are told from folds.

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
        labels: Mapping[str, str] | None = None,
        units: Mapping[str, str] | None = None,
        symmetry: Symmetry | None = None,
    ):
        self._read_names(name, states, parameters, labels, units)
        modes, surfaces, transitions = self._read_modes(modes, surfaces, transitions)
        self._read_surfaces(surfaces, period)
        self._read_transitions(transitions)
        if period is None:
            self.period_expr: sp.Expr | None = None
        else:
            self.period_expr = _sympify(period, self._symbols, "forcing period")
            if self.period_expr.free_symbols & (set(self.x) | {TIME}):
                raise ModelError("the forcing period may depend on parameters only")
            _check_compilable(self.period_expr, list(self.p), "forcing period", smooth=True)
        if self.period_expr is None and any(TIME in f.free_symbols for f in self.fields):
            raise ModelError("a vector field depends on time t but no forcing period is given (period=...)")
        self.check_parameters(np.array([self.defaults[k] for k in self.parameter_names]))
        if symmetry is not None and not isinstance(symmetry, Symmetry):
            raise ModelError(f"symmetry must be a Symmetry(...), got {symmetry!r}")
        #: the declared symmetry (None without one)
        self.symmetry: Symmetry | None = symmetry
        #: how the symmetry permutes modes and surfaces (None without one)
        self.symmetry_map: SymmetryMap | None = None if symmetry is None else check_symmetry(self, symmetry)

    # -- construction steps (in __init__'s order: an error names the first thing wrong) ------
    def _read_names(self, name: str, states: Sequence[str], parameters: Mapping[str, float],
                    labels: Mapping[str, str] | None, units: Mapping[str, str] | None) -> None:
        """The model's, states' and parameters' names, the defaults, labels, units and symbols."""
        if not isinstance(name, str) or not name.replace("_", "").isalnum():
            raise ModelError(f"model name {name!r} must be a string of letters and digits (underscores allowed)")
        self.name = name
        if isinstance(states, str) or not isinstance(states, Sequence):
            raise ModelError(f"states must be a list of names, got {states!r}")
        if not isinstance(parameters, Mapping):
            raise ModelError(f"parameters must be a mapping of names to default values, got {type(parameters).__name__}")
        self.state_names: tuple[str, ...] = tuple(_name(s, "state") for s in states)
        self.parameter_names: tuple[str, ...] = tuple(_name(q, "parameter") for q in parameters)
        self.defaults: dict[str, float] = {}
        for pname, value in parameters.items():
            if value is None:
                raise ModelError(f"parameter {pname!r} has no value")
            try:
                self.defaults[pname] = float(value)
            except (TypeError, ValueError):
                raise ModelError(f"parameter {pname!r} has non-numeric value {value!r}") from None
            if not math.isfinite(self.defaults[pname]):
                raise ModelError(f"parameter {pname!r} must be finite, got {value!r}")
        names = list(self.state_names) + list(self.parameter_names) + ["t"]
        dupes = {n for n in names if names.count(n) > 1}
        if dupes:
            raise ModelError(f"names used twice among states, parameters and time 't': {sorted(dupes)}")
        if not self.state_names:
            raise ModelError("a model needs at least one state")
        self.labels = _name_texts(labels, "labels", names)
        self.units = _name_texts(units, "units", names)
        self.x = sp.Matrix([sp.Symbol(s, real=True) for s in self.state_names])
        self.p = sp.Matrix([sp.Symbol(s, real=True) for s in self.parameter_names])
        self.t = TIME
        self._symbols = {s.name: s for s in list(self.x) + list(self.p)} | {"t": TIME}

    def _read_modes(self, modes: Sequence[Mode], surfaces: Mapping[str, Expr], transitions: Sequence[Transition]):
        """The modes, with the pieces of fields with sign, Abs, Min, Max... expanded into modes, surfaces and
        transitions (:mod:`saltation.model.nonsmooth`): returns the surfaces and transitions with theirs."""
        if isinstance(modes, (str, Mode)) or not isinstance(modes, Sequence) or not modes:
            raise ModelError("a model needs a list of at least one Mode")
        for m in modes:
            if not isinstance(m, Mode):
                raise ModelError(f"modes must be Mode(...) objects, got {m!r}")
            if not isinstance(m.name, str) or not m.name:
                raise ModelError(f"a mode's name must be a non-empty string, got {m.name!r}")
        #: where generated modes and surfaces came from (sign, Heaviside, Abs, Min, Max in a field)
        self.expansion = Expansion({}, {})
        #: the stuck modes of impacts that stick (``Transition(..., sticks=True)``), by name
        self.sticking: dict[str, Sticking] = {}
        if isinstance(surfaces, Mapping) and isinstance(transitions, Sequence) and not isinstance(transitions, str):
            modes, surfaces, transitions, self.sticking = expand_sticking(
                modes, dict(surfaces), transitions, lambda value, where: _sympify(value, self._symbols, where),
                list(self.x), TIME, (Mode, Transition, Crossing),
            )
            modes, surfaces, transitions, self.expansion = expand_nonsmooth(
                modes, surfaces, transitions, lambda value, where: _sympify(value, self._symbols, where), set(self.x),
                (Mode, Transition, Crossing),
            )
        self.modes: tuple[Mode, ...] = tuple(modes)
        self.mode_names: tuple[str, ...] = tuple(m.name for m in modes)
        if len(set(self.mode_names)) != len(self.mode_names):
            raise ModelError(f"mode names must be unique: {self.mode_names}")
        self.fields: tuple[sp.Matrix, ...] = tuple(self._parse_field(m) for m in modes)
        self.domains: tuple[tuple[Condition, ...], ...] = tuple(
            _conditions(m.domain, self._symbols, f"domain of mode {m.name!r}") for m in modes
        )
        return modes, surfaces, transitions

    def _read_surfaces(self, surfaces: Mapping[str, Expr], period: Expr | None) -> None:
        """The switching surfaces' names and indicators (a moving surface needs a forcing ``period``)."""
        if not isinstance(surfaces, Mapping):
            raise ModelError(f"surfaces must be a mapping of names to indicators, got {type(surfaces).__name__}")
        for sname in surfaces:
            if not isinstance(sname, str) or not sname:
                raise ModelError(f"a surface's name must be a non-empty string, got {sname!r}")
        self.surface_names: tuple[str, ...] = tuple(surfaces)
        self.indicators: tuple[sp.Expr, ...] = tuple(
            _sympify(expr, self._symbols, f"surface {sname!r}") for sname, expr in surfaces.items()
        )
        variables = [*self.x, *self.p, TIME]
        for sname, h in zip(self.surface_names, self.indicators):
            _check_compilable(h, variables, f"surface {sname!r}", smooth=True)
        for sname, h in zip(self.surface_names, self.indicators):
            if TIME in h.free_symbols and period is None:
                raise ModelError(
                    f"surface {sname!r}: indicator {h} depends on time t but no forcing period is given "
                    "(period=...); a surface that moves with time, or a clock, belongs to a forced model"
                )
            if not (h.free_symbols & (set(self.x) | {TIME})):
                raise ModelError(
                    f"surface {sname!r}: indicator {h} depends on neither the state {list(self.state_names)} nor "
                    "time t; a switching surface is crossed by moving in state space, or is a clock h(t) of a "
                    "forced model"
                )

    def _read_transitions(self, transitions: Sequence[Transition]) -> None:
        """The transitions, with their resets and guards."""
        if isinstance(transitions, (str, Transition)) or not isinstance(transitions, Sequence):
            raise ModelError(f"transitions must be a list of Transition(...) objects, got {transitions!r}")
        self.transitions: tuple[Transition, ...] = tuple(transitions)
        self.resets: list[sp.Matrix | None] = []
        self.guards: list[tuple[Condition, ...]] = []
        for k, tr in enumerate(self.transitions):
            reset, guard = self._read_transition(k, tr)
            self.resets.append(reset)
            self.guards.append(guard)

    def _read_transition(self, k: int, tr: Transition) -> tuple[sp.Matrix | None, tuple[Condition, ...]]:
        """Transition ``k`` checked against the modes and surfaces: its reset map (None without one) and guard."""
        if not isinstance(tr, Transition):
            raise ModelError(f"transition {k}: expected a Transition(...), got {tr!r}")
        where = f"transition {k} ({tr.source} -> {tr.target})"
        for role, mname in (("source", tr.source), ("target", tr.target)):
            if mname not in self.mode_names:
                raise ModelError(f"{where}: {role} mode {mname!r} does not exist; modes are {list(self.mode_names)}")
        if tr.surface not in self.surface_names:
            raise ModelError(f"{where}: surface {tr.surface!r} does not exist; surfaces are {list(self.surface_names)}")
        direction = tr.direction
        if isinstance(direction, bool) or not isinstance(direction, (int, np.integer)) or direction not in (1, -1, 0):
            raise ModelError(f"{where}: direction must be a Crossing (RISING +1, FALLING -1 or EITHER 0), "
                             f"got {direction!r}")
        if tr.reset is None:
            reset = None
        else:
            if isinstance(tr.reset, (str, sp.Basic)) or not isinstance(tr.reset, Sequence):
                raise ModelError(f"{where}: a reset map is a list of expressions, one per state, got {tr.reset!r}")
            if len(tr.reset) != self.n:
                raise ModelError(f"{where}: reset map has {len(tr.reset)} components, the model has {self.n} states")
            reset = self._per_state(tr.reset, lambda i: f"{where} reset component {i} ({self.state_names[i]}+)")
        return reset, _conditions(tr.guard, self._symbols, f"{where} guard")

    # -- construction helpers ---------------------------------------------------------------
    def _expressions(self):
        """Every expression of the model with where it stands (fields, indicators, resets, the period)."""
        for m, f in zip(self.mode_names, self.fields):
            for i, e in enumerate(f):
                yield e, f"mode {m!r}, field component {i} ({self.state_names[i]}')"
        for sname, h in zip(self.surface_names, self.indicators):
            yield h, f"surface {sname!r}"
        for k, g in enumerate(self.resets):
            if g is not None:
                for i, e in enumerate(g):
                    yield e, f"transition {k}, reset component {i}"
        if self.period_expr is not None:
            yield self.period_expr, "the forcing period"

    def _parse_field(self, mode: Mode) -> sp.Matrix:
        where = f"mode {mode.name!r}"
        if mode.name in self.expansion.modes:  # generated from a field with sign, Abs, ... (see saltation.model.nonsmooth)
            where = f"mode {self.expansion.modes[mode.name][0]!r} (its part {mode.name!r})"
        if isinstance(mode.field, (str, sp.Basic)) or not isinstance(mode.field, Sequence):
            raise ModelError(f"{where}: the vector field is a list of expressions, one per state, got {mode.field!r}")
        if len(mode.field) != len(self.state_names):
            raise ModelError(f"{where}: vector field has {len(mode.field)} components, the model has "
                             f"{len(self.state_names)} states")
        return self._per_state(mode.field, lambda i: f"{where}, field component {i} ({self.state_names[i]}')")

    def _per_state(self, values: Sequence[Expr], slot) -> sp.Matrix:
        """One smooth, compilable expression per state (a field or a reset map); ``slot(i)`` names each."""
        variables = [*self.x, *self.p, TIME]
        components = []
        for i, value in enumerate(values):
            expr = _sympify(value, self._symbols, slot(i))
            _check_compilable(expr, variables, slot(i), smooth=True)
            components.append(expr)
        return sp.Matrix(components)

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

    def domain_violations(self, mode: int | str, x0: Sequence[float], p: np.ndarray, t0: float = 0.0) -> list[str]:
        """The conditions of a mode's domain that do not hold at ``(t0, x0)``, as text.

        A mode without conditions (memory, such as a relay's or a thermostat's state, which only the
        transitions change) holds everywhere: the list is empty.

        Parameters
        ----------
        mode : int or str
            The mode.
        x0 : sequence of float
            The state.
        p : ndarray
            Parameter values.
        t0 : float
            Time.

        Returns
        -------
        list of str
            Each violated condition as ``"<expr> > 0 (it is <value>)"`` (``>=`` for a non-strict one).

        Raises
        ------
        ModelError
            For an unknown mode (naming the model's modes).
        """
        k = self.mode_index(mode)
        subs = dict(zip(self.x, map(float, x0))) | dict(zip(self.p, map(float, p))) | {TIME: float(t0)}
        failed = []
        for c in self.domains[k]:
            value = float(c.expr.subs(subs))
            if not c.holds(value):
                failed.append(f"{c.expr} {'>' if c.strict else '>='} 0 (it is {value:.6g})")
        return failed

    def mode_sides(self, mode: int | str) -> tuple[sp.Expr, ...]:
        """Expressions that are non-negative wherever ``mode`` is active (read by
        :func:`saltation.model.sides.on_its_side`: each mode's field on its own side of its surfaces).

        Parameters
        ----------
        mode : int or str
            The mode, by index or name.

        Returns
        -------
        tuple of sympy expressions
            The mode's domain conditions (``expr > 0`` or ``expr >= 0``), and for each transition out of the
            mode without a guard, its surface's indicator ``h`` (the mode is left where ``h`` falls through 0)
            or ``-h`` (left where ``h`` rises).  A transition that fires either way, or only under a guard,
            says nothing about the side.

        Raises
        ------
        ModelError
            If there is no such mode.
        """
        m = self.mode_index(mode)
        name = self.mode_names[m]
        sides: list[sp.Expr] = [c.expr for c in self.domains[m]]
        for tr, guard in zip(self.transitions, self.guards):
            if tr.source != name or guard or int(tr.direction) == 0:
                continue
            h = self.indicators[self.surface_index(tr.surface)]
            sides.append(h if int(tr.direction) < 0 else -h)
        return tuple(dict.fromkeys(sides))  # (in order, once)

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

    @cached_property
    def parallel_surfaces(self) -> tuple[tuple[int, int, sp.Expr], ...]:
        """Pairs of surfaces ``(i, j, gap)`` whose indicators differ by an amount the state does not change:
        ``h_i - h_j = gap(t, p)`` (the two edges of a band, such as a stick band ``|v - v_dr| < eta``).  A band
        narrower than its edges' resolution cannot be told from them (:meth:`Flow.run
        <saltation.engine.flow.Flow.run>` refuses it)."""
        out = []
        states = set(self.x)
        reads = [h.free_symbols & states for h in self.indicators]
        for i in range(len(self.indicators)):
            for j in range(i + 1, len(self.indicators)):
                if reads[i] != reads[j]:
                    continue  # (a quick test before the expansion: the pairs are many in a large model)
                gap = sp.expand(self.indicators[i] - self.indicators[j])
                if gap.free_symbols & states or gap == 0:
                    continue
                out.append((i, j, gap))
        return tuple(out)

    @cached_property
    def logic_states(self) -> tuple[int, ...]:
        """The states that no mode moves and no field reads (their field is 0 in every mode, and no mode's field
        depends on them): memory such as a latch's ``q``, changed only by resets and read only by domains and
        guards.  (A relay's output that enters the field, ``x' = -x + u``, or a velocity that no force changes,
        ``x' = vx, vx' = 0``, is no logic state: resetting it changes the motion.)"""
        read = set().union(*(f.free_symbols for f in self.fields))
        return tuple(i for i in range(self.n)
                     if self.x[i] not in read and all(_vanishes(f[i]) for f in self.fields))

    @cached_property
    def impacts(self) -> tuple[bool, ...]:
        """For each transition, whether its reset is an impact: it moves a state that is not a logic state
        (:attr:`logic_states`), or one that its surface's indicator reads (the state may land on the surface
        and be sent back).  A reset of other logic states only is a mode switch: whether the motion crosses is
        decided by the fields alone, as without a reset.  No reset on a clock (an indicator of time alone,
        ``h(t)``) is an impact: the state lies on the clock's surface at its instant whatever the reset makes of
        it, and time alone crosses it (once), as without a reset."""
        logic = set(self.logic_states)
        states = set(self.x)
        out = []
        for k, g in enumerate(self.resets):
            indicator = self.indicators[self.surface_index(self.transitions[k].surface)]
            if g is None or not indicator.free_symbols & states:
                out.append(False)
                continue
            moved = [i for i in range(self.n) if not _vanishes(g[i] - self.x[i])]
            out.append(any(i not in logic or self.x[i] in indicator.free_symbols for i in moved))
        return tuple(out)

    def reset_map(self, transition: int) -> sp.Matrix:
        """The reset map of a transition (the identity when it has none)."""
        g = self.resets[transition]
        return self.x if g is None else g

    def saltation_matrix(self, transition: int, *, on_surface: bool = True, simplify: bool = True,
                         one_sided: bool = False) -> sp.Matrix:
        """Closed-form saltation matrix of a transition, eq. (9) generalised to resets.

        ``S = g_x + (f+ - g_x f- - g_t) h_x / (h_x f- + h_t)``, with ``f-`` the
        field of the source mode at ``x``, ``f+`` that of the target mode at
        ``g(x)``.  With ``on_surface`` the indicator's zero set is used to
        simplify (the state lies on the surface when the event happens).
        ``simplify`` gives sympy's most readable form; without it the entries
        are only brought to cancelled fractions (the same functions, some ten
        times faster: what the numerical uses take).  ``one_sided`` reads each field on its mode's side
        of its surfaces (:func:`saltation.model.sides.on_its_side`: fractional powers of a vanishing
        base take their limit), for evaluation at and near the surface.
        """
        tr = self.transitions[transition]
        src, dst = self.mode_index(tr.source), self.mode_index(tr.target)
        d = self.surface_derivatives(tr.surface)
        g = self.reset_map(transition)
        g_x = g.jacobian(self.x)
        g_t = sp.diff(g, TIME)
        f_minus, f_plus = self.fields[src], self.fields[dst]
        if one_sided:
            moving = [*self.x, TIME]
            f_minus = on_its_side(f_minus, self.mode_sides(src), moving)
            f_plus = on_its_side(f_plus, self.mode_sides(dst), moving)
        f_plus = f_plus.xreplace(dict(zip(self.x, g)))
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
            *(repr([(sp.srepr(c.expr), c.strict) for c in d]) for d in self.domains),
            "period " + (sp.srepr(self.period_expr) if self.period_expr is not None else "None"),
        ]
        return "\n".join(parts)

    def __getstate__(self) -> dict:
        # compiled helper functions are rebuilt on demand (they do not pickle)
        state = dict(self.__dict__)
        state.pop("_period_functions", None)
        state.pop("_parameter_divisors", None)
        state.pop("_symmetry_functions", None)
        state.pop("_parameter_vectors", None)
        return state

    def axis_label(self, name: str) -> str:
        """How a plot's axis names a state or parameter: its label (declared, or the name as mathtext) and
        its unit, e.g. ``$\\omega$ (rad/s)``.

        Parameters
        ----------
        name : str
            A state's or parameter's name, or ``t``.

        Returns
        -------
        str

        Raises
        ------
        ModelError
            If the model has no state or parameter of that name.
        """
        if name not in (*self.state_names, *self.parameter_names, "t"):
            raise ModelError(f"{name!r} is not a state or parameter of {self.name!r}")
        from saltation.model.labels import tex_name

        text = f"${self.labels[name]}$" if name in self.labels else f"${tex_name(name)}$"
        return text + (f" ({self.units[name]})" if self.units.get(name) else "")

    def _repr_markdown_(self) -> str:
        """A summary for Jupyter (:mod:`saltation.summary`)."""
        from saltation.summary import system_summary

        return system_summary(self)

    def __repr__(self) -> str:
        kind = "autonomous" if self.is_autonomous else f"forced, period {self.period_expr}"
        return (
            f"PiecewiseSystem({self.name!r}, states={list(self.state_names)}, modes={list(self.mode_names)}, "
            f"surfaces={list(self.surface_names)}, {len(self.transitions)} transitions, {kind})"
        )


def _vanishes(expr: sp.Expr) -> bool:
    """Whether an expression is identically zero.

    A polynomial (in every symbol) is expanded, which is exact and fast.  Anything else is evaluated first at a
    point of positive rationals, to 50 digits: a value clearly away from zero proves it is not zero; only where
    the value is zero (or not a finite number) does ``sympy.simplify`` decide, which can take minutes on a large
    expression (a polynomial reset with trigonometric coefficients in a parameter).
    """
    expr = sp.sympify(expr)
    if expr == 0:
        return True
    if expr.is_polynomial():
        return sp.expand(expr) == 0
    symbols = sorted(expr.free_symbols, key=str)
    point = {s: sp.Rational(3 + 7 * k, 11 + 2 * k) for k, s in enumerate(symbols)}
    try:
        value = complex(expr.evalf(50, subs=point))
    except (TypeError, ValueError):
        value = complex("nan")
    if cmath.isfinite(value) and abs(value) > 1e-12:
        return False
    return sp.simplify(expr) == 0


def _simplify_on_surface(S: sp.Matrix, h: sp.Expr, x: sp.Matrix, reduce=sp.simplify) -> sp.Matrix:
    """Eliminate one state using ``h = 0`` where the indicator is linear in it, then ``reduce`` each entry."""
    for xi in x:
        if h.has(xi) and h.is_polynomial(xi) and sp.degree(h, xi) == 1:
            # h = a xi + b with a, b free of xi: xi = -b / a (sympy's solve would simplify its solution,
            # importing sympy.physics on the way: half a second at a diagram's first corner)
            a, b = sp.diff(h, xi), h.xreplace({xi: 0})
            if a != 0:
                return S.xreplace({xi: sp.cancel(-b / a)}).applyfunc(reduce)
    return S
