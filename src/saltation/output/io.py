"""Saving and loading: branches, diagrams, special points, sweeps and period maps, as JSON and CSV.

Formats
-------
Branch JSON (``save_branch_json``)
    One object with ``"format": "saltation.branches.branch"`` and ``"version": 1``, the branch's
    metadata, its points and its special points. It holds everything a :class:`Branch`
    holds, so ``load_branch_json(save_branch_json(b))`` gives back an equal branch.
Diagram JSON (``save_diagram_json``)
    ``"format": "saltation.apps.diagram"``: a list of branch objects as above.
Branch CSV (``save_branch_csv``)
    One row per branch point with the columns ``parameter, period, amplitude,
    half_peak_to_peak, stable, event_labels, step, iterations, state_0 .. state_{n-1}`` and, per
    multiplier ``i``, ``mu{i}_re, mu{i}_im, mu{i}_abs``. Events are joined with ``";"``;
    ``stable`` is ``true``/``false``. The CSV holds the points only: the branch's metadata and
    its special points go to a side file ``<stem>.meta.json`` (the branch JSON without its
    points, with ``"n_points"``, the number of rows of the CSV), which ``load_branch_csv`` reads
    when it is present.
Special-point records (``special_point_record``, ``save_special_points_json``)
    The public summary of a located special point, a flat JSON object per point.
Sweep JSON and CSV (``save_sweep``), period map JSON (``save_period_map``)
    ``"format": "saltation.sweep"`` and ``"saltation.period_map"``; the CSV of a sweep has one row
    per point: the parameter value, then every state.
Orbit JSON
    The record ``saltation orbit --json`` prints (:func:`~saltation.output.codecs.orbit_to_dict`).

Numbers are written at full precision (Python's shortest round-trip ``repr``), so a round
trip is lossless. JSON has no infinity or NaN: a non-finite real is written as the string
``"inf"``, ``"-inf"`` or ``"nan"``; a complex number is a pair ``[re, im]`` and an infinite
multiplier (the point at infinity, stored as ``complex(inf, 0)``) is the string ``"inf"``; one known to
grow along the negative real axis (``complex(-inf, 0)``, the crossing side of an impact's grazing) is
``["-inf", 0.0]``.
In CSV, non-finite values are written ``inf``, ``-inf`` and ``nan``, which Python's
``float`` reads back.  Every file is written atomically and read checked
(:mod:`saltation.output.files`); the records are encoded by :mod:`saltation.output.codecs`.
Both modules' names are importable from here too.
"""

from __future__ import annotations

import csv
import io as _io
import json
import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

# with the names this module held before files.py and codecs.py were split from it (private ones: __getattr__)
from saltation._moved import forward_names
from saltation.branches.branch import Branch, BranchKind, BranchPoint
from saltation.output import codecs as _codecs
from saltation.output import files as _files
from saltation.output.codecs import (  # noqa: F401
    Decoder,
    Encoder,
    _branch_from_dict,
    _check_record,
    _metadata_to_dict,
    branch_from_dict,
    branch_to_dict,
    period_map_from_dict,
    period_map_to_dict,
    special_point_record,
    sweep_from_dict,
    sweep_to_dict,
)
from saltation.output.files import (  # noqa: F401
    BRANCH_FORMAT,
    DIAGRAM_FORMAT,
    FORMAT_NAMES,
    FORMAT_VERSION,
    PERIOD_MAP_FORMAT,
    SWEEP_FORMAT,
    FileFormatError,
    PathType,
    T,
    UnwritableFieldError,
    _check_format,
    _Fields,
    _item,
    _read_json,
    _read_text,
    check_format,
    format_header,
    write_atomically,
    write_json,
)
from saltation.sweeps.sweeps import PeriodMap, SweepResult

__all__ = [
    "FileFormatError",
    "UnwritableFieldError",
    "branch_from_dict",
    "branch_to_dict",
    "csv_metadata_path",
    "load_branch_csv",
    "load_branch_json",
    "load_branch_points_csv",
    "load_diagram_json",
    "load_netcdf",
    "load_period_map",
    "load_special_points_json",
    "load_sweep",
    "save_branch_csv",
    "save_branch_json",
    "save_diagram_json",
    "save_netcdf",
    "save_period_map",
    "save_special_points_json",
    "save_sweep",
    "special_point_record",
    "write_atomically",
    "write_json",
]

EVENT_SEPARATOR = ";"


def __getattr__(name: str) -> Any:
    """The private names this module held before :mod:`~saltation.output.files` and
    :mod:`~saltation.output.codecs` were split from it (kept until release 0.3.0)."""
    for module in (_files, _codecs):
        if name.startswith("_") and not name.startswith("__") and hasattr(module, name):
            return getattr(module, name)
    return _public(name)


#: the public names it held in release 0.1 and no longer imports (until 0.3.0)
_public = forward_names(__name__, ("saltation.branches.branch", "saltation.kinds", "saltation.errors"))


# ---------------------------------------------------------------------------
# one writer and one reader per JSON file kind
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class _JsonFile:
    """A kind of JSON file: its record's encoder and decoder, and whether it may hold bare ``NaN`` and
    ``Infinity`` (a sweep's settings are written as given; the branch formats encode every number)."""

    encode: Callable[[Any], Any]
    #: ``decode(document, fields)``
    decode: Callable[[Any, _Fields], Any]
    bare_constants: bool = False

    def save(self, obj: Any, path: PathType) -> Path:
        return write_json(self.encode(obj), path, allow_nan=self.bare_constants)

    def load(self, path: PathType) -> Any:
        return self.decode(_read_json(path, bare_constants=self.bare_constants), _Fields(path))


def _diagram_from_dict(d: Any, f: _Fields) -> list[Branch]:
    d = _check_format(d, DIAGRAM_FORMAT, f)
    items = f.take(d, "", "branches", f.list)
    return [_branch_from_dict(b, f, _item("branches", k)) for k, b in enumerate(items)]


_BRANCH_FILE = _JsonFile(branch_to_dict, lambda d, f: _branch_from_dict(d, f))
_DIAGRAM_FILE = _JsonFile(lambda branches: {**format_header(DIAGRAM_FORMAT),
                                            "branches": [branch_to_dict(b) for b in branches]}, _diagram_from_dict)
_SPECIAL_POINTS_FILE = _JsonFile(list, lambda d, f: [_check_record(r, f, f"[{k}]")
                                                     for k, r in enumerate(f.list(d, "(top level)"))])
_SWEEP_FILE = _JsonFile(sweep_to_dict, lambda d, f: sweep_from_dict(d, source=f.source), bare_constants=True)
_PERIOD_MAP_FILE = _JsonFile(period_map_to_dict, lambda d, f: period_map_from_dict(d, source=f.source),
                             bare_constants=True)


# ---------------------------------------------------------------------------
# branch JSON and diagram JSON
# ---------------------------------------------------------------------------


def save_branch_json(branch: Branch, path: PathType) -> Path:
    """Write a branch, with its special points, to a JSON file (atomically: see :func:`write_atomically`).

    Parameters
    ----------
    branch : Branch
        The branch.
    path : str or path-like
        The file to write.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OSError
        If the file cannot be written (see :func:`write_atomically`).
    """
    return _BRANCH_FILE.save(branch, path)


def load_branch_json(path: PathType) -> Branch:
    """Read a branch written by :func:`save_branch_json`.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    Branch

    Raises
    ------
    FileFormatError
        If the file is not a complete branch file of a supported version: the message names the
        file and the field (a ``ValueError``).
    OSError
        If the file cannot be read.
    """
    return _BRANCH_FILE.load(path)


def save_diagram_json(branches: Iterable[Branch], path: PathType) -> Path:
    """Write several branches (a bifurcation diagram) to one JSON file (atomically).

    Parameters
    ----------
    branches : iterable of Branch
        The branches.
    path : str or path-like
        The file to write.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OSError
        If the file cannot be written (see :func:`write_atomically`).
    """
    return _DIAGRAM_FILE.save(branches, path)


def load_diagram_json(path: PathType) -> list[Branch]:
    """Read the branches written by :func:`save_diagram_json`.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    list of Branch

    Raises
    ------
    FileFormatError
        As :func:`load_branch_json`; fields are named ``branches[k].points[j].stable`` and the like.
    OSError
        If the file cannot be read.
    """
    return _DIAGRAM_FILE.load(path)


# ---------------------------------------------------------------------------
# branch CSV
# ---------------------------------------------------------------------------

#: The columns of a branch CSV before the states and multipliers (``events`` in files before 2026-11-24).
_CSV_COLUMNS = ("parameter", "period", "amplitude", "half_peak_to_peak", "stable", "event_labels", "step", "iterations")


def csv_metadata_path(path: PathType) -> Path:
    """The side file holding a CSV branch's metadata and special points: ``<stem>.meta.json``.

    Parameters
    ----------
    path : str or path-like
        The CSV file.

    Returns
    -------
    Path
        The side file's path, in the same folder.
    """
    path = Path(path)
    return path.with_name(path.stem + ".meta.json")


def _csv_float(x: float) -> str:
    return repr(float(x))


_VALUE_COLUMN = re.compile(r"^(multiplier|eigenvalue)(\d+)_(re|im|abs)$")


def csv_header(branch: Branch, n_state: int, n_mu: int) -> list[str]:
    """The header of a branch's CSV: the continuation parameter's name, the fixed columns (period,
    amplitude, ...), the states by name (their values at the start of the period; ``state_<name>`` for a
    name that is also a column's), then per multiplier ``multiplier<i>_re``, ``_im`` and ``_abs``
    (``i`` from 1), or for an equilibrium branch per eigenvalue of the Jacobian ``eigenvalue<i>_re``
    and ``_im``."""
    parameter = branch.parameter_name or "parameter"
    names = tuple(branch.state_names) if len(branch.state_names) == n_state else tuple(f"state_{i}" for i in range(n_state))
    taken = set(_CSV_COLUMNS[1:]) | {parameter}
    states = [f"state_{name}" if name in taken or _VALUE_COLUMN.match(name) else name for name in names]
    header = [parameter, *_CSV_COLUMNS[1:], *states]
    if branch.kind is BranchKind.EQUILIBRIUM:
        for i in range(1, n_mu + 1):
            header += [f"eigenvalue{i}_re", f"eigenvalue{i}_im"]
    else:
        for i in range(1, n_mu + 1):
            header += [f"multiplier{i}_re", f"multiplier{i}_im", f"multiplier{i}_abs"]
    return header


def _csv_text(branch: Branch) -> str:
    """The CSV of the branch's points (checked before anything is written)."""
    n_state = len(branch.points[0].state) if branch.points else 0
    n_mu = len(branch.points[0].multipliers) if branch.points else 0
    for k, p in enumerate(branch.points):
        if len(p.state) != n_state or len(p.multipliers) != n_mu:
            raise ValueError(
                f"point {k} has {len(p.state)} states and {len(p.multipliers)} multipliers; "
                f"point 0 has {n_state} and {n_mu}"
            )
        bad = [e for e in p.event_labels if EVENT_SEPARATOR in e]
        if bad:
            raise ValueError(f"point {k}: event label {bad[0]!r} contains the separator {EVENT_SEPARATOR!r}")
    header = csv_header(branch, n_state, n_mu)
    equilibria = branch.kind is BranchKind.EQUILIBRIUM
    buffer = _io.StringIO(newline="")
    writer = csv.writer(buffer)
    writer.writerow(header)
    for p in branch.points:
        row = [
            _csv_float(p.parameter),
            _csv_float(p.period),
            _csv_float(p.amplitude),
            _csv_float(p.half_peak_to_peak),
            "true" if p.stable else "false",
            EVENT_SEPARATOR.join(p.event_labels),
            _csv_float(p.step),
            str(int(p.iterations)),
        ]
        row += [_csv_float(x) for x in p.state]
        for z in np.asarray(p.multipliers, dtype=complex):
            row += [_csv_float(z.real), _csv_float(z.imag)] + ([] if equilibria else [_csv_float(abs(z))])
        writer.writerow(row)
    return buffer.getvalue()


def save_branch_csv(branch: Branch, path: PathType, *, metadata: bool = True) -> Path:
    """Write a branch's points to CSV, one row per point (atomically: see :func:`write_atomically`).

    Parameters
    ----------
    branch : Branch
        All points must have the same number of states and of multipliers.
    path : str or path-like
        The CSV file.
    metadata : bool
        Also write the branch's metadata and special points to ``<stem>.meta.json``
        (see :func:`csv_metadata_path`), with the number of rows of the CSV (``"n_points"``),
        so that :func:`load_branch_csv` restores the whole branch and detects a truncated CSV.
        Both files are written before either replaces an old one.

    Returns
    -------
    Path
        The CSV file written.

    Raises
    ------
    ValueError
        If the points differ in their number of states or multipliers, or an event label
        contains the separator ``";"``; no file is touched.
    OSError
        If a file cannot be written; the old files are untouched.
    """
    path = Path(path)
    branch_to_dict(branch)  # every field writable, or UnwritableFieldError naming the one that is not
    files: dict[Path, str] = {path: _csv_text(branch)}
    if metadata:
        meta = _metadata_to_dict(branch)
        meta["n_points"] = len(branch.points)
        files[csv_metadata_path(path)] = json.dumps(meta, indent=1, allow_nan=False) + "\n"
    write_atomically(files)
    return path


def _parse_bool(s: str) -> bool:
    v = s.strip().lower()
    if v in ("true", "1"):
        return True
    if v in ("false", "0"):
        return False
    raise ValueError(f"not a boolean: {s!r}")


def _named_csv_header(header: list[str], f: _Fields) -> list[str]:
    """A header of :func:`csv_header` in the internal names of the first format (``parameter``,
    ``state_<i>``, ``mu<i>_re``, ... from 0), which the rest of the reader uses."""
    fixed = set(_CSV_COLUMNS[1:])
    out = ["parameter"]
    n_state = 0
    for name in header[1:]:
        m = _VALUE_COLUMN.match(name)
        if m:
            i = int(m.group(2)) - 1
            if i < 0:
                f.fail("line 1 (header)", f"the column {name!r}: multipliers and eigenvalues count from 1")
            out.append(f"mu{i}_{m.group(3)}")
        elif name in fixed or name == "events":
            out.append(name)
        else:
            out.append(f"state_{n_state}")
            n_state += 1
    return out


def _csv_header(header: list[str], f: _Fields) -> tuple[dict[str, int], int, int]:
    """The columns of a branch CSV by name, the number of states and of multipliers.  Files written
    before 2026-11-26 name the columns ``parameter``, ``state_<i>``, ``mu<i>_re`` ...; newer ones after the
    parameter and the states (:func:`csv_header`)."""
    named = bool(header) and header[0] != "parameter"
    if named:
        values = "eigenvalue" if any(h.startswith("eigenvalue") for h in header) else "multiplier"
        header = _named_csv_header(header, f)

    def shown(name: str) -> str:  # a column as the file names it
        m = re.match(r"^mu(\d+)_(re|im|abs)$", name)
        return f"{values}{int(m.group(1)) + 1}_{m.group(2)}" if named and m else name

    col: dict[str, int] = {}
    for j, name in enumerate(header):
        if name in col:
            f.fail("line 1 (header)", f"the column {name!r} appears twice")
        col[name] = j
    if "event_labels" not in col and "events" in col:
        col["event_labels"] = col.pop("events")
    for name in _CSV_COLUMNS:
        if name not in col:
            f.fail("line 1 (header)", f"missing the column {name!r}")
    known = set(_CSV_COLUMNS)
    n_state = sum(1 for h in col if h.startswith("state_"))
    n_mu = sum(1 for h in col if h.startswith("mu") and h.endswith("_re"))
    known |= {f"state_{i}" for i in range(n_state)}
    known |= {f"mu{i}_{part}" for i in range(n_mu) for part in ("re", "im", "abs")}
    for name in col:
        if name not in known:
            f.fail("line 1 (header)", f"unexpected column {name!r} (the columns are {', '.join(_CSV_COLUMNS)}, "
                   f"state_0 .. state_{{n-1}}, mu{{i}}_re, mu{{i}}_im, mu{{i}}_abs)")
    for i in range(n_mu):
        for part in ("re", "im"):
            if f"mu{i}_{part}" not in col:
                f.fail("line 1 (header)", f"missing the column {shown(f'mu{i}_{part}')!r}")
    return col, n_state, n_mu



def _read_csv_points(path: PathType, f: _Fields, check_header: Callable[[list[str]], None] | None = None) -> list[BranchPoint]:
    text = _read_text(path, f, "CSV", "the file is empty (no header)")
    reader = csv.reader(_io.StringIO(text, newline=""), strict=True)
    try:
        rows = [(reader.line_num, row) for row in reader]
    except csv.Error as exc:
        f.fail(f"line {reader.line_num + 1}", f"not valid CSV: {exc}")
    if not text.endswith(("\n", "\r")):
        f.fail(f"line {rows[-1][0]}", "the file ends inside this row (no line end after it): truncated")
    (_, header), body = rows[0], [(line, row) for line, row in rows[1:] if row]
    col, n_state, n_mu = _csv_header(header, f)
    if check_header is not None:
        check_header(header)
    return [_csv_point(row, f"line {line} (point {k})", col, n_state, n_mu, f, header) for k, (line, row) in enumerate(body)]



def _csv_point(row: list[str], here: str, col: Mapping[str, int], n_state: int, n_mu: int, f: _Fields,
               header: Sequence[str]) -> BranchPoint:
    """The branch point of one CSV row (``here`` names it; messages name the columns as ``header`` does)."""
    if len(row) != len(col):
        f.fail(here, f"has {len(row)} fields; the header has {len(col)} (truncated or hand-edited?)")

    def cell(name: str, convert: Callable[[str], T], what: str) -> T:
        s = row[col[name]]
        try:
            if not s.strip():
                raise ValueError
            return convert(s)
        except ValueError:
            f.fail(f"{here}, column {header[col[name]]}", f"expected {what}, got {s!r}")

    def real(name: str, finite: bool = False) -> float:
        x = cell(name, float, "a number (or inf, -inf, nan)")
        if finite and not math.isfinite(x):
            f.fail(f"{here}, column {header[col[name]]}", f"expected a finite number, got {row[col[name]]!r}")
        return x

    def count(s: str) -> int:
        n = int(s)
        if n < 0:
            raise ValueError
        return n

    for i in range(n_mu):  # redundant, but a number
        if f"mu{i}_abs" in col:
            real(f"mu{i}_abs")
    events = row[col["event_labels"]]
    return BranchPoint(
        parameter=real("parameter", finite=True),
        state=np.array([real(f"state_{i}", finite=True) for i in range(n_state)], dtype=float),
        period=real("period"),
        amplitude=real("amplitude"),
        half_peak_to_peak=real("half_peak_to_peak"),
        multipliers=np.array([complex(real(f"mu{i}_re"), real(f"mu{i}_im")) for i in range(n_mu)], dtype=complex),
        stable=cell("stable", _parse_bool, "true or false"),
        event_labels=tuple(events.split(EVENT_SEPARATOR)) if events else (),
        step=real("step"),
        iterations=cell("iterations", count, "a non-negative integer"),
    )


def _check_named_header(header: list[str], d: Any, f: _Fields, meta: Path) -> None:
    """A CSV whose side file records the states' names has exactly the header :func:`csv_header` gives."""
    if not isinstance(d, dict) or not d.get("state_names") or not isinstance(d.get("parameter_name"), str):
        return  # (a side file of an earlier version, or a damaged one: its own reader says what is wrong)
    try:
        kind = BranchKind(d.get("kind", "periodic"))
    except ValueError:
        return  # (the side file's reader names the problem)
    if not header or header[0] == "parameter":
        return
    n_mu = sum(1 for h in header if (m := _VALUE_COLUMN.match(h)) and m.group(3) == "re")
    names = tuple(str(s) for s in d["state_names"])
    expected = csv_header(Branch(model="", parameter_name=d["parameter_name"], kind=kind, state_names=names),
                          len(names), n_mu)
    if header == expected:
        return
    odd = [h for h in header if h not in expected]
    if odd:
        f.fail("line 1 (header)", f"unexpected column {odd[0]!r}: the side file {meta.name} names the columns "
               f"{', '.join(expected)}")
    missing = [h for h in expected if h not in header]
    if missing:
        f.fail("line 1 (header)", f"missing the column {missing[0]!r} (the side file {meta.name} names the columns "
               f"{', '.join(expected)})")
    f.fail("line 1 (header)", f"the columns are not in the order the side file {meta.name} gives: {', '.join(expected)}")


def load_branch_points_csv(path: PathType) -> list[BranchPoint]:
    """Read the points of a branch CSV written by :func:`save_branch_csv`.

    The ``mu{i}_abs`` columns are redundant (they must be numbers, but are not used); multipliers
    are rebuilt from the real and imaginary parts.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    list of BranchPoint

    Raises
    ------
    FileFormatError
        If the file is empty, a column is missing, repeated or unknown, a row has the wrong number
        of fields or a field the wrong type (naming the line, the point and the column), or the
        file ends inside a row (truncated). Without the side file a CSV cut exactly at the end of
        a row cannot be told from a shorter branch: :func:`load_branch_csv` checks the count.
    OSError
        If the file cannot be read.
    """
    return _read_csv_points(path, _Fields(path))


def load_branch_csv(
    path: PathType,
    *,
    model: str = "",
    parameter_name: str = "parameter",
    kind: BranchKind = BranchKind.PERIODIC,
) -> Branch:
    """Read a branch from CSV (points) and its side file ``<stem>.meta.json`` (the rest).

    Parameters
    ----------
    path : str or path-like
        The CSV file written by :func:`save_branch_csv`.
    model, parameter_name, kind :
        Used only when the side file is absent; the branch then has no special points.

    Returns
    -------
    Branch

    Raises
    ------
    FileFormatError
        As :func:`load_branch_points_csv` for the CSV and :func:`load_branch_json` for the side
        file, and if the CSV has another number of rows than the side file records (side files
        written by earlier versions record none).
    OSError
        If a file cannot be read.
    """
    f = _Fields(path)
    meta = csv_metadata_path(path)
    if not meta.exists():
        return Branch(model=model, parameter_name=parameter_name, kind=kind, points=_read_csv_points(path, f))
    d = _read_json(meta)
    points = _read_csv_points(path, f, lambda header: _check_named_header(header, d, f, meta))
    mf = _Fields(meta)
    branch = _branch_from_dict(d, mf, "", points)
    n = mf.take(d, "", "n_points", lambda x, field: mf.integer(x, field, minimum=0), None)
    if n is not None and n != len(points):
        f.fail("", f"has {len(points)} rows of points; its side file {meta} records {n} (the CSV is truncated, or "
               "the two files come from different saves)")
    return branch



# ---------------------------------------------------------------------------
# special-point records
# ---------------------------------------------------------------------------


def save_special_points_json(records: Iterable[dict[str, Any]], path: PathType) -> Path:
    """Write special-point records (from :func:`special_point_record`) as a JSON array (atomically).

    Parameters
    ----------
    records : iterable of dict
        The records.
    path : str or path-like
        The file to write.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ValueError
        If a record holds a bare non-finite number (those of :func:`special_point_record` are encoded
        as strings); no file is touched.
    OSError
        If the file cannot be written (see :func:`write_atomically`).
    """
    return _SPECIAL_POINTS_FILE.save(records, path)


def load_special_points_json(path: PathType) -> list[dict[str, Any]]:
    """Read the records written by :func:`save_special_points_json` (as plain dicts, as written).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    list of dict

    Raises
    ------
    FileFormatError
        If the file is not a complete JSON array of records, a record lacks ``model``, ``kind``,
        ``parameter`` or ``value``, or a field has the wrong type (naming the file and the field,
        e.g. ``[2].bracket``).
    OSError
        If the file cannot be read.
    """
    return _SPECIAL_POINTS_FILE.load(path)


# ---------------------------------------------------------------------------
# sweeps and period maps
# ---------------------------------------------------------------------------


def _sweep_csv(result: SweepResult) -> str:
    """One row per point: the parameter value, then every state (full precision)."""
    buffer = _io.StringIO(newline="")
    w = csv.writer(buffer)
    w.writerow([result.parameter_name, *result.state_names])
    for lam, row in zip(result.parameter_points, result.states):
        w.writerow([repr(float(lam)), *(repr(float(v)) for v in row)])
    return buffer.getvalue()


def save_sweep(result: SweepResult, path: PathType) -> Path:
    """Write a sweep's points as JSON (``.json``) or CSV (any other suffix), atomically.

    The CSV has one row per point: the parameter value, then every state (full precision); the
    JSON keeps everything, :func:`load_sweep` reads it back.

    Parameters
    ----------
    result : SweepResult
        The sweep (:func:`saltation.sweeps.sweep`).
    path : str or path-like
        The file to write.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OSError
        If the file cannot be written (see :func:`write_atomically`); the old file is untouched.
    """
    if Path(path).suffix.lower() == ".json":
        return _SWEEP_FILE.save(result, path)
    return write_atomically({Path(path): _sweep_csv(result)})[0]


def load_sweep(path: PathType) -> SweepResult:
    """Read a sweep written by :func:`save_sweep` as JSON.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    SweepResult

    Raises
    ------
    FileFormatError
        If the file is not a complete sweep record (naming the file and the field).
    OSError
        If the file cannot be read.
    """
    return _SWEEP_FILE.load(path)


def save_period_map(grid: PeriodMap, path: PathType) -> Path:
    """Write a period map as JSON, atomically; :func:`load_period_map` reads it.

    Parameters
    ----------
    grid : PeriodMap
        The map (:func:`saltation.sweeps.period_map`).
    path : str or path-like
        The file to write.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OSError
        If the file cannot be written (see :func:`write_atomically`); the old file is untouched.
    """
    return _PERIOD_MAP_FILE.save(grid, path)


def load_period_map(path: PathType) -> PeriodMap:
    """Read a period map written by :func:`save_period_map`.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    PeriodMap

    Raises
    ------
    FileFormatError
        If the file is not a complete period map (naming the file and the field).
    OSError
        If the file cannot be read.
    """
    return _PERIOD_MAP_FILE.load(path)


def save_netcdf(result: SweepResult | PeriodMap, path: PathType) -> Path:
    """Write a sweep or a period map to a NetCDF file: its :meth:`~saltation.sweeps.SweepResult.to_xarray`
    dataset, with its attributes (atomically: see :func:`write_atomically`).

    The file is NetCDF 3 (64-bit offsets), written by scipy, which saltation depends on: any NetCDF
    reader opens it (``xarray.open_dataset(path)``, ``netCDF4``, ``ncdump``).

    Parameters
    ----------
    result : SweepResult or PeriodMap
        What to write.
    path : str or path-like
        The file (``.nc``).

    Returns
    -------
    Path
        The path written.

    Raises
    ------
    MissingDependencyError
        If xarray is not installed (``pip install 'saltation[xarray]'``).
    OSError
        If the file cannot be written.
    """
    data = result.to_xarray().to_netcdf(engine="scipy", format="NETCDF3_64BIT")
    return write_atomically({path: bytes(data)})[0]


def load_netcdf(path: PathType):
    """Read a NetCDF file written by :func:`save_netcdf` (or any NetCDF file) into memory.

    Parameters
    ----------
    path : str or path-like
        The file.

    Returns
    -------
    xarray.Dataset
        Its variables, coordinates and attributes, loaded (the file is closed).

    Raises
    ------
    MissingDependencyError
        If xarray is not installed (``pip install 'saltation[xarray]'``).
    OSError
        If the file cannot be read.
    """
    from saltation._optional import require

    xr = require("xarray", "xarray", "load_netcdf")
    with xr.open_dataset(path) as dataset:
        return dataset.load()
