"""Lyapunov exponents of a piecewise-smooth system, through the saltation matrices of its events.

The fundamental solution matrix is carried through every mode by the variational equation and jumped
by the saltation matrix of eq. (9) of *Fold bifurcations in discontinuous systems* at every event (the
engine does both, as for a monodromy matrix).  Over intervals of length ``interval`` the matrix
carried from an orthonormal frame ``Q`` is factored ``Phi Q = Q' R`` (QR); the logarithms of
``|R_ii|`` summed over the run and divided by its time are the exponents (Benettin's method, with
the discontinuities handled as by Müller).

A saltation matrix may be singular: the start of a sliding motion or of a stick phase maps a whole
direction onto the surface.  Volume in that direction is lost in finite time, not exponentially, and
its exponent is reported as ``-inf`` (exactly: its ``accuracy`` is 0).  Numerically a direction counts
as collapsed when, within one interval, it contracts below ``COLLAPSE`` times the largest stretch and
an event of that interval has a singular saltation matrix; without one, the interval is integrated in
shorter pieces until the contraction is resolved (a strongly damped direction has a finite exponent).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dgeqrf, dorgqr

from saltation.engine.flow import Flow, Tolerances
from saltation.errors import ModelError

#: A direction contracted below this fraction of the largest stretch within one interval is collapsed
#: (a singular saltation matrix): its exponent is ``-inf``.
COLLAPSE = 1e3 * np.finfo(float).eps

#: An interval is cut into pieces (each a quarter of the last) while a direction contracts past ``COLLAPSE``
#: within one piece and no event there has a singular saltation matrix, down to this fraction of it: a
#: strong exponential contraction is resolved, not mistaken for a collapse.
MIN_PIECE = 1e-4


@dataclass(frozen=True)
class LyapunovExponents:
    """The Lyapunov exponents of a run.

    Attributes
    ----------
    exponents : ndarray, shape (n,)
        Descending, per unit time; ``-inf`` for a direction collapsed by a singular saltation matrix.
        A forced model's time direction (exponent 0) is not among them: there is one per state.
    accuracy : ndarray, shape (n,)
        An estimate of each exponent's error: the standard error of the estimates over ``blocks``
        equal blocks of the run (0 for a collapsed direction).
    time : float
        The averaging time (after the transient).
    transient : float
        The time integrated before averaging.
    interval : float
        The base time between reorthonormalisations (while the frame stays well conditioned, several
        intervals pass between two, see :data:`MAX_CONDITION`).
    block_exponents : ndarray, shape (blocks, n)
        The exponents of each block.
    state : ndarray, shape (n,)
        Where the run ended.
    block_sum_rounding : ndarray, shape (blocks,)
        A bound on the rounding error of each block's sum of exponents (per unit time).  The sum is
        ``ln|det|`` of the fundamental matrix, kept by the QR steps, but the entries of a fundamental
        matrix carry rounding of ``eps |M|``, so its most contracted direction ``|R_nn|`` is known only to
        ``eps |R_11| / |R_nn|`` relative: small on a smooth flow, large past an impact that nearly grazes
        (its saltation matrix grows like ``1/v``).  Each QR step adds ``16 n eps |R_11| / |R_nn|``.
    """

    exponents: np.ndarray
    accuracy: np.ndarray
    time: float
    transient: float
    interval: float
    block_exponents: np.ndarray
    state: np.ndarray
    block_sum_rounding: np.ndarray | None = None

    @property
    def largest(self) -> float:
        """The largest exponent."""
        return float(self.exponents[0])

    def __repr__(self) -> str:
        pairs = ", ".join("-inf" if not math.isfinite(e) else f"{e:.6g} +- {a:.1g}"
                          for e, a in zip(self.exponents, self.accuracy))
        return f"LyapunovExponents([{pairs}], time={self.time:g})"


def lyapunov_exponents(
    flow: Flow,
    state0: Sequence[float],
    *,
    parameters: Mapping[str, float] | np.ndarray | None = None,
    time: float,
    transient: float = 0.0,
    t0: float = 0.0,
    interval: float | None = None,
    blocks: int = 10,
    tolerances: Tolerances | None = None,
    mode0: str | None = None,
) -> LyapunovExponents:
    """Lyapunov exponents from ``state0``, forward in time, through the saltation matrices of every event.

    Parameters
    ----------
    flow : Flow
    state0 : array_like, shape (n,)
        Where the run starts (the transient first, if any).
    parameters : mapping or ndarray, optional
        Parameter values (the model's defaults otherwise).
    time : float
        The averaging time, after the transient.
    transient : float
        Time integrated first, not averaged (to reach the attractor).
    t0 : float
        The start time (the forcing's phase).
    interval : float, optional
        Time between reorthonormalisations: by default the forcing period of a forced model, or 1
        time unit for an autonomous one, and never more than ``time / blocks``.  Where the fundamental
        matrix stays well conditioned over an interval, the next factorisation waits several (as many as
        keep its condition number under :data:`MAX_CONDITION`, at most 64), never past a block's end.
    blocks : int
        The run is cut into this many equal blocks; the spread of their estimates gives ``accuracy``.
    tolerances : Tolerances, optional
        Integration tolerances (the flow's by default).
    mode0 : str, optional
        The mode the run starts in (a memory mode, see :meth:`Flow.start_mode`); by default the
        model's initial-mode rule.

    Returns
    -------
    LyapunovExponents

    Raises
    ------
    ModelError
        If ``time`` or ``interval`` is not positive and finite, ``transient`` is negative, ``blocks`` is
        less than 2, or the state is not of the model's size.
    IntegrationError
        If an integration fails (a state in no mode, chattering, an undefined sliding motion, ...).
    InitialModeError
        If the state lies outside the domain of ``mode0`` (or, without it, in no mode's domain).

    References
    ----------
    G. Benettin, L. Galgani, A. Giorgilli and J.-M. Strelcyn (1980), "Lyapunov characteristic exponents
    for smooth dynamical systems and for Hamiltonian systems; a method for computing all of them",
    Meccanica 15.  P. C. Müller (1995), "Calculation of Lyapunov exponents for dynamic systems with
    discontinuities", Chaos, Solitons & Fractals 5.  R. I. Leine and D. H. Van Campen, *Fold
    bifurcations in discontinuous systems*, eq. (9) (the saltation matrix).
    """
    system = flow.system
    n = system.n
    x = np.asarray(state0, dtype=float).reshape(-1)
    if x.shape != (n,):
        raise ModelError(f"the state must have {n} components (the states {list(system.state_names)}), got {x.shape[0]}")
    time, transient = float(time), float(transient)
    if not (math.isfinite(time) and time > 0.0):
        raise ModelError(f"time must be positive and finite, got {time}")
    if not (math.isfinite(transient) and transient >= 0.0):
        raise ModelError(f"transient must be non-negative and finite, got {transient}")
    if isinstance(blocks, bool) or int(blocks) != blocks or blocks < 2:
        raise ModelError(f"blocks must be an integer of at least 2, got {blocks!r}")
    blocks = int(blocks)
    p = flow.parameters(parameters)
    if interval is None:
        interval = 1.0 if system.is_autonomous else system.forcing_period(p)
        interval = min(interval, time / blocks)
    interval = float(interval)
    if not (math.isfinite(interval) and interval > 0.0):
        raise ModelError(f"interval must be positive and finite, got {interval}")
    t = float(t0)
    mode = None if mode0 is None else system.mode_names[flow.start_mode(x, p, t, mode0)]
    if transient > 0.0:
        run = flow.run(x, t, t + transient, p, mode0=mode, tolerances=tolerances)
        x, t, mode = run.x1, run.t1, _next_mode(run.mode1)
    per_block = max(1, int(math.ceil(time / blocks / interval * (1.0 - 1e-12))))  # (a whole number of intervals
    #                                                                     is not rounded up by a last ulp)
    step = time / (blocks * per_block)  # every block of the same length, whole intervals
    q = np.eye(n)
    block_logs = np.zeros((blocks, n))
    block_rounding = np.zeros(blocks)  # bound on the rounding of each block's sum of logs (see LyapunovExponents)
    span = 1  # intervals per QR: more while the frame stays well conditioned over them
    for b in range(blocks):
        done = 0
        while done < per_block:
            k = min(span, per_block - done)
            end = t + k * step
            pieces = False
            while t < end:  # k intervals, in pieces where a strong contraction needs them
                h = end - t
                while True:
                    run = flow.run(x, t, t + h, p, mode0=mode, variational=True, phi0=q, tolerances=tolerances)
                    q_new, r_diag = _qr(run.monodromy)
                    d = np.abs(r_diag)
                    collapsed = d <= COLLAPSE * max(float(d.max()), np.finfo(float).tiny)
                    if not collapsed.any() or _singular_event(run) or h <= MIN_PIECE * step:
                        break
                    h *= 0.25  # an exponential contraction past the resolution of one piece: shorter pieces
                    pieces = True
                with np.errstate(divide="ignore"):
                    block_logs[b] += np.where(collapsed, -np.inf, np.log(np.where(collapsed, 1.0, d)))
                if not collapsed.any():
                    block_rounding[b] += 16 * n * np.finfo(float).eps * float(d.max() / d.min())
                q = q_new * np.where(r_diag < 0, -1.0, 1.0)  # (R with a positive diagonal: Q follows the frame)
                x, t, mode = run.x1, run.t1, _next_mode(run.mode1)
            done += k
            span = _next_span(d, k, pieces or collapsed.any())
    block_time = step * per_block
    with np.errstate(invalid="ignore"):
        estimates = block_logs / block_time
        totals = block_logs.sum(axis=0) / time
    order = np.argsort(-totals, kind="stable")
    exponents, estimates = totals[order], estimates[:, order]
    finite = np.isfinite(exponents)
    accuracy = np.zeros(n)
    if np.any(finite):
        spread = np.where(np.isfinite(estimates), estimates, np.nan)[:, finite]
        accuracy[finite] = np.nanstd(spread, axis=0, ddof=1) / math.sqrt(blocks)
    return LyapunovExponents(exponents=exponents, accuracy=accuracy, time=time, transient=transient, interval=step,
                             block_exponents=estimates, state=np.array(x), block_sum_rounding=block_rounding / block_time)


#: the largest condition number the fundamental matrix may reach between two QR factorisations: its smallest
#: direction then keeps about 10 of its 16 digits
MAX_CONDITION = 1e6


def _next_span(d: np.ndarray, k: int, irregular: bool) -> int:
    """How many intervals the next QR may wait: as many as keep the frame's condition number (the spread of
    ``|diag R|`` over ``k`` intervals, extrapolated) under :data:`MAX_CONDITION`; one after a collapse or pieces."""
    if irregular or d.size < 2:
        return 1
    growth = math.log10(float(d.max()) / float(d.min())) / k
    if growth <= 0.0:
        return 64
    return int(min(64, max(1, math.log10(MAX_CONDITION) // growth)))


def _qr(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(Q, diag(R))`` of ``a = Q R``, by LAPACK's dgeqrf and dorgqr (numpy's ``qr`` costs ten times as much
    on the small matrices of one interval)."""
    qr, tau, _, info = dgeqrf(a)
    if info != 0:
        raise np.linalg.LinAlgError(f"QR factorisation failed (LAPACK info {info})")
    q, _, info = dorgqr(qr, tau)
    if info != 0:
        raise np.linalg.LinAlgError(f"QR factorisation failed (LAPACK info {info})")
    return q, np.diagonal(qr).copy()


def _singular_event(run) -> bool:
    """Whether an event of the run has a singular saltation matrix (a sliding motion or a stick phase starts)."""
    for event in run.events:
        s = event.saltation
        scale = max(float(np.abs(s).max()), np.finfo(float).tiny) ** s.shape[0]
        if abs(float(np.linalg.det(s))) <= COLLAPSE * scale:
            return True
    return False


def _next_mode(mode: str) -> str | None:
    """The mode a run continues in: the previous run's last mode, or the initial-mode rule after a sliding
    motion (named ``a|b``)."""
    return None if "|" in mode else mode


__all__ = ["COLLAPSE", "MAX_CONDITION", "MIN_PIECE", "LyapunovExponents", "lyapunov_exponents"]
