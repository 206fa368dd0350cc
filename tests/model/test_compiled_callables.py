"""The escape hatch: a model given as compiled callables agrees with the same model from expressions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from saltation import Crossing, Flow, Transition
from saltation.engine.compiled import CompiledSystem
from saltation.errors import ModelError
from saltation.models import trilinear
from saltation.orbits.shooting import ShootingProblem, find_periodic_orbit

# parameters: m c k x_c k_f c_f f0 omega; modes: 0 contact_1, 1 contact_2, 2 free
# surfaces: 0 h1a = x - x_c, 1 h1b = k_f (x - x_c) + c_f v, 2 h2a = x + x_c, 3 h2b = k_f (x + x_c) + c_f v


@njit
def vector_field(mode, t, x, p, out):
    m, c, k, xc, kf, cf, f0, w = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    force = -c * x[1] - k * x[0] + f0 * math.sin(w * t)
    if mode == 0:
        force += -cf * x[1] - kf * (x[0] - xc)
    elif mode == 1:
        force += -cf * x[1] - kf * (x[0] + xc)
    out[0] = x[1]
    out[1] = force / m


@njit
def vector_field_jac(mode, t, x, p, out):
    m, c, k, kf, cf = p[0], p[1], p[2], p[4], p[5]
    out[0, 0] = 0.0
    out[0, 1] = 1.0
    if mode == 2:
        out[1, 0] = -k / m
        out[1, 1] = -c / m
    else:
        out[1, 0] = -(k + kf) / m
        out[1, 1] = -(c + cf) / m


@njit
def vector_field_dp(mode, t, x, p, out):
    m, c, k, xc, kf, cf, f0, w = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    out[:, :] = 0.0
    vector_field(mode, t, x, p, out[:, 0])
    out[0, 0] = 0.0
    out[1, 0] = -out[1, 0] / m  # d(force/m)/dm
    out[1, 1] = -x[1] / m
    out[1, 2] = -x[0] / m
    if mode == 0:
        out[1, 3] = kf / m
        out[1, 4] = -(x[0] - xc) / m
        out[1, 5] = -x[1] / m
    elif mode == 1:
        out[1, 3] = -kf / m
        out[1, 4] = -(x[0] + xc) / m
        out[1, 5] = -x[1] / m
    out[1, 6] = math.sin(w * t) / m
    out[1, 7] = f0 * t * math.cos(w * t) / m


@njit
def indicator(surface, t, x, p):
    xc, kf, cf = p[3], p[4], p[5]
    if surface == 0:
        return x[0] - xc
    if surface == 1:
        return kf * (x[0] - xc) + cf * x[1]
    if surface == 2:
        return x[0] + xc
    return kf * (x[0] + xc) + cf * x[1]


@njit
def indicator_grad(surface, t, x, p, hx, hp):
    xc, kf, cf = p[3], p[4], p[5]
    hx[:] = 0.0
    hp[:] = 0.0
    if surface == 0 or surface == 2:
        hx[0] = 1.0
        hp[3] = -1.0 if surface == 0 else 1.0
    else:
        sign = -1.0 if surface == 1 else 1.0
        hx[0] = kf
        hx[1] = cf
        hp[3] = sign * kf
        hp[4] = x[0] + sign * xc
        hp[5] = x[1]
    return 0.0


@njit
def guard(k, t, x, p):
    xc, kf, cf = p[3], p[4], p[5]
    if k == 0:
        return kf * (x[0] - xc) + cf * x[1] >= 0.0
    if k == 1:
        return x[0] - xc > 0.0
    if k == 4:
        return kf * (x[0] + xc) + cf * x[1] <= 0.0
    if k == 5:
        return x[0] + xc < 0.0
    return True


@njit
def in_domain(mode, t, x, p):
    xc, kf, cf = p[3], p[4], p[5]
    if mode == 0:
        return x[0] - xc > 0.0 and kf * (x[0] - xc) + cf * x[1] >= 0.0
    if mode == 1:
        return x[0] + xc < 0.0 and kf * (x[0] + xc) + cf * x[1] <= 0.0
    return True


def compiled_trilinear() -> CompiledSystem:
    reference = trilinear()
    transitions = [Transition(t.source, t.surface, t.direction, t.target) for t in reference.transitions]
    return CompiledSystem(
        "compiled_trilinear",
        reference.state_names,
        reference.defaults,
        reference.mode_names,
        reference.surface_names,
        transitions,
        {
            "vector_field": vector_field, "vector_field_jac": vector_field_jac, "vector_field_dp": vector_field_dp,
            "indicator": indicator, "indicator_grad": indicator_grad, "guard": guard, "in_domain": in_domain,
        },
        period=lambda p: 2 * math.pi / p[7],
        period_derivative=lambda p, k: -2 * math.pi / p[7] ** 2 if k == 7 else 0.0,
    )


@pytest.fixture(scope="module")
def flows():
    return Flow(compiled_trilinear()), Flow(trilinear())


def test_compiled_callables_match_expressions(flows):
    compiled, symbolic = flows
    for w in (0.7, 1.0, 1.2):
        a = find_periodic_orbit(compiled, [0.5, 0.5], parameters={"omega": w})
        b = find_periodic_orbit(symbolic, [0.5, 0.5], parameters={"omega": w})
        assert np.allclose(a.state0, b.state0, atol=1e-9)
        assert np.allclose(a.monodromy, b.monodromy, atol=1e-8)
        assert [e.surface for e in a.events] == [e.surface for e in b.events]
        for ea, eb in zip(a.trajectory.events, b.trajectory.events):
            assert np.allclose(ea.saltation, eb.saltation, atol=1e-9)


def test_compiled_parameter_sensitivity(flows):
    compiled, symbolic = flows
    pa = ShootingProblem(compiled, {"omega": 1.0}, continuation_parameter="omega")
    pb = ShootingProblem(symbolic, {"omega": 1.0}, continuation_parameter="omega")
    u = np.array([-0.42, 0.977])
    ea, eb = pa.evaluate(u, 1.0), pb.evaluate(u, 1.0)
    assert np.allclose(ea.jac_lam, eb.jac_lam, atol=1e-8)
    assert np.allclose(ea.residual, eb.residual, atol=1e-10)


def test_compiled_system_validation():
    ref = trilinear()
    base = {"vector_field": vector_field, "vector_field_jac": vector_field_jac, "indicator": indicator}
    with pytest.raises(ModelError, match="indicator_grad"):
        CompiledSystem("x", ref.state_names, ref.defaults, ref.mode_names, ref.surface_names, [], base)
    with pytest.raises(ModelError, match="nowhere"):
        CompiledSystem(
            "x", ref.state_names, ref.defaults, ref.mode_names, ref.surface_names,
            [Transition("free", "h1a", Crossing.RISING, "nowhere")], base | {"indicator_grad": indicator_grad},
        )
    with pytest.raises(ModelError, match="typo_field"):
        CompiledSystem("x", ref.state_names, ref.defaults, ref.mode_names, ref.surface_names, [],
                       base | {"indicator_grad": indicator_grad, "typo_field": vector_field})


def test_a_callable_that_does_not_fit_its_signature_is_named():
    """Each callable is compiled with its signature from the contract when the flow is built; one that
    does not fit (here an indicator without the parameter argument) is a ModelError naming it."""
    ref = trilinear()

    def bad_indicator(surface, t, x):
        return x[0]

    system = CompiledSystem(
        "test_bad_indicator", ref.state_names, ref.defaults, ref.mode_names, ref.surface_names, [],
        {"vector_field": vector_field, "vector_field_jac": vector_field_jac, "indicator": bad_indicator,
         "indicator_grad": indicator_grad},
    )
    with pytest.raises(ModelError, match="indicator does not compile with the signature"):
        Flow(system)
