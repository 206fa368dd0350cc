"""Bad command lines are one line and exit status 2; unexpected errors one line and 1 unless --debug.

Every numeric option of every subcommand is refused, naming the option and the value, when it is not a
number, not finite, out of its range (counts, step sizes, periods), or contradicts another (a range with
equal ends, a --period that is not the forcing period).  None of these cases reaches a computation.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from saltation.apps import cli
from saltation.errors import ConvergenceError, StationaryStateError

ORBIT = ["orbit", "block_on_belt"]
CONTINUE = ["continue", "block_on_belt", "--param", "v_dr", "--from", "1", "--to", "1.05", "--no-progress"]
FORCED_CONTINUE = ["continue", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.7", "--no-progress"]
LOCUS = ["locus", "trilinear", "--kind", "fold", "--param", "omega", "--range", "0.6,1.6", "--param2", "f0",
         "--range2", "0.1,0.3"]
SWEEP = ["sweep", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.7", "--num", "3"]
MAP = [*SWEEP, "--param2", "f0", "--from2", "0.1", "--to2", "0.2", "--num2", "2"]


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


BAD = [
    # Task: a forced model has no equilibria
    (["continue", "trilinear", "--equilibrium", "free", "--param", "omega", "--from", "1", "--to", "2"],
     ["--equilibrium free", "'trilinear' is forced", "no equilibria"]),
    ([*CONTINUE, "--equilibrium", "glide"], ["unknown mode 'glide' in --equilibrium", "stick, slip_plus, slip_minus"]),
    ([*CONTINUE, "--equilibrium", "slip_minus", "--period", "6"], ["--period does not apply to --equilibrium"]),
    ([*CONTINUE, "--equilibrium", "slip_minus", "--backward"], ["--backward does not apply to --equilibrium"]),
    # counts
    ([*CONTINUE, "--max-points", "0"], ["--max-points", "'0'", "positive integer"]),
    ([*CONTINUE, "--max-points", "-5"], ["--max-points", "'-5'", "positive integer"]),
    ([*CONTINUE, "--max-points", "2.5"], ["--max-points", "'2.5'"]),
    ([*SWEEP[:-1], "0"], ["--num", "'0'", "positive integer"]),
    ([*SWEEP, "--periods", "0"], ["--periods", "'0'", "positive integer"]),
    ([*SWEEP, "--transient", "-1"], ["--transient", "'-1'", "at least 0"]),
    ([*SWEEP, "--workers", "0"], ["--workers", "'0'", "positive integer"]),
    ([*SWEEP, "--num", "nan"], ["--num", "'nan'"]),
    ([*MAP[:-1], "0"], ["--num2", "'0'", "positive integer"]),
    ([*MAP, "--max-period", "0"], ["--max-period", "'0'", "positive integer"]),
    ([*MAP, "--max-period", "8", "--periods", "8"], ["--periods 8 must exceed --max-period 8"]),
    ([*SWEEP, "--max-period", "4"], ["--max-period belongs to a two-parameter map"]),
    # step sizes
    ([*CONTINUE, "--ds", "0"], ["--ds", "'0'", "positive finite"]),
    ([*CONTINUE, "--ds", "1e-300"], ["--ds", "'1e-300'", "below the smallest accepted value 1e-06"]),
    ([*CONTINUE, "--ds-max", "-0.1"], ["--ds-max", "'-0.1'", "positive finite"]),
    ([*CONTINUE, "--ds-max", "inf"], ["--ds-max", "'inf'", "positive finite"]),
    ([*CONTINUE, "--ds", "0.5"], ["--ds 0.5 exceeds --ds-max 0.02"]),
    (["paper", "--out", "unused", "--ds-max", "0"], ["--ds-max", "'0'", "positive finite"]),
    (["paper", "--out", "unused", "--ds-max", "1e-5"], ["--ds-max", "'1e-5'", "smallest accepted value 0.002"]),
    # periods and times
    ([*ORBIT, "--period", "1e-300"], ["--period 1e-300 is too short", "at least 1e-09"]),
    ([*ORBIT, "--period", "1e-10", "--t0", "1e4"], ["--period 1e-10 is too short", "at least 1e-09"]),
    ([*ORBIT, "--period", "0"], ["--period", "'0'", "positive finite"]),
    ([*ORBIT, "--period", "-6.3"], ["--period", "'-6.3'", "positive finite"]),
    ([*ORBIT, "--period", "nan"], ["--period", "'nan'", "positive finite"]),
    ([*ORBIT, "--period", "inf"], ["--period", "'inf'", "positive finite"]),
    ([*ORBIT, "--t0", "inf"], ["--t0", "'inf'", "finite"]),
    ([*ORBIT, "--t0", "nan"], ["--t0", "'nan'", "finite"]),
    ([*CONTINUE, "--period", "1e-300"], ["--period 1e-300 is too short"]),
    ([*LOCUS, "--period", "0"], ["--period", "'0'", "positive finite"]),
    # a --period that contradicts the forcing period
    (["orbit", "trilinear", "--period", "5"], ["forced", "forcing period 2*pi/omega = 5.235987756", "--period 5"]),
    (["orbit", "trilinear", "--set", "omega=0.7", "--period", "5.235987756"],
     ["forcing period 2*pi/omega = 8.97597901", "--period 5.235987756 contradicts it"]),
    ([*FORCED_CONTINUE, "--period", "6.3"], ["forcing period 2*pi/omega = 10.47197551 at --from 0.6", "--period 6.3"]),
    ([*LOCUS, "--period", "6.3"], ["forcing period 2*pi/omega = 10.47197551 at omega = 0.6", "--period 6.3"]),
    # parameter values for which the forcing period is none
    (["orbit", "trilinear", "--set", "omega=0"], ["--set", "forcing period", "divides by omega", "omega = 0"]),
    (["continue", "trilinear", "--param", "omega", "--from", "0", "--to", "1"], ["--from 0", "forcing period"]),
    (["sweep", "trilinear", "--param", "omega", "--from", "-1", "--to", "1", "--num", "3"],
     ["--param omega = -1", "forcing period"]),
    # bounds, and NaN / infinity as numbers
    (["continue", "block_on_belt", "--param", "v_dr", "--from", "1", "--to", "1"],
     ["--from and --to must differ, got 1 twice"]),
    (["continue", "block_on_belt", "--param", "v_dr", "--from", "1", "--to", "nan"], ["--to", "'nan'", "finite"]),
    (["continue", "block_on_belt", "--param", "v_dr", "--from=-inf", "--to", "1"], ["--from", "'-inf'", "finite"]),
    (["sweep", "trilinear", "--param", "omega", "--from", "1", "--to", "1", "--num", "3"],
     ["--from and --to are both 1", "--num 3"]),
    (["sweep", "trilinear", "--param", "omega", "--from", "1", "--to", "2", "--num", "1"],
     ["--num 1 takes one value", "--from 1 and --to 2 differ"]),
    (["sweep", "trilinear", "--param", "omega", "--from", "0.6", "--to", "inf", "--num", "3"],
     ["--to", "'inf'", "finite"]),
    ([*SWEEP, "--param2", "f0", "--from2", "0.1", "--to2", "0.1", "--num2", "2"],
     ["--from2 and --to2 are both 0.1", "--num2 2"]),
    ([*SWEEP, "--param2", "f0", "--from2", "0.1", "--to2", "nan", "--num2", "2"], ["--to2", "'nan'", "finite"]),
    ([*LOCUS[:7], "1,1", *LOCUS[8:]], ["--range", "the two ends must differ", "'1,1'"]),
    ([*LOCUS[:7], "0.6,nan", *LOCUS[8:]], ["--range", "'nan'", "finite"]),
    ([*LOCUS[:-1], "0.3,0.3"], ["--range2", "the two ends must differ", "'0.3,0.3'"]),
    ([*ORBIT, "--set", "c=inf"], ["--set 'c=inf'", "finite"]),
    ([*ORBIT, "--x0", "1,nan"], ["--x0 '1,nan'", "finite"]),
    # a parameter set twice
    ([*CONTINUE, "--set", "v_dr=2"], ["--set v_dr=2 conflicts with --param v_dr"]),
    ([*SWEEP, "--set", "omega=1"], ["--set omega=1 conflicts with --param omega"]),
    ([*MAP, "--set", "f0=0.3"], ["--set f0=0.3 conflicts with --param2 f0"]),
    ([*LOCUS, "--set", "omega=1"], ["--set omega=1 conflicts with --param omega"]),
    # the sweep's start rule and period maps of autonomous models
    ([*SWEEP, "--start", "sideways"], ["--start", "'sideways'", "'own', 'previous'"]),
    (["sweep", "block_on_belt", "--param", "v_dr", "--from", "1", "--to", "2", "--num", "2", "--param2", "k",
      "--from2", "1", "--to2", "2", "--num2", "2"], ["--param2", "'block_on_belt' is autonomous"]),
]


@pytest.mark.parametrize("argv, culprits", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_usage_is_one_line_exit_2_naming_the_option_and_the_value(capsys, monkeypatch, tmp_path, argv, culprits):
    monkeypatch.chdir(tmp_path)  # were a case to run after all, its files would land here
    code, out, err = _run(capsys, *argv)
    assert code == 2, err
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("saltation: error: ")
    for culprit in culprits:
        assert culprit in lines[0]


def test_negative_ranges_reach_the_parser():
    assert cli._join_negative_values(["--range", "-1,2", "--range2", "-0.5,0.5"]) == ["--range=-1,2", "--range2=-0.5,0.5"]


def test_forcing_period_given_as_period_is_accepted(capsys, trilinear_flow):
    """--period equal to the forcing period (to 1e-9) is what shooting uses anyway: the same orbit, the linear
    closed form (no contact at omega = 0.7)."""
    w = 0.7
    code, out, err = _run(capsys, "orbit", "trilinear", "--set", f"omega={w}", "--x0", "0.3,0",
                          "--period", repr(2 * np.pi / w), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["period"] == pytest.approx(2 * np.pi / w, rel=1e-14)
    assert data["amplitude"] == pytest.approx(0.2 / np.hypot(1 - w**2, 0.05 * w), rel=1e-8)


def test_a_forced_orbit_far_from_t0_zero_is_the_orbit_there(capsys, trilinear_flow):
    """--t0 1e12 is reduced modulo the forcing period: the multipliers equal those at t0 = 0 to rounding
    (the time 1e12 itself keeps only four decimals, and the orbit through it is the orbit at its remainder)."""
    runs = []
    for t0 in ("0", "1e12", "-2e9"):
        code, out, err = _run(capsys, "orbit", "trilinear", "--x0", "0.5,0.5", f"--t0={t0}", "--json")
        assert code == 0, err
        runs.append(json.loads(out))
    for run in runs[1:]:
        np.testing.assert_allclose(run["multipliers"], runs[0]["multipliers"], rtol=0, atol=1e-12)


# -- exceptions that are not bad usage ---------------------------------------------------------------------

def _raise(exc: BaseException):
    def fail(*args, **kwargs):
        raise exc

    return fail


def test_internal_error_is_one_line_exit_1(capsys, monkeypatch):
    import saltation.orbits.start

    monkeypatch.setattr(saltation.orbits.start, "find_periodic_orbit", _raise(ZeroDivisionError("float division by zero")))
    code, out, err = _run(capsys, "orbit", "trilinear", "--x0", "0.5,0.5")
    assert code == 1 and out == ""
    assert err.strip().splitlines() == [
        "saltation: error: internal error: ZeroDivisionError: float division by zero "
        "(run with --debug for the traceback)"
    ]
    monkeypatch.setattr(saltation.orbits.start, "find_periodic_orbit", _raise(KeyError()))
    code, _, err = _run(capsys, "orbit", "trilinear", "--x0", "0.5,0.5")
    assert code == 1
    assert err.strip().splitlines() == ["saltation: error: internal error: KeyError (run with --debug for the traceback)"]


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_lets_the_exception_through(capsys, monkeypatch, where):
    import saltation.orbits.start

    argv = ["orbit", "trilinear", "--x0", "0.5,0.5"]
    argv = ["--debug", *argv] if where == "before" else [*argv, "--debug"]
    monkeypatch.setattr(saltation.orbits.start, "find_periodic_orbit", _raise(RuntimeError("a bug")))
    with pytest.raises(RuntimeError, match="a bug"):
        cli.main(argv)
    monkeypatch.setattr(saltation.orbits.start, "find_periodic_orbit",
                        _raise(ConvergenceError("shooting did not converge", [1.0])))
    with pytest.raises(ConvergenceError):  # a failed computation too: --debug is for finding out why
        cli.main(argv)
    # bad usage stays one line, exit 2
    code, _, err = _run(capsys, *argv, "--period", "-1")
    assert code == 2 and len(err.strip().splitlines()) == 1


def test_debug_is_documented(capsys):
    code, out, _ = _run(capsys, "--help")
    assert code == 0 and "--debug" in out and "traceback" in out
    code, out, _ = _run(capsys, "sweep", "--help")
    assert code == 0 and "--debug" in out


SCRIPT = """
import sys
import saltation.orbits.start
from saltation.apps import cli

def fail(*args, **kwargs):
    raise RuntimeError("a bug")

saltation.orbits.start.find_periodic_orbit = fail
sys.exit(cli.main(sys.argv[1:]))
"""


def test_no_traceback_reaches_the_user_without_debug(trilinear_flow):
    argv = [sys.executable, "-c", SCRIPT, "orbit", "trilinear", "--x0", "0.5,0.5"]
    proc = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines() == [
        "saltation: error: internal error: RuntimeError: a bug (run with --debug for the traceback)"
    ]
    proc = subprocess.run([*argv, "--debug"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1
    assert "Traceback (most recent call last)" in proc.stderr and "RuntimeError: a bug" in proc.stderr


# -- a "periodic orbit" that is a stationary state ---------------------------------------------------------

def test_stationary_state_error_is_one_line_exit_1(capsys, monkeypatch):
    import saltation.orbits.start

    message = "shooting converged to an equilibrium at [1.0, 0.0], not a periodic orbit"
    monkeypatch.setattr(saltation.orbits.start, "find_periodic_orbit",
                        _raise(StationaryStateError(message, [1.0, 0.0], 6.3)))
    code, out, err = _run(capsys, "orbit", "block_on_belt", "--x0", "2,0", "--period", "6.3")
    assert code == 1 and out == ""
    assert err.strip().splitlines() == [f"saltation: error: {message}"]


def test_shooting_onto_the_equilibrium_is_an_error(capsys, belt_flow):
    """Above the fold (v_dr = 2) the block on a belt has no stick-slip cycle: shooting from [2, 0] with a
    period guess falls onto the equilibrium [F_slip / k, 0], which is no periodic orbit."""
    code, out, err = _run(capsys, "orbit", "block_on_belt", "--set", "v_dr=2", "--period", "6.3", "--x0", "2,0")
    assert code == 1, out
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("saltation: error: ")
    assert "equilibrium" in lines[0]
