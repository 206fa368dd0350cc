"""Second derivatives of a hybrid orbit's period map, exact through every event (second-order saltation).

The period map of a periodic orbit, ``P(x0) = x(t0 + T; t0, x0)`` (forced orbits, and the time-``T`` map of
autonomous ones), is smooth near an orbit whose events are transversal: its first derivative is the
monodromy matrix, the product of the flow's fundamental matrices and the saltation matrices of eq. (9); its
second derivative is what this module computes, without finite differences, from the model's sympy
expressions (:mod:`saltation.model.system`) and the orbit's event log (:mod:`saltation.engine.trajectory`).

The construction (derived in the developer notes, ``docs/algorithms.md``, "Second derivatives of the period
map"): in the extended state ``z = (t, x)`` every field is autonomous, ``z' = F(z) = (1, f(t, x))``, and the
orbit is a composition of

* *flow-to-section maps* ``G(z) = psi(tau(z), z)``, where ``psi(s, z)`` is the flow of the segment's field
  for a time ``s`` and ``tau(z)`` the time at which it reaches the next event's section, ``H(psi) = 0``
  (``H`` the indicator ``h(t, x)`` of the surface crossed, the exit side's Lie derivative ``h_x f + h_t``
  for the end of a sliding motion, ``t - t1`` for the end of the period, a hyperplane for a Poincare
  section);
* *event maps*: a transition's reset ``z -> (t, g(t, x))``, or the identity (a plain switch, the start
  or end of a sliding motion).

The 2-jet of a flow-to-section map follows from the first and second variational equations of the segment,
``Phi' = F_z Phi`` and ``Psi' = F_z Psi + F_zz[Phi, Phi]`` (integrated with scipy's DOP853 between the
logged event times, from the logged state after the previous event), and the implicit event time::

    tau_z  = -H_z Phi / (H_z F)
    G_z    = Phi + F tau_z
    G_zz   = Psi + F_z F tau_z tau_z + F_z Phi (x) tau_z + tau_z (x) F_z Phi + F tau_zz
    tau_zz = -(H_z [Psi + F_z F tau_z tau_z + F_z Phi (x) tau_z + tau_z (x) F_z Phi] + H_zz[G_z, G_z]) / (H_z F)

(every field and derivative at the event state); the jets compose by the chain rule,
``(J, K) -> (A J, A K + B[J, J])``.  The first-order part of the composition reproduces the library's
monodromy, whose saltation matrices are the same chain rule to first order: it is checked against it.
Filippov sliding motions are segments like any other, with the sliding field
``f_a + alpha (f_b - f_a)``, ``alpha = s_a / (s_a - s_b)``, ``s_m = h_x f_m + h_t``, which keeps ``h``
constant; they start at the surface (the identity map) and end where the exit side's Lie derivative
vanishes.

A complete chatter (impacts accumulating where the contact sticks, :mod:`saltation.engine.chatter`) is
differentiated as the engine maps it: the impacts it kept (flights to the surface and resets, like any others),
then its jump from the last of them onto the stuck motion, the plastic projection ``z -> (t, x + B c)`` onto
``h = 0``, ``Lh = 0`` along ``B = [b, f_x b]`` (``b`` the contact direction), whose 2-jet follows from the
implicit function theorem, then the stuck mode from that impact's time.  Its first derivative is the engine's
monodromy through the chatter; both stand for the limit of the infinitely many impacts up to an error that
shrinks geometrically with the impacts kept, estimated from the same map jumped one impact earlier
(:func:`chatter_errors`) and carried by the result (``first_error``, ``second_error``).  The short flights of a
chatter (relative velocity ``w``) are composed into the jets before them inside the section formulas, so that
rounding grows like ``1 / w`` rather than ``1 / w^3``.

The derivatives are exact up to the integration error of the variational equations (relative tolerance
:data:`RTOL`), amplified as the orbit's own sensitivity amplifies it.

References
----------
Nordmark and Piiroinen (2009), "Simulation and stability analysis of impacting systems with complete
chattering", *Nonlinear Dynamics* 58 (the jump onto the sticking motion).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from saltation.engine.flow import EventKind, Trajectory
from saltation.errors import InconsistentResultError, ModelError
from saltation.model.system import TIME, PiecewiseSystem

_log = logging.getLogger(__name__)

#: Relative and absolute tolerances of the second variational equation (scipy's DOP853).
RTOL = 1e-12
ATOL = 1e-12
#: The largest difference, relative to ``1 + |x|``, between a segment's end state integrated here and the
#: event state the engine logged; and between the first derivative of the period map composed here and the
#: engine's monodromy, relative to ``1 + |M|``.  Both compute one thing twice at tight tolerances.
AGREEMENT = 1e-6
#: Newton iterations on a flow-to-section time that must be found (a perturbed orbit's Poincare return).
SECTION_ITERATIONS = 12


@dataclass(frozen=True, eq=False)
class MapDerivatives:
    """The first and second derivatives of a period map (unpacks and indexes as ``(first, second)``).

    Attributes
    ----------
    first : ndarray, shape (m, m)
        ``P_x``: the monodromy matrix (the derivative of the return map on a section, for a Poincare map).
    second : ndarray, shape (m, m, m)
        ``P_xx``, with ``second[i, j, k] = d^2 P_i / dx_j dx_k`` (symmetric in ``j, k``).
    first_error, second_error : float
        Where the orbit chatters to rest (complete chatter, :mod:`saltation.engine.chatter`): an estimate of the
        largest error of the entries of ``first`` and ``second`` that the engine's jump from its last impact kept,
        in place of the limit of the impacts, makes (:func:`chatter_errors`).  0 without complete chatter.  The
        integration error (:data:`RTOL`) comes on top.
    earlier : tuple of (float, ndarray, ndarray)
        For each complete chatter, the ratio ``r`` and the derivatives with its jump made one impact earlier
        (:attr:`RunJets.earlier`), in the same coordinates: what the errors are estimated from.
    """

    first: np.ndarray
    second: np.ndarray
    first_error: float = 0.0
    second_error: float = 0.0
    earlier: tuple = ()

    def __iter__(self):
        return iter((self.first, self.second))

    def __getitem__(self, index):
        return (self.first, self.second)[index]

    def __len__(self) -> int:
        return 2


class SectionMapDerivatives(NamedTuple):
    """The derivatives of an autonomous orbit's Poincare map in the coordinates of its section.

    The section is the hyperplane through the orbit's state ``x*`` normal to the flow there,
    ``n . (x - x*) = 0`` with ``n = f(x*) / |f(x*)|``; its points are ``x = x* + basis @ y``.

    Attributes
    ----------
    first : ndarray, shape (n - 1, n - 1)
        The return map's derivative in ``y``: its eigenvalues are the nontrivial Floquet multipliers.
    second : ndarray, shape (n - 1, n - 1, n - 1)
        Its second derivative in ``y``.
    basis : ndarray, shape (n, n - 1)
        Orthonormal columns spanning the section.
    normal : ndarray, shape (n,)
        The unit normal ``n``.
    first_error, second_error : float
        The estimated error from complete chatter, as :class:`MapDerivatives`'s (0 without).
    earlier : tuple of (float, ndarray, ndarray)
        As :class:`MapDerivatives`'s, in the section's coordinates.
    """

    first: np.ndarray
    second: np.ndarray
    basis: np.ndarray
    normal: np.ndarray
    first_error: float = 0.0
    second_error: float = 0.0
    earlier: tuple = ()


# ----------------------------------------------------------------------------------------------- the model
def _symbolic_model(system) -> PiecewiseSystem:
    """The model, if it is written with sympy expressions (a compiled-callable model has none to differentiate)."""
    if not isinstance(system, PiecewiseSystem):
        raise ModelError(f"second derivatives of the period map need a model written with sympy expressions "
                         f"(a PiecewiseSystem); {getattr(system, 'name', system)!r} is given as compiled callables")
    return system


def _arguments(system: PiecewiseSystem) -> list:
    return [TIME, *system.x, *system.p]


def _field_expression(system: PiecewiseSystem, key: tuple) -> sp.Matrix:
    """The vector field of a segment: a mode's (``("mode", m)``) or a sliding motion's (``("slide", a, b, s)``)."""
    if key[0] == "mode":
        return system.fields[key[1]]
    _, a, b, s = key
    sa, sb = system.lie_derivative(a, s), system.lie_derivative(b, s)
    alpha = sa / (sa - sb)
    return system.fields[a] + alpha * (system.fields[b] - system.fields[a])


@lru_cache(maxsize=256)
def _field_jets(system: PiecewiseSystem, key: tuple):
    """``(t, x..., p...) -> [F, F_z, F_zz]`` flattened, for the extended field ``F = (1, f)`` of a segment."""
    z = [TIME, *system.x]
    F = [sp.Integer(1), *_field_expression(system, key)]
    Fz = [[sp.diff(Fi, zj) for zj in z] for Fi in F]
    Fzz = [sp.diff(Fz[i][j], zk) for i in range(len(z)) for j in range(len(z)) for zk in z]
    flat = F + [e for row in Fz for e in row] + Fzz
    return sp.lambdify(_arguments(system), flat, modules="numpy", cse=True)


def _section_expression(system: PiecewiseSystem, key: tuple) -> sp.Expr:
    """The function whose zero ends a segment: a surface's indicator (``("surface", s)``) or the exit side's
    Lie derivative at the end of a sliding motion (``("exit", mode, s)``)."""
    if key[0] == "surface":
        return system.indicators[key[1]]
    _, mode, s = key
    return system.lie_derivative(mode, s)


@lru_cache(maxsize=256)
def _section_jets(system: PiecewiseSystem, key: tuple):
    """``(t, x..., p...) -> [H, H_z, H_zz]`` flattened."""
    z = [TIME, *system.x]
    H = _section_expression(system, key)
    Hz = [sp.diff(H, zj) for zj in z]
    Hzz = [sp.diff(Hz[j], zk) for j in range(len(z)) for zk in z]
    return sp.lambdify(_arguments(system), [H, *Hz, *Hzz], modules="numpy", cse=True)


@lru_cache(maxsize=256)
def _reset_jets(system: PiecewiseSystem, transition: int):
    """``(t, x..., p...) -> [R, R_z, R_zz]`` flattened, for the extended reset ``R(z) = (t, g(t, x))``."""
    z = [TIME, *system.x]
    R = [TIME, *system.resets[transition]]
    Rz = [[sp.diff(Ri, zj) for zj in z] for Ri in R]
    Rzz = [sp.diff(Rz[i][j], zk) for i in range(len(z)) for j in range(len(z)) for zk in z]
    return sp.lambdify(_arguments(system), R + [e for row in Rz for e in row] + Rzz, modules="numpy", cse=True)


def _values(function, z: np.ndarray, p: np.ndarray, shapes: tuple[tuple[int, ...], ...]) -> list[np.ndarray]:
    """A lambdified jet at ``z``, cut into arrays of the given shapes."""
    flat = np.asarray(function(*z, *p), dtype=float)
    out, at = [], 0
    for shape in shapes:
        size = math.prod(shape)
        out.append(flat[at:at + size].reshape(shape))
        at += size
    return out


def _field_at(system: PiecewiseSystem, key: tuple, z: np.ndarray, p: np.ndarray):
    N = len(z)
    return _values(_field_jets(system, key), z, p, ((N,), (N, N), (N, N, N)))


def _bilinear(T: np.ndarray, U: np.ndarray, V: np.ndarray) -> np.ndarray:
    """``T[U, V]``: ``out[i, j, k] = T[i, a, b] U[a, j] V[b, k]``."""
    return np.tensordot(np.tensordot(T, U, axes=([1], [0])), V, axes=([1], [0]))


def compose(outer: tuple[np.ndarray, np.ndarray], inner: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The 2-jet of ``outer o inner`` by the chain rule.

    Parameters
    ----------
    outer, inner : tuple of ndarray
        ``(A, B)`` each: first derivative, shape (m, l) and (l, k), and second derivative, shape (m, l, l)
        and (l, k, k).

    Returns
    -------
    tuple of ndarray
        ``(A_o A_i, A_o B_i + B_o[A_i, A_i])``.
    """
    A, B = outer
    J, K = inner
    return A @ J, np.tensordot(A, K, axes=([1], [0])) + _bilinear(B, J, J)


# ------------------------------------------------------------------------------------------------ segments
class _Jump(NamedTuple):
    """A complete chatter (:mod:`saltation.engine.chatter`), jumped from one of its impacts onto the stuck motion."""

    chatter: int  # which of the run's accumulations
    free: int  # the mode the impacts leave into
    stuck: int  # the stuck mode
    surface: int
    label: str


class _Segment(NamedTuple):
    """A stretch of the orbit between two events, and the event that ends it."""

    field: tuple  # ("mode", m) or ("slide", a, b, s)
    t_start: float
    t_end: float
    x_start: np.ndarray | None  # None: where the jump before it put the state
    x_end: np.ndarray  # the engine's state at the end (before the event)
    section: tuple  # ("surface", s), ("exit", mode, s) or ("time",)
    reset: int  # the transition whose reset follows, or -1
    label: str
    jump: _Jump | None = None  # a complete chatter jumped after the reset (the stuck segment follows)
    fork: _Jump | None = None  # the same chatter jumped one impact earlier, after this reset (its accuracy)
    join: int = -1  # the chatter whose stuck segment this is (where the earlier jump joins the orbit)


def chatter_impacts(traj: Trajectory) -> list[tuple[int, list[int]]]:
    """The complete chatters of a run: for each accumulation, the index of its event into the stuck mode and the
    indices of the impacts of its sequence the run kept (consecutive, ending just before that event).

    Parameters
    ----------
    traj : Trajectory
        A run (of a model with ``sticks=True`` impacts, :mod:`saltation.model.contacts`).

    Returns
    -------
    list of (int, list of int)
        One entry per :attr:`Trajectory.accumulations <saltation.engine.trajectory.Trajectory.accumulations>`,
        in their order (empty for a run without complete chatter).

    Raises
    ------
    InconsistentResultError
        If an accumulation has no event into its stuck mode, or no impact before it.
    """
    events = traj.events
    out = []
    for c, acc in enumerate(traj.accumulations):
        k = next((i for i, e in enumerate(events) if e.t == acc.t and e.mode_to == acc.mode
                  and e.kind == EventKind.TRANSITION), None)
        chain: list[int] = []
        i = -1 if k is None else k - 1
        while i >= 0 and events[i].kind == EventKind.TRANSITION and events[i].transition == acc.transition:
            chain.insert(0, i)
            i -= 1
        if k is None or not chain:
            raise InconsistentResultError(f"the complete chatter {c} of the run (impacts on {acc.surface!r} "
                                          f"accumulating at t = {acc.t:.12g}) has no "
                                          f"{'event into mode ' + repr(acc.mode) if k is None else 'impact'} "
                                          "in the event log")
        out.append((k, chain))
    return out


def _segments(traj: Trajectory, levels: dict[int, int] | None = None) -> list[_Segment]:
    """The orbit's segments between its logged events, with the section and reset ending each.

    A complete chatter (impacts jumped to their accumulation point, :mod:`saltation.engine.chatter`) is the
    impacts of its sequence up to the ``j``-th, the engine's jump from that impact onto the stuck motion (the
    plastic projection, :func:`_jump_jets`) and the stuck motion from that impact's time: the engine's own map
    (its monodromy is that map's derivative), whose distance from the chatter's limit shrinks with the relative
    velocity at the impact jumped from.  ``j`` is every impact kept by default (the engine's jump), or
    ``levels[c]`` for the ``c``-th chatter of the run; the jump from the impact before is marked too (``fork``),
    to estimate that distance.

    Parameters
    ----------
    traj : Trajectory
        One period (or any run) of a model written with sympy expressions.
    levels : dict of int to int, optional
        For a chatter of the run (its index in ``traj.accumulations``), how many impacts of its sequence are
        kept before the jump (at least 1, at most the run's).

    Returns
    -------
    list
        One record per segment: its field (a mode's or a sliding motion's), its start and end times and
        states, the section that ends it and the reset that follows (and a chatter's jump).

    Raises
    ------
    ModelError
        If the model is given as compiled callables, or a level is not one of a chatter's impacts.
    InconsistentResultError
        If the event log ends a sliding motion that never started, or has a chatter without its impacts.
    """
    system = _symbolic_model(traj.system)
    names = system.mode_names
    events = traj.events
    skip: set[int] = set()
    jumps: dict[int, _Jump] = {}
    forks: dict[int, _Jump] = {}
    for c, (k, chain) in enumerate(chatter_impacts(traj)):
        j = len(chain) if levels is None or c not in levels else int(levels[c])
        if not 1 <= j <= len(chain):
            raise ModelError(f"chatter {c} of the run kept {len(chain)} impacts: cannot jump from impact {j}")
        last = events[chain[j - 1]]
        jump = _Jump(c, names.index(last.mode_to), names.index(events[k].mode_to), system.surface_index(last.surface),
                     f"the complete chatter on {last.surface!r} into {events[k].mode_to!r} at t = {events[k].t:.10g}")
        skip.update(chain[j:])
        skip.add(k)
        jumps[chain[j - 1]] = jump
        if j >= 2:
            forks[chain[j - 2]] = jump
    field: tuple = ("mode", system.mode_index(traj.mode0))
    t, x = traj.t0, np.asarray(traj.x0, dtype=float)
    join = -1
    out = []
    for k, e in enumerate(events):
        if k in skip:
            continue
        s = system.surface_index(e.surface)
        if e.kind == EventKind.SLIDING_START:
            if field[0] == "slide" and field[3] == s:
                continue  # a shooting node inside a sliding motion (multiple shooting): no event of the orbit
            section, reset = ("surface", s), -1
            after = ("slide", names.index(e.mode_from), names.index(e.mode_to), s)
        elif e.kind == EventKind.SLIDING_END:
            if field[0] != "slide":
                raise InconsistentResultError(f"event {k} at t = {e.t:.12g} ends a sliding motion on {e.surface!r} "
                                              "that the event log never started")
            section, reset = ("exit", names.index(e.mode_to), field[3]), -1
            after = ("mode", names.index(e.mode_to))
        else:
            section = ("surface", s)
            reset = e.transition if system.resets[e.transition] is not None else -1
            after = ("mode", names.index(e.mode_to))
        label = f"event {k} ({e.kind.name.lower()} {e.mode_from} -> {e.mode_to} on {e.surface!r} at t = {e.t:.10g})"
        out.append(_Segment(field, t, float(e.t), x, np.asarray(e.x_minus, dtype=float), section, reset, label,
                            jumps.get(k), forks.get(k), join))
        field, t, x, join = after, float(e.t), np.asarray(e.x_plus, dtype=float), -1
        if k in jumps:
            field, x, join = ("mode", jumps[k].stuck), None, jumps[k].chatter
    out.append(_Segment(field, t, float(traj.t1), x, np.asarray(traj.x1, dtype=float), ("time",), -1,
                        f"the end of the run at t = {traj.t1:.10g}", None, None, join))
    return out


def _field_name(system: PiecewiseSystem, key: tuple) -> str:
    if key[0] == "mode":
        return f"mode {system.mode_names[key[1]]!r}"
    return (f"the sliding motion on {system.surface_names[key[3]]!r} "
            f"({system.mode_names[key[1]]}|{system.mode_names[key[2]]})")


def _flow(system: PiecewiseSystem, key: tuple, z0: np.ndarray, duration: float, p: np.ndarray,
          rtol: float, atol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The flow of a segment's field for ``duration`` from ``z0``: the end state and the first and second
    variational matrices ``Phi`` (N, N) and ``Psi`` (N, N, N)."""
    N = len(z0)
    if duration == 0.0:
        return z0.copy(), np.eye(N), np.zeros((N, N, N))
    function = _field_jets(system, key)
    N2 = N * N

    def rhs(_t, y):
        flat = np.asarray(function(*y[:N], *p), dtype=float)
        Fz = flat[N:N + N2].reshape(N, N)
        Fzz = flat[N + N2:].reshape(N, N, N)
        Phi = y[N:N + N2].reshape(N, N)
        Psi = y[N + N2:].reshape(N, N, N)
        dPsi = np.tensordot(Fz, Psi, axes=([1], [0])) + _bilinear(Fzz, Phi, Phi)
        return np.concatenate([flat[:N], (Fz @ Phi).ravel(), dPsi.ravel()])

    y0 = np.concatenate([z0, np.eye(N).ravel(), np.zeros(N * N2)])
    sol = solve_ivp(rhs, (float(z0[0]), float(z0[0]) + duration), y0, method="DOP853", rtol=rtol, atol=atol)
    if sol.status != 0 or not np.all(np.isfinite(sol.y[:, -1])):
        raise InconsistentResultError(f"the second variational equation of {_field_name(system, key)} could not be "
                                      f"integrated from t = {z0[0]:.10g} for {duration:.6g}: {sol.message}")
    y = sol.y[:, -1]
    return y[:N], y[N:N + N2].reshape(N, N), y[N + N2:].reshape(N, N, N)


def _section_values(system: PiecewiseSystem, section: tuple, z: np.ndarray, p: np.ndarray):
    """``H, H_z, H_zz`` of a section at ``z`` (``("time", t1)``, ``("plane", normal, point)`` or a model's)."""
    N = len(z)
    if section[0] == "time":
        return z[0] - section[1], np.eye(N)[0], np.zeros((N, N))
    if section[0] == "plane":
        normal, point = section[1], section[2]
        return float(normal @ (z[1:] - point)), np.concatenate([[0.0], normal]), np.zeros((N, N))
    H, Hz, Hzz = _values(_section_jets(system, section), z, p, ((1,), (N,), (N, N)))
    return float(H[0]), Hz, Hzz


class _Arrival(NamedTuple):
    """A segment's flow at its section: what the 2-jet of the flow-to-section map is made of (:func:`_section_jets_of`)."""

    z: np.ndarray
    Phi: np.ndarray
    Psi: np.ndarray
    F: np.ndarray
    FzF: np.ndarray
    Fz: np.ndarray
    Hz: np.ndarray
    Hzz: np.ndarray
    speed: float


def _section_jets_of(arrival: _Arrival, inner: tuple[np.ndarray, np.ndarray] | None = None):
    """The 2-jet of the flow-to-section map composed with an inner map, ``G o inner``.

    The inner jets ``(Z1, Z2)`` go into the flow's first: ``Phi Z1`` and ``Psi[Z1, Z1] + Phi Z2``, then the event
    time's derivatives.  Mathematically the chain rule on ``(G_z, G_zz)``; numerically better where the flight is
    short (the impacts of a chatter): ``G_z`` and ``G_zz`` have entries of order ``1 / (H_z F)`` and its square and
    cube across the section, which the inner map's columns (along it, in exact arithmetic) only cancel to the
    rounding of those entries, while ``H_z Phi Z1`` is small to start with.
    """
    a = arrival
    N = len(a.z)
    Z1, Z2 = (np.eye(N), None) if inner is None else inner
    Phi = a.Phi @ Z1
    Psi = _bilinear(a.Psi, Z1, Z1)
    if Z2 is not None:
        Psi = Psi + np.tensordot(a.Phi, Z2, axes=([1], [0]))
    tau_z = -(a.Hz @ Phi) / a.speed
    Gz = Phi + np.outer(a.F, tau_z)
    FzPhi = a.Fz @ Phi
    Ghat = (Psi + np.einsum("i,j,k->ijk", a.FzF, tau_z, tau_z) + np.einsum("ij,k->ijk", FzPhi, tau_z)
            + np.einsum("ik,j->ijk", FzPhi, tau_z))
    tau_zz = -(np.tensordot(a.Hz, Ghat, axes=([0], [0])) + Gz.T @ a.Hzz @ Gz) / a.speed
    Gzz = Ghat + np.einsum("i,jk->ijk", a.F, tau_zz)
    return Gz, Gzz


def _to_section(system: PiecewiseSystem, key: tuple, section: tuple, z0: np.ndarray, duration: float,
                p: np.ndarray, rtol: float, atol: float, what: str, *, search: bool = False):
    """Flow from ``z0`` with a segment's field to its section: the state there and the 2-jet ``(G_z, G_zz)``
    of the flow-to-section map ``z -> psi(tau(z), z)``.

    ``duration`` is the flow time to the section (the logged one).  The state reached is put on the section
    by one Newton correction of the time, applied to the state and the variational matrices to first order;
    a correction larger than the agreement the logged time promises raises, unless ``search`` is set (a
    Poincare return time not known beforehand), which then integrates again to the corrected time.
    """
    arrival, duration = _arrive(system, key, section, z0, duration, p, rtol, atol, what, search=search)
    return arrival.z, duration, _section_jets_of(arrival)


def _arrive(system: PiecewiseSystem, key: tuple, section: tuple, z0: np.ndarray, duration: float,
            p: np.ndarray, rtol: float, atol: float, what: str, *, search: bool = False) -> tuple[_Arrival, float]:
    """:func:`_to_section`'s flow to the section, with what the jets are made of (the flow time too)."""
    z, Phi, Psi = _flow(system, key, z0, duration, p, rtol, atol)
    for _ in range(SECTION_ITERATIONS):
        F, Fz, Fzz = _field_at(system, key, z, p)
        H, Hz, _ = _section_values(system, section, z, p)
        speed = float(Hz @ F)
        if speed == 0.0 or not math.isfinite(speed):
            raise InconsistentResultError(f"{what}: {_field_name(system, key)} is tangent to the section there "
                                          "(the event is not transversal: the period map is not differentiable)")
        delta = -H / speed
        small = abs(delta) <= 1e-7 * (1.0 + abs(duration))
        if small or not search:
            if not small and abs(delta) > AGREEMENT * (1.0 + abs(duration)):
                raise InconsistentResultError(f"{what}: the segment integrated from the logged state reaches its "
                                              f"section {delta:.3g} away in time from the logged event")
            # the remaining correction, to first order (it is of the order of the integration error)
            z = z + delta * F
            Psi = Psi + delta * (np.tensordot(Fz, Psi, axes=([1], [0])) + _bilinear(Fzz, Phi, Phi))
            Phi = Phi + delta * (Fz @ Phi)
            break
        duration += delta
        z, Phi, Psi = _flow(system, key, z0, duration, p, rtol, atol)
    else:
        raise InconsistentResultError(f"{what}: the flow does not settle on its section within "
                                      f"{SECTION_ITERATIONS} Newton steps of the return time")
    F, Fz, _ = _field_at(system, key, z, p)
    _, Hz, Hzz = _section_values(system, section, z, p)
    return _Arrival(z, Phi, Psi, F, Fz @ F, Fz, Hz, Hzz, float(Hz @ F)), duration


def _reset_at(system: PiecewiseSystem, transition: int, z: np.ndarray, p: np.ndarray):
    N = len(z)
    R, Rz, Rzz = _values(_reset_jets(system, transition), z, p, ((N,), (N, N), (N, N, N)))
    return R, (Rz, Rzz)


@lru_cache(maxsize=64)
def _direction_jets(system: PiecewiseSystem, free: int, stuck: int):
    """``(t, x..., p...) -> [B, B_z, B_zz]`` flattened, ``B = [b, f_x b]`` (n, 2): the contact direction of a stuck
    mode and the displacement an impulse along it makes under the free mode's field, the directions the engine's
    plastic projection moves along (:mod:`saltation.engine.chatter`; any multiple of ``b`` spans the same)."""
    z = [TIME, *system.x]
    b = sp.Matrix(system.sticking[system.mode_names[stuck]].direction)
    c = system.jacobian(free) * b
    B = [[b[i], c[i]] for i in range(system.n)]
    Bz = [sp.diff(B[i][a], zj) for i in range(system.n) for a in range(2) for zj in z]
    Bzz = [sp.diff(B[i][a], zj, zk) for i in range(system.n) for a in range(2) for zj in z for zk in z]
    return sp.lambdify(_arguments(system), [e for row in B for e in row] + Bz + Bzz, modules="numpy", cse=True)


def _jump_jets(system: PiecewiseSystem, jump: _Jump, z: np.ndarray, p: np.ndarray):
    """The engine's jump of a complete chatter from an impact at ``z = (t, x)`` (just after its reset): the state
    moved along ``B = [b, f_x b]`` onto ``h = 0, Lh = 0`` at the same time, and the 2-jet of that map.

    With ``Y(c, z) = (t, x + B(t, x) c)`` and ``c(z)`` the solution of ``G(Y) = (h, Lh)(Y) = 0``, the implicit
    function theorem gives ``c_z = -(G_Y B)^-1 G_Y Y_z`` and, differentiating ``G(Y(c(z), z)) = 0`` twice,
    ``c_zz = -(G_Y B)^-1 (G_Y W + G_YY[Y', Y'])`` with ``Y' = B c_z + Y_z`` and ``W = Y_zz + Y_cz c_z``
    (symmetrized); the map's second derivative is ``B c_zz + W``.
    """
    N = len(z)
    n = N - 1
    Bfun = _direction_jets(system, jump.free, jump.stuck)

    def directions(at: np.ndarray):
        return _values(Bfun, at, p, ((n, 2), (n, 2, N), (n, 2, N, N)))

    def constraint(at: np.ndarray):
        h, hz, hzz = _section_values(system, ("surface", jump.surface), at, p)
        L, Lz, Lzz = _section_values(system, ("exit", jump.free, jump.surface), at, p)
        return np.array([h, L]), np.vstack([hz, Lz]), np.stack([hzz, Lzz])

    B, Bz, Bzz = directions(z)
    Bext, Bzext, Bzzext = (np.concatenate([np.zeros((1,) + a.shape[1:]), a]) for a in (B, Bz, Bzz))
    c = np.zeros(2)
    scale = 1.0 + float(np.max(np.abs(z[1:])))
    for _ in range(SECTION_ITERATIONS):
        Y = z + Bext @ c
        r, GY, _ = constraint(Y)
        if np.max(np.abs(r)) <= 4.0 * np.finfo(float).eps * scale:
            break
        c = c - np.linalg.solve(GY @ Bext, r)
    Y = z + Bext @ c
    r, GY, GYY = constraint(Y)
    GB = GY @ Bext
    if not np.max(np.abs(r)) <= 1e-12 * scale or not np.linalg.cond(GB) < 1e12:
        raise InconsistentResultError(f"{jump.label}: the jump from the impact at t = {z[0]:.10g} does not reach the "
                                      f"stuck motion (|h, Lh| = {np.max(np.abs(r)):.3g} after Newton)")
    Yz = np.eye(N) + np.einsum("iaj,a->ij", Bzext, c)
    cz = -np.linalg.solve(GB, GY @ Yz)
    first = Bext @ cz + Yz
    W = np.einsum("iajk,a->ijk", Bzzext, c) + np.einsum("iaj,ak->ijk", Bzext, cz) + np.einsum("iak,aj->ijk", Bzext, cz)
    czz = -np.linalg.solve(GB, (np.tensordot(GY, W, axes=([1], [0])) + _bilinear(GYY, first, first)).reshape(2, -1))
    second = np.tensordot(Bext, czz.reshape(2, N, N), axes=([1], [0])) + W
    return Y, (first, second)


def _state_check(x: np.ndarray, expected: np.ndarray, what: str) -> None:
    gap = float(np.max(np.abs(x - expected)))
    if not gap <= AGREEMENT * (1.0 + float(np.max(np.abs(expected)))):
        raise InconsistentResultError(f"{what}: the segment integrated from the logged state ends {gap:.3g} away from "
                                      "the state the engine logged there")


class RunJets(NamedTuple):
    """The 2-jet in ``z = (t, x)`` of the map from the start of a run to its end section (:func:`run_jets`).

    Attributes
    ----------
    first : ndarray, shape (n + 1, n + 1)
        First derivative in ``z``.
    second : ndarray, shape (n + 1, n + 1, n + 1)
        Second derivative in ``z``.
    end : ndarray, shape (n + 1,)
        Where the map ends (time and state).
    last_field : tuple
        The field of the last segment.
    impacts : tuple of int
        For each complete chatter of the run, the impacts of its sequence kept before its jump.
    earlier : tuple of (float, ndarray, ndarray)
        For each complete chatter, the same map with the jump made one impact earlier: the ratio ``r`` of the
        relative velocities across the impact jumped from (``-w+ / w-``, the rate at which the chatter's
        distance from its limit shrinks from one impact to the next) and the first and second derivatives.
        The jets' distance from those of the chatter's limit is at most about ``r / (1 - r)`` times their
        distance from these (:func:`chatter_errors`; ``nan`` where a chatter kept a single impact).
    """

    first: np.ndarray
    second: np.ndarray
    end: np.ndarray
    last_field: tuple
    impacts: tuple[int, ...] = ()
    earlier: tuple = ()


def run_jets(traj: Trajectory, p: np.ndarray, *, rtol: float = RTOL, atol: float = ATOL,
             section: tuple | None = None, levels: dict[int, int] | None = None) -> RunJets:
    """The 2-jet in ``z = (t, x)`` of the map from the start of a run to its end section, through its events and
    complete chatters.

    A complete chatter (:mod:`saltation.engine.chatter`) is differentiated as the engine maps it: the impacts
    kept, the plastic projection from the last of them onto the stuck motion (``h = 0``, ``Lh = 0``, along the
    contact direction ``b`` and ``f_x b``, whose 2-jet is exact by the implicit function theorem) and the stuck
    motion from that impact's time.  Its first derivative is the engine's monodromy through the chatter; both
    differ from the derivatives of the chatter's limit by an amount that shrinks with the relative velocity at the
    impact jumped from (geometrically, by the restitution, from one impact to the next).  That amount is estimated
    from the same map with the jump made one impact earlier (:attr:`RunJets.earlier`).

    Parameters
    ----------
    traj : Trajectory
        The run, with its event log (a model written with sympy expressions).
    p : ndarray
        The parameter values of the run.
    rtol, atol : float
        Tolerances of the second variational equation.
    section : tuple, optional
        Where the map ends after the run's end: ``("plane", normal, point)``, the hyperplane
        ``normal . (x - point) = 0`` reached by the last segment's flow (a Poincare section); by default the
        run's end time ``t1``.
    levels : dict of int to int, optional
        For a chatter of the run (its index in ``traj.accumulations``), how many impacts of its sequence to keep
        before the jump (by default all the run kept): runs from nearby states that kept different numbers are
        differentiated as the same map this way.

    Returns
    -------
    RunJets
        The jets, where they end, and the chatters' accuracy.

    Raises
    ------
    ModelError
        If the model is given as compiled callables, or a level is not one of a chatter's impacts.
    InconsistentResultError
        If a segment integrated here does not end at the engine's logged state, an event is not transversal, or a
        chatter's jump does not reach the stuck motion.

    References
    ----------
    Nordmark and Piiroinen (2009), "Simulation and stability analysis of impacting systems with complete
    chattering", *Nonlinear Dynamics* 58 (the jump onto the sticking motion and its Jacobian).
    """
    system = _symbolic_model(traj.system)
    p = np.asarray(p, dtype=float)
    N = system.n + 1
    J, K = np.eye(N), np.zeros((N, N, N))
    z = None
    segments = _segments(traj, levels)
    joins = {seg.join: seg for seg in segments if seg.join >= 0}
    pending: dict[int, tuple] = {}  # chatter -> (ratio, jets of the earlier jump up to its stuck segment's end)
    earlier: dict[int, list] = {}  # chatter -> [ratio, J, K] of the earlier jump, carried along from its join

    def apply(jet):
        nonlocal J, K
        J, K = compose(jet, (J, K))
        for alt in earlier.values():
            alt[1], alt[2] = compose(jet, (alt[1], alt[2]))

    def arrive(arrival: _Arrival):
        nonlocal J, K
        J, K = _section_jets_of(arrival, (J, K))
        for alt in earlier.values():
            alt[1], alt[2] = _section_jets_of(arrival, (alt[1], alt[2]))

    for seg in segments:
        z0 = z.copy() if seg.x_start is None else np.concatenate([[seg.t_start], seg.x_start])
        end = ("time", seg.t_end) if seg.section[0] == "time" else seg.section
        # (a stuck motion from a chatter jumped earlier than the engine did ends where its state takes it)
        arrival, _ = _arrive(system, seg.field, end, z0, seg.t_end - seg.t_start, p, rtol, atol, seg.label,
                             search=seg.join >= 0)
        z = arrival.z
        _state_check(z[1:], seg.x_end, seg.label)
        arrive(arrival)
        if seg.join in pending:
            # the chatter's jets with the earlier jump have reached the end of its stuck segment: they go on from here
            earlier[seg.join] = list(pending.pop(seg.join))
        z_before = z
        if seg.reset >= 0:
            z, jet = _reset_at(system, seg.reset, z, p)
            apply(jet)
        if seg.fork is not None:
            # the chatter jumped from this impact instead: onto the stuck motion, to the end of its stuck segment
            fork, target = seg.fork, joins[seg.fork.chatter]
            w_minus = _section_values(system, ("exit", fork.free, fork.surface), z_before, p)[0]
            w_plus = _section_values(system, ("exit", fork.free, fork.surface), z, p)[0]
            ratio = abs(w_plus / w_minus) if w_minus != 0.0 else math.nan
            z_fork, jet_fork = _jump_jets(system, fork, z, p)
            t_end = ("time", target.t_end) if target.section[0] == "time" else target.section
            stuck, _ = _arrive(system, ("mode", fork.stuck), t_end, z_fork, target.t_end - z_fork[0], p, rtol, atol,
                               f"{fork.label}, jumped one impact earlier", search=True)
            pending[fork.chatter] = (ratio, *_section_jets_of(stuck, compose(jet_fork, (J, K))))
        if seg.jump is not None:
            z, jet = _jump_jets(system, seg.jump, z, p)
            apply(jet)
    last = segments[-1].field
    if section is not None:
        arrival, _ = _arrive(system, last, section, z, 0.0, p, rtol, atol, "the return to the Poincare section",
                             search=True)
        z = arrival.z
        arrive(arrival)
    chatters = chatter_impacts(traj)
    kept = tuple(len(chain) if levels is None or c not in levels else int(levels[c])
                 for c, (_, chain) in enumerate(chatters))
    nowhere = (math.nan, np.full_like(J, math.nan), np.full_like(K, math.nan))  # a chatter that kept one impact
    alternatives = tuple(tuple(earlier[c]) if c in earlier else nowhere for c in range(len(chatters)))
    _log.debug("second-order jets of %s through %d segments", system.name, len(segments))
    return RunJets(J, K, z, last, kept, alternatives)


def extended_jets(traj: Trajectory, p: np.ndarray, *, rtol: float = RTOL, atol: float = ATOL,
                  section: tuple | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple]:
    """The 2-jet in ``z = (t, x)`` of the map from the start of a run to its end section.

    Parameters
    ----------
    traj : Trajectory
        The run, with its event log (a model written with sympy expressions).
    p : ndarray
        The parameter values of the run.
    rtol, atol : float
        Tolerances of the second variational equation.
    section : tuple, optional
        Where the map ends after the run's end: ``("plane", normal, point)``, the hyperplane
        ``normal . (x - point) = 0`` reached by the last segment's flow (a Poincare section); by default the
        run's end time ``t1``.

    Returns
    -------
    J : ndarray, shape (n + 1, n + 1)
        First derivative in ``z``.
    K : ndarray, shape (n + 1, n + 1, n + 1)
        Second derivative in ``z``.
    z_end : ndarray, shape (n + 1,)
        Where the map ends (time and state).
    last_field : tuple
        The field of the last segment.

    Raises
    ------
    ModelError
        If the model is given as compiled callables.
    InconsistentResultError
        If a segment integrated here does not end at the engine's logged state, or an event is not transversal.

    Notes
    -----
    Through a complete chatter these are the jets of the engine's jump, known to the accuracy
    :func:`run_jets` estimates (which this function leaves out).
    """
    jets = run_jets(traj, p, rtol=rtol, atol=atol, section=section)
    return jets.first, jets.second, jets.end, jets.last_field


def _orbit_parts(orbit) -> tuple[Trajectory, np.ndarray]:
    traj = getattr(orbit, "trajectory", None)
    if traj is None or getattr(orbit, "parameters", None) is None:
        raise ModelError(f"expected a PeriodicOrbit (with its trajectory and parameters), got {type(orbit).__name__}")
    _symbolic_model(traj.system)
    return traj, np.asarray(orbit.parameters, dtype=float)


def _check_first_derivative(first: np.ndarray, monodromy: np.ndarray | None, what: str,
                            allowance: float = 0.0) -> float:
    """The first derivative composed here against the engine's monodromy (eq. 9's saltation matrices).

    Parameters
    ----------
    first : ndarray, shape (n, n)
        The first-order part of the composed jets.
    monodromy : ndarray or None
        The engine's monodromy of the same run (None: nothing to check).
    what : str
        What the map is, for the message.
    allowance : float
        A difference the two may have besides (absolute): twice the estimated error of a complete chatter jumped
        from an earlier impact than the engine's.

    Returns
    -------
    float
        The largest difference, relative to ``1 + max |M|``.

    Raises
    ------
    InconsistentResultError
        If they differ by more than :data:`AGREEMENT` (and the allowance).
    """
    if monodromy is None:
        return float("nan")
    scale = 1.0 + float(np.max(np.abs(monodromy)))
    gap = float(np.max(np.abs(first - monodromy))) / scale
    if not gap <= AGREEMENT + allowance / scale:
        raise InconsistentResultError(f"{what}: the first derivative composed through the events differs from the "
                                      f"engine's monodromy by {gap:.3g} (relative): the orbit's events and the model "
                                      "disagree")
    return gap


def period_map_derivatives(orbit, *, rtol: float = RTOL, atol: float = ATOL) -> MapDerivatives:
    """The first and second derivatives of a periodic orbit's period map, exact through its events.

    The map is ``P(x0) = x(t0 + T; t0, x0)`` over the orbit's trajectory (in its direction of integration):
    a forced orbit's stroboscopic map, an autonomous orbit's time-``T`` map.  Its first derivative is the
    monodromy matrix (checked against the engine's, which carries the saltation matrices of eq. 9); the
    second derivative composes the second variational equation of each segment with the second derivatives
    of the event times, of the resets and of the surfaces (see the module's description).  Where the orbit's
    state lies on an event (a surface crossed, or a sliding motion started, at ``t0``), the map is not smooth
    there: its derivatives are those of the side the run takes, as the monodromy's are.

    Parameters
    ----------
    orbit : PeriodicOrbit
        A periodic orbit of a model written with sympy expressions.
    rtol, atol : float
        Tolerances of the second variational equation (scipy's DOP853).

    Returns
    -------
    MapDerivatives
        ``(first, second)``: ``P_x``, shape (n, n), and ``P_xx``, shape (n, n, n).  Exact up to the
        integration error at these tolerances, amplified as the orbit amplifies perturbations.

    Raises
    ------
    ModelError
        If the orbit's model is given as compiled callables, or ``orbit`` is not a periodic orbit.
    InconsistentResultError
        If the first derivative differs from the engine's monodromy by more than :data:`AGREEMENT`, a
        segment does not end at the logged event state, or an event is tangent to its surface.

    References
    ----------
    Leine and Van Campen, "Fold bifurcations in discontinuous systems", eq. (9) (the first-order jumps).
    Hiskens and Pai (2000), "Trajectory sensitivity analysis of hybrid systems", IEEE Trans. Circuits
    Syst. I 47 (the event-time derivatives through implicit functions).
    """
    traj, p = _orbit_parts(orbit)
    return run_map_derivatives(traj, p, traj.monodromy, rtol=rtol, atol=atol)


def run_map_derivatives(traj: Trajectory, p: np.ndarray, monodromy: np.ndarray | None, *, rtol: float = RTOL,
                        atol: float = ATOL, levels: dict[int, int] | None = None) -> MapDerivatives:
    """:func:`period_map_derivatives` of one run (the orbit's, or one from a perturbed state): the derivatives of
    its state at its end time by its state at its start time.

    Parameters
    ----------
    traj : Trajectory
        The run.
    p : ndarray
        Its parameters.
    monodromy : ndarray or None
        The engine's monodromy of the run, to check the first derivative against (None: no check).
    rtol, atol : float
        Tolerances of the second variational equation.
    levels : dict of int to int, optional
        The impacts of each complete chatter kept before its jump (:func:`run_jets`).

    Returns
    -------
    MapDerivatives
        As :func:`period_map_derivatives`.

    Raises
    ------
    ModelError
        If the model is given as compiled callables.
    InconsistentResultError
        As :func:`period_map_derivatives`.
    """
    jets = run_jets(traj, p, rtol=rtol, atol=atol, levels=levels)
    first, second = _state_blocks(jets.first, jets.second)
    earlier = tuple((r, *_state_blocks(Ja, Ka)) for r, Ja, Ka in jets.earlier)
    first_error, second_error = chatter_errors(first, second, earlier)
    _check_first_derivative(first, monodromy, f"the period map of {traj.system.name!r}", 2.0 * first_error)
    return MapDerivatives(first.copy(), second.copy(), first_error, second_error, earlier)


def _state_blocks(J: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The state blocks of jets in ``z = (t, x)``: the map at a fixed start time, its state at the end."""
    return J[1:, 1:], K[1:, 1:, 1:]


def chatter_errors(first: np.ndarray, second: np.ndarray, earlier: tuple) -> tuple[float, float]:
    """The estimated error of a map's first and second derivatives that its complete chatters make.

    A chatter's jump from the impact before the one the derivatives jump from (:attr:`RunJets.earlier`) gives
    derivatives that differ from these; the distance of these from the chatter's limit is at most about that
    difference times ``r / (1 - r)``, ``r`` the ratio of the relative velocities across the impact (the jump's
    distance from the limit shrinks geometrically, by at least ``r`` from one impact to the next: by ``r^3`` on
    the ball on a sprung table of ``tests/orbits/test_second_order_chatter.py``).

    Parameters
    ----------
    first, second : ndarray
        The map's first and second derivatives.
    earlier : tuple of (float, ndarray, ndarray)
        For each chatter, ``r`` and the derivatives with the earlier jump, in the same coordinates.

    Returns
    -------
    tuple of float
        The estimates for the entries of the first and the second derivative, summed over the chatters (0
        without; infinite where a chatter kept a single impact or ``r`` is not below 1).
    """
    first_error = second_error = 0.0
    for r, Aa, Ba in earlier:
        factor = r / (1.0 - r) if 0.0 <= r < 1.0 else math.inf
        if not (math.isfinite(factor) and np.all(np.isfinite(Aa)) and np.all(np.isfinite(Ba))):
            return math.inf, math.inf
        first_error += factor * float(np.max(np.abs(Aa - first)))
        second_error += factor * float(np.max(np.abs(Ba - second)))
    return first_error, second_error


def section_basis(normal: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the hyperplane normal to ``normal``.

    Parameters
    ----------
    normal : ndarray, shape (n,)
        A nonzero vector.

    Returns
    -------
    ndarray, shape (n, n - 1)
        Orthonormal columns, each orthogonal to ``normal``.

    Raises
    ------
    ModelError
        If ``normal`` is zero or not finite.
    """
    normal = np.asarray(normal, dtype=float)
    size = float(np.linalg.norm(normal))
    if not (size > 0.0 and math.isfinite(size)):
        raise ModelError(f"a section needs a nonzero finite normal, got {normal}")
    u, _, _ = np.linalg.svd((normal / size)[:, None], full_matrices=True)
    return u[:, 1:]


def poincare_map_derivatives(orbit, *, rtol: float = RTOL, atol: float = ATOL) -> SectionMapDerivatives:
    """The first and second derivatives of an autonomous orbit's Poincare map, in its section's coordinates.

    The section is the hyperplane through the orbit's state normal to its velocity there; the map is the
    time-``T`` map followed by the flow back (or on) to the section, whose 2-jet composes with the rest
    like the flow to any event (see the module's description).

    Parameters
    ----------
    orbit : PeriodicOrbit
        An autonomous periodic orbit of a model written with sympy expressions, whose state is not at an
        event.
    rtol, atol : float
        Tolerances of the second variational equation.

    Returns
    -------
    SectionMapDerivatives
        The derivatives in the section's coordinates, its basis and normal.

    Raises
    ------
    ModelError
        If the orbit is forced, or its model is given as compiled callables.
    InconsistentResultError
        As :func:`period_map_derivatives`, or if the map does not return to its section.
    """
    traj, p = _orbit_parts(orbit)
    if not getattr(orbit, "autonomous", False):
        raise ModelError("a Poincare map belongs to an autonomous orbit; a forced orbit's period map is "
                         "period_map_derivatives(orbit)")
    return section_map_derivatives(traj, p, traj.monodromy, rtol=rtol, atol=atol)


def section_map_derivatives(traj: Trajectory, p: np.ndarray, monodromy: np.ndarray | None, *,
                            rtol: float = RTOL, atol: float = ATOL, normal: np.ndarray | None = None,
                            point: np.ndarray | None = None,
                            levels: dict[int, int] | None = None) -> SectionMapDerivatives:
    """:func:`poincare_map_derivatives` of one run from a state on the section (the orbit's or a perturbed one).

    Parameters
    ----------
    traj : Trajectory
        A run over (about) one period from a state on the section.
    p : ndarray
        Its parameters.
    monodromy : ndarray or None
        The engine's monodromy of the run, to check the first derivative against (None: no check).
    rtol, atol : float
        Tolerances of the second variational equation.
    normal, point : ndarray, optional
        The section ``normal . (x - point) = 0``; by default through the run's initial state, normal to the
        field of its first segment there.
    levels : dict of int to int, optional
        The impacts of each complete chatter kept before its jump (:func:`run_jets`).

    Returns
    -------
    SectionMapDerivatives
        As :func:`poincare_map_derivatives`.

    Raises
    ------
    ModelError
        If the model is given as compiled callables, or the field vanishes at the state.
    InconsistentResultError
        As :func:`period_map_derivatives`.
    """
    system = _symbolic_model(traj.system)
    p = np.asarray(p, dtype=float)
    if point is None:
        point = np.asarray(traj.x0, dtype=float)
    if normal is None:
        key = _segments(traj)[0].field
        F = _field_at(system, key, np.concatenate([[traj.t0], point]), p)[0][1:]
        size = float(np.linalg.norm(F))
        if not size > 0.0:
            raise ModelError(f"the field of {_field_name(system, key)} vanishes at the orbit's state: no section")
        normal = F / size
    jets = run_jets(traj, p, rtol=rtol, atol=atol, section=("plane", normal, point), levels=levels)
    Q = section_basis(normal)

    def in_section(J: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return Q.T @ J[1:, 1:] @ Q, np.einsum("ai,ajk,jb,kc->ibc", Q, K[1:, 1:, 1:], Q, Q)

    if monodromy is not None:
        # the time-T map's derivative projected along the flow onto the section
        F_end = _field_at(system, _segments(traj)[-1].field, np.concatenate([[traj.t1], traj.x1]), p)[0][1:]
        projected = monodromy - np.outer(F_end, normal @ monodromy) / float(normal @ F_end)
        fixed = jets.first[1:, 1:]
        allowance = chatter_errors(fixed, fixed, tuple((r, Ja[1:, 1:], Ja[1:, 1:]) for r, Ja, _ in jets.earlier))[0]
        _check_first_derivative(fixed, projected, f"the Poincare map of {system.name!r}", 2.0 * allowance)
    first, second = in_section(jets.first, jets.second)
    earlier = tuple((r, *in_section(Ja, Ka)) for r, Ja, Ka in jets.earlier)
    return SectionMapDerivatives(first, second, Q, normal, *chatter_errors(first, second, earlier), earlier)


__all__ = ["AGREEMENT", "ATOL", "RTOL", "MapDerivatives", "RunJets", "SectionMapDerivatives", "chatter_errors",
           "chatter_impacts", "compose", "extended_jets", "period_map_derivatives", "poincare_map_derivatives",
           "run_jets", "run_map_derivatives", "section_basis", "section_map_derivatives"]
