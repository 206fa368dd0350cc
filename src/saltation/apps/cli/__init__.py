"""Command line interface: ``saltation SUBCOMMAND ...``.

One module per subcommand, each with its ``cmd_<name>(args) -> int`` and an ``add_parser`` registered in
:data:`SUBCOMMANDS`; shipped models are looked up in :data:`saltation.models.SHIPPED`.  Every failure of a
subcommand becomes one line ``saltation: error: ...`` on stderr and a non-zero exit status:

* 0: success;
* 1: the computation failed (integration, Newton, ...), or writing its files did (a full disk: the
  message names the file; files are written atomically, so an old file of that name is untouched);
* 2: bad usage (unknown model, parameter or option, malformed value, an ``--out`` that is a file or
  cannot be created or written in);
* 141 (128 + SIGPIPE): standard output was closed early (``saltation orbit ... | head -1``): no message.

The output folder (``--out``) is created and tried with a test file before any computation.
Numeric options are checked before any computation (:mod:`~saltation.apps.cli.options`).  An
unexpected exception (a bug, not one of saltation's errors) is one line too, ``internal error: TYPE:
MESSAGE``, with exit status 1; the global option ``--debug`` lets every exception through with its
traceback instead.

The modules:

* :mod:`~saltation.apps.cli.errors`: the program's name, :class:`UsageError` and :class:`CommandError`;
* :mod:`~saltation.apps.cli.models`: finding and loading models, model files, a model's flow;
* :mod:`~saltation.apps.cli.options`: the options' converters and checks, and the arguments several
  subcommands share;
* :mod:`~saltation.apps.cli.starts`: transients with the shipped models' hints, the first point of a branch;
* :mod:`~saltation.apps.cli.text`: number formatting, the special-point table, the progress bar;
* :mod:`~saltation.apps.cli.orbit`, :mod:`~saltation.apps.cli.continue_`, :mod:`~saltation.apps.cli.locus`,
  :mod:`~saltation.apps.cli.paper`, :mod:`~saltation.apps.cli.sweep`, :mod:`~saltation.apps.cli.lyapunov`:
  one subcommand each.

Every name the single module ``saltation.apps.cli`` had is still imported from here.
"""

from __future__ import annotations

import argparse
import atexit
import contextlib
import logging
import os
import sys
import tempfile  # noqa: F401 (saltation.apps.cli.tempfile: the module whose mkstemp tries --out)
import threading
from collections.abc import Callable, Sequence

from saltation._moved import forward_names
from saltation.apps.cli import continue_, locus, lyapunov, orbit, paper, sweep
from saltation.apps.cli.continue_ import cmd_continue
from saltation.apps.cli.errors import PROG, CommandError, UsageError
from saltation.apps.cli.locus import cmd_locus
from saltation.apps.cli.lyapunov import cmd_lyapunov
from saltation.apps.cli.models import (
    MODEL_HELP,
    build_model,
    load_model_file,
    make_flow,
    model_names,
)
from saltation.apps.cli.options import (
    FORCING_PERIOD_MATCH,
    MIN_PERIOD,
    MIN_STEP,
    MODE0_HELP,
    PERIOD_HELP,
    SEGMENTS_TYPE,
    check_equilibrium_option,
    check_forced_period,
    check_grid,
    check_mode0,
    check_not_set,
    check_out_dir,
    check_parameter,
    check_period,
    check_start_field,
    check_start_period,
    forcing_period_at,
    parse_sets,
    parse_vector,
    usable_parameters,
)
from saltation.apps.cli.orbit import cmd_orbit, format_orbit
from saltation.apps.cli.paper import PAPER_MIN_DS_MAX, cmd_paper
from saltation.apps.cli.starts import (
    equilibrium_start,
    estimate_period,
    periodic_start,
    transient,
)
from saltation.apps.cli.sweep import cmd_sweep, sweep_start
from saltation.apps.cli.text import multipliers_json
from saltation.errors import SaltationError


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


#: Subcommands in the order of ``saltation --help``: each adds its parser to the subparsers
#: action and sets ``handler`` to its ``cmd_<name>(args) -> int``.
SUBCOMMANDS: list[Callable[[argparse._SubParsersAction], None]] = [
    orbit.add_parser,
    continue_.add_parser,
    locus.add_parser,
    paper.add_parser,
    sweep.add_parser,
    lyapunov.add_parser,
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
        with _library_warnings_on_stderr():
            status = int(_handler(args)(args) or 0)
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


class _StderrHandler(logging.Handler):
    """The library's warnings as lines ``saltation: MESSAGE`` on the standard error of the moment (a test's
    captured stream included)."""

    def emit(self, record: logging.LogRecord) -> None:
        with contextlib.suppress(Exception):
            print(f"{PROG}: {record.getMessage()}", file=sys.stderr, flush=True)


@contextlib.contextmanager
def _library_warnings_on_stderr():
    """While a subcommand runs, the library's warnings (a damaged kernel cache rebuilt, a sweep's failed value)
    are shown on standard error; its other records stay with the application's logging."""
    handler = _StderrHandler(logging.WARNING)
    logger = logging.getLogger("saltation")
    logger.addHandler(handler)
    try:
        yield
    finally:
        logger.removeHandler(handler)


def _handler(args: argparse.Namespace) -> Callable[[argparse.Namespace], int]:
    """The subcommand's function as this package names it (``cmd_<name>``): the package's name is the one
    called, so that replacing it here replaces the subcommand."""
    return globals().get(args.handler.__name__, args.handler)


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


__all__ = [
    "DEBUG_HELP",
    "FORCING_PERIOD_MATCH",
    "MIN_PERIOD",
    "MIN_STEP",
    "MODE0_HELP",
    "MODEL_HELP",
    "PAPER_MIN_DS_MAX",
    "PERIOD_HELP",
    "PROG",
    "SEGMENTS_TYPE",
    "SHIPPED",
    "SUBCOMMANDS",
    "CommandError",
    "UsageError",
    "build_model",
    "build_parser",
    "check_equilibrium_option",
    "check_forced_period",
    "check_grid",
    "check_mode0",
    "check_not_set",
    "check_out_dir",
    "check_parameter",
    "check_period",
    "check_start_field",
    "check_start_period",
    "cmd_continue",
    "cmd_locus",
    "cmd_lyapunov",
    "cmd_orbit",
    "cmd_paper",
    "cmd_sweep",
    "equilibrium_start",
    "estimate_period",
    "forcing_period_at",
    "format_orbit",
    "load_model_file",
    "main",
    "make_flow",
    "model_names",
    "multipliers_json",
    "orbit_to_dict",
    "parse_sets",
    "parse_vector",
    "periodic_start",
    "run",
    "sweep_start",
    "transient",
    "usable_parameters",
]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
_forward = forward_names(__name__, ('saltation.orbits.multiple', 'saltation.orbits.start', 'saltation.errors', 'saltation.model.system'))
#: names of this package imported on first use: the shipped models and the orbit codec load sympy and numba
_LAZY = {"SHIPPED": "saltation.models", "orbit_to_dict": "saltation.output.codecs"}


def __getattr__(name: str):
    """:data:`SHIPPED` and ``orbit_to_dict`` on first use; the names of release 0.1, forwarded with a warning."""
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    return _forward(name)
