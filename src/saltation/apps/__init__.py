"""Layer 8, applications: the command line and the paper's figures.

- :mod:`~saltation.apps.cli`: ``saltation ...``, a package with one module per subcommand;
- :mod:`~saltation.apps.paper`: Figures 3, 4, 6 and 7 of *Fold bifurcations in discontinuous systems*;
- :mod:`~saltation.apps.sweeps`: the old path of :mod:`saltation.sweeps` (until release 0.3.0);
- :mod:`~saltation.apps.diagram`: the old path of :mod:`saltation.special_points.follow` (until release 0.3.0).
"""
