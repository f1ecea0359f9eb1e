"""``python -m g1patch.cli``: the command line."""

import sys

from . import main

sys.exit(main())
