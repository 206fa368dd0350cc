"""What a condition reads: one shot of the period, its piece at an interior instant, and its rows.

A condition sees the orbit through a :class:`Shot` (or, under multiple shooting, through
:class:`Segments`, the period shot in segments) and answers with :class:`Rows`.  The shot carries the
narrow context a condition may use: how it was run (the flow, ``t0``, the direction of time, the
tolerances, the disabled transitions), a partial run to another instant (:meth:`Shot.run_to`), the
monodromy of the period from another start (:meth:`Shot.monodromy`) and the period under other
parameters (:meth:`Shot.period_at`).  :class:`Located` is a solved conditioned problem.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from saltation.engine.flow import Flow, Trajectory
from saltation.errors import SaltationError


@dataclass
class Piece:
    """The shot at an interior instant: time, state, mode, ``Phi(t, t0)`` and the sensitivities ``d x / d p_j``.

    Attributes
    ----------
    t : float
        The instant.
    x : ndarray, shape (n,)
        The state there.
    mode : str
        The mode there.
    fundamental : ndarray, shape (n, n)
        The fundamental solution matrix ``Phi(t, t0)`` (saltation matrices included).
    sensitivities : dict of int to ndarray, shape (n,)
        ``d x(t) / d p_j``, by parameter index.
    sliding : bool
        Whether the shot is on a sliding motion there.
    velocity : ndarray, shape (n,), or None
        The vector field there (the sliding field on a sliding motion).
    """

    t: float
    x: np.ndarray
    mode: str
    fundamental: np.ndarray
    sensitivities: dict[int, np.ndarray]
    sliding: bool = False
    velocity: np.ndarray | None = None


@dataclass
class Shot:
    """One shot of the period and what conditions read from it.

    Attributes
    ----------
    x0 : ndarray, shape (n,)
        The initial state.
    period : float
        The period.
    parameters : ndarray
        Parameter values.
    trajectory : Trajectory
        The whole period, with its monodromy.
    sensitivities : dict of int to ndarray
        ``d x(end) / d p_j`` as carried by the shot (the period's motion with the parameter is added by
        the periodicity rows).
    piece : Piece or None
        The shot at the split instant, when a condition asked for one.
    flow, t0, sign, tolerances, disabled :
        How the shot was run, for conditions that need a further partial run.
    mode0 : str or None
        With multiple shooting: the mode the segment from ``x0`` at ``t0`` starts in (the conditions'
        derivatives by ``x0`` are then by that segment's node); None: the trajectory's.
    forcing_period : callable or None
        A forced orbit's period as a function of the parameter values; None for an autonomous orbit,
        whose period is an unknown of its own (:meth:`period_at`).
    rerun : callable or None
        ``(x0, T, p) -> M``: the monodromy of the whole period from another start, of another length,
        under other parameters, run and closed at the seam as this shot was (:meth:`monodromy`); None
        for one segment's shot under multiple shooting.
    """

    x0: np.ndarray
    period: float
    parameters: np.ndarray
    trajectory: Trajectory
    sensitivities: dict[int, np.ndarray]
    piece: Piece | None
    flow: Flow
    t0: float
    sign: float
    tolerances: object
    disabled: tuple[int, ...] = ()
    mode0: str | None = None
    forcing_period: Callable[[np.ndarray], float] | None = field(default=None, repr=False)
    rerun: Callable[[np.ndarray, float, np.ndarray], np.ndarray] | None = field(default=None, repr=False)

    @property
    def autonomous(self) -> bool:
        """Whether the period is an unknown of its own (an autonomous orbit), not the forcing's."""
        return self.forcing_period is None

    def period_at(self, p: np.ndarray) -> float:
        """The period under the parameter values ``p``.

        Parameters
        ----------
        p : ndarray
            Parameter values.

        Returns
        -------
        float
            An autonomous orbit's period (an unknown, the shot's own); a forced orbit's forcing period at
            ``p`` (times the number of forcing periods it closes after).

        Raises
        ------
        ModelError
            If the forcing period is not positive and finite at ``p``.
        """
        return self.period if self.forcing_period is None else self.forcing_period(p)

    def monodromy(self, x0: np.ndarray, T: float, p: np.ndarray) -> np.ndarray:
        """The monodromy of the period from ``x0``, of length ``T``, under ``p``, closed at the seam as this shot.

        Parameters
        ----------
        x0 : ndarray, shape (n,)
            The initial state.
        T : float
            The period.
        p : ndarray
            Parameter values.

        Returns
        -------
        ndarray, shape (n, n)
            The monodromy.

        Raises
        ------
        SaltationError
            If the shot cannot be run again (one segment's shot under multiple shooting).
        IntegrationError, ModelError, InitialModeError
            If the run fails (see :meth:`Flow.run`).
        """
        if self.rerun is None:
            raise SaltationError("this shot is one segment of several: its period cannot be run again from it")
        return self.rerun(x0, T, p)

    def run_to(self, t: float, params: Sequence[int]) -> Piece:
        """A partial run from ``t0`` to ``t`` with the sensitivities of ``params`` (one integration each).

        Parameters
        ----------
        t : float
            The instant to run to.
        params : sequence of int
            Indices of the parameters whose sensitivities to carry.

        Returns
        -------
        Piece
            The shot at ``t``.

        Raises
        ------
        IntegrationError, ModelError, InitialModeError
            If a run fails (see :meth:`Flow.run`).
        """
        mode0 = self.mode0 if self.mode0 is not None else self.trajectory.mode0
        runs = [self.flow.run(self.x0, self.t0, t, self.parameters, mode0=mode0, variational=True,
                              sensitivity=j, disabled=self.disabled, tolerances=self.tolerances)
                for j in (list(params) or [-1])]
        first = runs[0]
        return Piece(t=float(t), x=first.x1, mode=first.mode1, fundamental=first.monodromy,
                     sensitivities={j: r.parameter_sensitivity for j, r in zip(params, runs)},
                     sliding=first.sliding_at_end, velocity=first.velocity_end)


def segment_of(t: float, times: np.ndarray) -> int:
    """The segment whose interval holds the instant ``t`` (the nearest, for an instant just outside).

    Parameters
    ----------
    t : float
        An instant.
    times : ndarray, shape (m + 1,)
        The segments' bounds, in the direction of time.

    Returns
    -------
    int
        The segment's index, in ``0 .. m - 1``.
    """
    m = len(times) - 1
    pos = (t - times[0]) / (times[-1] - times[0]) * m
    return int(min(max(math.floor(pos), 0), m - 1))


@dataclass
class Segments:
    """The period shot in ``m`` segments (multiple shooting), as conditions read it.

    Attributes
    ----------
    whole : Shot
        The whole period from the first node: the segments' trajectories joined, no sensitivities.
    nodes : ndarray, shape (m n,)
        The segments' initial states, one after the other.
    times : ndarray, shape (m + 1,)
        The segments' bounds ``t_i = t0 + s i T / m``.
    trajectories : list of Trajectory
        Each segment's run, with its transfer matrix.
    piece : Piece or None
        The shot at the split instant, when a condition asked for one.
    split : int or None
        The segment that holds the split instant.
    """

    whole: Shot
    nodes: np.ndarray
    times: np.ndarray
    trajectories: list[Trajectory]
    piece: Piece | None = None
    split: int | None = None

    def segment_of(self, t: float) -> int:
        """The segment whose interval holds the instant ``t`` (the nearest, for an instant just outside).

        Parameters
        ----------
        t : float
            An instant.

        Returns
        -------
        int
            The segment's index.
        """
        return segment_of(t, self.times)

    def shot(self, i: int) -> Shot:
        """The shot of segment ``i``: from its node at ``t_i``, its derivatives by that node.

        Parameters
        ----------
        i : int
            The segment.

        Returns
        -------
        Shot
            The whole period's trajectory, from the node ``i`` at ``t_i``, in the mode the segment starts
            in, with the piece where the split lies in this segment.
        """
        n = len(self.whole.x0)
        return replace(self.whole, x0=np.array(self.nodes[i * n:(i + 1) * n]), t0=float(self.times[i]),
                       piece=self.piece if i == self.split else None, mode0=self.trajectories[i].mode0, rerun=None)

    def transfer(self, i: int, x: np.ndarray, t_a: float, t_b: float, p: np.ndarray) -> np.ndarray:
        """Segment ``i`` run again from ``x`` at ``t_a`` to ``t_b`` under ``p``: its transfer matrix.

        Parameters
        ----------
        i : int
            The segment (it starts in the mode it starts in now).
        x : ndarray, shape (n,)
            The initial state.
        t_a, t_b : float
            The interval.
        p : ndarray
            Parameter values.

        Returns
        -------
        ndarray, shape (n, n)
            ``Phi(t_b, t_a)``, saltation matrices included.

        Raises
        ------
        IntegrationError, ModelError, InitialModeError
            If the run fails (see :meth:`Flow.run`).
        """
        w = self.whole
        return w.flow.run(x, t_a, t_b, p, mode0=self.trajectories[i].mode0, variational=True, disabled=w.disabled,
                          tolerances=w.tolerances).monodromy


@dataclass
class Rows:
    """A condition's values and derivatives.

    Attributes
    ----------
    value : ndarray, shape (m,)
        The ``m`` equations' values.
    d_x0 : ndarray, shape (m, n)
        Derivatives by the initial state (or the node of the segment that holds the condition).
    d_period : ndarray, shape (m,)
        Derivatives by the period.
    d_parameters : ndarray, shape (m, k)
        Derivatives by the parameters of the derivative columns, in the problem's order.
    d_extra : ndarray, shape (m, e)
        Derivatives by the condition's own extra unknowns.
    """

    value: np.ndarray
    d_x0: np.ndarray
    d_period: np.ndarray
    d_parameters: np.ndarray
    d_extra: np.ndarray

    @classmethod
    def zeros(cls, size: int, n: int, k: int, e: int) -> Rows:
        """Rows of zeros.

        Parameters
        ----------
        size : int
            Number of equations.
        n : int
            Number of state (or node) columns.
        k : int
            Number of parameter columns.
        e : int
            Number of the condition's own unknowns.

        Returns
        -------
        Rows
            Zeros of those shapes.
        """
        return cls(np.zeros(size), np.zeros((size, n)), np.zeros(size), np.zeros((size, k)), np.zeros((size, e)))


@dataclass
class Located:
    """A solution of a conditioned problem.

    Attributes
    ----------
    unknowns : ndarray
        ``(x0[, T], free parameters..., extras...)``.
    state0 : ndarray
        The orbit's initial state.
    period : float
        Its period.
    parameters : ndarray
        Every parameter's value there.
    shot : Shot
        The shot at the solution.
    accuracy : ndarray
        Per free parameter: the Newton correction that would follow, plus the integration error carried
        to it through the inverse Jacobian (an estimate of its error).
    residuals : list of float
        Newton's residual history.
    """

    unknowns: np.ndarray
    state0: np.ndarray
    period: float
    parameters: np.ndarray
    shot: Shot
    accuracy: np.ndarray
    residuals: list[float] = field(default_factory=list)


__all__ = ["Located", "Piece", "Rows", "Segments", "Shot", "segment_of"]
