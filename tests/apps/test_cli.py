"""The command line, end to end: ``saltation orbit`` against closed forms and the paper's stick-slip cycles."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest
from scipy.linalg import expm

from saltation.apps import cli
from saltation.errors import ConvergenceError
from saltation.models import trilinear

# Appendix A
M, C, K, F0 = 1.0, 0.05, 1.0, 0.2
W = 0.7  # below the contact range: the orbit never reaches x_c = 1
REQUIRED = {"state0", "period", "amplitude", "multipliers", "events", "converged"}


def _strict_json(text: str) -> dict:
    """Parse JSON, refusing the non-standard NaN / Infinity."""

    def refuse(name):
        raise ValueError(f"non-standard JSON constant {name}")

    return json.loads(text, parse_constant=refuse)


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _linear_reference(w: float = W):
    """Steady state x = X sin(w t - phi) of m x'' + c x' + k x = f0 sin(w t), and its multipliers."""
    X = F0 / np.hypot(K - M * w**2, C * w)
    phi = np.arctan2(C * w, K - M * w**2)
    state0 = np.array([-X * np.sin(phi), X * w * np.cos(phi)])
    A = np.array([[0.0, 1.0], [-K / M, -C / M]])
    mu = np.linalg.eigvals(expm(A * 2 * np.pi / w))
    return X, state0, mu


def _pairs(mu) -> np.ndarray:
    return np.sort_complex(np.array([complex(*m) for m in mu]))


@pytest.fixture(scope="module")
def compiled(trilinear_flow, belt_flow):
    """Both shipped models compiled (the CLI then loads them from the cache)."""
    return trilinear_flow, belt_flow


def test_orbit_json_matches_linear_closed_form(capsys, compiled):
    code, out, err = _run(capsys, "orbit", "trilinear", "--set", "omega=0.7", "--x0", "0.3,0", "--json")
    assert code == 0, err
    data = _strict_json(out)
    assert REQUIRED <= set(data)
    X, state0, mu = _linear_reference()
    assert data["converged"] is True
    assert data["period"] == pytest.approx(2 * np.pi / W, rel=1e-14)
    assert data["amplitude"] == pytest.approx(X, rel=1e-8)
    assert np.allclose(data["state0"], state0, rtol=0, atol=1e-8)
    assert np.allclose(_pairs(data["multipliers"]), np.sort_complex(mu), rtol=0, atol=1e-8)
    assert data["events"] == []
    assert data["stable"] is True
    assert data["parameters"]["omega"] == W and data["parameters"]["f0"] == F0


def test_orbit_subprocess_python_m(compiled):
    """``python -m saltation`` with the transient default (no --x0)."""
    proc = subprocess.run(
        [sys.executable, "-m", "saltation", "orbit", "trilinear", "--json", "--set", "omega=0.7"],
        capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    data = _strict_json(proc.stdout)
    X, state0, mu = _linear_reference()
    assert data["amplitude"] == pytest.approx(X, rel=1e-8)
    assert np.allclose(data["state0"], state0, rtol=0, atol=1e-8)
    assert np.allclose(_pairs(data["multipliers"]), np.sort_complex(mu), rtol=0, atol=1e-8)


def test_orbit_phase_t0(capsys, compiled):
    """--t0 shifts the phase of the forcing: state0 is the steady state at t0."""
    t0 = 1.3
    code, out, err = _run(capsys, "orbit", "trilinear", "--set", "omega=0.7", "--t0", str(t0), "--x0", "0.3,0", "--json")
    assert code == 0, err
    data = _strict_json(out)
    X, _, _ = _linear_reference()
    phi = np.arctan2(C * W, K - M * W**2)
    assert data["t0"] == t0
    assert np.allclose(data["state0"], [X * np.sin(W * t0 - phi), X * W * np.cos(W * t0 - phi)], atol=1e-8)


def test_orbit_contact_orbit_has_events(capsys, compiled):
    """omega = 1.2 from the far side: the large orbit in contact with both supports (x0 with a minus sign)."""
    code, out, err = _run(capsys, "orbit", "trilinear", "--x0", "-1,0", "--json")
    assert code == 0, err
    data = _strict_json(out)
    assert data["amplitude"] > 1.0  # beyond x_c
    surfaces = {s for s, _ in data["events"]}
    assert surfaces == {"h1a", "h1b", "h2a", "h2b"}
    times = [t for _, t in data["events"]]
    assert times == sorted(times) and 0.0 <= times[0] and times[-1] <= data["period"]


def test_stable_stick_slip_cycle_from_transient(capsys, compiled):
    """No --x0, no --period: transient, period estimate, then the stable cycle with multipliers (1, ~0)."""
    code, out, err = _run(capsys, "orbit", "block_on_belt", "--json")
    assert code == 0, err
    data = _strict_json(out)
    assert data["converged"] and data["stable"] and data["autonomous"]
    assert data["period"] == pytest.approx(6.494, abs=2e-3)
    mu = sorted(abs(complex(*m)) for m in data["multipliers"])
    assert mu[1] == pytest.approx(1.0, abs=1e-6)
    assert mu[0] < 1e-3  # zero as eta -> 0 (the stick phase)
    # one stick phase per period: enter it on the band, leave it where the spring force reaches F_stick
    assert sorted(s for s, _ in data["events"]) == ["band_lower", "stick_upper"]


def test_unstable_stick_slip_cycle_backward_has_infinite_multiplier(capsys, compiled):
    code, out, err = _run(
        capsys, "orbit", "block_on_belt", "--backward", "--x0", "1.0,-0.95", "--period", "6.3", "--json"
    )
    assert code == 0, err
    data = _strict_json(out)
    assert data["backward"] is True and data["stable"] is False and data["converged"] is True
    assert "inf" in data["multipliers"]
    finite = [complex(*m) for m in data["multipliers"] if m != "inf"]
    assert len(finite) == 1 and finite[0] == pytest.approx(1.0, abs=1e-6)
    assert "inf" in data["multiplier_magnitudes"]
    assert data["period"] == pytest.approx(6.44, abs=0.01)
    assert data["events"] and all(t < 0 for _, t in data["events"])  # backward time
    # the same cycle from a backward transient, with the period estimated
    code, out2, err = _run(capsys, "orbit", "block_on_belt", "--backward", "--json")
    assert code == 0, err
    data2 = _strict_json(out2)
    assert "inf" in data2["multipliers"]
    assert data2["period"] == pytest.approx(data["period"], rel=1e-8)
    assert data2["amplitude"] == pytest.approx(data["amplitude"], rel=1e-6)


def test_table_output(capsys, compiled):
    code, out, err = _run(capsys, "orbit", "block_on_belt", "--backward", "--x0", "1.0,-0.95", "--period", "6.3")
    assert code == 0, err
    for row in ("state0", "period", "amplitude", "multipliers", "stability", "events"):
        assert any(line.startswith(row) for line in out.splitlines()), row
    assert "|mu| = inf" in out
    assert "infinitely unstable" in out
    code, out, err = _run(capsys, "orbit", "trilinear", "--set", "omega=0.7", "--x0", "0.3,0")
    assert code == 0, err
    assert "stable" in out and "events       none" in out
    X, _, _ = _linear_reference()
    assert f"{X:.8f}"[:8] in out


@pytest.mark.parametrize(
    "argv, culprit",
    [
        (["orbit", "pendulum"], "unknown model 'pendulum'"),
        (["orbit", "trilinear", "--set", "omgea=1"], "unknown parameter 'omgea'"),
        (["orbit", "trilinear", "--set", "omega"], "NAME=VALUE"),
        (["orbit", "trilinear", "--set", "omega=fast"], "'fast' is not a number"),
        (["orbit", "trilinear", "--x0", "0.5;0.5"], "malformed --x0"),
        (["orbit", "trilinear", "--x0", "1,2,3"], "has 3 components"),
        (["orbit", "trilinear", "--x0", "nan,0"], "finite"),
        (["orbit", "trilinear", "--period", "5"], "forced"),
        (["orbit", "block_on_belt", "--period", "-1"], "positive"),
        (["orbit", "trilinear", "--frobnicate"], "unrecognized arguments"),
        (["continue", "trilinear", "--param", "omgea", "--from", "0.6", "--to", "0.7"], "unknown parameter 'omgea' in --param"),
        (["sweep", "trilinear", "--param", "omgea", "--from", "0.6", "--to", "0.7", "--num", "2"],
         "unknown parameter 'omgea' in --param"),
        (["sweep", "bouncing_ball", "--param", "A", "--from", "0.3", "--to", "0.4", "--num", "2", "--param2", "eps",
          "--from2", "0.4", "--to2", "0.5", "--num2", "2"], "unknown parameter 'eps' in --param2"),
        (["orbit"], "MODEL"),
        ([], "subcommand"),
    ],
)
def test_bad_usage_is_one_line_exit_2(capsys, argv, culprit):
    code, out, err = _run(capsys, *argv)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("saltation: error: ")
    assert culprit in lines[0]


def test_failed_computation_is_one_line_exit_1(capsys, compiled):
    # the transient from the equilibrium [F_slip/k, 0] does not oscillate: no period to estimate
    code, out, err = _run(capsys, "orbit", "block_on_belt", "--x0", "1,0")
    assert code == 1 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("saltation: error: ") and "period" in lines[0]


def test_newton_failure_is_one_line_exit_1(capsys, compiled, monkeypatch):
    import saltation.orbits.start

    def fail(*args, **kwargs):
        raise ConvergenceError("shooting (forward time) for 'trilinear' did not converge in 30 iterations", [1.0, 2.0])

    monkeypatch.setattr(saltation.orbits.start, "find_periodic_orbit", fail)
    code, out, err = _run(capsys, "orbit", "trilinear", "--x0", "0.5,0.5", "--json")
    assert code == 1 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("saltation: error: shooting") and "did not converge" in lines[0]
    assert "Traceback" not in err


def test_bad_usage_subprocess_has_no_traceback():
    proc = subprocess.run(
        [sys.executable, "-m", "saltation", "orbit", "trilinear", "--set", "omgea=1"],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.strip().splitlines() == [
        "saltation: error: unknown parameter 'omgea' in --set for model 'trilinear'; "
        "parameters are m, c, k, x_c, k_f, c_f, f0, omega"
    ]


def test_help_explains_every_option(capsys):
    code, out, _ = _run(capsys, "--help")
    assert code == 0 and "orbit" in out
    code, out, _ = _run(capsys, "orbit", "--help")
    assert code == 0
    for option in ("MODEL", "--set", "--x0", "--t0", "--period", "--backward", "--json"):
        assert option in out
    for name in cli.SHIPPED:
        assert name in out
    for pname in trilinear().parameter_names:
        assert f"{pname}=" in out


def test_registry_and_helpers():
    assert set(cli.SHIPPED) >= {"trilinear", "block_on_belt"}
    assert cli.multipliers_json([0.5 + 0.25j, complex(np.inf, 0)]) == [[0.5, 0.25], "inf"]
    assert cli._join_negative_values(["orbit", "m", "--x0", "-1,0", "--json"]) == ["orbit", "m", "--x0=-1,0", "--json"]
    assert cli._join_negative_values(["--x0", "--json"]) == ["--x0", "--json"]


# ---------------------------------------------------------------------------------------------
# continue and paper
# ---------------------------------------------------------------------------------------------

def test_continue_writes_branch_that_loads_back(tmp_path, capsys):
    from saltation.output import io

    status = cli.main([
        "continue", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.8",
        "--ds-max", "0.05", "--out", str(tmp_path), "--no-progress",
    ])
    assert status == 0
    out = capsys.readouterr().out
    assert "points" in out
    branch = io.load_branch_json(tmp_path / "trilinear_omega_branch.json")
    assert branch.parameter[0] == pytest.approx(0.6) and branch.parameter[-1] == pytest.approx(0.8)
    # no contact below w_A: the linear closed-form amplitude
    w = branch.parameter
    assert np.allclose(branch.amplitude, 0.2 / np.sqrt((1 - w**2) ** 2 + (0.05 * w) ** 2), rtol=1e-8)
    points = io.load_branch_csv(tmp_path / "trilinear_omega_branch.csv")
    assert np.allclose(points.parameter, branch.parameter, rtol=0, atol=0)
    assert (tmp_path / "trilinear_omega_diagram.png").stat().st_size > 0
    assert json.loads((tmp_path / "trilinear_omega_special_points.json").read_text()) == []


def test_continue_records_and_passes_a_grazing(tmp_path, capsys):
    """The impact oscillator from its non-impacting orbit at s = 3 down to s = 2.5: the grazing at
    s* = 1 / sqrt((1 - w^2)^2 + (2 zeta w)^2) is in the special-points file, and the branch goes on
    onto impacting orbits."""
    import json

    status = cli.main([
        "continue", "impact_oscillator", "--param", "s", "--from", "3.0", "--to", "2.5", "--out", str(tmp_path),
        "--no-progress",
    ])
    assert status == 0, capsys.readouterr().err
    records = json.loads((tmp_path / "impact_oscillator_s_special_points.json").read_text())
    zeta, w = 0.05, 0.8
    (grazing,) = [r for r in records if r["kind"] == "grazing"]
    assert grazing["value"] == pytest.approx(1 / np.hypot(1 - w**2, 2 * zeta * w), abs=1e-9)
    # the crossing side's multiplier grows without bound along the negative real axis (Nordmark's map)
    assert grazing["limits"] == "grazing" and ["-inf", 0.0] in grazing["multipliers_plus"]
    assert grazing["scenario"] == "persistence" and grazing["period_two"] is True
    branch = json.loads((tmp_path / "impact_oscillator_s_branch.json").read_text())
    assert min(pt["parameter"] for pt in branch["points"]) == pytest.approx(2.5)


def test_continue_rejects_unknown_parameter(tmp_path, capsys):
    status = cli.main(["continue", "trilinear", "--param", "nope", "--from", "0.6", "--to", "0.8", "--out", str(tmp_path)])
    assert status != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nope" in err[0]


@pytest.mark.slow  # runs saltation paper
def test_paper_end_to_end(tmp_path, capsys):
    status = cli.main(["paper", "--out", str(tmp_path), "--ds-max", "0.05", "--no-progress"])
    assert status == 0
    records = json.loads((tmp_path / "special_points.json").read_text())
    kinds = {(r["model"], r["kind"]) for r in records}
    assert ("trilinear", "discontinuous_fold") in kinds
    assert ("trilinear", "nonsmooth_no_crossing") in kinds
    assert ("trilinear", "fold") in kinds
    assert ("block_on_belt", "discontinuous_fold") in kinds
    for r in records:
        assert {"model", "kind", "parameter", "value", "amplitude"} <= set(r)
        if r["kind"] in ("fold", "period_doubling", "neimark_sacker", "hopf"):
            assert "multipliers" in r
        else:
            assert {"multipliers_minus", "multipliers_plus", "crossing_q"} <= set(r)
    fold = next(r for r in records if r["model"] == "block_on_belt" and r["kind"] == "discontinuous_fold")
    assert "inf" in fold["multipliers_plus"]
    for stem in ("fig3_trilinear_response", "fig4_trilinear_multipliers", "fig6_block_on_belt_phase_plane",
                 "fig7_block_on_belt_diagram"):
        assert (tmp_path / f"{stem}.png").stat().st_size > 0
        assert (tmp_path / f"{stem}.pdf").stat().st_size > 0
    from saltation.output import io

    branch = io.load_branch_json(tmp_path / "trilinear_branch.json")
    assert len(branch) > 20
    assert len(io.load_diagram_json(tmp_path / "block_on_belt_branches.json")) == 3
    # every PDF embeds its fonts as TrueType (Type 42, as a CID-keyed font), none as Type 3 (refused by journals)
    pdfs = sorted(tmp_path.glob("*.pdf"))
    assert len(pdfs) >= 5
    for pdf in pdfs:
        data = pdf.read_bytes()
        assert b"/Subtype /Type3" not in data and b"/Type3" not in data, pdf.name
        assert b"/CIDFontType2" in data, pdf.name  # (matplotlib's Type 42 in PDF)
    # the count of files written that the command prints is the count of files in the folder
    written = re.search(r"(\d+) files written", capsys.readouterr().out)
    assert written and int(written.group(1)) == len(list(tmp_path.iterdir()))


def test_sweep_end_to_end(tmp_path, capsys):
    from saltation.apps.sweeps import SweepResult

    status = cli.main([
        "sweep", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.7", "--num", "3",
        "--periods", "5", "--transient", "60", "--workers", "1", "--out", str(tmp_path),
    ])
    assert status == 0
    result = SweepResult.load(tmp_path / "trilinear_omega_sweep.json")
    # no contact: every section point is the harmonic response at t = 0 (x(0) = -f0 c w / det)
    for k, w in enumerate(np.linspace(0.6, 0.7, 3)):
        det = (1 - w**2) ** 2 + (0.05 * w) ** 2
        assert np.allclose(result.at(k)[:, 0], -0.2 * 0.05 * w / det, atol=1e-6)
    assert (tmp_path / "trilinear_omega_sweep.png").stat().st_size > 0
    assert "Poincare" in capsys.readouterr().out


def test_sweep_map_on_a_dask_scheduler_equals_the_local_map(tmp_path, capsys):
    """--param2 ... gives the period map; --scheduler runs it on a Dask cluster, with the same cells."""
    import distributed

    from saltation.apps.sweeps import PeriodMap

    args = ["sweep", "bouncing_ball", "--param", "A", "--from", "0.33", "--to", "0.39", "--num", "3",
            "--param2", "e", "--from2", "0.45", "--to2", "0.55", "--num2", "2", "--max-period", "4",
            "--transient", "150", "--x0", "0.62,-3.94", "--workers", "2"]
    assert cli.main([*args, "--out", str(tmp_path / "local")]) == 0
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        assert cli.main([*args, "--out", str(tmp_path / "dask"), "--scheduler", cluster.scheduler_address]) == 0
    local = PeriodMap.from_dict(json.loads((tmp_path / "local" / "bouncing_ball_A_e_map.json").read_text()))
    remote = PeriodMap.from_dict(json.loads((tmp_path / "dask" / "bouncing_ball_A_e_map.json").read_text()))
    np.testing.assert_array_equal(remote.periods, local.periods)
    assert local.periods.shape == (2, 3) and (local.periods == 1).any()  # period 1 below the doubling
    assert (tmp_path / "dask" / "bouncing_ball_A_e_map.png").stat().st_size > 0
    assert "6 cells (3 x 2)" in capsys.readouterr().out


def test_sweep_map_usage_errors(tmp_path, capsys):
    base = ["sweep", "bouncing_ball", "--param", "A", "--from", "0.33", "--to", "0.39", "--num", "3"]
    assert cli.main([*base, "--param2", "e", "--out", str(tmp_path)]) == 2
    assert "needs all of --param2, --from2, --to2 and --num2" in capsys.readouterr().err
    assert cli.main([*base, "--scheduler", "nowhere://cluster", "--out", str(tmp_path)]) == 2
    assert "cannot reach the Dask scheduler" in capsys.readouterr().err


# --- model files: MODEL as PATH.py:NAME -------------------------------------------------------

MODEL_FILE = '''
from saltation.models import trilinear

low_forcing = trilinear(f0=0.1)       # a model object


def stiffer(k_f=8.0):                 # a function whose arguments all have defaults
    return trilinear(k_f=k_f)


def needs_argument(k_f):
    return trilinear(k_f=k_f)


def not_a_model():
    return 42
'''


def test_model_file_runs_like_a_shipped_model(tmp_path, capsys):
    """A model object and a factory function from a user's file: the same orbit as the shipped model
    with those parameters (the linear response, no contact at omega = 0.7)."""
    path = tmp_path / "my_models.py"
    path.write_text(MODEL_FILE)
    for spec, f0 in ((f"{path}:low_forcing", 0.1), (f"{path}:stiffer", F0)):
        code, out, err = _run(capsys, "orbit", spec, "--set", "omega=0.7", "--json")
        assert code == 0, err
        rec = json.loads(out)
        X = f0 / np.hypot(K - M * 0.7**2, C * 0.7)
        assert rec["amplitude"] == pytest.approx(X, rel=1e-8)
        assert rec["model"] == "trilinear"


@pytest.mark.parametrize(
    "name, message",
    [
        ("missing", "has no name 'missing'; models in it: low_forcing"),
        ("needs_argument", "function 'needs_argument' needs arguments"),
        ("not_a_model", "not_a_model() returned int"),
    ],
)
def test_model_file_errors_name_the_file_and_the_name(tmp_path, capsys, name, message):
    path = tmp_path / "my_models.py"
    path.write_text(MODEL_FILE)
    code, _, err = _run(capsys, "orbit", f"{path}:{name}")
    assert code == 2
    assert str(path) in err and message in err and len(err.strip().splitlines()) == 1


def test_model_file_that_fails_or_is_missing(tmp_path, capsys):
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('no such support')\n")
    code, _, err = _run(capsys, "orbit", f"{broken}:model")
    assert code == 2 and str(broken) in err and "RuntimeError: no such support" in err
    code, _, err = _run(capsys, "orbit", f"{tmp_path / 'absent.py'}:model")
    assert code == 2 and "absent.py" in err and "does not exist" in err


def test_each_shipped_model_declares_itself_in_its_own_file():
    """The command line keeps no per-model tables: each model file ends with its ShippedModel, whose
    name is the model's, and whose transient start (if any) is a state of the model."""
    import importlib

    from saltation.models import SHIPPED

    for name, shipped in SHIPPED.items():
        module = importlib.import_module(f"saltation.models.{name}")
        assert module.SHIPPED is shipped
        system = shipped.factory()
        assert system.name == name and shipped.summary
        if shipped.start is not None:
            for backward in (False, True):
                assert len(shipped.start(system.defaults, backward)) == system.n
    assert "two_mass_stops" in SHIPPED  # the newest gallery model is on the command line too


def _run_program(setup: str, argv: list[str]) -> subprocess.CompletedProcess:
    """``cli.run`` in a fresh interpreter, after the statements ``setup``, with ``argv``."""
    code = f"import atexit, pathlib, sys, threading, time; {setup}; sys.argv = {['saltation', *argv]!r}; " \
           "from saltation.apps.cli import run; run()"
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=False)


def test_the_program_ends_at_once_after_its_exit_handlers(compiled, tmp_path):
    """``saltation`` (``cli.run``) skips the interpreter's teardown but not the exit handlers: one registered
    during the command runs, the output is whole, and the status is the command's."""
    marker = tmp_path / "handler_ran"
    handler = f"atexit.register(lambda: pathlib.Path({str(marker)!r}).write_text('yes'))"
    proc = _run_program(handler, ["orbit", "trilinear", "--json", "--set", "omega=0.7"])
    assert proc.returncode == 0, proc.stderr
    assert marker.read_text() == "yes"
    assert _strict_json(proc.stdout)["stable"] is True
    bad = _run_program(handler, ["orbit", "trilinear", "--json", "--set", "omgea=1"])
    assert bad.returncode == 2 and bad.stdout == "" and bad.stderr.startswith("saltation: error: unknown parameter")


def test_the_program_waits_for_a_running_thread(tmp_path):
    """Where a thread that is not a daemon still runs when the command returns, ``cli.run`` exits the usual
    way, which waits for it: what the thread writes is there."""
    marker = tmp_path / "thread_done"
    thread = f"threading.Thread(target=lambda: (time.sleep(1.0), pathlib.Path({str(marker)!r}).write_text('done'))).start()"
    proc = _run_program(thread, ["--version"])
    assert proc.returncode == 0, proc.stderr
    assert marker.read_text() == "done"
