"""Periodically forced leaky integrate-and-fire neuron: fire at the threshold and reset to rest.

Keener, Hoppensteadt and Rinzel (SIAM J. Appl. Math. 41, 1981); Coombes and Bressloff (Phys. Rev. E 60, 1999).
Dimensionless: ``v' = -v + I + A cos(omega t)``; when ``v`` reaches 1 the neuron fires and ``v`` is reset to 0
(the reset forgets the state: the next firing time depends on the last one only).  With ``omega = 2 pi`` the
forcing period is 1; with ``A = 0.3`` the neuron fires once per forcing period (1:1 phase locking) for ``I``
between about 1.54 and 1.62 (the natural period ``ln(I / (I - 1))`` is near 1 there).

Reference (numpy/scipy only): the explicit solution between spikes, the firing-time map ``t_n -> t_{n+1}``
(the first root of ``v = 1`` by a scan and ``brentq``), and its derivative in closed form,
``F'(t_n) = exp(-(t_{n+1} - t_n)) (I + A cos(omega t_n)) / (I - 1 + A cos(omega t_{n+1}))``.  A 1:1 locked
orbit is a root of ``F(t) - t - T``; its Floquet multiplier (of the stroboscopic map) is ``F'`` there.  The
edge of the 1:1 tongue is a saddle-node of the firing map: the minimum over ``t`` of ``F(t) - t - T`` is zero
(inner root of ``F' = 1`` by ``brentq``, outer ``brentq`` in ``I``), and so is its curve in ``A``.  The sweep is checked against the
reference's stroboscopic map and its rotation number.
"""

from __future__ import annotations

import itertools

import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, LocusStep, Orbit, SweepStep
from scipy.optimize import brentq

from saltation import Crossing, Mode, PiecewiseSystem, Transition

DEFAULTS = {"I": 1.58, "A": 0.3, "omega": 2 * np.pi}
T0 = 0.75  # the section: no orbit of the branch below fires at this phase of the forcing
EPS = 4 * np.finfo(float).eps


def lif_forced(**overrides) -> PiecewiseSystem:
    return PiecewiseSystem(
        name="literature_lif_forced",
        states=["v"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("subthreshold", ["-v + I + A*cos(omega*t)"])],
        surfaces={"threshold": "v - 1"},
        transitions=[Transition("subthreshold", "threshold", Crossing.RISING, "subthreshold", reset=["0"])],
        period="2*pi/omega",
    )


# ---------------------------------------------------------------------------------------------------------
# the reference: explicit solution, firing-time map, stroboscopic map (numpy/scipy only)

def _vp(q, t):
    """The periodic particular solution of ``v' = -v + A cos(omega t)``."""
    w = q["omega"]
    return q["A"] * (np.cos(w * t) + w * np.sin(w * t)) / (1.0 + w * w)


def _v(q, t0, v0, t):
    """The voltage at ``t`` from ``v0`` at ``t0``, before any spike."""
    e = np.exp(-(t - t0))
    return v0 * e + q["I"] * (1.0 - e) + _vp(q, t) - e * _vp(q, t0)


def _dv(q, t0, v0, t):
    return -_v(q, t0, v0, t) + q["I"] + q["A"] * np.cos(q["omega"] * t)


def _first_spike(q, t0, v0, t_end=np.inf):
    """The first instant after ``t0`` where ``v`` reaches 1 (``None`` before ``t_end``): a scan in steps of
    ``T / 400`` (one forcing period at a time, vectorized); in a step where ``v'`` turns from rising to
    falling, the local maximum is checked too (a threshold crossing hidden between two scan points)."""
    T = 2 * np.pi / q["omega"]
    f = lambda t: _v(q, t0, v0, t) - 1.0
    df = lambda t: _dv(q, t0, v0, t)
    a = t0
    while a < t_end:
        ts = np.minimum(a + np.arange(401) * (T / 400), t_end)
        above = f(ts) >= 0.0
        d = df(ts)
        peaks = (d[:-1] > 0.0) & (d[1:] < 0.0)
        for k in np.flatnonzero(above[1:] | peaks):
            if above[k + 1]:
                return brentq(f, ts[k], ts[k + 1], xtol=1e-15, rtol=EPS)
            if peaks[k]:
                tm = brentq(df, ts[k], ts[k + 1], xtol=1e-15, rtol=EPS)
                if f(tm) >= 0.0:
                    return brentq(f, ts[k], tm, xtol=1e-15, rtol=EPS)
        a = ts[-1]
        if a - t0 > 1000 * T:
            raise RuntimeError("no spike within 1000 forcing periods")
    return None


def firing_map(q, t0):
    """The next firing time after a spike at ``t0``, and the map's derivative in closed form."""
    t1 = _first_spike(q, t0, 0.0)
    w, I, A = q["omega"], q["I"], q["A"]
    d = np.exp(-(t1 - t0)) * (I + A * np.cos(w * t0)) / (I - 1.0 + A * np.cos(w * t1))
    return t1, d


def _locked_phase(q, lo, hi):
    """The firing phase of a 1:1 orbit, a root of ``F(t) - t - T`` in ``[lo, hi]``."""
    T = 2 * np.pi / q["omega"]
    return brentq(lambda t: firing_map(q, t)[0] - t - T, lo, hi, xtol=1e-15, rtol=EPS)


def _stable_phase(q):
    """The stable 1:1 orbit's firing phase (the root of ``F(t) - t - T`` where ``F' < 1``), from a scan."""
    T = 2 * np.pi / q["omega"]
    ts = np.linspace(0.0, T, 201)
    g = [firing_map(q, t)[0] - t - T for t in ts]
    for k in range(200):
        if g[k] > 0.0 >= g[k + 1]:  # F(t) - t falls through T: F' < 1
            return _locked_phase(q, ts[k], ts[k + 1])
    raise ValueError("no stable 1:1 orbit")


def multipliers(p):
    q = dict(p)
    t = _stable_phase(q)
    return np.array([firing_map(q, t)[1]])


def state(p):
    """The stable orbit's voltage at the section ``t = T0``, from its last spike before ``T0``."""
    q = dict(p)
    T = 2 * np.pi / q["omega"]
    t = _stable_phase(q)
    t_last = t + np.floor((T0 - t) / T) * T
    return np.array([_v(q, t_last, 0.0, T0)])


def tongue_edge(q, lo=1.50, hi=1.56):
    """The lower edge of the 1:1 tongue in ``I``: the minimum of ``F(t) - t - T`` over ``t`` is zero (a
    saddle-node of the firing map; the branch of 1:1 orbits turns there)."""
    def lowest(I):
        r = dict(q, I=I)
        T = 2 * np.pi / r["omega"]
        ts = np.linspace(0.0, T, 101)
        d = np.array([firing_map(r, t)[1] - 1.0 for t in ts])
        k = next(k for k in range(100) if d[k] < 0.0 <= d[k + 1])  # F' - 1 rises through 0: the minimum
        tm = brentq(lambda t: firing_map(r, t)[1] - 1.0, ts[k], ts[k + 1], xtol=1e-15, rtol=EPS)
        return firing_map(r, tm)[0] - tm - T

    return brentq(lowest, lo, hi, xtol=1e-15, rtol=EPS)


def strobe(q, t0, v0):
    """The reference's stroboscopic map: the voltage one forcing period after ``(t0, v0)``, and the number
    of spikes on the way."""
    T = 2 * np.pi / q["omega"]
    t, v, spikes = t0, v0, 0
    while True:
        ts = _first_spike(q, t, v, t0 + T)
        if ts is None:
            return _v(q, t, v, t0 + T), spikes
        t, v, spikes = ts, 0.0, spikes + 1


def rotation_number(q, n=400, skip=200):
    """Spikes per forcing period, from the firing map."""
    T = 2 * np.pi / q["omega"]
    t = 0.0
    for _ in range(skip):
        t = firing_map(q, t)[0]
    t1 = t
    for _ in range(n):
        t = firing_map(q, t)[0]
    return n * T / (t - t1)


# ---------------------------------------------------------------------------------------------------------

def _fold():
    # the nested brentq to a few eps; the located fold's own accuracy is added by the test
    return [Expected(("fold",), tongue_edge(dict(DEFAULTS)), 1e-9)]


def _tongue_edge_in_A(A: float) -> float:
    """The curve of the tongue's lower edge in the forcing amplitude: the nested ``brentq`` at each ``A``.  (It
    agrees to 1e-15 with the straight line ``I = e / (e - 1) - A / sqrt(1 + omega^2)``: a spike at ``t`` followed
    by one exactly a period later needs ``(I + v_p(t)) (1 - e^{-T}) = 1``, lowest where ``v_p`` is largest.)"""
    return tongue_edge(dict(DEFAULTS, A=A), 1.30, 1.58)


SWEEP_I = [1.05, 1.08, 1.16, 1.30, 1.40, 1.58, 2.00]


def _sweep_follows_the_map(result) -> None:
    """At each ``I``: every sampled section state is the reference stroboscopic map's image of the one before,
    and where the reference's rotation number is a ratio ``p/q`` with small ``q`` (a locked orbit), the sweep
    repeats after ``q`` forcing periods (and not within 8 where it is not locked)."""
    from fractions import Fraction

    assert len(result.failures) == 0
    for k, I in enumerate(SWEEP_I):
        q = dict(DEFAULTS, I=I)
        x = np.asarray(result.at(k), dtype=float)[:, 0]
        assert len(x) == 200
        for a, b in itertools.pairwise(x):
            y, _ = strobe(q, 0.0, a)
            # the reset forgets: one period amplifies a sample's error by at most exp(-T) times f+/f-
            assert abs(y - b) <= 1e-7, (I, a, b, y)
        rho = rotation_number(q)
        ratio = Fraction(rho).limit_denominator(8)
        locked = abs(rho - float(ratio)) < 1e-9
        tail = x[100:]
        period = next((k for k in range(1, 9) if np.max(np.abs(tail[k:] - tail[:-k])) <= 1e-6), 0)
        # locked p:q -> the section repeats after q forcing periods; otherwise not within 8
        assert period == (ratio.denominator if locked else 0), (I, rho, ratio, period)


CASE = LiteratureCase(
    name="lif_forced",
    field="neuroscience",
    source="Keener, Hoppensteadt and Rinzel 1981; Coombes and Bressloff 1999 (forced leaky integrate-and-fire)",
    model=lif_forced,
    orbit=Orbit(parameters=dict(DEFAULTS), guess=[0.8], t0=T0, multipliers=multipliers, state=state),
    # the stable 1:1 orbit, down to the tongue's lower edge, and back along the unstable 1:1 orbit
    branch=BranchStep("I", (1.52, 1.60), _fold, ds=0.005, ds_max=0.01),
    # the tongue's lower edge continued in the forcing amplitude; each point a fold located as on the branch
    locus=LocusStep("fold", "A", (0.1, 0.6), _tongue_edge_in_A, tol=1e-9),
    sweep=SweepStep("I", SWEEP_I, _sweep_follows_the_map, options={"x0": [0.0], "start": "own"}),
)
