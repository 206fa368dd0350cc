"""The peak-current-mode boost converter's stroboscopic map in closed form, written without saltation.

Deane (1992); Banerjee and Chakrabarty (1998).  Over one clock period ``T`` from a clock instant with inductor
current ``i0 < I_ref`` and capacitor voltage ``v0``: the switch is ON (``L i' = E``, ``C v' = -v / R``) until the
current reaches ``I_ref`` at ``t_on = L (I_ref - i0) / E``, then OFF (``L i' = E - v``, ``C v' = i - v / R``, an
affine system: its flow is a matrix exponential of the augmented matrix) until the next clock instant.  The
current stays positive in the range used (continuous conduction), and ``t_on < T``.

The derivative of the map is differentiated in closed form through the switching instant ``t_on`` (its
dependence on ``i0``), checked against central differences by :func:`map_jacobian_by_differences`.  The period-1
orbit is the map's fixed point (Newton), and its period doubling the parameter where an eigenvalue of the map's
derivative is -1 (brentq on ``det(DP + I)``).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

DEFAULTS = {"E": 10.0, "L": 1e-3, "C": 12e-6, "R": 20.0, "T": 100e-6, "I_ref": 1.5}


def _off_flow(q: dict, tau: float) -> np.ndarray:
    """The 3 x 3 augmented flow ``[[A, b], [0, 0]]`` of the OFF phase over ``tau``."""
    E, L, C, R = q["E"], q["L"], q["C"], q["R"]
    M = np.array([[0.0, -1.0 / L, E / L], [1.0 / C, -1.0 / (R * C), 0.0], [0.0, 0.0, 0.0]])
    return expm(M * tau)


def strobe(q: dict, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The state at the next clock instant and the map's derivative, from ``x = (i0, v0)`` at a clock instant."""
    E, L, C, R, T, I_ref = (q[k] for k in ("E", "L", "C", "R", "T", "I_ref"))
    i0, v0 = float(x[0]), float(x[1])
    t_on = L * (I_ref - i0) / E
    if not 0.0 < t_on < T:
        raise ValueError(f"the ON phase lasts {t_on:.3g} s, outside (0, T): not the period-1 orbit of this reference")
    v_on = v0 * np.exp(-t_on / (R * C))
    F = _off_flow(q, T - t_on)
    y = F @ np.array([I_ref, v_on, 1.0])
    # derivative: d t_on / d i0 = -L / E; the OFF phase starts at (I_ref, v_on) and lasts T - t_on
    dvon = np.array([v_on / (R * C) * L / E, np.exp(-t_on / (R * C))])  # d v_on / d (i0, v0)
    dstart = np.array([[0.0, 0.0], dvon])  # d (I_ref, v_on) / d (i0, v0)
    dtau = np.array([L / E, 0.0])  # d (T - t_on) / d (i0, v0)
    A = F[:2, :2]
    f_end = np.array([(E - y[1]) / L, (y[0] - y[1] / R) / C])  # the OFF field at the end
    J = A @ dstart + np.outer(f_end, dtau)
    return y[:2], J


def map_jacobian_by_differences(q: dict, x: np.ndarray, h: float = 1e-7) -> np.ndarray:
    cols = []
    for k in range(2):
        e = np.zeros(2)
        e[k] = h * max(1.0, abs(x[k]))
        cols.append((strobe(q, x + e)[0] - strobe(q, x - e)[0]) / (2 * e[k]))
    return np.array(cols).T


def fixed_point(q: dict, guess=(1.4, 19.0)) -> tuple[np.ndarray, np.ndarray]:
    """The period-1 orbit at a clock instant, and the map's derivative there (Newton to rounding)."""
    x = np.array(guess, dtype=float)
    for _ in range(50):
        y, J = strobe(q, x)
        dx = np.linalg.solve(J - np.eye(2), -(y - x))
        x = x + dx
        if np.linalg.norm(dx) <= 1e-14 * (1.0 + np.linalg.norm(x)):
            break
    return x, strobe(q, x)[1]


def period_doubling(q: dict, lo: float = 1.6, hi: float = 1.8) -> float:
    """The ``I_ref`` where the fixed point's map has an eigenvalue -1 (brentq to 4 eps)."""
    def test(I_ref: float) -> float:
        _, J = fixed_point(dict(q, I_ref=I_ref))
        return float(np.linalg.det(J + np.eye(2)))

    return brentq(test, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps)


def period_two_orbit(q: dict) -> np.ndarray:
    """A point of the period-2 orbit born at the period doubling, where it attracts (just past a supercritical
    doubling): the map iterated from the period-1 orbit moved along the eigenvector of its eigenvalue below -1,
    then Newton on ``P(P(x)) = x``."""
    x1, J = fixed_point(q)
    w, V = np.linalg.eig(J)
    k = int(np.argmin(w.real))
    x = x1 + 1e-3 * np.real(V[:, k]) / np.linalg.norm(V[:, k])
    for _ in range(2000):
        x = strobe(q, x)[0]
    for _ in range(60):
        y1, J1 = strobe(q, x)
        y2, J2 = strobe(q, y1)
        dx = np.linalg.solve(J2 @ J1 - np.eye(2), -(y2 - x))
        x = x + dx
        if np.linalg.norm(dx) <= 1e-14 * (1.0 + np.linalg.norm(x)):
            break
    if np.linalg.norm(x - x1) < 1e-6:
        raise ValueError("Newton went back to the period-1 orbit")
    return x
