"""The set-valued classification of a non-smooth point: pure linear algebra on its one-sided monodromies.

At a point where the orbit's event sequence changes, the monodromies on the two sides, ``M-`` and ``M+``,
give the set-valued Floquet multipliers, the eigenvalues of ``(1 - q) M- + q M+`` for ``q`` in ``[0, 1]``.
Where that set crosses the unit circle the point is a discontinuous fold (through +1), flip (through -1)
or Neimark-Sacker (a complex pair); if it stays on one side it is a jump without crossing
(:func:`classify_nonsmooth`).

The classification reads :class:`~saltation.branches.branch.SpecialPointKind` from the branch records, so it
lives with the special points rather than in :mod:`saltation.orbits.floquet`, below them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from saltation.errors import SaltationError
from saltation.kinds import SpecialPointKind
from saltation.orbits.floquet import eigenvalues, set_valued_multipliers

__all__ = ["SetValuedCrossing", "classify_nonsmooth"]


@dataclass(frozen=True)
class SetValuedCrossing:
    """How the set-valued multipliers of a non-smooth point meet the unit circle.

    Attributes
    ----------
    kind : SpecialPointKind
        ``discontinuous_fold`` (through +1), ``discontinuous_flip`` (through -1),
        ``discontinuous_neimark_sacker`` (a complex pair) or ``nonsmooth_no_crossing``.
    q : float or None
        Where the crossing happens on the convex combination ``(1 - q) M- + q M+`` (None without one).
    point : complex or None
        The forward-time multiplier on the unit circle there (None without a crossing).
    gamma : complex or None
        For a symmetric orbit classified by its half-period map: the half-period multiplier on the
        unit circle (``point = gamma**2``).
    """

    kind: SpecialPointKind
    q: float | None
    point: complex | None
    gamma: complex | None = None


def classify_nonsmooth(
    m_minus: np.ndarray | None,
    m_plus: np.ndarray | None,
    *,
    backward: bool = False,
    autonomous: bool = False,
    mu_minus: np.ndarray | None = None,
    mu_plus: np.ndarray | None = None,
    num: int = 801,
) -> SetValuedCrossing:
    """Classify a non-smooth point from its one-sided monodromies.

    The eigenvalue paths of ``(1 - q) M- + q M+`` are followed for ``q`` in
    ``[0, 1]``.  Where the two sides have as many multipliers outside the unit circle, the first
    non-trivial path whose magnitude passes 1 decides the kind; where they differ, the crossing that takes
    a path out (or in) for good does: the last crossing of a path that ends outside, the first of one that
    starts outside (a path that leaves through +1 and returns before a complex pair leaves does not make
    the jump a fold).  Monodromies computed in backward time are combined in backward
    time (their eigenvalues are reciprocals of the forward multipliers, and
    the unit circle, +1 and -1 are the same).  When one side is infinitely
    unstable (a forward multiplier is infinite; ``M`` is then not available
    in forward time), the jump runs along the real axis from the finite
    multiplier to infinity and crosses at ``q = 0``.

    Parameters
    ----------
    m_minus, m_plus : ndarray, shape (n, n), or None
        The one-sided monodromies, in the direction of integration (None for an infinitely unstable
        side).
    backward : bool
        Whether they were computed in backward time.
    autonomous : bool
        Whether the orbit is autonomous (its trivial path, at 1 throughout, is skipped).
    mu_minus, mu_plus : ndarray, complex, optional
        The one-sided forward multipliers, needed where a monodromy is None.
    num : int
        Number of values of ``q`` on which the paths are followed (each crossing is then refined by
        bisection).

    Returns
    -------
    SetValuedCrossing
        The kind, and where the set crosses the unit circle.

    Raises
    ------
    SaltationError
        If a monodromy is missing and the multipliers do not make up for it (both sides' multipliers
        are needed, and one side must be infinitely unstable).
    numpy.linalg.LinAlgError
        If a monodromy is not finite.

    References
    ----------
    Leine and Van Campen, "Fold bifurcations in discontinuous systems" (set-valued Floquet
    multipliers and discontinuous bifurcations).
    """
    if m_minus is None or m_plus is None:
        fin = mu_minus if m_minus is not None else mu_plus
        inf_side = mu_plus if m_minus is not None else mu_minus
        if fin is None or inf_side is None:
            raise SaltationError("a non-smooth point needs both one-sided monodromies or multipliers")
        if any(np.isinf(np.abs(inf_side))):
            finite_partner = [m for m in fin if abs(m - 1.0) > 1e-6 or not autonomous]
            m = finite_partner[0] if finite_partner else fin[-1]
            if abs(m.imag) < 1e-9 and m.real >= 0:
                return SetValuedCrossing(SpecialPointKind.DISCONTINUOUS_FOLD, 0.0, complex(1.0, 0.0))
            if abs(m.imag) < 1e-9:
                return SetValuedCrossing(SpecialPointKind.DISCONTINUOUS_FLIP, 0.0, complex(-1.0, 0.0))
            return SetValuedCrossing(SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER, 0.0, m / abs(m))
        raise SaltationError("one-sided monodromy missing for a finite jump")
    sv = set_valued_multipliers(m_minus, m_plus, num=num, backward=False)
    paths = sv.paths
    mags = np.abs(paths)
    n = paths.shape[1]
    trivial = -1
    if autonomous:
        dev = np.max(np.abs(paths - 1.0), axis=0)
        trivial = int(np.argmin(dev)) if np.min(dev) < 1e-5 else -1
    # where the number of multipliers outside the unit circle differs between the two sides, the kind is that
    # of the crossing that takes a path out for good: the last crossing of a path outside at q = 1, the
    # first of one outside at q = 0 (a path may leave through +1 and come back before a complex pair leaves
    # for good: the jump is then a discontinuous Neimark-Sacker).  Otherwise the set's first crossing.
    g_all = np.where(np.isfinite(mags), mags - 1.0, 1e300)
    keep = [i for i in range(n) if i != trivial]
    net = bool(keep) and int(np.sum(g_all[0, keep] > 0)) != int(np.sum(g_all[-1, keep] > 0))
    best = None
    for i in keep:
        g = g_all[:, i]
        sign_change = np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) <= 0)[0]
        if sign_change.size == 0:
            continue
        if net:
            if (g[0] > 0) == (g[-1] > 0):
                continue  # out and back (or in and out again): not what changes the count
            k = int(sign_change[-1] if g[-1] > 0 else sign_change[0])
        else:
            k = int(sign_change[0])
        if g[k] == g[k + 1]:
            qc = float(sv.q[k])
        else:
            qc = float(sv.q[k] + (sv.q[k + 1] - sv.q[k]) * g[k] / (g[k] - g[k + 1]))
        qc, point = _refine_crossing(m_minus, m_plus, paths[k, i], qc, float(sv.q[k]), float(sv.q[k + 1]))
        if best is None or qc < best[0]:
            best = (qc, point)
    if best is None:
        return SetValuedCrossing(SpecialPointKind.NONSMOOTH_NO_CROSSING, None, None)
    qc, point = best
    if backward:
        point = 1.0 / point
    if abs(point.imag) > 1e-6:
        kind = SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER
    elif point.real > 0:
        kind = SpecialPointKind.DISCONTINUOUS_FOLD
    else:
        kind = SpecialPointKind.DISCONTINUOUS_FLIP
    return SetValuedCrossing(kind, qc, complex(point))


def _refine_crossing(m_minus, m_plus, guide: complex, q0: float, qa: float, qb: float) -> tuple[float, complex]:
    """Refine the crossing ``|mu(q)| = 1`` of the eigenvalue path near ``guide`` by bisection."""

    def mu_at(q: float, near: complex) -> complex:
        ev = eigenvalues((1.0 - q) * m_minus + q * m_plus)  # (LAPACK's dgeev as numpy's eigvals, without its dispatch)
        return complex(ev[np.argmin(np.abs(ev - near))])

    ma = mu_at(qa, guide)
    ga = abs(ma) - 1.0
    near = ma
    for _ in range(60):
        qm = 0.5 * (qa + qb)
        mm = mu_at(qm, near)
        gm = abs(mm) - 1.0
        if np.sign(gm) == np.sign(ga) and gm != 0.0:
            qa, ga, near = qm, gm, mm
        else:
            qb = qm
            near = mm
        if qb - qa < 1e-13:
            break
    q = 0.5 * (qa + qb)
    return q, mu_at(q, near)
