"""Gallery figure: the ball on its vibrating table with restitution e = 0, a contact that sticks.

Not a hook of its own: ``docs/hooks/gallery.py`` imports :func:`figure_ball_on_table` and computes it like
its other figures (in a child process, at every build; nothing is checked in).  From scratch, with the
shipped ``saltation.models.bouncing_ball`` at ``e = 0`` (its impact declares ``sticks=True``):

* the sticking orbit at ``A = 0.26`` over two forcing periods, the ball's height and the table's, the
  phase on the table shaded (from the landing to the release at ``t_r = asin(g / (A omega^2)) / omega``);
* the branch continued in ``A`` from there: the share of the period spent on the table, from the events
  of each orbit, against its closed form, down to zero at ``A* = (g / omega^2) sqrt(1 + pi^2)``, where the
  plastic bouncing orbit takes over; and the orbit's nonzero multiplier, 0 while it sticks and
  ``1 - sqrt(Gamma^2 - pi^2)`` beyond ``A*`` (``Gamma = A omega^2 / g``), which reaches -1 at the period
  doubling ``Gamma = sqrt(pi^2 + 4)``.

Run ``python docs/hooks/gallery_sticking.py OUT.png`` to compute the figure by hand.
"""

from __future__ import annotations

import math

#: The table's amplitude of the orbit drawn over time, and the range of the branch.
A_ORBIT = 0.26
A_RANGE = (0.26, 0.95)
G, OMEGA = 9.81, 2 * math.pi


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


def _stuck_share(flow, problem_parameters, point) -> float:
    """The share of the period the orbit of a branch point spends on the table, from its events."""
    import itertools

    traj = flow.run(point.state, point.t0, point.t0 + point.period, problem_parameters, mode0=point.mode0)
    stuck = flow.system.mode_index("flight@table")
    times = [point.t0] + [e.t for e in traj.events] + [point.t0 + point.period]
    modes = [flow.system.mode_index(point.mode0)] + [flow.system.mode_index(e.mode_to) for e in traj.events]
    return sum(b - a for (a, b), m in zip(itertools.pairwise(times), modes, strict=True) if m == stuck) / point.period


def figure_ball_on_table():
    """The sticking orbit at A = 0.26 over two periods; the branch in A through A* with its closed forms."""
    import numpy as np
    from matplotlib.figure import Figure

    from saltation import ContinuationSettings, Flow, continue_orbit, find_periodic_orbit
    from saltation.models import bouncing_ball
    from saltation.special_points.follow import distinct_special_points

    system = bouncing_ball(e=0.0, A=A_ORBIT)
    flow = Flow(system)
    orbit = find_periodic_orbit(flow, [0.0, 0.0])
    period = orbit.period
    fig = Figure(figsize=(10.0, 4.6), layout="constrained")
    axes = fig.subplot_mosaic([["y", "branch"], ["gap", "branch"]], height_ratios=[2.2, 1])
    ax1, ax_gap, ax2 = axes["y"], axes["gap"], axes["branch"]

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
    records = [{"kind": sp.kind.value, "parameter": "A", "value": float(sp.parameter), "accuracy": float(sp.accuracy)}
               for sp in distinct_special_points([branch])]
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
    print(json.dumps({"points": found, "seconds": time.perf_counter() - start}, indent=1))
