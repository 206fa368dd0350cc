"""Newton's method on a branch: the corrector shared by continuation and the location of special points.

``r(z) = 0`` with ``z = (u, lam)`` for a problem of the protocol of
:mod:`saltation.orbits.shooting` (``evaluate``, ``describe``, and optionally
``correct``, the compiled iteration), bordered by one linear condition
``normal . (z - z_pred) = 0``: a pseudo-arclength step, or a fixed parameter.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from saltation.errors import ConvergenceError
from saltation.orbits.records import BranchPoint, Evaluation


class NewtonSettings(Protocol):
    """What the corrector reads of its settings (``ContinuationSettings`` has them)."""

    tol: float
    max_newton: int
    max_correction: float


@dataclass
class Solution:
    """A corrected point ``z = (u, lam)`` with its evaluation and summary."""

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
    """An event sequence (labels or :func:`saltation.orbits.shooting.event_ids`) up to cyclic rotation (where an
    orbit starts is not a change)."""
    if not events:
        return events
    rotations = [events[k:] + events[:k] for k in range(len(events))]
    return min(rotations)


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
    """Newton solvers on the branch of one problem (shared by continuation and location)."""

    problem: object
    settings: NewtonSettings

    def solve_bordered(self, z_pred: np.ndarray, normal: np.ndarray) -> Solution:
        """Solve ``r(z) = 0``, ``normal . (z - z_pred) = 0`` by Newton from ``z_pred``.

        Raises
        ------
        ConvergenceError
            If Newton does not converge in ``max_newton`` iterations.
        """
        prob = self.problem
        s = self.settings
        found = None
        compiled = getattr(prob, "correct", None)  # shooting problems iterate in the compiled kernel
        if compiled is not None:
            found = compiled(z_pred, normal, tol=s.tol, max_newton=s.max_newton, max_correction=s.max_correction)
        if found is not None:
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
            J = bordered(ev.jac_u, ev.jac_lam, normal)
            rhs = np.append(ev.residual, normal @ (z - z_pred))
            try:
                dz = np.linalg.solve(J, rhs)
            except np.linalg.LinAlgError:
                break
            if np.linalg.norm(dz) > s.max_correction * (1.0 + np.linalg.norm(z)):
                break  # diverging: let the step control shorten the step
            z = z - dz
        raise ConvergenceError("corrector did not converge", history)

    def solve_fixed(self, u0: np.ndarray, lam: float) -> Solution:
        """Solve ``r(u, lam) = 0`` at fixed ``lam`` (natural parameter)."""
        e = np.zeros(len(u0) + 1)
        e[-1] = 1.0
        return self.solve_bordered(np.append(u0, lam), e)

    def tangent(self, sol: Solution, previous: np.ndarray) -> np.ndarray:
        """Unit tangent at ``sol`` oriented along ``previous``."""
        ev = sol.evaluation
        J = bordered(ev.jac_u, ev.jac_lam, previous)
        rhs = np.zeros(J.shape[0])
        rhs[-1] = 1.0
        try:
            t = np.linalg.solve(J, rhs)
        except np.linalg.LinAlgError:
            t = previous.copy()
        t /= np.linalg.norm(t)
        if t @ previous < 0:
            t = -t
        return t


__all__ = ["Corrector", "NewtonSettings", "Solution", "bordered", "canonical_events"]
