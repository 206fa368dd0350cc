"""mkdocs hook: compute the gallery's figures with saltation at every build.

Each shipped model of the gallery gets one figure, computed from scratch by
the library in the working tree (``PYTHONPATH=src``; the repository's ``src``
is put first on ``sys.path`` in any case) and drawn with
:mod:`saltation.output.plotting` on matplotlib ``Figure`` objects (no pyplot state).
Nothing is checked in: the PNGs exist only in memory and in the built site.

* ``on_pre_build`` computes the figures, each in its own Python process (two
  at a time; ``SALTATION_DOCS_JOBS=N`` for another number), and keeps the PNG
  bytes and the located special points;
* ``on_files`` adds the PNGs to the site as ``gallery/img/<model>.png``;
* ``on_page_markdown`` replaces a line ``<!-- gallery-points: <model> -->`` in
  a page by the table of the special points located in this build.

A figure whose computation fails fails the build (an error, not a warning).
Compiled kernels are cached in ``~/.cache/saltation`` (or
``$SALTATION_CACHE_DIR``): the first build on a machine compiles each model
once (about 25 s each), later builds take seconds per figure.

Run ``python docs/hooks/gallery.py MODEL OUT.png`` to compute one figure by hand.
"""

from __future__ import annotations

import base64
import concurrent.futures
import io
import json
import logging
import os
import subprocess
import sys
import time
from pathlib import Path

from gallery_chaos import figure_impact_chaos  # noqa: F401  (compute() finds figure_<model> in globals())
from gallery_criticality import figure_criticality  # noqa: F401
from gallery_rotor import figure_neimark_sacker  # noqa: F401
from gallery_sliding import figure_sliding_mode  # noqa: F401
from gallery_sticking import figure_ball_on_table  # noqa: F401

log = logging.getLogger("mkdocs.hooks.gallery")

REPO = Path(__file__).resolve().parents[2]
SRC = REPO / "src"

#: Gallery models, each a function below that returns ``(Figure, special points)``.
MODELS = ("impact_oscillator", "impact_chaos", "bouncing_ball", "friction_oscillator", "relay_feedback", "buck_converter",
          "two_mass_stops", "tilted_relay", "sliding_mode", "phase_response", "neimark_sacker", "criticality",
          "ball_on_table")

_RESULTS: dict[str, dict] = {}


# ---------------------------------------------------------------------------------------------------------------
# the figures (run in a child process: ``python gallery.py MODEL``)
# ---------------------------------------------------------------------------------------------------------------


def _two_panels(width: float = 10.0, height: float = 4.0):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    return fig, fig.subplots(1, 2)


def _records(*branches):
    """The special points of the branches, each once (a period-2 branch starts with the period doubling it
    was born at, which its parent branch holds too)."""
    from saltation.special_points.follow import distinct_special_points

    return [
        {"kind": sp.kind.value, "parameter": branches[0].parameter_name, "value": float(sp.parameter),
         "accuracy": float(sp.accuracy)}
        for sp in distinct_special_points(branches)
    ]


def figure_impact_oscillator():
    """Branch over the stop position s through the grazing; the grazing curve in (s, omega) vs its closed form."""
    import numpy as np

    from saltation import ContinuationSettings, Flow, ShootingProblem, continue_branch
    from saltation.special_points.loci import follow_locus
    from saltation.models import impact_oscillator
    from saltation.models.impact_oscillator import DEFAULTS
    from saltation.output.plotting import plot_response

    zeta, w = DEFAULTS["zeta"], DEFAULTS["omega"]
    d = (1 - w**2) ** 2 + (2 * zeta * w) ** 2
    x0 = [(1 - w**2) / d, w * 2 * zeta * w / d]  # the harmonic response at t = 0
    problem = ShootingProblem(Flow(impact_oscillator()), {"s": 3.0}, continuation_parameter="s")
    branch = continue_branch(problem, x0, 3.0, directions=(-1,),
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(1.6, 3.0)))
    fig, (ax1, ax2) = _two_panels()
    plot_response(branch, ax1, xlabel="stop position s", ylabel="max |x| over a period")
    ax1.set_title("period-1 orbits over s")
    (graze,) = [sp for sp in branch.special_points if sp.kind.value == "grazing"]
    locus = follow_locus(problem, graze, "omega", (0.6, 1.0))
    omega = np.linspace(0.6, 1.0, 200)
    ax2.plot(omega, 1 / np.sqrt((1 - omega**2) ** 2 + (2 * zeta * omega) ** 2), color="0.7", linewidth=4,
             label="closed form $1/\\sqrt{(1-\\omega^2)^2+(2\\zeta\\omega)^2}$")
    ax2.plot(locus.values[:, 1], locus.values[:, 0], "k.", markersize=3, label="follow_locus")
    ax2.set_xlabel("omega")
    ax2.set_ylabel("s at grazing")
    ax2.set_title("grazing curve in (omega, s)")
    ax2.legend(fontsize="small")
    return fig, _records(branch)


def figure_bouncing_ball():
    """Period-1 branch over A with its period doubling, and the period-2 branch born there."""
    import numpy as np

    from saltation import ContinuationSettings, Flow, ShootingProblem, continue_branch
    from saltation.special_points.branch_switching import follow_period_doubled_branch
    from saltation.special_points.loci import follow_locus
    from saltation.models import bouncing_ball
    from saltation.models.bouncing_ball import DEFAULTS
    from saltation.output.plotting import plot_response

    g, e, a0, w = (DEFAULTS[k] for k in ("g", "e", "A", "omega"))
    period = 2 * np.pi / w
    phi = np.arccos((1 - e) * np.pi * g / ((1 + e) * a0 * w**2))  # the impact phase of the period-1 orbit
    t_i, v_plus = phi / w, g * period / 2
    tau = (-t_i) % period
    x0 = [a0 * np.sin(w * t_i) + v_plus * tau - g * tau**2 / 2, v_plus - g * tau]
    problem = ShootingProblem(Flow(bouncing_ball()), {"A": a0}, continuation_parameter="A")
    branch = continue_branch(problem, x0, a0, directions=(1,), label="period 1",
                             settings=ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(a0, 0.45)))
    (pd,) = [sp for sp in branch.special_points if sp.kind.value == "period_doubling"]
    doubled = follow_period_doubled_branch(problem, pd, settings=ContinuationSettings(ds=0.005, ds_max=0.01,
                                                                                       bounds=(a0, 0.45)))
    fig, (ax1, ax2) = _two_panels()
    plot_response([branch, doubled], ax1, measure="half_peak_to_peak", colors=["k", "C0"],
                  xlabel="table amplitude A", ylabel="half peak-to-peak of the height y")
    ax1.set_title("period-1 and period-2 orbits over A")
    locus = follow_locus(problem, pd, "e", (0.3, 0.7))
    e_ref = np.linspace(0.3, 0.7, 200)
    a_ref = g / w**2 * np.sqrt((np.pi * (1 - e_ref) / (1 + e_ref)) ** 2 + (2 * (1 + e_ref**2) / (1 + e_ref) ** 2) ** 2)
    ax2.plot(e_ref, a_ref, color="0.7", linewidth=4, label="closed form (Holmes 1982)")
    ax2.plot(locus.values[:, 1], locus.values[:, 0], "k.", markersize=3, label="follow_locus")
    ax2.set_xlabel("restitution e")
    ax2.set_ylabel("A at the period doubling")
    ax2.set_title("period-doubling curve in (e, A)")
    ax2.legend(fontsize="small")
    return fig, _records(branch, doubled)


def figure_friction_oscillator():
    """Branch over the belt speed v_b through grazing-, switching- and crossing-sliding; sticking orbits."""
    import numpy as np

    from saltation import ContinuationSettings, Flow, ShootingProblem, continue_branch
    from saltation.models import friction_oscillator
    from saltation.models.friction_oscillator import DEFAULTS
    from saltation.output.plotting import PhaseCurve, plot_phase_plane, plot_response

    zeta, friction, a, w = (DEFAULTS[k] for k in ("zeta", "F", "a", "omega"))
    d = (1 - w**2) ** 2 + (2 * zeta * w) ** 2
    amp, phi = a / np.sqrt(d), np.arctan2(2 * zeta * w, 1 - w**2)
    x0 = [friction + amp * np.cos(-phi), -amp * w * np.sin(-phi)]  # the slower-than-belt harmonic response
    flow = Flow(friction_oscillator())
    problem = ShootingProblem(flow, {"v_b": 2.5}, continuation_parameter="v_b")
    branch = continue_branch(problem, x0, 2.5, directions=(-1,),
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.85, 2.5)))
    fig, (ax1, ax2) = _two_panels()
    plot_response(branch, ax1, xlabel="belt speed v_b")
    ax1.set_title("period-1 orbits over v_b")
    curves = []
    period = 2 * np.pi / w
    for k, v_b in enumerate((2.0, 1.2, 0.9)):
        i = int(np.argmin(np.abs(branch.parameter - v_b)))
        p = problem.parameters_at(branch.parameter[i])
        traj = flow.run(branch.points[i].state, 0.0, period, p, dense=True)
        _, x = traj.sample(16)
        curves.append(PhaseCurve(x, f"v_b = {branch.parameter[i]:.2f}", "stable"))
        ax2.axhline(branch.parameter[i], color=f"C{k}", linewidth=0.8, linestyle=":")
    plot_phase_plane(curves, ax2, legend=True)
    for k, line in enumerate(ax2.get_lines()[-len(curves):]):
        line.set_color(f"C{k}")
    ax2.legend(fontsize="small")
    ax2.set_title("orbits; sticking on x' = v_b (dotted)")
    return fig, _records(branch)


def figure_relay_feedback():
    """The symmetric self-oscillation over sigma through the onset of sliding; phase portraits."""
    import numpy as np

    from saltation import ContinuationSettings, Flow, ShootingProblem, continue_branch, find_periodic_orbit
    from saltation.models import relay_feedback
    from saltation.output.plotting import PhaseCurve, plot_phase_plane, plot_response

    flow = Flow(relay_feedback())
    orbit = find_periodic_orbit(flow, [0.5, -4.0, -1.5], period=7.0)
    problem = ShootingProblem(flow, {"sigma": 0.5}, continuation_parameter="sigma")
    branch = continue_branch(problem, problem.pack(orbit.state0, orbit.period), 0.5, directions=(-1,),
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.03, 0.5)))
    fig, (ax1, ax2) = _two_panels()
    plot_response(branch, ax1, state_name="x_1", xlabel="sigma")
    ax1.set_title("symmetric self-oscillation over sigma")
    curves = []
    for sigma in (0.5, 0.03):
        i = int(np.argmin(np.abs(branch.parameter - sigma)))
        point = branch.points[i]
        traj = flow.run(point.state[:3], 0.0, point.period, problem.parameters_at(point.parameter), dense=True)
        _, x = traj.sample(16)
        curves.append(PhaseCurve(x[:, :2], f"sigma = {point.parameter:.2f}", "stable"))
    plot_phase_plane(curves, ax2, xlabel="x1", ylabel="x2")
    for k, line in enumerate(ax2.get_lines()[-len(curves):]):
        line.set_color(f"C{k}")
    ax2.plot([0, 0], [-1, 1], color="C3", linewidth=3, label="sliding region on x1 = 0")
    ax2.legend(fontsize="small")
    ax2.set_title("orbits in (x1, x2)")
    return fig, _records(branch)


def figure_buck_converter():
    """Period-1 orbits over the input voltage E: border collision at saturation and period doubling."""
    from saltation import ContinuationSettings, Flow, ShootingProblem, continue_branch, find_periodic_orbit
    from saltation.models import buck_converter
    from saltation.output.plotting import plot_multipliers, plot_response

    flow = Flow(buck_converter())
    start = find_periodic_orbit(flow, [0.6, 12.0, 0.2], parameters={"E": 20.0}, period=1.0)
    problem = ShootingProblem(flow, {"E": 20.0}, continuation_parameter="E")
    branch = continue_branch(problem, problem.pack(start.state0, start.period), 20.0,
                             settings=ContinuationSettings(bounds=(11.5, 26.0), tol=1e-12))
    fig, (ax1, ax2) = _two_panels()
    plot_response(branch, ax1, state_name="i", xlabel="input voltage E [V]")
    ax1.set_title("period-1 orbits over E")
    plot_multipliers(branch, ax2, xlabel="input voltage E [V]")
    ax2.set_title("Floquet multipliers")
    return fig, _records(branch)


def figure_two_mass_stops():
    """Two masses between compliant stops: contact with stop 1, then stop 2, and the folds near the second onset."""
    import numpy as np

    from saltation import ContinuationSettings, Flow, ShootingProblem, continue_branch, find_periodic_orbit
    from saltation.models.two_mass_stops import DEFAULTS, two_mass_stops
    from saltation.output.plotting import plot_response

    m1, m2, k1, k2, c1, c2, w = (DEFAULTS[k] for k in ("m1", "m2", "k1", "k2", "c1", "c2", "omega"))
    mass, stiffness = np.diag([m1, m2]), np.array([[k1 + k2, -k2], [-k2, k2]])
    damping = np.array([[c1 + c2, -c2], [-c2, c2]])
    per_force = np.linalg.solve(stiffness - w**2 * mass + 1j * w * damping, [1.0, 0.0])  # the harmonic response

    def free_state0(force):
        x = per_force * force
        return np.array([x[0].real, (1j * w * x[0]).real, x[1].real, (1j * w * x[1]).real])

    flow = Flow(two_mass_stops())
    problem = ShootingProblem(flow, {"F": 0.3}, continuation_parameter="F")
    branch = continue_branch(problem, free_state0(0.3), 0.3, directions=(1,),
                             settings=ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(0.3, 1.0)))
    f1 = 0.78
    zoom_problem = ShootingProblem(flow, {"F": f1}, continuation_parameter="F")
    x0 = find_periodic_orbit(flow, free_state0(f1), parameters={"F": f1}).state0
    zoom = continue_branch(zoom_problem, x0, f1, directions=(1,), settings=ContinuationSettings(
        ds=0.0005, ds_max=0.001, bounds=(f1, 0.79), max_points=1000))
    fig, (ax1, ax2) = _two_panels()
    plot_response(branch, ax1, state_name="x_1", xlabel="forcing amplitude F")
    onset = ax1.axvline(DEFAULTS["d1"] / abs(per_force[0]), color="0.7", linewidth=3, zorder=0,
                        label="contact begins (closed form)")
    ax1.legend(handles=[*ax1.get_legend().legend_handles, onset], fontsize="small")
    ax1.set_title("from free motion to contact with both stops")
    plot_response(zoom, ax2, state_name="x_1", xlabel="forcing amplitude F")
    ax2.set_title("near the onset of contact with stop 2 (small steps)")
    return fig, _records(branch, zoom)


def figure_tilted_relay():
    """Branch over v through grazing- and switching-sliding; both curves in (v, kappa) vs the closed-form grazing."""
    import numpy as np

    from saltation import ContinuationSettings, Flow, ShootingProblem, continue_branch
    from saltation.special_points.loci import follow_locus
    from saltation.models.tilted_relay import DEFAULTS, tilted_relay
    from saltation.output.plotting import plot_response

    zeta, friction, a, w = (DEFAULTS[k] for k in ("zeta", "F", "a", "omega"))
    d = (1 - w**2) ** 2 + (2 * zeta * w) ** 2
    c_cos, c_sin = a * (1 - w**2) / d, a * 2 * zeta * w / d
    x0 = [friction + c_cos, w * c_sin]  # the harmonic response of mode minus (s < 0) at t = 0
    problem = ShootingProblem(Flow(tilted_relay()), {"v": 3.0}, continuation_parameter="v")
    branch = continue_branch(problem, x0, 3.0, directions=(-1,),
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(1.5, 3.0)))
    fig, (ax1, ax2) = _two_panels()
    plot_response(branch, ax1, xlabel="v")
    ax1.set_title("period-1 orbits over v")
    kappa = np.linspace(0.3, 0.7, 200)
    ax2.plot(friction * kappa + np.hypot(c_cos, c_sin) * np.hypot(kappa, w), kappa, color="0.7", linewidth=4,
             label="closed form $v = \\kappa F + A\\sqrt{\\kappa^2+\\omega^2}$")
    curve = ContinuationSettings(ds=0.01, ds_max=0.02)
    for kind, style in (("grazing_sliding", "k."), ("switching_sliding", "C3.")):
        (sp,) = [sp for sp in branch.special_points if sp.kind.value == kind]
        locus = follow_locus(problem, sp, "kappa", (0.3, 0.7), settings=curve)
        ax2.plot(locus.values[:, 0], locus.values[:, 1], style, markersize=3, label=f"{kind} (follow_locus)")
    ax2.set_xlabel("v")
    ax2.set_ylabel("kappa")
    ax2.set_title("sliding bifurcation curves in (v, kappa)")
    ax2.legend(fontsize="small")
    return fig, _records(branch)


def figure_phase_response():
    """The Izhikevich neuron's phase response curve (regular spiking, I = 10), from the spike, both components."""
    import numpy as np

    from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit, phase_response

    neuron = PiecewiseSystem(
        name="izhikevich",
        states=["v", "u"],
        parameters={"a": 0.02, "b": 0.2, "c": -65.0, "d": 8.0, "I": 10.0},
        modes=[Mode("subthreshold", ["0.04*v**2 + 5*v + 140 - u + I", "a*(b*v - u)"])],
        surfaces={"apex": "v - 30"},
        transitions=[Transition("subthreshold", "apex", Crossing.RISING, "subthreshold", reset=["c", "u + d"])],
    )
    orbit = find_periodic_orbit(Flow(neuron), [-65.0, -5.0], period=40.0)
    prc = phase_response(orbit, points=600)
    since = np.mod(prc.phases - prc.event_phases[0], 1.0)  # the phase since the spike (its reset)
    order = np.argsort(since)
    fig, (ax1, ax2) = _two_panels()
    for ax, j, unit in ((ax1, 0, "ms per mV"), (ax2, 1, "ms per unit of u")):
        ax.plot(since[order], prc.values[order, j], "k-")
        ax.axhline(0.0, color="0.7", linewidth=0.8)
        ax.set_xlabel("phase since the spike (cycles)")
        ax.set_ylabel(f"Z_{prc.state_names[j]} ({unit})")
        ax.set_title(f"phase response to a kick of {prc.state_names[j]} (T = {prc.period:.2f} ms)")
    return fig, []


def compute(model: str) -> dict:
    """Compute one model's figure: ``{"png": base64, "points": [...], "seconds": float}``."""
    if str(SRC) not in sys.path:
        sys.path.insert(0, str(SRC))
    start = time.perf_counter()
    fig, points = globals()[f"figure_{model}"]()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    import saltation

    return {"png": base64.b64encode(buf.getvalue()).decode(), "points": points,
            "seconds": time.perf_counter() - start, "saltation": str(Path(saltation.__file__).parent)}


# ---------------------------------------------------------------------------------------------------------------
# mkdocs events
# ---------------------------------------------------------------------------------------------------------------


def _run_child(model: str) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(SRC)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    env.setdefault("MPLBACKEND", "Agg")
    proc = subprocess.run([sys.executable, __file__, model], capture_output=True, text=True, env=env, cwd=REPO)
    if proc.returncode != 0:
        raise RuntimeError(f"gallery figure of {model!r} failed:\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def on_pre_build(config) -> None:
    _RESULTS.clear()
    start = time.perf_counter()
    with concurrent.futures.ThreadPoolExecutor(max_workers=int(os.environ.get("SALTATION_DOCS_JOBS", "2"))) as pool:
        for model, result in zip(MODELS, pool.map(_run_child, MODELS)):
            _RESULTS[model] = result
            log.info("gallery: %s computed in %.1f s (saltation from %s)", model, result["seconds"],
                     result["saltation"])
    log.info("gallery: %d figures in %.1f s", len(_RESULTS), time.perf_counter() - start)


def on_files(files, config):
    from mkdocs.structure.files import File

    for model, result in _RESULTS.items():
        files.append(File.generated(config, f"gallery/img/{model}.png", content=base64.b64decode(result["png"])))
    return files


def on_page_markdown(markdown: str, page, config, files) -> str:
    marker = "<!-- gallery-points: "
    if marker not in markdown:
        return markdown
    out = []
    for line in markdown.splitlines():
        if line.startswith(marker):
            model = line[len(marker):].split()[0]
            points = _RESULTS[model]["points"]
            rows = ["| kind | parameter | located value | accuracy |", "|---|---|---|---|"]
            rows += [f"| `{p['kind']}` | `{p['parameter']}` | {p['value']:.10g} | {p['accuracy']:.1e} |" for p in points]
            out.extend(rows)
        else:
            out.append(line)
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    if len(sys.argv) == 3:  # by hand: python docs/hooks/gallery.py MODEL OUT.png
        res = compute(sys.argv[1])
        Path(sys.argv[2]).write_bytes(base64.b64decode(res["png"]))
        print(json.dumps({k: v for k, v in res.items() if k != "png"}, indent=1))
    else:
        print(json.dumps(compute(sys.argv[1])))
