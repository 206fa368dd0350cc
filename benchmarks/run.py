"""Benchmarks of saltation against a hand-written scipy baseline, in one process.

Run by hand (not by CI)::

    python benchmarks/run.py                 # every benchmark, a table of times and ratios
    python benchmarks/run.py --quick --json  # under a minute once kernels are compiled; one JSON object
    python benchmarks/run.py --only orbit sweep

Times are medians of repeats, warm (kernels compiled and loaded, one untimed
run first), wall clock.  The baseline (``scipy_baseline.py``) is the same
algorithm written by hand for the trilinear system with ``solve_ivp``
(DOP853, rtol 1e-10, atol 1e-12 as saltation's defaults).  Its results are
checked against saltation's before anything is timed: the orbit and its
multipliers must agree to 1e-8, or the run stops.

Benchmarks
----------
orbit       one periodic orbit of the trilinear system at omega = 1.0 (and 0.7) from a
            guess 1e-3 away, Newton to 1e-10, with monodromy and multipliers; against it, the
            limit of the affine path: the matrix exponentials alone (one per segment between
            events, compiled, times the period maps shooting took), and the cost of one call
            of the engine that takes no step
nonlinear   one orbit of a Duffing oscillator with an impact stop (not piecewise affine: the
            DOP853 path), against the same algorithm with solve_ivp (``nonlinear_baseline.py``)
fig3        the response curve of Fig. 3 (``paper.trilinear_diagram``, >= 400 points,
            special points located); baseline: pseudo-arclength over the same curve.  Timed
            after a first run, timed apart: the first diagram of a model in a process also
            derives the closed-form saltation matrices of its corners (sympy, once)
fig7        the block-on-belt diagram of Fig. 7 (``paper.block_on_belt_diagram``), as fig3; no
            baseline
paper       ``python -m saltation paper`` in a fresh process, empty and warm kernel cache
            (full runs only: the empty-cache run compiles every kernel)
multipliers Floquet multipliers on the no-contact branch vs eig(expm(A T)), default tolerances
events      event times of a piecewise-linear flow vs closed form
chain       the chain of n masses, n = 1 ... 64 (32 with --quick): time per orbit, fitted growth exponent
sweep       brute-force diagram, 161 values of omega x 200 forcing periods (100 transient,
            100 sampled), on every core; baseline: the same simulation with solve_ivp

``--quick`` runs fewer repeats, times the slow scipy baselines (continuation,
brute force) on a subset and scales them to the full job (marked "est."),
and skips the paper runs.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.linalg import expm

sys.path.insert(0, str(Path(__file__).resolve().parent))

import scipy_baseline as sb  # noqa: E402

from saltation import Flow, Tolerances  # noqa: E402
from saltation.models import block_on_belt, chain, trilinear  # noqa: E402
from saltation.apps.paper import PaperSettings, block_on_belt_diagram, trilinear_diagram  # noqa: E402
from saltation.orbits.shooting import find_periodic_orbit  # noqa: E402
from saltation.sweeps import sweep  # noqa: E402

TARGETS = {
    "orbit_ms": 0.3,
    "orbit_ratio_vs_scipy": 150.0,
    "orbit_over_limit": 3.0,
    "orbit_nonlinear_ratio_vs_scipy": 50.0,
    "fig3_s": 0.3,
    "fig3_ratio_vs_scipy": 150.0,
    "fig7_s": 0.3,
    "paper_cold_s": 30.0,
    "paper_warm_s": 5.0,
    "multiplier_error": 1e-9,
    "event_time_error": 1e-12,
    "chain_exponent": 2.0,
    "sweep_s": 1.0,
    "sweep_ratio_vs_scipy": 80.0,
    "corner_curve_s_per_200_points": 0.5,
    "fold_curve_s_per_200_points": 0.3,
    "sliding_curve_s_per_200_points": 1.0,
    "lyapunov_1000_periods_ms": 50.0,
    "lyapunov_map_100x100_s": 60.0,
}


# -- the limit of the affine path: the matrix exponentials alone -----------------------------------
def _compiled_expm():
    """A compiled ``expm`` (scaling and squaring of a degree-18 Taylor series, full double precision for
    the small matrices here), and a loop over a period's segments in compiled code: what one period map
    of a piecewise-affine orbit cannot do without."""
    from numba import njit

    @njit(cache=True)
    def expm(A):
        n = A.shape[0]
        norm = 0.0
        for i in range(n):
            row = 0.0
            for j in range(n):
                row += abs(A[i, j])
            norm = max(norm, row)
        s = 0
        while norm > 0.5:
            norm *= 0.5
            s += 1
        B = A / 2.0**s
        E = np.eye(n)
        term = np.eye(n)
        for k in range(1, 19):
            term = term @ B / k
            E = E + term
        for _ in range(s):
            E = E @ E
        return E

    @njit(cache=True)
    def period_exponentials(generators, spans):
        out = np.zeros((generators.shape[1], generators.shape[1]))
        for i in range(generators.shape[0]):
            out += expm(generators[i] * spans[i])
        return out

    return expm, period_exponentials


def orbit_limit(orbit, system_params: dict):
    """The matrix exponentials of an orbit of the trilinear system: one per segment between its events
    (the augmented generator of ``(x, 1, cos w t, sin w t)``, size 5), as many times as the orbit's
    shooting took period maps.  Returns (a function computing those of one period map, the number of
    period maps, the number of segments)."""
    from saltation.models.trilinear import DEFAULTS as TRI

    q = TRI | system_params
    m, c, k, kf, cf, xc, f0, w = (q[a] for a in ("m", "c", "k", "k_f", "c_f", "x_c", "f0", "omega"))
    traj = orbit.trajectory
    times = [traj.t0] + [e.t for e in traj.events] + [traj.t1]
    modes = [traj.mode0] + [e.mode_to for e in traj.events]
    generators = []
    for mode in modes:
        G = np.zeros((5, 5))
        G[0, 1] = 1.0
        contact = mode != "free"
        G[1, 0] = -(k + (kf if contact else 0.0)) / m
        G[1, 1] = -(c + (cf if contact else 0.0)) / m
        if contact:  # the support's offset, on the constant component
            G[1, 2] = (kf * xc if "1" in mode else -kf * xc) / m
        G[1, 4] = f0 / m  # the forcing on sin(w t) (its phase does not change the cost)
        G[3, 4], G[4, 3] = -w, w
        generators.append(G)
    generators = np.array(generators)
    spans = np.diff(np.array(times))
    _, period_exponentials = _compiled_expm()
    period_exponentials(generators, spans)  # compiled (or loaded) before anything is timed
    return (lambda: period_exponentials(generators, spans)), orbit.iterations + 1, len(spans)


def interleaved_medians(fns, repeat: int) -> list[float]:
    """Median times of several functions timed in turn within each repetition, so that a change of the
    machine's load affects them alike (their ratio is what is read)."""
    times = [[] for _ in fns]
    for fn in fns:
        fn()
    for _ in range(repeat):
        for k, fn in enumerate(fns):
            t = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t)
    return [statistics.median(ts) for ts in times]


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def median_time(fn, repeat: int, warmup: int = 1) -> float:
    """Median wall time of ``fn()`` over ``repeat`` runs after ``warmup`` untimed ones."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def timed_runs(fn, quick: bool):
    """Median time of 1 (quick) or 3 runs of a long job whose kernels are warm, and its last result."""
    times = []
    for _ in range(1 if quick else 3):
        t = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), result


def warm_up(system) -> None:
    """Load (or compile) a model's kernels and run them once, so that no timing includes it."""
    flow = Flow(system)
    flow.run(np.zeros(system.n) + 0.5, 0.0, 1.0, flow.parameters(), variational=True)


def sorted_multipliers(mu) -> np.ndarray:
    mu = np.asarray(mu, dtype=complex)
    return mu[np.lexsort((mu.imag, mu.real))]


# -- benchmarks -----------------------------------------------------------------------------------
def bench_orbit(quick: bool) -> dict:
    flow = Flow(trilinear())
    out = {}
    for omega, tag in ((1.0, ""), (0.7, "_no_contact")):
        p = flow.parameters({"omega": omega})
        start = flow.run([0.0, 0.0], 0.0, 100 * 2 * math.pi / omega, p).x1
        ref = find_periodic_orbit(flow, start, parameters={"omega": omega})
        guess = ref.state0 + 1e-3
        orb = find_periodic_orbit(flow, guess, parameters={"omega": omega}, tol=1e-10)
        base = sb.Trilinear(omega=omega)
        x_sp, M_sp, mu_sp, it_sp, ev_sp = base.shoot(guess, tol=1e-10)
        # the baseline must compute the same thing
        dx = float(np.max(np.abs(x_sp - orb.state0)))
        dmu = float(np.max(np.abs(sorted_multipliers(mu_sp) - sorted_multipliers(orb.multipliers))))
        assert dx < 1e-8 and dmu < 1e-8, f"scipy baseline disagrees at omega={omega}: |dx|={dx:.2e}, |dmu|={dmu:.2e}"
        assert [s for s, _ in ev_sp] == [e.surface for e in orb.events], (ev_sp, orb.event_labels)
        t_s = median_time(lambda: find_periodic_orbit(flow, guess, parameters={"omega": omega}, tol=1e-10),
                          20 if quick else 200)
        t_b = median_time(lambda: base.shoot(guess, tol=1e-10), 3 if quick else 15)
        t_map = median_time(lambda: flow.run(orb.state0, 0.0, orb.period, p, variational=True), 50 if quick else 500)
        t_call = median_time(lambda: flow.run(orb.state0, 0.0, 0.0, p, variational=True), 50 if quick else 500)
        exponentials, maps, segments = orbit_limit(orb, {"omega": omega})
        t_orbit, t_exp = interleaved_medians(
            [lambda: find_periodic_orbit(flow, guess, parameters={"omega": omega}, tol=1e-10), exponentials],
            50 if quick else 500)
        limit_ms = t_exp * maps * 1e3
        out |= {
            f"orbit{tag}_limit_ms": limit_ms,
            f"orbit{tag}_over_limit": t_orbit * 1e3 / limit_ms,
            f"orbit{tag}_segments": segments,
            f"orbit{tag}_period_map_ms": t_map * 1e3,
            f"orbit{tag}_call_overhead_ms": t_call * 1e3,
        }
        out |= {
            f"orbit{tag}_ms": t_s * 1e3,
            f"orbit{tag}_scipy_ms": t_b * 1e3,
            f"orbit{tag}_ratio_vs_scipy": t_b / t_s,
            f"orbit{tag}_newton_iterations": orb.iterations,
            f"orbit{tag}_events": len(orb.events),
            f"orbit{tag}_agreement": max(dx, dmu),
        }
    return out


def bench_fig3(quick: bool) -> dict:
    settings = PaperSettings()  # the diagram as `saltation paper` computes it
    warm_up(trilinear())
    # the first diagram of a model in a process also derives the closed-form saltation matrices of its corners
    # (sympy, once per transition): timed apart, and the diagram timed after it, as the full run times it
    t_first, _ = timed_runs(lambda: trilinear_diagram(settings), True)
    t_s, branch = timed_runs(lambda: trilinear_diagram(settings), quick)
    n_points = len(branch.points)
    assert n_points >= 400, n_points
    # baseline: pseudo-arclength with the scipy shooting over the same curve (no special-point location);
    # quick: coarser steps (about 150 points), the time per point scaled to saltation's number of points.
    # max_step limited: solve_ivp checks the events' signs at step ends only, so a shallow contact inside
    # one step is missed, the period map jumps where it is first seen, and the corrector stalls at w_A.
    base = sb.Trilinear(omega=0.6, max_step=0.3)
    x0 = sb.closed_form_no_contact_state(0.6)
    ds = 0.04 if quick else 0.01
    t0 = time.perf_counter()
    pts = base.continuation(x0, 0.6, 1.6, ds=ds, ds_max=ds)
    t_b = time.perf_counter() - t0
    assert pts[-1][0] >= 1.6 and max(q[0] for q in pts) < 1.6 + ds, "the baseline did not follow the whole curve"
    per_point = t_b / len(pts)
    t_b_full = per_point * n_points  # the baseline's time per point, for saltation's number of points
    return {
        "fig3_s": t_s,
        "fig3_first_s": t_first,
        "fig3_points": n_points,
        "fig3_special_points": [sp.kind.value for sp in branch.special_points],
        "fig3_scipy_s": t_b_full,
        "fig3_scipy_points": len(pts),
        "fig3_scipy_estimated": len(pts) != n_points,
        "fig3_ratio_vs_scipy": t_b_full / t_s,
        "fig3_ms_per_point": 1e3 * t_s / n_points,
        "fig3_scipy_ms_per_point": 1e3 * per_point,
    }


def bench_fig7(quick: bool) -> dict:
    warm_up(block_on_belt())
    t_first, _ = timed_runs(block_on_belt_diagram, True)  # with the closed forms of its corners (see bench_fig3)
    t_s, diagram = timed_runs(block_on_belt_diagram, quick)
    return {
        "fig7_s": t_s,
        "fig7_first_s": t_first,
        "fig7_points": [len(b.points) for b in diagram.branches],
        "fig7_special_points": [sp.kind.value for sp in diagram.special_points],
    }


def bench_paper(quick: bool) -> dict:
    if quick:
        return {}
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, SALTATION_CACHE_DIR=str(Path(tmp) / "cache"))
        cmd = [sys.executable, "-m", "saltation", "paper", "--out", str(Path(tmp) / "out"), "--no-progress"]
        for key in ("paper_cold_s", "paper_warm_s"):
            t = time.perf_counter()
            proc = subprocess.run(cmd, env=env, capture_output=True, text=True)
            out[key] = time.perf_counter() - t
            if proc.returncode != 0:
                raise RuntimeError(f"saltation paper failed:\n{proc.stderr[-2000:]}")
    out["paper_command"] = "python -m saltation paper --out DIR --no-progress (SALTATION_CACHE_DIR=empty tmpdir)"
    return out


def bench_multipliers(quick: bool) -> dict:
    """No-contact orbits at default tolerances: multipliers vs the eigenvalues of expm(A T)."""
    flow = Flow(trilinear())
    d = trilinear().defaults
    A = np.array([[0.0, 1.0], [-d["k"] / d["m"], -d["c"] / d["m"]]])
    err, err_b = 0.0, 0.0
    for omega in (0.6, 0.7, 0.8, 1.5, 1.6):
        T = 2 * math.pi / omega
        exact = sorted_multipliers(np.linalg.eigvals(expm(A * T)))
        x0 = sb.closed_form_no_contact_state(omega)
        orb = find_periodic_orbit(flow, x0 + 1e-3, parameters={"omega": omega})
        assert not orb.events
        err = max(err, float(np.max(np.abs(sorted_multipliers(orb.multipliers) - exact))))
        mu_b = sb.Trilinear(omega=omega).shoot(x0 + 1e-3)[2]
        err_b = max(err_b, float(np.max(np.abs(sorted_multipliers(mu_b) - exact))))
    return {"multiplier_error": err, "multiplier_error_scipy": err_b}


def bench_events(quick: bool) -> dict:
    """Event times of piecewise-linear flows of the trilinear model against closed form.

    * Free flight at constant speed (``k = c = f0 = 0``): ``x = V t`` meets ``x_c`` at ``x_c / V``;
      the integration is exact, so this measures the event location alone.
    * Undamped, unforced (``c = c_f = f0 = 0``) from ``(0, 2)``: free flight ``x = 2 sin t`` meets
      ``x_c = 1`` at ``pi / 6``; each contact lasts ``2 atan2(V1 / w1, x_c - x_e) / w1``
      (``w1 = sqrt((k + k_f) / m)``, ``x_e = k_f x_c / (k + k_f)``, ``V1 = sqrt(3)``), each free
      flight between the supports ``pi / 3``: eleven events in 12 time units.
    """
    flow = Flow(trilinear())
    loc = 0.0
    for V in (0.3, 1.0, 3.7):
        for xc in (1.0, 0.37, 2.9):
            p = flow.parameters({"k": 0.0, "c": 0.0, "f0": 0.0, "c_f": 0.0, "x_c": xc})
            tr = flow.run([0.0, V], 0.0, 2 * xc / V, p)
            loc = max(loc, abs(tr.events[0].t - xc / V))
    d = trilinear().defaults
    w1 = math.sqrt((d["k"] + d["k_f"]) / d["m"])
    xe = d["k_f"] * d["x_c"] / (d["k"] + d["k_f"])
    contact = 2 * math.atan2(math.sqrt(3.0) / w1, d["x_c"] - xe) / w1
    times = [math.pi / 6]
    while len(times) < 11:
        times += [times[-1] + contact, times[-1] + contact + math.pi / 3]
    exact = np.array(times[:11])
    p = flow.parameters({"c": 0.0, "f0": 0.0, "c_f": 0.0})
    out = {"event_location_error": loc}
    for key, tol in (("event_time_error", None), ("event_time_error_tight", Tolerances(rtol=1e-13, atol=1e-15))):
        tr = flow.run([0.0, 2.0], 0.0, 12.0, p, tolerances=tol)
        got = np.array([e.t for e in tr.events])
        assert got.shape == exact.shape, (got, exact)
        out[key] = float(np.max(np.abs(got - exact)))
        out[key + "_first"] = float(abs(got[0] - exact[0]))
    return out


def linear_amplitude_of_last_mass(n: int, omega: float, d: dict) -> float:
    """Steady amplitude of ``x_n`` of the chain without contact: ``(K - w^2 M + i w C) X = f0 e_1``."""
    K = np.diag([2.0] * (n - 1) + [1.0]) - np.diag([1.0] * (n - 1), 1) - np.diag([1.0] * (n - 1), -1)
    if n == 1:
        K = np.ones((1, 1))
    F = np.zeros(n)
    F[0] = d["f0"]
    X = np.linalg.solve(d["k"] * K - omega**2 * d["m"] * np.eye(n) + 1j * omega * d["c"] * K, F)
    return float(abs(X[-1]))


def bench_chain(quick: bool) -> dict:
    """Chains of n masses at omega = 1 with the supports at 0.7 times the free amplitude of the last
    mass, so that every orbit touches both supports (four events per period) whatever n."""
    ns = (1, 2, 4, 8, 16, 32) if quick else (1, 2, 4, 8, 16, 32, 64)
    omega = 1.0
    T = 2 * math.pi / omega
    rows = []
    for n in ns:
        t = time.perf_counter()
        system = chain(n)
        flow = Flow(system)
        overrides = {"omega": omega, "x_c": 0.7 * linear_amplitude_of_last_mass(n, omega, system.defaults)}
        p = flow.parameters(overrides)
        start = flow.run(np.zeros(2 * n), 0.0, 150 * T, p).x1
        ref = find_periodic_orbit(flow, start, parameters=overrides)
        setup = time.perf_counter() - t
        guess = ref.state0 + 1e-3
        t_orbit = median_time(lambda: find_periodic_orbit(flow, guess, parameters=overrides), 3 if quick else 10)
        t_period = median_time(lambda: flow.run(ref.state0, 0.0, T, p, variational=True), 5 if quick else 20)
        orb = find_periodic_orbit(flow, guess, parameters=overrides)
        rows.append({"n": n, "orbit_ms": t_orbit * 1e3, "period_map_ms": t_period * 1e3,
                     "newton_iterations": orb.iterations, "events": len(orb.events), "setup_s": setup})
        log(f"  chain n={n}: {rows[-1]}")
    big = [r for r in rows if r["n"] >= 4]
    logn = np.log([r["n"] for r in big])
    slope = np.polyfit(logn, np.log([r["orbit_ms"] for r in big]), 1)[0]
    slope_pm = np.polyfit(logn, np.log([r["period_map_ms"] for r in big]), 1)[0]
    return {"chain": rows, "chain_exponent": float(slope), "chain_exponent_period_map": float(slope_pm)}


def bench_sweep(quick: bool) -> dict:
    omegas = np.linspace(0.6, 1.6, 161)
    periods, transient = 100, 100  # 200 forcing periods simulated per value
    warm_up(trilinear())
    t_s, res = timed_runs(lambda: sweep(trilinear(), "omega", omegas, periods=periods, transient=transient), quick)
    assert not res.failures, res.failures
    out = {"sweep_s": t_s, "sweep_points": int(res.states.shape[0]), "sweep_workers": _cores()}
    if not quick:
        out["sweep_1_worker_s"] = median_time(
            lambda: sweep(trilinear(), "omega", omegas, periods=periods, transient=transient, workers=1), 1, warmup=0)
    base = sb.Trilinear()
    subset = omegas[::32] if quick else omegas
    t = time.perf_counter()
    base.brute_force(subset, periods=periods, transient=transient)
    t_b = (time.perf_counter() - t) * len(omegas) / len(subset)
    out |= {"sweep_scipy_s": t_b, "sweep_scipy_estimated": len(subset) < len(omegas), "sweep_ratio_vs_scipy": t_b / t_s}
    return out


def bench_loci(quick: bool) -> dict:
    """Locating special points (in period maps: the time of one located point over that of one period
    map with its monodromy) and two-parameter curves (the trilinear corner and fold curves in (omega, f0),
    scaled to 200 points)."""
    from saltation.special_points.continuation import ContinuationSettings, continue_branch
    from saltation.special_points.grazing import locate_grazing
    from saltation.special_points.loci import follow_locus
    from saltation.models import impact_oscillator
    from saltation.apps.paper import linear_response_state
    from saltation.orbits.shooting import ShootingProblem

    flow = Flow(trilinear())
    p = flow.parameters({"omega": 1.0})
    x0 = find_periodic_orbit(flow, flow.run([0.0, 0.0], 0.0, 100 * 2 * math.pi, p).x1, parameters={"omega": 1.0}).state0
    t_map = median_time(lambda: flow.run(x0, 0.0, 2 * math.pi, p, variational=True, sensitivity=7), 50 if quick else 500)
    problem = ShootingProblem(flow, {"omega": 0.6}, continuation_parameter="omega")
    branch = continue_branch(problem, linear_response_state(dict(flow.system.defaults, omega=0.6)), 0.6,
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.6, 1.6)), directions=(1,))
    corner = next(sp for sp in branch.special_points if sp.kind.value == "discontinuous_fold")
    fold = next(sp for sp in branch.special_points if sp.kind.value == "fold")
    out = {"period_map_ms": t_map * 1e3}
    for name, sp in (("corner", corner), ("fold", fold)):
        settings = ContinuationSettings(ds=0.002, ds_max=0.002, bounds=(0.05, 0.4), max_points=200)
        t, locus = timed_runs(lambda sp=sp: follow_locus(problem, sp, "f0", (0.05, 0.4), settings=settings), quick)
        out[f"{name}_curve_points"] = len(locus)
        out[f"{name}_curve_s_per_200_points"] = t * 200 / len(locus)
    impact = Flow(impact_oscillator())
    w = impact.system.defaults["omega"]
    det = (1 - w**2) ** 2 + (0.1 * w) ** 2
    guess = np.array([(1 - w**2) / det, 0.1 * w * w / det])
    t_graze = median_time(lambda: locate_grazing(impact, guess, 2.9, "s", 0, 0.3, parameters={"s": 2.9}), 5 if quick else 30)
    out["grazing_location_ms"] = t_graze * 1e3
    out["grazing_location_in_period_maps"] = t_graze / t_map
    out.update(_sliding_locations(quick))
    out.update(_sliding_curve(quick))
    return out


def _sliding_curve(quick: bool) -> dict:
    """The switching-sliding curve of the forced relay with a tilted switching line in (v, kappa), scaled
    to 200 points (one Newton step of its defining system: one integration per freed parameter)."""
    from saltation.models.tilted_relay import tilted_relay
    from saltation.special_points.continuation import ContinuationSettings, continue_branch
    from saltation.special_points.loci import follow_locus
    from saltation.orbits.shooting import ShootingProblem

    flow = Flow(tilted_relay())
    problem = ShootingProblem(flow, {"v": 3.0}, continuation_parameter="v")
    start = find_periodic_orbit(flow, [0.0, 1.0], parameters={"v": 3.0}).state0
    branch = continue_branch(problem, start, 3.0, directions=(-1,),
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(1.5, 3.0)))
    point = next(sp for sp in branch.special_points if sp.kind.value == "switching_sliding")
    settings = ContinuationSettings(ds=0.002, ds_max=0.002, bounds=(0.3, 0.7), max_points=200)
    t, locus = timed_runs(lambda: follow_locus(problem, point, "kappa", (0.3, 0.7), settings=settings), quick)
    return {"sliding_curve_points": len(locus), "sliding_curve_s_per_200_points": t * 200 / len(locus)}


def _sliding_locations(quick: bool) -> dict:
    """The friction oscillator's crossing- and adding-sliding, located from a nearby orbit, in period maps of
    that model (with monodromy and a parameter sensitivity)."""
    from saltation.models import friction_oscillator
    from saltation.special_points.sliding import locate_adding_sliding, locate_tangent_arrival, sliding_change

    out = {}
    for name, param, value, near, other in (("crossing_sliding", "v_b", 0.9, 0.91, {"F": 0.5}),
                                            ("adding_sliding", "F", 0.2, 0.905, {"v_b": 0.2})):
        flow = Flow(friction_oscillator(**other))
        T = 2 * math.pi / 0.8
        far = 0.9 if name == "crossing_sliding" else 0.895

        def orbit(v):
            q = flow.parameters({param: v})
            x = np.array([0.0, q[flow.system.parameter_index("v_b")]])
            for _ in range(100):
                x = flow.run(x, 0.0, T, q).x1
            return find_periodic_orbit(flow, x, parameters={param: v}).state0, q

        x_near, p_near = orbit(near)
        x_far, p_far = orbit(far)
        t_map = median_time(lambda: flow.run(x_near, 0.0, T, p_near, variational=True, sensitivity=0), 20 if quick else 200)
        a, b = flow.run(x_near, 0.0, T, p_near), flow.run(x_far, 0.0, T, p_far)
        without, with_, p_wo, p_w = (a, b, p_near, p_far) if len(a.events) < len(b.events) else (b, a, p_far, p_near)
        change = sliding_change(flow, without, with_, p_w, p_wo)
        if change.kind.value == "adding_sliding":
            locate = lambda: locate_adding_sliding(flow, x_near, near, param, change.t_guess, change.mode,  # noqa: E731
                                                   change.surface, change.side, parameters=p_near)
        else:
            locate = lambda: locate_tangent_arrival(flow, x_near, near, param, change.index, change.mode,  # noqa: E731
                                                    change.side, parameters=p_near)
        t = median_time(locate, 3 if quick else 10)
        out[f"{name}_location_ms"] = t * 1e3
        out[f"{name}_location_in_period_maps"] = t / t_map
    return out


def bench_nonlinear(quick: bool) -> dict:
    """One orbit of the Duffing impact oscillator (not piecewise affine: the DOP853 path) against the same
    algorithm written with solve_ivp (``nonlinear_baseline.py``)."""
    import nonlinear_baseline as nb

    flow = Flow(nb.model())
    p = flow.parameters({})
    T = 2 * math.pi / nb.DEFAULTS["omega"]
    start = flow.run([0.0, 0.0], 0.0, 200 * T, p).x1
    ref = find_periodic_orbit(flow, start)
    guess = ref.state0 + 1e-3
    orb = find_periodic_orbit(flow, guess, tol=1e-10)
    base = nb.DuffingImpact()
    x_sp, _, mu_sp, _, impacts = base.shoot(guess, tol=1e-10)
    dx = float(np.max(np.abs(x_sp - orb.state0)))
    dmu = float(np.max(np.abs(sorted_multipliers(mu_sp) - sorted_multipliers(orb.multipliers))))
    assert dx < 1e-8 and dmu < 1e-8, f"the nonlinear baseline disagrees: |dx|={dx:.2e}, |dmu|={dmu:.2e}"
    assert len(impacts) == len(orb.events), (impacts, orb.event_labels)
    t_s = median_time(lambda: find_periodic_orbit(flow, guess, tol=1e-10), 20 if quick else 200)
    t_b = median_time(lambda: base.shoot(guess, tol=1e-10), 3 if quick else 15)
    traj = flow.run(orb.state0, 0.0, T, p, variational=True)
    return {
        "orbit_nonlinear_ms": t_s * 1e3,
        "orbit_nonlinear_scipy_ms": t_b * 1e3,
        "orbit_nonlinear_ratio_vs_scipy": t_b / t_s,
        "orbit_nonlinear_agreement": max(dx, dmu),
        "orbit_nonlinear_steps_per_period": traj.n_steps,
        "orbit_nonlinear_newton_iterations": orb.iterations,
    }


def bench_lyapunov(quick: bool) -> dict:
    """Lyapunov exponents of the trilinear system over 1,000 forcing periods at w = 1.2 (contact every period),
    reorthonormalised every period; and the time of the same periods without the variational equation."""
    from saltation.orbits.lyapunov import lyapunov_exponents

    flow = Flow(trilinear())
    w = 1.2
    T = 2 * math.pi / w
    p = flow.parameters({"omega": w})
    start = flow.run([0.1, 0.0], 0.0, 100 * T, p).x1
    lyapunov_exponents(flow, start, parameters=p, time=10 * T)

    def once():
        return lyapunov_exponents(flow, start, parameters=p, time=1000 * T)

    t_s, result = timed_runs(once, quick)
    plain = min(_time_of(lambda: flow.run(start, 0.0, 1000 * T, p)) for _ in range(3))
    # a Lyapunov map of the impact oscillator's route to chaos (omega, r), 100 x 100 cells on this machine's
    # cores, 200 transient periods and 64 sampled per cell (--quick: 25 x 25, scaled by 16)
    from saltation.sweeps import period_map
    from saltation.models import impact_oscillator

    size = 25 if quick else 100
    t = time.perf_counter()
    pm = period_map(impact_oscillator(s=1.0), "omega", np.linspace(2.0, 3.0, size), "r", np.linspace(0.5, 0.9, size),
                    lyapunov=True)
    map_s = (time.perf_counter() - t) * (100 / size) ** 2
    return {"lyapunov_1000_periods_ms": 1e3 * t_s, "lyapunov_plain_run_ms": 1e3 * plain,
            "lyapunov_exponents": [float(e) for e in result.exponents],
            "lyapunov_map_100x100_s": map_s, "lyapunov_map_estimated": size < 100,
            "lyapunov_map_cells_without_period": int(np.sum(pm.periods == 0))}


def _time_of(fn) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


BENCHMARKS = {
    "nonlinear": bench_nonlinear,
    "loci": bench_loci,
    "orbit": bench_orbit,
    "fig3": bench_fig3,
    "fig7": bench_fig7,
    "paper": bench_paper,
    "multipliers": bench_multipliers,
    "events": bench_events,
    "chain": bench_chain,
    "sweep": bench_sweep,
    "lyapunov": bench_lyapunov,
}


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def machine() -> dict:
    import numba
    import scipy

    return {
        "cores": _cores(),
        "cpu": _cpu_name(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "load_average_at_start": os.getloadavg()[0] if hasattr(os, "getloadavg") else None,
    }


def _cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def table(results: dict) -> str:
    def fmt(v):
        if isinstance(v, bool) or v is None:
            return str(v)
        if isinstance(v, float):
            return f"{v:.3g}"
        return str(v)

    def met(key, v):
        if key not in TARGETS or not isinstance(v, (int, float)):
            return ""
        goal = TARGETS[key]
        ok = v >= goal if key.endswith("ratio_vs_scipy") else v <= goal
        sign = ">=" if key.endswith("ratio_vs_scipy") else "<="
        return f"target {sign} {goal:g}: {'met' if ok else 'MISSED'}"

    rows = [
        ("one orbit, omega=1.0 (ms)", "orbit_ms", "orbit_scipy_ms", "orbit_ratio_vs_scipy"),
        ("one orbit, omega=0.7 (ms)", "orbit_no_contact_ms", "orbit_no_contact_scipy_ms",
         "orbit_no_contact_ratio_vs_scipy"),
        ("  omega=1.0: its matrix exponentials alone (ms)", "orbit_limit_ms", None, None),
        ("  omega=1.0: orbit / its exponentials", "orbit_over_limit", None, None),
        ("  omega=1.0: one period map (ms)", "orbit_period_map_ms", None, None),
        ("  one call of the engine, no step (ms)", "orbit_call_overhead_ms", None, None),
        ("one orbit, Duffing impact (ms)", "orbit_nonlinear_ms", "orbit_nonlinear_scipy_ms",
         "orbit_nonlinear_ratio_vs_scipy"),
        ("Fig. 3 diagram (s)", "fig3_s", "fig3_scipy_s", "fig3_ratio_vs_scipy"),
        ("  the first in a process (s)", "fig3_first_s", None, None),
        ("Fig. 7 diagram (s)", "fig7_s", None, None),
        ("  the first in a process (s)", "fig7_first_s", None, None),
        ("paper, empty cache (s)", "paper_cold_s", None, None),
        ("paper, warm cache (s)", "paper_warm_s", None, None),
        ("multiplier error", "multiplier_error", "multiplier_error_scipy", None),
        ("event time error, rtol 1e-10", "event_time_error", None, None),
        ("event time error, rtol 1e-13", "event_time_error_tight", None, None),
        ("event location error (exact flow)", "event_location_error", None, None),
        ("chain growth exponent, orbit (n>=4)", "chain_exponent", None, None),
        ("chain growth exponent, period map", "chain_exponent_period_map", None, None),
        ("sweep 161 x 200 periods (s)", "sweep_s", "sweep_scipy_s", "sweep_ratio_vs_scipy"),
        ("sweep, one worker (s)", "sweep_1_worker_s", None, None),
        ("one period map with monodromy (ms)", "period_map_ms", None, None),
        ("grazing located (in period maps)", "grazing_location_in_period_maps", None, None),
        ("crossing-sliding located (in period maps)", "crossing_sliding_location_in_period_maps", None, None),
        ("adding-sliding located (in period maps)", "adding_sliding_location_in_period_maps", None, None),
        ("corner curve, 200 points (s)", "corner_curve_s_per_200_points", None, None),
        ("fold curve, 200 points (s)", "fold_curve_s_per_200_points", None, None),
        ("sliding curve, 200 points (s)", "sliding_curve_s_per_200_points", None, None),
        ("Lyapunov exponents, 1000 periods (ms)", "lyapunov_1000_periods_ms", None, None),
        ("  the same periods, no variational equation (ms)", "lyapunov_plain_run_ms", None, None),
        ("Lyapunov map, 100 x 100 cells (s)", "lyapunov_map_100x100_s", None, None),
    ]
    lines = [f"{'benchmark':42s} {'saltation':>11s} {'scipy':>11s} {'ratio':>8s}  target"]
    for label, k, kb, kr in rows:
        if k not in results:
            continue
        est = " est." if (kb and kb.endswith("_s") and results.get(kb[:-2] + "_estimated", False)) else ""
        b = fmt(results[kb]) + est if kb and kb in results else "-"
        r = fmt(results[kr]) if kr and kr in results else "-"
        target = met(k, results[k])
        if kr and kr in results and kr in TARGETS:
            target += ("; " if target else "") + met(kr, results[kr])
        lines.append(f"{label:42s} {fmt(results[k]):>11s} {b:>11s} {r:>8s}  {target}")
    if "chain" in results:
        lines.append("")
        lines.append(f"{'chain n':>8s} {'orbit ms':>10s} {'period map ms':>14s} {'Newton':>7s} {'events':>7s}")
        for r in results["chain"]:
            lines.append(f"{r['n']:8d} {r['orbit_ms']:10.3g} {r['period_map_ms']:14.3g} "
                         f"{r['newton_iterations']:7d} {r['events']:7d}")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats, scaled baselines, no paper runs (under a minute)")
    ap.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    ap.add_argument("--only", nargs="+", choices=sorted(BENCHMARKS), help="run only these benchmarks")
    args = ap.parse_args(argv)
    results: dict = {"quick": args.quick, "machine": machine()}
    t_all = time.perf_counter()
    for name, fn in BENCHMARKS.items():
        if args.only and name not in args.only:
            continue
        log(f"{name} ...")
        t = time.perf_counter()
        results |= fn(args.quick)
        log(f"{name}: {time.perf_counter() - t:.1f} s")
    results["machine"]["load_average_at_end"] = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    results["total_s"] = time.perf_counter() - t_all
    results["targets"] = TARGETS
    if args.json:
        print(json.dumps(results, default=float))
    else:
        print(table(results))
        m = results["machine"]
        print(f"\n{m['cores']} cores, {m['cpu']}; Python {m['python']}, numba {m['numba']}, scipy {m['scipy']}; "
              f"load average {m['load_average_at_start']:.2f} at start, {m['load_average_at_end']:.2f} at end; "
              f"{results['total_s']:.0f} s in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
