"""Symmetric periodic orbits: the half-period map and the split of their multipliers.

For a model with a symmetry ``x -> S x``, ``t -> t + T/2`` (:mod:`saltation.model.symmetry`) a
periodic orbit is *symmetric* when ``x(t0 + T/2) = S x(t0)``: it is a fixed point of the half-period map
``G(x) = S^-1 phi(t0 + T/2; t0, x)``.  Equivariance, ``phi(t0 + T; t0 + T/2, S y) = S phi(t0 + T/2; t0, y)``,
gives the period map ``phi(t0 + T; t0, x) = G(G(x))`` (``S^2 = I``), so the monodromy is ``M = DG^2`` and every Floquet multiplier is the square ``mu = gamma^2`` of an
eigenvalue ``gamma`` of ``DG``.  The split:

* ``gamma`` with a positive real part: a *symmetric* multiplier; at ``gamma = +1`` the symmetric
  orbits have a fold;
* ``gamma`` with a negative real part: an *antisymmetric* multiplier (its eigenvector ``v`` satisfies
  ``v(t + T/2) = -S v(t)``); at ``gamma = -1`` the full multiplier is +1 but the symmetric branch goes
  on: two branches of asymmetric orbits, mirror images of each other, leave it (a symmetry-breaking
  pitchfork);
* ``gamma = +-i`` gives ``mu = -1``: a period doubling.

The half-period map carries the saltation matrices of its events like the monodromy, so at a corner
its one-sided limits and their convex combination give set-valued ``gamma`` as in *Fold bifurcations in
discontinuous systems*; a jump of a real ``gamma`` through -1 is a discontinuous symmetry breaking.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from saltation._moved import forward_names
from saltation.errors import InconsistentResultError, ModelError
from saltation.orbits.floquet import eigenvalues, reciprocal, sort_multipliers
from saltation.orbits.problem import newton

#: an orbit is symmetric when ``|S^-1 x(t0 + T/2) - x0| <= SYMMETRIC_TOL (1 + |x0|)``: orbits are
#: converged to about 1e-10, and an asymmetric orbit at distance d from a symmetry breaking misses its
#: mirror image by O(sqrt(d))
SYMMETRIC_TOL = 1e-7
#: ``DG^2`` and the monodromy computed over the whole period agree to the integration's accuracy; a
#: relative difference above this means the declared symmetry does not hold for this orbit
CONSISTENCY_TOL = 1e-6


@dataclass(frozen=True)
class SymmetricMultipliers:
    """The half-period map of a periodic orbit and its multipliers split by the symmetry.

    Attributes
    ----------
    half_map : ndarray, shape (n, n)
        ``DG = S^-1 Phi(t0 + T/2, t0)`` in the direction of integration.
    gamma : ndarray, complex
        Its eigenvalues as forward-time values (reciprocals for a backward-time orbit), sorted by
        decreasing magnitude.
    multipliers : ndarray, complex
        ``gamma**2``: the Floquet multipliers, in the same order.
    antisymmetric : ndarray of bool
        Which multipliers are antisymmetric (``gamma`` with a negative real part).
    symmetry_error : float
        ``|S^-1 x(t0 + T/2) - x0| / (1 + |x0|)``: zero for a symmetric orbit.
    symmetric : bool
        ``symmetry_error <= SYMMETRIC_TOL``.  The split means something only for a symmetric orbit.
    """

    half_map: np.ndarray
    gamma: np.ndarray
    multipliers: np.ndarray
    antisymmetric: np.ndarray
    symmetry_error: float
    symmetric: bool

    @property
    def antisymmetric_multipliers(self) -> np.ndarray:
        """The antisymmetric Floquet multipliers ``gamma**2``."""
        return self.multipliers[self.antisymmetric]

    @property
    def symmetric_multipliers(self) -> np.ndarray:
        """The symmetric Floquet multipliers ``gamma**2``."""
        return self.multipliers[~self.antisymmetric]


def symmetry_matrix(system) -> np.ndarray:
    """The matrix ``S`` of a model's declared symmetry.

    Parameters
    ----------
    system : PiecewiseSystem

    Returns
    -------
    ndarray, shape (n, n)

    Raises
    ------
    ModelError
        If the model declares no symmetry.
    """
    sym = getattr(system, "symmetry", None)
    if sym is None:
        raise ModelError(f"model {system.name!r} declares no symmetry (PiecewiseSystem(..., symmetry=Symmetry(...)))")
    return sym.S


def split_multipliers(half_map: np.ndarray, *, backward: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(gamma, gamma**2, antisymmetric)`` from a half-period map's Jacobian (forward-time values).

    Parameters
    ----------
    half_map : ndarray, shape (n, n)
        ``DG`` in the direction of integration.
    backward : bool
        Whether it was computed in backward time (its eigenvalues are then reciprocals of the forward
        ones).

    Returns
    -------
    gamma, multipliers : ndarray, complex
    antisymmetric : ndarray of bool

    Raises
    ------
    numpy.linalg.LinAlgError
        If the matrix is not finite.
    """
    gamma = eigenvalues(half_map)
    if backward:
        gamma = reciprocal(gamma)
    gamma = sort_multipliers(gamma)
    return gamma, gamma**2, gamma.real < 0.0


def half_period_trajectory(flow, state0, p: np.ndarray, *, t0: float, period: float, backward: bool = False,
                           tolerances=None, sensitivity: int = -1):
    """The shot over half a period from ``state0``, with its fundamental solution matrix.

    Parameters
    ----------
    flow : Flow
    state0 : array_like, shape (n,)
    p : ndarray
        Parameter values.
    t0 : float
        Initial time.
    period : float
        The orbit's period (the forcing period of a forced orbit).
    backward : bool
        Integrate in backward time.
    tolerances : Tolerances, optional
    sensitivity : int
        A parameter index whose sensitivity the shot carries (-1 for none).

    Returns
    -------
    Trajectory

    Raises
    ------
    IntegrationError
        If the shot fails (see :meth:`Flow.run`).
    """
    sign = -1.0 if backward else 1.0
    x0 = np.ascontiguousarray(np.asarray(state0, dtype=float))
    return flow.run(x0, t0, t0 + sign * 0.5 * period, p, variational=True, sensitivity=sensitivity,
                    tolerances=tolerances)


def symmetric_multipliers(
    flow,
    state0,
    *,
    parameters=None,
    period: float | None = None,
    t0: float = 0.0,
    backward: bool = False,
    monodromy: np.ndarray | None = None,
    tolerances=None,
) -> SymmetricMultipliers:
    """The half-period map of a periodic orbit, and its multipliers split into symmetric and antisymmetric.

    Parameters
    ----------
    flow : Flow
        The compiled flow of a model that declares a symmetry.
    state0 : array_like, shape (n,)
        A state of the orbit at ``t0``.
    parameters : mapping or ndarray, optional
        Parameter values (the model's defaults otherwise).
    period : float, optional
        The period; a forced orbit's is the forcing period (the default), an autonomous orbit's must be
        given.
    t0 : float
        Initial time.
    backward : bool
        Compute the half-period map in backward time (an infinitely unstable orbit).
    monodromy : ndarray, shape (n, n), optional
        The orbit's monodromy over the whole period in the direction of integration; when given,
        ``DG^2`` is checked against it for a symmetric orbit (next to a corner of switching surfaces the
        monodromy moves like the square root of the distance to it, and the check can fail on rounding:
        leave it out there).
    tolerances : Tolerances, optional
        Integration tolerances (the flow's by default).

    Returns
    -------
    SymmetricMultipliers

    Raises
    ------
    ModelError
        If the model declares no symmetry, or an autonomous orbit has no period.
    InconsistentResultError
        If the orbit is symmetric but ``DG^2`` differs from ``monodromy`` by more than
        :data:`CONSISTENCY_TOL` (relative): the equations do not have the symmetry along this orbit.
    IntegrationError
        If the shot fails.

    References
    ----------
    Leine and Van Campen (2002), "Discontinuous bifurcations of periodic solutions", Mathematical and
    Computer Modelling 36 (symmetry-breaking bifurcations of the trilinear system).  Golubitsky,
    Stewart and Schaeffer (1988), *Singularities and Groups in Bifurcation Theory*, vol. II, Springer.
    """
    system = flow.system
    S = symmetry_matrix(system)
    p = flow.parameters(parameters)
    if period is None:
        if system.is_autonomous:
            raise ModelError(f"model {system.name!r} is autonomous: give the orbit's period")
        period = system.forcing_period(p)
    x0 = np.asarray(state0, dtype=float)
    traj = half_period_trajectory(flow, x0, p, t0=t0, period=float(period), backward=backward, tolerances=tolerances)
    return split_half_map(S, traj, x0, backward=backward, monodromy=monodromy)


def split_half_map(S: np.ndarray, traj, x0: np.ndarray, *, backward: bool = False,
                   monodromy: np.ndarray | None = None) -> SymmetricMultipliers:
    """:class:`SymmetricMultipliers` from a shot over half a period (see :func:`symmetric_multipliers`).

    Parameters
    ----------
    S : ndarray, shape (n, n)
        The symmetry's matrix.
    traj : Trajectory
        The shot from ``x0`` over half the period, with its fundamental solution matrix.
    x0 : ndarray, shape (n,)
        Its initial state.
    backward : bool
        Whether the shot ran in backward time.
    monodromy : ndarray, optional
        The monodromy over the whole period, to check ``DG^2`` against.

    Returns
    -------
    SymmetricMultipliers

    Raises
    ------
    InconsistentResultError
        See :func:`symmetric_multipliers`.
    """
    DG = S @ traj.monodromy  # S^-1 = S
    error = float(np.linalg.norm(S @ traj.x1 - x0)) / (1.0 + float(np.linalg.norm(x0)))
    symmetric = error <= SYMMETRIC_TOL
    if symmetric and monodromy is not None:
        scale = 1.0 + float(np.linalg.norm(monodromy))
        mismatch = float(np.linalg.norm(DG @ DG - monodromy)) / scale
        if mismatch > CONSISTENCY_TOL:
            raise InconsistentResultError(
                f"the square of the half-period map's Jacobian differs from the monodromy by {mismatch:.2g} "
                "(relative) on a symmetric orbit: the model does not have its declared symmetry along this orbit"
            )
    gamma, mu, anti = split_multipliers(DG, backward=backward)
    return SymmetricMultipliers(half_map=DG, gamma=gamma, multipliers=mu, antisymmetric=anti,
                                symmetry_error=error, symmetric=symmetric)


def solve_symmetric_orbit(
    flow,
    state0,
    p: np.ndarray,
    *,
    t0: float = 0.0,
    period: float | None = None,
    backward: bool = False,
    tolerances=None,
    tol: float = 1e-12,
    max_iter: int = 30,
) -> tuple[np.ndarray, float, SymmetricMultipliers]:
    """A symmetric periodic orbit as a fixed point of the half-period map, by Newton on ``G(x) - x = 0``.

    Unlike the whole period's map, whose Jacobian ``DG^2 - I`` is singular at a symmetry breaking,
    ``DG - I`` stays regular there (``gamma = -1``), so the symmetric orbits are found, and a symmetry
    breaking located, to full accuracy.  An autonomous orbit's half period is an unknown too, fixed by
    the phase condition ``f(x_start) . (x - x_start) = 0``.

    Parameters
    ----------
    flow : Flow
        The compiled flow of a model that declares a symmetry.
    state0 : array_like, shape (n,)
        The starting guess.
    p : ndarray
        Parameter values.
    t0 : float
        Initial time.
    period : float, optional
        A forced orbit's period (the forcing period by default); an autonomous orbit's starting guess.
    backward : bool
        Shoot in backward time.
    tolerances : Tolerances, optional
        Integration tolerances.
    tol : float
        Newton stops when ``|G(x) - x| <= tol (1 + |x|)``.
    max_iter : int
        Newton iterations at most.

    Returns
    -------
    state : ndarray, shape (n,)
    period : float
    half : SymmetricMultipliers
        Of the orbit found.

    Raises
    ------
    ModelError
        If the model declares no symmetry, or an autonomous orbit has no period guess.
    ConvergenceError
        If Newton does not converge.
    IntegrationError
        If a shot fails.

    References
    ----------
    Stoer and Bulirsch, *Introduction to Numerical Analysis*, Springer, section 7.3 (shooting).
    """
    system = flow.system
    S = symmetry_matrix(system)
    autonomous = system.is_autonomous
    if period is None:
        if autonomous:
            raise ModelError(f"model {system.name!r} is autonomous: give a guess of the orbit's period")
        period = system.forcing_period(p)
    n = system.n
    sign = -1.0 if backward else 1.0
    x = np.array(state0, dtype=float)
    T = float(period)
    f_ref = x_ref = None
    if autonomous:
        x_ref = x.copy()
        f_ref = flow.vector_field(system.initial_mode(x, p, t0), t0, x, p)

    def equations(u: np.ndarray):
        x, T = u[:n], (float(u[n]) if autonomous else float(period))
        traj = half_period_trajectory(flow, x, p, t0=t0, period=T, backward=backward, tolerances=tolerances)
        r = S @ traj.x1 - x
        J = S @ traj.monodromy - np.eye(n)
        if autonomous:
            r = np.append(r, f_ref @ (x - x_ref))
            J = np.block([[J, (0.5 * sign * (S @ traj.velocity_end))[:, None]], [f_ref[None, :], np.zeros((1, 1))]])
        return r, J, traj

    u0 = np.append(x, T) if autonomous else x
    solved = newton(equations, u0, tol=tol, max_iter=max_iter, size=lambda u: float(np.linalg.norm(u[:n])),
                    what=f"symmetric orbit of {system.name!r} (Newton on the half-period map)")
    x = solved.u[:n].copy()
    T = float(solved.u[n]) if autonomous else T
    return x, T, split_half_map(S, solved.extra, x, backward=backward)


def symmetry_breaking_test(gamma: np.ndarray) -> float:
    """A test function that changes sign where a real ``gamma`` passes -1: ``prod(gamma + 1)``, real.

    Complex pairs contribute ``|gamma + 1|^2 > 0``; the result is scaled to stay finite.

    Parameters
    ----------
    gamma : ndarray, complex
        Half-period multipliers.

    Returns
    -------
    float
    """
    value = np.prod(np.asarray(gamma, dtype=complex) + 1.0)
    return float(np.real(value)) / (1.0 + float(np.abs(value)))


__all__ = [
    "CONSISTENCY_TOL", "SYMMETRIC_TOL", "SymmetricMultipliers", "half_period_trajectory", "split_half_map",
    "solve_symmetric_orbit", "split_multipliers", "symmetric_multipliers", "symmetry_breaking_test", "symmetry_matrix",
]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.errors',))
