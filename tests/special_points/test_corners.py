"""Orbits that pass within a hair of a corner of switching surfaces are never corrupted.

Near the paper's w_A and w_B the free orbit touches the corner of Sigma_1a and Sigma_1b
(and of Sigma_2a, Sigma_2b): a contact of depth d lasts O(sqrt(d)). A transition into
contact may then land where the contact force is already negative; the exit must fire at
once (a zero-length segment), never a contact that is never left.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from saltation.engine.flow import Tolerances
from saltation.models.trilinear import DEFAULTS as TRI
from saltation.apps.paper import linear_response_state

M, C, K, F0, XC, CF = (TRI[k] for k in ("m", "c", "k", "f0", "x_c", "c_f"))


def corner_frequencies():
    w2 = np.roots([M**2, C**2 - 2 * K * M, K**2 - (F0 / XC) ** 2])
    return np.sort(np.sqrt(w2[w2 > 0].real))


W_A, W_B = corner_frequencies()
# the free orbit at these frequencies reaches the supports by a depth of about d |dA/dw|
NEAR_CORNER = [W_A + d for d in (1e-8, 1e-10, 1e-12, 1e-13)] + [W_B - d for d in (1e-8, 1e-10, 1e-12, 1e-13)]


def contact_pairs(events) -> bool:
    """Every entry into a contact is followed by the exit from that contact."""
    modes = [(e.mode_from, e.mode_to) for e in events]
    if len(modes) % 2:
        return False
    return all(a[1] == b[0] != "free" and a[0] == b[1] == "free" for a, b in zip(modes[::2], modes[1::2]))


@pytest.mark.parametrize("exact", [True, False], ids=["exact", "dop853"])
@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8, 1e-10])
def test_near_corner_orbits_pair_their_events_and_end_right(trilinear_flow, exact, rtol):
    flow = trilinear_flow
    tol = Tolerances(rtol=rtol, atol=1e-2 * rtol, exact_affine=exact)
    reference_tol = Tolerances(rtol=1e-13, atol=1e-15)
    for w in NEAR_CORNER:
        p = flow.parameters({"omega": w})
        x0 = linear_response_state(dict(TRI, omega=w))
        T = 2 * np.pi / w
        traj = flow.run(x0, 0.0, T, p, tolerances=tol)
        ref = flow.run(x0, 0.0, T, p, tolerances=reference_tol)
        assert contact_pairs(traj.events), (w, [(e.mode_from, e.mode_to) for e in traj.events])
        assert contact_pairs(ref.events)
        assert traj.mode1 == "free"
        # The state error of the method, eps ~ rtol over a period (50 rtol bounds it on the no-contact
        # orbits), may decide whether a contact of depth eps happens at all. Such a contact lasts
        # 2 sqrt(2 eps / a) and changes the velocity by at most c_f/m times the entry velocity
        # sqrt(2 a eps) (S_1a, eq. 11): the state after one period is right to that.
        eps = 50.0 * rtol
        a_max = (K * XC + F0) / M + 1.0  # |x''| near the supports, with margin
        bound = eps + 2.0 * CF / M * np.sqrt(2.0 * a_max * eps)
        assert np.abs(traj.x1 - ref.x1).max() <= bound, (w, np.abs(traj.x1 - ref.x1).max(), bound)


def test_a_transition_beyond_an_exit_fires_the_exit_at_once(trilinear_flow):
    """Entering contact where the contact force is already negative: a zero-length contact with both
    saltation matrices, S_1b S_1a = S_1a (eqs. 11, 12)."""
    flow = trilinear_flow
    p = flow.parameters({"omega": 1.0})
    # on Sigma_1a, moving into the support (v > 0) but with k_f (x - x_c) + c_f v < 0 is impossible;
    # start in contact with a negative contact force instead: the exit through h1b fires at t0
    x0 = np.array([XC + 1e-3, -0.1])  # k_f 1e-3 - c_f 0.1 < 0
    traj = flow.run(x0, 0.0, 0.1, p, mode0="contact_1", variational=True)
    first = traj.events[0]
    assert first.t == 0.0 and first.mode_from == "contact_1" and first.mode_to == "free" and first.surface == "h1b"
    np.testing.assert_allclose(first.x_minus, x0, rtol=0, atol=0)


def free_monodromy(omega: float) -> np.ndarray:
    """The free mode's monodromy over the forcing period, expm(A T)."""
    from scipy.linalg import expm

    return expm(np.array([[0.0, 1.0], [-K / M, -C / M]]) * 2 * np.pi / omega)


def free_amplitude_slope(omega: float) -> float:
    """|dA/dw| of the free orbit's amplitude ``A = F0 / sqrt((K - M w^2)^2 + (C w)^2)``."""
    q = (K - M * omega**2) ** 2 + (C * omega) ** 2
    dq = -4 * M * omega * (K - M * omega**2) + 2 * C**2 * omega
    return abs(-0.5 * F0 * q**-1.5 * dq)


@pytest.mark.parametrize("exact, rtol", [(True, 1e-10), (False, 1e-10), (False, 1e-8), (False, 1e-6)],
                         ids=["exact", "dop853-1e-10", "dop853-1e-8", "dop853-1e-6"])
@pytest.mark.parametrize("corner", ["A", "B"])
def test_the_symmetric_orbit_meets_both_corners_at_once_at_any_tolerance(exact, rtol, corner):
    """At w_A and w_B (closed form) the symmetric free orbit reaches both supports' corners at once: one
    non-smooth point, where the sequence passes from no contact to both contacts.  DOP853's error breaks the
    symmetry by some 1e-10 in w, so that one contact comes a hair before the other (a sequence with one
    contact, in a window narrower than the integration's resolution): that is still the one point, of the
    kind the exact flow finds, not a corner with no crossing and the second change missed.

    Located within its bracket plus the integration's error estimate over ``|dA/dw|`` (the free orbit's
    amplitude against w); its free side's multipliers are eig(expm(A T)) there, within the stated accuracy
    of the multipliers plus the integration's relative error times ``1 + |expm(A T)|``."""
    from saltation import Flow
    from saltation.branches.continuation import ContinuationSettings
    from saltation.models import trilinear
    from saltation.orbits.shooting import ShootingProblem
    from saltation.special_points.continuation import continue_branch

    w_star, start, bounds, direction, kind = {
        "A": (W_A, 0.85, (0.85, 1.0), 1, "nonsmooth_no_crossing"),
        "B": (W_B, 1.2, (1.0, 1.2), -1, "discontinuous_fold"),
    }[corner]
    flow = Flow(trilinear(), Tolerances(rtol=rtol, atol=1e-2 * rtol, exact_affine=exact))
    params = dict(TRI) | {"omega": start}
    problem = ShootingProblem(flow, {"omega": start}, continuation_parameter="omega")
    branch = continue_branch(problem, linear_response_state(params), start, directions=(direction,),
                             settings=ContinuationSettings(ds=0.015, ds_max=0.015, bounds=bounds))
    points = [sp for sp in branch.special_points if sp.kind.value not in ("fold", "endpoint")]
    assert [sp.kind.value for sp in points] == [kind], points
    sp = points[0]
    assert sorted([len(sp.event_labels_minus), len(sp.event_labels_plus)]) == [0, 4], sp
    # Flow.integration_error on DOP853: rtol (1 + |x|) (1 + events), |x| at most the larger of A = x_c and w A
    relative = 0.0 if exact else rtol * (1 + 4)
    resolution = relative * (1 + max(1.0, w_star) * XC)
    assert abs(sp.parameter - w_star) <= sp.accuracy + 1e-13 + resolution / free_amplitude_slope(w_star)
    mu_free = sp.multipliers_minus if not sp.event_labels_minus else sp.multipliers_plus
    monodromy = free_monodromy(w_star)
    expected = np.sort_complex(np.linalg.eigvals(monodromy))
    scale = 1.0 + np.linalg.norm(monodromy, 2)
    assert np.abs(np.sort_complex(mu_free) - expected).max() <= sp.multipliers_accuracy + (1e-12 + relative) * scale


def asymmetric_supports(lower_gap: float):
    """The trilinear system with the lower support at ``-lower_gap`` instead of ``-x_c`` (a user's model)."""
    from saltation.model import Crossing, Mode, PiecewiseSystem, Transition

    rising, falling = Crossing.RISING, Crossing.FALLING
    forcing = "f0*sin(omega*t)"
    return PiecewiseSystem(
        name="trilinear_asymmetric",
        states=["x", "v"],
        parameters=dict(TRI) | {"x_d": lower_gap},
        modes=[
            Mode("contact_1", ["v", f"(-c*v - k*x - c_f*v - k_f*(x - x_c) + {forcing})/m"],
                 domain=["x - x_c > 0", "k_f*(x - x_c) + c_f*v >= 0"]),
            Mode("contact_2", ["v", f"(-c*v - k*x - c_f*v - k_f*(x + x_d) + {forcing})/m"],
                 domain=["x + x_d < 0", "k_f*(x + x_d) + c_f*v <= 0"]),
            Mode("free", ["v", f"(-c*v - k*x + {forcing})/m"]),
        ],
        surfaces={"h1a": "x - x_c", "h1b": "k_f*(x - x_c) + c_f*v", "h2a": "x + x_d", "h2b": "k_f*(x + x_d) + c_f*v"},
        transitions=[
            Transition("free", "h1a", rising, "contact_1", guard=["k_f*(x - x_c) + c_f*v >= 0"]),
            Transition("free", "h1b", rising, "contact_1", guard=["x - x_c > 0"]),
            Transition("contact_1", "h1b", falling, "free"),
            Transition("contact_1", "h1a", falling, "free"),
            Transition("free", "h2a", falling, "contact_2", guard=["k_f*(x + x_d) + c_f*v <= 0"]),
            Transition("free", "h2b", falling, "contact_2", guard=["x + x_d < 0"]),
            Transition("contact_2", "h2b", rising, "free"),
            Transition("contact_2", "h2a", rising, "free"),
        ],
        period="2*pi/omega",
    )


@pytest.mark.parametrize("exact", [True, False], ids=["exact", "dop853"])
def test_two_separate_corners_in_one_continuation_step(monkeypatch, exact):
    """With the lower support 1e-3 farther than the upper one, the free orbit reaches the upper corner at
    w_A (closed form) and the one-contact orbit the lower corner some 2e-4 later: both changes fall in one
    continuation step (no branch point has one contact), farther apart than the integration's
    resolution, so they are two points, each located once.

    References: the first point is at w_A with the free side's multipliers eig(expm(A T)), as in the test
    above.  The second has no closed form: fixed-parameter shooting 1e-7 beyond its bracket on either side
    gives one contact and two; its one-contact side's multipliers are the limit of that orbit's, extrapolated
    linearly from w* - e and w* - 2e (error about the second difference d2, taken twice), within the stated
    accuracy of the multipliers plus their slope times the point's accuracy."""
    from saltation import Flow
    from saltation.branches.continuation import ContinuationSettings
    from saltation.orbits.shooting import ShootingProblem, find_periodic_orbit
    from saltation.special_points import detection
    from saltation.special_points.continuation import continue_branch

    located = []
    bisect = detection.SpecialPointDetector._bisect_event_change

    def counting_bisect(self, a, b):
        located.append((a, b))
        return bisect(self, a, b)

    monkeypatch.setattr(detection.SpecialPointDetector, "_bisect_event_change", counting_bisect)
    rtol = 1e-10
    flow = Flow(asymmetric_supports(XC + 1e-3), Tolerances(rtol=rtol, atol=1e-2 * rtol, exact_affine=exact))
    start = 0.85
    problem = ShootingProblem(flow, {"omega": start}, continuation_parameter="omega")
    branch = continue_branch(problem, linear_response_state(dict(TRI) | {"omega": start}), start, directions=(1,),
                             settings=ContinuationSettings(ds=0.015, ds_max=0.015, bounds=(start, 0.95)))
    contacts = [len(p.event_labels) for p in branch.points]
    assert 2 not in contacts and (0, 4) in set(itertools.pairwise(contacts)), contacts
    points = [sp for sp in branch.special_points if sp.kind.value != "endpoint"]
    assert [sp.kind.value for sp in points] == ["nonsmooth_no_crossing"] * 2, points
    first, second = points
    assert [len(first.event_labels_minus), len(first.event_labels_plus)] == [0, 2]
    assert [len(second.event_labels_minus), len(second.event_labels_plus)] == [2, 4]
    assert len(located) == 2  # one bisection each: the second change's bracket is not located again

    relative = 0.0 if exact else rtol * (1 + 4)
    resolution = relative * (1 + XC)
    assert abs(first.parameter - W_A) <= first.accuracy + 1e-13 + resolution / free_amplitude_slope(W_A)
    monodromy = free_monodromy(W_A)
    scale = 1.0 + np.linalg.norm(monodromy, 2)
    error = np.abs(np.sort_complex(first.multipliers_minus) - np.sort_complex(np.linalg.eigvals(monodromy))).max()
    assert error <= first.multipliers_accuracy + (1e-12 + relative) * scale

    w2 = second.parameter
    margin = 1e-7
    for w, n_events in ((min(second.bracket) - margin, 2), (max(second.bracket) + margin, 4)):
        orbit = find_periodic_orbit(flow, second.state, parameters={"omega": w})
        assert len(orbit.trajectory.events) == n_events, (w, orbit.trajectory.events)
    e = 1e-7
    mus = []
    for j in (1, 2, 3):
        orbit = find_periodic_orbit(flow, second.state, parameters={"omega": w2 - j * e})
        assert len(orbit.trajectory.events) == 2
        mus.append(np.sort_complex(orbit.multipliers))
    limit = 2 * mus[0] - mus[1]
    d2 = np.abs(mus[0] - 2 * mus[1] + mus[2]).max()
    slope = np.abs(mus[0] - mus[1]).max() / e
    error = np.abs(np.sort_complex(second.multipliers_minus) - limit).max()
    assert error <= second.multipliers_accuracy + 2 * d2 + slope * second.accuracy + (1e-12 + relative) * scale
    # the reference tells the sides apart: the two-contact side's multipliers are elsewhere
    assert np.abs(np.sort_complex(second.multipliers_plus) - limit).max() > 1e3 * error
