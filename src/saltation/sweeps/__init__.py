"""Layer 6, sweeps: brute-force diagrams and period maps, by simulation.

- :mod:`~saltation.sweeps.sweeps`: :func:`sweep`, :func:`period_map` and their records :class:`SweepResult`
  and :class:`PeriodMap`;
- :mod:`~saltation.sweeps.sections`: what a sweep samples, :class:`Section` (the stroboscopic section, the
  maxima, a switching surface's events or the crossings of an expression) read by :func:`parse_section`,
  and where a trajectory crosses it;
- :mod:`~saltation.sweeps.parallel`: the job runner, chunks of values in this process, in local worker
  processes or as Dask tasks.

Their files are :mod:`saltation.output.io`'s (``save_sweep``, ``save_period_map``), their figures
:mod:`saltation.output.plotting`'s (``plot_sweep``, ``plot_period_map``).
"""

from saltation.sweeps.sections import Section, parse_section
from saltation.sweeps.sweeps import (
    PeriodMap,
    StartState,
    SweepResult,
    SweepStart,
    attractor_period,
    period_map,
    sweep,
)

__all__ = ["PeriodMap", "Section", "StartState", "SweepResult", "SweepStart", "attractor_period", "parse_section",
           "period_map", "sweep"]
