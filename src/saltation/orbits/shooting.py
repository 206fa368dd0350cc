"""Periodic solutions by shooting, and equilibria, as problems ``r(u, lambda) = 0``.

A shooting problem exposes the residual of the period map and its exact
Jacobian (the monodromy matrix, with every saltation matrix applied) through
the small protocol that :mod:`saltation.branches.continuation` uses:
``evaluate(u, lam) -> Evaluation(residual, jac_u, jac_lam, ...)``.

* Forced systems: ``u = x0``, period ``T`` fixed by the forcing,
  ``r = phi(t0 + s T; t0, x0) - x0`` with ``s = +1`` (forward) or ``-1``
  (backward time).
* Autonomous systems: ``u = (x0, T)``, the same residual closed by the phase
  condition ``f(x_ref) . (x0 - x_ref) = 0``.

Degenerate cases, each with its rule (see the orbits page of the user guide):

* the guess lies on (or next to) a switching surface: the shooting state is
  moved along the guess's own trajectory to the middle of its longest stretch
  between events, so that the section (the phase condition) is transverse to
  the flow and away from every surface;
* a shot that ends on a surface, in the mode the transition out of it leads
  away from the start mode, gets that transition applied at the end of the
  period (its reset and saltation matrix): every event is logged once per period;
* a state that does not move over the period (an equilibrium, a
  pseudo-equilibrium, a period shrunk to zero) raises
  :class:`~saltation.errors.StationaryStateError`;
* an autonomous orbit whose monodromy does not map the flow direction to itself
  (trivial multiplier off by more than :data:`TRIVIAL_MULTIPLIER_ACCURACY`)
  raises :class:`~saltation.errors.InconsistentResultError`;
* forced systems integrate from ``t0`` reduced modulo the forcing period,
  autonomous ones from ``t = 0``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from saltation.engine.flow import (
    EventKind,
    Flow,
    SwitchingEvent,
    Tolerances,
    Trajectory,
)
from saltation.errors import (
    ConvergenceError,
    InconsistentResultError,
    IntegrationError,
    ModelError,
    NoOrbitNearGuessError,
    SaltationError,
    StationaryStateError,
)
from saltation.model.system import PiecewiseSystem
from saltation.orbits.conditions import Condition, ConditionedProblem, join
from saltation.orbits.floquet import (
    autonomous_multipliers,
    is_stable,
    multipliers_from_monodromy,
    product_eigenvalues,
    reciprocal,
    sort_multipliers,
)
from saltation.orbits.problem import BranchProblem, newton
from saltation.orbits.start import starting_guess_and_mode
from saltation.orbits.records import (
    Evaluation,
    BranchPoint,
    SolutionSummary,
    amplitude_measures,
    event_ids,
    event_labels,
)

#: The largest error of an autonomous orbit's trivial multiplier (``|M n - n|``, see
#: :func:`saltation.orbits.floquet.autonomous_multipliers`) that a converged orbit may have.
TRIVIAL_MULTIPLIER_ACCURACY = 1e-6
#: An event closer than this fraction of the period to the start of the shooting interval moves the
#: shooting state of a guess (or of a branch's orbit) to the middle of its longest stretch between events.
SEAM_MARGIN = 0.02
#: A state whose excursion over the period is below this many times the integration tolerance does not move.
STATIONARY_FACTOR = 100.0
#: ... nor above this fraction of the state's scale ``1 + max |x_i|``: the cap applies from ``rtol = 1e-7`` on.  A
#: stationary state's excursion is what rounding and Newton's tolerance leave, whatever the integration tolerance;
#: at ``rtol = 1e-2``, 100 times the tolerance is the size of the orbits themselves.
STATIONARY_FRACTION = 1e-5
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


#: Newton steps of an autonomous orbit that make the period longer than this many times its guess are
#: shortened (as steps that do not reduce the residual): a period near zero can throw the next iterate far away.
PERIOD_GROWTH = 100.0


#: the kernel's event kinds as plain integers (an Enum member costs an attribute lookup in a hot path)
_TRANSITION, _SLIDING_START, _SLIDING_END = (int(EventKind.TRANSITION), int(EventKind.SLIDING_START),
                                             int(EventKind.SLIDING_END))


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic solution found by shooting.

    Attributes
    ----------
    system_name : str
        Name of the model.
    state0 : ndarray, shape (n,)
        State at ``t0`` on the orbit.
    period : float
        The period (a forced orbit's is its forcing period).
    t0 : float
        Initial time (a forced orbit's phase of the forcing).
    backward : bool
        Whether the orbit was computed in backward time.
    autonomous : bool
        Whether the model is autonomous.
    parameters : ndarray
        Parameter values.
    monodromy : ndarray, shape (n, n)
        Monodromy in the direction of integration.
    multipliers : ndarray, complex
        Forward-time Floquet multipliers (``inf`` for an infinitely unstable direction).
    trajectory : Trajectory
        One period, with its events.
    converged : bool
        Whether Newton converged.
    iterations : int
        Newton iterations.
    residual_norm : float
        Norm of the last residual.
    residuals : list of float
        Newton residual history.
    trivial_error : float
        Autonomous orbits: ``|M n - n|`` along the unit velocity ``n`` (see
        :func:`saltation.orbits.floquet.autonomous_multipliers`), at most
        :data:`TRIVIAL_MULTIPLIER_ACCURACY`; ``nan`` for forced orbits.  By multiple shooting, the
        largest ``|Phi_i f(x_i) - f(x_(i+1))| / |f(x_(i+1))|`` over the segments.
    problem : ShootingProblem or None
        The shooting problem that found it (its flow, tolerances and section): what
        :func:`saltation.special_points.continuation.continue_orbit` follows.
    segments : int
        The number of shooting segments (1: single shooting).
    nodes : ndarray, shape (segments, n), or None
        The segments' initial states (multiple shooting); the first is ``state0``.
    mode0 : str or None
        The mode the orbit is in at ``state0``: the one its shooting started in (named by ``mode0`` of
        :func:`find_periodic_orbit`, or the model's initial-mode rule).  None in records made without it.
    """

    system_name: str
    state0: np.ndarray
    period: float
    t0: float
    backward: bool
    autonomous: bool
    parameters: np.ndarray
    monodromy: np.ndarray
    multipliers: np.ndarray
    trajectory: Trajectory
    converged: bool
    iterations: int
    residual_norm: float
    residuals: list[float] = field(default_factory=list)
    trivial_error: float = float("nan")
    #: the shooting problem that found it (its flow, tolerances and section): what
    #: :func:`saltation.special_points.continuation.continue_orbit` follows
    problem: ShootingProblem | None = field(default=None, repr=False, compare=False)
    #: the number of shooting segments (1: single shooting), and their initial states (multiple shooting)
    segments: int = 1
    nodes: np.ndarray | None = field(default=None, repr=False)
    #: the mode at ``state0`` (where the shooting starts)
    mode0: str | None = None

    @property
    def amplitude(self) -> float:
        """``max |x_1|`` over the period (:func:`~saltation.orbits.records.amplitude_measures`)."""
        return amplitude_measures(self.trajectory)["amplitude"]

    @property
    def half_peak_to_peak(self) -> float:
        """``(max x_1 - min x_1) / 2`` over the period (:func:`~saltation.orbits.records.amplitude_measures`)."""
        return amplitude_measures(self.trajectory)["half_peak_to_peak"]

    @property
    def backward_multipliers(self) -> np.ndarray:
        """Eigenvalues of the monodromy in the direction of integration."""
        return np.linalg.eigvals(self.monodromy)

    @property
    def stable(self) -> bool:
        return is_stable(self.multipliers, autonomous=self.autonomous)

    @property
    def trivial_multiplier_error(self) -> float:
        """How far the trivial multiplier can be from 1 (autonomous orbits): ``|M n - n|``, an accuracy figure."""
        return self.trivial_error

    @property
    def events(self) -> list[SwitchingEvent]:
        """The events of one period (as :attr:`Trajectory.events`)."""
        return self.trajectory.events

    @property
    def event_labels(self) -> tuple[str, ...]:
        """Readable labels of the orbit's cycle of events (see :func:`event_labels`)."""
        return event_labels(self.trajectory)

    def _repr_markdown_(self) -> str:
        """A summary for Jupyter (:mod:`saltation.summary`)."""
        from saltation.summary import orbit_summary

        return orbit_summary(self)

    def __repr__(self) -> str:
        state = ", ".join(f"{v:.6g}" for v in np.asarray(self.state0)[:6]) + (", ..." if len(self.state0) > 6 else "")
        mu = f"{np.max(np.abs(self.multipliers)):.6g}" if len(self.multipliers) else "-"
        how = ("backward" if self.backward else "forward") + (", autonomous" if self.autonomous else ", forced")
        mode = f" in {self.mode0!r}" if self.mode0 is not None else ""
        return (f"PeriodicOrbit({self.system_name!r}, T={self.period:.10g}, x0=[{state}]{mode}, max |mu|={mu}, "
                f"{'stable' if self.stable else 'unstable'}, {len(self.events)} events, {how}"
                + ("" if self.converged else ", NOT converged") + ")")


def stationary_floor(tolerances: Tolerances, size: float) -> float:
    """The excursion (or speed) below which a state of magnitude ``size`` does not move.

    ``min(STATIONARY_FACTOR (atol + rtol s), STATIONARY_FRACTION s)`` with ``s = 1 + size``: many times the
    integration tolerance at the state's scale, but never a sizeable part of that scale, so that a loose
    tolerance does not make real orbits look stationary.

    Parameters
    ----------
    tolerances : Tolerances
        The integration tolerances.
    size : float
        ``max |x_i|`` of the state.

    Returns
    -------
    float
        The floor.
    """
    scale = 1.0 + size
    return min(STATIONARY_FACTOR * (tolerances.atol + tolerances.rtol * scale), STATIONARY_FRACTION * scale)


class ShootingProblem(BranchProblem):
    """Periodic orbits of a model by single shooting.

    The residual is the period map minus the identity, ``r = phi(t0 + s T; t0, x0) - x0``, and its
    Jacobian the monodromy matrix minus the identity, the monodromy carrying the saltation matrix of
    every event (eq. (9) of *Fold bifurcations in discontinuous systems*): Newton converges
    quadratically through the events.

    Parameters
    ----------
    flow : Flow
        The compiled flow of the model.
    parameters : mapping or ndarray, optional
        Parameter values (defaults of the model otherwise).
    continuation_parameter : str, optional
        Name of the parameter ``lam`` for :meth:`evaluate` (continuation).
    backward : bool
        Shoot in backward time (infinitely unstable orbits).
    t0 : float
        Initial time (forced systems: the phase of the forcing).
    tolerances : Tolerances, optional
        Integration tolerances (the flow's by default).
    periods : int
        Forced systems: the number of forcing periods the orbit takes to
        close (2 for the branch born at a period doubling).  Such problems
        iterate Newton in Python rather than in the compiled kernel.
    mode0 : str or int, optional
        The mode every shot starts in (:attr:`mode0`), for a mode that is memory (a latch, a relay with
        hysteresis, a thermostat: modes whose domains overlap, which the state alone does not tell
        apart).  The shooting state must lie in its domain (or on its boundary).  None (the default):
        each shot starts in the mode the model's domains give its state.

    Attributes
    ----------
    mode0 : str or None
        The mode the shots start in (None: the model's initial-mode rule).  Moving a guess's state off
        the switching surfaces (:meth:`start_off_surfaces`) keeps it, unless the orbit spends too short
        a stretch in it; then it becomes the mode of the stretch the state moves to.

    Raises
    ------
    ModelError
        If ``periods`` is not a positive integer (or not 1 for an autonomous model), ``t0`` is not
        finite, a parameter name or value is invalid, the forcing period is not positive and finite, or
        ``mode0`` is not a mode of the model (the message lists them).

    References
    ----------
    Stoer and Bulirsch, *Introduction to Numerical Analysis*, Springer, section 7.3 (shooting
    methods).  Leine and Van Campen, "Fold bifurcations in discontinuous systems", eq. (9) (the
    saltation matrix in the monodromy).
    """

    def __init__(
        self,
        flow: Flow,
        parameters: Mapping[str, float] | np.ndarray | None = None,
        *,
        continuation_parameter: str | None = None,
        backward: bool = False,
        t0: float = 0.0,
        tolerances: Tolerances | None = None,
        periods: int = 1,
        mode0: str | int | None = None,
    ):
        if int(periods) != periods or periods < 1:
            raise ModelError(f"periods must be a positive integer, got {periods!r}")
        if periods != 1 and flow.system.is_autonomous:
            raise ModelError(f"model {flow.system.name!r} is autonomous: its period is an unknown, not a number of periods")
        self.periods = int(periods)
        self.flow = flow
        self.system = flow.system
        self.p = flow.parameters(parameters)
        self.lam_index = -1 if continuation_parameter is None else self.system.parameter_index(continuation_parameter)
        self.lam_name = continuation_parameter
        self.backward = bool(backward)
        self.sign = -1.0 if backward else 1.0
        self.tolerances = tolerances
        self.autonomous = self.system.is_autonomous
        t0 = float(t0)
        if not math.isfinite(t0):
            raise ModelError(f"t0 must be finite, got {t0}")
        # an autonomous field does not depend on time: integrate from 0; a forced one from the phase of the
        # forcing at t0 (a time of 1e12 keeps only 4 decimals: the orbit there is the orbit at t0 mod T)
        self.t0 = 0.0 if self.autonomous or t0 == 0.0 else math.fmod(t0, self.system.forcing_period(self.p))
        self.x_ref: np.ndarray | None = None
        self.f_ref: np.ndarray | None = None
        self.mode0: str | None = None if mode0 is None else self.system.mode_names[self.system.mode_index(mode0)]

    def __repr__(self) -> str:
        how = ("backward" if self.backward else "forward") + (", autonomous" if self.autonomous else ", forced")
        lam = f", continuation in {self.lam_name}" if self.lam_name else ""
        periods = f", {self.periods} periods" if self.periods != 1 else ""
        mode = f", from mode {self.mode0!r}" if self.mode0 is not None else ""
        return f"ShootingProblem({self.system.name!r}, {how}{periods}{lam}{mode})"

    def start_mode(self, x: np.ndarray, p: np.ndarray) -> int:
        """The mode a shot from ``x`` starts in: :attr:`mode0`, checked against its domain, or the model's rule.

        Parameters
        ----------
        x : ndarray, shape (n,)
            The shooting state.
        p : ndarray, shape (n_params,)
            Parameter values.

        Returns
        -------
        int
            Index of the mode.

        Raises
        ------
        InitialModeError
            If ``x`` lies outside the domain of :attr:`mode0` (or, without it, in no mode's domain).
        """
        return self.flow.start_mode(x, p, self.t0, self.mode0)

    # -- the protocol used by continuation ----------------------------------------------
    @property
    def dimension(self) -> int:
        """Number of unknowns ``u``."""
        return self.system.n + (1 if self.autonomous else 0)

    def pack(self, state0: Sequence[float], period: float | None = None) -> np.ndarray:
        """Unknowns ``u`` from an initial state (and period, autonomous systems).

        Parameters
        ----------
        state0 : sequence of float
            The initial state, ``n`` values.
        period : float, optional
            The period guess of an autonomous model (ignored for a forced one).

        Returns
        -------
        ndarray
            ``x0`` (forced) or ``(x0, T)`` (autonomous).

        Raises
        ------
        ModelError
            If the state has the wrong size, or an autonomous model is given no positive period.
        """
        x0 = np.asarray(state0, dtype=float)
        if x0.shape != (self.system.n,):
            raise ModelError(f"initial state must have {self.system.n} components {list(self.system.state_names)}")
        if not self.autonomous:
            return x0.copy()
        if period is None or not period > 0:
            raise ModelError(f"model {self.system.name!r} is autonomous: give a positive period guess")
        return np.append(x0, float(period))

    def set_phase_reference(self, u: np.ndarray, lam: float | None = None) -> None:
        """Anchor the phase condition ``f(x_ref) . (x0 - x_ref) = 0`` at ``u``.

        Parameters
        ----------
        u : ndarray
            Unknowns ``(x0, T)``; ``x_ref`` is their state.
        lam : float, optional
            Value of the continuation parameter.

        Raises
        ------
        StationaryStateError
            If the vector field vanishes at the state (an equilibrium).
        InitialModeError
            If the state lies in no mode's domain.
        """
        self.anchor_phase(np.asarray(u[: self.system.n], dtype=float), self.parameters_at(lam))

    def anchor_phase(self, x: np.ndarray, p: np.ndarray) -> None:
        """Anchor the phase condition at the state ``x`` under the parameters ``p``.

        Parameters
        ----------
        x : ndarray, shape (n,)
            The reference state ``x_ref``.
        p : ndarray, shape (n_params,)
            Parameter values; ``f_ref`` is the unit vector field of ``x``'s mode there.

        Raises
        ------
        StationaryStateError
            If the vector field vanishes at ``x`` (an equilibrium).
        InitialModeError
            If ``x`` lies in no mode's domain (outside that of :attr:`mode0`).
        """
        mode = self.start_mode(x, p)
        f = self.flow.vector_field(mode, self.t0, x, p)
        norm = np.linalg.norm(f)
        if not norm > 0:
            raise StationaryStateError(
                f"the state x = {x.tolist()} is an equilibrium of mode {self.system.mode_names[mode]!r} of "
                f"{self.system.name!r} (its vector field vanishes there): no phase condition, not a periodic orbit", x)
        self.x_ref = x.copy()
        self.f_ref = f / norm

    def start_off_surfaces(self, u: np.ndarray, lam: float | None = None) -> np.ndarray:
        """An autonomous guess whose state lies away from every switching surface.

        When the guess's state lies on a surface or next to one (the flow reaches it within
        :data:`SEAM_MARGIN` of the period, either way in time), the state is moved along the guess's
        own trajectory to the middle of its longest stretch between events that is not a sliding
        motion.  The phase condition anchored there is transverse to the flow and away from the
        surfaces, so Newton does not put the shooting state on a surface.  Otherwise, or when the
        guess cannot be integrated (Newton then reports why), ``u`` is returned as it is.

        With a start mode (:attr:`mode0`), the stretch is the longest one in that mode; if the orbit
        spends too short a stretch in it, the longest of any mode, and :attr:`mode0` becomes that
        stretch's mode (the shooting state and its mode move together).

        Parameters
        ----------
        u : ndarray
            The guess ``(x0, T)`` (a forced model's ``x0`` is returned as it is).
        lam : float, optional
            Value of the continuation parameter.

        Returns
        -------
        ndarray
            The guess, its state moved or not.

        Raises
        ------
        InitialModeError
            If the guess's state lies in no mode's domain (when its distance to the surfaces is measured).
        """
        if not self.autonomous:
            return u
        n = self.system.n
        x0, T = np.asarray(u[:n], dtype=float), float(u[n])
        if not (T > 0 and math.isfinite(T)):
            return u
        p = self.parameters_at(lam)
        try:
            traj = self.flow.run(x0, self.t0, self.t0 + self.sign * T, p, mode0=self.mode0, tolerances=self.tolerances)
        except SaltationError:
            return u
        t_mid = self._off_the_seam(traj, x0, T, p)
        if t_mid is None:
            return u
        try:
            mid = self.flow.run(x0, self.t0, self.t0 + self.sign * t_mid, p, mode0=self.mode0, tolerances=self.tolerances)
        except SaltationError:
            return u
        if self.mode0 is not None:
            self.mode0 = mid.mode1  # (the stretch's mode)
        return np.append(mid.x1, T)

    def _off_the_seam(self, traj, x0: np.ndarray, T: float, p: np.ndarray) -> float | None:
        """Where along one period ``traj`` (from ``x0``) a shooting state lies away from every event: the
        middle of the longest stretch between events that is not a sliding motion (of the start mode's, if
        :attr:`mode0` is set and it is long enough), as a time from the start; None where the seam is clear
        already (no event within :data:`SEAM_MARGIN` of the period of either end, nor a surface that near) or no
        stretch is long enough."""
        times = [abs(e.t - self.t0) for e in traj.events]
        margin = SEAM_MARGIN * T
        # the period's end counts as its start: a state whose flow reaches a surface right at the end of the
        # period (the image of a reset there, as a clock's phase 0) sits on the seam too
        if not times or (min(times[0], T - times[-1]) >= margin and self._time_to_surfaces(x0, p) >= margin
                         and self._time_to_surfaces(traj.x1, p) >= margin):
            return None
        stretches = []  # (length, middle, mode) of each stretch between events that is not a sliding motion
        sliding, mode = False, traj.mode0
        for k, (a, b) in enumerate(zip([0.0, *times], [*times, T])):
            if k > 0:
                sliding = traj.events[k - 1].kind == EventKind.SLIDING_START
                mode = traj.events[k - 1].mode_to
            if not sliding:
                stretches.append((b - a, 0.5 * (a + b), mode))
        own = [s for s in stretches if s[2] == self.mode0 and s[0] >= 2.0 * margin]
        best, t_mid, mode = max(own or stretches, key=lambda s: s[0], default=(0.0, None, None))
        if t_mid is None or best < 2.0 * margin:
            return None
        return t_mid

    @property
    def can_collapse(self) -> bool:
        """An autonomous orbit may shrink onto an equilibrium; a forced one keeps its period."""
        return self.autonomous

    def rephase(self, u: np.ndarray, lam: float | None) -> np.ndarray | None:
        """The orbit's state moved off its events: :meth:`start_off_surfaces` (autonomous) or
        :meth:`move_section` (forced, with :attr:`t0`).

        Parameters
        ----------
        u : ndarray
            The unknowns of a solved orbit.
        lam : float or None
            The parameter's value.

        Returns
        -------
        ndarray
            The moved unknowns (``u`` itself where the seam is clear).

        Raises
        ------
        InitialModeError
            If the state lies in no mode's domain.
        """
        return self.start_off_surfaces(u, lam) if self.autonomous else self.move_section(u, lam)

    @property
    def section_time(self) -> float:
        """A forced orbit's section time :attr:`t0` (0 for an autonomous one)."""
        return 0.0 if self.autonomous else float(self.t0)

    @property
    def section_settings(self) -> dict:
        return {"t0": self.t0, "mode0": self.mode0}

    def align_section(self, point) -> None:
        """Take the section time of a recorded point: a forced orbit's state lies on its orbit at the point's own
        ``t0``, which a branch may have moved (:meth:`move_section`) since the problem was built.

        Parameters
        ----------
        point : BranchPoint or SpecialPoint
            A point whose ``t0`` (0 where it has none) becomes :attr:`t0` of a forced problem.
        """
        t0 = float(getattr(point, "t0", 0.0) or 0.0)
        if not self.autonomous and math.isfinite(t0) and t0 != self.t0:
            self.t0 = t0

    def move_section(self, u: np.ndarray, lam: float | None = None) -> np.ndarray:
        """A forced orbit's shooting state moved, with the section time :attr:`t0`, off the switching events.

        A forced orbit's section is a choice: where an event of the orbit lies at (or next to) ``t0``, the
        stroboscopic map has a kink there and Newton cycles across it.  The section is moved along the orbit
        to the middle of its longest stretch between events (as :meth:`start_off_surfaces` moves an autonomous
        orbit's state), and :attr:`t0` (and :attr:`mode0`, if set) with it; the multipliers do not change.
        This changes the problem: the points a branch records carry their own ``t0``.

        Parameters
        ----------
        u : ndarray
            The state ``x0`` of a forced orbit at :attr:`t0`.
        lam : float, optional
            Value of the continuation parameter.

        Returns
        -------
        ndarray
            The state at the new :attr:`t0`, or ``u`` itself where the seam is clear, the problem is autonomous
            or the orbit cannot be integrated.
        """
        if self.autonomous:
            return u
        n = self.system.n
        x0 = np.asarray(u[:n], dtype=float)
        p = self.parameters_at(lam)
        T = self.period_of(u, lam)
        try:
            traj = self.flow.run(x0, self.t0, self.t0 + self.sign * T, p, mode0=self.mode0, tolerances=self.tolerances)
            t_mid = self._off_the_seam(traj, x0, T, p)
            if t_mid is None:
                return u
            mid = self.flow.run(x0, self.t0, self.t0 + self.sign * t_mid, p, mode0=self.mode0, tolerances=self.tolerances)
        except SaltationError:
            return u
        if self.mode0 is not None:
            self.mode0 = mid.mode1
        self.t0 = math.fmod(self.t0 + self.sign * t_mid, self.system.forcing_period(p))
        return np.asarray(mid.x1, dtype=float)

    def _time_to_surfaces(self, x: np.ndarray, p: np.ndarray) -> float:
        """The least time ``|h| / |dh/dt|`` in which the flow at ``x`` reaches a switching surface (linearised)."""
        flow, t = self.flow, self.t0
        f = flow.vector_field(self.start_mode(x, p), t, x, p)
        least = math.inf
        for k in range(len(self.system.surface_names)):
            h = abs(flow.indicator(k, t, x, p))
            hx, ht, _ = flow.indicator_gradient(k, t, x, p)
            rate = abs(float(hx @ f) + ht)
            least = min(least, 0.0 if h == 0.0 else (h / rate if rate > 0.0 else math.inf))
        return least

    def period_of(self, u: np.ndarray, lam: float | None = None) -> float:
        """The period of the unknowns ``u`` at ``lam``.

        Parameters
        ----------
        u : ndarray
            Unknowns ``x0`` or ``(x0, T)``.
        lam : float, optional
            Value of the continuation parameter.

        Returns
        -------
        float
            ``T`` of an autonomous orbit; ``periods`` times the forcing period of a forced one.

        Raises
        ------
        ModelError
            If the forcing period is not positive and finite at these parameters.
        """
        return float(u[-1]) if self.autonomous else self.periods * self.system.forcing_period(self.parameters_at(lam))

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        """Residual ``r(u, lam)`` and its exact Jacobians.

        One shot over the period with the fundamental solution matrix (:meth:`close_period` applied),
        then :meth:`periodicity`.

        Parameters
        ----------
        u : ndarray
            Unknowns ``x0`` or ``(x0, T)``.
        lam : float, optional
            Value of the continuation parameter.
        need_lam : bool
            Compute ``jac_lam`` too (the shot then carries the parameter sensitivity).

        Returns
        -------
        Evaluation
            ``residual``, ``jac_u``, ``jac_lam`` (None without ``lam`` or ``need_lam``) and the shot.

        Raises
        ------
        IntegrationError
            If the period is not positive, or the shot fails (see :meth:`Flow.run`).
        InitialModeError, ModelError
            A state in no mode's domain (outside that of :attr:`mode0`), an invalid parameter.
        InconsistentResultError
            A reset exactly at the seam (see :meth:`close_period`).
        StationaryStateError
            An autonomous orbit whose phase condition is anchored at an equilibrium.
        """
        n = self.system.n
        p = self.parameters_at(lam)
        x0 = np.ascontiguousarray(u[:n])
        T = self.period_of(u, lam)
        if not T > 0:
            raise IntegrationError(f"shooting period must be positive, got {T}")
        pidx = self.lam_index if (need_lam and lam is not None) else -1
        mode0 = None if self.mode0 is None else self.start_mode(x0, p)  # (the named mode, in its domain)
        traj = self.flow.run(
            x0, self.t0, self.t0 + self.sign * T, p, mode0=mode0, variational=True, sensitivity=pidx,
            tolerances=self.tolerances,
        )
        traj = self.close_period(traj, p, pidx)
        sens = {pidx: traj.parameter_sensitivity} if pidx >= 0 else {}
        r, J, jp = self.periodicity(x0, traj, p, sens)
        return Evaluation(residual=r, jac_u=J, jac_lam=jp[:, 0].copy() if pidx >= 0 else None, trajectory=traj)

    def periodicity(
        self, x0: np.ndarray, traj: Trajectory, p: np.ndarray, sensitivities: Mapping[int, np.ndarray]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The periodicity equations of one shot, and the phase condition of an autonomous orbit.

        The one place (besides the compiled kernel) where ``x(t0 + s T) - x0 = 0`` and its Jacobian are
        written; every defining system of a special point adds its conditions to these rows
        (:mod:`saltation.orbits.conditions`).

        Parameters
        ----------
        x0 : ndarray, shape (n,)
            The shot's initial state.
        traj : Trajectory
            The shot over the period, with its monodromy (and :meth:`close_period` applied).
        p : ndarray
            Parameter values of the shot.
        sensitivities : mapping of int to ndarray, shape (n,)
            ``d x(end) / d p_j`` as the shot carried them, by parameter index.

        Returns
        -------
        residual : ndarray, shape (n[+1],)
            ``x(t0 + s T) - x0`` (and the phase condition).
        jac_u : ndarray, shape (n[+1], n[+1])
            By ``u = (x0[, T])``.
        jac_p : ndarray, shape (n[+1], k)
            By the parameters of ``sensitivities``, in their order: for a forced orbit the period
            ``T(p)`` moves the end point along the flow, ``psi_j + s dT/dp_j f(end)``.

        Raises
        ------
        StationaryStateError
            If the phase condition is not anchored yet and ``x0`` is an equilibrium.
        """
        n = self.system.n
        M = traj.monodromy
        rows = n + (1 if self.autonomous else 0)
        r = np.empty(rows)
        r[:n] = traj.x1 - x0
        J = np.zeros((rows, rows))
        J[:n, :n] = M
        J[:n, :n] -= np.eye(n)
        jp = np.zeros((rows, len(sensitivities)))
        for c, (j, psi) in enumerate(sensitivities.items()):
            jp[:n, c] = psi
            if not self.autonomous:
                dT = self.periods * self.system.period_derivative(p, j)
                if dT:  # the period moves with the parameter: the end point moves along the flow
                    jp[:n, c] += (self.sign * dT) * traj.velocity_end
        if self.autonomous:
            if self.x_ref is None:
                self.anchor_phase(x0, p)
            r[n] = self.f_ref @ (x0 - self.x_ref)
            J[:n, n] = self.sign * traj.velocity_end
            J[n, :n] = self.f_ref
        return r, J, jp

    def with_conditions(
        self, conditions: Sequence[Condition], free: Sequence[str], *, continuation: str | None = None,
        parameters: np.ndarray | None = None,
    ) -> ConditionedProblem:
        """This problem with conditions attached and parameters freed.

        The defining system of a special point (``continuation`` None) or a two-parameter curve of one
        (see :mod:`saltation.orbits.conditions`).

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
            If the equations and unknowns do not balance, or a name is not a parameter (see
            :class:`ConditionedProblem`).

        Examples
        --------
        A grazing of transition 0 near ``t = 0.3``, located in ``s``::

            located = problem.with_conditions([Tangency(flow, 0, 0.3)], free=("s",)).solve(u0)
        """
        return ConditionedProblem(self, conditions, free, continuation=continuation, parameters=parameters)

    def close_period(self, traj: Trajectory, p: np.ndarray, sensitivity: int = -1, *,
                     disabled: Sequence[int] = ()) -> Trajectory:
        """The shot with the crossing at the seam ``t0 = t0 + T`` counted once, as the orbit crosses there.

        A shooting state on a switching surface (wherever the phase condition, or a forced orbit's
        ``t0``, put it) meets the crossing at both ends of the interval, and the engine, which fires
        an event once the indicator has changed sign, may log it at the start, at the end, at
        both or at neither, as rounding falls:

        * at both (the first and the last event are the same transition, within ``1e-7 T`` of the
          ends): the shot is run again from the start in the mode that crossing enters, so that it
          is logged at most at the end (a reset there is ambiguous: InconsistentResultError), and
          then as below;
        * at neither (the shot starts in mode ``a`` with no event and ends, within rounding, on the
          surface of a transition from its final mode ``b`` back to ``a``): that transition is
          applied at the end (reset, saltation matrix of eq. (9), parameter sensitivity) and logged.

        Any other shot is returned as it is; the transitions in ``disabled`` (passed by a virtual orbit)
        are never applied at the seam.

        Parameters
        ----------
        traj : Trajectory
            A shot over one period (a shot without monodromy is returned as it is).
        p : ndarray
            Its parameter values.
        sensitivity : int
            Index of the parameter whose sensitivity the shot carries (-1: none).
        disabled : sequence of int
            Transitions the shot passes without firing (see :meth:`Flow.run`).

        Returns
        -------
        Trajectory
            The shot, the seam's event logged once.

        Raises
        ------
        InconsistentResultError
            For a reset (an impact) exactly at the seam, logged at both ends.
        IntegrationError
            If the shot run again fails, or the transition applied at the end is tangent to its surface.
        """
        sys_ = self.system
        if traj.monodromy is None:
            return traj
        ev_t, ev_int = traj.event_log[0], traj.event_log[1]  # the kernel's log: read without building records
        if len(ev_t) >= 2:
            delta = 1e-7 * max(1.0, abs(traj.t1 - traj.t0))
            first_kind, last_kind = int(ev_int[0, 0]), int(ev_int[-1, 0])
            # (or the last event, a sliding motion's end, enters the mode the first has entered)
            if (first_kind == _TRANSITION and last_kind in (_TRANSITION, _SLIDING_END)
                    and ev_int[0, 4] == ev_int[-1, 4] and (last_kind != _TRANSITION or ev_int[0, 1] == ev_int[-1, 1])
                    and abs(ev_t[0] - traj.t0) <= delta and abs(traj.t1 - ev_t[-1]) <= delta):
                first = traj.events[0]
                if sys_.resets[first.transition] is not None:
                    raise InconsistentResultError(
                        f"transition {sys_.transitions[first.transition].label!r} (a reset) happens at the start and at "
                        f"the end of the shooting interval of {sys_.name!r}, at t = {traj.t0:.12g}: the state there is "
                        "ambiguous (before or after the reset); shoot from another t0"
                    )
                traj = self.flow.run(traj.x0, traj.t0, traj.t1, p, mode0=first.mode_to, variational=True,
                                     sensitivity=sensitivity, tolerances=self.tolerances,
                                     disabled=disabled)  # then as below
            elif (len(ev_t) >= 3 and first_kind == _SLIDING_START and ev_int[1, 0] == _SLIDING_END
                  and last_kind == _SLIDING_END and ev_int[1, 4] == ev_int[-1, 4]
                  and abs(ev_t[0] - traj.t0) <= delta and abs(ev_t[1] - traj.t0) <= delta
                  and abs(traj.t1 - ev_t[-1]) <= delta):
                # a sliding motion ends at the seam (logged at t0 + T) and is met again at t0, with no length:
                # a state on the sliding region's edge starts there a sliding motion that ends at once.  That
                # pair is dropped from the log; its matrices (the projection onto the surface, and the
                # identity of the exit) stay in the monodromy matrix M, whose range lies in the surface's
                # tangent space after the sliding motion, so that they leave its multipliers as they are; the
                # shot starts in the mode that sliding motion leaves into
                traj = replace(traj, mode0=traj.events[1].mode_to, event_log=tuple(column[2:] for column in traj.event_log))
        if traj.sliding_at_end:
            return self._leave_sliding_at_the_end(traj, p, sensitivity)
        if traj.mode1 == traj.mode0:
            return traj
        if traj.events and traj.events[0].t == traj.t0:
            return traj  # the start fired its own event: the shot starts after it
        flow, t1, x1 = self.flow, traj.t1, traj.x1
        scale = 1.0 + float(np.abs(x1).max())
        for k, tr in enumerate(sys_.transitions):
            if tr.source != traj.mode1 or tr.target != traj.mode0 or k in disabled:
                continue
            h = flow.indicator(tr.surface, t1, x1, p)
            hx, _, _ = flow.indicator_gradient(tr.surface, t1, x1, p)
            # within Newton's closing error of the state (1e-8 relative): the orbit crosses here, at the seam
            if abs(h) > 1e-8 * scale * float(np.linalg.norm(hx)) or not flow.guard_holds(k, t1, x1, p):
                continue
            x_plus, S, dp = flow.transition_jump(k, t1, x1, p)
            psi = traj.parameter_sensitivity
            if psi is not None and sensitivity >= 0:
                psi = S @ psi + dp[:, sensitivity]
            log = _logged(traj, EventKind.TRANSITION, k, tr.surface, tr.source, tr.target, x1, x_plus, S)
            return replace(
                traj, x1=x_plus, mode1=tr.target, event_log=log, monodromy=S @ traj.monodromy,
                parameter_sensitivity=psi, velocity_end=flow.vector_field(tr.target, t1, x_plus, p),
            )
        return traj

    def _leave_sliding_at_the_end(self, traj: Trajectory, p: np.ndarray, sensitivity: int) -> Trajectory:
        """A shot that starts off a sliding motion, in one of its modes, and ends on it where that mode's
        field turns tangent to the surface: the orbit leaves the sliding motion at the seam.  Its end is
        applied and logged at ``t0 + T``, with the saltation matrix the engine uses at a sliding exit
        (eq. 9 with the exit side's Lie derivative ``L = h_x f + h_t`` as the event function and the
        sliding field before it)."""
        starts = [e for e in traj.events if e.kind == EventKind.SLIDING_START]
        if not starts or (traj.events[0].kind == EventKind.SLIDING_START and traj.events[0].t == traj.t0):
            return traj
        last = starts[-1]
        if traj.mode0 not in (last.mode_from, last.mode_to):
            return traj
        flow, t1, x1 = self.flow, traj.t1, traj.x1
        L, L_x, L_p, L_t = flow.lie_derivative(traj.mode0, last.surface, t1, x1, p)
        scale = 1.0 + float(np.abs(x1).max())
        if abs(L) > 1e-8 * scale * float(np.linalg.norm(L_x)):
            return traj
        f_slide = traj.velocity_end
        f_out = flow.vector_field(traj.mode0, t1, x1, p)
        den = float(L_x @ f_slide) + L_t
        if den == 0.0:
            return traj
        w = f_out - f_slide
        S = np.eye(self.system.n) + np.outer(w, L_x) / den
        psi = traj.parameter_sensitivity
        if psi is not None and sensitivity >= 0:
            psi = S @ psi + w * L_p[sensitivity] / den
        other = last.mode_to if traj.mode0 == last.mode_from else last.mode_from
        log = _logged(traj, EventKind.SLIDING_END, -1, last.surface, other, traj.mode0, x1, x1, S)
        return replace(traj, mode1=traj.mode0, event_log=log, monodromy=S @ traj.monodromy, sliding_at_end=False,
                       parameter_sensitivity=psi, velocity_end=f_out)

    def correct(
        self, z_pred: np.ndarray, normal: np.ndarray, *, tol: float, max_newton: int, max_correction: float
    ) -> tuple[np.ndarray, Evaluation, int] | None:
        """The corrector of pseudo-arclength continuation, iterated in the compiled kernel.

        Solves ``r(u, lam) = 0``, ``normal . (z - z_pred) = 0`` for
        ``z = (u, lam)`` by the Newton iteration of
        :meth:`saltation.branches.continuation.Corrector.solve_bordered`.

        Parameters
        ----------
        z_pred : ndarray
            The predicted point ``(u, lam)``.
        normal : ndarray
            The pseudo-arclength row (the tangent at the last point).
        tol : float
            Newton tolerance.
        max_newton : int
            Largest number of iterations.
        max_correction : float
            The iteration stops when a correction exceeds ``max_correction (1 + |z|)``.

        Returns
        -------
        tuple of (ndarray, Evaluation, int) or None
            The solution ``z``, its evaluation and the number of iterations; or None when the kernel
            cannot run it (no continuation parameter, several forcing periods, a forcing period given as a
            callable, a singular matrix, an event at the end of the period, or a shot that does not start in
            :attr:`mode0`): then iterate in Python.

        Raises
        ------
        ConvergenceError
            If Newton does not converge.
        IntegrationError, ModelError, InitialModeError
            If the last shot failed (as :meth:`Flow.run` raises it).
        StationaryStateError
            If the phase condition would be anchored at an equilibrium.
        InconsistentResultError
            A reset exactly at the seam (see :meth:`close_period`).
        """
        if self.lam_index < 0 or self.periods != 1:
            return None  # the kernel's corrector closes orbits after one forcing period
        if not self._compiled_start(z_pred[: self.system.n], self.parameters_at(float(z_pred[-1]))):
            return None  # the kernel's shots start in the mode of the model's rule, not in mode0
        phase = None
        if self.autonomous:
            if self.x_ref is None:
                self.set_phase_reference(z_pred[:-1], float(z_pred[-1]))
            phase = (self.x_ref, self.f_ref)
        found = self.flow.compiled_newton(
            z_pred, normal, self.p, t0=self.t0, sign=self.sign, lam_index=self.lam_index, span=0.0, phase=phase,
            tol=tol, max_iter=max_newton, max_correction=max_correction, damped=False, tolerances=self.tolerances,
        )
        if found is None or found.unsupported:
            return None  # iterate in Python
        n, z = self.system.n, found.z
        p_end = self.p.copy()
        p_end[self.lam_index] = z[-1]
        traj = self.flow.shot_trajectory(found, z[:n].copy(), self.t0, p_end, self.lam_index)  # a failed shot raises
        if self.mode0 is not None and traj.mode0 != self.mode0:
            return None  # its last shot started in another mode than mode0
        if self.close_period(traj, p_end) is not traj:
            return None  # an event at the end of the period, which the kernel's iteration does not apply
        if not found.converged:
            raise ConvergenceError("corrector did not converge", found.history)
        m, jac = len(z) - 1, found.jacobian
        ev = Evaluation(residual=jac[:, 0].copy(), jac_u=jac[:, 1 : 1 + m].copy(), jac_lam=jac[:, 1 + m].copy(),
                        trajectory=traj, bordered_tangent=None if found.tangent is None else (normal, found.tangent))
        return z, ev, found.iterations

    def verify(self, u: np.ndarray, lam: float | None, traj: Trajectory) -> tuple[np.ndarray, float]:
        """The forward-time multipliers of a solved point and its trivial multiplier's error.

        Called once the point is known to satisfy the periodicity equations.

        Parameters
        ----------
        u : ndarray
            The solved unknowns.
        lam : float or None
            Value of the continuation parameter.
        traj : Trajectory
            The shot over the period, with its monodromy.

        Returns
        -------
        multipliers : ndarray, complex
            Forward-time Floquet multipliers.
        trivial_error : float
            ``|M n - n|`` of an autonomous orbit (``nan`` for a forced one).

        Raises
        ------
        StationaryStateError
            If the state does not move over the period (see :meth:`stationary_reason`).
        InconsistentResultError
            If an autonomous orbit's monodromy does not map the flow direction to itself within
            :data:`TRIVIAL_MULTIPLIER_ACCURACY`, or (with :attr:`mode0`) its shot ends in another mode
            (:meth:`check_mode_closes`).
        """
        reason = self.stationary_reason(u, lam, traj)
        if reason is not None:
            raise StationaryStateError(reason, u[: self.system.n], self.period_of(u, lam))
        self.check_mode_closes(traj)
        if not self.autonomous:
            return multipliers_from_monodromy(traj.monodromy, backward=self.backward), float("nan")
        found = autonomous_multipliers(traj.monodromy, traj.velocity_end, backward=self.backward)
        if not found.trivial_error <= TRIVIAL_MULTIPLIER_ACCURACY:
            x0 = np.array2string(np.asarray(u[: self.system.n]), precision=8)
            raise InconsistentResultError(
                f"the orbit of {self.system.name!r} from x0 = {x0} (period {self.period_of(u, lam):.10g}) does not "
                f"map its own flow direction to itself: |M n - n| = {found.trivial_error:.2e} > "
                f"{TRIVIAL_MULTIPLIER_ACCURACY:g}, so its trivial multiplier is not 1 and its monodromy is wrong "
                "(an event missing from it, or too loose integration tolerances)"
            )
        return found.multipliers, found.trivial_error

    def check_mode_closes(self, traj: Trajectory) -> None:
        """With a start mode (:attr:`mode0`): the solved shot ends in the mode it starts in.

        The state alone does not tell a memory mode from the mode it shares its domain with: a shot that
        returns to its state in the other one (the thermostat's temperature back at its start, but
        cooling where it started heating) solves the periodicity equations without being periodic.
        (Without :attr:`mode0` the domains give each state its mode, as they always have.)

        Parameters
        ----------
        traj : Trajectory
            The shot over the period (:meth:`close_period` applied).

        Raises
        ------
        InconsistentResultError
            Naming both modes, if the shot ends in another mode than it starts in.
        """
        if self.mode0 is not None and traj.mode1 != traj.mode0:
            raise InconsistentResultError(
                f"the shot of {self.system.name!r} from x0 = {np.array2string(traj.x0, precision=8)} returns to its "
                f"state in mode {traj.mode1!r}, not in the mode {traj.mode0!r} it starts in: the state closes but "
                "the mode does not, so it is not a periodic orbit (give a better period guess)"
            )

    def _compiled_start(self, x: np.ndarray, p: np.ndarray) -> bool:
        """Whether the kernel's Newton loop, whose shots start in the mode of the model's rule, may solve from
        ``x``: always without :attr:`mode0`, else where that rule gives :attr:`mode0` (its result is checked)."""
        if self.mode0 is None:
            return True
        try:
            return self.system.mode_names[self.flow.initial_mode(x, p, self.t0)] == self.mode0
        except SaltationError:
            return False

    def stationary_reason(self, u: np.ndarray, lam: float | None, traj: Trajectory) -> str | None:
        """Why a solved point is not a periodic orbit, or None: its state does not move over the period.

        The excursion ``max_i (max x_i - min x_i)`` over the period is compared with
        :func:`stationary_floor`: :data:`STATIONARY_FACTOR` times the integration tolerance at the state's
        scale, at most :data:`STATIONARY_FRACTION` of that scale.  Below it, the
        point is an equilibrium of a mode, a pseudo-equilibrium (a point of a sliding or sticking set
        where the sliding motion stops), or a period shrunk to zero.

        Parameters
        ----------
        u : ndarray
            The solved unknowns.
        lam : float or None
            Value of the continuation parameter.
        traj : Trajectory
            The shot over the period.

        Returns
        -------
        str or None
            The explanation (which of the three, and where), or None for a state that moves, and for every
            orbit of a forced model: there a constant solution (an equilibrium that the moving surfaces never
            reach, a state that sticks all period) is a genuine T-periodic orbit, with multipliers
            ``expm(J T)``; only an autonomous orbit's period is free to shrink onto a state that does not move.
        """
        if not self.autonomous:
            return None
        tol = self.tolerances or self.flow.tolerances
        n = self.system.n
        # plain floats: this runs for every orbit and branch point, on a few numbers
        excursion = max(map(float.__sub__, traj.x_max.tolist(), traj.x_min.tolist()))
        floor = stationary_floor(tol, max(map(abs, u[:n].tolist())))
        if excursion > floor:
            return None
        x0 = np.asarray(u[:n], dtype=float)
        T = self.period_of(u, lam)
        where = f"at x = {np.array2string(x0, precision=10)}"
        p = self.parameters_at(lam)
        sliding = traj.sliding_at_end or any(e.kind != EventKind.TRANSITION for e in traj.events)
        speed = float(np.linalg.norm(traj.velocity_end))
        if sliding and speed <= floor:
            surfaces = sorted({e.surface for e in traj.events if e.kind == EventKind.SLIDING_START})
            on = f" on surface {surfaces[0]!r}" if surfaces else ""
            return (f"shooting for {self.system.name!r} converged to a pseudo-equilibrium{on} {where}: a point of a "
                    f"sliding or sticking set where the motion stops (it moves by {excursion:.1e} over the period "
                    f"{T:.6g}), not a periodic orbit")
        f = self.flow.vector_field(traj.mode0, self.t0, x0, p)
        if float(np.linalg.norm(f)) <= floor:
            return (f"shooting for {self.system.name!r} converged to an equilibrium of mode {traj.mode0!r} {where} "
                    f"(|f| = {float(np.linalg.norm(f)):.1e}; it moves by {excursion:.1e} over the period {T:.6g}), "
                    "not a periodic orbit")
        return (f"shooting for {self.system.name!r} converged to the period T = {T:.3e} {where}, over which the "
                f"state moves by {excursion:.1e} only (|f| = {float(np.linalg.norm(f)):.3g}): it does not return by "
                "its own motion; not a periodic orbit, nor an equilibrium; give a better period guess")

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> BranchPoint:
        """Summary of a solved point for a branch (multipliers, amplitude, events).

        Parameters
        ----------
        u : ndarray
            The solved unknowns.
        lam : float or None
            Value of the continuation parameter.
        ev : Evaluation
            Its evaluation (with the shot).

        Returns
        -------
        BranchPoint
            The record a branch keeps.

        Raises
        ------
        StationaryStateError, InconsistentResultError
            As :meth:`verify`: such a point is not accepted on a branch.
        """
        traj = ev.trajectory
        mu, trivial_error = self.verify(u, lam, traj)
        return BranchPoint(
            parameter=math.nan if lam is None else float(lam),
            state=np.array(u[: self.system.n]),
            period=self.period_of(u, lam),
            multipliers=mu,
            stable=is_stable(mu, autonomous=self.autonomous),
            event_labels=event_labels(traj),
            monodromy=traj.monodromy,
            event_ids=event_ids(traj),
            trivial_error=trivial_error,
            mode0=traj.mode0,
            **amplitude_measures(traj),
        )

    def accept(self, u: np.ndarray, lam: float | None) -> None:
        """Called by continuation at every accepted point: re-anchor the phase condition.

        Parameters
        ----------
        u : ndarray
            The accepted unknowns.
        lam : float or None
            Value of the continuation parameter.

        Raises
        ------
        StationaryStateError
            If the accepted state of an autonomous orbit is an equilibrium.
        """
        if self.autonomous:
            self.set_phase_reference(u, lam)

    # -- solving ------------------------------------------------------------------------
    def solve(self, u0: np.ndarray, lam: float | None = None, *, tol: float = 1e-10, max_iter: int = 30) -> PeriodicOrbit:
        """Newton on the period map from the guess ``u0``.

        A forced orbit is iterated in the compiled kernel; an autonomous one (or a forced one the kernel
        cannot close) in Python, with damped steps.

        Parameters
        ----------
        u0 : ndarray
            Guess of the unknowns (:meth:`pack`).
        lam : float, optional
            Value of the continuation parameter.
        tol : float
            Newton tolerance: converged when ``|r| <= tol (1 + |u|)``.
        max_iter : int
            Largest number of Newton iterations.

        Returns
        -------
        PeriodicOrbit
            The orbit, with its forward-time multipliers.

        Raises
        ------
        ConvergenceError
            With the residual history when Newton fails; a :class:`NoOrbitNearGuessError` when, in
            addition, the flow from an autonomous guess comes to rest.
        StationaryStateError
            When it converges to a state that does not move (an equilibrium, a pseudo-equilibrium, a
            period shrunk to zero).
        InconsistentResultError
            When an autonomous orbit's trivial multiplier is not 1 within :data:`TRIVIAL_MULTIPLIER_ACCURACY`.
        IntegrationError, InitialModeError
            When the shot from the guess itself fails.
        """
        u0 = np.asarray(u0, dtype=float)
        if self.autonomous:
            u0 = self.start_off_surfaces(u0, lam)
            self.set_phase_reference(u0, lam)
        else:
            # the period is fixed: the whole iteration runs in the compiled kernel
            p = self.parameters_at(lam)
            T = self.period_of(u0, lam)
            found = self.flow.compiled_newton(
                u0, None, p, t0=self.t0, sign=self.sign, lam_index=-1, span=T, phase=None, tol=tol, max_iter=max_iter,
                max_correction=0.0, damped=True, tolerances=self.tolerances,
            ) if T > 0 and self._compiled_start(u0, p) else None
            if found is not None and found.converged:  # otherwise the Python iteration explains the failure
                x = found.z.copy()
                traj = self.flow.shot_trajectory(found, x, self.t0, p, -1)
                # else an event at the end, or a last shot that does not start in mode0: iterate in Python
                if self.close_period(traj, p) is traj and (self.mode0 is None or traj.mode0 == self.mode0):
                    return self.orbit(x, lam, traj, found.history, period=T, parameters=p)

        longest = PERIOD_GROWTH * float(u0[-1]) if self.autonomous else math.inf

        def fun(u):
            if self.autonomous and not u[-1] <= longest:  # a Newton step that throws the period far away
                raise ConvergenceError(f"the period {u[-1]:.3g} exceeds {PERIOD_GROWTH:g} times its guess")
            ev = self.evaluate(u, lam, need_lam=False)
            return ev.residual, ev.jac_u, ev

        direction = "backward" if self.backward else "forward"
        try:
            u, history, ev = newton(
                fun, u0, tol=tol, max_iter=max_iter, what=f"shooting ({direction} time) for {self.system.name!r}",
                damped=True,
            )
        except ConvergenceError as exc:
            rest = self.comes_to_rest(u0, lam)
            if rest is not None:
                message = str(exc).split(" (residual history")[0]
                raise NoOrbitNearGuessError(f"{message}; {rest[1]}", exc.residuals, rest[0], float(u0[-1])) from exc
            raise
        return self.orbit(u, lam, ev.trajectory, history)

    def comes_to_rest(self, u: np.ndarray, lam: float | None = None, periods: int = 100) -> tuple[np.ndarray, str] | None:
        """Where the flow from an autonomous guess comes to rest within ``periods`` guessed periods, or None.

        A guess near no periodic orbit often lies in the basin of a stationary state: a sticking
        set (a sliding motion that stops, a pseudo-equilibrium) or an equilibrium.  That is the
        explanation a failed shooting gives.

        Parameters
        ----------
        u : ndarray
            The guess ``(x0, T)``.
        lam : float, optional
            Value of the continuation parameter.
        periods : int
            How many guessed periods to integrate.

        Returns
        -------
        tuple of (ndarray, str) or None
            The state where the flow stops and the explanation; None for a forced model, a guess that
            cannot be integrated, or a flow that keeps moving.
        """
        if not self.autonomous:
            return None
        n = self.system.n
        x0, T = np.asarray(u[:n], dtype=float), float(u[n])
        if not (T > 0 and math.isfinite(T)):
            return None
        p = self.parameters_at(lam)
        try:
            traj = self.flow.run(x0, self.t0, self.t0 + self.sign * periods * T, p, mode0=self.mode0,
                                 tolerances=self.tolerances)
        except SaltationError:
            return None
        tol = self.tolerances or self.flow.tolerances
        floor = stationary_floor(tol, float(np.abs(traj.x1).max()))
        if not float(np.linalg.norm(traj.velocity_end)) <= floor:
            return None
        where = np.array2string(traj.x1, precision=10)
        if traj.sliding_at_end:
            return traj.x1, (f"no periodic orbit near the guess: the flow from it comes to rest at a "
                             f"pseudo-equilibrium x = {where} (a sliding or sticking set where the motion stops)")
        return traj.x1, f"no periodic orbit near the guess: the flow from it comes to rest at an equilibrium x = {where}"

    def orbit(
        self, u: np.ndarray, lam: float | None, trajectory: Trajectory, history: Sequence[float], *,
        period: float | None = None, parameters: np.ndarray | None = None,
    ) -> PeriodicOrbit:
        """Package a solved point ``u`` and its trajectory over one period as a :class:`PeriodicOrbit`.

        Parameters
        ----------
        u : ndarray
            The solved unknowns.
        lam : float or None
            Value of the continuation parameter.
        trajectory : Trajectory
            The shot over the period, with its monodromy.
        history : sequence of float
            Newton's residual history.
        period, parameters : optional
            The period and the parameters at ``lam``, when the caller has them already.

        Returns
        -------
        PeriodicOrbit
            The orbit, with its multipliers (:meth:`verify`).

        Raises
        ------
        StationaryStateError, InconsistentResultError
            As :meth:`verify`.
        """
        M = trajectory.monodromy
        mu, trivial_error = self.verify(u, lam, trajectory)
        return PeriodicOrbit(
            system_name=self.system.name,
            state0=np.array(u[: self.system.n]),
            period=self.period_of(u, lam) if period is None else period,
            t0=self.t0,
            backward=self.backward,
            autonomous=self.autonomous,
            parameters=self.parameters_at(lam) if parameters is None else parameters,
            monodromy=M,
            multipliers=mu,
            trajectory=trajectory,
            converged=True,
            iterations=max(len(history) - 1, 0),
            residual_norm=float(history[-1]),
            residuals=list(history),
            trivial_error=trivial_error,
            problem=self,
            mode0=trajectory.mode0,
        )


def _logged(traj: Trajectory, kind: EventKind, transition: int, surface: str, mode_from: str, mode_to: str,
            x_minus: np.ndarray, x_plus: np.ndarray, S: np.ndarray) -> tuple[np.ndarray, ...]:
    """The trajectory's event log with one more event at its end (the kernel's layout)."""
    sys_ = traj.system
    ev_t, ev_int, ev_xm, ev_xp, ev_S = traj.event_log
    row = np.array([[int(kind), transition, sys_.surface_index(surface), sys_.mode_index(mode_from),
                     sys_.mode_index(mode_to)]], dtype=ev_int.dtype)
    return (np.append(ev_t, traj.t1), np.vstack([ev_int, row]), np.vstack([ev_xm, x_minus[None, :]]),
            np.vstack([ev_xp, x_plus[None, :]]), np.concatenate([ev_S, S[None, :, :]]))


def find_periodic_orbit(
    flow: Flow | PiecewiseSystem,
    state0: Sequence[float] | None = None,
    *,
    parameters: Mapping[str, float] | None = None,
    period: float | None = None,
    backward: bool = False,
    t0: float = 0.0,
    tol: float = 1e-10,
    max_iter: int = 30,
    tolerances: Tolerances | None = None,
    segments: int = 1,
    transient_length: float | None = None,
    mode0: str | None = None,
) -> PeriodicOrbit:
    """Find one periodic orbit by shooting from a guess.

    Parameters
    ----------
    flow : Flow or PiecewiseSystem
        The flow of the model (a model is given a :class:`Flow` of its own, with its default tolerances).
    state0 : array_like, optional
        Guess of the state at ``t0``.  Without one, the guess is the end of a transient from zeros
        (:func:`saltation.orbits.start.transient`, in the direction of integration).
    parameters : mapping, optional
        Parameter overrides.
    period : float, optional
        Period guess of an autonomous system; without one, it is read from a transient from
        ``state0`` (:func:`saltation.orbits.start.estimate_period`).  A forced system's period is its
        forcing period; a ``period`` given for it must equal that.
    backward : bool
        Shoot in backward time.
    t0 : float
        Initial time (forced systems: the phase of the forcing; reduced modulo
        the forcing period before integrating).
    tol : float
        Newton tolerance: converged when ``|r| <= tol (1 + |u|)``.
    max_iter : int
        Largest number of Newton iterations.
    tolerances : Tolerances, optional
        Integration tolerances (the flow's by default).
    segments : int
        Shooting segments: 1 is single shooting; ``m > 1`` is multiple shooting
        (:class:`MultipleShootingProblem`), for strongly unstable orbits, long periods and large
        models.  ``state0`` is then either one state (the nodes are taken from its trajectory, which
        on a strongly unstable orbit drifts away within the period) or a guess of every node, shape
        ``(m, n)``, at ``t0 + i T / m``.  At most :data:`MAX_SEGMENTS`, and ``m n`` at most
        :data:`MAX_NODE_VALUES` (the Newton matrix of multiple shooting is dense).
    transient_length : float, optional
        Length of the transient of an autonomous model, when one is needed
        (:data:`saltation.orbits.start.TRANSIENT_TIME` by default).
    mode0 : str, optional
        The mode the orbit starts in at ``state0``: for a mode that is memory (a latch, a relay with
        hysteresis, a thermostat), which the state alone does not tell from another mode with the same
        domain.  ``state0`` must lie in its domain (or on its boundary).  Every shot starts in it (with
        multiple shooting the first segment; each further one in the mode the one before it ends in),
        and the orbit must close in it.  Without ``state0`` the transient starts in ``mode0`` and the
        orbit in the mode the transient ends in.  An autonomous guess moved off the switching surfaces
        stays in ``mode0`` where the orbit spends a long enough stretch in it.  The orbit records its
        mode as :attr:`PeriodicOrbit.mode0`.  None (the default): the model's domains give the mode.

    Returns
    -------
    PeriodicOrbit
        With its forward-time multipliers; for autonomous orbits the trivial
        direction is deflated (:func:`saltation.orbits.floquet.autonomous_multipliers`).

    Raises
    ------
    ModelError
        A ``period`` that contradicts the forcing period, a state of the wrong size, a guess of every
        node without a period, an invalid parameter or number of segments, a ``mode0`` that is not a
        mode of the model (the message lists its modes).
    ConvergenceError
        Newton did not converge (with its residual history); a :class:`NoOrbitNearGuessError` when,
        in addition, the flow from an autonomous guess comes to rest.
    StationaryStateError
        Shooting converged to a state that does not move: an equilibrium, a
        pseudo-equilibrium, or a period shrunk to zero.
    InconsistentResultError
        An autonomous orbit whose trivial multiplier is not 1 to
        :data:`TRIVIAL_MULTIPLIER_ACCURACY`.
    StartGuessError
        Without a guess: the transient failed, diverged or shows no oscillation.
    IntegrationError, InitialModeError
        The shot from the guess itself fails (Newton's later trial steps that fail are shortened); a
        guess state outside the domain of ``mode0`` (the message names the mode and its conditions).
    KernelCacheError
        A model given as such cannot be compiled into the kernel cache.

    References
    ----------
    Stoer and Bulirsch, *Introduction to Numerical Analysis*, Springer, section 7.3 (single and
    multiple shooting).  Leine and Van Campen, "Fold bifurcations in discontinuous systems", eq. (9)
    (the saltation matrices in the monodromy).
    """
    if not isinstance(flow, Flow):  # a model
        flow = Flow(flow, tolerances=tolerances)
    segments = check_segments(segments, flow.system.n)  # (before a transient is integrated for a guess)
    if state0 is not None and np.ndim(state0) == 2 and period is None and flow.system.is_autonomous:
        raise ModelError(f"a guess of every node of the autonomous model {flow.system.name!r} needs a period guess")
    prob = ShootingProblem(flow, parameters, backward=backward, t0=t0, tolerances=tolerances, mode0=mode0)
    if state0 is None or (flow.system.is_autonomous and period is None):
        state0, period, prob.mode0 = starting_guess_and_mode(
            flow, prob.p, state0, period, t0=t0, backward=backward, length=transient_length, mode0=prob.mode0)
    if prob.mode0 is not None:  # the guess (its first node) lies in the mode's domain, or an error says why
        first = np.asarray(state0, dtype=float)
        prob.start_mode(first[0] if first.ndim == 2 else first, prob.p)
    if not prob.autonomous and period is not None:
        forced = prob.period_of(prob.pack(state0))
        if not abs(float(period) - forced) <= 1e-12 * forced:
            raise ModelError(
                f"model {flow.system.name!r} is forced: its period is the forcing period {forced:.10g} at these "
                f"parameters, not the period {period!r} given (omit period, or change the forcing parameters)"
            )
    guess = np.asarray(state0, dtype=float)
    if segments == 1 or guess.ndim == 1:
        if segments == 1:
            return prob.solve(prob.pack(state0, period), tol=tol, max_iter=max_iter)
        multiple = MultipleShootingProblem(prob, segments)
        u0 = prob.start_off_surfaces(prob.pack(state0, period))
        # the nodes together along the orbit: off the events, and out of its sliding motions where they fit
        U0 = multiple.start_off_surfaces(multiple.pack(u0), sliding_only=True)
        return multiple.solve(U0, tol=tol, max_iter=max_iter)
    multiple = MultipleShootingProblem(prob, segments)
    if guess.shape != (multiple.segments, flow.system.n):
        raise ModelError(f"a guess of every node of {segments} segments has shape ({segments}, {flow.system.n}), "
                         f"got {guess.shape}")
    prob.pack(guess[0], period)  # checks the period guess of an autonomous model
    U0 = guess.ravel()
    return multiple.solve(np.append(U0, float(period)) if prob.autonomous else U0, tol=tol, max_iter=max_iter)


# -- multiple shooting ---------------------------------------------------------------------
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
            trivial_error=orbit.trivial_error, mode0=orbit.mode0, **amplitude_measures(traj),
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
