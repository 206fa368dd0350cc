"""Models given as compiled callables: the escape hatch for fields sympy cannot express.

A :class:`CompiledSystem` carries numba-compiled functions with the same
signatures as the ones :mod:`saltation.engine.codegen` generates from expressions,
and the user supplies every derivative.  It works with :class:`~saltation.Flow`,
shooting and continuation like a :class:`~saltation.model.system.PiecewiseSystem`;
what it cannot do is print saltation matrices in closed form.

Required functions (``mode``, ``surface``, ``k`` are integer indices; arrays
are written in place)::

    vector_field(mode, t, x, p, out)            # f
    vector_field_jac(mode, t, x, p, out)        # f_x, shape (n, n)
    indicator(surface, t, x, p) -> float        # h
    indicator_grad(surface, t, x, p, hx, hp) -> float   # fills h_x, h_p; returns h_t

Optional ones (defaults: no parameter derivatives, no resets, no guards,
every state in the first mode, sliding unavailable)::

    vector_field_dp(mode, t, x, p, out)         # f_p, shape (n, n_params)
    reset_map(k, t, x, p, out)                  # g of transition k
    reset_jac(k, t, x, p, gx, gt, gp)           # g_x, g_t, g_p
    guard(k, t, x, p) -> bool
    in_domain(mode, t, x, p) -> bool            # the initial-mode rule
    lie_derivative(mode, surface, t, x, p, gx, gp) -> float   # h_x f + h_t and its gradients (sliding)
    lie_derivative_dt(mode, surface, t, x, p) -> float

Each function is compiled once per process with its signature from the
contract (``saltation.engine._contract.MODEL_SIGNATURES``); the engine is the one
every model shares, compiled once per machine.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from saltation.engine._contract import MODEL_SIGNATURES
from saltation.errors import InitialModeError, ModelError
from saltation.model.system import Crossing, NamedParts, Transition

REQUIRED = ("vector_field", "vector_field_jac", "indicator", "indicator_grad")
OPTIONAL = (
    "vector_field_dp", "reset_map", "reset_jac", "guard", "in_domain", "lie_derivative", "lie_derivative_dt",
)

_DEFAULTS = '''
@njit
def indicator_rate(surface, t, x, f, p, hx, hp):
    acc = indicator_grad(surface, t, x, p, hx, hp)  # h_t + h_x f from the model's indicator_grad
    for i in range(x.shape[0]):
        acc += hx[i] * f[i]
    return acc

@njit
def affine_parts(mode, p, A, B, w):
    return

@njit
def affine_parts_dp(mode, p, Ap, Bp, wp):
    return
@njit
def forcing_period(p):
    return math.nan  # a Python callable: the compiled corrector is not used

@njit
def forcing_period_dp(p, k):
    return math.nan

@njit
def vector_field_dp(mode, t, x, p, out):
    out[:, :] = 0.0

@njit
def reset_map(k, t, x, p, out):
    out[:] = x

@njit
def reset_jac(k, t, x, p, gx, gt, gp):
    gx[:, :] = 0.0
    for i in range(gx.shape[0]):
        gx[i, i] = 1.0
    gt[:] = 0.0
    gp[:, :] = 0.0

@njit
def guard(k, t, x, p):
    return True

@njit
def in_domain(mode, t, x, p):
    return mode == 0

@njit
def domain_margin(mode, t, x, p):
    return math.inf  # unknown for callables: no check beyond in_domain

@njit
def lie_derivative(mode, surface, t, x, p, gx, gp):
    gx[:] = math.nan
    gp[:] = math.nan
    return math.nan

@njit
def lie_derivative_dt(mode, surface, t, x, p):
    return math.nan
'''


class CompiledSystem(NamedParts):
    """A piecewise-smooth system given by numba-compiled callables.

    Parameters
    ----------
    name : str
    states : sequence of str
    parameters : mapping of str to float
    modes, surfaces : sequence of str
        Names; the callables receive their indices.
    transitions : sequence of Transition
        As for :class:`~saltation.model.system.PiecewiseSystem`; ``reset`` is any
        non-None value for a transition whose reset ``reset_map`` implements,
        and guards are evaluated by the ``guard`` callable.
    functions : mapping of str to numba dispatcher
        The compiled functions (see the module docstring).
    period : callable, optional
        ``period(p) -> float``: the forcing period (forced systems); with it,
        ``period_derivative(p, k) -> float`` may be given too (default: central
        differences).

    Raises
    ------
    ModelError
        For a missing required function, an unknown function name, or a
        transition naming an unknown mode or surface.
    """

    def __init__(
        self,
        name: str,
        states: Sequence[str],
        parameters: Mapping[str, float],
        modes: Sequence[str],
        surfaces: Sequence[str],
        transitions: Sequence[Transition],
        functions: Mapping[str, Callable],
        *,
        period: Callable[[np.ndarray], float] | None = None,
        period_derivative: Callable[[np.ndarray, int], float] | None = None,
    ):
        self.name = name
        self.state_names = tuple(states)
        self.parameter_names = tuple(parameters)
        self.defaults = {k: float(v) for k, v in parameters.items()}
        self.mode_names = tuple(modes)
        self.surface_names = tuple(surfaces)
        missing = [f for f in REQUIRED if f not in functions]
        if missing:
            raise ModelError(f"compiled system {name!r}: missing function(s) {missing}; required are {list(REQUIRED)}")
        unknown = sorted(set(functions) - set(REQUIRED) - set(OPTIONAL))
        if unknown:
            raise ModelError(f"compiled system {name!r}: unknown function name(s) {unknown}")
        self.functions = dict(functions)
        self.transitions = tuple(transitions)
        for k, tr in enumerate(self.transitions):
            for role, mname in (("source", tr.source), ("target", tr.target)):
                if mname not in self.mode_names:
                    raise ModelError(f"transition {k}: {role} mode {mname!r} does not exist; modes are {list(self.mode_names)}")
            if tr.surface not in self.surface_names:
                raise ModelError(f"transition {k}: surface {tr.surface!r} does not exist; surfaces are {list(self.surface_names)}")
            Crossing(int(tr.direction))
        if any(tr.reset is not None for tr in self.transitions) and "reset_map" not in functions:
            raise ModelError(f"compiled system {name!r}: a transition has a reset but no reset_map/reset_jac is given")
        self.resets = [tr.reset for tr in self.transitions]
        self._period = period
        self._period_derivative = period_derivative
        self.fingerprint = f"compiled:{name}:{id(self)}"

    # -- the interface Flow and the problems use -----------------------------------------
    @property
    def is_autonomous(self) -> bool:
        return self._period is None

    @property
    def period_expr(self) -> str | None:
        return None if self._period is None else "period(p)"

    def forcing_period(self, p: np.ndarray) -> float:
        if self._period is None:
            raise ModelError(f"model {self.name!r} is autonomous: it has no forcing period")
        value = float(self._period(p))
        if not (math.isfinite(value) and value > 0):
            raise ModelError(f"forcing period evaluates to {value} for these parameters")
        return value

    def period_derivative(self, p: np.ndarray, index: int) -> float:
        if self._period is None:
            return 0.0
        if self._period_derivative is not None:
            return float(self._period_derivative(p, index))
        h = 1e-6 * (1.0 + abs(p[index]))
        up, down = p.copy(), p.copy()
        up[index] += h
        down[index] -= h
        return (float(self._period(up)) - float(self._period(down))) / (2 * h)

    def initial_mode(self, x0, p, t0: float = 0.0) -> int:
        raise InitialModeError(
            f"initial state {list(map(float, x0))} at t = {t0} lies in no mode of {self.name!r} "
            "(its in_domain function is false for every mode)"
        )

    def __repr__(self) -> str:
        return f"CompiledSystem({self.name!r}, states={list(self.state_names)}, modes={list(self.mode_names)})"


def build_model_functions(system: CompiledSystem) -> tuple:
    """The model tuple the engine takes (see ``saltation.engine._contract``): the system's callables and the
    defaults, each compiled with its signature from the contract (in memory, once per process)."""
    import numba

    namespace: dict[str, object] = {"np": np, "math": math, "njit": numba.njit}
    exec(compile(_DEFAULTS, f"<saltation defaults for {system.name}>", "exec"), namespace)  # noqa: S102
    namespace.update(system.functions)
    initial = (
        "@njit\n"
        "def initial_mode(t, x, p):\n"
        f"    for m in range({len(system.mode_names)}):\n"
        "        if in_domain(m, t, x, p):\n"
        "            return m\n"
        "    return -1\n"
    )
    exec(compile(initial, f"<saltation initial mode for {system.name}>", "exec"), namespace)  # noqa: S102
    functions = []
    for name, signature in MODEL_SIGNATURES.items():
        f = namespace[name]
        try:
            functions.append(numba.njit(signature)(getattr(f, "py_func", f)))
        except Exception as exc:  # numba's typing errors are long: name the function and the signature first
            raise ModelError(
                f"compiled system {system.name!r}: {name} does not compile with the signature {signature} "
                f"(arrays float64 and C-contiguous, indices int64): {exc}"
            ) from exc
    affine = np.zeros(len(system.mode_names), dtype=np.bool_)  # no exact flows: the fields are opaque
    return (*functions, affine)
