"""``saltation sweep``: a brute-force diagram, or with ``--param2`` a map of the attractor's period, on
local processes or a Dask cluster (:mod:`saltation.sweeps`)."""

from __future__ import annotations

import argparse
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import saltation.apps.cli.models as models  # noqa: PLR0402 (one place to replace it; importing the package would be a cycle)
from saltation.apps.cli.errors import UsageError
from saltation.apps.cli.models import build_model
from saltation.apps.cli.options import (
    add_mode0,
    add_model,
    add_out,
    add_set,
    add_x0,
    check_grid,
    check_mode0,
    check_not_set,
    check_out_dir,
    check_parameter,
    check_start_field,
    finite,
    forcing_period_at,
    integer,
    parse_sets,
    parse_vector,
)
from saltation.apps.cli.text import fmt, paragraph

if TYPE_CHECKING:
    import numpy as np

    from saltation.model.system import PiecewiseSystem


def sweep_start(args: argparse.Namespace, system: PiecewiseSystem):
    """The start of a sweep's values and the rule using it: ``(x0, SweepStart)``.

    ``--x0`` gives one state; without it a shipped model with a ``start`` function starts each value from
    that function of the value's own parameters, and any other model from zeros.  ``--start`` chooses the
    rule; by default ``own`` with a start function, ``previous`` otherwise.
    """
    from saltation.sweeps import SweepStart

    if args.x0 is not None:
        x0 = parse_vector(args.x0, system)
    else:
        from saltation.models import SHIPPED

        function = SHIPPED[args.model].start if args.model in SHIPPED else None
        x0 = None
        if function is not None:
            def x0(values: Mapping[str, float], _function=function) -> list[float]:
                return list(_function(values, False))

            x0.__module__, x0.__qualname__ = function.__module__, function.__qualname__  # as the files record it
    if args.start_rule is not None:
        rule = SweepStart(args.start_rule)
    else:
        rule = SweepStart.OWN if callable(x0) else SweepStart.PREVIOUS
    return x0, rule


def cmd_sweep(args: argparse.Namespace) -> int:
    """``saltation sweep``: a brute-force diagram of a shipped model."""
    import numpy as np

    from saltation.output import io, plotting
    from saltation.sweeps import SweepStart, sweep

    system, overrides, values, values2 = _checked_grid(args)
    section = _checked_section(args, system)
    x0, rule = sweep_start(args, system)
    mode0 = check_mode0(args, system)
    check_out_dir(args.out)
    flow = models.make_flow(system)  # compile (or load) here, with the notice, before the workers load it from the cache
    if args.x0 is not None and isinstance(x0, np.ndarray):
        p = flow.parameters(overrides)
        p[system.parameter_index(args.param)] = values[0]
        check_start_field(flow, x0, p, args.x0, 0.0, mode0)
    client = _dask_client(args.scheduler)
    try:
        if args.param2 is not None:
            return _period_map_command(args, system, values, values2, x0, rule, overrides, client)
        result = sweep(
            system, args.param, values, periods=200 if args.periods is None else args.periods,
            transient=args.transient, x0=x0, start=rule, parameters=overrides, workers=args.workers, client=client,
            lyapunov=args.lyapunov, mode0=mode0, section=section,
        )
    finally:
        if client is not None:
            client.close()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"{system.name}_{args.param}_sweep"
    io.save_sweep(result, stem.with_suffix(".json"))
    plotting.save_figure(plotting.plot_sweep(result), stem)
    kind = {"poincare": "Poincare section points", "maxima": "maxima of x_1"}.get(result.section)
    if kind is None:
        kind = section.words
    how = "its own start" if rule is SweepStart.OWN else "the previous value's final state"
    print(f"{sum(len(result.at(k)) for k in range(args.num))} {kind} at {args.num} values of {args.param} "
          f"(each from {how}); written to {stem}.json/.png/.pdf")
    if result.failures:
        print(f"{len(result.failures)} value(s) failed: " + "; ".join(f"{args.param} = {fmt(v)}: {m}"
                                                                     for v, m in result.failures[:3])
              + ("; ..." if len(result.failures) > 3 else ""))
    return 0


def _checked_section(args: argparse.Namespace, system: PiecewiseSystem):
    """``--section`` and ``--direction`` read against the model: a :class:`~saltation.sweeps.sections.Section`, or
    None (the default: the stroboscopic section of a forced model, the maxima of x_1 otherwise).

    Raises
    ------
    UsageError
        For an unknown name (naming the model's surfaces and states), the stroboscopic section of an autonomous
        model, a direction without a surface or an expression, or a section given with ``--param2``.
    """
    from saltation.errors import ModelError
    from saltation.sweeps.sections import parse_section

    if args.section is None:
        if args.direction is not None:
            raise UsageError("--direction belongs to --section (a switching surface or an expression)")
        return None
    if args.param2 is not None:
        raise UsageError("--section belongs to a sweep; a two-parameter map (--param2) reads the stroboscopic section")
    try:
        return parse_section(system, args.section, args.direction)
    except (ModelError, ValueError) as exc:
        raise UsageError(f"--section: {exc}") from None


def _direction(text: str) -> int:
    """The converter of ``--direction``: +1, -1 or 0 (or rising, falling, either)."""
    words = {"+1": 1, "1": 1, "rising": 1, "-1": -1, "falling": -1, "0": 0, "either": 0}
    if text.strip() not in words:
        raise argparse.ArgumentTypeError(f"{text!r} is not +1 (rising), -1 (falling) or 0 (either)")
    return words[text.strip()]


_direction.__name__ = "--direction"


def _checked_grid(args: argparse.Namespace):
    """The model, its ``--set`` values and the grid of ``--param`` (and ``--param2``), checked before any
    computation.

    Raises
    ------
    UsageError
        For an unknown parameter, a malformed grid, an incomplete or misplaced two-parameter option, or a value
        without a forcing period.
    """
    system = build_model(args.model)
    check_parameter(system, args.param, "--param")
    overrides = parse_sets(args.set, system)
    check_not_set(overrides, args.param, "--param")
    values = check_grid(args.start, args.stop, args.num, ("--from", "--to", "--num"))
    two = [args.param2, args.start2, args.stop2, args.num2]
    if any(v is not None for v in two) and not all(v is not None for v in two):
        raise UsageError("a two-parameter map needs all of --param2, --from2, --to2 and --num2")
    if args.param2 is None and args.max_period is not None:
        raise UsageError("--max-period belongs to a two-parameter map (--param2 ...)")
    values2 = None
    if args.param2 is not None:
        check_parameter(system, args.param2, "--param2")
        if args.param2 == args.param:
            raise UsageError(f"--param and --param2 must differ, got {args.param!r} twice")
        check_not_set(overrides, args.param2, "--param2")
        if system.is_autonomous:
            raise UsageError(f"--param2 (a period map counts forcing periods) needs a forced model; {system.name!r} "
                             "is autonomous")
        values2 = check_grid(args.start2, args.stop2, args.num2, ("--from2", "--to2", "--num2"))
        max_period = 16 if args.max_period is None else args.max_period
        if args.periods is not None and args.periods <= max_period:
            raise UsageError(f"--periods {args.periods} must exceed --max-period {max_period}: a period is read off "
                             "its repetitions")
    if not system.is_autonomous:  # every value's forcing period (e.g. 2*pi/omega at omega = 0 is none)
        _check_forcing(args, system, overrides, values, values2)
    return system, overrides, values, values2


def _check_forcing(args: argparse.Namespace, system: PiecewiseSystem, overrides: dict[str, float],
                   values: np.ndarray, values2: np.ndarray | None) -> None:
    """Every value of the grid has a forcing period (bad usage naming the value otherwise)."""

    base = system.parameter_vector(overrides)
    for v in values:
        for v2 in (values2 if values2 is not None else [None]):
            p = base.copy()
            p[system.parameter_index(args.param)] = v
            where = f"--param {args.param} = {fmt(v)}"
            if v2 is not None:
                p[system.parameter_index(args.param2)] = v2
                where += f", --param2 {args.param2} = {fmt(v2)}"
            forcing_period_at(system, p, where)


def _dask_client(address: str | None):
    """A client of the Dask cluster at ``address`` (``--scheduler``), or None."""
    if address is None:
        return None
    try:
        from distributed import Client
    except ImportError:
        raise UsageError("--scheduler needs Dask: pip install 'saltation[distributed]'") from None
    try:
        return Client(address, timeout=30)
    except (OSError, TimeoutError, ValueError) as exc:
        raise UsageError(f"cannot reach the Dask scheduler at {address!r}: {exc}") from None


def _period_map_command(args, system, values, values2, x0, rule, overrides, client) -> int:
    """``saltation sweep ... --param2``: the attractor's period on a grid of two parameters."""
    from saltation.output import io, plotting
    from saltation.sweeps import period_map

    max_period = 16 if args.max_period is None else args.max_period
    grid = period_map(
        system, args.param, values, args.param2, values2, max_period=max_period, periods=args.periods,
        transient=args.transient, x0=x0, start=rule, parameters=overrides, workers=args.workers, client=client,
        lyapunov=args.lyapunov, mode0=check_mode0(args, system),
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"{system.name}_{args.param}_{args.param2}_map"
    io.save_period_map(grid, stem.with_suffix(".json"))
    plotting.save_figure(plotting.plot_period_map(grid), stem)
    found = int((grid.periods > 0).sum())
    print(f"{grid.periods.size} cells ({args.num} x {args.num2}): a period up to {max_period} found in {found}, "
          f"none in {int((grid.periods == 0).sum())}, failed in {int((grid.periods < 0).sum())}; "
          f"written to {stem}.json/.png/.pdf")
    return 0


def add_parser(sub) -> None:
    """The parser of ``saltation sweep``."""
    p = sub.add_parser(
        "sweep",
        help="brute-force diagram: simulate at each parameter value and plot the sampled attractor",
        description=paragraph(
            """Simulate a shipped model at --num parameter values between --from and --to, discard a
            transient, and sample the attractor: the Poincare section x(t0 + k T) for forced models,
            the maxima of x_1 for autonomous ones (over --periods time units of 2 pi, which are not
            the period of an orbit), or with --section the crossings of a switching surface or of an
            expression of the states (--periods and --transient then count crossings). Each value
            starts from its own start (--start own: --x0, or the shipped model's start at that
            value's parameters) or from the previous value's
            final state (--start previous); the default is own where the model has a start of its own
            and --x0 is not given, previous otherwise. Uses every local core, or a Dask cluster
            (--scheduler). Writes MODEL_PARAM_sweep.json and a plot (PNG, PDF) into --out. With
            --param2 NAME --from2 V --to2 V --num2 N, a grid of two parameters whose cells record the
            period of the attractor in forcing periods (or none found: chaos or a period longer
            than --max-period), drawn as a map: MODEL_PARAM_PARAM2_map.json and its plot."""
        ),
    )
    add_model(p)
    p.add_argument("--param", metavar="NAME", required=True, help="the swept parameter")
    p.add_argument("--from", dest="start", metavar="V", type=finite, required=True, help="first value")
    p.add_argument("--to", dest="stop", metavar="V", type=finite, required=True, help="last value")
    p.add_argument("--num", metavar="N", type=integer("--num", 1), required=True,
                   help="number of values (1 takes --from = --to)")
    p.add_argument("--periods", metavar="P", type=integer("--periods", 1), default=None,
                   help="periods sampled per value: forcing periods, or time units of 2 pi for an autonomous model, "
                        "or with --section crossings (default 200; a map: 4 times --max-period)")
    p.add_argument("--transient", metavar="Q", type=integer("--transient", 0), default=100,
                   help="periods (or with --section crossings) discarded first (default 100)")
    p.add_argument("--section", metavar="NAME_OR_EXPR", default=None,
                   help="what to sample: 'poincare' (forced models: x(t0 + k T), their default), 'maxima' (maxima "
                        "of x_1, the default of autonomous models), a switching surface's name (its switching "
                        "events, the state just before each), or an expression of the states, parameters and time "
                        "t such as 'x - 1' or 'sin(omega*t)' (its crossings of zero); with a surface or an "
                        "expression --periods and --transient count crossings")
    p.add_argument("--direction", metavar="+1|-1|0", type=_direction, default=None,
                   help="with --section a surface or an expression: +1 the crossings where it rises through zero, "
                        "-1 where it falls, 0 both (default: a surface's every event, an expression's rising "
                        "crossings)")
    add_set(p, "override another parameter")
    add_x0(p, "start state (default: the shipped model's start at each value's own parameters, if it has one, else "
           "zeros)")
    add_mode0(p, "; a value that starts from the previous one's final state goes on in its final mode")
    p.add_argument("--start", dest="start_rule", choices=("own", "previous"), default=None,
                   help="where each value starts: 'own' from the start (--x0, or the model's start at that value's "
                        "parameters), 'previous' from the previous value's final state, following an attractor while "
                        "it lasts (default: own for a shipped model's start, previous otherwise)")
    p.add_argument("--workers", metavar="N", type=integer("--workers", 1), default=None,
                   help="worker processes, or chunks on a Dask cluster (default: every core, every cluster thread)")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run the values as tasks on the Dask cluster at this scheduler address (pip install "
                        "'saltation[distributed]'); the results equal a local run with the same --workers")
    p.add_argument("--lyapunov", action="store_true",
                   help="also record the largest Lyapunov exponent at each value (or cell), over the sampled periods, "
                        "and draw it (a panel below the diagram or the map): negative for a long period or a slow "
                        "transient, positive for chaos")
    p.add_argument("--param2", metavar="NAME", default=None,
                   help="a second parameter: a two-parameter map of the attractor's period (forced models)")
    p.add_argument("--from2", dest="start2", metavar="V", type=finite, default=None, help="first value of --param2")
    p.add_argument("--to2", dest="stop2", metavar="V", type=finite, default=None, help="last value of --param2")
    p.add_argument("--num2", metavar="N", type=integer("--num2", 1), default=None, help="number of values of --param2")
    p.add_argument("--max-period", dest="max_period", metavar="K", type=integer("--max-period", 1), default=None,
                   help="the longest period (in forcing periods) a map looks for (default 16)")
    add_out(p)
    p.set_defaults(handler=cmd_sweep)
