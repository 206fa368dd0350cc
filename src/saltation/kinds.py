"""The vocabulary of branches and their special points: kinds, statuses, limits and stop reasons.

A foundation module (it imports nothing of the package), so that the orbit layer, which classifies
multipliers, and the special-point layer name the kinds they find below the branch records of
:mod:`saltation.branches.branch`, which re-exports them.
"""

from __future__ import annotations

import enum


class SpecialPointKind(enum.Enum):
    """Kinds of special points; the value is the name used in files and on the command line."""

    FOLD = "fold"
    #: a real multiplier passes +1 without a turning point of the parameter: branches cross (a transcritical
    #: or pitchfork point, whether or not the model declares the symmetry behind it)
    BRANCH_POINT = "branch_point"
    PERIOD_DOUBLING = "period_doubling"
    NEIMARK_SACKER = "neimark_sacker"
    HOPF = "hopf"
    DISCONTINUOUS_FOLD = "discontinuous_fold"
    DISCONTINUOUS_FLIP = "discontinuous_flip"
    DISCONTINUOUS_NEIMARK_SACKER = "discontinuous_neimark_sacker"
    NONSMOOTH_NO_CROSSING = "nonsmooth_no_crossing"
    GRAZING = "grazing"
    GRAZING_SLIDING = "grazing_sliding"
    CROSSING_SLIDING = "crossing_sliding"
    SWITCHING_SLIDING = "switching_sliding"
    ADDING_SLIDING = "adding_sliding"
    #: the orbits of a branch shrink onto an equilibrium: located where their excursion extrapolates to zero
    CYCLE_COLLAPSE = "cycle_collapse"
    #: on a two-parameter curve of special points: where two defining conditions meet (the kind of the
    #: special point changes along the curve; :attr:`SpecialPoint.sides` names the two)
    CODIMENSION_TWO = "codimension_two"
    #: an equilibrium of a mode reaches a switching surface, where a pseudo-equilibrium meets it
    #: (:attr:`SpecialPoint.classification`: ``persistence`` or ``nonsmooth_fold``)
    BOUNDARY_EQUILIBRIUM = "boundary_equilibrium"
    #: a symmetric orbit's antisymmetric multiplier passes +1 (its half-period multiplier -1): two branches
    #: of asymmetric orbits leave the symmetric branch, which goes on (a pitchfork, not a fold)
    SYMMETRY_BREAKING = "symmetry_breaking"
    #: the set-valued half-period multiplier of a symmetric orbit jumps through -1 at a corner
    DISCONTINUOUS_SYMMETRY_BREAKING = "discontinuous_symmetry_breaking"
    #: where a user's monitor (:class:`saltation.branches.monitors.Monitor`) crosses zero along a branch
    MONITOR = "monitor"

    @property
    def is_nonsmooth(self) -> bool:
        return self in NONSMOOTH_KINDS


NONSMOOTH_KINDS = frozenset(
    {
        SpecialPointKind.DISCONTINUOUS_FOLD,
        SpecialPointKind.DISCONTINUOUS_FLIP,
        SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER,
        SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING,
        SpecialPointKind.NONSMOOTH_NO_CROSSING,
        SpecialPointKind.GRAZING,
        SpecialPointKind.GRAZING_SLIDING,
        SpecialPointKind.CROSSING_SLIDING,
        SpecialPointKind.SWITCHING_SLIDING,
        SpecialPointKind.ADDING_SLIDING,
    }
)


class CodimensionTwoKind(enum.Enum):
    """Names of the smooth codimension-two points of a fixed point of the period map, met along a curve of folds,
    period doublings or Neimark-Sacker points (Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed.,
    Springer 2004, section 9.1, the codimension-two bifurcations of fixed points of maps); the value is the
    name used in files.

    :attr:`SpecialPoint.codimension_two` names the point; :attr:`SpecialPoint.sides` holds the curve's kind
    and the kind it meets there.
    """

    #: on a fold curve: the quadratic normal-form coefficient ``<p, B(q, q)> / 2`` changes sign (two folds meet)
    CUSP = "cusp"
    #: 1:1 resonance: a double multiplier +1 (Jordan block); on a Neimark-Sacker curve ``kappa = cos theta -> 1``,
    #: on a fold curve a second multiplier reaches +1 (the Bogdanov-Takens point of the map)
    STRONG_RESONANCE_1_1 = "strong_resonance_1_1"
    #: 1:2 resonance: a double multiplier -1; ``kappa -> -1`` on a Neimark-Sacker curve, a second multiplier -1
    #: on a period-doubling curve
    STRONG_RESONANCE_1_2 = "strong_resonance_1_2"
    #: 1:3 resonance: multipliers ``exp(+-2 pi i / 3)`` (``kappa = -1/2``)
    STRONG_RESONANCE_1_3 = "strong_resonance_1_3"
    #: 1:4 resonance: multipliers ``+-i`` (``kappa = 0``)
    STRONG_RESONANCE_1_4 = "strong_resonance_1_4"
    #: fold-flip: multipliers +1 and -1 (a fold curve meets a period-doubling curve)
    FOLD_FLIP = "fold_flip"
    #: fold-Neimark-Sacker: a multiplier +1 and a complex pair on the unit circle
    FOLD_NEIMARK_SACKER = "fold_neimark_sacker"
    #: flip-Neimark-Sacker: a multiplier -1 and a complex pair on the unit circle
    FLIP_NEIMARK_SACKER = "flip_neimark_sacker"
    #: generalized period doubling: the cubic normal-form coefficient of the flip vanishes (needs that coefficient)
    GENERALIZED_PERIOD_DOUBLING = "generalized_period_doubling"
    #: Chenciner (degenerate Neimark-Sacker): the first Lyapunov coefficient of the torus vanishes (needs it)
    CHENCINER = "chenciner"


class SpecialPointStatus(str, enum.Enum):
    """How a special point was found; the value is the name used in files."""

    #: by Newton on its defining system (:mod:`saltation.orbits.conditions`), to the stated accuracy
    LOCATED = "located"
    #: between two computed solutions (a bisection of a test function or of the event sequence), or
    #: extrapolated: it lies within ``bracket``, and ``parameter`` is a point of it
    BRACKETED = "bracketed"
    #: its location failed: only the branch points around it are known
    FAILED = "failed"


class Limits(str, enum.Enum):
    """How the one-sided multipliers of a non-smooth point were obtained; the value is the name in files."""

    #: not one-sided (a smooth point)
    NONE = ""
    #: the limits at the boundary orbit, with closed-form saltation matrices at the corner
    EXACT = "exact"
    #: the limits at the boundary orbit, with the saltation matrices of the nearest orbit
    NEAREST_SALTATION = "nearest_saltation"
    #: the monodromies of the two orbits bracketing the point
    NEAREST_ORBITS = "nearest_orbits"
    #: the limit along the branch, its square-root behaviour extrapolated (``growth_exponents`` holds the
    #: fitted exponents of those that grow without bound)
    EXTRAPOLATED = "extrapolated"
    #: a grazing: the grazing orbit's monodromy on the side that misses the surface
    GRAZING = "grazing"
    #: an orbit that lies on a switching surface all round: the variational equation along it with its own
    #: mode's Jacobian and with the Jacobian of the mode across the surface (:mod:`saltation.orbits.on_surface`)
    ON_SURFACE = "on_surface"

    @classmethod
    def parse(cls, text: str) -> tuple[Limits, tuple[float, ...]]:
        """A name as files hold it, with the growth exponents that files before this release wrote into
        it (``"extrapolated (unbounded: |mu| ~ d^-0.50)"``)."""
        import re

        head = text.split(" (", 1)[0].strip()
        exponents = tuple(float(a) for a in re.findall(r"d\^(-?[0-9.]+(?:e-?[0-9]+)?)", text))
        return cls(head), exponents


class BorderScenario(str, enum.Enum):
    """What Feigin's classification of a border collision predicts at a discontinuity-induced point; the value
    is the name used in files (:func:`saltation.orbits.border_collision.feigin_scenario`)."""

    #: the orbit crosses the border: one orbit on either side, it goes on as the other
    PERSISTENCE = "persistence"
    #: the orbits of the two sides lie on the same side of the point, meet there and vanish together
    NONSMOOTH_FOLD = "nonsmooth_fold"
    #: the theorem says nothing: a multiplier on the unit circle within the accuracy, both sides unbounded, or
    #: the one-sided multipliers of the half-period map needed (a symmetric orbit's symmetry breaking)
    UNDETERMINED = "undetermined"


class StopReason(enum.Enum):
    """Why a continuation run stopped; the value is the message."""

    PARAMETER_BOUND = "reached a parameter bound"
    MAX_POINTS = "reached the maximum number of points"
    MIN_STEP = "the corrector failed at the minimum step size"
    CLOSED_LOOP = "the branch closed on itself"
    USER = "stopped by the user"
    CYCLE_COLLAPSE = "the cycle collapsed onto an equilibrium"
    ERROR = "stopped by an error (the branch's stop_detail gives it)"
    MONITOR = "a monitor that stops the branch reached its value"


class Criticality(str, enum.Enum):
    """What a period doubling or Neimark-Sacker bifurcation gives birth to, by the sign of its normal-form
    coefficient (:func:`saltation.orbits.criticality.criticality`); the value is the name used in files."""

    #: a stable period-2 orbit or invariant circle (torus), on the side where the orbit is unstable
    SUPERCRITICAL = "supercritical"
    #: an unstable period-2 orbit or invariant circle, on the side where the orbit is stable
    SUBCRITICAL = "subcritical"
    #: the coefficient is zero within its accuracy: a higher-order term decides (a codimension-two point)
    DEGENERATE = "degenerate"


class BranchKind(enum.Enum):
    PERIODIC = "periodic"
    EQUILIBRIUM = "equilibrium"


__all__ = ["NONSMOOTH_KINDS", "BorderScenario", "BranchKind", "CodimensionTwoKind", "Criticality", "Limits",
           "SpecialPointKind", "SpecialPointStatus", "StopReason"]
