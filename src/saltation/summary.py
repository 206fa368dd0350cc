"""Short Markdown summaries of the objects a user meets, for Jupyter and for printing.

:class:`~saltation.model.system.PiecewiseSystem`, :class:`~saltation.orbits.shooting.PeriodicOrbit`,
:class:`~saltation.branches.branch.Branch` and :class:`~saltation.branches.branch.SpecialPoint` show
these in a notebook (their ``_repr_markdown_``); ``summary(obj)`` gives the same
text anywhere.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np


def _number(x: float, digits: int = 10) -> str:
    return "nan" if x is None or not np.isfinite(x) else f"{x:.{digits}g}"


def _multipliers(mu: np.ndarray | None) -> str:
    if mu is None:
        return "-"
    parts = []
    for z in np.asarray(mu).ravel():
        if not np.isfinite(z):
            parts.append("inf")
        elif abs(z.imag) > 1e-12 * max(1.0, abs(z)):
            parts.append(f"{z.real:.6g}{z.imag:+.6g}j (modulus {abs(z):.6g})")
        else:
            parts.append(f"{z.real:.6g}")
    return ", ".join(parts)


def _table(rows: Iterable[tuple[str, str]]) -> str:
    lines = ["| | |", "|---|---|"]
    lines += [f"| {key} | {value.replace('|', '/')} |" for key, value in rows]
    return "\n".join(lines)


def _sequence(events: Sequence[str]) -> str:
    return " -> ".join(events) if events else "(none)"


def system_summary(system) -> str:
    """A model: states, parameters with their values, modes with their fields, transitions."""
    forced = "autonomous" if system.is_autonomous else f"forced, period `{system.period_expr}`"
    rows = [
        ("states", ", ".join(system.state_names)),
        ("parameters", ", ".join(f"{k} = {v:g}" for k, v in system.defaults.items()) or "(none)"),
        ("time", forced),
    ]
    fields = getattr(system, "fields", None)
    for m, name in enumerate(system.mode_names):
        rows.append((f"mode `{name}`", ", ".join(f"`{f}`" for f in fields[m]) if fields is not None else "(compiled)"))
    indicators = getattr(system, "indicators", None)
    for s, name in enumerate(system.surface_names):
        rows.append((f"surface `{name}`", f"`{indicators[s]}` = 0" if indicators is not None else "(compiled)"))
    for k, tr in enumerate(system.transitions):
        reset = " with a reset" if system.resets[k] is not None else ""
        rows.append((f"transition {k}", f"{tr.source} -> {tr.target} on {tr.surface} ({tr.direction.name.lower()}){reset}"))
    symmetry = getattr(system, "symmetry", None)
    if symmetry is not None:
        pairs = sorted({tuple(sorted((system.mode_names[i], system.mode_names[k])))
                        for i, k in enumerate(system.symmetry_map.modes)})
        modes = ", ".join(f"{a} <-> {b}" if a != b else a for a, b in pairs)
        rows.append(("symmetry", f"x -> S x, t -> t + T/2, S = {[list(r) for r in symmetry.matrix]} (modes: {modes})"))
    return f"**{system.name}** (piecewise-smooth model)\n\n" + _table(rows)


def orbit_summary(orbit) -> str:
    """A periodic orbit: period, amplitude, multipliers and stability, events, convergence."""
    direction = "backward-time shooting" if orbit.backward else "forward-time shooting"
    stable = "stable" if orbit.stable else "unstable"
    rows = [
        ("period", _number(orbit.period)),
        ("amplitude max abs(x1)", _number(orbit.amplitude, 8)),
        ("multipliers", f"{_multipliers(orbit.multipliers)} ({stable})"),
        ("events per period", _sequence(orbit.event_labels)),
        ("initial state", ", ".join(f"{v:.10g}" for v in orbit.state0)),
        ("Newton", (f"{'converged' if orbit.converged else 'not converged'} in {orbit.iterations} iterations, "
                    f"residual {orbit.residual_norm:.2e}")),
    ]
    return f"**periodic orbit** of {orbit.system_name} ({direction})\n\n" + _table(rows)


def special_point_summary(point) -> str:
    """A special point: kind, where (and how well it is located), multipliers (one-sided at a corner)."""
    rows = [
        ("parameter", f"{_number(point.parameter, 12)} (located to {point.accuracy:.1e})"),
        ("amplitude", _number(point.amplitude, 8)),
    ]
    if point.multipliers is not None:
        rows.append(("multipliers", _multipliers(point.multipliers)))
    if point.multipliers_minus is not None or point.multipliers_plus is not None:
        rows.append(("multipliers, one side", _multipliers(point.multipliers_minus)))
        rows.append(("multipliers, other side", _multipliers(point.multipliers_plus)))
        if point.limits:
            rows.append(("one-sided multipliers", point.limits.value + (f" (growing like d^{point.growth_exponents})" if point.growth_exponents else "")))
    if np.isfinite(point.multipliers_accuracy):
        rows.append(("multipliers known to", f"{point.multipliers_accuracy:.1e}"))
    if point.crossing_q is not None:
        rows.append(("unit circle crossed at", f"q = {point.crossing_q:.8g} (multiplier {point.crossing_point:.6g})"))
    if point.event_labels_minus or point.event_labels_plus:
        rows.append(("events, one side", _sequence(point.event_labels_minus)))
        rows.append(("events, other side", _sequence(point.event_labels_plus)))
    if point.scenario is not None:
        rows.append(("border collision (Feigin)", scenario_text(point)))
    if getattr(point, "criticality", None) is not None:
        coefficient, accuracy = point.normal_form
        rows.append(("criticality", f"{point.criticality.value} (cubic coefficient {coefficient:.6g} +- {accuracy:.1g})"))
    if point.sensitivities:
        rows.append(("sensitivities", ", ".join(f"d/d{name} {value:.6g}" for name, value in point.sensitivities.items())))
    if point.touch_surface:
        rows.append(("touches", f"surface {point.touch_surface} (field of {point.touch_mode}) at t = {point.touch_time:.8g}"))
    if point.note:
        rows.append(("note", point.note))
    return f"**{point.kind.value}**\n\n" + _table(rows)


def scenario_text(point) -> str:
    """What Feigin's classification predicts at a non-smooth point, in words: ``persistence``,
    ``nonsmooth_fold``, either with ``, period two`` where a period-two orbit is born, or ``undetermined``
    (``-`` where it was not asked)."""
    scenario = point.scenario
    if scenario is None:
        return "-"
    return scenario.value + (", period two" if point.period_two else "")


def stop_text(branch) -> str:
    """Why a branch's runs stopped, in words, each reason once: "reached a parameter bound" for both
    directions, "reached a parameter bound; the corrector failed" for two different ones (in run order)."""
    reasons = [str(r.value if hasattr(r, "value") else r) for r in [branch.stop_reason, *branch.stop_reasons] if r is not None]
    unique = list(dict.fromkeys(reasons))
    if len(unique) == 1 and len(reasons) > 1:
        return f"{unique[0]} (both directions)" if len(reasons) == 2 else f"{unique[0]} (every run)"
    return "; ".join(unique)


def branch_summary(branch) -> str:
    """A branch: its range, stability, how it ended, and its special points."""
    lam = branch.parameter
    stable = int(np.count_nonzero(branch.stable)) if len(branch) else 0
    rows = [
        ("parameter", f"{branch.parameter_name} from {_number(lam[0], 8)} to {_number(lam[-1], 8)}" if len(branch) else "-"),
        ("points", f"{len(branch)} ({stable} stable)"),
        ("shooting", "backward time" if branch.backward else "forward time"),
        ("stopped", stop_text(branch) or "-"),
    ]
    if getattr(branch, "stop_detail", ""):
        rows.append(("failure", branch.stop_detail))
    text = f"**{branch.label or branch.kind.value} branch** of {branch.model}\n\n" + _table(rows)
    if branch.special_points:
        text += "\n\n| special point | " + branch.parameter_name + " | located to |\n|---|---|---|\n"
        text += "\n".join(f"| {sp.kind.value} | {sp.parameter:.10g} | {sp.accuracy:.1e} |" for sp in branch.special_points)
    return text


def summary(obj) -> str:
    """The Markdown summary of a model, periodic orbit, branch or special point (this module imports
    none of their modules: they import it)."""
    if hasattr(obj, "monodromy") and hasattr(obj, "state0"):
        return orbit_summary(obj)
    if hasattr(obj, "points") and hasattr(obj, "special_points"):
        return branch_summary(obj)
    if hasattr(obj, "bracket") and hasattr(obj, "kind"):
        return special_point_summary(obj)
    if hasattr(obj, "mode_names") and hasattr(obj, "transitions"):
        return system_summary(obj)
    raise TypeError(f"no summary for {type(obj).__name__}")
