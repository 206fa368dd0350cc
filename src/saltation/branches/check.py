"""The invariants that make a computed branch trustworthy, checked on the branch as it is.

A branch is a list of points with their multipliers and a list of special points.  Four things must
hold of it, whatever the model:

- the trivial multiplier of an autonomous orbit is 1, to the monodromy's own accuracy;
- every change of the number of multipliers outside the unit circle (of eigenvalues in the right half
  plane, for equilibria) between two consecutive points is covered by special points of that step whose
  kinds can make it: a fold, branch point or period doubling one multiplier, a Neimark-Sacker point or a
  Hopf point a pair, a discontinuous point the difference of its one-sided multipliers;
- each special point's multipliers agree with its kind (a fold has a multiplier at +1, a period doubling
  one at -1, a Neimark-Sacker point a complex pair on the unit circle, a discontinuous point a set-valued
  crossing where its kind says);
- a ``bracketed`` point lies inside its bracket, and its ``accuracy`` is at least the bracket's width;
- a non-smooth point whose border collision Feigin's classification decides (``scenario``) agrees with the
  branch through it: at a ``nonsmooth_fold`` the branch turns back (the points before and after it lie on
  the same side of its parameter), at ``persistence`` it goes on (on opposite sides).  Checked where the
  step holds that point alone and both points lie farther from it than its accuracy;
- a non-smooth point marks a change: its two sides differ in their event sequences (up to where the orbit
  starts: a rotation of the sequence as the section moves through an event is no change), in their
  stability, or it is a tangency;
- a branch that stopped because its corrector failed says what it found there: a special point at that
  end, or the corrector's named failure (``stop_detail``).

:func:`check_branch` returns the violations; :meth:`saltation.branches.branch.Branch.check` is the same.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from saltation.errors import SaltationError

#: a multiplier counts as outside the unit circle when ``|mu| > 1 + COUNT_TOL`` (as
#: :func:`saltation.orbits.floquet.is_stable` decides stability)
COUNT_TOL = 1e-6


@dataclass(frozen=True)
class Violation:
    """One broken invariant of a branch.

    Attributes
    ----------
    rule : str
        ``trivial_multiplier``, ``uncovered_change``, ``kind_mismatch``, ``bracket``, ``border_scenario``,
        ``no_change`` or ``silent_stop``.
    index : int or None
        The branch point (or the step from it to the next) where it is broken.
    message : str
        A sentence naming what is wrong.
    """

    rule: str
    index: int | None
    message: str


@dataclass(frozen=True)
class BranchCheck:
    """The result of :func:`check_branch`.

    Attributes
    ----------
    violations : tuple of Violation
        Every broken invariant (empty when the branch holds).
    """

    violations: tuple[Violation, ...]

    @property
    def ok(self) -> bool:
        return not self.violations

    def __bool__(self) -> bool:
        return self.ok

    def __str__(self) -> str:
        if self.ok:
            return "the branch holds every invariant"
        return "\n".join(f"[{v.rule}] {v.message}" for v in self.violations)

    def raise_if_broken(self) -> None:
        """Raise :class:`~saltation.errors.SaltationError` listing the violations, if there are any."""
        if not self.ok:
            raise SaltationError(f"the branch breaks {len(self.violations)} invariant(s):\n{self}")


# kinds and reasons are compared by their names: this module is imported by saltation.branches.branch
# ---------------------------------------------------------------------------------------------------
def unstable_count(mu, *, autonomous: bool, equilibrium: bool = False) -> int:
    """The number of multipliers outside the unit circle (the trivial one of an autonomous orbit left out),
    or of eigenvalues with positive real part for an equilibrium; an infinite multiplier counts."""
    mu = np.asarray(mu, dtype=complex).ravel()
    if equilibrium:
        return int(np.count_nonzero(mu.real > 0.0))
    if autonomous and mu.size:
        finite = np.where(np.isfinite(mu), np.abs(mu - 1.0), np.inf)
        mu = np.delete(mu, int(np.argmin(finite)))
    mod = np.where(np.isfinite(mu), np.abs(mu), np.inf)
    return int(np.count_nonzero(mod > 1.0 + COUNT_TOL))


def count_range(mu, *, autonomous: bool, equilibrium: bool = False) -> tuple[int, int]:
    """The fewest and most multipliers outside the unit circle that rounding allows: those within
    ``COUNT_TOL`` of the circle (of the imaginary axis, for an equilibrium) may be on either side."""
    mu = np.asarray(mu, dtype=complex).ravel()
    if equilibrium:
        return int(np.count_nonzero(mu.real > COUNT_TOL)), int(np.count_nonzero(mu.real > -COUNT_TOL))
    mu = _nontrivial(mu, autonomous)
    mod = np.where(np.isfinite(mu), np.abs(mu), np.inf)
    return int(np.count_nonzero(mod > 1.0 + COUNT_TOL)), int(np.count_nonzero(mod > 1.0 - COUNT_TOL))


def _nontrivial(mu, autonomous: bool) -> np.ndarray:
    mu = np.asarray(mu, dtype=complex).ravel()
    if autonomous and mu.size:
        finite = np.where(np.isfinite(mu), np.abs(mu - 1.0), np.inf)
        mu = np.delete(mu, int(np.argmin(finite)))
    return mu


def kind_tolerance(sp) -> float:
    """How far a special point's multipliers may lie from its kind's target and still agree with it.

    A located point satisfies its defining condition to the corrector's tolerance, and its multipliers
    are known to ``multipliers_accuracy``; at a fold the multiplier at +1 moves like the square root of
    the parameter's error.  The tolerance is the larger of ``1e-4``, ``10 sqrt(accuracy)`` (relative to
    the parameter's size) and ``10 multipliers_accuracy``.
    """
    acc = sp.accuracy if math.isfinite(sp.accuracy) else 0.0
    scale = max(1.0, abs(sp.parameter))
    tol = max(1e-4, 10.0 * math.sqrt(acc / scale))
    if math.isfinite(sp.multipliers_accuracy):
        tol = max(tol, 10.0 * sp.multipliers_accuracy)
    return tol


def _kind_problem(sp, autonomous: bool, equilibrium: bool) -> str | None:
    """Why a special point's multipliers do not agree with its kind, or None when they do."""
    tol = kind_tolerance(sp)
    kind = sp.kind.value
    if kind in ("fold", "branch_point", "period_doubling", "neimark_sacker", "hopf"):
        if sp.multipliers is None:
            return f"{sp.kind.value} at {sp.parameter:.10g} has no multipliers"
        mu = np.asarray(sp.multipliers, dtype=complex)
        if equilibrium:
            if kind == "hopf":
                cplx = mu[np.abs(mu.imag) > tol]
                near = float(np.min(np.abs(cplx.real))) if cplx.size else math.inf
                return None if near <= tol * max(1.0, float(np.max(np.abs(mu)))) else (
                    f"hopf at {sp.parameter:.10g} has no complex pair on the imaginary axis (nearest real part {near:.3g})")
            near = float(np.min(np.abs(mu))) if mu.size else math.inf
            return None if near <= tol * max(1.0, float(np.max(np.abs(mu)))) else (
                f"{sp.kind.value} at {sp.parameter:.10g} has no zero eigenvalue (nearest {near:.3g})")
        mu = _nontrivial(mu, autonomous)
        mu = mu[np.isfinite(mu)]
        if kind == "neimark_sacker":
            cplx = mu[np.abs(mu.imag) > tol]
            near = float(np.min(np.abs(np.abs(cplx) - 1.0))) if cplx.size else math.inf
            return None if near <= tol else (
                f"neimark_sacker at {sp.parameter:.10g} has no complex pair on the unit circle "
                f"(multipliers {_text(mu)})")
        target = -1.0 if kind == "period_doubling" else 1.0
        near = float(np.min(np.abs(mu - target))) if mu.size else math.inf
        return None if near <= tol else (
            f"{sp.kind.value} at {sp.parameter:.10g} has no multiplier at {target:+.0f} "
            f"(nearest {near:.3g} away; multipliers {_text(mu)})")
    crossing_kinds = {"discontinuous_fold": "+1", "discontinuous_flip": "-1", "discontinuous_neimark_sacker": "complex"}
    if kind in crossing_kinds:
        z = sp.crossing_point
        if z is None or not _isfinite(z):
            return f"{sp.kind.value} at {sp.parameter:.10g} has no set-valued crossing point"
        z = complex(z)
        want = crossing_kinds[kind]
        on_axis = abs(z.imag) <= 1e-6 * max(1.0, abs(z))
        if want == "complex":
            ok = not on_axis
        else:
            ok = on_axis and (z.real > 0.0) == (want == "+1")
        if not ok:
            return f"{sp.kind.value} at {sp.parameter:.10g} crosses the unit circle at {z:.6g}, not at {want}"
        return None
    if kind == "nonsmooth_no_crossing" and sp.multipliers_minus is not None and sp.multipliers_plus is not None:
        a = unstable_count(sp.multipliers_minus, autonomous=autonomous)
        b = unstable_count(sp.multipliers_plus, autonomous=autonomous)
        if a != b:
            return (f"nonsmooth_no_crossing at {sp.parameter:.10g} has {a} one-sided multipliers outside the unit "
                    f"circle on one side and {b} on the other")
    return None


def _isfinite(z) -> bool:
    z = complex(z)
    return math.isfinite(z.real) and math.isfinite(z.imag)


def _span(r: tuple[int, int]) -> str:
    return str(r[0]) if r[0] == r[1] else f"{r[0]}-{r[1]}"


def _text(mu: np.ndarray) -> str:
    return "[" + ", ".join(f"{complex(m):.6g}" for m in np.asarray(mu).ravel()[:6]) + "]"


def _change_made(sp, autonomous: bool) -> tuple[int, bool] | None:
    """How many multipliers a special point can move across the unit circle: ``(k, exact)`` where ``exact``
    says the count changes by exactly ``+-k``, or None when the point can make any change."""
    kind = sp.kind.value
    if sp.status.value == "failed":
        return 0, False
    if kind in ("fold", "branch_point", "period_doubling", "symmetry_breaking"):
        return 1, True
    if kind in ("neimark_sacker", "hopf"):
        return 2, True
    if kind in ("cycle_collapse", "codimension_two", "boundary_equilibrium"):
        return None
    if kind == "monitor":
        return 0, False  # a user's mark: it moves no multiplier
    if sp.multipliers_minus is not None and sp.multipliers_plus is not None:
        a = unstable_count(sp.multipliers_minus, autonomous=autonomous)
        b = unstable_count(sp.multipliers_plus, autonomous=autonomous)
        return abs(a - b), False
    return None  # a non-smooth point whose sides are unknown: it may make any change


def _scenario_violations(branch) -> list[Violation]:
    """Where a non-smooth point's Feigin scenario disagrees with the branch through it (see the module)."""
    pts = branch.points
    out = []
    count: dict[int, int] = {}
    for sp in branch.special_points:
        count[sp.index] = count.get(sp.index, 0) + 1
    for sp in branch.special_points:
        scenario = getattr(sp.scenario, "value", None)
        if scenario not in ("persistence", "nonsmooth_fold") or sp.status.value == "failed":
            continue
        i = sp.index
        if not (0 <= i and i + 1 < len(pts)) or count[i] != 1:
            continue
        margin = max(sp.accuracy if math.isfinite(sp.accuracy) else math.inf, 1e-12 * max(1.0, abs(sp.parameter)))
        before, after = pts[i].parameter - sp.parameter, pts[i + 1].parameter - sp.parameter
        if not (abs(before) > margin and abs(after) > margin):
            continue
        turns = (before > 0) == (after > 0)
        if turns != (scenario == "nonsmooth_fold"):
            what = "turns back at it" if turns else "goes on through it"
            out.append(Violation(
                "border_scenario", i,
                f"{sp.kind.value} at {sp.parameter:.10g}: Feigin's classification says {scenario}, but the branch "
                f"{what} ({branch.parameter_name} {pts[i].parameter:.10g} -> {pts[i + 1].parameter:.10g})"))
    return out


#: the kinds that are a tangency: something changes at them (a surface is touched) even where the event
#: sequences of their two sides read alike
_TANGENCY_KINDS = ("grazing", "grazing_sliding", "crossing_sliding", "switching_sliding", "adding_sliding")


def _unchanged_violations(branch, autonomous: bool) -> list[Violation]:
    """Non-smooth points whose two sides differ in nothing: the same event sequence up to where the orbit
    starts, the same stability, and no tangency (see the module)."""
    from saltation.branches.corrector import canonical_events

    out = []
    for sp in branch.special_points:
        kind = sp.kind.value
        if sp.one_sided is None or kind in _TANGENCY_KINDS or not sp.kind.is_nonsmooth:
            continue
        minus = sp.one_sided.event_ids_minus or sp.one_sided.event_labels_minus
        plus = sp.one_sided.event_ids_plus or sp.one_sided.event_labels_plus
        if not minus or not plus or canonical_events(tuple(minus)) != canonical_events(tuple(plus)):
            continue
        mu_a, mu_b = sp.one_sided.multipliers_minus, sp.one_sided.multipliers_plus
        if mu_a is None or mu_b is None:
            continue
        if unstable_count(mu_a, autonomous=autonomous) != unstable_count(mu_b, autonomous=autonomous):
            continue
        out.append(Violation("no_change", sp.index,
                             f"{kind} at {sp.parameter:.10g}: its two sides have the same events (up to where the orbit "
                             "starts) and the same stability, and it is no tangency: nothing changes there"))
    return out


# ---------------------------------------------------------------------------------------------------
def check_branch(branch, *, trivial_tol: float = 1e-6) -> BranchCheck:
    """The invariants of a computed branch (see the module's description).

    Parameters
    ----------
    branch : Branch
        A branch as continuation returned it (or as read from a file: points without monodromies are
        checked alike).
    trivial_tol : float
        The trivial multiplier of an autonomous orbit must lie within ``trivial_tol (1 + |mu|_max)``
        of 1, or within the orbit's own ``trivial_error`` (``|M n - n|``) where that is larger but still
        below ``1e-3``.

    Returns
    -------
    BranchCheck
        The violations found (``.ok`` when there are none).
    """
    out: list[Violation] = []
    pts = branch.points
    equilibrium = branch.kind.value == "equilibrium"
    autonomous = bool(branch.autonomous) and not equilibrium
    curve = branch.curve_of is not None

    if autonomous:
        for i, p in enumerate(pts):
            mu = np.asarray(p.multipliers, dtype=complex)
            if not mu.size:
                continue
            finite = mu[np.isfinite(mu)]
            dist = float(np.min(np.abs(finite - 1.0))) if finite.size else math.inf
            scale = 1.0 + (float(np.max(np.abs(finite))) if finite.size else 0.0)
            allowed = max(trivial_tol * scale, min(1e-3, p.trivial_error if math.isfinite(p.trivial_error) else 0.0))
            if not dist <= allowed:
                out.append(Violation("trivial_multiplier", i,
                                     f"point {i} ({branch.parameter_name} = {p.parameter:.10g}): the trivial multiplier "
                                     f"is {dist:.3g} from 1 (allowed {allowed:.3g})"))

    for sp in branch.special_points:
        why = _kind_problem(sp, autonomous, equilibrium)
        if why is not None and not curve:
            out.append(Violation("kind_mismatch", sp.index, why))
        if sp.status.value == "bracketed":
            lo, hi = sorted(map(float, sp.bracket))
            if math.isfinite(lo) and math.isfinite(hi):
                if not lo <= sp.parameter <= hi:
                    out.append(Violation("bracket", sp.index,
                                         f"{sp.kind.value} at {sp.parameter:.12g} lies outside its bracket [{lo:.12g}, {hi:.12g}]"))
                if not sp.accuracy >= (hi - lo) * (1.0 - 1e-12):
                    out.append(Violation("bracket", sp.index,
                                         f"{sp.kind.value} at {sp.parameter:.12g}: accuracy {sp.accuracy:.3g} is less than "
                                         f"its bracket's width {hi - lo:.3g}"))

    if not curve:
        out.extend(_scenario_violations(branch))
        out.extend(_unchanged_violations(branch, autonomous))
        ranges = [count_range(p.multipliers, autonomous=autonomous, equilibrium=equilibrium) for p in pts]
        by_index: dict[int, list] = {}
        for sp in branch.special_points:
            by_index.setdefault(sp.index, []).append(sp)
        for i in range(len(pts) - 1):
            (a_lo, a_hi), (b_lo, b_hi) = ranges[i], ranges[i + 1]
            # the smallest change the two points' counts allow (0 where their ranges overlap)
            delta = b_lo - a_hi if b_lo > a_hi else (b_hi - a_lo if b_hi < a_lo else 0)
            here = list(by_index.get(i, []))
            # a special point at a branch point itself (located on it, in the step before or after) covers
            # both steps that meet there
            for j, shared in ((i - 1, i), (i + 1, i + 1)):
                for sp in by_index.get(j, []):
                    lam = pts[shared].parameter
                    if abs(sp.parameter - lam) <= max(sp.accuracy, 1e-12 * max(1.0, abs(lam))):
                        here.append(sp)
            if delta == 0 and not here:
                continue
            made = [_change_made(sp, autonomous) for sp in here]
            if any(m is None for m in made):
                continue
            reach = sum(k for k, _ in made)
            parity_fixed = all(exact or k == 0 for k, exact in made)
            fits = abs(delta) <= reach and (not parity_fixed or (reach - abs(delta)) % 2 == 0)
            if delta != 0 and not fits:
                kinds = ", ".join(sp.kind.value for sp in here) or "no special point"
                out.append(Violation(
                    "uncovered_change", i,
                    f"from point {i} to {i + 1} ({branch.parameter_name} {pts[i].parameter:.10g} -> "
                    f"{pts[i + 1].parameter:.10g}) the multipliers outside the unit circle go from {_span(ranges[i])} "
                    f"to {_span(ranges[i + 1])}, and the step holds {kinds}"))

    ends = [(branch.stop_reason, len(pts) - 1)] + [(r, 0) for r in branch.stop_reasons[:1]]
    for reason, end in ends:
        if getattr(reason, "name", None) == "MIN_STEP" and pts:
            near = [sp for sp in branch.special_points if abs(sp.index - end) <= 1 or (end > 0 and sp.index >= end - 1)]
            if not near and not branch.stop_detail:
                out.append(Violation("silent_stop", end,
                                     f"the branch stopped at point {end} ({branch.parameter_name} = "
                                     f"{pts[end].parameter:.10g}) because the corrector failed, without a special point there"))
    return BranchCheck(tuple(out))


__all__ = ["COUNT_TOL", "BranchCheck", "Violation", "check_branch", "count_range", "kind_tolerance", "unstable_count"]
