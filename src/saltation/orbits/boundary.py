"""One-sided monodromies at a boundary orbit, as exact limits.

Where the event sequence of a branch changes because a segment of the orbit
shrinks to zero length (the orbit passes through a corner of switching
surfaces, as at the paper's w_A and w_B), the Floquet multipliers are
set-valued.  Their two ends are the limits, at the boundary orbit, of the
monodromies on either side:

* ``M_without``: the monodromy of the boundary orbit itself, on the side
  without the segment (continuous there);
* ``M_with``: the same orbit with the zero-length segment inserted at the
  instant ``t*`` where it touches the corner,
  ``M_with = Phi(T, t*) S_exit S_entry Phi(t*, t0)`` (eq. 8 at both events,
  the flow over the segment being the identity in the limit).

Near a corner the monodromy of the side with the segment moves like the
square root of the distance to the boundary, so the monodromies of nearby
orbits are poor estimates of ``M_with`` (an error of ``sqrt(d)``); this module
computes the limit itself.  The saltation matrices are taken at the corner
from their closed form (eq. 9 simplified on the switching surface by sympy),
where eq. (9) would be 0/0 at the corner itself (the entry is tangent to its
surface).  Where no closed form is available (compiled callables) or it is
not finite at the corner, the saltation matrices of the nearest orbit on
that side are used, and the result says so (:attr:`OneSidedLimits.exact`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import sympy as sp
from scipy.optimize import brentq

from saltation.engine.flow import EventKind, SwitchingEvent, Trajectory
from saltation.model.sides import on_its_side
from saltation.model.system import PiecewiseSystem


@dataclass(frozen=True)
class OneSidedLimits:
    """The two one-sided monodromies of a boundary orbit (in the direction of integration).

    Attributes
    ----------
    monodromy_without, monodromy_with : ndarray, shape (n, n)
        Limits at the boundary orbit without and with the zero-length segments.
    touch_times : tuple of float
        The instants ``t*`` where the segments touch the corner.
    touch_states : tuple of ndarray
        The states there.
    exact : bool
        True when every saltation matrix is its closed form at the corner;
        False when the saltation matrices of the nearest orbit with the
        segment were used (then ``M_with`` is known to ``O(sqrt(d))``).
    """

    monodromy_without: np.ndarray
    monodromy_with: np.ndarray
    touch_times: tuple[float, ...]
    touch_states: tuple[np.ndarray, ...]
    exact: bool


def _key(e: SwitchingEvent) -> tuple[int, int]:
    return (int(e.kind), int(e.transition))


def zero_length_segments(
    without: Sequence[SwitchingEvent], with_: Sequence[SwitchingEvent], *, time_tol: float
) -> list[list[int]] | None:
    """Group the events that only the side with the segments has.

    Every event of ``without`` must appear in ``with_`` with the same
    transition at nearly the same time (within ``time_tol``); the others form
    groups of consecutive events, each an excursion that leaves a mode and
    returns to it (a sliding motion started and left counts: grazing-sliding).
    Returns the groups as index lists into ``with_``, or None when the two
    sequences do not differ that way.
    """
    extra: list[int] = []
    j = 0
    for i, e in enumerate(with_):
        if j < len(without) and _key(without[j]) == _key(e) and abs(without[j].t - e.t) <= time_tol:
            j += 1
        else:
            extra.append(i)
    if j != len(without) or not extra:
        return None
    groups: list[list[int]] = []
    for i in extra:  # consecutive extra events, each group closed when its excursion returns
        g = groups[-1] if groups else None
        if g is not None and i == g[-1] + 1 and with_[g[-1]].mode_to != with_[g[0]].mode_from:
            g.append(i)
        else:
            groups.append([i])
    for g in groups:
        first, last = with_[g[0]], with_[g[-1]]
        if first.mode_from != last.mode_to or first.kind == EventKind.SLIDING_END:
            return None
    return groups


@lru_cache(maxsize=256)
def _closed_form_saltation(system: PiecewiseSystem, transition: int):
    """eq. (9) with resets, simplified on the switching surface, as a numeric function of (t, x, p)
    (fractions cancelled, not sympy's full simplify: the same function, at a tenth of the cost)."""
    S = system.saltation_matrix(transition, on_surface=True, simplify=False, one_sided=True)
    return sp.lambdify((system.t, list(system.x), list(system.p)), S, modules="numpy")


@lru_cache(maxsize=256)
def _reset_function(system: PiecewiseSystem, transition: int):
    return sp.lambdify((system.t, list(system.x), list(system.p)), system.resets[transition], modules="numpy")


def _reset(system: PiecewiseSystem, transition: int, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
    if system.resets[transition] is None:
        return x
    return np.asarray(_reset_function(system, transition)(t, list(x), list(p)), dtype=float).reshape(-1)


def saltation_at_corner(
    system, transitions: Sequence[int], t: float, x: np.ndarray, p: np.ndarray
) -> np.ndarray | None:
    """Product ``S_last ... S_first`` of closed-form saltation matrices at ``(t, x)``.

    None when the model has no closed form (compiled callables), or a factor is not finite there, or a factor
    whose source field is tangent to its surface there is unbounded (:func:`_factor_is_unbounded`): the
    excursion enters with the normal speed ``+d`` and leaves with ``-d'``, so factors that grow like ``1/d`` do
    not cancel in the excursion's map (a field that jumps along its surface, as at a pre-stressed stop, gives
    ``S_exit S_entry = I`` when both are taken at one point, while the excursion's map grows like ``1/d``).
    """
    if not isinstance(system, PiecewiseSystem):
        return None
    n = system.n
    P = np.eye(n)
    x = np.asarray(x, dtype=float)
    for k in transitions:
        with np.errstate(divide="ignore", invalid="ignore"):  # 0/0 at a tangency: reported as None below
            S = np.asarray(_closed_form_saltation(system, int(k))(t, list(x), list(p)), dtype=float).reshape(n, n)
        if not np.all(np.isfinite(S)) or _factor_is_unbounded(system, int(k), t, x, p, S):
            return None
        P = S @ P
        x = _reset(system, int(k), t, x, p)
    return P


#: a transition's source field is tangent to its surface where its normal speed is below this fraction of
#: ``|h_x| |f|`` (a located tangency reaches 1e-17 to 1e-7; a transversal crossing is of order one)
TANGENT_SPEED = 1e-6


def _factor_is_unbounded(system: PiecewiseSystem, transition: int, t: float, x: np.ndarray, p: np.ndarray,
                         S: np.ndarray) -> bool:
    """Whether the saltation matrix ``S`` of ``transition`` at a tangency grows like ``1 / d`` (eq. 9 with a
    numerator that does not vanish there), told apart from a bounded one as in
    :func:`corner_saltation_is_bounded`; False where the crossing is transversal."""
    speed, hx, f = (float(v) for v in _tangency_terms(system, transition)(t, list(np.asarray(x, float)), list(p)))
    scale = hx * f
    if not scale > 0.0 or abs(speed) > TANGENT_SPEED * scale:
        return False
    return bool(np.linalg.norm(S) > np.sqrt(scale / max(abs(speed), np.finfo(float).tiny)))


@lru_cache(maxsize=256)
def _tangency_terms(system: PiecewiseSystem, transition: int):
    """``(h_x f- + h_t, |h_x|, |f-|)`` of a transition, as a numeric function of (t, x, p)."""
    tr = system.transitions[transition]
    d = system.surface_derivatives(tr.surface)
    source = system.mode_index(tr.source)
    f_minus = on_its_side(system.fields[source], system.mode_sides(source), [*system.x, system.t])
    speed = (d.h_x * f_minus)[0, 0] + d.h_t
    return sp.lambdify((system.t, list(system.x), list(system.p)),
                       [speed, sp.sqrt(sum(e**2 for e in d.h_x)), sp.sqrt(sum(e**2 for e in f_minus))],
                       modules="numpy")


def corner_saltation_is_bounded(system, transition: int, t: float, x: np.ndarray, p: np.ndarray,
                                P: np.ndarray | None) -> bool:
    """Whether the product ``P`` of saltation matrices of an excursion that grazes ``transition`` at ``(t, x)``
    stays bounded as the excursion shrinks to the tangency.

    The denominator ``d = h_x f- + h_t`` of eq. (9) vanishes at the tangency and is located only to some
    accuracy, so ``P`` is evaluated at a small ``d`` rather than at 0.  A product that is unbounded grows like
    ``1/d`` (``|P| |d|`` is of the order of the jump ``|h_x| |f|``); a bounded one stays of order one.  The two are
    told apart at the geometric mean of the two predictions, ``|P| = sqrt(|h_x| |f| / |d|)``, which lies orders
    of magnitude from both for any ``d`` the location reaches (``|d| / (|h_x| |f|)`` of 1e-17 to 1e-7 gives a
    split at 3e8 to 3e3), so the answer does not depend on how closely, or with which rounding, the tangency was
    located.

    Parameters
    ----------
    system : PiecewiseSystem
    transition : int
        The grazed transition (its source mode's field is tangent to its surface at ``(t, x)``).
    t, x, p
        The tangency and the parameters.
    P : ndarray or None
        The product from :func:`saltation_at_corner` (None: not finite there, hence unbounded).

    Returns
    -------
    bool
    """
    if P is None or not np.all(np.isfinite(P)):
        return False
    speed, hx, f = (float(v) for v in _tangency_terms(system, int(transition))(t, list(np.asarray(x, float)), list(p)))
    scale = hx * f
    if not scale > 0.0:
        return False  # a rest point on the surface (or a degenerate surface): eq. (9) has no limit there
    return bool(np.linalg.norm(P) <= np.sqrt(scale / max(abs(speed), np.finfo(float).tiny)))


def one_sided_limits(
    flow,
    without: Trajectory,
    with_: Trajectory,
    p: np.ndarray,
    *,
    tolerances=None,
) -> OneSidedLimits | None:
    """The exact one-sided monodromies at the boundary orbit ``without``.

    Parameters
    ----------
    flow : Flow
    without : Trajectory
        One period of the orbit on the side without the zero-length segments,
        as close to the boundary as located (with its monodromy).
    with_ : Trajectory
        One period of the nearest orbit on the other side.
    p : ndarray
        Parameters of ``without``.

    Returns
    -------
    OneSidedLimits or None
        None when the two sides do not differ by zero-length excursions, or
        a touching instant cannot be found, or ``Phi(t*, t0)`` is singular.
    """
    system = flow.system
    t0, t1 = without.t0, without.t1
    span = abs(t1 - t0)
    ev_wo, ev_w = without.events, with_.events
    groups = zero_length_segments(ev_wo, ev_w, time_tol=1e-4 * span)
    if groups is None:
        return None
    run = lambda t: flow.run(without.x0, t0, t, p, mode0=without.mode0, tolerances=tolerances)  # noqa: E731
    M_wo = without.monodromy
    times, states = [], []
    exact = True
    conjugated = []
    for g in groups:
        t_star = _touch_time(flow, run, [ev_w[i] for i in g], p, t0, t1)
        if t_star is None:
            return None
        traj = flow.run(without.x0, t0, t_star, p, mode0=without.mode0, variational=True, tolerances=tolerances)
        phi = traj.monodromy
        if np.linalg.cond(phi) > 1e10:
            return None
        transitions_only = all(ev_w[i].kind == EventKind.TRANSITION for i in g)
        P = saltation_at_corner(system, [ev_w[i].transition for i in g], t_star, traj.x1, p) if transitions_only else None
        if P is None:
            exact = False
            P = np.eye(system.n)
            for i in g:
                P = ev_w[i].saltation @ P
        conjugated.append(np.linalg.solve(phi, P @ phi))
        times.append(float(t_star))
        states.append(traj.x1.copy())
    # M_with = Phi(T, t_k*) P_k ... P_1 Phi(t_1*, t0) = M_without C_k ... C_1, C_j = Phi(t_j*, t0)^-1 P_j Phi(t_j*, t0)
    product = np.eye(system.n)
    for C in conjugated:
        product = C @ product
    M_w = M_wo @ product
    return OneSidedLimits(
        monodromy_without=M_wo.copy(), monodromy_with=M_w, touch_times=tuple(times), touch_states=tuple(states),
        exact=exact,
    )


def _touch_time(flow, run, group: Sequence[SwitchingEvent], p, t0, t1) -> float | None:
    """The instant where the boundary orbit passes the corner of the group's surfaces.

    A surface of the group that the boundary orbit crosses transversally near
    the group's events has a simple root there (the exit surface of a contact
    at a corner, for example); the first such root, bracketed around the
    events' times, is ``t*``.
    """
    system = flow.system
    ta, tb = group[0].t, group[-1].t
    width = max(abs(tb - ta), 1e-9 * max(1.0, abs(ta)))
    lo_limit, hi_limit = min(t0, t1), max(t0, t1)
    surfaces = []
    for e in group:
        s = system.surface_names.index(e.surface)
        if s not in surfaces:
            surfaces.append(s)
    for s in surfaces:
        h = lambda t: flow.indicator(s, t, run(t).x1, p)  # noqa: E731
        for grow in (1.0, 4.0, 16.0):
            a = max(lo_limit, min(ta, tb) - (grow - 1.0) * width)
            b = min(hi_limit, max(ta, tb) + (grow - 1.0) * width)
            if b <= a:
                continue
            ha, hb = h(a), h(b)
            if ha == 0.0:
                return a
            if hb == 0.0:
                return b
            if np.sign(ha) != np.sign(hb):
                return float(brentq(h, a, b, xtol=1e-15 * max(1.0, abs(a)), rtol=1e-15, maxiter=200))
    return None
