"""The condition protocol: one or more equations attached to a periodic orbit.

A :class:`Condition` is asked, in this order, where to split the shot (:meth:`Condition.split_hint`),
its values and exact derivatives at the shot (:meth:`Condition.rows`; under multiple shooting
:meth:`Condition.segmented_rows`), and, at every accepted point, to move its guesses along
(:meth:`Condition.accept`).  A condition that finds the split in the wrong place raises
:class:`Resplit` with a better one.
"""

from __future__ import annotations

import abc
from collections.abc import Sequence

import numpy as np

from saltation.orbits.conditions.shot import Rows, Segments, Shot


class Condition(abc.ABC):
    """One or more equations attached to a periodic orbit (see :mod:`saltation.orbits.conditions`).

    A subclass sets the class attributes and writes :meth:`rows`; it overrides :meth:`split` (or
    :meth:`split_hint`) when its rows read the shot's fundamental matrix at an interior instant,
    :meth:`instant` when it reads the orbit elsewhere than there, and :meth:`segmented_rows` when under
    multiple shooting it reads more than the segment that holds its instant.

    Attributes
    ----------
    size : int
        Number of equations.
    extras : int
        Number of unknowns of its own (an instant).
    disabled : tuple of int
        Transitions the orbit passes as if they were not there (a grazing's virtual orbit).
    name : str
        What it locates, for messages.
    start_mode : str or None
        The mode the shot starts in (None: the model's initial-mode rule at ``x0``).
    anchors_phase : bool
        It fixes the phase of an autonomous orbit, whose phase condition it then replaces.
    """

    size: int = 1
    extras: int = 0
    disabled: tuple[int, ...] = ()
    name: str = "condition"
    #: the mode the shot starts in (None: the model's initial-mode rule at ``x0``)
    start_mode: str | None = None
    #: it fixes the phase of an autonomous orbit, whose phase condition it then replaces
    anchors_phase: bool = False

    def start(self) -> np.ndarray:
        """The initial values of its extra unknowns.

        Returns
        -------
        ndarray, shape (extras,)
            Their guesses (none by default).
        """
        return np.zeros(0)

    def split(self, extra: np.ndarray) -> float | None:
        """The instant to split the shot at (its fundamental matrix there is then free), or None.

        Parameters
        ----------
        extra : ndarray, shape (extras,)
            The condition's own unknowns.

        Returns
        -------
        float or None
            The instant, or None for a shot that is not split.
        """
        return None

    def split_hint(self, extra: np.ndarray, period: float | None, sign: float) -> float | None:
        """The instant to split the next shot at, before it is run, or None.

        The problem splits the shot at the first condition's hint that is not None.  By default the
        hint is :meth:`split`; a condition whose instant is only known from the last evaluation (an
        event's time) gives a hint from there.

        Parameters
        ----------
        extra : ndarray, shape (extras,)
            The condition's own unknowns.
        period : float or None
            A forced orbit's period at the problem's parameters (a scale of time); None for an
            autonomous orbit.
        sign : float
            The direction of time, ``+1`` or ``-1``.

        Returns
        -------
        float or None
            The instant, or None for no preference.
        """
        return self.split(extra)

    def instant(self, extra: np.ndarray) -> float | None:
        """The instant at which it reads the orbit, or None (the start, or the whole period).

        Multiple shooting reads it from the segment that holds that instant.

        Parameters
        ----------
        extra : ndarray, shape (extras,)
            The condition's own unknowns.

        Returns
        -------
        float or None
            The instant (by default the split instant).
        """
        return self.split(extra)

    @abc.abstractmethod
    def rows(self, shot: Shot, extra: np.ndarray, params: Sequence[int]) -> Rows:
        """Its values and derivatives at the shot.

        Parameters
        ----------
        shot : Shot
            The shot of the period (split where :meth:`split_hint` asked).  It holds all a condition
            may read besides: how it was run, partial runs, the monodromy from another start, the
            period under other parameters.
        extra : ndarray, shape (extras,)
            The condition's own unknowns.
        params : sequence of int
            The parameter indices of the derivative columns, in order.

        Returns
        -------
        Rows
            ``size`` equations and their derivatives.

        Raises
        ------
        Resplit
            If the shot must be split elsewhere first.
        """

    def segmented_rows(self, segments: Segments, extra: np.ndarray, params: Sequence[int]
                       ) -> tuple[int | None, Rows]:
        """Its values and derivatives under multiple shooting.

        By default :meth:`rows` at the shot of the segment that holds :meth:`instant` (the first
        segment when it is None), its derivatives by that segment's node.

        Parameters
        ----------
        segments : Segments
            The period shot in segments.
        extra : ndarray, shape (extras,)
            The condition's own unknowns.
        params : sequence of int
            The parameter indices of the derivative columns, in order.

        Returns
        -------
        segment : int or None
            The segment whose node ``d_x0`` is by, or None when ``d_x0`` is by every node (shape
            ``(size, m n)``).
        rows : Rows
            ``size`` equations and their derivatives.

        Raises
        ------
        Resplit
            If the shot must be split elsewhere first.
        """
        t = self.instant(extra)
        i = 0 if t is None else segments.segment_of(t)
        return i, self.rows(segments.shot(i), extra, params)

    def accept(self, shot: Shot, extra: np.ndarray) -> None:
        """Called at every accepted point: move the guesses along.

        Parameters
        ----------
        shot : Shot
            The accepted point's shot.
        extra : ndarray, shape (extras,)
            The condition's own unknowns there.
        """


class Resplit(Exception):
    """Raised by :meth:`Condition.rows`: the shot must be split again, at the instant ``t``.

    Parameters
    ----------
    t : float
        The instant to split the shot at.
    """

    def __init__(self, t: float):
        super().__init__(t)
        self.t = t


__all__ = ["Condition", "Resplit"]
