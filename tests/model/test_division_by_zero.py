"""A model's expression that divides by zero somewhere is the model's business, not an internal error.

* A Jeffcott rotor in a clearance circle ``sqrt(x^2 + y^2) = delta`` (the contact force ``beta (1 - delta/r)``):
  the circle's indicator has no gradient at its centre, ``x / r = 0 / 0``, which is where a user starts (at rest).
  The state there is a distance ``delta`` from the surface, and the orbit from it is the free whirl, in closed
  form: amplitude ``rho omega^2 / sqrt((1 - omega^2)^2 + (2 zeta omega)^2)`` in each direction, multipliers the
  eigenvalues of ``expm(A T)`` of the damped oscillator (each twice).
* A field that divides by zero at the start gives the engine's error naming the mode, not ``ZeroDivisionError``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit
from saltation.errors import IntegrationError

ZETA, BETA, DELTA, RHO, OMEGA = 0.05, 20.0, 1.0, 0.5, 0.7
R = "sqrt(x**2 + y**2)"


def rotor() -> PiecewiseSystem:
    fx, fy = "rho*omega**2*cos(omega*t)", "rho*omega**2*sin(omega*t)"
    return PiecewiseSystem(
        name="test_rotor_clearance", states=["x", "y", "vx", "vy"],
        parameters={"zeta": ZETA, "beta": BETA, "delta": DELTA, "rho": RHO, "omega": OMEGA},
        modes=[Mode("contact", ["vx", "vy", f"-2*zeta*vx - x - beta*(1 - delta/{R})*x + {fx}",
                                f"-2*zeta*vy - y - beta*(1 - delta/{R})*y + {fy}"], domain=[f"{R} - delta > 0"]),
               Mode("free", ["vx", "vy", f"-2*zeta*vx - x + {fx}", f"-2*zeta*vy - y + {fy}"])],
        surfaces={"gap": f"{R} - delta"},
        transitions=[Transition("free", "gap", Crossing.RISING, "contact"),
                     Transition("contact", "gap", Crossing.FALLING, "free")],
        period="2*pi/omega",
    )


def test_a_start_where_the_indicator_has_no_gradient():
    orbit = find_periodic_orbit(Flow(rotor()), [0.0, 0.0, 0.0, 0.0])
    amplitude = RHO * OMEGA**2 / math.hypot(1 - OMEGA**2, 2 * ZETA * OMEGA)
    assert amplitude < DELTA and not orbit.events  # the free whirl, inside the clearance
    # Newton to 1e-10 on integration at rtol 1e-10 over one period (the closed form is exact)
    assert orbit.amplitude == pytest.approx(amplitude, abs=1e-9)
    T = 2 * math.pi / OMEGA
    single = np.linalg.eigvals(expm(np.array([[0.0, 1.0], [-1.0, -2 * ZETA]]) * T))
    expected = np.sort_complex(np.concatenate([single, single]))
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), expected, rtol=0, atol=1e-9)


def test_a_field_that_divides_by_zero_names_its_mode():
    system = PiecewiseSystem(
        name="test_divides_by_zero", states=["x", "v"], parameters={"a": 1.0},
        modes=[Mode("pole", ["v", "a/x"])], surfaces={"wall": "x - 2"},
        transitions=[Transition("pole", "wall", Crossing.RISING, "pole", reset=["x", "-v"])],
    )
    with pytest.raises(IntegrationError, match="'pole'"):
        Flow(system).run([0.0, 0.0], 0.0, 1.0, system.parameter_vector())
