"""Shooting from degenerate guesses: a right orbit or a named error, never a wrong number.

Property-based (hypothesis) over piecewise-affine models whose orbits are known in closed form
(``tests/references.py``), with drawn parameters and guesses placed on a switching surface, at a
turning point, inside a sticking set, at an equilibrium, on the orbit itself, and with period
guesses near 0 (1e-300 .. 1e-3) and near the true one:

* the relay oscillator with negative damping ``x'' - 2 z x' + x = -F sgn(x')``: one (unstable)
  symmetric cycle, period ``2 pi / w``, turning points ``+-F (r + 1) / (r - 1)``, multipliers
  ``1, r^2`` with ``r = exp(pi z / w)``, ``w = sqrt(1 - z^2)``; sticking set ``|x| <= F`` on ``v = 0``;
* Coulomb friction on fixed ground, the same model with ``z = 0``: no periodic orbit at all
  (the energy decreases), every orbit stops in the sticking set;
* the forced bilinear oscillator ``x'' + 2 z x' + x + k2 max(x - d, 0) = a cos(w t)``: its one
  periodic orbit (``k2 < 4 z``) never reaching ``x = d``, crossing it without effect (``k2 = 0``) or
  into a stiffer spring, from matrix exponentials (saltation matrices I: the field is continuous);
* the forced relay ``x'' + 2 z x' + x = a cos(w t) - F sgn(x')`` (Coulomb friction on fixed ground,
  forced, ``F < a``): orbits that cross ``v = 0`` (saltation matrices ``diag(1, v'+ / v'-)``) or stick
  on it (Filippov; a multiplier 0), checked by the closed-form period map from the orbit's own state;
* every tolerance: the forced bilinear orbit from next to it, at ``rtol`` from 1e-12 to 0.5, on the exact
  flow (the closed-form orbit to rounding) and on DOP853 (an orbit or a named error, never a stationary state);
* far times: a forced orbit at ``t0 = 1e12`` is the ``t0 = 0`` orbit at ``t0 mod T``; and a period
  guess that contradicts the forcing period is a ``ModelError`` (the shipped trilinear model).

Each draw either returns the closed-form orbit (state on it, period, multipliers, the trivial
one included, to 1e-8), or raises a subclass of ``saltation.SaltationError``; any other
exception fails.  A ``StationaryStateError`` must name a state that does not move: a point of
the sticking set, or one whose speed times the period is below the integration's resolution.

Tolerances: the modes are affine, so saltation steps them with the exact flow (rounding:
1e-12 relative).  Newton stops once its residual is below ``1e-10 (1 + |u|)``; the error it
leaves is ``J^-1`` times that residual.  Forced orbits: ``|(M - I)^-1|`` with the closed-form
monodromy, twice; the forced relay's closure from the orbit's own state: twice the residual.
Autonomous relay cycles: ``NEWTON = 1e3``, a bound of ``|J^-1|`` for the drawn range
(``|r^2 - 1| >= 0.37``, speed on the cycle at least 0.02).  Multipliers to 1e-8 times the
largest one (the monodromy's scale).

Runtime: module-level flows (compiled once per machine, then loaded), the hypothesis profile ``ci``
of conftest.py (50 examples per property: some 10 s in all);
``HYPOTHESIS_PROFILE=thorough python -m pytest tests/orbits/test_degenerate_orbits.py`` draws 1000 per
property.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import references as R
from hypothesis import assume, example, given
from hypothesis import strategies as st
from scipy.linalg import expm

import saltation
from saltation import (
    Crossing,
    EventKind,
    Flow,
    Mode,
    PiecewiseSystem,
    Tolerances,
    Transition,
    find_periodic_orbit,
)
from saltation.models import trilinear

#: closed-form piecewise-affine flows are exact to rounding
ROUNDING = 1e-12
#: multipliers, the trivial one included, relative to the largest one (the monodromy's scale: Newton's
#: residual of 1e-10 moves the monodromy of a cycle with multiplier 72 by some 1e-8 absolute)
MULTIPLIERS = 1e-8
#: a bound of the inverse shooting Jacobian of the relay cycles (see the module docstring)
NEWTON = 1e3
#: a state whose speed times the period is below this (relative) does not move by its own motion
RESOLUTION = 1e-6


# -- the models, compiled once per module -------------------------------------------------------

@functools.cache
def relay_flow() -> Flow:
    """``x'' - 2 z x' + x = -F sgn(x')``; with ``z = 0`` Coulomb friction on fixed ground."""
    return Flow(PiecewiseSystem(
        name="relay_negative_damping",
        states=["x", "v"],
        parameters={"z": 0.25, "F": 1.0},
        modes=[
            Mode("plus", ["v", "2*z*v - x - F"], domain=["v > 0"]),
            Mode("minus", ["v", "2*z*v - x + F"]),
        ],
        surfaces={"v": "v"},
        transitions=[
            Transition("plus", "v", Crossing.FALLING, "minus"),
            Transition("minus", "v", Crossing.RISING, "plus"),
        ],
    ))


@functools.cache
def bilinear_flow() -> Flow:
    """``x'' + 2 z x' + x + k2 max(x - d, 0) = a cos(w t)``."""
    return Flow(PiecewiseSystem(
        name="forced_bilinear",
        states=["x", "v"],
        parameters={"z": 0.2, "a": 1.0, "w": 1.2, "k2": 0.6, "d": 0.3},
        modes=[
            Mode("right", ["v", "-2*z*v - x - k2*(x - d) + a*cos(w*t)"], domain=["x - d > 0"]),
            Mode("left", ["v", "-2*z*v - x + a*cos(w*t)"]),
        ],
        surfaces={"split": "x - d"},
        transitions=[
            Transition("left", "split", Crossing.RISING, "right"),
            Transition("right", "split", Crossing.FALLING, "left"),
        ],
        period="2*pi/w",
    ))


@functools.cache
def forced_relay_flow() -> Flow:
    """``x'' + 2 z x' + x = a cos(w t) - F sgn(x')``: Coulomb friction on fixed ground, forced (Filippov)."""
    return Flow(PiecewiseSystem(
        name="forced_relay",
        states=["x", "v"],
        parameters={"z": 0.1, "a": 1.0, "w": 1.2, "F": 0.3},
        modes=[
            Mode("plus", ["v", "-2*z*v - x - F + a*cos(w*t)"], domain=["v > 0"]),
            Mode("minus", ["v", "-2*z*v - x + F + a*cos(w*t)"]),
        ],
        surfaces={"v": "v"},
        transitions=[
            Transition("plus", "v", Crossing.FALLING, "minus"),
            Transition("minus", "v", Crossing.RISING, "plus"),
        ],
        period="2*pi/w",
    ))


@functools.cache
def trilinear_flow() -> Flow:
    return Flow(trilinear())


# -- outcomes ---------------------------------------------------------------------------------

def outcome(call):
    """The orbit ``call()`` returns, or the named saltation error it raises (any other exception propagates)."""
    try:
        return call()
    except saltation.SaltationError as err:
        assert type(err) is not saltation.SaltationError, f"an unnamed SaltationError: {err}"
        return err


def relay_speed(state, z: float, F: float) -> float:
    """The speed at ``state`` in the mode it starts in (``plus`` for ``v > 0``, else ``minus``), closed form."""
    x, v = float(state[0]), float(state[1])
    return math.hypot(v, 2 * z * v - x - F) if v > 0 else math.hypot(v, 2 * z * v - x + F)


def check_relay_error(err: saltation.SaltationError, z: float, F: float) -> None:
    """A stationary state must be one: in the sticking set, or (a period shrunk to zero) not moving over its period
    (its speed times the period below the resolution: near an equilibrium of its mode, or a period of ~0)."""
    if isinstance(err, saltation.StationaryStateError) and len(err.state):
        x = np.asarray(err.state)
        moves = relay_speed(x, z, F) * abs(err.period)
        assert R.relay_stationary(x, F) or moves <= RESOLUTION * (1 + np.abs(x).max()), (str(err), x, err.period)


def split_multipliers(multipliers) -> tuple[complex, complex]:
    m = sorted(np.asarray(multipliers, complex), key=lambda q: abs(q - 1.0))
    return m[0], m[1]


def check_relay_orbit(orbit, z: float, F: float) -> None:
    cyc = R.relay_cycle(z, F)
    assert cyc.multiplier == pytest.approx(cyc.multiplier_det_rule, rel=1e-13)  # the reference's own cross-check
    newton = NEWTON * orbit.residual_norm
    assert abs(orbit.period - cyc.period) <= ROUNDING * cyc.period + newton, (orbit.period, cyc.period)
    assert R.relay_distance_to_cycle(z, F, orbit.state0) <= ROUNDING * cyc.turning_point + newton, orbit.state0
    # the reported multipliers, and the raw monodromy's eigenvalues
    scale = max(1.0, cyc.multiplier)
    for mults in (orbit.multipliers, np.linalg.eigvals(orbit.monodromy)):
        trivial, nontrivial = split_multipliers(mults)
        assert abs(trivial - 1.0) <= MULTIPLIERS * scale, mults
        assert abs(nontrivial - cyc.multiplier) <= MULTIPLIERS * scale, (mults, cyc.multiplier)
    # one crossing each way per period, each logged once
    events = orbit.events
    assert sorted((e.mode_from, e.mode_to) for e in events) == [("minus", "plus"), ("plus", "minus")], events
    assert all(e.kind == EventKind.TRANSITION for e in events)


# -- strategies -------------------------------------------------------------------------------

tiny_periods = st.floats(-300.0, -3.0).map(lambda e: 10.0**e)


def period_guesses(true_period: float):
    return st.one_of(tiny_periods, st.just(true_period), st.floats(0.9, 1.1).map(lambda s: s * true_period))


@st.composite
def relay_cases(draw):
    z = draw(st.floats(0.05, 0.6))
    F = draw(st.floats(0.1, 2.0))
    cyc = R.relay_cycle(z, F)
    a = cyc.turning_point
    kind = draw(st.sampled_from(["turning_point", "switching_surface", "sticking_set", "equilibrium", "on_cycle",
                                 "near_cycle"]))
    if kind == "turning_point":
        guess = [draw(st.sampled_from([a, -a])), 0.0]
    elif kind == "switching_surface":
        guess = [draw(st.floats(-2 * a, 2 * a)), 0.0]
    elif kind == "sticking_set":
        guess = [draw(st.floats(-F, F)), 0.0]
    elif kind == "equilibrium":  # of mode plus (-F, 0), of mode minus (F, 0); the origin
        guess = [draw(st.sampled_from([-F, F, 0.0])), 0.0]
    else:
        guess = list(R.relay_cycle_state(z, F, draw(st.floats(0.0, cyc.period))))
        if kind == "near_cycle":
            guess = [g + draw(st.floats(-0.05, 0.05)) * a for g in guess]
    return z, F, kind, guess, draw(period_guesses(cyc.period))


@st.composite
def coulomb_cases(draw):
    F = draw(st.floats(0.1, 2.0))
    kind = draw(st.sampled_from(["switching_surface", "sticking_set", "equilibrium", "anywhere"]))
    if kind == "switching_surface":  # a turning point of the decaying oscillation, or in the sticking set
        guess = [draw(st.floats(-10 * F, 10 * F)), 0.0]
    elif kind == "sticking_set":
        guess = [draw(st.floats(-F, F)), 0.0]
    elif kind == "equilibrium":
        guess = [draw(st.sampled_from([-F, F, 0.0])), 0.0]
    else:
        guess = [draw(st.floats(-10 * F, 10 * F)), draw(st.floats(-10 * F, 10 * F))]
    return F, kind, guess, draw(period_guesses(2 * math.pi))


@st.composite
def bilinear_cases(draw):
    z = draw(st.floats(0.1, 0.6))
    a = draw(st.floats(0.5, 2.0))
    w = draw(st.floats(0.6, 2.0))
    k2 = draw(st.one_of(st.just(0.0), st.floats(0.0, 3.9 * z)))
    left = R.bilinear_modes(z, a, w, 0.0, 0.0)[0]
    amplitude = float(np.max(np.abs([left.particular(t)[0] for t in np.linspace(0, 2 * math.pi / w, 64)])))
    d = draw(st.floats(-1.3, 1.3)) * amplitude  # |d| > amplitude: the surface may never be reached
    ref = R.bilinear_orbit(z, a, w, k2, d)
    assume(ref is not None)
    T = ref.period
    kind = draw(st.sampled_from(["on_orbit", "surface_at_crossing", "switching_surface", "turning_point", "rest",
                                 "anywhere"]))
    t0 = draw(st.floats(0.0, T))
    if kind == "on_orbit":
        guess = ref.state(t0)
    elif kind == "surface_at_crossing" and ref.crossings:  # on the surface at the instant the orbit crosses it
        t0 = draw(st.sampled_from([c[0] for c in ref.crossings]))
        guess = ref.state(t0)
        guess[0] = d
    elif kind == "turning_point" and ref.turning_times():
        t0 = draw(st.sampled_from(ref.turning_times()))
        guess = ref.state(t0)
        guess[1] = 0.0
    elif kind in ("switching_surface", "surface_at_crossing", "turning_point"):
        guess = np.array([d, draw(st.floats(-3.0, 3.0))])
    elif kind == "rest":  # the unforced left mode's equilibrium
        guess = np.zeros(2)
    else:
        guess = np.array([draw(st.floats(-3.0, 3.0)), draw(st.floats(-3.0, 3.0))])
    period = draw(st.one_of(st.none(), st.none(), period_guesses(T)))
    return {"z": z, "a": a, "w": w, "k2": k2, "d": d}, ref, kind, t0, [float(g) for g in guess], period


# -- properties -------------------------------------------------------------------------------

@given(relay_cases())
@example((0.25, 1.0, "turning_point", [R.relay_cycle(0.25, 1.0).turning_point, 0.0], R.relay_cycle(0.25, 1.0).period))
@example((0.25, 1.0, "sticking_set", [0.5, 0.0], R.relay_cycle(0.25, 1.0).period))
@example((0.25, 1.0, "on_cycle", list(R.relay_cycle_state(0.25, 1.0, 1.0)), 1e-300))
@example((0.599609375, 1.0, "turning_point", [1.2099631779070683, 0.0], 1e-4))  # near the edge of the sticking set
@example((0.5625, 1.0, "turning_point", [1.2674923801221267, 0.0], 6.857295127704517))  # multiplier 72
def test_relay_oscillator(case):
    z, F, kind, guess, period = case
    result = outcome(lambda: find_periodic_orbit(relay_flow(), guess, parameters={"z": z, "F": F}, period=period))
    if isinstance(result, saltation.SaltationError):
        check_relay_error(result, z, F)
        if kind == "sticking_set" and abs(guess[0]) < F:
            # nothing moves from there (Newton's first residual is 0): the error says it stands still
            assert isinstance(result, saltation.StationaryStateError), result
        # from the cycle itself with its period, Newton starts at the solution: it must be found
        assert not (kind in ("turning_point", "on_cycle") and period == R.relay_cycle(z, F).period), result
    else:
        assert kind != "sticking_set" or abs(guess[0]) >= F
        check_relay_orbit(result, z, F)


@given(coulomb_cases())
@example((0.5, "switching_surface", [3.0, 0.0], 2 * math.pi))
@example((0.5, "equilibrium", [0.5, 0.0], 2 * math.pi))
@example((0.7001513769944144, "switching_surface", [4.243050789658888, 0.0], 2 * math.pi))  # Newton's period 1.6e16
@example((1.4703132660826086, "anywhere", [-8.125, 0.75], 2 * math.pi))
def test_coulomb_friction_has_no_periodic_orbit(case):
    F, kind, guess, period = case
    result = outcome(lambda: find_periodic_orbit(relay_flow(), guess, parameters={"z": 0.0, "F": F}, period=period))
    assert isinstance(result, saltation.SaltationError), f"an orbit where there is none: {result}"
    check_relay_error(result, 0.0, F)
    if kind == "sticking_set" and abs(guess[0]) < F:
        assert isinstance(result, saltation.StationaryStateError), result


def assert_multipliers(got, expected) -> None:
    got, expected = R.sorted_multipliers(got), R.sorted_multipliers(expected)
    scale = max(1.0, float(np.abs(expected).max()))
    assert np.max(np.abs(got - expected)) <= MULTIPLIERS * scale, (got, expected)


def check_forced_orbit(orbit, ref: R.ForcedOrbit, t0: float) -> None:
    expected = ref.state(t0)
    M = ref.monodromy(t0)
    newton = 2 * np.linalg.norm(np.linalg.inv(M - np.eye(2)), 2) * orbit.residual_norm
    assert orbit.period == pytest.approx(ref.period, rel=ROUNDING)
    assert np.linalg.norm(orbit.state0 - expected) <= ROUNDING * (1 + np.linalg.norm(expected)) + newton, \
        (orbit.state0, expected)
    assert_multipliers(orbit.multipliers, ref.multipliers)
    # the closed-form monodromy from t0 itself, and the orbit's crossings of x = d, each logged once
    np.testing.assert_allclose(orbit.monodromy, M, atol=MULTIPLIERS)
    assert sorted(e.mode_to for e in orbit.events) == sorted("right" if c[1] > 0 else "left" for c in ref.crossings)


def at_crossing(ref, params: dict, index: int):
    """The case of a guess on the surface at the instant of the reference orbit's event ``index``."""
    t0 = ref.crossings[index][0]
    guess = ref.state(t0)
    guess[0] = params["d"]
    return params, ref, "surface_at_crossing", t0, [float(g) for g in guess], None


_BILINEAR = {"z": 0.2, "a": 1.0, "w": 1.2, "k2": 0.6, "d": 0.3}
_SHORT_EXCURSION = {"z": 0.5, "a": 1.0, "w": 1.0, "k2": 0.0, "d": 0.9996891820008162}
_SLOW = {"z": 0.59765625, "a": 1.0, "w": 0.6015625, "k2": 1.0, "d": 0.06501084261206838}


@given(bilinear_cases())
@example(at_crossing(R.bilinear_orbit(**_BILINEAR), _BILINEAR, 0))  # upwards into the stiffer spring
@example(at_crossing(R.bilinear_orbit(**_BILINEAR), _BILINEAR, 1))
@example(at_crossing(R.bilinear_orbit(**_SHORT_EXCURSION), _SHORT_EXCURSION, 0))  # above x = d for 0.05 of 6.28
@example(at_crossing(R.bilinear_orbit(**_SLOW), _SLOW, 1))  # upwards
def test_forced_bilinear_oscillator(case):
    params, ref, kind, t0, guess, period = case
    assert R.bilinear_unique(params["z"], params["k2"])  # one periodic orbit: the reference's
    result = outcome(lambda: find_periodic_orbit(bilinear_flow(), guess, parameters=params, period=period, t0=t0))
    if isinstance(result, saltation.SaltationError):
        # named, and never a stationary state: the forcing (a >= 0.5) never lets the state rest
        assert not isinstance(result, saltation.StationaryStateError), result
        # from the orbit itself at its own time, Newton starts at the solution: it must be found
        on_orbit = np.linalg.norm(np.array(guess) - ref.state(t0)) <= ROUNDING * (1 + np.linalg.norm(guess))
        exact = kind == "on_orbit" or (kind in ("surface_at_crossing", "turning_point") and on_orbit)
        assert not (exact and period is None), f"no orbit from the {kind} guess {guess} at t0 = {t0}: {result!r}"
        return
    check_forced_orbit(result, ref, t0)


@st.composite
def loose_tolerances(draw):
    """Tolerances from tight to very loose: ``rtol`` log-uniform in [1e-12, 0.5], ``atol`` 1e-4 to 1 times it."""
    rtol = 10.0 ** draw(st.floats(-12.0, math.log10(0.5)))
    return Tolerances(rtol=rtol, atol=rtol * 10.0 ** draw(st.floats(-4.0, 0.0)), exact_affine=draw(st.booleans()))


@given(bilinear_cases(), loose_tolerances())
@example((_BILINEAR, R.bilinear_orbit(**_BILINEAR), "on_orbit", 1.0, None, None), Tolerances(rtol=0.05, atol=0.005))
@example((_BILINEAR, R.bilinear_orbit(**_BILINEAR), "on_orbit", 1.0, None, None),
         Tolerances(rtol=0.05, atol=0.005, exact_affine=False))
def test_forced_orbits_at_every_tolerance(case, tolerances):
    """Near its orbit, a forced orbit is found at any tolerance, never taken for a stationary state (100 times a
    loose tolerance is the orbit's own size: :func:`saltation.orbits.shooting.stationary_floor` caps it).  The
    exact flow of its affine modes does not depend on the tolerances (they govern its dense output only): the
    orbit is the closed-form one to rounding.  DOP853 at such tolerances is only as accurate as they are, or
    Newton fails on its noise: a named error then."""
    params, ref, _, t0, _, _ = case
    guess = ref.state(t0) * (1.0 + 1e-3)
    result = outcome(lambda: find_periodic_orbit(bilinear_flow(), guess, parameters=params, t0=t0,
                                                 tolerances=tolerances))
    assert not isinstance(result, saltation.StationaryStateError), (tolerances, result)
    if tolerances.exact_affine:
        assert not isinstance(result, saltation.SaltationError), (tolerances, result)
        check_forced_orbit(result, ref, t0)


@st.composite
def forced_relay_cases(draw):
    z = draw(st.floats(0.02, 0.3))  # damped: isolated orbits (z = 0 has neutral families)
    a = draw(st.floats(0.5, 2.0))
    w = draw(st.floats(0.5, 2.5))
    F = draw(st.floats(0.05, 0.8)) * a
    ref = R.forced_relay_orbit(z, a, w, F)
    assume(ref is not None)
    T = ref.period
    kind = draw(st.sampled_from(["on_orbit", "surface_at_event", "switching_surface", "sticking_set", "equilibrium",
                                 "anywhere"]))
    t0 = draw(st.floats(0.0, T))
    centre = a * math.cos(w * t0)  # the sticking set at t0: |x - a cos(w t0)| < F on v = 0
    if kind == "on_orbit":
        guess = list(ref.state(t0))
    elif kind == "surface_at_event":  # on v = 0 at the instant the orbit crosses it, sticks or leaves the stick
        event = draw(st.sampled_from(ref.events))
        t0, guess = event.t, [event.x, 0.0]
    elif kind == "switching_surface":
        guess = [draw(st.floats(-3.0, 3.0)), 0.0]
    elif kind == "sticking_set":
        guess = [centre + draw(st.floats(-1.0, 1.0)) * F, 0.0]
    elif kind == "equilibrium":  # a mode's field vanishes there at t0: the edges of the sticking set
        guess = [centre + draw(st.sampled_from([-F, F])), 0.0]
    else:
        guess = [draw(st.floats(-3.0, 3.0)), draw(st.floats(-3.0, 3.0))]
    period = draw(st.one_of(st.none(), st.none(), period_guesses(T)))
    return {"z": z, "a": a, "w": w, "F": F}, ref, kind, t0, guess, period


def at_event(params: dict, index: int):
    """The case of a guess on ``v = 0`` at the instant of the reference orbit's event ``index``."""
    ref = R.forced_relay_orbit(**params)
    event = ref.events[index]
    return params, ref, "surface_at_event", event.t, [event.x, 0.0], None


_CROSSING, _STICKING = {"z": 0.1, "a": 1.0, "w": 1.2, "F": 0.3}, {"z": 0.1, "a": 1.0, "w": 1.5, "F": 0.6}


@given(forced_relay_cases())
@example(at_event(_CROSSING, 0))  # on v = 0 as the orbit crosses it upwards
@example(at_event(_CROSSING, 1))  # downwards
@example(at_event(_STICKING, 0))  # as it starts sticking
@example(at_event(_STICKING, 1))  # as it leaves the stick
@example(at_event({"z": 0.25, "a": 1.0, "w": 1.0, "F": 0.625}, 3))  # as it leaves the second stick
@example(at_event({"z": 0.21875, "a": 1.0, "w": 1.890625, "F": 0.75}, 1))  # the stick's end at t0 and at t0 + T
def test_forced_relay(case):
    """Orbits crossing v = 0 or sticking on it, against the closed-form period map from the orbit's own state."""
    params, ref, kind, t0, guess, period = case
    result = outcome(lambda: find_periodic_orbit(forced_relay_flow(), guess, parameters=params, period=period, t0=t0))
    if isinstance(result, saltation.SaltationError):
        # with F < a nothing stays stuck for a whole period: there is no stationary state
        assert not isinstance(result, saltation.StationaryStateError), result
        assert not (kind in ("on_orbit", "surface_at_event") and period is None), \
            f"no orbit from the {kind} guess {guess} at t0 = {t0}: {result!r}"
        return
    orbit = result
    try:
        closure, events, M = R.forced_relay_check(params["z"], params["a"], params["w"], params["F"], orbit.state0,
                                                  orbit.t0)
    except R.Grazing:  # the orbit meets the sticking set's edge: crossing and sticking are both its limits
        assume(False)
    assert orbit.period == pytest.approx(ref.period, rel=ROUNDING)
    assert np.linalg.norm(closure) <= ROUNDING * (1 + np.linalg.norm(orbit.state0)) + 2 * orbit.residual_norm, closure
    assert_multipliers(orbit.multipliers, np.linalg.eigvals(M))
    # each crossing, stick and release once per period
    assert len(orbit.event_labels) == len(events), (orbit.event_labels, [e.kind for e in events])


FAR = {"z": 0.2, "a": 1.0, "w": 1.2, "k2": 0.6, "d": 0.3}
#: Newton to rounding here, so that what is compared is the arithmetic of time, not Newton's default 1e-10
#: (a residual of 1e-10 alone moves these multipliers by 1e-12)
FAR_TOL = 1e-13


@functools.cache
def far_reference() -> tuple[R.ForcedOrbit, object]:
    ref = R.bilinear_orbit(**FAR)
    assert ref.kind == "crossing" and len(ref.crossings) == 2
    return ref, find_periodic_orbit(bilinear_flow(), ref.state(0.0), parameters=FAR, tol=FAR_TOL)


@given(st.floats(3.0, 13.0).map(lambda e: float(round(10.0**e))))
@example(1e12)
def test_forced_orbit_far_in_time(t0):
    """At t0 = 1e12 the orbit is the t0 = 0 orbit, at the phase t0 mod T (to what a double t0 holds)."""
    ref, at_zero = far_reference()
    check_forced_orbit(at_zero, ref, 0.0)
    tau = R.reduced_time(t0, FAR["w"])
    far = find_periodic_orbit(bilinear_flow(), ref.state(tau), parameters=FAR, t0=t0, tol=FAR_TOL)
    np.testing.assert_allclose(R.sorted_multipliers(far.multipliers), R.sorted_multipliers(at_zero.multipliers), rtol=0, atol=1e-12)
    # its state lies on the t0 = 0 orbit, at a time within a few ulps of t0 of t0 mod T
    t_on, distance = R.orbit_time_of(ref, far.state0, tau)
    newton = 2 * np.linalg.norm(np.linalg.inv(ref.monodromy(t_on) - np.eye(2)), 2) * far.residual_norm
    assert distance <= ROUNDING * (1 + np.linalg.norm(far.state0)) + newton, (far.state0, distance)
    assert abs(t_on - tau) <= 4 * math.ulp(t0), (t_on, tau)


@given(st.floats(0.5, 5.0), st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)))
@example(5.0, (0.5, 0.5))
def test_a_period_that_contradicts_the_forcing_is_a_model_error(period, state):
    with pytest.raises(saltation.ModelError, match="forc"):
        find_periodic_orbit(trilinear_flow(), list(state), parameters={"omega": 1.2}, period=period)


def test_the_forcing_period_itself_is_accepted():
    flow = trilinear_flow()
    given_period = find_periodic_orbit(flow, [0.5, 0.5], parameters={"omega": 1.2}, period=2 * math.pi / 1.2)
    without = find_periodic_orbit(flow, [0.5, 0.5], parameters={"omega": 1.2})
    assert given_period.period == pytest.approx(2 * math.pi / 1.2, rel=ROUNDING)
    np.testing.assert_allclose(given_period.state0, without.state0, rtol=0, atol=ROUNDING)


# -- the references against themselves (their cross-checks) ---------------------------------------

@pytest.mark.parametrize("z, F", [(0.05, 0.1), (0.25, 1.0), (0.6, 2.0)])
def test_relay_reference_cross_checks(z, F):
    cyc = R.relay_cycle(z, F)
    # half a period by the matrix exponential takes the turning point to its mirror image
    np.testing.assert_allclose(R.relay_half_cycle_by_expm(z, F, cyc.turning_point), [-cyc.turning_point, 0.0],
                               rtol=0, atol=ROUNDING * cyc.turning_point)
    # return map of the half-cycle and the determinant rule give the same multiplier
    assert cyc.multiplier == pytest.approx(cyc.multiplier_det_rule, rel=ROUNDING)
    # the closed-form cycle is at distance 0 from itself, and a point off it is not
    for t in np.linspace(0.0, cyc.period, 7):
        state = R.relay_cycle_state(z, F, t)
        assert R.relay_distance_to_cycle(z, F, state) <= ROUNDING * cyc.turning_point
        assert R.relay_distance_to_cycle(z, F, 1.01 * state) >= 1e-3 * cyc.turning_point


def test_coulomb_reference_has_no_fixed_point():
    """Every turning point outside the sticking set is followed by a smaller one: the orbit runs down."""
    F = 0.5
    lo, hi = R.coulomb_sticking_set(F)
    for a in [-7.3, -1.2, -0.51, 0.51, 1.0, 2.9, 40.0]:
        assert not lo <= a <= hi
        assert abs(R.coulomb_next_turning_point(F, a)) == pytest.approx(abs(abs(a) - 2 * F))
        assert abs(R.coulomb_next_turning_point(F, a)) < abs(a)


@pytest.mark.parametrize("k2, d", [(0.0, 0.3), (0.6, 0.3), (0.6, 5.0), (0.6, -5.0), (0.7, -0.2)])
def test_bilinear_reference_cross_checks(k2, d):
    z, a, w = 0.2, 1.0, 1.2
    ref = R.bilinear_orbit(z, a, w, k2, d)
    left, right = R.bilinear_modes(z, a, w, k2, d)
    # the closed-form exponential is scipy's, and the closed-form monodromy is the product of scipy's
    for tau in (0.3, 2.0, ref.period):
        np.testing.assert_allclose(left.exp(tau), expm(left.A * tau), rtol=0, atol=ROUNDING)
        np.testing.assert_allclose(right.exp(tau), expm(right.A * tau), rtol=0, atol=ROUNDING)
    np.testing.assert_allclose(ref.monodromy(0.0), R.bilinear_monodromy_by_expm(ref), rtol=0, atol=ROUNDING)
    # periodic, and the uniqueness certificate agrees with a numerical common Lyapunov function
    np.testing.assert_allclose(ref.state(ref.period - 1e-12), ref.state0, rtol=0, atol=1e-11)
    assert R.bilinear_unique(z, k2) and R.common_lyapunov([left.A, right.A]) is not None
    # the three kinds: never reached (d beyond the orbit), crossed twice
    kind = "left" if d > 1.0 else "right" if d < -1.0 else "crossing"
    assert ref.kind == kind
    if kind != "crossing":  # the linear oscillator: multipliers eig(expm(A T))
        mode = left if kind == "left" else right
        np.testing.assert_allclose(ref.multipliers, R.sorted_multipliers(np.linalg.eigvals(expm(mode.A * ref.period))),
                                   rtol=0, atol=ROUNDING)
    else:
        assert [c[1] for c in sorted(ref.crossings)] in ([1, -1], [-1, 1])
        for tc, _ in ref.crossings:
            assert ref.state(tc)[0] == pytest.approx(d, abs=ROUNDING)
