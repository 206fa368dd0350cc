"""Results of continuation: branches of solutions and their special points."""

from __future__ import annotations

import copy
import inspect
import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from saltation.errors import SaltationError
from saltation.kinds import (  # noqa: F401  (the vocabulary's names here: where release 0.1 had them)
    NONSMOOTH_KINDS,
    BorderScenario,
    BranchKind,
    CodimensionTwoKind,
    Criticality,
    Limits,
    SpecialPointKind,
    SpecialPointStatus,
    StopReason,
)
from saltation.orbits.floquet import is_stable
from saltation.orbits.records import BranchPoint


@dataclass(frozen=True)
class OneSided:
    """The two sides of a non-smooth special point: what the orbit is just before and just after it.

    At a discontinuity-induced point the orbit's monodromy jumps (the saltation matrices of eq. (9) of
    the event that appears or vanishes), so the point has two one-sided monodromies ``M-`` and ``M+``
    and the set-valued multipliers ``eig((1 - q) M- + q M+)``, ``q`` in [0, 1] (eq. (45)).

    Attributes
    ----------
    multipliers_minus, multipliers_plus : ndarray or None
        The one-sided multipliers (eigenvalues of ``M-`` and ``M+``; ``inf`` where they grow without
        bound towards the point).
    monodromy_minus, monodromy_plus : ndarray or None
        The one-sided monodromy matrices (forward time where finite).
    event_labels_minus, event_labels_plus : tuple of str
        The event sequences on either side, by label.
    event_ids_minus, event_ids_plus : tuple of (int, int, int)
        The same sequences by identity, ``(kind, transition, mode entered)`` each
        (:func:`saltation.orbits.records.event_ids`; empty in files written before 2026-12-05).
    limits : Limits
        How the one-sided multipliers were obtained (a string enum: ``limits == "exact"`` holds).
    growth_exponents : tuple of float
        With ``limits`` EXTRAPOLATED: the fitted exponents ``a`` of ``|mu| ~ d^a`` of the multipliers
        that grow without bound towards the point (reported as ``inf``).
    crossing_q : float or None
        Where the set-valued multipliers cross the unit circle.
    crossing_point : complex or None
        The multiplier on the unit circle at ``crossing_q``.
    scenario : BorderScenario or None
        What Feigin's classification of the border collision predicts from the two sides' real multipliers
        (:func:`saltation.orbits.border_collision.feigin_scenario`): ``persistence`` (the orbit crosses the
        border), ``nonsmooth_fold`` (the orbits of both sides meet there and vanish) or ``undetermined``;
        None where it was not asked (and in files written before 2026-12-06).
    period_two : bool or None
        With ``scenario``: True where a period-two orbit is born at the point (an odd number of real
        multipliers less than -1 on the two sides together), False where the theorem says nothing about
        one, None where the scenario is undetermined or was not asked.

    Raises
    ------
    ValueError
        If ``limits`` or ``scenario`` is given as a name that is not one of its values.
    """

    multipliers_minus: np.ndarray | None = None
    multipliers_plus: np.ndarray | None = None
    monodromy_minus: np.ndarray | None = None
    monodromy_plus: np.ndarray | None = None
    event_labels_minus: tuple[str, ...] = ()
    event_labels_plus: tuple[str, ...] = ()
    event_ids_minus: tuple[tuple[int, int, int], ...] = ()
    event_ids_plus: tuple[tuple[int, int, int], ...] = ()
    limits: Limits = Limits.NONE
    growth_exponents: tuple[float, ...] = ()
    crossing_q: float | None = None
    crossing_point: complex | None = None
    scenario: BorderScenario | None = None
    period_two: bool | None = None

    def __post_init__(self):
        # names as files and older callers give them
        if self.scenario is not None and not isinstance(self.scenario, BorderScenario):
            object.__setattr__(self, "scenario", BorderScenario(self.scenario))
        if not isinstance(self.limits, Limits):
            limits, exponents = Limits.parse(str(self.limits))
            object.__setattr__(self, "limits", limits)
            if exponents and not self.growth_exponents:
                object.__setattr__(self, "growth_exponents", exponents)
        object.__setattr__(self, "growth_exponents", tuple(float(a) for a in self.growth_exponents))
        for name in ("event_labels_minus", "event_labels_plus"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        for name in ("event_ids_minus", "event_ids_plus"):
            object.__setattr__(self, name, tuple(tuple(int(i) for i in e) for e in getattr(self, name)))


@dataclass(frozen=True)
class Touch:
    """Where the orbit of a special point meets a switching surface without crossing it.

    At a grazing, a sliding bifurcation or a boundary equilibrium: the surface, the mode whose field is
    tangent to it there, and the instant.

    Attributes
    ----------
    surface : str
        The surface touched.
    mode : str
        The mode whose field is tangent to it there (empty when unknown).
    time : float
        The instant of the touch (``nan`` for an equilibrium, or when unknown).
    """

    surface: str
    mode: str = ""
    time: float = float("nan")


#: The flat names of the parts' fields (keyword arguments of :class:`SpecialPoint` and its properties).
_ONE_SIDED_NAMES = tuple(f.name for f in fields(OneSided))
_TOUCH_NAMES = {"touch_surface": "surface", "touch_mode": "mode", "touch_time": "time"}


@dataclass(frozen=True)
class SpecialPoint:
    """A located special point of a branch: a thin core and two optional typed parts.

    The core says what the point is, where, how precisely and on which orbit; :class:`OneSided` holds
    the two sides of a non-smooth point and :class:`Touch` the touch of a surface.  The parts' fields
    read as flat properties (``sp.multipliers_minus`` is ``sp.one_sided.multipliers_minus``, ``None``
    or empty without the part; ``sp.touch_surface`` is ``sp.touch.surface``), and the constructor takes
    them as flat keyword arguments too (``SpecialPoint(..., multipliers_minus=mu, touch_surface="h")``
    fills the parts).

    Attributes
    ----------
    kind : SpecialPointKind
        What the point is.
    parameter : float
        Located parameter value.
    bracket : (float, float)
        Parameter values on either side between which it was located.
    accuracy : float
        Width of the final bracket (how precisely it is located).
    index : int
        The point lies between branch points ``index`` and ``index + 1``.
    state, period, amplitude :
        The solution at the special point.
    multipliers : ndarray or None
        Multipliers at a smooth special point.
    event_ids : tuple of (int, int, int)
        The event sequence of the point's orbit by identity (smooth points; a non-smooth point has
        the two sides' in ``one_sided``).
    note : str
        A sentence on how it was found or classified.
    multipliers_accuracy : float
        How well the multipliers (one-sided or not) are known: an estimate of the error of their
        matrices (``nan`` when unknown).
    status : SpecialPointStatus
        Located by its defining system, bracketed between two solutions, or failed.
    second_parameter : float
        On a two-parameter curve: the second parameter's value at the point (``parameter`` is the
        first's; ``nan`` on a one-parameter branch).
    sides : (str, str)
        At a CODIMENSION_TWO point: the kinds of the special point on either side along the curve (where a
        corner's kind changes), or the curve's kind and the kind it meets there (a smooth point named by
        ``codimension_two``: ``("fold", "period_doubling")`` at a fold-flip, ``("neimark_sacker",
        "neutral_saddle")`` where a Neimark-Sacker curve turns into a neutral saddle at a 1:1 resonance).
    classification : str
        At a BOUNDARY_EQUILIBRIUM: ``persistence`` (the equilibrium of the mode and the pseudo-equilibrium
        exist on opposite sides of the point: one goes on as the other) or ``nonsmooth_fold`` (on the same
        side: they meet and disappear together).
    t0 : float
        The time at which the orbit passes ``state`` (a forced orbit's section, as for
        :attr:`BranchPoint.t0`); 0 for autonomous orbits and equilibria.
    one_sided : OneSided or None
        The two sides of a non-smooth point (None at a smooth one).
    touch : Touch or None
        Where the orbit touches a surface (grazing, sliding bifurcations, boundary equilibria).
    codimension_two : CodimensionTwoKind or None
        At a smooth CODIMENSION_TWO point of a fold, period-doubling or Neimark-Sacker curve: its name (cusp,
        a strong resonance, fold-flip ...); None elsewhere (and in files written before 2027-01).
    sensitivities : dict of str to float, or None
        How the point's parameter moves with each other parameter of the model, ``d parameter / d q`` by
        the implicit function theorem on its defining system
        (:func:`saltation.special_points.sensitivity.sensitivities`, which also gives the derivatives of
        the period and the state); None until they are asked for
        (:func:`saltation.special_points.sensitivity.add_sensitivities`).
    criticality : Criticality or None
        At a period doubling or a Neimark-Sacker point: whether the period-2 orbit or the torus is born stable
        (``supercritical``), unstable (``subcritical``), or the cubic coefficient vanishes within its accuracy
        (``degenerate``), from the normal form of the period map
        (:func:`saltation.orbits.criticality.criticality`); None elsewhere, where it could not be computed (it
        says why in the log), and in files written before 2026-12-05.
    normal_form : (float, float) or None
        The cubic normal-form coefficient behind ``criticality`` and its accuracy.

    Raises
    ------
    ValueError
        If ``status`` is given as a name that is not one of its values.
    TypeError
        If a keyword argument is neither a field nor a flat name of a part's field.
    """

    kind: SpecialPointKind
    parameter: float
    bracket: tuple[float, float]
    accuracy: float
    index: int
    state: np.ndarray
    period: float
    amplitude: float
    multipliers: np.ndarray | None = None
    event_ids: tuple[tuple[int, int, int], ...] = ()
    note: str = ""
    multipliers_accuracy: float = float("nan")
    status: SpecialPointStatus = SpecialPointStatus.BRACKETED
    second_parameter: float = float("nan")
    sides: tuple[str, ...] = ()
    classification: str = ""
    t0: float = 0.0
    one_sided: OneSided | None = None
    touch: Touch | None = None
    codimension_two: CodimensionTwoKind | None = None
    sensitivities: dict[str, float] | None = None
    criticality: Criticality | None = None
    normal_form: tuple[float, float] | None = None

    def __post_init__(self):
        if self.criticality is not None and not isinstance(self.criticality, Criticality):
            object.__setattr__(self, "criticality", Criticality(self.criticality))
        if self.codimension_two is not None and not isinstance(self.codimension_two, CodimensionTwoKind):
            object.__setattr__(self, "codimension_two", CodimensionTwoKind(self.codimension_two))
        if not isinstance(self.status, SpecialPointStatus):
            object.__setattr__(self, "status", SpecialPointStatus(self.status))
        object.__setattr__(self, "event_ids", tuple(tuple(int(i) for i in e) for e in self.event_ids))

    # the parts' fields, flat
    multipliers_minus = property(lambda self: self._side("multipliers_minus"))
    multipliers_plus = property(lambda self: self._side("multipliers_plus"))
    monodromy_minus = property(lambda self: self._side("monodromy_minus"))
    monodromy_plus = property(lambda self: self._side("monodromy_plus"))
    event_labels_minus = property(lambda self: self._side("event_labels_minus"))
    event_labels_plus = property(lambda self: self._side("event_labels_plus"))
    event_ids_minus = property(lambda self: self._side("event_ids_minus"))
    event_ids_plus = property(lambda self: self._side("event_ids_plus"))
    limits = property(lambda self: self._side("limits"))
    growth_exponents = property(lambda self: self._side("growth_exponents"))
    crossing_q = property(lambda self: self._side("crossing_q"))
    crossing_point = property(lambda self: self._side("crossing_point"))
    scenario = property(lambda self: self._side("scenario"))
    period_two = property(lambda self: self._side("period_two"))
    touch_surface = property(lambda self: self.touch.surface if self.touch is not None else "")
    touch_mode = property(lambda self: self.touch.mode if self.touch is not None else "")
    touch_time = property(lambda self: self.touch.time if self.touch is not None else float("nan"))

    def _side(self, name: str):
        return getattr(self.one_sided if self.one_sided is not None else _NO_SIDES, name)

    def _repr_markdown_(self) -> str:
        """A summary for Jupyter (:mod:`saltation.summary`)."""
        from saltation.summary import special_point_summary

        return special_point_summary(self)

    def __repr__(self) -> str:
        where = f"{self.parameter:.10g}"
        if self.second_parameter is not None and math.isfinite(self.second_parameter):
            where += f", {self.second_parameter:.10g}"
        sides = f" {self.sides[0]} -> {self.sides[1]}" if self.sides else ""
        if self.codimension_two is not None:
            sides = f" {self.codimension_two.value}{sides}"
        return f"SpecialPoint({self.kind.value}{sides} at {where}, located to {self.accuracy:.1e}, {self.status.value})"


_NO_SIDES = OneSided()
_init_fields = SpecialPoint.__init__


def _init_with_flat_names(self, *args, **kwargs) -> None:
    """The dataclass's ``__init__``, with the parts' fields also taken by their flat names."""
    sided = {name: kwargs.pop(name) for name in _ONE_SIDED_NAMES if name in kwargs}
    touched = {_TOUCH_NAMES[name]: kwargs.pop(name) for name in tuple(_TOUCH_NAMES) if name in kwargs}
    if sided:
        kwargs["one_sided"] = replace(kwargs.get("one_sided") or _NO_SIDES, **sided)
    if touched:
        touch = kwargs.get("touch")
        if touch is None:
            touch = Touch(**{"surface": "", **touched})
        else:
            touch = replace(touch, **touched)
        kwargs["touch"] = touch if touch.surface else None
    _init_fields(self, *args, **kwargs)


_init_with_flat_names.__signature__ = inspect.signature(_init_fields)  # type: ignore[attr-defined]
SpecialPoint.__init__ = _init_with_flat_names  # type: ignore[method-assign]


@dataclass
class Branch:
    """A branch of periodic orbits or equilibria, as columns per point plus special points.

    Attributes
    ----------
    model : str
        Name of the model.
    parameter_name : str
        The continuation parameter.
    kind : BranchKind
    backward : bool
        Whether its orbits were computed by backward-time shooting.
    points : list of BranchPoint
    special_points : list of SpecialPoint
    stop_reason : StopReason or None
        Why the (first) run stopped.
    stop_reasons : list
        Why each further run (other directions) stopped.
    stop_detail : str
        What a run that stopped because its corrector failed met there: the corrector's last error, where
        no special point explains the end (empty otherwise).
    fixed_parameters : dict
        Values of every parameter (the continuation parameter at the start point).
    label : str
        A name for plots ("stable periodic", "equilibrium", ...).
    autonomous : bool
        Whether its orbits are of an autonomous model (their period is an unknown).
    second_parameter_name : str
        On a two-parameter curve of special points (:func:`saltation.special_points.loci.follow_locus`):
        the second parameter, whose values are the column :attr:`second_parameter` (empty otherwise).
    curve_of : SpecialPointKind or None
        On such a curve: the kind of the special point it continues.
    state_names : tuple of str
        The model's states, in the order of each point's ``state`` (empty in files written before
        2026-11-26); they name the CSV columns.
    axis_labels : dict of str to str
        The axis label of each state and parameter as the model declares it (mathtext with its unit,
        :meth:`saltation.model.system.PiecewiseSystem.axis_label`); plots use them.
    measures : tuple of str
        The measures of the orbits every point records (:attr:`BranchPoint.measures`,
        :mod:`saltation.orbits.measures`; :meth:`measure` gives a column).
    problem : BranchProblem or None
        The problem the branch was computed with (set by the continuation; not written to files, and
        None for a branch read from one): two-parameter curves and branch switches start from it.
    """

    model: str
    parameter_name: str
    kind: BranchKind
    backward: bool = False
    points: list[BranchPoint] = field(default_factory=list)
    special_points: list[SpecialPoint] = field(default_factory=list)
    stop_reason: StopReason | None = None
    stop_reasons: list[StopReason | None] = field(default_factory=list)
    stop_detail: str = ""
    fixed_parameters: dict[str, float] = field(default_factory=dict)
    label: str = ""
    autonomous: bool = False
    second_parameter_name: str = ""
    curve_of: SpecialPointKind | None = None
    state_names: tuple[str, ...] = ()
    axis_labels: dict[str, str] = field(default_factory=dict)
    measures: tuple[str, ...] = ()
    #: The problem the branch was computed with (set by the continuation; not a field: not compared, not
    #: written to files).  Curves in two parameters and branch switches start from it.
    problem = None

    def _repr_markdown_(self) -> str:
        """A summary for Jupyter (:mod:`saltation.summary`)."""
        from saltation.summary import branch_summary

        return branch_summary(self)

    def __repr__(self) -> str:
        from saltation.summary import stop_text

        name = type(self).__name__
        if not len(self):
            return f"{name}({self.model!r}, {self.kind.value}, no points)"
        lam = self.parameter
        span = f"{self.parameter_name} {lam[0]:.6g} .. {lam[-1]:.6g}"
        if self.second_parameter_name:
            mu = self.second_parameter
            span += f", {self.second_parameter_name} {mu[0]:.6g} .. {mu[-1]:.6g}"
        kinds = ", ".join(sp.kind.value for sp in self.special_points[:4]) + (", ..." if len(self.special_points) > 4 else "")
        special = f"{len(self.special_points)} special point{'s' if len(self.special_points) != 1 else ''}"
        special += f" ({kinds})" if kinds else ""
        stop = stop_text(self)
        return (f"{name}({self.model!r}, {self.label or self.kind.value}, {span}, {len(self)} point"
                f"{'s' if len(self) != 1 else ''} ({int(np.count_nonzero(self.stable))} stable), {special}"
                + (f", stopped: {stop}" if stop else "") + ")")

    def __len__(self) -> int:
        return len(self.points)

    # columns
    @property
    def parameter(self) -> np.ndarray:
        return np.array([p.parameter for p in self.points])

    @property
    def second_parameter(self) -> np.ndarray:
        """The second parameter's column on a two-parameter curve (``nan`` on a one-parameter branch)."""
        return np.array([p.second_parameter for p in self.points])

    def measure(self, text: str) -> np.ndarray:
        """The column of one of the branch's measures (:attr:`measures`).

        Parameters
        ----------
        text : str
            The measure, as it was asked for (``"norm"``, ``"sqrt(x**2 + y**2)"``).

        Returns
        -------
        ndarray
            Its value at every point (``nan`` where a point lacks it).

        Raises
        ------
        KeyError
            If the branch was not computed with that measure (the message lists those it has).
        """
        if text not in self.measures and not any(text in p.measures for p in self.points):
            raise KeyError(f"the branch has no measure {text!r}; its measures: {', '.join(self.measures) or 'none'} "
                           "(ContinuationSettings(measures=...))")
        return np.array([p.measures.get(text, np.nan) for p in self.points], dtype=float)

    @property
    def curve_kinds(self) -> list[SpecialPointKind | None]:
        """On a two-parameter curve of non-smooth points: the kind of the point at each curve point
        (:attr:`BranchPoint.curve_kind`; None elsewhere)."""
        return [p.curve_kind for p in self.points]

    @property
    def amplitude(self) -> np.ndarray:
        return np.array([p.amplitude for p in self.points])

    @property
    def half_peak_to_peak(self) -> np.ndarray:
        return np.array([p.half_peak_to_peak for p in self.points])

    @property
    def period(self) -> np.ndarray:
        return np.array([p.period for p in self.points])

    @property
    def stable(self) -> np.ndarray:
        return np.array([p.stable for p in self.points], dtype=bool)

    @property
    def states(self) -> np.ndarray:
        return np.array([p.state for p in self.points])

    @property
    def mode0(self) -> list[str | None]:
        """The mode each point's orbit starts in (:attr:`BranchPoint.mode0`; None for equilibria, and for points
        read from files written before it was recorded)."""
        return [p.mode0 for p in self.points]

    @property
    def multipliers(self) -> np.ndarray:
        """Multipliers per point, shape (m, n), complex."""
        return np.array([p.multipliers for p in self.points])

    def to_pandas(self):
        """The branch as a table: one row per point, columns named after the parameters and the states.

        Columns: the continuation parameter (by its name; the second parameter too on a two-parameter
        curve), the state at the section (by the states' names; ``state_<name>`` where a name is taken by
        another column), ``period``, ``amplitude``, ``half_peak_to_peak``, ``stable``, the multipliers
        ``multiplier1`` .. (complex; ``eigenvalue1`` .. on a branch of equilibria) with their moduli
        ``multiplier1_abs`` .., ``events`` (the event sequence of one period, its labels joined by ``"; "``),
        ``event_count``, ``mode0``, ``t0``, ``step``, ``iterations``, ``curve_kind`` and ``special_point``
        (the kinds of the special points located between this point and the next, ``", "``-joined; empty
        elsewhere), then one column per measure the branch was computed with (:attr:`measures`, by its text;
        ``measure <text>`` where the text is taken).  ``DataFrame.attrs`` holds the branch's metadata (model, parameters, kind, label, how each
        run stopped).

        Returns
        -------
        pandas.DataFrame

        Raises
        ------
        MissingDependencyError
            If pandas is not installed (``pip install 'saltation[pandas]'``).
        """
        from saltation._optional import require

        pd = require("pandas", "pandas", "Branch.to_pandas")
        names = [self.parameter_name] + ([self.second_parameter_name] if self.second_parameter_name else [])
        columns: dict[str, object] = {names[0]: self.parameter}
        if self.second_parameter_name:
            columns[names[1]] = self.second_parameter
        n = len(self.points[0].state) if self.points else len(self.state_names)
        fixed = {"period", "amplitude", "half_peak_to_peak", "stable", "events", "event_count", "mode0", "t0", "step",
                 "iterations", "curve_kind", "special_point", *names}
        for i, name in enumerate(self.state_names or [f"x{i + 1}" for i in range(n)]):
            columns[f"state_{name}" if name in fixed else name] = self.states[:, i] if self.points else []
        columns |= {"period": self.period, "amplitude": self.amplitude, "half_peak_to_peak": self.half_peak_to_peak,
                    "stable": self.stable}
        value = "eigenvalue" if self.kind is BranchKind.EQUILIBRIUM else "multiplier"
        mu = self.multipliers.reshape(len(self.points), -1) if self.points else np.zeros((0, n), dtype=complex)
        for i in range(mu.shape[1]):
            columns[f"{value}{i + 1}"] = mu[:, i]
            columns[f"{value}{i + 1}_abs"] = np.abs(mu[:, i])
        special = ["" for _ in self.points]
        for sp in self.special_points:
            if 0 <= sp.index < len(special):
                special[sp.index] = ", ".join(filter(None, (special[sp.index], sp.kind.value)))
        columns |= {
            "events": ["; ".join(p.event_labels) for p in self.points],
            "event_count": [len(p.event_labels) for p in self.points],
            "mode0": [p.mode0 for p in self.points], "t0": [p.t0 for p in self.points],
            "step": [p.step for p in self.points], "iterations": [p.iterations for p in self.points],
            "curve_kind": [None if p.curve_kind is None else p.curve_kind.value for p in self.points],
            "special_point": special,
        }
        for text in self.measures:  # the measures the branch was computed with, by their text
            columns[text if text not in columns else f"measure {text}"] = self.measure(text)
        table = pd.DataFrame(columns)
        table.attrs = {
            "model": self.model, "parameter_name": self.parameter_name, "kind": self.kind.value, "label": self.label,
            "backward": self.backward, "autonomous": self.autonomous, "fixed_parameters": dict(self.fixed_parameters),
            "second_parameter_name": self.second_parameter_name,
            "curve_of": None if self.curve_of is None else self.curve_of.value,
            "stop_reasons": [None if r is None else r.name.lower() for r in [self.stop_reason, *self.stop_reasons]],
            "stop_detail": self.stop_detail,
        }
        return table

    def check_stability_flags(self) -> bool:
        """Whether every stored stability flag agrees with the stored multipliers.

        Returns
        -------
        bool
            True when each point's ``stable`` is what its multipliers say (eigenvalues with negative
            real parts, for equilibria).
        """
        if self.kind is BranchKind.EQUILIBRIUM:
            return all(p.stable == bool(np.all(np.real(p.multipliers) < 0)) for p in self.points)
        return all(p.stable == is_stable(p.multipliers, autonomous=self.autonomous) for p in self.points)

    def check(self):
        """The invariants every computed branch must hold (:func:`saltation.branches.check.check_branch`):
        the trivial multiplier at 1, every change of stability covered by a special point of the right
        kind, honest brackets, no silent stop.

        Returns
        -------
        BranchCheck
            Its ``violations`` (``.ok`` when there are none; ``.raise_if_broken()`` raises).
        """
        from saltation.branches.check import check_branch

        return check_branch(self)

    def extend(self, other: Branch) -> None:
        """Prepend a run of the same branch in the other direction from the same start point.

        The other run's points (its start point dropped) are reversed and put first, and every special
        point's ``index`` is moved to match.

        Parameters
        ----------
        other : Branch
            The run in the other direction, from the same start point.
        """
        m = len(other.points)
        self.stop_detail = "; ".join(d for d in (other.stop_detail, self.stop_detail) if d)
        self.points = list(reversed(other.points[1:])) + self.points
        moved = [_reindex(sp, m - 2 - sp.index) for sp in other.special_points]
        self.special_points = moved + [_reindex(sp, sp.index + m - 1) for sp in self.special_points]


def _reindex(sp: SpecialPoint, index: int) -> SpecialPoint:
    return replace(sp, index=index)


def problem_and_point(source, point: SpecialPoint | int, what: str):
    """The problem and the special point a curve or a branch switch starts from.

    From a :class:`Branch` (``source``), a copy of the problem it was computed with (the branch's own is
    left as it is) and its special point ``point`` (a :class:`SpecialPoint` or its index in
    ``special_points``); from a problem, that problem and ``point`` as given (the form of release 0.1, kept).

    Parameters
    ----------
    source : Branch or BranchProblem
        What the user holds.
    point : SpecialPoint or int
        The special point, or its index on the branch.
    what : str
        What starts there, for the error messages.

    Returns
    -------
    tuple of (BranchProblem, SpecialPoint)
        The problem and the point.

    Raises
    ------
    SaltationError
        If the branch holds no problem (it was read from a file), or the index names no special point.
    """
    if not isinstance(source, Branch):
        if not isinstance(point, SpecialPoint):
            raise SaltationError(f"{what}: a special point by index needs the branch, not its problem")
        return source, point
    if source.problem is None:
        raise SaltationError(f"{what}: this branch holds no problem (it was read from a file): pass the problem it "
                             "was computed with, e.g. ShootingProblem(flow, parameters, continuation_parameter=...)")
    if not isinstance(point, SpecialPoint):
        count = len(source.special_points)
        if isinstance(point, bool) or not isinstance(point, (int, np.integer)) or not -count <= point < count:
            raise SaltationError(f"{what}: the branch has {count} special points; {point!r} is not an index of one")
        point = source.special_points[int(point)]
    return copy.copy(source.problem), point
