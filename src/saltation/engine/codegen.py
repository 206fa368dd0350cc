"""Code generation: the compiled engine, and a :class:`~saltation.model.system.PiecewiseSystem`'s functions.

Two kinds of generated module, each written once to the kernel cache
directory and imported; numba compiles them with ``cache=True``, so each
compiles once per machine:

* the **engine** (the integrator template ``_kernel_source.py``), one per
  state dimension up to 4 (``N_STATE`` a compile-time constant) and one for
  every larger dimension; it takes the model as a tuple of first-class
  functions, so it does not depend on the model and is compiled once, not
  once per model (about 40 s of compiling, the first time a dimension is used; the message says
  how long it should take on this machine, :mod:`saltation.engine.buildtime`);
* the **model functions**: the model's exact derivatives printed as Python
  source (with common subexpressions eliminated), each compiled eagerly with
  its signature from the contract (``_contract.py``); a new or changed model
  compiles only these (seconds; announced when it should take 10 s or more here, as for a model of
  many states).

The kernel cache
----------------
The folder is ``$SALTATION_CACHE_DIR`` if set, otherwise
``$XDG_CACHE_HOME/saltation`` (``~/.cache/saltation``); numba keeps the
compiled code in its ``__pycache__`` (or under ``$NUMBA_CACHE_DIR`` if set).

*Keys.*  A module is named after a hash of its own generated source text
(``<model name>_<hash>.py``, ``engine_n<N>_<hash>.py``), together with the
versions of numba and Python.  The source holds the contract and everything
compiled: fields and their derivatives, surfaces, transitions with their
guards and resets, the modes' domains (the initial-mode rule), the forcing
period and its derivatives, the order of states and parameters.  Two models
therefore share a module exactly when they compile to the same code, whatever
the model's own fingerprint leaves out, and a change to the generators (this
module, ``affine.py``, ``model.py``) that changes the code changes the name.
A model's source is generated once per system object in a process (about 0.2 s;
about 1.3 s for a 32-state chain).

*Checks.*  Before a module is imported, the file must be exactly the source it
is named after (a truncated or altered module is rewritten), and each of
numba's index and data files for it must consist of whole pickles (checked
without running them; damaged ones are removed, so numba compiles again).  A
module that still fails to import from what was cached is rebuilt from scratch
once.  Every file saltation writes goes through a temporary file renamed over
the target, so a crash leaves the old file or the whole new one.  What cannot
be rebuilt raises :class:`KernelCacheError` naming the folder to delete.

*Build times.*  Each build's duration is recorded in ``build_times.json`` in the folder; the next
builds' messages estimate their time from it (:mod:`saltation.engine.buildtime`).

*Read-only caches.*  If the folder (or numba's folder for it) cannot be
written, the process says so once on standard error and uses a private
per-user folder in the temporary directory (:func:`fallback_directory`)
instead; modules already compiled in the read-only folder are copied there,
not recompiled.  If that cannot be used either, :class:`KernelCacheError` says
why.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib.util
import json
import logging
import os
import pickle
import pickletools
import stat
import sys
import tempfile
import threading
import time
import weakref
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from saltation.engine._atomic import write_atomic
from saltation.engine._contract import MODEL_FUNCTIONS, MODEL_SIGNATURES
from saltation.engine.affine import affine_form
from saltation.engine.buildtime import BuildEstimate, estimate_build, timed
from saltation.errors import SaltationError
from saltation.model.contacts import sticking_twins
from saltation.model.sides import on_its_side
from saltation.model.system import TIME, PiecewiseSystem

_TEMPLATE = Path(__file__).with_name("_kernel_source.py")
_CONTRACT = Path(__file__).with_name("_contract.py")
_RECORDS = Path(__file__).with_name("_records.py")
_LOADED: dict[str, ModuleType] = {}
_log = logging.getLogger(__name__)
_IMPORT_LOCK = threading.RLock()  # threads that build flows at once import each module once


def _dop853_tableau() -> dict[str, np.ndarray]:
    """The Dormand-Prince 8(5,3) tableau of scipy's DOP853 (imported only when a kernel is generated)."""
    from scipy.integrate._ivp import dop853_coefficients as dop853

    return {name: np.asarray(getattr(dop853, name), dtype=float) for name in ("A", "B", "C", "E3", "E5", "D")}


class _Printer(PythonCodePrinter):
    def __init__(self, names: dict[sp.Symbol, str]):
        super().__init__({"standard": "python3", "fully_qualified_modules": True})
        self._names = names

    def _print_Symbol(self, expr):
        return self._names.get(expr, super()._print_Symbol(expr))

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_Integer(self, expr):
        return repr(float(expr))

    def _print_Pow(self, expr, rational=False):
        # a small integer power as products: the float exponent the other integers get would call libm's
        # pow, some 20 times a multiplication (a Duffing field's x**3 was a sixth of its orbit's time)
        base, exponent = expr.as_base_exp()
        if exponent.is_Integer and 2 <= abs(int(exponent)) <= 8:
            factor = f"({self._print(base)})"
            product = "*".join([factor] * abs(int(exponent)))
            return f"({product})" if exponent > 0 else f"(1.0/({product}))"
        return super()._print_Pow(expr, rational=rational)


def _rate_symbol(i: int) -> sp.Symbol:
    """Component ``i`` of the velocity ``f`` an indicator's rate is taken along (printed ``f[i]``)."""
    return sp.Symbol(f"_rate_f{i}")


@dataclass(frozen=True)
class _Assignment:
    target: str
    expr: sp.Expr


class _Emitter:
    """Prints blocks of assignments with common subexpressions eliminated."""

    def __init__(self, system: PiecewiseSystem):
        names = {s: f"x[{i}]" for i, s in enumerate(system.x)}
        names |= {s: f"p[{i}]" for i, s in enumerate(system.p)}
        names[TIME] = "t"
        names |= {_rate_symbol(i): f"f[{i}]" for i in range(system.n)}
        self.printer = _Printer(names)

    def block(self, assignments: list[_Assignment], indent: str, result: sp.Expr | None = None) -> list[str]:
        exprs = [a.expr for a in assignments] + ([result] if result is not None else [])
        if not exprs:
            return []
        repl, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("_c"), optimizations=None)
        lines = [f"{indent}{self.printer.doprint(sym)} = {self.printer.doprint(val)}" for sym, val in repl]
        for a, e in zip(assignments, reduced):
            lines.append(f"{indent}{a.target} = {self.printer.doprint(e)}")
        if result is not None:
            lines.append(f"{indent}return {self.printer.doprint(reduced[-1])}")
        return lines


def _decorator(name: str) -> str:
    """A model function is compiled with its signature from the contract (eagerly), so the engine can
    take it as a first-class function.  A division by zero in a model's expression (``delta / r`` or the
    gradient ``x / r`` of a circle at its centre) gives an infinity or NaN, as in numpy, that the engine
    reports by mode and surface (or that does not matter where it arises), not a ``ZeroDivisionError``
    from inside the compiled engine that names nothing."""
    return f"@njit(MODEL_SIGNATURES[{name!r}], cache=True, error_model='numpy')"


#: A generated function longer than this (lines) is compiled without LLVM's optimization passes
#: (numba's ``_dbg_optnone``, a flag of numba >= 0.58): their time grows faster than the code's length.
#: On the 128-state chain (functions of 200 to 800 straight lines) the first orbit in a fresh process
#: came in 73 s with them and 34 s without, and the warm orbit took the same 130 ms: its steps are the
#: engine's exact affine steps, which stay optimized.  Small models (every function shorter) are not
#: affected.
UNOPTIMIZED_FUNCTION_LINES = 200


def _numba_can_skip_optimization() -> bool:
    """Whether this numba takes the ``_dbg_optnone`` option (a numba without it compiles every function
    optimized, as before)."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:  # pragma: no cover - numba's layout changed
        return False
    return hasattr(CPUTargetOptions, "_dbg_optnone")


def _skip_optimization_of_long_functions(src: list[str]) -> list[str]:
    """The generated lines, with the decorators of functions longer than :data:`UNOPTIMIZED_FUNCTION_LINES`
    asking numba to leave them unoptimized (not ``initial_mode``, which calls another model function:
    unoptimized, that call is a dynamic global that numba cannot cache)."""
    if not _numba_can_skip_optimization():
        return list(src)
    starts = [i for i, line in enumerate(src) if line.startswith("@njit(MODEL_SIGNATURES[")] + [len(src)]
    out = list(src)
    for a, b in zip(starts[:-1], starts[1:]):
        if (b - a > UNOPTIMIZED_FUNCTION_LINES and out[a].endswith(")")
                and "['initial_mode']" not in out[a]):
            out[a] = out[a][: -len(")")] + ", _dbg_optnone=True)"
    return out


def _dispatch(name: str, args: str, index: str, cases: list[tuple[int, list[str]]], default: str) -> list[str]:
    lines = [_decorator(name), f"def {name}({args}):"]
    for k, body in cases:
        if not body:
            continue
        lines.append(f"    if {index} == {k}:")
        lines.extend(body)
        if not body[-1].lstrip().startswith("return"):
            lines.append("        return " + ("" if default == "None" else default))
    lines.append(f"    return {default}" if default != "None" else "    return")
    return lines


def _mode_dispatch(
    name: str, args: str, em: _Emitter, cases: list[tuple[int, list[_Assignment]]], zero: list[str]
) -> list[str]:
    """A function of ``mode`` that writes arrays: ``zero`` (lines that clear them) once, then the
    assignments every mode of ``cases`` shares (the same target and expression) once, then each
    mode's own.  Modes usually differ in a few entries (a contact force in one equation), so the
    generated code grows with the model's distinct expressions, not with their number times the
    number of modes."""
    lines = [_decorator(name), f"def {name}({args}):"]
    if not cases:
        return lines + ["    return"]
    per_mode = [{a.target: a.expr for a in assigns} for _, assigns in cases]
    shared = [a for a in cases[0][1] if all(d.get(a.target) == a.expr for d in per_mode[1:])] if len(cases) > 1 else []
    shared_targets = {a.target for a in shared}
    lines += [f"    {z}" for z in zero] + em.block(shared, "    ")
    for k, assigns in cases:
        own = [a for a in assigns if a.target not in shared_targets]
        if own:
            lines.append(f"    if mode == {k}:")
            lines += em.block(own, "        ")
            lines.append("        return")
    lines.append("    return")
    return lines


def _matrix_assignments(target: str, M: sp.Matrix, lead: str = "") -> list[_Assignment]:
    """``target[lead i, j] = M[i, j]`` for the nonzero entries (``lead`` indexes a stack of matrices)."""
    out = []
    for i in range(M.rows):
        for j in range(M.cols):
            if M[i, j] != 0:
                out.append(_Assignment(f"{target}[{lead}{i}, {j}]", M[i, j]))
    return out


def generate_source(system: PiecewiseSystem) -> str:
    """The Python source of the compiled model functions (without the integrator)."""
    em = _Emitter(system)
    src: list[str] = [
        f"# Generated by saltation.engine.codegen for model {system.name!r}. Do not edit.",
        "import math",
        "import numpy as np",
        "from numba import njit",
        "",
    ]
    src += _field_source(system, em)
    src += _indicator_source(system, em)
    src += _lie_source(system, em)
    src += _reset_source(system, em)
    src += _affine_source(system, em)
    src += _domain_source(system, em)
    src += _period_source(system, em)
    src.append("MODEL = (" + ", ".join(MODEL_FUNCTIONS) + ", affine_modes)  # the engine's first argument")
    return "\n".join(_skip_optimization_of_long_functions(src)) + "\n"


def _field_source(system: PiecewiseSystem, em: _Emitter) -> list[str]:
    """``vector_field``, ``vector_field_jac``, ``vector_field_dp``: each mode's ``f``, ``f_x``, ``f_p``."""
    x, p = system.x, system.p
    src: list[str] = []
    modes = range(len(system.modes))
    # f, f_x, f_p
    # each mode read on its own side of its surfaces (saltation.model.sides), after differentiation
    sides = [system.mode_sides(m) for m in modes]
    moving = [*x, TIME]
    src += _mode_dispatch(
        "vector_field", "mode, t, x, p, out", em,
        [(m, [_Assignment(f"out[{i}]", on_its_side(e, sides[m], moving)) for i, e in enumerate(system.fields[m])])
         for m in modes], [],
    )
    jac_cases = []
    dp_cases = []
    for m in modes:
        f = system.fields[m]
        jac_cases.append((m, _matrix_assignments("out", on_its_side(f.jacobian(x), sides[m], moving))))
        fp = on_its_side(f.jacobian(p), sides[m], moving) if system.n_params else sp.zeros(system.n, 0)
        dp_cases.append((m, _matrix_assignments("out", fp)))
    src += _mode_dispatch("vector_field_jac", "mode, t, x, p, out", em, jac_cases, ["out[:, :] = 0.0"])
    src += _mode_dispatch("vector_field_dp", "mode, t, x, p, out", em, dp_cases, ["out[:, :] = 0.0"])
    return src


def _indicator_source(system: PiecewiseSystem, em: _Emitter) -> list[str]:
    """``indicator``, ``indicator_grad``, ``indicator_rate``: each surface's ``h``, its gradients, its rate along a velocity."""
    ind = "        "
    src: list[str] = []
    surfaces = range(len(system.surface_names))
    src += _dispatch(
        "indicator", "surface, t, x, p", "surface",
        [(s, em.block([], ind, result=system.indicators[s])) for s in surfaces],
        "0.0",
    )
    grad_cases = []
    for s in surfaces:
        d = system.surface_derivatives(s)
        body = [f"{ind}hx[:] = 0.0", f"{ind}hp[:] = 0.0"]
        assigns = [_Assignment(f"hx[{i}]", d.h_x[0, i]) for i in range(system.n) if d.h_x[0, i] != 0]
        assigns += [_Assignment(f"hp[{j}]", d.h_p[0, j]) for j in range(system.n_params) if d.h_p[0, j] != 0]
        body += em.block(assigns, ind, result=d.h_t)
        grad_cases.append((s, body))
    src += _dispatch("indicator_grad", "surface, t, x, p, hx, hp", "surface", grad_cases, "0.0")
    # h_t + h_x f: the rate of an indicator along a velocity f (event detection, every step)
    rate_cases = []
    for s in surfaces:
        d = system.surface_derivatives(s)
        rate = d.h_t + sum((d.h_x[0, i] * _rate_symbol(i) for i in range(system.n)), sp.Integer(0))
        rate_cases.append((s, em.block([], ind, result=rate)))
    # (hx, hp: work arrays for an indicator_rate built on indicator_grad, as CompiledSystem's; unused here)
    src += _dispatch("indicator_rate", "surface, t, x, f, p, hx, hp", "surface", rate_cases, "0.0")
    return src


def _lie_source(system: PiecewiseSystem, em: _Emitter) -> list[str]:
    """``lie_derivative``, ``lie_derivative_dt``: ``h_x f + h_t`` with its gradients, for the (mode, surface) pairs of transitions."""
    x, p = system.x, system.p
    ind = "        "
    src: list[str] = []
    # Lie derivatives h_x f + h_t (with gradients) for the pairs used by transitions (sliding)
    pairs = sorted(
        {(system.mode_index(tr.source), system.surface_index(tr.surface)) for tr in system.transitions}
        | {(system.mode_index(tr.target), system.surface_index(tr.surface)) for tr in system.transitions}
    )
    lie_lines = [_decorator("lie_derivative"), "def lie_derivative(mode, surface, t, x, p, gx, gp):", "    gx[:] = 0.0", "    gp[:] = 0.0"]
    for m, s in pairs:
        sigma = system.lie_derivative(m, s)
        gx = on_its_side(sp.Matrix([sigma]).jacobian(x), system.mode_sides(m), [*x, TIME])
        gp = on_its_side(sp.Matrix([sigma]).jacobian(p), system.mode_sides(m), [*x, TIME]) if system.n_params else sp.zeros(1, 0)
        sigma = on_its_side(sigma, system.mode_sides(m), [*x, TIME])
        assigns = [_Assignment(f"gx[{i}]", gx[0, i]) for i in range(system.n) if gx[0, i] != 0]
        assigns += [_Assignment(f"gp[{j}]", gp[0, j]) for j in range(system.n_params) if gp[0, j] != 0]
        lie_lines.append(f"    if mode == {m} and surface == {s}:")
        lie_lines += em.block(assigns, ind, result=sigma)
    lie_lines.append("    return 0.0")
    src += lie_lines
    lie_t = [_decorator("lie_derivative_dt"), "def lie_derivative_dt(mode, surface, t, x, p):"]
    for m, s in pairs:
        dsigma = on_its_side(sp.diff(system.lie_derivative(m, s), TIME), system.mode_sides(m), [*x, TIME])
        if dsigma != 0:
            lie_t.append(f"    if mode == {m} and surface == {s}:")
            lie_t += em.block([], ind, result=dsigma)
    lie_t.append("    return 0.0")
    src += lie_t
    return src


def _reset_source(system: PiecewiseSystem, em: _Emitter) -> list[str]:
    """``reset_map``, ``reset_jac``: each transition's reset ``g`` and ``g_x``, ``g_t``, ``g_p``."""
    x, p = system.x, system.p
    ind = "        "
    src: list[str] = []
    reset_cases = []
    rjac_cases = []
    for k, g in enumerate(system.resets):
        if g is None:
            continue
        reset_cases.append((k, em.block([_Assignment(f"out[{i}]", e) for i, e in enumerate(g)], ind)))
        gx = g.jacobian(x)
        gt = sp.diff(g, TIME)
        gp = g.jacobian(p) if system.n_params else sp.zeros(system.n, 0)
        assigns = _matrix_assignments("gx", gx) + [_Assignment(f"gt[{i}]", gt[i]) for i in range(system.n) if gt[i] != 0]
        assigns += _matrix_assignments("gp", gp)
        rjac_cases.append((k, [f"{ind}gx[:, :] = 0.0", f"{ind}gt[:] = 0.0", f"{ind}gp[:, :] = 0.0"] + em.block(assigns, ind)))
    src += _dispatch("reset_map", "k, t, x, p, out", "k", reset_cases, "None")
    src += _dispatch("reset_jac", "k, t, x, p, gx, gt, gp", "k", rjac_cases, "None")
    return src


def _domain_source(system: PiecewiseSystem, em: _Emitter) -> list[str]:
    """``guard``, ``in_domain``, ``domain_margin`` and ``initial_mode`` (the first mode whose domain holds)."""
    ind = "        "
    src: list[str] = []
    # guards of transitions, domains of modes (the initial-mode rule)
    src += _dispatch("guard", "k, t, x, p", "k", _condition_cases(em, system.guards, ind), "True")
    src += _dispatch("in_domain", "mode, t, x, p", "mode", _condition_cases(em, system.domains, ind), "True")
    src += _dispatch("domain_margin", "mode, t, x, p", "mode", _margin_cases(em, system.domains, ind), "math.inf")
    src += [
        _decorator("initial_mode"),
        "def initial_mode(t, x, p):",
        f"    for m in range({len(system.modes)}):",
        "        if in_domain(m, t, x, p):",
        "            return m",
        "    return -1",
    ]
    return src


def _period_source(system: PiecewiseSystem, em: _Emitter) -> list[str]:
    """``forcing_period(p)`` and its derivative ``forcing_period_dp(p, k)`` (0 for autonomous models)."""
    period = system.period_expr if system.period_expr is not None else sp.Integer(0)
    src = [_decorator("forcing_period"), "def forcing_period(p):"] + em.block([], "    ", result=period)
    src += [_decorator("forcing_period_dp"), "def forcing_period_dp(p, k):"]
    for k, pk in enumerate(system.p):
        d = sp.diff(period, pk)
        if d != 0:
            src.append(f"    if k == {k}:")
            src += em.block([], "        ", result=d)
    src.append("    return 0.0")
    return src


def _affine_source(system: PiecewiseSystem, em: _Emitter) -> list[str]:
    """``affine_modes`` and the parts ``A, B, (omega, phase)`` of affine modes with their parameter derivatives."""
    forms = [affine_form(f, system.x, TIME) for f in system.fields]
    src = [f"affine_modes = np.array({[f is not None for f in forms]!r}, dtype=np.bool_)"]
    cases, dp_cases = [], []
    for m, form in enumerate(forms):
        if form is None:
            continue
        assigns = _matrix_assignments("A", form.A) + _matrix_assignments("B", form.B)
        assigns += [_Assignment(f"w[{i}]", e) for i, e in enumerate((form.omega, form.phase)) if e != 0]
        cases.append((m, assigns))
        dp_assigns = []
        for k, pk in enumerate(system.p):
            dp_assigns += _matrix_assignments("Ap", form.A.diff(pk), f"{k}, ") + _matrix_assignments("Bp", form.B.diff(pk), f"{k}, ")
            dp_assigns += [
                _Assignment(f"wp[{k}, {i}]", sp.diff(e, pk)) for i, e in enumerate((form.omega, form.phase)) if sp.diff(e, pk) != 0
            ]
        dp_cases.append((m, dp_assigns))
    src += _mode_dispatch("affine_parts", "mode, p, A, B, w", em, cases, ["A[:, :] = 0.0", "B[:, :] = 0.0", "w[:] = 0.0"])
    src += _mode_dispatch(
        "affine_parts_dp", "mode, p, Ap, Bp, wp", em, dp_cases, ["Ap[:, :, :] = 0.0", "Bp[:, :, :] = 0.0", "wp[:, :] = 0.0"]
    )
    return src


def _condition_cases(em: _Emitter, condition_lists, ind: str) -> list[tuple[int, list[str]]]:
    """Dispatch cases returning whether every condition ``expr > 0`` (or ``>= 0``) holds."""
    cases = []
    for k, conds in enumerate(condition_lists):
        if not conds:
            continue
        body = []
        for c in conds:
            op = ">" if c.strict else ">="
            body.append(f"{ind}if not ({em.printer.doprint(c.expr)} {op} 0.0):")
            body.append(f"{ind}    return False")
        body.append(f"{ind}return True")
        cases.append((k, body))
    return cases


def _margin_cases(em: _Emitter, condition_lists, ind: str) -> list[tuple[int, list[str]]]:
    """Dispatch cases returning the smallest ``expr`` of a mode's conditions ``expr > 0`` (negative:
    how far the state lies outside the domain)."""
    cases = []
    for k, conds in enumerate(condition_lists):
        if conds:
            body = [f"{ind}m = math.inf"]
            for c in conds:
                body += [f"{ind}v = {em.printer.doprint(c.expr)}", f"{ind}if v < m:", f"{ind}    m = v"]
            cases.append((k, body + [f"{ind}return m"]))
    return cases


def transition_table(system: PiecewiseSystem) -> np.ndarray:
    """Integer table of transitions: source, surface, direction, target, has_reset, is_impact, sticks.

    ``is_impact``: the reset moves a state that the modes move (:attr:`PiecewiseSystem.impacts`); a reset of
    logic states only is a mode switch for the geometry of the crossing.  Models without expressions (compiled
    callables) count every reset as an impact.  ``sticks``: for an impact, the index of its sticking twin (the
    transition from the same mode on the same surface into the stuck mode that ``sticks=True`` added,
    :mod:`saltation.model.contacts`), whose impacts may accumulate into it (complete chatter); -1 for none."""
    impacts = getattr(system, "impacts", None)
    twins = sticking_twins(system)
    rows = [
        (
            system.mode_index(tr.source),
            system.surface_index(tr.surface),
            int(tr.direction),
            system.mode_index(tr.target),
            int(system.resets[k] is not None),
            int(system.resets[k] is not None if impacts is None else impacts[k]),
            twins.get(k, -1),
        )
        for k, tr in enumerate(system.transitions)
    ]
    return np.array(rows, dtype=np.int64).reshape(len(rows), 7)


SPECIALIZED_DIMENSIONS = range(1, 5)
"""State dimensions with an engine of their own, where ``N_STATE`` is a compile-time constant (loops
over the state of known length: about 3x fewer cycles per step for small systems).  Every other
dimension shares the engine compiled with ``N_STATE = 0``."""


def engine_dimension(n: int) -> int:
    """The ``N_STATE`` of the engine that integrates models of ``n`` states (0: the shared engine)."""
    return n if n in SPECIALIZED_DIMENSIONS else 0


def engine_source(n_state: int) -> str:
    """The engine's module: the contract, ``N_STATE``, the DOP853 tableau, then the integrator template."""
    head = [
        f"# Generated by saltation.engine.codegen: the engine for N_STATE = {n_state}. Do not edit.",
        _CONTRACT.read_text(),
        f"N_STATE = {n_state}  # 0: any state dimension, taken from the arrays",
        f"# the loop's records: saltation/engine/_records.py, {hashlib.sha256(_RECORDS.read_bytes()).hexdigest()[:16]}",
        "import numpy as np",
    ]
    head += [f"RK_{name} = np.array({arr.tolist()!r})" for name, arr in _dop853_tableau().items()]
    return "\n".join(head) + "\n\n" + _model_from_addresses_source() + "\n\n" + _TEMPLATE.read_text()


def _model_from_addresses_source() -> str:
    """``model_from_addresses(addresses, affine_modes)``: the engine's model tuple, in the contract's
    order, built from the addresses of the model's functions (see :func:`model_addresses`)."""
    lines = ["from numba import njit", ""]
    lines += [f"_FUNCTION_TYPE_{k} = MODEL_TYPE.types[{k}]" for k in range(len(MODEL_FUNCTIONS))]
    lines += [
        "",
        "",
        "@njit(cache=True)",
        "def model_from_addresses(a, affine_modes):",
        '    """The model tuple (``MODEL_TYPE``) from the addresses of its functions, two per row."""',
        "    return (",
    ]
    lines += [f"        _function_at(_FUNCTION_TYPE_{k}, a[{k}, 0], a[{k}, 1]),  # {name}" for k, name in enumerate(MODEL_FUNCTIONS)]
    lines += ["        affine_modes,", "    )", ""]
    return "\n".join(lines)


def model_addresses(model: tuple, engine: ModuleType | None = None) -> np.ndarray:
    """The addresses the engine takes for a model tuple's functions: per function (in the contract's
    order) its C wrapper and its numba entry point, from numba's own helpers for first-class functions;
    with an ``engine``, rows for its integrator (``INTEGRATOR_ROW``, which its Newton calls), and for the
    integrator's loop and the two helpers it calls through their addresses (``STEPS_ROW``,
    ``SURFACE_STEP_ROW``, ``SLIDING_EVENTS_ROW``).
    They stay valid while the functions live (:class:`~saltation.engine.flow.Flow` keeps them)."""
    from numba.experimental.function_type import _get_jit_address, _get_wrapper_address

    pairs = list(zip(model[: len(MODEL_FUNCTIONS)], MODEL_SIGNATURES.values()))
    if engine is not None:  # rows INTEGRATOR_ROW, STEPS_ROW, SURFACE_STEP_ROW, SLIDING_EVENTS_ROW
        for name, kind in (("integrate_kernel", "INTEGRATOR_TYPE"), ("_integrate_steps", "STEPS_TYPE"),
                           ("_surface_step", "SURFACE_STEP_TYPE"), ("_sliding_events", "SLIDING_EVENTS_TYPE")):
            function, signature = getattr(engine, name), getattr(engine, kind).signature
            if function.nopython_signatures != [signature]:
                raise RuntimeError(f"the engine's {name} is compiled as {function.nopython_signatures}, "
                                   f"not as it is called ({signature})")
            pairs.append((function, signature))
    addresses = np.array([(_get_wrapper_address(f, sig), _get_jit_address(f, sig)) for f, sig in pairs], dtype=np.int64)
    if (addresses <= 0).any():
        raise RuntimeError("a model function has no compiled entry point for its signature in the contract")
    return addresses


def model_source(system: PiecewiseSystem) -> str:
    """The module of a model's compiled functions: the contract (their signatures), then the functions."""
    return _CONTRACT.read_text() + "\n\n" + generate_source(system)


# -- the kernel cache ---------------------------------------------------------------------------------


class KernelCacheError(SaltationError, RuntimeError):
    """The kernel cache cannot be used: it cannot be written, or an entry cannot be rebuilt.

    The message names the folder concerned and what to do (make it writable, free space, delete it, or
    point ``SALTATION_CACHE_DIR`` elsewhere).
    """


def cache_directory() -> Path:
    """The configured kernel cache folder: ``$SALTATION_CACHE_DIR`` if set, otherwise
    ``$XDG_CACHE_HOME/saltation`` (``~/.cache/saltation``), as an absolute path.

    It is used if it can be written; otherwise :func:`active_cache_directory` falls back to
    :func:`fallback_directory`.
    """
    env = os.environ.get("SALTATION_CACHE_DIR")
    if env:
        return Path(os.path.abspath(os.path.expanduser(env)))
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(os.path.abspath(base)) / "saltation"


def fallback_directory() -> Path:
    """The per-user folder used when :func:`cache_directory` cannot be written:
    ``saltation-<user id>`` in the temporary folder (``/tmp``), private to the user."""
    uid = os.getuid() if hasattr(os, "getuid") else os.environ.get("USERNAME", "user")
    return Path(tempfile.gettempdir()) / f"saltation-{uid}"


_ACTIVE: dict[str, Path] = {}  # configured folder -> the folder used (itself, or the fallback)
_NOTICES: set[str] = set()  # messages already printed by this process


def _notice(message: str) -> None:
    """Log ``message`` as a warning of ``saltation.engine.codegen``, once per process (the command line shows
    the library's warnings on standard error)."""
    if message not in _NOTICES:
        _NOTICES.add(message)
        _log.warning("%s", message)


def _numba_cache_dir(directory: Path) -> Path:
    """Where numba keeps the compiled code of the modules in ``directory``: ``__pycache__`` beside them,
    or under ``$NUMBA_CACHE_DIR`` if that is set (numba's own choice of location)."""
    from numba.core import config

    if config.CACHE_DIR:
        from numba.core.caching import _CacheLocator

        return Path(config.CACHE_DIR) / _CacheLocator.get_suitable_cache_subpath(str(directory / "module.py"))
    return directory / "__pycache__"


def _write_problem(directory: Path) -> str | None:
    """Why modules cannot be written to ``directory`` and compiled there (``None``: they can).

    Creates the folder and numba's folder for it if needed, and writes a temporary file in each (the
    test numba makes before it caches anything)."""
    for folder in (directory, _numba_cache_dir(directory)):
        try:
            folder.mkdir(parents=True, exist_ok=True)
            tempfile.TemporaryFile(dir=folder).close()
        except OSError as exc:
            return f"{folder}: {type(exc).__name__}: {exc.strerror or exc}"
    return None


def _private_problem(directory: Path) -> str | None:
    """Why the fallback folder may not be used (``None``: it may): it must be a real folder of this user
    that no one else can write, since the modules in it are imported."""
    try:
        directory.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = os.lstat(directory)
    except OSError as exc:
        return f"{type(exc).__name__}: {exc.strerror or exc}"
    if not stat.S_ISDIR(st.st_mode):
        return "it is not a folder (a symbolic link or a file)"
    if hasattr(os, "getuid") and (st.st_uid != os.getuid() or st.st_mode & 0o022):
        return "it belongs to another user or others can write to it"
    return _write_problem(directory)


def active_cache_directory() -> Path:
    """The kernel cache folder this process uses.

    :func:`cache_directory` if modules can be written to it (and numba's cache beside them);
    otherwise :func:`fallback_directory`, saying so once on standard error (modules already compiled
    in the configured folder are copied from it, not recompiled).

    Raises
    ------
    KernelCacheError
        If neither folder can be used.
    """
    primary = cache_directory()
    with _IMPORT_LOCK:
        if str(primary) in _ACTIVE:
            return _ACTIVE[str(primary)]
        problem = _write_problem(primary)
        if problem is None:
            active = primary
        else:
            active = fallback_directory()
            other = _private_problem(active)
            if other is not None:
                raise KernelCacheError(
                    f"the kernel cache {primary} cannot be written ({problem}), nor the fallback {active} ({other}); "
                    "make one of them writable, or set SALTATION_CACHE_DIR to a writable folder"
                )
            _notice(
                f"the kernel cache {primary} cannot be written ({problem}); using {active} instead (modules "
                f"compiled in {primary} are copied from it). Make {primary} writable or set SALTATION_CACHE_DIR "
                "to a writable folder to keep compiled modules there."
            )
        _ACTIVE[str(primary)] = active
        return active


def _versions() -> str:
    """What a compiled module depends on besides its source: numba's and Python's versions."""
    import numba

    return f"numba {numba.__version__}; {sys.implementation.cache_tag} {sys.version_info[:3]}; {sys.platform}"


def _digest(*texts: str) -> str:
    return hashlib.sha256("\0".join(texts).encode()).hexdigest()[:20]


_ENGINES: dict[int, tuple[str, str]] = {}  # N_STATE -> (stem, source) in this process
_MODELS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # system -> (stem, source)


#: The files whose text shapes a generated module besides the model itself: a change to any of them is a
#: change of the generators, and the memo of sources (:func:`_remembered`) forgets what they made.
#: the files whose text decides the generated code: the code generator's and every module of the model layer
#: (how a model reads its expressions: the expansion of ``sign``..., one-sided fields)
_GENERATORS = (Path(__file__), _TEMPLATE, _CONTRACT, _RECORDS, Path(__file__).with_name("affine.py"),
               *sorted((Path(__file__).parents[1] / "model").glob("*.py")))
_GENERATOR_DIGEST: list[str] = []


def _generator_digest() -> str:
    """A hash of the generators' text and of the versions of what they call (sympy; scipy's DOP853 tableau)."""
    if not _GENERATOR_DIGEST:
        from importlib.metadata import version

        texts = [p.read_text() for p in _GENERATORS]
        _GENERATOR_DIGEST.append(_digest(*texts, f"sympy {version('sympy')}; scipy {version('scipy')}", _versions()))
    return _GENERATOR_DIGEST[0]


def _definition(system) -> str | None:
    """A hash of everything a model was built from: every attribute it holds but the ones derived from the
    others on demand (its ``cached_property`` values, the fingerprint among them), pickled.  Anything that can
    change the generated code is in it (so a memo found by it is that code); what cannot (labels, units,
    defaults) only makes more misses.  None where the model does not pickle."""
    try:
        state = system.__getstate__()
        derived = {name for cls in type(system).__mro__ for name, value in vars(cls).items()
                   if isinstance(value, functools.cached_property)}
        return hashlib.sha256(pickle.dumps({k: state[k] for k in sorted(state) if k not in derived},
                                           protocol=4)).hexdigest()
    except Exception:  # noqa: BLE001 (a model that does not pickle is generated each time)
        return None


def _remembered(kind: str, identity: str) -> tuple[str, str] | None:
    """The module generated before for ``identity`` (a hash of a model's definition, :func:`_definition`; an
    engine's dimension) by these generators: ``(stem, source)`` read back from the cache folder, or None.

    Generating a module's source takes sympy's differentiation and printing (0.2 s for a small model, 1.3 s
    for a 32-state one; the engine's needs scipy's tableau): a warm start reads it instead.  The memo names
    the module only; the module must still hash to its name (:func:`_digest` of its text), so a damaged or
    foreign file is never taken for it.
    """
    try:
        key = _digest(kind, identity, _generator_digest())
        for directory in dict.fromkeys((active_cache_directory(), cache_directory())):
            memo = directory / "memo" / key
            if not memo.is_file():
                continue
            stem = memo.read_text().strip()
            source = (directory / f"{stem}.py").read_text()
            if stem.rsplit("_", 1)[-1] == _digest(source, _versions()):
                return stem, source
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return None


def _remember(kind: str, identity: str, stem: str) -> None:
    """Write the memo of :func:`_remembered` (where the folder cannot be written, it is only not kept)."""
    with contextlib.suppress(OSError):
        folder = active_cache_directory() / "memo"
        folder.mkdir(exist_ok=True)
        _write_atomic(folder / _digest(kind, identity, _generator_digest()), stem.encode())


def _engine_module(n_state: int) -> tuple[str, str]:
    """The engine's module name (``engine_n<N>_<hash of its source and versions>``) and its source."""
    with _IMPORT_LOCK:
        if n_state not in _ENGINES:
            hit = _remembered("engine", str(n_state))
            if hit is None:
                source = engine_source(n_state)
                hit = (f"engine_n{n_state}_{_digest(source, _versions())}", source)
                _remember("engine", str(n_state), hit[0])
            _ENGINES[n_state] = hit
        return _ENGINES[n_state]


def _model_module(system: PiecewiseSystem) -> tuple[str, str]:
    """A model's module name (``<model name>_<hash of its source and versions>``) and its source.

    The name hashes the generated source itself, so two models share a module exactly when everything
    compiled into it is the same (fields, surfaces, transitions, guards, resets, domains, the period and
    its derivatives, the order of states and parameters, the contract, the code that generates it).
    The source is generated once per system object in a process."""
    with _IMPORT_LOCK:
        try:
            hit = _MODELS.get(system)
        except TypeError:  # an object that cannot be a weak key: generate each time
            hit = None
        if hit is None:
            identity = _definition(system)
            hit = _remembered("model", identity) if identity is not None else None
            if hit is None:
                source = model_source(system)
                hit = (f"{system.name}_{_digest(source, _versions())}", source)
                if identity is not None:
                    _remember("model", identity, hit[0])
            try:
                _MODELS[system] = hit
            except TypeError:
                pass
        return hit


def _engine_path(n_state: int) -> Path:
    """Where the engine of a dimension lives in the active cache folder."""
    return active_cache_directory() / f"{_engine_module(n_state)[0]}.py"


def _model_path(system: PiecewiseSystem) -> Path:
    """Where a model's functions live in the active cache folder."""
    return active_cache_directory() / f"{_model_module(system)[0]}.py"


def _numba_files(numba_dir: Path, stem: str) -> list[Path]:
    """numba's index (``.nbi``) and data (``.nbc``) files of the module ``stem``."""
    files = [*numba_dir.glob(f"{stem}.*.nbi"), *numba_dir.glob(f"{stem}.*.nbc")]
    files += [*numba_dir.glob(f"*-{stem}.*.nbi"), *numba_dir.glob(f"*-{stem}.*.nbc")]  # (library caches)
    return sorted(set(files))


_FOUND: set[tuple[frozenset[Path], str, str]] = set()  # what _cached found in this process (a listing of a large
#                                                       cache takes some 50 ms)


def _cached(stem: str, function: str) -> bool:
    """Whether numba's on-disk cache holds ``function`` of the module ``stem`` (in the active folder, or
    in the configured one it would be copied from)."""
    folders = frozenset({active_cache_directory(), cache_directory()})
    if (folders, stem, function) in _FOUND:
        return True
    found = any(any(_numba_cache_dir(d).glob(f"{stem}.{function}-*.nbi")) for d in folders)
    if found:
        _FOUND.add((folders, stem, function))
    return found


def is_engine_compiled(n: int) -> bool:
    """Whether the engine that integrates models of ``n`` states is compiled on this machine (or loaded
    in this process)."""
    stem = _engine_module(engine_dimension(n))[0]
    loaded = _LOADED.get(f"_saltation_engine_{stem}")
    if loaded is not None and all(getattr(loaded, name).overloads for name in ENTRY_POINTS):
        return True
    return all(_cached(stem, name) for name in ENTRY_POINTS)


def is_compiled(system: PiecewiseSystem) -> bool:
    """Whether numba's on-disk cache already holds the engine for this model and the model's functions."""
    from saltation.engine.compiled import CompiledSystem

    if isinstance(system, CompiledSystem):
        return False  # its functions are compiled in each process
    return is_engine_compiled(system.n) and _cached(_model_module(system)[0], "vector_field")


def _write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all (:func:`saltation.engine._atomic.write_atomic`)."""
    write_atomic(path, data)


def _intact(path: Path, pickles: int) -> bool:
    """Whether ``path`` holds ``pickles`` whole pickles and nothing else (read without running them)."""
    try:
        with open(path, "rb") as fh:
            for _ in range(pickles):
                for _op in pickletools.genops(fh):
                    pass
            return fh.read(1) == b""
    except Exception:  # noqa: BLE001 (a damaged pickle raises anything: ValueError, EOFError, ...)
        return False


def _stamps(files: list[Path]) -> dict[str, list[int]]:
    """Size and modification time (ns) of each file, by name: what changes when a file is rewritten or cut."""
    out = {}
    for f in files:
        with contextlib.suppress(OSError):
            st = f.stat()
            out[f.name] = [st.st_size, st.st_mtime_ns]
    return out


def _read_stamps(path: Path) -> dict | None:
    """The stamps :func:`_prepare` wrote when it last found a module's numba files whole, or None."""
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def _remove(files: list[Path]) -> None:
    for f in files:
        with contextlib.suppress(FileNotFoundError):
            f.unlink()


def _seed(stem: str, data: bytes, directory: Path) -> bool:
    """Copy the module ``stem`` and numba's files for it from the configured cache folder to ``directory``
    (the fallback), if the configured folder holds it intact.  Whether it did."""
    primary = cache_directory()
    if primary == directory:
        return False
    try:
        if (primary / f"{stem}.py").read_bytes() != data:
            return False
        files = _numba_files(_numba_cache_dir(primary), stem)
        contents = [(f.name, f.read_bytes()) for f in files]
    except OSError:
        return False
    target = _numba_cache_dir(directory)
    for name, content in contents:
        _write_atomic(target / name, content)
    _write_atomic(directory / f"{stem}.py", data)
    return True


def _prepare(directory: Path, stem: str, source: str, what: str) -> bool:
    """Make ``directory/<stem>.py`` hold exactly ``source`` and numba's files for it whole (a damaged
    module is rewritten; damaged numba files are removed, so numba compiles those functions again).
    Whether anything compiled before is there to be loaded."""
    path = directory / f"{stem}.py"
    data = source.encode()
    try:
        current = path.read_bytes()
    except FileNotFoundError:
        current = None
    if current != data and not (current is None and _seed(stem, data, directory)):
        if current is not None:
            _notice(f"the cached module of {what} {path} was damaged (it is not the source it is named after); "
                    "rewriting it")
        _remove(list((directory / "__pycache__").glob(f"{stem}.*.pyc")))  # Python's own bytecode of it
        _write_atomic(path, data)
    numba_dir = _numba_cache_dir(directory)
    files = _numba_files(numba_dir, stem)
    stamp = numba_dir / f"{stem}.saltation-intact.json"
    seen = _stamps(files)
    if _read_stamps(stamp) == seen:
        damaged = []  # every file as it was when it was last found whole
    else:
        damaged = [f for f in files if not _intact(f, 2 if f.suffix == ".nbi" else 1)]
        if not damaged and files:
            with contextlib.suppress(OSError):
                _write_atomic(stamp, json.dumps(seen).encode())
    if damaged:
        names = ", ".join(f.name for f in damaged[:2]) + (f" and {len(damaged) - 2} more" if len(damaged) > 2 else "")
        _notice(f"numba's cache of {what} in {numba_dir} was damaged ({names}); compiling it again")
        _remove(damaged)  # (numba compiles what has no index, or whose index names a missing data file)
    return current == data or len(files) > len(damaged)


def _execute(path: Path, modname: str) -> ModuleType:
    """Import the module at ``path`` under ``modname`` (numba compiles, or loads from its cache, the
    functions compiled eagerly)."""
    spec = importlib.util.spec_from_file_location(modname, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[modname] = module  # numba finds a module's globals by its name when it loads its cache
    try:
        spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(modname, None)
        raise
    return module


def _environment_failure(exc: BaseException) -> bool:
    """Whether ``exc`` is the file system's (a folder numba or saltation cannot write, a full disk)
    rather than a fault of the generated code."""
    return isinstance(exc, OSError) or (isinstance(exc, RuntimeError) and "no locator" in str(exc))


def _load(stem: str, source: str, modname: str, what: str, after: Callable[[ModuleType], None] | None = None) -> ModuleType:
    """Import the generated module ``stem`` (``source``) from the active cache folder, once per process.

    A module or numba cache file that is damaged is rebuilt; a module that does not load from what
    was cached (a damaged file that still looked whole) is rebuilt from scratch, once.  ``after(module)``
    runs once the module is imported (each call), under the same rebuild: the engine compiles its entry
    points there.

    Raises
    ------
    KernelCacheError
        If the folder cannot be written, or the module cannot be rebuilt in it.
    """
    with _IMPORT_LOCK:
        if modname in _LOADED:
            if after is not None:
                after(_LOADED[modname])
            return _LOADED[modname]
        directory = active_cache_directory()
        path = directory / f"{stem}.py"
        delete = f"delete the folder {directory} (it only holds compiled code) and run again"
        try:
            prior = _prepare(directory, stem, source, what)
        except OSError as exc:
            raise KernelCacheError(f"cannot read or write {what} in the kernel cache {directory} "
                                   f"({type(exc).__name__}: {exc}); free space or make it writable, or {delete}") from exc
        try:
            module = _execute(path, modname)
            if after is not None:
                after(module)
        except Exception as exc:
            if not prior:  # a fresh build failed: the cache did not cause it
                if _environment_failure(exc):
                    raise KernelCacheError(f"cannot compile {what} in the kernel cache {directory} "
                                           f"({type(exc).__name__}: {exc}); make it writable, or {delete}") from exc
                raise
            _notice(f"{what} did not load from the kernel cache {directory} ({type(exc).__name__}: "
                    f"{' '.join(str(exc).split())[:200]}); compiling it again")
            try:
                numba_dir = _numba_cache_dir(directory)
                _remove(_numba_files(numba_dir, stem) + list((directory / "__pycache__").glob(f"{stem}.*.pyc")))
                _write_atomic(path, source.encode())
                module = _execute(path, modname)
                if after is not None:
                    after(module)
            except Exception as again:
                if _environment_failure(again) or _environment_failure(exc):
                    raise KernelCacheError(f"{what} cannot be rebuilt in the kernel cache {directory} "
                                           f"({type(again).__name__}: {again}); {delete}") from again
                raise
        _LOADED[modname] = module
        return module


_BUILD_WATCHERS: list[Callable[[str | None, float], None]] = []


@contextlib.contextmanager
def build_watcher(callback: Callable[[str | None, float], None]):
    """While active, a build (:func:`building`) is shown by ``callback(message, seconds)``, every second
    and once at the end with ``message`` None, instead of a line of its own on standard error: a progress
    bar on the terminal shows it (the command line's does)."""
    _BUILD_WATCHERS.append(callback)
    try:
        yield
    finally:
        _BUILD_WATCHERS.remove(callback)


@contextlib.contextmanager
def building(message: str | None, *, stream=None, interval: float = 1.0, estimate: BuildEstimate | None = None):
    """Say what is being built, and keep saying it until it is done (a compile of a minute should not look
    like a hang): an ``INFO`` record of ``saltation.engine.codegen`` at its start and its end, and a tqdm bar
    of its seconds on standard error where that is a terminal or a notebook (:mod:`saltation.progress`, which
    can turn it off).  With a :func:`build_watcher` active, the watcher shows it instead; with ``stream``, a
    line on that stream, rewritten with the seconds on a terminal.  A build within one already announced (in
    this thread) is not announced again, nor recorded.  ``message`` None: a build not announced.

    With ``estimate`` (:func:`saltation.engine.buildtime.estimate_build`, made as the build starts), a build
    that finishes is recorded in the kernel cache folder, and the next builds' estimates come from it."""
    if getattr(_BUILD_NOTICE, "active", False):  # (within a build already announced: that notice covers it)
        yield
        return
    _BUILD_NOTICE.active = True
    try:
        with contextlib.ExitStack() as stack:
            if estimate is not None:  # (a build that raises is not recorded)
                stack.enter_context(timed(active_cache_directory(), estimate))
            if message is not None:
                stack.enter_context(_announced(message, stream, interval,
                                               None if estimate is None else estimate.seconds))
            yield
    finally:
        _BUILD_NOTICE.active = False


_BUILD_NOTICE = threading.local()


@contextlib.contextmanager
def _announced(message: str, stream, interval: float, seconds: float | None = None):
    _log.info("%s", message)
    start = time.monotonic()
    try:
        with _shown(message, stream, interval, seconds):
            yield
    finally:
        _log.info("%s: done in %.0f s", message, time.monotonic() - start)


@contextlib.contextmanager
def _ticking(interval: float, tick: Callable[[float], None], name: str):
    """Call ``tick(seconds elapsed)`` every ``interval`` seconds in a thread of its own while the block runs."""
    done = threading.Event()
    start = time.monotonic()

    def run() -> None:
        while not done.wait(interval):
            tick(time.monotonic() - start)

    ticker = threading.Thread(target=run, name=name, daemon=True)
    ticker.start()
    try:
        yield
    finally:
        done.set()
        ticker.join()


@contextlib.contextmanager
def _shown(message: str, stream, interval: float, seconds: float | None):
    """Show a build while it runs: to the build watchers, on ``stream``, or in a progress bar."""
    start = time.monotonic()
    watchers = list(_BUILD_WATCHERS)
    if watchers:
        def tell(elapsed: float) -> None:
            for watch in watchers:
                watch(message, elapsed)

        tell(0.0)
        try:
            with _ticking(interval, tell, "saltation-build-watch"):
                yield
        finally:
            for watch in watchers:
                watch(None, time.monotonic() - start)
        return
    if stream is None:
        with _progress_bar(message, interval, seconds):
            yield
        return
    live = bool(getattr(stream, "isatty", lambda: False)())
    stream.write(f"saltation: {message}" + ("" if live else "\n"))
    stream.flush()
    if not live:
        yield
        return

    def tick(elapsed: float) -> None:
        stream.write(f"\rsaltation: {message} ... {elapsed:.0f} s")
        stream.flush()

    try:
        with _ticking(interval, tick, "saltation-build-notice"):
            yield
    finally:
        stream.write(f"\rsaltation: {message} ... done in {time.monotonic() - start:.0f} s\n")
        stream.flush()


@contextlib.contextmanager
def _progress_bar(message: str, interval: float, seconds: float | None):
    """A tqdm bar of the seconds of a build (:func:`saltation.progress.bar`; nothing where bars are off or
    standard error is not a terminal)."""
    from saltation.progress import bar

    shown = bar(f"saltation: {message}", seconds)
    if shown is None or shown.disable:
        if shown is not None:
            shown.close()
        yield
        return
    try:
        with _ticking(interval, lambda elapsed: shown.update(elapsed - shown.n), "saltation-build-bar"):
            yield
    finally:
        shown.close()


ENTRY_POINTS = {
    "_integrate_steps": "STEPS_SIGNATURE",
    "_surface_step": "SURFACE_STEP_SIGNATURE",
    "_sliding_events": "SLIDING_EVENTS_SIGNATURE",
    "correct_periodic": "CORRECT_SIGNATURE",
    "integrate_kernel": "INTEGRATE_SIGNATURE",
}
"""The engine's separately compiled functions and the names of their signatures in its module.  Each is
compiled for that signature alone, and on its own: each calls the others through their addresses (the
Newton the integrator, the integrator its step-and-event loop, the loop its surfaces' watch and its
sliding steps' events), so none links another into its library, and a cold cache compiles them side by
side (:func:`saltation.engine.precompile.compile_in_parallel`)."""

COMPILE_GROUPS = (("_integrate_steps",), ("_surface_step", "_sliding_events", "correct_periodic", "integrate_kernel"))
"""How a cold cache splits :data:`ENTRY_POINTS` between processes: the loop (the longest, some 20 s) in one,
the rest (about as long together) in another, so that two cores finish at about the same time."""

COMPILE_GROUP_SECONDS = (22.0, 18.0)
"""About how long each of :data:`COMPILE_GROUPS` takes to compile (one core of a 2-core machine, 2-state
engine): :mod:`saltation.engine.precompile` balances the processes of a cold build by them."""


SHARED_ENGINE_FACTOR = 1.2
"""How much longer the engine that every larger dimension shares (``N_STATE = 0``: loops over a state of
unknown length) takes to compile than one of a fixed dimension.  Measured: 1.11 and 1.27 times the
processor time, in two pairs of first builds on one machine (with a 10-state chain's functions, against
the 2-state engine with ``trilinear``'s)."""


def engine_seconds(n_state: int, names: Iterable[str]) -> float:
    """About how long compiling the entry points ``names`` of the engine with ``N_STATE = n_state`` takes,
    on one core as :data:`COMPILE_GROUP_SECONDS`: each group's seconds shared equally between its
    functions, times :data:`SHARED_ENGINE_FACTOR` for the shared engine (0).

    Parameters
    ----------
    n_state : int
        The engine's ``N_STATE`` (:func:`engine_dimension`).
    names : iterable of str
        Entry points (:data:`ENTRY_POINTS`) to compile.

    Returns
    -------
    float
        Seconds.
    """
    todo = set(names)
    seconds = sum(cost * len(todo.intersection(group)) / len(group)
                  for group, cost in zip(COMPILE_GROUPS, COMPILE_GROUP_SECONDS))
    return seconds * (SHARED_ENGINE_FACTOR if n_state == 0 else 1.0)


def model_seconds(system: PiecewiseSystem) -> float:
    """About how long a model's functions take to compile, in an interpreter that has compiled something
    already (one core of a 2-core machine, as :data:`COMPILE_GROUP_SECONDS`):
    2 s, a tenth of a second for each pair of a mode and a surface (the Lie derivatives) and each
    transition (the guards), and ``n**2 / 400`` s for ``n`` states (the Jacobians).  Measured: 3.3 s for
    ``trilinear`` (3 modes, 4 surfaces, 8 transitions), 5 s for ``block_on_belt`` (3, 5, 14); on a
    machine (or a load) that took 6.4 s for ``trilinear``, a chain of 2 masses (4 states; 3, 4, 8) 7.3 s,
    of 8 masses 8.5 s, of 16 10.5 s and of 32 (64 states) 23.6 s.

    Parameters
    ----------
    system : PiecewiseSystem
        The model.

    Returns
    -------
    float
        Seconds.
    """
    return 2.0 + 0.1 * (len(system.modes) * len(system.surface_names) + len(system.transitions)) + system.n**2 / 400


def _entry_points(names: tuple[str, ...]) -> Callable[[ModuleType], None]:
    def compile_them(module: ModuleType) -> None:
        for name in names:
            dispatcher = getattr(module, name)
            if not dispatcher.overloads:
                dispatcher.compile(getattr(module, ENTRY_POINTS[name]))  # (numba loads it from its cache if there)
            dispatcher.disable_compile()  # one signature: a call with other types is an error, not a new compile

    return compile_them


def load_engine(n: int, entry_points: tuple[str, ...] = tuple(ENTRY_POINTS)) -> ModuleType:
    """Import the engine that integrates models of ``n`` states with its ``entry_points`` compiled,
    compiling them first if this machine has not yet (once; it says so on standard error, with how long
    it should take here, since it takes a while)."""
    n_state = engine_dimension(n)
    stem, source = _engine_module(n_state)
    modname = f"_saltation_engine_{stem}"
    what = f"the integrator for N_STATE = {n_state}"
    loaded = _LOADED.get(modname)
    if not (loaded is not None and all(getattr(loaded, name).overloads for name in entry_points)) and not all(
        _cached(stem, name) for name in entry_points
    ):
        which = f"{n_state}-state models" if n_state else f"models of {min(SPECIALIZED_DIMENSIONS.stop, n)} or more states"
        estimate = None
        if not getattr(_BUILD_NOTICE, "active", False):  # (within a build, that build's estimate covers it)
            work = engine_seconds(n_state, [name for name in entry_points if not _cached(stem, name)])
            estimate = estimate_build(active_cache_directory(), engine_kind(n_state), (work,))
        when = f"{estimate.text}; " if estimate is not None and estimate.text else ""
        with building(f"compiling the integrator for {which}, once for this machine ({when}"
                      f"cached in {active_cache_directory()})", estimate=estimate):
            return _load(stem, source, modname, what, _entry_points(entry_points))
    return _load(stem, source, modname, what, _entry_points(entry_points))


def engine_kind(n_state: int) -> str:
    """The kind of build (:mod:`saltation.engine.buildtime`) of the engine with ``N_STATE = n_state``.

    Parameters
    ----------
    n_state : int
        The engine's ``N_STATE`` (:func:`engine_dimension`).

    Returns
    -------
    str
        ``"engine 2"``, or ``"engine 5+"`` for the engine every larger dimension shares (0).
    """
    return f"engine {n_state}" if n_state else f"engine {SPECIALIZED_DIMENSIONS.stop}+"


MODEL_ANNOUNCED_SECONDS = 10.0
"""A model's functions compiled on their own are announced (:func:`building`) when they should take at
least this long here: a model of many states (some 25 s for 64), not the seconds of a small one."""


_LOADED_COMPILED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # CompiledSystem -> model tuple


def load_model_functions(system: PiecewiseSystem) -> tuple:
    """The model tuple the engine takes (see the contract): the model's compiled functions and which
    modes are affine, generated, written and compiled if needed (cached per machine)."""
    from saltation.engine.compiled import CompiledSystem, build_model_functions

    if isinstance(system, CompiledSystem):
        with _IMPORT_LOCK:  # (kept per object: an id in a key could be reused by a later object)
            if system not in _LOADED_COMPILED:
                _LOADED_COMPILED[system] = build_model_functions(system)
            return _LOADED_COMPILED[system]
    stem, source = _model_module(system)
    modname, what = f"_saltation_model_{stem}", f"the functions of model {system.name!r}"
    if modname in _LOADED or getattr(_BUILD_NOTICE, "active", False) or _cached(stem, "vector_field"):
        return _load(stem, source, modname, what).MODEL
    work = model_seconds(system)  # (a small model is not worth the probe of a first estimate: it is not announced)
    estimate = estimate_build(active_cache_directory(), "model functions", (work,), calibrate=work >= 5.0)
    announced = estimate.seconds is not None and estimate.seconds >= MODEL_ANNOUNCED_SECONDS
    message = f"compiling {what}, once for this machine ({estimate.text})" if announced else None
    with building(message, estimate=estimate):
        return _load(stem, source, modname, what).MODEL
