"""Layer 6, output: figures and files.

:mod:`~saltation.output.plotting` (matplotlib figures in the paper's line styles) and
:mod:`~saltation.output.io` (JSON and CSV files of branches, sweeps, maps and curves).  Importing
:mod:`saltation` does not import matplotlib; :mod:`~saltation.output.plotting` does.
"""
