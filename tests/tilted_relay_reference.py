"""Closed-form references for the forced relay with a tilted switching line (numpy and scipy only).

    x' = y,   y' = -x - 2 zeta y - F sgn(s) + a cos(omega t),   s = y + kappa x - v.

Independent of saltation: nothing here imports it.

* Smooth modes (``sigma = +1`` where ``s > 0``, ``-1`` where ``s < 0``): ``z' = A z + (0, -sigma F) +
  (0, a cos(omega t))``, ``A = [[0, 1], [-1, -2 zeta]]``.  Their flow is the harmonic response
  ``x_p = -sigma F + c cos(omega t) + d sin(omega t)``, ``c = a (1 - omega^2) / D``,
  ``d = 2 a zeta omega / D``, ``D = (1 - omega^2)^2 + (2 zeta omega)^2``, plus
  ``exp(A tau) (z0 - z_p(t0))``, ``exp(A tau)`` by the eigen-decomposition of ``A``.
* Sliding on ``s = 0`` (``y = v - kappa x``): both fields have the first component ``y``, so Filippov's
  convex combination has ``x' = v - kappa x`` exactly: ``x = v/kappa + (x0 - v/kappa) exp(-kappa (t - t0))``.
* The rate of ``s`` along mode ``sigma`` on the line: ``L_sigma = G(t, x) - sigma F``,
  ``G = (kappa - 2 zeta) v - (1 + kappa^2 - 2 zeta kappa) x + a cos(omega t)``.  Sliding region
  ``|G| < F``; the sliding motion leaves into ``s < 0`` where ``G = -F``, into ``s > 0`` where ``G = F``.
* Grazing-sliding of the ``s < 0`` slip orbit (its harmonic response): along it
  ``s = kappa F - v + A sqrt(kappa^2 + omega^2) cos(omega t - psi)``, ``A = a / sqrt(D)``,
  ``psi = atan2(kappa d - omega c, kappa c + omega d)``; it touches the line at
  ``v = kappa F + A sqrt(kappa^2 + omega^2)``, at ``omega t = psi``, where ``L_- = 0`` and
  ``L_+ = -2F < 0`` (the boundary of the sliding region).
* Switching-sliding: the orbit arrives from ``s < 0`` at ``(t_e, x_e)`` where the far side's field is
  tangent, ``G(t_e, x_e) = F`` (``x_e`` explicit in ``t_e`` and ``v``), slides until ``G = -F``, follows
  the ``s < 0`` mode back to the line at ``t_e + T``, ``x_e``: two equations in ``(t_e, v)``, fsolve.
  The tangency is invisible from ``s > 0`` where ``d2s/dt2 < 0`` along the ``plus`` field there.

Event times are first roots on a grid (4001 points a period) refined by brentq.  :func:`brute_force`
integrates the Filippov system without any closed form (scipy's DOP853 with event location) to check
the closed forms.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve

DEFAULTS = {"zeta": 0.1, "F": 0.5, "a": 1.0, "omega": 0.8, "kappa": 0.5, "v": 2.0}
EPS = 4 * np.finfo(float).eps


def params(**overrides) -> dict:
    return DEFAULTS | overrides


def period(p) -> float:
    return 2 * np.pi / p["omega"]


def _solve(fun, guess, p, what):
    """fsolve to the last bit, then a check of the residual (1e-12)."""
    u, _, _, msg = fsolve(fun, guess, args=(p,), xtol=1e-14, full_output=True)
    res = np.abs(fun(u, p)).max()
    if res > 1e-12:
        raise ValueError(f"{what} did not converge (residual {res:.1e}: {msg})")
    return u


# -- the smooth modes --------------------------------------------------------------------------------
def _harmonic(p):
    w, z, a = p["omega"], p["zeta"], p["a"]
    D = (1 - w**2) ** 2 + (2 * z * w) ** 2
    return a * (1 - w**2) / D, a * 2 * z * w / D


def response(t, sigma, p):
    """The harmonic response of mode ``sigma`` (its periodic slip orbit): shape (len(t), 2) or (2,)."""
    t = np.asarray(t, dtype=float)
    w = p["omega"]
    c, d = _harmonic(p)
    x = -sigma * p["F"] + c * np.cos(w * t) + d * np.sin(w * t)
    y = w * (-c * np.sin(w * t) + d * np.cos(w * t))
    return np.stack([x, y], axis=-1)


def _expm(tau, p):
    """``exp(A tau)`` for an array of ``tau``, by the eigen-decomposition of ``A``: shape (len(tau), 2, 2)."""
    A = np.array([[0.0, 1.0], [-1.0, -2 * p["zeta"]]])
    lam, V = np.linalg.eig(A)
    return np.einsum("ij,mj,jk->mik", V, np.exp(np.outer(np.atleast_1d(tau), lam)), np.linalg.inv(V)).real


def mode_flow(z0, t0, ts, sigma, p):
    """Mode ``sigma``'s flow from ``(t0, z0)`` at the times ``ts``: shape (len(ts), 2)."""
    ts = np.atleast_1d(np.asarray(ts, dtype=float))
    return response(ts, sigma, p) + _expm(ts - t0, p) @ (np.asarray(z0, dtype=float) - response(t0, sigma, p))


def indicator(z, p):
    z = np.asarray(z, dtype=float)
    return z[..., 1] + p["kappa"] * z[..., 0] - p["v"]


def field(t, z, sigma, p):
    x, y = z
    return np.array([y, -x - 2 * p["zeta"] * y - sigma * p["F"] + p["a"] * np.cos(p["omega"] * t)])


def s_rate(t, z, sigma, p):
    """``h_x f_sigma + h_t`` (``h_t = 0``): the rate of ``s`` along mode ``sigma``."""
    return p["kappa"] * z[1] + field(t, z, sigma, p)[1]


def s_curvature(t, z, sigma, p):
    """``d2s/dt2`` along mode ``sigma`` (``y'' = -y - 2 zeta y' - a omega sin(omega t)``)."""
    f = field(t, z, sigma, p)
    ydd = -z[1] - 2 * p["zeta"] * f[1] - p["a"] * p["omega"] * np.sin(p["omega"] * t)
    return p["kappa"] * f[1] + ydd


def first_root(g, a, b, rising=None, num=4001):
    """The first zero of ``g`` (vectorised) in ``(a, b]`` on a grid of ``num`` points, rising, falling or
    either, refined by brentq; None if there is none on the grid."""
    ts = np.linspace(a, b, num)
    v = g(ts)
    if rising is True:
        hit = (v[:-1] < 0) & (v[1:] >= 0)
    elif rising is False:
        hit = (v[:-1] > 0) & (v[1:] <= 0)
    else:
        hit = np.sign(v[:-1]) != np.sign(v[1:])
    k = np.nonzero(hit)[0]
    if not len(k):
        return None
    k = k[0]
    return brentq(lambda t: float(np.atleast_1d(g(np.array([t])))[0]), ts[k], ts[k + 1], xtol=1e-15, rtol=EPS)


def mode_arrival(z0, t0, sigma, p, span=None, skip=1e-9):
    """The first time after ``t0`` where mode ``sigma``'s flow reaches ``s = 0`` (rising for ``sigma = -1``,
    falling for ``+1``), and the state there; None if not within ``span`` (a period by default)."""
    span = period(p) if span is None else span
    def g(ts):
        return indicator(mode_flow(z0, t0, ts, sigma, p), p)

    t = first_root(g, t0 + skip, t0 + span, rising=(sigma < 0))
    return None if t is None else (t, mode_flow(z0, t0, [t], sigma, p)[0])


# -- the sliding motion --------------------------------------------------------------------------------
def G(t, x, p):
    """``L_sigma = G - sigma F`` on the line."""
    k, z = p["kappa"], p["zeta"]
    return (k - 2 * z) * p["v"] - (1 + k * k - 2 * z * k) * x + p["a"] * np.cos(p["omega"] * t)


def sliding_x(x0, t0, t, p):
    k, v = p["kappa"], p["v"]
    return v / k + (x0 - v / k) * np.exp(-k * (np.asarray(t, dtype=float) - t0))


def sliding_state(x0, t0, t, p):
    x = sliding_x(x0, t0, t, p)
    return np.stack([x, p["v"] - p["kappa"] * x], axis=-1)


def sliding_exit(x0, t0, p, span=None, skip=1e-9):
    """Where the sliding motion from ``(t0, x0)`` leaves the sliding region: ``(t, x, sigma)``, ``sigma`` the
    mode it leaves into (``G = -F``: into ``s < 0``; ``G = F``: into ``s > 0``); None within ``span``."""
    span = period(p) if span is None else span
    F = p["F"]
    ts = np.linspace(t0 + skip, t0 + span, 4001)
    g = G(ts, sliding_x(x0, t0, ts, p), p)
    out = np.nonzero(np.abs(g) >= F)[0]
    if not len(out):
        return None
    k = out[0]
    if k == 0:
        raise ValueError("the sliding motion starts outside the sliding region")
    sigma = -1 if g[k] < 0 else 1
    t = brentq(lambda t: G(t, sliding_x(x0, t0, t, p), p) - sigma * F, ts[k - 1], ts[k], xtol=1e-15, rtol=EPS)
    return t, float(sliding_x(x0, t0, t, p)), sigma


# -- the orbit with one sliding segment: arrive from s < 0, slide, leave into s < 0 -----------------------
def slide_and_return(t_e, x_e, p):
    """From the arrival ``(t_e, x_e)`` on the line: slide, leave into ``s < 0``, return to the line.
    Returns ``(t_x, x_x, t_r, z_r)``: the exit and the return."""
    t_x, x_x, sigma = sliding_exit(x_e, t_e, p)
    if sigma != -1:
        raise ValueError("the sliding motion leaves into s > 0")
    t_r, z_r = mode_arrival([x_x, p["v"] - p["kappa"] * x_x], t_x, -1, p)
    return t_x, x_x, t_r, z_r


def sliding_orbit_residual(u, p):
    t_e, x_e = u
    _, _, t_r, z_r = slide_and_return(t_e, x_e, p)
    return np.array([t_r - t_e - period(p), z_r[0] - x_e])


def sliding_orbit(p, guess=None):
    """The periodic orbit with one sliding segment: ``(t_e, x_e, t_x, x_x)`` (arrival and exit).  The guess
    ``(t_e, x_e)`` defaults to where the slip orbit of ``s < 0`` (its harmonic response) crosses the line."""
    if guess is None:
        t_a, z_a = mode_arrival(response(0.0, -1, p), 0.0, -1, p)
        guess = [t_a, z_a[0]]
    t_e, x_e = _solve(sliding_orbit_residual, guess, p, "the sliding orbit")
    if not abs(G(t_e, x_e, p)) < p["F"]:
        raise ValueError("at the arrival the far side's field does not push back: no sliding")
    t_x, x_x, _, _ = slide_and_return(t_e, x_e, p)
    return t_e, x_e, t_x, x_x


def orbit_state(t, orbit, p):
    """The state of the periodic sliding orbit ``(t_e, x_e, t_x, x_x)`` at time ``t``."""
    t_e, x_e, t_x, x_x = orbit
    tau = t_e + (t - t_e) % period(p)
    if tau <= t_x:
        return sliding_state(x_e, t_e, tau, p)
    return mode_flow([x_x, p["v"] - p["kappa"] * x_x], t_x, [tau], -1, p)[0]


# -- grazing-sliding --------------------------------------------------------------------------------------
def grazing_sliding(p2_value=None, p2="kappa", **fixed):
    """``(v, t_touch)`` at the grazing-sliding of the ``s < 0`` slip orbit, ``t_touch`` in ``[0, T)``:
    ``v = kappa F + A sqrt(kappa^2 + omega^2)``."""
    p = params(**fixed) | ({} if p2_value is None else {p2: p2_value})
    c, d = _harmonic(p)
    k, w = p["kappa"], p["omega"]
    v = k * p["F"] + np.hypot(c, d) * np.hypot(k, w)
    psi = np.arctan2(k * d - w * c, k * c + w * d) % (2 * np.pi)
    return float(v), float(psi / w)


def grazing_sliding_by_root(p2_value=None, p2="kappa", **fixed):
    """The same by one scalar root: the maximum of ``s + v`` along the slip orbit (brentq on ``ds/dt = 0``),
    a check of the closed form."""
    p = params(**fixed) | ({} if p2_value is None else {p2: p2_value})
    T = period(p)
    q = p | {"v": 0.0}

    def rate(ts):
        return np.array([s_rate(t, response(t, -1, q), -1, q) for t in np.atleast_1d(ts)])

    t_max = first_root(rate, 0.0, T, rising=False)
    if t_max is None:  # the maximum at the section: look across it
        t_max = first_root(rate, -T / 2, T / 2, rising=False) % T
    return float(indicator(response(t_max, -1, q), q)), float(t_max)


# -- switching-sliding --------------------------------------------------------------------------------------
def tangent_arrival_x(t_e, v, p):
    """``x`` on the line where the far side's field is tangent: ``G(t_e, x) = F``."""
    k, z = p["kappa"], p["zeta"]
    return ((k - 2 * z) * v + p["a"] * np.cos(p["omega"] * t_e) - p["F"]) / (1 + k * k - 2 * z * k)


def switching_sliding_residual(u, p):
    t_e, v = u
    q = p | {"v": v}
    x_e = tangent_arrival_x(t_e, v, q)
    _, _, t_r, z_r = slide_and_return(t_e, x_e, q)
    return np.array([t_r - t_e - period(q), z_r[0] - x_e])


def switching_sliding_point(p2_value=None, p2="kappa", guess=(6.54, 2.36), **fixed):
    """``(v, t_e, x_e, curvature)`` at the switching-sliding: fsolve in ``(t_e, v)`` from ``guess``; ``t_e``
    reduced to ``[0, T)``; ``curvature`` is ``d2s/dt2`` along the ``plus`` field at the arrival (negative:
    invisible from ``s > 0``)."""
    p = params(**fixed) | ({} if p2_value is None else {p2: p2_value})
    t_e, v = _solve(switching_sliding_residual, guess, p, "the switching-sliding")
    q = p | {"v": v}
    x_e = tangent_arrival_x(t_e, v, q)
    return float(v), float(t_e % period(q)), float(x_e), float(s_curvature(t_e, [x_e, v - q["kappa"] * x_e], 1, q))


def switching_sliding_orbit(p2_value=None, p2="kappa", guess=(6.54, 2.36), **fixed):
    """The orbit at the switching-sliding: ``(parameters, (t_e, x_e, t_x, x_x))``."""
    v, t_e, x_e, _ = switching_sliding_point(p2_value, p2, guess, **fixed)
    q = params(**fixed) | ({} if p2_value is None else {p2: p2_value}) | {"v": v}
    t_x, x_x, _, _ = slide_and_return(t_e, x_e, q)
    return q, (t_e, x_e, t_x, x_x)


def switching_sliding_walk(p2_values, p2="kappa", start=None, guess=(6.54, 2.36), step=0.01, **fixed):
    """The switching-sliding points ``(v, t_e, x_e, curvature)`` at the given values of ``p2``, walked from
    ``start`` (the value of ``p2`` where ``guess = (t_e, v)`` holds; the default's by default) outwards in
    steps of at most ``step``, each solution the next one's guess."""
    start = params(**fixed)[p2] if start is None else float(start)
    values = np.atleast_1d(np.asarray(p2_values, dtype=float))
    out = [None] * len(values)
    for side in (values >= start, values < start):
        u, here = np.asarray(guess, dtype=float), start
        for i in sorted(np.nonzero(side)[0], key=lambda i: abs(values[i] - start)):
            target = values[i]
            steps = max(1, int(np.ceil(abs(target - here) / step)))
            for value in np.linspace(here, target, steps + 1)[1:]:
                point = switching_sliding_point(value, p2, guess=u, **fixed)
                T = period(params(**fixed) | {p2: value})
                t_e = u[0] + (point[1] - u[0] + T / 2) % T - T / 2  # continuous, not reduced modulo T
                u = np.array([t_e, point[0]])
            out[i], here = point, target
    return out


def switching_sliding(p2_values, p2="kappa", start=None, guess=(6.54, 2.36), **fixed):
    """``v`` along the switching-sliding curve at the given values of ``p2`` (:func:`switching_sliding_walk`)."""
    return np.array([pt[0] for pt in switching_sliding_walk(p2_values, p2, start, guess, **fixed)])


# -- brute force: scipy's solve_ivp with events, Filippov's rules on the line -----------------------------------
def brute_force(z0, t0, t1, p, rtol=1e-12, atol=1e-14, max_step=0.02, max_events=50):
    """Integrate the Filippov system numerically, with no closed form: the two modes and the sliding motion
    (Filippov's convex combination ``alpha f_+ + (1 - alpha) f_-`` tangent to the line, integrated as an ODE
    in ``(x, y)``) by DOP853 with event location.  A start on the line (to 1e-12) inside the sliding region
    slides.  Steps are at most ``max_step`` long, so that no shallow crossing of the line passes between
    two steps unseen.  Returns the final state and the events ``[(t, kind)]``, kind ``crossing``, ``sliding_start``
    or ``sliding_end``."""
    F = p["F"]
    z = np.asarray(z0, dtype=float)
    t = float(t0)
    events = []
    s0 = indicator(z, p)
    if abs(s0) <= 1e-12 * (1.0 + np.abs(z).max()):
        if not abs(G(t, z[0], p)) < F:
            raise ValueError("a start on the line outside the sliding region")
        state = "sliding"
        z = np.array([z[0], p["v"] - p["kappa"] * z[0]])
    else:
        state = "minus" if s0 < 0 else "plus"

    def filippov(t, z):
        lp, lm = s_rate(t, z, 1, p), s_rate(t, z, -1, p)
        alpha = lm / (lm - lp)
        return alpha * field(t, z, 1, p) + (1 - alpha) * field(t, z, -1, p)

    while t < t1 and len(events) < max_events:
        if state in ("minus", "plus"):
            sigma = -1 if state == "minus" else 1

            def hit(t, z, *_):
                return indicator(z, p)

            hit.terminal, hit.direction = True, -sigma
            sol = solve_ivp(field, (t, t1), z, method="DOP853", rtol=rtol, atol=atol,
                            max_step=max_step, events=hit, args=(sigma, p))
            if sol.status != 1:
                return sol.y[:, -1], events
            t, z = float(sol.t_events[0][0]), sol.y_events[0][0]
            # the far side's field pushes back: sliding (also where it is tangent to rounding, the limit from the
            # sliding side: a crossing there would start on the line and could miss its own return at once)
            if s_rate(t, z, -sigma, p) * sigma > -1e-12:
                events.append((t, "sliding_start"))
                state = "sliding"
            else:
                events.append((t, "crossing"))
                state = "plus" if sigma < 0 else "minus"
            z = np.array([z[0], p["v"] - p["kappa"] * z[0]])
        else:
            def into_minus(t, z):  # L_- falls through zero
                return s_rate(t, z, -1, p)

            def into_plus(t, z):  # L_+ rises through zero
                return s_rate(t, z, 1, p)

            into_minus.terminal = into_plus.terminal = True
            into_minus.direction, into_plus.direction = -1, 1
            sol = solve_ivp(filippov, (t, t1), z, method="DOP853", rtol=rtol, atol=atol, max_step=max_step,
                            events=[into_minus, into_plus])
            if sol.status != 1:
                return sol.y[:, -1], events
            which = 0 if len(sol.t_events[0]) else 1
            t, z = float(sol.t_events[which][0]), sol.y_events[which][0]
            events.append((t, "sliding_end"))
            state = "minus" if which == 0 else "plus"
    return z, events


if __name__ == "__main__":  # a self-test: the closed forms against the brute-force integration
    p = params(v=2.5)
    orbit = sliding_orbit(p)
    z0 = orbit_state(0.0, orbit, p)
    z1, events = brute_force(z0, 0.0, period(p), p)
    print("sliding orbit at v = 2.5:", orbit, "state at t = 0:", z0)
    print("  brute force over a period: |z(T) - z(0)| =", np.abs(z1 - z0).max(), "events", events)
    print("grazing-sliding (v, t):", grazing_sliding(), "by a root:", grazing_sliding_by_root())
    print("switching-sliding (v, t_e, x_e, d2s/dt2 of plus):", switching_sliding_point())
