"""``python -m snakesim.cli``, the same as ``snakesim``."""

import sys

from snakesim.cli.app import main

sys.exit(main())
