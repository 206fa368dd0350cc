"""A clocked model whose period map is a normal form, and its codimension-two points in closed form (sympy).

The model (built in ``tests/special_points/test_codimension_two_closed_forms.py`` from :func:`reset_expressions`):
states ``u = (u1, u2, u3)``, forced with period 1, turning about the ``u3`` axis once a period (``u1' = -2 pi u2``,
``u2' = 2 pi u1``, ``u3' = 0``: the flow over half a period is the half turn ``R = diag(-1, -1, 1)``, over the
period the identity), and kicked once a period, at ``t = 1/2`` (the clock ``-sin(2 pi t)`` rising), by the reset
``u -> C + P G(P^-1 (u - C))``.  ``P`` (:data:`MIX`) and ``C`` (:data:`CENTRE`) are a fixed invertible mixing and
shift, so no state of the user's coordinates is decoupled; ``G`` is the normal form, in the coordinates ``v = (x,
y1, y2)``, ``z = y1 + i y2``:

* ``sel = 1``: ``x -> x + a - x^2 + k |z|^2`` (a fold of the fixed points ``x* = +-sqrt(a)`` at ``a = 0``);
* ``sel = 0``: ``x -> -(1 + a) x + s x^2 + e x^3 + k |z|^2`` (the fixed point ``x* = 0`` flips at ``a = 0``);
* both: ``z -> e^{i theta} z (1 + b + m x + (c + i w) |z|^2)`` (a Neimark-Sacker pair where
  ``|1 + b + m x*| = 1``),

with the unfolding ``a = alpha + beta/2 - 1/4``, ``b = beta - 2 alpha/5 - 1/10``, ``c = alpha - 1/10``, ``e = beta -
1/2`` in the model's parameters ``(alpha, beta)``, and ``k = 1/2``, ``m = -1``, ``s = 1/2``, ``w = 3/10``, ``cos theta
= 3/5``, ``sin theta = 4/5`` (``theta = 0.927``: no strong resonance, ``kappa = 3/5`` everywhere).

The period map from ``t = 0`` is ``u -> R (C + P G(P^-1 (R u - C)))``: ``G`` conjugated by the affine map ``u = R (C
+ P v)``.  So its fixed points are ``R (C + P v*)``, ``v*`` those of ``G``, and its multipliers the eigenvalues of
``G``'s Jacobian ``J`` (the monodromy is ``R P J P^-1 R``).  In ``G``'s own coordinates everything is read off:

* the Jacobian at ``v* = (x*, 0, 0)`` is block diagonal, ``lambda_x`` (``1 - 2 x*`` or ``-(1 + a)``) and ``(1 + b +
  m x*)`` times the rotation by ``theta``;
* on a period-doubling curve (``sel = 0``, ``a = 0``) the line ``z = 0`` is invariant: the map on its centre manifold
  is ``f(x) = -x + s x^2 + e x^3``, whose second iterate is ``x - 2 (e + s^2) x^3 + O(x^4)`` (sympy's series, below),
  the second iterate of ``xi -> -xi + b xi^3``, and that cubic coefficient is not changed by the near-identity changes
  of coordinates that remove the quadratic term: the flip coefficient is ``b = e + s^2``;
* on a Neimark-Sacker curve the map commutes with the rotations of ``z``, so its centre manifold is ``x = x* + H |z|^2
  + O(|z|^4)``; invariance at second order (along ``y = (rho, 0)``, sympy's series) gives ``H = k / (1 - lambda_x)``,
  and then ``|z'|^2 / |z|^2 = 1 + 2 (c + m H) |z|^2 + O(|z|^4)``: the first Lyapunov coefficient is ``d = c + m H``
  (in ``w -> e^{i theta} w (1 + d |w|^2)``, with ``|w| = |z|``).

The library states each coefficient for a critical eigenvector of unit length in the user's coordinates
(:mod:`saltation.orbits.criticality`).  ``u - u* = R P (v - v*)``, ``R`` orthogonal: for the flip ``q`` is ``R P e_x``
normalised, so ``xi_user = |P e_x| xi`` and ``b_user = b / |P e_x|^2``; for the pair, ``y = w q_y + conj`` with
``q_y = (1, -i) / sqrt(2)`` (the eigenvector of ``e^{i theta}``) has ``|z|^2 = 2 |w|^2``, and ``|P (0, q_y)|^2 = (|P
e_2|^2 + |P e_3|^2) / 2``, so ``d_user = 4 d / (|P e_2|^2 + |P e_3|^2)``.

numpy and sympy only.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

Q = sp.Rational
#: the mixing ``u - C = P v`` and the shift ``C``
MIX = sp.Matrix([[1, Q(1, 2), 0], [Q(1, 5), 1, Q(2, 5)], [Q(-3, 10), Q(1, 4), 1]])
CENTRE = sp.Matrix([Q(3, 10), Q(-1, 5), Q(1, 2)])
COS, SIN = Q(3, 5), Q(4, 5)
K, M, S, W = Q(1, 2), -1, Q(1, 2), Q(3, 10)
THETA = float(sp.atan2(SIN, COS))
#: the flow over half a period
HALF_TURN = np.diag([-1.0, -1.0, 1.0])
#: ``b_user = FLIP_SCALE * b``, ``d_user = TORUS_SCALE * d`` (the critical eigenvector of unit length in ``u``)
FLIP_SCALE = 1 / (MIX[:, 0].T * MIX[:, 0])[0]
TORUS_SCALE = 4 / ((MIX[:, 1].T * MIX[:, 1])[0] + (MIX[:, 2].T * MIX[:, 2])[0])

alpha, beta = sp.symbols("alpha beta", real=True)
_x, _rho, _H = sp.symbols("x rho H", real=True)
_P = np.array(MIX, dtype=float)
_C = np.array(CENTRE, dtype=float).ravel()


def unfolding(al, be) -> tuple:
    """``(a, b, c, e)`` at the parameters ``(alpha, beta)``."""
    return al + be / 2 - Q(1, 4), be - 2 * al / 5 - Q(1, 10), al - Q(1, 10), be - Q(1, 2)


def normal_form(v, al, be, sel) -> sp.Matrix:
    """``G(v)`` (the module's docstring), in its real form."""
    x, y1, y2 = v
    a, b, c, e = unfolding(al, be)
    r2 = y1**2 + y2**2
    fold = x + a - x**2 + K * r2
    flip = -(1 + a) * x + S * x**2 + e * x**3 + K * r2
    g, twist = 1 + b + M * x + c * r2, W * r2
    p1, p2 = g * y1 - twist * y2, g * y2 + twist * y1
    return sp.Matrix([sel * fold + (1 - sel) * flip, COS * p1 - SIN * p2, SIN * p1 + COS * p2])


def reset_expressions() -> list[str]:
    """The reset ``u -> C + P G(P^-1 (u - C))`` in the states ``u1, u2, u3`` and parameters ``alpha, beta, sel``."""
    u = sp.Matrix(sp.symbols("u1 u2 u3"))
    al, be, sel = sp.symbols("alpha beta sel")
    out = CENTRE + MIX * normal_form(MIX.inv() * (u - CENTRE), al, be, sel)
    return [str(sp.expand(expr)) for expr in out]


# ------------------------------------------------------------------------------------------------
# fixed points, multipliers, states


def fixed_point(al: float, be: float, sel: int, sign: int = 1) -> np.ndarray:
    """``v* = (x*, 0, 0)``: ``x* = sign sqrt(a)`` (``sel = 1``) or 0."""
    a = float(unfolding(al, be)[0])
    if sel == 0:
        return np.zeros(3)
    assert a >= 0, "no fixed point: beyond the fold"
    return np.array([sign * np.sqrt(a), 0.0, 0.0])


_V = sp.symbols("v1 v2 v3", real=True)
_SEL = sp.Symbol("sel")
_JACOBIAN = sp.lambdify((_V, alpha, beta, _SEL), normal_form(_V, alpha, beta, _SEL).jacobian(_V), "numpy")
_MAP = sp.lambdify((_V, alpha, beta, _SEL), normal_form(_V, alpha, beta, _SEL), "numpy")


def nf_jacobian(al: float, be: float, sel: int, v: np.ndarray) -> np.ndarray:
    """``G``'s Jacobian at ``v``."""
    return np.array(_JACOBIAN(v, al, be, sel), dtype=float)


def nf_residual(al: float, be: float, sel: int, v: np.ndarray) -> float:
    """``|G(v) - v|``: zero at a fixed point."""
    return float(np.max(np.abs(np.array(_MAP(v, al, be, sel), dtype=float).ravel() - v)))


def multipliers(al: float, be: float, sel: int, v: np.ndarray) -> np.ndarray:
    """The orbit's multipliers: ``lambda_x`` and ``(1 + b + m x*) e^{+-i theta}``, in closed form."""
    a, b, _, _ = (float(t) for t in unfolding(al, be))
    lam_x = 1 - 2 * v[0] if sel == 1 else -(1 + a)
    modulus = 1 + b + float(M) * v[0]
    return np.array([lam_x, modulus * np.exp(1j * THETA), modulus * np.exp(-1j * THETA)])


def orbit_state(v: np.ndarray) -> np.ndarray:
    """The orbit's state at ``t = 0`` for ``G``'s fixed point ``v``: ``R (C + P v)``."""
    return HALF_TURN @ (_C + _P @ v)


def monodromy(al: float, be: float, sel: int, v: np.ndarray) -> np.ndarray:
    """``R P J P^-1 R``."""
    return HALF_TURN @ _P @ nf_jacobian(al, be, sel, v) @ np.linalg.inv(_P) @ HALF_TURN


def amplitude(v: np.ndarray) -> float:
    """The orbit's ``max |u1|``: the state turns on the circle of radius ``|(u1, u2)|`` (the kick at ``t = 1/2``
    leaves the fixed point where it is)."""
    u = _C + _P @ v
    return float(np.hypot(u[0], u[1]))


# ------------------------------------------------------------------------------------------------
# the cubic coefficients, by reduction to the centre manifold


def flip_coefficient_nf() -> sp.Expr:
    """``b = e + s^2`` along the period-doubling curve (``sel = 0``, ``a = 0``), a function of ``beta``, from the
    second iterate of the map on the invariant line ``z = 0``: ``f(f(x)) = x - 2 b x^3 + O(x^4)``."""
    on_curve = sp.solve(unfolding(alpha, beta)[0], alpha)[0]
    line = sp.expand(normal_form([_x, 0, 0], on_curve, beta, 0)[0])
    assert line.coeff(_x, 0) == 0 and line.coeff(_x, 1) == -1
    second = sp.expand(line.subs(_x, line))
    assert second.coeff(_x, 1) == 1 and second.coeff(_x, 2) == 0
    return sp.expand(-second.coeff(_x, 3) / 2)


def lyapunov_coefficient_nf(al, be, sel: int, x_star) -> sp.Expr:
    """``d = c + m H`` at a Neimark-Sacker fixed point ``(x*, 0, 0)`` (``mu = |1 + b + m x*| = 1``), by invariance of
    the centre manifold ``x = x* + H rho^2`` at second order along ``y = (rho, 0)`` (``x'`` has the ``rho^2`` term
    ``H |z'|^2 = H mu^2 rho^2``) and the growth ``|z'|^2 = mu^2 rho^2 + 2 mu d rho^4 + O(rho^6)``."""
    image = normal_form([x_star + _H * _rho**2, _rho, 0], al, be, sel)
    modulus2 = sp.expand(image[1] ** 2 + image[2] ** 2)
    mu2 = modulus2.coeff(_rho, 2)
    H = sp.solve(sp.Eq(sp.expand(image[0]).coeff(_rho, 2), _H * mu2), _H)[0]
    growth = sp.expand(modulus2.subs(_H, H)).coeff(_rho, 4)
    return sp.simplify(growth / (2 * sp.sqrt(mu2)))


def flip_coefficient(be: float) -> float:
    """The library's ``b`` (unit eigenvector in ``u``) at the point ``beta`` of the period-doubling curve."""
    return float((FLIP_SCALE * flip_coefficient_nf()).subs(beta, be))


def lyapunov_coefficient(al: float, be: float, sel: int, x_star: float) -> float:
    """The library's ``d`` (unit eigenvector in ``u``) at a point of a Neimark-Sacker curve."""
    return float(TORUS_SCALE * lyapunov_coefficient_nf(sp.Float(al, 30), sp.Float(be, 30), sel, sp.Float(x_star, 30)))


# ------------------------------------------------------------------------------------------------
# the codimension-two points and the curves


def fold_neimark_sacker() -> tuple[float, float]:
    """``a = b = 0`` (with ``x* = 0``): the fold's multiplier 1 and the pair ``e^{+-i theta}`` (also the
    flip-Neimark-Sacker point of ``sel = 0``, whose ``x* = 0`` has ``-(1 + a) = -1``)."""
    a, b, _, _ = unfolding(alpha, beta)
    sol = sp.solve([a, b], [alpha, beta], dict=True)[0]
    return float(sol[alpha]), float(sol[beta])


def generalized_period_doubling() -> tuple[float, float]:
    """``a = 0`` and ``b_flip = 0``."""
    (sol,) = sp.solve([unfolding(alpha, beta)[0], flip_coefficient_nf()], [alpha, beta], dict=True)
    return float(sol[alpha]), float(sol[beta])


def chenciner(bounds: tuple[float, float]) -> tuple[float, float]:
    """``sel = 0``: ``b = 0`` and ``d = 0`` at ``x* = 0``, the root with ``alpha`` within ``bounds``."""
    b = unfolding(alpha, beta)[1]
    d = lyapunov_coefficient_nf(alpha, beta, 0, 0)
    roots = [s for s in sp.solve([b, sp.numer(sp.together(d))], [alpha, beta], dict=True)
             if bounds[0] < float(s[alpha]) < bounds[1]]
    (sol,) = roots
    return float(sol[alpha]), float(sol[beta])


def parameters_of(a, b) -> tuple[float, float]:
    """``(alpha, beta)`` where the unfolding has ``a`` and ``b`` (it is affine and invertible)."""
    aa, bb = unfolding(alpha, beta)[:2]
    sol = sp.solve([aa - a, bb - b], [alpha, beta], dict=True)[0]
    return float(sol[alpha]), float(sol[beta])


def fold_torus_point(t: float) -> tuple[float, float]:
    """``sel = 1``: the Neimark-Sacker curve ``|1 + b + m x*| = 1`` with ``x* = t`` (``a = t^2``, ``b = -m t``)."""
    return parameters_of(t * t, -float(M) * t)
