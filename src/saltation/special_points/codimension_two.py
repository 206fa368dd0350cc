"""Smooth codimension-two points along curves of folds, period doublings and Neimark-Sacker points.

Along a two-parameter curve of a smooth bifurcation of a periodic orbit (a fixed point of the period map),
test functions of the curve's points change sign where a second condition is met (Kuznetsov 2004, section
9.1, the codimension-two bifurcations of fixed points of maps).  Each is a :class:`TestFunction`; the
curve's kind has its list (:data:`TESTS`):

* a fold curve (a multiplier ``+1``): the cusp (the quadratic normal-form coefficient ``<p, B(q, q)> / (2
  <p, q>)`` changes sign; ``B`` the second derivative of the period map, by central differences of the
  monodromy along ``q``: ``B(q, q) = (M(x + h q) - M(x - h q)) q / (2 h)``; :func:`cusp_coefficient`), the 1:1
  resonance (a second multiplier at
  ``+1``), fold-flip (one at ``-1``), fold-Neimark-Sacker (a pair with product 1);
* a period-doubling curve (``-1``): fold-flip (a multiplier ``+1``), the 1:2 resonance (a second ``-1``),
  flip-Neimark-Sacker, and the generalized period doubling (a slot: its test function needs the cubic
  normal-form coefficient of the flip, which this module does not compute yet);
* a Neimark-Sacker curve (``exp(+-i theta)``, ``kappa = cos theta``): the strong resonances 1:1
  (``kappa = 1``), 1:2 (``kappa = -1``), 1:3 (``kappa = -1/2``) and 1:4 (``kappa = 0``), fold- and
  flip-Neimark-Sacker, and Chenciner (a slot: it needs the first Lyapunov coefficient of the torus);
* a crossing-, switching- or adding-sliding curve: its orbit's period map is continuously differentiable
  across the bifurcation (its corrections are of second or third order, di Bernardo, Kowalczyk and Nordmark
  2002), so both sides share the curve's multipliers, and the curve meets a fold, period-doubling or
  Neimark-Sacker curve of the orbits where ``prod (mu - 1)``, ``prod (mu + 1)`` or ``prod_{i<j} (mu_i mu_j - 1)``
  over all of them vanishes (a sliding orbit's multipliers 0 are factors -1, 1 and -1, never a zero); along a
  crossing- or switching-sliding curve also the far field's curvature at the arrival, signed positive where
  visible, whose zero (a cubic tangency) turns one kind into the other;
* a grazing-sliding curve: the same products over its orbit's multipliers, those of the orbits that miss the
  sliding region (one side's, where Feigin's scenario may change).  These have no
  :class:`~saltation.kinds.CodimensionTwoKind`: ``sides`` and ``note`` say what they are.

The multipliers other than the curve's own (the one nearest ``+1`` or ``-1``, or the pair nearest
``exp(+-i theta)``) enter as products ``prod (mu - 1)``, ``prod (mu + 1)`` and ``prod_{i<j} (mu_i mu_j -
1)``, real for a real matrix.  For a second multiplier at the curve's own ``+-1`` (1:1 on a fold curve, 1:2
on a period-doubling curve) the factor of the next nearest has the curve's own added, ``(mu_1 -+ 1) + (mu_2
-+ 1)``: near the double multiplier (a Jordan block) each eigenvalue is known only to the square root of the
monodromy's rounding, their sum to the rounding itself.  A sign change between two curve points is located on
the curve (the curve's own corrector on the hyperplanes across the chord between them) by the Illinois
variant of regula falsi, to ``tol`` in the two parameters, at the end of the final bracket where the test
function is smaller; a location that does not converge is left bracketed between the two points.  A zero of
``prod (mu_i mu_j - 1)`` at a real pair (a neutral saddle among the other multipliers) is not a bifurcation
and is dropped.

References
----------
Kuznetsov (2004), *Elements of Applied Bifurcation Theory*, 3rd ed., Springer: section 9.1 (the
codimension-two bifurcations of maps), section 10.3 (their test functions along fold, flip and
Neimark-Sacker curves).  Govaerts (2000), *Numerical Methods for Bifurcations of Dynamical Equilibria*, SIAM.
di Bernardo, Kowalczyk and Nordmark (2002), "Bifurcations of dynamical systems with sliding: derivation of
normal-form mappings", Physica D 170 (the sliding bifurcations' maps).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from saltation.branches.branch import (
    CodimensionTwoKind,
    SpecialPoint,
    SpecialPointKind,
    SpecialPointStatus,
)
from saltation.errors import SaltationError
from saltation.orbits.records import BranchPoint

_log = logging.getLogger(__name__)

_C2 = CodimensionTwoKind


@dataclass
class CurvePoint:
    """What a test function reads at a point of a curve.

    Attributes
    ----------
    z : ndarray
        The curve's unknowns and its parameter, ``(x0 or nodes, first parameter, extras, second parameter)``.
    multipliers : ndarray
        The orbit's multipliers.
    monodromy : ndarray
        Its monodromy matrix.
    kappa : float or None
        On a Neimark-Sacker curve: ``cos theta`` (the curve's unknown).
    others : ndarray
        The multipliers without the curve's own (the one nearest ``+1`` or ``-1``, the pair of ``kappa``).
    summary : BranchPoint or None
        The record of its orbit (period, amplitude), which a codimension-two point located here carries.
    """

    z: np.ndarray
    multipliers: np.ndarray
    monodromy: np.ndarray
    kappa: float | None
    others: np.ndarray
    summary: BranchPoint | None = None


@dataclass(frozen=True)
class TestFunction:
    """A codimension-two point's test function along a curve.

    Attributes
    ----------
    name : CodimensionTwoKind or None
        The point it finds; None where it has no name of a smooth point (along a sliding bifurcation's curve,
        where ``label`` says what it finds).
    meets : str
        The kind of special point the curve meets there (the second of its ``sides``).
    value : callable or None
        ``(curve, point, reference) -> float`` (``reference`` the previous point's fold vectors ``(q, p)``, which
        orient this point's, or None; the cusp's returns ``(value, (q, p))``);
        None: a slot whose test function is not computed yet (the normal-form coefficients it needs).
    circle_only : bool
        On a Neimark-Sacker curve: only between two points whose pair lies on the unit circle (``|kappa| < 1``).
    pair : bool
        A zero of ``prod (mu_i mu_j - 1)``: dropped where the pair with product 1 is real (a neutral saddle).
    label : str
        What a zero means, in words (the record's note); the name's words where empty.
    changes_kind : bool
        The test's sign is the curve's kind (crossing- or switching-sliding): its zero's ``sides`` are the kinds
        before and after it along the curve.
    """

    name: CodimensionTwoKind | None
    meets: str
    value: Callable | None
    circle_only: bool = False
    pair: bool = False
    label: str = ""
    changes_kind: bool = False


def _prod_minus(others: np.ndarray, target: float) -> float:
    """``prod (mu - target)`` over the other multipliers (real: they come in conjugate pairs)."""
    return float(np.real(np.prod(others - target))) if others.size else 1.0


def _second_at(multipliers: np.ndarray, target: float) -> float:
    """``prod (mu - target)`` over the other multipliers, with the curve's own multiplier (the nearest ``target``)
    added to the next nearest's factor: ``(mu_1 - target) + (mu_2 - target)``.

    On the curve the first term is zero to the corrector's tolerance, so this is the product over the others;
    but near a double multiplier (a 1:1 or 1:2 resonance, a Jordan block) each of the two eigenvalues is known
    only to the square root of the monodromy's rounding (1e-7 for 1e-14), and which of them is the curve's own
    is a toss-up, while their sum (the trace of the monodromy on their invariant plane) is as accurate as the
    monodromy.  Real: the rest come in conjugate pairs.
    """
    mu = np.asarray(multipliers, dtype=complex)
    if mu.size < 2:
        return 1.0
    order = np.argsort(np.abs(mu - target), kind="stable")
    pair = (mu[order[0]] - target) + (mu[order[1]] - target)
    return float(np.real(pair * np.prod(mu[order[2:]] - target)))


def _prod_pairs(others: np.ndarray) -> float:
    """``prod_{i<j} (mu_i mu_j - 1)``: zero where two of the other multipliers have product 1."""
    out = 1.0 + 0.0j
    for i in range(len(others)):
        for j in range(i + 1, len(others)):
            out *= others[i] * others[j] - 1.0
    return float(np.real(out))


def fold_eigenvectors(M: np.ndarray, reference: tuple[np.ndarray, np.ndarray] | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Unit null vectors of a fold: ``M q = q``, ``p^T M = p^T``, ``|q| = |p| = 1``.

    Parameters
    ----------
    M : ndarray, shape (n, n)
        The monodromy at a fold.
    reference : (ndarray, ndarray), optional
        ``(q, p)`` of a neighbouring point of the curve: each is oriented along its own (``q . q_ref >= 0``,
        ``p . p_ref >= 0``); without it, ``p . q >= 0``.

    Returns
    -------
    q, p : ndarray, shape (n,)

    Raises
    ------
    numpy.linalg.LinAlgError
        If the singular value decomposition does not converge.
    """
    n = M.shape[0]
    U, _, Vt = np.linalg.svd(M - np.eye(n))
    q, p = Vt[-1].copy(), U[:, -1].copy()
    if reference is not None:
        q = q if q @ reference[0] >= 0 else -q
        p = p if p @ reference[1] >= 0 else -p
    elif p @ q < 0:
        p = -p
    return q, p


def cusp_coefficient(curve, point: CurvePoint, reference: tuple[np.ndarray, np.ndarray] | None = None, *,
                     h: float = 1e-4) -> tuple[float, tuple[np.ndarray, np.ndarray]]:
    """The cusp's test function: ``<p, B(q, q)>`` at a fold of the period map, with unit ``p`` and ``q``.

    The quadratic normal-form coefficient of the fold is ``a = <p, B(q, q)> / (2 <p, q>)`` (the map reads
    ``y -> y + a y^2 + ...`` on its centre manifold); the test function leaves out the factor ``1 / (2 <p,
    q>)``, which passes through infinity where ``<p, q>`` vanishes (a 1:1 resonance, a Jordan block of the
    multiplier 1), so that it changes sign at a cusp only; ``p`` and ``q`` are oriented along the curve.
    ``B(q, q)``, the second derivative of the period map along ``q``, is the central difference of the
    monodromy along ``q``: ``(M(x + d q) - M(x - d q)) q / (2 d)``, ``d = h (1 + |x|)``; its error is
    ``O(d^2)`` times the third derivative of the period map plus the integration error divided by ``d``.

    Parameters
    ----------
    curve
        The fold curve's problem (:class:`~saltation.special_points.loci.MultiplierCurve`): its ``monodromy``,
        ``period_at`` and parameters.
    point : CurvePoint
        A point of the curve.
    reference : (ndarray, ndarray), optional
        ``(q, p)`` of the previous point, which orient these.
    h : float
        Relative step of the central difference.

    Returns
    -------
    value : float
        ``<p, B(q, q)>``.
    vectors : (ndarray, ndarray)
        The oriented ``(q, p)``.

    Raises
    ------
    SaltationError
        If a run fails.
    """
    n = curve.system.n
    z = point.z
    x0 = np.asarray(z[:n], dtype=float)
    p_all = _parameters(curve, z)
    T = curve.period_at(z[:-1], p_all)
    q, p = fold_eigenvectors(point.monodromy, reference)
    d = h * (1.0 + float(np.linalg.norm(x0)))
    B = (curve.monodromy(x0 + d * q, T, p_all) @ q - curve.monodromy(x0 - d * q, T, p_all) @ q) / (2.0 * d)
    return float(p @ B), (q, p)


def _parameters(curve, z: np.ndarray) -> np.ndarray:
    """Every parameter's value at a curve point ``z = (u, lam)``."""
    return curve.parameters_at(float(z[-1]), z[:-1])


def _cusp(curve, point: CurvePoint, reference):
    return cusp_coefficient(curve, point, reference)


def normal_form_coefficient(curve, point: CurvePoint, kind: SpecialPointKind) -> float:
    """The cubic normal-form coefficient at a curve point: the flip's ``b`` (period-doubling curves) or the first
    Lyapunov coefficient ``d`` (Neimark-Sacker curves), by :func:`saltation.orbits.criticality.criticality`.

    The point's orbit is solved again from its state (Newton converges at once), at every parameter of the point.

    Parameters
    ----------
    curve
        The curve's problem (its flow, section time, parameters and period).
    point : CurvePoint
        A point of the curve.
    kind : SpecialPointKind
        ``period_doubling`` or ``neimark_sacker``.

    Returns
    -------
    float
        The coefficient; it changes sign at a generalised period doubling or a Chenciner point.

    Raises
    ------
    SaltationError
        If the orbit cannot be solved again, or as :func:`~saltation.orbits.criticality.criticality` (a strong
        resonance, a change of the event sequence within the differences' steps).
    """
    from saltation.orbits.criticality import criticality
    from saltation.orbits.start import find_periodic_orbit

    n = curve.system.n
    z = point.z
    p_all = _parameters(curve, z)
    T = curve.period_at(z[:-1], p_all)
    orbit = find_periodic_orbit(curve.flow, np.asarray(z[:n], dtype=float),
                                parameters=dict(zip(curve.system.parameter_names, map(float, p_all))),
                                period=T if curve.autonomous else None, t0=curve.t0, backward=curve.backward)
    return float(criticality(orbit, kind).coefficient)


def _flip_coefficient(curve, point: CurvePoint, reference) -> float:
    return normal_form_coefficient(curve, point, SpecialPointKind.PERIOD_DOUBLING)


def _lyapunov_coefficient(curve, point: CurvePoint, reference) -> float:
    return normal_form_coefficient(curve, point, SpecialPointKind.NEIMARK_SACKER)


#: the test functions that need the cubic normal form (each point's orbit solved again and its second and third
#: derivatives taken: a tenth of a second to seconds a point), computed when asked (``normal_forms=True``)
NORMAL_FORM_TESTS = {CodimensionTwoKind.GENERALIZED_PERIOD_DOUBLING: _flip_coefficient,
                     CodimensionTwoKind.CHENCINER: _lyapunov_coefficient}


#: The test functions of each curve's kind.
TESTS: dict[SpecialPointKind, tuple[TestFunction, ...]] = {
    SpecialPointKind.FOLD: (
        TestFunction(_C2.CUSP, "fold", _cusp),
        TestFunction(_C2.STRONG_RESONANCE_1_1, "fold", lambda c, pt, r: _second_at(pt.multipliers, 1.0)),
        TestFunction(_C2.FOLD_FLIP, "period_doubling", lambda c, pt, r: _prod_minus(pt.others, -1.0)),
        TestFunction(_C2.FOLD_NEIMARK_SACKER, "neimark_sacker", lambda c, pt, r: _prod_pairs(pt.others), pair=True),
    ),
    SpecialPointKind.PERIOD_DOUBLING: (
        TestFunction(_C2.FOLD_FLIP, "fold", lambda c, pt, r: _prod_minus(pt.others, 1.0)),
        TestFunction(_C2.STRONG_RESONANCE_1_2, "period_doubling", lambda c, pt, r: _second_at(pt.multipliers, -1.0)),
        TestFunction(_C2.FLIP_NEIMARK_SACKER, "neimark_sacker", lambda c, pt, r: _prod_pairs(pt.others), pair=True),
        # the cubic normal-form coefficient of the flip changes sign (with normal_forms=True)
        TestFunction(_C2.GENERALIZED_PERIOD_DOUBLING, "period_doubling", None),
    ),
    SpecialPointKind.NEIMARK_SACKER: (
        TestFunction(_C2.STRONG_RESONANCE_1_1, "fold", lambda c, pt, r: pt.kappa - 1.0),
        TestFunction(_C2.STRONG_RESONANCE_1_2, "period_doubling", lambda c, pt, r: pt.kappa + 1.0),
        TestFunction(_C2.STRONG_RESONANCE_1_3, "neimark_sacker", lambda c, pt, r: pt.kappa + 0.5, circle_only=True),
        TestFunction(_C2.STRONG_RESONANCE_1_4, "neimark_sacker", lambda c, pt, r: pt.kappa, circle_only=True),
        TestFunction(_C2.FOLD_NEIMARK_SACKER, "fold", lambda c, pt, r: _prod_minus(pt.others, 1.0), circle_only=True),
        TestFunction(_C2.FLIP_NEIMARK_SACKER, "period_doubling", lambda c, pt, r: _prod_minus(pt.others, -1.0),
                     circle_only=True),
        # the first Lyapunov coefficient of the torus changes sign (with normal_forms=True)
        TestFunction(_C2.CHENCINER, "neimark_sacker", None, circle_only=True),
    ),
}


def _visibility(curve, point: CurvePoint, reference) -> float:
    return curve.arrival_visibility(point.z)


#: The tests along a sliding bifurcation's curve: the multipliers of its orbit (the same on both sides: the period
#: map is continuously differentiable across a crossing-, switching- or adding-sliding) at ``+1``, ``-1`` or a pair
#: on the unit circle; each product runs over all of them (a sliding orbit's multipliers 0 give factors ``-1``, ``1``
#: and ``-1``, never a zero).
_SLIDING_MULTIPLIER_TESTS = (
    TestFunction(None, "fold", lambda c, pt, r: _prod_minus(pt.others, 1.0),
                 label="a multiplier of its orbits passes +1 (a fold curve of the orbits on both sides crosses it)"),
    TestFunction(None, "period_doubling", lambda c, pt, r: _prod_minus(pt.others, -1.0),
                 label="a multiplier of its orbits passes -1 (a period-doubling curve of the orbits on both sides "
                       "crosses it)"),
    TestFunction(None, "neimark_sacker", lambda c, pt, r: _prod_pairs(pt.others), pair=True,
                 label="a pair of multipliers of its orbits crosses the unit circle (a Neimark-Sacker curve of the "
                       "orbits on both sides crosses it)"),
)
#: crossing- and switching-sliding: the far field's curvature at the arrival, signed positive where it is visible
#: (its orbit leaves the surface to its own side: crossing-sliding), changes sign where it has a cubic tangency
_VISIBILITY_TEST = TestFunction(None, "", _visibility, changes_kind=True,
                                label="the far field's tangency at the arrival changes from visible to invisible "
                                      "or back (a cubic tangency there: crossing- and switching-sliding meet)")
TESTS[SpecialPointKind.CROSSING_SLIDING] = _SLIDING_MULTIPLIER_TESTS + (_VISIBILITY_TEST,)
TESTS[SpecialPointKind.SWITCHING_SLIDING] = _SLIDING_MULTIPLIER_TESTS + (_VISIBILITY_TEST,)
TESTS[SpecialPointKind.ADDING_SLIDING] = _SLIDING_MULTIPLIER_TESTS
#: a grazing-sliding curve: its orbit touches the boundary of the sliding region, so its multipliers are those of the
#: orbits that miss it (the side without sliding, whose one-sided multipliers they are); one at ``+1``, ``-1`` or a
#: pair on the unit circle is where a fold, period-doubling or Neimark-Sacker curve of those orbits crosses it, and
#: Feigin's scenario at the grazing-sliding may change there (the sliding side's multipliers are not followed)
TESTS[SpecialPointKind.GRAZING_SLIDING] = (
    TestFunction(None, "fold", lambda c, pt, r: _prod_minus(pt.others, 1.0),
                 label="a multiplier of the orbits that miss the sliding region passes +1 (a fold curve of those "
                       "orbits crosses it)"),
    TestFunction(None, "period_doubling", lambda c, pt, r: _prod_minus(pt.others, -1.0),
                 label="a multiplier of the orbits that miss the sliding region passes -1 (a period-doubling curve of "
                       "those orbits crosses it)"),
    TestFunction(None, "neimark_sacker", lambda c, pt, r: _prod_pairs(pt.others), pair=True,
                 label="a pair of multipliers of the orbits that miss the sliding region crosses the unit circle (a "
                       "Neimark-Sacker curve of those orbits crosses it)"),
)


def others_of(multipliers: np.ndarray, kind: SpecialPointKind, kappa: float | None) -> np.ndarray:
    """The multipliers without the curve's own: the one nearest ``+1`` (fold) or ``-1`` (period doubling), or
    the two nearest the pair of ``kappa`` (Neimark-Sacker: ``kappa +- i sqrt(1 - kappa^2)``, or the real pair
    ``kappa +- sqrt(kappa^2 - 1)`` of a neutral saddle); all of them on a sliding bifurcation's curve.

    Parameters
    ----------
    multipliers : ndarray
        The orbit's multipliers.
    kind : SpecialPointKind
        FOLD, PERIOD_DOUBLING or NEIMARK_SACKER (or the kind of a sliding bifurcation).
    kappa : float or None
        The Neimark-Sacker curve's ``kappa``.

    Returns
    -------
    ndarray
        The other multipliers.
    """
    mu = np.asarray(multipliers, dtype=complex)
    if kind not in (SpecialPointKind.FOLD, SpecialPointKind.PERIOD_DOUBLING, SpecialPointKind.NEIMARK_SACKER):
        return mu  # a sliding bifurcation's curve: no multiplier is the curve's own
    if kind is SpecialPointKind.NEIMARK_SACKER:
        root = np.sqrt(complex(kappa * kappa - 1.0))
        own = [kappa + root, kappa - root]
    else:
        own = [1.0 if kind is SpecialPointKind.FOLD else -1.0]
    keep = np.ones(len(mu), dtype=bool)
    for target in own:
        free = np.flatnonzero(keep)
        keep[free[np.argmin(np.abs(mu[free] - target))]] = False
    return mu[keep]


@dataclass
class _Evaluated:
    """A curve point with its test values (None where a slot) and the fold's ``(q, p)``."""

    point: CurvePoint
    values: list[float | None]
    q: tuple[np.ndarray, np.ndarray] | None = None


class CodimensionTwoSearch:
    """Test functions along a fold, period-doubling, Neimark-Sacker or sliding bifurcation's curve, and the
    location of their zeros.

    A located point's ``accuracy`` is the final bracket in the two parameters (plus, for a cusp, the central
    difference's error through the test function's slope; for the tests without a name, those of a sliding
    bifurcation's curve, the curve point's own error: the next Newton correction and the integration error
    carried to the parameters).

    Parameters
    ----------
    curve
        The curve's problem (:class:`~saltation.special_points.loci.MultiplierCurve`,
        :class:`~saltation.special_points.loci.NeimarkSackerCurve` or
        :class:`~saltation.special_points.loci.SlidingCurve`).
    kind : SpecialPointKind
        FOLD, PERIOD_DOUBLING, NEIMARK_SACKER, CROSSING_SLIDING, SWITCHING_SLIDING or ADDING_SLIDING.
    corrector : Corrector
        The curve's corrector (:class:`~saltation.branches.corrector.Corrector`).
    tol : float
        Location tolerance in the two parameters.
    max_iter : int
        Largest number of corrected points per location.
    normal_forms : bool
        Also the tests that need the cubic normal form at every point (:data:`NORMAL_FORM_TESTS`: generalised
        period doubling, Chenciner), which cost a tenth of a second to seconds a point.
    """

    def __init__(self, curve, kind: SpecialPointKind, corrector, *, tol: float = 1e-8, max_iter: int = 30,
                 normal_forms: bool = False):
        self.curve = curve
        self.kind = kind
        self.corrector = corrector
        self.tests = tuple(replace(t, value=NORMAL_FORM_TESTS[t.name]) if normal_forms and t.value is None
                           and t.name in NORMAL_FORM_TESTS else t for t in TESTS[kind])
        self.tol = float(tol)
        self.max_iter = int(max_iter)

    # -- one point --------------------------------------------------------------------------------
    def point(self, z: np.ndarray, multipliers: np.ndarray, monodromy: np.ndarray,
              summary: BranchPoint | None = None) -> CurvePoint:
        """A curve point as the test functions read it.

        Parameters
        ----------
        z : ndarray
            ``(u, lam)`` in the curve's layout.
        multipliers, monodromy : ndarray
            The orbit's.
        summary : BranchPoint, optional
            The record of the orbit (period, amplitude).

        Returns
        -------
        CurvePoint
        """
        kappa = float(z[-2]) if self.kind is SpecialPointKind.NEIMARK_SACKER else None
        return CurvePoint(z=np.asarray(z, dtype=float), multipliers=np.asarray(multipliers),
                          monodromy=np.asarray(monodromy), kappa=kappa,
                          others=others_of(multipliers, self.kind, kappa), summary=summary)

    def evaluate(self, point: CurvePoint, reference: np.ndarray | None) -> _Evaluated:
        """Every test function at a point (None for slots, and where one fails: a run, a Jordan block).

        Parameters
        ----------
        point : CurvePoint
        reference : (ndarray, ndarray) or None
            Orients the fold's ``q`` and ``p``.

        Returns
        -------
        _Evaluated
        """
        values, q = [], None
        for test in self.tests:
            if test.value is None:
                values.append(None)
                continue
            try:
                v = test.value(self.curve, point, reference)
            except (SaltationError, np.linalg.LinAlgError) as exc:
                _log.debug("%s test function failed at %s: %s", _what(test), point.z[-1], exc)
                values.append(None)
                continue
            if isinstance(v, tuple):
                v, q = v
            values.append(float(v))
        return _Evaluated(point, values, q)

    # -- along the curve --------------------------------------------------------------------------
    def search(self, zs: Sequence[np.ndarray], summaries: Sequence) -> list[tuple[int, SpecialPoint]]:
        """The codimension-two points between consecutive curve points.

        Parameters
        ----------
        zs : sequence of ndarray
            The curve's points ``(u, lam)`` in the curve's layout, in order along it.
        summaries : sequence of BranchPoint
            Their records (multipliers, monodromy), in the same order.

        Returns
        -------
        list of (int, SpecialPoint)
            ``(index, point)``: the point lies between curve points ``index`` and ``index + 1``.
        """
        evaluated: list[_Evaluated] = []
        q = None
        for z, bp in zip(zs, summaries):
            e = self.evaluate(self.point(z, bp.multipliers, bp.monodromy, bp), q)
            q = e.q if e.q is not None else q
            evaluated.append(e)
        found = []
        for a in range(len(evaluated) - 1):
            ea, eb = evaluated[a], evaluated[a + 1]
            for k, test in enumerate(self.tests):
                va, vb = ea.values[k], eb.values[k]
                if va is None or vb is None or va * vb > 0 or (va == 0 and vb == 0):
                    continue
                if test.circle_only and not (abs(ea.point.kappa) < 1 and abs(eb.point.kappa) < 1):
                    continue
                sp = self._locate(test, k, ea, eb, a, summaries[a])
                if sp is not None:
                    found.append((a, sp))
        return found

    def _corrected(self, za: np.ndarray, zb: np.ndarray, s: float) -> tuple[np.ndarray, CurvePoint]:
        """The curve's point on the hyperplane across the chord ``za -> zb`` at ``za + s (zb - za)``."""
        chord = zb - za
        normal = chord / np.linalg.norm(chord)
        sol = self.corrector.solve_bordered(za + s * chord, normal)
        bp = sol.summary
        return sol.z, self.point(sol.z, bp.multipliers, bp.monodromy, bp)

    def _locate(self, test: TestFunction, k: int, ea: _Evaluated, eb: _Evaluated, index: int, near
                ) -> SpecialPoint | None:
        """A sign change of ``test`` between two curve points, located by Illinois on the chord's hyperplanes."""
        curve = self.curve
        za, zb = ea.point.z, eb.point.z
        first = curve.n_base  # the first parameter's place in z
        params = lambda z: np.array([z[first], z[-1]])
        # the condition's guesses (a Neimark-Sacker curve's borders, a sliding curve's arrival) moved to the
        # bracket's start, from wherever the search's evaluations left them
        anchor = getattr(curve, "anchor_at", None) or getattr(curve, "reborder_at", None)
        if anchor is not None:
            anchor(za)
        s_lo, s_hi, f_lo, f_hi = 0.0, 1.0, ea.values[k], eb.values[k]
        lo_z, hi_z = za, zb
        q_ref = ea.q
        status, side = SpecialPointStatus.BRACKETED, 0
        best_z, best_point, f_best = None, None, None
        # the bracket's ends as (z, point, |f|), with the test function's own values (Illinois halves f_lo or f_hi)
        end_lo, end_hi = (za, ea.point, abs(f_lo)), (zb, eb.point, abs(f_hi))
        try:
            for _ in range(self.max_iter):
                s = (s_lo * f_hi - s_hi * f_lo) / (f_hi - f_lo) if f_hi != f_lo else 0.5 * (s_lo + s_hi)
                s = min(max(s, s_lo + 1e-3 * (s_hi - s_lo)), s_hi - 1e-3 * (s_hi - s_lo))
                z, point = self._corrected(za, zb, s)
                e = self.evaluate(point, q_ref)
                f = e.values[k]
                if f is None:
                    break
                best_z, best_point, f_best = z, point, f
                if f == 0.0:
                    lo_z = hi_z = z
                    status = SpecialPointStatus.LOCATED
                    break
                if (f > 0) == (f_lo > 0):
                    s_lo, f_lo, lo_z = s, f, z
                    end_lo = (z, point, abs(f))
                    f_hi = f_hi * 0.5 if side == -1 else f_hi
                    side = -1
                else:
                    s_hi, f_hi, hi_z = s, f, z
                    end_hi = (z, point, abs(f))
                    f_lo = f_lo * 0.5 if side == 1 else f_lo
                    side = 1
                if np.max(np.abs(params(hi_z) - params(lo_z))) <= self.tol * (1.0 + np.max(np.abs(params(z)))):
                    status = SpecialPointStatus.LOCATED
                    # the point is the bracket's end where the test function is smaller (Illinois leaves its last
                    # iterate at either end, at times the far one)
                    best_z, best_point = min(end_lo, end_hi, key=lambda end: end[2])[:2]
                    break
        except (SaltationError, np.linalg.LinAlgError) as exc:
            _log.info("%s between curve points %d and %d not located: %s", _what(test), index, index + 1, exc)
        if best_point is None:
            best_z, best_point = (za, ea.point) if abs(ea.values[k]) <= abs(eb.values[k]) else (zb, eb.point)
        if f_best is not None and abs(f_best) > max(abs(ea.values[k]), abs(eb.values[k])):
            # the test function grew where it changed sign: it passed through infinity (the cubic coefficient at a
            # strong resonance), not through zero
            _log.info("%s test changes sign through a pole between curve points %d and %d: not a bifurcation",
                      _what(test), index, index + 1)
            return None
        if test.pair and not _pair_on_circle(best_point.others):
            _log.info("%s test vanishes at a real pair with product 1 (a neutral saddle): not a bifurcation",
                      _what(test))
            return None
        if status is SpecialPointStatus.LOCATED:
            where = params(best_z)
            accuracy = float(np.max(np.abs(params(hi_z) - params(lo_z))))
            if test.name is _C2.CUSP:  # the central difference's error, through the test function's slope
                accuracy += self._cusp_error(best_point, q_ref, ea, eb, k)
            # the curve point's own error (its next Newton correction and the integration error, carried to the
            # parameters): a point is no better known than the curve it lies on
            own = self._curve_error(best_z, (zb - za) / np.linalg.norm(zb - za))
            if test.name is None or math.isfinite(own):  # (a sliding curve's point says when it is not known)
                accuracy += own
        else:
            where, accuracy = params(best_z), float(np.max(np.abs(params(zb) - params(za))))
        try:
            sides = self._sides(test, za, zb, best_z)
        except SaltationError as exc:
            _log.info("the kind of the sliding bifurcation is not known at the point: %s", exc)
            sides = (self.kind.value, test.meets)
        return _record(sides, test, where, accuracy, index, near, status,
                       (float(params(lo_z)[0]), float(params(hi_z)[0])), best_point, curve)


    def _sides(self, test: TestFunction, za: np.ndarray, zb: np.ndarray, z: np.ndarray) -> tuple[str, str]:
        """A zero's ``sides``: the curve's kinds at the bracket's two points (a test whose sign is the kind), or
        the curve's kind at the zero ``z`` (a sliding bifurcation's, which may change along its curve) and the kind
        the curve meets there."""
        kind_at = getattr(self.curve, "kind_at", None)
        if test.changes_kind and kind_at is not None:
            return kind_at(za).value, kind_at(zb).value
        return (self.kind if kind_at is None else kind_at(z)).value, test.meets

    def _curve_error(self, z: np.ndarray, normal: np.ndarray) -> float:
        """The error of a corrected curve point in the two parameters, as a located point's
        (:func:`saltation.orbits.problem.accuracy`): the next Newton correction on the hyperplane through it
        across the chord, plus the integration error carried to the parameters through the inverse of the
        bordered Jacobian; ``inf`` where it cannot be computed."""
        curve = self.curve
        first = curve.n_base
        try:
            ev = curve.evaluate(z[:-1], float(z[-1]))
            B = np.block([[ev.jac_u, ev.jac_lam[:, None]], [normal[None, :]]])
            inverse = np.linalg.inv(B)
        except (SaltationError, np.linalg.LinAlgError):
            return float("inf")
        error = curve.flow.integration_error(ev.trajectory, curve.tolerances)
        dz = inverse @ np.append(ev.residual, 0.0)
        carried = np.abs(inverse[:, :-1]).sum(axis=1) * error
        return float(max(abs(dz[first]) + carried[first], abs(dz[-1]) + carried[-1]))

    def _cusp_error(self, point: CurvePoint, q_ref, ea: _Evaluated, eb: _Evaluated, k: int) -> float:
        """The cusp's location error from that of its test function: ``4/3 |f(h) - f(h/2)|`` (the ``O(h^2)``
        error of the central difference, estimated) over the test function's slope between the two points."""
        first = self.curve.n_base
        try:
            f1 = cusp_coefficient(self.curve, point, q_ref)[0]
            f2 = cusp_coefficient(self.curve, point, q_ref, h=0.5e-4)[0]
        except SaltationError:
            return float("inf")
        za, zb = ea.point.z, eb.point.z
        width = float(np.max(np.abs(np.array([zb[first] - za[first], zb[-1] - za[-1]]))))
        slope = abs(eb.values[k] - ea.values[k]) / width if width > 0 else 0.0
        return float("inf") if slope == 0 else 4.0 / 3.0 * abs(f1 - f2) / slope


def _pair_on_circle(others: np.ndarray, tol: float = 1e-3) -> bool:
    """Whether two of the multipliers are a complex pair on the unit circle (not a real pair with product 1)."""
    for m in others:
        if abs(m.imag) > tol and abs(abs(m) - 1.0) < tol:
            return True
    return False


def _what(test: TestFunction) -> str:
    """A test's name in words (its label where it has no name)."""
    return test.name.value.replace("_", " ") if test.name is not None else test.label


def _record(sides: tuple[str, str], test: TestFunction, where: np.ndarray, accuracy: float, index: int, near,
            status: SpecialPointStatus, bracket: tuple[float, float], point: CurvePoint, curve) -> SpecialPoint:
    """The record of a located (or bracketed) codimension-two point (``sides``: the curve's kind and the kind it
    meets, or the curve's kinds before and after it): the state, period and amplitude of ``point``'s orbit (those
    of the curve point ``near`` where ``point`` carries no record of its own)."""
    n = curve.system.n
    lo, hi = sorted(bracket)
    if test.name is not None:
        note = f"{_what(test)} on the {sides[0]} curve (a zero of its test function, {status.value})"
    elif test.changes_kind:
        note = f"{sides[0]} -> {sides[1]}: {test.label} (a zero of its test function, {status.value})"
    else:
        note = f"on the {sides[0]} curve {test.label} (a zero of its test function, {status.value})"
    own = point.summary if point.summary is not None else near
    return SpecialPoint(
        kind=SpecialPointKind.CODIMENSION_TWO, parameter=float(where[0]), second_parameter=float(where[1]),
        bracket=(lo, hi), accuracy=accuracy, index=int(index), state=np.array(point.z[:n]),
        period=float(own.period), amplitude=float(own.amplitude), status=status,
        sides=tuple(sides), codimension_two=test.name, multipliers=np.array(point.multipliers),
        note=note,
    )


__all__ = [
    "NORMAL_FORM_TESTS",
    "TESTS",
    "CodimensionTwoSearch",
    "CurvePoint",
    "TestFunction",
    "cusp_coefficient",
    "normal_form_coefficient",
    "fold_eigenvectors",
    "others_of",
]
