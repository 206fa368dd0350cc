"""Gallery figure: the impact oscillator's route to chaos, coloured by the largest Lyapunov exponent.

Not a hook of its own: ``docs/hooks/gallery.py`` imports :func:`figure_impact_chaos` and computes it
like its other figures (in a child process, at every build; nothing is checked in).  The figure is
computed from scratch with the library:

* a period map of ``saltation.models.impact_oscillator`` at ``s = 1.3`` over the forcing frequency
  ``omega`` and the restitution ``r`` (:func:`saltation.period_map` with ``lyapunov=True``), drawn
  twice: the attractor's period (``PeriodMap.plot``) and each cell's largest Lyapunov exponent (the
  colour map of ``saltation sweep --lyapunov``, :meth:`PeriodMap.plot`'s second panel);
* a brute-force diagram along the row ``r = 0.8`` of the map, ``omega`` decreasing
  (:func:`saltation.sweep` with ``lyapunov=True``), over its largest exponent;
* the period-1 orbit continued along that row from ``omega = 0.66`` to 0.60, the period-2 branch born at
  its period doubling, and the period-2 orbit the diagram settles on below them: their period doublings are
  the special points of the page.

The settings are module constants, shared with ``tests/gallery/test_gallery_impact_chaos.py``, which recomputes
single cells of the same map.  Run ``python docs/hooks/gallery_chaos.py OUT.png`` to compute the figure
by hand.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

#: The stop (fixed): far enough from the free response that the force at the stop, cos(omega t) - s,
#: always pulls away from it (no sticking, no chattering).
S = 1.3
#: Columns and rows of the map: (first, last, number) of omega and of r.
OMEGA = (0.54, 0.66, 41)
R = (0.5, 0.9, 33)
#: The map's settings: each cell from rest at t = 0 (independent cells), 200 forcing periods of transient,
#: 64 sampled (the periods looked for up to 8, the exponent over the 64).
MAP_SETTINGS = {"max_period": 8, "periods": 64, "transient": 200, "x0": (0.0, 0.0), "start": "own"}
#: The line of the map swept: r, and omega from high to low (each value from the previous one's end).
SWEEP_R = 0.8
SWEEP_OMEGA = (0.66, 0.54, 161)
#: Two chunks (workers), whatever the machine: each starts from rest at its first value (0.66 and 0.59925), so
#: the diagram does not depend on the number of cores.
SWEEP_SETTINGS = {"periods": 64, "transient": 200, "x0": (0.0, 0.0), "start": "previous", "workers": 2}
#: The period-1 branch: from a stable period-1 orbit at the top of the swept line, down to the end of the
#: cascade (omega, first and last).
BRANCH = (0.66, 0.60)
#: A stable period-2 orbit on the swept line below the first two doublings (three impacts per two forcing
#: periods), and the interval it is continued over.
PERIOD_2 = 0.633
PERIOD_2_BOUNDS = (0.62, 0.64)


def grid(spec: tuple[float, float, int]):
    """The values of ``(first, last, number)``, as the map and the tests use them."""
    import numpy as np

    return np.linspace(spec[0], spec[1], int(spec[2]))


def system():
    """The impact oscillator with the stop at ``S`` (the defaults otherwise: zeta = 0.05)."""
    from saltation.models import impact_oscillator

    return impact_oscillator(s=S)


def chaos_map(omega=None, r=None, *, workers: int | None = None):
    """The period map with each cell's largest Lyapunov exponent (the module's grid by default)."""
    import saltation

    omega = grid(OMEGA) if omega is None else omega
    r = grid(R) if r is None else r
    return saltation.period_map(system(), "omega", omega, "r", r, lyapunov=True, workers=workers, **MAP_SETTINGS)


def chaos_sweep(omega=None):
    """The brute-force diagram along ``r = SWEEP_R``, with the largest exponent at each value."""
    import saltation

    omega = grid(SWEEP_OMEGA) if omega is None else omega
    return saltation.sweep(system(), "omega", omega, lyapunov=True, parameters={"r": SWEEP_R}, **SWEEP_SETTINGS)


def doubling_branches():
    """The branches of the route along ``r = SWEEP_R``, each by continuation in omega:

    * the period-1 orbit over ``BRANCH`` (omega decreasing), from a stable one at its top;
    * the period-2 branch born at its period doubling (``follow_period_doubled_branch``);
    * the period-2 orbit the sweep settles on further down (three impacts per two forcing periods), from the
      end of a transient at ``PERIOD_2``, continued both ways over ``PERIOD_2_BOUNDS``.
    """
    from saltation import ContinuationSettings, Flow, ShootingProblem, continue_branch, find_periodic_orbit
    from saltation.special_points.branch_switching import follow_period_doubled_branch

    flow = Flow(system())
    start, low = BRANCH
    p = {"r": SWEEP_R, "omega": start}
    orbit = find_periodic_orbit(flow, parameters=p)  # from the end of a transient from rest
    problem = ShootingProblem(flow, p, continuation_parameter="omega")
    branches = [continue_branch(problem, orbit.state0, start, directions=(-1,), label="period 1",
                                settings=ContinuationSettings(ds=0.002, ds_max=0.005, bounds=(low, start)))]
    doublings = [sp for sp in branches[0].special_points if sp.kind.value == "period_doubling"]
    if doublings:
        branches.append(follow_period_doubled_branch(problem, doublings[0], label="period 2",
                                                     settings=ContinuationSettings(ds=0.001, ds_max=0.002,
                                                                                   bounds=(low, start))))
    p2 = {"r": SWEEP_R, "omega": PERIOD_2}
    guess = flow.run(MAP_SETTINGS["x0"], 0.0, MAP_SETTINGS["transient"] * 2 * math.pi / PERIOD_2,
                     flow.parameters(p2)).x1
    problem2 = ShootingProblem(flow, p2, continuation_parameter="omega", periods=2)
    orbit2 = problem2.solve(problem2.pack(guess))
    branches.append(continue_branch(problem2, orbit2.state0, PERIOD_2, label="period 2, three impacts",
                                    settings=ContinuationSettings(ds=0.001, ds_max=0.002, bounds=PERIOD_2_BOUNDS)))
    return branches


def _records(branches):
    """The special points of the branches, each once (a period-2 branch starts with the period doubling it
    was born at, which its parent branch holds too)."""
    from saltation.special_points.follow import distinct_special_points

    name = branches[0].parameter_name if branches else ""
    return [
        {"kind": sp.kind.value, "parameter": name, "value": float(sp.parameter), "accuracy": float(sp.accuracy)}
        for sp in distinct_special_points(branches)
    ]


def draw(pmap, sweep, branches=()):
    """The figure of a map, a sweep along one of its rows and the branches' period doublings (a matplotlib
    ``Figure``, no pyplot).

    Top: the map's periods (``PeriodMap.plot``) and its largest exponents, the colour map of
    :meth:`PeriodMap.plot` (diverging ``RdBu_r``, symmetric about 0: red is chaos), with the swept row
    dashed.  Bottom: the diagram (``SweepResult.plot``) over its largest exponent, the period doublings
    located on the branches dotted.
    """
    import numpy as np
    from matplotlib.figure import Figure

    from saltation.output.plotting import _edges

    fig = Figure(figsize=(11.0, 9.0), layout="constrained")
    top, bottom = fig.subfigures(2, 1, height_ratios=(1.0, 1.15))
    ax_period, ax_exponent = top.subplots(1, 2)
    pmap.plot(ax_period)
    ax_period.collections[0].set_gid("period_map")
    ax_period.set_title("period of the attractor (from rest)")
    # the largest exponent as `saltation sweep --param2 ... --lyapunov` draws it (PeriodMap.plot's second panel)
    finite = np.isfinite(pmap.largest_exponents)
    limit = float(np.nanmax(np.abs(pmap.largest_exponents))) if finite.any() else 1.0
    mesh = ax_exponent.pcolormesh(_edges(pmap.values), _edges(pmap.values2), pmap.largest_exponents,
                                  cmap="RdBu_r", vmin=-limit, vmax=limit)
    mesh.set_gid("exponent_map")
    top.colorbar(mesh, ax=ax_exponent).set_label(r"largest Lyapunov exponent $\lambda_1$ (red: chaos)")
    ax_exponent.set_xlabel(pmap.parameter_name)
    ax_exponent.set_ylabel(pmap.parameter2_name)
    ax_exponent.set_title("largest Lyapunov exponent")
    for ax in (ax_period, ax_exponent):
        ax.axhline(SWEEP_R, color="k", linestyle="--", linewidth=0.9)

    ax_diagram, ax_lyap = bottom.subplots(2, 1, sharex=True, height_ratios=(2.0, 1.0))
    sweep.plot(ax_diagram)
    ax_diagram.collections[0].set_gid("diagram")
    ax_diagram.set_xlabel("")
    ax_diagram.set_title(f"along r = {SWEEP_R:g} (dashed above), omega decreasing: Poincare section")
    ax_lyap.axhline(0.0, color="0.6", linewidth=0.8)
    ax_lyap.plot(sweep.values, sweep.largest_exponents, color="k", linewidth=1.0, marker=".", markersize=2.5,
                 gid="largest_exponent")
    ax_lyap.set_ylabel(r"$\lambda_1$")
    ax_lyap.set_xlabel(sweep.parameter_name)
    first = True
    for branch in branches:
        for sp in branch.special_points:
            if sp.kind.value != "period_doubling":
                continue
            for ax in (ax_diagram, ax_lyap):
                ax.axvline(sp.parameter, color="C3", linestyle=":", linewidth=1.0,
                           label="period doubling (continuation)" if first and ax is ax_diagram else None)
            first = False
    if not first:
        ax_diagram.legend(fontsize="small", loc="lower left")
    ax_diagram.set_xlim(min(sweep.values), max(sweep.values))
    return fig


def figure_impact_chaos(omega=None, r=None, sweep_omega=None):
    """The route to chaos in (omega, r): the periods, the largest Lyapunov exponents, a diagram along r = 0.8.

    The grids are the module's by default (the tests pass small ones).
    """
    pmap = chaos_map(omega, r)
    sweep = chaos_sweep(sweep_omega)
    branches = doubling_branches()
    return draw(pmap, sweep, branches), _records(branches)


if __name__ == "__main__":  # by hand: python docs/hooks/gallery_chaos.py OUT.png
    import json
    import time

    src = str(Path(__file__).resolve().parents[2] / "src")
    if src not in sys.path:
        sys.path.insert(0, src)
    start = time.perf_counter()
    fig, points = figure_impact_chaos()
    fig.savefig(sys.argv[1] if len(sys.argv) > 1 else "impact_chaos.png", dpi=110)
    print(json.dumps({"points": points, "seconds": time.perf_counter() - start}, indent=1))
