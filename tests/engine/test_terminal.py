"""What the terminal shows: nothing stray at exit, a build shown in the progress bar, tables that keep
their columns, counts in words."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest


def _on_a_terminal(code: str) -> bytes:
    """Everything ``python -c code`` writes to a pseudo-terminal (standard output and error)."""
    pty = pytest.importorskip("pty")
    master, slave = pty.openpty()
    try:
        subprocess.run([sys.executable, "-c", code], stdin=slave, stdout=slave, stderr=slave, check=True, timeout=120)
    finally:
        os.close(slave)
    out = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # (EIO: the terminal's other end is closed and drained)
            break
        if not chunk:
            break
        out += chunk
    os.close(master)
    return out


def test_importing_writes_nothing_to_a_terminal():
    """numba's first warning initialises colorama, whose reset at exit wrote ESC[0m; saltation unregisters it."""
    assert _on_a_terminal("import saltation") == b""
    assert _on_a_terminal("import saltation; from saltation.models import trilinear; saltation.Flow(trilinear())") == b""


def test_a_build_is_shown_by_the_watcher_until_done():
    from saltation.engine.codegen import build_watcher, building

    seen = []
    with build_watcher(lambda message, seconds: seen.append((message, seconds))), building("compiling", interval=0.02):
        import time

        time.sleep(0.1)
    assert seen[0][0] == "compiling" and len(seen) >= 3  # at once, then every interval
    assert seen[-1][0] is None and seen[-1][1] >= 0.1  # done: the bar goes back to its stage


def test_the_special_point_table_keeps_its_columns_with_long_names():
    from saltation.apps.paper import special_point_table

    records = [
        {"model": "a_model_with_a_rather_long_name", "kind": "discontinuous_neimark_sacker_and_more", "parameter": "omega",
         "value": 1.25, "multipliers_minus": [[1.0, 0.0], [0.5, 0.0]], "multipliers_plus": None},
        {"model": "short", "kind": "fold", "parameter": "a_long_parameter_name", "value": -3.5,
         "multipliers": [[1.0, 0.0], [0.25, 0.0]]},
    ]
    lines = special_point_table(records).splitlines()
    assert len(lines) == 3
    rows = [line.split() for line in lines[1:]]
    assert rows[0][:4] == ["a_model_with_a_rather_long_name", "discontinuous_neimark_sacker_and_more", "omega", "1.2500000000"]
    assert rows[1][:4] == ["short", "fold", "a_long_parameter_name", "-3.5000000000"]
    # every column starts where its header does
    starts = [lines[0].index("kind"), lines[0].index("value") + len("value")]
    assert lines[1].index("discontinuous") == lines[2].index("fold") == starts[0]
    assert lines[1].index("1.2500000000") + len("1.2500000000") == starts[1]


def test_the_continue_summary_counts_in_words(tmp_path, capsys):
    from saltation.apps import cli

    status = cli.main(["continue", "trilinear", "--param", "omega", "--from", "0.6", "--to", "0.62",
                       "--ds-max", "0.05", "--out", str(tmp_path), "--no-progress"])
    assert status == 0
    out = capsys.readouterr().out
    assert "branch(es)" not in out and " 1 points" not in out
    assert " on 1 branch of trilinear over omega" in out
