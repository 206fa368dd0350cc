"""A hand-written scipy implementation for the trilinear spring system: the benchmarks' baseline.

What a competent user would write without saltation, for this one model:

* ``solve_ivp`` with DOP853 (rtol 1e-10, atol 1e-12, as saltation's defaults),
  one integration per mode, ended by terminal events;
* the variational equation ``Phi' = A Phi`` integrated alongside the state,
  ``Phi`` jumped at every event by the saltation matrix of eq. (9),
  ``S = I + (f+ - f-) h_x / (h_x f-)``;
* Newton shooting on the period map with the monodromy matrix as its Jacobian,
  converged when ``|r| <= tol (1 + |x0|)`` (saltation's criterion);
* pseudo-arclength continuation of the response curve (the parameter column of
  the Jacobian by a central difference);
* a brute-force diagram: simulate, sample the stroboscopic section on the dense
  output, continue from the previous value's final state.

The contact regions are those of the paper (eqs. 4-7): contact with the first
support holds while ``min(x - x_c, k_f (x - x_c) + c_f x')`` is positive, with
the second while ``max(x + x_c, k_f (x + x_c) + c_f x')`` is negative.  Each
region is entered and left where that (continuous) function crosses zero, so
one event function per region boundary covers every transition of
``saltation.models.trilinear`` including its guards; the surface that fired is
the one of the two that vanishes at the event.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

#: Appendix A of the paper (as ``saltation.models.trilinear.DEFAULTS``).
DEFAULTS = {"m": 1.0, "c": 0.05, "k": 1.0, "x_c": 1.0, "k_f": 4.0, "c_f": 0.5, "f0": 0.2, "omega": 1.2}

FREE, CONTACT_1, CONTACT_2 = 0, 1, 2
MODE_NAMES = ("free", "contact_1", "contact_2")
RTOL, ATOL = 1e-10, 1e-12


@dataclass
class Segment:
    """Result of :meth:`Trilinear.flow`."""

    x1: np.ndarray
    monodromy: np.ndarray | None
    events: list[tuple[str, float]] = field(default_factory=list)  # (surface, time)
    mode1: int = FREE
    nfev: int = 0
    samples: list[np.ndarray] = field(default_factory=list)  # states at the requested sample times


class Trilinear:
    """The trilinear spring system, written out by hand."""

    def __init__(self, rtol: float = RTOL, atol: float = ATOL, max_step: float = np.inf, **params: float):
        self.p = DEFAULTS | params
        self.rtol, self.atol, self.max_step = rtol, atol, max_step

    # -- the model -----------------------------------------------------------------------------
    def matrices(self, mode: int) -> tuple[np.ndarray, np.ndarray]:
        """``x' = A x + b + (0, f0 sin(omega t) / m)`` in a mode."""
        p = self.p
        m, c, k, kf, cf, xc = p["m"], p["c"], p["k"], p["k_f"], p["c_f"], p["x_c"]
        if mode == FREE:
            return np.array([[0.0, 1.0], [-k / m, -c / m]]), np.zeros(2)
        A = np.array([[0.0, 1.0], [-(k + kf) / m, -(c + cf) / m]])
        sign = 1.0 if mode == CONTACT_1 else -1.0
        return A, np.array([0.0, sign * kf * xc / m])

    def initial_mode(self, x: np.ndarray) -> int:
        p = self.p
        if x[0] - p["x_c"] > 0 and p["k_f"] * (x[0] - p["x_c"]) + p["c_f"] * x[1] >= 0:
            return CONTACT_1
        if x[0] + p["x_c"] < 0 and p["k_f"] * (x[0] + p["x_c"]) + p["c_f"] * x[1] <= 0:
            return CONTACT_2
        return FREE

    def region_functions(self):
        """Event functions of the two contact regions (state only), and their surfaces' gradients."""
        p = self.p
        xc, kf, cf = p["x_c"], p["k_f"], p["c_f"]

        def g1(t, y):  # > 0 inside contact region 1
            return min(y[0] - xc, kf * (y[0] - xc) + cf * y[1])

        def g2(t, y):  # < 0 inside contact region 2
            return max(y[0] + xc, kf * (y[0] + xc) + cf * y[1])

        return g1, g2

    def surface_at(self, region: int, x: np.ndarray) -> tuple[str, np.ndarray]:
        """Which of the region's two surfaces vanishes at ``x`` (the other does not), and its gradient."""
        p = self.p
        xc, kf, cf = p["x_c"], p["k_f"], p["c_f"]
        if region == 1:
            a, b, names = x[0] - xc, kf * (x[0] - xc) + cf * x[1], ("h1a", "h1b")
        else:
            a, b, names = x[0] + xc, kf * (x[0] + xc) + cf * x[1], ("h2a", "h2b")
        if abs(a) <= abs(b) / kf:
            return names[0], np.array([1.0, 0.0])
        return names[1], np.array([kf, cf])

    # -- integration -----------------------------------------------------------------------------
    def flow(self, x0, t0: float, t1: float, *, variational: bool = True, mode: int | None = None,
             sample_times: np.ndarray | None = None) -> Segment:
        """Integrate from ``t0`` to ``t1 > t0`` through every contact event.

        ``sample_times`` (increasing, in ``(t0, t1]``): states there are read off the dense output
        (``t_eval``) into ``Segment.samples``.
        """
        p = self.p
        w, f0, m = p["omega"], p["f0"], p["m"]
        x = np.asarray(x0, dtype=float).copy()
        Phi = np.eye(2)
        mode = self.initial_mode(x) if mode is None else mode
        g1, g2 = self.region_functions()
        t = float(t0)
        seg = Segment(x1=x, monodromy=None, mode1=mode)
        n_events = 0
        while True:
            A, b = self.matrices(mode)

            if variational:
                def rhs(tt, y, A=A, b=b):
                    dy = np.empty(6)
                    dy[:2] = A @ y[:2] + b
                    dy[1] += f0 * math.sin(w * tt) / m
                    dy[2:] = (A @ y[2:].reshape(2, 2)).ravel()
                    return dy
                y0 = np.concatenate([x, Phi.ravel()])
            else:
                def rhs(tt, y, A=A, b=b):
                    dy = A @ y + b
                    dy[1] += f0 * math.sin(w * tt) / m
                    return dy
                y0 = x

            # the events that leave the current mode, in the direction that leaves it
            if mode == FREE:
                e1 = lambda tt, y: g1(tt, y)  # noqa: E731
                e1.terminal, e1.direction = True, 1.0
                e2 = lambda tt, y: g2(tt, y)  # noqa: E731
                e2.terminal, e2.direction = True, -1.0
                events, targets, regions = [e1, e2], [CONTACT_1, CONTACT_2], [1, 2]
            elif mode == CONTACT_1:
                e1 = lambda tt, y: g1(tt, y)  # noqa: E731
                e1.terminal, e1.direction = True, -1.0
                events, targets, regions = [e1], [FREE], [1]
            else:
                e2 = lambda tt, y: g2(tt, y)  # noqa: E731
                e2.terminal, e2.direction = True, 1.0
                events, targets, regions = [e2], [FREE], [2]

            t_eval = None
            if sample_times is not None:
                t_eval = sample_times[(sample_times > t) & (sample_times <= t1)]
            sol = solve_ivp(rhs, (t, t1), y0, method="DOP853", rtol=self.rtol, atol=self.atol,
                            events=events, max_step=self.max_step, t_eval=t_eval)
            seg.nfev += sol.nfev
            if sample_times is not None and len(sol.t):
                seg.samples.extend(np.asarray(sol.y)[:2].T.copy())
            if sol.status == -1:
                raise RuntimeError(f"solve_ivp failed at t = {sol.t[-1]}: {sol.message}")
            if sol.status == 0:  # reached t1
                y = sol.y[:, -1]
                seg.x1 = y[:2].copy()
                seg.monodromy = y[2:].reshape(2, 2).copy() if variational else None
                seg.mode1 = mode
                return seg
            # an event ended the integration
            k = next(i for i, te in enumerate(sol.t_events) if len(te))
            te, ye = sol.t_events[k][0], sol.y_events[k][0]
            target = targets[k]
            surface, hx = self.surface_at(regions[k], ye[:2])
            if variational:
                forcing = np.array([0.0, f0 * math.sin(w * te) / m])
                A2, b2 = self.matrices(target)
                f_minus = A @ ye[:2] + b + forcing
                f_plus = A2 @ ye[:2] + b2 + forcing
                S = np.eye(2) + np.outer(f_plus - f_minus, hx) / (hx @ f_minus)  # eq. (9), h_t = 0
                Phi = S @ ye[2:].reshape(2, 2)
            x = ye[:2].copy()
            t = te
            mode = target
            seg.events.append((surface, te))
            n_events += 1
            if n_events > 100_000:
                raise RuntimeError("too many events")

    # -- periodic orbits ----------------------------------------------------------------------
    def period(self) -> float:
        return 2.0 * math.pi / self.p["omega"]

    def shoot(self, x0, *, tol: float = 1e-10, max_iter: int = 30):
        """Newton on the period map from ``x0``; returns (state, monodromy, multipliers, iterations, events)."""
        x = np.asarray(x0, dtype=float).copy()
        T = self.period()
        for it in range(max_iter + 1):
            seg = self.flow(x, 0.0, T)
            r = seg.x1 - x
            if np.linalg.norm(r) <= tol * (1.0 + np.linalg.norm(x)):
                return x, seg.monodromy, np.linalg.eigvals(seg.monodromy), it, seg.events
            x = x + np.linalg.solve(seg.monodromy - np.eye(2), -r)
        raise RuntimeError(f"Newton did not converge in {max_iter} iterations")

    def continuation(self, x0, omega0: float, omega1: float, *, ds: float = 0.01, ds_max: float = 0.01,
                     max_points: int = 5000, tol: float = 1e-10):
        """Pseudo-arclength continuation of the response curve over omega in [omega0, omega1].

        Unknowns ``(x0, omega)``; residual ``phi_T(x0) - x0`` with ``T = 2 pi / omega``; the Jacobian's
        state block is ``M - I``, its omega column a central difference.  Returns a list of
        (omega, state, multipliers).
        """
        lo, hi = min(omega0, omega1), max(omega0, omega1)

        def residual(u, with_jac):
            sys_ = Trilinear(self.rtol, self.atol, self.max_step, **(self.p | {"omega": u[2]}))
            seg = sys_.flow(u[:2], 0.0, sys_.period())
            r = seg.x1 - u[:2]
            if not with_jac:
                return r, None, seg
            h = 1e-6 * max(1.0, abs(u[2]))
            rp = Trilinear(self.rtol, self.atol, self.max_step, **(self.p | {"omega": u[2] + h}))
            rm = Trilinear(self.rtol, self.atol, self.max_step, **(self.p | {"omega": u[2] - h}))
            dr = (rp.flow(u[:2], 0.0, rp.period(), variational=False).x1
                  - rm.flow(u[:2], 0.0, rm.period(), variational=False).x1) / (2 * h)
            J = np.column_stack([seg.monodromy - np.eye(2), dr])
            return r, J, seg

        # first point
        x, M, mu, _, _ = Trilinear(self.rtol, self.atol, self.max_step, **(self.p | {"omega": omega0})).shoot(x0, tol=tol)
        u = np.array([x[0], x[1], omega0])
        _, J, seg = residual(u, True)
        tangent = _null_vector(J)
        if tangent[2] * (omega1 - omega0) < 0:
            tangent = -tangent
        points = [(omega0, x.copy(), mu)]
        step = ds
        while len(points) < max_points:
            pred = u + step * tangent
            v = pred.copy()
            ok = False
            for _ in range(8):
                r, J, seg = residual(v, True)
                F = np.append(r, tangent @ (v - pred))
                if np.linalg.norm(F) <= tol * (1.0 + np.linalg.norm(v)):
                    ok = True
                    break
                v = v + np.linalg.solve(np.vstack([J, tangent]), -F)
            if not ok:
                step *= 0.5
                if step < 1e-6:
                    break
                continue
            new_tangent = _null_vector(J)
            if new_tangent @ tangent < 0:
                new_tangent = -new_tangent
            u, tangent = v, new_tangent
            points.append((u[2], u[:2].copy(), np.linalg.eigvals(seg.monodromy)))
            if not lo <= u[2] <= hi:
                break
            step = min(ds_max, step * 1.5)
        return points

    # -- brute force ------------------------------------------------------------------------
    def brute_force(self, omegas, *, periods: int = 100, transient: int = 100, x0=(0.0, 0.0)):
        """Stroboscopic section after a transient, each omega from the previous final state.

        Two integrations per omega (transient, sampling window), the section points read off the
        dense output with ``t_eval``.  Returns a list of (omega, samples of shape (periods, 2)).
        """
        x = np.asarray(x0, dtype=float)
        mode = None
        out = []
        for w in omegas:
            sys_ = Trilinear(self.rtol, self.atol, self.max_step, **(self.p | {"omega": float(w)}))
            T = sys_.period()
            if transient:
                seg = sys_.flow(x, 0.0, transient * T, variational=False, mode=mode)
                x, mode = seg.x1, seg.mode1
            times = T * np.arange(transient + 1, transient + periods + 1)
            seg = sys_.flow(x, transient * T, times[-1], variational=False, mode=mode, sample_times=times)
            x, mode = seg.x1, seg.mode1
            samples = seg.samples
            out.append((float(w), np.array(samples)))
        return out


def _null_vector(J: np.ndarray) -> np.ndarray:
    _, _, vt = np.linalg.svd(J)
    v = vt[-1]
    return v / np.linalg.norm(v)


def closed_form_no_contact_state(omega: float, **params: float) -> np.ndarray:
    """``(x(0), x'(0))`` of the harmonic response of ``m x'' + c x' + k x = f0 sin(w t)``."""
    p = DEFAULTS | params
    m, c, k, f0 = p["m"], p["c"], p["k"], p["f0"]
    det = (k - m * omega**2) ** 2 + (c * omega) ** 2
    return np.array([-f0 * c * omega / det, f0 * (k - m * omega**2) * omega / det])


if __name__ == "__main__":
    import time

    for w in (0.7, 1.0):
        tri = Trilinear(omega=w)
        guess = closed_form_no_contact_state(w) if w < 0.8 else np.array([-0.42, 0.977])
        t = time.perf_counter()
        x, M, mu, it, ev = tri.shoot(guess + 1e-3)
        print(f"omega={w}: x0={x}, |mu|={np.abs(mu)}, {it} Newton steps, {len(ev)} events, "
              f"{(time.perf_counter() - t) * 1e3:.1f} ms")
