"""Sliding bifurcations of periodic orbits in Filippov systems.

Where a periodic orbit's sequence of events changes by a sliding segment, the
change is one of the four codimension-one sliding bifurcations (di Bernardo,
Kowalczyk and Nordmark, Physica D 170, 2002; Kuznetsov, Rinaldi and
Gragnani, Int. J. Bif. Chaos 13, 2003):

* grazing-sliding: the orbit grazes the switching surface at the boundary of
  the sliding region (one side misses the surface, the other slides for a
  moment).  Located by the grazing defining system of
  :mod:`saltation.grazing` with the transition into sliding disabled;
* crossing-sliding: the orbit reaches the surface exactly at the boundary of
  the sliding region where the far side's field ``f_B`` is tangent to it.  On
  one side it starts sliding at once; on the other it first crosses into
  ``B`` and comes back to slide.  Located here by periodicity plus
  ``h_x f_B = 0`` at the point where the sliding starts;
* switching-sliding and adding-sliding (a sliding motion that ends at a
  tangency where the orbit then grazes or crosses the surface again) are not
  recognised yet.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ConvergenceError, ModelError
from .grazing import location_tolerances
from .integrate import EventKind, Flow, SwitchingEvent, Trajectory


@dataclass(frozen=True)
class CrossingSliding:
    """A located crossing-sliding orbit.

    Attributes
    ----------
    parameter : float
    state0 : ndarray
        The orbit's state at ``t0`` (it starts sliding at ``t_hit``, exactly where ``f_B`` is tangent).
    t_hit : float
    x_hit : ndarray
    far_mode : str
        The mode ``B`` whose field is tangent to the surface there.
    accuracy : float
        The Newton correction of the parameter that would follow, plus the
        integration error carried to the parameter (an error estimate).
    residuals : list of float
    trajectory : Trajectory
    """

    parameter: float
    state0: np.ndarray
    t_hit: float
    x_hit: np.ndarray
    far_mode: str
    accuracy: float
    residuals: list[float]
    trajectory: Trajectory


def crossing_sliding_change(without: Trajectory, with_: Trajectory) -> tuple[int, SwitchingEvent] | None:
    """Recognise a crossing-sliding change between two orbits.

    ``with_`` has one event more: a crossing of a surface into a mode ``B``,
    right before the start of a sliding motion on the same surface, where
    ``without`` starts sliding at once.  Returns ``(index of the sliding start
    in without's events, the crossing in with_)`` or None.
    """
    ev_wo, ev_w = without.events, with_.events
    if len(ev_w) != len(ev_wo) + 1:
        return None
    for i, e in enumerate(ev_w[:-1]):
        nxt = ev_w[i + 1]
        if e.kind == EventKind.TRANSITION and nxt.kind == EventKind.SLIDING_START and nxt.surface == e.surface:
            rest = ev_w[:i] + ev_w[i + 1:]
            same = all(a.kind == b.kind and a.surface == b.surface for a, b in zip(rest, ev_wo))
            if same and ev_wo[i].kind == EventKind.SLIDING_START:
                return i, e
    return None


def locate_crossing_sliding(
    flow: Flow, x0: np.ndarray, lam: float, lam_name: str, index: int, far_mode: str, *, parameters=None,
    t0: float = 0.0, tol: float = 1e-12, max_iter: int = 20, fd_step: float = 1e-7, tolerances=None,
) -> CrossingSliding:
    """Newton's method on periodicity plus ``h_x f_B + h_t = 0`` where the orbit starts sliding.

    ``index`` is the position of that sliding start among the orbit's events
    (on the other side of the bifurcation, the crossing into ``B`` takes its
    place: the same arrival at the surface); the derivatives of the tangency
    condition are taken by central differences.

    Raises
    ------
    ConvergenceError
        If Newton does not converge, or the orbit's events change along the way.
    ModelError
        For an autonomous model.
    """
    system = flow.system
    tolerances = location_tolerances(flow, tolerances)
    if system.is_autonomous:
        raise ModelError(f"locating a crossing-sliding is implemented for forced models; {system.name!r} is autonomous")
    j = system.parameter_index(lam_name)
    p = flow.parameters(parameters).copy()
    n = system.n
    history: list[float] = []

    def tangency(z: np.ndarray) -> tuple[float, Trajectory]:
        q = p.copy()
        q[j] = z[-1]
        traj = flow.run(z[:n], t0, t0 + system.forcing_period(q), q, tolerances=tolerances)
        # the orbit's arrival at the surface: the start of sliding on one side of the bifurcation, the
        # crossing into B on the other (the same point, continuous across it)
        if len(traj.events) <= index or traj.events[index].kind == EventKind.SLIDING_END:
            raise ConvergenceError("crossing-sliding: the orbit's events changed during the iteration", history)
        e = traj.events[index]
        hx, ht, _ = flow.indicator_gradient(e.surface, e.t, e.x_minus, q)
        return float(hx @ flow.vector_field(far_mode, e.t, e.x_minus, q) + ht), traj

    z = np.append(np.asarray(x0, dtype=float), float(lam))
    for it in range(max_iter + 1):
        q = p.copy()
        q[j] = z[-1]
        T = system.forcing_period(q)
        full = flow.run(z[:n], t0, t0 + T, q, variational=True, parameter=j, tolerances=tolerances)
        c, traj = tangency(z)
        residual = np.append(full.x1 - z[:n], c)
        rn = float(np.linalg.norm(residual))
        history.append(rn)
        J = np.zeros((n + 1, n + 1))
        J[:n, :n] = full.monodromy - np.eye(n)
        J[:n, n] = full.parameter_sensitivity + system.period_derivative(q, j) * full.velocity_end
        for i in range(n + 1):
            step = fd_step * max(1.0, abs(z[i]))
            e = np.zeros(n + 1)
            e[i] = step
            J[n, i] = (tangency(z + e)[0] - tangency(z - e)[0]) / (2 * step)
        dz = np.linalg.solve(J, -residual)
        if rn <= tol * (1.0 + float(np.linalg.norm(z))):
            hit = traj.events[index]
            carried = float(np.abs(np.linalg.inv(J)[-1]).sum()) * flow.integration_error(full, tolerances)
            return CrossingSliding(
                parameter=float(z[-1]), state0=z[:n].copy(), t_hit=hit.t, x_hit=hit.x_minus.copy(), far_mode=far_mode,
                accuracy=abs(float(dz[-1])) + carried + 4e-16 * max(1.0, abs(float(z[-1]))), residuals=history,
                trajectory=full,
            )
        if it == max_iter:
            break
        z = z + dz
    raise ConvergenceError("crossing-sliding did not converge", history)


__all__ = ["CrossingSliding", "crossing_sliding_change", "locate_crossing_sliding"]
