"""Finding and loading models: a shipped model by name, a model file ``PATH.py:NAME``, and its flow."""

from __future__ import annotations

import sys
import threading
from pathlib import Path
from typing import TYPE_CHECKING

from saltation.apps.cli.errors import PROG, UsageError
from saltation.errors import SaltationError

if TYPE_CHECKING:
    from saltation.model.system import PiecewiseSystem

#: The shipped models the command line names, in the order of :data:`saltation.models.SHIPPED` (written out
#: here so that help and ``--version`` do not build the models: a test holds the two equal).
SHIPPED_NAMES = ("trilinear", "block_on_belt", "impact_oscillator", "bouncing_ball", "friction_oscillator",
                 "relay_feedback", "buck_converter", "two_mass_stops", "tilted_relay", "symmetric_impact_oscillator",
                 "sliding_mode")


def model_names() -> str:
    """The shipped models' names, as help and messages list them."""
    return ", ".join(SHIPPED_NAMES)


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
    from saltation.models import SHIPPED

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
    from saltation.model.system import PiecewiseSystem

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
