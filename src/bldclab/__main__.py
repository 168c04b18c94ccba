"""``python -m bldclab``: the same as the ``bldclab`` command (and ``python -m bldclab.cli``)."""

import sys

from .cli import main

sys.exit(main())
