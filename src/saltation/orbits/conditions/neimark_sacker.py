"""A complex pair of multipliers on the unit circle (Neimark-Sacker), minimally augmented.

:class:`NeimarkSackerCondition`: with ``kappa = cos theta`` an unknown, the matrix ``M^2 - 2 kappa M + I``
is singular with a two-dimensional null space where ``M`` has the multipliers ``exp(+-i theta)`` (the real
invariant plane of the pair).  Bordered by two vectors on each side, the bordered system's ``2 x 2`` block
``G`` vanishes there; two of its four entries are the defining conditions (Govaerts 2000, section 4.4 for
the Hopf analogue ``A^2 + kappa I``; Kuznetsov 2004, section 10.3.2).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from saltation.errors import SaltationError
from saltation.orbits.conditions.base import Condition
from saltation.orbits.conditions.multiplier import (
    _product,
    monodromy_differences,
    segmented_monodromy_differences,
)
from saltation.orbits.conditions.shot import Rows, Segments, Shot

#: The bordered matrix counts as singular above this condition number.
_SINGULAR = 1e13


class NeimarkSackerCondition(Condition):
    """A complex pair of multipliers ``exp(+-i theta)`` on the unit circle, ``kappa = cos theta`` an unknown.

    ``A(kappa) = M^2 - 2 kappa M + I`` (``M`` the monodromy) has rank ``n - 2`` exactly there: on the pair's
    real invariant plane ``M`` acts as a ``2 x 2`` matrix ``S`` with ``S^2 - tr(S) S + det(S) I = 0``, so
    ``A`` restricted to it is ``(tr S - 2 kappa) S + (1 - det S) I``, zero where ``det S = 1`` and
    ``kappa = tr(S) / 2``.  The bordered system ``[[A, B], [C^T, 0]] [V; G] = [0; I_2]`` (``B``, ``C`` of
    shape ``(n, 2)``) gives the ``2 x 2`` block ``G``, which vanishes exactly where ``A`` has that rank.
    ``G`` moves in the two-dimensional span of ``S`` and ``I`` (to first order), so two of its entries are
    the two conditions: those whose derivatives by ``kappa`` and by a scaling of ``M`` (the pair's modulus)
    are the farthest from dependent, chosen with the borders.

    The borders are the null vectors of ``A`` (right, ``C``) and of ``A^T`` (left, ``B``) at the first
    evaluation, and again at every accepted point (:meth:`accept`): the pair's plane turns along a curve.
    The derivative by ``kappa`` is exact, ``dG = -W^T (dA) V`` with ``W`` from the transposed system; those
    by the state, the period and the parameters are central differences over further shots, kept and
    reused as :class:`~saltation.orbits.conditions.MultiplierCondition` does (``reuse``).  The residual is
    always exact.

    A real pair of multipliers ``mu``, ``1 / mu`` (a neutral saddle) satisfies the same equations, with
    ``kappa = (mu + 1 / mu) / 2`` and ``|kappa| > 1``: :meth:`kind` tells them apart.  The trivial multiplier
    1 of an autonomous orbit gives ``2 - 2 kappa`` on its direction, which vanishes only at ``kappa = 1``.

    Parameters
    ----------
    kappa : float
        The guess of ``kappa = cos theta`` (the real part of the pair nearest the unit circle).
    h : float
        Relative step of the central differences.
    reuse : float
        Relative distance within which the kept derivatives are tried again (0: never).

    References
    ----------
    Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM (minimally augmented
    systems with two borders; the Hopf condition ``A^2 + kappa I``).  Kuznetsov (2004), *Elements of
    Applied Bifurcation Theory*, 3rd ed., Springer, section 10.3 (the Neimark-Sacker condition of maps
    ``M^2 - 2 kappa M + I``, the neutral saddle).
    """

    size = 2
    extras = 1
    name = "Neimark-Sacker"

    def __init__(self, kappa: float, *, h: float = 1e-6, reuse: float = 1e-3):
        self.kappa0 = float(kappa)
        self.h = float(h)
        self.reuse = float(reuse)
        self._border: tuple[np.ndarray, np.ndarray] | None = None
        self._entries: tuple[tuple[int, int], tuple[int, int]] | None = None
        self._kept: tuple[np.ndarray, tuple, Rows] | None = None
        self._last: tuple[np.ndarray, float] | None = None

    # -- state along a curve ------------------------------------------------------------
    def start(self) -> np.ndarray:
        """The initial value of ``kappa``.

        Returns
        -------
        ndarray, shape (1,)
            ``[kappa]``.
        """
        return np.array([self.kappa0])

    def state(self) -> dict:
        """What moves along a curve (the borders, the chosen entries, the kept derivatives), for a restart.

        Returns
        -------
        dict
            A copy, for :meth:`restore`.
        """
        return {"_border": self._border, "_entries": self._entries, "_kept": None, "_last": None}

    def restore(self, state: dict) -> None:
        """Restore a :meth:`state`.

        Parameters
        ----------
        state : dict
            What :meth:`state` returned.
        """
        for key, value in state.items():
            setattr(self, key, value)

    @property
    def last(self) -> tuple[np.ndarray, float]:
        """The monodromy and ``kappa`` of the last evaluation (not of the differences' shots).

        Raises
        ------
        SaltationError
            Before any evaluation.
        """
        if self._last is None:
            raise SaltationError("the Neimark-Sacker condition has not been evaluated yet")
        return self._last

    @staticmethod
    def kind(kappa: float) -> str:
        """What a solution with this ``kappa`` is.

        Parameters
        ----------
        kappa : float
            The solved unknown.

        Returns
        -------
        str
            ``"neimark_sacker"`` for ``|kappa| < 1`` (multipliers ``kappa +- i sqrt(1 - kappa^2)``),
            ``"neutral_saddle"`` otherwise (real multipliers ``kappa +- sqrt(kappa^2 - 1)``, product 1).
        """
        return "neimark_sacker" if abs(kappa) < 1.0 else "neutral_saddle"

    # -- the bordered system ------------------------------------------------------------
    @staticmethod
    def matrix(M: np.ndarray, kappa: float) -> np.ndarray:
        """``M^2 - 2 kappa M + I``.

        Parameters
        ----------
        M : ndarray, shape (n, n)
            A monodromy.
        kappa : float
            ``cos theta``.

        Returns
        -------
        ndarray, shape (n, n)
        """
        return M @ M - 2.0 * kappa * M + np.eye(M.shape[0])

    def _bordered(self, A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``G``, ``V`` and ``W`` of the bordered system and its transpose, bordered by the kept vectors."""
        n = A.shape[0]
        if self._border is None:
            U, _, Vt = np.linalg.svd(A)
            self._border = (U[:, -2:].copy(), Vt[-2:].T.copy())
        B, C = self._border
        K = np.zeros((n + 2, n + 2))
        K[:n, :n], K[:n, n:], K[n:, :n] = A, B, C.T
        rhs = np.zeros((n + 2, 2))
        rhs[n:] = np.eye(2)
        if not np.all(np.isfinite(K)) or np.linalg.cond(K) > _SINGULAR:
            raise SaltationError("the bordered matrix of the Neimark-Sacker condition is singular (the pair's "
                                 "plane has turned away from the borders, or two pairs meet)")
        solution = np.linalg.solve(K, rhs)
        adjoint = np.linalg.solve(K.T, rhs)
        return solution[n:], solution[:n], adjoint[:n]

    def _choose_entries(self, M: np.ndarray, kappa: float, V: np.ndarray, W: np.ndarray) -> None:
        """The two entries of ``G`` whose derivatives by ``kappa`` and by the pair's modulus (``M`` scaled)
        are the farthest from dependent."""
        d_kappa = -W.T @ (-2.0 * M) @ V
        d_scale = -W.T @ (2.0 * M @ M - 2.0 * kappa * M) @ V
        best, chosen = -1.0, None
        for a, b in itertools.combinations([(0, 0), (0, 1), (1, 0), (1, 1)], 2):
            det = abs(d_kappa[a] * d_scale[b] - d_kappa[b] * d_scale[a])
            if det > best:
                best, chosen = det, (a, b)
        self._entries = chosen

    def values(self, M: np.ndarray, kappa: float) -> tuple[np.ndarray, np.ndarray]:
        """The two conditions of a monodromy and their exact derivatives by ``kappa``.

        Parameters
        ----------
        M : ndarray, shape (n, n)
            A monodromy.
        kappa : float
            ``cos theta``.

        Returns
        -------
        g : ndarray, shape (2,)
            The chosen entries of ``G``: zero where ``M^2 - 2 kappa M + I`` has rank ``n - 2``.
        dg_dkappa : ndarray, shape (2,)
            Their derivatives by ``kappa``.

        Raises
        ------
        SaltationError
            If the bordered matrix is singular.
        numpy.linalg.LinAlgError
            If the singular value decomposition at the first call does not converge.
        """
        G, V, W = self._bordered(self.matrix(M, kappa))
        if self._entries is None:
            self._choose_entries(M, kappa, V, W)
        dG = 2.0 * W.T @ M @ V  # -W^T (dA / dkappa) V
        (a, b) = self._entries
        return np.array([G[a], G[b]]), np.array([dG[a], dG[b]])

    def _g(self, M: np.ndarray, kappa: float) -> np.ndarray:
        return self.values(M, kappa)[0]

    def reborder(self, M: np.ndarray, kappa: float) -> None:
        """Border again with the null vectors of ``M^2 - 2 kappa M + I`` and its transpose, and choose the
        entries again (the kept derivatives are dropped).

        Parameters
        ----------
        M : ndarray, shape (n, n)
            The monodromy at a solution.
        kappa : float
            Its ``kappa``.

        Raises
        ------
        SaltationError
            If the bordered matrix is singular.
        """
        _, V, W = self._bordered(self.matrix(M, kappa))
        B, C = np.linalg.qr(W)[0], np.linalg.qr(V)[0]
        self._border = (B, C)
        _, V, W = self._bordered(self.matrix(M, kappa))
        self._choose_entries(M, kappa, V, W)
        self._kept = None

    def accept(self, shot: Shot, extra: np.ndarray) -> None:
        """At an accepted point: border again there (:meth:`reborder`), from the last evaluation.

        Parameters
        ----------
        shot : Shot
            The accepted point's shot.
        extra : ndarray, shape (1,)
            ``kappa`` there.
        """
        if self._last is not None:
            try:
                self.reborder(*self._last)
            except SaltationError:
                pass  # the old borders stay; the next evaluation says if they no longer serve

    # -- the rows -----------------------------------------------------------------------
    def _kept_rows(self, point: np.ndarray, params: Sequence[int], value: np.ndarray, n_x: int) -> Rows | None:
        """The derivatives taken last, if they predict the values at ``point`` (``(x, T, p, kappa)``)."""
        kept = self._kept
        if kept is None or self.reuse <= 0 or kept[0].shape != point.shape or kept[1] != tuple(params):
            return None
        z0, _, rows = kept
        step = point - z0
        if np.any(np.abs(step) > self.reuse * (1.0 + np.abs(z0))):
            return None
        predicted = (rows.value + rows.d_x0 @ step[:n_x] + rows.d_period * step[n_x]
                     + rows.d_parameters @ step[n_x + 1:-1][list(params)] + rows.d_extra[:, 0] * step[-1])
        if np.any(np.abs(value - predicted) > np.maximum(0.1 * np.abs(value - rows.value), 1e-12)):
            return None
        return rows

    def _keep(self, point: np.ndarray, params: Sequence[int], rows: Rows) -> None:
        self._kept = (point.copy(), tuple(params), Rows(rows.value.copy(), rows.d_x0.copy(), rows.d_period.copy(),
                                                        rows.d_parameters.copy(), rows.d_extra.copy()))

    def _head(self, M: np.ndarray, kappa: float, n_x: int, k: int) -> Rows:
        """The rows with the values and the exact ``kappa`` column filled (the last evaluation remembered)."""
        out = Rows.zeros(2, n_x, k, 1)
        out.value[:], out.d_extra[:, 0] = self.values(M, kappa)
        self._last = (np.array(M), float(kappa))
        return out

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int]) -> Rows:
        """The two conditions at the shot's monodromy, their derivatives (central differences, or the kept
        ones) and the exact derivative by ``kappa``.

        Parameters
        ----------
        shot : Shot
            The shot of the period, whose :meth:`Shot.monodromy` the differences shoot.
        extra : ndarray, shape (1,)
            ``kappa``.
        params : sequence of int
            The parameter indices of the derivative columns.

        Returns
        -------
        Rows
            Two equations.

        Raises
        ------
        SaltationError
            If a bordered matrix is singular, or a shot of the differences fails (an
            :class:`IntegrationError`).
        """
        kappa = float(extra[0])
        n = len(shot.x0)
        out = self._head(shot.trajectory.monodromy, kappa, n, len(params))
        point = np.concatenate([shot.x0, [shot.period], shot.parameters, [kappa]])
        kept = self._kept_rows(point, params, out.value, n)
        if kept is not None:
            out.d_x0[:], out.d_period[:], out.d_parameters[:] = kept.d_x0, kept.d_period, kept.d_parameters
            return out
        monodromy_differences(shot, lambda M: self._g(M, kappa), self.h, params, out)
        self._keep(point, params, out)
        return out

    def segmented_rows(self, segments: Segments, extra: np.ndarray, params: Sequence[int]
                       ) -> tuple[int | None, Rows]:
        """The conditions at the product of the segments' transfer matrices, and their derivatives by every node.

        As :meth:`MultiplierCondition.segmented_rows`: a node's derivatives rerun its segment only, those by
        the period and the parameters every segment.

        Parameters
        ----------
        segments : Segments
            The period shot in segments.
        extra : ndarray, shape (1,)
            ``kappa``.
        params : sequence of int
            The parameter indices of the derivative columns.

        Returns
        -------
        segment : None
            The derivatives are by every node.
        rows : Rows
            Two equations, ``d_x0`` of shape ``(2, m n)``.

        Raises
        ------
        SaltationError
            If a bordered matrix is singular, or a run of the differences fails (an
            :class:`IntegrationError`).
        """
        kappa = float(extra[0])
        shot, U, segs = segments.whole, segments.nodes, segments.trajectories
        n, m, T, p = len(shot.x0), len(segs), shot.period, shot.parameters
        out = self._head(_product([seg.monodromy for seg in segs]), kappa, m * n, len(params))
        point = np.concatenate([U[: m * n], [T], p, [kappa]])
        kept = self._kept_rows(point, params, out.value, m * n)
        if kept is not None:
            out.d_x0[:], out.d_period[:], out.d_parameters[:] = kept.d_x0, kept.d_period, kept.d_parameters
            return None, out
        segmented_monodromy_differences(segments, lambda M: self._g(M, kappa), self.h, params, out)
        self._keep(point, params, out)
        return None, out


def nearest_pair_kappa(multipliers: np.ndarray) -> float:
    """``kappa = cos theta`` of the complex pair of multipliers nearest the unit circle (a start guess).

    Parameters
    ----------
    multipliers : ndarray
        An orbit's multipliers.

    Returns
    -------
    float
        The real part of that multiplier divided by its modulus.

    Raises
    ------
    SaltationError
        If the multipliers have no complex pair.
    """
    mu = np.asarray(multipliers, dtype=complex)
    pairs = mu[np.abs(mu.imag) > 1e-9 * np.maximum(1.0, np.abs(mu))]
    if pairs.size == 0:
        raise SaltationError(f"no complex pair among the multipliers {np.round(mu, 6).tolist()}: not a "
                             "Neimark-Sacker point")
    best = pairs[np.argmin(np.abs(np.abs(pairs) - 1.0))]
    return float(best.real / abs(best))


__all__ = ["NeimarkSackerCondition", "nearest_pair_kappa"]
