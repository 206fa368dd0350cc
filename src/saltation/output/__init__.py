"""Layer 7, output: figures and files.

- :mod:`~saltation.output.plotting`: matplotlib figures in the paper's line styles (branches, multipliers,
  phase planes, curves, sweeps and period maps);
- :mod:`~saltation.output.io`: saving and loading branches, diagrams, special points, sweeps and period
  maps, JSON and CSV;
- :mod:`~saltation.output.codecs`: one codec per record, from a record to the object its file holds and back;
- :mod:`~saltation.output.files`: atomic writing, validated reading, format headers.

Importing :mod:`saltation` does not import matplotlib; :mod:`~saltation.output.plotting` does.
"""
