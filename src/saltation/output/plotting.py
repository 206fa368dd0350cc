"""Figures of branches, Floquet multipliers and phase planes, drawn as in *Fold bifurcations
in discontinuous systems*: stable solutions solid, unstable ones dash-dot (Figs. 3 and 7),
jumps of the multipliers at non-smooth points dotted (Fig. 4).

Every function draws on a given ``Axes`` or on a new :class:`matplotlib.figure.Figure`
(never through ``pyplot``, so no global figure state is created or leaked) and returns the
figure. :func:`save_figure` writes a PNG and a PDF.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from saltation.branches.branch import Branch, BranchKind, SpecialPoint, SpecialPointKind
from saltation.model.labels import tex_name
from saltation.orbits.measures import measure_label
from saltation.sweeps.sections import Section
from saltation.sweeps.sweeps import PeriodMap, SweepResult

__all__ = [
    "CurveStyle",
    "NotebookFigure",
    "MEASURE_LABELS",
    "PUBLICATION_RC",
    "PhaseCurve",
    "SPECIAL_POINT_MARKERS",
    "axis_label",
    "figure_of",
    "new_figure",
    "plot_loci",
    "plot_multipliers",
    "plot_period_map",
    "plot_phase_plane",
    "plot_response",
    "plot_sweep",
    "save_figure",
    "save_figures",
]

#: matplotlib settings :func:`save_figure` writes with: TrueType (Type 42) fonts in PDF and PostScript
#: (matplotlib's default, Type 3, is refused by several journals), also for mathtext.
PUBLICATION_RC = {"pdf.fonttype": 42, "ps.fonttype": 42}

STABLE_STYLE = "-"
UNSTABLE_STYLE = "-."
JUMP_STYLE = ":"

#: Marker and legend text per kind of special point.
SPECIAL_POINT_MARKERS: dict[SpecialPointKind, tuple[str, str]] = {
    SpecialPointKind.FOLD: ("o", "fold"),
    SpecialPointKind.BRANCH_POINT: ("x", "branch point"),
    SpecialPointKind.PERIOD_DOUBLING: ("s", "period doubling"),
    SpecialPointKind.NEIMARK_SACKER: ("D", "Neimark-Sacker"),
    SpecialPointKind.HOPF: ("^", "Hopf"),
    SpecialPointKind.DISCONTINUOUS_FOLD: ("*", "discontinuous fold"),
    SpecialPointKind.DISCONTINUOUS_FLIP: ("P", "discontinuous flip"),
    SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER: ("X", "discontinuous Neimark-Sacker"),
    SpecialPointKind.NONSMOOTH_NO_CROSSING: ("v", "non-smooth point, no crossing"),
    SpecialPointKind.GRAZING: ("h", "grazing"),
    SpecialPointKind.MONITOR: ("3", "monitor"),
    SpecialPointKind.GRAZING_SLIDING: ("H", "grazing-sliding"),
    SpecialPointKind.CROSSING_SLIDING: ("<", "crossing-sliding"),
    SpecialPointKind.SWITCHING_SLIDING: (">", "switching-sliding"),
    SpecialPointKind.ADDING_SLIDING: ("d", "adding-sliding"),
    SpecialPointKind.CYCLE_COLLAPSE: ("8", "cycle collapses onto an equilibrium"),
    SpecialPointKind.CODIMENSION_TWO: ("p", "codimension-two point of a curve"),
    SpecialPointKind.BOUNDARY_EQUILIBRIUM: ("+", "boundary equilibrium"),
    SpecialPointKind.SYMMETRY_BREAKING: ("1", "symmetry breaking"),
    SpecialPointKind.DISCONTINUOUS_SYMMETRY_BREAKING: ("2", "discontinuous symmetry breaking"),
}

#: Axis label per amplitude measure (mathtext); ``{x}`` is the first state as mathtext.
MEASURE_LABELS: dict[str, str] = {
    "amplitude": r"$A = \max_t\,|{x}|$",
    "half_peak_to_peak": r"$A = \frac{{1}}{{2}}\,(\max_t {x} - \min_t {x})$",
}

def axis_label(name: str, labels: Mapping[str, str] | None = None) -> str:
    """The axis label of a state or parameter: the model's own label when it declares one (see
    :class:`saltation.model.system.PiecewiseSystem`, ``labels`` and ``units``; a branch records them in
    :attr:`~saltation.branches.branch.Branch.axis_labels`), else the name as mathtext.

    Parameters
    ----------
    name : str
    labels : mapping of str to str, optional
        Axis labels by name, as a branch records them.

    Returns
    -------
    str

    Raises
    ------
    Nothing: every name has a label.
    """
    if labels and name in labels:
        return labels[name]
    return f"${tex_name(name)}$" if name else ""

Measure = str | Callable[[Branch], np.ndarray]


class NotebookFigure(Figure):
    """A :class:`matplotlib.figure.Figure` that Jupyter shows, once, as the last expression of a cell.

    It is made without ``pyplot``, so no backend shows it on its own, and it renders itself as PNG for
    IPython's display (``_repr_png_``), whatever the backend (with ``%matplotlib inline`` IPython's own
    formatter for figures draws the same PNG).  Everything else is a plain figure: ``savefig``,
    :func:`save_figure`, adding axes.
    """

    def _repr_png_(self) -> bytes:
        from io import BytesIO

        buffer = BytesIO()
        self.savefig(buffer, format="png", dpi=100)
        return buffer.getvalue()


def new_figure(figsize: tuple[float, float] = (6.4, 4.8)) -> NotebookFigure:
    """A new figure of this module's kind (constrained layout, shown by Jupyter once; see :class:`NotebookFigure`).

    Parameters
    ----------
    figsize : (float, float)
        Width and height in inches.

    Returns
    -------
    NotebookFigure

    Raises
    ------
    ValueError
        If the size is not positive (matplotlib's check).
    """
    return NotebookFigure(figsize=figsize, layout="constrained")


def figure_of(ax: Axes) -> Figure:
    """The figure of a caller's ``Axes``, to be returned by a plotting function.

    A figure of ``pyplot`` is shown by a notebook's inline backend when the cell ends; returned as the
    cell's last expression, IPython's formatter would show it once more.  So, in IPython, this figure's
    PNG is drawn once by whichever display comes first (the cell's result, or the backend's), which
    then closes it in ``pyplot`` (as the inline backend does after every cell) so that the backend does
    not draw it again.  Figures made without ``pyplot`` are left as they are.

    Parameters
    ----------
    ax : Axes

    Returns
    -------
    Figure
        ``ax.figure``.

    Raises
    ------
    Nothing of its own: outside IPython it only returns the figure.
    """
    fig = ax.figure
    if getattr(getattr(fig, "canvas", None), "manager", None) is None:
        return fig
    try:
        from IPython import get_ipython
    except ImportError:
        return fig
    shell = get_ipython()
    formatters = getattr(getattr(shell, "display_formatter", None), "formatters", {})
    png = formatters.get("image/png")
    if png is None:
        return fig
    import weakref

    key = id(fig)

    def once(figure):
        png.singleton_printers.pop(key, None)
        from IPython.core.pylabtools import print_figure
        from matplotlib import pyplot

        data = print_figure(figure, "png")
        pyplot.close(figure)  # the backend's own display at the cell's end skips it now
        return data

    png.singleton_printers[key] = once
    weakref.finalize(fig, png.singleton_printers.pop, key, None)
    return fig


def _new_axes(ax: Axes | None, figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is not None:
        return figure_of(ax), ax
    fig = new_figure(figsize)
    return fig, fig.add_subplot()


def _as_list(branches: Branch | Iterable[Branch]) -> list[Branch]:
    return [branches] if isinstance(branches, Branch) else list(branches)


# ---------------------------------------------------------------------------
# response / bifurcation diagram
# ---------------------------------------------------------------------------


def _measure_values(branch: Branch, measure: Measure) -> np.ndarray:
    if callable(measure):
        return np.asarray(measure(branch), dtype=float)
    if measure in MEASURE_LABELS:
        return getattr(branch, measure)
    if measure in branch.measures:
        return branch.measure(measure)
    raise ValueError(f"unknown amplitude measure {measure!r}; use one of {sorted(MEASURE_LABELS)}, a measure the "
                     f"branch was computed with ({', '.join(branch.measures) or 'none'}: "
                     "ContinuationSettings(measures=...)) or a callable")


def _special_point_y(branch: Branch, sp: SpecialPoint, y: np.ndarray, measure: Measure) -> float:
    """The measure at a special point: stored for ``amplitude``, else interpolated between its neighbours."""
    if measure == "amplitude":
        return float(sp.amplitude)
    p = branch.parameter
    i = int(np.clip(sp.index, 0, len(p) - 1))
    j = min(i + 1, len(p) - 1)
    dp = p[j] - p[i]
    t = 0.5 if dp == 0 else float(np.clip((sp.parameter - p[i]) / dp, 0.0, 1.0))
    return float((1 - t) * y[i] + t * y[j])


def stability_runs(
    branch: Branch, y: np.ndarray, special_y: dict[int, float] | None = None
) -> list[tuple[bool, np.ndarray, np.ndarray]]:
    """Split a branch into runs of equal stability.

    Parameters
    ----------
    branch : Branch
    y : ndarray, shape (m,)
        The plotted measure per point.
    special_y : dict, optional
        ``index -> y`` of special points; where stability changes between points ``i`` and
        ``i + 1`` and a special point has index ``i``, both runs end at that special point,
        otherwise they meet half way between the two points.

    Returns
    -------
    list of (stable, x, y)
        Consecutive runs; neighbouring runs share their end point so the curve is unbroken.
    """
    x = branch.parameter
    stable = branch.stable
    special_y = special_y or {}
    sp_x = {sp.index: sp.parameter for sp in branch.special_points}
    runs: list[tuple[bool, np.ndarray, np.ndarray]] = []
    if len(x) == 0:
        return runs
    start = 0
    head: tuple[float, float] | None = None
    for i in range(len(x)):
        last = i == len(x) - 1
        if not last and stable[i + 1] == stable[i]:
            continue
        xs, ys = list(x[start : i + 1]), list(y[start : i + 1])
        if head is not None:
            xs.insert(0, head[0])
            ys.insert(0, head[1])
        if not last:
            if i in special_y:
                head = (sp_x[i], special_y[i])
            else:
                head = (0.5 * (x[i] + x[i + 1]), 0.5 * (y[i] + y[i + 1]))
            xs.append(head[0])
            ys.append(head[1])
        runs.append((bool(stable[i]), np.array(xs), np.array(ys)))
        start = i + 1
    return runs


def plot_response(
    branches: Branch | Iterable[Branch],
    ax: Axes | None = None,
    *,
    measure: Measure = "amplitude",
    ylabel: str | None = None,
    xlabel: str | None = None,
    state_name: str | None = None,
    colors: Sequence[str] | None = None,
    special_points: bool = True,
    legend: bool = True,
    figsize: tuple[float, float] = (6.0, 4.5),
) -> Figure:
    """Response (bifurcation) diagram: an amplitude measure against the parameter.

    Stable segments are drawn solid and unstable ones dash-dot (Figs. 3 and 7); each branch is
    split into runs by its ``stable`` column. Special points are marked, one marker per kind.

    Crowded special points are grouped: a point closer than 3 % of the data's extent (on each axis, so
    about the same distance on screen) to a group's first point joins that group.  The first point of a
    group is drawn full size with an open marker, named by the legend; the others smaller with filled
    markers, on top, and named beside the group by at most four labels: one per kind with its count
    (``"grazing ×5"``), the fourth counting the points of any further kinds (``"7 more special
    points"``).  A label stands a bounded offset from its marker, towards the middle of the axes, in the
    first of a few places where it lies inside the axes and overlaps no other label; with no such place
    it is left out, and the legend's entry for filled markers (there when any marker is filled) counts
    its points.  So the open markers, the labels' counts and the points left out add up to the number of
    special points.  Labels and legend take no part in the figure's layout (the axes keep their size
    however many points there are; a legend of more than 12 entries is set in two columns), and a label
    is not drawn when its point lies outside the axes.

    Parameters
    ----------
    branches : Branch or iterable of Branch
    ax : Axes, optional
        Draw here; by default on a new figure.
    measure : {"amplitude", "half_peak_to_peak"} or callable
        ``"amplitude"`` is ``max |x_1|`` over a period, ``"half_peak_to_peak"`` is
        ``(max x_1 - min x_1) / 2``; a callable maps a branch to one value per point.
    ylabel : str, optional
        Defaults to a label naming the measure (required wording for a callable measure).
    xlabel : str, optional
        Defaults to the first branch's parameter, as its model labels it (mathtext and unit).
    state_name : str, optional
        The first state in the default y label; by default the branch's first state, as its model
        labels it.
    colors : sequence of str, optional
        One colour per branch; defaults to black for all (the paper's style).
    special_points : bool
        Mark the branches' special points (crowded ones grouped, as above).
    legend : bool
        Add a legend (line styles, branch labels, kinds of special points present, filled markers).
    figsize : (float, float)
        Size of a new figure, in inches.

    Returns
    -------
    Figure

    Raises
    ------
    ValueError
        For an unknown measure name.
    """
    branches = _as_list(branches)
    fig, ax = _new_axes(ax, figsize)
    handles: list[Line2D] = []
    kinds_seen: list[SpecialPointKind] = []
    marks_at: list[tuple[SpecialPointKind, float, float]] = []
    all_x: list[float] = []
    all_y: list[float] = []
    drawn: dict[tuple[bool, bool], None] = {}  # (equilibrium, stable) styles drawn, in order: the legend's
    for b, branch in enumerate(branches):
        color = colors[b % len(colors)] if colors else "k"
        y = _measure_values(branch, measure)
        sp_y = {sp.index: _special_point_y(branch, sp, y, measure) for sp in branch.special_points}
        equilibria = branch.kind is BranchKind.EQUILIBRIUM
        for stable, xs, ys in stability_runs(branch, y, sp_y):
            style = _run_style(equilibria, stable)
            ax.plot(xs, ys, color=style.get("color", color) if not colors else color,
                    **{k: v for k, v in style.items() if k != "color"},
                    gid=("equilibrium_" if equilibria else "") + ("stable" if stable else "unstable"))
            drawn[(equilibria, stable)] = None
        if branch.label and colors:
            handles.append(Line2D([], [], color=color, label=branch.label))
        if special_points:
            for sp in branch.special_points:
                marks_at.append((sp.kind, float(sp.parameter), float(_special_point_y(branch, sp, y, measure))))
                if sp.kind not in kinds_seen:
                    kinds_seen.append(sp.kind)
        all_x.extend(branch.parameter)
        all_y.extend(np.asarray(y, dtype=float)[np.isfinite(y)])
    filled = _mark_special_points(ax, marks_at, all_x, all_y)
    runs_styles = [Line2D([], [], **_run_style(eq, stable), label=_RUN_NAMES[(eq, stable)]) for eq, stable in drawn]
    marks = [
        Line2D([], [], linestyle="none", marker=SPECIAL_POINT_MARKERS[k][0], markersize=9,
               markerfacecolor="white", markeredgecolor="k", label=SPECIAL_POINT_MARKERS[k][1])
        for k in kinds_seen
    ] + ([filled] if filled is not None else [])
    first = branches[0] if branches else None
    if ylabel is None:
        ylabel = _measure_label(measure, first, state_name)
    ax.set_ylabel(ylabel)
    if xlabel is None:
        xlabel = axis_label(first.parameter_name, first.axis_labels) if first is not None else ""
    ax.set_xlabel(xlabel)
    if legend:
        entries = runs_styles + handles + marks
        box = ax.legend(handles=entries, loc="best", fontsize="small", ncol=1 if len(entries) <= _LEGEND_ROWS else 2)
        box.set_in_layout(False)  # inside the axes: shrinking them to make room would only make it overflow more
    return fig


#: Entries of a response diagram's legend in one column at most; more are set in two.
_LEGEND_ROWS = 12


_RUN_NAMES = {(False, True): "stable", (False, False): "unstable", (True, True): "equilibrium, stable",
              (True, False): "equilibrium, unstable"}


def _run_style(equilibria: bool, stable: bool) -> dict:
    """Line style of a run of a branch: periodic orbits black, solid where stable and dash-dot where not
    (the paper's Figs. 3 and 7); equilibria thinner, grey, solid or dotted (distinct in black and white)."""
    if equilibria:
        return {"color": "0.45", "linestyle": "-" if stable else ":", "linewidth": 1.2}
    return {"color": "k", "linestyle": STABLE_STYLE if stable else UNSTABLE_STYLE, "linewidth": 1.5}


def _measure_label(measure: Measure, branch: Branch | None, state_name: str | None) -> str:
    """The y label of a measure: mathtext of the first state, with its unit if the model declares one."""
    if not isinstance(measure, str):
        return "A"
    if measure not in MEASURE_LABELS:
        return measure_label(measure)
    unit = ""
    if state_name is None:
        name = branch.state_names[0] if branch is not None and branch.state_names else "x"
        label = branch.axis_labels.get(name, "") if branch is not None else ""
        tex = label.split("$")[1] if label.count("$") >= 2 else tex_name(name)
        unit = label.rsplit("$", 1)[-1] if label.count("$") >= 2 else ""
    else:
        tex = tex_name(state_name)
    return MEASURE_LABELS[measure].format(x=tex) + unit


#: Special points closer than this to a group's first point (a fraction of the data's extent on each axis,
#: so about the same distance on screen in either direction) are drawn as one group (see :func:`plot_response`).
_NEAR = 0.03
#: At most this many labels name the filled markers of a group; past it the last one counts the rest.
_MAX_LABELS = 4
#: A label's offset from its marker, in points: sideways, and up or down by one of ``_LABEL_SLOTS`` steps.
_LABEL_DX, _LABEL_DY, _LABEL_SLOTS = 24.0, 14.0, 6

_Mark = tuple[SpecialPointKind, float, float]


def _group_special_points(marks: Sequence[_Mark], width: float, height: float, near: float) -> list[list[_Mark]]:
    """Groups of special points, in order: a point joins the first group whose first point lies closer than
    ``near`` (a fraction of ``width`` and ``height``), else it starts a group of its own.  So every group
    spans at most ``2 near``, and the first points of two groups are at least ``near`` apart."""
    groups: list[list[_Mark]] = []
    for mark in marks:
        _, x, y = mark
        for group in groups:
            _, gx, gy = group[0]
            if math.hypot((x - gx) / width, (y - gy) / height) < near:
                group.append(mark)
                break
        else:
            groups.append([mark])
    return groups


def _group_labels(others: Sequence[_Mark], most: int = _MAX_LABELS) -> list[tuple[str, str, int, float, float]]:
    """The labels of a group's filled markers: ``(text, gid, count, x, y)``, ``(x, y)`` the marker the
    leader line goes to.

    One label per kind, in the order the kinds come, ``"grazing"`` for one point and ``"grazing ×5"`` for
    five; past ``most`` kinds the last label counts the points of the remaining kinds (``"7 more special
    points"``, gid ``special_points_label``), so the counts of a group's labels add up to ``len(others)``."""
    by_kind: dict[SpecialPointKind, list[_Mark]] = {}
    for mark in others:
        by_kind.setdefault(mark[0], []).append(mark)
    kinds = list(by_kind)
    named = kinds if len(kinds) <= most else kinds[: most - 1]
    labels = []
    for kind in named:
        (_, x, y), n, name = by_kind[kind][0], len(by_kind[kind]), SPECIAL_POINT_MARKERS[kind][1]
        text = name if n == 1 else f"{name} \N{MULTIPLICATION SIGN}{n}"
        labels.append((text, f"{kind.value}_label", n, x, y))
    rest = [mark for kind in kinds[len(named):] for mark in by_kind[kind]]
    if rest:
        labels.append((f"{len(rest)} more special points", "special_points_label", len(rest), rest[0][1], rest[0][2]))
    return labels


def _place_labels(ax: Axes, labels: Sequence[tuple[str, str, int, float, float]]) -> int:
    """Annotate the labels (:func:`_group_labels`), each where its text has room; return how many points
    the labels left out name (those that found no room).

    A label's text stands ``_LABEL_DX`` points beside its marker, towards the middle of the axes, and
    ``_LABEL_DY`` times 1 to ``_LABEL_SLOTS`` points above or below it (towards the middle first), in the
    first place where its box (measured from the font) lies inside the axes and overlaps no label placed
    before it; with no such place it is left out.  The axes are measured as they are now, before the
    figure's layout, which only moves the points apart if it enlarges them.  The labels take no part in
    the layout and are not drawn when their point lies outside the axes."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import text_to_path

    ax.get_xlim(), ax.get_ylim()  # (the limits the markers made)
    prop = FontProperties(size="x-small")
    scale = ax.figure.dpi / 72.0
    pad = 2.0 * scale
    frame = ax.bbox
    placed: list[tuple[float, float, float, float]] = []
    left_out = 0
    for text, gid, count, x, y in labels:
        px, py = ax.transData.transform((x, y))
        fx, fy = ax.transAxes.inverted().transform((px, py))
        dx, dy = (-1.0 if fx > 0.5 else 1.0), (-1.0 if fy > 0.5 else 1.0)  # towards the middle
        w, h, _ = text_to_path.get_text_width_height_descent(text, prop, ismath=False)
        w, h = w * scale, h * scale
        for offset in [dy * _LABEL_DY * s for s in range(1, _LABEL_SLOTS + 1)] + \
                      [-dy * _LABEL_DY * s for s in range(1, _LABEL_SLOTS + 1)]:
            x0 = px + dx * _LABEL_DX * scale - (w if dx < 0 else 0.0)
            y0 = py + offset * scale - 0.5 * h
            box = (x0 - pad, y0 - pad, x0 + w + pad, y0 + h + pad)
            inside = frame.x0 <= box[0] and box[2] <= frame.x1 and frame.y0 <= box[1] and box[3] <= frame.y1
            if inside and not any(b[0] < box[2] and box[0] < b[2] and b[1] < box[3] and box[1] < b[3] for b in placed):
                break
        else:
            left_out += count
            continue
        placed.append(box)
        label = ax.annotate(text, xy=(x, y), xytext=(dx * _LABEL_DX, offset), textcoords="offset points",
                            ha="right" if dx < 0 else "left", va="center", fontsize="x-small", gid=gid,
                            annotation_clip=True, arrowprops={"arrowstyle": "-", "color": "0.4", "linewidth": 0.6,
                                                             "shrinkA": 0, "shrinkB": 4})
        label.set_in_layout(False)
    return left_out


def _mark_special_points(ax: Axes, marks: Sequence[_Mark], all_x: Sequence[float], all_y: Sequence[float], *,
                         near: float = _NEAR) -> Line2D | None:
    """Draw special-point markers, each at its point, and name crowded ones; return the legend's entry for
    filled markers (``None`` when none is filled).

    The points are grouped (:func:`_group_special_points`: closer than ``near``, a fraction of the data's
    extent, to a group's first point).  A group's first point is drawn full size and open, named by the
    legend as its kind; each other one smaller and filled, on top, so that none hides another.  The filled
    markers of a group are named by at most :data:`_MAX_LABELS` labels (:func:`_group_labels`: one per
    kind, with a count), each with a leader line to its kind's first filled marker, placed where they have
    room inside the axes (:func:`_place_labels`; the legend's entry counts the points of labels left out).
    So the open markers, the labels' counts and the points left out add up to all points.
    """
    if not marks:
        return None
    xs, ys = np.asarray(all_x, dtype=float), np.asarray(all_y, dtype=float)
    width = float(np.ptp(xs)) if xs.size and np.ptp(xs) > 0 else 1.0
    height = float(np.ptp(ys)) if ys.size and np.ptp(ys) > 0 else 1.0
    filled: list[str] = []  # the markers drawn filled
    labels: list[tuple[str, str, int, float, float]] = []
    for first, *others in _group_special_points(marks, width, height, near):
        for rank, (kind, x, y) in enumerate([first, *others]):
            style = {"linestyle": "none", "marker": SPECIAL_POINT_MARKERS[kind][0], "markersize": 9,
                     "markerfacecolor": "white", "markeredgecolor": "k", "zorder": 5, "gid": kind.value,
                     "clip_on": False}  # (whole at an edge)
            if rank:
                style.update(markersize=max(4.0, 9.0 - 2.0 * rank), markerfacecolor="k", zorder=5 + rank)
                filled.append(style["marker"])
            ax.plot([x], [y], **style)
        labels += _group_labels(others)
    left_out = _place_labels(ax, labels)
    if not filled:
        return None
    from matplotlib.markers import MarkerStyle

    marker = next((m for m in filled if MarkerStyle(m).is_filled()), "o")  # (not "x": it shows no face)
    text = "filled: near another point, labelled" + (f"; {left_out} unlabelled (no room)" if left_out else "")
    return Line2D([], [], linestyle="none", marker=marker, markersize=6.0, markerfacecolor="k", markeredgecolor="k",
                  label=text)


# ---------------------------------------------------------------------------
# Floquet multipliers
# ---------------------------------------------------------------------------


_MULTIPLIER_DASHES = ["-", (0, (5, 2)), (0, (6, 2, 1, 2)), (0, (3, 1, 1, 1, 1, 1)), (0, (8, 3))]


def _multiplier_style(i: int) -> dict:
    """The line of ``|mu_(i+1)|``: the first black, solid and thickest, the next ones grey, thinner and broken,
    drawn on top, so that each is seen in black and white, also where two coincide (a complex pair)."""
    return {"color": "k" if i == 0 else ("0.55" if i % 2 else "0.35"),
            "linestyle": _MULTIPLIER_DASHES[i % len(_MULTIPLIER_DASHES)], "linewidth": max(0.8, 2.4 - 0.8 * i)}


def _assign_sides(
    sp: SpecialPoint, before: np.ndarray, after: np.ndarray, top: float
) -> tuple[np.ndarray, np.ndarray, bool]:
    """One-sided magnitudes at a non-smooth point, ordered (branch side before, branch side after).

    Which side of the branch ``multipliers_minus`` belongs to is decided by closeness (in
    clipped magnitude) to the multipliers of the neighbouring branch points. The flag says
    whether the sizes match those of the branch points (so that curves can be joined to them).
    """
    minus = np.minimum(np.abs(sp.multipliers_minus), top)
    plus = np.minimum(np.abs(sp.multipliers_plus), top)
    if not (before.size == after.size == minus.size == plus.size):
        return minus, plus, False
    keep = np.sum(np.abs(minus - before) + np.abs(plus - after))
    swap = np.sum(np.abs(plus - before) + np.abs(minus - after))
    return (minus, plus, True) if keep <= swap else (plus, minus, True)


def plot_multipliers(
    branch: Branch,
    ax: Axes | None = None,
    *,
    ymax: float | None = None,
    xlabel: str | None = None,
    legend: bool = True,
    figsize: tuple[float, float] = (6.0, 4.5),
) -> Figure:
    """Magnitudes of the Floquet multipliers along a branch (Fig. 4).

    Each ``|mu_i|`` (multipliers in stored order, i.e. by decreasing magnitude) is drawn
    against the parameter, with a dashed line at ``|mu| = 1``. At every non-smooth special
    point the curves are broken, and the jump from the one-sided multipliers
    ``multipliers_minus`` to ``multipliers_plus`` is drawn as a vertical dotted segment at the
    special point's parameter value. Infinite multipliers are clipped to the top of the axis
    and marked with upward triangles.

    Parameters
    ----------
    branch : Branch
    ax : Axes, optional
    ymax : float, optional
        Where infinite (and larger) magnitudes are clipped, just below the top of the axis;
        by default a little above the largest finite magnitude (and above 1).
    xlabel : str, optional
        Defaults to the branch's parameter name.
    legend : bool
    figsize : (float, float)

    Returns
    -------
    Figure

    Raises
    ------
    Nothing of its own: infinite multipliers are clipped and marked, not refused.
    """
    fig, ax = _new_axes(ax, figsize)
    x = branch.parameter
    mags = np.abs(branch.multipliers) if len(branch) else np.zeros((0, 0))
    nonsmooth = [sp for sp in branch.special_points if sp.kind.is_nonsmooth
                 and sp.multipliers_minus is not None and sp.multipliers_plus is not None]
    if ymax is None:
        finite = [mags[np.isfinite(mags)]]
        for sp in nonsmooth:
            for mu in (sp.multipliers_minus, sp.multipliers_plus):
                a = np.abs(mu)
                finite.append(a[np.isfinite(a)])
        values = np.concatenate(finite) if finite else np.zeros(0)
        ymax = 1.15 * max(1.0, float(values.max()) if values.size else 1.0)
    top = ymax
    clipped = np.minimum(mags, top)

    # break the curves at non-smooth points, extending each piece to the point's location
    cuts = sorted(((sp.index, sp) for sp in nonsmooth if 0 <= sp.index < len(x) - 1), key=lambda c: c[0])
    pieces: list[tuple[list[float], list[np.ndarray]]] = []
    start = 0
    lead: tuple[float, np.ndarray] | None = None
    for idx, sp in cuts + [(len(x) - 1, None)]:
        xs = list(x[start : idx + 1])
        ys = list(clipped[start : idx + 1])
        if lead is not None:
            xs.insert(0, lead[0])
            ys.insert(0, lead[1])
        lead = None
        if sp is not None:
            lo, hi, joined = _assign_sides(sp, clipped[idx], clipped[idx + 1], top)
            if joined:
                xs.append(sp.parameter)
                ys.append(lo)
                lead = (sp.parameter, hi)
        pieces.append((xs, ys))
        start = idx + 1

    # the jumps: multipliers_minus[i] -> multipliers_plus[i] (both sorted by decreasing magnitude)
    for sp in nonsmooth:
        lo = np.minimum(np.abs(sp.multipliers_minus), top)
        hi = np.minimum(np.abs(sp.multipliers_plus), top)
        for a, b in zip(lo, hi):
            ax.plot([sp.parameter, sp.parameter], [a, b], color="k", linestyle=JUMP_STYLE, linewidth=1.2, gid="jump")
        if np.any(lo >= top) or np.any(hi >= top):
            ax.plot([sp.parameter], [top], linestyle="none", marker="^", color="k", clip_on=False, gid="infinite")

    n_mu = mags.shape[1] if mags.ndim == 2 else 0
    styles = [_multiplier_style(i) for i in range(n_mu)]
    colors = [st["color"] for st in styles]
    for xs, ys in pieces:
        if not xs:
            continue
        ys_arr = np.array(ys)
        for i in range(n_mu):  # later ones thinner and broken, on top: a pair of equal |mu| shows both
            ax.plot(xs, ys_arr[:, i], **styles[i], zorder=2 + i, gid=f"mu{i}")
    for i in range(n_mu):
        inf_idx = np.flatnonzero(~np.isfinite(mags[:, i]))
        if inf_idx.size:
            every = max(1, inf_idx.size // 25)
            ax.plot(x[inf_idx[::every]], np.full(inf_idx[::every].size, top), linestyle="none", marker="^",
                    markersize=5, color=colors[i], clip_on=False, gid="infinite")

    ax.axhline(1.0, color="0.6", linestyle="-", linewidth=0.8, zorder=1, gid="unit")
    ax.set_ylim(-0.03 * top, 1.05 * top)
    ax.set_xlabel(xlabel if xlabel is not None else axis_label(branch.parameter_name, branch.axis_labels))
    ax.set_ylabel(r"$|\mu_i|$")
    if legend:
        handles = [Line2D([], [], **styles[i], label=rf"$|\mu_{{{i + 1}}}|$") for i in range(n_mu)]
        handles.append(Line2D([], [], color="0.6", linestyle="-", linewidth=0.8, label=r"$|\mu| = 1$"))
        if nonsmooth:
            handles.append(Line2D([], [], color="k", linestyle=JUMP_STYLE, label="jump at non-smooth point"))
        if not np.all(np.isfinite(mags)) or any(
            not np.all(np.isfinite(m)) for sp in nonsmooth for m in (sp.multipliers_minus, sp.multipliers_plus)
        ):
            handles.append(Line2D([], [], color="k", linestyle="none", marker="^", label=r"$|\mu| = \infty$ (clipped)"))
        ax.legend(handles=handles, loc="best", fontsize="small")
    return fig


# ---------------------------------------------------------------------------
# phase plane
# ---------------------------------------------------------------------------


class CurveStyle(enum.Enum):
    """How a curve of the phase plane is drawn (Fig. 6)."""

    STABLE = "stable"  #: stable limit cycle: bold solid
    UNSTABLE = "unstable"  #: unstable limit cycle: dashed
    TRAJECTORY = "trajectory"  #: a transient flow: thin solid with a direction arrow


_CURVE_KW = {
    CurveStyle.STABLE: {"linestyle": "-", "linewidth": 2.5, "color": "k"},
    CurveStyle.UNSTABLE: {"linestyle": "--", "linewidth": 1.5, "color": "k"},
    CurveStyle.TRAJECTORY: {"linestyle": "-", "linewidth": 0.8, "color": "0.35"},
}


@dataclass(frozen=True)
class PhaseCurve:
    """A sampled curve of the phase plane.

    Attributes
    ----------
    points : ndarray, shape (m, 2)
        Samples ``(x, x')``.
    label : str
        Legend text (empty: no legend entry).
    style : CurveStyle or str
    """

    points: np.ndarray
    label: str = ""
    style: CurveStyle | str = CurveStyle.STABLE


def plot_phase_plane(
    curves: Sequence[PhaseCurve],
    ax: Axes | None = None,
    *,
    equilibrium: Sequence[float] | None = None,
    equilibrium_label: str = "equilibrium",
    stick_band: tuple[float, float] | None = None,
    band_label: str | None = None,
    stick_region: tuple[float, float] | None = None,
    regions: Sequence[str] = (),
    xlabel: str = "$x$",
    ylabel: str = r"$\dot x$",
    legend: bool = True,
    legend_below: bool = False,
    labels: Sequence[tuple[str, Sequence[float]]] = (),
    figsize: tuple[float, float] = (6.0, 4.5),
) -> Figure:
    """Phase plane with limit cycles, an equilibrium and the stick band (Fig. 6).

    Parameters
    ----------
    curves : sequence of PhaseCurve
        Stable limit cycles are drawn bold solid, unstable ones dashed, trajectories thin.
    ax : Axes, optional
    equilibrium : (float, float), optional
        Drawn as a dot.
    equilibrium_label : str
    stick_band : (float, float), optional
        ``(v_dr, eta)``: shade the band ``|x' - v_dr| < eta``. ``eta`` is the half-width to
        display; the real one is tiny, so pass an enlarged value to make the band visible.
    band_label : str, optional
        Legend text of the band; by default it names the inequality.
    stick_region : (float, float), optional
        ``(x_min, x_max)``: the part of the band where the state sticks (the paper's ``D``,
        ``|k x + c x'| < F_stick`` as well); only that part is shaded, and the band's edges are drawn
        as the boundaries of the subspaces.
    regions : sequence of str
        Names written in the subspaces: above the band, below it and in the shaded part, in that
        order (the paper's ``("V", "W", "D")``).
    xlabel, ylabel : str
    legend : bool
    legend_below : bool
        Put the legend below the axes, where it hides nothing.
    labels : sequence of (str, (float, float))
        Text written at points of the plane (the names of flows, say).
    figsize : (float, float)

    Returns
    -------
    Figure

    Raises
    ------
    ValueError
        If a curve's points are not of shape (m, 2).
    """
    fig, ax = _new_axes(ax, figsize)
    if stick_band is not None:
        v_dr, eta = stick_band
        label = band_label if band_label is not None else f"D: |x' - v_dr| < eta (v_dr = {v_dr:g}, eta enlarged)"
        if stick_region is None:
            ax.axhspan(v_dr - eta, v_dr + eta, color="0.8", alpha=0.7, linewidth=0, label=label, gid="stick_band")
        for edge in (v_dr - eta, v_dr + eta):
            ax.axhline(edge, color="0.3", linewidth=0.8)
    for k, curve in enumerate(curves):
        pts = np.asarray(curve.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ValueError(f"curve {k} ({curve.label!r}): points must have shape (m, 2), got {pts.shape}")
        style = CurveStyle(curve.style)
        (line,) = ax.plot(pts[:, 0], pts[:, 1], label=curve.label or None, gid=style.value, **_CURVE_KW[style])
        if style is CurveStyle.TRAJECTORY and len(pts) > 2:
            j = len(pts) // 2
            ax.annotate("", xy=pts[j + 1], xytext=pts[j],
                        arrowprops={"arrowstyle": "->", "color": line.get_color(), "linewidth": 1.0})
    if equilibrium is not None:
        ax.plot([equilibrium[0]], [equilibrium[1]], linestyle="none", marker="o", markersize=7, color="k",
                label=equilibrium_label, gid="equilibrium", zorder=5)
    for text, (x, y) in labels:
        ax.annotate(text, xy=(x, y), xytext=(4, 4), textcoords="offset points", fontsize="medium", gid="label")
    if stick_band is not None and stick_region is not None:  # D within the data's range (the axes keep theirs)
        v_dr, eta = stick_band
        x_min, x_max = ax.get_xlim()
        lo, hi = max(stick_region[0], x_min), min(stick_region[1], x_max)
        ax.fill_between([lo, hi], v_dr - eta, v_dr + eta, color="0.8", alpha=0.7, linewidth=0, label=label,
                        gid="stick_band", zorder=0.5)
        for x_edge in {lo, hi} & set(stick_region):
            ax.plot([x_edge, x_edge], [v_dr - eta, v_dr + eta], color="0.3", linewidth=0.8)
        ax.set_xlim(x_min, x_max)
    if regions and stick_band is not None:
        v_dr, eta = stick_band
        x_min, x_max = ax.get_xlim()
        above, below, *inside = regions
        for text, y, va in ((above, v_dr + eta, "bottom"), (below, v_dr - eta, "top")):
            ax.annotate(text, xy=(x_max, y), xytext=(-8, 3 if va == "bottom" else -3), textcoords="offset points",
                        ha="right", va=va, fontsize="large", fontstyle="italic", gid="region")
        if inside and stick_region is not None:
            x_d = max(stick_region[0], x_min) + 0.08 * (x_max - x_min)
            ax.annotate(inside[0], xy=(x_d, v_dr), xytext=(0, -22), textcoords="offset points", ha="center",
                        va="top", fontsize="large", fontstyle="italic", gid="region",
                        arrowprops={"arrowstyle": "-", "color": "0.3", "linewidth": 0.6})
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if legend and ax.get_legend_handles_labels()[0]:
        if legend_below:
            ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize="small", frameon=False)
        else:
            ax.legend(loc="best", fontsize="small")
    return fig


# ---------------------------------------------------------------------------
# output
# ---------------------------------------------------------------------------


def _drawn(fig: Figure, stem: str | PathLike[str], dpi: int) -> dict[Path, bytes]:
    """``stem.png`` and ``stem.pdf`` of a figure, drawn in memory (see :func:`save_figure`)."""
    from io import BytesIO

    import matplotlib

    stem = Path(stem)
    png = stem.with_name(stem.name + ".png")
    pdf = stem.with_name(stem.name + ".pdf")
    images = {}
    with matplotlib.rc_context(PUBLICATION_RC):
        for path, options in ((png, {"format": "png", "dpi": dpi}), (pdf, {"format": "pdf"})):
            buffer = BytesIO()
            fig.savefig(buffer, **options)
            images[path] = buffer.getvalue()
    return images


def save_figure(fig: Figure, stem: str | PathLike[str], *, dpi: int = 200) -> tuple[Path, Path]:
    """Write ``stem.png`` and ``stem.pdf``, atomically.

    The PDF embeds its fonts as TrueType (Type 42), as journals ask, never as Type 3.  Both images are
    drawn in memory first, then written through
    :func:`saltation.output.io.write_atomically`: each file is the whole new image or the old file, never a
    part of one (a failure while drawing leaves both old files untouched).

    Parameters
    ----------
    fig : Figure
    stem : str or path-like
        Path without extension (dots in it are kept); missing directories are created.
    dpi : int
        Resolution of the PNG.

    Returns
    -------
    (Path, Path)
        The PNG and PDF files.

    Raises
    ------
    OSError
        If a file cannot be written (naming it).
    """
    from saltation.output.io import write_atomically

    images = _drawn(fig, stem, dpi)
    write_atomically(images)
    return tuple(images)  # type: ignore[return-value]


#: Figures handed to the forked drawing process of :func:`save_figures` (it inherits them; nothing is pickled).
_FORKED_FIGURES: list[tuple[Figure, Path]] = []


def _drawn_in_fork(k: int, dpi: int) -> dict[Path, bytes]:
    fig, stem = _FORKED_FIGURES[k]
    return _drawn(fig, stem, dpi)


def save_figures(figures: Sequence[tuple[Figure, str | PathLike[str]]], *, dpi: int = 200) -> list[Path]:
    """Write several figures as :func:`save_figure` does, drawn on two cores where the platform forks.

    Drawing a PDF with embedded TrueType fonts takes a few tenths of a second a figure, most of it
    subsetting the fonts.  On Linux with more than one core, a forked process draws every other
    figure (it inherits them: nothing is pickled) while this one draws the rest; the images come
    back as bytes and are written here, each file atomically.  A figure the forked process fails to
    draw is drawn here again (so that its error, if it has one, is raised here); elsewhere the
    figures are drawn in turn.

    Parameters
    ----------
    figures : sequence of (Figure, stem)
        The figures and their paths without extension.
    dpi : int
        Resolution of the PNGs.

    Returns
    -------
    list of Path
        The PNG and PDF of each figure, in order.

    Raises
    ------
    OSError
        If a file cannot be written (naming it).
    """
    import contextlib
    import multiprocessing
    import os
    import sys

    from saltation.output.io import write_atomically

    figures = [(fig, Path(stem)) for fig, stem in figures]
    images: dict[int, dict[Path, bytes]] = {}
    if len(figures) > 1 and sys.platform.startswith("linux") and (os.cpu_count() or 1) > 1:
        _FORKED_FIGURES[:] = figures
        # no process forked (OSError), or a figure it failed to draw: drawn below, where an error is raised
        try:
            with contextlib.suppress(OSError), multiprocessing.get_context("fork").Pool(1) as pool:
                remote = {k: pool.apply_async(_drawn_in_fork, (k, dpi)) for k in range(1, len(figures), 2)}
                for k in range(0, len(figures), 2):
                    images[k] = _drawn(*figures[k], dpi)
                for k, result in remote.items():
                    with contextlib.suppress(Exception):
                        images[k] = result.get()
        finally:
            _FORKED_FIGURES.clear()
    written: list[Path] = []
    for k, (fig, stem) in enumerate(figures):
        drawn = images[k] if k in images else _drawn(fig, stem, dpi)
        write_atomically(drawn)
        written += list(drawn)
    return written


def plot_loci(loci, *, title: str = "") -> Figure:
    """Two-parameter curves of special points (:class:`saltation.special_points.loci.Locus`), codimension-two points marked.

    Parameters
    ----------
    loci : sequence of Locus
    title : str

    Returns
    -------
    Figure

    Raises
    ------
    Nothing of its own: empty curves are skipped.
    """
    fig = new_figure((6.4, 4.8))
    ax = fig.add_subplot()
    for k, locus in enumerate(loci):
        if len(locus):
            ax.plot(locus.parameter, locus.second_parameter, "-", color=f"C{k % 10}", label=f"curve {k}")
        for c in locus.special_points:
            at = (c.parameter, c.second_parameter)
            ax.plot(*at, "o", color="k", markersize=5)
            ax.annotate(" -> ".join(c.sides), at, textcoords="offset points", xytext=(6, 6), fontsize=7)
    if loci:
        ax.set_xlabel(loci[0].parameter_name)
        ax.set_ylabel(loci[0].second_parameter_name)
        ax.legend(loc="best", fontsize=8)
    ax.set_title(title)
    return fig


# ---------------------------------------------------------------------------
# sweeps and period maps
# ---------------------------------------------------------------------------


def plot_sweep(result: SweepResult, ax: Axes | None = None, *, state: int | str = 0, **style) -> Figure:
    """Draw a brute-force diagram: the points over the parameter, on ``ax`` or a new Figure (no pyplot state).

    Parameters
    ----------
    result : SweepResult
        The sweep (:func:`saltation.sweeps.sweep`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on (a new figure by default).
    state : int or str
        The state plotted, by index or name.
    **style
        Keyword arguments of :meth:`matplotlib.axes.Axes.scatter`, over the defaults (black dots of 2
        points square).

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn on.

    Raises
    ------
    ModelError
        For an unknown state name or an index out of range.
    """
    k = result.state_index(state)
    exponent_ax = None
    if ax is None and result.largest_exponents is not None:  # the diagram over the largest exponent
        fig = new_figure((6.4, 6.0))
        ax, exponent_ax = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    elif ax is None:
        fig = new_figure((6.4, 4.4))
        ax = fig.add_subplot()
    else:
        fig = figure_of(ax)
    # dots of 2 points square: seen on a page at any density (a point per sample, no edge)
    kw = {"s": 2.0, "color": "k", "marker": ".", "linewidths": 0, "rasterized": True} | style
    ax.scatter(result.parameter_points, result.states[:, k], **kw)
    ax.set_xlabel(result.parameter_name)
    name = result.state_names[k]
    if result.section == "poincare":
        ax.set_ylabel(f"{name} (Poincare section)")
    elif result.section == "maxima":
        ax.set_ylabel(f"{name} at maxima of {result.state_names[0]}")
    else:  # a surface's events or an expression's crossings
        ax.set_ylabel(f"{name} at {Section.from_code(result.section).words}")
    ax.set_title(f"{result.model}: brute-force diagram")
    if exponent_ax is not None:
        exponent_ax.axhline(0.0, color="0.6", linewidth=0.8)
        exponent_ax.plot(result.values, result.largest_exponents, color="k", linewidth=1.0, marker=".", markersize=2.5,
                         gid="largest_exponent")
        exponent_ax.set_ylabel(r"largest Lyapunov exponent $\lambda_1$")
        exponent_ax.set_xlabel(result.parameter_name)
    return fig


def plot_period_map(grid: PeriodMap, ax: Axes | None = None) -> Figure:
    """Draw a period map: one colour per period (1 ... max_period).

    Grey where no period up to ``max_period`` settled within the transient (chaos, a longer period,
    or a slow transient: the colour bar says "not periodic"); white for failures.

    Parameters
    ----------
    grid : PeriodMap
        The map (:func:`saltation.sweeps.period_map`).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on (a new figure by default).

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn on, with its colour bar.
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap

    own = ax is None
    exponent_ax = None
    if own and grid.largest_exponents is not None:  # the periods above, the largest exponent below
        fig = new_figure((6.4, 8.4))
        ax, exponent_ax = fig.subplots(2, 1, sharex=True)
    elif own:
        fig = new_figure((6.4, 4.8))
        ax = fig.add_subplot()
    else:
        fig = figure_of(ax)
    import matplotlib

    base = matplotlib.colormaps["tab20"]
    colours = ["white", "0.6"] + [base(k % 20) for k in range(grid.max_period)]
    cmap = ListedColormap(colours)
    norm = BoundaryNorm(np.arange(-1.5, grid.max_period + 1.5), cmap.N)
    mesh = ax.pcolormesh(_edges(grid.values), _edges(grid.values2), grid.periods, cmap=cmap, norm=norm)
    bar = fig.colorbar(mesh, ax=ax, ticks=np.arange(-1, grid.max_period + 1))
    # "not periodic": no period up to max_period within the transient (chaos, a longer period, or not settled)
    bar.ax.set_yticklabels(["failed", f"no period <= {grid.max_period}"]
                           + [str(k) for k in range(1, grid.max_period + 1)])
    bar.set_label("period of the attractor (forcing periods)")
    ax.set_xlabel(grid.parameter_name)
    ax.set_ylabel(grid.parameter2_name)
    ax.set_title(f"{grid.model}: period of the attractor")
    if exponent_ax is not None:
        limit = float(np.nanmax(np.abs(grid.largest_exponents))) if np.isfinite(grid.largest_exponents).any() else 1.0
        mesh2 = exponent_ax.pcolormesh(_edges(grid.values), _edges(grid.values2), grid.largest_exponents,
                                       cmap="RdBu_r", vmin=-limit, vmax=limit)
        fig.colorbar(mesh2, ax=exponent_ax).set_label(r"largest Lyapunov exponent $\lambda_1$ (red: chaos)")
        exponent_ax.set_xlabel(grid.parameter_name)
        exponent_ax.set_ylabel(grid.parameter2_name)
    return fig


def _edges(v: np.ndarray) -> np.ndarray:
    """Cell edges around grid values (midpoints; a single value gets a unit cell)."""
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])
