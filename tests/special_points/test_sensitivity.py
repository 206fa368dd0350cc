"""Sensitivities of special points (:mod:`saltation.special_points.sensitivity`) against closed forms and
against finite differences of the points relocated at ``q +- h``.

References, independent of the implicit function theorem on the defining systems:

* the trilinear model's corners at w_A and w_B, where the free orbit's amplitude is x_c:
  ``F(w, q) = (k - m w^2)^2 + (c w)^2 - (f0 / x_c)^2 = 0``, so ``dw/dq = -F_q / F_w`` (0 for k_f and c_f);
* the impact oscillator's grazing ``s* = 1 / sqrt((1 - w^2)^2 + (2 zeta w)^2)``, and the friction
  oscillator's grazing-sliding ``v_b* = a w / sqrt((1 - w^2)^2 + (2 zeta w)^2)`` (derivatives by sympy);
* the bouncing ball's period doubling, ``A* = g / w^2 sqrt((pi (1 - e) / (1 + e))^2 + (2 (1 + e^2) / (1 + e)^2)^2)``
  (Holmes 1982; derivatives by sympy);
* the trilinear fold: Richardson-extrapolated central differences of the fold relocated at ``q +- h``,
  ``+- 2h`` and ``+- 4h`` (a different computation: Newton on the perturbed system, not the linear solve),
  and the envelope formula ``d omega / d q = -(w^T F_q) / (w^T F_omega)`` with ``w`` the left null vector of
  ``M - I`` (no second derivative, no bordered test function);
* the friction oscillator's switching-sliding: central differences of the relocated point, as the fold.

The finite differences' tolerance is their own error estimate: the difference of two Richardson values
(of steps h, 2h and 2h, 4h), plus the relocations' error over the step, plus the accuracy the sensitivity
claims.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from saltation import Flow
from saltation.branches.branch import SpecialPoint, SpecialPointKind
from saltation.errors import ModelError, SaltationError
from saltation.models import (
    bouncing_ball,
    friction_oscillator,
    impact_oscillator,
    trilinear,
)
from saltation.models.bouncing_ball import DEFAULTS as BALL
from saltation.models.friction_oscillator import DEFAULTS as FRICTION
from saltation.models.impact_oscillator import DEFAULTS as IMPACT
from saltation.models.trilinear import DEFAULTS as TRI
from saltation.models.trilinear import linear_response_state
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.special_points.sensitivity import (
    add_sensitivities,
    defining_system,
    sensitivities,
)


@pytest.fixture(scope="module")
def trilinear_branch():
    flow = Flow(trilinear())
    problem = ShootingProblem(flow, {"omega": 0.6}, continuation_parameter="omega")
    return continue_branch(problem, linear_response_state(dict(TRI, omega=0.6)), 0.6,
                           settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.6, 1.6)), directions=(1,))


def point_of(branch, kind: str) -> int:
    (i,) = [i for i, sp_ in enumerate(branch.special_points) if sp_.kind.value == kind]
    return i


def richardson(located, q: float, h: float) -> tuple[float, float]:
    """``(d/dq, its error estimate)`` of ``located(value) -> (parameter, accuracy)`` at ``q``: central differences
    of steps h, 2h, 4h, extrapolated; the error is the two extrapolations' difference plus the locations' error
    carried by the smallest step."""
    values, worst = {}, 0.0
    for k in (1, 2, 4):
        (a, ea), (b, eb) = located(q + k * h), located(q - k * h)
        values[k] = (a - b) / (2 * k * h)
        worst = max(worst, ea, eb)
    r1 = (4 * values[1] - values[2]) / 3
    r2 = (4 * values[2] - values[4]) / 3
    return r1, abs(r1 - r2) + 2 * worst / h


def relocate(flow, point: SpecialPoint, lam: str, q: str, value: float) -> tuple[float, float]:
    """The point relocated by its defining system with ``q = value``: its parameter and accuracy."""
    problem = ShootingProblem(flow, {lam: point.parameter, q: value}, continuation_parameter=lam)
    system, u0 = defining_system(problem, point)
    found = system.solve(u0, tol=1e-13)
    return float(found.parameters[problem.lam_index]), float(found.accuracy[0])


@pytest.mark.parametrize("kind", ["nonsmooth_no_crossing", "discontinuous_fold"])
def test_the_trilinear_corners_against_closed_form(trilinear_branch, kind):
    m, c, k, f0, xc = (TRI[q] for q in ("m", "c", "k", "f0", "x_c"))
    s = sensitivities(trilinear_branch, point_of(trilinear_branch, kind))
    w = s.parameter
    assert (k - m * w**2) ** 2 + (c * w) ** 2 == pytest.approx((f0 / xc) ** 2, abs=1e-13)
    F_w = 2 * (k - m * w**2) * (-2 * m * w) + 2 * c**2 * w
    F_q = {"m": -2 * (k - m * w**2) * w**2, "c": 2 * c * w**2, "k": 2 * (k - m * w**2), "f0": -2 * f0 / xc**2,
           "x_c": 2 * f0**2 / xc**3, "k_f": 0.0, "c_f": 0.0}
    assert set(s.d_parameter) == set(F_q)
    for q, value in F_q.items():
        # the free flow is exact (affine modes): the sensitivities are good to rounding, as they claim
        assert s.d_parameter[q] == pytest.approx(-value / F_w, abs=s.accuracy[q] + 1e-13), q
    # the period is the forcing period's: d(2 pi / w)/dq = -2 pi / w^2 dw/dq
    assert s.d_period["f0"] == pytest.approx(-2 * np.pi / w**2 * s.d_parameter["f0"], rel=1e-12)


def test_the_trilinear_fold_against_relocated_folds_and_the_envelope_formula(trilinear_branch):
    branch = trilinear_branch
    i = point_of(branch, "fold")
    fold = branch.special_points[i]
    s = sensitivities(branch, i)
    flow = branch.problem.flow
    for q in ("f0", "c_f", "m"):
        reference, error = richardson(lambda v, q=q: relocate(flow, fold, "omega", q, v), TRI[q], 1e-3)
        assert abs(s.d_parameter[q] - reference) <= error + s.accuracy[q], (q, s.d_parameter[q], reference, error)
    # the envelope formula at the relocated fold, every parameter
    p = flow.parameters({"omega": s.parameter})
    T = 2 * np.pi / s.parameter
    names = flow.system.parameter_names
    runs = {q: flow.run(s.state, 0.0, T, p, variational=True, sensitivity=names.index(q)) for q in names}
    M = runs["omega"].monodromy
    w = np.linalg.svd(M - np.eye(2))[0][:, -1]  # the left null vector of M - I

    def F(q):
        dT = -2 * np.pi / s.parameter**2 if q == "omega" else 0.0
        return runs[q].parameter_sensitivity + dT * runs[q].velocity_end

    for q in s.d_parameter:
        envelope = -(w @ F(q)) / (w @ F("omega"))
        assert s.d_parameter[q] == pytest.approx(envelope, abs=1e-9 + s.accuracy[q]), q


def test_the_period_doubling_of_the_bouncing_ball_against_closed_form():
    g_, e_, a0, w_ = (BALL[q] for q in ("g", "e", "A", "omega"))
    T = 2 * np.pi / w_
    phi = np.arccos((1 - e_) * np.pi * g_ / ((1 + e_) * a0 * w_**2))
    t_i, v_plus = phi / w_, g_ * T / 2
    tau = (-t_i) % T
    x0 = np.array([a0 * np.sin(w_ * t_i) + v_plus * tau - g_ * tau**2 / 2, v_plus - g_ * tau])
    problem = ShootingProblem(Flow(bouncing_ball()), {"A": a0}, continuation_parameter="A")
    branch = continue_branch(problem, x0, a0, settings=ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(a0, 0.5)),
                             directions=(1,))
    s = sensitivities(branch, point_of(branch, "period_doubling"))
    g, e, w = sp.symbols("g e omega")
    A_pd = g / w**2 * sp.sqrt((sp.pi * (1 - e) / (1 + e)) ** 2 + (2 * (1 + e**2) / (1 + e) ** 2) ** 2)
    at = {g: g_, e: e_, w: w_}
    assert s.parameter == pytest.approx(float(A_pd.subs(at)), abs=1e-11)
    for q, symbol in (("g", g), ("e", e), ("omega", w)):
        reference = float(sp.diff(A_pd, symbol).subs(at))
        # the bordered test function's derivatives are central differences: the estimate says how well
        assert s.accuracy[q] < 1e-8
        assert s.d_parameter[q] == pytest.approx(reference, abs=s.accuracy[q] + 1e-12), q


def test_the_grazing_of_the_impact_oscillator_against_closed_form():
    zeta_, w_ = IMPACT["zeta"], IMPACT["omega"]
    det = (1 - w_**2) ** 2 + (2 * zeta_ * w_) ** 2
    problem = ShootingProblem(Flow(impact_oscillator()), {"s": 3.0}, continuation_parameter="s")
    branch = continue_branch(problem, np.array([(1 - w_**2) / det, 2 * zeta_ * w_**2 / det]), 3.0,
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(2.5, 3.0)), directions=(-1,))
    s = sensitivities(branch, point_of(branch, "grazing"))
    zeta, w = sp.symbols("zeta omega")
    s_star = 1 / sp.sqrt((1 - w**2) ** 2 + (2 * zeta * w) ** 2)
    at = {zeta: zeta_, w: w_}
    for q, symbol in (("zeta", zeta), ("omega", w)):
        assert s.d_parameter[q] == pytest.approx(float(sp.diff(s_star, symbol).subs(at)), abs=s.accuracy[q] + 1e-12)
    assert s.d_parameter["r"] == pytest.approx(0.0, abs=s.accuracy["r"] + 1e-14)  # no impact on the grazing orbit


@pytest.fixture(scope="module")
def friction_branch():
    zeta_, f_, a_, w_ = (FRICTION[k] for k in ("zeta", "F", "a", "omega"))
    det = (1 - w_**2) ** 2 + (2 * zeta_ * w_) ** 2
    amplitude, phi = a_ / np.sqrt(det), np.arctan2(2 * zeta_ * w_, 1 - w_**2)
    x0 = np.array([f_ + amplitude * np.cos(-phi), -amplitude * w_ * np.sin(-phi)])  # the slower-than-belt response
    problem = ShootingProblem(Flow(friction_oscillator()), {"v_b": 2.5}, continuation_parameter="v_b")
    return continue_branch(problem, x0, 2.5, settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.85, 2.5)),
                           directions=(-1,))


def test_the_grazing_sliding_of_the_friction_oscillator_against_closed_form(friction_branch):
    s = sensitivities(friction_branch, point_of(friction_branch, "grazing_sliding"))
    zeta, a, w = sp.symbols("zeta a omega")
    v_star = a * w / sp.sqrt((1 - w**2) ** 2 + (2 * zeta * w) ** 2)
    at = {zeta: FRICTION["zeta"], a: FRICTION["a"], w: FRICTION["omega"]}
    for q, symbol in (("zeta", zeta), ("a", a), ("omega", w)):
        assert s.d_parameter[q] == pytest.approx(float(sp.diff(v_star, symbol).subs(at)), abs=s.accuracy[q] + 1e-12), q
    assert s.d_parameter["F"] == pytest.approx(0.0, abs=s.accuracy["F"] + 1e-13)  # the orbit never slides


def test_the_switching_sliding_against_relocated_points(friction_branch):
    branch = friction_branch
    i = point_of(branch, "switching_sliding")
    point = branch.special_points[i]
    s = sensitivities(branch, i)
    flow = branch.problem.flow
    for q in ("zeta", "F", "a", "omega"):
        reference, error = richardson(lambda v, q=q: relocate(flow, point, "v_b", q, v), FRICTION[q], 1e-3)
        assert abs(s.d_parameter[q] - reference) <= error + s.accuracy[q], (q, s.d_parameter[q], reference, error)


def test_sensitivities_are_stored_on_the_points_and_kept_in_files(trilinear_branch, tmp_path):
    import copy

    from saltation.output.io import (
        load_branch_csv,
        load_branch_json,
        save_branch_csv,
        save_branch_json,
    )
    from saltation.summary import special_point_summary

    branch = copy.copy(trilinear_branch)
    branch.special_points = list(trilinear_branch.special_points)
    found = add_sensitivities(branch, parameters=["f0", "c"])
    assert all(f is not None for f in found)
    for sp_, f in zip(branch.special_points, found):
        assert sp_.sensitivities == f.d_parameter and list(sp_.sensitivities) == ["f0", "c"]
    for again in (load_branch_json(save_branch_json(branch, tmp_path / "b.json")),
                  load_branch_csv(save_branch_csv(branch, tmp_path / "b.csv"))):
        assert [sp_.sensitivities for sp_ in again.special_points] == [sp_.sensitivities for sp_ in branch.special_points]
    assert "d/df0" in special_point_summary(branch.special_points[0])
    # the branch it was copied from is left as it was
    assert all(sp_.sensitivities is None for sp_ in trilinear_branch.special_points)


def test_bad_requests_name_the_problem(trilinear_branch, tmp_path):
    from dataclasses import replace

    from saltation.output.io import load_branch_json, save_branch_json

    i = point_of(trilinear_branch, "fold")
    with pytest.raises(ModelError, match="nope"):
        sensitivities(trilinear_branch, i, parameters=["nope"])
    with pytest.raises(ModelError, match="'omega' is the branch's own parameter"):
        sensitivities(trilinear_branch, i, parameters=["omega"])
    monitor = SpecialPoint(kind=SpecialPointKind.NEIMARK_SACKER, parameter=1.0, bracket=(1.0, 1.0), accuracy=0.0,
                           index=0, state=np.zeros(2), period=1.0, amplitude=0.0)
    with pytest.raises(ModelError, match="neimark_sacker"):
        sensitivities(trilinear_branch.problem, monitor)
    read = load_branch_json(save_branch_json(trilinear_branch, tmp_path / "b.json"))
    with pytest.raises(SaltationError, match="holds no problem"):
        sensitivities(read, i)
    with pytest.raises(SaltationError, match="holds no problem"):
        add_sensitivities(read)
    backward = ShootingProblem(trilinear_branch.problem.flow, {"omega": 1.0}, continuation_parameter="omega",
                               backward=True)
    corner = trilinear_branch.special_points[point_of(trilinear_branch, "discontinuous_fold")]
    with pytest.raises(ModelError, match="backward-time orbit: the point does not say which surface"):
        sensitivities(backward, corner)
    autonomous = ShootingProblem(Flow(hopf_model(False)), {"mu": 0.2}, continuation_parameter="mu")
    fold = replace(trilinear_branch.special_points[i], state=np.array([-0.5, 0.0]))
    with pytest.raises(ModelError, match="fold of an autonomous orbit"):
        sensitivities(autonomous, fold)


def test_multiple_shooting_gives_the_same_sensitivities(trilinear_branch):
    """The defining system by multiple shooting (three segments, the condition read from the segment that holds
    its instant) against single shooting's, at the corner and at the fold."""
    import copy

    from saltation.orbits.shooting import MultipleShootingProblem

    for kind in ("discontinuous_fold", "fold"):
        point = trilinear_branch.special_points[point_of(trilinear_branch, kind)]
        single = sensitivities(trilinear_branch.problem, point, parameters=["f0", "c"])
        multiple = sensitivities(MultipleShootingProblem(copy.copy(trilinear_branch.problem), 3), point,
                                 parameters=["f0", "c"])
        for q in ("f0", "c"):
            assert multiple.d_parameter[q] == pytest.approx(single.d_parameter[q],
                                                            abs=single.accuracy[q] + multiple.accuracy[q] + 1e-12)


def hopf_model(backward: bool):
    """The Hopf normal form against a wall ``x = c`` with the impact ``y -> -r y`` (the model of
    test_grazing_backward_autonomous.py, written the same way): its cycle ``rho = sqrt(mu)`` of period 2 pi
    grazes the wall at ``mu* = c^2``, so ``d mu* / dc = 2 c``, ``d mu* / dr = 0`` and the period does not move."""
    from saltation import Crossing, Mode, PiecewiseSystem, Transition

    s = "-" if backward else ""
    return PiecewiseSystem(
        name=f"test_hopf_impact_{'backward' if backward else 'forward'}", states=["x", "y"],
        parameters={"mu": 0.2, "c": 0.5, "r": 0.8},
        modes=[Mode("free", [f"{s}(mu*x - y - x*(x**2 + y**2))", f"{s}(x + mu*y - y*(x**2 + y**2))"])],
        surfaces={"wall": "x - c"},
        transitions=[Transition("free", "wall", Crossing.RISING, "free", reset=["x", "-r*y"])],
    )


@pytest.mark.parametrize("backward", [False, True], ids=["forward", "backward"])
def test_an_autonomous_grazing_against_closed_form(backward):
    problem = ShootingProblem(Flow(hopf_model(backward)), {"mu": 0.2}, continuation_parameter="mu", backward=backward)
    branch = continue_branch(problem, problem.pack([-np.sqrt(0.2), 0.0], 2 * np.pi), 0.2, directions=(1,),
                             settings=ContinuationSettings(ds=0.01, ds_max=0.02, bounds=(0.2, 0.3)))
    s = sensitivities(branch, point_of(branch, "grazing"))
    assert s.parameter == pytest.approx(0.25, abs=s.location_accuracy + 1e-12)
    assert s.d_parameter["c"] == pytest.approx(2 * 0.5, abs=s.accuracy["c"] + 1e-12)
    assert s.d_parameter["r"] == pytest.approx(0.0, abs=s.accuracy["r"] + 1e-14)
    assert s.d_period["c"] == pytest.approx(0.0, abs=1e-10)  # the cycle's period is 2 pi for every mu
    # the branch's problem keeps its own phase anchor
    assert branch.problem.x_ref is not None and not np.allclose(branch.problem.x_ref, s.state)
