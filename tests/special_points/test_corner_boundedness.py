"""Whether an excursion's saltation matrices stay bounded at a tangency does not depend on how closely the
tangency was located (``saltation.orbits.boundary.corner_saltation_is_bounded``).

At a grazing the denominator ``d = h_x f- + h_t`` of eq. (9) vanishes.  A located grazing has ``d`` of 1e-17 to
1e-7 relative to ``|h_x| |f|``, depending on the tolerances and on the rounding of the machine; the answer must
be the same at every such ``d``.  Closed forms (no integration, so no kernel is compiled):

* an impact ``v -> -r v`` on ``x = s`` of ``x'' = -2 zeta x' - x + cos(omega t)``: eq. (9) gives
  ``S = [[-r, 0], [(f+_v + r f-_v) / v, -r]]``, unbounded as ``v = d -> 0`` (``f_v`` is the acceleration, of order
  one at ``x = s = 2`` where ``cos`` cannot balance the spring);
* a continuous field (a spring that engages at ``x = s``, the same force on both sides there): ``S = I`` at
  every ``d`` and for the entry and exit together.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import Crossing, Mode, PiecewiseSystem, Transition
from saltation.orbits.boundary import corner_saltation_is_bounded, saltation_at_corner

S, R, ZETA, OMEGA = 2.0, 0.8, 0.05, 0.8
FORCING = "cos(omega*t)"


@functools.cache
def impact() -> PiecewiseSystem:
    return PiecewiseSystem(
        "test_corner_impact", states=["x", "v"], parameters={"zeta": ZETA, "omega": OMEGA, "r": R, "s": S},
        modes=[Mode("free", ["v", f"-2*zeta*v - x + {FORCING}"])],
        surfaces={"stop": "x - s"},
        transitions=[Transition("free", "stop", Crossing.RISING, "free", reset=["x", "-r*v"])],
        period="2*pi/omega",
    )


@functools.cache
def spring() -> PiecewiseSystem:
    return PiecewiseSystem(
        "test_corner_spring", states=["x", "v"], parameters={"zeta": ZETA, "omega": OMEGA, "k": 4.0, "s": S},
        modes=[Mode("free", ["v", f"-2*zeta*v - x + {FORCING}"], domain=["x - s < 0"]),
               Mode("contact", ["v", f"-2*zeta*v - x - k*(x - s) + {FORCING}"])],
        surfaces={"stop": "x - s"},
        transitions=[Transition("free", "stop", Crossing.RISING, "contact"),
                     Transition("contact", "stop", Crossing.FALLING, "free")],
        period="2*pi/omega",
    )


# the normal speed at the located tangency, relative to |h_x| |f| (of order one here): what location reaches
speeds = st.builds(lambda e, sign: sign * 10.0 ** e, st.floats(-17.0, -5.0), st.sampled_from([-1.0, 1.0]))
instants = st.floats(0.0, 2 * math.pi / OMEGA)


@settings(max_examples=200, deadline=None)
@given(d=speeds, t=instants)
def test_an_impact_at_a_tangency_is_unbounded_however_closely_it_is_located(d, t):
    system = impact()
    p = system.parameter_vector()
    x = np.array([S, d])
    P = saltation_at_corner(system, [0], t, x, p)
    if P is not None:  # eq. (9) in closed form: the (2, 1) entry is (f+_v + r f-_v) / v
        f_minus = -2 * ZETA * d - S + math.cos(OMEGA * t)
        f_plus = -2 * ZETA * (-R * d) - S + math.cos(OMEGA * t)
        expected = np.array([[-R, 0.0], [(f_plus + R * f_minus) / d, -R]])
        np.testing.assert_allclose(P, expected, rtol=1e-12, atol=1e-12)  # the same formula: rounding units apart
    assert not corner_saltation_is_bounded(system, 0, t, x, p, P)


@settings(max_examples=200, deadline=None)
@given(d=speeds | st.just(0.0), t=instants)
def test_a_continuous_field_is_bounded_however_closely_it_is_located(d, t):
    system = spring()
    p = system.parameter_vector()
    x = np.array([S, d])
    for excursion in ([0], [0, 1]):  # the entry alone, and entry and exit together
        P = saltation_at_corner(system, excursion, t, x, p)
        np.testing.assert_allclose(P, np.eye(2), rtol=0, atol=1e-15)  # S = I on the surface (f+ = f- there)
        assert corner_saltation_is_bounded(system, 0, t, x, p, P)


def test_a_saltation_matrix_that_is_not_finite_is_unbounded():
    system = impact()
    p = system.parameter_vector()
    x = np.array([S, 0.0])
    assert saltation_at_corner(system, [0], 0.0, x, p) is None  # x / 0
    assert not corner_saltation_is_bounded(system, 0, 0.0, x, p, None)
