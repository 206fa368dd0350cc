"""Multiple shooting against a closed-form strongly unstable orbit, and against single shooting.

``unstable_relay``: in coordinates ``(y, z) = R^T x`` (``R`` a rotation by ``theta``),

    y' = lam y + a cos(w t) - k sgn(y),        z' = -mu z,

switching on ``y = 0`` (a tilted line in ``x``).  The orbit is symmetric (``y(t + T/2) = -y(t)``)
with ``z = 0``: it enters ``y > 0`` at ``t_c``, where ``P(t_c) = (k / lam) (1 - E) / (1 + E)``,
``E = exp(lam T / 2)``, ``P = A cos(w t) + B sin(w t)`` the forced part (``A = -a lam / (w^2 + lam^2)``,
``B = a w / (w^2 + lam^2)``), and there ``y(t) = P(t) + k / lam + C exp(lam (t - t_c))``.  The
fields differ in ``y`` only, so the saltation matrices are diagonal in ``(y, z)``, with
``y'_+ / y'_-`` at a crossing: the multipliers are ``exp(lam T) ((a c - k) / (a c + k))^2``
(``c = cos(w t_c)``) and ``exp(-mu T)`` exactly.  With ``lam T = ln 1e10`` the first is about ``9e8``.

Accuracy promised: the exact path integrates affine modes to rounding, so each segment's map and
transfer matrix are exact to ``~1e-15`` relative; over a segment the state error grows by the
``m``-th root of the large multiplier.  The state is then right to ``1e-9`` relative, the large
multiplier to ``1e-6`` relative and the small one to ``1e-8``: the periodic Schur decomposition is
backward stable factor by factor, and this small multiplier is well conditioned with respect to the
factors (the monodromy is diagonal in ``(y, z)``), where ``eig`` of the assembled product loses it to
``eps`` times the product's size.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit
from saltation.errors import ConvergenceError
from saltation.orbits.floquet import product_eigenvalues

W, MU, K, A_Y, THETA = 1.0, 1.0, 0.3, 1.0, 0.6
T = 2 * np.pi / W
LAM = np.log(1e10) / T


@functools.cache
def unstable_relay() -> Flow:
    c, s = float(np.cos(THETA)), float(np.sin(THETA))
    # x = R (y, z), R = [[c, -s], [s, c]]; y = c x1 + s x2, z = -s x1 + c x2
    y, z = f"({c!r}*x1 + {s!r}*x2)", f"(-{s!r}*x1 + {c!r}*x2)"
    fields = {}
    for name, sgn in (("plus", 1), ("minus", -1)):
        dy = f"(lam*{y} + a*cos(w*t) - k*({sgn}))"
        dz = f"(-mu*{z})"
        fields[name] = [f"{c!r}*{dy} - {s!r}*{dz}", f"{s!r}*{dy} + {c!r}*{dz}"]
    return Flow(PiecewiseSystem(
        name="test_unstable_relay", states=["x1", "x2"],
        parameters={"lam": LAM, "a": A_Y, "w": W, "mu": MU, "k": K},
        modes=[Mode("plus", fields["plus"], domain=[f"{y} > 0"]), Mode("minus", fields["minus"], domain=[f"{y} < 0"])],
        surfaces={"s": y},
        transitions=[Transition("plus", "s", Crossing.FALLING, "minus"),
                     Transition("minus", "s", Crossing.RISING, "plus")],
        period="2*pi/w"))


def closed_form(t0: float) -> tuple[np.ndarray, np.ndarray]:
    """The orbit's state at ``t0`` (in x) and its multipliers."""
    den = W**2 + LAM**2
    Ay, By = -A_Y * LAM / den, A_Y * W / den
    amp, phi = np.hypot(Ay, By), np.arctan2(By, Ay)
    E = np.exp(LAM * T / 2)
    target = (K / LAM) * (1 - E) / (1 + E)
    for t_c in ((phi + s * np.arccos(target / amp)) / W for s in (1, -1)):
        if A_Y * np.cos(W * t_c) > K:  # enters y > 0 there
            break
    else:
        raise AssertionError("no crossing into y > 0")

    def P(t):
        return Ay * np.cos(W * t) + By * np.sin(W * t)

    tau = (t0 - t_c) % T
    sign = 1.0 if tau < T / 2 else -1.0
    tau = tau if tau < T / 2 else tau - T / 2
    # y on the half period after the crossing into y > 0, then by symmetry
    y_half = P(t_c + tau) + K / LAM + (-P(t_c) - K / LAM) * np.exp(LAM * tau)
    y0 = sign * y_half
    R = np.array([[np.cos(THETA), -np.sin(THETA)], [np.sin(THETA), np.cos(THETA)]])
    c = np.cos(W * t_c)
    return R @ np.array([y0, 0.0]), np.array([np.exp(LAM * T) * ((A_Y * c - K) / (A_Y * c + K)) ** 2,
                                              np.exp(-MU * T)])


@pytest.mark.parametrize("t0", [0.3, 2.0])
def test_multiple_shooting_finds_the_strongly_unstable_orbit(t0):
    x_ref, mu_ref = closed_form(t0)
    nodes = np.array([closed_form(t0 + i * T / 10)[0] for i in range(10)]) + 1e-6  # a guess of every node
    orbit = find_periodic_orbit(unstable_relay(), nodes, t0=t0, segments=10)
    assert orbit.segments == 10 and orbit.nodes.shape == (10, 2)
    assert np.abs(orbit.state0 - x_ref).max() <= 1e-9 * np.abs(x_ref).max()
    mu = np.sort(np.abs(orbit.multipliers))
    assert mu[1] == pytest.approx(mu_ref[0], rel=1e-6)
    assert abs(mu[0] - mu_ref[1]) <= 1e-8
    assert len(orbit.event_labels) == 2  # one crossing each way


def test_single_shooting_cannot_converge_there_even_from_the_exact_state():
    x_ref, _ = closed_form(0.3)
    with pytest.raises(ConvergenceError):
        find_periodic_orbit(unstable_relay(), x_ref, t0=0.3)


def test_single_and_multiple_shooting_agree_where_both_converge():
    """The same model with a mild multiplier (lam T = ln 10): both methods, the same orbit and multipliers."""
    flow = unstable_relay()
    params = {"lam": np.log(10.0) / T}
    single = find_periodic_orbit(flow, [0.1, -0.3], parameters=params, t0=0.3)
    multiple = find_periodic_orbit(flow, [0.1, -0.3], parameters=params, t0=0.3, segments=5)
    assert np.abs(single.state0 - multiple.state0).max() <= 1e-10
    assert np.sort(np.abs(single.multipliers)) == pytest.approx(np.sort(np.abs(multiple.multipliers)), rel=1e-9)
    assert np.abs(multiple.multipliers).min() == pytest.approx(np.exp(-MU * T), rel=1e-9)


def test_product_eigenvalues_keep_the_small_ones():
    """Factors ``Q_{i+1} D Q_i^T`` with orthogonal ``Q_i`` and diagonal ``D``: the product's eigenvalues are
    ``d^p``, each well conditioned with respect to the factors (perturbing each factor by eps moves an
    eigenvalue by about ``p eps`` relative), so the backward-stable periodic Schur decomposition finds
    every one to ``1e-9`` relative; eig of the assembled product loses the small ones to eps times
    the product's size (``2e-6`` against ``1e-7``)."""
    rng = np.random.default_rng(3)
    n, p = 3, 10
    qs = [np.linalg.qr(rng.normal(size=(n, n)))[0] for _ in range(p)]
    d = np.array([10.0, 0.5, 0.2])
    rs = [np.diag(d) for _ in range(p)]
    factors = [qs[(i + 1) % p] @ rs[i] @ qs[i].T for i in range(p)]
    exact = np.sort(d**p)
    found = np.sort(np.abs(product_eigenvalues(factors)))
    assert found == pytest.approx(exact, rel=1e-9)
    product = np.eye(n)
    for f in factors:
        product = f @ product
    assembled = np.sort(np.abs(np.linalg.eigvals(product)))
    assert abs(assembled[0] - exact[0]) > 1e3 * abs(found[0] - exact[0])  # what the factors save


def test_segments_must_be_a_positive_integer():
    from saltation.errors import ModelError

    with pytest.raises(ModelError, match="segments"):
        find_periodic_orbit(unstable_relay(), [0.1, 0.1], segments=0)


def test_the_parameter_column_of_the_matching_equations_equals_finite_differences(trilinear_flow):
    """Segment ``i`` of a forced orbit runs over ``[t0 + i T / m, t0 + (i + 1) T / m]`` with ``T = 2 pi /
    omega``: its column by ``omega`` holds the sensitivity and the motion of both ends of the segment.
    Central differences of the residual (the period map of DOP853 steps and exact affine steps at rtol
    1e-12, step 1e-6): agreement to 1e-6 relative, the differences' truncation and rounding."""
    from saltation.engine.flow import Tolerances
    from saltation.models.trilinear import DEFAULTS as TRI
    from saltation.apps.paper import linear_response_state
    from saltation.orbits.shooting import MultipleShootingProblem, ShootingProblem

    tol = Tolerances(rtol=1e-12, atol=1e-14)
    base = ShootingProblem(trilinear_flow, {"omega": 1.3}, continuation_parameter="omega", tolerances=tol)
    multiple = MultipleShootingProblem(base, 4)
    U = multiple.pack(linear_response_state(dict(TRI, omega=1.3)), 1.3)
    column = multiple.evaluate(U, 1.3).jac_lam
    h = 1e-6
    numeric = (multiple.evaluate(U, 1.3 + h, need_lam=False).residual
               - multiple.evaluate(U, 1.3 - h, need_lam=False).residual) / (2 * h)
    np.testing.assert_allclose(column, numeric, rtol=1e-6, atol=1e-6 * np.abs(numeric).max())


def test_a_branch_by_multiple_shooting_has_the_special_points_of_single_shooting(trilinear_flow):
    """The trilinear branch over omega: the same special points, each within the sum of the two stated
    accuracies, and the multipliers of the orbits at the fold agree to the fold's multiplier accuracy."""
    from saltation.models.trilinear import DEFAULTS as TRI
    from saltation.apps.paper import linear_response_state
    from saltation.special_points.continuation import ContinuationSettings, continue_orbit

    x0 = linear_response_state(dict(TRI, omega=0.6))
    settings = ContinuationSettings(ds=0.02, ds_max=0.05)
    branches = []
    for m in (1, 4):
        orbit = find_periodic_orbit(trilinear_flow, x0, parameters={"omega": 0.6}, segments=m)
        branches.append(continue_orbit(orbit, "omega", bounds=(0.6, 1.6), directions=(1,), settings=settings))
    single, multiple = ([sp for sp in b.special_points] for b in branches)
    assert [sp.kind for sp in single] == [sp.kind for sp in multiple] and len(single) == 3
    for a, b in zip(single, multiple):
        assert abs(a.parameter - b.parameter) <= a.accuracy + b.accuracy + 1e-12, (a.kind, a.parameter, b.parameter)
    assert all(b.stop_reason.name == "PARAMETER_BOUND" for b in branches)


def test_the_command_line_shoots_with_segments(capsys):
    """``orbit --segments 3`` finds the single-shooting orbit (state and multipliers to 1e-9: both
    converge to |r| <= 1e-10 (1 + |u|) on an orbit whose M - I is well conditioned) and says so."""
    import json

    from saltation.apps import cli

    found = []
    for m in (1, 3):
        assert cli.main(["orbit", "trilinear", "--set", "omega=1.2", "--x0", "0.5,0.5", "--segments", str(m),
                         "--json"]) == 0
        found.append(json.loads(capsys.readouterr().out))
    single, multiple = found
    assert (single["segments"], multiple["segments"]) == (1, 3)
    np.testing.assert_allclose(multiple["state0"], single["state0"], atol=1e-9)
    np.testing.assert_allclose(multiple["multipliers"], single["multipliers"], atol=1e-9)


@pytest.mark.parametrize("segments", [3, 4, 6, 8])
def test_stick_slip_orbits_by_multiple_shooting_match_single_shooting(belt_flow, segments):
    """A node inside the stick phase moves with the stick phase's own field: the flow-direction check of an
    autonomous orbit takes each node's velocity from the segment that arrives there (it took the start mode's
    field, and refused the stick-slip cycles with 3, 6 and 8 segments, 8.3e-1, and the backward-time one with 4,
    1e-4).  Reference: the same cycles by single shooting (a second method), and the trivial multiplier 1."""
    from conftest import stick_slip_orbit, unstable_orbit

    for single, backward, guess, period in ((stick_slip_orbit(belt_flow), False, None, 6.5),
                                            (unstable_orbit(belt_flow), True, [1.0, -0.95], 6.3)):
        start = single.state0 if guess is None else guess
        multiple = find_periodic_orbit(belt_flow, start, period=period, backward=backward, segments=segments)
        # both are converged to Newton's tolerance 1e-10 on states of size 1, with periods near 6.5
        assert multiple.period == pytest.approx(single.period, abs=1e-8)
        finite = lambda mu: np.sort_complex(np.asarray(mu)[np.isfinite(mu)])  # noqa: E731
        np.testing.assert_allclose(finite(multiple.multipliers), finite(single.multipliers), atol=1e-8)
        assert np.count_nonzero(~np.isfinite(multiple.multipliers)) == np.count_nonzero(~np.isfinite(single.multipliers))
