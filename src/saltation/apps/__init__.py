"""Layer 7, applications: the command line, the paper's figures, sweeps and diagrams.

:mod:`~saltation.apps.cli` (``saltation ...``: a package, one module per subcommand),
:mod:`~saltation.apps.paper` (Figures 3, 4, 6 and 7 of *Fold bifurcations in discontinuous systems*),
:mod:`~saltation.apps.sweeps` (brute-force diagrams and period maps, on local processes or Dask) and
:mod:`~saltation.apps.diagram` (the old path of :mod:`saltation.special_points.follow`, until release 0.3.0).
"""
