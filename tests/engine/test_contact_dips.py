"""Contacts that dip through a surface within one step are never lost on the DOP853 path.

The suite's wall oscillator (``conftest.oscillator_system``: modes ``below`` and ``above`` share the field
``x'' = -x``, so the wall ``x = a`` changes nothing but the mode): ``x = sin(t + phi)`` reaches ``a = 1 - delta``
at ``t = asin(a) - phi + 2 pi k`` (upwards), a contact ``2 sqrt(2 delta)`` long, much shorter than a step.  With
``Tolerances(exact_affine=False)`` every step is a DOP853 step, as in every nonlinear mode, and such a contact is
seen on the dense output as a dip through the wall; the step's own solution is then checked at the dip's bottom.
That check used the first point of the dip search below zero, which may lie at the dip's edge, where the step's
solution and the dense output differ by more than the depth there: contacts 1e-8 deep were lost at rtol 1e-10
(phi = 3.87358185436469: the one at t = 16.546628973; delta = 1e-9, phi = 4.786297551067168: t = 9.350824669).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import oscillator_system
from saltation import Flow, Tolerances

SPAN = 20 * math.pi


@pytest.fixture(scope="module")
def flows():
    system = oscillator_system()
    return {rtol: Flow(system, tolerances=Tolerances(rtol=rtol, atol=1e-2 * rtol, exact_affine=False))
            for rtol in (1e-10, 1e-6)}


def contacts(flow, delta: float, phi: float):
    """The upward crossings logged, and those of the closed form whose contact ends before the run does."""
    a = 1.0 - delta
    traj = flow.run([math.sin(phi), math.cos(phi)], 0.0, SPAN, flow.parameters({"a": a}))
    logged = np.array([e.t for e in traj.events if e.mode_to == "above"])
    width = 2.0 * math.sqrt(2.0 * delta)
    ref = [math.asin(a) - phi + 2 * math.pi * k for k in range(-1, 12)]
    return logged, [t for t in ref if 0.0 < t and t + width < SPAN - 1e-3]


def check(flow, delta: float, phi: float, rtol: float):
    logged, ref = contacts(flow, delta, phi)
    assert len(logged) == len(ref), (delta, phi, sorted(set(np.round(ref, 6)) - set(np.round(logged, 6))))
    # a crossing at speed sqrt(2 delta) is located to the state's error over that speed (100 rtol: the error
    # the run accumulates over ten periods)
    tol = 100 * rtol / math.sqrt(2 * delta)
    assert np.all(np.abs(np.sort(logged) - np.sort(ref)) <= tol)


@pytest.mark.parametrize("delta, phi", [(1e-8, 3.87358185436469), (1e-9, 4.786297551067168)])
def test_the_contacts_once_lost(flows, delta, phi):
    check(flows[1e-10], delta, phi, 1e-10)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, 2 * math.pi), st.sampled_from([(1e-10, 1e-9), (1e-10, 1e-8), (1e-10, 1e-6), (1e-6, 1e-5),
                                                     (1e-6, 1e-3)]))
def test_no_contact_ten_times_deeper_than_rtol_is_lost(flows, phi, setting):
    rtol, delta = setting
    check(flows[rtol], delta, phi, rtol)
