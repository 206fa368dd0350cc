"""Export and reload of branches and special points (JSON and CSV), and the file writing of the library.

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

Numbers are written at full precision (Python's shortest round-trip ``repr``), so a round
trip is lossless. JSON has no infinity or NaN: a non-finite real is written as the string
``"inf"``, ``"-inf"`` or ``"nan"``; a complex number is a pair ``[re, im]`` and an infinite
multiplier (the point at infinity, stored as ``complex(inf, 0)``) is the string ``"inf"``.
In CSV, non-finite values are written ``inf``, ``-inf`` and ``nan``, which Python's
``float`` reads back.

Guarantees
----------
Writing
    Every file the library writes (these formats, :func:`write_json`, sweeps, maps, figures)
    goes through :func:`write_atomically`: it is written to a temporary file in the same folder
    and then renamed over the target, so a reader sees the old file or the whole new one, never
    a part. On any failure (an exception while encoding, a full disk) the temporary file is
    removed and the old file, if any, is untouched.
Reading
    Every loader checks what it reads and raises :class:`FileFormatError` (a ``ValueError``)
    naming the file and the field, e.g. ``branch.json: points[3].stable: expected true or false,
    got "false"``: for a file that is not complete JSON (truncated), a missing field, a value of
    the wrong type (a boolean must be a JSON boolean, a number a JSON number or one of the
    strings above), a list of the wrong length, a CSV row with the wrong number of fields, a CSV
    that ends inside a row, or a CSV with fewer or more rows than its side file records.
    A missing or unreadable file raises the usual ``OSError``.
"""

from __future__ import annotations

import csv
import dataclasses
import errno
import io as _io
import json
import math
import os
import re
import secrets
import stat
from collections.abc import Callable, Iterable, Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import Any, NoReturn, TypeVar

import numpy as np

from saltation.branches.branch import (
    Branch,
    BranchKind,
    BranchPoint,
    SpecialPoint,
    SpecialPointKind,
    SpecialPointStatus,
    StopReason,
)
from saltation.errors import SaltationError

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
    "load_special_points_json",
    "save_branch_csv",
    "save_branch_json",
    "save_diagram_json",
    "save_special_points_json",
    "special_point_record",
    "write_atomically",
    "write_json",
]

BRANCH_FORMAT = "saltation.branches.branch"
DIAGRAM_FORMAT = "saltation.apps.diagram"
SWEEP_FORMAT = "saltation.sweep"
PERIOD_MAP_FORMAT = "saltation.period_map"
FORMAT_VERSION = 1
EVENT_SEPARATOR = ";"

#: Every ``"format"`` string the library has ever written, and what it reads it as: ``(format,
#: versioned)``, the current format of the file and whether the file also carries ``"version"``
#: (:data:`FORMAT_VERSION`). A record of an earlier release reads as the current one (the fields it
#: lacks take their defaults); a name not listed here is refused.
FORMAT_NAMES: dict[str, tuple[str, bool]] = {
    BRANCH_FORMAT: (BRANCH_FORMAT, True),  # branch JSON, each branch of a diagram, a CSV's side file
    DIAGRAM_FORMAT: (DIAGRAM_FORMAT, True),
    SWEEP_FORMAT: (SWEEP_FORMAT, True),
    PERIOD_MAP_FORMAT: (PERIOD_MAP_FORMAT, True),
    # before the re-layout of the package into folders (2026-11-22 to 2026-11-25)
    "saltation.branch": (BRANCH_FORMAT, True),
    "saltation.diagram": (DIAGRAM_FORMAT, True),
    # before the format and its version were two keys (2026-11-22 to 2026-11-25)
    "saltation.sweep/1": (SWEEP_FORMAT, False),
    "saltation.period_map/1": (PERIOD_MAP_FORMAT, False),
}

PathType = str | PathLike[str]
T = TypeVar("T")


class FileFormatError(SaltationError, ValueError):
    """A file (or a record) is not what its loader reads.

    Truncated, not JSON or CSV, a missing field, a value of the wrong type or a list of the wrong
    length.  The message is ``SOURCE: FIELD: PROBLEM`` (``SOURCE: PROBLEM`` for the file as a whole).

    Attributes
    ----------
    source : str
        The file (as given to the loader), or a description of the record (``"branch record"``).
    field : str
        The field, e.g. ``"points[3].stable"``, ``"line 12 (point 10), column stable"``; empty when the
        problem is the file as a whole (truncated JSON, an empty file).
    problem : str
        What is wrong with it.
    """

    def __init__(self, source: str, field: str, problem: str):
        self.source, self.field, self.problem = str(source), field, problem
        super().__init__(f"{self.source}: {field}: {problem}" if field else f"{self.source}: {problem}")


class UnwritableFieldError(SaltationError, TypeError):
    """A field of a record cannot be written to its file (a label that is not a string, a number
    that is not a number), raised before anything is written.

    Attributes
    ----------
    field : str
        The field, e.g. ``"label"``, ``"special_points[1].note"``, ``"points[3].event_labels[0]"``.
    problem : str
        What is wrong with its value.
    """

    def __init__(self, field: str, problem: str):
        self.field, self.problem = field, problem
        super().__init__(f"cannot write field {field}: {problem}")


def _enc_str(s: Any) -> str:
    if not isinstance(s, str):
        raise UnwritableFieldError("", f"expected a string, got {type(s).__name__} {_short(s)}")
    return str(s)


def _enc_strs(items: Any) -> list[str]:
    return _enc_items(_enc_str)(items)


def _enc_items(enc: Callable[[Any], Any]) -> Callable[[Any], list[Any]]:
    """An encoder of a list whose items ``enc`` encodes, naming the item that fails."""

    def encode(items: Any) -> list[Any]:
        out = []
        for k, x in enumerate(items):
            try:
                out.append(enc(x))
            except UnwritableFieldError as exc:
                raise UnwritableFieldError(f"[{k}]" + (f".{exc.field}" if exc.field and exc.field[0] != "[" else exc.field),
                                           exc.problem) from None
        return out

    return encode


def _short(v: Any) -> str:
    text = repr(v)
    return text if len(text) <= 80 else text[:77] + "..."


# ---------------------------------------------------------------------------
# writing files: atomically
# ---------------------------------------------------------------------------

#: Bytes per ``os.write`` call.
_CHUNK = 1 << 16


def _with_name(exc: OSError, path: Path) -> OSError:
    """``exc`` naming ``path`` (an ``os.write`` error names no file)."""
    if exc.errno is None or exc.filename is not None:
        return exc
    return OSError(exc.errno, exc.strerror, str(path))  # the errno's subclass (PermissionError, ...)


def _stage(path: Path, data: bytes) -> str:
    """Write ``data`` to a new temporary file next to ``path`` (flushed to disk); its name."""
    stem = path.name[:200]
    for _ in range(100):
        tmp = os.path.join(path.parent, f".{stem}.{secrets.token_hex(4)}.tmp")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
        except FileExistsError:
            continue
        except OSError as exc:
            raise _with_name(exc, path) from None
        break
    else:  # pragma: no cover (a hundred random names taken)
        raise FileExistsError(f"no free temporary name next to {path}")
    try:
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(fd, view[:_CHUNK]) :]
            os.fsync(fd)
        finally:
            os.close(fd)
        try:  # keep the permissions of the file replaced (a new file has the umask's)
            os.chmod(tmp, stat.S_IMODE(os.stat(path).st_mode))
        except OSError:
            pass
    except BaseException as exc:
        _remove(tmp)
        if isinstance(exc, OSError):
            raise _with_name(exc, path) from None
        raise
    return tmp


#: What a file that is not a regular one is, by its ``stat`` mode.
_FILE_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISCHR, "a character device"),
               (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _refuse_special(path: Path) -> None:
    """Raise ``FileExistsError`` naming ``path`` if it exists and is not a regular file (a folder, a
    named pipe, a device, a socket): renaming a file over it would replace it."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return  # absent (or unreadable: the writing says why)
    if stat.S_ISREG(mode):
        return
    kind = next((name for test, name in _FILE_KINDS if test(mode)), "not a regular file")
    raise OSError(errno.EEXIST, f"is {kind}, not a regular file: not replaced by the file to write", str(path))


def _remove(tmp: str) -> None:
    try:
        os.unlink(tmp)
    except OSError:
        pass


def write_atomically(files: Mapping[PathType, bytes | str]) -> list[Path]:
    """Write files so that each is either the whole new content or untouched; every writer of the library uses it.

    Each content goes to a temporary file in its target's folder (created if missing), flushed to
    disk; once all of them are written, each is renamed over its target (``os.replace``, atomic).
    A symbolic link is followed: the file it points to is replaced.

    Parameters
    ----------
    files : mapping of path to bytes or str
        The files and their contents (a ``str`` is written as UTF-8).

    Returns
    -------
    list of Path
        The files written, in the order given.

    Raises
    ------
    OSError
        If a folder cannot be created or a file cannot be written (a full disk, no permission),
        naming the file; ``FileExistsError`` if a path given exists and is not a regular file (a
        folder, a named pipe, a device such as ``/dev/null``, a socket), which is left as it is.
        No temporary file is left behind, and no file given is changed (unless the failure is in
        the renaming itself, after some were replaced).
    """
    targets = [(Path(p), c.encode("utf-8") if isinstance(c, str) else bytes(c)) for p, c in files.items()]
    reals = [Path(os.path.realpath(path)) if path.is_symlink() else path for path, _ in targets]
    for real in reals:
        _refuse_special(real)
    staged: list[tuple[str, Path]] = []
    try:
        for (path, data), real in zip(targets, reals):
            real.parent.mkdir(parents=True, exist_ok=True)
            staged.append((_stage(real, data), real))
        while staged:
            tmp, real = staged[0]
            try:
                os.replace(tmp, real)
            except OSError as exc:
                raise _with_name(exc, real) from None
            staged.pop(0)
    finally:
        for tmp, _ in staged:
            _remove(tmp)
    return [path for path, _ in targets]


def write_json(obj: Any, path: PathType, *, allow_nan: bool = True) -> Path:
    """Write ``obj`` as indented JSON with a final newline (atomically, creating the folder).

    Every JSON file the library writes goes through here (and :func:`write_atomically`).

    Parameters
    ----------
    obj : JSON-serialisable object
    path : str or path-like
    allow_nan : bool
        False refuses NaN and infinities (the branch formats encode them as strings first).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ValueError
        If ``obj`` holds a non-finite number and ``allow_nan`` is False (no file is touched).
    OSError
        If the file cannot be written (see :func:`write_atomically`).
    """
    text = json.dumps(obj, indent=1, allow_nan=allow_nan) + "\n"
    return write_atomically({Path(path): text})[0]


def _write_json(obj: Any, path: PathType) -> Path:
    return write_json(obj, path, allow_nan=False)


# ---------------------------------------------------------------------------
# reading files: every value checked, every failure naming the file and the field
# ---------------------------------------------------------------------------

_MISSING: Any = object()
_NON_FINITE = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}


class _Bare:
    """A number of a JSON file that is no finite double: a bare ``NaN``/``Infinity``/``-Infinity`` (not
    JSON), or a literal too large for a double (``1e400``, read as an infinity)."""

    def __init__(self, token: str, value: float | None = None):
        self.token = token
        self.value = {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}[token] if value is None else value
        self.problem = (f'{token} is not JSON: a non-finite number is written "nan", "inf" or "-inf"' if value is None
                        else f'{token} is too large for a double (an infinity is written "inf" or "-inf")')


class _Object(dict):
    """A JSON object whose text repeats a key (the last one would silently win)."""

    duplicate: str = ""


def _sub(where: str, key: str) -> str:
    return f"{where}.{key}" if where else key


def _item(where: str, i: int) -> str:
    return f"{where}[{i}]"


def _show(v: Any) -> str:
    """A value as the file spells it, shortened."""
    if isinstance(v, _Bare):
        return v.token
    try:
        text = json.dumps(v, allow_nan=True)
    except (TypeError, ValueError):
        text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."


class _Fields:
    """Reads the values of a decoded document, failing with :class:`FileFormatError` naming the field."""

    def __init__(self, source: PathType | str):
        self.source = str(source)

    def fail(self, field: str, problem: str) -> NoReturn:
        raise FileFormatError(self.source, field, problem)

    # -- containers ----------------------------------------------------------------------------
    def obj(self, v: Any, field: str) -> dict[str, Any]:
        if not isinstance(v, dict):
            self.fail(field, f"expected an object {{...}}, got {_show(v)}")
        return v

    def list(self, v: Any, field: str, length: int | None = None) -> list[Any]:
        if not isinstance(v, list):
            self.fail(field, f"expected a list [...], got {_show(v)}")
        if length is not None and len(v) != length:
            self.fail(field, f"expected {length} entries, got {len(v)}")
        return v

    def take(self, d: Mapping[str, Any], where: str, key: str, decode: Callable[[Any, str], T],
             default: Any = _MISSING) -> T:
        """``decode(d[key])``, the field named ``where.key``; ``default`` if the key is absent (else a failure)."""
        field = _sub(where, key)
        if key not in d:
            if default is _MISSING:
                self.fail(field, "missing")
            return default
        return decode(d[key], field)

    # -- scalars --------------------------------------------------------------------------------
    def string(self, v: Any, field: str) -> str:
        if not isinstance(v, str):
            self.fail(field, f"expected a string, got {_show(v)}")
        return v

    def boolean(self, v: Any, field: str) -> bool:
        if not isinstance(v, (bool, np.bool_)):
            self.fail(field, f"expected true or false, got {_show(v)}")
        return bool(v)

    def integer(self, v: Any, field: str, minimum: int | None = None, maximum: int | None = None) -> int:
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
            self.fail(field, f"expected an integer, got {_show(v)}")
        if (minimum is not None and v < minimum) or (maximum is not None and v > maximum):
            bounds = f"at least {minimum}" if maximum is None else f"from {minimum} to {maximum}"
            self.fail(field, f"expected an integer {bounds}, got {_show(int(v))}")
        return int(v)

    def real(self, v: Any, field: str, *, finite: bool = False) -> float:
        if isinstance(v, _Bare):
            x = v.value
        elif isinstance(v, str) and v in _NON_FINITE:
            x = _NON_FINITE[v]
        elif isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
            self.fail(field, f'expected a number (or "inf", "-inf", "nan"), got {_show(v)}')
        else:
            try:
                x = float(v)
            except OverflowError:  # an integer beyond the doubles
                self.fail(field, f'{_show(v)} is too large for a double (an infinity is written "inf" or "-inf")')
        if finite and not math.isfinite(x):
            self.fail(field, f"expected a finite number, got {_show(v)}")
        return x

    def complex(self, v: Any, field: str) -> complex:
        if v == "inf":
            return complex(math.inf, 0.0)
        if not isinstance(v, list) or len(v) != 2:
            self.fail(field, f'expected a complex number [re, im] (or "inf"), got {_show(v)}')
        return complex(self.real(v[0], _item(field, 0)), self.real(v[1], _item(field, 1)))

    def choice(self, v: Any, field: str, choices: Mapping[str, T]) -> T:
        if not isinstance(v, str) or v not in choices:
            self.fail(field, f"expected one of {', '.join(json.dumps(c) for c in choices)}, got {_show(v)}")
        return choices[v]

    # -- arrays -----------------------------------------------------------------------------------
    def strings(self, v: Any, field: str) -> tuple[str, ...]:
        return tuple(self.string(s, _item(field, i)) for i, s in enumerate(self.list(v, field)))

    def reals(self, v: Any, field: str, length: int | None = None, *, finite: bool = False) -> np.ndarray:
        items = self.list(v, field, length)
        return np.array([self.real(x, _item(field, i), finite=finite) for i, x in enumerate(items)], dtype=float)

    def complexes(self, v: Any, field: str, length: int | None = None) -> np.ndarray:
        items = self.list(v, field, length)
        return np.array([self.complex(z, _item(field, i)) for i, z in enumerate(items)], dtype=complex)

    def square(self, v: Any, field: str) -> np.ndarray:
        """A square matrix: a list of ``k`` rows of ``k`` numbers."""
        rows = self.list(v, field)
        return np.array([self.reals(r, _item(field, i), len(rows)) for i, r in enumerate(rows)], dtype=float).reshape(
            len(rows), len(rows))

    @staticmethod
    def nullable(decode: Callable[[Any, str], T]) -> Callable[[Any, str], T | None]:
        return lambda v, field: None if v is None else decode(v, field)


def _read_json(path: PathType, *, bare_constants: bool = False) -> Any:
    """The JSON document in ``path``.

    Raises
    ------
    FileFormatError
        If the file is empty, not UTF-8, not complete JSON, repeats a key of an object, or (unless
        ``bare_constants``) holds a bare ``NaN``/``Infinity`` (not JSON: the formats write
        ``"nan"``, ``"inf"``) or a number too large for a double (``1e400``); the field is named
        where it can be.
    OSError
        If the file cannot be read.
    """
    fields = _Fields(path)
    text = _read_text(path, fields, "JSON", "the file is empty")
    flags = {"bare": False, "duplicate": False}

    def constant(token: str) -> _Bare:
        flags["bare"] = True
        return _Bare(token)

    def number(token: str) -> float | _Bare:
        x = float(token)
        if math.isfinite(x):
            return x
        flags["bare"] = True
        return _Bare(token, x)

    def pairs(items: list[tuple[str, Any]]) -> dict[str, Any]:
        d = dict(items)
        if len(d) == len(items):
            return d
        flagged, seen = _Object(items), set()
        for key, _ in items:
            if key in seen:
                flagged.duplicate = key
                break
            seen.add(key)
        flags["duplicate"] = True
        return flagged

    try:
        doc = json.loads(text, parse_constant=constant, parse_float=number, object_pairs_hook=pairs)
    except json.JSONDecodeError as exc:
        fields.fail("", f"not valid JSON at line {exc.lineno} column {exc.colno}: {exc.msg} (the file is truncated or "
                    "damaged)")
    except RecursionError:
        fields.fail("", "not valid JSON: nested too deeply")
    if not (flags["bare"] or flags["duplicate"]):
        return doc

    def walk(v: Any, field: str) -> Any:
        if isinstance(v, _Bare):
            if not bare_constants:
                fields.fail(field or "(top level)", v.problem)
            return v.value
        if isinstance(v, dict):
            if getattr(v, "duplicate", ""):
                fields.fail(field or "(top level)", f"the key {json.dumps(v.duplicate)} appears more than once")
            return {k: walk(x, _sub(field, k)) for k, x in v.items()}
        if isinstance(v, list):
            return [walk(x, _item(field, i)) for i, x in enumerate(v)]
        return v

    return walk(doc, "")


def format_header(name: str) -> dict[str, Any]:
    """The first two keys of every record file the library writes (branches, diagrams, sweeps, period
    maps): ``{"format": name, "version": FORMAT_VERSION}``."""
    return {"format": name, "version": FORMAT_VERSION}


def _check_format(d: Any, expected: str, fields: _Fields, where: str = "", *, legacy: str | None = None) -> dict[str, Any]:
    """``d`` as an object of format ``expected``, version :data:`FORMAT_VERSION` (:func:`format_header`),
    or of a name an earlier release wrote for it (:data:`FORMAT_NAMES`); ``legacy`` is one more
    single ``"format"`` string (without ``"version"``) to accept."""
    d = fields.obj(d, where or "(top level)")
    fmt = d.get("format", _MISSING)
    if fmt is _MISSING:
        fields.fail(_sub(where, "format"), f"missing: not a {expected} file")
    known = FORMAT_NAMES.get(fmt) if isinstance(fmt, str) else None
    if known is None and legacy is not None and fmt == legacy:
        known = (expected, False)
    if known is None or known[0] != expected:
        earlier = [repr(name) for name, (current, _) in FORMAT_NAMES.items() if current == expected and name != expected]
        also = f" (earlier releases wrote {' or '.join(earlier)})" if earlier else ""
        what = f" (a {known[0]} file of an earlier release)" if known is not None and known[0] != fmt else ""
        fields.fail(_sub(where, "format"), f"expected format {expected!r}, found {_show(fmt)}{what}: "
                    f"not a {expected} record{also}")
    if not known[1] and "version" not in d:  # the name says the version
        return d
    version = d.get("version", _MISSING)
    if version is _MISSING:
        fields.fail(_sub(where, "version"), "missing")
    if version != FORMAT_VERSION or isinstance(version, bool):
        fields.fail(_sub(where, "version"), f"unsupported {expected} version {_show(version)} (this library reads "
                    f"{FORMAT_VERSION})")
    return d


check_format = _check_format


# ---------------------------------------------------------------------------
# scalar and array encoding
# ---------------------------------------------------------------------------


def _enc_float(x: float) -> float | str:
    """A real number for JSON: the float itself, or ``"inf"``, ``"-inf"``, ``"nan"``."""
    x = float(x)
    if math.isfinite(x):
        return x
    if math.isnan(x):
        return "nan"
    return "inf" if x > 0 else "-inf"


def _enc_complex(z: complex) -> list[float | str] | str:
    """A complex number as ``[re, im]``; an infinite one as ``"inf"``."""
    z = complex(z)
    if math.isinf(z.real) or math.isinf(z.imag):
        return "inf"
    return [_enc_float(z.real), _enc_float(z.imag)]


def _enc_complex_array(a: np.ndarray | None) -> list[Any] | None:
    if a is None:
        return None
    return [_enc_complex(z) for z in np.asarray(a, dtype=complex).ravel()]


def _enc_real_array(a: np.ndarray | None) -> list[Any] | None:
    """A real array of any shape as nested lists of encoded floats."""
    if a is None:
        return None
    a = np.asarray(a, dtype=float)
    if a.ndim == 0:
        return _enc_float(a)  # type: ignore[return-value]
    return [_enc_real_array(row) for row in a]  # type: ignore[misc]


# ---------------------------------------------------------------------------
# dataclasses <-> plain dicts
# ---------------------------------------------------------------------------


# Each record type is written and read field by field from its dataclass: a codec per field, chosen by
# the field's type annotation unless the table below names one for the field.  A field that has neither
# stops the import (a new field cannot be left out of the files by oversight); a field missing from a
# file takes its dataclass default (files written before it existed), and one without a default fails.

Encoder = Callable[[Any], Any]
#: ``decode(fields, value, field path, the fields decoded so far)``
Decoder = Callable[["_Fields", Any, str, dict[str, Any]], Any]


def _dec(method: str, **kw: Any) -> Decoder:
    """A decoder calling ``_Fields.<method>(value, field, **kw)``."""
    return lambda f, v, field, done: getattr(f, method)(v, field, **kw)


def _nullable(dec: Decoder) -> Decoder:
    return lambda f, v, field, done: None if v is None else dec(f, v, field, done)


def _as_tuple(dec: Decoder) -> Decoder:
    return lambda f, v, field, done: tuple(float(x) for x in dec(f, v, field, done))


def _square_of_state(f: _Fields, v: Any, field: str, done: dict[str, Any]) -> np.ndarray:
    """A square matrix as large as the record's state (decoded before it)."""
    m = f.square(v, field)
    state = done.get("state")
    if state is not None and m.shape[0] != len(state):
        n = len(state)
        f.fail(field, f"expected a {n} x {n} matrix (the state has {n} components), got {m.shape[0]} x {m.shape[0]}")
    return m


def _event_ids_dec(f: _Fields, v: Any, field: str, done: dict[str, Any]) -> tuple[tuple[int, int, int], ...]:
    """A point's event identities: ``[[kind, transition, mode entered], ...]``."""
    if not isinstance(v, list) or not all(
            isinstance(e, list) and len(e) == 3 and all(isinstance(i, int) and not isinstance(i, bool) for i in e)
            for e in v):
        f.fail(field, f"expected a list of [kind, transition, mode] integer triples, got {v!r}")
    return tuple((e[0], e[1], e[2]) for e in v)


def _choice(choices: Mapping[str, Any]) -> Decoder:
    return lambda f, v, field, done: f.choice(v, field, choices)


#: codecs by type annotation (as the dataclasses spell it)
_BY_TYPE: dict[str, tuple[Encoder, Decoder]] = {
    "float": (lambda x: _enc_float(x), _dec("real")),
    "bool": (bool, _dec("boolean")),
    "int": (int, _dec("integer")),
    "str": (_enc_str, _dec("string")),
    "tuple[str, ...]": (_enc_strs, _dec("strings")),
    "tuple[float, ...]": (lambda a: [_enc_float(x) for x in a], _as_tuple(_dec("reals"))),
    "float | None": (lambda x: None if x is None else _enc_float(x), _nullable(_dec("real"))),
    "str | None": (lambda s: None if s is None else _enc_str(s), _nullable(_dec("string"))),
    "complex | None": (lambda z: None if z is None else _enc_complex(z), _nullable(_dec("complex"))),
}
_REAL_ARRAY = (_enc_real_array, _nullable(_dec("reals")))
_COMPLEX_ARRAY = (_enc_complex_array, _nullable(_dec("complexes")))
_SQUARE = (_enc_real_array, _nullable(_square_of_state))
_EVENT_IDS = (lambda ids: [[int(k), int(tr), int(m)] for k, tr, m in ids], _event_ids_dec)


def _enum(cls: type) -> tuple[Encoder, Decoder]:
    return (lambda e: e.value, _choice({k.value: k for k in cls}))


_KINDS = {k.value: k for k in SpecialPointKind}
_STATUSES = {k.value: k for k in SpecialPointStatus}


class _Codec:
    """The codec of a record dataclass: its fields, each with an encoder and a decoder.

    Parameters
    ----------
    cls : dataclass type
    fields : mapping
        Codecs of fields that the type annotation does not decide (arrays, enums, checked values).
    skip : set of str
        Fields not written (kept in memory only).
    old_names : mapping
        Field -> the key files of earlier releases used for it.
    """

    def __init__(self, cls: type, fields: Mapping[str, tuple[Encoder, Decoder]], *, skip: frozenset[str] = frozenset(),
                 old_names: Mapping[str, str] | None = None):
        self.cls = cls
        self.old_names = dict(old_names or {})
        self.fields: list[tuple[str, Encoder, Decoder, bool]] = []
        for fld in dataclasses.fields(cls):
            if fld.name in skip:
                continue
            codec = fields.get(fld.name) or _BY_TYPE.get(str(fld.type))
            if codec is None:
                raise TypeError(f"{cls.__name__}.{fld.name} ({fld.type}) has no file codec: add one to saltation.output.io")
            required = fld.default is dataclasses.MISSING and fld.default_factory is dataclasses.MISSING
            self.fields.append((fld.name, *codec, required))

    def encode(self, obj: Any) -> dict[str, Any]:
        """The record as a JSON-ready object; :class:`UnwritableFieldError` names a field that cannot be written."""
        out = {}
        for name, enc, _, _ in self.fields:
            value = getattr(obj, name)
            try:
                out[name] = enc(value)
            except UnwritableFieldError as exc:
                inner = exc.field if not exc.field or exc.field[0] == "[" else "." + exc.field
                raise UnwritableFieldError(name + inner, exc.problem) from None
            except (TypeError, ValueError, OverflowError, AttributeError) as exc:
                raise UnwritableFieldError(name, f"{type(value).__name__} {_short(value)} ({type(exc).__name__}: "
                                           f"{exc})") from None
        return out

    def decode(self, f: _Fields, v: Any, where: str, **given: Any) -> Any:
        """The record from its object ``v`` (the field path ``where``); ``given`` are the skipped fields."""
        d = f.obj(v, where)
        done: dict[str, Any] = {}
        for name, _, dec, required in self.fields:
            key = name if name in d or self.old_names.get(name) not in d else self.old_names[name]
            if key not in d:
                if required:
                    f.fail(_sub(where, name), "missing")
                continue  # the dataclass default: a file written before the field existed
            done[name] = dec(f, d[key], _sub(where, key), done)
        return self.cls(**done, **given)


_POINT_CODEC = _Codec(
    BranchPoint,
    {
        "parameter": (_enc_float, _dec("real", finite=True)),
        "state": (_enc_real_array, _dec("reals", finite=True)),
        "multipliers": (_enc_complex_array, _dec("complexes")),
        "iterations": (int, _dec("integer", minimum=0)),
        "monodromy": _SQUARE,
        "event_ids": _EVENT_IDS,
    },
    old_names={"event_labels": "events"},  # "events": files before 2026-11-24
)

_SPECIAL_POINT_CODEC = _Codec(
    SpecialPoint,
    {
        "kind": _enum(SpecialPointKind),
        "bracket": (lambda b: [_enc_float(x) for x in b], _as_tuple(_dec("reals", length=2))),
        "state": _REAL_ARRAY,
        "multipliers": _COMPLEX_ARRAY,
        "multipliers_minus": _COMPLEX_ARRAY,
        "multipliers_plus": _COMPLEX_ARRAY,
        "monodromy_minus": _SQUARE,
        "monodromy_plus": _SQUARE,
        # written by name; read as a string, which SpecialPoint parses (with the exponents files before
        # 2026-11-25 wrote into it)
        "limits": (lambda e: e.value, _dec("string")),
        # files before 2026-11-25 do not say: the dataclass default, the weaker claim (within its bracket)
        "status": _enum(SpecialPointStatus),
    },
    old_names={"event_labels_minus": "events_minus", "event_labels_plus": "events_plus"},
)


def _point_to_dict(p: BranchPoint) -> dict[str, Any]:
    return _POINT_CODEC.encode(p)


def _point_from_dict(v: Any, f: _Fields, where: str) -> BranchPoint:
    return _POINT_CODEC.decode(f, v, where)


def _check_points(points: Sequence[BranchPoint], f: _Fields, name: Callable[[int], str]) -> None:
    """Every point has as many states and multipliers as the first (``name(k)`` names point ``k``)."""
    if not points:
        return
    n_state, n_mu = len(points[0].state), len(points[0].multipliers)
    for k, p in enumerate(points):
        for attr, n in (("state", n_state), ("multipliers", n_mu)):
            if len(getattr(p, attr)) != n:
                f.fail(_sub(name(k), attr), f"has {len(getattr(p, attr))} entries; {_sub(name(0), attr)} has {n}")


def _special_point_to_dict(sp: SpecialPoint) -> dict[str, Any]:
    return _SPECIAL_POINT_CODEC.encode(sp)


def _special_point_from_dict(v: Any, f: _Fields, where: str) -> SpecialPoint:
    return _SPECIAL_POINT_CODEC.decode(f, v, where)


def _enc_stop(reason: StopReason | None) -> str | None:
    """A stop reason by its (lower-case) name; its value is a sentence that may be reworded."""
    return None if reason is None else reason.name.lower()


_STOPS = {r.name.lower(): r for r in StopReason}
_BRANCH_KINDS = {k.value: k for k in BranchKind}


def _dec_fixed(f: _Fields, v: Any, field: str, done: dict[str, Any]) -> dict[str, float]:
    return {k: f.real(x, _sub(field, k)) for k, x in f.obj(v, field).items()}


def _dec_texts(f: _Fields, v: Any, field: str, done: dict[str, Any]) -> dict[str, str]:
    return {k: f.string(x, _sub(field, k)) for k, x in f.obj(v, field).items()}


def _dec_list(dec: Decoder) -> Decoder:
    return lambda f, v, field, done: [dec(f, x, _item(field, k), done) for k, x in enumerate(f.list(v, field))]


_STOP = (_enc_stop, _nullable(_choice(_STOPS)))
_BRANCH_CODEC = _Codec(
    Branch,
    {
        "kind": _enum(BranchKind),
        "special_points": (_enc_items(lambda sp: _special_point_to_dict(sp)),
                           _dec_list(lambda f, v, field, done: _special_point_from_dict(v, f, field))),
        "stop_reason": _STOP,
        "stop_reasons": (lambda rs: [_enc_stop(r) for r in rs], _dec_list(_STOP[1])),
        "fixed_parameters": (lambda d: {str(k): _enc_float(v) for k, v in d.items()}, _dec_fixed),
        "axis_labels": (lambda d: {str(k): str(v) for k, v in d.items()}, _dec_texts),
        "curve_of": (lambda k: None if k is None else k.value, _nullable(_choice(_KINDS))),
    },
    skip=frozenset({"points"}),  # written beside the metadata (JSON) or as the rows of a CSV
)


def _metadata_to_dict(branch: Branch) -> dict[str, Any]:
    return {**format_header(BRANCH_FORMAT), **_BRANCH_CODEC.encode(branch)}


def branch_to_dict(branch: Branch) -> dict[str, Any]:
    """The branch as a JSON-ready dict (the content of a branch JSON file).

    Parameters
    ----------
    branch : Branch
        The branch.

    Returns
    -------
    dict
        Metadata, ``points`` and ``special_points``, encoded as described in the module
        docstring (no bare infinities or NaNs, complex numbers as ``[re, im]``).
    """
    d = _metadata_to_dict(branch)
    try:
        d["points"] = _enc_items(_point_to_dict)(branch.points)
    except UnwritableFieldError as exc:
        raise UnwritableFieldError("points" + exc.field, exc.problem) from None
    return d


def _branch_from_dict(v: Any, f: _Fields, where: str = "", points: list[BranchPoint] | None = None) -> Branch:
    d = _check_format(v, BRANCH_FORMAT, f, where)
    if points is None:
        if "points" not in d:
            hint = " (a CSV's side file? read the CSV with load_branch_csv)" if "n_points" in d else ""
            f.fail(_sub(where, "points"), "missing" + hint)
        items = f.list(d["points"], _sub(where, "points"))
        points = [_point_from_dict(p, f, _item(_sub(where, "points"), k)) for k, p in enumerate(items)]
        _check_points(points, f, lambda k: _item(_sub(where, "points"), k))
    return _BRANCH_CODEC.decode(f, d, where, points=points)


def branch_from_dict(d: dict[str, Any], *, points: list[BranchPoint] | None = None,
                     source: str = "branch record") -> Branch:
    """Rebuild a :class:`Branch` from :func:`branch_to_dict` output, checking every field.

    Parameters
    ----------
    d : dict
        Branch dict; its ``points`` entry is used unless ``points`` is given.
    points : list of BranchPoint, optional
        Points read elsewhere (from a CSV file).
    source : str
        What ``d`` was read from, for the messages (a file name).

    Returns
    -------
    Branch

    Raises
    ------
    FileFormatError
        If ``d`` is not a branch of a supported version, or a field is missing, of the wrong type
        or of the wrong length; the message names ``source`` and the field.
    """
    return _branch_from_dict(d, _Fields(source), "", points)


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
    return _write_json(branch_to_dict(branch), path)


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
    return _branch_from_dict(_read_json(path), _Fields(path))


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
    obj = {
        **format_header(DIAGRAM_FORMAT),
        "branches": [branch_to_dict(b) for b in branches],
    }
    return _write_json(obj, path)


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
    f = _Fields(path)
    d = _check_format(_read_json(path), DIAGRAM_FORMAT, f)
    items = f.take(d, "", "branches", f.list)
    return [_branch_from_dict(b, f, _item("branches", k)) for k, b in enumerate(items)]


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


def _read_text(path: PathType, fields: _Fields, kind: str, empty: str) -> str:
    """A file's text (UTF-8, a byte-order mark allowed), or a FileFormatError naming it."""
    try:
        text = Path(path).read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        fields.fail("", f"not a UTF-8 text file (byte {exc.start}): not a {kind} file, or damaged")
    if not text.strip():
        fields.fail("", empty)
    return text


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
# public special-point records
# ---------------------------------------------------------------------------


def special_point_record(sp: SpecialPoint, model: str, parameter: str) -> dict[str, Any]:
    """The public record of a special point, as written to ``special_points.json``.

    Parameters
    ----------
    sp : SpecialPoint
        The special point.
    model : str
        Name of the model.
    parameter : str
        Name of the continuation parameter.

    Returns
    -------
    dict
        Keys ``model``, ``kind`` (the kind's value, e.g. ``"discontinuous_fold"``),
        ``parameter`` (the parameter's name), ``value`` (its located value), ``amplitude``;
        then ``multipliers`` for a smooth point, or ``multipliers_minus``,
        ``multipliers_plus`` and ``crossing_q`` for a non-smooth one; then ``bracket``,
        ``accuracy``, ``crossing_point``, ``note``, ``multipliers_accuracy`` (an estimate of the
        multipliers' error), ``limits`` (how the one-sided multipliers were obtained:
        ``"exact"``, ``"nearest_saltation"``, ``"nearest_orbits"``, ``"extrapolated"``, ``"grazing"``
        or ``""``), ``status`` (``"located"`` by a defining system, ``"bracketed"`` or ``"failed"``),
        ``growth_exponents`` where multipliers grow without bound towards the point; for a grazing or a sliding
        bifurcation also ``touch_surface``, ``touch_mode`` and ``touch_time`` (where the orbit meets
        the surface, and whose field is tangent there). Multipliers are ``[re, im]`` pairs, an
        infinite one the string ``"inf"``; absent values are ``null``.
    """
    rec: dict[str, Any] = {
        "model": model,
        "kind": sp.kind.value,
        "parameter": parameter,
        "value": _enc_float(sp.parameter),
        "amplitude": _enc_float(sp.amplitude),
    }
    if sp.kind.is_nonsmooth:
        rec["multipliers_minus"] = _enc_complex_array(sp.multipliers_minus)
        rec["multipliers_plus"] = _enc_complex_array(sp.multipliers_plus)
        rec["crossing_q"] = None if sp.crossing_q is None else _enc_float(sp.crossing_q)
    else:
        rec["multipliers"] = _enc_complex_array(sp.multipliers)
    rec["bracket"] = [_enc_float(b) for b in sp.bracket]
    rec["accuracy"] = _enc_float(sp.accuracy)
    rec["crossing_point"] = None if sp.crossing_point is None else _enc_complex(sp.crossing_point)
    rec["note"] = sp.note
    rec["multipliers_accuracy"] = _enc_float(sp.multipliers_accuracy)
    rec["limits"] = sp.limits.value
    rec["status"] = sp.status.value
    if sp.growth_exponents:
        rec["growth_exponents"] = [_enc_float(a) for a in sp.growth_exponents]
    if sp.touch_surface:
        rec["touch_surface"] = sp.touch_surface
        rec["touch_mode"] = sp.touch_mode
        rec["touch_time"] = _enc_float(sp.touch_time)
    if sp.classification:
        rec["classification"] = sp.classification
    return rec


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
    return _write_json(list(records), path)


def _check_record(v: Any, f: _Fields, where: str) -> dict[str, Any]:
    """A special-point record, every field it has checked; returned as read."""
    d = f.obj(v, where)
    opt = f.nullable
    for key, decode in (("model", f.string), ("kind", lambda x, field: f.choice(x, field, _KINDS)),
                        ("parameter", f.string), ("value", f.real)):
        f.take(d, where, key, decode)
    optional: dict[str, Callable[[Any, str], Any]] = {
        "amplitude": f.real, "multipliers": opt(f.complexes), "multipliers_minus": opt(f.complexes),
        "multipliers_plus": opt(f.complexes), "crossing_q": opt(f.real),
        "bracket": lambda x, field: f.reals(x, field, 2), "accuracy": f.real, "crossing_point": opt(f.complex),
        "note": f.string, "multipliers_accuracy": f.real, "limits": f.string, "touch_surface": f.string,
        "touch_mode": f.string, "touch_time": f.real, "status": lambda x, field: f.choice(x, field, _STATUSES),
        "growth_exponents": f.reals,
        "classification": lambda x, field: f.choice(x, field, {"persistence": "persistence", "nonsmooth_fold": "nonsmooth_fold"}),
    }
    for key, decode in optional.items():
        f.take(d, where, key, decode, None)
    return d


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
    f = _Fields(path)
    items = f.list(_read_json(path), "(top level)")
    return [_check_record(r, f, f"[{k}]") for k, r in enumerate(items)]
