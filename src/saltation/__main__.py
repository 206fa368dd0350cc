"""``python -m saltation``: the command line interface (see :mod:`saltation.apps.cli`)."""

from saltation.apps.cli import run

run()
