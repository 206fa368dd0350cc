"""Files: written atomically, read back checked, and the command line's output folder and OS errors.

* Writing: every writer (branch JSON and CSV with its side file, diagram, special points,
  ``write_json``, sweep JSON and CSV, period map, figures) leaves the old file untouched and no
  temporary file behind when it fails midway: an exception while encoding, or a full disk
  (``os.write`` patched to write part of the data, then fail with ENOSPC).
* Reading: truncated and hand-edited files raise :class:`FileFormatError` naming the file and
  the field; a round trip of every file kind gives back what was written (compared field by field,
  figures byte for byte with matplotlib's own writing), and files of the previous version still read.
* Command line: a bad ``--out`` is exit status 2 before any computation; a full disk while writing
  is one line and exit status 1; a closed standard output (``| head``) exits quietly.
"""

from __future__ import annotations

import csv
import dataclasses
import errno
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from saltation.apps import cli
from saltation.output import io, plotting
from saltation.branches.branch import (
    Branch,
    BranchKind,
    BranchPoint,
    SpecialPoint,
    SpecialPointKind,
    StopReason,
)
from saltation.errors import SaltationError
from saltation.output.io import FileFormatError
from saltation.apps.sweeps import PeriodMap, SweepResult, SweepStart

INF = complex(math.inf, 0.0)


# ---------------------------------------------------------------------------------------------
# objects to write, and an independent comparison
# ---------------------------------------------------------------------------------------------

def make_branch(n_points: int = 28, label: str = "stable periodic") -> Branch:
    """A branch whose numbers need full precision, with infinite multipliers, NaN periods and every kind of field."""
    points = []
    for k in range(n_points):
        stable = k % 3 != 2
        mu = np.array([0.5 + 0.1j * k / 7, 0.5 - 0.1j * k / 7]) if stable else np.array([INF, 1.0 + 1e-16j])
        points.append(BranchPoint(
            parameter=1 / 3 + k / 97, state=np.array([math.sqrt(2) * k, -math.pi / (k + 1)]),
            period=math.nan if k == 5 else 2 * math.pi / (1 + k / 89), amplitude=math.e + k * 1e-9,
            half_peak_to_peak=math.e - k / 7, multipliers=mu, stable=stable,
            event_labels=("free -[h+]-> contact", "contact -[h-]-> free") if stable else (),
            step=1e-3 / 3 * (k + 1), iterations=k % 4,
        ))
    specials = [
        SpecialPoint(kind=SpecialPointKind.FOLD, parameter=0.4142135623730951, bracket=(0.41421356, 0.41421357),
                     accuracy=1e-8, index=2, state=np.array([0.1, -0.2]), period=6.283185307179586, amplitude=1.5,
                     multipliers=np.array([1.0 + 0j, 0.3 - 0.1j]), note="smooth fold"),
        SpecialPoint(kind=SpecialPointKind.DISCONTINUOUS_FOLD, parameter=0.7071067811865476,
                     bracket=(0.70710678, 0.70710679), accuracy=1e-8, index=4, state=np.array([2.0, 0.5]), period=4.1,
                     amplitude=2.0, multipliers_minus=np.array([1.0 + 0j, 0j]), multipliers_plus=np.array([INF, 1 + 0j]),
                     monodromy_minus=np.array([[1.0, 0.25], [0.0, 0.0]]),
                     monodromy_plus=np.array([[1.0, 0.0], [math.inf, 1.0]]), crossing_q=0.5, crossing_point=1 + 0j,
                     event_labels_minus=("slip -[stick+]-> stick",), event_labels_plus=("a", "b"),
                     note="set-valued multiplier crosses at +1", multipliers_accuracy=1e-9, limits="exact"),
        SpecialPoint(kind=SpecialPointKind.ADDING_SLIDING, parameter=0.9, bracket=(0.89, 0.91), accuracy=0.02,
                     index=6, state=np.array([0.1, 0.2]), period=math.nan, amplitude=0.5,
                     multipliers_minus=np.array([0.6 + 0j, 0j]), multipliers_plus=np.array([0.62 + 0j, 0j]),
                     touch_surface="v_rel", touch_mode="slip_plus", touch_time=7.538131315032597),
    ]
    return Branch(model="block_on_belt", parameter_name="v_dr", kind=BranchKind.PERIODIC, backward=True,
                  points=points, special_points=specials, stop_reason=StopReason.MIN_STEP,
                  stop_reasons=[StopReason.PARAMETER_BOUND, None], fixed_parameters={"m": 1.0, "eta": 1e-4},
                  label=label, autonomous=True, state_names=("x", "v"), axis_labels={"v_dr": "$v_{dr}$ (m/s)"})


def make_sweep() -> SweepResult:
    return SweepResult(
        model="trilinear", parameter_name="omega", values=np.array([0.5, 0.6, 0.7]), counts=np.array([2, 0, 1]),
        parameter_points=np.array([0.5, 0.5, 0.7]),
        states=np.array([[1 / 3, -2 / 3], [math.pi, math.nan], [math.inf, -1e-300]]), state_names=("x", "v"),
        section="poincare", failures=((0.6, "too many steps"),),
        settings={"periods": 2, "transient": 1, "t0": 0.0, "x0": [0.0, 0.25]}, start=SweepStart.OWN,
    )


def make_map() -> PeriodMap:
    return PeriodMap(
        model="bouncing_ball", parameter_name="A", parameter2_name="e", values=np.array([0.1, 0.2, 1 / 3]),
        values2=np.array([0.5, 0.75]), periods=np.array([[1, 2, 0], [-1, 4, 16]]), max_period=16,
        failures=((0.1, 0.75, "chattering"),), settings={"periods": 64, "transient": 100, "tolerance": 1e-6},
        start=SweepStart.PREVIOUS,
    )


def assert_same(a, b, where: str = "") -> None:
    """``a`` and ``b`` equal field by field (dataclasses, arrays, NaN equal to NaN, types kept)."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            assert_same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.shape == b.shape and a.dtype.kind == b.dtype.kind, where
        assert np.array_equal(a, b, equal_nan=True), where
    elif isinstance(a, float):
        assert isinstance(b, float) and (a == b or (math.isnan(a) and math.isnan(b))), (where, a, b)
    elif isinstance(a, complex):
        assert isinstance(b, complex) and a == b, (where, a, b)
    elif isinstance(a, (list, tuple)):
        assert type(a) is type(b) and len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{k}]")
    elif isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), where
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}")
    else:
        assert type(a) is type(b) and a == b, (where, a, b)


def refused(load, path, field: str, *fragments: str) -> FileFormatError:
    """``load(path)`` raises FileFormatError naming ``path`` and ``field``, its message holding ``fragments``."""
    with pytest.raises(FileFormatError) as info:
        load(path)
    err = info.value
    assert isinstance(err, SaltationError) and isinstance(err, ValueError)
    assert (err.source, err.field) == (str(path), field), str(err)
    assert str(err).startswith(f"{path}: {field}: " if field else f"{path}: "), str(err)
    for fragment in fragments:
        assert fragment in err.problem, str(err)
    return err


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


# ---------------------------------------------------------------------------------------------
# every writer, every file kind
# ---------------------------------------------------------------------------------------------

def _write_figure(folder: Path) -> list[Path]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 1.5))
    fig.add_subplot().plot([0, 1, 2], [1, 0, 2])
    return list(plotting.save_figure(fig, folder / "figure", dpi=50))


#: name -> write(folder) returning the files written
WRITERS = {
    "branch_json": lambda d: [io.save_branch_json(make_branch(), d / "branch.json")],
    "diagram_json": lambda d: [io.save_diagram_json([make_branch(), make_branch(3, "unstable")], d / "diagram.json")],
    "branch_csv": lambda d: [io.save_branch_csv(make_branch(), d / "branch.csv"), d / "branch.meta.json"],
    "special_points": lambda d: [io.save_special_points_json(
        [io.special_point_record(sp, "block_on_belt", "v_dr") for sp in make_branch().special_points],
        d / "special_points.json")],
    "write_json": lambda d: [io.write_json({"a": [1, 2.5, None], "b": "text"}, d / "record.json")],
    "sweep_json": lambda d: [make_sweep().save(d / "sweep.json")],
    "sweep_csv": lambda d: [make_sweep().save(d / "sweep.csv")],
    "period_map": lambda d: [make_map().save(d / "map.json")],
    "figure": _write_figure,
}


@pytest.fixture
def full_disk(monkeypatch, tmp_path):
    """``os.write`` into a file under ``tmp_path`` (whose name holds ``only``, if set) writes half of what it is
    given and then fails with ENOSPC, as on a full disk; other writes go through."""
    real_write, root = os.write, os.path.realpath(tmp_path)
    state = {"only": "", "calls": 0}

    def write(fd, data):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            target = ""
        if target.startswith(root) and state["only"] in os.path.basename(target):
            state["calls"] += 1
            real_write(fd, bytes(data[: max(1, len(data) // 2)]))
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_write(fd, data)

    monkeypatch.setattr(os, "write", write)
    return state


@pytest.mark.parametrize("kind", list(WRITERS))
def test_a_full_disk_leaves_the_old_files_untouched(tmp_path, kind, full_disk):
    """Whatever is written, a write failing midway (ENOSPC) raises OSError naming a file, leaves every old
    file byte for byte as it was, and leaves no temporary file."""
    out = tmp_path / "out"
    out.mkdir()
    full_disk["only"] = "\0"  # nothing fails while the old files are written
    old = {p: b"old content of " + p.name.encode() + b"\n" for p in WRITERS[kind](out)}
    for p, content in old.items():
        p.write_bytes(content)
    full_disk["only"] = ""
    with pytest.raises(OSError) as info:
        WRITERS[kind](out)
    assert info.value.errno == errno.ENOSPC and full_disk["calls"] >= 1
    assert Path(info.value.filename) in old
    assert {p: p.read_bytes() for p in old} == old
    assert leftovers(out) == [] and sorted(out.iterdir()) == sorted(old)


@pytest.mark.parametrize("kind", list(WRITERS))
def test_a_full_disk_leaves_no_file_where_there_was_none(tmp_path, kind, full_disk):
    with pytest.raises(OSError):
        WRITERS[kind](tmp_path / "new")
    assert list((tmp_path / "new").iterdir()) == []


def test_a_failing_side_file_keeps_the_old_csv_too(tmp_path, full_disk):
    """A CSV and its side file are both written before either replaces the old one: a disk that fills up
    on the side file leaves the old pair, which still agree with each other."""
    old = make_branch(7, "old")
    full_disk["only"] = "\0"  # nothing fails while the old files are written
    io.save_branch_csv(old, tmp_path / "branch.csv")
    before = {p: p.read_bytes() for p in tmp_path.iterdir()}
    full_disk["only"] = ".meta.json"
    with pytest.raises(OSError) as info:
        io.save_branch_csv(make_branch(), tmp_path / "branch.csv")
    assert info.value.filename == str(tmp_path / "branch.meta.json")
    assert {p: p.read_bytes() for p in tmp_path.iterdir()} == before
    assert_same(old, io.load_branch_csv(tmp_path / "branch.csv"))


def test_a_failed_csv_save_leaves_no_partial_file(tmp_path):
    """An event label holding the separator (``m;1``) at point 10 of 28: the error names the point, and no CSV
    is left that would load with 10 points; an old CSV stays as it was."""
    branch = make_branch()
    p = branch.points[10]
    branch.points[10] = dataclasses.replace(p, event_labels=("m;1",))
    with pytest.raises(ValueError, match=r"point 10: event label 'm;1'"):
        io.save_branch_csv(branch, tmp_path / "branch.csv")
    assert list(tmp_path.iterdir()) == []
    good = io.save_branch_csv(make_branch(5), tmp_path / "branch.csv")
    before = good.read_bytes(), io.csv_metadata_path(good).read_bytes()
    with pytest.raises(ValueError, match="point 10"):
        io.save_branch_csv(branch, good)
    assert (good.read_bytes(), io.csv_metadata_path(good).read_bytes()) == before
    assert len(io.load_branch_csv(good)) == 5 and leftovers(tmp_path) == []


def test_an_exception_while_drawing_leaves_the_old_figures(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    stem = tmp_path / "figure"
    for suffix in (".png", ".pdf"):
        stem.with_name("figure" + suffix).write_bytes(b"old")
    fig = Figure()
    real = Figure.savefig

    def savefig(self, fname, **kwargs):
        if kwargs.get("format") == "pdf":
            raise RuntimeError("the PDF backend failed")
        return real(self, fname, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    with pytest.raises(RuntimeError):
        plotting.save_figure(fig, stem)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == {"figure.png": b"old", "figure.pdf": b"old"}


def test_atomic_writes_keep_permissions_and_follow_links(tmp_path):
    target = tmp_path / "data" / "branch.json"
    io.save_branch_json(make_branch(3), target)  # creates the folder
    umask = os.umask(0o022)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask  # a new file: as open() would create it
    target.chmod(0o640)
    io.save_branch_json(make_branch(4), target)
    assert target.stat().st_mode & 0o777 == 0o640  # a replaced file keeps its permissions
    link = tmp_path / "link.json"
    link.symlink_to(target)
    io.save_branch_json(make_branch(5), link)
    assert link.is_symlink() and len(io.load_branch_json(target)) == 5
    assert leftovers(target.parent) == [] and leftovers(tmp_path) == []


# ---------------------------------------------------------------------------------------------
# round trips
# ---------------------------------------------------------------------------------------------

def test_round_trip_of_every_file_kind(tmp_path, monkeypatch):
    """Each file reads back to what was written: branches, diagrams, CSV (with and without its side file),
    records, sweeps (the CSV read with numpy), maps; figures equal matplotlib's own files byte for byte."""
    branch = make_branch()
    assert_same(branch, io.load_branch_json(io.save_branch_json(branch, tmp_path / "b.json")))
    diagram = [make_branch(), make_branch(3, "unstable")]
    assert_same(diagram, io.load_diagram_json(io.save_diagram_json(diagram, tmp_path / "d.json")))
    assert_same(branch, io.load_branch_csv(io.save_branch_csv(branch, tmp_path / "b.csv")))
    points = io.load_branch_points_csv(io.save_branch_csv(branch, tmp_path / "p.csv", metadata=False))
    assert not (tmp_path / "p.meta.json").exists()
    assert_same(branch.points, points)
    records = [io.special_point_record(sp, "block_on_belt", "v_dr") for sp in branch.special_points]
    path = io.save_special_points_json(records, tmp_path / "sp.json")
    loaded = io.load_special_points_json(path)
    assert loaded == records == json.loads(path.read_text()) and all(type(r) is dict for r in loaded)
    obj = {"a": [1, 2.5, None, True], "b": {"c": "text"}}
    assert json.loads(io.write_json(obj, tmp_path / "r.json").read_text()) == obj

    sweep = make_sweep()
    assert_same(sweep, SweepResult.load(sweep.save(tmp_path / "s.json")))
    table = np.loadtxt(sweep.save(tmp_path / "s.csv"), delimiter=",", skiprows=1)
    assert np.array_equal(table, np.column_stack([sweep.parameter_points, sweep.states]), equal_nan=True)
    assert (tmp_path / "s.csv").read_text().splitlines()[0] == "omega,x,v"
    grid = make_map()
    assert_same(grid, PeriodMap.load(grid.save(tmp_path / "m.json")))
    assert_same(grid, PeriodMap.from_dict(grid.to_dict()))

    from matplotlib.figure import Figure

    monkeypatch.setenv("SOURCE_DATE_EPOCH", "0")  # a reproducible PDF
    fig = Figure(figsize=(3, 2))
    fig.add_subplot().plot([0, 1, 2], [1, 0, 2], "o-")
    png, pdf = plotting.save_figure(fig, tmp_path / "fig.v1", dpi=60)
    assert (png.name, pdf.name) == ("fig.v1.png", "fig.v1.pdf")
    import matplotlib

    with matplotlib.rc_context(plotting.PUBLICATION_RC):  # what save_figure writes with (TrueType fonts)
        fig.savefig(tmp_path / "reference.png", dpi=60)
        fig.savefig(tmp_path / "reference.pdf")
    assert png.read_bytes() == (tmp_path / "reference.png").read_bytes()
    assert pdf.read_bytes() == (tmp_path / "reference.pdf").read_bytes()
    assert leftovers(tmp_path) == []


# files as the previous version wrote them (saltation.output.io before the side file recorded its number of rows)
OLD_CSV = (
    "parameter,period,amplitude,half_peak_to_peak,stable,event_labels,step,iterations,state_0,state_1,mu0_re,mu0_im,"
    "mu0_abs,mu1_re,mu1_im,mu1_abs\r\n"
    "0.5,6.5,1.25,1.0,true,free -[h+]-> contact;contact -[h-]-> free,0.01,3,0.25,-1.5,0.5,0.25,0.5590169943749475,0.5,"
    "-0.25,0.5590169943749475\r\n"
    "0.75,nan,1.5,1.25,false,,0.02,0,0.125,-1.75,inf,0.0,inf,1.0,0.0,1.0\r\n"
)
OLD_META = """{"format": "saltation.branches.branch", "version": 1, "model": "trilinear", "parameter_name": "omega",
 "kind": "periodic", "backward": true, "autonomous": false, "label": "old branch", "stop_reason": "min_step",
 "stop_reasons": [null], "fixed_parameters": {"omega": 0.5, "f0": 0.2},
 "special_points": [{"kind": "discontinuous_fold", "parameter": 0.625, "bracket": [0.6, 0.65], "accuracy": 0.05,
  "index": 0, "state": [0.2, -1.6], "period": 7.0, "amplitude": 1.3, "multipliers": null,
  "multipliers_minus": [[1.0, 0.0], [0.5, 0.0]], "multipliers_plus": ["inf", [1.0, 0.0]],
  "monodromy_minus": [[1.0, 0.5], [0.0, 0.5]], "monodromy_plus": null, "crossing_q": 0.5, "crossing_point": [1.0, 0.0],
  "event_labels_minus": [], "event_labels_plus": [], "note": "old", "multipliers_accuracy": "nan", "limits": "",
  "touch_surface": "", "touch_mode": "", "touch_time": "nan"}]}
"""


def test_files_of_the_previous_version_still_read(tmp_path):
    (tmp_path / "old.csv").write_bytes(OLD_CSV.encode())
    (tmp_path / "old.meta.json").write_text(OLD_META)
    branch = io.load_branch_csv(tmp_path / "old.csv")
    expected = [
        BranchPoint(0.5, np.array([0.25, -1.5]), 6.5, 1.25, 1.0, np.array([0.5 + 0.25j, 0.5 - 0.25j]), True,
                    ("free -[h+]-> contact", "contact -[h-]-> free"), 0.01, 3),
        BranchPoint(0.75, np.array([0.125, -1.75]), math.nan, 1.5, 1.25, np.array([INF, 1 + 0j]), False, (), 0.02, 0),
    ]
    assert_same(expected, branch.points)
    assert (branch.model, branch.label, branch.backward, branch.stop_reasons) == ("trilinear", "old branch", True, [None])
    (sp,) = branch.special_points
    assert (sp.kind, sp.bracket, sp.crossing_point, sp.monodromy_plus) == (
        SpecialPointKind.DISCONTINUOUS_FOLD, (0.6, 0.65), 1 + 0j, None)
    assert np.array_equal(sp.multipliers_plus, [INF, 1 + 0j])
    # version 1 wrote the parts' fields flat: they read into the parts (no touch: its surface was empty)
    assert sp.touch is None and sp.one_sided is not None and sp.one_sided.crossing_q == 0.5
    assert np.array_equal(sp.one_sided.monodromy_minus, [[1.0, 0.5], [0.0, 0.5]])
    # and are written back at version 2, nested, to read as the same point
    again = io.branch_from_dict(io.branch_to_dict(branch))
    assert io.branch_to_dict(branch)["version"] == 2
    assert_same(branch, again)
    # the same branch as JSON (its points written into the side file's object) reads as well
    d = json.loads(OLD_META)
    d["points"] = [io._point_to_dict(p) for p in expected]
    (tmp_path / "old.json").write_text(json.dumps(d))
    assert_same(branch, io.load_branch_json(tmp_path / "old.json"))


def test_the_side_file_records_the_number_of_rows(tmp_path):
    path = io.save_branch_csv(make_branch(), tmp_path / "b.csv")
    meta = json.loads(io.csv_metadata_path(path).read_text())
    with path.open(newline="") as fh:
        assert meta["n_points"] == len(list(csv.reader(fh))) - 1 == 28


# ---------------------------------------------------------------------------------------------
# truncated files
# ---------------------------------------------------------------------------------------------

JSON_FILES = {
    "branch_json": ("branch.json", io.load_branch_json),
    "diagram_json": ("diagram.json", io.load_diagram_json),
    "special_points": ("special_points.json", io.load_special_points_json),
    "sweep_json": ("sweep.json", SweepResult.load),
    "period_map": ("map.json", PeriodMap.load),
}


@pytest.mark.parametrize("kind", list(JSON_FILES))
def test_truncated_json_is_refused_naming_the_file(tmp_path, kind):
    """Every file cut short anywhere (at 40 places, the empty file included) is refused, never read in part."""
    name, load = JSON_FILES[kind]
    (path,) = WRITERS[kind](tmp_path)
    text = path.read_bytes()
    cut = tmp_path / ("cut_" + name)
    for n in sorted(set(np.linspace(0, len(text.rstrip()) - 1, 40).astype(int))):
        cut.write_bytes(text[:n])
        refused(load, cut, "", "the file is empty" if n == 0 or not text[:n].strip() else "not valid JSON")


def test_truncated_csv_is_refused(tmp_path):
    """A CSV cut inside a row ends without a line end; one cut at the end of a row has fewer rows than its side
    file records. Cut anywhere (every row boundary and 40 places more), it is refused."""
    path = io.save_branch_csv(make_branch(), tmp_path / "branch.csv")
    data = path.read_bytes()
    ends = [k + 1 for k in range(len(data)) if data[k:k + 1] == b"\n"]
    cut = tmp_path / "cut.csv"
    io.csv_metadata_path(cut).write_bytes(io.csv_metadata_path(path).read_bytes())
    cuts = sorted(set(ends[:-1]) | set(np.linspace(1, len(data) - 1, 40).astype(int).tolist()))
    for n in cuts:
        cut.write_bytes(data[:n])
        if data[:n].endswith((b"\n", b"\r")):  # cut at the end of a row: whole rows, one count short at least
            n_points = data[:n].count(b"\n") + data[:n].endswith(b"\r") - 1
            if n_points == 28:  # only the last "\n" of "\r\n" is missing: every row is there, and reads back
                assert_same(make_branch(), io.load_branch_csv(cut))
                continue
            refused(io.load_branch_csv, cut, "", f"has {n_points} rows of points", "records 28", "truncated")
        else:
            line = data[:n].count(b"\n") + 1
            refused(io.load_branch_csv, cut, f"line {line}", "ends inside this row", "truncated")
            refused(io.load_branch_points_csv, cut, f"line {line}", "ends inside this row")
    cut.write_bytes(b"")
    refused(io.load_branch_csv, cut, "", "the file is empty")
    # the last digit of the last row cut off: still a full row of numbers, but no line end
    cut.write_bytes(data[:-3])
    refused(io.load_branch_points_csv, cut, "line 29", "ends inside this row")


# ---------------------------------------------------------------------------------------------
# hand-edited files
# ---------------------------------------------------------------------------------------------

def _set(*keys_and_value):
    *keys, value = keys_and_value

    def edit(d):
        for k in keys[:-1]:
            d = d[k]
        d[keys[-1]] = value

    return edit


def _del(*keys):
    def edit(d):
        for k in keys[:-1]:
            d = d[k]
        del d[keys[-1]]

    return edit


BRANCH_EDITS = [
    (_set("points", 3, "stable", "false"), "points[3].stable", 'expected true or false, got "false"'),
    (_set("points", 3, "stable", 1), "points[3].stable", "expected true or false, got 1"),
    (_set("points", 2, "parameter", "1.5"), "points[2].parameter", 'expected a number (or "inf", "-inf", "nan"), got "1.5"'),
    (_set("points", 2, "parameter", "inf"), "points[2].parameter", 'expected a finite number, got "inf"'),
    (_set("points", 2, "period", None), "points[2].period", "expected a number"),
    (_set("points", 2, "period", True), "points[2].period", "expected a number"),
    (_set("points", 1, "state", [1.0]), "points[1].state", "has 1 entries; points[0].state has 2"),
    (_set("points", 1, "state", "x"), "points[1].state", 'expected a list [...], got "x"'),
    (_set("points", 1, "multipliers", 0, [1.0]), "points[1].multipliers[0]", "expected a complex number [re, im]"),
    (_set("points", 1, "multipliers", 1, ["x", 0.0]), "points[1].multipliers[1][0]", "expected a number"),
    (_set("points", 1, "multipliers", [[1.0, 0.0]]), "points[1].multipliers", "has 1 entries; points[0].multipliers has 2"),
    (_set("points", 0, "iterations", 1.5), "points[0].iterations", "expected an integer, got 1.5"),
    (_set("points", 0, "iterations", -1), "points[0].iterations", "expected an integer at least 0, got -1"),
    (_set("points", 0, "event_labels", "a"), "points[0].event_labels", 'expected a list [...], got "a"'),
    (_set("points", 0, "event_labels", [1]), "points[0].event_labels[0]", "expected a string, got 1"),
    (_set("points", 0, 7), "points[0]", "expected an object {...}, got 7"),
    (_del("points", 4, "period"), "points[4].period", "missing"),
    (_del("points"), "points", "missing"),
    (_set("points", {}), "points", "expected a list"),
    (_del("model"), "model", "missing"),
    (_set("model", 3), "model", "expected a string, got 3"),
    (_set("kind", "limit_cycle"), "kind", 'expected one of "periodic", "equilibrium", got "limit_cycle"'),
    (_set("backward", "no"), "backward", 'expected true or false, got "no"'),
    (_set("stop_reason", "bogus"), "stop_reason", 'expected one of "parameter_bound"'),
    (_set("stop_reasons", 1, 5), "stop_reasons[1]", "got 5"),
    (_set("fixed_parameters", "m", "one"), "fixed_parameters.m", 'got "one"'),
    (_set("fixed_parameters", [1.0]), "fixed_parameters", "expected an object"),
    (_set("special_points", 0, "kind", "foldd"), "special_points[0].kind", 'got "foldd"'),
    (_set("special_points", 1, "bracket", [1.0]), "special_points[1].bracket", "expected 2 entries, got 1"),
    (_set("special_points", 1, "index", "4"), "special_points[1].index", "expected an integer"),
    (_set("special_points", 1, "one_sided", "monodromy_minus", [[1.0, 2.0], [3.0]]),
     "special_points[1].one_sided.monodromy_minus[1]", "expected 2 entries, got 1"),
    (_set("special_points", 1, "one_sided", "monodromy_plus", np.eye(3).tolist()),
     "special_points[1].one_sided.monodromy_plus", "expected a 2 x 2 matrix (the state has 2 components), got 3 x 3"),
    (_set("special_points", 1, "one_sided", "crossing_point", [1.0]), "special_points[1].one_sided.crossing_point",
     "expected a complex"),
    (_set("special_points", 1, "one_sided", 3), "special_points[1].one_sided", "expected an object"),
    (_set("special_points", 1, "touch", {"mode": "m"}), "special_points[1].touch.surface", "missing"),
    (_set("special_points", 2, "note", None), "special_points[2].note", "expected a string, got null"),
    (_set("format", "saltation.apps.diagram"), "format", "expected format 'saltation.branches.branch', found \"saltation.apps.diagram\""),
    (_del("format"), "format", "missing: not a saltation.branches.branch file"),
    (_set("version", 3), "version", "unsupported saltation.branches.branch version 3 (this library reads 1 and 2)"),
]


@pytest.mark.parametrize(("edit", "field", "message"), BRANCH_EDITS, ids=[f for _, f, _ in BRANCH_EDITS])
def test_hand_edited_branch_json_is_refused_naming_the_field(tmp_path, edit, field, message):
    d = io.branch_to_dict(make_branch(6))
    edit(d)
    path = tmp_path / "branch.json"
    path.write_text(json.dumps(d, indent=1))
    refused(io.load_branch_json, path, field, message)
    with pytest.raises(FileFormatError, match="^" + re.escape(f"branch record: {field}: ") + ".*" + re.escape(message)):
        io.branch_from_dict(d)


def test_what_json_cannot_say_is_refused_naming_the_field(tmp_path):
    path = tmp_path / "branch.json"
    d = io.branch_to_dict(make_branch(6))
    d["points"][5]["period"] = math.nan  # json.dumps writes the non-standard NaN
    path.write_text(json.dumps(d))
    refused(io.load_branch_json, path, "points[5].period", 'NaN is not JSON: a non-finite number is written "nan"')
    text = json.dumps(io.branch_to_dict(make_branch(6)))
    path.write_text(text.replace('"amplitude": ', '"amplitude": 1e400, "x": ', 1))
    refused(io.load_branch_json, path, "special_points[0].amplitude", "1e400 is too large for a double")
    path.write_text(text.replace('"step": ', '"step": 1' + "0" * 400 + ', "y": ', 1))
    refused(io.load_branch_json, path, "points[0].step", "is too large for a double")
    path.write_text(text.replace('"stable": true', '"stable": true, "stable": false', 1))
    refused(io.load_branch_json, path, "points[0]", 'the key "stable" appears more than once')
    path.write_text("[1, 2]")
    refused(io.load_branch_json, path, "(top level)", "expected an object")
    path.write_bytes(b"\x89PNG\r\n\x1a\n\0\0")
    refused(io.load_branch_json, path, "", "not a UTF-8 text file")
    path.write_text("  \n")
    refused(io.load_branch_json, path, "", "the file is empty")
    path.write_text(io.csv_metadata_path(io.save_branch_csv(make_branch(3), tmp_path / "b.csv")).read_text())
    refused(io.load_branch_json, path, "points", "missing", "load_branch_csv")


def test_hand_edited_diagram_and_records_are_refused_naming_the_field(tmp_path):
    (path,) = WRITERS["diagram_json"](tmp_path)
    d = json.loads(path.read_text())
    d["branches"][1]["points"][0]["stable"] = "true"
    path.write_text(json.dumps(d))
    refused(io.load_diagram_json, path, "branches[1].points[0].stable", 'got "true"')
    d["branches"] = {}
    path.write_text(json.dumps(d))
    refused(io.load_diagram_json, path, "branches", "expected a list")
    path.write_text(json.dumps({"format": "saltation.branches.branch", "version": 1}))
    refused(io.load_diagram_json, path, "format", "expected format 'saltation.apps.diagram'")

    (path,) = WRITERS["special_points"](tmp_path)
    records = json.loads(path.read_text())
    for edit, field, message in [
        (_set(1, "kind", "nope"), "[1].kind", 'got "nope"'),
        (_set(0, "value", "0.5"), "[0].value", "expected a number"),
        (_del(2, "model"), "[2].model", "missing"),
        (_set(1, "multipliers_plus", [[1.0]]), "[1].multipliers_plus[0]", "expected a complex number"),
        (_set(0, "bracket", [0.1, 0.2, 0.3]), "[0].bracket", "expected 2 entries, got 3"),
    ]:
        edited = json.loads(json.dumps(records))
        edit(edited)
        path.write_text(json.dumps(edited))
        refused(io.load_special_points_json, path, field, message)
    path.write_text(json.dumps({"records": records}))
    refused(io.load_special_points_json, path, "(top level)", "expected a list")


SWEEP_EDITS = [
    (_set("counts", [2, 0]), "counts", "expected 3 entries, got 2"),
    (_set("counts", 1, -1), "counts[1]", "at least 0"),
    (_set("counts", 1, 1), "parameter_points", "expected 4 entries, got 3"),
    (_set("states", 1, [0.5]), "states[1]", "expected 2 entries, got 1"),
    (_set("states", [[0.0, 0.0]]), "states", "expected 3 entries, got 1"),
    (_set("parameter_points", 2, 0.6), "parameter_points[2]", "by the counts it is a point of the value 0.7"),
    (_set("values", 0, "nan"), "values[0]", "expected a finite number"),
    (_set("section", "poincaré"), "section", 'expected one of "poincare", "maxima"'),
    (_set("start", "sideways"), "start", 'expected one of "previous", "own", got "sideways"'),
    (_set("failures", 0, ["x"]), "failures[0]", "expected 2 entries, got 1"),
    (_set("failures", 0, 1, 7), "failures[0][1]", "expected a string"),
    (_set("state_names", []), "state_names", "expected at least one state name"),
    (_set("settings", []), "settings", "expected an object"),
    (_del("model"), "model", "missing"),
    (_set("format", "saltation.period_map"), "format", "not a saltation.sweep record"),
    (_set("version", 2), "version", "unsupported saltation.sweep version 2"),
]


@pytest.mark.parametrize(("edit", "field", "message"), SWEEP_EDITS, ids=[f for _, f, _ in SWEEP_EDITS])
def test_hand_edited_sweep_is_refused_naming_the_field(tmp_path, edit, field, message):
    path = make_sweep().save(tmp_path / "sweep.json")
    d = json.loads(path.read_text())
    edit(d)
    path.write_text(json.dumps(d))
    refused(SweepResult.load, path, field, message)


MAP_EDITS = [
    (_set("periods", 1, [1, 2]), "periods[1]", "expected 3 entries, got 2"),
    (_set("periods", [[1, 2, 0]]), "periods", "expected 2 entries, got 1"),
    (_set("periods", 0, 1, 17), "periods[0][1]", "expected an integer from -1 to 16, got 17"),
    (_set("periods", 0, 1, 2.0), "periods[0][1]", "expected an integer, got 2.0"),
    (_set("max_period", 0), "max_period", "at least 1"),
    (_set("values2", [0.5]), "periods", "expected 1 entries, got 2"),
    (_set("failures", 0, [0.1, "x"]), "failures[0]", "expected 3 entries, got 2"),
    (_set("failures", 0, 0, "x"), "failures[0][0]", "expected a number"),
    (_del("settings"), "settings", "missing"),
    (_set("parameter2", None), "parameter2", "expected a string"),
]


@pytest.mark.parametrize(("edit", "field", "message"), MAP_EDITS, ids=[f for _, f, _ in MAP_EDITS])
def test_hand_edited_period_map_is_refused_naming_the_field(tmp_path, edit, field, message):
    path = make_map().save(tmp_path / "map.json")
    d = json.loads(path.read_text())
    edit(d)
    path.write_text(json.dumps(d))
    refused(PeriodMap.load, path, field, message)


def test_sweep_files_may_hold_what_their_writer_wrote(tmp_path):
    """Sweep and map files are written allowing NaN (in free-form settings): such a file reads back."""
    sweep = dataclasses.replace(make_sweep(), settings={"t0": math.nan, "x0": [math.inf, 0.0]})
    back = SweepResult.load(sweep.save(tmp_path / "s.json"))
    assert "NaN" in (tmp_path / "s.json").read_text()
    assert math.isnan(back.settings["t0"]) and back.settings["x0"] == [math.inf, 0.0]
    assert SweepResult.from_dict(sweep.to_dict()).settings["x0"] == [math.inf, 0.0]


def _edit_csv(path: Path, edit) -> None:
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    edit(rows)
    with path.open("w", newline="") as fh:
        csv.writer(fh).writerows(rows)


def _cell(row: int, column: str, value: str):
    def edit(rows):
        rows[row][rows[0].index(column)] = value

    return edit


def _drop_column(column: str):
    def edit(rows):
        j = rows[0].index(column)
        for r in rows:
            del r[j]

    return edit


CSV_EDITS = [
    (_cell(3, "stable", "yes"), "line 4 (point 2), column stable", "expected true or false, got 'yes'"),
    (_cell(3, "v_dr", "abc"), "line 4 (point 2), column v_dr", "expected a number"),
    (_cell(3, "v_dr", "nan"), "line 4 (point 2), column v_dr", "expected a finite number, got 'nan'"),
    (_cell(5, "v", ""), "line 6 (point 4), column v", "expected a number"),
    (_cell(5, "multiplier2_abs", "big"), "line 6 (point 4), column multiplier2_abs", "expected a number"),
    (_cell(2, "iterations", "1.5"), "line 3 (point 1), column iterations", "expected a non-negative integer"),
    (_cell(2, "iterations", "-2"), "line 3 (point 1), column iterations", "expected a non-negative integer"),
    (lambda rows: rows[4].pop(), "line 5 (point 3)", "has 15 fields; the header has 16"),
    (lambda rows: rows[4].append("1.0"), "line 5 (point 3)", "has 17 fields; the header has 16"),
    (_drop_column("step"), "line 1 (header)", "missing the column 'step'"),
    (_drop_column("multiplier2_im"), "line 1 (header)", "missing the column 'multiplier2_im'"),
    (lambda rows: rows[0].__setitem__(rows[0].index("v"), "w"), "line 1 (header)", "unexpected column 'w'"),
    (lambda rows: rows[0].__setitem__(rows[0].index("step"), "period"), "line 1 (header)",
     "the column 'period' appears twice"),
    (lambda rows: [r.append("extra") for r in rows], "line 1 (header)", "unexpected column 'extra'"),
]


@pytest.mark.parametrize(("edit", "field", "message"), CSV_EDITS, ids=[f"{f}: {m}" for _, f, m in CSV_EDITS])
def test_hand_edited_csv_is_refused_naming_the_line_and_column(tmp_path, edit, field, message):
    path = io.save_branch_csv(make_branch(6), tmp_path / "branch.csv")
    _edit_csv(path, edit)
    refused(io.load_branch_csv, path, field, message)


def test_a_side_file_from_another_save_is_refused(tmp_path):
    path = io.save_branch_csv(make_branch(6), tmp_path / "branch.csv")
    meta = io.csv_metadata_path(path)
    d = json.loads(meta.read_text())
    d["n_points"] = 30
    meta.write_text(json.dumps(d))
    refused(io.load_branch_csv, path, "", "has 6 rows of points; its side file", "records 30")
    d["n_points"] = "6"
    meta.write_text(json.dumps(d))
    with pytest.raises(FileFormatError, match=rf"^{meta}: n_points: expected an integer"):
        io.load_branch_csv(path)
    d["n_points"], d["kind"] = 6, "cycle"
    meta.write_text(json.dumps(d))
    with pytest.raises(FileFormatError, match=rf"^{meta}: kind: expected one of"):
        io.load_branch_csv(path)
    del d["n_points"]  # a side file of the previous version: no count, no check
    d["kind"] = "periodic"
    meta.write_text(json.dumps(d))
    assert len(io.load_branch_csv(path)) == 6


# ---------------------------------------------------------------------------------------------
# the command line
# ---------------------------------------------------------------------------------------------

def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


COMMANDS = {
    "continue": ["continue", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.8", "--no-progress"],
    "sweep": ["sweep", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.7", "--num", "2"],
    "map": ["sweep", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.7", "--num", "2", "--param2", "f0",
            "--from2", "0.1", "--to2", "0.2", "--num2", "2"],
    "locus": ["locus", "trilinear", "--kind", "fold", "--param", "omega", "--range", "0.6,0.8", "--param2", "f0",
              "--range2", "0.1,0.3", "--no-progress"],
    "paper": ["paper", "--no-progress"],
}


@pytest.fixture
def no_computation(monkeypatch):
    """Any computation fails the test: a bad --out must be refused before it."""
    from saltation.apps import paper

    def computed(*args, **kwargs):
        raise AssertionError("computed before checking --out")

    monkeypatch.setattr(cli.models, "make_flow", computed)
    monkeypatch.setattr(paper, "compute", computed)


@pytest.mark.parametrize("command", list(COMMANDS))
def test_an_out_that_is_a_file_is_bad_usage_before_computing(tmp_path, capsys, command, no_computation):
    afile = tmp_path / "results"
    afile.write_text("not a folder")
    code, out, err = _run(capsys, *COMMANDS[command], "--out", str(afile))
    assert (code, out) == (2, "")
    assert err == f"saltation: error: --out {str(afile)!r} is a file, not a folder\n"
    code, out, err = _run(capsys, *COMMANDS[command], "--out", str(afile / "sub"))
    assert (code, out) == (2, "")
    assert err.startswith(f"saltation: error: --out {str(afile / 'sub')!r}: cannot create the folder: a file is in "
                          "the way") and err.count("\n") == 1
    assert afile.read_text() == "not a folder"


def test_an_out_that_cannot_be_created_or_written_is_bad_usage(tmp_path, capsys, monkeypatch, no_computation):
    """As root, permissions do not stop writes: a read-only file system and a refused test file are simulated."""
    real_mkdir = Path.mkdir

    def read_only(self, *args, **kwargs):
        if str(self).startswith(str(tmp_path)):
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(self))
        return real_mkdir(self, *args, **kwargs)

    monkeypatch.setattr(Path, "mkdir", read_only)
    code, out, err = _run(capsys, *COMMANDS["continue"], "--out", str(tmp_path / "new"))
    assert (code, out) == (2, "")
    assert err == f"saltation: error: --out {str(tmp_path / 'new')!r}: cannot create the folder: Read-only file system\n"
    monkeypatch.setattr(Path, "mkdir", real_mkdir)

    def refuse(*args, **kwargs):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))

    monkeypatch.setattr(cli.tempfile, "mkstemp", refuse)
    code, out, err = _run(capsys, *COMMANDS["sweep"], "--out", str(tmp_path))
    assert (code, out) == (2, "")
    assert err == f"saltation: error: --out {str(tmp_path)!r}: cannot write in the folder: Permission denied\n"


def test_a_full_disk_while_writing_is_one_line_and_the_old_files_stay(tmp_path, capsys, full_disk, trilinear_flow):
    """The folder is created first; the computation runs; the first file fails (ENOSPC): one line naming the file,
    exit status 1, no traceback, the old file as it was, no temporary file; --debug raises the OSError."""
    out_dir = tmp_path / "new" / "out"
    full_disk["only"] = "\0"
    code, _, err = _run(capsys, *COMMANDS["continue"], "--ds-max", "0.05", "--out", str(out_dir))
    assert code == 0, err
    old = {p: p.read_bytes() for p in out_dir.iterdir()}
    assert len(old) == 6  # branch JSON, CSV and side file, special points, PNG, PDF
    full_disk["only"] = ""
    code, out, err = _run(capsys, *COMMANDS["continue"], "--ds-max", "0.05", "--out", str(out_dir))
    target = out_dir / "trilinear_omega_branch.json"
    assert (code, out) == (1, "")
    assert err == f"saltation: error: {target}: No space left on device\n"
    assert {p: p.read_bytes() for p in out_dir.iterdir()} == old
    with pytest.raises(OSError) as info:
        cli.main([*COMMANDS["continue"], "--ds-max", "0.05", "--out", str(out_dir), "--debug"])
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(target)
    assert leftovers(out_dir) == []


def test_a_broken_pipe_not_on_stdout_is_one_line(capsys, monkeypatch):
    """A BrokenPipeError while standard output is still open (here: captured) is a failure like any OS error."""

    def broken(args):
        raise BrokenPipeError(errno.EPIPE, os.strerror(errno.EPIPE))

    monkeypatch.setattr(cli, "cmd_orbit", broken)
    code, out, err = _run(capsys, "orbit", "trilinear")
    assert (code, out, err) == (1, "", "saltation: error: Broken pipe\n")


def test_a_closed_stdout_exits_quietly(trilinear_flow):
    """``saltation orbit ... | head -0``: the reader has gone before the orbit is printed; no message, no
    traceback, exit status 141 (128 + SIGPIPE, as a shell reports a process killed by SIGPIPE)."""
    proc = subprocess.Popen([sys.executable, "-m", "saltation", "orbit", "trilinear", "--x0", "0.3,0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # long before the orbit is found and printed
    err = proc.stderr.read().decode()
    assert (proc.wait(timeout=300), err) == (141, "")


def test_sweep_and_map_files_of_the_earlier_format_key_are_read(tmp_path):
    """Files written before the common format convention hold ``"format": "saltation.sweep/1"`` (or
    ``"saltation.period_map/1"``) and no ``"version"``: they read back to the same record."""
    sweep = make_sweep()
    d = sweep.to_dict()
    assert (d["format"], d["version"]) == ("saltation.sweep", 1)
    del d["version"]
    d["format"] = "saltation.sweep/1"
    again = SweepResult.from_dict(d)
    assert again.to_dict() == sweep.to_dict()
