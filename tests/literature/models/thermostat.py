"""A thermostat with hysteresis heating a room whose outside temperature varies daily (a forced relay).

The textbook hybrid automaton of the thermostat (Henzinger, *The theory of hybrid automata*, LICS 1996;
Alur et al., Theor. Comput. Sci. 138 (1995) 3-34, the room heated by a switched heater), with Newton's law
of cooling towards a periodic outside temperature: time in days,

    T' = -a (T - T_out(t)) + q u,    T_out(t) = T0 + A cos(omega t),

the heater on (``u = 1``) from the moment ``T`` falls through ``T_low`` until it rises through ``T_high``,
then off (``u = 0``).  The heater's state is memory: the modes ``on`` and ``off`` have no domains, and an
orbit starts in a named mode (``mode0``).  Without the daily swing (``A = 0``) the thermostat cycles with
its own period ``2 ln(3/2) / a = 0.81`` days; the swing locks it to one heating phase a day (a period-1
orbit of the stroboscopic map) above a saddle-node of the map at ``A = 2.858`` (below it the reference map's
attractor has no period up to 16: quasi-periodic or long-period motion).

Reference (numpy/scipy only): the explicit scalar solution in each mode,
``T(t) = T_p(t) + (T(s) - T_p(s)) exp(-a (t - s))`` with the particular solution
``T_p(t) = T0 + q u / a + A a (a cos(omega t) + omega sin(omega t)) / (a^2 + omega^2)``, each switching
instant by ``brentq`` on it (after a grid search for the first crossing in the right direction), the
stroboscopic map over one day from ``t = 0`` in ``off``, and its derivative in closed form,
``P'(T) = exp(-a 2 pi / omega) prod (f+ / f-)`` (the scalar saltation factors at the switches).  The
fixed point by ``brentq`` on ``P(T) - T``; the fold by ``fsolve`` on ``P(T) = T, P'(T) = 1`` in ``(T, A)``.
"""

from __future__ import annotations

import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, LocusStep, Orbit, SweepStep
from scipy.optimize import brentq, fsolve

from saltation import Crossing, Mode, PiecewiseSystem, Transition

DEFAULTS = {"a": 1.0, "q": 20.0, "T0": 10.0, "A": 4.0, "omega": 2 * np.pi, "T_low": 18.0, "T_high": 22.0}


def thermostat(**overrides) -> PiecewiseSystem:
    cooling = "-a*(T - T0 - A*cos(omega*t))"
    return PiecewiseSystem(
        name="literature_thermostat",
        states=["T"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("on", [f"{cooling} + q"]), Mode("off", [cooling])],  # memory: no domains
        surfaces={"hi": "T - T_high", "lo": "T - T_low"},
        transitions=[
            Transition("on", "hi", Crossing.RISING, "off"),
            Transition("off", "lo", Crossing.FALLING, "on"),
        ],
        period="2*pi/omega",
    )


# --- the reference: the explicit scalar solution, brentq for the switching instants -----------------


def _particular(t, u, p):
    a, w = p["a"], p["omega"]
    return p["T0"] + p["q"] * u / a + p["A"] * a * (a * np.cos(w * t) + w * np.sin(w * t)) / (a * a + w * w)


def _solution(t, s, Ts, u, p):
    return _particular(t, u, p) + (Ts - _particular(s, u, p)) * np.exp(-p["a"] * (t - s))


def _field(t, T, u, p):
    return -p["a"] * (T - p["T0"] - p["A"] * np.cos(p["omega"] * t)) + p["q"] * u


def strobe(T: float, mode: str, p, t0: float = 0.0, grid: int = 2000):
    """One day of the thermostat from ``(t0, T, mode)``: the state and mode at ``t0 + 2 pi / omega``, the
    derivative of the end state by the start state, and the switching instants."""
    day = 2 * np.pi / p["omega"]
    t, end, d, switches = t0, t0 + day, 1.0, []
    while True:
        u = 1.0 if mode == "on" else 0.0
        threshold, sign = (p["T_high"], 1.0) if mode == "on" else (p["T_low"], -1.0)
        g = lambda s: sign * (_solution(s, t, T, u, p) - threshold)  # noqa: B023
        ts = np.linspace(t, end, max(int(grid * (end - t) / day), 2) + 1)
        gs = g(ts)
        up = np.nonzero((gs[:-1] < 0.0) & (gs[1:] >= 0.0))[0]
        if len(up) == 0:
            return _solution(end, t, T, u, p), mode, d * np.exp(-p["a"] * (end - t)), switches
        s = brentq(g, ts[up[0]], ts[up[0] + 1], xtol=1e-15, rtol=1e-15)
        d *= np.exp(-p["a"] * (s - t)) * _field(s, threshold, 1.0 - u, p) / _field(s, threshold, u, p)
        switches.append(s)
        t, T, mode = s, threshold, ("off" if mode == "on" else "on")


def fixed_point(p, lo: float = 20.0, hi: float = 21.9) -> float:
    """The stable locked orbit's temperature at ``t = 0`` (``off``), by ``brentq`` on ``P(T) - T``."""
    return brentq(lambda T: strobe(T, "off", p)[0] - T, lo, hi, xtol=1e-14, rtol=1e-15)


def fold(p) -> tuple[float, float]:
    """``(A, T)`` of the saddle-node: ``P(T) = T`` and ``P'(T) = 1`` (``fsolve``, residuals below 1e-12)."""
    def residual(z):
        q = dict(p, A=z[1])
        T1, _, d, _ = strobe(z[0], "off", q)
        return [T1 - z[0], d - 1.0]

    z, _info, _ok, msg = fsolve(residual, [19.5, 2.9], xtol=1e-14, full_output=True)
    assert np.max(np.abs(residual(z))) < 1e-12, (msg, residual(z))
    return float(z[1]), float(z[0])


def _multipliers(p) -> np.ndarray:
    return np.array([strobe(fixed_point(p), "off", p)[2]])


def _fold_expected() -> list[Expected]:
    # fsolve to 1e-12 on the closed form; the library locates the fold by its test function to ~1e-9
    # (it agrees to 1e-14 here)
    return [Expected(("fold",), fold(dict(DEFAULTS))[0], 1e-9)]


SWEEP_A = [2.0, 2.5, 3.5, 6.0]


def _reference_period(p, n_transient: int = 400, n: int = 40) -> tuple[int, float]:
    T, mode = 20.0, "off"
    for _ in range(n_transient):
        T, mode, _, _ = strobe(T, mode, p, grid=400)
    seq = []
    for _ in range(n):
        T, mode, _, _ = strobe(T, mode, p, grid=400)
        seq.append((round(T, 7), mode))
    period = next((k for k in range(1, 17) if all(seq[i] == seq[i + k] for i in range(n - k))), 0)
    return period, T


def _sweep_periods(result) -> None:
    """The attractor's period in days at each amplitude is the reference map's: none up to 16 below the
    saddle-node (A = 2, 2.5), one above it (A = 3.5, 6), where every sample is the locked orbit's state."""
    from saltation.apps.sweeps import attractor_period

    assert not result.failures, result.failures
    for k, A in enumerate(SWEEP_A):
        p = dict(DEFAULTS, A=A)
        ref_period, _ = _reference_period(p)
        samples = result.at(k)
        assert attractor_period(samples, 16) == ref_period, (A, ref_period)
        if ref_period == 1:
            np.testing.assert_allclose(samples[:, 0], fixed_point(p), rtol=0, atol=1e-8)


CASE = LiteratureCase(
    name="thermostat",
    field="control",
    source="Henzinger 1996 (the thermostat automaton), with a daily outside temperature (forced hybrid system)",
    model=thermostat,
    orbit=Orbit(
        parameters=dict(DEFAULTS),
        guess=[20.8],
        mode0="off",
        multipliers=_multipliers,
        state=lambda p: np.array([fixed_point(p)]),
    ),
    # down from A = 4 to the saddle-node at A = 2.87, and back up the unstable locked orbit to A = 5
    branch=BranchStep("A", (2.5, 5.0), _fold_expected, ds=0.05, ds_max=0.1),
    locus=LocusStep("fold", "omega", (5.5, 7.0), lambda w: fold(dict(DEFAULTS, omega=w))[0], tol=1e-8),
    sweep=SweepStep("A", SWEEP_A, _sweep_periods,
                    options={"x0": [20.0], "mode0": "off", "transient": 400, "periods": 40}),
)
