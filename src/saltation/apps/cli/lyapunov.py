"""``saltation lyapunov``: the Lyapunov exponents of a model's motion, through the saltation matrices of its
events (:func:`saltation.orbits.lyapunov.lyapunov_exponents`)."""

from __future__ import annotations

import argparse
import json
import math

import saltation.apps.cli.models as models  # noqa: PLR0402 (one place to replace it; importing the package would be a cycle)
from saltation.apps.cli.errors import UsageError
from saltation.apps.cli.models import build_model
from saltation.apps.cli.options import (
    add_json,
    add_model,
    add_set,
    add_x0,
    check_start_field,
    non_negative,
    parse_sets,
    parse_vector,
    positive,
)
from saltation.apps.cli.starts import transient
from saltation.apps.cli.text import paragraph
from saltation.errors import ModelError


def _exponent_json(value: float) -> float | str:
    """An exponent for JSON: a finite number, or ``"-inf"``, ``"inf"`` or ``"nan"``."""
    return value if math.isfinite(value) else ("-inf" if value < 0 else ("inf" if value > 0 else "nan"))


def cmd_lyapunov(args: argparse.Namespace) -> int:
    """``saltation lyapunov``: the Lyapunov exponents of a run, through the saltation matrices of its events."""
    from saltation.orbits.lyapunov import lyapunov_exponents, plan_run

    system = build_model(args.model)
    overrides = parse_sets(args.set, system)
    flow = models.make_flow(system)
    p = flow.parameters(overrides)
    try:  # a run too short for an accuracy, or too long to finish, is refused before the start's transient
        plan_run(system, p, time=args.time, transient=args.transient, names={"time": "--time", "transient": "--transient"})
    except ModelError as exc:
        raise UsageError(str(exc)) from None
    if args.x0 is not None:
        x0 = parse_vector(args.x0, system)
        check_start_field(flow, x0, p, args.x0)
    else:  # the shipped model's start, or (autonomous) a start whose transient moves
        x0 = transient(flow, args.model, p, None, t0=0.0, backward=False)[1]
    result = lyapunov_exponents(flow, x0, parameters=p, time=args.time, transient=args.transient)
    if args.json:
        print(json.dumps({
            "model": system.name,
            "parameters": dict(zip(system.parameter_names, map(float, p))),
            "exponents": [_exponent_json(float(e)) for e in result.exponents],
            "accuracy": [float(a) for a in result.accuracy],
            "time": result.time,
            "transient": result.transient,
            "interval": result.interval,
            "state_end": [float(v) for v in result.state],
        }))
        return 0
    print(f"Lyapunov exponents of {system.name} over t = {result.time:g} after a transient of {result.transient:g} "
          f"(reorthonormalised every {result.interval:.6g}):")
    for k, (e, a) in enumerate(zip(result.exponents, result.accuracy), start=1):
        print(f"  lambda_{k} = " + ("-inf  (a direction collapsed by a singular saltation matrix)" if not math.isfinite(e)
                                    else f"{e:+.6f}  +- {a:.1e}"))
    return 0


def add_parser(sub) -> None:
    """The parser of ``saltation lyapunov``."""
    p = sub.add_parser(
        "lyapunov",
        help="the Lyapunov exponents of a model's motion",
        description=paragraph(
            """Integrate a model with its variational equation, jumped by the saltation matrix at every
            event, and reorthonormalise the fundamental matrix at intervals (QR): the Lyapunov exponents,
            per unit time, with an estimate of each one's error from the spread over ten blocks of the run.
            A direction collapsed by a singular saltation matrix (the start of a sliding motion or a stick
            phase) has the exponent -inf. A forced model's time direction is not counted."""
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_model(p)
    add_set(p, "override a parameter (repeat for several)")
    add_x0(p, "the state the run starts from (default: the model's start)")
    p.add_argument("--time", metavar="T", type=positive("--time"), required=True,
                   help="the averaging time: at least 5 forcing periods (an autonomous model: 5 time units), so that "
                   "each of the ten blocks covers half a one and their spread measures the error, and at most "
                   "a million of them (each one a variational integration and a QR factorisation)")
    p.add_argument("--transient", metavar="T", type=non_negative("--transient"), default=0.0,
                   help="time integrated first, not averaged (default 0)")
    add_json(p, "print one JSON object (model, parameters, exponents, accuracy, time, transient, interval, state_end)")
    p.set_defaults(handler=cmd_lyapunov)
