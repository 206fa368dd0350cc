"""Pseudo-equilibria of Filippov systems (saltation.orbits.pseudo_equilibria) against closed forms."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation import Crossing, Flow, Mode, PiecewiseSystem, Transition
from saltation import find_periodic_orbit as saltation_find_periodic_orbit
from saltation.errors import ModelError
from saltation.apps import cli
from saltation.orbits.pseudo_equilibria import find_pseudo_equilibrium
from saltation.orbits.shooting import EquilibriumProblem

A, B, C, D = 1.0, 2.0, 0.5, 0.3


def relay(sign: str = "-") -> PiecewiseSystem:
    """``x' = a`` (x < 0) or ``-b`` (x > 0): both push into x = 0, where the state slides with the weight
    ``a / (a + b)`` of the right field; ``y' = {sign}y + c`` or ``{sign}y - d``.  The pseudo-equilibrium is
    ``y = {-sign}(b c - a d) / (a + b)``, with the sliding eigenvalue ``{sign}1``."""
    return PiecewiseSystem(
        f"test_pseudo_relay_{'stable' if sign == '-' else 'unstable'}", states=["x", "y"],
        parameters={"a": A, "b": B, "c": C, "d": D},
        modes=[Mode("left", ["a", f"{sign}y + c"], domain=["x < 0"]), Mode("right", ["-b", f"{sign}y - d"], domain=["x >= 0"])],
        surfaces={"s": "x"},
        transitions=[Transition("left", "s", Crossing.RISING, "right"), Transition("right", "s", Crossing.FALLING, "left")],
    )


def test_a_stable_pseudo_equilibrium_against_its_closed_form():
    point = find_pseudo_equilibrium(relay("-"), "s", [0.1, 1.0])
    weight = A / (A + B)
    np.testing.assert_allclose(point.state, [0.0, (B * C - A * D) / (A + B)], rtol=0, atol=1e-12)
    assert point.weights == pytest.approx((1 - weight, weight), abs=1e-12)
    assert point.modes == ("left", "right") and point.admissible and point.stable
    # central differences of the sliding field (steps 1e-6) on an affine field: exact to rounding, 1e-9
    np.testing.assert_allclose(point.eigenvalues, [-1.0], atol=1e-8)


def test_an_unstable_pseudo_equilibrium_is_found_and_said_unstable():
    point = find_pseudo_equilibrium(Flow(relay("+")), "s", [0.0, 0.0])
    np.testing.assert_allclose(point.state, [0.0, -(B * C - A * D) / (A + B)], rtol=0, atol=1e-12)
    np.testing.assert_allclose(point.eigenvalues, [1.0], atol=1e-8)
    assert point.admissible and not point.stable
    assert "unstable" in repr(point)


def test_the_sliding_field_is_restricted_to_the_surface():
    """Three states: on x = 0 the sliding motion of (y, z) is y' = -y + z, z' = -z - y + const, eigenvalues
    -1 +- i; the pseudo-equilibrium is where both vanish."""
    system = PiecewiseSystem(
        "test_pseudo_three", states=["x", "y", "z"], parameters={"a": A, "b": B, "c": C, "d": D},
        modes=[Mode("left", ["a", "-y + z", "-z - y + c"], domain=["x < 0"]),
               Mode("right", ["-b", "-y + z", "-z - y - d"], domain=["x >= 0"])],
        surfaces={"s": "x"},
        transitions=[Transition("left", "s", Crossing.RISING, "right"), Transition("right", "s", Crossing.FALLING, "left")],
    )
    point = find_pseudo_equilibrium(system, "s", [0.2, 0.0, 0.0])
    forcing = (B * C - A * D) / (A + B)  # (1 - a) c - a d with a = A / (A + B)
    np.testing.assert_allclose(point.state, [0.0, forcing / 2, forcing / 2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(point.eigenvalues, [-1 - 1j, -1 + 1j], atol=1e-8)


def test_a_point_outside_the_sliding_region_is_virtual():
    """With both fields pointing right (b < 0), nothing slides: the rest point of the combination has a weight
    outside (0, 1) and is called virtual."""
    point = find_pseudo_equilibrium(relay("-"), "s", [0.0, 0.0], parameters={"b": -2.0})
    assert not point.admissible and not point.stable
    assert point.weights[1] == pytest.approx(A / (A - 2.0), abs=1e-12)


def test_bad_input_is_named(trilinear_flow):
    with pytest.raises(ModelError, match="forced"):
        find_pseudo_equilibrium(trilinear_flow, "h1a", [0.0, 0.0])
    with pytest.raises(ModelError, match="surface 'nope' does not exist"):
        find_pseudo_equilibrium(relay(), "nope", [0.0, 0.0])


def test_a_branch_of_pseudo_equilibria_against_its_closed_form():
    """Continued in c, the relay's pseudo-equilibrium is y = (b c - a d) / (a + b) at every point, stable, with the
    sliding eigenvalue -1."""
    from saltation import ContinuationSettings
    from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem
    from saltation.special_points.continuation import continue_branch

    flow = Flow(relay("-"))
    first = find_pseudo_equilibrium(flow, "s", [0.0, 0.0])
    problem = PseudoEquilibriumProblem(flow, "s", first.modes, {"c": C}, continuation_parameter="c")
    branch = continue_branch(problem, PseudoEquilibriumProblem.unknowns(first), C,
                             settings=ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(-1.0, 2.0)))
    c = branch.parameter
    assert c.min() == pytest.approx(-1.0) and c.max() == pytest.approx(2.0) and len(branch) > 20
    np.testing.assert_allclose(branch.states[:, 1], (B * c - A * D) / (A + B), rtol=0, atol=1e-12)
    np.testing.assert_allclose(branch.states[:, 0], 0.0, atol=1e-12)
    assert np.all(branch.stable)
    np.testing.assert_allclose(np.asarray(branch.multipliers)[:, 0], -1.0, atol=1e-8)


def test_the_command_continues_pseudo_equilibria(tmp_path, capsys):
    """``saltation continue FILE:relay --equilibrium sliding:s``: the branch's CSV holds the closed form."""
    import csv

    from saltation.apps import cli

    model = tmp_path / "relay_model.py"  # a user's model file, importing the model from this test module
    model.write_text(f"import sys\nsys.path.insert(0, {str(Path(__file__).parent)!r})\n"
                     "from test_pseudo_equilibria import relay\n")
    status = cli.main(["continue", f"{model}:relay", "--param", "c", "--from", "0.5", "--to", "1.5",
                       "--equilibrium", "sliding:s", "--out", str(tmp_path / "out"), "--no-progress"])
    assert status == 0
    (table,) = (tmp_path / "out").glob("*_branch.csv")
    rows = list(csv.DictReader(table.open(newline="")))
    assert len(rows) > 5 and "eigenvalue1_re" in rows[0]
    for row in rows:
        assert float(row["y"]) == pytest.approx((B * float(row["c"]) - A * D) / (A + B), abs=1e-12)
        assert float(row["eigenvalue1_re"]) == pytest.approx(-1.0, abs=1e-8)
    assert cli.main(["continue", f"{model}:relay", "--param", "c", "--from", "0.5", "--to", "1.5",
                     "--equilibrium", "sliding:nope", "--out", str(tmp_path / "out2"), "--no-progress"]) == 2
    assert "unknown surface 'nope'" in capsys.readouterr().err


def boundary_model(stable: bool) -> PiecewiseSystem:
    """x < 0: ``x' = (x + mu)`` or ``-(x + mu)`` (``stable``), ``y' = -y``; x >= 0: ``x' = -1``, ``y' = -y``.  The left
    mode's equilibrium (-mu, 0) is admissible for mu > 0.  On x = 0 the left field's normal component is mu (or
    -mu), the right one's -1: both push into the surface, and the pseudo-equilibrium (0, 0) is admissible, for
    mu > 0 (or mu < 0), its weight a = mu / (mu + 1) (or -mu / (1 - mu)).  At mu = 0 the equilibrium reaches the
    surface: with the unstable field both exist for mu > 0 (a non-smooth fold), with the stable one each on its
    own side (persistence)."""
    sign = "-" if stable else ""
    return PiecewiseSystem(
        f"test_boundary_equilibrium_{'persistence' if stable else 'fold'}", states=["x", "y"], parameters={"mu": 0.5},
        modes=[Mode("left", [f"{sign}(x + mu)", "-y"], domain=["x < 0"]), Mode("right", ["-1", "-y"], domain=["x >= 0"])],
        surfaces={"s": "x"},
        transitions=[Transition("left", "s", Crossing.RISING, "right"), Transition("right", "s", Crossing.FALLING, "left")],
    )


@pytest.mark.parametrize(("stable", "start", "classification"), [(False, 0.5, "nonsmooth_fold"),
                                                                 (True, -0.5, "persistence")])
def test_boundary_equilibria_are_located_and_classified_against_the_closed_form(stable, start, classification):
    from saltation import ContinuationSettings
    from saltation.branches.branch import SpecialPointKind
    from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem
    from saltation.special_points.boundary_equilibria import boundary_equilibria
    from saltation.special_points.continuation import continue_branch

    flow = Flow(boundary_model(stable))
    first = find_pseudo_equilibrium(flow, "s", [0.0, 0.3], parameters={"mu": start})
    assert first.admissible
    problem = PseudoEquilibriumProblem(flow, "s", first.modes, {"mu": start}, continuation_parameter="mu")
    branch = continue_branch(problem, PseudoEquilibriumProblem.unknowns(first), start,
                             settings=ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(-0.5, 0.5)))
    (point,) = boundary_equilibria(problem, branch)
    assert point.kind is SpecialPointKind.BOUNDARY_EQUILIBRIUM and point.classification == classification
    assert point.parameter == pytest.approx(0.0, abs=1e-12) and point.accuracy <= 1e-9
    np.testing.assert_allclose(point.state, [0.0, 0.0], atol=1e-12)
    assert point.touch_mode == "left"
    # the left mode's equilibrium's eigenvalues there: +-1 in x (unstable or stable field), -1 in y
    np.testing.assert_allclose(np.sort(point.multipliers.real), np.sort([-1.0 if stable else 1.0, -1.0]), atol=1e-12)


def test_the_command_records_the_boundary_equilibrium(tmp_path, capsys):
    """``continue ... --equilibrium sliding:s`` on the persistence example, from mu = -0.5 to 0.5: the special points
    file names the boundary equilibrium at mu = 0 with its classification."""
    from saltation.apps import cli
    from saltation.output.io import load_special_points_json

    model = tmp_path / "boundary_model.py"
    model.write_text(f"import sys\nsys.path.insert(0, {str(Path(__file__).parent)!r})\n"
                     "from test_pseudo_equilibria import boundary_model\nmodel = boundary_model(True)\n")
    status = cli.main(["continue", f"{model}:model", "--param", "mu", "--from", "-0.5", "--to", "0.5",
                       "--equilibrium", "sliding:s", "--x0", "0,0.3", "--out", str(tmp_path / "out"), "--no-progress"])
    assert status == 0
    (records,) = (tmp_path / "out").glob("*_special_points.json")
    (record,) = load_special_points_json(records)  # (its reader checks the classification's value too)
    assert record["kind"] == "boundary_equilibrium" and record["classification"] == "persistence"
    assert abs(record["value"]) < 1e-12
    assert "boundary_equilibrium" in capsys.readouterr().out
    # and the branch through it: the left mode's equilibria (-mu, 0), followed from the boundary equilibrium
    from saltation.output.io import load_branch_json

    others = sorted(p for p in (tmp_path / "out").glob("*_branch_*.json") if not p.name.endswith(".meta.json"))
    assert others
    through = [load_branch_json(path) for path in others]
    assert any(b.label == "equilibrium of left" for b in through)
    for b in through:
        np.testing.assert_allclose(b.states[:, 0], -b.parameter, atol=1e-12)


@pytest.mark.parametrize(("stable", "classification"), [(False, "nonsmooth_fold"), (True, "persistence")])
def test_a_modes_equilibrium_branch_finds_the_same_boundary_equilibrium(stable, classification):
    """The left mode's equilibrium (-mu, 0), continued in mu through 0, crosses the surface x = 0 there: the same
    point and the same classification as from the branch of pseudo-equilibria (its partner, the pseudo-equilibrium,
    admissible for mu > 0 with the unstable field, for mu < 0 with the stable one)."""
    from saltation import ContinuationSettings
    from saltation.orbits.shooting import EquilibriumProblem
    from saltation.special_points.boundary_equilibria import boundary_equilibria_of_mode
    from saltation.special_points.continuation import continue_branch

    flow = Flow(boundary_model(stable))
    problem = EquilibriumProblem(flow, "left", {"mu": 0.5}, continuation_parameter="mu")
    branch = continue_branch(problem, problem.solve([-0.5, 0.0], 0.5).state, 0.5,
                             settings=ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(-0.5, 0.5)))
    np.testing.assert_allclose(branch.states[:, 0], -branch.parameter, atol=1e-12)  # the closed form
    (point,) = boundary_equilibria_of_mode(problem, branch)
    assert point.classification == classification
    assert point.parameter == pytest.approx(0.0, abs=1e-12) and point.touch_surface == "s"
    np.testing.assert_allclose(point.state, [0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(("right_field", "classification"), [("-(x + mu)", "persistence"), ("x - mu", "nonsmooth_fold")])
def test_a_boundary_equilibrium_without_sliding_is_classified_by_the_other_modes_equilibrium(right_field, classification):
    """x < 0: x' = -(x + mu); x >= 0: x' = -(x + mu) (the same field: the equilibrium -mu passes the surface, persistence)
    or x' = x - mu (equilibrium +mu, admissible for mu > 0 like the left one -mu: they meet at 0, a non-smooth fold).
    At x = 0 both fields have the normal component -mu: the surface is crossed, never slid on."""
    from saltation import ContinuationSettings
    from saltation.orbits.shooting import EquilibriumProblem
    from saltation.special_points.boundary_equilibria import boundary_equilibria_of_mode
    from saltation.special_points.continuation import continue_branch

    system = PiecewiseSystem(
        f"test_boundary_crossing_{classification}", states=["x", "y"], parameters={"mu": 0.5},
        modes=[Mode("left", ["-(x + mu)", "-y"], domain=["x < 0"]), Mode("right", [right_field, "-y"], domain=["x >= 0"])],
        surfaces={"s": "x"},
        transitions=[Transition("left", "s", Crossing.RISING, "right"), Transition("right", "s", Crossing.FALLING, "left")],
    )
    flow = Flow(system)
    problem = EquilibriumProblem(flow, "left", {"mu": 0.5}, continuation_parameter="mu")
    branch = continue_branch(problem, problem.solve([-0.5, 0.0], 0.5).state, 0.5,
                             settings=ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(-0.5, 0.5)))
    (point,) = boundary_equilibria_of_mode(problem, branch)
    assert point.classification == classification
    assert point.parameter == pytest.approx(0.0, abs=1e-12)


# -- two-parameter curves of boundary equilibria ---------------------------------------------------------
def curve_model() -> PiecewiseSystem:
    """x + nu^2 < 0: ``x' = -(x + mu)``, ``y' = -(y - nu)``, equilibrium (-mu, nu); beyond it ``x' = -1``.  The
    equilibrium reaches the surface ``x + nu^2 = 0`` where ``mu = nu^2``: the closed form of the curve."""
    return PiecewiseSystem(
        "test_boundary_equilibrium_curve", ["x", "y"], {"mu": 0.5, "nu": 0.5},
        [Mode("left", ["-(x + mu)", "-(y - nu)"], domain=["x + nu**2 < 0"]), Mode("right", ["-1", "-y"])],
        {"s": "x + nu**2"},
        [Transition("left", "s", Crossing.RISING, "right"), Transition("right", "s", Crossing.FALLING, "left")],
    )


def test_a_boundary_equilibrium_curve_against_its_closed_form():
    from saltation.special_points.boundary_equilibria import boundary_equilibria_of_mode, follow_boundary_equilibrium_curve
    from saltation.special_points.continuation import ContinuationSettings, continue_branch

    flow = Flow(curve_model())
    problem = EquilibriumProblem(flow, "left", continuation_parameter="mu")
    x0 = problem.solve([-0.5, 0.5], 0.5).state
    branch = continue_branch(problem, x0, 0.5, settings=ContinuationSettings(bounds=(0.0, 1.0)), directions=(-1,))
    (point,) = boundary_equilibria_of_mode(problem, branch)
    assert point.parameter == pytest.approx(0.25, abs=1e-12)
    settings = ContinuationSettings(tol=1e-12)
    locus = follow_boundary_equilibrium_curve(flow, point, "mu", "nu", (-1.0, 1.0), settings=settings)
    mu, nu = locus.values.T
    assert nu.min() == pytest.approx(-1.0) and nu.max() == pytest.approx(1.0)  # both directions to the bounds
    assert "reached a parameter bound" in locus.stop_detail
    # on the curve: mu = nu^2, the equilibrium (-mu, nu) on the surface; the corrector's tolerance 1e-12
    np.testing.assert_allclose(mu, nu**2, rtol=0, atol=1e-11)
    np.testing.assert_allclose(locus.states[:, 0], -mu, atol=1e-11)
    np.testing.assert_allclose(locus.states[:, 1], nu, atol=1e-11)


def test_the_locus_command_continues_boundary_equilibria(tmp_path, capsys):
    path = tmp_path / "curve_model.py"
    path.write_text("import sys\nsys.path.insert(0, %r)\nfrom test_pseudo_equilibria import curve_model\n"
                    % str(Path(__file__).parent))
    status = cli.main(["locus", f"{path}:curve_model", "--kind", "boundary_equilibrium", "--equilibrium", "left",
                       "--param", "mu", "--range", "0.5,0", "--param2", "nu", "--range2", "0,0.8", "--x0", "-0.5,0.5",
                       "--json", "--no-progress"])
    assert status == 0
    record = json.loads(capsys.readouterr().out)
    assert record["kind"] == "boundary_equilibrium" and len(record["curves"]) == 1
    points = np.array(record["curves"][0]["points"])
    np.testing.assert_allclose(points[:, 0], points[:, 1] ** 2, atol=1e-9)  # the corrector's default tolerance
    assert cli.main(["locus", f"{path}:curve_model", "--kind", "boundary_equilibrium", "--param", "mu", "--range",
                     "0.5,0", "--param2", "nu", "--range2", "0,0.8", "--no-progress"]) == 2
    assert "--equilibrium" in capsys.readouterr().err


# -- the sticking set of a friction oscillator on a resting ground ------------------------------------------
def sticking_model() -> PiecewiseSystem:
    """``x'' + c x' + k x = -mu sgn(x')``: on ``x' = 0`` the sliding field vanishes wherever ``|k x| < mu``."""
    return PiecewiseSystem(
        "test_sticking_set", ["x", "v"], {"k": 2.0, "mu": 0.5, "c": 0.1},
        [Mode("forward", ["v", "-k*x - c*v - mu"], domain=["v > 0"]), Mode("backward", ["v", "-k*x - c*v + mu"])],
        {"s": "v"},
        [Transition("forward", "s", Crossing.FALLING, "backward"), Transition("backward", "s", Crossing.RISING, "forward")],
    )


@pytest.fixture(scope="module")
def sticking_flow():
    return Flow(sticking_model())


@settings(max_examples=25, deadline=None)
@given(x=st.floats(-0.5, 0.5))
def test_the_sticking_set_is_a_continuum_of_pseudo_equilibria(sticking_flow, x):
    """Closed form: every (x, 0) with |k x| < mu is a pseudo-equilibrium with the weight
    a = (mu - k x) / (2 mu) of the forward-slip field; it is not isolated (the sliding field's Jacobian on
    the surface is 0), so it is neither stable nor unstable; beyond |x| = mu / k it is virtual."""
    k, mu = 2.0, 0.5
    point = find_pseudo_equilibrium(sticking_flow, "s", [x, 0.0])
    np.testing.assert_allclose(point.state, [x, 0.0], atol=1e-12)
    assert point.modes == ("backward", "forward")
    assert point.weights[1] == pytest.approx((mu - k * x) / (2 * mu), abs=1e-12)
    assert point.admissible == (abs(k * x) < mu)
    assert not point.isolated and not point.stable
    if point.admissible:
        assert "continuum" in repr(point)


# -- a cycle born at a boundary focus -------------------------------------------------------------------------
SIGMA = 0.2


def focus_model() -> PiecewiseSystem:
    """x < 0: the unstable focus ``z' = A (z - (-mu, 0))``, ``A = [[s, -1], [1, s]]``; x > 0: ``x' = -1``, ``y' = -y``.
    For mu > 0 the focus is admissible and the orbits spiral out onto the surface, slide up to the visible
    tangency at (0, s mu) and leave it: an attracting sliding cycle, which shrinks onto the point as mu -> 0."""
    return PiecewiseSystem(
        "test_boundary_focus", ["x", "y"], {"mu": 0.1, "s": SIGMA},
        [Mode("left", ["s*(x + mu) - y", "(x + mu) + s*y"], domain=["x < 0"]), Mode("right", ["-1", "-y"])],
        {"h": "x"},
        [Transition("left", "h", Crossing.RISING, "right"), Transition("right", "h", Crossing.FALLING, "left")],
    )


def reference_sliding_cycle(mu: float, s: float = SIGMA) -> tuple[float, float]:
    """The sliding cycle's period and size in closed form: the focus's arc from the tangency point (0, s mu)
    back to x = 0 (matrix exponential, its return found by brentq), then the sliding motion on x = 0, where
    ``y' = (y^2 + s (1 - mu) y + mu) / (s mu - y + 1)`` (Filippov's combination), from the arc's end up to
    the tangency point (quadrature)."""
    from scipy.integrate import quad
    from scipy.linalg import expm
    from scipy.optimize import brentq

    A = np.array([[s, -1.0], [1.0, s]])
    z_eq, z0 = np.array([-mu, 0.0]), np.array([0.0, s * mu])
    arc = lambda t: z_eq + expm(A * t) @ (z0 - z_eq)  # noqa: E731
    ts = np.linspace(1e-6, 2 * np.pi, 20001)
    xs = np.array([arc(t)[0] for t in ts])
    k = int(np.argmax(xs[1:] >= 0.0))  # the first return to x = 0
    t_hit = brentq(lambda t: arc(t)[0], ts[k], ts[k + 1], xtol=1e-15)
    y_hit = arc(t_hit)[1]
    assert y_hit < s * mu  # it lands on the sliding segment, below the tangency
    t_slide = quad(lambda y: (s * mu - y + 1.0) / (y**2 + s * (1.0 - mu) * y + mu), y_hit, s * mu, epsabs=1e-14)[0]
    fine = np.array([arc(t) for t in np.linspace(0.0, t_hit, 200001)])
    size = max(np.ptp(fine[:, 0]), np.ptp(np.append(fine[:, 1], [y_hit, s * mu])))
    return t_hit + t_slide, size


def test_a_boundary_focus_creates_a_sliding_cycle_against_its_closed_form():
    from saltation.special_points.boundary_equilibria import boundary_equilibria_of_mode, cycle_at_boundary_equilibrium
    from saltation.special_points.continuation import ContinuationSettings, continue_branch

    flow = Flow(focus_model())
    problem = EquilibriumProblem(flow, "left", continuation_parameter="mu")
    branch = continue_branch(problem, [-0.1, 0.0], 0.1, settings=ContinuationSettings(bounds=(-0.1, 0.1)),
                             directions=(-1,))
    (point,) = boundary_equilibria_of_mode(problem, branch)
    assert point.parameter == pytest.approx(0.0, abs=1e-12)
    assert "attracting sliding cycle surrounds it for mu > 0" in point.note
    span = abs(branch.points[point.index + 1].parameter - branch.points[point.index].parameter)
    cycle = cycle_at_boundary_equilibrium(problem, point, span)
    assert cycle.kind == "sliding" and cycle.side == 1
    period, size = reference_sliding_cycle(cycle.parameter)
    # the shooting converges to 1e-10; the size is read from the dense output's extremes
    assert cycle.period == pytest.approx(period, rel=1e-8)
    assert cycle.size == pytest.approx(size, rel=1e-6)
    assert cycle.sizes[1] / cycle.sizes[0] == pytest.approx(0.5, abs=0.05)  # it shrinks linearly onto the point


def test_a_stable_boundary_focus_creates_no_cycle():
    from saltation.special_points.boundary_equilibria import boundary_equilibria_of_mode

    system = PiecewiseSystem(
        "test_stable_boundary_focus", ["x", "y"], {"mu": 0.1, "s": -SIGMA},
        [Mode("left", ["s*(x + mu) - y", "(x + mu) + s*y"], domain=["x < 0"]), Mode("right", ["-1", "-y"])],
        {"h": "x"},
        [Transition("left", "h", Crossing.RISING, "right"), Transition("right", "h", Crossing.FALLING, "left")],
    )
    from saltation.special_points.continuation import ContinuationSettings, continue_branch

    flow = Flow(system)
    problem = EquilibriumProblem(flow, "left", continuation_parameter="mu")
    branch = continue_branch(problem, [-0.1, 0.0], 0.1, settings=ContinuationSettings(bounds=(-0.1, 0.1)),
                             directions=(-1,))
    (point,) = boundary_equilibria_of_mode(problem, branch)
    assert point.classification == "persistence" and "cycle" not in point.note


def test_a_branch_point_exactly_on_the_edge_still_gives_its_boundary_equilibrium():
    """sliding_mode(k=-1, U=1): the branch of pseudo-equilibria (r, 0) has the weight (U - k r) / (2U), which is
    1 at r = 1; a branch point lands there to the last bit (r = 0.9999999999999999, weight exactly 1.0), and
    the boundary equilibrium is found once, from the step that ends on it."""
    from saltation.models import sliding_mode
    from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem
    from saltation.special_points.boundary_equilibria import boundary_equilibria, sliding_weight
    from saltation.special_points.continuation import ContinuationSettings, continue_branch

    flow = Flow(sliding_mode(k=-1.0, U=1.0))
    first = find_pseudo_equilibrium(flow, "s", [0.25, 0.0], parameters={"r": 0.25})
    problem = PseudoEquilibriumProblem(flow, "s", first.modes, {"r": 0.25}, continuation_parameter="r")
    branch = continue_branch(problem, PseudoEquilibriumProblem.unknowns(first), 0.25,
                             settings=ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(-1.5, 1.5)))
    weights = [sliding_weight(problem, pt.state, pt.parameter) for pt in branch.points]
    found = boundary_equilibria(problem, branch)
    assert sorted(round(sp.parameter, 12) for sp in found) == [-1.0, 1.0]
    assert 1.0 in weights  # the case this test is about: a branch point exactly on the edge


def test_a_periodic_orbit_search_takes_a_parameter_vector():
    flow = Flow(focus_model())
    p = flow.parameters({"mu": 0.01})
    orbit = saltation_find_periodic_orbit(flow, [-0.02, 0.0], parameters=p)
    assert orbit.period > 0
