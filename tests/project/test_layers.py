"""The package's layers: one folder each, no import cycles, each depending only on the layers before it.

The order is model -> engine -> orbits -> branches -> special_points -> sweeps -> output -> apps;
``errors`` and ``summary`` import nothing of the package, and ``models`` (the shipped models) only the
model layer.  Imports are read from the source (``ast``), at any depth of a file, so a function-level
import counts as much as one at the top.  The only exceptions are the deprecated wrappers in
:data:`ALLOWED_UPWARD`, which import the output layer inside the method (the sweeps' file methods, the
curves' record), until release 0.3.0.
"""

from __future__ import annotations

import ast
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

import saltation

ROOT = Path(saltation.__file__).parent
LAYERS = ["model", "engine", "orbits", "branches", "special_points", "sweeps", "output", "apps"]
FOUNDATION = {"errors", "summary", "_moved", "kinds", "_optional", "progress"}  # import nothing of the package's layers

#: (module, function) whose imports are not counted: the records' deprecated file and figure methods,
#: which import the output layer when called (they go in release 0.3.0).
ALLOWED_UPWARD = {("saltation.sweeps.sweeps", f"{record}.{method}")
                  for record in ("SweepResult", "PeriodMap")
                  for method in ("to_dict", "from_dict", "save", "load", "plot")} | {
    ("saltation.special_points.loci", "Locus.record"), ("saltation.special_points.loci", "codimension_two_record")}


def _place(module: str) -> str:
    """``saltation.engine.flow`` -> ``engine``; ``saltation.errors`` -> ``errors``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _allowed_nodes(name: str, tree: ast.Module) -> set[int]:
    """The ``id`` of every node inside the functions of module ``name`` that :data:`ALLOWED_UPWARD` names."""
    out: set[int] = set()
    for top in tree.body:
        if isinstance(top, ast.FunctionDef) and (name, top.name) in ALLOWED_UPWARD:
            out.update(id(n) for n in ast.walk(top))
        for fn in getattr(top, "body", []) if isinstance(top, ast.ClassDef) else []:
            if isinstance(fn, ast.FunctionDef) and (name, f"{top.name}.{fn.name}") in ALLOWED_UPWARD:
                out.update(id(n) for n in ast.walk(fn))
    return out


def _imports() -> dict[str, set[str]]:
    """Module (dotted, below ``saltation``) -> the package modules it imports."""
    deps: dict[str, set[str]] = {}
    for f in ROOT.rglob("*.py"):
        name = ".".join(("saltation", *f.relative_to(ROOT).with_suffix("").parts)).removesuffix(".__init__")
        found = set()
        tree = ast.parse(f.read_text())
        allowed = _allowed_nodes(name, tree)
        for node in ast.walk(tree):
            if id(node) in allowed:
                continue
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("saltation"):
                found.add(node.module)
            elif isinstance(node, ast.Import):
                found.update(a.name for a in node.names if a.name.startswith("saltation"))
            elif isinstance(node, ast.ImportFrom) and node.level:
                found.add(name.rsplit(".", node.level - (f.stem == "__init__"))[0] + (f".{node.module}" if node.module else ""))
        deps[name] = found
    return deps


def test_every_module_lives_in_a_layer_folder():
    loose = sorted(f.stem for f in ROOT.glob("*.py") if f.stem not in FOUNDATION | {"__init__", "__main__"})
    assert loose == []
    assert sorted(p.name for p in ROOT.iterdir() if p.is_dir() and (p / "__init__.py").exists()) == sorted(
        [*LAYERS, "models"])


def test_layers_depend_only_on_layers_before_them():
    order = {layer: i for i, layer in enumerate(LAYERS)}
    upward = []
    for module, deps in _imports().items():
        here = _place(module)
        for dep in deps:
            there = _place(dep)
            if here in FOUNDATION:
                if there in order:
                    upward.append((module, dep))
            elif here == "models":
                if there in order and there != "model":
                    upward.append((module, dep))
            elif here in order and there in order and order[there] > order[here]:
                upward.append((module, dep))
    assert upward == []


def test_the_engine_knows_nothing_of_orbits_and_the_continuation_engine_no_detector():
    deps = _imports()
    assert all(_place(d) in ("model", "engine", "errors", "summary", "progress") for d in deps["saltation.engine.codegen"])
    assert deps["saltation.engine._contract"] == set()  # copied verbatim into every generated module
    assert not any(d.startswith("saltation.special_points") for d in deps["saltation.branches.continuation"])


def test_no_import_cycles():
    deps = _imports()

    def reaches(a: str, b: str, seen: set[str]) -> bool:
        for d in deps.get(a, ()):
            if d == b or (d not in seen and not seen.add(d) and reaches(d, b, seen)):
                return True
        return False

    cycles = [(a, b) for a in sorted(deps) for b in sorted(deps[a]) if b in deps and b != a and reaches(b, a, set())]
    assert cycles == []


def test_import_saltation_leaves_matplotlib_out():
    code = "import sys, saltation; print('matplotlib' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"


@pytest.mark.parametrize("old, new", [("saltation.integrate", "saltation.engine.flow"),
                                      ("saltation.shooting", "saltation.orbits.shooting"),
                                      ("saltation.continuation", "saltation.special_points.continuation"),
                                      ("saltation.bifurcations", "saltation.special_points.detection")])
def test_the_flat_layouts_paths_still_import_with_a_warning(old, new):
    import importlib

    sys.modules.pop(old, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        module = importlib.import_module(old)
    assert module is importlib.import_module(new)
    assert module.__spec__.name == new
    assert any(issubclass(w.category, DeprecationWarning) and new in str(w.message) for w in caught)


def test_the_old_continuation_path_keeps_its_special_points():
    """``saltation.continuation.Continuation`` detected special points: at its old path it still does."""
    from saltation.branches.continuation import Continuation as Engine
    from saltation.special_points.continuation import Continuation
    from saltation.special_points.detection import SpecialPointDetector

    assert issubclass(Continuation, Engine)
    assert Continuation.__init__.__kwdefaults__["detector"] is SpecialPointDetector
    assert Engine.__init__.__kwdefaults__["detector"] is None


def test_no_top_level_name_hides_a_module():
    """``import saltation.X as m`` must give the package X, not a function exported under the same name."""
    hidden = sorted(name for name in saltation.__all__ if name in [*LAYERS, "models", "errors", "summary"])
    assert hidden == []


def test_the_allowed_exceptions_exist_and_are_the_only_upward_imports_of_sweeps():
    """Each wrapper named in ALLOWED_UPWARD exists; without the exceptions, those are sweeps' only upward imports."""
    import saltation.sweeps.sweeps as module

    import importlib

    for name, qualified in ALLOWED_UPWARD:
        found = importlib.import_module(name)
        for part in qualified.split("."):
            found = getattr(found, part)
        assert callable(found), qualified
    tree = ast.parse(Path(module.__file__).read_text())
    upward = {(node.lineno, node.module) for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
              and node.module and _place(node.module) in ("output", "apps")}
    assert len(upward) == sum(name == module.__name__ for name, _ in ALLOWED_UPWARD)
