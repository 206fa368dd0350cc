"""A forced model's constant solution is a periodic orbit (an autonomous model's is refused as stationary).

A damped oscillator ``x'' + 2 zeta x' + x = 0`` below a moving wall ``x = 1 + b sin(omega t)`` (``b < 1``), and a
stiff contact beyond it.  The wall never reaches the rest state ``(0, 0)``, so it is a solution of period
``2 pi / omega`` whatever the forcing does beyond it: its multipliers are the eigenvalues of ``expm(A T)``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit

ZETA, OMEGA = 0.1, 1.3


def test_the_rest_state_below_a_moving_wall_is_a_forced_orbit():
    system = PiecewiseSystem(
        "test_rest_below_moving_wall", states=["x", "v"], parameters={"zeta": ZETA, "omega": OMEGA, "b": 0.5},
        modes=[Mode("free", ["v", "-2*zeta*v - x"], domain=["x - 1 - b*sin(omega*t) < 0"]),
               Mode("contact", ["v", "-2*zeta*v - x - 50*(x - 1 - b*sin(omega*t))"])],
        surfaces={"wall": "x - 1 - b*sin(omega*t)"},
        transitions=[Transition("free", "wall", Crossing.RISING, "contact"),
                     Transition("contact", "wall", Crossing.FALLING, "free")],
        period="2*pi/omega",
    )
    orbit = find_periodic_orbit(Flow(system), [0.0, 0.0])
    # the rest state is an exact solution: Newton starts there and the exact flow of the affine mode keeps it
    np.testing.assert_allclose(orbit.state0, [0.0, 0.0], rtol=0, atol=1e-12)
    assert abs(orbit.period - 2 * math.pi / OMEGA) <= 4 * np.finfo(float).eps * orbit.period and not orbit.events
    expected = np.linalg.eigvals(expm(np.array([[0.0, 1.0], [-1.0, -2 * ZETA]]) * orbit.period))
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), np.sort_complex(expected), rtol=0, atol=1e-10)
    assert orbit.stable
