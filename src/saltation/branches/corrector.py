"""Newton's method on a branch: the corrector shared by continuation and the location of special points.

``r(z) = 0`` with ``z = (u, lam)`` for a problem of the protocol of
:mod:`saltation.orbits.shooting` (``evaluate``, ``describe``, and optionally
``correct``, the compiled iteration), bordered by one linear condition
``normal . (z - z_pred) = 0``: a pseudo-arclength step, or a fixed parameter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Protocol

import numpy as np

from saltation.errors import ConvergenceError
from saltation.orbits.problem import BranchProblem, bordered_solve
from saltation.orbits.records import BranchPoint, Evaluation


class NewtonSettings(Protocol):
    """What the corrector reads of its settings (``ContinuationSettings`` has them)."""

    tol: float
    max_newton: int
    max_correction: float


@dataclass
class Solution:
    """A corrected point ``z = (u, lam)`` with its evaluation and summary.

    Attributes
    ----------
    z : ndarray
        The point, ``(u, lam)``.
    evaluation : Evaluation
        The problem's evaluation there.
    summary : BranchPoint
        The problem's description of it.
    tangent : ndarray or None
        The unit tangent of the branch there, once computed.
    iterations : int
        Newton iterations of the corrector.
    step : float
        The arclength step that led to it.
    tests : dict of str to float
        Test-function values, by the detector.
    """

    z: np.ndarray
    evaluation: Evaluation
    summary: BranchPoint
    tangent: np.ndarray | None = None
    iterations: int = 0
    step: float = 0.0
    tests: dict[str, float] = field(default_factory=dict, repr=False)  # test-function values, by the detector

    @property
    def u(self) -> np.ndarray:
        return self.z[:-1]

    @property
    def lam(self) -> float:
        return float(self.z[-1])


def canonical_events(events: tuple) -> tuple:
    """An event sequence up to cyclic rotation (where an orbit starts is not a change).

    Parameters
    ----------
    events : tuple
        Event labels, or event identities (:func:`saltation.orbits.records.event_ids`).

    Returns
    -------
    tuple
        The least rotation of the sequence: equal for two sequences that differ only by where they
        start.
    """
    if not events:
        return events
    if type(events) is tuple:
        try:
            return _least_rotation(events)
        except TypeError:  # unhashable items
            pass
    return min(events[k:] + events[:k] for k in range(len(events)))


@lru_cache(maxsize=512)
def _least_rotation(events: tuple) -> tuple:
    """The least rotation of a sequence (cached: continuation compares the same few sequences at every
    point)."""
    return min(events[k:] + events[:k] for k in range(len(events)))


def bordered(jac_u: np.ndarray, jac_lam: np.ndarray, row: np.ndarray) -> np.ndarray:
    """The bordered matrix ``[[J_u, J_lam], [row]]`` of the pseudo-arclength system."""
    m = jac_u.shape[0]
    J = np.empty((m + 1, m + 1))
    J[:m, :m] = jac_u
    J[:m, m] = jac_lam
    J[m] = row
    return J


@dataclass
class Corrector:
    """Newton solvers on the branch of one problem (shared by continuation and location).

    Attributes
    ----------
    problem : BranchProblem
        The branch's problem (its ``evaluate``, ``describe`` and ``correct``, the compiled iteration
        where it has one).
    settings : NewtonSettings
        Its ``tol``, ``max_newton`` and ``max_correction`` (:class:`ContinuationSettings` has them).
    """

    problem: BranchProblem
    settings: NewtonSettings

    def solve_bordered(self, z_pred: np.ndarray, normal: np.ndarray) -> Solution:
        """Solve ``r(z) = 0``, ``normal . (z - z_pred) = 0`` by Newton from ``z_pred``.

        The problem's compiled iteration (``correct``) is used where it has one and it runs; otherwise the
        iteration is in Python.  An iteration stops early when a correction exceeds ``max_correction (1
        + |z|)`` or the bordered matrix is singular.

        Parameters
        ----------
        z_pred : ndarray
            The predicted point ``(u, lam)``.
        normal : ndarray
            The bordering row: the tangent at the last point (pseudo-arclength), or ``e_lam`` (a fixed
            parameter).

        Returns
        -------
        Solution
            The corrected point, its evaluation, summary and iteration count.

        Raises
        ------
        ConvergenceError
            If Newton does not converge in ``max_newton`` iterations.
        SaltationError
            Whatever the problem's evaluation or description raises (an :class:`IntegrationError`, a
            :class:`StationaryStateError` ...).
        """
        prob = self.problem
        s = self.settings
        found = prob.correct(z_pred, normal, tol=s.tol, max_newton=s.max_newton, max_correction=s.max_correction)
        if found is not None:  # the problem's compiled iteration ran
            z, ev, it = found
            return Solution(z=z, evaluation=ev, summary=prob.describe(z[:-1], float(z[-1]), ev), iterations=it)
        z = z_pred.copy()
        history = []
        for it in range(s.max_newton + 1):
            ev = prob.evaluate(z[:-1], float(z[-1]))
            rn = float(np.linalg.norm(ev.residual))
            history.append(rn)
            if not np.isfinite(rn):
                break
            if rn <= s.tol * (1.0 + float(np.linalg.norm(z[:-1]))):
                return Solution(z=z, evaluation=ev, summary=prob.describe(z[:-1], float(z[-1]), ev), iterations=it)
            if it == s.max_newton:
                break
            dz = bordered_solve(ev.jac_u, ev.jac_lam, normal[:-1], normal[-1], np.append(ev.residual, normal @ (z - z_pred)))
            if dz is None:
                break  # singular
            if np.linalg.norm(dz) > s.max_correction * (1.0 + np.linalg.norm(z)):
                break  # diverging: let the step control shorten the step
            z = z - dz
        raise ConvergenceError("corrector did not converge", history)

    def solve_fixed(self, u0: np.ndarray, lam: float) -> Solution:
        """Solve ``r(u, lam) = 0`` at fixed ``lam`` (natural parameter).

        Parameters
        ----------
        u0 : ndarray
            Guess of the unknowns.
        lam : float
            The parameter's value.

        Returns
        -------
        Solution
            The corrected point.

        Raises
        ------
        ConvergenceError, SaltationError
            As :meth:`solve_bordered`.
        """
        e = np.zeros(len(u0) + 1)
        e[-1] = 1.0
        return self.solve_bordered(np.append(u0, lam), e)

    def tangent(self, sol: Solution, previous: np.ndarray) -> np.ndarray:
        """Unit tangent at ``sol`` oriented along ``previous``.

        Solves ``[[J_u, J_lam], [previous]] t = e_last``; where that matrix is singular, ``previous``
        itself is returned (normalised).

        Parameters
        ----------
        sol : Solution
            A corrected point with ``jac_lam`` in its evaluation.
        previous : ndarray
            The previous tangent (or ``e_lam`` at the start).

        Returns
        -------
        ndarray
            The unit tangent, with ``t . previous >= 0``.
        """
        ev = sol.evaluation
        known = ev.bordered_tangent
        if known is not None and known[0] is previous:
            # solved by the compiled corrector with this very row, by the same elimination with partial
            # pivoting (zero where singular: then as below)
            t, info = known[1].copy(), 0
        else:
            rhs = np.zeros(len(previous))
            rhs[-1] = 1.0
            t = bordered_solve(ev.jac_u, ev.jac_lam, previous[:-1], previous[-1], rhs)
            info = 0 if t is not None else 1
            t = previous.copy() if t is None else t
        # in plain floats (an overflow is inf, without numpy's error state): a few numbers per branch point
        size = sum(v * v for v in t.tolist())
        if info != 0 or not math.isfinite(size) or size == 0.0:  # singular: info > 0
            t = previous.copy()
            size = sum(v * v for v in t.tolist())
        t /= math.sqrt(size)
        if t @ previous < 0:  # (numpy's product: its sign where t is all but normal to previous, as callers check it)
            t = -t
        return t


__all__ = ["Corrector", "NewtonSettings", "Solution", "bordered", "canonical_events"]
