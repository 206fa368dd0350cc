"""Contacts that stick: a plastic impact continued as the motion constrained to the moving surface.

The ball on the table ``s(t) = A sin(omega t)`` with restitution ``e = 0`` (``A omega^2 = 1.046 g`` at
``A = 0.26``): it lands, moves with the table while the contact force ``g + s''(t)`` is positive, and
leaves where it vanishes, at ``t_r = asin(g / (A omega^2)) / omega``.  References in closed form:

* release at ``t_r``; the state there ``(s(t_r), s'(t_r))``; the state at ``t = 0`` (on the table)
  ``(0, A omega)``;
* the landing: the first root after ``t_r`` of ``s(t_r) + s'(t_r) tau - g tau^2 / 2 = s(t_r + tau)``
  (scipy's ``brentq`` on that closed form);
* both multipliers 0: the stuck state is fixed by time alone;
* the stuck phase vanishes where the flight lasts one period, ``A omega cos(omega t_r) = g T / 2``:
  ``A* = (g / omega^2) sqrt(1 + pi^2)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit
from saltation.errors import ModelError

G, OMEGA = 9.81, 2 * math.pi


def ball(e: float = 0.0, A: float = 0.26) -> PiecewiseSystem:
    return PiecewiseSystem(
        name="ball_on_table_sticks", states=["y", "v"],
        parameters={"g": G, "e": e, "A": A, "omega": OMEGA},
        modes=[Mode("flight", ["v", "-g"])],
        surfaces={"table": "y - A*sin(omega*t)"},
        transitions=[Transition("flight", "table", Crossing.FALLING, "flight",
                                reset=["y", "(1 + e)*A*omega*cos(omega*t) - e*v"], sticks=True)],
        period="2*pi/omega",
    )


def release_time(A: float) -> float:
    return math.asin(G / (A * OMEGA**2)) / OMEGA


def landing_time(A: float) -> float:
    tr = release_time(A)
    s = lambda t: A * math.sin(OMEGA * t)  # noqa: E731
    ds = lambda t: A * OMEGA * math.cos(OMEGA * t)  # noqa: E731
    gap = lambda tau: s(tr) + ds(tr) * tau - G * tau**2 / 2 - s(tr + tau)  # noqa: E731
    # the gap opens (its third derivative at the release is positive) and closes once within the period
    taus = np.linspace(1e-3, 1.0, 2001)
    values = [gap(t) for t in taus]
    k = next(i for i in range(len(taus) - 1) if values[i] > 0 >= values[i + 1])
    return tr + brentq(gap, taus[k], taus[k + 1], xtol=1e-15)


def test_the_model_gets_the_stuck_motion_and_its_release():
    system = ball()
    assert system.mode_names == ("flight", "flight@table")
    assert system.surface_names == ("table", "table@release")
    y, v = system.x
    g, e, A, omega = system.p
    t = system.t
    assert list(system.fields[1]) == [v, -A * omega**2 * sp_sin(omega * t)]
    assert (system.indicators[1] - (g - A * omega**2 * sp_sin(omega * t))).simplify() == 0
    assert system.sticking["flight@table"].direction == (0, 1)


def sp_sin(arg):
    import sympy

    return sympy.sin(arg)


def test_a_plastic_ball_sticks_and_is_released_where_the_table_decelerates_at_g():
    A = 0.26
    orbit = find_periodic_orbit(ball(A=A), [0.0, 0.0])
    assert orbit.period == pytest.approx(1.0, rel=1e-15)
    # at t = 0 the ball is on the table, moving with it
    assert orbit.state0 == pytest.approx([0.0, A * OMEGA], abs=1e-12)
    assert orbit.trajectory.events[0].mode_from == "flight@table" or orbit.mode0 == "flight@table"
    events = {e.surface: e for e in orbit.trajectory.events}
    assert set(events) == {"table", "table@release"}
    tr, tl = release_time(A), landing_time(A)
    assert events["table@release"].t == pytest.approx(tr, abs=1e-10)
    assert events["table@release"].x_minus == pytest.approx([A * math.sin(OMEGA * tr), A * OMEGA * math.cos(OMEGA * tr)],
                                                           abs=1e-10)
    assert events["table"].t == pytest.approx(tl, abs=1e-10)
    assert events["table"].mode_to == "flight@table"
    # the stuck state is fixed by time: the period map forgets everything
    assert np.all(np.abs(orbit.multipliers) <= 1e-12)
    assert np.all(np.abs(orbit.monodromy) <= 1e-10)


def test_the_stuck_phase_ends_where_the_flight_lasts_a_period():
    """Along ``A`` the sticking orbit goes on, with no special point, to ``A*``, where the landing meets the
    release: located there (in its bracket), the plastic bouncing orbit takes over."""
    from saltation import ContinuationSettings, continue_orbit

    a_star = G / OMEGA**2 * math.sqrt(1 + math.pi**2)
    start = find_periodic_orbit(ball(A=0.7), [0.0, 0.0])
    branch = continue_orbit(start, "A", bounds=(0.7, 0.85), directions=(1,),
                            settings=ContinuationSettings(ds=0.01, ds_max=0.02))
    assert [sp.kind.value for sp in branch.special_points] == ["nonsmooth_no_crossing"]
    point = branch.special_points[0]
    lo, hi = point.bracket
    assert lo <= point.parameter <= hi
    assert lo - 1e-9 <= a_star <= hi + 1e-9
    assert point.parameter == pytest.approx(a_star, abs=max(point.accuracy, 1e-8))
    for p in branch.points:
        sticking = any("table@release" in label for label in p.event_labels)
        assert sticking == (p.parameter < a_star)
        if sticking:  # (past A*, a plastic impact without sticking leaves the table at its speed: one multiplier)
            assert np.all(np.abs(p.multipliers) <= 1e-10)
        else:
            assert p.event_labels == ("flight -[table-]-> flight",)


def test_a_sticking_impact_needs_a_reset_and_a_side():
    with pytest.raises(ModelError, match=r"sticks=True needs an impact"):
        PiecewiseSystem(name="no_reset", states=["y", "v"], parameters={"g": 9.81},
                        modes=[Mode("flight", ["v", "-g"])], surfaces={"floor": "y"},
                        transitions=[Transition("flight", "floor", Crossing.FALLING, "flight", sticks=True)])
    with pytest.raises(ModelError, match=r"not EITHER"):
        PiecewiseSystem(name="no_side", states=["y", "v"], parameters={"g": 9.81},
                        modes=[Mode("flight", ["v", "-g"])], surfaces={"floor": "y"},
                        transitions=[Transition("flight", "floor", Crossing.EITHER, "flight", reset=["y", "0"],
                                                sticks=True)])
    with pytest.raises(ModelError, match=r"changes 2 states"):
        PiecewiseSystem(name="two_changed", states=["y", "v"], parameters={"g": 9.81},
                        modes=[Mode("flight", ["v", "-g"])], surfaces={"floor": "y"},
                        transitions=[Transition("flight", "floor", Crossing.FALLING, "flight", reset=["0", "0"],
                                                sticks=True)])


def test_a_ball_on_a_fixed_floor_comes_to_rest_and_stays():
    """``e = 0`` on a floor that does not move: it lands once and rests (the force ``g`` never vanishes)."""
    system = PiecewiseSystem(name="ball_rests", states=["y", "v"], parameters={"g": 9.81},
                             modes=[Mode("flight", ["v", "-g"])], surfaces={"floor": "y"},
                             transitions=[Transition("flight", "floor", Crossing.FALLING, "flight",
                                                     reset=["y", "0"], sticks=True)])
    run = Flow(system).run([1.0, 0.0], 0.0, 3.0, system.parameter_vector())
    assert [e.mode_to for e in run.events] == ["flight@floor"]
    assert run.events[0].t == pytest.approx(math.sqrt(2 / 9.81), abs=1e-12)
    assert run.x1 == pytest.approx([0.0, 0.0], abs=1e-12)


# ---------------------------------------------------------------------------------------------------------
# resets that forget


def test_backward_shooting_through_a_reset_that_forgets_is_refused_naming_the_transition():
    """Backward in time a plastic landing cannot be undone: no infinitely unstable orbit lies behind it."""
    orbit = find_periodic_orbit(ball(A=0.26), [0.0, 0.0])
    with pytest.raises(ModelError, match=r"transition \d+ \(flight -\[table-\]-> flight@table\).*forgets"):
        find_periodic_orbit(ball(A=0.26), orbit.state0, backward=True)


def test_an_elastic_impact_still_runs_backwards():
    """A reset with a regular saltation matrix (``e = 0.5``) is not refused backward in time."""
    from saltation.orbits.single import check_resets_run_backwards

    system = ball(e=0.5, A=0.3)
    run = Flow(system).run([0.05, 3.0], 0.0, -0.1, system.parameter_vector(), variational=True)
    assert any(e.surface == "table" for e in run.events)
    check_resets_run_backwards(system, run)  # does not raise


def test_a_complete_chatter_counts_once_in_the_event_identities():
    """How many of the chatter's impacts were resolved before the jump is the integrator's business: the orbit's
    identities keep the run once, also where it wraps round the start of the period."""
    from saltation.orbits.records import _chatter_as_one

    system = ball(e=0.5)
    stuck = system.mode_names.index("flight@table")
    release, impact, land = (0, 0, 0), (0, 2, 0), (0, 1, stuck)
    assert _chatter_as_one(system, (release, impact, impact, impact, land)) == (release, impact, land)
    assert _chatter_as_one(system, (release, impact, land)) == (release, impact, land)
    assert _chatter_as_one(system, (impact, impact, land, release, impact)) == (impact, land, release)
    # two bounces that do not end in a chatter are two events
    assert _chatter_as_one(system, (release, impact, impact)) == (release, impact, impact)


def test_a_chattering_branch_passes_the_section_without_a_false_point():
    """e = 0.5: along A the accumulation point drifts onto the section t0 = 0 (near A = 0.392); the branch moves
    its section off it (where Newton stalls there), and the chatter counts once in the orbits' identities, so no
    change of the event sequence is read as a bifurcation: every orbit sticks (multipliers 0) and no special point
    is reported up to A = 0.394."""
    from saltation import ContinuationSettings, continue_orbit
    from saltation.models import bouncing_ball

    start = find_periodic_orbit(bouncing_ball(e=0.5, A=0.36), [0.0, 0.36 * OMEGA])
    branch = continue_orbit(start, "A", bounds=(0.36, 0.394), directions=(1,),
                            settings=ContinuationSettings(ds=0.004, ds_max=0.004))
    assert branch.special_points == []
    assert branch.points[-1].parameter == pytest.approx(0.394)
    assert any(p.t0 != 0.0 for p in branch.points)  # the section moved
    for p in branch.points:
        assert np.all(np.abs(p.multipliers) <= 1e-10)
        assert any("table@release" in label for label in p.event_labels)
    assert branch.check().ok
