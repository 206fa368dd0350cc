"""Feigin's classification of a border collision, from the one-sided multipliers of a non-smooth point.

Where an orbit's event sequence changes, its period map is piecewise smooth near the orbit: two smooth
pieces meet at a border, with the Jacobians ``M-`` and ``M+`` there (the one-sided monodromies).  A fixed
point that reaches the border as a parameter passes a value (a *border collision*, or C-bifurcation) does
what the real multipliers of the two sides say (Feigin 1970, 1978; di Bernardo, Feigin, Hogan and Homer
1999).  With ``sigma_A^+`` the number of real multipliers greater than 1 of side ``A`` and ``sigma_A^-``
the number of those less than -1:

* ``sigma_-^+ + sigma_+^+`` even: *persistence*, one fixed point on either side (the orbit crosses the
  border and goes on);
* odd: a *non-smooth fold*, two fixed points on one side (one of each kind) that meet at the border and
  vanish, none on the other;
* ``sigma_-^- + sigma_+^-`` odd: a period-two orbit is born at the point too (flip-like); even: the theorem
  says nothing about one.

The reason is the fixed-point index: a fixed point of side ``A`` has index ``sign det(I - M_A)``, and
``det(I - M_A)`` has the sign ``(-1)^sigma_A^+`` (a complex pair adds ``|1 - mu|^2 > 0``, a real
multiplier less than 1 a positive factor); the total index near the point is the same on both sides of
the collision.  The same with ``det(I + M_A)`` for the period-two points of the second iterate.

The rule this module applies (:func:`feigin_scenario`):

* the trivial multiplier of an autonomous orbit (the one nearest 1, as the branch checker and the
  set-valued classification leave it out) is not counted: the count is that of the Poincaré map;
* a real multiplier is one within the tolerance of the real axis;
* an infinite multiplier counts as a real one beyond the unit circle on the side of its sign: ``+inf``
  (the point at infinity, as the library records an infinitely unstable direction, Leine and Van Campen
  sec. 4: ``lambda = (1, inf)``) as greater than 1, ``-inf`` as less than -1.  The fixed-point index still
  decides: the factor ``1 - mu`` of ``det(I - M)`` has the sign of ``-mu`` for a large ``|mu|`` (at an
  impact's grazing, Nordmark's square-root map, the crossing side's large multiplier tends to ``-inf``);
* the answer is *undetermined* where the theorem does not apply: a non-trivial multiplier within the
  tolerance of the unit circle (the theorem needs generic multipliers; the tolerance is the multipliers'
  own accuracy, at least :data:`CIRCLE_TOL`), an infinite multiplier that is not real, or infinite
  multipliers on both sides (neither side's map has a finite Jacobian: no piecewise-smooth continuous map
  at the border, as at the paper's stick-slip fold, where the stable side's multiplier grows like
  ``d^(-1/2)`` too).

The theorem assumes a map that is continuous at the border, with one border crossed: at a corner of a
symmetric orbit that meets two mirror-image borders at once the count is that of the whole period's
multipliers, the squares of the half-period map's; where those say a symmetry breaking
(``discontinuous_symmetry_breaking``), the caller asks for *undetermined*
(:func:`saltation.special_points.points.with_border_scenario` does).

References
----------
Feigin (1970), "Doubling of the oscillation period with C-bifurcations in piecewise-continuous systems",
J. Appl. Math. Mech. 34; Feigin (1978), "On the structure of C-bifurcation boundaries of piecewise-continuous
systems", J. Appl. Math. Mech. 42.  di Bernardo, Feigin, Hogan and Homer (1999), "Local analysis of
C-bifurcations in n-dimensional piecewise-smooth dynamical systems", Chaos, Solitons & Fractals 10.
di Bernardo, Budd, Champneys and Kowalczyk (2008), *Piecewise-smooth Dynamical Systems*, Springer, sec. 3.5.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from saltation.kinds import BorderScenario

__all__ = ["CIRCLE_TOL", "FeiginScenario", "feigin_scenario"]

#: the least distance from the unit circle at which a multiplier counts as off it (the branch checker's
#: :data:`~saltation.branches.check.COUNT_TOL`)
CIRCLE_TOL = 1e-6


@dataclass(frozen=True)
class FeiginScenario:
    """What Feigin's classification predicts at a border collision, and the counts it is read from.

    Attributes
    ----------
    scenario : BorderScenario
        ``persistence``, ``nonsmooth_fold`` or ``undetermined``.
    period_two : bool or None
        True where a period-two orbit is born at the point (``sigma^-`` odd); False where the theorem
        says nothing about one (even); None where the scenario is undetermined.
    sigma_plus : tuple of int
        Real multipliers greater than 1 on the minus side and on the plus side (infinite ones counted by
        their sign).
    sigma_minus : tuple of int
        Real multipliers less than -1 on either side.
    tolerance : float
        The distance from the unit circle (and from the real axis) within which a multiplier was taken
        to be on it.
    reason : str
        A sentence: the counts and what follows, or why the theorem says nothing.
    """

    scenario: BorderScenario
    period_two: bool | None
    sigma_plus: tuple[int, int]
    sigma_minus: tuple[int, int]
    tolerance: float
    reason: str


def _nontrivial(mu: np.ndarray, autonomous: bool) -> np.ndarray:
    """The multipliers without the trivial one (the finite one nearest 1) of an autonomous orbit."""
    if autonomous and mu.size:
        finite = np.where(np.isfinite(mu), np.abs(mu - 1.0), np.inf)
        mu = np.delete(mu, int(np.argmin(finite)))
    return mu


def _counts(mu: np.ndarray, tol: float) -> tuple[int, int, str | None]:
    """``(sigma^+, sigma^-, why undetermined or None)`` of one side's non-trivial multipliers."""
    plus = minus = 0
    for m in mu.tolist():
        re, im = m.real, m.imag
        if math.isinf(im) or math.isnan(re) or (math.isnan(im) and not math.isinf(re)):
            return 0, 0, f"a multiplier is infinite off the real axis or not a number ({m})"
        if math.isinf(re):  # the point at infinity (+inf), or an unbounded one along the negative axis
            if re > 0:
                plus += 1
            else:
                minus += 1
            continue
        modulus = abs(m)
        if abs(modulus - 1.0) <= tol:
            return 0, 0, f"the multiplier {_text(m)} lies on the unit circle within {tol:.1e}"
        if abs(im) <= tol * max(1.0, modulus) and modulus > 1.0:
            if re > 0:
                plus += 1
            else:
                minus += 1
    return plus, minus, None


def _text(m: complex) -> str:
    return f"{m.real:.6g}" if m.imag == 0.0 else f"{m.real:.6g}{m.imag:+.6g}j"


def feigin_scenario(
    multipliers_minus,
    multipliers_plus,
    *,
    autonomous: bool = False,
    tolerance: float = CIRCLE_TOL,
) -> FeiginScenario:
    """Feigin's prediction at a border collision from the two sides' multipliers (see the module's rule).

    Parameters
    ----------
    multipliers_minus, multipliers_plus : array_like, complex
        The one-sided (forward-time) multipliers; ``inf`` (``complex(inf, 0)``) for one that grows without
        bound towards the point, ``complex(-inf, 0)`` where it does so along the negative real axis.
    autonomous : bool
        Whether the orbit is autonomous: its trivial multiplier (the one nearest 1 on each side) is left out.
    tolerance : float
        How near the unit circle (and the real axis) a multiplier counts as on it: the multipliers' accuracy
        (at least :data:`CIRCLE_TOL` is used).

    Returns
    -------
    FeiginScenario
        The scenario, the period-two flag, the counts and a sentence.

    Raises
    ------
    ValueError
        If the two sides have different numbers of multipliers, or none.

    References
    ----------
    Feigin (1978), "On the structure of C-bifurcation boundaries of piecewise-continuous systems", J. Appl.
    Math. Mech. 42.  di Bernardo, Feigin, Hogan and Homer (1999), "Local analysis of C-bifurcations in
    n-dimensional piecewise-smooth dynamical systems", Chaos, Solitons & Fractals 10.
    """
    mu_a = np.asarray(multipliers_minus, dtype=complex).ravel()
    mu_b = np.asarray(multipliers_plus, dtype=complex).ravel()
    if mu_a.size != mu_b.size or not mu_a.size:
        raise ValueError(f"the two sides have {mu_a.size} and {mu_b.size} multipliers: a border collision needs the "
                         "same number (at least one) on both")
    tol = max(float(tolerance), CIRCLE_TOL) if math.isfinite(tolerance) else CIRCLE_TOL
    sides = [_nontrivial(mu_a, autonomous), _nontrivial(mu_b, autonomous)]

    def undetermined(why: str, plus=(0, 0), minus=(0, 0)) -> FeiginScenario:
        return FeiginScenario(BorderScenario.UNDETERMINED, None, plus, minus, tol,
                              f"Feigin's classification does not apply: {why}")

    if all(np.any(~np.isfinite(mu)) for mu in sides):
        return undetermined("both sides have an infinite multiplier (neither one-sided map has a finite Jacobian)")
    counted = []
    for name, mu in zip(("minus", "plus"), sides):
        plus, minus, why = _counts(mu, tol)
        if why is not None:
            return undetermined(f"on the {name} side {why}")
        counted.append((plus, minus))
    sigma_plus = (counted[0][0], counted[1][0])
    sigma_minus = (counted[0][1], counted[1][1])
    fold = sum(sigma_plus) % 2 == 1
    period_two = sum(sigma_minus) % 2 == 1
    scenario = BorderScenario.NONSMOOTH_FOLD if fold else BorderScenario.PERSISTENCE
    what = ("a non-smooth fold (the orbits of the two sides meet at the point and vanish)" if fold
            else "persistence (the orbit crosses the border)")
    two = ("a period-two orbit is born there" if period_two
           else "the theorem says nothing about a period-two orbit")
    reason = (f"real multipliers > 1: {sigma_plus[0]} and {sigma_plus[1]}, < -1: {sigma_minus[0]} and "
              f"{sigma_minus[1]} (minus and plus side{', the trivial one left out' if autonomous else ''}): "
              f"{what}; {two}")
    return FeiginScenario(scenario, period_two, sigma_plus, sigma_minus, tol, reason)
