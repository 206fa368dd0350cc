"""The outputs printed in the README and the documentation are what the code prints.

Conventions, in README.md, docs/index.md, docs/theory.md and docs/user-guide/*.md:

* **An example and its output** is a ```python block followed by a ```text block, with nothing between
  them but blank lines and, optionally, a line ``prints``. The ```python blocks of a file run in order
  in one namespace per file (a later example may use what an earlier one defined; a block without output
  runs too), from the file's first block to its last example with an output, in a temporary working
  folder. What an example prints must equal its ```text block exactly, up to whitespace (any run of
  spaces and line breaks counts as one space). Examples therefore print with explicit formats, to the
  digits that are known (``f"{orbit.period:.9f}"``, ``abs(mu).round(12)``), not ``repr`` of floats.
* **A command and its output** is a ```console block: lines ``$ saltation ...`` each followed by what
  the command prints, its standard output (its standard error when it fails). The command runs in this
  process (``saltation.apps.cli.main``) with ``DIR`` replaced by a temporary folder; a command shown in
  several blocks runs once. The command line's formats are fixed, so the text is compared number by
  number: a number shows the digits that are promised (``1.098192624`` means within 5e-10 of the printed
  value, ``12`` means 12), a number ending in ``...`` is cut there (``6.4393839142...`` means
  6.4393839142 <= x < 6.4393839143), a ``...`` on its own stands for any text (lines left out), and all
  other text must match up to whitespace.
* Every ```python block that calls ``print`` shows its output, and every ```text block belongs to an
  example: an output cannot be shown unchecked, nor left out.

With a warm kernel cache this file takes about 10 s (``saltation paper`` 3-6 s of it); on an empty one the
examples compile their models first (the relay feedback system's three states an engine of their own).
"""

from __future__ import annotations

import contextlib
import io
import math
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow  # runs every example of the README and the docs, saltation paper included

ROOT = Path(__file__).parents[2]
FILES = ["README.md", "docs/index.md", "docs/theory.md",
         *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs" / "user-guide").glob("*.md"))]

# numpy's default print options, as in a fresh session (another test may have changed them)
NUMPY_PRINT = {"precision": 8, "threshold": 1000, "edgeitems": 3, "linewidth": 75, "suppress": False,
               "nanstr": "nan", "infstr": "inf", "sign": "-", "floatmode": "maxprec", "legacy": False}


@dataclass
class Block:
    lang: str
    text: str
    line: int      # of the opening fence, 1-based
    after: int     # index of the first line after the closing fence


def blocks(path: str) -> list[Block]:
    """The fenced blocks of a Markdown file (indented ones too, e.g. in list items, dedented)."""
    lines = (ROOT / path).read_text().splitlines()
    out, i = [], 0
    while i < len(lines):
        m = re.match(r"^( *)```([\w+-]*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        indent, j = len(m.group(1)), i + 1
        while j < len(lines) and not re.match(r"^ *```\s*$", lines[j]):
            j += 1
        assert j < len(lines), f"{path}:{i + 1}: fence not closed"
        body = "\n".join(line[indent:] if line.startswith(" " * indent) else line.lstrip() for line in lines[i + 1:j])
        out.append(Block(m.group(2), body, i + 1, j + 1))
        i = j + 1
    return out


def examples(path: str) -> list[tuple[Block, Block | None]]:
    """The ```python blocks of a file, each with its ```text output block (or None)."""
    lines = (ROOT / path).read_text().splitlines()
    bs = blocks(path)
    out = []
    for k, b in enumerate(bs):
        if b.lang != "python":
            continue
        nxt = bs[k + 1] if k + 1 < len(bs) else None
        between = [line.strip() for line in lines[b.after:nxt.line - 1]] if nxt else []
        paired = nxt is not None and nxt.lang == "text" and all(s in ("", "prints", "prints:") for s in between)
        out.append((b, nxt if paired else None))
    return out


def normalized(text: str) -> str:
    return " ".join(text.split())


# ---------------------------------------------------------------------------------------------------
# numbers to the digits shown

_NUMBER = r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?"
_TOKEN = re.compile(rf"""
    (?P<cut>(?<![\w.])[-+]?\d+\.\d+\.\.\.)          # a number cut off: 6.4393839142...
  | (?P<num>(?<![\w.]){_NUMBER}(?![\w.]))             # a number
  | (?P<any>\.\.\.)                                    # any text
  | (?P<lit>.)                                         # anything else, as it is
""", re.VERBOSE | re.DOTALL)


def _unit(shown: str) -> float:
    """The value of one unit in the last digit shown: 1e-10 for 1.0981926242, 10 for 1.573e+04."""
    mantissa, _, exponent = shown.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (int(exponent or 0) - decimals)


def compare_numbers(expected: str, actual: str) -> str | None:
    """None if ``actual`` shows ``expected`` (numbers to the digits shown, ``...`` elisions); else why not."""
    exp, act = normalized(expected), normalized(actual)
    parts = [(m.lastgroup, m.group()) for m in _TOKEN.finditer(exp)]
    pattern, numbers = [], []
    for k, (kind, text) in enumerate(parts):
        if kind == "any":
            pattern.append("(?:.*?)")
        elif kind in ("num", "cut"):
            pattern.append(rf"(?<![\w.])({_NUMBER})(?![\w])")
            numbers.append((kind, text))
        elif text == " " and any(0 <= j < len(parts) and parts[j][0] == "any" for j in (k - 1, k + 1)):
            pattern.append(" ?")  # the spaces around an elision are optional
        else:
            pattern.append(re.escape(text))
    m = re.fullmatch("".join(pattern), act, re.DOTALL)
    if m is None:
        return f"the text differs:\n--- shown\n{expected}\n--- printed\n{actual}"
    wrong = []
    for (kind, shown), printed in zip(numbers, m.groups()):
        x, a, unit = float(shown.removesuffix("...")), float(printed), _unit(shown.removesuffix("..."))
        if kind == "num":
            ok = abs(a - x) <= 0.5 * unit * (1 + 1e-9)
        else:
            ok = math.copysign(1, a) == math.copysign(1, x) and abs(x) - 1e-9 * unit <= abs(a) < abs(x) + unit
        if not ok:
            wrong.append(f"{shown} shown, {printed} printed")
    if wrong:
        return "numbers differ: " + "; ".join(wrong) + f"\n--- shown\n{expected}\n--- printed\n{actual}"
    return None


def test_comparison_of_numbers():
    """The rules of the comparison itself."""
    assert compare_numbers("a 1.0981926242 b", "a   1.0981926242\nb") is None
    assert compare_numbers("1.098192624", "1.0981926242") is None
    assert compare_numbers("1.098192624", "1.0981926249") is not None
    assert compare_numbers("12 4955 1.573e+04", "12 4955 1.573e+04") is None
    assert compare_numbers("12", "23") is not None
    assert compare_numbers("1.573e+04", "1.5734e+04") is None
    assert compare_numbers("1.573e+04", "4955") is not None
    assert compare_numbers('{"a": 1, ..., "p": 6.43938...}', '{"a": 1, "b": [2, 3], "p": 6.439383914}') is None
    assert compare_numbers('"p": 6.43938...', '"p": 6.43937999') is not None
    assert compare_numbers("...\nhead\n...\nx 1.5\n...", "pre amble\nhead\nmid 3\nx 1.5\ntail 7") is None
    assert compare_numbers("head\n...\nx 1.5\n...", "pre amble\nhead\nmid 3\nx 1.5\ntail 7") is not None
    assert compare_numbers("x inf", "x 1.5") is not None
    assert compare_numbers("fig3 h1a", "fig4 h1a") is not None


# ---------------------------------------------------------------------------------------------------
# the conventions hold


def test_every_printed_output_is_checked():
    problems = []
    for path in FILES:
        outputs = set()
        for code, out in examples(path):
            if out is not None:
                outputs.add(out.line)
            elif re.search(r"\bprint\(", code.text):
                problems.append(f"{path}:{code.line}: a ```python block that prints shows no ```text output after it")
        for b in blocks(path):
            if b.lang == "text" and b.line not in outputs:
                problems.append(f"{path}:{b.line}: a ```text block that follows no ```python example")
            if b.lang == "console" and not any(line.startswith("$ saltation ") for line in b.text.splitlines()[:1]):
                problems.append(f"{path}:{b.line}: a ```console block must start with a line '$ saltation ...'")
    assert not problems, "\n".join(problems)


# ---------------------------------------------------------------------------------------------------
# the Python examples


EXAMPLE_FILES = [p for p in FILES if any(out is not None for _, out in examples(p))]


@pytest.mark.parametrize("path", EXAMPLE_FILES)
def test_python_examples_print_what_is_shown(path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    pairs = examples(path)
    last = max(k for k, (_, out) in enumerate(pairs) if out is not None)
    namespace: dict = {"__name__": "__main__"}
    problems = []
    with np.printoptions(**NUMPY_PRINT):
        for code, out in pairs[:last + 1]:
            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                exec(compile(code.text, f"{path}:{code.line}", "exec"), namespace)  # noqa: S102
            if out is not None and normalized(printed.getvalue()) != normalized(out.text):
                problems.append(f"{path}:{out.line}: the output shown differs from what the example at line "
                                f"{code.line} prints\n--- shown\n{out.text}\n--- printed\n{printed.getvalue()}")
    assert not problems, "\n\n".join(problems)


# ---------------------------------------------------------------------------------------------------
# the command line


def console_sessions(path: str) -> list[tuple[int, str, str]]:
    """(line, command, shown output) of every ``$ saltation ...`` in the ```console blocks of a file."""
    out = []
    for b in blocks(path):
        if b.lang != "console":
            continue
        command, shown = None, []
        for line in [*b.text.splitlines(), "$ "]:
            if line.startswith("$ "):
                if command is not None:
                    out.append((b.line, command, "\n".join(shown)))
                command, shown = line[2:].strip(), []
            else:
                shown.append(line)
    return out


SESSIONS = [(path, line, command, shown) for path in FILES for line, command, shown in console_sessions(path)]


@pytest.fixture(scope="module")
def run_command(tmp_path_factory):
    """Run a ``saltation ...`` command line in this process, once per command; what it prints."""
    from saltation.apps import cli

    folder = tmp_path_factory.mktemp("console")
    done: dict[str, str] = {}

    def run(command: str) -> str:
        if command not in done:
            argv = shlex.split(command)
            assert argv[0] == "saltation", command
            argv = [str(folder / f"out{len(done)}") if a == "DIR" else a for a in argv[1:]]
            stdout, stderr = io.StringIO(), io.StringIO()
            with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
                try:
                    status = cli.main(argv)
                except SystemExit as e:
                    status = e.code
            done[command] = (stdout if status in (0, None) else stderr).getvalue().replace(str(folder), "DIR")
        return done[command]

    return run


@pytest.mark.parametrize(("path", "line", "command", "shown"), SESSIONS,
                         ids=[f"{p}:{line}:{c.split()[1]}" for p, line, c, _ in SESSIONS])
def test_commands_print_what_is_shown(path, line, command, shown, run_command):
    why = compare_numbers(shown, run_command(command))
    assert why is None, f"{path}:{line}: `{command}`: {why}"


def test_the_papers_table_is_checked():
    """The special points of `saltation paper` are shown, and so checked, in the README."""
    assert any(path == "README.md" and command.startswith("saltation paper") and "discontinuous_fold" in shown
               for path, _, command, shown in SESSIONS)
