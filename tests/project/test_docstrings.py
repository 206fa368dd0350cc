"""Every public callable's docstring has its numpydoc sections.

The callables are collected, not listed: every callable of ``saltation.__all__``, and the public
functions and classes of the modules in :data:`MODULES` (their ``__all__``; for a module without
one, the public functions and classes it defines), with the public methods those classes define
(not the ones they inherit).  A section is a line with its name followed by a line of dashes.

The rules:

* a function or method has a docstring, with ``Parameters`` when it takes parameters (other than
  ``self`` or ``cls``), naming each of them, and ``Returns`` or ``Yields`` when it returns
  something other than None (by its return annotation, or, without one, by a ``return`` of a
  value or a ``yield`` in its body).  A method without a docstring of its own shows its base
  class's (``inspect.getdoc``), which must then fit it;
* a module-level function also has ``Raises``, except those in :data:`RAISES_EXEMPT`, each with
  the reason: array arithmetic or record building that raises nothing of its own;
* a class documents its constructor: ``Parameters`` (naming each of them) when ``__init__`` takes
  any, ``Raises`` when ``__init__`` or ``__post_init__`` raises.  A dataclass or named tuple may
  document its fields as ``Attributes`` instead (they are its constructor's parameters);
* callables whose algorithm comes from the literature (:data:`REFERENCES_REQUIRED`) have
  ``References``.

Not checked: exceptions (their docstring says when they are raised, and their constructors are
the library's own), enums (members, no constructor) and protocols (no constructor; their methods
are checked); and the modules another change owns (:data:`SKIPPED_MODULES`).  Properties are
documented as attributes and are not checked.

The test imports the package and reads docstrings and signatures only: nothing is computed.
"""

from __future__ import annotations

import ast
import dataclasses
import enum
import importlib
import inspect
import re
import textwrap
from typing import Protocol

import pytest

import saltation

#: Modules whose public functions and classes are checked (with ``saltation.__all__``).
MODULES = (
    "saltation.special_points.follow",
    "saltation.models.trilinear",
    "saltation.orbits.problem",
    "saltation.orbits.single",
    "saltation.orbits.multiple",
    "saltation.orbits.equilibria",
    "saltation.orbits.seam",
    "saltation.orbits.records",
    "saltation.orbits.shooting",
    "saltation.orbits.floquet",
    "saltation.orbits.conditions",
    "saltation.orbits.conditions.shot",
    "saltation.orbits.conditions.base",
    "saltation.orbits.conditions.tangency",
    "saltation.orbits.conditions.arrival",
    "saltation.orbits.conditions.multiplier",
    "saltation.orbits.conditions.neimark_sacker",
    "saltation.orbits.conditions.conditioned",
    "saltation.orbits.conditions.segmented",
    "saltation.orbits.conditions.joining",
    "saltation.orbits.start",
    "saltation.orbits.measures",
    "saltation.orbits.phase_response",
    "saltation.orbits.second_order",
    "saltation.orbits.criticality",
    "saltation.progress",
    "saltation.branches.monitors",
    "saltation.special_points.continuation",
    "saltation.special_points.loci",
    "saltation.special_points.codimension_two",
    "saltation.special_points.grazing",
    "saltation.special_points.sliding",
    "saltation.special_points.detection",
    "saltation.special_points.detector",
    "saltation.special_points.context",
    "saltation.orbits.classification",
    "saltation.special_points.smooth",
    "saltation.special_points.nonsmooth",
    "saltation.special_points.symmetric",
    "saltation.special_points.points",
    "saltation.special_points.branch_switching",
    "saltation.branches.continuation",
    "saltation.engine.flow",
    "saltation.engine.chatter",
    "saltation.engine.buildtime",
    "saltation.apps.sweeps",
    "saltation.sweeps.sections",
    "saltation.output.io",
    "saltation.model.regularize",
    "saltation.model.sides",
    "saltation.model.contacts",
    "saltation.model.symmetry",
    "saltation.orbits.symmetry",
    "saltation.orbits.border_collision",
    "saltation.orbits.parameter_jacobian",
    "saltation.special_points.sensitivity",
)

#: Modules whose docstrings are being rewritten by another change at the same time.
SKIPPED_MODULES = frozenset({
    "saltation.model.system",
    "saltation.output.plotting",
    "saltation.apps.paper",
    "saltation.apps.diagram",
})

#: Functions without a ``Raises`` section, and why.
RAISES_EXEMPT = {
    "saltation.progress.enabled": "reads a setting",
    "saltation.progress.set_enabled": "stores a setting",
    "saltation.progress.bar": "makes a tqdm bar",
    "saltation.orbits.measures.measure_state": "arithmetic on the given state",
    "saltation.model.sides.on_its_side": "rewrites a sympy expression; sympy's own errors are its",
    "saltation.orbits.measures.measure_label": "builds a text",
    "saltation.branches.monitors.illinois_on_secant": "the test function's and the corrector's errors are theirs; "
                                                       "a point the corrector cannot reach ends the iteration",
    "saltation.special_points.loci.curve_stops": "record building",
    "saltation.special_points.codimension_two.others_of": "array arithmetic on the given multipliers",
    "saltation.special_points.points.two_sides": "record building",
    "saltation.orbits.single.stationary_floor": "arithmetic on the given tolerances and size",
    "saltation.orbits.problem.residual_norm": "array arithmetic",
    "saltation.orbits.seam.leave_sliding_at_the_end": "linear algebra on the shot's end; the model's functions raise nothing here",
    "saltation.orbits.problem.bordered_solve": "a LAPACK solve that reports a singular matrix by returning None",
    "saltation.orbits.records.amplitude_measures": "array arithmetic on a trajectory's extremes",
    "saltation.orbits.records.orbit_events": "reads a trajectory's events",
    "saltation.orbits.records.event_ids": "reads a trajectory's event log",
    "saltation.orbits.records.event_labels": "reads a trajectory's event log",
    "saltation.engine.flow.dense_evaluate": "array arithmetic on the given steps",
    "saltation.engine.chatter.accumulation_time": "arithmetic on the given times",
    "saltation.model.contacts.sticking_twins": "reads the model's transitions",
    "saltation.engine.buildtime.estimate_build": "an unreadable record or a failed test compile gives no estimate",
    "saltation.engine.buildtime.record_build": "a folder that cannot be written is left alone",
    "saltation.engine.buildtime.timed": "records through record_build; the block's own errors pass through",
    "saltation.engine.buildtime.expected_cores": "arithmetic on the load average (none: a guess)",
    "saltation.engine.buildtime.wall_seconds": "arithmetic on the given work",
    "saltation.engine.buildtime.probe_seconds": "a compile that fails gives None",
    "saltation.orbits.floquet.reciprocal": "array arithmetic on the given multipliers",
    "saltation.orbits.second_order.compose": "array arithmetic on the given jets",
    "saltation.orbits.second_order.chatter_errors": "array arithmetic on the given derivatives",
    "saltation.orbits.floquet.sort_multipliers": "sorts the given values",
    "saltation.orbits.floquet.trivial_multiplier_error": "array arithmetic on the given multipliers",
    "saltation.orbits.floquet.is_stable": "array arithmetic on the given multipliers",
    "saltation.orbits.start.period_from_events": "reads the events of a computed trajectory",
    "saltation.orbits.conditions.shot.segment_of": "arithmetic on the given instant and bounds",
    "saltation.orbits.start.candidate_starts": "builds arrays",
    "saltation.branches.corrector.canonical_events": "rotates a tuple",
    "saltation.special_points.points.special_point_between": "builds a record from two solutions",
    "saltation.special_points.points.smooth_point": "builds a record from a located solution",
    "saltation.special_points.points.period_doubling_of_half_point": "builds a record from a located orbit",
    "saltation.special_points.points.symmetry_breaking_point": "builds a record from a located orbit",
    "saltation.special_points.points.unlocated_symmetry_breaking": "builds a record from two solutions",
    "saltation.special_points.points.on_surface_point": "builds a record from computed limits",
    "saltation.special_points.points.sliding_bifurcation_point":
        "the location's errors are caught: it returns None instead",
    "saltation.special_points.grazing.location_tolerances": "copies tolerances with smaller values",
    "saltation.special_points.grazing.indicator_rate": "evaluates the model at a computed state",
    "saltation.special_points.grazing.growth_exponent": "a least-squares fit of the given numbers",
    "saltation.special_points.sliding.sliding_change": "compares the event sequences of computed trajectories",
    "saltation.sweeps.sweeps.attractor_period": "array arithmetic on the given samples",
    "saltation.output.codecs.branch_to_dict": "encodes a branch",
    "saltation.output.io.csv_metadata_path": "builds a path",
    "saltation.output.codecs.special_point_record": "encodes a special point",
    "saltation.special_points.symmetric.symmetric_crossing": "relabels a given classification",
    "saltation.orbits.symmetry.symmetry_breaking_test": "array arithmetic on the given multipliers",
}

#: Callables whose algorithm comes from the literature: they cite it.
REFERENCES_REQUIRED = (
    "saltation.orbits.second_order.period_map_derivatives",
    "saltation.orbits.second_order.run_jets",
    "saltation.orbits.criticality.criticality",
    "saltation.engine.flow.Flow.run",
    "saltation.engine.chatter.run_through_accumulations",
    "saltation.engine.chatter.accumulation_time",
    "saltation.engine.flow.Flow.transition_jump",
    "saltation.engine.flow.simulate",
    "saltation.engine.flow.dense_evaluate",
    "saltation.orbits.floquet.product_eigenvalues",
    "saltation.orbits.floquet.set_valued_multipliers",
    "saltation.orbits.single.ShootingProblem",
    "saltation.orbits.multiple.MultipleShootingProblem",
    "saltation.orbits.start.find_periodic_orbit",
    "saltation.orbits.conditions.conditioned.ConditionedProblem",
    "saltation.orbits.conditions.multiplier.MultiplierCondition",
    "saltation.orbits.conditions.neimark_sacker.NeimarkSackerCondition",
    "saltation.orbits.conditions.tangency.Tangency",
    "saltation.orbits.conditions.arrival.ArrivalTangency",
    "saltation.orbits.conditions.arrival.CubicTangency",
    "saltation.branches.continuation.Continuation",
    "saltation.branches.continuation.continue_branch",
    "saltation.special_points.continuation.continue_branch",
    "saltation.special_points.continuation.continue_orbit",
    "saltation.orbits.classification.classify_nonsmooth",
    "saltation.special_points.points.grazing_point",
    "saltation.special_points.smooth.locate_smooth",
    "saltation.special_points.grazing.locate_grazing",
    "saltation.special_points.sliding.locate_tangent_arrival",
    "saltation.special_points.sliding.locate_adding_sliding",
    "saltation.special_points.loci.follow_locus",
    "saltation.special_points.loci.MultiplierCurve",
    "saltation.special_points.loci.NeimarkSackerCurve",
    "saltation.special_points.branch_switching.follow_period_doubled_branch",
    "saltation.model.regularize.regularize",
)

_DASHES = re.compile(r"^-{3,}$")


def _sections(doc: str) -> dict[str, list[str]]:
    """The docstring's sections: each header's name and the lines under it (dedented docstring)."""
    lines = doc.splitlines()
    heads = [i for i in range(len(lines) - 1) if lines[i].strip() and _DASHES.match(lines[i + 1].strip())]
    out = {}
    for k, i in enumerate(heads):
        end = heads[k + 1] if k + 1 < len(heads) else len(lines)
        out[lines[i].strip()] = lines[i + 2 : end]
    return out


def _documented_names(lines: list[str]) -> set[str]:
    """The names of a Parameters section's entries (``a, b : type`` gives ``a`` and ``b``)."""
    names = set()
    for line in lines:
        if line.strip() and not line.startswith((" ", "\t")):
            for name in line.split(" : ")[0].split(","):
                names.add(name.strip().lstrip("*").rstrip(":").strip())
    return names


def _qualified(obj) -> str:
    return f"{obj.__module__}.{obj.__qualname__}"


def _public_callables() -> dict[str, object]:
    """Every callable to check, by its qualified name (where it is defined)."""
    found = {}

    def add(obj):
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and obj.__module__ not in SKIPPED_MODULES:
            found[_qualified(obj)] = obj

    for name in saltation.__all__:
        add(getattr(saltation, name))
    for modname in MODULES:
        module = importlib.import_module(modname)
        names = getattr(module, "__all__", None)
        if names is None:
            names = [k for k, v in vars(module).items()
                     if (inspect.isfunction(v) or inspect.isclass(v)) and v.__module__ == modname]
        for name in names:
            if not name.startswith("_"):
                add(getattr(module, name))
    return found


def _skipped_class(cls) -> bool:
    return (issubclass(cls, BaseException) or issubclass(cls, enum.Enum)
            or (issubclass(cls, Protocol) and getattr(cls, "_is_protocol", False)))


def _is_record(cls) -> bool:
    """A dataclass or a named tuple: its constructor's parameters are its fields."""
    return dataclasses.is_dataclass(cls) or (issubclass(cls, tuple) and hasattr(cls, "_fields"))


def _methods(cls) -> dict[str, object]:
    """The public methods a class defines itself (plain, static and class methods; not properties)."""
    out = {}
    for name, value in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(value, (staticmethod, classmethod)):
            value = value.__func__
        if inspect.isfunction(value):
            out[f"{_qualified(cls)}.{name}"] = (cls, name, value)
    return out


CALLABLES = _public_callables()
FUNCTIONS = {k: v for k, v in CALLABLES.items() if inspect.isfunction(v)}
CLASSES = {k: v for k, v in CALLABLES.items() if inspect.isclass(v) and not _skipped_class(v)}
METHODS = {k: m for cls in CLASSES.values() for k, m in _methods(cls).items()}
METHODS.update({k: m for cls in CALLABLES.values() if inspect.isclass(cls) and _skipped_class(cls)
                and issubclass(cls, Protocol) for k, m in _methods(cls).items()})


def _function_node(func) -> ast.FunctionDef | None:
    try:
        source = textwrap.dedent(inspect.getsource(func))
    except (OSError, TypeError):
        return None
    tree = ast.parse(source)
    return next((n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))), None)


def _own_nodes(node):
    """The nodes of a function's body, without those of the functions and classes defined in it."""
    stack = list(node.body)
    while stack:
        n = stack.pop()
        yield n
        for child in ast.iter_child_nodes(n):
            if not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
                stack.append(child)


def _returns_something(func) -> bool:
    annotation = inspect.signature(func).return_annotation
    if annotation is not inspect.Signature.empty:
        return annotation not in (None, "None", type(None), "NoReturn")
    node = _function_node(func)
    if node is None:
        return False
    return any((isinstance(n, ast.Return) and n.value is not None
                and not (isinstance(n.value, ast.Constant) and n.value.value is None))
               or isinstance(n, (ast.Yield, ast.YieldFrom)) for n in _own_nodes(node))


def _raises(func) -> bool:
    """Whether a function's own body has a ``raise`` statement."""
    node = _function_node(func)
    return node is not None and any(isinstance(n, ast.Raise) for n in _own_nodes(node))


def _parameters(func, *, bound: bool) -> list[str]:
    params = list(inspect.signature(func).parameters.values())
    if bound and params and params[0].name in ("self", "cls"):
        params = params[1:]
    return [p.name for p in params]


def _check_signature_documented(name: str, doc: str, params: list[str]) -> None:
    sections = _sections(doc)
    if not params:
        return
    assert "Parameters" in sections, f"{name}: no Parameters section (it takes {params})"
    missing = [p for p in params if p not in _documented_names(sections["Parameters"])]
    assert not missing, f"{name}: Parameters does not name {missing}"


def _check_returns(name: str, doc: str, func) -> None:
    if _returns_something(func):
        sections = _sections(doc)
        assert "Returns" in sections or "Yields" in sections, f"{name}: it returns something but has no Returns"


def test_the_collection_finds_the_public_api():
    assert "saltation.orbits.start.find_periodic_orbit" in FUNCTIONS
    assert "saltation.engine.flow.Flow.run" in METHODS
    assert "saltation.orbits.conditions.conditioned.ConditionedProblem" in CLASSES
    assert "saltation.branches.continuation.Detector.check" in METHODS  # a protocol's methods are checked
    assert len(FUNCTIONS) > 60 and len(CLASSES) > 40 and len(METHODS) > 100


def test_the_exemptions_name_existing_functions():
    stale = sorted(set(RAISES_EXEMPT) - set(FUNCTIONS))
    assert not stale, f"exempt functions that are not public functions (any more): {stale}"
    listed = sorted(set(REFERENCES_REQUIRED) - set(FUNCTIONS) - set(CLASSES) - set(METHODS))
    assert not listed, f"REFERENCES_REQUIRED names unknown callables: {listed}"


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_function_docstring(name):
    func = FUNCTIONS[name]
    doc = inspect.getdoc(func)
    assert doc, f"{name}: no docstring"
    _check_signature_documented(name, doc, _parameters(func, bound=False))
    _check_returns(name, doc, func)
    if name not in RAISES_EXEMPT:
        assert "Raises" in _sections(doc), f"{name}: no Raises section (or an entry in RAISES_EXEMPT with a reason)"


@pytest.mark.parametrize("name", sorted(CLASSES))
def test_class_docstring(name):
    cls = CLASSES[name]
    doc = inspect.cleandoc(cls.__doc__ or "")
    assert doc, f"{name}: no docstring"
    sections = _sections(doc)
    params = _parameters(cls, bound=False)
    if _is_record(cls):
        if params:
            assert "Attributes" in sections or "Parameters" in sections, f"{name}: its fields are not documented"
    elif "__init__" in vars(cls):
        _check_signature_documented(name, doc, params)
    own = [vars(cls)[k] for k in ("__init__", "__post_init__") if inspect.isfunction(vars(cls).get(k))]
    if any(_raises(f) for f in own):
        assert "Raises" in sections, f"{name}: its constructor raises, but the docstring has no Raises"


@pytest.mark.parametrize("name", sorted(METHODS))
def test_method_docstring(name):
    cls, attr, func = METHODS[name]
    doc = inspect.getdoc(getattr(cls, attr))
    assert doc, f"{name}: no docstring (nor one of a base class's method)"
    bound = not isinstance(vars(cls)[attr], staticmethod)
    _check_signature_documented(name, doc, _parameters(func, bound=bound))
    _check_returns(name, doc, func)


@pytest.mark.parametrize("name", REFERENCES_REQUIRED)
def test_literature_is_cited(name):
    obj = CALLABLES.get(name) or (METHODS[name][2] if name in METHODS else None)
    assert obj is not None, name
    doc = inspect.cleandoc(obj.__doc__ or "")
    assert "References" in _sections(doc), f"{name}: its algorithm comes from the literature; no References"
