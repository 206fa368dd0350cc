"""How a cold build shares its compile jobs between interpreters (saltation.engine.precompile.schedule)."""

from __future__ import annotations

import itertools

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
