"""Files and messages that must not mislead.

* Every ``"format"`` string the library ever wrote (:data:`saltation.output.io.FORMAT_NAMES`) reads
  as its current format: the files of ``tests/data/old_formats`` (written by earlier releases, see
  its README) load to the branch, diagram, CSV, sweep and period map they were written from.
* Saving onto something that is not a regular file (a named pipe, a device) is refused, naming the
  path and what it is, and leaves it in place.
* Messages say what is true: a state too large for the integration, an infinite value in a mode,
  an unencodable field of a branch, an expression too deep to simplify.
"""

from __future__ import annotations

import dataclasses
import json
import os
import stat
import warnings
from pathlib import Path

import numpy as np
import pytest

from saltation.apps.sweeps import PeriodMap, SweepResult, SweepStart
from saltation.branches.branch import BranchKind, SpecialPointKind, StopReason
from saltation.output import io
from saltation.output.io import FileFormatError

OLD = Path(__file__).parents[1] / "data" / "old_formats"
RELEASES = sorted(p.name for p in OLD.iterdir() if p.is_dir())


# ---------------------------------------------------------------------------------------------
# files of earlier releases
# ---------------------------------------------------------------------------------------------

def check_old_branch(b, label: str = "main", n: int = 3) -> None:
    """``b`` is the branch ``write_old_formats.py`` wrote (every field compared with what it set)."""
    assert (b.model, b.parameter_name, b.kind, b.label, b.backward, b.autonomous) == (
        "trilinear", "omega", BranchKind.PERIODIC, label, False, False)
    assert b.stop_reason is StopReason.MAX_POINTS
    assert b.fixed_parameters == {"zeta": 0.05, "g": 2.0}
    assert len(b.points) == n
    for k, p in enumerate(b.points):
        lam = 1.0 + 0.25 * k
        assert (p.parameter, p.period, p.amplitude, p.half_peak_to_peak) == (lam, 2 * np.pi / lam, 1.5 + k / 4,
                                                                             1.25 + k / 4)
        assert np.array_equal(p.state, [0.5 + k / 8, -0.25])
        assert np.array_equal(p.multipliers, [0.5 + 0.25j, 0.5 - 0.25j])
        assert (p.stable, p.event_labels, p.step, p.iterations) == (True, ("hit stop", "leave stop"), 0.125, 3)
    (sp,) = b.special_points
    assert (sp.kind, sp.parameter, tuple(sp.bracket), sp.accuracy, sp.index, sp.period, sp.amplitude, sp.note) == (
        SpecialPointKind.FOLD, 1.375, (1.25, 1.5), 0.25, 1, 4.5, 1.75, "smooth fold")
    assert np.array_equal(sp.state, [0.625, -0.25]) and np.array_equal(sp.multipliers, [1.0, 0.25])


def written_format(path: Path) -> str:
    return json.loads(path.read_text())["format"]


@pytest.mark.parametrize("release", RELEASES)
def test_branch_diagram_and_csv_files_of_earlier_releases_read(release):
    """A branch JSON (``"saltation.branch"``), a diagram (``"saltation.diagram"``, whose branches say
    ``"saltation.branch"``) and a CSV with its side file (``"saltation.branch"``) of each earlier release
    read back to the branch they were written from."""
    folder = OLD / release
    assert written_format(folder / "branch.json") == "saltation.branch"
    assert written_format(folder / "branch.meta.json") == "saltation.branch"
    assert written_format(folder / "diagram.json") == "saltation.diagram"
    check_old_branch(io.load_branch_json(folder / "branch.json"))
    main, second = io.load_diagram_json(folder / "diagram.json")
    check_old_branch(main)
    check_old_branch(second, "second", 2)
    check_old_branch(io.load_branch_csv(folder / "branch.csv"))


@pytest.mark.parametrize("release", [r for r in RELEASES if (OLD / r / "sweep.json").exists()])
def test_sweep_and_period_map_files_of_earlier_releases_read(release):
    """A sweep (``"saltation.sweep/1"``) and a period map (``"saltation.period_map/1"``), with no
    ``"version"`` key, read back to what was written (without ``start``: each value from the previous)."""
    folder = OLD / release
    assert written_format(folder / "sweep.json") == "saltation.sweep/1"
    assert written_format(folder / "period_map.json") == "saltation.period_map/1"
    s = SweepResult.load(folder / "sweep.json")
    assert (s.model, s.parameter_name, s.section, s.state_names, s.start) == (
        "trilinear", "omega", "poincare", ("x", "v"), SweepStart.PREVIOUS)
    assert s.values.tolist() == [1.0, 1.5] and s.counts.tolist() == [2, 1]
    assert s.parameter_points.tolist() == [1.0, 1.0, 1.5]
    assert s.states.tolist() == [[0.5, -0.25], [0.75, 0.125], [0.625, 0.0]]
    assert s.settings == {"periods": 4, "transient": 2}
    m = PeriodMap.load(folder / "period_map.json")
    assert (m.model, m.parameter_name, m.parameter2_name, m.max_period, m.start) == (
        "trilinear", "omega", "zeta", 8, SweepStart.PREVIOUS)
    assert m.values.tolist() == [1.0, 1.5] and m.values2.tolist() == [0.0, 0.05, 0.1]
    assert m.periods.tolist() == [[1, 2], [1, -1], [4, 1]]
    assert m.failures == ((1.5, 0.05, "no convergence"),)


def test_every_format_string_ever_written_is_in_the_table():
    """The table holds the four current formats (each its own, with ``"version"``) and every name the
    fixtures of earlier releases hold, each mapped to the current format of that kind of file."""
    current = {io.BRANCH_FORMAT, io.DIAGRAM_FORMAT, io.SWEEP_FORMAT, io.PERIOD_MAP_FORMAT}
    assert {name: io.FORMAT_NAMES[name] for name in current} == {name: (name, True) for name in current}
    kinds = {"branch.json": io.BRANCH_FORMAT, "branch.meta.json": io.BRANCH_FORMAT, "diagram.json": io.DIAGRAM_FORMAT,
             "sweep.json": io.SWEEP_FORMAT, "period_map.json": io.PERIOD_MAP_FORMAT}
    seen = set()
    for path in OLD.glob("*/*.json"):
        name = written_format(path)
        seen.add(name)
        assert io.FORMAT_NAMES[name][0] == kinds[path.name], path
        assert io.FORMAT_NAMES[name][1] == ("version" in json.loads(path.read_text())), path
    assert seen | current == set(io.FORMAT_NAMES)


def test_a_file_of_another_kind_is_refused_naming_both(tmp_path):
    """An old diagram given to the branch loader, or an old branch to the diagram loader, is refused as
    what it is; an unknown name is refused."""
    with pytest.raises(FileFormatError) as info:
        io.load_branch_json(OLD / "2026-11-25" / "diagram.json")
    assert info.value.field == "format"
    assert "found \"saltation.diagram\" (a saltation.apps.diagram file of an earlier release)" in str(info.value)
    assert "earlier releases wrote 'saltation.branch'" in str(info.value)
    with pytest.raises(FileFormatError, match="not a saltation.apps.diagram record"):
        io.load_diagram_json(OLD / "2026-11-25" / "branch.json")
    d = json.loads((OLD / "2026-11-25" / "branch.json").read_text())
    for bad in ("saltation.branch/1", "saltation.sweep"):
        d["format"] = bad
        (tmp_path / "b.json").write_text(json.dumps(d))
        with pytest.raises(FileFormatError, match="not a saltation.branches.branch record"):
            io.load_branch_json(tmp_path / "b.json")


# ---------------------------------------------------------------------------------------------
# saving onto something that is not a regular file
# ---------------------------------------------------------------------------------------------

def old_branch():
    return io.load_branch_json(OLD / "2026-11-25" / "branch.json")


def refused_onto(save, target: Path, kind: str) -> None:
    """``save(target)`` raises FileExistsError naming ``target`` and ``kind``; ``target`` keeps its kind and
    no other file appears in its folder."""
    mode = os.lstat(target).st_mode
    before = sorted(os.listdir(target.parent))
    with pytest.raises(FileExistsError) as info:
        save(target)
    assert info.value.filename == str(target)
    assert f"is {kind}, not a regular file" in str(info.value) and str(target) in str(info.value)
    assert os.lstat(target).st_mode == mode
    assert sorted(os.listdir(target.parent)) == before


def test_saving_onto_a_named_pipe_is_refused_and_leaves_it(tmp_path):
    """``save_branch_json`` onto a FIFO used to rename a regular file over it: it is refused, naming the
    path and what it is, and the pipe stays a pipe (no temporary file is left either)."""
    pipe = tmp_path / "branch.json"
    os.mkfifo(pipe)
    b = old_branch()
    refused_onto(lambda p: io.save_branch_json(b, p), pipe, "a named pipe (FIFO)")
    assert stat.S_ISFIFO(os.lstat(pipe).st_mode)
    # through a symbolic link, and as the side file of a CSV (then neither file of the pair is written)
    (tmp_path / "link.json").symlink_to(pipe)
    with pytest.raises(FileExistsError, match="named pipe"):
        io.save_branch_json(b, tmp_path / "link.json")
    assert stat.S_ISFIFO(os.lstat(pipe).st_mode) and (tmp_path / "link.json").is_symlink()
    os.mkfifo(tmp_path / "curve.meta.json")
    with pytest.raises(FileExistsError, match="curve.meta.json"):
        io.save_branch_csv(b, tmp_path / "curve.csv")
    assert not (tmp_path / "curve.csv").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["branch.json", "curve.meta.json", "link.json"]


def test_saving_onto_a_device_or_a_folder_is_refused(tmp_path):
    """A copy of ``/dev/full`` (a character device, where ``mknod`` is permitted) and a folder are refused
    by every writer; a regular file is still replaced."""
    folder = tmp_path / "out.json"
    folder.mkdir()
    refused_onto(lambda p: io.write_json({"a": 1}, p), folder, "a folder")
    device = tmp_path / "full"
    try:
        os.mknod(device, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
    except (PermissionError, AttributeError):
        pass  # not root: the FIFO above stands for every special file
    else:
        refused_onto(lambda p: io.save_branch_json(old_branch(), p), device, "a character device")
        assert stat.S_ISCHR(os.lstat(device).st_mode)
    plain = tmp_path / "plain.json"
    plain.write_text("old\n")
    io.save_branch_json(old_branch(), plain)
    check_old_branch(io.load_branch_json(plain))


# ---------------------------------------------------------------------------------------------
# messages that say what is true
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize(("change", "field", "problem"), [
    (lambda b: setattr(b, "label", object()), "label", "expected a string, got object <object object at"),
    (lambda b: setattr(b, "label", b"main"), "label", "expected a string, got bytes b'main'"),
    (lambda b: b.special_points.__setitem__(0, dataclasses.replace(b.special_points[0], note=3)),
     "special_points[0].note", "expected a string, got int 3"),
    (lambda b: b.points.__setitem__(2, dataclasses.replace(b.points[2], event_labels=("hit stop", None))),
     "points[2].event_labels[1]", "expected a string, got NoneType None"),
    (lambda b: b.points.__setitem__(1, dataclasses.replace(b.points[1], parameter="x")),
     "points[1].parameter", "str 'x' (ValueError: could not convert string to float"),
])
def test_a_field_that_cannot_be_written_is_named(tmp_path, change, field, problem):
    """A branch holding a value its file cannot hold (a label that is an object or bytes, ...) is refused
    by the JSON and CSV writers with UnwritableFieldError (a TypeError) naming the field, before any file
    is written (an object's label was written as its repr before)."""
    b = old_branch()
    change(b)
    for save, name in ((io.save_branch_json, "b.json"), (io.save_branch_csv, "b.csv"),
                       (lambda b, p: io.save_diagram_json([b], p), "d.json")):
        with pytest.raises(io.UnwritableFieldError) as info:
            save(b, tmp_path / name)
        assert isinstance(info.value, TypeError)
        assert info.value.field.endswith(field) and problem in info.value.problem
        assert str(info.value).startswith(f"cannot write field {info.value.field}: ")
    assert list(tmp_path.iterdir()) == []


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    """``saltation ARGV`` in this process: exit status, standard output and error."""
    from saltation.apps import cli

    try:
        status = cli.main(list(argv))
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def test_a_finite_start_too_large_for_the_integration_is_said_so(capsys):
    """``--x0 1e308,1e308`` is finite: it is refused as bad usage (exit status 2) in one line saying that
    the field of its mode overflows there, with no RuntimeWarning (the check summed the state, which
    overflowed, and called it not finite); ``--x0 1e200,0``, whose residual's norm overflowed, converges."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        status, out, err = run_cli(capsys, "orbit", "trilinear", "--x0", "1e308,1e308")
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and "not finite" not in err.split("field")[0], err
    assert "--x0 '1e308,1e308': the vector field of mode 'contact_1' is not finite at this state" in err
    assert "it overflows, the state is too large for the integration" in err
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        status, out, err = run_cli(capsys, "orbit", "trilinear", "--x0", "1e200,0")
    assert (status, err) == (0, "") and "period       5.235987756" in out


def test_a_huge_finite_state_is_finite_for_the_flow(trilinear_flow):
    """``Flow.run`` from a finite state whose sum overflows says what fails (the field of its mode), not
    that the state is not finite, and no RuntimeWarning escapes."""
    from saltation.errors import NonFiniteError

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(NonFiniteError) as info:
            trilinear_flow.run([1e308, 1e308], 0.0, 1.0, trilinear_flow.parameters())
    assert "the vector field of mode 'contact_1' returned NaN or infinity at t = 0" in str(info.value)
    assert "initial state" not in str(info.value)


@pytest.mark.parametrize(("expression", "says"), [
    ("oo", "'oo' is not finite: it is infinite"), ("-oo", "'-oo' is not finite: it is infinite"), ("x*oo", "'x*oo' is not finite: it is infinite"),
    ("zoo", "'zoo' is not finite: it is infinite"), ("nan", "'nan' is not finite: it is not a number (NaN)"),
    ("2 + 3*I", "'2 + 3*I' is complex-valued"),
    ("sin(-Pow(2.5, 1e308))", "sympy cannot evaluate expression 'sin(-Pow(2.5, 1e308))' (RecursionError"),
])
def test_a_field_expression_is_refused_for_what_it_is(expression, says):
    """An infinite field (``oo``) was refused as complex-valued, and ``sin(-Pow(2.5, 1e308))`` raised a
    RecursionError: each is a ModelError naming the mode and the expression, saying what is wrong."""
    from saltation import Crossing, Mode, ModelError, PiecewiseSystem, Transition

    with pytest.raises(ModelError) as info:
        PiecewiseSystem(name="m", states=["x", "v"], parameters={"a": 1.0},
                        modes=[Mode("m1", ["v", expression]), Mode("m2", ["v", "-x"])], surfaces={"wall": "x - a"},
                        transitions=[Transition("m1", "wall", Crossing.RISING, "m2"),
                                     Transition("m2", "wall", Crossing.FALLING, "m1")])
    assert str(info.value).startswith("mode 'm1', field component 1: ")
    assert says in str(info.value)


@pytest.mark.parametrize("command", [
    ["continue", "trilinear", "--param", "omega", "--from", "1.0", "--to", "1.1", "--no-progress"],
    ["locus", "trilinear", "--kind", "fold", "--param", "omega", "--range", "1.0,1.3", "--param2", "f0",
     "--range2", "0.1,0.3", "--no-progress"],
    ["lyapunov", "trilinear", "--time", "100"],
    ["sweep", "trilinear", "--param", "omega", "--from", "1.0", "--to", "1.1", "--num", "2", "--workers", "1"],
], ids=["continue", "locus", "lyapunov", "sweep"])
def test_a_start_too_large_for_the_integration_is_bad_usage_in_every_command(capsys, command, tmp_path):
    """As for ``orbit``: a finite ``--x0`` whose field overflows is bad usage (exit 2), in one line naming the mode."""
    extra = ["--out", str(tmp_path)] if command[0] in ("continue", "sweep") else []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        status, out, err = run_cli(capsys, *command, *extra, "--x0", "1e308,1e308")
    assert status == 2 and out == ""
    assert err.count("\n") == 1
    assert "--x0 '1e308,1e308': the vector field of mode 'contact_1' is not finite at this state" in err
