"""Symmetric orbits: the declared symmetry, the half-period map and symmetry breaking.

References: the free oscillator's half-period map ``-expm(A T/2)`` (closed form), central differences
of the half-period map ``G(x) = S phi(T/2; 0, x)``, the whole period's monodromy (``M = DG^2``), and the
period map itself for the mirror images of asymmetric orbits.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

from conftest import TIGHT, central_difference_jacobian
from saltation import Flow, Mode, PiecewiseSystem, Symmetry, find_periodic_orbit
from saltation.branches.branch import SpecialPointKind
from saltation.errors import InconsistentResultError, ModelError
from saltation.models import trilinear
from saltation.models.trilinear import DEFAULTS as TRI
from saltation.orbits.symmetry import SYMMETRIC_TOL, symmetric_multipliers, symmetry_breaking_test


# -- the declaration ------------------------------------------------------------------------------
def test_the_trilinear_system_maps_its_supports_onto_each_other():
    system = trilinear()
    assert system.symmetry == Symmetry.of_signs([-1, -1])
    names = system.mode_names
    image = {names[i]: names[k] for i, k in enumerate(system.symmetry_map.modes)}
    assert image == {"contact_1": "contact_2", "contact_2": "contact_1", "free": "free"}
    surfaces = system.surface_names
    assert {surfaces[j]: surfaces[k] for j, k in enumerate(system.symmetry_map.surfaces)} == {
        "h1a": "h2a", "h1b": "h2b", "h2a": "h1a", "h2b": "h1b"}
    assert set(system.symmetry_map.surface_signs) == {-1}  # h1a(-x) = -(x + x_c) = -h2a(x)


def _oscillator(field_v: str, symmetry: Symmetry, **kw) -> PiecewiseSystem:
    return PiecewiseSystem("sym_check", ["x", "v"], {"w": 1.3}, [Mode("m", ["v", field_v])], {}, [],
                           period="2*pi/w", symmetry=symmetry, **kw)


@pytest.mark.parametrize(("field_v", "matrix", "message"), [
    ("-x - 0.1*v + cos(w*t) + 0.2", [[-1, 0], [0, -1]], "mirror image of mode 'm'"),  # a constant force
    ("-x - 0.1*v + cos(w*t) + 0.3*x**2", [[-1, 0], [0, -1]], "mirror image of mode 'm'"),  # an even term
    ("-x - 0.1*v + cos(w*t)", [[1, 0], [0, -1]], "mirror image of mode 'm'"),  # not the right matrix
    ("-x - 0.1*v + cos(w*t)", [[-1, 0], [0, -1], [0, 0]], "square"),
    ("-x - 0.1*v + cos(w*t)", [[2, 0], [0, 0.5]], "involution"),
    ("-x - 0.1*v + cos(w*t)", [[-1, 0, 0], [0, -1, 0], [0, 0, 1]], "3 x 3"),
])
def test_a_symmetry_the_equations_do_not_have_is_refused(field_v, matrix, message):
    with pytest.raises(ModelError, match=message):
        _oscillator(field_v, Symmetry(matrix))


def test_only_half_period_shifts_are_accepted():
    with pytest.raises(ModelError, match="0.5"):
        Symmetry([[-1, 0], [0, -1]], shift=0.25)
    with pytest.raises(ModelError, match="Symmetry"):
        _oscillator("-x + cos(w*t)", "x -> -x")


def test_a_transition_without_a_mirror_image_is_named():
    """An impact on one stop only: the modes and the surface's image exist, the transition's does not."""
    with pytest.raises(ModelError, match=r"transition 0 .*has no mirror image"):
        PiecewiseSystem(
            "one_stop", ["x", "v"], {"w": 1.3, "d": 1.0},
            [Mode("free", ["v", "-x - 0.1*v + cos(w*t)"])],
            {"right": "x - d", "left": "x + d"},
            [__import__("saltation").Transition("free", "right", 1, "free", reset=["x", "-0.8*v"])],
            period="2*pi/w", symmetry=Symmetry.of_signs([-1, -1]),
        )


# -- the half-period map --------------------------------------------------------------------------
@pytest.fixture(scope="module")
def tri_flow():
    return Flow(trilinear())


def _a_free(p: dict) -> np.ndarray:
    return np.array([[0.0, 1.0], [-p["k"] / p["m"], -p["c"] / p["m"]]])


@settings(max_examples=15, deadline=None)
@given(omega=st.floats(0.3, 3.0), c=st.floats(0.0, 0.5))
def test_the_free_orbit_half_map_is_minus_the_exponential_of_half_a_period(tri_flow, omega, c):
    """Without contact (small forcing) the half-period map's Jacobian is -expm(A T/2) exactly, the
    multipliers are the squares of its eigenvalues, and the orbit is symmetric."""
    p = dict(TRI) | {"omega": omega, "c": c, "f0": 1e-3}
    det = (p["k"] - omega**2) ** 2 + (c * omega) ** 2
    a, b = p["f0"] * (p["k"] - omega**2) / det, -p["f0"] * c * omega / det  # x = a sin(wt) + b cos(wt)
    x0 = np.array([b, a * omega])
    T = 2 * np.pi / omega
    half = symmetric_multipliers(tri_flow, x0, parameters=p, monodromy=expm(_a_free(p) * T))
    np.testing.assert_allclose(half.half_map, -expm(_a_free(p) * T / 2), rtol=0, atol=1e-10)
    assert half.symmetric and half.symmetry_error < 1e-10
    gamma = np.linalg.eigvals(-expm(_a_free(p) * T / 2))
    np.testing.assert_allclose(np.sort_complex(half.gamma), np.sort_complex(gamma), atol=1e-10)
    np.testing.assert_allclose(np.sort_complex(half.multipliers), np.sort_complex(np.linalg.eigvals(expm(_a_free(p) * T))),
                               atol=1e-10)


@pytest.mark.parametrize("omega", [0.95, 1.0])
def test_the_half_map_of_a_contact_orbit_is_the_derivative_of_the_half_period_map(tri_flow, omega):
    """Reference: central differences of G(x) = -phi(T/2; 0, x) (no saltation matrices), and the whole
    period's monodromy, which must be DG^2."""
    p = tri_flow.parameters({"omega": omega})
    orbit = find_periodic_orbit(tri_flow, [1.5, 0.0], parameters={"omega": omega})
    assert len(orbit.event_labels) == 4  # both supports touched: the saltation matrices are in the map
    T = 2 * np.pi / omega
    half = symmetric_multipliers(tri_flow, orbit.state0, parameters=p, monodromy=orbit.monodromy, tolerances=TIGHT)
    assert half.symmetric
    fd = central_difference_jacobian(lambda x: -tri_flow.run(x, 0.0, T / 2, p, tolerances=TIGHT).x1, orbit.state0, 1e-6)
    np.testing.assert_allclose(half.half_map, fd, rtol=0, atol=1e-6)
    np.testing.assert_allclose(half.half_map @ half.half_map, orbit.monodromy, rtol=0, atol=1e-8)
    np.testing.assert_allclose(np.sort_complex(half.multipliers), np.sort_complex(orbit.multipliers), atol=1e-8)


def test_a_monodromy_that_is_not_the_square_of_the_half_map_is_an_error(tri_flow):
    orbit = find_periodic_orbit(tri_flow, [1.5, 0.0], parameters={"omega": 1.0})
    with pytest.raises(InconsistentResultError, match="declared symmetry"):
        symmetric_multipliers(tri_flow, orbit.state0, parameters={"omega": 1.0}, monodromy=orbit.monodromy + 0.01)


def test_an_autonomous_orbit_needs_its_period():
    relay = PiecewiseSystem("sym_relay", ["x", "v"], {"a": 0.1},
                            [Mode("m", ["v", "-x - a*v"])], {}, [], symmetry=Symmetry.of_signs([-1, -1]))
    with pytest.raises(ModelError, match="period"):
        symmetric_multipliers(Flow(relay), [1.0, 0.0])


def test_the_symmetry_breaking_test_changes_sign_where_a_real_gamma_passes_minus_one():
    assert symmetry_breaking_test(np.array([-0.9, 0.3])) > 0
    assert symmetry_breaking_test(np.array([-1.1, 0.3])) < 0
    assert symmetry_breaking_test(np.array([-0.5 + 0.9j, -0.5 - 0.9j])) > 0  # a complex pair never


# -- symmetry breaking where the orbit touches both supports at once ---------------------------------
#: stiff, lightly damped supports and strong forcing (as in tests/branches/test_continuation.py): the no-contact
#: symmetric orbit touches both supports at once, and the branch goes on with asymmetric orbits that
#: touch one support
IMPACTING = {"k_f": 25.0, "c": 0.01, "f0": 0.6, "c_f": 0.5}


@pytest.fixture(scope="module")
def one_sided_branch(tri_flow):
    from saltation.apps.paper import linear_response_state
    from saltation.orbits.shooting import ShootingProblem
    from saltation.special_points.continuation import ContinuationSettings, continue_branch

    problem = ShootingProblem(tri_flow, IMPACTING | {"omega": 0.5}, continuation_parameter="omega")
    x0 = linear_response_state(dict(TRI) | IMPACTING | {"omega": 0.5})
    settings_ = ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(0.5, 0.7), max_points=60)
    return continue_branch(problem, x0, 0.5, settings=settings_, directions=(1,))


def test_the_branch_leaves_the_symmetric_orbits_at_a_discontinuous_symmetry_breaking(tri_flow, one_sided_branch):
    """Where the no-contact orbit reaches x = +-x_c (the closed form of the linear response), the branch
    passes onto orbits that touch one support: the point is a discontinuous symmetry breaking, the
    orbits before it are symmetric, those after it are not, and the mirror image S x(t + T/2) of each
    asymmetric orbit is another periodic orbit (checked with the period map)."""
    first = one_sided_branch.special_points[0]
    assert first.kind is SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING
    assert "from symmetric to asymmetric" in first.note
    # the no-contact orbit's amplitude f0 / sqrt((k - m w^2)^2 + (c w)^2) reaches x_c there
    k, m, c, f0 = TRI["k"], TRI["m"], IMPACTING["c"], IMPACTING["f0"]
    amplitude = lambda w: f0 / np.sqrt((k - m * w**2) ** 2 + (c * w) ** 2)  # noqa: E731
    assert first.bracket[0] - 1e-9 <= first.parameter <= first.bracket[1] + 1e-9
    assert amplitude(first.bracket[0]) <= TRI["x_c"] + 1e-9 and amplitude(first.bracket[1]) >= TRI["x_c"] - 1e-9
    S = np.diag([-1.0, -1.0])
    before = one_sided_branch.points[: first.index + 1]
    after = one_sided_branch.points[first.index + 1: first.index + 6]
    for pt in before[-3:]:
        p = tri_flow.parameters(IMPACTING | {"omega": pt.parameter})
        assert symmetric_multipliers(tri_flow, pt.state, parameters=p).symmetric
    for pt in after:
        p = tri_flow.parameters(IMPACTING | {"omega": pt.parameter})
        T = 2 * np.pi / pt.parameter
        half = symmetric_multipliers(tri_flow, pt.state, parameters=p)
        assert not half.symmetric and half.symmetry_error > 100 * SYMMETRIC_TOL
        mirror = S @ tri_flow.run(pt.state, 0.0, T / 2, p, tolerances=TIGHT).x1  # S x(T/2): the mirror at t = 0
        again = tri_flow.run(mirror, 0.0, T, p, tolerances=TIGHT).x1
        assert np.linalg.norm(again - mirror) < 1e-8 * (1 + np.linalg.norm(mirror))
        assert np.linalg.norm(mirror - pt.state) > 1e-4  # another orbit, not the same one


# -- smooth symmetry breaking against an independent reference (tests/symmetry_reference.py) ------------
import symmetry_reference as reference  # noqa: E402  (numpy and scipy only: a closed-form flow)

from saltation.orbits.shooting import ShootingProblem  # noqa: E402
from saltation.special_points.branch_switching import follow_asymmetric_branch  # noqa: E402
from saltation.special_points.continuation import ContinuationSettings, continue_branch  # noqa: E402

#: the reference locates the parameter to 1e-11 (its closed-form and variational Jacobians agree to 3e-13,
#: its module docstring says); the library's brentq on the half-period map to 1e-13
REFERENCE_ACCURACY = 1e-11
STRONG = {"f0": 2.0}


@pytest.fixture(scope="module")
def strong_branch(tri_flow):
    problem = ShootingProblem(tri_flow, STRONG | {"omega": 0.84}, continuation_parameter="omega")
    orbit = problem.solve(np.array([-0.27, 0.84]), 0.84)
    settings_ = ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(0.7, 0.84))
    return problem, continue_branch(problem, orbit.state0, 0.84, settings=settings_, directions=(-1,))


@pytest.fixture(scope="module")
def strong_references():
    p = dict(TRI) | STRONG
    first = reference.trilinear_symmetry_breaking(p, 0.83, 0.836, np.array([-0.2738, 0.8268]))
    second = reference.trilinear_symmetry_breaking(p, 0.73, 0.74, np.array([-0.2797, 0.5836]))
    return first, second


def test_symmetry_breaking_of_the_trilinear_system_against_a_closed_form_flow(tri_flow, strong_branch,
                                                                            strong_references):
    """With strong forcing the symmetric orbit's antisymmetric multiplier passes +1 twice (its half-period
    multiplier -1): two symmetry breakings, no fold, the branch unstable between them."""
    _, branch = strong_branch
    points = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.SYMMETRY_BREAKING]
    assert len(points) == 2 and len(branch.special_points) == 2  # not folds
    for sp, (omega, state, gamma) in zip(points, strong_references):
        assert sp.status == "located"
        assert sp.parameter == pytest.approx(omega, abs=REFERENCE_ACCURACY + sp.accuracy)
        np.testing.assert_allclose(sp.state, state, atol=1e-9)
        assert _nearest_to(sp.multipliers, 1.0) == pytest.approx(1.0, abs=1e-9)
        # both half-period multipliers (the reference's are -1 and the other one), and the full ones their squares
        half = symmetric_multipliers(tri_flow, sp.state, parameters=STRONG | {"omega": sp.parameter}, tolerances=TIGHT)
        np.testing.assert_allclose(np.sort(half.gamma.real), np.sort(gamma), atol=1e-9)
        np.testing.assert_allclose(np.sort(sp.multipliers.real), np.sort(gamma**2), atol=1e-9)
    between = [pt for pt in branch.points if points[1].parameter < pt.parameter < points[0].parameter]
    assert between and not any(pt.stable for pt in between)
    outside = [pt for pt in branch.points if not points[1].parameter <= pt.parameter <= points[0].parameter]
    assert outside and all(pt.stable for pt in outside)


def _nearest_to(mu, target):
    mu = np.asarray(mu)
    return mu[np.argmin(np.abs(mu - target))]


def test_the_asymmetric_branch_joins_the_two_symmetry_breakings(tri_flow, strong_branch, strong_references):
    """The branch born at the first point: its orbits are not symmetric, the mirror image of each is an orbit
    too, and it meets the symmetric orbits again at the second point (a supercritical pitchfork: stable)."""
    problem, branch = strong_branch
    first = branch.special_points[0]
    settings_ = ContinuationSettings(ds=0.005, ds_max=0.02, bounds=(0.7, 0.84), max_points=400)
    side = follow_asymmetric_branch(problem, first, settings=settings_)
    met = [sp for sp in side.special_points if sp.kind is SpecialPointKind.SYMMETRY_BREAKING]
    assert met, side.special_points
    for sp in met:
        ref = min(strong_references, key=lambda r: abs(r[0] - sp.parameter))
        assert sp.parameter == pytest.approx(ref[0], abs=REFERENCE_ACCURACY + sp.accuracy)
    S = np.diag([-1.0, -1.0])
    for pt in side.points[1::10]:
        p = tri_flow.parameters(STRONG | {"omega": pt.parameter})
        T = 2 * np.pi / pt.parameter
        assert not symmetric_multipliers(tri_flow, pt.state, parameters=p).symmetric
        mirror = S @ tri_flow.run(pt.state, 0.0, T / 2, p, tolerances=TIGHT).x1
        np.testing.assert_allclose(tri_flow.run(mirror, 0.0, T, p, tolerances=TIGHT).x1, mirror, atol=1e-8)
        assert pt.stable  # born stable from a supercritical pitchfork


def test_the_paper_folds_stay_folds(tri_flow):
    """On the paper's branch (Appendix A) the smooth fold has its symmetric half-period multiplier at +1,
    and no point is a symmetry breaking."""
    problem = ShootingProblem(tri_flow, {"omega": 0.6}, continuation_parameter="omega")
    orbit = problem.solve(np.zeros(2), 0.6)
    branch = continue_branch(problem, orbit.state0, 0.6, settings=ContinuationSettings(bounds=(0.6, 1.6)),
                             directions=(1,))
    kinds = [sp.kind for sp in branch.special_points]
    assert kinds == [SpecialPointKind.NONSMOOTH_NO_CROSSING, SpecialPointKind.FOLD, SpecialPointKind.DISCONTINUOUS_FOLD]
    fold = branch.special_points[1]
    half = symmetric_multipliers(tri_flow, fold.state, parameters={"omega": fold.parameter})
    assert half.symmetric
    assert _nearest_to(half.gamma, 1.0) == pytest.approx(1.0, abs=1e-6)
    assert _nearest_to(half.gamma, -1.0).real > -0.9


def test_symmetry_breaking_of_an_impact_oscillator_between_two_stops():
    """Subcritical: the asymmetric orbits are born unstable on the side where the symmetric one is stable."""
    from saltation.models import symmetric_impact_oscillator
    from saltation.models.symmetric_impact_oscillator import DEFAULTS

    flow = Flow(symmetric_impact_oscillator())
    problem = ShootingProblem(flow, {"omega": 0.95}, continuation_parameter="omega")
    orbit = problem.solve(np.array([0.92, 0.49]), 0.95)
    branch = continue_branch(problem, orbit.state0, 0.95, settings=ContinuationSettings(bounds=(0.9, 1.05)),
                             directions=(1,))
    (sp,) = branch.special_points
    assert sp.kind is SpecialPointKind.SYMMETRY_BREAKING
    omega, state, _ = reference.impact_symmetry_breaking(dict(DEFAULTS), 0.97, 0.99, np.array([0.922, 0.4935]))
    assert sp.parameter == pytest.approx(omega, abs=REFERENCE_ACCURACY + sp.accuracy)
    np.testing.assert_allclose(sp.state, state, atol=1e-9)
    side = follow_asymmetric_branch(problem, sp, settings=ContinuationSettings(ds=0.002, bounds=(0.9, 0.99),
                                                                               max_points=6))
    assert all(pt.parameter >= sp.parameter - 1e-9 for pt in side.points)
    assert not any(pt.stable for pt in side.points[1:])


def test_an_autonomous_symmetric_orbit_of_the_relay_feedback_system():
    """The relay oscillation is symmetric (x -> -x after half its period): its half-period map has the trivial
    eigenvalue +1 (the flow direction), the squares of its eigenvalues are the Floquet multipliers of the
    whole period, and Newton on the half-period map (with the half period an unknown) finds the same
    period and multipliers from a perturbed guess."""
    from saltation.models import relay_feedback
    from saltation.orbits.symmetry import solve_symmetric_orbit

    flow = Flow(relay_feedback())
    orbit = find_periodic_orbit(flow, [0.1, 0.0, 0.0])
    half = symmetric_multipliers(flow, orbit.state0, period=orbit.period, monodromy=orbit.monodromy,
                                 tolerances=TIGHT)
    assert half.symmetric
    assert _nearest_to(half.gamma, 1.0) == pytest.approx(1.0, abs=1e-8)
    np.testing.assert_allclose(np.sort_complex(half.multipliers), np.sort_complex(orbit.multipliers), atol=1e-8)
    x, T, again = solve_symmetric_orbit(flow, orbit.state0 + 1e-3, flow.parameters(), period=1.001 * orbit.period)
    assert T == pytest.approx(orbit.period, abs=1e-9)
    np.testing.assert_allclose(np.sort_complex(again.gamma), np.sort_complex(half.gamma), atol=1e-8)


def test_the_command_follows_the_asymmetric_branch(tmp_path, capsys, strong_references):
    """``saltation continue`` writes the symmetric branch and the asymmetric one born at its first symmetry
    breaking (which meets the second: it is not started again from there)."""
    import json

    from saltation.apps import cli

    status = cli.main(["continue", "trilinear", "--set", "f0=2.0", "--param", "omega", "--from", "0.84", "--to", "0.7",
                       "--x0", "-0.27,0.84", "--out", str(tmp_path), "--no-progress"])
    assert status == 0
    out = capsys.readouterr().out
    assert "on 2 branches" in out
    records = json.loads((tmp_path / "trilinear_omega_special_points.json").read_text())
    breaks = sorted(r["value"] for r in records if r["kind"] == "symmetry_breaking")
    assert len(breaks) == 4  # two on the symmetric branch, the same two where the asymmetric one meets it
    for value in breaks:
        ref = min((r[0] for r in strong_references), key=lambda w: abs(w - value))
        assert value == pytest.approx(ref, abs=REFERENCE_ACCURACY + 1e-13)
    assert (tmp_path / "trilinear_omega_branch_1.json").exists()


def test_a_symmetry_that_holds_at_some_parameter_values_only():
    """A bias b breaks x -> -x: the declaration is checked at the defaults (b = 0), and again at a branch's
    parameters, where the half-period analysis is left out if the symmetry does not hold."""
    from saltation.model.symmetry import check_symmetry
    from saltation.special_points.detection import SpecialPointDetector
    from saltation.branches.branch import Branch, BranchKind
    from saltation.branches.corrector import Corrector

    system = PiecewiseSystem("biased_backlash", ["x", "v"], {"w": 1.3, "b": 0.0},
                             [Mode("m", ["v", "-x - 0.1*v + cos(w*t) + b"])], {}, [], period="2*pi/w",
                             symmetry=Symmetry.of_signs([-1, -1]))
    check_symmetry(system, system.symmetry, np.array([1.3, 0.0]))
    with pytest.raises(ModelError, match="mirror image of mode 'm'"):
        check_symmetry(system, system.symmetry, np.array([1.3, 0.3]))
    flow = Flow(system)
    for b, symmetric in ((0.0, True), (0.3, False)):
        problem = ShootingProblem(flow, {"b": b}, continuation_parameter="w")
        branch = Branch(model=system.name, parameter_name="w", kind=BranchKind.PERIODIC, points=[])
        detector = SpecialPointDetector(problem, Corrector(problem, ContinuationSettings()), branch)
        assert (detector.symmetry is not None) == symmetric


@pytest.mark.unchecked_branches  # the location is made to fail: the change it leaves uncovered is the point
def test_a_symmetry_breaking_that_cannot_be_located_is_reported_as_failed(tri_flow, monkeypatch):
    """Where the half-period multiplier changes sign of ``gamma + 1`` between two branch points but Newton on
    the half-period map fails, the point is kept, with status failed and the two points' bracket."""
    import saltation.special_points.symmetric as detection
    from saltation.errors import ConvergenceError

    def fails(*args, **kwargs):
        raise ConvergenceError("no symmetric orbit (test)", [1.0])

    monkeypatch.setattr(detection, "solve_symmetric_orbit", fails)
    problem = ShootingProblem(tri_flow, STRONG | {"omega": 0.84}, continuation_parameter="omega")
    orbit = problem.solve(np.array([-0.27, 0.84]), 0.84)
    branch = continue_branch(problem, orbit.state0, 0.84, settings=ContinuationSettings(ds=0.01, ds_max=0.02,
                                                                                       bounds=(0.8, 0.84)),
                             directions=(-1,))
    (sp,) = branch.special_points
    assert sp.kind is SpecialPointKind.SYMMETRY_BREAKING and sp.status == "failed"
    assert sp.bracket[0] < 0.8331698679 < sp.bracket[1]
    assert "no symmetric orbit (test)" in sp.note


def test_a_symmetry_whose_guards_differ_is_refused():
    """The impact oscillator between two stops, its right stop guarded by ``v > 10`` (it never acts at these
    speeds): the mirror image of an orbit that bounces off the left stop passes the right one, so the model is
    not symmetric, and declaring it so is refused, naming the transition (it used to be accepted, and its grazing
    labelled a discontinuous symmetry breaking)."""
    from saltation import Crossing, Transition
    from saltation.models.symmetric_impact_oscillator import DEFAULTS

    def model(guard):
        return PiecewiseSystem(
            name="guarded_stops", states=["x", "v"], parameters=dict(DEFAULTS),
            modes=[Mode("free", ["v", "-2*zeta*v - x + f0*cos(omega*t)"])],
            surfaces={"right": "x - d", "left": "x + d"},
            transitions=[Transition("free", "right", Crossing.RISING, "free", reset=["x", "-r*v"], guard=guard),
                         Transition("free", "left", Crossing.FALLING, "free", reset=["x", "-r*v"])],
            period="2*pi/omega", symmetry=Symmetry.of_signs([-1, -1]),
        )

    with pytest.raises(ModelError, match=r"transition 0 \(free -\[right\+\]-> free\) has no mirror image.*guard"):
        model(["v - 10 > 0"])
    assert model([]).symmetry is not None  # the same model without the guard is symmetric
