"""``saltation orbit``: one periodic orbit of a model, found by shooting, as a table or JSON."""

from __future__ import annotations

import argparse
import json
import math
from typing import TYPE_CHECKING

import saltation.apps.cli.models as models  # noqa: PLR0402 (one place to replace it; importing the package would be a cycle)
from saltation.apps.cli.errors import PROG
from saltation.apps.cli.models import build_model
from saltation.apps.cli.options import (
    MIN_PERIOD,
    add_json,
    add_measure,
    add_mode0,
    add_model,
    add_period,
    add_segments,
    add_set,
    add_x0,
    check_forced_period,
    check_mode0,
    check_period,
    check_start_field,
    finite,
    forcing_period_at,
    parse_measure_options,
    parse_sets,
    parse_vector,
)
from saltation.apps.cli.starts import estimate_period, transient
from saltation.apps.cli.text import complex_text, fmt, paragraph

if TYPE_CHECKING:
    from saltation.model.system import PiecewiseSystem


def format_orbit(orbit, system: PiecewiseSystem) -> str:
    """A short human-readable table of an orbit."""
    import numpy as np

    from saltation.engine.flow import EventKind

    kind = "autonomous" if system.is_autonomous else f"forced, forcing period {system.period_expr}"
    rows: list[tuple[str, str]] = []
    rows.append(("model", f"{system.name} ({kind})"))
    rows.append(("parameters", ", ".join(f"{k} = {fmt(v)}" for k, v in zip(system.parameter_names, orbit.parameters))))
    rows.append(("time", "backward (shooting in backward time)" if orbit.backward else "forward"))
    rows.append(("state0", ", ".join(f"{k} = {fmt(v)}" for k, v in zip(system.state_names, orbit.state0))
                 + f"   at t0 = {fmt(orbit.t0)}" + (f", in mode {orbit.mode0}" if orbit.mode0 is not None else "")))
    rows.append(("period", fmt(orbit.period)))
    rows.append(("amplitude", f"{fmt(orbit.amplitude)}   (max |{system.state_names[0]}| over the period)"))
    mu = np.asarray(orbit.multipliers, dtype=complex)
    texts = [complex_text(m) for m in mu]
    width = max(len(s) for s in texts) if texts else 0
    for i, (m, s) in enumerate(zip(mu, texts)):
        mag = "inf" if not np.isfinite(m) else fmt(abs(m))
        rows.append(("multipliers" if i == 0 else "", f"{s:<{width}}   |mu| = {mag}"))
    if orbit.stable:
        stab = "stable"
    elif not np.all(np.isfinite(mu)):
        stab = "infinitely unstable (an infinite multiplier)"
    else:
        stab = "unstable"
    if system.is_autonomous:
        stab += f"; trivial multiplier 1 excluded (its error {orbit.trivial_multiplier_error:.1e})"
    rows.append(("stability", stab))
    events = orbit.trajectory.events
    if not events:
        rows.append(("events", "none"))
    for i, e in enumerate(events):
        what = {EventKind.SLIDING_START: "  sliding starts", EventKind.SLIDING_END: "  sliding ends"}.get(e.kind, "")
        rows.append(("events" if i == 0 else "", f"{e.surface:<12} t = {fmt(e.t):<16} {e.mode_from} -> {e.mode_to}{what}"))
    its = orbit.iterations
    rows.append(("Newton", f"converged in {its} iteration{'s' if its != 1 else ''}, residual {orbit.residual_norm:.1e}"))
    return "\n".join(f"{k:<12} {v}".rstrip() for k, v in rows)


def cmd_orbit(args: argparse.Namespace) -> int:
    """``saltation orbit``: find one periodic orbit of a shipped model and print it."""
    from saltation.orbits.start import find_periodic_orbit

    system = build_model(args.model)
    overrides = parse_sets(args.set, system)
    measures = parse_measure_options(args, system)
    x0 = parse_vector(args.x0, system) if args.x0 is not None else None
    mode0 = check_mode0(args, system)
    period = args.period
    if system.is_autonomous:
        t0 = 0.0  # an autonomous field does not depend on time: the orbit is the same from any t0
        check_period(period, t0)
    else:
        where = "the parameters of --set" if overrides else "the default parameters"
        # the orbit at t0 is the orbit at t0 modulo the forcing period (where times keep their digits)
        t0 = math.fmod(args.t0, forcing_period_at(system, system.parameter_vector(overrides), where))
        check_forced_period(system, period, system.parameter_vector(overrides), where)
        period = None  # shooting takes the forcing period
    flow = models.make_flow(system)
    p = flow.parameters(overrides)
    if x0 is not None:
        check_start_field(flow, x0, p, args.x0, t0, mode0)
    if x0 is None or (system.is_autonomous and period is None):
        traj, _ = transient(flow, args.model, p, x0, t0=t0, backward=args.backward, mode0=mode0)
        if x0 is None:  # the guess is the transient's end, in the mode it ends in
            x0, mode0 = traj.x1.copy(), None if mode0 is None else traj.mode1
        if system.is_autonomous and period is None:
            period = estimate_period(traj)
    orbit = find_periodic_orbit(
        flow, x0, parameters=overrides, period=period, backward=args.backward, t0=t0, segments=args.segments,
        mode0=mode0,
    )
    values = {}
    if measures:
        from saltation.orbits.measures import measure_orbit

        values = measure_orbit(flow, orbit.state0, orbit.period, p, measures, t0=orbit.t0, mode0=orbit.mode0,
                               backward=args.backward)
    if args.json:
        from saltation.output.codecs import orbit_to_dict

        print(json.dumps(orbit_to_dict(orbit, system) | ({"measures": values} if measures else {})))
    else:
        print(format_orbit(orbit, system))
        for m in measures:
            print(f"{'measure':<12} {m.label} = {fmt(values[m.text])}")
    return 0


def orbit_epilog() -> str:
    """The epilog of ``saltation orbit --help``: the shipped models, the start, the output, the exit status."""
    from saltation.models import SHIPPED
    from saltation.orbits.start import TRANSIENT_PERIODS

    parts = ["shipped models (states; parameters with their default values):"]
    for name, shipped in SHIPPED.items():
        system = shipped.factory()
        kind = "autonomous" if system.is_autonomous else f"forced, period {system.period_expr}"
        parts.append(paragraph(f"{name}: {shipped.summary}; {kind}", "  "))
        parts.append(paragraph(
            f"states {', '.join(system.state_names)}; "
            + " ".join(f"{k}={fmt(v)}" for k, v in system.defaults.items()), "    "))
    parts += [
        "",
        paragraph(
            f"""Without --x0, a transient is simulated from a default state ({TRANSIENT_PERIODS} forcing
            periods for forced models, about 50 oscillation periods for autonomous ones) in the
            direction of integration (with --backward it runs backward, and so approaches orbits
            that attract in backward time, such as infinitely unstable ones), and shooting starts
            from its end state. For autonomous models without --period, the period guess is the
            time between two repetitions of the transient's event sequence, or between crossings
            of the Poincare section x_1 = mid-range when it has no events."""
        ),
        "",
        paragraph(
            """Output: state0, period, amplitude (max |x_1| over the period), the Floquet
            multipliers in forward time (an infinite one, of an infinitely unstable orbit, is
            'inf') with their magnitudes, stability, and the switching events (surface, time) of
            one period. --json prints one JSON object with the keys model, parameters,
            state_names, state0, t0, period, autonomous, backward, amplitude, half_peak_to_peak,
            multipliers ([re, im] pairs, or "inf"), multiplier_magnitudes, stable, events
            ([surface, time] pairs), event_modes, converged, iterations, residual_norm, segments, mode0
            (the mode at state0)."""
        ),
        "",
        paragraph(
            """Exit status: 0 when an orbit is found, 1 when the computation fails (e.g. Newton does
            not converge), 2 for bad usage; errors are one line on stderr."""
        ),
        "",
        "examples:",
        f"  {PROG} orbit trilinear --set omega=1.2 --x0 0.5,0.5",
        f"  {PROG} orbit trilinear --set omega=0.7 --json",
        f"  {PROG} orbit block_on_belt",
        f"  {PROG} orbit block_on_belt --backward --x0 1.0,-0.95 --period 6.3",
    ]
    return "\n".join(parts)


def add_parser(sub) -> None:
    """The parser of ``saltation orbit``."""
    p = sub.add_parser(
        "orbit",
        help="find one periodic orbit of a shipped model and print it",
        description=paragraph(
            """Find one periodic orbit of a shipped model by shooting (Newton on the period map, with
            the monodromy matrix and every saltation matrix as its Jacobian) from a guess, and print
            it with its Floquet multipliers."""
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog_factory=orbit_epilog,
    )
    add_model(p)
    add_set(p, "override a parameter of the model (repeat for several), e.g. --set omega=0.7")
    add_x0(p, "guess of the state at t0, one comma-separated number per state (write --x0=-1,0 or "
           "--x0 -1,0 for a negative first component); default: the end of a transient")
    p.add_argument(
        "--t0", metavar="T", type=finite, default=0.0,
        help="initial time, i.e. the phase of the forcing at state0 (default 0; reduced modulo the forcing period)",
    )
    add_period(p, f"period guess for autonomous models, at least {MIN_PERIOD:g} (default: estimated from a "
               "transient); forced models take the forcing period (a --period must equal it)")
    p.add_argument(
        "--backward", action="store_true",
        help="shoot in backward time: finds orbits that are unstable in forward time, including "
        "infinitely unstable ones (a multiplier 'inf')",
    )
    add_segments(p)
    add_mode0(p)
    add_measure(p, "; printed after the orbit (--json: the key measures, by SPEC)")
    add_json(p, "print one JSON object instead of a table")
    p.set_defaults(handler=cmd_orbit)
