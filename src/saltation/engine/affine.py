"""Affine modes: vector fields whose flow is known exactly.

A mode whose field has the form

    f(t, x, p) = A(p) x + b(p) + c(p) cos(theta) + d(p) sin(theta),   theta = Omega(p) t + phi(p)

(every mode of both models of *Fold bifurcations in discontinuous systems*) is
the first block of the autonomous linear system ``u' = M u`` in
``u = (x, 1, cos theta, sin theta)``.  Its flow, fundamental solution matrix
and parameter sensitivity are the exponential of ``M`` (block-triangular for
the sensitivity), which the integrator sums as a Taylor series to rounding
error instead of approximating it by Runge-Kutta stages (``docs/algorithms.md``).

:func:`affine_form` recognises such fields symbolically; anything else
(nonlinear fields, parametric excitation, several forcing frequencies) is
left to the general integrator.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp


@dataclass(frozen=True)
class AffineForm:
    """``f = A x + B (1, cos theta, sin theta)``, ``theta = omega t + phase``.

    Attributes
    ----------
    A : sympy.Matrix, shape (n, n)
    B : sympy.Matrix, shape (n, 3)
        Columns ``b``, ``c``, ``d``.
    omega, phase : sympy.Expr
        Frequency and phase of the forcing (both 0 without a time-dependent part).
    """

    A: sp.Matrix
    B: sp.Matrix
    omega: sp.Expr
    phase: sp.Expr


def affine_form(field: sp.Matrix, states: Sequence[sp.Symbol], time: sp.Symbol) -> AffineForm | None:
    """The affine form of a mode's field, or None if it has none.

    Parameters
    ----------
    field : sympy.Matrix, shape (n, 1)
    states : sequence of sympy.Symbol
    time : sympy.Symbol

    Returns
    -------
    AffineForm or None
        None when ``f_x`` depends on ``x`` or ``t``, or when the rest is not a
        constant plus one harmonic ``cos``/``sin`` of a phase linear in ``t``.
    """
    x = sp.Matrix(list(states))
    state_set = set(states)
    A = field.jacobian(x)
    if any(a.has(time) or (a.free_symbols & state_set) for a in A):
        return None
    rest = sp.expand(field - A * x)
    if any(r.free_symbols & state_set for r in rest):
        return None
    harmonics = {a.args[0] for r in rest for a in r.atoms(sp.sin, sp.cos) if a.has(time)}
    if not harmonics:
        if any(r.has(time) for r in rest):
            return None
        return AffineForm(A, rest.row_join(sp.zeros(len(states), 2)), sp.Integer(0), sp.Integer(0))
    if len(harmonics) > 1:
        return None
    theta = harmonics.pop()
    omega = sp.diff(theta, time)
    if omega.has(time) or omega.free_symbols & state_set or omega == 0:
        return None
    cos_t, sin_t = sp.Dummy("cos_theta"), sp.Dummy("sin_theta")
    replaced = rest.xreplace({sp.cos(theta): cos_t, sp.sin(theta): sin_t})
    if any(r.has(time) for r in replaced):
        return None
    columns = []
    for r in replaced:
        c = sp.diff(r, cos_t)
        d = sp.diff(r, sin_t)
        if (c.free_symbols | d.free_symbols) & {cos_t, sin_t}:
            return None
        columns.append([sp.expand(r - c * cos_t - d * sin_t), c, d])
    B = sp.Matrix(columns)
    if any(b.free_symbols & {cos_t, sin_t} for b in B):
        return None
    return AffineForm(A, B, omega, sp.expand(theta - omega * time))
