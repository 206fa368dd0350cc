"""Codecs: one per record, from a record to the JSON-ready object its file holds and back.

The records of the branch layer (:class:`~saltation.branches.branch.BranchPoint`,
:class:`~saltation.branches.branch.SpecialPoint`, :class:`~saltation.branches.branch.Branch`) are
written and read field by field from their dataclasses (:class:`_Codec`): a new field cannot be
left out of the files by oversight.  The flat special-point record of ``special_points.json``
(:func:`special_point_record`) is a view of the special point's codec: the same encoders and
decoders, a few fields renamed and the rest left out.  :class:`~saltation.sweeps.SweepResult`,
:class:`~saltation.sweeps.PeriodMap` and :class:`~saltation.orbits.shooting.PeriodicOrbit` have a
codec each (:func:`sweep_to_dict`, :func:`period_map_to_dict`, :func:`orbit_to_dict`).

Encoding: numbers at full precision; a non-finite real is the string ``"inf"``, ``"-inf"`` or
``"nan"``; a complex number a pair ``[re, im]``, an infinite one the string ``"inf"`` (``["-inf", 0.0]``
along the negative real axis).  Decoding
checks every value and fails with :class:`~saltation.output.files.FileFormatError` naming the
field (:mod:`saltation.output.files`).
"""

from __future__ import annotations

import dataclasses
import math
from collections import ChainMap
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from saltation.branches.branch import (
    BorderScenario,
    Branch,
    BranchKind,
    BranchPoint,
    CodimensionTwoKind,
    Criticality,
    OneSided,
    SpecialPoint,
    SpecialPointKind,
    SpecialPointStatus,
    StopReason,
    Touch,
)
from saltation.output.files import (
    BRANCH_FORMAT,
    PERIOD_MAP_FORMAT,
    SWEEP_FORMAT,
    UnwritableFieldError,
    _check_format,
    _Fields,
    _item,
    _short,
    _show,
    _sub,
    format_header,
)
from saltation.sweeps.sections import Section
from saltation.sweeps.sweeps import PeriodMap, SweepResult, SweepStart

__all__ = [
    "Decoder",
    "Encoder",
    "branch_from_dict",
    "branch_to_dict",
    "codimension_two_record",
    "locus_record",
    "orbit_to_dict",
    "period_map_from_dict",
    "period_map_to_dict",
    "special_point_record",
    "sweep_from_dict",
    "sweep_to_dict",
]


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
    """A complex number as ``[re, im]``; the point at infinity (``complex(inf, 0)``) as ``"inf"``, and an
    infinite multiplier along the negative real axis (``complex(-inf, 0)``) as ``["-inf", 0.0]``, which
    readers before it read as the same number."""
    z = complex(z)
    if math.isinf(z.real) and z.real < 0 and z.imag == 0.0:
        return [_enc_float(z.real), 0.0]
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
    "dict[str, float]": (lambda d: {str(k): _enc_float(v) for k, v in d.items()},
                         lambda f, v, field, done: {k: f.real(x, _sub(field, k)) for k, x in f.obj(v, field).items()}),
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
                raise TypeError(f"{cls.__name__}.{fld.name} ({fld.type}) has no file codec: add one to saltation.output.codecs")
            required = fld.default is dataclasses.MISSING and fld.default_factory is dataclasses.MISSING
            self.fields.append((fld.name, *codec, required))
        self.codecs = {name: (enc, dec) for name, enc, dec, _ in self.fields}

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

    def decode(self, f: _Fields, v: Any, where: str, *, outer: Mapping[str, Any] | None = None, **given: Any) -> Any:
        """The record from its object ``v`` (the field path ``where``); ``given`` are the skipped fields, and
        ``outer`` the fields decoded so far of the record this one is a part of."""
        d = f.obj(v, where)
        done: dict[str, Any] = {}
        seen = ChainMap(done, dict(outer or {}))
        for name, _, dec, required in self.fields:
            key = name if name in d or self.old_names.get(name) not in d else self.old_names[name]
            if key not in d:
                if required:
                    f.fail(_sub(where, name), "missing")
                continue  # the dataclass default: a file written before the field existed
            done[name] = dec(f, d[key], _sub(where, key), seen)
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
        "curve_kind": (lambda k: None if k is None else k.value, _nullable(_choice(_KINDS))),
    },
    old_names={"event_labels": "events"},  # "events": files before 2026-11-24
)

_ONE_SIDED_CODEC = _Codec(
    OneSided,
    {
        "multipliers_minus": _COMPLEX_ARRAY,
        "multipliers_plus": _COMPLEX_ARRAY,
        "monodromy_minus": _SQUARE,
        "monodromy_plus": _SQUARE,
        "event_ids_minus": _EVENT_IDS,
        "event_ids_plus": _EVENT_IDS,
        # written by name; read as a string, which OneSided parses (with the exponents files before
        # 2026-11-25 wrote into it)
        "limits": (lambda e: e.value, _dec("string")),
        # optional keys (2026-12-06): files before them read as None, and readers before them skip them
        "scenario": (lambda e: None if e is None else e.value, _nullable(_choice({k.value: k for k in BorderScenario}))),
        "period_two": (lambda b: None if b is None else bool(b), _nullable(_dec("boolean"))),
    },
    old_names={"event_labels_minus": "events_minus", "event_labels_plus": "events_plus"},
)

_TOUCH_CODEC = _Codec(Touch, {})


def _part(codec: _Codec) -> tuple[Encoder, Decoder]:
    """The codec of an optional part of a record (``null`` when absent); its decoders see the record's
    fields decoded so far (a one-sided monodromy is as large as the point's state)."""
    return (lambda part: None if part is None else codec.encode(part),
            _nullable(lambda f, v, field, done: codec.decode(f, v, field, outer=done)))


_SPECIAL_POINT_CODEC = _Codec(
    SpecialPoint,
    {
        "kind": _enum(SpecialPointKind),
        "bracket": (lambda b: [_enc_float(x) for x in b], _as_tuple(_dec("reals", length=2))),
        "state": _REAL_ARRAY,
        "multipliers": _COMPLEX_ARRAY,
        "event_ids": _EVENT_IDS,
        # files before 2026-11-25 do not say: the dataclass default, the weaker claim (within its bracket)
        "status": _enum(SpecialPointStatus),
        "one_sided": _part(_ONE_SIDED_CODEC),
        "touch": _part(_TOUCH_CODEC),
        # files before 2027-01 do not have it: None
        "codimension_two": (lambda k: None if k is None else k.value,
                            _nullable(_choice({k.value: k for k in CodimensionTwoKind}))),
        # an optional key (2026-12-06): files before it read as None, and readers before it skip it
        "sensitivities": (lambda d: None if d is None else {str(k): _enc_float(v) for k, v in d.items()},
                          _nullable(lambda f, v, field, done: _dec_fixed(f, v, field, done))),
        # optional keys (2026-12-05): files before them read as None, and readers before them skip them
        "criticality": (lambda k: None if k is None else k.value,
                        _nullable(_choice({k.value: k for k in Criticality}))),
        "normal_form": (lambda c: None if c is None else [_enc_float(x) for x in c],
                        _nullable(_as_tuple(_dec("reals", length=2)))),
    },
)

#: The keys of a version-1 special point (flat) that belong to its parts, with their part's field names.
_FLAT_ONE_SIDED = {name: name for name in ("multipliers_minus", "multipliers_plus", "monodromy_minus",
                                           "monodromy_plus", "event_labels_minus", "event_labels_plus",
                                           "events_minus", "events_plus", "limits", "growth_exponents",
                                           "crossing_q", "crossing_point")}
_FLAT_TOUCH = {"touch_surface": "surface", "touch_mode": "mode", "touch_time": "time"}
#: values a version-1 file writes for a field it has nothing for
_NOTHING = (None, [], "", "none", "nan")


def _nested_parts(d: dict[str, Any]) -> dict[str, Any]:
    """A special point of a version-1 file (the parts' fields flat beside the core's) in the layout of
    version 2: the flat keys that say something gathered into ``one_sided`` and ``touch``."""
    core = {k: v for k, v in d.items() if k not in _FLAT_ONE_SIDED and k not in _FLAT_TOUCH}
    sided = {_FLAT_ONE_SIDED[k]: v for k, v in d.items() if k in _FLAT_ONE_SIDED and v not in _NOTHING}
    touched = {_FLAT_TOUCH[k]: v for k, v in d.items() if k in _FLAT_TOUCH}
    core["one_sided"] = sided or None
    core["touch"] = touched if touched.get("surface") else None
    return core


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
    d = f.obj(v, where)
    if "one_sided" not in d:  # version 1 (before 2026-12-05): the parts' fields flat beside the core's
        d = _nested_parts(d)
    return _SPECIAL_POINT_CODEC.decode(f, d, where)


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
# the flat special-point record: a view of the special point's codec
# ---------------------------------------------------------------------------

#: When a key of the flat record is shown, by the point it shows.
_SHOWN: dict[str, Callable[[SpecialPoint], bool]] = {
    "always": lambda sp: True,
    "nonsmooth": lambda sp: sp.kind.is_nonsmooth,
    "smooth": lambda sp: not sp.kind.is_nonsmooth,
    "growth": lambda sp: bool(sp.growth_exponents),
    "touch": lambda sp: bool(sp.touch_surface),
    "classified": lambda sp: bool(sp.classification),
    "scenario": lambda sp: sp.scenario is not None,
    "sensitivities": lambda sp: sp.sensitivities is not None,
}

#: The flat record after ``model``, ``kind`` and ``parameter`` (the parameter's name): each key, the
#: special point's field it shows (encoded and decoded by the special point's codec), and when.
_FLAT_VIEW: tuple[tuple[str, str, str], ...] = (
    ("value", "parameter", "always"),
    ("amplitude", "amplitude", "always"),
    ("multipliers_minus", "multipliers_minus", "nonsmooth"),
    ("multipliers_plus", "multipliers_plus", "nonsmooth"),
    ("crossing_q", "crossing_q", "nonsmooth"),
    ("multipliers", "multipliers", "smooth"),
    ("bracket", "bracket", "always"),
    ("accuracy", "accuracy", "always"),
    ("crossing_point", "crossing_point", "always"),
    ("note", "note", "always"),
    ("multipliers_accuracy", "multipliers_accuracy", "always"),
    ("limits", "limits", "always"),
    ("status", "status", "always"),
    ("growth_exponents", "growth_exponents", "growth"),
    ("touch_surface", "touch_surface", "touch"),
    ("touch_mode", "touch_mode", "touch"),
    ("touch_time", "touch_time", "touch"),
    ("classification", "classification", "classified"),
    ("scenario", "scenario", "scenario"),
    ("period_two", "period_two", "scenario"),
    ("sensitivities", "sensitivities", "sensitivities"),
)

#: The codec of every field and part's field by its flat name.
_FLAT_CODECS: dict[str, tuple[Encoder, Decoder]] = {
    **_SPECIAL_POINT_CODEC.codecs, **_ONE_SIDED_CODEC.codecs,
    **{"touch_" + name: codec for name, codec in _TOUCH_CODEC.codecs.items()},
}


def _flat(sp: SpecialPoint) -> dict[str, Any]:
    """The special point's codec with its parts' fields flat (an absent part's fields at their defaults)."""
    full = _special_point_to_dict(sp)
    sided = full.pop("one_sided") or _ONE_SIDED_CODEC.encode(OneSided())
    touched = full.pop("touch") or _TOUCH_CODEC.encode(Touch(""))
    return {**full, **sided, **{"touch_" + name: value for name, value in touched.items()}}


#: Decoders of the flat record that check more than the special point's codec.
_FLAT_CHECKS: dict[str, Decoder] = {
    "classification": _choice({"persistence": "persistence", "nonsmooth_fold": "nonsmooth_fold"}),
}


def special_point_record(sp: SpecialPoint, model: str, parameter: str) -> dict[str, Any]:
    """The public record of a special point, as written to ``special_points.json``: a flat view of its codec.

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
        the surface, and whose field is tangent there); where Feigin's classification was asked,
        ``scenario`` (``"persistence"``, ``"nonsmooth_fold"`` or ``"undetermined"``) and
        ``period_two``; where sensitivities were asked, ``sensitivities`` (``{parameter: d value / d
        parameter}``). Multipliers are ``[re, im]`` pairs, an infinite one the string ``"inf"``
        (``["-inf", 0.0]`` along the negative real axis); absent values are ``null``.
    """
    full = _flat(sp)
    return {"model": model, "kind": full["kind"], "parameter": parameter,
            **{key: full[name] for key, name, when in _FLAT_VIEW if _SHOWN[when](sp)}}


def _check_record(v: Any, f: _Fields, where: str) -> dict[str, Any]:
    """A flat special-point record, every field it has checked by the special point's decoders; returned as read."""
    d = f.obj(v, where)
    codecs = _FLAT_CODECS
    for key, decode in (("model", f.string), ("kind", lambda x, field: f.choice(x, field, _KINDS)),
                        ("parameter", f.string)):
        f.take(d, where, key, decode)
    f.take(d, where, "value", lambda x, field: codecs["parameter"][1](f, x, field, {}))
    for key, name, _ in _FLAT_VIEW[1:]:
        dec = _FLAT_CHECKS.get(key) or codecs[name][1]
        f.take(d, where, key, lambda x, field, dec=dec: dec(f, x, field, {}), None)
    return d


# ---------------------------------------------------------------------------
# two-parameter curves: a view of their branch
# ---------------------------------------------------------------------------


def codimension_two_record(sp: SpecialPoint) -> dict[str, Any]:
    """A codimension-two point of a curve as ``saltation locus --json`` writes it.

    Parameters
    ----------
    sp : SpecialPoint
        A point of kind ``codimension_two``.

    Returns
    -------
    dict
        ``kind`` (the kinds on its two sides, ``"discontinuous_fold -> nonsmooth_flip"``; at a smooth point the
        curve's kind and the one it meets, ``"fold -> period_doubling"``), ``name`` (a smooth point's
        :class:`~saltation.kinds.CodimensionTwoKind` value, ``"fold_flip"``, ``"cusp"`` ...; null at a change of
        a corner's kind), ``value`` (the two parameters), ``accuracy`` and ``status``.
    """
    return {
        "kind": " -> ".join(sp.sides),
        "name": None if sp.codimension_two is None else sp.codimension_two.value,
        "value": [float(sp.parameter), float(sp.second_parameter)],
        "accuracy": float(sp.accuracy),
        "status": sp.status.value,
    }


def locus_record(curve: Branch) -> dict[str, Any]:
    """A two-parameter curve (:func:`saltation.special_points.loci.follow_locus`) as ``saltation locus --json``
    writes it.

    Parameters
    ----------
    curve : Branch
        The curve: a branch with ``curve_of`` set.

    Returns
    -------
    dict
        ``points`` (``[first, second parameter]`` pairs), ``stop_reason`` (each direction's reason in words: the
        branch's ``stop_detail``) and ``special_points`` (:func:`codimension_two_record` each).
    """
    return {
        "points": [[float(p.parameter), float(p.second_parameter)] for p in curve.points],
        "stop_reason": curve.stop_detail,
        "special_points": [codimension_two_record(c) for c in curve.special_points],
    }


# ---------------------------------------------------------------------------
# sweeps and period maps
# ---------------------------------------------------------------------------


def _start_rule(f: _Fields, v: Any, field: str) -> SweepStart:
    return f.choice(v, field, {k.value: k for k in SweepStart})


def _section_code(f: _Fields, v: Any, field: str) -> str:
    """A sweep's ``section``: ``"poincare"``, ``"maxima"`` (every file before sections could be named) or the code
    of a surface or an expression (:meth:`Section.from_code <saltation.sweeps.sections.Section.from_code>`)."""
    try:
        return Section.from_code(v).code if isinstance(v, str) else f.string(v, field)
    except ValueError:
        f.fail(field, f'expected one of "poincare", "maxima", "surface:NAME", "surface:NAME:WORD" or '
                      f'"expr:EXPRESSION:WORD" (WORD rising, falling or either), got {_show(v)}')


def sweep_to_dict(result: SweepResult) -> dict[str, Any]:
    """A sweep as a JSON-ready dictionary (non-finite numbers as strings), with the format header.

    Parameters
    ----------
    result : SweepResult
        The sweep.

    Returns
    -------
    dict
        The record :func:`sweep_from_dict` reads.

    Raises
    ------
    TypeError, ValueError
        If a value or state is not a number (the result was not built by :func:`~saltation.sweeps.sweep`).
    """
    return {
        **format_header(SWEEP_FORMAT),
        "model": result.model,
        "parameter": result.parameter_name,
        "section": result.section,
        "start": result.start.value,
        "state_names": list(result.state_names),
        "settings": dict(result.settings),
        "values": [_enc_float(v) for v in result.values],
        "counts": [int(c) for c in result.counts],
        "parameter_points": [_enc_float(v) for v in result.parameter_points],
        "states": [[_enc_float(v) for v in row] for row in result.states],
        "failures": [[_enc_float(v), msg] for v, msg in result.failures],
        **({} if result.largest_exponents is None else
           {"largest_exponents": [_enc_float(v) for v in result.largest_exponents]}),
    }


def sweep_from_dict(d: dict[str, Any], *, source: str = "sweep record") -> SweepResult:
    """The sweep :func:`sweep_to_dict` describes, every field checked.

    A record without ``"start"``, written before it was recorded, started each value from the previous
    one: :attr:`~saltation.sweeps.SweepStart.PREVIOUS`.  Its ``"section"`` is ``"poincare"``,
    ``"maxima"`` (as in every record written before sections could be named) or the code of a surface
    or an expression (:meth:`Section.from_code <saltation.sweeps.sections.Section.from_code>`).

    Parameters
    ----------
    d : dict
        A record as :func:`sweep_to_dict` returns it (or as read from its JSON file).
    source : str
        What ``d`` was read from, for the messages (a file name).

    Returns
    -------
    SweepResult

    Raises
    ------
    FileFormatError
        If ``d`` is not a sweep record, or a field is missing, of the wrong type or of the wrong
        length (``counts`` as long as ``values``, as many ``states`` and ``parameter_points`` as
        the counts add up to, each state as long as ``state_names``, each point's parameter its
        value's); the message names ``source`` and the field.
    """
    f = _Fields(source)
    d = _check_format(d, SWEEP_FORMAT, f)  # (or a name of an earlier release: FORMAT_NAMES)
    names = f.take(d, "", "state_names", f.strings)
    if not names:
        f.fail("state_names", "expected at least one state name")
    values = f.take(d, "", "values", lambda v, field: f.reals(v, field, finite=True))
    counts = f.take(d, "", "counts", lambda v, field: f.list(v, field, len(values)))
    counts = np.array([f.integer(c, f"counts[{k}]", minimum=0) for k, c in enumerate(counts)], dtype=int)
    total = int(counts.sum())
    points = f.take(d, "", "parameter_points", lambda v, field: f.reals(v, field, total, finite=True))
    expected = np.repeat(values, counts)
    for k in np.flatnonzero(points != expected)[:1]:
        f.fail(f"parameter_points[{k}]", f"is {float(points[k])!r}; by the counts it is a point of the value "
               f"{float(expected[k])!r}")
    rows = f.take(d, "", "states", lambda v, field: f.list(v, field, total))
    states = np.array([f.reals(r, f"states[{k}]", len(names)) for k, r in enumerate(rows)],
                      dtype=float).reshape(-1, len(names))
    failures = [f.list(v, f"failures[{k}]", 2) for k, v in enumerate(f.take(d, "", "failures", f.list))]
    return SweepResult(
        model=f.take(d, "", "model", f.string),
        parameter_name=f.take(d, "", "parameter", f.string),
        values=values,
        counts=counts,
        parameter_points=points,
        states=states,
        state_names=names,
        section=f.take(d, "", "section", lambda v, field: _section_code(f, v, field)),
        failures=tuple((f.real(v, f"failures[{k}][0]"), f.string(m, f"failures[{k}][1]"))
                       for k, (v, m) in enumerate(failures)),
        settings=dict(f.take(d, "", "settings", f.obj, {})),
        start=f.take(d, "", "start", lambda v, field: _start_rule(f, v, field), SweepStart.PREVIOUS),
        largest_exponents=f.take(d, "", "largest_exponents", lambda v, field: f.reals(v, field, len(values)), None),
    )


def period_map_to_dict(grid: PeriodMap) -> dict[str, Any]:
    """A period map as a JSON-ready dictionary, with the format header.

    Parameters
    ----------
    grid : PeriodMap
        The map.

    Returns
    -------
    dict
        The record :func:`period_map_from_dict` reads.

    Raises
    ------
    TypeError, ValueError
        If a value or period is not a number (the map was not built by :func:`~saltation.sweeps.period_map`).
    """
    return {
        **format_header(PERIOD_MAP_FORMAT),
        "model": grid.model,
        "parameter": grid.parameter_name,
        "parameter2": grid.parameter2_name,
        "start": grid.start.value,
        "values": [float(v) for v in grid.values],
        "values2": [float(v) for v in grid.values2],
        "periods": [[int(c) for c in row] for row in grid.periods],
        "max_period": int(grid.max_period),
        "failures": [[float(a), float(b), m] for a, b, m in grid.failures],
        "settings": dict(grid.settings),
        **({} if grid.largest_exponents is None else {"largest_exponents": [
            [_enc_float(v) for v in row] for row in grid.largest_exponents]}),
    }


def period_map_from_dict(d: dict[str, Any], *, source: str = "period map record") -> PeriodMap:
    """The map :func:`period_map_to_dict` describes, every field checked (a record without ``"start"`` is
    :attr:`~saltation.sweeps.SweepStart.PREVIOUS`).

    Parameters
    ----------
    d : dict
        A record as :func:`period_map_to_dict` returns it (or as read from its JSON file).
    source : str
        What ``d`` was read from, for the messages (a file name).

    Returns
    -------
    PeriodMap

    Raises
    ------
    FileFormatError
        If ``d`` is not a period map, or a field is missing, of the wrong type or of the wrong
        length (``periods`` one row of ``len(values)`` integers from -1 to ``max_period`` per
        value of ``values2``); the message names ``source`` and the field.
    """
    f = _Fields(source)
    d = _check_format(d, PERIOD_MAP_FORMAT, f)  # (or a name of an earlier release: FORMAT_NAMES)
    values = f.take(d, "", "values", lambda v, field: f.reals(v, field, finite=True))
    values2 = f.take(d, "", "values2", lambda v, field: f.reals(v, field, finite=True))
    max_period = f.take(d, "", "max_period", lambda v, field: f.integer(v, field, minimum=1))
    rows = f.take(d, "", "periods", lambda v, field: f.list(v, field, len(values2)))
    periods = np.array(
        [[f.integer(c, f"periods[{i}][{j}]", minimum=-1, maximum=max_period)
          for j, c in enumerate(f.list(row, f"periods[{i}]", len(values)))] for i, row in enumerate(rows)],
        dtype=int,
    ).reshape(len(values2), len(values))
    failures = [f.list(v, f"failures[{k}]", 3) for k, v in enumerate(f.take(d, "", "failures", f.list))]
    return PeriodMap(
        model=f.take(d, "", "model", f.string),
        parameter_name=f.take(d, "", "parameter", f.string),
        parameter2_name=f.take(d, "", "parameter2", f.string),
        values=values,
        values2=values2,
        periods=periods,
        max_period=max_period,
        failures=tuple((f.real(a, f"failures[{k}][0]"), f.real(b, f"failures[{k}][1]"),
                        f.string(m, f"failures[{k}][2]")) for k, (a, b, m) in enumerate(failures)),
        settings=dict(f.take(d, "", "settings", f.obj)),
        start=f.take(d, "", "start", lambda v, field: _start_rule(f, v, field), SweepStart.PREVIOUS),
        largest_exponents=f.take(d, "", "largest_exponents", lambda v, field: np.array(
            [f.reals(row, f"{field}[{k}]", len(values)) for k, row in enumerate(f.list(v, field, len(values2)))]), None),
    )


# ---------------------------------------------------------------------------
# periodic orbits
# ---------------------------------------------------------------------------


def _orbit_multiplier(m: complex) -> list[float] | str:
    """A multiplier of an orbit's record: ``[re, im]``, or ``"inf"`` where it is not finite."""
    return "inf" if not np.isfinite(m) else [float(m.real), float(m.imag)]


def orbit_to_dict(orbit: Any, system: Any) -> dict[str, Any]:
    """A periodic orbit as a JSON-ready dictionary (what ``saltation orbit --json`` prints).

    Parameters
    ----------
    orbit : PeriodicOrbit
        The orbit (:func:`saltation.orbits.shooting.find_periodic_orbit`).
    system : PiecewiseSystem
        Its model, for the names of its states and parameters.

    Returns
    -------
    dict
        ``model``, ``parameters`` (name to value), ``state_names``, ``state0``, ``t0``, ``period``,
        ``autonomous``, ``backward``, ``amplitude``, ``half_peak_to_peak``, ``multipliers``
        (forward-time ``[re, im]`` pairs, one that is not finite the string ``"inf"``),
        ``multiplier_magnitudes``, ``stable``, ``events`` (``[surface, time]`` pairs),
        ``event_modes`` (``[mode before, mode after]``), ``converged``, ``iterations``,
        ``residual_norm``, ``segments`` and ``mode0``.

    Raises
    ------
    AttributeError, TypeError, ValueError
        If ``orbit`` lacks a field of a periodic orbit, or a field is not a number.
    """
    mu = np.asarray(orbit.multipliers, dtype=complex)
    return {
        "model": system.name,
        "parameters": dict(zip(system.parameter_names, map(float, orbit.parameters))),
        "state_names": list(system.state_names),
        "state0": [float(v) for v in orbit.state0],
        "t0": float(orbit.t0),
        "period": float(orbit.period),
        "autonomous": bool(orbit.autonomous),
        "backward": bool(orbit.backward),
        "amplitude": float(orbit.amplitude),
        "half_peak_to_peak": float(orbit.half_peak_to_peak),
        "multipliers": [_orbit_multiplier(m) for m in mu],
        "multiplier_magnitudes": ["inf" if not np.isfinite(m) else float(abs(m)) for m in mu],
        "stable": bool(orbit.stable),
        "events": [[str(e.surface), float(e.t)] for e in orbit.trajectory.events],
        "event_modes": [[e.mode_from, e.mode_to] for e in orbit.trajectory.events],
        "converged": bool(orbit.converged),
        "iterations": int(orbit.iterations),
        "residual_norm": float(orbit.residual_norm),
        "segments": int(orbit.segments),
        "mode0": orbit.mode0,
    }
