"""Several figures written at once (saltation.output.plotting.save_figures): the same files as one by one."""

from __future__ import annotations

import re

import matplotlib

matplotlib.use("Agg")

import pytest
from matplotlib.figure import Figure

from saltation.output import plotting


def _figures(count: int) -> list[Figure]:
    figures = []
    for k in range(count):
        fig = Figure(figsize=(3, 2))
        ax = fig.add_subplot()
        ax.plot([0, 1, 2], [k, k + 1, k * k], label=rf"$\mu_{k}$")
        ax.set_title(f"figure {k}")
        ax.legend()
        figures.append(fig)
    return figures


def _without_date(pdf: bytes) -> bytes:
    """A PDF without its creation date (the only part that differs between two writes of one figure)."""
    return re.sub(rb"/CreationDate \(D:\d+Z\)", b"", pdf)


@pytest.mark.parametrize("count", [1, 2, 5])
def test_the_same_files_as_one_by_one(tmp_path, count):
    """Each PNG is byte for byte the one :func:`save_figure` writes, each PDF too but for its creation
    date, in order; the forked process draws every other figure where there is one."""
    figures = _figures(count)
    one_by_one = [path for k, fig in enumerate(figures) for path in plotting.save_figure(fig, tmp_path / "a" / f"f{k}", dpi=80)]
    together = plotting.save_figures([(fig, tmp_path / "b" / f"f{k}") for k, fig in enumerate(figures)], dpi=80)
    assert [p.relative_to(tmp_path / "b") for p in together] == [p.relative_to(tmp_path / "a") for p in one_by_one]
    for a, b in zip(one_by_one, together):
        if a.suffix == ".png":
            assert a.read_bytes() == b.read_bytes(), b.name
        else:
            assert _without_date(a.read_bytes()) == _without_date(b.read_bytes()), b.name
    assert not plotting._FORKED_FIGURES  # nothing left behind for a later fork


def test_a_figure_the_fork_fails_to_draw_is_drawn_here(tmp_path, monkeypatch):
    """Where the forked process fails (here: every time), its figures are drawn by the caller instead."""

    def failing(k, dpi):
        raise RuntimeError("the forked process failed")

    monkeypatch.setattr(plotting, "_drawn_in_fork", failing)
    figures = _figures(3)
    written = plotting.save_figures([(fig, tmp_path / f"f{k}") for k, fig in enumerate(figures)], dpi=80)
    assert [p.name for p in written] == ["f0.png", "f0.pdf", "f1.png", "f1.pdf", "f2.png", "f2.pdf"]
    assert all(p.stat().st_size > 0 for p in written)


def test_a_figure_that_cannot_be_drawn_raises_here(tmp_path):
    """A drawing error is raised to the caller (not lost in the forked process), and no file of that
    figure is written."""
    good, bad = _figures(2)

    def cannot_draw(*args, **kwargs):
        raise ValueError("cannot draw this figure")

    bad.savefig = cannot_draw
    with pytest.raises(ValueError, match="cannot draw this figure"):
        plotting.save_figures([(good, tmp_path / "good"), (bad, tmp_path / "bad")], dpi=80)
    assert not (tmp_path / "bad.png").exists() and not (tmp_path / "bad.pdf").exists()
