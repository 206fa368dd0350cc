"""The estimate of a first build (:mod:`saltation.engine.buildtime`): from the builds recorded in the cache
folder, else from a test compile, else none; a record that cannot be read is ignored; the record is
written whole.  Nothing here compiles the engine or a model (the records are written by hand), and no
test times anything: the estimates are checked against arithmetic on the numbers given."""

from __future__ import annotations

import io
import json
import os
import time
from pathlib import Path

import pytest

from saltation.engine import buildtime, codegen
from saltation.engine.buildtime import (
    PARALLEL_SCALE,
    PROBE_SECONDS,
    RECORD_FILE,
    BuildEstimate,
    estimate_build,
    record_build,
    wall_seconds,
)

NUMBA = buildtime._numba_version()
CORES = buildtime._cores()


@pytest.fixture
def free_cores(monkeypatch):
    """Two cores for every build, and no test compile unless a test provides one."""
    monkeypatch.setattr(buildtime, "expected_cores", lambda processes: 2.0)
    monkeypatch.setattr(buildtime, "probe_seconds", lambda: pytest.fail("the test compile ran"))


def write_records(folder, builds, **top):
    data = {"format": "saltation build times", "version": 1, "builds": builds} | top
    (folder / RECORD_FILE).write_text(json.dumps(data))


def build(kind="engine 2", seconds=60.0, work=(15.0, 15.0), cores=1.0, numba=NUMBA, machine=CORES, cpu=None):
    """A recorded build: its scale is ``seconds / wall_seconds(work, cores)`` (2 by default)."""
    return {"kind": kind, "seconds": seconds, "cpu": cpu, "work": list(work), "cores": cores, "numba": numba,
            "machine_cores": machine}


# -- from the records ----------------------------------------------------------------------------------


def test_the_estimate_is_the_last_builds_of_its_kind_scaled_to_its_work(tmp_path, free_cores):
    """Scale: the median of the last three builds of the kind (the time each took over the time its work
    takes on the cores it expected); the others and the older ones do not count."""
    write_records(tmp_path, [build(seconds=300.0), build(seconds=90.0), build(seconds=60.0, cpu=500.0),
                             build(seconds=45.0), build("model functions", seconds=1.0, work=(10.0,))])
    est = estimate_build(tmp_path, "engine 2", [22.0, 18.0, 0.0])
    assert (est.work, est.cores) == ((22.0, 18.0), 2.0)
    assert est.seconds == pytest.approx(2.0 * 22.0)  # the scales 3, 2 and 1.5: their median; a core each
    assert est.source == "builds of this kind"


def test_the_same_build_again_is_estimated_at_the_time_it_took(tmp_path, free_cores):
    write_records(tmp_path, [build(seconds=55.0, work=(26.0, 24.9), cores=2.0)])
    assert estimate_build(tmp_path, "engine 2", (26.0, 24.9)).seconds == pytest.approx(55.0)


def test_a_kind_never_built_here_is_scaled_from_the_other_builds(tmp_path, free_cores, monkeypatch):
    """Of the same number of processes: the load weighs differently on one process and on two."""
    write_records(tmp_path, [build("engine 2", seconds=75.0, work=(12.5, 12.5)), build("engine 3", seconds=60.0),
                             build("model functions", seconds=40.0, work=(4.0,))])
    monkeypatch.setattr(buildtime, "expected_cores", lambda processes: 1.0)
    est = estimate_build(tmp_path, "engine 5+", (15.0, 15.0))
    assert est.seconds == pytest.approx(2.5 * 30.0)  # the median of 3 and 2 (not 10); one core for both processes
    assert est.source == "other builds"
    assert est.text == "about 75 s"
    assert estimate_build(tmp_path, "engine 5+", (4.0,)).seconds == pytest.approx(40.0)  # one process: scale 10
    write_records(tmp_path, [build("engine 2", seconds=75.0, work=(12.5, 12.5))])
    monkeypatch.setattr(buildtime, "probe_seconds", lambda: 3 * PROBE_SECONDS)
    est = estimate_build(tmp_path, "model functions", (6.0,))  # builds of two processes only: the test compile
    assert (est.seconds, est.source) == (pytest.approx(18.0), "a test compile")


def test_builds_with_another_numba_or_other_cores_do_not_count(tmp_path, free_cores, monkeypatch):
    write_records(tmp_path, [build(numba="0.0.1"), build(machine=CORES + 7)])
    monkeypatch.setattr(buildtime, "probe_seconds", lambda: None)
    est = estimate_build(tmp_path, "engine 2", (22.0, 18.0))
    assert est.seconds is None and est.source == "unknown"


# -- with nothing recorded ------------------------------------------------------------------------------


def test_with_nothing_recorded_a_test_compile_gives_the_scale(tmp_path, free_cores, monkeypatch):
    monkeypatch.setattr(buildtime, "probe_seconds", lambda: 2 * PROBE_SECONDS)  # a machine twice as slow
    est = estimate_build(tmp_path, "engine 2", (40.0,))
    assert est.seconds == pytest.approx(80.0)
    assert est.source == "a test compile"
    est = estimate_build(tmp_path, "engine 2", (22.0, 18.0))  # two processes: a larger scale
    assert est.seconds == pytest.approx(2 * PARALLEL_SCALE * 22.0)
    assert not (tmp_path / RECORD_FILE).exists()  # an estimate writes nothing


def test_without_records_or_a_test_compile_the_estimate_is_unknown_and_says_nothing(tmp_path, free_cores, monkeypatch):
    est = estimate_build(tmp_path, "model functions", (4.0,), calibrate=False)  # (the probe is not compiled)
    assert (est.seconds, est.source, est.text) == (None, "unknown", "")
    monkeypatch.setattr(buildtime, "probe_seconds", lambda: None)  # numba cannot compile the probe
    assert estimate_build(tmp_path, "engine 2", (22.0, 18.0)).text == ""


def test_the_test_compile_compiles():
    """The probe compiles here and takes some time (how much is not checked: no timed tests)."""
    assert buildtime.probe_seconds() > 0


# -- records that cannot be read -----------------------------------------------------------------------


@pytest.mark.parametrize("content", [
    b"\x00\xff\xfe garbage",
    b'{"format": "saltation build times", "version": 1, "builds": [{"kind": "engine 2", "sec',  # cut short
    b"[1, 2, 3]",
    b'{"format": "another program", "version": 1, "builds": []}',
    b'{"format": "saltation build times", "version": 99, "builds": [{"kind": "engine 2"}]}',
    b'{"format": "saltation build times", "version": 1, "builds": {"engine 2": 60}}',
    b'{"format": "saltation build times", "version": 1, "builds": [7, null, {"kind": 2}, '
    + b", ".join(json.dumps(build(numba="0.0.1") | bad).encode() for bad in (
        {"seconds": "60"}, {"cpu": -1}, {"work": []}, {"work": [1, "2"]}, {"cores": True}, {"machine_cores": 2.5},
        {"kind": None})) + b"]}",
], ids=["bytes", "truncated", "list", "foreign", "other version", "not a list", "bad entries"])
def test_a_record_that_cannot_be_read_is_ignored_and_replaced(tmp_path, free_cores, monkeypatch, content):
    (tmp_path / RECORD_FILE).write_bytes(content)
    monkeypatch.setattr(buildtime, "probe_seconds", lambda: PROBE_SECONDS)
    est = estimate_build(tmp_path, "engine 2", (40.0,))
    assert est.source == "a test compile" and est.seconds == pytest.approx(40.0)
    record_build(tmp_path, est, 50.0, 60.0)
    data = json.loads((tmp_path / RECORD_FILE).read_text())
    assert [(b["kind"], b["seconds"], b["cpu"], b["work"]) for b in data["builds"]] == [("engine 2", 50.0, 60.0, [40.0])]
    assert estimate_build(tmp_path, "engine 2", (40.0,)).seconds == pytest.approx(50.0)


def test_a_record_in_a_folder_that_cannot_be_read_or_written_is_no_error(tmp_path, free_cores):
    missing = tmp_path / "a file, not a folder"
    missing.write_text("")
    record_build(missing, BuildEstimate("engine 2", (40.0,), 1.0, None, "unknown"), 50.0)
    assert estimate_build(missing, "engine 2", (40.0,), calibrate=False).seconds is None


# -- writing the record ---------------------------------------------------------------------------------


def test_the_record_is_written_whole_through_a_renamed_file(tmp_path, monkeypatch):
    est = BuildEstimate("engine 2", (22.0, 18.0), 1.5, 45.0, "a test compile")
    record_build(tmp_path, est, 50.0)
    before = (tmp_path / RECORD_FILE).read_bytes()
    renamed = []
    real_replace = os.replace

    def replace(src, dst):
        renamed.append((os.path.basename(src), os.path.basename(dst), json.loads(Path(src).read_text())))
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(buildtime.os, "replace", replace)
    record_build(tmp_path, est, 60.0)  # the rename fails: no error, the old record whole, no temporary file left
    assert (tmp_path / RECORD_FILE).read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [RECORD_FILE]
    (src, dst, written), = renamed
    assert dst == RECORD_FILE and src != RECORD_FILE and len(written["builds"]) == 2  # the whole new record
    monkeypatch.setattr(buildtime.os, "replace", real_replace)
    record_build(tmp_path, est, 60.0)
    entries = json.loads((tmp_path / RECORD_FILE).read_text())["builds"]
    assert [b["seconds"] for b in entries] == [50.0, 60.0]
    assert entries[-1] | {"when": None} == {"kind": "engine 2", "seconds": 60.0, "cpu": None, "work": [22.0, 18.0],
                                            "cores": 1.5, "estimate": 45.0, "source": "a test compile",
                                            "numba": NUMBA, "machine_cores": CORES, "when": None}


def test_the_record_keeps_the_newest_builds(tmp_path):
    est = BuildEstimate("model functions", (4.0,), 1.0, None, "unknown")
    for k in range(buildtime._KEEP + 5):
        record_build(tmp_path, est, 1.0 + k)
    entries = json.loads((tmp_path / RECORD_FILE).read_text())["builds"]
    assert [b["seconds"] for b in entries] == [1.0 + k for k in range(5, buildtime._KEEP + 5)]


def test_a_build_is_recorded_when_it_finishes_and_not_when_it_fails(tmp_path, monkeypatch):
    """:func:`~saltation.engine.codegen.building` records the build it was given the estimate of, once it
    is done; a build that raised, and one within another, are not recorded."""
    monkeypatch.setenv("SALTATION_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(codegen, "_ACTIVE", {})
    est = BuildEstimate("engine 2", (0.2, 0.1), 2.0, 50.0, "a test compile")
    with pytest.raises(RuntimeError), codegen.building("compiling", stream=io.StringIO(), estimate=est):
        time.sleep(0.01)
        raise RuntimeError("the compiler failed")
    assert not (tmp_path / RECORD_FILE).exists()
    log = io.StringIO()
    part = BuildEstimate("models", (1.0,), 1.0, None, "unknown")
    with codegen.building(f"compiling the integrator ({est.text})", stream=log, estimate=est), \
            codegen.building("compiling a part", stream=log, estimate=part):
        time.sleep(0.01)
    assert log.getvalue() == "saltation: compiling the integrator (about 50 s)\n"
    with codegen.building(None, stream=log, estimate=BuildEstimate("model functions", (0.1,), 1.0, None, "unknown")):
        time.sleep(0.01)  # a build not announced is recorded too
    assert log.getvalue() == "saltation: compiling the integrator (about 50 s)\n"
    entries = json.loads((tmp_path / RECORD_FILE).read_text())["builds"]
    assert [(b["kind"], b["estimate"]) for b in entries] == [("engine 2", 50.0), ("model functions", None)]


# -- the arithmetic -------------------------------------------------------------------------------------


def test_the_wall_time_of_processes_sharing_cores():
    assert wall_seconds((22.0, 18.0), 2) == 22.0  # a core each: the longest
    assert wall_seconds((22.0, 18.0), 1) == 40.0  # one core between them: the sum
    assert wall_seconds((22.0, 4.0), 1.5) == pytest.approx(4 / 0.75 + 18.0)  # three quarters each, then a whole one
    assert wall_seconds((10.0,), 0.5) == 20.0
    assert wall_seconds((), 2) == 0.0


def test_the_cores_expected_lie_between_a_guess_and_the_share_the_load_leaves(monkeypatch):
    """The geometric mean of a guess (halfway between the machine to itself and shared with a program as
    busy as the build) and of the share the load average leaves the build's processes."""
    monkeypatch.setattr(buildtime, "_cores", lambda: 2)
    monkeypatch.setattr(buildtime, "_load", lambda: 0.0)
    assert buildtime.expected_cores(2) == pytest.approx((2 ** 0.5 * 2) ** 0.5)
    assert buildtime.expected_cores(1) == 1.0 and buildtime.expected_cores(5) == pytest.approx((2 ** 0.5 * 2) ** 0.5)
    monkeypatch.setattr(buildtime, "_load", lambda: 2.0)  # two processes running besides: half of the two cores
    assert buildtime.expected_cores(2) == pytest.approx((2 ** 0.5 * 1) ** 0.5)
    assert buildtime.expected_cores(1) == pytest.approx((2 / 3) ** 0.5)
    monkeypatch.setattr(buildtime, "_load", lambda: None)  # (no load average: the guess alone)
    assert buildtime.expected_cores(2) == pytest.approx(2 ** 0.5)


@pytest.mark.parametrize("seconds, text", [(None, ""), (0.2, "about 1 s"), (7.4, "about 7 s"), (52.0, "about 50 s"),
                                           (53.0, "about 55 s"), (104.0, "about 100 s"), (200.0, "about 3 min")])
def test_the_estimate_as_a_message_says_it(seconds, text):
    assert BuildEstimate("engine 2", (1.0,), 1.0, seconds, "a test compile").text == text



def test_a_build_that_compiled_nothing_is_not_recorded(tmp_path):
    """A build done in a fiftieth of its work's time found everything compiled: it says nothing of the machine."""
    record_build(tmp_path, BuildEstimate("engine 2", (22.0, 18.0), 2.0, 50.0, "a test compile"), 0.4)
    assert not (tmp_path / RECORD_FILE).exists()
    record_build(tmp_path, BuildEstimate("engine 2", (22.0, 18.0), 2.0, 50.0, "a test compile"), 0.5)
    assert (tmp_path / RECORD_FILE).exists()
