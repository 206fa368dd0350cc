"""Monitors: a user's own test functions along a branch, located like the special points.

A :class:`Monitor` is a function of a branch point's record (:class:`~saltation.orbits.records.BranchPoint`)
whose zeros the continuation locates, by the Illinois iteration on the secant that locates the smooth
special points (:func:`illinois_on_secant`), and records as special points of kind ``monitor``; one that
``stop`` s ends the run there (:attr:`~saltation.kinds.StopReason.MONITOR`).  As COCO's and
BifurcationKit's user events: "the amplitude equals the clearance", "the maximum contact force reaches F".

Written as text (:meth:`Monitor.parse`, the command line's ``--monitor``), a monitor is ``EXPR`` (located
where it crosses zero) or ``LHS = RHS``.  Each side is an expression of the record's numbers, by name:
``parameter`` (or the continuation parameter's own name), ``period``, ``amplitude``, ``half_peak_to_peak``,
``excursion``, ``largest_multiplier`` (the largest modulus), the model's other parameters (their values);
or, where a side names a state, a measure of the orbit (:mod:`saltation.orbits.measures`: ``x`` is
``max |x|``, ``sqrt(x**2 + y**2)`` its largest value over the period, ``ptp:x``, ``norm``), which the branch
then records at every point.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from saltation.errors import ModelError
from saltation.orbits.measures import Measure
from saltation.orbits.records import BranchPoint

__all__ = ["Monitor", "illinois_on_secant", "parse_monitors"]

#: the record's numbers a monitor's expression may name
RECORD_NAMES = ("parameter", "period", "amplitude", "half_peak_to_peak", "excursion", "largest_multiplier")


@dataclass(frozen=True)
class Monitor:
    """A function of a branch point whose zeros the continuation locates.

    Attributes
    ----------
    name : str
        What the special points it makes are called (their ``note``; the text of a parsed monitor).
    function : callable
        ``function(point) -> float`` of a :class:`~saltation.orbits.records.BranchPoint` (with its
        ``measures``).
    stop : bool
        Whether the run ends where it crosses zero.
    measures : tuple of str
        The measures the function reads from ``point.measures`` (the continuation records them).

    Raises
    ------
    TypeError
        If ``function`` is not callable.
    """

    name: str
    function: Callable[[BranchPoint], float]
    stop: bool = False
    measures: tuple[str, ...] = ()

    def __post_init__(self):
        if not callable(self.function):
            raise TypeError(f"monitor {self.name!r}: its function must be callable, got {type(self.function).__name__}")

    def __call__(self, point: BranchPoint) -> float:
        return float(self.function(point))

    @classmethod
    def parse(cls, text: str, system, parameter: str, *, stop: bool = False) -> Monitor:
        """The monitor written ``EXPR`` or ``LHS = RHS`` (see the module's docstring).

        Parameters
        ----------
        text : str
            The monitor.
        system : PiecewiseSystem
            The model (its states and parameters).
        parameter : str
            The continuation parameter.
        stop : bool
            Whether the run ends where it crosses zero.

        Returns
        -------
        Monitor

        Raises
        ------
        ModelError
            If a side does not parse, or names what is neither a number of the record, a parameter nor a
            measure of the model.
        """
        lhs, sep, rhs = str(text).partition("=")
        sides = [_side(lhs.strip(), system, parameter, text)]
        if sep:
            sides.append(_side(rhs.strip(), system, parameter, text))
        measures = tuple(m for _, m in sides if m)
        functions = [f for f, _ in sides]

        def value(point: BranchPoint) -> float:
            out = functions[0](point)
            return out - functions[1](point) if len(functions) > 1 else out

        return cls(str(text).strip(), value, stop, measures)


def _side(expression: str, system, parameter: str, text: str) -> tuple[Callable[[BranchPoint], float], str]:
    """One side of a monitor: a function of the record, and the measure it reads (or "")."""
    import sympy as sp

    if not expression:
        raise ModelError(f"monitor {text!r}: a side of '=' is empty")
    names = {name: sp.Symbol(name) for name in (*RECORD_NAMES, *system.parameter_names)}
    try:
        expr = sp.sympify(expression, locals=names)
    except (sp.SympifyError, SyntaxError, TypeError):
        expr = None
    if expr is not None and isinstance(expr, sp.Expr) and {str(s) for s in expr.free_symbols} <= set(names):
        used = sorted(str(s) for s in expr.free_symbols)
        f = sp.lambdify([sp.Symbol(n) for n in used], expr, modules="math")
        return (lambda point: float(f(*(_record_value(point, n, parameter, system) for n in used)))), ""
    try:
        measure = Measure.parse(expression, system)
    except ModelError as exc:
        raise ModelError(f"monitor {text!r}: {expression!r} is neither an expression of the record's numbers "
                         f"({', '.join(RECORD_NAMES)}, the parameters) nor a measure of the orbit: {exc}") from None
    return (lambda point: float(point.measures[measure.text])), measure.text


def _record_value(point: BranchPoint, name: str, parameter: str, system) -> float:
    if name == "parameter" or name == parameter:
        return float(point.parameter)
    if name == "largest_multiplier":
        return float(np.max(np.abs(point.multipliers))) if len(point.multipliers) else math.nan
    if name in RECORD_NAMES:
        return float(getattr(point, name))
    return float(system.defaults[name]) if name in getattr(system, "defaults", {}) else math.nan


def parse_monitors(monitors: Sequence[Monitor | str], system, parameter: str) -> tuple[Monitor, ...]:
    """Monitors from their Python form or their text.

    Parameters
    ----------
    monitors : sequence of Monitor or str
        The monitors (texts are parsed by :meth:`Monitor.parse`, not stopping).
    system : PiecewiseSystem
        The model.
    parameter : str
        The continuation parameter.

    Returns
    -------
    tuple of Monitor

    Raises
    ------
    ModelError
        As :meth:`Monitor.parse`.
    """
    return tuple(m if isinstance(m, Monitor) else Monitor.parse(m, system, parameter) for m in monitors)


def illinois_on_secant(on_secant: Callable[[float], object], test: Callable[[object], float], a, b, *,
                       tol: float, distance: Callable[[object, object], float], max_iter: int = 80):
    """The bracket of a sign change of ``test`` between two branch points, narrowed along their secant by the
    Illinois method (regula falsi with the halving of a stale end).

    Parameters
    ----------
    on_secant : callable
        ``on_secant(sigma)``: the corrected point at the fraction ``sigma`` of the secant from ``a`` to ``b``
        (raises :class:`~saltation.errors.SaltationError` where it cannot be corrected).
    test : callable
        The test function of a point.
    a, b :
        The points on either side of the sign change.
    tol : float
        The bracket is narrowed until its ends are this close.
    distance : callable
        ``distance(p, q)`` of two points.
    max_iter : int
        The most iterations.

    Returns
    -------
    tuple
        ``(lo, hi)``: the final bracket (the same point twice where the test is exactly 0).

    References
    ----------
    Dowell and Jarratt (1971), "A modified regula falsi method for computing the root of an equation",
    BIT 11.
    """
    from saltation.errors import SaltationError

    sa, sb = 0.0, 1.0
    ga, gb = test(a), test(b)
    lo, hi = a, b
    side = 0
    for _ in range(max_iter):
        if distance(lo, hi) <= tol:
            break
        sm = sb - gb * (sb - sa) / (gb - ga) if gb != ga else 0.5 * (sa + sb)
        if not (sa < sm < sb) or (sb - sa) < 1e-14:
            sm = 0.5 * (sa + sb)
        try:
            mid = on_secant(sm)
        except SaltationError:
            break
        gm = test(mid)
        if gm == 0.0:
            return mid, mid
        if np.sign(gm) == np.sign(ga):
            sa, ga, lo = sm, gm, mid
            if side == -1:
                gb *= 0.5
            side = -1
        else:
            sb, gb, hi = sm, gm, mid
            if side == 1:
                ga *= 0.5
            side = 1
    return lo, hi
