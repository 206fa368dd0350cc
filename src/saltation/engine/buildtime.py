"""How long a first build takes on this machine: the estimate a build's message gives, and where it comes from.

A build (the engine of a state dimension, a model's functions, or several of them side by side) is
described by its *work*: the seconds each of its processes compiles, on a core of its own, on the
machine the costs were measured on (:data:`~saltation.engine.codegen.COMPILE_GROUP_SECONDS`,
:func:`~saltation.engine.codegen.model_seconds`).  The estimate is the time that work takes on the
cores the build can expect (:func:`expected_cores`, :func:`wall_seconds`), times this machine's
*scale*:

* the median scale of this machine's last three builds of the same kind (the engine of a dimension,
  models' functions) and number of processes: the time each took over the time its work takes on the
  cores it expected.  Each build is recorded in ``build_times.json`` in the kernel cache folder
  (:func:`record_build`), with the numba version and the number of cores it ran with (and its
  processor time, for a reader); builds of another numba or another number of cores do not count;
* else that of its last five builds of other kinds with as many processes (the load of other programs
  weighs differently on one process and on several);
* else a calibration: a small function compiled by numba here (some 0.1 s of processor time, after
  numba's own start, which the build needs anyway), against the time it takes on a machine of scale 1
  (:data:`PROBE_SECONDS`, measured), and for a build of several processes :data:`PARALLEL_SCALE`
  times that;
* else (numba cannot compile the probe, or a small build that is not worth it) there is no estimate,
  and the message gives no time.

A record that cannot be read (damaged, another program's, another version's) is ignored, and the next
build writes the file anew; the file is written whole (a temporary file renamed over it).  Nothing
here raises: a build never fails for its estimate.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import statistics
import time
from dataclasses import dataclass
from pathlib import Path

from saltation.engine._atomic import write_atomic

RECORD_FILE = "build_times.json"
"""The name of the record of this machine's builds, in the kernel cache folder."""

_FORMAT = "saltation build times"
_VERSION = 1
_KEEP = 40  # records kept (the newest)
_SAME_KIND = 3  # the newest records of the same kind that the scale is the median of
_ANY_KIND = 5  # ... of any kind (as many processes), when there is none of the same kind

PROBE_SECONDS = 0.107
"""Processor time of :func:`probe_seconds`'s compile on a machine where a build of one process has scale 1.

Measured on a 2-core machine (AMD EPYC under KVM, numba 0.68.1, Python 3.11.7, other sessions' work
coming and going): the probe took 0.094-0.099 s, and 7 builds of a model's functions alone (2 to 64
states, 6-24 s, at load averages from 2.4 to 5.9) took 0.895 times (0.90 to 1.12 times that) as long
as their work on the cores :func:`expected_cores` gave.  So 0.096 / 0.895 = 0.107 s
(``benchmarks/build_estimate.py`` measures it again)."""

PARALLEL_SCALE = 1.45
"""How much larger the scale of a build of several processes is than that of one, when it comes from
the test compile: its interpreters start and import, it waits for the slowest, and the load average
weighs on it otherwise.  Measured with :data:`PROBE_SECONDS`: 14 first builds of an engine (for 2 or for
5 and more states) beside the functions of 1 or of 3 models, in 2 processes, at load averages from 0.5
to 5.6, took 35-93 s, 1.30 times (0.62 to 1.67 times that: other work starting or ending during the
build) as long as their work on the cores expected; 1.30 / 0.895 = 1.45."""


@dataclass(frozen=True)
class BuildEstimate:
    """How long a build is expected to take, and from what.

    Attributes
    ----------
    kind : str
        What is built (``"engine 2"``, ``"engine 5+"``, ``"model functions"``...): records of the same
        kind are preferred.
    work : tuple of float
        Seconds each of its processes compiles on a core of its own, at scale 1.
    cores : float
        The cores it is expected to have.
    seconds : float or None
        The estimate (None: unknown).
    source : str
        Where the scale came from: ``"builds of this kind"``, ``"other builds"``, ``"a test compile"`` or
        ``"unknown"``.
    """

    kind: str
    work: tuple[float, ...]
    cores: float
    seconds: float | None
    source: str

    @property
    def text(self) -> str:
        """The estimate as a message says it (``"about 50 s"``, ``"about 3 min"``), empty when unknown."""
        if self.seconds is None:
            return ""
        s = self.seconds
        if s < 10:
            return f"about {max(1, round(s))} s"
        if s < 100:
            return f"about {5 * round(s / 5)} s"
        return f"about {round(s / 60)} min" if s >= 150 else f"about {10 * round(s / 10)} s"


# -- the cores a build can expect -------------------------------------------------------------------


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _load() -> float | None:
    """The load average of the last minute (processes running or waiting to), None where not known."""
    try:
        return max(0.0, os.getloadavg()[0])
    except (AttributeError, OSError):
        return None


def expected_cores(processes: int) -> float:
    """The cores a build of ``processes`` processes can expect over the next minute.

    The geometric mean of a guess that knows nothing of now (halfway, geometrically, between the machine
    to itself and shared with another program as busy as the build: ``min(p, c)`` and ``min(p, c / 2)``
    cores, for ``p`` processes on ``c`` cores) and of the share the last minute's load average ``L`` leaves
    it, ``c p / (p + L)`` (at most ``min(p, c)``).  Either alone was further from the truth: the load of a
    shared machine changes within the minute a build takes (see ``benchmarks/build_estimate.py``).

    Parameters
    ----------
    processes : int
        Processes of the build (each uses one core at most).

    Returns
    -------
    float
        Cores (fractional), at most ``min(processes, cores)``.
    """
    cores = _cores()
    p = max(1, processes)
    alone = float(min(p, cores))
    guess = math.sqrt(alone * min(p, cores / 2))
    load = _load()
    if load is None:
        return guess
    return math.sqrt(guess * min(alone, cores * p / (p + load)))


def wall_seconds(work: tuple[float, ...] | list[float], cores: float) -> float:
    """How long processes with ``work`` seconds each take on ``cores`` cores, shared equally (each process
    uses one core at most).

    Parameters
    ----------
    work : sequence of float
        Seconds of each process on a core of its own.
    cores : float
        Cores available (may be fractional).

    Returns
    -------
    float
        The time until the last process is done (0 without work).
    """
    left = sorted(w for w in work if w > 0)
    cores = max(cores, 1e-3)
    elapsed = done = 0.0
    for k, w in enumerate(left):
        rate = min(1.0, cores / (len(left) - k))  # each process still running advances at this rate
        elapsed += (w - done) / rate
        done = w
    return elapsed


# -- the calibration ---------------------------------------------------------------------------------


def _probe_function(a, b, n):  # pragma: no cover - compiled, not run
    s = 0.0
    for i in range(n):
        v = a[i] * b[i]
        if v > 0.0:
            s += v ** 0.5
        else:
            s -= 0.5 * v
    return s


def probe_seconds() -> float | None:
    """The processor time numba takes to compile a small function here (the least of two compiles, after
    a first one that starts numba's compiler if this process has not yet): about 0.1 s.

    Returns
    -------
    float or None
        Seconds of this thread's processor time, None if numba cannot compile here.
    """
    try:
        import numba

        numba.njit(numba.float64(numba.float64))(lambda x: x + 1.0)  # (numba's start: not timed)
        signature = numba.float64(numba.float64[:], numba.float64[:], numba.int64)
        best = None
        for _ in range(2):
            start = time.thread_time()
            numba.njit(signature)(_probe_function)
            spent = time.thread_time() - start
            best = spent if best is None else min(best, spent)
        return best
    except Exception:  # noqa: BLE001 - no estimate, no failure
        return None


# -- the record --------------------------------------------------------------------------------------


def _numba_version() -> str:
    try:
        import numba

        return str(numba.__version__)
    except Exception:  # noqa: BLE001
        return "unknown"


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value < 1e6


def _entries(directory: Path) -> list[dict]:
    """The valid records in ``directory``'s file (none if it is missing, damaged or not this format)."""
    try:
        data = json.loads((directory / RECORD_FILE).read_text())
    except (OSError, ValueError, UnicodeDecodeError):
        return []
    if not isinstance(data, dict) or data.get("format") != _FORMAT or data.get("version") != _VERSION:
        return []
    builds = data.get("builds")
    if not isinstance(builds, list):
        return []
    return [b for b in builds if _valid(b)]


def _valid(entry) -> bool:
    """Whether a recorded build has every field an estimate reads, of its type."""
    return (isinstance(entry, dict) and isinstance(entry.get("kind"), str) and isinstance(entry.get("numba"), str)
            and isinstance(entry.get("machine_cores"), int) and _number(entry.get("seconds"))
            and _number(entry.get("cores")) and (entry.get("cpu") is None or _number(entry.get("cpu")))
            and isinstance(entry.get("work"), list) and bool(entry["work"]) and all(_number(w) for w in entry["work"]))


def _write_atomic(path: Path, text: str) -> None:
    write_atomic(path, text.encode())


def _processor_seconds() -> float | None:
    """Processor time of this process and of its children that have ended (None where not known)."""
    try:
        import resource
    except ImportError:
        return None
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


@contextlib.contextmanager
def timed(directory: Path, estimate: BuildEstimate):
    """Record the build run in the ``with`` block (:func:`record_build`) once it is done: how long it took,
    and the processor time of this process and the children it waited for; a build that raised is not
    recorded.

    Parameters
    ----------
    directory : Path
        The kernel cache folder.
    estimate : BuildEstimate
        The build's estimate, made as it starts.

    Yields
    ------
    None
        The build runs in the block.
    """
    start, cpu = time.monotonic(), _processor_seconds()
    yield
    after = _processor_seconds()
    record_build(directory, estimate, time.monotonic() - start, None if cpu is None or after is None else after - cpu)


def _scale(entry: dict) -> float:
    """The scale of a recorded build: the time it took over the time its work takes on the cores it
    expected (so the machine's usual load counts, as it will for the next build)."""
    return entry["seconds"] / wall_seconds(entry["work"], entry["cores"])


def record_build(directory: Path, estimate: BuildEstimate, seconds: float, cpu: float | None = None) -> None:
    """Add a finished build to the record in ``directory`` (the newest 40 are kept); one that took less
    than a fiftieth of its work's time is not a compile, and is left out.

    The file is written to a temporary file renamed over it, so a crash leaves the old record or the new
    one; one that cannot be read is replaced.  A folder that cannot be written is left alone.

    Parameters
    ----------
    directory : Path
        The kernel cache folder.
    estimate : BuildEstimate
        The build's estimate, made as it started (its kind, work and cores).
    seconds : float
        How long it took.
    cpu : float, optional
        The processor time it took, its processes together.
    """
    nominal = wall_seconds(estimate.work, estimate.cores) if estimate.cores > 0 else 0.0
    if not (nominal > 0 and round(seconds, 3) > 0) or seconds < nominal / 50:
        return  # (a fiftieth of its work's time: it found everything compiled after all, and compiled nothing)
    entry = {"kind": estimate.kind, "seconds": round(float(seconds), 3),
             "cpu": None if cpu is None or round(cpu, 2) <= 0 else round(float(cpu), 2),
             "work": [round(float(w), 2) for w in estimate.work], "cores": round(float(estimate.cores), 3),
             "estimate": None if estimate.seconds is None else round(float(estimate.seconds), 1),
             "source": estimate.source, "numba": _numba_version(), "machine_cores": _cores(),
             "when": time.strftime("%Y-%m-%dT%H:%M:%S")}
    builds = (_entries(directory) + [entry])[-_KEEP:]
    head = json.dumps({"format": _FORMAT, "version": _VERSION})[:-1]  # (one line a build)
    text = head + ', "builds": [\n' + ",\n".join(json.dumps(b) for b in builds) + "\n]}\n"
    with contextlib.suppress(OSError):
        _write_atomic(directory / RECORD_FILE, text)


def estimate_build(directory: Path, kind: str, work: tuple[float, ...] | list[float], *,
                   calibrate: bool = True) -> BuildEstimate:
    """How long a build will take on this machine (see the module's description).

    Parameters
    ----------
    directory : Path
        The kernel cache folder (where the record is).
    kind : str
        What is built: records of the same kind are preferred.
    work : sequence of float
        Seconds each of its processes compiles on a core of its own, at scale 1.
    calibrate : bool
        Whether to compile the probe when nothing is recorded (else the estimate is unknown then).

    Returns
    -------
    BuildEstimate
        The estimate; its ``seconds`` is None if there is none.
    """
    work = tuple(float(w) for w in work if w > 0)
    if not work:
        return BuildEstimate(kind, work, 1.0, None, "unknown")
    cores = expected_cores(len(work))
    version, machine = _numba_version(), _cores()
    mine = [b for b in _entries(directory)  # (the load weighs differently on one process and on several)
            if b["numba"] == version and b["machine_cores"] == machine and len(b["work"]) == len(work)]
    same = [_scale(b) for b in mine if b["kind"] == kind][-_SAME_KIND:]
    scales = same or [_scale(b) for b in mine][-_ANY_KIND:]
    if scales:
        scale, source = statistics.median(scales), "builds of this kind" if same else "other builds"
    else:
        probe = probe_seconds() if calibrate else None
        if probe is None or probe <= 0:
            return BuildEstimate(kind, work, cores, None, "unknown")
        scale, source = probe / PROBE_SECONDS * (PARALLEL_SCALE if len(work) > 1 else 1.0), "a test compile"
    return BuildEstimate(kind, work, cores, scale * wall_seconds(work, cores), source)


__all__ = ["PARALLEL_SCALE", "PROBE_SECONDS", "RECORD_FILE", "BuildEstimate", "estimate_build", "expected_cores",
           "probe_seconds", "record_build", "timed", "wall_seconds"]
