"""Periodic orbits that lie on a switching surface along their whole period, and their one-sided limits.

A synchronous whirl of a rotor whose radius equals its clearance, a relay oscillation whose amplitude
equals its threshold: the orbit stays on the surface ``h = 0`` without crossing it, in one mode, and the
next orbit of its branch lies in the other mode (all round it).  No event marks the change; both orbits
have the same trajectory at the boundary (where the field is continuous across the surface), but their
monodromies differ, since the field's Jacobian jumps.  The one-sided limits at the boundary orbit are the
solutions of the variational equation

    Phi' = f_x^{(m)}(t, x(t)) Phi,   Phi(t0) = I,

along the boundary orbit ``x(t)``, with the Jacobian of its own mode (``M-``) and of the mode across the
surface (``M+``).  The set-valued multipliers of eq. (9)'s convex hull ``(1 - q) M- + q M+`` then classify
the point like any corner (Leine and Van Campen, *Fold bifurcations in discontinuous systems*).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

#: an orbit lies on a surface when ``|h|`` stays within this fraction of ``1 + max |x|`` over the period
ON_SURFACE_TOL = 1e-6


@dataclass(frozen=True)
class OrbitOnSurface:
    """A periodic orbit on a switching surface along its whole period.

    Attributes
    ----------
    surface : str
        The surface it lies on.
    mode, other_mode : str
        Its mode, and the mode a transition across the surface enters.
    distance : float
        The largest ``|h|`` over the period.
    """

    surface: str
    mode: str
    other_mode: str
    distance: float


def orbit_on_surface(flow, traj, p: np.ndarray, *, tol: float = ON_SURFACE_TOL) -> OrbitOnSurface | None:
    """The surface an event-free periodic orbit lies on along its whole period, or None.

    Parameters
    ----------
    flow : Flow
        The model's flow.
    traj : Trajectory
        One period of the orbit, with dense output and no events.
    p : ndarray
        Parameter values.
    tol : float
        ``|h| <= tol (1 + max |x|)`` everywhere on the period counts as on the surface.

    Returns
    -------
    OrbitOnSurface or None
        The surface, the orbit's mode and the mode across it (a transition without reset from the orbit's
        mode over that surface), or None when the orbit has events, leaves every surface, or no transition
        without reset crosses the surface it lies on.
    """
    if traj.events:
        return None
    system = flow.system
    _, xs = traj.sample(8)
    ts = np.linspace(traj.t0, traj.t1, len(xs))
    scale = 1.0 + float(np.max(np.abs(xs)))
    mode = traj.mode0
    for tr in system.transitions:
        if tr.source != mode or tr.target == mode or tr.reset is not None:
            continue
        h = np.array([flow.indicator(tr.surface, t, x, p) for t, x in zip(ts, xs)])
        distance = float(np.max(np.abs(h)))
        if distance <= tol * scale:
            return OrbitOnSurface(tr.surface, mode, tr.target, distance)
    return None


def monodromy_in_mode(flow, traj, p: np.ndarray, mode: str, *, rtol: float = 1e-11, atol: float = 1e-13) -> np.ndarray:
    """The solution of the variational equation along an event-free trajectory with one mode's Jacobian.

    Parameters
    ----------
    flow : Flow
        The model's flow.
    traj : Trajectory
        The trajectory (dense output, no events).
    p : ndarray
        Parameter values.
    mode : str
        The mode whose field's Jacobian ``f_x`` is used along the trajectory's states.
    rtol, atol : float
        Tolerances of the variational integration (scipy's DOP853).

    Returns
    -------
    ndarray, shape (n, n)
        ``Phi(t1)`` with ``Phi(t0) = I``.
    """
    n = flow.system.n

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        x = traj.at(np.array([t]))[0]
        return (flow.vector_field_jacobian(mode, t, x, p) @ y.reshape(n, n)).ravel()

    sol = solve_ivp(rhs, (traj.t0, traj.t1), np.eye(n).ravel(), method="DOP853", rtol=rtol, atol=atol)
    return sol.y[:, -1].reshape(n, n)


__all__ = ["ON_SURFACE_TOL", "OrbitOnSurface", "monodromy_in_mode", "orbit_on_surface"]
