"""A branch holds its problem, and every problem keeps one declared contract.

A two-parameter curve starts from the branch the user holds (``follow_locus(branch, index, ...)``), as
from the ``(problem, point)`` of release 0.1, and gives the same curve; a branch read from a file, which
holds no problem, says what to pass instead.  The continuation engine asks a problem through
:class:`~saltation.orbits.problem.BranchProblem` and never probes its type.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

import saltation
from saltation import Flow
from saltation.branches.branch import SpecialPointKind
from saltation.errors import SaltationError
from saltation.models import impact_oscillator
from saltation.models.impact_oscillator import DEFAULTS as IMPACT
from saltation.orbits.conditions import ConditionedProblem
from saltation.orbits.equilibria import EquilibriumProblem
from saltation.orbits.multiple import MultipleShootingProblem
from saltation.orbits.problem import BranchProblem
from saltation.orbits.pseudo_equilibria import PseudoEquilibriumProblem
from saltation.orbits.single import ShootingProblem
from saltation.output.io import load_branch_json, save_branch_json
from saltation.special_points.boundary_equilibria import BoundaryEquilibriumCurve
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.special_points.loci import GrazingCurve, MultiplierCurve, SlidingCurve, follow_locus

SRC = Path(saltation.__file__).parent


@pytest.fixture(scope="module")
def impact_branch():
    """The impact oscillator's branch in ``s`` down to its grazing, and the linear response's closed form."""
    flow = Flow(impact_oscillator())
    zeta, w = IMPACT["zeta"], IMPACT["omega"]
    problem = ShootingProblem(flow, {"s": 3.0}, continuation_parameter="s")
    det = (1 - w**2) ** 2 + (2 * zeta * w) ** 2
    x0 = np.array([(1 - w**2) / det, 2 * zeta * w**2 / det])
    branch = continue_branch(problem, x0, 3.0, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.5, 3.0)),
                             directions=(-1,))
    return problem, branch


def test_a_curve_starts_from_the_branch_as_from_its_problem(impact_branch):
    problem, branch = impact_branch
    assert branch.problem is problem
    index = next(i for i, sp in enumerate(branch.special_points) if sp.kind is SpecialPointKind.GRAZING)
    from_branch = follow_locus(branch, index, "omega", (0.75, 0.85))
    from_problem = follow_locus(problem, branch.special_points[index], "omega", (0.75, 0.85))
    np.testing.assert_array_equal(from_branch.values, from_problem.values)
    # the closed form of the grazing curve: the linear response's amplitude reaches the stop at s
    s, omega = from_branch.values.T
    zeta = IMPACT["zeta"]
    np.testing.assert_allclose(s, 1 / np.sqrt((1 - omega**2) ** 2 + (2 * zeta * omega) ** 2), rtol=0, atol=1e-9)
    assert branch.problem is problem and problem.p[problem.lam_index] == 3.0  # the branch's own is left as it is


def test_a_branch_read_from_a_file_says_what_to_pass(impact_branch, tmp_path):
    _, branch = impact_branch
    save_branch_json(branch, tmp_path / "b.json")
    read = load_branch_json(tmp_path / "b.json")
    assert read.problem is None
    with pytest.raises(SaltationError, match="holds no problem.*pass the problem"):
        follow_locus(read, 0, "omega", (0.75, 0.85))


@pytest.mark.parametrize("index", [99, -99, 1.5, True, "0"])
def test_an_index_that_names_no_special_point_is_refused(impact_branch, index):
    _, branch = impact_branch
    with pytest.raises(SaltationError, match=f"has {len(branch.special_points)} special points"):
        follow_locus(branch, index, "omega", (0.75, 0.85))


@pytest.mark.parametrize("cls", [ShootingProblem, MultipleShootingProblem, EquilibriumProblem, PseudoEquilibriumProblem,
                                 ConditionedProblem, GrazingCurve, SlidingCurve, MultiplierCurve,
                                 BoundaryEquilibriumCurve])
def test_every_problem_keeps_the_declared_contract(cls):
    assert issubclass(cls, BranchProblem)
    assert not getattr(cls, "__abstractmethods__", None), f"{cls.__name__} leaves {cls.__abstractmethods__} abstract"


def _probes(path: Path) -> list[str]:
    """``isinstance``/``getattr``/``hasattr`` calls whose first argument is a problem (not one of its parts)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id in ("isinstance", "getattr", "hasattr") and node.args):
            text = ast.unparse(node.args[0])
            if re.fullmatch(r"((self|ctx|cont)\.)?prob(lem)?", text):
                found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    return found


DETECTOR = ["detector", "context", "smooth", "nonsmooth", "symmetric", "points"]


def test_the_continuation_engine_and_the_detector_ask_the_problem_and_never_probe_it():
    files = [*sorted((SRC / "branches").glob("*.py")), *(SRC / "special_points" / f"{m}.py" for m in DETECTOR)]
    probes = [p for f in files for p in _probes(f)]
    assert probes == []
