"""Contact laws as measured: fractional powers of the distance to a surface, read on each mode's own side.

A Hertzian contact ``k (x - d)^(3/2)`` and a friction law with a non-integer power of the slip speed are
written as users write them (``Heaviside``, ``sign`` and ``Abs`` in one mode, expanded by the model into
modes split at the surface).  At the surface, and in the stages of the step that crosses it, real
arithmetic gives ``NaN`` for a fractional power of a base a rounding below zero; each mode's field is read
on its own side instead (:mod:`saltation.model.sides`).

References, independent of the library: scipy's ``solve_ivp`` (DOP853) on the same equations written with
``max(., 0)`` and ``sign`` by hand, restarted at each crossing by its own events (no saltation matrix); the
periodic orbit by Newton on that period map and its multipliers as the eigenvalues of the map's central
differences.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit
from saltation.errors import NonFiniteError
from saltation.model.sides import on_its_side

S, P, Q, E = sp.symbols("s p q e")


# ---------------------------------------------------------------------------------------------------------
# the rewrite itself


@settings(max_examples=60, deadline=None)
@given(st.floats(1.05, 3.0).filter(lambda e: abs(e - round(e)) > 1e-3), st.floats(0.1, 10.0),
       st.floats(0.0, 5.0), st.floats(1e-300, 5.0))
def test_a_fractional_power_is_unchanged_on_its_side_and_takes_its_limit_beyond(e, c, s, beyond):
    """``(c s)^e``, ``s`` a mode's side: the same value where ``s >= 0``; beyond, the value at ``s = 0``
    (0), where real arithmetic has none; its derivative likewise (``e c (c s)^(e-1)``, also 0 at the surface)."""
    expr = (P * S) ** E  # (the exponent an argument: printed floats would round it)
    one_sided = on_its_side(expr, [S], [S])
    d_one_sided = on_its_side(sp.diff(expr, S), [S], [S])
    f = lambda s, c: sp.lambdify((S, P, E), one_sided, modules="math")(s, c, e)  # noqa: E731
    df = lambda s, c: sp.lambdify((S, P, E), d_one_sided, modules="math")(s, c, e)  # noqa: E731
    assert f(s, c) == (c * s) ** e  # computed as written: the same rounding
    # the derivative's powers are gathered (c^e s^(e-1)): pow's rounding, relative eps (1 + e |log|) each
    rounding = 8 * np.finfo(float).eps * (1 + e * (abs(math.log(c)) + abs(math.log(s)))) if s > 0 else 0.0
    assert df(s, c) == pytest.approx(e * c * (c * s) ** (e - 1), rel=rounding, abs=0.0)
    assert f(-beyond, c) == 0.0
    assert df(-beyond, c) == 0.0
    with pytest.raises((ValueError, TypeError)):  # what real arithmetic does there (math: ValueError)
        complex_or_error = sp.lambdify((S, P, E), expr, modules="math")(-beyond, c, e)
        if isinstance(complex_or_error, complex):
            raise TypeError("complex")


def test_a_power_in_its_exponent_has_its_limit_in_the_parameter_derivative():
    """``d/dq (s/p)^q = (s/p)^q log(s/p)``: 0 at the surface (its limit), where ``0 * log 0`` has no value."""
    expr = sp.diff((S / P) ** Q, Q)
    f = sp.lambdify((S, P, Q), on_its_side(expr, [S], [S]), modules="math")
    assert f(0.0, 0.5, 1.5) == 0.0
    assert f(-1e-17, 0.5, 1.5) == 0.0
    assert f(0.3, 0.5, 1.5) == pytest.approx((0.6**1.5) * math.log(0.6), rel=1e-14)


def test_only_fractional_powers_of_a_side_are_rewritten():
    assert on_its_side(S**2 + (S + 1) ** sp.Rational(1, 2), [S], [S]) == S**2 + (S + 1) ** sp.Rational(1, 2)
    assert on_its_side(S ** sp.Rational(3, 2), [], [S]) == S ** sp.Rational(3, 2)


def test_a_mode_knows_its_sides_from_its_domain_and_the_transitions_that_leave_it():
    system = PiecewiseSystem(
        name="sides_probe", states=["x", "v"], parameters={"d": 0.5},
        modes=[Mode("free", ["v", "-x"], domain=["x < d"]),
               Mode("contact", ["v", "-x - (x - d)**1.5"]),
               Mode("latched", ["v", "-x"])],
        surfaces={"edge": "x - d", "far": "x - 2"},
        transitions=[Transition("free", "edge", Crossing.RISING, "contact"),
                     Transition("contact", "edge", Crossing.FALLING, "free"),
                     Transition("contact", "far", Crossing.RISING, "latched", guard=["v > 0"]),
                     Transition("latched", "far", Crossing.EITHER, "free")],
    )
    x, d = system.x[0], system.p[0]
    assert system.mode_sides("free") == (d - x,)  # its domain; and left where x - d rises: the same side
    assert system.mode_sides("contact") == (x - d,)  # left where x - d falls; the guarded one says nothing
    assert system.mode_sides("latched") == ()  # left either way: no side


# ---------------------------------------------------------------------------------------------------------
# scipy's reference: the same equations, restarted at each crossing by their own events


def _scipy_period_map(fields, surface, side, t0, t1, y0):
    """Integrate ``fields[side]`` until ``surface`` changes sign, switch, and go on to ``t1``."""
    t, y = t0, np.asarray(y0, dtype=float)
    for _ in range(50):
        event = lambda tt, yy: surface(yy)  # noqa: E731
        event.terminal, event.direction = True, -side
        sol = solve_ivp(fields[side], (t, t1), y, method="DOP853", rtol=1e-12, atol=1e-13, events=event)
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.status == 0:
            return y
        side = -side
    raise AssertionError("too many crossings")


def _scipy_orbit(fields, surface, period, y0):
    """The periodic orbit through ``y0`` (Newton on scipy's period map) and its multipliers (central
    differences of the map, step 1e-4: truncation h^2 and the integration's error over h, each about 1e-8)."""
    def side_of(y):
        return 1 if surface(y) > 0 else -1

    def pmap(y):
        return _scipy_period_map(fields, surface, side_of(y), 0.0, period, y)

    def jac(y, h=1e-4):
        return np.column_stack([(pmap(y + h * e) - pmap(y - h * e)) / (2 * h) for e in np.eye(len(y))])

    y = np.asarray(y0, dtype=float)
    for _ in range(20):
        r = pmap(y) - y
        if np.linalg.norm(r) < 1e-11:
            break
        y = y - np.linalg.solve(jac(y) - np.eye(len(y)), r)
    return y, np.linalg.eigvals(jac(y))


def _sorted(mu):
    return np.array(sorted(np.asarray(mu, dtype=complex), key=lambda z: (round(z.real, 6), z.imag)))


# ---------------------------------------------------------------------------------------------------------
# a Hertzian contact: x'' + 0.1 x' + x + 5 H(x - 0.5) (x - 0.5)^(3/2) = 0.6 cos(1.1 t)


def hertz_contact() -> PiecewiseSystem:
    """Written as on paper: the contact force acts where the penetration is positive."""
    return PiecewiseSystem(
        name="hertz_contact", states=["x", "v"],
        parameters={"c": 0.1, "k": 5.0, "d": 0.5, "F": 0.6, "omega": 1.1},
        modes=[Mode("m", ["v", "-c*v - x - k*Heaviside(x - d)*(x - d)**Rational(3, 2) + F*cos(omega*t)"])],
        surfaces={}, transitions=[], period="2*pi/omega",
    )


def test_the_hertzian_contact_orbit_matches_scipy():
    c, k, d, F, w = 0.1, 5.0, 0.5, 0.6, 1.1
    T = 2 * math.pi / w

    def field(t, y):
        x, v = y
        return [v, -c * v - x - k * max(x - d, 0.0) ** 1.5 + F * math.cos(w * t)]

    y_ref, mu_ref = _scipy_orbit({1: field, -1: field}, lambda y: y[0] - d, T, [1.1494, 0.9496])
    assert np.allclose(y_ref, [1.1494, 0.9496], atol=1e-4)  # (the orbit)
    orbit = find_periodic_orbit(hertz_contact(), [1.1494, 0.9496])
    assert orbit.period == pytest.approx(T, rel=1e-14)
    assert np.allclose(orbit.state0, y_ref, atol=1e-8)
    assert np.allclose(_sorted(orbit.multipliers), _sorted(mu_ref), atol=1e-6)
    assert abs(orbit.multipliers[0]) == pytest.approx(0.7516, abs=1e-3)  # a complex pair of modulus about 0.75
    assert len(orbit.trajectory.events) == 2  # into the contact and out


# ---------------------------------------------------------------------------------------------------------
# a friction law with a non-integer power of the slip speed (Stribeck), its exponent a parameter


def stribeck(delta: float = 1.5) -> PiecewiseSystem:
    """``x'' + 2 zeta x' + x = F cos(omega t) - sign(v) (mu_d + (mu_s - mu_d) exp(-(|v|/v_s)^delta))``."""
    return PiecewiseSystem(
        name="stribeck_power_law", states=["x", "v"],
        parameters={"zeta": 0.05, "mu_s": 0.3, "mu_d": 0.1, "v_s": 0.5, "F": 2.0, "omega": 0.8, "delta": delta},
        modes=[Mode("m", ["v", "-2*zeta*v - x + F*cos(omega*t) "
                               "- sign(v)*(mu_d + (mu_s - mu_d)*exp(-(Abs(v)/v_s)**delta))"])],
        surfaces={}, transitions=[], period="2*pi/omega",
    )


def _stribeck_fields(delta):
    zeta, mu_s, mu_d, v_s, F, w = 0.05, 0.3, 0.1, 0.5, 2.0, 0.8

    def field(sign):
        def f(t, y):
            x, v = y
            return [v, -2 * zeta * v - x + F * math.cos(w * t)
                    - sign * (mu_d + (mu_s - mu_d) * math.exp(-((max(sign * v, 0.0) / v_s) ** delta)))]
        return f

    return {1: field(1), -1: field(-1)}


def test_the_stribeck_orbit_matches_scipy():
    T = 2 * math.pi / 0.8
    y_ref, mu_ref = _scipy_orbit(_stribeck_fields(1.5), lambda y: y[1], T, [5.14, 1.18])
    orbit = find_periodic_orbit(stribeck(), [5.14, 1.18])
    assert np.allclose(orbit.state0, y_ref, atol=1e-8)
    assert np.allclose(_sorted(orbit.multipliers), _sorted(mu_ref), atol=1e-6)
    assert [e.surface for e in orbit.trajectory.events] == ["v", "v"]  # two reversals, no sliding


def test_the_sensitivity_to_the_exponent_matches_finite_differences():
    """``f_p`` holds ``(|v|/v_s)^delta log(|v|/v_s)``, which is ``0 log 0`` at the surface: read as its limit,
    the period map's derivative in ``delta`` agrees with scipy's central differences (step 1e-4: about 1e-7)."""
    system = stribeck()
    flow = Flow(system)
    p = system.parameter_vector()
    T = 2 * math.pi / 0.8
    y0 = np.array([5.144467238, 1.178681988])
    run = flow.run(y0, 0.0, T, p, variational=True, sensitivity="delta")
    h = 1e-4
    plus = _scipy_period_map(_stribeck_fields(1.5 + h), lambda y: y[1], 1, 0.0, T, y0)
    minus = _scipy_period_map(_stribeck_fields(1.5 - h), lambda y: y[1], 1, 0.0, T, y0)
    fd = (plus - minus) / (2 * h)
    assert np.all(np.isfinite(run.parameter_sensitivity))
    assert np.allclose(np.ravel(run.parameter_sensitivity), fd, atol=1e-6)


def test_a_power_below_one_of_the_slip_speed_is_refused_at_the_surface_naming_the_mode():
    """``|v|^0.6``: the field has a limit at ``v = 0`` but its Jacobian does not (``v^-0.4``): the variational
    equation cannot be carried through the surface, and the integrator says where."""
    flow = Flow(stribeck(0.6))
    p = flow.system.parameter_vector()
    plain = flow.run([1.0, 0.5], 0.0, 10.0, p)  # the field alone has its limit: the motion runs
    assert np.all(np.isfinite(plain.x1)) and len(plain.events) >= 1
    with pytest.raises(NonFiniteError, match=r"mode 'm\[v"):
        flow.run([1.0, 0.5], 0.0, 10.0, p, variational=True)
