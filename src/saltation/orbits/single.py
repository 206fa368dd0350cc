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

import logging
import math
from collections.abc import Mapping, Sequence

import numpy as np

from saltation.engine.flow import (
    EventKind,
    Flow,
    Tolerances,
    Trajectory,
)
from saltation.engine.trajectory import SwitchingEvent
from saltation.errors import (
    ConvergenceError,
    InconsistentResultError,
    IntegrationError,
    ModelError,
    NoOrbitNearGuessError,
    SaltationError,
    StationaryStateError,
)
from saltation.orbits.conditions import Condition, ConditionedProblem
from saltation.orbits.floquet import (
    autonomous_multipliers,
    is_stable,
    multipliers_from_monodromy,
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
from saltation.orbits.seam import close_period

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
#: Newton steps of an autonomous orbit that make the period longer than this many times its guess are
#: shortened (as steps that do not reduce the residual): a period near zero can throw the next iterate far away.
PERIOD_GROWTH = 100.0


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


_log = logging.getLogger(__name__)

#: an autonomous orbit covers its closed curve ``k`` times when the flow from its state over ``T / k`` closes to
#: within this many times the integration tolerance (:meth:`ShootingProblem.repetitions`)
REPEAT_CLOSURE = 100.0

#: an event's saltation matrix is singular (its reset forgets) where ``|det S|`` is below this fraction of
#: ``max(1, |S|)^n``
SINGULAR_SALTATION = 1e-12


def forgetting_event(system, traj: Trajectory) -> tuple[int, SwitchingEvent, float] | None:
    """The first event of a run whose reset forgets: a transition with a reset whose saltation matrix is singular.

    A reset that forgets (a plastic impact, a landing that sticks, a neuron's voltage reset, a latch) maps a
    whole direction of states to one, so its saltation matrix (eq. (9)) has ``|det S|`` below
    :data:`SINGULAR_SALTATION` times ``max(1, |S|)^n``.

    Parameters
    ----------
    system : PiecewiseSystem or CompiledSystem
        The model (its resets).
    traj : Trajectory
        A run with its events and their saltation matrices.

    Returns
    -------
    tuple of (int, SwitchingEvent, float) or None
        The transition's index, the event and ``det S``; None if no event of the run forgets.

    Raises
    ------
    ValueError
        If an event's saltation matrix is not square (never for the engine's runs).
    """
    resets = getattr(system, "resets", None)
    if resets is None:
        return None
    for event in traj.events:
        k = int(event.transition)
        if event.kind is not EventKind.TRANSITION or not 0 <= k < len(resets) or resets[k] is None:
            continue
        S = np.asarray(event.saltation, dtype=float)
        if S.ndim != 2 or S.shape[0] != S.shape[1]:
            raise ValueError(f"the saltation matrix of event {event!r} is not square: shape {S.shape}")
        scale = max(1.0, float(np.linalg.norm(S))) ** S.shape[0]
        det = float(np.linalg.det(S))
        if abs(det) <= SINGULAR_SALTATION * scale:
            return k, event, det
    return None


def check_resets_run_backwards(system, traj: Trajectory) -> None:
    """Refuse a backward-time run that passes a reset that forgets.

    Backward in time the engine applies each transition's reset as written (see the user guide on
    backward time).  A reset whose saltation matrix is singular (a plastic impact, a landing that sticks,
    a neuron's voltage reset, a latch that forgets) maps a whole direction of states to one: it cannot be
    run backwards, and the backward map's zero multiplier would read as an infinitely unstable orbit in
    forward time, which does not exist.

    Parameters
    ----------
    system : PiecewiseSystem or CompiledSystem
        The model (its resets).
    traj : Trajectory
        A backward-time run.

    Raises
    ------
    ModelError
        Naming the first transition with a reset whose saltation matrix is singular at its event
        (:func:`forgetting_event`).
    """
    found = forgetting_event(system, traj)
    if found is not None:
        k, event, det = found
        tr = system.transitions[k]
        raise ModelError(
            f"backward-time shooting passes transition {k} ({tr.label}) at t = {event.t:.10g}, whose reset forgets "
            f"(its saltation matrix is singular, det S = {det:.3g}): a reset that forgets cannot be run backwards, "
            "and no infinitely unstable orbit lies behind it; shoot in forward time"
        )


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
    def single_shooting(self) -> ShootingProblem:
        """The problem itself."""
        return self

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
        """The shot with the crossing at the seam ``t0 = t0 + T`` counted once (:func:`saltation.orbits.seam.close_period`).

        Parameters
        ----------
        traj : Trajectory
            A shot over one period.
        p : ndarray
            Its parameter values.
        sensitivity : int
            Index of the parameter whose sensitivity the shot carries (-1: none).
        disabled : sequence of int
            Transitions the shot passes without firing.

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
        return close_period(self, traj, p, sensitivity, disabled=disabled)

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
        ModelError
            In backward time, if the orbit passes a reset that forgets (:func:`check_resets_run_backwards`).
        InconsistentResultError
            If an autonomous orbit's monodromy does not map the flow direction to itself within
            :data:`TRIVIAL_MULTIPLIER_ACCURACY`, or (with :attr:`mode0`) its shot ends in another mode
            (:meth:`check_mode_closes`).
        """
        reason = self.stationary_reason(u, lam, traj)
        if reason is not None:
            raise StationaryStateError(reason, u[: self.system.n], self.period_of(u, lam))
        self.check_mode_closes(traj)
        if self.backward:
            check_resets_run_backwards(self.system, traj)
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
            measures=measure_orbit(self.flow, u[: self.system.n], self.period_of(u, lam), self.parameters_at(lam, u),
                                   self.measures, t0=self.t0, mode0=traj.mode0, backward=self.backward),
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
        ModelError
            In backward time, when Newton fails and the forward run from the guess passes a reset that forgets
            (:meth:`forward_run_forgets`), or when the orbit's run passes one (:func:`check_resets_run_backwards`).
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
            forgets = self.forward_run_forgets(u0, lam)
            if forgets is not None:
                raise ModelError(f"shooting (backward time) for {self.system.name!r} found no orbit: {forgets}") from exc
            rest = self.comes_to_rest(u0, lam)
            if rest is not None:
                message = str(exc).split(" (residual history")[0]
                raise NoOrbitNearGuessError(f"{message}; {rest[1]}", exc.residuals, rest[0], float(u0[-1])) from exc
            raise
        if self.autonomous:
            k = self.repetitions(u, lam, ev.trajectory)
            if k > 1:  # a closed curve covered k times: the orbit is the curve once, with the period T / k
                T = self.period_of(u, lam)
                _log.info("shooting for %r converged to an orbit covered %d times (period %.10g): solving again with "
                          "the period %.10g", self.system.name, k, T, T / k)
                return self.solve(self.pack(u[: self.system.n], T / k), lam, tol=tol, max_iter=max_iter)
        return self.orbit(u, lam, ev.trajectory, history)

    def repetitions(self, u: np.ndarray, lam: float | None, trajectory: Trajectory) -> int:
        """How many times a converged autonomous orbit covers its closed curve over its period (1 for a minimal one).

        Newton on ``(x0, T)`` also solves for an orbit covered twice or more, ``phi(k T') = x0`` with ``T = k T'``,
        and from a poor guess (a reset that forgets, a period guess a multiple of the true one) it can converge
        there.  Candidates ``k`` come from the orbit's events: a sequence of ``N`` events that repeats with lag
        ``N / k``, at the same states and at time lags ``T / k``; an orbit without events tries ``k = 2, 3``.
        A candidate is confirmed when the flow from ``x0`` over ``T / k`` closes to within
        :data:`REPEAT_CLOSURE` times the integration tolerance.

        Parameters
        ----------
        u : ndarray
            The converged unknowns ``(x0, T)``.
        lam : float or None
            Value of the continuation parameter.
        trajectory : Trajectory
            The orbit's shot over its period.

        Returns
        -------
        int
            The number of times ``k >= 1``; always 1 for a forced orbit.

        Raises
        ------
        ValueError
            If the trajectory's event states do not have the model's dimension (never for the engine's runs).
        """
        if not self.autonomous:
            return 1
        n = self.system.n
        x0 = np.asarray(u[:n], dtype=float)
        T = float(self.period_of(u, lam))
        tol = self.tolerances or self.flow.tolerances
        close = REPEAT_CLOSURE * (tol.atol + tol.rtol * (1.0 + float(np.abs(x0).max())))
        events = trajectory.events
        count = len(events)
        if count:
            candidates = []
            for k in range(count, 1, -1):
                lag = count // k
                if count % k or not all(events[j].signature == events[j + lag].signature for j in range(count - lag)):
                    continue
                if all(np.shape(events[j].x_plus) == (n,) and float(np.abs(events[j].x_plus - events[j + lag].x_plus).max())
                       <= 1e3 * close and abs(abs(events[j + lag].t - events[j].t) - T / k) <= 1e-6 * T
                       for j in range(count - lag)):
                    candidates.append(k)
        else:
            candidates = [3, 2]
        p = self.parameters_at(lam)
        for k in candidates:  # the largest first: the shortest period
            try:
                run = self.flow.run(x0, self.t0, self.t0 + self.sign * T / k, p, mode0=trajectory.mode0,
                                    tolerances=self.tolerances)
            except SaltationError:
                continue
            if float(np.abs(run.x1 - x0).max()) <= close:
                return k
        return 1

    def forward_run_forgets(self, u: np.ndarray, lam: float | None = None) -> str | None:
        """Why a backward-time shooting from the guess ``u`` cannot find the forward orbit through it, or None.

        The forward run from the guess over its period is asked for a reset that forgets
        (:func:`forgetting_event`).  Such a reset maps a whole direction of states to one, so the forward orbit
        through it has no counterpart in backward time: the backward flow from the state after the reset does
        not return to the states before it, whatever the guess.

        Parameters
        ----------
        u : ndarray
            The guess ``(x0, T)`` (``x0`` alone for a forced model).
        lam : float, optional
            Value of the continuation parameter.

        Returns
        -------
        str or None
            The explanation, naming the transition; None in forward time, or when the forward run passes no
            reset that forgets (or cannot be integrated).

        Raises
        ------
        ValueError
            If an event's saltation matrix is not square (never for the engine's runs).
        """
        if not self.backward:
            return None
        p = self.parameters_at(lam)
        T = self.period_of(u, lam)
        if not (math.isfinite(T) and T > 0):
            return None
        try:
            traj = self.flow.run(np.asarray(u[: self.system.n], dtype=float), self.t0, self.t0 + T, p,
                                 mode0=self.mode0, variational=True, tolerances=self.tolerances)
        except SaltationError:
            return None
        found = forgetting_event(self.system, traj)
        if found is None:
            return None
        k, event, det = found
        return (f"the forward run from the guess passes transition {k} ({self.system.transitions[k].label}) at "
                f"t = {event.t:.10g}, whose reset forgets (its saltation matrix is singular, det S = {det:.3g}): the "
                "forward orbit through it has no backward-time counterpart; shoot in forward time")

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


__all__ = ["PERIOD_GROWTH", "REPEAT_CLOSURE", "SEAM_MARGIN", "SINGULAR_SALTATION", "STATIONARY_FACTOR", "STATIONARY_FRACTION",
           "TRIVIAL_MULTIPLIER_ACCURACY", "ShootingProblem", "check_resets_run_backwards", "forgetting_event", "stationary_floor"]
