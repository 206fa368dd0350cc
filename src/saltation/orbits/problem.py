"""The problem base of every branch, and the one Newton iteration and bordered solve beneath them.

A branch is the set of solutions of ``r(u, lam) = 0``: periodic orbits by single or multiple shooting,
equilibria, pseudo-equilibria, and orbits with defining conditions attached (special points, their
curves in two parameters).  Each kind is a :class:`BranchProblem`; the continuation engine
(:mod:`saltation.branches.continuation`) and the special-point layer speak to that base only.

:func:`newton` is the one plain Newton iteration of the package (the bordered corrector of a branch,
:class:`saltation.branches.corrector.Corrector`, is the other), :func:`accuracy` the one estimate of
how well a located unknown is known, and :func:`bordered_solve` the one solve of a bordered system
``[[A, b], [c, d]] x = rhs``.
"""

from __future__ import annotations

import abc
import logging
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import lapack

from saltation.errors import ConvergenceError, ModelError, SaltationError
from saltation.orbits.records import BranchPoint, Evaluation

_log = logging.getLogger(__name__)


class BranchProblem(abc.ABC):
    """A problem ``r(u, lam) = 0`` whose solutions make a branch: the contract every problem keeps.

    An implementation provides, and the continuation engine, the corrector and the special-point layer
    rely on nothing else:

    1. the attributes ``system`` (the model), ``flow`` (its compiled flow), ``p`` (the parameter values),
       ``lam_name`` and ``lam_index`` (the continuation parameter, ``None`` and ``-1`` without one);
    2. :attr:`dimension`, the number of unknowns ``u``;
    3. :meth:`evaluate`, the residual and its Jacobians at ``(u, lam)``;
    4. :meth:`describe`, the record of a solved point for its branch;
    5. optionally :meth:`accept` (called with every accepted point: re-anchor a phase condition, move
       a guess), :meth:`correct` (a compiled corrector), :meth:`rephase` (move the unknowns to another
       section of the same solution), :attr:`single_shooting` (the single-shooting problem it is, for
       the one-sided limits and the half-period map) and the class attributes :attr:`branch_kind`,
       :attr:`backward`, :attr:`autonomous`, :attr:`can_collapse`, :attr:`periods`, :attr:`mode0`,
       :attr:`tolerances` and :attr:`measures`.

    Implementations document only what differs from this contract.
    """

    #: What a branch of this problem is (:class:`saltation.branches.branch.BranchKind` by value).
    branch_kind: str = "periodic"
    #: Whether the problem shoots in backward time (infinitely unstable orbits).
    backward: bool = False
    #: Whether the model is autonomous (the period is an unknown).
    autonomous: bool = True
    #: Whether the branch's orbits may shrink onto an equilibrium (a cycle collapse ends the branch).
    can_collapse: bool = False
    #: Forced orbits: the number of forcing periods an orbit closes after.
    periods: int = 1
    #: The mode the shots start in (None: the model's domains give it).
    mode0: str | None = None
    #: Integration tolerances (None: the flow's own).
    tolerances: object = None
    #: The measures every described point carries in :attr:`BranchPoint.measures`
    #: (:class:`saltation.orbits.measures.Measure`; the continuation sets them from its settings).
    measures: tuple = ()

    system: object
    #: The model's compiled flow.
    flow: object = None
    p: np.ndarray
    lam_name: str | None
    lam_index: int

    @property
    @abc.abstractmethod
    def dimension(self) -> int:
        """Number of unknowns ``u``."""

    def parameters_at(self, lam: float | None = None, u: np.ndarray | None = None) -> np.ndarray:
        """Every parameter's value at the continuation parameter ``lam`` (and the unknowns ``u``).

        Parameters
        ----------
        lam : float or None
            Value of the continuation parameter (None: the problem's parameters as they are).
        u : ndarray, optional
            The unknowns: a problem whose unknowns hold parameters (a curve in two parameters) reads
            them from ``u``; the others ignore it.

        Returns
        -------
        ndarray, shape (n_params,)
            A copy of the parameters.

        Raises
        ------
        ModelError
            If ``lam`` is given and the problem has no continuation parameter.
        """
        p = np.array(self.p, dtype=float)
        if lam is not None:
            if self.lam_index < 0:
                raise ModelError("this problem has no continuation parameter")
            p[self.lam_index] = lam
        return p

    def lam0(self) -> float:
        """The continuation parameter's value in the problem's parameters.

        Returns
        -------
        float
            The starting value of ``lam``.

        Raises
        ------
        ModelError
            If the problem has no continuation parameter.
        """
        if self.lam_index < 0:
            raise ModelError("this problem has no continuation parameter")
        return float(self.p[self.lam_index])

    @abc.abstractmethod
    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        """The residual ``r(u, lam)`` and its Jacobians.

        Parameters
        ----------
        u : ndarray, shape (dimension,)
            The unknowns.
        lam : float, optional
            Value of the continuation parameter (None: the problem's own value).
        need_lam : bool
            Compute ``jac_lam`` too (a fixed-parameter solve does not need it).

        Returns
        -------
        Evaluation
            ``residual``, ``jac_u``, ``jac_lam`` (None without ``lam`` or ``need_lam``), and the
            trajectory where there is one.

        Raises
        ------
        SaltationError
            Whatever the integration or the model raises (an :class:`IntegrationError`, a
            :class:`StationaryStateError` ...).
        """

    @abc.abstractmethod
    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> BranchPoint:
        """The record of a solved point for its branch.

        Parameters
        ----------
        u : ndarray
            The solved unknowns.
        lam : float or None
            The parameter's value.
        ev : Evaluation
            The evaluation at the solution.

        Returns
        -------
        BranchPoint
            State, period, amplitude, multipliers (or eigenvalues), stability and events.
        """

    def accept(self, u: np.ndarray, lam: float | None) -> None:
        """Called with every accepted point of a branch (default: nothing).

        Parameters
        ----------
        u : ndarray
            The accepted unknowns.
        lam : float or None
            The parameter's value there.
        """

    def correct(self, z_pred: np.ndarray, normal: np.ndarray, *, tol: float, max_newton: int,
                max_correction: float) -> tuple[np.ndarray, Evaluation, int] | None:
        """A compiled corrector of the bordered system, where the problem has one (default: None).

        Parameters
        ----------
        z_pred : ndarray
            The predicted point ``(u, lam)``.
        normal : ndarray
            The bordering row.
        tol : float
            Newton tolerance on the residual.
        max_newton : int
            Largest number of iterations.
        max_correction : float
            A correction longer than this (relative to ``1 + |z|``) counts as divergence.

        Returns
        -------
        tuple of (ndarray, Evaluation, int) or None
            The corrected point, its evaluation and the iterations; None to iterate in Python.
        """
        return None

    def rephase(self, u: np.ndarray, lam: float | None) -> np.ndarray | None:
        """The unknowns of the same solution at another section, off its events (default: None, cannot).

        The engine calls it before giving up a step: a periodic orbit's shooting state may have drifted
        onto an event.  A problem that moves its section keeps the new one (its :attr:`section_time`,
        :attr:`section_settings`).

        Parameters
        ----------
        u : ndarray
            The unknowns of a solved point.
        lam : float or None
            Its parameter's value.

        Returns
        -------
        ndarray or None
            The moved unknowns, or None where the problem cannot move them.

        Raises
        ------
        SaltationError
            If the solution cannot be integrated to find a better section.
        """
        return None

    @property
    def single_shooting(self):
        """The problem as single shooting of periodic orbits (a :class:`~saltation.orbits.single.ShootingProblem`),
        or None for any other kind: the special points that need one shot of the period (one-sided limits,
        the half-period map) ask for it."""
        return None

    @property
    def section_time(self) -> float:
        """The time of the section the unknowns' state lies at (a forced orbit's ``t0``; 0 otherwise)."""
        return 0.0

    @property
    def section_settings(self) -> dict:
        """What :meth:`rephase` may change, to put back if the moved point is refused (default: nothing)."""
        return {}

    def restore_section(self, settings: dict) -> None:
        """Put back what :attr:`section_settings` returned.

        Parameters
        ----------
        settings : dict
            A value of :attr:`section_settings`.
        """
        for key, value in settings.items():
            setattr(self, key, value)


@dataclass
class NewtonResult:
    """The solution of :func:`newton`.

    It unpacks as ``u, residuals, extra`` (the tuple :func:`newton` returned in release 0.1; the
    unpacking goes in release 0.3.0).

    Attributes
    ----------
    u : ndarray
        The solution.
    residuals : list of float
        Residual norms, first to last.
    extra : object
        The third item of ``fun`` at the solution.
    residual : ndarray
        The residual at the solution.
    jacobian : ndarray
        Its Jacobian there.
    """

    u: np.ndarray
    residuals: list[float]
    extra: object
    residual: np.ndarray
    jacobian: np.ndarray
    iterations: int = field(init=False)

    def __post_init__(self) -> None:
        self.iterations = len(self.residuals) - 1

    def __iter__(self) -> Iterator:
        return iter((self.u, self.residuals, self.extra))


def residual_norm(v: np.ndarray) -> float:
    """The 2-norm of ``v``, scaled so that it overflows only when the norm itself exceeds the largest float.

    (``np.linalg.norm`` squares the entries: a residual of ``1e200`` would read as infinite.)

    Parameters
    ----------
    v : ndarray
        A vector.

    Returns
    -------
    float
        ``|v|``.
    """
    with np.errstate(over="ignore"):
        norm = float(np.linalg.norm(v))
        if math.isfinite(norm) or not np.isfinite(v).all():
            return norm
        big = float(np.max(np.abs(v)))
        return big * float(np.linalg.norm(np.asarray(v, dtype=float) / big))


def newton(
    fun: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, object]],
    u0: np.ndarray,
    *,
    tol: float = 1e-10,
    max_iter: int = 30,
    what: str = "Newton",
    damped: bool = False,
    size: Callable[[np.ndarray], float] | None = None,
    history: list[float] | None = None,
    wrap_errors: bool = False,
) -> NewtonResult:
    """Newton's method on ``fun(u) -> (r, J, extra)``.

    Converged when ``|r| <= tol (1 + size(u))``.  With ``damped``, a step is halved (up to 8 times)
    until the residual decreases.  A trial step at which ``fun`` raises a :class:`SaltationError`
    counts as one that does not reduce it.

    Parameters
    ----------
    fun : callable
        ``fun(u)`` returns the residual ``r``, its Jacobian ``J`` (square) and anything else
        (``extra``) to hand back with the solution.
    u0 : ndarray
        Initial iterate.
    tol : float
        Tolerance.
    max_iter : int
        Largest number of iterations.
    what : str
        What is solved, for the error messages.
    damped : bool
        Halve steps that do not reduce the residual.
    size : callable, optional
        The size of an iterate the tolerance is relative to (``|u|`` by default; a problem whose
        unknowns mix a state with a weight or a period measures the state).
    history : list of float, optional
        A list to append the residual norms to (a new one by default).
    wrap_errors : bool
        Turn a :class:`SaltationError` of ``fun`` (at the first evaluation too) into a
        :class:`ConvergenceError` whose message starts with ``what``.

    Returns
    -------
    NewtonResult
        The solution, the residual history, ``extra``, the residual and the Jacobian there.

    Raises
    ------
    ConvergenceError
        With the residual history: after ``max_iter`` iterations, when the Jacobian is singular, the
        residual is not finite, or no step reduces it.
    SaltationError
        Whatever ``fun`` raises at ``u0`` (the first evaluation is not a trial step), unless
        ``wrap_errors``.
    """
    size = size or residual_norm
    u = np.array(u0, dtype=float)
    history = [] if history is None else history

    def call(v: np.ndarray):
        if not wrap_errors:
            return fun(v)
        try:
            return fun(v)
        except ConvergenceError:
            raise
        except SaltationError as exc:
            raise ConvergenceError(f"{what}: {exc}", history) from exc

    r, J, extra = call(u)
    for it in range(max_iter + 1):
        rn = residual_norm(r)
        history.append(rn)
        _log.debug("%s: iteration %d, residual %.3e", what, it, rn)
        if not np.isfinite(rn):
            why = ("not finite" if not np.isfinite(r).all() else
                   f"too large for a float (its entries reach {float(np.max(np.abs(r))):.3g})")
            raise ConvergenceError(f"{what}: residual is {why} at iteration {it}", history)
        if rn <= tol * (1.0 + size(u)):
            return NewtonResult(u=u, residuals=history, extra=extra, residual=r, jacobian=J)
        if it == max_iter:
            break
        try:
            du = np.linalg.solve(J, -r)
        except np.linalg.LinAlgError:
            raise ConvergenceError(f"{what}: singular Jacobian at iteration {it}", history) from None
        trial, failure = None, None
        for _ in range(9 if damped else 1):
            try:
                trial = call(u + du)
            except SaltationError as exc:  # (with wrap_errors, a ConvergenceError naming what failed)
                trial, failure = None, (exc if wrap_errors else None)
            if trial is not None and (not damped or residual_norm(trial[0]) < rn):
                break
            du = 0.5 * du
            trial = None
        if trial is None:
            if failure is not None:
                raise failure
            raise ConvergenceError(f"{what}: no step reduces the residual at iteration {it}", history)
        u = u + du
        r, J, extra = trial
    raise ConvergenceError(f"{what} did not converge in {max_iter} iterations", history)


def accuracy(result: NewtonResult, integration_error: float, rows: slice) -> np.ndarray:
    """How well the unknowns ``u[rows]`` of a Newton solution are known.

    The correction that would follow, plus the integration error carried to them through the inverse
    Jacobian, plus their rounding: ``|du| + |J^-1|_rows 1 e + 4 eps max(1, |u|)``.

    Parameters
    ----------
    result : NewtonResult
        A converged solution.
    integration_error : float
        The largest error of the integration behind the residual
        (:meth:`saltation.engine.flow.Flow.integration_error`).
    rows : slice
        The unknowns asked for (the freed parameters of a located point).

    Returns
    -------
    ndarray
        One bound per unknown.

    Raises
    ------
    ConvergenceError
        If the Jacobian at the solution is singular.
    """
    J, u = result.jacobian, result.u
    try:
        du = np.linalg.solve(J, -result.residual)
        inverse = np.linalg.inv(J)
    except np.linalg.LinAlgError:
        raise ConvergenceError("singular Jacobian of the defining system", result.residuals) from None
    return (np.abs(du[rows]) + np.abs(inverse[rows]).sum(axis=1) * integration_error
            + 4e-16 * np.maximum(1.0, np.abs(u[rows])))


def bordered_solve(A: np.ndarray, b: np.ndarray, c: np.ndarray, d: float, rhs: np.ndarray) -> np.ndarray | None:
    """Solve the bordered system ``[[A, b], [c, d]] x = rhs`` (one border row and column).

    By LAPACK's ``dgesv`` on the assembled matrix (elimination with partial pivoting), without numpy's
    per-call cost: it runs for every branch point on a matrix of a few rows.

    Parameters
    ----------
    A : ndarray, shape (m, m)
    b : ndarray, shape (m,)
        The border column.
    c : ndarray, shape (m,)
        The border row (for a branch: the tangent, or ``e_lam`` at a fixed parameter).
    d : float
        The corner.
    rhs : ndarray, shape (m + 1,)

    Returns
    -------
    ndarray or None
        ``x``, or None where the matrix is singular.

    References
    ----------
    Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM (bordered
    systems).
    """
    m = A.shape[0]
    B = np.empty((m + 1, m + 1))
    B[:m, :m] = A
    B[:m, m] = b
    B[m, :m] = c
    B[m, m] = d
    _, _, x, info = lapack.dgesv(B, np.asarray(rhs, dtype=float))
    return None if info != 0 else x


__all__ = ["BranchProblem", "NewtonResult", "accuracy", "bordered_solve", "newton", "residual_norm"]
