"""Each mode's field read on its own side of its switching surfaces: one-sided limits at the surface.

A contact law as measured is a fractional power of the penetration: a Hertzian contact
``k (x - d)^(3/2)``, a friction law with a non-integer power of the slip speed.  In the mode where the
contact acts, the base ``x - d`` is positive; at the surface it is zero, and the integrator evaluates the
mode's field there (the event's state, eq. 9 needs ``f`` on both sides) and a little beyond it (the stages
of the step that crosses, the iterations that locate the event).  Real arithmetic then gives ``NaN`` for
``(-1e-17)^(3/2)``, and ``0/0``-like infinities for the derivatives, though the mode's field has a limit at
its surface.

Here each mode knows the expressions that are non-negative wherever it is active
(:meth:`saltation.model.system.PiecewiseSystem.mode_sides`): its
domain's conditions, and the surfaces it leaves through a transition without a guard (a mode left where
``h`` falls through zero lives where ``h >= 0``).  :func:`on_its_side` rewrites a power ``b^e`` with a
non-integer exponent whose base is ``b = c s``, a multiple of such an expression ``s`` by numbers and
parameters, into ``(c max(s, 0))^e``.  On the mode's side (``s >= 0``) nothing changes, whatever the sign
of ``c``; beyond the surface the base is held at its value on the surface, so the field takes its limit
there.  A base that is negative inside the mode's own region still gives ``NaN`` there (and the integrator
says so, naming the mode): the rewrite only reads the mode where its surfaces bound it.

Apply it after differentiation (the derivative of ``max(b, 0)`` is not the field's): the code generator
rewrites ``f``, ``f_x``, ``f_p`` and the Lie derivatives of each mode (:mod:`saltation.engine.codegen`).
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

__all__ = ["on_its_side"]


def _multiple(base: sp.Expr, side: sp.Expr, moving: frozenset) -> sp.Expr | None:
    """``c`` with ``base = c * side`` and ``c`` free of the state and time (a number or parameters), or None."""
    if side == 0 or not base.free_symbols & moving:
        return None
    ratio = sp.cancel(base / side)
    if ratio == 0 or ratio.free_symbols & moving or ratio.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        return None
    return ratio


def _fractional(exponent: sp.Expr) -> bool:
    """A power that real arithmetic cannot take of a negative base: not an integer (or not known to be one)."""
    return not (exponent.is_Integer or (exponent.is_Number and float(exponent).is_integer()))


def on_its_side(expr, sides: Sequence[sp.Expr], moving: Sequence[sp.Symbol]):
    """``expr`` with each fractional power of a mode-side expression read on that side.

    Parameters
    ----------
    expr : sympy expression or Matrix
        A field, one of its derivatives, or a Lie derivative of the mode.
    sides : sequence of sympy expressions
        What :meth:`~saltation.model.system.PiecewiseSystem.mode_sides` gives for the mode.
    moving : sequence of sympy symbols
        The states and time (what is not a parameter).

    Returns
    -------
    sympy expression or Matrix
        ``expr`` with every ``b**e`` (``e`` not an integer, ``b = c * s`` for one of ``sides`` ``s`` and a
        factor ``c`` of numbers and parameters) written ``(c * Max(s, 0))**e``: the same value wherever
        ``s >= 0`` (the mode's side), the value at the surface ``s = 0`` beyond it.  In a product, the
        powers of multiples of one side are gathered first (``(v/v_s)**delta / v``, a derivative, becomes
        ``v_s**-delta * Max(v, 0)**(delta - 1)``: its limit at the surface, not ``0/0``), and a ``log(b)``
        beside ``b**e`` (a derivative in the exponent) reads ``b`` at least the smallest positive double,
        so that the product takes its limit 0.  ``expr`` itself when nothing applies.
    """
    if not sides:
        return expr
    moving = frozenset(moving)
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(lambda e: on_its_side(e, sides, moving))

    def side_of(base: sp.Expr) -> tuple[sp.Expr, sp.Expr] | None:
        for s in sides:
            c = _multiple(base, s, moving)
            if c is not None:
                return c, s
        return None

    def one_sided_power(node: sp.Basic) -> bool:
        return isinstance(node, sp.Pow) and _fractional(node.exp) and side_of(node.base) is not None

    def gathered(node: sp.Mul) -> sp.Expr:
        groups: dict[sp.Expr, list] = {}
        rest = []
        for f in node.args:
            base, exp = (f.base, f.exp) if isinstance(f, sp.Pow) else (f, sp.Integer(1))
            found = side_of(base) if not isinstance(f, sp.log) else None
            if found is None:
                rest.append(f)
                continue
            c, s = found
            groups.setdefault(s, []).append((c, exp, _fractional(exp)))
        for s, members in groups.items():
            if not any(frac for _, _, frac in members):  # no fractional power of this side: as written
                rest += [sp.Pow(c * s, e) for c, e, _ in members]
                continue
            total = sp.Add(*(e for _, e, _ in members))
            coefficient = sp.Mul(*(sp.Pow(c, e) for c, e, _ in members))
            rest.append(coefficient * sp.Pow(sp.Max(s, 0), total, evaluate=False))
        logs = {s for s in groups if any(frac for _, _, frac in groups[s])}
        out = []
        for f in rest:
            found = side_of(f.args[0]) if isinstance(f, sp.log) else None
            if found is not None and found[1] in logs:
                f = sp.log(found[0] * sp.Max(found[1], _TINY))
            out.append(f)
        return sp.Mul(*out, evaluate=False)

    def has_one_sided_power(node: sp.Basic) -> bool:
        return isinstance(node, sp.Mul) and any(one_sided_power(f) for f in node.args)

    expr = expr.replace(has_one_sided_power, gathered)
    return expr.replace(one_sided_power, lambda node: sp.Pow(
        sp.Mul(side_of(node.base)[0], sp.Max(side_of(node.base)[1], 0), evaluate=False), node.exp, evaluate=False))


#: where ``b^e log(b)`` is read beyond its surface, ``log`` sees this instead of 0 (the power is 0 there, so
#: the product is the limit 0)
_TINY = sp.Float(2.2250738585072014e-308)
