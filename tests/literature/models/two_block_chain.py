"""Two blocks on a moving belt, coupled by a spring, each held by a spring to the wall (stick-slip chain).

Galvanetto, "Some discontinuous bifurcations in a two-block stick-slip system", J. Sound Vib. 248 (2001)
653-669; Galvanetto and Bishop (the one-block system, Meccanica 1999).  Nondimensional, unit masses:

    x1'' = -k1 x1 - kc (x1 - x2) - mu(x1' - V),
    x2'' = -k2 x2 - kc (x2 - x1) - mu(x2' - V),
    mu(w) = F sgn(w) - alpha w + beta w^3   (a velocity-weakening law with a static level F),

``V`` the belt speed.  Written as on paper with ``sign(v_i - V)``: saltation expands it into four slip modes and
the two surfaces ``v_i = V``; a block sticks to the belt (Filippov sliding on its surface) while its spring
force ``f_i`` satisfies ``|f_i| < F``.  The parameters here (``k2 = 1.5`` makes the blocks differ) are ours, not
the paper's; on the branch below the two stick phases never overlap (sliding on both surfaces at once is not
defined in saltation).

Reference (numpy/scipy only): ``solve_ivp`` (DOP853, rtol = atol = 1e-12) with its own stick/slip logic (a
slipping block whose relative velocity reaches 0 sticks if ``|f_i| < F``, else slips the other way; a stuck
block moves with the belt until ``|f_i|`` reaches ``F``).  The Poincare section is the end of block 1's stick
phase (``v1 = V``, ``f1 = -F``, so ``x1 = (kc x2 + F) / (k1 + kc)``): a map of ``(x2, v2)``, its fixed point
by Newton, its Jacobian by central differences (h = 1e-5; 1e-9 between h = 3e-5 and 1e-5).  The monodromy's
multipliers are 1, the map's two, and 0 (block 1's stick phase annihilates a direction).  Block 2 arrives at
its surface twice a period for ``0.449 < V < 0.674``: it crosses with ``f2 > F``, slips forward briefly and
comes back to stick; at both ends of that interval it arrives where ``f2 = F`` (the forward-slip field
tangent to the surface) with ``f2`` decreasing: an invisible tangency, a switching-sliding bifurcation.
Located by ``brentq`` on ``f2 - F`` at the first arrival.  Just above the range, a smooth fold at
``V = 0.69993603`` (``fsolve`` on ``P(z) = z``, ``det(DP - I) = 0``; saltation: 0.6999360305).
"""

from __future__ import annotations

import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, Orbit, SweepStep
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from saltation import Mode, PiecewiseSystem

DEFAULTS = {"k1": 1.0, "k2": 1.5, "kc": 0.5, "F": 1.0, "alpha": 1.0, "beta": 0.3, "V": 0.5}


def two_block_chain(**overrides) -> PiecewiseSystem:
    def friction(i):
        return f"F*sign(v{i} - V) - alpha*(v{i} - V) + beta*(v{i} - V)**3"

    return PiecewiseSystem(
        name="literature_two_block_chain",
        states=["x1", "v1", "x2", "v2"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("slip", ["v1", f"-k1*x1 - kc*(x1 - x2) - ({friction(1)})",
                             "v2", f"-k2*x2 - kc*(x2 - x1) - ({friction(2)})"])],
        surfaces={},
        transitions=[],
    )


# --- the reference: solve_ivp with its own stick/slip logic -----------------------------------------------


def spring(x, p) -> np.ndarray:
    x1, x2 = x[0], x[2]
    return np.array([-p["k1"] * x1 - p["kc"] * (x1 - x2), -p["k2"] * x2 - p["kc"] * (x2 - x1)])


def _rhs(x, s, p) -> np.ndarray:
    f, V = spring(x, p), p["V"]
    out = np.empty(4)
    for i in range(2):
        if s[i] == 0:  # stuck: moves with the belt
            out[2 * i], out[2 * i + 1] = V, 0.0
        else:
            w = x[2 * i + 1] - V
            out[2 * i] = x[2 * i + 1]
            out[2 * i + 1] = f[i] - (p["F"] * s[i] - p["alpha"] * w + p["beta"] * w**3)
    return out


def run(x, s, p, T, stop=None):
    """From state ``x`` with the blocks' modes ``s`` (+1, -1 slip forward/back relative to the belt, 0 stuck)
    for time ``T``, or until ``stop(block, kind)`` holds after an event.  Returns ``(x, s, log, t)``, ``log`` the
    events ``(t, block, kind, modes, state)``."""
    t, x, s, V, log, fresh = 0.0, np.array(x, float), list(s), p["V"], [], {}
    while t < T:
        evs = []
        for i in range(2):
            if s[i] == 0:
                def hi(tt, y, i=i):
                    return spring(y, p)[i] - p["F"]

                def lo(tt, y, i=i):
                    return spring(y, p)[i] + p["F"]

                hi.direction, lo.direction = 1, -1
                evs += [(hi, i, "hi"), (lo, i, "lo")]
            else:
                t_in = fresh.get(i, -1.0)

                def arrive(tt, y, i=i, t_in=t_in):
                    # just after a switch of this block its relative velocity leaves 0 (quadratically out of a
                    # stick phase): no arrival within 1e-6 (solve_ivp would take the start, where w = 0)
                    if t_in >= 0.0 and tt - t_in < 1e-6:
                        return float(s[i])
                    return y[2 * i + 1] - V

                arrive.direction = -s[i]
                evs.append((arrive, i, "v"))
        for e in evs:
            e[0].terminal = True
        modes = list(s)
        sol = solve_ivp(lambda tt, y, modes=modes: _rhs(y, modes, p), (t, T), x, events=[e[0] for e in evs],
                        rtol=1e-12, atol=1e-12, method="DOP853")
        hits = [(sol.t_events[k][0], k) for k in range(len(evs)) if len(sol.t_events[k])]
        if not hits:
            return sol.y[:, -1], s, log, T
        t, k = min(hits)
        x = sol.y_events[k][0].copy()
        _, i, kind = evs[k]
        if kind == "v":
            x[2 * i + 1] = V
            s[i] = 0 if abs(spring(x, p)[i]) < p["F"] else -s[i]
        else:
            s[i] = 1 if kind == "hi" else -1
        if s[i] != 0:
            fresh[i] = t
        else:
            fresh.pop(i, None)
        log.append((t, i, kind, list(s), x.copy()))
        if stop is not None and stop(i, kind):
            return x, s, log, t
    return x, s, log, t


def section_state(z, p) -> np.ndarray:
    """Block 1 at the end of its stick phase (``v1 = V``, spring force ``-F``), block 2 at ``z = (x2, v2)``."""
    x2, v2 = z
    return np.array([(p["kc"] * x2 + p["F"]) / (p["k1"] + p["kc"]), p["V"], x2, v2])


def poincare(z, p, full: bool = False):
    """From the end of block 1's stick phase to the next (block 2 slipping back at the section)."""
    x, s, log, T = run(section_state(z, p), [-1, -1], p, 1e3, stop=lambda i, kind: i == 0 and kind == "lo")
    assert s[1] == -1, "block 2 is not slipping back at the section"
    z1 = np.array([x[2], x[3]])
    return (z1, T, log) if full else z1


def jacobian(z, p, h: float = 1e-5) -> np.ndarray:
    J = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        J[:, j] = (poincare(z + e, p) - poincare(z - e, p)) / (2 * h)
    return J


def fixed_point(p, z0=(-0.33, -0.39)) -> np.ndarray:
    z = np.array(z0, float)
    for _ in range(30):
        dz = -np.linalg.solve(jacobian(z, p) - np.eye(2), poincare(z, p) - z)
        z = z + dz
        if np.max(np.abs(dz)) < 1e-13:
            break
    assert np.max(np.abs(poincare(z, p) - z)) < 1e-12
    return z


def multipliers(p) -> np.ndarray:
    """The nontrivial multipliers: the section map's two and 0."""
    return np.append(np.linalg.eigvals(jacobian(fixed_point(p), p)), 0.0)


def _arrival_excess(V: float, z0) -> float:
    """``f2 - F`` where block 2 first arrives at its surface after the section, and that instant's ``df2/dt``."""
    p = dict(DEFAULTS, V=V)
    z = fixed_point(p, z0)
    _, _, log = poincare(z, p, full=True)
    x = next(e[4] for e in log if e[1] == 1 and e[2] == "v")
    return spring(x, p)[1] - p["F"], -(p["k2"] + p["kc"]) * x[3] + p["kc"] * x[1]


def _switching_sliding() -> list[Expected]:
    out = []
    for lo, hi, z0 in [(0.40, 0.45, (-0.326, -0.331)), (0.67, 0.68, (-0.302, -0.453))]:
        V = brentq(lambda v: _arrival_excess(v, z0)[0], lo, hi, xtol=1e-13)  # noqa: B023
        assert _arrival_excess(V, z0)[1] < 0.0  # f2 falls through F: the tangency is invisible
        # brentq to 1e-13 on a residual accurate to ~1e-11 with slope ~0.05-1; the located point's accuracy added
        out.append(Expected(("switching_sliding",), V, 1e-9))
    return out


def x1_maxima(p, z0=(-0.33, -0.39)):
    """The local maxima of ``x1`` over one period of the reference orbit (``v1`` falling through 0 while block 1
    slips; while it sticks ``v1 = V > 0``), and the period."""
    z = fixed_point(p, z0)
    _, T, log = poincare(z, p, full=True)
    segments = [(0.0, [-1, -1], section_state(z, p))] + [(e[0], e[3], e[4]) for e in log]
    out = []
    for (t0, s, x0), t1 in zip(segments, [e[0] for e in segments[1:]] + [T]):
        if s[0] == 0:
            continue

        def top(t, y):
            return y[1]

        top.direction = -1
        sol = solve_ivp(lambda t, y, s=s: _rhs(y, s, p), (t0, t1), x0, events=top, rtol=1e-12, atol=1e-12,
                        method="DOP853")
        out += [y[0] for y in sol.y_events[0]]
    return np.array(out), T


SWEEP_V = [0.5, 0.6]
SWEEP_PERIOD, SWEEP_PERIODS = 5.0, 10


def _sweep_maxima_on_the_cycle(result) -> None:
    """From the orbit's guess, 100 time units of transient (the map's multipliers are 0.24 and 0.14 in modulus:
    0.24^20 ~ 4e-13): every sampled maximum of ``x1`` is the reference cycle's one maximum, once a period."""
    assert not result.failures, result.failures
    for k, V in enumerate(SWEEP_V):
        maxima, T = x1_maxima(dict(DEFAULTS, V=V))
        assert len(maxima) == 1
        x1 = np.asarray(result.at(k), dtype=float)[:, 0]
        window = SWEEP_PERIOD * SWEEP_PERIODS
        assert np.floor(window / T) <= len(x1) <= np.ceil(window / T), (len(x1), window / T)
        # the maxima come from the dense output at the integration's rtol 1e-10
        np.testing.assert_allclose(x1, maxima[0], rtol=0, atol=1e-8)


CASE = LiteratureCase(
    name="two_block_chain",
    field="mechanics; Filippov benchmark",
    source="Galvanetto, J. Sound Vib. 248 (2001) 653-669 (two-block stick-slip chain on a moving belt)",
    model=two_block_chain,
    # a state in the middle of a slip phase of both blocks (from the reference orbit at V = 0.5)
    orbit=Orbit(parameters=dict(DEFAULTS), guess=[-0.07, -0.36, 0.84, 0.16], period=4.9, multipliers=multipliers),
    branch=BranchStep("V", (0.38, 0.69), _switching_sliding),
    # measured: the sampled maxima within 7e-12 (V = 0.5) and 1.4e-11 (V = 0.6) of the reference's
    sweep=SweepStep("V", SWEEP_V, _sweep_maxima_on_the_cycle,
                    options={"x0": [-0.07, -0.36, 0.84, 0.16], "transient": 20, "periods": SWEEP_PERIODS,
                             "period": SWEEP_PERIOD}),
)
