"""``python -m dem.cli``: the ``dem`` command."""

import sys

from dem.cli import main

sys.exit(main())
