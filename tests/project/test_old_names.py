"""Every name release 0.1 held at the top level of one of its modules still imports from there, until 0.3.0.

``tests/data/names_0_1.json`` lists them: the classes, functions and constants of the package that each
module of release 0.1 defined or imported (read from that release by importing every module).  A name
that moved is found in its new home, with a ``DeprecationWarning`` that names it.
"""

from __future__ import annotations

import importlib
import json
import warnings
from pathlib import Path

import pytest

NAMES = json.loads((Path(__file__).parents[1] / "data" / "names_0_1.json").read_text())


@pytest.mark.parametrize("module", sorted(NAMES))
def test_the_names_of_release_0_1_still_import(module):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        found = importlib.import_module(module)
        lost = [name for name in NAMES[module] if not hasattr(found, name)]
    assert lost == [], f"{module} no longer gives {lost}"


def test_a_moved_name_says_where_it_lives():
    import saltation.orbits.shooting as old

    with pytest.warns(DeprecationWarning, match="saltation.orbits.shooting.event_ids lives in saltation.orbits.records"):
        from saltation.orbits.records import event_ids

        assert old.event_ids is event_ids
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        old.no_such_name  # noqa: B018


# modules kept whole only to hold release 0.1's names: the library itself imports from their new homes, so
# that a command loads only what it uses (``saltation.orbits.shooting`` imports every orbit module)
REEXPORT_MODULES = ("saltation.orbits.shooting", "saltation.special_points.detection")


def test_the_library_does_not_import_its_old_module_names():
    import re

    src = Path(__file__).parents[2] / "src" / "saltation"
    pattern = re.compile(r"^\s*(from|import)\s+(" + "|".join(re.escape(m) for m in REEXPORT_MODULES) + r")\b", re.MULTILINE)
    users = []
    for path in sorted(src.rglob("*.py")):
        dotted = ".".join(path.relative_to(src.parent).with_suffix("").parts)
        if dotted in REEXPORT_MODULES:
            continue
        users += [f"{path.relative_to(src.parent)}: {m.group(0).strip()}" for m in pattern.finditer(path.read_text())]
    assert users == [], "import from the new homes instead:\n" + "\n".join(users)
