"""Independent reference for the Jeffcott rotor with a snubber ring.

Nothing here imports saltation: only numpy and scipy.  The model is the one of
``/work/shared/trial-models/jeffcott_snubber.py`` (states ``(x, y, vx, vy)``, in that order)::

    x'' + 2 zeta x' + x + beta H(r - delta) (1 - delta/r) (x - mu y) = rho omega^2 cos(omega t)
    y'' + 2 zeta y' + y + beta H(r - delta) (1 - delta/r) (mu x + y) = rho omega^2 sin(omega t) - g

with ``r = sqrt(x^2 + y^2)`` and forcing period ``T = 2 pi / omega``.  In the complex coordinate
``z = x + i y`` it reads ``z'' + 2 zeta z' + z + beta H(r - delta) (1 - delta/r) (1 + i mu) z =
rho omega^2 exp(i omega t) - i g``.  The contact force vanishes on the clearance circle, so the
field is continuous there (its Jacobian jumps): every saltation matrix is the identity and the
monodromy matrix is the plain solution of the variational equation along the orbit.

How.

* :func:`period_map` integrates the state and the variational equation with ``solve_ivp``
  (DOP853, ``rtol = 1e-12``, ``atol = 1e-13``), one mode at a time: the integration stops at
  every crossing of ``r = delta`` (a terminal event on ``r^2 - delta^2``, rising in free flight,
  falling in contact) and restarts in the other mode, so that the kink of the field is never
  inside a step.  The crossing time found on the dense output is polished by Newton on the
  integrated state, and the first step after a restart is 1e-5.  A contact arc (or a lift-off)
  short enough to fit inside one step would not change the sign of the event function at the
  step ends; the extrema of ``r`` are therefore recorded too (non-terminal events on
  ``x vx + y vy``), and an extremum beyond the circle has its first crossing located on the
  dense output and the integration restarted there.  :func:`monodromy_fd` is the central
  finite-difference derivative of the same map.
* :func:`periodic_orbit`: damped Newton on ``P(x) - x`` with the variational monodromy.
* Closed forms: the free whirl ``z = A exp(i (omega t - phi)) - i g``, ``A exp(-i phi) = rho
  omega^2 / (1 - omega^2 + 2 i zeta omega)``, its first contact with the ring (``A(omega) + g =
  delta``, a quadratic in ``omega^2``), and, for ``g = 0``, the contact whirl ``z = R exp(i
  (omega t - phi))`` with ``R > delta``.  In the frame rotating with the forcing, ``z = w exp(i
  omega t)``, the contact whirl is an equilibrium ``w* = R exp(-i phi)`` of::

      w'' + 2 (zeta + i omega) w' + (1 - omega^2 + 2 i zeta omega) w
          + beta (1 - delta/|w|) (1 + i mu) w = rho omega^2

  so that ``(1 - omega^2 + 2 i zeta omega + beta (1 - delta/R) (1 + i mu)) R exp(-i phi) = rho
  omega^2``, i.e. ``|a R - b| = rho omega^2`` with ``a = 1 - omega^2 + beta + i (2 zeta omega +
  beta mu)`` and ``b = beta delta (1 + i mu)``, a quadratic in ``R`` (:func:`contact_whirl`).
  The change of frame is ``(q, q') -> (Rot(omega t) q, Rot(omega t) (q' + omega J q))``, the
  same matrix at ``t = 0`` and ``t = T``; the monodromy matrix is therefore similar to
  ``expm(J_rot T)``, ``J_rot`` the Jacobian of the rotating-frame equation at ``w*``
  (:func:`contact_whirl_multipliers`).  ``D[(1 - delta/r) w] = (1 - delta/r) I + delta w w^T /
  r^3``, which tends to the radial projector ``w w^T / delta^2``, not to 0, as ``R -> delta+``
  (:func:`contact_onset_limit`).
* Special points of ``jeffcott_gravity``'s branch of T-periodic orbits (:data:`GRAVITY_POINTS`):
  brentq in omega on ``det(M + I)`` (period doubling), on ``|mu| - 1`` for the largest non-real
  multiplier (torus), or on ``r_ext - delta`` (grazing), the orbit being re-solved by Newton at
  each omega from the last one; folds as the extremum of omega along the branch.  The branch
  folds twice (near 0.9602 and 0.8824), so the brackets and starting states come from a
  pseudo-arclength continuation from first contact (:func:`gravity_branch`, slow);
  :func:`gravity_period_doublings` finds the first two by natural-parameter stepping alone.

Accuracy (printed by :func:`main`).

* Variational vs central finite-difference monodromy (step 1e-5) on an orbit crossing the
  circle twice: 1.6e-8 relative.  Along 81 points of the gravity branch, ``P`` and ``M`` agree
  with an integration limited to ``max_step = 2e-3`` (which resolves every arc by its events
  directly) to 1e-9 relative, 3e-9 at the one point 2e-6 past first contact, where the contact
  arc is tangent enough for the crossing-time error to show through the Jacobian's jump.
* Closed-form contact whirls (``mu = 0`` and ``mu = 0.1``): Newton from the closed-form state
  moves it by less than 1e-11 and the multipliers agree with the variational monodromy to 5e-12
  (3e-11 once).  Contact onsets: residual ``A - delta`` below 3e-16.
* Special points: the frequencies move by at most 6e-13 between ``rtol = 1e-12`` and ``1e-13``
  and by at most 3e-11 (1.8e-10 for grazings) with ``rtol = 1e-10``; see
  :data:`GRAVITY_REFERENCE` for the bound used.

Times (one core): :func:`period_map` 0.03 s, :func:`check_monodromy` 0.3 s,
:func:`gravity_period_doublings` 2 s, :func:`gravity_point` 0.6-4 s (folds 5-9 s),
:func:`gravity_branch` about 2 minutes, :func:`main` about 2 minutes (plus 2 with ``--branch``).

Run ``python tests/rotor_reference.py`` to print the reference values.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.optimize import brentq

#: Parameters of ``jeffcott_snubber.PARAMETERS`` other than the forcing frequency ``omega``.
DEFAULTS = {"zeta": 0.05, "beta": 20.0, "delta": 1.0, "rho": 0.5, "mu": 0.0, "g": 0.0}
#: ``jeffcott_gravity``: the defaults with ``g = 0.2``.
GRAVITY = dict(DEFAULTS, g=0.2)
#: ``jeffcott_friction``: the defaults with ``mu = 0.1``.
FRICTION = dict(DEFAULTS, mu=0.1)
#: Integration tolerances of :func:`period_map`.
RTOL, ATOL = 1e-12, 1e-13
#: Most mode switches (and restarts) in one period.
MAX_SWITCHES = 200
#: An extremum of ``r`` counts as beyond the circle when ``|r^2 - delta^2|`` exceeds this (a
#: shallower double crossing inside one step, i.e. a near-tangency, is not resolved).
GAP_TOL = 1e-12

FREE, CONTACT = 0, 1
_J2 = np.array([[0.0, -1.0], [1.0, 0.0]])  # multiplication by i


def _params(params: dict) -> dict:
    """The defaults overridden by ``params``; raises ``TypeError`` on an unknown name."""
    unknown = set(params) - set(DEFAULTS)
    if unknown:
        raise TypeError(f"unknown parameter(s): {sorted(unknown)}")
    return dict(DEFAULTS, **params)


def _field(mode: int, omega: float, p: dict):
    """Right-hand side of state plus variational equation (20 components) in one mode."""
    zeta, beta, delta, rho, mu, g = (p[k] for k in ("zeta", "beta", "delta", "rho", "mu", "g"))
    amp = rho * omega**2

    if mode == FREE:
        A = np.zeros((4, 4))
        A[0, 2] = A[1, 3] = 1.0
        A[2, 0] = A[3, 1] = -1.0
        A[2, 2] = A[3, 3] = -2.0 * zeta

        def rhs(t, s):
            x, y, vx, vy = s[:4]
            out = np.empty(20)
            out[0], out[1] = vx, vy
            out[2] = -2.0 * zeta * vx - x + amp * np.cos(omega * t)
            out[3] = -2.0 * zeta * vy - y + amp * np.sin(omega * t) - g
            out[4:] = (A @ s[4:].reshape(4, 4)).ravel()
            return out

        return rhs

    def rhs(t, s):
        x, y, vx, vy = s[:4]
        r = np.sqrt(x * x + y * y)
        k = beta * (1.0 - delta / r)
        out = np.empty(20)
        out[0], out[1] = vx, vy
        out[2] = -2.0 * zeta * vx - x - k * (x - mu * y) + amp * np.cos(omega * t)
        out[3] = -2.0 * zeta * vy - y - k * (mu * x + y) + amp * np.sin(omega * t) - g
        # D[(1 - delta/r) q] = (1 - delta/r) I + delta q q^T / r^3, then times [[1, -mu], [mu, 1]]
        c = beta * delta / r**3
        dxx, dxy, dyy = k + c * x * x, c * x * y, k + c * y * y
        Phi = s[4:].reshape(4, 4)
        dPhi = np.empty((4, 4))
        dPhi[0], dPhi[1] = Phi[2], Phi[3]
        dPhi[2] = -(1.0 + dxx - mu * dxy) * Phi[0] - (dxy - mu * dyy) * Phi[1] - 2.0 * zeta * Phi[2]
        dPhi[3] = -(mu * dxx + dxy) * Phi[0] - (1.0 + mu * dxy + dyy) * Phi[1] - 2.0 * zeta * Phi[3]
        out[4:] = dPhi.ravel()
        return out

    return rhs


def _gap(t, s, delta):
    """``r^2 - delta^2``: positive in contact."""
    return s[0] * s[0] + s[1] * s[1] - delta * delta


def _radial(t, s, delta):
    """``(x vx + y vy)``: zero at the extrema of ``r``."""
    return s[0] * s[2] + s[1] * s[3]


def _refine(field, sol, tc: float, delta: float, rtol: float, atol: float):
    """A crossing time located on the dense output, polished by Newton on the integrated state.

    The dense output of DOP853 is less accurate than its steps, and near a tangency, where the
    gap function is flat, an error in the crossing time shows in the monodromy matrix (through
    the jump of the Jacobian).  Here the state at ``tc`` is integrated afresh from the start of
    the step that contains it, and ``tc`` corrected by ``-h / h'`` (``h = r^2 - delta^2``,
    ``h' = 2 (x vx + y vy)``) until the correction is below 1e-14.  (What remains is the
    integration error of the state divided by the slope ``h'``.)

    Parameters
    ----------
    field : callable
        Right-hand side of the mode the crossing ends.
    sol : OdeResult
        The integration, with its dense output.
    tc : float
        Crossing time located on the dense output.
    delta : float
        Clearance.
    rtol, atol : float
        Integration tolerances.

    Returns
    -------
    t : float
        The crossing time.
    s : ndarray, shape (20,)
        State and variational matrix there.
    """
    ts = sol.sol.ts
    i = min(max(int(np.searchsorted(ts, tc, side="right")) - 1, 0), len(ts) - 2)
    ta, ya = ts[i], sol.sol(ts[i])  # a step point: the dense output is exact there
    if i == 0:
        ya = sol.y[:, 0]
    t, s = tc, sol.sol(tc)
    for _ in range(4):
        if t > ta:
            r = solve_ivp(field, (ta, t), ya, method="DOP853", rtol=rtol, atol=atol)
            s = r.y[:, -1]
        slope = 2.0 * _radial(t, s, delta)
        if slope == 0.0:
            break
        dt = -_gap(t, s, delta) / slope
        if abs(dt) > 1e-6 or t + dt <= ta:  # not a transversal crossing near tc: keep the dense one
            return tc, sol.sol(tc)
        t += dt
        if abs(dt) < 1e-14:
            break
    return t, s


def _kind(field, t, s) -> str:
    """``"max"`` or ``"min"``: the sign of ``d/dt (x vx + y vy)`` at an extremum of ``r``."""
    a = field(t, s)
    return "max" if s[2] ** 2 + s[3] ** 2 + s[0] * a[2] + s[1] * a[3] < 0 else "min"


def _initial_mode(s: np.ndarray, delta: float) -> int:
    """Contact if ``r > delta``, free if ``r < delta``; on the circle, by the sign of ``r'``."""
    h = _gap(0.0, s, delta)
    if h != 0.0:
        return CONTACT if h > 0 else FREE
    return CONTACT if _radial(0.0, s, delta) > 0 else FREE


def flow(state, omega: float, t_end: float | None = None, rtol: float = RTOL, atol: float = ATOL,
         record: bool = False, **params):
    """State and state-transition matrix from ``t = 0`` to ``t_end``, mode by mode.

    Parameters
    ----------
    state : array_like, shape (4,)
        Initial state ``(x, y, vx, vy)`` at ``t = 0``.
    omega : float
        Forcing frequency.
    t_end : float, optional
        Final time; the forcing period ``2 pi / omega`` by default.
    rtol, atol : float
        Tolerances of ``solve_ivp`` (DOP853) on state and variational equation.
    record : bool
        Also return the crossings of ``r = delta`` and the extrema of ``r``.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    y : ndarray, shape (4,)
        State at ``t_end``.
    Phi : ndarray, shape (4, 4)
        Its derivative with respect to ``state`` (every saltation matrix is the identity).
    crossings : list of (float, str)
        Only when ``record``: ``(t, kind)``, kind ``"enter"`` or ``"leave"``.
    extrema : list of (float, float, str)
        Only when ``record``: ``(t, r, kind)`` of every extremum of ``r``, kind ``"max"`` or
        ``"min"`` (meaningless on a circular whirl, where ``r' = 0`` up to round-off).

    Raises
    ------
    RuntimeError
        An integration failed, or more than :data:`MAX_SWITCHES` mode switches.
    """
    p = _params(params)
    delta = p["delta"]
    T = 2.0 * np.pi / omega
    t_end = T if t_end is None else float(t_end)
    s = np.concatenate([np.asarray(state, dtype=float), np.eye(4).ravel()])
    mode = _initial_mode(s, delta)
    t = 0.0
    crossings, extrema = [], []
    fields = {FREE: _field(FREE, omega, p), CONTACT: _field(CONTACT, omega, p)}
    first_step = None  # after a restart on the circle: a small first step (see below)
    for _ in range(MAX_SWITCHES):
        sign = 1.0 if mode == FREE else -1.0  # direction of the crossing that leaves the mode

        def gap(t, s, _d=delta):
            return _gap(t, s, _d)

        gap.terminal, gap.direction = True, sign

        def extremum(t, s, _d=delta):
            return _radial(t, s, _d)

        # free: maxima of r (r' falls through 0); contact: minima; both when recording
        extremum.terminal, extremum.direction = False, (0.0 if record else -sign)

        # Restarting on the circle, the gap function is ~0; a first step spanning a whole short arc
        # would end on the far side and report the crossing at the start.  A first step of 1e-5
        # leaves the circle in the crossing direction; a crossing reported at the start anyway is
        # retried with smaller first steps.
        for fs in (first_step, None if first_step is None else first_step * 1e-3, 1e-11):
            if fs is not None:
                fs = min(fs, 0.5 * (t_end - t))
            sol = solve_ivp(fields[mode], (t, t_end), s, method="DOP853", rtol=rtol, atol=atol,
                            events=(gap, extremum), dense_output=True, first_step=fs)
            if sol.status < 0:
                raise RuntimeError(f"solve_ivp failed at t = {sol.t[-1]}: {sol.message}")
            if not (sol.status == 1 and sol.t[-1] - t <= 1e-13 * max(1.0, t)) or first_step is None:
                break
        else:
            raise RuntimeError(f"crossing at the restart itself (t = {t}): a tangency?")
        t_stop = sol.t[-1]
        # a double crossing inside one step: an extremum of r on the far side of the circle
        found = [(te, ye, _kind(fields[mode], te, ye)) for te, ye in zip(sol.t_events[1], sol.y_events[1])]
        missed = [te for te, ye, kind in found
                  if sign * _gap(te, ye, delta) > GAP_TOL and te < t_stop
                  and kind == ("max" if mode == FREE else "min")]
        undo = False
        if missed:
            te = missed[0]
            ts = sol.sol.ts
            i = max(int(np.searchsorted(ts, te)) - 1, 0)
            grid = np.linspace(ts[i], te, 65)
            inside = [u for u in grid[:-1] if sign * _gap(u, sol.sol(u), delta) < 0]
            if inside:
                tc = brentq(lambda u: _gap(u, sol.sol(u), delta), inside[-1], te, xtol=1e-15, rtol=8.9e-16)
                t_next, s_next = _refine(fields[mode], sol, tc, delta, rtol, atol)
            elif ts[i] == t and crossings and abs(_gap(t, s, delta)) < 1e-9:
                # the arc that began at t ended within round-off of it (the gap function started on
                # the wrong side): a tangency; undo the crossing at t
                t_next, s_next, undo = t, s, True
            else:
                raise RuntimeError(f"missed crossing near t = {te} not bracketed")
        elif sol.status == 1:
            t_next, s_next = _refine(fields[mode], sol, sol.t_events[0][0], delta, rtol, atol)
        else:
            t_next = None
        extrema += [(te, float(np.hypot(ye[0], ye[1])), kind) for te, ye, kind in found
                    if t_next is None or te < t_next]
        if t_next is None:
            y = sol.y[:, -1]
            out = (y[:4].copy(), y[4:].reshape(4, 4).copy())
            return (*out, crossings, extrema) if record else out
        t, s = t_next, s_next
        if undo:
            crossings.pop()
        else:
            crossings.append((t, "enter" if mode == FREE else "leave"))
        mode = CONTACT if mode == FREE else FREE
        first_step = 1e-5
    raise RuntimeError(f"more than {MAX_SWITCHES} mode switches in one period")


def period_map(state, omega: float, rtol: float = RTOL, atol: float = ATOL, **params):
    """The period map ``P`` (stroboscopic map at ``t = 0 -> T``) and its monodromy matrix.

    Parameters
    ----------
    state : array_like, shape (4,)
        State ``(x, y, vx, vy)`` at ``t = 0``.
    omega : float
        Forcing frequency; ``T = 2 pi / omega``.
    rtol, atol : float
        Integration tolerances.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    P : ndarray, shape (4,)
        State at ``t = T``.
    M : ndarray, shape (4, 4)
        ``dP / dstate`` from the variational equation.

    Raises
    ------
    RuntimeError
        From :func:`flow`.
    """
    return flow(state, omega, rtol=rtol, atol=atol, **params)


def monodromy_fd(state, omega: float, h: float = 1e-5, **params) -> np.ndarray:
    """Central finite-difference derivative of :func:`period_map`.

    Parameters
    ----------
    state : array_like, shape (4,)
        State at ``t = 0``.
    omega : float
        Forcing frequency.
    h : float
        Step (absolute, the same for every component).
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    ndarray, shape (4, 4)
        ``(P(state + h e_j) - P(state - h e_j)) / (2 h)`` in column ``j``.

    Raises
    ------
    RuntimeError
        From :func:`flow`.
    """
    state = np.asarray(state, dtype=float)
    M = np.empty((4, 4))
    for j in range(4):
        e = np.zeros(4)
        e[j] = h
        M[:, j] = (period_map(state + e, omega, **params)[0] - period_map(state - e, omega, **params)[0]) / (2 * h)
    return M


def periodic_orbit(omega: float, guess, tol: float | None = None, maxit: int = 30, rtol: float = RTOL,
                   atol: float = ATOL, **params):
    """The T-periodic orbit through ``guess``, by damped Newton on ``P(x) - x``.

    Parameters
    ----------
    omega : float
        Forcing frequency.
    guess : array_like, shape (4,)
        Initial guess of the state at ``t = 0``.
    tol : float, optional
        Stop when ``|P(x) - x| <= tol`` (max norm); ``max(1e-11, rtol / 2)`` by default.
    maxit : int
        Most Newton steps.
    rtol, atol : float
        Integration tolerances.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    state : ndarray, shape (4,)
        Periodic state at ``t = 0``.
    multipliers : ndarray, shape (4,), complex
        Eigenvalues of the monodromy matrix at ``state``, sorted by decreasing modulus.
    M : ndarray, shape (4, 4)
        The monodromy matrix.

    Raises
    ------
    RuntimeError
        Newton's method did not converge.
    """
    tol = max(1e-11, 0.5 * rtol) if tol is None else tol
    x = np.asarray(guess, dtype=float).copy()
    P, M = period_map(x, omega, rtol=rtol, atol=atol, **params)
    F = P - x
    for _ in range(maxit):
        if np.max(np.abs(F)) <= tol:
            mult = np.linalg.eigvals(M)
            return x, mult[np.argsort(-np.abs(mult), kind="stable")], M
        dx = np.linalg.solve(M - np.eye(4), -F)
        # backtracking: P is only C^1 (the field's Jacobian jumps), full steps can overshoot
        lam = 1.0
        while True:
            xn = x + lam * dx
            Pn, Mn = period_map(xn, omega, rtol=rtol, atol=atol, **params)
            Fn = Pn - xn
            if np.linalg.norm(Fn) < (1 - 1e-4 * lam) * np.linalg.norm(F) or lam < 1e-3:
                break
            lam *= 0.5
        x, P, M, F = xn, Pn, Mn, Fn
    raise RuntimeError(f"Newton did not converge at omega = {omega} (|F| = {np.max(np.abs(F)):.2e})")


# ----------------------------------------------------------------------------------------------
# closed forms


def free_amplitude(omega: float, **params) -> float:
    """Radius ``A = rho omega^2 / |1 - omega^2 + 2 i zeta omega|`` of the free whirl.

    Parameters
    ----------
    omega : float
        Forcing frequency.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    float
        ``A(omega)``.
    """
    p = _params(params)
    return p["rho"] * omega**2 / abs(1 - omega**2 + 2j * p["zeta"] * omega)


def free_whirl(omega: float, **params) -> np.ndarray:
    """State at ``t = 0`` of the free whirl ``z = A exp(i (omega t - phi)) - i g``.

    Parameters
    ----------
    omega : float
        Forcing frequency.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    ndarray, shape (4,)
        ``(x, y, vx, vy)`` at ``t = 0`` (a periodic orbit as long as it stays inside the circle).
    """
    p = _params(params)
    W = p["rho"] * omega**2 / (1 - omega**2 + 2j * p["zeta"] * omega)  # A exp(-i phi)
    z, dz = W - 1j * p["g"], 1j * omega * W
    return np.array([z.real, z.imag, dz.real, dz.imag])


def free_multipliers(omega: float, **params) -> np.ndarray:
    """Floquet multipliers of the free (linear) flow, ``eig(expm(A T))``.

    Parameters
    ----------
    omega : float
        Forcing frequency.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    ndarray, shape (4,), complex
        Two complex-conjugate pairs ``exp((-zeta +- i sqrt(1 - zeta^2)) T)``, each double.
    """
    p = _params(params)
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2, 0] = A[3, 1] = -1.0
    A[2, 2] = A[3, 3] = -2.0 * p["zeta"]
    return np.sort_complex(np.linalg.eigvals(expm(A * 2 * np.pi / omega)))


def contact_onsets(**params) -> np.ndarray:
    """Frequencies at which the free whirl first touches the ring, ``A(omega) + g = delta``.

    Parameters
    ----------
    **params
        Model parameters overriding :data:`DEFAULTS` (``g >= 0``, ``g < delta``).

    Returns
    -------
    ndarray
        The positive roots, ascending (with ``s = omega^2``: ``rho^2 s^2 = (delta - g)^2 ((1 -
        s)^2 + 4 zeta^2 s)``, a quadratic in ``s``), each polished by brentq on
        ``A(omega) + g - delta``.

    Raises
    ------
    ValueError
        ``g >= delta``.
    """
    p = _params(params)
    d = p["delta"] - abs(p["g"])
    if d <= 0:
        raise ValueError("g >= delta: the ring is touched at rest")
    # (d^2 - rho^2) s^2 + d^2 (4 zeta^2 - 2) s + d^2 = 0
    roots = np.roots([d * d - p["rho"] ** 2, d * d * (4 * p["zeta"] ** 2 - 2), d * d])
    out = []
    for s in sorted(roots[np.isreal(roots)].real):
        if s <= 0:
            continue
        w = np.sqrt(s)
        f = lambda om: free_amplitude(om, **params) - d  # noqa: E731
        lo, hi = w * (1 - 1e-6), w * (1 + 1e-6)
        out.append(brentq(f, lo, hi, xtol=1e-16, rtol=8.9e-16) if f(lo) * f(hi) < 0 else w)
    return np.array(out)


def contact_whirl(omega: float, **params) -> list[tuple[float, float]]:
    """Whirls in contact all round (``g = 0``): ``z = R exp(i (omega t - phi))``, ``R > delta``.

    ``(1 - omega^2 + 2 i zeta omega + beta (1 - delta/R) (1 + i mu)) R exp(-i phi) = rho omega^2``,
    i.e. ``|a R - b| = rho omega^2`` with ``a = 1 - omega^2 + beta + i (2 zeta omega + beta mu)``,
    ``b = beta delta (1 + i mu)``: ``|a|^2 R^2 - 2 Re(a conj(b)) R + |b|^2 - rho^2 omega^4 = 0``.

    Parameters
    ----------
    omega : float
        Forcing frequency.
    **params
        Model parameters overriding :data:`DEFAULTS`; ``g`` must be 0.

    Returns
    -------
    list of (float, float)
        ``(R, phi)`` of each root with ``R > delta`` (0, 1 or 2 of them), ascending in ``R``.

    Raises
    ------
    ValueError
        ``g != 0`` (the whirl is then not a circle).
    """
    p = _params(params)
    if p["g"] != 0:
        raise ValueError("the contact whirl is a circle only for g = 0")
    zeta, beta, delta, rho, mu = (p[k] for k in ("zeta", "beta", "delta", "rho", "mu"))
    a = 1 - omega**2 + beta + 1j * (2 * zeta * omega + beta * mu)
    b = beta * delta * (1 + 1j * mu)
    c2, c1, c0 = abs(a) ** 2, -2 * (a * np.conj(b)).real, abs(b) ** 2 - rho**2 * omega**4
    disc = c1 * c1 - 4 * c2 * c0
    if disc < 0:
        return []
    sq = np.sqrt(disc)
    out = []
    for R in sorted({(-c1 - sq) / (2 * c2), (-c1 + sq) / (2 * c2)}):
        if R > delta:
            W = rho * omega**2 / (a - b / R)  # R exp(-i phi)
            out.append((float(abs(W)), float(-np.angle(W))))
    return out


def contact_whirl_state(omega: float, R: float, phi: float) -> np.ndarray:
    """State at ``t = 0`` of the whirl ``z = R exp(i (omega t - phi))``.

    Parameters
    ----------
    omega : float
        Forcing frequency.
    R, phi : float
        Radius and phase lag.

    Returns
    -------
    ndarray, shape (4,)
        ``(x, y, vx, vy)``.
    """
    W = R * np.exp(-1j * phi)
    return np.array([W.real, W.imag, (1j * omega * W).real, (1j * omega * W).imag])


def rotating_jacobian(omega: float, R: float, phi: float, **params) -> np.ndarray:
    """Jacobian at the whirl ``w* = R exp(-i phi)`` of the rotating-frame equation (contact side).

    Parameters
    ----------
    omega : float
        Forcing frequency.
    R, phi : float
        Radius and phase lag of the whirl; ``R = delta`` gives the one-sided limit ``R -> delta+``.
    **params
        Model parameters overriding :data:`DEFAULTS` (``g = 0``).

    Returns
    -------
    ndarray, shape (4, 4)
        For the state ``(u, v, u', v')``, ``w = u + i v``: ``[[0, I], [-(1 - omega^2) I - 2 zeta
        omega J - beta K D, -2 zeta I - 2 omega J]]`` with ``J`` the rotation by 90 degrees,
        ``K = [[1, -mu], [mu, 1]]`` and ``D = (1 - delta/R) I + delta w w^T / R^3``.
    """
    p = _params(params)
    zeta, beta, delta, mu = (p[k] for k in ("zeta", "beta", "delta", "mu"))
    w = np.array([R * np.cos(phi), -R * np.sin(phi)])
    D = (1 - delta / R) * np.eye(2) + delta * np.outer(w, w) / R**3
    K = np.array([[1.0, -mu], [mu, 1.0]])
    I2 = np.eye(2)
    Jr = np.zeros((4, 4))
    Jr[:2, 2:] = I2
    Jr[2:, :2] = -(1 - omega**2) * I2 - 2 * zeta * omega * _J2 - beta * K @ D
    Jr[2:, 2:] = -2 * zeta * I2 - 2 * omega * _J2
    return Jr


def contact_whirl_multipliers(omega: float, R: float, phi: float, **params) -> np.ndarray:
    """Floquet multipliers of the contact whirl: ``eig(expm(J_rot T))``.

    The monodromy matrix in the fixed frame is ``C expm(J_rot T) C^-1`` with ``C = [[I, 0],
    [omega J, I]]`` (the rotation is the identity after one period), so the eigenvalues agree.

    Parameters
    ----------
    omega : float
        Forcing frequency.
    R, phi : float
        Radius and phase lag of the whirl (``R = delta``: the one-sided limit at contact onset).
    **params
        Model parameters overriding :data:`DEFAULTS` (``g = 0``).

    Returns
    -------
    ndarray, shape (4,), complex
        Sorted by decreasing modulus.
    """
    mult = np.linalg.eigvals(expm(rotating_jacobian(omega, R, phi, **params) * 2 * np.pi / omega))
    return mult[np.argsort(-np.abs(mult), kind="stable")]


def contact_onset_limit(omega0: float, **params) -> np.ndarray:
    """One-sided (contact side) multipliers of the whirl at a contact onset ``A(omega0) = delta``.

    Parameters
    ----------
    omega0 : float
        An onset frequency from :func:`contact_onsets` (``g = 0``).
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    ndarray, shape (4,), complex
        :func:`contact_whirl_multipliers` at ``R = delta`` and the phase of the free whirl.
    """
    p = _params(params)
    W = p["rho"] * omega0**2 / (1 - omega0**2 + 2j * p["zeta"] * omega0)
    return contact_whirl_multipliers(omega0, p["delta"], -np.angle(W), **params)


def _mult_distance(m1, m2) -> float:
    """Largest distance between two multiplier sets, matched greedily."""
    m2 = list(np.asarray(m2))
    worst = 0.0
    for a in np.asarray(m1):
        j = int(np.argmin([abs(a - b) for b in m2]))
        worst = max(worst, abs(a - m2.pop(j)))
    return worst


# ----------------------------------------------------------------------------------------------
# self checks


def check_monodromy(omega: float = 0.79, state=None, h: float = 1e-5, **params) -> float:
    """Variational against finite-difference monodromy; asserts agreement to 1e-6.

    Parameters
    ----------
    omega : float
        Forcing frequency.
    state : array_like, optional
        Initial state; by default the free whirl of the same parameters, pushed outwards by 2 %
        (an orbit that crosses the circle).
    h : float
        Finite-difference step.
    **params
        Model parameters; :data:`GRAVITY` when none are given.

    Returns
    -------
    float
        ``max |M_var - M_fd| / max |M_var|``.

    Raises
    ------
    AssertionError
        Disagreement above 1e-6, or no crossing of the circle.
    """
    params = params or GRAVITY
    if state is None:
        state = free_whirl(omega, **params) * 1.02
    crossings = flow(state, omega, record=True, **params)[2]
    assert len(crossings) >= 2, "the test orbit does not cross the circle"
    M = period_map(state, omega, **params)[1]
    Mfd = monodromy_fd(state, omega, h=h, **params)
    err = float(np.max(np.abs(M - Mfd)) / np.max(np.abs(M)))
    assert err < 1e-6, err
    return err


def check_contact_whirl(omega: float = 1.2, **params) -> float:
    """The closed-form contact whirl is a periodic orbit with the closed-form multipliers.

    Parameters
    ----------
    omega : float
        Forcing frequency with a contact whirl (the smallest root ``R > delta`` is used).
    **params
        Model parameters (``g = 0``).

    Returns
    -------
    float
        Largest of ``|P(x) - x|`` at the closed-form state and the multiplier mismatch.

    Raises
    ------
    AssertionError
        Either above 1e-8.
    """
    R, phi = contact_whirl(omega, **params)[0]
    x = contact_whirl_state(omega, R, phi)
    P, M = period_map(x, omega, **params)
    e1 = float(np.max(np.abs(P - x)))
    e2 = _mult_distance(np.linalg.eigvals(M), contact_whirl_multipliers(omega, R, phi, **params))
    assert e1 < 1e-8 and e2 < 1e-8, (e1, e2)
    return max(e1, e2)


# ----------------------------------------------------------------------------------------------
# period doublings of the gravity branch


def arclength_branch(omega0: float, x0, omega_stop: float, ds: float = 0.004, ds_min: float = 1e-7,
                     ds_max: float = 0.01, max_points: int = 2000, tol: float = 1e-11, **params):
    """Pseudo-arclength continuation of a T-periodic orbit in ``(x, omega)``, through folds.

    Parameters
    ----------
    omega0 : float
        Starting frequency.
    x0 : array_like, shape (4,)
        Periodic state (or a close guess) at ``omega0``.
    omega_stop : float
        Stop once omega passes it (either way).
    ds, ds_min, ds_max : float
        Initial, smallest and largest step (Euclidean norm in ``(x, omega)``).
    max_points : int
        Most points.
    tol : float
        Corrector tolerance on ``|P(x) - x|``.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    list of dict
        For each point: ``omega``, ``x``, ``mult`` (by decreasing modulus), ``det_plus``
        (``det(M + I)``), ``det_minus`` (``det(M - I)``, changes sign at a fold).

    Raises
    ------
    RuntimeError
        The step fell below ``ds_min``.
    """
    def residual(u):
        x, om = u[:4], u[4]
        P, M = period_map(x, om, **params)
        h = 1e-6 * max(1.0, abs(om))
        Pw = (period_map(x, om + h, **params)[0] - period_map(x, om - h, **params)[0]) / (2 * h)
        return P - x, np.hstack([M - np.eye(4), Pw[:, None]]), M

    def record(u, M):
        mult = np.linalg.eigvals(M)
        return {"omega": float(u[4]), "x": u[:4].copy(), "mult": mult[np.argsort(-np.abs(mult), kind="stable")],
                "det_plus": float(np.linalg.det(M + np.eye(4))), "det_minus": float(np.linalg.det(M - np.eye(4)))}

    x, _, _ = periodic_orbit(omega0, x0, tol=tol, **params)
    u = np.append(x, omega0)
    F, DF, M = residual(u)
    tangent = np.linalg.svd(DF)[2][-1]
    direction = np.sign(omega_stop - omega0)
    if tangent[4] * direction < 0:
        tangent = -tangent
    points = [record(u, M)]
    while len(points) < max_points and (u[4] - omega_stop) * direction < 0:
        v = u + ds * tangent
        ok = False
        for it in range(8):
            F, DF, M = residual(v)
            if np.max(np.abs(F)) <= tol:
                ok = True
                break
            A = np.vstack([DF, tangent])
            dv = np.linalg.solve(A, -np.append(F, tangent @ (v - u) - ds))
            v = v + dv
            if np.linalg.norm(dv) > 0.5 * max(ds, 1e-3):
                break
        if not ok:
            ds *= 0.5
            if ds < ds_min:
                raise RuntimeError(f"arclength step below {ds_min} at omega = {u[4]}")
            continue
        new_tangent = np.linalg.svd(DF)[2][-1]
        if new_tangent @ tangent < 0:
            new_tangent = -new_tangent
        u, tangent = v, new_tangent
        points.append(record(u, M))
        if it <= 3:
            ds = min(ds * 1.3, ds_max)
    return points


def period_doubling(lo: float, hi: float, guess, xtol: float = 1e-12, rtol: float = RTOL,
                    atol: float = ATOL, **params):
    """Period doubling between ``lo`` and ``hi``: brentq in omega on ``det(M + I)``.

    Parameters
    ----------
    lo, hi : float
        Bracket (``det(M + I)`` changes sign).
    guess : array_like, shape (4,)
        Periodic state near the bracket (updated with every orbit found).
    xtol : float
        brentq's tolerance in omega.
    rtol, atol : float
        Integration tolerances.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    omega : float
        The period-doubling frequency.
    state : ndarray, shape (4,)
        The periodic state there.
    multipliers : ndarray, shape (4,), complex
        Its multipliers (one of them -1).

    Raises
    ------
    ValueError
        No sign change over the bracket.
    RuntimeError
        Newton failed.
    """
    memo = {"x": np.asarray(guess, dtype=float)}

    def f(om):
        x, m, M = periodic_orbit(om, memo["x"], rtol=rtol, atol=atol, **params)
        memo.update(x=x, m=m)
        return np.linalg.det(M + np.eye(4))

    om = brentq(f, lo, hi, xtol=xtol, rtol=8.9e-16)
    f(om)
    return om, memo["x"], memo["m"]


def _pair_modulus(M: np.ndarray) -> float:
    """Modulus minus 1 of the largest non-real multiplier (NaN when all are real)."""
    m = np.linalg.eigvals(M)
    c = m[np.abs(m.imag) > 1e-9 * np.maximum(1.0, np.abs(m))]
    return float(np.max(np.abs(c)) - 1.0) if c.size else float("nan")


def neimark_sacker(lo: float, hi: float, guess, xtol: float = 1e-12, rtol: float = RTOL,
                   atol: float = ATOL, **params):
    """Neimark-Sacker (torus) point between ``lo`` and ``hi``: brentq on ``|mu| - 1``.

    ``mu`` is the non-real multiplier of largest modulus; it must stay non-real over the bracket.

    Parameters
    ----------
    lo, hi : float
        Bracket.
    guess : array_like, shape (4,)
        Periodic state near the bracket.
    xtol : float
        brentq's tolerance in omega.
    rtol, atol : float
        Integration tolerances.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    omega : float
        The frequency.
    state : ndarray, shape (4,)
        The periodic state there.
    multipliers : ndarray, shape (4,), complex
        Its multipliers (a pair on the unit circle).

    Raises
    ------
    ValueError
        No sign change, or a real pair, over the bracket.
    RuntimeError
        Newton failed.
    """
    memo = {"x": np.asarray(guess, dtype=float)}

    def f(om):
        x, m, M = periodic_orbit(om, memo["x"], rtol=rtol, atol=atol, **params)
        memo.update(x=x, m=m)
        v = _pair_modulus(M)
        if np.isnan(v):
            raise ValueError(f"no complex pair at omega = {om}")
        return v

    om = brentq(f, lo, hi, xtol=xtol, rtol=8.9e-16)
    f(om)
    return om, memo["x"], memo["m"]


def fold_point(c_lo: float, c_hi: float, guess, omega_guess: float, rtol: float = RTOL,
               atol: float = ATOL, **params):
    """Fold (saddle-node) of T-periodic orbits: the extremum of omega along the branch.

    The branch is parametrised by ``c = vx(0)`` (monotone through the fold): for fixed ``c``,
    Newton's method solves ``P(x, omega) = x`` for ``(x, y, vy, omega)``; the extremum of
    ``omega(c)`` is located by bounded Brent minimisation (of ``-omega`` or ``omega``).

    Parameters
    ----------
    c_lo, c_hi : float
        Bracket of ``vx(0)`` around the fold.
    guess : array_like, shape (4,)
        Periodic state near the fold.
    omega_guess : float
        Its frequency.
    rtol, atol : float
        Integration tolerances.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    omega : float
        Frequency of the fold.
    state : ndarray, shape (4,)
        Periodic state there.
    multipliers : ndarray, shape (4,), complex
        Its multipliers (one of them 1).

    Raises
    ------
    RuntimeError
        Newton failed.
    """
    from scipy.optimize import minimize_scalar

    memo = {"u": np.append(np.asarray(guess, dtype=float), omega_guess)}

    def solve(c):
        u = memo["u"].copy()
        u[2] = c
        for _ in range(30):
            x, om = u[:4], u[4]
            P, M = period_map(x, om, rtol=rtol, atol=atol, **params)
            F = P - x
            if np.max(np.abs(F)) <= 1e-11:
                memo.update(u=u, M=M)
                return om
            h = 1e-6
            Pw = (period_map(x, om + h, rtol=rtol, atol=atol, **params)[0]
                  - period_map(x, om - h, rtol=rtol, atol=atol, **params)[0]) / (2 * h)
            J = M - np.eye(4)
            J[:, 2] = Pw  # unknowns (x, y, omega, vy): vx is fixed
            d = np.linalg.solve(J, -F)
            u[[0, 1, 4, 3]] += d[[0, 1, 2, 3]]
        raise RuntimeError(f"fold corrector failed at vx = {c}")

    o1, o2, o3 = solve(c_lo), solve(0.5 * (c_lo + c_hi)), solve(c_hi)
    sign = -1.0 if o2 > max(o1, o3) else 1.0  # maximum: minimise -omega
    res = minimize_scalar(lambda c: sign * solve(c), bounds=(min(c_lo, c_hi), max(c_lo, c_hi)),
                          method="bounded", options={"xatol": 1e-7})
    om = solve(res.x)
    mult = np.linalg.eigvals(memo["M"])
    return om, memo["u"][:4].copy(), mult[np.argsort(-np.abs(mult), kind="stable")]


def grazing_point(lo: float, hi: float, guess, t_guess: float, kind: str, xtol: float = 1e-12,
                  rtol: float = RTOL, atol: float = ATOL, **params):
    """Grazing of the T-periodic orbit with the circle: brentq on ``r_ext - delta``.

    ``r_ext`` is the extremum of ``r`` of the given kind nearest to ``t_guess``: a maximum that
    reaches the circle from inside (a new contact arc), or a minimum that reaches it from outside
    (a new lift-off).

    Parameters
    ----------
    lo, hi : float
        Bracket in omega.
    guess : array_like, shape (4,)
        Periodic state near the bracket.
    t_guess : float
        Time of the grazing extremum (within the period), roughly.
    kind : {"max", "min"}
        Kind of the extremum.
    xtol : float
        brentq's tolerance in omega.
    rtol, atol : float
        Integration tolerances.
    **params
        Model parameters overriding :data:`DEFAULTS`.

    Returns
    -------
    omega : float
        The grazing frequency.
    t : float
        Time of the grazing.
    multipliers : ndarray, shape (4,), complex
        Multipliers of the grazing orbit.

    Raises
    ------
    ValueError
        No sign change over the bracket.
    RuntimeError
        Newton failed.
    """
    p = _params(params)
    memo = {"x": np.asarray(guess, dtype=float), "t": t_guess}

    def f(om):
        x, m, M = periodic_orbit(om, memo["x"], rtol=rtol, atol=atol, **params)
        ext = [e for e in flow(x, om, rtol=rtol, atol=atol, record=True, **params)[3] if e[2] == kind]
        te, r, _ = min(ext, key=lambda e: abs(e[0] - memo["t"]))
        memo.update(x=x, m=m, t=te)
        return r - p["delta"]

    om = brentq(f, lo, hi, xtol=xtol, rtol=8.9e-16)
    f(om)
    return om, memo["t"], memo["m"]


def gravity_period_doublings(which=(0, 1), rtol: float = RTOL, atol: float = ATOL):
    """The first two period doublings of ``jeffcott_gravity``, by natural-parameter stepping.

    The branch of T-periodic orbits is started from the free whirl just past first contact
    (``omega_c + 2e-6``) and continued in omega (steps of at most 0.004) to each bracket,
    ``[omega_c + 2e-6, 0.78775]`` and ``[0.795, 0.797]``, where brentq finds the zero of
    ``det(M + I)``.

    Parameters
    ----------
    which : sequence of int
        Which of the two to compute (0, 1).
    rtol, atol : float
        Integration tolerances.

    Returns
    -------
    list of (float, ndarray, ndarray)
        ``(omega, state, multipliers)`` of each.

    Raises
    ------
    RuntimeError
        Newton failed along the continuation.
    """
    p = GRAVITY
    kw = dict(rtol=rtol, atol=atol)
    lo1 = contact_onsets(**p)[0] + 2e-6
    x = periodic_orbit(lo1, free_whirl(lo1, **p), **kw, **p)[0]
    om_at, out = lo1, []
    for k, (lo, hi) in enumerate([(lo1, 0.78775), (0.795, 0.797)]):
        if k > max(which):
            break
        if lo > om_at:
            steps = np.linspace(om_at, lo, max(2, int(np.ceil((lo - om_at) / 0.004)) + 1))
            for om in steps[1:]:
                x = periodic_orbit(om, x, **kw, **p)[0]
            om_at = lo
        if k in which:
            out.append(period_doubling(lo, hi, x, **kw, **p))
    return out


#: Special points along ``jeffcott_gravity``'s branch of T-periodic orbits, in the order of the
#: branch (pseudo-arclength continuation from first contact, :func:`gravity_branch`): kind,
#: bracket (in omega; for a fold, in ``vx(0)``), a periodic state at one end of the bracket and
#: extra arguments.  The branch folds twice (``omega`` turns back at the first fold and forward
#: again at the second), so natural-parameter stepping from first contact only reaches the
#: points before the first fold.
GRAVITY_POINTS = [
    ("period doubling", (0.7876310735, 0.7877262719), (0.7833293232, -0.3625150721, 0.1280033101, 0.6169728934), {}),
    ("period doubling", (0.7954799133, 0.7970998379), (0.8246273785, -0.3445677464, 0.1391978821, 0.6176602885), {}),
    ("torus", (0.7987041063, 0.8002915564), (0.8433162173, -0.3393478527, 0.1426779701, 0.6166730525), {}),
    ("grazing", (0.8119823512, 0.8120015158), (0.9289249439, -0.3353365281, 0.1483768496, 0.6100900279),
     {"t_guess": 7.334063, "kind": "max"}),  # 2 -> 4 crossings
    ("torus", (0.8120015158, 0.8120126775), (0.9290054463, -0.3353717773, 0.1483106438, 0.6101112747), {}),
    ("period doubling", (0.8120747388, 0.8120976881), (0.9289787992, -0.3356322609, 0.1476470608, 0.6103953616), {}),
    ("period doubling", (0.8242372844, 0.8264972615), (0.8784793957, -0.3149023359, 0.0990107760, 0.6811178724), {}),
    ("grazing", (0.9457044551, 0.9487150181), (0.8311105001, -0.0651512966, -0.0149923361, 0.9759597714),
     {"t_guess": 1.423094, "kind": "max"}),  # 4 -> 6 crossings
    ("period doubling", (0.9487150181, 0.9502606877), (0.8314722646, -0.0587808785, -0.0151222813, 0.9830542111), {}),
    ("fold", (0.0820336463, 0.1277556369), (0.8295816219, -0.0508322476, 0.1006974751, 0.9627388128),
     {"omega_guess": 0.9601371959}),
    ("period doubling", (0.9369672289, 0.9388036922), (0.9150158148, -0.0667127971, 0.2664474679, 0.8262764501), {}),
    ("period doubling", (0.9244008402, 0.9266730492), (0.9448342639, -0.0879977721, 0.2823565688, 0.7833974969), {}),
    ("fold", (0.1382633368, 0.1854906682), (1.0089275848, -0.2017432294, 0.1664592216, 0.7068286556),
     {"omega_guess": 0.8824806803}),
    ("period doubling", (0.9017258814, 0.9039284210), (1.0145993615, -0.1884286335, 0.0402113674, 0.7782786442), {}),
    ("torus", (0.9061807123, 0.9084778824), (1.0158319305, -0.1825748309, 0.0260233532, 0.7902398129), {}),
    ("grazing", (0.9558970682, 0.9590654373), (1.0290411152, -0.1057388459, -0.0861431704, 0.9112113460),
     {"t_guess": 5.750400, "kind": "min"}),  # 6 -> 4 crossings
    ("torus", (0.9590654373, 0.9623769540), (1.0302024822, -0.1001835245, -0.0898217972, 0.9178816930), {}),
    ("grazing", (0.9590654373, 0.9623769540), (1.0302024822, -0.1001835245, -0.0898217972, 0.9178816930),
     {"t_guess": 4.419502, "kind": "min"}),  # 4 -> 2 crossings
    ("torus", (0.9623769540, 0.9657876560), (1.0315734353, -0.0942884968, -0.0926993618, 0.9245309825), {}),
    ("grazing", (1.0020706833, 1.0032597761), (1.0431458382, -0.0228684876, -0.1129400203, 1.0089912815),
     {"t_guess": 1.621818, "kind": "max"}),  # 2 -> 4 crossings
    ("period doubling", (1.0020706833, 1.0032597761), (1.0431458382, -0.0228684876, -0.1129400203, 1.0089912815), {}),
    ("period doubling", (1.0149778313, 1.0191301591), (1.0465207100, -0.0328892851, -0.1259452866, 1.0205628394), {}),
]

#: The frequencies :func:`gravity_point` finds for :data:`GRAVITY_POINTS` (``rtol = 1e-12``),
#: with a bound on their error.  They move by at most 6e-13 with ``rtol = 1e-13`` and by at
#: most 3e-11 (1.8e-10 for the grazings) with ``rtol = 1e-10``; the bound is 1e-10 (1e-9 for
#: the grazings, whose extremum of ``r`` is located on the dense output).
GRAVITY_REFERENCE = [
    ("period doubling", 0.7876680818817, 1e-10),
    ("period doubling", 0.7962099127969, 1e-10),
    ("torus", 0.7995728148677, 1e-10),
    ("grazing", 0.8119846105183, 1e-09),
    ("torus", 0.8120034917726, 1e-10),
    ("period doubling", 0.8120795429813, 1e-10),
    ("period doubling", 0.8258021380159, 1e-10),
    ("grazing", 0.9484917118160, 1e-09),
    ("period doubling", 0.9487460468455, 1e-10),
    ("fold", 0.9601710913539, 1e-10),
    ("period doubling", 0.9384726268680, 1e-10),
    ("period doubling", 0.9264931496841, 1e-10),
    ("fold", 0.8824483808638, 1e-10),
    ("period doubling", 0.9028298009197, 1e-10),
    ("torus", 0.9068621174735, 1e-10),
    ("grazing", 0.9583156907280, 1e-09),
    ("torus", 0.9623578687472, 1e-10),
    ("grazing", 0.9623622474425, 1e-09),
    ("torus", 0.9632101515728, 1e-10),
    ("grazing", 1.0025931168894, 1e-09),
    ("period doubling", 1.0026193587241, 1e-10),
    ("period doubling", 1.0156318093107, 1e-10),
]


def gravity_point(k: int, rtol: float = RTOL, atol: float = ATOL):
    """Locate the special point ``GRAVITY_POINTS[k]`` of ``jeffcott_gravity``'s branch.

    Parameters
    ----------
    k : int
        Index in :data:`GRAVITY_POINTS`.
    rtol, atol : float
        Integration tolerances.

    Returns
    -------
    kind : str
        ``"period doubling"``, ``"torus"``, ``"fold"`` or ``"grazing"``.
    omega : float
        Its frequency.
    multipliers : ndarray, shape (4,), complex
        Multipliers of the orbit there.

    Raises
    ------
    RuntimeError
        Newton failed.
    """
    kind, (lo, hi), x, extra = GRAVITY_POINTS[k]
    kw = dict(rtol=rtol, atol=atol, **GRAVITY)
    if kind == "period doubling":
        om, _, m = period_doubling(lo, hi, x, **kw)
    elif kind == "torus":
        om, _, m = neimark_sacker(lo, hi, x, **kw)
    elif kind == "fold":
        om, _, m = fold_point(lo, hi, x, extra["omega_guess"], **kw)
    else:
        om, _, m = grazing_point(lo, hi, x, extra["t_guess"], extra["kind"], **kw)
    return kind, float(om), m


def gravity_branch(omega_stop: float = 1.03, ds: float = 0.002):
    """The branch of ``jeffcott_gravity`` from first contact, by pseudo-arclength continuation.

    Slow (about two minutes): the source of the brackets of :data:`GRAVITY_POINTS`.

    Parameters
    ----------
    omega_stop : float
        Stop once omega passes it.
    ds : float
        Initial step.

    Returns
    -------
    points : list of dict
        As :func:`arclength_branch`, each with ``ncross``, the number of crossings of the circle
        in one period, added.
    brackets : list of (str, float, float)
        ``(kind, omega_a, omega_b)`` of consecutive points between which ``det(M + I)`` (period
        doubling), ``det(M - I)`` (fold), the modulus of a complex pair minus 1 (torus) or the
        number of crossings (grazing) changes.

    Raises
    ------
    RuntimeError
        From :func:`arclength_branch`.
    """
    p = GRAVITY
    om0 = contact_onsets(**p)[0] + 2e-6
    pts = arclength_branch(om0, free_whirl(om0, **p), omega_stop, ds=ds, **p)
    for q in pts:
        q["ncross"] = len(flow(q["x"], q["omega"], record=True, **p)[2])
    brackets = []
    for a, b in zip(pts[:-1], pts[1:]):
        if a["ncross"] != b["ncross"]:
            brackets.append(("grazing", a["omega"], b["omega"]))
        if a["det_plus"] * b["det_plus"] < 0:
            brackets.append(("period doubling", a["omega"], b["omega"]))
        if a["det_minus"] * b["det_minus"] < 0:
            brackets.append(("fold", a["omega"], b["omega"]))
        ma, mb = (M["mult"][np.abs(M["mult"].imag) > 1e-9] for M in (a, b))
        if ma.size and mb.size and (np.max(np.abs(ma)) - 1) * (np.max(np.abs(mb)) - 1) < 0:
            # the same pair on both sides (not one turned real and another taken instead)
            if abs(np.max(np.abs(ma)) - np.max(np.abs(mb))) < 0.2:
                brackets.append(("torus", a["omega"], b["omega"]))
    return pts, brackets


# ----------------------------------------------------------------------------------------------


def main(argv=None):
    """Print every reference value, its check and the time it takes.

    Parameters
    ----------
    argv : list of str, optional
        ``["--branch"]`` also re-runs the pseudo-arclength continuation (about two minutes) and
        prints the brackets it finds.

    Returns
    -------
    None
    """
    import sys

    argv = sys.argv[1:] if argv is None else argv
    np.set_printoptions(precision=10, linewidth=140)

    def timed(fn, *a, **k):
        t0 = time.perf_counter()
        out = fn(*a, **k)
        return out, time.perf_counter() - t0

    print("== 1. period map: variational vs central finite-difference monodromy")
    err, dt = timed(check_monodromy)
    print(f"gravity, omega = 0.79, free whirl * 1.02 (crosses the circle twice): max|M - M_fd| / max|M| = "
          f"{err:.1e}  (check_monodromy: {dt:.2f} s)")
    _, dt = timed(period_map, free_whirl(0.79, **GRAVITY) * 1.02, 0.79, **GRAVITY)
    print(f"one period_map call with monodromy: {dt:.3f} s")

    print("\n== 3a. g = 0: the free whirl touches the ring, A(omega) = delta")
    onsets, dt = timed(contact_onsets)
    for om, q in zip(onsets, (0.820631087712087, 1.407088466022592)):
        print(f"omega = {float(om)!r}  (A - delta = {free_amplitude(om) - 1:.1e}; quoted {q}, difference {om - q:.1e})")
    print(f"({dt * 1e3:.1f} ms)")

    print("\n== 3a. g = 0, mu = 0: contact whirl z = R exp(i (omega t - phi)), closed form vs Newton + variational")
    for om in (0.9, 1.2, 1.5):
        for R, phi in contact_whirl(om):
            xs = contact_whirl_state(om, R, phi)
            (xn, mn, _), dt = timed(periodic_orbit, om, xs)
            mc = contact_whirl_multipliers(om, R, phi)
            print(f"omega = {om}: R = {R!r}, phi = {phi!r}\n    multipliers {mc}\n    "
                  f"|x_Newton - x_closed| = {np.max(np.abs(xn - xs)):.1e}, "
                  f"|multipliers - numerical| = {_mult_distance(mn, mc):.1e}  ({dt:.2f} s)")
    e, dt = timed(check_contact_whirl)
    print(f"check_contact_whirl (omega = 1.2): {e:.1e}  ({dt:.2f} s)")

    print("\n== 3b. g = 0.2: first contact, A(omega) + g = delta")
    og, dt = timed(contact_onsets, **GRAVITY)
    print(f"omega_c = {float(og[0])!r} (quoted 0.7876290735450562, difference {og[0] - 0.7876290735450562:.1e}); "
          f"second root {float(og[1])!r}")
    for f in (1 - 1e-6, 1 + 1e-6):
        cr = flow(free_whirl(og[0] * f, **GRAVITY), og[0] * f, record=True, **GRAVITY)[2]
        print(f"free whirl at omega_c * {f}: {len(cr)} crossings of the circle")

    print("\n== 5. mu = 0.1, g = 0: one-sided multipliers at the contact onset")
    om0 = contact_onsets(**FRICTION)[0]
    print(f"onset omega = {float(om0)!r} (mu does not enter the free whirl)")
    mf = free_multipliers(om0, **FRICTION)
    print(f"free side: eig(expm(A T)) = {mf} (each double),\n    modulus exp(-zeta T) = "
          f"{float(np.exp(-0.05 * 2 * np.pi / om0))!r}")
    ml = contact_onset_limit(om0, **FRICTION)
    print(f"contact side, R -> delta+: {ml}\n    moduli {np.abs(ml)}")
    for eps in (1e-3, 1e-4, 1e-5, 1e-6):
        om = om0 + eps
        R, phi = contact_whirl(om, **FRICTION)[0]
        xs = contact_whirl_state(om, R, phi)
        (xn, mn, _), dt = timed(periodic_orbit, om, xs, **FRICTION)
        mc = contact_whirl_multipliers(om, R, phi, **FRICTION)
        print(f"omega = onset + {eps:g}: R - delta = {R - 1:.3e}, largest {mc[0]:.8f}; closed form vs numerical "
              f"{_mult_distance(mn, mc):.1e}; distance to the limit {_mult_distance(mc, ml):.1e}  ({dt:.2f} s)")
    print(f"omega = onset - 1e-4: contact whirls {contact_whirl(om0 - 1e-4, **FRICTION)} "
          "(none: R > delta only above onset)")

    print("\n== 4. jeffcott_gravity: first two period doublings by natural-parameter stepping from first contact")
    res, dt = timed(gravity_period_doublings, (0, 1))
    res2, dt2 = timed(gravity_period_doublings, (0, 1), rtol=1e-13, atol=1e-14)
    for (om, _, m), (om2, _, _), q in zip(res, res2, (0.78766808, 0.79620991)):
        print(f"omega_PD = {om!r}  (rtol 1e-13: change {om2 - om:.1e}; quoted {q}: difference {om - q:.1e})"
              f"\n    multipliers {m}")
    print(f"gravity_period_doublings: {dt:.1f} s (rtol 1e-12), {dt2:.1f} s (rtol 1e-13)")

    print("\n== 4'. all special points along the branch (GRAVITY_POINTS, in branch order)")
    for k, (kind, ref, tol) in enumerate(GRAVITY_REFERENCE):
        (kd, om, m), dt = timed(gravity_point, k)
        (_, om2, _), _ = timed(gravity_point, k, rtol=1e-13, atol=1e-14)
        flag = "" if abs(om - ref) <= tol else "  <-- differs from GRAVITY_REFERENCE"
        print(f"{k:2d} {kd:16s} omega = {om:.13f}  (rtol 1e-13 change {om2 - om:+.1e}, bound {tol:.0e}; "
              f"{dt:.1f} s){flag}\n    multipliers {np.round(m, 6)}")

    if "--branch" in argv:
        print("\n== pseudo-arclength continuation from first contact (gravity_branch)")
        (pts, brackets), dt = timed(gravity_branch)
        print(f"{len(pts)} points, {dt:.0f} s")
        for kind, a, b in brackets:
            print(f"  {kind:16s} between omega = {a:.10f} and {b:.10f}")


if __name__ == "__main__":
    main()
