"""The compiled event-driven integrator: the engine (source template).

This file is not imported as a module.  :mod:`saltation.engine.codegen` writes it
into the kernel cache after the contract (``_contract.py``), the state
dimension ``N_STATE`` and the Dormand-Prince 8(5,3) tableau (``RK_A``,
``RK_B``, ``RK_C``, ``RK_E3``, ``RK_E5``, ``RK_D``), and numba compiles it
once per machine and caches it on disk.  Nothing in it belongs to a model:
the model's compiled functions arrive as the first argument of every
function that calls them, a tuple typed by the signatures of the contract
(``MODEL_TYPE``: first-class functions), so a new model compiles only its own
small functions.  ``N_STATE`` is a compile-time constant in the engines of
small state dimensions (``n = N_STATE or x.shape[0]`` folds to a constant and
loops over the state have a known length) and 0 in the engine of any
dimension, where ``n`` comes from the arrays.

The integrator (see ``docs/algorithms.md``):

* takes DOP853 steps of the augmented system ``x' = f``, ``Phi' = f_x Phi``,
  ``psi' = f_x psi + f_p[:, k]`` with the error controlled on ``x``
  (``_rk_step``), or exact steps of affine modes (``_exact_step``);
* watches the indicators of the surfaces of the current mode's transitions,
  including indicators that dip through zero and back within one step
  (a golden-section search on the dense output when the indicator's slope
  reverses, ``_dip_search``), locates each crossing by bracketing on the dense
  output (``_bracket_root``) and refines it by re-stepping from the step start
  to near machine precision;
* applies the transition (reset, new mode) and jumps ``Phi`` by the saltation
  matrix ``S = g_x + (f+ - g_x f- - g_t) h_x / (h_x f- + h_t)`` (eq. 9 with
  resets), ``psi`` by the parameter column of the same formula, in one place:
  ``_saltation_jump``;
* slides (Filippov) when the new field pushes back into the surface, and
  leaves the sliding motion where either field turns tangent
  (``_sliding_exit_event``), or where it crosses another surface on which a
  transition out of either of its modes holds (``_sliding_match``,
  ``_sliding_transition``); a sliding motion that leaves the domain of one
  of its modes where no transition holds stops the run
  (``_sliding_region_margin``).
"""

import math

import numpy as np
from numba import njit
from numba import types as nt
from numba.core import cgutils
from numba.extending import intrinsic

from saltation.engine._records import (
    Affine,
    Arrays,
    Flags,
    Gradients,
    Log,
    LoopState,
    Matrices,
    Settings,
    Surfaces,
    Taylor,
    Vectors,
    Work,
)

# The status codes (STATUS_*), event kinds (EVENT_*), Newton outcomes (SHOOT_*), the layout of the
# packed results (INFO_*, result_offsets) and of the model tuple (VECTOR_FIELD, ..., MODEL_TYPE) come
# from saltation/_contract.py, whose text the engine's module starts with; the offsets are compiled
# here for the engine's own use.
if False:  # never runs: these names come from saltation/_contract.py, which the generated module starts with
    from saltation.engine._contract import (
        ACCUMULATION_IMPACTS,
        AFFINE_MODES,
        AFFINE_PARTS,
        AFFINE_PARTS_DP,
        DENSE_ROWS,
        DOMAIN_MARGIN,
        EVENT_LOG_INTS,
        EVENT_SLIDING_END,
        EVENT_SLIDING_START,
        EVENT_TRANSITION,
        FORCING_PERIOD,
        FORCING_PERIOD_DP,
        GUARD,
        IN_DOMAIN,
        INDICATOR,
        INDICATOR_GRAD,
        INDICATOR_RATE,
        INFO_EVENT_LOG,
        INFO_EVENTS,
        INFO_FAILED_MODE,
        INFO_FAILED_SURFACE,
        INFO_FINAL_MODE,
        INFO_INITIAL_MODE,
        INFO_REJECTED,
        INFO_SLIDE,
        INFO_STATUS,
        INFO_STEPS,
        INITIAL_MODE,
        INTEGRATOR_ROW,
        LIE_DERIVATIVE,
        LIE_DERIVATIVE_DT,
        LOG_KIND,
        LOG_MODE_FROM,
        LOG_MODE_TO,
        LOG_SURFACE,
        LOG_TRANSITION,
        MODEL_TYPE,
        RESET_JAC,
        RESET_MAP,
        SF_DRIFT,
        SF_H_EVENTS,
        SF_STEP,
        SF_T,
        SF_WIDTH,
        SHOOT_BAD_PERIOD,
        SHOOT_CONVERGED,
        SHOOT_FAILED,
        SHOOT_MAX_ITER,
        SHOOT_SINGULAR,
        SI_AFTER_SLIDING,
        SI_AT_START,
        SI_EVENTS,
        SI_FAILED_MODE,
        SI_FAILED_SURFACE,
        SI_LAST_JUMP,
        SI_LAST_KIND,
        SI_MODE,
        SI_NEED_SIGNS,
        SI_PENDING,
        SI_RECORDS,
        SI_REJECTED,
        SI_STATUS,
        SI_STEPS,
        SI_WIDTH,
        SLIDE_BLOCKED,
        SLIDE_LEAVES_REGION,
        SLIDE_RESET_INTO,
        SLIDE_WIDTH,
        SLIDING_EVENTS_ROW,
        STATUS_ACCUMULATION,
        STATUS_CHATTERING,
        STATUS_MAX_EVENTS,
        STATUS_MAX_STEPS,
        STATUS_NON_FINITE,
        STATUS_OK,
        STATUS_OUTSIDE_DOMAIN,
        STATUS_SLIDING_UNDEFINED,
        STATUS_STEP_TOO_SMALL,
        STATUS_TANGENTIAL,
        STEPS_ROW,
        SURFACE_STEP_ROW,
        TIME_UNRESOLVED,
        VECTOR_FIELD,
        VECTOR_FIELD_DP,
        VECTOR_FIELD_JAC,
        accumulation_point,
        event_row_offsets,
        newton_layout,
        result_offsets,
        step_record_width,
    )
    N_STATE = 0  # the state dimension, or 0 (see above): from the engine's header
result_offsets_c = njit(cache=True, inline="always")(result_offsets)
event_row_offsets_c = njit(cache=True, inline="always")(event_row_offsets)
step_record_width_c = njit(cache=True, inline="always")(step_record_width)
newton_layout_c = njit(cache=True, inline="always")(newton_layout)
accumulation_point_c = njit(cache=True, inline="always")(accumulation_point)

# The signatures of the engine's two entry points, compiled when the engine is imported: the model (see
# ``model_from_addresses``), then the arguments as :mod:`saltation.engine.flow` passes them (C-contiguous
# float arrays, int64, bool).
_R, _I, _B = nt.float64, nt.int64, nt.boolean
_V, _M, _T = nt.float64[::1], nt.float64[:, ::1], nt.int64[:, ::1]
_A = (nt.int64[:, ::1], nt.boolean[::1])  # the model: addresses of its functions, affine-mode flags
INTEGRATE_SIGNATURE = (*_A, _R, _R, _V, _I, _V, _B, _I, _R, _R, _R, _R, _I, _I, _T, _I, _B, _M, _V, _B, _B)
INTEGRATE_RESULT = nt.Tuple((nt.int64[::1], nt.float64[::1]))  # (ints, floats): see ``_pack_result``
# ``correct_periodic`` calls the integrator through its address (the row INTEGRATOR_ROW of ``addresses``,
# after the model's functions), as a first-class function: it neither links nor compiles the integrator,
# so the two entry points compile side by side, each in its own process, on a cold cache.
INTEGRATOR_TYPE = nt.FunctionType(INTEGRATE_RESULT(*INTEGRATE_SIGNATURE))
CORRECT_SIGNATURE = (*_A, _V, _V, _R, _R, _B, _I, _R, _V, _V, _V, _R, _I, _R, _B, _R, _R, _R, _I, _I, _T, _I, _M, _V, _B,
                     _B)
# The step-and-event loop and the two largest helpers it calls are compiled on their own too (see
# ``saltation.engine.codegen.ENTRY_POINTS``) and called through their addresses (the rows STEPS_ROW,
# SURFACE_STEP_ROW and SLIDING_EVENTS_ROW of ``addresses``, after the integrator's): a direct call links
# the callee into its caller's library and optimizes it there again, and keeps both in one process on a
# cold cache, where these compile side by side.
_F3, _VI, _VB = nt.float64[:, :, ::1], nt.int64[::1], nt.boolean[::1]
SURFACE_STEP_SIGNATURE = (MODEL_TYPE, _B, _I, _VI, _I, _R, _R, _V, _V, _R, _M, _M, _V, _M, _F3, _M, _M, _M, _V, _V, _V, _V,
                          _V, _R, _VI, _V, _V, _V, _V, _V, _V, _VB, _B)
SURFACE_STEP_TYPE = nt.FunctionType(nt.Tuple((_B, _R, _R, _R, _R, _B, _B))(*SURFACE_STEP_SIGNATURE))
SLIDING_EVENTS_SIGNATURE = (MODEL_TYPE, SURFACE_STEP_TYPE, _B, _I, _VI, _R, _R, _V, _V, _R, _M, _M, _V, _M, _F3, _M, _M,
                            _M, _V, _V, _V, _V, _V, _V, _V, _V, _V, _R, _T, _VB, _VI, _V, _V, _V, _V, _V, _V, _VB)
SLIDING_EVENTS_TYPE = nt.FunctionType(
    nt.Tuple((_R, _I, _I, _I, _I, _R, _R, _R, _B, _B, _R, _I, _I))(*SLIDING_EVENTS_SIGNATURE))

# The step-and-event loop takes its arrays and settings in named records (saltation/engine/_records.py, one
# class each per process), built once by integrate_kernel.
def _record_type(cls, *types):
    """The numba type of a record ``cls`` of fields of ``types`` (as numba types one built in compiled code)."""
    return nt.BaseTuple.from_types(types, cls)


SETTINGS_TYPE = _record_type(Settings, _B, _R, _V, _B, _I, _R, _R, _R, _I, _I, _T, _I, _B, _I, _R, _R)
ARRAYS_TYPE = _record_type(
    Arrays, _record_type(Vectors, *(_V,) * 17), _record_type(Matrices, *(_M,) * 7),
    _record_type(Work, _M, _F3, _M, _M), _record_type(Affine, _F3, _F3, _M, _F3, _F3), _record_type(Taylor, _M, _F3, _M),
    _record_type(Gradients, *(_V,) * 4), _record_type(Surfaces, *(_V,) * 6), _record_type(Flags, *(_VB,) * 3))
LOG_TYPE = _record_type(Log, _M, _T, _M, _F3)
LOOP_STATE_TYPE = _record_type(LoopState, _V, _VI, _VI, _VI)
STEPS_SIGNATURE = (MODEL_TYPE, SURFACE_STEP_TYPE, SLIDING_EVENTS_TYPE, SETTINGS_TYPE, ARRAYS_TYPE, LOG_TYPE,
                   LOOP_STATE_TYPE)
STEPS_TYPE = nt.FunctionType(_B(*STEPS_SIGNATURE))



@intrinsic
def _function_at(typingctx, function_type, c_address, jit_address):
    """A first-class function value of type ``function_type`` (a ``FunctionType``, given as a global)
    from the addresses of a compiled function's C wrapper and numba entry point, as numba builds one
    when it unboxes a dispatcher (``numba.experimental.function_type``): calls go to the numba entry
    point, with numba's calling convention."""
    fnty = function_type.instance_type

    def codegen(context, builder, signature, args):
        value = cgutils.create_struct_proxy(fnty)(context, builder)
        pointer = context.get_value_type(nt.voidptr)
        value.c_addr = builder.inttoptr(args[1], pointer)
        value.py_addr = cgutils.get_null_value(pointer)
        value.jit_addr = builder.inttoptr(args[2], pointer)
        return value._getvalue()

    return fnty(function_type, nt.int64, nt.int64), codegen


EPS = 2.220446049250313e-16
CHATTER_WINDOW = 20
SLIDING_EXIT_SAMPLES = 8  # samples of the sliding-exit functions inside a sliding step (see the event search)
DOMAIN_TOLERANCE = 1e-8  # relative: a state beyond its mode's domain by more is an error of the model
SIDE_NUDGE = 1e-10  # relative: how far off its surface a sliding state is moved to take one side's guards and domain

# event kinds (0: an indicator; 1, 2: a sliding motion's exit on side a, b) and "none", as typed
# integers: a literal int argument would make numba compile the callee once more for it
KIND_INDICATOR = np.int64(0)
NONE = np.int64(-1)
#: bits of a surface's ``fires`` flags: its crossing has been taken at the current instant and no motion has
#: turned back across it since (see _exit_at_once), and the side that crossing left the state on (set: positive)
FIRED_NOW = np.int64(16)
FIRED_POSITIVE = np.int64(32)
FIRED_BITS = np.int64(48)
# the same for flags passed to the integrator from compiled code (a literal True is a type of its own)
ON = np.bool_(True)
OFF = np.bool_(False)


@njit(cache=True, inline="always")  # inlined: array arguments cost more than the work
def _field(model, mode, slide, t, x, p, var, pidx, f, J, fpc, ws1, ws2, ws3, wsJ1, wsJ2, wsP, gA, gB, gpA, gpB):
    """Vector field (and Jacobian and parameter column) of a mode or a sliding motion.

    ``slide = (active, mode_a, mode_b, surface, crossing, time direction)``; the sliding field
    is Filippov's ``f_a + alpha (f_b - f_a)`` with ``alpha = s_a / (s_a - s_b)``,
    ``s_m = h_x f_m + h_t``.
    """
    n = N_STATE or x.shape[0]
    if slide[0] == 0:
        model[VECTOR_FIELD](mode, t, x, p, f)
        if var:
            model[VECTOR_FIELD_JAC](mode, t, x, p, J)
            if pidx >= 0:
                model[VECTOR_FIELD_DP](mode, t, x, p, wsP)
                for i in range(n):
                    fpc[i] = wsP[i, pidx]
        return
    ma = slide[1]
    mb = slide[2]
    surf = slide[3]
    model[VECTOR_FIELD](ma, t, x, p, ws1)
    model[VECTOR_FIELD](mb, t, x, p, ws2)
    sa = model[LIE_DERIVATIVE](ma, surf, t, x, p, gA, gpA)
    sb = model[LIE_DERIVATIVE](mb, surf, t, x, p, gB, gpB)
    d = sa - sb
    alpha = sa / d
    for i in range(n):
        f[i] = ws1[i] + alpha * (ws2[i] - ws1[i])
    if var:
        model[VECTOR_FIELD_JAC](ma, t, x, p, wsJ1)
        model[VECTOR_FIELD_JAC](mb, t, x, p, wsJ2)
        d2 = d * d
        for j in range(n):
            ws3[j] = (sa * gB[j] - sb * gA[j]) / d2
        for i in range(n):
            df = ws2[i] - ws1[i]
            for j in range(n):
                J[i, j] = wsJ1[i, j] + alpha * (wsJ2[i, j] - wsJ1[i, j]) + df * ws3[j]
        if pidx >= 0:
            dalpha = (sa * gpB[pidx] - sb * gpA[pidx]) / d2
            model[VECTOR_FIELD_DP](ma, t, x, p, wsP)
            for i in range(n):
                fpc[i] = wsP[i, pidx] * (1.0 - alpha)
            model[VECTOR_FIELD_DP](mb, t, x, p, wsP)
            for i in range(n):
                fpc[i] += alpha * wsP[i, pidx] + (ws2[i] - ws1[i]) * dalpha


@njit(cache=True, inline="always")  # inlined: array arguments cost more than the work
def _aug_rhs(model, mode, slide, t, y, p, var, pidx, dy, W, WJ, WP, wv):
    """Right-hand side of the augmented system ``[x, Phi (row-major), psi]``."""
    n = N_STATE or wv.shape[1]
    x = y[:n]
    f = wv[0]
    fpc = wv[1]
    J = WJ[0]
    _field(model, mode, slide, t, x, p, var, pidx, f, J, fpc, wv[2], wv[3], wv[4], WJ[1], WJ[2], WP, wv[5], wv[6], W[0], W[1])
    for i in range(n):
        dy[i] = f[i]
    if var:
        # J Phi by rows of J (contiguous inner loops; the zeros of a sparse J are skipped)
        for i in range(n):
            for j in range(n):
                dy[n + i * n + j] = 0.0
            for k in range(n):
                a = J[i, k]
                if a != 0.0:
                    for j in range(n):
                        dy[n + i * n + j] += a * y[n + k * n + j]
        off = n + n * n
        for i in range(n):
            acc = 0.0
            for k in range(n):
                acc += J[i, k] * y[off + k]
            dy[off + i] = acc + (fpc[i] if pidx >= 0 else 0.0)


@njit(cache=True, _nrt=False)
def _aug_rhs_called(model, mode, slide, t, y, p, var, pidx, dy, W, WJ, WP, wv):
    """:func:`_aug_rhs` as a call, for the places outside the stepper (inlining there only costs compile time)."""
    _aug_rhs(model, mode, slide, t, y, p, var, pidx, dy, W, WJ, WP, wv)


@njit(cache=True, _nrt=False)
def _field_called(model, mode, slide, t, x, p, f, WJ, WP, wv, W):
    """The field (no derivatives) of a mode or sliding motion, as a call."""
    _field(model, mode, slide, t, x, p, False, -1, f, WJ[0], wv[1], wv[2], wv[3], wv[4], WJ[1], WJ[2], WP, wv[5], wv[6], W[0], W[1])


@njit(cache=True, _nrt=False)
def _rk_step(model, mode, slide, t, y, h, p, var, pidx, rtol, atol, K, ynew, ytmp, W, WJ, WP, wv, n_err):
    """One DOP853 step from ``(t, y)`` with ``K[0] = f(t, y)`` given; returns the error norm.

    The error is measured on the first ``n_err`` components (the state, or the
    state and the variational components).
    """
    N = y.shape[0]
    for s in range(1, 13):  # stages 1-11, then the solution (stage 12: the field at its end)
        yst = ytmp if s < 12 else ynew
        for i in range(N):
            acc = 0.0
            for j in range(s):
                a = RK_A[s, j] if s < 12 else RK_B[j]  # noqa: F821
                if a != 0.0:
                    acc += a * K[j, i]
            yst[i] = y[i] + h * acc
        # one call site: the field is inlined here, once
        _aug_rhs(model, mode, slide, t + RK_C[s] * h if s < 12 else t + h, yst, p, var, pidx, K[s], W, WJ, WP, wv)  # noqa: F821
    e5 = 0.0
    e3 = 0.0
    for i in range(n_err):
        sc = atol + rtol * max(abs(y[i]), abs(ynew[i]))
        a5 = 0.0
        a3 = 0.0
        for j in range(13):
            a5 += RK_E5[j] * K[j, i]  # noqa: F821
            a3 += RK_E3[j] * K[j, i]  # noqa: F821
        e5 += (a5 / sc) ** 2
        e3 += (a3 / sc) ** 2
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n_err)


@njit(cache=True, _nrt=False)
def _dense_coefficients(model, mode, slide, t, y, ynew, h, p, K, F, xtmp, W, WJ, WP, wv):
    """Coefficients of the 7th-order continuous extension of the state ``x`` only."""
    n = N_STATE or F.shape[1]
    for s in range(13, 16):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                a = RK_A[s, j]  # noqa: F821
                if a != 0.0:
                    acc += a * K[j, i]
            xtmp[i] = y[i] + h * acc
        # (no variational part; the flags typed, not literal: literals would compile the call a second time)
        _aug_rhs_called(model, mode, slide, t + RK_C[s] * h, xtmp, p, np.bool_(False), np.int64(-1), K[s], W, WJ, WP, wv)  # noqa: F821
    for i in range(n):
        dyi = ynew[i] - y[i]
        F[0, i] = dyi
        F[1, i] = h * K[0, i] - dyi
        F[2, i] = 2.0 * dyi - h * (K[12, i] + K[0, i])
        for r in range(4):
            acc = 0.0
            for j in range(16):
                acc += RK_D[r, j] * K[j, i]  # noqa: F821
            F[3 + r, i] = h * acc


MAX_TAYLOR = 60  # terms of the exact flow's series; more means the step is too long
EXACT_STEP_BOUND = 4.0  # longest exact step, times the row-sum norm of its generator: the magnitudes of its
# series' terms sum to at most e^4 ~ 55 times the state's, so that summing them loses under two digits


def _dense_basis(s):
    """DOP853's dense-output basis ``s^a (1 - s)^b``, ``a = j // 2 + 1``, ``b = (j + 1) // 2`` (see ``_dense_eval``)."""
    s = np.asarray(s, dtype=float)
    return np.stack([s ** (j // 2 + 1) * (1.0 - s) ** ((j + 1) // 2) for j in range(7)], axis=-1)


def _lobatto_interpolation():
    """Nodes of the exact steps' dense output and the bound of its error on each Taylor term.

    The dense output of an exact step interpolates the step's Taylor
    polynomial at the eight Chebyshev-Lobatto points of [0, 1] (near-minimax);
    ``bound[k]`` is the largest error of that interpolation of ``s^k``.
    """
    nodes = 0.5 * (1.0 - np.cos(np.pi * np.arange(8) / 7.0))
    to_dense = np.linalg.inv(_dense_basis(nodes[1:]))
    grid = np.linspace(0.0, 1.0, 2001)
    basis = _dense_basis(grid)
    bound = np.zeros(MAX_TAYLOR + 1)
    for k in range(8, MAX_TAYLOR + 1):
        bound[k] = np.max(np.abs(basis @ (to_dense @ nodes[1:] ** k) - grid**k))
    return nodes, to_dense, bound


LOBATTO_NODES, LOBATTO_TO_DENSE, LOBATTO_BOUND = _lobatto_interpolation()


@njit(cache=True, _nrt=False)
def _affine_norm(A, B, om):
    """Row-sum norm of the augmented matrix ``[[A, B], [0, omega J]]`` of an affine mode."""
    n = N_STATE or A.shape[0]
    mnorm = abs(om)
    for i in range(n):
        row = 0.0
        for j in range(n):
            row += abs(A[i, j])
        for j in range(3):
            row += abs(B[i, j])
        mnorm = max(mnorm, row)
    return mnorm


@njit(cache=True, _nrt=False)
def _exact_end(mode, t_end, x, y, tail, rtol, atol, AFF_A, AFF_B, AFF_W, K):
    """End of an exact step at ``t_end`` in state ``x`` (from ``y``): ``K[12] = f(t_end, x)``; returns the
    error norm of the step's dense output, whose bound per component is ``tail``."""
    n = N_STATE or AFF_A.shape[1]
    A = AFF_A[mode]
    B = AFF_B[mode]
    theta = AFF_W[mode, 0] * t_end + AFF_W[mode, 1]
    c1 = math.cos(theta)
    s1 = math.sin(theta)
    err = 0.0
    for i in range(n):
        acc = B[i, 0] + B[i, 1] * c1 + B[i, 2] * s1
        for j in range(n):
            acc += A[i, j] * x[j]
        K[12, i] = acc
        sc = atol + rtol * max(abs(y[i]), abs(x[i]))
        err += (tail[i] / sc) ** 2
    return math.sqrt(err / n)


@njit(cache=True, _nrt=False)
def _exact_step(mode, t, y, h, var, pidx, rtol, atol, AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP, K, ynew, TW, TP, TC):
    """One step of the exact flow of an affine mode; returns the dense output's error norm.

    The mode's field is ``A x + B z`` with ``z = (1, cos theta, sin theta)``,
    ``theta = omega t + phase``; ``(x, z)``, the fundamental solution matrix and
    the sensitivity ``(psi, dz/dp)`` obey a linear system with constant
    coefficients, whose Taylor series is summed here until its terms fall below
    rounding: the step is exact for any ``h``.  The scaled Taylor coefficients of
    ``[x, Phi, psi]`` go to the rows of ``TC`` (row 0 is ``y``; their number, or 0
    when there is no series, goes to row ``MAX_TAYLOR + 1``, the fraction of the
    step they are summed at to row ``MAX_TAYLOR + 2``: see :func:`_exact_dense`
    and :func:`_exact_fraction`), ``K[12]`` receives ``f(t + h, x(t + h))``.  The error
    returned bounds the error of the dense output (a degree-7 interpolant of the
    series) against the tolerances, and rejects steps long enough for the series
    to lose digits.
    """
    n = N_STATE or AFF_A.shape[1]
    A = AFF_A[mode]
    B = AFF_B[mode]
    om = AFF_W[mode, 0]
    # the sensitivity is carried whenever Phi is, except where it is zero and stays so: no parameter
    # (its forcing terms are zero when pidx < 0) and psi = 0 at the step's start (a period map's shots)
    sens = var and pidx >= 0
    if var and not sens:
        for i in range(n):
            if y[n + n * n + i] != 0.0:
                sens = True
    Ap = AFF_AP[mode]
    Bp = AFF_BP[mode]
    omp = AFF_W[mode, 2]
    TC[MAX_TAYLOR + 1, 0] = 0.0
    mnorm = _affine_norm(A, B, om)
    bmax = 0.0
    for i in range(n):
        for j in range(3):
            bmax = max(bmax, abs(B[i, j]))
    if mnorm * abs(h) > EXACT_STEP_BOUND:
        return (mnorm * abs(h) / 2.0) ** 8
    xs = TW[0]
    xt = TW[1]
    xn = TW[2]
    ss = TW[3]
    st = TW[4]
    sn = TW[5]
    tail = TW[6]
    Ps = TP[0]
    Pt = TP[1]
    # the Taylor terms of z = (1, cos theta, sin theta) and of dz/dp (the first component is constant)
    theta = om * t + AFF_W[mode, 1]
    z1 = math.cos(theta)
    z2 = math.sin(theta)
    thp = omp * t + AFF_W[mode, 3]
    ze1 = -thp * z2
    ze2 = thp * z1
    for i in range(n):
        xs[i] = y[i]
        xt[i] = y[i]
        TC[0, i] = y[i]
        tail[i] = 0.0
        if sens:
            ss[i] = y[n + n * n + i]
            st[i] = ss[i]
        if var:
            TC[0, n + n * n + i] = y[n + n * n + i]
            for j in range(n):
                Ps[i, j] = y[n + i * n + j]
                Pt[i, j] = Ps[i, j]
                TC[0, n + i * n + j] = Ps[i, j]
    bz0 = 1.0  # the constant forcing term enters the first term only
    small = 0
    converged = False
    n_terms = 0
    for k in range(1, MAX_TAYLOR + 1):
        c = h / k
        for i in range(n):
            acc = B[i, 0] * bz0 + B[i, 1] * z1 + B[i, 2] * z2
            for j in range(n):
                acc += A[i, j] * xt[j]
            xn[i] = c * acc
        if sens:
            for i in range(n):
                acc = B[i, 1] * ze1 + B[i, 2] * ze2 + Bp[i, 0] * bz0 + Bp[i, 1] * z1 + Bp[i, 2] * z2
                for j in range(n):
                    acc += A[i, j] * st[j] + Ap[i, j] * xt[j]
                sn[i] = c * acc
            ze1, ze2 = c * (-om * ze2 - omp * z2), c * (om * ze1 + omp * z1)
            for i in range(n):
                st[i] = sn[i]
                ss[i] += st[i]
                TC[k, n + n * n + i] = st[i]
        elif var:
            for i in range(n):
                TC[k, n + n * n + i] = 0.0  # (summed by _exact_fraction)
        z1, z2 = -c * om * z2, c * om * z1
        bz0 = 0.0
        for i in range(n):
            xt[i] = xn[i]
            xs[i] += xt[i]
            TC[k, i] = xt[i]
        if var:
            # the term c A Pt by rows of A (contiguous inner loops; the zeros of a sparse A are skipped)
            for i in range(n):
                for j in range(n):
                    TP[2, i, j] = 0.0
                for l in range(n):
                    a = c * A[i, l]
                    if a != 0.0:
                        for j in range(n):
                            TP[2, i, j] += a * Pt[l, j]
            for i in range(n):
                for j in range(n):
                    Pt[i, j] = TP[2, i, j]
                    Ps[i, j] += Pt[i, j]
                    TC[k, n + i * n + j] = Pt[i, j]
        if k < 7:
            continue  # the test below needs two small terms from k = 7 on, the tail bound is zero below 8
        # the term's and the partial sum's size (state, forcing, Phi, sensitivity)
        tnorm = bmax * max(abs(z1), abs(z2))
        snorm = 0.0
        for i in range(n):
            tail[i] += LOBATTO_BOUND[k] * abs(xt[i])
            tnorm = max(tnorm, abs(xt[i]))
            snorm = max(snorm, abs(xs[i]))
        if sens:
            tnorm = max(tnorm, abs(ze1), abs(ze2))
            for i in range(n):
                tnorm = max(tnorm, abs(st[i]))
                snorm = max(snorm, abs(ss[i]))
        if var:
            for i in range(n):
                for j in range(n):
                    tnorm = max(tnorm, abs(Pt[i, j]))
                    snorm = max(snorm, abs(Ps[i, j]))
        small = small + 1 if tnorm <= 1e-17 * snorm else 0
        if k >= 8 and small >= 2:
            converged = True
            n_terms = k + 1
            break
    if not converged:
        return np.inf
    for i in range(n):
        ynew[i] = xs[i]
        if var:
            for j in range(n):
                ynew[n + i * n + j] = Ps[i, j]
            ynew[n + n * n + i] = ss[i] if sens else 0.0
    TC[MAX_TAYLOR + 1, 0] = n_terms
    TC[MAX_TAYLOR + 2, 0] = 1.0
    return _exact_end(mode, t + h, xs, y, tail, rtol, atol, AFF_A, AFF_B, AFF_W, K)


@njit(cache=True, _nrt=False)
def _exact_fraction(mode, t, y, h, theta, var, rtol, atol, AFF_A, AFF_B, AFF_W, K, ynew, TW, TC):
    """The exact step of ``theta * h`` (``0 <= theta <= 1``) from the series of a step of ``h`` in ``TC``.

    The Taylor series of the exact flow converges on the whole step, so a
    shorter step (after a rejection, to an event, in its refinement) is the
    same series summed at ``theta``: no new series.  Returns the error norm of
    the shorter step's dense output, as :func:`_exact_step`.
    """
    n = N_STATE or AFF_A.shape[1]
    n_terms = int(TC[MAX_TAYLOR + 1, 0])
    N = n + n * n + n if var else n
    for c in range(N):
        v = 0.0
        for k in range(n_terms - 1, 0, -1):
            v = (v + TC[k, c]) * theta
        ynew[c] = v + TC[0, c]
    tail = TW[6]
    for i in range(n):
        tail[i] = 0.0
        pw = theta ** 8
        for k in range(8, n_terms):
            tail[i] += LOBATTO_BOUND[k] * abs(TC[k, i]) * pw
            pw *= theta
    TC[MAX_TAYLOR + 2, 0] = theta
    return _exact_end(mode, t + theta * h, ynew, y, tail, rtol, atol, AFF_A, AFF_B, AFF_W, K)


@njit(cache=True, _nrt=False)
def _exact_dense(y, ynew, TC, F):
    """Dense output of an exact step: its Taylor series interpolated at the Chebyshev-Lobatto points
    (of the fraction of the series' step that was taken, see :func:`_exact_fraction`)."""
    n = N_STATE or F.shape[1]
    n_terms = int(TC[MAX_TAYLOR + 1, 0])
    theta = TC[MAX_TAYLOR + 2, 0]
    for i in range(n):
        for r in range(7):
            F[r, i] = LOBATTO_TO_DENSE[r, 6] * (ynew[i] - y[i])
        for j in range(1, 7):
            sj = LOBATTO_NODES[j] * theta
            v = 0.0
            for k in range(n_terms - 1, 0, -1):
                v = (v + TC[k, i]) * sj
            for r in range(7):
                F[r, i] += LOBATTO_TO_DENSE[r, j - 1] * v


@njit(cache=True, _nrt=False)  # a call, not inlined: without reference counting, passing arrays costs little
def _step(model, exact, mode, slide, t, y, h, p, var, pidx, rtol, atol, K, ynew, ytmp, W, WJ, WP, wv, n_err,
          AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP, TW, TP, TC):
    """A step of the exact flow (affine mode, not sliding) or of DOP853; returns the error norm.

    An exact step no longer than the one whose series ``TC`` holds from the
    same ``(t, y)`` (its size in ``TC[MAX_TAYLOR + 3, 0]``, 0 for none: the
    caller clears it when ``(t, y)`` moves on) is that series summed at a
    fraction of its step.
    """
    if exact:
        base = TC[MAX_TAYLOR + 3, 0]
        if base != 0.0 and 0.0 <= h / base <= 1.0:
            return _exact_fraction(mode, t, y, base, h / base, var, rtol, atol, AFF_A, AFF_B, AFF_W, K, ynew, TW, TC)
        err = _exact_step(mode, t, y, h, var, pidx, rtol, atol, AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP, K, ynew, TW, TP, TC)
        TC[MAX_TAYLOR + 3, 0] = h if TC[MAX_TAYLOR + 1, 0] > 0.0 else 0.0
        return err
    return _rk_step(model, mode, slide, t, y, h, p, var, pidx, rtol, atol, K, ynew, ytmp, W, WJ, WP, wv, n_err)


@njit(cache=True, _nrt=False)
def _dense(model, exact, mode, slide, t, y, ynew, h, p, K, F, xtmp, W, WJ, WP, wv, TC):
    """Dense-output coefficients of the step just taken (by :func:`_step`)."""
    if exact:
        _exact_dense(y, ynew, TC, F)
    else:
        _dense_coefficients(model, mode, slide, t, y, ynew, h, p, K, F, xtmp, W, WJ, WP, wv)


@njit(cache=True, _nrt=False)
def _dense_eval(F, y, s, out):
    n = N_STATE or F.shape[1]
    for i in range(n):
        v = 0.0
        for k in range(7):
            v += F[6 - k, i]
            if k % 2 == 0:
                v *= s
            else:
                v *= 1.0 - s
        out[i] = v + y[i]


@njit(cache=True, _nrt=False)
def _event_value(model, kind, idx, slide, t, x, p, gtmp, gptmp):
    """Event function: an indicator (kind 0) or a sliding-exit function (kind 1: side a, 2: side b)."""
    if kind == 0:
        return model[INDICATOR](idx, t, x, p)
    if kind == 1:
        return slide[4] * slide[5] * model[LIE_DERIVATIVE](slide[1], slide[3], t, x, p, gtmp, gptmp)
    return -slide[4] * slide[5] * model[LIE_DERIVATIVE](slide[2], slide[3], t, x, p, gtmp, gptmp)


@njit(cache=True, _nrt=False)
def _series_eval(TC, theta, out):
    """The state of an exact step at the fraction ``theta`` of its series' step (``TC``, see
    :func:`_exact_step`): the series itself, exact to rounding, not its degree-7 interpolant."""
    n = out.shape[0]
    n_terms = int(TC[MAX_TAYLOR + 1, 0])
    for i in range(n):
        v = 0.0
        for k in range(n_terms - 1, 0, -1):
            v = (v + TC[k, i]) * theta
        out[i] = v + TC[0, i]


@njit(cache=True, _nrt=False)
def _state_at(exact, TC, F, y, s, h, out):
    """The state at the fraction ``s`` of the step ``h`` just taken: on the exact flow's own series
    (an exact step: exact to rounding, so that event location does not depend on the tolerances),
    else on the dense output."""
    base = TC[MAX_TAYLOR + 3, 0]
    if exact and base != 0.0 and TC[MAX_TAYLOR + 1, 0] > 0.0:
        _series_eval(TC, s * h / base, out)
    else:
        _dense_eval(F, y, s, out)


@njit(cache=True, _nrt=False)
def _dense_event(model, kind, idx, slide, sgn, t, h, F, y, s, p, xtmp, gtmp, gptmp, exact, TC):
    """``sgn`` times an event function at the fraction ``s`` of the step ``h`` (see :func:`_state_at`)."""
    _state_at(exact, TC, F, y, s, h, xtmp)
    return sgn * _event_value(model, kind, idx, slide, t + s * h, xtmp, p, gtmp, gptmp)


@njit(cache=True, _nrt=False)
def _bracket_root(model, kind, idx, slide, sgn, t, h, F, y, sa, sb, gb, p, xtmp, gtmp, gptmp, exact, TC):
    """Regula falsi with the Anderson-Bjorck modification, for the root of ``sgn * event`` on the dense output
    in ``[sa, sb]`` (value > 0 at sa, <= 0 at sb), to a bracket of a few rounding units.

    Where the same end is kept twice, the value at the other end is scaled by ``1 - g_new / g_old`` (half
    where that is not positive: Illinois).  Anderson and Bjorck (1973), "A new high order method of regula
    falsi type for computing a root of an equation", BIT 13, 253-264.
    """
    ga = _dense_event(model, kind, idx, slide, sgn, t, h, F, y, sa, p, xtmp, gtmp, gptmp, exact, TC)
    if ga <= 0.0:
        ga = 1e-300
    side = 0
    for _ in range(100):
        if sb - sa <= 4.0 * EPS * max(1.0, sb):
            break
        sc = sb - gb * (sb - sa) / (gb - ga)
        if not (sa < sc < sb):
            sc = 0.5 * (sa + sb)
        gc = _dense_event(model, kind, idx, slide, sgn, t, h, F, y, sc, p, xtmp, gtmp, gptmp, exact, TC)
        if gc > 0.0:
            sa = sc
            ga = gc
            if side == -1:
                gb *= 0.5
            side = -1
        else:
            sb = sc
            gb = gc
            if gc == 0.0:
                break
            if side == 1:
                ga *= 0.5
            side = 1
    return sb


@njit(cache=True, _nrt=False)
def _dip_search(model, kind, idx, slide, sgn, t, h, F, y, p, xtmp, gtmp, gptmp, lo, hi, exact, TC, bottom):
    """Golden-section search for the minimum of ``sgn * event`` on ``[lo, hi]`` of the step; returns (s, value).

    With ``bottom`` it searches the minimum itself (to 1e-12 of the step): the bottom of a dip known to cross,
    where the step's own solution is compared with the dense output's (a point just below zero near the dip's
    edge, within the two's difference of the surface, would refute a contact 1e-8 deep).  Otherwise it
    stops at the first value <= 0 (the dip crosses), or where the minimum is certainly positive: once
    the bracket is below 1 % of the range, the three last points give the curvature ``f''`` (a divided
    difference), and ``min(fc, fd) > 4 |f''| (b - a)^2`` bounds ``f(x*) >= f(x_best) - f''(xi) (x_best -
    x*)^2 / 2`` away from zero with a factor 8 to spare on the curvature; the value returned is then a
    point's, not the minimum.  A shallow dip (a near-grazing) never passes that test and is searched to
    1e-12 of the step, as every dip was before.
    """
    invphi = 0.6180339887498949
    a = lo
    b = hi
    c = b - invphi * (b - a)
    d = a + invphi * (b - a)
    fc = _dense_event(model, kind, idx, slide, sgn, t, h, F, y, c, p, xtmp, gtmp, gptmp, exact, TC)
    fd = _dense_event(model, kind, idx, slide, sgn, t, h, F, y, d, p, xtmp, gtmp, gptmp, exact, TC)
    xo = 0.0  # the bracket's end the last move dropped an inner point to, and its value
    fo = 0.0
    have_old = False
    for _ in range(80):
        if not bottom:
            if fc <= 0.0:
                return c, fc
            if fd <= 0.0:
                return d, fd
        if b - a < 1e-12:
            break
        if not bottom and have_old and b - a < 1e-2 * (hi - lo):
            # the second divided difference of the three points c < d and xo (an end of the bracket)
            x0, x1, x2, f0, f1, f2 = (xo, c, d, fo, fc, fd) if xo < c else (c, d, xo, fc, fd, fo)
            curvature = abs(2.0 * ((f2 - f1) / (x2 - x1) - (f1 - f0) / (x1 - x0)) / (x2 - x0))
            if min(fc, fd) > 4.0 * curvature * (b - a) * (b - a):
                if fc < fd:
                    return c, fc
                return d, fd
        if fc < fd:
            xo = d
            fo = fd
            b = d
            d = c
            fd = fc
            c = b - invphi * (b - a)
            fc = _dense_event(model, kind, idx, slide, sgn, t, h, F, y, c, p, xtmp, gtmp, gptmp, exact, TC)
        else:
            xo = c
            fo = fc
            a = c
            c = d
            fc = fd
            d = a + invphi * (b - a)
            fd = _dense_event(model, kind, idx, slide, sgn, t, h, F, y, d, p, xtmp, gtmp, gptmp, exact, TC)
        have_old = True
    if fc < fd:
        return c, fc
    return d, fd


@njit(cache=True, _nrt=False)
def _surface_resolution(model, s, t, x, p, hx, hp):
    """How near zero the indicator of surface ``s`` is rounding, at ``(t, x)``: 16 rounding units of
    the terms it is made of, ``|h_x_i| max(1, |x_i|)``, ``|h_t| max(1, |t|)`` and ``|h_p_j p_j|`` (a state
    that close is on the surface).  Not a fixed distance: a band 1e-13 wide (a stick band) is
    resolved, and an indicator of a large state is not taken as exact.  A term that is not finite (the
    gradient of ``sqrt(x^2 + y^2) - delta`` at the circle's centre, where the indicator has none) is left
    out: the state is as far from the surface as its indicator says."""
    ht = model[INDICATOR_GRAD](s, t, x, p, hx, hp)
    scale = abs(ht) * max(1.0, abs(t)) if math.isfinite(ht) else 0.0
    for i in range(x.shape[0]):
        term = abs(hx[i]) * max(1.0, abs(x[i]))
        if math.isfinite(term):
            scale += term
    for j in range(p.shape[0]):
        term = abs(hp[j] * p[j])
        if math.isfinite(term):
            scale += term
    return 16.0 * EPS * scale


@njit(cache=True, _nrt=False)
def _surface_crossings(model, idx, slide, sg, t, h, F, y, p, xtmp, gtmp, gptmp, exact, TC, v_start, res, slope_start,
                       v_end, slope_end, dip):
    """Where surface ``idx``, on side ``sg`` at the step's start, is crossed within the step:
    ``(s1, s2, s_lo, s_dip, known)``, fractions of the step (2.0: none).

    ``s1`` is the first crossing, to side ``-sg``, within ``[s_lo, s_dip]``.  A step whose end lies on
    the same side (``dip``: the slope along the motion turned within it) may hold a dip through the
    surface: its bottom ``s_dip`` is searched for, and where it lies across, ``s1`` is the way in and
    ``s2`` the way back, within ``[s_dip, 1]`` (whichever of the two has a transition is the event).
    A sign change at the step's end gives ``s_dip = 1``.  A step that starts on the surface
    (``|v_start| <= res``, its rounding: after an event) moving to side ``sg`` (or tangent to it, as where a
    sliding motion ends) and ends across it has made an excursion: the crossing is its way back, bracketed from a point of the excursion, however short
    (``s_lo``), not from the start, where the value is rounding; where no point of it lies beyond
    rounding, the excursion is too shallow to resolve and the crossing is its way back all the same
    (``known``: its side is ``-sg``, whatever the slope at the event, a rounding near the start); one
    that ends within rounding of the surface too, still moving away from it (``slope_end``), has
    resolved no crossing.  On an exact step the event function
    is evaluated on the exact flow's series, so that whether a near-tangency crosses is decided to
    rounding, at any tolerance.
    """
    if sg * v_end <= 0.0:
        s_lo = 0.0
        known = False
        if abs(v_start) <= res and sg * slope_start >= 0.0:
            s_top, v_top = _dip_search(model, KIND_INDICATOR, idx, slide, -sg, t, h, F, y, p, xtmp, gtmp, gptmp, 0.0, 1.0,
                                       exact, TC, False)
            if v_top < 0.0:
                s_lo = s_top
            if v_top >= -res:
                # an excursion too shallow to resolve: if it ends within rounding of the surface, still
                # moving away from it, nothing has been resolved; else the crossing is its way back, to
                # side -sg
                if abs(v_end) <= res and sg * slope_end >= 0.0:
                    return 2.0, 2.0, 0.0, 2.0, False
                known = True
        s1 = _bracket_root(model, KIND_INDICATOR, idx, slide, sg, t, h, F, y, s_lo, 1.0, min(sg * v_end, -1e-300), p,
                           xtmp, gtmp, gptmp, exact, TC)
        return s1, 2.0, s_lo, 1.0, known
    if not dip:
        return 2.0, 2.0, 0.0, 2.0, False
    smin, vmin = _dip_search(model, KIND_INDICATOR, idx, slide, sg, t, h, F, y, p, xtmp, gtmp, gptmp, 0.0, 1.0, exact, TC,
                             False)
    if vmin > 0.0:
        return 2.0, 2.0, 0.0, 2.0, False
    # it crosses: the dip's bottom itself, where the step's own solution is checked against it
    smin, vmin = _dip_search(model, KIND_INDICATOR, idx, slide, sg, t, h, F, y, p, xtmp, gtmp, gptmp, 0.0, 1.0, exact, TC,
                             True)
    s_lo = 0.0
    if abs(v_start) <= res and sg * slope_start >= 0.0:
        # a step from the surface (after an event) that goes back through it and out again: the way in is
        # bracketed from the top of the excursion before the dip, not from the start, where the value is rounding
        s_top, v_top = _dip_search(model, KIND_INDICATOR, idx, slide, -sg, t, h, F, y, p, xtmp, gtmp, gptmp, 0.0, smin,
                                   exact, TC, True)
        if not v_top < -res:
            return 2.0, 2.0, 0.0, 2.0, False  # no excursion beyond rounding before the dip: the dip is the departure's
        s_lo = s_top
    s1 = _bracket_root(model, KIND_INDICATOR, idx, slide, sg, t, h, F, y, s_lo, smin, min(vmin, -1e-300), p, xtmp, gtmp,
                       gptmp, exact, TC)
    s2 = _bracket_root(model, KIND_INDICATOR, idx, slide, -sg, t, h, F, y, smin, 1.0, min(-sg * v_end, -1e-300), p, xtmp,
                       gtmp, gptmp, exact, TC)
    return s1, s2, s_lo, smin, False


@njit(cache=True, _nrt=False)
def _firing_transition(model, mode, idx, cross, t_e, x_e, p, tr_table):
    """The first transition out of ``mode`` on surface ``idx`` that fires crossing to side ``cross``
    at ``(t_e, x_e)`` (its direction and guard hold), or -1."""
    for k in range(tr_table.shape[0]):
        if tr_table[k, 0] != mode or tr_table[k, 1] != idx:
            continue
        dk = tr_table[k, 2]
        if dk != 0 and dk != cross:
            continue
        if model[GUARD](k, t_e, x_e, p):
            return k
    return NONE


@njit(cache=True, _nrt=False)
def _slope(model, mode, slide, kind, idx, t, x, f, p, hx, hp, gtmp, gptmp):
    """Time derivative of an event function along ``f`` (indicators: ``h_x f + h_t``; sliding exits:
    the Lie derivative's ``s_x f + s_t``)."""
    n = N_STATE or x.shape[0]
    if kind == 0:
        return model[INDICATOR_RATE](idx, t, x, f, p, hx, hp)
    m = slide[1] if kind == 1 else slide[2]
    model[LIE_DERIVATIVE](m, slide[3], t, x, p, gtmp, gptmp)
    acc = model[LIE_DERIVATIVE_DT](m, slide[3], t, x, p)
    for i in range(n):
        acc += gtmp[i] * f[i]
    return (slide[4] if kind == 1 else -slide[4]) * slide[5] * acc


@njit(cache=True)
def _resized_rows(a, m):
    """A copy of the first rows of the 2-d array ``a`` in an array of ``m`` rows (grown with zeros).

    Plain loops: numba compiles slice assignments into much more code.
    """
    b = np.zeros((m, a.shape[1]), dtype=a.dtype)
    for i in range(min(m, a.shape[0])):
        for j in range(a.shape[1]):
            b[i, j] = a[i, j]
    return b


@njit(cache=True)
def _resized_steps(a, m):
    """:func:`_resized_rows` for the stack of dense-output coefficients, shape (steps, 7, n)."""
    b = np.zeros((m, a.shape[1], a.shape[2]))
    for i in range(min(m, a.shape[0])):
        for r in range(a.shape[1]):
            for j in range(a.shape[2]):
                b[i, r, j] = a[i, r, j]
    return b


@njit(cache=True, _nrt=False)
def _record_step(rec, rec_F, n_rec, t, h, s_end, x, F):
    """Append a step's dense output: row ``(start, size, end fraction, start state)`` and coefficients; the caller has made room for it.  Returns the number of rows."""
    rec[n_rec, 0] = t
    rec[n_rec, 1] = h
    rec[n_rec, 2] = s_end
    for i in range(x.shape[0]):
        rec[n_rec, 3 + i] = x[i]
        for r in range(DENSE_ROWS):
            rec_F[n_rec, r, i] = F[r, i]
    return n_rec + 1


@njit(cache=True, _nrt=False)
def _dense_component(F, y, s, i):
    """Component ``i`` of the continuous extension at fraction ``s`` of the step."""
    v = 0.0
    for k in range(7):
        v += F[6 - k, i]
        if k % 2 == 0:
            v *= s
        else:
            v *= 1.0 - s
    return v + y[i]


@njit(cache=True, _nrt=False)
def _track_extrema(F, y, s_end, xmin, xmax, f0, f1, xtmp, direction):
    """Update per-component extrema over a step segment ``s in [0, s_end]`` of the dense output.

    ``f0``, ``f1`` are the time derivatives at the segment's ends (``direction``
    the sign of the step): a component whose derivative keeps its sign has its
    extremes at the ends (updated by the caller).

    Golden-section search to a bracket of 1e-5, then one parabolic step: the
    extreme value is then exact to far below the integration tolerance.
    """
    n = N_STATE or xmin.shape[0]
    invphi = 0.6180339887498949
    for i in range(n):
        if f0[i] * f1[i] > 0.0:
            continue
        for sense in (1.0, -1.0):
            rate = direction * f0[i]  # d x_i / d s at the start
            if (sense > 0.0 and rate < 0.0) or (sense < 0.0 and rate > 0.0):
                continue  # rising then falling has an inner maximum only, and vice versa
            a = 0.0
            b = s_end
            c = b - invphi * (b - a)
            d = a + invphi * (b - a)
            fc = -sense * _dense_component(F, y, c, i)
            fd = -sense * _dense_component(F, y, d, i)
            while b - a > 1e-5 * s_end:
                if fc < fd:
                    b = d
                    d = c
                    fd = fc
                    c = b - invphi * (b - a)
                    fc = -sense * _dense_component(F, y, c, i)
                else:
                    a = c
                    c = d
                    fc = fd
                    d = a + invphi * (b - a)
                    fd = -sense * _dense_component(F, y, d, i)
            best = min(fc, fd)
            # one parabolic step through (c, fc), (m, fm), (d, fd)
            m = 0.5 * (c + d)
            fm = -sense * _dense_component(F, y, m, i)
            denom = fc - 2.0 * fm + fd
            if denom > 0.0:
                sv = m + 0.5 * (d - c) * 0.5 * (fc - fd) / denom
                if a <= sv <= b:
                    best = min(best, fm, -sense * _dense_component(F, y, sv, i))
            best = min(best, fm)
            v = -best * sense
            if v > xmax[i]:
                xmax[i] = v
            if v < xmin[i]:
                xmin[i] = v


@njit(cache=True, _nrt=False)  # once per mode entered; not inlined, no reference counting
def _watch_surfaces(model, mode, slide, t, y, K, p, direction, last_kind, tr_table, watched, fires, surf_old, surf_res,
                    slope_old, surf_sign, fixed_sign, hx, hp, gtmp, gptmp):
    """Entering a mode (or a sliding motion): which surfaces its transitions watch, which way each
    fires (``fires``: 1 to the negative side, 2 to the positive, 3 both), and the sign memory of each
    (value, slope along the motion and side, in the direction of travel), except the signs an event
    has just fixed (``fixed_sign``).  A sliding motion watches the surfaces, other than its own, of
    the transitions out of either of its modes (its region may end there: ``_sliding_match``)."""
    n = N_STATE or hx.shape[0]  # (see the engine's header)
    n_surfaces = watched.shape[0]
    n_tr = tr_table.shape[0]
    # sign memory of every surface watched in this mode, in the direction of travel
    for s in range(n_surfaces):
        # bit 4 of fires: the surface was watched by the motion just left, so its side (surf_sign) is current
        # (bits 16 and 32, a crossing already taken at this instant and its side, are kept: see _exit_at_once)
        fires[s] = (4 if watched[s] else 0) | (fires[s] & FIRED_BITS)
        if fires[s] & FIRED_NOW:
            # a zero-length visit whose motion turns back across the surface just crossed: crossing it again at
            # this instant is a new crossing (a latch set again at the comparator's level is reset again)
            sl = direction * _slope(model, mode, slide, KIND_INDICATOR, s, t, y[:n], K[0, :n], p, hx, hp, gtmp, gptmp)
            if sl * (1.0 if fires[s] & FIRED_POSITIVE else -1.0) < 0.0:
                fires[s] &= ~FIRED_BITS
        watched[s] = False
    for k in range(n_tr):
        src = tr_table[k, 0]
        if (src == mode) if slide[0] == 0 else ((src == slide[1] or src == slide[2]) and tr_table[k, 1] != slide[3]):
            watched[tr_table[k, 1]] = True
            dk = tr_table[k, 2]
            fires[tr_table[k, 1]] |= 3 if dk == 0 else (1 if dk < 0 else 2)
    for s in range(n_surfaces):
        if watched[s]:
            v = model[INDICATOR](s, t, y[:n], p)
            surf_old[s] = v
            surf_res[s] = _surface_resolution(model, s, t, y[:n], p, hx, hp)
            sl = direction * _slope(model, mode, slide, KIND_INDICATOR, s, t, y[:n], K[0, :n], p, hx, hp, gtmp, gptmp)
            if fixed_sign[s] and last_kind == EVENT_SLIDING_END:
                # a sliding motion has just ended on this surface, where the new field is tangent
                # to it: the slope is zero (its computed value is rounding, and a dip test on it
                # would find the surface again at once when the motion slid a rounding off it)
                sl = 0.0
            slope_old[s] = sl
            if fixed_sign[s]:
                continue
            if abs(v) > surf_res[s]:
                surf_sign[s] = 1.0 if v > 0 else -1.0
            elif fires[s] & 4:
                # reached at the instant of the event just processed, by the motion that watched it: it keeps
                # the side it came from, and its own crossing is due at once (_exit_at_once: coinciding events)
                pass
            elif sl != 0.0:
                # on it, from a side no motion watched: the side is the one the motion goes to (bit 8: a guess,
                # so that a transition out of this mode that the motion crosses it by fires at once)
                fires[s] |= 8
                surf_sign[s] = 1.0 if sl > 0 else -1.0
            else:
                surf_sign[s] = 1.0 if v >= 0 else -1.0


@njit(cache=True, _nrt=False)  # once per mode entered; not inlined, no reference counting
def _exit_at_once(model, mode, slide, t, y, K, p, direction, at_start, on_surface, drift, last_kind, jumped, n_ev,
                  tr_table, surf_old, surf_res, slope_old, surf_sign, fixed_sign, fires, xtmp):
    """A transition out of the mode just entered that fires at once, without a step: at the start, on a
    surface the field crosses in the transition's direction; after a transition at a corner of
    switching surfaces, an exit that already holds (on a surface the state lies on, to the domain's
    tolerance, or on any after a reset, ``jumped``, which may move the state across surfaces).  Returns ``(transition or -1, status)``: the status
    is STATUS_OUTSIDE_DOMAIN when the state lies outside the mode's domain by more than rounding and no
    exit holds (the model's domains and transitions disagree).

    After a transition that has ended a sliding motion (``at_start`` then too), the state lies on the
    sliding surface ``on_surface`` (-1: none) up to the integration's ``drift`` off it (a distance):
    the new field may cross it, and the drift counts as rounding in the domain's test.

    Coinciding events: after any transition, a surface the state lies on (to its resolution) that the new
    field crosses in the direction of one of the mode's transitions fires at once, where the state reached it
    from the side that transition fires from (``fires`` bit 4: its side is the one the motion just left kept)
    or from a side no motion watched (bit 8).  Events due at one instant are so processed one after the
    other, each from the mode the previous one entered, the transitions of a mode in their listed order."""
    n = N_STATE or xtmp.shape[0]  # (see the engine's header)
    n_tr = tr_table.shape[0]
    pending = NONE
    dt_nudge = direction * (1e-10 + 16.0 * EPS * abs(t))  # a hair: not a fraction of |t| (1e2 at t = 1e12)
    for i in range(n):
        xtmp[i] = y[i] + dt_nudge * K[0, i]
    if (at_start or n_ev > 0) and slide[0] == 0:
        # A start on a surface (|h| within its rounding) with this mode's field crossing it in the direction
        # of one of its transitions: the transition fires at once, as if the motion had just
        # arrived (it may start a sliding motion), instead of moving on in this mode beyond its
        # surface. Its guard is taken a hair along the motion. The same where a transition has
        # ended a sliding motion: the state lies on the sliding surface, and the new mode's field
        # may cross it (into a new sliding motion, say).
        #   After an event (coinciding events): a surface that the motion reached at the event's instant, from
        # the side its transition fires from (its side kept by _watch_surfaces), fires at once in the order
        # the transitions are listed, each from the mode the previous one entered (a zero-length visit).
        for k in range(n_tr):
            if tr_table[k, 0] != mode or tr_table[k, 2] == 0:
                continue
            s = tr_table[k, 1]
            if (abs(surf_old[s]) > surf_res[s] and s != on_surface) or slope_old[s] * tr_table[k, 2] <= 0.0:
                continue
            if fixed_sign[s] and surf_sign[s] == tr_table[k, 2]:
                continue  # the side an event has just put the state on (the surface just crossed)
            if not at_start and (fixed_sign[s] or ((fires[s] & 8) == 0 and surf_sign[s] != -tr_table[k, 2])):
                continue  # after an event: a surface reached from the side its transition fires from, or one whose
                #           side no motion has watched (as at the start)
            if not at_start and fires[s] & FIRED_NOW:
                continue  # a crossing is one event: a surface crossed at this instant, and not crossed back by any
                #           motion since, is not crossed again without a step (a clock h(t), which stays at zero
                #           through the instant and which every mode's motion crosses the same way)
            if model[GUARD](k, t + dt_nudge, xtmp, p):
                pending = k
                break
    # A state outside the domain of its mode (a transition has led there at a corner of
    # switching surfaces): the exit that holds already (the state lies beyond its surface, in
    # the transition's direction, and its guard holds; the surface just crossed excepted) fires
    # at once. Domain and guards are taken a hair along the motion, so that a condition that is
    # zero here (on the surface just crossed) counts on the side the motion goes to.
    # (after a transition, or at the start; a sliding motion ends on its surface by construction)
    if pending < 0 and slide[0] == 0 and last_kind == EVENT_TRANSITION and not model[IN_DOMAIN](mode, t + dt_nudge, xtmp, p):
        scale = 1.0
        for i in range(n):
            scale = max(scale, abs(y[i]))
        for k in range(n_tr):
            if tr_table[k, 0] != mode or tr_table[k, 2] == 0:
                continue
            s = tr_table[k, 1]
            if fixed_sign[s] or surf_sign[s] != tr_table[k, 2]:
                continue
            if n_ev > 0 and not jumped and abs(surf_old[s]) > DOMAIN_TOLERANCE * scale + 2.0 * drift:
                continue  # a surface the motion has not reached (no reset has moved the state across it)
            if model[GUARD](k, t + dt_nudge, xtmp, p):
                pending = k
                break
        # no exit holds: the domain fails by rounding (a condition on the surface just crossed,
        # with the motion nearly tangent to it), and the run goes on; or by more, and the model's
        # domains and transitions disagree: the run stops (STATUS_OUTSIDE_DOMAIN)
        if pending < 0 and n_ev > 0:  # (a mode given for the start is the caller's choice)
            if model[DOMAIN_MARGIN](mode, t + dt_nudge, xtmp, p) < -DOMAIN_TOLERANCE * scale - 2.0 * drift:
                return NONE, STATUS_OUTSIDE_DOMAIN
    return pending, STATUS_OK


@njit(cache=True, _nrt=False)  # once per event; not inlined, no reference counting
def _refine_event(model, exact, mode, slide, t, h, y, ynew, ysave, K, Ksave, s_e, kind, idx, sgn_ev, s_lo, s_hi, p, var,
                  pidx, rtol, atol, ytmp, work, n_err, affine, taylor, gradients):
    """Refine an event bracketed at the fraction ``s_e`` of the step ``h`` from ``(t, y)`` (``ynew``: the
    state there); returns the event's fraction of the step, with ``ynew`` the state at it.

    Newton on the event function ``g`` (``sgn_ev`` times an indicator, or a sliding motion's exit
    function) of the stepped solution, with its exact slope along the augmented field: a correction
    far below the step is a first-order Taylor step of ``[x, Phi, psi]`` (its second-order term is
    below rounding), a larger one a re-step from ``y``.  The root lies in ``[s_lo, s_hi]``, with
    ``g(s_hi) <= 0`` on the stepped solution: a Newton step out of the bracket known so far is a
    bisection (near a tangency Newton alone wanders off).  Then the event state is pushed, by
    doubling nudges along the field (re-steps beyond 1e-9 of the step), onto or just past the
    switching set, never before it (``g <= 0``) and never beyond ``s_hi``.  ``work``, ``affine``,
    ``taylor`` and ``gradients`` are the integrator's work arrays, in tuples (a call of more than 30
    arguments is one numba cannot inline).
    """
    W, WJ, WP, wv = work
    AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP = affine
    TW, TP, TC = taylor
    hx, hp, gtmp, gptmp = gradients
    n = N_STATE or hx.shape[0]  # (see the engine's header)
    N = y.shape[0]
    for i in range(N):
        ysave[i] = y[i]
    for i in range(N):
        Ksave[0, i] = K[0, i]
    s_tiny = 2.0 * EPS * max(1.0, abs(t) / max(abs(h), 1e-300))
    g_e = sgn_ev * _event_value(model, kind, idx, slide, t + s_e * h, ynew[:n], p, gtmp, gptmp)
    for it in range(64):
        if g_e == 0.0:
            break
        if g_e > 0.0:
            s_lo = max(s_lo, s_e)
        else:
            s_hi = min(s_hi, s_e)
        _aug_rhs_called(model, mode, slide, t + s_e * h, ynew, p, var, pidx, Ksave[1], W, WJ, WP, wv)
        dg = sgn_ev * h * _slope(model, mode, slide, kind, idx, t + s_e * h, ynew[:n], Ksave[1, :n], p, hx, hp, gtmp, gptmp)
        s_new = s_e - g_e / dg if (dg != 0.0 and math.isfinite(dg)) else -1.0
        if not (s_lo <= s_new <= s_hi):
            if s_hi - s_lo <= s_tiny:
                break
            s_new = 0.5 * (s_lo + s_hi)
        if abs(s_new - s_e) <= s_tiny:
            break
        if abs(s_new - s_e) <= 1e-9:
            dt = (s_new - s_e) * h
            for i in range(N):
                ynew[i] += dt * Ksave[1, i]
        else:
            for i in range(N):
                K[0, i] = Ksave[0, i]
            if s_new > 0.0:
                _step(model, exact, mode, slide, t, ysave, s_new * h, p, var, pidx, rtol, atol, K, ynew, ytmp, W, WJ, WP, wv,
                      n_err, AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP, TW, TP, TC)
            else:
                for i in range(N):
                    ynew[i] = ysave[i]
        s_e = s_new
        g_e = sgn_ev * _event_value(model, kind, idx, slide, t + s_e * h, ynew[:n], p, gtmp, gptmp)
    # make sure the event state lies on (or just past) the switching set, never before it
    bump = 2.0 * s_tiny
    for it in range(80):
        if g_e <= 0.0 or s_e >= s_hi:
            break
        ds = min(bump, s_hi - s_e)
        if ds <= 1e-9:
            _aug_rhs_called(model, mode, slide, t + s_e * h, ynew, p, var, pidx, Ksave[1], W, WJ, WP, wv)
            for i in range(N):
                ynew[i] += ds * h * Ksave[1, i]
        else:
            for i in range(N):
                K[0, i] = Ksave[0, i]
            _step(model, exact, mode, slide, t, ysave, (s_e + ds) * h, p, var, pidx, rtol, atol, K, ynew, ytmp, W, WJ, WP,
                  wv, n_err, AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP, TW, TP, TC)
        s_e += ds
        bump *= 2.0
        g_e = sgn_ev * _event_value(model, kind, idx, slide, t + s_e * h, ynew[:n], p, gtmp, gptmp)
    for i in range(N):
        K[0, i] = Ksave[0, i]
    return s_e


@njit(cache=True, inline="always")
def _chatter_width(t, h_scale):
    """The time below which events crowd (chattering): 1e-9 of the step ``h_scale`` (the time scale of
    the motion) plus a few rounding units of ``t``; neither a fraction of ``|t|`` nor of the span."""
    return 16.0 * EPS * abs(t) + 1e-9 * h_scale


@njit(cache=True, _nrt=False)  # not inlined: called only where a new field turns back at its surface
def _goes_on_without_sliding(model, mode_to, s, t_e, xplus, fb, p, tr_table, direction, xn):
    """Whether the mode ``mode_to``, entered across surface ``s`` with a field that turns back across it, simply
    goes on: it has no transition of its own on ``s`` (it does not watch it: a latch's state, a relay's output,
    which hold whatever side of ``s`` the motion is on) and its domain holds a hair along its motion.  Then
    the motion continues in it, and no sliding motion is called for."""
    n = N_STATE or xplus.shape[0]  # (see the engine's header)
    for k in range(tr_table.shape[0]):
        if tr_table[k, 0] == mode_to and tr_table[k, 1] == s:
            return False
    tau = direction * (1e-10 + 16.0 * EPS * abs(t_e))  # a hair (as _exit_at_once's nudge)
    for i in range(n):
        xn[i] = xplus[i] + tau * fb[i]
    return model[IN_DOMAIN](mode_to, t_e + tau, xn, p)


@njit(cache=True, _nrt=False)  # not inlined: called only after a reset that leaves the state on its surface
def _crossing_fires(model, mode_to, s, side, t_e, xplus, fb, p, tr_table, direction, xn):
    """Whether a transition of ``mode_to`` fires where its motion crosses surface ``s`` from ``xplus`` on it
    towards ``side`` (+-1): one on ``s`` in that direction (or either) whose guard holds a hair along the
    motion."""
    n = N_STATE or xplus.shape[0]  # (see the engine's header)
    tau = direction * (1e-10 + 16.0 * EPS * abs(t_e))  # a hair (as _exit_at_once's nudge)
    for i in range(n):
        xn[i] = xplus[i] + tau * fb[i]
    for k in range(tr_table.shape[0]):
        if tr_table[k, 0] != mode_to or tr_table[k, 1] != s:
            continue
        dk = tr_table[k, 2]
        if dk != 0 and dk * side < 0.0:
            continue
        if model[GUARD](k, t_e + tau, xn, p):
            return True
    return False


@njit(cache=True, _nrt=False)  # not inlined: called only for transitions with a reset, it keeps the integrator's loop lean
def _reset_landing(model, k, s, mode_to, t_e, xplus, p, tr_table, direction, cross, den, sig_b, ht, hx, fb, n_ev,
                   chatter_ring, slide, h_scale, xn, fn, wn, wp):
    """After the reset of transition ``k`` on surface ``s``: where the state lies on the surface (or as far
    past it as the motion goes in a few rounding units of t), the new field must take it back to the side
    it came from. Returns ``(status, back)``: ``back`` that side (0: the state is off the surface), and a
    status other than OK where the field pushes it back across (STATUS_SLIDING_UNDEFINED, cause
    SLIDE_RESET_INTO, or STATUS_CHATTERING at the end of a Zeno accumulation) or where the bounce is too
    small to resolve (STATUS_STEP_TOO_SMALL or STATUS_CHATTERING)."""
    n = N_STATE or xplus.shape[0]  # (see the engine's header)
    back = 0.0
    # on the surface: to 1e-12, or to how far the motion goes in a few rounding units of t (an event state
    # lies on or just past the surface at a time on t's grid)
    on_tol = 1e-12 + 16.0 * EPS * abs(t_e) * (abs(den) + abs(sig_b))
    if abs(model[INDICATOR](s, t_e, xplus, p)) <= on_tol:
        back = -1.0 if (tr_table[k, 2] > 0 or (tr_table[k, 2] == 0 and cross > 0)) else 1.0
        rate = direction * sig_b * back
        scale = abs(ht)
        for i in range(n):
            scale += abs(hx[i] * fb[i])
        if rate <= 1e-12 * scale:
            pushes = True
            if rate >= -1e-12 * scale:
                # the new field is tangent to the surface (a plastic impact, e = 0): its rate a hair
                # along the motion decides whether it pushes the state back into the surface
                tau = direction * (1e-6 * h_scale + 16.0 * EPS * abs(t_e))  # 1e-6 of the step, past the rounding of t
                for i in range(n):
                    xn[i] = xplus[i] + tau * fb[i]
                model[VECTOR_FIELD](mode_to, t_e + tau, xn, p, fn)
                pushes = direction * model[INDICATOR_RATE](s, t_e + tau, xn, fn, p, wn, wp) * back < 0.0
            if pushes and not _crossing_fires(model, mode_to, s, -back, t_e, xplus, fb, p, tr_table, direction, xn):
                # the new mode has no transition that this crossing of its surface fires (none watches it that
                # way, or their guards fail a hair along the motion: a walker's legs swapped at heel strike
                # leave the swing foot on the ground with the stance leg ahead): the motion goes on across it
                return STATUS_OK, 0.0
            if pushes:
                if n_ev >= 1 and abs(t_e - chatter_ring[(n_ev - 1) % CHATTER_WINDOW]) <= _chatter_width(t_e, h_scale):
                    # the impact before lies below the resolution of the motion: impacts accumulate
                    return STATUS_CHATTERING, back
                if direction * den * back >= 0.0:
                    # the event lies past the surface's extremum (a grazing within the step, found by the
                    # dip search): the state's side is left to the rule after a reset
                    return STATUS_OK, 0.0
                # the reset leaves the state on the surface, and the new field pushes it back across:
                # no motion is defined (a ball that comes to rest on the floor needs a sliding mode)
                slide[0] = SLIDE_RESET_INTO
                slide[1] = k
                return STATUS_SLIDING_UNDEFINED, back
        beyond = -back * model[INDICATOR](s, t_e, xplus, p)
        if beyond > 1e-12 and beyond > (64.0 * EPS * abs(t_e) + 1e-9 * h_scale) * rate:
            # the event state lies past the surface (by the time axis' resolution) farther than the motion
            # after the reset brings it back in a few rounding units of t: a bounce too small to resolve
            if 16.0 * EPS * abs(t_e) > 1e-9 * h_scale:
                return STATUS_STEP_TOO_SMALL, back
            return STATUS_CHATTERING, back
    return STATUS_OK, back


#: the longest run of impacts whose span sets the tolerance of their accumulation point (see _accumulates)
ACCUMULATION_SPAN = 64


@njit(cache=True, _nrt=False)  # not inlined: called only after an impact of a transition that can stick
def _accumulates(model, k, s, t_e, xplus, fplus, den, p, ev, ev_int, n_ev, rtol, wn, wp):
    """Whether the impacts of transition ``k`` (on surface ``s``, which can stick: a transition from the same
    mode on the same surface leads into a stuck mode) accumulate: the last ``ACCUMULATION_IMPACTS`` events
    are its impacts, their intervals shrink by the ratio ``lam = -w+ / w-`` of the relative velocities
    across the last one (``den = w-``; ``w+`` along the field ``fplus`` after it, at ``xplus``), and the
    times' accumulation point (``accumulation_point``) is known to ``rtol`` of the impacts' span (or no
    better: the estimate has stopped improving near that, or the last interval is 1e-4 of the span).  Then
    the run stops (STATUS_ACCUMULATION) and the flow jumps to the accumulation point."""
    if not den < 0.0 and not den > 0.0:
        return False
    lam = -model[INDICATOR_RATE](s, t_e, xplus, fplus, p, wn, wp) / den
    if not (lam > 0.0 and lam < 1.0):
        return False
    chain = 0
    while chain < ACCUMULATION_SPAN and chain < n_ev:
        r = n_ev - 1 - chain
        if ev_int[r, LOG_TRANSITION] != k or ev_int[r, LOG_KIND] != EVENT_TRANSITION:
            break
        chain += 1
    if chain < ACCUMULATION_IMPACTS:
        return False
    m = n_ev - 1
    estimate, error = accumulation_point_c(ev[m - 4, 0], ev[m - 3, 0], ev[m - 2, 0], ev[m - 1, 0], ev[m, 0], lam)
    before, error_before = accumulation_point_c(ev[m - 5, 0], ev[m - 4, 0], ev[m - 3, 0], ev[m - 2, 0], ev[m - 1, 0],
                                                lam)
    if not error < math.inf:
        return False
    span = ev[m, 0] - ev[n_ev - chain, 0]
    tol = rtol * span + 64.0 * EPS * abs(ev[m, 0])
    if error <= tol:
        return True
    if error_before <= 1e3 * tol and error >= error_before:
        return True  # the estimate no longer improves: the impacts' times are as precise as they get
    return ev[m, 0] - ev[m - 1, 0] <= 1e-4 * span


@njit(cache=True, _nrt=False)  # once per event; not inlined, no reference counting
def _apply_transition(model, k, s, mode, t_e, x_e, p, tr_table, direction, known_side, n_ev, chatter_ring, hx, hp, fa,
                      fb, fplus, xplus, gx, gt, gp, slide, surf_sign, fixed_sign, from_sliding, h_scale, xn, fn, wn,
                      wp):
    """Apply transition ``k`` (surface ``s``) at the event ``(t_e, x_e)`` in ``mode``: the reset
    ``xplus = g(x_e)`` with ``g_x, g_t, g_p``, the surface's gradient ``h_x, h_p``, the fields ``f-``
    (``fa``) and ``f+`` (``fplus``) and the denominator ``h_x f- + h_t`` of eq. (9), which
    ``_saltation_jump`` turns into the saltation matrix.

    Where no reset applies and the new field pushes back into the surface, a Filippov sliding motion
    starts (``slide`` set, ``f+`` the sliding field).  Returns ``(status, mode_to, kind, den)``: a
    status other than OK for a tangential crossing, a sliding motion that is not defined, or impacts
    accumulating below the resolution of the state (chattering).

    ``from_sliding``: the transition ends a sliding motion (``_sliding_transition``), whose field the
    caller has put in ``fa``; a new field that pushes back across this surface would call for sliding
    on two surfaces at once, which is not defined here (STATUS_SLIDING_UNDEFINED).  ``known_side``:
    the side of ``s`` the transition leads to where that is known beforehand: +-1 where it fires at
    once, +-2 where it is the way back of an excursion too shallow to resolve (whose crossings may
    still accumulate: chattering); 0: the side the motion crosses to, by the sign of ``h_x f- + h_t``.
    """
    n = N_STATE or fa.shape[0]  # (see the engine's header)
    kind_logged = EVENT_TRANSITION
    mode_to = tr_table[k, 3]
    ht = model[INDICATOR_GRAD](s, t_e, x_e, p, hx, hp)
    if not from_sliding:
        model[VECTOR_FIELD](mode, t_e, x_e, p, fa)
    den = ht
    for i in range(n):
        den += hx[i] * fa[i]
    if tr_table[k, 4] != 0:
        model[RESET_MAP](k, t_e, x_e, p, xplus)
        model[RESET_JAC](k, t_e, x_e, p, gx, gt, gp)
    else:
        for i in range(n):
            xplus[i] = x_e[i]
    model[VECTOR_FIELD](mode_to, t_e, xplus, p, fb)
    sig_b = ht
    for i in range(n):
        sig_b += hx[i] * fb[i]
    # the side it leads to: known where it fired at once, or where it is the way back of an excursion
    # too shallow to resolve (see _surface_crossings); else the side the motion crosses to
    at_once = abs(known_side) == 1.0
    cross = (1.0 if known_side > 0 else -1.0) if known_side != 0.0 else (1.0 if direction * den > 0 else -1.0)
    if den == 0.0 or not math.isfinite(den):
        return STATUS_TANGENTIAL, mode_to, EVENT_TRANSITION, den
    if not at_once and tr_table[k, 2] != 0 and direction * den * tr_table[k, 2] <= 0.0 and n_ev >= 8:
        # a "crossing" that moves against its transition's direction, after at least 8 events within
        # 1e-6 (relative) of it: events accumulate below the resolution of the state (impacts of a
        # ball coming to rest on a moving table, say), and going on would pass through the surface
        # (a corner's few events at one instant are no accumulation)
        crowd = 0
        for j in range(min(n_ev, CHATTER_WINDOW)):
            if abs(t_e - chatter_ring[j]) <= 1e-6 * max(1.0, abs(t_e)):
                crowd += 1
        if crowd >= 8:
            return STATUS_CHATTERING, mode_to, EVENT_TRANSITION, den
    back = 0.0  # after a reset that leaves the state on the surface: the side it must go back to
    if tr_table[k, 5] != 0 and not from_sliding:  # an impact (a reset of logic states only is a mode switch)
        code, back = _reset_landing(model, k, s, mode_to, t_e, xplus, p, tr_table, direction, cross, den, sig_b, ht,
                                    hx, fb, n_ev, chatter_ring, slide, h_scale, xn, fn, wn, wp)
        if code != STATUS_OK:
            return code, mode_to, EVENT_TRANSITION, den
    goes_on = False
    if tr_table[k, 5] == 0 and direction * sig_b * cross < 0.0 and not from_sliding:
        goes_on = _goes_on_without_sliding(model, mode_to, s, t_e, xplus, fb, p, tr_table, direction, xn)
    if tr_table[k, 5] == 0 and direction * sig_b * cross < 0.0 and not goes_on:
        # no jump, and the new field pushes back: Filippov sliding along the surface (not defined where the
        # switch also resets logic states: the sliding motion would need both modes' memory at once)
        if den == sig_b or from_sliding or tr_table[k, 4] != 0:
            return STATUS_SLIDING_UNDEFINED, mode_to, EVENT_TRANSITION, den
        alpha = den / (den - sig_b)
        for i in range(n):
            fplus[i] = fa[i] + alpha * (fb[i] - fa[i])
        slide[0] = 1
        slide[1] = mode
        slide[2] = mode_to
        slide[3] = s
        slide[4] = 1 if cross > 0 else -1
        kind_logged = EVENT_SLIDING_START
    else:
        for i in range(n):
            fplus[i] = fb[i]
    # the side of the surface the motion continues on (after a reset it may be the old one)
    h_after = model[INDICATOR](s, t_e, xplus, p)
    if goes_on:
        surf_sign[s] = -cross  # the new mode's motion turns back across the surface it does not watch
    elif slide[0] == 1 or tr_table[k, 5] == 0:
        surf_sign[s] = cross
    elif back != 0.0:
        surf_sign[s] = back
    elif abs(h_after) > _surface_resolution(model, s, t_e, xplus, p, wn, wp):
        surf_sign[s] = 1.0 if h_after > 0 else -1.0
    elif direction * sig_b != 0.0:
        surf_sign[s] = 1.0 if direction * sig_b > 0 else -1.0
    else:
        surf_sign[s] = cross
    fixed_sign[s] = True
    return STATUS_OK, mode_to, kind_logged, den


@njit(cache=True, _nrt=False)  # once per event; not inlined, no reference counting
def _leave_sliding(model, kind, mode, slide, t_e, x_e, p, hx, hp, fa, fplus, xplus, WJ, WP, wv, W, surf_sign,
                   fixed_sign):
    """End a sliding motion where side a (``kind`` 1) or side b (``kind`` 2) turns tangent: the event
    function's gradient (the exit side's Lie derivative ``h_x f + h_t``, signed) in ``hx, hp``, the
    sliding field ``f-`` (``fa``) and the exit side's field ``f+`` (``fplus``), for eq. (9) without a
    reset.  Returns ``(mode_from, mode_to, den)``.
    """
    n = N_STATE or fa.shape[0]  # (see the engine's header)
    exit_mode = slide[1] if kind == 1 else slide[2]
    _field_called(model, mode, slide, t_e, x_e, p, fa, WJ, WP, wv, W)
    sgl = 1.0 if kind == 1 else -1.0
    sgl = sgl * slide[4]
    model[LIE_DERIVATIVE](exit_mode, slide[3], t_e, x_e, p, hx, hp)
    for i in range(n):
        hx[i] *= sgl
    for j in range(hp.shape[0]):
        hp[j] *= sgl
    den = sgl * model[LIE_DERIVATIVE_DT](exit_mode, slide[3], t_e, x_e, p)
    for i in range(n):
        den += hx[i] * fa[i]
    for i in range(n):
        xplus[i] = x_e[i]
    model[VECTOR_FIELD](exit_mode, t_e, xplus, p, fplus)
    crossing_sign = slide[4]
    surf_sign[slide[3]] = -crossing_sign if kind == 1 else crossing_sign
    fixed_sign[slide[3]] = True
    mode_from = slide[2] if kind == 1 else slide[1]
    mode_to = exit_mode
    slide[0] = 0
    if den == 0.0:
        den = 1e-300
    return mode_from, mode_to, den


@njit(cache=True, _nrt=False)
def _sliding_side(model, slide, side, t, x, p, hs, hsp, out):
    """A sliding state ``x`` moved a hair (``SIDE_NUDGE`` of its size) to the side of its surface where
    the indicator has the sign ``side`` (mode a's side is ``-slide[4]``, b's ``slide[4]``), into
    ``out``: where that mode's guards and domain are taken, so that their conditions on the surface
    itself are not decided by rounding.  The state is moved along the indicator's gradient, and only
    as far as needed (not when the integration has left it that far on that side already); returns
    the distance moved (the integration's drift off the surface, or the hair)."""
    n = N_STATE or x.shape[0]  # (see the engine's header)
    s = slide[3]
    h = model[INDICATOR](s, t, x, p)
    model[INDICATOR_GRAD](s, t, x, p, hs, hsp)
    g2 = 0.0
    scale = 1.0
    for i in range(n):
        g2 += hs[i] * hs[i]
        scale = max(scale, abs(x[i]))
    c = 0.0
    if g2 > 0.0 and math.isfinite(g2):
        target = side * SIDE_NUDGE * scale * math.sqrt(g2)
        if side * h < side * target:
            c = (target - h) / g2
    for i in range(n):
        out[i] = x[i] + c * hs[i]
    return abs(c) * math.sqrt(g2)


@njit(cache=True, _nrt=False)
def _sliding_match(model, slide, w, cross, t, x, p, tr_table, hs, hsp, xside):
    """Where a sliding motion crosses surface ``w`` (not its own) to the side ``cross``: ``(ka, kb)``, the
    first transition out of its mode a (b) on ``w`` in that direction whose guard holds on a's (b's) side of
    the sliding surface, or -1 for none."""
    ka = NONE
    kb = NONE
    n_tr = tr_table.shape[0]
    for j in range(1, 3):
        m = slide[j]
        side = -slide[4] if j == 1 else slide[4]
        moved = False
        for k in range(n_tr):
            if tr_table[k, 0] != m or tr_table[k, 1] != w:
                continue
            dk = tr_table[k, 2]
            if dk != 0 and dk != cross:
                continue
            if not moved:
                _sliding_side(model, slide, side, t, x, p, hs, hsp, xside)
                moved = True
            if model[GUARD](k, t, xside, p):
                if j == 1:
                    ka = k
                else:
                    kb = k
                break
    return ka, kb


@njit(cache=True, _nrt=False)
def _sliding_transition(model, slide, ka, kb, t_e, x_e, p, tr_table, direction, hs, hsp, fc, fd):
    """Which transition ends a sliding motion (modes a, b on surface s) where it meets another surface on
    which a transition out of a (``ka``) or b (``kb``, -1 for none) holds: ``(transition, mode, status)``.

    Beyond that surface, a's side of s belongs to the target c of ``ka`` (or still to a), b's side to the
    target d of ``kb`` (or to b).  One transition, or two into one mode: it fires.  Two into different
    modes: if c's field crosses s towards b's side and d's does not push back, the motion goes on in d
    (``kb`` fires); if neither pushes towards s, both leave the surface and the motion is not unique
    (STATUS_SLIDING_UNDEFINED, mode -1); otherwise ``ka`` fires (c leaves s on its side, or both push
    towards s and c's own transition on s starts their sliding motion at once).
    """
    n = N_STATE or x_e.shape[0]  # (see the engine's header)
    if ka < 0:
        return kb, NONE, STATUS_OK
    if kb < 0:
        return ka, NONE, STATUS_OK
    c = tr_table[ka, 3]
    d = tr_table[kb, 3]
    if c == d:
        return ka, NONE, STATUS_OK
    ht = model[INDICATOR_GRAD](slide[3], t_e, x_e, p, hs, hsp)
    model[VECTOR_FIELD](c, t_e, x_e, p, fc)
    model[VECTOR_FIELD](d, t_e, x_e, p, fd)
    sc = ht
    sd = ht
    for i in range(n):
        sc += hs[i] * fc[i]
        sd += hs[i] * fd[i]
    towards_c = direction * sc * slide[4] > 0.0
    towards_d = direction * sd * slide[4] < 0.0
    if towards_c and not towards_d:
        return kb, NONE, STATUS_OK
    if not towards_c and not towards_d:
        return NONE, NONE, STATUS_SLIDING_UNDEFINED
    return ka, NONE, STATUS_OK


@njit(cache=True, _nrt=False)
def _sliding_region_margin(model, slide, t, x, p, hs, hsp, xside):
    """How far a sliding state lies inside the domains of the motion's two modes, each taken on its own
    side of the surface (``_sliding_side``), relative to the state's size (negative: outside):
    ``(margin, mode)`` of the nearer boundary (``inf`` for modes without a domain).  Twice the distance
    the state was moved counts as inside: where the integration has drifted off the surface (by its
    local errors, in a curved surface's sliding motion at loose tolerances), moving the state to a side
    moves it along the other conditions too."""
    n = N_STATE or x.shape[0]  # (see the engine's header)
    scale = 1.0
    for i in range(n):
        scale = max(scale, abs(x[i]))
    best = np.inf
    which = slide[1]
    for j in range(1, 3):
        moved = _sliding_side(model, slide, -slide[4] if j == 1 else slide[4], t, x, p, hs, hsp, xside)
        m = (model[DOMAIN_MARGIN](slide[j], t, xside, p) + 2.0 * moved) / scale
        if m < best:
            best = m
            which = slide[j]
    return best, which


@njit(cache=True, _nrt=False)
def _sliding_region_end(model, slide, t, h, F, y, p, hs, hsp, xside, xtmp, n_surfaces):
    """A sliding step that ends outside the domain of one of the motion's modes (by more than
    DOMAIN_TOLERANCE): the fraction of the step where it leaves it (bisection on the dense output),
    that mode, and the surface it leaves across (the nearest other surface within 1e-6 of the state's
    size, else the sliding surface: the domain ends where no surface is).  Returns ``(s, mode, surface)``."""
    n = N_STATE or xtmp.shape[0]  # (see the engine's header)
    lo = 0.0
    hi = 1.0
    _dense_eval(F, y, hi, xtmp)
    _, mode_out = _sliding_region_margin(model, slide, t + h, xtmp, p, hs, hsp, xside)
    for _ in range(100):
        if hi - lo <= 4.0 * EPS * max(1.0, hi):
            break
        mid = 0.5 * (lo + hi)
        _dense_eval(F, y, mid, xtmp)
        m, which = _sliding_region_margin(model, slide, t + mid * h, xtmp, p, hs, hsp, xside)
        if m < -DOMAIN_TOLERANCE:
            hi = mid
            mode_out = which
        else:
            lo = mid
    _dense_eval(F, y, hi, xtmp)
    scale = 1.0
    for i in range(n):
        scale = max(scale, abs(xtmp[i]))
    surface = slide[3]
    nearest = 1e-6 * scale
    for w in range(n_surfaces):
        if w == slide[3]:
            continue
        v = model[INDICATOR](w, t + hi * h, xtmp, p)
        model[INDICATOR_GRAD](w, t + hi * h, xtmp, p, hs, hsp)
        g = 0.0
        for i in range(n):
            g += hs[i] * hs[i]
        if g > 0.0 and abs(v) / math.sqrt(g) <= nearest:
            nearest = abs(v) / math.sqrt(g)
            surface = w
    return hi, mode_out, surface


@njit(cache=True, _nrt=False)  # once per event; not inlined, no reference counting
def _saltation_jump(gx, gt, gp, fa, fplus, hx, hp, den, y, var, pidx, S, w, Phi_tmp, psi_tmp):
    """The saltation matrix of eq. (9), with a reset ``g`` (the identity without one), and the jumps of
    the fundamental solution matrix and the parameter sensitivity: the one place where they happen.

    ``S = g_x + w h_x / den`` with ``w = f+ - g_x f- - g_t`` and ``den = h_x f- + h_t`` (the event
    function's rate along the old field ``f-``: an indicator's, or a sliding exit's), into ``S``;
    ``Phi <- S Phi`` and ``psi <- S psi + g_p[:, k] + w h_p[k] / den`` for parameter ``k = pidx``, in
    ``y = [x, Phi, psi]`` when ``var``.
    """
    n = N_STATE or fa.shape[0]
    for i in range(n):
        acc = fplus[i] - gt[i]
        for j in range(n):
            acc -= gx[i, j] * fa[j]
        w[i] = acc
    for i in range(n):
        for j in range(n):
            S[i, j] = gx[i, j] + w[i] * hx[j] / den
    if var:
        for i in range(n):
            for j in range(n):
                acc = 0.0
                for k2 in range(n):
                    acc += S[i, k2] * y[n + k2 * n + j]
                Phi_tmp[i, j] = acc
        off = n + n * n
        for i in range(n):
            acc = 0.0
            for k2 in range(n):
                acc += S[i, k2] * y[off + k2]
            if pidx >= 0:
                acc += gp[i, pidx] + w[i] * hp[pidx] / den
            psi_tmp[i] = acc
        for i in range(n):
            for j in range(n):
                y[n + i * n + j] = Phi_tmp[i, j]
            y[off + i] = psi_tmp[i]


@njit(cache=True, inline="always")  # once per event; inlined into the loop, it allocates nothing
def _log_event(ev, ev_int, n_ev, t_e, kind, transition, surface, mode_from, mode_to, x_minus, x_plus, S):
    """Append an event to the log (rows ``(t, x-, x+, S)`` and ``(kind, transition, surface, mode from,
    mode to)``, as ``_contract.py`` lays them out); the caller has made room for it."""
    n = N_STATE or x_minus.shape[0]
    o_xm, o_xp, o_s, _ = event_row_offsets_c(n)
    ev[n_ev, 0] = t_e
    ev_int[n_ev, LOG_KIND] = kind
    ev_int[n_ev, LOG_TRANSITION] = transition
    ev_int[n_ev, LOG_SURFACE] = surface
    ev_int[n_ev, LOG_MODE_FROM] = mode_from
    ev_int[n_ev, LOG_MODE_TO] = mode_to
    for i in range(n):
        ev[n_ev, o_xm + i] = x_minus[i]
        ev[n_ev, o_xp + i] = x_plus[i]
        for j in range(n):
            ev[n_ev, o_s + i * n + j] = S[i, j]


@njit(cache=True, inline="always")  # its arrays are the kernel's own: inlined, nothing is passed
def _pack_result(t, y, var, xmin, xmax, K, ev, ev_int, n_ev, rec, rec_F, n_rec, status, info_mode, info_surface,
                 n_steps, n_rejected, mode, slide, mode0):
    """The result of an integration as two packed arrays (each returned array costs a conversion), laid
    out as ``_contract.py`` says and read by ``saltation.engine.flow.Flow._unpack``."""
    n = N_STATE or xmin.shape[0]
    # floats: t, x, Phi, psi, x_min, x_max, f at the end; the event log's rows (t, x-, x+, S); the steps'
    # rows (start, size, end fraction, start state); their dense-output coefficients
    o_x, o_phi, _, o_min, o_max, o_vel, n_out = result_offsets_c(n)
    w_ev = ev.shape[1]
    w_rec = rec.shape[1]
    out = np.zeros(n_out + n_ev * w_ev + n_rec * (w_rec + DENSE_ROWS * n))
    out[0] = t
    for i in range(n):
        out[o_x + i] = y[i]
        out[o_min + i] = xmin[i]
        out[o_max + i] = xmax[i]
        out[o_vel + i] = K[0, i]  # the field (or sliding field) at the end
    if var:
        for i in range(n * n + n):  # Phi, then psi
            out[o_phi + i] = y[n + i]
    at = n_out
    for r in range(n_ev):
        for j in range(w_ev):
            out[at] = ev[r, j]
            at += 1
    for r in range(n_rec):
        for j in range(w_rec):
            out[at] = rec[r, j]
            at += 1
    for r in range(n_rec):
        for q in range(DENSE_ROWS):
            for j in range(n):
                out[at] = rec_F[r, q, j]
                at += 1
    # integers: status, mode and surface of a failure, events, steps, rejected steps, final mode,
    # sliding state (5), initial mode; the event log's rows (kind, transition, surface, mode from, mode to)
    info = np.zeros(INFO_EVENT_LOG + EVENT_LOG_INTS * n_ev, dtype=np.int64)
    info[INFO_STATUS] = status
    info[INFO_FAILED_MODE] = info_mode
    info[INFO_FAILED_SURFACE] = info_surface
    info[INFO_EVENTS] = n_ev
    info[INFO_STEPS] = n_steps
    info[INFO_REJECTED] = n_rejected
    info[INFO_FINAL_MODE] = mode
    for i in range(SLIDE_WIDTH):
        info[INFO_SLIDE + i] = slide[i]
    info[INFO_INITIAL_MODE] = mode0
    for r in range(n_ev):
        for j in range(EVENT_LOG_INTS):
            info[INFO_EVENT_LOG + EVENT_LOG_INTS * r + j] = ev_int[r, j]
    return info, out


@njit(cache=True, inline="always")  # once per sliding step
def _sliding_exit_event(model, exact, mode, slide, t, h, y, ynew, t_new, K, F, xtmp, W, WJ, WP, wv, TC, p, samples, gtmp, gptmp,
                        no_dip):
    """The first exit of the sliding motion within the accepted step from ``(t, y)`` to ``(t_new, ynew)``,
    where the field of side a (kind 1) or b (kind 2) turns tangent: ``(fraction of the step, kind,
    surface, the end of its root's bracket, whether the dense output was built)``, the kind -1 when
    there is none.
    """
    n = N_STATE or F.shape[1]
    have_dense = False
    best_s = 2.0
    best_kind = NONE
    best_idx = NONE
    best_hi = 1.0  # where the exit function is known to be <= 0: the end of its root's bracket
    for kind in (np.int64(1), np.int64(2)):
        v1 = _event_value(model, kind, NONE, slide, t_new, ynew[:n], p, gtmp, gptmp)
        # A sliding field is often so simple that the step control allows steps over
        # much of a forcing period, while an exit function with explicit time dependence
        # may dip below zero and recover (or turn negative more than once) within the
        # step: it is sampled inside, a local minimum of the samples is searched for a
        # dip below zero (golden section between its neighbours), and the first sign
        # change is the one located.
        if not have_dense:
            _dense(model, exact, mode, slide, t, y, ynew, h, p, K, F, xtmp, W, WJ, WP, wv, TC)
            have_dense = True
        sb = 1.0
        samples[0] = _event_value(model, kind, NONE, slide, t, y[:n], p, gtmp, gptmp)
        samples[SLIDING_EXIT_SAMPLES] = v1
        for j in range(1, SLIDING_EXIT_SAMPLES):
            samples[j] = _dense_event(model, kind, NONE, slide, 1.0, t, h, F, y, j / SLIDING_EXIT_SAMPLES, p,
                                      xtmp, gtmp, gptmp, exact, TC)
        # (inside the step only where the step's own solution has not refuted the dense output's dip)
        for j in range(SLIDING_EXIT_SAMPLES if no_dip[no_dip.shape[0] - 3 + kind] else 1, SLIDING_EXIT_SAMPLES + 1):
            sj = j / SLIDING_EXIT_SAMPLES
            if samples[j] <= 0.0:
                sb = sj
                v1 = samples[j]
                break
            if j < SLIDING_EXIT_SAMPLES and samples[j] <= samples[j - 1] and samples[j] <= samples[j + 1]:
                smin, vmin = _dip_search(model, kind, NONE, slide, 1.0, t, h, F, y, p, xtmp, gtmp, gptmp,
                                         (j - 1) / SLIDING_EXIT_SAMPLES, (j + 1) / SLIDING_EXIT_SAMPLES, exact, TC, False)
                if vmin <= 0.0:
                    sb = smin
                    v1 = vmin
                    break
        if v1 <= 0.0:
            if not have_dense:
                _dense(model, exact, mode, slide, t, y, ynew, h, p, K, F, xtmp, W, WJ, WP, wv, TC)
                have_dense = True
            sr = _bracket_root(model, kind, NONE, slide, 1.0, t, h, F, y, 0.0, sb, min(v1, -1e-300), p, xtmp, gtmp, gptmp,
                               exact, TC)
            if sr < best_s:
                best_s = sr
                best_kind = kind
                best_idx = slide[3]
                best_hi = sb
    return best_s, best_kind, best_idx, best_hi, have_dense


@njit(cache=True, _nrt=False)  # compiled for SURFACE_STEP_SIGNATURE only, called through SURFACE_STEP_ROW
def _surface_step(model, exact, mode, slide, s, t, h, y, ynew, t_new, K, F, xtmp, W, WJ, WP, wv, TC, p, gtmp, gptmp, hx,
                  hp, direction, fires, surf_sign, surf_old, surf_res, surf_new, slope_old, slope_new, no_dip, have_dense):
    """Surface ``s`` over the accepted step from ``(t, y)`` to ``(t_new, ynew)``, of a mode or of a sliding
    motion: its value and slope at the step's end (to ``surf_new``, ``slope_new``), and, where a
    transition may fire on it (a sign change towards a side some transition crosses to, or a dip
    either way that the step's own solution has not refuted), its crossings (``_surface_crossings``).
    Returns ``(whether it has crossings to match, s1, s2, s_lo, s_dip, known, have_dense)``: the
    caller matches them with the transitions of its mode (or of the sliding motion's two modes)."""
    n = N_STATE or xtmp.shape[0]
    v = model[INDICATOR](s, t_new, ynew[:n], p)
    surf_new[s] = v
    sl = direction * _slope(model, mode, slide, KIND_INDICATOR, s, t_new, ynew[:n], K[12, :n], p, hx, hp, gtmp, gptmp)
    slope_new[s] = sl
    sg = surf_sign[s]
    to_other = (fires[s] & (1 if sg > 0.0 else 2)) != 0  # a transition crosses to side -sg
    to_own = (fires[s] & (2 if sg > 0.0 else 1)) != 0
    # a dip: the slope turns within the step from towards the surface to away from it; or a step from the surface
    # (after an event on it) moving away that ends on its side moving away, within which the motion may have
    # turned back through the surface and out again (an impact's short flight while the relative acceleration
    # changes sign)
    dip = (to_other or to_own) and not no_dip[s] and sg * sl > 0.0 and (
        sg * slope_old[s] < 0.0 or (abs(surf_old[s]) <= surf_res[s] and sg * slope_old[s] > 0.0 and sg * v > 0.0))
    if not (to_other and sg * v <= 0.0) and not dip:
        return False, 2.0, 2.0, 0.0, 1.0, False, have_dense
    if not have_dense:
        _dense(model, exact, mode, slide, t, y, ynew, h, p, K, F, xtmp, W, WJ, WP, wv, TC)
    s1, s2, s_lo, s_dip, known = _surface_crossings(model, s, slide, sg, t, h, F, y, p, xtmp, gtmp, gptmp, exact, TC,
                                                    surf_old[s], surf_res[s], slope_old[s], v, sl, dip)
    return True, s1, s2, s_lo, s_dip, known, True


@njit(cache=True, inline="always")
def _crossing_event(sr, which, surface, tr, tr2, cross, s_lo, s_dip):
    """The candidate event of a crossing of ``surface`` at the fraction ``sr`` of the step: its way in
    (``which`` 0) or, past a dip's bottom ``s_dip``, its way back (1), where transition ``tr`` fires (and
    ``tr2``, a sliding motion's other mode's).  Returns the loop's ``best_*`` in their order: ``(s, kind,
    surface, tr, tr2, sign of the event function, bracket of its root (lo, hi), whether it is a dip's)``,
    ``cross`` being the new side in the direction of travel."""
    lo = s_lo if which == 0 else s_dip
    hi = s_dip if which == 0 else 1.0
    return sr, KIND_INDICATOR, surface, tr, tr2, -cross, lo, hi, s_dip < 1.0


@njit(cache=True, _nrt=False)  # compiled for SLIDING_EVENTS_SIGNATURE only, called through SLIDING_EVENTS_ROW
def _sliding_events(model, surface_step, exact, mode, slide, t, h, y, ynew, t_new, K, F, xtmp, W, WJ, WP, wv, TC, p, samples, gtmp,
                    gptmp, hx, hp, hs, hsp, xside, direction, tr_table, watched, fires, surf_sign, surf_old, surf_res,
                    surf_new, slope_old, slope_new, no_dip):
    """The first event of a sliding step from ``(t, y)`` to ``(t_new, ynew)``: an exit (kind 1 or 2,
    ``_sliding_exit_event``), or a crossing of a watched surface (kind 0) where a transition out of
    either mode holds (``_sliding_match``: ``best_tr``, ``best_tr2`` for modes a and b); and where the
    motion leaves the domain of one of its modes (``_sliding_region_margin``; 2.0 for nowhere).
    Returns ``(s, kind, surface, ka, kb, whether the dense output was built, s_out, mode_out,
    surface_out)``; the watched surfaces' values and slopes at the step's end go to ``surf_new``,
    ``slope_new``, as in the step of a mode."""
    n = N_STATE or xtmp.shape[0]  # (see the engine's header)
    best_s, best_kind, best_idx, best_hi, have_dense = _sliding_exit_event(
        model, exact, mode, slide, t, h, y, ynew, t_new, K, F, xtmp, W, WJ, WP, wv, TC, p, samples, gtmp, gptmp, no_dip)
    best_tr = NONE
    best_tr2 = NONE
    best_sgn = 1.0  # the event function's sign, the bracket of its root and whether it is a dip's (see _refine_event)
    best_lo = 0.0
    best_dip = best_hi < 1.0  # an exit inside the step: seen on the dense output only
    for s in range(watched.shape[0]):
        if not watched[s]:
            continue
        crossing, s1, s2, s_lo, s_dip, known, have_dense = surface_step(
            model, exact, mode, slide, s, t, h, y, ynew, t_new, K, F, xtmp, W, WJ, WP, wv, TC, p, gtmp, gptmp, hx, hp,
            direction, fires, surf_sign, surf_old, surf_res, surf_new, slope_old, slope_new, no_dip, have_dense)
        if not crossing:
            continue
        sg = surf_sign[s]
        for which in range(2):
            sr = s1 if which == 0 else s2
            if sr >= best_s:
                continue
            # the transitions out of the motion's modes there, each with its guard on its own side
            # of the sliding surface
            _dense_eval(F, y, sr, xtmp)
            cross = -sg if which == 0 else sg
            ka, kb = _sliding_match(model, slide, s, cross, t + sr * h, xtmp, p, tr_table, hs, hsp, xside)
            if ka >= 0 or kb >= 0:
                best_s, best_kind, best_idx, best_tr, best_tr2, best_sgn, best_lo, best_hi, best_dip = _crossing_event(
                    sr, which, s, ka, kb, cross, s_lo, s_dip)
                break
    # a sliding motion is defined where both its modes are: where it leaves the domain of either
    s_out = 2.0
    mode_out = NONE
    surface_out = NONE
    margin, _ = _sliding_region_margin(model, slide, t_new, ynew[:n], p, hs, hsp, xside)
    if margin < -DOMAIN_TOLERANCE:
        if not have_dense:
            _dense(model, exact, mode, slide, t, y, ynew, h, p, K, F, xtmp, W, WJ, WP, wv, TC)
            have_dense = True
        s_out, mode_out, surface_out = _sliding_region_end(model, slide, t, h, F, y, p, hs, hsp, xside, xtmp,
                                                           watched.shape[0])
    return (best_s, best_kind, best_idx, best_tr, best_tr2, best_sgn, best_lo, best_hi, best_dip, have_dense, s_out,
            mode_out, surface_out)


@njit(cache=True, _nrt=False)
def _needs_extrema(K, xmin):
    n = N_STATE or xmin.shape[0]
    for i in range(n):
        if K[0, i] * K[12, i] <= 0.0:
            return True
    return False


# --------------------------------------------------------------------------------------------------
# The entry points, ``integrate_kernel`` here and ``correct_periodic`` below, are each compiled with its
# signature from the contract. Python passes the model as the addresses of its compiled functions (an
# integer array, two per function: the C wrapper and the numba entry, as ``Flow`` takes them from the
# dispatchers once) and the affine-mode flags: arrays are typed at once, where a tuple of dispatchers
# would be typed and converted to function types on every call (some 200 microseconds).  They are the
# integrator and the Newton themselves, not wrappers around them: numba links and re-optimizes every
# callee into each caller's library, so a wrapper level costs the integrator's optimization once more
# (some 4 s each on the one-time build).
# --------------------------------------------------------------------------------------------------

@njit(cache=True, _nrt=False)  # compiled for STEPS_SIGNATURE only, called through its address (STEPS_ROW)
def _integrate_steps(model, surface_step, sliding_events, run, arrays, log, loop):
    """The step-and-event loop of :func:`integrate_kernel`, on the arrays it has allocated.

    ``run`` holds the run's settings (a :data:`Settings`), ``arrays`` the work arrays (an :data:`Arrays`),
    ``log`` the event log and recorded steps.  It resumes from, and leaves, its scalar state in the slots
    ``SF_*`` and ``SI_*`` of ``loop.state_f`` and ``loop.state_i`` (see :func:`_loop_state`).  Returns True
    when it has stopped because the event log or the record of steps is full (it allocates nothing): the
    caller doubles them and calls again.
    """
    (exact_affine, t_end, p, var, pidx, rtol, atol, max_step, max_events, max_steps, tr_table, n_surfaces, record,
     n_err, direction, sliding_step_cap) = run  # (the records' fields have the names they are unpacked into)
    (y, ynew, ytmp, ysave, xtmp, fa, fb, fplus, xplus, gt, wvec, psi_tmp, samples, chatter_ring, h_mode, xmin,
     xmax) = arrays.vectors
    K, Ksave, F, gx, gp, S, Phi_tmp = arrays.matrices
    work = arrays.work
    W, WJ, WP, wv = work
    affine = arrays.affine
    AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP = affine
    taylor = arrays.taylor
    TW, TP, TC = taylor
    gradients = arrays.gradients
    hx, hp, gtmp, gptmp = gradients
    surf_sign, surf_old, surf_res, slope_old, surf_new, slope_new = arrays.surfaces
    watched, fixed_sign, no_dip = arrays.flags
    ev, ev_int, rec, rec_F = log
    state_f, state_i, slide, fires = loop
    n = N_STATE or xmin.shape[0]
    N = y.shape[0]
    # while sliding: the sliding surface's gradient and a state moved to one of its sides (_sliding_side),
    # in arrays that only an event's jump (wvec, psi_tmp) or a field's evaluation (W) use otherwise
    hs = psi_tmp
    hsp = W[1]
    xside = wvec
    # views the loop passes on, made once
    K0 = K[0]
    K12 = K[12]
    y_x = y[:n]
    ynew_x = ynew[:n]
    t = state_f[SF_T]
    habs = state_f[SF_STEP]
    drift = state_f[SF_DRIFT]
    h_events = state_f[SF_H_EVENTS]
    mode = state_i[SI_MODE]
    n_ev = state_i[SI_EVENTS]
    n_rec = state_i[SI_RECORDS]
    n_steps = state_i[SI_STEPS]
    n_rejected = state_i[SI_REJECTED]
    status = state_i[SI_STATUS]
    info_mode = state_i[SI_FAILED_MODE]
    info_surface = state_i[SI_FAILED_SURFACE]
    pending = state_i[SI_PENDING]
    last_kind = state_i[SI_LAST_KIND]
    after_sliding = state_i[SI_AFTER_SLIDING]
    need_signs = state_i[SI_NEED_SIGNS] != 0
    last_jump = state_i[SI_LAST_JUMP] != 0
    at_start = state_i[SI_AT_START] != 0
    full = False
    while status == STATUS_OK and (t_end - t) * direction > 0.0:
        if n_ev >= ev.shape[0] or (record and n_rec >= rec.shape[0]):
            full = True  # the caller doubles the logs and calls again: the loop resumes here
            break
        if need_signs:
            _watch_surfaces(model, mode, slide, t, y, K, p, direction, last_kind, tr_table, watched, fires, surf_old,
                            surf_res, slope_old, surf_sign, fixed_sign, hx, hp, gtmp, gptmp)
            pending, status = _exit_at_once(model, mode, slide, t, y, K, p, direction, at_start or after_sliding >= 0,
                                            after_sliding, drift, last_kind, last_jump, n_ev, tr_table, surf_old, surf_res,
                                            slope_old, surf_sign, fixed_sign, fires, xtmp)
            at_start = False
            after_sliding = NONE
            drift = 0.0
            if status != STATUS_OK:
                info_mode = mode
                break
            for s in range(n_surfaces):
                fixed_sign[s] = False
            need_signs = False

        at_once = pending >= 0
        if at_once:
            # a transition has just led into a mode whose exit already holds: that exit fires at once,
            # a segment of zero length, with both saltation matrices (never a step outside the domain)
            best_kind = KIND_INDICATOR
            best_idx = tr_table[pending, 1]
            best_tr = pending
            best_tr2 = NONE
            best_known = False
            pending = NONE
            s_e = 0.0
            h = direction * habs
            for i in range(N):
                ynew[i] = y[i]
        else:
            for s in range(n_surfaces):
                fires[s] &= ~FIRED_BITS  # a step: a new instant
            if n_steps >= max_steps:
                status = STATUS_MAX_STEPS
                info_mode = mode
                break
            remaining = abs(t_end - t)
            habs = min(habs, max_step)
            if slide[0] == 1 and sliding_step_cap > 0.0:
                habs = min(habs, sliding_step_cap)
            exact = exact_affine and slide[0] == 0 and model[AFFINE_MODES][mode]
            if exact:
                # the longest step whose series keeps its digits (_exact_step rejects longer ones): known
                # before the step, so no step is attempted beyond it and rejected (a field that is zero
                # has no such bound)
                mnorm = _affine_norm(AFF_A[mode], AFF_B[mode], AFF_W[mode, 0])
                if mnorm * habs > EXACT_STEP_BOUND:
                    habs = (1.0 - 1e-12) * EXACT_STEP_BOUND / mnorm
            if habs >= remaining or remaining - habs < 1e-12 * remaining:
                habs = remaining
            # attempt a step
            rejected = False
            while True:
                h = direction * habs
                err = _step(model, exact, mode, slide, t, y, h, p, var, pidx, rtol, atol, K, ynew, ytmp, W, WJ, WP, wv, n_err,
                            AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP, TW, TP, TC)
                finite = math.isfinite(err)
                if finite and err <= 1.0:
                    break
                n_rejected += 1
                rejected = True
                if not finite:
                    fin = True
                    for i in range(N):
                        if not math.isfinite(ynew[i]):
                            fin = False
                    if not fin and habs < 1e-10 * max(1.0, abs(t)):
                        status = STATUS_NON_FINITE
                        info_mode = mode
                        break
                    habs *= 0.2
                else:
                    habs *= max(0.2, 0.9 * err ** (-1.0 / 8.0))
                if habs < 10.0 * EPS * max(1.0, abs(t)):
                    status = STATUS_STEP_TOO_SMALL
                    info_mode = mode
                    break
            if status != STATUS_OK:
                break
            n_steps += 1
            t_new = t + h
            if habs == remaining:
                t_new = t_end
            for i in range(n):
                if not math.isfinite(ynew[i]) or not math.isfinite(K[12, i]):
                    status = STATUS_NON_FINITE
                    info_mode = mode
            if status != STATUS_OK:
                break

            # ---------------------------------------------------------------- events
            have_dense = False
            best_s = 2.0
            best_kind = NONE
            best_idx = NONE
            best_tr = NONE
            best_tr2 = NONE
            best_sgn = 1.0  # the event function's sign, the bracket of its root and whether it is a dip's
            best_lo = 0.0
            best_hi = 1.0
            best_dip = False
            best_known = False  # whether the side it leads to is known (the way back of a shallow excursion)
            if slide[0] == 0:
                for s in range(n_surfaces):
                    if not watched[s]:
                        continue
                    crossing, s1, s2, s_lo, s_dip, known, have_dense = surface_step(
                        model, exact, mode, slide, s, t, h, y, ynew, t_new, K, F, xtmp, W, WJ, WP, wv, TC, p, gtmp, gptmp,
                        hx, hp, direction, fires, surf_sign, surf_old, surf_res, surf_new, slope_old, slope_new, no_dip,
                        have_dense)
                    if not crossing:
                        continue
                    sg = surf_sign[s]
                    for which in range(2):
                        # the way in, then (where no transition fires there) the way back of a dip
                        sr = s1 if which == 0 else s2
                        if sr >= best_s:
                            continue
                        _state_at(exact, TC, F, y, sr, h, xtmp)
                        cross = -sg if which == 0 else sg  # new side in the direction of travel
                        k = _firing_transition(model, mode, s, cross, t + sr * h, xtmp, p, tr_table)
                        if k >= 0:
                            best_s, best_kind, best_idx, best_tr, best_tr2, best_sgn, best_lo, best_hi, best_dip = (
                                _crossing_event(sr, which, s, k, NONE, cross, s_lo, s_dip))
                            best_known = known and which == 0
                            break
            else:
                (best_s, best_kind, best_idx, best_tr, best_tr2, best_sgn, best_lo, best_hi, best_dip, have_dense, s_out,
                 mode_out, surface_out) = sliding_events(model, surface_step, exact, mode, slide, t, h, y, ynew, t_new, K, F, xtmp, W, WJ,
                                                          WP, wv, TC, p, samples, gtmp, gptmp, hx, hp, hs, hsp, xside,
                                                          direction, tr_table, watched, fires, surf_sign, surf_old,
                                                          surf_res, surf_new, slope_old, slope_new, no_dip)
                if s_out < best_s:
                    # the motion leaves the domain of one of its modes before any event: not defined
                    status = STATUS_SLIDING_UNDEFINED
                    info_mode = mode_out
                    info_surface = surface_out
                    slide[0] = SLIDE_LEAVES_REGION
                    t = t + s_out * h
                    _dense_eval(F, y, s_out, xtmp)
                    for i in range(n):
                        y[i] = xtmp[i]
                    break

            if best_kind < 0:
                # ----------------------------------------------------------- accept whole step
                if record or _needs_extrema(K, xmin):
                    if not have_dense:
                        _dense(model, exact, mode, slide, t, y, ynew, h, p, K, F, xtmp, W, WJ, WP, wv, TC)
                        have_dense = True
                    _track_extrema(F, y, 1.0, xmin, xmax, K0, K12, xtmp, direction)
                for i in range(n):
                    xmin[i] = min(xmin[i], ynew[i])
                    xmax[i] = max(xmax[i], ynew[i])
                if record:
                    n_rec = _record_step(rec, rec_F, n_rec, t, h, 1.0, y_x, F)
                t = t_new
                TC[MAX_TAYLOR + 3, 0] = 0.0  # the series starts at the old (t, y)
                for i in range(N):
                    y[i] = ynew[i]
                for i in range(N):
                    K[0, i] = K[12, i]
                for s in range(n_surfaces):
                    if watched[s]:
                        surf_old[s] = surf_new[s]
                        slope_old[s] = slope_new[s]
                        if surf_new[s] != 0.0:
                            surf_sign[s] = 1.0 if surf_new[s] > 0 else -1.0
                fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-1.0 / 8.0))
                if rejected and not exact:
                    # no growth right after a rejection (Hairer & Wanner, II.4); an exact step's error
                    # (of its dense output) is a smooth function of h and needs no such caution
                    fac = min(fac, 1.0)
                habs = abs(h) * fac
                if slide[0] == 0:
                    h_mode[mode] = habs
                for s in range(no_dip.shape[0]):
                    no_dip[s] = False
                continue

            # --------------------------------------------------------------- an event
            if best_dip and not exact:
                # a dip through the switching set seen on the dense output: the step's own solution must
                # lie across at the dip's bottom too, else the two differ within the tolerance there and
                # there is no crossing: the step is taken again, without that dip
                second = best_lo > 0.0  # (the event is a dip's way back: its bottom starts the bracket)
                bottom = best_lo if second else best_hi
                _step(model, exact, mode, slide, t, y, bottom * h, p, var, pidx, rtol, atol, K, ynew, ytmp, W, WJ, WP, wv,
                      n_err, AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP, TW, TP, TC)
                g_bottom = best_sgn * _event_value(model, best_kind, best_idx, slide, t + bottom * h, ynew_x, p, gtmp,
                                                   gptmp)
                if (g_bottom < 0.0) if second else (g_bottom > 0.0):
                    no_dip[best_idx if best_kind == KIND_INDICATOR else n_surfaces - 1 + best_kind] = True
                    continue
            # the shortened step that ends at the event must pass the error test too: a step can
            # straddle a thin layer (e.g. where a sliding motion ends) that its own estimate missed
            err_e = _step(model, exact, mode, slide, t, y, best_s * h, p, var, pidx, rtol, atol, K, ynew, ytmp, W, WJ, WP, wv, n_err,
                          AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP, TW, TP, TC)
            if err_e > 1.0 and best_s * habs > 100.0 * EPS * max(1.0, abs(t)):
                n_rejected += 1
                habs = best_s * habs * max(0.2, 0.9 * err_e ** (-1.0 / 8.0))
                continue
            _track_extrema(F, y, best_s, xmin, xmax, K0, K12, xtmp, direction)
            if record:
                n_rec = _record_step(rec, rec_F, n_rec, t, h, best_s, y_x, F)
            s_e = _refine_event(
                model, exact, mode, slide, t, h, y, ynew, ysave, K, Ksave, best_s, best_kind, best_idx, best_sgn, best_lo,
                best_hi, p, var, pidx, rtol, atol, ytmp, work, n_err, affine,
                taylor, gradients)
            for s in range(no_dip.shape[0]):
                no_dip[s] = False
        t_e = t + s_e * h
        # state at the event (before it)
        for i in range(N):
            y[i] = ynew[i]
        x_e = y_x
        mode_from = mode
        kind_logged = EVENT_TRANSITION
        mode_to = mode
        den = 0.0
        # S and the jump of psi are built from: n (hx, hp, ht), f-, f+, g_x, g_t, g_p
        for i in range(n):
            for j in range(n):
                gx[i, j] = 1.0 if i == j else 0.0
            gt[i] = 0.0
            for j in range(gp.shape[1]):
                gp[i, j] = 0.0
        if best_kind == 0:
            from_sliding = slide[0] != 0
            if from_sliding:
                # a sliding motion meets another surface where a transition out of one of its modes
                # holds: the motion ends, from its own field (f-), by the transition that decides
                best_tr, info_mode, status = _sliding_transition(model, slide, best_tr, best_tr2, t_e, x_e, p, tr_table,
                                                                 direction, hx, hp, fb, fplus)
                if status == STATUS_OK:
                    _field_called(model, mode, slide, t_e, x_e, p, fa, WJ, WP, wv, W)
                    mode = tr_table[best_tr, 0]
                    mode_from = mode
                    slide[0] = 0
                    if tr_table[best_tr, 5] == 0:
                        # the state stays on the sliding surface, on the side of the mode whose
                        # transition fired: a new field that crosses the surface fires at once
                        # (_exit_at_once), or at the first step's sign change
                        side = -slide[4] if mode == slide[1] else slide[4]
                        drift = _sliding_side(model, slide, side, t_e, x_e, p, hs, hsp, xside)
                        after_sliding = slide[3]
                        surf_sign[slide[3]] = side
                        fixed_sign[slide[3]] = True
            if status == STATUS_OK:
                known_side = 0.0
                if at_once:
                    known_side = 1.0 if tr_table[best_tr, 2] > 0 else -1.0
                elif best_known:
                    known_side = -2.0 * best_sgn
                status, mode_to, kind_logged, den = _apply_transition(
                    model, best_tr, best_idx, mode, t_e, x_e, p, tr_table, direction, known_side, n_ev, chatter_ring, hx, hp,
                    fa, fb, fplus, xplus, gx, gt, gp, slide, surf_sign, fixed_sign, from_sliding,
                    abs(h), xtmp, wvec, gtmp, gptmp)
                info_mode = mode_to if from_sliding and status == STATUS_SLIDING_UNDEFINED else mode
            if status != STATUS_OK:
                info_surface = best_idx
                if from_sliding and status == STATUS_SLIDING_UNDEFINED:
                    slide[0] = SLIDE_BLOCKED  # (the motion's modes, surface and crossing are kept for the message)
                    t = t_e
                if status == STATUS_CHATTERING or status == STATUS_STEP_TOO_SMALL or slide[0] == SLIDE_RESET_INTO:
                    t = t_e
                break
        else:
            mode_from, mode_to, den = _leave_sliding(
                model, best_kind, mode, slide, t_e, x_e, p, hx, hp, fa, fplus, xplus, WJ, WP, wv, W, surf_sign,
                fixed_sign)
            kind_logged = EVENT_SLIDING_END
        mode = mode_to
        # the saltation matrix, eq. (9), and the jumps of Phi and psi
        _saltation_jump(gx, gt, gp, fa, fplus, hx, hp, den, y, var, pidx, S, wvec, Phi_tmp, psi_tmp)
        # log
        _log_event(ev, ev_int, n_ev, t_e, kind_logged, best_tr, best_idx, mode_from, mode_to, x_e, xplus, S)
        if best_kind == KIND_INDICATOR:
            fires[best_idx] = (fires[best_idx] & ~FIRED_BITS) | FIRED_NOW | (FIRED_POSITIVE if surf_sign[best_idx] > 0 else 0)
        chatter_ring[n_ev % CHATTER_WINDOW] = t_e
        h_events = max(h_events, abs(h))
        last_kind = kind_logged
        last_jump = best_kind == KIND_INDICATOR and tr_table[best_tr, 4] != 0
        n_ev += 1
        for i in range(n):
            y[i] = xplus[i]
            xmin[i] = min(xmin[i], x_e[i], xplus[i])
            xmax[i] = max(xmax[i], x_e[i], xplus[i])
        if n_ev >= max_events:
            status = STATUS_MAX_EVENTS
            info_mode = mode
            info_surface = best_idx
            t = t_e
            break
        if (direction > 0.0 and best_kind == KIND_INDICATOR and kind_logged == EVENT_TRANSITION
                and tr_table[best_tr, 6] >= 0 and tr_table[best_tr, 5] != 0
                and _accumulates(model, best_tr, best_idx, t_e, xplus, fplus, den, p, ev, ev_int, n_ev, rtol, gtmp,
                                 gptmp)):
            # impacts that accumulate where the contact can stick (complete chatter): the run stops after this
            # one, and the flow (saltation.engine.flow) jumps to their limit, into the stuck mode
            status = STATUS_ACCUMULATION
            info_mode = mode
            info_surface = best_idx
            t = t_e
            break
        if 100.0 * EPS * abs(t_e) > h_events:
            # the time axis at t_e cannot resolve the motion: a step is no more than 100 rounding units of t,
            # and event times (each rounded to t's grid) would be off by a sizeable part of a step
            status = STATUS_STEP_TOO_SMALL
            info_mode = mode
            info_surface = best_idx
            t = t_e
            break
        if n_ev >= CHATTER_WINDOW:
            oldest = chatter_ring[n_ev % CHATTER_WINDOW]
            # events that crowd below the resolution of the motion: 1e-9 of the step (the time scale of
            # the motion), or a few rounding units of t (not a fraction of |t| or of the span: events
            # well apart at t = 1e12 are no chattering)
            if abs(t_e - oldest) <= _chatter_width(t_e, abs(h)):
                if EPS * abs(t_e) > 1e-9 * h_events:
                    slide[0] = TIME_UNRESOLVED  # a rounding unit of t is not small beside the motion's steps
                status = STATUS_CHATTERING
                info_mode = mode
                info_surface = best_idx
                t = t_e
                break
        t = t_e
        TC[MAX_TAYLOR + 3, 0] = 0.0
        if abs(t_end - t) <= 4.0 * EPS * max(1.0, abs(t)):
            t = t_end
        _aug_rhs_called(model, mode, slide, t, y, p, var, pidx, K0, W, WJ, WP, wv)
        for i in range(n):
            if not math.isfinite(K[0, i]):
                status = STATUS_NON_FINITE
                info_mode = mode
        if slide[0] == 0 and h_mode[mode] > 0.0:
            habs = h_mode[mode]  # the step that suited this mode when it was left: a better guess than the old mode's
        else:
            habs = max(abs(h) * (1.0 - s_e), abs(h) * 0.5)
        need_signs = True
    _loop_state(state_f, state_i, t, habs, drift, h_events, mode, n_ev, n_rec, n_steps, n_rejected, status, info_mode,
                info_surface, pending, last_kind, after_sliding, need_signs, last_jump, at_start)
    return full


@njit(cache=True, _nrt=False)
def _loop_state(state_f, state_i, t, habs, drift, h_events, mode, n_ev, n_rec, n_steps, n_rejected, status, info_mode,
                info_surface, pending, last_kind, after_sliding, need_signs, last_jump, at_start):
    """Leave the integrator loop's scalar state in its slots (``SF_*``, ``SI_*``; booleans as 0 and 1)."""
    state_f[SF_T] = t
    state_f[SF_STEP] = habs
    state_f[SF_DRIFT] = drift
    state_f[SF_H_EVENTS] = h_events
    state_i[SI_MODE] = mode
    state_i[SI_EVENTS] = n_ev
    state_i[SI_RECORDS] = n_rec
    state_i[SI_STEPS] = n_steps
    state_i[SI_REJECTED] = n_rejected
    state_i[SI_STATUS] = status
    state_i[SI_FAILED_MODE] = info_mode
    state_i[SI_FAILED_SURFACE] = info_surface
    state_i[SI_PENDING] = pending
    state_i[SI_LAST_KIND] = last_kind
    state_i[SI_AFTER_SLIDING] = after_sliding
    state_i[SI_NEED_SIGNS] = 1 if need_signs else 0
    state_i[SI_LAST_JUMP] = 1 if last_jump else 0
    state_i[SI_AT_START] = 1 if at_start else 0


@njit(cache=True, nogil=True)  # compiled for INTEGRATE_SIGNATURE only, by saltation.engine.codegen.load_engine
def integrate_kernel(
    addresses, affine_modes, t0, t_end, x0, mode0, p, var, pidx, rtol, atol, h_init, max_step, max_events, max_steps,
    tr_table, n_surfaces, record, phi0, psi0, control_variational, exact_affine,
):
    """Integrate from ``t0`` to ``t_end`` (either direction), event by event.

    The model comes as the addresses of its compiled functions (see the note above).  Returns
    ``(ints, floats)``, two packed arrays (see ``saltation.engine.flow.Flow._unpack``).
    """
    model = model_from_addresses(addresses, affine_modes)  # noqa: F821
    n = N_STATE or x0.shape[0]
    npar = p.shape[0]
    N = n + n * n + n if var else n
    n_err = N if (var and control_variational) else n
    direction = 1.0 if t_end >= t0 else -1.0

    # The work arrays are views of one block of floats, one of integers and one of flags: three allocations
    # a run, not fifty (and fewer array constructors to compile).
    n_modes = model[AFFINE_MODES].shape[0]
    np1 = max(npar, 1)
    n_float = (36 + MAX_TAYLOR + 4) * N + 21 * n + 10 * n * n + 14 * n + 4 * np1 + 3 * n * np1
    n_float += n_modes * (2 * n * n + 6 * n + 5) + (np1 * (n * n + 3 * n + 2) if exact_affine else 0)
    n_float += 6 * n_surfaces + SLIDING_EXIT_SAMPLES + 1 + CHATTER_WINDOW + SF_WIDTH
    floats = np.zeros(n_float)
    at = 0
    y = floats[at:at + N]
    ynew = floats[at + N:at + 2 * N]
    ytmp = floats[at + 2 * N:at + 3 * N]
    ysave = floats[at + 3 * N:at + 4 * N]
    at += 4 * N
    K = floats[at:at + 16 * N].reshape((16, N))
    Ksave = floats[at + 16 * N:at + 32 * N].reshape((16, N))
    at += 32 * N
    # Taylor coefficients of [x, Phi, psi] of the last exact step; then their number, the fraction of
    # the step taken and the step (see ``_step``)
    TC = floats[at:at + (MAX_TAYLOR + 4) * N].reshape((MAX_TAYLOR + 4, N))
    at += (MAX_TAYLOR + 4) * N
    F = floats[at:at + 7 * n].reshape((7, n))
    wv = floats[at + 7 * n:at + 14 * n].reshape((7, n))
    TW = floats[at + 14 * n:at + 21 * n].reshape((7, n))
    at += 21 * n
    WJ = floats[at:at + 3 * n * n].reshape((3, n, n))
    TP = floats[at + 3 * n * n:at + 6 * n * n].reshape((3, n, n))
    at += 6 * n * n
    gx = floats[at:at + n * n].reshape((n, n))
    S = floats[at + n * n:at + 2 * n * n].reshape((n, n))
    Phi_tmp = floats[at + 2 * n * n:at + 3 * n * n].reshape((n, n))
    at += 4 * n * n  # (one n x n spare)
    xtmp = floats[at:at + n]
    hx = floats[at + n:at + 2 * n]
    gtmp = floats[at + 2 * n:at + 3 * n]
    fa = floats[at + 3 * n:at + 4 * n]
    fb = floats[at + 4 * n:at + 5 * n]
    fplus = floats[at + 5 * n:at + 6 * n]
    xplus = floats[at + 6 * n:at + 7 * n]
    gt = floats[at + 7 * n:at + 8 * n]
    wvec = floats[at + 8 * n:at + 9 * n]
    psi_tmp = floats[at + 9 * n:at + 10 * n]
    xmin = floats[at + 10 * n:at + 11 * n]
    xmax = floats[at + 11 * n:at + 12 * n]
    at += 14 * n  # (two spare)
    hp = floats[at:at + np1]
    gptmp = floats[at + np1:at + 2 * np1]
    at += 2 * np1
    W = floats[at:at + 2 * np1].reshape((2, np1))
    WP = floats[at + 2 * np1:at + 2 * np1 + n * np1].reshape((n, np1))
    gp = floats[at + 2 * np1 + n * np1:at + 2 * np1 + 2 * n * np1].reshape((n, np1))
    at += 2 * np1 + 3 * n * np1  # (one n x np1 spare)

    # exact flows of affine modes: A, B, (omega, phase, d omega/dp, d phase/dp), dA/dp, dB/dp
    AFF_A = floats[at:at + n_modes * n * n].reshape((n_modes, n, n))
    AFF_AP = floats[at + n_modes * n * n:at + 2 * n_modes * n * n].reshape((n_modes, n, n))
    at += 2 * n_modes * n * n
    AFF_B = floats[at:at + n_modes * n * 3].reshape((n_modes, n, 3))
    AFF_BP = floats[at + n_modes * n * 3:at + 2 * n_modes * n * 3].reshape((n_modes, n, 3))
    at += 6 * n_modes * n
    AFF_W = floats[at:at + 4 * n_modes].reshape((n_modes, 4))
    h_mode = floats[at + 4 * n_modes:at + 5 * n_modes]  # the step proposed last in each mode (0: none yet)
    at += 5 * n_modes
    if exact_affine:
        Ap_all = floats[at:at + np1 * n * n].reshape((np1, n, n))
        Bp_all = floats[at + np1 * n * n:at + np1 * (n * n + 3 * n)].reshape((np1, n, 3))
        wp_all = floats[at + np1 * (n * n + 3 * n):at + np1 * (n * n + 3 * n + 2)].reshape((np1, 2))
        at += np1 * (n * n + 3 * n + 2)
        for m in range(n_modes):
            if model[AFFINE_MODES][m]:
                model[AFFINE_PARTS](m, p, AFF_A[m], AFF_B[m], AFF_W[m, :2])
                if var and pidx >= 0:
                    model[AFFINE_PARTS_DP](m, p, Ap_all, Bp_all, wp_all)
                    for i in range(n):
                        for j in range(n):
                            AFF_AP[m, i, j] = Ap_all[pidx, i, j]
                        for j in range(3):
                            AFF_BP[m, i, j] = Bp_all[pidx, i, j]
                    AFF_W[m, 2] = wp_all[pidx, 0]
                    AFF_W[m, 3] = wp_all[pidx, 1]
    surf_sign = floats[at:at + n_surfaces]
    surf_old = floats[at + n_surfaces:at + 2 * n_surfaces]
    # how near zero each indicator is rounding where the mode was entered
    surf_res = floats[at + 2 * n_surfaces:at + 3 * n_surfaces]
    slope_old = floats[at + 3 * n_surfaces:at + 4 * n_surfaces]
    surf_new = floats[at + 4 * n_surfaces:at + 5 * n_surfaces]
    slope_new = floats[at + 5 * n_surfaces:at + 6 * n_surfaces]
    at += 6 * n_surfaces
    samples = floats[at:at + SLIDING_EXIT_SAMPLES + 1]
    at += SLIDING_EXIT_SAMPLES + 1
    chatter_ring = floats[at:at + CHATTER_WINDOW]
    at += CHATTER_WINDOW
    state_f = floats[at:at + SF_WIDTH]

    ints = np.zeros(6 + n_surfaces + SI_WIDTH, dtype=np.int64)
    slide = ints[:6]  # active, mode_a, mode_b, surface, crossing, time direction
    fires = ints[6:6 + n_surfaces]  # new signs with a transition: 1 for -1, 2 for +1, 3 both
    state_i = ints[6 + n_surfaces:]
    bools = np.zeros(3 * n_surfaces + 2, dtype=np.bool_)
    watched = bools[:n_surfaces]
    fixed_sign = bools[n_surfaces:2 * n_surfaces]
    # dips of the dense output the step's own solution did not confirm (surfaces, then a sliding motion's two exits)
    no_dip = bools[2 * n_surfaces:]

    for i in range(n):
        y[i] = x0[i]
    if var:
        for i in range(n):
            for j in range(n):
                y[n + i * n + j] = phi0[i, j]
            y[n + n * n + i] = psi0[i]

    mode = mode0
    slide[5] = 1 if direction > 0 else -1
    t = t0

    # event log
    ev_cap = 16
    ev = np.zeros((ev_cap, event_row_offsets_c(n)[3]))  # t, x-, x+, S (row-major)
    ev_int = np.zeros((ev_cap, EVENT_LOG_INTS), dtype=np.int64)  # kind, transition, surface, mode_from, mode_to
    n_ev = np.int64(0)  # typed, not literal: literal ints specialise (and compile) callees again

    rec_cap = 64 if record else 1
    rec = np.zeros((rec_cap, step_record_width_c(n)))  # start, size, end fraction, start state
    rec_F = np.zeros((rec_cap, DENSE_ROWS, n))
    n_rec = np.int64(0)

    for i in range(n):
        xmin[i] = y[i]
        xmax[i] = y[i]

    status = STATUS_OK
    info_mode = -1
    info_surface = -1
    n_steps = 0
    n_rejected = 0

    _aug_rhs_called(model, mode, slide, t, y, p, var, pidx, K[0], W, WJ, WP, wv)
    for i in range(n):
        if not math.isfinite(K[0, i]) or not math.isfinite(y[i]):
            status = STATUS_NON_FINITE
            info_mode = mode
    tspan = abs(t_end - t0)
    # initial step (Hairer & Wanner, II.4)
    if h_init > 0.0:
        habs = h_init
    else:
        d0 = 0.0
        d1 = 0.0
        for i in range(n):
            sc = atol + rtol * abs(y[i])
            d0 += (y[i] / sc) ** 2
            d1 += (K[0, i] / sc) ** 2
        d0 = math.sqrt(d0 / n)
        d1 = math.sqrt(d1 / n)
        habs = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
        habs = min(habs, tspan if tspan > 0 else 1.0)
        if exact_affine and model[AFFINE_MODES][mode]:
            # an exact step is good for h |M| of order one (``_exact_step``): start there, not from
            # the estimate of a method of order 8 at these tolerances
            habs = max(habs, 0.5 / max(_affine_norm(AFF_A[mode], AFF_B[mode], AFF_W[mode, 0]), 1e-300))
        habs = max(habs, 1e-6 * max(tspan, 1e-300))
        habs = min(habs, 0.1 * tspan) if tspan > 0 else habs
    habs = min(habs, max_step)

    need_signs = True
    pending = NONE  # a transition to fire at once, without a step (see below)
    last_kind = EVENT_TRANSITION  # kind of the last event (the start counts as a transition)
    last_jump = False  # whether the last event's transition had a reset (the state may jump across surfaces)
    at_start = True
    after_sliding = NONE  # the surface of the sliding motion the last event (a transition) has ended
    drift = 0.0  # how far the state lies off that surface (the integration's drift along the motion)
    # a sliding motion steps at most an eighth of the forcing period: its field can be so simple that
    # the error control allows any step, while its exit functions vary with the forcing
    sliding_step_cap = model[FORCING_PERIOD](p) / 8.0
    h_events = 0.0  # the longest step that ended at an event: the time scale of the motion, for a message

    t_far = max(abs(t0), abs(t_end))
    if tspan > 0.0 and 100.0 * EPS * t_far > tspan and EPS * t_far > 1e-9:
        # far from t = 0 (a rounding unit of t above 1e-9), a span of less than a hundred of them: the time
        # axis cannot resolve the motion (nor the end time asked for)
        status = STATUS_STEP_TOO_SMALL
        info_mode = mode
    # The loop runs in a function compiled without reference counting: every array this function passes
    # to a call is otherwise counted up and down around it (two atomic operations), which cost more than
    # a short step's work.  It allocates nothing: when a log is full it returns, and resumes once doubled.
    run = Settings(exact_affine, t_end, p, var, pidx, rtol, atol, max_step, max_events, max_steps, tr_table, n_surfaces,
                   record, n_err, direction, sliding_step_cap)
    arrays = Arrays(
        Vectors(y, ynew, ytmp, ysave, xtmp, fa, fb, fplus, xplus, gt, wvec, psi_tmp, samples, chatter_ring, h_mode, xmin,
                xmax),
        Matrices(K, Ksave, F, gx, gp, S, Phi_tmp), Work(W, WJ, WP, wv), Affine(AFF_A, AFF_B, AFF_W, AFF_AP, AFF_BP),
        Taylor(TW, TP, TC), Gradients(hx, hp, gtmp, gptmp),
        Surfaces(surf_sign, surf_old, surf_res, slope_old, surf_new, slope_new), Flags(watched, fixed_sign, no_dip))
    loop = LoopState(state_f, state_i, slide, fires)
    _loop_state(state_f, state_i, t, habs, drift, h_events, mode, n_ev, n_rec, n_steps, n_rejected, status, info_mode,
                info_surface, pending, last_kind, after_sliding, need_signs, last_jump, at_start)
    surface_step = _function_at(SURFACE_STEP_TYPE, addresses[SURFACE_STEP_ROW, 0], addresses[SURFACE_STEP_ROW, 1])
    sliding_events = _function_at(SLIDING_EVENTS_TYPE, addresses[SLIDING_EVENTS_ROW, 0], addresses[SLIDING_EVENTS_ROW, 1])
    integrate_steps = _function_at(STEPS_TYPE, addresses[STEPS_ROW, 0], addresses[STEPS_ROW, 1])
    while integrate_steps(model, surface_step, sliding_events, run, arrays, Log(ev, ev_int, rec, rec_F), loop):
        if state_i[SI_EVENTS] >= ev.shape[0]:
            ev = _resized_rows(ev, 2 * ev.shape[0])
            ev_int = _resized_rows(ev_int, 2 * ev_int.shape[0])
        if record and state_i[SI_RECORDS] >= rec.shape[0]:
            rec = _resized_rows(rec, 2 * rec.shape[0])
            rec_F = _resized_steps(rec_F, 2 * rec_F.shape[0])
    t = state_f[SF_T]
    mode = state_i[SI_MODE]
    n_ev = state_i[SI_EVENTS]
    n_rec = state_i[SI_RECORDS]
    n_steps = state_i[SI_STEPS]
    n_rejected = state_i[SI_REJECTED]
    status = state_i[SI_STATUS]
    info_mode = state_i[SI_FAILED_MODE]
    info_surface = state_i[SI_FAILED_SURFACE]

    return _pack_result(t, y, var, xmin, xmax, K, ev, ev_int, n_ev, rec, rec_F, n_rec, status, info_mode, info_surface,
                        n_steps, n_rejected, mode, slide, mode0)


@njit(cache=True, inline="always")  # inlined: each library level links and re-optimizes the integrator
def _shot(model, integrate, addresses, affine_modes, x, t0, t1, p, pidx, rtol, atol, max_step, max_events, max_steps, tr_table,
          n_surfaces, phi0, psi0, control_variational, exact_affine):
    """One shot ``x -> x(t1)`` with the fundamental solution matrix (and ``psi`` of parameter ``pidx``);
    status != 0 on failure (also for a state in no mode)."""
    mode = model[INITIAL_MODE](t0, x, p)
    failed = mode < 0  # in no mode: not integrated, the caller sees the failure in info[0]
    res = integrate(
        addresses, affine_modes, t0, t0 if failed else t1, x, max(mode, NONE + 1), p, ON, pidx, rtol, atol, 0.0, max_step, max_events,
        max_steps, tr_table, n_surfaces, OFF, phi0, psi0, control_variational, exact_affine,
    )
    if failed:
        res[0][INFO_STATUS] = STATUS_NON_FINITE
    return res


@njit(cache=True, inline="always")  # inlined: see _shot
def _periodic_shot(model, integrate, addresses, affine_modes, z, t0, sign, autonomous, lam_index, span, p, x, rtol, atol, max_step, max_events, max_steps,
                   tr_table, n_surfaces, phi0, psi0, control_variational, exact_affine):
    """The shot of one Newton iterate ``z = (x0[, T][, lam])`` over its period (forced: ``span``, or the
    forcing period at ``lam`` when ``span`` is 0); returns ``(ok, result)``, ``ok`` False for a period
    that is not positive (``p``, ``x``: work arrays)."""
    n = N_STATE or x.shape[0]
    m_u = n + 1 if autonomous else n
    if lam_index >= 0 and z.shape[0] > m_u:
        p[lam_index] = z[m_u]
    if autonomous:
        period = z[n]
    else:
        period = span if span > 0.0 else model[FORCING_PERIOD](p)
    for i in range(n):
        x[i] = z[i]
    span = period if period > 0.0 else 0.0  # (also for nan)
    res = _shot(model, integrate, addresses, affine_modes, x, t0, t0 + sign * span, p, lam_index, rtol, atol, max_step, max_events, max_steps,
                tr_table, n_surfaces, phi0, psi0, control_variational, exact_affine)
    return period > 0.0, res


@njit(cache=True, _nrt=False)
def _periodic_residual(out, z, autonomous, x_ref, f_ref, r):
    """Residual of the periodic-orbit equations at ``z`` into ``r``: ``x(t0 + sign T) - x0`` and,
    autonomous, the phase condition ``f_ref . (x0 - x_ref)``; returns its norm."""
    n = N_STATE or x_ref.shape[0]
    rn = 0.0
    o_x = result_offsets_c(n)[0]
    for i in range(n):
        r[i] = out[o_x + i] - z[i]
        rn += r[i] * r[i]
    if autonomous:
        acc = 0.0
        for i in range(n):
            acc += f_ref[i] * (z[i] - x_ref[i])
        r[n] = acc
        rn += acc * acc
    return math.sqrt(rn)


@njit(cache=True, _nrt=False)
def _solve_pivoted(A, b, x):
    """Solve ``A x = b`` by Gaussian elimination with partial pivoting (LAPACK's ``dgesv`` algorithm),
    overwriting ``A`` and ``b``; False for a zero or not finite pivot.

    The Newton matrices are (n + 2) x (n + 2) at most; numba's ``np.linalg.solve``
    would add seconds of compilation per model for them.
    """
    m = b.shape[0]
    for k in range(m):
        piv = k
        big = abs(A[k, k])
        for i in range(k + 1, m):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                piv = i
        if not (big > 0.0) or not math.isfinite(big):
            return False
        if piv != k:
            for j in range(m):
                A[k, j], A[piv, j] = A[piv, j], A[k, j]
            b[k], b[piv] = b[piv], b[k]
        for i in range(k + 1, m):
            factor = A[i, k] / A[k, k]
            if factor != 0.0:
                for j in range(k + 1, m):
                    A[i, j] -= factor * A[k, j]
                b[i] -= factor * b[k]
    for k in range(m - 1, -1, -1):
        acc = b[k]
        for j in range(k + 1, m):
            acc -= A[k, j] * x[j]
        x[k] = acc / A[k, k]
    return True


@njit(cache=True)
def _newton_result(code, it, z, history, n_history, jac, tangent, res):
    """``correct_periodic``'s result: ``(code, iterations, [z | residual history | jac | tangent], ints,
    floats)``, the last two the kernel result at ``z`` (each returned array costs a conversion)."""
    m = z.shape[0]
    o_history, o_jac, o_tangent, size = newton_layout_c(m, jac.shape[0], n_history, tangent.shape[0] > 0)
    packed = np.empty(size)
    for i in range(m):
        packed[i] = z[i]
    for i in range(n_history):
        packed[o_history + i] = history[i]
    at = o_jac
    for i in range(jac.shape[0]):
        for j in range(jac.shape[1]):
            packed[at] = jac[i, j]
            at += 1
    for i in range(tangent.shape[0]):
        packed[o_tangent + i] = tangent[i]
    return code, it, packed, res[0], res[1]


@njit(cache=True, nogil=True)  # compiled for CORRECT_SIGNATURE only, by saltation.engine.codegen.load_engine
def correct_periodic(addresses, affine_modes, z_pred, normal, t0, sign, autonomous, lam_index, span, p0, x_ref, f_ref, tol, max_newton,
                     max_correction, damped, rtol, atol, max_step, max_events, max_steps, tr_table, n_surfaces,
                     phi0, psi0, control_variational, exact_affine):
    """Newton on the periodic-orbit equations of a shooting problem, compiled.

    ``u = x0`` (forced: the period is ``span``, or when ``span`` is 0 the
    forcing period, which follows ``lam``) or ``u = (x0, T)`` (autonomous, with the phase condition
    ``f_ref . (x0 - x_ref) = 0``); ``r(u, lam) = x(t0 + sign T) - x0``.

    * ``damped`` False, ``z = (u, lam)``: the iteration of
      ``saltation.branches.continuation.Corrector.solve_bordered``, ``r = 0`` with
      ``normal . (z - z_pred) = 0`` (pseudo-arclength), which stops when a
      correction exceeds ``max_correction (1 + |z|)``.
    * ``damped`` True, ``z = u`` (``lam`` fixed, ``normal`` unused): the
      iteration of ``saltation.orbits.shooting.newton(..., damped=True)`` on
      ``r = 0``; a step is halved (up to 8 times) until the residual
      decreases.

    Converged when ``|r| <= tol (1 + |u|)``.  Returns ``(code, iterations, [z |
    residual history | r, J_u, J_lam by rows | tangent], ints, floats)``, the last two the
    kernel result at z (see :func:`_newton_result`); the tangent (bordered system only) solves
    ``[[J_u, J_lam], [normal]] t = e_last`` at the converged z (zeros where singular or not converged).
    """
    model = model_from_addresses(addresses, affine_modes)  # noqa: F821
    integrate = _function_at(INTEGRATOR_TYPE, addresses[INTEGRATOR_ROW, 0], addresses[INTEGRATOR_ROW, 1])
    n = N_STATE or phi0.shape[0]
    m_u = n_u = n + (1 if autonomous else 0)  # unknowns u (and rows of r)
    m_z = z_pred.shape[0]  # m_u, or m_u + 1 with lam
    z = z_pred.copy()
    zt = z_pred.copy()
    p = p0.copy()
    x = np.zeros(n)
    history = np.zeros(max_newton + 1)
    jac = np.zeros((m_u, m_u + 2))  # residual, then the Jacobian [J_u | J_lam]
    Jb = np.zeros((m_z, m_z))
    rhs = np.zeros(m_z)
    r = np.zeros(m_u)
    _, o_phi, o_psi, _, _, velocity, _ = result_offsets_c(n)
    dz = np.zeros(m_z)
    rn = np.inf
    it = 0
    trial = 0  # > 0: zt is the trial point of a damped step, halved trial - 1 times
    res = (np.zeros(13, dtype=np.int64), np.zeros(1))  # the kernel result at z, from the first shot on
    code = SHOOT_MAX_ITER
    n_history = 0
    # one call site of the shot: the integrator is compiled into this function once
    while True:
        cand = zt if trial > 0 else z
        ok, res_c = _periodic_shot(model, integrate, addresses, affine_modes, cand, t0, sign, autonomous, lam_index, span, p, x, rtol, atol, max_step,
                                   max_events, max_steps, tr_table, n_surfaces, phi0, psi0, control_variational,
                                   exact_affine)
        if trial > 0:
            if ok and res_c[0][INFO_STATUS] == STATUS_OK and _periodic_residual(
                    res_c[1], zt, autonomous, x_ref, f_ref, r) < rn:
                for j in range(m_z):
                    z[j] = zt[j]
                trial = 0
                it += 1
            elif trial == 9:
                code, n_history = SHOOT_FAILED, it + 1
                break
            else:
                for j in range(m_z):
                    dz[j] *= 0.5
                    zt[j] = z[j] - dz[j]
                trial += 1
                continue
        res = res_c
        if not ok:
            code, n_history = SHOOT_BAD_PERIOD, it
            break
        if res[0][INFO_STATUS] != STATUS_OK:
            code, n_history = SHOOT_FAILED, it
            break
        out = res[1]
        rn = _periodic_residual(out, z, autonomous, x_ref, f_ref, r)
        history[it] = rn
        un = 0.0
        for i in range(n_u):
            un += z[i] * z[i]
        # the residual and the Jacobian at z (returned with the converged point: the tangent needs them)
        for i in range(m_u):
            jac[i, 0] = r[i]
        for i in range(n):
            for j in range(n):
                jac[i, 1 + j] = out[o_phi + i * n + j] - (1.0 if i == j else 0.0)
            jac[i, 1 + m_u] = out[o_psi + i] if lam_index >= 0 else 0.0
        if autonomous:
            for i in range(n):
                jac[i, 1 + n] = sign * out[velocity + i]
                jac[n, 1 + i] = f_ref[i]
        elif lam_index >= 0 and span == 0.0:
            dperiod = model[FORCING_PERIOD_DP](p, lam_index)
            for i in range(n):
                jac[i, 1 + m_u] += sign * dperiod * out[velocity + i]
        n_history = it + 1
        if not math.isfinite(rn):
            code = SHOOT_FAILED
            break
        if rn <= tol * (1.0 + math.sqrt(un)):
            code = SHOOT_CONVERGED
            break
        if it == max_newton:
            break
        for i in range(m_u):
            for j in range(m_z):
                Jb[i, j] = jac[i, 1 + j]
            rhs[i] = jac[i, 0]
        if m_z > m_u:  # the pseudo-arclength row
            acc = 0.0
            for j in range(m_z):
                Jb[m_u, j] = normal[j]
                acc += normal[j] * (z[j] - z_pred[j])
            rhs[m_u] = acc
        if not _solve_pivoted(Jb, rhs, dz):
            code = SHOOT_SINGULAR
            break
        if damped:
            for j in range(m_z):
                zt[j] = z[j] - dz[j]
            trial = 1
            continue
        dn = 0.0
        zn = 0.0
        for j in range(m_z):
            dn += dz[j] * dz[j]
            zn += z[j] * z[j]
        if math.sqrt(dn) > max_correction * (1.0 + math.sqrt(zn)):
            break  # diverging
        for j in range(m_z):
            z[j] -= dz[j]
        it += 1
    # the bordered system's tangent direction at the solution, [[J_u, J_lam], [normal]] t = e_last (what
    # saltation.branches.corrector.Corrector.tangent solves next with normal as the previous tangent);
    # zeros where it is singular or the iteration has not converged
    tangent = np.zeros(m_z if m_z > m_u else 0)
    if code == SHOOT_CONVERGED and m_z > m_u:
        for i in range(m_u):
            for j in range(m_z):
                Jb[i, j] = jac[i, 1 + j]
            rhs[i] = 0.0
        for j in range(m_z):
            Jb[m_u, j] = normal[j]
        rhs[m_u] = 1.0
        if not _solve_pivoted(Jb, rhs, tangent):
            for j in range(m_z):
                tangent[j] = 0.0
    # one call of the result (each literal code as an argument would compile it once more)
    return _newton_result(code, it, z, history, n_history, jac, tangent, res)

