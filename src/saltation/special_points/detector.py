"""The special-point detector: the sequence of detection at each continuation step, and what it is made of.

:class:`SpecialPointDetector` is what the continuation engine is handed.  At each step it asks whether the
orbit's event sequence changed; if so the change is located and classified
(:mod:`~saltation.special_points.nonsmooth`), and the smooth pieces of the step are searched by test
functions (:mod:`~saltation.special_points.smooth`); a declared symmetry adds the half-period map
(:mod:`~saltation.special_points.symmetric`).  The records are built in
:mod:`~saltation.special_points.points`.  Those modules' functions take the detector as their context
(:class:`~saltation.special_points.context.DetectionContext`, which it extends): this class holds the
sequencing only.

Smooth special points are found by test functions and located by the
Illinois method along the secant between two branch points:

* fold (turning point): the parameter component of the tangent changes sign;
* period doubling: a real multiplier passes -1 (``prod(mu + 1)`` changes sign);
* Neimark-Sacker: a complex pair leaves the unit circle (a product of two multipliers passes 1);
* branch point: a real multiplier passes +1 without a turning point (``prod(mu - 1)`` changes sign);
* Hopf (equilibria): a complex pair of eigenvalues crosses the imaginary axis.

*Discontinuous* (non-smooth) points are where the orbit's event sequence
changes.  They are located by bisection along the secant to ``locate_tol``;
the monodromies on both sides, ``M-`` and ``M+``, give the set-valued
Floquet multipliers, the eigenvalues of ``(1 - q) M- + q M+`` for ``q`` in
``[0, 1]``.  Where that set crosses the unit circle the point is a
discontinuous fold (through +1), flip (through -1) or Neimark-Sacker (a
complex pair); if it stays on one side it is a jump without crossing.

For a model that declares a symmetry (:mod:`saltation.model.symmetry`), the symmetric orbits' multipliers
are split by the half-period map (:mod:`saltation.orbits.symmetry`): where a real half-period multiplier
passes -1 the point is a ``symmetry_breaking`` (the full multiplier passes +1, but the branch goes on),
located on the half-period map, where it is regular; at corners the set-valued half-period multipliers
classify the point (``discontinuous_symmetry_breaking`` through -1), and a branch that passes at a
non-smooth point from symmetric to asymmetric orbits records a ``discontinuous_symmetry_breaking`` too.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from saltation.branches.branch import SpecialPoint, SpecialPointKind
from saltation.branches.corrector import Solution, canonical_events
from saltation.orbits.symmetry import SymmetricMultipliers
from saltation.special_points import nonsmooth, smooth, symmetric
from saltation.special_points.context import DetectionContext
from saltation.special_points.points import with_border_scenario
from saltation.special_points.smooth import smooth_points
from saltation.special_points.symmetric import symmetry_breaking_corner

__all__ = ["SpecialPointDetector"]


class SpecialPointDetector(DetectionContext):
    """Looks for special points between consecutive branch points and locates them.

    Made by the continuation engine as ``SpecialPointDetector(problem, corrector, branch)`` (a
    :data:`~saltation.branches.continuation.DetectorFactory`).  It is the context its parts are handed
    (:class:`~saltation.special_points.context.DetectionContext`); its methods sequence them.

    Parameters
    ----------
    problem : ShootingProblem or EquilibriumProblem
        The branch's problem.
    corrector : Corrector
        The branch's corrector (its settings give the location tolerance ``locate_tol``).
    branch : Branch
        The branch being followed (its kind, time direction and whether it is autonomous).
    """

    # -- the engine's protocol -------------------------------------------------------------
    def past_failure(self, prev: Solution) -> tuple[Solution, SpecialPoint] | None:
        """Past a grazing that stopped the corrector: :func:`~saltation.special_points.nonsmooth.past_grazing`.

        Parameters
        ----------
        prev : Solution
            The last point the corrector reached.

        Returns
        -------
        tuple of (Solution, SpecialPoint) or None
            The first solution across the grazing and the grazing's record (with Feigin's scenario), or None.
        """
        found = nonsmooth.past_grazing(self, prev)
        return None if found is None else (found[0], self.with_scenario(found[1]))

    def at_failure(self, prev: Solution, failed: float) -> SpecialPoint | None:
        """The end of a branch whose last orbit comes to lie on a switching surface all round:
        :func:`~saltation.special_points.nonsmooth.on_surface_end`.

        Parameters
        ----------
        prev : Solution
            The last point the corrector reached.
        failed : float
            A parameter value beyond it at which the corrector failed.

        Returns
        -------
        SpecialPoint or None
            A ``bracketed`` point between the last orbit and the first failure (with Feigin's scenario), or None.
        """
        found = nonsmooth.on_surface_end(self, prev, failed)
        return None if found is None else self.with_scenario(found)

    def with_scenario(self, sp: SpecialPoint) -> SpecialPoint:
        """A point with Feigin's prediction of its border collision, where it has one-sided multipliers:
        :func:`~saltation.special_points.points.with_border_scenario`.

        Parameters
        ----------
        sp : SpecialPoint
            A special point found on the branch.

        Returns
        -------
        SpecialPoint
            The point, its ``scenario`` and ``period_two`` filled in where it has both sides' multipliers.
        """
        return with_border_scenario(sp, autonomous=self.autonomous)

    # -- sequencing -----------------------------------------------------------------------
    def check(self, a: Solution, b: Solution, index: int) -> list[SpecialPoint]:
        """The special points between two consecutive branch points, in branch order.

        Where the event sequence changes, the non-smooth point is located first; the smooth test
        functions are then evaluated on each smooth piece of the step (from ``a`` to the located
        point's near side, from its far side to ``b``), so that a fold or a multiplier crossing in the
        same step as the change is found too.

        Parameters
        ----------
        a, b : Solution
            Consecutive corrected points.
        index : int
            The index of ``a`` on the branch.

        Returns
        -------
        list of SpecialPoint
            The located points (folds and multiplier crossings that fail their check are left out), the
            non-smooth ones with Feigin's scenario (:meth:`with_scenario`).

        Raises
        ------
        SaltationError
            If the one-sided monodromies needed to classify a non-smooth point are missing.
        """
        return [self.with_scenario(sp) for sp in self._check(a, b, index, None)]

    def _check(self, a: Solution, b: Solution, index: int,
               bracket: tuple[Solution, Solution] | None) -> list[SpecialPoint]:
        """:meth:`check`, with the bracket of the step's first change when it is already located."""
        if canonical_events(a.summary.event_ids) == canonical_events(b.summary.event_ids):
            return smooth_points(self, a, b, index)
        lo, hi = bracket if bracket is not None else self._bisect_event_change(a, b)
        hi, following = self._past_unresolved_sequences(hi, b)
        corner = symmetry_breaking_corner(self, self.nonsmooth_point(lo, hi, index, far=(a, b)), a, b)
        before = smooth_points(self, a, lo, index) if lo is not a else []
        # a step may hold more than one change: the rest of it is checked as a step of its own, from the
        # next change's bracket where that was located already
        after = self._check(hi, b, index, following) if hi is not b else []
        return [*before, corner, *after]

    def _past_unresolved_sequences(
        self, hi: Solution, b: Solution,
    ) -> tuple[Solution, tuple[Solution, Solution] | None]:
        """``hi``, or the far side of the changes beyond it that lie within the resolution of the first;
        and the bracket of the next change, where one was located and is not merged.

        Between ``hi`` (just past a change) and ``b`` the sequence may change again.  Where the orbits of
        ``hi``'s sequence span no more than the location tolerance or the integration's error estimate
        (:meth:`~saltation.engine.flow.Flow.integration_error`), the two changes are one point: a
        simultaneous change (two corners collided at once, as the symmetric orbit's two contacts of Fig. 3,
        which DOP853's error splits by some 1e-10 in the parameter), classified from its outer sides.
        A change farther away is a point of its own: its bracket is returned, so that it is not located a
        second time.
        """
        seq_b = canonical_events(b.summary.event_ids)
        while canonical_events(hi.summary.event_ids) != seq_b:
            lo2, hi2 = self._bisect_event_change(hi, b)
            width = float(np.linalg.norm(lo2.z - hi.z))
            if width > max(self.tol, self.state_resolution(hi)):
                return hi, (lo2, hi2)
            hi = hi2
        return hi, None

    # -- the parts, as methods -------------------------------------------------------------
    def half_map(self, sol: Solution) -> SymmetricMultipliers | None:
        """The half-period map of a solution's orbit and its split multipliers:
        :func:`~saltation.special_points.symmetric.half_map`.

        Parameters
        ----------
        sol : Solution
            A corrected branch point.

        Returns
        -------
        SymmetricMultipliers or None
            None without a declared symmetry or when the half shot fails.
        """
        return symmetric.half_map(self, sol)

    def locate_symmetry_breaking(self, a: Solution, b: Solution, index: int) -> SpecialPoint:
        """Locate a symmetry breaking on the symmetric orbits:
        :func:`~saltation.special_points.symmetric.locate_symmetry_breaking`.

        Parameters
        ----------
        a, b : Solution
            Symmetric branch points on either side.
        index : int
            The index of ``a`` on the branch.

        Returns
        -------
        SpecialPoint
            Status ``located``, or ``failed`` with the two branch points' bracket.
        """
        return symmetric.locate_symmetry_breaking(self, a, b, index)

    def locate_smooth(
        self, a: Solution, b: Solution, index: int, kind: SpecialPointKind, test: Callable[[Solution], float]
    ) -> SpecialPoint | None:
        """Illinois iteration on a test function along the secant:
        :func:`~saltation.special_points.smooth.locate_smooth`.

        Parameters
        ----------
        a, b : Solution
            Corrected points on either side of the sign change.
        index : int
            The index of ``a`` on the branch.
        kind : SpecialPointKind
            The kind looked for.
        test : callable
            The test function of a :class:`Solution`.

        Returns
        -------
        SpecialPoint or None
            The located point, or None where the multipliers do not meet the kind's condition.
        """
        return smooth.locate_smooth(self, a, b, index, kind, test)

    def locate_nonsmooth(self, a: Solution, b: Solution, index: int) -> SpecialPoint:
        """Bisection along the secant on the event sequence, then set-valued multipliers.

        Parameters
        ----------
        a, b : Solution
            Corrected points with different event sequences.
        index : int
            The index of ``a`` on the branch.

        Returns
        -------
        SpecialPoint
            The non-smooth point (see :meth:`nonsmooth_point`).

        Raises
        ------
        SaltationError
            If the one-sided monodromies needed to classify it are missing.
        """
        lo, hi = self._bisect_event_change(a, b)
        return self.nonsmooth_point(lo, hi, index, far=(a, b))

    def _bisect_event_change(self, a: Solution, b: Solution) -> tuple[Solution, Solution]:
        """:func:`~saltation.special_points.nonsmooth.bisect_event_change`."""
        return nonsmooth.bisect_event_change(self, a, b)

    def nonsmooth_point(
        self, lo: Solution, hi: Solution, index: int, note: str = "", *, far: tuple[Solution, Solution] | None = None
    ) -> SpecialPoint:
        """Special point record from the two one-sided solutions around a non-smooth point:
        :func:`~saltation.special_points.nonsmooth.nonsmooth_point`.

        Parameters
        ----------
        lo, hi : Solution
            The bracketing solutions (``lo`` on the side of point ``index``).
        index : int
            The index of the branch point before the non-smooth point.
        note : str
            A note for the record.
        far : tuple of Solution, optional
            The branch points beyond ``lo`` and ``hi``.

        Returns
        -------
        SpecialPoint
            The classified point, with its one-sided multipliers and their accuracy.

        Raises
        ------
        SaltationError
            If the one-sided monodromies needed to classify it are missing.
        """
        return nonsmooth.nonsmooth_point(self, lo, hi, index, note, far=far)
