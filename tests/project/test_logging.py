"""The library reports through the standard ``logging`` module, one logger per module under its layer, and is
quiet unless the application configures logging; only the command line prints."""

from __future__ import annotations

import ast
import logging
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).parents[2] / "src" / "saltation"


def _continue_trilinear():
    from saltation import ContinuationSettings, Flow, continue_orbit, find_periodic_orbit
    from saltation.models import trilinear

    flow = Flow(trilinear())
    orbit = find_periodic_orbit(flow, [0.0, 0.0], parameters={"omega": 0.6})
    return continue_orbit(orbit, "omega", bounds=(0.6, 1.0), directions=(1,),
                          settings=ContinuationSettings(bounds=(0.6, 1.0)))


def test_a_branch_logs_what_it_finds_under_its_layers_logger(caplog):
    with caplog.at_level(logging.DEBUG, logger="saltation"):
        branch = _continue_trilinear()
    by_logger = {}
    for record in caplog.records:
        by_logger.setdefault(record.name, []).append(record)
    assert set(by_logger) <= {name for name in by_logger if name.startswith("saltation.")}
    infos = [r.getMessage() for r in by_logger["saltation.branches.continuation"] if r.levelno == logging.INFO]
    assert infos[0] == "trilinear: following omega from 0.6, increasing"
    (corner,) = branch.special_points
    assert f"trilinear: nonsmooth_no_crossing at omega = {corner.parameter:.10g} (bracketed, to " in infos[1]
    assert infos[-1] == f"trilinear: {len(branch)} points, stopped: reached a parameter bound"
    points = [r for r in by_logger["saltation.branches.continuation"] if r.levelno == logging.DEBUG]
    assert len(points) == len(branch)  # one line per point, at DEBUG
    assert any(r.levelno == logging.DEBUG for r in by_logger["saltation.orbits.problem"])  # Newton's iterations


def test_a_failed_value_of_a_sweep_is_a_warning(caplog):
    from saltation.models import trilinear
    from saltation.sweeps import sweep

    with caplog.at_level(logging.WARNING, logger="saltation"):
        # omega = 0: no forcing period, so that value fails (and is recorded), the other one runs
        result = sweep(trilinear(), "omega", np.array([0.0, 1.0]), periods=2, transient=2, workers=1)
    assert [v for v, _ in result.failures] == [0.0]
    (record,) = [r for r in caplog.records if r.name == "saltation.sweeps.sweeps"]
    assert record.levelno == logging.WARNING and "the sweep failed at omega = 0" in record.getMessage()


def test_the_library_is_quiet_unless_logging_is_configured():
    code = ("import numpy as np\n"
            "from saltation import ContinuationSettings, Flow, continue_orbit, find_periodic_orbit\n"
            "from saltation.models import trilinear\n"
            "flow = Flow(trilinear())\n"
            "orbit = find_periodic_orbit(flow, [0.0, 0.0], parameters={'omega': 0.6})\n"
            "continue_orbit(orbit, 'omega', bounds=(0.6, 0.9), directions=(1,))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert (done.stdout, done.stderr) == ("", "")


def _prints(tree: ast.AST) -> list[int]:
    """Lines that print: ``print(...)``, or a write to ``sys.stdout`` / ``sys.stderr``."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            if isinstance(f, ast.Name) and f.id == "print":
                lines.append(node.lineno)
            elif (isinstance(f, ast.Attribute) and f.attr == "write" and isinstance(f.value, ast.Attribute)
                  and f.value.attr in ("stdout", "stderr")):
                lines.append(node.lineno)
    return lines


def test_no_print_in_the_library_outside_the_command_line():
    found = {}
    for path in ROOT.rglob("*.py"):
        if "apps" in path.relative_to(ROOT).parts[:1]:
            continue
        lines = _prints(ast.parse(path.read_text()))
        if lines:
            found[str(path.relative_to(ROOT))] = lines
    assert found == {}


class _Terminal:
    """A standard error that says it is a terminal, keeping what is written."""

    def __init__(self):
        import io

        self.buffer = io.StringIO()

    def write(self, text):
        return self.buffer.write(text)

    def flush(self):
        pass

    def isatty(self):
        return True


def test_a_build_shows_a_bar_on_a_terminal_and_the_switch_turns_it_off(monkeypatch, caplog):
    import time

    from saltation import progress
    from saltation.engine.codegen import building

    for value, on in (("", True), ("1", True), ("0", False), ("off", False), ("False", False)):
        monkeypatch.setenv(progress.ENVIRONMENT_VARIABLE, value)
        assert progress.enabled() is on
    monkeypatch.delenv(progress.ENVIRONMENT_VARIABLE)
    progress.set_enabled(False)
    assert not progress.enabled() and progress.bar("x", 3.0) is None
    progress.set_enabled(None)
    assert progress.enabled()

    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    with caplog.at_level(logging.INFO, logger="saltation.engine"), building("compiling a test", interval=0.02):
        time.sleep(0.15)
    assert "saltation: compiling a test" in terminal.buffer.getvalue()  # the bar, with its seconds
    messages = [r.getMessage() for r in caplog.records if r.name == "saltation.engine.codegen"]
    assert messages[0] == "compiling a test" and messages[1].startswith("compiling a test: done in ")
    terminal.buffer.truncate(0)
    monkeypatch.setenv(progress.ENVIRONMENT_VARIABLE, "0")
    with building("compiling a test", interval=0.02):
        time.sleep(0.05)
    assert terminal.buffer.getvalue() == ""
