"""Brute-force diagrams and period maps: moved to :mod:`saltation.sweeps` (a library layer).

This module re-exports the names for one release; it goes in release 0.3.0.  Import them from
:mod:`saltation.sweeps` (or the top level: ``saltation.sweep``, ``saltation.period_map``).
"""

from saltation.sweeps.sweeps import (
    PeriodMap,
    StartState,
    SweepResult,
    SweepStart,
    attractor_period,
    period_map,
    sweep,
)

__all__ = ["PeriodMap", "StartState", "SweepResult", "SweepStart", "attractor_period", "period_map", "sweep"]
