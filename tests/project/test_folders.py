"""A folder tells its contents: each package's docstring names every module in it, and only those.

The names are read as ``:mod:`~saltation.<folder>.<module>``` references (or ``saltation.<folder>.<module>``
in double backquotes) in the ``__init__`` docstring of the folder.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import saltation

ROOT = Path(saltation.__file__).parent
FOLDERS = sorted(p for p in [ROOT, *ROOT.rglob("*")] if p.is_dir() and (p / "__init__.py").exists())


def _dotted(folder: Path) -> str:
    return ".".join(("saltation", *folder.relative_to(ROOT).parts))


@pytest.mark.parametrize("folder", [f for f in FOLDERS if f != ROOT], ids=lambda f: _dotted(f))
def test_the_folder_docstring_lists_its_modules(folder):
    doc = ast.get_docstring(ast.parse((folder / "__init__.py").read_text())) or ""
    package = _dotted(folder)
    named = set(re.findall(re.escape(package) + r"\.(\w+)", doc))
    present = {p.stem for p in folder.glob("*.py") if p.stem != "__init__"}
    present |= {p.name for p in folder.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert present - named == set(), f"{package}: its docstring does not name {sorted(present - named)}"
    assert named - present == set(), f"{package}: its docstring names modules it does not hold: {sorted(named - present)}"
