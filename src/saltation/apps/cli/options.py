"""Options shared by the subcommands: their converters, their checks before any computation, and the
arguments several subcommands take, each written once.

A count must be a positive (or non-negative) integer, a step size, tolerance or period a positive finite
number, every number finite, and a range's two ends must differ; each bad value is bad usage
(:class:`~saltation.apps.cli.errors.UsageError`) naming the option and the value.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from saltation.apps.cli.errors import UsageError
from saltation.apps.cli.models import MODEL_HELP, model_names
from saltation.apps.cli.text import fmt
from saltation.errors import SaltationError

if TYPE_CHECKING:
    import numpy as np

    from saltation.model.system import PiecewiseSystem

#: The most shooting segments ``--segments`` takes: :data:`saltation.orbits.multiple.MAX_SEGMENTS`, written out
#: here so that building the parser loads no solver (a test holds the two equal).
MAX_SEGMENTS = 1000

#: The shortest period (guess) accepted, in time units, relative to ``max(1, |t0|)``: over shorter times
#: the time axis near ``t0`` no longer resolves the period to a millionth, and every state of a model whose
#: field is of order one moves by less than the shooting tolerance, so shooting would "converge" anywhere.
MIN_PERIOD = 1e-9
#: Relative difference below which a --period given for a forced model is its forcing period.
FORCING_PERIOD_MATCH = 1e-9
#: The smallest continuation step the command line accepts (``ContinuationSettings.ds_min``).
MIN_STEP = 1e-6
#: Help of ``--period`` of ``continue`` and ``locus``.
PERIOD_HELP = (f"period guess for autonomous models, at least {MIN_PERIOD:g} (forced models take the forcing period: "
               "a --period must equal it)")
#: Help of ``--mode0`` of ``orbit``, ``continue``, ``locus`` and ``sweep``.
MODE0_HELP = ("the mode the start state (--x0, or the start of a transient) is in: for a mode that is memory (a latch, "
              "a relay with hysteresis, a thermostat), which the state alone does not tell from another mode with the "
              "same domain; the state must lie in its domain (default: the mode the model's domains give the state)")

def check_parameter(system: PiecewiseSystem, name: str, flag: str) -> str:
    """A parameter named on the command line (``--param`` and the like) must be the model's.

    Raises
    ------
    UsageError
        For an unknown name (bad usage: exit status 2).
    """
    if name not in system.parameter_names:
        raise UsageError(
            f"unknown parameter {name!r} in {flag} for model {system.name!r}; "
            f"parameters are {', '.join(system.parameter_names)}"
        )
    return name


def check_mode0(args: argparse.Namespace, system: PiecewiseSystem) -> str | None:
    """``--mode0 NAME``: a mode of the model (or None when not given).

    Raises
    ------
    UsageError
        For an unknown name (bad usage: exit status 2), listing the model's modes.
    """
    name = getattr(args, "mode0", None)
    if name is not None and name not in system.mode_names:
        raise UsageError(f"unknown mode {name!r} in --mode0 for model {system.name!r}; modes are "
                         f"{', '.join(system.mode_names)}")
    return name


def parse_sets(items: Sequence[str] | None, system: PiecewiseSystem) -> dict[str, float]:
    """Parameter overrides from ``--set NAME=VALUE`` items (the last one of a name wins).

    Raises
    ------
    UsageError
        For a malformed item, an unknown parameter or a value that is not a finite number.
    """
    out: dict[str, float] = {}
    for item in items or ():
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise UsageError(f"malformed --set {item!r}: expected NAME=VALUE, e.g. --set omega=1.2")
        if name not in system.parameter_names:
            raise UsageError(
                f"unknown parameter {name!r} in --set for model {system.name!r}; "
                f"parameters are {', '.join(system.parameter_names)}"
            )
        try:
            value = float(text)
        except ValueError:
            raise UsageError(f"malformed --set {item!r}: {text.strip()!r} is not a number") from None
        if not math.isfinite(value):
            raise UsageError(f"--set {item!r}: the value must be finite")
        out[name] = value
    from saltation.model.system import PiecewiseSystem

    if isinstance(system, PiecewiseSystem):
        usable_parameters(system, out, "--set")  # a zero divisor (m = 0), named with its expression
    return out


def usable_parameters(system: PiecewiseSystem, values: Mapping[str, float], where: str) -> np.ndarray:
    """The parameter vector at ``values``, or bad usage naming ``where`` (a zero divisor, a non-finite value)."""

    try:
        return system.parameter_vector(values)
    except SaltationError as exc:
        raise UsageError(f"{where}: {exc}") from None


def parse_vector(text: str, system: PiecewiseSystem, option: str = "--x0") -> np.ndarray:
    """A state from ``V1,V2,...`` with one finite number per state of the model.

    Raises
    ------
    UsageError
        For a malformed list or the wrong number of components.
    """
    import numpy as np

    parts = [s.strip() for s in text.split(",")]
    try:
        values = [float(s) for s in parts]
    except ValueError:
        raise UsageError(
            f"malformed {option} {text!r}: expected {system.n} comma-separated numbers such as "
            f"{','.join(['0.5'] * system.n)}"
        ) from None
    if len(values) != system.n:
        raise UsageError(
            f"{option} {text!r} has {len(values)} component{'s' if len(values) != 1 else ''}; model "
            f"{system.name!r} has {system.n} states ({', '.join(system.state_names)})"
        )
    if not all(math.isfinite(v) for v in values):
        raise UsageError(f"{option} {text!r}: every component must be finite")
    return np.array(values)


def check_start_field(flow, x0: np.ndarray, p: np.ndarray, text: str, t0: float = 0.0,
                      mode0: str | None = None, option: str = "--x0") -> None:
    """Bad usage if the field of the start's mode is not finite at ``x0`` (a finite state too large for
    the integration: its field overflows), naming the option, the mode and the field.

    Raises
    ------
    UsageError
        If the vector field at ``(t0, x0)`` holds an infinity or a NaN.
    """
    import numpy as np

    try:
        mode = flow.start_mode(x0, p, t0, mode0)
    except SaltationError:
        return  # the run says why (a state in no mode's domain, a mode0 that does not hold it)
    with np.errstate(all="ignore"):
        field = flow.vector_field(mode, t0, x0, p)
    if np.isfinite(field).all():
        return
    name = flow.system.mode_names[mode]
    why = (": it overflows, the state is too large for the integration"
           if np.isinf(field).any() and np.max(np.abs(x0)) > 1e100 else "")
    raise UsageError(f"{option} {text!r}: the vector field of mode {name!r} is not finite at this state "
                     f"({', '.join(fmt(v) for v in field)}){why}")


def non_negative(option: str) -> Callable[[str], float]:
    """A converter of a non-negative finite number."""

    def convert(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not (math.isfinite(value) and value >= 0):
            raise argparse.ArgumentTypeError(f"{text!r} must be a non-negative finite number")
        return value

    return convert


def positive(option: str, minimum: float | None = None, why: str = "") -> Callable[[str], float]:
    """A converter of a positive finite number (at least ``minimum`` if given, ``why`` saying why)."""

    def convert(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"{text!r} must be a positive finite number")
        if minimum is not None and value < minimum:
            raise argparse.ArgumentTypeError(f"{text!r} is below the smallest accepted value {minimum:g}{why}")
        return value

    convert.__name__ = option
    return convert


def integer(option: str, minimum: int, maximum: int | None = None, why: str = "") -> Callable[[str], int]:
    """A converter of an integer of at least ``minimum`` (1: a positive count, 0: a non-negative one), and at most
    ``maximum`` if given (``why`` saying why)."""
    what = "a positive integer" if minimum == 1 else f"an integer of at least {minimum}"

    def convert(text: str) -> int:
        try:
            value = int(text.strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"{text!r} must be {what}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"{text!r} is above the largest accepted value {maximum}{why}")
        return value

    convert.__name__ = option
    return convert


#: The converter of ``--segments``: a positive integer of at most :data:`~saltation.orbits.shooting.MAX_SEGMENTS`.
SEGMENTS_TYPE = integer(
    "--segments", 1, MAX_SEGMENTS,
    " (each segment holds an n x n transfer matrix and costs an integration per Newton step, and the Newton system "
    f"is dense in the m n node values; {MAX_SEGMENTS} segments bring a multiplier of 1e300 down to 2 per segment)")


def finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} must be finite")
    return value


def check_period(period: float | None, t0: float = 0.0) -> None:
    """A ``--period`` long enough to resolve at ``t0`` (see :data:`MIN_PERIOD`).

    Raises
    ------
    UsageError
        Naming the value and the shortest accepted one.
    """
    if period is None:
        return
    shortest = MIN_PERIOD * max(1.0, abs(t0))
    if period < shortest:
        relative = f" ({MIN_PERIOD:g} times |t0| = {abs(t0):g})" if abs(t0) > 1 else ""
        raise UsageError(f"--period {period:g} is too short: a period must be at least {shortest:g}{relative}")


def forcing_period_at(system: PiecewiseSystem, p: np.ndarray, where: str) -> float:
    """The forcing period of a forced model at the parameter values ``p``.

    Raises
    ------
    UsageError
        If it is not a positive finite number there (``where`` names the options that set ``p``).
    """

    try:
        value = float(system.forcing_period(p))
    except (SaltationError, ArithmeticError, ValueError) as exc:  # e.g. 2*pi/omega at omega = 0
        value, detail = math.nan, f" ({type(exc).__name__}: {exc})"
    else:
        detail = ""
    if not (math.isfinite(value) and value > 0):
        values = ", ".join(f"{k}={fmt(v)}" for k, v in zip(system.parameter_names, p))
        raise UsageError(
            f"{where}: the forcing period {system.period_expr} of model {system.name!r} is not a positive finite "
            f"number at {values}{detail}"
        )
    return value


def check_forced_period(system: PiecewiseSystem, period: float | None, p: np.ndarray, where: str) -> None:
    """A ``--period`` given for a forced model must be its forcing period (which shooting uses anyway).

    Raises
    ------
    UsageError
        Naming the forcing period when ``period`` contradicts it.
    """

    if period is None or system.is_autonomous:
        return
    forcing = forcing_period_at(system, p, where)
    if abs(period - forcing) > FORCING_PERIOD_MATCH * forcing:
        raise UsageError(
            f"model {system.name!r} is forced: its period is the forcing period {system.period_expr} = "
            f"{fmt(forcing)} at {where}; --period {fmt(period)} contradicts it (drop --period, or change "
            "the forcing with --set)"
        )


def check_out_dir(path: str | os.PathLike[str], option: str = "--out") -> Path:
    """The output folder of a subcommand, created if missing and tried with a test file (before computing).

    Parameters
    ----------
    path : str or path-like
        The folder given on the command line.
    option : str
        The option that gave it, for the message.

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    UsageError
        If it is a file, or cannot be created or written in (exit status 2), naming the option, the
        folder and the reason.
    """
    out = Path(path)
    where = f"{option} {str(path)!r}"
    if out.exists() and not out.is_dir():
        raise UsageError(f"{where} is a file, not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        if isinstance(exc, (FileExistsError, NotADirectoryError)):
            reason = "a file is in the way"
            if exc.filename and str(exc.filename) != str(path):
                reason += f" ({exc.filename})"
        else:
            reason = exc.strerror or str(exc)
        raise UsageError(f"{where}: cannot create the folder: {reason}") from None
    try:
        fd, probe = tempfile.mkstemp(dir=out, prefix=".saltation-write-test-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise UsageError(f"{where}: cannot write in the folder: {exc.strerror or exc}") from None
    return out

def check_not_set(overrides: Mapping[str, float], name: str, flag: str) -> None:
    """A parameter whose values an option sets (``--param``) may not be given by ``--set`` as well.

    Raises
    ------
    UsageError
        Naming both options.
    """
    if name in overrides:
        raise UsageError(f"--set {name}={fmt(overrides[name])} conflicts with {flag} {name}, which sets its values")


def check_grid(start: float, stop: float, num: int, names: tuple[str, str, str]) -> np.ndarray:
    """``num`` evenly spaced values from ``start`` to ``stop``: one value needs ``start == stop``,
    several need them to differ.

    Raises
    ------
    UsageError
        Naming the three options and their values.
    """
    import numpy as np

    first, last, count = names
    if num == 1 and start != stop:
        raise UsageError(f"{count} 1 takes one value, but {first} {fmt(start)} and {last} {fmt(stop)} differ "
                         f"(give {count} 2 or more, or the same value twice)")
    if num > 1 and start == stop:
        raise UsageError(f"{first} and {last} are both {fmt(start)}: {count} {num} values would all be the same")
    return np.linspace(start, stop, num)

def check_start_period(args: argparse.Namespace, system: PiecewiseSystem, p: np.ndarray, where: str) -> None:
    """``--period`` of ``continue`` and ``locus``: long enough (autonomous models), or the forcing period at the
    start of the branch (forced ones).

    Raises
    ------
    UsageError
        Naming the value (and the forcing period it contradicts).
    """

    if system.is_autonomous:
        check_period(args.period)
    else:
        check_forced_period(system, args.period, p, where)

def check_equilibrium_option(args: argparse.Namespace, system) -> None:
    """``--equilibrium MODE`` or ``sliding:SURFACE``: a mode or surface of an autonomous model, and no option that
    applies to periodic orbits only.

    Raises
    ------
    UsageError
        Naming the option and what is wrong.
    """
    if not system.is_autonomous:
        raise UsageError(
            f"--equilibrium {args.equilibrium}: model {system.name!r} is forced (forcing period "
            f"{system.period_expr}): it has no equilibria; continue its periodic orbits (drop --equilibrium)"
        )
    sliding_on = args.equilibrium.partition("sliding:")[2] if args.equilibrium.startswith("sliding:") else None
    if sliding_on is not None and sliding_on not in system.surface_names:
        raise UsageError(f"unknown surface {sliding_on!r} in --equilibrium sliding:SURFACE for model {system.name!r}; "
                         f"surfaces are {', '.join(system.surface_names)}")
    try:
        if sliding_on is None:
            system.mode_index(args.equilibrium)
    except SaltationError:
        raise UsageError(f"unknown mode {args.equilibrium!r} in --equilibrium for model {system.name!r}; modes "
                         f"are {', '.join(system.mode_names)} (or sliding:SURFACE for pseudo-equilibria)") from None
    for flag, given in (("--period", args.period is not None), ("--backward", args.backward),
                        ("--segments", args.segments != 1), ("--mode0", getattr(args, "mode0", None) is not None),
                        ("--period-doubled", getattr(args, "period_doubled", False))):
        if given:
            raise UsageError(f"{flag} does not apply to --equilibrium (an equilibrium has no period and no "
                             "direction of time)")

def parse_range(option: str):
    def parse(text: str) -> tuple[float, float]:
        parts = text.split(",")
        if len(parts) != 2:
            raise argparse.ArgumentTypeError(f"expected two numbers A,B, got {text!r}")
        a, b = (finite(v) for v in parts)
        if a == b:
            raise argparse.ArgumentTypeError(f"the two ends must differ, got {text!r}")
        return a, b

    return parse

def add_step_options(p, what: str = "") -> None:
    """``--ds``, ``--ds-max`` and ``--max-points`` (of the branch, and of each curve where ``what`` says so)."""
    p.add_argument("--ds", metavar="S", type=positive("--ds", MIN_STEP, " (the smallest step of a continuation)"),
                   default=None, help=f"initial arclength step{what}, at most --ds-max (default 0.01, or --ds-max if smaller)")
    p.add_argument("--ds-max", metavar="S", type=positive("--ds-max", MIN_STEP, " (the smallest step of a continuation)"),
                   default=0.02, help=f"largest step{what} (default 0.02)")
    p.add_argument("--max-points", metavar="N", type=integer("--max-points", 1), default=2000,
                   help=f"largest number of points{what}, a positive integer (default 2000)")


#: Help of ``--measure``.
MEASURE_HELP = ("a measure of the orbits: a state NAME (max |NAME| over the period), ptp:NAME (peak to peak), "
                "section:NAME (its value at the section), norm (max of the state's Euclidean norm), or an expression "
                "of the states, parameters and t (its largest value; min:EXPR its smallest), e.g. 'sqrt(x**2 + y**2)'; "
                "repeat for several")


def add_measure(p: argparse.ArgumentParser, what: str = "") -> None:
    """``--measure SPEC`` (repeatable)."""
    p.add_argument("--measure", metavar="SPEC", action="append", default=[], help=MEASURE_HELP + what)


def parse_measure_options(args: argparse.Namespace, system) -> tuple:
    """The ``--measure`` options as measures of the model.

    Raises
    ------
    UsageError
        Naming the measure and the model's states, for one that does not parse.
    """
    from saltation.errors import ModelError
    from saltation.orbits.measures import parse_measures

    try:
        return parse_measures(args.measure, system)
    except ModelError as exc:
        raise UsageError(f"--measure: {exc}") from None


def add_monitor(p: argparse.ArgumentParser) -> None:
    """``--monitor EXPR`` (repeatable) and ``--stop-at-monitor``."""
    p.add_argument("--monitor", metavar="EXPR", action="append", default=[],
                   help="locate where EXPR crosses zero along the branch (or where LHS = RHS), recorded as a "
                        "special point of kind monitor: an expression of parameter (or the parameter's name), "
                        "period, amplitude, half_peak_to_peak, excursion, largest_multiplier and the model's "
                        "parameters, or a measure of the orbits as --measure writes it, e.g. 'amplitude = 1.5' or "
                        "'sqrt(x**2 + y**2) = 0.8'; repeat for several")
    p.add_argument("--stop-at-monitor", action="store_true", help="end the branch where a --monitor crosses zero")


def parse_monitor_options(args: argparse.Namespace, system) -> tuple:
    """The ``--monitor`` options as monitors of the model.

    Raises
    ------
    UsageError
        Naming the monitor, for one that does not parse.
    """
    from saltation.branches.monitors import Monitor
    from saltation.errors import ModelError

    try:
        return tuple(Monitor.parse(text, system, args.param, stop=args.stop_at_monitor) for text in args.monitor)
    except ModelError as exc:
        raise UsageError(f"--monitor: {exc}") from None


def step_settings(args, bounds: tuple[float, float]):
    """The continuation settings of ``--ds``, ``--ds-max`` and ``--max-points`` over ``bounds``."""
    from saltation.special_points.continuation import ContinuationSettings

    if args.ds is not None and args.ds > args.ds_max:
        raise UsageError(f"--ds {fmt(args.ds)} exceeds --ds-max {fmt(args.ds_max)}: the first step cannot be "
                         "longer than the largest")
    ds = min(0.01, args.ds_max) if args.ds is None else args.ds
    return ContinuationSettings(ds=ds, ds_max=args.ds_max, bounds=(min(bounds), max(bounds)),
                                max_points=args.max_points, ds_min=MIN_STEP)


# --------------------------------------------------------------------------------------------
# arguments several subcommands take
# --------------------------------------------------------------------------------------------

#: Help of ``--x0`` of the subcommands that follow a branch.
X0_HELP = "guess of the start state (default: the end of a transient)"
#: Help of ``--segments``: what each subcommand adds to it follows.
SEGMENTS_HELP = ("shooting segments: 1 (default) is single shooting; M > 1 is multiple shooting with M nodes along the "
                 f"period, at most {MAX_SEGMENTS}, for strongly unstable orbits (multipliers of 1e8 and more), long "
                 "periods and large models")


def add_model(p: argparse.ArgumentParser) -> None:
    """The positional ``MODEL``: a shipped model or a model file."""
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP.format(names=model_names()))


def add_set(p: argparse.ArgumentParser, help: str) -> None:
    """``--set NAME=VALUE``, repeated (:func:`parse_sets`)."""
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[], help=help)


def add_x0(p: argparse.ArgumentParser, help: str = X0_HELP) -> None:
    """``--x0 V1,V2,...`` (:func:`parse_vector`)."""
    p.add_argument("--x0", metavar="V1,V2,...", help=help)


def add_period(p: argparse.ArgumentParser, help: str = PERIOD_HELP) -> None:
    """``--period T``: a positive finite number."""
    p.add_argument("--period", metavar="T", type=positive("--period"), help=help)


def add_mode0(p: argparse.ArgumentParser, more: str = "") -> None:
    """``--mode0 NAME`` (:func:`check_mode0`), its help :data:`MODE0_HELP` and ``more``."""
    p.add_argument("--mode0", metavar="NAME", default=None, help=MODE0_HELP + more)


def add_segments(p: argparse.ArgumentParser, more: str = "") -> None:
    """``--segments M``, its help :data:`SEGMENTS_HELP` and ``more``."""
    p.add_argument("--segments", metavar="M", type=SEGMENTS_TYPE, default=1, help=SEGMENTS_HELP + more)


def add_out(p: argparse.ArgumentParser, help: str = "output directory (default: the current one)", *,
            default: str | None = ".", required: bool = False) -> None:
    """``--out DIR`` (checked by :func:`check_out_dir` before any computation)."""
    p.add_argument("--out", metavar="DIR", default=default, required=required, help=help)


def add_json(p: argparse.ArgumentParser, help: str) -> None:
    """``--json``: one JSON object on standard output."""
    p.add_argument("--json", action="store_true", help=help)


def add_no_progress(p: argparse.ArgumentParser) -> None:
    """``--no-progress``."""
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")


def parse_start(args: argparse.Namespace, flow, p: np.ndarray) -> np.ndarray | None:
    """The start state of ``--x0`` at ``t0 = 0`` (None without it), its field checked at the parameters ``p``.

    Raises
    ------
    UsageError
        For a malformed ``--x0`` or a field that is not finite there.
    """

    x0 = parse_vector(args.x0, flow.system) if args.x0 is not None else None
    if x0 is not None:
        check_start_field(flow, x0, p, args.x0, 0.0, args.mode0)
    return x0
