"""``python -m bldclab.cli``: the same as the ``bldclab`` command."""

import sys

from . import main

sys.exit(main())
