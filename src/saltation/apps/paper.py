"""Reproduce the figures of *Fold bifurcations in discontinuous systems*.

* Fig. 3: response diagram of the trilinear spring system over the forcing
  frequency, with the corners at w_A and w_B and the smooth fold of the
  hardened peak.
* Fig. 4: magnitudes of its Floquet multipliers, with the jumps at w_A
  (inside the unit circle) and w_B (through +1: a discontinuous fold).
* Fig. 6: phase plane of the block-on-belt system: stable stick-slip limit
  cycle, unstable limit cycle (backward time), equilibrium and stick band.
* Fig. 7: bifurcation diagram of the block-on-belt system over the belt
  velocity: stable branch, infinitely unstable branch (backward-time
  shooting) joined at a discontinuous fold, and the equilibrium branch.

:func:`reproduce` computes everything and writes figures (PNG, PDF), branch
data (JSON, CSV) and ``special_points.json``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from matplotlib.lines import Line2D

from saltation._moved import forward_names
from saltation.branches.branch import Branch
from saltation.engine.flow import Flow
from saltation.engine.precompile import compile_in_parallel
from saltation.errors import SaltationError
from saltation.model.regularize import regularize
from saltation.model.system import PiecewiseSystem
from saltation.models import SHIPPED, block_on_belt, trilinear
from saltation.models.trilinear import linear_response_state
from saltation.orbits.equilibria import EquilibriumProblem
from saltation.orbits.floquet import multipliers_from_monodromy
from saltation.orbits.single import ShootingProblem
from saltation.orbits.start import estimate_period, find_periodic_orbit, transient
from saltation.output import io, plotting
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.special_points.follow import BifurcationDiagram, follow_branch

Progress = Callable[[str, int], None] | None


@dataclass(frozen=True)
class PaperSettings:
    """Ranges and step sizes of the paper's diagrams.

    Attributes
    ----------
    omega_range : (float, float)
        Forcing frequencies of Figs. 3 and 4.
    v_dr_range : (float, float)
        Belt velocities of Fig. 7.
    ds_max : float
        Largest continuation step (smaller gives denser diagrams).
    phase_plane_v_dr : float
        Belt velocity of Fig. 6.
    """

    omega_range: tuple[float, float] = (0.6, 1.6)
    v_dr_range: tuple[float, float] = (0.2, 1.4)
    ds: float = 0.015
    ds_max: float = 0.015
    phase_plane_v_dr: float = 1.0


#: Smoothing widths of the regularized block-on-belt model (below the stick band's eta = 1e-4, which the
#: smoothing must resolve for a stick-slip cycle to exist at all).
SMOOTHING_WIDTHS = (1e-5, 3e-6, 1e-6)


@dataclass(frozen=True)
class SmoothingRow:
    """What forward continuation of the regularized block-on-belt model reaches, for one width.

    Attributes
    ----------
    epsilon : float
        Smoothing width (:func:`saltation.regularize.regularize`).
    turning_point : float
        The largest ``v_dr`` of the forward branch (where it turns, or stops).
    points_beyond : int
        Points of the forward branch past its turning point (on the smoothed unstable branch).
    largest_multiplier : float
        The largest ``|mu|`` the forward branch reaches.
    stop_reason : str
    unstable_multiplier : float
        ``|mu|`` of the smoothed unstable cycle at ``v_dr = 1`` found by backward-time shooting
        (``inf`` when its backward multiplier is zero to the monodromy's accuracy: beyond double precision).
    unstable_amplitude : float
        Its amplitude, against the discontinuous model's infinitely unstable cycle.
    """

    epsilon: float
    turning_point: float
    points_beyond: int
    largest_multiplier: float
    stop_reason: str
    unstable_multiplier: float
    unstable_amplitude: float

    def record(self) -> dict:
        return {k: (v if isinstance(v, str) else (float(v) if np.isfinite(v) else "inf")) for k, v in self.__dict__.items()}


@dataclass
class PaperResults:
    """Everything :func:`compute` produces."""

    trilinear_branch: Branch
    block_on_belt: BifurcationDiagram
    phase_plane: dict[str, np.ndarray] = field(default_factory=dict)
    smoothing: list[SmoothingRow] = field(default_factory=list)
    smoothed_branches: list[Branch] = field(default_factory=list)

    def special_point_records(self) -> list[dict]:
        """Public records of every located special point (the contract of ``special_points.json``)."""
        records = [io.special_point_record(sp, "trilinear", "omega") for sp in self.trilinear_branch.special_points]
        records += [io.special_point_record(sp, "block_on_belt", "v_dr") for sp in self.block_on_belt.special_points]
        return records


def trilinear_diagram(settings: PaperSettings = PaperSettings(), progress: Progress = None) -> Branch:
    """The response curve of Figs. 3 and 4, over ``settings.omega_range``."""
    system = trilinear()
    flow = Flow(system)
    lo, hi = settings.omega_range
    params = dict(system.defaults) | {"omega": lo}
    problem = ShootingProblem(flow, {"omega": lo}, continuation_parameter="omega")
    cset = ContinuationSettings(ds=min(settings.ds, settings.ds_max), ds_max=settings.ds_max, bounds=(lo, hi), max_points=5000)
    counter = _counter(progress, "trilinear response")
    branch = continue_branch(problem, linear_response_state(params), lo, settings=cset, directions=(1,), progress=counter)
    branch.label = "periodic"
    return branch


def block_on_belt_diagram(settings: PaperSettings = PaperSettings(), progress: Progress = None) -> BifurcationDiagram:
    """Fig. 7: stable, infinitely unstable and equilibrium branches over ``settings.v_dr_range``."""
    system = block_on_belt()
    flow = Flow(system)
    lo, hi = settings.v_dr_range
    v0 = settings.phase_plane_v_dr
    cset = ContinuationSettings(ds=min(settings.ds, settings.ds_max), ds_max=settings.ds_max, bounds=(lo, hi), max_points=5000, ds_min=1e-5)
    stable0 = stable_stick_slip_cycle(flow, v0)
    problem = ShootingProblem(flow, {"v_dr": v0}, continuation_parameter="v_dr")
    u0 = problem.pack(stable0.state0, stable0.period)
    counter = _counter(progress, "block-on-belt")
    down = follow_branch(problem, u0, v0, settings=cset, direction=-1, progress=counter, switch=False,
                         through_fold=False)
    # upward the stable branch ends at the discontinuous fold: the infinitely unstable branch goes on beyond it
    up = follow_branch(problem, u0, v0, settings=cset, direction=1, progress=counter, switch=False)
    if up.beyond is None:
        raise up.error or SaltationError(
            f"the stable branch of block_on_belt ended without a discontinuous fold ({up.end.value})")
    unstable = up.beyond
    stable = up.branch
    stable.extend(down.branch)
    stable.stop_reasons.append(down.branch.stop_reason)
    stable.label = "stable periodic (forward time)"
    unstable.label = "unstable periodic (backward time)"

    eq_problem = EquilibriumProblem(flow, "slip_minus", {"v_dr": lo}, continuation_parameter="v_dr")
    x_eq = np.array([system.defaults["F_slip"] / system.defaults["k"], 0.0])
    equilibrium = continue_branch(
        eq_problem, x_eq, lo, settings=ContinuationSettings(ds=0.05, ds_max=0.05, bounds=(lo, hi)), directions=(1,)
    )
    equilibrium.label = "equilibrium"
    return BifurcationDiagram(model=system.name, parameter_name="v_dr", branches=[stable, unstable, equilibrium])


def stable_stick_slip_cycle(flow: Flow, v_dr: float):
    """The stable stick-slip limit cycle at belt velocity ``v_dr`` (transient, then shooting)."""
    p = flow.parameters({"v_dr": v_dr})
    # every orbit through the stick band lies on the stable cycle after its stick phase: from the start
    # the command line uses too (sticking to the belt)
    values = dict(zip(flow.system.parameter_names, p))
    run = transient(flow, p, SHIPPED["block_on_belt"].start(values, False), length=40.0)
    return find_periodic_orbit(flow, run.x1, parameters={"v_dr": v_dr}, period=estimate_period(run))


def phase_plane(v_dr: float = 1.0) -> dict[str, np.ndarray]:
    """Fig. 6: stable and unstable limit cycles (sampled), the equilibrium, the stick band."""
    system = block_on_belt()
    flow = Flow(system)
    stable = stable_stick_slip_cycle(flow, v_dr)
    # the unstable cycle attracts in backward time: a backward transient from inside the stable cycle
    p = flow.parameters({"v_dr": v_dr})
    d = system.defaults
    x_eq = np.array([system.defaults["F_slip"] / system.defaults["k"], 0.0])
    guess = x_eq + 0.9 * (stable.state0 - x_eq)
    back = flow.run(guess, 0.0, -3 * stable.period, p)
    unstable = find_periodic_orbit(flow, back.x1, parameters={"v_dr": v_dr}, period=stable.period, backward=True)
    ts, xs = flow.run(stable.state0, 0.0, stable.period, p, dense=True).sample(16)
    tu, xu = flow.run(unstable.state0, 0.0, -unstable.period, p, dense=True).sample(16)
    # the paper's flows: I from outside the stable cycle, II between the cycles (both reach the stick band
    # D and join the stable cycle), III inside the unstable cycle (to the equilibrium)
    right_s, right_u = xs[:, 0].max(), xu[:, 0].max()
    starts = {"flow_I": [right_s + 0.35, 0.0], "flow_II": [0.5 * (right_s + right_u), 0.0],
              "flow_III": [x_eq[0] + 0.85 * (right_u - x_eq[0]), 0.0]}
    flows = {}
    for name, x in starts.items():  # each until it sticks (then it is on the stable cycle), or 1.6 periods
        t_end = 1.6 * stable.period
        first = flow.run(x, 0.0, t_end, p)
        sticks = [e.t for e in first.events if e.mode_to == "stick"]
        flows[name] = flow.run(x, 0.0, min([t_end] + [t + 0.4 for t in sticks]), p, dense=True).sample(40)[1]
    return {
        "stable": xs,
        "unstable": xu,
        **flows,
        "equilibrium": x_eq,
        "stable_multipliers": stable.multipliers,
        "unstable_multipliers": unstable.multipliers,
        "unstable_backward_multipliers": multipliers_from_monodromy(unstable.monodromy),
        "v_dr": np.array(v_dr),
        "eta": np.array(system.defaults["eta"]),
        # D: the band |x' - v_dr| < eta where the spring and damper force is below F_stick (eq. 17)
        "stick_x": np.array([(-d["F_stick"] - d["c"] * v_dr) / d["k"], (d["F_stick"] - d["c"] * v_dr) / d["k"]]),
    }


@functools.cache  # a model is immutable (as the shipped models, built once): regularizing it again is wasted
def smoothed_block_on_belt() -> PiecewiseSystem:
    """The block-on-belt model smoothed by :func:`saltation.regularize.regularize` (width a parameter)."""
    return regularize(block_on_belt(), SMOOTHING_WIDTHS[0])


def smoothing_study(
    settings: PaperSettings = PaperSettings(), progress: Progress = None, widths: tuple[float, ...] = SMOOTHING_WIDTHS,
    v_start: float = 0.8,
) -> tuple[list[SmoothingRow], list[Branch]]:
    """The paper's smoothing claim, shown: the regularized model's stable branch, followed in forward time.

    For each width the branch from ``v_start`` upward turns near the fold of the discontinuous model;
    past it the smoothed unstable cycle is so unstable (its multiplier grows without bound as the
    width shrinks; by backward-time shooting: ``unstable_multiplier``) that forward continuation
    stops within a few points of the turning point, or at it.
    """
    flow = Flow(smoothed_block_on_belt())
    switch = Flow(block_on_belt())
    unstable = find_periodic_orbit(switch, [1.0, -0.95], period=6.3, backward=True)  # the discontinuous model's
    lo, hi = settings.v_dr_range
    rows, branches = [], []
    counter = _counter(progress, "smoothed block-on-belt")
    for eps in widths:
        values = {"v_dr": v_start, "epsilon": eps}
        start = flow.run([0.0, v_start], 0.0, 60.0, flow.parameters(values))
        orbit = find_periodic_orbit(flow, start.x1, parameters=values, period=6.5)
        problem = ShootingProblem(flow, values, continuation_parameter="v_dr")
        cset = ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(v_start, hi), max_points=400)
        branch = continue_branch(problem, problem.pack(orbit.state0, orbit.period), v_start, settings=cset,
                                 directions=(1,), progress=counter, label=f"smoothed, epsilon = {eps:g}")
        lam = branch.parameter
        k = int(np.argmax(lam))
        try:
            smooth_unstable = find_periodic_orbit(flow, unstable.state0, parameters={"epsilon": eps},
                                                  period=unstable.period, backward=True)
            mu_u, amp_u = float(np.max(np.abs(smooth_unstable.multipliers))), smooth_unstable.amplitude
        except SaltationError:
            mu_u, amp_u = float("nan"), float("nan")
        rows.append(SmoothingRow(
            epsilon=eps, turning_point=float(lam[k]), points_beyond=len(branch) - 1 - k,
            largest_multiplier=float(max(np.max(np.abs(pt.multipliers)) for pt in branch.points)),
            stop_reason=branch.stop_reason.value, unstable_multiplier=mu_u, unstable_amplitude=amp_u,
        ))
        branches.append(branch)
    return rows, branches


def smoothing_table(rows: list[SmoothingRow], unstable_amplitude: float | None = None) -> str:
    """A plain-text table of :func:`smoothing_study`."""
    head = (f"{'epsilon':>8} {'turns at v_dr':>14} {'points past':>11} {'largest |mu| reached':>21} "
            f"{'|mu| of unstable cycle at v_dr=1':>33} {'its amplitude':>14}")
    lines = [head]
    for r in rows:
        lines.append(f"{r.epsilon:>8.0e} {r.turning_point:>14.8f} {r.points_beyond:>11d} {r.largest_multiplier:>21.4g} "
                     f"{r.unstable_multiplier:>33.4g} {r.unstable_amplitude:>14.6f}")
    if unstable_amplitude is not None:
        lines.append(f"{'':>8} the discontinuous model's infinitely unstable cycle at v_dr=1 has amplitude {unstable_amplitude:.6f}")
    return "\n".join(lines)


def compute(settings: PaperSettings = PaperSettings(), progress: Progress = None) -> PaperResults:
    """Compute the data of Figs. 3, 4, 6 and 7 and the smoothing study (compiling the models at once on a cold cache)."""
    # the engine's build starts before the models are built (they have two states: position and velocity)
    compile_in_parallel((make() for make in (trilinear, block_on_belt, smoothed_block_on_belt)), dimensions=(2,))
    # the smoothing study runs beside the figures: the engine releases the GIL, and the two share nothing
    with ThreadPoolExecutor(1) as pool:
        smoothing = pool.submit(smoothing_study, settings, progress)
        trilinear_branch = trilinear_diagram(settings, progress)
        diagram = block_on_belt_diagram(settings, progress)
        plane = phase_plane(settings.phase_plane_v_dr)
        rows, smoothed = smoothing.result()
    return PaperResults(
        trilinear_branch=trilinear_branch,
        block_on_belt=diagram,
        phase_plane=plane,
        smoothing=rows,
        smoothed_branches=smoothed,
    )


def _branch_csv(branch, path: Path) -> list[Path]:
    """A branch as CSV and the metadata file beside it: both paths."""
    return [io.save_branch_csv(branch, path), io.csv_metadata_path(path)]


def write(results: PaperResults, out: Path) -> list[Path]:
    """Write figures (PNG and PDF), branch data (JSON and CSV) and ``special_points.json``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    figures = []  # drawn at the end, together (plotting.save_figures: on two cores where it can)
    tri = results.trilinear_branch
    figures.append((plotting.plot_response([tri]), out / "fig3_trilinear_response"))
    figures.append((plotting.plot_multipliers(tri), out / "fig4_trilinear_multipliers"))
    pp = results.phase_plane
    curves = [
        plotting.PhaseCurve(pp["stable"], label="stable limit cycle", style=plotting.CurveStyle.STABLE),
        plotting.PhaseCurve(pp["unstable"], label="unstable limit cycle (backward time)", style=plotting.CurveStyle.UNSTABLE),
        *(plotting.PhaseCurve(pp[f"flow_{k}"], label="flows I, II, III" if k == "I" else "",
                              style=plotting.CurveStyle.TRAJECTORY) for k in ("I", "II", "III")),
    ]
    fig6 = plotting.plot_phase_plane(
        curves, equilibrium=pp["equilibrium"], stick_band=(float(pp["v_dr"]), 0.05), band_label="stick phase D (eta enlarged)",
        stick_region=(float(pp["stick_x"][0]), float(pp["stick_x"][1])), regions=("V", "W", "D"),
        legend_below=True, labels=[(k, pp[f"flow_{k}"][0]) for k in ("I", "II", "III")], figsize=(6.0, 5.2),
    )
    figures.append((fig6, out / "fig6_block_on_belt_phase_plane"))
    figures.append((plotting.plot_response(results.block_on_belt.branches), out / "fig7_block_on_belt_diagram"))

    written.append(io.save_branch_json(tri, out / "trilinear_branch.json"))
    written += _branch_csv(tri, out / "trilinear_branch.csv")
    written.append(io.save_diagram_json(results.block_on_belt.branches, out / "block_on_belt_branches.json"))
    for k, br in enumerate(results.block_on_belt.branches):
        written += _branch_csv(br, out / f"block_on_belt_branch{k}.csv")
    np.savez(out / "fig6_phase_plane.npz", **{k: np.asarray(v) for k, v in pp.items()})
    written.append(out / "fig6_phase_plane.npz")
    written.append(io.save_special_points_json(results.special_point_records(), out / "special_points.json"))
    if results.smoothing:
        stable, unstable = results.block_on_belt.branches[:2]
        fig8 = plotting.plot_response([stable, unstable], special_points=False, legend=False)
        ax = fig8.axes[0]
        for line in ax.lines:  # the discontinuous model's branches on top, thick: the smoothed ones lie along them
            line.set_linewidth(2.6)
            line.set_zorder(4)
        handles = [Line2D([], [], color="k", linestyle="-", linewidth=2.6, label="stable (discontinuous model)"),
                   Line2D([], [], color="k", linestyle="-.", linewidth=2.6, label="infinitely unstable (backward time)")]
        dashes = [(0, (4, 1.5)), (0, (1, 1)), (0, (6, 1.5, 1, 1.5))]
        for k, (row, br) in enumerate(zip(results.smoothing, results.smoothed_branches)):
            style = {"color": "0.55" if k % 2 else "0.3", "linestyle": dashes[k % len(dashes)], "linewidth": 1.1}
            ax.plot(br.parameter, br.amplitude, zorder=5, **style)
            ax.plot(br.parameter[-1], br.amplitude[-1], "x", color=style["color"], zorder=6)
            handles.append(Line2D([], [], label=rf"smoothed, $\varepsilon$ = {row.epsilon:g}", **style))
        ax.set_xlim(0.8, 1.12)
        ax.set_ylim(1.9, 2.45)
        ax.legend(handles=handles, loc="lower left", fontsize=7)
        ax.set_title("Smoothed models follow the stable branch and stop at its fold (x: last point);\n"
                     "the infinitely unstable branch is found by backward shooting of the discontinuous model",
                     fontsize=8)
        figures.append((fig8, out / "fig8_block_on_belt_smoothed"))
        written.append(io.write_json([r.record() for r in results.smoothing], out / "smoothing_table.json"))
    return plotting.save_figures(figures, dpi=150) + written


def special_point_table(records: list[dict]) -> str:
    """A plain-text table of located special points: where, the multipliers' moduli on either side, and what
    Feigin's classification predicts at a non-smooth point (``persistence`` or ``nonsmooth_fold``, with
    ``, period two`` where a period-two orbit is born; ``undetermined``; ``-`` at a smooth point)."""

    def fmt(mu) -> str:
        if mu is None:
            return "-"
        return " ".join(_modulus(m) for m in mu)

    def scenario(r: dict) -> str:
        if r.get("scenario") is None:
            return "-"
        return str(r["scenario"]) + (", period two" if r.get("period_two") else "")

    cells = [(str(r["model"]), str(r["kind"]), str(r["parameter"]), f"{r['value']:.10f}",
              fmt(r.get("multipliers_minus", r.get("multipliers"))), fmt(r.get("multipliers_plus")), scenario(r))
             for r in records]
    head = ("model", "kind", "parameter", "value", "|mu| minus / at", "|mu| plus", "border collision")
    # each column as wide as its longest entry (at least as the paper's table has it): long names keep the columns
    widths = [max([least, len(h)] + [len(c[k]) for c in cells])
              for k, (least, h) in enumerate(zip((14, 30, 10, 16, 22, 18, 18), head))]
    left = (True, True, False, False, False, False, False)

    def line(row) -> str:
        return " ".join(f"{c:<{w}}" if lft else f"{c:>{w}}" for c, w, lft in zip(row, widths, left)).rstrip()

    return "\n".join([line(head), *(line(c) for c in cells)])


def _modulus(m) -> str:
    """A multiplier's modulus as the table shows it (``inf`` for an infinite one, written ``"inf"`` or
    ``["-inf", 0.0]``)."""
    if m == "inf":
        return "inf"
    re, im = (float(x) for x in m)  # ("-inf", "nan" as files write them)
    z = abs(complex(re, im))
    return "inf" if z == float("inf") else f"{z:.4f}"


def _counter(progress: Progress, what: str):
    count = [0]

    def tick(_point=None):
        count[0] += 1
        if progress is not None:
            progress(what, count[0])

    return tick


__all__ = [
    "PaperResults",
    "PaperSettings",
    "block_on_belt_diagram",
    "compute",
    "linear_response_state",  # of saltation.models.trilinear, re-exported here until release 0.3.0
    "phase_plane",
    "smoothing_study",
    "smoothing_table",
    "special_point_table",
    "trilinear_diagram",
    "write",
]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.special_points.follow', 'saltation.branches.continuation'))
