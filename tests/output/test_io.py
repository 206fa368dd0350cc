"""Export and reload of branches and special points."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from saltation.branches.branch import (
    Branch,
    BranchKind,
    BranchPoint,
    OneSided,
    SpecialPoint,
    SpecialPointKind,
    StopReason,
    Touch,
)
from saltation.output.io import (
    csv_metadata_path,
    load_branch_csv,
    load_branch_json,
    load_diagram_json,
    load_special_points_json,
    save_branch_csv,
    save_branch_json,
    save_diagram_json,
    save_special_points_json,
    special_point_record,
)

INF = complex(math.inf, 0.0)


def _point(k: int, *, stable: bool, mu: np.ndarray, events: tuple[str, ...]) -> BranchPoint:
    # irrational-looking values exercise full-precision writing
    return BranchPoint(
        parameter=0.1 * k + 1 / 3,
        state=np.array([np.sqrt(2) * k, -np.pi / (k + 1)]),
        period=2 * np.pi / (1.0 + 0.1 * k + 1e-17 * k),
        amplitude=np.e + k * 1e-9,
        half_peak_to_peak=np.e - k / 7,
        multipliers=mu,
        stable=stable,
        event_labels=events,
        step=1e-3 / 3 * (k + 1),
        iterations=k % 4,
    )


def smooth_fold() -> SpecialPoint:
    return SpecialPoint(
        kind=SpecialPointKind.FOLD,
        parameter=1.2345678901234567,
        bracket=(1.2345678901, 1.2345678902),
        accuracy=1e-10,
        index=2,
        state=np.array([0.1, -0.2]),
        period=6.283185307179586,
        amplitude=1.5,
        multipliers=np.array([1.0 + 0.0j, 0.3 - 0.1j]),
        note="smooth fold",
    )


def discontinuous_fold() -> SpecialPoint:
    return SpecialPoint(
        kind=SpecialPointKind.DISCONTINUOUS_FOLD,
        parameter=0.7071067811865476,
        bracket=(0.70710678, 0.70710679),
        accuracy=1e-8,
        index=4,
        state=np.array([2.0, 0.5]),
        period=4.1,
        amplitude=2.0,
        one_sided=OneSided(
            multipliers_minus=np.array([1.0 + 0j, 0.0 + 0j]),
            multipliers_plus=np.array([INF, 1.0 + 0j]),
            monodromy_minus=np.array([[1.0, 0.25], [0.0, 0.0]]),
            monodromy_plus=np.array([[1.0, 0.0], [np.inf, 1.0]]),
            crossing_q=0.5,
            crossing_point=1.0 + 0.0j,
            event_labels_minus=("slip -[stick+]-> stick",),
            event_labels_plus=("slip -[stick+]-> stick", "stick -[slip-]-> slip"),
            event_ids_minus=((1, 0, 1),),
            event_ids_plus=((1, 0, 1), (1, 1, 0)),
        ),
        note="set-valued multiplier crosses at +1",
    )


def no_crossing() -> SpecialPoint:
    return SpecialPoint(
        kind=SpecialPointKind.NONSMOOTH_NO_CROSSING,
        parameter=0.9,
        bracket=(0.89, 0.91),
        accuracy=0.02,
        index=5,
        state=np.array([1.0, 0.0]),
        period=math.nan,
        amplitude=1.0,
        multipliers_minus=np.array([0.5 + 0.2j, 0.5 - 0.2j]),
        multipliers_plus=np.array([0.4 + 0j, 0.1 + 0j]),
    )


def adding_sliding() -> SpecialPoint:
    return SpecialPoint(
        kind=SpecialPointKind.ADDING_SLIDING,
        parameter=0.9000743388806751,
        bracket=(0.9000743388806701, 0.9000743388806801),
        accuracy=5e-15,
        index=6,
        state=np.array([0.1, 0.2]),
        period=7.853981633974483,
        amplitude=0.5,
        multipliers_minus=np.array([0.6 + 0j, 0j]),
        multipliers_plus=np.array([0.62 + 0j, 0j]),
        touch_surface="v_rel",
        touch_mode="slip_plus",
        touch_time=7.538131315032597,
    )


def synthetic_branch() -> Branch:
    points = []
    for k in range(8):
        stable = k < 5
        if stable:
            mu = np.array([0.5 + 0.25j * k / 8, 0.5 - 0.25j * k / 8])
            events = ("free -[h1+]-> contact", "contact -[h1-]-> free")
        else:
            mu = np.array([INF, 1.0 + 1e-16j])
            events = ("slide on stick (slip|stick)", "leave stick sliding -> slip")
        points.append(_point(k, stable=stable, mu=mu, events=events))
    points.append(_point(8, stable=False, mu=np.array([INF, 1.0 + 0j]), events=()))
    return Branch(
        model="block_on_belt",
        parameter_name="v_dr",
        kind=BranchKind.PERIODIC,
        backward=True,
        points=points,
        special_points=[smooth_fold(), discontinuous_fold(), no_crossing(), adding_sliding()],
        stop_reason=StopReason.MIN_STEP,
        stop_reasons=[StopReason.PARAMETER_BOUND, None],
        fixed_parameters={"m": 1.0, "k": 1.0, "c": 0.0, "F_slip": 1.0, "F_stick": 2.0, "eta": 1e-4},
        label="unstable periodic",
        autonomous=True,
    )


def _same_array(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype.kind == b.dtype.kind and np.array_equal(a, b, equal_nan=True)


def _same_float(a: float | None, b: float | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return a == b or (math.isnan(a) and math.isnan(b))


def assert_points_equal(p: BranchPoint, q: BranchPoint) -> None:
    for name in ("parameter", "period", "amplitude", "half_peak_to_peak", "step"):
        assert _same_float(getattr(p, name), getattr(q, name)), name
    assert _same_array(p.state, q.state)
    assert _same_array(p.multipliers, q.multipliers)
    assert p.stable == q.stable and isinstance(q.stable, bool)
    assert p.event_labels == q.event_labels and isinstance(q.event_labels, tuple)
    assert p.iterations == q.iterations


def assert_special_points_equal(s: SpecialPoint, t: SpecialPoint) -> None:
    assert s.kind is t.kind
    for name in ("parameter", "accuracy", "period", "amplitude", "crossing_q"):
        assert _same_float(getattr(s, name), getattr(t, name)), name
    assert tuple(s.bracket) == tuple(t.bracket)
    assert s.index == t.index
    for name in ("state", "multipliers", "multipliers_minus", "multipliers_plus", "monodromy_minus", "monodromy_plus"):
        assert _same_array(getattr(s, name), getattr(t, name)), name
    assert s.crossing_point == t.crossing_point
    assert s.event_labels_minus == t.event_labels_minus and s.event_labels_plus == t.event_labels_plus
    assert (s.one_sided is None) == (t.one_sided is None) and (s.touch is None) == (t.touch is None)
    assert (s.touch_surface, s.touch_mode) == (t.touch_surface, t.touch_mode) and _same_float(s.touch_time, t.touch_time)
    assert (s.limits, s.growth_exponents, s.event_ids_minus, s.event_ids_plus, s.event_ids) == (
        t.limits, t.growth_exponents, t.event_ids_minus, t.event_ids_plus, t.event_ids)
    assert s.note == t.note


def assert_branches_equal(a: Branch, b: Branch) -> None:
    assert (a.model, a.parameter_name, a.kind, a.backward, a.stop_reason, a.label, a.autonomous) == (
        b.model, b.parameter_name, b.kind, b.backward, b.stop_reason, b.label, b.autonomous
    )
    assert a.fixed_parameters == b.fixed_parameters
    assert a.stop_reasons == b.stop_reasons
    assert len(a.points) == len(b.points)
    for p, q in zip(a.points, b.points):
        assert_points_equal(p, q)
    assert len(a.special_points) == len(b.special_points)
    for s, t in zip(a.special_points, b.special_points):
        assert_special_points_equal(s, t)


# --- JSON -------------------------------------------------------------------


def test_branch_json_round_trip_is_lossless(tmp_path):
    branch = synthetic_branch()
    path = save_branch_json(branch, tmp_path / "branch.json")
    assert_branches_equal(branch, load_branch_json(path))


def test_branch_json_is_strict_json_with_inf_as_string(tmp_path):
    path = save_branch_json(synthetic_branch(), tmp_path / "branch.json")
    text = path.read_text()
    assert "Infinity" not in text and "NaN" not in text
    d = json.loads(text)
    last = d["points"][-1]
    assert last["multipliers"] == ["inf", [1.0, 0.0]]
    assert (d["stop_reason"], d["stop_reasons"]) == ("min_step", ["parameter_bound", None])
    assert d["special_points"][2]["period"] == "nan"
    assert d["special_points"][1]["one_sided"]["monodromy_plus"] == [[1.0, 0.0], ["inf", 1.0]]


def test_branch_json_round_trip_of_equilibrium_branch(tmp_path):
    eq = Branch(
        model="block_on_belt",
        parameter_name="v_dr",
        kind=BranchKind.EQUILIBRIUM,
        points=[
            BranchPoint(
                parameter=v, state=np.array([1.0, 0.0]), period=math.nan, amplitude=1.0,
                half_peak_to_peak=0.0, multipliers=np.array([-0.1 + 1j, -0.1 - 1j]), stable=True, event_labels=(),
            )
            for v in (0.1, 0.2)
        ],
    )
    assert_branches_equal(eq, load_branch_json(save_branch_json(eq, tmp_path / "eq.json")))


def test_diagram_json_round_trip(tmp_path):
    a = synthetic_branch()
    b = synthetic_branch()
    b.label, b.backward, b.stop_reason, b.special_points = "stable periodic", False, None, []
    loaded = load_diagram_json(save_diagram_json([a, b], tmp_path / "diagram.json"))
    assert len(loaded) == 2
    assert_branches_equal(a, loaded[0])
    assert_branches_equal(b, loaded[1])


def test_load_rejects_other_formats(tmp_path):
    path = tmp_path / "x.json"
    path.write_text(json.dumps({"format": "something else", "version": 1}))
    with pytest.raises(ValueError, match="saltation.branches.branch"):
        load_branch_json(path)
    path.write_text(json.dumps({"format": "saltation.branches.branch", "version": 99}))
    with pytest.raises(ValueError, match="version 99"):
        load_branch_json(path)


# --- CSV --------------------------------------------------------------------


def test_csv_columns(tmp_path):
    """The columns are named after the parameter, the states and what each multiplier column holds."""
    branch = synthetic_branch()
    branch.state_names = ("x", "v")
    path = save_branch_csv(branch, tmp_path / "branch.csv")
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == [
        "v_dr", "period", "amplitude", "half_peak_to_peak", "stable", "event_labels", "step", "iterations",
        "x", "v", "multiplier1_re", "multiplier1_im", "multiplier1_abs", "multiplier2_re", "multiplier2_im",
        "multiplier2_abs",
    ]
    assert len(rows) == 1 + len(synthetic_branch())
    first = dict(zip(rows[0], rows[1]))
    assert first["stable"] == "true"
    assert first["event_labels"] == "free -[h1+]-> contact;contact -[h1-]-> free"
    assert float(first["v_dr"]) == 1 / 3
    last = dict(zip(rows[0], rows[-1]))
    assert (last["multiplier1_re"], last["multiplier1_im"], last["multiplier1_abs"]) == ("inf", "0.0", "inf")
    assert last["event_labels"] == ""


def test_csv_columns_of_equilibria_and_of_clashing_names(tmp_path):
    """An equilibrium branch's values are the Jacobian's eigenvalues (no modulus column); a state named like a
    fixed column, or a branch without state names (files before they were recorded), gets a prefixed name;
    both read back the same."""
    branch = synthetic_branch()
    branch.kind, branch.state_names = BranchKind.EQUILIBRIUM, ("period", "v")
    path = save_branch_csv(branch, tmp_path / "eq.csv", metadata=False)
    header = next(csv.reader(path.open(newline="")))
    assert header[8:] == ["state_period", "v", "eigenvalue1_re", "eigenvalue1_im", "eigenvalue2_re", "eigenvalue2_im"]
    loaded = load_branch_csv(path, model="block_on_belt", parameter_name="v_dr")
    for p, q in zip(branch.points, loaded.points):
        np.testing.assert_array_equal(p.state, q.state)
        np.testing.assert_array_equal(p.multipliers, q.multipliers)
    branch = synthetic_branch()
    path = save_branch_csv(branch, tmp_path / "unnamed.csv", metadata=False)
    assert next(csv.reader(path.open(newline="")))[8:10] == ["state_0", "state_1"]


def test_csv_of_the_first_format_still_loads(tmp_path):
    """A CSV written before the columns were named (parameter, state_0, mu0_re, ...) loads as it did."""
    branch = synthetic_branch()
    rows = [["parameter", "period", "amplitude", "half_peak_to_peak", "stable", "event_labels", "step", "iterations",
             "state_0", "state_1", "mu0_re", "mu0_im", "mu0_abs", "mu1_re", "mu1_im", "mu1_abs"]]
    for p in branch.points:
        row = [repr(float(p.parameter)), repr(float(p.period)), repr(float(p.amplitude)), repr(float(p.half_peak_to_peak)),
               "true" if p.stable else "false", ";".join(p.event_labels), repr(float(p.step)), str(p.iterations)]
        row += [repr(float(x)) for x in p.state]
        for z in p.multipliers:
            row += [repr(float(z.real)), repr(float(z.imag)), repr(float(abs(z)))]
        rows.append(row)
    path = tmp_path / "old.csv"
    with path.open("w", newline="") as fh:
        csv.writer(fh).writerows(rows)
    loaded = load_branch_csv(path, model="block_on_belt", parameter_name="v_dr")
    assert len(loaded) == len(branch)
    for p, q in zip(branch.points, loaded.points):
        assert (q.parameter, q.stable, q.event_labels) == (p.parameter, p.stable, p.event_labels)
        np.testing.assert_array_equal(p.state, q.state)
        np.testing.assert_array_equal(p.multipliers, q.multipliers)


def test_csv_round_trip_of_points_is_lossless(tmp_path):
    branch = synthetic_branch()
    path = save_branch_csv(branch, tmp_path / "branch.csv", metadata=False)
    assert not csv_metadata_path(path).exists()
    loaded = load_branch_csv(path, model="block_on_belt", parameter_name="v_dr")
    assert (loaded.model, loaded.parameter_name, loaded.special_points) == ("block_on_belt", "v_dr", [])
    assert len(loaded) == len(branch)
    for p, q in zip(branch.points, loaded.points):
        assert_points_equal(p, q)


def test_csv_with_side_file_restores_the_whole_branch(tmp_path):
    branch = synthetic_branch()
    path = save_branch_csv(branch, tmp_path / "run.v1.csv")
    assert csv_metadata_path(path) == tmp_path / "run.v1.meta.json"
    assert_branches_equal(branch, load_branch_csv(path))


def test_csv_rejects_ragged_points(tmp_path):
    branch = synthetic_branch()
    p = branch.points[3]
    branch.points[3] = BranchPoint(
        p.parameter, np.zeros(3), p.period, p.amplitude, p.half_peak_to_peak, p.multipliers, p.stable, p.event_labels
    )
    with pytest.raises(ValueError, match="point 3"):
        save_branch_csv(branch, tmp_path / "bad.csv")


# --- special-point records --------------------------------------------------

COMMON = {
    "model", "kind", "parameter", "value", "amplitude", "bracket", "accuracy", "crossing_point", "note",
    "multipliers_accuracy", "limits", "status",
}


def test_record_of_smooth_point():
    rec = special_point_record(smooth_fold(), "trilinear", "omega")
    assert set(rec) == COMMON | {"multipliers"}
    assert list(rec)[:5] == ["model", "kind", "parameter", "value", "amplitude"]
    assert rec["model"] == "trilinear"
    assert rec["kind"] == "fold"
    assert rec["parameter"] == "omega"
    assert rec["value"] == 1.2345678901234567
    assert rec["amplitude"] == 1.5
    assert rec["multipliers"] == [[1.0, 0.0], [0.3, -0.1]]
    assert rec["bracket"] == [1.2345678901, 1.2345678902]
    assert rec["accuracy"] == 1e-10
    assert rec["crossing_point"] is None
    assert rec["note"] == "smooth fold"


def test_record_of_nonsmooth_point():
    rec = special_point_record(discontinuous_fold(), "block_on_belt", "v_dr")
    assert set(rec) == COMMON | {"multipliers_minus", "multipliers_plus", "crossing_q"}
    assert rec["kind"] == "discontinuous_fold"
    assert rec["parameter"] == "v_dr"
    assert rec["value"] == 0.7071067811865476
    assert rec["multipliers_minus"] == [[1.0, 0.0], [0.0, 0.0]]
    assert rec["multipliers_plus"] == ["inf", [1.0, 0.0]]
    assert rec["crossing_q"] == 0.5
    assert rec["crossing_point"] == [1.0, 0.0]

    rec = special_point_record(no_crossing(), "trilinear", "omega")
    assert set(rec) == COMMON | {"multipliers_minus", "multipliers_plus", "crossing_q"}
    assert rec["crossing_q"] is None and rec["crossing_point"] is None


def test_record_of_sliding_bifurcation_says_where_it_touches():
    rec = special_point_record(adding_sliding(), "friction_oscillator", "F")
    assert set(rec) == COMMON | {"multipliers_minus", "multipliers_plus", "crossing_q", "touch_surface",
                                 "touch_mode", "touch_time"}
    assert (rec["kind"], rec["touch_surface"], rec["touch_mode"]) == ("adding_sliding", "v_rel", "slip_plus")
    assert rec["touch_time"] == 7.538131315032597


def test_special_points_json(tmp_path):
    branch = synthetic_branch()
    records = [special_point_record(sp, branch.model, branch.parameter_name) for sp in branch.special_points]
    path = save_special_points_json(records, tmp_path / "special_points.json")
    text = path.read_text()
    assert "Infinity" not in text and "NaN" not in text
    assert json.loads(text) == records
    assert load_special_points_json(path) == records


def test_every_dataclass_field_is_written(tmp_path):
    """A field added to Branch, BranchPoint or SpecialPoint must be added to the file format too."""
    from dataclasses import fields

    branch = synthetic_branch()
    d = json.loads(save_branch_json(branch, tmp_path / "b.json").read_text())
    assert {f.name for f in fields(Branch)} <= set(d)
    assert {f.name for f in fields(BranchPoint)} == set(d["points"][0])
    assert {f.name for f in fields(SpecialPoint)} == set(d["special_points"][0])
    sided = next(sp for sp in d["special_points"] if sp["one_sided"] is not None)
    assert {f.name for f in fields(OneSided)} == set(sided["one_sided"])
    touched = next(sp for sp in d["special_points"] if sp["touch"] is not None)
    assert {f.name for f in fields(Touch)} == set(touched["touch"])


def test_a_field_without_a_codec_stops_the_import():
    """The codecs are built from the dataclasses' fields: a field of a type they do not know is an error
    at import, naming it, not a field silently left out of the files."""
    from dataclasses import dataclass

    from saltation.output.io import _Codec

    @dataclass
    class Record:
        value: float
        shape: set

    with pytest.raises(TypeError, match=r"Record\.shape \(set\) has no file codec"):
        _Codec(Record, {})


def test_curve_records_round_trip(tmp_path):
    """A branch point's second parameter, a codimension-two point's sides and second parameter, and the
    kind a curve continues are written and read back."""
    from dataclasses import replace

    branch = synthetic_branch()
    branch.points = [replace(p, second_parameter=0.25 + k) for k, p in enumerate(branch.points)]
    branch.special_points = [replace(branch.special_points[0], kind=SpecialPointKind.CODIMENSION_TWO,
                                     second_parameter=0.125, sides=("fold", "grazing"))]
    branch.second_parameter_name, branch.curve_of = "f0", SpecialPointKind.FOLD
    again = load_branch_json(save_branch_json(branch, tmp_path / "c.json"))
    assert again.second_parameter.tolist() == branch.second_parameter.tolist()
    (sp,) = again.special_points
    assert (sp.kind, sp.second_parameter, sp.sides) == (SpecialPointKind.CODIMENSION_TWO, 0.125, ("fold", "grazing"))
    assert (again.second_parameter_name, again.curve_of) == ("f0", SpecialPointKind.FOLD)


def test_files_written_before_the_event_labels_rename_are_read(tmp_path):
    """Branch files (JSON and CSV) from before the fields were named event_labels (keys "events",
    "events_minus", "events_plus") read back to the same branch."""
    branch = synthetic_branch()
    text = save_branch_json(branch, tmp_path / "new.json").read_text()
    old = text.replace('"event_labels_minus"', '"events_minus"').replace('"event_labels_plus"', '"events_plus"')
    old = old.replace('"event_labels"', '"events"')
    (tmp_path / "old.json").write_text(old)
    assert "event_labels" not in old
    again = load_branch_json(tmp_path / "old.json")
    assert [p.event_labels for p in again.points] == [p.event_labels for p in branch.points]
    assert [(s.event_labels_minus, s.event_labels_plus) for s in again.special_points] == [
        (s.event_labels_minus, s.event_labels_plus) for s in branch.special_points
    ]
    csv_path = save_branch_csv(branch, tmp_path / "new.csv")
    lines = csv_path.read_text().splitlines()
    lines[0] = lines[0].replace("event_labels", "events")
    old_csv = tmp_path / "old.csv"
    old_csv.write_text("\n".join(lines) + "\n")
    csv_metadata_path(old_csv).write_text(csv_metadata_path(csv_path).read_text())
    assert [p.event_labels for p in load_branch_csv(old_csv).points] == [p.event_labels for p in branch.points]
