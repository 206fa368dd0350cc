"""``saltation locus``: the special points of one kind of a branch, each continued as a curve in a second
parameter (:func:`saltation.special_points.loci.follow_locus`)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import saltation.apps.cli.models as models  # noqa: PLR0402 (one place to replace it; importing the package would be a cycle)
from saltation.apps.cli.errors import UsageError
from saltation.apps.cli.models import build_model
from saltation.apps.cli.options import (
    add_json,
    add_mode0,
    add_model,
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
    forcing_period_at,
    parse_range,
    parse_sets,
    parse_start,
    step_settings,
)
from saltation.apps.cli.starts import branch_start
from saltation.apps.cli.text import fmt, paragraph, point_counter, progress_bar
from saltation.errors import SaltationError


def cmd_locus(args: argparse.Namespace) -> int:
    """``saltation locus``: continue the special points of one kind of a branch in a second parameter."""
    from saltation.special_points.follow import follow_branch

    kind, system, overrides = _checked(args)
    (start, stop), (lo2, hi2) = args.range, args.range2
    flow = models.make_flow(system)
    p = flow.parameters(overrides)
    value2 = p[system.parameter_index(args.param2)]
    if not lo2 <= value2 <= hi2 and not hi2 <= value2 <= lo2:
        raise UsageError(f"the value of {args.param2} ({value2:g}) lies outside --range2")
    x0 = parse_start(args, flow, p)
    settings = step_settings(args, (start, stop))
    update, close = progress_bar(not args.no_progress)
    try:
        problem, u0 = branch_start(args, flow, overrides, p, x0, start)
        followed = follow_branch(problem, u0, start, settings=settings, direction=1 if stop > start else -1,
                                 progress=point_counter(update, f"{args.model}: {args.param}"), switch=False,
                                 through_fold=False)
        curve_settings = step_settings(args, (lo2, hi2))
        counter2 = point_counter(update, f"{args.model}: {kind.value} over {args.param2}")
        if args.equilibrium is not None:
            from saltation.special_points.boundary_equilibria import (
                follow_boundary_equilibrium_curve,
            )

            loci = [follow_boundary_equilibrium_curve(flow, sp, args.param, args.param2, curve_settings.bounds,
                                                      parameters=overrides, settings=curve_settings, progress=counter2)
                    for sp in followed.boundary_equilibria]
        else:
            loci = _loci(args, system, kind, problem, followed.branch, curve_settings, counter2)
    finally:
        close()
    _report(args, system, kind, loci)
    return 0


def _checked(args: argparse.Namespace):
    """The kind, the model and its parameter values at the start of ``--range``, every option checked (and
    ``--out`` created) before any computation."""
    from saltation.branches.branch import SpecialPointKind

    try:
        kind = SpecialPointKind(args.kind)
    except ValueError:
        raise UsageError(f"unknown kind {args.kind!r}; kinds are {', '.join(k.value for k in SpecialPointKind)}") from None
    system = build_model(args.model)
    for name, flag in ((args.param, "--param"), (args.param2, "--param2")):
        check_parameter(system, name, flag)
    if (kind is SpecialPointKind.BOUNDARY_EQUILIBRIUM) != (args.equilibrium is not None):
        raise UsageError("--kind boundary_equilibrium needs --equilibrium MODE or --equilibrium sliding:SURFACE "
                         "(the branch of equilibria it lies on), and --equilibrium applies to it only")
    if args.equilibrium is not None:
        check_equilibrium_option(args, system)
    check_mode0(args, system)
    if args.param == args.param2:
        raise UsageError("--param and --param2 must differ")
    start, stop = args.range
    overrides = parse_sets(args.set, system)
    check_not_set(overrides, args.param, "--param")
    overrides[args.param] = start
    if not system.is_autonomous:
        for value in (start, stop):
            forcing_period_at(system, system.parameter_vector(overrides | {args.param: value}),
                              f"--range {fmt(start)},{fmt(stop)}")
    check_start_period(args, system, system.parameter_vector(overrides), f"{args.param} = {fmt(start)}")
    if args.out is not None:
        check_out_dir(args.out)
    return kind, system, overrides


def _loci(args: argparse.Namespace, system, kind, problem, branch, settings, progress) -> list:
    """The curve of each special point of ``kind`` on the branch (with ``--segments`` the curves' defining
    systems shoot by segments too).

    Raises
    ------
    SaltationError
        If the branch has no such point and stopped before the end of ``--range``.
    """
    from saltation.special_points.loci import follow_locus

    points = [sp for sp in branch.special_points if sp.kind is kind]
    reason = branch.stop_reason
    if not points and reason is not None and reason.name != "PARAMETER_BOUND":
        found = ", ".join(f"{sp.kind.value} at {sp.parameter:.8g}" for sp in branch.special_points) or "none"
        detail = f" ({branch.stop_detail})" if branch.stop_detail else ""
        raise SaltationError(
            f"no {kind.value} point on the branch of {system.name}: it stopped at {args.param} = "
            f"{branch.points[-1].parameter:.10g} before the end of --range ({reason.value}{detail}); "
            f"special points found: {found}. Try a larger --max-points, another --ds-max or --range")
    return [follow_locus(problem, sp, args.param2, settings.bounds, settings=settings, progress=progress)
            for sp in points]


def _report(args: argparse.Namespace, system, kind, loci: list) -> None:
    """Write the curves into ``--out`` (JSON and a plot) and print them (``--json``: one JSON object)."""
    from saltation.output import plotting
    from saltation.output.codecs import locus_record
    from saltation.output.io import write_json

    record = {
        "model": system.name, "kind": kind.value, "param": args.param, "param2": args.param2,
        "curves": [locus_record(locus) for locus in loci],
    }
    if args.out is not None:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        stem = out / f"{system.name}_{kind.value}_{args.param}_{args.param2}_locus"
        write_json(record, stem.with_suffix(".json"))
        plotting.save_figure(plotting.plot_loci(loci, title=f"{system.name}: {kind.value}"), stem)
    if args.json:
        print(json.dumps(record))
        return
    print(f"{len(loci)} curve(s) of {kind.value} points of {system.name} in ({args.param}, {args.param2})")
    for k, locus in enumerate(loci):
        print(f"  curve {k}: {len(locus.points)} points; {locus.stop_detail}")
        for c in locus.special_points:
            name = f"{c.codimension_two.value}: " if c.codimension_two is not None else ""
            print(f"    {name}{c.sides[0]} -> {c.sides[1]} at {args.param} = {c.parameter:.8g}, {args.param2} = "
                  f"{c.second_parameter:.8g} (within {c.accuracy:.2g}, {c.status.value})")
    if args.out is not None:
        print(f"written to {stem}.json (.png, .pdf)")


def add_parser(sub) -> None:
    """The parser of ``saltation locus``."""
    p = sub.add_parser(
        "locus",
        help="continue the special points of one kind of a branch in a second parameter (two-parameter curves)",
        description=paragraph(
            """Follow the branch of periodic orbits of MODEL from the start state over --param in --range
            (as 'continue' does), take every special point of kind --kind on it, and continue each as a
            curve in (--param, --param2) with --param2 in --range2, in both directions, by its defining
            system: grazing and corner collisions by periodicity plus tangency, folds and period
            doublings by periodicity plus a bordered test function, Neimark-Sacker points by periodicity
            plus two entries of the bordered M^2 - 2 kappa M + I. Where the kind of a corner changes
            along its curve, or a fold, period-doubling or Neimark-Sacker curve meets a second condition
            (cusp, strong resonances, fold-flip ...: a codimension-two point, its "name"), the curve
            records it. With --kind
            boundary_equilibrium and --equilibrium MODE (or sliding:SURFACE) the branch is of equilibria, and
            each boundary equilibrium is continued by the mode's equilibrium plus h = 0. --json prints
            {"model", "kind", "param", "param2", "curves": [{"points": [[value of param, value of
            param2], ...], "stop_reason", "special_points"}]}; --out writes the same and a plot."""
        ),
    )
    add_model(p)
    p.add_argument("--kind", metavar="KIND", required=True,
                   help="a SpecialPointKind value: fold, period_doubling, neimark_sacker, grazing, discontinuous_fold, nonsmooth_no_crossing, ...")
    p.add_argument("--param", metavar="NAME", required=True, help="the parameter of the branch")
    p.add_argument("--range", metavar="A,B", type=parse_range("--range"), required=True, help="the branch from A towards B")
    p.add_argument("--param2", metavar="NAME2", required=True, help="the second parameter")
    p.add_argument("--range2", metavar="C,D", type=parse_range("--range2"), required=True, help="the range of the second parameter")
    add_set(p, "override a parameter (repeat for several)")
    add_x0(p)
    add_period(p)
    p.add_argument("--backward", action="store_true", help="shoot in backward time")
    add_mode0(p)
    add_out(p, "write the curves (JSON) and their plot here", default=None)
    add_json(p, "print one JSON object")
    add_segments(p, " (for the branch; the curves' defining systems use single shooting)")
    p.add_argument("--equilibrium", metavar="MODE",
                   help="with --kind boundary_equilibrium: the branch is of this mode's equilibria (or, as "
                   "sliding:SURFACE, of the pseudo-equilibria on that surface), and its boundary equilibria are "
                   "continued by the mode's equilibrium plus h = 0")
    add_step_options(p, " of the branch and of each curve")
    add_no_progress(p)
    p.set_defaults(handler=cmd_locus)
