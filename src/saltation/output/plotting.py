"""Figures of branches, Floquet multipliers and phase planes, drawn as in *Fold bifurcations
in discontinuous systems*: stable solutions solid, unstable ones dash-dot (Figs. 3 and 7),
jumps of the multipliers at non-smooth points dotted (Fig. 4).

Every function draws on a given ``Axes`` or on a new :class:`matplotlib.figure.Figure`
(never through ``pyplot``, so no global figure state is created or leaked) and returns the
figure. :func:`save_figure` writes a PNG and a PDF.
"""

from __future__ import annotations

import math

import enum
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.transforms import offset_copy
from matplotlib.lines import Line2D

from saltation.branches.branch import Branch, SpecialPoint, SpecialPointKind

__all__ = [
    "CurveStyle",
    "NotebookFigure",
    "MEASURE_LABELS",
    "PUBLICATION_RC",
    "PhaseCurve",
    "SPECIAL_POINT_MARKERS",
    "figure_of",
    "new_figure",
    "plot_loci",
    "plot_multipliers",
    "plot_phase_plane",
    "plot_response",
    "save_figure",
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
    SpecialPointKind.PERIOD_DOUBLING: ("s", "period doubling"),
    SpecialPointKind.NEIMARK_SACKER: ("D", "Neimark-Sacker"),
    SpecialPointKind.HOPF: ("^", "Hopf"),
    SpecialPointKind.DISCONTINUOUS_FOLD: ("*", "discontinuous fold"),
    SpecialPointKind.DISCONTINUOUS_FLIP: ("P", "discontinuous flip"),
    SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER: ("X", "discontinuous Neimark-Sacker"),
    SpecialPointKind.NONSMOOTH_NO_CROSSING: ("v", "non-smooth point, no crossing"),
    SpecialPointKind.GRAZING: ("h", "grazing"),
    SpecialPointKind.GRAZING_SLIDING: ("H", "grazing-sliding"),
    SpecialPointKind.CROSSING_SLIDING: ("<", "crossing-sliding"),
    SpecialPointKind.SWITCHING_SLIDING: (">", "switching-sliding"),
    SpecialPointKind.ADDING_SLIDING: ("d", "adding-sliding"),
    SpecialPointKind.CYCLE_COLLAPSE: ("8", "cycle collapses onto an equilibrium"),
    SpecialPointKind.CODIMENSION_TWO: ("p", "codimension-two point of a curve"),
}

#: Axis label per amplitude measure; ``{x}`` is the name of the first state.
MEASURE_LABELS: dict[str, str] = {
    "amplitude": "A = max |{x}| over a period",
    "half_peak_to_peak": "A = half peak-to-peak of {x}",
}

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
    """A new figure of this module's kind (constrained layout, shown by Jupyter once; see :class:`NotebookFigure`)."""
    return NotebookFigure(figsize=figsize, layout="constrained")


def figure_of(ax: Axes) -> Figure:
    """The figure of a caller's ``Axes``, to be returned by a plotting function.

    A figure of ``pyplot`` is shown by a notebook's inline backend when the cell ends; returned as the
    cell's last expression, IPython's formatter would show it once more.  So, in IPython, this figure's
    PNG is drawn once by whichever display comes first (the cell's result, or the backend's), which
    then closes it in ``pyplot`` (as the inline backend does after every cell) so that the backend does
    not draw it again.  Figures made without ``pyplot`` are left as they are.
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
    if measure not in MEASURE_LABELS:
        raise ValueError(f"unknown amplitude measure {measure!r}; use one of {sorted(MEASURE_LABELS)} or a callable")
    return getattr(branch, measure)


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
    state_name: str = "x",
    colors: Sequence[str] | None = None,
    special_points: bool = True,
    legend: bool = True,
    figsize: tuple[float, float] = (6.0, 4.5),
) -> Figure:
    """Response (bifurcation) diagram: an amplitude measure against the parameter.

    Stable segments are drawn solid and unstable ones dash-dot (Figs. 3 and 7); each branch is
    split into runs by its ``stable`` column. Special points are marked, one marker per kind.

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
        Defaults to the first branch's parameter name.
    state_name : str
        Name of the first state in the default y label.
    colors : sequence of str, optional
        One colour per branch; defaults to black for all (the paper's style).
    special_points : bool
        Mark the branches' special points.
    legend : bool
        Add a legend (line styles, branch labels, kinds of special points present).
    figsize : (float, float)
        Size of a new figure, in inches.

    Returns
    -------
    Figure
    """
    branches = _as_list(branches)
    fig, ax = _new_axes(ax, figsize)
    handles: list[Line2D] = []
    kinds_seen: list[SpecialPointKind] = []
    marks_at: list[tuple[SpecialPointKind, float, float]] = []
    all_x: list[float] = []
    all_y: list[float] = []
    for b, branch in enumerate(branches):
        color = colors[b % len(colors)] if colors else "k"
        y = _measure_values(branch, measure)
        sp_y = {sp.index: _special_point_y(branch, sp, y, measure) for sp in branch.special_points}
        for stable, xs, ys in stability_runs(branch, y, sp_y):
            ax.plot(
                xs, ys, color=color, linestyle=STABLE_STYLE if stable else UNSTABLE_STYLE,
                linewidth=1.5, gid="stable" if stable else "unstable",
            )
        if branch.label and colors:
            handles.append(Line2D([], [], color=color, label=branch.label))
        if special_points:
            for sp in branch.special_points:
                marks_at.append((sp.kind, float(sp.parameter), float(_special_point_y(branch, sp, y, measure))))
                if sp.kind not in kinds_seen:
                    kinds_seen.append(sp.kind)
        all_x.extend(branch.parameter)
        all_y.extend(np.asarray(y, dtype=float)[np.isfinite(y)])
    _mark_special_points(fig, ax, marks_at, all_x, all_y)
    runs_styles = [Line2D([], [], color="k", linestyle=STABLE_STYLE, label="stable"),
                   Line2D([], [], color="k", linestyle=UNSTABLE_STYLE, label="unstable")]
    marks = [
        Line2D([], [], linestyle="none", marker=SPECIAL_POINT_MARKERS[k][0], markersize=9,
               markerfacecolor="white", markeredgecolor="k", label=SPECIAL_POINT_MARKERS[k][1])
        for k in kinds_seen
    ]
    if ylabel is None:
        ylabel = MEASURE_LABELS[measure].format(x=state_name) if isinstance(measure, str) else "A"
    ax.set_ylabel(ylabel)
    ax.set_xlabel(xlabel if xlabel is not None else (branches[0].parameter_name if branches else ""))
    if legend:
        ax.legend(handles=runs_styles + handles + marks, loc="best", fontsize="small")
    return fig


def _mark_special_points(fig: Figure, ax: Axes, marks: list[tuple[SpecialPointKind, float, float]],
                         all_x: Sequence[float], all_y: Sequence[float], *, near: float = 0.03) -> None:
    """Draw special-point markers; of markers closer than ``near`` (a fraction of the data's extent)
    the first stays at its point and the others move aside along a diagonal, each tied to its point by
    a thin leader line, so that every marker stays visible."""
    if not marks:
        return
    xs, ys = np.asarray(all_x, dtype=float), np.asarray(all_y, dtype=float)
    width = float(np.ptp(xs)) if xs.size and np.ptp(xs) > 0 else 1.0
    height = float(np.ptp(ys)) if ys.size and np.ptp(ys) > 0 else 1.0
    placed: list[tuple[float, float]] = []
    for kind, x, y in marks:
        crowd = sum(1 for (px, py) in placed if math.hypot((x - px) / width, (y - py) / height) < near)
        placed.append((x, y))
        marker, _ = SPECIAL_POINT_MARKERS[kind]
        style = {"linestyle": "none", "marker": marker, "markersize": 9, "markerfacecolor": "white",
                 "markeredgecolor": "k", "zorder": 5, "gid": kind.value}
        if crowd == 0:
            ax.plot([x], [y], **style)
            continue
        shift = 16.0 * crowd  # points, down and to the right of the crowded spot
        ax.plot([x], [y], transform=offset_copy(ax.transData, fig=fig, x=shift, y=-shift, units="points"), **style)
        ax.annotate("", xy=(x, y), xytext=(shift, -shift), textcoords="offset points",
                    arrowprops={"arrowstyle": "-", "color": "0.4", "linewidth": 0.6, "shrinkA": 5, "shrinkB": 0})


# ---------------------------------------------------------------------------
# Floquet multipliers
# ---------------------------------------------------------------------------


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
    colors = [f"C{i}" for i in range(n_mu)]
    for xs, ys in pieces:
        if not xs:
            continue
        ys_arr = np.array(ys)
        for i in range(n_mu):
            ax.plot(xs, ys_arr[:, i], color=colors[i], linestyle="-", linewidth=1.5, gid=f"mu{i}")
    for i in range(n_mu):
        inf_idx = np.flatnonzero(~np.isfinite(mags[:, i]))
        if inf_idx.size:
            every = max(1, inf_idx.size // 25)
            ax.plot(x[inf_idx[::every]], np.full(inf_idx[::every].size, top), linestyle="none", marker="^",
                    markersize=5, color=colors[i], clip_on=False, gid="infinite")

    ax.axhline(1.0, color="0.4", linestyle="--", linewidth=1.0, gid="unit")
    ax.set_ylim(-0.03 * top, 1.05 * top)
    ax.set_xlabel(xlabel if xlabel is not None else branch.parameter_name)
    ax.set_ylabel(r"$|\mu_i|$")
    if legend:
        handles = [Line2D([], [], color=colors[i], label=rf"$|\mu_{{{i + 1}}}|$") for i in range(n_mu)]
        handles.append(Line2D([], [], color="0.4", linestyle="--", label=r"$|\mu| = 1$"))
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
    xlabel: str = "x",
    ylabel: str = "x'",
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
    from io import BytesIO

    from saltation.output.io import write_atomically

    stem = Path(stem)
    png = stem.with_name(stem.name + ".png")
    pdf = stem.with_name(stem.name + ".pdf")
    import matplotlib

    images = {}
    with matplotlib.rc_context(PUBLICATION_RC):
        for path, options in ((png, {"format": "png", "dpi": dpi}), (pdf, {"format": "pdf"})):
            buffer = BytesIO()
            fig.savefig(buffer, **options)
            images[path] = buffer.getvalue()
    write_atomically(images)
    return png, pdf


def plot_loci(loci, *, title: str = ""):
    """Two-parameter curves of special points (:class:`saltation.special_points.loci.Locus`), codimension-two points marked."""
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
