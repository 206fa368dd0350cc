"""The parameter Jacobian of periodic orbits (:func:`saltation.orbits.parameter_jacobian.orbit_parameter_jacobian`)
against a closed form and against finite differences of orbits found again at ``q +- h``.

* the trilinear model's free orbit below the supports is the harmonic response, ``x0 = (b, a omega)`` with
  ``x = a sin(omega t) + b cos(omega t)`` (:func:`~saltation.models.trilinear.linear_response_state`):
  its derivatives by sympy;
* its orbit in contact with both supports (four events a period) and the block-on-belt stick-slip cycle
  (autonomous, its phase on the section through its own state normal to the field there): central
  differences of the orbits solved again at ``q +- h``, ``+- 2h``, ``+- 4h``, Richardson-extrapolated; their
  tolerance is the difference of the two extrapolations plus the solves' accuracy over the step.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from saltation import Flow, find_periodic_orbit
from saltation.errors import ModelError, SaltationError
from saltation.models.trilinear import DEFAULTS as TRI
from saltation.models.trilinear import linear_response_state
from saltation.orbits.parameter_jacobian import orbit_parameter_jacobian
from saltation.orbits.shooting import ShootingProblem


def richardson(solve, q: float, h: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """``(d/dq, error estimate)`` of the vector ``solve(value)`` at ``q`` (see the module's description)."""
    d = {k: (solve(q + k * h) - solve(q - k * h)) / (2 * k * h) for k in (1, 2, 4)}
    r1, r2 = (4 * d[1] - d[2]) / 3, (4 * d[2] - d[4]) / 3
    return r1, np.abs(r1 - r2) + 2 * tol / h


def test_the_free_orbit_against_the_harmonic_response(trilinear_flow):
    orbit = find_periodic_orbit(trilinear_flow, linear_response_state(dict(TRI, omega=0.6)), parameters={"omega": 0.6})
    jac = orbit_parameter_jacobian(orbit)
    assert jac.parameter_names == tuple(trilinear_flow.system.parameter_names)
    m, c, k, f0, w = sp.symbols("m c k f0 omega")
    det = (k - m * w**2) ** 2 + (c * w) ** 2
    x0 = [-f0 * c * w / det, f0 * (k - m * w**2) / det * w]
    at = {m: TRI["m"], c: TRI["c"], k: TRI["k"], f0: TRI["f0"], w: 0.6}
    for name in jac.parameter_names:
        d_state, d_period = jac.column(name)
        symbol = sp.Symbol(name)
        reference = [float(sp.diff(x, symbol).subs(at)) for x in x0]
        # the free mode is affine: its flow is exact, the Jacobian good to rounding, as it claims
        np.testing.assert_allclose(d_state, reference, rtol=0, atol=jac.accuracy[jac.parameter_names.index(name)] + 1e-14)
        assert d_period == pytest.approx(-2 * np.pi / 0.6**2 if name == "omega" else 0.0, abs=1e-13)
    assert jac.condition < 10


def test_the_orbit_in_contact_against_finite_differences(trilinear_flow, contact_orbit):
    orbit = contact_orbit
    assert len(orbit.trajectory.events) == 4
    jac = orbit_parameter_jacobian(orbit, parameters=["k_f", "c_f", "f0", "omega"])

    def solve(name):
        def at(value):
            problem = ShootingProblem(trilinear_flow, dict(zip(trilinear_flow.system.parameter_names, orbit.parameters))
                                      | {name: value})
            return problem.solve(orbit.state0, tol=1e-13).state0
        return at

    for name in jac.parameter_names:
        q = float(orbit.parameters[trilinear_flow.system.parameter_names.index(name)])
        reference, error = richardson(solve(name), q, 1e-4, 1e-13)
        d_state, _ = jac.column(name)
        assert np.all(np.abs(d_state - reference) <= error + jac.accuracy[jac.parameter_names.index(name)]), (
            name, d_state, reference, error)


def test_an_autonomous_stick_slip_cycle_against_finite_differences():
    from saltation.apps.paper import stable_stick_slip_cycle
    from saltation.models import block_on_belt

    flow = Flow(block_on_belt())
    orbit = stable_stick_slip_cycle(flow, 0.6)
    names = ["v_dr", "k"]
    jac = orbit_parameter_jacobian(orbit, parameters=names)
    system = flow.system
    mode = system.mode_names[flow.start_mode(orbit.state0, orbit.parameters, 0.0, orbit.mode0)]
    field = flow.vector_field(mode, 0.0, orbit.state0, orbit.parameters)

    def solve(name):
        def at(value):
            problem = ShootingProblem(flow, dict(zip(system.parameter_names, orbit.parameters)) | {name: value},
                                      mode0=orbit.mode0)
            # the phase on the section through the orbit's state, normal to its field (as the Jacobian's)
            problem.x_ref, problem.f_ref = orbit.state0.copy(), field / np.linalg.norm(field)
            found = problem.solve(problem.pack(orbit.state0, orbit.period), tol=1e-12)
            return np.append(found.state0, found.period)
        return at

    for name in names:
        q = float(orbit.parameters[system.parameter_index(name)])
        reference, error = richardson(solve(name), q, 1e-4, 1e-11)
        d_state, d_period = jac.column(name)
        bound = error + jac.accuracy[names.index(name)]
        assert np.all(np.abs(np.append(d_state, d_period) - reference) <= bound), (name, d_state, d_period, reference,
                                                                                   error)
        assert abs(d_period) > 0.1  # the period moves: the comparison is not of zeros


def test_a_singular_orbit_or_one_without_a_problem_is_refused(trilinear_flow):
    """Without damping or forcing, the free oscillator's orbit of period 2 pi closes from every state near it:
    ``M = I``, and its periodicity equations are singular."""
    from dataclasses import replace

    guess = find_periodic_orbit(trilinear_flow, linear_response_state(dict(TRI, omega=0.6)), parameters={"omega": 0.6})
    resonant = replace(guess, state0=np.array([0.1, 0.0]), period=2 * np.pi,
                       parameters=trilinear_flow.parameters({"c": 0.0, "f0": 0.0, "omega": 1.0}))
    with pytest.raises(SaltationError, match="singular.*eigenvalues 1"):
        orbit_parameter_jacobian(resonant)
    with pytest.raises(SaltationError, match="holds no shooting problem"):
        orbit_parameter_jacobian(replace(guess, problem=None))
    with pytest.raises(ModelError, match="nope"):
        orbit_parameter_jacobian(guess, parameters=["nope"])
    with pytest.raises(KeyError, match="f0"):
        orbit_parameter_jacobian(guess, parameters=["c"]).column("f0")
