"""The contract between the compiled engine, the model functions and Python, defined once.

Every generated module (the engine of a state dimension, the functions of a
model) starts with this file's text (numba folds its names into constants),
and :mod:`saltation.engine.flow` imports it to read the engine's results: the
status codes, the kinds of events, the outcomes of the engine's Newton
iterations, the layout of the two packed result arrays, and the model
functions the engine calls, with their signatures.  Keep it free of package
imports: it is copied verbatim.
"""

import math as _math
import warnings as _warnings

from numba import types as _t
from numba.core.errors import NumbaExperimentalFeatureWarning as _Experimental

# numba calls first-class function types experimental; the engine is built on them (the model tuple
# below), and tests/test_engine.py holds the engine to the results of the per-model kernels it replaced
_warnings.filterwarnings("ignore", message=".*First-class function type", category=_Experimental)

# Status codes of an integration (saltation.engine.flow.Status).
STATUS_OK = 0
STATUS_MAX_EVENTS = 1
STATUS_CHATTERING = 2
STATUS_STEP_TOO_SMALL = 3
STATUS_NON_FINITE = 4
STATUS_SLIDING_UNDEFINED = 5
STATUS_MAX_STEPS = 6
STATUS_TANGENTIAL = 7
STATUS_OUTSIDE_DOMAIN = 8
STATUS_ACCUMULATION = 9  # (not an error) the impacts of a transition that can stick accumulate: the run stops after
#                          the last one kept, and saltation.engine.flow.Flow.run jumps to their limit (complete chatter)

# Kinds of switching events (saltation.engine.flow.EventKind).
EVENT_TRANSITION = 0
EVENT_SLIDING_START = 1
EVENT_SLIDING_END = 2

# Outcomes of the kernel's Newton iterations (correct_periodic).
SHOOT_CONVERGED = 0
SHOOT_FAILED = 1  # an integration failed, the residual is not finite, or no step reduces it
SHOOT_MAX_ITER = 2
SHOOT_BAD_PERIOD = 3  # a period that is not positive (the caller's own iteration explains it)
SHOOT_SINGULAR = 4  # a Newton matrix with a zero (or not finite) pivot (the caller's own iteration explains it)

# The integer array of an integration's result: status, mode and surface of a failure, number of events,
# steps, rejected steps, final mode, sliding state (SLIDE_WIDTH entries), initial mode; then the event
# log's rows (kind, transition, surface, mode from, mode to).
INFO_STATUS = 0
INFO_FAILED_MODE = 1
INFO_FAILED_SURFACE = 2
INFO_EVENTS = 3
INFO_STEPS = 4
INFO_REJECTED = 5
INFO_FINAL_MODE = 6
INFO_SLIDE = 7
SLIDE_WIDTH = 5
# The first entry of the sliding state: 0 not sliding, 1 sliding. A run stopped with STATUS_SLIDING_UNDEFINED
# during a sliding motion gives the cause there instead (with the motion's modes, surface and crossing after it):
SLIDE_LEAVES_REGION = 2  # it leaves the domain of its mode INFO_FAILED_MODE (across INFO_FAILED_SURFACE, or its own
#                          surface when no other lies there), and no transition out of either mode holds there
SLIDE_BLOCKED = 3  # the transition on INFO_FAILED_SURFACE leads to no motion the integrator defines: the field of
#                    INFO_FAILED_MODE pushes back across that surface, or (mode -1) both new modes leave the sliding surface
SLIDE_RESET_INTO = 4  # (not sliding) the reset of transition INFO_SLIDE + 1 leaves the state on INFO_FAILED_SURFACE
#                       and the new field pushes it back across: no motion is defined
TIME_UNRESOLVED = 5  # (with STATUS_CHATTERING) events closer than the resolution of the time axis at |t|, not of the motion
INFO_INITIAL_MODE = 12
INFO_EVENT_LOG = 13
# The event log's integer columns, then their number (a row per event, after INFO_EVENT_LOG).
LOG_KIND, LOG_TRANSITION, LOG_SURFACE, LOG_MODE_FROM, LOG_MODE_TO = range(5)
EVENT_LOG_INTS = 5
# The rows of DOP853's dense-output coefficients of a step (a step's coefficients are DENSE_ROWS x n floats).
DENSE_ROWS = 7
# The scalar slots of the integrator loop's state (the engine's own: its loop leaves and resumes from them):
# floats (time, proposed step, drift off the surface of a sliding motion just ended, longest step to an event),
SF_T, SF_STEP, SF_DRIFT, SF_H_EVENTS = range(4)
SF_WIDTH = 4
# and integers (booleans as 0 and 1): mode, events, recorded steps, steps, rejected steps, status, failed mode and
# surface, a transition pending at once, kind of the last event, the surface of a sliding motion just ended,
# whether the surfaces' signs need reading, whether the last event jumped, whether at the start.
(SI_MODE, SI_EVENTS, SI_RECORDS, SI_STEPS, SI_REJECTED, SI_STATUS, SI_FAILED_MODE, SI_FAILED_SURFACE, SI_PENDING,
 SI_LAST_KIND, SI_AFTER_SLIDING, SI_NEED_SIGNS, SI_LAST_JUMP, SI_AT_START) = range(14)
SI_WIDTH = 14


def result_offsets(n):
    """Offsets in the float array of an integration's result, for ``n`` states: ``(x, Phi, psi, x_min,
    x_max, f at the end, event log)``. The time at the end comes first; the event log's rows are
    ``(t, x-, x+, S)``; after them the recorded steps and their dense-output coefficients."""
    x = 1
    phi = x + n
    psi = phi + n * n
    x_min = psi + n
    x_max = x_min + n
    velocity = x_max + n
    events = velocity + n
    return x, phi, psi, x_min, x_max, velocity, events


def event_row_offsets(n):
    """Offsets in a row of the event log's floats, for ``n`` states: ``(x-, x+, S, width)``; the event's
    time comes first, ``S`` is row-major, and ``width = 1 + 2 n + n^2`` floats make a row."""
    x_minus = 1
    x_plus = x_minus + n
    saltation = x_plus + n
    return x_minus, x_plus, saltation, saltation + n * n


def step_record_width(n):
    """Floats in a recorded step's row, for ``n`` states: start, size, end fraction, start state (its
    DENSE_ROWS x n dense-output coefficients follow all the rows in the packed result)."""
    return 3 + n


#: impacts of one transition in a row, at least, before their times are extrapolated to their accumulation point
ACCUMULATION_IMPACTS = 6


def accumulation_point(t0, t1, t2, t3, t4, lam):
    """The accumulation point of impact times ``t0 < t1 < ... < t4`` (the last five of a chattering sequence)
    whose intervals shrink by the ratio ``lam`` (``0 < lam < 1``, the restitution the impacts apply to the
    relative velocity), and a bound on its error.

    Near a complete chatter the times are ``t_k = T + sum_j c_j lam^(j k)`` (the relative velocity after
    impact ``k`` is an analytic function of ``lam^k``): Richardson's elimination of the powers ``lam``,
    ``lam^2``, ``lam^3``, ``lam^4`` leaves ``T``; the error is bounded by the difference between the last two
    levels.  Returns ``(T, error)``, the error infinite where the intervals do not shrink (not an
    accumulation).
    """
    d1, d2, d3, d4 = t1 - t0, t2 - t1, t3 - t2, t4 - t3
    if not (lam > 0.0 and lam < 1.0 and d4 > 0.0 and d3 > d4 and d2 > d3 and d1 > d2):
        return t4, _math.inf
    a0 = (t1 - lam * t0) / (1.0 - lam)  # level 1: lam^k eliminated
    a1 = (t2 - lam * t1) / (1.0 - lam)
    a2 = (t3 - lam * t2) / (1.0 - lam)
    a3 = (t4 - lam * t3) / (1.0 - lam)
    q = lam * lam
    b0 = (a1 - q * a0) / (1.0 - q)  # level 2
    b1 = (a2 - q * a1) / (1.0 - q)
    b2 = (a3 - q * a2) / (1.0 - q)
    q = q * lam
    c0 = (b1 - q * b0) / (1.0 - q)  # level 3
    c1 = (b2 - q * b1) / (1.0 - q)
    q = q * lam
    d0 = (c1 - q * c0) / (1.0 - q)  # level 4
    if not d0 > t4:
        return t4, _math.inf
    return d0, abs(d0 - c1)


def newton_layout(m_z, m_u, n_history, bordered):
    """Offsets in the packed result of the engine's Newton (``correct_periodic``): ``(history, jacobian,
    tangent, size)``.  ``z`` (``m_z`` entries) comes first, then the residual norms (``n_history``), then
    ``[r | J_u | J_lam]`` row-major (``m_u`` rows of ``m_u + 2``), then the tangent (``m_z`` entries for
    the ``bordered`` system, none for the period map alone)."""
    history = m_z
    jacobian = history + n_history
    tangent = jacobian + m_u * (m_u + 2)
    return history, jacobian, tangent, tangent + (m_z if bordered else 0)


# The model functions the engine calls, in the order of the model tuple the engine takes (its first
# argument): each compiled with the signature below, so the engine is typed with function types, not
# with the functions, and is compiled once for all models. The tuple ends with AFFINE_MODES, whether
# each mode's field is affine in the state (an array of booleans).
_F1, _F2, _F3 = _t.float64[::1], _t.float64[:, ::1], _t.float64[:, :, ::1]
_I, _R = _t.int64, _t.float64
MODEL_SIGNATURES = {
    "vector_field": _t.void(_I, _R, _F1, _F1, _F1),  # (mode, t, x, p, f)
    "vector_field_jac": _t.void(_I, _R, _F1, _F1, _F2),  # (mode, t, x, p, f_x)
    "vector_field_dp": _t.void(_I, _R, _F1, _F1, _F2),  # (mode, t, x, p, f_p)
    "indicator": _R(_I, _R, _F1, _F1),  # (surface, t, x, p) -> h
    "indicator_grad": _R(_I, _R, _F1, _F1, _F1, _F1),  # (surface, t, x, p, h_x, h_p) -> h_t
    "indicator_rate": _R(_I, _R, _F1, _F1, _F1, _F1, _F1),  # (surface, t, x, f, p, work, work) -> h_t + h_x f
    "lie_derivative": _R(_I, _I, _R, _F1, _F1, _F1, _F1),  # (mode, surface, t, x, p, g_x, g_p) -> h_x f + h_t
    "lie_derivative_dt": _R(_I, _I, _R, _F1, _F1),  # (mode, surface, t, x, p) -> its partial in t
    "reset_map": _t.void(_I, _R, _F1, _F1, _F1),  # (transition, t, x, p, g)
    "reset_jac": _t.void(_I, _R, _F1, _F1, _F2, _F1, _F2),  # (transition, t, x, p, g_x, g_t, g_p)
    "affine_parts": _t.void(_I, _F1, _F2, _F2, _F1),  # (mode, p, A, B, (omega, phase))
    "affine_parts_dp": _t.void(_I, _F1, _F3, _F3, _F2),  # (mode, p, dA/dp, dB/dp, d(omega, phase)/dp)
    "guard": _t.boolean(_I, _R, _F1, _F1),  # (transition, t, x, p)
    "in_domain": _t.boolean(_I, _R, _F1, _F1),  # (mode, t, x, p)
    "domain_margin": _R(_I, _R, _F1, _F1),  # (mode, t, x, p) -> smallest condition value
    "initial_mode": _I(_R, _F1, _F1),  # (t, x, p) -> first mode whose domain holds, or -1
    "forcing_period": _R(_F1),  # (p) -> T (0: autonomous)
    "forcing_period_dp": _R(_F1, _I),  # (p, k) -> dT/dp_k
}
MODEL_FUNCTIONS = tuple(MODEL_SIGNATURES)
INTEGRATOR_ROW = len(MODEL_FUNCTIONS)  # the engine's addresses: the model's functions, then the integrator
# then the integrator's loop and the two helpers it calls through their addresses (see the engine)
STEPS_ROW, SURFACE_STEP_ROW, SLIDING_EVENTS_ROW = INTEGRATOR_ROW + 1, INTEGRATOR_ROW + 2, INTEGRATOR_ROW + 3
(VECTOR_FIELD, VECTOR_FIELD_JAC, VECTOR_FIELD_DP, INDICATOR, INDICATOR_GRAD, INDICATOR_RATE, LIE_DERIVATIVE,
 LIE_DERIVATIVE_DT, RESET_MAP, RESET_JAC, AFFINE_PARTS, AFFINE_PARTS_DP, GUARD, IN_DOMAIN, DOMAIN_MARGIN,
 INITIAL_MODE, FORCING_PERIOD, FORCING_PERIOD_DP, AFFINE_MODES) = range(len(MODEL_FUNCTIONS) + 1)
MODEL_TYPE = _t.Tuple(tuple(_t.FunctionType(sig) for sig in MODEL_SIGNATURES.values()) + (_t.boolean[::1],))
