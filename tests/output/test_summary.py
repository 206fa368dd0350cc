"""The Markdown summaries a notebook shows for a model, an orbit, a branch and a special point."""

from __future__ import annotations

import numpy as np

from saltation import continue_orbit, find_periodic_orbit
from saltation.models import trilinear
from saltation.summary import summary


def test_model_summary_lists_modes_surfaces_and_transitions():
    system = trilinear()
    text = system._repr_markdown_()
    assert text == summary(system)
    for name in (*system.mode_names, *system.surface_names, *system.state_names):
        assert name in text
    assert text.count("| transition ") == len(system.transitions)
    assert "forced, period `2*pi/omega`" in text


def test_orbit_and_branch_summaries_carry_their_numbers(trilinear_flow):
    orbit = find_periodic_orbit(trilinear_flow, [0.5, 0.5], parameters={"omega": 1.2})
    text = orbit._repr_markdown_()
    assert f"{orbit.period:.10g}" in text and f"{2 * np.pi / 1.2:.10g}" in text
    assert ("(stable)" in text) == orbit.stable
    for mu in orbit.multipliers:
        assert f"{abs(mu):.6g}" in text

    start = find_periodic_orbit(trilinear_flow, [0.5, 0.5], parameters={"omega": 0.85})
    branch = continue_orbit(start, "omega", bounds=(0.85, 0.95))  # through the corner at w_A
    assert branch.special_points
    text = branch._repr_markdown_()
    assert f"{len(branch)} ({int(branch.stable.sum())} stable)" in text
    for sp in branch.special_points:
        assert f"{sp.parameter:.10g}" in text
        assert sp.kind.value in sp._repr_markdown_()
        assert f"{sp.parameter:.12g}" in sp._repr_markdown_()
