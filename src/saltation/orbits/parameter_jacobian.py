"""The parameter Jacobian of a periodic orbit: how its initial state and period move with each parameter.

A periodic orbit solves the periodicity equations ``F(x0[, T], p) = x(t0 + s T; x0, p) - x0 = 0`` (with the
phase condition ``f_ref . (x0 - x_ref) = 0`` of an autonomous orbit, whose period ``T`` is an unknown).
Where their Jacobian ``F_u`` is regular (no multiplier at 1 but the trivial one), the orbit moves smoothly
with every parameter ``q``, and by the implicit function theorem

    d(x0[, T]) / dq = -F_u^-1 F_q,

with ``F_u = [M - I (, s f(end)); f_ref^T (, 0)]`` (``M`` the monodromy, saltation matrices included, eq.
(9)) and ``F_q = psi_q + s dT/dq f(end)``: the engine's parameter sensitivity ``psi_q = dx(end)/dq`` (eq. (9)'s
jumps carried by the sensitivity too, :attr:`~saltation.engine.trajectory.Trajectory.parameter_sensitivity`),
and for a forced orbit the motion of its end with its forcing period.  One integration per parameter, one
factorization for all.  An autonomous orbit's phase is fixed on the section through its own initial state,
normal to the field there: ``d x0 / dq`` is the motion of the orbit's crossing of that section.

:func:`orbit_parameter_jacobian` computes it for a :class:`~saltation.orbits.records.PeriodicOrbit`;
the sensitivities of special points, whose defining systems add conditions to these equations, are
:mod:`saltation.special_points.sensitivity`'s.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from saltation.errors import SaltationError

__all__ = ["SINGULAR", "OrbitParameterJacobian", "orbit_parameter_jacobian"]

#: the periodicity equations' Jacobian is taken as singular (the orbit at a fold or a branch point, where it does
#: not move smoothly with the parameters) where its least singular value is at most this times the size of its
#: entries (or a hundred times the integration's relative error, where that is larger)
SINGULAR = 1e-12


@dataclass(frozen=True)
class OrbitParameterJacobian:
    """The derivatives of a periodic orbit's initial state and period by parameters.

    Attributes
    ----------
    parameter_names : tuple of str
        The parameters, in the order of the columns.
    state : ndarray, shape (n, k)
        ``d x0 / d q`` per parameter (a column each).
    period : ndarray, shape (k,)
        ``d T / d q`` per parameter (a forced orbit's: that of its forcing period).
    accuracy : ndarray, shape (k,)
        An error estimate of each column (its largest entry): the integration error carried through the
        inverse Jacobian, plus rounding.
    condition : float
        The condition number of the periodicity equations' Jacobian.
    """

    parameter_names: tuple[str, ...]
    state: np.ndarray
    period: np.ndarray
    accuracy: np.ndarray
    condition: float

    def column(self, name: str) -> tuple[np.ndarray, float]:
        """The derivatives by one parameter.

        Parameters
        ----------
        name : str
            A parameter of :attr:`parameter_names`.

        Returns
        -------
        d_state : ndarray, shape (n,)
            ``d x0 / d name``.
        d_period : float
            ``d T / d name``.

        Raises
        ------
        KeyError
            If ``name`` is not one of :attr:`parameter_names` (the message lists them).
        """
        if name not in self.parameter_names:
            raise KeyError(f"no derivative by {name!r}: the Jacobian's parameters are {', '.join(self.parameter_names)}")
        j = self.parameter_names.index(name)
        return self.state[:, j].copy(), float(self.period[j])


def orbit_parameter_jacobian(orbit, parameters: Sequence[str] | None = None) -> OrbitParameterJacobian:
    """``d(x0, T) / dq`` of a periodic orbit for each parameter ``q``, by the implicit function theorem.

    Parameters
    ----------
    orbit : PeriodicOrbit
        An orbit found by shooting (:func:`~saltation.orbits.start.find_periodic_orbit`,
        :meth:`~saltation.orbits.single.ShootingProblem.solve`); its ``problem`` gives the flow, the section
        and the tolerances (a multiple-shooting orbit is differentiated by single shooting from its
        ``state0``).
    parameters : sequence of str, optional
        The parameters to differentiate by (every parameter of the model by default).

    Returns
    -------
    OrbitParameterJacobian
        The derivatives of the initial state and the period, their accuracy and the condition number.

    Raises
    ------
    SaltationError
        If the orbit holds no shooting problem (a record built by hand), or its periodicity equations are singular
        (a multiplier at 1 besides the trivial one: a fold or branch point, where the orbit does not move
        smoothly with the parameters).
    ModelError
        If a name is not a parameter of the model.
    IntegrationError
        If the orbit's period cannot be integrated again.

    References
    ----------
    Leine and Van Campen, "Fold bifurcations in discontinuous systems", eq. (9) (the saltation matrices in
    the monodromy).  Hiskens and Pai (2000), "Trajectory sensitivity analysis of hybrid systems", IEEE
    Trans. Circuits Syst. I 47 (the jumps of the parameter sensitivities at events).
    """
    problem = getattr(orbit, "problem", None)
    if problem is None:
        raise SaltationError("the orbit holds no shooting problem (a record built by hand): find it with "
                             "find_periodic_orbit or ShootingProblem.solve")
    # (multiple shooting: its single-shooting problem, from the orbit's first node)
    single = problem.single_shooting if problem.single_shooting is not None else getattr(problem, "problem", None)
    if single is None or not hasattr(single, "periodicity"):
        raise SaltationError(f"the orbit's problem ({type(problem).__name__}) is not one of shooting periodic orbits")
    single = copy.copy(single)
    system, flow = single.system, single.flow
    names = tuple(system.parameter_names if parameters is None else parameters)
    columns = [system.parameter_index(name) for name in names]
    p = np.asarray(orbit.parameters, dtype=float)
    x0 = np.asarray(orbit.state0, dtype=float)
    T = float(orbit.period)
    single.t0 = float(orbit.t0)
    mode0 = orbit.mode0 if orbit.mode0 is not None else single.mode0
    sensitivities, traj = {}, None
    for j in columns or [-1]:
        run = flow.run(x0, single.t0, single.t0 + single.sign * T, p, mode0=mode0, variational=True, sensitivity=j,
                       tolerances=single.tolerances)
        traj = single.close_period(run, p, j)
        if j >= 0:
            sensitivities[j] = traj.parameter_sensitivity
    n = system.n
    if single.autonomous:
        single.mode0 = mode0
        single.anchor_phase(x0, p)  # the section through the orbit's own state, normal to the field there
    _, J, jp = single.periodicity(x0, traj, p, sensitivities)
    # the entries of J and F_q are known to the integration's relative error (J's to that of the monodromy
    # and the field it is made of): J is singular where its least singular value is no more than that
    relative = flow.integration_error(traj, single.tolerances) / (1.0 + float(np.abs(traj.x1).max())) + 1e-15
    singular_values = np.linalg.svd(J, compute_uv=False)
    scale = 1.0 + float(np.abs(traj.monodromy).max()) + (float(np.abs(traj.velocity_end).max()) if single.autonomous else 0.0)
    condition = float(singular_values[0] / singular_values[-1]) if singular_values[-1] > 0 else float("inf")
    if not singular_values[-1] > max(SINGULAR, 100.0 * relative) * scale:
        raise SaltationError(
            f"the periodicity equations of the orbit are singular (least singular value {singular_values[-1]:.1e} of "
            f"a Jacobian of entries up to {scale:.3g}): a multiplier is at 1 (the monodromy's eigenvalues "
            f"{', '.join(f'{complex(m):.6g}' for m in np.linalg.eigvals(traj.monodromy))}), so the orbit is at a "
            "fold or branch point and does not move smoothly with the parameters")
    inverse = np.linalg.inv(J)
    v = -inverse @ jp if columns else np.zeros((J.shape[0], 0))
    # their errors carried through J^-1
    bound = np.abs(inverse) @ (relative * (np.abs(J) @ np.abs(v) + np.abs(jp))) if columns else np.zeros((J.shape[0], 0))
    if single.autonomous:
        period = v[n].copy()
    else:
        period = np.array([single.periods * system.period_derivative(p, j) for j in columns])
    accuracy = bound.max(axis=0) + 4e-16 * np.maximum(1.0, np.abs(v).max(axis=0)) if columns else np.zeros(0)
    return OrbitParameterJacobian(parameter_names=names, state=v[:n].copy(), period=period,
                                  accuracy=accuracy, condition=condition)
