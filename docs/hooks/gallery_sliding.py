"""The gallery's figure of the sliding-mode controlled plant (``saltation.models.sliding_mode``).

:func:`figure_sliding_mode` returns ``(Figure, special points)`` like the ``figure_*`` functions of
``docs/hooks/gallery.py``: the equilibria, pseudo-equilibria and boundary equilibria over the
reference ``r`` for a stable plant (``k = 3``: persistence) and an unstable one (``k = -1.5``:
non-smooth folds), and a phase portrait of each at ``r = 0.2``.

Run ``python docs/hooks/gallery_sliding.py OUT.png`` to compute it by hand.
"""

from __future__ import annotations

#: The two plants: a stable one (``k > 0``) and an unstable one (``k < 0``).
SETTINGS = ((3.0, "stable plant, k = 3"), (-1.5, "unstable plant, k = -1.5"))
R_RANGE = (-1.0, 1.0)  # the reference's range of the diagrams
R_PHASE = 0.2  # the reference of the phase portraits
MODE_COLORS = {"u_plus": "C0", "u_minus": "C2"}
PSEUDO_COLOR = "C3"


def _records(branch, k: float):
    return [
        {"kind": sp.kind.value, "parameter": branch.parameter_name, "value": float(sp.parameter),
         "accuracy": float(sp.accuracy), "classification": sp.classification, "k": k}
        for sp in branch.special_points
    ]


def _styled_runs(ax, r, x1, admissible, stable, color, switches):
    """Draw a branch in runs: solid where admissible and stable, dashed where admissible and unstable, thin
    dotted where virtual (outside its region).  Neighbouring runs meet at a value of ``switches`` (the
    boundary equilibria) between their points, otherwise half way."""
    import numpy as np

    r, x1 = np.asarray(r, dtype=float), np.asarray(x1, dtype=float)
    key = [(bool(a), bool(s)) for a, s in zip(admissible, stable)]
    head = None
    start = 0
    for i in range(1, len(r) + 1):
        if i < len(r) and key[i] == key[start]:
            continue
        xs, ys = list(r[start:i]), list(x1[start:i])
        if head is not None:
            xs.insert(0, head[0])
            ys.insert(0, head[1])
        if i < len(r):
            inside = [s for s in switches if min(r[i - 1], r[i]) <= s <= max(r[i - 1], r[i])]
            at = inside[0] if inside else 0.5 * (r[i - 1] + r[i])
            t = (at - r[i - 1]) / (r[i] - r[i - 1])
            head = (at, (1 - t) * x1[i - 1] + t * x1[i])
            xs.append(head[0])
            ys.append(head[1])
        adm, stab = key[start]
        style = ({"linestyle": "-", "linewidth": 2.0} if adm and stab else
                 {"linestyle": "--", "linewidth": 2.0} if adm else {"linestyle": ":", "linewidth": 1.2})
        ax.plot(xs, ys, color=color, **style)
        start = i


def _legend(ax, entries, loc):
    """A legend of colours (which equilibrium) and line styles (admissible and stable, admissible and
    unstable, virtual)."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=color, linewidth=2.0, label=label) for label, color in entries]
    handles += [Line2D([], [], color="k", linestyle="-", linewidth=2.0, label="admissible, stable"),
                Line2D([], [], color="k", linestyle="--", linewidth=2.0, label="admissible, unstable"),
                Line2D([], [], color="k", linestyle=":", linewidth=1.2, label="virtual"),
                Line2D([], [], linestyle="none", marker="o", markersize=8, markerfacecolor="white",
                       markeredgecolor="k", label="boundary equilibrium")]
    ax.legend(handles=handles, fontsize="x-small", loc=loc)


def _diagram(ax, flow, k: float, title: str):
    """Pseudo-equilibria and both modes' equilibria over r at stiffness k; the boundary equilibria marked.
    Returns the branch of pseudo-equilibria with its boundary equilibria as special points."""
    import numpy as np

    from saltation import ContinuationSettings, continue_branch, find_pseudo_equilibrium
    from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem
    from saltation.orbits.shooting import EquilibriumProblem
    from saltation.special_points.boundary_equilibria import (
        boundary_equilibria,
        sliding_weight,
    )

    settings = ContinuationSettings(ds=0.05, ds_max=0.1, bounds=R_RANGE)
    first = find_pseudo_equilibrium(flow, "s", [R_PHASE, 0.0], parameters={"k": k, "r": R_PHASE})
    problem = PseudoEquilibriumProblem(flow, "s", first.modes, {"k": k, "r": R_PHASE}, continuation_parameter="r")
    branch = continue_branch(problem, PseudoEquilibriumProblem.unknowns(first), R_PHASE, settings=settings)
    branch.special_points = boundary_equilibria(problem, branch)
    weights = np.array([sliding_weight(problem, pt.state, pt.parameter) for pt in branch.points])
    switches = [sp.parameter for sp in branch.special_points]
    _styled_runs(ax, branch.parameter, branch.states[:, 0], (weights > 0) & (weights < 1), branch.stable,
                 PSEUDO_COLOR, switches)
    for mode, sign in (("u_plus", -1.0), ("u_minus", 1.0)):  # u_plus lives where s < 0, u_minus where s > 0
        eq = EquilibriumProblem(flow, mode, {"k": k, "r": R_PHASE}, continuation_parameter="r")
        x0 = eq.solve([0.0, 0.0], R_PHASE).state
        modes = continue_branch(eq, x0, R_PHASE, settings=settings)
        inside = [sign * flow.indicator("s", 0.0, pt.state, eq.parameters_at(pt.parameter)) > 0 for pt in modes.points]
        _styled_runs(ax, modes.parameter, modes.states[:, 0], inside, modes.stable, MODE_COLORS[mode], switches)
    for sp in branch.special_points:
        ax.plot([sp.parameter], [sp.state[0]], "o", markersize=8, markerfacecolor="white", markeredgecolor="k",
                zorder=5)
        ax.annotate(sp.classification.replace("_", " "), xy=(sp.parameter, sp.state[0]),
                    xytext=(-8 if sp.parameter > 0 else 8, 12 if sp.state[0] < 0 else -16), textcoords="offset points",
                    ha="right" if sp.parameter > 0 else "left", fontsize="small")
    ax.set_xlabel("reference r")
    ax.set_ylabel("x1 at the equilibrium")
    ax.set_title(title)
    _legend(ax, [("pseudo-equilibrium (r, 0)", PSEUDO_COLOR), ("equilibrium of u_plus", MODE_COLORS["u_plus"]),
                 ("equilibrium of u_minus", MODE_COLORS["u_minus"])], "upper left")
    return branch


def _phase_portrait(ax, flow, k: float, title: str):
    """Trajectories at r = R_PHASE, the switching line with its sliding segment, the equilibria."""
    import numpy as np

    from saltation import find_pseudo_equilibrium
    from saltation.orbits.pseudo_equilibria import sliding_weight
    from saltation.output.plotting import PhaseCurve, plot_phase_plane

    p = flow.parameters({"k": k, "r": R_PHASE})
    lam = float(p[flow.system.parameter_index("lam")])
    box = 1.3
    curves = []
    starts = [(1.1, a) for a in np.linspace(0.0, 2 * np.pi, 9)[:-1]]
    if k < 0:  # more starts near the pseudo-equilibrium's basin, between the saddles
        starts += [(0.5, a) for a in np.linspace(0.0, 2 * np.pi, 7)[:-1]]
    for radius, angle in starts:
        x0 = [R_PHASE + radius * np.cos(angle), radius * np.sin(angle)]
        _, x = flow.run(x0, 0.0, 8.0, p, dense=True).sample(8)
        out = np.flatnonzero(np.max(np.abs(x), axis=1) > 1.5 * box)
        curves.append(PhaseCurve(x[: out[0] + 1] if out.size else x, "", "trajectory"))
    plot_phase_plane(curves, ax, xlabel="x1", ylabel="x2", legend=False)
    x1 = np.linspace(-box, box, 801)
    line = np.column_stack([x1, -lam * (x1 - R_PHASE)])
    ax.plot(line[:, 0], line[:, 1], color="0.6", linewidth=0.8, label="switching line s = 0")
    minus, plus = flow.system.mode_index("u_plus"), flow.system.mode_index("u_minus")
    a = np.array([sliding_weight(flow, "s", minus, plus, x, p) for x in line])
    sliding = np.where((a > 0) & (a < 1), line[:, 1], np.nan)
    ax.plot(line[:, 0], sliding, color=PSEUDO_COLOR, linewidth=3.5, alpha=0.7, label="sliding segment")
    point = find_pseudo_equilibrium(flow, "s", [R_PHASE, 0.0], parameters=p)
    ax.plot(*point.state, "o", color=PSEUDO_COLOR, markersize=8, zorder=6,
            label=f"pseudo-equilibrium ({'stable' if point.stable else 'unstable'})")
    for mode, sign in (("u_plus", -1.0), ("u_minus", 1.0)):
        m = flow.system.mode_index(mode)
        x = np.linalg.solve(flow.vector_field_jacobian(m, 0.0, np.zeros(2), p), -flow.vector_field(m, 0.0, np.zeros(2), p))
        admissible = sign * flow.indicator("s", 0.0, x, p) > 0
        eig = np.linalg.eigvals(flow.vector_field_jacobian(m, 0.0, x, p))
        kind = ("saddle" if np.prod(eig.real) < 0 else "focus" if np.any(eig.imag != 0) else "node")
        ax.plot(*x, "X" if admissible else "o", color=MODE_COLORS[mode], markersize=8, zorder=6,
                markerfacecolor=MODE_COLORS[mode] if admissible else "white",
                label=f"{mode}: {kind}, {'admissible' if admissible else 'virtual'}")
    ax.set_xlim(-box, box)
    ax.set_ylim(-box, box)
    ax.set_title(title)
    ax.legend(fontsize="x-small", loc="lower left")


def figure_sliding_mode():
    """Equilibria, pseudo-equilibria and boundary equilibria over r for k = 3 and k = -1.5; phase portraits."""
    from matplotlib.figure import Figure

    from saltation import Flow
    from saltation.models.sliding_mode import sliding_mode

    flow = Flow(sliding_mode())
    fig = Figure(figsize=(10.0, 8.5), layout="constrained")
    axes = fig.subplots(2, 2)
    points = []
    for column, (k, name) in enumerate(SETTINGS):
        branch = _diagram(axes[0, column], flow, k, f"equilibria over r: {name}")
        points += _records(branch, k)
        _phase_portrait(axes[1, column], flow, k, f"phase portrait at r = {R_PHASE:g}: {name}")
    return fig, points


if __name__ == "__main__":
    import json
    import sys
    import time
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))
    start = time.perf_counter()
    figure, found = figure_sliding_mode()
    figure.savefig(sys.argv[1] if len(sys.argv) > 1 else "sliding_mode.png", dpi=110)
    print(json.dumps({"points": found, "seconds": time.perf_counter() - start}, indent=1))
