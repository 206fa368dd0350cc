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

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import io, plotting
from .branch import Branch, SpecialPoint
from .codegen import compile_in_parallel
from .continuation import Continuation, ContinuationSettings, continue_branch
from .diagram import BifurcationDiagram, follow_through_discontinuous_fold
from .errors import SaltationError
from .floquet import multipliers_from_monodromy
from .integrate import Flow
from .models import block_on_belt, trilinear
from .shooting import EquilibriumProblem, ShootingProblem, find_periodic_orbit

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


@dataclass
class PaperResults:
    """Everything :func:`compute` produces."""

    trilinear_branch: Branch
    block_on_belt: BifurcationDiagram
    phase_plane: dict[str, np.ndarray] = field(default_factory=dict)

    def special_point_records(self) -> list[dict]:
        """Public records of every located special point (the contract of ``special_points.json``)."""
        records = [io.special_point_record(sp, "trilinear", "omega") for sp in self.trilinear_branch.special_points]
        records += [io.special_point_record(sp, "block_on_belt", "v_dr") for sp in self.block_on_belt.special_points]
        return records


def linear_response_state(params: dict[str, float]) -> np.ndarray:
    """State at t = 0 of the harmonic response of ``m x'' + c x' + k x = f0 sin(w t)`` (no contact)."""
    m, c, k, f0, w = (params[n] for n in ("m", "c", "k", "f0", "omega"))
    # x = a sin(wt) + b cos(wt)
    det = (k - m * w**2) ** 2 + (c * w) ** 2
    a = f0 * (k - m * w**2) / det
    b = -f0 * c * w / det
    return np.array([b, a * w])


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
    down = Continuation(problem, cset)
    for point in down.run(u0, v0, direction=-1):
        counter(point)
    up = Continuation(problem, cset)
    for point in up.run(u0, v0, direction=1):
        counter(point)
    unstable, fold = follow_through_discontinuous_fold(up, settings=cset, progress=counter)
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
    # every orbit through the stick band lies on the stable cycle after its stick phase
    transient = flow.run([0.0, v_dr], 0.0, 40.0, p)
    period = _return_time(transient)
    return find_periodic_orbit(flow, transient.x1, parameters={"v_dr": v_dr}, period=period)


def _return_time(traj) -> float:
    """Time between the last two events of the same transition (a period estimate)."""
    last = traj.events[-1]
    for e in reversed(traj.events[:-1]):
        if e.transition == last.transition and e.kind == last.kind:
            return last.t - e.t
    raise SaltationError("the transient shows no repeated event; cannot estimate the period")


def phase_plane(v_dr: float = 1.0) -> dict[str, np.ndarray]:
    """Fig. 6: stable and unstable limit cycles (sampled), the equilibrium, the stick band."""
    system = block_on_belt()
    flow = Flow(system)
    stable = stable_stick_slip_cycle(flow, v_dr)
    # the unstable cycle attracts in backward time: a backward transient from inside the stable cycle
    p = flow.parameters({"v_dr": v_dr})
    x_eq = np.array([system.defaults["F_slip"] / system.defaults["k"], 0.0])
    guess = x_eq + 0.9 * (stable.state0 - x_eq)
    back = flow.run(guess, 0.0, -3 * stable.period, p)
    unstable = find_periodic_orbit(flow, back.x1, parameters={"v_dr": v_dr}, period=stable.period, backward=True)
    ts, xs = flow.run(stable.state0, 0.0, stable.period, p, dense=True).sample(16)
    tu, xu = flow.run(unstable.state0, 0.0, -unstable.period, p, dense=True).sample(16)
    return {
        "stable": xs,
        "unstable": xu,
        "equilibrium": x_eq,
        "stable_multipliers": stable.multipliers,
        "unstable_multipliers": unstable.multipliers,
        "unstable_backward_multipliers": multipliers_from_monodromy(unstable.monodromy),
        "v_dr": np.array(v_dr),
        "eta": np.array(system.defaults["eta"]),
    }


def compute(settings: PaperSettings = PaperSettings(), progress: Progress = None) -> PaperResults:
    """Compute the data of Figs. 3, 4, 6 and 7 (compiling both models at once on a cold cache)."""
    compile_in_parallel([trilinear(), block_on_belt()])
    return PaperResults(
        trilinear_branch=trilinear_diagram(settings, progress),
        block_on_belt=block_on_belt_diagram(settings, progress),
        phase_plane=phase_plane(settings.phase_plane_v_dr),
    )


def write(results: PaperResults, out: Path) -> list[Path]:
    """Write figures (PNG and PDF), branch data (JSON and CSV) and ``special_points.json``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    tri = results.trilinear_branch
    written += plotting.save_figure(plotting.plot_response([tri]), out / "fig3_trilinear_response", dpi=150)
    written += plotting.save_figure(plotting.plot_multipliers(tri), out / "fig4_trilinear_multipliers", dpi=150)
    pp = results.phase_plane
    curves = [
        plotting.PhaseCurve(pp["stable"], label="stable limit cycle", style=plotting.CurveStyle.STABLE),
        plotting.PhaseCurve(pp["unstable"], label="unstable limit cycle (backward time)", style=plotting.CurveStyle.UNSTABLE),
    ]
    fig6 = plotting.plot_phase_plane(
        curves, equilibrium=pp["equilibrium"], stick_band=(float(pp["v_dr"]), 0.05), band_label="stick band D (eta enlarged)"
    )
    written += plotting.save_figure(fig6, out / "fig6_block_on_belt_phase_plane", dpi=150)
    written += plotting.save_figure(plotting.plot_response(results.block_on_belt.branches), out / "fig7_block_on_belt_diagram", dpi=150)

    written.append(io.save_branch_json(tri, out / "trilinear_branch.json"))
    written.append(io.save_branch_csv(tri, out / "trilinear_branch.csv"))
    written.append(io.save_diagram_json(results.block_on_belt.branches, out / "block_on_belt_branches.json"))
    for k, br in enumerate(results.block_on_belt.branches):
        written.append(io.save_branch_csv(br, out / f"block_on_belt_branch{k}.csv"))
    np.savez(out / "fig6_phase_plane.npz", **{k: np.asarray(v) for k, v in pp.items()})
    written.append(out / "fig6_phase_plane.npz")
    written.append(io.save_special_points_json(results.special_point_records(), out / "special_points.json"))
    return written


def special_point_table(records: list[dict]) -> str:
    """A plain-text table of located special points."""

    def fmt(mu) -> str:
        if mu is None:
            return "-"
        return " ".join("inf" if m == "inf" else f"{abs(complex(*m)):.4f}" for m in mu)

    rows = [f"{'model':<14} {'kind':<30} {'parameter':>10} {'value':>16} {'|mu| minus / at':>22} {'|mu| plus':>18}"]
    for r in records:
        minus = r.get("multipliers_minus", r.get("multipliers"))
        plus = r.get("multipliers_plus")
        rows.append(
            f"{r['model']:<14} {r['kind']:<30} {r['parameter']:>10} {r['value']:>16.10f} {fmt(minus):>22} {fmt(plus):>18}"
        )
    return "\n".join(rows)


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
    "phase_plane",
    "special_point_table",
    "trilinear_diagram",
    "write",
]
