"""Gallery figure: the ball on its vibrating table, a contact that sticks, with restitution e = 0 and e = 0.5.

Not a hook of its own: ``docs/hooks/gallery.py`` imports :func:`figure_ball_on_table` and computes it like
its other figures (in a child process, at every build; nothing is checked in).  From scratch, with the
shipped ``saltation.models.bouncing_ball`` (its impact declares ``sticks=True``).  Top row, ``e = 0``:

* the sticking orbit at ``A = 0.26`` over two forcing periods, the ball's height and the table's, the
  phase on the table shaded (from the landing to the release at ``t_r = asin(g / (A omega^2)) / omega``);
* the branch continued in ``A`` from there: the share of the period spent on the table, from the events
  of each orbit, against its closed form, down to zero at ``A* = (g / omega^2) sqrt(1 + pi^2)``, where the
  plastic bouncing orbit takes over; and the orbit's nonzero multiplier, 0 while it sticks and
  ``1 - sqrt(Gamma^2 - pi^2)`` beyond ``A*`` (``Gamma = A omega^2 / g``), which reaches -1 at the period
  doubling ``Gamma = sqrt(pi^2 + 4)``.

Bottom row, ``e = 0.5`` (complete chatter, :mod:`saltation.engine.chatter`):

* the orbit at ``A = 0.36`` over two periods: released at ``t_r``, the ball lands, bounces ever lower
  (the impacts kept, against the impact times of the flights in closed form) and the engine jumps to the
  accumulation point (``Trajectory.accumulations``), where it rides on the table until the next release;
  the stuck phase of the flights in closed form shaded;
* the branch continued in ``A`` from ``0.36`` to just beyond ``A* = 0.39692553514``, where the
  accumulation point reaches the release: the stuck phase per period of each orbit, from its events,
  against the flights in closed form (``stick_length``), with the branch's located end; and the same
  near ``A*`` on logarithmic axes.

The flights in closed form (``chatter_reference``, ``stick_length``, ``sticking_ends``) are those of
``tests/engine/test_complete_chatter.py``, copied here (a docs hook does not import the tests), with the
scan for each flight's landing evaluated on an array.

Run ``python docs/hooks/gallery_sticking.py OUT.png`` to compute the figure by hand.
"""

from __future__ import annotations

import math

#: The table's amplitude of the orbit drawn over time, and the range of the branch (e = 0).
A_ORBIT = 0.26
A_RANGE = (0.26, 0.95)
G, OMEGA = 9.81, 2 * math.pi
#: e = 0.5: the restitution, the amplitude of the orbit drawn over time, where the branch's small steps begin,
#: and how far beyond the end of the sticking orbits the branch goes.
E_CHATTER = 0.5
A_CHATTER = 0.36
A_FINE = 0.3965
BEYOND = 3e-4
#: What the last computation of the e = 0.5 panels measured against the flights in closed form (printed by hand).
MEASURED: dict = {}


def release_time(A: float) -> float:
    """``t_r = asin(g / (A omega^2)) / omega``: the table decelerates at ``g``, the contact force vanishes."""
    return math.asin(G / (A * OMEGA**2)) / OMEGA


def landing_time(A: float) -> float:
    """The first landing after the release at ``t_r``: the root of ``s(t_r) + s'(t_r) tau - g tau^2 / 2 = s(t_r +
    tau)`` (the ball leaves with the table's velocity), by ``brentq`` after a scan (no integration)."""
    import numpy as np
    from scipy.optimize import brentq

    tr = release_time(A)

    def gap(tau):
        return (A * math.sin(OMEGA * tr) + A * OMEGA * math.cos(OMEGA * tr) * tau - G * tau**2 / 2
                - A * math.sin(OMEGA * (tr + tau)))

    taus = np.linspace(1e-3, 1.05, 2101)
    values = [gap(t) for t in taus]
    k = next(i for i in range(len(taus) - 1) if values[i] > 0 >= values[i + 1])
    return tr + brentq(gap, taus[k], taus[k + 1], xtol=1e-15)


# ------------------------------------------------------------------------------ e = 0.5: the flights in closed form
def _table_rest(t0: float, tau: float, amplitude: float) -> float:
    """``s(t0 + tau) - s(t0) - s'(t0) tau`` without cancellation."""
    a, b = OMEGA * t0, OMEGA * tau
    sin_b_minus_b = math.sin(b) - b if b > 1e-3 else -(b**3) / 6 * (1 - b * b / 20 * (1 - b * b / 42))
    return amplitude * (-2 * math.sin(a) * math.sin(b / 2) ** 2 + math.cos(a) * sin_b_minus_b)


def _height_over_tau(t0: float, w0: float, tau: float, amplitude: float) -> float:
    """The height over the table after ``tau`` of free flight from the table at ``t0`` with relative velocity
    ``w0``, divided by ``tau``."""
    return w0 - G * tau / 2 - _table_rest(t0, tau, amplitude) / tau


def _heights_over_tau(t0: float, w0: float, taus, amplitude: float):
    """:func:`_height_over_tau` on an array of ``tau`` (the scan for a landing)."""
    import numpy as np

    a, b = OMEGA * t0, OMEGA * taus
    series = -(b**3) / 6 * (1 - b * b / 20 * (1 - b * b / 42))
    sin_b_minus_b = np.where(b > 1e-3, np.sin(b) - b, series)
    return w0 - G * taus / 2 - amplitude * (-2 * math.sin(a) * np.sin(b / 2) ** 2 + math.cos(a) * sin_b_minus_b) / taus


def _relative_velocity(t0: float, w0: float, tau: float, amplitude: float) -> float:
    """The velocity relative to the table after ``tau`` of that flight."""
    return w0 - G * tau + 2 * amplitude * OMEGA * math.sin(OMEGA * t0 + OMEGA * tau / 2) * math.sin(OMEGA * tau / 2)


def _flight(t0: float, w0: float, amplitude: float) -> float:
    """The duration of the flight from the table at ``t0`` with relative velocity ``w0 >= 0``: ``brentq`` in a
    bracket from a scan (long flights) or around ``2 w0 / a`` (short ones, ``a`` the relative deceleration).
    Raises ValueError where the flight does not come back."""
    import numpy as np
    from scipy.optimize import brentq

    def height(tau: float) -> float:
        return _height_over_tau(t0, w0, tau, amplitude)

    decel = G - amplitude * OMEGA**2 * math.sin(OMEGA * t0)
    guess = 2 * w0 / decel if w0 > 0 else 0.0
    if guess > 1e-3 or w0 == 0:
        taus = np.linspace(1e-4, 1.0, 10001)
        values = _heights_over_tau(t0, w0, taus, amplitude)
        down = np.flatnonzero((values[:-1] > 0) & (values[1:] <= 0))
        if not len(down):
            raise ValueError("the flight does not come back to the table")
        k = int(down[0])
        lo, hi = taus[max(k - 1, 0)], taus[min(k + 2, len(taus) - 1)]  # the scan's bracket, widened by a step
        lo, hi = (taus[k], taus[k + 1]) if not height(lo) > 0 >= height(hi) else (lo, hi)
    else:
        lo, hi = 0.5 * guess, 1.5 * guess
    return brentq(height, lo, hi, xtol=1e-300, rtol=8.9e-16, maxiter=500)


def chatter_reference(amplitude: float, w_stop: float = 1e-13) -> tuple[list[float], float | None]:
    """From rest on the table at the release ``t_r``, the impact times flight by flight (``w+ = -e w-``) until the
    relative velocity is below ``w_stop``, and the accumulation point (that impact plus the geometric tail
    ``2 w / ((1 - e) a)``); None for it where the impacts escape (the table's deceleration reaches ``g``
    first, or the next release comes first): no orbit that sticks."""
    t_r = release_time(amplitude)
    t, w, times = t_r, 0.0, []
    while True:
        try:
            tau = _flight(t, w, amplitude)
        except ValueError:
            return times, None
        w = -E_CHATTER * _relative_velocity(t, w, tau, amplitude)
        t += tau
        times.append(t)
        decel = G - amplitude * OMEGA**2 * math.sin(OMEGA * t)
        if not decel > 0 or t > t_r + 1:
            return times, None
        if w < w_stop:
            t_inf = t + 2 * w / ((1 - E_CHATTER) * decel)
            return times, (t_inf if t_inf < t_r + 1 else None)


def stick_length(amplitude: float) -> float | None:
    """The stuck phase per period of the orbit that sticks, from the flights in closed form: from the
    accumulation point to the next release ``t_r + 1``; None where there is no such orbit."""
    _, t_inf = chatter_reference(amplitude)
    return None if t_inf is None else release_time(amplitude) + 1 - t_inf


def sticking_ends() -> float:
    """Where the stuck phase vanishes (the accumulation point reaches the release), by bisection on the
    existence of the orbit that sticks, to ``1e-13``."""
    lo, hi = 0.3965, 0.3975
    if stick_length(lo) is None or stick_length(hi) is not None:
        raise RuntimeError("the end of the sticking orbits (e = 0.5) is not in [0.3965, 0.3975]")
    while hi - lo > 1e-13:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stick_length(mid) is not None else (lo, mid)
    return 0.5 * (lo + hi)


def _stuck_share(flow, problem_parameters, point) -> float:
    """The share of the period the orbit of a branch point spends on the table, from its events."""
    import itertools

    traj = flow.run(point.state, point.t0, point.t0 + point.period, problem_parameters, mode0=point.mode0)
    stuck = flow.system.mode_index("flight@table")
    times = [point.t0] + [e.t for e in traj.events] + [point.t0 + point.period]
    modes = [flow.system.mode_index(point.mode0)] + [flow.system.mode_index(e.mode_to) for e in traj.events]
    return sum(b - a for (a, b), m in zip(itertools.pairwise(times), modes, strict=True) if m == stuck) / point.period


def _plastic_panels(ax1, ax_gap, ax2) -> list[dict]:
    """e = 0: the sticking orbit at A = 0.26 over two periods; the branch in A through A* with its closed forms."""
    import numpy as np

    from saltation import ContinuationSettings, Flow, continue_orbit, find_periodic_orbit
    from saltation.models import bouncing_ball
    from saltation.special_points.follow import distinct_special_points

    flow = Flow(bouncing_ball(e=0.0, A=A_ORBIT))
    orbit = find_periodic_orbit(flow, [0.0, 0.0])
    period = orbit.period

    # left: two periods of the orbit, the table, the phases on the table
    traj = flow.run(orbit.state0, 0.0, 2 * period, flow.parameters({}), mode0=orbit.mode0, dense=True)
    t, x = traj.sample(16)
    ax1.plot(t, A_ORBIT * np.sin(OMEGA * t), color="0.6", linewidth=3, label="table $A \\sin \\omega t$")
    ax1.plot(t, x[:, 0], "k-", linewidth=1.2, label="ball $y(t)$")
    ax_gap.plot(t, x[:, 0] - A_ORBIT * np.sin(OMEGA * t), "k-", linewidth=1.2)
    tr, tl = release_time(A_ORBIT), landing_time(A_ORBIT) % period
    for k in range(3):  # on the table from each landing to the next release (clipped to the two periods)
        lo, hi = max(tl + (k - 1) * period, 0.0), min(tr + k * period, 2 * period)
        for ax in (ax1, ax_gap):
            ax.axvspan(lo, hi, color="C1", alpha=0.2, linewidth=0,
                       label="on the table (closed form: landing to $t_r$)" if k == 0 and ax is ax1 else None)
    for e in traj.events:
        marker = "v" if e.mode_to == "flight@table" else "^"
        ax1.plot([e.t], [e.x_minus[0]], marker, color="C3" if marker == "v" else "C0", markersize=7)
        ax_gap.plot([e.t], [0.0], marker, color="C3" if marker == "v" else "C0", markersize=6)
    ax1.plot([], [], "v", color="C3", label="landing (event `table`)")
    ax1.plot([], [], "^", color="C0", label="release (event `table@release`)")
    ax_gap.set_xlabel("time t (periods of the table)")
    ax_gap.set_ylabel("$y - A \\sin \\omega t$")
    ax_gap.set_xlim(0.0, 2 * period)
    ax1.set_ylabel("height")
    ax1.tick_params(labelbottom=False)
    ax1.set_title(f"e = 0, A = {A_ORBIT:g}: the ball sticks, then flies")
    ax1.legend(fontsize="x-small", loc="upper left")
    ax1.set_xlim(0.0, 2 * period)
    ax1.set_ylim(-0.32, 0.62)

    # right: the branch in A, through A*, to the period doubling of the bouncing orbit
    branch = continue_orbit(orbit, "A", bounds=A_RANGE, directions=(1,),
                            settings=ContinuationSettings(ds=0.01, ds_max=0.02))
    shares, mus = [], []
    for point in branch.points:
        p = flow.parameters({"A": point.parameter})
        shares.append(_stuck_share(flow, p, point))
        mus.append(point.multipliers[np.argmax(np.abs(point.multipliers))].real)
    a_star = G / OMEGA**2 * math.sqrt(1 + math.pi**2)
    a_pd = G / OMEGA**2 * math.sqrt(math.pi**2 + 4)
    a = np.linspace(A_RANGE[0], a_star, 300)
    ref_share = [1.0 - (landing_time(v) - release_time(v)) / period for v in a]
    ax2.plot(a, ref_share, color="C1", linewidth=5, alpha=0.4, label="share on the table, closed form")
    ax2.plot(branch.parameter, shares, "k.", markersize=4, label="share on the table, from the events")
    a = np.linspace(a_star, A_RANGE[1], 200)
    gamma = a * OMEGA**2 / G
    ax2.plot(a, 1 - np.sqrt(gamma**2 - math.pi**2), color="C0", linewidth=5, alpha=0.4,
             label="multiplier $1 - \\sqrt{\\Gamma^2 - \\pi^2}$, closed form")
    ax2.plot([A_RANGE[0], a_star], [0.0, 0.0], color="C0", linewidth=5, alpha=0.4)
    ax2.plot(branch.parameter, mus, "x", color="C0", markersize=4, label="multiplier of the orbit")
    for value, name, y in ((a_star, "$A^*$", 0.9), (a_pd, "period\ndoubling", 0.8)):
        ax2.axvline(value, color="0.5", linestyle=":", linewidth=1)
        ax2.annotate(name, (value, y), xytext=(-4, 0), textcoords="offset points", ha="right", va="top",
                     fontsize="small")
    for sp in distinct_special_points([branch]):
        ax2.plot([sp.parameter], [0.0 if sp.kind.value != "period_doubling" else -1.0], "o", markersize=8,
                 markerfacecolor="white", markeredgecolor="k", zorder=5)
    ax2.axhline(-1.0, color="0.7", linewidth=0.8)
    ax2.set_xlabel("table amplitude A")
    ax2.set_ylabel("share of the period / multiplier")
    ax2.set_title("sticking orbits over A, then the bouncing orbit")
    ax2.legend(fontsize="x-small", loc="lower left")
    ax2.set_ylim(-1.15, 1.0)
    return [{"kind": sp.kind.value, "parameter": "A", "value": float(sp.parameter), "accuracy": float(sp.accuracy)}
            for sp in distinct_special_points([branch])]


def _chatter_panels(ax1, ax_gap, ax2, ax_log) -> list[dict]:
    """e = 0.5: the chattering orbit at A = 0.36 over two periods; the branch in A to just beyond the end of
    the sticking orbits, against the flights in closed form."""
    import numpy as np

    from saltation import ContinuationSettings, continue_orbit, find_periodic_orbit
    from saltation.models import bouncing_ball

    def orbit_after_release(amplitude: float):
        """The period-1 orbit from the flight after the release (``tau = 0.3`` after it, from rest on the table):
        a section that the accumulation point never crosses along the branch."""
        t_r, tau = release_time(amplitude), 0.3
        s, ds = amplitude * math.sin(OMEGA * t_r), amplitude * OMEGA * math.cos(OMEGA * t_r)
        return find_periodic_orbit(bouncing_ball(e=E_CHATTER, A=amplitude),
                                   [s + ds * tau - G * tau**2 / 2, ds - G * tau], t0=t_r + tau)

    # left: two periods of the orbit at A = 0.36, from t = 0 (on the table: the state there is the table's)
    orbit = orbit_after_release(A_CHATTER)
    flow, period = orbit.problem.flow, orbit.period
    p = flow.parameters({"A": A_CHATTER})
    to_one = flow.run(orbit.state0, orbit.t0, 1.0, p, mode0=orbit.mode0)
    if to_one.mode1 != "flight@table":
        raise RuntimeError(f"the orbit at A = {A_CHATTER} is not on the table at t = 0 (mode {to_one.mode1})")
    traj = flow.run(to_one.x1, 0.0, 2 * period, p, mode0=to_one.mode1, dense=True)
    t, x = traj.sample(16)
    table = A_CHATTER * np.sin(OMEGA * t)
    ref_impacts, ref_t_inf = chatter_reference(A_CHATTER)
    tr = release_time(A_CHATTER)
    impacts = [e for e in traj.events if e.surface == "table" and e.mode_to == "flight"]
    releases = [e for e in traj.events if e.surface == "table@release"]
    zoom = ax_gap.inset_axes([0.37, 0.36, 0.2, 0.6])  # the last impacts before the first accumulation point
    for ax in (ax_gap, zoom):
        ax.plot(t, x[:, 0] - table, "k-", linewidth=1.0)
        for k in range(3):  # stuck from each accumulation point to the next release (clipped to the two periods)
            lo, hi = max(ref_t_inf + (k - 1) * period, 0.0), min(tr + k * period, 2 * period)
            ax.axvspan(lo, hi, color="C1", alpha=0.2, linewidth=0)
        ax.plot([e.t for e in impacts], [0.0] * len(impacts), "v", color="C3", markersize=4)
        ref_times = [u + k * period for k in range(2) for u in ref_impacts]
        ax.plot(ref_times, [0.0] * len(ref_times), "|", color="0.3", markersize=12 if ax is zoom else 8)
        ax.plot([a.t for a in traj.accumulations], [0.0] * len(traj.accumulations), "*", color="C2",
                markersize=10, markeredgecolor="k", markeredgewidth=0.5)
        ax.plot([e.t for e in releases], [0.0] * len(releases), "^", color="C0", markersize=6)
    first = min(traj.accumulations, key=lambda a: a.t)
    zoom.set_xlim(first.t - 0.07, first.t + 0.008)
    zoom.set_ylim(-0.0006, 0.0035)
    zoom.set_xticks([round(first.t - 0.05, 2), round(first.t, 2)])
    zoom.set_yticks([0.0, 0.003])
    zoom.tick_params(labelsize="xx-small")
    ax_gap.indicate_inset_zoom(zoom, edgecolor="0.4")
    ax1.plot(t, table, color="0.6", linewidth=3, label="table")
    ax1.plot(t, x[:, 0], "k-", linewidth=1.2, label="ball $y(t)$")
    for k in range(3):
        lo, hi = max(ref_t_inf + (k - 1) * period, 0.0), min(tr + k * period, 2 * period)
        ax1.axvspan(lo, hi, color="C1", alpha=0.2, linewidth=0,
                    label="stuck (closed form)" if k == 0 else None)
    ax1.plot([e.t for e in impacts], [e.x_minus[0] for e in impacts], "v", color="C3", markersize=4,
             label="impacts")
    ax1.plot([a.t for a in traj.accumulations], [a.x[0] for a in traj.accumulations], "*", color="C2",
             markersize=11, markeredgecolor="k", markeredgewidth=0.5,
             label="accumulation point")
    ax1.plot([e.t for e in releases], [e.x_minus[0] for e in releases], "^", color="C0", markersize=7,
             label="release")
    ax1.plot([], [], "|", color="0.3", markersize=8, label="impacts (closed form)")
    ax_gap.set_xlabel("time t (periods of the table)")
    ax_gap.set_ylabel("$y - A \\sin \\omega t$")
    ax_gap.set_xlim(0.0, 2 * period)
    ax1.set_ylabel("height")
    ax1.tick_params(labelbottom=False)
    ax1.set_title(f"e = {E_CHATTER:g}, A = {A_CHATTER:g}: the ball chatters, sticks, then flies")
    ax1.legend(fontsize="x-small", loc="upper left", ncols=2)
    ax1.set_xlim(0.0, 2 * period)
    ax1.set_ylim(-0.42, 0.85)

    # right: the branch in A, coarse steps to A_FINE, then small ones through the end of the sticking orbits
    a_star = sticking_ends()
    coarse = continue_orbit(orbit, "A", bounds=(A_CHATTER, A_FINE), directions=(1,),
                            settings=ContinuationSettings(ds=0.002, ds_max=0.002))
    fine = continue_orbit(orbit_after_release(A_FINE), "A", bounds=(A_FINE, a_star + BEYOND), directions=(1,),
                          settings=ContinuationSettings(ds=0.0002, ds_max=0.0002))
    if coarse.special_points:
        raise RuntimeError(f"special points on the sticking branch before A = {A_FINE}: {coarse.special_points}")
    end = fine.special_points[0]
    if not (end.kind.value == "nonsmooth_no_crossing" and abs(end.parameter - a_star) <= end.accuracy + 1e-12):
        raise RuntimeError(f"the sticking branch (e = {E_CHATTER}) ends at {end.kind.value} A = {end.parameter!r} "
                           f"(accuracy {end.accuracy:.1e}), not at the flights' A* = {a_star!r}")
    params, stuck, errors = [], [], []
    for point in [*coarse.points, *fine.points]:
        share = _stuck_share(flow, flow.parameters({"A": point.parameter}), point) * point.period
        ref = stick_length(point.parameter)
        if point.parameter < end.bracket[0]:
            if ref is None or not share > 0:
                raise RuntimeError(f"the orbit at A = {point.parameter!r}, before the end, does not stick "
                                   f"(stuck phase {share!r} from its events, {ref!r} from the flights)")
            errors.append(abs(share - ref))
        elif point.parameter > end.bracket[1] and (ref is not None or share != 0.0):
            raise RuntimeError(f"the orbit at A = {point.parameter!r}, beyond the end, sticks")
        params.append(point.parameter)
        stuck.append(share)
    if max(errors) > 1e-9:  # the test's tolerance (tests/engine/test_complete_chatter.py)
        raise RuntimeError(f"the stuck phase differs from the flights in closed form by {max(errors):.1e}")
    params, stuck = np.array(params), np.array(stuck)
    a = np.r_[np.linspace(A_CHATTER, a_star - 1e-4, 120), a_star - np.geomspace(1e-4, 1e-10, 40)]
    ref_stuck = np.array([stick_length(v) for v in a])
    ax2.plot(np.r_[a, a_star, a_star + BEYOND], np.r_[ref_stuck, 0.0, 0.0], color="C1", linewidth=5, alpha=0.4,
             label="flights in closed form")
    ax2.plot(params, stuck, "k.", markersize=4, label="from the events of each orbit")
    ax2.axvline(a_star, color="0.5", linestyle=":", linewidth=1)
    ax2.annotate("$A^*$", (a_star, 0.24), xytext=(-4, 0), textcoords="offset points", ha="right", va="top",
                 fontsize="small")
    ax2.plot([end.parameter], [0.0], "o", markersize=8, markerfacecolor="white", markeredgecolor="k", zorder=5,
             label=f"located end, A = {end.parameter:.9f}")
    ax2.set_ylabel("stuck phase per period")
    ax2.set_title(f"e = {E_CHATTER:g}: the stuck phase over A")
    ax2.set_xlabel("table amplitude A")
    ax2.legend(fontsize="x-small", loc="lower left")
    ax2.set_xlim(A_CHATTER - 0.001, a_star + BEYOND + 0.001)

    sticks = (params < end.bracket[0]) & (a_star - params > 0)
    ax_log.loglog(a_star - a, ref_stuck, color="C1", linewidth=5, alpha=0.4)
    ax_log.loglog(a_star - params[sticks], stuck[sticks], "k.", markersize=4)
    ax_log.set_xlabel("$A^* - A$")
    ax_log.set_ylabel("stuck phase")
    ax_log.invert_xaxis()
    ax_log.grid(True, which="major", color="0.9", linewidth=0.6)
    MEASURED.update(orbits=len(params), sticking=len(errors), stuck_phase_error=max(errors), a_star=a_star,
                    end=end.parameter, end_minus_a_star=end.parameter - a_star, end_accuracy=end.accuracy,
                    bracket_minus_a_star=[b - a_star for b in end.bracket],
                    specials_beyond=len(fine.special_points) - 1,
                    impacts_kept=[sum(k <= e.t < k + 1 for e in impacts) for k in range(2)],
                    impacts_error=max(abs(e.t - math.floor(e.t) - r) for k in range(2) for e, r in zip(
                        [e for e in impacts if k <= e.t < k + 1], ref_impacts, strict=False)),
                    accumulation_error=[acc.t % period - ref_t_inf for acc in traj.accumulations],
                    accumulation_accuracy=[acc.accuracy for acc in traj.accumulations])
    return [{"kind": end.kind.value, "parameter": f"A (e = {E_CHATTER:g})", "value": float(end.parameter),
             "accuracy": float(end.accuracy)}]


def figure_ball_on_table():
    """Top, e = 0: the sticking orbit and its branch in A; bottom, e = 0.5: the chattering orbit and the branch
    to the end of the sticking orbits."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10.0, 9.4), layout="constrained")
    axes = fig.subplot_mosaic([["y", "branch"], ["gap", "branch"], ["y5", "stuck5"], ["gap5", "stuck5"],
                               ["gap5", "log5"]], height_ratios=[2.2, 1, 2.2, 0.5, 1.2])
    records = _plastic_panels(axes["y"], axes["gap"], axes["branch"])
    records += _chatter_panels(axes["y5"], axes["gap5"], axes["stuck5"], axes["log5"])
    return fig, records


if __name__ == "__main__":
    import json
    import sys
    import time
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))
    start = time.perf_counter()
    figure, found = figure_ball_on_table()
    figure.savefig(sys.argv[1] if len(sys.argv) > 1 else "ball_on_table.png", dpi=110)
    print(json.dumps({"points": found, "seconds": time.perf_counter() - start, "e = 0.5": MEASURED}, indent=1))
