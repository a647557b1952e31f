"""``python -m snakesim``: the ``snakesim`` command (see snakesim.cli)."""

import sys

from snakesim.cli.app import main

sys.exit(main())
