"""What a subcommand prints: numbers, multipliers, paragraphs of help, the special-point table and the
progress bar."""

from __future__ import annotations

import sys
import textwrap
from collections.abc import Callable, Sequence


def fmt(value: float) -> str:
    """A number with ten significant digits, as every message and table prints it."""
    return f"{value:.10g}"


def complex_text(mu: complex) -> str:
    """A multiplier as ``RE + IMi`` (``inf`` for an infinite one, ``RE`` for a real one)."""
    import numpy as np

    if not np.isfinite(mu):
        return "inf"
    if mu.imag == 0:
        return fmt(mu.real)
    sign = "+" if mu.imag > 0 else "-"
    return f"{fmt(mu.real)} {sign} {fmt(abs(mu.imag))}i"


def multipliers_json(mu: Sequence[complex]) -> list:
    """Multipliers as ``[re, im]`` pairs, an infinite one as the string ``"inf"``."""
    import numpy as np

    return ["inf" if not np.isfinite(m) else [float(m.real), float(m.imag)] for m in np.asarray(mu, dtype=complex)]


def paragraph(text: str, indent: str = "") -> str:
    """``text`` refilled to 88 columns, every line indented by ``indent`` (help texts)."""
    return textwrap.fill(" ".join(text.split()), width=88, initial_indent=indent, subsequent_indent=indent)


def special_points_text(records: list[dict]) -> str:
    """The table of located special points (:func:`saltation.apps.paper.special_point_table`), or a line
    saying there are none."""
    from saltation.apps.paper import special_point_table

    return special_point_table(records) if records else "no special points located"


def progress_bar(enabled: bool) -> tuple[Callable[[str, int], None] | None, Callable[[], None]]:
    """A tqdm progress callback ``(stage, count)`` (or None when disabled), and the function that closes it.

    On a terminal the bar also shows a one-time build of the integrator; elsewhere there is no bar, and a
    build says so in a line of its own.
    """
    if not enabled:
        return None, lambda: None
    from tqdm import tqdm

    from saltation.engine.codegen import build_watcher

    bar = tqdm(total=None, unit=" points", file=sys.stderr, dynamic_ncols=True, leave=False, mininterval=0.25, disable=None)
    if bar.disable:  # not a terminal: no bar, and a build says so in a line of its own
        return (lambda stage, count: None), bar.close
    stage_now = [""]

    def update(stage: str, _count: int) -> None:
        stage_now[0] = stage.rstrip(": ")
        bar.set_description_str(stage_now[0])
        bar.update(1)

    def watch(message: str | None, seconds: float) -> None:  # a one-time build, shown in the bar
        bar.set_description_str(f"{message} ({seconds:.0f} s)" if message else stage_now[0])
        bar.refresh()

    watching = build_watcher(watch)
    watching.__enter__()

    def close() -> None:
        watching.__exit__(None, None, None)
        bar.close()

    return update, close


def point_counter(update: Callable[[str, int], None] | None, stage: str) -> Callable[[object], None] | None:
    """A branch-point callback that advances the progress bar ``update`` under ``stage`` (None without a bar)."""
    return (lambda point: update(stage, 0)) if update else None
