"""A conditioned problem's equations under multiple shooting, as functions of the problem they are handed.

The orbit's rows are the matching equations of the segments (the base problem's,
:meth:`saltation.orbits.multiple.MultipleShootingProblem.matching`) and, unless a condition fixes the
phase, the phase condition.  Each condition answers through :meth:`Condition.segmented_rows`: by
default it is read from the segment that holds its instant, its derivatives by that segment's node.

A segment ``i`` starts at ``t_i = t0 + s i T / m``: where ``T`` moves (an autonomous orbit's unknown
period, a forcing period that depends on a parameter), so does ``x(t)`` at a fixed instant ``t`` of the
segment, by ``-Phi(t, t_i) f(t_i, x_i) dt_i``; the rows by one node get that term.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from saltation.engine.flow import Trajectory
from saltation.errors import ConvergenceError
from saltation.orbits.conditions.base import Resplit
from saltation.orbits.conditions.joining import _joined, join
from saltation.orbits.conditions.shot import Piece, Rows, Segments, Shot, segment_of

# The annotations name ConditionedProblem without importing it: its module imports this one.


def equations(problem: ConditionedProblem, u: np.ndarray, lam: float | None, *, need_lam: bool = True  # noqa: F821
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, Segments, list[Shot]]:
    """Residual, ``d/du`` and ``d/dlam`` of a conditioned problem with multiple shooting.

    Parameters
    ----------
    problem : ConditionedProblem
        The problem, on a multiple-shooting base problem.
    u : ndarray
        The unknowns (every node first).
    lam : float or None
        Value of the curve's parameter.
    need_lam : bool
        Compute ``d/dlam`` too.

    Returns
    -------
    r : ndarray, shape (dimension,)
        The residual: the matching equations, the phase condition, then each condition's.
    J : ndarray, shape (dimension, dimension)
        Its Jacobian by ``u``.
    jl : ndarray or None
        Its derivative by ``lam`` (None without ``lam`` or ``need_lam``).
    segments : Segments
        The period shot in segments.
    shots : list of Shot
        The shot each condition was read from.

    Raises
    ------
    ConvergenceError
        If the period is not positive and finite, or the shot cannot be split before a condition's
        event.
    SaltationError
        If a condition cannot be evaluated or a run fails (an :class:`IntegrationError`).
    """
    p, T, params, extras = problem._point(u, lam, need_lam)
    m = problem.segments
    U = np.ascontiguousarray(u[: problem.n_nodes])
    times = problem.t0 + problem.sign * T * np.arange(m + 1) / m
    split = problem._split_time(extras)
    for _ in range(3):
        by_column, segments = shoot(problem, U, T, p, params, times, split)
        try:
            placed = [c.segmented_rows(segments, e, params) for c, e in zip(problem.conditions, extras)]
            break
        except Resplit as again:
            split = again.t
    else:
        raise ConvergenceError("the shot could not be split before the condition's event")
    r, J, jl = _orbit_rows(problem, segments, by_column, params)
    _condition_rows(problem, segments, params, placed, r, J, jl)
    return r, J, jl, segments, [segments.shot(0 if i is None else i) for i, _ in placed]


def shoot(problem: ConditionedProblem, U: np.ndarray, T: float, p: np.ndarray, params: Sequence[int],  # noqa: F821
          times: np.ndarray, split: float | None) -> tuple[list[list[Trajectory]], Segments]:
    """Every segment, one run per parameter of ``params``, the one that holds ``split`` split there.

    Parameters
    ----------
    problem : ConditionedProblem
        The problem.
    U : ndarray, shape (m n,)
        The nodes.
    T : float
        The period.
    p : ndarray
        Parameter values.
    params : sequence of int
        Indices of the parameters whose sensitivities to carry (one run of every segment each).
    times : ndarray, shape (m + 1,)
        The segments' bounds.
    split : float or None
        The instant to split the shot at (ignored outside the period).

    Returns
    -------
    by_column : list of list of Trajectory
        Per parameter column (one list without parameters), the segments.
    segments : Segments
        The first column's segments as conditions read them.

    Raises
    ------
    IntegrationError, ModelError, InitialModeError
        If a run fails (see :meth:`Flow.run`).
    """
    n, m = problem.system.n, problem.segments
    flow, tol, disabled = problem.flow, problem.tolerances, problem.disabled
    split_seg = None if split is None else segment_of(split, times)
    by_column: list[list[Trajectory]] = []
    pieces: dict[int, Trajectory] = {}
    for j in params or [-1]:
        mode, row = problem.mode0, []
        for i in range(m):
            x = np.ascontiguousarray(U[i * n:(i + 1) * n])
            if i == split_seg and min(times[i], times[i + 1]) < split < max(times[i], times[i + 1]):
                a = flow.run(x, times[i], split, p, mode0=mode, variational=True, sensitivity=j,
                             disabled=disabled, tolerances=tol)
                b = flow.run(a.x1, split, times[i + 1], p, mode0=a.mode1, variational=True, sensitivity=j,
                             phi0=a.monodromy, psi0=a.parameter_sensitivity if j >= 0 else None,
                             disabled=disabled, tolerances=tol)
                traj = _joined(a, b)
                pieces[j] = a
            else:
                traj = flow.run(x, times[i], times[i + 1], p, mode0=mode, variational=True, sensitivity=j,
                                disabled=disabled, tolerances=tol)
            row.append(traj)
            mode = traj.mode1
        by_column.append(row)
    first = by_column[0]
    piece = None
    if split_seg is not None and pieces:
        a0 = pieces[(params or [-1])[0]]
        piece = Piece(t=float(a0.t1), x=a0.x1, mode=a0.mode1, fundamental=a0.monodromy,
                      sensitivities={j: pieces[j].parameter_sensitivity for j in params},
                      sliding=a0.sliding_at_end, velocity=a0.velocity_end)
    whole = problem._shot(np.array(U[:n]), T, p, join(first), {}, None)
    return by_column, Segments(whole=whole, nodes=U, times=times, trajectories=first, piece=piece, split=split_seg)


def _orbit_rows(problem: ConditionedProblem, segments: Segments, by_column: list[list[Trajectory]],  # noqa: F821
                params: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The residual and Jacobians with the orbit's rows filled: matching, then the phase condition."""
    n, nodes_n, nb, k = problem.system.n, problem.n_nodes, problem.n_base, len(problem.free)
    U, p = segments.nodes, segments.whole.parameters
    dim = problem.dimension
    r, J = np.zeros(dim), np.zeros((dim, dim))
    rows_m, block, jp = problem.base.matching(
        U, p, segments.trajectories,
        [(j, [seg.parameter_sensitivity for seg in by_column[c]]) for c, j in enumerate(params)])
    r[:nodes_n] = rows_m
    J[:nodes_n, : block.shape[1]] = block
    if problem.n_orbit_rows > nodes_n:  # the phase condition (unless a condition fixes the phase)
        single = problem.single
        if single.x_ref is None:
            single.anchor_phase(U[:n].copy(), p)
        r[nodes_n] = single.f_ref @ (U[:n] - single.x_ref)
        J[nodes_n, :n] = single.f_ref
    J[:nodes_n, nb:nb + k] = jp[:, :k]
    jl = np.append(jp[:, k], np.zeros(dim - nodes_n)) if len(params) > k else None
    return r, J, jl


def _condition_rows(problem: ConditionedProblem, segments: Segments, params: Sequence[int],  # noqa: F821
                    placed: list[tuple[int | None, Rows]], r: np.ndarray, J: np.ndarray, jl: np.ndarray | None
                    ) -> None:
    """Fill the conditions' rows of ``r``, ``J`` and ``jl`` (in place), each by its segment's node or by every node."""
    n, m, nodes_n, nb, k = problem.system.n, problem.segments, problem.n_nodes, problem.n_base, len(problem.free)
    p, times = segments.whole.parameters, segments.times
    row, col = problem.n_orbit_rows, nb + k
    for c, (i, b) in zip(problem.conditions, placed):
        rows = slice(row, row + c.size)
        r[rows] = b.value
        if i is None:  # by every node
            J[rows, :nodes_n] = b.d_x0
            if problem.autonomous:
                J[rows, nodes_n] = b.d_period
            dp = b.d_parameters
        else:
            J[rows, i * n:(i + 1) * n] = b.d_x0
            # the segment's start moves with T: x(t) at a fixed t moves by -Phi f(t_i, x_i) dt_i
            f_i = problem.flow.vector_field(segments.trajectories[i].mode0, float(times[i]),
                                            np.array(segments.nodes[i * n:(i + 1) * n]), p)
            moves = -(b.d_x0 @ f_i) * (problem.sign * i / m)
            dp = b.d_parameters.copy()
            if problem.autonomous:
                J[rows, nodes_n] = b.d_period + moves
            else:
                for cc, j in enumerate(params):
                    dp[:, cc] += moves * problem.periods * problem.system.period_derivative(p, j)
        J[rows, nb:nb + k] = dp[:, :k]
        J[rows, col:col + c.extras] = b.d_extra
        if jl is not None:
            jl[rows] = dp[:, k]
        row += c.size
        col += c.extras


__all__ = ["equations", "shoot"]
