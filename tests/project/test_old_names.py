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
