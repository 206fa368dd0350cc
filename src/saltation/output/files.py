"""Files: atomic writing, validated reading and the format headers shared by every file of the library.

Guarantees
----------
Writing
    Every file the library writes (branches, diagrams, special points, sweeps, maps, figures, any
    :func:`write_json`) goes through :func:`write_atomically`: it is written to a temporary file in
    the same folder and then renamed over the target, so a reader sees the old file or the whole new
    one, never a part. On any failure (an exception while encoding, a full disk) the temporary file
    is removed and the old file, if any, is untouched.
Reading
    Every loader checks what it reads and raises :class:`FileFormatError` (a ``ValueError``)
    naming the file and the field, e.g. ``branch.json: points[3].stable: expected true or false,
    got "false"``: for a file that is not complete JSON (truncated), a missing field, a value of
    the wrong type (a boolean must be a JSON boolean, a number a JSON number or one of the
    strings ``"inf"``, ``"-inf"``, ``"nan"``), a list of the wrong length, a CSV row with the wrong
    number of fields, a CSV that ends inside a row, or a CSV with fewer or more rows than its side
    file records. A missing or unreadable file raises the usual ``OSError``.
Headers
    Every record file starts with ``{"format": NAME, "version": FORMAT_VERSIONS[NAME]}``
    (:func:`format_header`); :func:`check_format` reads it at every version of READABLE_VERSIONS, and the names of earlier releases
    (:data:`FORMAT_NAMES`).
"""

from __future__ import annotations

import errno
import json
import math
import os
import secrets
import stat
from collections.abc import Callable, Mapping
from os import PathLike
from pathlib import Path
from typing import Any, NoReturn, TypeVar

import numpy as np

from saltation.errors import SaltationError

__all__ = [
    "BRANCH_FORMAT",
    "DIAGRAM_FORMAT",
    "FORMAT_NAMES",
    "FORMAT_VERSION",
    "FORMAT_VERSIONS",
    "PERIOD_MAP_FORMAT",
    "READABLE_VERSIONS",
    "SWEEP_FORMAT",
    "FileFormatError",
    "PathType",
    "T",
    "UnwritableFieldError",
    "check_format",
    "format_header",
    "write_atomically",
    "write_json",
]

BRANCH_FORMAT = "saltation.branches.branch"
DIAGRAM_FORMAT = "saltation.apps.diagram"
SWEEP_FORMAT = "saltation.sweep"
PERIOD_MAP_FORMAT = "saltation.period_map"
#: The version every record file but a branch's is written at (sweeps, period maps, diagrams).
FORMAT_VERSION = 1
#: The version each format is written at.  Branches are at 2 since 2026-12-05: a special point's one-sided
#: data and touch are nested parts (``one_sided``, ``touch``) instead of flat keys.
FORMAT_VERSIONS: dict[str, int] = {BRANCH_FORMAT: 2, DIAGRAM_FORMAT: FORMAT_VERSION, SWEEP_FORMAT: FORMAT_VERSION,
                                   PERIOD_MAP_FORMAT: FORMAT_VERSION}
#: The versions each format is read at: every version written before (a record of an older version reads
#: as the current one).
READABLE_VERSIONS: dict[str, tuple[int, ...]] = {BRANCH_FORMAT: (1, 2), DIAGRAM_FORMAT: (1,), SWEEP_FORMAT: (1,),
                                                 PERIOD_MAP_FORMAT: (1,)}

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



def _read_text(path: PathType, fields: _Fields, kind: str, empty: str) -> str:
    """A file's text (UTF-8, a byte-order mark allowed), or a FileFormatError naming it."""
    try:
        text = Path(path).read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        fields.fail("", f"not a UTF-8 text file (byte {exc.start}): not a {kind} file, or damaged")
    if not text.strip():
        fields.fail("", empty)
    return text



def format_header(name: str) -> dict[str, Any]:
    """The first two keys of every record file the library writes (branches, diagrams, sweeps, period
    maps): ``{"format": name, "version": FORMAT_VERSIONS[name]}``."""
    return {"format": name, "version": FORMAT_VERSIONS[name]}


def _check_format(d: Any, expected: str, fields: _Fields, where: str = "", *, legacy: str | None = None) -> dict[str, Any]:
    """``d`` as an object of format ``expected`` at a version it is read at (:data:`READABLE_VERSIONS`),
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
    readable = READABLE_VERSIONS[expected]
    if version not in readable or isinstance(version, bool):
        fields.fail(_sub(where, "version"), f"unsupported {expected} version {_show(version)} (this library reads "
                    f"{' and '.join(map(str, readable))})")
    return d


check_format = _check_format

