"""The engine's Newton on periodic orbits (``correct_periodic``): the shooting loop run without a return to
Python per shot.

:func:`compiled_newton` runs it on a :class:`~saltation.engine.flow.Flow`'s model (what it solves is the
shooting layer's business, :mod:`saltation.orbits.shooting`), :class:`CompiledNewton` is its outcome and
:func:`shot_trajectory` the trajectory of its last shot.  :class:`~saltation.engine.flow.Flow` keeps
:meth:`~saltation.engine.flow.Flow.compiled_newton` and :meth:`~saltation.engine.flow.Flow.shot_trajectory`,
which call these.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from saltation.engine import _contract as kc
from saltation.engine.trajectory import _STATUS_OK, Trajectory, unpack_result
from saltation.model.system import PiecewiseSystem

_Flow = Any  # a saltation.engine.flow.Flow (which imports this module)
_Tolerances = Any  # a saltation.engine.flow.Tolerances


@dataclass(frozen=True)
class CompiledNewton:
    """The outcome of the kernel's Newton loop (:func:`compiled_newton`).

    Attributes
    ----------
    code : int
        ``SHOOT_*`` of :mod:`saltation.engine._contract` (``converged``, ``bad_period``...).
    iterations : int
    z : ndarray
        The last iterate.
    history : list of float
        Residual norms.
    jacobian : ndarray
        ``[r | J_u | J_lam]`` at ``z`` (rows of the periodicity and phase conditions).
    shot : tuple
        The kernel's packed result of the shot from ``z`` (read by :func:`shot_trajectory`).
    tangent : ndarray or None
        The bordered system only: ``t`` with ``[[J_u, J_lam], [normal]] t = e_last`` at the converged ``z``,
        not normalised (the next tangent of pseudo-arclength continuation, whose ``normal`` is the last
        tangent); None for the period map alone, or where the matrix is singular or Newton has not converged.
    """

    code: int
    iterations: int
    z: np.ndarray
    history: list[float]
    jacobian: np.ndarray
    shot: tuple = field(repr=False)
    tangent: np.ndarray | None = field(default=None, repr=False)

    @property
    def converged(self) -> bool:
        return self.code == kc.SHOOT_CONVERGED

    @property
    def unsupported(self) -> bool:
        """A period that is not positive, a singular Newton matrix, or a shot that stopped where impacts accumulate
        (complete chatter, which :meth:`~saltation.engine.flow.Flow.run` jumps and the kernel's loop does not):
        iterate in Python (for the reason, or through the accumulation)."""
        return (self.code in (kc.SHOOT_BAD_PERIOD, kc.SHOOT_SINGULAR)
                or int(self.shot[0][kc.INFO_STATUS]) == kc.STATUS_ACCUMULATION)


def compiled_newton(
    flow: _Flow, z0: np.ndarray, normal: np.ndarray | None, p: np.ndarray, *, t0: float, sign: float, lam_index: int,
    span: float, phase: tuple[np.ndarray, np.ndarray] | None, tol: float, max_iter: int, max_correction: float,
    damped: bool, tolerances: _Tolerances | None = None,
) -> CompiledNewton | None:
    """Run the kernel's Newton loop on periodic orbits (no return to Python per shot).

    The loop is compiled with the integrator it calls; what it solves is
    the shooting layer's business (:mod:`saltation.orbits.shooting`): the period
    map at a fixed span (``normal`` None, ``damped``), or the bordered
    pseudo-arclength system of ``z = (x0[, T], lam)`` (``span`` 0: the
    forcing period follows ``lam``; ``phase = (x_ref, f_ref)`` for
    autonomous orbits).

    Parameters
    ----------
    flow : Flow
        The flow whose engine runs the loop (its model, tolerances and transition table).
    z0 : ndarray
        Initial iterate: ``x0`` (and ``T`` for an autonomous orbit), then ``lam`` for the bordered
        system.
    normal : ndarray or None
        The pseudo-arclength row of the bordered system (None: the period map at a fixed ``lam``).
    p : ndarray, shape (n_params,)
        Parameter values (the continuation parameter's entry is taken from ``z``).
    t0 : float
        Initial time of every shot.
    sign : float
        +1 to shoot forward in time, -1 backward.
    lam_index : int
        Index of the continuation parameter.
    span : float
        The length of a shot of a forced orbit at fixed parameters (0: the forcing period at ``lam``).
    phase : tuple of ndarray or None
        ``(x_ref, f_ref)``, the phase condition of an autonomous orbit.
    tol : float
        Newton tolerance: converged when ``|r| <= tol (1 + |u|)``.
    max_iter : int
        Largest number of iterations.
    max_correction : float
        The bordered loop stops when a correction exceeds ``max_correction (1 + |z|)``.
    damped : bool
        Newton on the period map at a fixed ``lam`` (``normal`` unused), each step halved (up to 8
        times) until the residual decreases; False: the bordered pseudo-arclength system.
    tolerances : Tolerances, optional
        Integration tolerances (the flow's by default).

    Returns
    -------
    CompiledNewton or None
        The loop's outcome (its ``code`` says whether it converged, and why not), or None when the
        kernel cannot run the problem (a forcing period given as a Python callable).
    """
    if span == 0.0 and phase is None and not isinstance(flow.system, PiecewiseSystem):
        return None  # the forcing period is a Python callable
    steps, limits, flags = flow._kernel_tolerances(tolerances or flow.tolerances, _c_array(p))
    x_ref, f_ref = (_c_array(a) for a in phase) if phase is not None else (flow._zeros, flow._zeros)
    z0 = _c_array(z0)
    code, it, packed, *out = flow._engine.correct_periodic(
        flow._addresses, flow._affine_modes, z0, flow._zeros if normal is None else _c_array(normal), float(t0), float(sign),
        bool(phase is not None), int(lam_index), float(span), _c_array(p), x_ref, f_ref,
        float(tol), int(max_iter), float(max_correction), bool(damped), *steps, *limits, flow._table,
        flow._n_surfaces, flow._identity, flow._zeros, *flags,
    )
    m_u = len(z0) - (0 if normal is None else 1)
    z, history, jac, tangent = _newton_unpack(packed, len(z0), m_u)
    return CompiledNewton(code=int(code), iterations=int(it), z=z, history=history.tolist(), jacobian=jac,
                          shot=out, tangent=tangent if tangent.size and tangent.any() else None)



def shot_trajectory(flow: _Flow, result: CompiledNewton, x0: np.ndarray, t0: float, p: np.ndarray, sensitivity: int) -> Trajectory:
    """The trajectory of the last shot of :func:`compiled_newton`.

    Parameters
    ----------
    flow : Flow
        The flow that ran it.
    result : CompiledNewton
        The outcome of :func:`compiled_newton`.
    x0 : ndarray, shape (n,)
        The initial state of that shot.
    t0 : float
        Its initial time.
    p : ndarray, shape (n_params,)
        Its parameter values.
    sensitivity : int
        Index of the parameter whose sensitivity the shot carried (-1: none).

    Returns
    -------
    Trajectory
        The shot, with its monodromy (no dense output).

    Raises
    ------
    IntegrationError
        The error of the shot, if it failed (as :meth:`~saltation.engine.flow.Flow.run` raises it: a subclass such as
        :class:`ChatteringError`, or :class:`ModelError` for a state outside every domain).
    InitialModeError
        If the shot failed and ``x0`` lies in no mode's domain.
    """
    ok = int(result.shot[0][kc.INFO_STATUS]) == _STATUS_OK
    # the shot's initial mode; after a failure the rule itself, which raises for a state in no mode
    m0 = int(result.shot[0][kc.INFO_INITIAL_MODE]) if ok else flow.initial_mode(x0, p, t0)
    return unpack_result(flow.system, result.shot, x0, float(t0), m0, True, sensitivity, False)


def _c_array(a) -> np.ndarray:
    """``a`` as the engine and the model functions take arrays (their signatures are fixed): float64,
    C-contiguous and writeable, copied only when it is not already."""
    if type(a) is np.ndarray and a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable:
        return a  # the common case, without np.require's general checks (a few microseconds a call)
    return np.require(a, dtype=np.float64, requirements=("C", "W"))


def _newton_unpack(packed: np.ndarray, m_z: int, m_u: int) -> tuple[np.ndarray, ...]:
    """The kernel Newton's packed result: ``z``, the residual history, ``[r | J_u | J_lam]`` (``m_u`` rows)
    and the bordered system's tangent direction (``m_z`` entries, none for the period map alone), laid out
    as the contract's ``newton_layout`` says."""
    bordered = m_z > m_u
    n_history = packed.size - kc.newton_layout(m_z, m_u, 0, bordered)[3]
    o_history, o_jac, o_tangent, _ = kc.newton_layout(m_z, m_u, n_history, bordered)
    return (packed[:m_z], packed[o_history:o_jac], packed[o_jac:o_tangent].reshape(m_u, m_u + 2), packed[o_tangent:])


__all__ = ["CompiledNewton", "compiled_newton", "shot_trajectory"]
