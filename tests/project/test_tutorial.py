"""The tutorial notebook (examples/tutorial.ipynb) runs from top to bottom, and its numbers are right."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib
import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

pytestmark = pytest.mark.slow  # executes the tutorial notebook in a kernel of its own

NOTEBOOK = Path(__file__).parents[2] / "examples" / "tutorial.ipynb"


@pytest.fixture(scope="module")
def tutorial() -> dict:
    """The notebook's code cells executed in order in one namespace, as Jupyter would (figures off screen)."""
    matplotlib.use("Agg")
    cells = json.loads(NOTEBOOK.read_text())["cells"]
    namespace: dict = {}
    for k, cell in enumerate(cells):
        if cell["cell_type"] == "code":
            exec(compile("".join(cell["source"]), f"{NOTEBOOK.name}, cell {k}", "exec"), namespace)  # noqa: S102
    return namespace


def test_every_summary_the_notebook_shows_renders(tutorial):
    for name in ("system", "orbit", "branch", "corner"):
        assert tutorial[name]._repr_markdown_().startswith("**")


def test_the_monodromy_check_passes(tutorial):
    """Central differences of the period map against the monodromy matrix: both modes are affine, so
    the flow is exact to rounding and the differences are good to about 1e-9 (rounding over the step
    1e-6); 1e-6 leaves room for the events' locations."""
    assert np.abs(tutorial["differences"] - tutorial["orbit"].monodromy).max() < 1e-6


def test_the_corner_is_where_the_free_orbit_reaches_the_support(tutorial):
    """The first special point: where the free, linear response first has amplitude x_c, from its
    closed form f0 / |k - m w^2 + i c w| = x_c (to the accuracy the point states); and on the free
    side its multipliers are those of expm(A T) of the free mode at the located parameter (to the
    accuracy the point states for its multipliers)."""
    pars = tutorial["system"].defaults
    m, c, k, x_c, f0 = (pars[name] for name in ("m", "c", "k", "x_c", "f0"))

    def amplitude_gap(w):
        return f0 / np.hypot(k - m * w**2, c * w) - x_c

    w_a = scipy.optimize.brentq(amplitude_gap, 0.6, 1.0, xtol=1e-15)
    corner = tutorial["corner"]
    assert corner.kind.is_nonsmooth
    assert abs(corner.parameter - w_a) <= corner.accuracy + 1e-9
    A = np.array([[0.0, 1.0], [-k / m, -c / m]])
    free = np.sort_complex(np.linalg.eigvals(scipy.linalg.expm(A * 2 * np.pi / corner.parameter)))
    sides = [np.sort_complex(np.asarray(mu)) for mu in (corner.multipliers_minus, corner.multipliers_plus)]
    assert np.isfinite(corner.multipliers_accuracy)
    assert min(np.abs(side - free).max() for side in sides) <= corner.multipliers_accuracy


def _executed(cells_after: list[str] = ()) -> list:
    """The notebook run by a Jupyter kernel (nbclient, the default inline backend), with ``cells_after``
    appended (not saved); its code cells, outputs included."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    notebook.cells += [nbformat.v4.new_code_cell(source) for source in cells_after]
    nbclient.NotebookClient(notebook, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()
    return [cell for cell in notebook.cells if cell.cell_type == "code"]


def _images(cell) -> int:
    return sum("image/png" in output.get("data", {}) for output in cell.outputs)


def test_the_executed_notebook_shows_each_figure_once():
    """A plotting function's figure, as a cell's last expression, is shown exactly once by Jupyter: made
    without pyplot (no backend shows it on its own) it draws itself as PNG; drawn on the caller's pyplot
    axes, the backend shows it and IPython's formatter is told not to show it again."""
    on_pyplot_axes = (
        "import matplotlib.pyplot as plt\n"
        "fig, ax = plt.subplots()\n"
        "plot_response(branch, ax=ax)"
    )
    assigned_only = "figure = plot_response(branch)"  # no last expression: nothing shown
    cells = _executed([on_pyplot_axes, assigned_only])
    tutorial_cells, (pyplot_cell, assigned_cell) = cells[:-2], cells[-2:]
    plotting = [cell for cell in tutorial_cells if "plot_response(branch)" in cell.source or "plot_multipliers(branch)" in cell.source]
    assert len(plotting) == 2  # plot_response and plot_multipliers, each the last expression of its cell
    assert [_images(cell) for cell in plotting] == [1, 1]
    assert sum(_images(cell) for cell in tutorial_cells) == 2  # and no other cell shows an image
    assert _images(pyplot_cell) == 1
    assert _images(assigned_cell) == 0
