"""What a sweep samples: its section, and where a trajectory crosses it.

A :class:`Section` is one of four kinds:

* ``"poincare"``: the stroboscopic section ``x(t0 + k T)`` of a forced model, ``T`` its forcing period;
* ``"maxima"``: the local maxima of the first state ``x_1``;
* ``"surface"``: a switching surface of the model, by name.  The samples are its switching events (the
  transitions that fire on it and the sliding motions that start on it, as the engine logs them), each
  the state just before the event (before a reset); with a direction, only the events where the
  surface's indicator rises (+1) or falls (-1).  A crossing that fires no transition (no transition
  out of the mode on that surface in that direction, or a guard that does not hold) is no event: give
  the surface's indicator as an expression to sample every crossing;
* ``"expression"``: the zeros of a function ``g(t, x, p)`` of the states, the parameters and time
  ``t``, written as a string that sympy parses against the model's names (``"x - 1"``, ``"v"``,
  ``"sin(omega*t)"`` for the clock of a forced model), crossed in a direction: +1 where ``g`` passes
  from negative to zero or positive, -1 the other way, 0 either.  The crossings are located on the
  integrator's dense output (DOP853's continuous extension, accurate to the integration tolerance):
  the sign of ``g`` is read at :data:`_GRID` + 1 points of every step, and each change of sign is
  bisected on that step's interpolant to rounding.  A reset that jumps across ``g = 0`` is no crossing.

:func:`parse_section` reads what a user gives (``sweep(section=..., direction=...)``, the command line's
``--section`` and ``--direction``) against a model; :attr:`Section.code` is how
:class:`~saltation.sweeps.sweeps.SweepResult` and its files record it (``"poincare"``, ``"maxima"``,
``"surface:NAME"``, ``"surface:NAME:rising"``, ``"expr:x - 1:falling"``), and :meth:`Section.from_code`
reads it back.  The crossings themselves are found in the worker processes
(:mod:`~saltation.sweeps.parallel`) by this module's private functions.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from saltation.engine.flow import Trajectory, dense_evaluate
from saltation.engine.trajectory import EventKind
from saltation.errors import ModelError
from saltation.model.system import PiecewiseSystem

__all__ = ["Section", "parse_section"]

#: The kinds of section.
_KINDS = ("poincare", "maxima", "surface", "expression")
#: The words of the directions in a section's code: +1 rising, -1 falling, 0 either.
_DIRECTION_WORDS = {1: "rising", -1: "falling", 0: "either"}
_WORD_DIRECTIONS = {word: d for d, word in _DIRECTION_WORDS.items()}
#: The prefixes of a surface's and an expression's code.
_PREFIXES = {"surface": "surface:", "expression": "expr:"}

#: Points per integration step at which an expression's sign is read (its ends included).
_GRID = 12
#: Bisections of each change of sign (2**-60 of a twelfth of a step: below rounding).
_BISECTIONS = 60
#: Two consecutive steps whose joint states differ by more than this (relative) are split by a reset.
_JUMP = 1e-6
#: The columns of an event's integers (:meth:`~saltation.engine.trajectory.Trajectory.event_rows`).
_KIND, _TRANSITION, _SURFACE, _MODE_FROM = range(4)


@dataclass(frozen=True)
class Section:
    """What a sweep samples (see the module's text).

    Attributes
    ----------
    kind : {"poincare", "maxima", "surface", "expression"}
        The stroboscopic section of a forced model, the maxima of ``x_1``, a switching surface's events, or
        the zeros of an expression.
    target : str
        The surface's name, or the expression as sympy writes it (``""`` for the other kinds).
    direction : int or None
        +1 (rising: the surface's indicator, or the expression, passing from negative to positive), -1
        (falling) or 0 (either); None for ``"poincare"`` and ``"maxima"``, and for a surface whose every
        switching event counts, each in the direction of its transition (the same events as 0).

    Raises
    ------
    ValueError
        For an unknown kind, a target missing or given where it has none, or a direction other than
        +1, -1, 0 (or None where it is allowed: not for an expression).
    """

    kind: str
    target: str = ""
    direction: int | None = None

    def __post_init__(self):
        if self.kind not in _KINDS:
            raise ValueError(f"a section's kind is one of {', '.join(_KINDS)}, got {self.kind!r}")
        crossing = self.kind in _PREFIXES
        if crossing != bool(self.target) or not isinstance(self.target, str) or ":" in self.target:
            what = "a surface's name or an expression without ':'" if crossing else "none"
            raise ValueError(f"the target of a {self.kind!r} section is {what}, got {self.target!r}")
        if self.direction is not None and (isinstance(self.direction, bool) or self.direction not in (1, -1, 0)):
            raise ValueError(f"a section's direction is +1, -1 or 0, got {self.direction!r}")
        if self.direction is not None and not crossing:
            raise ValueError(f"the {self.kind!r} section takes no direction, got {self.direction!r}")
        if self.direction is None and self.kind == "expression":
            raise ValueError("an expression's section needs a direction (+1, -1 or 0)")
        object.__setattr__(self, "direction", None if self.direction is None else int(self.direction))

    @property
    def crossings(self) -> bool:
        """Whether the section counts crossings (a surface or an expression): then a sweep's ``periods`` and
        ``transient`` are numbers of crossings."""
        return self.kind in _PREFIXES

    @property
    def code(self) -> str:
        """The section as :attr:`SweepResult.section <saltation.sweeps.sweeps.SweepResult>` and the files
        record it: ``"poincare"``, ``"maxima"``, ``"surface:NAME"`` (every event), ``"surface:NAME:WORD"`` or
        ``"expr:EXPRESSION:WORD"``, with ``WORD`` one of ``rising``, ``falling``, ``either``."""
        if not self.crossings:
            return self.kind
        text = _PREFIXES[self.kind] + self.target
        return text if self.direction is None else f"{text}:{_DIRECTION_WORDS[self.direction]}"

    @property
    def words(self) -> str:
        """The section in words, for messages and axis labels (``"rising crossings of x - 1 = 0"``)."""
        if self.kind == "poincare":
            return "Poincare section"
        if self.kind == "maxima":
            return "maxima of the first state"
        which = {None: "", 1: "rising ", -1: "falling ", 0: ""}[self.direction]
        if self.kind == "surface":
            return f"{which}crossings of surface {self.target}" if self.direction else f"events on surface {self.target}"
        return f"{which}crossings of {self.target} = 0"

    @classmethod
    def from_code(cls, code: str) -> Section:
        """The section a code (:attr:`code`) writes.

        Parameters
        ----------
        code : str
            ``"poincare"``, ``"maxima"``, ``"surface:NAME"``, ``"surface:NAME:WORD"`` or ``"expr:EXPRESSION:WORD"``
            (``WORD``: ``rising``, ``falling`` or ``either``).

        Returns
        -------
        Section

        Raises
        ------
        TypeError
            If ``code`` is not a string.
        ValueError
            If ``code`` is none of these (the expression is not parsed: that needs the model,
            :func:`parse_section`).
        """
        if not isinstance(code, str):
            raise TypeError(f"a section's code is a string, got {code!r}")
        if code in ("poincare", "maxima"):
            return cls(code)
        kind, target, direction = _split_code(code)
        if kind is None or (kind == "expression" and direction is None):
            raise ValueError(f"{code!r} is not a section's code: 'poincare', 'maxima', 'surface:NAME[:WORD]' or "
                             "'expr:EXPRESSION:WORD' (WORD rising, falling or either)")
        return cls(kind, target.strip(), direction)


def _split_code(text: str) -> tuple[str | None, str, int | None]:
    """``(kind, target, direction)`` of a text with a prefix (``surface:``, ``expr:``) and an optional
    direction word at its end; ``(None, text, None)`` without a prefix.

    Raises
    ------
    ValueError
        For a surface's code whose last part is no direction word.
    """
    for kind, prefix in _PREFIXES.items():
        if text.startswith(prefix):
            body, colon, word = text[len(prefix):].rpartition(":")
            if colon and word.strip() in _WORD_DIRECTIONS:
                return kind, body, _WORD_DIRECTIONS[word.strip()]
            if colon and kind == "surface":
                raise ValueError(f"{text!r}: the direction of a surface is rising, falling or either, got {word!r}")
            return kind, text[len(prefix):], None
    return None, text, None


def _direction(direction) -> int | None:
    """A direction given by a user: None, or +1, -1, 0 (a :class:`~saltation.model.Crossing` too).

    Raises
    ------
    ValueError
        For anything else.
    """
    if direction is None:
        return None
    if isinstance(direction, str) and direction.strip() in _WORD_DIRECTIONS:
        return _WORD_DIRECTIONS[direction.strip()]
    if isinstance(direction, (bool, np.bool_)) or not isinstance(direction, (int, np.integer)) or direction not in (1, -1, 0):
        raise ValueError(f"direction must be +1 (rising), -1 (falling) or 0 (either), got {direction!r}")
    return int(direction)


def _symbols(system: PiecewiseSystem) -> dict:
    """The model's states, parameters and time by name (the symbols its expressions are written in)."""
    return {s.name: s for s in (*system.x, *system.p)} | {"t": system.t}


def parse_section(system: PiecewiseSystem, section: str | Section, direction: int | None = None) -> Section:
    """The section a user names, read against a model.

    A string is ``"poincare"`` (forced models), ``"maxima"``, a switching surface's name, or an expression of
    the model's states, parameters and time ``t``; a surface's name wins over an expression that is a state's
    name (write ``"expr:NAME"`` for the state).  The codes of :attr:`Section.code` are accepted too.

    Parameters
    ----------
    system : PiecewiseSystem
        The model.
    section : str or Section
        The section.
    direction : int, optional
        +1 (rising), -1 (falling) or 0 (either way) for a surface or an expression (also the words rising,
        falling, either).  None: a surface's every switching event, or an expression's rising crossings.  A
        direction in the code (``"expr:v:falling"``) must agree with it.

    Returns
    -------
    Section
        With the expression as sympy writes it (``"x - 1"`` for ``"x-1"``).

    Raises
    ------
    ModelError
        For a name that is no surface of the model and no expression of its states, parameters and time (the
        message lists its surfaces and states), an expression that depends on neither a state nor time, or the
        stroboscopic section of an autonomous model.
    ValueError
        For a section that is not a string, a direction other than +1, -1, 0, a direction given with
        ``"poincare"`` or ``"maxima"``, or one that contradicts the code's.
    """
    from saltation.model.system import _sympify

    direction = _direction(direction)
    if isinstance(section, Section):
        section = section.code
    if not isinstance(section, str) or not section.strip():
        raise ValueError(f"a section is 'poincare', 'maxima', a surface's name or an expression, got {section!r}")
    text = section.strip()
    if text in ("poincare", "maxima"):
        if direction is not None:
            raise ValueError(f"the {text!r} section takes no direction, got {direction:+d}")
        if text == "poincare" and system.is_autonomous:
            raise ModelError(f"the stroboscopic section 'poincare' needs a forced model; {system.name!r} is autonomous: "
                             "name a switching surface or an expression of its states, or 'maxima'")
        return Section(text)
    kind, target, coded = _split_code(text)
    if coded is not None and direction is not None and coded != direction:
        raise ValueError(f"section {text!r} says {_DIRECTION_WORDS[coded]}, but the direction given is {direction:+d}")
    direction = coded if direction is None else direction
    target = target.strip()
    if kind == "surface" or (kind is None and target in system.surface_names):
        if target not in system.surface_names:
            raise ModelError(f"section {text!r}: {system.name!r} has no switching surface {target!r}; its surfaces "
                             f"are {', '.join(system.surface_names) or 'none'}")
        return Section("surface", target, direction)
    try:
        expr = _sympify(target, _symbols(system), f"section {target!r}")
    except ModelError as exc:
        reason = str(exc).removeprefix(f"section {target!r}: ").split("; known states")[0]
        raise ModelError(
            f"{target!r} is no section of {system.name!r}: not 'poincare' or 'maxima', not a switching surface "
            f"({', '.join(system.surface_names) or 'none'}), and not an expression of the states "
            f"({', '.join(system.state_names)}), the parameters ({', '.join(system.parameter_names)}) and time t "
            f"({reason})"
        ) from None
    if not expr.free_symbols & {*system.x, system.t}:
        raise ModelError(f"section {target!r} depends on no state of {system.name!r} "
                         f"({', '.join(system.state_names)}) and not on time t: it is never crossed")
    return Section("expression", str(expr), 1 if direction is None else direction)


# -- the crossings (in the worker processes) --------------------------------------------------------------------
_FUNCTIONS: dict[tuple, Callable] = {}


def _expression_function(system: PiecewiseSystem, text: str) -> Callable[[np.ndarray, np.ndarray, np.ndarray],
                                                                            np.ndarray]:
    """``g(t, x, p)`` of an expression (as :func:`parse_section` wrote it), vectorised over times ``t``
    (shape (m,)) and states ``x`` (shape (m, n)); made once per process and model."""
    key = (system.fingerprint, text)
    if key not in _FUNCTIONS:
        import sympy as sp

        raw = sp.lambdify([system.t, *system.x, *system.p], sp.sympify(text, locals=_symbols(system)), modules="numpy")

        def g(t: np.ndarray, x: np.ndarray, p: np.ndarray) -> np.ndarray:
            with np.errstate(all="ignore"):
                value = raw(t, *x.T, *p)
            return np.broadcast_to(np.asarray(value, dtype=float), t.shape)

        _FUNCTIONS[key] = g
    return _FUNCTIONS[key]


def _expression_crossings(traj: Trajectory, g: Callable, p: np.ndarray, direction: int,
                          g_before: float | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Where ``g(t, x(t), p)`` changes sign in ``direction`` along a dense trajectory: the times, the states
    (shape (m, n)), and ``g`` at its end (``g_before`` of the trajectory run on from there).

    ``g`` is read at ``_GRID + 1`` points of every step; a rising crossing is a pair of consecutive points
    with ``g < 0`` then ``g >= 0`` (falling: ``g > 0`` then ``g <= 0``), so that a zero at a point counts
    once.  Where one step joins the next without a reset, the next step's first value is the previous
    step's last (the two interpolants differ by the integration tolerance there, and a zero at the joint
    would otherwise count twice or not at all); a pair across a reset is no crossing.  Each change of sign
    is bisected on its step's interpolant, :data:`_BISECTIONS` times.
    """
    t_old, h, s_end, y0, F = traj.dense_steps
    n = traj.x1.size
    if t_old.size == 0:
        return np.zeros(0), np.zeros((0, n)), g_before if g_before is not None else float("nan")
    grid = np.linspace(0.0, 1.0, _GRID + 1)
    ks = np.repeat(np.arange(t_old.size), grid.size)
    ss = (grid[None, :] * s_end[:, None]).reshape(-1)
    xs = dense_evaluate(F[ks], y0[ks], ss)
    gs = np.array(g(t_old[ks] + ss * h[ks], xs, p), dtype=float)
    firsts = np.arange(1, t_old.size) * grid.size  # the first point of every step but the first
    joined = np.all(np.abs(xs[firsts] - xs[firsts - 1]) <= _JUMP * (1.0 + np.abs(xs[firsts])), axis=1)
    gs[firsts[joined]] = gs[firsts[joined] - 1]
    if g_before is not None:
        gs[0] = g_before
    a, b = gs[:-1], gs[1:]
    hit = {1: (a < 0) & (b >= 0), -1: (a > 0) & (b <= 0)}
    found = hit[direction] if direction else hit[1] | hit[-1]
    idx = np.flatnonzero(found & (ks[:-1] == ks[1:]))
    if idx.size == 0:
        return np.zeros(0), np.zeros((0, n)), float(gs[-1])
    k, lo, hi, side = ks[idx], ss[idx].copy(), ss[idx + 1].copy(), np.sign(a[idx])
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        before = g(t_old[k] + mid * h[k], dense_evaluate(F[k], y0[k], mid), p) * side > 0  # still on lo's side
        lo, hi = np.where(before, mid, lo), np.where(before, hi, mid)
    return t_old[k] + hi * h[k], dense_evaluate(F[k], y0[k], hi), float(gs[-1])


_RATES: dict[tuple, Callable] = {}


def _event_direction(system: PiecewiseSystem, row: np.ndarray, t: float, x: np.ndarray, p: np.ndarray) -> int:
    """The direction in which an event crossed its surface: its transition's, or (for a transition that fires
    either way) the sign of ``dh/dt`` along the field of the mode it left."""
    transition = system.transitions[int(row[_TRANSITION])]
    if int(transition.direction) != 0:
        return int(transition.direction)
    key = (system.fingerprint, int(row[_MODE_FROM]), int(row[_SURFACE]))
    if key not in _RATES:
        import sympy as sp

        rate = system.lie_derivative(int(row[_MODE_FROM]), int(row[_SURFACE]))
        _RATES[key] = sp.lambdify([system.t, *system.x, *system.p], rate, modules="math")
    return 1 if _RATES[key](t, *x, *p) > 0 else -1


def _surface_crossings(traj: Trajectory, section: Section, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The times and states (just before each event, shape (m, n)) of a trajectory's switching events on the
    section's surface: transitions and starts of sliding, in the section's direction (None, 0: all)."""
    system = traj.system
    ev_t, rows, x_minus = traj.event_log[0], traj.event_log[1], traj.event_log[2]
    keep = (rows[:, _SURFACE] == system.surface_index(section.target)) & (rows[:, _KIND] != EventKind.SLIDING_END)
    idx = np.flatnonzero(keep)
    if section.direction:
        idx = np.array([i for i in idx if _event_direction(system, rows[i], float(ev_t[i]), x_minus[i], p)
                        == section.direction], dtype=int)
    return np.asarray(ev_t[idx], dtype=float), np.asarray(x_minus[idx], dtype=float).reshape(-1, system.n)
