"""The package's layers: no import cycles, and each layer depends only on the layers below it."""

from __future__ import annotations

import ast
from pathlib import Path

import saltation

ROOT = Path(saltation.__file__).parent


def _imports() -> dict[str, set[str]]:
    """Module -> the package modules it imports (relative imports, at any depth of the file)."""
    deps: dict[str, set[str]] = {}
    for f in ROOT.glob("*.py"):
        names = set()
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                names.update([node.module.split(".")[0]] if node.module else [a.name for a in node.names])
        deps[f.stem] = names
    return deps


def test_no_import_cycles():
    deps = _imports()

    def reaches(a: str, b: str, seen: set[str]) -> bool:
        for d in deps.get(a, ()):
            if d == b or (d not in seen and not seen.add(d) and reaches(d, b, seen)):
                return True
        return False

    cycles = [(a, b) for a in sorted(deps) for b in sorted(deps[a]) if b in deps and reaches(b, a, set())]
    assert cycles == []


def test_layers_depend_only_on_layers_below():
    deps = _imports()
    below_the_flow = {"codegen", "compiled", "model", "affine", "errors", "_contract"}
    assert deps["codegen"] <= below_the_flow  # code generation knows nothing of integration
    assert "shooting" not in deps["integrate"] and "continuation" not in deps["integrate"]
    assert "continuation" not in deps["corrector"] and "continuation" not in deps["bifurcations"]
    assert deps["_contract"] == set()  # copied verbatim into every generated module


def test_no_top_level_name_hides_a_module():
    """``import saltation.X as m`` must give the module X, not a function exported under the same name."""
    import importlib

    modules = {f.stem for f in ROOT.glob("*.py") if not f.stem.startswith("_")}
    hidden = sorted(name for name in saltation.__all__ if name in modules)
    assert hidden == []
    for name in modules:
        importlib.import_module(f"saltation.{name}")
        assert type(getattr(saltation, name)).__name__ == "module", name
