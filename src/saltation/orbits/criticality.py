"""Criticality of period doublings and Neimark-Sacker bifurcations of hybrid periodic orbits.

At a period doubling (a multiplier -1) or a Neimark-Sacker bifurcation (a pair ``e^{+-i theta}``) of a
periodic orbit, the sign of one normal-form coefficient of the period map decides what is born: a stable
period-2 orbit or invariant circle (torus) on the side where the orbit is unstable (*supercritical*), or an
unstable one on the side where it is stable (*subcritical*).  The coefficients need the map's derivatives up
to the third at the orbit: the first two are exact through every event
(:mod:`saltation.orbits.second_order`); the third, along the critical eigenvectors only, is the central
difference of the exact second derivative at the orbit's state moved along them, with Richardson
extrapolation.  Through a complete chatter (:mod:`saltation.engine.chatter`) the map is the engine's jump from
one of its impacts onto the stuck motion, from the same impact at the orbit and at every state moved off it
(however many impacts each run resolved), and the accuracy says how far that is from the chatter's limit.

For a map ``x -> A x + B(x, x)/2 + C(x, x, x)/6 + ...`` (Kuznetsov, *Elements of Applied Bifurcation
Theory*, 3rd ed., 2004, sec. 5.4; Kuznetsov and Meijer, SIAM J. Sci. Comput. 26, 2005, sec. 2):

* period doubling, ``A q = -q``, ``A^T p = -p``, ``p . q = 1``, ``|q| = 1``: the map on its center
  manifold is ``xi -> -xi + b xi^3 + ...`` with ::

      b = (1/6) p . C(q, q, q) + (1/2) p . B(q, (I - A)^-1 B(q, q)),

  supercritical (a stable period-2 orbit) when ``b > 0``;
* Neimark-Sacker, ``A q = e^{i theta} q``, ``A^T p = e^{i theta} p``, ``p . q = 1``, ``|q| = 1``: the map on
  its center manifold is ``w -> e^{i theta} w (1 + d |w|^2) + ...`` with the first Lyapunov coefficient ::

      d = (1/2) Re{ e^{-i theta} [ p . C(q, q, qbar) + 2 p . B(q, (I - A)^-1 B(q, qbar))
                                   + p . B(qbar, (e^{2 i theta} I - A)^-1 B(q, q)) ] },

  supercritical (a stable invariant circle) when ``d < 0``.

``p . v`` is the bilinear product ``sum p_i v_i``.  A forced orbit's map is its stroboscopic map in the
state's coordinates; an autonomous orbit's is its Poincare map on the hyperplane through its state normal to
the flow, in an orthonormal basis of that hyperplane (:func:`saltation.orbits.second_order.section_basis`);
the value of a coefficient depends on those coordinates (through ``|q| = 1``), its sign does not.  An orbit
computed in backward time is analysed as the same orbit in forward time: the coefficients of the inverse map
are those of the forward map with the sign changed.
"""

from __future__ import annotations

import copy
import logging
import math
from dataclasses import dataclass, field

import numpy as np

from saltation.engine.flow import Flow, Trajectory
from saltation.errors import InconsistentResultError, ModelError, SaltationError
from saltation.kinds import Criticality, SpecialPointKind
from saltation.orbits.second_order import (
    _field_at,
    _segments,
    _symbolic_model,
    chatter_impacts,
    run_map_derivatives,
    section_basis,
    section_map_derivatives,
)

_log = logging.getLogger(__name__)

#: The distance of the critical multiplier from -1 (period doubling) or of its modulus from 1
#: (Neimark-Sacker) that an orbit may have: the orbit must be at its bifurcation.
MULTIPLIER_TOLERANCE = 1e-6
#: The step of the central differences of the second derivative, as a fraction of the orbit's excursion.
STEP_FRACTION = 1e-3
#: An event closer than this fraction of the period to the orbit's state moves the state, for the
#: analysis, to the middle of the longest stretch between events (as shooting moves its section).
SEAM_MARGIN = 0.02
#: Strong resonances ``e^{i k theta} = 1`` (k = 1..4) within this distance make a Neimark-Sacker coefficient
#: meaningless (k = 3: not defined).
RESONANCE_TOLERANCE = 1e-3


@dataclass(frozen=True)
class NormalFormCoefficient:
    """The criticality of a period doubling or Neimark-Sacker bifurcation of a periodic orbit.

    Attributes
    ----------
    kind : SpecialPointKind
        ``PERIOD_DOUBLING`` or ``NEIMARK_SACKER``.
    coefficient : float
        The normal-form coefficient of the forward-time map: ``b`` of ``xi -> -xi + b xi^3`` (period
        doubling) or the first Lyapunov coefficient ``d`` of ``w -> e^{i theta} w (1 + d |w|^2)``
        (Neimark-Sacker), with the critical eigenvector of unit length in the map's coordinates.
    accuracy : float
        An estimate of its error: the Richardson estimate of the central differences of the third
        derivative, plus the integration error carried by the differences, plus, on an orbit that chatters to
        rest, the distance from the chatter's limit (the coefficient with each chatter jumped one impact
        earlier, :func:`saltation.orbits.second_order.chatter_errors`).
    criticality : Criticality
        Supercritical (``b > 0``, ``d < 0``: a stable period-2 orbit or invariant circle), subcritical, or
        degenerate (``|coefficient| <= accuracy``).
    multiplier : complex
        The critical forward-time multiplier (``e^{i theta}`` with ``theta`` in ``(0, pi)``).
    eigenvector : ndarray
        ``q`` in the map's coordinates (complex for Neimark-Sacker), ``|q| = 1``.
    coordinates : str
        ``"state"`` (a forced orbit's stroboscopic map) or ``"section"`` (an autonomous orbit's Poincare map).
    basis : ndarray or None
        The section's orthonormal basis, shape (n, n - 1), for ``"section"`` (the map's coordinates ``y``
        stand for the state ``state + basis @ y``).
    state : ndarray
        The orbit's state the map was expanded at.
    t0 : float
        The time at which the orbit passes ``state`` (it may differ from the orbit's own: see :data:`SEAM_MARGIN`).
    step : float
        The step of the central differences along ``q``.
    """

    kind: SpecialPointKind
    coefficient: float
    accuracy: float
    criticality: Criticality
    multiplier: complex
    eigenvector: np.ndarray = field(repr=False)
    coordinates: str = "state"
    basis: np.ndarray | None = field(default=None, repr=False)
    state: np.ndarray | None = field(default=None, repr=False)
    t0: float = 0.0
    step: float = float("nan")

    def __repr__(self) -> str:
        name = "b" if self.kind is SpecialPointKind.PERIOD_DOUBLING else "d"
        return (f"NormalFormCoefficient({self.kind.value}: {name} = {self.coefficient:.6g} +- {self.accuracy:.2g}, "
                f"{self.criticality.value})")


class _SequenceChanged(SaltationError):
    """A perturbed state's run has other events than the orbit's: the step is too large."""


class _ReturnMap:
    """An orbit's period map (forced) or Poincare map (autonomous), expanded at its state: its first and second
    derivatives at the state moved by ``y`` (in the map's coordinates)."""

    def __init__(self, orbit):
        traj = getattr(orbit, "trajectory", None)
        if traj is None or getattr(orbit, "parameters", None) is None:
            raise ModelError(f"expected a PeriodicOrbit, got {type(orbit).__name__}")
        self.system = _symbolic_model(traj.system)
        if not getattr(orbit, "converged", True):
            raise ModelError("the orbit did not converge: its normal form means nothing")
        problem = getattr(orbit, "problem", None)
        self.flow = getattr(problem, "flow", None) or Flow(self.system)
        self.tolerances = getattr(problem, "tolerances", None)
        self.p = np.asarray(orbit.parameters, dtype=float)
        self.autonomous = bool(orbit.autonomous)
        self.backward = bool(orbit.backward)
        self.span = float(traj.t1 - traj.t0)
        self.trajectory = self._off_the_seam(traj)
        self.t0 = float(self.trajectory.t0)
        self.state = np.asarray(self.trajectory.x0, dtype=float)
        self.mode0 = self.trajectory.mode0
        self.signature, self.kept = _sequence(self.trajectory)
        excursion = float(np.max(self.trajectory.x_max - self.trajectory.x_min))
        self.scale = excursion if excursion > 0.0 else 1.0 + float(np.max(np.abs(self.state)))
        self.normal = self.basis = None
        if self.autonomous:
            key = _segments(self.trajectory)[0].field
            F = _field_at(self.system, key, np.concatenate([[self.t0], self.state]), self.p)[0][1:]
            self.normal = F / float(np.linalg.norm(F))
            self.basis = section_basis(self.normal)

    def _run(self, x: np.ndarray, t0: float, span: float, mode0: str, variational: bool = True) -> Trajectory:
        return self.flow.run(x, t0, t0 + span, self.p, mode0=mode0, variational=variational,
                             tolerances=self.tolerances)

    def _off_the_seam(self, traj: Trajectory) -> Trajectory:
        """The orbit's run, or one from the middle of its longest stretch between events that is not a sliding
        motion, where an event lies within :data:`SEAM_MARGIN` of the period of its start or end."""
        margin = SEAM_MARGIN * abs(self.span)
        times = [abs(e.t - traj.t0) for e in traj.events]
        if traj.monodromy is not None and (not times or (times[0] >= margin and abs(self.span) - times[-1] >= margin)):
            return traj
        stretches = [(abs(s.t_end - s.t_start), 0.5 * (s.t_start + s.t_end)) for s in _segments(traj)
                     if s.field[0] == "mode"]
        length, middle = max(stretches, default=(0.0, None))
        if middle is None or length < 2.0 * margin:
            raise ModelError("the orbit has no stretch between events longer than "
                             f"{2 * SEAM_MARGIN:g} of its period to expand its period map at")
        mid = self._run(np.asarray(traj.x0, dtype=float), traj.t0, middle - traj.t0, traj.mode0, variational=False)
        moved = self._run(np.asarray(mid.x1, dtype=float), middle, self.span, mid.mode1)
        gap = float(np.max(np.abs(moved.x1 - mid.x1)))
        if not gap <= 1e-6 * (1.0 + float(np.max(np.abs(mid.x1)))):
            raise InconsistentResultError(f"the orbit does not close when started at t = {middle:.10g} "
                                          f"(it misses its state by {gap:.3g})")
        _log.debug("criticality: the map is expanded at t = %.10g, off the events", middle)
        return moved

    def run(self, y: np.ndarray) -> Trajectory:
        """The run from the state moved by ``y`` (in the map's coordinates), with the orbit's events."""
        x = self.state + (self.basis @ y if self.autonomous else y)
        traj = self._run(x, self.t0, self.span, self.mode0)
        signature, kept = _sequence(traj)
        if signature != self.signature:
            raise _SequenceChanged(f"the run from {x} has other events than the orbit")
        self.kept = tuple(min(a, b) for a, b in zip(self.kept, kept))
        return traj

    def jets(self, traj: Trajectory | None = None):
        """The map's derivatives (``first``, ``second``, and the chatters' ``earlier`` ones) from a run (None: the
        orbit's), each complete chatter jumped from the impact all the runs so far kept (:attr:`kept`): the same
        map at every state, whatever impacts the integrator resolved before its jumps."""
        traj = self.trajectory if traj is None else traj
        levels = dict(enumerate(self.kept))
        if self.autonomous:
            return section_map_derivatives(traj, self.p, traj.monodromy, normal=self.normal, point=self.state,
                                           levels=levels)
        return run_map_derivatives(traj, self.p, traj.monodromy, levels=levels)


def _sequence(traj: Trajectory) -> tuple[list, tuple[int, ...]]:
    """A run's events by signature, each complete chatter's impacts counted once (how many of them the integrator
    resolved before it jumped to their accumulation point depends on the state, not on the orbit), and how many
    each chatter kept."""
    chatters = chatter_impacts(traj)
    extra = {i for _, chain in chatters for i in chain[1:]}
    return ([e.signature for i, e in enumerate(traj.events) if i not in extra],
            tuple(len(chain) for _, chain in chatters))


def _parse_kind(kind) -> SpecialPointKind | None:
    if kind is None:
        return None
    try:
        parsed = kind if isinstance(kind, SpecialPointKind) else SpecialPointKind(kind)
    except ValueError:
        parsed = None
    if parsed not in (SpecialPointKind.PERIOD_DOUBLING, SpecialPointKind.NEIMARK_SACKER):
        raise ModelError(f"criticality is defined for period_doubling and neimark_sacker, got "
                         f"{getattr(kind, 'value', kind)!r}")
    return parsed


def _eig(A: np.ndarray, target: complex) -> tuple[complex, np.ndarray, np.ndarray, float]:
    """The eigenvalue of ``A`` nearest ``target``, its right and left eigenvectors ``q`` (``|q| = 1``) and
    ``p`` (``p . q = 1``), and the distance to the next eigenvalue."""
    mu, V = np.linalg.eig(A)
    k = int(np.argmin(np.abs(mu - target)))
    others = np.delete(mu, k)
    gap = float(np.min(np.abs(others - mu[k]))) if others.size else math.inf
    q = V[:, k] / np.linalg.norm(V[:, k])
    muT, W = np.linalg.eig(A.T)
    w = W[:, int(np.argmin(np.abs(muT - mu[k])))]
    return complex(mu[k]), q, w / (w @ q), gap


def _critical(A: np.ndarray, kind: SpecialPointKind | None, tolerance: float):
    """The critical multiplier of the map (in its direction of integration), its vectors, and the kind."""
    mu_all = np.linalg.eigvals(A)
    if kind is None:
        flip = float(np.min(np.abs(mu_all + 1.0)))
        complex_ = [m for m in mu_all if m.imag > 1e-8]
        ns = min((abs(abs(m) - 1.0) for m in complex_), default=math.inf)
        kind = SpecialPointKind.PERIOD_DOUBLING if flip <= ns else SpecialPointKind.NEIMARK_SACKER
    if kind is SpecialPointKind.PERIOD_DOUBLING:
        mu, q, p, gap = _eig(A, -1.0)
        distance = abs(mu + 1.0)
        if not (distance <= tolerance and gap > distance):
            raise ModelError(f"the orbit has no simple multiplier at -1 (the nearest is {mu:.8g}, "
                             f"{distance:.2g} away; tolerance {tolerance:g}): not at a period doubling")
        q, p = q.real / np.linalg.norm(q.real), p.real
        k = int(np.argmax(np.abs(q)))
        q = q * np.sign(q[k])
        return kind, -1.0 + 0j, q, p / (p @ q)
    complex_ = [m for m in mu_all if m.imag > 1e-8]
    if not complex_:
        raise ModelError(f"the orbit has no complex multipliers (they are {np.round(mu_all, 8)}): not at a "
                         "Neimark-Sacker bifurcation")
    target = min(complex_, key=lambda m: abs(abs(m) - 1.0))
    mu, q, p, gap = _eig(A, target)
    distance = abs(abs(mu) - 1.0)
    if not distance <= tolerance:
        raise ModelError(f"the orbit has no multipliers on the unit circle (the nearest pair is {mu:.8g}, "
                         f"|mu| - 1 = {abs(mu) - 1.0:.2g}; tolerance {tolerance:g}): not at a Neimark-Sacker bifurcation")
    theta = math.atan2(mu.imag, mu.real)
    for order in (1, 2, 3, 4):
        if abs(np.exp(1j * order * theta) - 1.0) < RESONANCE_TOLERANCE:
            raise ModelError(f"the multipliers e^(+-i theta), theta = {theta:.6g}, are at a strong 1:{order} "
                             "resonance: the Neimark-Sacker normal form does not decide the criticality there")
    return kind, mu, q, p


def _flip_coefficient(A, B, D, q, p) -> float:
    """``b = p . C(q,q,q)/6 + p . B(q, (I - A)^-1 B(q,q))/2`` with ``C(q, ., .) = D``."""
    n = len(q)
    Bqq = np.einsum("ijk,j,k->i", B, q, q)
    h2 = np.linalg.solve(np.eye(n) - A, Bqq)
    return float(p @ np.einsum("ijk,j,k->i", D, q, q) / 6.0 + p @ np.einsum("ijk,j,k->i", B, q, h2) / 2.0)


def _ns_coefficient(A, B, D, q, p, mu) -> float:
    """``d = Re(e^{-i theta} c1)``, ``c1 = p . [C(q,q,qbar) + 2 B(q, h11) + B(qbar, h20)] / 2`` with
    ``C(q, ., .) = D``."""
    n = len(q)
    qb = q.conj()
    h11 = np.linalg.solve(np.eye(n) - A, np.einsum("ijk,j,k->i", B, q, qb))
    h20 = np.linalg.solve(mu**2 * np.eye(n) - A, np.einsum("ijk,j,k->i", B, q, q))
    c1 = 0.5 * p @ (np.einsum("ijk,j,k->i", D, q, qb) + 2.0 * np.einsum("ijk,j,k->i", B, q, h11)
                    + np.einsum("ijk,j,k->i", B, qb, h20))
    return float((c1 * mu.conjugate() / abs(mu)).real)


def _differences(the_map: _ReturnMap, q: np.ndarray, step: float) -> tuple[list, float]:
    """The exact first and second derivatives at the state moved by ``+-s v`` and ``+-s v / 2``, for the real
    and imaginary parts ``v`` of ``q``: ``[(v, ((d+, d-) at s, the same at s/2)), ...]`` (each ``d`` a
    :class:`~saltation.orbits.second_order.MapDerivatives`) and ``s``.  A step whose runs change the event
    sequence is quartered (a grazing or a corner nearby).  The runs are made first, so that every complete chatter
    is jumped from the same impact in all of them."""
    parts = [v for v in ((q.real, q.imag) if np.iscomplexobj(q) else (q,))]
    for _ in range(4):
        try:
            runs = []
            for v in parts:
                if not np.any(v):
                    runs.append((v, None))
                    continue
                runs.append((v, [(the_map.run(s * v), the_map.run(-s * v)) for s in (step, step / 2)]))
            break
        except _SequenceChanged:
            step /= 4.0
    else:
        raise SaltationError("the orbit's event sequence changes within "
                             f"{4 * step:.2g} of its state along the critical eigenvector: a grazing or corner is too "
                             "near for the normal form of a smooth map")
    out = [(v, None if pairs is None else [(the_map.jets(plus), the_map.jets(minus)) for plus, minus in pairs])
           for v, pairs in runs]
    return out, step


def _arrays(differences: list, chatter: int | None = None) -> list:
    """``differences`` as ``[(v, ((A+, A-, B+, B-) at s, the same at s/2)), ...]``: the derivatives themselves, or
    (``chatter``) those with that complete chatter jumped one impact earlier."""
    def pick(d):
        return (d.first, d.second) if chatter is None else d.earlier[chatter][1:]

    out = []
    for v, runs in differences:
        if runs is None:
            out.append((v, None))
            continue
        rows = []
        for plus, minus in runs:
            (A_plus, B_plus), (A_minus, B_minus) = pick(plus), pick(minus)
            rows.append((A_plus, A_minus, B_plus, B_minus))
        out.append((v, rows))
    return out


def _third_derivative(differences: list, step: float, n: int, complex_: bool) -> tuple[np.ndarray, np.ndarray]:
    """``C(q, ., .)`` by central differences of the second derivative at ``s`` and ``s/2``: the Richardson
    extrapolation and the plain difference at ``s/2``."""
    estimates = []
    for j, s in enumerate((step, step / 2)):
        total = np.zeros((n, n, n), dtype=complex if complex_ else float)
        for i, (_, runs) in enumerate(differences):
            if runs is None:
                continue
            _, _, B_plus, B_minus = runs[j]
            total = total + (1j if i == 1 else 1.0) * (B_plus - B_minus) / (2.0 * s)
        estimates.append(total)
    return (4.0 * estimates[1] - estimates[0]) / 3.0, estimates[1]


def _coefficients(kind: SpecialPointKind, A: np.ndarray, B: np.ndarray, arrays: list, step: float, q: np.ndarray,
                  p: np.ndarray, mu: complex) -> tuple[float, float]:
    """The normal-form coefficient with the third derivative's Richardson extrapolation, and with its plain
    difference at ``s/2``."""
    D, D_half = _third_derivative(arrays, step, len(q), np.iscomplexobj(q))
    if kind is SpecialPointKind.PERIOD_DOUBLING:
        return _flip_coefficient(A, B, D.real, q, p), _flip_coefficient(A, B, D_half.real, q, p)
    return _ns_coefficient(A, B, D, q, p, mu), _ns_coefficient(A, B, D_half, q, p, mu)


def _integration_error(differences: list, B: np.ndarray, step: float) -> float:
    """The integration error of the differences of the second derivative, measured on those of the first: the
    exact ``B v`` against the Richardson extrapolation of ``(A(x + s v) - A(x - s v)) / 2s`` (whose own
    truncation error is of fourth order).  Raises if they disagree beyond what the differences explain."""
    worst = 0.0
    for v, runs in differences:
        if runs is None:
            continue
        d1 = (runs[0][0] - runs[0][1]) / (2.0 * step)
        d2 = (runs[1][0] - runs[1][1]) / step
        exact = np.einsum("ijk,k->ij", B, v)
        error = float(np.max(np.abs((4.0 * d2 - d1) / 3.0 - exact)))
        truncation = float(np.max(np.abs(d2 - d1)))
        if not error <= 10.0 * truncation + 1e-6 * (1.0 + float(np.max(np.abs(B)))):
            raise InconsistentResultError(f"the exact second derivative of the period map differs by {error:.3g} from "
                                          "central differences of its exact first derivative")
        worst = max(worst, error)
    return worst


def criticality(orbit, kind: SpecialPointKind | str | None = None, *, tolerance: float = MULTIPLIER_TOLERANCE,
                step: float | None = None) -> NormalFormCoefficient:
    """The criticality of an orbit's period doubling or Neimark-Sacker bifurcation, from its normal form.

    Parameters
    ----------
    orbit : PeriodicOrbit
        A periodic orbit at the bifurcation (a multiplier at -1, or a pair on the unit circle), of a model
        written with sympy expressions, forced or autonomous, forward or backward in time.
    kind : SpecialPointKind or str, optional
        ``period_doubling`` or ``neimark_sacker``; by default the one whose multipliers lie nearer.
    tolerance : float
        How far the critical multiplier may be from -1 (or its modulus from 1).
    step : float, optional
        The step of the central differences along the critical eigenvector (by default
        :data:`STEP_FRACTION` of the orbit's excursion).

    Returns
    -------
    NormalFormCoefficient
        The coefficient, its accuracy and the verdict.

    Raises
    ------
    ModelError
        If ``kind`` is neither, the orbit is not at that bifurcation (within ``tolerance``), a Neimark-Sacker
        pair is at a strong resonance (1:1 to 1:4), the orbit did not converge, or its model is given as
        compiled callables.
    InconsistentResultError
        As :func:`saltation.orbits.second_order.period_map_derivatives`; or if the exact second derivative
        disagrees with central differences of the exact first derivative.
    SaltationError
        If the event sequence changes within the steps of the differences (a grazing or corner nearby).

    References
    ----------
    Kuznetsov (2004), *Elements of Applied Bifurcation Theory*, 3rd ed., Springer, secs. 4.4, 4.6 and 5.4.
    Kuznetsov and Meijer (2005), "Numerical normal forms for codim 2 bifurcations of fixed points with at
    most two critical eigenvalues", SIAM J. Sci. Comput. 26.  Kuznetsov, Govaerts, Doedel and Dhooge (2005),
    "Numerical periodic normalization for codim 1 bifurcations of limit cycles", SIAM J. Numer. Anal. 43.
    """
    kind = _parse_kind(kind)
    the_map = _ReturnMap(orbit)
    kept = the_map.kept
    at_orbit = the_map.jets()
    kind, mu, q, p = _critical(at_orbit.first, kind, tolerance)
    h = STEP_FRACTION * the_map.scale if step is None else float(step)
    if not (h > 0.0 and math.isfinite(h)):
        raise ModelError(f"the step of the differences must be positive, got {step!r}")
    differences, h = _differences(the_map, q, h)
    if the_map.kept != kept:  # a nearby run resolved fewer impacts of a chatter: the orbit's map jumps from there too
        at_orbit = the_map.jets()
    A, B = at_orbit.first, at_orbit.second
    arrays = _arrays(differences)
    value, rough = _coefficients(kind, A, B, arrays, h, q, p, mu)
    # the error of the plain differences at s/2 (an upper bound of the extrapolated value's), and the
    # integration error the differences carry (C's entries err by about what A's differences do)
    accuracy = abs(value - rough) + float(np.linalg.norm(p)) * _integration_error(arrays, B, h)
    # on an orbit that chatters to rest: the coefficient's distance from the chatter's limit, from the map with
    # each chatter jumped one impact earlier (geometric convergence, as second_order.chatter_errors)
    for c, (r, A_c, B_c) in enumerate(at_orbit.earlier):
        factor = r / (1.0 - r) if 0.0 <= r < 1.0 else math.inf
        if not math.isfinite(factor):
            accuracy = math.inf
            continue
        earlier, _ = _coefficients(kind, A_c, B_c, _arrays(differences, c), h, q, p, mu)
        accuracy += factor * abs(earlier - value)
    if the_map.backward:
        value = -value  # the inverse map's coefficient: the forward-time orbit's is its negative
        mu = 1.0 / mu
        if mu.imag < 0:
            mu, q = mu.conjugate(), q.conj()
    supercritical = value > 0 if kind is SpecialPointKind.PERIOD_DOUBLING else value < 0
    verdict = (Criticality.DEGENERATE if not abs(value) > accuracy
               else Criticality.SUPERCRITICAL if supercritical else Criticality.SUBCRITICAL)
    _log.debug("criticality of %s: %s %.6g +- %.2g", the_map.system.name, kind.value, value, accuracy)
    return NormalFormCoefficient(
        kind=kind, coefficient=value, accuracy=accuracy, criticality=verdict, multiplier=complex(mu), eigenvector=q,
        coordinates="section" if the_map.autonomous else "state", basis=the_map.basis, state=the_map.state.copy(),
        t0=the_map.t0, step=h,
    )


def special_point_criticality(source, point, *, tolerance: float = MULTIPLIER_TOLERANCE,
                              step: float | None = None) -> NormalFormCoefficient:
    """The criticality of a period doubling or Neimark-Sacker point of a branch.

    The point's orbit is solved again (Newton, from the point's state at its parameter and section time,
    on a copy of the branch's problem) and handed to :func:`criticality`.

    Parameters
    ----------
    source : Branch, BranchProblem or PeriodicOrbit
        The branch the point belongs to (it holds its problem), the problem the branch was computed
        with (with its continuation parameter), or an orbit whose problem that is.
    point : SpecialPoint or int
        A special point of kind ``period_doubling`` or ``neimark_sacker`` (from a branch, also its index in
        ``branch.special_points``).
    tolerance, step :
        As :func:`criticality`.

    Returns
    -------
    NormalFormCoefficient
        As :func:`criticality`.

    Raises
    ------
    ModelError
        If the point is of another kind, ``source`` holds no problem, the index names no special point, or
        as :func:`criticality`.
    ConvergenceError
        If the point's orbit cannot be solved again.
    InconsistentResultError, SaltationError
        As :func:`criticality`.
    """
    problem = source
    if hasattr(source, "special_points"):  # a branch
        count = len(source.special_points)
        if isinstance(point, (int, np.integer)) and not isinstance(point, bool):
            if not -count <= int(point) < count:
                raise ModelError(f"the branch has {count} special points; {point!r} is not an index of one")
            point = source.special_points[int(point)]
        problem = source.problem
    elif hasattr(source, "trajectory") and hasattr(source, "problem"):  # an orbit
        problem = source.problem
    if problem is None or not hasattr(problem, "solve"):
        raise ModelError("the special point's criticality needs the problem its branch was computed with (a branch "
                         "read from a file holds none): pass the problem, e.g. ShootingProblem(flow, parameters, "
                         "continuation_parameter=...)")
    kind = getattr(point, "kind", None)
    if kind not in (SpecialPointKind.PERIOD_DOUBLING, SpecialPointKind.NEIMARK_SACKER):
        raise ModelError(f"criticality is defined for period_doubling and neimark_sacker points, got "
                         f"{getattr(kind, 'value', kind)!r}")
    if getattr(problem, "lam_index", -1) < 0:
        raise ModelError("the problem has no continuation parameter: the special point's parameter cannot be set "
                         "(pass the branch, or the problem it was computed with)")
    problem = copy.copy(problem)
    getattr(problem, "align_section", lambda point: None)(point)
    lam = float(point.parameter)
    orbit = problem.solve(problem.pack(point.state, point.period), lam)
    return criticality(orbit, kind, tolerance=tolerance, step=step)


__all__ = ["MULTIPLIER_TOLERANCE", "RESONANCE_TOLERANCE", "SEAM_MARGIN", "STEP_FRACTION", "NormalFormCoefficient",
           "criticality", "special_point_criticality"]
