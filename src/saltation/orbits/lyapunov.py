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
        The averaging time, after the transient: at least ``blocks`` times half the motion's time scale (the
        forcing period of a forced model, one time unit of an autonomous one; see :data:`MIN_BLOCK`), so that
        the spread of the blocks measures the error, and at most :data:`MAX_INTERVALS` intervals.
    transient : float
        Time integrated first, not averaged (to reach the attractor).
    t0 : float
        The start time (the forcing's phase), finite.
    interval : float, optional
        Time between reorthonormalisations: by default the forcing period of a forced model, or 1
        time unit for an autonomous one, and never more than ``time / blocks``.  Where the fundamental
        matrix stays well conditioned over an interval, the next factorisation waits several (as many as
        keep its condition number under :data:`MAX_CONDITION`, at most 64), never past a block's end.
    blocks : int
        The run is cut into this many equal blocks; the spread of their estimates gives ``accuracy``.  From 2
        to :data:`MAX_INTERVALS`.
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
        Before any integration, naming the argument: if ``time`` or ``interval`` is not positive and finite,
        ``transient`` is negative, ``t0`` is not finite, ``blocks`` is not an integer from 2 to
        :data:`MAX_INTERVALS`, or the state is not finite or not of the model's size; if ``time`` is too short
        to estimate an accuracy (shorter than ``blocks`` times half the forcing period, or half a time unit);
        if the run would take more than :data:`MAX_INTERVALS` intervals (the estimate given), or intervals
        below :data:`MIN_RELATIVE_INTERVAL` of ``|t0| + transient + time`` (see :func:`plan_run`).
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
    if not np.all(np.isfinite(x)):
        raise ModelError(f"the state must be finite, got {x.tolist()}")
    p = flow.parameters(parameters)
    time, transient, t0, interval, blocks, per_block = plan_run(system, p, time=time, transient=transient, t0=t0,
                                                                 interval=interval, blocks=blocks)
    t = float(t0)
    mode = None if mode0 is None else system.mode_names[flow.start_mode(x, p, t, mode0)]
    if transient > 0.0:
        run = flow.run(x, t, t + transient, p, mode0=mode, tolerances=tolerances)
        x, t, mode = run.x1, run.t1, _next_mode(run.mode1)
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


#: The most reorthonormalisation intervals a run may take (``blocks`` times the intervals of a block): each is a
#: variational integration and a QR factorisation, some 20 microseconds at the least, minutes in all past this.
MAX_INTERVALS = 10**6

#: Each block must cover at least this fraction of the motion's time scale (the forcing period of a forced model,
#: one time unit of an autonomous one): over less, consecutive blocks see the same stretch of the motion, their
#: spread is no measure of the error (ten blocks of half a time unit of the damped trilinear oscillator spread by
#: a twentieth of their error).
MIN_BLOCK = 0.5

#: The longest transient, in time scales of the motion (forcing periods, or time units of an autonomous model):
#: the integration takes at most a million steps (Tolerances.max_steps), and every time scale takes at least one
MAX_TRANSIENT = 1e6

#: The interval (the time between two factorisations) must be at least this fraction of the largest time of the
#: run, ``|t0| + transient + time``: a shorter one does not move the clock.
MIN_RELATIVE_INTERVAL = 1e-9


def plan_run(
    system,
    parameters: np.ndarray,
    *,
    time: float,
    transient: float = 0.0,
    t0: float = 0.0,
    interval: float | None = None,
    blocks: int = 10,
    names: Mapping[str, str] | None = None,
) -> tuple[float, float, float, float, int, int]:
    """The arguments of :func:`lyapunov_exponents` checked, and the intervals of its run, before any integration.

    Parameters
    ----------
    system : PiecewiseSystem
    parameters : ndarray
        The parameter values (to evaluate the forcing period).
    time, transient, t0, interval, blocks
        As for :func:`lyapunov_exponents`.
    names : mapping, optional
        How a message names each argument (the command line's ``{"time": "--time"}``); by its name otherwise.

    Returns
    -------
    time, transient, t0, interval : float
        ``interval`` the base interval (its default filled in).
    blocks : int
    per_block : int
        Intervals per block: ``time / (blocks * per_block)`` is the interval the run takes.

    Raises
    ------
    ModelError
        Naming the argument and what it must be: ``time`` not positive and finite, or shorter than ``blocks``
        times half the motion's time scale (:data:`MIN_BLOCK`: the forcing period, or one time unit of an
        autonomous model), so that no accuracy can be estimated; ``transient`` negative or not finite, or longer
        than :data:`MAX_TRANSIENT` time scales; ``t0`` not
        finite; ``blocks`` not an integer from 2 to :data:`MAX_INTERVALS`; ``interval`` not positive and finite,
        or below :data:`MIN_RELATIVE_INTERVAL` of ``|t0| + transient + time``; or a run of more than
        :data:`MAX_INTERVALS` intervals (the estimated number given).
    """
    names = dict(names or {})

    def name(argument: str) -> str:
        return names.get(argument, argument)

    def number(argument: str, value) -> float:
        try:
            if isinstance(value, bool):
                raise TypeError
            return float(value)
        except (TypeError, ValueError):
            raise ModelError(f"{name(argument)} must be a real number, got {value!r}") from None

    time, transient, t0 = number("time", time), number("transient", transient), number("t0", t0)
    if not (math.isfinite(time) and time > 0.0):
        raise ModelError(f"{name('time')} must be positive and finite, got {time}")
    if not (math.isfinite(transient) and transient >= 0.0):
        raise ModelError(f"{name('transient')} must be non-negative and finite, got {transient}")
    if not math.isfinite(t0):
        raise ModelError(f"{name('t0')} (the start time) must be finite, got {t0}")
    try:
        whole = not isinstance(blocks, bool) and int(blocks) == blocks
    except (TypeError, ValueError, OverflowError):
        whole = False
    if not whole or not 2 <= blocks <= MAX_INTERVALS:
        raise ModelError(f"{name('blocks')} must be an integer from 2 to {MAX_INTERVALS} (each block is at least one "
                         f"interval of the run, and a run takes at most {MAX_INTERVALS}), got {blocks!r}")
    blocks = int(blocks)
    if system.is_autonomous:
        scale, what = 1.0, "a time unit"
    else:
        scale = system.forcing_period(parameters)
        what = f"the forcing period {scale:g}"
    if transient > MAX_TRANSIENT * scale:
        raise ModelError(
            f"{name('transient')} = {transient:g} is {transient / scale:.3g} times {what}, more than the "
            f"{MAX_TRANSIENT:.0e} an integration's step budget can cover (every time scale of the motion takes steps); "
            f"ask for a shorter {name('transient')}")
    shortest = blocks * MIN_BLOCK * scale
    if time < shortest * (1.0 - 1e-12):
        raise ModelError(
            f"{name('time')} = {time:g} is too short to estimate an accuracy: each of the {blocks} blocks must "
            f"cover at least {MIN_BLOCK:g} times {what} (over less, consecutive blocks see the same stretch of the "
            f"motion and their spread is no measure of the error), so {name('time')} must be at least {shortest:g}")
    given = interval is not None
    if not given:
        interval = min(scale, time / blocks)
    interval = number("interval", interval)
    if not (math.isfinite(interval) and interval > 0.0):
        raise ModelError(f"{name('interval')} must be positive and finite, got {interval}")
    with np.errstate(over="ignore"):
        per = time / blocks / interval * (1.0 - 1e-12)  # (a whole number of intervals is not rounded up by a last ulp)
    count = blocks * math.ceil(per) if math.isfinite(per) else math.inf
    if count > MAX_INTERVALS:
        culprit = name("interval") if given else name("time")
        raise ModelError(
            f"{culprit}: a run of time {time:g} in intervals of {interval:g} takes {count:.3g} intervals, more than the "
            f"{MAX_INTERVALS} a run may take (each is a variational integration and a QR factorisation); "
            f"ask for a shorter time" + (" or a longer interval" if given else ""))
    per_block = max(1, int(math.ceil(per)))
    step = time / (blocks * per_block)
    latest = abs(t0) + transient + time
    if step < MIN_RELATIVE_INTERVAL * latest:
        raise ModelError(
            f"the intervals of {step:g} ({name('interval')}) are below {MIN_RELATIVE_INTERVAL:g} of the run's largest "
            f"time |{name('t0')}| + {name('transient')} + {name('time')} = {latest:g}: the clock does not resolve them "
            f"(a forced model's phase is {name('t0')} modulo its period)")
    return time, transient, t0, interval, blocks, per_block


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


__all__ = ["COLLAPSE", "MAX_CONDITION", "MAX_INTERVALS", "MAX_TRANSIENT", "MIN_BLOCK", "MIN_PIECE", "MIN_RELATIVE_INTERVAL",
           "LyapunovExponents", "lyapunov_exponents", "plan_run"]
