"""Layer 6, sweeps: brute-force diagrams and period maps, by simulation.

- :mod:`~saltation.sweeps.sweeps`: :func:`sweep`, :func:`period_map` and their records :class:`SweepResult`
  and :class:`PeriodMap`;
- :mod:`~saltation.sweeps.parallel`: the job runner, chunks of values in this process, in local worker
  processes or as Dask tasks.

Their files are :mod:`saltation.output.io`'s (``save_sweep``, ``save_period_map``), their figures
:mod:`saltation.output.plotting`'s (``plot_sweep``, ``plot_period_map``).
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
