"""Branches as pandas tables, sweeps and period maps as xarray datasets and NetCDF files."""

from __future__ import annotations

import json
import math
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation.branches.branch import Branch, BranchKind, BranchPoint, SpecialPoint, SpecialPointKind, StopReason
from saltation.errors import MissingDependencyError
from saltation.sweeps import PeriodMap, SweepResult, SweepStart

pd = pytest.importorskip("pandas")
xr = pytest.importorskip("xarray")


def _point(k: int, *, stable: bool = True) -> BranchPoint:
    state = np.array([0.1 * k, -0.2 * k])
    mu = np.array([0.5 + 0.1j * k, 0.5 - 0.1j * k]) if stable else np.array([1.5 + 0j, 0.2 + 0j])
    return BranchPoint(0.5 + 0.1 * k, state, 6.0 + k, 1.0 + k, 0.5 + k, mu, stable,
                       ("free -[h+]-> contact", "contact -[h-]-> free")[: k % 3], 0.1, 3, mode0="free", t0=0.25)


def _branch(n: int = 6) -> Branch:
    points = [_point(k, stable=k < 3) for k in range(n)]
    fold = SpecialPoint(SpecialPointKind.FOLD, 0.75, (0.7, 0.8), 0.1, 2, points[2].state, 8.0, 3.0,
                        multipliers=points[2].multipliers)
    graze = SpecialPoint(SpecialPointKind.GRAZING, 0.76, (0.7, 0.8), 0.1, 2, points[2].state, 8.0, 3.0)
    return Branch(model="trilinear", parameter_name="omega", kind=BranchKind.PERIODIC, points=points,
                  special_points=[fold, graze], stop_reason=StopReason.PARAMETER_BOUND,
                  stop_reasons=[StopReason.MIN_STEP], fixed_parameters={"omega": 0.5, "f0": 0.2},
                  state_names=("x", "period"), label="periodic")


def test_a_branch_as_a_table_has_a_row_per_point_and_its_columns_named():
    branch = _branch()
    table = branch.to_pandas()
    assert len(table) == len(branch)
    np.testing.assert_array_equal(table["omega"], branch.parameter)
    # a state named like another column is prefixed
    np.testing.assert_array_equal(table["x"], branch.states[:, 0])
    np.testing.assert_array_equal(table["state_period"], branch.states[:, 1])
    np.testing.assert_array_equal(table["period"], branch.period)
    np.testing.assert_array_equal(table["stable"], branch.stable)
    for i in range(2):
        np.testing.assert_array_equal(table[f"multiplier{i + 1}"], branch.multipliers[:, i])
        np.testing.assert_array_equal(table[f"multiplier{i + 1}_abs"], np.abs(branch.multipliers[:, i]))
    assert list(table["event_count"]) == [len(p.event_labels) for p in branch.points]
    assert table["events"][2] == "free -[h+]-> contact; contact -[h-]-> free"
    assert list(table["special_point"]) == ["", "", "fold, grazing", "", "", ""]
    assert table.attrs["model"] == "trilinear" and table.attrs["stop_reasons"] == ["parameter_bound", "min_step"]
    # the table filters and groups as users expect
    assert table[table["stable"]]["omega"].max() == pytest.approx(branch.parameter[2])


def test_an_empty_branch_and_a_branch_of_equilibria_as_tables():
    empty = Branch(model="m", parameter_name="a", kind=BranchKind.PERIODIC, state_names=("x", "y"))
    table = empty.to_pandas()
    assert len(table) == 0 and {"a", "x", "y", "period"} <= set(table.columns)
    eq = Branch(model="m", parameter_name="a", kind=BranchKind.EQUILIBRIUM, points=[_point(1)], state_names=("x", "y"))
    assert "eigenvalue1" in eq.to_pandas().columns and "multiplier1" not in eq.to_pandas().columns


def _sweep(counts: list[int], exponents: bool) -> SweepResult:
    values = np.linspace(0.5, 1.5, len(counts))
    rng = np.random.default_rng(len(counts))
    states = rng.normal(size=(sum(counts), 2))
    return SweepResult(
        model="trilinear", parameter_name="omega", values=values, counts=np.array(counts),
        parameter_points=np.repeat(values, counts), states=states, state_names=("x", "v"), section="poincare",
        failures=((0.75, "step size underflow near µ ≈ 0"),) if 0 in counts else (),
        settings={"periods": 5, "parameters": {"omega": 1.2, "f0": 0.2}, "tolerances": {"rtol": 1e-10},
                  "units": {"omega": "rad/s", "x": "m"}},
        start=SweepStart.OWN, largest_exponents=rng.normal(size=len(counts)) if exponents else None)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 6), min_size=1, max_size=7), st.booleans())
def test_a_sweep_as_a_dataset_holds_every_sample_once(counts, exponents):
    result = _sweep(counts, exponents)
    ds = result.to_xarray()
    assert ds.sizes["omega"] == len(counts) and ds.sizes["sample"] == max(counts)
    np.testing.assert_array_equal(ds["count"].values, counts)
    for j, name in enumerate(result.state_names):
        grid = ds[name].values
        taken = grid[~np.isnan(grid)]
        np.testing.assert_array_equal(taken, result.states[:, j])  # row by row, in order, nothing else
        for k, c in enumerate(counts):
            assert np.isnan(grid[k, c:]).all() and not np.isnan(grid[k, :c]).any()
    assert ("largest_exponent" in ds) == exponents


def test_a_sweep_written_to_netcdf_reads_back_with_its_attributes(tmp_path):
    from saltation.output.io import load_netcdf, save_netcdf

    result = _sweep([3, 0, 2], exponents=True)
    back = load_netcdf(save_netcdf(result, tmp_path / "sweep.nc"))
    np.testing.assert_array_equal(back["x"].values, result.to_xarray()["x"].values)
    np.testing.assert_array_equal(back["omega"].values, result.values)
    assert back["omega"].attrs["units"] == "rad/s" and back["x"].attrs["units"] == "m"
    assert back.attrs["model"] == "trilinear" and back.attrs["start"] == "own"
    assert json.loads(back.attrs["settings_parameters"]) == {"omega": 1.2, "f0": 0.2}
    assert json.loads(back.attrs["failures"]) == [[0.75, "step size underflow near µ ≈ 0"]]
    from saltation import __version__

    assert back.attrs["saltation_version"] == __version__
    # and xarray's own reader sees the same
    with xr.open_dataset(tmp_path / "sweep.nc") as ds:
        assert ds.attrs["section"] == "poincare"


def test_a_period_map_as_a_dataset_and_a_file(tmp_path):
    from saltation.output.io import load_netcdf, save_netcdf

    periods = np.array([[1, 2, 0], [-1, 1, 3]])
    grid = PeriodMap("trilinear", "omega", "f0", np.array([0.5, 1.0, 1.5]), np.array([0.1, 0.2]), periods, 8,
                     failures=((0.5, 0.2, "failed"),), settings={"units": {"f0": "N"}},
                     largest_exponents=np.array([[-0.1, -0.2, 0.3], [math.nan, -0.1, -0.05]]))
    ds = grid.to_xarray()
    assert ds["period"].dims == ("f0", "omega")
    assert int(ds["period"].sel(omega=1.5, f0=0.2)) == 3  # the row is the second parameter
    back = load_netcdf(save_netcdf(grid, tmp_path / "map.nc"))
    np.testing.assert_array_equal(back["period"].values, periods)
    np.testing.assert_array_equal(back["largest_exponent"].values, grid.largest_exponents)
    assert back["f0"].attrs["units"] == "N" and int(back.attrs["max_period"]) == 8


@pytest.mark.parametrize("missing", ["pandas", "xarray"])
def test_a_missing_optional_dependency_is_named_with_its_extra(monkeypatch, missing):
    monkeypatch.setitem(sys.modules, missing, None)  # (an import of it raises ImportError)
    call = _branch().to_pandas if missing == "pandas" else _sweep([1], False).to_xarray
    with pytest.raises(MissingDependencyError, match=rf"needs {missing}.*pip install 'saltation\[{missing}\]'"):
        call()
