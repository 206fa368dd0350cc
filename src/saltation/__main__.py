"""``python -m saltation``: the command line interface (see :mod:`saltation.apps.cli`)."""

import sys

from saltation.apps.cli import main

sys.exit(main())
