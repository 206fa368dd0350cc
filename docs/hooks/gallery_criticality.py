"""Gallery figure: super- and subcritical period doublings, and a generalised period doubling.

Not a hook of its own: ``docs/hooks/gallery.py`` imports :func:`figure_criticality` and computes it like its other
figures (in a child process, at every build; nothing is checked in).  From scratch, with the shipped models and
the settings of ``tests/special_points/test_criticality_on_points.py`` and ``tests/orbits/test_second_order.py``:

* the bouncing ball (``e = 0.5``) over ``A`` through its period doubling, supercritical: the period-2 branch
  (``follow_period_doubled_branch``) born beyond it and stable;
* two masses between stops over ``omega`` through their period doubling near 0.4516, subcritical: the period-2
  branch born before it and unstable;
* the two masses' period-doubling curve in ``(omega, F)`` with ``normal_forms=True``: the generalised period
  doubling where the flip coefficient ``b`` changes sign, and the 1:2 resonance where a second multiplier passes
  -1; and ``b`` along the curve, each value from ``criticality`` at an orbit of the curve.

Each period-2 orbit is drawn by its state at ``t = 0`` and at ``t = T`` (the two points of the period-2 cycle of
the stroboscopic map), each period-1 orbit by its state at ``t = 0``.

Run ``python docs/hooks/gallery_criticality.py OUT.png`` to compute the figure by hand.
"""

from __future__ import annotations

#: The ball's period-1 orbit at A = 0.37 (a start guess) and the range of A drawn.
BALL_STATE = (0.8027, -3.6704)
BALL_RANGE = (0.37, 0.39)
#: The two masses' orbit near their period doubling at omega = 0.452, F = 1 (a start guess; the tests' state).
TWO_MASS_STATE = (0.8869838955762865, 0.02956094651817481, 1.3985524338147999, -0.19102019176461646)
OMEGA_RANGE = (0.4505, 0.4525)
#: The range of F of the period-doubling curve (it starts at F = 1).
F_RANGE = (0.87, 1.0)
#: ``b`` is computed at every other point of the curve below this F (where it changes fast), every sixth above.
F_DENSE = 0.91
GPD = "generalized_period_doubling"


def _after(flow, branch, k: int, fraction: float):
    """State ``k`` of each point of a branch a ``fraction`` of its period after its section time."""
    import numpy as np

    out = []
    for pt in branch.points:
        p = flow.parameters(dict(branch.fixed_parameters, **{branch.parameter_name: pt.parameter}))
        out.append(flow.run(pt.state, pt.t0, pt.t0 + fraction * pt.period, p, mode0=pt.mode0).x1[k])
    return np.array(out)


def _doubling(ax, flow, single, doubled, k: int, ylabel: str, title: str, loc: str):
    """A period-1 branch (state k at t = 0) and the period-2 branch born at its doubling (at t = 0 and t = T)."""
    from matplotlib.lines import Line2D

    from saltation.output.plotting import SPECIAL_POINT_MARKERS, plot_response

    plot_response(single, ax, measure=lambda b: b.states[:, k], legend=False)
    plot_response(doubled, ax, measure=lambda b: b.states[:, k], colors=["C0"], legend=False)
    plot_response(doubled, ax, measure=lambda b: _after(flow, b, k, 0.5), colors=["C0"], legend=False)
    handles = [Line2D([], [], color="k", label="period 1, stable"),
               Line2D([], [], color="k", linestyle="-.", label="period 1, unstable"),
               Line2D([], [], color="C0", label="period 2, stable (at t = 0 and T)"),
               Line2D([], [], color="C0", linestyle="-.", label="period 2, unstable")]
    kinds = {sp.kind for b in (single, doubled) for sp in b.special_points}
    handles += [Line2D([], [], linestyle="none", marker=SPECIAL_POINT_MARKERS[kind][0], markerfacecolor="white",
                       markeredgecolor="k", markersize=8, label=SPECIAL_POINT_MARKERS[kind][1])
                for kind in SPECIAL_POINT_MARKERS if kind in kinds]
    ax.legend(handles=handles, fontsize="x-small", loc=loc)
    ax.set_ylabel(ylabel)
    ax.set_title(title)


def _records(single, doubled):
    """The special points of a period-1 branch and of the period-2 branch born on it (its first point, the
    doubling, once), with their criticality."""
    from saltation.special_points.follow import distinct_special_points

    first = {(sp.kind.value, float(sp.parameter)) for sp in single.special_points}
    return [{"kind": (sp.kind.value + (f" ({sp.criticality.value})" if sp.criticality else "")
                      + ("" if (sp.kind.value, float(sp.parameter)) in first else ", of the period-2 branch")),
             "parameter": single.parameter_name, "value": float(sp.parameter), "accuracy": float(sp.accuracy)}
            for sp in distinct_special_points([single, doubled])]


def _coefficients(flow, curve, points):
    """``b`` at each point of a period-doubling curve (nan where it cannot be computed), and the multiplier of
    largest modulus other than the one at -1 (nan if complex)."""
    import numpy as np

    from saltation import find_periodic_orbit
    from saltation.errors import SaltationError
    from saltation.kinds import SpecialPointKind
    from saltation.orbits.criticality import criticality

    b, other = [], []
    for pt in points:
        orbit = find_periodic_orbit(flow, pt.state, parameters={curve.parameter_name: pt.parameter,
                                                                curve.second_parameter_name: pt.second_parameter})
        try:
            b.append(criticality(orbit, SpecialPointKind.PERIOD_DOUBLING).coefficient)
        except SaltationError:
            b.append(np.nan)
        rest = np.delete(pt.multipliers, np.argmin(np.abs(pt.multipliers + 1)))
        other.append(float(rest[np.argmax(np.abs(rest))].real) if np.all(np.abs(rest.imag) < 1e-9) else np.nan)
    return np.array(b), np.array(other)


def figure_criticality():
    """Supercritical (ball) and subcritical (two masses) period doublings; the flip coefficient along a curve."""
    import itertools

    import numpy as np
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from saltation import ContinuationSettings, Flow, continue_orbit, find_periodic_orbit
    from saltation.models import bouncing_ball, two_mass_stops
    from saltation.special_points.branch_switching import follow_period_doubled_branch
    from saltation.special_points.loci import follow_locus

    fig = Figure(figsize=(10.0, 7.6), layout="constrained")
    axes = fig.subplots(2, 2)
    records = []

    # the bouncing ball: supercritical
    ball = Flow(bouncing_ball())
    orbit = find_periodic_orbit(ball, list(BALL_STATE), parameters={"A": BALL_RANGE[0]})
    single = continue_orbit(orbit, "A", bounds=BALL_RANGE, directions=(1,),
                            settings=ContinuationSettings(ds=0.002, ds_max=0.002))
    (pd,) = [sp for sp in single.special_points if sp.kind.value == "period_doubling"]
    doubled = follow_period_doubled_branch(single, pd, settings=ContinuationSettings(ds=0.001, ds_max=0.002,
                                                                                     bounds=BALL_RANGE))
    _doubling(axes[0, 0], ball, single, doubled, 1, "velocity v at t = 0 (and t = T)",
              f"bouncing ball: supercritical, b = {pd.normal_form[0]:.2f}", "upper left")
    axes[0, 0].set_xlabel("table amplitude A")
    records += _records(single, doubled)

    # two masses between stops: subcritical
    masses = Flow(two_mass_stops())
    orbit = find_periodic_orbit(masses, list(TWO_MASS_STATE), parameters={"omega": 0.452})
    single = continue_orbit(orbit, "omega", bounds=OMEGA_RANGE, directions=(-1, 1),
                            settings=ContinuationSettings(ds=2e-4, ds_max=2e-4))
    (pd,) = [sp for sp in single.special_points if sp.kind.value == "period_doubling"]
    doubled = follow_period_doubled_branch(single, pd, settings=ContinuationSettings(ds=2e-4, ds_max=1e-3,
                                                                                     bounds=OMEGA_RANGE))
    _doubling(axes[0, 1], masses, single, doubled, 0, "x1 at t = 0 (and t = T)",
              f"two masses between stops: subcritical, b = {pd.normal_form[0]:.2f}", "lower left")
    lo, hi = axes[0, 1].get_ylim()
    axes[0, 1].set_ylim(lo - 0.6 * (hi - lo), hi)  # room for the legend below the branches
    axes[0, 1].set_xlabel("forcing frequency omega")
    axes[0, 1].xaxis.set_major_locator(MaxNLocator(5))
    records += _records(single, doubled)

    # the period-doubling curve in (omega, F): where b changes sign
    index = single.special_points.index(pd)
    located = follow_locus(single, index, "F", F_RANGE, settings=ContinuationSettings(ds=0.01, ds_max=0.03),
                           normal_forms=True)
    curve = follow_locus(single, index, "F", F_RANGE, settings=ContinuationSettings(ds=0.005, ds_max=0.005))
    last = len(curve.points) - 1  # every other point up to F_DENSE, every sixth beyond (half a second each)
    points = [pt for i, pt in enumerate(curve.points)
              if i % (2 if pt.second_parameter < F_DENSE else 6) == 0 or i == last]
    b, other = _coefficients(masses, curve, points)
    ax, axb = axes[1, 0], axes[1, 1]
    omega = np.array([pt.parameter for pt in points])
    force = np.array([pt.second_parameter for pt in points])
    beyond = other < -1  # a second multiplier beyond -1: the period-1 orbit unstable on both sides of the curve
    ax.plot(omega, force, "k-", linewidth=1, zorder=1)
    ax.plot(omega[~beyond], force[~beyond], "k.", markersize=5, label="no other multiplier below -1")
    ax.plot(omega[beyond], force[beyond], ".", color="C3", markersize=5, label="a second multiplier below -1")
    poles = [sp.second_parameter for sp in located.special_points if sp.codimension_two.value != GPD]
    across = [any(min(lo, hi) < f < max(lo, hi) for f in poles) for lo, hi in itertools.pairwise(force)]
    cut = np.concatenate([[0], 1 + np.flatnonzero(across), [len(force)]])
    for i, j in itertools.pairwise(cut):  # the line is not drawn across a pole of b
        axb.plot(force[i:j], b[i:j], "k-", linewidth=1, zorder=1)
    axb.plot(force[~beyond], b[~beyond], "k.", markersize=5)
    axb.plot(force[beyond], b[beyond], ".", color="C3", markersize=5)
    markers = {GPD: ("D", "C2"), "strong_resonance_1_2": ("o", "C3")}
    for sp in located.special_points:
        name = sp.codimension_two.value
        marker, color = markers.get(name, ("^", "0.5"))
        ax.plot([sp.parameter], [sp.second_parameter], marker, markerfacecolor="white", markeredgecolor=color,
                markeredgewidth=2, markersize=9, zorder=5, label=name.replace("_", " "))
        if name == GPD:
            axb.plot([sp.second_parameter], [0.0], marker, markerfacecolor="white", markeredgecolor=color,
                     markeredgewidth=2, markersize=9, zorder=5, label=name.replace("_", " "))
        else:
            axb.axvline(sp.second_parameter, color=color, linestyle=":", linewidth=1.2,
                        label=f"{name.replace('_', ' ')} (b has a pole)")
        records.append({"kind": f"{name} ({' -> '.join(sp.sides)})",
                        "parameter": f"omega (at F = {sp.second_parameter:.8f})", "value": float(sp.parameter),
                        "accuracy": float(sp.accuracy)})
    ax.plot([pd.parameter], [1.0], "s", markerfacecolor="white", markeredgecolor="k", markersize=8, zorder=5,
            label="the subcritical doubling above (F = 1)")
    ax.set_xlabel("forcing frequency omega")
    ax.set_ylabel("forcing amplitude F")
    ax.set_title("two masses: period-doubling curve in (omega, F)")
    ax.legend(fontsize="x-small", loc="upper left")
    axb.axhline(0.0, color="0.6", linewidth=0.8)
    axb.set_yscale("symlog", linthresh=10.0)
    axb.set_xlabel("forcing amplitude F along the curve")
    axb.set_ylabel("flip coefficient b (symmetric log scale)")
    axb.set_title("b > 0 supercritical, b < 0 subcritical")
    axb.legend(fontsize="x-small", loc="lower right")
    return fig, records


if __name__ == "__main__":
    import json
    import sys
    import time
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))
    start = time.perf_counter()
    figure, found = figure_criticality()
    figure.savefig(sys.argv[1] if len(sys.argv) > 1 else "criticality.png", dpi=110)
    print(json.dumps({"points": found, "seconds": time.perf_counter() - start}, indent=1))
