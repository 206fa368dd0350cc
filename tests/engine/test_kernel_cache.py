"""The kernel cache: what a compiled module is keyed on, and what happens when the cache is damaged or
cannot be written (see the "Kernel cache" section of the README and :mod:`saltation.engine.codegen`).

Every test works in a fresh cache folder of its own (``SALTATION_CACHE_DIR`` in ``tmp_path``); the
2-state engine stays loaded in the process (or is copied, for the tests that start a new process), so
only the small test models compile here.  "The next run" is simulated in the process by forgetting the
imported module (:func:`_forget`), and once for real in a fresh interpreter.
"""

from __future__ import annotations

import errno
import logging
import os
import pickle
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition
from saltation.engine import codegen
from saltation.engine.codegen import KernelCacheError
from saltation.orbits.shooting import find_periodic_orbit

pytestmark = pytest.mark.slow  # builds kernel caches of its own (a compile per test)

ZETA, OMEGA = 0.05, 1.3


def forced_oscillator(
    *,
    name: str = "test_kernel_cache_oscillator",
    period: str = "2*pi/omega",
    domains: tuple[str, str] = ("x < 0", "x >= 0"),
    parameters: tuple[str, ...] = ("zeta", "omega"),
    field: str = "-x - 2*zeta*v + cos(omega*t)",
    surface: str = "x",
    guard: tuple[str, ...] = (),
    reset: tuple[str, str] | None = None,
) -> PiecewiseSystem:
    """``x'' + 2 zeta x' + x = cos(omega t)``, written as two modes with the same field on either side of
    ``x = 0`` (so that the domains decide which mode a state starts in).  Affine with one harmonic: the
    integrator uses the exact flow, and everything has a closed form (:func:`steady_state`)."""
    values = {"zeta": ZETA, "omega": OMEGA}
    return PiecewiseSystem(
        name,
        states=["x", "v"],
        parameters={q: values[q] for q in parameters},
        modes=[Mode("left", ["v", field], domain=[domains[0]]), Mode("right", ["v", field], domain=[domains[1]])],
        surfaces={"s": surface},
        transitions=[
            Transition("left", "s", Crossing.RISING, "right", guard=list(guard)),
            Transition("right", "s", Crossing.FALLING, "left", reset=None if reset is None else list(reset)),
        ],
        period=period,
    )


def steady_state(t: float) -> np.ndarray:
    """The forced oscillator's periodic solution ``Re(exp(i omega t) / (1 - omega^2 + 2 i zeta omega))``."""
    z = np.exp(1j * OMEGA * t) / (1 - OMEGA**2 + 2j * ZETA * OMEGA)
    return np.array([z.real, (1j * OMEGA * z).real])


def floquet_multipliers(period: float) -> np.ndarray:
    """``exp(lambda T)`` for the eigenvalues ``lambda = -zeta +- i sqrt(1 - zeta^2)`` of the linear part."""
    lam = -ZETA + 1j * np.sqrt(1 - ZETA**2)
    return np.sort_complex(np.exp(np.array([lam, lam.conjugate()]) * period))


# -- a fresh cache per test ----------------------------------------------------------------------------


class _Stderr(logging.Handler):
    """The engine's records as lines ``saltation: MESSAGE`` on the standard error of the moment, as an
    application (the command line) that shows them does."""

    def emit(self, record: logging.LogRecord) -> None:
        print(f"saltation: {record.getMessage()}", file=sys.stderr)


@pytest.fixture(autouse=True)
def _engine_records_on_stderr():
    """The library is quiet by default (it logs); these tests read what it says about the cache on stderr."""
    handler, logger = _Stderr(logging.INFO), logging.getLogger("saltation.engine")
    level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    yield
    logger.removeHandler(handler)
    logger.setLevel(level)



@pytest.fixture(scope="module")
def engine() -> tuple[Path, str]:
    """The 2-state engine, loaded in this process; where it is cached and its module name."""
    codegen.load_engine(2)
    return codegen.active_cache_directory(), codegen._engine_module(2)[0]


@pytest.fixture
def cache(tmp_path, monkeypatch, engine) -> Path:
    """A fresh, empty kernel cache folder; the process keeps its engine but forgets every model module."""
    primary = tmp_path / "cache"
    monkeypatch.setenv("SALTATION_CACHE_DIR", str(primary))
    engines = {k: v for k, v in codegen._LOADED.items() if k.startswith("_saltation_engine_")}
    monkeypatch.setattr(codegen, "_LOADED", engines)
    monkeypatch.setattr(codegen, "_ACTIVE", {})
    monkeypatch.setattr(codegen, "_NOTICES", set())
    monkeypatch.setattr(codegen, "_FOUND", set())
    monkeypatch.setattr(codegen, "fallback_directory", lambda: tmp_path / "fallback")
    return primary


def _forget(system: PiecewiseSystem) -> None:
    """Forget the imported module of ``system``, so that the next Flow imports it from the disk again (as
    the next run would)."""
    modname = f"_saltation_model_{codegen._model_module(system)[0]}"
    codegen._LOADED.pop(modname, None)
    sys.modules.pop(modname, None)


def _module_file(system: PiecewiseSystem) -> Path:
    return codegen._model_path(system)


def _numba_files(system: PiecewiseSystem) -> list[Path]:
    path = _module_file(system)
    return codegen._numba_files(codegen._numba_cache_dir(path.parent), path.stem)


def _run(flow: Flow):
    """A trajectory from the steady state over 5 time units, with its monodromy."""
    return flow.run(steady_state(0.0), 0.0, 5.0, flow.parameters(), variational=True)


def _assert_same(tr, reference) -> None:
    np.testing.assert_allclose(tr.x1, reference.x1, rtol=0, atol=1e-15)
    np.testing.assert_allclose(tr.monodromy, reference.monodromy, rtol=0, atol=1e-15)


def _loaded_from_cache(flow: Flow) -> bool:
    """Whether every function of the flow's model was loaded from numba's cache, none compiled."""
    dispatchers = flow._model[: len(codegen.MODEL_FUNCTIONS)]
    return all(sum(d.stats.cache_hits.values()) == 1 and not d.stats.cache_misses for d in dispatchers)


# -- 1. the key covers everything compiled -------------------------------------------------------------


@pytest.mark.parametrize("first", ["2*pi/omega", "4*pi/omega"])
def test_models_differing_only_in_their_period_have_their_own_periods(cache, first):
    """A model with twice the forcing period (to look for subharmonics) is not integrated over the first
    one's period: each finds the steady state (closed form) with its own period and its own multipliers
    ``exp(lambda T)``.  In either order, in one process and a fresh cache; even with equal fingerprints."""
    periods = {"2*pi/omega": 2 * np.pi / OMEGA, "4*pi/omega": 4 * np.pi / OMEGA}
    order = [first] + [p for p in periods if p != first]
    systems = [forced_oscillator(period=p) for p in order]
    for s in systems:
        s.__dict__["fingerprint"] = "the same fingerprint"  # the key does not rely on it
    flows = [Flow(s) for s in systems]
    assert _module_file(systems[0]) != _module_file(systems[1])
    for flow, expr in zip(flows, order):
        orbit = find_periodic_orbit(flow, [0.0, 0.0], tol=1e-12)
        assert orbit.period == pytest.approx(periods[expr], rel=1e-15)
        np.testing.assert_allclose(orbit.state0, steady_state(0.0), rtol=0, atol=1e-10)
        np.testing.assert_allclose(np.sort_complex(orbit.multipliers), floquet_multipliers(periods[expr]),
                                   rtol=0, atol=1e-10)


def test_models_differing_only_in_a_domain_start_in_their_own_modes(cache):
    """On ``x = 0`` the state starts in the right mode when its domain is ``x >= 0`` and in the left one
    when the left's is ``x <= 0``: the domains (and their strictness) are compiled, so they are keyed."""
    closed = forced_oscillator(domains=("x < 0", "x >= 0"))
    open_ = forced_oscillator(domains=("x <= 0", "x > 0"))
    for s in (closed, open_):
        s.__dict__["fingerprint"] = "the same fingerprint"
    on_surface, p = np.array([0.0, 1.0]), Flow(closed).parameters()
    for system, expected in ((closed, "right"), (open_, "left"), (closed, "right")):
        flow = Flow(system)
        assert system.mode_names[flow.initial_mode(on_surface, p)] == expected
        assert flow.run(on_surface, 0.0, 0.01, p).mode0 == expected
        assert system.mode_names[flow.initial_mode(np.array([-1e-300, 0.0]), p)] == "left"


def test_the_module_name_changes_with_everything_compiled():
    """Each change to what is compiled gives a module of its own; the same model built again, or in
    another process with other hash seeds, gives the same one (no recompilation from run to run)."""
    variants = {
        "base": forced_oscillator(),
        "period": forced_oscillator(period="4*pi/omega"),
        "strictness of a domain": forced_oscillator(domains=("x <= 0", "x > 0")),
        "a domain": forced_oscillator(domains=("x < 0", "x >= 1")),
        "order of the parameters": forced_oscillator(parameters=("omega", "zeta")),
        "field": forced_oscillator(field="-x - 2*zeta*v + 0.5*cos(omega*t)"),
        "surface": forced_oscillator(surface="x + v/10"),
        "guard": forced_oscillator(guard=("v > 0",)),
        "reset": forced_oscillator(reset=("x", "-0.9*v")),
        "name": forced_oscillator(name="test_kernel_cache_renamed"),
    }
    stems = {what: codegen._model_module(s)[0] for what, s in variants.items()}
    assert len(set(stems.values())) == len(stems), stems
    assert codegen._model_module(forced_oscillator())[0] == stems["base"]
    # the versions of numba and Python are part of the key
    versions = codegen._versions
    try:
        codegen._versions = lambda: versions() + " (another numba)"
        assert codegen._model_module(forced_oscillator())[0] != stems["base"]
    finally:
        codegen._versions = versions
    # the same name in a fresh interpreter, whatever its hash seed
    script = (
        f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); from saltation.engine import codegen; "
        "from test_kernel_cache import forced_oscillator; print(codegen._model_module(forced_oscillator())[0])"
    )
    for seed in ("0", "12345"):
        out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True,
                             env={**os.environ, "PYTHONHASHSEED": seed})
        assert out.stdout.strip() == stems["base"]


def test_a_module_holding_another_models_source_is_rewritten(cache, capsys):
    """The file named after a model's source is checked against that source before it is imported: the
    twice-as-long period's module overwritten by the other model's (both valid Python) is detected."""
    short, long_ = forced_oscillator(), forced_oscillator(period="4*pi/omega")
    Flow(short), Flow(long_)
    _forget(long_)
    _module_file(long_).write_bytes(_module_file(short).read_bytes())
    orbit = find_periodic_orbit(Flow(long_), [0.0, 0.0], tol=1e-12)
    assert orbit.period == pytest.approx(4 * np.pi / OMEGA, rel=1e-15)
    assert "was damaged" in capsys.readouterr().err
    assert _module_file(long_).read_text() == codegen._model_module(long_)[1]


# -- 2. a damaged cache is rebuilt ---------------------------------------------------------------------


def _copy_engine(engine: tuple[Path, str], cache: Path) -> None:
    """Copy the compiled 2-state engine into a fresh cache folder (compiling it takes a minute)."""
    real, stem = engine
    target = codegen._numba_cache_dir(cache)
    target.mkdir(parents=True, exist_ok=True)
    shutil.copy(real / f"{stem}.py", cache)
    for f in codegen._numba_files(codegen._numba_cache_dir(real), stem):
        shutil.copy(f, target)


def _truncate(path: Path, keep: float = 0.5) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * keep)])


def _damage(system: PiecewiseSystem, how: str) -> None:
    module, files = _module_file(system), _numba_files(system)
    index = next(f for f in files if ".vector_field-" in f.name and f.suffix == ".nbi")
    data = next(f for f in files if ".vector_field-" in f.name and f.suffix == ".nbc")
    if how == "truncated module":
        _truncate(module)
    elif how == "empty module":
        module.write_bytes(b"")
    elif how == "truncated index":
        _truncate(index)
    elif how == "garbage index":
        index.write_bytes(b"garbage\n")
    elif how == "truncated data":
        for f in files:
            if f.suffix == ".nbc":
                _truncate(f, 0.1)
    elif how == "data of the wrong kind":  # whole pickles: only loading them fails
        data.write_bytes(pickle.dumps(("not", "a compiled function")))
    else:
        raise AssertionError(how)


DAMAGES = ["truncated module", "empty module", "truncated index", "garbage index", "truncated data",
           "data of the wrong kind"]


@pytest.mark.parametrize("how", DAMAGES)
def test_a_damaged_cache_entry_is_rebuilt(cache, capsys, how):
    """The next Flow of a model whose cached module or numba files were damaged works, says what it
    rebuilt, and integrates as before (to 1e-15) and as the closed form says; after the repair the one
    after loads everything from the cache again."""
    system = forced_oscillator()
    reference = _run(Flow(system))
    np.testing.assert_allclose(reference.x1, steady_state(5.0), rtol=0, atol=1e-12)
    _forget(system)
    _damage(system, how)
    _assert_same(_run(Flow(system)), reference)
    err = capsys.readouterr().err
    assert "damaged" in err or "did not load" in err, err
    assert str(cache) in err
    assert _module_file(system).read_text() == codegen._model_module(system)[1]
    _forget(system)
    again = Flow(system)
    assert _loaded_from_cache(again)
    _assert_same(_run(again), reference)
    assert capsys.readouterr().err == ""


def test_a_damaged_engine_module_is_rewritten_without_recompiling(cache, engine, monkeypatch):
    """The engine's module file truncated: it is rewritten, and numba's cache of it (keyed on the
    source's contents) still serves, so the engine is not compiled again."""
    stem = engine[1]
    _copy_engine(engine, cache)
    _truncate(cache / f"{stem}.py")
    modname = f"_saltation_engine_{stem}"
    monkeypatch.setitem(sys.modules, modname, sys.modules[modname])  # the process's engine, back afterwards
    codegen._LOADED.pop(modname)
    module = codegen.load_engine(2)
    assert (cache / f"{stem}.py").read_text() == codegen._engine_module(2)[1]
    flow = Flow(forced_oscillator())
    assert flow._engine is module
    np.testing.assert_allclose(_run(flow).x1, steady_state(5.0), rtol=0, atol=1e-12)
    assert sum(module.integrate_kernel.stats.cache_hits.values()) == 1
    assert not module.integrate_kernel.stats.cache_misses


def test_what_cannot_be_rebuilt_names_the_folder_to_delete(cache, monkeypatch):
    """A damaged module that cannot be rewritten (the disk is full) raises KernelCacheError naming the
    cache folder to delete, not an OSError from deep inside."""
    system = forced_oscillator()
    Flow(system)
    _forget(system)
    _truncate(_module_file(system))

    def disk_full(path, data):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(codegen, "_write_atomic", disk_full)
    with pytest.raises(KernelCacheError, match="No space left") as info:
        Flow(system)
    assert f"delete the folder {cache}" in str(info.value)


def test_numba_unable_to_cache_is_a_kernel_cache_error(cache, monkeypatch):
    """numba's "no locator" (it found no folder it can write) becomes a KernelCacheError naming the
    folder; a genuine error of the generated code is not disguised as one."""
    system = forced_oscillator()

    def no_locator(path, modname):
        raise RuntimeError(f"cannot cache function 'vector_field': no locator available for file {str(path)!r}")

    monkeypatch.setattr(codegen, "_execute", no_locator)
    with pytest.raises(KernelCacheError, match="no locator") as info:
        Flow(system)
    assert str(cache) in str(info.value)

    def typing_error(path, modname):
        raise TypeError("a fault of the generated code")

    monkeypatch.setattr(codegen, "_execute", typing_error)
    with pytest.raises(TypeError, match="generated code"):
        Flow(forced_oscillator(period="4*pi/omega"))


def test_a_new_process_repairs_a_damaged_cache(cache, engine):
    """End to end, in fresh interpreters: a run compiles the model into a fresh cache (with a copy of the
    engine); its module is truncated and its numba index and data damaged; the next run repairs them and
    prints the same trajectory, bit for bit."""
    _copy_engine(engine, cache)
    script = textwrap.dedent(f"""
        import logging
        import sys
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        logging.basicConfig(format="saltation: %(message)s")  # (the library logs; this run shows its warnings)
        from saltation import Flow
        from test_kernel_cache import forced_oscillator, _run
        tr = _run(Flow(forced_oscillator()))
        print([v.hex() for v in [*tr.x1, *tr.monodromy.ravel()]])
    """)

    def run():
        return subprocess.run([sys.executable, "-c", script], check=False, capture_output=True, text=True, timeout=600,
                              env={**os.environ, "SALTATION_CACHE_DIR": str(cache)})

    first = run()
    assert first.returncode == 0, first.stderr
    assert "compiling the integrator" not in first.stderr  # the copied engine served
    system = forced_oscillator()
    _damage(system, "truncated module")
    _damage(system, "garbage index")
    _damage(system, "truncated data")
    second = run()
    assert second.returncode == 0, second.stderr
    assert second.stdout == first.stdout
    assert "damaged" in second.stderr and str(cache) in second.stderr
    third = run()
    assert third.returncode == 0 and third.stdout == first.stdout and third.stderr == ""


# -- 2. a cache that cannot be written -----------------------------------------------------------------


def _tree(folder: Path) -> dict[str, tuple[int, int]]:
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns) for p in folder.rglob("*")}


def _read_only(monkeypatch, folder: Path) -> None:
    """Make saltation see ``folder`` as not writable (tests run as root, who writes through chmod)."""
    original = codegen._write_problem

    def problem(directory):
        if directory == folder:
            return f"{folder}: PermissionError: Permission denied"
        return original(directory)

    monkeypatch.setattr(codegen, "_write_problem", problem)


def test_a_read_only_cache_is_used_through_the_fallback_folder(cache, tmp_path, monkeypatch, capsys):
    """With the cache folder not writable, a model compiled in it is copied to the per-user fallback
    folder and loaded from numba's cache there (not compiled again), the folder is left untouched, and
    the process says so once on standard error, naming both folders."""
    system = forced_oscillator()
    reference = _run(Flow(system))
    _forget(system)
    before = _tree(cache)
    _read_only(monkeypatch, cache)
    monkeypatch.setattr(codegen, "_ACTIVE", {})
    flow = Flow(system)
    assert _loaded_from_cache(flow)
    _assert_same(_run(flow), reference)
    fallback = tmp_path / "fallback"
    assert _module_file(system).parent == fallback
    assert _module_file(system).read_text() == codegen._model_module(system)[1]
    other = Flow(forced_oscillator(period="4*pi/omega"))  # a new model compiles in the fallback folder
    assert codegen._model_path(other.system).parent == fallback
    _forget(system)
    Flow(system)
    err = capsys.readouterr().err
    assert err.count("cannot be written") == 1, err
    assert str(cache) in err and str(fallback) in err
    assert _tree(cache) == before


def test_a_read_only_cache_without_a_usable_fallback_says_why(cache, tmp_path, monkeypatch):
    """The fallback folder must be the user's own and writable by no one else (its modules are
    imported): one that others can write is refused, and the error names both folders."""
    _read_only(monkeypatch, cache)
    fallback = tmp_path / "fallback"
    fallback.mkdir()
    fallback.chmod(0o777)
    with pytest.raises(KernelCacheError) as info:
        Flow(forced_oscillator())
    message = str(info.value)
    assert str(cache) in message and str(fallback) in message and "others can write" in message
    assert "SALTATION_CACHE_DIR" in message


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0,
                    reason="root writes to read-only folders, so chmod cannot make the cache read-only; "
                           "test_a_read_only_cache_is_used_through_the_fallback_folder simulates it instead")
def test_a_folder_made_read_only_with_chmod(cache, tmp_path, capsys):
    """The same with a real read-only folder (as a user other than root)."""
    system = forced_oscillator()
    reference = _run(Flow(system))
    _forget(system)
    codegen._ACTIVE.clear()
    folders = [cache / "__pycache__", cache]
    for f in folders:
        f.chmod(0o555)
    try:
        flow = Flow(system)
        assert _loaded_from_cache(flow)
        _assert_same(_run(flow), reference)
        assert _module_file(system).parent == tmp_path / "fallback"
    finally:
        for f in reversed(folders):
            f.chmod(0o755)
    assert capsys.readouterr().err.count("cannot be written") == 1


def test_only_long_generated_functions_skip_llvm_optimization():
    """Functions longer than UNOPTIMIZED_FUNCTION_LINES are compiled unoptimized (their optimization time
    grows faster than their length); the paper's models and small chains keep every function optimized,
    and so their modules (named by the hash of their source) are unchanged."""
    from saltation.engine.codegen import UNOPTIMIZED_FUNCTION_LINES, _skip_optimization_of_long_functions, generate_source
    from saltation.models import block_on_belt, chain, trilinear

    short = ["@njit(MODEL_SIGNATURES['f'], cache=True)", "def f(x):", "    return x"]
    long = ["@njit(MODEL_SIGNATURES['g'], cache=True)", "def g(x):"] + ["    y = x"] * UNOPTIMIZED_FUNCTION_LINES
    out = _skip_optimization_of_long_functions(short + long)
    assert out[0] == short[0]
    assert out[len(short)] == "@njit(MODEL_SIGNATURES['g'], cache=True, _dbg_optnone=True)"
    for system in (trilinear(), block_on_belt(), chain(8)):
        assert "_dbg_optnone" not in generate_source(system)
    assert "_dbg_optnone" in generate_source(chain(16))


def test_a_model_compiled_without_optimization_computes_the_same(monkeypatch):
    """Every function of a model left unoptimized (the threshold lowered to 3 lines): its orbit's
    multipliers are still the eigenvalues of expm(A T) of the damped linear oscillator, to 1e-10."""
    from scipy.linalg import expm

    from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition, find_periodic_orbit
    from saltation.engine import codegen

    monkeypatch.setattr(codegen, "UNOPTIMIZED_FUNCTION_LINES", 3)
    system = PiecewiseSystem(
        name="test_unoptimized_oscillator", states=["x", "v"], parameters={"c": 0.3, "k": 2.0, "w": 1.7, "xc": 50.0},
        modes=[Mode("free", ["v", "-c*v - k*x + cos(w*t)"])], surfaces={"wall": "x - xc"},
        transitions=[Transition("free", "wall", Crossing.RISING, "free", reset=["x", "-v"])], period="2*pi/w",
    )
    assert "_dbg_optnone" in codegen.generate_source(system)
    orbit = find_periodic_orbit(Flow(system), [0.0, 0.0])
    T = 2 * np.pi / 1.7
    expected = np.linalg.eigvals(expm(np.array([[0.0, 1.0], [-2.0, -0.3]]) * T))
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), np.sort_complex(expected), rtol=0, atol=1e-10)


def test_a_build_says_what_it_builds_and_keeps_moving_on_a_terminal():
    """On a terminal the notice is rewritten with the seconds elapsed until the build is done; elsewhere
    (a log, a pipe) it is one line."""
    import io
    import time

    from saltation.engine.codegen import building

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    term = Terminal()
    with building("compiling the integrator", stream=term, interval=0.02):
        time.sleep(0.2)
    text = term.getvalue()
    assert text.startswith("saltation: compiling the integrator")
    assert text.count("\rsaltation: compiling the integrator ... ") >= 2  # at least one tick, then "done"
    assert text.endswith(" s\n") and "... done in " in text
    log = io.StringIO()
    with building("compiling the integrator", stream=log, interval=0.02):
        time.sleep(0.05)
    assert log.getvalue() == "saltation: compiling the integrator\n"


def test_the_parallel_build_names_what_it_builds(monkeypatch, capsys):
    """The notice of a cold build names the models' sizes ("2-state models"), not a count of dimensions."""
    from saltation.engine import precompile
    from saltation.models import block_on_belt, trilinear

    monkeypatch.setattr(precompile, "is_compiled", lambda system: False)
    monkeypatch.setattr(precompile, "is_engine_compiled", lambda n: False)
    monkeypatch.setattr(precompile, "_run_in_processes", lambda jobs, workers: None)
    monkeypatch.setattr(precompile, "_start_worker", lambda: subprocess.Popen([sys.executable, "-c", ""], stdin=subprocess.PIPE))
    assert precompile.compile_in_parallel([trilinear(), block_on_belt()], workers=2) == ["trilinear", "block_on_belt"]
    err = capsys.readouterr().err
    assert "compiling the integrator for 2-state models" in err and "the functions of 2 models" in err


def test_the_newton_compiles_without_the_integrator(tmp_path):
    """The engine's Newton calls the integrator through its address, so on an empty cache it compiles on its own
    (in seconds, beside the integrator's build): after compiling only ``correct_periodic`` the cache holds no
    integrator.  (That the two, compiled in separate processes, work together is what every orbit test runs on
    after the suite's parallel build of a cold cache, ``tests/conftest.py``.)"""
    env = dict(os.environ, SALTATION_CACHE_DIR=str(tmp_path))
    newton_only = (
        "from saltation.engine import codegen; codegen.load_engine(2, ('correct_periodic',)); "
        "stem = codegen._engine_module(2)[0]; "
        "print(codegen._cached(stem, 'correct_periodic'), codegen._cached(stem, 'integrate_kernel'))"
    )
    out = subprocess.run([sys.executable, "-c", newton_only], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "False"], out.stderr


def test_the_suite_compiles_into_its_own_cache():
    """The suite (tests/conftest.py) sets the kernel cache to a folder of its own before anything compiles, so the
    user's cache (~/.cache/saltation, or their SALTATION_CACHE_DIR) is untouched by a test run; command-line runs
    the tests start inherit it."""
    from conftest import TEST_CACHE

    assert os.environ["SALTATION_CACHE_DIR"] == str(TEST_CACHE.resolve())
    user_default = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "saltation"
    assert TEST_CACHE.resolve() != user_default.resolve()
    assert codegen.cache_directory() == TEST_CACHE.resolve()


# -- 4. a warm start reads what it generated before ------------------------------------------------------


def test_a_warm_start_reads_the_generated_source_back_and_never_a_damaged_one(cache, monkeypatch):
    """The memo of generated sources: a new system object of the same model (a new process) gets the module
    generated before, read back from the cache folder, without generating it (sympy's work); a module file
    that no longer hashes to its name is not taken, and is generated again."""
    first = forced_oscillator()
    stem, source = codegen._model_module(first)
    Flow(first)  # writes the module (and its memo)

    def no_generation(system):
        raise AssertionError("generated again")

    monkeypatch.setattr(codegen, "model_source", no_generation)
    assert codegen._model_module(forced_oscillator()) == (stem, source)
    # another model (another fingerprint) is generated
    with pytest.raises(AssertionError, match="generated again"):
        codegen._model_module(forced_oscillator(field="-x - 3*zeta*v + cos(omega*t)"))
    # a damaged module file is not taken for the module
    _module_file(first).write_text(source[: len(source) // 2])
    assert codegen._remembered("model", codegen._definition(first)) is None
    monkeypatch.undo()
    monkeypatch.setenv("SALTATION_CACHE_DIR", str(cache))
    assert codegen._model_module(forced_oscillator()) == (stem, source)


def test_numba_files_found_whole_are_not_read_again_until_they_change(cache, monkeypatch):
    """Checking numba's files pickle by pickle takes a tenth of a second a start: their sizes and times,
    stamped when they were last found whole, stand for the check until a file changes."""
    system = forced_oscillator()
    reference = _run(Flow(system))
    stem, source = codegen._model_module(system)
    Flow(system)
    _forget(system)
    Flow(system)  # a second start: the files are checked and stamped
    stamp = codegen._numba_cache_dir(cache) / f"{stem}.saltation-intact.json"
    assert stamp.is_file()
    checked = []
    real = codegen._intact
    monkeypatch.setattr(codegen, "_intact", lambda path, pickles: checked.append(path) or real(path, pickles))
    _forget(system)
    _assert_same(_run(Flow(system)), reference)
    assert checked == []  # nothing changed: nothing read
    _forget(system)
    _damage(system, "truncated index")
    _assert_same(_run(Flow(system)), reference)
    assert checked  # a file changed: every file is read again, and the damaged one rebuilt
