"""The sliding-mode controlled plant (saltation.models.sliding_mode) against its closed forms.

x1' = x2, x2' = -k x1 - c x2 + u, u = -U sgn(s), s = x2 + lam (x1 - r); mode u_plus (u = +U) where s < 0,
u_minus (u = -U) where s > 0.  By hand (and sympy):

* along a mode's field s' = u - G, G = k x1 + (c - lam) x2: Filippov's weight of u_minus's field is
  a = (U - G) / (2 U), the sliding field (1 - a) f_plus + a f_minus = (x2, -lam x2);
* the pseudo-equilibrium is (r, 0), with a = (U - k r) / (2 U), admissible (0 < a < 1) for |k r| < U;
  the sliding field's Jacobian on the line (tangent (1, -lam)) is the number -lam;
* the regular equilibria are (U / k, 0) of u_plus, in s < 0 for r > U / k, and (-U / k, 0) of u_minus,
  in s > 0 for r < -U / k; both have the eigenvalues (-c +- sqrt(c^2 - 4 k)) / 2;
* each reaches the line, on the pseudo-equilibrium, at r = U / k (u_plus) and r = -U / k (u_minus): for
  k > 0 the equilibrium and the pseudo-equilibrium are admissible on opposite sides (persistence), for
  k < 0 on the same side (a saddle meets the pseudo-node: a non-smooth fold).
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from saltation import (
    ContinuationSettings,
    Flow,
    continue_branch,
    find_pseudo_equilibrium,
)
from saltation.branches.branch import SpecialPointKind
from saltation.models.sliding_mode import DEFAULTS, sliding_mode
from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem
from saltation.orbits.shooting import EquilibriumProblem
from saltation.special_points.boundary_equilibria import (
    boundary_equilibria,
    boundary_equilibria_of_mode,
    sliding_weight,
)

pytestmark = pytest.mark.slow  # computes a gallery diagram

#: (k, c, U, lam): the gallery's stable and unstable plant, and two other settings.
SETTINGS = [
    pytest.param((3.0, 0.5, 1.0, 2.0), id="stable-plant"),
    pytest.param((-1.5, 0.5, 1.0, 2.0), id="unstable-plant"),
    pytest.param((1.7, 0.3, 0.8, 0.6), id="stable-other"),
    pytest.param((-2.2, 0.9, 1.3, 1.1), id="unstable-other"),
]
TOL = 1e-9


@pytest.fixture(scope="module")
def flow():
    return Flow(sliding_mode())


def values(setting, r=0.0):
    k, c, U, lam = setting
    return {"k": k, "c": c, "U": U, "lam": lam, "r": r}


def plant_eigenvalues(k, c):
    root = np.sqrt(complex(c**2 - 4 * k))
    return np.sort_complex(np.array([(-c + root) / 2, (-c - root) / 2]))


def pseudo_branch(flow, setting):
    first = find_pseudo_equilibrium(flow, "s", [0.3, -0.2], parameters=values(setting))
    problem = PseudoEquilibriumProblem(flow, "s", first.modes, values(setting), continuation_parameter="r")
    branch = continue_branch(problem, PseudoEquilibriumProblem.unknowns(first), 0.0,
                             settings=ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(-1.0, 1.0)))
    return problem, branch


def test_the_defaults_are_the_gallery_stable_plant():
    assert DEFAULTS == {"k": 3.0, "c": 0.5, "U": 1.0, "lam": 2.0, "r": 0.2}


@pytest.mark.parametrize("setting", SETTINGS)
@pytest.mark.parametrize("r", [-0.45, 0.0, 0.3, 0.9])
def test_a_pseudo_equilibrium_against_its_closed_form(flow, setting, r):
    """(r, 0), the weight (U - k r) / (2 U) of u_minus, admissible for |k r| < U, the sliding eigenvalue -lam."""
    k, _c, U, lam = setting
    point = find_pseudo_equilibrium(flow, "s", [r + 0.4, 0.3], parameters=values(setting, r))
    a = (U - k * r) / (2 * U)
    np.testing.assert_allclose(point.state, [r, 0.0], rtol=0, atol=TOL)
    assert point.modes == ("u_plus", "u_minus")
    assert point.weights == pytest.approx((1 - a, a), abs=TOL)
    assert point.admissible == (abs(k * r) < U)
    # central differences (steps 1e-6) of an affine sliding field: exact to rounding
    np.testing.assert_allclose(point.eigenvalues, [-lam], atol=1e-8)
    assert point.stable == (abs(k * r) < U) and point.isolated


@pytest.mark.parametrize("setting", SETTINGS)
def test_a_branch_of_pseudo_equilibria_and_its_boundary_equilibria(flow, setting):
    """Over r in [-1, 1]: the states, weights and sliding eigenvalues at every point; the boundary equilibria at
    r = +-U / k on the equilibria (+-U / k, 0), with the plant's eigenvalues, persistence for k > 0 and a
    non-smooth fold for k < 0."""
    k, c, U, lam = setting
    problem, branch = pseudo_branch(flow, setting)
    r = branch.parameter
    assert r.min() == pytest.approx(-1.0) and r.max() == pytest.approx(1.0) and len(branch) > 15
    np.testing.assert_allclose(branch.states, np.column_stack([r, np.zeros_like(r)]), rtol=0, atol=TOL)
    weights = np.array([sliding_weight(problem, pt.state, pt.parameter) for pt in branch.points])
    np.testing.assert_allclose(weights, (U - k * r) / (2 * U), rtol=0, atol=TOL)
    np.testing.assert_array_equal(branch.stable, np.abs(k * r) < U)
    np.testing.assert_allclose(np.asarray(branch.multipliers)[:, 0], -lam, atol=1e-8)

    points = boundary_equilibria(problem, branch)
    assert len(points) == 2
    expected = "persistence" if k > 0 else "nonsmooth_fold"
    by_mode = {sp.touch_mode: sp for sp in points}
    for mode, sign in (("u_plus", 1.0), ("u_minus", -1.0)):  # u_plus at r = U / k, u_minus at r = -U / k
        sp = by_mode[mode]
        assert sp.kind is SpecialPointKind.BOUNDARY_EQUILIBRIUM and sp.touch_surface == "s"
        assert sp.classification == expected
        assert sp.parameter == pytest.approx(sign * U / k, abs=TOL) and sp.accuracy <= TOL
        np.testing.assert_allclose(sp.state, [sign * U / k, 0.0], atol=TOL)
        np.testing.assert_allclose(np.sort_complex(sp.multipliers), plant_eigenvalues(k, c), atol=TOL)


@pytest.mark.parametrize("setting", SETTINGS)
def test_the_modes_equilibria_and_the_same_boundary_equilibria(flow, setting):
    """Each mode's equilibrium (+-U / k, 0), admissible for r > U / k (u_plus) or r < -U / k (u_minus), crosses the
    line at the same r, with the same classification, seen from the mode's branch."""
    k, c, U, _lam = setting
    expected = "persistence" if k > 0 else "nonsmooth_fold"
    for mode, sign in (("u_plus", 1.0), ("u_minus", -1.0)):
        problem = EquilibriumProblem(flow, mode, values(setting), continuation_parameter="r")
        x0 = problem.solve([0.1, 0.1], 0.0).state
        branch = continue_branch(problem, x0, 0.0, settings=ContinuationSettings(ds=0.05, ds_max=0.1, bounds=(-1.0, 1.0)))
        np.testing.assert_allclose(branch.states, np.tile([sign * U / k, 0.0], (len(branch), 1)), rtol=0, atol=TOL)
        np.testing.assert_allclose(np.sort_complex(np.asarray(branch.multipliers)[0]), plant_eigenvalues(k, c), atol=TOL)
        np.testing.assert_array_equal(branch.stable, np.full(len(branch), k > 0))  # a focus or node, or a saddle
        s = np.array([flow.indicator("s", 0.0, pt.state, problem.parameters_at(pt.parameter)) for pt in branch.points])
        inside = s < 0 if mode == "u_plus" else s > 0
        np.testing.assert_array_equal(inside, branch.parameter > U / k if mode == "u_plus" else branch.parameter < -U / k)
        (sp,) = boundary_equilibria_of_mode(problem, branch)
        assert sp.touch_mode == mode and sp.classification == expected
        assert sp.parameter == pytest.approx(sign * U / k, abs=TOL)


def test_beyond_the_folds_one_saddle_is_left(flow):
    """k < 0, |r| > U / |k|: the pseudo-equilibrium is virtual, and so is the saddle it met; only the other saddle
    is admissible (u_plus's for r > U / |k|, u_minus's for r < -U / |k|): no rest state attracts."""
    k, U = -1.5, 1.0
    for r in (-0.9, 0.8):
        p = flow.parameters({"k": k, "r": r})
        assert not find_pseudo_equilibrium(flow, "s", [r, 0.0], parameters=p).admissible
        plus_inside = flow.indicator("s", 0.0, np.array([U / k, 0.0]), p) < 0  # u_plus's equilibrium in s < 0
        minus_inside = flow.indicator("s", 0.0, np.array([-U / k, 0.0]), p) > 0  # u_minus's in s > 0
        assert (plus_inside, minus_inside) == ((True, False) if r > 0 else (False, True))


@pytest.mark.parametrize(("k", "stop", "classification"), [("3", "0.6", "persistence"),
                                                           ("-1.5", "0.9", "nonsmooth_fold")])
def test_the_command_continues_the_pseudo_equilibria_through_a_boundary_equilibrium(tmp_path, capsys, k, stop,
                                                                                    classification):
    """``saltation continue FILE:sliding_mode --param r --from 0.2 --to STOP --equilibrium sliding:s --set k=K``:
    the branch's CSV holds (r, 0) and the sliding eigenvalue -lam; the special points name the boundary
    equilibrium at r = U / k (u_plus) or -U / k (u_minus) with its classification; the mode's equilibria are
    followed from it."""
    from saltation.apps import cli
    from saltation.output.io import load_branch_json, load_special_points_json

    model = tmp_path / "sliding_model.py"  # a user's model file, importing the (not yet shipped) model
    model.write_text("from saltation.models.sliding_mode import sliding_mode\n")
    out = tmp_path / "out"
    status = cli.main(["continue", f"{model}:sliding_mode", "--param", "r", "--from", "0.2", "--to", stop,
                       "--equilibrium", "sliding:s", "--set", f"k={k}", "--out", str(out), "--no-progress"])
    assert status == 0
    assert "boundary_equilibrium" in capsys.readouterr().out
    (table,) = out.glob("*_branch.csv")
    rows = list(csv.DictReader(table.open(newline="")))
    assert len(rows) > 5
    lam, U, kv = DEFAULTS["lam"], DEFAULTS["U"], float(k)
    for row in rows:
        assert float(row["x1"]) == pytest.approx(float(row["r"]), abs=TOL)
        assert float(row["x2"]) == pytest.approx(0.0, abs=TOL)
        assert float(row["eigenvalue1_re"]) == pytest.approx(-lam, abs=1e-8)
    (records,) = out.glob("*_special_points.json")
    (record,) = load_special_points_json(records)
    boundary = U / kv if kv > 0 else -U / kv  # u_plus's at U / k (k > 0), u_minus's at -U / k (k < 0)
    assert record["kind"] == "boundary_equilibrium" and record["classification"] == classification
    assert record["value"] == pytest.approx(boundary, abs=TOL)
    through = [load_branch_json(p) for p in sorted(out.glob("*_branch_*.json")) if not p.name.endswith(".meta.json")]
    assert through
    for b in through:
        np.testing.assert_allclose(b.states, np.tile([U / kv if kv > 0 else -U / kv, 0.0], (len(b), 1)), atol=TOL)
