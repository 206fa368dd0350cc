"""The chain of masses with trilinear contacts on its last mass (the scaling benchmark model)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import TIGHT, central_difference_jacobian
from saltation import Flow
from saltation.models import chain
from saltation.orbits.shooting import find_periodic_orbit


@pytest.fixture(scope="module")
def chain1_flow() -> Flow:
    return Flow(chain(1))


@pytest.fixture(scope="module")
def chain2_flow() -> Flow:
    return Flow(chain(2))


def test_structure():
    sys2 = chain(2, k_f=5.0)
    assert sys2.name == "chain2"
    assert sys2.state_names == ("x1", "x2", "v1", "v2")
    assert sys2.mode_names == ("contact_1", "contact_2", "free")
    assert dict(zip(sys2.parameter_names, sys2.parameter_vector()))["k_f"] == 5.0
    # the contact acts on the last mass only: the modes differ in its acceleration alone
    free, contact = sys2.fields[sys2.mode_index("free")], sys2.fields[sys2.mode_index("contact_1")]
    assert [sp_expr == 0 for sp_expr in (contact - free)] == [True, True, True, False]
    with pytest.raises(ValueError, match="positive integer"):
        chain(0)


@pytest.mark.parametrize("omega", [0.7, 1.0, 1.5])
def test_one_mass_is_the_trilinear_system(trilinear_flow, chain1_flow, omega):
    """Same orbit, events and multipliers as ``trilinear()`` (no contact at 0.7 and 1.5, four contacts at 1.0)."""
    p = trilinear_flow.parameters({"omega": omega})
    guess = trilinear_flow.run([0.0, 0.0], 0.0, 100 * 2 * np.pi / omega, p).x1
    ref = find_periodic_orbit(trilinear_flow, guess, parameters={"omega": omega})
    orb = find_periodic_orbit(chain1_flow, guess, parameters={"omega": omega})
    np.testing.assert_allclose(orb.state0, ref.state0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(orb.monodromy, ref.monodromy, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.sort_complex(orb.multipliers), np.sort_complex(ref.multipliers), rtol=0, atol=1e-9)
    assert [e.surface for e in orb.events] == [e.surface for e in ref.events]
    np.testing.assert_allclose([e.t for e in orb.events], [e.t for e in ref.events], rtol=0, atol=1e-10)
    assert (len(ref.events) == 4) == (omega == 1.0)


def test_one_mass_trajectory_matches_in_every_mode(trilinear_flow, chain1_flow):
    """A transient through contacts with both supports: identical trajectories."""
    p = trilinear_flow.parameters({"omega": 1.1, "f0": 0.4})
    a = trilinear_flow.run([1.5, 0.0], 0.0, 30.0, p, variational=True)
    b = chain1_flow.run([1.5, 0.0], 0.0, 30.0, p, variational=True)
    assert a.mode0 == b.mode0 == "contact_1"
    assert [e.surface for e in a.events] == [e.surface for e in b.events] and len(a.events) >= 6
    np.testing.assert_allclose(b.x1, a.x1, atol=1e-12)
    np.testing.assert_allclose(b.monodromy, a.monodromy, atol=1e-10)


def test_two_mass_monodromy_against_finite_differences(chain2_flow):
    """Contact orbit near the first resonance (four events per period): variational vs central differences."""
    omega = 0.6
    p = chain2_flow.parameters({"omega": omega})
    T = 2 * np.pi / omega
    guess = chain2_flow.run(np.zeros(4), 0.0, 200 * T, p).x1
    orb = find_periodic_orbit(chain2_flow, guess, parameters={"omega": omega})
    assert [e.surface for e in orb.events] == ["h1a", "h1b", "h2a", "h2b"]
    assert orb.stable

    def period_map(x0):
        return chain2_flow.run(x0, 0.0, T, p, tolerances=TIGHT).x1

    fd = central_difference_jacobian(period_map, orb.state0, 1e-5)
    scale = np.max(np.abs(fd))
    assert np.max(np.abs(orb.monodromy - fd)) <= 1e-7 * scale
    # the saltation matrices matter: free flight alone gives a different monodromy
    free_only = chain2_flow.run(orb.state0, 0.0, T, chain2_flow.parameters({"omega": omega, "x_c": 100.0}), variational=True)
    assert np.max(np.abs(free_only.monodromy - fd)) > 1e-2 * scale


def test_two_mass_no_contact_multipliers_are_exp_of_the_linear_system(chain2_flow):
    """Without contact the chain is linear: multipliers are the eigenvalues of expm(A T)."""
    from scipy.linalg import expm

    omega = 1.6
    p = chain2_flow.parameters({"omega": omega})
    T = 2 * np.pi / omega
    guess = chain2_flow.run(np.zeros(4), 0.0, 200 * T, p).x1
    orb = find_periodic_orbit(chain2_flow, guess, parameters={"omega": omega})
    assert orb.events == []
    A = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [-2, 1, -0.1, 0.05], [1, -1, 0.05, -0.05]])  # m = k = 1, c = 0.05
    expected = np.sort_complex(np.linalg.eigvals(expm(A * T)))
    np.testing.assert_allclose(np.sort_complex(orb.multipliers), expected, atol=1e-9)
