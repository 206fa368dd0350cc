"""Floquet multipliers, from the monodromy matrix, and set-valued multipliers at non-smooth points."""

from __future__ import annotations

import cmath
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg import lapack


def multipliers_from_monodromy(monodromy: np.ndarray, *, backward: bool = False) -> np.ndarray:
    """Forward-time Floquet multipliers, sorted by decreasing magnitude.

    Parameters
    ----------
    monodromy : ndarray, shape (n, n)
        Fundamental solution matrix over one period in the direction of integration.
    backward : bool
        Whether the monodromy was computed in backward time; the forward
        multipliers are then the reciprocals of its eigenvalues, and a zero
        backward multiplier becomes an infinite forward one (an infinitely
        unstable orbit).

    Returns
    -------
    ndarray, complex, shape (n,)
        The multipliers, sorted as :func:`sort_multipliers`.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the monodromy is not finite, or its eigenvalues do not converge.
    """
    mu = eigenvalues(monodromy)
    if backward:
        mu = reciprocal(mu)
    return sort_multipliers(mu)


@dataclass(frozen=True)
class AutonomousMultipliers:
    """Floquet multipliers of an autonomous orbit, the trivial direction deflated.

    Attributes
    ----------
    multipliers : ndarray, complex
        Forward-time multipliers, sorted as :func:`sort_multipliers`: the
        trivial one (``n.T M n`` along the unit velocity ``n``) and the
        eigenvalues of the return map's derivative on the section normal to the flow.
    trivial_error : float
        ``|M n - n|``: how far the monodromy is from mapping the flow direction
        to itself (0 for an exact monodromy of a closed orbit).  It bounds the
        trivial multiplier's distance from 1 and is the accuracy figure of the
        monodromy matrix.
    """

    multipliers: np.ndarray
    trivial_error: float


def autonomous_multipliers(monodromy: np.ndarray, velocity: np.ndarray, *, backward: bool = False) -> AutonomousMultipliers:
    """Multipliers of an autonomous orbit with the trivial direction deflated.

    The monodromy ``M`` of a closed orbit maps the velocity ``f(x0)`` to itself.
    In an orthonormal basis ``[n, Q]`` with ``n = f / |f|``, ``Q.T M Q`` is the
    derivative of the return map on the section through ``x0`` normal to the
    flow (the projection along ``f`` of ``M`` onto that section), whose
    eigenvalues are the nontrivial multipliers; the trivial one is
    ``n.T M n``.  A fold of a two-state orbit then reports ``1`` and ``1``
    (not the pair ``1 +- i sqrt(err)`` that the double eigenvalue of the full
    matrix gives under rounding).

    Parameters
    ----------
    monodromy : ndarray, shape (n, n)
        In the direction of integration.
    velocity : ndarray, shape (n,)
        The vector field at the orbit's state (the sliding field on a sliding motion).
    backward : bool
        Reciprocal multipliers (see :func:`multipliers_from_monodromy`); a backward
        multiplier not above ``max(1e-13, trivial_error)`` in magnitude, zero to the
        monodromy's accuracy, becomes an infinite forward one.

    Returns
    -------
    AutonomousMultipliers
        The forward-time multipliers (sorted as :func:`sort_multipliers`) and ``|M n - n|``.

    Raises
    ------
    ValueError
        If the velocity is zero or not finite (a stationary state has no flow direction).
    numpy.linalg.LinAlgError
        If the monodromy is not finite, or the eigenvalues do not converge.
    """
    M = np.asarray(monodromy, dtype=float)
    f = np.asarray(velocity, dtype=float)
    if f.shape == (2,) and M.shape == (2, 2):
        return _autonomous_multipliers_2(M, f, backward)
    norm = float(np.linalg.norm(f))
    if not norm > 0.0 or not math.isfinite(norm):
        raise ValueError("the velocity is zero or not finite: no flow direction to deflate")
    n_dir = f / norm
    # Householder reflection: an orthonormal basis whose first vector is n_dir
    v = n_dir.copy()
    v[0] += math.copysign(1.0, v[0] if v[0] != 0.0 else 1.0)
    H = np.eye(len(f)) - 2.0 * np.outer(v, v) / float(v @ v)
    Q = H[:, 1:]
    Mn = M @ n_dir
    trivial = float(n_dir @ Mn)
    error = float(np.linalg.norm(Mn - n_dir))
    mu = np.append(complex(trivial), eigenvalues(Q.T @ M @ Q)) if len(f) > 1 else np.array([complex(trivial)])
    if backward:  # a backward multiplier within the monodromy's accuracy of zero is an infinite forward one
        mu = reciprocal(mu, zero=max(1e-13, error))
    return AutonomousMultipliers(sort_multipliers(mu), error)


def _autonomous_multipliers_2(M: np.ndarray, f: np.ndarray, backward: bool) -> AutonomousMultipliers:
    """:func:`autonomous_multipliers` of a two-state orbit, in plain floats (it runs at every branch point
    of a planar model, where numpy's per-call cost is most of the work): with ``n = f / |f|`` and the
    unit normal ``q = (-n_1, n_0)``, the multipliers are ``n.T M n`` and the 1 x 1 deflated ``q.T M q``."""
    (m00, m01), (m10, m11) = M.tolist()
    f0, f1 = f.tolist()
    norm = math.hypot(f0, f1)
    if not norm > 0.0 or not math.isfinite(norm):
        raise ValueError("the velocity is zero or not finite: no flow direction to deflate")
    if not all(map(math.isfinite, (m00, m01, m10, m11))):
        raise np.linalg.LinAlgError("matrix contains infs or NaNs: no eigenvalues")
    n0, n1 = f0 / norm, f1 / norm
    mn0, mn1 = m00 * n0 + m01 * n1, m10 * n0 + m11 * n1
    trivial = n0 * mn0 + n1 * mn1
    error = math.hypot(mn0 - n0, mn1 - n1)
    q0, q1 = -n1, n0
    other = q0 * (m00 * q0 + m01 * q1) + q1 * (m10 * q0 + m11 * q1)
    mu = np.array([trivial, other], dtype=complex)
    if backward:
        mu = reciprocal(mu, zero=max(1e-13, error))
    return AutonomousMultipliers(sort_multipliers(mu), error)


def eigenvalues(matrix: np.ndarray) -> np.ndarray:
    """Eigenvalues of a real square matrix, complex.

    LAPACK's ``dgeev`` (what :func:`numpy.linalg.eigvals` calls) through
    :mod:`scipy.linalg.lapack`, without numpy's per-call dispatch, which costs
    several times the work for the small matrices of a monodromy.

    Parameters
    ----------
    matrix : array_like, shape (n, n)
        A real matrix.

    Returns
    -------
    ndarray, complex, shape (n,)
        Its eigenvalues, in LAPACK's order (complex pairs adjacent).

    Raises
    ------
    numpy.linalg.LinAlgError
        If the matrix is not finite or the QR algorithm does not converge.
    """
    a = np.asarray(matrix, dtype=float)
    # a small matrix is checked in plain floats (numpy's reduction costs more than the check)
    if not (all(map(math.isfinite, a.ravel().tolist())) if a.size <= 64 else np.isfinite(a).all()):
        raise np.linalg.LinAlgError("matrix contains infs or NaNs: no eigenvalues")
    wr, wi, _, _, info = lapack.dgeev(a, compute_vl=0, compute_vr=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"eigenvalues did not converge (LAPACK dgeev info = {info})")
    mu = np.empty(wr.shape, dtype=complex)
    mu.real = wr
    mu.imag = wi
    return mu


def reciprocal(mu: np.ndarray, *, zero: float = 1e-13) -> np.ndarray:
    """``1 / mu`` with multipliers below ``zero`` in magnitude mapped to infinity.

    Parameters
    ----------
    mu : ndarray, complex
        Multipliers (backward-time ones, for example).
    zero : float
        Magnitude at or below which a multiplier counts as zero.

    Returns
    -------
    ndarray, complex
        The reciprocals, in the same order; ``inf`` for a zero multiplier.
    """
    out = np.empty_like(mu, dtype=complex)
    for i, m in enumerate(mu):
        out[i] = complex(np.inf, 0.0) if abs(m) <= zero else 1.0 / m
    return out


def sort_multipliers(mu: np.ndarray) -> np.ndarray:
    """Sort by decreasing magnitude, then by argument (deterministic order).

    Parameters
    ----------
    mu : array_like, complex
        Multipliers.

    Returns
    -------
    ndarray, complex
        The same values, sorted.
    """
    values = np.asarray(mu, dtype=complex).tolist()  # a plain sort: numpy's lexsort costs more for a few values
    return np.array(sorted(values, key=lambda z: (-abs(z), -cmath.phase(z))), dtype=complex)


def trivial_multiplier_error(mu: np.ndarray) -> float:
    """Distance from 1 of the multiplier closest to 1 (the trivial one of an autonomous orbit).

    Parameters
    ----------
    mu : ndarray, complex
        Multipliers (infinite ones are ignored).

    Returns
    -------
    float
        ``min |mu - 1|`` over the finite multipliers; ``inf`` if there is none.
    """
    finite = mu[np.isfinite(mu)]
    return float(np.min(np.abs(finite - 1.0))) if finite.size else np.inf


def is_stable(mu: np.ndarray, *, autonomous: bool, tol: float = 1e-6) -> bool:
    """All multipliers inside the unit circle (the trivial one excepted for autonomous orbits).

    Parameters
    ----------
    mu : array_like, complex
        Forward-time multipliers.
    autonomous : bool
        Whether the orbit is autonomous: the multiplier closest to 1 (the trivial one) is then not
        counted.
    tol : float
        A multiplier counts as inside when ``|mu| < 1 + tol``.

    Returns
    -------
    bool
        True for a stable orbit.
    """
    mu = np.asarray(mu, dtype=complex)
    if not autonomous:
        return all(abs(m) < 1.0 + tol for m in mu.tolist())  # plain complex numbers: a few of them
    keep = np.abs(mu) < 1.0 + tol
    if mu.size:
        keep[int(np.argmin(np.where(np.isfinite(mu), np.abs(mu - 1.0), np.inf)))] = True  # the trivial one
    return bool(np.all(keep))


@dataclass(frozen=True)
class SetValuedMultipliers:
    """Eigenvalue paths of ``(1 - q) M- + q M+`` for ``q`` in ``[0, 1]``.

    Attributes
    ----------
    q : ndarray, shape (m,)
    paths : ndarray, shape (m, n), complex
        Multipliers at each ``q`` (continuous paths, matched by proximity).
    """

    q: np.ndarray
    paths: np.ndarray


def set_valued_multipliers(
    m_minus: np.ndarray, m_plus: np.ndarray, *, num: int = 401, backward: bool = False
) -> SetValuedMultipliers:
    """Set-valued Floquet multipliers at a non-smooth point (convex hull of ``M-`` and ``M+``).

    For backward-time monodromies the convex combination is formed in
    backward time and the paths are mapped to forward-time multipliers.

    Parameters
    ----------
    m_minus, m_plus : ndarray, shape (n, n)
        The monodromies on either side of the non-smooth point, in the direction of integration.
    num : int
        Number of values of ``q``, evenly spaced in ``[0, 1]``.
    backward : bool
        Whether the monodromies were computed in backward time (the paths are then the reciprocals
        of the eigenvalues, see :func:`reciprocal`).

    Returns
    -------
    SetValuedMultipliers
        ``q`` and the eigenvalue paths of ``(1 - q) M- + q M+``, each path matched by proximity
        from one ``q`` to the next.

    Raises
    ------
    numpy.linalg.LinAlgError
        If a monodromy is not finite, or the eigenvalues do not converge.

    References
    ----------
    Leine and Van Campen, "Fold bifurcations in discontinuous systems" (set-valued Floquet
    multipliers, the eigenvalues of the convex combination of the monodromies).
    """
    q = np.linspace(0.0, 1.0, num)
    n = m_minus.shape[0]
    hull = (1.0 - q)[:, None, None] * m_minus + q[:, None, None] * m_plus
    eigenvalues = np.linalg.eigvals(hull).astype(complex)  # one stacked call
    if n == 2:
        paths = _match_pairs(eigenvalues, sort_multipliers(eigenvalues[0]))
    else:
        rows = eigenvalues.tolist()  # Python complex numbers: the matching below touches each a few times
        prev = sort_multipliers(eigenvalues[0]).tolist()
        matched = [prev]
        for row in rows[1:]:
            prev = _match_list(prev, row)
            matched.append(prev)
        paths = np.array(matched, dtype=complex).reshape(num, n)
    if backward:
        paths = np.array([reciprocal(row) for row in paths])
    return SetValuedMultipliers(q=q, paths=paths)


def _match_pairs(rows: np.ndarray, first: np.ndarray) -> np.ndarray:
    """:func:`_match_list` down the rows of pairs ``rows`` (shape (m, 2)), the first row ordered as ``first``.

    Row ``k`` keeps its order or is swapped; which depends only on whether row ``k - 1`` was, through two
    comparisons computed for all rows at once (the distances from each of the previous row's two values),
    so only a loop over booleans remains."""
    a, b = rows[:, 0], rows[:, 1]
    keep_after_kept = np.abs(a[1:] - a[:-1]) <= np.abs(b[1:] - a[:-1])  # the previous row's first is a
    keep_after_swapped = np.abs(a[1:] - b[:-1]) <= np.abs(b[1:] - b[:-1])  # ... is b
    swapped = [not (first[0] == a[0] and first[1] == b[0])]
    for kept_k, swapped_k in zip(keep_after_kept.tolist(), keep_after_swapped.tolist()):
        swapped.append(not (swapped_k if swapped[-1] else kept_k))
    return np.where(np.array(swapped)[:, None], rows[:, ::-1], rows)


def _match(prev: np.ndarray, new: np.ndarray) -> np.ndarray:
    """Reorder ``new`` to follow ``prev`` (greedy nearest neighbour)."""
    return np.array(_match_list(np.asarray(prev).tolist(), np.asarray(new).tolist()), dtype=complex)


def _match_list(prev: list[complex], new: list[complex]) -> list[complex]:
    """:func:`_match` on lists of Python complex numbers (each takes the nearest of those left, in order)."""
    if len(prev) == 2:  # the common case, written out (the first of equally near ones is taken, as below)
        a, b = new
        return [a, b] if abs(a - prev[0]) <= abs(b - prev[0]) else [b, a]
    left = list(new)
    out = []
    for m in prev:
        j = min(range(len(left)), key=lambda jj: abs(left[jj] - m))
        out.append(left.pop(j))
    return out


def product_eigenvalues(factors: Sequence[np.ndarray]) -> np.ndarray:
    """Eigenvalues of ``factors[-1] @ ... @ factors[0]``, from the factors (periodic Schur decomposition).

    The product is never formed: SLICOT's MB03VD reduces the factors to periodic Hessenberg form and
    MB03WD computes the periodic real Schur form, so that small eigenvalues of a product with large
    ones keep their accuracy.

    Parameters
    ----------
    factors : sequence of ndarray, shape (n, n)
        The factors in the order they act (the first acts first).

    Returns
    -------
    ndarray, complex, shape (n,)
        The eigenvalues of the product, in the order of the Schur form's diagonal.

    Raises
    ------
    numpy.linalg.LinAlgError
        If a single factor is given (its eigenvalues are then computed directly) and it is not
        finite, or its eigenvalues do not converge.

    References
    ----------
    Bojanczyk, Golub and Van Dooren (1992), "The periodic Schur decomposition: algorithms and
    applications", Proc. SPIE 1770.
    """
    mats = [np.asarray(a, dtype=float) for a in factors]
    n = mats[0].shape[0]
    if n == 0:
        return np.zeros(0, dtype=complex)
    if n == 1:
        return np.array([complex(np.prod([a[0, 0] for a in mats]))])
    if len(mats) == 1:
        return np.linalg.eigvals(mats[0]).astype(complex)
    from slycot import (  # SLICOT: the reduction to periodic Hessenberg form, then the QZ-like sweep
        mb03vd,
        mb03wd,
    )

    p = len(mats)
    # SLICOT's convention is H = H_1 H_2 ... H_p: the factor acting last comes first
    stack = np.asfortranarray(np.stack(mats[::-1], axis=2))
    reduced, _ = mb03vd(n, 1, n, stack)
    h = np.array(reduced, order="F")
    for j in range(p):  # below the Hessenberg (first) and triangular (others) parts lie the reflectors
        h[:, :, j] = np.triu(h[:, :, j], -1 if j == 0 else 0)
    t, _, w = mb03wd("S", "N", n, 1, n, 1, n, h, np.zeros((n, n, p), order="F"))
    w = np.asarray(w, dtype=complex)
    # A 2x2 block of the first factor's quasi-triangular form whose eigenvalues are real (MB03WD leaves
    # such a block unsplit when its iteration stalls) has them from the formed 2x2 product, which loses
    # the small one to eps times the large one.  The small one is taken instead from the determinant,
    # a product of the blocks' determinants (each well computed): det(B) / (the large one).
    k = 0
    while k < n - 1:
        if t[k + 1, k, 0] != 0.0:
            pair = w[k:k + 2]
            if pair[0].imag == 0.0 and pair[1].imag == 0.0:
                det = 1.0
                for j in range(p):
                    block = t[k:k + 2, k:k + 2, j]
                    det *= block[0, 0] * block[1, 1] - block[0, 1] * block[1, 0]
                big = k if abs(pair[0]) >= abs(pair[1]) else k + 1
                if w[big] != 0.0:
                    w[2 * k + 1 - big] = det / w[big].real
            k += 2
        else:  # a 1x1 block: the product of the factors' diagonal entries (MB03WD's own value of it is
            # scaled and loses digits)
            w[k] = np.prod(t[k, k, :])
            k += 1
    if k == n - 1:
        w[k] = np.prod(t[k, k, :])
    return np.asarray(w, dtype=complex)
