"""``saltation continue``: one branch of periodic orbits (or equilibria) over a parameter, the branches born
on it and the one beyond a discontinuous fold (:func:`saltation.special_points.follow.follow_branch`),
written as CSV, JSON and a diagram."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import saltation.apps.cli.models as models  # noqa: PLR0402 (one place to replace it; importing the package would be a cycle)
from saltation.apps.cli.errors import UsageError
from saltation.apps.cli.models import build_model
from saltation.apps.cli.options import (
    add_measure,
    add_mode0,
    add_model,
    add_monitor,
    add_no_progress,
    add_out,
    add_period,
    add_segments,
    add_set,
    add_step_options,
    add_x0,
    check_equilibrium_option,
    check_mode0,
    check_not_set,
    check_out_dir,
    check_parameter,
    check_start_period,
    finite,
    forcing_period_at,
    parse_measure_options,
    parse_monitor_options,
    parse_sets,
    parse_start,
    step_settings,
    usable_parameters,
)
from saltation.apps.cli.starts import branch_start
from saltation.apps.cli.text import (
    fmt,
    paragraph,
    point_counter,
    progress_bar,
    special_points_text,
)


def cmd_continue(args: argparse.Namespace) -> int:
    """``saltation continue``: follow one branch of a shipped model and write its data and plot."""
    from saltation.kinds import SpecialPointKind
    from saltation.special_points.follow import SWITCHES, follow_branch

    system, overrides, settings = _checked(args)
    start, stop = float(args.start), float(args.stop)
    flow = models.make_flow(system)
    p = flow.parameters(overrides)
    x0 = parse_start(args, flow, p)
    update, close = progress_bar(not args.no_progress)
    counter = point_counter(update, f"{args.model}: {args.param}")
    try:
        problem, u0 = branch_start(args, flow, overrides, p, x0, start)
        switch_at = (*SWITCHES, SpecialPointKind.PERIOD_DOUBLING) if args.period_doubled else SWITCHES
        followed = follow_branch(problem, u0, start, settings=settings, direction=1 if stop > start else -1,
                                 progress=counter, switch_at=switch_at)
    finally:
        close()
    _write(args, system, followed.branches, _end_note(followed, args.param))
    return 0


def _checked(args: argparse.Namespace):
    """The model, its parameter values at ``--from`` and the continuation settings, every option checked
    (and ``--out`` created) before any computation."""
    system = build_model(args.model)
    check_parameter(system, args.param, "--param")
    overrides = parse_sets(args.set, system)
    check_not_set(overrides, args.param, "--param")
    start, stop = float(args.start), float(args.stop)
    if start == stop:
        raise UsageError(f"--from and --to must differ, got {fmt(start)} twice")
    settings = replace(step_settings(args, (start, stop)),
                       measures=tuple(m.text for m in parse_measure_options(args, system)),
                       monitors=parse_monitor_options(args, system))
    if args.equilibrium is not None:
        check_equilibrium_option(args, system)
    if args.period_doubled and args.segments != 1:
        raise UsageError(f"--period-doubled follows the period-2 branches by single shooting: drop --segments "
                         f"{args.segments}")
    check_mode0(args, system)
    overrides[args.param] = start
    for flag, value in (("--to", stop), ("--from", start)):
        p0 = usable_parameters(system, overrides | {args.param: value}, f"{flag} {fmt(value)}")
        if not system.is_autonomous:
            forcing_period_at(system, p0, f"{flag} {fmt(value)}")
    check_start_period(args, system, p0, f"--from {fmt(start)}")
    check_out_dir(args.out)
    return system, overrides, settings


def _end_note(followed, parameter: str) -> str:
    """A line on how the branch ended, where its stop reason does not say it all ("" otherwise)."""
    from saltation.special_points.follow import BranchEnd

    if followed.end is BranchEnd.ON_SURFACE:
        sp = followed.ended_at
        return (f"the branch ended at a {sp.kind.value} at {parameter} = {sp.parameter:.10g}, where its "
                f"orbit lies on {sp.touch_surface} all round")
    if followed.end is BranchEnd.DISCONTINUOUS_FOLD:
        return "the branch ended at a discontinuous fold; its continuation was followed in backward time"
    if followed.end is BranchEnd.CORRECTOR_FAILED:
        return f"the branch ended where the corrector failed ({followed.error})"
    return ""


def _write(args: argparse.Namespace, system, branches: list, note: str) -> None:
    """Write the branches, their special points and the diagram into ``--out``, and say what was found."""
    from saltation.output import io, plotting
    from saltation.special_points.follow import distinct_special_points

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"{system.name}_{args.param}"
    for k, br in enumerate(branches):
        suffix = "" if k == 0 else f"_{k}"
        io.save_branch_json(br, out / f"{stem}_branch{suffix}.json")
        io.save_branch_csv(br, out / f"{stem}_branch{suffix}.csv")
    records = [io.special_point_record(sp, system.name, args.param) for sp in distinct_special_points(branches)]
    io.save_special_points_json(records, out / f"{stem}_special_points.json")
    measure = args.measure[0] if args.measure else "amplitude"
    plotting.save_figure(plotting.plot_response(branches, measure=measure), out / f"{stem}_diagram")
    total = sum(len(b) for b in branches)
    reasons = "; ".join(b.stop_reason.value for b in branches if b.stop_reason is not None)
    print(f"{total} point{'s' if total != 1 else ''} on {len(branches)} branch{'es' if len(branches) != 1 else ''} of "
          f"{system.name} over {args.param}; stopped: {reasons}")
    if note:
        print(note)
    print(special_points_text(records))
    print(f"written to {out}/{stem}_*")


def add_parser(sub) -> None:
    """The parser of ``saltation continue``."""
    p = sub.add_parser(
        "continue",
        help="follow a branch of periodic orbits (or equilibria) over a parameter; write CSV/JSON and a plot",
        description=paragraph(
            """Follow one branch of periodic orbits of a shipped model by pseudo-arclength continuation
            in one parameter, from --from towards --to, through the corners of the branch, locating
            smooth and discontinuous bifurcations (set-valued Floquet multipliers). A forward-time
            branch that ends at a discontinuous fold is followed beyond it by backward-time shooting.
            Writes MODEL_PARAM_branch.json/.csv, MODEL_PARAM_special_points.json and a diagram
            (PNG and PDF) into --out."""
        ),
    )
    add_model(p)
    p.add_argument("--param", metavar="NAME", required=True, help="the continuation parameter")
    p.add_argument("--from", dest="start", metavar="V", type=finite, required=True, help="start value of the parameter")
    p.add_argument("--to", dest="stop", metavar="V", type=finite, required=True, help="end value of the parameter")
    add_set(p, "override another parameter of the model (repeat for several)")
    add_x0(p)
    add_period(p)
    p.add_argument("--backward", action="store_true", help="shoot in backward time (infinitely unstable branches)")
    add_mode0(p, "; every point of the branch starts in it")
    p.add_argument("--equilibrium", metavar="MODE", help="continue an equilibrium of this mode instead of periodic orbits "
                   "(autonomous models); sliding:SURFACE continues the pseudo-equilibria of the sliding motion on "
                   "that surface")
    p.add_argument("--period-doubled", action="store_true",
                   help="also follow the branch of period-2 orbits born at each period doubling (forced models: "
                   "over two forcing periods; autonomous ones: the doubled period an unknown)")
    add_out(p)
    add_step_options(p)
    add_segments(p, "; the branch's multipliers come from the segments' matrices (periodic Schur decomposition)")
    add_measure(p, "; every point records them (the branch files' measures) and the diagram plots the first")
    add_monitor(p)
    add_no_progress(p)
    p.set_defaults(handler=cmd_continue)
