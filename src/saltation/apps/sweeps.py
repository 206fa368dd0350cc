"""Brute-force diagrams and period maps: moved to :mod:`saltation.sweeps` (a library layer).

This module re-exports the names for one release; it goes in release 0.3.0.  Import them from
:mod:`saltation.sweeps` (or the top level: ``saltation.sweep``, ``saltation.period_map``); the files
of sweeps and maps are :mod:`saltation.output.io`'s, their figures :mod:`saltation.output.plotting`'s.
"""

import importlib
from typing import Any

from saltation._moved import forward_names
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

#: Where the private names of this module went (the job runner; the plotting helpers).
_PRIVATE_HOMES = ("saltation.sweeps.sweeps", "saltation.sweeps.parallel", "saltation.output.plotting")


def __getattr__(name: str) -> Any:
    """The private names this module held (``_edges``, ``_run_jobs``, ...), from their new modules."""
    if name.startswith("_") and not name.startswith("__"):
        for home in _PRIVATE_HOMES:
            module = importlib.import_module(home)
            if hasattr(module, name):
                return getattr(module, name)
    return _public(name)


#: the public names it held in release 0.1 and no longer imports (until 0.3.0)
_public = forward_names(__name__, ("saltation.sweeps.sweeps", "saltation.sweeps.parallel", "saltation.output.files",
                                          "saltation.output.io", "saltation.engine.flow", "saltation.errors",
                                          "saltation.model.system"))
