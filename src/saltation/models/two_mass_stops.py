"""Two forced masses on springs between two compliant stops (a two-degree-of-freedom contact oscillator).

Mass ``m1`` hangs on the spring ``k1`` (damper ``c1``) from the ground, mass ``m2`` on the spring
``k2`` (damper ``c2``) from mass 1, and mass 1 is forced by ``F cos(omega t)``:

    m1 x1'' = -k1 x1 - c1 x1' - k2 (x1 - x2) - c2 (x1' - x2') - P1 + F cos(omega t),
    m2 x2'' = -k2 (x2 - x1) - c2 (x2' - x1') + P2.

Mass 1 meets a compliant stop (spring ``k_s1``, damper ``c_s1``) at the gap ``d1`` above its rest
position, mass 2 another one (``k_s2``, ``c_s2``) at ``d2`` below its rest position.  A stop pushes
only: its force is that of its spring and damper while the mass is beyond the gap and that force
is compressive, and zero otherwise (it never pulls the mass back),

    P1 = k_s1 (x1 - d1) + c_s1 x1'   while  x1 > d1  and  k_s1 (x1 - d1) + c_s1 x1' >= 0,
    P2 = -(k_s2 (x2 + d2) + c_s2 x2')  while  x2 < -d2  and  k_s2 (x2 + d2) + c_s2 x2' <= 0.

This is the contact law of the paper's trilinear system (*Fold bifurcations in discontinuous
systems*, eqs. 4-7; ``saltation.models.trilinear``), the compliant support of Shaw and Holmes (*A
periodically forced piecewise linear oscillator*, J. Sound Vib. 90, 1983) and of Wiercigroch's
models of systems with motion-dependent discontinuities (Chaos, Solitons and Fractals 11, 2000),
given to each mass of a two-degree-of-freedom chain as in Natsiavas (*Dynamics of
multiple-degree-of-freedom oscillators with colliding components*, J. Sound Vib. 165, 1993). The
parameter values are our own, not taken from these sources: the undamped linear modes have the
frequencies 0.765 and 1.848, the forcing (``omega = 0.5``) lies below both, and the masses swing
nearly in phase with it. At ``F = 1`` the stable periodic orbit meets stop 2 near the trough of the
forcing and stop 1 near its peak, once each per period (multipliers of modulus 0.712 and 0.309).
Without contact the orbit is the linear harmonic response; mass 1 reaches its stop first, at
``F = d1 / |X1 / F| = 0.6076930845`` (``(K - omega^2 M + i omega C) X = (F, 0)``). The contact with
stop 1 delays that with stop 2 (at 0.6381 without stop 1) to ``F = 0.7855456194``, where the branch
turns back at once (a smooth fold at 0.7856348579, 9e-5 further) and again at 0.7823154078: the
orbits touching both stops and those touching stop 1 only coexist in between.

Modes: ``free``, ``stop_1``, ``stop_2`` and ``both`` (every one affine, with one harmonic forcing
term: the integrator steps with the exact flow).  Surfaces: ``gap_1 = x1 - d1`` and
``force_1 = k_s1 (x1 - d1) + c_s1 x1'`` for stop 1, ``gap_2 = x2 + d2`` and
``force_2 = k_s2 (x2 + d2) + c_s2 x2'`` for stop 2.  Contact begins on the gap surface (where the
stop's force is ``c_s v``, so the field jumps: the saltation matrix is the rank-one update
``I - (c_s / m) e_v e_x^T`` of the mass's velocity by its position) and ends where the stop's force
vanishes (the field is continuous there: ``S = I``).  The modes are regions of the state space, so
every boundary is listed both ways (backward time), for either state of the other stop.
"""

from __future__ import annotations

import functools

from ..model import Crossing, Mode, PiecewiseSystem, Transition
from .shipped import ShippedModel

RISING, FALLING = Crossing.RISING, Crossing.FALLING

#: our own values (see the module's docstring)
DEFAULTS = {
    "m1": 1.0, "m2": 0.5, "k1": 1.0, "k2": 1.0, "c1": 0.05, "c2": 0.05, "F": 1.0, "omega": 0.5,
    "d1": 1.0, "d2": 1.2, "k_s1": 10.0, "c_s1": 0.2, "k_s2": 10.0, "c_s2": 0.2,
}

GAP_1, FORCE_1 = "x1 - d1", "k_s1*(x1 - d1) + c_s1*v1"
GAP_2, FORCE_2 = "x2 + d2", "k_s2*(x2 + d2) + c_s2*v2"


def _field(stop_1: bool, stop_2: bool) -> list[str]:
    p1 = f" - ({FORCE_1})" if stop_1 else ""
    p2 = f" - ({FORCE_2})" if stop_2 else ""
    return [
        "v1",
        f"(-k1*x1 - c1*v1 - k2*(x1 - x2) - c2*(v1 - v2){p1} + F*cos(omega*t))/m1",
        "v2",
        f"(-k2*(x2 - x1) - c2*(v2 - v1){p2})/m2",
    ]


@functools.lru_cache(maxsize=64)  # a model is immutable: building it again (sympy) is wasted
def two_mass_stops(**overrides: float) -> PiecewiseSystem:
    """The two-mass system with two compliant stops; keyword arguments override the defaults
    ``m1 m2 k1 k2 c1 c2 F omega d1 d2 k_s1 c_s1 k_s2 c_s2``."""
    in_1 = [f"{GAP_1} > 0", f"{FORCE_1} >= 0"]  # stop 1 pushes mass 1 down
    in_2 = [f"{GAP_2} < 0", f"{FORCE_2} <= 0"]  # stop 2 pushes mass 2 up
    transitions = []
    for off, on in (("free", "stop_1"), ("stop_2", "both")):  # stop 1, with stop 2 either way
        transitions += [
            Transition(off, "gap_1", RISING, on, guard=[f"{FORCE_1} >= 0"]),
            Transition(off, "force_1", RISING, on, guard=[f"{GAP_1} > 0"]),
            Transition(on, "force_1", FALLING, off),
            Transition(on, "gap_1", FALLING, off),
        ]
    for off, on in (("free", "stop_2"), ("stop_1", "both")):  # stop 2, with stop 1 either way
        transitions += [
            Transition(off, "gap_2", FALLING, on, guard=[f"{FORCE_2} <= 0"]),
            Transition(off, "force_2", FALLING, on, guard=[f"{GAP_2} < 0"]),
            Transition(on, "force_2", RISING, off),
            Transition(on, "gap_2", RISING, off),
        ]
    return PiecewiseSystem(
        name="two_mass_stops",
        states=["x1", "v1", "x2", "v2"],
        parameters=DEFAULTS | overrides,
        modes=[
            Mode("both", _field(True, True), domain=in_1 + in_2),
            Mode("stop_1", _field(True, False), domain=in_1),
            Mode("stop_2", _field(False, True), domain=in_2),
            Mode("free", _field(False, False)),
        ],
        surfaces={"gap_1": GAP_1, "force_1": FORCE_1, "gap_2": GAP_2, "force_2": FORCE_2},
        transitions=transitions,
        period="2*pi/omega",
    )


SHIPPED = ShippedModel(
    "two_mass_stops",
    two_mass_stops,
    "two forced masses on springs, each against a compliant stop on its own side (forcing F cos(omega t) on mass 1)",
)
