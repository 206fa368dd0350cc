"""Scalar measures of a periodic orbit: what a branch diagram plots and a monitor watches.

The amplitude the library has always recorded is ``max |x_1|`` over the period.  A rotor's amplitude is its
radius ``max sqrt(x^2 + y^2)``, and a current-mode converter's ``max i`` is the reference current itself, so a
branch can be measured by any of these (:class:`Measure`, by its text):

* ``NAME`` (a state): ``max |NAME|`` over the period, from the engine's extremes of the state;
* ``ptp:NAME``: its peak-to-peak value ``max NAME - min NAME``;
* ``section:NAME``: its value at the orbit's section (the state the shooting starts from);
* ``norm``: ``max ||x||_2`` over the period, every state counted;
* ``max:EXPR`` or ``min:EXPR``, or an expression ``EXPR`` of the states, the parameters and ``t`` that is
  not a state's name: its largest (smallest) value over the period, e.g. ``sqrt(x**2 + y**2)``.

The extremes of ``norm`` and of expressions are found on the dense output of one period (DOP853's
interpolant): the best of a few samples per integration step and at the events, refined by a bounded
scalar minimisation in the interval around it, so they carry the integration's accuracy.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from saltation.errors import ModelError

__all__ = ["Measure", "measure_label", "measure_orbit", "measure_state", "parse_measures"]

#: samples of the dense output per integration step where an extreme is looked for
SAMPLES_PER_STEP = 8


@dataclass(frozen=True)
class Measure:
    """A scalar measure of one period of an orbit, given by its text (see the module's docstring).

    Attributes
    ----------
    text : str
        The measure as written (``"x"``, ``"norm"``, ``"ptp:x"``, ``"section:x"``, ``"sqrt(x**2 + y**2)"``):
        its name in records, files and tables.
    kind : str
        ``"amplitude"``, ``"ptp"``, ``"section"``, ``"norm"``, ``"max"`` or ``"min"``.
    state : int
        The state's index (``amplitude``, ``ptp``, ``section``; -1 otherwise).
    expression : str
        The expression (``max``, ``min``; empty otherwise).

    Raises
    ------
    ModelError
        Raised by :meth:`parse`, naming the model's states, for a name that is not a state or an expression
        that does not parse.
    """

    text: str
    kind: str
    state: int = -1
    expression: str = ""
    _function: Callable | None = field(default=None, compare=False, repr=False)

    @classmethod
    def parse(cls, text: str, system) -> Measure:
        """The measure ``text`` of the model ``system``.

        Parameters
        ----------
        text : str
            The measure (see the module's docstring).
        system : PiecewiseSystem
            The model: its states, parameters and symbols.

        Returns
        -------
        Measure

        Raises
        ------
        ModelError
            For an unknown state, an expression that does not parse or that names something that is not
            a state, a parameter or ``t``.
        """
        text = str(text).strip()
        names = list(system.state_names)
        head, sep, rest = text.partition(":")
        if text == "norm":
            return cls(text, "norm")
        if sep and head in ("ptp", "section"):
            return cls(text, head, state=_state_index(rest.strip(), names, text))
        if text in names:
            return cls(text, "amplitude", state=names.index(text))
        kind, expression = (head, rest.strip()) if sep and head in ("max", "min") else ("max", text)
        return cls(text, kind, expression=expression, _function=_compile(expression, system, text))

    @property
    def label(self) -> str:
        """How axes and tables name it (:func:`measure_label`)."""
        return measure_label(self.text)

    def value(self, traj, state0: np.ndarray, p: np.ndarray) -> float:
        """The measure of one period.

        Parameters
        ----------
        traj : Trajectory
            One period of the orbit; with dense output (``dense=True``) for ``norm`` and expressions.
        state0 : ndarray
            The state at the section.
        p : ndarray
            The parameter vector.

        Returns
        -------
        float

        Raises
        ------
        ValueError
            If ``norm`` or an expression is asked of a trajectory without dense output.
        """
        if self.kind == "amplitude":
            return float(max(abs(traj.x_max[self.state]), abs(traj.x_min[self.state])))
        if self.kind == "ptp":
            return float(traj.x_max[self.state] - traj.x_min[self.state])
        if self.kind == "section":
            return float(state0[self.state])
        if self.kind == "norm":
            return _extreme(traj, lambda t, x: np.sqrt(np.sum(x * x, axis=1)), +1)
        f = self._function
        return _extreme(traj, lambda t, x: np.broadcast_to(f(t, x.T, p), t.shape).astype(float),
                        +1 if self.kind == "max" else -1)

    @property
    def needs_dense(self) -> bool:
        """Whether it is computed on the dense output (``norm`` and expressions)."""
        return self.kind in ("norm", "max", "min")


def _state_index(name: str, names: Sequence[str], text: str) -> int:
    if name not in names:
        raise ModelError(f"measure {text!r}: {name!r} is not a state of the model (states: {', '.join(names)})")
    return names.index(name)


def _compile(expression: str, system, text: str) -> Callable:
    """``f(t, x, p)`` of an expression of the states (rows of ``x``), the parameters and ``t``."""
    import sympy as sp

    symbols = {str(s): s for s in (*system.x, *system.p)} | {"t": sp.Symbol("t")}
    try:
        expr = sp.sympify(expression, locals=symbols)
    except (sp.SympifyError, SyntaxError, TypeError) as exc:
        raise ModelError(f"measure {text!r} does not parse: {exc}") from None
    unknown = sorted(str(s) for s in getattr(expr, "free_symbols", set()) if str(s) not in symbols)
    if unknown or not isinstance(expr, sp.Expr):
        raise ModelError(f"measure {text!r}: {', '.join(unknown) or expression!r} is not a state, a parameter "
                         f"or t (states: {', '.join(system.state_names)}; parameters: "
                         f"{', '.join(system.parameter_names)})")
    t = symbols["t"]
    return sp.lambdify((t, list(system.x), list(system.p)), expr, modules="numpy")


def _extreme(traj, g: Callable[[np.ndarray, np.ndarray], np.ndarray], sign: int) -> float:
    """The largest (``sign`` +1) or smallest (-1) value of ``g(t, x)`` over a dense trajectory: sampled on
    every step and at both sides of every event (a reset's state after it too), refined around the best."""
    from scipy.optimize import minimize_scalar

    t_old, h, s_end = (np.asarray(a, dtype=float) for a in traj.dense_steps[:3])
    fractions = np.linspace(0.0, 1.0, SAMPLES_PER_STEP + 1)
    times = (t_old[:, None] + (h * s_end)[:, None] * fractions[None, :]).ravel()
    lo_t, hi_t = min(traj.t0, traj.t1), max(traj.t0, traj.t1)
    times = np.unique(np.clip(np.concatenate([times, [traj.t0, traj.t1]]), lo_t, hi_t))
    values = sign * g(times, traj.at(times))
    k = int(np.argmax(values))
    best = float(values[k])
    ends = [(e.t, x) for e in traj.events for x in (e.x_minus, e.x_plus)] + [(traj.t1, traj.x1)]
    for t, x in ends:
        best = max(best, float(sign * g(np.array([t]), np.asarray(x, dtype=float)[None, :])[0]))
    lo, hi = times[max(k - 1, 0)], times[min(k + 1, times.size - 1)]
    if hi > lo:
        found = minimize_scalar(lambda s: -sign * float(g(np.array([s]), traj.at(np.array([s])))[0]),
                                bounds=(lo, hi), method="bounded", options={"xatol": 1e-12 * max(1.0, abs(hi))})
        if found.success and -found.fun > best:
            best = float(-found.fun)
    return sign * best


def measure_orbit(flow, state0: np.ndarray, period: float, p: np.ndarray, measures: Sequence[Measure], *,
                  t0: float = 0.0, mode0: str | None = None, backward: bool = False) -> dict[str, float]:
    """The measures of the periodic orbit through ``state0``: one period integrated (with dense output
    where a measure needs it).

    Parameters
    ----------
    flow : Flow
        The model's flow.
    state0 : ndarray
        The state at the section.
    period : float
        The period (of the orbit, over the shooting's periods).
    p : ndarray
        The parameter vector.
    measures : sequence of Measure
        What to measure.
    t0 : float
        The section time.
    mode0 : str, optional
        The mode the orbit starts in.
    backward : bool
        Whether the orbit was found in backward time (the same period is integrated forward from the state
        at the section, unless the flow only runs backward there).

    Returns
    -------
    dict of str to float
        Each measure's value by its text.

    Raises
    ------
    IntegrationError
        If the period cannot be integrated.
    """
    if not measures or not math.isfinite(period) or period <= 0.0:
        return {}
    dense = any(m.needs_dense for m in measures)
    t1 = t0 - period if backward else t0 + period
    traj = flow.run(np.asarray(state0, dtype=float), t0, t1, p, mode0=mode0, dense=dense)
    return {m.text: m.value(traj, state0, p) for m in measures}


def measure_state(state: np.ndarray, p: np.ndarray, measures: Sequence[Measure]) -> dict[str, float]:
    """The measures of a state that does not move (an equilibrium): its extremes are the state itself.

    Parameters
    ----------
    state : ndarray
        The state.
    p : ndarray
        The parameter vector.
    measures : sequence of Measure
        What to measure.

    Returns
    -------
    dict of str to float
        Each measure's value by its text (a peak-to-peak value 0).
    """
    x = np.asarray(state, dtype=float)
    out = {}
    for m in measures:
        if m.kind in ("amplitude", "section"):
            value = abs(x[m.state]) if m.kind == "amplitude" else x[m.state]
        elif m.kind == "ptp":
            value = 0.0
        elif m.kind == "norm":
            value = np.linalg.norm(x)
        else:
            value = np.asarray(m._function(0.0, x, p), dtype=float)
        out[m.text] = float(value)
    return out


def measure_label(text: str) -> str:
    """How a figure's axis names a measure given by its text (without the model): ``max |x|``,
    ``max x - min x``, ``x at the section``, ``max ||x||``, ``max sqrt(x**2 + y**2)``.

    Parameters
    ----------
    text : str
        The measure.

    Returns
    -------
    str
    """
    head, sep, rest = text.partition(":")
    if text == "norm":
        return "max ||x||"
    if sep and head == "ptp":
        return f"max {rest.strip()} - min {rest.strip()}"
    if sep and head == "section":
        return f"{rest.strip()} at the section"
    if sep and head in ("max", "min"):
        return f"{head} {rest.strip()}"
    return f"max |{text}|" if text.isidentifier() else f"max {text}"


def parse_measures(texts: Sequence[str] | Mapping, system) -> tuple[Measure, ...]:
    """Measures of a model from their texts (each once, in order).

    Parameters
    ----------
    texts : sequence of str
        The measures.
    system : PiecewiseSystem
        The model.

    Returns
    -------
    tuple of Measure

    Raises
    ------
    ModelError
        As :meth:`Measure.parse`.
    """
    out: dict[str, Measure] = {}
    for text in texts:
        measure = text if isinstance(text, Measure) else Measure.parse(text, system)
        out.setdefault(measure.text, measure)
    return tuple(out.values())
