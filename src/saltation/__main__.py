"""``python -m saltation``: the command line interface (see :mod:`saltation.cli`)."""

import sys

from .cli import main

sys.exit(main())
