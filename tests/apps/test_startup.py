"""What the command line and ``import saltation`` load before they are asked for work.

sympy (about 0.9 s) and numba (about 0.6 s) are needed to build and run a model, not to print a version, a help
text or to import the package: these tests read ``sys.modules`` of a fresh interpreter, which does not depend
on the machine's speed (the times themselves are measured in ``benchmarks/startup.py``).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("numba", "sympy", "matplotlib")


def _loaded_after(code: str) -> dict:
    """The heavy modules a fresh interpreter holds after running ``code``, and what it printed."""
    probe = (
        "import contextlib, io, json, sys\n"
        "out = io.StringIO()\n"
        "with contextlib.redirect_stdout(out):\n"
        + "".join(f"    {line}\n" for line in code.splitlines())
        + f"print(json.dumps({{'loaded': [m for m in {HEAVY!r} if m in sys.modules], 'out': out.getvalue()}}))\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def test_import_saltation_loads_neither_sympy_nor_numba():
    assert _loaded_after("import saltation")["loaded"] == []


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["continue", "--help"], ["sweep", "--help"]])
def test_version_and_help_load_neither_sympy_nor_numba(argv):
    """(``orbit --help`` lists the shipped models with their states and parameters: it builds them.)"""
    found = _loaded_after(
        "from saltation.apps.cli import main\n"
        f"try:\n    main({argv!r})\nexcept SystemExit:\n    pass"
    )
    assert found["loaded"] == [], found["loaded"]
    assert found["out"].strip(), "nothing printed"
    if argv == ["--version"]:
        import saltation

        assert found["out"].strip() == f"saltation {saltation.__version__}"
    else:
        assert "usage: saltation" in found["out"]


def test_the_names_of_the_package_are_there_when_used():
    """Every name of ``saltation.__all__`` resolves (from its module), and ``dir`` lists them before their use."""
    import saltation

    assert set(saltation.__all__) <= set(dir(saltation))
    for name in saltation.__all__:
        assert getattr(saltation, name) is not None, name
    from saltation.engine.flow import Flow
    from saltation.special_points.continuation import continue_orbit

    assert saltation.Flow is Flow and saltation.continue_orbit is continue_orbit
    with pytest.raises(AttributeError, match="no attribute 'Flw'"):
        saltation.Flw  # noqa: B018


def test_the_command_lines_copies_of_library_constants_agree():
    """The command line writes out the shipped models' names and the largest number of segments (so that its
    parser loads no model and no solver): they are the library's."""
    from saltation.apps.cli.models import SHIPPED_NAMES
    from saltation.apps.cli.options import MAX_SEGMENTS
    from saltation.models import SHIPPED
    from saltation.orbits.multiple import MAX_SEGMENTS as LIBRARY_MAX

    assert SHIPPED_NAMES == tuple(SHIPPED)
    assert MAX_SEGMENTS == LIBRARY_MAX
