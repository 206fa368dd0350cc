"""Chua's circuit with its piecewise-linear diode: the period doubling of the single-scroll cycle and the
double scroll's Lyapunov exponent.

Matsumoto, *A chaotic attractor from Chua's circuit*, IEEE Trans. Circuits Syst. 31 (1984) 1055-1058;
Chua, Komuro and Matsumoto, *The double scroll family*, IEEE Trans. Circuits Syst. 33 (1986) 1072-1118.
In dimensionless form

    x' = alpha (y - x - g(x)),   y' = x - y + z,   z' = -beta y,
    g(x) = m1 x + (m0 - m1) / 2 (|x + 1| - |x - 1|),

written as on paper, with ``Abs``: saltation splits the field into the three affine regions ``x < -1``,
``|x| < 1``, ``x > 1`` (a continuous field: the saltation matrices are the identity).  With
``m0 = -8/7, m1 = -5/7, beta = 14.286`` the cycle around the equilibrium in ``x > 1`` doubles its period
as ``alpha`` grows (the route to the spiral attractor, Chua et al. 1986, section IV); at ``alpha = 15.6,
beta = 28`` the motion is the double scroll, chaotic (Matsumoto 1984); the reference's largest Lyapunov
exponent over 2000 time units is 0.437.

Reference (numpy/scipy only): in each region ``x' = A x + b`` flows in closed form,
``x(t) = x_e + e^{A t} (x0 - x_e)``; steps of 0.01 with ``brentq`` for the crossings of ``x = +-1``.  The
Poincare map on ``x = 1`` (falling, in ``(y, z)``) has its fixed point by Newton with central differences;
the monodromy is the product of the ``e^{A dt}`` (identity saltation matrices), and the multipliers are its
eigenvalues without the trivial one.  The period doubling is ``det(M + I) = 0`` along the branch
(``brentq`` in ``alpha``).  The Lyapunov exponents from the same closed-form flow and its tangent map, with a
QR step after each visit to a region (``--thorough``: the reference takes 30-100 s).
"""

from __future__ import annotations

import functools

import numpy as np
from corpus import BranchStep, Expected, LiteratureCase, LyapunovStep, Orbit, SweepStep
from scipy.linalg import expm
from scipy.optimize import brentq

from saltation import Mode, PiecewiseSystem

DEFAULTS = {"alpha": 8.0, "beta": 14.286, "m0": -8.0 / 7.0, "m1": -5.0 / 7.0}
DOUBLE_SCROLL = {"alpha": 15.6, "beta": 28.0, "m0": -8.0 / 7.0, "m1": -5.0 / 7.0}


def chua(**overrides) -> PiecewiseSystem:
    g = "m1*x + (m0 - m1)/2*(Abs(x + 1) - Abs(x - 1))"
    return PiecewiseSystem(
        name="literature_chua_pwl",
        states=["x", "y", "z"],
        parameters=DEFAULTS | overrides,
        modes=[Mode("circuit", [f"alpha*(y - x - ({g}))", "x - y + z", "-beta*y"])],
        surfaces={},
        transitions=[],
    )


# --- the reference: matrix exponentials and brentq ---------------------------------------------------


def _regions(p) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """``x' = A x + b`` in ``x < -1`` (-1), ``|x| < 1`` (0), ``x > 1`` (1)."""
    a, b, m0, m1 = p["alpha"], p["beta"], p["m0"], p["m1"]

    def A(m: float) -> np.ndarray:
        return np.array([[-a * (1.0 + m), a, 0.0], [1.0, -1.0, 1.0], [0.0, -b, 0.0]])

    c = a * (m0 - m1)
    return {0: (A(m0), np.zeros(3)), 1: (A(m1), np.array([-c, 0.0, 0.0])), -1: (A(m1), np.array([c, 0.0, 0.0]))}


def _region(x) -> int:
    return 1 if x[0] > 1.0 else (-1 if x[0] < -1.0 else 0)


def run(x0, p, t_end: float | None = None, section: bool = False, h: float = 0.01, on_switch=None):
    """``(x, M, t)``: the closed-form flow from ``x0`` to ``t_end``, or (``section``) to the next crossing of
    ``x = 1`` from ``x > 1``; ``M`` the product of the ``e^{A dt}`` over the regions visited (the derivative
    of the flow).  ``on_switch(M_segment, dt)``, if given, takes each region's factor as it ends, and then
    ``M`` is not accumulated.  Steps of ``h`` bracket the crossings of ``x = +-1``; ``brentq`` solves them."""
    regions = {k: (A, -np.linalg.solve(A, b), expm(A * h)) for k, (A, b) in _regions(p).items()}
    x, t, M, reg = np.array(x0, float), 0.0, np.eye(3), _region(x0)
    x_seg, t_seg = x, t  # where the flow entered the current region
    crossed = None  # the level just crossed: not watched on the first step after the crossing

    def segment(A, t1):
        factor = expm(A * (t1 - t_seg))
        if on_switch is not None:
            on_switch(factor, t1 - t_seg)
            return M
        return factor @ M

    while True:
        A, xe, step = regions[reg]
        if t_end is not None and t + h >= t_end:
            M = segment(A, t_end)
            return xe + expm(A * (t_end - t_seg)) @ (x_seg - xe), M, t_end
        xn = xe + step @ (x - xe)
        hit = None
        for level in (1.0, -1.0):
            if (x[0] - level) * (xn[0] - level) < 0.0 and not (level == crossed and t == t_seg):
                s = brentq(lambda s: (xe + expm(A * (t + s - t_seg)) @ (x_seg - xe))[0] - level, 0.0, h,
                           xtol=1e-16, rtol=1e-15)
                if hit is None or s < hit[0]:
                    hit = (s, level)
        if hit is None:
            x, t = xn, t + h
            continue
        s, level = hit
        M = segment(A, t + s)
        x = xe + expm(A * (t + s - t_seg)) @ (x_seg - xe)
        t = t + s
        x_seg, t_seg, crossed = x, t, level
        if section and reg == 1:
            return x, M, t
        reg = 0 if reg != 0 else int(level)


def _poincare(yz, p):
    x, M, T = run([1.0, yz[0], yz[1]], p, section=True)
    return x[1:], M, T


def cycle(p, yz=(-0.354, -1.307)):
    """The single-scroll cycle: ``((y, z) on x = 1, monodromy, period)``, Newton with central differences."""
    yz = np.array(yz, float)
    for _ in range(30):
        y, _, _ = _poincare(yz, p)
        d = 1e-6
        J = np.column_stack([(_poincare(yz + d * e, p)[0] - _poincare(yz - d * e, p)[0]) / (2 * d) for e in np.eye(2)])
        step = np.linalg.solve(J - np.eye(2), yz - y)
        yz = yz + step
        if np.linalg.norm(step) < 1e-13:
            break
    _, M, T = _poincare(yz, p)
    return yz, M, T


def multipliers(p) -> np.ndarray:
    mu = np.linalg.eigvals(cycle(p)[1])
    return np.delete(mu, int(np.argmin(np.abs(mu - 1.0))))


def period_doubling_alpha(p=DEFAULTS, lo: float = 8.1, hi: float = 8.25) -> float:
    """``det(M + I) = 0`` along the branch (``brentq`` in ``alpha``, each orbit by Newton)."""
    return brentq(lambda a: np.linalg.det(cycle(dict(p, alpha=a))[1] + np.eye(3)), lo, hi, xtol=1e-13, rtol=1e-14)


def _period_doubling() -> list[Expected]:
    # brentq to 1e-13 on a map whose fixed point is right to ~1e-12: the PD to ~1e-10; the location promises 1e-8
    return [Expected(("period_doubling",), period_doubling_alpha(), 1e-8)]


@functools.lru_cache(maxsize=4)
def lyapunov_reference(p=tuple(DOUBLE_SCROLL.items()), x0=(0.1, 0.0, 0.0), transient: float = 100.0,
                       time: float = 2000.0) -> np.ndarray:
    """The Lyapunov exponents of the closed-form flow: the tangent map of each visit to a region,
    re-orthonormalised by QR after each."""
    p = dict(p)
    x, _, _ = run(x0, p, t_end=transient)
    state = {"Q": np.eye(3), "total": np.zeros(3)}

    def on_switch(factor, dt):
        Q, R = np.linalg.qr(factor @ state["Q"])
        state["Q"], state["total"] = Q, state["total"] + np.log(np.abs(np.diag(R)))

    run(x, p, t_end=time, on_switch=on_switch)
    return np.sort(state["total"] / time)[::-1]


def _lyapunov_against_the_reference(exponents: np.ndarray) -> None:
    reference = lyapunov_reference()
    assert 0.3 < reference[0] < 0.5, f"the reference's largest exponent {reference[0]} is not the double scroll's"
    # two finite-time averages over different stretches of a chaotic motion: a few percent apart
    assert abs(exponents[0] - reference[0]) <= 0.05 * reference[0], (exponents, reference)
    assert abs(exponents[1]) <= 0.02, exponents  # the flow's direction


SWEEP_ALPHA = [8.0, 8.3]


def _sweep_periods(result) -> None:
    """One maximum of ``x`` at ``alpha = 8.0`` (the cycle below the period doubling), two at 8.3 (the doubled
    cycle, before the next doubling near 8.37: the reference's own iterates alternate between two points)."""
    assert not result.failures, result.failures
    for k, n in enumerate([1, 2]):
        x = np.sort(result.at(k)[:, 0])
        distinct = 1 + int(np.sum(np.diff(x) > 1e-6))
        assert distinct == n, (SWEEP_ALPHA[k], x)


CASE = LiteratureCase(
    name="chua_pwl",
    field="electronics",
    source="Matsumoto 1984; Chua, Komuro and Matsumoto 1986 (Chua's circuit, the double scroll family)",
    model=chua,
    orbit=Orbit(
        parameters=dict(DEFAULTS),
        guess=[1.0, -0.35, -1.31],  # on x = 1, from a transient of the reference
        period=2.25,
        multipliers=multipliers,
    ),
    branch=BranchStep("alpha", (8.0, 8.3), _period_doubling, ds=0.02, ds_max=0.05),
    sweep=SweepStep("alpha", SWEEP_ALPHA, _sweep_periods,
                    options={"x0": [1.5, 0.1, -1.5], "transient": 60, "periods": 30, "period": 2.25,
                             "start": "own"}),
    lyapunov=LyapunovStep(dict(DOUBLE_SCROLL), [0.1, 0.0, 0.0], time=2000.0, transient=100.0,
                          check=_lyapunov_against_the_reference, thorough=True),  # the reference takes 30-100 s
)
