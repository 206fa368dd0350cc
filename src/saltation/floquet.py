"""Floquet multipliers, from the monodromy matrix, and set-valued multipliers at non-smooth points."""

from __future__ import annotations

import cmath
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
    """
    mu = eigenvalues(monodromy)
    if backward:
        mu = reciprocal(mu)
    return sort_multipliers(mu)


def eigenvalues(matrix: np.ndarray) -> np.ndarray:
    """Eigenvalues of a real square matrix, complex.

    LAPACK's ``dgeev`` (what :func:`numpy.linalg.eigvals` calls) through
    :mod:`scipy.linalg.lapack`, without numpy's per-call dispatch, which costs
    several times the work for the small matrices of a monodromy.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the matrix is not finite or the QR algorithm does not converge.
    """
    a = np.asarray(matrix, dtype=float)
    if not np.isfinite(a).all():
        raise np.linalg.LinAlgError("matrix contains infs or NaNs: no eigenvalues")
    wr, wi, _, _, info = lapack.dgeev(a, compute_vl=0, compute_vr=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"eigenvalues did not converge (LAPACK dgeev info = {info})")
    mu = np.empty(wr.shape, dtype=complex)
    mu.real = wr
    mu.imag = wi
    return mu


def reciprocal(mu: np.ndarray, *, zero: float = 1e-13) -> np.ndarray:
    """``1 / mu`` with multipliers below ``zero`` in magnitude mapped to infinity."""
    out = np.empty_like(mu, dtype=complex)
    for i, m in enumerate(mu):
        out[i] = complex(np.inf, 0.0) if abs(m) <= zero else 1.0 / m
    return out


def sort_multipliers(mu: np.ndarray) -> np.ndarray:
    """Sort by decreasing magnitude, then by argument (deterministic order)."""
    values = np.asarray(mu, dtype=complex).tolist()  # a plain sort: numpy's lexsort costs more for a few values
    return np.array(sorted(values, key=lambda z: (-abs(z), -cmath.phase(z))), dtype=complex)


def trivial_multiplier_error(mu: np.ndarray) -> float:
    """Distance from 1 of the multiplier closest to 1 (the trivial one of an autonomous orbit)."""
    finite = mu[np.isfinite(mu)]
    return float(np.min(np.abs(finite - 1.0))) if finite.size else np.inf


def is_stable(mu: np.ndarray, *, autonomous: bool, tol: float = 1e-6) -> bool:
    """All multipliers inside the unit circle (the trivial one excepted for autonomous orbits)."""
    mu = np.asarray(mu, dtype=complex)
    keep = np.abs(mu) < 1.0 + tol
    if autonomous and mu.size:
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
    """
    q = np.linspace(0.0, 1.0, num)
    n = m_minus.shape[0]
    hull = (1.0 - q)[:, None, None] * m_minus + q[:, None, None] * m_plus
    eigenvalues = np.linalg.eigvals(hull).astype(complex)  # one stacked call
    paths = np.empty((num, n), dtype=complex)
    prev = None
    for k in range(num):
        mu = sort_multipliers(eigenvalues[k]) if prev is None else _match(prev, eigenvalues[k])
        paths[k] = mu
        prev = mu
    if backward:
        paths = np.array([reciprocal(row) for row in paths])
    return SetValuedMultipliers(q=q, paths=paths)


def _match(prev: np.ndarray, new: np.ndarray) -> np.ndarray:
    """Reorder ``new`` to follow ``prev`` (greedy nearest neighbour)."""
    out = np.empty_like(prev)
    left = list(range(len(new)))
    for i, m in enumerate(prev):
        j = min(left, key=lambda jj: abs(new[jj] - m))
        out[i] = new[j]
        left.remove(j)
    return out
