"""Multiple shooting of an AUTONOMOUS strongly unstable orbit against its closed form (the forced
counterpart is ``test_multiple_shooting.py``).

``unstable_relay``: a third-order relay feedback system ``x' = A x + B u``, ``u = -sgn(x1)``, with the
plant of :mod:`saltation.models.relay_feedback` in observer form but its real pole moved to ``s = +a``:

    G(s) = (s^2 - 2 sigma s + 1) / ((s^2 + 2 zeta w s + w^2)(s - a)),

    A = [[a - 2 zeta w, 1, 0], [2 zeta w a - w^2, 0, 1], [a w^2, 0, 0]],   B = [1, -2 sigma, 1]^T,

switching on ``x1 = 0`` (mode ``u_plus``, ``u = +1``, in ``x1 < 0``).  ``A`` has the eigenvalue ``+a``,
which the switching sees (``C = e1`` is not orthogonal to its eigenvector): with ``zeta = 0.2``, ``w = 1``,
``sigma = -1.5`` the symmetric self-oscillation has period ``T = 5.82`` and multipliers
``(1.23e9, 1, 0.320)`` at ``a = 4``, and ``(801, 1, 0.515)`` at ``a = 1.75``.

Closed form (symmetry ``x -> -x``).  The orbit crosses ``x1 = 0`` downwards at ``x0`` into ``u_plus``
and reaches ``-x0`` at the half period ``h``: ``e^{Ah} x0 + A^{-1}(e^{Ah} - I) B = -x0``, i.e.

    x0(h) = -A^{-1} tanh(A h / 2) B          (tanh of the diagonalised ``A``, exact in ``h``),

and ``h`` is the root of ``x0(h)_1 = 0`` (brentq) on the long orbit's bracket; ``x0_2 < -1`` makes both
switches transversal crossings (``x1' = x2 -+ 1 < 0`` on either side) and ``x1 < 0`` on ``(0, h)`` is
checked.  On ``[0, h)`` ``x(t) = e^{At} x0 + A^{-1}(e^{At} - I) B``, on ``[h, 2h)`` ``x(t) = -x(t - h)``.
The saltation matrix at ``-x0`` (``u_plus`` to ``u_minus``) is ``S = I + (f_- - f_+) e1^T / f_+,1`` and by
the symmetry the one at ``x0`` is the same, so the monodromy is ``(S e^{Ah})^2``: the large multiplier
is the square of the largest eigenvalue of ``S e^{Ah}``, and the small one follows from the determinant,
``mu_small mu_large = det(S)^2 e^{tr(A) T}`` with ``det S = f_-,1 / f_+,1`` (the velocity ratio at the
switch) and ``tr A = a - 2 zeta w``, so that it keeps its full relative accuracy.  Checked against a
50-digit mpmath evaluation of the same formulas: ``h`` to 1e-15, states to 1e-13, multipliers to 4e-13
relative.

Accuracy promised: every mode is affine, so the exact path integrates each segment to rounding; the
periodic Schur decomposition keeps the small multiplier (see ``test_multiple_shooting.py``).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

from saltation import (
    Crossing,
    Flow,
    Mode,
    PiecewiseSystem,
    Transition,
    find_periodic_orbit,
)
from saltation.errors import ConvergenceError, InconsistentResultError
from saltation.special_points.continuation import continue_orbit

ZETA, W, SIGMA = 0.2, 1.0, -1.5
A_STRONG = 4.0  # multiplier 1.23e9
A_MILD = 1.75  # multiplier 801: single shooting converges too
HALF_PERIOD_BRACKET = (2.2, 3.5)  # the long orbit's h for a in [1.75, 4.5]; the short orbit has h < 1.9


def _field(u: str) -> list[str]:
    """``A x + B u``."""
    return [
        f"(a - 2*zeta*w)*x1 + x2 + ({u})",
        f"(2*zeta*w*a - w**2)*x1 + x3 - 2*sigma*({u})",
        f"a*w**2*x1 + ({u})",
    ]


@functools.cache
def unstable_relay() -> Flow:
    return Flow(PiecewiseSystem(
        name="test_unstable_relay_feedback",
        states=["x1", "x2", "x3"],
        parameters={"zeta": ZETA, "w": W, "a": A_STRONG, "sigma": SIGMA},
        modes=[Mode("u_plus", _field("1"), domain=["x1 < 0"]), Mode("u_minus", _field("-1"))],
        surfaces={"y": "x1"},
        transitions=[Transition("u_plus", "y", Crossing.RISING, "u_minus"),
                     Transition("u_minus", "y", Crossing.FALLING, "u_plus")],
    ))


# ---------------------------------------------------------------------------- closed form
def plant(a: float) -> tuple[np.ndarray, np.ndarray]:
    A = np.array([[a - 2 * ZETA * W, 1.0, 0.0], [2 * ZETA * W * a - W**2, 0.0, 1.0], [a * W**2, 0.0, 0.0]])
    return A, np.array([1.0, -2 * SIGMA, 1.0])


def _crossing_state(A: np.ndarray, B: np.ndarray, h: float) -> np.ndarray:
    """``x0(h) = -A^{-1} tanh(A h / 2) B``: the state that ``u_plus`` maps to ``-x0`` in the time ``h``."""
    d, V = np.linalg.eig(A)
    tanh = (V * np.tanh(d * h / 2)) @ np.linalg.inv(V)
    return -np.linalg.solve(A, (tanh @ B).real)


def _on_orbit(A: np.ndarray, B: np.ndarray, h: float, x0: np.ndarray, t: float) -> np.ndarray:
    """``e^{A tau} x0 + A^{-1}(e^{A tau} - I) B`` on the first half period, its mirror image on the second."""
    tau, sign = t % (2 * h), 1.0
    if tau >= h:
        tau, sign = tau - h, -1.0
    E = expm(A * tau)
    return sign * (E @ x0 + np.linalg.solve(A, (E - np.eye(3)) @ B))


@functools.cache
def half_orbit(a: float) -> tuple[float, np.ndarray]:
    """The half period ``h`` and the downward crossing ``x0`` of the long symmetric orbit."""
    A, B = plant(a)
    h = brentq(lambda s: _crossing_state(A, B, s)[0], *HALF_PERIOD_BRACKET, xtol=1e-15,
               rtol=4 * np.finfo(float).eps)
    x0 = _crossing_state(A, B, h)
    assert x0[1] < -1  # crossings, not sliding, at both switches
    assert all(_on_orbit(A, B, h, x0, t)[0] < 0 for t in np.linspace(0, h, 60)[1:-1])  # no other switch
    return h, x0


def state_at(a: float, t: float) -> np.ndarray:
    """The orbit's state ``t`` after its downward crossing."""
    return _on_orbit(*plant(a), *half_orbit(a), t)


def velocity(a: float, x: np.ndarray) -> np.ndarray:
    A, B = plant(a)
    return A @ x + B * (1.0 if x[0] < 0 else -1.0)


def period_and_multipliers(a: float) -> tuple[float, float, float]:
    """``(T, mu_large, mu_small)``."""
    h, x0 = half_orbit(a)
    A, B = plant(a)
    f_plus, f_minus = A @ -x0 + B, A @ -x0 - B
    S = np.eye(3) + np.outer(f_minus - f_plus, [1.0, 0.0, 0.0]) / f_plus[0]
    large = float(np.max(np.abs(np.linalg.eigvals(S @ expm(A * h))))) ** 2
    small = (f_minus[0] / f_plus[0]) ** 2 * np.exp(np.trace(A) * 2 * h) / large
    return 2 * h, large, small


def on_section(a: float, x_ref: np.ndarray, t_guess: float) -> float:
    """The time near ``t_guess`` at which the orbit meets the phase condition's hyperplane
    ``f(x_ref) . (x - x_ref) = 0`` (where the shooting anchors it)."""
    f = velocity(a, x_ref)
    return brentq(lambda t: f @ (state_at(a, t) - x_ref), t_guess - 0.1, t_guess + 0.1, xtol=1e-15)


def check_orbit(orbit, a: float, t_start: float) -> None:
    """Nodes, period and multipliers of a multiple-shooting ``orbit`` against the closed form; ``t_start``
    is the time of its first node after the downward crossing."""
    T, large, small = period_and_multipliers(a)
    m = orbit.segments
    assert orbit.nodes.shape == (m, 3)
    # period and every node to 1e-9 relative: Newton stops at |r| <= 1e-10 (1 + |U|) (~4e-9 here) or
    # below, the nodes' error is about twice the residual, and |x| ~ 10; each segment's map is exact to
    # rounding, amplified over a segment by the m-th root of 1e9 only
    assert orbit.period == pytest.approx(T, rel=1e-9)
    for i, node in enumerate(orbit.nodes):
        x = state_at(a, t_start + i * T / m)
        assert np.abs(node - x).max() <= 1e-9 * np.abs(x).max(), i
    mu = np.sort(np.abs(orbit.multipliers))
    # the large one to 1e-6 relative: a simple, well-conditioned eigenvalue of a product of exact factors
    assert mu[2] == pytest.approx(large, rel=1e-6)
    # the small one (0.32 at a = 4, 0.51 at a = 1.75) to 1e-8 absolute, i.e. 2e-8..3e-8 relative (absolute
    # as in test_multiple_shooting.py: next to 1 and 1e9 it is the size of the error that matters): the
    # periodic Schur decomposition is backward stable factor by factor and this multiplier is well
    # conditioned with respect to the factors, where eig of the product would lose it to eps |M| ~ 1e-7
    assert abs(mu[0] - small) <= 1e-8
    # the trivial one to 1e-8 absolute: the product of the segments' gains along the flow, the flow
    # direction mapped from node to node by exact factors
    assert abs(mu[1] - 1.0) <= 1e-8
    assert len(orbit.event_labels) == 2  # one crossing each way


# ---------------------------------------------------------------------------- tests
def test_closed_form_is_the_long_symmetric_orbit():
    """The closed form itself: a periodic solution of the flow, with the documented numbers."""
    for a in (A_STRONG, A_MILD):
        h, x0 = half_orbit(a)
        np.testing.assert_allclose(state_at(a, 2 * h - 1e-12), x0, atol=1e-9)
        assert np.abs(x0 + state_at(a, h)).max() <= 1e-12 * np.abs(x0).max()
    assert period_and_multipliers(A_STRONG) == pytest.approx((5.82494717, 1.2327449e9, 0.31971418), rel=1e-7)
    assert period_and_multipliers(A_MILD) == pytest.approx((5.09001, 801.11665, 0.51488251), rel=1e-5)


@pytest.mark.parametrize("phase", [0.25, 0.5, 1.5])
def test_single_shooting_fails_from_the_exact_state(phase):
    """What is true: single shooting FAILS from the exact state (it is not merely less accurate).  One
    rounding unit of the state (~1e-15) grows by 1.2e9 over the period, so the closing residual stalls
    at 3..200 times Newton's tolerance 1e-10 (1 + |u|) ~ 1e-9 (seen over 17 phases of the orbit), and no
    damped step reduces it further.  Where the rounding of a CPU lets the residual slip under the tolerance, the
    monodromy it comes with maps the flow direction 1e-2 off itself (the same 1.2e9 gain), and the orbit is
    refused for that: a failure either way, never an orbit."""
    h, _ = half_orbit(A_STRONG)
    x = state_at(A_STRONG, phase * h)
    with pytest.raises((ConvergenceError, InconsistentResultError)) as info:
        find_periodic_orbit(unstable_relay(), x, period=2 * h)
    if isinstance(info.value, ConvergenceError):
        assert "no step reduces the residual" in str(info.value)
        assert min(info.value.residuals) > 1e-10 * (1 + np.linalg.norm(np.append(x, 2 * h)))
    else:
        assert "trivial multiplier is not 1" in str(info.value)


@pytest.mark.parametrize("segments", [8, 16])
def test_multiple_shooting_from_the_exact_state(segments):
    """One guessed state (the exact one, period off by 1e-4): the nodes are taken from its trajectory."""
    h, _ = half_orbit(A_STRONG)
    t0 = h / 2  # mid-way between the switches: start_off_surfaces leaves it where it is
    x = state_at(A_STRONG, t0)
    orbit = find_periodic_orbit(unstable_relay(), x, period=2 * h * (1 + 1e-4), segments=segments)
    assert orbit.segments == segments and orbit.nodes.shape == (segments, 3)
    check_orbit(orbit, A_STRONG, on_section(A_STRONG, x, t0))


@pytest.mark.parametrize("t0", [0.7, 4.1])
def test_multiple_shooting_from_a_guess_of_every_node(t0):
    """Every node guessed 1e-6 off the orbit, the period 1e-5 off."""
    m = 12
    T, _, _ = period_and_multipliers(A_STRONG)
    nodes = np.array([state_at(A_STRONG, t0 + i * T / m) for i in range(m)]) + 1e-6
    orbit = find_periodic_orbit(unstable_relay(), nodes, period=T * (1 + 1e-5), segments=m)
    check_orbit(orbit, A_STRONG, on_section(A_STRONG, nodes[0], t0))


def test_single_and_multiple_shooting_agree_where_both_converge():
    """At a = 1.75 (multiplier 801) both methods converge from the exact state, period 1e-4 off."""
    params = {"a": A_MILD}
    h, _ = half_orbit(A_MILD)
    x = state_at(A_MILD, h / 2)
    single = find_periodic_orbit(unstable_relay(), x, parameters=params, period=2 * h * (1 + 1e-4))
    multiple = find_periodic_orbit(unstable_relay(), x, parameters=params, period=2 * h * (1 + 1e-4), segments=8)
    t_start = on_section(A_MILD, x, h / 2)
    check_orbit(multiple, A_MILD, t_start)
    T, large, small = period_and_multipliers(A_MILD)
    x_ref = state_at(A_MILD, t_start)
    # single shooting to the same accuracies: the monodromy (|M| ~ 1e3) loses nothing that matters here
    assert np.abs(single.state0 - x_ref).max() <= 1e-9 * np.abs(x_ref).max()
    assert single.period == pytest.approx(T, rel=1e-9)
    mu1, mum = np.sort(np.abs(single.multipliers)), np.sort(np.abs(multiple.multipliers))
    # the nontrivial ones to 1e-8 relative: eig of the assembled monodromy loses only eps |M| ~ 1e-13 here
    assert mu1[[0, 2]] == pytest.approx([small, large], rel=1e-8)
    # single shooting's trivial one to 1e-7 only: it is perturbed by the orbit's closing error (Newton's
    # last residual, up to 1e-9) times |M| ~ 1e3 (seen: 6e-9); multiple shooting's gains keep it to 1e-8
    assert abs(mu1[1] - 1.0) <= 1e-7
    # and the two methods to each other, to the sum of their accuracies
    assert np.abs(single.state0 - multiple.state0).max() <= 2e-9 * np.abs(x_ref).max()
    assert single.period == pytest.approx(multiple.period, rel=2e-9)
    assert mu1[[0, 2]] == pytest.approx(mum[[0, 2]], rel=2e-8)
    assert abs(mu1[1] - mum[1]) <= 1.1e-7


def test_continuation_by_multiple_shooting_follows_the_closed_form():
    """From a = 4 up to the bound 4.1: every point's period and multipliers are the closed form's, no
    special point (the multipliers stay far from the unit circle, the event sequence does not change)."""
    m = 8
    h, _ = half_orbit(A_STRONG)
    x = state_at(A_STRONG, h / 2)
    orbit = find_periodic_orbit(unstable_relay(), x, period=2 * h, segments=m)
    upper = 4.1
    branch = continue_orbit(orbit, "a", bounds=(3.9, upper), segments=m, directions=(1,))
    assert branch.stop_reason.name == "PARAMETER_BOUND"
    assert branch.parameter[0] == A_STRONG and branch.parameter[-1] == pytest.approx(upper, abs=1e-12)
    assert len(branch.points) >= 4
    assert branch.special_points == []
    for point in branch.points:
        a = float(point.parameter)
        T, large, small = period_and_multipliers(a)
        # the corrector's tolerance is Newton's (1e-10): the same accuracies as find_periodic_orbit
        assert point.period == pytest.approx(T, rel=1e-9), a
        mu = np.sort(np.abs(point.multipliers))
        assert mu[2] == pytest.approx(large, rel=1e-6), a
        assert abs(mu[0] - small) <= 1e-8, a
        assert abs(mu[1] - 1.0) <= 1e-8, a
