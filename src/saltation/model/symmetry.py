"""A model's symmetry: a linear map of the state with a shift of half a period.

Many piecewise-smooth models map to themselves under ``x -> S x`` together with
``t -> t + T/2``: the trilinear system, relay feedback systems, impacting
systems with two stops.  Their *symmetric* periodic orbits satisfy
``x(t + T/2) = S x(t)`` and are fixed points of the half-period map
``G(x) = S^-1 phi(t0 + T/2; t0, x)``; the monodromy is ``M = DG^2`` (see
:mod:`saltation.orbits.symmetry`).

A :class:`Symmetry` is declared on a :class:`~saltation.model.system.PiecewiseSystem`
(``symmetry=Symmetry([[-1, 0], [0, -1]])``).  :func:`check_symmetry` verifies it
when the model is built: every mode's field, every surface, every transition
and every reset must have a mirror image in the model, checked at random
states, times and the default parameters.  A declared symmetry that the
equations do not have is a :class:`~saltation.errors.ModelError` naming the
part without a mirror.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from saltation.errors import ModelError

#: random states at which the mirror images are compared
_SAMPLES = 7
#: relative agreement of a part with its mirror image at the samples (the expressions are evaluated in
#: double precision; a model that is not symmetric misses by O(1))
_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Symmetry:
    """A symmetry ``x -> S x``, ``t -> t + shift T`` of a model (a Z2 symmetry: ``S^2 = I``, shift 1/2).

    Parameters
    ----------
    matrix : sequence of sequences of float
        The matrix ``S`` (n x n), with ``S @ S = I``.
    shift : float
        The time shift as a fraction of the period: the forcing period of a forced model, the orbit's
        period of an autonomous one.  Only ``0.5`` (half a period) is supported.

    Raises
    ------
    ModelError
        If the matrix is not square and finite, is not an involution, or the shift is not 1/2.

    References
    ----------
    Golubitsky, Stewart and Schaeffer (1988), *Singularities and Groups in Bifurcation Theory*, vol. II,
    Springer (symmetric periodic orbits and their symmetry-breaking bifurcations).
    """

    matrix: Sequence[Sequence[float]]
    shift: float = 0.5
    S: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        try:
            S = np.array(self.matrix, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"a symmetry's matrix must be a square matrix of numbers, got {self.matrix!r}") from None
        if S.ndim != 2 or S.shape[0] != S.shape[1] or not np.all(np.isfinite(S)):
            raise ModelError(f"a symmetry's matrix must be a square, finite matrix, got shape {S.shape}")
        if not np.allclose(S @ S, np.eye(len(S)), rtol=0.0, atol=1e-12):
            raise ModelError("a symmetry's matrix S must be an involution (S @ S = I): a shift of half a period "
                             "applied twice is the identity")
        if float(self.shift) != 0.5:
            raise ModelError(f"a symmetry's time shift must be 0.5 (half a period), got {self.shift!r}; "
                             "other shifts are not supported")
        S.setflags(write=False)
        object.__setattr__(self, "matrix", tuple(tuple(float(v) for v in row) for row in S))
        object.__setattr__(self, "shift", 0.5)
        object.__setattr__(self, "S", S)

    @classmethod
    def of_signs(cls, signs: Sequence[float]) -> Symmetry:
        """The diagonal symmetry ``x_i -> signs[i] x_i`` (``Symmetry.of_signs([-1, -1])`` for ``x -> -x``).

        Parameters
        ----------
        signs : sequence of float
            The diagonal of ``S``: a list of +1 and -1, one per state.

        Returns
        -------
        Symmetry

        Raises
        ------
        ModelError
            If ``signs`` is not a non-empty list of numbers each +1 or -1 (a string, None, a single number, a
            nested list, any other value).
        """
        problem = f"signs must be a list of +1 and -1, one per state, got {signs!r}"
        if isinstance(signs, (str, bytes)) or not isinstance(signs, (Sequence, np.ndarray)):
            raise ModelError(problem)
        try:
            values = np.asarray(signs, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(problem) from None
        if values.ndim != 1 or values.size == 0 or not np.all(np.abs(values) == 1.0):
            raise ModelError(problem)
        return cls(np.diag(values).tolist())


@dataclass(frozen=True)
class SymmetryMap:
    """How a symmetry permutes a model's parts (the result of :func:`check_symmetry`).

    Attributes
    ----------
    modes : tuple of int
        ``modes[i]`` is the mode whose field is the image of mode ``i``'s.
    surfaces : tuple of int
        ``surfaces[j]`` is the surface that is the image of surface ``j``.
    surface_signs : tuple of int
        ``h_{surfaces[j]}(S x, t + T/2) = surface_signs[j] h_j(x, t)``.
    """

    modes: tuple[int, ...]
    surfaces: tuple[int, ...]
    surface_signs: tuple[int, ...]


def _evaluator(system, key: str, exprs: Sequence[sp.Expr], values: np.ndarray):
    """``f(x, t)`` for expressions of the model at the parameter values ``values`` (numpy, vectorised over
    samples).  The lambdified functions are kept on the model (``_symmetry_functions``): a branch checks the
    symmetry again at its own parameters."""
    cache = system.__dict__.setdefault("_symmetry_functions", {})
    fn = cache.get(key)
    if fn is None:
        fn = cache[key] = sp.lambdify([*system.x, system.t, *system.p], [sp.sympify(e) for e in exprs],
                                      modules="numpy")

    def evaluate(X: np.ndarray, t: np.ndarray) -> np.ndarray:
        with np.errstate(all="ignore"):
            out = fn(*X.T, t, *values)
        return np.array([np.broadcast_to(np.asarray(v, dtype=float), t.shape) for v in out]).T  # (samples, k)

    return evaluate


def _guard(system, k: int, values: np.ndarray):
    """``guard(x, t) -> (holds, decisive)`` of transition ``k`` over samples: whether every condition of its
    guard holds, and where that is decided beyond rounding (no condition within ``1e-9`` of its boundary)."""
    conditions = system.guards[k]
    if not conditions:
        return lambda X, t: (np.ones(len(t), dtype=bool), np.ones(len(t), dtype=bool))
    evaluate = _evaluator(system, f"guard {k}", [c.expr for c in conditions], values)

    def truth(X: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        v = evaluate(X, t)  # (samples, conditions)
        holds = np.ones(len(t), dtype=bool)
        for i, c in enumerate(conditions):
            holds &= (v[:, i] > 0.0) if c.strict else (v[:, i] >= 0.0)
        decisive = np.all(np.abs(v) > 1e-9 * (1.0 + np.abs(v)), axis=1) & np.all(np.isfinite(v), axis=1)
        return holds, decisive

    return truth


def _same_guard(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> bool:
    """Two guards hold at the same samples (where both are decided)."""
    decisive = a[1] & b[1]
    return bool(np.array_equal(a[0][decisive], b[0][decisive]))


def _close(a: np.ndarray, b: np.ndarray) -> bool:
    ok = np.isfinite(a) & np.isfinite(b)
    if not ok.any():
        return False
    scale = 1.0 + np.maximum(np.abs(a[ok]), np.abs(b[ok]))
    return bool(np.all(np.abs(a[ok] - b[ok]) <= _TOLERANCE * scale))


def check_symmetry(system, symmetry: Symmetry, parameters: np.ndarray | None = None) -> SymmetryMap:
    """Verify that a model has the symmetry it declares, and find how its parts map.

    The model is equivariant if, with ``y = S x`` and ``s = t + T/2``, for every mode ``m`` there is a
    mode ``m'`` with ``f_m'(s, y) = S f_m(t, x)``; for every surface ``j`` a surface ``j'`` with
    ``h_j'(s, y) = +-h_j(t, x)``; and for every transition a transition between the image modes, on the
    image surface, in the same direction of crossing (reversed where the indicator changes sign), whose
    reset satisfies ``g'(s, y) = S g(t, x)`` and whose guard holds at ``(s, y)`` where the transition's
    holds at ``(t, x)``.  Each is compared at random states and times and at the
    model's default parameters.

    Parameters
    ----------
    system : PiecewiseSystem
        The model.
    symmetry : Symmetry
        Its declared symmetry.
    parameters : ndarray, optional
        The parameter values to check at (the model's defaults otherwise): a symmetry may hold only at
        some values (a bias parameter at 0, say).

    Returns
    -------
    SymmetryMap
        The images of the modes and surfaces.

    Raises
    ------
    ModelError
        If the matrix does not fit the state, or a mode, surface or transition has no mirror image
        (the message names it).
    """
    n = system.n
    S = symmetry.S
    if S.shape != (n, n):
        raise ModelError(f"model {system.name!r}: the symmetry's matrix is {S.shape[0]} x {S.shape[1]}, "
                         f"the model has {n} states")
    rng = np.random.default_rng(20021125)
    X = rng.normal(scale=2.0, size=(_SAMPLES, n))
    values = (np.array([system.defaults[name] for name in system.parameter_names]) if parameters is None
              else np.asarray(parameters, dtype=float))
    if system.period_expr is None:
        half = 0.0
    else:
        half = 0.5 * float(system.period_expr.xreplace(dict(zip(system.p, map(float, values)))))
    t = rng.uniform(0.0, 7.0, size=_SAMPLES)
    Y, s = X @ S.T, t + half

    fields = [_evaluator(system, f"field {i}", list(f), values) for i, f in enumerate(system.fields)]
    here = [f(X, t) @ S.T for f in fields]  # S f_m(t, x)
    there = [f(Y, s) for f in fields]  # f_m'(s, S x)
    modes = []
    for i, name in enumerate(system.mode_names):
        image = next((k for k in range(len(fields)) if _close(there[k], here[i])), None)
        if image is None:
            raise ModelError(f"model {system.name!r} does not have its declared symmetry: no mode's field is the "
                             f"mirror image of mode {name!r}'s (f'(t + T/2, S x) = S f(t, x) fails for every mode)")
        modes.append(image)

    h = _evaluator(system, "indicators", list(system.indicators), values)
    h_here, h_there = h(X, t), h(Y, s)
    surfaces, signs = [], []
    for j, name in enumerate(system.surface_names):
        found = None
        for k in range(len(system.surface_names)):
            for sign in (1, -1):
                if _close(h_there[:, k], sign * h_here[:, j]):
                    found = (k, sign)
                    break
            if found:
                break
        if found is None:
            raise ModelError(f"model {system.name!r} does not have its declared symmetry: no surface is the mirror "
                             f"image of surface {name!r} (h'(t + T/2, S x) = +-h(t, x) fails for every surface)")
        surfaces.append(found[0])
        signs.append(found[1])

    index = {name: i for i, name in enumerate(system.mode_names)}
    surface_index = {name: j for j, name in enumerate(system.surface_names)}
    resets = [None if g is None else _evaluator(system, f"reset {k}", list(g), values)
              for k, g in enumerate(system.resets)]
    guards = [_guard(system, k, values) for k in range(len(system.transitions))]
    for k, tr in enumerate(system.transitions):
        j = surface_index[tr.surface]
        want = (modes[index[tr.source]], surfaces[j], int(tr.direction) * signs[j], modes[index[tr.target]])
        mirror = None
        for k2, tr2 in enumerate(system.transitions):
            got = (index[tr2.source], surface_index[tr2.surface], int(tr2.direction), index[tr2.target])
            if got != want:
                continue
            same_reset = (resets[k] is None and resets[k2] is None) or (
                resets[k] is not None and resets[k2] is not None
                and _close(resets[k2](Y, s), resets[k](X, t) @ S.T)
            )
            if same_reset and _same_guard(guards[k](X, t), guards[k2](Y, s)):
                mirror = k2
                break
        if mirror is None:
            raise ModelError(f"model {system.name!r} does not have its declared symmetry: transition {k} "
                             f"({tr.label}) has no mirror image (a transition from mode "
                             f"{system.mode_names[want[0]]!r} on surface {system.surface_names[want[1]]!r} to mode "
                             f"{system.mode_names[want[3]]!r} with the mirrored direction, reset and guard)")
    return SymmetryMap(tuple(modes), tuple(surfaces), tuple(signs))


__all__ = ["Symmetry", "SymmetryMap", "check_symmetry"]
