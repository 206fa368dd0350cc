"""Neimark-Sacker curves and the codimension-two points of fold and Neimark-Sacker curves, against closed forms.

The model: the Jeffcott rotor against a snubber ring (``../shared/trial-models/jeffcott_snubber.py``), isotropic,
without gravity, with a strong contact friction of the backward sense (``mu < 0``), heavier damping and a softer
ring (``zeta = 0.2``, ``beta = 3``, ``rho = 0.3``).  Its whirls in contact all round are circles, ``z = R exp(i
(omega t - phi))``: equilibria of the frame rotating with the forcing.  The reference (``tests/rotor_reference.py``,
numpy and scipy only) has them in closed form (``|a R - b| = rho omega^2``, a quadratic in ``R``) with the
rotating frame's Jacobian ``J`` written by hand; the orbit's multipliers are ``exp(lambda T)``, ``lambda`` the
eigenvalues of ``J``.  So:

* the Neimark-Sacker curve is the rotating frame's Hopf curve: a complex pair ``lambda = +-i nu`` of ``J``, found
  here by brentq in ``mu`` at each ``omega`` of the curve; ``theta = nu T``;
* past the 1:1 resonance the same defining system holds at a neutral saddle: a real pair ``lambda``, ``-lambda``
  of ``J`` (multipliers ``exp(+-lambda T)``, product 1, ``|kappa| > 1``);
* the 1:1 resonance where the Neimark-Sacker curve meets the fold curve is the rotating frame's
  Bogdanov-Takens point: ``J`` has a double zero eigenvalue where the quadratic in ``R`` has a double root, found
  by scipy's fsolve on those two closed-form conditions.  Both curves find it, each by its own test function.

The cusp: the trilinear model's fold curve in (omega, f0) has a cusp where its two folds meet (the smooth fold of
the jump up and that of the jump down); there the curve's projection on the parameter plane turns back, ``f0``
and ``omega`` both at an extremum along the curve.  The located zero of the normal-form coefficient is checked
against that extremum, found from the curve's points by a parabola (a different quantity than the coefficient,
which is a central difference of the monodromy).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import rotor_reference as reference
from conftest import trial_model
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from saltation import Flow
from saltation.apps import cli
from saltation.branches.branch import (
    CodimensionTwoKind,
    SpecialPointKind,
    SpecialPointStatus,
)
from saltation.orbits.conditions import NeimarkSackerCondition
from saltation.orbits.shooting import ShootingProblem
from saltation.special_points.continuation import ContinuationSettings, continue_branch
from saltation.special_points.loci import follow_locus

ROTOR = {"zeta": 0.2, "beta": 3.0, "rho": 0.3}
MU0, OMEGA0 = -0.35, 1.25
MU_RANGE = (-0.43, -0.33)


# ------------------------------------------------------------------------------------------------
# the closed forms (the reference's contact whirl and rotating-frame Jacobian, and scipy)


def whirls(omega: float, mu: float) -> list[tuple[float, float]]:
    return reference.contact_whirl(omega, mu=mu, **ROTOR)


def eigenvalues(omega: float, mu: float, whirl: tuple[float, float]) -> np.ndarray:
    return np.linalg.eigvals(reference.rotating_jacobian(omega, *whirl, mu=mu, **ROTOR))


def slow_pair(omega: float, mu: float) -> complex:
    """The upper whirl's eigenvalue of the slow pair (the one that crosses the imaginary axis)."""
    lam = eigenvalues(omega, mu, whirls(omega, mu)[-1])
    return min(lam, key=lambda z: abs(z.imag) - 10 * (z.imag > 0))


def hopf_mu(omega: float, near: float, width: float = 1e-5) -> float:
    """The rotating frame's Hopf point at ``omega``: ``Re lambda = 0`` for the slow pair, by brentq in mu within
    ``width`` of ``near`` (brentq fails where the root is not there)."""
    return brentq(lambda mu: slow_pair(omega, mu).real, near - width, near + width, xtol=1e-15, rtol=1e-15)


def bogdanov_takens() -> tuple[float, float]:
    """``(omega, mu)`` where the quadratic in ``R`` has a double root and ``J`` a double zero eigenvalue."""
    zeta, beta, delta, rho = ROTOR["zeta"], ROTOR["beta"], 1.0, ROTOR["rho"]

    def conditions(v):
        omega, mu = v
        a = 1 - omega**2 + beta + 1j * (2 * zeta * omega + beta * mu)
        b = beta * delta * (1 + 1j * mu)
        c2, c1, c0 = abs(a) ** 2, -2 * (a * np.conj(b)).real, abs(b) ** 2 - rho**2 * omega**4
        R = -c1 / (2 * c2)
        W = rho * omega**2 / (a - b / R)
        J = reference.rotating_jacobian(omega, abs(W), -np.angle(W), mu=mu, **ROTOR)
        return [(c1 * c1 - 4 * c2 * c0) / c2, np.poly(J)[-2]]  # the double root; the coefficient of lambda

    omega, mu = fsolve(conditions, [1.098, -0.4257], xtol=1e-14)
    assert np.max(np.abs(conditions([omega, mu]))) < 1e-12
    return float(omega), float(mu)


# ------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def rotor():
    system = trial_model("jeffcott_snubber").rotor(mu=MU0, **ROTOR)
    problem = ShootingProblem(Flow(system), {"omega": OMEGA0}, continuation_parameter="omega")
    x0 = reference.contact_whirl_state(OMEGA0, *whirls(OMEGA0, MU0)[-1])
    return problem, x0


@pytest.fixture(scope="module")
def ns_curve(rotor):
    problem, x0 = rotor
    branch = continue_branch(problem, x0, OMEGA0, settings=ContinuationSettings(ds=0.02, ds_max=0.05,
                                                                             bounds=(OMEGA0, 1.45)), directions=(1,))
    (ns,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.NEIMARK_SACKER]
    settings = ContinuationSettings(ds=0.005, ds_max=0.01, bounds=MU_RANGE)
    return ns, follow_locus(problem, ns, "mu", MU_RANGE, settings=settings)


def _closed_form_multipliers(omega: float, mu: float, state: np.ndarray) -> np.ndarray:
    """``exp(lambda T)`` of the contact whirl at ``(omega, mu)`` whose state is ``state``."""
    whirl = min(whirls(omega, mu), key=lambda w: np.linalg.norm(reference.contact_whirl_state(omega, *w) - state))
    assert np.linalg.norm(reference.contact_whirl_state(omega, *whirl) - state) < 1e-7
    return np.linalg.eigvals(expm(reference.rotating_jacobian(omega, *whirl, mu=mu, **ROTOR) * 2 * np.pi / omega))


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    b = list(b)
    worst = 0.0
    for x in a:
        j = int(np.argmin([abs(x - y) for y in b]))
        worst = max(worst, abs(x - b.pop(j)))
    return worst


def test_the_neimark_sacker_curve_is_the_rotating_frames_hopf_curve(ns_curve):
    """Every Neimark-Sacker point of the curve lies on the closed-form Hopf curve, with its multipliers
    ``exp(+-i nu T)``; past the 1:1 resonance the curve's points are neutral saddles (a real pair of ``J`` with
    zero sum) and are labelled so (no curve kind).

    Tolerances: the defining system is solved to 1e-10 in its residual (the bordered ``G`` entries and the
    periodicity) with an integration error of about 1e-10; the Hopf condition's slope in ``mu`` is of order one, so
    ``mu`` agrees to 1e-8.  The multipliers agree with ``exp(lambda T)`` to 1e-8 (monodromy to the integration
    tolerance, eigenvalues of a well-separated spectrum)."""
    _, curve = ns_curve
    assert curve.curve_of is SpecialPointKind.NEIMARK_SACKER
    assert len(curve.points) > 30 and "reached a parameter bound" in curve.stop_detail
    on_circle = [bp for bp in curve.points if bp.curve_kind is SpecialPointKind.NEIMARK_SACKER]
    saddles = [bp for bp in curve.points if bp.curve_kind is None]
    assert len(on_circle) > 20 and len(saddles) > 5
    checked = 0
    for bp in on_circle[::3]:
        omega, mu = bp.parameter, bp.second_parameter
        if all(whirls(omega, mu + d) for d in (-1e-5, 1e-5)):  # (not within 1e-5 of the fold)
            assert mu == pytest.approx(hopf_mu(omega, mu), abs=1e-8)
            checked += 1
        closed = _closed_form_multipliers(omega, mu, bp.state)
        assert _distance(bp.multipliers, closed) < 1e-8
        pair = bp.multipliers[np.argmin(np.abs(np.abs(bp.multipliers) - 1.0))]
        assert abs(abs(pair) - 1.0) < 1e-8 and abs(pair.imag) > 0.1
        nu = abs(slow_pair(omega, mu).imag)
        assert abs(np.angle(pair)) == pytest.approx(nu * 2 * np.pi / omega, abs=1e-7)
    assert checked > 5
    for bp in saddles[::3]:
        omega, mu = bp.parameter, bp.second_parameter
        closed = _closed_form_multipliers(omega, mu, bp.state)
        assert _distance(bp.multipliers, closed) < 1e-8
        real = np.sort(closed[np.abs(closed.imag) < 1e-12].real)
        assert real.size == 2 and real[0] * real[1] == pytest.approx(1.0, abs=1e-8)


def test_the_one_one_resonance_ends_the_neimark_sacker_curve_at_the_bogdanov_takens_point(ns_curve):
    """Where ``kappa`` passes 1 the Neimark-Sacker curve meets the fold curve: the closed-form Bogdanov-Takens
    point of the rotating frame, within the stated accuracy (the bracket of ``kappa - 1``, whose error is the
    corrector's 1e-10) plus 1e-8."""
    _, curve = ns_curve
    (r1,) = [sp for sp in curve.special_points if sp.codimension_two is CodimensionTwoKind.STRONG_RESONANCE_1_1]
    assert r1.kind is SpecialPointKind.CODIMENSION_TWO and r1.status is SpecialPointStatus.LOCATED
    assert r1.sides == ("neimark_sacker", "fold")
    omega, mu = bogdanov_takens()
    assert abs(r1.parameter - omega) <= r1.accuracy + 1e-8
    assert abs(r1.second_parameter - mu) <= r1.accuracy + 1e-8
    # no other codimension-two point on this curve: theta = nu T stays below 1.3 (no 1:3 or 1:4 resonance)
    assert len(curve.special_points) == 1


def test_the_name_of_a_codimension_two_point_is_written_and_read(ns_curve, tmp_path):
    """A curve with a named codimension-two point round-trips through a branch file (and a file without the
    field reads as None)."""
    from saltation.output.codecs import branch_from_dict, branch_to_dict
    from saltation.output.io import load_branch_json, save_branch_json

    _, curve = ns_curve
    again = load_branch_json(save_branch_json(curve, tmp_path / "ns.json"))
    assert [sp.codimension_two for sp in again.special_points] == [CodimensionTwoKind.STRONG_RESONANCE_1_1]
    assert [bp.curve_kind for bp in again.points] == [bp.curve_kind for bp in curve.points]
    old = branch_to_dict(curve)
    for sp in old["special_points"]:
        del sp["codimension_two"]
    assert branch_from_dict(old).special_points[0].codimension_two is None


def test_the_fold_curve_finds_the_same_one_one_resonance(rotor):
    """On the fold curve of the contact whirls a second multiplier reaches +1 at the same Bogdanov-Takens point
    (its test function is the product of the other multipliers minus one, not ``kappa``)."""
    problem, x0 = rotor
    branch = continue_branch(problem, x0, OMEGA0, settings=ContinuationSettings(ds=0.02, ds_max=0.05,
                                                                             bounds=(1.0, OMEGA0)), directions=(-1,))
    (fold,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.FOLD]
    curve = follow_locus(problem, fold, "mu", MU_RANGE, settings=ContinuationSettings(ds=0.005, ds_max=0.01,
                                                                                    bounds=MU_RANGE))
    (r1,) = curve.special_points
    assert r1.codimension_two is CodimensionTwoKind.STRONG_RESONANCE_1_1 and r1.sides == ("fold", "fold")
    omega, mu = bogdanov_takens()
    assert abs(r1.parameter - omega) <= r1.accuracy + 1e-8
    assert abs(r1.second_parameter - mu) <= r1.accuracy + 1e-8


def test_the_cusp_of_the_trilinear_fold_curve(trilinear_flow):
    """The trilinear fold curve's cusp, a zero of ``<p, B(q, q)>``, lies where the curve turns back in the
    parameter plane: ``f0`` is least there along the curve, and so is ``omega``.  The extremum is found by a
    parabola through the five curve points around the least ``f0`` (in the arclength of the curve in the full
    space, where the curve is smooth); it moves by the difference between the three- and five-point parabolas,
    which bounds its error."""
    from saltation.models.trilinear import DEFAULTS as TRI
    from saltation.models.trilinear import linear_response_state

    problem = ShootingProblem(trilinear_flow, {"omega": 0.6}, continuation_parameter="omega")
    branch = continue_branch(problem, linear_response_state(dict(TRI, omega=0.6)), 0.6,
                             settings=ContinuationSettings(ds=0.02, ds_max=0.05, bounds=(0.6, 1.6)), directions=(1,))
    (fold,) = [sp for sp in branch.special_points if sp.kind is SpecialPointKind.FOLD]
    bounds = (0.05, 0.4)
    curve = follow_locus(problem, fold, "f0", bounds, settings=ContinuationSettings(ds=0.01, ds_max=0.02,
                                                                                  bounds=bounds))
    (cusp,) = [sp for sp in curve.special_points if sp.codimension_two is CodimensionTwoKind.CUSP]
    assert cusp.sides == ("fold", "fold") and cusp.status is SpecialPointStatus.LOCATED
    z = np.column_stack([curve.states, curve.values])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(z, axis=0), axis=1))])
    i = int(np.argmin(curve.values[:, 1]))
    assert 2 <= i <= len(s) - 3

    def extremum(width: int) -> np.ndarray:
        window = slice(i - width, i + width + 1)
        f0 = np.polyfit(s[window], curve.values[window, 1], 2)
        at = -f0[1] / (2 * f0[0])
        omega = np.polyfit(s[window], curve.values[window, 0], 2)
        return np.array([np.polyval(omega, at), np.polyval(f0, at)])

    five, three = extremum(2), extremum(1)
    bound = float(np.max(np.abs(five - three)))
    np.testing.assert_allclose([cusp.parameter, cusp.second_parameter], five, rtol=0,
                               atol=cusp.accuracy + bound + 1e-9)


def test_a_neutral_saddle_is_told_apart_and_refused():
    """``M^2 - 2 kappa M + I`` is singular for a real pair with product 1 too (``|kappa| > 1``): the condition
    says which, and a curve does not start from a point without a complex pair."""
    from saltation.errors import SaltationError
    from saltation.orbits.conditions.neimark_sacker import nearest_pair_kappa

    assert NeimarkSackerCondition.kind(0.3) == "neimark_sacker" and NeimarkSackerCondition.kind(1.2) == "neutral_saddle"
    theta = 0.7
    M = np.diag([0.5, 0.2, 3.0])
    M[:2, :2] = [[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]]
    condition = NeimarkSackerCondition(np.cos(theta) + 0.05)
    g, dg = condition.values(M, np.cos(theta))
    assert np.max(np.abs(g)) < 1e-14  # exactly singular at kappa = cos theta
    # the derivative by kappa against a central difference
    h = 1e-6
    diff = (condition.values(M, np.cos(theta) + h)[0] - condition.values(M, np.cos(theta) - h)[0]) / (2 * h)
    np.testing.assert_allclose(dg, diff, rtol=0, atol=1e-8)
    saddle = np.diag([2.0, 0.5, 0.1])
    assert np.max(np.abs(NeimarkSackerCondition(1.2).values(saddle, 1.25)[0])) < 1e-14  # (2 + 1/2) / 2
    with pytest.raises(SaltationError, match="no complex pair"):
        nearest_pair_kappa(np.linalg.eigvals(saddle))
    assert nearest_pair_kappa(np.linalg.eigvals(M)) == pytest.approx(np.cos(theta), abs=1e-14)


def test_locus_command_line_for_neimark_sacker(capsys):
    """``saltation locus --kind neimark_sacker``: the same JSON keys as every kind, the codimension-two point
    named."""
    model = f"{trial_model('jeffcott_snubber').__file__}:jeffcott"
    x0 = ",".join(f"{v:.15g}" for v in reference.contact_whirl_state(OMEGA0, *whirls(OMEGA0, MU0)[-1]))
    sets = [a for k, v in (ROTOR | {"mu": MU0}).items() for a in ("--set", f"{k}={v}")]
    status = cli.main(["locus", model, "--kind", "neimark_sacker", "--param", "omega", "--range", "1.25,1.45",
                       "--param2", "mu", "--range2", "-0.43,-0.33", *sets, "--x0", x0, "--json", "--no-progress",
                       "--ds-max", "0.01"])
    out, err = capsys.readouterr()
    assert status == 0, err
    record = json.loads(out)
    assert set(record) == {"model", "kind", "param", "param2", "curves"} and record["kind"] == "neimark_sacker"
    (curve,) = record["curves"]
    assert set(curve) == {"points", "stop_reason", "special_points"}
    (r1,) = curve["special_points"]
    assert r1["name"] == "strong_resonance_1_1" and r1["kind"] == "neimark_sacker -> fold"
    omega, mu = bogdanov_takens()
    assert abs(r1["value"][0] - omega) <= r1["accuracy"] + 1e-8 and abs(r1["value"][1] - mu) <= r1["accuracy"] + 1e-8
