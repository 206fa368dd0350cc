"""Saltation matrices of the paper models: closed forms (eqs. 9, 11-14, 19-20) vs the library.

Every expected matrix here is derived by hand from eq. (9),
``S = I + (f+ - f-) n^T / (n^T f-)`` (no indicator depends on time), with the
vector fields typed in again from eqs. (1)-(3) and (15)-(17); the library's
``PiecewiseSystem.saltation_matrix`` is never used to build an expectation.

Symbols: ``w = sqrt(k/m)``; on the band edges ``a+ = (-k x - c (v_dr + eta) - F_slip)/m``
and ``a- = (-k x - c (v_dr - eta) + F_slip)/m`` are the slip accelerations;
``dF = F_stick - F_slip``.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from saltation import EventKind
from saltation.models import WRegion, block_on_belt, trilinear

R = dict(real=True)
x, v, t = sp.symbols("x v t", **R)
m, c, k, x_c, k_f, c_f, f0, omega = sp.symbols("m c k x_c k_f c_f f0 omega", **R)
v_dr, F_slip, F_stick, eta = sp.symbols("v_dr F_slip F_stick eta", **R)
X = sp.Matrix([x, v])
I2 = sp.eye(2)
W = sp.sqrt(k / m)


def eq9(f_minus: sp.Matrix, f_plus: sp.Matrix, h: sp.Expr) -> sp.Matrix:
    """Eq. (9) of the paper for a time-independent indicator, written out here."""
    n = sp.Matrix([h]).jacobian(X).T
    return I2 + (f_plus - f_minus) * n.T / (n.T * f_minus)[0, 0]


# ---------------------------------------------------------------- trilinear, eqs. (1)-(7)
FORCE = f0 * sp.sin(omega * t)
TRI_FIELDS = {
    "free": sp.Matrix([v, (-c * v - k * x + FORCE) / m]),
    "contact_1": sp.Matrix([v, (-(c + c_f) * v - k * x - k_f * (x - x_c) + FORCE) / m]),
    "contact_2": sp.Matrix([v, (-(c + c_f) * v - k * x - k_f * (x + x_c) + FORCE) / m]),
}
TRI_SURFACES = {"h1a": x - x_c, "h1b": k_f * (x - x_c) + c_f * v, "h2a": x + x_c, "h2b": k_f * (x + x_c) + c_f * v}

S_1a = sp.Matrix([[1, 0], [-c_f / m, 1]])  # eq. (11) = eq. (13)
#: hand-simplified closed forms, by (source, surface, target).  Contact is made through
#: h_ia (eqs. 11, 13) and lost through h_ib (eqs. 12, 14); backward time crosses the same
#: surfaces the other way: through h_ia out of contact (the inverse of S_ia), through h_ib into it.
TRI_CLOSED = {
    ("free", "h1a", "contact_1"): S_1a,
    ("contact_1", "h1b", "free"): I2,
    ("free", "h2a", "contact_2"): S_1a,
    ("contact_2", "h2b", "free"): I2,
    ("contact_1", "h1a", "free"): sp.Matrix([[1, 0], [c_f / m, 1]]),
    ("free", "h1b", "contact_1"): I2,
    ("contact_2", "h2a", "free"): sp.Matrix([[1, 0], [c_f / m, 1]]),
    ("free", "h2b", "contact_2"): I2,
}

# ---------------------------------------------------------------- block on belt, eqs. (15)-(17)
BELT_FIELDS = {
    "stick": sp.Matrix([v_dr, -(v - v_dr) * W]),
    "slip_plus": sp.Matrix([v, (-k * x - c * v - F_slip) / m]),
    "slip_minus": sp.Matrix([v, (-k * x - c * v + F_slip) / m]),
    # region W with its own field (WRegion.STICK_FRICTION)
    "w_plus": sp.Matrix([v, (-k * x - c * v + F_stick) / m]),
    "w_minus": sp.Matrix([v, (-k * x - c * v - F_stick) / m]),
}
BELT_SURFACES = {
    "band_upper": v - v_dr - eta,
    "band_lower": v - v_dr + eta,
    "stick_upper": k * x + c * v - F_stick,
    "stick_lower": k * x + c * v + F_stick,
    "v_rel": v - v_dr,
}
A_PLUS = (-k * x - c * (v_dr + eta) - F_slip) / m
A_MINUS = (-k * x - c * (v_dr - eta) + F_slip) / m
DF = F_stick - F_slip


def _stick_to_slip(sign_surface: int, slip_force: sp.Expr) -> sp.Matrix:
    """Stick -> slip through k x + c v = sign_surface * F_stick, by hand from eq. (9)."""
    n = sp.Matrix([k, c])
    jump = sp.Matrix([v - v_dr, (-sign_surface * F_stick + slip_force) / m + (v - v_dr) * W])
    return I2 + jump * n.T / (k * v_dr - c * (v - v_dr) * W)


BELT_CLOSED = {
    ("slip_plus", "band_upper", "stick"): sp.Matrix([[1, -eta / A_PLUS], [0, -eta * W / A_PLUS]]),
    ("slip_minus", "band_lower", "stick"): sp.Matrix([[1, eta / A_MINUS], [0, eta * W / A_MINUS]]),
    ("stick", "band_upper", "slip_plus"): sp.Matrix([[1, -1 / W], [0, -A_PLUS / (eta * W)]]),
    ("stick", "band_lower", "slip_minus"): sp.Matrix([[1, -1 / W], [0, A_MINUS / (eta * W)]]),
    ("slip_plus", "v_rel", "slip_minus"): sp.Matrix(
        [[1, 0], [0, (-k * x - c * v_dr + F_slip) / (-k * x - c * v_dr - F_slip)]]
    ),
    ("slip_minus", "v_rel", "slip_plus"): sp.Matrix(
        [[1, 0], [0, (-k * x - c * v_dr - F_slip) / (-k * x - c * v_dr + F_slip)]]
    ),
    ("stick", "stick_upper", "slip_plus"): _stick_to_slip(+1, -F_slip),
    ("stick", "stick_upper", "slip_minus"): _stick_to_slip(+1, +F_slip),
    ("stick", "stick_lower", "slip_plus"): _stick_to_slip(-1, -F_slip),
    ("stick", "stick_lower", "slip_minus"): _stick_to_slip(-1, +F_slip),
}

#: eq. (19), and eq. (20) corrected as in NOTES.md (the printed form is its c = 0 case)
S_ALPHA = sp.Matrix([[1, 0], [0, 0]])
S_BETA = sp.Matrix([[1, 0], [-DF / (m * v_dr), 1 - c * DF / (k * m * v_dr)]])
S_BETA_PRINTED = sp.Matrix([[1, 0], [-DF / (m * v_dr), 1]])


def _on_surface_points(h: sp.Expr, rng: np.random.Generator, params: list[sp.Symbol], count: int = 4):
    """Random substitutions (parameters, then a state on ``h = 0``)."""
    free_state = v if h.has(x) else x
    solved_state = x if h.has(x) else v
    (root,) = sp.solve(sp.Eq(h, 0), solved_state)
    for _ in range(count):
        subs = {s: float(rng.uniform(0.3, 2.0)) for s in params}
        if eta in subs:
            subs[eta] = float(rng.uniform(1e-3, 5e-2))
        subs[t] = float(rng.uniform(0, 6))
        subs[free_state] = float(rng.uniform(-1.5, 2.5))
        subs[solved_state] = float(root.subs(subs))
        yield subs


def _compare_on_surface(S_lib: sp.Matrix, S_ref: sp.Matrix, h: sp.Expr, params, rng):
    symbols = [x, v, t, *params]
    f_lib = sp.lambdify(symbols, S_lib, "numpy")
    f_ref = sp.lambdify(symbols, S_ref, "numpy")
    checked = 0
    for subs in _on_surface_points(h, rng, params):
        args = [subs[s] for s in symbols]
        with np.errstate(all="ignore"):
            a = np.array(f_lib(*args), dtype=float)
            b = np.array(f_ref(*args), dtype=float)
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
            continue
        np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-11)
        checked += 1
    assert checked >= 2


_SALTATION_CACHE: dict[tuple[str, int], sp.Matrix] = {}


def _library_saltation(system, index: int) -> sp.Matrix:
    """``system.saltation_matrix(index)``, computed once per model (sympy's simplify is slow)."""
    key = (system.fingerprint, index)
    if key not in _SALTATION_CACHE:
        _SALTATION_CACHE[key] = system.saltation_matrix(index)
    return _SALTATION_CACHE[key]


def _lookup(system, source, surface, target) -> int:
    for idx, tr in enumerate(system.transitions):
        if (tr.source, tr.surface, tr.target) == (source, surface, target):
            return idx
    raise LookupError((source, surface, target))


@pytest.fixture(scope="module")
def tri_system():
    return trilinear()


@pytest.fixture(scope="module")
def belt_system():
    return block_on_belt()


# ------------------------------------------------------------------ symbolic, trilinear
TRI_PARAMS = [m, c, k, x_c, k_f, c_f, f0, omega]


@pytest.mark.parametrize("key", list(TRI_CLOSED), ids=lambda k: "-".join(k))
def test_trilinear_saltation_closed_form(tri_system, key):
    S_lib = _library_saltation(tri_system, _lookup(tri_system, *key))
    # the paper's matrices are constant: the library must give them exactly
    assert sp.simplify(S_lib - TRI_CLOSED[key]) == sp.zeros(2, 2), S_lib
    # and eq. (9) applied to the fields typed in above agrees on the surface
    source, surface, target = key
    S_eq9 = eq9(TRI_FIELDS[source], TRI_FIELDS[target], TRI_SURFACES[surface])
    _compare_on_surface(S_eq9, TRI_CLOSED[key], TRI_SURFACES[surface], TRI_PARAMS, np.random.default_rng(1))


def test_trilinear_every_transition_has_a_closed_form(tri_system):
    keys = {(tr.source, tr.surface, tr.target) for tr in tri_system.transitions}
    assert keys == set(TRI_CLOSED)


def test_trilinear_corner_matrices_are_not_inverse(tri_system):
    """S_1a != S_1b^{-1}: the corner of Sigma_1 that makes the fold discontinuous."""
    S1a = _library_saltation(tri_system, _lookup(tri_system, "free", "h1a", "contact_1"))
    S1b = _library_saltation(tri_system, _lookup(tri_system, "contact_1", "h1b", "free"))
    assert sp.simplify(S1a * S1b - I2) != sp.zeros(2, 2)
    assert sp.simplify((S1a * S1b - I2).subs(c_f, 0)) == sp.zeros(2, 2)


# ------------------------------------------------------------------ symbolic, block on belt
BELT_PARAMS = [m, c, k, v_dr, F_slip, F_stick, eta]


@pytest.mark.parametrize("key", list(BELT_CLOSED), ids=lambda k: "-".join(k))
def test_belt_saltation_closed_form(belt_system, key):
    source, surface, target = key
    h = BELT_SURFACES[surface]
    S_lib = _library_saltation(belt_system, _lookup(belt_system, *key))
    rng = np.random.default_rng(2)
    _compare_on_surface(S_lib, BELT_CLOSED[key], h, BELT_PARAMS, rng)
    _compare_on_surface(eq9(BELT_FIELDS[source], BELT_FIELDS[target], h), BELT_CLOSED[key], h, BELT_PARAMS, rng)


@pytest.mark.parametrize(
    "w_region", [WRegion.SLIP, WRegion.STICK_FRICTION], ids=lambda w: w.value
)
def test_belt_every_transition_matches_eq9(w_region):
    """All transitions of both variants of the switch model, against eq. (9) on the hand-typed fields."""
    system = block_on_belt(w_region)
    rng = np.random.default_rng(3)
    for idx, tr in enumerate(system.transitions):
        h = BELT_SURFACES[tr.surface]
        S_ref = eq9(BELT_FIELDS[tr.source], BELT_FIELDS[tr.target], h)
        _compare_on_surface(_library_saltation(system, idx), S_ref, h, BELT_PARAMS, rng)


def test_slip_to_stick_tends_to_S_alpha(belt_system):
    """Eq. (19): the slip -> stick matrices tend to [[1, 0], [0, 0]] as eta -> 0."""
    for key in [("slip_minus", "band_lower", "stick"), ("slip_plus", "band_upper", "stick")]:
        S = _library_saltation(belt_system, _lookup(belt_system, *key))
        limit = S.applyfunc(lambda e: sp.limit(e, eta, 0))
        assert sp.simplify(limit - S_ALPHA) == sp.zeros(2, 2), (key, limit)
        # singular for every eta: det S = 0 only in the limit, det = eta w / a otherwise
        assert sp.simplify(S.det().subs(eta, 0)) == 0


def test_stick_to_slip_is_corrected_S_beta(belt_system):
    """Eq. (20) as corrected in NOTES.md; the printed form holds for c = 0 only."""
    S = _library_saltation(belt_system, _lookup(belt_system, "stick", "stick_upper", "slip_minus"))
    at_belt_speed = sp.simplify(S.subs(v, v_dr))  # eta -> 0: the stick state moves with the belt
    assert sp.simplify(at_belt_speed - S_BETA) == sp.zeros(2, 2), at_belt_speed
    assert sp.simplify(at_belt_speed - S_BETA_PRINTED) != sp.zeros(2, 2)
    assert sp.simplify((at_belt_speed - S_BETA_PRINTED).subs(c, 0)) == sp.zeros(2, 2)
    # S_alpha S_beta != I (the corner at the fold)
    assert sp.simplify(S_ALPHA * S_BETA - I2) != sp.zeros(2, 2)


# ------------------------------------------------------------------ numerical, at real events
def _numeric(S: sp.Matrix, values: dict) -> np.ndarray:
    return np.array(S.subs(values).evalf(), dtype=float)


def test_trilinear_event_saltation_forward(contact_orbit):
    events = contact_orbit.trajectory.events
    assert [e.surface for e in events] == ["h1a", "h1b", "h2a", "h2b"]
    pv = _param_values("trilinear", contact_orbit.parameters)
    for e in events:
        expected = _numeric(TRI_CLOSED[(e.mode_from, e.surface, e.mode_to)], pv)
        np.testing.assert_allclose(e.saltation, expected, rtol=0, atol=1e-12, err_msg=e.surface)


def test_trilinear_event_saltation_backward(trilinear_flow, contact_orbit):
    """Backward time from T to 0: out of contact through h_ia (S_ia^-1), into contact through h_ib (I)."""
    T = contact_orbit.period
    back = trilinear_flow.run(contact_orbit.state0, T, 0.0, contact_orbit.parameters)
    assert [(e.mode_from, e.surface, e.mode_to) for e in back.events] == [
        ("free", "h2b", "contact_2"),
        ("contact_2", "h2a", "free"),
        ("free", "h1b", "contact_1"),
        ("contact_1", "h1a", "free"),
    ]
    pv = _param_values("trilinear", contact_orbit.parameters)
    for e in back.events:
        expected = _numeric(TRI_CLOSED[(e.mode_from, e.surface, e.mode_to)], pv)
        np.testing.assert_allclose(e.saltation, expected, rtol=0, atol=1e-12, err_msg=e.surface)


def _param_values(system_name: str, params: np.ndarray) -> dict:
    """Substitutions for the parameter symbols, matched by name (not by position)."""
    names = (trilinear() if system_name == "trilinear" else block_on_belt()).parameter_names
    return {sp.Symbol(name, real=True): float(val) for name, val in zip(names, params)}


def _belt_values(params: np.ndarray, state: np.ndarray) -> dict:
    return _param_values("block_on_belt", params) | {x: state[0], v: state[1]}


def test_stick_slip_event_saltation(stable_cycle):
    """The stable cycle's two events against the eta-exact forms and eqs. (19), (20) up to O(eta)."""
    events = stable_cycle.trajectory.events
    assert [(e.mode_from, e.surface, e.mode_to) for e in events] == [
        ("slip_minus", "band_lower", "stick"),
        ("stick", "stick_upper", "slip_minus"),
    ]
    p = stable_cycle.parameters
    pv = _param_values("block_on_belt", p)
    eta_value = pv[eta]
    alpha, beta = events
    # slip -> stick: eta-exact closed form at the event state, and eq. (19) up to O(eta)
    np.testing.assert_allclose(
        alpha.saltation, _numeric(BELT_CLOSED[("slip_minus", "band_lower", "stick")], _belt_values(p, alpha.x_minus)),
        rtol=1e-12, atol=1e-14,
    )
    assert abs(alpha.saltation[0, 1]) > 0.1 * eta_value  # O(eta), not zero: eta is finite
    np.testing.assert_allclose(alpha.saltation, np.array(S_ALPHA, dtype=float), rtol=0, atol=10 * eta_value)
    # stick -> slip: eta-exact closed form, the corrected eq. (20) up to O(eta), not the printed one
    np.testing.assert_allclose(
        beta.saltation, _numeric(BELT_CLOSED[("stick", "stick_upper", "slip_minus")], _belt_values(p, beta.x_minus)),
        rtol=1e-12, atol=1e-14,
    )
    np.testing.assert_allclose(beta.saltation, _numeric(S_BETA, pv), rtol=0, atol=10 * eta_value)
    assert beta.saltation[1, 1] == pytest.approx(0.9, abs=10 * eta_value)  # 1 - c dF/(k m v_dr), c = 0.1


def test_stick_to_slip_event_without_damping_is_printed_eq20(belt_flow):
    """With c = 0 (a parameter value, no recompilation) eq. (20) holds as printed."""
    p = belt_flow.parameters({"c": 0.0})
    traj = belt_flow.run([0.0, 1.0], 0.0, 15.0, p)  # starts sticking
    betas = [e for e in traj.events if (e.mode_from, e.surface) == ("stick", "stick_upper")]
    assert betas
    pv = _param_values("block_on_belt", p)
    expected = _numeric(S_BETA_PRINTED, pv)
    for e in betas:
        np.testing.assert_allclose(e.saltation, expected, rtol=0, atol=10 * pv[eta])
        np.testing.assert_allclose(
            e.saltation, _numeric(BELT_CLOSED[("stick", "stick_upper", "slip_minus")], _belt_values(p, e.x_minus)),
            rtol=1e-12, atol=1e-14,
        )


def test_unstable_cycle_sliding_start_is_singular(unstable_cycle):
    """Backward time, V -> D: the attraction sliding mode's saltation matrix is singular."""
    starts = [e for e in unstable_cycle.trajectory.events if e.kind == EventKind.SLIDING_START]
    assert len(starts) == 1
    e = starts[0]
    assert e.surface == "band_lower"
    p = unstable_cycle.parameters
    vals = _belt_values(p, e.x_minus)
    # by hand: S = I + (f_s - f_a) n^T / (n^T f_a), n = [0, 1], f_a = slip_minus, f_b = stick,
    # f_s = f_a + alpha (f_b - f_a), alpha = s_a / (s_a - s_b), s = n^T f
    s_a = float(A_MINUS.subs(vals))
    s_b = float((eta * W).subs(vals))
    alpha = s_a / (s_a - s_b)
    eta_value = vals[eta]
    expected = np.array([[1.0, alpha * eta_value / s_a], [0.0, 0.0]])
    np.testing.assert_allclose(e.saltation, expected, rtol=1e-12, atol=1e-14)
    assert abs(np.linalg.det(e.saltation)) < 1e-14


@pytest.mark.parametrize("make", [trilinear, block_on_belt])
def test_the_fast_closed_form_is_the_same_function(make):
    """``simplify=False`` (cancelled fractions, what corners evaluate) and sympy's simplify give the same
    saltation matrices, on the surface, at random states and times (eliminating x on the surface)."""
    system = make()
    rng = np.random.default_rng(5)
    p = [system.defaults[name] for name in system.parameter_names]
    for k in range(len(system.transitions)):
        slow = sp.lambdify((system.t, list(system.x), list(system.p)), _library_saltation(system, k))
        fast = sp.lambdify((system.t, list(system.x), list(system.p)), system.saltation_matrix(k, simplify=False))
        for _ in range(4):
            t, x = rng.uniform(0, 5), rng.uniform(-2, 2, system.n)
            a, b = np.array(slow(t, list(x), p), float), np.array(fast(t, list(x), p), float)
            np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)
