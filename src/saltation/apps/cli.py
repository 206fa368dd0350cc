"""Command line interface: ``saltation SUBCOMMAND ...``.

One function per subcommand (``cmd_<name>``), each registered by an
``_add_<name>_parser`` function in :data:`SUBCOMMANDS`; shipped models are
looked up in :data:`saltation.models.SHIPPED`.  Every failure of a subcommand becomes one line
``saltation: error: ...`` on stderr and a non-zero exit status:

* 0: success;
* 1: the computation failed (integration, Newton, ...), or writing its files did (a full disk: the
  message names the file; files are written atomically, so an old file of that name is untouched);
* 2: bad usage (unknown model, parameter or option, malformed value, an ``--out`` that is a file or
  cannot be created or written in);
* 141 (128 + SIGPIPE): standard output was closed early (``saltation orbit ... | head -1``): no message.

The output folder (``--out``) is created and tried with a test file before any computation.
Numeric options are checked before any computation: a count must be a positive
(or non-negative) integer, a step size, tolerance or period a positive finite
number, every number finite, and a range's two ends must differ; each bad value
is bad usage naming the option and the value.  An unexpected exception (a bug,
not one of saltation's errors) is one line too, ``internal error: TYPE: MESSAGE``,
with exit status 1; the global option ``--debug`` lets every exception through
with its traceback instead.
"""

from __future__ import annotations

import argparse
import atexit
import json
import math
import os
import sys
import tempfile
import textwrap
import threading
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from saltation.errors import ModelError, SaltationError, StartGuessError
from saltation.model.system import PiecewiseSystem
from saltation.models import SHIPPED
from saltation.orbits import start as start_guesses
from saltation.orbits.shooting import MAX_SEGMENTS
from saltation.orbits.start import TRANSIENT_PERIODS

PROG = "saltation"

#: The shortest period (guess) accepted, in time units, relative to ``max(1, |t0|)``: over shorter times
#: the time axis near ``t0`` no longer resolves the period to a millionth, and every state of a model whose
#: field is of order one moves by less than the shooting tolerance, so shooting would "converge" anywhere.
MIN_PERIOD = 1e-9
#: Relative difference below which a --period given for a forced model is its forcing period.
FORCING_PERIOD_MATCH = 1e-9
#: The smallest continuation step the command line accepts (``ContinuationSettings.ds_min``).
MIN_STEP = 1e-6
#: The smallest ``--ds-max`` of ``saltation paper``: each of its branches has at most 5000 points, and
#: Fig. 7's stable branch takes about 3300 of them at a largest step of 0.002.
PAPER_MIN_DS_MAX = 2e-3
#: Help of ``--period`` of ``continue`` and ``locus``.
PERIOD_HELP = (f"period guess for autonomous models, at least {MIN_PERIOD:g} (forced models take the forcing period: "
               "a --period must equal it)")
#: Help of ``--mode0`` of ``orbit``, ``continue``, ``locus`` and ``sweep``.
MODE0_HELP = ("the mode the start state (--x0, or the start of a transient) is in: for a mode that is memory (a latch, "
              "a relay with hysteresis, a thermostat), which the state alone does not tell from another mode with the "
              "same domain; the state must lie in its domain (default: the mode the model's domains give the state)")


class UsageError(SaltationError, ValueError):
    """The command line is malformed (exit status 2)."""


class CommandError(SaltationError, RuntimeError):
    """A subcommand could not do its job (exit status 1)."""


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, raised as :class:`UsageError`.

    ``epilog_factory`` builds the epilog only when help is printed (it may be costly).
    """

    def __init__(self, *args, epilog_factory: Callable[[], str] | None = None, **kwargs):
        super().__init__(*args, **kwargs)
        self.epilog_factory = epilog_factory

    def error(self, message: str):  # noqa: D102 (argparse protocol)
        raise UsageError(f"{message} (see '{self.prog} --help')")

    def format_help(self) -> str:  # noqa: D102
        if self.epilog_factory is not None:
            self.epilog = self.epilog_factory()
        return super().format_help()


# --------------------------------------------------------------------------------------------
# shared helpers (for every subcommand that works on a shipped model)
# --------------------------------------------------------------------------------------------

def model_names() -> str:
    return ", ".join(SHIPPED)


MODEL_HELP = (
    "a shipped model ({names}) or a model file PATH.py:NAME, where NAME in that file is a PiecewiseSystem "
    "(or CompiledSystem) or a function without required arguments that returns one"
)


def build_model(spec: str) -> PiecewiseSystem:
    """The model a command line names: a shipped model with its defaults, or ``PATH.py:NAME``.

    In a model file, ``NAME`` is a :class:`~saltation.model.system.PiecewiseSystem`
    (or :class:`~saltation.engine.compiled.CompiledSystem`), or a function without
    required arguments that returns one.

    Raises
    ------
    UsageError
        If no model of that name is shipped, or the file, the name or what it
        gives is not a model (the message names the file and the name).
    """
    path, sep, attr = spec.rpartition(":")
    if sep and path.endswith(".py"):
        return load_model_file(Path(path), attr)
    try:
        factory = SHIPPED[spec].factory
    except KeyError:
        raise UsageError(
            f"unknown model {spec!r}; shipped models are {model_names()}, or give a model file as PATH.py:NAME"
        ) from None
    return factory()


def load_model_file(path: Path, name: str) -> PiecewiseSystem:
    """``name`` from the Python file ``path``: a model, or a function without required arguments returning one.

    Raises
    ------
    UsageError
        Naming the file and the name: a missing file, an error while running
        it, a missing name, required arguments, or something that is not a model.
    """
    import importlib.util
    import inspect

    from saltation.engine.compiled import CompiledSystem

    where = f"model file {str(path)!r}"
    if not name.isidentifier():
        raise UsageError(f"{where}: {name!r} is not a Python name (give PATH.py:NAME)")
    if not path.is_file():
        raise UsageError(f"{where} does not exist")
    module_name = f"_saltation_model_file_{abs(hash(str(path.resolve())))}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module  # dataclasses and numba look a module up by its name
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the user's code: any failure is reported, naming the file
        sys.modules.pop(module_name, None)
        raise UsageError(f"{where} failed to run: {type(exc).__name__}: {exc}") from None
    if not hasattr(module, name):
        found = sorted(k for k, v in vars(module).items() if isinstance(v, (PiecewiseSystem, CompiledSystem)))
        raise UsageError(f"{where} has no name {name!r}" + (f"; models in it: {', '.join(found)}" if found else ""))
    obj = getattr(module, name)
    if not isinstance(obj, (PiecewiseSystem, CompiledSystem)):
        if not callable(obj):
            raise UsageError(f"{where}: {name!r} is neither a model nor a function returning one")
        try:
            inspect.signature(obj).bind()
        except TypeError:
            raise UsageError(f"{where}: function {name!r} needs arguments; it must be callable without any") from None
        except ValueError:
            pass  # no signature to inspect (a builtin): just call it
        try:
            obj = obj()
        except SaltationError as exc:
            raise UsageError(f"{where}: {name}() failed: {exc}") from None
        except Exception as exc:  # the user's code
            raise UsageError(f"{where}: {name}() failed: {type(exc).__name__}: {exc}") from None
        if not isinstance(obj, (PiecewiseSystem, CompiledSystem)):
            raise UsageError(f"{where}: {name}() returned {type(obj).__name__}, not a PiecewiseSystem or CompiledSystem")
    return obj


def make_flow(system: PiecewiseSystem):
    """The compiled flow of a model (compiles on first use, cached on disk afterwards).

    On a terminal, says so on stderr when compiling the model's functions takes more than a few
    seconds (the one-time build of the integrator says so itself).
    """
    from saltation.engine.flow import Flow

    timer = None
    if sys.stderr.isatty():
        def notice() -> None:
            print(f"{PROG}: compiling the functions of model {system.name!r} (first use of these equations only)...",
                  file=sys.stderr, flush=True)

        timer = threading.Timer(3.0, notice)
        timer.daemon = True
        timer.start()
    try:
        return Flow(system)
    finally:
        if timer is not None:
            timer.cancel()


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
                     f"({', '.join(_fmt(v) for v in field)}){why}")


def _non_negative(option: str) -> Callable[[str], float]:
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


def _positive(option: str, minimum: float | None = None, why: str = "") -> Callable[[str], float]:
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


def _integer(option: str, minimum: int, maximum: int | None = None, why: str = "") -> Callable[[str], int]:
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
SEGMENTS_TYPE = _integer(
    "--segments", 1, MAX_SEGMENTS,
    " (each segment holds an n x n transfer matrix and costs an integration per Newton step, and the Newton system "
    f"is dense in the m n node values; {MAX_SEGMENTS} segments bring a multiplier of 1e300 down to 2 per segment)")


def _finite(text: str) -> float:
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
        values = ", ".join(f"{k}={_fmt(v)}" for k, v in zip(system.parameter_names, p))
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
            f"{_fmt(forcing)} at {where}; --period {_fmt(period)} contradicts it (drop --period, or change "
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


def _os_error_text(exc: OSError) -> str:
    """An OS error as one line naming its file: ``FILE: REASON``."""
    reason = exc.strerror or str(exc) or type(exc).__name__
    if exc.filename is None:
        return reason
    files = f"{exc.filename} -> {exc.filename2}" if exc.filename2 is not None else f"{exc.filename}"
    return f"{files}: {reason}"


def _stdout_closed() -> bool:
    """Whether standard output is a pipe (or socket) whose reader has gone."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return False
    try:
        import select

        poller = select.poll()
        poller.register(fd, select.POLLOUT)
        return any(event & select.POLLERR for _, event in poller.poll(0))
    except (AttributeError, OSError, ValueError):  # no poll (Windows): assume it was stdout
        return True


def _silence_stdout() -> None:
    """Point standard output at the null device, so the interpreter's last flush cannot fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (AttributeError, OSError, ValueError):
        pass


def check_not_set(overrides: Mapping[str, float], name: str, flag: str) -> None:
    """A parameter whose values an option sets (``--param``) may not be given by ``--set`` as well.

    Raises
    ------
    UsageError
        Naming both options.
    """
    if name in overrides:
        raise UsageError(f"--set {name}={_fmt(overrides[name])} conflicts with {flag} {name}, which sets its values")


def check_grid(start: float, stop: float, num: int, names: tuple[str, str, str]) -> np.ndarray:
    """``num`` evenly spaced values from ``start`` to ``stop``: one value needs ``start == stop``,
    several need them to differ.

    Raises
    ------
    UsageError
        Naming the three options and their values.
    """
    first, last, count = names
    if num == 1 and start != stop:
        raise UsageError(f"{count} 1 takes one value, but {first} {_fmt(start)} and {last} {_fmt(stop)} differ "
                         f"(give {count} 2 or more, or the same value twice)")
    if num > 1 and start == stop:
        raise UsageError(f"{first} and {last} are both {_fmt(start)}: {count} {num} values would all be the same")
    return np.linspace(start, stop, num)


def _fmt(value: float) -> str:
    return f"{value:.10g}"


def _complex_text(mu: complex) -> str:
    if not np.isfinite(mu):
        return "inf"
    if mu.imag == 0:
        return _fmt(mu.real)
    sign = "+" if mu.imag > 0 else "-"
    return f"{_fmt(mu.real)} {sign} {_fmt(abs(mu.imag))}i"


def multipliers_json(mu: Sequence[complex]) -> list:
    """Multipliers as ``[re, im]`` pairs, an infinite one as the string ``"inf"``."""
    return ["inf" if not np.isfinite(m) else [float(m.real), float(m.imag)] for m in np.asarray(mu, dtype=complex)]


# --------------------------------------------------------------------------------------------
# transients: a starting guess when the user gives none
# --------------------------------------------------------------------------------------------

def transient(flow, name: str, p: np.ndarray, state: np.ndarray | None, *, t0: float, backward: bool,
              mode0: str | None = None):
    """A transient in the direction of integration (:func:`saltation.orbits.start.transient`) from the
    shipped model's start state and with its length, in the mode ``mode0`` (``--mode0``; by default the
    model's domains give it); returns (trajectory, start state).  An autonomous model without a start state
    starts where its transient oscillates (:func:`saltation.orbits.start.oscillating_transient`: the origin,
    then unit states)."""
    system = flow.system
    values = dict(zip(system.parameter_names, map(float, p)))
    length_fn = SHIPPED[name].transient_length if name in SHIPPED else None
    length = length_fn(values) if (length_fn and system.is_autonomous) else None
    start = SHIPPED[name].start if name in SHIPPED else None
    if state is None and start is None and system.is_autonomous:
        try:
            traj, _ = start_guesses.oscillating_transient(flow, p, t0=t0, backward=backward, length=length,
                                                          mode0=mode0)
        except StartGuessError as exc:
            raise CommandError(f"{exc}; give a starting guess with --x0 and --period") from None
        return traj, traj.x0
    if state is None:
        state = np.array(start(values, backward) if start else np.zeros(system.n), dtype=float)
    try:
        traj = start_guesses.transient(flow, p, state, t0=t0, backward=backward, length=length, mode0=mode0)
    except StartGuessError as exc:
        raise CommandError(f"{exc}; give a starting guess with --x0") from None
    return traj, state


def estimate_period(traj) -> float:
    """Period estimate from a transient of an autonomous model (:func:`saltation.orbits.start.estimate_period`).

    Raises
    ------
    CommandError
        If the transient shows no oscillation (e.g. it settles to an equilibrium).
    """
    try:
        return start_guesses.estimate_period(traj)
    except StartGuessError as exc:
        raise CommandError(f"{exc}; give --period and a guess --x0") from None


# --------------------------------------------------------------------------------------------
# orbit
# --------------------------------------------------------------------------------------------

def orbit_to_dict(orbit, system: PiecewiseSystem) -> dict:
    """A JSON-ready description of a :class:`~saltation.orbits.shooting.PeriodicOrbit`."""
    mu = np.asarray(orbit.multipliers, dtype=complex)
    return {
        "model": system.name,
        "parameters": dict(zip(system.parameter_names, map(float, orbit.parameters))),
        "state_names": list(system.state_names),
        "state0": [float(v) for v in orbit.state0],
        "t0": float(orbit.t0),
        "period": float(orbit.period),
        "autonomous": bool(orbit.autonomous),
        "backward": bool(orbit.backward),
        "amplitude": float(orbit.amplitude),
        "half_peak_to_peak": float(orbit.half_peak_to_peak),
        "multipliers": multipliers_json(mu),
        "multiplier_magnitudes": ["inf" if not np.isfinite(m) else float(abs(m)) for m in mu],
        "stable": bool(orbit.stable),
        "events": [[str(e.surface), float(e.t)] for e in orbit.trajectory.events],
        "event_modes": [[e.mode_from, e.mode_to] for e in orbit.trajectory.events],
        "converged": bool(orbit.converged),
        "iterations": int(orbit.iterations),
        "residual_norm": float(orbit.residual_norm),
        "segments": int(orbit.segments),
        "mode0": orbit.mode0,
    }


def format_orbit(orbit, system: PiecewiseSystem) -> str:
    """A short human-readable table of an orbit."""
    from saltation.engine.flow import EventKind

    kind = "autonomous" if system.is_autonomous else f"forced, forcing period {system.period_expr}"
    rows: list[tuple[str, str]] = []
    rows.append(("model", f"{system.name} ({kind})"))
    rows.append(("parameters", ", ".join(f"{k} = {_fmt(v)}" for k, v in zip(system.parameter_names, orbit.parameters))))
    rows.append(("time", "backward (shooting in backward time)" if orbit.backward else "forward"))
    rows.append(("state0", ", ".join(f"{k} = {_fmt(v)}" for k, v in zip(system.state_names, orbit.state0))
                 + f"   at t0 = {_fmt(orbit.t0)}" + (f", in mode {orbit.mode0}" if orbit.mode0 is not None else "")))
    rows.append(("period", _fmt(orbit.period)))
    rows.append(("amplitude", f"{_fmt(orbit.amplitude)}   (max |{system.state_names[0]}| over the period)"))
    mu = np.asarray(orbit.multipliers, dtype=complex)
    texts = [_complex_text(m) for m in mu]
    width = max(len(s) for s in texts) if texts else 0
    for i, (m, s) in enumerate(zip(mu, texts)):
        mag = "inf" if not np.isfinite(m) else _fmt(abs(m))
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
        rows.append(("events" if i == 0 else "", f"{e.surface:<12} t = {_fmt(e.t):<16} {e.mode_from} -> {e.mode_to}{what}"))
    its = orbit.iterations
    rows.append(("Newton", f"converged in {its} iteration{'s' if its != 1 else ''}, residual {orbit.residual_norm:.1e}"))
    return "\n".join(f"{k:<12} {v}".rstrip() for k, v in rows)


def cmd_orbit(args: argparse.Namespace) -> int:
    """``saltation orbit``: find one periodic orbit of a shipped model and print it."""
    from saltation.orbits.shooting import find_periodic_orbit

    system = build_model(args.model)
    overrides = parse_sets(args.set, system)
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
    flow = make_flow(system)
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
    if args.json:
        print(json.dumps(orbit_to_dict(orbit, system)))
    else:
        print(format_orbit(orbit, system))
    return 0


def _paragraph(text: str, indent: str = "") -> str:
    return textwrap.fill(" ".join(text.split()), width=88, initial_indent=indent, subsequent_indent=indent)


def _orbit_epilog() -> str:
    parts = ["shipped models (states; parameters with their default values):"]
    for name, shipped in SHIPPED.items():
        system = shipped.factory()
        kind = "autonomous" if system.is_autonomous else f"forced, period {system.period_expr}"
        parts.append(_paragraph(f"{name}: {shipped.summary}; {kind}", "  "))
        parts.append(_paragraph(
            f"states {', '.join(system.state_names)}; "
            + " ".join(f"{k}={_fmt(v)}" for k, v in system.defaults.items()), "    "))
    parts += [
        "",
        _paragraph(
            f"""Without --x0, a transient is simulated from a default state ({TRANSIENT_PERIODS} forcing
            periods for forced models, about 50 oscillation periods for autonomous ones) in the
            direction of integration (with --backward it runs backward, and so approaches orbits
            that attract in backward time, such as infinitely unstable ones), and shooting starts
            from its end state. For autonomous models without --period, the period guess is the
            time between two repetitions of the transient's event sequence, or between crossings
            of the Poincare section x_1 = mid-range when it has no events."""
        ),
        "",
        _paragraph(
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
        _paragraph(
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


def _add_orbit_parser(sub) -> None:
    p = sub.add_parser(
        "orbit",
        help="find one periodic orbit of a shipped model and print it",
        description=_paragraph(
            """Find one periodic orbit of a shipped model by shooting (Newton on the period map, with
            the monodromy matrix and every saltation matrix as its Jacobian) from a guess, and print
            it with its Floquet multipliers."""
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog_factory=_orbit_epilog,
    )
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP.format(names=model_names()))
    p.add_argument(
        "--set", metavar="NAME=VALUE", action="append", default=[],
        help="override a parameter of the model (repeat for several), e.g. --set omega=0.7",
    )
    p.add_argument(
        "--x0", metavar="V1,V2,...",
        help="guess of the state at t0, one comma-separated number per state (write --x0=-1,0 or "
        "--x0 -1,0 for a negative first component); default: the end of a transient",
    )
    p.add_argument(
        "--t0", metavar="T", type=_finite, default=0.0,
        help="initial time, i.e. the phase of the forcing at state0 (default 0; reduced modulo the forcing period)",
    )
    p.add_argument(
        "--period", metavar="T", type=_positive("--period"),
        help=f"period guess for autonomous models, at least {MIN_PERIOD:g} (default: estimated from a transient); "
        "forced models take the forcing period (a --period must equal it)",
    )
    p.add_argument(
        "--backward", action="store_true",
        help="shoot in backward time: finds orbits that are unstable in forward time, including "
        "infinitely unstable ones (a multiplier 'inf')",
    )
    p.add_argument(
        "--segments", metavar="M", type=SEGMENTS_TYPE, default=1,
        help="shooting segments: 1 (default) is single shooting; M > 1 is multiple shooting with M nodes along the "
        f"period, at most {MAX_SEGMENTS}, for strongly unstable orbits (multipliers of 1e8 and more), long periods and large models",
    )
    p.add_argument("--mode0", metavar="NAME", default=None, help=MODE0_HELP)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.set_defaults(handler=cmd_orbit)


# --------------------------------------------------------------------------------------------
# continue
# --------------------------------------------------------------------------------------------

def _progress_bar(enabled: bool):
    """A tqdm progress callback ``(stage, count)`` (or None when disabled)."""
    if not enabled:
        return None, lambda: None
    from tqdm import tqdm

    from saltation.engine.codegen import build_watcher

    bar = tqdm(total=None, unit=" points", file=sys.stderr, dynamic_ncols=True, leave=False, mininterval=0.25, disable=None)
    if bar.disable:  # not a terminal: no bar, and a build says so in a line of its own
        return (lambda stage, count: None), bar.close
    stage_now = [""]

    def update(stage: str, _count: int) -> None:
        stage_now[0] = stage.rstrip(": ")
        bar.set_description_str(stage_now[0])
        bar.update(1)

    def watch(message: str | None, seconds: float) -> None:  # a one-time build, shown in the bar
        bar.set_description_str(f"{message} ({seconds:.0f} s)" if message else stage_now[0])
        bar.refresh()

    watching = build_watcher(watch)
    watching.__enter__()

    def close() -> None:
        watching.__exit__(None, None, None)
        bar.close()

    return update, close


def _special_points_text(records: list[dict]) -> str:
    from saltation.apps.paper import special_point_table

    return special_point_table(records) if records else "no special points located"


def periodic_start(args: argparse.Namespace, flow, overrides: dict[str, float], p: np.ndarray, x0: np.ndarray | None):
    """The shooting problem over ``--param`` and its first unknowns: a periodic orbit from ``--x0`` (or
    the end of a transient) and ``--period`` (or an estimate), forward or ``--backward``, starting in
    ``--mode0`` where it is given (and then every point of the branch)."""
    from saltation.orbits.shooting import MultipleShootingProblem, ShootingProblem, find_periodic_orbit

    system = flow.system
    period = args.period if system.is_autonomous else None  # checked by the caller (check_start_period)
    mode0 = check_mode0(args, system)
    if x0 is None or (system.is_autonomous and period is None):
        traj, _ = transient(flow, args.model, p, x0, t0=0.0, backward=args.backward, mode0=mode0)
        if x0 is None:  # the guess is the transient's end, in the mode it ends in
            x0, mode0 = traj.x1.copy(), None if mode0 is None else traj.mode1
        if system.is_autonomous and period is None:
            period = estimate_period(traj)
    segments = getattr(args, "segments", 1)
    orbit = find_periodic_orbit(flow, x0, parameters=overrides, period=period, backward=args.backward,
                                segments=segments, mode0=mode0)
    # a named start mode is kept along the branch: the orbit's own (its state may have moved off a surface)
    problem = ShootingProblem(flow, overrides, continuation_parameter=args.param, backward=args.backward,
                              mode0=None if mode0 is None else orbit.mode0)
    if segments > 1:  # multiple shooting: the unknowns are the orbit's nodes (and its period)
        nodes = np.asarray(orbit.nodes, dtype=float).ravel()
        return MultipleShootingProblem(problem, segments), (np.append(nodes, orbit.period) if system.is_autonomous
                                                            else nodes)
    return problem, problem.pack(orbit.state0, orbit.period if system.is_autonomous else None)


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


def cmd_continue(args: argparse.Namespace) -> int:
    """``saltation continue``: follow one branch of a shipped model and write its data and plot."""
    from saltation.output import io
    from saltation.output import plotting
    from saltation.special_points.continuation import Continuation
    from saltation.apps.diagram import distinct_special_points, follow_through_discontinuous_fold
    from saltation.orbits.shooting import EquilibriumProblem

    system = build_model(args.model)
    check_parameter(system, args.param, "--param")
    overrides = parse_sets(args.set, system)
    check_not_set(overrides, args.param, "--param")
    start, stop = float(args.start), float(args.stop)
    if start == stop:
        raise UsageError(f"--from and --to must differ, got {_fmt(start)} twice")
    settings = _step_settings(args, (start, stop))
    if args.equilibrium is not None:
        check_equilibrium_option(args, system)
    check_mode0(args, system)
    overrides[args.param] = start
    for flag, value in (("--to", stop), ("--from", start)):
        p0 = usable_parameters(system, overrides | {args.param: value}, f"{flag} {_fmt(value)}")
        if not system.is_autonomous:
            forcing_period_at(system, p0, f"{flag} {_fmt(value)}")
    check_start_period(args, system, p0, f"--from {_fmt(start)}")
    check_out_dir(args.out)
    flow = make_flow(system)
    p = flow.parameters(overrides)
    x0 = parse_vector(args.x0, system) if args.x0 is not None else None
    if x0 is not None:
        check_start_field(flow, x0, p, args.x0, 0.0, args.mode0)
    direction = 1 if stop > start else -1
    update, close = _progress_bar(not args.no_progress)
    counter = (lambda point: update(f"{args.model}: {args.param}", 0)) if update else None
    branches = []
    try:
        if args.equilibrium is not None:
            problem, u0 = equilibrium_start(args.equilibrium, flow, overrides, args.param, x0, start)
        else:
            problem, u0 = periodic_start(args, flow, overrides, p, x0)
        cont = Continuation(problem, settings)
        for point in cont.run(u0, start, direction=direction):
            if counter:
                counter(point)
        if args.equilibrium is not None:  # where an equilibrium reaches a switching surface
            from saltation.special_points.boundary_equilibria import boundary_equilibria, boundary_equilibria_of_mode

            found = (boundary_equilibria if args.equilibrium.startswith("sliding:") else boundary_equilibria_of_mode)(
                problem, cont.branch)
            cont.branch.special_points = sorted([*cont.branch.special_points, *found], key=lambda sp: sp.index)
        branches.append(cont.branch)
        if args.equilibrium is not None:
            branches += _through_boundary_equilibria(flow, overrides, args.param, settings, cont.branch,
                                                     sliding=args.equilibrium.startswith("sliding:"))
        else:
            branches += _asymmetric_branches(problem, cont.branch, settings)
        note = ""
        ended = [sp for sp in cont.branch.special_points
                 if sp.index >= len(cont.branch.points) - 1 and sp.limits.value == "on_surface"]
        if ended and cont.branch.stop_reason is not None and cont.branch.stop_reason.name == "MIN_STEP":
            note = (f"the branch ended at a {ended[0].kind.value} at {args.param} = {ended[0].parameter:.10g}, where its "
                    f"orbit lies on {ended[0].touch_surface} all round")
        elif cont.branch.stop_reason is not None and cont.branch.stop_reason.name == "MIN_STEP" and not args.backward \
                and args.equilibrium is None and args.segments == 1:
            try:
                unstable, _fold = follow_through_discontinuous_fold(cont, settings=settings, progress=counter)
                branches.append(unstable)
                note = "the branch ended at a discontinuous fold; its continuation was followed in backward time"
            except SaltationError as exc:
                note = f"the branch ended where the corrector failed ({exc})"
    finally:
        close()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"{system.name}_{args.param}"
    for k, br in enumerate(branches):
        suffix = "" if k == 0 else f"_{k}"
        io.save_branch_json(br, out / f"{stem}_branch{suffix}.json")
        io.save_branch_csv(br, out / f"{stem}_branch{suffix}.csv")
    records = [io.special_point_record(sp, system.name, args.param) for sp in distinct_special_points(branches)]
    io.save_special_points_json(records, out / f"{stem}_special_points.json")
    plotting.save_figure(plotting.plot_response(branches), out / f"{stem}_diagram")
    total = sum(len(b) for b in branches)
    reasons = "; ".join(b.stop_reason.value for b in branches if b.stop_reason is not None)
    print(f"{total} point{'s' if total != 1 else ''} on {len(branches)} branch{'es' if len(branches) != 1 else ''} of "
          f"{system.name} over {args.param}; stopped: {reasons}")
    if note:
        print(note)
    print(_special_points_text(records))
    print(f"written to {out}/{stem}_*")
    return 0


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
                        ("--segments", args.segments != 1), ("--mode0", getattr(args, "mode0", None) is not None)):
        if given:
            raise UsageError(f"{flag} does not apply to --equilibrium (an equilibrium has no period and no "
                             "direction of time)")


def equilibrium_start(which: str, flow, overrides: dict, parameter: str, x0, start: float):
    """The problem and first point of an equilibrium branch: ``which`` is a mode (its equilibria) or
    ``sliding:SURFACE`` (pseudo-equilibria), ``x0`` the guess (the origin when None)."""
    from saltation.orbits.shooting import EquilibriumProblem

    guess = x0 if x0 is not None else np.zeros(flow.system.n)
    if which.startswith("sliding:"):
        from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem, find_pseudo_equilibrium

        surface = which.partition(":")[2]
        first = find_pseudo_equilibrium(flow, surface, guess, parameters=flow.parameters(overrides))
        problem = PseudoEquilibriumProblem(flow, surface, first.modes, overrides, continuation_parameter=parameter)
        return problem, PseudoEquilibriumProblem.unknowns(first)
    problem = EquilibriumProblem(flow, which, overrides, continuation_parameter=parameter)
    return problem, problem.solve(guess, start).state


def _asymmetric_branches(problem, branch, settings) -> list:
    """From each symmetry breaking of a branch of symmetric orbits, the branch of asymmetric orbits born there
    (one of each mirror pair; a branch that meets the symmetric orbits again at another symmetry breaking
    is not started again from there).  A branch that cannot start is left out."""
    from saltation.branches.branch import SpecialPointKind
    from saltation.orbits.shooting import ShootingProblem
    from saltation.special_points.branch_switching import follow_asymmetric_branch

    if not isinstance(problem, ShootingProblem):
        return []
    others, reached = [], []
    for sp in branch.special_points:
        if sp.kind is not SpecialPointKind.SYMMETRY_BREAKING:
            continue
        if any(abs(sp.parameter - lam) <= 1e-8 * max(1.0, abs(lam)) for lam in reached):
            continue
        try:
            side = follow_asymmetric_branch(problem, sp, settings=settings,
                                            label=f"asymmetric, from {problem.lam_name} = {sp.parameter:.9g}")
        except SaltationError:
            continue
        reached += [p.parameter for p in side.special_points if p.kind is SpecialPointKind.SYMMETRY_BREAKING]
        others.append(side)
    return others


def _through_boundary_equilibria(flow, overrides: dict, parameter: str, settings, branch, *, sliding: bool) -> list:
    """From each boundary equilibrium of an equilibrium branch, the other branch through it, both ways: a mode's
    equilibria from a branch of pseudo-equilibria, the pseudo-equilibria on the surface from a mode's branch
    (where the surface slides there).  A branch that cannot start is left out."""
    from saltation.branches.branch import SpecialPointKind
    from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem, find_pseudo_equilibrium
    from saltation.orbits.shooting import EquilibriumProblem
    from saltation.special_points.continuation import Continuation

    others = []
    for sp in branch.special_points:
        if sp.kind is not SpecialPointKind.BOUNDARY_EQUILIBRIUM:
            continue
        values = overrides | {parameter: sp.parameter}
        try:
            if sliding:  # from the pseudo-equilibria to the mode's equilibria
                problem = EquilibriumProblem(flow, sp.touch_mode, values, continuation_parameter=parameter)
                u0 = problem.solve(sp.state, sp.parameter).state
            else:
                point = find_pseudo_equilibrium(flow, sp.touch_surface, sp.state, parameters=flow.parameters(values))
                problem = PseudoEquilibriumProblem(flow, sp.touch_surface, point.modes, values,
                                                   continuation_parameter=parameter)
                u0 = PseudoEquilibriumProblem.unknowns(point)
            for direction in (1, -1):
                cont = Continuation(problem, settings)
                for _ in cont.run(u0, sp.parameter, direction=direction):
                    pass
                cont.branch.label = f"equilibrium of {sp.touch_mode}" if sliding else f"pseudo-equilibria on {sp.touch_surface}"
                if len(cont.branch) > 1:
                    others.append(cont.branch)
        except SaltationError:
            continue
    return others


def _add_continue_parser(sub) -> None:
    p = sub.add_parser(
        "continue",
        help="follow a branch of periodic orbits (or equilibria) over a parameter; write CSV/JSON and a plot",
        description=_paragraph(
            """Follow one branch of periodic orbits of a shipped model by pseudo-arclength continuation
            in one parameter, from --from towards --to, through the corners of the branch, locating
            smooth and discontinuous bifurcations (set-valued Floquet multipliers). A forward-time
            branch that ends at a discontinuous fold is followed beyond it by backward-time shooting.
            Writes MODEL_PARAM_branch.json/.csv, MODEL_PARAM_special_points.json and a diagram
            (PNG and PDF) into --out."""
        ),
    )
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP.format(names=model_names()))
    p.add_argument("--param", metavar="NAME", required=True, help="the continuation parameter")
    p.add_argument("--from", dest="start", metavar="V", type=_finite, required=True, help="start value of the parameter")
    p.add_argument("--to", dest="stop", metavar="V", type=_finite, required=True, help="end value of the parameter")
    p.add_argument(
        "--set", metavar="NAME=VALUE", action="append", default=[],
        help="override another parameter of the model (repeat for several)",
    )
    p.add_argument("--x0", metavar="V1,V2,...", help="guess of the start state (default: the end of a transient)")
    p.add_argument("--period", metavar="T", type=_positive("--period"), help=PERIOD_HELP)
    p.add_argument("--backward", action="store_true", help="shoot in backward time (infinitely unstable branches)")
    p.add_argument("--mode0", metavar="NAME", default=None, help=MODE0_HELP + "; every point of the branch starts in it")
    p.add_argument("--equilibrium", metavar="MODE", help="continue an equilibrium of this mode instead of periodic orbits "
                   "(autonomous models); sliding:SURFACE continues the pseudo-equilibria of the sliding motion on "
                   "that surface")
    p.add_argument("--out", metavar="DIR", default=".", help="output directory (default: the current one)")
    _add_step_options(p)
    p.add_argument(
        "--segments", metavar="M", type=SEGMENTS_TYPE, default=1,
        help="shooting segments: 1 (default) is single shooting; M > 1 is multiple shooting with M nodes along the "
        f"period, at most {MAX_SEGMENTS}, for strongly unstable orbits (multipliers of 1e8 and more), long periods and large models; the branch's multipliers come from the segments' matrices (periodic Schur decomposition)",
    )
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    p.set_defaults(handler=cmd_continue)


# --------------------------------------------------------------------------------------------
# locus
# --------------------------------------------------------------------------------------------

def _range(option: str):
    def parse(text: str) -> tuple[float, float]:
        parts = text.split(",")
        if len(parts) != 2:
            raise argparse.ArgumentTypeError(f"expected two numbers A,B, got {text!r}")
        a, b = (_finite(v) for v in parts)
        if a == b:
            raise argparse.ArgumentTypeError(f"the two ends must differ, got {text!r}")
        return a, b

    return parse


def cmd_locus(args: argparse.Namespace) -> int:
    """``saltation locus``: continue the special points of one kind of a branch in a second parameter."""
    from saltation.output import plotting
    from saltation.branches.branch import SpecialPointKind
    from saltation.special_points.continuation import Continuation
    from saltation.output.io import write_json
    from saltation.special_points.loci import follow_locus

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
    (start, stop), (lo2, hi2) = args.range, args.range2
    overrides = parse_sets(args.set, system)
    check_not_set(overrides, args.param, "--param")
    overrides[args.param] = start
    if not system.is_autonomous:
        for value in (start, stop):
            forcing_period_at(system, system.parameter_vector(overrides | {args.param: value}),
                              f"--range {_fmt(start)},{_fmt(stop)}")
    check_start_period(args, system, system.parameter_vector(overrides), f"{args.param} = {_fmt(start)}")
    if args.out is not None:
        check_out_dir(args.out)
    flow = make_flow(system)
    p = flow.parameters(overrides)
    if not lo2 <= p[system.parameter_index(args.param2)] <= hi2 and not hi2 <= p[system.parameter_index(args.param2)] <= lo2:
        raise UsageError(f"the value of {args.param2} ({p[system.parameter_index(args.param2)]:g}) lies outside --range2")
    x0 = parse_vector(args.x0, system) if args.x0 is not None else None
    if x0 is not None:
        check_start_field(flow, x0, p, args.x0, 0.0, args.mode0)
    settings = _step_settings(args, (start, stop))
    update, close = _progress_bar(not args.no_progress)
    counter = (lambda point: update(f"{args.model}: {args.param}", 0)) if update else None
    try:
        if args.equilibrium is not None:
            problem, u0 = equilibrium_start(args.equilibrium, flow, overrides, args.param, x0, start)
        else:
            problem, u0 = periodic_start(args, flow, overrides, p, x0)
        cont = Continuation(problem, settings)
        for point in cont.run(u0, start, direction=1 if stop > start else -1):
            if counter:
                counter(point)
        curve_settings = _step_settings(args, (lo2, hi2))
        counter2 = (lambda point: update(f"{args.model}: {kind.value} over {args.param2}", 0)) if update else None
        if args.equilibrium is not None:
            from saltation.special_points.boundary_equilibria import (
                boundary_equilibria,
                boundary_equilibria_of_mode,
                follow_boundary_equilibrium_curve,
            )

            find = boundary_equilibria if args.equilibrium.startswith("sliding:") else boundary_equilibria_of_mode
            loci = [follow_boundary_equilibrium_curve(flow, sp, args.param, args.param2, curve_settings.bounds,
                                                      parameters=overrides, settings=curve_settings, progress=counter2)
                    for sp in find(problem, cont.branch)]
        else:
            points = [sp for sp in cont.branch.special_points if sp.kind is kind]
            reason = cont.branch.stop_reason
            if not points and reason is not None and reason.name != "PARAMETER_BOUND":
                found = ", ".join(f"{sp.kind.value} at {sp.parameter:.8g}" for sp in cont.branch.special_points) or "none"
                detail = f" ({cont.branch.stop_detail})" if cont.branch.stop_detail else ""
                raise SaltationError(
                    f"no {kind.value} point on the branch of {system.name}: it stopped at {args.param} = "
                    f"{cont.branch.points[-1].parameter:.10g} before the end of --range ({reason.value}{detail}); "
                    f"special points found: {found}. Try a larger --max-points, another --ds-max or --range")
            # with --segments the curves' defining systems shoot by segments too
            loci = [follow_locus(problem, sp, args.param2, curve_settings.bounds, settings=curve_settings,
                                 progress=counter2)
                    for sp in points]
    finally:
        close()
    record = {
        "model": system.name, "kind": kind.value, "param": args.param, "param2": args.param2,
        "curves": [locus.record() for locus in loci],
    }
    if args.out is not None:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        stem = out / f"{system.name}_{kind.value}_{args.param}_{args.param2}_locus"
        write_json(record, stem.with_suffix(".json"))
        plotting.save_figure(plotting.plot_loci(loci, title=f"{system.name}: {kind.value}"), stem)
    if args.json:
        print(json.dumps(record))
    else:
        print(f"{len(loci)} curve(s) of {kind.value} points of {system.name} in ({args.param}, {args.param2})")
        for k, locus in enumerate(loci):
            print(f"  curve {k}: {len(locus.points)} points; {locus.stop_reason}")
            for c in locus.special_points:
                print(f"    {c.sides[0]} -> {c.sides[1]} at {args.param} = {c.parameter:.8g}, {args.param2} = "
                      f"{c.second_parameter:.8g} (within {c.accuracy:.2g}, {c.status.value})")
        if args.out is not None:
            print(f"written to {stem}.json (.png, .pdf)")
    return 0


def _add_step_options(p, what: str = "") -> None:
    """``--ds``, ``--ds-max`` and ``--max-points`` (of the branch, and of each curve where ``what`` says so)."""
    p.add_argument("--ds", metavar="S", type=_positive("--ds", MIN_STEP, " (the smallest step of a continuation)"),
                   default=None, help=f"initial arclength step{what}, at most --ds-max (default 0.01, or --ds-max if smaller)")
    p.add_argument("--ds-max", metavar="S", type=_positive("--ds-max", MIN_STEP, " (the smallest step of a continuation)"),
                   default=0.02, help=f"largest step{what} (default 0.02)")
    p.add_argument("--max-points", metavar="N", type=_integer("--max-points", 1), default=2000,
                   help=f"largest number of points{what}, a positive integer (default 2000)")


def _step_settings(args, bounds: tuple[float, float]):
    """The continuation settings of ``--ds``, ``--ds-max`` and ``--max-points`` over ``bounds``."""
    from saltation.special_points.continuation import ContinuationSettings

    if args.ds is not None and args.ds > args.ds_max:
        raise UsageError(f"--ds {_fmt(args.ds)} exceeds --ds-max {_fmt(args.ds_max)}: the first step cannot be "
                         "longer than the largest")
    ds = min(0.01, args.ds_max) if args.ds is None else args.ds
    return ContinuationSettings(ds=ds, ds_max=args.ds_max, bounds=(min(bounds), max(bounds)),
                                max_points=args.max_points, ds_min=MIN_STEP)


def _add_locus_parser(sub) -> None:
    p = sub.add_parser(
        "locus",
        help="continue the special points of one kind of a branch in a second parameter (two-parameter curves)",
        description=_paragraph(
            """Follow the branch of periodic orbits of MODEL from the start state over --param in --range
            (as 'continue' does), take every special point of kind --kind on it, and continue each as a
            curve in (--param, --param2) with --param2 in --range2, in both directions, by its defining
            system: grazing and corner collisions by periodicity plus tangency, folds and period
            doublings by periodicity plus a bordered test function. Where the kind of a corner changes
            along its curve (a codimension-two point) the curve records it. With --kind
            boundary_equilibrium and --equilibrium MODE (or sliding:SURFACE) the branch is of equilibria, and
            each boundary equilibrium is continued by the mode's equilibrium plus h = 0. --json prints
            {"model", "kind", "param", "param2", "curves": [{"points": [[value of param, value of
            param2], ...], "stop_reason", "special_points"}]}; --out writes the same and a plot."""
        ),
    )
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP.format(names=model_names()))
    p.add_argument("--kind", metavar="KIND", required=True,
                   help="a SpecialPointKind value: fold, period_doubling, grazing, discontinuous_fold, nonsmooth_no_crossing, ...")
    p.add_argument("--param", metavar="NAME", required=True, help="the parameter of the branch")
    p.add_argument("--range", metavar="A,B", type=_range("--range"), required=True, help="the branch from A towards B")
    p.add_argument("--param2", metavar="NAME2", required=True, help="the second parameter")
    p.add_argument("--range2", metavar="C,D", type=_range("--range2"), required=True, help="the range of the second parameter")
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[], help="override a parameter (repeat for several)")
    p.add_argument("--x0", metavar="V1,V2,...", help="guess of the start state (default: the end of a transient)")
    p.add_argument("--period", metavar="T", type=_positive("--period"), help=PERIOD_HELP)
    p.add_argument("--backward", action="store_true", help="shoot in backward time")
    p.add_argument("--mode0", metavar="NAME", default=None, help=MODE0_HELP)
    p.add_argument("--out", metavar="DIR", help="write the curves (JSON) and their plot here")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--segments", metavar="M", type=SEGMENTS_TYPE, default=1,
        help="shooting segments: 1 (default) is single shooting; M > 1 is multiple shooting with M nodes along the "
        f"period, at most {MAX_SEGMENTS}, for strongly unstable orbits (multipliers of 1e8 and more), long periods and large models (for the branch; the curves' defining systems use single shooting)",
    )
    p.add_argument("--equilibrium", metavar="MODE",
                   help="with --kind boundary_equilibrium: the branch is of this mode's equilibria (or, as "
                   "sliding:SURFACE, of the pseudo-equilibria on that surface), and its boundary equilibria are "
                   "continued by the mode's equilibrium plus h = 0")
    _add_step_options(p, " of the branch and of each curve")
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    p.set_defaults(handler=cmd_locus)


# --------------------------------------------------------------------------------------------
# paper
# --------------------------------------------------------------------------------------------

def cmd_paper(args: argparse.Namespace) -> int:
    """``saltation paper``: reproduce Figures 3, 4, 6 and 7 with their data."""
    from saltation.apps import paper

    check_out_dir(args.out)
    settings = paper.PaperSettings(ds=args.ds_max, ds_max=args.ds_max)
    update, close = _progress_bar(not args.no_progress)
    try:
        results = paper.compute(settings, progress=update)
    finally:
        close()
    written = paper.write(results, Path(args.out))
    print(_special_points_text(results.special_point_records()))
    if results.smoothing:
        print()
        print("the block-on-belt model smoothed (saltation.model.regularize), its stable branch followed in forward time:")
        print(paper.smoothing_table(results.smoothing))
    print(f"{len(written)} files written to {args.out}: figures fig3, fig4, fig6, fig7, fig8 (PNG and PDF), branch "
          "data (JSON; CSV, each with its .meta.json), the phase plane's curves (NPZ), special_points.json and "
          "smoothing_table.json")
    return 0


def _add_paper_parser(sub) -> None:
    p = sub.add_parser(
        "paper",
        help="reproduce Figures 3, 4, 6 and 7 of 'Fold bifurcations in discontinuous systems'",
        description=_paragraph(
            """Compute the response curve of the trilinear spring system (Figs. 3 and 4: corners at
            w_A and w_B, the discontinuous fold at w_B, the smooth fold of the hardened peak), the
            phase plane of the block-on-belt system (Fig. 6) and its bifurcation diagram with the
            infinitely unstable branch found by backward-time shooting (Fig. 7). Writes the figures
            (PNG and PDF), the branch data (JSON and CSV) and DIR/special_points.json, and prints the
            located special points."""
        ),
    )
    p.add_argument("--out", metavar="DIR", required=True, help="output directory")
    p.add_argument(
        "--ds-max", metavar="S", default=0.015,
        type=_positive("--ds-max", PAPER_MIN_DS_MAX, " (a branch of the paper has at most 5000 points)"),
        help=f"largest continuation step: smaller gives denser diagrams (default 0.015, about 400 points in Fig. 3; "
             f"at least {PAPER_MIN_DS_MAX:g})",
    )
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    p.set_defaults(handler=cmd_paper)


# --------------------------------------------------------------------------------------------
# sweep
# --------------------------------------------------------------------------------------------

def sweep_start(args: argparse.Namespace, system: PiecewiseSystem):
    """The start of a sweep's values and the rule using it: ``(x0, SweepStart)``.

    ``--x0`` gives one state; without it a shipped model with a ``start`` function starts each value from
    that function of the value's own parameters, and any other model from zeros.  ``--start`` chooses the
    rule; by default ``own`` with a start function, ``previous`` otherwise.
    """
    from saltation.apps.sweeps import SweepStart

    if args.x0 is not None:
        x0 = parse_vector(args.x0, system)
    else:
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
    from saltation.output import plotting
    from saltation.apps.sweeps import SweepStart, sweep

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
        base = system.parameter_vector(overrides)
        for v in values:
            for v2 in (values2 if values2 is not None else [None]):
                p = base.copy()
                p[system.parameter_index(args.param)] = v
                where = f"--param {args.param} = {_fmt(v)}"
                if v2 is not None:
                    p[system.parameter_index(args.param2)] = v2
                    where += f", --param2 {args.param2} = {_fmt(v2)}"
                forcing_period_at(system, p, where)
    x0, rule = sweep_start(args, system)
    mode0 = check_mode0(args, system)
    check_out_dir(args.out)
    flow = make_flow(system)  # compile (or load) here, with the notice, before the workers load it from the cache
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
            lyapunov=args.lyapunov, mode0=mode0,
        )
    finally:
        if client is not None:
            client.close()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"{system.name}_{args.param}_sweep"
    result.save(stem.with_suffix(".json"))
    plotting.save_figure(result.plot(), stem)
    kind = "Poincare section points" if not system.is_autonomous else "maxima of x_1"
    how = "its own start" if rule is SweepStart.OWN else "the previous value's final state"
    print(f"{sum(len(result.at(k)) for k in range(args.num))} {kind} at {args.num} values of {args.param} "
          f"(each from {how}); written to {stem}.json/.png/.pdf")
    if result.failures:
        print(f"{len(result.failures)} value(s) failed: " + "; ".join(f"{args.param} = {_fmt(v)}: {m}"
                                                                     for v, m in result.failures[:3])
              + ("; ..." if len(result.failures) > 3 else ""))
    return 0


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
    from saltation.output import plotting
    from saltation.apps.sweeps import period_map

    max_period = 16 if args.max_period is None else args.max_period
    grid = period_map(
        system, args.param, values, args.param2, values2, max_period=max_period, periods=args.periods,
        transient=args.transient, x0=x0, start=rule, parameters=overrides, workers=args.workers, client=client,
        lyapunov=args.lyapunov, mode0=check_mode0(args, system),
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"{system.name}_{args.param}_{args.param2}_map"
    grid.save(stem.with_suffix(".json"))
    plotting.save_figure(grid.plot(), stem)
    found = int((grid.periods > 0).sum())
    print(f"{grid.periods.size} cells ({args.num} x {args.num2}): a period up to {max_period} found in {found}, "
          f"none in {int((grid.periods == 0).sum())}, failed in {int((grid.periods < 0).sum())}; "
          f"written to {stem}.json/.png/.pdf")
    return 0


def _add_sweep_parser(sub) -> None:
    p = sub.add_parser(
        "sweep",
        help="brute-force diagram: simulate at each parameter value and plot the sampled attractor",
        description=_paragraph(
            """Simulate a shipped model at --num parameter values between --from and --to, discard a
            transient, and sample the attractor: the Poincare section x(t0 + k T) for forced models,
            the maxima of x_1 for autonomous ones. Each value starts from its own start (--start own:
            --x0, or the shipped model's start at that value's parameters) or from the previous value's
            final state (--start previous); the default is own where the model has a start of its own
            and --x0 is not given, previous otherwise. Uses every local core, or a Dask cluster
            (--scheduler). Writes MODEL_PARAM_sweep.json and a plot (PNG, PDF) into --out. With
            --param2 NAME --from2 V --to2 V --num2 N, a grid of two parameters whose cells record the
            period of the attractor in forcing periods (or none found: chaos or a period longer
            than --max-period), drawn as a map: MODEL_PARAM_PARAM2_map.json and its plot."""
        ),
    )
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP.format(names=model_names()))
    p.add_argument("--param", metavar="NAME", required=True, help="the swept parameter")
    p.add_argument("--from", dest="start", metavar="V", type=_finite, required=True, help="first value")
    p.add_argument("--to", dest="stop", metavar="V", type=_finite, required=True, help="last value")
    p.add_argument("--num", metavar="N", type=_integer("--num", 1), required=True,
                   help="number of values (1 takes --from = --to)")
    p.add_argument("--periods", metavar="P", type=_integer("--periods", 1), default=None,
                   help="periods sampled per value (default 200; a map: 4 times --max-period)")
    p.add_argument("--transient", metavar="Q", type=_integer("--transient", 0), default=100,
                   help="periods discarded first (default 100)")
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[], help="override another parameter")
    p.add_argument("--x0", metavar="V1,V2,...",
                   help="start state (default: the shipped model's start at each value's own parameters, if it has "
                        "one, else zeros)")
    p.add_argument("--mode0", metavar="NAME", default=None,
                   help=MODE0_HELP + "; a value that starts from the previous one's final state goes on in its final mode")
    p.add_argument("--start", dest="start_rule", choices=("own", "previous"), default=None,
                   help="where each value starts: 'own' from the start (--x0, or the model's start at that value's "
                        "parameters), 'previous' from the previous value's final state, following an attractor while "
                        "it lasts (default: own for a shipped model's start, previous otherwise)")
    p.add_argument("--workers", metavar="N", type=_integer("--workers", 1), default=None,
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
    p.add_argument("--from2", dest="start2", metavar="V", type=_finite, default=None, help="first value of --param2")
    p.add_argument("--to2", dest="stop2", metavar="V", type=_finite, default=None, help="last value of --param2")
    p.add_argument("--num2", metavar="N", type=_integer("--num2", 1), default=None, help="number of values of --param2")
    p.add_argument("--max-period", dest="max_period", metavar="K", type=_integer("--max-period", 1), default=None,
                   help="the longest period (in forcing periods) a map looks for (default 16)")
    p.add_argument("--out", metavar="DIR", default=".", help="output directory (default: the current one)")
    p.set_defaults(handler=cmd_sweep)


# --------------------------------------------------------------------------------------------
# lyapunov
# --------------------------------------------------------------------------------------------

def _exponent_json(value: float) -> float | str:
    return value if math.isfinite(value) else ("-inf" if value < 0 else ("inf" if value > 0 else "nan"))


def cmd_lyapunov(args: argparse.Namespace) -> int:
    """``saltation lyapunov``: the Lyapunov exponents of a run, through the saltation matrices of its events."""
    from saltation.orbits.lyapunov import lyapunov_exponents, plan_run

    system = build_model(args.model)
    overrides = parse_sets(args.set, system)
    flow = make_flow(system)
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


def _add_lyapunov_parser(sub) -> None:
    p = sub.add_parser(
        "lyapunov",
        help="the Lyapunov exponents of a model's motion",
        description=_paragraph(
            """Integrate a model with its variational equation, jumped by the saltation matrix at every
            event, and reorthonormalise the fundamental matrix at intervals (QR): the Lyapunov exponents,
            per unit time, with an estimate of each one's error from the spread over ten blocks of the run.
            A direction collapsed by a singular saltation matrix (the start of a sliding motion or a stick
            phase) has the exponent -inf. A forced model's time direction is not counted."""
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("model", metavar="MODEL", help=MODEL_HELP.format(names=model_names()))
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[], help="override a parameter (repeat for several)")
    p.add_argument("--x0", metavar="V1,V2,...", help="the state the run starts from (default: the model's start)")
    p.add_argument("--time", metavar="T", type=_positive("--time"), required=True,
                   help="the averaging time: at least 5 forcing periods (an autonomous model: 5 time units), so that "
                   "each of the ten blocks covers half a one and their spread measures the error, and at most "
                   "a million of them (each one a variational integration and a QR factorisation)")
    p.add_argument("--transient", metavar="T", type=_non_negative("--transient"), default=0.0,
                   help="time integrated first, not averaged (default 0)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (model, parameters, exponents, accuracy, time, transient, interval, state_end)")
    p.set_defaults(handler=cmd_lyapunov)


# --------------------------------------------------------------------------------------------
# the program
# --------------------------------------------------------------------------------------------

#: Subcommands in the order of ``saltation --help``: each adds its parser to the subparsers
#: action and sets ``handler`` to its ``cmd_<name>(args) -> int``.
SUBCOMMANDS: list[Callable[[argparse._SubParsersAction], None]] = [
    _add_orbit_parser,
    _add_continue_parser,
    _add_locus_parser,
    _add_paper_parser,
    _add_sweep_parser,
    _add_lyapunov_parser,
]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    from saltation import __version__

    parser = _Parser(
        prog=PROG,
        description=(
            "saltation: bifurcation analysis of periodic solutions of discontinuous (piecewise-smooth) "
            "systems, with saltation matrices, shooting in forward and backward time and Floquet "
            "multipliers, after the paper 'Fold bifurcations in discontinuous systems'."
        ),
        epilog=f"Run '{PROG} SUBCOMMAND --help' for the options of a subcommand. Shipped models: {model_names()}.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    sub = parser.add_subparsers(dest="command", metavar="SUBCOMMAND", title="subcommands", parser_class=_Parser)
    for add in SUBCOMMANDS:
        add(sub)
    for subparser in sub.choices.values():  # also after the subcommand; SUPPRESS keeps a --debug given before it
        subparser.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP)
    return parser


DEBUG_HELP = "let a failed computation or an unexpected error through with its Python traceback (instead of one line)"


def _join_negative_values(argv: list[str], options: Sequence[str] = ("--x0", "--range", "--range2")) -> list[str]:
    """Let ``--x0 -1,0`` (and ``--range -1,2``) through argparse (which would take ``-1,0`` for an option)."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        if argv[i] in options and i + 1 < len(argv) and argv[i + 1].startswith("-") and argv[i + 1][1:2] not in ("", "-") \
                and not argv[i + 1][1:2].isalpha():
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
            continue
        out.append(argv[i])
        i += 1
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status.

    Every failure is one line ``saltation: error: ...`` on stderr: bad usage (a bad ``--out``
    included, found before computing) exits with 2, a failed computation (a
    :class:`~saltation.errors.SaltationError` or ``ValueError``) with 1, an OS error while writing
    the results (a full disk: ``FILE: REASON``) with 1, and any other exception, a bug, with 1 as
    ``internal error: TYPE: MESSAGE``.  With ``--debug`` (before or after the subcommand) a failed
    computation, an OS error or a bug is raised instead, with its traceback.  A standard output
    closed by its reader (``| head``) ends the command quietly with 141 (128 + SIGPIPE).
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv[: argv.index("--")] if "--" in argv else "--debug" in argv  # before parsing succeeds
    try:
        parser = build_parser()
        args = parser.parse_args(_join_negative_values(argv))
        debug = bool(getattr(args, "debug", False))
        if getattr(args, "handler", None) is None:
            raise UsageError(f"choose a subcommand ({', '.join(parser._subparsers._group_actions[0].choices)}); "
                             f"see '{PROG} --help'")
        status = int(args.handler(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not in the interpreter's last flush
        return status
    except SystemExit as exc:  # --help, --version
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except UsageError as exc:
        _fail(exc)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError as exc:
        if _stdout_closed():  # the reader of our output has gone (| head): nothing to say, nowhere to say it
            _silence_stdout()
            return 141
        if debug:
            raise
        _fail(_os_error_text(exc))
        return 1
    except OSError as exc:  # writing the results failed (a full disk, a folder removed meanwhile): one line
        if debug:
            raise
        _fail(_os_error_text(exc))
        return 1
    except (SaltationError, ValueError) as exc:
        if debug:
            raise
        _fail(exc)
        return 1
    except Exception as exc:  # a bug: one line, unless --debug asks for the traceback
        if debug:
            raise
        text = " ".join(str(exc).split())
        _fail(f"internal error: {type(exc).__name__}{': ' + text if text else ''} "
              f"(run with --debug for the traceback)")
        return 1


def run() -> None:
    """The ``saltation`` program (and ``python -m saltation``): :func:`main`, then a quick exit.

    The interpreter's own teardown frees numba's compiled code and type system object by object, which
    takes over half a second after the work is done.  By then every result is written and closed, so the
    program runs the exit handlers (``atexit``: temporary folders, logging, a Dask client's shutdown),
    flushes its streams and ends the process at once, with :func:`main`'s status.  Where another thread
    is still running, or the interpreter offers no way to run the handlers, it exits the usual way.
    """
    status = main()
    run_handlers = getattr(atexit, "_run_exitfuncs", None)  # (CPython's; what the usual exit calls)
    if run_handlers is None or any(t.is_alive() and not t.daemon for t in threading.enumerate()
                                   if t is not threading.main_thread()):
        sys.exit(status)
    run_handlers()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # (a reader that has gone: nothing more to say, nowhere to say it)
            pass
    os._exit(status)


def _fail(exc: BaseException | str) -> None:
    """Print ``saltation: error: MESSAGE`` as one line on stderr."""
    message = (" ".join(str(exc).split()) or type(exc).__name__) if isinstance(exc, BaseException) else exc
    print(f"{PROG}: error: {message}", file=sys.stderr)


if __name__ == "__main__":  # pragma: no cover
    run()
