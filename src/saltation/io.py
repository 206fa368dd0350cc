"""Export and reload of branches and special points (JSON and CSV).

Formats
-------
Branch JSON (``save_branch_json``)
    One object with ``"format": "saltation.branch"`` and ``"version": 1``, the branch's
    metadata, its points and its special points. It holds everything a :class:`Branch`
    holds, so ``load_branch_json(save_branch_json(b))`` gives back an equal branch.
Diagram JSON (``save_diagram_json``)
    ``"format": "saltation.diagram"``: a list of branch objects as above.
Branch CSV (``save_branch_csv``)
    One row per branch point with the columns ``parameter, period, amplitude,
    half_peak_to_peak, stable, event_labels, step, iterations, state_0 .. state_{n-1}`` and, per
    multiplier ``i``, ``mu{i}_re, mu{i}_im, mu{i}_abs``. Events are joined with ``";"``;
    ``stable`` is ``true``/``false``. The CSV holds the points only: the branch's metadata and
    its special points go to a side file ``<stem>.meta.json`` (the branch JSON without its
    points), which ``load_branch_csv`` reads when it is present.
Special-point records (``special_point_record``, ``save_special_points_json``)
    The public summary of a located special point, a flat JSON object per point.

Numbers are written at full precision (Python's shortest round-trip ``repr``), so a round
trip is lossless. JSON has no infinity or NaN: a non-finite real is written as the string
``"inf"``, ``"-inf"`` or ``"nan"``; a complex number is a pair ``[re, im]`` and an infinite
multiplier (the point at infinity, stored as ``complex(inf, 0)``) is the string ``"inf"``.
In CSV, non-finite values are written ``inf``, ``-inf`` and ``nan``, which Python's
``float`` reads back.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterable, Sequence
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from .branch import Branch, BranchKind, BranchPoint, SpecialPoint, SpecialPointKind, StopReason

__all__ = [
    "branch_from_dict",
    "branch_to_dict",
    "csv_metadata_path",
    "load_branch_csv",
    "load_branch_points_csv",
    "load_branch_json",
    "load_diagram_json",
    "load_special_points_json",
    "save_branch_csv",
    "save_branch_json",
    "save_diagram_json",
    "save_special_points_json",
    "special_point_record",
]

BRANCH_FORMAT = "saltation.branch"
DIAGRAM_FORMAT = "saltation.diagram"
FORMAT_VERSION = 1
EVENT_SEPARATOR = ";"

PathType = str | PathLike[str]


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


def _dec_float(v: float | int | str) -> float:
    return float(v)


def _enc_complex(z: complex) -> list[float | str] | str:
    """A complex number as ``[re, im]``; an infinite one as ``"inf"``."""
    z = complex(z)
    if math.isinf(z.real) or math.isinf(z.imag):
        return "inf"
    return [_enc_float(z.real), _enc_float(z.imag)]


def _dec_complex(v: Sequence[float | str] | str) -> complex:
    if isinstance(v, str):
        if v != "inf":
            raise ValueError(f"a complex number must be [re, im] or 'inf', got {v!r}")
        return complex(math.inf, 0.0)
    re, im = v
    return complex(_dec_float(re), _dec_float(im))


def _enc_complex_array(a: np.ndarray | None) -> list[Any] | None:
    if a is None:
        return None
    return [_enc_complex(z) for z in np.asarray(a, dtype=complex).ravel()]


def _dec_complex_array(v: list[Any] | None) -> np.ndarray | None:
    if v is None:
        return None
    return np.array([_dec_complex(z) for z in v], dtype=complex)


def _enc_real_array(a: np.ndarray | None) -> list[Any] | None:
    """A real array of any shape as nested lists of encoded floats."""
    if a is None:
        return None
    a = np.asarray(a, dtype=float)
    if a.ndim == 0:
        return _enc_float(a)  # type: ignore[return-value]
    return [_enc_real_array(row) for row in a]  # type: ignore[misc]


def _dec_real_array(v: list[Any] | None) -> np.ndarray | None:
    if v is None:
        return None

    def walk(x: Any) -> Any:
        return [walk(y) for y in x] if isinstance(x, list) else _dec_float(x)

    return np.array(walk(v), dtype=float)


# ---------------------------------------------------------------------------
# dataclasses <-> plain dicts
# ---------------------------------------------------------------------------


def _point_to_dict(p: BranchPoint) -> dict[str, Any]:
    return {
        "parameter": _enc_float(p.parameter),
        "state": _enc_real_array(p.state),
        "period": _enc_float(p.period),
        "amplitude": _enc_float(p.amplitude),
        "half_peak_to_peak": _enc_float(p.half_peak_to_peak),
        "multipliers": _enc_complex_array(p.multipliers),
        "stable": bool(p.stable),
        "event_labels": list(p.event_labels),
        "step": _enc_float(p.step),
        "iterations": int(p.iterations),
    }


def _point_from_dict(d: dict[str, Any]) -> BranchPoint:
    return BranchPoint(
        parameter=_dec_float(d["parameter"]),
        state=_dec_real_array(d["state"]),
        period=_dec_float(d["period"]),
        amplitude=_dec_float(d["amplitude"]),
        half_peak_to_peak=_dec_float(d["half_peak_to_peak"]),
        multipliers=_dec_complex_array(d["multipliers"]),
        stable=bool(d["stable"]),
        event_labels=tuple(d["event_labels"] if "event_labels" in d else d["events"]),  # (files before 2026-11-24: "events")
        step=_dec_float(d["step"]),
        iterations=int(d["iterations"]),
    )


def _special_point_to_dict(sp: SpecialPoint) -> dict[str, Any]:
    return {
        "kind": sp.kind.value,
        "parameter": _enc_float(sp.parameter),
        "bracket": [_enc_float(b) for b in sp.bracket],
        "accuracy": _enc_float(sp.accuracy),
        "index": int(sp.index),
        "state": _enc_real_array(sp.state),
        "period": _enc_float(sp.period),
        "amplitude": _enc_float(sp.amplitude),
        "multipliers": _enc_complex_array(sp.multipliers),
        "multipliers_minus": _enc_complex_array(sp.multipliers_minus),
        "multipliers_plus": _enc_complex_array(sp.multipliers_plus),
        "monodromy_minus": _enc_real_array(sp.monodromy_minus),
        "monodromy_plus": _enc_real_array(sp.monodromy_plus),
        "crossing_q": None if sp.crossing_q is None else _enc_float(sp.crossing_q),
        "crossing_point": None if sp.crossing_point is None else _enc_complex(sp.crossing_point),
        "event_labels_minus": list(sp.event_labels_minus),
        "event_labels_plus": list(sp.event_labels_plus),
        "note": sp.note,
        "multipliers_accuracy": _enc_float(sp.multipliers_accuracy),
        "limits": sp.limits,
        "touch_surface": sp.touch_surface,
        "touch_mode": sp.touch_mode,
        "touch_time": _enc_float(sp.touch_time),
    }


def _special_point_from_dict(d: dict[str, Any]) -> SpecialPoint:
    lo, hi = d["bracket"]
    return SpecialPoint(
        kind=SpecialPointKind(d["kind"]),
        parameter=_dec_float(d["parameter"]),
        bracket=(_dec_float(lo), _dec_float(hi)),
        accuracy=_dec_float(d["accuracy"]),
        index=int(d["index"]),
        state=_dec_real_array(d["state"]),
        period=_dec_float(d["period"]),
        amplitude=_dec_float(d["amplitude"]),
        multipliers=_dec_complex_array(d.get("multipliers")),
        multipliers_minus=_dec_complex_array(d.get("multipliers_minus")),
        multipliers_plus=_dec_complex_array(d.get("multipliers_plus")),
        monodromy_minus=_dec_real_array(d.get("monodromy_minus")),
        monodromy_plus=_dec_real_array(d.get("monodromy_plus")),
        crossing_q=None if d.get("crossing_q") is None else _dec_float(d["crossing_q"]),
        crossing_point=None if d.get("crossing_point") is None else _dec_complex(d["crossing_point"]),
        event_labels_minus=tuple(d.get("event_labels_minus", d.get("events_minus", ()))),
        event_labels_plus=tuple(d.get("event_labels_plus", d.get("events_plus", ()))),
        note=d.get("note", ""),
        multipliers_accuracy=_dec_float(d.get("multipliers_accuracy", "nan")),
        limits=d.get("limits", ""),
        touch_surface=d.get("touch_surface", ""),
        touch_mode=d.get("touch_mode", ""),
        touch_time=_dec_float(d.get("touch_time", "nan")),
    )


def _enc_stop(reason: StopReason | None) -> str | None:
    """A stop reason by its (lower-case) name; its value is a sentence that may be reworded."""
    return None if reason is None else reason.name.lower()


def _dec_stop(name: str | None) -> StopReason | None:
    return None if name is None else StopReason[name.upper()]


def _metadata_to_dict(branch: Branch) -> dict[str, Any]:
    return {
        "format": BRANCH_FORMAT,
        "version": FORMAT_VERSION,
        "model": branch.model,
        "parameter_name": branch.parameter_name,
        "kind": branch.kind.value,
        "backward": bool(branch.backward),
        "autonomous": bool(branch.autonomous),
        "label": branch.label,
        "stop_reason": _enc_stop(branch.stop_reason),
        "stop_reasons": [_enc_stop(r) for r in branch.stop_reasons],
        "fixed_parameters": {str(k): _enc_float(v) for k, v in branch.fixed_parameters.items()},
        "special_points": [_special_point_to_dict(sp) for sp in branch.special_points],
    }


def branch_to_dict(branch: Branch) -> dict[str, Any]:
    """The branch as a JSON-ready dict (the content of a branch JSON file).

    Parameters
    ----------
    branch : Branch

    Returns
    -------
    dict
        Metadata, ``points`` and ``special_points``, encoded as described in the module
        docstring (no bare infinities or NaNs, complex numbers as ``[re, im]``).
    """
    d = _metadata_to_dict(branch)
    d["points"] = [_point_to_dict(p) for p in branch.points]
    return d


def _check_format(d: dict[str, Any], expected: str, where: str) -> None:
    fmt = d.get("format")
    if fmt != expected:
        raise ValueError(f"{where}: expected format {expected!r}, found {fmt!r}")
    version = d.get("version")
    if version != FORMAT_VERSION:
        raise ValueError(f"{where}: unsupported {expected} version {version!r} (this library reads {FORMAT_VERSION})")


def branch_from_dict(d: dict[str, Any], *, points: list[BranchPoint] | None = None) -> Branch:
    """Rebuild a :class:`Branch` from :func:`branch_to_dict` output.

    Parameters
    ----------
    d : dict
        Branch dict; its ``points`` entry is used unless ``points`` is given.
    points : list of BranchPoint, optional
        Points read elsewhere (from a CSV file).
    """
    _check_format(d, BRANCH_FORMAT, "branch")
    if points is None:
        points = [_point_from_dict(p) for p in d.get("points", [])]
    return Branch(
        model=d["model"],
        parameter_name=d["parameter_name"],
        kind=BranchKind(d["kind"]),
        backward=bool(d.get("backward", False)),
        points=points,
        special_points=[_special_point_from_dict(s) for s in d.get("special_points", [])],
        stop_reason=_dec_stop(d.get("stop_reason")),
        stop_reasons=[_dec_stop(r) for r in d.get("stop_reasons", [])],
        fixed_parameters={k: _dec_float(v) for k, v in d.get("fixed_parameters", {}).items()},
        label=d.get("label", ""),
        autonomous=bool(d.get("autonomous", False)),
    )


def write_json(obj: Any, path: PathType, *, allow_nan: bool = True) -> Path:
    """Write ``obj`` as indented JSON with a final newline, creating the folder; every JSON file the
    library writes goes through here.  ``allow_nan`` False refuses NaN and infinities (the branch
    formats encode them as strings first)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(obj, indent=1, allow_nan=allow_nan) + "\n", encoding="utf-8")
    return path


def _write_json(obj: Any, path: PathType) -> Path:
    return write_json(obj, path, allow_nan=False)


def _read_json(path: PathType) -> Any:
    with Path(path).open(encoding="utf-8") as fh:
        return json.load(fh)


# ---------------------------------------------------------------------------
# branch JSON and diagram JSON
# ---------------------------------------------------------------------------


def save_branch_json(branch: Branch, path: PathType) -> Path:
    """Write a branch, with its special points, to a JSON file.

    Parameters
    ----------
    branch : Branch
    path : str or path-like

    Returns
    -------
    Path
        The file written.
    """
    return _write_json(branch_to_dict(branch), path)


def load_branch_json(path: PathType) -> Branch:
    """Read a branch written by :func:`save_branch_json`.

    Raises
    ------
    ValueError
        If the file is not a branch file of a supported version.
    """
    return branch_from_dict(_read_json(path))


def save_diagram_json(branches: Iterable[Branch], path: PathType) -> Path:
    """Write several branches (a bifurcation diagram) to one JSON file.

    Parameters
    ----------
    branches : iterable of Branch
    path : str or path-like

    Returns
    -------
    Path
        The file written.
    """
    obj = {
        "format": DIAGRAM_FORMAT,
        "version": FORMAT_VERSION,
        "branches": [branch_to_dict(b) for b in branches],
    }
    return _write_json(obj, path)


def load_diagram_json(path: PathType) -> list[Branch]:
    """Read the branches written by :func:`save_diagram_json`."""
    d = _read_json(path)
    _check_format(d, DIAGRAM_FORMAT, str(path))
    return [branch_from_dict(b) for b in d["branches"]]


# ---------------------------------------------------------------------------
# branch CSV
# ---------------------------------------------------------------------------


def csv_metadata_path(path: PathType) -> Path:
    """The side file holding a CSV branch's metadata and special points: ``<stem>.meta.json``."""
    path = Path(path)
    return path.with_name(path.stem + ".meta.json")


def _csv_float(x: float) -> str:
    return repr(float(x))


def save_branch_csv(branch: Branch, path: PathType, *, metadata: bool = True) -> Path:
    """Write a branch's points to CSV, one row per point.

    Parameters
    ----------
    branch : Branch
        All points must have the same number of states and of multipliers.
    path : str or path-like
        The CSV file.
    metadata : bool
        Also write the branch's metadata and special points to ``<stem>.meta.json``
        (see :func:`csv_metadata_path`), so that :func:`load_branch_csv` restores the
        whole branch.

    Returns
    -------
    Path
        The CSV file written.

    Raises
    ------
    ValueError
        If the points differ in their number of states or multipliers, or an event label
        contains the separator ``";"``.
    """
    path = Path(path)
    n_state = len(branch.points[0].state) if branch.points else 0
    n_mu = len(branch.points[0].multipliers) if branch.points else 0
    header = ["parameter", "period", "amplitude", "half_peak_to_peak", "stable", "event_labels", "step", "iterations"]
    header += [f"state_{i}" for i in range(n_state)]
    for i in range(n_mu):
        header += [f"mu{i}_re", f"mu{i}_im", f"mu{i}_abs"]
    with path.open("w", encoding="utf-8", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        for k, p in enumerate(branch.points):
            if len(p.state) != n_state or len(p.multipliers) != n_mu:
                raise ValueError(
                    f"point {k} has {len(p.state)} states and {len(p.multipliers)} multipliers; "
                    f"point 0 has {n_state} and {n_mu}"
                )
            bad = [e for e in p.event_labels if EVENT_SEPARATOR in e]
            if bad:
                raise ValueError(f"point {k}: event label {bad[0]!r} contains the separator {EVENT_SEPARATOR!r}")
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
                row += [_csv_float(z.real), _csv_float(z.imag), _csv_float(abs(z))]
            writer.writerow(row)
    if metadata:
        _write_json(_metadata_to_dict(branch), csv_metadata_path(path))
    return path


def _parse_bool(s: str) -> bool:
    v = s.strip().lower()
    if v in ("true", "1"):
        return True
    if v in ("false", "0"):
        return False
    raise ValueError(f"not a boolean: {s!r}")


def load_branch_points_csv(path: PathType) -> list[BranchPoint]:
    """Read the points of a branch CSV written by :func:`save_branch_csv`.

    The ``mu{i}_abs`` columns are redundant and ignored; multipliers are rebuilt from the
    real and imaginary parts.
    """
    with Path(path).open(encoding="utf-8", newline="") as fh:
        reader = csv.reader(fh)
        header = next(reader)
        col = {name: j for j, name in enumerate(header)}
        state_cols = sorted((int(h[6:]), j) for h, j in col.items() if h.startswith("state_"))
        n_mu = sum(1 for h in header if h.startswith("mu") and h.endswith("_re"))
        points = []
        for row in reader:
            if not row:
                continue
            events = row[col["event_labels" if "event_labels" in col else "events"]]
            points.append(
                BranchPoint(
                    parameter=float(row[col["parameter"]]),
                    state=np.array([float(row[j]) for _, j in state_cols], dtype=float),
                    period=float(row[col["period"]]),
                    amplitude=float(row[col["amplitude"]]),
                    half_peak_to_peak=float(row[col["half_peak_to_peak"]]),
                    multipliers=np.array(
                        [complex(float(row[col[f"mu{i}_re"]]), float(row[col[f"mu{i}_im"]])) for i in range(n_mu)],
                        dtype=complex,
                    ),
                    stable=_parse_bool(row[col["stable"]]),
                    event_labels=tuple(events.split(EVENT_SEPARATOR)) if events else (),
                    step=float(row[col["step"]]),
                    iterations=int(row[col["iterations"]]),
                )
            )
    return points


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
    """
    points = load_branch_points_csv(path)
    meta = csv_metadata_path(path)
    if meta.exists():
        return branch_from_dict(_read_json(meta), points=points)
    return Branch(model=model, parameter_name=parameter_name, kind=kind, points=points)


# ---------------------------------------------------------------------------
# public special-point records
# ---------------------------------------------------------------------------


def special_point_record(sp: SpecialPoint, model: str, parameter: str) -> dict[str, Any]:
    """The public record of a special point, as written to ``special_points.json``.

    Parameters
    ----------
    sp : SpecialPoint
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
        multipliers' error) and ``limits`` (how the one-sided multipliers were obtained:
        ``"exact"``, ``"nearest_saltation"``, ``"nearest_orbits"``); for a grazing or a sliding
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
    rec["limits"] = sp.limits
    if sp.touch_surface:
        rec["touch_surface"] = sp.touch_surface
        rec["touch_mode"] = sp.touch_mode
        rec["touch_time"] = _enc_float(sp.touch_time)
    return rec


def save_special_points_json(records: Iterable[dict[str, Any]], path: PathType) -> Path:
    """Write special-point records (from :func:`special_point_record`) as a JSON array.

    Returns
    -------
    Path
        The file written.
    """
    return _write_json(list(records), path)


def load_special_points_json(path: PathType) -> list[dict[str, Any]]:
    """Read the records written by :func:`save_special_points_json` (as plain dicts)."""
    return _read_json(path)
