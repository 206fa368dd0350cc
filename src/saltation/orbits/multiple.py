"""Periodic orbits by multiple shooting: ``m`` segments whose ends match, for orbits whose multipliers are
too large for one shot (Stoer and Bulirsch, section 7.3.5); each segment's transfer matrix carries the
saltation matrices of its events (eq. (9) of *Fold bifurcations in discontinuous systems*).
"""


from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from saltation.engine.flow import (
    EventKind,
    Trajectory,
)
from saltation.errors import (
    ConvergenceError,
    InconsistentResultError,
    ModelError,
    SaltationError,
    StationaryStateError,
)
from saltation.orbits.conditions import Condition, ConditionedProblem, join
from saltation.orbits.floquet import (
    is_stable,
    product_eigenvalues,
    reciprocal,
    sort_multipliers,
)
from saltation.orbits.measures import measure_orbit
from saltation.orbits.problem import BranchProblem, newton
from saltation.orbits.records import (
    BranchPoint,
    Evaluation,
    PeriodicOrbit,
    amplitude_measures,
    event_ids,
    event_labels,
)
from saltation.orbits.single import (
    SEAM_MARGIN,
    TRIVIAL_MULTIPLIER_ACCURACY,
    ShootingProblem,
)

#: The most segments of multiple shooting.  Each segment holds an n x n transfer matrix and costs a variational
#: integration per Newton step, and the Newton system is dense: ``(m n)^2`` numbers, 32 MB for 1000 segments of a
#: model of 2 states (1000 segments bring a multiplier of 1e300 down to 2 per segment: plenty).
MAX_SEGMENTS = 1000
#: The most node values ``m n`` of multiple shooting: its dense Newton matrix of ``(m n)^2`` numbers, 128 MB here.
MAX_NODE_VALUES = 4000


def check_segments(segments, n: int | None = None, name: str = "segments") -> int:
    """The number of shooting segments as an int, or an error that says what it must be.

    Parameters
    ----------
    segments : int
        A positive integer, at most :data:`MAX_SEGMENTS`.
    n : int, optional
        The model's number of states: ``segments * n`` must then be at most :data:`MAX_NODE_VALUES`.
    name : str
        How the message names the argument.

    Returns
    -------
    int

    Raises
    ------
    ModelError
        If ``segments`` is not an integer from 1 to :data:`MAX_SEGMENTS` (not a number, not finite, a
        fraction, a bool), or makes more than :data:`MAX_NODE_VALUES` node values with ``n`` states.
    """
    try:
        whole = not isinstance(segments, bool) and int(segments) == segments
    except (TypeError, ValueError, OverflowError):
        whole = False
    why = (f"each segment holds an n x n transfer matrix and costs an integration per Newton step, and the Newton "
           f"system is dense in the m n node values; {MAX_SEGMENTS} segments bring a multiplier of 1e300 down to 2 "
           f"per segment")
    if not whole or not 1 <= segments <= MAX_SEGMENTS:
        raise ModelError(f"{name} must be a positive integer of at most {MAX_SEGMENTS} ({why}), got {segments!r}")
    segments = int(segments)
    if n is not None and segments * n > MAX_NODE_VALUES:
        raise ModelError(
            f"{name} = {segments} with {n} states makes {segments * n} node values, more than the {MAX_NODE_VALUES} "
            f"multiple shooting takes (its Newton matrix is dense: (m n)^2 numbers); at most "
            f"{MAX_NODE_VALUES // n} segments for this model")
    return segments


class MultipleShootingProblem(BranchProblem):
    """A periodic orbit of a :class:`~saltation.orbits.shooting.ShootingProblem` by ``segments`` segments.

    Single shooting solves ``phi_T(x0) - x0 = 0`` with the monodromy ``M - I`` as its Jacobian.  On an
    orbit with a multiplier of ``1e10`` an error of one rounding unit in ``x0`` grows to ``1e-6`` over
    the period: Newton cannot bring the residual below that, and fails even from the exact state.
    Multiple shooting cuts the period into ``m`` segments of ``T / m`` with nodes ``x_1 .. x_m`` and
    solves

        phi_{T/m}(x_i, t_i) - x_{i+1} = 0,   i = 1 .. m   (x_{m+1} = x_1),

    (and, for an autonomous orbit, the phase condition ``f_ref . (x_1 - x_ref) = 0`` with the period
    ``T`` an unknown), a block-cyclic system whose blocks are the segments' transfer matrices ``Phi_i``
    (each jumped by the saltation matrix of eq. (9) at its events).  The growth over one segment is only
    the ``m``-th root of the period's.

    The monodromy is the product ``M = Phi_m ... Phi_1``.  Its eigenvalues are taken from the factors,
    without forming the product, by the periodic Schur decomposition (SLICOT's MB03VD and MB03WD, through
    slycot): the small multipliers of an orbit with a large one keep their accuracy, which ``eig`` of the
    assembled product loses (to about ``eps |M|``).  For an autonomous orbit each factor is first
    restricted to the normal of the flow at its nodes, ``Q_{i+1}^T Phi_i Q_i``: since ``Phi_i f(x_i) =
    f(x_{i+1})``, this leaves the nontrivial multipliers, and the trivial one is the product of the
    factors' gains along the flow.

    The unknowns are ``U = (x_1, ..., x_m[, T])``; the problem's time direction, ``t0``, tolerances
    and parameters are kept.

    Parameters
    ----------
    problem : ShootingProblem
        The single-shooting problem of the orbit (one forcing period).
    segments : int
        The number of segments ``m`` (at least 1; 1 is single shooting written as this problem), at most
        :data:`MAX_SEGMENTS`, and ``m n`` at most :data:`MAX_NODE_VALUES` (the Newton matrix is dense).

    Raises
    ------
    ModelError
        If ``segments`` is not a positive integer of at most :data:`MAX_SEGMENTS` (and :data:`MAX_NODE_VALUES`
        node values), or ``problem`` closes after several forcing periods.

    References
    ----------
    Stoer and Bulirsch, *Introduction to Numerical Analysis*, Springer, section 7.3.5 (multiple
    shooting).  Bojanczyk, Golub and Van Dooren (1992), "The periodic Schur decomposition: algorithms
    and applications", Proc. SPIE 1770.
    """

    def __init__(self, problem: ShootingProblem, segments: int):
        segments = check_segments(segments, problem.system.n)
        if problem.periods != 1:
            raise ModelError("multiple shooting of an orbit of several forcing periods: give segments for one period")
        self.problem = problem
        self.segments = segments
        self.n = problem.system.n
        # what the continuation engine reads of a problem (the base problem's)
        self.flow, self.system, self.p = problem.flow, problem.system, problem.p
        self.lam_index, self.lam_name = problem.lam_index, problem.lam_name
        self.backward, self.autonomous, self.t0 = problem.backward, problem.autonomous, problem.t0
        self.sign, self.tolerances, self.periods = problem.sign, problem.tolerances, 1
        self._segs: tuple[np.ndarray, float | None, list[Trajectory]] | None = None

    def __repr__(self) -> str:
        return f"MultipleShootingProblem({self.problem!r}, {self.segments} segments)"

    @property
    def mode0(self) -> str | None:
        """The mode the first segment starts in (the single-shooting problem's
        :attr:`~ShootingProblem.mode0`; None: the model's domains give it)."""
        return self.problem.mode0

    @property
    def dimension(self) -> int:
        return self.segments * self.n + (1 if self.problem.autonomous else 0)

    def period_of(self, U: np.ndarray, lam: float | None = None) -> float:
        """The period of the unknowns ``U`` at ``lam``.

        Parameters
        ----------
        U : ndarray
            The nodes (and the period of an autonomous orbit).
        lam : float, optional
            Value of the continuation parameter.

        Returns
        -------
        float
            ``T`` of an autonomous orbit; the forcing period of a forced one.

        Raises
        ------
        ModelError
            If the forcing period is not positive and finite at these parameters.
        """
        return float(U[-1]) if self.problem.autonomous else self.problem.period_of(U[: self.n], lam)

    def _times(self, T: float) -> np.ndarray:
        prob = self.problem
        return prob.t0 + prob.sign * T * np.arange(self.segments + 1) / self.segments

    def pack(self, u: np.ndarray, lam: float | None = None) -> np.ndarray:
        """Nodes from a single-shooting guess ``u = (x0[, T])``: the guess's own trajectory at ``t_i``.

        Parameters
        ----------
        u : ndarray
            The single-shooting guess (:meth:`ShootingProblem.pack`).
        lam : float, optional
            Value of the continuation parameter.

        Returns
        -------
        ndarray
            ``U = (x_1, ..., x_m[, T])``.

        Raises
        ------
        IntegrationError, InitialModeError
            If the guess's trajectory cannot be integrated.
        """
        prob = self.problem
        T = prob.period_of(u, lam)
        p = prob.parameters_at(lam)
        times = self._times(T)
        nodes = [np.asarray(u[: self.n], dtype=float)]
        mode = prob.mode0
        for i in range(self.segments - 1):
            traj = prob.flow.run(nodes[-1], times[i], times[i + 1], p, mode0=mode, tolerances=prob.tolerances)
            nodes.append(traj.x1)
            mode = traj.mode1
        U = np.concatenate(nodes)
        return np.append(U, T) if prob.autonomous else U

    def start_off_surfaces(self, U: np.ndarray, lam: float | None = None, *, sliding_only: bool = False) -> np.ndarray:
        """Nodes of an autonomous orbit moved together along it, so that none lies near a switching event.

        The nodes sit at the fractions ``i / m`` of the period from the first: a node on an event (a clock's
        reset) makes the matching condition jump.  All nodes are moved by the same time ``s`` along the orbit,
        the ``s`` in ``[0, T / m)`` that puts the fewest of them inside a sliding motion (a node there starts
        its segment on the surface) and then keeps them farthest (in time, modulo the period) from every event
        of the period, if the nodes lie within :data:`SEAM_MARGIN` of the period of one now, or inside a sliding
        motion.

        Parameters
        ----------
        U : ndarray
            The nodes ``(x_1, ..., x_m, T)``.
        lam : float, optional
            Value of the continuation parameter.
        sliding_only : bool
            Move the nodes only where one lies inside a sliding motion (the start of
            :func:`find_periodic_orbit`, whose first node is the user's guess where it is not).

        Returns
        -------
        ndarray
            The nodes, moved or not (a forced model's, or an orbit that cannot be integrated, as they are).
        """
        prob = self.problem
        if not prob.autonomous:
            return U
        T = float(U[-1])
        if not (T > 0 and math.isfinite(T)):
            return U
        p = prob.parameters_at(lam)
        x0 = np.asarray(U[: self.n], dtype=float)
        try:
            traj = prob.flow.run(x0, prob.t0, prob.t0 + prob.sign * T, p, mode0=prob.mode0, tolerances=prob.tolerances)
        except SaltationError:
            return U
        events = np.array([abs(e.t - prob.t0) for e in traj.events] + [0.0])  # the period's seam is one too
        offsets = T * np.arange(self.segments) / self.segments
        # the sliding motions' stretches of the period: a node inside one is avoidable where another shift has
        # fewer (a node there lies on the surface, where the shot starts in a sliding motion of its own)
        sliding = []
        for k, e in enumerate(traj.events):
            if e.kind == EventKind.SLIDING_START:
                end = abs(traj.events[k + 1].t - prob.t0) if k + 1 < len(traj.events) else T
                sliding.append((abs(e.t - prob.t0), end))

        def clearance(shift: float) -> float:
            d = np.abs(((offsets[:, None] + shift - events[None, :]) + 0.5 * T) % T - 0.5 * T)
            return float(d.min())

        def in_sliding(shift: float) -> int:
            at = (offsets + shift) % T
            return int(sum(np.count_nonzero((at > a) & (at < b)) for a, b in sliding))

        def score(shift: float) -> tuple[int, float]:
            return (-in_sliding(shift), min(clearance(shift), SEAM_MARGIN * T))

        margin = SEAM_MARGIN * T
        if in_sliding(0.0) == 0 and (sliding_only or clearance(0.0) >= margin):
            return U
        shifts = np.linspace(0.0, T / self.segments, 201)[:-1]
        best = max(shifts, key=lambda s: (score(s), clearance(s)))
        if (score(best), clearance(best)) <= (score(0.0), clearance(0.0)):
            return U
        try:
            moved = prob.flow.run(x0, prob.t0, prob.t0 + prob.sign * best, p, mode0=prob.mode0, tolerances=prob.tolerances)
            if prob.mode0 is not None:
                prob.mode0 = moved.mode1
            return self.pack(np.append(moved.x1, T), lam)
        except SaltationError:
            return U

    def shoot(self, U: np.ndarray, lam: float | None = None, sensitivity: int = -1) -> list[Trajectory]:
        """The segments from the nodes of ``U``, each with its transfer matrix.

        Each segment starts in the mode its predecessor ends in (the first in the problem's
        :attr:`~ShootingProblem.mode0`, or the mode of its state), so that nodes inside a memory mode keep it.

        Parameters
        ----------
        U : ndarray
            The nodes (and the period of an autonomous orbit).
        lam : float, optional
            Value of the continuation parameter.
        sensitivity : int
            Index of the parameter whose sensitivity each segment carries (-1: none).

        Returns
        -------
        list of Trajectory
            The ``m`` segments, with their transfer matrices.

        Raises
        ------
        ConvergenceError
            If the period is not positive and finite (a Newton step threw it away).
        IntegrationError, InitialModeError
            If a segment cannot be integrated.
        """
        prob, n = self.problem, self.n
        T = self.period_of(U, lam)
        if not (T > 0 and math.isfinite(T)):
            raise ConvergenceError(f"the period must be positive and finite, got {T}")
        p = prob.parameters_at(lam)
        times = self._times(T)
        segs: list[Trajectory] = []
        mode = None if prob.mode0 is None else prob.start_mode(U[:n], p)
        for i in range(self.segments):
            x = np.ascontiguousarray(U[i * n:(i + 1) * n])
            traj = prob.flow.run(x, times[i], times[i + 1], p, mode0=mode, variational=True, sensitivity=sensitivity,
                                 tolerances=prob.tolerances)
            segs.append(traj)
            mode = traj.mode1
        return segs

    def residual(self, U: np.ndarray, lam: float | None = None, *, sensitivity: int = -1
                 ) -> tuple[np.ndarray, np.ndarray, list[Trajectory]]:
        """``(r, J, segments)``: the matching equations (and phase condition) and their exact Jacobian.

        Parameters
        ----------
        U : ndarray
            The nodes (and the period of an autonomous orbit).
        lam : float, optional
            Value of the continuation parameter.
        sensitivity : int
            Index of the parameter whose sensitivity each segment carries (-1: none).

        Returns
        -------
        r : ndarray, shape (dimension,)
            The residual.
        J : ndarray, shape (dimension, dimension)
            Its Jacobian by ``U``.
        segments : list of Trajectory
            The segments (:meth:`shoot`).

        Raises
        ------
        ConvergenceError, IntegrationError, InitialModeError
            As :meth:`shoot`.
        StationaryStateError
            If the phase condition would be anchored at an equilibrium.
        """
        prob, n = self.problem, self.n
        segs = self.shoot(U, lam, sensitivity)
        dim = self.dimension
        r = np.zeros(dim)
        J = np.zeros((dim, dim))
        rows, block, _ = self.matching(U, prob.parameters_at(lam), segs)
        r[: len(rows)] = rows
        J[: len(rows), : block.shape[1]] = block
        if prob.autonomous:
            if prob.x_ref is None:
                prob.set_phase_reference(U[:n], lam)
            r[-1] = prob.f_ref @ (U[:n] - prob.x_ref)
            J[-1, :n] = prob.f_ref
        return r, J, segs

    def with_conditions(
        self, conditions: Sequence[Condition], free: Sequence[str], *, continuation: str | None = None,
        parameters: np.ndarray | None = None,
    ) -> ConditionedProblem:
        """The defining system of a special point (or a two-parameter curve of one) by multiple shooting.

        The unknowns are ``(x_1..x_m[, T], freed parameters, the conditions' own)``; each condition is
        read from the segment that holds its instant (see :meth:`ShootingProblem.with_conditions`).

        Parameters
        ----------
        conditions : sequence of Condition
            The conditions that define the point.
        free : sequence of str
            The parameters that become unknowns.
        continuation : str, optional
            The curve's parameter (a two-parameter curve).
        parameters : ndarray, optional
            The parameter values to start from (the problem's own by default).

        Returns
        -------
        ConditionedProblem
            The extended problem.

        Raises
        ------
        ModelError
            If the equations and unknowns do not balance, or a name is not a parameter.
        """
        return ConditionedProblem(self, conditions, free, continuation=continuation, parameters=parameters)

    def matching(self, U: np.ndarray, p: np.ndarray, segs: Sequence[Trajectory],
                 columns: Sequence[tuple[int, Sequence[np.ndarray]]] = ()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The matching equations ``x_i(t_{i+1}) - x_{i+1} = 0``: the one place they are written.

        Parameters
        ----------
        U : ndarray
            The nodes (and the period of an autonomous orbit).
        p : ndarray
            The parameters.
        segs : sequence of Trajectory
            The segments from the nodes, with their transfer matrices.
        columns : sequence of (int, sequence of ndarray)
            Per parameter ``j``: the segments' sensitivities to it.

        Returns
        -------
        r : ndarray, shape (m n,)
            The mismatch at each node.
        J : ndarray, shape (m n, m n [+ 1])
            By the nodes (and the period: segment ``i`` ends at ``t0 + s (i + 1) T / m``).
        jp : ndarray, shape (m n, len(columns))
            By the parameters: ``psi_i + s dT/dp ((i + 1) f(end_i) - i Phi_i f(t_i, x_i)) / m`` where the
            forcing period ``T`` moves with ``p_j`` (both ends of every segment move).
        """
        prob, n, m = self.problem, self.n, self.segments
        nn = m * n
        r = np.zeros(nn)
        J = np.zeros((nn, nn + (1 if prob.autonomous else 0)))
        jp = np.zeros((nn, len(columns)))
        for i, seg in enumerate(segs):
            nxt = (i + 1) % m
            rows = slice(i * n, (i + 1) * n)
            r[rows] = seg.x1 - U[nxt * n:(nxt + 1) * n]
            J[rows, i * n:(i + 1) * n] += seg.monodromy
            J[rows, nxt * n:(nxt + 1) * n] -= np.eye(n)
            if prob.autonomous:
                J[rows, nn] = (prob.sign / m) * seg.velocity_end
            for c, (j, psis) in enumerate(columns):
                jp[rows, c] = psis[i]
                dT = 0.0 if prob.autonomous else prob.system.period_derivative(p, j)
                if dT:
                    f_start = prob.flow.vector_field(seg.mode0, seg.t0, seg.x0, p)
                    jp[rows, c] += (prob.sign * dT / m) * ((i + 1) * seg.velocity_end - i * (seg.monodromy @ f_start))
        return r, J, jp

    # -- the continuation protocol ----------------------------------------------------------
    def parameters_at(self, lam: float | None = None, u: np.ndarray | None = None) -> np.ndarray:
        return self.problem.parameters_at(lam)

    def lam0(self) -> float:
        return self.problem.lam0()

    def rephase(self, u: np.ndarray, lam: float | None) -> np.ndarray | None:
        """The nodes moved off the orbit's events (:meth:`start_off_surfaces`); a forced orbit's stay.

        Parameters
        ----------
        u : ndarray
            The nodes (and the period of an autonomous orbit).
        lam : float or None
            The parameter's value.

        Returns
        -------
        ndarray or None
            The moved nodes; None for a forced orbit.
        """
        return self.start_off_surfaces(u, lam) if self.autonomous else None

    @property
    def section_time(self) -> float:
        return self.problem.section_time

    @property
    def section_settings(self) -> dict:
        return {"mode0": self.problem.mode0}

    def restore_section(self, settings: dict) -> None:
        self.problem.mode0 = settings["mode0"]

    def evaluate(self, U: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        """The matching equations at ``(U, lam)`` with their Jacobians by ``U`` and by ``lam``.

        Segment ``i`` runs from ``t_i = t0 + s i T / m``: where the forcing period ``T`` moves with
        ``lam``, its start and end move too, ``d/dlam = psi_i + s dT/dlam ((i + 1) f(end_i) - i Phi_i
        f(t_i, x_i)) / m``.

        Parameters
        ----------
        U : ndarray
            The nodes (and the period of an autonomous orbit).
        lam : float, optional
            Value of the continuation parameter.
        need_lam : bool
            Compute ``jac_lam`` too.

        Returns
        -------
        Evaluation
            ``residual``, ``jac_u``, ``jac_lam`` and the segments joined into one trajectory.

        Raises
        ------
        ConvergenceError, IntegrationError, InitialModeError
            As :meth:`shoot`.
        StationaryStateError
            If the phase condition would be anchored at an equilibrium.
        """
        pidx = self.lam_index if (need_lam and lam is not None) else -1
        r, J, segs = self.residual(U, lam, sensitivity=pidx)
        jl = None
        if pidx >= 0:
            jl = np.zeros(self.dimension)
            _, _, jp = self.matching(U, self.parameters_at(lam), segs,
                                     [(pidx, [seg.parameter_sensitivity for seg in segs])])
            jl[: len(jp)] = jp[:, 0]
        self._segs = (np.array(U, dtype=float), lam, segs)
        return Evaluation(residual=r, jac_u=J, jac_lam=jl, trajectory=join(segs))

    def describe(self, U: np.ndarray, lam: float | None, ev: Evaluation) -> BranchPoint:
        """A branch point's summary, its multipliers from the segments' matrices (periodic Schur).

        Parameters
        ----------
        U : ndarray
            The solved nodes.
        lam : float or None
            Value of the continuation parameter.
        ev : Evaluation
            Its evaluation (the segments of the last :meth:`evaluate` at ``U`` are reused).

        Returns
        -------
        BranchPoint
            The record a branch keeps.

        Raises
        ------
        StationaryStateError, InconsistentResultError
            As :meth:`orbit`.
        """
        segs = self._segs[2] if self._segs is not None and np.array_equal(self._segs[0], U) else self.shoot(U, lam)
        orbit = self.orbit(U, lam, segs, [0.0])
        traj = orbit.trajectory
        return BranchPoint(
            parameter=math.nan if lam is None else float(lam), state=np.array(U[: self.n]), period=orbit.period,
            multipliers=orbit.multipliers, stable=is_stable(orbit.multipliers, autonomous=self.autonomous),
            event_labels=event_labels(traj), monodromy=traj.monodromy, event_ids=event_ids(traj),
            trivial_error=orbit.trivial_error, mode0=orbit.mode0,
            measures=measure_orbit(self.flow, U[: self.n], orbit.period, self.parameters_at(lam, U), self.measures,
                                   t0=self.t0, mode0=orbit.mode0, backward=self.backward),
            **amplitude_measures(traj),
        )

    def accept(self, U: np.ndarray, lam: float | None) -> None:
        """Called by continuation at every accepted point: re-anchor the phase condition.

        Parameters
        ----------
        U : ndarray
            The accepted nodes.
        lam : float or None
            Value of the continuation parameter.

        Raises
        ------
        StationaryStateError
            If the accepted first node of an autonomous orbit is an equilibrium.
        """
        if self.autonomous:
            self.problem.set_phase_reference(U, lam)

    def solve(self, U0: np.ndarray, lam: float | None = None, *, tol: float = 1e-10, max_iter: int = 30) -> PeriodicOrbit:
        """Newton on the matching equations from the nodes ``U0`` (see :meth:`pack`).

        Parameters
        ----------
        U0 : ndarray
            Guess of the nodes (and the period of an autonomous orbit).
        lam : float, optional
            Value of the continuation parameter.
        tol : float
            Newton tolerance: converged when ``|r| <= tol (1 + |U|)``.
        max_iter : int
            Largest number of Newton iterations.

        Returns
        -------
        PeriodicOrbit
            The orbit, its multipliers from the periodic Schur decomposition.

        Raises
        ------
        ConvergenceError
            With the residual history when Newton fails.
        StationaryStateError, InconsistentResultError
            As :meth:`orbit`.
        IntegrationError, InitialModeError
            When the segments from the guess cannot be integrated.
        """
        prob = self.problem
        U0 = np.asarray(U0, dtype=float)
        if prob.autonomous:
            prob.set_phase_reference(U0[: self.n], lam)

        def fun(U):
            r, J, segs = self.residual(U, lam)
            return r, J, segs

        direction = "backward" if prob.backward else "forward"
        U, history, segs = newton(
            fun, U0, tol=tol, max_iter=max_iter, damped=True,
            what=f"multiple shooting ({self.segments} segments, {direction} time) for {prob.system.name!r}",
        )
        return self.orbit(U, lam, segs, history)

    def multipliers(self, U: np.ndarray, lam: float | None, segs: list[Trajectory]) -> tuple[np.ndarray, float]:
        """Forward-time multipliers from the segments' transfer matrices.

        Parameters
        ----------
        U : ndarray
            The solved nodes.
        lam : float or None
            Value of the continuation parameter.
        segs : list of Trajectory
            The segments, with their transfer matrices.

        Returns
        -------
        multipliers : ndarray, complex
            Forward-time multipliers, by the periodic Schur decomposition of the factors.
        trivial_error : float
            Autonomous orbits: the largest relative error of ``Phi_i f(x_i) = f(x_{i+1})``, the trivial
            direction's consistency (``nan`` for a forced orbit).

        Raises
        ------
        StationaryStateError
            If a node of an autonomous orbit is an equilibrium.
        """
        prob, n = self.problem, self.n
        factors = [seg.monodromy for seg in segs]
        if not prob.autonomous:
            mu = product_eigenvalues(factors)
            return sort_multipliers(reciprocal(mu) if prob.backward else mu), float("nan")
        # each node's velocity is the one the orbit arrives with, the end of the segment before it (where a
        # node lies in a sliding motion or a stick phase, the motion's own field, not its start mode's)
        velocities = [segs[i - 1].velocity_end for i in range(len(segs))]
        bases, normals = [], []
        for f in velocities:
            norm = float(np.linalg.norm(f))
            if not norm > 0:
                raise StationaryStateError(f"a node of the orbit of {prob.system.name!r} is an equilibrium", U[:n])
            q, _ = np.linalg.qr(np.column_stack([f / norm, np.eye(n)]))
            normals.append(f / norm)
            bases.append(q[:, 1:n])
        m = self.segments
        reduced, gain, error = [], 1.0, 0.0
        for i, seg in enumerate(segs):
            j = (i + 1) % m
            image = seg.monodromy @ velocities[i]
            error = max(error, float(np.linalg.norm(image - velocities[j]) / np.linalg.norm(velocities[j])))
            gain *= float(normals[j] @ seg.monodromy @ normals[i])
            reduced.append(bases[j].T @ seg.monodromy @ bases[i])
        nontrivial = product_eigenvalues(reduced) if n > 1 else np.zeros(0, dtype=complex)
        mu = np.append(nontrivial, gain).astype(complex)
        return sort_multipliers(reciprocal(mu) if prob.backward else mu), error

    def orbit(self, U: np.ndarray, lam: float | None, segs: list[Trajectory], history: Sequence[float]) -> PeriodicOrbit:
        """The solved nodes as a :class:`PeriodicOrbit`, its trajectory the segments joined.

        Parameters
        ----------
        U : ndarray
            The solved nodes.
        lam : float or None
            Value of the continuation parameter.
        segs : list of Trajectory
            The segments.
        history : sequence of float
            Newton's residual history.

        Returns
        -------
        PeriodicOrbit
            With its multipliers, segments and nodes.

        Raises
        ------
        StationaryStateError
            If the state does not move over the period, or a node is an equilibrium.
        InconsistentResultError
            If an autonomous orbit's segments do not map the flow direction from node to node within
            :data:`TRIVIAL_MULTIPLIER_ACCURACY`, or (with a start mode) the last segment ends in another
            mode than the first starts in.
        """
        prob, n = self.problem, self.n
        trajectory = join(segs)
        T = self.period_of(U, lam)
        u_single = np.append(U[:n], T) if prob.autonomous else U[:n]
        reason = prob.stationary_reason(u_single, lam, trajectory)
        if reason is not None:
            raise StationaryStateError(reason, U[:n], T)
        prob.check_mode_closes(trajectory)
        mu, trivial_error = self.multipliers(U, lam, segs)
        if prob.autonomous and not trivial_error <= TRIVIAL_MULTIPLIER_ACCURACY:
            raise InconsistentResultError(
                f"the orbit of {prob.system.name!r} by multiple shooting does not map its own flow direction from "
                f"node to node: |Phi_i f_i - f_(i+1)| / |f_(i+1)| = {trivial_error:.2e} > {TRIVIAL_MULTIPLIER_ACCURACY:g}"
            )
        return PeriodicOrbit(
            system_name=prob.system.name, state0=np.array(U[:n]), period=T, t0=prob.t0, backward=prob.backward,
            autonomous=prob.autonomous, parameters=prob.parameters_at(lam), monodromy=trajectory.monodromy,
            multipliers=mu, trajectory=trajectory, converged=True, iterations=max(len(history) - 1, 0),
            residual_norm=float(history[-1]), residuals=list(history), trivial_error=trivial_error, problem=prob,
            segments=self.segments, nodes=np.array(U[: self.segments * n]).reshape(self.segments, n),
            mode0=trajectory.mode0,
        )


__all__ = ["MAX_NODE_VALUES", "MAX_SEGMENTS", "MultipleShootingProblem", "check_segments"]
