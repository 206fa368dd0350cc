"""Figures: they draw, they save, and they use the paper's line styles."""

from __future__ import annotations

import functools
import math
import re
import warnings

import matplotlib
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from matplotlib.figure import Figure

from saltation.branches.branch import Branch, BranchKind, BranchPoint, SpecialPoint, SpecialPointKind
from saltation.output.plotting import (
    SPECIAL_POINT_MARKERS,
    CurveStyle,
    PhaseCurve,
    plot_multipliers,
    plot_phase_plane,
    plot_response,
    save_figure,
    stability_runs,
)

INF = complex(math.inf, 0.0)


def _pt(p: float, a: float, mu: list[complex], stable: bool) -> BranchPoint:
    return BranchPoint(
        parameter=p, state=np.array([a, 0.0]), period=2 * np.pi / p, amplitude=a, half_peak_to_peak=0.9 * a,
        multipliers=np.array(mu, dtype=complex), stable=stable, event_labels=(),
    )


def trilinear_like() -> Branch:
    """Stable, then unstable past a smooth fold at index 4, with a non-smooth point at index 1."""
    pts = []
    for k in range(10):
        p = 1.0 + 0.1 * k if k < 5 else 1.4 - 0.1 * (k - 4)
        a = 0.5 + 0.2 * k
        if k < 2:
            mu = [0.6 + 0.3j, 0.6 - 0.3j]
        elif k < 5:
            mu = [0.9, 0.2]
        else:
            mu = [1.5 + 0.1 * k, 0.1]
        pts.append(_pt(p, a, mu, stable=k < 5))
    specials = [
        SpecialPoint(
            kind=SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER, parameter=1.15, bracket=(1.1, 1.2), accuracy=0.1,
            index=1, state=np.array([0.8, 0.0]), period=5.0, amplitude=0.8,
            multipliers_minus=np.array([0.6 + 0.3j, 0.6 - 0.3j]), multipliers_plus=np.array([0.85, 0.25]),
        ),
        SpecialPoint(
            kind=SpecialPointKind.FOLD, parameter=1.45, bracket=(1.44, 1.46), accuracy=0.02, index=4,
            state=np.array([1.4, 0.0]), period=4.3, amplitude=1.4, multipliers=np.array([1.0, 0.15]),
        ),
    ]
    return Branch(model="trilinear", parameter_name="omega", kind=BranchKind.PERIODIC, points=pts,
                  special_points=specials, label="periodic")


def block_on_belt_like() -> Branch:
    """Stable stick-slip cycles (1, 0), a discontinuous fold, unstable ones (1, inf)."""
    pts = [_pt(0.5 + 0.05 * k, 2.0 - 0.1 * k, [1.0, 0.0], True) for k in range(5)]
    pts += [_pt(0.75 - 0.05 * k, 1.5 - 0.1 * k, [INF, 1.0], False) for k in range(5)]
    fold = SpecialPoint(
        kind=SpecialPointKind.DISCONTINUOUS_FOLD, parameter=0.73, bracket=(0.72, 0.74), accuracy=0.02, index=4,
        state=np.array([1.55, 0.0]), period=6.0, amplitude=1.55,
        multipliers_minus=np.array([1.0, 0.0], dtype=complex), multipliers_plus=np.array([INF, 1.0]),
        crossing_q=0.5, crossing_point=1.0 + 0j,
    )
    return Branch(model="block_on_belt", parameter_name="v_dr", kind=BranchKind.PERIODIC, points=pts,
                  special_points=[fold], autonomous=True, label="stick-slip")


def _special_y(branch, sp) -> float:
    """The amplitude the plot marks a special point at (see saltation.output.plotting)."""
    from saltation.output.plotting import _special_point_y

    return _special_point_y(branch, sp, branch.amplitude, "amplitude")


def _lines(fig: Figure, gid: str):
    return [ln for ln in fig.axes[0].get_lines() if ln.get_gid() == gid]


def _assert_written(paths):
    for path in paths:
        assert path.exists() and path.stat().st_size > 1000
    png, pdf = paths
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert pdf.read_bytes()[:5] == b"%PDF-"


# --- response diagram -------------------------------------------------------


def test_response_line_styles_follow_stability(tmp_path):
    branch = trilinear_like()
    fig = plot_response(branch)
    stable, unstable = _lines(fig, "stable"), _lines(fig, "unstable")
    assert len(stable) == 1 and len(unstable) == 1
    assert stable[0].get_linestyle() == "-"
    assert unstable[0].get_linestyle() == "-."
    # the runs meet at the fold, which lies between the last stable and first unstable point
    assert stable[0].get_xdata()[-1] == unstable[0].get_xdata()[0] == 1.45
    assert stable[0].get_ydata()[-1] == unstable[0].get_ydata()[0] == 1.4
    np.testing.assert_array_equal(stable[0].get_xdata()[:-1], branch.parameter[:5])
    np.testing.assert_array_equal(unstable[0].get_ydata()[1:], branch.amplitude[5:])
    _assert_written(save_figure(fig, tmp_path / "response"))


def test_response_marks_special_points_with_distinct_markers_and_legend():
    fig = plot_response([trilinear_like(), block_on_belt_like()], colors=["k", "C1"])
    markers = {
        kind: _lines(fig, kind.value)[0].get_marker()
        for kind in (SpecialPointKind.FOLD, SpecialPointKind.DISCONTINUOUS_FOLD,
                     SpecialPointKind.DISCONTINUOUS_NEIMARK_SACKER)
    }
    assert len(set(markers.values())) == 3
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert {"stable", "unstable", "fold", "discontinuous fold", "periodic", "stick-slip"} <= set(texts)


def test_response_runs_split_by_stability_change():
    branch = trilinear_like()
    flags = [True, True, False, False, True]
    branch.points = [
        BranchPoint(p.parameter, p.state, p.period, p.amplitude, p.half_peak_to_peak, p.multipliers, f, p.event_labels)
        for p, f in zip(branch.points[:5], flags)
    ]
    branch.special_points = []
    runs = stability_runs(branch, branch.amplitude)
    assert [r[0] for r in runs] == [True, False, True]
    # neighbouring runs meet half way between the points where stability changes
    assert runs[0][1][-1] == runs[1][1][0] == pytest.approx(1.15)
    assert runs[1][2][-1] == runs[2][2][0] == pytest.approx(1.2)


@pytest.mark.parametrize(
    ("measure", "words"),
    [("amplitude", r"\max_t\,|x|"), ("half_peak_to_peak", r"\max_t x - \min_t x")],
)
def test_response_y_label_names_the_measure(measure, words):
    branch = trilinear_like()
    fig = plot_response(branch, measure=measure)
    ax = fig.axes[0]
    assert words in ax.get_ylabel()
    assert ax.get_xlabel() == r"$\omega$"  # mathtext: Greek letters by name
    expected = branch.amplitude if measure == "amplitude" else branch.half_peak_to_peak
    np.testing.assert_array_equal(_lines(fig, "stable")[0].get_ydata()[:5], expected[:5])


def test_response_custom_measure_and_bad_measure():
    fig = plot_response(trilinear_like(), measure=lambda b: b.period, ylabel="T")
    assert fig.axes[0].get_ylabel() == "T"
    with pytest.raises(ValueError, match="unknown amplitude measure 'peak'"):
        plot_response(trilinear_like(), measure="peak")


def test_response_draws_on_given_axes():
    fig = Figure()
    ax = fig.add_subplot(1, 2, 2)
    assert plot_response(block_on_belt_like(), ax=ax) is fig
    assert ax.get_lines()


# --- multipliers ------------------------------------------------------------


def test_multipliers_unit_line_and_dotted_jump(tmp_path):
    branch = trilinear_like()
    fig = plot_multipliers(branch)
    unit = _lines(fig, "unit")
    assert len(unit) == 1 and unit[0].get_linestyle() == "-" and unit[0].get_color() == "0.6"  # light, under
    assert list(unit[0].get_ydata()) == [1.0, 1.0]
    jumps = _lines(fig, "jump")
    assert len(jumps) == 2
    for ln in jumps:
        assert ln.get_linestyle() == ":"
        assert list(ln.get_xdata()) == [1.15, 1.15]
    ends = sorted(tuple(ln.get_ydata()) for ln in jumps)
    assert ends == sorted([(abs(0.6 + 0.3j), 0.85), (abs(0.6 - 0.3j), 0.25)])
    # the magnitude curves are broken at the non-smooth point and joined to its one-sided values
    mu0 = _lines(fig, "mu0")
    assert len(mu0) == 2
    assert mu0[0].get_xdata()[-1] == mu0[1].get_xdata()[0] == 1.15
    assert mu0[0].get_ydata()[-1] == pytest.approx(abs(0.6 + 0.3j))
    assert mu0[1].get_ydata()[0] == 0.85
    _assert_written(save_figure(fig, tmp_path / "multipliers"))


def test_multipliers_infinite_clipped_to_top(tmp_path):
    fig = plot_multipliers(block_on_belt_like())
    ax = fig.axes[0]
    top = max(max(ln.get_ydata()) for ln in _lines(fig, "jump"))
    assert np.isfinite(top) and 1.0 < top < ax.get_ylim()[1]
    jumps = _lines(fig, "jump")
    assert {tuple(ln.get_ydata()) for ln in jumps} == {(1.0, top), (0.0, 1.0)}
    assert all(list(ln.get_xdata()) == [0.73, 0.73] for ln in jumps)
    infinite = _lines(fig, "infinite")
    assert infinite and all(ln.get_marker() == "^" for ln in infinite)
    assert all(np.all(ln.get_ydata() == top) for ln in infinite)
    for ln in _lines(fig, "mu0") + _lines(fig, "mu1"):
        assert np.all(np.isfinite(ln.get_ydata())) and np.all(ln.get_ydata() <= top)
    _assert_written(save_figure(fig, tmp_path / "sub" / "multipliers.belt"))
    assert (tmp_path / "sub" / "multipliers.belt.pdf").exists()


# --- phase plane ------------------------------------------------------------


def _circle(r: float, c=(0.0, 0.0), m: int = 100) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, m)
    return np.column_stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)])


def test_phase_plane(tmp_path):
    curves = [
        PhaseCurve(_circle(2.0), "stable limit cycle", CurveStyle.STABLE),
        PhaseCurve(_circle(1.0, (1.0, 0.0)), "unstable limit cycle", "unstable"),
        PhaseCurve(_circle(2.5)[:60], "flow I", CurveStyle.TRAJECTORY),
    ]
    fig = plot_phase_plane(curves, equilibrium=(1.0, 0.0), stick_band=(2.0, 0.1))
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("$x$", r"$\dot x$")
    (stable,) = _lines(fig, "stable")
    (unstable,) = _lines(fig, "unstable")
    assert stable.get_linestyle() == "-" and unstable.get_linestyle() == "--"
    assert stable.get_linewidth() > unstable.get_linewidth()
    (eq,) = _lines(fig, "equilibrium")
    assert eq.get_marker() == "o" and list(eq.get_xdata()) == [1.0]
    band = [p for p in ax.patches if p.get_gid() == "stick_band"]
    assert len(band) == 1
    ys = ax.transData.inverted().transform(band[0].get_verts())[:, 1]
    assert ys.min() == pytest.approx(1.9) and ys.max() == pytest.approx(2.1)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "stable limit cycle" in texts and "equilibrium" in texts
    _assert_written(save_figure(fig, tmp_path / "phase"))


def test_phase_plane_rejects_bad_shapes():
    with pytest.raises(ValueError, match="curve 0 .*shape"):
        plot_phase_plane([PhaseCurve(np.zeros((5, 3)), "bad")])


def test_no_pyplot_figures_leak():
    import matplotlib.pyplot as plt

    before = plt.get_fignums()
    plot_response(trilinear_like())
    plot_multipliers(block_on_belt_like())
    plot_phase_plane([PhaseCurve(_circle(1.0))])
    assert plt.get_fignums() == before
    assert matplotlib.get_backend()


def test_every_kind_of_special_point_has_a_marker():
    assert set(SPECIAL_POINT_MARKERS) == set(SpecialPointKind)
    assert len({marker for marker, _ in SPECIAL_POINT_MARKERS.values()}) == len(SPECIAL_POINT_MARKERS)


def test_nearby_special_points_are_each_drawn_at_their_point_and_named():
    """Two special points at almost the same place (the paper's Fig. 7 at its fold): both markers are drawn at
    their points, the second smaller and filled on top (neither hides the other), and named by an annotation
    with a leader line whose text lies inside the axes."""
    from dataclasses import replace

    branch = trilinear_like()
    near = replace(branch.special_points[1], kind=SpecialPointKind.NONSMOOTH_NO_CROSSING, parameter=1.4501)
    branch.special_points.append(near)
    fig = plot_response(branch)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()  # (a figure made without pyplot has no drawing canvas of its own)
    (fold,) = _lines(fig, "fold")
    (other,) = _lines(fig, "nonsmooth_no_crossing")
    assert (other.get_xdata()[0], other.get_ydata()[0]) == (1.4501, _special_y(branch, near))  # at its point
    assert other.get_markersize() < fold.get_markersize() and other.get_zorder() > fold.get_zorder()
    assert other.get_markerfacecolor() == "k"
    ax = fig.axes[0]
    (label,) = [t for t in ax.texts if t.get_gid() == "nonsmooth_no_crossing_label"]
    assert label.arrow_patch is not None and label.get_text() == "non-smooth point, no crossing"
    inside = ax.get_window_extent()
    box = label.get_window_extent(fig.canvas.get_renderer())
    assert inside.x0 <= box.x0 and box.x1 <= inside.x1 and inside.y0 <= box.y0 and box.y1 <= inside.y1


def test_phase_plane_legend_below_hides_nothing():
    curves = [PhaseCurve(_circle(2.0), "stable limit cycle", CurveStyle.STABLE)]
    fig = plot_phase_plane(curves, equilibrium=(0.0, 0.0), legend_below=True, labels=[("I", (2.0, 0.0))])
    fig.canvas.draw()
    ax = fig.axes[0]
    legend_box = ax.get_legend().get_window_extent()
    assert legend_box.y1 <= ax.get_window_extent().y0  # entirely below the axes
    assert [t.get_text() for t in ax.texts] == ["I"]


def test_a_model_declares_its_labels_and_units():
    """Axis labels are mathtext: a model may declare a state's or parameter's label and unit; plots of its
    branches use them (recorded on the branch), and an unknown name is refused."""
    from saltation import ContinuationSettings, Crossing, Flow, Mode, PiecewiseSystem, Transition, continue_orbit
    from saltation.errors import ModelError
    from saltation.orbits.shooting import find_periodic_orbit

    def model(**kw):
        return PiecewiseSystem(
            "test_plotting_labels", states=["x", "v"], parameters={"omega": 0.8, "zeta": 0.1},
            modes=[Mode("left", ["v", "-x - 2*zeta*v + cos(omega*t)"], domain=["x < 2"]),
                   Mode("right", ["v", "-x - 2*zeta*v + cos(omega*t)"], domain=["x >= 2"])],
            surfaces={"s": "x - 2"},
            transitions=[Transition("left", "s", Crossing.RISING, "right"),
                         Transition("right", "s", Crossing.FALLING, "left")],
            period="2*pi/omega", **kw)

    system = model(labels={"v": r"\dot x"}, units={"omega": "rad/s", "x": "m"})
    assert system.axis_label("omega") == r"$\omega$ (rad/s)"
    assert system.axis_label("v") == r"$\dot x$"
    assert system.axis_label("zeta") == r"$\zeta$"
    with pytest.raises(ModelError, match="'omgea' is not a state or parameter"):
        model(units={"omgea": "rad/s"})
    flow = Flow(system)
    orbit = find_periodic_orbit(flow, [0.0, 0.0])
    branch = continue_orbit(orbit, "omega", bounds=(0.8, 0.9), settings=ContinuationSettings(ds=0.05, ds_max=0.05))
    ax = plot_response(branch).axes[0]
    assert ax.get_xlabel() == r"$\omega$ (rad/s)"
    assert ax.get_ylabel() == r"$A = \max_t\,|x|$ (m)"


# --- crowded special points -------------------------------------------------


def crowded_branch(specials: list[tuple[SpecialPointKind, int, float]]) -> Branch:
    """60 points, stable for the first half; a special point ``(kind, index, t)`` lies on the branch a fraction
    ``t`` of the way from point ``index`` to the next (so it moves no axis limit)."""
    pts = [_pt(1.0 + 0.01 * k, 0.5 + 0.02 * k + 0.3 * math.sin(k / 6), [0.5, 0.1], k < 30) for k in range(60)]
    sps = []
    for kind, i, t in specials:
        p = (1 - t) * pts[i].parameter + t * pts[i + 1].parameter
        a = (1 - t) * pts[i].amplitude + t * pts[i + 1].amplitude
        sps.append(SpecialPoint(kind=kind, parameter=p, bracket=(pts[i].parameter, pts[i + 1].parameter),
                                accuracy=0.01, index=i, state=np.array([a, 0.0]), period=1.0, amplitude=a))
    return Branch(model="rotor", parameter_name="omega", kind=BranchKind.PERIODIC, points=pts, special_points=sps)


_FILLED = "filled: near another point, labelled"


def _named(text: str) -> int:
    """How many points a label names: ``"grazing ×5"`` five, ``"7 more special points"`` seven, else one."""
    counted = re.search(r"\u00d7(\d+)$", text) or re.match(r"(\d+) more special points$", text)
    return int(counted.group(1)) if counted else 1


def _check_crowded_figure(branch: Branch, bare_position) -> int:
    """Draw the branch's response with every warning an error, and check the rule of crowded labels: the axes
    as large as without special points, every label inside the axes (so inside the figure), every point an
    open marker or counted once by a label or by the legend's entry for filled markers.  Returns how many
    points the legend counts as unlabelled."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_response(branch)
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
    ax = fig.axes[0]
    # the layout is solved numerically (kiwisolver): equal decorations give equal axes up to round-off,
    # far below a pixel (1e-9 of the figure)
    np.testing.assert_allclose(ax.get_position().bounds, bare_position, rtol=0, atol=1e-9)
    renderer = canvas.get_renderer()
    labels = [t for t in ax.texts if str(t.get_gid()).endswith("_label")]
    inside, page = ax.get_window_extent(renderer), fig.bbox
    for label in labels:
        box = label.get_window_extent(renderer)
        assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1, label
        assert inside.x0 <= box.x0 and box.x1 <= inside.x1 and inside.y0 <= box.y0 and box.y1 <= inside.y1, label
        assert not label.get_in_layout() and label.get_annotation_clip()
    kinds = {kind.value for kind in SpecialPointKind}
    marks = [ln for ln in ax.get_lines() if ln.get_gid() in kinds]
    assert len(marks) == len(branch.special_points)  # every point marked at its point
    filled = [ln for ln in marks if ln.get_markerfacecolor() == "k"]
    legend = {t.get_text(): h for t, h in zip(ax.get_legend().get_texts(), ax.get_legend().legend_handles)}
    entry = [text for text in legend if text.startswith(_FILLED)]
    assert len(entry) == (1 if filled else 0)
    left_out = 0
    if entry:
        assert legend[entry[0]].get_markerfacecolor() == "k"  # the entry shows a filled marker
        counted = re.search(r"; (\d+) unlabelled \(no room\)$", entry[0])
        left_out = int(counted.group(1)) if counted else 0
    assert sum(_named(t.get_text()) for t in labels) + left_out == len(filled)
    assert len(marks) - len(filled) + sum(_named(t.get_text()) for t in labels) + left_out == len(branch.special_points)
    return left_out


@functools.cache
def _bare_position():
    """The axes' position in the response diagram of the same branch without special points."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = plot_response(crowded_branch([]))
    FigureCanvasAgg(fig).draw()
    return fig.axes[0].get_position().bounds


def test_thirty_eight_special_points_on_one_branch_keep_the_axes_and_count_every_point():
    """A rotor-like branch with 38 special points, 30 of them in three clumps of six kinds: no warning, the axes
    keep their size, the labels stay inside them, each clump is named by four labels (three kinds and the
    rest counted) and the legend explains the filled markers."""
    kinds = [SpecialPointKind.GRAZING, SpecialPointKind.GRAZING_SLIDING, SpecialPointKind.CROSSING_SLIDING,
             SpecialPointKind.FOLD, SpecialPointKind.PERIOD_DOUBLING, SpecialPointKind.HOPF]
    clumps = [(kinds[j % len(kinds)], centre, 0.05 * j) for centre in (10, 30, 48) for j in range(10)]
    spread = [(SpecialPointKind.GRAZING, i, 0.5) for i in (2, 6, 18, 22, 38, 42, 54, 57)]  # alone
    branch = crowded_branch(clumps + spread)
    assert len(branch.special_points) == 38
    _check_crowded_figure(branch, _bare_position())
    ax = plot_response(branch).axes[0]
    texts = sorted(t.get_text() for t in ax.texts)
    assert texts == sorted(["grazing-sliding \u00d72", "crossing-sliding \u00d72", "fold \u00d72",
                            "3 more special points"] * 3)
    assert sum(ln.get_markerfacecolor() == "white" for ln in ax.get_lines() if ln.get_marker() != "None") == 11
    assert any(t.get_text() == _FILLED for t in ax.get_legend().get_texts())


def test_a_group_of_many_kinds_has_at_most_four_labels():
    from saltation.output.plotting import _MAX_LABELS, _group_labels

    others = [(kind, 1.0, 1.0) for kind in list(SpecialPointKind)[:7] for _ in range(2)]
    labels = _group_labels(others)
    assert len(labels) == _MAX_LABELS == 4
    assert [text for text, *_ in labels] == ["fold \u00d72", "branch point \u00d72", "period doubling \u00d72",
                                             "8 more special points"]
    assert sum(count for _, _, count, _, _ in labels) == len(others)


_KINDS = st.sampled_from(list(SpecialPointKind))


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(_KINDS, st.sampled_from([3, 4, 20, 21, 40, 57]), st.floats(0.0, 1.0)), max_size=48))
@example([(SpecialPointKind.GRAZING, 20, 0.0)] * 40)
@example([(kind, 40, 0.5) for kind in SpecialPointKind] * 2)
def test_crowded_special_points_never_squash_the_axes(specials):
    """Any number of special points of any kinds, clumped at a few places or not (every kind twice at one
    point: a legend of 22 entries): the rule of crowded labels holds."""
    _check_crowded_figure(crowded_branch(specials), _bare_position())


def test_labels_without_room_are_counted_by_the_legend():
    """112 special points, two at every step of the branch: the labels that find no room inside the axes
    are left out, and the legend's entry for filled markers counts their points."""
    specials = [(SpecialPointKind.GRAZING if i % 3 else SpecialPointKind.FOLD, i, t)
                for i in range(2, 58) for t in (0.0, 0.5)]
    assert _check_crowded_figure(crowded_branch(specials), _bare_position()) > 0
