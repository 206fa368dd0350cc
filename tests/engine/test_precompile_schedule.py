"""How a cold build shares its compile jobs between interpreters (saltation.engine.precompile.schedule)."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation.engine.codegen import COMPILE_GROUP_SECONDS
from saltation.engine.precompile import model_seconds, schedule
from saltation.models import block_on_belt, trilinear


def _makespan(costs: list[float], shares: list[list[int]]) -> float:
    return max(sum(costs[k] for k in share) for share in shares)


def _best_makespan(costs: list[float], workers: int) -> float:
    """The optimum by brute force over every assignment (small instances only)."""
    best = float("inf")
    for owner in itertools.product(range(workers), repeat=len(costs)):
        loads = [0.0] * workers
        for k, w in enumerate(owner):
            loads[w] += costs[k]
        best = min(best, max(loads))
    return best


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(min_value=0.1, max_value=30.0), min_size=1, max_size=7), st.integers(1, 3))
def test_every_job_runs_once_within_graham_bound(costs, workers):
    """Each job is given to exactly one interpreter, no more interpreters than asked are used, and the
    longest one finishes within 4/3 - 1/(3 m) of the best possible time (Graham's bound for the
    longest-processing-time rule, against the optimum found by brute force)."""
    shares = schedule(costs, workers)
    assert sorted(k for share in shares for k in share) == list(range(len(costs)))
    assert 1 <= len(shares) <= workers and all(shares)
    bound = (4.0 / 3.0 - 1.0 / (3.0 * workers)) * _best_makespan(costs, workers)
    assert _makespan(costs, shares) <= bound * (1.0 + 1e-12)  # (sums of the same floats in another order)


def test_longest_first_within_each_interpreter():
    """Each interpreter runs its share longest first, and the two engine groups go to different ones."""
    costs = [*COMPILE_GROUP_SECONDS, 3.0, 4.9, 2.0]
    shares = schedule(costs, 2)
    for share in shares:
        assert [costs[k] for k in share] == sorted((costs[k] for k in share), reverse=True)
    assert {shares[0][0], shares[1][0]} == {0, 1}


def test_the_papers_cold_build_is_balanced():
    """The paper's cold build (one engine in two groups, three models' functions) on two cores: the
    block-on-belt model, the larger one, joins the engine's shorter group, and the two interpreters'
    estimated work differs by less than a model's."""
    from saltation.apps.paper import smoothed_block_on_belt

    models = [trilinear(), block_on_belt(), smoothed_block_on_belt()]
    costs = [*COMPILE_GROUP_SECONDS, *(model_seconds(m) for m in models)]
    assert model_seconds(models[1]) > model_seconds(models[0]) > model_seconds(models[2])
    shares = schedule(costs, 2)
    loads = [sum(costs[k] for k in share) for share in shares]
    assert abs(loads[0] - loads[1]) < min(costs[2:])
    shorter_group = next(share for share in shares if 1 in share)
    assert 3 in shorter_group  # block_on_belt


def _record_a_cold_build(monkeypatch) -> tuple[list[str], object]:
    """Nothing cached, interpreters that do nothing: the events of a build (starts, models built, the
    run's jobs and interpreters) and a generator of two models that records each build."""
    import subprocess
    import sys

    from saltation.engine import precompile

    events: list[str] = []

    def start():
        events.append("start")
        return subprocess.Popen([sys.executable, "-c", ""], stdin=subprocess.PIPE)

    def models():
        for make in (trilinear, block_on_belt):
            events.append("build")
            yield make()

    monkeypatch.setattr(precompile, "is_compiled", lambda system: False)
    monkeypatch.setattr(precompile, "is_engine_compiled", lambda n: False)
    monkeypatch.setattr(precompile, "_start_worker", start)
    monkeypatch.setattr(precompile, "_run_in_processes",
                        lambda jobs, workers: events.append(f"run {len(jobs)} jobs, {len(workers)} interpreter(s)"))
    return events, models()


def test_the_interpreters_start_before_the_models_are_built(monkeypatch):
    """Given the engines' dimensions, a cold build starts its interpreters first and only then builds
    the models (a generator, consumed after the start), so that their imports overlap; this process
    keeps a share, so two processes in all use one interpreter."""
    from saltation.engine import precompile

    events, models = _record_a_cold_build(monkeypatch)
    assert precompile.compile_in_parallel(models, workers=2, dimensions=(2,)) == ["trilinear", "block_on_belt"]
    assert events == ["start", "build", "build", "run 4 jobs, 1 interpreter(s)"]


def test_a_machine_of_many_cores_starts_what_the_jobs_keep_busy(monkeypatch):
    """With 8 cores, two interpreters start early (the engine's two groups), a third once the models are
    known (four jobs: this process and three interpreters), and no more."""
    from saltation.engine import precompile

    events, models = _record_a_cold_build(monkeypatch)
    assert precompile.compile_in_parallel(models, workers=8, dimensions=(2,)) == ["trilinear", "block_on_belt"]
    assert events == ["start", "start", "build", "build", "start", "run 4 jobs, 3 interpreter(s)"]


def test_nothing_to_share_starts_no_interpreter(monkeypatch):
    """One job (or none) is left to the caller's first use: no interpreter is started, and one started
    early, for an engine that turns out to be the only job, is stopped."""
    from saltation.engine import precompile

    started = []
    monkeypatch.setattr(precompile, "is_compiled", lambda system: True)
    monkeypatch.setattr(precompile, "_run_in_processes", lambda jobs, workers: pytest.fail("nothing to run"))
    real_start = precompile._start_worker
    monkeypatch.setattr(precompile, "_start_worker", lambda: started.append(real_start()) or started[-1])
    monkeypatch.setattr(precompile, "is_engine_compiled", lambda n: True)
    assert precompile.compile_in_parallel([trilinear()], workers=2) == []
    assert started == []
    monkeypatch.setattr(precompile, "COMPILE_GROUPS", (("_integrate_steps",),))  # one group: a single job
    monkeypatch.setattr(precompile, "is_engine_compiled", lambda n: False)
    assert precompile.compile_in_parallel([trilinear()], workers=2, dimensions=(2,)) == []
    assert len(started) == 1 and started[0].returncode is not None  # stopped, and waited for


def test_a_worker_given_no_jobs_exits():
    """A worker reads its jobs from standard input: given none, it exits at once, with status 0."""
    from saltation.engine import precompile

    worker = precompile._start_worker()
    precompile._give_jobs(worker, [])
    assert worker.wait(timeout=120) == 0


def test_a_build_within_a_build_is_announced_once():
    """The process's own share of a parallel build compiles through the calls a first use makes, which
    announce themselves: within the build's notice they say nothing more."""
    import io

    from saltation.engine.codegen import building

    log = io.StringIO()
    with building("compiling the integrator", stream=log), building("compiling the integrator for N_STATE = 2", stream=log):
        pass
    with building("compiling the functions of 1 model", stream=log):
        pass
    assert log.getvalue() == "saltation: compiling the integrator\nsaltation: compiling the functions of 1 model\n"
