"""What the parts of the special-point detector share: its context and the multiplier helpers they all read.

:class:`DetectionContext` holds what detection at a branch step needs to know of the branch: its problem, its
corrector (with the location tolerance ``locate_tol``), the branch itself and what follows from them (an
equilibrium branch, an autonomous orbit, the symmetry of the half-period map).  The functions of
:mod:`~saltation.special_points.smooth`, :mod:`~saltation.special_points.nonsmooth` and
:mod:`~saltation.special_points.symmetric` take it as their first argument, ``ctx``, and read nothing else
of the detector; :class:`~saltation.special_points.detector.SpecialPointDetector` is one.
"""

from __future__ import annotations

import cmath
import math

import numpy as np

from saltation.branches.branch import Branch, BranchKind
from saltation.branches.corrector import Corrector, Solution
from saltation.errors import ModelError
from saltation.model.symmetry import check_symmetry

__all__ = ["DetectionContext"]


class DetectionContext:
    """The branch a special point is looked for on, as the detector's parts read it.

    Parameters
    ----------
    problem : ShootingProblem or EquilibriumProblem
        The branch's problem.
    corrector : Corrector
        The branch's corrector (its settings give the location tolerance ``locate_tol``).
    branch : Branch
        The branch being followed (its kind, time direction and whether it is autonomous).

    Attributes
    ----------
    tol : float
        The location tolerance (the corrector's ``locate_tol``).
    equilibrium : bool
        Whether the branch is one of equilibria.
    autonomous : bool
        Whether its orbits are autonomous (they have a trivial multiplier).
    symmetry : ndarray or None
        The matrix ``S`` of the model's declared symmetry, where it splits the multipliers of the symmetric
        orbits (one-period single shooting, the symmetry holding at the branch's parameters); else None.
    """

    def __init__(self, problem, corrector: Corrector, branch: Branch):
        self.problem = problem
        self.corrector = corrector
        self.branch = branch
        self.tol = corrector.settings.locate_tol
        self.equilibrium = branch.kind is BranchKind.EQUILIBRIUM
        self.autonomous = branch.autonomous and not self.equilibrium
        symmetry = getattr(problem.system, "symmetry", None)
        # the half-period map splits the multipliers of the symmetric orbits of one-period shooting, where the
        # model has its symmetry at the branch's parameters (it may hold at some values only)
        self.symmetry = None
        if symmetry is not None and problem.single_shooting is not None and problem.periods == 1:
            try:
                check_symmetry(problem.system, symmetry, problem.parameters_at(branch.points[0].parameter
                                                                               if branch.points else None))
            except ModelError:
                pass
            else:
                self.symmetry = symmetry.S

    def on_secant(self, a: Solution, b: Solution, sigma: float) -> Solution:
        """The branch point on the secant from ``a`` to ``b`` at the fraction ``sigma``.

        Parameters
        ----------
        a, b : Solution
            Two corrected points.
        sigma : float
            Fraction of the secant (0 at ``a``, 1 at ``b``).

        Returns
        -------
        Solution
            The point corrected on the hyperplane normal to the secant through ``a + sigma (b - a)``.

        Raises
        ------
        ConvergenceError, SaltationError
            As :meth:`Corrector.solve_bordered`.
        """
        d = b.z - a.z
        return self.corrector.solve_bordered(a.z + sigma * d, _unit(d))

    def matrix_error(self, sol: Solution) -> float:
        """An error estimate of the multipliers' matrix at a solution.

        For autonomous orbits ``|M n - n|`` (the trivial multiplier's error), for forced ones the flow's
        error estimate relative to the state, times ``|M|``; rounding for an equilibrium's Jacobian.

        Parameters
        ----------
        sol : Solution
            A corrected branch point.

        Returns
        -------
        float
        """
        ev = sol.evaluation
        if self.equilibrium:
            return 1e-12 * (1.0 + float(np.linalg.norm(ev.jac_u)))
        if self.autonomous:
            return float(sol.summary.trivial_error)
        traj = ev.trajectory
        flow = self.problem.flow
        relative = flow.integration_error(traj, self.problem.tolerances) / (1.0 + float(np.abs(traj.x1).max()))
        return relative * (1.0 + float(np.linalg.norm(traj.monodromy)))

    def state_resolution(self, sol: Solution) -> float:
        """The flow's estimate of the error of a solution's end state (0 for an equilibrium).

        Parameters
        ----------
        sol : Solution
            A corrected branch point.

        Returns
        -------
        float
        """
        if self.equilibrium:
            return 0.0
        return self.problem.flow.integration_error(sol.evaluation.trajectory, self.problem.tolerances)

    def oriented_tangent(self, sol: Solution, direction: np.ndarray) -> np.ndarray:
        """The unit tangent at ``sol`` oriented along ``direction`` (the one continuation computed, if any).

        Parameters
        ----------
        sol : Solution
            A corrected branch point.
        direction : ndarray
            The direction the tangent is to point along (its sign only matters).

        Returns
        -------
        ndarray
        """
        if sol.tangent is None:
            return self.corrector.tangent(sol, direction)
        return sol.tangent if sol.tangent @ direction >= 0.0 else -sol.tangent


def _complex_text(z: complex) -> str:
    return f"{z.real:.9g}" if abs(z.imag) <= 1e-12 else f"{z.real:.9g}{z.imag:+.9g}i"


def _nearest(mu: np.ndarray, target: float) -> complex:
    """The multiplier nearest ``target`` (``inf`` when there is none)."""
    mu = np.asarray(mu, dtype=complex)
    mu = mu[np.isfinite(mu)]
    return complex(mu[int(np.argmin(np.abs(mu - target)))]) if mu.size else complex(np.inf)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / math.sqrt(float(v @ v))  # numpy's norm of a vector, without its per-call dispatch


def _nontrivial(sol: Solution, autonomous: bool) -> np.ndarray:
    """Multipliers without the trivial one (closest to 1) of an autonomous orbit."""
    mu = sol.summary.multipliers
    if not autonomous:
        return mu
    mu = np.asarray(mu, dtype=complex)
    if mu.size:
        finite = np.where(np.isfinite(mu), np.abs(mu - 1.0), np.inf)
        keep = np.ones(mu.size, dtype=bool)
        keep[int(np.argmin(finite))] = False
        mu = mu[keep]
    return mu


def _finite(mu: np.ndarray) -> list[complex]:
    """The finite multipliers, as plain complex numbers (the test functions run for every branch point, on a
    few numbers: numpy's per-call cost would exceed the arithmetic)."""
    return [m for m in np.asarray(mu, dtype=complex).tolist() if cmath.isfinite(m)]
