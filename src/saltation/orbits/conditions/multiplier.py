"""A multiplier at ``+1`` (fold) or ``-1`` (period doubling), minimally augmented.

:class:`MultiplierCondition`: the bordered test function of Govaerts (*Numerical Methods for
Bifurcations of Dynamical Equilibria*, SIAM 2000) vanishes where ``M - mu I`` is singular; its bordered
system is solved by :func:`saltation.orbits.problem.bordered_solve`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from saltation.errors import SaltationError
from saltation.orbits.conditions.base import Condition
from saltation.orbits.conditions.shot import Rows, Segments, Shot
from saltation.orbits.problem import bordered_solve


class MultiplierCondition(Condition):
    """A multiplier at ``mu`` (``+1``: fold, ``-1``: period doubling), minimally augmented.

    ``g`` solves ``[[M - mu I, b], [c^T, 0]] [v; g] = [0; 1]`` with ``b``, ``c`` the singular vectors of
    ``M - mu I`` at the first evaluation (kept): ``g = 0`` exactly where ``M - mu I`` is singular.  Its
    derivatives are central differences over further shots (the second derivatives of the flow are
    not carried by the engine): ``2 (n + 1 + k)`` period maps for ``n`` states, the period and ``k``
    parameters.  They are kept, and used again at a point within ``reuse`` (relative, in each of the
    state, the period and the parameters) of where they were taken, if they predict ``g`` there: the
    linearization from the kept point must agree with the new ``g`` to a tenth of the change of ``g``
    (or 1e-12).  The Newton iterations of one continuation step stay that close to its predicted point,
    so a step mostly takes them once; near a corner, where ``g`` bends sharply, the check fails and they
    are taken again.  The residual, ``g`` itself, is always exact: only the Newton's rate depends on
    them.  ``reuse=0`` takes them at every evaluation.

    Parameters
    ----------
    mu : float
        The multiplier: ``+1`` (fold) or ``-1`` (period doubling).
    h : float
        Relative step of the central differences.
    reuse : float
        Relative distance within which the kept derivatives are tried again (0: never).

    References
    ----------
    Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM (minimally
    augmented systems, the bordered test function).
    """

    name = "multiplier"

    def __init__(self, mu: float, *, h: float = 1e-6, reuse: float = 1e-3):
        self.mu = float(mu)
        self.h = float(h)
        self.reuse = float(reuse)
        self._border: tuple[np.ndarray, np.ndarray] | None = None
        self._kept: tuple[np.ndarray, tuple, Rows] | None = None

    def kept_derivatives(self, point: np.ndarray, params: Sequence[int], value: float, n_x: int) -> Rows | None:
        """The derivatives taken last, if they still serve at ``point``; otherwise None.

        They serve when ``point`` is within ``reuse`` of where they were taken, with the same free
        parameters, and they predict ``g`` there (``value``) to a tenth of its change.

        Parameters
        ----------
        point : ndarray
            ``(x0 or nodes, T, parameters)``.
        params : sequence of int
            The parameter indices of the derivative columns.
        value : float
            ``g`` at ``point``.
        n_x : int
            The number of leading entries of ``point`` that are the state or the nodes.

        Returns
        -------
        Rows or None
            The kept rows, or None.
        """
        kept = self._kept
        if kept is None or self.reuse <= 0 or kept[0].shape != point.shape or kept[1] != tuple(params):
            return None
        z0, _, rows = kept
        step = point - z0
        if np.any(np.abs(step) > self.reuse * (1.0 + np.abs(z0))):
            return None
        predicted = (rows.value[0] + rows.d_x0[0] @ step[:n_x] + rows.d_period[0] * step[n_x]
                     + rows.d_parameters[0] @ step[n_x + 1:][list(params)])
        if abs(value - predicted) > max(0.1 * abs(value - rows.value[0]), 1e-12):
            return None
        return rows

    def keep_derivatives(self, point: np.ndarray, params: Sequence[int], rows: Rows) -> None:
        """Keep derivatives for :meth:`kept_derivatives` (copies).

        Parameters
        ----------
        point : ndarray
            ``(x0 or nodes, T, parameters)`` where they were taken.
        params : sequence of int
            The parameter indices of the derivative columns.
        rows : Rows
            The derivatives.
        """
        self._kept = (point.copy(), tuple(params), Rows(rows.value.copy(), rows.d_x0.copy(), rows.d_period.copy(),
                                                        rows.d_parameters.copy(), rows.d_extra.copy()))

    def g(self, M: np.ndarray) -> float:
        """The bordered test function ``g`` of a monodromy.

        The bordering vectors are the singular vectors of ``M - mu I`` at the first call, kept after.

        Parameters
        ----------
        M : ndarray, shape (n, n)
            A monodromy.

        Returns
        -------
        float
            ``g``, zero exactly where ``M - mu I`` is singular.

        Raises
        ------
        SaltationError
            If the bordered matrix is singular.
        numpy.linalg.LinAlgError
            If the singular value decomposition at the first call does not converge.
        """
        n = M.shape[0]
        A = M - self.mu * np.eye(n)
        if self._border is None:
            U, _, Vt = np.linalg.svd(A)
            self._border = (U[:, -1].copy(), Vt[-1].copy())
        b, c = self._border
        rhs = np.zeros(n + 1)
        rhs[n] = 1.0
        solution = bordered_solve(A, b, c, 0.0, rhs)
        if solution is None:
            raise SaltationError(f"the bordered matrix of the multiplier {self.mu:+g} test is singular")
        return float(solution[n])

    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int]) -> Rows:
        """``g`` of the shot's monodromy and its derivatives (central differences, or the kept ones).

        Parameters
        ----------
        shot : Shot
            The shot of the period, whose :meth:`Shot.monodromy` the differences shoot.
        extra : ndarray, shape (0,)
            No unknowns of its own.
        params : sequence of int
            The parameter indices of the derivative columns.

        Returns
        -------
        Rows
            One equation.

        Raises
        ------
        SaltationError
            If a bordered matrix is singular, or a shot of the differences fails (an
            :class:`IntegrationError`).
        """
        n = len(shot.x0)
        out = Rows.zeros(1, n, len(params), 0)
        out.value[0] = self.g(shot.trajectory.monodromy)
        point = np.concatenate([shot.x0, [shot.period], shot.parameters])
        kept = self.kept_derivatives(point, params, out.value[0], n)
        if kept is not None:
            out.d_x0[:], out.d_period[:], out.d_parameters[:] = kept.d_x0, kept.d_period, kept.d_parameters
            return out
        monodromy_differences(shot, lambda M: [self.g(M)], self.h, params, out)
        self.keep_derivatives(point, params, out)
        return out

    def segmented_rows(self, segments: Segments, extra: np.ndarray, params: Sequence[int]
                       ) -> tuple[int | None, Rows]:
        """``g`` of the product of the segments' transfer matrices, and its derivatives by every node.

        The derivatives by a node rerun its segment only (one run per entry); those by the period and
        the parameters rerun every segment; all are central differences, or the kept ones.

        Parameters
        ----------
        segments : Segments
            The period shot in segments.
        extra : ndarray, shape (0,)
            No unknowns of its own.
        params : sequence of int
            The parameter indices of the derivative columns.

        Returns
        -------
        segment : None
            The derivatives are by every node.
        rows : Rows
            One equation, ``d_x0`` of shape ``(1, m n)``.

        Raises
        ------
        SaltationError
            If a bordered matrix is singular, or a run of the differences fails (an
            :class:`IntegrationError`).
        """
        shot, U, segs = segments.whole, segments.nodes, segments.trajectories
        n, m, T, p = len(shot.x0), len(segs), shot.period, shot.parameters
        out = Rows.zeros(1, m * n, len(params), 0)
        out.value[0] = self.g(_product([seg.monodromy for seg in segs]))
        point = np.concatenate([U[: m * n], [T], p])
        kept = self.kept_derivatives(point, params, out.value[0], m * n)
        if kept is not None:
            out.d_x0[:], out.d_period[:], out.d_parameters[:] = kept.d_x0, kept.d_period, kept.d_parameters
            return None, out
        segmented_monodromy_differences(segments, lambda M: [self.g(M)], self.h, params, out)
        self.keep_derivatives(point, params, out)
        return None, out


def monodromy_differences(shot: Shot, g: Callable[[np.ndarray], Sequence[float]], h: float, params: Sequence[int],
                          out: Rows) -> None:
    """Central differences of ``g(M)`` (``M`` the shot's monodromy) by the state, the period (autonomous) and
    the parameters ``params``, written into ``out``'s derivative rows.

    Parameters
    ----------
    shot : Shot
        The shot of the period; :meth:`Shot.monodromy` shoots the differences.
    g : callable
        ``M -> values``, one per row of ``out``.
    h : float
        Relative step.
    params : sequence of int
        The parameter indices of the derivative columns.
    out : Rows
        Its ``d_x0``, ``d_period`` and ``d_parameters`` are filled.

    Raises
    ------
    SaltationError
        If a shot of the differences fails (an :class:`IntegrationError`), or as ``g``.
    """
    n = len(shot.x0)
    G = lambda x, T, q: np.asarray(g(shot.monodromy(x, T, q)), dtype=float)  # noqa: E731
    for i in range(n):
        d = h * max(1.0, abs(shot.x0[i]))
        e = np.zeros(n)
        e[i] = d
        out.d_x0[:, i] = (G(shot.x0 + e, shot.period, shot.parameters) - G(shot.x0 - e, shot.period, shot.parameters)) / (2 * d)
    if shot.autonomous:
        d = h * max(1.0, shot.period)
        out.d_period[:] = (G(shot.x0, shot.period + d, shot.parameters) - G(shot.x0, shot.period - d, shot.parameters)) / (2 * d)
    for c, j in enumerate(params):
        d = h * max(1.0, abs(shot.parameters[j]))
        q = shot.parameters.copy()
        q[j] += d
        up = G(shot.x0, shot.period_at(q), q)
        q[j] -= 2 * d
        out.d_parameters[:, c] = (up - G(shot.x0, shot.period_at(q), q)) / (2 * d)


def segmented_monodromy_differences(segments: Segments, g: Callable[[np.ndarray], Sequence[float]], h: float,
                                    params: Sequence[int], out: Rows) -> None:
    """:func:`monodromy_differences` for a period shot in segments: a node's differences rerun its segment
    only, those by the period and the parameters every segment.

    Parameters
    ----------
    segments : Segments
        The period shot in segments.
    g : callable
        ``M -> values``, one per row of ``out`` (``M`` the product of the segments' transfer matrices).
    h : float
        Relative step.
    params : sequence of int
        The parameter indices of the derivative columns.
    out : Rows
        Its ``d_x0`` (by every node), ``d_period`` and ``d_parameters`` are filled.

    Raises
    ------
    SaltationError
        If a run of the differences fails (an :class:`IntegrationError`), or as ``g``.
    """
    shot, U, times, segs = segments.whole, segments.nodes, segments.times, segments.trajectories
    n, m, T, p = len(shot.x0), len(segs), shot.period, shot.parameters
    factors = [seg.monodromy for seg in segs]
    G = lambda M: np.asarray(g(M), dtype=float)  # noqa: E731

    def whole(TT: float, q: np.ndarray) -> np.ndarray:
        ts = shot.t0 + shot.sign * TT * np.arange(m + 1) / m
        return _product([segments.transfer(i, U[i * n:(i + 1) * n], ts[i], ts[i + 1], q) for i in range(m)])

    for i in range(m):
        x = U[i * n:(i + 1) * n]
        for a in range(n):
            d = h * max(1.0, abs(x[a]))
            e = np.zeros(n)
            e[a] = d
            up, down = list(factors), list(factors)
            up[i] = segments.transfer(i, x + e, times[i], times[i + 1], p)
            down[i] = segments.transfer(i, x - e, times[i], times[i + 1], p)
            out.d_x0[:, i * n + a] = (G(_product(up)) - G(_product(down))) / (2 * d)
    if shot.autonomous:
        d = h * max(1.0, T)
        out.d_period[:] = (G(whole(T + d, p)) - G(whole(T - d, p))) / (2 * d)
    for c, j in enumerate(params):
        d = h * max(1.0, abs(p[j]))
        q = p.copy()
        q[j] += d
        up = G(whole(shot.period_at(q), q))
        q[j] -= 2 * d
        out.d_parameters[:, c] = (up - G(whole(shot.period_at(q), q))) / (2 * d)


def _product(factors: Sequence[np.ndarray]) -> np.ndarray:
    """The product of consecutive transfer matrices, the last one leftmost."""
    M = factors[0]
    for F in factors[1:]:
        M = F @ M
    return M


__all__ = ["MultiplierCondition", "monodromy_differences", "segmented_monodromy_differences"]
