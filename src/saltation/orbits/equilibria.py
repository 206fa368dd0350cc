"""Equilibria of one mode of an autonomous model, ``f(x, p) = 0``, as a branch problem.

(Pseudo-equilibria, rest points of a sliding motion, are in :mod:`saltation.orbits.pseudo_equilibria`.)
"""


from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from saltation.engine.flow import (
    Flow,
)
from saltation.errors import (
    ModelError,
)
from saltation.orbits.measures import measure_state
from saltation.orbits.problem import BranchProblem, newton
from saltation.orbits.records import (
    BranchPoint,
    Evaluation,
)


@dataclass(frozen=True)
class Equilibrium:
    """An equilibrium of one mode, with the eigenvalues of ``f_x`` there.

    Attributes
    ----------
    mode : str
        The mode.
    state : ndarray, shape (n,)
        The equilibrium.
    parameters : ndarray
        Parameter values.
    eigenvalues : ndarray, complex
        Eigenvalues of the mode's ``f_x`` at the state.
    residuals : list of float
        Newton's residual history.
    """

    mode: str
    state: np.ndarray
    parameters: np.ndarray
    eigenvalues: np.ndarray
    residuals: list[float]

    @property
    def stable(self) -> bool:
        return bool(np.all(self.eigenvalues.real < 0))


class EquilibriumProblem(BranchProblem):
    """Equilibria ``f(x, p) = 0`` of one mode (autonomous systems), in the continuation protocol.

    Parameters
    ----------
    flow : Flow
        The compiled flow of an autonomous model.
    mode : str or int
        The mode whose field vanishes.
    parameters : mapping or ndarray, optional
        Parameter values (defaults of the model otherwise).
    continuation_parameter : str, optional
        Name of the parameter ``lam`` (continuation).

    Raises
    ------
    ModelError
        If the model is forced, or a mode, parameter name or value is invalid.
    """

    #: what a branch of this problem is (:class:`saltation.branches.branch.BranchKind` by value)
    branch_kind = "equilibrium"

    def __init__(
        self,
        flow: Flow,
        mode: str | int,
        parameters: Mapping[str, float] | np.ndarray | None = None,
        *,
        continuation_parameter: str | None = None,
    ):
        self.flow = flow
        self.system = flow.system
        if not self.system.is_autonomous:
            raise ModelError(f"model {self.system.name!r} is forced (its fields depend on time): it has no "
                             "equilibria; its stationary responses are periodic orbits (ShootingProblem)")
        self.mode = self.system.mode_index(mode)
        self.p = flow.parameters(parameters)
        self.lam_index = -1 if continuation_parameter is None else self.system.parameter_index(continuation_parameter)
        self.lam_name = continuation_parameter
        self.autonomous = True
        self.backward = False

    @property
    def dimension(self) -> int:
        return self.system.n

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        """The field ``f(x, p)`` of the mode and its Jacobians.

        Parameters
        ----------
        u : ndarray, shape (n,)
            The state.
        lam : float, optional
            Value of the continuation parameter.
        need_lam : bool
            Compute ``jac_lam`` (``f_p`` of the continuation parameter) too.

        Returns
        -------
        Evaluation
            ``residual = f``, ``jac_u = f_x``, ``jac_lam`` (None without ``lam`` or ``need_lam``).
        """
        p = self.parameters_at(lam)
        x = np.asarray(u, dtype=float)
        f = self.flow.vector_field(self.mode, 0.0, x, p)
        J = self.flow.vector_field_jacobian(self.mode, 0.0, x, p)
        jl = None
        if need_lam and lam is not None:
            jl = self.flow.vector_field_parameters(self.mode, 0.0, x, p)[:, self.lam_index].copy()
        return Evaluation(residual=f, jac_u=J, jac_lam=jl)

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> BranchPoint:
        """Summary of a solved equilibrium for a branch: the eigenvalues of ``f_x`` as its multipliers.

        Parameters
        ----------
        u : ndarray, shape (n,)
            The equilibrium.
        lam : float or None
            Value of the continuation parameter.
        ev : Evaluation
            Its evaluation.

        Returns
        -------
        BranchPoint
            With the eigenvalues sorted by decreasing real part, stable when all have negative real
            parts, and no period.

        Raises
        ------
        numpy.linalg.LinAlgError
            If the Jacobian is not finite.
        """
        eig = np.linalg.eigvals(ev.jac_u).astype(complex)
        eig = eig[np.lexsort((-eig.imag, -eig.real))]
        return BranchPoint(
            parameter=math.nan if lam is None else float(lam),
            state=np.array(u),
            period=float("nan"),
            amplitude=float(abs(u[0])),
            half_peak_to_peak=0.0,
            multipliers=eig,
            stable=bool(np.all(eig.real < 0)),
            event_labels=(),
            measures=measure_state(u, self.parameters_at(lam, u), self.measures),
        )

    def accept(self, u: np.ndarray, lam: float | None) -> None:
        """Nothing to re-anchor for equilibria.

        Parameters
        ----------
        u : ndarray
            The accepted state.
        lam : float or None
            Value of the continuation parameter.
        """

    def solve(self, x0: Sequence[float], lam: float | None = None, *, tol: float = 1e-12, max_iter: int = 30) -> Equilibrium:
        """Newton on ``f(x, p) = 0`` from the guess ``x0``.

        Parameters
        ----------
        x0 : sequence of float
            Guess of the equilibrium.
        lam : float, optional
            Value of the continuation parameter.
        tol : float
            Newton tolerance: converged when ``|f| <= tol (1 + |x|)``.
        max_iter : int
            Largest number of Newton iterations.

        Returns
        -------
        Equilibrium
            The equilibrium and its eigenvalues.

        Raises
        ------
        ConvergenceError
            With the residual history when Newton fails.
        """
        def fun(u):
            ev = self.evaluate(u, lam, need_lam=False)
            return ev.residual, ev.jac_u, ev

        mname = self.system.mode_names[self.mode]
        x, history, ev = newton(fun, np.asarray(x0, dtype=float), tol=tol, max_iter=max_iter, what=f"equilibrium of mode {mname!r}")
        return Equilibrium(
            mode=mname,
            state=x,
            parameters=self.parameters_at(lam),
            eigenvalues=np.linalg.eigvals(ev.jac_u),
            residuals=history,
        )


__all__ = ["Equilibrium", "EquilibriumProblem"]
